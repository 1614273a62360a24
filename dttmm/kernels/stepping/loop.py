"""The step skeleton every scheme and loop variant goes through (docs/solver.md, "The step").

A run's data reach the kernels as a few typed structures (numba named tuples), not dozens of
positional arrays:

  params    the frozen model's tables as one flat model (kernels/schema.py::FlatModel: two
            buffers, their offsets and sizes; read by name through kernels/model_tables.py)
  Settings  the run's integrator and Newton settings
  state     the preallocated state the loop advances in place, flat (kernels/schema.py::STATE,
            a FlatState: read by name through kernels/state_tables.py)
  sweep     the assembly's scratch (element transfers, Riccati and direct sweeps), flat
            (kernels/schema.py::SWEEP, a FlatSweep: kernels/sweep_tables.py)
  inputs    one chunk's prescribed data (ground motion, applied loads), step by step, flat
            (kernels/schema.py::INPUTS, a FlatInputs: kernels/input_tables.py)
  rec       where one chunk's samples are written, flat (RECORD, a FlatRecord:
            kernels/record_tables.py)
  monitor   the step's local error estimate, flat (MONITOR, a FlatMonitor:
            kernels/monitor_tables.py; docs/solver.md, "Runs that cannot go wrong")

bundled as one Run, and a loop variant's own scratch (its "loop" structure).  run_steps is the
skeleton: predict, then Newton iterations (iterate: linearize, sweep, recover; adopt: the
solution becomes the next guess), update, record; finish once the chunk is done.  A variant
(the general loop in kernels/stepping/step.py, the fused ball-chain loop in
kernels/stepping/ball_chain.py, the energy-momentum loop in kernels/stepping/em_step.py) supplies
only these pieces, declared once with loop_variant(); each variant gets its own copy of the skeleton
with its pieces inlined (_skeleton), so the skeleton costs nothing at run time.  A loop structure no
variant declared is refused.
"""
from collections import namedtuple
from types import FunctionType

from numba import njit
from numba._dispatcher import compute_fingerprint

from .. import CONTRACT, input_tables, monitor_tables, no_alloc_kernel, state_tables
from ..algebra.mat3 import put1, put2

OK, SINGULAR, NOT_FINITE, UNSUPPORTED, ERROR_ESTIMATE, UNCONVERGED = 0, 1, 2, 3, 4, 5

Settings = namedtuple("Settings", [
    "mode",             # RICCATI_FULL / RICCATI_REDUCED / DIRECT_REDUCED / DIRECT_FULL (step.py)
    "h",                # the step, s
    "coef",             # (4,) beta, gamma, alpha_m, alpha_f (run_tables.Integrator)
    "newton_max",       # extra linearizations per step
    "newton_tol",       # stop iterating below this change (rad; scaled modal units)
    "record_every",     # record after every record_every-th step of a chunk
    "max_step_error",   # stop (ERROR_ESTIMATE) where a step's local error estimate exceeds it
                        # (rad or m; inf: never)
    "stop_unconverged",  # stop (UNCONVERGED) at a step whose Newton iterations do not converge
    "start",            # the consistent start instead of steps: the fused variants' one linear
                        # sweep at acceleration level (kernels/stepping/ball_chain.py::start_loop)
])

# params: the flat model (kernels/schema.py::FlatModel)
Run = namedtuple("Run", ["params", "settings", "state", "sweep", "inputs", "rec", "monitor"])

_PIECES = ("predict", "iterate", "adopt", "update", "record", "finish")
_VARIANTS = {}          # loop structure's class -> {piece name: njit function}


def loop_variant(loop_class, **pieces):
    """Declare a loop variant: the named tuple class of its own scratch and its njit pieces,
    each called as piece(loop, run, s, i):
      predict(loop, run, s, 0)         the guess for step s
      iterate(loop, run, s, it)        linearize, sweep, recover -> (status, detail, change)
      adopt(loop, run, s, it)          the latest solution becomes the guess
      update(loop, run, s, 0)          advance the state over step s -> every value finite
      record(loop, run, s, slot)       write the state into run.rec at slot
      finish(loop, run, n_steps, 0)    once, after the chunk's last step
    """
    if set(pieces) != set(_PIECES):
        raise TypeError(f"loop_variant({loop_class.__name__}): pieces must be exactly {_PIECES}, "
                        f"got {sorted(pieces)}")
    _VARIANTS[loop_class] = dict(pieces)


def _unbound(name):
    def piece(loop, run, s, i):
        raise NotImplementedError(f"{name}: a loop variant's piece, bound in its own skeleton "
                                  f"(loop.py::_skeleton)")
    piece.__name__ = name
    return piece


# the names the skeleton calls; each variant's copy of the skeleton binds them to its pieces
predict, iterate, adopt, update, record, finish = (_unbound(name) for name in _PIECES)


