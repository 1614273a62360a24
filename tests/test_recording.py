"""Recording that scales (docs/solver.md, "Steps and records"): a bounded default, samples at
given times, a run continued from a checkpoint equal to the uninterrupted run to the last bit,
and the peak memory of a long run."""
import pickle
import sys
from pathlib import Path

import numpy as np
import pytest

from dttmm import (BallJoint, Checkpoint, ElasticHinge, Result, build_chain, simulate)
from dttmm.model.chains import (arm, five_link_tree, rigid_chain, stiff_cantilever, three_pendulum,
                          unit_link)
from dttmm.solving import run_records

ROOT = Path(__file__).resolve().parents[1]
STATE = ("t", "rotation", "angular_velocity", "angular_acceleration", "force", "moment",
         "modal_coordinates", "modal_velocities", "joint_coordinates", "joint_rates",
         "drive_force", "position_output", "velocity_input", "kinetic", "potential")


def _elastic_chain():
    """A chain with an elastic hinge: the general loop."""
    return build_chain([BallJoint(), unit_link(angular_velocity=[0.0, 0.5, 0.0]),
                        ElasticHinge(1e4, 1e3, rotational_damping=0.5), unit_link()])


@pytest.mark.parametrize("name, make, options", [
    ("three-pendulum (fused chain)", three_pendulum, {}),
    ("tree (fused tree)", five_link_tree, {}),
    ("elastic hinge (general loop)", _elastic_chain, {}),
    ("welded beams (fused welded chain)", lambda: stiff_cantilever(3), {}),
    ("rigid arm, motion drive (joints, Newton iterations)", lambda: arm(drive="motion"), {}),
    ("energy-momentum", lambda: rigid_chain(3), {"scheme": "energy_momentum"}),
])
def test_two_halves_equal_the_whole_run_to_the_last_bit(name, make, options):
    model = make()
    whole = simulate(model, 0.2, 1e-3, record_every=1, **options)
    first = simulate(model, 0.1, 1e-3, record_every=1, **options)
    second = simulate(model, 0.2, 1e-3, record_every=1, resume=first.checkpoint, **options)
    assert second.t[0] == first.t[-1] == pytest.approx(0.1)
    for field in STATE:
        a = getattr(whole, field)
        if a is None:
            continue
        joined = np.concatenate([getattr(first, field), getattr(second, field)[1:]])
        assert np.array_equal(joined, a), f"{name}: {field}"
    assert second.info["newton_unconverged_steps"] == whole.info["newton_unconverged_steps"]


def test_a_checkpoint_saved_to_a_file_resumes_the_same(tmp_path):
    model = rigid_chain(3)
    first = simulate(model, 0.05, 1e-3)
    first.checkpoint.save(tmp_path / "c.npz")
    back = Checkpoint.load(tmp_path / "c.npz")
    a = simulate(model, 0.1, 1e-3, resume=first.checkpoint)
    b = simulate(model, 0.1, 1e-3, resume=back)
    assert np.array_equal(a.rotation, b.rotation) and np.array_equal(a.force, b.force)


def test_a_checkpoint_refuses_another_run():
    first = simulate(rigid_chain(3), 0.05, 1e-3)
    with pytest.raises(ValueError, match="dt"):
        simulate(rigid_chain(3), 0.1, 5e-4, resume=first.checkpoint)
    with pytest.raises(ValueError, match="scheme"):
        simulate(rigid_chain(3), 0.1, 1e-3, scheme="paper", resume=first.checkpoint)
    with pytest.raises(ValueError, match="bodies|model"):
        simulate(rigid_chain(4), 0.1, 1e-3, resume=first.checkpoint)
    with pytest.raises(ValueError, match="not after"):
        simulate(rigid_chain(3), 0.05, 1e-3, resume=first.checkpoint)
    with pytest.raises(ValueError, match="Checkpoint"):
        simulate(rigid_chain(3), 0.1, 1e-3, resume=first)


def test_the_default_recording_is_bounded_and_keeps_the_end():
    model = rigid_chain(3)
    short = simulate(model, 0.5, 1e-3)                   # 500 steps: every step
    assert len(short.t) == 501
    long = simulate(model, 5.0, 1e-3)                    # 5000 steps: every 5th
    assert len(long.t) == 1001 and np.allclose(np.diff(long.t), 5e-3)
    odd = simulate(model, 4.0015, 1e-3)                  # 4002 steps (dt kept: 4.0015 / 4002)
    assert len(odd.t) <= 1002 and odd.t[-1] == pytest.approx(4.0015)
    full = simulate(model, 5.0, 1e-3, record_every=1)
    assert np.array_equal(long.position_output, full.position_output[::5])


