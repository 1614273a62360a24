"""The generalized-alpha scheme element by element (docs/solver.md, "The step"; the scheme in
step.py's docstring): its coefficients and offsets, and for each kind of element the guess the
predictor makes (a body's rotation increment, a beam's modal coordinates, a joint's coordinates,
an elastic hinge's deflection, a welded or locked body's frame) and the advance the update makes
from the converged step.  The general loop's pieces that call them are in step.py.
"""
import numpy as np
from numba import njit

from .. import CONTRACT, allocating_kernel, kernel, model_tables
from ...elements import BEAM, RIGID, ROD
from ...elements.beam import MODES, TORSION_MODES
from ...elements.drives import MOTION
from ...elements.kinds import MAX_COORDINATES, UNDECLARED_BODY_KIND
from ..transfers.beam_relations import end_section_motion
from ..transfers.strain_rod import rod_end_frame, rod_tables_of
from ..transfers.hinge import elastic_hinge_loads
from ..transfers.joint import drive_share, joint_frame, n_coordinates
from ..algebra.mat3 import matmul, matmul_into, matvec, mm3_into, put1
from ..algebra.so3 import expm_so3, left_jacobian, log_so3


@kernel
def _integrator_coefficients(h, coef):
    beta, gamma, alpha_m, alpha_f = coef[0], coef[1], coef[2], coef[3]
    c1 = (1.0 - alpha_m) / ((1.0 - alpha_f) * beta * h * h)
    c3 = gamma / (beta * h)
    return c1, c3


@kernel
def _offsets(h, coef, v, acc, p):
    """w1, w3 with acc_{n+1} = c1 x + w1, v_{n+1} = c3 x + w3 (x the increment over the step)."""
    w1 = np.empty_like(v)
    w3 = np.empty_like(v)
    _offsets_into(h, coef, v, acc, p, w1, w3, np.empty_like(v))
    return w1, w3


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _offsets_into(h, coef, v, acc, p, w1, w3, x_pred):
    """_offsets in place, with the constant-acceleration predictor x_pred = h v + h^2 p / 2
    (elementwise, no temporaries: it runs for every body and step)."""
    beta, gamma, alpha_m, alpha_f = coef[0], coef[1], coef[2], coef[3]
    ratio = (1.0 - alpha_m) / (1.0 - alpha_f)
    for i in range(v.shape[0]):
        known = h * v[i] + h * h * (0.5 - beta) * p[i]
        w1[i] = (-ratio * known / (beta * h * h)
                 + (alpha_m * p[i] - alpha_f * acc[i]) / (1.0 - alpha_f))
        w3[i] = v[i] + h * (1.0 - gamma) * p[i] - gamma / (beta * h) * known
        x_pred[i] = h * v[i] + 0.5 * h * h * p[i]


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _advance_history(h, coef, x, v, acc, p):
    """In place: v, acc, p at t_{n+1} from the increment x."""
    beta, gamma, alpha_m, alpha_f = coef[0], coef[1], coef[2], coef[3]
    for i in range(x.shape[0]):
        p_new = (x[i] - h * v[i] - h * h * (0.5 - beta) * p[i]) / (beta * h * h)
        v[i] += h * (1.0 - gamma) * p[i] + h * gamma * p_new
        acc[i] = ((1.0 - alpha_m) * p_new + alpha_m * p[i] - alpha_f * acc[i]) / (1.0 - alpha_f)
        p[i] = p_new


@allocating_kernel
def _hinge_deflection(params, z, w1d, c1, k):
    """Elastic hinge k's deflection d (world) at the step's end from its stations'
    accelerations: a_in - a_out,P = c1 d + w1d (docs/solver.md), the inboard station the
    parent's output (0: the ground)."""
    i_in, i_p = 2 * k + 1, 2 * model_tables.parent(params)[k] + 2
    return ((z[i_in, 0] - z[i_p, 0] - w1d[k, 0]) / c1, (z[i_in, 1] - z[i_p, 1] - w1d[k, 1]) / c1,
            (z[i_in, 2] - z[i_p, 2] - w1d[k, 2]) / c1)


@allocating_kernel
def _body_kinematics(c1, c3, rot_n, phi, w1, w3, rot, lam, w, wd, dw, dwd):
    """A body's rotation, angular velocity and acceleration at the end of the step as functions
    of its world rotation increment phi, with their derivatives (docs/solver.md):
    A = exp(phi^) A_n, w = c3 phi + w3, w' = c1 phi + w1."""
    e3 = np.empty((3, 3))
    expm_so3(phi, e3)
    matmul_into(e3, rot_n, rot)
    left_jacobian(phi, lam)
    for i in range(3):
        w[i] = c3 * phi[i] + w3[i]
        wd[i] = c1 * phi[i] + w1[i]
        for j in range(3):
            dw[i, j] = c3 if i == j else 0.0
            dwd[i, j] = c1 if i == j else 0.0


