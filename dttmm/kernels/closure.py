"""Closing joints in the general loop's step (docs/loops.md, "The step with loops").

The tree's full-state sweep (sweep.py::riccati_tree_full) is linear in the loads at its
stations.  Each scalar constraint r of a closing joint acts through one multiplier lam_r, its
loads on the sides' output stations the constraint's Jacobian transposed (a gap row: a force
lam_r e on side b at its point, -lam_r e on side a at the same point; a dot row: a couple
lam_r (y x x) on b, its opposite on a).  One sweep without them and one per row with
lam_r = 1 give the stations as affine functions of the multipliers; the rows' values

    gap (e world):   e . (a_b - a_a)
    gap (e in a):    e . (a_b - a_a) + (e x d) . alpha_a + (w_a x (w_a x e)) . d + 2 (w_a x e) . d'
    dot:             (y x x) . (alpha_b - alpha_a) + (w_b - w_a) . ((w_b x y) x x + y x (w_a x x))

(a point's acceleration a = a_O + alpha x arm + w x (w x arm) from its body's output station)
are held at zero, the constraints' second derivatives (acceleration level, as the consistent
start and the pinned tip hold theirs).  After the step the configuration and then the rates
are projected back onto the loops along the step's own responses to unit multipliers
(project_positions, project_rates), so that every step ends with its loops closed.

Scope (refused before a run otherwise, solver._check_loops): rigid bodies, a fixed ground;
every joint kind in the tree.
"""
from collections import namedtuple

import numpy as np
from numba import njit

from . import CONTRACT
from ..elements.hinges import AXIS_1
from ..elements.joints import PRISMATIC
from .joint import n_coordinates
from .so3 import expm_so3
from .sweep import riccati_tree_full

GROUND = -1
GAP_WORLD, GAP_A, DOT = 0, 1, 2

# the closing joints as the loop reads them, and the loop's scratch for them (solver.
# loop_tables): rows (R) and closing joints (m) in the kernel model's numbering
Loops = namedtuple("Loops", [
    "kind", "owner", "v1", "v2",     # (R,), (R,), (R, 3), (R, 3): GAP_WORLD / GAP_A / DOT, its
                                     # closing joint, e (or x, in a's frame) and y (b's frame)
    "body", "point",                 # (m, 2), (m, 2, 3): the sides' bodies and points (in the
                                     # body's frame from its input point; the ground's: world,
                                     # from the ground point)
    "ground", "ground_rot",          # (3,), (3, 3) the ground point and frame (a fixed ground)
    "targets",                       # (R,) the rows' targets (zero: acceleration level)
    "port_load",                     # (n, 6) scratch: the multipliers' loads on the stations
    "z_save", "nu_save", "tau_save",  # (R + 1, ...) each sweep's stations and joints
    "delassus", "lam", "values",     # (R, R), (R,), (R + 1, R)
    "r_out", "v_out",                # (n, 3) each: the output points' positions, velocities
    "g", "gd",                       # (R,) the rows' positions and rates
    "stats",                         # (4,) the run's largest position residual after a step
                                     # (before the projection), rate residual before and after
                                     # the rates' projection, position residual after its
])

AXIS_1_START = AXIS_1.start
POSITION_PROJECTIONS = 4     # Gauss-Newton projections of the positions after a step, at most
POSITION_TOL = 1e-13         # m, rad: where they stop


@njit(cache=True, fastmath=CONTRACT)
def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


