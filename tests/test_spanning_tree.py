"""System.build(tree="shortest") (issue 65, item 1): a system built as a chain of loops is
rebuilt on the breadth-first spanning tree from the ground, so each loop runs through a few
bodies; the same mechanism, the same motion (docs/loops.md, "Choosing the spanning tree")."""
import numpy as np
import pytest

import dttmm
from dttmm import (BallJoint, CylindricalJoint, ElasticHinge, EulerBernoulliBeam, FixedHinge,
                   Ground, PlanarJoint, PrismaticJoint, RevoluteJoint, RigidBody, SpringDamper,
                   System, UniversalJoint, simulate_reference)
from dttmm.model.assembly import assemble
from dttmm.elements.kinds import COORDINATE_0, RATE_0, row_axes
from dttmm.model.mechanisms import _frame, n_four_bar, parallelogram


def test_the_chain_built_four_bar_is_rooted_at_its_pivots():
    """The N-four-bar as a chain (every loop through v0) rebuilt: every vertical bar a root at
    its ground pivot, the horizontal bars on their neighbours, the joints' names kept."""
    model = n_four_bar(10, tree="shortest")
    roots = {model.body_names[k] for k in range(model.n_bodies) if model.parent[k] < 0}
    assert roots == {f"v{i}" for i in range(11)}
    assert set(model.closure_names) == {"B1"} | {f"H{i}" for i in range(2, 11)}
    assert "the loops share most bodies" not in model.describe()
    assert "the loops share most bodies" in n_four_bar(10).describe()


def test_the_rebuilt_four_bar_moves_as_the_local_tree_through_its_flat_position():
    """n = 2 over 1 s at dt 1e-3 (the bars pass horizontal, every pivot on one line, at
    0.714 s): every mass centre as the four-bar built on its ground pivots to 1e-9 m, and B0
    within 3e-6 m of the exact one-degree-of-freedom reduction (the local tree's own error)."""
    shortest, ground = n_four_bar(2, tree="shortest"), n_four_bar(2, tree="ground")
    a, b = dttmm.simulate(shortest, 1.0, 1e-3), dttmm.simulate(ground, 1.0, 1e-3)
    for name in ("v0", "v1", "v2", "h1", "h2"):
        i, j = shortest.body_names.index(name), ground.body_names.index(name)
        assert np.abs(a.position_mass_center[:, i] - b.position_mass_center[:, j]).max() < 1e-9
    h1 = shortest.body_names.index("h1")
    assert np.abs(a.position_input[:, h1, :2] - parallelogram(2, a.t)).max() < 3e-6


def _bar(name, rotation, **kw):
    return RigidBody(mass=1.0, inertia=[1e-3, 1 / 12, 1 / 12], inertia_about="mass_center",
                     to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0], rotation=rotation,
                     name=name, **kw)


def _rot_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return [[c, -s, 0], [s, c, 0], [0, 0, 1.0]]


def test_a_body_described_from_another_point_is_the_same_body():
    """A four-bar built as a chain whose rocker, its inertia given about its input point and a
    pendulum on a named point, is reached by the new tree at its ground pivot (its far end):
    every mass centre moves as in the system built as added (to 1e-6 m, the two trees' own
    errors at dt 1e-3 over 0.5 s), and the loop stays closed."""
    z = [0, 0, 1.0]

    def system():
        s = System(gravity=[0, -9.81, 0])
        s.add(_bar("crank", _rot_z(np.pi / 2)), RevoluteJoint(axis=z, rate=2.0, name="A"))
        s.add(_bar("coupler", np.eye(3)), RevoluteJoint(axis=z, name="B"), parent="crank")
        s.add(RigidBody(mass=1.5, inertia_about="input",
                        inertia=[[0.0026, -0.015, 0], [-0.015, 0.495, 0], [0, 0, 0.4956]],
                        to_mass_center=[0.5, 0.02, 0], to_output=[1.0, 0, 0],
                        points={"p": [0.3, 0, 0]},
                        rotation=_rot_z(-np.pi / 2), name="rocker"),
              RevoluteJoint(axis=z, name="C"), parent="coupler")
        s.add(_bar("pendulum", _rot_z(-np.pi / 3)), RevoluteJoint(axis=z, name="P"),
              parent="rocker", at="p")
        s.close(RevoluteJoint(axis=z, name="D"), "rocker", "ground")
        return s
    as_added = assemble(system().build(), keep=["A"])
    shortest = assemble(system().build(tree="shortest"), keep=["A"])
    assert shortest.parent[shortest.body_names.index("rocker")] == -1
    assert shortest.closure_names == ("C",)
    a, b = dttmm.simulate(as_added, 0.5, 1e-3), dttmm.simulate(shortest, 0.5, 1e-3)
    for name in ("crank", "coupler", "rocker", "pendulum"):
        i, j = as_added.body_names.index(name), shortest.body_names.index(name)
        assert np.abs(a.position_mass_center[:, i] - b.position_mass_center[:, j]).max() < 1e-6
    assert b.info["loop_position_residual"] < 1e-10


