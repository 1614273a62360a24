"""Building and stepping very long chains (issue 30, "a million bodies").

    python benchmarks/build.py [--quick] [--sizes 1000 10000 ...] [--json FILE]

For each size N, in a fresh process (so that its peak memory is its own): N unit rods on
ball joints listed as the user would (distinct but equal objects, each rod named in the loop
that makes them), build_chain's wall time,
then a 10-step run at dt = 1e-3 after a 2-step warm-up (the kernels compiled or loaded), its
cost per body-step, and the process's peak resident memory.  The build's and the step's
exponents are fitted over N.  --quick: N = 1e3 and 1e4 (the CI's smoke run).  Not a test:
nothing is asserted.
"""
import argparse
import json
import resource
import subprocess
import sys
import time

import numpy as np


def one(n):
    """(build s, us per body-step, peak MB) of an N-rod chain, in this process."""
    import dttmm
    rod = dict(mass=1.0, inertia=[1e-4, 1 / 12, 1 / 12], inertia_about="mass_center",
               to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0])
    elements = []
    for k in range(n):
        elements += [dttmm.BallJoint(), dttmm.RigidBody(**rod, name=f"rod{k}")]
    t0 = time.perf_counter()
    model = dttmm.build_chain(elements, gravity=[0, -9.81, 0])
    build = time.perf_counter() - t0
    del elements
    dttmm.simulate(model, 2e-3, 1e-3)
    t0 = time.perf_counter()
    dttmm.simulate(model, 1e-2, 1e-3)
    step = (time.perf_counter() - t0) / (10 * n) * 1e6
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return build, step, peak


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="N = 1e3 and 1e4")
    ap.add_argument("--sizes", type=int, nargs="*", help="the sizes N (default 1e3 .. 1e6)")
    ap.add_argument("--one", type=int, help=argparse.SUPPRESS)    # (the child process)
    ap.add_argument("--json", help="write the figures to this file")
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps(one(args.one)))
        return 0
    sizes = args.sizes or ([1000, 10000] if args.quick else [1000, 10000, 100000, 1000000])
    rows = []
    print(f"{'N':>9} {'build s':>9} {'us/body':>8} {'step us/body':>13} {'peak MB':>8}")
    for n in sizes:
        out = subprocess.run([sys.executable, __file__, "--one", str(n)], capture_output=True,
                             text=True, check=True).stdout.strip().splitlines()[-1]
        build, step, peak = json.loads(out)
        rows.append(dict(n=n, build_s=build, step_us_per_body=step, peak_mb=peak))
        print(f"{n:>9} {build:>9.2f} {1e6 * build / n:>8.1f} {step:>13.3f} {peak:>8.0f}",
              flush=True)
    if len(rows) >= 2:
        n = np.array([r["n"] for r in rows], dtype=float)
        t = np.array([r["build_s"] for r in rows])
        exponent = np.polyfit(np.log(n), np.log(t), 1)[0]
        step = np.array([r["step_us_per_body"] for r in rows]) * n      # (us per step)
        step_exponent = np.polyfit(np.log(n), np.log(step), 1)[0]
        print(f"build time ~ N^{exponent:.2f}, step time ~ N^{step_exponent:.2f}")
        rows.append(dict(build_exponent=exponent, step_exponent=step_exponent))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
