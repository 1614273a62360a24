"""The beam's twist (docs/beam.md, "Torsion"): torsion_modes twist coordinates per beam, the
sections spinning by w . A e1 + psi'.  Against the clamped-free shaft's frequencies, the
uniform twist under an end torque, the Newton-Euler reference (order 2) and energy
conservation; bad input is refused naming the beam."""
import numpy as np
import pytest

from dttmm import (EulerBernoulliBeam, FixedHinge, Ground, PrescribedMotion, build_chain,
                   simulate, static_equilibrium)
from dttmm.elements.beam import FAMILY, LENGTH, torsion_shapes
from helpers import (driven_arm_on_two_elements, energy_gaps_with_an_arm, fitted_frequencies,
                     fitted_order, output_errors_against_reference)

L, MU, JP, GJ = 1.0, 2.0, 1e-3, 50.0


def shaft(n_elements, twist_modes, end_torque=None, **beam):
    """A clamped-free beam of n welded elements along x, stiff in bending, no gravity."""
    parts = []
    for k in range(n_elements):
        last = k == n_elements - 1
        parts += [FixedHinge(), EulerBernoulliBeam(
            length=L / n_elements, mass_per_length=MU, bending_stiffness=1e5,
            polar_inertia_per_length=JP, modes_per_plane=1, torsion_modes=twist_modes,
            torsional_stiffness=GJ, end_torque=end_torque if last else None, **beam)]
    return build_chain(parts, gravity=[0.0, 0.0, 0.0])


def tip_twist(model, eta):
    """psi(L) of a one-beam model's beam from its coordinates eta (v, w, then the twist)."""
    row = model.beam_params[0]
    mt = len(eta) - 2
    psi_l = torsion_shapes(int(row[FAMILY]), row[LENGTH], mt, [row[LENGTH]])[0][:, 0]
    return psi_l @ eta[2:]


@pytest.mark.parametrize("n_elements, twist_modes", [(1, 3), (4, 3)])
def test_clamped_free_twist_frequencies(n_elements, twist_modes):
    """The first three frequencies (2 n - 1) / (4 L) sqrt(G J / (rho I_p)) within 0.5%, from the
    small vibrations about the static equilibrium (the solver's own linearization): one
    element with the free tip's eigenfunctions, or four welded elements with the loaded-end
    polynomial modes (measured: 0.001%, 0.002%, 0.024%)."""
    st = static_equilibrium(shaft(n_elements, twist_modes))
    f = st.frequencies[np.isfinite(st.frequencies)]
    for n in (1, 2, 3):
        want = (2 * n - 1) / (4 * L) * np.sqrt(GJ / JP)
        got = f[np.argmin(np.abs(f - want))]
        assert abs(got / want - 1.0) < 5e-3, (n, got, want)


def test_free_twist_vibration_runs_at_the_shafts_frequency():
    """DT-TMM's own run: an initial twist of the first mode rings at the shaft's frequency w as
    the trapezoidal rule carries it, (2 / dt) atan(w dt / 2) (1.03e-4 below w at dt = 1e-4;
    fitted to the twist coordinate over 0.3 s), to 1e-6."""
    model = shaft(1, 2, initial_modal_coordinates=[0.0, 0.0, 0.01, 0.0])
    h = 1e-4
    res = simulate(model, 0.3, h)
    omega = fitted_frequencies(res.t, res.modal_coordinates[:, 2], 1)[0]
    exact = 2 * np.pi * np.sqrt(GJ / JP) / (4 * L)
    want = 2.0 / h * np.arctan(exact * h / 2.0)
    assert abs(omega / want - 1.0) < 1e-6, (omega, want, exact)


@pytest.mark.parametrize("n_elements", [1, 3])
def test_end_torque_twists_the_shaft_uniformly(n_elements):
    """Static: an end torque T about the axis twists the tip by T L / (G J) (the loaded-end
    twist modes hold the linear twist exactly), and every element by its share.  (A torque
    fixed in the world does no conservative work on the bending: the shaft's two equal bending
    frequencies split into a complex pair, 1e-5 of them at T = 2 N m, and the static solve
    says so as flutter; measured, both element counts.)"""
    torque = 2.0
    model = shaft(n_elements, 2, end_torque=lambda t: [torque, 0.0, 0.0])
    with pytest.warns(UserWarning, match="flutter"):
        st = static_equilibrium(model)
    eta = st.model.initial_modal_coordinates
    per = len(eta) // n_elements
    twists = [tip_twist(st.model, eta[k * per:(k + 1) * per]) for k in range(n_elements)]
    want = torque * L / GJ / n_elements
    assert np.allclose(twists, want, rtol=1e-8), (twists, want)
    # the welded elements' frames follow the twisted end sections
    last = st.model.initial_rotation[-1]
    angle = np.arctan2(last[2, 1], last[1, 1])
    assert abs(angle - (n_elements - 1) * want) < 1e-8, angle