def test_what_cannot_be_rebuilt_is_refused_naming_it():
    z = [0, 0, 1.0]
    s = System(gravity=[0, -9.81, 0])
    s.add(_bar("crank", _rot_z(np.pi / 2)), RevoluteJoint(axis=z, name="A"))
    s.add(EulerBernoulliBeam(length=1.0, bending_stiffness=100.0, mass_per_length=1.0,
                             polar_inertia_per_length=1e-3, name="beam"), FixedHinge(),
          parent="crank")
    s.close(RevoluteJoint(axis=z, name="D"), "beam", "ground")
    with pytest.raises(ValueError, match=r"tree='shortest'.*'beam'.*input end is its root"):
        s.build(tree="shortest")
    with pytest.raises(ValueError, match="tree must be 'as added' or 'shortest'"):
        s.build(tree="bfs")


def test_a_closing_elastic_hinge_the_tree_would_take_is_refused():
    """A closing elastic hinge measures its deflection and rest rotation between its two
    points; in the tree it would start from zero (the link moved 0.045 m at t = 0, no error):
    tree='shortest' refuses to take it, naming it."""
    z = [0, 0, 1.0]
    s = System(gravity=[0, -9.81, 0])
    s.add(_bar("crank", _rot_z(np.pi / 2)), RevoluteJoint(axis=z, name="A"))
    s.add(_bar("link", _rot_z(-0.3)), RevoluteJoint(axis=z, name="B"), parent="crank")
    s.close(ElasticHinge(1e3, 10.0, name="E"), "ground", "link", at_a=[1.0, 0.7, 0.0])
    with pytest.raises(ValueError, match=r"tree='shortest'.*elastic hinge 'E' closes a loop"):
        s.build(tree="shortest")
    assert s.build().closure_names == ("E",)


# ---- joints with coordinates the new tree moves (into the tree from its loop, the other way,
# out of it): they start where the system as built stands

def _slider_joint(kind, drives):
    """The slider's joint "slide" of _slider_crank: along world x (the slider's x); driven
    (springs: x to rest 0.2 m, a planar joint's y to 0, a cylindrical joint's turn to 0) or
    not."""
    x, y = [1.0, 0, 0], [0, 1.0, 0]
    if kind == "prismatic":
        return PrismaticJoint(axis=x, drive=SpringDamper(40.0, 0.5, rest=0.2) if drives else
                              None, name="slide")
    if kind == "cylindrical":
        return CylindricalJoint(axis=x, drives=(SpringDamper(0.05, 1e-3), SpringDamper(
            40.0, 0.5, rest=0.2)) if drives else (None, None), name="slide")
    return PlanarJoint(axis1=x, axis2=y, drives=(SpringDamper(40.0, 0.5, rest=0.2), SpringDamper(
        30.0, 0.5, rest=0.0), None) if drives else (None, None, None), name="slide")


def _slider_crank(kind, reversed_, rod_w=None, c_rates=(0.0, 0.0)):
    """The IFToMM slider-crank (dttmm.model.mechanisms.slider_crank) built as a chain, the slider
    hanging from the rod by the universal joint C, its joint "slide" of `kind` closing the loop
    to the ground at the origin: from the ground to the slider (driven), or, reversed_, from
    the slider to the ground (undriven: the new tree runs it the other way).  rod_w, c_rates:
    the rod's angular velocity and C's rates at t = 0."""
    a, b, c = np.array([0, 0.1, 0.12]), np.array([0, 0.1, 0.2]), np.array([0.2, 0, 0])
    s = System(gravity=[0, 0, -9.81], ground=Ground(position=a))
    s.add(RigidBody(mass=0.12, inertia=[1e-4, 1e-4, 1e-5], inertia_about="mass_center",
                    to_mass_center=[0, 0, 0.04], to_output=[0, 0, 0.08], name="crank",
                    rotation=np.eye(3)), RevoluteJoint(axis=[1, 0, 0], rate=6.0, name="A"))
    rod_frame = _frame(c - b, [0, 0, 1.0])
    s.add(RigidBody(mass=0.5, inertia=[4e-4, 4e-3, 4e-3], inertia_about="mass_center",
                    to_mass_center=[0.15, 0, 0], to_output=[0.3, 0, 0], rotation=rod_frame,
                    angular_velocity=rod_w, name="rod"), BallJoint(name="B"), parent="crank")
    across = rod_frame.T @ (np.array([0, -2, 1.0]) / np.sqrt(5))
    s.add(RigidBody(mass=2.0, inertia=[1.5e-4, 1e-4, 1.2e-4], inertia_about="mass_center",
                    name="slider", rotation=np.eye(3)),
          UniversalJoint(axis1=across, axis2=[1, 0, 0], rates=tuple(c_rates), name="C"),
          parent="rod")
    joint = _slider_joint(kind, not reversed_)
    if reversed_:
        s.close(joint, "slider", "ground", at_b=[0, 0, 0])
    else:
        s.close(joint, "ground", "slider", at_a=[0, 0, 0])
    return s


