"""numba kernels on flat arrays: rotations, element transfer matrices, assembly sweeps, the step."""
from numba import njit


def no_alloc_kernel(fn):
    """njit(cache=True) without numba's reference counting (its `_nrt=False` option), for the
    step's kernels that allocate nothing.  Every array argument and every view then costs no
    pair of atomic reference-count calls; numba leaves most of those in functions with loops
    and branches (the compiled beam map had ~400 such call sites).  Measured on the beam's
    reduced map (kernels/beam.py::beam_ball_map): 1.64 against 1.96 us per call.  A kernel
    that allocates fails to compile, so the option cannot hide a mistake."""
    return njit(cache=True, _nrt=False)(fn)
