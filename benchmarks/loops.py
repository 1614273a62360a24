"""Per-step cost of closed loops against the same bodies opened into a tree (issue 29).

    python benchmarks/loops.py [--quick] [--json FILE]

For each mechanism (the IFToMM slider-crank, the Stewart platform with its slides prescribed,
the N-four-bar on its chain and its ground spanning trees, and the chain rebuilt by
System.build(tree="shortest")) the model with its closing joints
and the same model with them removed ("opened": the tree alone, which falls freely) are timed
in turn in one process, A B A B ..., each a run of fixed steps at dt = 1e-3 after a warm-up;
the cost of a step is the difference of a long and a short run over the steps between (no
setup), the best of 3 pairs.  The N-four-bar's cost exponent is fitted over N on each tree
(the ground tree and the shortest from N = 2 to 160, their loops local: O(N); the chain tree,
every loop through the first bar, to N = 40: O(N^2)).  Then the one loop a chain closes in its
sweeps' own tip condition (build_chain(..., tip="ball"), closures.PINNED_TIP_SWEEP) against the
same closure run as a row of the loops' table, on a chain of N rods: what keeping that special
case buys.
--quick: fewer sizes and steps (the CI's smoke run).  Not a test: nothing is asserted.
"""
import argparse
import json
import time
from dataclasses import replace

import numpy as np

import dttmm
from dttmm.model.closures import empty_table
from dttmm.model.mechanisms import n_four_bar, slider_crank, stewart_platform


def opened(model):
    """The model without its closing joints."""
    return replace(model, **empty_table())


def step_cost(model, steps, dt=1e-3):
    """Seconds per step: (long run - short run) / (steps between)."""
    short, long_ = max(2, steps // 10), steps
    t0 = time.perf_counter()
    dttmm.simulate(model, short * dt, dt, record_every=short)
    t1 = time.perf_counter()
    dttmm.simulate(model, long_ * dt, dt, record_every=long_)
    t2 = time.perf_counter()
    return ((t2 - t1) - (t1 - t0)) / (long_ - short)


def measure(model, steps, pairs=3):
    """(with loops, opened) seconds per step, the best of `pairs` interleaved pairs."""
    tree = opened(model)
    for m in (model, tree):
        dttmm.simulate(m, 2e-3, 1e-3)                  # compile or load, warm up
    a, b = [], []
    for _ in range(pairs):
        a.append(step_cost(model, steps))
        b.append(step_cost(tree, steps))
    return min(a), min(b)


def pinned_chain(n):
    """N unit rods on ball joints, the first along x, each turned 0.3 rad about z from the
    last, the tip ball-jointed to the ground where it starts, under gravity along -y."""
    rod = dict(mass=1.0, inertia=[1e-4, 1 / 12, 1 / 12], inertia_about="mass_center",
               to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0])
    elements = []
    for k in range(n):
        c, s = np.cos(-0.3 * k), np.sin(-0.3 * k)
        elements += [dttmm.BallJoint(), dttmm.RigidBody(**rod, rotation=[[c, -s, 0], [s, c, 0],
                                                                          [0, 0, 1]])]
    return dttmm.build_chain(elements, tip="ball", gravity=[0, -9.81, -1.0])


def tip_cost(model, steps, pairs):
    """(tip condition, loop row) seconds per step, interleaved pairs, the best of each."""
    a, b = [], []
    for _ in range(pairs):
        for on, out in ((True, a), (False, b)):
            dttmm.model.closures.PINNED_TIP_SWEEP = on
            dttmm.simulate(model, 2e-3, 1e-3)          # compile or load, warm up
            out.append(step_cost(model, steps))
    dttmm.model.closures.PINNED_TIP_SWEEP = True
    return min(a), min(b)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer sizes and steps")
    ap.add_argument("--json", help="write the figures to this file")
    args = ap.parse_args(argv)
    sizes = (2, 10) if args.quick else (2, 10, 40, 160)
    cases = [("slider-crank", slider_crank(), 400), ("Stewart platform", stewart_platform(), 200)]
    for n in sizes:
        if n <= 40:
            cases.append((f"{n}-four-bar, chain tree", n_four_bar(n), 200 if n < 40 else 40))
        # (at least 100 steps: a run's setup, ~0.2 s at N = 160, must not enter the difference)
        for tree in ("ground", "shortest"):
            cases.append((f"{n}-four-bar, {tree} tree", n_four_bar(n, tree=tree),
                          max(100, 4000 // (5 * n))))
    if args.quick:      # (at least 50 steps: with fewer a run's setup enters the difference)
        cases = [(name, m, max(50, steps // 4)) for name, m, steps in cases]
    rows = []
    print(f"{'model':<28} {'rows':>5} {'loops us/step':>14} {'opened us/step':>15} {'ratio':>7}")
    for name, model, steps in cases:
        with_loops, tree = measure(model, steps, 2 if args.quick else 3)
        rows_count = len(dttmm.model.loop_rows.constraint_rows(model)[0])
        rows.append(dict(model=name, rows=rows_count, loops_us=with_loops * 1e6,
                         opened_us=tree * 1e6, ratio=with_loops / tree))
        print(f"{name:<28} {rows_count:>5} {with_loops * 1e6:>14.0f} {tree * 1e6:>15.0f} "
              f"{with_loops / tree:>7.1f}", flush=True)
    for tree in ("ground", "shortest", "chain"):
        sized = [(int(r["model"].split("-")[0]), r["loops_us"]) for r in rows
                 if r["model"].endswith(f"{tree} tree")]
        if len(sized) < 2:
            continue
        n, us = np.array(sized, dtype=float).T
        exponent = np.polyfit(np.log(n), np.log(us), 1)[0]     # (over every size, N = 2 on)
        ratio = (f", N = 40 / N = 10: {us[n == 40][0] / us[n == 10][0]:.2f}"
                 if 40 in n and 10 in n else "")
        print(f"N-four-bar on its {tree} tree: cost ~ N^{exponent:.2f} "
              f"(N = {', '.join(str(int(x)) for x in n)}){ratio}")
        rows.append(dict(model=f"four-bar exponent ({tree} tree)", exponent=exponent))
    print(f"\n{'pinned-tip chain':<28} {'tip us/step':>14} {'row us/step':>15} {'ratio':>7}")
    for n in (3, 10) if args.quick else (3, 10, 40):
        # (thousands of steps: the fused chain's step costs microseconds, a run's setup more)
        tip, row = tip_cost(pinned_chain(n), 2000 if args.quick else 20000,
                            2 if args.quick else 3)
        rows.append(dict(model=f"{n}-rod pinned chain", tip_us=tip * 1e6, row_us=row * 1e6,
                         ratio=row / tip))
        print(f"{f'{n} rods':<28} {tip * 1e6:>14.1f} {row * 1e6:>15.1f} {row / tip:>7.1f}",
              flush=True)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
