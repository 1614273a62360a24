"""Closing joints in the general loop's step (docs/loops.md, "The step with loops").

The tree's full-state sweep (sweep.py::riccati_tree_full) is linear in the loads at its
stations.  Each scalar constraint r of a closing joint acts through one multiplier lam_r, its
loads on the sides' output stations the constraint's Jacobian transposed (a gap row: a force
lam_r e on side b at its point, -lam_r e on side a at the same point; a dot row: a couple
lam_r (y x x) on b, its opposite on a).  One sweep of the step with a P column per row
(sweep_columns: the Riccati matrices once) gives the stations as affine functions of the
multipliers; the rows' values

    gap (e world):   e . (a_b - a_a)
    gap (e in a):    e . (a_b - a_a) + (e x d) . alpha_a + (w_a x (w_a x e)) . d + 2 (w_a x e) . d'
    dot:             (y x x) . (alpha_b - alpha_a) + (w_b - w_a) . ((w_b x y) x x + y x (w_a x x))

(a point's acceleration a = a_O + alpha x arm + w x (w x arm) from its body's output station)
are held at zero, the constraints' second derivatives (acceleration level, as the consistent
start and the pinned tip hold theirs).  After the step the configuration and then the rates
are projected back onto the loops along the step's own responses to unit multipliers
(project_onto_loops), so that every step ends with its loops closed.

Scope (refused before a run otherwise, closures.check_runs_in_sweeps): rigid bodies, a fixed
ground; every joint kind in the tree.
"""
from collections import namedtuple

import numpy as np
from numba import njit

from . import CONTRACT
from ..closures import DOT, GAP_A, GAP_WORLD
from ..elements import BEAM
from ..elements.beam import AXIAL_MODES, LENGTH, MODES, STIFFENING, TORSION_MODES
from ..elements.hinges import AXIS_1, FIXED
from ..elements.joints import PRISMATIC
from .beam import end_section_motion
from .joint import FREE, PRESCRIBED, joint_frame, n_coordinates
from .so3 import expm_so3
from .sweep import IDENTITY, JOINT, TRANSFER, _gauss_solve, _mm, _mv


# the closing joints as the loop reads them, and the loop's scratch for them (solver.
# loop_tables): rows (R) and closing joints (m) in the kernel model's numbering
Loops = namedtuple("Loops", [
    "kind", "owner", "v1", "v2",     # (R,), (R,), (R, 3), (R, 3): GAP_WORLD / GAP_A / DOT, its
                                     # closing joint, e (or x, in a's frame) and y (b's frame)
    "body", "point",                 # (m, 2), (m, 2, 3): the sides' bodies and points (in the
                                     # body's frame from its input point; the ground's: world,
                                     # from the ground point)
    "ground", "ground_rot",          # (3,), (3, 3) the ground point and frame (a fixed ground)
    "z_save", "nu_save", "tau_save",  # (R + 1, ...) each sweep's stations and joints
    "delassus", "lam", "values",     # (R, R), (R,), (R + 1, R)
    "r_out", "v_out",                # (n, 3) each: the output points' positions, velocities
    "g", "gd",                       # (R,) the rows' positions and rates
    "loads", "p_col", "port_col",    # (R + 1, n, 6), (R + 1, 2n + 1, 6), (R + 1, n, 6):
    "h_store", "k_store", "free_store",   # sweep_columns' scratch: (n, 3, 6), (R + 1, n, 3),
                                     # (n, 4) int
    "eta_col",                       # (R, n_eta) each row's response of the beams' eta''
    "wrench",                        # (m, 6) each closing joint's force and couple on side b
                                     # (world; the couple about its point) from loops.lam
    "stats",                         # (4,) the run's largest position residual after a step
                                     # (before the projection), rate residual before and after
                                     # the rates' projection, position residual after its
])

AXIS_1_START = AXIS_1.start
POSITION_PROJECTIONS = 4     # Gauss-Newton projections of the positions after a step, at most
POSITION_TOL = 1e-13         # m, rad: where they stop
RATE_TOL = 1e-13             # m/s, rad/s: the rates' projection's


@njit(cache=True, fastmath=CONTRACT)
def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


