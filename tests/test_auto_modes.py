"""modes_per_plane="auto" and Model.describe() (issue 16: model no more than a scene needs,
and say what was kept and why)."""
import numpy as np
import pytest

import dttmm
from dttmm.interfaces.scene import load_scene, save_scene

EI = 100.0



def test_auto_modes_keep_what_is_below_the_cutoff_and_say_why(tmp_path):
    """modes_per_plane='auto' (issue 16): a clamped-free beam (EI = 100 N m^2, mu = 1 kg/m,
    L = 1 m: 5.60, 35.07, 98.19, 192.4, 318.1 Hz, the exact eigenvalues) keeps the modes at or
    below the cutoff, at least one; describe() names the count, the family and its reason, and
    the next frequency; a scene written from the model builds the same arrays again.  Below
    the second mode it keeps 2, not 1: "auto" keeps at least what the default's accuracy
    needs (one eigenfunction is 1.3% off the static deflection under the beam's weight)."""
    def model(cutoff):
        beam = dttmm.EulerBernoulliBeam(length=1.0, bending_stiffness=EI, mass_per_length=1.0,
                                        polar_inertia_per_length=1e-4, modes_per_plane="auto",
                                        frequency_cutoff=cutoff, name="arm")
        return dttmm.build_chain([dttmm.FixedHinge(), beam], gravity=(0.0, 0.0, 0.0))
    for cutoff, kept in ((1.0, 2), (40.0, 2), (300.0, 4), (1e6, 10)):
        assert model(cutoff).n_modes[0] == 2 * kept, cutoff
    text = model(300.0).describe()
    assert "4 modes per plane" in text and "the next at 318.1 Hz" in text
    assert "clamped-free eigenfunctions" in text and "free tip" in text
    assert "stiffening on" in text                 # (the default: a clamped-free beam)
    path = tmp_path / "auto.toml"
    save_scene(model(300.0), path)
    again = load_scene(path).model
    assert np.array_equal(again.beam_params, model(300.0).beam_params)
    with pytest.raises(ValueError, match="'arm'.*without a frequency_cutoff.*step=dt"):
        dttmm.build_chain([dttmm.FixedHinge(), dttmm.EulerBernoulliBeam(
            length=1.0, bending_stiffness=EI, mass_per_length=1.0,
            polar_inertia_per_length=1e-4, modes_per_plane="auto", name="arm")])
    with pytest.raises(ValueError, match="modes_per_plane='auto' only"):
        dttmm.build_chain([dttmm.FixedHinge(), dttmm.EulerBernoulliBeam(
            length=1.0, bending_stiffness=EI, mass_per_length=1.0,
            polar_inertia_per_length=1e-4, modes_per_plane=2, frequency_cutoff=10.0)])


def test_auto_modes_take_their_cutoff_from_the_step_and_the_drives():
    """modes_per_plane='auto' without a frequency_cutoff, built with step= (and duration=):
    the cutoff is 1 / (20 step), 500 Hz at step 1e-4 s, where the clamped-free beam above
    (5.60, 35.07, 98.19, 192.4, 318.1, 475.2, 663.7 Hz) keeps 6 modes; on a hub swung by
    theta = 0.01 sin(2 pi 4 t) over 10 s (40 periods: the angular acceleration's spectrum is
    one line at 4 Hz) it is ten times that, 40 Hz: 2 modes, and describe() says why; a
    constant spin bounds nothing; a scene's [run] dt (1e-3 s: 50 Hz, 2 modes) does the
    same."""
    from dttmm import Ground, PrescribedMotion
    from dttmm.interfaces.scene import scene_from_dict, scene_of
    w = 2 * np.pi * 4.0

    def model(motion=None, **build):
        beam = dttmm.EulerBernoulliBeam(length=1.0, bending_stiffness=EI, mass_per_length=1.0,
                                        polar_inertia_per_length=1e-4, modes_per_plane="auto",
                                        name="arm")
        return dttmm.build_chain([dttmm.FixedHinge(), beam], gravity=(0.0, 0.0, 0.0),
                                 ground=Ground(motion=motion), **build)
    swing = PrescribedMotion.spin_about_axis(
        [0, 0, 1], lambda t: 0.01 * np.sin(w * t), lambda t: 0.01 * w * np.cos(w * t),
        lambda t: -0.01 * w * w * np.sin(w * t))
    spin = PrescribedMotion.spin_about_axis([0, 0, 1], lambda t: 2.0 * t, lambda t: 2.0,
                                            lambda t: 0.0)
    assert model(step=1e-4).n_modes[0] == 2 * 6
    assert model(swing, step=1e-4).n_modes[0] == 2 * 6          # no duration: the step's
    swung = model(swing, step=1e-4, duration=10.0)
    assert swung.n_modes[0] == 2 * 2
    assert abs(swung.beam_params[0, 9] - 40.0) < 0.05            # ten times 4 Hz
    assert "ten times the drives' bandwidth, 4 Hz" in swung.describe()
    assert model(spin, step=1e-4, duration=10.0).n_modes[0] == 2 * 6
    assert "from the step 0.0001 s" in model(step=1e-4).describe()
    scene = scene_of(model(step=1e-4), run=dict(t_end=1.0, dt=1e-3))    # 50 Hz: 2 modes
    for body in scene["body"]:
        body.pop("frequency_cutoff", None)
    assert scene_from_dict(scene).model.n_modes[0] == 2 * 2
    with pytest.raises(ValueError, match="step"):
        model(step=-1.0)


