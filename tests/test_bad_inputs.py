"""Inputs that used to slip through or give unhelpful messages (issue 28, items 4 and 5): each is
refused with a message naming the argument, element, file or time, or made to work as meant.
One row per case; each row says what used to happen."""
import dataclasses
import subprocess
import sys

import numpy as np
import pytest

import dttmm
from dttmm import (BallJoint, JointForce, RevoluteJoint, RigidBody, System, build_chain,
                   simulate)
from dttmm.model.chains import rigid_chain


def link(**kw):
    return RigidBody(mass=1.0, inertia=[1 / 6, 5 / 12, 5 / 12], inertia_about="input",
                     to_mass_center=[0.5, 0, 0], to_output=[1, 0, 0], **kw)


def pendulum(**kw):
    return build_chain([BallJoint(), link(**kw)], gravity=[0, -9.81, 0])


def revolute(drive):
    system = System(gravity=[0, -9.81, 0])
    system.add(link(), RevoluteJoint(axis=[0, 0, 1], drive=drive, name="shoulder"))
    return system.build()


# (simulate's keyword arguments, the message expected); before: accepted or a raw error
SIMULATE_ARGUMENTS = [
    (dict(newton_tol=-1.0), "newton_tol must be a finite number >= 0"),       # accepted
    (dict(newton_tol=np.nan), "newton_tol must be a finite number >= 0"),     # accepted
    (dict(newton_iterations=np.nan), "newton_iterations must be an integer"),  # int(NaN)
    (dict(newton_iterations=True), "newton_iterations must be an integer"),   # coerced
    (dict(record_every=np.inf), "record_every must be an integer"),           # int(inf)
    (dict(dt=1e-300), "dt = 1e-300 s makes"),                                 # ZeroDivision
    (dict(t_eval=[]), "t_eval is empty"),                                     # IndexError
    (dict(rho_inf="x"), "rho_inf must be in"),                                # raw float()
    (dict(scheme="energy_momentum", rho_inf=0.5), "rho_inf must be 1"),       # ignored
    (dict(richardson=True, stream="s"), "richardson=True and stream"),        # dropped
    (dict(richardson=True, max_energy_error=0.1), "richardson=True and max_energy_error"),
    (dict(full_state="no"), "full_state must be True or False"),              # coerced
    (dict(richardson="yes"), "richardson must be True, False or the number of runs"),
]


@pytest.mark.parametrize("options, message", SIMULATE_ARGUMENTS,
                         ids=[m for _, m in SIMULATE_ARGUMENTS])
