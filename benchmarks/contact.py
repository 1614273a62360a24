"""What contact costs a step (issue 67): a chain of capsules lying on the ground, held above it,
and without shapes.

    python benchmarks/contact.py [--quick] [--json FILE] [--links N]

The chain of dttmm.model.chains.capsule_chain (N links on ball joints, the first on a free joint,
each a capsule of 0.02 m radius, 2N contact spheres) in three variants, timed in turn in one
process, A B C A B C ...:
  touching   lying on the plane (started at its radius: every sphere pushes, every step),
  apart      the same shapes with the plane 10 m below (the contact spheres tested every
             iteration, never touching: the search alone),
  no shapes  the same chain without shapes or plane.
Each a run of fixed steps at dt = 1e-4 s after a warm-up; the cost of a step is the difference
of a long and a short run over the steps between (no setup), the best of --pairs rounds.
Printed: us per step and the ratios to "no shapes", and the Newton iterations each took (the
contacts' evaluation is per sphere and linear in N; a touching contact also iterates the step).
--quick: N = 5, fewer steps (the CI's smoke run).  Not a test: nothing is asserted.
"""
import argparse
import json
import os
import time

import dttmm
from dttmm.model.chains import capsule_chain


def step_cost(model, steps, dt=1e-4):
    """(seconds per step: (long run - short run) / (steps between), Newton iterations used)."""
    short = max(2, steps // 10)
    t0 = time.perf_counter()
    dttmm.simulate(model, short * dt, dt, record_every=short)
    t1 = time.perf_counter()
    result = dttmm.simulate(model, steps * dt, dt, record_every=steps)
    t2 = time.perf_counter()
    return ((t2 - t1) - (t1 - t0)) / (steps - short), result.info["newton_iterations_used"]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--links", type=int, default=20)
    parser.add_argument("--pairs", type=int, default=3)
    parser.add_argument("--json")
    args = parser.parse_args(argv)
    n = 5 if args.quick else args.links
    steps = 200 if args.quick else 4000
    variants = {"touching": capsule_chain(n, height=0.02),
                "apart": capsule_chain(n, height=0.02, plane_at=-10.0),
                "no shapes": capsule_chain(n, height=0.02, shapes=False)}
    for model in variants.values():
        dttmm.simulate(model, 2e-3, 1e-4)           # compile or load, warm up
    best = {name: (float("inf"), 0) for name in variants}
    for _ in range(1 if args.quick else args.pairs):
        for name, model in variants.items():
            cost = step_cost(model, steps)
            best[name] = min(best[name], cost)
    base = best["no shapes"][0]
    cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo")
                if line.startswith("cpu family")), "?") if os.path.exists("/proc/cpuinfo") else "?"
    print(f"capsule chain of {n} links ({2 * n} contact spheres), dt = 1e-4 s, {steps} steps, "
          f"CPU family {cpu}")
    for name, (cost, iterations) in best.items():
        print(f"  {name:<10} {cost * 1e6:9.2f} us/step  x{cost / base:5.2f}  "
              f"(Newton iterations up to {iterations + 1} a step)")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"links": n, "us_per_step": {k: v[0] * 1e6 for k, v in best.items()},
                       "iterations": {k: v[1] for k, v in best.items()}}, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
