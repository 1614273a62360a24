import os
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))


def pytest_configure(config):
    # A sound run of the suite never trips the unresolved-step flag (tests that mean to catch
    # it).  Added here, not in pyproject.toml's filterwarnings: pytest would import dttmm to
    # resolve that option's warning class as it reads the file.
    config.addinivalue_line("filterwarnings", "error::dttmm.solving.solver.UnresolvedMotionWarning")


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


def _compile_families(directory):
    """Each family compiled by the first worker to lock it; the rest waited for."""
    import fcntl
    import time
    import warnings
    from dttmm.interfaces.precompile import FAMILIES, compile_family
    left = [name for name, _ in FAMILIES]
    for blocking in (False, True):
        for name in tuple(left):
            with open(directory / f"{name}.lock", "a") as lock:
                try:
                    fcntl.flock(lock, fcntl.LOCK_EX | (0 if blocking else fcntl.LOCK_NB))
                except BlockingIOError:
                    continue                    # another worker compiles it
                done = directory / f"{name}.done"
                if not done.exists():
                    t0 = time.perf_counter()
                    try:            # (dttmm compile's families: dttmm/interfaces/precompile.py)
                        compile_family(name)
                    except Exception as err:    # (the tests that use it will say what)
                        warnings.warn(f"compiling the {name} kernels first failed: {err}")
                    done.touch()
                    print(f"\n{os.environ.get('PYTEST_XDIST_WORKER')}: the {name} kernels "
                          f"ready in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
            left.remove(name)


def pytest_collection_finish(session):
    run = os.environ.get("PYTEST_XDIST_TESTRUNUID")
    if (run is None or int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")) < 2
            or len(session.items) < WHOLE_SUITE):
        return
    import tempfile
    directory = Path(tempfile.gettempdir()) / f"dttmm-compile-{run}"
    directory.mkdir(exist_ok=True)
    _compile_families(directory)
