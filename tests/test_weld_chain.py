"""The fused loop for chains of beams welded by fixed hinges (kernels/stepping/weld_chain.py)
against the general loop (kernels/stepping/step.py): the same step computed two ways, so they must
agree to rounding, on every beam feature the fused loop covers.  (The welded beam's physics is
checked elsewhere: the clamped-beam, twist, stretch, load and elastica tests run through this
loop.)"""
import numpy as np
import pytest
from helpers import fused_and_general

from dttmm import (BallJoint, EulerBernoulliBeam, FixedHinge, Ground, PrescribedMotion,
                   RigidBody, build_chain, forward_dynamics, simulate)
from dttmm.model.chains import stiff_cantilever

HUB = PrescribedMotion.spin_about_axis([0, 0, 1], angle=lambda t: 0.5 * t * t, rate=lambda t: t,
                                       acceleration=lambda t: 1.0, position=[0.1, 0.0, 0.0])


def _both_loops(monkeypatch, model, t_end, dt, **kwargs):
    return fused_and_general(monkeypatch, model, t_end, dt, "welded-chain", **kwargs)


def _assert_same(fused, general, rtol=1e-9, rtol_acceleration=1e-7):
    """The loops agree step by step to rounding (measured on two soft sagging elements: 1e-18
    rad on rotations, 1e-12 relative on angular accelerations after one step), and those
    differences grow with the run in these soft, sagging chains alike in both loops (6e-11
    relative on positions after 0.3 s, 1e-14 after 0.1 s), so the runs are short.
    rtol_acceleration: the angular accelerations carry the rounding of the positions times
    c1 = 4 / h^2 and the stiffness (measured 2e-9 to 3e-9 relative after 0.1 s)."""
    names = ("position_output", "angular_velocity", "force", "moment", "modal_coordinates",
             "modal_velocities")
    for name in names + ("angular_acceleration",):
        a, b = getattr(fused, name), getattr(general, name)
        tol = rtol_acceleration if name == "angular_acceleration" else rtol
        assert np.abs(a - b).max() <= tol * np.abs(b).max(), name
    assert np.array_equal(fused.t, general.t)


def test_fused_welded_loop_matches_the_general_loop_on_a_driven_cantilever(monkeypatch):
    """Four stiffened elements on a spun-up hub with gravity, with and without Newton
    iterations (the same iteration counts)."""
    model = stiff_cantilever(4)
    fused, general = _both_loops(monkeypatch, model, 0.3, 1e-3, rho_inf=0.9, record_every=10)
    _assert_same(fused, general)
    on_hub = build_chain([FixedHinge(), EulerBernoulliBeam(
        length=1.0, mass_per_length=2.0, bending_stiffness=[60.0, 80.0],
        polar_inertia_per_length=2e-3, modes_per_plane=3)] * 2,
        gravity=[0.0, 0.0, -9.81], ground=Ground(motion=HUB))
    fused, general = _both_loops(monkeypatch, on_hub, 0.1, 1e-3, rho_inf=0.9,
                                 newton_iterations=3)
    _assert_same(fused, general)
    assert fused.info["newton_iterations_used"] == general.info["newton_iterations_used"] >= 1


def test_fused_welded_loop_matches_with_twist_stretch_and_every_load(monkeypatch):
    """Twist and stretch modes, an end force and torque in body axes, a distributed load: the
    differenced columns of beam_transfer, through the fused sweep."""
    def element(**loads):
        return EulerBernoulliBeam(length=0.8, mass_per_length=2.0, bending_stiffness=[60.0, 80.0],
                                  polar_inertia_per_length=2e-3, modes_per_plane=2,
                                  torsion_modes=1, torsional_stiffness=8.0, axial_modes=1,
                                  axial_stiffness=3000.0, **loads)
    tip = element(end_force=lambda t: [0.0, 0.5 * t, -1.0], end_torque=lambda t: [0.1, 0.0, 0.0],
                  distributed_load=lambda t: [0.0, 0.2, 0.0], load_axes="body")
    model = build_chain([FixedHinge(), element(), FixedHinge(), tip],
                        gravity=[0.0, 0.0, -9.81], ground=Ground(motion=HUB))
    fused, general = _both_loops(monkeypatch, model, 0.1, 1e-3, rho_inf=0.9, record_every=5)
    _assert_same(fused, general)


@pytest.mark.parametrize("what, elements, tip", [
    ("a ball joint between the beams", [FixedHinge(), "beam", BallJoint(), "beam"], None),
    ("a rigid body welded at the tip",
     [FixedHinge(), "beam", FixedHinge(), RigidBody(mass=1.0, inertia=np.eye(3) * 0.01,
                                                    inertia_about="mass_center",
                                                    to_output=[0.1, 0.0, 0.0])], None),
    ("a tip pinned to the ground", [FixedHinge(), "beam", FixedHinge(), "beam"], "ball"),
])
def test_other_chains_keep_their_loops(what, elements, tip):
    beam = dict(length=0.5, mass_per_length=2.0, bending_stiffness=100.0,
                polar_inertia_per_length=1e-3, modes_per_plane=1)
    chain = [EulerBernoulliBeam(**beam) if e == "beam" else e for e in elements]
    model = build_chain(chain, **({"tip": tip} if tip else {}))
    assert simulate(model, 2e-3, 1e-3).info["loop"] != "welded-chain", what


def test_the_welded_loops_own_start_gives_the_general_starts_accelerations():
    """The welded-chain loop takes its consistent start as one pass of its own iterate
    (weld_chain.start_loop); forward_dynamics takes it by the general loop's start
    (step.py::initial_accelerations): a bent, moving, loaded chain on an accelerating hub, with
    twist and stretch, gives the same accelerations and station loads to rounding."""
    def element(**more):
        return EulerBernoulliBeam(length=0.8, mass_per_length=2.0, bending_stiffness=[60.0, 80.0],
                                  polar_inertia_per_length=2e-3, modes_per_plane=2,
                                  torsion_modes=1, torsional_stiffness=8.0, axial_modes=1,
                                  axial_stiffness=3000.0, **more)
    bent = element(initial_modal_coordinates=[0.02, -0.004, 0.01, 0.002, 0.05, 1e-4],
                   initial_modal_velocities=[0.1, 0.0, -0.2, 0.05, 0.3, 1e-3])
    tip = element(end_force=lambda t: [0.0, 0.5, -1.0], end_torque=lambda t: [0.1, 0.0, 0.0],
                  distributed_load=lambda t: [0.0, 0.2, 0.0], load_axes="body",
                  initial_modal_velocities=[0.0, 0.2, 0.1, 0.0, -0.1, 0.0])
    model = build_chain([FixedHinge(), bent, FixedHinge(), tip],
                        gravity=[0.0, 0.0, -9.81], ground=Ground(motion=HUB))
    run = simulate(model, 1e-3, 1e-3)
    assert run.info["loop"] == "welded-chain"
    general = forward_dynamics(model)
    for ours, theirs in ((run.angular_acceleration[0], general["angular_acceleration"]),
                         (run.force[0], general["force"]), (run.moment[0], general["moment"])):
        assert np.abs(ours - theirs).max() <= 1e-12 * np.abs(theirs).max()
    assert np.abs(general["angular_acceleration"][1]).max() > 1.0       # (not a trivial case)
