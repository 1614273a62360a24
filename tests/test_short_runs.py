"""Short runs do not redo their setup (issue 30): what a run derives from its frozen model alone
(the kernels' model and tables, the loops' closure at t = 0, the supported-ness checks) is
computed once per model and kept on it (model.model_fact); the kernels read those tables and
never write them, so a second run of the same model gives the first one's numbers bit for bit."""
import pickle

import numpy as np
import pytest

from dttmm import BallJoint, build_chain, simulate
from dttmm.model.chains import arm, rigid_chain, three_pendulum, unit_link
from dttmm.model.mechanisms import n_four_bar
from dttmm.results.recording import leaves
from dttmm.results.result import FIELDS
from dttmm.solving import run_checks, run_tables


MODELS = {
    "rigid chain (fused loop)": lambda: rigid_chain(3),
    "three-pendulum (fused, beams)": lambda: three_pendulum(),
    "flexible arm, PD drive (general loop)": lambda: arm(drive="pd", flexible=True),
    "four-bar (closed loop)": lambda: n_four_bar(2),
}


def _tables(model):
    km = run_tables.kernel_model(model)[0]
    return leaves((run_tables.kernel_params(km), run_tables.beam_tables(km),
                   run_tables.loop_tables(km)))


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
    original = run_tables._kernel_model
    monkeypatch.setattr(run_tables, "_kernel_model", lambda m: calls.append(m) or original(m))
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
    """A checkpoint's arrays are read-only and resume the run: a run of its own (a large
    model's) hands them over without a copy (a million bodies' would double its memory); a
    run kept on its model (solving/run_plan.py) copies them, since the next run reuses its
    arrays."""
    result = simulate(rigid_chain(3), 0.01, 1e-3)
    arrays = result.checkpoint.arrays
    assert arrays and not any(a.flags.writeable for a in arrays)
    resumed = simulate(rigid_chain(3), 0.02, 1e-3, resume=result.checkpoint)
    assert resumed.n_steps == 20


KEPT = {
    "rigid chain (fused loop)": lambda: rigid_chain(3),
    "three-pendulum (fused, beams)": lambda: three_pendulum(),
    "arm, compiled PD force (general loop)": lambda: arm(drive="pd-njit", flexible=True),
    "four-bar (closed loop, energy held)": lambda: n_four_bar(2),
}


def _run_arrays(result):
    return [getattr(result, key) for key in ("t", "rotation", "angular_velocity", "force",
                                             "moment", "position_output")]


@pytest.mark.parametrize("name", list(KEPT))
def test_a_prepared_run_kept_on_the_model_gives_a_fresh_models_numbers(name):
    """A model whose start calls no function of the user's keeps its prepared run (the kernels'
    arrays after the consistent start: solving/run_plan.py) and starts the next run from it: runs
    with other steps and options and a resumed run in between, a run equals the same run of
    the same system built again bit for bit, and a finished run's checkpoint is not changed
    by the runs after it (they reuse the kept arrays, not the checkpoint's)."""
    model = KEPT[name]()
    first = simulate(model, 0.02, 1e-3)
    kept = model.__dict__["_prepared_runs"]
    assert len(kept) == 1
    ending = [a.copy() for a in first.checkpoint.arrays]
    simulate(model, 0.01, 5e-4, record_every=3)
    simulate(model, 0.04, 1e-3, resume=first.checkpoint)
    again = simulate(model, 0.02, 1e-3)
    fresh = simulate(KEPT[name](), 0.02, 1e-3)
    assert len(kept) == 2                   # (dt = 1e-3 and 5e-4)
    for a, b, c in zip(_run_arrays(first), _run_arrays(again), _run_arrays(fresh)):
        np.testing.assert_array_equal(a, c)
        np.testing.assert_array_equal(b, c)
    for a, b in zip(ending, first.checkpoint.arrays):
        np.testing.assert_array_equal(a, b)
    for a, b in zip(fresh.checkpoint.arrays, again.checkpoint.arrays):
        np.testing.assert_array_equal(a, b)