def test_samples_at_given_times():
    model = three_pendulum()
    full = simulate(model, 0.3, 1e-3, record_every=1)
    at = simulate(model, 0.3, 1e-3, t_eval=[0.0, 0.05, 0.123, 0.3])
    assert np.allclose(at.t, [0.0, 0.05, 0.123, 0.3])
    rows = [0, 50, 123, 300]
    for field in ("rotation", "position_output", "modal_coordinates", "force", "kinetic"):
        assert np.array_equal(getattr(at, field), getattr(full, field)[rows]), field
    by_dt = simulate(model, 0.3, 1e-3, record_dt=0.1)
    assert np.allclose(by_dt.t, [0.0, 0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match=r"t_eval\[1\] = 0.0505 s is not on the step grid"):
        simulate(model, 0.3, 1e-3, t_eval=[0.0, 0.0505])
    with pytest.raises(ValueError, match="one of record_every, record_dt and t_eval"):
        simulate(model, 0.3, 1e-3, record_every=2, record_dt=0.1)
    with pytest.raises(ValueError, match="increase"):
        simulate(model, 0.3, 1e-3, t_eval=[0.2, 0.1])


def test_richardson_keeps_the_times_asked_for():
    model = rigid_chain(2)
    res = simulate(model, 0.2, 1e-3, t_eval=[0.0, 0.1, 0.2], richardson=True)
    assert np.allclose(res.t, [0.0, 0.1, 0.2]) and res.info["richardson"]


def test_results_are_read_only_and_name_their_columns(tmp_path):
    res = simulate(rigid_chain(2), 0.01, 1e-3)
    with pytest.raises(AttributeError, match="read-only"):
        res.t = None
    res.save_csv(tmp_path / "r.csv")
    head = (tmp_path / "r.csv").read_text().splitlines()[0].split(",")
    assert head[:4] == ["t", "link1.x", "link1.y", "link1.z"]
    back = Result.load_npz(_saved(res, tmp_path))
    assert back.body_names == ("link1", "link2")
    assert np.array_equal(back.kinetic, res.kinetic)
    copy = pickle.loads(pickle.dumps(simulate(rigid_chain(2), 0.01, 1e-3)))
    assert np.array_equal(copy.position_output, res.position_output)


def _saved(res, tmp_path):
    res.save_npz(tmp_path / "r.npz")
    return tmp_path / "r.npz"


def test_a_long_run_stays_small():
    """The issue's case: a 100-link chain, 5 s at dt = 1e-4 (50000 steps), default recording,
    positions read: the whole process's peak under 500 MB (it peaked at 5.5 GB when every step
    was recorded and every derived quantity computed at the end)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from recording import long_run_memory
    figures = long_run_memory(100, 5.0, 1e-4)
    print(f"100-link chain, 5 s at dt = 1e-4: {figures}")
    assert figures["samples"] <= 1001
    assert figures["peak_mb"] < 500


def test_a_streamed_run_equals_the_run_in_memory_and_reloads(tmp_path):
    """simulate(..., stream=dir): the same samples as the run kept in memory, bit for bit,
    read back by load_stream; an adaptive run's times too."""
    from dttmm import load_stream
    model = three_pendulum()
    kept = simulate(model, 0.3, 1e-3, record_every=7)
    streamed = simulate(model, 0.3, 1e-3, record_every=7, stream=tmp_path / "run")
    again = load_stream(model, tmp_path / "run")
    for name in STATE:
        a = getattr(kept, name)
        if a is not None:
            np.testing.assert_array_equal(getattr(streamed, name), a, err_msg=name)
            np.testing.assert_array_equal(getattr(again, name), a, err_msg=name)
    assert isinstance(streamed.rotation, np.memmap) and again.n_steps == 300
    adaptive = simulate(model, 0.3, rtol=1e-5, t_eval=[0.1, 0.2, 0.3], stream=tmp_path / "a")
    np.testing.assert_array_equal(load_stream(model, tmp_path / "a").t, [0.0, 0.1, 0.2, 0.3])
    np.testing.assert_array_equal(load_stream(model, tmp_path / "a").position_output,
                                  adaptive.position_output)
    with pytest.raises(ValueError, match="holds no stream"):
        load_stream(model, tmp_path)
    with pytest.raises(ValueError, match="bodies"):
        load_stream(rigid_chain(2), tmp_path / "run")


def test_a_run_that_stops_leaves_its_samples_in_the_stream(tmp_path):
    from dttmm import DivergenceError, load_stream
    with pytest.raises(DivergenceError) as err:
        simulate(rigid_chain(3), 20.0, 0.5, record_every=1, stream=tmp_path / "s")
    saved = load_stream(rigid_chain(3), tmp_path / "s")
    np.testing.assert_array_equal(saved.t, err.value.partial.t)
    np.testing.assert_array_equal(saved.rotation, err.value.partial.rotation)


def test_a_streamed_run_holds_no_samples_in_memory(tmp_path):
    """A 30-link chain, 2 s at dt = 1e-4 recorded at every step (20001 samples, 130 MB of
    state): the process's peak with the samples streamed to disk is at least 100 MB below the
    same run kept in memory (measured in subprocesses)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from recording import long_run_memory
    kept = long_run_memory(30, 2.0, 1e-4, record_every=1)
    streamed = long_run_memory(30, 2.0, 1e-4, record_every=1, stream=tmp_path / "s")
    print(f"kept {kept['peak_mb']:.0f} MB, streamed {streamed['peak_mb']:.0f} MB")
    assert streamed["samples"] == kept["samples"] == 20001
    assert streamed["peak_mb"] < kept["peak_mb"] - 100


@pytest.mark.parametrize("options", [dict(record_every=1), dict(record_every=3),
                                     dict(record_every=10), dict(record_every=11),
                                     dict(t_eval=[0.002, 0.005, 0.01]), dict(t_eval=[0.003]),
                                     {}])
def test_a_fixed_step_run_knows_how_many_samples_it_records(options):
    """A fixed-step run writes its samples into arrays of the rows it will record
    (run_records._sample_count; recording.Recording(samples=)): the count is the samples it then
    records, from t = 0 and from a checkpoint, so that no row is joined or left over."""
    model = rigid_chain(3)
    runs = [(0, simulate(model, 0.01, 1e-3, **options))]
    if "t_eval" not in options:                 # (a checkpoint's run: its times after it)
        first = simulate(model, 0.004, 1e-3, **options)
        runs.append((4, simulate(model, 0.01, 1e-3, resume=first.checkpoint, **options)))
    for start, result in runs:
        sampling = run_records._sampling(10, 1e-3, options.get("record_every"), None,
                                    options.get("t_eval"), start, model.n_bodies)
        assert len(result.t) == run_records._sample_count(sampling, start, 10), (start, result.t)
