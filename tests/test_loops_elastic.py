"""An elastic hinge closing a loop (loop_rows.spring_directions, docs/loops.md "An elastic hinge
closing a loop"): the same mechanism built with the hinge in the tree and with it closing the
loop is one physical system, so the closing hinge in DT-TMM and in the reference converges to
the reference's tree hinge, whose equations (docs/hinges.md) share no code with the rows."""
import numpy as np
import pytest

import dttmm
from dttmm import BallJoint, ElasticHinge, RigidBody, System, UniversalJoint, simulate, \
    simulate_reference

from helpers import energy_drift, fitted_order, rot_z

# the spring's principal axes turned off the link's (a full matrix), its couple anisotropic
K_T = rot_z(0.4) @ np.diag([2e4, 1e4, 5e3]) @ rot_z(0.4).T
K_R = [80.0, 100.0, 120.0]
ARM_INERTIA = [[0.02, 0.003, 0.0], [0.003, 0.05, 0.001], [0.0, 0.001, 0.06]]


def _spring(damping, name="spring", **extra):
    return ElasticHinge(translational_stiffness=K_T, rotational_stiffness=K_R,
                        rotational_damping=[0.3 * damping, 0.5 * damping, 0.4 * damping],
                        name=name, **extra)


def _link():
    return RigidBody(mass=1.0, inertia=[0.02, 0.08, 0.09], inertia_about="mass_center",
                     to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0], name="link")


def in_the_tree(damping=1.0, gravity=(0.0, -3.0, -9.81)):
    """ground -ball- link -elastic- arm, the arm's end closed to the ground point by a
    universal joint (the arm runs back from the link's tip to the origin, its mass centre off
    that line)."""
    system = System(gravity=gravity)
    system.add(_link(), BallJoint())
    system.add(RigidBody(mass=0.8, inertia=ARM_INERTIA, inertia_about="mass_center",
                         to_mass_center=[-0.5, 0.4, 0.1], to_output=[-1.0, 0, 0], name="arm"),
               _spring(damping), parent="link")
    system.close(UniversalJoint(axis1=[0, 0, 1.0], axis2=[0, 1.0, 0]), "arm", "ground")
    return system.build()


def closing(damping=1.0, gravity=(0.0, -3.0, -9.81), **extra):
    """The same bodies as in_the_tree with the hinge closing the loop: the arm hangs from the
    ground point by the universal joint (its axes swapped: now the ground's first), the elastic
    hinge joins the link's tip (side a, the tree hinge's inboard body) to the arm's."""
    system = System(gravity=gravity)
    system.add(_link(), BallJoint())
    system.add(RigidBody(mass=0.8, inertia=ARM_INERTIA, inertia_about="mass_center",
                         to_mass_center=[0.5, 0.4, 0.1], to_output=[1.0, 0, 0], name="arm"),
               UniversalJoint(axis1=[0, 1.0, 0], axis2=[0, 0, 1.0]))
    system.close(_spring(damping, **extra), "link", "arm")
    return system.build()


def test_a_closing_elastic_hinge_is_the_tree_hinge_in_both_solvers():
    """Over 0.3 s under gravity from rest (the link's tip falls 0.6 m): the reference's
    closing hinge follows its tree hinge to 1e-8 m (measured 2e-13), and DT-TMM's converges
    to it at order 2, the points and the hinge's force on the arm (measured 3.4e-6, 1.0e-6,
    2.7e-7 m and 7.4e-2, 2.2e-2, 5.7e-3 N of 2.2 N at dt = 1e-3, 5e-4, 2.5e-4: the spring's
    2e4 N/m times the points' error; asserted from 5e-4 down, past the pre-asymptotic
    first step)."""
    t_end, t = 0.3, np.linspace(0.0, 0.3, 4)
    tree = simulate_reference(in_the_tree(), t_end, t_eval=t, rtol=1e-11, atol=1e-13)
    model = closing()
    ref = simulate_reference(model, t_end, t_eval=t, rtol=1e-11, atol=1e-13)
    link_tip = tree.position_output[:, 0]
    assert np.abs(link_tip - link_tip[0]).max() > 0.05               # it moves
    assert np.abs(ref.position_output[:, 0] - link_tip).max() < 1e-8
    assert np.abs(ref.position_mass_center[:, 1] - tree.position_mass_center[:, 1]).max() < 1e-8
    # the force on the arm: the tree hinge's load on its outboard body, the closure's on b
    force = tree.force[:, 1]
    assert np.abs(force).max() > 1.0
    assert np.abs(ref.closure_force[:, 0] - force).max() < 1e-6 * np.abs(force).max()
    steps, errors, force_errors = [5e-4, 2.5e-4, 1.25e-4], [], []
    for dt in steps:
        result = simulate(model, t_end, dt, t_eval=t)
        errors.append(max(np.abs(result.position_output[:, 0] - link_tip).max(),
                          np.abs(result.position_mass_center[:, 1]
                                 - tree.position_mass_center[:, 1]).max()))
        force_errors.append(np.abs(result.closure_force[:, 0] - force).max())
        assert result.info["loop_position_residual"] < 1e-10
    assert abs(fitted_order(steps, errors) - 2.0) < 0.2, errors
    assert abs(fitted_order(steps, force_errors) - 2.0) < 0.2, force_errors
    assert errors[-1] < 1e-7


