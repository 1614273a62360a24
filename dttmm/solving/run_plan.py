"""A prepared run (issue 30's short runs, issue 31's reshape): everything a run of one model with
one set of options builds before its first step, built once.

PreparedRun holds the kernel model and its tables, the mode and the loop variant the method
table picks (methods.py), the run's preallocated arrays (state, sweep, loop, monitor: "the
structures", the only things the compiled loop writes besides a chunk's records) and their
values after the consistent start.  In a run that may be kept (below) the structures' arrays
are views of one flat buffer per dtype (float64, int64), so that putting the start back before
a run, or keeping a run's end for its checkpoint, is one copy of each buffer (a copy per array
would cost ~0.5 us each, of ~100); any other run steps the arrays as they were made.

A prepared run is kept on the model (per RunOptions.plan_key, at most KEEP of them) where its
start is a pure function of the model and the options (no Python function of the user's is
evaluated at t = 0: no applied loads, no moving ground, no drive but springs and compiled
forces) and its buffer is small (KEEP_BYTES); a run then starts from the kept start instead of
computing it.  Otherwise (and while another run uses the kept one, e.g. a drive that runs a
simulation) each run prepares its own, as before.
"""
import threading
from collections import OrderedDict

import numpy as np

from ..model import closures, loop_rows
from . import consistent_start, run_checks, run_inputs, run_tables
from ..model.loop_rows import has_closure_drives
from ..elements.drives import FORCE, MOTION, PD, SPRING_DAMPER, runs_in_loop
from ..kernels.stepping import ball_chain, em_step, runge_kutta, tree, weld_chain
from ..kernels.assembly import solve as ksolve
from ..kernels.stepping import step as kstep
from ..kernels.assembly.loop_projection import start_energy
from ..elements.kinds import BODY_KIND, DEFLECTING
from ..kernels.schema import FUSED_LAYOUT, MONITOR_LAYOUT
from ..kernels.stepping.loop import DirectCalls, Settings, run_steps
from .methods import SCHEMES
from ..model.model import model_fact
from ..results.recording import RecordLayout, leaves, model_fingerprint

KEEP = 8                    # prepared runs kept per model (the latest used)
KEEP_BYTES = 2 ** 24        # ... each of at most this much of arrays (a few thousand bodies)


def runs_fused(model, mode, scheme):
    """Whether a kernel model runs in a fused loop (kernels/stepping/ball_chain.py,
    kernels/stepping/tree.py): rigid bodies and beams between ball joints, Newmark or the high-order
    scheme."""
    return (run_tables.FUSED_BALL_CHAIN and mode in (ksolve.RICCATI_REDUCED, ksolve.RICCATI_TREE)
            and scheme.loop in ("newmark", "runge_kutta") and not model.needs_general_loop
            and all(BODY_KIND[int(c)].fused for c in model.body_kind))


def runs_welded(model, mode, scheme):
    """Whether a kernel model runs in the fused welded-chain loop (kernels/stepping/weld_chain.py):
    a chain of beams welded end to end from the ground (fixed hinges, a free tip), Newmark."""
    return (run_tables.FUSED_BALL_CHAIN and mode == ksolve.RICCATI_FULL and scheme.loop == "newmark"
            and model.is_chain and not model.tip_pinned and model.n_bodies > 0
            and all(int(c) == run_tables.BEAM for c in model.body_kind)
            and all(int(h) == run_tables.FIXED for h in model.hinge_kind)
            and not any(model.ground_locked[1:]))


def kernels_used(model, scheme, method="riccati", full_state=False):
    """The loop variant that runs a user's model with `scheme` (dttmm/solving/methods.py),
    `method` and `full_state` (describe(); simulate's BLAS threads: only the general and
    energy-momentum loops call LAPACK).  A fact of the model and the options, kept on it (a
    short run's fixed cost: ~6 us), per value of the switch that sends chains to the general
    loop (tests turn it)."""
    return _kernels_used(model, scheme.name, method, bool(full_state),
                         run_tables.FUSED_BALL_CHAIN)


@model_fact
def _kernels_used(model, scheme_name, method, full_state, fused_switch):
    scheme = SCHEMES[scheme_name]
    km, _ = run_tables.kernel_model(model)
    mode = run_tables._mode(km, method, full_state, scheme.loop == "runge_kutta")
    if runs_fused(km, mode, scheme):
        return "ball-tree" if mode == ksolve.RICCATI_TREE else "ball-chain"
    if scheme.loop == "energy_momentum":
        return "energy-momentum"
    if runs_welded(km, mode, scheme):
        return "welded-chain"
    return "general"


