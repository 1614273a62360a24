"""Flexible modes resolved or flagged (issue 65, item 5): a fixed-step run whose step does not
resolve a kept bending mode that vibrates with more than 1e-3 of the run's energy warns, naming
the beam and the mode and advising 20 steps a period."""
import warnings

import numpy as np
import pytest

from dttmm import (EulerBernoulliBeam, FixedHinge, JointMotion, RevoluteJoint, RigidBody, System,
                   UnresolvedMotionWarning, simulate)
from dttmm.describe import beam_frequencies


def smooth(amplitude, duration):
    """JointMotion from 0 to `amplitude` over `duration`, at rest at both ends."""
    w = 2 * np.pi / duration
    return JointMotion(
        position=lambda t: np.where(t < duration, amplitude * (t / duration - np.sin(w * t)
                                                               / (2 * np.pi)), amplitude),
        velocity=lambda t: np.where(t < duration, amplitude * (1 - np.cos(w * t)) / duration,
                                    0.0),
        acceleration=lambda t: np.where(t < duration, amplitude * w * np.sin(w * t) / duration,
                                        0.0))


def slewing_arm():
    """An aluminium arm (1.8 m, 10 mm square: first mode 2.54 Hz) clamped to a hub slewed by
    1 rad in 1 s about z, no gravity."""
    e, rho, a = 70e9, 2700.0, 0.01
    system = System(gravity=[0, 0, 0])
    system.add(RigidBody(mass=5.0, inertia=[0.05] * 3, inertia_about="mass_center", name="hub"),
               RevoluteJoint(axis=[0, 0, 1], drive=smooth(1.0, 1.0)))
    system.add(EulerBernoulliBeam(length=1.8, bending_stiffness=e * a ** 4 / 12, density=rho,
                                  area=a * a, polar_inertia_per_length=rho * a ** 4 / 6,
                                  name="arm"), FixedHinge(), parent="hub")
    return system.build()


def test_the_arm_is_the_issues():
    assert beam_frequencies(slewing_arm(), 1)[0][0] == pytest.approx(2.54, abs=0.01)


@pytest.mark.parametrize("dt", [0.1, 0.05])
def test_a_step_too_coarse_for_the_first_mode_warns(dt):
    """dt = 0.05 s: 7.9 steps a period of the 2.54 Hz mode, the tip at 3 s +45 mm where the
    converged run has -27 mm, the step error estimate 9e-4 (under the 0.05 stop): before,
    silent."""
    with pytest.warns(UnresolvedMotionWarning, match=r"beam 'arm''s bending mode 1 \(plane v, "
                                                     r"2\.539 Hz\).*take dt <= 0\.02 s"):
        simulate(slewing_arm(), 3.0, dt)


def test_a_step_that_resolves_the_modes_is_silent():
    with warnings.catch_warnings():
        warnings.simplefilter("error", UnresolvedMotionWarning)
        simulate(slewing_arm(), 3.0, 5e-4)
