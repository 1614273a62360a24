"""Scene files, profiles and the command line (docs/scenes.md): every shipped scene builds the
same model as its Python builder and runs from `dttmm run`; a model saves to a scene and loads
back to the same arrays; bad scenes are refused naming the file, the table and the key."""
import dataclasses
import subprocess
import sys

import numpy as np
import pytest

from dttmm.model.chains import (arm, bouncing_ball, box_on_incline, five_link_tree, rigid_chain,
                                spacecraft, stiff_cantilever, three_pendulum, tumbling_box)
from dttmm.interfaces.cli import main, shipped_scenes
from dttmm.model.mechanisms import flexible_slider_crank, n_four_bar, slider_crank, stewart_platform
from dttmm.model.model import Model
from dttmm.results.result import Result
from dttmm.model.profiles import KINDS, profile
from dttmm.interfaces.scene import SceneError, load_scene, save_scene

BUILDERS = {"three_pendulum": three_pendulum, "rigid_chain": lambda: rigid_chain(3),
            "tree": five_link_tree, "arm": lambda: arm("torque"),
            "arm_motion": lambda: arm("motion"),
            "flexible_arm": lambda: arm("motion", flexible=True),
            "cantilever": lambda: stiff_cantilever(4),
            "slider_crank": slider_crank, "four_bar": lambda: n_four_bar(2),
            "stewart": lambda: stewart_platform("motion"),
            "flexible_slider_crank": flexible_slider_crank, "tumbling_body": tumbling_box,
            "spacecraft": spacecraft, "bouncing_ball": bouncing_ball,
            "incline": box_on_incline}


# the closed-loop mechanisms are assembled (dttmm.assemble): their joints' rest rotations are
# read again from the frames the scene holds, equal to rounding (measured 8e-16)
ASSEMBLED = {"slider_crank", "four_bar", "stewart", "flexible_slider_crank",
             "incline"}     # (and the incline's tilted box: its rotation projected onto
#                             rotations again when read, equal to rounding, 2e-16)


def same_model(a, b, atol=0.0):
    for f in dataclasses.fields(Model):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert x.shape == y.shape and (np.array_equal(x, y) if atol == 0.0 else
                                           np.allclose(x, y, rtol=0.0, atol=atol)), f.name
        elif f.name in ("n_bodies", "body_names", "hinge_names", "tip_pinned"):
            assert x == y, f.name
    for da, db in zip(a.drives, b.drives):
        for x, y in zip(da, db):
            assert (x is None) == (y is None)
            if x is not None:
                assert {k: x[k] for k in ("kind", "stiffness", "damping", "rest")} == \
                       {k: y[k] for k in ("kind", "stiffness", "damping", "rest")}
    for fa, fb in zip(a.forces + a.torques, b.forces + b.torques):
        assert (fa is None) == (fb is None)


def test_every_example_ships_as_a_scene_that_builds_the_same_model():
    assert set(shipped_scenes()) == set(BUILDERS)
    for name, build in BUILDERS.items():
        same_model(build(), load_scene(shipped_scenes()[name]).model,
                   1e-14 if name in ASSEMBLED else 0.0)


@pytest.mark.parametrize("name", sorted(BUILDERS))
def test_a_model_saves_to_a_scene_and_loads_back_the_same(name, tmp_path):
    scene = load_scene(shipped_scenes()[name])
    save_scene(scene.model, tmp_path / "copy.toml", run=scene.run, name=name)
    back = load_scene(tmp_path / "copy.toml")
    same_model(scene.model, back.model, 1e-14 if name in ASSEMBLED else 0.0)
    assert back.run == scene.run