@njit(cache=True, inline='always', fastmath=CONTRACT)
def report(out_info, status, step, detail, n_rec):
    """The loop's outcome in out_info: [status, the failing step (or the steps taken), detail
    (the singular element's code for SINGULAR, the most Newton iterations used for OK, 0 for
    NOT_FINITE), samples recorded]; out_info[4] (unconverged steps) accumulates over chunks."""
    out_info[0] = status
    out_info[1] = step
    out_info[2] = detail
    out_info[3] = n_rec


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _largest_change(now, before, largest):
    for i in range(now.shape[0]):
        largest = max(largest, abs(now[i] - before[i]))
    return largest


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _largest_change2(now, before, largest):
    for i in range(before.shape[0]):
        for j in range(before.shape[1]):
            largest = max(largest, abs(now[i, j] - before[i, j]))
    return largest


@njit(cache=True, inline='always', fastmath=CONTRACT)
def keep_pseudo(pseudo, eta_p, jqp, defl_pseudo, kept):
    """The state's pseudo-accelerations p_n before the step into kept, the monitor's
    (pseudo, eta_p, jqp, defl_pseudo) (for step_error).  The monitor holds rows for what the
    model has: no joint coordinates' rows without joints with coordinates, no deflections' rows
    without elastic hinges (solver.simulate), which it then skips."""
    put2(kept[0], pseudo)        # (over kept's rows: none for a kind not there)
    put1(kept[1], eta_p)
    put2(kept[2], jqp)
    put2(kept[3], defl_pseudo)


@njit(cache=True, inline='always', fastmath=CONTRACT)
def step_error(pseudo, eta_p, jqp, defl_pseudo, kept, h, beta):
    """The step's local error estimate (Zienkiewicz and Xie 1991): the Newmark displacement
    update x = h v_n + h^2 (1/2 - beta) p_n + h^2 beta p_{n+1} differs from the Taylor series by
    (beta - 1/6) h^2 (p_{n+1} - p_n) + O(h^4), so e = |beta - 1/6| h^2 max |p_{n+1} - p_n| over
    every rotation increment (rad), modal coordinate, joint coordinate (rad or m) and elastic
    deflection (m): the state's p_{n+1} against kept's p_n (keep_pseudo)."""
    largest = _largest_change2(pseudo, kept[0], 0.0)
    largest = _largest_change(eta_p, kept[1], largest)
    largest = _largest_change2(jqp, kept[2], largest)
    largest = _largest_change2(defl_pseudo, kept[3], largest)
    return abs(beta - 1.0 / 6.0) * h * h * largest


def _run_steps(loop, run, out_info):
    """Take run.inputs.force.shape[0] steps (docs/solver.md, "The step").  What it reads of
    the run is read here, before the steps: numba keeps a structure read in more than one block
    in a stack slot of its whole type, which LLVM splits up again at every read
    (docs/solver.md, "Compile time", item 6); `run` goes on whole to the pieces only."""
    settings, state, monitor = run.settings, run.state, run.monitor
    pseudo = state_tables.pseudo(state)
    eta_p = state_tables.eta_p(state)
    jqp = state_tables.jqp(state)
    defl_pseudo = state_tables.defl_pseudo(state)
    n_steps = input_tables.force(run.inputs).shape[0]
    newton_max, newton_tol = settings.newton_max, settings.newton_tol
    start, h, beta = settings.start, settings.h, settings.coef[0]
    max_step_error, record_every = settings.max_step_error, settings.record_every
    stop_unconverged = settings.stop_unconverged
    kept = (monitor_tables.pseudo(monitor), monitor_tables.eta_p(monitor),
            monitor_tables.jqp(monitor), monitor_tables.defl_pseudo(monitor))
    error_so_far = monitor_tables.error(monitor)
    max_iter = 0
    n_rec = 0
    for s in range(n_steps):
        if not start:
            predict(loop, run, s, 0)
        change = 0.0
        for it in range(newton_max + 1):
            status, detail, change = iterate(loop, run, s, it)
            if status != OK:
                report(out_info, status, s, detail, n_rec)
                return
            max_iter = max(max_iter, it)
            if it == newton_max or change <= newton_tol:
                break
            adopt(loop, run, s, it)
        if start:       # the accelerations at t = 0 are in: stations written below
            break
        if newton_max > 0 and change > newton_tol:
            out_info[4] += 1
            if stop_unconverged:
                report(out_info, UNCONVERGED, s, 0, n_rec)
                return
        keep_pseudo(pseudo, eta_p, jqp, defl_pseudo, kept)
        if not update(loop, run, s, 0):
            report(out_info, NOT_FINITE, s, 0, n_rec)
            return
        error = step_error(pseudo, eta_p, jqp, defl_pseudo, kept, h, beta)
        error_so_far[0] = max(error_so_far[0], error)
        if not error <= max_step_error:
            error_so_far[1] = error
            report(out_info, ERROR_ESTIMATE, s, 0, n_rec)
            return
        if (s + 1) % record_every == 0:
            record(loop, run, s, n_rec)
            n_rec += 1
    finish(loop, run, n_steps, 0)
    report(out_info, OK, n_steps, max_iter, n_rec)


