"""DT-TMM's accelerations of any state at any time: the consistent start's O(N) sweep at
acceleration level (docs/solver.md, "Consistent start"; with closing joints, docs/loops.md,
"The sweep with closing joints"), as a function of the state for users and checks (docs/
dynamics.md).
"""
import threading

import numpy as np

from ..elements.kinds import (CHILD, COORDINATE_0, FLEXIBLE, MAX_COORDINATES, RATE_0, SLIDE,
                              TURN, WITH_COORDINATES, coordinates_of, row_axes)

# the state forward_dynamics takes, as Result records it (one sample), and the kernel state's
# field each is written to; deflection and deflection_rate: elastic hinges' (world, m, m/s)
STATE_KEYS = ("rotation", "angular_velocity", "joint_coordinates", "joint_rates",
              "modal_coordinates", "modal_velocities", "deflection", "deflection_rate")


def forward_dynamics(model, t=0.0, state=None):
    """The accelerations of a state at time t, by DT-TMM's O(N) sweep at acceleration level
    (the step's own linearization taken at zero step: the consistent start).

    Parameters
    ----------
    model : Model
        Any model ``simulate`` runs with the Newmark scheme (trees, beams, joints with
        coordinates and drives, elastic hinges, closed loops on a fixed ground).
    t : float
        The time, s: the ground's motion, the applied loads and the drives are taken at t.
    state : mapping, optional
        The state, as a Result records it at one sample (``result.state(i)``): ``rotation``
        (n, 3, 3), ``angular_velocity`` (n, 3, rad/s), ``joint_coordinates``, ``joint_rates``
        (total coordinates, Result's order), ``modal_coordinates``, ``modal_velocities``
        (total modes), ``deflection``, ``deflection_rate`` (n, 3: elastic hinges', world,
        m and m/s). A key left out keeps the model's initial state. A joint's child frame
        follows its parent's and the joint's coordinates (a welded body its parent's): given,
        it must agree with them (to 1e-9). With closed loops the state must close them
        (as a Result's samples do).

    Returns
    -------
    dict
        ``angular_acceleration`` (n, 3, rad/s^2), ``input_acceleration`` (n, 3, m/s^2, each
        body's input point), ``joint_acceleration`` (total coordinates, as Result's
        joint_coordinates), ``modal_acceleration`` (total modes), ``deflection_acceleration``
        (n, 3: elastic hinges', world), ``rotation`` and ``angular_velocity`` (the state's,
        every frame that follows its parent's rebuilt), ``force``, ``moment`` (n, 3:
        what the inboard side exerts on each body at its input point, N and N m about it, as
        Result's), ``multipliers`` (the closing joints' rows, R) and ``residual`` (R: the rows'
        accelerations after the solve, m/s^2 or rad/s^2).

    Raises
    ------
    ValueError
        A model the Newmark loops do not run, a state of the wrong shape, not finite, or whose
        joint children's frames do not follow their joints' coordinates.
    """
    from ..model.model import Model
    if not isinstance(model, Model):
        raise ValueError(f"forward_dynamics: model must be a Model, got {type(model).__name__}")
    t = float(t)
    if not np.isfinite(t):
        raise ValueError(f"forward_dynamics: t must be a finite time (s), got {t!r}")
    return _accelerations(model, t, state, True)