@njit(cache=True, fastmath=CONTRACT)
def _beam_offset(params, k, rot, w, eta, eta_d):
    """Beam k's output point from its input point, rho = A p and its rate w x rho + A p', with
    p = [L - c(L) + u_x(L), v(L), w(L)] (docs/beam.md, "End sections": c(L) the
    foreshortening with geometric stiffening, beam.end_foreshortening; u_x(L) the stretch;
    result.beam_output_offset in Python)."""
    bp, moments, mode_off, ends = params.beams[1][k], params.beams[2][k], params.beams[3], \
        params.beams[4][k]
    i0 = mode_off[k]
    m, mt, ma = int(bp[MODES]), int(bp[TORSION_MODES]), int(bp[AXIAL_MODES])
    p = np.zeros(3)
    p_d = np.zeros(3)
    p[0] = bp[LENGTH]
    for j in range(m):
        for plane in range(2):
            p[1 + plane] += ends[j, 0] * eta[i0 + plane * m + j]
            p_d[1 + plane] += ends[j, 0] * eta_d[i0 + plane * m + j]
    if bp[STIFFENING] != 0.0:       # c = 1/2 eta^T D0 eta per plane, c' = eta'^T D0 eta
        for plane in range(2):
            for a in range(m):
                for b in range(m):
                    d0 = moments[a, 2 + m + b]
                    ea = eta[i0 + plane * m + a]
                    p[0] -= 0.5 * ea * d0 * eta[i0 + plane * m + b]
                    p_d[0] -= eta_d[i0 + plane * m + a] * d0 * eta[i0 + plane * m + b]
    for j in range(ma):
        i = i0 + 2 * m + mt + j
        p[0] += ends[m + mt + j, 0] * eta[i]
        p_d[0] += ends[m + mt + j, 0] * eta_d[i]
    rho = rot[k] @ p
    return rho, _cross(w[k], rho) + rot[k] @ p_d


@njit(cache=True, fastmath=CONTRACT)
def tree_points(params, rot, w, jq, jqd, eta, eta_d, loops):
    """Every body's output point and its velocity (loops.r_out, v_out) from the rotations,
    angular velocities, joint coordinates and rates and the beams' modal coordinates and rates:
    r_in = r_out,P + d (a slide's d = A_P n q), r_out = r_in + A l_IO (a rigid body) or
    r_in + rho (a beam's deflected end, _beam_offset); the kernel model hangs every child at
    its parent's output point."""
    n = rot.shape[0]
    for k in range(n):
        p = params.parent[k]
        if p < 0:
            r = loops.ground.copy()
            v = np.zeros(3)
            rot_p = loops.ground_rot
            w_p = np.zeros(3)
        else:
            r = loops.r_out[p].copy()
            v = loops.v_out[p].copy()
            rot_p = rot[p]
            w_p = w[p]
        if params.hinge_kind[k] == PRISMATIC:
            u = rot_p @ params.hinge_params[k, AXIS_1_START:AXIS_1_START + 3]
            d = u * jq[k, 0]
            r += d
            v += _cross(w_p, d) + u * jqd[k, 0]
        if params.beams[0][k] == BEAM:
            arm, arm_rate = _beam_offset(params, k, rot, w, eta, eta_d)
        else:
            arm = rot[k] @ params.body_params[k, 4:7]
            arm_rate = _cross(w[k], arm)
        loops.r_out[k] = r + arm
        loops.v_out[k] = v + arm_rate


@njit(cache=True, fastmath=CONTRACT)
def _side(params, loops, rot, w, c, s):
    """(body, point, velocity, arm from the body's output point, frame, angular velocity) of
    closing joint c's side s."""
    k = loops.body[c, s]
    local = loops.point[c, s]
    if k < 0:
        return k, loops.ground + local, np.zeros(3), local, loops.ground_rot, np.zeros(3)
    arm = rot[k] @ (local - params.body_params[k, 4:7])
    return (k, loops.r_out[k] + arm, loops.v_out[k] + _cross(w[k], arm), arm, rot[k], w[k])


