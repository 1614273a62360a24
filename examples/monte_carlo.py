"""A Monte Carlo of the paper's three-pendulum on dask.distributed (docs/sweeps.md): body 6's
initial spin about world y and the beam's stiffness drawn at random, each run to t_end, the
tip's (body 6's output point) final height gathered into a table and a histogram.

    python examples/monte_carlo.py --runs 100 --workers 2 --csv mc.csv --plots figs

Spin uniform in [0, 2] rad/s; stiffness factor log-uniform in [0.25, 4] (the beam's modulus
times it).  --engine processes runs on a local process pool instead (no dask needed).
"""
import argparse
import os
import sys

import numpy as np

import dttmm
from dttmm.model.chains import three_pendulum


def make_model(spin, stiffness):
    return three_pendulum(stiffness_factor=stiffness, tip_angular_velocity=(0.0, spin, 0.0))


def tip_height(result, model):
    """y of body 6's output point at the end, m."""
    return {"tip_height": result.position_output[-1, 2, 1]}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=100)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--engine", choices=("dask", "processes", "serial"), default="dask")
    ap.add_argument("--t-end", type=float, default=1.0)
    ap.add_argument("--dt", type=float, default=1e-4)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--csv", help="write the table (spin, stiffness, tip_height)")
    ap.add_argument("--plots", help="directory for the histogram")
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    runs = [{"spin": float(s), "stiffness": float(k)}
            for s, k in zip(rng.uniform(0.0, 2.0, args.runs),
                            np.exp(rng.uniform(np.log(0.25), np.log(4.0), args.runs)))]
    table = dttmm.sweep(make_model, runs, args.t_end, args.dt, outputs=tip_height,
                        engine=args.engine, n_workers=args.workers,
                        record_every=int(round(args.t_end / args.dt)))
    h = table["tip_height"]
    print(f"{len(table)} runs of {args.t_end:g} s at dt = {args.dt:g} s on {table.engine} "
          f"({args.workers} workers): {table.wall_time:.1f} s; tip height at the end: mean "
          f"{h.mean():.4f} m, std {h.std():.4f} m, range [{h.min():.4f}, {h.max():.4f}] m")
    if args.csv:
        table.save_csv(args.csv)
    if args.plots:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        os.makedirs(args.plots, exist_ok=True)
        fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
        ax.hist(h, bins=20, color="tab:blue", edgecolor="white")
        ax.set_xlabel(f"tip height y at t = {args.t_end:g} s (m)")
        ax.set_ylabel("runs")
        ax.set_title(f"Three-pendulum Monte Carlo: {len(table)} runs, spin U[0, 2] rad/s, "
                     f"stiffness x logU[1/4, 4]", fontsize=10)
        fig.savefig(os.path.join(args.plots, "monte_carlo_tip_height.png"), dpi=90)
        plt.close(fig)
    return 0


if __name__ == "__main__":
    sys.exit(main())