def _accelerations(model, t, state, check_frames, extra_loads=None, extra_joint_forces=None):
    """forward_dynamics' work; check_frames: refuse given rotations of bodies whose frames
    follow their parents' that do not agree with them (dttmm.ode gives placeholders there);
    extra_loads: (force, torque) (n, 3) each on the model's bodies, added to its loads;
    extra_joint_forces: (n, 3) generalized forces on the joints' coordinates (where
    run_inputs.additive_joint_force)."""
    from . import consistent_start, run_inputs, run_tables
    from ..kernels import python_twin
    from ..kernels.assembly.closure import row_residuals, set_ground
    from ..kernels.assembly.loop_projection import _dependent_frames
    with _evaluation(model) as work:
        km, keep, mode, settings, params, columns = (work.km, work.keep, work.mode,
                                                     work.settings, work.params, work.columns)
        ws, loops, monitor, n = work, work.loops, work.monitor, km.n_bodies
        if state is not None:
            _set_state(model, km, keep, columns, ws.state, state, check_frames)
            _, g_rot, g_w, g_wd, g_pos, g_vel = run_inputs._ground(km, [t])
            set_ground(loops, g_pos[0], g_vel[0], np.zeros(3), g_rot[0], g_w[0], g_wd[0])
            given = (ws.state.rot[keep].copy(), ws.state.omega[keep].copy()) if check_frames else ()
            # (the kernels' callee, called here through its twin, kernels/__init__.py::python_twin)
            frames = python_twin(_dependent_frames)
            frames(params, loops, ws.state, np.arange(n, dtype=np.int64), np.zeros(60))
            for key, rebuilt, value in zip(("rotation", "angular_velocity"),
                                           (ws.state.rot[keep], ws.state.omega[keep]), given):
                off = np.abs(rebuilt - value).reshape(len(keep), -1).max(axis=1)
                if key in state and off.max() > 1e-9 * max(1.0, np.abs(value).max()):
                    k = int(np.argmax(off))
                    raise ValueError(f"forward_dynamics: the state's {key} of body "
                                     f"'{model.body_names[k]}' is {off[k]:.3g} off what its joint "
                                     f"'{model.hinge_names[k]}' and its parent give (a joint's "
                                     f"child follows its parent and the joint's coordinates)")
        if extra_loads is not None:         # onto the kernel bodies that carry each body's loads
            extra = np.zeros((2, n, 3))
            extra[:, run_tables.loaded_bodies(model, km, keep)] = extra_loads
            extra_loads = extra
        if extra_joint_forces is not None:
            extra = np.zeros((n, MAX_COORDINATES))
            extra[keep] = extra_joint_forces
            extra_joint_forces = extra
        consistent_start._consistent_start(km, mode, "riccati", None, params, settings, ws.state,
                                           ws.sweep, monitor, 0.0, loops, t=t,
                                           extra_loads=extra_loads,
                                           extra_joint_forces=extra_joint_forces, in_skeleton=True)
        st = ws.state
        residual = np.zeros(loops.rows)
        if loops.rows:
            row_residuals(loops, st.z, residual)
        inputs = 2 * keep + 1
        return {"angular_acceleration": st.z[inputs, 3:6].copy(),
                "input_acceleration": st.z[inputs, 0:3].copy(),
                "joint_acceleration": np.array([st.jqdd[keep[k], i] for k, i in columns]),
                "modal_acceleration": st.eta_acc.copy(),
                "deflection_acceleration": st.defl_acc[keep].copy(),
                "rotation": st.rot[keep].copy(), "angular_velocity": st.omega[keep].copy(),
                "offsets": (st.defl[keep].copy(), st.defl_rate[keep].copy()),
                "force": st.z[inputs, 9:12].copy(), "moment": st.z[inputs, 6:9].copy(),
                "multipliers": loops.lam.copy(), "residual": residual}


class _Evaluation:
    """forward_dynamics' workspace of one model (_evaluation): the kernel model and its tables,
    and the state, sweep, loops and monitor of a fresh Workspace, loop_tables and Monitor, their
    arrays gathered into flat buffers (run_plan.kept_arrays, as a kept prepared run's) that
    restart() puts back to those fresh values, so that a call computes what it would on new
    ones (a call of dttmm.ode's right-hand side, linearize's differences)."""

    def __init__(self, model):
        from . import run_checks, run_tables
        from .run_plan import copies_of, kept_arrays, movable_arrays
        from ..model.closures import check_runs_in_sweeps
        from ..kernels.schema import MONITOR_LAYOUT
        from ..kernels.stepping.loop import Settings
        if model.n_closures and not model.tip_pinned:
            check_runs_in_sweeps(model, "forward_dynamics", moving_ground=True)
        run_checks.check_supported(model, "newmark", "riccati", True)
        km, keep = run_tables.kernel_model(model)
        self.km, self.keep = km, keep
        self.mode = run_tables._mode(km, "riccati", True)
        self.settings = Settings(mode=self.mode, h=1.0,
                                 coef=run_tables.Integrator.from_rho_inf(1.0).array(),
                                 newton_max=0, newton_tol=0.0, record_every=1,
                                 max_step_error=np.inf, stop_unconverged=False, start=False)
        n = km.n_bodies
        monitor = MONITOR_LAYOUT.zeros(bodies=n, modes=int(km.n_modes.sum()),
                                       coordinate_bodies=n, elastic_bodies=0)
        ws = run_tables.Workspace(km)
        self.params = run_tables.kernel_params(km)
        self.columns = run_tables.coordinate_columns(model)
        structures = (ws.state, ws.sweep, run_tables.loop_tables(km), monitor)
        self.buffers, structures, _, self.others = kept_arrays(structures,
                                                               movable_arrays(structures))
        self.state, self.sweep, self.loops, self.monitor = structures
        self.fresh = copies_of(self.buffers, self.others)
        self.lock = threading.Lock()

    def restart(self):
        """Every array back to its fresh value."""
        from .run_plan import put_back
        put_back(self.buffers, self.others, self.fresh)


class _evaluation:
    """with _evaluation(model) as work: the model's kept _Evaluation, restarted, where it is free
    (held until the block ends), else a new one (another thread's call)."""

    __slots__ = ("model", "work")

    def __init__(self, model):
        self.model, self.work = model, None

    def __enter__(self):
        from ..model import closures
        from . import run_tables
        key = (closures.PINNED_TIP_SWEEP, run_tables.BANDED_ROWS)     # (switches tests turn)
        with _KEPT_LOCK:
            kept = self.model.__dict__.get("_evaluation")
            if kept is None or kept[0] != key:
                kept = (key, _Evaluation(self.model))
                object.__setattr__(self.model, "_evaluation", kept)   # (a frozen Model)
        work = kept[1]
        if work.lock.acquire(blocking=False):
            self.work = work
            work.restart()
            return work
        return _Evaluation(self.model)

    def __exit__(self, *exc):
        if self.work is not None:
            self.work.lock.release()
            self.work = None
        return False


