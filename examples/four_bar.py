"""The N-four-bar (IFToMM / MBS library A02), closed loops through singular positions, by DT-TMM.

    python examples/four_bar.py --n 2 --t-end 10 --dt 1e-3 --csv four_bar.csv --plots figures

N + 1 vertical unit bars on revolute joints to the ground at (i, 0), N horizontal bars between
their tops, every axis along z, gravity -9.81 along y (dttmm.model.mechanisms.n_four_bar).  The
spanning tree (--tree): "ground" (default) roots every vertical bar at its ground pivot, hangs
each horizontal bar from the bar before it and closes it on the next, so each loop is local and
a step costs O(N); "chain" holds the first vertical bar and the horizontal bars, and N
revolute joints close the loops to the ground, every loop through the first bar: O(N^2);
"shortest" is that chain rebuilt by System.build(tree="shortest"), local again: O(N).
The bars start upright, B_0 (the first bar's top) moving at (1, 0) m/s; twice a turn the
bars lie flat, where the loops are singular and the spatial revolute joints redundant.
The run is compared with the exact one-degree-of-freedom reduction of the parallelogram.  CSV:
t, B0_x, B0_y, B0_vx, B0_vy every 0.01 s.
"""
import argparse
import sys
from pathlib import Path

import numpy as np

from dttmm import simulate
from dttmm.model.mechanisms import n_four_bar, parallelogram


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=2, help="horizontal bars (default 2)")
    ap.add_argument("--t-end", type=float, default=10.0, help="end time, s (default 10)")
    ap.add_argument("--dt", type=float, default=1e-3, help="time step, s (default 1e-3)")
    ap.add_argument("--csv", help="write t, B0_x, B0_y, B0_vx, B0_vy every 0.01 s")
    ap.add_argument("--plots", help="directory for the figure (PNG)")
    ap.add_argument("--tree", choices=("ground", "chain", "shortest"), default="ground",
                    help="spanning tree: 'ground' (default, local loops, O(N) a step), "
                         "'chain' (every loop through the first bar, O(N^2)) or 'shortest' "
                         "(the chain rebuilt on local loops, O(N))")
    args = ap.parse_args(argv)
    if args.n < 1:
        print(f"error: --n must be at least 1, got {args.n}", file=sys.stderr)
        return 2

    model = n_four_bar(args.n, tree=args.tree)
    every = max(1, int(round(0.01 / args.dt)))
    try:
        res = simulate(model, args.t_end, args.dt, record_every=every)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    first = model.body_names.index("v0")
    b0 = res.position_output[:, first, :2]
    arm = b0 - res.position_input[:, first, :2]
    v0 = np.cross(res.angular_velocity[:, first], np.pad(arm, ((0, 0), (0, 1))))[:, :2]
    exact = parallelogram(args.n, res.t)
    error = np.abs(b0 - exact).max(axis=1)
    print(f"{args.n}-four-bar, {res.n_steps} steps of {args.dt:g} s ({res.info['loop']} loop): "
          f"{res.wall_time:.3f} s wall, {1e6 * res.wall_time / res.n_steps:.1f} us/step")
    print(f"  B_0 at t = {res.t[-1]:g} s: {np.array2string(b0[-1], precision=9)} m; largest "
          f"distance from the exact reduction {error.max():.3e} m")
    info = res.info
    print(f"  loop residuals after every step: positions {info['loop_position_residual']:.2e} m, "
          f"rates {info['loop_rate_residual']:.2e} m/s")
    if args.csv:
        data = np.column_stack([res.t, b0, v0])
        np.savetxt(args.csv, data, delimiter=",", comments="", fmt="%.12g",
                   header="t,B0_x,B0_y,B0_vx,B0_vy")
        print(f"wrote {args.csv}")
    if args.plots:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        out = Path(args.plots)
        out.mkdir(parents=True, exist_ok=True)
        fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
        ax[0].plot(res.t, b0[:, 0], lw=0.9, label="x (DT-TMM)")
        ax[0].plot(res.t, b0[:, 1], lw=0.9, label="y (DT-TMM)")
        ax[0].plot(res.t, exact[:, 0], "k:", lw=0.8, label="exact reduction")
        ax[0].plot(res.t, exact[:, 1], "k:", lw=0.8)
        ax[0].set(xlabel="t, s", ylabel="B_0, m", title="The first bar's top")
        ax[0].legend(fontsize=8)
        ax[1].semilogy(res.t[1:], error[1:], lw=0.9)
        ax[1].set(xlabel="t, s", ylabel="|B_0 - exact|, m",
                  title=f"Distance from the exact reduction (dt = {args.dt:g} s)")
        fig.suptitle(f"{args.n}-four-bar: closed loops through their flat positions (DT-TMM)")
        fig.tight_layout()
        path = out / "four_bar.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
