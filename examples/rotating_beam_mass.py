"""Seed 000's rotating beam no. 2: a 5 m aluminium tube carrying a 5 kg mass on a 1 m arm,
hanging in gravity, then spun up on its hub, by DT-TMM.

    python examples/rotating_beam_mass.py --elements 1 --t-end 20 --csv beam_mass.csv --plots figs

The tube (rho = 3000 kg/m^3, L = 5 m, E = 6.9e10 Pa, G = 2.6e10 Pa, hollow circular section
R = 0.0326 m, r = 0.0306 m) is clamped along x to a hub that turns about the vertical z axis;
a 5 kg point mass sits on a massless 1 m arm welded to the tip, perpendicular to the tube and
horizontal (along y), gravity -z.  The tube bends in two planes, twists (its torsion modes,
docs/beam.md "Torsion": the mass's weight twists it by about m g L_arm L / (G J) = 0.024 rad)
and is stiffened by its axial force (geometric stiffening).  First the static equilibrium
(dttmm.static_equilibrium: the tube sags about 0.25 m at the tip under its own and the mass's
weight), then from rest there the hub follows the spin-up law of rotating beam no. 1,
theta(t) = (omega / T)(t^2 / 2 + (T / 2 pi)^2 (cos(2 pi t / T) - 1)) for t <= T = 15 s, then
omega (t - T / 2).  K elements of L / K welded end to end (--elements), each with --modes
bending modes per plane and --twist twist modes.  CSV: t, tip_x, tip_y, tip_z, mass_x, mass_y,
mass_z, the tube's tip and the mass in the hub's rotating frame (m).

The step damps what it does not resolve (generalized-alpha, --rho-inf 0.9): the tube's higher
bending and twist modes (hundreds of Hz against dt = 1e-3 s).  One element meets the
Newton-Euler reference on the same model to 9e-8 m at dt 1e-3, with rho_inf 0.9 or 1 alike:
the arm, and each element of a welded chain, follows its inboard's end section exactly
(docs/beam.md "End sections"; integrated on their own, their angular accelerations alternated
from step to step, and with --rho-inf 1 the run grew away near t = 11 s).
"""
import argparse
import sys
from pathlib import Path

import numpy as np

from dttmm import (EulerBernoulliBeam, FixedHinge, Ground, PrescribedMotion, RigidBody,
                   build_chain, simulate, static_equilibrium)
from dttmm.model.profiles import profile

LENGTH, DENSITY, YOUNG, SHEAR = 5.0, 3000.0, 6.9e10, 2.6e10
R_OUT, R_IN = 0.0326, 0.0306
PERIOD = 15.0
MASS, ARM = 5.0, 1.0


def beam_with_mass(elements=1, modes=3, twist=2, omega=6.0):
    """The hub (a prescribed spin about z, at rest at t = 0), the tube of `elements` welded
    elements and the mass on its arm welded to the tip."""
    area = np.pi * (R_OUT ** 2 - R_IN ** 2)
    inertia = np.pi / 4 * (R_OUT ** 4 - R_IN ** 4)        # I of the section; I_p = 2 I
    angle = profile({"profile": "spin_up", "omega": omega, "period": PERIOD})
    hub = PrescribedMotion.spin_about_axis([0, 0, 1], angle, angle.rate, angle.acceleration)
    parts = []
    for k in range(elements):
        parts += [FixedHinge(),
                  EulerBernoulliBeam(length=LENGTH / elements, density=DENSITY, area=area,
                                     bending_stiffness=YOUNG * inertia,
                                     polar_inertia_per_length=DENSITY * 2 * inertia,
                                     torsional_stiffness=SHEAR * 2 * inertia,
                                     modes_per_plane=modes, torsion_modes=twist,
                                     stiffening=True, name=f"tube{k + 1}")]
    # the point mass on its massless arm: a rigid body whose mass centre is 1 m along y
    # (a small inertia of its own keeps it a body: 1e-6 kg m^2, a point for the motion)
    parts += [FixedHinge(), RigidBody(mass=MASS, inertia=np.eye(3) * 1e-6,
                                      inertia_about="mass_center",
                                      to_mass_center=(0.0, ARM, 0.0), name="mass")]
    return build_chain(parts, gravity=[0.0, 0.0, -9.81], ground=Ground(motion=hub))


