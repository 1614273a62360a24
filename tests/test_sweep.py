"""Sweeps of many runs (docs/sweeps.md): on a LocalCluster of 2 dask workers, and on a local
process pool, the table equals the same runs made one after the other in this process."""
import numpy as np
import pytest

import dttmm
from dttmm.model.chains import rigid_chain

RUNS = {"n_links": [3], "gravity": [(0.0, -9.81, 0.0), (0.0, -4.0, 0.0)],
        "tip_angular_velocity": [(0.0, 0.1, 0.0), (0.3, 0.0, 0.2)]}


@pytest.mark.parametrize("engine", ["dask", "processes"])
def test_a_sweep_equals_the_serial_runs(engine):
    pytest.importorskip("dask.distributed") if engine == "dask" else None
    serial = dttmm.sweep(rigid_chain, RUNS, 0.2, 1e-3, engine="serial")
    spread = dttmm.sweep(rigid_chain, RUNS, 0.2, 1e-3, engine=engine, n_workers=2)
    assert len(serial) == len(spread) == 4 and spread.engine == engine
    assert spread.outputs == serial.outputs and len(serial.outputs) == 9
    for name in serial.parameters + serial.outputs:
        assert np.array_equal(serial[name], spread[name]), name
    # the table's rows are the runs themselves
    one = dttmm.simulate(rigid_chain(3, gravity=(0.0, -4.0, 0.0),
                                     tip_angular_velocity=(0.3, 0.0, 0.2)), 0.2, 1e-3)
    assert spread["link3.y"][3] == one.position_output[-1, 2, 1]


def test_a_sweep_refuses_ragged_parameters():
    with pytest.raises(ValueError, match="same keys"):
        dttmm.sweep(rigid_chain, [{"n_links": 2}, {"gravity": (0, 0, 0)}], 0.1, 1e-3,
                    engine="serial")
    with pytest.raises(ValueError, match="engine"):
        dttmm.sweep(rigid_chain, {"n_links": [2]}, 0.1, 1e-3, engine="threads")
    with pytest.raises(ValueError, match="at least one value"):
        dttmm.sweep(rigid_chain, {"n_links": []}, 0.1, 1e-3, engine="serial")
    with pytest.raises(RuntimeError, match=r"every run failed.*outputs \['n_links'\] have the "
                                           r"names of parameters"):
        dttmm.sweep(rigid_chain, {"n_links": [2]}, 0.1, 1e-3, engine="serial",
                    outputs=lambda result, model: {"n_links": 1.0})


@pytest.mark.parametrize("engine", ["serial", "processes", "dask"])
def test_a_failing_run_keeps_the_others(engine):
    """One run of three fails (a step far too large for its fast spin stops it): the table
    keeps the two that finished, the failed row's outputs are NaN, table.failures names its
    parameter set and error, and a warning says so (before, the sweep raised and the finished
    runs were lost)."""
    if engine == "dask":
        pytest.importorskip("dask.distributed")
    runs = [{"n_links": 2, "tip_angular_velocity": (0.0, 0.0, w)} for w in (0.1, 4000.0, 0.2)]
    with pytest.warns(UserWarning, match="1 of 3 runs failed.*4000"):
        table = dttmm.sweep(rigid_chain, runs, 0.05, 1e-3, engine=engine, n_workers=2)
    assert len(table) == 3 and len(table.failures) == 1
    assert np.isnan(table["link2.x"][1]) and np.isfinite(table["link2.x"][[0, 2]]).all()
    assert table.failures[0][0]["tip_angular_velocity"] == (0.0, 0.0, 4000.0)
    assert "DivergenceError" in table.failures[0][1]
    with pytest.raises(ValueError, match="parameter 'n_links' must be a list"):
        dttmm.sweep(rigid_chain, {"n_links": 2}, 0.1, 1e-3, engine="serial")
    with pytest.raises(ValueError, match="dict of lists"):
        dttmm.sweep(rigid_chain, 2.0, 0.1, 1e-3, engine="serial")


def test_a_dask_sweep_in_a_script_without_a_main_guard_says_so(tmp_path):
    """dask's workers import the script that started them: without a main guard they start
    the sweep again and fail, which dask reports as "Nanny failed to start"; the sweep says
    what to do instead."""
    pytest.importorskip("dask.distributed")
    import subprocess
    import sys
    script = tmp_path / "sweep_script.py"
    script.write_text("import dttmm\nfrom dttmm.model.chains import rigid_chain\n"
                      "dttmm.sweep(rigid_chain, {'n_links': [2]}, 0.01, 1e-3, engine='dask',\n"
                      "            n_workers=1)\n")
    run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                         cwd=tmp_path, timeout=300)
    assert run.returncode != 0
    assert "if __name__ == \"__main__\":" in run.stderr.splitlines()[-1]