@kernel
def _joint_child_guess(kind, hp, parent_frame, q, qd, qdd, c1, c3, rot_n, phi, w1, w3, rot, lam,
                       w, wd, dw, dwd):
    """A joint child's guess: its frame from the parent's guess and the coordinates' (kernels/
    joint.py::joint_frame), written as a body's kinematics in its rotation increment phi =
    log(A A_n^T) with the offsets that make w = c3 phi + w3, w' = c1 phi + w1 hold at the guess
    (the element kernels' derivatives in phi are then those of a body integrated on its own: a
    Jacobian exact to O(c3/c1) terms, docs/joints.md)."""
    rot_p, w_p, wd_p = parent_frame
    d = np.empty(3)
    d_rate = np.empty(3)
    joint_frame(kind, hp, rot_p, w_p, wd_p, q, qd, qdd, rot, w, wd, d, d_rate)
    rel = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            rel[i, j] = rot[i, 0] * rot_n[j, 0] + rot[i, 1] * rot_n[j, 1] + rot[i, 2] * rot_n[j, 2]
    log_so3(rel, phi)
    for i in range(3):
        w1[i] = wd[i] - c1 * phi[i]
        w3[i] = w[i] - c3 * phi[i]
    _body_kinematics(c1, c3, rot_n, phi, w1, w3, rot, lam, w, wd, dw, dwd)


@kernel
def _end_section_frame(params, k, rest, rot, w, wd, eta, eta_d, eta_dd, rot_out, w_out, wd_out):
    """The frame welded to beam k's end section (rest: the weld's R0) from the beam's frame and
    modal coordinates (docs/beam.md, "End sections"; beam.end_section_motion): A_O = A
    exp(theta^) R0, theta = [psi(L), -w'(L), v'(L)]; w_O = w + A J_l(theta) theta';
    w_O' = w' + w x (A J_l theta') + A (J_l theta'' + DJ_l(theta)[theta'] theta') (exact; its
    leading term theta' x (theta x theta') / 6 alone left the twisting arm of
    tests/test_torsion.py an energy error of 4e-5 that did not fall with dt)."""
    mode_off, ends = model_tables.mode_offset(params), model_tables.beam_ends(params)
    beam_params = model_tables.beam_params(params)
    i0, i1 = mode_off[k], mode_off[k + 1]
    m = int(beam_params[k, MODES])
    bending, twist = ends[k, :m], ends[k, m:m + int(beam_params[k, TORSION_MODES])]
    end_section_motion(bending, twist, rot, w, wd, eta[i0:i1], eta_d[i0:i1], eta_dd[i0:i1],
                       rest, rot_out, w_out, wd_out, np.empty(48))


@allocating_kernel
def _welded_frame(params, k, rot, w, wd, eta, eta_d, eta_dd, rot_out, w_out, wd_out):
    """The frame of a welded body (_welded) from its parent's: A = A_P R0, w = w_P, w' = w_P',
    or the end section's of a parent beam (_end_section_frame) or strain rod
    (strain_rod.rod_end_frame); a parent's kind code none of these names is refused
    (elements/kinds.py, UNDECLARED_BODY_KIND)."""
    p = model_tables.parent(params)[k]
    hinge_params, hinge_row = model_tables.hinge_params(params), model_tables.hinge_row(params)
    rest = hinge_params[hinge_row[k], 0:9].copy().reshape((3, 3))
    body_kind = model_tables.body_kind(params)
    if body_kind[p] == BEAM:
        _end_section_frame(params, p, rest, rot[p], w[p], wd[p], eta, eta_d, eta_dd,
                           rot_out, w_out, wd_out)
    elif body_kind[p] == ROD:
        mode_off = model_tables.mode_offset(params)
        i0, i1 = mode_off[p], mode_off[p + 1]
        steps, xi0, phi = rod_tables_of(params, p)[:3]
        rod_end_frame(steps, xi0, phi, rot[p], w[p], wd[p], eta[i0:i1], eta_d[i0:i1],
                      eta_dd[i0:i1], rest, rot_out, w_out, wd_out)
    elif body_kind[p] == RIGID:
        mm3_into(rot[p], rest, rot_out)
        put1(w_out, w[p])
        put1(wd_out, wd[p])
    else:
        raise ValueError(UNDECLARED_BODY_KIND)


