"""Assembly says what it did (issue 65, item 4): closing the loops reports how far each body
moved (m, rad) and warns where a body moved beyond 1% of the model's reach or 0.01 rad; a loop
that cannot close is refused with its gap in metres and in radians apart, and the smallest gap
reached."""
import warnings

import numpy as np
import pytest

import dttmm
from dttmm.model.loop_kinematics import AssemblyWarning

UP = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]          # a bar's x along world y


def bar(name, **kw):
    return dttmm.RigidBody(mass=1.0, inertia=[1e-3, 1 / 12, 1 / 12], inertia_about="mass_center",
                           to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0], name=name, **kw)


def square_four_bar(pivot):
    """A unit-square four-bar: the left bar on the ground's origin, the top bar on its tip, the
    right bar hanging from the top bar's end; the right bar's tip is closed to the ground point
    `pivot` (where the links reach: (1, 0, 0))."""
    z = [0, 0, 1.0]
    system = dttmm.System(gravity=[0, -9.81, 0])
    system.add(bar("left", rotation=UP), dttmm.RevoluteJoint(axis=z))
    system.add(bar("top", rotation=np.eye(3)), dttmm.RevoluteJoint(axis=z), parent="left")
    system.add(bar("right", rotation=[[0, 1, 0], [-1, 0, 0], [0, 0, 1]]),
               dttmm.RevoluteJoint(axis=z), parent="top")
    system.close(dttmm.RevoluteJoint(axis=z, name="pivot"), "right", "ground", at_b=pivot)
    return system.build()


def test_a_closed_model_assembles_without_a_word():
    with warnings.catch_warnings():
        warnings.simplefilter("error", AssemblyWarning)
        model = dttmm.assemble(square_four_bar([1.0, 0, 0]))
    assert "bodies moved at most 0 m" in model.describe()


def test_a_pivot_out_of_place_is_reached_by_moving_bodies_and_said():
    """The pivot 0.3 m to the right of where the links reach (a parallelogram becomes a
    trapezoid): assemble closes it (before: silently) and names the bodies it moved, with the
    distance and the angle; describe() says the largest."""
    with pytest.warns(AssemblyWarning, match=r"moved bodies beyond 0\.01 .*'left' .* m and .* "
                                               r"rad") as caught:
        model = dttmm.assemble(square_four_bar([1.3, 0, 0]))
    message = str(caught[0].message)
    assert "'right'" in message and "the mechanism simulated is not the one given" in message
    pos, _ = dttmm.loop_residuals(model)
    assert pos.max() < 1e-10
    assert "assembled" in model.describe() and "rad ('" in model.describe()


def test_a_pivot_out_of_reach_is_refused_with_metres_and_radians():
    """The pivot 5 m away: the links cannot reach; the gap left is given in m and in rad apart
    (before: 'a gap of 14.42 (m or rad) is left ... (from 5)', a gap that grew, units mixed),
    with the smallest reached."""
    with pytest.raises(ValueError, match=r"cannot close: after \d+ iterations a gap of [0-9.e+-]+ "
                                         r"m and [0-9.e+-]+ rad is left .*the smallest reached"):
        dttmm.assemble(square_four_bar([5.0, 0, 0]))


def test_describe_gives_a_closed_loops_true_mobility():
    """Issue 65, item 6: a closed one-degree-of-freedom four-bar (its spatial revolute joints
    redundant in the plane) said 'mobility at least -2' and 'tip free'; now its mobility is
    Grübler's count corrected by the rank of the constraint rows, and it is 'closed by 1
    joint'."""
    text = dttmm.assemble(square_four_bar([1.0, 0, 0])).describe()
    assert "3 of them redundant: mobility 1 as a rigid mechanism" in text
    assert "closed by 1 joint" in text and "tip free" not in text
    from dttmm.model.mechanisms import slider_crank, stewart_platform
    assert "mobility 1 as a rigid mechanism" in slider_crank().describe()
    assert "0 of them redundant: mobility 6" in stewart_platform("motion").describe()
