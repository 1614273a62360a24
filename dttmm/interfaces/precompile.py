"""`dttmm compile`: every compiled family of kernels, ahead of the first run (docs/solver.md,
"Compile time").

One compiled core runs every kind of model: the general loop (its consistent start, sweeps,
closing joints, beams, strain rods, elastic hinges and joints with coordinates, read from the
model's tables at run time), with statics, forward dynamics and linearize on its start, and
the kernels the Python layer calls around it (solving/core.py).  The fused loops (ball chains,
trees, welded chains, the energy-momentum scheme, DOP853) and the Newton-Euler reference are
families of their own, each compiled on its first use.  numba keeps
what it compiles in its cache (`cache_location()`); a later process, whatever its model,
loads it.  Each family below is compiled by a short run of a small model in a process of its
own, as many at once as the machine has cores (numba compiles on one).  After it a read-only
install compiles nothing (tests/test_precompile.py).
"""
import os
import subprocess
import sys
import time


def _general_loop():
    """The core: the general loop, its start and the kernels Python calls around it
    (solving/core.py), which statics, linear models and forward dynamics take theirs from."""
    from ..model.chains import arm, stiff_cantilever, three_pendulum
    from ..model.mechanisms import n_four_bar
    from ..solving.dynamics import forward_dynamics, linearize
    from ..solving.solver import simulate
    from ..solving.statics import static_equilibrium
    simulate(arm(), 2e-3, 1e-3)
    simulate(n_four_bar(2), 2e-3, 1e-3, hold_energy=True)
    simulate(three_pendulum(), 2e-3, 1e-3, scheme="paper")
    simulate(arm(), 2e-3, 1e-3, rtol=1e-6)
    static_equilibrium(stiff_cantilever(2))
    linearize(n_four_bar(2))
    forward_dynamics(arm(), 0.0)


def _fused_chain():
    from ..model.chains import rigid_chain
    from ..solving.solver import simulate
    for scheme in ("newmark", "dop853", "energy_momentum"):
        simulate(rigid_chain(3), 2e-3, 1e-3, scheme=scheme)


def _fused_tree():
    from ..model.chains import five_link_tree
    from ..solving.solver import simulate
    for scheme in ("newmark", "dop853"):
        simulate(five_link_tree(), 2e-3, 1e-3, scheme=scheme)


def _welded_chain():
    from ..model.chains import stiff_cantilever
    from ..solving.solver import simulate
    simulate(stiff_cantilever(2), 2e-3, 1e-3)


def _reference():
    from ..model.chains import arm, three_pendulum
    from ..reference import simulate_reference
    simulate_reference(three_pendulum(), 1e-3)
    simulate_reference(arm(), 1e-3)


def _reference_rhs():
    """The reference's right-hand side as scipy's solve_ivp calls it."""
    from ..model.chains import arm
    from ..reference import simulate_reference
    simulate_reference(arm(), 1e-3, method="RK45")


# (name, what compiles it), the longest first
FAMILIES = (("general loop", _general_loop), ("reference", _reference),
            ("fused tree", _fused_tree), ("fused chain", _fused_chain),
            ("welded chain", _welded_chain), ("reference right-hand side", _reference_rhs))


def compile_family(name):
    """Compile the family called `name` (FAMILIES) in this process, quietly."""
    import contextlib
    import io
    import warnings
    job = dict(FAMILIES)[name]
    with contextlib.redirect_stderr(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")         # (the short runs' flags on their steps)
        job()


def cache_location():
    """Where numba keeps dttmm's compiled kernels: beside their sources (__pycache__ folders in
    the installed package), or NUMBA_CACHE_DIR where it is set, or numba's per-user cache where
    the package is not writable."""
    from ..kernels.algebra.mat3 import matmul
    matmul(_eye(), _eye())          # (loads or compiles it: its cache is then located)
    path = matmul._cache._cache_path
    package = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))     # dttmm/
    if path.startswith(package):
        return f"{package} (the __pycache__ folder beside each kernel's source)"
    return path


def _eye():
    import numpy as np
    return np.eye(3)


def compile_all(jobs=None, progress=True, out=sys.stderr):
    """Compile every family (FAMILIES), `jobs` processes at once (default: the machine's cores);
    return {family: seconds}.  Raises RuntimeError naming a family whose run failed."""
    jobs = max(1, int(jobs or os.cpu_count() or 1))
    waiting, running, took = list(FAMILIES), {}, {}
    t0 = time.perf_counter()
    total = len(FAMILIES)

    def show(note):
        if progress:
            done = len(took)
            bar = "#" * (20 * done // total) + "-" * (20 - 20 * done // total)
            print(f"\rdttmm compile [{bar}] {done}/{total} {note:60s}", end="", file=out,
                  flush=True)

    show(f"compiling {', '.join(n for n, _ in FAMILIES[:jobs])}")
    while waiting or running:
        while waiting and len(running) < jobs:
            name, _ = waiting.pop(0)
            command = [sys.executable, "-c",
                       "from dttmm.interfaces.precompile import compile_family; "
                       f"compile_family({name!r})"]
            running[name] = (subprocess.Popen(command, stdout=subprocess.DEVNULL,
                                              stderr=subprocess.PIPE, text=True),
                             time.perf_counter())
        time.sleep(0.2)
        for name, (process, started) in tuple(running.items()):
            if process.poll() is None:
                continue
            del running[name]
            if process.returncode != 0:
                for other, _ in running.values():
                    other.kill()
                error = process.stderr.read().strip().splitlines()[-1:]
                raise RuntimeError(f"dttmm compile: the {name} family failed: {error}")
            took[name] = time.perf_counter() - started
            show(f"{name} ready ({took[name]:.0f} s, {time.perf_counter() - t0:.0f} s in all)")
    if progress:
        print(file=out)
    return took
