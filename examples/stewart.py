"""A Stewart platform, six legs closing five loops, by DT-TMM.

    python examples/stewart.py --drive motion --t-end 3 --dt 1e-4 --csv stewart.csv --plots figures

Six legs of two bodies (a universal joint at the base, a prismatic joint along the leg, a ball
joint at the platform) carry a 10 kg platform (dttmm.model.mechanisms.stewart_platform; issue 29's
data).  --drive motion prescribes each slide, s_i(t) = +-0.05 (1 - cos 2 pi t) m (+ for legs 1,
3, 5); --drive force pushes each slide by 2e4 (s_ref - s) - 500 s' N.  Gravity along -z, from
rest.  CSV: t, x, y, z, qw, qx, qy, qz (the platform's centre and orientation) then f1 ... f6
(the legs' drive forces, N) every 0.01 s.
"""
import argparse
import sys
from pathlib import Path

import numpy as np

from dttmm import simulate
from dttmm.model.mechanisms import stewart_platform
from dttmm.results.result import rotation_to_quaternion


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--drive", choices=["motion", "force"], default="motion",
                    help="prescribed slides (default) or forces tracking them")
    ap.add_argument("--t-end", type=float, default=3.0, help="end time, s (default 3)")
    ap.add_argument("--dt", type=float, default=1e-4, help="time step, s (default 1e-4)")
    ap.add_argument("--csv", help="write t, x, y, z, qw, qx, qy, qz, f1..f6 every 0.01 s")
    ap.add_argument("--plots", help="directory for the figure (PNG)")
    args = ap.parse_args(argv)

    model = stewart_platform(args.drive)
    every = max(1, int(round(0.01 / args.dt)))
    try:
        res = simulate(model, args.t_end, args.dt, record_every=every)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    k = model.body_names.index("platform")
    centre = res.position_mass_center[:, k]
    quat = np.array([rotation_to_quaternion(r) for r in res.rotation[:, k]])
    slides = [model.hinge_names.index(f"P{i + 1}") for i in range(6)]
    names = list(res.info["coordinate_names"])
    columns = [names.index(model.hinge_names[j]) for j in slides]
    force = res.drive_force[:, columns]
    print(f"Stewart platform, {args.drive} drive, {res.n_steps} steps of {args.dt:g} s "
          f"({res.info['loop']} loop): {res.wall_time:.3f} s wall, "
          f"{1e6 * res.wall_time / res.n_steps:.0f} us/step")
    print(f"  platform centre at t = {res.t[-1]:g} s: {np.array2string(centre[-1], precision=9)} m;"
          f" leg forces {np.array2string(force[-1], precision=3)} N")
    info = res.info
    print(f"  loop residuals after every step: positions {info['loop_position_residual']:.2e} m, "
          f"rates {info['loop_rate_residual']:.2e} m/s")
    if args.csv:
        data = np.column_stack([res.t, centre, quat, force])
        head = "t,x,y,z,qw,qx,qy,qz," + ",".join(f"f{i + 1}" for i in range(6))
        np.savetxt(args.csv, data, delimiter=",", comments="", fmt="%.12g", header=head)
        print(f"wrote {args.csv}")
    if args.plots:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        out = Path(args.plots)
        out.mkdir(parents=True, exist_ok=True)
        fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
        for i, c in enumerate("xyz"):
            ax[0].plot(res.t, centre[:, i] - centre[0, i], lw=0.9, label=f"{c} - {c}(0)")
        ax[0].set(xlabel="t, s", ylabel="m", title="Platform centre")
        ax[0].legend(fontsize=8)
        for i in range(6):
            ax[1].plot(res.t, force[:, i], lw=0.9, label=f"leg {i + 1}")
        ax[1].set(xlabel="t, s", ylabel="N", title="Leg drive forces")
        ax[1].legend(fontsize=7, ncol=2)
        fig.suptitle(f"Stewart platform, {args.drive} drive (DT-TMM, dt = {args.dt:g} s)")
        fig.tight_layout()
        path = out / "stewart.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