@njit(cache=True, fastmath=CONTRACT)
def tree_points(params, rot, w, jq, jqd, loops):
    """Every body's output point and its velocity (loops.r_out, v_out) from the rotations,
    angular velocities and joint coordinates and rates: r_in = r_out,P + d (a slide's
    d = A_P n q), r_out = r_in + A l_IO (rigid bodies; the kernel model hangs every child at
    its parent's output point)."""
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
        arm = rot[k] @ params.body_params[k, 4:7]
        loops.r_out[k] = r + arm
        loops.v_out[k] = v + _cross(w[k], arm)


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
    """loops.port_load: the loads of row r's unit multiplier on its sides' output stations,
    e = -[couple about O; force] (a station's e is what its body exerts outboard)."""
    loops.port_load[:, :] = 0.0
    c = loops.owner[r]
    ka, p_a, _, arm_a, f_a, _ = _side(params, loops, rot, w, c, 0)
    kb, p_b, _, arm_b, f_b, _ = _side(params, loops, rot, w, c, 1)
    if loops.kind[r] == DOT:
        x = f_a @ loops.v1[r]
        y = f_b @ loops.v2[r]
        couple = _cross(y, x)
        for i in range(3):
            if kb >= 0:
                loops.port_load[kb, i] -= couple[i]
            if ka >= 0:
                loops.port_load[ka, i] += couple[i]
        return
    e = loops.v1[r] if loops.kind[r] == GAP_WORLD else f_a @ loops.v1[r]
    if kb >= 0:                         # e on b at p_b
        m = _cross(arm_b, e)
        for i in range(3):
            loops.port_load[kb, i] -= m[i]
            loops.port_load[kb, 3 + i] -= e[i]
    if ka >= 0:                         # -e on a at p_b: arm from a's output point
        m = _cross(arm_a + (p_b - p_a), e)
        for i in range(3):
            loops.port_load[ka, i] += m[i]
            loops.port_load[ka, 3 + i] += e[i]


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
def solve_with_loops(params, sweep, root_f, loops, rot, w, targets, z):
    """The sweep with the closing joints' multipliers (the module docstring): the base sweep
    and one per row into loops.z_save, nu_save, tau_save (angular-acceleration slots), the
    Delassus matrix of the rows' values, the multipliers holding the rows at targets, and
    their superposition into z, sweep.joint_nu and joint_tau.  rot, w: the bodies' rotations
    and angular velocities the rows are written at.  Returns the sweep's status."""
    n = rot.shape[0]
    n_rows = loops.kind.shape[0]
    sw = sweep
    acc = np.empty((n, 3))
    alpha = np.empty((n, 3))
    for j in range(n_rows + 1):
        if j == 0:
            loops.port_load[:, :] = 0.0
        else:
            _unit_loads(params, loops, rot, w, j - 1)
        status = riccati_tree_full(sw.kind, sw.u, sw.known_loads, sw.joint_dof,
                                   sw.joint_tau_nu, params.parent, root_f, sw.s, sw.p,
                                   sw.tree_s, sw.tree_p, sw.joint_nu, sw.joint_tau, z,
                                   loops.port_load)
        if status != 0:
            return status
        loops.z_save[j] = z
        loops.nu_save[j] = sw.joint_nu
        loops.tau_save[j] = sw.joint_tau
        for k in range(n):
            acc[k] = z[2 * k + 2, 0:3]
            alpha[k] = z[2 * k + 1, 3:6]
        row_values(params, loops, rot, w, acc, alpha, loops.values[j])
    for r in range(n_rows):
        for j in range(n_rows):
            loops.delassus[r, j] = loops.values[j + 1, r] - loops.values[0, r]
    lam = _least_solve(loops.delassus, targets - loops.values[0])
    loops.lam[:] = lam
    z[:, :] = loops.z_save[0]
    sw.joint_nu[:, :] = loops.nu_save[0]
    sw.joint_tau[:, :] = loops.tau_save[0]
    for j in range(n_rows):
        z += lam[j] * (loops.z_save[j + 1] - loops.z_save[0])
        sw.joint_nu[:, :] += lam[j] * (loops.nu_save[j + 1] - loops.nu_save[0])
        sw.joint_tau[:, :] += lam[j] * (loops.tau_save[j + 1] - loops.tau_save[0])
    return 0


@njit(cache=True, fastmath=CONTRACT)
def guess_points(params, loops, guess, jq_star, jqd_star):
    """The closing joints' points at the step's guess (rotations guess.rot, angular
    velocities guess.w, the joints' coordinates and rates), where the rows' velocity terms and
    the multipliers' arms are taken in a Newton iteration."""
    tree_points(params, guess.rot, guess.w, jq_star, jqd_star, loops)


@njit(cache=True, fastmath=CONTRACT)
def _add_rates(params, loops, state, j, f):
    """Every body's angular velocity and joint coordinate's rate += f times row j's response
    (the sweep's response of w' and q'' to row j's unit multiplier)."""
    n = state.rot.shape[0]
    for k in range(n):
        for i in range(3):
            state.omega[k, i] += f * (loops.z_save[j + 1, 2 * k + 1, 3 + i]
                                      - loops.z_save[0, 2 * k + 1, 3 + i])
        for i in range(n_coordinates(params.hinge_kind[k])):
            state.jqd[k, i] += f * (loops.nu_save[j + 1, k, i] - loops.nu_save[0, k, i])


@njit(cache=True, fastmath=CONTRACT)
def _field_size(loops, j):
    """The largest w' or q'' of row j's response (its unit multiplier's)."""
    size = 0.0
    for k in range(loops.z_save.shape[1]):
        for i in range(3, 6):
            size = max(size, abs(loops.z_save[j + 1, k, i] - loops.z_save[0, k, i]))
    for k in range(loops.nu_save.shape[1]):
        for i in range(3):
            size = max(size, abs(loops.nu_save[j + 1, k, i] - loops.nu_save[0, k, i]))
    return size


@njit(cache=True, fastmath=CONTRACT)
def _move(params, loops, state, j, f, e3):
    """Turn every body by f times row j's response of w' (A <- exp(f dw'^) A) and move every
    joint coordinate by f times its response of q''; a slide's offset follows."""
    n = state.rot.shape[0]
    phi = np.empty(3)
    for k in range(n):
        for i in range(3):
            phi[i] = f * (loops.z_save[j + 1, 2 * k + 1, 3 + i] - loops.z_save[0, 2 * k + 1, 3 + i])
        expm_so3(phi, e3)
        state.rot[k] = e3 @ state.rot[k]
        for i in range(n_coordinates(params.hinge_kind[k])):
            state.jq[k, i] += f * (loops.nu_save[j + 1, k, i] - loops.nu_save[0, k, i])


