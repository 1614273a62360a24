"""The paper's rigid-flexible three-pendulum (Rui et al. 2012, Section 5) by DT-TMM and by the
Newton-Euler reference: the paper's Figs. 5-8 overlaid and a table like its Table 1.

    python examples/three_pendulum.py --t-end 2 --dt 1e-4 --modes 2 --csv tp.csv --plots figs
"""
import argparse
import os
import sys
import time

import numpy as np

from dttmm import simulate
from dttmm.model.chains import three_pendulum
from dttmm.reference import simulate_reference
from dttmm.results.result import beam_midpoint_deflection

BODY2, BEAM4, BODY6 = 0, 1, 2
SAMPLE = 1e-3          # output grid, s


def run(args):
    model = three_pendulum(modes_per_plane=args.modes)
    n_out = int(round(args.t_end / SAMPLE))
    t_grid = np.arange(n_out + 1) * SAMPLE
    every = max(1, int(round(SAMPLE / args.dt)))

    def dttmm_run(t_end, **kw):
        return simulate(model, t_end, args.dt, method=args.method, **kw)

    def reference_run(t_end, **kw):
        return simulate_reference(model, t_end, method="RK45", rtol=args.ref_rtol,
                                  atol=args.ref_rtol * 1e-2, **kw)

    for timed in (dttmm_run, reference_run):    # JIT warm-up: the timed calls' kernels
        timed(10 * args.dt)                     # compiled (or loaded) before their clocks run
    t0 = time.perf_counter()
    dt_res = dttmm_run(args.t_end, record_every=every)
    dt_wall = time.perf_counter() - t0
    t0 = time.perf_counter()
    ne_res = reference_run(args.t_end, t_eval=t_grid)
    ne_wall = time.perf_counter() - t0
    tight = simulate_reference(model, args.t_end, method="DOP853", rtol=1e-12, atol=1e-13,
                               t_eval=t_grid)
    return model, dt_res, dt_wall, ne_res, ne_wall, tight


def errors(model, res, tight):
    pos = np.abs(res.position_output - tight.position_output).max()
    mid = np.abs(beam_midpoint_deflection(model, res, BEAM4)
                 - beam_midpoint_deflection(model, tight, BEAM4)).max()
    return pos, mid


def write_csv(path, model, res):
    mid = beam_midpoint_deflection(model, res, BEAM4)
    data = np.column_stack([res.t, res.position_output[:, BODY2], mid,
                            res.position_output[:, BODY6], res.total_energy])
    np.savetxt(path, data, delimiter=",", comments="", fmt="%.12g",
               header="t,x2,y2,z2,v_mid,w_mid,x6,y6,z6,energy")


