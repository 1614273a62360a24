"""Where a run's time goes, by compiled function: perf's samples named after numba's code.

    python benchmarks/jit_profile.py SYSTEM [--steps N] [--top 30] [--against DIR]
    python benchmarks/jit_profile.py SYSTEM --map-only FILE    (the symbol map alone, no perf)

SYSTEM is one of benchmarks/step_ab.py's (four_bar, arm, three_pendulum, ...).  perf (Debian's
linux-perf) samples the CPU every 0.25 ms, but numba's machine code has no symbols where perf
looks for them, so its samples show as bare addresses.  This script runs the system in a child
process that records each compiled library's object code as numba loads it (from its cache or
from a compile: a hook on CPUCodeLibrary._set_compiled_object), and when the run ends reads
each object's function symbols (nm), places them at the addresses the JIT loaded the object at
(its entry function's address less that function's offset in the object; numba puts all of an
object's code in one section) and writes /tmp/perf-PID.map, the file perf reads for code made at
run time.  A kernel appears under its own name where LLVM did not inline it into its caller.

The report: each function's samples per 1,000 steps (the run's, after a warm-up; the import and
the warm-up are in the samples too, under Python's and LLVM's names, which the table leaves
out), and with --against, the same system under another checkout, side by side.  These
machines' speed drifts between processes by up to 2x: compare functions' shares within a run,
or normalize by a part the change cannot move (the LAPACK routines in a loop that calls them).
Not a test: nothing is asserted (tests/test_kernel_entries.py checks the map).
"""
import argparse
import atexit
import collections
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def demangled(name):
    """numba's mangled name (_ZN5dttmm7kernels9transfers5joint11joint_frameB2v7B...E...) as
    dttmm.kernels.transfers.joint.joint_frame; another name as it is."""
    if not name.startswith("_ZN"):
        return name
    parts, i = [], 3
    while i < len(name) and name[i].isdigit():
        j = i
        while name[j].isdigit():
            j += 1
        length = int(name[i:j])
        parts.append(name[j:j + length])
        i = j + length
    return ".".join(parts).replace("_3c", "<").replace("_3e", ">") or name


def _record_objects():
    """Keep every compiled library's object code as numba loads it: [(library, bytes)]."""
    from numba.core import codegen
    objects = []
    original = codegen.CPUCodeLibrary._set_compiled_object

    def record(self, value):
        objects.append((self, bytes(value)))
        return original(self, value)
    codegen.CPUCodeLibrary._set_compiled_object = record
    return objects


def symbol_map(objects, scratch):
    """Lines 'START SIZE NAME' (hex) for every function of the loaded objects."""
    lines = []
    for i, (library, elf) in enumerate(objects):
        path = os.path.join(scratch, f"{i}.o")
        with open(path, "wb") as f:
            f.write(elf)
        listing = subprocess.run(["nm", "-S", "--defined-only", path], capture_output=True,
                                 text=True).stdout
        functions = []
        for line in listing.splitlines():
            fields = line.split()
            if len(fields) == 4 and fields[2] in "tTwW":
                functions.append((int(fields[0], 16), int(fields[1], 16), fields[3], fields[2]))
        base = None
        for offset, _, name, kind in functions:     # one loaded function places the object: a
            if kind != "T":                         # global one (a weak one, such as the NRT's
                continue                            # helpers, resolves to another object's)
            address = library._codegen._engine.get_function_address(name)
            if address:
                base = address - offset
                break
        if base is not None:
            lines += [f"{base + offset:x} {size:x} {name}"
                      for offset, size, name, _ in functions]
    return list(dict.fromkeys(lines))


