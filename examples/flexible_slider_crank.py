"""The flexible slider-crank of seed 000 (section 1.4), a closed loop with a flexible link, by
DT-TMM.

    python examples/flexible_slider_crank.py --t-end 0.1 --csv fsc.csv --plots figures

A rigid crank 0.15 m turned at a prescribed 150 rad/s about world z, a steel rod 0.3 m long
(d = 6 mm, E = 2e11 Pa, rho = 7870 kg/m^3) that bends and stretches, on revolute joints at the
crank's end A and at the slider B, a point mass of half the rod's mass sliding on the x axis;
no gravity (dttmm.model.mechanisms.flexible_slider_crank; docs/loops.md).  At t = 0 the rod lies
straight along +x with rigid-body velocities.  CSV: t, mid_deflection (the rod's mid-point from
the middle of the chord AB, along z x (B - A) / |B - A|), half_elongation ((|AB| - 0.3) / 2),
slider_x, every 1e-4 s.  The defaults (one element of three bending modes per plane and one
stretch mode, dt = 1e-5 s) are the fewest whose mid-point deflection is converged to 1% of its
peak in elements and in dt (two modes miss it by half its peak); docs/loops.md gives the
numbers.
"""
import argparse
import sys
from pathlib import Path

import numpy as np

from dttmm import simulate
from dttmm.model.mechanisms import flexible_slider_crank
from dttmm.results.plots import centerlines

ROD = 0.3           # m, the rod's length at rest


def rod_measures(model, res, elements):
    """(mid_deflection, half_elongation, slider_x), each (T,), of a run."""
    first = model.body_names.index("rod1")
    last = model.body_names.index(f"rod{elements}")
    slider = model.body_names.index("slider")
    a = res.position_input[:, first]
    b = res.position_input[:, slider]
    # the rod's mid-point: the middle of the middle element, or the joint of the middle two
    lines = centerlines(res, model, points=3)
    mid = (lines[:, first + elements // 2, 1] if elements % 2
           else lines[:, first + elements // 2 - 1, 2])
    chord = b - a
    length = np.linalg.norm(chord, axis=1)
    normal = np.cross([0.0, 0.0, 1.0], chord / length[:, None])
    deflection = np.einsum("ti,ti->t", mid - 0.5 * (a + b), normal)
    assert last == first + elements - 1
    return deflection, 0.5 * (length - ROD), b[:, 0]


def run(t_end=0.1, dt=1e-5, elements=1, modes=3, axial_modes=1, energy=False):
    """The model and a DT-TMM run of it, recorded every 1e-4 s (or every step if dt is
    coarser)."""
    model = flexible_slider_crank(elements=elements, modes=modes, axial_modes=axial_modes)
    every = max(1, int(round(1e-4 / dt)))
    options = {"max_energy_error": 1.0} if energy else {}
    return model, simulate(model, t_end, dt, record_every=every, **options)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=0.1, help="end time, s (default 0.1)")
    ap.add_argument("--dt", type=float, default=1e-5, help="time step, s (default 1e-5)")
    ap.add_argument("--elements", type=int, default=1,
                    help="beams welded end to end in the rod (default 1)")
    ap.add_argument("--modes", type=int, default=3,
                    help="bending modes per plane of each element (default 3)")
    ap.add_argument("--csv", help="write t, mid_deflection, half_elongation, slider_x every "
                                  "1e-4 s")
    ap.add_argument("--plots", help="directory for the figure (PNG)")
    args = ap.parse_args(argv)
    if args.elements < 1 or args.modes < 1:
        print("error: --elements and --modes must be at least 1", file=sys.stderr)
        return 2
    try:
        model, res = run(args.t_end, args.dt, args.elements, args.modes, energy=True)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    deflection, half, slider_x = rod_measures(model, res, args.elements)
    info = res.info
    print(f"flexible slider-crank ({args.elements} element(s) of {args.modes} modes per plane, "
          f"{res.n_steps} steps of {args.dt:g} s, {info['loop']} loop): {res.wall_time:.2f} s "
          f"wall")
    print(f"  mid-point deflection: largest {np.abs(deflection).max() * 1e3:.4f} mm, at "
          f"t = {res.t[-1]:g} s {deflection[-1] * 1e3:.4f} mm; half elongation: largest "
          f"{np.abs(half).max() * 1e3:.5f} mm")
    print(f"  energy balance (the crank drive's work included): {info['energy_balance_error']:.2e}"
          f" of the largest kinetic energy; loop residuals after every step: positions "
          f"{info['loop_position_residual']:.1e} m, rates {info['loop_rate_residual']:.1e} m/s")
    if args.csv:
        data = np.column_stack([res.t, deflection, half, slider_x])
        np.savetxt(args.csv, data, delimiter=",", comments="", fmt="%.12g",
                   header="t,mid_deflection,half_elongation,slider_x")
        print(f"wrote {args.csv}")
    if args.plots:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        out = Path(args.plots)
        out.mkdir(parents=True, exist_ok=True)
        fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
        ax[0].plot(res.t, deflection * 1e3, lw=0.9)
        ax[0].set(xlabel="t, s", ylabel="mid-point deflection, mm",
                  title="Rod mid-point deflection (from the chord AB)")
        ax[1].plot(res.t, half * 1e3, lw=0.9)
        ax[1].set(xlabel="t, s", ylabel="half elongation, mm", title="Half the rod's elongation")
        for a in ax:
            a.grid(alpha=0.3)
        fig.suptitle(f"Flexible slider-crank (seed 000), crank at 150 rad/s: DT-TMM, "
                     f"{args.elements} element(s), dt = {args.dt:g} s")
        fig.tight_layout()
        path = out / "flexible_slider_crank.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
