"""What a model uses, as compile-time constants of the kernels (docs/solver.md, "Compile time").

numba compiles every branch of a function, whether a run ever takes it or not, and links every
kernel a function may call into its machine code, so the general loop's skeleton (with the
loops' solver, the beam's transfer, six sweeps) took 95 s to compile cold for the rigid arm,
which uses none of those.  The kernels therefore test what a model uses through the flags
below, module globals that numba reads as constants: a branch such as

    if HAS_BEAMS and body_kind[k] == BEAM:
        beam_transfer(...)

is dropped with its callee (numba's dead-branch pruning, before typing) where HAS_BEAMS is
False.  The flags are True here, so a kernel called as it is compiles everything, and
`specialized(kernel, features)` gives its copy for one set of features: a copy of its code
whose globals bind the flags to constants and every kernel it calls that reads a flag (through
any depth of calls) to that kernel's copy for the same features.  Each copy is its own numba
function, compiled and cached under its own name (the features in it), so each kind of model
compiles what it uses once per machine.

A flag that is off never makes a kernel run another kind of element: the element dispatch ends
in a refusal (the kernels' UNSUPPORTED codes, or a raise) where a kind is not compiled in, so a
model whose features were mistaken stops naming the element instead of running without it.
"""
import os
from functools import lru_cache
from types import CodeType

from numba import config
from numba.core.dispatcher import Dispatcher

from . import code_copy, recompiled

# DTTMM_SPECIALIZE=0: every kind of model runs the one copy with every flag on (what a test
# suite or a parameter study over many kinds of models wants: each kind would compile its own
# copy, about a minute each on 2 cores, where the one copy compiles once in a few).  With
# numba's compilation off (NUMBA_DISABLE_JIT=1) the kernels are plain Python functions and run
# as that one copy.
SPECIALIZE = os.environ.get("DTTMM_SPECIALIZE", "1") != "0" and not config.DISABLE_JIT

# the model's elements and the scheme (solver.kernel_features sets them from a model)
HAS_BEAMS = True                # modal beams (body kind BEAM)
HAS_RODS = True                 # strain rods (body kind ROD)
HAS_ELASTIC_HINGES = True       # elastic hinges (hinge kind ELASTIC)
HAS_LOOPS = True                # closing joints (kernels/assembly/closure.py)
HAS_STATION_HISTORIES = True    # the paper's scheme: station points with their own histories
HAS_JOINTS = True               # joints with coordinates (read by the reference's kernels only:
#                                 DT-TMM's sweeps say so by SWEEP_JOINTS; reference_features)
HAS_EXACT_STIFFENING = True     # stiffened beams' exact foreshortening tables (read by the
#                                 reference's kernels only: newton_euler.py::reference_features)
# the run's sweep (its mode, kernels/assembly/sweep.py): exactly one is on in a model's copy
SWEEP_JOINTS = True             # RICCATI_JOINTS: the full-state tree sweep with joint elements
SWEEP_FULL = True               # RICCATI_FULL: the chain's full-state Riccati sweep
SWEEP_DIRECT_FULL = True        # DIRECT_FULL
SWEEP_TREE = True               # RICCATI_TREE: the reduced tree sweep
SWEEP_REDUCED = True            # RICCATI_REDUCED: the chain's reduced Riccati sweep
SWEEP_DIRECT_REDUCED = True     # DIRECT_REDUCED
# on only in the copy with every flag on, which runs every kind of model (DTTMM_SPECIALIZE=0, the
# tests); off in a model's own copy, whose flags say what the model has, not only what it may
# have: a copy for closing joints runs models with closing joints only, and compiles no step
# without them (step.py::solve_step and its sweep, ~10 s cold).  solver.kernel_features never
# gives it.
EVERY_KIND = True

FLAGS = ("HAS_BEAMS", "HAS_RODS", "HAS_ELASTIC_HINGES", "HAS_LOOPS", "HAS_STATION_HISTORIES",
         "HAS_JOINTS", "HAS_EXACT_STIFFENING", "SWEEP_JOINTS", "SWEEP_FULL", "SWEEP_DIRECT_FULL",
         "SWEEP_TREE", "SWEEP_REDUCED", "SWEEP_DIRECT_REDUCED", "EVERY_KIND")
ALL = frozenset(FLAGS)

# the short names in a copy's name (and so in numba's cache files)
_SHORT = dict(HAS_BEAMS="b", HAS_RODS="r", HAS_ELASTIC_HINGES="e", HAS_LOOPS="l",
              HAS_STATION_HISTORIES="s", HAS_JOINTS="j", HAS_EXACT_STIFFENING="x",
              SWEEP_JOINTS="J", SWEEP_FULL="F", SWEEP_DIRECT_FULL="DF", SWEEP_TREE="T",
              SWEEP_REDUCED="R", SWEEP_DIRECT_REDUCED="DR", EVERY_KIND="all")