@allocating_kernel
def _welded_guess(params, k, c1, c3, w1e, w3e, eta_n, eta_dd_star, rot_n, guess, w1, w3):
    """A welded body's guess from its parent's (_welded_frame; a beam's modal coordinates at
    their guess), with the offsets that make w = c3 phi + w3, w' = c1 phi + w1 hold at it (as
    _joint_child_guess)."""
    phi_star, rot_star, lam, w, wd, dw, dwd = guess
    eta = (eta_dd_star - w1e) / c1 if eta_n.shape[0] > 0 else eta_n.copy()
    eta_d = c3 * eta + w3e
    _welded_frame(params, k, rot_star, w, wd, eta, eta_d, eta_dd_star, rot_star[k], w[k],
                  wd[k])
    rel = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            rel[i, j] = (rot_star[k, i, 0] * rot_n[j, 0] + rot_star[k, i, 1] * rot_n[j, 1]
                         + rot_star[k, i, 2] * rot_n[j, 2])
    log_so3(rel, phi_star[k])
    for i in range(3):
        w1[i] = wd[k, i] - c1 * phi_star[k, i]
        w3[i] = w[k, i] - c3 * phi_star[k, i]
    _body_kinematics(c1, c3, rot_n, phi_star[k], w1, w3, rot_star[k], lam[k], w[k], wd[k],
                     dw[k], dwd[k])


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _coordinates_from_nu(c1, c3, q_n, w1q, w3q, nu, q, qd, qdd):
    """A coordinate's guess from its acceleration nu: dq = (nu - w1q) / c1."""
    dq = (nu - w1q) / c1
    q[0] = q_n + dq
    qd[0] = c3 * dq + w3q
    qdd[0] = nu


@allocating_kernel
def _ground_guess(rot_before, rot_now, g_w, g_wd, ground):
    """The ground's motion over the step into ground = (rot, lam, w, wd, dwd, phi): its rotation
    increment phi = log(R_{s+1} R_s^T) and left Jacobian, its rotation and rates at t_{s+1}."""
    g_rot, g_lam, w, wd, _, phi = ground
    rel = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            rel[i, j] = (rot_now[i, 0] * rot_before[j, 0] + rot_now[i, 1] * rot_before[j, 1]
                         + rot_now[i, 2] * rot_before[j, 2])
            g_rot[i, j] = rot_now[i, j]
        w[i] = g_w[i]
        wd[i] = g_wd[i]
    log_so3(rel, phi)
    left_jacobian(phi, g_lam)


@allocating_kernel
def _modal_guess(h, coef, c1, c3, eta, eta_d, eta_acc, eta_p, w1e, w3e, eta_dd_star):
    """The modal coordinates' offsets (eta'' = c1 eta + w1e, eta' = c3 eta + w3e) and their
    predicted accelerations eta''* (constant-acceleration predictor)."""
    a1, a3 = _offsets(h, coef, eta_d, eta_acc, eta_p)
    for i in range(eta.shape[0]):
        w1e[i] = a1[i] - c1 * eta[i]
        w3e[i] = a3[i] - c3 * eta[i]
        eta_dd_star[i] = c1 * (eta[i] + h * eta_d[i] + 0.5 * h * h * eta_p[i]) + w1e[i]


@allocating_kernel
def _joint_guess(hk, hp, drive, given, h, coef, c1, c3, q, qd, qdd, qp, w1q, w3q, q_s, qd_s,
                 qdd_s, frame, rot_n, phi, w1, w3, rot, lam, w, wd, dw, dwd):
    """A joint's coordinates' guess for the step (a prescribed motion's from its input given
    (3, 3) at t_{s+1}, the others' by the constant-acceleration predictor), their offsets
    w1q, w3q, and its child's guess from the parent's frame (_joint_child_guess)."""
    x_pred = np.empty(MAX_COORDINATES)
    _offsets_into(h, coef, qd, qdd, qp, w1q, w3q, x_pred)
    for i in range(n_coordinates(hk)):
        if drive[i, 0] == MOTION:
            q_s[i] = given[i, 0]
            qd_s[i] = given[i, 1]
            qdd_s[i] = given[i, 2]
            dq = q_s[i] - q[i]
            w1q[i] = qdd_s[i] - c1 * dq
            w3q[i] = qd_s[i] - c3 * dq
        else:
            _coordinates_from_nu(c1, c3, q[i], w1q[i], w3q[i], c1 * x_pred[i] + w1q[i],
                                 q_s[i:i + 1], qd_s[i:i + 1], qdd_s[i:i + 1])
    _joint_child_guess(hk, hp, frame, q_s, qd_s, qdd_s, c1, c3, rot_n, phi, w1, w3, rot, lam, w,
                       wd, dw, dwd)


