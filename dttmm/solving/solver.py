"""DT-TMM time integration of a model (chains, trees, joints with coordinates):
simulate(model, t_end, dt | rtol, ...) -> Result.

The frozen Model is read-only; all mutable state lives in a Workspace allocated once per run.
The time loop runs in numba (one skeleton, kernels/stepping/loop.py, with the scheme's loop variant)
in chunks of fixed steps, or in an adaptive run's segments (adaptive.py); Python only evaluates
the prescribed ground motion, applied loads and joint drives for each chunk, judges segments,
and collects the recorded samples (results/recording.py).
"""
import contextlib
import functools
import time

from ..model.model import Model
from ..results.recording import (Recording, model_fingerprint)
from .resolution import warn_bent
from .threads import blas_threads, thread_count
from . import drivers
from .run_options import run_options
from .run_plan import kernels_used, prepared_run
from ..results.result import Result
from .run_checks import (UnresolvedMotionWarning, check_supported)
from .run_records import _result


MAX_STEP_ERROR = 0.05       # rad or m: simulate's default local error estimate limit per step
_NO_LIMIT = contextlib.nullcontext()    # (a run whose loop calls no LAPACK: blas_threads'
#                                         context manager itself costs a short run ~3 us)


def simulate(model: Model, t_end, dt=None, *, rtol=None, atol=0.0, method="riccati",
             scheme="newmark", rho_inf=1.0, newton_iterations=None, newton_tol=1e-12,
             record_every=None, record_dt=None, t_eval=None, full_state=False, richardson=False,
             progress=None, max_step_error=MAX_STEP_ERROR, max_energy_error=None,
             hold_energy=None, resume=None, stream=None, threads=None) -> Result:
    """Integrate a model from t = 0 to t_end by DT-TMM.

    Parameters
    ----------
    model : Model
        The frozen system (``dttmm.System(...).build()`` or ``dttmm.build_chain``).
    t_end : float
        End time, s (> 0).
    dt : float, optional
        The step, s (> 0). The run takes n = ceil(t_end / dt) equal steps of t_end / n (dt
        itself where it divides t_end), so the last step lands on t_end; ``info["dt"]`` is the
        step taken. With rtol: the first step (default t_end / 1000).
    rtol, atol : float, optional
        Adaptive steps (Newmark scheme): the step is chosen from the local error estimate so
        that the error accumulated over the run stays near atol + rtol (rad for rotations, m
        for displacements; rtol is relative to a motion of order one radian, atol an absolute
        floor, default 0). Segments of up to 256 equal steps run compiled; one whose estimate
        per unit time exceeds (atol + rtol) / t_end is taken again with a smaller step
        (growth at most 1.5x, shrink at most 5x per segment). ``n_steps`` counts the accepted
        steps; ``info`` reports ``steps_rejected`` (and ``segments_rejected``), ``dt_min`` and
        ``dt_max`` (docs/solver.md, "Adaptive steps").
    method : {"riccati", "direct"}
        "riccati" (default; stable for long and stiff chains) or "direct" (multiplies the
        transfer matrices out, as the paper does; chains only; loses accuracy on long or stiff
        chains).
    scheme : {"newmark", "energy_momentum", "paper", "dop853"}
        The table of schemes is ``dttmm.solving.methods.SCHEMES``.
        "newmark" (default): generalized-alpha, every element and topology.
        "energy_momentum": rigid chains with ball and fixed hinges on a fixed ground; a
        second-order step that conserves the total energy and the angular momentum to
        newton_tol (docs/solver.md). "paper": the paper's scheme, for comparison only (every
        station point with its own position history; it develops a growing step-to-step
        oscillation in long runs; docs/solver.md, "The paper's scheme"). "dop853": the
        explicit Runge-Kutta method of order 8 on the rotation group, compiled with the
        acceleration sweep (docs/integrators.md): chains and trees of rigid bodies and beams
        on ball joints, a fixed ground and gravity; with rtol its steps are chosen by its
        embedded estimate (the local error of each coordinate within atol + rtol |y|, of each
        rotation within atol + rtol rad; atol at least 1e-6 rtol) and its samples come from
        its dense output; with dt alone, fixed steps of dt. Explicit: stiff beams hold its
        steps below their stability limit.
    rho_inf : float
        Generalized-alpha spectral radius at infinite frequency, in [0, 1]; 1 (default) is the
        trapezoidal Newmark rule, smaller values damp high frequencies. Newmark scheme only.
    newton_iterations : int, optional
        Extra linearizations about the latest solution per step, stopping once the update is
        below newton_tol (rad, or scaled modal units). Default: 0 for Newmark (one
        linearization about the predictor is second-order accurate); 8 with joints with
        coordinates or a weld on a beam's end in a tree (their linearization is exact only to
        O(dt) terms; docs/joints.md); 20 for the energy-momentum scheme. Steps that use them
        all without reaching newton_tol are counted in ``info["newton_unconverged_steps"]``.
    newton_tol : float
        See newton_iterations (rad; default 1e-12).
    record_every : int, optional
        Record every k-th step.
    record_dt : float, optional
        Record every record_dt seconds (rounded to a whole number of steps).
    t_eval : array_like, optional
        Record at these times, s (increasing, on the step grid: multiples of dt; an adaptive
        run lands its steps on them). Give at most one of record_every, record_dt and t_eval.
        Default: every step of a run of up to 1000 steps, else every ceil(steps / 1000)-th step
        (at most ~1000 samples, and no more than about 256 MB of them: fewer for models of
        more than ~270 bodies, the first and last state of a million; adaptive: the first
        segment end after each t_end / 1000). The first and the final state are always
        recorded. Derived quantities (positions,
        energies) are computed when first read (``Result``).
    full_state : bool
        Use the 13-entry state even where the reduced [a; q] form applies (a tree: the
        full-state tree sweep, docs/assembly.md "Trees with joints").
    richardson : bool or int
        True: run at dt and dt/2 and return their Richardson extrapolation
        (4 y_dt/2 - y_dt) / 3 at the recorded times (Newmark only): fourth-order accurate where
        dt resolves the motion, for 3x the steps. An int L from 2 to 4: L runs at dt, dt/2, ...
        dt/2^(L-1), combined by Romberg's rule on the even powers of the step (orders 4, 6, 8
        with Newton iterations to newton_tol; each run is the trapezoidal rule, stable at any
        step, so the combination stays bounded where dt is far above a stiff beam's periods).
        ``info["richardson_correction_m"]`` is the largest change it made to a recorded point
        position; wall_time and n_steps count every run (docs/solver.md, "Richardson
        extrapolation").
    progress : bool, optional
        A tqdm progress bar on stderr once the run is expected to take more than about two
        seconds: None (default) when stderr is a terminal, True always, False never.
    max_step_error : float, optional
        Stop at the first step whose local error estimate (Zienkiewicz-Xie, |beta - 1/6| h^2
        max |p_{n+1} - p_n| over every rotation, modal and joint coordinate and deflection; rad
        or m) exceeds it; default 0.05; None never stops. ``info["step_error_max"]`` is the
        run's largest estimate (docs/solver.md, "Runs that cannot go wrong").
    max_energy_error : float, optional
        Stop when the energy balance breaks: |E - E(0) - W| above this fraction of the largest
        kinetic energy so far, E the total energy (the drives' springs left out), W the work of
        the applied loads, the joint drives, the elastic hinges' and beams' dampers and a
        moving ground since t = 0 (checked at the end of every chunk of up to 1000 steps;
        fixed steps). ``info["energy_balance_error"]`` is the run's largest. Default None: not
        checked (it derives every step's velocities; docs/solver.md, "Energy balance").
    hold_energy : bool, optional
        Closed loops of rigid bodies on which nothing works (gravity, no loads, drives,
        dampers or moving ground; rho_inf = 1): after each step's projection onto the loops,
        every rate is scaled so that the total energy is its value at the start (the least
        change of the rates, in the kinetic metric, that holds it; the positions keep the
        step's own second-order error; docs/loops.md, "The energy held"). None (default): held
        wherever it applies; False: never; True: held, or a ValueError saying why it cannot
        be. ``info["energy_held"]`` says which, ``info["energy_correction"]`` the largest
        relative change of the rates it made in one step.
    resume : Checkpoint, optional
        Continue the run that wrote it (``result.checkpoint``, or ``Checkpoint.load``) from
        its last step to t_end, with the same model, dt and options: the continued run takes
        the same steps on the same numbers, so the two halves equal the whole run bit for bit.
        Its first sample is the checkpoint's state.
    stream : str or path, optional
        A directory to write the samples to as they are recorded, instead of keeping them in
        memory (for long, densely recorded runs): one raw file per recorded quantity and an
        index, rewritten after each chunk. The Result's stored arrays are then read-only
        memory maps of those files; ``dttmm.load_stream(model, path)`` reads them again, also
        those of a run that stopped or was killed (the samples written so far). A stream
        already in the directory is replaced.
    threads : int, optional
        BLAS threads the run may use (the loops' small LAPACK calls). Default: 1, or the
        environment variable DTTMM_BLAS_THREADS; the process's own limit is restored after the
        run (dttmm/solving/threads.py; docs/solver.md, "Threads").

    Returns
    -------
    Result
        The recorded samples (``dttmm.Result``: times in s, positions in m, rotations,
        angular velocities in rad/s, interior forces in N and moments in N m at every body's
        input, energies in J, joint coordinates and drive forces), ``wall_time`` (s, the whole
        call), ``info`` (mode, loop, dt, Newton and error statistics) and ``checkpoint`` (the
        state after the last step, for ``resume``).

    Raises
    ------
    ValueError
        Before the run: a bad argument, or what the solver does not run for this model
        (naming the element).
    DivergenceError
        A run that cannot go on: a step's error estimate above max_step_error, an
        energy-momentum step that does not converge, a beam deflected beyond its length, a
        singular transfer, or NaN. Its message names the step, the time and the cause;
        ``err.partial`` holds the Result recorded before it.
    """
    wall0 = time.perf_counter()
    threads = thread_count(threads)
    return _simulate(wall0, threads, model, t_end, dt, rtol=rtol, atol=atol, method=method,
                     scheme=scheme, rho_inf=rho_inf, newton_iterations=newton_iterations,
                     newton_tol=newton_tol, record_every=record_every,
                     record_dt=record_dt, t_eval=t_eval, full_state=full_state,
                     richardson=richardson, progress=progress,
                     max_step_error=max_step_error, max_energy_error=max_energy_error,
                     hold_energy=hold_energy, resume=resume, stream=stream)


