"""The command line (docs/scenes.md, "Command line"):

    dttmm run SCENE.toml [--t-end S] [--dt S] [--method M] [--scheme S] [--record-dt S]
                         [--out FILE.npz] [--csv FILE] [--plots DIR] [--animate FILE.gif]
                         [--static-start] [--no-energy-balance]
    dttmm info SCENE.toml          bodies, joints, degrees of freedom, beams' modes, a dt
    dttmm example [NAME] [--force] the shipped scenes; NAME: write NAME.toml here
    dttmm compile [--jobs N]       compile every kernel ahead (CI, containers, a shared install)

Also `python -m dttmm ...`.  Exit status 0, or 2 with a one-line message for a bad scene or
argument, 1 for a run that stopped (DivergenceError).
"""
import argparse
import shutil
import sys
import time
from importlib import resources
from pathlib import Path

import numpy as np

from .describe import describe_counts, suggested_dt
from ..solving.methods import SCHEMES, SWEEPS
from .scene import SceneError, load_scene


def main(argv=None):
    ap = argparse.ArgumentParser(prog="dttmm", description="DT-TMM multibody dynamics: run "
                                 "scene files, describe them, get the shipped examples.")
    sub = ap.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="simulate a scene file")
    run.add_argument("scene", help="scene file (TOML)")
    run.add_argument("--t-end", type=float, help="end time, s (default: the scene's [run])")
    run.add_argument("--dt", type=float, help="step, s (default: the scene's, else info's)")
    run.add_argument("--rtol", type=float,
                     help="adaptive steps to this tolerance (rad, m); --dt is then the first")
    run.add_argument("--max-energy-error", type=float,
                     help="stop when the energy balance breaks by more than this fraction of "
                          "the largest kinetic energy")
    run.add_argument("--method", choices=tuple(SWEEPS))
    run.add_argument("--scheme", choices=tuple(SCHEMES),
                     help="the time-stepping scheme (dttmm/solving/methods.py): " + "; ".join(
                         f"{name}: {scheme.summary}" for name, scheme in SCHEMES.items()))
    run.add_argument("--record-dt", type=float, help="record every RECORD_DT s")
    run.add_argument("--out", help="write the Result to FILE.npz (Result.load_npz reads it)")
    run.add_argument("--csv", help="write t, the output points and the energies to FILE.csv")
    run.add_argument("--plots", help="draw the run's figures into DIR")
    run.add_argument("--animate", help="write a 3D animation (FILE.gif or FILE.mp4)")
    run.add_argument("--view", default="auto",
                     help="the animation's view: auto (default: a planar motion square on), "
                          "oblique, xy, xz, yz, or ELEVATION,AZIMUTH in degrees")
    run.add_argument("--checkpoint", help="write the final state to FILE.npz (to resume)")
    run.add_argument("--resume", help="continue from a checkpoint file")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    run.add_argument("--no-energy-balance", action="store_true",
                     help="a driven or loaded scene: do not keep the energy balance (it "
                          "derives every step's velocities: 1.2-3.5x the run's time)")
    run.add_argument("--static-start", action="store_true",
                     help="start at rest in the static equilibrium (dttmm.static_equilibrium)")
    info = sub.add_parser("info", help="describe a scene file")
    info.add_argument("scene")
    example = sub.add_parser("example", help="list the shipped scenes, or write one here")
    example.add_argument("name", nargs="?")
    example.add_argument("--to", default=".", help="directory to write NAME.toml into")
    example.add_argument("--force", action="store_true",
                         help="overwrite NAME.toml if it exists")
    compile_ = sub.add_parser("compile", help="compile every kernel now (once per install), "
                              "so that no run waits for numba")
    compile_.add_argument("--jobs", type=int, help="processes at once (default: the cores)")
    compile_.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = ap.parse_args(argv)
    try:
        return {"run": _run, "info": _info, "example": _example,
                "compile": _compile}[args.command](args)
    except SceneError as err:
        print(f"dttmm: {err}", file=sys.stderr)
        return 2


def _compile(args):
    from .precompile import cache_location, compile_all
    t0 = time.perf_counter()
    try:
        took = compile_all(args.jobs, progress=not args.no_progress)
    except RuntimeError as err:
        print(f"dttmm: {err}", file=sys.stderr)
        return 1
    print(f"compiled {len(took)} families of kernels in {time.perf_counter() - t0:.0f} s "
          f"({', '.join(f'{name} {s:.0f} s' for name, s in took.items())})")
    print(f"cache: {cache_location()}")
    return 0