def test_simulate_refuses_bad_arguments_by_name(options, message, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    run = dict(t_end=0.01, dt=1e-3)
    run.update(options)
    with pytest.raises(ValueError, match=f"simulate: .*{message}"):
        simulate(rigid_chain(2), **run)


# (a model builder, the message expected at build); before: accepted (coerced)
BUILD_INPUTS = [
    (lambda: pendulum(force=lambda t: [[0.0, 0.0, 1.0]]), "force.0. must be a flat vector"),
    (lambda: pendulum(force=lambda t: ["1", "2", "3"]), "force.0. must be a vector of 3"),
    (lambda: pendulum(force=[0.0, 1.0]), "force must be 3 finite numbers, a function of time"),
    (lambda: pendulum(torque=[0.0, np.nan, 1.0]), "torque must be 3 finite numbers"),
    (lambda: pendulum(force="up"), "force must be 3 finite numbers"),
    (lambda: revolute(JointForce(lambda t, q, qd: "1.5")), "must return a number.*text"),
    (lambda: build_chain([BallJoint(), RigidBody(mass=True, inertia=[1, 1, 1],
                                                  inertia_about="input",
                                                  to_mass_center=[0, 0, 0],
                                                  to_output=[1, 0, 0])]),
     "mass must be a number, got True"),
    (lambda: build_chain([BallJoint(), link(name=5)]), "name must be a string, got 5"),
    (lambda: build_chain([BallJoint(), link(name="ground")]), "the name 'ground' is the ground"),
]


@pytest.mark.parametrize("build, message", BUILD_INPUTS, ids=[m for _, m in BUILD_INPUTS])
def test_bad_elements_are_refused_at_build(build, message):
    with pytest.raises(ValueError, match=message):
        build()


def _ground_nan_after(t0):
    def rotation(t):
        return np.eye(3) * (np.nan if t > t0 else 1.0)
    return dttmm.Ground(motion=dttmm.PrescribedMotion(rotation=rotation))


# (a model whose user function goes wrong after t = 0.02 s, the cause expected); before:
# "the step is too large for the motion" or a raw numpy error mid-run
MID_RUN = [
    (lambda: pendulum(force=lambda t: [np.nan if t > 0.02 else 0.0, 0, 0]),
     r"the force \(N\) of body 'body0' returned \[nan, 0.0, 0.0\] at t = 0.021"),
    (lambda: pendulum(torque=lambda t: [0, 0, np.inf if t > 0.02 else 0.0]),
     r"the torque \(N m\) of body 'body0' returned .* at t = 0.021"),
    (lambda: pendulum(force=lambda t: [[0, 0, 1]] if t > 0.02 else [0, 0, 1]),
     r"the force \(N\) of body 'body0' failed at t = 0.021"),
    (lambda: pendulum(force=lambda t: 1 / 0 if t > 0.02 else [0, 0, 0]),
     r"failed at t = 0.021 s \(ZeroDivisionError"),
    (lambda: revolute(JointForce(lambda t, q, qd: np.nan if t > 0.02 else 0.0)),
     r"the drive of 'shoulder' \(coordinate 1\) returned nan at t = 0.021"),
    (lambda: build_chain([BallJoint(), link()], ground=_ground_nan_after(0.02)),
     r"the ground's motion is not finite at t = 0.021"),
]


@pytest.mark.parametrize("build, cause", MID_RUN, ids=[c[:30] for _, c in MID_RUN])
def test_a_user_function_gone_wrong_mid_run_is_named(build, cause):
    with pytest.raises(dttmm.DivergenceError, match=cause) as err:
        simulate(build(), 0.05, 1e-3)
    assert err.value.step == 21 and err.value.partial is not None


def test_checkpoints_carry_their_model_and_content():
    """Another model of the same shapes, an edited or truncated file, an adaptive run's
    missing checkpoint: each refused (before: resumed, loaded, or restarted at t = 0)."""
    first = simulate(rigid_chain(2), 0.02, 1e-3)
    heavier = dataclasses.replace(rigid_chain(2),
                                  body_params=np.array(rigid_chain(2).body_params) * 2.0)
    with pytest.raises(ValueError, match="another model"):
        simulate(heavier, 0.04, 1e-3, resume=first.checkpoint)
    adaptive = simulate(rigid_chain(2), 0.02, rtol=1e-4)
    assert not adaptive.checkpoint
    with pytest.raises(ValueError, match="adaptive run .* keeps no checkpoint"):
        simulate(rigid_chain(2), 0.04, 1e-3, resume=adaptive.checkpoint)
    with pytest.raises(ValueError, match="Richardson"):
        rich = simulate(rigid_chain(2), 0.02, 1e-3, richardson=True)
        simulate(rigid_chain(2), 0.04, 1e-3, resume=rich.checkpoint)
    with pytest.raises(ValueError):
        first.checkpoint.arrays[0][...] = 0.0


def test_checkpoint_files_that_were_changed_are_refused(tmp_path):
    first = simulate(rigid_chain(2), 0.02, 1e-3)
    path = tmp_path / "c.npz"
    first.checkpoint.save(path)
    data = dict(np.load(path))
    for change in ("step", "array"):
        edited = dict(data)
        if change == "step":
            edited["step"] = np.array(5)
        else:
            edited["a0"] = data["a0"] * 1.0001
        np.savez(tmp_path / f"{change}.npz", **edited)
        with pytest.raises(ValueError, match="changed after Checkpoint.save"):
            dttmm.Checkpoint.load(tmp_path / f"{change}.npz")
    (tmp_path / "cut.npz").write_bytes(path.read_bytes()[:200])
    with pytest.raises(ValueError, match="not a checkpoint written by Checkpoint.save"):
        dttmm.Checkpoint.load(tmp_path / "cut.npz")
    np.savez(tmp_path / "foreign.npz", x=np.zeros(3))
    with pytest.raises(ValueError, match="not a checkpoint"):
        dttmm.Checkpoint.load(tmp_path / "foreign.npz")
    assert dttmm.Checkpoint.load(path).step == 20


def test_streams_keep_other_files_and_their_model(tmp_path):
    """stream=DIR refuses a directory with files that are not a stream's (before: deleted
    every *.bin in it); load_stream refuses another model (before: positions off by 2 m)
    and a damaged stream with a message (before: JSONDecodeError, mmap errors)."""
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "data.bin").write_bytes(b"keep me")
    with pytest.raises(ValueError, match="not a stream's .data.bin"):
        simulate(rigid_chain(2), 0.02, 1e-3, stream=mine)
    assert (mine / "data.bin").read_bytes() == b"keep me"
    run = tmp_path / "run"
    simulate(rigid_chain(2), 0.02, 1e-3, stream=run)
    simulate(rigid_chain(2), 0.02, 1e-3, stream=run)             # a stream replaces a stream
    assert len(dttmm.load_stream(rigid_chain(2), run).t) == 21
    with pytest.raises(ValueError, match="another model"):
        dttmm.load_stream(rigid_chain(2, gravity=(0.0, -4.0, 0.0)), run)
    (run / "index.json").write_text("{not json")
    with pytest.raises(ValueError, match="load_stream: the stream in .* damaged"):
        dttmm.load_stream(rigid_chain(2), run)