_KEPT_LOCK = threading.Lock()


def _set_state(model, km, keep, columns, kernel_state, state, check=True):
    """Write the given state (forward_dynamics' mapping) into the kernel model's state; check:
    that each rotation is one (dttmm.ode's are, by construction)."""
    unknown = sorted(set(state) - set(STATE_KEYS))
    if unknown:
        raise ValueError(f"forward_dynamics: the state has no {unknown[0]!r}; its keys are "
                         f"{', '.join(STATE_KEYS)}")
    n, n_eta = model.n_bodies, int(km.n_modes.sum())
    shapes = {"rotation": (n, 3, 3), "angular_velocity": (n, 3), "deflection": (n, 3),
              "deflection_rate": (n, 3), "joint_coordinates": (len(columns),),
              "joint_rates": (len(columns),), "modal_coordinates": (n_eta,),
              "modal_velocities": (n_eta,)}
    values = {}
    for key, value in state.items():
        if value is None:
            continue
        value = np.asarray(value, dtype=float)
        if value.shape != shapes[key]:
            raise ValueError(f"forward_dynamics: state[{key!r}] must have shape "
                             f"{shapes[key]}, got {value.shape}")
        if not np.all(np.isfinite(value)):
            raise ValueError(f"forward_dynamics: state[{key!r}] is not finite")
        if key == "rotation" and check:
            error = np.abs(np.einsum("kji,kjl->kil", value, value) - np.eye(3)).max(axis=(1, 2))
            if error.max() > 1e-9:
                k = int(np.argmax(error))
                raise ValueError(f"forward_dynamics: state['rotation'][{k}] (body "
                                 f"'{model.body_names[k]}') is not a rotation: R^T R is "
                                 f"{error[k]:.3g} off the identity")
        values[key] = value
    for key, field in (("rotation", "rot"), ("angular_velocity", "omega"),
                       ("deflection", "defl"), ("deflection_rate", "defl_rate")):
        if key in values:
            getattr(kernel_state, field)[keep] = values[key]
    for key, field in (("joint_coordinates", "jq"), ("joint_rates", "jqd")):
        if key in values:
            for c, (k, i) in enumerate(columns):
                getattr(kernel_state, field)[keep[k], i] = values[key][c]
    for key, field in (("modal_coordinates", "eta"), ("modal_velocities", "eta_d")):
        if key in values:
            getattr(kernel_state, field)[:] = values[key]


