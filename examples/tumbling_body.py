"""Dzhanibekov's nut: a free box spun about its intermediate axis flips over and back.

    python examples/tumbling_body.py --csv tumbling.csv --plots figs

A uniform rigid box of 1 kg, 0.3 m along its x axis, 0.2 m along y and 0.1 m along z (principal
moments (b^2 + c^2) m / 12: 0.00417, 0.00833 and 0.01083 kg m^2), on a free joint
(dttmm.FreeJoint, docs/free_joint.md) with its input point at its mass centre, starts at the
origin at rest in translation, with the identity rotation and w(0) = (1e-3, 4, 1e-3) rad/s in
body axes: spun about y, its intermediate axis, the motion Euler's equations say is unstable.
No gravity, 20 s.  Every ~10 s the box turns over: w_y goes from +4 to -4 rad/s and back, at
the times the closed form gives (w_y = A sn(lambda t + tau_0 | m), Landau and Lifshitz,
Mechanics, section 37; printed beside the run's).

Printed: the flips' times against the closed form, the kinetic energy's and the angular
momentum's largest relative change (nothing acts on the box: both should stay; the Newmark step
holds them to O(dt^2)), and the wall time.  --csv: t, wx, wy, wz (body-frame angular velocity,
rad/s), energy (kinetic, J), momentum (|H| about the mass centre, kg m^2/s), every 10 ms.
--plots: tumbling_body.png, the body rates and the two invariants' changes against t.

The default step, 1 ms, keeps every column within 0.1% of its largest value of a converged run's
(tests/test_free_joint.py measures it against a run at 0.125 ms).
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.special import ellipk, ellipkinc

from dttmm import simulate
from dttmm.model.chains import tumbling_box

MASS, SIDES = 1.0, np.array([0.3, 0.2, 0.1])
INERTIA = MASS * (np.sum(SIDES ** 2) - SIDES ** 2) / 12.0      # (b^2 + c^2) m / 12, ...
W0 = np.array([1e-3, 4.0, 1e-3])
COLUMNS = ("t", "wx", "wy", "wz", "energy", "momentum")


def box_model():
    """The box on a free joint at the origin, no gravity (dttmm.model.chains.tumbling_box)."""
    return tumbling_box(SIDES, MASS, W0)


def columns(result):
    """(T, 6) the CSV's columns: t, the body-frame angular velocity, the kinetic energy and
    |H| about the mass centre (A J A^T w)."""
    a, w = result.rotation[:, 0], result.angular_velocity[:, 0]
    w_body = np.einsum("tji,tj->ti", a, w)
    energy = 0.5 * np.einsum("ti,i,ti->t", w_body, INERTIA, w_body)
    momentum = np.linalg.norm(w_body * INERTIA, axis=1)
    return np.column_stack([result.t, w_body, energy, momentum])


def closed_form_flips(t_end):
    """The times w_y changes sign, from the closed form (H^2 > 2 E J_y here: w_y = A_2 sn,
    w_x = A_1 cn, w_z = A_3 dn)."""
    j1, j2, j3 = INERTIA
    two_e, h2 = np.sum(INERTIA * W0 * W0), np.sum((INERTIA * W0) ** 2)
    lam = np.sqrt((j3 - j2) * (h2 - two_e * j1) / (j1 * j2 * j3))
    m = (j2 - j1) * (two_e * j3 - h2) / ((j3 - j2) * (h2 - two_e * j1))
    a1 = np.sqrt((two_e * j3 - h2) / (j1 * (j3 - j1)))
    tau0 = ellipkinc(np.arccos(W0[0] / a1), m)
    flips = (2.0 * ellipk(m) * np.arange(1, 100) - tau0) / lam
    return flips[flips <= t_end]


def flips_of(t, wy):
    """The times wy changes sign, linear between samples."""
    i = np.nonzero(np.sign(wy[1:]) != np.sign(wy[:-1]))[0]
    return t[i] - wy[i] * (t[i + 1] - t[i]) / (wy[i + 1] - wy[i])


def run(t_end=20.0, dt=1e-3):
    """The run, sampled every 10 ms (every step if dt is longer)."""
    return simulate(box_model(), t_end, dt, record_every=max(1, int(round(0.01 / dt))))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=20.0, help="s (default 20)")
    parser.add_argument("--dt", type=float, default=1e-3, help="the step, s (default 1e-3)")
    parser.add_argument("--csv", help="write " + ", ".join(COLUMNS) + " (every 10 ms) here")
    parser.add_argument("--plots", help="write tumbling_body.png into this directory")
    args = parser.parse_args(argv)
    if not (args.t_end > 0 and args.dt > 0):
        parser.error("--t-end and --dt must be > 0")
    wall = time.perf_counter()
    result = run(args.t_end, args.dt)
    wall = time.perf_counter() - wall
    table = columns(result)
    print(f"tumbling box, 1 kg, 0.3 x 0.2 x 0.1 m, w(0) = {W0.tolist()} rad/s (body axes), "
          f"dt = {args.dt:g} s, {args.t_end:g} s in {wall:.1f} s")
    ours, exact = flips_of(table[:, 0], table[:, 2]), closed_form_flips(args.t_end)
    print(f"{'flip':>5} {'run (s)':>10} {'closed form (s)':>16} {'difference (s)':>15}")
    for i, t_exact in enumerate(exact):
        t_run = ours[i] if i < len(ours) else np.nan
        print(f"{i + 1:5d} {t_run:10.5f} {t_exact:16.5f} {t_run - t_exact:15.2e}")
    for name, col in (("kinetic energy", 4), ("|H| about the mass centre", 5)):
        change = np.abs(table[:, col] / table[0, col] - 1.0).max()
        print(f"{name}: largest relative change {change:.2e}")
    if args.csv:
        np.savetxt(args.csv, table, delimiter=",", header=",".join(COLUMNS), comments="",
                   fmt="%.10g")
        print(f"wrote {args.csv}")
    if args.plots:
        _plot(table, exact, args, Path(args.plots))
    return 0


def _plot(table, exact, args, folder):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    folder.mkdir(parents=True, exist_ok=True)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8.4, 6.4), sharex=True,
                                      gridspec_kw=dict(height_ratios=[2, 1]))
    t = table[:, 0]
    for col, name in zip((1, 2, 3), ("w_x", "w_y", "w_z")):
        top.plot(t, table[:, col], lw=1.4, label=name)
    for t_flip in exact:
        top.axvline(t_flip, color="k", lw=0.7, ls=":")
    top.set_ylabel("body-frame angular velocity (rad/s)")
    top.set_title(f"Tumbling box spun about its intermediate axis (dt = {args.dt:g} s)\n"
                  f"dotted: the flips' closed-form times", fontsize=10)
    top.legend(fontsize=8, loc="lower left")
    top.grid(alpha=0.3)
    for col, name in ((4, "kinetic energy"), (5, "|H| about the mass centre")):
        bottom.plot(t, table[:, col] / table[0, col] - 1.0, lw=1.2, label=name)
    bottom.set_xlabel("t (s)")
    bottom.set_ylabel("relative change (-)")
    bottom.legend(fontsize=8)
    bottom.grid(alpha=0.3)
    fig.tight_layout()
    out = folder / "tumbling_body.png"
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print(f"wrote {out}")


if __name__ == "__main__":
    sys.exit(main())
