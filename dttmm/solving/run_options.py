"""simulate's arguments, checked once (RunOptions): every bad argument is refused here, naming
it, before anything is built or run.  The defaults that depend on the model (Newton iterations,
whether the energy is held) are decided here too, so that drivers and prepared runs read one
record of what the run is."""
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from . import adaptive as adaptive_steps
from ..model import closures
from . import consistent_start, run_checks, run_records, run_tables
from .methods import SWEEPS, scheme_named
from ..model.model import Model
from ..results.recording import Checkpoint, NoCheckpoint


MAX_STEPS = 10 ** 12    # more steps than this in one run is a unit mistake, not a plan
MAX_LEVELS = 4          # richardson's most runs (h, h/2, h/4, h/8: order 8)


@dataclass(frozen=True)
class RunOptions:
    """One simulate call's arguments, checked (simulate's docstring says what each means)."""
    model: Model                # the user's model (closed where it has loops: run_checks._closed)
    t_end: float
    dt: float                   # the step (an adaptive run's first step)
    dt_given: bool              # dt given (not an adaptive run's default first step)
    n_steps: int                # fixed steps: ceil(t_end / dt), dt = t_end / n_steps
    scheme: object              # methods.Scheme
    method: str                 # methods.SWEEPS
    rho_inf: float
    coef: np.ndarray = field(repr=False)   # generalized-alpha coefficients (run_tables.Integrator)
    newton_iterations: int = 0
    newton_tol: float = 1e-12
    full_state: bool = False
    max_step_error: float = np.inf
    max_energy_error: object = None
    hold_energy: bool = False   # resolved: held or not
    richardson: int = 1         # the runs extrapolated from (1: none; 2: richardson=True)
    rtol: object = None         # adaptive steps where given
    atol: float = 0.0
    sampling: object = 1        # fixed steps: every k-th step (int) or these steps (array)
    targets: object = None      # adaptive: the times it lands on and records (None: default)
    progress: object = None
    resume: object = None
    stream: object = None

    @property
    def adaptive(self):
        return self.rtol is not None

    @cached_property
    def plan_key(self):
        """What a prepared run depends on (run_plan.py): the options that shape its arrays,
        its loop variant and its start, not the run's length, records or output."""
        return (self.dt, self.scheme.name, self.method, self.rho_inf, self.newton_iterations,
                self.newton_tol, bool(self.full_state), self.max_step_error,
                bool(self.hold_energy))


_PLAIN = frozenset((int, float, str, bool, type(None)))  # arguments whose checked options are
#                                                         kept
KEEP_OPTIONS = 32       # checked options kept per model (the latest calls' arguments)


def run_options(model, t_end, dt, *, rtol, atol, method, scheme, rho_inf, newton_iterations,
                newton_tol, record_every, record_dt, t_eval, full_state, richardson, progress,
                max_step_error, max_energy_error, hold_energy, resume, stream):
    """simulate's arguments checked (RunOptions): a call with the same plain arguments (numbers,
    strings, None; their types too: True is not 1) as one of the model's latest returns that
    call's options, unchecked again (a short run's fixed cost); any other is checked
    (_checked)."""
    args = (t_end, dt, rtol, atol, method, scheme, rho_inf, newton_iterations, newton_tol,
            record_every, record_dt, full_state, richardson, progress, max_step_error,
            max_energy_error, hold_energy)
    types = tuple(map(type, args))
    plain = (isinstance(model, Model) and t_eval is None and resume is None and stream is None
             and _PLAIN.issuperset(types))
    if plain:
        key = args + types + (closures.PINNED_TIP_SWEEP,)  # (a switch of
        #                                                                   how loops run)
        kept = model.__dict__.get("_run_options")
        if kept is not None and key in kept:
            return kept[key]
    opts = _checked(model, t_end, dt, rtol=rtol, atol=atol, method=method, scheme=scheme,
                    rho_inf=rho_inf, newton_iterations=newton_iterations, newton_tol=newton_tol,
                    record_every=record_every, record_dt=record_dt, t_eval=t_eval,
                    full_state=full_state, richardson=richardson, progress=progress,
                    max_step_error=max_step_error, max_energy_error=max_energy_error,
                    hold_energy=hold_energy, resume=resume, stream=stream)
    if plain:
        kept = model.__dict__.get("_run_options")
        if kept is None or len(kept) >= KEEP_OPTIONS:
            kept = {}
            object.__setattr__(model, "_run_options", kept)    # (a frozen Model)
        kept[key] = opts
    return opts


