"""Closed loops: the closure table (System.close, Model.closure_*), its checks, and the pinned
tip as one of its rows (docs/loops.md)."""
import numpy as np
import pytest

import dttmm
from dttmm import (BallJoint, FixedHinge, PrismaticJoint,
                   RevoluteJoint, RigidBody, System, UniversalJoint, build_chain, simulate,
                   simulate_reference)
from dttmm.model.loop_rows import GROUND
from dttmm.model.loop_kinematics import closure_gaps, closure_points
from dttmm.elements import BALL, PRISMATIC, REVOLUTE, UNIVERSAL

from helpers import rot_z

UP = rot_z(np.pi / 2)       # a bar's x axis along world y


def bar(name, length=1.0, mass=1.0, **kw):
    return RigidBody(mass=mass, inertia=[1e-3, length ** 2 / 12, length ** 2 / 12],
                     inertia_about="mass_center", to_mass_center=[length / 2, 0, 0],
                     to_output=[length, 0, 0], name=name, **kw)


def four_bar():
    """A unit square four-bar: the left bar up from the ground point (0, 0), the coupler from
    its top to (1, 1), the right bar down from there; a stub welded to the coupler.  Closing
    the right bar's end to the ground at (1, 0) makes the loop."""
    system = System(gravity=[0, -9.81, 0])
    left = system.add(bar("left", rotation=UP), RevoluteJoint(axis=[0, 0, 1]), parent="ground")
    top = system.add(bar("top", rotation=np.eye(3)), RevoluteJoint(axis=[0, 0, 1]), parent=left)
    system.add(bar("right", rotation=rot_z(-np.pi / 2)), RevoluteJoint(axis=[0, 0, 1]),
               parent=top)
    system.add(bar("stub", 0.1), FixedHinge(), parent=top)
    return system


def test_the_pinned_tip_is_one_row_of_the_closure_table_and_runs_as_before():
    """build_chain(tip="ball") is a ball joint from the last output point to the ground where
    it starts, and both loops give what they gave before the table (commit 426d217, numbers
    recorded there: the ball-chain loop and the general loop, to 1e-12)."""
    rod = dict(mass=1.0, inertia=[1e-4, 1 / 12, 1 / 12], inertia_about="mass_center",
               to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0])
    model = build_chain([BallJoint(), RigidBody(**rod, rotation=rot_z(-0.3)), BallJoint(),
                         RigidBody(**rod, rotation=rot_z(-np.pi / 2)), BallJoint(),
                         RigidBody(**rod, rotation=rot_z(np.pi))], tip="ball",
                        gravity=[0, -9.81, -3.0])
    assert model.n_closures == 1 and model.tip_pinned
    assert model.closure_kind.tolist() == [BALL]
    assert model.closure_body.tolist() == [[2, GROUND]]
    tip = [np.cos(0.3) - 1.0, -np.sin(0.3) - 1.0, 0.0]          # where the tip starts
    assert np.allclose(model.closure_point[0], [[1.0, 0, 0], tip], rtol=0, atol=1e-15)
    assert closure_gaps(model)[0] == 0.0
    before = {"ball-chain": [[-0.034545278066799, -0.995788446787426, -0.084923453815601],
                             [0.731708356481159, -1.337840075443703, -0.628849966200898],
                             [-0.04466381865044, -1.295522339099221, 2.524350032e-06]],
              "general": [[-0.034545278066797, -0.995788446787428, -0.084923453815602],
                          [0.731708356481158, -1.337840075443714, -0.628849966200901],
                          [-0.044663818650444, -1.295522339099225, 2.524350024e-06]]}
    for full_state in (False, True):
        result = simulate(model, 0.5, 1e-3, full_state=full_state)
        assert np.allclose(result.position_output[-1], before[result.info["loop"]], rtol=0,
                           atol=1e-12)
    # the same row written out by hand is the same model
    system = System(gravity=[0, -9.81, -3.0])
    links = [system.add(RigidBody(**rod, rotation=rot_z(a), name=f"l{i}"), BallJoint(),
                        parent=f"l{i - 1}" if i else None)
             for i, a in enumerate((-0.3, -np.pi / 2, np.pi))]
    system.close(BallJoint(name="tip"), links[-1], "ground")
    by_hand = system.build()
    assert by_hand.tip_pinned
    assert np.array_equal(by_hand.closure_params, model.closure_params)
    again = simulate(by_hand, 0.5, 1e-3)
    assert np.array_equal(again.position_output[-1], before["ball-chain"]) or np.allclose(
        again.position_output[-1], before["ball-chain"], rtol=0, atol=1e-12)
    # and run as a row of the loops' table instead of the sweeps' tip condition
    # (closures.PINNED_TIP_SWEEP off), the same physics: both within second-order reach of
    # the reference (measured 2.1e-5 and 1.4e-5 m at dt = 1e-3, 5.3e-6 and 3.5e-6 at 5e-4;
    # the tip moves 1 m)
    ref = simulate_reference(model, 0.5, t_eval=[0.0, 0.5], rtol=1e-11, atol=1e-13)
    try:
        dttmm.model.closures.PINNED_TIP_SWEEP = False
        assert not model.tip_pinned
        as_row = simulate(model, 0.5, 1e-3)
    finally:
        dttmm.model.closures.PINNED_TIP_SWEEP = True
    assert as_row.info["loop_position_residual"] < 1e-10
    assert np.abs(again.position_output[-1] - ref.position_output[-1]).max() < 3e-5
    assert np.abs(as_row.position_output[-1] - ref.position_output[-1]).max() < 2e-5