class ODE:
    """A model's equations of motion as a first-order system for any ODE integrator
    (``scipy.integrate.solve_ivp``): ``dttmm.ode(model)`` (docs/dynamics.md, "Any
    integrator").

    The state vector y holds, in this order: for every body whose rotation is its own (on a
    ball joint or an elastic hinge; the others follow their parents' and their joints'
    coordinates) its unit quaternion [w, x, y, z] and its angular velocity (world, rad/s); for
    every elastic hinge its deflection and rate (world, m, m/s); every joint coordinate, then
    every joint rate (Result's joint_coordinates order); every modal coordinate, then every
    modal rate.  ``names`` labels each entry, ``y0`` is the model's initial state,
    ``fun(t, y)`` its derivative by ``forward_dynamics`` (the quaternions' rates
    q' = 1/2 [0, w] q, world w, normalized before use; so an integrator's drift off |q| = 1
    does not enter the dynamics), ``state(y)`` the forward_dynamics / Result layout of y,
    ``frames(t, y)`` every body's rotation and angular velocity.
    Closed loops are refused: an ODE integrator holds their constraints at acceleration
    level only, and the positions drift off the loops (``simulate`` projects them back).
    """

    def __init__(self, model, _closed=False):
        from . import run_tables
        from ..elements.hinges import BALL
        from ..elements.kinds import DEFLECTING
        from ..model.model import Model
        if not isinstance(model, Model):
            raise ValueError(f"ode: model must be a Model, got {type(model).__name__}")
        if model.n_closures and not _closed:    # (linearize takes the tree's coordinates)
            raise ValueError("ode: closed loops drift off their constraints in an ODE "
                             "integrator (they are held at acceleration level only); "
                             "simulate projects them back after every step")
        self.model = model
        # bodies turning on their own (behind ball joints, elastic hinges, free joints) and
        # joints whose child's input point moves on its own (an elastic hinge's deflection, a
        # free joint's flight: d, world)
        self.free = np.nonzero(np.isin(model.hinge_kind, (BALL,) + DEFLECTING))[0]
        self.elastic = np.nonzero(np.isin(model.hinge_kind, DEFLECTING))[0]
        self.columns = run_tables.coordinate_columns(model)
        n_eta = int(model.n_modes.sum())
        names = []
        for k in self.free:
            b = model.body_names[k]
            names += [f"{b}.q{c}" for c in "wxyz"] + [f"{b}.w{c}" for c in "xyz"]
        for k in self.elastic:
            h = model.hinge_names[k]
            names += [f"{h}.d{c}" for c in "xyz"] + [f"{h}.d'{c}" for c in "xyz"]
        names += [f"{model.hinge_names[k]}.q{i}" for k, i in self.columns]
        names += [f"{model.hinge_names[k]}.q{i}'" for k, i in self.columns]
        names += [f"eta{j}" for j in range(n_eta)] + [f"eta{j}'" for j in range(n_eta)]
        self.names = tuple(names)
        self._n_eta = n_eta
        start = forward_dynamics(model)         # the initial state, every frame rebuilt
        initial = run_tables.Workspace(model).state     # (its offsets and joint coordinates)
        self.y0 = self._pack(start["rotation"], start["angular_velocity"], initial.defl,
                             initial.defl_rate,
                             np.array([initial.jq[k, i] for k, i in self.columns]),
                             np.array([initial.jqd[k, i] for k, i in self.columns]),
                             np.asarray(model.initial_modal_coordinates, dtype=float),
                             np.asarray(model.initial_modal_velocities, dtype=float))

    def _pack(self, rot, omega, defl, defl_rate, q, qd, eta, eta_d):
        from ..results.result import rotation_to_quaternion
        parts = []
        for k in self.free:
            parts += [rotation_to_quaternion(rot[k]), omega[k]]
        for k in self.elastic:
            parts += [defl[k], defl_rate[k]]
        return np.concatenate(parts + [q, qd, eta, eta_d]).astype(float)

    def state(self, y):
        """The state y as forward_dynamics takes it (a body that follows its parent has its
        initial rotation there, which the sweep's kinematics rebuild; one welded to a fixed
        ground keeps it)."""
        y = np.asarray(y, dtype=float)
        n = self.model.n_bodies
        rot = np.array(self.model.initial_rotation, dtype=float, order="C")
        omega = np.zeros((n, 3))
        defl, defl_rate = np.zeros((n, 3)), np.zeros((n, 3))
        o = 0
        for k in self.free:
            q = y[o:o + 4] / np.linalg.norm(y[o:o + 4])
            rot[k] = _rotation_of(q)
            omega[k] = y[o + 4:o + 7]
            o += 7
        for k in self.elastic:
            defl[k], defl_rate[k] = y[o:o + 3], y[o + 3:o + 6]
            o += 6
        n_q = len(self.columns)
        q, qd = y[o:o + n_q], y[o + n_q:o + 2 * n_q]
        o += 2 * n_q
        n_eta = self._n_eta
        state = {"rotation": rot, "angular_velocity": omega, "joint_coordinates": q,
                 "joint_rates": qd, "modal_coordinates": y[o:o + n_eta],
                 "modal_velocities": y[o + n_eta:o + 2 * n_eta]}
        if len(self.elastic):
            state.update(deflection=defl, deflection_rate=defl_rate)
        return state

    def frames(self, t, y):
        """(rotation (n, 3, 3), angular_velocity (n, 3)) of every body at (t, y), those that
        follow their parents rebuilt from them."""
        out = _accelerations(self.model, float(t), self.state(y), False)
        return out["rotation"], out["angular_velocity"]

    def fun(self, t, y):
        """dy/dt at (t, y)."""
        y = np.asarray(y, dtype=float)
        out = _accelerations(self.model, float(t), self.state(y), False)
        parts, o = [], 0
        for k in self.free:     # q' = 1/2 [0, w] q: [-w . v, q0 w + w x v]
            (q0, v0, v1, v2), (w0, w1, w2) = y[o:o + 4], y[o + 4:o + 7]
            parts += [0.5 * np.array([-(w0 * v0 + w1 * v1 + w2 * v2),
                                      q0 * w0 + w1 * v2 - w2 * v1,
                                      q0 * w1 + w2 * v0 - w0 * v2,
                                      q0 * w2 + w0 * v1 - w1 * v0]),
                      out["angular_acceleration"][k]]
            o += 7
        for k in self.elastic:
            parts += [y[o + 3:o + 6], out["deflection_acceleration"][k]]
            o += 6
        n_q = len(self.columns)
        parts += [y[o + n_q:o + 2 * n_q], out["joint_acceleration"]]
        o += 2 * n_q
        n_eta = self._n_eta
        parts += [y[o + n_eta:o + 2 * n_eta], out["modal_acceleration"]]
        return np.concatenate(parts)


def ode(model):
    """The model's equations of motion for any ODE integrator (docs/dynamics.md, "Any
    integrator").

    Parameters
    ----------
    model : Model
        A model without closed loops that ``simulate`` runs with the Newmark scheme.

    Returns
    -------
    ODE
        Its ``y0``, ``fun(t, y)``, ``names``, ``state(y)`` and ``frames(t, y)``, e.g.
        ``sol = scipy.integrate.solve_ivp(system.fun, (0, 1), system.y0, method="DOP853")``.

    Raises
    ------
    ValueError
        A model with closed loops, or one the Newmark loops do not run.
    """
    return ODE(model)


