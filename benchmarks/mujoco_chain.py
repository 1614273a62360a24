"""DT-TMM against MuJoCo on the rigid N-link ball chain, both at fixed steps, at equal error.

The same system on both sides: dttmm.model.chains.rigid_chain(N) (unit links: 1 kg, mass centre at
0.5 m, inertia diag(1/6, 1/6, 1/6) kg m^2 about it, ball joints 1 m apart, gravity -9.81 along
y, all along +x at rest but the last link, turning at 0.1 rad/s about y), written as MJCF: a
ball joint at each body's origin, an explicit inertial, no geoms, no damping, no armature,
contacts and constraints disabled.  Before anything is timed the script checks that it is the
same system: MuJoCo's RK4 at dt = 1e-5 s against the Newton-Euler reference
(dttmm.simulate_reference, rtol 1e-12) on the tip's position after 0.1 s (printed; refused
above 1e-8 m).

MuJoCo steps at a fixed step with its RK4 integrator (fourth order) and with its default
semi-implicit Euler (first order); DT-TMM with its fixed-step Newmark scheme
(dttmm.simulate(model, t_end, dt), second order) and, beside it, the same with
richardson=True (fourth order).  Each run's error is the tip's distance at t_end from a truth:
Pinocchio's articulated-body algorithm under scipy's DOP853 at rtol 1e-13 (benchmarks/peers.py)
if Pinocchio is installed, else the Newton-Euler reference at rtol 1e-12, atol 1e-14.  Every run
is timed around the whole call (MuJoCo: its MjData, made once beforehand, reset, the initial
state set, all steps in one mj_step(..., nstep) call, the tip's position computed; DT-TMM: the
simulate call, recording the start and the end only); both sides run once, short, before any
clock runs (DT-TMM compiles its kernels then), and the runs of both sides are interleaved, the
median of --repeats kept.  DT-TMM's high-order scheme (scheme="dop853", error-controlled steps,
rtol 1e-4 to 1e-11) runs beside them for comparison.

The wall times at equal error are interpolated on the log-log work-precision curves; the
figures are MuJoCo's time over DT-TMM's Newmark time, and MuJoCo's RK4 time over DT-TMM's
high-order time (above 1: DT-TMM faster).

    python benchmarks/mujoco_chain.py [--quick] [--json FILE] [--sizes N ...] [--repeats R]
                                      (N = 3, 10, 30 over 1 s; --quick: N = 3 over 0.5 s)

Needs MuJoCo (`pip install mujoco`); without it the script says so and exits 0.
"""
import argparse
import json
import os
import sys
import time

import numpy as np

from dttmm import simulate, simulate_reference
from dttmm.model.chains import rigid_chain

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peers import (cpu_description, curve_figures, interleaved_curves,  # noqa: E402
                   pinocchio_run, time_at)                               # (benchmarks/peers.py)

INTEGRATORS = {"rk4": "RK4", "euler": "Euler"}


def mjcf_chain(n, integrator="RK4", dt=1e-3):
    """MJCF of rigid_chain(n): link k+1 at the output point [1, 0, 0] of link k, a site at the
    last link's output point (the tip)."""
    inertia = " ".join([repr(1.0 / 6.0)] * 3)
    body = '<site name="tip" pos="1 0 0"/>'
    for k in reversed(range(n)):
        body = (f'<body name="link{k + 1}" pos="{1 if k else 0} 0 0">'
                f'<joint name="ball{k + 1}" type="ball" damping="0" armature="0"/>'
                f'<inertial pos="0.5 0 0" mass="1" diaginertia="{inertia}"/>{body}</body>')
    return (f'<mujoco model="rigid_chain_{n}">'
            f'<option timestep="{dt!r}" gravity="0 -9.81 0" integrator="{integrator}">'
            f'<flag contact="disable" constraint="disable"/></option>'
            f'<worldbody>{body}</worldbody></mujoco>')


def mujoco_run(model, data, dt, t_end):
    """(wall time s, tip position at t_end) of MuJoCo at the fixed step dt, on data made
    beforehand (making it costs ~0.6 ms, its 13 MB arena zeroed; resetting it, 3 us)."""
    import mujoco
    model.opt.timestep = dt
    steps = int(round(t_end / dt))
    if abs(steps * dt - t_end) > 1e-9 * t_end:
        raise ValueError(f"mujoco_run: dt = {dt:g} s does not divide t_end = {t_end:g} s")
    t0 = time.perf_counter()
    mujoco.mj_resetData(model, data)
    data.qvel[-2] = 0.1             # the last link turns about y (its own frame = world's)
    mujoco.mj_step(model, data, nstep=steps)
    mujoco.mj_kinematics(model, data)
    tip = data.site_xpos[0].copy()
    return time.perf_counter() - t0, tip


def dttmm_run(model, dt, t_end, **kwargs):
    """(wall time s, tip position at t_end) of DT-TMM at the fixed step dt."""
    t0 = time.perf_counter()
    res = simulate(model, t_end, dt, record_every=int(round(t_end / dt)), **kwargs)
    return time.perf_counter() - t0, res.position_output[-1, -1]


def dttmm_high_order(model, rtol, t_end):
    """(wall time s, tip position at t_end) of DT-TMM's high-order scheme at rtol."""
    t0 = time.perf_counter()
    res = simulate(model, t_end, rtol=rtol, atol=rtol * 1e-2, scheme="dop853", t_eval=[t_end])
    return time.perf_counter() - t0, res.position_output[-1, -1]


