"""Seed 000's rotating beam no. 1: a 10 m aluminium tube on a hub spun up to omega, by DT-TMM.

    python examples/spin_up.py --omega 6 --elements 20 --t-end 20 --csv spin_up.csv --plots figs

The hub turns about the vertical z axis by the spin-up law theta(t) = (omega / T)(t^2 / 2 +
(T / 2 pi)^2 (cos(2 pi t / T) - 1)) for t <= T = 15 s, then omega (t - T / 2)
(dttmm.model.profiles, "spin_up"); the tube (rho = 3000 kg/m^3, L = 10 m, E = 6.9e10 Pa, hollow
circular section R = 0.0326 m, r = 0.0306 m) is clamped to it along x, no gravity, as K
elements of L / K welded end to end (--elements), each with --modes modes per plane; or, with
--kind rod, K strain rods (docs/strain_rod.md) of --modes strain coefficients per plane (their
curvature a polynomial field, the centre line its exponential: the spin's stiffening comes from
the exact kinematics).  CSV:
t, u_tip (the tip's displacement along the beam from the undeformed length, m), v_tip (its
lateral deflection in the plane of rotation, m), both in the hub's rotating frame.

The known result: v_tip dips to about -0.58 m near t = 6.8 s and returns close to zero.  One
element follows it, since the beam's geometric stiffening (docs/beam.md) carries
the centrifugal stiffening; with --no-stiffening (the paper's beam) one element's deflection
grows without bound once spun past its first bending frequency (3.8 rad/s) and the run stops
with DivergenceError, and only a chain of about 20 elements gets there, as their frames carry
the stiffening between them.
"""
import argparse
import sys
from pathlib import Path

import numpy as np

from dttmm import (DivergenceError, EulerBernoulliBeam, FixedHinge, Ground, PrescribedMotion,
                   StrainRod, build_chain, simulate)
from dttmm.model.profiles import profile

LENGTH, DENSITY, YOUNG = 10.0, 3000.0, 6.9e10
R_OUT, R_IN = 0.0326, 0.0306
PERIOD = 15.0


def tube(elements=1, modes=3, omega=6.0, stiffening=True, kind="modal"):
    """The hub (a prescribed spin about z) and the tube of `elements` welded elements: modal
    Euler-Bernoulli beams (kind "modal"; stiffening: their geometric stiffening) or strain rods
    (kind "rod"; `modes` strain coefficients per plane)."""
    if kind not in ("modal", "rod"):
        raise ValueError(f"tube: kind must be 'modal' or 'rod', not {kind!r}")
    area = np.pi * (R_OUT ** 2 - R_IN ** 2)
    inertia = np.pi / 4 * (R_OUT ** 4 - R_IN ** 4)
    angle = profile({"profile": "spin_up", "omega": omega, "period": PERIOD})
    hub = PrescribedMotion.spin_about_axis([0, 0, 1], angle, angle.rate, angle.acceleration)
    parts = []
    for k in range(elements):
        common = dict(length=LENGTH / elements, bending_stiffness=YOUNG * inertia,
                      polar_inertia_per_length=DENSITY * 2 * inertia, name=f"tube{k + 1}")
        if kind == "rod":
            element = StrainRod(mass_per_length=DENSITY * area, strain_modes=modes, **common)
        else:
            element = EulerBernoulliBeam(density=DENSITY, area=area, modes_per_plane=modes,
                                         stiffening=stiffening, **common)
        parts += [FixedHinge(), element]
    return build_chain(parts, gravity=[0.0, 0.0, 0.0], ground=Ground(motion=hub))


def tip_in_hub_frame(model, res):
    """(u_tip, v_tip): the tip's displacement along the beam from L and its lateral
    deflection, in the hub's rotating frame, m."""
    tip = res.position_output[:, -1]
    rot = np.array([model.ground_state(t)[3] for t in res.t])
    local = np.einsum("tji,tj->ti", rot, tip)
    return local[:, 0] - LENGTH, local[:, 1]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--omega", type=float, default=6.0, help="final hub speed, rad/s (6)")
    ap.add_argument("--elements", type=int, default=1, help="welded elements (1)")
    ap.add_argument("--modes", type=int, default=3,
                    help="modes per plane per element (a rod's strain coefficients; 3)")
    ap.add_argument("--kind", choices=("modal", "rod"), default="modal",
                    help="the element: the modal Euler-Bernoulli beam (default) or the strain "
                         "rod")
    ap.add_argument("--t-end", type=float, default=20.0, help="end time, s (20)")
    ap.add_argument("--dt", type=float, default=1e-3, help="time step, s (1e-3)")
    ap.add_argument("--no-stiffening", action="store_true",
                    help="the paper's beam, without geometric stiffening")
    ap.add_argument("--csv", help="write t, u_tip, v_tip every 0.01 s (those before a stop)")
    ap.add_argument("--plots", help="directory for the figure (PNG)")
    args = ap.parse_args(argv)

    model = tube(args.elements, args.modes, args.omega, not args.no_stiffening, args.kind)
    stopped = False
    try:
        res = simulate(model, args.t_end, args.dt, record_dt=0.01)
    except DivergenceError as err:
        stopped = True
        print(f"stopped: {err}\n(a beam without geometric stiffening cannot follow a spin "
              f"past its first frequency: drop --no-stiffening, or try --elements 20)",
              file=sys.stderr)
        res = err.partial
        if res is None or len(res.t) < 2:
            return 1
    u, v = tip_in_hub_frame(model, res)
    low = int(np.argmin(v))
    print(f"spin-up to {args.omega:g} rad/s, {args.elements} {args.kind} element(s) x "
          f"{args.modes} modes: "
          f"{res.n_steps} steps of {args.dt:g} s, {res.wall_time:.2f} s wall; v_tip minimum "
          f"{v[low]:.4f} m at t = {res.t[low]:.2f} s, at the end {v[-1]:.4f} m; u_tip at the "
          f"end {u[-1]:.5f} m")
    if args.csv:
        np.savetxt(args.csv, np.column_stack([res.t, u, v]), delimiter=",",
                   header="t,u_tip,v_tip", comments="", fmt="%.12g")
        print(f"wrote {args.csv}")
    if args.plots:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        out = Path(args.plots)
        out.mkdir(parents=True, exist_ok=True)
        fig, ax = plt.subplots(2, 1, figsize=(8, 6), sharex=True, constrained_layout=True)
        ax[0].plot(res.t, v)
        ax[0].set(ylabel="v_tip (m)", title=f"Spin-up to {args.omega:g} rad/s: the tip in the "
                  f"hub frame ({args.elements} {args.kind} element(s), {args.modes} "
                  f"{'strain coefficients' if args.kind == 'rod' else 'modes'} per plane)")
        ax[1].plot(res.t, u)
        ax[1].set(xlabel="t (s)", ylabel="u_tip (m)")
        for a in ax:
            a.grid(alpha=0.3)
        path = out / "spin_up.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        print(f"wrote {path}")
    return 1 if stopped else 0


if __name__ == "__main__":
    sys.exit(main())