def plot(directory, model, dt_res, ne_res):
    """The paper's Figs. 5-8, DT-TMM and the Newton-Euler reference overlaid, each component on
    an axis of its own, angles unwrapped, and the difference DT-TMM - reference beside them."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    os.makedirs(directory, exist_ok=True)
    if len(dt_res.t) != len(ne_res.t) or not np.allclose(dt_res.t, ne_res.t, atol=1e-9):
        raise ValueError("plot: the two runs must be sampled at the same times")
    mids = [1e3 * beam_midpoint_deflection(model, r, BEAM4) for r in (dt_res, ne_res)]
    angles = [np.unwrap(r.xyz_angles, axis=0) for r in (dt_res, ne_res)]
    figures = [
        ("fig5_midpoint_in_plane.png", "Fig. 5: beam 4's mid-point deflection in plane",
         ["v (mm)"], [m[:, :1] for m in mids], "mm"),
        ("fig6_midpoint_out_of_plane.png", "Fig. 6: beam 4's mid-point deflection out of plane",
         ["w (mm)"], [m[:, 1:] for m in mids], "mm"),
        ("fig7_angles_body2.png", "Fig. 7: x-y-z angles of body 2 (unwrapped)",
         ["theta_x (rad)", "theta_y (rad)", "theta_z (rad)"], [a[:, BODY2] for a in angles],
         "rad"),
        ("fig8_angles_beam4.png", "Fig. 8: x-y-z angles of beam 4's frame (unwrapped)",
         ["theta_x (rad)", "theta_y (rad)", "theta_z (rad)"], [a[:, BEAM4] for a in angles],
         "rad"),
    ]
    paths = []
    for name, title, labels, (a, b), unit in figures:
        rows = len(labels)
        fig, axes = plt.subplots(rows, 2, figsize=(10, 2.2 + 1.9 * rows), sharex=True,
                                 squeeze=False, constrained_layout=True)
        for c in range(rows):
            ax, diff = axes[c]
            ax.plot(dt_res.t, a[:, c], lw=1.4, label="DT-TMM")
            ax.plot(ne_res.t, b[:, c], "--", lw=1.1, label="Newton-Euler reference")
            ax.set_ylabel(labels[c])
            diff.plot(dt_res.t, a[:, c] - b[:, c], lw=1.0, color="k")
            diff.set_ylabel(f"DT-TMM - reference ({unit})")
            for x in (ax, diff):
                x.grid(alpha=0.3)
        axes[0, 0].legend(fontsize=8)
        axes[0, 0].set_title("both methods", fontsize=10)
        axes[0, 1].set_title("their difference", fontsize=10)
        for x in axes[-1]:
            x.set_xlabel("t (s)")
        fig.suptitle(title)
        path = os.path.join(directory, name)
        fig.savefig(path, dpi=90)
        plt.close(fig)
        paths.append(path)
    return paths


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=2.0)
    ap.add_argument("--dt", type=float, default=1e-4)
    ap.add_argument("--modes", type=int, default=2, help="bending modes per plane")
    ap.add_argument("--method", choices=["direct", "riccati"], default="riccati")
    ap.add_argument("--ref-rtol", type=float, default=1e-8,
                    help="relative tolerance of the timed Newton-Euler run")
    ap.add_argument("--csv", help="t, x2, y2, z2, v_mid, w_mid, x6, y6, z6, energy")
    ap.add_argument("--plots", help="directory for the paper's Figs. 5-8")
    args = ap.parse_args(argv)

    model, dt_res, dt_wall, ne_res, ne_wall, tight = run(args)
    dt_err, ne_err = errors(model, dt_res, tight), errors(model, ne_res, tight)
    mid = beam_midpoint_deflection(model, tight, BEAM4)
    print(f"three-pendulum, {args.t_end:g} s, {args.modes} modes per plane")
    print(f"beam mid-point deflection peaks: in plane {1e3 * np.abs(mid[:, 0]).max():.4f} mm, "
          f"out of plane {1e3 * np.abs(mid[:, 1]).max():.4f} mm")
    print(f"{'method':34s} {'wall, s':>9s} {'position error, m':>18s} {'mid-point error, m':>19s}")
    print(f"{'DT-TMM ' + args.method + f', dt = {args.dt:g}':34s} {dt_wall:9.3f} "
          f"{dt_err[0]:18.2e} {dt_err[1]:19.2e}")
    print(f"{f'Newton-Euler RK45, rtol = {args.ref_rtol:g}':34s} {ne_wall:9.3f} "
          f"{ne_err[0]:18.2e} {ne_err[1]:19.2e}")
    print(f"wall-time ratio Newton-Euler / DT-TMM: {ne_wall / dt_wall:.2f} "
          f"(errors against Newton-Euler DOP853 at rtol = 1e-12)")
    e = dt_res.total_energy
    print(f"DT-TMM energy drift: {np.abs(e - e[0]).max() / dt_res.kinetic.max():.2e} of the "
          f"largest kinetic energy")
    if args.csv:
        write_csv(args.csv, model, dt_res)
        print(f"wrote {args.csv}")
    if args.plots:
        for p in plot(args.plots, model, dt_res, ne_res):
            print(f"wrote {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
