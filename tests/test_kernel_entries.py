"""Kernels only other kernels call are compiled without numba's entry points for Python
(kernels/__init__.py::CalleeKernel), into libraries only their callers link
(kernels/__init__.py::LinkedOnlyLibrary); called from Python, they run their twin."""
import os
import subprocess
import sys

import numpy as np
from numba import njit

from dttmm import kernels
from dttmm.kernels import CalleeKernel
from dttmm.kernels.algebra.so3 import exp_coefficients
from dttmm.kernels.assembly.closure import set_ground
from dttmm.kernels.stepping.step import solve_step


@njit
def _calls_exp_coefficients(th2):
    return exp_coefficients(th2)


def _entry_point(compiled):
    cres = next(iter(compiled.overloads.values()))
    return cres.library.get_pointer_to_function(cres.fndesc.llvm_cpython_wrapper_name)


def test_a_callee_kernel_has_no_python_entry_and_python_calls_run_its_twin():
    expected = (np.sin(0.5) / 0.5, (1.0 - np.cos(0.5)) / 0.25)   # (sin t / t, (1 - cos t) / t^2)
    # another kernel calls it: its own code, no entry point
    assert np.allclose(_calls_exp_coefficients(0.25), expected, rtol=1e-15, atol=0.0)
    assert isinstance(exp_coefficients, CalleeKernel) and _entry_point(exp_coefficients) == 0
    # Python calls it: the twin, with its entry point
    assert np.allclose(exp_coefficients(0.25), expected, rtol=1e-15, atol=0.0)
    twin = kernels.PYTHON_CALLED[exp_coefficients]
    assert not isinstance(twin, CalleeKernel) and _entry_point(twin) != 0
    assert twin.py_func.__qualname__ == "exp_coefficients__python"   # (its own cache files)


def test_no_kernel_has_a_c_entry_point():
    """numba's C entry point (for numba.cfunc and first-class function values) is left out of
    every kernel: an entry kernel and a callee's twin have the CPython one only."""
    from dttmm.kernels.transfers.joint import n_coordinates
    assert n_coordinates(1) >= 0 and exp_coefficients(0.25)[0] > 0.0   # (compiled or loaded)
    for compiled in (n_coordinates, kernels.PYTHON_CALLED[exp_coefficients]):
        assert not isinstance(compiled, CalleeKernel)
        assert compiled.targetoptions["no_cfunc_wrapper"]
        assert not compiled.targetoptions.get("no_cpython_wrapper", False)
        cres = next(iter(compiled.overloads.values()))
        assert cres.library.get_pointer_to_function(cres.fndesc.llvm_cpython_wrapper_name) != 0
        assert cres.library.get_pointer_to_function(cres.fndesc.llvm_cfunc_wrapper_name) == 0


def test_callees_and_entries_are_of_their_kinds():
    assert isinstance(solve_step, CalleeKernel)
    assert not isinstance(set_ground, CalleeKernel)      # (entry=True)


def test_a_callee_called_by_the_package_is_noted_for_the_suite():
    scope = {"__name__": "dttmm.somewhere", "exp_coefficients": exp_coefficients}
    exec("def package_code():\n    return exp_coefficients(0.25)", scope)
    scope["package_code"]()
    assert kernels.CALLED_BY_PACKAGE == {"exp_coefficients"}
    kernels.CALLED_BY_PACKAGE.clear()   # (conftest's check would fail this test)
    exp_coefficients(0.25)              # a test's own call is not the package's
    assert not kernels.CALLED_BY_PACKAGE


def test_a_callee_kernels_library_makes_no_machine_code_of_its_own():
    fn = exp_coefficients.py_func
    callee = kernels._dispatcher(CalleeKernel, kernels.code_copy(fn, "uncached", fn.__globals__),
                                 exp_coefficients.targetoptions, cache=False)   # (compiled here)
    caller = njit(lambda th2: callee(th2))
    assert np.allclose(caller(0.25), exp_coefficients(0.25), rtol=1e-15, atol=0.0)
    cres = next(iter(callee.overloads.values()))
    assert kernels.LINKED_ONLY          # (this numba has what it needs)
    assert isinstance(cres.library, kernels.LinkedOnlyLibrary)
    assert cres.library.codegen._engine.get_function_address(cres.fndesc.mangled_name) == 0
    own = next(iter(caller.overloads.values()))     # the caller's machine code, the callee's in it
    assert own.library.codegen._engine.get_function_address(own.fndesc.mangled_name) != 0