def test_a_start_that_calls_the_users_functions_is_taken_again_each_run():
    """A load is a function of the user's, which may read what the user changes between runs
    (here a gain in a list): such a model's start is computed by every run, never kept, so a
    run after the change equals a new model's run with the new gain."""
    gain = [1.0]

    def model():
        return build_chain([BallJoint(), unit_link(force=lambda t: [0.0, 0.0, gain[0]]),
                            BallJoint(), unit_link()])
    changed = model()
    before = simulate(changed, 0.01, 1e-3)
    gain[0] = 30.0
    after = simulate(changed, 0.01, 1e-3)
    fresh = simulate(model(), 0.01, 1e-3)
    assert "_prepared_runs" not in changed.__dict__ or not changed.__dict__["_prepared_runs"]
    assert np.abs(after.position_output - before.position_output).max() > 1e-5
    for a, b in zip(_run_arrays(after), _run_arrays(fresh)):
        np.testing.assert_array_equal(a, b)


def test_a_repeated_calls_options_are_kept_and_bad_ones_still_refused():
    """A call with the arguments of an earlier one (same values and types) takes its checked
    options (run_options); True and 1 are not the same argument, so a refused value is refused
    after an accepted one that compares equal; arrays (t_eval) are checked every time."""
    from dttmm.solving.run_options import run_options
    model = rigid_chain(2)
    args = dict(rtol=None, atol=0.0, method="riccati", scheme="newmark", rho_inf=1.0,
                newton_iterations=None, newton_tol=1e-12, record_every=None, record_dt=None,
                t_eval=None, full_state=True, richardson=False, progress=None,
                max_step_error=0.05, max_energy_error=None, hold_energy=None, resume=None,
                stream=None)
    first = run_options(model, 0.01, 1e-3, **args)
    assert run_options(model, 0.01, 1e-3, **args) is first
    assert run_options(model, 0.01, 2e-3, **args) is not first
    with pytest.raises(ValueError, match="full_state must be True or False"):
        simulate(model, 0.01, 1e-3, full_state=1)
    simulate(model, 0.01, 1e-3, t_eval=[0.005])
    with pytest.raises(ValueError, match="t_eval"):
        simulate(model, 0.01, 1e-3, t_eval=[0.0055])


@pytest.mark.parametrize("name", list(MODELS))
def test_every_array_of_a_runs_result_is_read_only(name):
    """A solver's Result makes its arrays read-only in place (Result._of_run): every array field,
    stored or derived, refuses a write."""
    res = simulate(MODELS[name](), 0.004, 1e-3)
    arrays = {field: getattr(res, field) for field in FIELDS
              if isinstance(getattr(res, field), np.ndarray)}
    assert {"t", "rotation", "force", "moment", "position_output", "kinetic"} <= set(arrays)
    for field, value in arrays.items():
        with pytest.raises(ValueError, match="read-only"):
            value[...] = 0.0


def test_direct_calls_go_to_the_code_numba_chose_and_only_for_the_same_types(monkeypatch):
    """kernels/stepping/loop.py::DirectCalls: the second of two calls with arguments of the same
    types finds numba's entry point (after which the calls go there, with the right answers); a call
    whose varying parts change type (an int where a float was, a 2-d array where a 1-d one
    was) goes through numba's dispatcher, which compiles a version for it."""
    from collections import namedtuple

    from numba import njit

    from dttmm.kernels.stepping import loop as kloop
    found = []
    original = kloop._entry_point
    monkeypatch.setattr(kloop, "_entry_point",
                        lambda c, a: found.append(original(c, a)) or found[-1])
    fake_run = namedtuple("FakeRun", "settings inputs rec")

    @njit
    def skeleton(loop, run, out):
        out[0] = loop[0] + run.settings[0] + run.inputs[0].sum() + run.rec[0]

    calls = kloop.DirectCalls()
    out = np.zeros(1)
    for i, (h, inputs) in enumerate([(1.0, np.ones(2)), (2.0, np.ones(3)), (3.0, np.ones(4)),
                                     (4, np.ones(4)), (5.0, np.ones((2, 2)))]):
        calls(skeleton, ((10.0,), fake_run((h,), (inputs,), (0.5,)), out))
        assert out[0] == 10.0 + h + inputs.sum() + 0.5
    # the entry point was looked up at the second call (the same types as the first), used at
    # the third, and dropped at the fourth and fifth (new types: the dispatcher again)
    assert len(found) == 1 and found[0] is not None
    assert len(skeleton.overloads) == 3
    # where no entry point is found (numba's compilation off, or a converted type), the calls
    # go through the dispatcher and the lookup is not repeated
    monkeypatch.setattr(kloop, "_entry_point", lambda c, a: found.append(None))
    calls = kloop.DirectCalls()
    for _ in range(4):
        calls(skeleton, ((10.0,), fake_run((1.0,), (np.ones(2),), (0.5,)), out))
        assert out[0] == 13.5
    assert found[1:] == [None]