def test_named_points_keep_their_indices_through_a_scene(tmp_path):
    """A body with three named points of which only the second and third carry children:
    the saved scene keeps their indices (the first written as a stand-in), so the model comes
    back with the same attachment arrays."""
    from dttmm import BallJoint, System
    from dttmm.model.chains import unit_link
    system = System()
    system.add(unit_link(name="hub", points={"a": [0.1, 0, 0], "b": [0.2, 0, 0],
                                             "c": [0.3, 0.1, 0]}), BallJoint())
    system.add(unit_link(name="left"), BallJoint(), parent="hub", at="b")
    system.add(unit_link(name="right"), BallJoint(), parent="hub", at="c")
    model = system.build()
    save_scene(model, tmp_path / "points.toml")
    same_model(model, load_scene(tmp_path / "points.toml").model)


def test_the_drives_of_a_scene_move_as_in_python():
    """The arm's motion drive from its scene equals the Python builder's law at any time."""
    drive = load_scene(shipped_scenes()["arm_motion"]).model.drives[0][0]
    position, velocity, acceleration = drive["function"]
    for t in (0.0, 0.3, 1.7):
        assert position(t) == pytest.approx(0.5 * t + 0.2 * (1.0 - np.cos(2.0 * t)), abs=1e-15)
        assert velocity(t) == pytest.approx(0.5 + 0.4 * np.sin(2.0 * t), abs=1e-15)
        assert acceleration(t) == pytest.approx(0.8 * np.cos(2.0 * t), abs=1e-15)


@pytest.mark.parametrize("kind", KINDS)
def test_profiles_carry_their_own_derivatives(kind):
    """Each profile's rate and acceleration against central differences of its value."""
    spec = {"constant": {"value": 2.0}, "linear": {"slope": 0.7, "offset": 1.0},
            "sine": {"amplitude": [1.0, 2.0], "frequency": 0.8, "phase": 0.3},
            "ramp": {"value": 3.0, "duration": 2.0}, "spin_up": {"omega": 6.0, "period": 15.0},
            "pulse": {"value": [0.0, 10.0], "duration": 1.0},
            "table": {"t": [0.0, 1.0, 3.0], "value": [0.0, 2.0, 1.0]},
            "sum": {"terms": [{"profile": "linear", "slope": 1.0},
                              {"profile": "sine", "amplitude": 1.0,
                               "angular_frequency": 2.0}]}}[kind]
    p = profile(dict(profile=kind, **spec))
    eps = 1e-5
    for t in (0.4, 1.3, 7.7, 16.0):
        rate = (np.asarray(p(t + eps)) - p(t - eps)) / (2 * eps)
        acc = (np.asarray(p.rate(t + eps)) - p.rate(t - eps)) / (2 * eps)
        assert np.allclose(p.rate(t), rate, atol=1e-6), t
        assert np.allclose(p.acceleration(t), acc, atol=1e-5), t
    assert profile(p.spec()).spec() == p.spec()


def test_a_pulse_is_its_value_then_nothing_and_their_mean_at_the_switch():
    p = profile({"profile": "pulse", "value": 10.0, "duration": 2.0})
    assert (p(0.0), p(1.999), p(2.0), p(2.0 + 1e-6), p(5.0)) == (10.0, 10.0, 5.0, 0.0, 0.0)
    assert p.rate(1.0) == 0.0 and p.acceleration(1.0) == 0.0


def test_the_spin_up_law_of_seed_000():
    """theta(t) = (W / T)(t^2 / 2 + (T / 2 pi)^2 (cos(2 pi t / T) - 1)) up to T, then
    W (t - T / 2): continuous with its rate and acceleration at T, rate W after it."""
    p = profile({"profile": "spin_up", "omega": 6.0, "period": 15.0})
    t = 4.0
    assert p(t) == pytest.approx(6.0 / 15.0 * (t * t / 2 + (15.0 / (2 * np.pi)) ** 2
                                                * (np.cos(2 * np.pi * t / 15.0) - 1.0)))
    assert p(15.0) == pytest.approx(6.0 * 7.5) and p.rate(15.0) == pytest.approx(6.0)
    assert p.acceleration(15.0) == pytest.approx(0.0, abs=1e-12) and p.rate(20.0) == 6.0


