"""The consistent start: the accelerations of a state, by the fused loop's own sweep or the
general loop's start (docs/solver.md, "Consistent start")."""
import numpy as np

from ..elements.drives import MOTION
from ..elements.hinges import DEFLECTION_RATE_0
from ..elements.kinds import DEFLECTING
from ..elements.rigid_body import TO_MASS_CENTER, TO_OUTPUT
from ..kernels.stepping import ball_chain
from ..kernels.stepping import weld_chain
from ..kernels.stepping import step as kstep
from ..kernels import python_twin
from ..kernels.assembly.closure import set_ground
from ..kernels.schema import INPUT_LAYOUT, MODEL_LAYOUT, RECORD_LAYOUT, FlatWeld
from ..kernels.stepping.loop import OK, SINGULAR, UNSUPPORTED, Run
from ..kernels.stepping.loop import DirectCalls, run_steps
from ..kernels.assembly.sweep import LOST_ACCURACY
from ..model.model import model_fact
from ..model.loop_rows import closure_forces, closure_targets, has_closure_drives
from . import core
from ..vectors import cross
from .run_tables import _station_histories, compiled_forces, loop_tables
from .run_checks import DivergenceError, _DIRECT_HINT, _singular_cause, _unsupported_cause
from .run_inputs import _drive_number, _ground, _joint_inputs, _loads


def _steps(t_end, dt):
    """(n, h): n = ceil(t_end / dt) equal steps of h = t_end / n, so that the last one lands on
    t_end; h = dt where dt divides t_end (to 1e-9 of a step)."""
    n = max(1, int(np.ceil(t_end / dt - 1e-9)))
    return n, (dt if abs(n * dt - t_end) <= 1e-9 * dt else t_end / n)


