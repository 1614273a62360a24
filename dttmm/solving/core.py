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

Where the machine has a second core, the first use compiles in two processes (docs/solver.md,
"Compile time", item 15): numba caches each kernel on its own, and a kernel that another
process has cached is loaded, not compiled, when a caller reaches it.  So a helper process
compiles the consistent start (`initial_accelerations` with the element transfers under it,
helper_calls) while this one compiles the loops' solves and projection, which the start calls
too (main_calls, first, so the helper finds them cached), and the list above; the skeleton,
compiled last, then loads both.  The argument types are this run's (numba types pickle), and
tests/test_precompile.py checks that they are the ones the skeleton calls with (else the
helper's work would be compiled again: slower, never wrong).
"""
import importlib
import os
import pickle
import subprocess
import sys

import numpy as np
from numba import typeof
from numba.core import types

from ..kernels import python_twin
from ..kernels.algebra.so3 import expm_so3, left_jacobian, log_so3
from ..kernels.assembly.closure import row_residuals, set_ground, solve_with_loops
from ..kernels.assembly.loop_projection import _dependent_frames, project_onto_loops, start_energy
from ..kernels.stepping import step as kstep
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


def _row(array_type):
    """numba's type of a[i] for an array a of array_type (C rows stay C)."""
    return array_type.copy(ndim=array_type.ndim - 1,
                           layout="C" if array_type.layout == "C" else "A")


def helper_calls(loop, run):
    """(kernel, argument types) the helper process compiles: the consistent start, as the
    skeleton calls it (kernels/stepping/step.py::_iterate, inputs at step s); loop and run: the
    general loop's scratch and Run (kernels/stepping/loop.py)."""
    inputs = run.inputs
    ground = types.BaseTuple.from_types([_row(typeof(inputs.g_acc)), _row(typeof(inputs.g_rot)),
                                         _row(typeof(inputs.g_w)), _row(typeof(inputs.g_wd))])
    return ((kstep.initial_accelerations,
             (typeof(run.params), typeof(run.settings), typeof(run.state), typeof(run.sweep),
              ground, _row(typeof(inputs.force)), _row(typeof(inputs.torque)),
              _row(typeof(inputs.line_load)), _row(typeof(inputs.joint_input)),
              typeof(loop.loops), typeof(loop.scratch.forces),
              typeof(_contacts_of_scratch(loop.scratch)))),)


def _contacts_of_scratch(g):
    """The general loop's contacts argument of the start (kernels/stepping/step.py::
    _contacts_of) from its scratch's tables, for its type."""
    inst = (g.contact_point, g.contact_offset, g.contact_force, g.contact_slope,
            g.contact_next, g.contact_body_first, g.contact_count)
    return inst, (inst[5], inst[4], inst[0], inst[1], inst[2], inst[3]), g.contact_centre


def main_calls(loop, run):
    """(kernel, argument types) this process compiles before python_calls while the helper
    compiles helper_calls: the sweeps of a step with and without closing joints and the
    projection onto the loops, as the start (step.py::initial_accelerations) and the skeleton's
    update call them."""
    params, state, sweep, loops = (typeof(run.params), typeof(run.state), typeof(run.sweep),
                                   typeof(loop.loops))
    integer = typeof(0)
    root_f = typeof(np.zeros(6))
    rot, omega, z = typeof(run.state.rot), typeof(run.state.omega), typeof(run.state.z)
    parent = types.Array(params.types[1].dtype, 1, "C")     # (model_tables.parent's view)
    tip_pinned = params.types[1].dtype                      # (a table's one value)
    return ((kstep.solve_step, (integer, tip_pinned, parent, sweep, root_f, z)),
            (solve_with_loops, (params, sweep, root_f, loops, rot, omega, z)),
            (project_onto_loops, (params, loops, state)))


def complete(params, loops, state, loop=None, run=None):
    """Where the core compiles in this process (compiled_here), compile every kernel of
    python_calls too; once per process (every run on the general loop, statics, linear models
    and forward dynamics call this after set_ground, before the skeleton).  loop, run: the
    general loop's scratch and Run, where the skeleton follows: with a second core, a helper
    process compiles part of the core meanwhile (helper_calls)."""
    if _completed:
        return
    _completed.append(True)
    if not compiled_here():
        return
    helper = None
    calls = python_calls(params, loops, state)
    if loop is not None and (os.cpu_count() or 1) > 1:
        helper = _start_helper(helper_calls(loop, run))
        if helper is not None:
            calls = main_calls(loop, run) + calls
    try:
        for kernel, argument_types in calls:
            kernel.compile(argument_types)
        if helper is not None:
            helper.wait(timeout=HELPER_TIMEOUT)
    except subprocess.TimeoutExpired:       # (the skeleton compiles what is missing)
        pass
    finally:                                # (also where this process is interrupted)
        if helper is not None and helper.poll() is None:
            helper.kill()


HELPER_TIMEOUT = 900.0      # s: far beyond the helper's share (~50 s on the slower machines)


def _start_helper(calls):
    """A process compiling `calls` (kernel, argument types) into numba's cache, or None where
    one cannot start (this process then compiles everything itself)."""
    # (this package, not another on the helper's path: its folder first where it is not on the
    # path already, as a checkout's; an installed package's folder, site-packages, is)
    parent = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    program = (f"import sys\nif {parent!r} not in sys.path: sys.path.insert(0, {parent!r})\n"
               f"from dttmm.solving.core import compile_sent\ncompile_sent()\n")
    try:
        payload = pickle.dumps([(kernel.py_func.__module__, kernel.py_func.__name__,
                                 argument_types) for kernel, argument_types in calls])
        process = subprocess.Popen([sys.executable, "-c", program], stdin=subprocess.PIPE,
                                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        process.stdin.write(payload)
        process.stdin.close()
    except (OSError, TypeError, ValueError, pickle.PicklingError, AttributeError):
        return None
    return process


def compile_sent():
    """The helper process (_start_helper): compile the calls pickled on stdin."""
    for module, name, argument_types in pickle.loads(sys.stdin.buffer.read()):
        getattr(importlib.import_module(module), name).compile(argument_types)


def compiled_here():
    """Whether this process compiled set_ground rather than loading it from numba's cache: the
    core's first use on this install (or its cache dropped after an edit of the kernels)."""
    stats = getattr(set_ground, "stats", None)         # (None: numba's compilation off)
    return stats is not None and sum(stats.cache_misses.values()) > 0