_CACHED = '''
import sys
import numpy as np
from dttmm.kernels import kernel


@kernel
def callee(x):
    return np.sin(x) + 2.0 * x


@kernel(entry=True)
def first(x):
    return callee(x) + 1.0


@kernel(entry=True)
def second(x):
    return 3.0 * callee(x)


if __name__ == "__main__":
    entry = first if sys.argv[1] == "first" else second
    print(repr(entry(0.5)), callee.stats.cache_hits.get(callee.signatures[0], 0)
          if callee.signatures else -1)
'''


def test_a_callee_kernel_caches_and_links_from_its_cache(tmp_path):
    """Its cache holds the code its callers link: a process that compiles a new caller loads the
    callee from it, and a cached caller runs without the callee."""
    (tmp_path / "cached_kernels.py").write_text(_CACHED)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))

    def run(which):
        done = subprocess.run([sys.executable, "cached_kernels.py", which], cwd=tmp_path, env=env,
                              capture_output=True, text=True, check=True)
        value, hits = done.stdout.split()
        return float(value), int(hits)

    x = 0.5
    assert run("first") == (np.sin(x) + 2.0 * x + 1.0, 0)    # compiles both, caches both
    assert run("first") == (np.sin(x) + 2.0 * x + 1.0, -1)   # its cache: the callee not needed
    assert run("second") == (3.0 * (np.sin(x) + 2.0 * x), 1)  # links the callee's cache


def test_the_profilers_symbol_map_names_the_loaded_kernels(tmp_path):
    """benchmarks/jit_profile.py's map (what perf reads to name the JIT's samples): a run's
    compiled loop and its callees at distinct nonzero addresses, their names demangled."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    path = tmp_path / "perf.map"
    subprocess.run([sys.executable, os.path.join(root, "benchmarks", "jit_profile.py"),
                    "three_pendulum", "--map-only", str(path)], check=True, cwd=root,
                   env=dict(os.environ, PYTHONPATH=root))
    sys.path.insert(0, os.path.join(root, "benchmarks"))
    try:
        from jit_profile import demangled
    finally:
        sys.path.pop(0)
    rows = [line.split() for line in path.read_text().splitlines()]
    starts = [int(start, 16) for start, _, _ in rows]
    names = {demangled(name) for _, _, name in rows}
    assert all(starts) and len(set(starts)) == len(starts)
    assert any(n.startswith("dttmm.kernels.stepping.loop.run_steps_") for n in names), names
    assert demangled("_ZN5dttmm7kernels9transfers5joint11joint_frameB2v7B68c8tJTIeE") == (
        "dttmm.kernels.transfers.joint.joint_frame")


def _doubled(x):
    return 2.0 * x


kernels.ALWAYS_INLINED.add(_doubled)          # (as kernel(always_inline=True), compiled here)
_always_inlined = kernels._dispatcher(CalleeKernel, _doubled, exp_coefficients.targetoptions,
                                      cache=False)


@njit
def _calls_doubled(x):
    return _always_inlined(x) + 1.0


def test_an_always_inlined_kernel_leaves_no_call_in_its_caller():
    """kernel(..., always_inline=True) (kernels/__init__.py::ALWAYS_INLINED): its library marks
    its function alwaysinline for LLVM, and its caller's optimized code calls it nowhere."""
    assert _calls_doubled(1.5) == 4.0
    cres = next(iter(_always_inlined.overloads.values()))
    assert isinstance(cres.library, kernels.LinkedOnlyLibrary) and cres.library.always_inline
    own = [f for f in cres.library._get_module_for_linking().functions if not f.is_declaration]
    assert own and all(b"alwaysinline" in list(f.attributes) for f in own)
    caller = next(iter(_calls_doubled.overloads.values()))
    name = cres.fndesc.mangled_name
    body = caller.library.get_function(caller.fndesc.mangled_name)
    assert name not in str(body)                # (no call of it left)
