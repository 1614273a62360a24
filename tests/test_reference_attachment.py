"""The Newton-Euler reference with bodies joined at named attachment points of a rigid parent
(RigidBody(points=...), System.add(..., at=NAME); dttmm/reference/newton_euler.py, "Attachment
points"), against results it does not compute itself: a weld at a named point is one rigid body
whose mass, mass centre and inertia are summed here by hand (parallel-axis theorem), and trees
hanging from named points conserve energy and the angular momentum about the vertical through the
root."""
import numpy as np

from dttmm import (BallJoint, ElasticHinge, FixedHinge, JointMotion, PrismaticJoint,
                   RevoluteJoint, RigidBody, SpringDamper, System)
from dttmm.model.chains import TURNED_ABOUT_Y, unit_link
from dttmm.reference import simulate_reference
from dttmm.results.result import angular_momentum

G = 9.81
TIGHT = dict(rtol=1e-11, atol=1e-11)


def rot(axis, angle):
    """Rot(n, q) from scipy's rotation vector (not the package's Rodrigues)."""
    from scipy.spatial.transform import Rotation
    axis = np.asarray(axis, float)
    return Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).as_matrix()


def drift_of(res):
    """Largest excursion of the total energy from its start, over the largest kinetic energy."""
    energy = res.total_energy
    return np.abs(energy - energy[0]).max() / res.kinetic.max()


def shift(mass, c):
    """Parallel-axis term m (|c|^2 E - c c^T)."""
    c = np.asarray(c, float)
    return mass * (c @ c * np.eye(3) - np.outer(c, c))


# body A of the composite: 1 kg, output [1, 0, 0], mass centre [0.5, 0, 0], a full inertia
M_A, C_A, O_A = 1.0, np.array([0.5, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])
J_A = np.array([[0.05, 0.004, -0.002], [0.004, 0.09, 0.003], [-0.002, 0.003, 0.1]])  # about C
SIDE = np.array([0.3, 0.2, -0.1])
# body B, welded at A's "side" point, turned by R_B
M_B, C_B, O_B = 0.7, np.array([0.2, -0.1, 0.15]), np.array([0.4, 0.3, 0.2])
J_B = np.array([[0.02, 0.001, 0.0], [0.001, 0.03, -0.002], [0.0, -0.002, 0.035]])    # about C
R_B = rot([0.0, 1.0, 1.0], 0.9)
R_START = rot([1.0, 2.0, 3.0], 0.7)
W_START = np.array([0.8, -1.1, 1.5])


def test_a_weld_at_a_named_point_is_one_rigid_body():
    """A on a ball joint at the ground, B welded at A's named point: over 2 s the pair moves as
    the single rigid body with the summed mass, mass centre and inertia (built here by hand, in
    A's frame from A's input point), to 1e-8 m: A's output point, B's output point, B's frame,
    the mass centre and the ground's reaction force."""
    system = System(gravity=[0.0, -G, 0.0])
    system.add(RigidBody(mass=M_A, inertia=J_A, inertia_about="mass_center", to_mass_center=C_A,
                         to_output=O_A, rotation=R_START, angular_velocity=W_START, name="a",
                         points={"side": SIDE}), BallJoint())
    system.add(RigidBody(mass=M_B, inertia=J_B, inertia_about="mass_center", to_mass_center=C_B,
                         to_output=O_B, name="b"), FixedHinge(rotation=R_B), parent="a",
               at="side")
    pair = system.build()
    assert list(pair.attachment) == [0, 1]

    c_b = SIDE + R_B @ C_B                                    # B's mass centre in A's frame
    mass = M_A + M_B
    center = (M_A * C_A + M_B * c_b) / mass
    j_input = J_A + shift(M_A, C_A) + R_B @ J_B @ R_B.T + shift(M_B, c_b)
    one = System(gravity=[0.0, -G, 0.0])
    one.add(RigidBody(mass=mass, inertia=j_input, inertia_about="input", to_mass_center=center,
                      to_output=O_A, rotation=R_START, angular_velocity=W_START), BallJoint())
    single = one.build()

    t = np.linspace(0.0, 2.0, 201)
    res = simulate_reference(pair, 2.0, t_eval=t, **TIGHT)
    ref = simulate_reference(single, 2.0, t_eval=t, **TIGHT)
    assert np.abs(ref.angular_velocity[:, 0] - W_START).max() > 0.5    # it really tumbles
    b_point = ref.position_input[:, 0] + ref.rotation[:, 0] @ (SIDE + R_B @ O_B)
    errors = {
        "A output": np.abs(res.position_output[:, 0] - ref.position_output[:, 0]).max(),
        "B output": np.abs(res.position_output[:, 1] - b_point).max(),
        "B frame": np.abs(res.rotation[:, 1] - ref.rotation[:, 0] @ R_B).max(),
        "mass centre": np.abs((M_A * res.position_mass_center[:, 0] + M_B *
                               res.position_mass_center[:, 1]) / mass -
                              ref.position_mass_center[:, 0]).max(),
    }
    force = np.abs(res.force[:, 0] - ref.force[:, 0]).max() / np.abs(ref.force[:, 0]).max()
    print("weld at a named point vs one body:",
          ", ".join(f"{k} {v:.2e}" for k, v in errors.items()), f", ground force {force:.2e}")
    for name, err in errors.items():
        assert err < 1e-8, (name, err)
    assert force < 1e-8
    # B sits at A's named point exactly, in A's frame turned by R_B
    np.testing.assert_allclose(res.position_input[:, 1], res.position_input[:, 0] +
                               res.rotation[:, 0] @ SIDE, rtol=0, atol=1e-14)
    relative = np.einsum("tji,tjk->tik", res.rotation[:, 0], res.rotation[:, 1])
    assert np.abs(relative - R_B).max() < 1e-14


