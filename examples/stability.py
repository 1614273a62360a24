"""Where methods fail and where DT-TMM with the Riccati sweep does not (issue 4).

    python examples/stability.py [--quick] [--out DIR] [--long]

1. Direct vs Riccati as the chain grows: rigid ball-joint chains (N = 3 .. 1000) and stiff
   cantilevers of beam elements joined by fixed hinges, at dt = 1e-3 and 1e-4.  The error of the
   direct sweep is measured against the Riccati run at the same dt (what the products lose) and
   the Riccati run against the Newton-Euler reference where that is feasible (N <= 10).
2. Unconditional stability: the three-pendulum with the beam's modulus raised 10x .. 1000x.
   DT-TMM keeps dt = 1e-4; the explicit Runge-Kutta reference's step count grows with the
   stiffest frequency.
3. Long runs of the three-pendulum and of a 10-link chain at dt = 1e-4 (20 s; 120 s with --long,
   5 s with --quick), for the project's scheme and for the paper's (plain Newmark with every
   station point carrying its own position history, scheme="paper"): the largest angular
   acceleration and the energy error per window, and where the paper's scheme stops.
Prints every number and saves PNG charts in DIR (default: stability/).

Its first run on a machine compiles every method it compares: six copies of the loops (both
schemes, the direct and Riccati sweeps, rigid and welded chains) and the reference's kernels
for two kinds of model under both integrators, 4-25 s each, about 2.5 minutes together on 2
cores (numba's cache keeps them: a later --quick run takes ~7 s).
"""
import argparse
import os
import time

import numpy as np

from dttmm import DivergenceError, simulate
from dttmm.model.chains import rigid_chain, stiff_cantilever, three_pendulum
from dttmm.reference import simulate_reference


def direct_vs_riccati(make, sizes, dts, t_end, reference_up_to, converged_up_to):
    """rows of (N, dt, direct error or None if it stopped, Riccati error (against the reference
    up to reference_up_to bodies, beyond it against a Riccati run at dt / 4 up to
    converged_up_to; False where not computed), us per step of Riccati, of direct)."""
    simulate(make(sizes[0]), 10 * dts[0], dts[0])                     # JIT warm-up
    simulate(make(sizes[0]), 10 * dts[0], dts[0], method="direct")
    rows = []
    for n in sizes:
        model = make(n)
        for dt in dts:
            steps = max(10, int(round(t_end / dt)))
            t = steps * dt
            ric = simulate(model, t, dt, record_every=steps)
            try:
                dire = simulate(model, t, dt, method="direct", record_every=steps)
                d_err = np.abs(dire.position_output - ric.position_output).max()
                d_cost = 1e6 * dire.wall_time / steps
            except DivergenceError as err:
                d_err, d_cost = None, None
                print(f"    N={n} dt={dt:g}: direct stopped: {err.cause[:70]}")
            r_err = False                    # not computed
            if n <= reference_up_to:
                ref = simulate_reference(model, t, rtol=1e-12, atol=1e-13, t_eval=[0.0, t])
                r_err = np.abs(ric.position_output[-1] - ref.position_output[-1]).max()
            elif n <= converged_up_to:
                fine = simulate(model, t, dt / 4, record_every=4 * steps)
                r_err = np.abs(ric.position_output[-1] - fine.position_output[-1]).max()
            rows.append((n, dt, d_err, r_err, 1e6 * ric.wall_time / steps, d_cost))
            print(f"  N={n:5d} dt={dt:g}: direct - Riccati {_fmt(d_err)} m, Riccati - reference "
                  f"{_fmt(r_err)} m, Riccati {rows[-1][4]:.0f} us/step, direct "
                  f"{_fmt(d_cost, '.0f')} us/step", flush=True)
    return rows


def _fmt(x, spec=".2e"):
    return "failed" if x is None else ("-" if x is False else format(x, spec))


