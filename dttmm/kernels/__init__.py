"""numba kernels on flat arrays, in layers, each using only those above it:

  algebra/     3 x 3 algebra and rotations (mat3.py, so3.py)
  transfers/   each element's transfer matrix over one step (body, beam, hinge, joint, em_body)
  assembly/    one step's sweeps (sweep.py: chains; tree_sweep.py: trees) and the closing joints
               held with them (closure.py, loop_columns.py, loop_projection.py)
  stepping/    the time loops: the step skeleton (loop.py), its variants (step.py, ball_chain.py,
               tree.py, weld_chain.py, em_step.py) and the high-order integrator (runge_kutta.py)

with, here, the decorators every kernel is compiled with.  One compiled copy of each kernel runs
every kind of model: what a model uses is read from its tables at run time, so a user compiles
the core once per install (`dttmm compile`, or the first run), never once per kind of model."""
import gc
import os
import sys
import weakref
from pathlib import Path
from types import FunctionType

import llvmlite.binding as llvm
from numba import config, njit
from numba.core import compiler
from numba.core import event as numba_event
from numba.core.caching import NullCache
from numba.core.codegen import JITCodeLibrary
from numba.core.registry import CPUDispatcher


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


def _lock_cache_saves():
    """numba saves a compiled version into the kernel's cache index and a numbered data file
    (numba/core/caching.py, IndexDataCacheFile.save: read the index, take the first free number,
    write the index, then the data) with no lock.  Two processes saving versions of one kernel
    at once (the core's first use compiles in two, solving/core.py; `dttmm compile` runs its
    families side by side) could take the same number, and one version's entry would then name
    the other's machine code.  Each save holds a lock on its cache folder (where the platform
    has fcntl; a folder it cannot write to saves as numba does)."""
    try:
        import fcntl
    except ImportError:
        return
    from numba.core.caching import IndexDataCacheFile
    save = IndexDataCacheFile.save
    if getattr(save, "locked", False):
        return

    def locked_save(self, key, data):
        try:
            lock = open(os.path.join(self._cache_path, ".dttmm-save.lock"), "a")
        except OSError:
            return save(self, key, data)
        with lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            return save(self, key, data)
    locked_save.locked = True
    IndexDataCacheFile.save = locked_save


_lock_cache_saves()


def compiled_dttmm_function(event):
    """The Python function a "numba:compile" event compiles if it is dttmm's (a kernel, a
    kernel's copy or twin, the reference's), else None (a user's own numba function).  The
    listeners that act on dttmm's compiles only (here; results/feedback.py's notice) ask this."""
    function = getattr(event.data.get("dispatcher"), "py_func", None)
    return function if getattr(function, "__module__", "").startswith("dttmm") else None


class _NoGarbageCollectionWhileCompiling(numba_event.Listener):
    """Python's cyclic garbage collector off while numba compiles a kernel of dttmm's (the
    outermost "numba:compile" event whose function is dttmm's; docs/solver.md, "Compile time",
    item 12), on again after.  numba makes millions of short-lived Python objects as it types
    and lowers (its IR, types, llvmlite's IR), and every 700 allocations the collector walks the
    young ones, and the survivors again later: measured, cold, two processes side by side, 8-14%
    of a compile (the arm 68.0 -> 58.4 s, the four-bar 123.0 -> 112.5 s, the flexible
    slider-crank 180.4 -> 158.6 s).  The garbage it would have freed stays until the end: at
    most GC_CAP objects (the flexible slider-crank's compile peaks at 1.26 GB against 0.59; past
    the cap the collector runs once when a kernel's compile ends), freed when it is back."""

    GC_CAP = 8_000_000          # objects allocated since the last collection

    def __init__(self):
        self.depth = 0
        self.paused = False

    def on_start(self, event):
        self.depth += 1
        if self.depth > 1 or not gc.isenabled():
            return
        if compiled_dttmm_function(event) is not None:
            gc.disable()
            self.paused = True

    def on_end(self, event):
        self.depth -= 1
        if not self.paused:
            return
        if self.depth == 0:
            gc.enable()
            self.paused = False
        elif gc.get_count()[0] > self.GC_CAP:
            gc.collect()


_no_gc_while_compiling = _NoGarbageCollectionWhileCompiling()
numba_event.register("numba:compile", _no_gc_while_compiling)


def _collector_back_in_child():
    """A child forked by another thread during a compile (a process pool) compiles nothing:
    its collector on, as the parent's will be."""
    if _no_gc_while_compiling.paused:
        gc.enable()
    _no_gc_while_compiling.__init__()


os.register_at_fork(after_in_child=_collector_back_in_child)


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