def _consistent_start(model, mode, method, fused, params, settings, state, sweep, monitor, dt,
                      loops=None, t=0.0, extra_loads=None,
                      extra_joint_forces=None, in_skeleton=False):
    """The accelerations of the state at time t (a run's start: t = 0; docs/solver.md,
    "Consistent start") into state: by the fused loop's own sweep (fused: its (runner, loop)) or
    kernels/stepping/step.py::initial_accelerations, with the closing joints (loops: loop_tables)
    held at acceleration level; in_skeleton: as one pass of the general loop's skeleton (a run
    on it, statics, linear models and forward dynamics: the one compiled core, nothing compiled
    for them alone), else the start alone (the energy-momentum scheme, a family of its own:
    initial_accelerations' twin, with entry points).  extra_loads: (force, torque), (n, 3)
    each, world, added to the applied loads (at the mass centres; dynamics.linearize's inputs);
    extra_joint_forces: (n, 3) generalized forces added to the joint coordinates' (where
    additive_joint_force says they add)."""
    loops = loop_tables(model) if loops is None else loops
    n = model.n_bodies
    g_acc, g_rot, g_w, g_wd, g_pos, g_vel = _ground(model, [t])
    force, torque, line_load = _loads(model, [t])
    if extra_loads is not None:
        force[0] += extra_loads[0]
        torque[0] += extra_loads[1]
    joint_input = _joint_inputs(model, [t], state, dt)
    if extra_joint_forces is not None:      # (n, MAX_COORDINATES): onto the drives' known forces
        joint_input[0, :, :, 0] += extra_joint_forces
    try:
        if fused:       # the fused loop's own sweep (compiles nothing else)
            status = _fused_start(*fused, start_pass(
                params, settings, state, sweep, monitor,
                (g_acc, g_rot, g_w, g_wd, g_pos, g_vel), (force, torque, line_load),
                joint_input, loops.rows))
        else:
            set_ground(loops, g_pos[0], g_vel[0], g_acc[0], g_rot[0], g_w[0], g_wd[0])
            loop = run = None
            if in_skeleton:     # one pass of the general loop's skeleton (Settings.start),
                # on a throwaway scratch: the run that follows compiles nothing else for it
                loop = kstep.general_loop(n, len(state.eta), settings.h, settings.coef,
                                          _station_histories(model, state, False), loops,
                                          compiled_forces(model), len(model.contacts))
                run = start_pass(params, settings, state, sweep, monitor,
                                 (g_acc, g_rot, g_w, g_wd, g_pos, g_vel),
                                 (force, torque, line_load), joint_input, loops.rows)
            core.complete(params, loops, state, loop, run)  # (where the core compiles: all)
            if has_closure_drives(model):   # a driven closing coordinate's q''(0), a
                loops.target[:, :] = closure_targets(model, [t], loops)[0]  # spring's rest
                loops.step_coef[:] = 0.0        # the springs' forces explicit

            if in_skeleton:
                def start():
                    info = np.zeros(5, dtype=np.int64)
                    run_steps(loop, run, info, calls=_start_calls(model))
                    return _start_status(info)
            else:               # the start alone: its copy's twin, with entry points
                start_alone = python_twin(kstep.initial_accelerations)

                def start():
                    return start_alone(
                        params, settings, state, sweep, (g_acc[0], g_rot[0], g_w[0], g_wd[0]),
                        force[0], torque[0], line_load[0], joint_input[0], loops,
                        compiled_forces(model), start_contacts(params, n))
            status = start()
            forces = closure_forces(model, loops)
            if forces and status == 0:  # a closing JointForce's f(0, q, q'): the start's
                for r, law, who in forces:  # force rows leave q, q' in loops.g, gd
                    loops.target[r, 2] = _drive_number(law(t, loops.g[r], loops.gd[r]), who, t)
                status = start()
            for r in np.nonzero(loops.coordinate >= 0)[0]:   # the drives' rates at t = 0
                loops.wrench[loops.owner[r], 8 + loops.coordinate[r]] = (
                    loops.target[r, 1] if loops.law[r, 0] == MOTION else loops.gd[r])
    except np.linalg.LinAlgError as err:
        raise DivergenceError(0, t, f"consistent start: a matrix of the sweep is singular "
                              f"or not finite ({err})"
                              + (f"; {_DIRECT_HINT}" if method == "direct" else "")) from None
    if status == LOST_ACCURACY:
        raise DivergenceError(0, t, "consistent start: the direct sweep lost its accuracy; "
                              + _DIRECT_HINT)
    if status == _NOT_FINITE_START:
        raise DivergenceError(0, t, "consistent start: the accelerations are NaN or infinite "
                              "(check the model's masses, inertias and initial state)")
    if status < 0:
        raise ValueError(_unsupported_cause(model, -status, "the consistent start"))
    if status != 0:
        raise DivergenceError(0, t, _singular_cause(model, mode, status, "consistent start"))
    for k in range(n):
        state.omega_dot[k] = g_wd[0] if model.ground_locked[k] else state.z[2 * k + 1, 3:6]
        if model.hinge_kind[k] in DEFLECTING:
            st = 2 * model.parent[k] + 2            # the inboard station (0: the ground)
            state.defl_acc[k] = state.z[2 * k + 1, 0:3] - state.z[st, 0:3]
    state.pseudo[:] = state.omega_dot
    state.eta_p[:] = state.eta_acc
    state.defl_pseudo[:] = state.defl_acc


@model_fact
def _start_calls(model):
    """The model's skeleton passes of a start (statics, linear models and forward dynamics call
    one per evaluation): a call of the types of the one before goes straight to its compiled
    code, without numba typing the general loop's ~180 arrays again (kernels/stepping/loop.py::
    DirectCalls; forward_dynamics of the arm 0.57 -> 0.52 ms a call, one process)."""
    return DirectCalls()


def start_pass(params, settings, state, sweep, monitor, ground, loads, joint_input,
               n_closures):
    """The Run of one pass of a loop's consistent start at one time (_fused_start, the general
    loop's in _consistent_start; the high-order scheme's stages,
    kernels/stepping/runge_kutta.py): ground = _ground's six (1, ...) arrays, loads = _loads'
    three, joint_input = _joint_inputs'; no Newton iteration, no record."""
    g_acc, g_rot, g_w, g_wd, g_pos, g_vel = ground
    force, torque, line_load = loads
    return Run(params, settings._replace(newton_max=0, start=True), state, sweep,
               INPUT_LAYOUT.pack(g_acc=g_acc, g_rot=np.concatenate([g_rot, g_rot]), g_w=g_w,
                                 g_wd=g_wd, g_pos=g_pos, g_vel=g_vel, force=force, torque=torque,
                                 line_load=line_load, joint_input=joint_input,
                                 closure_target=np.zeros((1, n_closures, 3))),
               _record(0, len(state.rot), len(state.eta)), monitor)


