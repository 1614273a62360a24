"""Many runs of varied parameters on a distributed engine (docs/sweeps.md).

    table = dttmm.sweep(make_model, {"spin": [0.1, 0.2], "stiffness": [0.5, 1.0]},
                        t_end=1.0, dt=1e-4, outputs=tip_height)

make_model(**parameters) builds each run's model; outputs(result, model) reduces each run to a
dict of numbers (default: the final position of every body's output point).  The runs go to
dask.distributed (a LocalCluster of n_workers processes by default, or the scheduler at
`scheduler`), imported only here; without dask, to a local process pool.  Each worker process
loads the compiled kernels from numba's cache (compiling them once if the cache is cold); a
run on a worker is the same computation as in this process, so the table equals serial runs.
"""
import itertools
import os
import time
import warnings
from concurrent.futures import ProcessPoolExecutor

import numpy as np


class SweepTable:
    """The sweep's table: one row per run, a column per parameter and per output.

    Made by ``sweep`` (docs/sweeps.md).  ``table[name]`` is a column, ``len(table)`` the number
    of runs.

    Parameters
    ----------
    rows : list of dict
        One dict per run: column name -> value (the run's parameters and outputs).
    parameters : sequence of str
        The parameters' column names.
    outputs : sequence of str
        The outputs' column names.
    wall_time : float
        The whole sweep's wall-clock time, s.
    engine : str
        The engine the runs went to: "dask", "processes" or "serial".
    failures : list of (dict, str), optional
        The runs that failed: their parameters and the error (type and message); their rows'
        outputs are NaN.

    Attributes
    ----------
    columns : dict
        name -> (runs,) ndarray, for every parameter and output.
    parameters, outputs : list of str
        The column names of each kind.
    wall_time : float
        s, the whole sweep.
    engine : str
        "dask", "processes" or "serial".
    failures : list of (dict, str)
        As given (empty when every run finished).

    Raises
    ------
    KeyError
        A row without one of the columns.

    Examples
    --------
    >>> from dttmm import SweepTable
    >>> table = SweepTable([{"k": 1.0, "tip.y": -0.9}, {"k": 2.0, "tip.y": -0.8}], ["k"],
    ...                    ["tip.y"], wall_time=0.1, engine="serial")
    >>> len(table), table["tip.y"].tolist()
    (2, [-0.9, -0.8])
    """

    def __init__(self, rows, parameters, outputs, wall_time, engine, failures=()):
        self.parameters, self.outputs = list(parameters), list(outputs)
        self.columns = {name: np.array([row.get(name, np.nan) if name in self.outputs
                                        else row[name] for row in rows])
                        for name in self.parameters + self.outputs}
        self.wall_time, self.engine = wall_time, engine
        self.failures = list(failures)

    def __len__(self):
        return len(next(iter(self.columns.values()))) if self.columns else 0

    def __getitem__(self, name):
        return self.columns[name]

    def __repr__(self):
        failed = f", {len(self.failures)} failed" if self.failures else ""
        return (f"SweepTable({len(self)} runs{failed}; parameters {self.parameters}; outputs "
                f"{self.outputs}; {self.wall_time:.3g} s on {self.engine})")

    def save_csv(self, path):
        """Write the table as CSV: a header row of the column names (parameters, then
        outputs), then one row per run, every number to 17 significant digits.

        Parameters
        ----------
        path : str or path-like
            The file written (replaced if it exists).
        """
        names = self.parameters + self.outputs
        data = np.column_stack([self.columns[n] for n in names])
        np.savetxt(path, data, delimiter=",", header=",".join(names), comments="",
                   fmt="%.17g")


def final_points(result, model):
    """The default outputs: x, y, z of every body's output point at the end (m)."""
    end = result.position_output[-1]
    return {f"{name}.{c}": float(end[k, i]) for k, name in enumerate(model.body_names)
            for i, c in enumerate("xyz")}


FAILED = "__failed__"     # a failed run's row: its parameters and this key, the error


def _run_one(make_model, parameters, t_end, dt, outputs, options):
    """One run, on whichever process it lands: the model, the run, its outputs; a run that
    raises returns its parameters and the error instead (the sweep keeps the others)."""
    from ..solving.solver import simulate
    try:
        model = make_model(**parameters)
        result = simulate(model, t_end, dt, progress=False, **options)
        values = outputs(result, model)
        clash = sorted(set(values) & set(parameters))
        if clash:
            raise ValueError(f"sweep: outputs {clash} have the names of parameters; name them "
                             f"apart (a column each)")
        return dict(parameters, **{k: float(v) for k, v in values.items()})
    except Exception as err:            # reported with its parameter set by sweep
        return dict(parameters, **{FAILED: f"{type(err).__name__}: {err}"})


def _grid(parameters):
    """A list of dicts as it is; a dict of lists as their product (every combination)."""
    if isinstance(parameters, dict):
        names = list(parameters)
        for n in names:
            if isinstance(parameters[n], (str, bytes)) or not hasattr(parameters[n], "__len__"):
                raise ValueError(f"sweep: parameter {n!r} must be a list of values, got "
                                 f"{parameters[n]!r} (one value: [{parameters[n]!r}])")
        empty = [n for n in names if len(parameters[n]) == 0]
        if not names or empty:
            raise ValueError(f"sweep: every parameter needs at least one value; "
                             f"{empty or 'no parameters'} given none")
        return [dict(zip(names, values))
                for values in itertools.product(*(parameters[n] for n in names))]
    if not isinstance(parameters, (list, tuple)) or not all(isinstance(p, dict)
                                                          for p in parameters):
        raise ValueError(f"sweep: parameters must be a dict of lists, or a non-empty list of "
                         f"dicts with the same keys, got {type(parameters).__name__}")
    runs = [dict(p) for p in parameters]
    if not runs or any(set(r) != set(runs[0]) for r in runs):
        raise ValueError("sweep: parameters must be a dict of lists, or a non-empty list of "
                         "dicts with the same keys")
    return runs


