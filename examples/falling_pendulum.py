"""The soft falling pendulum: a flexible beam pinned at one end falls from the horizontal.

    python examples/falling_pendulum.py --csv tip.csv --plots figs

Berzeri and Shabana's ANCF benchmark (also seed 002's falling pendulum): a beam of 1.2 m,
cross-section area 0.0018 m^2, second moment of area 1.215e-8 m^4 in both planes, density
5540 kg/m^3 and Young's modulus 0.7e6 Pa (EI = 8.5e-3 N m^2: it hangs like a rope), axial
stiffness EA = 1e6 N (--axial-stiffness; the benchmark's original E A = 1260 N as a second
case; "rigid" for an inextensible centre line), pinned to the ground at the origin by a ball
joint, lies along +x at rest at t = 0 and falls under gravity, 9.81 m/s^2 along -y.  Around
t = 0.4 s its tip whips past the pin at ~20 m/s.

The beam is K welded modal Euler-Bernoulli elements (--elements, default 32) of --modes per
plane (default 2, the beam's own default) with geometric stiffening, its foreshortening kept to
all orders (--stiffening exact, the default here; docs/beam.md, "The exact foreshortening"),
one stretch mode each where EA is given; or, with --kind rod, K strain rods (docs/strain_rod.md:
a curvature field of --modes coefficients per plane, the configuration the exponential of the
strain, one stretch coefficient field where EA is given); --reference runs the Newton-Euler
reference instead of DT-TMM (DOP853 at rtol 1e-8; --dt unused).  Measured over 1 s in DT-TMM
(dt = 1e-4 s): 8 rods of linear strain within 9.5e-3 m of 32 modal elements at the tip (EA =
1e6, and inextensible alike), 4.7 s against 5.4 s of wall time (a rod's step costs ~2.4 modal
elements'); 8 against 16 rods 7.2e-3 m, 16 rods against the 32 modal 6.3e-3 m; dt = 1e-4
against 5e-5 s 3.1e-6 m; the energy kept to 2.0e-6 of the
largest kinetic energy.  Printed: the tip every 0.1 s, the total energy's
largest change over the run as a fraction of the largest kinetic energy (nothing dissipates or
works: it should stay near zero), and the wall time.  --csv: t, tip_x, tip_y every 1 ms;
--plots: falling_pendulum.png, the beam's centre line every 0.1 s.

Why exact: the beam's default stiffening keeps its kinetic energy to second order in the
modes, which stops being positive once an element bends more than ~0.17 rad over its length
with two modes per plane, ~0.95 rad with one (docs/beam.md, "Where the second-order energy
stops"); at the whip the tip elements bend that far, and such a run stops there and says so
(--stiffening second-order).  Measured (docs/beam.md), dt = 1e-4 s over 1 s: the defaults
(32 x 2, exact, EA = 1e6) run through in 6 s with the energy kept to 2.7e-6 of the largest
kinetic energy, the tip within 5.3e-3 m of 96 second-order elements of one mode; second-order
with one mode per plane, 48 elements run through and 32 stop at t = 0.47 s.  A run that stops
says so, prints what it had, and returns 1.
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

from dttmm import (BallJoint, DivergenceError, EulerBernoulliBeam, FixedHinge, StrainRod,
                   build_chain, simulate, simulate_reference)

LENGTH, AREA, SECOND_MOMENT, DENSITY, YOUNG = 1.2, 0.0018, 1.215e-8, 5540.0, 0.7e6
GRAVITY = 9.81
# the modal Euler-Bernoulli beam, or the strain rod (docs/strain_rod.md: its curvature a
# polynomial field of `modes` coefficients per plane, a constant curvature exact in one
# element)
KINDS = ("modal", "rod")


def pendulum(elements=32, kind="modal", modes=2, axial_stiffness=1e6, exact=True):
    """The pendulum as `elements` welded beam elements (kind "modal") or strain rods (kind
    "rod") behind a ball joint at the origin; axial_stiffness None: an inextensible centre
    line; exact: the modal beam's foreshortening to all orders (stiffening="exact")."""
    if kind not in KINDS:
        raise ValueError(f"pendulum: kind must be one of {KINDS}, not {kind!r}")
    parts = []
    for k in range(elements):
        joint = BallJoint(name="pin") if k == 0 else FixedHinge(name=f"weld{k}")
        common = dict(length=LENGTH / elements, bending_stiffness=YOUNG * SECOND_MOMENT,
                      mass_per_length=DENSITY * AREA,
                      polar_inertia_per_length=DENSITY * 2 * SECOND_MOMENT,
                      axial_stiffness=axial_stiffness, name=f"element{k + 1}")
        if kind == "rod":
            element = StrainRod(strain_modes=modes, stretch=axial_stiffness is not None,
                                **common)
        else:
            element = EulerBernoulliBeam(modes_per_plane=modes,
                                         stiffening="exact" if exact else True,
                                         axial_modes=0 if axial_stiffness is None else 1,
                                         **common)
        parts += [joint, element]
    return build_chain(parts, gravity=[0.0, -GRAVITY, 0.0])


def run(elements=32, kind="modal", modes=2, axial_stiffness=1e6, t_end=1.0, dt=1e-4,
        exact=True, reference=False):
    """(Result, the DivergenceError or None): a run that stops gives its samples so far.
    reference: run the Newton-Euler reference instead of DT-TMM (DOP853, rtol 1e-8, atol
    1e-10; dt unused), sampled every 1 ms."""
    model = pendulum(elements, kind, modes, axial_stiffness, exact)
    if reference:
        samples = np.linspace(0.0, t_end, int(round(t_end / 1e-3)) + 1)
        return simulate_reference(model, t_end, rtol=1e-8, atol=1e-10, t_eval=samples), None
    every = max(1, int(round(1e-3 / dt)))           # a sample every ~1 ms
    try:
        return simulate(model, t_end, dt, record_every=every), None
    except DivergenceError as err:
        return err.partial, err