BASE = '''
[model]
gravity = [0.0, -9.81, 0.0]

[[body]]
name = "link"
type = "rigid"
mass = 1.0
inertia = [0.1, 0.4, 0.4]
inertia_about = "input"
to_mass_center = [0.5, 0.0, 0.0]
to_output = [1.0, 0.0, 0.0]

[body.joint]
type = "ball"

[[body]]
name = "beam"
type = "beam"
length = 1.0
mass_per_length = 1.3
bending_stiffness = 300.0
polar_inertia_per_length = 1e-4

[body.joint]
type = "ball"
parent = "link"
'''


@pytest.mark.parametrize("change, message", [
    (("mass = 1.0\n", ""), r"\[\[body\]\] 1 \('link'\) needs the key 'mass'"),   # missing key
    (("mass = 1.0", 'mass = "heavy"'), r"\[\[body\]\] 1 \('link'\) key 'mass': a number"),
    (('type = "beam"', 'type = "rope"'), r"\[\[body\]\] 2 \('beam'\) key 'type'"),  # unknown kind
    (("length = 1.0", "length = -1.0"), r"\[\[body\]\] 2 \('beam'\).*length must be > 0"),
    (('type = "ball"\nparent', 'type = "hinge"\nparent'), r"\[body.joint\] key 'type'"),
    (("inertia_about", "inertia_around"), r"unknown key 'inertia_around'"),
    (('parent = "link"', 'parent = "lnk"'), r"parent 'lnk' is not in the system"),
    (("bending_stiffness = 300.0", "bending_stiffness = [1, 2, 3]"),
     r"key 'bending_stiffness': a number or 2 numbers"),
])
def test_bad_scenes_name_the_file_the_table_and_the_key(tmp_path, change, message):
    path = tmp_path / "bad.toml"
    old, new = change
    assert old in BASE
    path.write_text(BASE.replace(old, new, 1))
    with pytest.raises(SceneError, match=message) as err:
        load_scene(path)
    assert str(path) in str(err.value)
    path.write_text(BASE)
    load_scene(path)                                        # (the base itself is fine)