def test_auto_twist_and_stretch_keep_their_modes_below_the_cutoff():
    """torsion_modes="auto" and axial_modes="auto" (with modes_per_plane="auto") keep every
    twist and stretch mode at or below frequency_cutoff, maybe none: a clamped-free shaft
    (twist 55.9, 167.7, 279.5 Hz; stretch 39.5, 118.6, 197.6 Hz)."""
    from dttmm import EulerBernoulliBeam, FixedHinge, build_chain

    def shaft(cutoff, **kw):
        return build_chain([FixedHinge(), EulerBernoulliBeam(
            length=1.0, mass_per_length=2.0, bending_stiffness=1e3, polar_inertia_per_length=1e-3,
            modes_per_plane="auto", frequency_cutoff=cutoff, torsion_modes="auto",
            torsional_stiffness=50.0, axial_modes="auto", axial_stiffness=5e4, name="shaft",
            **kw)], gravity=[0.0, 0.0, 0.0])
    for cutoff, twist, stretch in ((30.0, 0, 0), (60.0, 1, 1), (200.0, 2, 3)):
        model = shaft(cutoff)
        assert tuple(model.beam_params[0, [10, 13]]) == (twist, stretch), cutoff
        assert model.n_modes[0] == 2 * model.beam_params[0, 6] + twist + stretch
    with pytest.raises(ValueError, match="'shaft'.*torsion_modes='auto'.*modes_per_plane='auto'"):
        build_chain([FixedHinge(), EulerBernoulliBeam(
            length=1.0, mass_per_length=2.0, bending_stiffness=1e3, polar_inertia_per_length=1e-3,
            torsion_modes="auto", torsional_stiffness=50.0, name="shaft")])


def test_the_default_beam_meets_engineering_accuracy():
    """A steel cantilever (1 m, 10 mm square) with a 0.2 kg tip mass, built with the defaults:
    first frequency within 1% of the exact root of 1 + cos b cosh b + r b (cos b sinh b -
    sin b cosh b) = 0 (r the mass ratio), tip deflection under gravity within 1% of
    mu g L^4 / 8 EI + M g L^3 / 3 EI.  One mode per plane, the old default, was 20% and 30% off
    (measured: 7.05 Hz against 5.857, 6.47 mm against 9.24).  describe() gives the estimate."""
    from scipy.optimize import brentq
    e, rho, a, length, tip = 210e9, 7850.0, 0.01, 1.0, 0.2
    ei, mu = e * a ** 4 / 12.0, rho * a * a
    model = dttmm.build_chain([
        dttmm.FixedHinge(),
        dttmm.EulerBernoulliBeam(length=length, bending_stiffness=ei, mass_per_length=mu,
                                 polar_inertia_per_length=rho * a ** 4 / 6.0, name="steel"),
        dttmm.FixedHinge(),
        dttmm.RigidBody(mass=tip, inertia=[1e-9] * 3, inertia_about="mass_center",
                        to_mass_center=[0, 0, 0], to_output=[0, 0, 0])],
        gravity=[0.0, -9.81, 0.0])
    r = tip / (mu * length)
    root = brentq(lambda b: 1 + np.cos(b) * np.cosh(b)
                  + r * b * (np.cos(b) * np.sinh(b) - np.sin(b) * np.cosh(b)), 0.5, 1.875)
    exact_f = root ** 2 * np.sqrt(ei / mu) / (2 * np.pi * length ** 2)
    exact_d = 9.81 * (mu * length ** 4 / (8 * ei) + tip * length ** 3 / (3 * ei))
    eq = dttmm.static_equilibrium(model)
    f = eq.frequencies[np.isfinite(eq.frequencies) & (eq.frequencies > 0)][0]
    assert abs(f / exact_f - 1.0) < 0.01, (f, exact_f)
    assert abs(-eq.positions()[2][-1][1] / exact_d - 1.0) < 0.01
    text = model.describe()
    assert "3 modes per plane" in text and "estimated truncation error" in text
    assert "0.2 kg beyond its output" in text and "modes_per_plane=None (default)" in text


def test_the_default_count_follows_the_given_initial_coordinates():
    """Initial modal coordinates without modes_per_plane say the count by their size; a size
    that fits no count is refused naming the beam."""
    beam = lambda **kw: dttmm.EulerBernoulliBeam(length=1.0, bending_stiffness=EI,
                                                 mass_per_length=1.0,
                                                 polar_inertia_per_length=1e-4, name="b", **kw)
    model = dttmm.build_chain([dttmm.FixedHinge(), beam(initial_modal_coordinates=[0.0] * 6)])
    assert model.n_modes[0] == 6
    with pytest.raises(ValueError, match="'b'.*initial_modal_coordinates must have"):
        dttmm.build_chain([dttmm.FixedHinge(), beam(initial_modal_coordinates=[0.0] * 3)])
