"""The project's benchmark: every timing and work-precision figure in one process.

    python benchmarks/run.py [--quick] --json FILE

Writes the figures to FILE (names carry their units) and PNG charts beside it.  Timings are
medians over repeats after a JIT warm-up; where two methods are compared the figure is their
ratio, measured in this one run (these machines are noisy).  Not a test: nothing is asserted.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from dttmm import BallJoint, simulate
from dttmm.model.chains import arm, binary_tree, rigid_chain, stiff_cantilever, three_pendulum
from dttmm.reference import simulate_reference
from dttmm.results.result import beam_midpoint_deflection
from dttmm.elements import BALL, FIXED
from dttmm.kernels.assembly import sweep as ksweep
from dttmm.kernels.assembly.solve import solve_step
from dttmm.solving.run_tables import Workspace, _mode, kernel_model
from numba import njit

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import adaptive  # noqa: E402  (benchmarks/adaptive.py)
import recording  # noqa: E402  (benchmarks/recording.py)


def median_us_per_step(model, steps, repeats, **kw):
    """Cost of one step at dt = 1e-4 without the run's fixed setup (workspace, consistent start):
    the difference of a run of `steps` steps and one of steps // 5, over the steps between."""
    simulate(model, 5 * 1e-4, 1e-4, **kw)                         # warm-up (JIT, caches)
    short = max(1, steps // 5)
    times = []
    for _ in range(repeats):
        long_run = simulate(model, steps * 1e-4, 1e-4, record_every=steps, **kw)
        short_run = simulate(model, short * 1e-4, 1e-4, record_every=short, **kw)
        times.append((long_run.wall_time - short_run.wall_time)
                     / (long_run.n_steps - short_run.n_steps))
    return 1e6 * float(np.median(times))


@njit
def _repeat_solve(repeats, mode, tip_pinned, parent, sweep, root, z):
    for _ in range(repeats):
        solve_step(mode, tip_pinned, parent, sweep, root, z)


def us_per_call(model, steps=1, batches=5, calls=300):
    """A simulate call's fixed cost: the wall time per call of a run of `steps` steps of
    1e-4 s, the median of `batches` batches of `calls` calls (after a warm-up)."""
    for _ in range(20):
        simulate(model, steps * 1e-4, 1e-4)
    times = []
    for _ in range(batches):
        t0 = time.perf_counter()
        for _ in range(calls):
            simulate(model, steps * 1e-4, 1e-4)
        times.append((time.perf_counter() - t0) / calls)
    return 1e6 * float(np.median(times))


def floor_us_per_step(model, repeats=20000):
    """The cost of the dense products and the boundary solve alone: the step's sweep (same
    element kinds and matrix sizes, the mode simulate picks) on fixed transfers, in a compiled
    loop."""
    chain, _ = kernel_model(model)
    ws = Workspace(chain)
    sweep = ws.sweep
    rng = np.random.default_rng(0)
    for j in range(sweep.u.shape[0]):
        sweep.u[j, :, :12] = np.eye(12) + 0.05 * rng.normal(size=(12, 12))
        sweep.u[j, :, 12] = rng.normal(size=12)
        if j % 2 == 1:
            sweep.kind[j] = ksweep.TRANSFER
        else:
            sweep.kind[j] = {BALL: ksweep.BALL, FIXED: ksweep.IDENTITY}.get(
                int(chain.hinge_kind[j // 2]), ksweep.TRANSFER)
    # (the argument types the loops pass: another would add a second compiled version of
    # solve_step to the cache, which tests/test_precompile.py finds)
    args = (_mode(chain, "riccati", False), int(chain.tip_pinned), np.array(chain.parent), sweep,
            np.zeros(6), ws.state.z)
    _repeat_solve(10, *args)
    t0 = time.perf_counter()
    _repeat_solve(repeats, *args)
    return 1e6 * (time.perf_counter() - t0) / repeats


def paired_ratio_to_floor(model, steps, repeats):
    """The step's cost over the floor's: the median of `repeats` ratios, each of a step cost
    and a floor measured back to back, so that the machine's drift between two figures measured
    minutes apart does not enter the ratio."""
    return float(np.median([median_us_per_step(model, steps, 1) / floor_us_per_step(model)
                            for _ in range(repeats)]))


def end_errors(model, res, ref, beam=None):
    pos = float(np.abs(res.position_output[-1] - ref.position_output[-1]).max())
    if beam is None:
        return pos
    mid = float(np.abs(beam_midpoint_deflection(model, res, beam)[-1]
                       - beam_midpoint_deflection(model, ref, beam)[-1]).max())
    return max(pos, mid)


def work_precision(model, t_end, dts, rtols, beam=None, newton=(0,), richardson_dts=(),
                   adaptive_rtols=(), high_order_rtols=(), reference_methods=("RK45", "DOP853")):
    """Curves of (wall time s, error m at t_end) for DT-TMM over dts (per Newton setting, with
    Richardson extrapolation over richardson_dts, with adaptive steps over adaptive_rtols, and
    with the high-order scheme over high_order_rtols) and for the reference over rtols (RK45,
    DOP853).  Every run is timed around the whole call, setup and result included, on both
    sides; the errors against the reference at rtol 1e-13."""
    grid = np.array([0.0, t_end])
    tight = simulate_reference(model, t_end, method="DOP853", rtol=1e-13, atol=1e-15,
                               t_eval=grid)
    # JIT warm-up: every timed kind of call run once, short, before any clock runs (from a cold
    # cache the first RK45 call compiled the reference's scipy right-hand side: ~11 s timed)
    short = 10 * dts[-1]
    simulate(model, short, dts[-1])
    if richardson_dts:
        simulate(model, short, dts[-1], richardson=True)
    if adaptive_rtols:
        simulate(model, short, rtol=adaptive_rtols[0], t_eval=[short])
    for method in reference_methods:
        simulate_reference(model, short, method=method, rtol=rtols[0], atol=rtols[0] * 1e-2)

    def timed(fn, *args, **kw):
        t0 = time.perf_counter()
        res = fn(*args, **kw)
        return time.perf_counter() - t0, end_errors(model, res, tight, beam)

    curves = {}
    for it in newton:
        curves[f"dttmm_newton{it}"] = [timed(simulate, model, t_end, dt, newton_iterations=it,
                                             record_every=int(round(t_end / dt)))
                                       for dt in dts]
    if richardson_dts:
        curves["dttmm_richardson"] = [timed(simulate, model, t_end, dt, richardson=True,
                                            record_every=int(round(t_end / dt)))
                                      for dt in richardson_dts]
    if adaptive_rtols:
        curves["dttmm_adaptive"] = [timed(simulate, model, t_end, rtol=rtol, t_eval=[t_end])
                                    for rtol in adaptive_rtols]
    if high_order_rtols:
        simulate(model, 10 * dts[-1], rtol=1e-3, scheme="dop853")      # (compiled)
        curves["dttmm_dop853"] = [timed(simulate, model, t_end, rtol=rtol, atol=rtol * 1e-2,
                                        scheme="dop853", t_eval=[t_end])
                                  for rtol in high_order_rtols]
    for method in reference_methods:
        curves[method] = [timed(simulate_reference, model, t_end, method=method, rtol=rtol,
                                atol=rtol * 1e-2, t_eval=grid) for rtol in rtols]
    return curves


def time_at_error(points, target):
    """Wall time at the given error, interpolated in log-log on a curve (None if the curve
    does not reach it)."""
    pts = sorted(points, key=lambda p: p[1])
    errs = np.log([max(p[1], 1e-300) for p in pts])
    times = np.log([p[0] for p in pts])
    lt = np.log(target)
    if lt < errs[0] or lt > errs[-1]:
        return None
    return float(np.exp(np.interp(lt, errs, times)))


def speedups(curves, target):
    """The reference's time (the faster of RK45 and DOP853) over DT-TMM's at equal error, for
    each DT-TMM curve; None where either side does not reach the error."""
    theirs = [time_at_error(curves[m], target) for m in ("RK45", "DOP853")]
    theirs = [t for t in theirs if t is not None]
    out = {}
    for name, pts in curves.items():
        if name.startswith("dttmm"):
            ours = time_at_error(pts, target)
            out[name] = None if ours is None or not theirs else min(theirs) / ours
    return out


def report_speedups(fig, prefix, curves, targets):
    """fig[prefix + "speedup_vs_newton_euler_at_<target>m"]: DT-TMM's best option; the plain
    Newmark (no Newton iterations) and Richardson figures beside it."""
    for target in targets:
        ratios = speedups(curves, target)
        name = f"{prefix}speedup_vs_newton_euler_at_{target:.0e}m"
        reached = [r for r in ratios.values() if r is not None]
        fig[name] = max(reached) if reached else None
        fig[name + "_plain_newmark"] = ratios["dttmm_newton0"]
        if "dttmm_richardson" in ratios:
            fig[name + "_richardson"] = ratios["dttmm_richardson"]


def high_order_chart(fig, out_dir, quick):
    """Issue 31's work-precision chart: the three-pendulum and rigid chains of 3, 10, 30, 100
    links over 1 s, every DT-TMM scheme against the reference (numba Newton-Euler right-hand
    side with scipy's DOP853), errors from 1e-3 to 1e-10 m; fig gets the best DT-TMM
    scheme's and the reference's time at 1e-6 and 1e-9 m, and their ratio."""
    t_end = 0.5 if quick else 1.0
    tols = [1e-3, 1e-5, 1e-7, 1e-9, 1e-11] if quick else [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8,
                                                          1e-9, 1e-10, 1e-11, 1e-12]
    systems = [("three_pendulum", three_pendulum(2))] + [
        (f"chain{n}", rigid_chain(n)) for n in ((3, 10) if quick else (3, 10, 30, 100))]
    for name, model in systems:
        stiff = name == "three_pendulum"
        dts = [1e-3, 5e-4, 2.5e-4] if stiff else [1e-2, 5e-3, 2.5e-3]
        curves = work_precision(model, t_end, dts, [t for t in tols if t >= 1e-10],
                                richardson_dts=dts, adaptive_rtols=tols[:4],
                                high_order_rtols=tols, reference_methods=("DOP853",))
        chart_work_precision(os.path.join(out_dir, f"work_precision_high_order_{name}.png"),
                             f"{name.replace('_', '-')}, {t_end:g} s: every scheme", curves)
        fig[f"high_order_{name}"] = curves
        for target in (1e-6, 1e-9):
            ours = {k: time_at_error(v, target) for k, v in curves.items()
                    if k.startswith("dttmm")}
            reached = {k: t for k, t in ours.items() if t is not None}
            best = min(reached, key=reached.get) if reached else None
            theirs = time_at_error(curves["DOP853"], target)
            key = f"high_order_{name}_at_{target:.0e}m"
            fig[key + "_best_dttmm"] = best
            fig[key + "_best_dttmm_s"] = reached.get(best)
            fig[key + "_reference_dop853_s"] = theirs
            fig[key + "_speedup"] = (None if best is None or theirs is None
                                     else theirs / reached[best])
        print(name, {k: v for k, v in fig.items() if k.startswith(f"high_order_{name}_")},
              flush=True)


def chart_work_precision(path, title, curves):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for name, pts in curves.items():
        # (the reference's curves are the Newton-Euler reference under scipy's integrator of
        # that name, not dttmm's scheme="dop853": the legend says so)
        label = name if name.startswith("dttmm") else f"reference + scipy {name}"
        ax.loglog([p[0] for p in pts], [max(p[1], 1e-16) for p in pts], "o-", label=label)
    ax.set_xlabel("wall time, s")
    ax.set_ylabel("error at the end, m")
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def chart_scaling(path, sizes, rigid, beams, reference):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    ax.loglog(sizes, rigid, "o-", label="DT-TMM rigid chain, us/step")
    ax.loglog(sizes[:len(beams)], beams, "s-", label="DT-TMM beam cantilever, us/step")
    ax.loglog(sizes[:len(reference)], reference, "^--", label="Newton-Euler, us per RHS")
    ax.set_xlabel("bodies N")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def reference_us_per_rhs(model, evaluations=200):
    from dttmm.reference.newton_euler import _Problem
    prob = _Problem(model)
    y = prob.initial_state()
    prob.rhs(0.0, y)
    t0 = time.perf_counter()
    for _ in range(evaluations):
        prob.rhs(0.0, y)
    return 1e6 * (time.perf_counter() - t0) / evaluations


def jit_warmup_seconds(cold):
    code = ("import time; t0 = time.perf_counter(); from dttmm import simulate; "
            "from dttmm.model.chains import three_pendulum; "
            "simulate(three_pendulum(2), 1e-4, 1e-4); "
            "print(time.perf_counter() - t0)")
    env = dict(os.environ)
    with tempfile.TemporaryDirectory() as cache:
        if cold:
            env["NUMBA_CACHE_DIR"] = cache
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             env=env, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def strain_rods(fig, quick):
    """Issue 32's speed figures: the strain rod's cost per element and step against the modal
    beam's (the soft pendulum of examples/falling_pendulum.py as 8 elements of each, its fall's
    first steps at dt = 1e-4 s); and, in the full run, the wall time of its whole second at the
    accuracy of 1e-2 m: 8 rods against 32 modal elements, and of the elastica's static roll-up
    to the full circle: one rod against 16 modal elements (docs/strain_rod.md, "In the
    sweep")."""
    sys.path.insert(0, os.path.join(ROOT, "examples"))
    import falling_pendulum
    steps, repeats = (200, 3) if quick else (1000, 5)
    for kind in ("modal", "rod"):
        per_step = median_us_per_step(falling_pendulum.pendulum(8, kind), steps, repeats)
        fig[f"soft_pendulum_{kind}_us_per_element_step"] = per_step / 8
    fig["rod_over_modal_per_element_step"] = (fig["soft_pendulum_rod_us_per_element_step"]
                                              / fig["soft_pendulum_modal_us_per_element_step"])
    if not quick:
        tips = {}
        for kind, elements in (("modal", 32), ("rod", 8)):
            res, stopped = falling_pendulum.run(elements, kind)
            fig[f"soft_pendulum_1s_{kind}_{elements}_wall_s"] = (
                None if stopped is not None else res.wall_time)
            tips[kind] = res.position_output[:, -1]
        if len(tips["modal"]) == len(tips["rod"]):
            fig["soft_pendulum_1s_rod_8_from_modal_32_m"] = float(
                np.linalg.norm(tips["rod"] - tips["modal"], axis=1).max())
        # the elastica rolled up to the full circle in 8 load steps by the static solve: one
        # rod of constant strain (exact) against 16 modal elements (examples/elastica.py)
        import elastica
        for kind, elements, modes in (("rod", 1, 1), ("modal", 16, 2)):
            start = time.perf_counter()
            runs = elastica.roll_up(elements, 8, modes, kind=kind)
            fig[f"elastica_{kind}_{elements}_wall_s"] = time.perf_counter() - start
            fig[f"elastica_{kind}_{elements}_worst_tip_error_m"] = max(
                float(np.linalg.norm(eq.positions()[2][-1] - elastica.exact_tip(lam)))
                for lam, eq in runs)
    print({k: v for k, v in fig.items()
           if "soft_pendulum" in k or k.startswith(("rod_", "elastica_"))}, flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer points, shorter runs")
    ap.add_argument("--json", required=True, help="output file for the figures")
    args = ap.parse_args(argv)
    out_dir = os.path.dirname(os.path.abspath(args.json))
    os.makedirs(out_dir, exist_ok=True)
    quick = args.quick
    fig = {}
    steps, repeats = (500, 3) if quick else (2000, 5)

    for m in (1, 2, 3):
        fig[f"three_pendulum_us_per_step_modes{m}"] = median_us_per_step(three_pendulum(m),
                                                                          steps, repeats)
    fig["floor_us_per_step"] = floor_us_per_step(three_pendulum(2))
    fig["ratio_to_floor"] = paired_ratio_to_floor(three_pendulum(2), steps, 2 * repeats - 1)
    fig["rigid_chain_3_us_per_step_energy_momentum"] = median_us_per_step(
        rigid_chain(3), steps, repeats, scheme="energy_momentum")
    # a call's fixed cost (issue 30: short runs), 1 and 10 steps
    for name, make in (("rigid_chain_3", lambda: rigid_chain(3)),
                       ("three_pendulum", three_pendulum)):
        for n in (1, 10):
            fig[f"{name}_us_per_call_{n}_steps"] = us_per_call(make(), n)
    print(json.dumps(fig, indent=1), flush=True)

    model = three_pendulum(2)
    t_wp = 0.5 if quick else 2.0
    dts = [2e-3, 1e-3, 5e-4, 2.5e-4] if quick else [2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4, 6.25e-5]
    rtols = [1e-2, 1e-4, 1e-6, 1e-8] if quick else [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8,
                                                     1e-9, 1e-10]
    curves = work_precision(model, t_wp, dts, rtols, beam=1, newton=(0, 2),
                            richardson_dts=dts[:-1], adaptive_rtols=(1e-3, 1e-4, 1e-5, 1e-6))
    chart_work_precision(os.path.join(out_dir, "work_precision_three_pendulum.png"),
                         f"three-pendulum, {t_wp:g} s", curves)
    report_speedups(fig, "", curves, (1e-4, 1e-6, 1e-8))
    fig["work_precision_three_pendulum"] = curves
    print({k: v for k, v in fig.items() if k.startswith("speedup")}, flush=True)

    for n in ((30,) if quick else (30, 100)):
        t_c = 0.1 if quick else 0.5
        c = work_precision(rigid_chain(n), t_c, [2e-3, 1e-3, 5e-4, 2.5e-4],
                           [1e-2, 1e-4, 1e-6, 1e-8] if quick else [1e-2, 1e-3, 1e-4, 1e-5, 1e-6,
                                                                    1e-7, 1e-8],
                           richardson_dts=[2.5e-2, 1.25e-2, 1e-2, 6.25e-3, 5e-3, 2.5e-3],
                           adaptive_rtols=(1e-3, 1e-4, 1e-5, 1e-6))
        chart_work_precision(os.path.join(out_dir, f"work_precision_chain{n}.png"),
                             f"{n}-link rigid chain, {t_c:g} s", c)
        report_speedups(fig, f"chain{n}_", c, (1e-6,))
        fig[f"work_precision_chain{n}"] = c
        print(n, {k: v for k, v in fig.items() if k.startswith(f"chain{n}_")}, flush=True)

    high_order_chart(fig, out_dir, quick)

    sizes = [3, 10, 30, 100] if quick else [3, 10, 30, 100, 300, 1000]
    # ~0.1-0.5 s of stepping per size (shorter runs left the differences to the machine's noise)
    rigid = [median_us_per_step(rigid_chain(n), max(100, min(2000, 60000 // n)), 5)
             for n in sizes]
    beam_sizes = sizes[:3] if quick else sizes[:4]
    beams = [median_us_per_step(stiff_cantilever(n), max(50, min(1000, 6000 // n)), 3)
             for n in beam_sizes]
    ref_sizes = sizes[:3] if quick else sizes[:5]
    reference = [reference_us_per_rhs(rigid_chain(n)) for n in ref_sizes]
    for n, us in zip(sizes, rigid):
        fig[f"rigid_chain_{n}_us_per_step"] = us
    for n, us in zip(beam_sizes, beams):
        fig[f"beam_chain_{n}_us_per_step"] = us
    # a beam element welded by fixed hinges (the fused welded-chain loop) against one between
    # ball joints (the fused ball-chain loop), per element and step: issue 16's 2x target
    for n in (3, 10, 30, 100):
        steps = max(50, min(1000, 6000 // n))
        fig[f"welded_beam_{n}_us_per_element_step"] = median_us_per_step(
            stiff_cantilever(n), steps, 3) / n
        fig[f"ball_joint_beam_{n}_us_per_element_step"] = median_us_per_step(
            stiff_cantilever(n, joint=BallJoint), steps, 3) / n
    for n, us in zip(ref_sizes, reference):
        fig[f"newton_euler_rigid_chain_{n}_us_per_rhs"] = us
    big = [i for i, n in enumerate(sizes) if n >= 30]
    fig["rigid_chain_cost_slope"] = float(np.polyfit(np.log([sizes[i] for i in big]),
                                                     np.log([rigid[i] for i in big]), 1)[0])
    chart_scaling(os.path.join(out_dir, "scaling.png"), sizes, rigid, beams, reference)

    # binary trees of 2^d - 1 unit links against chains of as many links, each ratio of a tree
    # and a chain measured back to back (median of 5 pairs)
    for depth in ((6, 8) if quick else (6, 8, 10)):
        n = 2 ** depth - 1
        tree, chain = binary_tree(depth), rigid_chain(n)
        run_steps = max(100, min(2000, 60000 // n))
        pairs = [(median_us_per_step(tree, run_steps, 1), median_us_per_step(chain, run_steps, 1))
                 for _ in range(5)]
        fig[f"binary_tree_{n}_us_per_step"] = float(np.median([a for a, _ in pairs]))
        fig[f"binary_tree_{n}_over_chain"] = float(np.median([a / b for a, b in pairs]))
    print({k: v for k, v in fig.items() if k.startswith("binary_tree")}, flush=True)

    # the arm of examples/arm.py (joints with coordinates: the general loop's full-state tree
    # sweep, Newton-iterated); the torque drive is a Python function called once per step
    for drive in ("torque", "motion"):
        for flexible in (False, True):
            key = f"arm_{drive}{'_flexible' if flexible else ''}_us_per_step"
            fig[key] = median_us_per_step(arm(drive, flexible), 2000, 3)
    print({k: v for k, v in fig.items() if k.startswith("arm")}, flush=True)

    # recording (benchmarks/recording.py): every step recorded and the derived quantities read,
    # against only the end, interleaved pairs; the 100-link chain's peak memory in a subprocess
    for name, model in (("three_pendulum", three_pendulum(2)), ("rigid_chain_3", rigid_chain(3))):
        rec = recording.recording_overhead(model, pairs=5 if quick else 15)
        fig[f"recording_{name}_full_over_end_only"] = rec["full_over_end_only"]
        fig[f"recording_{name}_us_per_sample"] = rec["extra_us_per_sample"]
        fig[f"recording_{name}_positions_us_per_sample"] = rec["positions_us_per_sample"]
        fig[f"recording_{name}_energies_us_per_sample"] = rec["energies_us_per_sample"]
    mem = recording.long_run_memory(100, 1.0 if quick else 5.0, 1e-4)
    fig["recording_chain100_peak_mb"] = mem["peak_mb"]
    fig["recording_chain100_samples"] = mem["samples"]
    print({k: v for k, v in fig.items() if k.startswith("recording")}, flush=True)

    # adaptive steps against the fixed step of equal error (benchmarks/adaptive.py):
    # interleaved pairs, the median wall-time ratio per rtol (the limit: 1.5)
    for name, model, t_a in (("three_pendulum", three_pendulum(), 2.0),
                             ("chain30", rigid_chain(30), 1.0)):
        table = adaptive.adaptive_against_fixed(model, t_a, (1e-3, 1e-4, 1e-5, 1e-6),
                                                3 if quick else 7)
        for rtol, row in table.items():
            fig[f"adaptive_{name}_rtol{rtol:.0e}_over_fixed"] = row["ratio"]
            fig[f"adaptive_{name}_rtol{rtol:.0e}_error_m"] = row["error"]
    print({k: v for k, v in fig.items() if k.startswith("adaptive")}, flush=True)

    # sweeps: the Monte Carlo of examples/monte_carlo.py on 1 and 2 dask workers (runs per
    # second, the LocalCluster's start and each worker's cache load included)
    runs = 20 if quick else 100
    for workers in (1, 2):
        out = subprocess.run([sys.executable, os.path.join(ROOT, "examples", "monte_carlo.py"),
                              "--runs", str(runs), "--workers", str(workers)],
                             capture_output=True, text=True, check=True)
        wall = float(out.stdout.split(" s; tip height")[0].rsplit(": ", 1)[-1])
        fig[f"sweep_monte_carlo_{workers}_workers_runs_per_s"] = runs / wall
    print({k: v for k, v in fig.items() if k.startswith("sweep")}, flush=True)

    strain_rods(fig, quick)

    fig["jit_warmup_s_warm_cache"] = jit_warmup_seconds(cold=False)
    fig["jit_warmup_s_cold_cache"] = None if quick else jit_warmup_seconds(cold=True)
    with open(args.json, "w") as f:
        json.dump(fig, f, indent=1)
    print(json.dumps({k: v for k, v in fig.items() if not k.startswith("work_precision")},
                     indent=1))


if __name__ == "__main__":
    main()
