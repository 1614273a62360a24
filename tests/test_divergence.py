"""Runs that cannot go wrong silently (docs/solver.md, "Runs that cannot go wrong"): a step too
large for the motion, a motion that runs away, an energy-momentum step that does not converge
and a beam deflected beyond its length each stop with DivergenceError naming the step, its
time and the cause, keeping the samples so far; the same systems at a sound step run through."""
import numpy as np
import pytest

import dttmm

from dttmm import (BallJoint, DivergenceError, EulerBernoulliBeam, FixedHinge, Ground,
                   PrescribedMotion, build_chain, simulate)
from dttmm.model.chains import rigid_chain, unit_link


def _spinning_chain():
    """Three unit links turning at 100 rad/s about the vertical through the root."""
    spin = [0.0, 100.0, 0.0]
    return build_chain([BallJoint(), unit_link(angular_velocity=spin), BallJoint(),
                        unit_link(angular_velocity=spin), BallJoint(),
                        unit_link(angular_velocity=spin)])


def test_a_step_too_large_for_the_motion_stops_the_run():
    """The 3-link chain at dt = 0.5 s (its energy grew from 2e-3 J to 1.8e31 J over 20 s):
    stopped at its first step (measured estimate 0.98 rad); at dt = 1e-2 s it runs through
    (largest estimate 2.0e-4)."""
    with pytest.raises(DivergenceError, match=r"step 1 \(t = 0\.5 s\).*local error estimate.*"
                                              r"max_step_error = 0\.05.*smaller dt") as err:
        simulate(rigid_chain(3), 20.0, 0.5)
    assert err.value.partial is not None and len(err.value.partial.t) >= 1
    sound = simulate(rigid_chain(3), 20.0, 1e-2, record_every=10)
    assert sound.t[-1] == pytest.approx(20.0) and sound.info["step_error_max"] < 1e-3
    with pytest.warns(dttmm.UnresolvedMotionWarning, match="turns by up to"):
        unguarded = simulate(rigid_chain(3), 5.0, 0.5, max_step_error=None)
    assert unguarded.info["step_error_max"] > 0.05        # what the guard stops
    # (and what the unresolved-step flag says of the run that went on)


def test_a_chain_spun_at_100_rad_s_with_a_large_step_stops():
    """w dt = 1 rad per step (its energy grew to 1.8e30 J): stopped within a few steps
    (measured: step 4); at dt = 1e-4 it keeps its energy."""
    with pytest.raises(DivergenceError, match="local error estimate") as err:
        simulate(_spinning_chain(), 2.0, 1e-2)
    assert err.value.step <= 10
    sound = simulate(_spinning_chain(), 0.2, 1e-4, record_every=100)
    e = sound.total_energy
    assert abs(e[-1] - e[0]) < 1e-8 * e[0]


def test_an_unconverged_energy_momentum_step_stops_the_run():
    """At dt = 0.5 s the energy-momentum step's Newton iterations do not converge (19 of 20
    steps were counted, and returned): stopped at the first one; at dt = 1e-3 none."""
    with pytest.raises(DivergenceError, match="energy-momentum step's Newton iterations did not "
                                              "converge"):
        simulate(rigid_chain(3), 10.0, 0.5, scheme="energy_momentum")
    sound = simulate(rigid_chain(3), 1.0, 1e-3, scheme="energy_momentum", record_every=100)
    assert sound.info["newton_unconverged_steps"] == 0


def test_a_beam_spun_past_its_first_frequency_stops():
    """A 10 m aluminium tube (seed 000's rotating beam) clamped to a hub spun up to 6 rad/s,
    above its first bending frequency (3.8 rad/s): with geometric stiffening switched off its
    modes grow without bound (to 1e41 m at 30 s); the run stops once the tip deflects more
    than the beam's length, naming the beam (issue 16: not a silent 1e41 m)."""
    area = np.pi * (0.0326 ** 2 - 0.0306 ** 2)
    inertia = np.pi / 4 * (0.0326 ** 4 - 0.0306 ** 4)
    beam = EulerBernoulliBeam(length=10.0, density=3000.0, area=area,
                              bending_stiffness=6.9e10 * inertia,
                              polar_inertia_per_length=3000.0 * 2 * inertia, name="tube",
                              stiffening=False)
    omega, t_up = 6.0, 15.0

    def angle(t):
        if t <= t_up:
            return omega / t_up * (t * t / 2 + (t_up / (2 * np.pi)) ** 2
                                   * (np.cos(2 * np.pi * t / t_up) - 1))
        return omega * (t - t_up / 2)

    def rate(t):
        return omega / t_up * (t - t_up / (2 * np.pi) * np.sin(2 * np.pi * t / t_up)) \
            if t <= t_up else omega

    def acceleration(t):
        return omega / t_up * (1 - np.cos(2 * np.pi * t / t_up)) if t <= t_up else 0.0

    hub = PrescribedMotion.spin_about_axis([0, 0, 1], angle, rate, acceleration)
    model = build_chain([FixedHinge(), beam], gravity=[0, 0, 0], ground=Ground(motion=hub))
    with pytest.raises(DivergenceError, match="tip of beam 'tube' deflects .* more than the "
                                              "beam's length, 10 m") as err:
        simulate(model, 30.0, 1e-3, record_every=100)
    assert 0.0 < err.value.t < 30.0 and err.value.partial is not None


def test_max_step_error_is_checked():
    for bad in (0.0, -1.0, np.nan, "x"):
        with pytest.raises(ValueError, match="max_step_error"):
            simulate(rigid_chain(2), 0.01, 1e-3, max_step_error=bad)


def _whirling_chain():
    """Issue 28's case 3: the README's uniform links, three of them, the last whirling at
    100 rad/s about y; nothing works on it, so its energy is a constant of the motion."""
    link = lambda **kw: dttmm.RigidBody(mass=1.0, inertia=[1 / 6, 5 / 12, 5 / 12],
                                        inertia_about="input", to_mass_center=[0.5, 0, 0],
                                        to_output=[1, 0, 0], **kw)
    return dttmm.build_chain([BallJoint(), link(), BallJoint(), link(), BallJoint(),
                              link(angular_velocity=[0.0, 100.0, 0.0])],
                             gravity=[0.0, -9.81, 0.0])


def test_a_step_that_cannot_resolve_the_motion_is_flagged():
    """At dt = 0.01 s the whirling link turns by 1 rad per step: every local error estimate
    stays under max_step_error (measured 0.037) while the energy, which physics keeps
    constant, drifts by 22% of the largest kinetic energy; the run warns (before stop 28 it
    returned silently).  At dt = 2.5e-3 s (0.25 rad per step) the drift is below 1% and
    nothing is flagged."""
    with pytest.warns(dttmm.UnresolvedMotionWarning, match="'body2' turns by up to 1 rad"):
        coarse = simulate(_whirling_chain(), 2.0, 0.01)
    drift = np.abs(coarse.total_energy - coarse.total_energy[0]).max() / coarse.kinetic.max()
    assert drift > 0.1 and coarse.info["step_error_max"] < 0.05
    assert coarse.info["turn_per_step_max"] == pytest.approx(1.0, rel=1e-3)
    fine = simulate(_whirling_chain(), 2.0, 2.5e-3)             # (warnings are errors here)
    drift = np.abs(fine.total_energy - fine.total_energy[0]).max() / fine.kinetic.max()
    assert drift < 0.01 and fine.info["turn_per_step_max"] < 0.35
