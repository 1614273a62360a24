"""The beam's stretch (docs/beam.md, "Stretch"): axial_modes coordinates per beam moving the
sections along the frame's x by u_x = U . xi, exactly in every integral.  Against the
clamped-free rod's frequencies, the static stretch under an end force, the Newton-Euler
reference (order 2, with twist and stiffening on a driven hub) and energy conservation; bad
input is refused naming the beam.  (The kernel's integrals against a direct quadrature, and
its linearization, are in tests/test_kernels.py.)"""
import numpy as np
import pytest

from dttmm import EulerBernoulliBeam, FixedHinge, build_chain, static_equilibrium
from dttmm.elements.beam import stretch_along
from helpers import (driven_arm_on_two_elements, energy_gaps_with_an_arm, fitted_order,
                     output_errors_against_reference)

L, MU, EA = 1.0, 2.0, 5e4


def rod(n_elements, stretch_modes, end_force=None, **beam):
    """A clamped-free beam of n welded elements along x, stiff in bending, no gravity."""
    parts = []
    for k in range(n_elements):
        last = k == n_elements - 1
        parts += [FixedHinge(), EulerBernoulliBeam(
            length=L / n_elements, mass_per_length=MU, bending_stiffness=1e5,
            polar_inertia_per_length=1e-3, modes_per_plane=1, axial_modes=stretch_modes,
            axial_stiffness=EA, end_force=end_force if last else None, **beam)]
    return build_chain(parts, gravity=[0.0, 0.0, 0.0])


@pytest.mark.parametrize("n_elements, stretch_modes", [(1, 3), (4, 3)])
def test_clamped_free_axial_frequencies(n_elements, stretch_modes):
    """The first three frequencies (2 n - 1) / (4 L) sqrt(E A / mu) within 0.5%, from the small
    vibrations about the static equilibrium: one element with the free tip's eigenfunctions
    (measured exact), four welded elements with the loaded-end polynomial modes (measured
    +0.0008%, +0.0021%, +0.024%)."""
    st = static_equilibrium(rod(n_elements, stretch_modes))
    f = st.frequencies[np.isfinite(st.frequencies)]
    for n in (1, 2, 3):
        want = (2 * n - 1) / (4 * L) * np.sqrt(EA / MU)
        got = f[np.argmin(np.abs(f - want))]
        assert abs(got / want - 1.0) < 5e-3, (n, got, want)


@pytest.mark.parametrize("n_elements", [1, 3])
def test_end_force_stretches_the_rod_by_f_l_over_ea(n_elements):
    """Static: a pull F along the axis stretches the tip by F L / (E A) (the loaded-end
    stretch modes hold the linear displacement exactly): the output point moves out by it."""
    pull = 500.0
    st = static_equilibrium(rod(n_elements, 2, end_force=lambda t: [pull, 0.0, 0.0]))
    tip = st.positions()[2][-1]
    assert abs(tip[0] - (L + pull * L / EA)) < 1e-12, tip
    eta = st.model.initial_modal_coordinates
    per = len(eta) // n_elements
    ends = [stretch_along(st.model.beam_params[k], eta[k * per:(k + 1) * per],
                          [L / n_elements])[0] for k in range(n_elements)]
    assert np.allclose(ends, pull * L / EA / n_elements, rtol=1e-9), ends


def test_stretch_converges_to_the_reference_at_order_2():
    """Issue 16: DT-TMM against the Newton-Euler reference on a beam with stretch, torsion and
    stiffening under a driven hub (the reference's own stretch terms: its P, G, Q, C columns
    and rows, closed-form shape constants); output points at t = 1 s, dt 1e-3 .. 1.25e-4:
    fitted order 2 +- 0.2 (measured 2.10: 5.5e-5, 1.1e-5, 2.3e-6, 7.4e-7 m)."""
    model = driven_arm_on_two_elements(axial_modes=2, axial_stiffness=2000.0)
    steps = np.array([1e-3, 5e-4, 2.5e-4, 1.25e-4])
    errors = output_errors_against_reference(model, steps)
    slope = fitted_order(steps, errors)
    assert abs(slope - 2.0) < 0.2, (errors, slope)
    assert errors[-1] < 1e-5, errors


def test_stretch_conserves_energy():
    """A cantilever with stretch and twist and a body on an arm, released under a gravity with
    a component along it, no damping: energy (the stretch's 1/2 E A int u_x'^2 and its share
    of the kinetic energy counted by the result's own quadrature) holds to 1e-5 of the
    largest kinetic energy at dt 5e-4, falling at order 2 (measured 1.08e-5, 2.7e-6 at dt
    1e-3, 5e-4)."""
    beam = EulerBernoulliBeam(length=1.0, mass_per_length=2.0, bending_stiffness=[60.0, 80.0],
                              polar_inertia_per_length=2e-3, modes_per_plane=2, torsion_modes=1,
                              torsional_stiffness=8.0, axial_modes=2, axial_stiffness=3000.0)
    gaps, runs = energy_gaps_with_an_arm(beam, [-6.0, 0.0, -7.0])
    for res in runs:
        assert np.abs(res.modal_coordinates[:, 5:]).max() > 1e-4     # it does stretch
    assert gaps[1] < 1e-5 and gaps[0] / gaps[1] > 3.0, gaps


@pytest.mark.parametrize("kwargs, words", [
    (dict(axial_modes=-1, axial_stiffness=1.0), "axial_modes.*integer >= 0"),
    (dict(axial_modes=2.5, axial_stiffness=1.0), "axial_modes.*integer >= 0"),
    (dict(axial_modes=7, axial_stiffness=1.0), "axial_modes is at most 6"),
    (dict(axial_modes=2), "axial_modes=2 needs axial_stiffness"),
    (dict(axial_modes=2, axial_stiffness=0.0), "axial_stiffness"),
    (dict(axial_modes=2, axial_stiffness=-3.0), "axial_stiffness"),
    (dict(axial_modes=2, axial_stiffness=np.inf), "axial_stiffness"),
    (dict(axial_modes=1, axial_stiffness=1.0, initial_modal_coordinates=[0.0, 0.0]),
     "initial_modal_coordinates"),
])
def test_bad_stretch_input_is_refused_naming_the_beam(kwargs, words):
    with pytest.raises(ValueError, match="'rod'.*" + words):
        build_chain([FixedHinge(), EulerBernoulliBeam(
            length=1.0, mass_per_length=1.0, bending_stiffness=1.0,
            polar_inertia_per_length=1e-3, name="rod", **kwargs)])


def test_stretch_in_a_scene_round_trip(tmp_path):
    """A scene's beam takes axial_modes and axial_stiffness, save_scene writes them back;
    `describe` lists the stretch modes' frequencies."""
    from dttmm.interfaces.scene import load_scene, save_scene
    model = rod(1, 2, initial_modal_coordinates=[0.0, 0.0, 1e-4, 0.0], name="rod")
    save_scene(model, tmp_path / "rod.toml")
    again = load_scene(tmp_path / "rod.toml").model
    assert np.array_equal(again.beam_params, model.beam_params)
    assert np.array_equal(again.initial_modal_coordinates, [0.0, 0.0, 1e-4, 0.0])
    first = np.sqrt(EA / MU) / (4 * L)
    assert f"2 stretch modes, own frequencies (Hz): [ {first:.4f}" in model.describe()