# The fields of the run's structures (kernels/stepping/loop.py,
# kernels/stepping/step.py::GeneralLoop) that only code under a flag reads: a model's copy of the
# kernels takes them as None where none of their flags is on, so that numba compiles the structures
# it does take and no more (every array a structure carries is a dozen values numba passes, copies
# and reference-counts wherever the structure goes: the general loop's structures carry ~180 arrays,
# and its skeleton compiled in 36 s with all of them and 29 s without the 47 the rigid arm never
# reads).
READ_UNDER = {
    ("loop", "loops"): ("HAS_LOOPS",),            # the closing joints' tables and scratch
    ("loop", "at_guess"): ("HAS_LOOPS",),
    ("inputs", "closure_target"): ("HAS_LOOPS",),
    ("inputs", "g_pos"): ("HAS_LOOPS",),
    ("inputs", "g_vel"): ("HAS_LOOPS",),
    ("rec", "closure_wrench"): ("HAS_LOOPS",),
    ("sweep", "split"): ("SWEEP_FULL",),           # each sweep's own scratch
    #                                                 (kernels/assembly/sweep.py)
    ("sweep", "s"): ("SWEEP_FULL", "SWEEP_JOINTS", "HAS_LOOPS"),   # (the loops' columns:
                                                                    # closure.py)
    ("sweep", "p"): ("SWEEP_FULL", "SWEEP_JOINTS"),
    ("sweep", "tinv"): ("SWEEP_FULL",),
    ("sweep", "t"): ("SWEEP_FULL",),
    ("sweep", "g"): ("SWEEP_FULL", "SWEEP_DIRECT_FULL"),
    ("sweep", "gv"): ("SWEEP_FULL", "SWEEP_DIRECT_FULL"),
    ("sweep", "red_v"): ("SWEEP_TREE", "SWEEP_REDUCED", "SWEEP_DIRECT_REDUCED"),
    ("sweep", "red_phi"): ("SWEEP_TREE", "SWEEP_REDUCED", "SWEEP_DIRECT_REDUCED"),
    ("sweep", "red_aq"): ("SWEEP_TREE", "SWEEP_REDUCED", "SWEEP_DIRECT_REDUCED"),
    ("sweep", "red_s"): ("SWEEP_TREE", "SWEEP_REDUCED"),
    ("sweep", "red_p"): ("SWEEP_TREE", "SWEEP_REDUCED"),
    ("sweep", "red_tinv"): ("SWEEP_TREE", "SWEEP_REDUCED"),
    ("sweep", "red_t"): ("SWEEP_REDUCED",),
    ("sweep", "dir_z"): ("SWEEP_DIRECT_FULL",),
    ("sweep", "dir_o"): ("SWEEP_DIRECT_FULL",),
    ("sweep", "port_s"): ("SWEEP_TREE",),
    ("sweep", "port_p"): ("SWEEP_TREE",),
    ("sweep", "aq_out"): ("SWEEP_TREE",),
    ("sweep", "tree_s"): ("SWEEP_JOINTS", "HAS_LOOPS"),
    ("sweep", "tree_p"): ("SWEEP_JOINTS",),
}


def kept(name, field, features):
    """Whether the copy for `features` takes the field of the structure called `name`
    (READ_UNDER) as it is, not as None."""
    return (features == ALL or not SPECIALIZE
            or bool(set(READ_UNDER.get((name, field), features)) & features))


def unread_dropped(structure, name, features):
    """The named tuple `structure` (called `name` in READ_UNDER) with the fields no code of a
    copy for `features` reads set to None (itself where there are none)."""
    drop = _dropped(name, structure._fields, features, SPECIALIZE)
    return structure._replace(**drop) if drop else structure


@lru_cache(maxsize=256)
def _dropped(name, fields, features, specialize):
    return {field: None for field in fields if not kept(name, field, features)}


_READS = {}         # python function -> whether it reads a flag, itself or through its callees
_COPIES = {}        # (python function, features) -> its copy's dispatcher


def _names(code):
    """The global names a code object (and the code objects nested in it) reads."""
    names = set(code.co_names)
    for const in code.co_consts:
        if isinstance(const, CodeType):
            names |= _names(const)
    return names


def reads_flags(kernel):
    """Whether the njit kernel reads a flag, in its own code or in a kernel it calls."""
    fn = kernel.py_func
    known = _READS.get(fn)
    if known is None:
        _READS[fn] = False          # (a cycle of calls: numba has none, this ends it)
        names = _names(fn.__code__)
        known = bool(names & ALL) or any(
            isinstance(fn.__globals__.get(name), Dispatcher)
            and reads_flags(fn.__globals__[name]) for name in names)
        _READS[fn] = known
    return known


def specialized(kernel, features=ALL):
    """The njit kernel's copy compiled for a model using `features` (flag names that are on;
    the rest are off): the kernel itself where it reads no flag, where every flag is on, or
    where copies are off (SPECIALIZE)."""
    features = frozenset(features)
    unknown = features - ALL
    if unknown:
        raise ValueError(f"specialized: unknown features {sorted(unknown)}; known: {FLAGS}")
    if features == ALL or not SPECIALIZE or not reads_flags(kernel):
        return kernel
    fn = kernel.py_func
    key = (fn, features)
    copy = _COPIES.get(key)
    if copy is None:
        scope = dict(fn.__globals__)
        for name in _names(fn.__code__):
            if name in ALL:
                scope[name] = name in features
            elif isinstance(scope.get(name), Dispatcher):
                scope[name] = specialized(scope[name], features)
        tag = "_".join(_SHORT[f] for f in FLAGS if f in features) or "none"
        copy = recompiled(kernel, code_copy(fn, tag, scope))
        _COPIES[key] = copy
    return copy
