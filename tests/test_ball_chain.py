"""The fused loop for rigid bodies and beams between ball joints (kernels/stepping/ball_chain.py)
against the general loop (kernels/stepping/step.py): the same step computed two ways, so they must
agree to rounding, on every feature the fused loop covers.  (Its physics is checked like every other
path's: the rigid-chain tests against the reference, conservation and analytic cases all run
through it.)"""
import numpy as np
import pytest
from helpers import fused_and_general, rot_z

from dttmm import BallJoint, DivergenceError, Ground, PrescribedMotion, RigidBody, build_chain, \
    simulate
from dttmm.model.chains import rigid_chain, three_pendulum, unit_link
from dttmm.solving import run_tables


def _both_loops(monkeypatch, model, t_end, dt, **kwargs):
    return fused_and_general(monkeypatch, model, t_end, dt, "ball-chain", **kwargs)


def _assert_same(fused, general, rtol=1e-9, beams=False):
    names = ("position_output", "angular_velocity", "angular_acceleration", "force")
    for name in names + (("modal_coordinates", "modal_velocities") if beams else ()):
        a, b = getattr(fused, name), getattr(general, name)
        scale = np.abs(b).max()
        assert np.abs(a - b).max() <= rtol * scale, name
    assert np.array_equal(fused.t, general.t)


def _asymmetric_chain(n, **tip_kwargs):
    """Bodies with offset mass centres and full inertia tensors, a torque and a force, so every
    term of the body map is exercised."""
    elements = []
    rng = np.random.default_rng(3)
    for k in range(n):
        j = np.diag([0.2, 0.5, 0.6]) + 0.03 * (lambda a: a + a.T)(rng.normal(size=(3, 3)))
        body = RigidBody(mass=1.0 + k, inertia=j, inertia_about="mass_center",
                         to_mass_center=[0.4, 0.1 * (k + 1), -0.05], to_output=[0.9, 0.2, 0.1],
                         angular_velocity=[0.3, -0.2, 1.0 + k],
                         torque=(lambda t: [0.1 * np.sin(3 * t), 0.0, 0.2]) if k == 0 else None,
                         force=(lambda t: [0.0, 0.0, 2.0 * np.cos(t)]) if k == n - 1 else None)
        elements += [BallJoint(), body]
    return build_chain(elements, **tip_kwargs)


def test_fused_loop_matches_the_general_loop_on_a_swinging_chain(monkeypatch):
    fused, general = _both_loops(monkeypatch, rigid_chain(10), 1.0, 1e-3, record_every=10)
    _assert_same(fused, general)


def test_fused_loop_matches_with_loads_offsets_and_newton_iterations(monkeypatch):
    model = _asymmetric_chain(4)
    fused, general = _both_loops(monkeypatch, model, 0.5, 1e-3, newton_iterations=3)
    _assert_same(fused, general)
    assert fused.info["newton_iterations_used"] == general.info["newton_iterations_used"] >= 1


def test_fused_loop_matches_with_a_pinned_tip_and_a_moving_ground(monkeypatch):
    hub = PrescribedMotion.spin_about_axis([0, 0, 1], angle=lambda t: 0.5 * t * t,
                                           rate=lambda t: t, acceleration=lambda t: 1.0,
                                           position=[0.1, 0.0, 0.0])
    model = _asymmetric_chain(3, ground=Ground(motion=hub))
    fused, general = _both_loops(monkeypatch, model, 0.5, 1e-3, record_every=5)
    _assert_same(fused, general)
    pinned = build_chain([BallJoint(), unit_link(angular_velocity=[0.0, 1.0, 0.0]),
                          BallJoint(), unit_link(rotation=rot_z(-np.pi / 2)),
                          BallJoint(), unit_link(rotation=rot_z(np.pi))], tip="ball")
    fused, general = _both_loops(monkeypatch, pinned, 0.5, 1e-3)
    _assert_same(fused, general)


def test_fused_loop_matches_on_the_three_pendulum(monkeypatch):
    """Beams between ball joints: the beam's transfer folded into the fused sweep, its modal
    accelerations recovered and integrated there (measured agreement: 5e-12 relative on the
    angular accelerations, 1e-15 on positions)."""
    fused, general = _both_loops(monkeypatch, three_pendulum(2), 0.3, 1e-4, record_every=10)
    _assert_same(fused, general, beams=True)
    damped = three_pendulum(3, damping_ratio=0.02)
    fused, general = _both_loops(monkeypatch, damped, 0.1, 1e-4, newton_iterations=2)
    _assert_same(fused, general, beams=True)


def test_fused_loop_reports_divergence_like_the_general_loop(monkeypatch):
    """A torque growing without bound spins the chain up until the state overflows: both loops
    stop at the same step with the same cause and a partial result."""
    spinning = unit_link(torque=lambda t: [0.0, 0.0, 1e300 * t])
    model = build_chain([BallJoint(), unit_link(), BallJoint(), spinning])
    errors = []
    for fused in (True, False):
        monkeypatch.setattr(run_tables, "FUSED_BALL_CHAIN", fused)
        with pytest.raises(DivergenceError) as err:
            simulate(model, 1.0, 1e-2)
        errors.append(err.value)
    assert errors[0].step == errors[1].step >= 1
    assert errors[0].cause == errors[1].cause
    assert errors[0].partial.info["loop"] == "ball-chain"
    assert np.array_equal(errors[0].partial.t, errors[1].partial.t)