@allocating_kernel
def _locked_guess(rel, ground, c1, c3, phi, rot, lam, w, wd, dw, dwd, w1, w3):
    """A locked body moves with the ground (its rotation relative to the ground's: rel), with
    the offsets that make w' = c1 phi + w1, w = c3 phi + w3 hold the ground's values (beams use
    them)."""
    g_rot, g_lam, g_w, g_wd, g_dwd, phi_g = ground
    matmul_into(g_rot, rel, rot)
    for i in range(3):
        phi[i] = phi_g[i]
        w[i] = g_w[i]
        wd[i] = g_wd[i]
        w1[i] = g_wd[i] - c1 * phi_g[i]
        w3[i] = g_w[i] - c3 * phi_g[i]
        for j in range(3):
            lam[i, j] = g_lam[i, j]
            dw[i, j] = c3 if i == j else 0.0
            dwd[i, j] = g_dwd[i, j]


@allocating_kernel
def _deflection_offsets(h, coef, c1, c3, d, d_rate, d_acc, d_pseudo, w1d, w3d):
    """An elastic hinge's deflection's offsets over the step (as a modal coordinate's)."""
    a1, a3 = _offsets(h, coef, d_rate, d_acc, d_pseudo)
    for i in range(3):
        w1d[i] = a1[i] - c1 * d[i]
        w3d[i] = a3[i] - c3 * d[i]


@allocating_kernel
def _station_offsets(h, coef, histories):
    """The paper's scheme: every station point's and mass centre's offset w1_X (a_X = c1 dr_X +
    w1_X)."""
    _, st_v, st_a, st_p, c_v, c_a, c_p, w1_st, w1_c = histories
    for j in range(st_v.shape[0]):
        w1, _ = _offsets(h, coef, st_v[j], st_a[j], st_p[j])
        put1(w1_st[j], w1)
    for k in range(c_v.shape[0]):
        w1, _ = _offsets(h, coef, c_v[k], c_a[k], c_p[k])
        put1(w1_c[k], w1)


@allocating_kernel
def _stations_guess(z, phi_g, phi_star, z_star):
    """The stations' guess: the last step's states with the predicted rotation increments in
    the phi slots."""
    for j in range(z.shape[0]):
        for i in range(12):
            z_star[j, i] = z[j, i]
    for i in range(3):
        z_star[0, 3 + i] = phi_g[i]
    for k in range(phi_star.shape[0]):
        for i in range(3):
            z_star[2 * k + 1, 3 + i] = phi_star[k, i]
            z_star[2 * k + 2, 3 + i] = phi_star[k, i]


@allocating_kernel
def _spring_guess(hp, rot_in, rot, w_any, d, d_rate, d_pseudo, h, c3, w3d, into_inboard, z_in,
                  z_out):
    """An elastic hinge's spring force at the predicted deflection into its stations' guess: an
    O(h^3) guess, where the last step's force is only O(h) (the hinge's d x q is bilinear in
    two unknowns).  The force does not depend on the angular velocities: any will do for them."""
    d_pred = d + h * d_rate + 0.5 * h * h * d_pseudo
    q_pred, _, _ = elastic_hinge_loads(hp, rot_in, w_any, rot, w_any, d_pred, c3 * d_pred + w3d)
    for i in range(3):
        if into_inboard:
            z_in[9 + i] = q_pred[i]
        z_out[9 + i] = q_pred[i]


@allocating_kernel
def _joint_adopt(hk, hp, drive, c1, c3, q, w1q, w3q, nu, q_s, qd_s, qdd_s, frame, rot_n, phi,
                 w1, w3, rot, lam, w, wd, dw, dwd, z_in, z_out):
    """A joint's coordinates' new guess from their accelerations nu (a prescribed motion's stays
    as given), its child's guess from the parent's frame, and the child's phi slots."""
    for i in range(n_coordinates(hk)):
        if drive[i, 0] != MOTION:
            _coordinates_from_nu(c1, c3, q[i], w1q[i], w3q[i], nu[i], q_s[i:i + 1],
                                 qd_s[i:i + 1], qdd_s[i:i + 1])
    _joint_child_guess(hk, hp, frame, q_s, qd_s, qdd_s, c1, c3, rot_n, phi, w1, w3, rot, lam, w,
                       wd, dw, dwd)
    for i in range(3):
        z_in[3 + i] = phi[i]
        z_out[3 + i] = phi[i]