def test_a_closing_joint_reads_its_rest_from_the_frames_at_the_start():
    system = four_bar()
    # the right bar's end onto the ground's (1, 0): a revolute joint about z
    system.close(RevoluteJoint(axis=[0, 0, 1], name="pin"), "right", "ground")
    model = system.build()
    assert model.n_closures == 1 and not model.tip_pinned
    assert model.closure_kind.tolist() == [REVOLUTE]
    assert model.closure_body.tolist() == [[2, GROUND]]
    assert model.closure_names == ("pin",)
    assert closure_gaps(model)[0] < 1e-15
    p_a, p_b, f_a, f_b = closure_points(model)
    assert np.allclose(p_a[0], [1.0, 0.0, 0.0]) and np.allclose(p_b[0], [1.0, 0.0, 0.0])
    r0 = model.closure_params[0, 0:9].reshape(3, 3)
    assert np.allclose(f_a[0] @ r0, f_b[0])               # F_b = F_a Rot(n, 0) R0
    # the ground's point defaults to where the other side's starts; given, it may leave a gap
    ground = four_bar()
    ground.close(BallJoint(), "top", "ground")
    ground.close(PrismaticJoint(axis=[1, 0, 0]), "ground", "right", at_a=[0.0, 0.0, 0.0])
    ground.close(UniversalJoint(axis1=[0, 0, 1], axis2=[0, 1, 0]), "left", "top", at_a="input",
                 at_b=[0.5, 0.0, 0.0])
    model = ground.build()
    assert model.closure_kind.tolist() == [BALL, PRISMATIC, UNIVERSAL]
    gaps = closure_gaps(model)
    assert gaps[0] == 0.0
    assert gaps[1] < 1e-15                       # (1, 0) lies on the slide y = 0 along x
    assert np.isclose(model.closure_params[1, 51], 1.0)     # the slide's coordinate, measured
    assert np.isclose(gaps[2], np.hypot(0.5, 1.0))          # (0, 0) against (0.5, 1)


