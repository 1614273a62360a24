"""DT-TMM against Pinocchio on the rigid N-link ball chain (issue 31's work-precision figure).

The same system on both sides: dttmm.model.chains.rigid_chain(N) (unit links: 1 kg, mass centre at
0.5 m, inertia diag(1/6, 1/6, 1/6) kg m^2 about it, spherical joints 1 m apart, gravity -9.81
along y, all along +x at rest but the last link, turning at 0.1 rad/s about y).  Pinocchio's
articulated-body algorithm (pin.aba) gives the accelerations of (q, v), quaternions and local
angular velocities per joint, which scipy's DOP853 integrates (the quaternions' rates
1/2 q (x) [w; 0], normalized before every evaluation).  DT-TMM runs its best schemes: the
high-order one (scheme="dop853") and Newmark with Richardson extrapolation.  Every run is timed
around the whole call; the error is the tip's distance at t_end from a truth: Pinocchio's run
at rtol 1e-13 (checked against the Newton-Euler reference, dttmm.simulate_reference, for
N <= 10), and for N = 100, where Pinocchio + scipy at rtol 1e-8 already takes minutes, DT-TMM's
high-order run at rtol 1e-13, checked against Pinocchio's at 1e-7 (their distance printed).
Where Pinocchio's tightest run does not reach an error target, its time there is at least that
run's (printed as a lower bound, and so the speed-up).

    python benchmarks/peers.py [--quick] [--json FILE] [--sizes N ...]
                                           (N = 3, 10, 30, 100; --quick: 3, 10 over 0.5 s)

Needs Pinocchio (`pip install pin`); without it the script says so and exits 0.  MuJoCo is not
run: its stepping is a fixed-step integrator of its own, not an error-controlled one
(benchmarks/mujoco_chain.py compares it with DT-TMM at fixed steps).
"""
import argparse
import json
import os
import platform
import time

import numpy as np

from dttmm import simulate, simulate_reference
from dttmm.model.chains import rigid_chain


def pinocchio_chain(n):
    """Pinocchio's model of rigid_chain(n) and the joint of its tip."""
    import pinocchio as pin
    model = pin.Model()
    model.gravity.linear = np.array([0.0, -9.81, 0.0])
    parent = 0
    for k in range(n):
        offset = pin.SE3(np.eye(3), np.array([1.0 if k else 0.0, 0.0, 0.0]))
        joint = model.addJoint(parent, pin.JointModelSpherical(), offset, f"ball{k + 1}")
        model.appendBodyToJoint(joint, pin.Inertia(1.0, np.array([0.5, 0.0, 0.0]),
                                                   np.eye(3) / 6.0), pin.SE3.Identity())
        parent = joint
    return model, parent


def pinocchio_run(n, t_end, rtol):
    """(wall time s, tip position at t_end) of Pinocchio's ABA under scipy's DOP853."""
    import pinocchio as pin
    from scipy.integrate import solve_ivp
    model, tip = pinocchio_chain(n)
    data = model.createData()
    q0 = pin.neutral(model)
    v0 = np.zeros(model.nv)
    v0[-2] = 0.1                    # the last link turns about y (its own frame = world's)
    tau = np.zeros(model.nv)

    def fun(_, y):
        q = y[:4 * n].reshape(n, 4)
        q = q / np.linalg.norm(q, axis=1)[:, None]
        v = y[4 * n:]
        w = v.reshape(n, 3)
        x, yq, z, s = q[:, 0], q[:, 1], q[:, 2], q[:, 3]     # (pinocchio: x, y, z, w)
        dq = 0.5 * np.stack([s * w[:, 0] + yq * w[:, 2] - z * w[:, 1],
                             s * w[:, 1] + z * w[:, 0] - x * w[:, 2],
                             s * w[:, 2] + x * w[:, 1] - yq * w[:, 0],
                             -(x * w[:, 0] + yq * w[:, 1] + z * w[:, 2])], axis=1)
        return np.concatenate([dq.ravel(), pin.aba(model, data, q.ravel(), v, tau)])

    y0 = np.concatenate([q0, v0])
    t0 = time.perf_counter()
    sol = solve_ivp(fun, (0.0, t_end), y0, method="DOP853", rtol=rtol, atol=rtol * 1e-2,
                    t_eval=[t_end])
    q = sol.y[:4 * n, -1].reshape(n, 4)
    q = (q / np.linalg.norm(q, axis=1)[:, None]).ravel()
    pin.forwardKinematics(model, data, q)
    tip_position = data.oMi[tip].act(np.array([1.0, 0.0, 0.0]))
    return time.perf_counter() - t0, tip_position


def timed(fn, *args, **kwargs):
    t0 = time.perf_counter()
    result = fn(*args, **kwargs)
    return time.perf_counter() - t0, result.position_output[-1, -1]


def time_at(points, target):
    """Wall time at the error target, log-log interpolated (None where not reached)."""
    pts = sorted(points, key=lambda p: p[1])
    errs = np.log([max(p[1], 1e-300) for p in pts])
    if not errs[0] <= np.log(target) <= errs[-1]:
        return None
    return float(np.exp(np.interp(np.log(target), errs, np.log([p[0] for p in pts]))))


def cpu_description():
    """The machine's CPU model name and family (/proc/cpuinfo), or platform's processor."""
    if not os.path.exists("/proc/cpuinfo"):
        return [platform.processor()]
    return [line.split(":")[1].strip() for line in open("/proc/cpuinfo")
            if line.startswith(("model name", "cpu family"))][:2]