# What numba builds for calls from Python, left out of a kernel only other kernels call: numba
# compiles every function with a CPython entry point (unboxing each argument: every array of the
# run's structures) and a C entry point beside its code, optimizes both and makes machine code
# of them in its own library, though a kernel's callers link only its code.  Measured on the
# four-bar's cold compile (every callee compiled without them, one process each, quiet):
# 83.5 s against 107.5 s.  The C entry point (a C function of the kernel's own arguments, for
# numba.cfunc and numba's first-class function values) is left out of every kernel, entries and
# twins too: Python calls the CPython one, kernels call the code itself (the compiled drives'
# C callbacks are the user's functions', elements/drives.py).  Measured on the four-bar's cold
# compile, two processes side by side twice: 108 -> 103 s and 98 -> 94 s (the skeleton's C entry
# alone was ~2,000 lines of LLVM IR beside its ~10,000: every array of its structures passed
# as separate scalars); docs/solver.md, "Compile time", item 14.
_NO_C_ENTRY = dict(no_cfunc_wrapper=True)
_NO_PYTHON_ENTRY = dict(no_cpython_wrapper=True, **_NO_C_ENTRY)


class LinkedOnlyLibrary(JITCodeLibrary):
    """The code library of a kernel only other kernels call: its code only ever runs linked into
    theirs.  numba finalizes every library alike (numba/core/codegen.py, CPUCodeLibrary.finalize):
    it links in the libraries of the kernels it calls, optimizes the linked whole (LLVM's module
    passes) and makes machine code of it, and every library that links this one optimizes and
    makes machine code of it again, with its own callers' code.  A linked-only library does
    neither for itself: its functions, each optimized on its own when lowered (LLVM's function
    passes, as before), are linked as they are into its callers' libraries, which optimize the
    linked whole as they always did; its machine code is that of its environment's global
    variable alone (numba sets it when the compile ends, and its cache holds that machine code
    and the code for linking, as any library's).  Measured on the four-bar's cold compile (two
    processes side by side, their results bit-identical): 203 -> 168 s.  It overrides two
    methods of numba's CPUCodeLibrary and calls its helpers (numba 0.58 to 0.68); where a numba
    lacks them, callee kernels lower as any other (LINKED_ONLY), and tests/test_kernel_entries.py
    checks both the library and its cache."""

    always_inline = False       # (ALWAYS_INLINED: its function inlined into every caller)

    def add_ir_module(self, ir_module):
        if self.always_inline:
            for function in ir_module.functions:
                if not function.is_declaration and "noinline" not in function.attributes:
                    function.attributes.add("alwaysinline")
        super().add_ir_module(ir_module)

    def _optimize_final_module(self):
        pass

    def _finalize_final_module(self):
        self._finalize_dynamic_globals()
        self._verify_declare_only_symbols()
        environment = "\n".join(str(gv) for gv in self._final_module.global_variables
                                if gv.name.startswith("_ZN08NumbaEnv"))
        module = llvm.parse_assembly(environment)
        module.triple = self._final_module.triple
        module.data_layout = str(self._final_module.data_layout)
        module._CPUCodeLibrary__library = weakref.proxy(self)   # (numba's object-cache hooks)
        self._codegen._add_module(module)
        self._codegen._engine.finalize_object()
        self._finalized = True


LINKED_ONLY = all(hasattr(JITCodeLibrary, name) for name in (
    "_optimize_final_module", "_finalize_final_module", "_finalize_dynamic_globals",
    "_verify_declare_only_symbols", "enable_object_caching"))


# The callee kernels whose code LLVM inlines into every caller (kernel(..., always_inline=True)):
# small kernels that take the run's structures whole, called a few times a step.  numba passes
# a structure to a function as every scalar of every array it carries (the general loop's
# scratch: dozens of arrays, each 5-9 values), so a call that LLVM leaves a call costs that; since
# the flat model's accessors made their bodies larger, LLVM's own threshold left the loop
# projection's residuals, rows and dependent frames as calls (docs/solver.md, "Compile time",
# item 16).
ALWAYS_INLINED = set()


class LinkedOnlyCompiler(compiler.Compiler):
    """numba's compiler, lowering into a LinkedOnlyLibrary."""

    def compile_extra(self, func):
        if self.state.library is None:
            library = LinkedOnlyLibrary(self.state.targetctx.codegen(), func.__qualname__)
            library.always_inline = func in ALWAYS_INLINED
            library.enable_object_caching()
            self.state.library = library
        return super().compile_extra(func)


class CalleeKernel(CPUDispatcher):
    """A kernel numba compiles without entry points for Python (kernel(), no_alloc_kernel(),
    allocating_kernel() without entry=True) into a LinkedOnlyLibrary: other kernels call it as
    any other.  Called from Python it runs its twin (python_twin: the same code compiled, once,
    with them) instead of jumping into code that is not there.  The package's own Python code
    calls only kernels declared with entry=True: a call from it is noted in CALLED_BY_PACKAGE,
    which the test suite checks after every test (tests/conftest.py)."""

    def __init__(self, py_func, locals=None, targetoptions=None,
                 pipeline_class=LinkedOnlyCompiler if LINKED_ONLY else compiler.Compiler):
        super().__init__(py_func, locals, targetoptions, pipeline_class)

    def __call__(self, *args, **kwargs):
        if sys._getframe(1).f_globals.get("__name__", "").startswith("dttmm."):
            CALLED_BY_PACKAGE.add(self.py_func.__qualname__)
        return python_twin(self)(*args, **kwargs)


PYTHON_CALLED = {}          # a callee kernel -> its twin, where Python called it
CALLED_BY_PACKAGE = set()   # the callee kernels the package's Python code called (by name)


