"""simulate's drivers (issue 31's reshape): how a prepared run (run_plan.py) is stepped to
t_end.  Stepping is one call's records and chunk inputs; fixed_steps runs chunks of equal steps
(with the energy balance where asked), adaptive runs segments whose step the local error
estimate chooses (adaptive.py), runge_kutta runs the high-order scheme's compiled steps
(kernels/stepping/runge_kutta.py), richardson extrapolates two to four fixed-step runs.  Each ends
in the run's Result."""
import time
import warnings

import numpy as np

from . import adaptive as adaptive_steps
from . import consistent_start, run_checks, run_inputs, run_records, run_tables
from .energy_balance import EnergyBalance
from ..results.feedback import Progress, note_once
from ..model.loop_rows import closure_targets
from ..kernels.stepping import runge_kutta as runge_kutta_kernels
from ..kernels.schema import INPUT_LAYOUT
from ..kernels.stepping.loop import ERROR_ESTIMATE, NOT_FINITE, OK, SINGULAR, UNSUPPORTED, Run
from ..results.recording import Checkpoint, NoCheckpoint, Recording, SampleStream
from .resolution import warn_contact, warn_unresolved
from ..results.result import _drive_spring_energy


class Stepping:
    """One simulate call on a prepared run: its records (results/recording.py), the prescribed
    inputs of its chunks, the compiled loop's calls, and its Result."""

    def __init__(self, plan, opts, wall0):
        self.plan, self.opts, self.wall0 = plan, opts, wall0
        model = plan.model
        n = model.n_bodies
        counters, done = (0, 0), 0
        resume = opts.resume
        if resume is not None:
            resume.restore(plan.structures, plan.checkpoint_run)
            counters, done = resume.counters, resume.step
            if plan.loop_name == "general":     # this process's callbacks, not the checkpoint's
                # addresses (another process's, or another function of the same name)
                plan.loop.scratch.forces[:] = run_tables.compiled_forces(model)
        self.done = done
        self.samples = None if opts.adaptive else run_records._sample_count(opts.sampling, done,
                                                                   opts.n_steps)
        self.recording = Recording(plan.record_layout, None if opts.stream is None else
                                   SampleStream.create(opts.stream, plan.keys, opts.dt,
                                                       dict(plan.run_info, method=opts.method,
                                                            adaptive=opts.adaptive)),
                                   self.samples)
        self.recording.add_state(done, 0.0 if opts.adaptive else None)
        # chunks of up to CHUNK steps; a JointForce drive given as a Python function of the
        # state is evaluated in Python, one step ahead: one step per chunk (said once per
        # process)
        stepwise = plan.stepwise
        self.force_drives = bool(stepwise)
        if stepwise:
            note_once("stepwise", f"dttmm: a JointForce given as a Python function of the "
                      f"state ({stepwise[0]}) makes the run take one step per compiled call, "
                      f"several times the cost of a step; on a tree joint, a function compiled "
                      f"with @numba.njit (f(t, q, q_dot) of three floats) runs inside the loop "
                      f"(docs/joints.md)")
        # a chunk's inputs and record rows hold each of its steps for every body: no more steps
        # than the run has, nor than CHUNK_BYTES of them (a million bodies: one step per chunk)
        self.size = 1 if self.force_drives else max(1, min(
            run_records.CHUNK, run_records.CHUNK_BYTES // (run_records.CHUNK_STEP_BYTES * n),
            run_records.CHUNK if opts.adaptive else opts.n_steps - done))
        self.static_ground = model.ground_motion is None
        self.no_loads = not plan.has_loads
        self._fixed_ground = None       # (fixed_ground)
        # nothing prescribed varies in time: every chunk of m steps reads the same inputs
        self.static_inputs = (self.static_ground and self.no_loads
                              and not plan.joint_inputs_vary and not plan.targets_vary
                              and not plan.closing_forces)
        # the compiled loop's status, failing step, Newton iterations, samples written and
        # unconverged steps (a kept run's own array: its next call's arguments are the same)
        self.info = plan.chunk_arrays(("info",), lambda: np.zeros(5, dtype=np.int64))
        self.info[:4] = 0
        self.info[4] = counters[1]
        self.max_newton = counters[0]

    def records(self, every, balance):
        """Where the compiled loop writes a chunk's samples (consistent_start._record), every
        every-th
        step of chunks of up to self.size steps; a run that samples only its ends (a million
        bodies by default: run_records._sampling) records its last state from the state itself, and
        its chunks write no rows (the rows of a step would hold 0.4 KB per body)."""
        plan = self.plan
        ends_only = balance is None and self.samples == 2
        shape = (0 if ends_only else max(1, self.size // every),) + plan.record_shape
        return ends_only, plan.chunk_arrays(("record",) + shape,
                                            lambda: consistent_start._record(*shape))

    def chunk_inputs(self, done, m, h):
        """The prescribed data of the m steps of h after step `done` (inputs_for): a run whose
        inputs do not vary in time reads the same arrays each chunk (made once per length)."""
        if self.static_inputs:
            return self.plan.chunk_arrays(("inputs", self.size, m), lambda: self.inputs_for(
                np.arange(m + 1) * h, None, h))
        return self.inputs_for((done + np.arange(m + 1)) * h, (done + np.arange(m) + 0.5) * h, h)

    def fixed_ground(self):
        """A fixed ground's six arrays (run_inputs._ground) for chunks of up to self.size steps,
        made once."""
        if self._fixed_ground is None:
            self._fixed_ground = self.plan.chunk_arrays(
                ("ground", self.size),
                lambda: run_inputs._ground(self.plan.model, np.zeros(self.size + 1)))
        return self._fixed_ground

    def inputs_for(self, times, mid_times, h):
        """The prescribed data of m = len(times) - 1 steps of h from times[0] (a FlatInputs,
        kernels/schema.py::INPUTS, zero where nothing is prescribed; valid until the next call
        of the same length): at the steps' ends times[1:] (the energy-momentum step's loads: at
        mid_times)."""
        plan, model = self.plan, self.plan.model
        m = len(times) - 1
        # (a kept run's inputs of m steps, made once: every call writes all that is prescribed,
        # and what is not stays zero)
        inputs = plan.chunk_arrays(("inputs", m), lambda: INPUT_LAYOUT.zeros(
            steps=m, bodies=model.n_bodies, rows=plan.loops.rows))
        if self.static_ground:
            ga, gr, gw, gwd, gp, gv = (a[:m + 1] for a in self.fixed_ground())
        else:
            ga, gr, gw, gwd, gp, gv = run_inputs._ground(model, times)
            ga, gw, gwd, gp, gv = ga[1:], gw[1:], gwd[1:], gp[1:], gv[1:]
        for name, value in (("g_acc", ga[:m]), ("g_rot", gr), ("g_w", gw[:m]),
                            ("g_wd", gwd[:m]), ("g_pos", gp[:m]), ("g_vel", gv[:m])):
            getattr(inputs, name)[:] = value
        if not self.no_loads:
            loads = run_inputs._loads(model, mid_times if self.opts.scheme.loads_at_midpoints
                                      else times[1:])
            for name, value in zip(("force", "torque", "line_load"), loads):
                getattr(inputs, name)[:] = value
        if plan.joint_inputs_vary:
            inputs.joint_input[:] = run_inputs._joint_inputs(model, times[1:], plan.state, h)
        loops = plan.loops
        if plan.targets_vary:
            inputs.closure_target[:] = closure_targets(model, times[1:], loops)
        for r, law, who in plan.closing_forces:  # f(t, q, q') at the predictor from the last
            q, qd, qdd = loops.g[r], loops.gd[r], loops.acc[r]  # step's q, q' (its projection)
            inputs.closure_target[0, r, 2] = run_inputs._drive_number(
                law(times[1], q + h * qd + 0.5 * h * h * qdd, qd + h * qdd), who, times[1])
        return inputs

    def run_chunk(self, inputs, rec, h, every, first_step, t_first, step_limit=None):
        """The compiled loop over one chunk's steps (stopping at a step whose estimate exceeds
        step_limit, default max_step_error); a singular matrix found in numpy (the general
        loop's small solves) stops the run."""
        plan, opts = self.plan, self.opts
        step_limit = opts.max_step_error if step_limit is None else step_limit
        try:
            settings = plan.chunk_arrays(("settings", h, every, step_limit),
                                         lambda: plan.settings._replace(
                                             h=h, record_every=every, max_step_error=step_limit))
            plan.runner(plan.loop, Run(plan.params, settings, plan.state, plan.sweep, inputs, rec,
                                       plan.monitor), self.info, calls=plan.calls)
        except np.linalg.LinAlgError as err:
            raise run_checks.DivergenceError(
                first_step + 1, t_first, f"a matrix of the sweep is singular somewhere in steps "
                f"{first_step + 1}..{first_step + len(inputs.force)} ({err}); "
                f"{run_checks._DIRECT_HINT if opts.method == 'direct' else ''}") from None
        if self.info[0] == UNSUPPORTED:
            raise ValueError(run_checks._unsupported_cause(plan.model, int(self.info[2]),
                                                  f"the {plan.loop_name} loop"))

    def partial(self, steps_taken):
        """The Result of the samples recorded so far (a run that stops)."""
        return run_records._result(self.plan.user_model, self.recording, self.opts.dt,
                         time.perf_counter() - self.wall0, steps_taken, dict(self.plan.run_info))

    def stopped(self, step, t, cause, steps_taken):
        """The DivergenceError of a run that stops at `step` (time t) for `cause`, with the samples
        recorded so far and, where a stiffened beam had bent near where its second-order energy
        stops holding, that (run_checks._stiffened_bend_hint)."""
        partial = self.partial(steps_taken)
        hint = run_checks._stiffened_bend_hint(self.plan.user_model, partial)
        return run_checks.DivergenceError(step, t, cause + hint, partial)


def _faster(a, b):
    """The faster of two (rad/s, body) (run_checks._fastest_rate), the first where equal."""
    return b if b[0] > a[0] else a


def fixed_steps(run):
    """Chunks of equal steps to n_steps (run_records._next_chunk), recorded as `sampling` asks, the
    energy balance checked after each where asked; the Result with its checkpoint."""
    plan, opts, recording = run.plan, run.opts, run.recording
    model, state, info, dt = plan.model, plan.state, run.info, opts.dt
    n_steps, sampling, keys, done = opts.n_steps, opts.sampling, plan.keys, run.done
    every = sampling if isinstance(sampling, int) else run.size + 1
    balance = None
    if opts.max_energy_error is not None:           # every step's state, for the balance
        every = 1
        work_steps, work_values = [np.array([done])], [np.zeros(1)]     # W at every step

        def result_of(values, steps):
            rows = Recording(plan.record_layout)
            rows.add(values, steps)
            return run_records._result(plan.user_model, rows, dt, 0.0, 0, {}), rows.arrays()

        balance = EnergyBalance(plan.user_model, opts.max_energy_error, result_of,
                                run_tables.beam_tables(plan.user_model))
        start_values = dict(state.tables(), **plan.history_values)
        f0, tq0, ll0 = run_inputs._loads(model, [done * dt])
        loaded = plan.loaded
        balance.start({key: start_values[key][None] for key in keys}, f0[:, loaded],
                      tq0[:, loaded], ll0[:, loaded])
    ends_only, rec = run.records(every, balance)
    max_newton = run.max_newton
    # (a run of one chunk never shows a bar: Progress shows one after the first chunk)
    bar = Progress(n_steps - done, opts.progress if n_steps - done > run.size else False)
    fastest = (plan.start_fastest if done == 0      # (rad/s, body) over the samples
               else run_checks._fastest_rate(state.omega[None]))
    try:
        while done < n_steps:
            m, every = run_records._next_chunk(done, n_steps, sampling, run.size)
            if ends_only:
                every = m + 1
            try:
                inputs = run.chunk_inputs(done, m, dt)
            except run_checks.UserFunctionError as err:
                step = max(int(round(err.t / dt)), done + 1)
                raise run_checks.DivergenceError(step, err.t, str(err), run.partial(done)) from None
            run.run_chunk(inputs, rec, dt, 1 if balance else every, done, (done + 1) * dt)
            status, failed_at, newton, n_rec, _ = info.tolist()     # (Python ints)
            if balance is not None and n_rec:       # the samples asked for, from every step's
                picked = np.arange(every - 1, n_rec, every)
                if len(picked):
                    recording.add({key: getattr(rec, key)[picked] for key in keys},
                                  done + 1 + picked)
            elif n_rec:
                recording.add({key: getattr(rec, key)[:n_rec] for key in keys},
                              done + every * np.arange(1, n_rec + 1))
            if status != OK:
                step = done + failed_at + 1
                cause = run_checks._failure_cause(model, plan.mode, info, plan.monitor,
                                                  plan.settings)
                if opts.method == "direct" and status == SINGULAR:
                    cause += "; " + run_checks._DIRECT_HINT
                raise run.stopped(step, step * dt, cause, step - 1)
            max_newton = max(max_newton, newton)
            if n_rec:
                fastest = _faster(fastest, run_checks._fastest_rate(rec.omega[:n_rec]))
            if balance is not None:
                broken = balance.chunk({key: getattr(rec, key)[:m] for key in keys},
                                       done + np.arange(1, m + 1), dt,
                                       inputs.force[:, plan.loaded],
                                       inputs.torque[:, plan.loaded],
                                       inputs.line_load[:, plan.loaded])
                if broken:
                    raise run.stopped(done + m, (done + m) * dt, broken, done + m)
                work_steps.append(done + np.arange(1, m + 1))
                work_values.append(balance.chunk_work)
            done += m
            bar.update(done)
            runaway = run_checks._beam_beyond_its_length(model, plan.beam_tips, state.eta)
            if runaway:
                raise run.stopped(done, done * dt, runaway, done)
    finally:
        bar.close()
    rec = inputs = None                         # (the chunks' buffers)
    if recording.last_step != n_steps:          # the final state is always recorded
        recording.add_state(n_steps)
        fastest = _faster(fastest, run_checks._fastest_rate(state.omega[None]))
    unconverged = int(info[4])
    checkpoint = Checkpoint.of(n_steps, dt, plan.checkpoint_run, plan.ending(),
                               (max_newton, unconverged))
    turn = fastest[0] * dt
    if turn > run_checks.MAX_TURN_PER_STEP:
        warnings.warn(run_checks.UnresolvedMotionWarning(
            f"simulate: the step does not resolve the motion: body "
            f"'{model.body_names[fastest[1]]}' turns by up to {turn:.3g} rad per step "
            f"({fastest[0]:.4g} rad/s at dt = {dt:g} s), where the trapezoidal rule's phase "
            f"error, about (w dt)^2 / 12 per radian ({turn ** 2 / 12:.1%} here), may leave "
            f"the result far off; take dt <= {2 * np.pi / (20 * fastest[0]):.2g} s (20 steps "
            f"a turn), or rtol= for steps chosen by the error"), stacklevel=3)
    result = run_records._result(plan.user_model, recording, dt, 0.0, n_steps,
                       dict(plan.run_info, newton_iterations_used=max_newton,
                            newton_unconverged_steps=unconverged,
                            step_error_max=float(plan.monitor.error[0]),
                            turn_per_step_max=turn,
                            **({} if balance is None else
                               {"energy_balance_error": balance.worst}),
                            **run_tables._loop_info(plan.loops)),
                       checkpoint)
    warn_unresolved(plan.user_model, result, dt, run_checks.UnresolvedMotionWarning,
                    run_checks.MAX_TURN_PER_STEP)
    warn_contact(plan.user_model, result, dt, run_checks.UnresolvedMotionWarning,
                 run_checks.MAX_TURN_PER_STEP)
    if balance is not None:                     # W at the samples
        work = np.interp(np.asarray(recording.steps, dtype=float), np.concatenate(work_steps),
                         np.concatenate(work_values))
        if result.joint_coordinates is not None:
            # the balance counts the drives' springs in their work, the Result's potential
            # holds their energy: W here is the rest (total - total(0) - W is the balance)
            spring = _drive_spring_energy(plan.user_model, result.joint_coordinates, len(work))
            work = work + spring - spring[0]
        result = result.replace(energy_work=work)
    return result


def adaptive(run):
    """An adaptive run's segments (adaptive.py; docs/solver.md, "Adaptive steps"): save the
    run's arrays, take up to `most` steps of the controller's h (landing on the next sample
    time or t_end), then accept the segment or restore and retry with a smaller step.  A
    segment that fails (estimate above max_step_error, NaN, no Newton convergence, a singular
    transfer, a beam beyond its length) is retried with a quarter of the step; the run stops
    with DivergenceError once the step falls below adaptive.MIN_STEP of t_end.  The Result
    (no checkpoint: its steps lie on no grid)."""
    plan, opts, recording, info = run.plan, run.opts, run.recording, run.info
    model, monitor, settings = plan.model, plan.monitor, plan.settings
    control = adaptive_steps.StepControl(opts.t_end, opts.rtol, opts.atol, opts.dt)
    most = min(run.size, adaptive_steps.SEGMENT)
    _, rec = run.records(1, None)       # (every step may end a segment)
    targets, t_end = opts.targets, control.t_end
    snapshot = adaptive_steps.Snapshot(plan.structures)
    t, taken, largest, most_newton, i_target = 0.0, 0, 0.0, 0, 0
    every_default = t_end / run_records.MAX_SAMPLES
    next_default = every_default
    bar = Progress(run_records.MAX_SAMPLES, opts.progress)
    try:
        while t < t_end:
            if targets is not None:
                while i_target < len(targets) and targets[i_target] <= t:
                    i_target += 1
            target = targets[i_target] if targets is not None and i_target < len(targets) \
                else t_end
            m, h = adaptive_steps.segment(t, control.h, target, most)
            snapshot.save()
            run_records._set_step(plan.loop, h, opts.coef)
            monitor.error[0] = 0.0
            times = t + np.arange(m + 1) * h
            lands = times[-1] >= target * (1 - 1e-12)
            if lands:
                times[-1] = target
            # a step above the tolerance stops the segment at once (the skeleton's own check)
            try:
                inputs = run.inputs_for(times, times[:-1] + 0.5 * h, h)
            except run_checks.UserFunctionError as err:
                raise run_checks.DivergenceError(taken + 1, err.t, str(err),
                                                 run.partial(taken)) from None
            run.run_chunk(inputs, rec, h, m + 1, taken, times[1],
                          min(settings.max_step_error, control.step_limit(h)))
            over = info[0] == ERROR_ESTIMATE and monitor.error[0] <= settings.max_step_error
            failed = (info[0] != OK and not over) or bool(
                run_checks._beam_beyond_its_length(model, plan.beam_tips, plan.state.eta))
            steps_run = m if info[0] == OK else int(info[1]) + 1
            if control.after(float(monitor.error[0]), h, steps_run, failed):
                t, taken = float(times[-1]), taken + m
                largest = max(largest, float(monitor.error[0]))
                most_newton = max(most_newton, int(info[2]))
                if (lands and targets is not None) or (targets is None and t >= next_default):
                    recording.add_state(taken, t)
                    while next_default <= t:
                        next_default += every_default
                bar.update(int(run_records.MAX_SAMPLES * t / t_end))
                continue
            cause = (f"local error estimate {monitor.error[0]:.3g} above the tolerance's "
                     f"{control.step_limit(h):.3g} for a step of {h:.3g} s" if over
                     else run_checks._failure_cause(model, plan.mode, info, monitor, settings)
                     if info[0] != OK else "a beam deflected beyond its length")
            snapshot.restore()
            if control.too_small:
                raise run.stopped(taken + 1, t, f"adaptive steps: the step fell below "
                                  f"{adaptive_steps.MIN_STEP:g} of t_end ({control.h:.3g} s) at "
                                  f"t = {t:.6g} s; last cause: {cause}", taken)
    finally:
        bar.close()
    if recording.times[-1] != t_end:           # the final state is always recorded
        recording.add_state(taken, t_end)
    run_info = dict(plan.run_info, dt=None, dt_min=control.h_min, dt_max=control.h_max,
                    segments_rejected=control.rejected, steps_rejected=control.rejected_steps,
                    rtol=opts.rtol, atol=opts.atol)
    return run_records._result(plan.user_model, recording, opts.dt, 0.0, taken,
                     dict(run_info, newton_iterations_used=most_newton,
                          newton_unconverged_steps=int(info[4]),
                          step_error_max=largest, **run_tables._loop_info(plan.loops)),
                     NoCheckpoint("an adaptive run (rtol=) keeps no checkpoint: its steps "
                                  "lie on no grid to continue on; run again to a later "
                                  "t_end, or use fixed steps (dt) to resume"))


def runge_kutta(run):
    """The high-order scheme (kernels/stepping/runge_kutta.py; docs/integrators.md): its compiled
    steps from t = 0 to t_end, each sample from the step's dense output (MAX_SAMPLES equally spaced
    by default; record_dt, t_eval), in chunks of samples; the Result (no checkpoint: its steps
    lie on no grid)."""
    plan, opts, recording, info = run.plan, run.opts, run.recording, run.info
    n = plan.model.n_bodies
    rk, loop, evaluation = plan.integrator, plan.derivative_loop, plan.derivative_run
    t_end = opts.t_end
    if not opts.adaptive:                       # fixed steps: at the steps asked for
        sampling = opts.sampling
        times = (np.arange(sampling, opts.n_steps + 1, sampling) if isinstance(sampling, int)
                 else sampling) * opts.dt
    else:
        times = (opts.targets if opts.targets is not None
                 else np.arange(1, run_records.MAX_SAMPLES + 1) * (t_end / run_records.MAX_SAMPLES))
    times = np.asarray(times, dtype=float)
    if not len(times) or times[-1] < t_end:     # (the final state is always recorded)
        times = np.append(times, t_end)
    times[-1] = t_end
    rtol = opts.rtol if opts.adaptive else 0.0      # (0: fixed steps of dt)
    atol = max(opts.atol, ATOL_FLOOR * rtol)        # (every scale > 0: a coordinate at 0)
    if not runge_kutta_kernels.start(loop, evaluation, info, rk, rtol, atol,
                                     opts.dt if opts.dt_given else 0.0, t_end):
        why = _PASS_FAILURES.get(int(info[0]), f"status {int(info[0])}")
        raise run_checks.DivergenceError(0, 0.0,
                                         f"{opts.scheme.name}: the sweep failed at the initial "
                                f"state ({why})")
    size = max(1, min(len(times),
                      run_records.CHUNK_BYTES // (run_records.CHUNK_STEP_BYTES * max(n, 1))))
    n_eta = len(plan.state.eta)
    rec = plan.chunk_arrays(("samples", size, n, n_eta), lambda: consistent_start._record(size, n,
                                                                                          n_eta))
    sample_steps = np.zeros(size, dtype=np.int64)
    h_min = adaptive_steps.MIN_STEP * t_end
    done = 0
    bar = Progress(len(times), opts.progress)
    try:
        while done < len(times):
            chunk = np.ascontiguousarray(times[done:done + size])
            runge_kutta_kernels.steps(loop, evaluation, info, rk, chunk, rec, sample_steps,
                                      rtol, atol, h_min)
            n_rec = int(info[3])
            if n_rec:
                recording.add({key: getattr(rec, key)[:n_rec] for key in plan.keys},
                              sample_steps[:n_rec].tolist(), chunk[:n_rec].tolist())
            done += n_rec
            if info[0] != OK:
                t, taken = float(rk.control[0]), int(rk.control[2])
                passing = _PASS_FAILURES.get(int(info[2]), "")
                cause = (f"the step fell below {adaptive_steps.MIN_STEP:g} of t_end "
                         f"({rk.control[1]:.3g} s) at t = {t:.6g} s"
                         + (f"; last cause: {passing}" if passing else "")
                         if info[0] == ERROR_ESTIMATE else
                         _PASS_FAILURES.get(int(info[0]), f"status {int(info[0])}"))
                raise run.stopped(taken + 1, t, f"{opts.scheme.name}: {cause}", taken)
            bar.update(done)
    finally:
        bar.close()
    control = rk.control
    run_info = dict(plan.run_info, evaluations=int(control[4]))
    if opts.adaptive:
        run_info.update(dt=None, dt_min=float(control[6]), dt_max=float(control[7]),
                        steps_rejected=int(control[3]), rtol=opts.rtol, atol=atol)
    return run_records._result(plan.user_model, recording, opts.dt, 0.0, int(control[2]),
                     dict(run_info, newton_iterations_used=0, newton_unconverged_steps=0),
                     NoCheckpoint(f"a {opts.scheme.name} run keeps no checkpoint: its steps "
                                  f"lie on no grid to continue on; run again to a later t_end, "
                                  f"or use fixed steps (dt) to resume"))


ATOL_FLOOR = 1e-6      # the high-order scheme's least atol, relative to rtol (atol = 0 given)
_PASS_FAILURES = {SINGULAR: "a transfer of the sweep is singular",
                  NOT_FINITE: "an acceleration is not finite",
                  UNSUPPORTED: "an element kind the loop does not know"}


def richardson(opts, simulate):
    """The Romberg extrapolation of opts.richardson runs at dt, dt/2, dt/4, ... on the even
    powers of the step (run_records.richardson_extrapolation; docs/solver.md, "Richardson
    extrapolation"): orders 4, 6, 8 from two, three, four runs, at the recorded times."""
    runs = []
    sampling, dt, n_steps = opts.sampling, opts.dt, opts.n_steps
    for level in range(opts.richardson):
        factor = 2 ** level             # (the same times: factor times the steps between)
        records = (dict(record_every=factor * sampling) if isinstance(sampling, int)
                   else dict(t_eval=np.concatenate([[0.0], sampling * dt])))
        h = dt / factor
        try:
            runs.append(simulate(opts.model, n_steps * dt, h, method=opts.method,
                                 scheme=opts.scheme.name, rho_inf=opts.rho_inf,
                                 newton_iterations=opts.newton_iterations,
                                 newton_tol=opts.newton_tol, **records,
                                 full_state=opts.full_state, progress=opts.progress,
                                 max_step_error=(None if opts.max_step_error == np.inf
                                                 else opts.max_step_error),
                                 hold_energy=opts.hold_energy))
        except run_checks.DivergenceError as err:
            raise run_checks.DivergenceError(err.step, err.t,
                                             f"in the Richardson run at dt = {h:g} "
                                    f"s: {err.cause}", err.partial) from None
    return run_records.richardson_extrapolation(*runs)