def _record(n_rec_max, n, n_eta, v_st=False, v_c=False, n_closures=0):
    """Where a chunk's samples are written (kernels/schema.py::RECORD, a FlatRecord): n_rec_max
    of each; the paper scheme's station velocities, the mass-centre velocities and the closing
    joints' wrenches only where recorded."""
    return RECORD_LAYOUT.zeros(slots=n_rec_max, bodies=n, stations=2 * n + 1, modes=n_eta,
                               point_slots=n_rec_max if v_st else 1,
                               centre_slots=n_rec_max if v_c else 1,
                               wrench_slots=n_rec_max if n_closures else 1, closings=n_closures)


_NOT_FINITE_START = -(1 << 30)      # a start pass's status for accelerations not finite


def _fused_start(runner, loop, run):
    """The consistent start of the fused loops: their own iterate, once, at acceleration level
    (kernels/stepping/ball_chain.py::start_loop; run.settings.start).  Leaves the stations' states
    in state.z (angular accelerations in the phi slots) and the beams' modal accelerations in
    state.eta_acc, as kernels/stepping/step.py::initial_accelerations does; returns its status
    codes."""
    info = np.zeros(5, dtype=np.int64)
    step_coefficients = (weld_chain.start_loop(loop, run) if isinstance(loop, FlatWeld)
                         else ball_chain.start_loop(loop, run.state, run.sweep))
    runner(loop, run, info)
    loop.coefficients[:] = step_coefficients
    run.state.eta_acc[:] = loop.per_mode[4]
    return _start_status(info)


def _start_status(info):
    """The status code of a start pass (_fused_start's, the general loop's in _consistent_start)
    from its loop's info (kernels/stepping/loop.py::report): 0 done; SINGULAR's detail (the
    singular element, or the general loop's start's own code: kernels/stepping/step.py::_iterate
    under Settings.start); minus UNSUPPORTED's element (elements' codes are j + 1, never 0:
    _singular_cause); _NOT_FINITE_START for any other status, which never reads as done."""
    if info[0] == OK:
        return 0
    if info[0] == SINGULAR:
        return int(info[2])
    if info[0] == UNSUPPORTED:
        return -int(info[2])
    return _NOT_FINITE_START


def start_contacts(params, n_bodies):
    """The start's contacts argument (kernels/stepping/step.py::initial_accelerations) where it
    runs alone: the general loop's contact scratch for the model's spheres (_contacts_of)."""
    c = kstep.contact_scratch(n_bodies, len(MODEL_LAYOUT.table(params, "contacts")))
    inst = (c["contact_point"], c["contact_offset"], c["contact_force"], c["contact_slope"],
            c["contact_next"], c["contact_body_first"], c["contact_count"])
    return inst, (inst[5], inst[4], inst[0], inst[1], inst[2], inst[3]), c["contact_centre"]


def initial_mass_center_velocities(model, rot, omega):
    """(n, 3) mass-centre velocities of a chain from the initial rotations and angular
    velocities, and a free joint's flight rate (its d', as the build set it)."""
    p = model.body_params
    v_in = model.ground_state(0.0)[1].copy()
    v_c = np.empty((model.n_bodies, 3))
    for k in range(model.n_bodies):
        if model.hinge_kind[k] in DEFLECTING:
            v_in = v_in + model.hinge_params[k, DEFLECTION_RATE_0]
        v_c[k] = v_in + cross(omega[k], rot[k] @ p[k, TO_MASS_CENTER])
        v_in = v_in + cross(omega[k], rot[k] @ p[k, TO_OUTPUT])
    return v_c