def python_twin(kernel):
    """The callee kernel's code compiled (and cached) under its own name with the entry points
    numba builds for calls from Python (with numba's JIT off: the function itself)."""
    if config.DISABLE_JIT:
        return kernel
    twin = PYTHON_CALLED.get(kernel)
    if twin is None:
        clone = code_copy(kernel.py_func, "python", kernel.py_func.__globals__)
        options = {k: v for k, v in kernel.targetoptions.items() if k != "no_cpython_wrapper"}
        twin = PYTHON_CALLED[kernel] = _dispatcher(CPUDispatcher, clone, options,
                                                   cache=not isinstance(kernel._cache, NullCache))
    return twin


def code_copy(fn, suffix, scope):
    """fn's code as a function of its own named <name>__<suffix> (numba names its cache files
    after the qualified name), its globals read from scope: a kernel's twin (python_twin) or a
    loop variant's skeleton."""
    clone = FunctionType(fn.__code__, scope, f"{fn.__name__}__{suffix}", fn.__defaults__,
                         fn.__closure__)
    clone.__qualname__ = f"{fn.__qualname__}__{suffix}"
    clone.__doc__, clone.__module__ = fn.__doc__, fn.__module__
    return clone


def _dispatcher(kind, fn, options, cache=True):
    """What njit(cache=cache, **options) makes of fn, as a `kind` (CPUDispatcher or
    CalleeKernel)."""
    if config.DISABLE_JIT:
        return fn
    compiled = kind(py_func=fn, locals={}, targetoptions=dict(options, nopython=True))
    if cache:
        compiled.enable_caching()
    return compiled


def _compiled(fn, entry, always_inline=False, **options):
    """fn compiled with `options` and CONTRACT, a CalleeKernel unless entry (the decorators
    below, with or without their arguments); always_inline: its code inlined by LLVM into every
    caller (ALWAYS_INLINED)."""
    if fn is None:
        return lambda f: _compiled(f, entry, always_inline, **options)
    if always_inline:
        ALWAYS_INLINED.add(fn)
    kind, no_entry = (CPUDispatcher, _NO_C_ENTRY) if entry else (CalleeKernel, _NO_PYTHON_ENTRY)
    return _dispatcher(kind, fn, dict(options, fastmath=CONTRACT, **no_entry))


def kernel(fn=None, *, entry=False, always_inline=False):
    """njit(cache=True, fastmath=CONTRACT): a kernel called by other kernels only (a
    CalleeKernel) or, with entry=True, from Python too (by the package's Python code or its
    tests: a test's call of a callee would compile its twin, seconds for the larger kernels);
    always_inline: see ALWAYS_INLINED."""
    return _compiled(fn, entry, always_inline)


def no_alloc_kernel(fn=None, *, entry=False, always_inline=False):
    """kernel() without numba's reference counting (its `_nrt=False` option), for the
    step's kernels that allocate nothing.  Every array argument and every view then costs no
    pair of atomic reference-count calls; numba leaves most of those in functions with loops
    and branches (the compiled beam map had ~400 such call sites).  Measured on the beam's
    reduced map (kernels/transfers/beam.py::beam_ball_map): 1.64 against 1.96 us per call; on the
    fused ball-chain loop (kernels/stepping/ball_chain.py::_ball_chain_steps, its scratch allocated
    by its caller): 0.88x the time per step.  A kernel that allocates fails to compile (numba
    compiles its callees the same way), so the option cannot hide a mistake.  always_inline:
    see ALWAYS_INLINED."""
    return _compiled(fn, entry, always_inline, _nrt=False)


def allocating_kernel(fn=None, *, entry=False):
    """kernel() with numba's reference counting on, said explicitly (its `_nrt=True`),
    for the kernels the general and energy-momentum loops' pieces call that allocate, or call
    kernels that do (in step.py, every kernel the pieces call but the copy helpers (mat3.put*),
    `_all_finite`, `_integrator_coefficients`: a few of them, `_hinge_deflection` and
    `_locked_frame` among them, allocate nothing and would compile either way): every skeleton
    is compiled without reference counting
    (kernels/stepping/loop.py::_skeleton), and numba compiles a kernel called from another with
    its caller's setting unless the kernel sets its own (so would not compile these).  An array
    such a kernel allocates lives and dies in it: it returns status codes and numbers, never a
    new array (nothing would free one)."""
    return _compiled(fn, entry, _nrt=True)


# Small kernels called once per body and step (the predictor and history updates, the
# exponential and left Jacobian, the 3 x 3 products and inverse, the reduced Riccati step and
# recovery, the rigid body's reduced map) are declared njit(cache=True, inline='always'):
# numba inlines them into each caller before compiling it.  Measured in one process, 21
# interleaved pairs: the predictor, history, so3, Riccati step and recovery kernels 0.78x the
# time per step on the rigid 3-link chain and 0.90x on the three-pendulum (twice); the rigid map
# and the 3 x 3 product and inverse a further 0.87x and 0.95x (once).  A cold numba cache takes
# ~25 s longer to fill (114 against 87 s).