def test_the_closed_four_bar_is_described_and_a_loop_on_a_moving_ground_refused_in_statics():
    system = four_bar()
    system.close(RevoluteJoint(axis=[0, 0, 1], name="pin"), "right", "ground")
    model = system.build()
    moving = four_bar()
    moving.ground = dttmm.Ground(motion=dttmm.PrescribedMotion.spin_about_axis(
        [0, 1, 0], angle=lambda t: 0.1 * t, rate=lambda t: 0.1, acceleration=lambda t: 0.0))
    moving.close(RevoluteJoint(axis=[0, 0, 1], name="pin"), "right", "ground")
    with pytest.raises(ValueError, match="'pin'.*solved here on a fixed ground so far, and the "
                                         "ground moves; simulate and the Newton-Euler"):
        dttmm.static_equilibrium(moving.build())
    text = model.describe()
    assert "closure 0 'pin': a revolute joint from 'right' at [1.0, 0.0, 0.0] to the ground" \
        in text
    assert ("3 degrees of freedom in the tree, closed by 1 joint with 5 constraint equations, 3 "
            "of them redundant: mobility 1" in text)
    assert "projected back onto the loops after every step" in text
    assert "each of the 5 rows' sweep columns passes 4 of the 4 bodies" in text


def test_a_loop_through_an_elastic_hinge_rests_where_static_equilibrium_puts_it():
    """The four-bar hanging (gravity along +y), closed through a tail on an elastic hinge:
    the static equilibrium (the hinge's deflection and the bars' swing under gravity) is a
    rest state of the independent reference (to 1e-9 m over 0.3 s) and of DT-TMM."""
    soft = four_bar()
    soft.gravity = (0.0, 9.81, 0.0)
    soft.add(RigidBody(mass=1.0, inertia=[1e-3, 0.1, 0.1], inertia_about="mass_center",
                       to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0], name="tail"),
             dttmm.ElasticHinge(translational_stiffness=1e4, rotational_stiffness=1e2,
                                name="spring"), parent="right")
    soft.close(RevoluteJoint(axis=[0, 0, 1], name="pin"), "tail", "ground")
    equilibrium = dttmm.static_equilibrium(soft.build())
    model = equilibrium.model
    deflection = model.hinge_params[model.hinge_names.index("spring"), 45:48]
    assert np.abs(deflection).max() > 1e-4                 # the spring carries load
    ref = simulate_reference(model, 0.3, t_eval=np.linspace(0.0, 0.3, 7), rtol=1e-10,
                             atol=1e-12)
    assert np.abs(ref.position_output - ref.position_output[0]).max() < 1e-9
    result = simulate(model, 0.3, 1e-3)
    assert np.abs(result.position_output - ref.position_output[0]).max() < 1e-9


@pytest.mark.parametrize("close, message", [
    (lambda s: s.close(BallJoint(), "top", "top"), "closes body 'top' to itself"),
    (lambda s: s.close(BallJoint(), "ground", "ground"), "closes the ground to itself"),
    (lambda s: s.close(BallJoint(), "stub", "top", at_b="input"), "welded to each other"),
    (lambda s: s.close(BallJoint(), "nobody", "top"), "'nobody' is not a body of the system"),
    (lambda s: s.close(BallJoint(), 3.0, "top"), "a must be a body of the system"),
    (lambda s: s.close(BallJoint(), "top", "left", at_b="elbow"), "has no point 'elbow'"),
    (lambda s: s.close(bar("extra"), "top", "left"),
     "joint must be one of"),
    (lambda s: s.close(RevoluteJoint(axis=[0, 0, 0]), "right", "ground"), "axis must be a nonzero"),
    (lambda s: s.close(RevoluteJoint(axis=[0, np.nan, 1]), "right", "ground"), "axis"),
    (lambda s: s.close(UniversalJoint(axis1=[0, 0, 1], axis2=[0, 0, 1]), "right", "ground"),
     "must be perpendicular at the start; at t = 0 they make 0 deg"),
    (lambda s: s.close(FixedHinge(rotation=rot_z(0.1)), "right", "ground"),
     "rotation contradicts the bodies' frames"),
    (lambda s: s.close(PrismaticJoint(axis=[1, 0, 0], position=0.2), "right", "ground"),
     "leave position 0"),
    (lambda s: s.close(RevoluteJoint(axis=[0, 0, 1], rate=5.0), "right", "ground"),
     "rates follow from the motion of the bodies it joins.*leave rate 0"),
    (lambda s: s.close(UniversalJoint(axis1=[0, 0, 1], axis2=[1, 0, 0], rates=(0.0, 2.0)),
                       "right", "ground"), r"leave rates\[1\] 0"),
    (lambda s: s.close(BallJoint(), "top", "ground", at_b="output"), "on the ground is a position"),
])
def test_bad_closing_joints_are_refused_at_build_naming_the_joint(close, message):
    system = four_bar()
    close(system)
    with pytest.raises(ValueError, match=message):
        system.build()