def hub(**kw):
    """2 kg, its mass centre off its axis, two named points besides its output point."""
    return RigidBody(mass=2.0, inertia=[0.1, 0.15, 0.2], inertia_about="mass_center",
                     to_mass_center=[0.4, 0.0, 0.1], to_output=[0.8, 0.0, 0.0],
                     points={"left": [0.6, 0.0, 0.5], "right": [0.5, 0.1, -0.4]}, **kw)


def test_two_branches_on_named_points_conserve_energy_and_vertical_momentum():
    """A hub on a ball joint at the origin, a link on a ball joint at each of two named points,
    no damping, gravity along -y: over 2 s the energy stays within 1e-8 of the largest kinetic
    energy and the angular momentum about the world y axis through the root within 1e-8 of the
    largest |L|; the branches stay on their points."""
    system = System(gravity=[0.0, -G, 0.0])
    system.add(hub(name="hub", angular_velocity=[0.0, 1.2, 0.3]), BallJoint())
    system.add(unit_link(name="l", rotation=TURNED_ABOUT_Y, angular_velocity=[0.5, 0.0, -0.4]),
               BallJoint(), parent="hub", at="left")
    system.add(unit_link(name="r", angular_velocity=[0.3, 0.8, 0.0]), BallJoint(),
               parent="hub", at="right")
    model = system.build()
    assert list(model.attachment) == [0, 1, 2]
    res = simulate_reference(model, 2.0, t_eval=np.linspace(0.0, 2.0, 401), **TIGHT)
    drift = drift_of(res)
    momentum = angular_momentum(model, res)
    l_drift = np.abs(momentum[:, 1] - momentum[0, 1]).max() / np.abs(momentum).max()
    print(f"two branches on named points: energy drift {drift:.2e} of the largest kinetic "
          f"energy {res.kinetic.max():.3g} J; L_y drift {l_drift:.2e} of max |L| "
          f"{np.abs(momentum).max():.3g}")
    assert res.kinetic.max() > 1.0                 # it falls and swings
    assert np.abs(momentum[:, 0] - momentum[0, 0]).max() > 1e-2   # gravity turns L_x
    assert drift < 1e-8
    assert l_drift < 1e-8
    for k, point in ((1, [0.6, 0.0, 0.5]), (2, [0.5, 0.1, -0.4])):
        np.testing.assert_allclose(res.position_input[:, k], res.position_input[:, 0] +
                                   res.rotation[:, 0] @ np.array(point), rtol=0, atol=1e-14)


def _every_hinge_tree(at):
    """A hub with a ball, a weld, a revolute, a slide and an elastic hinge child, all at `at`
    (None: the output point, or a named point with the output point's coordinates)."""
    system = System(gravity=[0.0, -G, 0.0])
    system.add(RigidBody(mass=2.0, inertia=[0.1, 0.15, 0.2], inertia_about="mass_center",
                         to_mass_center=[0.4, 0.0, 0.1], to_output=[0.8, 0.1, -0.2],
                         points={"tip": [0.8, 0.1, -0.2]}, angular_velocity=[0.2, 0.9, -0.3],
                         name="hub"), BallJoint())
    system.add(unit_link(name="ball", angular_velocity=[0.0, 0.4, 0.6]), BallJoint(),
               parent="hub", at=at)
    system.add(unit_link(name="weld"), FixedHinge(rotation=rot([1, 1, 0], 0.6)), parent="hub",
               at=at)
    system.add(unit_link(name="hinge"), RevoluteJoint(axis=[0, 0, 1], angle=0.3, rate=-0.5),
               parent="hub", at=at)
    system.add(unit_link(name="slide"),
               PrismaticJoint(axis=[0, 1, 0], drive=SpringDamper(80.0, 0.0)), parent="hub",
               at=at)
    system.add(unit_link(name="spring", rotation=TURNED_ABOUT_Y),
               ElasticHinge(3e3, 80.0, rotation=TURNED_ABOUT_Y), parent="hub", at=at)
    return system.build()


