"""What a user waits for numba (issue 30: each scene under 60 s cold; issue 66: one core).

Two measurements, each process started fresh and run one after another (numba compiles on one
core), the numba cache in a temporary directory (NUMBA_CACHE_DIR), so the package's own cache
is neither read nor written:

* scenes (default): every shipped scene from an empty cache of its own, for a few steps
  (`dttmm run SCENE --t-end T`): the cold start (import, compile, run), then the warm start
  with the cache it filled.
* --session: a new user's session (issue 66), the kinds of model below one after another from
  ONE empty cache, as a user meets them: each process's whole first call, import included,
  and the compiled families it added to the cache (numba's index files: the first use of a
  family compiles it; a later model of another kind should compile nothing).  Then
  `dttmm compile`'s total from an empty cache.

    python benchmarks/compile.py [--quick] [--session] [--json FILE] [SCENE ...]

--quick: the rigid chain and the arm only (scenes), or the first two models (--session).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from importlib import resources
from pathlib import Path

# the session: (name, Python code run in a fresh process)
SESSION = [
    ("arm", "import dttmm; from dttmm.model.chains import arm\n"
            "dttmm.simulate(arm(), 0.01, 1e-3)"),
    ("slider-crank", "import dttmm; from dttmm.model.mechanisms import slider_crank\n"
                     "dttmm.simulate(slider_crank(), 0.01, 1e-3)"),
    ("N-four-bar", "import dttmm; from dttmm.model.mechanisms import n_four_bar\n"
                   "dttmm.simulate(n_four_bar(4), 0.01, 1e-3)"),
    ("cantilever + statics",
     "import dttmm\n"
     "beam = dttmm.EulerBernoulliBeam(length=1.0, bending_stiffness=210e9 * 1e-8 / 12,\n"
     "    density=7850.0, area=1e-4, polar_inertia_per_length=7850 * 2e-8 / 12)\n"
     "tip = dttmm.RigidBody(mass=0.2, inertia=[1e-6] * 3, inertia_about='mass_center')\n"
     "model = dttmm.build_chain([dttmm.FixedHinge(), beam, dttmm.FixedHinge(), tip],\n"
     "                          gravity=[0.0, -9.81, 0.0])\n"
     "dttmm.static_equilibrium(model); dttmm.simulate(model, 0.01, 1e-4)"),
    ("rod in a loop",
     "import dttmm; from dttmm.model.mechanisms import slider_crank\n"
     "rod = dttmm.StrainRod(length=0.3, bending_stiffness=50.0, mass_per_length=1.0,\n"
     "    polar_inertia_per_length=1e-4, name='rod')\n"
     "s = dttmm.System(gravity=[0, -9.81, 0])\n"
     "s.add(dttmm.RigidBody(mass=0.5, inertia=[1e-4, 2e-3, 2e-3], inertia_about='mass_center',\n"
     "      to_mass_center=[0.1, 0, 0], to_output=[0.2, 0, 0], name='crank'),\n"
     "      dttmm.RevoluteJoint(axis=[0, 0, 1.0], name='O'))\n"
     "s.add(rod, dttmm.RevoluteJoint(axis=[0, 0, 1.0], name='A'), parent='crank')\n"
     "s.close(dttmm.PrismaticJoint(axis=[1.0, 0, 0], name='slide'), 'rod', 'ground')\n"
     "dttmm.simulate(dttmm.assemble(s.build()), 0.01, 1e-3)"),
    ("elastic-hinge chain",
     "import dttmm; from dttmm.model.chains import unit_link\n"
     "parts = []\n"
     "for i in range(4):\n"
     "    parts += [dttmm.ElasticHinge(1e5, 1e3), unit_link(name=f'l{i}')]\n"
     "dttmm.simulate(dttmm.build_chain(parts, gravity=[0, -9.81, 0]), 0.01, 1e-3)"),
    ("fixed-hinge tree",
     "import dttmm; from dttmm.model.chains import unit_link\n"
     "s = dttmm.System(gravity=[0, -9.81, 0])\n"
     "s.add(unit_link(name='a'), dttmm.BallJoint(name='j'))\n"
     "s.add(unit_link(name='b'), dttmm.FixedHinge(), parent='a')\n"
     "s.add(unit_link(name='c'), dttmm.FixedHinge(rotation=[[0, -1, 0], [1, 0, 0], [0, 0, 1]]),\n"
     "      parent='a')\n"
     "dttmm.simulate(s.build(), 0.01, 1e-3)"),
]


def scenes():
    folder = resources.files("dttmm.interfaces") / "scenes"
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def timed(command, cache):
    """(wall time, None) of a process, or (None, its last line of error)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    t0 = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        return None, done.stderr.strip().splitlines()[-1:]
    return wall, None


def timed_scene(scene, cache, t_end):
    path = str(resources.files("dttmm.interfaces") / "scenes" / f"{scene}.toml")
    return timed([sys.executable, "-m", "dttmm", "run", path, "--t-end", str(t_end),
                  "--no-progress", "--no-energy-balance"], cache)


def cached_functions(cache):
    """The compiled functions in numba's cache (one index file each)."""
    return {p.name for p in Path(cache).rglob("*.nbi")}


def session(models):
    fig = {}
    with tempfile.TemporaryDirectory(prefix="dttmm-session-") as cache:
        for name, code in models:
            before = cached_functions(cache)
            wall, error = timed([sys.executable, "-c", code], cache)
            added = cached_functions(cache) - before
            names = sorted(a.split("-")[0].rsplit(".", 1)[-1] for a in added)
            fig[name] = {"first_call_s": wall, "functions_compiled": len(added),
                         "names": names, "error": error}
            print(f"{name:24s} {wall if wall is None else round(wall, 1)} s, "
                  f"{len(added)} functions compiled" + (f" ({error})" if error else "")
                  + (f": {', '.join(names)}" if 0 < len(names) <= 8 else ""), flush=True)
    with tempfile.TemporaryDirectory(prefix="dttmm-compile-") as cache:
        wall, error = timed([sys.executable, "-m", "dttmm", "compile", "--no-progress"], cache)
        fig["dttmm compile"] = {"total_s": wall, "error": error}
        print(f"{'dttmm compile':24s} {wall if wall is None else round(wall, 1)} s"
              + (f" ({error})" if error else ""), flush=True)
    return fig


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scenes", nargs="*", help="scene names (default: every shipped scene)")
    ap.add_argument("--quick", action="store_true", help="fewer scenes or models")
    ap.add_argument("--session", action="store_true", help="the new user's session (issue 66)")
    ap.add_argument("--json", help="write the figures to FILE")
    ap.add_argument("--t-end", type=float, default=0.002, help="seconds simulated (default "
                    "0.002: a few steps)")
    args = ap.parse_args(argv)
    if args.session:
        fig = session(SESSION[:2] if args.quick else SESSION)
    else:
        fig = {}
        names = args.scenes or (["rigid_chain", "arm"] if args.quick else scenes())
        for name in names:
            with tempfile.TemporaryDirectory(prefix="dttmm-cold-") as cache:
                cold, error = timed_scene(name, cache, args.t_end)
                warm, _ = timed_scene(name, cache, args.t_end) if error is None else (None, None)
            fig[name] = {"cold_s": cold, "warm_s": warm, "error": error}
            print(f"{name:24s} cold {cold if cold is None else round(cold, 1)} s, warm "
                  f"{warm if warm is None else round(warm, 1)} s"
                  + (f" ({error})" if error else ""), flush=True)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(fig, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