def stiffened_three_pendulum(factors, t_end, dt):
    rows = []
    for f in factors:
        model = three_pendulum(2, stiffness_factor=f)
        grid = np.array([0.0, t_end])
        tight = simulate_reference(model, t_end, method="DOP853", rtol=1e-11, atol=1e-13,
                                   t_eval=grid)
        res = simulate(model, t_end, dt, record_every=int(round(t_end / dt)))
        t0 = time.perf_counter()
        rk = simulate_reference(model, t_end, method="RK45", rtol=1e-6, atol=1e-8, t_eval=grid)
        rk_wall = time.perf_counter() - t0
        rows.append((f, np.abs(res.position_output[-1] - tight.position_output[-1]).max(),
                     res.wall_time, np.abs(rk.position_output[-1]
                                           - tight.position_output[-1]).max(),
                     rk_wall, int(rk.info.get("nfev", -1))))
        print(f"  E x {f:g}: DT-TMM dt={dt:g} error {rows[-1][1]:.2e} m in {rows[-1][2]:.2f} s; "
              f"RK45 rtol 1e-6 error {rows[-1][3]:.2e} m in {rk_wall:.2f} s, "
              f"{rows[-1][5]} right-hand sides", flush=True)
    return rows


def long_runs(t_end, dt, window):
    """Both schemes on the three-pendulum and a 10-link chain: {(system, scheme): (window ends,
    peak |angular acceleration| per window, energy error per window (of the largest kinetic
    energy), time the run stopped or None)}."""
    out = {}
    for name, model in (("three-pendulum", three_pendulum(2)), ("10-link chain", rigid_chain(10))):
        for scheme in ("newmark", "paper"):
            stopped = None
            try:
                res = simulate(model, t_end, dt, scheme=scheme,
                               record_every=int(round(0.005 / dt)))
            except DivergenceError as err:
                res, stopped = err.partial, err.t
            e = res.total_energy
            if scheme == "newmark":       # the largest kinetic energy of the motion itself
                k_max = res.kinetic.max()
            n_win = int(np.ceil(res.t[-1] / window - 1e-9))
            ends, peaks, e_err = [], [], []
            for i in range(n_win):
                sel = (res.t > i * window) & (res.t <= (i + 1) * window + 1e-12)
                ends.append(min((i + 1) * window, res.t[-1]))
                peaks.append(np.abs(res.angular_acceleration[sel]).max())
                e_err.append(np.abs(e[sel] - e[0]).max() / k_max)
            out[name, scheme] = (np.array(ends), np.array(peaks), np.array(e_err), stopped)
            label = "project's scheme" if scheme == "newmark" else "paper's scheme  "
            fate = (f"STOPPED at t = {stopped:.3f} s (the alternating mode)" if stopped
                    else f"ran {t_end:g} s")
            print(f"  {name}, {label}, dt={dt:g}: {fate}; peak angular acceleration per "
                  f"{window:g} s window {np.array2string(np.array(peaks), precision=3)} rad/s^2; "
                  f"largest energy error {max(e_err):.2e} of the largest kinetic energy",
                  flush=True)
    return out


