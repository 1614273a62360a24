"""Joints with coordinates (revolute, universal, prismatic) and their drives: the model they
build, and bad input refused at build time naming the joint and the argument
(elements/joints.py, elements/drives.py, docs/joints.md)."""
import numpy as np
import pytest

from dttmm import (JointForce, JointMotion, PrismaticJoint, RevoluteJoint,
                   SpringDamper, System, UniversalJoint, simulate)
from dttmm.model.chains import unit_link
from dttmm.elements.joints import rotation_about
from helpers import joints_arm


def arm(drive=None):
    """The issue's arm: revolute (world y), revolute (link 1's z), universal (link 2's z, link
    3's y), prismatic (link 3's x) with a spring-damper; joint 1 turning at 0.5 rad/s."""
    return joints_arm(drive)


def test_the_arm_starts_turning_rigidly_about_y():
    model = arm(JointForce(lambda t, q, qd: 2.0 * np.sin(np.pi * t)))
    np.testing.assert_allclose(model.initial_angular_velocity, [[0, 0.5, 0]] * 4, atol=1e-15)
    np.testing.assert_allclose(model.initial_rotation, [np.eye(3)] * 4, atol=1e-15)
    assert [len(d) for d in model.drives] == [1, 1, 2, 1]
    spring = model.drives[3][0]
    assert spring["stiffness"] == 50.0 and spring["damping"] == 0.5 and spring["rest"] == 0.0


def test_initial_coordinates_turn_the_child():
    """A revolute joint's initial angle turns the child about the axis (in the parent's frame);
    a universal joint's two angles compose as Rot(n1, q1) Rot(n2, q2)."""
    system = System()
    system.add(unit_link(name="a"), RevoluteJoint(axis=[0, 0, 1], angle=0.3, rate=2.0))
    system.add(unit_link(name="b"), UniversalJoint([0, 0, 1], [0, 1, 0], angles=(0.2, -0.4),
                                                   rates=(1.0, 0.5)), parent="a")
    model = system.build()
    a0 = rotation_about(np.array([0, 0, 1.0]), 0.3)
    np.testing.assert_allclose(model.initial_rotation[0], a0, atol=1e-15)
    a1 = a0 @ rotation_about(np.array([0, 0, 1.0]), 0.2) @ rotation_about(np.array([0, 1.0, 0]),
                                                                          -0.4)
    np.testing.assert_allclose(model.initial_rotation[1], a1, atol=1e-14)
    w1 = np.array([0, 0, 2.0]) + a0 @ [0, 0, 1.0] + a1 @ [0, 0.5, 0]
    np.testing.assert_allclose(model.initial_angular_velocity[1], w1, atol=1e-14)


def test_a_prescribed_motion_sets_the_start():
    motion = JointMotion(lambda t: 0.5 * t + 0.2 * (1 - np.cos(2 * t)),
                         lambda t: 0.5 + 0.4 * np.sin(2 * t), lambda t: 0.8 * np.cos(2 * t))
    model = arm(motion)
    np.testing.assert_allclose(model.initial_angular_velocity[0], [0, 0.5, 0], atol=1e-15)


