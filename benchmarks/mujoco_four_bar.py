"""DT-TMM against MuJoCo on the N-four-bar (closed loops), both at fixed steps, at equal error.

The same system on both sides: dttmm.model.mechanisms.n_four_bar(N, tree="ground") (N + 1 vertical
unit bars on revolute joints about z to the ground at (i, 0, 0), N horizontal bars joining
their tops; every bar 1 m, 1 kg, mass centre at its middle, inertia about it 1/12 kg m^2
across the bar and 1e-3 along it; gravity -9.81 along y; the bars upright, every vertical bar
turning at -1 rad/s about z, the horizontal bars translating), written as MJCF: each vertical
bar "v{i}" a body on a hinge about z at (i, 0, 0), each horizontal bar "h{i}" a child of
v{i-1} on a hinge about z at its top, and each loop closed by a <connect> equality between
h{i}'s far end and v{i}'s top (its out-of-plane row is redundant; MuJoCo regularizes it).
Explicit inertials, no geoms, no damping, no armature, contacts disabled; qvel set to the
parallelogram's rates (-1 rad/s on the ground hinges, +1 on the horizontal bars' hinges).

MuJoCo's equality constraints are soft: a spring-damper of time constant solref[0] (clamped to
at least 2 dt unless the refsafe flag is disabled; shorter ones are unstable at that dt) and an
impedance d from solimp, leaving a force deficit that scales with (1 - d).  The timed runs use
the stiffest MuJoCo allows at each step: solref = (2 dt, 1) and solimp = (0.9999, 0.9999,
0.001, 0.5, 2) (d at its ceiling, 0.9999), so the constraints stiffen as dt shrinks.  With a
fixed solref the error stops falling at a floor: the script measures it (Euler at dt = 1e-4)
at MuJoCo's default solref (0.02, 1) and solimp (0.9, 0.95, ...), and at solref 0.02 and
0.002 with d = 0.9999.  MuJoCo steps with its RK4 (fourth order) and its default semi-implicit
Euler; implicitfast takes the same steps as Euler here (no damping: measured, identical
errors), so it is left out.  From upright the bars start with no acceleration, so Euler's
first-order start-up error vanishes and its positions converge at about second order here.
Before anything is timed the script prints MuJoCo's distance from the exact reduction
(dttmm.model.mechanisms.parallelogram) at a tiny step: RK4 at dt = 1e-5 over the run.

DT-TMM runs dttmm.simulate(model, t_end, dt, record_every=k) with its defaults (the Newmark
step, second order; each step's loops projected, the energy held) and, beside it, the same
with richardson=True (fourth order).  Each run's error is the largest distance of the first
bar's top B_0 from the exact reduction over the samples every 0.01 s (both sides record the
same samples: MuJoCo in its mj_step loop, mj_kinematics at each sample; DT-TMM by
record_every).  Every run is timed around the whole call (MuJoCo: reset, initial state,
stepping, samples; its MjData made once beforehand); both sides run once before any clock runs
(DT-TMM compiles or loads its kernels then), the runs of both sides are interleaved, the order
reversed every repeat, and the median of --repeats kept.  The wall times at equal error are
interpolated on the log-log work-precision curves; the figures are MuJoCo's time over
DT-TMM's (above 1: DT-TMM faster).

    python benchmarks/mujoco_four_bar.py [--quick] [--json FILE]
                                                [--sizes N ...] [--repeats R]
                        (N = 2, 10, 40 over 1 s; --quick: N = 2 over 0.5 s, fewer steps)

Needs MuJoCo (`pip install mujoco`); without it the script says so and exits 0.  Not a test:
nothing is asserted.
"""
import argparse
import json
import os
import sys
import time

import numpy as np

from dttmm import simulate
from dttmm.model.mechanisms import n_four_bar, parallelogram

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peers import (cpu_description, curve_figures, interleaved_curves,  # noqa: E402
                   time_at)                                              # (benchmarks/peers.py)

SAMPLE = 0.01                                         # s between samples, both sides
STIFF_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)      # d at MuJoCo's ceiling
DEFAULT_SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)         # MuJoCo's defaults
FLOORS = {"solref0.02_default_solimp": ((0.02, 1.0), DEFAULT_SOLIMP),     # MuJoCo's defaults
          "solref0.02_d0.9999": ((0.02, 1.0), STIFF_SOLIMP),
          "solref0.002_d0.9999": ((0.002, 1.0), STIFF_SOLIMP)}