class PreparedRun:
    """The arrays and choices of a run of opts.model with opts' scheme, sweep, step and
    iterations, started (the consistent start taken) and ready to step.  Built by
    prepared_run; a kept one's run restores `started` (restart) before stepping."""

    def __init__(self, opts):
        scheme = opts.scheme
        user_model = opts.model
        model, keep = run_tables.kernel_model(user_model)
        self.scheme = scheme
        self.user_model, self.model, self.keep = user_model, model, keep
        self.loaded = run_tables.loaded_bodies(user_model, model,
                                               keep)  # where each body's loads act
        self.mode = mode = run_tables._mode(model, opts.method, opts.full_state,
                                            scheme.loop == "runge_kutta")
        dt, coef, n = opts.dt, opts.coef, model.n_bodies
        # the loop variant (kernels/stepping/loop.py): a fused one (kernels/stepping/ball_chain.py,
        # tree.py, weld_chain.py), the energy-momentum scheme's, or the general loop
        # (kernels/stepping/step.py); each records what its scheme defines
        fused = runs_fused(model, mode, scheme)
        if scheme.loop == "runge_kutta" and not fused:     # (check_supported refuses it)
            raise ValueError(f"simulate(scheme={scheme.name!r}): the model does not run in the "
                             f"fused ball-joint loops its stages take")
        ws = run_tables.Workspace(model, fused=fused)
        state = ws.state
        self.params = params = run_tables.kernel_params(model)
        self.settings = settings = Settings(
            mode=mode, h=dt, coef=coef, newton_max=int(opts.newton_iterations),
            newton_tol=opts.newton_tol, record_every=1, max_step_error=opts.max_step_error,
            stop_unconverged=scheme.stop_unconverged, start=False)
        monitor = MONITOR_LAYOUT.zeros(
            bodies=n, modes=len(state.eta),
            coordinate_bodies=n if run_tables.has_coordinates(model) else 0,
            elastic_bodies=n if np.isin(model.hinge_kind, DEFLECTING).any() else 0)
        welded = runs_welded(model, mode, scheme)
        loop = runner = None
        if fused and mode == ksolve.RICCATI_TREE:
            loop_name, runner = "ball-tree", run_steps
            loop = tree.fused_tree_loop(n, model.parent, model.mode_offsets, dt, coef)
        elif fused:
            loop_name, runner = "ball-chain", run_steps
            loop = ball_chain.fused_loop(n, model.mode_offsets, dt, coef)
        loops = run_tables.loop_tables(model)
        if welded:          # (its start: one pass of its own loop, then the loop from it)
            runner = run_steps
            loop = weld_chain.weld_loop(n, model.mode_offsets, dt, coef, state.z)
        consistent_start._consistent_start(
            model, mode, opts.method, (runner, loop) if fused or welded else None, params,
            settings, state, ws.sweep, monitor, dt, loops,
            in_skeleton=not (fused or welded or scheme.loop == "energy_momentum"))
        if opts.hold_energy:    # the total energy the steps hold (kernels/assembly/closure.py)
            loops.energy[:2] = 1.0, start_energy(params, loops, state)
        histories = run_tables._station_histories(model, state, scheme.name == "paper")
        state.z[:, 3:6] = 0.0          # from here on the phi slots hold rotation increments

        # the joints' offsets (an elastic hinge's deflection, a slide) where a joint has one
        # (they are zero otherwise: _result's zeros, 48 B per body and sample not kept)
        offsets = ["defl", "defl_rate"] if run_tables.has_offsets(model) else []
        keys = ["rot", "omega", "omega_dot", "z"] + offsets + ["eta", "eta_d"]
        if mode == ksolve.RICCATI_JOINTS:
            keys += ["jq", "jqd", "jtau"]
        if loops.rows:
            keys.append("closure_wrench")
        if scheme.loop == "energy_momentum":
            loop_name, runner = "energy-momentum", run_steps
            loop = em_step.energy_momentum_loop(n)
            state.v_c[:] = consistent_start.initial_mass_center_velocities(model, state.rot,
                                                                          state.omega)
        elif fused and scheme.loop == "runge_kutta":
            loop_name = f"runge-kutta ({loop_name})"
        elif fused:
            ball_chain.guess_from_stations(state.z, ws.sweep.red_aq)
        elif welded:
            loop_name, runner = "welded-chain", run_steps
            loop = weld_chain.weld_loop(n, model.mode_offsets, dt, coef, state.z)
        else:
            loop_name, runner = "general", run_steps
            loop = kstep.general_loop(n, len(state.eta), dt, coef, histories, loops,
                                      run_tables.compiled_forces(model).copy(),    # (the run's own)
                                      len(model.contacts))
        keys += list(scheme.records)
        self.keys, self.loop_name, self.runner, self.fused = keys, loop_name, runner, fused
        self.calls = _SameCalls()       # (its skeleton's calls: kernels/stepping/loop.py)
        self.run_info = dict(mode=run_tables._MODE_NAMES[mode], dt=dt, scheme=scheme.name,
                             loop=loop_name, model_fingerprint=model_fingerprint(user_model))
        if loops.rows:
            self.run_info.update(energy_held=bool(opts.hold_energy))
        if scheme.loads_at_midpoints:
            self.run_info.update(forces="step means (about t - dt/2)")
        elif scheme.damping:
            self.run_info.update(rho_inf=opts.rho_inf)
        self.checkpoint_run = dict(self.run_info, method=opts.method, bodies=n,
                                   newton_iterations=int(opts.newton_iterations))

        structures = (state, ws.sweep, loop, monitor)
        # a run that may be kept on the model (prepared_run): most arrays views of buffers, the
        # layout each leaf's place in them (None: not there); any other run's arrays stay as
        # they are (gathered, a million bodies' arrays would be held twice at once, and three
        # times with the start's copy: 3.5 GB at 10^6 bodies against 2 GB)
        movable = movable_arrays(structures)
        self.keepable = (start_is_pure(user_model)
                         and sum(a.nbytes for a in movable.values()) <= KEEP_BYTES)
        self.buffers, self.layout, self.others, self.started = [], None, None, None
        if self.keepable:
            self.buffers, structures, self.layout, self.others = kept_arrays(structures, movable)
            # (the start's values, which restart puts back)
            self.started = copies_of(self.buffers, self.others)
        self.state, self.sweep, self.loop, self.monitor = self.structures = structures
        self.loops = self.loop.loops if loop_name == "general" else loops
        v_st, c_v = ((self.loop.scratch.st_v, self.loop.scratch.c_v) if loop_name == "general"
                     else (histories[1], histories[4]))
        self.history_values = dict(v_st=v_st,
                                   v_c=self.state.v_c if scheme.name != "paper" else c_v,
                                   closure_wrench=self.loops.wrench)
        if scheme.loop == "runge_kutta":     # its stages: the fused loop's start pass
            self.derivative_run = consistent_start.start_pass(  # (fixed ground, no loads or
                params, settings, self.state, self.sweep, self.monitor,  # drives: check_supported)
                run_inputs._ground(model, [0.0]), run_inputs._loads(model, [0.0]),
                run_inputs._joint_inputs(model, [0.0]), loops.rows)
            self.derivative_loop = FUSED_LAYOUT.copy(self.loop)    # (its stages' own scratch)
            ball_chain.start_loop(self.derivative_loop, self.state, self.sweep)
            self.integrator = runge_kutta.runge_kutta_scratch(
                n, len(self.state.eta), runge_kutta.dop853_tables(),
                int(np.count_nonzero(model.hinge_kind == run_tables.FREE)))
        self.beam_tips = run_checks._beam_tips(model)
        self.start_fastest = run_checks._fastest_rate(self.state.omega[None])  # (drivers)
        self.closing_forces = loop_rows.closure_forces(model, self.loops)
        # what each run's chunks evaluate in Python (drivers.Stepping.inputs_for): JointForces
        # of the state given as Python functions (one step per chunk), the drives' and the
        # driven closing joints' inputs, the applied loads
        self.stepwise = [f"joint '{model.hinge_names[k]}'" for k, ds in enumerate(model.drives)
                         for d in ds if not runs_in_loop(d)] + [
                             who for _, _, who in self.closing_forces]
        self.joint_inputs_vary = any(d is not None and d["kind"] in (FORCE, MOTION, PD)
                                     for ds in model.drives for d in ds)
        self.targets_vary = has_closure_drives(model)
        self.has_loads = model.has_applied_loads
        # every kernel body is one of the model's, in order (an end section or offset that
        # the kernel model adds last leaves keep = 0 .. n - 1 with more kernel bodies)
        self.keeps_every_body = bool(len(keep) == model.n_bodies
                                     and np.array_equal(keep, np.arange(len(keep))))
        # what its runs record, and the arrays a sample of the state reads (recording.py);
        # a chunk's record's shape but its rows (consistent_start._record)
        self.record_shape = (n, len(self.state.eta), scheme.name == "paper", "v_c" in keys,
                             self.loops.wrench.shape[0] if "closure_wrench" in keys else 0)
        self.record_layout = RecordLayout(keys, keep, self.keeps_every_body, self.state,
                                          self.history_values)
        self.lock = threading.Lock()
        self.kept = False               # kept on the model (prepared_run)
        self._chunk_arrays = {}         # the chunks' input and record arrays, by their shape

    def restart(self):
        """Put the structures back to their values after the start (a kept prepared run,
        before each run)."""
        put_back(self.buffers, self.others, self.started)

    def ending(self):
        """The structures' arrays as a run left them, for its checkpoint: a kept run's copy
        (the next run reuses its arrays), gathered when first read; a run of its own's
        arrays themselves (a million bodies' state is not doubled)."""
        if not self.kept:
            return self.structures
        return _Ending(self, [b.copy() if b.size else b for b in self.buffers],  # (an empty
                       [a.copy() for a in self.others])         # buffer holds no leaf's values)

    def chunk_arrays(self, key, make):
        """Arrays of a chunk (its inputs known before the run, its records) that a kept run's
        next call can reuse: make() once per key (their shape).  The compiled loop writes the
        records, which the Recording copies out, and reads the inputs."""
        if not self.kept:
            return make()
        if key not in self._chunk_arrays:
            if len(self._chunk_arrays) >= KEEP_CHUNK_ARRAYS:    # (many run lengths or steps:
                self._chunk_arrays.clear()                      # the latest kept, not all)
            self._chunk_arrays[key] = make()
        return self._chunk_arrays[key]


