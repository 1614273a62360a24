"""A spacecraft slews: a free hub with two flexible panels, turned by a torque, then let go.

    python examples/spacecraft.py --csv spacecraft.csv --plots figs

A free rigid hub (200 kg, a uniform 1 m cube, on dttmm.FreeJoint: docs/free_joint.md) carries
two aluminium panels (E 70 GPa, 2700 kg/m^3), each 2 m long, 0.5 m wide and 2 mm thick,
modal Euler-Bernoulli beams clamped at the centres of its +x and -x faces and extending along
x, their 2 mm thickness in the plane of the slew (dttmm.model.chains.spacecraft).  The hub
starts at the origin at rest; a couple of 10 N m about its z axis acts for 2 s, then is let go;
no gravity; 20 s.  The panels lag behind the hub while it is driven and then vibrate in the
hub-panel mode (both panels bending alike while the hub counter-turns), at a frequency above
their clamped-free one (0.411 Hz) because the hub's inertia is finite.

Printed: the angular momentum about z after the torque (it should stay at the impulse, 20 N m
s) and its largest change, the panels' vibration frequency from the run's tip deflection
against this script's own eigen-analysis of the hub and two panels (hub_panel_frequency: the
hub's turn and 40 Hermite beam elements per panel, centrifugal stiffening at the run's spin
rate), and the wall time.  --csv: t, hub_angle (rad, unwrapped, about world z), hub_rate
(rad/s), tip_deflection (the +x panel's tip, y in the hub's frame, m), momentum_z (the
system's angular momentum about z about its mass centre, kg m^2/s), every 1 ms.  --plots:
spacecraft.png.  The default step, 1 ms, keeps every column within 0.1% of its largest value
of a run at a quarter of the step (tests/test_free_joint.py).
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.linalg import eigh

from dttmm import simulate
from dttmm.model.chains import slew_torque, spacecraft
from dttmm.results.result import momenta

HUB_MASS, HUB_SIDE = 200.0, 1.0
LENGTH, WIDTH, THICKNESS, YOUNG, DENSITY = 2.0, 0.5, 2e-3, 70e9, 2700.0
TORQUE, DURATION = 10.0, 2.0
COLUMNS = ("t", "hub_angle", "hub_rate", "tip_deflection", "momentum_z")


def model():
    return spacecraft(HUB_MASS, HUB_SIDE, LENGTH, WIDTH, THICKNESS, YOUNG, DENSITY,
                      slew_torque(TORQUE, DURATION))


def run(t_end=20.0, dt=1e-3):
    """The run, sampled every 1 ms (every step if dt is longer)."""
    return simulate(model(), t_end, dt, record_every=max(1, int(round(1e-3 / dt))))


def columns(spacecraft_model, result):
    """(T, 5) the CSV's columns (see the docstring)."""
    a = result.rotation[:, 0]
    angle = np.unwrap(np.arctan2(a[:, 1, 0], a[:, 0, 0]))
    rate = result.angular_velocity[:, 0, 2]
    tip = result.position_output[:, 1] - result.position_input[:, 0]     # the +x panel's
    tip_y = np.einsum("tji,tj->ti", a, tip)[:, 1]
    mass, first, linear, angular = momenta(spacecraft_model, result)
    about_centre = angular - np.cross(first / mass, linear)
    return np.column_stack([result.t, angle, rate, tip_y, about_centre[:, 2]])


def hub_panel_frequency(spin=0.0, elements=40):
    """Hz: the hub-panel mode's frequency, the hub free to turn, both panels bending alike in
    the slew's plane, linearized about a steady spin (rad/s) in the hub's frame.  Each panel's
    deflection w(x) from its clamp at radius r = hub_side / 2 in Hermite cubic elements; with
    the hub's turn theta,

        T = 1/2 (J_hub + 2 int mu (r + x)^2) theta'^2 + 2 int mu (r + x) theta' w' + int mu w'^2
        V = int EI w''^2 + int N w'^2 - int mu spin^2 w^2     (both panels: twice 1/2 ...)

    N(x) = mu spin^2 ((r + L)^2 - (r + x)^2) / 2 the centrifugal tension (the beam's
    foreshortening to second order), the last term the centrifugal softening of an in-plane
    deflection; the lowest nonzero eigenvalue of K - omega^2 M."""
    mu, ei = DENSITY * WIDTH * THICKNESS, YOUNG * WIDTH * THICKNESS ** 3 / 12.0
    radius, j_hub = 0.5 * HUB_SIDE, HUB_MASS * HUB_SIDE ** 2 / 6.0
    le = LENGTH / elements
    n = 2 * (elements + 1)
    mass, stiff, coupling = np.zeros((n, n)), np.zeros((n, n)), np.zeros(n)
    xi, wi = np.polynomial.legendre.leggauss(6)
    for e in range(elements):
        dofs = slice(2 * e, 2 * e + 4)
        for s, weight in zip(0.5 * (xi + 1.0), 0.5 * le * wi):
            x = e * le + s * le
            shape = np.array([1 - 3 * s * s + 2 * s ** 3, le * (s - 2 * s * s + s ** 3),
                              3 * s * s - 2 * s ** 3, le * (s ** 3 - s * s)])
            slope = np.array([6 * s * s - 6 * s, le * (1 - 4 * s + 3 * s * s),
                              6 * s - 6 * s * s, le * (3 * s * s - 2 * s)]) / le
            curve = np.array([12 * s - 6, le * (6 * s - 4), 6 - 12 * s, le * (6 * s - 2)]) / le ** 2
            tension = mu * spin ** 2 * ((radius + LENGTH) ** 2 - (radius + x) ** 2) / 2.0
            coupling[dofs] += weight * mu * (radius + x) * shape
            mass[dofs, dofs] += weight * mu * np.outer(shape, shape)
            stiff[dofs, dofs] += weight * (ei * np.outer(curve, curve)
                                           + tension * np.outer(slope, slope)
                                           - mu * spin ** 2 * np.outer(shape, shape))
    free = slice(2, n)                        # clamped: w(0) = w'(0) = 0
    m = n - 2
    big_m, big_k = np.zeros((m + 1, m + 1)), np.zeros((m + 1, m + 1))
    big_m[0, 0] = j_hub + 2.0 * mu * ((radius + LENGTH) ** 3 - radius ** 3) / 3.0
    big_m[0, 1:] = big_m[1:, 0] = 2.0 * coupling[free]
    big_m[1:, 1:] = 2.0 * mass[free, free]
    big_k[1:, 1:] = 2.0 * stiff[free, free]
    eig = eigh(big_k, big_m, eigvals_only=True)
    return float(np.sqrt(eig[eig > 1e-9 * eig.max()].min()) / (2.0 * np.pi))


