"""Five unit links in a tree of ball joints, falling under gravity, by DT-TMM.

    python examples/tree.py --t-end 2 --dt 1e-4 --csv tree.csv --plots figures

Links 2 and 4 hang from link 1's output point, link 3 from link 2's, link 5 from link 4's;
links 4 and 5 start along -z, links 1-3 along +x (dttmm.model.chains.five_link_tree).  The run is
swept from the leaves to the root each step (docs/assembly.md, "Trees").  CSV: t, x1, y1, z1,
..., x5, y5, z5, the world positions of the links' output points every 0.01 s.
"""
import argparse
import sys
from pathlib import Path

import numpy as np

from dttmm import simulate
from dttmm.model.chains import five_link_tree


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=2.0, help="end time, s (default 2)")
    ap.add_argument("--dt", type=float, default=1e-4, help="time step, s (default 1e-4)")
    ap.add_argument("--method", choices=["riccati", "direct"], default="riccati",
                    help="assembly (a tree needs riccati: the direct products run along a chain)")
    ap.add_argument("--csv", help="write t and the output points' positions every 0.01 s")
    ap.add_argument("--plots", help="directory for the figures (PNG)")
    args = ap.parse_args(argv)

    model = five_link_tree()
    every = max(1, int(round(0.01 / args.dt)))
    try:
        res = simulate(model, args.t_end, args.dt, method=args.method, record_every=every)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    e = res.total_energy
    print(f"5-link tree, {res.n_steps} steps of {args.dt:g} s by {res.info['mode']} "
          f"({res.info['loop']} loop): {res.wall_time:.3f} s wall, "
          f"{1e6 * res.wall_time / res.n_steps:.2f} us/step")
    for k, name in enumerate(model.body_names):
        print(f"  {name} output at t = {res.t[-1]:g} s: "
              f"{np.array2string(res.position_output[-1, k], precision=6)} m")
    print(f"energy drift: {np.abs(e - e[0]).max():.3e} J (largest kinetic energy "
          f"{res.kinetic.max():.3f} J)")
    if args.csv:
        head = ",".join(["t"] + [f"{c}{k + 1}" for k in range(model.n_bodies) for c in "xyz"])
        data = np.column_stack([res.t, res.position_output.reshape(len(res.t), -1)])
        np.savetxt(args.csv, data, delimiter=",", header=head, comments="", fmt="%.12g")
        print(f"wrote {args.csv}")
    if args.plots:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        out = Path(args.plots)
        out.mkdir(parents=True, exist_ok=True)
        fig, ax = plt.subplots(1, 3, figsize=(14, 4.4))
        for k, name in enumerate(model.body_names):
            p = res.position_output[:, k]
            ax[0].plot(p[:, 0], p[:, 2], lw=0.9, label=name)
            ax[1].plot(res.t, p[:, 1], lw=0.9, label=name)
        # the tree at a few instants, seen from above (x-z), joints to output points
        for t_mark in np.linspace(0.0, res.t[-1], 4):
            i = int(np.argmin(np.abs(res.t - t_mark)))
            for k in range(model.n_bodies):
                a, b = res.position_input[i, k], res.position_output[i, k]
                ax[0].plot([a[0], b[0]], [a[2], b[2]], color="0.4", lw=0.6, alpha=0.6)
        ax[0].set(xlabel="x, m", ylabel="z, m", aspect="equal",
                  title="Output points seen from above (grey: the tree at 4 instants)")
        ax[1].set(xlabel="t, s", ylabel="y, m", title="Height of the output points")
        ax[0].legend(fontsize=7)
        ax[2].plot(res.t, (e - e[0]) / res.kinetic.max(), lw=0.9)
        ax[2].set(xlabel="t, s", ylabel="(E - E0) / max kinetic energy",
                  title=f"Energy error (dt = {args.dt:g} s)")
        ax[2].ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
        fig.suptitle("Five-link tree of ball joints, falling under gravity (DT-TMM)")
        fig.tight_layout()
        path = out / "tree.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