def test_a_kept_run_holds_a_bounded_number_of_chunk_arrays_and_reuses_them_bitwise():
    """A kept prepared run keeps its chunks' arrays and settings by shape and step (a short
    run's fixed cost), but no more than run_plan.KEEP_CHUNK_ARRAYS of them however many run
    lengths a study asks for; a run after the bound was passed equals a fresh model's."""
    from dttmm.solving import run_plan
    model = rigid_chain(3)
    for n in range(1, 3 * run_plan.KEEP_CHUNK_ARRAYS):
        simulate(model, n * 1e-4, 1e-4)
    plan = next(iter(model.__dict__["_prepared_runs"].values()))
    assert 0 < len(plan._chunk_arrays) <= run_plan.KEEP_CHUNK_ARRAYS
    for a, b in zip(_run_arrays(simulate(model, 0.0137, 1e-4)),
                    _run_arrays(simulate(rigid_chain(3), 0.0137, 1e-4))):
        np.testing.assert_array_equal(a, b)


def test_the_fastest_rate_is_the_same_on_lists_and_on_arrays():
    """run_checks._fastest_rate's two paths (a few values in Python, many in numpy) pick the same
    largest |w| and body."""
    rng = np.random.default_rng(3)
    for shape in ((1, 3, 3), (2, 5, 3), (4, 8, 3), (40, 7, 3)):
        omega = rng.normal(size=shape)
        squares = (omega ** 2).sum(axis=-1)
        at = np.unravel_index(squares.argmax(), squares.shape)
        rate, body = run_checks._fastest_rate(omega)
        assert body == at[1]
        assert rate == pytest.approx(np.sqrt(squares[at]), rel=1e-15)


def test_a_kept_run_in_use_is_not_shared_and_is_released_after_its_run():
    """While a kept prepared run is in use (its lock held: another thread's run, here a run
    entered by hand), a run of the same model and options builds one of its own and gives the
    same numbers; the kept run is released when its run ends, even one that raised."""
    from dttmm.solving import run_plan
    from dttmm.solving.run_options import run_options
    model = rigid_chain(3)
    first = simulate(model, 0.01, 1e-3)
    opts = run_options(model, 0.01, 1e-3, rtol=None, atol=0.0, method="riccati",
                       scheme="newmark", rho_inf=1.0, newton_iterations=None, newton_tol=1e-12,
                       record_every=None, record_dt=None, t_eval=None, full_state=False,
                       richardson=False, progress=None, max_step_error=0.05,
                       max_energy_error=None, hold_energy=None, resume=None, stream=None)
    kept = next(iter(model.__dict__["_prepared_runs"].values()))
    with run_plan.prepared_run(opts) as plan:
        assert plan is kept and kept.lock.locked()
        during = simulate(model, 0.01, 1e-3)
    assert not kept.lock.locked()
    with pytest.raises(RuntimeError):
        with run_plan.prepared_run(opts):
            raise RuntimeError("a run that fails")
    assert not kept.lock.locked()
    for a, b in zip(_run_arrays(first), _run_arrays(during)):
        np.testing.assert_array_equal(a, b)


def test_the_layers_cross_product_is_numpys():
    """vectors.cross (the Result's derivations; index tables for a few vectors, one array for
    many) equals np.cross for every broadcast the derivations use, few vectors and many."""
    from dttmm.vectors import cross
    rng = np.random.default_rng(7)
    for sa, sb in (((3,), (3,)), ((5, 3), (3,)), ((4, 7, 3), (4, 7, 3)),
                   ((300, 9, 3), (300, 1, 3)), ((2, 3), (4, 1, 3)), ((3,), (1000, 3))):
        a, b = rng.normal(size=sa), rng.normal(size=sb)
        np.testing.assert_allclose(cross(a, b), np.cross(a, b), rtol=0, atol=1e-14)