def _run(args):
    from ..results.recording import Checkpoint
    from ..solving.run_checks import DivergenceError
    from ..solving.solver import simulate
    scene = load_scene(args.scene)
    options = dict(scene.run)
    for key, value in (("t_end", args.t_end), ("dt", args.dt), ("method", args.method),
                       ("scheme", args.scheme), ("record_dt", args.record_dt),
                       ("rtol", args.rtol), ("max_energy_error", args.max_energy_error)):
        if value is not None:
            options[key] = value
    if "t_end" not in options:
        print(f"dttmm: {args.scene}: no end time: give --t-end or t_end in [run]",
              file=sys.stderr)
        return 2
    if "dt" not in options:
        options["dt"] = suggested_dt(scene.model)
    if args.record_dt is not None or "rtol" in options:
        options.pop("record_every", None)
    t_end, dt = options.pop("t_end"), options.pop("dt")
    problem = _output_problem(args)
    if problem:
        print(f"dttmm: {problem}", file=sys.stderr)
        return 2
    try:
        resume = Checkpoint.load(args.resume) if args.resume else None
    except ValueError as err:
        print(f"dttmm: --resume: {err}", file=sys.stderr)
        return 2
    model = scene.model
    if args.static_start:
        from ..solving.statics import StaticEquilibriumError, static_equilibrium
        try:
            eq = static_equilibrium(model)
        except (StaticEquilibriumError, ValueError) as err:
            print(f"dttmm: {err}", file=sys.stderr)
            return 2
        model = eq.model
        freqs = eq.frequencies
        moving = [f for f in freqs if f > 0.0]
        print(f"static equilibrium in {eq.iterations} iterations ("
              f"{'stable' if eq.stable else 'UNSTABLE'}; {int(np.sum(freqs == 0.0))} neutral "
              f"directions; lowest frequencies (Hz): "
              f"{', '.join(f'{f:.4g}' for f in moving[:3])})")
    from ..solving.energy_balance import does_work
    worked = does_work(model)
    if (worked and "rtol" not in options and "max_energy_error" not in options
            and not args.no_energy_balance and not len(model.contacts)):
        options["max_energy_error"] = 1e300     # kept, to show the balance, never to stop
    steps = (f"adaptive steps, rtol = {options['rtol']:g}" if "rtol" in options
             else f"dt = {dt:g} s")
    print(f"{scene.path}: {describe_counts(model)}; t_end = {t_end:g} s, {steps}")
    try:
        res = simulate(model, t_end, dt, progress=False if args.no_progress else None,
                       resume=resume, **options)
    except DivergenceError as err:
        print(f"dttmm: {err}", file=sys.stderr)
        if err.partial is not None and args.out:
            err.partial.save_npz(args.out)
            print(f"wrote the samples before it to {args.out}", file=sys.stderr)
        return 1
    except ValueError as err:
        print(f"dttmm: {err}", file=sys.stderr)
        return 2
    energy = res.total_energy
    scale = max(float(np.abs(res.kinetic).max()), 1e-300)
    if "rtol" in options:
        print(f"adaptive: steps of {res.info['dt_min']:.3g} to {res.info['dt_max']:.3g} s, "
              f"{res.info['steps_rejected']} steps rejected")
    print(f"ran {res.n_steps} steps in {res.wall_time:.3g} s (loop {res.info['loop']}, "
          f"{res.info['mode']}); {len(res.t)} samples; largest step error estimate "
          f"{res.info.get('step_error_max', 0.0):.2g}")
    change = float(energy[-1] - energy[0])
    if res.energy_work is not None:
        gap = change - float(res.energy_work[-1])
        print(f"energy: largest kinetic {scale:.4g} J; the total changed by {change:.4g} J, "
              f"the work done on the system (loads, drives, dampers, ground) is "
              f"{float(res.energy_work[-1]):.4g} J: energy balance E - E(0) - W = {gap:.3g} J "
              f"({abs(gap) / scale:.2g} of the largest kinetic energy; at worst "
              f"{res.info['energy_balance_error']:.2g})")
    elif len(model.contacts):
        print(f"energy: largest kinetic {scale:.4g} J; the total changed by {change:.4g} J, "
              f"including what the contacts dissipate and store (not tracked: "
              f"docs/contact.md)")
    elif worked:
        print(f"energy: largest kinetic {scale:.4g} J; the total changed by {change:.4g} J, "
              f"including the work done on the system (not tracked: adaptive steps or "
              f"--no-energy-balance)")
    else:
        print(f"energy: largest kinetic {scale:.4g} J; the total (nothing works on the "
              f"system) changed by {change:.3g} J ({abs(change) / scale:.2g} of the largest "
              f"kinetic energy)")
    if args.out:
        res.save_npz(args.out)
        print(f"wrote {args.out}")
    if args.csv:
        res.save_csv(args.csv)
        print(f"wrote {args.csv}")
    if args.checkpoint and not res.checkpoint:
        print("dttmm: no checkpoint written: an adaptive run has no step grid to resume on",
              file=sys.stderr)
    elif args.checkpoint:
        res.checkpoint.save(args.checkpoint)
        print(f"wrote {args.checkpoint} (continue with --resume {args.checkpoint})")
    if args.plots:
        from ..results.plots import run_figures
        for path in run_figures(res, model, args.plots, title=scene.name):
            print(f"wrote {path}")
    if args.animate:
        from ..results.plots import animate
        animate(res, model, args.animate, title=scene.name, view=_view(args.view))
        print(f"wrote {args.animate}")
    return 0