KEEP_CHUNK_ARRAYS = 64  # a kept run's chunk arrays and settings kept (chunk_arrays)


class _SameCalls(DirectCalls):
    """A prepared run's DirectCalls (kernels/stepping/loop.py), which skip fingerprinting a call
    whose varying parts are the very objects of the call before: a kept run's next run of the
    same length steps with the same settings, inputs, record and info arrays (chunk_arrays), and
    their types cannot have changed (named tuples are immutable; an array's dtype, dimensions
    and layout are its own for life, and nothing makes these read-only), so that call's entry
    point is this one's.  Fingerprinting their ~30 fields cost a short run ~4 us."""

    def __init__(self):
        super().__init__()
        self.same = None        # (skeleton, settings, inputs, record, info) of self.key's call

    def __call__(self, compiled, args):
        _, run, out_info = args
        same = (compiled, run.settings, run.inputs, run.rec, out_info)
        if self.entry is not None and self.same is not None and all(
                a is b for a, b in zip(same, self.same)):
            self.entry(*args)
            return
        super().__call__(compiled, args)
        self.same = same


GATHERED = (np.float64, np.int64)      # the dtypes gathered into buffers (gathered)


def _root(a):
    while isinstance(a.base, np.ndarray):
        a = a.base
    return a


def movable_arrays(structures):
    """{id: array} of the arrays in the nested tuples that gathered moves into its buffers:
    every C-contiguous array of a GATHERED dtype whose memory no other leaf shares (an array
    that appears twice, once)."""
    arrays = leaves(structures)
    roots = [id(_root(a)) for a in arrays]
    sharing = {}
    for a, root in zip(arrays, roots):
        sharing.setdefault(root, set()).add(id(a))
    return {id(a): a for a, root in zip(arrays, roots)
            if a.dtype in GATHERED and a.flags.c_contiguous and a.size
            and len(sharing[root]) == 1}