def test_rows_dot_is_matmul_with_each_row_independent_of_the_others():
    """vectors.rows_dot (a beam's energies per recorded sample) equals x @ y, and each row of
    its result is bit for bit the same row of any longer x (a run and its resumed halves)."""
    from dttmm.vectors import rows_dot
    rng = np.random.default_rng(3)
    for sx, sy in (((201, 64), (64,)), ((201, 4), (4, 64)), ((201, 64, 3), (3,)), ((5,), (5, 7)),
                   ((201, 0), (0, 64))):
        x, y = rng.normal(size=sx), rng.normal(size=sy)
        np.testing.assert_allclose(rows_dot(x, y), x @ y, rtol=1e-13, atol=1e-13)
        if len(sx) > 1:
            for n in (1, 3, 101, 200):
                assert np.array_equal(rows_dot(x[:n], y), rows_dot(x, y)[:n])


def _assert_same_field(name, a, b):
    """Two Results' field: arrays equal bit for bit, of the same dtype, shape and read-only-ness;
    a checkpoint's step, run, counters and arrays; anything else equal."""
    if isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray), name
        assert (a.dtype, a.shape, a.flags.writeable) == (b.dtype, b.shape, b.flags.writeable), name
        np.testing.assert_array_equal(a, b, err_msg=name)
    elif name == "checkpoint":
        assert (a.step, a.h, a.run, a.counters) == (b.step, b.h, b.run, b.counters)
        assert len(a.arrays) == len(b.arrays)
        for x, y in zip(a.arrays, b.arrays):
            _assert_same_field(name, x, y)
    else:
        assert a == b, name


STORED = ("t", "rotation", "angular_velocity", "angular_acceleration", "force", "moment",
          "modal_coordinates", "modal_velocities", "joint_coordinates", "joint_rates",
          "drive_force", "closure_force", "closure_moment", "closure_drive_force")


@pytest.mark.parametrize("name", list(KEPT))
def test_a_short_runs_fast_path_gives_the_general_paths_result_field_by_field(name, monkeypatch):
    """A short run on a warm kept prepared run (its checked options, loop variant, record
    layout, chunk arrays and the compiled loop's entry point all reused: issue 66's fixed cost)
    gives the Result a run on a prepared run of its own gives (built for that run: KEEP_BYTES
    = 0), every field: its values bit for bit, dtype, shape and read-only-ness, the info, the
    checkpoint (and a run resumed from it); and its samples are a longer run's first ones."""
    from dttmm.solving import run_plan
    model = KEPT[name]()
    for steps, record_every in ((1, None), (3, 2), (1, None), (3, 2)):
        simulate(model, steps * 1e-3, 1e-3, record_every=record_every)     # (warm)
    fast = [simulate(model, steps * 1e-3, 1e-3, record_every=record_every)
            for steps, record_every in ((1, None), (3, 2))]
    fast_resumed = simulate(model, 5e-3, 1e-3, resume=fast[1].checkpoint)
    longer = simulate(model, 5e-3, 1e-3)
    assert len(model.__dict__["_prepared_runs"]) == 1
    monkeypatch.setattr(run_plan, "KEEP_BYTES", 0)
    own = KEPT[name]()
    general = [simulate(own, steps * 1e-3, 1e-3, record_every=record_every)
               for steps, record_every in ((1, None), (3, 2))]
    general_resumed = simulate(own, 5e-3, 1e-3, resume=general[1].checkpoint)
    assert not own.__dict__["_prepared_runs"]
    for a, b in list(zip(fast, general)) + [(fast_resumed, general_resumed)]:
        for field in FIELDS:
            if field != "wall_time":
                _assert_same_field(field, getattr(a, field), getattr(b, field))
    for field in STORED:            # (samples after steps 0 and 1; 0, 2 and 3)
        value = getattr(longer, field)
        if value is not None:
            np.testing.assert_array_equal(getattr(fast[0], field), value[:2], err_msg=field)
            np.testing.assert_array_equal(getattr(fast[1], field), value[[0, 2, 3]],
                                          err_msg=field)
        else:
            assert getattr(fast[0], field) is None, field
