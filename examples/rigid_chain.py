"""N-link rigid ball-joint chain falling under gravity, by DT-TMM.

    python examples/rigid_chain.py --links 3 --t-end 2 --dt 1e-3 --csv chain.csv --plot chain.png
"""
import argparse
import sys

import numpy as np

from dttmm import simulate
from dttmm.model.chains import rigid_chain


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--links", type=int, default=3, help="number of links N")
    ap.add_argument("--t-end", type=float, default=2.0, help="end time, s")
    ap.add_argument("--dt", type=float, default=1e-3, help="time step, s")
    ap.add_argument("--method", choices=["direct", "riccati"], default="riccati")
    ap.add_argument("--scheme", choices=["newmark", "energy_momentum"], default="newmark",
                    help="time step: generalized-alpha Newmark, or the energy-momentum scheme "
                         "(conserves energy and angular momentum exactly)")
    ap.add_argument("--rho-inf", type=float, default=1.0,
                    help="generalized-alpha rho_inf (Newmark scheme)")
    ap.add_argument("--record-every", type=int, default=1, help="keep every k-th step")
    ap.add_argument("--richardson", action="store_true",
                    help="run at dt and dt/2 and extrapolate (fourth order; Newmark scheme)")
    ap.add_argument("--csv", help="write t, x1, y1, z1, ..., xN, yN, zN (output points)")
    ap.add_argument("--plot", help="draw the output points' paths to this PNG")
    args = ap.parse_args(argv)

    model = rigid_chain(args.links)
    simulate(model, args.dt, args.dt, method=args.method, scheme=args.scheme)   # load the
    # compiled kernels first (numba's cache), so that the timing below is the stepping's
    res = simulate(model, args.t_end, args.dt, method=args.method, scheme=args.scheme,
                   rho_inf=args.rho_inf, record_every=args.record_every,
                   richardson=args.richardson)
    n = model.n_bodies
    e = res.total_energy
    steps = (f"{res.n_steps} steps of {args.dt:g} and {args.dt / 2:g} s (Richardson)"
             if args.richardson else f"{res.n_steps} steps of {args.dt:g} s")
    print(f"{n}-link chain, {steps} ({args.scheme}) by {res.info['mode']}: "
          f"{res.wall_time:.3f} s wall, {1e6 * res.wall_time / res.n_steps:.1f} us/step")
    if args.richardson:
        print(f"Richardson correction: {res.info['richardson_correction_m']:.2e} m")
    tip = np.array2string(res.position_output[-1, -1], precision=6)
    print(f"tip at t = {res.t[-1]:g} s: {tip} m")
    print(f"energy drift: {np.abs(e - e[0]).max():.3e} J (largest kinetic energy "
          f"{res.kinetic.max():.3f} J)")
    if args.csv:
        head = ",".join(["t"] + [f"{c}{k + 1}" for k in range(n) for c in "xyz"])
        data = np.column_stack([res.t, res.position_output.reshape(len(res.t), -1)])
        np.savetxt(args.csv, data, delimiter=",", header=head, comments="", fmt="%.12g")
        print(f"wrote {args.csv}")
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(1, 2, figsize=(10, 4.5))
        for k in range(n):
            ax[0].plot(res.position_output[:, k, 0], res.position_output[:, k, 1], lw=0.8,
                       label=f"link {k + 1}")
            ax[1].plot(res.t, res.position_output[:, k, 2], lw=0.8)
        ax[0].set(xlabel="x, m", ylabel="y, m", title="output points, x-y", aspect="equal")
        ax[1].set(xlabel="t, s", ylabel="z, m", title="out of plane")
        if n <= 10:
            ax[0].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(args.plot, dpi=110)
        print(f"wrote {args.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