def gathered(structures, movable):
    """(buffers, structures, layout): every array of movable (movable_arrays') replaced by a view
    of one flat buffer per dtype holding its values; layout: each leaf's (buffer, offset,
    shape) in the new structures' leaf order, None for a leaf left as it is."""
    arrays = leaves(structures)
    buffers, places = [], {}
    for i, dtype in enumerate(GATHERED):
        parts = [(key, a) for key, a in movable.items() if a.dtype == dtype]
        buffer = np.empty(sum(a.size for _, a in parts), dtype=dtype)
        at = 0
        for key, a in parts:
            buffer[at:at + a.size] = a.reshape(-1)
            places[key] = (i, at, a.shape)
            at += a.size
        buffers.append(buffer)

    def view(a):
        i, at, shape = places[id(a)]
        return buffers[i][at:at + a.size].reshape(shape)
    views = {key: view(a) for key, a in movable.items()}

    def rebuilt(part):
        if isinstance(part, np.ndarray):
            return views.get(id(part), part)
        if isinstance(part, tuple):
            items = [rebuilt(p) for p in part]
            return type(part)(*items) if hasattr(part, "_fields") else tuple(items)
        return part
    return buffers, rebuilt(structures), [places.get(id(a)) for a in arrays]


def kept_arrays(structures, movable):
    """(buffers, structures, layout, others): gathered's, and the leaves with values left out
    of its buffers (an array another leaf shares, a strided one), which a restart copies one
    by one (put_back)."""
    buffers, structures, layout = gathered(structures, movable)
    others = [a for a, place in zip(leaves(structures), layout) if place is None and a.size]
    return buffers, structures, layout, others