def _output_problem(args):
    """What is wrong with run's file arguments, checked before the run ("" if nothing): an
    output into a directory that does not exist, an animation that is neither .gif nor .mp4,
    a plots directory that is a file, a --resume file that does not exist."""
    for flag, path in (("--out", args.out), ("--csv", args.csv),
                       ("--checkpoint", args.checkpoint), ("--animate", args.animate)):
        if path and not Path(path).resolve().parent.is_dir():
            return f"{flag} {path}: the directory {str(Path(path).parent)!r} does not exist"
        if path and Path(path).is_dir():
            return f"{flag} {path}: is a directory; give a file name"
    if args.animate and Path(args.animate).suffix not in (".gif", ".mp4"):
        return f"--animate {args.animate}: write a .gif or an .mp4"
    if _view(args.view) is None:
        return (f"--view {args.view}: give auto, oblique, xy, xz, yz or ELEVATION,AZIMUTH in "
                f"degrees")
    if args.plots and Path(args.plots).exists() and not Path(args.plots).is_dir():
        return f"--plots {args.plots}: is a file; give a directory"
    if args.resume and not Path(args.resume).is_file():
        return f"--resume {args.resume}: no such file"
    return ""


def _view(text):
    """--view's value as animate takes it (a name, or (elevation, azimuth)); None if bad."""
    from ..results.plots import VIEWS
    if text in VIEWS:
        return text
    try:
        elevation, azimuth = (float(v) for v in text.split(","))
    except ValueError:
        return None
    return (elevation, azimuth) if np.isfinite([elevation, azimuth]).all() else None


def _info(args):
    scene = load_scene(args.scene)
    print(f"{scene.name} ({scene.path}): {scene.model.describe()}")
    if scene.run:
        print(f"[run]: {', '.join(f'{k} = {v}' for k, v in scene.run.items())}")
    return 0


def shipped_scenes():
    """name -> path of the scenes shipped in dttmm/interfaces/scenes."""
    folder = resources.files("dttmm.interfaces") / "scenes"
    return {Path(p.name).stem: Path(str(p)) for p in folder.iterdir() if p.name.endswith(".toml")}


def _example(args):
    scenes = shipped_scenes()
    if args.name is None:
        print("shipped scenes (dttmm example NAME writes NAME.toml here; dttmm run NAME.toml):")
        for name, path in sorted(scenes.items()):
            first = path.read_text().splitlines()[0].lstrip("# ").strip()
            print(f"  {name:<18} {first}")
        return 0
    if args.name not in scenes:
        print(f"dttmm: no shipped scene '{args.name}' (there are: {', '.join(sorted(scenes))})",
              file=sys.stderr)
        return 2
    target = Path(args.to) / f"{args.name}.toml"
    if not Path(args.to).is_dir():
        print(f"dttmm: --to {args.to}: no such directory", file=sys.stderr)
        return 2
    if target.exists() and not args.force:
        print(f"dttmm: {target} exists (an edited copy?): not overwritten; pass --force to "
              f"replace it, or --to another directory", file=sys.stderr)
        return 2
    shutil.copyfile(scenes[args.name], target)
    print(f"wrote {target}; run it: dttmm run {target}")
    return 0