@njit(cache=True, fastmath=CONTRACT)
def row_positions(params, loops, rot, w):
    """The rows' positions g and rates g' (loops.g, gd) at the points loops.r_out, v_out."""
    for r in range(loops.kind.shape[0]):
        c = loops.owner[r]
        _, p_a, v_a, _, f_a, w_a = _side(params, loops, rot, w, c, 0)
        _, p_b, v_b, _, f_b, w_b = _side(params, loops, rot, w, c, 1)
        if loops.kind[r] == DOT:
            x = f_a @ loops.v1[r]
            y = f_b @ loops.v2[r]
            loops.g[r] = x @ y
            loops.gd[r] = (w_b - w_a) @ _cross(y, x)
        else:
            e = loops.v1[r] if loops.kind[r] == GAP_WORLD else f_a @ loops.v1[r]
            d = p_b - p_a
            loops.g[r] = e @ d
            loops.gd[r] = e @ (v_b - v_a)
            if loops.kind[r] == GAP_A:
                loops.gd[r] += _cross(w_a, e) @ d


@njit(cache=True, fastmath=CONTRACT)
def row_values(params, loops, rot, w, acc, alpha, out):
    """Every row's value (the module docstring) from the output stations' accelerations acc
    (n, 3) and the bodies' angular accelerations alpha (n, 3)."""
    for r in range(loops.kind.shape[0]):
        c = loops.owner[r]
        ka, p_a, v_a, arm_a, f_a, w_a = _side(params, loops, rot, w, c, 0)
        kb, p_b, v_b, arm_b, f_b, w_b = _side(params, loops, rot, w, c, 1)
        acc_a, al_a, acc_b, al_b = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
        if ka >= 0:
            al_a = alpha[ka]
            acc_a = acc[ka] + _cross(al_a, arm_a) + _cross(w_a, _cross(w_a, arm_a))
        if kb >= 0:
            al_b = alpha[kb]
            acc_b = acc[kb] + _cross(al_b, arm_b) + _cross(w_b, _cross(w_b, arm_b))
        if loops.kind[r] == DOT:
            x = f_a @ loops.v1[r]
            y = f_b @ loops.v2[r]
            out[r] = (_cross(y, x) @ (al_b - al_a)
                      + (w_b - w_a) @ (_cross(_cross(w_b, y), x) + _cross(y, _cross(w_a, x))))
        else:
            e = loops.v1[r] if loops.kind[r] == GAP_WORLD else f_a @ loops.v1[r]
            out[r] = e @ (acc_b - acc_a)
            if loops.kind[r] == GAP_A:
                d = p_b - p_a
                we = _cross(w_a, e)
                out[r] += (_cross(e, d) @ al_a + _cross(w_a, we) @ d
                           + 2.0 * (we @ (v_b - v_a)))


@njit(cache=True, fastmath=CONTRACT)
def _unit_loads(params, loops, rot, w, r):
    """loops.loads[r + 1]: the loads of row r's unit multiplier on its sides' output stations,
    e = -[couple about O; force] (a station's e is what its body exerts outboard)."""
    load = loops.loads[r + 1]
    load[:, :] = 0.0
    c = loops.owner[r]
    ka, p_a, _, arm_a, f_a, _ = _side(params, loops, rot, w, c, 0)
    kb, p_b, _, arm_b, f_b, _ = _side(params, loops, rot, w, c, 1)
    if loops.kind[r] == DOT:
        x = f_a @ loops.v1[r]
        y = f_b @ loops.v2[r]
        couple = _cross(y, x)
        for i in range(3):
            if kb >= 0:
                load[kb, i] -= couple[i]
            if ka >= 0:
                load[ka, i] += couple[i]
        return
    e = loops.v1[r] if loops.kind[r] == GAP_WORLD else f_a @ loops.v1[r]
    if kb >= 0:                         # e on b at p_b
        m = _cross(arm_b, e)
        for i in range(3):
            load[kb, i] -= m[i]
            load[kb, 3 + i] -= e[i]
    if ka >= 0:                         # -e on a at p_b: arm from a's output point
        m = _cross(arm_a + (p_b - p_a), e)
        for i in range(3):
            load[ka, i] += m[i]
            load[ka, 3 + i] += e[i]


