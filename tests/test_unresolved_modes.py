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


# The issue's mast: 1 m of aluminium, 15 mm round, a 0.5 kg tip, clamped upright on a cart that
# moves 0.4 m and back in 0.5 s (x = 0.2 (1 - cos(4 pi t)) m), gravity along -y.
MAST_E, MAST_RHO, MAST_D = 70e9, 2700.0, 0.015


def mast(elements):
    """The mast of `elements` welded beam elements."""
    from dttmm import Ground, PrescribedMotion
    w = 4 * np.pi

    def during(f):
        return lambda t: np.array([f(t) if t < 0.5 else 0.0, 0.0, 0.0])
    cart = PrescribedMotion(position=during(lambda t: 0.2 * (1 - np.cos(w * t))),
                            velocity=during(lambda t: 0.2 * w * np.sin(w * t)),
                            acceleration=during(lambda t: 0.2 * w * w * np.cos(w * t)))
    area, second = np.pi * MAST_D ** 2 / 4, np.pi * MAST_D ** 4 / 64
    system = System(gravity=[0, -9.81, 0], ground=Ground(motion=cart))
    parent = None
    for i in range(elements):
        up = [[0, -1.0, 0], [1.0, 0, 0], [0, 0, 1.0]] if i == 0 else None
        parent = system.add(EulerBernoulliBeam(
            length=1.0 / elements, density=MAST_RHO, area=area, bending_stiffness=MAST_E * second,
            polar_inertia_per_length=2 * MAST_RHO * second, name=f"e{i}"),
            FixedHinge(rotation=up), parent=parent)
    system.add(RigidBody(mass=0.5, inertia=[1e-6] * 3, inertia_about="mass_center", name="tip"),
               FixedHinge(), parent=parent)
    return system.build()


def _mast_tip(elements):
    """The tip's deflection from the cart every 1 ms over 2 s at dt = 1e-4."""
    model = mast(elements)
    result = simulate(model, 2.0, 1e-4, record_every=10)
    cart = np.array([model.ground_state(t)[0][0] for t in result.t])
    return result.position_input[:, -1, 0] - cart


def test_the_mast_of_one_element_is_off_and_four_elements_hold_it():
    """The issue's mast of one element bends by 0.147 rad and its tip's deflection is 8.8% of
    the peak (98.6 mm) off 16 elements' (converged: 4 elements are within 0.26%); 4 elements
    (0.067 rad each at most) are within 2%.  Not flagged by the run (docs/beam.md, "How far an
    element bends": the spin-up's one element bends 0.0785 rad and is within 0.06% of 20, so
    no bend threshold tells the two apart)."""
    fine = _mast_tip(16)
    peak = np.abs(fine).max()
    assert 0.095 < peak < 0.102
    assert np.abs(_mast_tip(1) - fine).max() > 0.05 * peak
    assert np.abs(_mast_tip(4) - fine).max() < 0.02 * peak
