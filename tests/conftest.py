import os
import sys
from pathlib import Path

import pytest

# The suite runs dozens of kinds of models: one copy of the kernels with every feature compiled
# in serves them all (each kind would otherwise compile its own copy, about a minute each on 2
# cores; kernels/features.py).  tests/test_kernel_features.py turns the copies back on.  Set
# before dttmm is imported; the CLI's subprocesses inherit it.
os.environ.setdefault("DTTMM_SPECIALIZE", "0")

sys.path.insert(0, str(Path(__file__).parent))


def pytest_configure(config):
    # A sound run of the suite never trips the unresolved-step flag (tests that mean to catch
    # it).  Added here, not in pyproject.toml's filterwarnings: pytest resolves that option's
    # warning class when it reads the file, so dttmm was imported before the line above set
    # DTTMM_SPECIALIZE, and a run in one process compiled a copy of the kernels per kind of model.
    config.addinivalue_line("filterwarnings", "error::dttmm.solver.UnresolvedMotionWarning")


@pytest.fixture(autouse=True)
def _package_calls_only_entry_kernels():
    """The package's Python code calls only kernels compiled with numba's entry points for Python
    (kernels/__init__.py: entry=True); a call of a callee kernel from it runs the kernel's twin,
    a second compilation of its code, and fails the test that made it."""
    yield
    from dttmm import kernels
    if kernels.CALLED_BY_PACKAGE:
        names = sorted(kernels.CALLED_BY_PACKAGE)
        kernels.CALLED_BY_PACKAGE.clear()
        pytest.fail(f"dttmm's Python code called the callee kernels {names}: declare them "
                    f"entry=True (kernels/__init__.py::kernel)")


# --- The kernels compiled once per suite, in parallel -------------------------------------
# From a fresh clone most of the suite's time is numba compiling.  Run by pytest-xdist, each
# worker compiles whatever its first tests need, so both compiled the general loop and its start
# at once (each ~45 s of the first minute: a compile log of every worker found 191 of the
# suite's 814 s of compiling done twice).  Here each worker first takes, under a file lock, the
# next family of kernels no worker has taken, compiles it by a short run, and waits for the
# families the other workers hold; every test then loads them from numba's cache.  Only for a
# whole suite over several workers: a few tests run alone compile only what they use.
WHOLE_SUITE = 300          # tests collected


def _compile_general_loop():
    from helpers import joints_arm

    from dttmm import simulate
    simulate(joints_arm(), 2e-3, 1e-3)


def _compile_fused_tree():
    from dttmm import simulate
    from dttmm.chains import five_link_tree
    simulate(five_link_tree(), 2e-3, 1e-3)
    simulate(five_link_tree(), 2e-3, 1e-3, scheme="dop853")


def _compile_fused_chain():
    from dttmm import simulate
    from dttmm.chains import rigid_chain
    simulate(rigid_chain(3), 2e-3, 1e-3)
    simulate(rigid_chain(3), 2e-3, 1e-3, scheme="dop853")
    simulate(rigid_chain(3), 2e-3, 1e-3, scheme="energy_momentum")


def _compile_welded_chain():
    from dttmm import simulate
    from dttmm.chains import stiff_cantilever
    simulate(stiff_cantilever(2), 2e-3, 1e-3)


def _compile_reference():
    from helpers import joints_arm

    from dttmm.chains import three_pendulum
    from dttmm.reference import simulate_reference
    simulate_reference(three_pendulum(), 1e-3)
    simulate_reference(joints_arm(), 1e-3)


def _compile_reference_rhs():
    """The reference's right-hand side as scipy's solve_ivp calls it (the twin of rhs_kernel, a
    callee the compiled integrator links: ~30 s), which the first test through scipy on each
    worker compiled otherwise (measured: both did)."""
    from helpers import joints_arm

    from dttmm.reference import simulate_reference
    simulate_reference(joints_arm(), 1e-3, method="RK45")


# (taken in this order: measured, the worker that takes the general loop then takes the welded
# chain and the reference's right-hand side while the other compiles the reference, the fused
# tree and the fused chain, each ~6 minutes on 2 cores of an AMD EPYC)
KERNEL_FAMILIES = (("general_loop", _compile_general_loop), ("reference", _compile_reference),
                   ("fused_tree", _compile_fused_tree), ("fused_chain", _compile_fused_chain),
                   ("welded_chain", _compile_welded_chain),
                   ("reference_rhs", _compile_reference_rhs))


def _compile_families(directory):
    """Each family compiled by the first worker to lock it; the rest waited for."""
    import contextlib
    import fcntl
    import io
    import time
    import warnings
    left = list(KERNEL_FAMILIES)
    for blocking in (False, True):
        for name, job in tuple(left):
            with open(directory / f"{name}.lock", "a") as lock:
                try:
                    fcntl.flock(lock, fcntl.LOCK_EX | (0 if blocking else fcntl.LOCK_NB))
                except BlockingIOError:
                    continue                    # another worker compiles it
                done = directory / f"{name}.done"
                if not done.exists():
                    t0 = time.perf_counter()
                    try:            # (the compile notices: one line below instead; the
                        #             short runs' flags on what their step resolves)
                        with contextlib.redirect_stderr(io.StringIO()), \
                                warnings.catch_warnings():
                            warnings.simplefilter("ignore")
                            job()
                    except Exception as err:    # (the tests that use it will say what)
                        warnings.warn(f"compiling the {name} kernels first failed: {err}")
                    done.touch()
                    print(f"\n{os.environ.get('PYTEST_XDIST_WORKER')}: the {name} kernels "
                          f"ready in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
            left.remove((name, job))


def pytest_collection_finish(session):
    run = os.environ.get("PYTEST_XDIST_TESTRUNUID")
    if (run is None or int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")) < 2
            or len(session.items) < WHOLE_SUITE):
        return
    import tempfile
    directory = Path(tempfile.gettempdir()) / f"dttmm-compile-{run}"
    directory.mkdir(exist_ok=True)
    _compile_families(directory)
