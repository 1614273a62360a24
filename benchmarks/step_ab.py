"""Per-step cost of two checkouts of dttmm, A against B, in alternating processes.

    python benchmarks/step_ab.py A_DIR B_DIR [--pairs 9] [--json FILE] [--in-process] [--call]

--call: the fixed cost of a simulate call (a 1-step run, us per call) instead of a step's.

--in-process: both checkouts' packages are copied under other names (dttmm_a, dttmm_b; the
package imports itself relatively) into a temporary directory and imported into one process,
which then alternates A and B run by run (the machine's drift between processes, which on these
shared machines reaches 2x, then enters a pair only through the seconds between its two runs).

For each system (by default the three-pendulum, rigid chains of 3, 100 and 1000 links; --systems
arm flexible_arm: examples/arm.py's arm on the general loop, rigid and flexible; slider_crank: the
general loop with closing joints; four_bar: the 2-four-bar; cantilever: the stiff cantilever of 8
welded elements, the welded-chain loop) the two checkouts are timed in turn, A B A B ..., each time
in a fresh process that imports that checkout's dttmm (warm numba cache, JIT warm-up run first). A
process measures the cost of one step as the difference of a long and a short run over the steps
between (no setup, no recording), the median of 5. The figure per system is the median over the
pairs of the ratio A/B, so that the machine's drift between pairs does not enter it. Not a test:
nothing is asserted.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

SYSTEMS = {          # name: (constructor expression, steps of the long run: ~0.1-0.3 s)
    "three_pendulum": ("three_pendulum()", 40000),
    "rigid_chain_3": ("rigid_chain(3)", 200000),
    "rigid_chain_100": ("rigid_chain(100)", 5000),
    "rigid_chain_1000": ("rigid_chain(1000)", 500),
    "arm": ("arm(drive='motion')", 3000),                   # the general loop (joints)
    "flexible_arm": ("arm(drive='motion', flexible=True)", 2000),   # (joints and a beam)
    "cantilever": ("stiff_cantilever(8)", 5000),            # the welded-chain loop
    "slider_crank": ("slider_crank()", 3000),               # the general loop, closing joints
    "four_bar": ("n_four_bar(2)", 3000),                    # the general loop, two loops
}
DEFAULT = ["three_pendulum", "rigid_chain_3", "rigid_chain_100", "rigid_chain_1000"]

# the models' builders, in either layout (dttmm/model/ since the layer folders; dttmm/ before)
_IMPORTS = """try:
    from dttmm.model.chains import arm, rigid_chain, stiff_cantilever, three_pendulum
    from dttmm.model.mechanisms import n_four_bar, slider_crank
except ImportError:     # a checkout from before the layer folders (issue 66)
    from dttmm.chains import arm, rigid_chain, stiff_cantilever, three_pendulum
    from dttmm.mechanisms import n_four_bar, slider_crank
