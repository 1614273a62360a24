"""The elastica: a cantilever rolled up by a tip moment, by DT-TMM's static solve.

    python examples/elastica.py --elements 16 --steps 8 --csv elastica.csv --plots figs

A cantilever (L = 1 m, EI = 100 N m^2) clamped along x carries at its tip a moment
M = lam 2 pi EI / L about z, lam = 1/steps .. 1 (--steps, --lam-max): K welded beam elements
(--elements, with geometric stiffening, --modes per plane), or with --kind rod strain rods
(docs/strain_rod.md: --modes strain coefficients per plane; one rod of one coefficient holds the
constant curvature exactly: `--kind rod --elements 1 --modes 1 --steps 4` closes the circle to
1e-14 m), and a light body welded to the tip that carries the moment.  Each load step starts
from the last one's equilibrium (dttmm.static_equilibrium, guess=).  The exact centre line is
a circular arc of curvature M / EI: the tip at (L sin phi / phi, L (1 - cos phi) / phi),
phi = M L / EI = 2 pi lam, so at lam = 1 the beam closes into a circle.  CSV: lam, body, x, y,
z (the centre line's points, m); the table printed: the tip and its distance from the exact
tip per step.

With the moment about a fixed world axis, the static solve flags the equilibria past about
three quarters of a turn as unstable (a disturbance out of the plane grows: the moment does
not follow the tip section); the in-plane shape is still the equilibrium.
"""
import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

from dttmm import (EulerBernoulliBeam, FixedHinge, RigidBody, StrainRod, build_chain,
                   static_equilibrium)

LENGTH, EI = 1.0, 100.0


def cantilever(elements=16, moment=0.0, modes=2, kind="modal"):
    """K welded elements clamped along x and a light tip body carrying the moment about z, N m
    (no gravity): stiffened modal beams of `modes` per plane (kind "modal") or strain rods of
    `modes` strain coefficients per plane (kind "rod": a constant curvature is exact with one
    of one coefficient)."""
    if kind not in ("modal", "rod"):
        raise ValueError(f"cantilever: kind must be 'modal' or 'rod', not {kind!r}")
    parts = []
    for k in range(elements):
        common = dict(length=LENGTH / elements, bending_stiffness=EI,
                      polar_inertia_per_length=1e-4, mass_per_length=1.0,
                      name=f"element{k + 1}")
        element = (StrainRod(strain_modes=modes, **common) if kind == "rod" else
                   EulerBernoulliBeam(modes_per_plane=modes, stiffening=True, **common))
        parts += [FixedHinge(), element]
    parts += [FixedHinge(),
              RigidBody(mass=1.0, inertia=[1e-2] * 3, inertia_about="mass_center",
                        to_mass_center=[0, 0, 0], to_output=[0, 0, 0], name="tip",
                        torque=lambda t: [0.0, 0.0, moment])]
    return build_chain(parts, gravity=[0.0, 0.0, 0.0])


def exact_tip(lam):
    phi = 2.0 * np.pi * lam
    return np.array([LENGTH * np.sin(phi) / phi, LENGTH * (1.0 - np.cos(phi)) / phi, 0.0])


def roll_up(elements=16, steps=8, modes=2, lam_max=1.0, kind="modal"):
    """[(lam, StaticEquilibrium)] for lam = lam_max / steps .. lam_max."""
    out, guess = [], None
    for lam in lam_max * np.arange(1, steps + 1) / steps:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")           # the out-of-plane flag: see the docstring
            guess = static_equilibrium(cantilever(elements, lam * 2 * np.pi * EI / LENGTH,
                                                  modes, kind), guess=guess)
        out.append((lam, guess))
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elements", type=int, default=16, help="beam elements (default 16)")
    parser.add_argument("--steps", type=int, default=8, help="load steps to lam = 1 (default 8)")
    parser.add_argument("--modes", type=int, default=2,
                        help="modes per plane (a rod's strain coefficients; default 2)")
    parser.add_argument("--kind", choices=("modal", "rod"), default="modal",
                        help="the element: the modal beam (default) or the strain rod (one rod "
                             "of --modes 1 is exact)")
    parser.add_argument("--lam-max", type=float, default=1.0,
                        help="the last step's lam (default 1: the full circle)")
    parser.add_argument("--csv", help="write lam, body, x, y, z of the centre lines here")
    parser.add_argument("--plots", help="write elastica.png into this directory")
    args = parser.parse_args(argv)
    if args.elements < 1 or args.steps < 1:
        parser.error("--elements and --steps must be at least 1")
    runs = roll_up(args.elements, args.steps, args.modes, args.lam_max, args.kind)
    # points per element, for the CSV and the figure (a rod's arc is exact between them)
    points = max(9, 161 // args.elements) if args.kind == "rod" else 9
    print(f"{'lam':>6} {'phi (rad)':>10} {'tip x (m)':>11} {'tip y (m)':>11} "
          f"{'error (m)':>10} {'stable':>7} {'iterations':>10}")
    for lam, eq in runs:
        tip = eq.positions()[2][-1]
        print(f"{lam:6.3f} {2 * np.pi * lam:10.4f} {tip[0]:11.6f} {tip[1]:11.6f} "
              f"{np.linalg.norm(tip - exact_tip(lam)):10.2e} {str(eq.stable):>7} "
              f"{eq.iterations:10d}")
    if args.csv:
        rows = [(lam, k, *p) for lam, eq in runs
                for k, line in enumerate(eq.centreline(points)) for p in line]
        np.savetxt(args.csv, np.array(rows), delimiter=",", header="lam,body,x,y,z",
                   comments="", fmt=["%.6g", "%d", "%.9g", "%.9g", "%.9g"])
        print(f"wrote {args.csv}")
    if args.plots:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        Path(args.plots).mkdir(parents=True, exist_ok=True)
        fig, ax = plt.subplots(figsize=(8.6, 5.2))
        colours = plt.cm.viridis(np.linspace(0.0, 0.9, len(runs)))
        s = np.linspace(0.0, 1.0, 200)
        for (lam, eq), colour in zip(runs, colours):
            line = np.concatenate(eq.centreline(points))
            ax.plot(line[:, 0], line[:, 1], color=colour, lw=2.0,
                    label=f"M = {lam:.3g} x 2 pi EI/L")
            phi = 2.0 * np.pi * lam
            ax.plot(np.sin(phi * s) / phi, (1.0 - np.cos(phi * s)) / phi, "k:", lw=0.8)
        ax.plot([], [], "k:", lw=0.8, label="exact (circular arcs)")
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        what = "strain rod" if args.kind == "rod" else "modal beam element"
        ax.set_title(f"Elastica: cantilever under a tip moment, {args.elements} {what}"
                     f"{'s' if args.elements > 1 else ''}, static solve")
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
        ax.grid(alpha=0.3)
        fig.tight_layout()
        out = Path(args.plots) / "elastica.png"
        fig.savefig(out, dpi=110)
        print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