@allocating_kernel
def _advance_stations(h, coef, c1, z, rot_now, rot, body_kind, locked, lock_rel, body_params,
                      body_row, histories):
    """The paper's scheme: every station point's and rigid mass centre's history over the step
    from its displacement, a_X = c1 dr_X + w1_X (before the bodies' rotations advance)."""
    _, st_v, st_a, st_p, c_v, c_a, c_p, w1_st, w1_c = histories
    e3 = np.empty((3, 3))
    for k in range(rot.shape[0]):
        x_in = (z[2 * k + 1, 0:3] - w1_st[k]) / c1
        x_out = (z[2 * k + 2, 0:3] - w1_st[k + 1]) / c1
        if body_kind[k] == RIGID:
            if locked[k]:
                rot_new = matmul(rot_now, lock_rel[k])
            else:
                expm_so3(z[2 * k + 1, 3:6], e3)
                rot_new = matmul(e3, rot[k])
            x_c = x_in + matvec(rot_new - rot[k], body_params[body_row[k], 1:4])
            _advance_history(h, coef, x_c, c_v[k], c_a[k], c_p[k])
        elif body_kind[k] != BEAM:      # (a beam's stations only; the scheme runs no other)
            raise ValueError(UNDECLARED_BODY_KIND)
        _advance_history(h, coef, x_out, st_v[k + 1], st_a[k + 1], st_p[k + 1])


@allocating_kernel
def _advance_modal(h, coef, c1, eta_dd_new, w1e, eta, eta_d, eta_acc, eta_p):
    """The modal coordinates' histories over the step from their new accelerations; returns
    whether every rate is finite."""
    x = np.empty(eta.shape[0])
    for i in range(eta.shape[0]):
        x[i] = (eta_dd_new[i] - w1e[i]) / c1 - eta[i]
    _advance_history(h, coef, x, eta_d, eta_acc, eta_p)
    finite = True
    for i in range(eta.shape[0]):
        eta[i] = (eta_dd_new[i] - w1e[i]) / c1
        finite = finite and np.isfinite(eta_d[i])
    return finite


@allocating_kernel
def _advance_joint(hk, hp, drive, given, h, coef, c1, nu, tau, w1q, q, qd, qdd, qp, jtau, frame,
                   rot, w, wd, d, d_rate, pseudo):
    """A joint's coordinates' histories over the step from their accelerations nu (a prescribed
    motion's: as given (3, 3) at t_{s+1}), then its child's frame from the parent's new one
    (kernels/transfers/joint.py::joint_frame)."""
    x = np.zeros(MAX_COORDINATES)
    for i in range(n_coordinates(hk)):
        x[i] = (nu[i] - w1q[i]) / c1
        if drive[i, 0] == MOTION:
            x[i] = given[i, 0] - q[i]
    _advance_history(h, coef, x, qd, qdd, qp)
    for i in range(n_coordinates(hk)):
        q[i] += x[i]
        if drive[i, 0] == MOTION:
            q[i] = given[i, 0]
            qd[i] = given[i, 1]
            qdd[i] = given[i, 2]
        jtau[i] = drive_share(hp, drive, i, tau[i], q[i], qd[i])
    rot_p, w_p, wd_p = frame
    joint_frame(hk, hp, rot_p, w_p, wd_p, q, qd, qdd, rot, w, wd, d, d_rate)
    for i in range(3):
        pseudo[i] = wd[i]


@allocating_kernel
def _advance_body(h, coef, phi, rot, w, wd, p, e3, rot_prev):
    """A body integrated on its own: its angular velocity's history from its rotation increment
    phi, and its rotation A = exp(phi^) A_n (e3, rot_prev: scratch)."""
    _advance_history(h, coef, phi, w, wd, p)
    expm_so3(phi, e3)
    for i in range(3):
        for j in range(3):
            rot_prev[i, j] = rot[i, j]
    matmul_into(e3, rot_prev, rot)


@allocating_kernel
def _locked_frame(rot_now, rel, g_w, g_wd, rot, w, wd):
    """A locked body's frame from the ground's at the step's end."""
    matmul_into(rot_now, rel, rot)
    for i in range(3):
        w[i] = g_w[i]
        wd[i] = g_wd[i]


@allocating_kernel
def _advance_deflection(params, z, w1d, c1, k, h, coef, d, d_rate, d_acc, d_pseudo):
    """An elastic hinge's deflection's history over the step from its stations (the hinge's
    deflection at the step's end: _hinge_deflection)."""
    d_new = _hinge_deflection(params, z, w1d, c1, k)
    x = np.empty(3)
    for i in range(3):
        x[i] = d_new[i] - d[i]
    _advance_history(h, coef, x, d_rate, d_acc, d_pseudo)
    for i in range(3):
        d[i] = d_new[i]
