"""Roots at their own places on the ground (System.add(body, joint, at=[x, y, z]), issue 65):
a mechanism's ground pivots without a body welded to the ground to carry them.

The independent check is the same system with a hub welded to the ground carrying the roots on
its named points (the attachment path every tree already takes): both sides, DT-TMM and the
Newton-Euler reference, on a ground that spins up about a tilted axis (the places' velocity
and acceleration w_g x arm, w_g' x arm + w_g x (w_g x arm) all in play)."""
import numpy as np
import pytest

import dttmm
from dttmm import BallJoint, Ground, PrescribedMotion, RevoluteJoint, RigidBody, System
from dttmm.elements.joints import rotation_about

PLACE_A, PLACE_B = [0.3, 0.2, 0.1], [-0.4, 0.0, 0.25]


def _bar(name, rotation=None):
    return RigidBody(mass=1.0, inertia=[2e-3, 1 / 12, 1 / 12], inertia_about="mass_center",
                     to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0], rotation=rotation,
                     name=name)


def _spinning_ground():
    return Ground(motion=PrescribedMotion.spin_about_axis(
        [0.2, 0.1, 1.0], lambda t: 0.75 * t * t, lambda t: 1.5 * t, lambda t: 1.5))


def _pair(ground):
    """(placed, hub): two bars (one on a ball joint, one on a revolute joint with a third bar
    hanging from it) rooted at two places on the ground, and the same on a welded hub."""
    tilt = rotation_about([0, 0, 1.0], 0.4)
    placed = System(gravity=[0, -9.81, 0], ground=ground)
    placed.add(_bar("a", tilt), BallJoint(), at=PLACE_A)
    placed.add(_bar("b"), RevoluteJoint(axis=[0, 1.0, 1.0], rate=2.0), at=PLACE_B)
    placed.add(_bar("c"), BallJoint(), parent="b")
    hub = System(gravity=[0, -9.81, 0], ground=ground)
    hub.add(RigidBody(mass=3.0, inertia=[1.0, 1.0, 1.0], inertia_about="mass_center",
                      points={"pa": PLACE_A, "pb": PLACE_B}, name="hub"), dttmm.FixedHinge())
    hub.add(_bar("a", tilt), BallJoint(), parent="hub", at="pa")
    hub.add(_bar("b"), RevoluteJoint(axis=[0, 1.0, 1.0], rate=2.0), parent="hub", at="pb")
    hub.add(_bar("c"), BallJoint(), parent="b")
    return placed.build(), hub.build()


def _bodies(result, model):
    idx = [model.body_names.index(name) for name in ("a", "b", "c")]
    return (result.position_output[:, idx], result.rotation[:, idx],
            result.position_input[:, idx])


def test_roots_at_ground_places_move_as_on_a_welded_hub():
    """On a ground spinning up (0.75 t^2 rad about a tilted axis) over 0.5 s: DT-TMM with the
    roots placed equals DT-TMM on the hub to rounding (1e-12 m: the ground anchors are the
    hub's weld, without its mass, which the ground carries); the reference with the roots
    placed (its own kinematics of a place on a moving ground) equals the reference on the hub
    to its tolerance; and DT-TMM converges to the reference at order 2."""
    placed, hub = _pair(_spinning_ground())
    t = np.linspace(0.0, 0.5, 6)
    a = dttmm.simulate(placed, 0.5, 1e-3, t_eval=t)
    b = dttmm.simulate(hub, 0.5, 1e-3, t_eval=t)
    for x, y in zip(_bodies(a, placed), _bodies(b, hub)):
        assert np.abs(x - y).max() < 1e-12
    ref = dttmm.simulate_reference(placed, 0.5, t_eval=t, rtol=1e-12, atol=1e-14)
    ref_hub = dttmm.simulate_reference(hub, 0.5, t_eval=t, rtol=1e-12, atol=1e-14)
    for x, y in zip(_bodies(ref, placed), _bodies(ref_hub, hub)):
        assert np.abs(x - y).max() < 1e-9
    # the roots' input points sit at their places, turned with the ground
    rot_g = placed.ground_state(0.5)[3]
    assert np.allclose(ref.position_input[-1, 0], rot_g @ PLACE_A, atol=1e-12)
    assert np.allclose(a.position_input[-1, 1], rot_g @ PLACE_B, atol=1e-12)
    errors = []
    for dt in (2e-3, 1e-3):
        got = dttmm.simulate(placed, 0.5, dt, t_eval=t)
        errors.append(np.abs(got.position_output - ref.position_output).max())
    assert 3.2 < errors[0] / errors[1] < 5.0, errors
    assert errors[1] < 1e-4, errors


