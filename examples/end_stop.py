"""An arm's first link driven against an end stop: it strikes, rebounds at half its rate, returns.

    python examples/end_stop.py --csv end_stop.csv --plots figs

The arm of examples/arm.py (dttmm.model.chains.arm: link 1 on a revolute joint about world y,
link 2, link 3 on a universal joint, body 4 on a sprung slider; gravity along -y), joint 1
driven by the torque 2 sin(pi t) N m, with an end stop at 0.5 rad (dttmm.JointLimit, docs/
limits.md): restitution 0.5 for the inertia the arm shows about joint 1 at t = 0 (1 / (d q1'' /
d tau1), from dttmm.linearize), its contact lasting about 5 ms.  2 s.

Printed: each contact's time, the rate it struck at, the rate it left at, and their ratio, and
the wall time.  Measured at the defaults: three contacts, ratios 0.425, 0.355 and 0.292, not
0.5: links 2 to 4 swing on their own joints through the contact and take part of the motion
(0.422 at a quarter of the step: it is the mechanism, not the step).  A single link on the same
stop leaves at 0.5 of its rate to within 1% (tests/test_limits.py).  Between the contacts the
drive holds the link against the stop, until its torque turns.  --csv: t, angle (rad),
rate (rad/s), stop_torque (N m, the stop's generalized force on joint 1), every 1 ms.  --plots:
end_stop.png.  The default step, 1e-4 s, gives the contact 50 steps.
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

import dttmm
from dttmm import JointLimit, simulate
from dttmm.model.chains import arm

STOP, RESTITUTION, CONTACT_TIME = 0.5, 0.5, 5e-3
COLUMNS = ("t", "angle", "rate", "stop_torque")


def joint1_inertia():
    """kg m^2: the arm's inertia about joint 1 at t = 0, 1 / (d q1'' / d tau1) (the linear
    model's B: the input that is joint 1's generalized force, the state that is its rate)."""
    lin = dttmm.linearize(arm("torque"))
    row = lin.states.index("joint1.q0'")
    column = lin.inputs.index("joint1.torque0")
    return 1.0 / lin.B[row, column]


def model(inertia=None):
    inertia = joint1_inertia() if inertia is None else inertia
    stop = JointLimit.with_restitution(-np.inf, STOP, RESTITUTION, inertia, CONTACT_TIME)
    return arm("torque", stop=stop)


def run(t_end=2.0, dt=1e-4, inertia=None):
    """(the model, its run sampled every 1 ms)."""
    m = model(inertia)
    return m, simulate(m, t_end, dt, record_every=max(1, int(round(1e-3 / dt))))


def columns(result):
    return np.column_stack([result.t, result.joint_coordinates[:, 0], result.joint_rates[:, 0],
                            result.limit_force[:, 0]])


def contacts(result):
    """[(t_on, rate before, rate after)] per contact of joint 1's stop: the rates at the samples
    just before it pushed and just after it let go (Result.limit_contacts)."""
    rate, t = result.joint_rates[:, 0], result.t
    out = []
    for col, _, t_on, t_off in result.limit_contacts():
        if col != 0 or t_off is None:
            continue
        i_on, i_off = np.searchsorted(t, t_on), np.searchsorted(t, t_off)
        out.append((t_on, rate[max(i_on - 1, 0)], rate[min(i_off + 1, len(t) - 1)]))
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=2.0, help="s (default 2)")
    parser.add_argument("--dt", type=float, default=1e-4, help="the step, s (default 1e-4)")
    parser.add_argument("--csv", help="write " + ", ".join(COLUMNS) + " (every 1 ms) here")
    parser.add_argument("--plots", help="write end_stop.png into this directory")
    args = parser.parse_args(argv)
    if not (args.t_end > 0 and args.dt > 0):
        parser.error("--t-end and --dt must be > 0")
    wall = time.perf_counter()
    inertia = joint1_inertia()
    _, result = run(args.t_end, args.dt, inertia)
    wall = time.perf_counter() - wall
    print(f"arm against a stop at {STOP} rad, restitution {RESTITUTION} for {inertia:.4f} kg m^2 "
          f"about joint 1, dt = {args.dt:g} s, {args.t_end:g} s in {wall:.1f} s")
    print(f"{'contact at (s)':>15} {'struck at (rad/s)':>18} {'left at (rad/s)':>16} "
          f"{'ratio':>7}")
    for t_on, before, after in contacts(result):
        print(f"{t_on:15.4f} {before:18.5f} {after:16.5f} {-after / before:7.4f}")
    table = columns(result)
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
    fig, axes = plt.subplots(3, 1, figsize=(8.4, 7.0), sharex=True)
    t = table[:, 0]
    axes[0].plot(t, table[:, 1], lw=1.4)
    axes[0].axhline(STOP, color="k", lw=0.8, ls=":", label="the stop")
    axes[0].set_ylabel("joint 1 angle (rad)")
    axes[0].legend(fontsize=8)
    axes[0].set_title(f"Arm driven against an end stop at {STOP} rad, restitution {RESTITUTION} "
                      f"(dt = {args.dt:g} s)", fontsize=10)
    axes[1].plot(t, table[:, 2], lw=1.4, color="C1")
    axes[1].set_ylabel("joint 1 rate (rad/s)")
    axes[2].plot(t, table[:, 3], lw=1.4, color="C3")
    axes[2].set_ylabel("stop torque (N m)")
    axes[2].set_xlabel("t (s)")
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.tight_layout()
    out = folder / "end_stop.png"
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print(f"wrote {out}")


if __name__ == "__main__":
    sys.exit(main())
