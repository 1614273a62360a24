"""Where a child hangs in a tree: at a beam's end behind any joint kind, and at the named
points of a rigid body (run_tables.kernel_model's end sections and attachment offsets;
docs/topology.md, "What the kernels integrate"), against an analytical composite body, the
conservation laws and the independent Newton-Euler reference."""
import numpy as np

from dttmm import (BallJoint, ElasticHinge, EulerBernoulliBeam, FixedHinge, RevoluteJoint,
                   RigidBody, System, simulate)
from dttmm.model.chains import TURNED_ABOUT_Y, unit_link
from dttmm.reference import simulate_reference
from dttmm.results.result import angular_momentum

SIDE, TOP = [0.3, 0.2, -0.1], [0.6, 0.0, 0.3]


def _hub(**kwargs):
    return RigidBody(mass=1.0, inertia=[0.2, 0.3, 0.25], inertia_about="mass_center",
                     to_mass_center=[0.5, 0.0, 0.0], to_output=[1.0, 0.0, 0.0],
                     points={"side": SIDE, "top": TOP}, name="hub", **kwargs)


def _beam():
    return EulerBernoulliBeam(length=1.0, density=3300.0, area=4e-4, bending_stiffness=333.3,
                              polar_inertia_per_length=0.00088, name="beam")


def _errors(model, t_end, steps):
    """Largest output-point difference to a tight reference, per dt, and the runs."""
    runs = [simulate(model, t_end, dt, record_every=int(round(0.01 / dt))) for dt in steps]
    ref = simulate_reference(model, t_end, t_eval=runs[0].t, rtol=1e-12, atol=1e-12)
    return np.array([np.abs(r.position_output - ref.position_output).max() for r in runs]), runs


def _order(errors, steps):
    return np.log(errors[0] / errors[1]) / np.log(steps[0] / steps[1])


def _parallel_axis(inertia, mass, offset):
    return inertia + mass * (offset @ offset * np.eye(3) - np.outer(offset, offset))


def test_a_body_welded_at_a_named_point_is_one_composite_body():
    """A body welded at a named point of another moves as one rigid body with the summed mass,
    the combined mass centre and the inertia by the parallel-axis theorem (computed here by
    hand): a 3-D tumbling pendulum either way.  (The three bodies the kernels see, hub, offset
    and b, form a welded chain, whose bodies' rotations are each integrated: measured 6.9e-11 m
    apart at dt = 1e-3, 4.1e-12 m at 5e-4.)"""
    w0 = np.array([0.3, -0.5, 0.8])
    m_b, c_b, j_b = 0.7, np.array([0.1, 0.05, 0.2]), np.diag([0.05, 0.08, 0.06])
    two = System()
    two.add(_hub(angular_velocity=w0), BallJoint())
    two.add(RigidBody(mass=m_b, inertia=j_b, inertia_about="mass_center", to_mass_center=c_b,
                      to_output=[0.2, 0.0, 0.0], name="b"), FixedHinge(), parent="hub",
            at="side")
    m_a, c_a, j_a = 1.0, np.array([0.5, 0.0, 0.0]), np.diag([0.2, 0.3, 0.25])
    c_b_hub = np.array(SIDE) + c_b
    mass = m_a + m_b
    center = (m_a * c_a + m_b * c_b_hub) / mass
    inertia = _parallel_axis(j_a, m_a, c_a - center) + _parallel_axis(j_b, m_b, c_b_hub - center)
    one = System()
    one.add(RigidBody(mass=mass, inertia=inertia, inertia_about="mass_center",
                      to_mass_center=center, to_output=[1.0, 0.0, 0.0], angular_velocity=w0,
                      name="composite"), BallJoint())
    split = simulate(two.build(), 1.0, 5e-4, record_every=20)
    whole = simulate(one.build(), 1.0, 5e-4, record_every=20)
    moved = np.abs(whole.position_output[:, 0] - whole.position_output[0, 0]).max()
    assert moved > 0.5
    diff = np.abs(split.position_output[:, 0] - whole.position_output[:, 0]).max()
    assert diff < 1e-10, diff
    np.testing.assert_allclose(split.total_energy, whole.total_energy, rtol=0, atol=1e-10)