def same_system(n, models):
    """The tip's distance after 0.1 s between MuJoCo (RK4, dt = 1e-5) and the reference."""
    ref = simulate_reference(rigid_chain(n), 0.1, rtol=1e-12, atol=1e-14,
                             t_eval=[0.0, 0.1]).position_output[-1, -1]
    return float(np.linalg.norm(mujoco_run(*models["rk4"], 1e-5, 0.1)[1] - ref))


def truth_at(n, t_end):
    """The tip's position at t_end from Pinocchio at rtol 1e-13, else from the reference."""
    try:
        import pinocchio  # noqa: F401
    except ImportError:
        res = simulate_reference(rigid_chain(n), t_end, rtol=1e-12, atol=1e-14,
                                 t_eval=[0.0, t_end])
        return res.position_output[-1, -1], "newton_euler_rtol1e-12"
    return pinocchio_run(n, t_end, 1e-13)[1], "pinocchio_rtol1e-13"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="N = 3 over 0.5 s, fewer steps")
    ap.add_argument("--json", help="write the figures to FILE")
    ap.add_argument("--sizes", type=int, nargs="+", help="chain lengths (default 3 10 30)")
    ap.add_argument("--repeats", type=int, help="timed runs per point (default 5; quick 3)")
    args = ap.parse_args(argv)
    try:
        import mujoco
    except ImportError:
        print("benchmarks/mujoco_chain.py: MuJoCo is not installed (pip install mujoco): "
              "nothing run")
        return 0
    quick = args.quick
    t_end = 0.5 if quick else 1.0
    sizes = args.sizes or ((3,) if quick else (3, 10, 30))
    repeats = args.repeats or (3 if quick else 5)
    steps = {"mujoco_rk4": [1e-1, 5e-2, 2e-2] if quick else
             [1e-1, 6.25e-2, 5e-2, 4e-2, 2.5e-2, 2e-2, 1e-2, 5e-3, 2.5e-3, 1e-3],
             "mujoco_euler": [1e-3, 1e-4, 2.5e-5] if quick else
             [1e-3, 2.5e-4, 1e-4, 2.5e-5, 1e-5],
             "dttmm_newmark": [1e-2, 2e-3, 5e-4, 2e-4] if quick else
             [2e-2, 1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5],
             "dttmm_richardson": [2e-2, 5e-3] if quick else
             [5e-2, 2e-2, 1e-2, 5e-3, 2.5e-3, 1.25e-3],
             "dttmm_dop853": [1e-4, 1e-6, 1e-8] if quick else
             [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11]}    # (rtols)
    targets = (1e-4, 1e-6) if quick else (1e-3, 1e-4, 1e-5, 1e-6, 1e-8)
    cpu = cpu_description()
    fig = {"mujoco": mujoco.__version__, "cpu": cpu, "t_end_s": t_end, "repeats": repeats,
           "load_average_start": os.getloadavg()}
    print("MuJoCo", mujoco.__version__, "on", cpu, "load average", fig["load_average_start"],
          flush=True)
    for n in sizes:
        model = rigid_chain(n)
        models = {k: mujoco.MjModel.from_xml_string(mjcf_chain(n, v))
                  for k, v in INTEGRATORS.items()}
        models = {k: (m, mujoco.MjData(m)) for k, m in models.items()}
        fig[f"chain{n}_same_system_m"] = same_system(n, models)
        print(n, "MuJoCo's tip after 0.1 s against the Newton-Euler reference:",
              f"{fig[f'chain{n}_same_system_m']:.2e} m", flush=True)
        if not fig[f"chain{n}_same_system_m"] < 1e-8:
            raise SystemExit("benchmarks/mujoco_chain.py: the MJCF chain is not rigid_chain")
        truth, fig[f"chain{n}_truth"] = truth_at(n, t_end)
        runners = {"mujoco_rk4": lambda dt: mujoco_run(*models["rk4"], dt, t_end),
                   "mujoco_euler": lambda dt: mujoco_run(*models["euler"], dt, t_end),
                   "dttmm_newmark": lambda dt: dttmm_run(model, dt, t_end),
                   "dttmm_richardson": lambda dt: dttmm_run(model, dt, t_end, richardson=True),
                   "dttmm_dop853": lambda rtol: dttmm_high_order(model, rtol, t_end)}
        for name, run in runners.items():                  # warm-up (DT-TMM compiles here)
            run(steps[name][0])
        # interleaved: MuJoCo's and DT-TMM's runs alternate, the order reversed every repeat
        curves, walls = interleaved_curves(steps, runners, repeats,
                                           lambda tip: float(np.linalg.norm(tip - truth)))
        fig[f"chain{n}"] = curve_figures(steps, curves, walls)
        for k in curves:
            print(n, k, " ".join(f"{dt:g}:{w * 1e3:.3g}ms/{e:.1e}m"
                                 for dt, (w, e) in zip(steps[k], curves[k])), flush=True)
        for target in targets:
            at = {k: time_at(curves[k], target) for k in curves}
            row = {f"{k}_s": v for k, v in at.items()}
            for k, ours in (("mujoco_rk4", "newmark"), ("mujoco_euler", "newmark"),
                            ("mujoco_rk4", "dop853")):
                row[f"{k}_over_{ours}"] = (None if at[k] is None or at[f"dttmm_{ours}"] is None
                                           else at[k] / at[f"dttmm_{ours}"])
            fig[f"chain{n}_at_{target:.0e}m"] = row
            print(n, f"at {target:.0e} m:", {k: None if v is None else float(f"{v:.3g}")
                                             for k, v in row.items()}, flush=True)
    fig["load_average_end"] = os.getloadavg()
    print("load average", fig["load_average_end"])
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(fig, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