def test_a_closing_elastic_hinge_keeps_the_energy_and_its_dampers_balance():
    """Undamped with an isotropic couple (whose law K psi is then the gradient of
    1/2 psi . K psi), the total energy, the closing spring's strain in Result.potential,
    holds at order 2 over 1 s; damped, the energy balance (the dampers' work along the
    hinge's own rates) closes at order 2 to a small part of what the dampers take (measured
    6.8e-7 and 1.8e-7 of the largest kinetic energy at dt = 5e-4, 2.5e-4, where they take
    6.5e-5)."""
    system = System(gravity=[0.0, -3.0, -9.81])
    system.add(_link(), BallJoint())
    system.add(RigidBody(mass=0.8, inertia=ARM_INERTIA, inertia_about="mass_center",
                         to_mass_center=[0.5, 0.4, 0.1], to_output=[1.0, 0, 0], name="arm"),
               UniversalJoint(axis1=[0, 1.0, 0], axis2=[0, 0, 1.0]))
    system.close(ElasticHinge(translational_stiffness=K_T, rotational_stiffness=100.0),
                 "link", "arm")
    free = system.build()
    drifts = [energy_drift(free, 1.0, dt) for dt in (1e-3, 5e-4)]
    assert drifts[1] < 2e-5 and 3.0 < drifts[0] / drifts[1] < 5.0, drifts
    damped = closing(damping=10.0, translational_damping=K_T * 1e-3)
    gaps = []
    for dt in (5e-4, 2.5e-4):
        result = simulate(damped, 1.0, dt, max_energy_error=1.0)
        energy = result.kinetic + result.potential
        taken = (energy[0] - energy[-1]) / result.kinetic.max()
        assert taken > 5e-5
        gaps.append(result.info["energy_balance_error"])
    assert gaps[1] < 0.01 * taken and 3.0 < gaps[0] / gaps[1] < 5.0, gaps


def test_a_closing_elastic_hinge_describes_itself_and_round_trips_through_a_scene():
    from dttmm.interfaces.scene import scene_from_dict, scene_of
    model = closing()
    text = model.describe()
    assert "closure 0 'spring'" in text and "N m/rad" in text and "constrains nothing" in text
    data = scene_of(model, name="closing_spring")
    assert data["close"][0]["type"] == "elastic"
    again = scene_from_dict(data).model
    for name in ("closure_kind", "closure_body", "closure_point", "closure_params"):
        assert np.allclose(getattr(again, name), getattr(model, name), rtol=0, atol=1e-12)


@pytest.mark.parametrize("extra, message", [
    (dict(translational_damping=[[1.0, 0.5, 0.0], [0.5, 1.0, 0.0], [0.0, 0.0, 1.0]]),
     "translational_damping must share the principal axes of translational_stiffness"),
    (dict(deflection=[0.0, 0.01, 0.0]), "leave deflection None"),
])
def test_a_closing_elastic_hinge_refuses_what_it_cannot_mean(extra, message):
    with pytest.raises(ValueError, match=f"ElasticHinge 'spring' \\(closure 0\\): .*{message}"):
        closing(**extra)


def test_a_closing_elastic_hinge_rests_where_static_equilibrium_puts_it():
    """Hanging (gravity mostly along the links, +x, a little across): the static solve of
    the closing model and of its tree twin find the same equilibrium (the link's tip to 1e-9
    m), a rest state of the reference (to 1e-9 m over 0.2 s) with the spring loaded (its rest
    rotation kept from the built model, not read again)."""
    at_rest = []
    for build in (in_the_tree, closing):
        model = dttmm.static_equilibrium(build(gravity=(9.81, -1.0, -0.5))).model
        ref = simulate_reference(model, 0.2, t_eval=[0.0, 0.1, 0.2], rtol=1e-10, atol=1e-12)
        assert np.abs(ref.position_output - ref.position_output[0]).max() < 1e-9
        at_rest.append(ref)
    tree, closed = at_rest
    assert np.abs(closed.position_output[0, 0] - tree.position_output[0, 0]).max() < 1e-9
    assert np.abs(closed.closure_force[0, 0]).max() > 1.0
    assert np.abs(closed.closure_force[0, 0] - tree.force[0, 1]).max() < 1e-7


def test_the_suggested_step_resolves_an_elastic_hinge():
    """describe()'s suggested dt counts an elastic hinge's springs against the body they carry
    (it ignored them): a 1 kg body on a 1e6 N/m hinge oscillates at 159 Hz, so the step is at
    most a twentieth of its period; the run at that step keeps the oscillation's period to
    1% (its amplitude's zero crossings against 2 pi sqrt(m / k))."""
    from dttmm.interfaces.describe import suggested_dt
    from helpers import crossing_period
    system = System(gravity=[0.0, 0.0, 0.0])
    system.add(RigidBody(mass=1.0, inertia=[0.1, 0.1, 0.1], inertia_about="mass_center",
                         to_mass_center=[0.0, 0, 0], to_output=[0.0, 0, 0], name="body"),
               ElasticHinge(translational_stiffness=1e6, rotational_stiffness=1e4,
                            deflection=[1e-3, 0.0, 0.0]))
    model = system.build()
    period = 2 * np.pi * np.sqrt(1.0 / 1e6)
    dt = suggested_dt(model)
    assert dt <= period / 20 and dt >= period / 50
    assert f"suggested dt: {dt:g} s" in model.describe()
    result = simulate(model, 20 * period, dt)
    measured = crossing_period(result.t, result.position_input[:, 0, 0])
    assert abs(measured / period - 1.0) < 0.01