@njit(cache=True, fastmath=CONTRACT)
def _least_solve(a, b):
    """The least-norm x of a x = b by a truncated SVD (relative 1e-10)."""
    u, sv, vt = np.linalg.svd(a)
    x = np.zeros(a.shape[1])
    if sv.shape[0] == 0:
        return x
    ub = u.T @ b
    for i in range(sv.shape[0]):
        if sv[i] > 1e-10 * sv[0]:
            x += (ub[i] / sv[i]) * vt[i]
    return x


@njit(cache=True, fastmath=CONTRACT)
def closure_wrenches(params, loops, rot):
    """loops.wrench: each closing joint's force and couple on side b (world axes; the couple
    about b's point) from the multipliers loops.lam: a gap row's lam e, a dot row's couple
    lam (y x x) (the module docstring), with the rows' directions at the rotations rot."""
    loops.wrench[:, :] = 0.0
    for r in range(loops.kind.shape[0]):
        c = loops.owner[r]
        ka, kb = loops.body[c, 0], loops.body[c, 1]
        f_a = loops.ground_rot if ka < 0 else rot[ka]
        if loops.kind[r] == DOT:
            f_b = loops.ground_rot if kb < 0 else rot[kb]
            couple = _cross(f_b @ loops.v2[r], f_a @ loops.v1[r])
            for i in range(3):
                loops.wrench[c, 3 + i] += loops.lam[r] * couple[i]
        else:
            e = loops.v1[r] if loops.kind[r] == GAP_WORLD else f_a @ loops.v1[r]
            for i in range(3):
                loops.wrench[c, i] += loops.lam[r] * e[i]


@njit(cache=True, fastmath=CONTRACT)
def solve_with_loops(params, sweep, root_f, loops, rot, w, z):
    """The sweep with the closing joints' multipliers (the module docstring): the step and
    every row's response to its unit multiplier in one sweep (sweep_columns) into
    loops.z_save, nu_save, tau_save (angular-acceleration slots; column 0 the step without
    multipliers, column j + 1 row j's response), the Delassus matrix of the rows' values, the
    multipliers holding the rows at zero (acceleration level), and their superposition into z,
    sweep.joint_nu and joint_tau.  rot, w: the bodies' rotations and angular velocities the
    rows are written at, with their points in loops.r_out, v_out (tree_points).  Returns the
    sweep's status."""
    n = rot.shape[0]
    n_rows = loops.kind.shape[0]
    sw = sweep
    loops.loads[0] = 0.0
    for r in range(n_rows):
        _unit_loads(params, loops, rot, w, r)
    status = sweep_columns(sw.kind, sw.u, sw.joint_dof, sw.joint_tau_nu, params.parent, root_f,
                           sw.s, loops.p_col, sw.tree_s, loops.port_col, loops.h_store,
                           loops.k_store, loops.free_store, loops.z_save, loops.nu_save,
                           loops.tau_save, loops.loads)
    if status != 0:
        return status
    acc = np.zeros((n, 3))
    alpha = np.zeros((n, 3))
    kappa = np.empty(n_rows)
    row_values(params, loops, rot, w, acc, alpha, kappa)     # the rows' velocity terms
    for j in range(n_rows + 1):
        for k in range(n):
            acc[k] = loops.z_save[j, 2 * k + 2, 0:3]
            alpha[k] = loops.z_save[j, 2 * k + 1, 3:6]
        row_values(params, loops, rot, w, acc, alpha, loops.values[j])
    for r in range(n_rows):
        for j in range(n_rows):
            loops.delassus[r, j] = loops.values[j + 1, r] - kappa[r]
    lam = _least_solve(loops.delassus, -loops.values[0])
    loops.lam[:] = lam
    closure_wrenches(params, loops, rot)
    z[:, :] = loops.z_save[0]
    sw.joint_nu[:, :] = loops.nu_save[0]
    sw.joint_tau[:, :] = loops.tau_save[0]
    for j in range(n_rows):
        z += lam[j] * loops.z_save[j + 1]
        sw.joint_nu[:, :] += lam[j] * loops.nu_save[j + 1]
        sw.joint_tau[:, :] += lam[j] * loops.tau_save[j + 1]
    return 0