def test_result_arrays_are_read_only():
    """Before: writable, and positions and the CSV are derived lazily from them."""
    res = simulate(rigid_chain(2), 0.02, 1e-3)
    for name in ("t", "rotation", "angular_velocity"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(res, name)[...] = 0.0
    with pytest.raises(ValueError, match="read-only"):
        res.position_output[...] = 0.0


def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "dttmm", *args], capture_output=True,
                          text=True, cwd=cwd)


def test_cli_file_mistakes_exit_2_before_the_run(tmp_path):
    """Before: a traceback after the whole run, exit 1 (the status of a diverged run)."""
    assert _cli("example", "rigid_chain", cwd=tmp_path).returncode == 0
    for args, words in ((["--out", "missing/run.npz"], "does not exist"),
                        (["--animate", "a.txt"], "write a .gif or an .mp4"),
                        (["--resume", "nothing.npz"], "no such file")):
        run = _cli("run", "rigid_chain.toml", "--t-end", "1000", *args, cwd=tmp_path)
        assert run.returncode == 2 and words in run.stderr and "Traceback" not in run.stderr
        assert "ran " not in run.stdout               # refused before the run
    (tmp_path / "rigid_chain.toml").write_text("# edited\n" + (
        tmp_path / "rigid_chain.toml").read_text())
    again = _cli("example", "rigid_chain", cwd=tmp_path)
    assert again.returncode == 2 and "--force" in again.stderr
    assert (tmp_path / "rigid_chain.toml").read_text().startswith("# edited")
    assert _cli("example", "rigid_chain", "--force", cwd=tmp_path).returncode == 0


def test_static_equilibrium_counts_are_integers():
    with pytest.raises(ValueError, match="max_iterations must be an integer"):
        dttmm.static_equilibrium(pendulum(), max_iterations=np.nan)


def test_result_files_that_are_not_results_are_named(tmp_path):
    """Before: BadZipFile, KeyError, or numpy's allow_pickle hint."""
    res = simulate(rigid_chain(2), 0.02, 1e-3)
    res.save_npz(tmp_path / "r.npz")
    assert dttmm.Result.load_npz(tmp_path / "r.npz").n_steps == 20
    (tmp_path / "cut.npz").write_bytes((tmp_path / "r.npz").read_bytes()[:300])
    np.savez(tmp_path / "foreign.npz", x=np.zeros(3))
    np.savez(tmp_path / "pickled.npz", t=np.array([object()], dtype=object))
    for name, words in (("cut", "not a result"), ("foreign", "no method, t"),
                        ("pickled", "not a result"), ("missing", "no such file")):
        with pytest.raises(ValueError, match=f"Result.load_npz.*{name}.*{words}"):
            dttmm.Result.load_npz(tmp_path / f"{name}.npz")


