"""System.build(tree="shortest") (issue 65, item 1): a system built as a chain of loops is
rebuilt on the breadth-first spanning tree from the ground, so each loop runs through a few
bodies; the same mechanism, the same motion (docs/loops.md, "Choosing the spanning tree")."""
import numpy as np
import pytest

import dttmm
from dttmm import EulerBernoulliBeam, FixedHinge, RevoluteJoint, RigidBody, System
from dttmm.assembly import assemble
from dttmm.mechanisms import n_four_bar, parallelogram


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