@njit(cache=True, fastmath=CONTRACT)
def _modal_responses(params, loops, eta_map):
    """loops.eta_col[j]: row j's response of the beams' eta'' (eta'' = eta_map [z_I; 1] at the
    beam's input station, step.py::_modal_accelerations; homogeneous: its linear part)."""
    body_kind, mode_off = params.beams[0], params.beams[3]
    for j in range(loops.kind.shape[0]):
        z = loops.z_save[j + 1]
        for k in range(body_kind.shape[0]):
            if body_kind[k] == BEAM:
                for i in range(mode_off[k], mode_off[k + 1]):
                    v = 0.0
                    for c in range(12):
                        v += eta_map[i, c] * z[2 * k + 1, c]
                    loops.eta_col[j, i] = v


@njit(cache=True, fastmath=CONTRACT)
def _dependent_frames(params, loops, state):
    """Every body whose frame follows its parent's, from the parent's (root to leaves, as
    step.py::_update): a joint child's by its coordinates (joint.joint_frame, a slide's offset
    too), a welded body's as the parent's (R0) or its beam's end section's (beam.
    end_section_motion)."""
    zero = np.zeros(3)
    scratch = np.empty(48)
    body_kind, mode_off, ends, bp = params.beams[0], params.beams[3], params.beams[4], \
        params.beams[1]
    for k in range(state.rot.shape[0]):
        hk = params.hinge_kind[k]
        p = params.parent[k]
        if p < 0:
            rot_p, w_p, wd_p = loops.ground_rot, zero, zero
        else:
            rot_p, w_p, wd_p = state.rot[p], state.omega[p], state.omega_dot[p]
        if n_coordinates(hk) > 0:
            joint_frame(hk, params.hinge_params[k], rot_p, w_p, wd_p, state.jq[k],
                        state.jqd[k], state.jqdd[k], state.rot[k], state.omega[k],
                        state.omega_dot[k], state.defl[k], state.defl_rate[k])
        elif hk == FIXED and p >= 0 and not params.locked[k]:
            rest = params.hinge_params[k, 0:9].copy().reshape((3, 3))
            if body_kind[p] == BEAM:
                i0, i1 = mode_off[p], mode_off[p + 1]
                m, mt = int(bp[p, MODES]), int(bp[p, TORSION_MODES])
                end_section_motion(ends[p, :m], ends[p, m:m + mt], rot_p, w_p, wd_p,
                                   state.eta[i0:i1], state.eta_d[i0:i1], state.eta_acc[i0:i1],
                                   rest, state.rot[k], state.omega[k], state.omega_dot[k],
                                   scratch)
            else:
                state.rot[k] = rot_p @ rest
                state.omega[k] = w_p
                state.omega_dot[k] = wd_p
        else:
            continue
        state.pseudo[k] = state.omega_dot[k]


@njit(cache=True, fastmath=CONTRACT)
def _add_rates(params, loops, state, j, f):
    """The free bodies' angular velocities, the joint coordinates' and the modal coordinates'
    rates += f times row j's response (of w', q'' and eta''), the dependent frames after them."""
    n = state.rot.shape[0]
    for k in range(n):
        for i in range(3):
            state.omega[k, i] += f * loops.z_save[j + 1, 2 * k + 1, 3 + i]
        for i in range(n_coordinates(params.hinge_kind[k])):
            state.jqd[k, i] += f * loops.nu_save[j + 1, k, i]
    for i in range(state.eta_d.shape[0]):
        state.eta_d[i] += f * loops.eta_col[j, i]
    _dependent_frames(params, loops, state)


@njit(cache=True, fastmath=CONTRACT)
def _move(params, loops, state, j, f, e3):
    """Turn every body by f times row j's response of w' (A <- exp(f dw'^) A) and move every
    joint and modal coordinate by f times its response of q'' and eta'' (the dependent frames
    follow in _dependent_frames)."""
    n = state.rot.shape[0]
    phi = np.empty(3)
    for k in range(n):
        for i in range(3):
            phi[i] = f * loops.z_save[j + 1, 2 * k + 1, 3 + i]
        expm_so3(phi, e3)
        state.rot[k] = e3 @ state.rot[k]
        for i in range(n_coordinates(params.hinge_kind[k])):
            state.jq[k, i] += f * loops.nu_save[j + 1, k, i]
    for i in range(state.eta.shape[0]):
        state.eta[i] += f * loops.eta_col[j, i]


