"""The energy balance (docs/solver.md, "Energy balance"): with max_energy_error the run checks
E(t) - E(0) = W(0, t), W the work of the applied loads, the joint drives, the elastic hinges'
and the beams' dampers and a moving ground.  Each term is proven by the balance closing at
order 2 in dt on a system where that term is the only one outside E (an error in a term
leaves a gap that does not shrink: a wrong damper law did, at 6e-6 of the kinetic energy);
a run whose balance breaks stops; the samples are those of the same run without the check."""
import numpy as np
import pytest

from dttmm import (BallJoint, DivergenceError, ElasticHinge, EulerBernoulliBeam, FixedHinge,
                   Ground, PrescribedMotion, build_chain, simulate)
from dttmm.model.chains import arm, rigid_chain, three_pendulum, unit_link


def _hub():
    return PrescribedMotion.spin_about_axis([0, 1, 0], lambda t: t * t, lambda t: 2.0 * t,
                                            lambda t: 2.0)


CASES = {
    # name: (model, what is outside E)
    "joint torque drive": lambda: arm("torque"),
    "prescribed joint motion, flexible link": lambda: arm("motion", flexible=True),
    "applied force and torque": lambda: build_chain([
        BallJoint(), unit_link(torque=lambda t: [0.0, 0.0, 2.0 * np.sin(3 * t)],
                               force=lambda t: [1.0, 0.0, 0.0]),
        BallJoint(), unit_link()]),
    "elastic hinge dampers": lambda: build_chain([
        BallJoint(), unit_link(angular_velocity=[0.0, 0.5, 0.0]),
        ElasticHinge(1e4, 1e3, translational_damping=20.0, rotational_damping=0.5),
        unit_link()]),
    "moving ground, elastic root": lambda: build_chain([
        ElasticHinge(1e4, 1e3, translational_damping=5.0, rotational_damping=0.2), unit_link(),
        BallJoint(), unit_link()], ground=Ground(motion=_hub())),
    "moving ground, welded root": lambda: build_chain([
        FixedHinge(), unit_link(), BallJoint(), unit_link()], ground=Ground(motion=_hub())),
    "beam modal damping": lambda: build_chain([
        BallJoint(), EulerBernoulliBeam(length=1.0, mass_per_length=2.0, bending_stiffness=50.0,
                                        polar_inertia_per_length=1e-3, modes_per_plane=2,
                                        damping_ratio=0.05, angular_velocity=[0, 0, 2.0],
                                        initial_modal_velocities=[0.5, 0.0, 0.2, 0.0]),
        BallJoint(), unit_link()]),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_balance_closes_at_order_2(name):
    """Measured gaps (of the largest kinetic energy) at dt = 1e-3 / 5e-4 over 0.5 s: 7.6e-7 /
    1.9e-7 (torque drive) ... 8.7e-6 / 2.2e-6 (damped beam, which loses 0.09 J of 11 J)."""
    model = CASES[name]()
    gaps = [simulate(model, 0.5, dt, max_energy_error=1.0).info["energy_balance_error"]
            for dt in (1e-3, 5e-4)]
    order = np.log2(gaps[0] / gaps[1])
    print(name, gaps, order)
    assert 1.8 < order < 2.2 and gaps[1] < 1e-5


def test_the_work_is_counted():
    """The damped beam loses 0.09 J of its 11 J to its modal dampers: the balance counts it to
    2.2e-6 of the kinetic energy; without its dampers' work E - E(0) would be 8e-3 of it."""
    model = CASES["beam modal damping"]()
    run = simulate(model, 0.5, 5e-4, max_energy_error=1e-4, record_every=1)
    e = run.total_energy
    lost = (e[0] - e[-1]) / run.kinetic.max()
    assert lost > 5e-3 and run.info["energy_balance_error"] < 1e-3 * lost


def test_a_broken_balance_stops_the_run():
    """The 3-link chain at dt = 0.5 s with the error estimate switched off: its energy runs to
    1e31 J; the balance stops it (checked at the end of each chunk), naming the cause; at a
    sound step the same check passes."""
    with pytest.raises(DivergenceError, match="the energy balance broke") as err:
        simulate(rigid_chain(3), 20.0, 0.5, max_step_error=None, max_energy_error=0.01)
    assert err.value.partial is not None
    sound = simulate(rigid_chain(3), 2.0, 1e-3, max_energy_error=1e-4)
    assert sound.info["energy_balance_error"] < 1e-4


def test_the_samples_are_those_of_the_run_without_the_check():
    model = three_pendulum()
    for options in (dict(record_every=7), dict(t_eval=[0.1, 0.25, 0.4]), {}):
        plain = simulate(model, 0.4, 1e-3, **options)
        checked = simulate(model, 0.4, 1e-3, max_energy_error=1e-3, **options)
        np.testing.assert_array_equal(plain.t, checked.t)
        np.testing.assert_array_equal(plain.position_output, checked.position_output)
        np.testing.assert_array_equal(plain.force, checked.force)


def test_what_the_check_refuses():
    with pytest.raises(ValueError, match="max_energy_error"):
        simulate(rigid_chain(2), 0.1, 1e-3, max_energy_error=0.0)
    with pytest.raises(ValueError, match="adaptive steps .* max_energy_error"):
        simulate(rigid_chain(2), 0.1, rtol=1e-4, max_energy_error=1e-3)
    beam = EulerBernoulliBeam(length=1.0, mass_per_length=1.0, bending_stiffness=10.0,
                              polar_inertia_per_length=1e-3)
    with pytest.raises(ValueError, match="follows a beam"):
        simulate(build_chain([BallJoint(), beam, ElasticHinge(1e3, 1e2), unit_link()]), 0.1,
                 1e-3, max_energy_error=1e-3)
