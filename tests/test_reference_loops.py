"""The Newton-Euler reference with closed loops (docs/loops.md, docs/reference.md): published
values, exact reductions, two spanning trees of one mechanism, and assembly."""
import numpy as np
import pytest

import dttmm
from dttmm import BallJoint, RevoluteJoint, RigidBody, System, simulate_reference
from dttmm.model.mechanisms import n_four_bar, parallelogram, slider_crank

from helpers import rot_z


def test_slider_crank_energy_is_the_published_value_and_two_trees_agree():
    """Assembled from the crank's rate alone, the mechanism starts with the benchmark's energy
    0.76643568 J (z = 0 the datum), keeps it to 1e-10 J over 5 s, and the two spanning trees
    (a prismatic or a universal closing joint) move the slider alike to 1e-9 m."""
    t = np.linspace(0.0, 5.0, 251)
    runs = {}
    for tree in ("slider on the rod", "slider on the ground"):
        model = slider_crank(tree)
        positions, rates = dttmm.loop_residuals(model)
        # closed to rounding: 2.9e-16 m and 1.1e-15 m/s with numpy 2.4 (1e-15 held before it)
        assert positions.max() < 1e-14 and rates.max() < 1e-14
        runs[tree] = result = simulate_reference(model, 5.0, t_eval=t)
        energy = result.kinetic + result.potential
        assert abs(energy[0] - 0.76643568) < 1e-12
        assert np.abs(energy - energy[0]).max() < 1e-10
    on_rod = runs["slider on the rod"].position_input[:, 2]
    on_ground = runs["slider on the ground"].position_output[:, 2]
    assert np.abs(on_rod[:, 1:]).max() < 1e-10              # on its slide, the x axis
    assert np.abs(on_rod - on_ground).max() < 1e-9
    assert 0.12 < on_rod[:, 0].min() and on_rod[:, 0].max() < 0.36       # it moves


def test_n_four_bar_follows_the_parallelogram_through_its_flat_positions():
    """Spatial revolute joints make the planar loops redundant (10 constraint equations for
    2 loops that close 4 freedoms), and twice a turn the bars lie flat, where the loops are
    singular: the least closing forces (a truncated SVD of the Delassus matrix) carry the run
    through both flat positions of the first 2 s within 2e-6 m of the exact reduction (each
    later crossing adds 1e-7 to 1e-5 at rtol 1e-10: docs/loops.md).  At a flat position the
    truncation amplifies rounding: six starts moved by 1e-15 gave 7.7e-10 to 5.8e-7 m through
    scipy's DOP853 and 1.5e-8 to 3.2e-7 m through the compiled one (reference/integrator.py),
    so the bound is the spread's, not one start's (1e-7 before: 3e-8 by scipy's rounding)."""
    t = np.linspace(0.0, 2.0, 201)
    model = n_four_bar(2)
    assert "mobility 1 as a rigid mechanism (Grübler's count -5" in model.describe()
    result = simulate_reference(model, 2.0, t_eval=t)
    exact = parallelogram(2, t)
    theta = np.arctan2(exact[:, 0], exact[:, 1])
    assert np.any(np.abs(np.abs(theta) - np.pi / 2) < 0.05)          # flat at least once
    assert np.abs(result.position_output[:, 0, :2] - exact).max() < 2e-6


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
    assert np.allclose(result.closure_force[:, 0], [0.0, -9.81, 0.0], atol=1e-9)
    assert np.abs(result.closure_moment).max() < 1e-12
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
    with pytest.warns(dttmm.model.loop_kinematics.AssemblyWarning,
                      match="'rocker' 0.2 m and 0.2 rad"):
        assembled = dttmm.assemble(model, keep=["O"])      # (and says so: issue 65)
    assert dttmm.loop_residuals(assembled)[0].max() < 1e-12
    assert np.array_equal(assembled.initial_rotation[0], model.initial_rotation[0])
    with pytest.raises(ValueError, match="'pivot' cannot close: after .* a gap of .* m and"):
        dttmm.assemble(four_bar(0.2), keep=["O"])
    with pytest.raises(ValueError, match="keep names no joint or body"):
        dttmm.assemble(model, keep=["nothing"])