@njit(cache=True, fastmath=CONTRACT)
def _residuals(params, loops, state):
    """The rows' positions and rates at the state (loops.g, gd); their largest (|g|, |g'|)."""
    tree_points(params, state.rot, state.omega, state.jq, state.jqd, state.eta, state.eta_d,
                loops)
    row_positions(params, loops, state.rot, state.omega)
    largest_g, largest_gd = 0.0, 0.0
    for r in range(loops.kind.shape[0]):
        largest_g = max(largest_g, abs(loops.g[r]))
        largest_gd = max(largest_gd, abs(loops.gd[r]))
    return largest_g, largest_gd


@njit(cache=True, fastmath=CONTRACT)
def project_onto_loops(params, loops, state):
    """After a step: the configuration and the rates moved back onto the loops along the step's
    responses to unit multipliers, dx_j (row j's response of w' and q'', the least change in
    the metric of the step's own matrix; consistent across the joints, whose kinematics are
    linear in the rates and, to first order, in the increments).  The rows' rates are linear
    in the rates, so V[:, j] = g'(dx_j) - g'(0) (the tree's kinematics, O(n) per row) is
    exact, and it is also the rows' positions' Jacobian along dx_j: Gauss-Newton with V moves
    the configuration, x <- x + sum_j mu_j dx_j, V mu = -g, until |g| <= POSITION_TOL (at most
    POSITION_PROJECTIONS times), then V mu = -g' moves the rates, twice at most.  Records the
    largest residuals before and after (loops.stats)."""
    n_rows = loops.kind.shape[0]
    e3 = np.empty((3, 3))
    _modal_responses(params, loops, state.eta_map)
    g0, gd0 = _residuals(params, loops, state)
    loops.stats[0] = max(loops.stats[0], g0)
    loops.stats[1] = max(loops.stats[1], gd0)
    base = loops.gd.copy()
    for j in range(n_rows):                 # V, column by column
        _add_rates(params, loops, state, j, 1.0)
        _residuals(params, loops, state)
        for r in range(n_rows):
            loops.delassus[r, j] = loops.gd[r] - base[r]
        _add_rates(params, loops, state, j, -1.0)
    largest = g0
    for _ in range(POSITION_PROJECTIONS):
        if largest <= POSITION_TOL:
            break
        mu = _least_solve(loops.delassus, -loops.g)
        for j in range(n_rows):
            _move(params, loops, state, j, mu[j], e3)
        _dependent_frames(params, loops, state)
        largest, _ = _residuals(params, loops, state)
    loops.stats[3] = max(loops.stats[3], largest)
    rates = 0.0
    for _ in range(2):
        _, rates = _residuals(params, loops, state)
        if rates <= RATE_TOL:
            break
        mu = _least_solve(loops.delassus, -loops.gd)
        for j in range(n_rows):
            _add_rates(params, loops, state, j, mu[j])
        _, rates = _residuals(params, loops, state)
    loops.stats[2] = max(loops.stats[2], rates)


# The tree's full-state sweep with many load columns (sweep.py::riccati_tree_full, "Trees in
# full state"): the Riccati matrices S once, a P per column.  Column 0 carries the transfers'
# affine parts, the drives' and prescribed motions' values and the ground's motion (the step
# itself); every other column only its loads at the output stations (a unit multiplier's
# response: the same linear step, homogeneous).  Per element:
#   T = U_ee - S_O U_fe,  S_I = T^-1 (S_O U_ff - U_ef),  P_I,c = T^-1 (S_O u_f,c + P_O,c - u_e,c)
# (u_c = u for column 0, zero otherwise); per joint, with y_c = S_O c'_c + P_O,c,
#   k_c = D^-1 (tau0_F,c - Bl_F^T y_c),  P_J,c = Psi (y_c + G k_c)
# and in the recovery nu_F,c = k_c - D^-1 Bl_F^T S_O Phi f_I,c.