def measured_frequency(table, after=DURATION + 0.5):
    """Hz: from the tip deflection's zero crossings (about its mean) after `after` s."""
    keep = table[:, 0] > after
    t, y = table[keep, 0], table[keep, 3] - table[keep, 3].mean()
    i = np.nonzero(np.sign(y[1:]) != np.sign(y[:-1]))[0]
    crossings = t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])
    return float((len(crossings) - 1) / (2.0 * (crossings[-1] - crossings[0])))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=20.0, help="s (default 20)")
    parser.add_argument("--dt", type=float, default=1e-3, help="the step, s (default 1e-3)")
    parser.add_argument("--csv", help="write " + ", ".join(COLUMNS) + " (every 1 ms) here")
    parser.add_argument("--plots", help="write spacecraft.png into this directory")
    args = parser.parse_args(argv)
    if not (args.t_end > 0 and args.dt > 0):
        parser.error("--t-end and --dt must be > 0")
    wall = time.perf_counter()
    craft = model()
    result = run(args.t_end, args.dt)
    wall = time.perf_counter() - wall
    table = columns(craft, result)
    print(f"spacecraft: 200 kg hub, two 2 m aluminium panels, {TORQUE:g} N m for {DURATION:g} s;"
          f" dt = {args.dt:g} s, {args.t_end:g} s in {wall:.1f} s")
    after = table[:, 0] > DURATION + 0.5 * args.dt
    if after.any():
        h = table[after, 4]
        print(f"angular momentum about z after the torque: {h[0]:.9f} N m s (impulse "
              f"{TORQUE * DURATION:g}), largest change {np.abs(h - h[0]).max() / abs(h[0]):.2e} "
              f"of it")
        print(f"hub angle {table[-1, 1]:.6f} rad, rate {table[-1, 2]:.6f} rad/s at "
              f"t = {table[-1, 0]:g} s")
    if table[-1, 0] > DURATION + 3.0:
        spin = float(table[after, 2].mean())
        ours, theirs = measured_frequency(table), hub_panel_frequency(spin)
        print(f"panels' vibration: {ours:.5f} Hz from the tip; eigen-analysis {theirs:.5f} Hz "
              f"at {spin:.4f} rad/s ({100 * (ours / theirs - 1):+.2f}%), "
              f"{hub_panel_frequency(0.0):.5f} Hz at rest; clamped-free 0.41126 Hz")
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
    fig, axes = plt.subplots(3, 1, figsize=(8.4, 7.6), sharex=True)
    t = table[:, 0]
    axes[0].plot(t, table[:, 1], lw=1.4, label="hub angle (rad)")
    axes[0].plot(t, table[:, 2], lw=1.4, label="hub rate (rad/s)")
    axes[0].axvline(DURATION, color="k", lw=0.7, ls=":")
    axes[0].set_ylabel("rad, rad/s")
    axes[0].legend(fontsize=8)
    axes[0].set_title(f"Spacecraft slew: {TORQUE:g} N m on the hub for {DURATION:g} s, then "
                      f"released (dt = {args.dt:g} s)", fontsize=10)
    axes[1].plot(t, 1e3 * table[:, 3], lw=1.2, color="C2")
    axes[1].set_ylabel("+x panel tip, y in\nthe hub frame (mm)")
    axes[2].plot(t, table[:, 4], lw=1.2, color="C3")
    axes[2].set_ylabel("angular momentum\nabout z (N m s)")
    axes[2].set_xlabel("t (s)")
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.tight_layout()
    out = folder / "spacecraft.png"
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print(f"wrote {out}")


if __name__ == "__main__":
    sys.exit(main())
