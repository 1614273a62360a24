"""Cold compile time of every shipped scene (issue 30: each under 60 s on 2 cores).

Each scene runs in a fresh process with an empty numba cache of its own (NUMBA_CACHE_DIR in a
temporary directory, so the package's own cache is neither read nor written), for a few steps
(`dttmm run SCENE --t-end T`); the process's wall time is the cold start: import, compile,
run.  The same command again with the cache it filled is the warm start.  Scenes run one after
another (numba compiles on one core).

    python benchmarks/compile.py [--quick] [--json FILE] [SCENE ...]

--quick: the rigid chain and the arm only (the fused loop and the general loop).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from importlib import resources


def scenes():
    folder = resources.files("dttmm") / "scenes"
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def timed_run(scene, cache, t_end):
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    path = str(resources.files("dttmm") / "scenes" / f"{scene}.toml")
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "dttmm", "run", path, "--t-end", str(t_end),
                           "--no-progress", "--no-energy-balance"], env=env,
                          capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        return None, done.stderr.strip().splitlines()[-1:]
    return wall, None


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scenes", nargs="*", help="scene names (default: every shipped scene)")
    ap.add_argument("--quick", action="store_true", help="rigid_chain and arm only")
    ap.add_argument("--json", help="write the figures to FILE")
    ap.add_argument("--t-end", type=float, default=0.002, help="seconds simulated (default "
                    "0.002: a few steps)")
    args = ap.parse_args(argv)
    names = args.scenes or (["rigid_chain", "arm"] if args.quick else scenes())
    fig = {}
    for name in names:
        with tempfile.TemporaryDirectory(prefix="dttmm-cold-") as cache:
            cold, error = timed_run(name, cache, args.t_end)
            warm, _ = timed_run(name, cache, args.t_end) if error is None else (None, None)
        fig[name] = {"cold_s": cold, "warm_s": warm, "error": error}
        print(f"{name:24s} cold {cold if cold is None else round(cold, 1)} s, warm "
              f"{warm if warm is None else round(warm, 1)} s" + (f" ({error})" if error else ""),
              flush=True)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(fig, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
