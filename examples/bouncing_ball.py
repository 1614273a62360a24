"""A steel ball dropped on a rigid plane bounces, each rebound e^2 as high as the one before.

    python examples/bouncing_ball.py --csv ball.csv --plots figs

A steel ball (radius 0.05 m, 7850 kg/m^3: 4.11 kg) on a free joint (dttmm.FreeJoint), its
centre dropped from rest at 1 m above the plane z = 0, gravity -9.81 m/s^2 along z, 3 s
(dttmm.model.chains.bouncing_ball).  Its contact (dttmm.Sphere, dttmm.Contact; docs/contact.md)
has restitution 0.8 and lasts about 0.2 ms, a steel ball's on steel at the 4.3 m/s of the drop
(Hertz's law).  The contact law's damping scales with the speed, so that the ball leaves every
contact at 0.8 of the speed it struck at, whatever that speed: the bounces' heights fall as
0.64^n.

The steps are chosen by the error (simulate(rtol=1e-7): long in flight, about 1 us in a
contact): a contact this short against flights of 0.9 s is what adaptive steps are for.  A
fixed step of 5 us (600,000 steps) gives the rebounds' ratios within 0.2%, 20 steps a contact
within 0.5%.

Printed: each bounce's height above the plane (the centre's, less the radius) and its ratio to
the one before against e^2 = 0.64, the steps taken and the wall time.  --csv: t, z (the centre's
height above the plane, m), vz (its rate, m/s), every 0.1 ms.  --plots: bouncing_ball.png.
With --dt the steps are fixed at dt.
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

from dttmm import simulate
from dttmm.model.chains import bouncing_ball

RADIUS, HEIGHT, RESTITUTION = 0.05, 1.0, 0.8
RTOL, SAMPLE = 1e-7, 1e-4
COLUMNS = ("t", "z", "vz")


def run(t_end=3.0, dt=None, rtol=RTOL):
    """The ball's run sampled every 0.1 ms: adaptive steps (rtol) unless dt is given."""
    model = bouncing_ball(RADIUS, height=HEIGHT, restitution=RESTITUTION)
    if dt is None:
        return simulate(model, t_end, rtol=rtol, record_dt=SAMPLE)
    return simulate(model, t_end, dt, record_every=max(1, int(round(SAMPLE / dt))))


def columns(result):
    return np.column_stack([result.t, result.position_input[:, 0, 2],
                            result.velocity_input[:, 0, 2]])


def bounce_heights(result):
    """The drop's height and each rebound's, above the plane (the centre's highest point less
    the radius, between one contact and the next; Result.contacts)."""
    t, z = result.t, result.position_input[:, 0, 2]
    touches = result.contacts()
    heights = [HEIGHT - RADIUS]
    for (_, _, t_off), following in zip(touches, touches[1:] + [(0, t[-1] + 1.0, None)]):
        if t_off is None:
            break
        flight = (t > t_off) & (t < following[1])
        if flight.any() and following[1] <= t[-1]:      # (a whole flight: its top)
            heights.append(float(z[flight].max()) - RADIUS)
    return np.array(heights)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=3.0, help="s (default 3)")
    parser.add_argument("--dt", type=float, default=None,
                        help="a fixed step, s (default: steps chosen by the error, rtol 1e-7)")
    parser.add_argument("--csv", help="write " + ", ".join(COLUMNS) + " (every 0.1 ms) here")
    parser.add_argument("--plots", help="write bouncing_ball.png into this directory")
    args = parser.parse_args(argv)
    if not (args.t_end > 0 and (args.dt is None or args.dt > 0)):
        parser.error("--t-end and --dt must be > 0")
    wall = time.perf_counter()
    result = run(args.t_end, args.dt)
    wall = time.perf_counter() - wall
    steps = f"dt = {args.dt:g} s" if args.dt else f"rtol = {RTOL:g}"
    print(f"steel ball dropped from {HEIGHT} m, restitution {RESTITUTION}, {steps}: "
          f"{result.n_steps} steps, {args.t_end:g} s in {wall:.1f} s")
    heights = bounce_heights(result)
    print(f"{'bounce':>7} {'height (m)':>12} {'ratio':>8}   (e^2 = {RESTITUTION ** 2:.4g})")
    for i, h in enumerate(heights):
        ratio = f"{h / heights[i - 1]:8.5f}" if i else ""
        print(f"{i:7d} {h:12.6f} {ratio}")
    table = columns(result)
    if args.csv:
        np.savetxt(args.csv, table, delimiter=",", header=",".join(COLUMNS), comments="",
                   fmt="%.10g")
        print(f"wrote {args.csv}")
    if args.plots:
        _plot(table, heights, args, Path(args.plots))
    return 0


def _plot(table, heights, args, folder):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    folder.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(2, 1, figsize=(8.4, 6.4), sharex=True)
    t = table[:, 0]
    axes[0].plot(t, table[:, 1], lw=1.3, label="the centre")
    tops = (HEIGHT - RADIUS) * RESTITUTION ** (2 * np.arange(len(heights))) + RADIUS
    for top in tops[1:]:
        axes[0].axhline(top, color="k", lw=0.6, ls=":")
    axes[0].plot([], [], color="k", lw=0.6, ls=":", label="r + (1 m - r) e^(2n)")
    axes[0].set_ylabel("height z (m)")
    axes[0].legend(fontsize=8)
    axes[0].set_title(f"Steel ball bouncing on a rigid plane, restitution {RESTITUTION} "
                      f"({'dt = %g s' % args.dt if args.dt else 'rtol = %g' % RTOL})",
                      fontsize=10)
    axes[1].plot(t, table[:, 2], lw=1.1, color="C1")
    axes[1].set_ylabel("vertical velocity (m/s)")
    axes[1].set_xlabel("t (s)")
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.tight_layout()
    out = folder / "bouncing_ball.png"
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print(f"wrote {out}")


if __name__ == "__main__":
    sys.exit(main())