def copies_of(buffers, others):
    """The values of kept_arrays' buffers and other arrays, as put_back takes them."""
    return [b.copy() for b in buffers], [a.copy() for a in others]


def put_back(buffers, others, values):
    """The buffers and other arrays set to values (copies_of's)."""
    buffer_values, other_values = values
    for buffer, value in zip(buffers, buffer_values):
        if buffer.size:             # (a model without integer arrays: an empty buffer)
            buffer[:] = value
    for a, value in zip(others, other_values):
        np.copyto(a, value)


class _Ending:
    """A kept run's arrays as one run left them (PreparedRun.ending): copies of its buffers
    and other arrays, the arrays themselves made when called; pickled as those arrays."""

    def __init__(self, plan, copies, other_copies):
        self.plan, self.copies, self.other_copies = plan, copies, other_copies

    def __call__(self):
        """The leaves of the plan's structures as they were: a gathered array the same view
        of its buffer's copy, another its copy, an empty one a new empty array."""
        others = iter(self.other_copies)
        return [self.copies[place[0]][place[1]:place[1] + a.size].reshape(place[2])
                if place is not None else next(others) if a.size else np.empty_like(a)
                for a, place in zip(leaves(self.plan.structures), self.plan.layout)]

    def __reduce__(self):
        return tuple, (tuple(self()),)


def forget(model):
    """Drop the prepared runs kept on a model (a test that changes how a model runs)."""
    model.__dict__.pop("_prepared_runs", None)


@model_fact
def start_is_pure(model):
    """Whether a run's consistent start is a function of the model alone: no Python function
    of the user's is evaluated at t = 0 (applied loads, a moving ground, drives but springs
    and compiled forces, driven closing joints)."""
    if model.ground_motion is not None or model.has_applied_loads or has_closure_drives(model):
        return False
    return all(d is None or d["kind"] == SPRING_DAMPER or d.get("compiled")
               for ds in model.drives for d in ds)


_KEPT_LOCK = threading.Lock()


class prepared_run:
    """with prepared_run(opts) as plan: the prepared run of opts, restarted: the one kept on the
    model for opts' plan_key where there is one free (start_is_pure, KEEP_BYTES), else a new
    one (kept where it may be); a kept one is held (its lock) until the block ends.  (A class
    rather than a generator: a short run's fixed cost.)"""

    __slots__ = ("opts", "plan", "held")

    def __init__(self, opts):
        self.opts, self.plan, self.held = opts, None, False

    def __enter__(self):
        opts = self.opts
        model = opts.model
        key = opts.plan_key + (run_tables.FUSED_BALL_CHAIN, closures.PINNED_TIP_SWEEP)  # (switches
        #                                                                   that tests turn)
        pure = start_is_pure(model)
        if pure:
            with _KEPT_LOCK:
                kept = model.__dict__.get("_prepared_runs")
                if kept is None:
                    kept = OrderedDict()
                    object.__setattr__(model, "_prepared_runs", kept)
                plan = kept.get(key)
                if plan is not None:
                    kept.move_to_end(key)
            if plan is not None and plan.lock.acquire(blocking=False):
                self.plan, self.held = plan, True
                try:
                    plan.restart()
                except BaseException:
                    self.__exit__(None, None, None)
                    raise
                return plan
        plan = PreparedRun(opts)
        if plan.keepable:
            with _KEPT_LOCK:
                kept = model.__dict__["_prepared_runs"]
                if key not in kept:
                    plan.kept = True
                    kept[key] = plan
                    while len(kept) > KEEP:
                        kept.popitem(last=False)
        if plan.kept:
            plan.lock.acquire()
            self.held = True
        self.plan = plan
        return plan

    def __exit__(self, *exc):
        if self.held:
            self.held = False
            self.plan.lock.release()
        return False
