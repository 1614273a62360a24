"""The energy-momentum scheme's loop variant (docs/solver.md, "Energy-momentum scheme").

Each step solves the chain's nonlinear step equations (kernels/transfers/em_body.py) by Newton's
method: every body's transfer is linearized about the latest guess, the same sweeps as the
Newmark loop solve the linear chain, and the guess is updated until the rotation increments
change by less than newton_tol. The converged step conserves the total energy and the angular
momentum about any axis the external loads have no moment about, for rigid chains with ball and
fixed hinges on a fixed ground, and free chains (a free joint at the root or within: its LOCKED
element carries nothing, and the chain's displacement is its own), whose linear momentum it
keeps too. The pieces below go through the one skeleton (kernels/stepping/loop.py); state.z
holds the last step's station states [a, b, m, q] (see kernels/transfers/em_body.py),
state.omega_dot (w_{n+1} - w_n) / h of the last step (the predictor's slope) and state.v_c each
body's mass-centre velocity; inputs.force and inputs.torque are the applied loads' step means.
The pieces allocate nothing (the skeleton is compiled without numba's reference counting,
loop.py::_skeleton): their array work is written element by element into the loop's scratch; the
body's kernels, which allocate, are kernels/__init__.py::allocating_kernel.
"""
import numpy as np

from .. import (input_tables, loop_piece, model_tables, momentum_tables, record_tables,
                state_tables, sweep_tables)
from ...elements import RIGID
from ...elements.hinges import BALL, FIXED, FREE
from ..schema import MOMENTUM_LAYOUT, FlatMomentum
from ..transfers.em_body import em_body_kinematics, rigid_body_transfer_em
from .loop import NOT_FINITE, OK, SINGULAR, UNSUPPORTED, loop_variant
from ..assembly.solve import solve_step
from .step import _all_finite
from ..algebra.mat3 import put2, put3
from ..assembly.sweep import IDENTITY, LOCKED, TRANSFER
from ..assembly.sweep import BALL as EL_BALL

def energy_momentum_loop(n):
    """The energy-momentum loop's own scratch (kernels/schema.py::MOMENTUM) for n bodies."""
    return MOMENTUM_LAYOUT.zeros(stations=2 * n + 1)


@loop_piece
def _predict(loop, run, s, _):
    """The guess: phi = h w_n + h^2 w'_n / 2, in b = 2 phi / h^2 units."""
    z_star = momentum_tables.z_star(loop)
    state, h = run.state, run.settings.h
    z = state_tables.z(state)
    rot = state_tables.rot(state)
    omega_dot = state_tables.omega_dot(state)
    omega = state_tables.omega(state)
    put2(z_star, z)
    for k in range(rot.shape[0]):
        for i in range(3):
            b = (2.0 / h) * omega[k, i] + omega_dot[k, i]
            z_star[2 * k + 1, 3 + i] = b
            z_star[2 * k + 2, 3 + i] = b


@loop_piece
def _iterate(loop, run, s, it):
    """Every element's step transfer about the guess, the sweep; returns (status, detail,
    change) with change the largest update of a rotation increment (rad)."""
    z_star = momentum_tables.z_star(loop)
    load = momentum_tables.load(loop)
    root_f = momentum_tables.root_f(loop)
    torque = input_tables.torque(run.inputs)
    force = input_tables.force(run.inputs)
    params, state, sweep = run.params, run.state, run.sweep
    kind = sweep_tables.kind(sweep)
    u = sweep_tables.u(sweep)
    known_loads = sweep_tables.known_loads(sweep)
    z = state_tables.z(state)
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    v_c = state_tables.v_c(state)
    h = run.settings.h
    s_half = 0.5 * h * h
    body_params, body_row = model_tables.body_params(params), model_tables.body_row(params)
    hinge_kind, body_kind = model_tables.hinge_kind(params), model_tables.body_kind(params)
    gravity, inertia = model_tables.gravity(params), model_tables.mass_center_inertia(params)
    n = rot.shape[0]
    for k in range(n):
        if hinge_kind[k] == BALL:
            kind[2 * k] = EL_BALL
        elif hinge_kind[k] == FIXED:
            kind[2 * k] = IDENTITY
        elif hinge_kind[k] == FREE:     # nothing passes it (docs/free_joint.md): its child's
            kind[2 * k] = LOCKED        # displacement is the chain's own, both sides' loads 0
            for i in range(12):
                known_loads[2 * k, i] = 0.0
        else:
            return UNSUPPORTED, 2 * k + 1, 0.0
        if body_kind[k] != RIGID:
            return UNSUPPORTED, 2 * k + 2, 0.0
        kind[2 * k + 1] = TRANSFER
        row = body_row[k]             # (the body's row of the shared tables)
        for i in range(3):
            load[i] = body_params[row, 0] * gravity[i] + force[s, k, i]
        rigid_body_transfer_em(body_params[row], inertia[row], rot[k],
                               omega[k], v_c[k], h, z_star[2 * k + 1], load,
                               torque[s, k], u[2 * k + 1])
    if not _all_finite(u):
        return NOT_FINITE, 0, 0.0
    status = solve_step(run.settings.mode, model_tables.tip_pinned(params),
                        model_tables.parent(params), sweep, root_f, z)
    if status != 0:
        return SINGULAR, status, 0.0
    change = 0.0
    for k in range(n):
        for i in range(3):
            change = max(change, s_half * abs(z[2 * k + 1, 3 + i] - z_star[2 * k + 1, 3 + i]))
    return OK, 0, change


