"""The IFToMM spatial slider-crank, a closed loop, by DT-TMM (or the Newton-Euler reference).

    python examples/slider_crank.py --t-end 5 --dt 1e-4 --csv slider_crank.csv --plots figures

A crank on a revolute joint about world x at (0, 0.1, 0.12), a rod on a ball joint at its end,
a slider on the x axis: the rod joins it by a universal joint, and its prismatic joint closes
the loop (dttmm.model.mechanisms.slider_crank; docs/loops.md).  The crank turns at 6 rad/s at t = 0,
the rest assembled consistent with it; no drive, no friction, gravity along -z.  CSV: t,
slider_x, slider_vx, crank_angle (unwrapped), crank_rate every 1 ms.
"""
import argparse
import sys
from pathlib import Path

import numpy as np

from dttmm import simulate, simulate_reference
from dttmm.model.mechanisms import slider_crank


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=5.0, help="end time, s (default 5)")
    ap.add_argument("--dt", type=float, default=1e-4, help="time step, s (default 1e-4)")
    ap.add_argument("--solver", choices=["dttmm", "reference"], default="dttmm",
                    help="DT-TMM (default) or the Newton-Euler reference (DOP853, rtol 1e-10)")
    ap.add_argument("--csv", help="write t, slider_x, slider_vx, crank_angle, crank_rate "
                                  "every 1 ms")
    ap.add_argument("--plots", help="directory for the figure (PNG)")
    ap.add_argument("--no-hold-energy", action="store_true",
                    help="DT-TMM: step without holding the total energy (by default the rates "
                         "are scaled after every step to hold it; docs/loops.md)")
    args = ap.parse_args(argv)

    model = slider_crank()
    every = max(1, int(round(1e-3 / args.dt)))
    try:
        if args.solver == "dttmm":
            res = simulate(model, args.t_end, args.dt, record_every=every,
                           hold_energy=False if args.no_hold_energy else None)
        else:
            n = int(round(args.t_end / 1e-3))
            res = simulate_reference(model, args.t_end, t_eval=np.linspace(0, args.t_end, n + 1))
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    slider = model.body_names.index("slider")
    x, vx = res.position_input[:, slider, 0], res.velocity_input[:, slider, 0]
    angle, rate = res.joint_coordinates[:, 0], res.joint_rates[:, 0]
    e = res.total_energy
    what = (f"{res.n_steps} steps of {args.dt:g} s, {res.info['loop']} loop"
            if args.solver == "dttmm" else f"reference, {res.n_steps} steps")
    print(f"IFToMM slider-crank ({what}): {res.wall_time:.3f} s wall")
    print(f"  at t = {res.t[-1]:g} s: slider x = {x[-1]:.9f} m, vx = {vx[-1]:.9f} m/s, crank "
          f"{angle[-1]:.9f} rad at {rate[-1]:.9f} rad/s")
    print(f"  energy {e[0]:.8f} J at t = 0, drift {np.abs(e - e[0]).max():.3e} J (largest "
          f"kinetic energy {res.kinetic.max():.4f} J)")
    if args.solver == "dttmm":
        info = res.info
        print(f"  loop residuals after every step: positions "
              f"{info['loop_position_residual']:.2e} m, rates {info['loop_rate_residual']:.2e} m/s")
        print("  energy " + (f"held (rates scaled by at most {info['energy_correction']:.1e} in "
                             f"a step)" if info["energy_held"] else "not held (--no-hold-energy)"))
    if args.csv:
        data = np.column_stack([res.t, x, vx, angle, rate])
        np.savetxt(args.csv, data, delimiter=",", comments="", fmt="%.12g",
                   header="t,slider_x,slider_vx,crank_angle,crank_rate")
        print(f"wrote {args.csv}")
    if args.plots:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        out = Path(args.plots)
        out.mkdir(parents=True, exist_ok=True)
        fig, ax = plt.subplots(1, 3, figsize=(14, 4.2))
        ax[0].plot(res.t, x, lw=0.9)
        ax[0].set(xlabel="t, s", ylabel="slider x, m", title="Slider position")
        ax[1].plot(res.t, rate, lw=0.9)
        ax[1].set(xlabel="t, s", ylabel="crank rate, rad/s", title="Crank angular velocity")
        ax[2].plot(res.t, (e - e[0]) / res.kinetic.max(), lw=0.9)
        ax[2].set(xlabel="t, s", ylabel="(E - E0) / max kinetic energy",
                  title=f"Energy error ({args.solver}, dt = {args.dt:g} s"
                        + (", held)" if res.info.get("energy_held") else ")"))
        ax[2].ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
        fig.suptitle("IFToMM spatial slider-crank, a closed loop (free, gravity along -z)")
        fig.tight_layout()
        path = out / "slider_crank.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
