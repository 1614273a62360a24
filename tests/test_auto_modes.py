"""modes_per_plane="auto" and Model.describe() (issue 16: model no more than a scene needs,
and say what was kept and why)."""
import numpy as np
import pytest

import dttmm
from dttmm.scene import load_scene, save_scene

EI = 100.0



def test_auto_modes_keep_what_is_below_the_cutoff_and_say_why(tmp_path):
    """modes_per_plane='auto' (issue 16): a clamped-free beam (EI = 100 N m^2, mu = 1 kg/m,
    L = 1 m: 5.60, 35.07, 98.19, 192.4, 318.1 Hz, the exact eigenvalues) keeps the modes at or
    below the cutoff, at least one; describe() names the count, the family and its reason, and
    the next frequency; a scene written from the model builds the same arrays again."""
    def model(cutoff):
        beam = dttmm.EulerBernoulliBeam(length=1.0, bending_stiffness=EI, mass_per_length=1.0,
                                        polar_inertia_per_length=1e-4, modes_per_plane="auto",
                                        frequency_cutoff=cutoff, name="arm")
        return dttmm.build_chain([dttmm.FixedHinge(), beam], gravity=(0.0, 0.0, 0.0))
    for cutoff, kept in ((1.0, 1), (40.0, 2), (300.0, 4), (1e6, 10)):
        assert model(cutoff).n_modes[0] == 2 * kept, cutoff
    text = model(300.0).describe()
    assert "4 modes per plane" in text and "the next at 318.1 Hz" in text
    assert "clamped-free eigenfunctions" in text and "free tip" in text
    assert "stiffening on" in text                 # (the default: a clamped-free beam)
    path = tmp_path / "auto.toml"
    save_scene(model(300.0), path)
    again = load_scene(path).model
    assert np.array_equal(again.beam_params, model(300.0).beam_params)
    with pytest.raises(ValueError, match="frequency_cutoff.*missing"):
        dttmm.build_chain([dttmm.FixedHinge(), dttmm.EulerBernoulliBeam(
            length=1.0, bending_stiffness=EI, mass_per_length=1.0,
            polar_inertia_per_length=1e-4, modes_per_plane="auto")])
    with pytest.raises(ValueError, match="modes_per_plane='auto' only"):
        dttmm.build_chain([dttmm.FixedHinge(), dttmm.EulerBernoulliBeam(
            length=1.0, bending_stiffness=EI, mass_per_length=1.0,
            polar_inertia_per_length=1e-4, modes_per_plane=2, frequency_cutoff=10.0)])


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