def _checked(model, t_end, dt, *, rtol, atol, method, scheme, rho_inf, newton_iterations,
             newton_tol, record_every, record_dt, t_eval, full_state, richardson, progress,
             max_step_error, max_energy_error, hold_energy, resume, stream):
    """simulate's arguments checked, in the order simulate documents them (RunOptions)."""
    if not isinstance(model, Model):
        raise ValueError("simulate: model must be a Model (see dttmm.build_chain)")
    if run_tables.has_loops(model):
        model = run_checks._closed(model)
    t_end = run_checks._check_positive("t_end", t_end)
    scheme = scheme_named(scheme)
    adaptive = rtol is not None
    if adaptive:
        rtol, atol = run_checks._check_positive("rtol", rtol), float(atol)
        if not atol >= 0.0:
            raise ValueError(f"simulate: atol must be >= 0 (rad or m), got {atol!r}")
        for name, given, why in (("max_energy_error", max_energy_error is not None, "it is "
                                  "checked at fixed steps"),
                                 ("record_every", record_every is not None, "use record_dt or "
                                  "t_eval"), ("resume", resume is not None, "resume a fixed-step "
                                  "run"), ("richardson", richardson, "the extrapolation needs "
                                  "fixed steps"), ("scheme", not scheme.adaptive, "the scheme "
                                  "has no error estimate; use scheme='newmark' or 'dop853'")):
            if given:
                raise ValueError(f"simulate: adaptive steps (rtol) and {name} do not combine: "
                                 f"{why}")
        dt_given = dt is not None
        dt = t_end / run_records.MAX_SAMPLES if dt is None else dt
    elif dt is None:
        raise ValueError("simulate: give the step dt (s), or rtol for adaptive steps")
    else:
        dt_given = True
    dt = run_checks._check_positive("dt", dt)
    if t_end / dt > MAX_STEPS:
        raise ValueError(f"simulate: dt = {dt:g} s makes {t_end / dt:.3g} steps of t_end = "
                         f"{t_end:g} s (more than {MAX_STEPS:.0e}): dt is in seconds")
    n_steps, dt = consistent_start._steps(t_end, dt)
    if isinstance(resume, NoCheckpoint):
        raise ValueError(f"simulate(resume=...): {resume.why}")
    if resume is not None:
        if not isinstance(resume, Checkpoint):
            raise ValueError(f"simulate: resume must be a Checkpoint (result.checkpoint or "
                             f"dttmm.Checkpoint.load(path)), got {type(resume).__name__}")
        if richardson:
            raise ValueError("simulate: resume and richardson=True do not combine (the "
                             "extrapolation needs both runs from t = 0)")
        if abs(dt - resume.h) > 1e-12 * resume.h:
            raise ValueError(f"simulate(resume=...): the checkpoint's runs step dt = "
                             f"{resume.h:.17g} s; this run steps {dt:.17g} s (t_end = {t_end:g} s "
                             f"in steps of dt): resume with the same dt and a t_end on its grid")
        if resume.step >= n_steps:
            raise ValueError(f"simulate(resume=...): t_end = {t_end:g} s is not after the "
                             f"checkpoint's t = {resume.t:g} s")
    if adaptive:        # the times it lands on, or the steps it records (besides its ends)
        sampling, targets = 1, adaptive_steps.sample_times(t_end, record_dt, t_eval)
    else:
        sampling, targets = run_records._sampling(n_steps, dt, record_every, record_dt, t_eval,
                                      0 if resume is None else resume.step, model.n_bodies), None
    if newton_iterations is None:
        newton_iterations = (scheme.newton_iterations if scheme.newton_iterations is not None
                             else 16 if run_tables.has_loops(model)
                             else 8 if run_checks._iterates(model, full_state) else 0)
    newton_iterations = run_checks._check_count("newton_iterations", newton_iterations, 0)
    try:
        newton_tol = float(newton_tol)
    except (TypeError, ValueError):
        newton_tol = np.nan
    if not (np.isfinite(newton_tol) and newton_tol >= 0.0):
        raise ValueError(f"simulate: newton_tol must be a finite number >= 0 (rad or m), got "
                         f"{newton_tol!r}")
    coef = run_tables.Integrator.from_rho_inf(rho_inf).array()     # (checked here, before any run)
    if not scheme.damping and float(rho_inf) != 1.0:
        raise ValueError(f"simulate: scheme={scheme.name!r} takes no numerical damping: "
                         f"rho_inf must be 1, got {rho_inf!r}")
    if not isinstance(full_state, (bool, np.bool_)):
        raise ValueError(f"simulate: full_state must be True or False, got {full_state!r}")
    if isinstance(richardson, (bool, np.bool_)):
        richardson = 2 if richardson else 1         # (True: two runs, order 4)
    elif not (isinstance(richardson, (int, np.integer)) and 1 <= richardson <= MAX_LEVELS):
        raise ValueError(f"simulate: richardson must be True, False or the number of runs "
                         f"to extrapolate from, 1 to {MAX_LEVELS} (orders 2, 4, 6, 8), got "
                         f"{richardson!r}")
    richardson = int(richardson)
    max_step_error = (np.inf if max_step_error is None
                      else run_checks._check_positive("max_step_error", max_step_error))
    if hold_energy not in (None, True, False):
        raise ValueError(f"simulate: hold_energy must be None, True or False, got "
                         f"{hold_energy!r}")
    why_not_held = run_checks.energy_not_held(model, rho_inf)
    if hold_energy and why_not_held:
        raise ValueError(f"simulate: hold_energy=True, but the loops' projection cannot hold "
                         f"this model's energy: {why_not_held} (docs/loops.md, \"The energy "
                         f"held\"); leave hold_energy unset")
    hold_energy = why_not_held is None and hold_energy is not False
    if max_energy_error is not None:
        max_energy_error = run_checks._check_positive("max_energy_error", max_energy_error)
        if len(model.contacts):
            raise ValueError("simulate: max_energy_error: the energy balance does not count "
                             "the work of contacts yet (docs/contact.md); leave it unset for a "
                             "model with shapes")
    if richardson > 1:
        for name, value in (("stream", stream), ("max_energy_error", max_energy_error)):
            if value is not None:
                raise ValueError(f"simulate: richardson=True and {name} do not combine (the "
                                 f"result is the extrapolation of two runs, not one run's "
                                 f"samples or energy); run without richardson for {name}")
        if not scheme.richardson:
            raise ValueError(f"simulate: richardson=True needs scheme='newmark' (the "
                             f"{scheme.name!r} scheme's properties would not survive the "
                             f"extrapolation), got scheme={scheme.name!r}")
    if method not in SWEEPS:
        raise ValueError(f"simulate: method must be one of {tuple(SWEEPS)}, got {method!r}")
    return RunOptions(model=model, t_end=t_end, dt=dt, dt_given=dt_given, n_steps=n_steps,
                      scheme=scheme, method=method, rho_inf=float(rho_inf), coef=coef,
                      newton_iterations=newton_iterations, newton_tol=newton_tol,
                      full_state=bool(full_state), max_step_error=max_step_error,
                      max_energy_error=max_energy_error, hold_energy=hold_energy,
                      richardson=richardson, rtol=rtol, atol=float(atol),
                      sampling=sampling, targets=targets,
                      progress=progress, resume=resume, stream=stream)
