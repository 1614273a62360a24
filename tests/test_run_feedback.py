"""What a run gives back and tells its user: the last step lands on t_end, the final state is
always recorded, wall_time covers the whole call, a progress bar on long runs, a note while the
kernels compile, and the public names at the top level."""
import time
from importlib.metadata import version

import numpy as np

import dttmm
from dttmm import feedback, simulate
from dttmm.chains import rigid_chain


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


def test_a_note_while_kernels_compile_once(capsys, monkeypatch):
    """A kernel call that has not returned after COMPILE_NOTICE_AFTER seconds is compiling:
    stderr says so once per process; a quick call says nothing."""
    monkeypatch.setattr(feedback, "_noticed", False)
    monkeypatch.setattr(feedback, "COMPILE_NOTICE_AFTER", 0.05)
    with feedback.compile_notice():
        pass
    assert capsys.readouterr().err == ""
    with feedback.compile_notice():
        time.sleep(0.5)
    assert "compiling the numba kernels" in capsys.readouterr().err
    with feedback.compile_notice():
        time.sleep(0.5)
    assert capsys.readouterr().err == ""


def test_the_public_names_are_at_the_top_level():
    assert dttmm.__version__ == version("dttmm")
    for name in ("simulate", "simulate_reference", "Result", "DivergenceError", "System",
                 "build_chain", "Model"):
        assert name in dttmm.__all__ and hasattr(dttmm, name)
