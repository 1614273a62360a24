"""A box released on an inclined plane slides down it, or stays put below the friction angle.

    python examples/incline.py --mu 0.3 --angle 30 --csv incline.csv --plots figs

A uniform box of 1 kg, 0.2 x 0.2 x 0.1 m, on a free joint (dttmm.FreeJoint), resting on its
largest face on a plane inclined by ANGLE degrees (through the origin, falling along +x),
released at rest, gravity -9.81 m/s^2 along z, 2 s (dttmm.model.chains.box_on_incline).  Its
eight corners touch the plane (dttmm.Box, dttmm.Contact; docs/contact.md), with Coulomb's
friction MU (static = kinetic).  Above the friction angle (tan ANGLE > MU) it slides with the
acceleration g (sin ANGLE - MU cos ANGLE); below, friction holds it, to within the law's stick
velocity (1e-4 m/s): it creeps at v_s r / sqrt(1 - r^2), r = tan ANGLE / MU.

Printed: the distance and speed at the end against the closed form, and the wall time.  --csv:
t, s, v (the distance along the slope from the start, m, and the speed along it, m/s, positive
down the slope), every 1 ms.  --plots: incline.png.  The default step, 0.1 ms, gives each
corner's contact about 20 steps.
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

from dttmm import simulate
from dttmm.model.chains import box_on_incline

G = 9.81
COLUMNS = ("t", "s", "v")


def run(mu=0.3, angle=30.0, t_end=2.0, dt=1e-4):
    """The box's run on a plane inclined by `angle` degrees, sampled every 1 ms."""
    model = box_on_incline(mu, np.radians(angle))
    return simulate(model, t_end, dt, record_every=max(1, int(round(1e-3 / dt))))


def columns(result, angle):
    a = np.radians(angle)
    down = np.array([np.cos(a), 0.0, -np.sin(a)])
    x, v = result.position_input[:, 0], result.velocity_input[:, 0]
    return np.column_stack([result.t, (x - x[0]) @ down, v @ down])


def closed_form(mu, angle, t):
    """(s, v) of a block on the slope: g (sin a - mu cos a) t^2 / 2 while that is > 0, else 0."""
    a = np.radians(angle)
    acc = max(0.0, G * (np.sin(a) - mu * np.cos(a)))
    return 0.5 * acc * t * t, acc * t


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mu", type=float, default=0.3, help="friction coefficient (0.3)")
    parser.add_argument("--angle", type=float, default=30.0, help="the slope, degrees (30)")
    parser.add_argument("--t-end", type=float, default=2.0, help="s (default 2)")
    parser.add_argument("--dt", type=float, default=1e-4, help="the step, s (default 1e-4)")
    parser.add_argument("--csv", help="write " + ", ".join(COLUMNS) + " (every 1 ms) here")
    parser.add_argument("--plots", help="write incline.png into this directory")
    args = parser.parse_args(argv)
    if not (args.t_end > 0 and args.dt > 0 and args.mu >= 0 and 0 <= args.angle < 90):
        parser.error("--t-end and --dt must be > 0, --mu >= 0, 0 <= --angle < 90")
    wall = time.perf_counter()
    result = run(args.mu, args.angle, args.t_end, args.dt)
    wall = time.perf_counter() - wall
    table = columns(result, args.angle)
    s_exact, v_exact = closed_form(args.mu, args.angle, table[-1, 0])
    print(f"box on a {args.angle:g} degree slope, mu = {args.mu:g}, dt = {args.dt:g} s: "
          f"{args.t_end:g} s in {wall:.1f} s")
    print(f"at t = {table[-1, 0]:g} s: s = {table[-1, 1]:.6g} m (closed form {s_exact:.6g}), "
          f"v = {table[-1, 2]:.6g} m/s (closed form {v_exact:.6g})")
    if args.csv:
        np.savetxt(args.csv, table, delimiter=",", header=",".join(COLUMNS), comments="",
                   fmt="%.10g")
        print(f"wrote {args.csv}")
    if args.plots:
        _plot(table, args, Path(args.plots))
    return 0


def _plot(table, args, folder):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    folder.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(2, 1, figsize=(8.4, 6.0), sharex=True)
    t = table[:, 0]
    s_exact, v_exact = closed_form(args.mu, args.angle, t)
    axes[0].plot(t, table[:, 1], lw=1.6, label="dttmm")
    axes[0].plot(t, s_exact, "k:", lw=1.2, label="g (sin a - mu cos a) t^2 / 2")
    axes[0].set_ylabel("distance down the slope (m)")
    axes[0].legend(fontsize=8)
    axes[0].set_title(f"Box released on a {args.angle:g} degree slope, friction {args.mu:g} "
                      f"(dt = {args.dt:g} s)", fontsize=10)
    axes[1].plot(t, table[:, 2], lw=1.6, color="C1", label="dttmm")
    axes[1].plot(t, v_exact, "k:", lw=1.2, label="closed form")
    axes[1].set_ylabel("speed down the slope (m/s)")
    axes[1].set_xlabel("t (s)")
    axes[1].legend(fontsize=8)
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.tight_layout()
    out = folder / "incline.png"
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print(f"wrote {out}")


if __name__ == "__main__":
    sys.exit(main())