def _rotation_of(q):
    """The rotation matrix of a unit quaternion [w, x, y, z]."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


class LinearModel:
    """x' = A x + B u, y = C x + D u about a state (``dttmm.linearize``; docs/dynamics.md,
    "Linear models"): ``A``, ``B``, ``C``, ``D`` and the names of the ``states``, ``inputs``
    and ``outputs``; ``difference_error`` the central differences' error estimate (the largest
    change of any entry of A and B between steps eps and 2 eps, over 3, relative to their
    largest entry)."""

    def __init__(self, a, b, c, d, states, inputs, outputs, difference_error):
        self.A, self.B, self.C, self.D = a, b, c, d
        self.states, self.inputs, self.outputs = tuple(states), tuple(inputs), tuple(outputs)
        self.difference_error = float(difference_error)

    def __repr__(self):
        return (f"LinearModel({len(self.states)} states, {len(self.inputs)} inputs, "
                f"{len(self.outputs)} outputs)")


DIFFERENCE_STEP = 1e-5      # linearize's central differences: rad, m, rad/s, m/s, N, N m


def linearize(model, state=None, t=0.0):
    """The model's linear state-space model about a state (equilibrium or not).

    The states x are the configuration's perturbations, then their rates: every free rotation
    (a body on a ball joint or an elastic hinge) turned by a small world rotation vector
    (A <- exp(dth^) A; its rate is w, the world angular velocity), every elastic hinge's
    deflection, every joint coordinate, every modal coordinate; then w, the deflections',
    joint and modal rates.  The inputs u are a force and a torque (world) on every body (a
    rigid body's force at its mass centre; a beam's at its output end section, as its
    ``end_force`` and ``end_torque``, in its end section's axes if its ``load_axes`` is
    "body"), then a torque about every revolute joint's axis and each universal joint's two
    axes, and a force along every prismatic joint's axis: the coordinate's generalized force,
    added to its drive's, which the joint applies between its two frames (next to beams too);
    0 on a prescribed coordinate; for a compiled JointForce, a pair of body loads, offered
    between rigid bodies only.  The
    outputs y are every body's output point, world.  The accelerations' derivatives are
    central differences of ``forward_dynamics`` (step DIFFERENCE_STEP, extrapolated with the
    step twice as large; the error estimate is ``difference_error``); the rest is exact
    (dth' = w + 1/2 w x dth to first order).

    Parameters
    ----------
    model : Model
        A model that ``simulate`` runs with the Newmark scheme.  Closed by closing joints
        (rigid bodies on joints), its states are its independent coordinates and their rates
        (the loops' dependent coordinates follow; docs/dynamics.md, "Closed loops").
    state : mapping, optional
        The state to linearize about (as ``forward_dynamics`` takes it; ``result.state(i)``);
        default the model's initial state.
    t : float
        The time, s (loads, drives and the ground's motion at t).

    Returns
    -------
    LinearModel
        ``A``, ``B``, ``C``, ``D`` and the names of the states, inputs and outputs.

    Raises
    ------
    ValueError
        A closed model with beams, elastic hinges or a pinned tip, or without freedom left;
        a bad state (see forward_dynamics).
    """
    from ..elements.hinges import ELASTIC
    from ..elements.drives import MOTION
    from .run_inputs import additive_joint_force
    if len(getattr(model, "contacts", ())):
        raise ValueError("linearize: the model's bodies have contact shapes (docs/contact.md), "
                         "whose forces switch on and off: their linear model is not defined; "
                         "linearize the model without shapes")
    closed = bool(model.n_closures)
    if closed and (model.tip_pinned or model.has_beams
                   or np.isin(model.hinge_kind, (ELASTIC,)).any()):
        raise ValueError("linearize: closed loops are linearized for rigid bodies on joints "
                         "(closing joints, System.close); a pinned tip, beams or elastic "
                         "hinges in a closed model are not yet (static_equilibrium gives "
                         "their small vibrations at an equilibrium)")
    if isinstance(t, dict) or not isinstance(state, (dict, type(None))):
        raise ValueError(f"linearize: the arguments are (model, state=None, t=0.0): state a "
                         f"dict (forward_dynamics' or Result.state's), t a number of seconds; "
                         f"got state {type(state).__name__} and t {type(t).__name__} "
                         f"(forward_dynamics takes (model, t, state))")
    system = ODE(model, _closed=closed)
    t = float(t)
    base = forward_dynamics(model, t, state)            # the state with every frame rebuilt
    n = model.n_bodies
    full = {"rotation": base["rotation"], "angular_velocity": base["angular_velocity"]}
    start = system.state(system.y0)
    for key in ("joint_coordinates", "joint_rates", "modal_coordinates", "modal_velocities",
                "deflection", "deflection_rate"):
        if key in start:
            full[key] = np.array(start[key] if state is None or key not in state
                                 else state[key], dtype=float)
    free, elastic, columns = system.free, system.elastic, system.columns
    n_q, n_eta = len(columns), int(model.n_modes.sum())
    m = 3 * len(free) + 3 * len(elastic) + n_q + n_eta          # configuration coordinates
    names = ([f"{model.body_names[k]}.th{c}" for k in free for c in "xyz"]
             + [f"{model.hinge_names[k]}.d{c}" for k in elastic for c in "xyz"]
             + [f"{model.hinge_names[k]}.q{i}" for k, i in columns]
             + [f"eta{j}" for j in range(n_eta)])
    states = names + [s + "'" for s in names]

    def moved(dx, dv):
        """The state with the configuration moved by dx and the rates by dv (m each, x's
        order: a free rotation turned by the world rotation vector dx[3q:3q+3])."""
        s = {key: np.array(value, dtype=float) for key, value in full.items()}
        o = 3 * len(free)
        for q, k in enumerate(free):
            s["rotation"][k] = _turned(dx[3 * q:3 * q + 3]) @ s["rotation"][k]
            s["angular_velocity"][k] += dv[3 * q:3 * q + 3]
        for q, k in enumerate(elastic):
            s["deflection"][k] += dx[o + 3 * q:o + 3 * q + 3]
            s["deflection_rate"][k] += dv[o + 3 * q:o + 3 * q + 3]
        o += 3 * len(elastic)
        if n_q:
            s["joint_coordinates"] = s["joint_coordinates"] + dx[o:o + n_q]
            s["joint_rates"] = s["joint_rates"] + dv[o:o + n_q]
        if n_eta:
            s["modal_coordinates"] = s["modal_coordinates"] + dx[o + n_q:]
            s["modal_velocities"] = s["modal_velocities"] + dv[o + n_q:]
        return s

    def perturbed(j, eps):
        """The state with coordinate j of x (configuration, then rates) moved by eps."""
        dx, dv = np.zeros(m), np.zeros(m)
        (dv if j >= m else dx)[j % m] = eps
        return moved(dx, dv)

    if closed:              # the loops' coordinates: x's dependent ones follow the rest
        fixed = np.zeros(m, dtype=bool)     # a prescribed coordinate moves with t alone
        o = 3 * len(free) + 3 * len(elastic)
        for c, (k, i) in enumerate(columns):
            drive = model.drives[k][i]
            fixed[o + c] = drive is not None and drive["kind"] == MOTION
        perturbed, independent, moves = _closed_chart(model, t, full, free, columns, m, moved,
                                                      fixed)
        states = ([names[i] for i in independent]
                  + [names[i] + "'" for i in independent])

    def accelerations(out):
        return np.concatenate([out["angular_acceleration"][free].ravel(),
                               out["deflection_acceleration"][elastic].ravel(),
                               out["joint_acceleration"], out["modal_acceleration"]])

    def outputs(out, s):
        """Every output point of the state s (forward_dynamics' out of it: its frames)."""
        from .run_inputs import _points
        defl, defl_rate = out["offsets"]
        eta = np.asarray(s.get("modal_coordinates", np.zeros(0)), dtype=float)
        points = _points(model, np.array([t]), out["rotation"][None],
                         out["angular_velocity"][None], defl[None], defl_rate[None], eta[None],
                         np.zeros((1, n_eta)), None, None)
        return points["position_output"][0].ravel()

    # the joints' inputs: each coordinate's generalized force (a torque about a revolute
    # joint's axis or a universal joint's, a force along a slide), added to what its drive
    # gives (run_inputs.additive_joint_force: the joint's own element applies it, between its
    # frames,
    # next to beams too); a prescribed coordinate's is 0 (nothing moves it).  A compiled
    # JointForce has no such slot: there the input is a pair of body loads (a torque tau n,
    # +tau n on the child and -tau n on the parent; a slide's force f n, +f n on the child and
    # -f n on the parent at one point P, the child's input point, i.e. at the mass centres with
    # the torques +-(P - c) x f n), between rigid bodies only (a beam's body loads act at its
    # output end, not where the joint is; a strain rod carries none: half the pair would be
    # dropped)
    joint_inputs, joint_names = [], []
    points = None
    for k in range(n):
        kind = int(model.hinge_kind[k])
        if kind not in WITH_COORDINATES:
            continue
        p = model.parent[k]
        spec = coordinates_of(kind)
        for i, drive in enumerate(model.drives[k]):
            # a turn's torque, a slide's force (a joint of one slide: ".force")
            slide = spec[i].motion == SLIDE
            name = (f"{model.hinge_names[k]}.torque{i}" if not slide
                    else f"{model.hinge_names[k]}.force" + (f"{i}" if len(spec) > 1 else ""))
            if additive_joint_force(drive) or drive["kind"] == MOTION:
                joint_inputs.append((k, i, None if drive is None or drive["kind"] != MOTION
                                     else "prescribed"))
                joint_names.append(name)
                continue
            if model.body_kind[k] in FLEXIBLE or (p >= 0 and model.body_kind[p] in FLEXIBLE):
                continue            # (a beam's body loads act at its end; a rod has none)
            rot_p = model.ground_rotation if p < 0 else base["rotation"][p]
            axis = _joint_axis(model, base, k, i, rot_p)
            arms = None
            if slide:
                if points is None:
                    from .run_inputs import _points
                    defl, defl_rate = base["offsets"]
                    points = _points(model, np.array([t]), base["rotation"][None],
                                     base["angular_velocity"][None], defl[None],
                                     defl_rate[None],
                                     np.asarray(full.get("modal_coordinates",
                                                         np.zeros(0)))[None],
                                     np.zeros((1, n_eta)), None, None)
                at = points["position_input"][0, k]
                arms = [at - points["position_mass_center"][0, b] if b >= 0 else None
                        for b in (k, p)]
            joint_inputs.append((k, p, axis, arms))
            joint_names.append(name)
    n_u = 6 * n + len(joint_inputs)
    inputs = ([f"{model.body_names[k]}.f{c}" for k in range(n) for c in "xyz"]
              + [f"{model.body_names[k]}.m{c}" for k in range(n) for c in "xyz"] + joint_names)

    def loads(j, eps):
        """(force, torque, joint forces) of input j at eps (None: nothing moves)."""
        force, torque = np.zeros((n, 3)), np.zeros((n, 3))
        if j < 3 * n:
            force[j // 3, j % 3] = eps
        elif j < 6 * n:
            torque[(j - 3 * n) // 3, (j - 3 * n) % 3] = eps
        elif len(joint_inputs[j - 6 * n]) == 3:     # a coordinate's generalized force
            k, i, prescribed = joint_inputs[j - 6 * n]
            if prescribed:
                return None
            generalized = np.zeros((n, MAX_COORDINATES))
            generalized[k, i] = eps
            return force, torque, generalized
        else:
            k, p, axis, arms = joint_inputs[j - 6 * n]
            if arms is None:                    # a torque about the axis
                torque[k] += eps * axis
                if p >= 0:
                    torque[p] -= eps * axis
            else:                               # a force along the slide, on one line
                force[k] += eps * axis
                torque[k] += np.cross(arms[0], eps * axis)
                if p >= 0:
                    force[p] -= eps * axis
                    torque[p] -= np.cross(arms[1], eps * axis)
        return force, torque, None

    if closed:
        rows, d = independent, len(independent)
    else:
        rows, d, moves = np.arange(m), m, np.eye(m)

    def differenced(eps):
        da, db, dy = np.zeros((d, 2 * d)), np.zeros((d, n_u)), np.zeros((3 * n, d))
        for j in range(2 * d):
            up, down = perturbed(j, eps), perturbed(j, -eps)
            plus = _accelerations(model, t, up, False)
            minus = _accelerations(model, t, down, False)
            da[:, j] = (accelerations(plus)[rows] - accelerations(minus)[rows]) / (2 * eps)
            if j < d:
                dy[:, j] = (outputs(plus, up) - outputs(minus, down)) / (2 * eps)
        for j in range(n_u):
            up, down = loads(j, eps), loads(j, -eps)
            if up is None:                      # (a prescribed coordinate's force)
                continue
            plus = _accelerations(model, t, full, False, up[:2], up[2])
            minus = _accelerations(model, t, full, False, down[:2], down[2])
            db[:, j] = (accelerations(plus)[rows] - accelerations(minus)[rows]) / (2 * eps)
        return da, db, dy

    da1, db1, dy1 = differenced(DIFFERENCE_STEP)
    da2, db2, dy2 = differenced(2 * DIFFERENCE_STEP)
    da, db, dy = ((4 * x1 - x2) / 3 for x1, x2 in ((da1, da2), (db1, db2), (dy1, dy2)))
    error = (max(np.abs(da1 - da2).max(initial=0.0), np.abs(db1 - db2).max(initial=0.0)) / 3
             / max(np.abs(da).max(initial=0.0), np.abs(db).max(initial=0.0), 1e-300))
    kinematic = np.zeros((m, m))            # d x' / d x at fixed rates: dth' = w + 1/2 w x dth
    for q, k in enumerate(free):
        w = full["angular_velocity"][k]
        kinematic[3 * q:3 * q + 3, 3 * q:3 * q + 3] = 0.5 * np.array([[0.0, -w[2], w[1]],
                                                                       [w[2], 0.0, -w[0]],
                                                                       [-w[1], w[0], 0.0]])
    a = np.zeros((2 * d, 2 * d))
    a[:d, d:] = np.eye(d)
    a[:d, :d] = (kinematic @ moves)[rows]   # (moves = dx / dy: the dependent ones follow)
    a[d:] = da
    b = np.zeros((2 * d, n_u))
    b[d:] = db
    c = np.hstack([dy, np.zeros((3 * n, d))])
    outputs_names = [f"{model.body_names[k]}.r{c}" for k in range(n) for c in "xyz"]
    return LinearModel(a, b, c, np.zeros((3 * n, n_u)), states, inputs, outputs_names, error)


def _closed_chart(model, t, full, free, columns, m, moved, fixed):
    """A closed model's coordinates for linearize (docs/dynamics.md, "Closed loops"): the
    tree's coordinates x split into dependent and independent ones by the loops' constraint
    Jacobian G = dg/dx (g: loop_kinematics.closure_residuals at the tree's kinematics; central
    differences): the independent ones chosen root first, each whose column G can lose keeping
    its rank (singular values above 1e-6 of G's largest; G's own rank counts those above 1e-9,
    a planar loop's redundant rows dropping out), so a crank's angle before a coupler's.
    Returns (perturbed, independent, moves): perturbed(j, eps) the state with independent
    coordinate j (then rate j - d) moved by eps and the dependent ones solved (g = 0, then
    g' = G x' = 0, by Newton's iteration with G_dep); moves = dx/dy (m x d).  fixed: the
    coordinates that are neither (prescribed motions: they stay as they are)."""
    from scipy.linalg import lstsq
    from ..model.loop_kinematics import closure_residuals, tree_state
    from ..kernels.algebra.so3 import log_so3
    n = model.n_bodies

    def residuals(s):
        theta = np.zeros((n, 3))
        omega = np.array(model.initial_angular_velocity, dtype=float)
        q = np.array(model.hinge_params[:, COORDINATE_0])
        qd = np.array(model.hinge_params[:, RATE_0])
        for k in free:
            log_so3(np.ascontiguousarray(s["rotation"][k] @ model.initial_rotation[k].T),
                    theta[k])
            omega[k] = s["angular_velocity"][k]
        for c, (k, i) in enumerate(columns):
            q[k, i], qd[k, i] = s["joint_coordinates"][c], s["joint_rates"][c]
        g, gd, _ = closure_residuals(model, tree_state(model, theta, q, omega, qd), t)
        return g, gd

    zero = np.zeros(m)
    jac = np.zeros((len(residuals(moved(zero, zero))[0]), m))
    for j in range(m):
        step = np.zeros(m)
        step[j] = 1e-6
        jac[:, j] = (residuals(moved(step, zero))[0] - residuals(moved(-step, zero))[0]) / 2e-6
    movable = np.nonzero(~fixed)[0]
    singular = np.linalg.svd(jac[:, movable], compute_uv=False)
    rank = int(np.sum(singular > 1e-9 * singular[0])) if singular.size and singular[0] else 0
    independent = []            # root first: each coordinate whose loss leaves G_dep's rank
    for j in movable:
        if len(independent) == len(movable) - rank:
            break
        rest = np.setdiff1d(movable, independent + [j])
        kept = np.linalg.svd(jac[:, rest], compute_uv=False)
        if np.sum(kept > 1e-6 * singular[0]) == rank:
            independent.append(j)
    independent = np.array(independent, dtype=int)
    if not len(independent):
        raise ValueError("linearize: the closed model has no freedom left: its loops and its "
                         "prescribed motions fix every coordinate")
    dependent = np.setdiff1d(movable, independent)
    g_dep = jac[:, dependent]
    moves = np.zeros((m, len(independent)))
    moves[independent] = np.eye(len(independent))
    moves[dependent] = -lstsq(g_dep, jac[:, independent])[0]

    def solved(dx, dv, which):
        """dx or dv (which 0 or 1) with its dependent entries moved until g (or g') is 0."""
        target = (dx, dv)[which]
        for _ in range(50):
            r = residuals(moved(dx, dv))[which]
            if np.abs(r).max(initial=0.0) <= 1e-14:
                break
            change = lstsq(g_dep, r)[0]
            target[dependent] -= change
            if np.abs(change).max(initial=0.0) <= 1e-16:
                break
        return target

    def perturbed(j, eps):
        d = len(independent)
        dx, dv = np.zeros(m), np.zeros(m)
        if j < d:
            dx[independent[j]] = eps
        else:
            dv[independent[j - d]] = eps
        dx = solved(dx, dv, 0)
        return moved(dx, solved(dx, dv, 1))

    return perturbed, independent, moves


def _turned(phi):
    """exp(phi^), the rotation by the rotation vector phi."""
    angle = np.linalg.norm(phi)
    if angle == 0.0:
        return np.eye(3)
    k = np.array([[0.0, -phi[2], phi[1]], [phi[2], 0.0, -phi[0]], [-phi[1], phi[0], 0.0]])
    k /= angle
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def _joint_axis(model, base, k, i, rot_p):
    """Joint k's coordinate i's axis (world) at the state: a slide's or a turn's fixed in the
    parent, rot_p n; a turn's fixed in the child, A n (a joint has at most one turn in each
    frame: elements/kinds.py)."""
    c = coordinates_of(int(model.hinge_kind[k]))[i]
    axis = row_axes(model.hinge_params[k])[c.axis]
    return (base["rotation"][k] if c.motion == TURN and c.frame == CHILD else rot_p) @ axis