def test_a_place_on_a_fixed_turned_ground_and_its_statics():
    """Ground(position, rotation): a root's place is in the ground frame from the ground point;
    the run and statics put the root's input point there, a hanging bar under it."""
    turn = [[0, -1.0, 0], [1.0, 0, 0], [0, 0, 1.0]]
    system = System(gravity=[0, -9.81, 0], ground=Ground(position=[1.0, 2.0, 3.0], rotation=turn))
    system.add(_bar("hanging", [[0, 1.0, 0], [-1.0, 0, 0], [0, 0, 1.0]]),
               RevoluteJoint(axis=[0, 0, 1.0]), at=[0.5, 0.0, 0.0])
    model = system.build()
    place = np.array([1.0, 2.5, 3.0])                # (1, 2, 3) + turn @ (0.5, 0, 0)
    result = dttmm.simulate(model, 0.2, 1e-3)
    assert np.allclose(result.position_input[:, 0], place, atol=1e-12)
    assert np.allclose(result.position_output[:, 0], place + [0, -1.0, 0], atol=1e-12)
    statics = dttmm.static_equilibrium(model)
    assert np.allclose(statics.positions()[0][0], place, atol=1e-12)
    assert "to the ground at [0.5 0.  0. ] m" in model.describe()


def test_a_scene_keeps_the_places():
    """save_scene writes a root's place as at = [x, y, z]; loading it builds the same model."""
    placed, _ = _pair(Ground())
    from dttmm.interfaces.scene import scene_from_dict, scene_of
    data = scene_of(placed)
    model = scene_from_dict(data).model
    assert np.allclose(model.attachment_point, placed.attachment_point)


@pytest.mark.parametrize("at, message", [
    ("pivot", "the ground has no named points"),
    ([0.0, np.nan, 1.0], "at (a point of the ground)"),
    ([1.0, 2.0], "at (a point of the ground)"),
])
def test_a_bad_place_is_refused_naming_the_body(at, message):
    system = System()
    system.add(_bar("left"), BallJoint(), at=at)
    with pytest.raises(ValueError, match=r"left"):
        system.build()
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        system.build()


def test_a_chain_rooted_at_a_place_is_the_chain_on_a_moved_ground_point():
    """A ball chain whose root stands at [0.3, -0.2, 0.5] moves as the same chain on a ground
    point moved there (Ground(position=...)): the chain's positions and rotations to 1e-12
    (measured 4e-15; the placed chain runs on the general loop through its anchor's weld, the
    other on the fused ball loop)."""
    place = [0.3, -0.2, 0.5]

    def chain(at, ground):
        system = System(gravity=[0, -9.81, 0], ground=ground)
        parent = None
        for i in range(4):
            parent = system.add(_bar(f"l{i}", rotation_about([0, 0, 1.0], 0.3 * i)),
                                BallJoint(), parent=parent, at=at if i == 0 else None)
        return system.build()
    placed, moved = chain(place, Ground()), chain(None, Ground(position=place))
    a = dttmm.simulate(placed, 0.3, 1e-3, t_eval=[0.0, 0.15, 0.3])
    b = dttmm.simulate(moved, 0.3, 1e-3, t_eval=[0.0, 0.15, 0.3])
    assert np.abs(a.position_output - b.position_output).max() < 1e-12
    assert np.abs(a.rotation - b.rotation).max() < 1e-12
    assert np.allclose(a.position_input[:, 0], place, atol=1e-14)