@njit(cache=True, fastmath=CONTRACT)
def _slides(params, loops, state):
    """Every slide's offset d = u q and rate d' = w_P x d + u q' from the state (joint.py)."""
    for k in range(state.rot.shape[0]):
        if params.hinge_kind[k] == PRISMATIC:
            p = params.parent[k]
            rot_p = loops.ground_rot if p < 0 else state.rot[p]
            u = rot_p @ params.hinge_params[k, AXIS_1_START:AXIS_1_START + 3]
            w_p = np.zeros(3) if p < 0 else state.omega[p]
            state.defl[k] = u * state.jq[k, 0]
            state.defl_rate[k] = _cross(w_p, state.defl[k]) + u * state.jqd[k, 0]


@njit(cache=True, fastmath=CONTRACT)
def project_positions(params, loops, state):
    """After a step: the configuration moved onto the loops along the step's responses to unit
    multipliers (x <- x + sum_j mu_j dx_j, dx_j row j's response of w' and q'' taken as a
    rotation and a coordinate change: the least change in the metric of the step's own
    matrix), by Gauss-Newton on the rows' positions (their Jacobian along each response by a
    difference of 1e-7 rad or m), until they are below POSITION_TOL or after
    POSITION_PROJECTIONS; records the largest position residual before (loops.stats[0])."""
    n_rows = loops.kind.shape[0]
    e3 = np.empty((3, 3))
    g0 = np.empty(n_rows)
    for it in range(POSITION_PROJECTIONS + 1):
        tree_points(params, state.rot, state.omega, state.jq, state.jqd, loops)
        row_positions(params, loops, state.rot, state.omega)
        largest = 0.0
        for r in range(n_rows):
            largest = max(largest, abs(loops.g[r]))
        if it == 0:
            loops.stats[0] = max(loops.stats[0], largest)
        if largest <= POSITION_TOL or it == POSITION_PROJECTIONS:
            break
        g0[:] = loops.g
        for j in range(n_rows):
            size = _field_size(loops, j)
            eps = 1e-7 / size if size > 0.0 else 0.0
            if eps == 0.0:
                loops.delassus[:, j] = 0.0
                continue
            _move(params, loops, state, j, eps, e3)
            tree_points(params, state.rot, state.omega, state.jq, state.jqd, loops)
            row_positions(params, loops, state.rot, state.omega)
            for r in range(n_rows):
                loops.delassus[r, j] = (loops.g[r] - g0[r]) / eps
            _move(params, loops, state, j, -eps, e3)
        mu = _least_solve(loops.delassus, -g0)
        for j in range(n_rows):
            _move(params, loops, state, j, mu[j], e3)
        _slides(params, loops, state)
    loops.stats[3] = max(loops.stats[3], largest)


@njit(cache=True, fastmath=CONTRACT)
def project_rates(params, loops, state):
    """After a step: the rows' positions and rates at the new state (loops.stats), then the
    rates projected onto the loops along the step's responses to unit multipliers: every
    body's angular velocity and every joint coordinate's rate change by sum_j mu_j dv_j, dv_j
    the sweep's response of w' and q'' to row j (the least change in the metric of the step's
    own matrix), consistent with each other (the joints' kinematics are linear in the rates);
    the rows' rates are linear in the rates, so V[:, j] = g'(dv_j) - g'(0) is exact and
    V mu = -g' holds them at zero in one solve."""
    n_rows = loops.kind.shape[0]
    tree_points(params, state.rot, state.omega, state.jq, state.jqd, loops)
    row_positions(params, loops, state.rot, state.omega)
    largest_gd = 0.0
    for r in range(n_rows):
        largest_gd = max(largest_gd, abs(loops.gd[r]))
    loops.stats[1] = max(loops.stats[1], largest_gd)
    gd0 = loops.gd.copy()
    for j in range(n_rows):             # V, column by column (the row's response alone)
        _add_rates(params, loops, state, j, 1.0)
        tree_points(params, state.rot, state.omega, state.jq, state.jqd, loops)
        row_positions(params, loops, state.rot, state.omega)
        for r in range(n_rows):
            loops.delassus[r, j] = loops.gd[r] - gd0[r]
        _add_rates(params, loops, state, j, -1.0)
    mu = _least_solve(loops.delassus, -gd0)
    for j in range(n_rows):
        _add_rates(params, loops, state, j, mu[j])
    tree_points(params, state.rot, state.omega, state.jq, state.jqd, loops)
    row_positions(params, loops, state.rot, state.omega)
    after = 0.0
    for r in range(n_rows):
        after = max(after, abs(loops.gd[r]))
    loops.stats[2] = max(loops.stats[2], after)
    _slides(params, loops, state)