def sweep(make_model, parameters, t_end, dt, *, outputs=final_points, engine="dask",
          scheduler=None, n_workers=2, **simulate_options):
    """Run simulate(make_model(**p), t_end, dt, **simulate_options) for every parameter set p
    and gather outputs(result, model) as a SweepTable.

    Parameters
    ----------
    make_model : callable
        make_model(**p) -> Model; shipped to the workers by pickling (cloudpickle under dask:
        a function defined in a script works).
    parameters : dict of lists, or list of dicts
        The runs: every combination of a dict's lists, or the dicts as given.
    t_end, dt : float
        simulate's end time and step, s (as ``simulate``: t_end > 0, dt > 0).
    outputs : callable, optional
        outputs(result, model) -> dict of numbers; default: the final output points (m).
    engine : {"dask", "processes", "serial"}
        "dask" (default): dask.distributed, a LocalCluster of n_workers processes (one thread
        each) unless `scheduler` names one ("tcp://host:8786"); falls back to "processes"
        when dask is not installed (pip install dttmm[sweep]). "processes": a local process
        pool. "serial": in this process, one after the other.
    scheduler : str, optional
        The address of a running dask scheduler ("tcp://host:8786"); None (default): a
        LocalCluster started for the sweep and closed after it.  Engine "dask" only.
    n_workers : int, optional
        Worker processes of the LocalCluster or the process pool (default 2); None for the
        process pool: os.cpu_count().  Not used with a scheduler or engine "serial".
    **simulate_options
        Passed to every simulate call (method, scheme, record_dt, ...).

    Returns
    -------
    SweepTable
        One row per run, in the order of the parameter sets: the parameters' columns (the
        parameter sets' keys), then the outputs' (outputs' keys, values as float).

    Raises
    ------
    ValueError
        parameters neither a dict of lists nor a non-empty list of dicts with the same keys;
        an unknown engine.
    RuntimeError
        Every run failed (the first one's parameters and error).

    Warns
    -----
    UserWarning
        Some runs failed (``simulate``'s ValueError or ``DivergenceError``, make_model's or
        outputs' errors): the table keeps the others, the failed rows' outputs are NaN, and
        ``table.failures`` lists each failed parameter set with its error.

    Examples
    --------
    >>> import dttmm
    >>> def make_model(spin):
    ...     rod = dttmm.RigidBody(mass=1.0, inertia=[1e-4, 1 / 12, 1 / 12],
    ...                           inertia_about="mass_center", to_mass_center=[0.5, 0, 0],
    ...                           to_output=[1.0, 0, 0], angular_velocity=[0, 0, spin])
    ...     return dttmm.build_chain([dttmm.BallJoint(), rod])
    >>> table = dttmm.sweep(make_model, {"spin": [0.0, 1.0]}, t_end=0.1, dt=1e-3,
    ...                     engine="serial")  # doctest: +SKIP
    >>> table["body0.y"]  # doctest: +SKIP
    """
    runs = _grid(parameters)
    t0 = time.perf_counter()
    args = (t_end, dt, outputs, simulate_options)
    if engine == "dask":
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            engine = "processes"
    if engine == "dask":
        try:
            cluster = None if scheduler else LocalCluster(
                n_workers=n_workers, threads_per_worker=1, processes=True,
                dashboard_address=None)
        except Exception as err:
            raise RuntimeError(
                f"sweep: dask could not start its local workers ({type(err).__name__}: {err}); "
                f"a script that sweeps on dask must run the sweep under "
                f"'if __name__ == \"__main__\":' (the workers import the script), or pass "
                f"engine='processes' or 'serial'") from err
        client = Client(scheduler or cluster)
        try:
            futures = client.map(_run_one, [make_model] * len(runs), runs,
                                 *[[a] * len(runs) for a in args], pure=False)
            rows = client.gather(futures)
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    elif engine == "processes":
        workers = n_workers or os.cpu_count()
        with ProcessPoolExecutor(max_workers=workers) as pool:
            rows = list(pool.map(_run_one, [make_model] * len(runs), runs,
                                 *[[a] * len(runs) for a in args]))
    elif engine == "serial":
        rows = [_run_one(make_model, p, *args) for p in runs]
    else:
        raise ValueError(f"sweep: engine must be 'dask', 'processes' or 'serial', got "
                         f"{engine!r}")
    names = list(runs[0])
    failures = [({n: row[n] for n in names}, row[FAILED]) for row in rows if FAILED in row]
    done = [row for row in rows if FAILED not in row]
    if not done:
        params, error = failures[0]
        raise RuntimeError(f"sweep: every run failed; the first, {_label(params)}: {error}")
    if failures:
        warnings.warn(f"sweep: {len(failures)} of {len(rows)} runs failed; their outputs are NaN "
                      f"and table.failures lists each ("
                      + "; ".join(f"{_label(p)}: {e}" for p, e in failures[:3])
                      + ("; ..." if len(failures) > 3 else "") + ")", stacklevel=2)
    return SweepTable(rows, names, [k for k in done[0] if k not in names],
                      time.perf_counter() - t0, engine, failures)


def _label(parameters):
    return ", ".join(f"{k}={v!r}" for k, v in parameters.items())