def _stiffness(text):
    if text.lower() in ("rigid", "inf", "none"):
        return None
    value = float(text)
    if not value > 0.0:
        raise argparse.ArgumentTypeError("must be > 0 (N), or 'rigid'")
    return value


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elements", type=int, default=32, help="beam elements (default 32)")
    parser.add_argument("--kind", choices=KINDS, default="modal",
                        help="the beam element (default modal: the Euler-Bernoulli modal beam; "
                             "rod: the strain rod)")
    parser.add_argument("--reference", action="store_true",
                        help="run the Newton-Euler reference (DOP853, rtol 1e-8; --dt unused) "
                             "instead of DT-TMM")
    parser.add_argument("--modes", type=int, default=2,
                        help="modes per plane (a rod's: strain coefficients per plane; default 2)")
    parser.add_argument("--axial-stiffness", type=_stiffness, default=1e6,
                        help="E A, N (default 1e6; 1260 is the benchmark's original; 'rigid': "
                             "an inextensible centre line)")
    parser.add_argument("--stiffening", choices=("exact", "second-order"), default="exact",
                        help="the foreshortening to all orders (default; stiffening='exact') or "
                             "to second order in the modes (stiffening=True: see the docstring)")
    parser.add_argument("--t-end", type=float, default=1.0, help="s (default 1)")
    parser.add_argument("--dt", type=float, default=1e-4, help="the step, s (default 1e-4)")
    parser.add_argument("--csv", help="write t, tip_x, tip_y (every 1 ms) here")
    parser.add_argument("--plots", help="write falling_pendulum.png into this directory")
    args = parser.parse_args(argv)
    if args.elements < 1 or args.modes < 1:
        parser.error("--elements and --modes must be at least 1")
    wall = time.perf_counter()
    result, stopped = run(args.elements, args.kind, args.modes, args.axial_stiffness,
                          args.t_end, args.dt, args.stiffening == "exact", args.reference)
    wall = time.perf_counter() - wall
    tip = result.position_output[:, -1]
    stretch = ("inextensible" if args.axial_stiffness is None
               else f"EA = {args.axial_stiffness:g} N")
    how = ("the Newton-Euler reference, DOP853 at rtol 1e-8" if args.reference else
           f"stiffening {args.stiffening}, dt = {args.dt:g} s" if args.kind == "modal" else
           f"dt = {args.dt:g} s")
    print(f"soft falling pendulum: {args.elements} {args.kind} elements, {args.modes} mode(s) "
          f"per plane, {stretch}, {how}")
    print(f"{'t (s)':>7} {'tip x (m)':>11} {'tip y (m)':>11}")
    for t_mark in np.arange(0.0, result.t[-1] + 1e-9, 0.1):
        i = int(np.argmin(np.abs(result.t - t_mark)))
        print(f"{result.t[i]:7.3f} {tip[i, 0]:11.6f} {tip[i, 1]:11.6f}")
    energy = result.kinetic + result.potential
    largest = float(result.kinetic.max())
    change = float(np.abs(energy - energy[0]).max())
    print(f"energy: largest kinetic {largest:.4g} J; the total changed by at most "
          f"{change:.3g} J ({change / max(largest, 1e-300):.2e} of it); wall time {wall:.1f} s")
    if args.csv:
        np.savetxt(args.csv, np.column_stack([result.t, tip[:, 0], tip[:, 1]]), delimiter=",",
                   header="t,tip_x,tip_y", comments="", fmt="%.9g")
        print(f"wrote {args.csv}")
    if args.plots:
        _plot(result, args, how, Path(args.plots))
    if stopped is not None:
        print(f"stopped: {stopped}", file=sys.stderr)
        return 1
    return 0


def _plot(result, args, how, folder):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from dttmm.results.plots import centerlines
    folder.mkdir(parents=True, exist_ok=True)
    model = pendulum(args.elements, args.kind, args.modes, args.axial_stiffness,
                     args.stiffening == "exact")
    lines = centerlines(result, model)
    marks = np.arange(0.0, result.t[-1] + 1e-9, 0.1)
    fig, ax = plt.subplots(figsize=(8.4, 6.2))
    colours = plt.cm.viridis(np.linspace(0.0, 0.9, len(marks)))
    for t_mark, colour in zip(marks, colours):
        i = int(np.argmin(np.abs(result.t - t_mark)))
        line = lines[i].reshape(-1, 3)
        ax.plot(line[:, 0], line[:, 1], color=colour, lw=1.8, label=f"t = {result.t[i]:.1f} s")
    ax.plot([0.0], [0.0], "ko", ms=4)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    stretch = ("inextensible" if args.axial_stiffness is None
               else f"EA = {args.axial_stiffness:g} N")
    ax.set_title(f"Soft falling pendulum: {args.elements} {args.kind} elements x {args.modes} "
                 f"modes per plane\n({how}, {stretch})", fontsize=10)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    ax.grid(alpha=0.3)
    fig.tight_layout()
    out = folder / "falling_pendulum.png"
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print(f"wrote {out}")


if __name__ == "__main__":
    sys.exit(main())