def test_a_constant_load_is_three_numbers():
    """A load given as 3 numbers is the constant function: the same run as the function of
    time, on a rigid body and on a beam's end (and the model pickles, for a sweep's workers)."""
    import pickle
    from dttmm import EulerBernoulliBeam, FixedHinge
    given = pendulum(force=[0.0, 0.0, 2.0], torque=(0.1, 0.0, 0.0))
    called = pendulum(force=lambda t: [0.0, 0.0, 2.0], torque=lambda t: [0.1, 0.0, 0.0])
    a, b = simulate(given, 0.05, 1e-3), simulate(called, 0.05, 1e-3)
    assert np.array_equal(a.position_output, b.position_output)
    free = simulate(pendulum(), 0.05, 1e-3)
    assert np.abs(a.position_output[-1] - free.position_output[-1]).max() > 1e-4   # (it acts)

    def beam(**load):
        return build_chain([FixedHinge(), EulerBernoulliBeam(
            length=1.0, mass_per_length=1.0, bending_stiffness=50.0,
            polar_inertia_per_length=1e-3, modes_per_plane=2, **load)])
    a = simulate(beam(end_force=np.array([0.0, -1.0, 0.0])), 0.05, 1e-3)
    b = simulate(beam(end_force=lambda t: [0.0, -1.0, 0.0]), 0.05, 1e-3)
    assert np.array_equal(a.position_output, b.position_output)
    assert a.position_output[-1, 0, 1] < -1e-4                     # (it bends down)
    restored = pickle.loads(pickle.dumps(given))
    assert np.array_equal(simulate(restored, 0.05, 1e-3).position_output,
                          simulate(given, 0.05, 1e-3).position_output)


def _beam(**kw):
    return dttmm.EulerBernoulliBeam(**{**dict(length=1.0, bending_stiffness=100.0,
                                              mass_per_length=1.0,
                                              polar_inertia_per_length=1e-5), **kw})


# issue 65, item 10: (a model builder, the message expected at build); before, in the comment
ISSUE_65_ELEMENTS = [
    # ran, and returned an energy 1e260 times the kinetic
    (lambda: build_chain([dttmm.FixedHinge(), _beam(bending_stiffness=1e300)]),
     r"EulerBernoulliBeam \(body 0\): bending_stiffness gives the element an own frequency"),
    (lambda: build_chain([dttmm.FixedHinge(), dttmm.StrainRod(
        length=1.0, mass_per_length=1.0, bending_stiffness=1e300,
        polar_inertia_per_length=1e-5)]),
     r"StrainRod \(body 0\): bending_stiffness gives the element an own frequency"),
    # numpy's "cannot convert float NaN to integer" and an OverflowError
    (lambda: build_chain([dttmm.FixedHinge(), _beam(modes_per_plane=float("nan"))]),
     r"EulerBernoulliBeam \(body 0\): modes_per_plane must be an integer >= 1"),
    (lambda: build_chain([dttmm.FixedHinge(), _beam(modes_per_plane=float("inf"))]),
     r"EulerBernoulliBeam \(body 0\): modes_per_plane must be an integer >= 1"),
    # blamed on the step size after the first step
    (lambda: build_chain([BallJoint(), link()], gravity=[0, -1e300, 0]),
     r"System: gravity .* is beyond any physical system's"),
    # an IndexError
    (lambda: build_chain([BallJoint(), link()], ground=dttmm.Ground(
        motion=dttmm.PrescribedMotion(rotation=lambda t: np.eye(2)))),
     r"PrescribedMotion: rotation\(0\) must be"),
]


@pytest.mark.parametrize("build, message", ISSUE_65_ELEMENTS,
                         ids=["EI 1e300", "rod EI 1e300", "modes nan", "modes inf",
                              "gravity 1e300", "ground rotation 2x2"])
def test_issue_65_inputs_are_refused_at_build(build, message):
    with pytest.raises(ValueError, match=message):
        build()


def test_an_axis_of_any_finite_length_is_a_direction():
    """A revolute axis of 1e300 (its square overflowed: 'the transfer at hinge ... is
    singular') turns the link as the unit axis does."""
    def swing(axis):
        model = build_chain([RevoluteJoint(axis=axis), link()], gravity=[0, -9.81, 0])
        return simulate(model, 0.05, 1e-3).position_output[-1]
    assert np.array_equal(swing([0, 0, 1e300]), swing([0, 0, 1.0]))


def test_a_binary_scene_file_is_named(tmp_path):
    """A binary file given as a scene (a UnicodeDecodeError before)."""
    from dttmm.interfaces.scene import SceneError, load_scene
    path = tmp_path / "scene.toml"
    path.write_bytes(bytes(range(256)))
    with pytest.raises(SceneError, match="not a text file"):
        load_scene(path)
