"""numba kernels on flat arrays, in layers, each using only those above it:

  algebra/     3 x 3 algebra and rotations (mat3.py, so3.py)
  transfers/   each element's transfer matrix over one step (body, beam, hinge, joint, em_body)
  assembly/    one step's sweeps (sweep.py) and the closing joints held with them (closure.py)
  stepping/    the time loops: the step skeleton (loop.py), its variants (step.py, ball_chain.py,
               tree.py, weld_chain.py, em_step.py) and the high-order integrator (runge_kutta.py)

with, here, the decorators every kernel is compiled with and features.py, the flags that
compile a copy of the kernels per kind of model."""
from pathlib import Path

from numba import njit


def _drop_stale_caches():
    """numba checks a cached kernel against its own source file only, not against the files of
    the kernels it calls or inlines (the step skeleton in loop.py inlines the pieces of step.py,
    ball_chain.py, ...): after an edit of one of those (a git pull on an editable install) the
    skeleton would load stale machine code.  So every numba cache index older than the newest
    source file the kernels are compiled from (kernels/, elements/ for their constants,
    reference/) is dropped before anything compiles; the kernels then compile afresh once.
    Installed packages write their caches after their sources and keep them."""
    package = Path(__file__).resolve().parent.parent
    try:
        newest = max(p.stat().st_mtime for part in ("kernels", "elements", "reference")
                     for p in (package / part).rglob("*.py"))
        for index in package.rglob("__pycache__/*.nbi"):
            if index.stat().st_mtime < newest:
                index.unlink()
    except OSError:         # a read-only or concurrently changing installation: leave it
        pass


_drop_stale_caches()


# numba's fastmath flag 'contract' alone, on every kernel of the package (and the Newton-Euler
# reference's): LLVM may fuse a * b + c into one fused multiply-add (one rounding instead of two;
# what C compilers do by default) and assumes nothing else (no reassociation; NaN and infinity
# stay as they are, so the finite checks keep working).  Measured with it on the fused loop's
# kernels alone: the beam map 0.84x, the three-pendulum's step 0.84x (15 interleaved pairs);
# trajectories move at the rounding level.
CONTRACT = {"contract"}


def loop_piece(fn):
    """A loop variant's piece (kernels/stepping/loop.py), inlined by numba into the skeleton: each
    piece takes the run's structures, which a call would pass as hundreds of scalars."""
    return njit(cache=True, inline='always', fastmath=CONTRACT)(fn)


def no_alloc_kernel(fn):
    """njit(cache=True) without numba's reference counting (its `_nrt=False` option), for the
    step's kernels that allocate nothing.  Every array argument and every view then costs no
    pair of atomic reference-count calls; numba leaves most of those in functions with loops
    and branches (the compiled beam map had ~400 such call sites).  Measured on the beam's
    reduced map (kernels/transfers/beam.py::beam_ball_map): 1.64 against 1.96 us per call; on the
    fused ball-chain loop (kernels/stepping/ball_chain.py::_ball_chain_steps, its scratch allocated
    by its caller): 0.88x the time per step.  A kernel that allocates fails to compile (numba
    compiles its callees the same way), so the option cannot hide a mistake."""
    return njit(cache=True, _nrt=False, fastmath=CONTRACT)(fn)


def allocating_kernel(fn):
    """njit(cache=True) with numba's reference counting on, said explicitly (its `_nrt=True`),
    for the kernels the general and energy-momentum loops' pieces call that allocate, or call
    kernels that do (in step.py, every kernel the pieces call but the copy helpers `_put*`,
    `_all_finite`, `_integrator_coefficients`: a few of them, `_hinge_deflection` and
    `_locked_frame` among them, allocate nothing and would compile either way): every skeleton
    is compiled without reference counting
    (kernels/stepping/loop.py::_skeleton), and numba compiles a kernel called from another with
    its caller's setting unless the kernel sets its own (so would not compile these).  An array
    such a kernel allocates lives and dies in it: it returns status codes and numbers, never a
    new array (nothing would free one)."""
    return njit(cache=True, _nrt=True, fastmath=CONTRACT)(fn)


# Small kernels called once per body and step (the predictor and history updates, the
# exponential and left Jacobian, the 3 x 3 products and inverse, the reduced Riccati step and
# recovery, the rigid body's reduced map) are declared njit(cache=True, inline='always'):
# numba inlines them into each caller before compiling it.  Measured in one process, 21
# interleaved pairs: the predictor, history, so3, Riccati step and recovery kernels 0.78x the
# time per step on the rigid 3-link chain and 0.90x on the three-pendulum (twice); the rigid map
# and the 3 x 3 product and inverse a further 0.87x and 0.95x (once).  A cold numba cache takes
# ~25 s longer to fill (114 against 87 s).