"""

_CHILD = r"""
import statistics, sys
from dttmm import simulate
{imports}
model = {expr}
steps, dt = {steps}, 1e-4
simulate(model, 5 * dt, dt)
short = max(1, steps // 5)
costs = []
for _ in range(5):
    a = simulate(model, steps * dt, dt, record_every=steps)
    b = simulate(model, short * dt, dt, record_every=short)
    costs.append((a.wall_time - b.wall_time) / (a.n_steps - b.n_steps))
print(1e6 * statistics.median(costs))
"""


# --call: a simulate call's fixed cost, a 1-step run's wall time per call (median of 5 batches
# of 300 calls, after a warm-up)
_CALL_CHILD = r"""
import statistics, time
from dttmm import simulate
{imports}
model = {expr}
for _ in range(50):
    simulate(model, 1e-4, 1e-4)
batches = []
for _ in range(5):
    t0 = time.perf_counter()
    for _ in range(300):
        simulate(model, 1e-4, 1e-4)
    batches.append((time.perf_counter() - t0) / 300)
print(1e6 * statistics.median(batches))
"""


def us_per_step(checkout, system, call=False):
    """us per step of the system with the checkout's dttmm (call: us per 1-step call)."""
    expr, steps = SYSTEMS[system]
    env = dict(os.environ, PYTHONPATH=os.path.abspath(checkout))
    child = (_CALL_CHILD if call else _CHILD).format(imports=_IMPORTS, expr=expr, steps=steps)
    out = subprocess.run([sys.executable, "-c", child],
                         env=env, capture_output=True, text=True, check=True,
                         cwd=os.path.abspath(checkout))
    return float(out.stdout.strip().splitlines()[-1])


def _chains_of(package):
    """A package's chains and mechanisms as one namespace (dttmm/model/ since the layer folders;
    dttmm/ in checkouts from before them)."""
    import importlib
    try:
        names = [f"{package}.model.chains", f"{package}.model.mechanisms"]
        modules = [importlib.import_module(n) for n in names]
    except ImportError:
        modules = [importlib.import_module(f"{package}.{n}") for n in ("chains", "mechanisms")]
    return {**vars(modules[0]), **vars(modules[1])}


def in_process(a_dir, b_dir, systems, pairs):
    """{system: (median us A, median us B, [ratios])} with both packages in this process."""
    import importlib
    import shutil
    import tempfile
    import time
    root = tempfile.mkdtemp(prefix="step_ab_")
    for name, src in (("dttmm_a", a_dir), ("dttmm_b", b_dir)):
        shutil.copytree(os.path.join(src, "dttmm"), os.path.join(root, name), symlinks=True,
                        ignore=shutil.ignore_patterns("__pycache__"))   # caches name dttmm
    sys.path.insert(0, root)
    packages = [importlib.import_module(name) for name in ("dttmm_a", "dttmm_b")]
    chains = [_chains_of(name) for name in ("dttmm_a", "dttmm_b")]
    out = {}
    for system in systems:
        expr, steps = SYSTEMS[system]
        models = [eval(expr, c) for c in chains]                    # noqa: S307
        dt = 1e-4
        short = max(1, steps // 5)

        def cost(i):
            sim, model = packages[i].simulate, models[i]
            t0 = time.perf_counter()
            sim(model, steps * dt, dt, record_every=steps)
            t1 = time.perf_counter()
            sim(model, short * dt, dt, record_every=short)
            t2 = time.perf_counter()
            return 1e6 * ((t1 - t0) - (t2 - t1)) / (steps - short)

        for i in (0, 1):
            packages[i].simulate(models[i], 5 * dt, dt)                   # compile, caches
        a_us, b_us = [], []
        for _ in range(pairs):
            a_us.append(cost(0))
            b_us.append(cost(1))
        out[system] = (a_us, b_us)
    shutil.rmtree(root, ignore_errors=True)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--pairs", type=int, default=9)
    ap.add_argument("--systems", nargs="+", default=DEFAULT, choices=list(SYSTEMS))
    ap.add_argument("--json")
    ap.add_argument("--in-process", action="store_true",
                    help="both packages in one process, alternating run by run")
    ap.add_argument("--call", action="store_true",
                    help="a call's fixed cost (a 1-step run) instead of a step's")
    args = ap.parse_args(argv)
    if args.call and args.in_process:
        ap.error("--call runs in separate processes only (--in-process times steps)")
    unit = "us per call" if args.call else "us"
    out = {}
    if args.in_process:
        for system, (a_us, b_us) in in_process(args.a, args.b, args.systems, args.pairs).items():
            ratios = [a / b for a, b in zip(a_us, b_us)]
            out[system] = dict(a_us_per_step=statistics.median(a_us),
                               b_us_per_step=statistics.median(b_us),
                               ratio_a_over_b=statistics.median(ratios), ratio_min=min(ratios),
                               ratio_max=max(ratios), pairs=args.pairs, in_process=True)
            print(f"{system} (one process): A {out[system]['a_us_per_step']:.3f} us, "
                  f"B {out[system]['b_us_per_step']:.3f} us, "
                  f"A/B {out[system]['ratio_a_over_b']:.3f} (min {min(ratios):.3f}, "
                  f"max {max(ratios):.3f}, {args.pairs} pairs)", flush=True)
    for system in ([] if args.in_process else args.systems):
        us_per_step(args.a, system), us_per_step(args.b, system)     # fill both numba caches
        a_us, b_us, ratios = [], [], []
        for _ in range(args.pairs):
            a_us.append(us_per_step(args.a, system, args.call))
            b_us.append(us_per_step(args.b, system, args.call))
            ratios.append(a_us[-1] / b_us[-1])
        out[system] = dict(a_us_per_step=statistics.median(a_us),
                           b_us_per_step=statistics.median(b_us),
                           ratio_a_over_b=statistics.median(ratios),
                           ratio_min=min(ratios), ratio_max=max(ratios), pairs=args.pairs)
        print(f"{system}: A {out[system]['a_us_per_step']:.3f} {unit}, "
              f"B {out[system]['b_us_per_step']:.3f} {unit}, "
              f"A/B {out[system]['ratio_a_over_b']:.3f} "
              f"(min {min(ratios):.3f}, max {max(ratios):.3f}, {args.pairs} pairs)", flush=True)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