def test_a_named_point_at_the_output_point_is_the_output_point():
    """Every hinge kind on a named point with the output point's coordinates runs as on the
    output point (at=None), to 1e-12."""
    named, output = _every_hinge_tree("tip"), _every_hinge_tree(None)
    assert list(named.attachment) == [0, 1, 1, 1, 1, 1]
    assert list(output.attachment) == [0] * 6
    t = np.linspace(0.0, 1.0, 51)
    a = simulate_reference(named, 1.0, t_eval=t, **TIGHT)
    b = simulate_reference(output, 1.0, t_eval=t, **TIGHT)
    for key in ("position_input", "position_output", "rotation", "angular_velocity", "force",
                "moment", "joint_coordinates", "total_energy"):
        x, y = getattr(a, key), getattr(b, key)
        assert np.abs(x - y).max() <= 1e-12 * max(1.0, np.abs(y).max()), key
    assert drift_of(a) < 1e-8


def test_joints_with_coordinates_at_named_points_conserve_energy():
    """A revolute joint (axis in the hub's frame), a slide on a spring and an undamped elastic
    hinge, each at a different named point of a tumbling hub: energy (drive and hinge springs
    included) within 1e-8 of the largest kinetic energy over 2 s; the revolute child keeps its
    axis fixed in the hub and its input point on its named point."""
    system = System(gravity=[0.0, -G, 0.0])
    system.add(RigidBody(mass=2.0, inertia=[0.1, 0.15, 0.2], inertia_about="mass_center",
                         to_mass_center=[0.4, 0.0, 0.1], to_output=[0.8, 0.0, 0.0],
                         points={"a": [0.6, 0.0, 0.5], "b": [0.5, 0.1, -0.4],
                                 "c": [-0.2, 0.3, 0.1]},
                         angular_velocity=[0.3, 1.0, -0.2], name="hub"), BallJoint())
    axis = np.array([0.0, 0.6, 0.8])
    system.add(unit_link(name="hinge"), RevoluteJoint(axis=axis, angle=0.4, rate=1.5,
                                                      name="elbow"), parent="hub", at="a")
    system.add(unit_link(name="slide"),
               PrismaticJoint(axis=[0, 0, 1], rate=0.2, drive=SpringDamper(60.0, 0.0)),
               parent="hub", at="b")
    system.add(unit_link(name="spring", rotation=TURNED_ABOUT_Y),
               ElasticHinge(2e3, 60.0, rotation=TURNED_ABOUT_Y), parent="hub", at="c")
    model = system.build()
    res = simulate_reference(model, 2.0, t_eval=np.linspace(0.0, 2.0, 401), **TIGHT)
    drift = drift_of(res)
    print(f"joints on named points: energy drift {drift:.2e} of the largest kinetic energy "
          f"{res.kinetic.max():.3g} J; elbow angle {res.joint_coordinates[0, 0]:.3f} -> "
          f"{res.joint_coordinates[-1, 0]:.3f} rad")
    assert drift < 1e-8
    assert np.ptp(res.joint_coordinates[:, 0]) > 0.5          # the elbow really turns
    hub_axis = res.rotation[:, 0] @ axis
    child_axis = np.einsum("tij,j->ti", res.rotation[:, 1], axis)   # R0 = I: n fixed in both
    assert np.abs(child_axis - hub_axis).max() < 1e-13
    np.testing.assert_allclose(res.position_input[:, 1], res.position_input[:, 0] +
                               res.rotation[:, 0] @ np.array([0.6, 0.0, 0.5]), rtol=0,
                               atol=1e-14)


def test_a_locked_revolute_joint_at_a_named_point_is_a_weld():
    """A revolute joint held at 0.4 rad by a JointMotion at a named point moves like a FixedHinge
    turned by Rot(n, 0.4) there (to 1e-9 m over 2 s), and its drive torque is the weld's
    couple along the axis."""
    axis = np.array([0.0, 0.6, 0.8])

    def build(hinge):
        system = System(gravity=[0.0, -G, 0.0])
        system.add(hub(name="hub", rotation=R_START, angular_velocity=[0.3, 1.0, -0.2]),
                   BallJoint())
        system.add(unit_link(name="arm"), hinge, parent="hub", at="left")
        return system.build()

    locked = build(RevoluteJoint(axis=axis, angle=0.4, drive=JointMotion(
        lambda t: 0.4, lambda t: 0.0, lambda t: 0.0)))
    weld = build(FixedHinge(rotation=rot(axis, 0.4)))
    t = np.linspace(0.0, 2.0, 201)
    a = simulate_reference(locked, 2.0, t_eval=t, **TIGHT)
    b = simulate_reference(weld, 2.0, t_eval=t, **TIGHT)
    err = np.abs(a.position_output - b.position_output).max()
    torque = np.einsum("tij,j,ti->t", b.rotation[:, 0], axis, b.moment[:, 1])
    torque_err = np.abs(a.drive_force[:, 0] - torque).max() / np.abs(torque).max()
    print(f"locked revolute vs weld at a named point: {err:.2e} m, torque {torque_err:.2e}")
    assert err < 1e-9
    assert torque_err < 1e-7