def _points_tree(elastic=True):
    system = System(gravity=[0.0, -9.81, 0.0])
    system.add(_hub(angular_velocity=[0.0, 0.5, 0.0]), BallJoint())
    system.add(unit_link(name="on_side", angular_velocity=[0.2, 0.0, 0.3]), BallJoint(),
               parent="hub", at="side")
    system.add(unit_link(name="on_top", rotation=TURNED_ABOUT_Y), BallJoint(), parent="hub",
               at="top")
    system.add(unit_link(name="on_output"), BallJoint(), parent="hub")
    if elastic:
        system.add(unit_link(name="sprung"), ElasticHinge(2e4, 300.0, name="spring"),
                   parent="hub", at="side")
        system.add(unit_link(name="turning"), RevoluteJoint(axis=[0.0, 0.0, 1.0], name="pin"),
                   parent="on_top")
    return system.build()


def test_a_tree_on_named_points_keeps_its_energy_and_vertical_angular_momentum():
    """Ball-joint children on two named points and the output point of one body, undamped,
    2 s at dt = 1e-4: energy drift below 1e-6 of the largest kinetic energy, and the angular
    momentum about the vertical through the root (a ball joint at the origin, gravity along -y)
    conserved to the same order."""
    model = _points_tree(elastic=False)
    res = simulate(model, 2.0, 1e-4, record_every=100)
    k_max = res.kinetic.max()
    drift = np.abs(res.total_energy - res.total_energy[0]).max() / k_max
    momentum = angular_momentum(model, res)
    l_drift = np.abs(momentum[:, 1] - momentum[0, 1]).max() / np.abs(momentum).max()
    print(f"named points: energy drift {drift:.2e} of {k_max:.3g} J, L_y drift {l_drift:.2e}")
    assert k_max > 1.0
    assert drift < 1e-6 and l_drift < 1e-6


def test_children_on_named_points_match_the_reference():
    """Ball joints, an elastic hinge and a revolute joint's parent on named points: order 2 to
    the independent reference (which joins children at named points in its own equations)."""
    steps = np.array([1e-3, 5e-4])
    errors, runs = _errors(_points_tree(), 0.5, steps)
    assert runs[0].info["mode"] == "riccati-joints"
    print(f"named points: errors {errors}, order {_order(errors, steps):.2f}")
    assert abs(_order(errors, steps) - 2.0) < 0.2, errors
    assert errors[-1] < 1e-5


def test_a_beams_end_in_a_tree_carries_every_joint_kind():
    """A beam's end in a tree with a revolute joint, an elastic hinge, a ball joint and a weld
    numbered away from the beam on it (an end section welded to the beam carries the frame they
    need): order 2 to the independent reference."""
    system = System(gravity=[0.0, -9.81, 0.0])
    system.add(_beam(), BallJoint())
    system.add(unit_link(name="ball", angular_velocity=[0.0, 0.3, 0.2]), BallJoint(),
               parent="beam")
    system.add(unit_link(name="pinned"), RevoluteJoint(axis=[0.0, 0.0, 1.0], name="pin"),
               parent="beam")
    system.add(unit_link(name="sprung", rotation=TURNED_ABOUT_Y),
               ElasticHinge(2e4, 300.0, rotation=TURNED_ABOUT_Y, name="spring"), parent="beam")
    system.add(RigidBody(mass=0.3, inertia=0.01, inertia_about="mass_center", name="welded"),
               FixedHinge(name="weld"), parent="beam")
    model = system.build()
    steps = np.array([1e-3, 5e-4])
    errors, runs = _errors(model, 0.5, steps)
    assert runs[0].info["newton_iterations_used"] >= 1
    print(f"beam end: errors {errors}, order {_order(errors, steps):.2f}")
    assert abs(_order(errors, steps) - 2.0) < 0.2, errors
    assert errors[-1] < 1e-5


def test_a_weld_numbered_right_after_a_beam_but_elsewhere_is_not_the_beams():
    """A beam followed in the numbering by a body welded to another body: the beam's end is free
    (its transfer must not take that weld for its own), order 2 to the reference."""
    system = System(gravity=[0.0, -9.81, 0.0])
    system.add(_hub(angular_velocity=[0.0, 0.4, 0.0]), BallJoint())
    system.add(_beam(), BallJoint(), parent="hub")
    system.add(RigidBody(mass=0.5, inertia=0.02, inertia_about="mass_center",
                         to_mass_center=[0.0, 0.1, 0.0], name="welded"), FixedHinge(name="weld"),
               parent="hub")
    model = system.build()
    assert list(model.parent) == [-1, 0, 0] and model.hinge_kind[2] != model.hinge_kind[1]
    steps = np.array([1e-3, 5e-4])
    errors, _ = _errors(model, 0.5, steps)
    print(f"weld after a beam: errors {errors}, order {_order(errors, steps):.2f}")
    assert abs(_order(errors, steps) - 2.0) < 0.2, errors
    assert errors[-1] < 1e-5