def _simulate(wall0, threads, model, t_end, dt, **options):
    """simulate's run, its BLAS libraries held to `threads` threads where its loop calls
    LAPACK (threads.py; the fused loops call none: the limit's ~20 us would be a short run's
    largest fixed cost)."""
    opts = run_options(model, t_end, dt, **options)
    if opts.richardson > 1:
        return drivers.richardson(opts, functools.partial(simulate, threads=threads))
    check_supported(opts.model, opts.scheme.name, opts.method, opts.full_state)
    lapack = kernels_used(opts.model, opts.scheme, opts.method, opts.full_state) in (
        "general", "energy-momentum")
    with blas_threads(threads) if lapack else _NO_LIMIT, prepared_run(opts) as plan:
        run = drivers.Stepping(plan, opts, wall0)
        result = (drivers.runge_kutta if opts.scheme.loop == "runge_kutta"
                  else drivers.adaptive if opts.adaptive else drivers.fixed_steps)(run)
    warn_bent(model, result, UnresolvedMotionWarning)
    return result._timed(time.perf_counter() - wall0)


def load_stream(model, path):
    """The Result of the samples a run streamed to a directory.

    Parameters
    ----------
    model : Model
        The model that run simulated (the positions and energies are derived from it).
    path : str or path
        The directory given as ``simulate(..., stream=path)``.

    Returns
    -------
    Result
        The samples written (all of them, or those before the run stopped or was killed), its
        stored arrays read-only memory maps of the stream's files; ``n_steps`` is the step of
        the last sample, ``info`` the run's options.

    Raises
    ------
    ValueError
        No stream in the directory, a damaged one, or one of another model (its number of
        bodies, or its fingerprint: recording.model_fingerprint).
    """
    if not isinstance(model, Model):
        raise ValueError(f"load_stream: model must be the Model the run simulated, got "
                         f"{type(model).__name__}")
    try:
        recording = Recording.from_stream(path)
        meta = recording.stream.meta
        arrays = recording.arrays()
    except ValueError as err:
        if str(err).startswith("load_stream"):
            raise
        raise ValueError(f"load_stream: the stream in {str(path)!r} is damaged ({err})") from None
    except (OSError, KeyError, TypeError) as err:
        raise ValueError(f"load_stream: the stream in {str(path)!r} is damaged or not a "
                         f"stream's ({type(err).__name__}: {err})") from None
    if len(recording.steps) and arrays["rot"].shape[1] != model.n_bodies:
        raise ValueError(f"load_stream: the stream in {str(path)!r} holds "
                         f"{arrays['rot'].shape[1]} bodies; the model has {model.n_bodies}")
    written = meta.get("info", {}).get("model_fingerprint")
    if written is not None and written != model_fingerprint(model):
        raise ValueError(f"load_stream: the stream in {str(path)!r} was written by a run of "
                         f"another model (its fingerprint differs): load it with that model")
    return _result(model, recording, meta["dt"], 0.0, recording.last_step, dict(meta["info"]))