def _consistent(kind, reversed_):
    """_slider_crank with its rates at t = 0 consistent with its loop (the rod's and C's, as
    the tree as added assembles them keeping "A"): both trees then start from one motion."""
    m = assemble(_slider_crank(kind, reversed_).build(), keep=["A"])
    k = m.body_names.index("slider")
    assert np.abs(m.hinge_params[k, COORDINATE_0][:2]).max() < 1e-12    # (it moved nothing)
    return _slider_crank(kind, reversed_, m.initial_angular_velocity[m.body_names.index("rod")],
                         m.hinge_params[k, RATE_0][:2])


def _largest_gap(a, model_a, b, model_b):
    """The largest distance (m) between two runs' mass centres, body by body (by name)."""
    return max(np.abs(a.position_mass_center[:, model_a.body_names.index(name)]
                      - b.position_mass_center[:, model_b.body_names.index(name)]).max()
               for name in model_a.body_names)


@pytest.mark.parametrize("reversed_", [False, True], ids=["into-the-tree", "the-other-way"])
@pytest.mark.parametrize("kind", ["prismatic", "cylindrical", "planar"])
def test_a_closing_joint_with_slides_the_tree_takes_starts_at_the_gap(kind, reversed_):
    """The slider-crank whose slider closes the loop on a joint with slides (_slider_crank):
    tree="shortest" takes that joint into the tree (the ground's second edge), from the
    ground to the slider or the other way (axes turned into the new parent's frame).  It
    starts at the gap between its points, 0.2 m along x (it restarted at 0, the slider at
    the origin, the loop 0.2 m open), with the rates of the bodies' motion: the loop closed at
    t = 0, positions and rates, to 1e-12 (measured at most 1.1e-16 m, 7.5e-16 m/s); the
    Newton-Euler reference's runs from both trees within 1e-10 m over 0.5 s (measured 4.0e-13
    to 1.0e-12 m; the slider travels 0.08-0.09 m), DT-TMM's by the trees' own errors (they step
    different coordinates: into the tree / the other way, prismatic 1.3e-6 / 5.8e-7 m,
    cylindrical 1.3e-6 / 5.7e-7, planar 7.1e-6 / 1.0e-5 at dt = 1e-3; 8.5e-8 / 3.6e-8,
    8.5e-8 / 3.6e-8, 4.3e-7 / 5.8e-7 at 2.5e-4: order 2)."""
    system = _consistent(kind, reversed_)
    as_added, shortest = system.build(), system.build(tree="shortest")
    k = shortest.body_names.index("slider")
    assert shortest.hinge_names[k] == "slide" and shortest.parent[k] == -1
    assert shortest.closure_names == ("C",)
    for model in (as_added, shortest):
        positions, rates = dttmm.loop_residuals(model)
        assert positions.max() < 1e-12 and rates.max() < 1e-12, (positions, rates)
    x = float(shortest.hinge_params[k, COORDINATE_0][0 if kind != "cylindrical" else 1])
    assert abs(x - 0.2) < 1e-14, x        # (closing from the slider: -0.2)
    t = np.linspace(0.0, 0.5, 51)
    a, b = (simulate_reference(m, 0.5, t_eval=t, rtol=1e-11, atol=1e-11)
            for m in (as_added, shortest))
    assert _largest_gap(a, as_added, b, shortest) < 1e-10
    for dt, bound in ((1e-3, 2e-5), (2.5e-4, 1e-6)):
        a, b = (dttmm.simulate(m, 0.5, dt) for m in (as_added, shortest))
        assert _largest_gap(a, as_added, b, shortest) < bound, dt
        assert b.info["loop_position_residual"] < 1e-10


