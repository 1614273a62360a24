"""BLAS threads during a run (docs/solver.md, "Threads").

The loop kernels call LAPACK through numba's ``np.linalg`` on small blocks (an SVD of a loop's
rows, solves of 6 x 6 and 12 x 12 systems).  OpenBLAS starts a thread per core for each call; on
blocks this small the threads only wait for each other, and where another process keeps a core
busy they wait for it: the N = 10 four-bar stepped 5x slower with the default threads than with
one (issue 65).  A run therefore holds every BLAS library loaded in the process to one thread
while it steps, unless the caller asks for more: ``simulate(..., threads=k)`` or the environment
variable DTTMM_BLAS_THREADS=k.  The limit is set on entry to the run and the previous one
restored on exit (threadpoolctl), so the user's own numpy work around the run is untouched.
The fused loops (ball chains, trees, welded chains, DOP853) call no LAPACK: their runs set no
limit (setting and restoring it costs ~20 us, a short run's largest fixed cost).
"""
import os
from contextlib import contextmanager

ENVIRONMENT = "DTTMM_BLAS_THREADS"
_controller = None


def thread_count(threads=None):
    """How many BLAS threads a run may use: `threads` if given, else DTTMM_BLAS_THREADS, else
    1.  Raises ValueError for anything but a whole number >= 1."""
    where = "threads"
    if threads is None:
        threads = os.environ.get(ENVIRONMENT)
        if threads is None:
            return 1
        where = f"the environment variable {ENVIRONMENT}"
        try:
            threads = int(threads)
        except ValueError:
            raise ValueError(f"{where} must be a whole number >= 1, got {threads!r}") from None
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"simulate: {where} must be a whole number >= 1 (BLAS threads during "
                         f"the run), got {threads!r}")
    return threads


def _blas():
    """The process's BLAS libraries (one ThreadpoolController, made once: finding them costs
    ~16 ms, setting a limit ~0.1 ms).  numba's np.linalg calls scipy's LAPACK, so scipy's
    library is loaded first to be found with numpy's."""
    global _controller
    if _controller is None:
        import scipy.linalg.cython_lapack  # noqa: F401  (loads the library numba calls)
        from threadpoolctl import ThreadpoolController
        _controller = ThreadpoolController()
    return _controller


@contextmanager
def blas_threads(threads=None, needed=True):
    """Hold the process's BLAS libraries to thread_count(threads) threads inside the block,
    where `needed` (a loop that calls LAPACK: solver._simulate)."""
    threads = thread_count(threads)
    if not needed:
        yield
        return
    with _blas().limit(limits=threads, user_api="blas"):
        yield