def mjcf_four_bar(n, integrator="RK4"):
    """MJCF of n_four_bar(n): bodies in the world's orientation, so the inertias are world's."""
    vert = " ".join(map(repr, (1 / 12, 1e-3, 1 / 12)))     # bar along y
    horiz = " ".join(map(repr, (1e-3, 1 / 12, 1 / 12)))    # bar along x
    hinge = 'type="hinge" axis="0 0 1" damping="0" armature="0"'
    bodies, closures = [], []
    for i in range(n + 1):
        inner = '<site name="B0" pos="0 1 0"/>' if i == 0 else ""
        if i < n:
            inner += (f'<body name="h{i + 1}" pos="0 1 0"><joint name="H{i + 1}" {hinge}/>'
                      f'<inertial pos="0.5 0 0" mass="1" diaginertia="{horiz}"/></body>')
            closures.append(f'<connect body1="h{i + 1}" body2="v{i + 1}" anchor="1 0 0"/>')
        bodies.append(f'<body name="v{i}" pos="{i} 0 0"><joint name="O{i}" {hinge}/>'
                      f'<inertial pos="0 0.5 0" mass="1" diaginertia="{vert}"/>{inner}</body>')
    return (f'<mujoco model="four_bar_{n}">'
            f'<option timestep="0.001" gravity="0 -9.81 0" integrator="{integrator}">'
            f'<flag contact="disable"/></option><worldbody>{"".join(bodies)}</worldbody>'
            f'<equality>{"".join(closures)}</equality></mujoco>')


def mujoco_model(n, integrator):
    """(MjModel, MjData, the ground hinges' dofs, the horizontal bars' hinges' dofs)."""
    import mujoco
    model = mujoco.MjModel.from_xml_string(mjcf_four_bar(n, integrator))
    ground = [int(model.joint(f"O{i}").dofadr[0]) for i in range(n + 1)]
    tops = [int(model.joint(f"H{i}").dofadr[0]) for i in range(1, n + 1)]
    return model, mujoco.MjData(model), ground, tops


def mujoco_run(mj, dt, t_end, solref=None, solimp=STIFF_SOLIMP):
    """(wall time s, B_0's x, y every SAMPLE s) of MuJoCo at the fixed step dt; solref None:
    (2 dt, 1), the stiffest its refsafe clamp allows."""
    import mujoco
    model, data, ground, tops = mj
    every, samples = steps_per(dt, SAMPLE), steps_per(SAMPLE, t_end)
    model.opt.timestep = dt
    model.eq_solref[:] = (2 * dt, 1.0) if solref is None else solref
    model.eq_solimp[:] = solimp
    out = np.empty((samples + 1, 2))
    t0 = time.perf_counter()
    mujoco.mj_resetData(model, data)
    data.qvel[ground] = -1.0             # every vertical bar turns at -1 rad/s about z
    data.qvel[tops] = 1.0                # the horizontal bars translate
    mujoco.mj_kinematics(model, data)
    out[0] = data.site_xpos[0, :2]
    for k in range(samples):
        mujoco.mj_step(model, data, nstep=every)
        mujoco.mj_kinematics(model, data)          # site_xpos of the state after the step
        out[k + 1] = data.site_xpos[0, :2]
    return time.perf_counter() - t0, out


def dttmm_run(model, dt, t_end, **kwargs):
    """(wall time s, B_0's x, y every SAMPLE s) of DT-TMM at the fixed step dt."""
    first = model.body_names.index("v0")
    t0 = time.perf_counter()
    res = simulate(model, t_end, dt, record_every=steps_per(dt, SAMPLE), **kwargs)
    return time.perf_counter() - t0, res.position_output[:, first, :2]


def steps_per(dt, span):
    """span / dt as an int, refusing a dt that does not divide span."""
    k = int(round(span / dt))
    if k < 1 or abs(k * dt - span) > 1e-9 * span:
        raise ValueError(f"dt = {dt:g} s does not divide {span:g} s")
    return k