def test_twist_converges_to_the_reference_at_order_2():
    """DT-TMM against the Newton-Euler reference (its own twist rows, the Euler row's
    j_p int Psi coupling and B_t's columns A J_l e1 Psi(L)); output points at t = 1 s,
    dt 1e-3 .. 1.25e-4: fitted order 2 +- 0.2 (measured 1.99).  (Gravity comes on at t = 0 and
    rings the elements' second bending modes, 2400 rad/s, which the coarser steps do not
    resolve: the errors' ratios wander between 2.7 and 5 from step to step, the same with
    the twist switched off; without stiffening they are 3.9 to 4.5.)"""
    model = driven_arm_on_two_elements()
    steps = np.array([1e-3, 5e-4, 2.5e-4, 1.25e-4])
    errors = output_errors_against_reference(model, steps)
    slope = fitted_order(steps, errors)
    assert abs(slope - 2.0) < 0.2, (errors, slope)
    assert errors[-1] < 1e-4, errors


def test_twist_conserves_energy():
    """A twisting, bending cantilever with a body on an arm, released under gravity, no
    damping: kinetic plus potential energy (the twist's j_p (w . A e1 + psi')^2 / 2 and
    G J psi'^2 / 2 counted by the result's own quadrature) holds to 2e-5 of the largest
    kinetic energy at dt 1e-3, and the gap falls with dt at order 2 (measured 1.13e-5 and
    2.83e-6 at dt 1e-3 and 5e-4; the bound was 1e-5 while the arm was integrated on its own,
    7.1e-6 then: its frame now follows the end section exactly, kernels/stepping/step.py::_welded,
    and its mass centre meets the reference a little closer, 7.27e-6 against 7.58e-6 m)."""
    beam = EulerBernoulliBeam(length=1.0, mass_per_length=2.0, bending_stiffness=[60.0, 80.0],
                              polar_inertia_per_length=2e-3, modes_per_plane=2, torsion_modes=2,
                              torsional_stiffness=8.0)
    gaps, _ = energy_gaps_with_an_arm(beam, [0.0, 0.0, -9.81])
    # the arm's weight turns the tip by about m g r L / G J = 0.18 rad and back
    assert gaps[0] < 2e-5 and gaps[0] / gaps[1] > 3.0, gaps


@pytest.mark.parametrize("kwargs, words", [
    (dict(torsion_modes=-1, torsional_stiffness=1.0), "torsion_modes.*integer >= 0"),
    (dict(torsion_modes=1.5, torsional_stiffness=1.0), "torsion_modes.*integer >= 0"),
    (dict(torsion_modes=7, torsional_stiffness=1.0), "torsion_modes is at most 6"),
    (dict(torsion_modes=2), "torsion_modes=2 needs torsional_stiffness"),
    (dict(torsion_modes=2, torsional_stiffness=0.0), "torsional_stiffness"),
    (dict(torsion_modes=2, torsional_stiffness=-3.0), "torsional_stiffness"),
    (dict(torsion_modes=2, torsional_stiffness=np.nan), "torsional_stiffness"),
    (dict(torsion_modes=0, torsional_stiffness=-5.0), "torsional_stiffness"),
    (dict(torsion_modes=1, torsional_stiffness=1.0, initial_modal_coordinates=[0.0, 0.0]),
     "initial_modal_coordinates"),
])
def test_bad_twist_input_is_refused_naming_the_beam(kwargs, words):
    with pytest.raises(ValueError, match="'shaft'.*" + words):
        build_chain([FixedHinge(), EulerBernoulliBeam(
            length=1.0, mass_per_length=1.0, bending_stiffness=1.0,
            polar_inertia_per_length=1e-3, name="shaft", **kwargs)])


def test_twist_in_a_scene_round_trip(tmp_path):
    """A scene's beam takes torsion_modes and torsional_stiffness, save_scene writes them back,
    with the twist coordinates among the initial modal coordinates; `describe` lists the
    twist modes' frequencies."""
    from dttmm.interfaces.scene import load_scene, save_scene
    model = shaft(1, 2, initial_modal_coordinates=[0.0, 0.0, 0.01, -0.002], name="shaft")
    save_scene(model, tmp_path / "shaft.toml")
    again = load_scene(tmp_path / "shaft.toml").model
    assert np.array_equal(again.beam_params, model.beam_params)
    assert np.array_equal(again.initial_modal_coordinates, [0.0, 0.0, 0.01, -0.002])
    first = np.sqrt(GJ / JP) / (4 * L)
    assert f"2 twist modes, own frequencies (Hz): [ {first:.4f}" in model.describe()


def test_damped_twist_closes_the_energy_balance():
    """With modal damping on every mode (the twist's c_k = 2 zeta omega_k j_p L among them) and
    an end torque on the driven, twisting arm, simulate's energy balance (max_energy_error)
    counts the dampers' and the torque's work: its gap falls at order 2 with dt."""
    hub = PrescribedMotion.spin_about_axis([0, 0, 1], lambda t: 1.5 * t * t, lambda t: 3.0 * t,
                                           lambda t: 3.0)
    beam = EulerBernoulliBeam(length=1.0, mass_per_length=1.0, bending_stiffness=[30.0, 40.0],
                              polar_inertia_per_length=5e-3, modes_per_plane=2, torsion_modes=2,
                              torsional_stiffness=2.0, damping_ratio=0.05,
                              end_torque=lambda t: [0.3 * min(t, 1.0) ** 2, 0.0, 0.0])
    model = build_chain([FixedHinge(), beam], gravity=[0.0, 0.0, -9.81],
                        ground=Ground(motion=hub))
    gaps = [simulate(model, 1.0, h, max_energy_error=1.0).info["energy_balance_error"]
            for h in (2e-3, 1e-3)]
    assert gaps[1] < 1e-4 and gaps[0] / gaps[1] > 3.0, gaps