_SKELETONS = {}     # loop structure's class -> its skeleton


def _skeleton(loop_class):
    """_run_steps for one loop variant: a copy of its code whose globals bind predict, iterate,
    ... to the variant's pieces, compiled (and cached) on its own, without numba's reference
    counting (kernels/__init__.py::no_alloc_kernel).  numba inlines the pieces (njit
    inline='always') before typing.  Measured on a cold cache, the three-pendulum's fused
    skeleton: 60 s against 102 s (CPU) when the pieces were chosen by numba overloads on the
    loop structure's type (docs/solver.md, "Compile time").  The pieces allocate nothing
    themselves (a piece that allocates fails to compile): the fused loops allocate nothing at
    all; the general and energy-momentum loops' kernels that allocate are
    kernels/__init__.py::allocating_kernel.  Measured on the four-bar's cold compile: the
    general loop's skeleton 51 s against 79 s with reference counting (its own code 27 against
    51 s: numba's reference-count calls on every array its structures carry, and LLVM's passes
    over them), and its steps 1.4x faster."""
    compiled = _SKELETONS.get(loop_class)
    if compiled is None:
        pieces = _VARIANTS.get(loop_class)
        if pieces is None:
            raise TypeError(f"run_steps: no loop variant declares {loop_class.__name__} "
                            f"(kernels/stepping/loop.py::loop_variant)")
        name = f"run_steps_{loop_class.__name__}"
        fn = FunctionType(_run_steps.__code__, dict(globals(), **pieces), name)
        fn.__qualname__ = name          # (numba's cache files are named after it)
        fn.__doc__ = _run_steps.__doc__
        compiled = no_alloc_kernel(fn, entry=True)
        _SKELETONS[loop_class] = compiled
    return compiled


def run_steps(loop, run, out_info, calls=None):
    """The skeleton of the loop's variant, compiled once for every model it runs.  calls: the
    prepared run's DirectCalls."""
    (calls or _call)(_skeleton(type(loop)), (loop, run, out_info))


def _call(compiled, args):
    compiled(*args)


class DirectCalls:
    """One prepared run's calls of its skeleton (solver's PreparedRun): a call like the one
    before goes straight to the machine code numba chose for that one.

    numba's dispatcher types every argument of every call before choosing the compiled code:
    for a run's ~100 arrays in named tuples that was 13 of the 16 us a 1-step run spent in its
    compiled call (it fingerprints each named tuple's field names; plain tuples of the same
    arrays take 2 us).  All but three of a prepared run's structures (the loop variant's
    scratch, the model's arrays, the state, the sweep's scratch, the monitor) are the same arrays
    from call to call, written in place, never replaced: their types do not change.  The three that
    do (settings, a chunk's inputs and its record) are fingerprinted as plain tuples (~1 us); where
    they and the skeleton are those of the call before, the call goes to the entry point numba
    dispatched that call to (its compiled code's, which unboxes the arguments as the dispatcher
    would have; with one compiled version, that one; with several, the one of the arguments'
    types, looked up once).  Anything else goes through the dispatcher, as before."""

    def __init__(self):
        self.key = self.entry = None
        self.looked_up = False      # the entry point of self.key looked for (found or not)

    def __call__(self, compiled, args):
        loop, run, out_info = args
        key = (compiled, compute_fingerprint((tuple(run.settings), tuple(run.inputs),
                                              tuple(run.rec), out_info)))
        if key != self.key:
            compiled(*args)
            self.key, self.entry, self.looked_up = key, None, False
        elif self.entry is not None:
            self.entry(*args)
        else:       # the second call of these types: look once (with several compiled
            compiled(*args)     # versions the lookup types every argument, ~1 ms)
            if not self.looked_up:
                self.entry, self.looked_up = _entry_point(compiled, args), True


def _entry_point(compiled, args):
    """The compiled code numba's dispatcher runs for these arguments, or None (numba's
    compilation off; arguments it converts to another version's types)."""
    overloads = getattr(compiled, "overloads", None)
    if not overloads:
        return None
    if len(overloads) == 1:
        return next(iter(overloads.values())).entry_point
    found = overloads.get(tuple(compiled.typeof_pyval(a) for a in args))
    return None if found is None else found.entry_point
