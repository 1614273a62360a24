"""BLAS threads against the step, with the other cores kept busy (issue 65, item 2).

    python benchmarks/threads.py [--quick] [--n 10] [--json FILE]

The N-four-bar (dttmm.model.mechanisms.n_four_bar, its default chain tree, dt = 5e-4) is stepped in
child processes, while a busy process spins on every other core (bounded: it stops by itself):
  default   dttmm as a user runs it (a run holds BLAS to one thread: dttmm/solving/threads.py);
  one       OPENBLAS_NUM_THREADS=1 for the whole process (the workaround the issue measured);
  all       simulate(..., threads=cpu count): a thread per core, as BLAS starts by default
            (dttmm before the limit).
Pairs run interleaved (default, one, all, default, one, all, ...); each child reports the best
per-step cost of its runs (a long run less a short one).  Printed: each kind's median and the
ratios default / one (goal <= 1.1) and all / one.  Not a test: nothing is asserted.
"""
import argparse
import json
import os
import subprocess
import sys
import time

CHILD = r"""
import sys, time
import dttmm
from dttmm.model.mechanisms import n_four_bar
n, steps, threads = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
kw = {} if threads == "default" else dict(threads=int(threads))
model, dt = n_four_bar(n), 5e-4
dttmm.simulate(model, 4 * dt, dt, **kw)                      # load the kernels, warm up
best = float("inf")
for _ in range(3):
    t0 = time.perf_counter(); dttmm.simulate(model, 10 * dt, dt, record_every=10, **kw)
    t1 = time.perf_counter(); dttmm.simulate(model, steps * dt, dt, record_every=steps, **kw)
    t2 = time.perf_counter()
    best = min(best, ((t2 - t1) - (t1 - t0)) / (steps - 10))
print(best)
"""

SPIN = "import time\nt = time.perf_counter() + {seconds}\nwhile time.perf_counter() < t: pass\n"


def child_cost(n, steps, kind):
    env = dict(os.environ)
    env.pop("OPENBLAS_NUM_THREADS", None)
    env.pop("DTTMM_BLAS_THREADS", None)
    threads = "default"
    if kind == "one":
        env["OPENBLAS_NUM_THREADS"] = "1"
    elif kind == "all":
        threads = str(os.cpu_count())
    out = subprocess.run([sys.executable, "-c", CHILD, str(n), str(steps), threads], env=env,
                         capture_output=True, text=True, check=True)
    return float(out.stdout.split()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer steps and pairs (CI's smoke)")
    ap.add_argument("--n", type=int, default=10, help="horizontal bars (default 10)")
    ap.add_argument("--json", help="write the figures to this file")
    args = ap.parse_args(argv)
    steps, pairs = (60, 1) if args.quick else (400, 5)
    busy = [subprocess.Popen([sys.executable, "-c", SPIN.format(seconds=1800)])
            for _ in range(max(1, (os.cpu_count() or 2) - 1))]
    try:
        time.sleep(0.5)
        costs = {"default": [], "one": [], "all": []}
        for _ in range(pairs):
            for kind in costs:
                costs[kind].append(child_cost(args.n, steps, kind))
    finally:
        for p in busy:
            p.kill()
    med = {k: sorted(v)[len(v) // 2] for k, v in costs.items()}
    print(f"{args.n}-four-bar, dt = 5e-4, {len(busy)} busy process(es) beside it, "
          f"{pairs} interleaved triple(s):")
    for k, v in costs.items():
        runs = ", ".join(f"{1e3 * c:.3f}" for c in v)
        print(f"  {k:8s} {1e3 * med[k]:8.3f} ms/step (runs {runs})")
    print(f"  default / one thread: {med['default'] / med['one']:.3f} (goal <= 1.1); "
          f"a thread per core / one thread: {med['all'] / med['one']:.3f}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"n": args.n, "costs_s": costs, "median_s": med}, f, indent=1)


if __name__ == "__main__":
    main()