def chart_sizes(path, title, rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for dt, style in zip(sorted({r[1] for r in rows}, reverse=True), ("o-", "s--")):
        sel = [r for r in rows if r[1] == dt]
        ok = [r for r in sel if r[2] is not None]
        ax.loglog([r[0] for r in ok], [max(r[2], 1e-17) for r in ok], style,
                  label=f"direct - Riccati, dt={dt:g}")
        failed = [r[0] for r in sel if r[2] is None]
        if failed:
            ax.loglog(failed, [1e2] * len(failed), "x", ms=10, color="k")
        ref = [r for r in sel if r[3] not in (None, False)]
        if ref:
            ax.loglog([r[0] for r in ref], [r[3] for r in ref], style[0] + ":",
                      label=f"Riccati - reference, dt={dt:g}")
    ax.axhline(1e2, color="k", lw=0.5)
    ax.text(ax.get_xlim()[0] * 1.1, 2e2, "x: direct stopped (lost accuracy / singular)",
            fontsize=8)
    ax.text(ax.get_xlim()[0] * 1.1, 1e-16, "reference: Newton-Euler for small N, beyond it "
            "Riccati at dt/4", fontsize=7)
    ax.set_xlabel("number of bodies N")
    ax.set_ylabel("max position error, m")
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def chart_stiff(path, rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.6))
    f = [r[0] for r in rows]
    a1.loglog(f, [r[1] for r in rows], "o-", label="DT-TMM, fixed dt")
    a1.loglog(f, [r[3] for r in rows], "s--", label="RK45, rtol 1e-6")
    a1.set_xlabel("modulus factor")
    a1.set_ylabel("position error at the end, m")
    a1.legend(fontsize=8)
    a2.loglog(f, [r[2] for r in rows], "o-", label="DT-TMM wall time, s")
    a2.loglog(f, [r[4] for r in rows], "s--", label="RK45 wall time, s")
    a2.set_xlabel("modulus factor")
    a2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def chart_long(path, data):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(2, 2, figsize=(10, 6), sharex="col")
    systems = sorted({key[0] for key in data}, reverse=True)
    for col, system in enumerate(systems):
        for scheme, style, label in (("newmark", "-", "project's scheme"),
                                     ("paper", "--", "paper's scheme")):
            ends, peaks, e_err, stopped = data[system, scheme]
            axes[0, col].semilogy(ends, peaks, style, label=label)
            axes[1, col].semilogy(ends, np.maximum(e_err, 1e-16), style, label=label)
            if stopped:
                for ax in axes[:, col]:
                    ax.axvline(stopped, color="r", lw=0.8)
                axes[0, col].text(stopped, 1e3 * data[system, "newmark"][1].max(),
                                  f" stopped\n t = {stopped:.2f} s",
                                  color="r", fontsize=8, va="top")
        # the last window before a stop holds values near overflow: show the growth up to there
        axes[0, col].set_ylim(top=1e4 * data[system, "newmark"][1].max())
        axes[1, col].set_ylim(top=1e3)
        axes[0, col].set_title(system)
        axes[0, col].set_ylabel("peak |angular acceleration|, rad/s^2")
        axes[1, col].set_ylabel("energy error / largest kinetic energy")
        axes[1, col].set_xlabel("t, s")
        axes[0, col].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer sizes and shorter runs")
    ap.add_argument("--out", default="stability", help="directory for the PNG charts")
    ap.add_argument("--long", action="store_true",
                    help="the long runs over 120 s (~15 min) instead of 20 s")
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    rigid_sizes = [3, 10, 30] if args.quick else [3, 10, 30, 100, 300, 1000]
    beam_sizes = [3, 10, 30] if args.quick else [3, 10, 30, 100]
    t_end = 0.02 if args.quick else 0.03
    print("1. direct vs Riccati, rigid ball-joint chains")
    rigid = direct_vs_riccati(rigid_chain, rigid_sizes, [1e-3, 1e-4], t_end, 10, 1000)
    chart_sizes(os.path.join(args.out, "direct_vs_riccati_rigid.png"),
                "rigid ball-joint chains", rigid)
    print("   stiff cantilevers of beam elements (fixed hinges)")
    beams = direct_vs_riccati(stiff_cantilever, beam_sizes, [1e-3, 1e-4], t_end, 3, 30)
    chart_sizes(os.path.join(args.out, "direct_vs_riccati_beams.png"),
                "cantilevers of stiff beam elements", beams)
    print("2. the three-pendulum with a stiffer beam, DT-TMM at fixed dt vs explicit RK45")
    stiff = stiffened_three_pendulum([1, 10, 100] if args.quick else [1, 10, 100, 1000],
                                     0.2 if args.quick else 0.5, 1e-4)
    chart_stiff(os.path.join(args.out, "stiff_three_pendulum.png"), stiff)
    t_long = 120.0 if args.long else (5.0 if args.quick else 20.0)
    print(f"3. long runs, {t_long:g} s at dt = 1e-4: the project's scheme and the paper's "
          f"(independent station positions)")
    chart_long(os.path.join(args.out, "long_runs.png"),
               long_runs(t_long, 1e-4, 1.0 if args.long else 0.5))
    print(f"charts in {args.out}/")


if __name__ == "__main__":
    main()