def test_a_revolute_joint_run_the_other_way_keeps_its_axis():
    """The four-bar of test_a_body_described_from_another_point_is_the_same_body, its rocker's
    frame turned about its own x so that the closing joint D's axis in it is its y (world z):
    the new tree runs D the other way (the rocker on the ground), its axis turned into the
    ground's frame, world z (it came out along -x: the frames' product taken the other way,
    which only an axis the joint turns about in both frames, as in the planar four-bars,
    hides, and the loop locked: assemble refused to keep A's rate); the same run as the tree
    as added over 0.5 s (the rocker's mass centre travels 1 m): the references' 2.5e-13 m
    apart, DT-TMM's at dt = 1e-3 1.1e-14 m."""
    z = np.array([0, 0, 1.0])
    tilted = np.array(_rot_z(-np.pi / 2)) @ np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])

    def system():
        s = System(gravity=[0, -9.81, 0])
        s.add(_bar("crank", _rot_z(np.pi / 2)), RevoluteJoint(axis=z, rate=2.0, name="A"))
        s.add(_bar("coupler", np.eye(3)), RevoluteJoint(axis=z, name="B"), parent="crank")
        s.add(_bar("rocker", tilted), RevoluteJoint(axis=z, name="C"), parent="coupler")
        s.close(RevoluteJoint(axis=tilted.T @ z, name="D"), "rocker", "ground")
        return s
    as_added = assemble(system().build(), keep=["A"])
    shortest = assemble(system().build(tree="shortest"), keep=["A"])
    k = shortest.body_names.index("rocker")
    assert shortest.parent[k] == -1 and shortest.hinge_names[k] == "D"
    assert np.abs(row_axes(shortest.hinge_params[k])[0] - z).max() < 1e-15
    t = np.linspace(0.0, 0.5, 51)
    a, b = (simulate_reference(m, 0.5, t_eval=t, rtol=1e-11, atol=1e-11)
            for m in (as_added, shortest))
    assert _largest_gap(a, as_added, b, shortest) < 1e-10
    a, b = (dttmm.simulate(m, 0.5, 1e-3) for m in (as_added, shortest))
    assert _largest_gap(a, as_added, b, shortest) < 1e-9


def test_a_tree_joint_with_a_slide_the_tree_leaves_closes_the_loop():
    """An inverted slider-crank built as a chain: crank A on the ground, an arm on its tip (B),
    a sleeve sliding 0.5 m out along the arm (prismatic P) with a leg down to a pivot D on the
    ground.  tree="shortest" hangs the sleeve from D and leaves P to close the loop: its
    slide, measured between its points as every closing joint's, is the 0.5 m given (a closing
    joint's slide given a value was refused: "leave position 0"), the loop closed at t = 0 to
    1e-12 m (measured 0); the same run as the tree as added over 0.5 s (assembled keeping A;
    1 m of travel): the references' 7.9e-14 m apart, DT-TMM's 2.5e-7 m at dt = 1e-3 (1.5e-8 m
    at 2.5e-4: the trees' own errors)."""
    z = np.array([0, 0, 1.0])

    def system():
        s = System(gravity=[0, -9.81, 0])
        s.add(_bar("crank", _rot_z(np.pi / 2)), RevoluteJoint(axis=z, rate=2.0, name="A"))
        s.add(_bar("arm", np.eye(3)), RevoluteJoint(axis=z, name="B"), parent="crank")
        s.add(RigidBody(mass=1.0, inertia=[1 / 12, 1e-3, 1 / 12], inertia_about="mass_center",
                        to_mass_center=[0, -0.5, 0], to_output=[0, -1.0, 0], name="sleeve"),
              PrismaticJoint(axis=[1.0, 0, 0], position=0.5, name="P"), parent="arm")
        s.close(RevoluteJoint(axis=z, name="D"), "sleeve", "ground")
        return s
    as_added = assemble(system().build(), keep=["A"])
    shortest = system().build(tree="shortest")
    assert shortest.closure_names == ("P",)
    assert shortest.parent[shortest.body_names.index("sleeve")] == -1
    positions, _ = dttmm.loop_residuals(shortest)
    assert positions.max() < 1e-12
    assert abs(shortest.closure_params[0, COORDINATE_0][0] - 0.5) < 1e-15
    shortest = assemble(shortest, keep=["A"])
    t = np.linspace(0.0, 0.5, 51)
    a, b = (simulate_reference(m, 0.5, t_eval=t, rtol=1e-11, atol=1e-11)
            for m in (as_added, shortest))
    assert _largest_gap(a, as_added, b, shortest) < 1e-10
    a, b = (dttmm.simulate(m, 0.5, 1e-3) for m in (as_added, shortest))
    assert _largest_gap(a, as_added, b, shortest) < 2e-6