def test_a_profile_with_a_bad_key_is_refused(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(BASE.replace('type = "rigid"', 'type = "rigid"\n'
                                 'force = { profile = "sine", amplitude = 1.0 }'))
    with pytest.raises(SceneError, match=r"key 'force'.*'frequency' \(Hz\) and "
                                         r"'angular_frequency'"):
        load_scene(path)
    from dttmm.model.profiles import profile
    for spec, key in ((dict(profile="table", t=1.0, value=[1.0, 2.0]), "'t'"),
                      (dict(profile="table", t=[0.0, 1.0], value=3.0), "'value'")):
        with pytest.raises(ValueError, match=f"key {key}"):
            profile(spec)
    path.write_text("[model\n")
    with pytest.raises(SceneError, match="not valid TOML"):
        load_scene(path)


def test_info_prints_the_model(capsys):
    """The three-pendulum: 3 ball joints (9) and 2 modes per plane (4): 13 degrees of freedom;
    the beam's first pinned mode (pi / L)^2 sqrt(EI / mu) / 2 pi = 24.96 Hz."""
    assert main(["info", str(shipped_scenes()["three_pendulum"])]) == 0
    out = capsys.readouterr().out
    assert "13 degrees of freedom" in out and "24.96" in out and "suggested dt: 0.0005 s" in out


def test_run_from_the_static_equilibrium(tmp_path, capsys):
    """dttmm run --static-start: the three-pendulum hangs at rest (its equilibrium is stable) and
    the run from there keeps its output points to 1e-9 m."""
    out = tmp_path / "rest.npz"
    assert main(["run", str(shipped_scenes()["three_pendulum"]), "--t-end", "0.05",
                 "--static-start", "--no-progress", "--out", str(out)]) == 0
    assert "static equilibrium in" in capsys.readouterr().out
    res = Result.load_npz(out)
    assert np.abs(res.position_output - res.position_output[0]).max() < 1e-9


def test_example_lists_and_writes_the_shipped_scenes(tmp_path, capsys):
    assert main(["example"]) == 0
    assert "three_pendulum" in capsys.readouterr().out
    assert main(["example", "tree", "--to", str(tmp_path)]) == 0
    same_model(five_link_tree(), load_scene(tmp_path / "tree.toml").model)
    assert main(["example", "nothing"]) == 2


@pytest.mark.parametrize("name", sorted(BUILDERS))
def test_every_shipped_scene_runs_from_the_command_line(name, tmp_path):
    out = tmp_path / "r.npz"
    run = subprocess.run([sys.executable, "-m", "dttmm", "run", str(shipped_scenes()[name]),
                          "--t-end", "0.02", "--out", str(out), "--csv", str(tmp_path / "r.csv"),
                          "--no-progress"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    adaptive = "rtol" in load_scene(shipped_scenes()[name]).run
    assert (any(f"ran {n} steps" in run.stdout for n in (20, 200, 2000))
            or adaptive and "adaptive: steps of" in run.stdout), run.stdout
    from dttmm import Result
    res = Result.load_npz(out)
    assert res.t[-1] == pytest.approx(0.02) and np.all(np.isfinite(res.position_output))


def test_the_command_line_reports_a_bad_scene_and_a_run_that_stops(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(BASE.replace("length = 1.0", "length = -1.0"))
    run = subprocess.run([sys.executable, "-m", "dttmm", "run", str(bad), "--t-end", "1"],
                         capture_output=True, text=True)
    assert run.returncode == 2 and "bad.toml" in run.stderr and "length" in run.stderr
    run = subprocess.run([sys.executable, "-m", "dttmm", "run",
                          str(shipped_scenes()["rigid_chain"]), "--t-end", "5", "--dt", "0.5"],
                         capture_output=True, text=True)
    assert run.returncode == 1 and "local error estimate" in run.stderr
    run = subprocess.run([sys.executable, "-m", "dttmm", "run",            # adapts instead
                          str(shipped_scenes()["rigid_chain"]), "--t-end", "5", "--dt", "0.5",
                          "--rtol", "1e-4", "--no-progress"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "adaptive steps, rtol = 0.0001" in run.stdout and "steps rejected" in run.stdout
    run = subprocess.run([sys.executable, "-m", "dttmm", "run",            # the balance
                          str(shipped_scenes()["rigid_chain"]), "--t-end", "0.5", "--dt", "1e-3",
                          "--max-energy-error", "1e-4", "--no-progress"],
                         capture_output=True, text=True)
    assert run.returncode == 0 and "energy balance" in run.stdout, run.stderr


def test_figures_and_an_animation_are_written(tmp_path):
    from PIL import Image
    run = subprocess.run([sys.executable, "-m", "dttmm", "run",
                          str(shipped_scenes()["flexible_arm"]), "--t-end", "0.05",
                          "--plots", str(tmp_path / "figs"), "--animate",
                          str(tmp_path / "arm.gif"), "--no-progress"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    names = {p.name for p in (tmp_path / "figs").iterdir()}
    assert {"positions.png", "angles.png", "energy.png", "joints.png", "modal.png"} <= names
    with Image.open(tmp_path / "arm.gif") as gif:
        assert gif.n_frames > 10


def test_a_stiffened_beam_keeps_its_stiffening_through_a_scene(tmp_path):
    """save_scene writes `stiffening = true` for a beam with geometric stiffening, and the scene
    builds it back (beam_params' STIFFENING column), while a plain beam stays plain."""
    from dttmm.model.chains import three_pendulum
    for on in (True, False):
        model = three_pendulum(2, stiffening=on)
        save_scene(model, tmp_path / "tp.toml")
        assert ("stiffening = true" in (tmp_path / "tp.toml").read_text()) == on
        back = load_scene(tmp_path / "tp.toml").model
        same_model(model, back)
        assert back.beam_params[1, 8] == float(on)


# the soft pendulum of issue 32 (examples/falling_pendulum.py) as two strain rods: 1.2 m,
# A = 0.0018 m^2, I = 1.215e-8 m^4, rho = 5540 kg/m^3, E = 0.7e6 Pa, EA = 1e6 N
ROD_TABLE = '''
[[body]]
name = "{name}"
type = "rod"
length = 0.6
mass_per_length = 9.972
bending_stiffness = 8.505e-3
polar_inertia_per_length = 1.3462e-4
stretch = true
axial_stiffness = 1e6

[body.joint]
{joint}
'''
ROD_SCENE = ('''
[model]
name = "soft_pendulum"
gravity = [0.0, -9.81, 0.0]
''' + ROD_TABLE.format(name="inner", joint='type = "ball"')
             + ROD_TABLE.format(name="outer", joint='type = "fixed"\nparent = "inner"'))


def test_strain_rods_run_from_a_scene_and_save_back_as_rods(tmp_path):
    """type = "rod" builds the StrainRod the same arguments build in Python, and runs; a
    model of rods with twist, rotary inertia, damping and an initial strain saves and loads
    back to the same arrays (before, save_scene wrote a rod as the rigid body of its straight
    shape, quietly)."""
    from dttmm import BallJoint, FixedHinge, StrainRod, build_chain, simulate

    def rod(name, **extra):
        return StrainRod(length=0.6, mass_per_length=9.972, bending_stiffness=8.505e-3,
                         polar_inertia_per_length=1.3462e-4, stretch=True, axial_stiffness=1e6,
                         name=name, **extra)

    path = tmp_path / "rods.toml"
    path.write_text(ROD_SCENE)
    scene = load_scene(path)
    same_model(build_chain([BallJoint(), rod("inner"), FixedHinge(), rod("outer")],
                           gravity=[0.0, -9.81, 0.0]), scene.model)
    result = simulate(scene.model, 0.01, 1e-3)
    assert np.all(np.isfinite(result.modal_coordinates)) and result.t[-1] == pytest.approx(0.01)
    import matplotlib
    matplotlib.use("Agg")
    from dttmm.results.plots import plot_modal
    axes = plot_modal(result).axes[0]       # (a rod's strain, not a beam's modal coordinates)
    assert "strain coefficient (1/m" in axes.get_ylabel()
    assert axes.get_legend_handles_labels()[1][:2] == ["inner bend_z1", "inner bend_z2"]

    model = build_chain([BallJoint(), rod("inner", twist=True, torsional_stiffness=2e-2,
                                          rotary_inertia_per_length=[1e-6, 2e-6], damping=1e-3,
                                          strain_modes=3, stations=7,
                                          initial_strain=np.linspace(0.1, 0.9, 12)),
                         FixedHinge(), rod("outer", initial_strain_rate=np.arange(6.0))],
                        gravity=[0.0, -9.81, 0.0])
    save_scene(model, tmp_path / "copy.toml")
    text = (tmp_path / "copy.toml").read_text()
    assert text.count('type = "rod"') == 2 and 'type = "rigid"' not in text
    same_model(model, load_scene(tmp_path / "copy.toml").model)


@pytest.mark.parametrize("change, message", [
    (("bending_stiffness = 8.505e-3\n", ""), r"\('inner'\) needs the key 'bending_stiffness'"),
    (("stretch = true", "modes_per_plane = 2"), r"\('inner'\).*unknown key 'modes_per_plane'"),
    (("axial_stiffness = 1e6", "axial_stiffness = -1.0"), r"\('inner'\).*axial_stiffness"),
])
def test_bad_rods_in_a_scene_name_the_table_and_the_key(tmp_path, change, message):
    path = tmp_path / "bad.toml"
    old, new = change
    path.write_text(ROD_SCENE.replace(old, new, 1))
    with pytest.raises(SceneError, match=message):
        load_scene(path)