def test_a_closure_on_a_moving_ground_and_tip_ball_on_a_tree_say_what_to_do():
    hub = dttmm.PrescribedMotion.spin_about_axis([0, 0, 1], angle=lambda t: t,
                                                 rate=lambda t: 1.0, acceleration=lambda t: 0.0)
    with pytest.raises(ValueError, match="moving ground"):
        build_chain([BallJoint(), bar("a")], tip="ball", ground=dttmm.Ground(motion=hub))
    system = four_bar()
    with pytest.raises(ValueError, match="System.close"):
        system.build(tip="ball")


def test_closing_joints_in_scene_files_round_trip():
    """[[close]] tables build the same closure table as System.close, and save_scene writes
    them back (the rest rotation read again from the saved frames)."""
    from dttmm.interfaces.scene import scene_from_dict, scene_of
    system = four_bar()
    system.close(RevoluteJoint(axis=[0, 0, 1], name="pin"), "right", "ground")
    model = system.build()
    data = scene_of(model, name="four_bar")
    assert data["close"] == [{"type": "revolute", "name": "pin", "a": "right", "b": "ground",
                              "at_a": [1.0, 0.0, 0.0], "at_b": [1.0, 0.0, 0.0],
                              "axis": [0.0, 0.0, 1.0]}]
    again = scene_from_dict(data).model
    for name in ("closure_kind", "closure_body", "closure_point", "closure_on_end",
                 "closure_params"):
        assert np.allclose(getattr(again, name), getattr(model, name), rtol=0, atol=1e-15)
    bad = dict(data, close=[{"type": "revolute", "a": "right", "axis": [0, 0, 0]}])
    with pytest.raises(ValueError, match=r"\[\[close\]\] 1.*axis must be a nonzero"):
        scene_from_dict(bad, "four_bar.toml")
    with pytest.raises(ValueError, match=r"\[\[close\]\] 1: unknown key 'parent'"):
        scene_from_dict(dict(data, close=[{"type": "ball", "a": "right", "parent": "x"}]))


def _crank(rate):
    return dttmm.JointMotion(position=lambda t: rate * t, velocity=lambda t: rate,
                             acceleration=lambda t: 0.0)


def test_a_drive_on_a_joint_the_loop_locks_is_refused_naming_it():
    """A prescribed motion the loop cannot follow (issue 29's bad input): the four-bar's left
    crank driven and its coupler's joint driven too (one freedom, two motions), or a joint
    the loop holds still; assemble, simulate and the reference refuse it, naming the joint
    and the closing joint.  One drive on the crank is accepted."""
    def system(drive_top):
        s = System(gravity=[0, -9.81, 0])
        left = s.add(bar("left", rotation=UP),
                     RevoluteJoint(axis=[0, 0, 1], drive=_crank(1.0), name="crank"))
        top = s.add(bar("top", rotation=np.eye(3)),
                    RevoluteJoint(axis=[0, 0, 1], name="elbow",
                                  drive=_crank(0.5) if drive_top else None), parent=left)
        s.add(bar("right", rotation=rot_z(-np.pi / 2)), RevoluteJoint(axis=[0, 0, 1]),
              parent=top)
        s.close(RevoluteJoint(axis=[0, 0, 1], name="pin"), "right", "ground")
        return s.build()
    dttmm.assemble(system(False))                   # one drive: accepted
    model = system(True)
    for run in (dttmm.assemble, lambda m: simulate(m, 0.01, 1e-3),
                lambda m: dttmm.simulate_reference(m, 0.01)):
        with pytest.raises(ValueError, match="prescribed motion of joint '(crank|elbow)' "
                                             r"\(coordinate 1\) cannot move: closing joint\(s\) "
                                             "'pin' lock it"):
            run(model)
