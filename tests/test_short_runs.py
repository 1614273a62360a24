"""Short runs do not redo their setup (issue 30): what a run derives from its frozen model alone
(the kernels' model and tables, the loops' closure at t = 0, the supported-ness checks) is
computed once per model and kept on it (model.model_fact); the kernels read those tables and
never write them, so a second run of the same model gives the first one's numbers bit for bit."""
import pickle

import numpy as np
import pytest

from dttmm import simulate, solver
from dttmm.chains import arm, rigid_chain, three_pendulum
from dttmm.mechanisms import n_four_bar
from dttmm.recording import leaves


MODELS = {
    "rigid chain (fused loop)": lambda: rigid_chain(3),
    "three-pendulum (fused, beams)": lambda: three_pendulum(),
    "flexible arm, PD drive (general loop)": lambda: arm(drive="pd", flexible=True),
    "four-bar (closed loop)": lambda: n_four_bar(2),
}


def _tables(model):
    km = solver.kernel_model(model)[0]
    return leaves((solver.kernel_params(km), solver.beam_tables(km),
                   solver.loop_tables(km)))


@pytest.mark.parametrize("name", list(MODELS))
def test_the_tables_kept_on_a_model_are_never_written_and_a_rerun_is_bitwise(name):
    """After two runs, every table the kernels read from a model (its own arrays, and those
    kept on it) equals the tables of the same system built again (the kernels did not write
    them), and the second run's samples equal the first's bit for bit."""
    model = MODELS[name]()
    first = simulate(model, 0.02, 1e-3)
    second = simulate(model, 0.02, 1e-3)
    for key in ("rotation", "angular_velocity", "force", "moment", "position_output"):
        np.testing.assert_array_equal(getattr(first, key), getattr(second, key), err_msg=key)
    kept, fresh = _tables(model), _tables(MODELS[name]())
    assert len(kept) == len(fresh)
    for a, b in zip(kept, fresh):
        assert not np.shares_memory(a, b)
        np.testing.assert_array_equal(a, b)


def test_a_second_run_does_not_rebuild_the_kernels_model(monkeypatch):
    """The kernels' model is built on the first run of a model only; a new model (or a copy of
    it through pickle, which carries its fields, not its kept facts) builds its own."""
    calls = []
    original = solver._kernel_model
    monkeypatch.setattr(solver, "_kernel_model", lambda m: calls.append(m) or original(m))
    model = arm(drive="pd")
    simulate(model, 0.002, 1e-3)
    assert len(calls) == 1
    simulate(model, 0.002, 1e-3)
    simulate(model, 0.004, 1e-3, full_state=True)
    assert len(calls) == 1
    copy = pickle.loads(pickle.dumps(model))
    assert "_facts" not in copy.__dict__
    simulate(copy, 0.002, 1e-3)
    assert len(calls) == 2


def test_a_checkpoint_holds_the_finished_runs_arrays_read_only():
    """No copy of the state at the end of a run (a million bodies' would double its memory):
    the checkpoint holds the run's own arrays, which nothing writes again."""
    result = simulate(rigid_chain(3), 0.01, 1e-3)
    arrays = result.checkpoint.arrays
    assert arrays and not any(a.flags.writeable for a in arrays)
    resumed = simulate(rigid_chain(3), 0.02, 1e-3, resume=result.checkpoint)
    assert resumed.n_steps == 20
