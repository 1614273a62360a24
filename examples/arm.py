"""A driven arm on revolute, universal and prismatic joints, by DT-TMM.

    python examples/arm.py --t-end 2 --dt 1e-4 --drive torque --csv arm.csv --plots figures

Link 1 turns on a revolute joint about world y (driven: a torque 2 sin(pi t) N m, the angle
0.5 t + 0.2 (1 - cos 2t) rad prescribed, or PD feedback tracking that angle, kp = 200 N m/rad,
kd = 20 N m s/rad, inside the compiled loop: --drive pd as dttmm.PDTracking, --drive pd-njit
as the same law written as an @numba.njit JointForce, dttmm.model.chains.arm_servo); link 2 on a
revolute joint about link 1's z axis; link 3 on a universal joint (link 2's z, then link 3's
y); body 4 slides along link 3's x axis on a 50 N/m spring with a 0.5 N s/m damper
(dttmm.model.chains.arm).  --flexible makes link 2 the paper's beam 4.  The joints' coordinates
carry the integration and the step is swept leaves to root in full state (docs/joints.md).
CSV: t, x1, y1, z1, x2, y2, z2, x3, y3, z3 (links 1-3's output points), x4, y4, z4 (body 4's
mass centre), s4 (its slide from the start, m), tau1 (joint 1's torque: applied, needed by the
prescribed motion, or the feedback's, N m), every 0.01 s.
"""
import argparse
import sys
from pathlib import Path

import numpy as np

from dttmm import simulate
from dttmm.model.chains import arm


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=2.0, help="end time, s (default 2)")
    ap.add_argument("--dt", type=float, default=1e-4, help="time step, s (default 1e-4)")
    ap.add_argument("--method", choices=["riccati", "direct"], default="riccati",
                    help="assembly (joints with coordinates need riccati)")
    ap.add_argument("--drive", choices=["torque", "motion", "pd", "pd-njit"], default="torque",
                    help="joint 1: a torque 2 sin(pi t) N m (default), its angle prescribed, or "
                         "PD feedback tracking that angle (a PDTracking, or the law as a "
                         "numba-compiled JointForce)")
    ap.add_argument("--flexible", action="store_true", help="link 2 is the paper's beam 4")
    ap.add_argument("--csv", help="write the CSV columns above every 0.01 s")
    ap.add_argument("--plots", help="directory for the figures (PNG)")
    args = ap.parse_args(argv)

    model = arm(args.drive, args.flexible)
    every = max(1, int(round(0.01 / args.dt)))
    try:
        res = simulate(model, args.t_end, args.dt, method=args.method, record_every=every)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    slide = res.joint_coordinates[:, -1] - res.joint_coordinates[0, -1]
    tau1 = res.drive_force[:, 0]
    kind = "flexible" if args.flexible else "rigid"
    print(f"arm ({kind}, drive {args.drive}), {res.n_steps} steps of {args.dt:g} s by "
          f"{res.info['mode']} ({res.info['loop']} loop): {res.wall_time:.3f} s wall, "
          f"{1e6 * res.wall_time / res.n_steps:.1f} us/step, at most "
          f"{res.info['newton_iterations_used']} Newton iterations")
    for k, name in enumerate(model.body_names[:3]):
        print(f"  {name} output at t = {res.t[-1]:g} s: "
              f"{np.array2string(res.position_output[-1, k], precision=6)} m")
    print(f"  body4 mass centre: {np.array2string(res.position_mass_center[-1, 3], precision=6)}"
          f" m, slide {slide[-1]:.6f} m")
    print(f"joint 1 torque: {tau1[-1]:.6f} N m at the end, peak {np.abs(tau1).max():.4f} N m")
    if args.csv:
        head = "t,x1,y1,z1,x2,y2,z2,x3,y3,z3,x4,y4,z4,s4,tau1"
        data = np.column_stack([res.t, res.position_output[:, :3].reshape(len(res.t), -1),
                                res.position_mass_center[:, 3], slide, tau1])
        np.savetxt(args.csv, data, delimiter=",", header=head, comments="", fmt="%.12g")
        print(f"wrote {args.csv}")
    if args.plots:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        out = Path(args.plots)
        out.mkdir(parents=True, exist_ok=True)
        fig, ax = plt.subplots(2, 2, figsize=(12, 8))
        for k, name in enumerate(model.body_names[:3]):
            p = res.position_output[:, k]
            ax[0, 0].plot(p[:, 0], p[:, 2], lw=0.9, label=f"{name} output")
        p4 = res.position_mass_center[:, 3]
        ax[0, 0].plot(p4[:, 0], p4[:, 2], lw=0.9, label="body4 mass centre")
        ax[0, 0].set(xlabel="x, m", ylabel="z, m", aspect="equal", title="Seen from above")
        ax[0, 0].legend(fontsize=7)
        for k, name in enumerate(model.body_names[:3]):
            ax[0, 1].plot(res.t, res.position_output[:, k, 1], lw=0.9, label=f"{name} output")
        ax[0, 1].plot(res.t, p4[:, 1], lw=0.9, label="body4 mass centre")
        ax[0, 1].set(xlabel="t, s", ylabel="y, m", title="Heights")
        ax[0, 1].legend(fontsize=7)
        names = ["joint1 (rad)", "joint2 (rad)", "joint3 axis 1 (rad)", "joint3 axis 2 (rad)"]
        for c, name in enumerate(names):
            ax[1, 0].plot(res.t, res.joint_coordinates[:, c], lw=0.9, label=name)
        ax[1, 0].plot(res.t, 10.0 * slide, lw=0.9, label="joint4 slide x 10 (m)")
        ax[1, 0].set(xlabel="t, s", ylabel="coordinate", title="Joint coordinates")
        ax[1, 0].legend(fontsize=7)
        ax[1, 1].plot(res.t, tau1, lw=0.9)
        ax[1, 1].set(xlabel="t, s", ylabel="N m",
                     title="Joint 1 torque (" + {"torque": "applied",
                                                 "motion": "needed by the prescribed angle",
                                                 "pd": "the PD feedback's",
                                                 "pd-njit": "the compiled PD law's"}[args.drive]
                     + ")")
        fig.suptitle(f"Arm on revolute, universal and prismatic joints ({kind} link 2, "
                     f"drive {args.drive}; DT-TMM, dt = {args.dt:g} s)")
        fig.tight_layout()
        path = out / f"arm_{args.drive}{'_flexible' if args.flexible else ''}.png"
        fig.savefig(path, dpi=100)
        plt.close(fig)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