@loop_piece
def _adopt(loop, run, s, it):
    z_star = momentum_tables.z_star(loop)
    z = state_tables.z(run.state)
    put2(z_star, z)


@loop_piece
def _update(loop, run, s, _):
    """Rotations, angular velocities and mass-centre velocities over the step; a free joint's
    flight d (the child's input point from the parent's output point, world) by its
    displacement dd = dx_I - dx_O,parent and the midpoint rule, d'_{n+1} = 2 dd / h - d'_n."""
    rot_new = momentum_tables.rot_new(loop)
    omega_new = momentum_tables.omega_new(loop)
    state, h = run.state, run.settings.h
    defl = state_tables.defl(state)
    defl_rate = state_tables.defl_rate(state)
    hinge_kind = model_tables.hinge_kind(run.params)
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    v_c = state_tables.v_c(state)
    z = state_tables.z(state)
    omega_dot = state_tables.omega_dot(state)
    s_half = 0.5 * h * h
    body_params, body_row = model_tables.body_params(run.params), model_tables.body_row(run.params)
    finite = True
    for k in range(rot.shape[0]):
        zi = z[2 * k + 1]
        em_body_kinematics(rot[k], omega[k], zi[3:6], h, rot_new, omega_new)
        # v_C,n+1 = 2 dx_C / h - v_C,n,  dx_C = dx_I + A_{n+1} l_IC - A_n l_IC
        l_ic = body_params[body_row[k], 1:4]
        for i in range(3):
            now = rot_new[i, 0] * l_ic[0] + rot_new[i, 1] * l_ic[1] + rot_new[i, 2] * l_ic[2]
            before = rot[k, i, 0] * l_ic[0] + rot[k, i, 1] * l_ic[1] + rot[k, i, 2] * l_ic[2]
            dx_c = s_half * zi[i] + now - before
            v_c[k, i] = (2.0 / h) * dx_c - v_c[k, i]
            omega_dot[k, i] = (omega_new[i] - omega[k, i]) / h
            omega[k, i] = omega_new[i]
            for j in range(3):
                rot[k, i, j] = rot_new[i, j]
        if hinge_kind[k] == FREE:      # (a chain: the hinge's inboard station is 2k)
            for i in range(3):
                dd = s_half * (zi[i] - z[2 * k, i])
                defl[k, i] += dd
                defl_rate[k, i] = (2.0 / h) * dd - defl_rate[k, i]
        for i in range(3):
            if not (np.isfinite(omega[k, i]) and np.isfinite(v_c[k, i])):
                finite = False
    return finite


@loop_piece
def _record(loop, run, s, slot):
    state, rec = run.state, run.rec
    rec_rot = record_tables.rot(rec)
    rec_omega = record_tables.omega(rec)
    rec_omega_dot = record_tables.omega_dot(rec)
    rec_v_c = record_tables.v_c(rec)
    rec_z = record_tables.z(rec)
    rec_defl = record_tables.defl(rec)
    rec_defl_rate = record_tables.defl_rate(rec)
    defl = state_tables.defl(state)
    defl_rate = state_tables.defl_rate(state)
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    omega_dot = state_tables.omega_dot(state)
    v_c = state_tables.v_c(state)
    z = state_tables.z(state)
    put3(rec_rot[slot], rot)
    put2(rec_omega[slot], omega)
    put2(rec_omega_dot[slot], omega_dot)
    put2(rec_v_c[slot], v_c)
    put2(rec_z[slot], z)
    put2(rec_defl[slot], defl)          # (over the record's rows: none without free joints)
    put2(rec_defl_rate[slot], defl_rate)


@loop_piece
def _finish(loop, run, n_steps, _):
    pass


loop_variant(FlatMomentum, predict=_predict, iterate=_iterate, adopt=_adopt,
             update=_update, record=_record, finish=_finish)