@pytest.mark.parametrize("joint, words", [
    (lambda: RevoluteJoint(axis=[0, 0, 0], name="j"), "'j'.*axis must be a nonzero vector"),
    (lambda: RevoluteJoint(axis=[np.inf, 0, 1], name="j"), "'j'.*axis.*NaN or infinite"),
    (lambda: PrismaticJoint(axis=[0, 0], name="j"), "'j'.*axis must have 3 entries"),
    (lambda: UniversalJoint([0, 0, 1], [0, 0, 0], name="j"), "'j'.*axis2 must be a nonzero"),
    (lambda: UniversalJoint([0, 0, 1], [0, 1, 0], angles=(0.1,), name="j"),
     "'j'.*angles must be a pair"),
    (lambda: RevoluteJoint([0, 0, 1], drive=lambda t: 1.0, name="j"),
     "'j'.*drive must be a JointForce, SpringDamper, JointMotion or PDTracking"),
    (lambda: RevoluteJoint([0, 0, 1], drive=JointForce(3.0), name="j"),
     "'j'.*drive function must be callable"),
    (lambda: RevoluteJoint([0, 0, 1], drive=JointForce(lambda t: 1.0), name="j"),
     r"'j'.*drive function must take \(t, q, q_dot\)"),
    (lambda: RevoluteJoint([0, 0, 1], drive=JointForce(lambda t, q, qd: [1.0, 2.0]), name="j"),
     "'j'.*must return one number"),
    (lambda: RevoluteJoint([0, 0, 1], drive=JointForce(lambda t, q, qd: np.nan), name="j"),
     "'j'.*returned nan"),
    (lambda: PrismaticJoint([1, 0, 0], drive=SpringDamper(-1.0), name="j"),
     "'j'.*drive stiffness must be >= 0"),
    (lambda: RevoluteJoint([0, 0, 1], drive=JointMotion(lambda t: t), name="j"),
     "'j'.*prescribed joint motion needs its velocity"),
    (lambda: RevoluteJoint([0, 0, 1], drive=JointMotion(lambda t: t, lambda t: 2.0,
                                                        lambda t: 0.0), name="j"),
     r"'j'.*prescribed velocity\(0\) = 2.0 contradicts"),
    (lambda: RevoluteJoint([0, 0, 1], angle=0.5, drive=JointMotion(
        lambda t: t, lambda t: 1.0, lambda t: 0.0), name="j"),
     "'j'.*angle = 0.5.*contradict the prescribed motion"),
])
def test_bad_joints_name_the_joint_and_argument(joint, words):
    with pytest.raises(ValueError, match=words):
        joint().validated(0)


def test_universal_axes_must_be_perpendicular_and_rates_consistent():
    system = System()
    system.add(unit_link(name="a"), UniversalJoint([0, 0, 1], [0, 0.6, 0.8], name="u"))
    with pytest.raises(ValueError, match="UniversalJoint before .*axis1 and axis2 must be "
                                         "perpendicular"):
        system.build()
    system = System()
    system.add(unit_link(name="a", angular_velocity=[1.0, 0, 0]),
               RevoluteJoint([0, 0, 1], name="r"))
    with pytest.raises(ValueError, match="'a'.*angular_velocity.*contradicts the RevoluteJoint"):
        system.build()


def test_what_dttmm_does_not_run_with_them_is_refused_by_name():
    with pytest.raises(ValueError, match="hinge 'joint1' is a revolute joint.*method='direct'"):
        simulate(arm(), 0.01, 1e-3, method="direct")
    with pytest.raises(ValueError, match="hinge 'joint1' is a revolute joint.*Newmark scheme.*"
                                         "scheme='newmark'"):
        simulate(arm(), 0.01, 1e-3, scheme="energy_momentum")


def test_each_joint_kind_declares_its_coordinates_and_the_solver_and_kernels_read_them():
    """The number of free coordinates is a fact of the kind's declaration (elements/kinds.py),
    read by the model, the reference and the kernels alike; the arm's joints (revolute,
    revolute, universal, prismatic) give its Result five coordinate columns."""
    from dttmm import simulate
    from dttmm.model.chains import arm
    from dttmm.elements.kinds import JOINT_KINDS, coordinate_count
    from dttmm.kernels.transfers.joint import n_coordinates
    declared = {k.name: len(k.coordinates) for k in JOINT_KINDS}
    assert {k: v for k, v in declared.items() if k in (
        "BallJoint", "FixedHinge", "ElasticHinge", "RevoluteJoint", "UniversalJoint",
        "PrismaticJoint")} == {"BallJoint": 0, "FixedHinge": 0, "ElasticHinge": 0,
                               "RevoluteJoint": 1, "UniversalJoint": 2, "PrismaticJoint": 1}
    for kind in JOINT_KINDS:
        assert coordinate_count(kind.code) == n_coordinates(kind.code) == len(kind.coordinates)
    assert coordinate_count(99) == n_coordinates(99) == 0 == n_coordinates(-1)
    res = simulate(arm(drive="motion"), 0.002, 1e-3)
    assert res.joint_coordinates.shape[1] == 5 == len(res.info["coordinate_names"])
