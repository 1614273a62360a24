"""Per-step cost of two checkouts of dttmm, A against B, in alternating processes.

    python benchmarks/step_ab.py A_DIR B_DIR [--pairs 9] [--json FILE]

For each system (the three-pendulum, rigid chains of 3, 100 and 1000 links) the two checkouts
are timed in turn, A B A B ..., each time in a fresh process that imports that checkout's
dttmm (warm numba cache, JIT warm-up run first).  A process measures the cost of one step as
the difference of a long and a short run over the steps between (no setup, no recording), the
median of 3.  The figure per system is the median over the pairs of the ratio A/B, so that the
machine's drift between pairs does not enter it.  Not a test: nothing is asserted.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

SYSTEMS = {          # name: (constructor expression, steps of the long run)
    "three_pendulum": ("three_pendulum()", 4000),
    "rigid_chain_3": ("rigid_chain(3)", 20000),
    "rigid_chain_100": ("rigid_chain(100)", 1000),
    "rigid_chain_1000": ("rigid_chain(1000)", 100),
}

_CHILD = r"""
import statistics, sys
from dttmm import simulate
from dttmm.chains import rigid_chain, three_pendulum
model = {expr}
steps, dt = {steps}, 1e-4
simulate(model, 5 * dt, dt)
short = max(1, steps // 5)
costs = []
for _ in range(3):
    a = simulate(model, steps * dt, dt, record_every=steps)
    b = simulate(model, short * dt, dt, record_every=short)
    costs.append((a.wall_time - b.wall_time) / (a.n_steps - b.n_steps))
print(1e6 * statistics.median(costs))
"""


def us_per_step(checkout, system):
    expr, steps = SYSTEMS[system]
    env = dict(os.environ, PYTHONPATH=os.path.abspath(checkout))
    out = subprocess.run([sys.executable, "-c", _CHILD.format(expr=expr, steps=steps)],
                         env=env, capture_output=True, text=True, check=True,
                         cwd=os.path.abspath(checkout))
    return float(out.stdout.strip().splitlines()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--pairs", type=int, default=9)
    ap.add_argument("--systems", nargs="+", default=list(SYSTEMS))
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    out = {}
    for system in args.systems:
        us_per_step(args.a, system), us_per_step(args.b, system)     # fill both numba caches
        a_us, b_us, ratios = [], [], []
        for _ in range(args.pairs):
            a_us.append(us_per_step(args.a, system))
            b_us.append(us_per_step(args.b, system))
            ratios.append(a_us[-1] / b_us[-1])
        out[system] = dict(a_us_per_step=statistics.median(a_us),
                           b_us_per_step=statistics.median(b_us),
                           ratio_a_over_b=statistics.median(ratios),
                           ratio_min=min(ratios), ratio_max=max(ratios), pairs=args.pairs)
        print(f"{system}: A {out[system]['a_us_per_step']:.3f} us, "
              f"B {out[system]['b_us_per_step']:.3f} us, A/B {out[system]['ratio_a_over_b']:.3f} "
              f"(min {min(ratios):.3f}, max {max(ratios):.3f}, {args.pairs} pairs)", flush=True)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