def distance(b0, exact):
    """The largest distance of B_0 from the exact reduction over the samples (inf: blown up)."""
    if b0.shape != exact.shape or not np.all(np.isfinite(b0)):
        return float("inf")
    return float(np.linalg.norm(b0 - exact, axis=1).max())


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="N = 2 over 0.5 s, fewer steps")
    ap.add_argument("--json", help="write the figures to FILE")
    ap.add_argument("--sizes", type=int, nargs="+", help="numbers of loops (default 2 10 40)")
    ap.add_argument("--repeats", type=int, help="timed runs per point (default 3; quick 2)")
    args = ap.parse_args(argv)
    try:
        import mujoco
    except ImportError:
        print("benchmarks/mujoco_four_bar.py: MuJoCo is not installed (pip install mujoco): "
              "nothing run")
        return 0
    start = time.perf_counter()
    quick = args.quick
    t_end = 0.5 if quick else 1.0
    sizes = args.sizes or ((2,) if quick else (2, 10, 40))
    repeats = args.repeats or (2 if quick else 3)
    steps = {"mujoco_rk4": [1e-2, 2e-3, 5e-4] if quick else
             [1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4],
             "mujoco_euler": [1e-2, 1e-3, 1e-4] if quick else
             [1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5],
             "dttmm_newmark": [1e-2, 2e-3, 5e-4, 2e-4] if quick else
             [1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4],
             "dttmm_richardson": [1e-2, 2e-3] if quick else [1e-2, 5e-3, 2e-3, 1e-3]}
    targets = (1e-5, 1e-7) if quick else (1e-4, 1e-5, 1e-6, 1e-7)
    ratios = [(m, d) for m in ("mujoco_rk4", "mujoco_euler")
              for d in ("dttmm_newmark", "dttmm_richardson")]
    cpu = cpu_description()
    fig = {"mujoco": mujoco.__version__, "cpu": cpu, "t_end_s": t_end, "repeats": repeats,
           "sample_s": SAMPLE, "solimp": STIFF_SOLIMP, "solref": "(2 dt, 1)",
           "load_average_start": os.getloadavg()}
    print("MuJoCo", mujoco.__version__, "on", cpu, "load average", fig["load_average_start"],
          f"; t_end {t_end} s, B_0 sampled every {SAMPLE} s, median of {repeats}", flush=True)
    for n in sizes:
        model = n_four_bar(n, tree="ground")
        mjs = {"rk4": mujoco_model(n, "RK4"), "euler": mujoco_model(n, "Euler")}
        exact = parallelogram(n, SAMPLE * np.arange(steps_per(SAMPLE, t_end) + 1))
        check = distance(mujoco_run(mjs["rk4"], 1e-5, t_end)[1], exact)
        fig[f"four_bar{n}_same_system_m"] = check
        print(f"N = {n}: MuJoCo (RK4, dt = 1e-5, solref (2e-5, 1)) against the exact reduction "
              f"over {t_end:g} s: {check:.2e} m", flush=True)
        if not check < 1e-6:
            print("  warning: that is far: the MJCF may not be n_four_bar", flush=True)
        floors = {k: distance(mujoco_run(mjs["euler"], 1e-4, t_end, *v)[1], exact)
                  for k, v in FLOORS.items()}
        fig[f"four_bar{n}_mujoco_floor_m"] = floors
        print(f"N = {n}: MuJoCo's floors (Euler, dt = 1e-4, fixed solref):",
              ", ".join(f"{k} {v:.2e} m" for k, v in floors.items()), flush=True)
        runners = {"mujoco_rk4": lambda dt: mujoco_run(mjs["rk4"], dt, t_end),
                   "mujoco_euler": lambda dt: mujoco_run(mjs["euler"], dt, t_end),
                   "dttmm_newmark": lambda dt: dttmm_run(model, dt, t_end),
                   "dttmm_richardson": lambda dt: dttmm_run(model, dt, t_end, richardson=True)}
        t0 = time.perf_counter()
        for name, run in runners.items():                  # warm-up (DT-TMM compiles here)
            run(steps[name][0])
        print(f"N = {n}: warm-up {time.perf_counter() - t0:.1f} s", flush=True)
        # interleaved: MuJoCo's and DT-TMM's runs alternate, the order reversed every repeat
        curves, walls = interleaved_curves(steps, runners, repeats,
                                           lambda b0: distance(b0, exact))
        fig[f"four_bar{n}"] = curve_figures(steps, curves, walls)
        for k in curves:
            print(f"N = {n} {k:16s}", " ".join(f"{dt:g}:{w * 1e3:.3g}ms/{e:.1e}m"
                                               for dt, (w, e) in zip(steps[k], curves[k])),
                  flush=True)
        for target in targets:
            at = {k: time_at([p for p in curves[k] if np.isfinite(p[1])], target)
                  for k in curves}
            row = {f"{k}_s": v for k, v in at.items()}
            for m, d in ratios:
                row[f"{m}_over_{d[6:]}"] = (None if at[m] is None or at[d] is None
                                            else at[m] / at[d])
            fig[f"four_bar{n}_at_{target:.0e}m"] = row
            print(f"N = {n} at {target:.0e} m: times (ms) " + ", ".join(
                f"{k} {'-' if v is None else f'{v * 1e3:.3g}'}" for k, v in at.items())
                + "; MuJoCo / DT-TMM: " + ", ".join(
                f"{k} {'-' if v is None else f'{v:.3g}'}"
                for k, v in row.items() if "_over_" in k), flush=True)
    fig["load_average_end"] = os.getloadavg()
    fig["run_s"] = time.perf_counter() - start
    print("load average", fig["load_average_end"], f"; the whole run {fig['run_s']:.0f} s")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(fig, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
