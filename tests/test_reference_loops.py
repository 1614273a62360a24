"""The Newton-Euler reference with closed loops (docs/loops.md, docs/reference.md): published
values, exact reductions, two spanning trees of one mechanism, and assembly."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import dttmm
from dttmm import (BallJoint, PrismaticJoint, RevoluteJoint, RigidBody, System, UniversalJoint,
                   simulate_reference)

from helpers import rot_z


def _frame(x_axis, z_hint):
    x = np.asarray(x_axis, float) / np.linalg.norm(x_axis)
    y = np.cross(z_hint, x)
    y /= np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


def iftomm_slider_crank(tree="slider on the rod"):
    """The IFToMM spatial slider-crank (issue 29's data), from two spanning trees: the slider
    hanging from the rod by the universal joint and closed to the ground by its prismatic
    joint, or sliding on the ground (its point C offset from the ground point A) and closed to
    the rod by the universal joint."""
    a, b, c = np.array([0, 0.1, 0.12]), np.array([0, 0.1, 0.2]), np.array([0.2, 0, 0])
    system = System(gravity=[0, 0, -9.81], ground=dttmm.Ground(position=a))
    system.add(RigidBody(mass=0.12, inertia=[1e-4, 1e-4, 1e-5], inertia_about="mass_center",
                         to_mass_center=[0, 0, 0.04], to_output=[0, 0, 0.08], name="crank",
                         rotation=np.eye(3)), RevoluteJoint(axis=[1, 0, 0], rate=6.0, name="A"))
    rod_frame = _frame(c - b, [0, 0, 1.0])
    system.add(RigidBody(mass=0.5, inertia=[4e-4, 4e-3, 4e-3], inertia_about="mass_center",
                         to_mass_center=[0.15, 0, 0], to_output=[0.3, 0, 0],
                         rotation=rod_frame, name="rod"), BallJoint(name="B"), parent="crank")
    across = rod_frame.T @ (np.array([0, -2, 1.0]) / np.sqrt(5))     # in the rod's frame
    if tree == "slider on the rod":
        system.add(RigidBody(mass=2.0, inertia=[1e-4] * 3, inertia_about="mass_center",
                             name="slider", rotation=np.eye(3)),
                   UniversalJoint(axis1=across, axis2=[1, 0, 0], name="C"), parent="rod")
        system.close(PrismaticJoint(axis=[1, 0, 0], name="slide"), "ground", "slider",
                     at_a=[0, 0, 0])
    else:
        system.add(RigidBody(mass=2.0, inertia=[1e-4] * 3, inertia_about="mass_center",
                             to_mass_center=-a, to_output=-a, name="slider"),
                   PrismaticJoint(axis=[1, 0, 0], position=0.2, name="slide"))
        system.close(UniversalJoint(axis1=[1, 0, 0], axis2=across, name="C"), "slider", "rod")
    return dttmm.assemble(system.build(), keep=["A"])


def test_slider_crank_energy_is_the_published_value_and_two_trees_agree():
    """Assembled from the crank's rate alone, the mechanism starts with the benchmark's energy
    0.76643568 J (z = 0 the datum), keeps it to 1e-10 J over 5 s, and the two spanning trees
    (a prismatic or a universal closing joint) move the slider alike to 1e-9 m."""
    t = np.linspace(0.0, 5.0, 251)
    runs = {}
    for tree in ("slider on the rod", "slider on the ground"):
        model = iftomm_slider_crank(tree)
        positions, rates = dttmm.loop_residuals(model)
        assert positions.max() < 1e-15 and rates.max() < 1e-15
        runs[tree] = result = simulate_reference(model, 5.0, t_eval=t)
        energy = result.kinetic + result.potential
        assert abs(energy[0] - 0.76643568) < 1e-12
        assert np.abs(energy - energy[0]).max() < 1e-10
    on_rod = runs["slider on the rod"].position_input[:, 2]
    on_ground = runs["slider on the ground"].position_output[:, 2]
    assert np.abs(on_rod[:, 1:]).max() < 1e-10              # on its slide, the x axis
    assert np.abs(on_rod - on_ground).max() < 1e-9
    assert 0.12 < on_rod[:, 0].min() and on_rod[:, 0].max() < 0.36       # it moves


def n_four_bar(n):
    """The N-four-bar (issue 29's A02): the tree is the first vertical bar on the ground point,
    the horizontal bars end to end, each further vertical bar hanging down from a horizontal
    bar's end; each is closed to the ground at (i, 0) by a revolute joint."""
    def bar(name, rotation):
        return RigidBody(mass=1.0, inertia=[1e-3, 1 / 12, 1 / 12], inertia_about="mass_center",
                         to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0], rotation=rotation,
                         name=name)
    z = [0, 0, 1.0]
    system = System(gravity=[0, -9.81, 0])
    system.add(bar("v0", rot_z(np.pi / 2)), RevoluteJoint(axis=z, rate=-1.0, name="O0"))
    inboard = "v0"
    for i in range(1, n + 1):
        system.add(bar(f"h{i}", np.eye(3)), RevoluteJoint(axis=z), parent=inboard)
        system.add(bar(f"v{i}", rot_z(-np.pi / 2)), RevoluteJoint(axis=z), parent=f"h{i}")
        system.close(RevoluteJoint(axis=z, name=f"O{i}"), f"v{i}", "ground")
        inboard = f"h{i}"
    return dttmm.assemble(system.build(), keep=["O0"])


def parallelogram(n, t):
    """B_0 = (sin th, cos th) of the exact one-degree-of-freedom reduction: the vertical bars
    turn alike by th (clockwise from up), the horizontal bars translate; I th'' = c g sin th with
    I = (n + 1) / 3 + n (about the pivots, and the translating bars) and c = (n + 1) / 2 + n."""
    inertia, c = (n + 1) / 3 + n, (n + 1) / 2 + n
    sol = solve_ivp(lambda _, y: [y[1], 9.81 * c * np.sin(y[0]) / inertia], (0, t[-1]),
                    [0.0, 1.0], method="DOP853", rtol=1e-13, atol=1e-14, t_eval=t)
    return np.stack([np.sin(sol.y[0]), np.cos(sol.y[0])], axis=1)


def test_n_four_bar_follows_the_parallelogram_through_its_flat_positions():
    """Spatial revolute joints make the planar loops redundant (10 constraint equations for
    2 loops that close 4 freedoms), and twice a turn the bars lie flat, where the loops are
    singular: the least closing forces (a truncated SVD of the Delassus matrix) carry the run
    through both flat positions of the first 2 s within 1e-7 m of the exact reduction (measured
    3e-8; each later crossing adds 1e-7 to 1e-5 at rtol 1e-10: docs/loops.md)."""
    t = np.linspace(0.0, 2.0, 201)
    model = n_four_bar(2)
    assert "mobility at least -5" in model.describe()
    result = simulate_reference(model, 2.0, t_eval=t)
    exact = parallelogram(2, t)
    theta = np.arctan2(exact[:, 0], exact[:, 1])
    assert np.any(np.abs(np.abs(theta) - np.pi / 2) < 0.05)          # flat at least once
    assert np.abs(result.position_output[:, 0, :2] - exact).max() < 1e-7


def test_a_bar_pinned_at_both_ends_hangs_half_its_weight_on_each_pin():
    """A uniform 2 kg bar on a ball joint at the ground point, its far end closed to the ground
    by a ball joint: at rest, the closing joint's force on the ground is half the weight
    (closure_force: on side b, world axes)."""
    system = System(gravity=[0, -9.81, 0])
    system.add(RigidBody(mass=2.0, inertia=[1e-3, 0.5, 0.5], inertia_about="mass_center",
                         to_mass_center=[1.0, 0, 0], to_output=[2.0, 0, 0], name="bar"),
               BallJoint())
    system.close(BallJoint(name="far"), "bar", "ground")
    result = simulate_reference(system.build(), 0.5, t_eval=[0.0, 0.5])
    assert np.allclose(result.info["closure_force"][:, 0], [0.0, -9.81, 0.0], atol=1e-9)
    assert np.abs(result.info["closure_moment"]).max() < 1e-12
    assert np.allclose(result.force[:, 0], [0.0, 9.81, 0.0], atol=1e-9)
    assert np.abs(result.position_output[-1] - [2.0, 0, 0]).max() < 1e-12


def test_a_beam_closed_at_its_end_is_the_pinned_tip():
    """System.close(BallJoint(), beam, 'ground') is the row tip='ball' adds: the same run."""
    beam = dict(length=1.0, mass_per_length=1.32, bending_stiffness=333.3,
                polar_inertia_per_length=1e-4, modes_per_plane=3, stiffening=False)
    tip = dttmm.build_chain([BallJoint(), dttmm.EulerBernoulliBeam(**beam)], tip="ball")
    system = System()
    system.add(dttmm.EulerBernoulliBeam(**beam, name="beam"), BallJoint())
    system.close(BallJoint(), "beam", "ground")
    closed = system.build()
    t = np.linspace(0, 0.05, 11)
    a = simulate_reference(tip, 0.05, t_eval=t)
    b = simulate_reference(closed, 0.05, t_eval=t)
    assert np.array_equal(a.modal_coordinates, b.modal_coordinates)


def test_assembly_closes_a_gap_keeps_what_it_is_told_and_refuses_what_cannot_close():
    """The coupler's end given 0.1 m off its pivot: assembly moves the free joints (the kept
    crank stays) until the pin holds to 1e-12 m; a coupler too short to reach is refused,
    naming the joint and the gap."""
    def four_bar(coupler):
        system = System(gravity=[0, -9.81, 0])
        bar = dict(inertia_about="mass_center", mass=1.0, inertia=[1e-3, 0.1, 0.1])
        system.add(RigidBody(**bar, to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0],
                             rotation=rot_z(np.pi / 2 - 0.2), name="crank"),
                   RevoluteJoint(axis=[0, 0, 1], name="O"))
        system.add(RigidBody(**bar, to_mass_center=[coupler / 2, 0, 0],
                             to_output=[coupler, 0, 0], rotation=np.eye(3), name="coupler"),
                   RevoluteJoint(axis=[0, 0, 1]), parent="crank")
        system.add(RigidBody(**bar, to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0],
                             rotation=rot_z(-np.pi / 2), name="rocker"),
                   RevoluteJoint(axis=[0, 0, 1]), parent="coupler")
        system.close(RevoluteJoint(axis=[0, 0, 1], name="pivot"), "rocker", "ground",
                     at_b=[1.0, 0.0, 0.0])
        return system.build()
    model = four_bar(1.0)
    gap = dttmm.loop_residuals(model)[0][0]
    assert 0.1 < gap < 0.3                                  # the crank tilted by 0.2 rad
    assembled = dttmm.assemble(model, keep=["O"])
    assert dttmm.loop_residuals(assembled)[0].max() < 1e-12
    assert np.array_equal(assembled.initial_rotation[0], model.initial_rotation[0])
    with pytest.raises(ValueError, match="'pivot' cannot close: a gap of"):
        dttmm.assemble(four_bar(0.2), keep=["O"])
    with pytest.raises(ValueError, match="keep names no joint or body"):
        dttmm.assemble(model, keep=["nothing"])