@njit(cache=True, fastmath=CONTRACT)
def _element_columns(u, s_o, p_o, s_i, p_i, t, x):
    """Through an affine element z_O = U z_I + u: S_I and every column's P_I from the outboard
    S_O and P_O (C, 6), in one solve of T (the comment above; column 0 takes u's affine part);
    t (6, 6), x (6, 6 + C) scratch.  False if T is singular."""
    n_col = p_o.shape[0]
    for i in range(6):
        for j in range(6):
            tv = u[6 + i, 6 + j]
            xv = -u[6 + i, j]
            for m in range(6):
                tv -= s_o[i, m] * u[m, 6 + j]
                xv += s_o[i, m] * u[m, j]
            t[i, j] = tv
            x[i, j] = xv
        for c in range(n_col):
            pv = p_o[c, i]
            if c == 0:
                pv -= u[6 + i, 12]
                for m in range(6):
                    pv += s_o[i, m] * u[m, 12]
            x[i, 6 + c] = pv
    if not _gauss_solve(t, x, 6, 6 + n_col):
        return False
    for i in range(6):
        for j in range(6):
            s_i[i, j] = x[i, j]
        for c in range(n_col):
            p_i[c, i] = x[i, 6 + c]
    return True


@njit(cache=True, fastmath=CONTRACT)
def sweep_columns(kind, u, joint_dof, joint_drive, parent, root_f, s_mat, p_col, port_s,
                  port_p, h_store, k_store, free_store, z_col, nu_col, tau_col, loads):
    """The full-state tree sweep for loads.shape[0] columns at once (the comment above).
    loads (C, n, 6): each column's loads at the bodies' output stations (e = [m, q]); p_col
    (C, 2n + 1, 6), port_p (C, n, 6), h_store (n, 3, 6), k_store (C, n, 3), free_store (n, 4)
    scratch; writes each column's stations z_col (C, 2n + 1, 12), joints' nu_col and tau_col
    (C, n, 3).  Returns 0, or j + 1 for the element j whose elimination is singular (a LOCKED
    element, which only the consistent start of an elastic hinge has, is refused as one)."""
    n = parent.shape[0]
    n_col = loads.shape[0]
    port_s[:, :, :] = 0.0
    port_p[:, :, :] = loads
    t = np.empty((6, 6))
    x = np.empty((6, 6 + n_col))
    d = np.empty((3, 3))
    rhs = np.empty((3, 6 + n_col))
    g = np.empty((6, 3))
    for k in range(n - 1, -1, -1):
        jb, jh = 2 * k + 1, 2 * k
        # the body: T and S_I, and every column's P_I, in one solve
        if not _element_columns(u[jb], port_s[k], port_p[:, k], s_mat[jb], p_col[:, jb], t, x):
            return jb + 1
        kd = kind[jh]
        if kd == IDENTITY:
            s_mat[jh] = s_mat[jb]
            for c in range(n_col):
                p_col[c, jh] = p_col[c, jb]
        elif kd == TRANSFER:
            if not _element_columns(u[jh], s_mat[jb], p_col[:, jb], s_mat[jh], p_col[:, jh], t,
                                    x):
                return jh + 1
        elif kd == JOINT:
            uh = u[jh]
            s_o = s_mat[jb]
            mf = 0
            for c3 in range(3):
                if joint_dof[k, c3] == FREE:
                    free_store[k, mf] = c3
                    mf += 1
            free_store[k, 3] = mf
            s_phi = _mm(s_o, uh[0:6, 0:6])
            for a in range(mf):
                ca = free_store[k, a]
                for i in range(6):
                    gv = 0.0
                    for m in range(6):
                        gv += s_o[i, m] * uh[m, 6 + ca]
                    g[i, a] = gv
            # y_c = S_O c'_c + P_O,c: the affine part c' (prescribed coordinates too) in column 0
            y = np.empty((n_col, 6))
            for c in range(n_col):
                for i in range(6):
                    y[c, i] = p_col[c, jb, i]
            for i in range(6):
                ci = uh[i, 12]
                for c3 in range(3):
                    if joint_dof[k, c3] == PRESCRIBED:
                        ci += uh[i, 6 + c3] * joint_drive[k, c3, 2]
                for m in range(6):
                    y[0, m] += s_o[m, i] * ci
            for a in range(mf):
                ca = free_store[k, a]
                for j in range(6):
                    xv = 0.0
                    for i in range(6):
                        xv += uh[6 + i, ca] * s_phi[i, j]
                    rhs[a, j] = xv
                for c in range(n_col):
                    r = joint_drive[k, ca, 0] if c == 0 else 0.0
                    for i in range(6):
                        r -= uh[6 + i, ca] * y[c, i]
                    rhs[a, 6 + c] = r
                for b in range(mf):
                    xv = 0.0
                    for i in range(6):
                        xv += uh[6 + i, ca] * g[i, b]
                    d[a, b] = xv - (joint_drive[k, ca, 1] if a == b else 0.0)
            if mf > 0 and not _gauss_solve(d, rhs, mf, 6 + n_col):
                return jh + 1
            psi = uh[6:12, 6:12]
            s_e = s_phi.copy()
            for a in range(mf):
                for j in range(6):
                    h_store[k, a, j] = rhs[a, j]
                for c in range(n_col):
                    k_store[c, k, a] = rhs[a, 6 + c]
            for i in range(6):
                for a in range(mf):
                    for j in range(6):
                        s_e[i, j] -= g[i, a] * rhs[a, j]
            s_mat[jh] = _mm(psi, s_e)
            for c in range(n_col):
                p_e = y[c].copy()
                for i in range(6):
                    for a in range(mf):
                        p_e[i] += g[i, a] * rhs[a, 6 + c]
                p_col[c, jh] = _mv(psi, p_e)
        else:
            return jh + 1
        p = parent[k]
        if p >= 0:
            port_s[p] += s_mat[jh]
            for c in range(n_col):
                port_p[c, p] += p_col[c, jh]
    # the recovery, root to leaves, column by column
    f_i = np.empty(6)
    f_o = np.empty(6)
    for c in range(n_col):
        z = z_col[c]
        z[:, :] = 0.0
        if c == 0:
            z[0, 0:6] = root_f
        for k in range(n):
            jb, jh = 2 * k + 1, 2 * k
            p = parent[k]
            st = 0 if p < 0 else 2 * p + 2
            f_i[:] = z[st, 0:6]
            if p < 0:
                z[0, 6:12] += _mv(s_mat[jh], f_i) + p_col[c, jh]
            kd = kind[jh]
            if kd == IDENTITY:
                f_o[:] = f_i
            elif kd == TRANSFER:
                zi = np.empty(12)
                zi[0:6] = f_i
                zi[6:12] = _mv(s_mat[jh], f_i) + p_col[c, jh]
                f_o[:] = _mv(u[jh, 0:6, 0:12], zi)
                if c == 0:
                    f_o += u[jh, 0:6, 12]
            else:                       # JOINT
                for c3 in range(3):
                    nu_col[c, k, c3] = (joint_drive[k, c3, 2] if c == 0 and
                                        joint_dof[k, c3] == PRESCRIBED else 0.0)
                mf = free_store[k, 3]
                for a in range(mf):
                    xv = k_store[c, k, a]
                    for j in range(6):
                        xv -= h_store[k, a, j] * f_i[j]
                    nu_col[c, k, free_store[k, a]] = xv
                f_o[:] = _mv(u[jh, 0:6, 0:6], f_i)
                if c == 0:
                    f_o += u[jh, 0:6, 12]
                for c3 in range(3):
                    if joint_dof[k, c3] != 0:
                        for i in range(6):
                            f_o[i] += u[jh, i, 6 + c3] * nu_col[c, k, c3]
            z[jb, 0:6] = f_o
            z[jb, 6:12] = _mv(s_mat[jb], f_o) + p_col[c, jb]
            if kd == JOINT:
                for c3 in range(3):
                    xv = 0.0
                    if joint_dof[k, c3] != 0:
                        for i in range(6):
                            xv += u[jh, 6 + i, c3] * z[jb, 6 + i]
                    tau_col[c, k, c3] = xv
            z[jb + 1] = _mv(u[jb, :, 0:12], z[jb])
            if c == 0:
                z[jb + 1] += u[jb, :, 12]
    return 0
