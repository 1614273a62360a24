"""Wall time per step of DT-TMM and of the Newton-Euler reference on the rigid chain, one run.

    python benchmarks/rigid_chain_timing.py [--links 3 10] [--json out.json]

DT-TMM: median over repeats of a 2 s run at dt = 1e-3 after JIT warm-up, per step, for the
Riccati (reduced [a; q]), full-state Riccati and direct sweeps.  Reference: DOP853 at
rtol = 1e-10, per accepted step and per right-hand-side call.  Ratios are taken within the run.
"""
import argparse
import json
import statistics
import time


from dttmm import simulate
from dttmm.model.chains import rigid_chain
from dttmm.reference import simulate_reference


def median_time(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--links", type=int, nargs="+", default=[3, 10])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    out = {}
    t_end, dt = 2.0, 1e-3
    n_steps = int(round(t_end / dt))
    for n in args.links:
        model = rigid_chain(n)
        simulate(model, 0.01, dt)                                   # JIT warm-up
        simulate(model, 0.01, dt, full_state=True)
        simulate(model, 0.01, dt, method="direct")
        simulate_reference(model, 0.01)
        row = {}
        for name, kw in (("riccati", {}), ("riccati_full_state", dict(full_state=True)),
                         ("direct", dict(method="direct"))):
            wall = median_time(lambda: simulate(model, t_end, dt, record_every=n_steps, **kw),
                               args.repeats)
            row[f"dttmm_{name}_us_per_step"] = 1e6 * wall / n_steps
        ref = simulate_reference(model, t_end, rtol=1e-10, atol=1e-12)
        wall = median_time(lambda: simulate_reference(model, t_end, rtol=1e-10, atol=1e-12),
                           max(1, args.repeats // 2))
        row["reference_us_per_step"] = 1e6 * wall / ref.n_steps
        row["reference_us_per_rhs"] = 1e6 * wall / ref.info["nfev"]
        row["reference_steps_2s"] = ref.n_steps
        row["reference_wall_2s_s"] = wall
        row["dttmm_wall_2s_s"] = row["dttmm_riccati_us_per_step"] * n_steps * 1e-6
        row["reference_to_dttmm_wall_ratio_2s"] = wall / row["dttmm_wall_2s_s"]
        out[f"chain{n}"] = row
        print(f"N = {n}: " + ", ".join(f"{k} {v:.4g}" for k, v in row.items()))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