def interleaved_curves(steps, runners, repeats, error_of):
    """Work-precision curves timed interleaved: every (name, step) job of steps (name -> its
    steps or tolerances) run by runners[name](step), which returns (wall s, output); the peer's
    jobs (names not starting "dttmm") alternate with DT-TMM's, the order reversed every repeat.
    Returns ({name: [(median wall s, error_of(output)), ...]}, {job: every wall s})."""
    peer = [(k, dt) for k in steps if not k.startswith("dttmm") for dt in steps[k]]
    ours = [(k, dt) for k in steps if k.startswith("dttmm") for dt in steps[k]]
    order = [job for pair in zip(peer + [None] * len(ours), ours + [None] * len(peer))
             for job in pair if job is not None]
    walls, errors = {job: [] for job in order}, {}
    for r in range(repeats):
        for job in (order if r % 2 == 0 else order[::-1]):
            wall, output = runners[job[0]](job[1])
            walls[job].append(wall)
            errors[job] = error_of(output)
    curves = {k: [(float(np.median(walls[(k, dt)])), errors[(k, dt)]) for dt in steps[k]]
              for k in steps}
    return curves, walls


def curve_figures(steps, curves, walls):
    """The curves as the --json figures: per name, each step's wall, error and every wall."""
    return {k: [{"dt_s": dt, "wall_s": w, "error_m": e, "walls_s": walls[(k, dt)]}
                for dt, (w, e) in zip(steps[k], curves[k])] for k in curves}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="N = 3, 10 over 0.5 s")
    ap.add_argument("--json", help="write the figures to FILE")
    ap.add_argument("--sizes", type=int, nargs="+", help="chain lengths (default 3 10 30 100)")
    args = ap.parse_args(argv)
    try:
        import pinocchio  # noqa: F401
    except ImportError:
        print("benchmarks/peers.py: Pinocchio is not installed (pip install pin): nothing run")
        return 0
    t_end = 0.5 if args.quick else 1.0
    sizes = args.sizes or ((3, 10) if args.quick else (3, 10, 30, 100))
    tols = [1e-3, 1e-4, 1e-6, 1e-8, 1e-10] if args.quick else [1e-2, 1e-3, 1e-4, 1e-5, 1e-6,
                                                                1e-7, 1e-8, 1e-9, 1e-10, 1e-11]
    fig = {}
    for n in sizes:
        model = rigid_chain(n)
        # Pinocchio + scipy's DOP853 on 100 links: 1.2 s at rtol 1e-6, 12.5 s at 1e-7 (its
        # steps shrink with the quaternions' normalization); no truth from it at 1e-13
        pin_tols = [r for r in tols if r >= 1e-7] if n > 30 else tols
        if n > 30:
            truth = timed(simulate, model, t_end, rtol=1e-13, atol=1e-15, scheme="dop853",
                          t_eval=[t_end])[1]
            check = pinocchio_run(n, t_end, 1e-7)[1]
            fig[f"chain{n}_truths_differ_m"] = float(np.linalg.norm(check - truth))
            print(n, "DT-TMM at 1e-13 and Pinocchio at 1e-7 differ by",
                  fig[f"chain{n}_truths_differ_m"], "m", flush=True)
        else:
            truth = pinocchio_run(n, t_end, 1e-13)[1]          # (cheap: Pinocchio at 1e-13)
        if n <= 10:                 # the same system: the Newton-Euler reference agrees
            check = simulate_reference(model, t_end, rtol=1e-13, atol=1e-15,
                                       t_eval=[0.0, t_end]).position_output[-1, -1]
            fig[f"chain{n}_truths_differ_m"] = float(np.linalg.norm(check - truth))
            print(n, "Pinocchio and the Newton-Euler reference at 1e-13 differ by",
                  fig[f"chain{n}_truths_differ_m"], "m", flush=True)
        simulate(model, 0.01, rtol=1e-3, scheme="dop853")            # (compiled before
        simulate(model, 0.01, 2e-3, richardson=True)                  # the clocks run)
        pinocchio_run(n, 0.01, 1e-3)
        curves = {"pinocchio_dop853": [], "dttmm_dop853": [], "dttmm_richardson": []}
        for rtol in tols:
            if rtol in pin_tols:
                wall, tip = pinocchio_run(n, t_end, rtol)
                curves["pinocchio_dop853"].append((wall, float(np.linalg.norm(tip - truth))))
            wall, tip = timed(simulate, model, t_end, rtol=rtol, atol=rtol * 1e-2,
                              scheme="dop853", t_eval=[t_end])
            curves["dttmm_dop853"].append((wall, float(np.linalg.norm(tip - truth))))
        for dt in (2e-2, 1e-2, 5e-3, 2.5e-3, 1.25e-3):
            wall, tip = timed(simulate, model, t_end, dt, richardson=True,
                              record_every=int(round(t_end / dt)))
            curves["dttmm_richardson"].append((wall, float(np.linalg.norm(tip - truth))))
        fig[f"chain{n}"] = curves
        for target in (1e-6, 1e-9):
            theirs = time_at(curves["pinocchio_dop853"], target)
            bound = theirs is None and min(e for _, e in curves["pinocchio_dop853"]) > target
            if bound:           # not reached: at least the time of its most accurate run
                theirs = min(curves["pinocchio_dop853"], key=lambda p: p[1])[0]
            ours = {k: time_at(v, target) for k, v in curves.items() if k.startswith("dttmm")}
            ours = {k: v for k, v in ours.items() if v is not None}
            best = min(ours, key=ours.get) if ours else None
            key = f"chain{n}_at_{target:.0e}m"
            fig[key] = {"pinocchio_s": theirs, "pinocchio_s_is_lower_bound": bound,
                        "best_dttmm": best,
                        "best_dttmm_s": ours.get(best),
                        "speedup": None if best is None or theirs is None
                        else theirs / ours[best]}
            print(n, key, fig[key], flush=True)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(fig, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
