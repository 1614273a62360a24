"""What a run gives back and tells its user: the last step lands on t_end, the final state is
always recorded, wall_time covers the whole call, a progress bar on long runs, a note while the
kernels compile, and the public names at the top level."""
import threading
import time
from importlib.metadata import version

import numba
import numpy as np

import dttmm
from dttmm import simulate
from dttmm.results import feedback
from dttmm.model.chains import rigid_chain


def test_the_last_step_lands_on_t_end():
    """t_end = 0.05 at dt = 0.03 takes two equal steps of 0.025 s (not two of 0.03 s, ending at
    0.06); a dt that divides t_end is kept as given."""
    model = rigid_chain(3)
    res = simulate(model, 0.05, 0.03)
    assert res.n_steps == 2 and res.info["dt"] == 0.025
    np.testing.assert_allclose(res.t, [0.0, 0.025, 0.05], rtol=0, atol=1e-15)
    kept = simulate(model, 0.3, 0.1)
    assert kept.info["dt"] == 0.1 and kept.n_steps == 3


def test_the_final_state_is_always_recorded():
    """record_every = 10 over 25 steps records t = 0, steps 10 and 20, and the final state at
    step 25, the same state as a run that records every step."""
    model = rigid_chain(3)
    sparse = simulate(model, 0.025, 1e-3, record_every=10)
    every = simulate(model, 0.025, 1e-3)
    np.testing.assert_allclose(sparse.t, [0.0, 0.01, 0.02, 0.025], rtol=0, atol=1e-15)
    assert np.array_equal(sparse.position_output[-1], every.position_output[-1])
    assert np.array_equal(sparse.rotation[-1], every.rotation[-1])


def test_wall_time_covers_the_whole_call():
    model = rigid_chain(10)
    simulate(model, 0.01, 1e-3)                      # compiled and cached
    start = time.perf_counter()
    res = simulate(model, 0.5, 1e-4)
    outside = time.perf_counter() - start
    assert 0.9 * outside < res.wall_time <= outside


def test_a_progress_bar_on_long_runs_only(capsys, monkeypatch):
    model = rigid_chain(3)
    simulate(model, 0.01, 1e-3)
    monkeypatch.setattr(feedback, "PROGRESS_AFTER", 0.0)     # every run counts as long
    simulate(model, 0.5, 1e-4, progress=True)
    assert "step" in capsys.readouterr().err
    simulate(model, 0.5, 1e-4, progress=False)
    simulate(model, 0.5, 1e-4)                      # default: stderr is not a terminal here
    assert capsys.readouterr().err == ""
    monkeypatch.setattr(feedback, "PROGRESS_AFTER", 3600.0)
    simulate(model, 0.5, 1e-4, progress=True)      # expected to be quick: no bar
    assert capsys.readouterr().err == ""


def _fresh_kernel(module):
    """A numba function never compiled before, as if defined in `module`."""
    def kernel(x):
        total = 0.0
        for i in range(x.shape[0]):
            total += np.sin(x[i]) * np.cos(x[i]) + np.sqrt(abs(x[i]))
        return total
    kernel.__module__ = module
    kernel.__name__ = kernel.__qualname__ = "fresh_kernel"
    return numba.njit(cache=False)(kernel)


def test_a_line_while_kernels_compile_says_what_and_how_long(capsys, monkeypatch):
    """A compilation of dttmm's kernels that runs past COMPILE_NOTICE_AFTER seconds is said on
    stderr with its function and the seconds so far, and when it ends; a compiled call, and a
    compilation of a user's own numba function, say nothing (issue 30: no thread per call)."""
    monkeypatch.setattr(feedback, "COMPILE_NOTICE_AFTER", 0.0)
    threads = threading.active_count()
    kernel = _fresh_kernel("dttmm.kernels.fresh")
    kernel(np.ones(3))
    err = capsys.readouterr().err
    assert "compiling the numba kernels (fresh_kernel)" in err and "s so far" in err
    assert "compiled fresh_kernel in" in err
    _fresh_kernel("dttmm.kernels.fresh")(np.ones(3))    # a second: one line, not the whole why
    again = capsys.readouterr().err
    assert "compiling the numba kernels (fresh_kernel) too" in again
    assert "once per install" not in again and "compiled fresh_kernel in" in again
    kernel(np.ones(4))                                  # compiled: nothing
    _fresh_kernel("users_module")(np.ones(3))          # not ours: nothing
    assert capsys.readouterr().err == ""
    assert threading.active_count() <= threads + 1     # one watcher per process at most
    model = rigid_chain(2)
    simulate(model, 0.01, 1e-3)
    before = threading.active_count()
    simulate(model, 0.01, 1e-3)
    assert threading.active_count() == before


def test_the_garbage_collector_is_off_while_dttmm_compiles_and_back_after():
    """docs/solver.md, "Compile time", item 12: Python's cyclic garbage collector is off during
    the compile of a kernel of dttmm's, on again after it; a user's own numba function compiles
    with the collector as the user left it, and a collector the user turned off stays off."""
    import gc

    from numba.core import event as numba_event
    seen = []

    class Probe(numba_event.Listener):
        def on_start(self, event):
            seen.append(gc.isenabled())

        def on_end(self, event):
            pass
    probe = Probe()
    numba_event.register("numba:compile", probe)
    try:
        assert gc.isenabled()
        _fresh_kernel("dttmm.kernels.fresh")(np.ones(3))
        assert seen and not any(seen) and gc.isenabled()
        seen.clear()
        _fresh_kernel("users_module")(np.ones(3))
        assert seen and all(seen) and gc.isenabled()
        gc.disable()
        _fresh_kernel("dttmm.kernels.fresh")(np.ones(3))
        assert not gc.isenabled()
    finally:
        gc.enable()
        numba_event.unregister("numba:compile", probe)


def test_the_public_names_are_at_the_top_level():
    assert dttmm.__version__ == version("dttmm")
    for name in ("simulate", "simulate_reference", "Result", "DivergenceError", "System",
                 "build_chain", "Model"):
        assert name in dttmm.__all__ and hasattr(dttmm, name)


def test_import_dttmm_and_its_help_leave_the_heavy_libraries_unloaded():
    """Issue 30, item 6: `import dttmm` and `dttmm --help` import what they need only: not
    scipy's linear algebra or integrators (a beam's modes and the reference import them when
    used), matplotlib, dask or tqdm (measured: --help 0.72 s warm, 1.07 with scipy's)."""
    import subprocess
    import sys
    probe = ("import sys, runpy; sys.argv = ['dttmm', '--help']\n"
             "try:\n    runpy.run_module('dttmm', run_name='__main__')\n"
             "except SystemExit:\n    pass\n"
             "heavy = ('scipy.linalg', 'scipy.integrate', 'matplotlib', 'dask', 'tqdm')\n"
             "print(sorted(m for m in sys.modules if m.startswith(heavy)))\n")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip().splitlines()[-1] == "[]", out
