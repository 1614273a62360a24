"""Adaptive steps against the fixed step of equal error: for each rtol, the error of the
adaptive run at t_end (positions, against the Newton-Euler reference at rtol 1e-12), the
fixed step that reaches the same error (from fixed runs at dt, 2dt, ... : error = C dt^2 from
the nearest one), then interleaved pairs (adaptive, fixed at that step) in one process: the
median wall-time ratio (the issue's criterion: at most 1.5).

    python benchmarks/adaptive.py [--pairs 7]

Also called by benchmarks/run.py.  Not a test: nothing is asserted.
"""
import argparse
import json
import time

import numpy as np

from dttmm import simulate, simulate_reference
from dttmm.model.chains import rigid_chain, three_pendulum


def _wall(fn, *args, **kw):
    t0 = time.perf_counter()
    res = fn(*args, **kw)
    return time.perf_counter() - t0, res


def adaptive_against_fixed(model, t_end, rtols, pairs=7):
    """{rtol: dict(error, steps, rejected, fixed_dt, fixed_error, ratio)}."""
    tip = simulate_reference(model, t_end, rtol=1e-12, atol=1e-14,
                             t_eval=[0.0, t_end]).position_output[-1]

    def error(res):
        return float(np.abs(res.position_output[-1] - tip).max())

    simulate(model, t_end, rtol=rtols[0], t_eval=[t_end])        # JIT warm-up
    fixed = [(dt, error(simulate(model, t_end, dt, t_eval=[t_end])))
             for dt in t_end / np.array([250, 500, 1000, 2000, 4000, 8000, 16000, 32000])]
    out = {}
    for rtol in rtols:
        run = simulate(model, t_end, rtol=rtol, t_eval=[t_end])
        err = error(run)
        dt_near, e_near = min(fixed, key=lambda p: abs(np.log(p[1] / err)))
        dt_equal = dt_near * np.sqrt(err / e_near)
        check = error(simulate(model, t_end, dt_equal, t_eval=[t_end]))
        ratios = []
        for _ in range(pairs):
            t_a, _ = _wall(simulate, model, t_end, rtol=rtol, t_eval=[t_end])
            t_f, _ = _wall(simulate, model, t_end, dt_equal, t_eval=[t_end])
            ratios.append(t_a / t_f)
        out[rtol] = dict(error=err, steps=run.n_steps, rejected=run.info["steps_rejected"],
                         fixed_dt=float(dt_equal), fixed_error=check,
                         ratio=float(np.median(ratios)))
        print(f"rtol {rtol:g}: error {err:.2e} m in {run.n_steps} steps "
              f"(+{run.info['steps_rejected']} rejected); fixed dt {dt_equal:.3g} s: error "
              f"{check:.2e} m; adaptive / fixed wall time {np.median(ratios):.2f} "
              f"({min(ratios):.2f}-{max(ratios):.2f})", flush=True)
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=7)
    args = parser.parse_args(argv)
    out = {}
    for name, model, t_end in (("three_pendulum", three_pendulum(), 2.0),
                               ("chain30", rigid_chain(30), 1.0)):
        print(name, flush=True)
        out[name] = adaptive_against_fixed(model, t_end, (1e-3, 1e-4, 1e-5, 1e-6), args.pairs)
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()