def child(system, steps, map_path):
    """Run the system (a warm-up, then `steps` steps of 1e-4 s) and write its symbol map."""
    objects = _record_objects()
    sys.path.insert(0, HERE)
    from step_ab import SYSTEMS, _IMPORTS
    scope = {}
    exec(_IMPORTS + "from dttmm import simulate\n", scope)            # noqa: S102
    model = eval(SYSTEMS[system][0], scope)                            # noqa: S307
    simulate = scope["simulate"]

    def write():
        with tempfile.TemporaryDirectory() as scratch:
            lines = symbol_map(objects, scratch)
        with open(map_path or f"/tmp/perf-{os.getpid()}.map", "w") as f:
            f.write("\n".join(lines) + "\n")
    atexit.register(write)
    simulate(model, 5e-4, 1e-4)
    if steps:
        simulate(model, steps * 1e-4, 1e-4, record_every=steps)


def samples(checkout, system, steps):
    """{function: samples} of a perf record of the system under a checkout's dttmm."""
    env = dict(os.environ, PYTHONPATH=os.path.abspath(checkout), OPENBLAS_NUM_THREADS="1")
    with tempfile.TemporaryDirectory() as scratch:
        data = os.path.join(scratch, "perf.data")
        subprocess.run(["perf", "record", "-q", "-e", "cpu-clock", "-o", data, sys.executable,
                        os.path.abspath(__file__), system, "--child", str(steps)],
                       env=env, cwd=os.path.abspath(checkout), check=True,
                       stdout=subprocess.DEVNULL)
        report = subprocess.run(["perf", "report", "-i", data, "-n", "--no-children",
                                 "--sort", "sym", "--stdio"], capture_output=True, text=True,
                                check=True).stdout
    counts = collections.Counter()
    for line in report.splitlines():
        match = re.match(r"\s*[\d.]+%\s+(\d+)\s+\[[.k]\]\s+(\S+)", line)
        if match:
            counts[demangled(match.group(2))] += int(match.group(1))
    return counts


def compiled(name):
    """A function of the run: numba's code, its runtime, LAPACK, BLAS and libm."""
    return (name.startswith(("dttmm", "NRT_", "scipy_", "__")) or "HASWELL" in name
            or name in ("malloc", "free", "cfree@GLIBC_2.2.5", "_int_free", "_int_malloc"))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("system")
    parser.add_argument("--steps", type=int, default=30000)
    parser.add_argument("--top", type=int, default=30)
    parser.add_argument("--against", help="another checkout, profiled the same way")
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--map-only", metavar="FILE", help="run 10 steps, write the map there")
    args = parser.parse_args()
    if args.child is not None or args.map_only:
        child(args.system, 10 if args.map_only else args.child, args.map_only)
        return
    runs = [("this", samples(os.path.dirname(HERE), args.system, args.steps))]
    if args.against:
        runs.append((args.against, samples(args.against, args.system, args.steps)))
    per_k = []                  # per run: {function's name: (samples per 1,000 steps, module)}
    for _, counts in runs:      # (by its name alone: a kernel moved between modules matches)
        table = collections.defaultdict(lambda: [0.0, ""])
        for k, v in counts.items():
            if compiled(k):
                entry = table[k.rsplit(".", 1)[-1]]
                entry[0] += 1000.0 * v / args.steps
                entry[1] = k.rsplit(".", 1)[0] if "." in k else ""
        per_k.append(table)
    names = sorted(set().union(*per_k), key=lambda k: -max(p.get(k, [0.0])[0] for p in per_k))
    print(f"{args.system}: samples (0.25 ms each) per 1,000 steps of 1e-4 s")
    print("  ".join(f"{label[-12:]:>12}" for label, _ in runs) + "  function (module)")
    for k in names[:args.top]:
        module = next(p[k][1] for p in per_k if k in p)
        print("  ".join(f"{p.get(k, [0.0])[0]:12.1f}" for p in per_k) + f"  {k} ({module})")
    for label, keep in (("every compiled function", lambda k: True),
                        ("LAPACK and BLAS", lambda k: k.startswith("scipy_") or "HASWELL" in k)):
        print("  ".join(f"{sum(v[0] for k, v in p.items() if keep(k)):12.1f}" for p in per_k)
              + f"  ({label})")


if __name__ == "__main__":
    main()
