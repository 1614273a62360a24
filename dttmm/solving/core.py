"""The compiled core's kernels that the Python layer calls directly, compiled with the core
(issue 66: after the first run, no model compiles the core again; docs/solver.md, "Compile
time").

The general loop's skeleton (kernels/stepping/loop.py) is the core: every kind of model runs
it, and statics, linear models and forward dynamics take their start from it.  Around it the
Python layer calls a few small kernels itself: the closing joints' rows and energy, a start's
joint frames, the rods' kinematics, the rotations' exponential and logarithm.  numba compiles
each on its first call, so before this module a slider-crank after an arm compiled for 4.8 s
and a strain rod in a loop for 3.3 s.  `complete` compiles them all, by their argument types
(nothing is run), where the core compiles in this process: on a fresh install the first run
compiles 196 functions instead of 190 (the compiles it replaced took 1-3 s each; not timed on
their own), and no later model of any kind compiles anything of the core.
tests/test_precompile.py checks that the list below is whole (a run of each kind after
`complete` adds no compiled version to any of the core's kernels).
"""
import numpy as np
from numba import typeof

from ..kernels import python_twin
from ..kernels.algebra.so3 import expm_so3, left_jacobian, log_so3
from ..kernels.assembly.closure import row_residuals, set_ground
from ..kernels.assembly.loop_projection import _dependent_frames, start_energy
from ..kernels.transfers.joint import joint_frame, n_coordinates
from ..kernels.transfers.strain_rod import (rod_end_points, rod_jacobians, rod_kinematics,
                                            station_arrays)

_completed = []     # (this process has compiled or loaded them: once)


def _array(ndim, dtype=np.float64):
    """numba's type of a writable C-contiguous array (what every caller passes: copies)."""
    return typeof(np.zeros((1,) * ndim, dtype))


def python_calls(params, loops, state):
    """(kernel, argument types) of each call the Python layer makes into the core; params,
    loops and state: a run's flat model, closing joints' tables and state (their types are
    every model's: one core)."""
    v, m, t3, t4 = _array(1), _array(2), _array(3), _array(4)
    model, rows, st = typeof(params), typeof(loops), typeof(state)
    integer = typeof(0)
    return (
        (expm_so3, (v, m)),                 # model/sections.py, loop_kinematics.py, statics
        (left_jacobian, (v, m)),            # model/sections.py (a beam's end section)
        (log_so3, (m, v)),                  # dynamics.py (a state's rotations)
        (n_coordinates, (integer,)),        # statics.py
        (joint_frame, (integer, v, m, v, v, v, v, v, m, v, v, v, v)),  # run_tables, statics
        (set_ground, (rows, v, v, v, m, v, v)),     # consistent_start.py, dynamics.py
        (row_residuals, (rows, m, v)),              # dynamics.py
        (start_energy, (model, rows, st)),          # run_plan.py (hold_energy)
        (python_twin(_dependent_frames), (model, rows, st, _array(1, np.int64), v)),
        (station_arrays, (integer,)),               # model/rod_motion.py
        (rod_kinematics, (v, t3, t4, v, v, v, t3, m, m, m, m, m)),
        (rod_jacobians, (v, t3, t4, v)),
        (rod_end_points, (v, t3, t4, m, m)),
    )


def complete(params, loops, state):
    """Where the core compiles in this process (compiled_here), compile every kernel of
    python_calls too; once per process (every run on the general loop, statics, linear models
    and forward dynamics call this after set_ground, before the skeleton)."""
    if _completed:
        return
    _completed.append(True)
    if compiled_here():
        for kernel, types in python_calls(params, loops, state):
            kernel.compile(types)


def compiled_here():
    """Whether this process compiled set_ground rather than loading it from numba's cache: the
    core's first use on this install (or its cache dropped after an edit of the kernels)."""
    stats = getattr(set_ground, "stats", None)         # (None: numba's compilation off)
    return stats is not None and sum(stats.cache_misses.values()) > 0
