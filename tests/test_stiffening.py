"""Geometric stiffening of the beam (docs/beam.md, "Geometric stiffening"), by DT-TMM against
the Newton-Euler reference and against the beam without it; the spin-up's one-element check is
in test_examples_and_results.py, the kernels' in test_kernels.py."""
import numpy as np
import pytest

from dttmm import EulerBernoulliBeam, FixedHinge, build_chain, simulate
from dttmm.chains import three_pendulum
from helpers import fitted_order, output_errors_against_reference


def test_the_three_pendulums_stiff_beam_barely_feels_it():
    """The paper's beam is stiff (first frequency 25 Hz): its stiffening moves the bodies by
    3.0e-5 m at most over 2 s (measured), 4% of the beam's 0.72 mm deflection.  Issue 16
    expected below 1e-6 m; the physics says more: the joints pull the beam with ~10-20 N, which
    raises its first bending frequency by a few tenths of a percent, and the vibration's phase
    drifts by that much over 50 periods (both solvers agree on it: test below)."""
    t = np.linspace(0.0, 2.0, 201)
    runs = [simulate(three_pendulum(2, stiffening=s), 2.0, 1e-3, t_eval=t) for s in (False, True)]
    change = np.abs(runs[0].position_output - runs[1].position_output).max()
    assert 1e-6 < change < 1e-4, change


def test_the_stiffened_three_pendulum_conserves_energy():
    """Energy, with the foreshortening's terms (dttmm.result.chain_energies), over 2 s at
    dt = 1e-3: within 1e-5 of the largest kinetic energy (issue 16)."""
    res = simulate(three_pendulum(2, stiffening=True), 2.0, 1e-3)
    e = res.kinetic + res.potential
    assert np.abs(e - e[0]).max() < 1e-5 * res.kinetic.max()


def _hub_cantilever():
    """A soft cantilever with a tip mass on a hub driven about z, under gravity along -x (the
    beam's axis: it hangs, so gravity, the spin and the tip body's pull all stiffen it)."""
    from dttmm import Ground, PrescribedMotion, RigidBody

    def angle(t):
        return 2.0 * t * t

    hub = PrescribedMotion.spin_about_axis([0, 0, 1], angle, lambda t: 4.0 * t, lambda t: 4.0)
    beam = EulerBernoulliBeam(length=1.0, mass_per_length=1.0, bending_stiffness=[3.0, 4.0],
                              polar_inertia_per_length=1e-3, modes_per_plane=2,
                              stiffening=True)
    tip = RigidBody(mass=0.5, inertia=np.diag([1e-3, 1e-3, 1e-3]), inertia_about="mass_center",
                    to_mass_center=[0.05, 0.0, 0.0], to_output=[0.1, 0.0, 0.0])
    return build_chain([FixedHinge(), beam, FixedHinge(), tip], gravity=[-9.81, 0.0, 0.0],
                       ground=Ground(motion=hub))


@pytest.mark.parametrize("system", ["three_pendulum", "hub_cantilever"])
def test_stiffened_beam_converges_to_the_reference_at_order_2(system):
    """DT-TMM against the Newton-Euler reference (rtol 1e-11) on the same stiffened models:
    the three-pendulum (its beam between ball joints, pulled by the joints) and a soft
    cantilever with a tip body on a driven hub under gravity along its axis (welded ends, the
    end section's differenced columns); positions at t = 1 s, fitted order 2 +- 0.2."""
    model = three_pendulum(2, stiffening=True) if system == "three_pendulum" \
        else _hub_cantilever()
    steps = np.array([4e-3, 2e-3, 1e-3])
    errors = output_errors_against_reference(model, steps)
    slope = fitted_order(steps, errors)
    assert abs(slope - 2.0) < 0.2, (errors, slope)


def test_stiffening_must_be_a_bool():
    beam = EulerBernoulliBeam(length=1.0, mass_per_length=1.0, bending_stiffness=1.0,
                              polar_inertia_per_length=1e-3, stiffening="yes", name="b")
    with pytest.raises(ValueError, match="'b'.*stiffening must be True, False or None"):
        build_chain([FixedHinge(), beam])


def test_stiffening_is_on_by_default_except_where_it_would_lock():
    """stiffening=None (the default) resolves at the build: on for a cantilever and for a beam
    in a chain with a free tip; off for a beam without stretch modes in a closed loop (the tip
    pinned), where its inextensible centreline could not bow, and describe() says why; on there
    with stretch modes, or when asked for."""
    from dttmm import BallJoint
    from dttmm.elements.beam import STIFFENING

    def beam(**kw):
        return EulerBernoulliBeam(length=1.0, mass_per_length=1.0, bending_stiffness=10.0,
                                  polar_inertia_per_length=1e-3, **kw)
    assert build_chain([FixedHinge(), beam()]).beam_params[0, STIFFENING] == 1.0
    assert build_chain([BallJoint(), beam()]).beam_params[0, STIFFENING] == 1.0
    closed = build_chain([BallJoint(), beam()], tip="ball")
    assert closed.beam_params[0, STIFFENING] == 0.0
    assert "default for a beam without stretch modes in a closed loop" in closed.describe()
    for kw in (dict(axial_modes=1, axial_stiffness=1e6), dict(stiffening=True)):
        assert build_chain([BallJoint(), beam(**kw)], tip="ball").beam_params[0, STIFFENING] == 1.0
    assert build_chain([FixedHinge(), beam(stiffening=False)]).beam_params[0, STIFFENING] == 0.0


def _flexible_pendulum(elements, modes, stiffening):
    """Seed 001's flexible pendulum: a 0.4 m beam (A = 18 cm^2, rho = 5540 kg/m^3,
    I = 1.215e-8 m^4, E = 1e9 Pa, as read from the OCR) on a pin about z at its root,
    released horizontal under gravity -y, as `elements` welded elements."""
    from dttmm import RevoluteJoint
    length, area, rho, inertia = 0.4, 1.8e-3, 5540.0, 1.215e-8
    parts = []
    for i in range(elements):
        parts += [RevoluteJoint(axis=[0, 0, 1]) if i == 0 else FixedHinge(),
                  EulerBernoulliBeam(length=length / elements, density=rho, area=area,
                                     bending_stiffness=1e9 * inertia,
                                     polar_inertia_per_length=rho * 2 * inertia,
                                     modes_per_plane=modes, stiffening=stiffening)]
    return build_chain(parts, gravity=[0.0, -9.81, 0.0])


def test_seed_001_pendulum_one_stiffened_element_follows_the_chain():
    """The tip's deflection from the root section's tangent over the first second of the swing
    (peak 5.05 mm): one stiffened element with 5 modes per plane against a chain of 32 stiffened
    elements (3 modes each): within 5% of the peak over the whole history (measured 2.1%; 5.3%
    with 3 modes); the paper's beam, one element, misses it by more than the deflection itself
    (measured 106%: it cannot carry the swing's centrifugal tension)."""
    t = np.linspace(0.0, 1.0, 201)

    def deflection(model):
        res = simulate(model, 1.0, 1e-4, t_eval=t)
        tip = res.position_output[:, -1] - res.position_input[:, 0]
        return np.einsum("ti,ti->t", tip, res.rotation[:, 0, :, 1])
    chain = deflection(_flexible_pendulum(32, 3, True))
    peak = np.abs(chain).max()
    assert 4e-3 < peak < 6e-3
    assert np.abs(deflection(_flexible_pendulum(1, 5, True)) - chain).max() < 0.05 * peak
    assert np.abs(deflection(_flexible_pendulum(1, 5, False)) - chain).max() > 0.5 * peak
