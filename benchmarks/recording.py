"""What recording costs: a run recording every step against the same run recording only its end
(interleaved pairs in one process), and the peak memory of a long run with the default
recording (in a subprocess of its own).

    python benchmarks/recording.py [--pairs 15] [--links 100 --t-end 5 --dt 1e-4]

Also called by benchmarks/run.py.  Not a test: nothing is asserted.
"""
import argparse
import json
import resource
import subprocess
import sys
import time

import numpy as np

from dttmm import simulate
from dttmm.model.chains import rigid_chain, three_pendulum


def recording_overhead(model, steps=2000, dt=1e-3, pairs=15):
    """Interleaved pairs of the same run recording every step and only its end: the median
    ratio of the whole calls (the issue's criterion: at most 1.5), the extra cost per recorded
    sample (us), and what reading the derived quantities of every sample costs afterwards
    (positions; energies), us per sample."""
    t_end = steps * dt
    simulate(model, 10 * dt, dt)                                  # JIT warm-up
    ratios, per_sample, positions, energies = [], [], [], []
    for _ in range(pairs):
        t0 = time.perf_counter()
        full = simulate(model, t_end, dt, record_every=1)
        t_full = time.perf_counter() - t0
        t0 = time.perf_counter()
        end = simulate(model, t_end, dt, record_every=steps)
        t_end_only = time.perf_counter() - t0
        t0 = time.perf_counter()
        full.position_output
        t1 = time.perf_counter()
        full.kinetic
        t2 = time.perf_counter()
        ratios.append(t_full / t_end_only)
        per_sample.append(1e6 * (t_full - t_end_only) / (len(full.t) - len(end.t)))
        positions.append(1e6 * (t1 - t0) / len(full.t))
        energies.append(1e6 * (t2 - t1) / len(full.t))
    return dict(full_over_end_only=float(np.median(ratios)),
                extra_us_per_sample=float(np.median(per_sample)),
                positions_us_per_sample=float(np.median(positions)),
                energies_us_per_sample=float(np.median(energies)),
                end_only_ms=1e3 * t_end_only, samples=len(full.t))


def _peak_mb():
    """This process's peak resident memory, MB: VmHWM on Linux (ru_maxrss there keeps the peak
    of the process that forked this one, e.g. a large pytest process), ru_maxrss elsewhere."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _long_run(links, t_end, dt, record_every=0, stream="-"):
    model = rigid_chain(links)
    t0 = time.perf_counter()
    res = simulate(model, t_end, dt, progress=False, record_every=record_every or None,
                   stream=None if stream == "-" else stream)
    if stream == "-":
        res.position_output                                       # derived on first read
    wall = time.perf_counter() - t0
    peak_mb = _peak_mb()
    print(json.dumps(dict(links=links, t_end=t_end, dt=dt, samples=len(res.t), wall_s=wall,
                          peak_mb=peak_mb)))


def long_run_memory(links=100, t_end=5.0, dt=1e-4, record_every=0, stream="-"):
    """Peak resident memory (MB) of a process that builds a `links`-link chain, runs it with
    the default recording (or every record_every-th step; streamed to the directory `stream`)
    and reads its positions (not when streamed): the process's own peak, imports and loaded
    kernels included.  A short run in a process before it fills numba's cache, so that the
    measured process loads the kernels instead of compiling them (compiling takes ~1 GB)."""
    for t in (10 * dt, t_end):
        out = subprocess.run([sys.executable, __file__, "--child", str(links), str(t), str(dt),
                              str(record_every), str(stream)],
                             capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pairs", type=int, default=15)
    ap.add_argument("--links", type=int, default=100)
    ap.add_argument("--t-end", type=float, default=5.0)
    ap.add_argument("--dt", type=float, default=1e-4)
    ap.add_argument("--child", nargs=5, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        _long_run(int(args.child[0]), float(args.child[1]), float(args.child[2]),
                  int(args.child[3]), args.child[4])
        return
    for name, model in (("three-pendulum", three_pendulum()), ("rigid chain, 3 links",
                                                               rigid_chain(3))):
        print(name, json.dumps(recording_overhead(model, pairs=args.pairs)))
    print("long run", json.dumps(long_run_memory(args.links, args.t_end, args.dt)))


if __name__ == "__main__":
    main()