def in_hub_frame(model, res):
    """(tip, mass), each (T, 3): the tube's tip and the mass in the hub's rotating frame, m."""
    rot = np.array([model.ground_state(t)[3] for t in res.t])
    tip = res.position_output[:, -2]
    mass = res.position_mass_center[:, -1]
    return np.einsum("tji,tj->ti", rot, tip), np.einsum("tji,tj->ti", rot, mass)


def run(elements=1, modes=3, twist=2, omega=6.0, t_end=20.0, dt=1e-3, rho_inf=0.9,
        record_dt=0.01):
    """The static equilibrium, then the spin-up from it: (equilibrium, model, result)."""
    equilibrium = static_equilibrium(beam_with_mass(elements, modes, twist, omega))
    model = equilibrium.model
    return equilibrium, model, simulate(model, t_end, dt, rho_inf=rho_inf, record_dt=record_dt)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--omega", type=float, default=6.0, help="final hub speed, rad/s (6)")
    ap.add_argument("--elements", type=int, default=1, help="welded elements (1)")
    ap.add_argument("--modes", type=int, default=3, help="bending modes per plane (3)")
    ap.add_argument("--twist", type=int, default=2, help="twist modes per element (2)")
    ap.add_argument("--t-end", type=float, default=20.0, help="end time, s (20)")
    ap.add_argument("--dt", type=float, default=1e-3, help="time step, s (1e-3)")
    ap.add_argument("--rho-inf", type=float, default=0.9,
                    help="the step's damping of unresolved modes, 1 = none (0.9)")
    ap.add_argument("--csv", help="write t, tip_x, tip_y, tip_z, mass_x, mass_y, mass_z "
                                  "every 0.01 s")
    ap.add_argument("--plots", help="directory for the figure (PNG)")
    args = ap.parse_args(argv)

    equilibrium, model, res = run(args.elements, args.modes, args.twist, args.omega,
                                  args.t_end, args.dt, args.rho_inf)
    tip, mass = in_hub_frame(model, res)
    lowest = equilibrium.frequencies[np.isfinite(equilibrium.frequencies)
                                     & (equilibrium.frequencies > 1e-6)][:3]
    print(f"static equilibrium: {equilibrium.iterations} iterations, "
          f"{'stable' if equilibrium.stable else 'UNSTABLE'}; tip at {np.round(tip[0], 4)} m, "
          f"mass at {np.round(mass[0], 4)} m; lowest frequencies {np.round(lowest, 3)} Hz")
    print(f"spin-up to {args.omega:g} rad/s, {args.elements} element(s) x {args.modes} modes "
          f"per plane, {args.twist} twist: {res.n_steps} steps of {args.dt:g} s, "
          f"{res.wall_time:.2f} s wall")
    for name, p in (("tip", tip), ("mass", mass)):
        print(f"  {name:4}: y from {p[:, 1].min():.4f} to {p[:, 1].max():.4f} m, z from "
              f"{p[:, 2].min():.4f} to {p[:, 2].max():.4f} m; at the end "
              f"{np.round(p[-1], 4)} m")
    if args.csv:
        np.savetxt(args.csv, np.column_stack([res.t, tip, mass]), delimiter=",",
                   header="t,tip_x,tip_y,tip_z,mass_x,mass_y,mass_z", comments="", fmt="%.12g")
        print(f"wrote {args.csv}")
    if args.plots:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        out = Path(args.plots)
        out.mkdir(parents=True, exist_ok=True)
        fig, ax = plt.subplots(3, 2, figsize=(10, 8), sharex=True, constrained_layout=True)
        for j, (name, p) in enumerate((("tube tip", tip), ("mass", mass))):
            for i, axis in enumerate("xyz"):
                ax[i, j].plot(res.t, p[:, i])
                ax[i, j].set(ylabel=f"{axis} of the {name} (m)")
                ax[i, j].grid(alpha=0.3)
            ax[2, j].set(xlabel="t (s)")
        fig.suptitle(f"Rotating beam with an off-centred mass, spun up to {args.omega:g} rad/s: "
                     f"hub frame ({args.elements} element(s), {args.modes} modes per plane, "
                     f"{args.twist} twist)")
        path = out / "rotating_beam_mass.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
