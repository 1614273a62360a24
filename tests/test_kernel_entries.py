"""Kernels only other kernels call are compiled without numba's entry points for Python
(kernels/__init__.py::CalleeKernel); called from Python, they run their twin."""
import numpy as np
from numba import njit

from dttmm import kernels
from dttmm.kernels import CalleeKernel, recompiled
from dttmm.kernels.algebra.so3 import exp_coefficients
from dttmm.kernels.stepping.step import initial_accelerations, solve_step


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


def test_a_kernels_copies_are_of_its_kind():
    assert isinstance(solve_step, CalleeKernel)
    assert isinstance(recompiled(solve_step, solve_step.py_func), CalleeKernel)
    assert not isinstance(initial_accelerations, CalleeKernel)      # (entry=True)
    assert not isinstance(recompiled(initial_accelerations, initial_accelerations.py_func),
                          CalleeKernel)


def test_a_callee_called_by_the_package_is_noted_for_the_suite():
    scope = {"__name__": "dttmm.somewhere", "exp_coefficients": exp_coefficients}
    exec("def package_code():\n    return exp_coefficients(0.25)", scope)
    scope["package_code"]()
    assert kernels.CALLED_BY_PACKAGE == {"exp_coefficients"}
    kernels.CALLED_BY_PACKAGE.clear()   # (conftest's check would fail this test)
    exp_coefficients(0.25)              # a test's own call is not the package's
    assert not kernels.CALLED_BY_PACKAGE
