"""End stops on joint coordinates (elements/limits.py, docs/limits.md): the restitution law
against scipy's integration of the contact, a link's rebound against e times its rate at
impact, a drive held against a stop, DT-TMM against the Newton-Euler reference, scenes and
refusals."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import dttmm
from dttmm import (JointForce, JointLimit, PrismaticJoint, RevoluteJoint, RigidBody, System,
                   build_chain, simulate, simulate_reference)
from dttmm.elements.limits import restitution_damping_ratio, restitution_of
from dttmm.model.chains import unit_link
from dttmm.model.profiles import ProfileForce, profile
from dttmm.results.result import limit_forces

LINK_INERTIA = 5.0 / 12.0           # the unit link about its input point's z axis


def _order(errors, steps):
    return np.polyfit(np.log(steps), np.log(errors), 1)[0]


@pytest.mark.parametrize("restitution", [0.1, 0.5, 0.8, 0.95])
def test_the_restitution_law_against_the_integrated_contact(restitution):
    """The stop's damping ratio for e, then the contact integrated by scipy (a unit mass
    striking at 1 m/s, the force -max(0, k x + c x')): it leaves at e."""
    zeta = restitution_damping_ratio(restitution)
    assert restitution_of(zeta) == pytest.approx(restitution, abs=1e-12)
    k = 1.0e4
    c = 2.0 * zeta * np.sqrt(k)

    def rhs(_, y):
        return [y[1], -max(0.0, k * y[0] + c * y[1])]

    def leaves(_, y):                   # the force lets go: k x + c x' = 0, falling
        return k * y[0] + c * y[1]
    leaves.terminal, leaves.direction = True, -1
    sol = solve_ivp(rhs, (0.0, 1.0), [0.0, 1.0], events=leaves, rtol=1e-12, atol=1e-14,
                    method="DOP853", max_step=1e-4)
    assert -sol.y_events[0][0][1] == pytest.approx(restitution, rel=1e-7)


def _swinging(rate, stop, drive=None):
    """A unit link on a revolute joint about z, no gravity, turning at `rate` toward its
    stops."""
    return build_chain([RevoluteJoint(axis=[0, 0, 1], rate=rate, limits=stop, drive=drive,
                                      name="pin"), unit_link(name="link")], gravity=[0, 0, 0])


@pytest.mark.parametrize("restitution", [0.5, 0.8])
def test_a_link_rebounds_at_e_times_its_rate(restitution):
    """The link strikes the stop at 0.5 rad at 2 rad/s and leaves at -e 2 rad/s: within 1.5%
    with the contact's 5 ms in 100 steps (measured 0.83% at e = 0.5, 0.25% at 0.8), the error
    falling at order 1 in the step (the step does not locate the contact's start, where the
    damper's force jumps: docs/limits.md); the Result's stop force pushes only during the
    contact, its impulse the link's change of momentum, and drive_force holds none of it."""
    stop = JointLimit.with_restitution(-0.5, 0.5, restitution, LINK_INERTIA, 5e-3)
    model = _swinging(2.0, stop)
    errors = []
    for dt in (5e-5, 2.5e-5):
        run = simulate(model, 0.4, dt, record_every=1)   # (every step: the impulse below)
        errors.append(abs(run.joint_rates[-1, 0] / (-restitution * 2.0) - 1.0))
    assert errors[0] < 0.015, errors
    assert abs(_order(errors, [5e-5, 2.5e-5]) - 1.0) < 0.2, errors
    forces, engaged = limit_forces(model, run)
    assert np.array_equal(forces, run.limit_force) and engaged == run.limit_contacts()
    assert len(engaged) == 1 and engaged[0][:2] == (0, "upper")
    t_on, t_off = engaged[0][2:]
    assert t_on == pytest.approx(0.25, abs=1e-3) and 0.0 < t_off - t_on < 5e-3
    assert np.all(forces[:, 0] <= 0.0) and np.abs(run.drive_force).max() < 1e-9
    # the stop's angular impulse is the link's change of angular momentum about the axis
    impulse = np.trapezoid(forces[:, 0], run.t)
    assert impulse == pytest.approx(-LINK_INERTIA * 2.0 * (1.0 + restitution), rel=1e-2)


def test_a_drive_pushing_into_a_stop_is_held_there():
    """A constant torque of 5 N m drives the link into a stop of 1e4 N m/rad at 0.3 rad with
    damping: it comes to rest at 0.3 + 5 / 1e4 rad, the stop's torque -5 N m, the drive's 5."""
    stop = JointLimit(upper=0.3, stiffness=1e4, damping=50.0)
    model = _swinging(0.0, stop, drive=JointForce(ProfileForce(profile(5.0))))
    run = simulate(model, 3.0, 1e-3)
    forces, _ = limit_forces(model, run)
    assert run.joint_coordinates[-1, 0] == pytest.approx(0.3 + 5.0 / 1e4, abs=1e-9)
    assert abs(run.joint_rates[-1, 0]) < 1e-9
    assert forces[-1, 0] == pytest.approx(-5.0, abs=1e-6)
    assert run.drive_force[-1, 0] == pytest.approx(5.0, abs=1e-9)


@pytest.mark.parametrize("damping", [0.0, 1.0])
def test_stops_follow_the_reference(damping):
    """A double pendulum under gravity whose first joint strikes its stops and whose second
    slides between its own (a prismatic joint): DT-TMM's motion against the reference's.
    Elastic stops (damping 0): within 5.0e-6 m at dt = 1e-4 s (measured 9.9e-5, 4.9e-5, 5.0e-6
    at 4, 2 and 1 x 1e-4 s); damped: 6.0e-5 m.  The convergence is irregular: the step does
    not locate a contact's start (docs/limits.md)."""
    s = System(gravity=[0, -9.81, 0])
    s.add(unit_link(name="upper"), RevoluteJoint(axis=[0, 0, 1], angle=0.0, rate=-1.0, name="a",
                                                 limits=JointLimit(-0.6, 0.6, 2e3, 10.0 * damping)))
    slider = RigidBody(mass=0.5, inertia=[0.01, 0.01, 0.01], inertia_about="mass_center",
                       name="slider")
    s.add(slider, PrismaticJoint(axis=[1, 0, 0], rate=1.0, name="b",
                                 limits=JointLimit(-0.2, 0.2, 5e3, 20.0 * damping)),
          parent="upper")
    model = s.build()
    t_end = 1.0
    ref = simulate_reference(model, t_end, t_eval=np.linspace(0, t_end, 21), rtol=1e-11,
                             atol=1e-12)
    assert {c[0] for c in ref.limit_contacts()} == {0, 1}    # both stops are struck
    assert np.array_equal(ref.limit_force, limit_forces(model, ref)[0])
    errors = []
    for dt in (2e-4, 1e-4):
        run = simulate(model, t_end, dt, record_every=int(round(0.05 / dt)))
        errors.append(np.abs(run.position_output - ref.position_output).max())
        assert np.abs(run.drive_force).max() < 1e-9        # (the total less the stop: rounding)
        assert [c[:2] for c in run.limit_contacts()] == [c[:2] for c in ref.limit_contacts()]
    assert errors[1] < errors[0], errors
    assert errors[1] < (1e-5 if damping == 0.0 else 1.2e-4), errors


def test_limits_round_trip_through_a_scene(tmp_path):
    from dttmm.interfaces.scene import load_scene, save_scene
    model = _swinging(2.0, JointLimit(upper=0.5, stiffness=1e3, damping=2.0))
    save_scene(model, tmp_path / "stop.toml")
    again = load_scene(tmp_path / "stop.toml").model
    assert np.array_equal(again.hinge_params, model.hinge_params)
    s = System()
    s.add(unit_link(name="a"), dttmm.UniversalJoint(
        axis1=[0, 0, 1], axis2=[0, 1, 0], limits=(None, JointLimit(-1.0, 1.0, 10.0))))
    two = s.build()
    save_scene(two, tmp_path / "two.toml")
    assert np.array_equal(load_scene(tmp_path / "two.toml").model.hinge_params,
                          two.hinge_params)


def test_what_a_limit_refuses():
    with pytest.raises(ValueError, match=r"RevoluteJoint 'pin' \(hinge 0\): limits: lower"):
        _swinging(0.0, JointLimit(0.5, -0.5, 1.0))
    with pytest.raises(ValueError, match="stiffness must be given"):
        _swinging(0.0, JointLimit(-0.5, 0.5))
    with pytest.raises(ValueError, match="damping must be >= 0"):
        _swinging(0.0, JointLimit(-0.5, 0.5, 1.0, -1.0))
    with pytest.raises(ValueError, match="limits must be None or 2 entries"):
        build_chain([dttmm.UniversalJoint(axis1=[0, 0, 1], axis2=[0, 1, 0],
                                          limits=JointLimit(-1, 1, 1.0)), unit_link()])
    with pytest.raises(ValueError, match="restitution must be in"):
        JointLimit.with_restitution(-1, 1, 1.5, 1.0, 1e-3)
    s = System()
    s.add(unit_link(name="a"), RevoluteJoint(axis=[0, 0, 1]))
    s.close(RevoluteJoint(axis=[0, 0, 1], limits=JointLimit(-1, 1, 1.0)), "a", "ground")
    with pytest.raises(ValueError, match="closing joint"):
        s.build()


def test_the_end_stop_example(tmp_path):
    """examples/end_stop.py (1 s): its CSV has the issue's columns every 1 ms; the link strikes
    the stop (0.702 s), leaves it turning back, and the stop pushes only past 0.5 rad."""
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
    import end_stop
    csv = tmp_path / "e.csv"
    assert end_stop.main(["--t-end", "1", "--csv", str(csv), "--plots", str(tmp_path)]) == 0
    assert csv.read_text().splitlines()[0] == "t,angle,rate,stop_torque"
    table = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert np.allclose(table[:, 0], np.arange(1001) * 1e-3, atol=1e-9)
    assert (tmp_path / "end_stop.png").stat().st_size > 1000
    pushing = table[:, 3] < 0.0
    assert pushing.any() and np.all(table[pushing, 1] > 0.5) and np.all(table[:, 3] <= 0.0)
    _, result = end_stop.run(1.0)
    first = end_stop.contacts(result)[0]
    assert first[0] == pytest.approx(0.702, abs=2e-3) and first[1] > 0.0 > first[2]
