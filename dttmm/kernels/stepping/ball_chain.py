"""The time loop fused for chains of rigid bodies and beams joined by ball joints
(docs/assembly.md, "The fused ball-chain step").

The same step as the general loop (kernels/stepping/step.py) in RICCATI_REDUCED mode (Newmark
scheme), as a loop variant of the one skeleton (kernels/stepping/loop.py), on preallocated arrays:
each rigid body's reduced 6 x 7 map on [a; q; 1] is written directly in angular-acceleration slots
(no 12 x 13 transfer), and so is each beam's (kernels/transfers/beam.py::beam_ball_map); each map
goes straight into its Riccati step.  Results agree with the general loop to rounding
(tests/test_ball_chain.py).
"""
import numpy as np
from numba import njit

from ...elements import BEAM, RIGID
from .. import (CONTRACT, fused_tables, input_tables, kernel, loop_piece, model_tables,
                record_tables, state_tables, sweep_tables)
from ..schema import FUSED_LAYOUT, FlatFused, FlatFusedTree
from ..transfers.beam import ball_map_work_shape, beam_ball_map
from ..transfers.body import kappa_values, rigid_point_jacobian_values
from ..algebra.mat3 import (mm3_into, t_cross, t_hat, t_hat_mul, t_inverse, t_lin3, t_lin9, t_mm,
                            t_mmt, t_mul_hat, t_mv, t_of_mat, t_of_vec, t_outer, t_plus_diag)
from ..algebra.so3 import expm_so3, left_jacobian, log_so3
from .loop import NOT_FINITE, OK, SINGULAR, UNSUPPORTED, loop_variant
from .generalized_alpha import _advance_history, _offsets_into
from .step import fused_coefficients
from ..assembly.sweep import riccati_reduced_recover, riccati_reduced_step, riccati_reduced_tip


@njit(cache=True, inline='always', fastmath=CONTRACT)
def ball_body_map(p, rot, lam, w, wd, s, r, a_i, q_i, load, torque, v, pmap):
    """Body k's reduced map in angular-acceleration slots (docs/assembly.md, "The fused
    ball-chain step"), linearized about the guess (phi*, a_I*, q_I*):
      [a_O; q_O] = v [a_I; q_I; 1],   alpha = pmap [a_I; q_I; 1]  (the angular acceleration).
    p: body parameter row (mass, l_IC, l_IO, J_I); rot, lam: A* and J_l(phi*); w, wd: angular
    velocity and acceleration at phi*; s = 1/c1, r = c3/c1 (d w / d alpha = r I, d phi / d alpha
    = s I); load f = M g + F at the mass centre, torque applied.  Written on values
    (kernels/algebra/mat3.py's tuples): every intermediate stays in registers."""
    mass = p[0]
    a = t_of_mat(rot)
    lm = t_of_mat(lam)
    w_ = t_of_vec(w)
    wd_ = t_of_vec(wd)
    a_in = t_of_vec(a_i)
    q_in = t_of_vec(q_i)
    f = t_of_vec(load)
    rho = t_mv(a, (p[4], p[5], p[6]))                      # A* l_IO
    rho_c = t_mv(a, (p[1], p[2], p[3]))                    # A* l_IC
    arm = t_lin3(1.0, rho, -1.0, rho_c)
    kmat = kappa_values(w_, wd_)                            # kappa(x) = K x
    kap_o = t_mv(kmat, rho)
    kap_c = t_mv(kmat, rho_c)
    d_o = rigid_point_jacobian_values(rho, w_, kmat, lm, s, r)
    d_c = rigid_point_jacobian_values(rho_c, w_, kmat, lm, s, r)
    # J = A* J_I A*^T, and the moment relation's values at the guess (docs/rigid_body.md):
    # q_O = q_I + f - M (a_I + kappa_C),
    # m_O = -rho x q_O + rho_C x f + torque - (J w' + w x J w + M rho_C x a_I)
    jm = t_mmt(t_mm(a, (p[7], p[8], p[9], p[10], p[11], p[12], p[13], p[14], p[15])), a)
    jw = t_mv(jm, w_)
    jwd = t_mv(jm, wd_)
    q_o = (q_in[0] + f[0] - mass * (a_in[0] + kap_c[0]),
           q_in[1] + f[1] - mass * (a_in[1] + kap_c[1]),
           q_in[2] + f[2] - mass * (a_in[2] + kap_c[2]))
    m_1 = t_cross(rho_c, f)
    m_2 = t_cross(rho, q_o)
    m_3 = t_cross(w_, jw)
    m_4 = t_cross(rho_c, a_in)
    m_o = (m_1[0] - m_2[0] + torque[0] - jwd[0] - m_3[0] - mass * m_4[0],
           m_1[1] - m_2[1] + torque[1] - jwd[1] - m_3[1] - mass * m_4[1],
           m_1[2] - m_2[2] + torque[2] - jwd[2] - m_3[2] - mass * m_4[2])
    # D_m = M rho^ D_c - J - r (w^ J - (J w)^) + s [B - q_O^ rho^ + (f - M a_I)^ rho_C^] Lam,
    # B = (J w')^ - J w'^ - w^ (J w^ - (J w)^);  x^ y^ = y x^T - (x . y) E
    t1 = t_lin9(1.0, t_mul_hat(jm, w_), -1.0, t_hat(jw))
    b = t_lin9(1.0, t_lin9(1.0, t_hat(jwd), -1.0, t_mul_hat(jm, wd_)), -1.0, t_hat_mul(w_, t1))
    ext = (f[0] - mass * a_in[0], f[1] - mass * a_in[1], f[2] - mass * a_in[2])
    q_rho = t_plus_diag(t_outer(rho, q_o), -(q_o[0] * rho[0] + q_o[1] * rho[1] + q_o[2] * rho[2]))
    e_rho = t_plus_diag(t_outer(rho_c, ext),
                        -(ext[0] * rho_c[0] + ext[1] * rho_c[1] + ext[2] * rho_c[2]))
    inner = t_mm(t_lin9(1.0, t_lin9(1.0, b, -1.0, q_rho), 1.0, e_rho), lm)
    d_m = t_lin9(mass, t_hat_mul(rho, d_c), s, inner)
    d_m = t_lin9(1.0, d_m, -1.0, jm)
    d_m = t_lin9(1.0, d_m, -r, t_lin9(1.0, t_hat_mul(w_, jm), -1.0, t_hat(jw)))
    # fold (m_I = m_O = 0): 0 = r_m - rho^ q_I + M (rho - rho_C)^ a_I + D_m (alpha - w'),
    # r_m = m_O* + rho^ q_I* - M (rho - rho_C)^ a_I*:  alpha = P_a a_I + P_q q_I + w' - G r_m
    det, g = t_inverse(d_m)
    if det == 0.0:                  # (reported by the sweep's finite check)
        g = (np.nan, np.nan, np.nan, np.nan, np.nan, np.nan, np.nan, np.nan, np.nan)
    m_5 = t_cross(rho, q_in)
    m_6 = t_cross(arm, a_in)
    y = t_mv(g, (m_o[0] + m_5[0] - mass * m_6[0], m_o[1] + m_5[1] - mass * m_6[1],
                 m_o[2] + m_5[2] - mass * m_6[2]))              # G r_m
    p_q = t_mul_hat(g, rho)                                     # G rho^
    p_a = t_mul_hat(g, arm)                                     # G (rho - rho_C)^
    for i in range(3):
        for j in range(3):
            pmap[i, j] = -mass * p_a[3 * i + j]
            pmap[i, 3 + j] = p_q[3 * i + j]
        pmap[i, 6] = wd[i] - y[i]
    # a_O = a_I + kappa_O + D_o (alpha - w'),
    # q_O = q_I + f - M a_I - M kappa_C - M D_c (alpha - w')
    d_o_g = t_mm(d_o, g)
    d_c_g = t_mm(d_c, g)
    dog_a = t_mul_hat(d_o_g, arm)
    dog_r = t_mul_hat(d_o_g, rho)
    dcg_a = t_mul_hat(d_c_g, arm)
    dcg_r = t_mul_hat(d_c_g, rho)
    d_o_y = t_mv(d_o, y)
    d_c_y = t_mv(d_c, y)
    for i in range(3):
        for j in range(3):
            v[i, j] = -mass * dog_a[3 * i + j]
            v[i, 3 + j] = dog_r[3 * i + j]
            v[3 + i, j] = mass * mass * dcg_a[3 * i + j]
            v[3 + i, 3 + j] = -mass * dcg_r[3 * i + j]
        v[i, i] += 1.0
        v[3 + i, i] -= mass
        v[3 + i, 3 + i] += 1.0
        v[i, 6] = kap_o[i] - d_o_y[i]
        v[3 + i, 6] = f[i] - mass * kap_c[i] + mass * d_c_y[i]


@kernel
def _write_stations(aq, phi, phi_g, z):
    """The stations' states in the general loop's layout (kernels/stepping/step.py::_solve): z[0]
    the ground point [a, phi_g, 0, q]; z[2k + 1], z[2k + 2] body k's input and output."""
    n = phi.shape[0]
    z[:, :] = 0.0
    for i in range(3):
        z[0, i] = aq[0, i]
        z[0, 3 + i] = phi_g[i]
        z[0, 9 + i] = aq[0, 3 + i]
    for k in range(n):
        for i in range(3):
            z[2 * k + 1, i] = aq[k, i]
            z[2 * k + 1, 3 + i] = phi[k, i]
            z[2 * k + 1, 9 + i] = aq[k, 3 + i]
            z[2 * k + 2, i] = aq[k + 1, i]
            z[2 * k + 2, 3 + i] = phi[k, i]
            z[2 * k + 2, 9 + i] = aq[k + 1, 3 + i]


@kernel
def _ground_increment(g_rot, s, rel, out):
    """The ground's rotation increment over step s: log(R_{s+1} R_s^T) (rel: 3 x 3 scratch)."""
    for i in range(3):
        for j in range(3):
            rel[i, j] = (g_rot[s + 1, i, 0] * g_rot[s, j, 0] + g_rot[s + 1, i, 1] * g_rot[s, j, 1]
                         + g_rot[s + 1, i, 2] * g_rot[s, j, 2])
    log_so3(rel, out)


# The fused loop's own scratch (kernels/schema.py::FUSED, made by fused_loop; nothing is allocated
# in the loop, so its skeleton is compiled without numba's reference counting: loop.py::_skeleton).
def fused_loop(n, mode_off, h, coef, tree=False):
    """The fused loop's scratch (FUSED) for n bodies whose modal coordinates start at mode_off;
    with tree=True the tree's tables sized too (tree.py::fused_tree_loop)."""
    work_rows, work_columns = ball_map_work_shape(int(np.max(np.diff(mode_off))) if n else 0)
    loop = FUSED_LAYOUT.zeros(bodies=n, modes=int(mode_off[-1]), work_rows=work_rows,
                              work_columns=work_columns, tree_bodies=n if tree else 0)
    loop.coefficients[:] = fused_coefficients(h, coef)
    return FlatFusedTree(*loop) if tree else loop


def start_loop(loop, state, sweep):
    """The fused loop (chain or tree) set for the consistent start, which the skeleton then runs
    as one pass of the loop's own iterate (Settings.start; docs/solver.md, "The consistent
    start").  With the coefficients (c1, c3, s, r) = (1, 0, 0, 0), w1 = 0, w3 = w_n and the guess
    phi* = 0, a body's rotation slot is its angular acceleration (w' = phi, w = w_n, A = A_n) and
    nothing else moves with it (s = r = 0); with w1e = -eta_n, w3e = eta'_n and eta''* = 0 the
    beams keep eta_n and eta'_n.  The relations are then linear in the accelerations: one sweep
    solves them.  Set in place (the pass leaves its solution in the loop's scratch, where the
    first step starts from it); returns the step's coefficients, for the caller to put back."""
    w1, w3, phi_star = loop.per_body[0], loop.per_body[1], loop.per_body[2]
    w1[:] = 0.0
    w3[:] = state.omega
    phi_star[:] = 0.0
    loop.per_mode[0] = -state.eta
    loop.per_mode[1] = state.eta_d
    loop.per_mode[3] = 0.0
    sweep.red_aq[:] = 0.0
    step_coefficients = loop.coefficients.copy()
    loop.coefficients[:] = 1.0, 0.0, 0.0, 0.0
    return step_coefficients


@kernel(entry=True)
def guess_from_stations(z, aq):
    """The fused loop's guess [a; q] of every station (red_aq) from the stations' states z."""
    n = aq.shape[0] - 1
    for k in range(n):
        for i in range(3):
            aq[k, i] = z[2 * k + 1, i]
            aq[k, 3 + i] = z[2 * k + 1, 9 + i]
    for i in range(3):
        aq[n, i] = z[2 * n, i]
        aq[n, 3 + i] = z[2 * n, 9 + i]


@loop_piece
def _predict(loop, run, s, _):
    predict_offsets(run, fused_tables.coefficients(loop), fused_tables.per_body(loop),
                    fused_tables.per_mode(loop))


@njit(cache=True, inline='always', fastmath=CONTRACT)
def predict_offsets(run, coefficients, per_body, per_mode):
    """phi* of every body by the constant-acceleration predictor, with the integrator's offsets
    of the rotations and the modal coordinates (the fused and the welded loops' predictor: their
    coefficients, per_body and per_mode tables)."""
    state = run.state
    eta = state_tables.eta(state)
    omega = state_tables.omega(state)
    omega_dot = state_tables.omega_dot(state)
    pseudo = state_tables.pseudo(state)
    eta_d = state_tables.eta_d(state)
    eta_acc = state_tables.eta_acc(state)
    eta_p = state_tables.eta_p(state)
    h, coef = run.settings.h, run.settings.coef
    c1, c3 = coefficients[0], coefficients[1]
    w1, w3, phi_star = per_body[0], per_body[1], per_body[2]
    for k in range(omega.shape[0]):
        _offsets_into(h, coef, omega[k], omega_dot[k], pseudo[k], w1[k], w3[k], phi_star[k])
    n_eta = eta.shape[0]
    if n_eta > 0:                               # eta'' = c1 eta + w1e, eta' = c3 eta + w3e
        w1e, w3e, a1e, eta_dd_star = per_mode[0], per_mode[1], per_mode[2], per_mode[3]
        # (eta_dd_star first receives the predicted increment of eta)
        _offsets_into(h, coef, eta_d, eta_acc, eta_p, a1e, w3e, eta_dd_star)
        for i in range(n_eta):
            w1e[i] = a1e[i] - c1 * eta[i]
            w3e[i] -= c3 * eta[i]
            eta_dd_star[i] = c1 * (eta[i] + eta_dd_star[i]) + w1e[i]


@loop_piece
def _iterate(loop, run, s, it):
    """One forward pass (kinematics, reduced map, Riccati step per body) and one backward pass
    (recovery, beams' modal accelerations); returns (status, detail, change)."""
    mats = fused_tables.mats(loop)
    vecs = fused_tables.vecs(loop)
    pmap = fused_tables.pmap(loop)
    v = fused_tables.v(loop)
    coefficients = fused_tables.coefficients(loop)
    per_body = fused_tables.per_body(loop)
    per_mode = fused_tables.per_mode(loop)
    beam_work = fused_tables.beam_work(loop)
    params, state, inputs, sweep = run.params, run.state, run.inputs, run.sweep
    force = input_tables.force(inputs)
    torque = input_tables.torque(inputs)
    line_load = input_tables.line_load(inputs)
    g_acc = input_tables.g_acc(inputs)
    eta_map = state_tables.eta_map(state)
    s_mat = sweep_tables.red_s(sweep)
    p_vec = sweep_tables.red_p(sweep)
    t_inv = sweep_tables.red_tinv(sweep)
    t_vec = sweep_tables.red_t(sweep)
    aq = sweep_tables.red_aq(sweep)
    rot_ = state_tables.rot(state)
    c1, c3, s_c, r_c = coefficients[0], coefficients[1], coefficients[2], coefficients[3]
    w1, w3, phi_star, phi_new = per_body[0], per_body[1], per_body[2], per_body[3]
    t_buf, num_buf, e3, rot_star, lam = mats[0], mats[1], mats[2], mats[3], mats[4]
    w, wd, alpha, load = vecs[0], vecs[1], vecs[2], vecs[3]
    w1e, w3e, eta_dd_star, eta_dd_new = per_mode[0], per_mode[1], per_mode[3], per_mode[4]
    body_params, body_row = model_tables.body_params(params), model_tables.body_row(params)
    gravity, rot = model_tables.gravity(params), rot_
    body_kind = model_tables.body_kind(params)
    beam_params = model_tables.beam_params(params)
    beam_moments = model_tables.beam_moments(params)
    mode_off = model_tables.mode_offset(params)
    beam_ends = model_tables.beam_ends(params)
    beam_factors = model_tables.beam_factors(params)
    n = rot.shape[0]
    for i in range(3):
        p_vec[0, i] = g_acc[s, i]
        for j in range(3):
            s_mat[0, i, j] = 0.0
    for k in range(n):
        phi = phi_star[k]
        for i in range(3):
            w[i] = c3 * phi[i] + w3[k, i]
            wd[i] = c1 * phi[i] + w1[k, i]
        if body_kind[k] == BEAM:                # (its own kinematics: kernels/transfers/beam.py)
            i0, i1 = mode_off[k], mode_off[k + 1]
            m = (i1 - i0) // 2              # (no twist here: Model.has_twist runs general)
            tables = (beam_moments[k, :m, :4 * m + 2], beam_ends[k, :m], beam_factors[k, :m],
                      force[s, k], torque[s, k], line_load[s, k])   # (docs/beam.md)
            beam_ball_map(beam_params[k], tables, gravity, rot[k], phi, wd, coefficients,
                          w3[k], w1e[i0:i1], w3e[i0:i1], aq[k, 0:3], aq[k, 3:6],
                          eta_dd_star[i0:i1], beam_work, v, pmap[k], eta_map[i0:i1])
        elif body_kind[k] == RIGID:
            expm_so3(phi, e3)
            mm3_into(e3, rot[k], rot_star)
            left_jacobian(phi, lam)
            row = body_row[k]         # (the body's row of the shared table)
            for i in range(3):
                load[i] = body_params[row, 0] * gravity[i] + force[s, k, i]
            ball_body_map(body_params[row], rot_star, lam, w, wd, s_c, r_c, aq[k, 0:3],
                          aq[k, 3:6], load, torque[s, k], v, pmap[k])
        else:
            return UNSUPPORTED, 2 * k + 2, 0.0
        if riccati_reduced_step(v, s_mat[k], p_vec[k], s_mat[k + 1], p_vec[k + 1], t_inv[k],
                                t_vec[k], t_buf, num_buf) == 0.0:
            return SINGULAR, k + 1, 0.0
    riccati_reduced_tip(model_tables.tip_pinned(params), s_mat[n], p_vec[n], aq[n])
    change = 0.0
    finite = True
    for k in range(n - 1, -1, -1):
        riccati_reduced_recover(k, s_mat, p_vec, t_inv, t_vec, aq)
        change, finite = recover_body(pmap[k], aq[k], w1[k], c1, phi_star[k], phi_new[k],
                                      body_kind[k] == BEAM, mode_off[k], mode_off[k + 1],
                                      eta_map, eta_dd_star, eta_dd_new, alpha, change, finite)
    if not finite:
        return NOT_FINITE, 0, change
    return OK, 0, change


@njit(cache=True, inline='always', fastmath=CONTRACT)
def recover_body(pk, aq_k, w1_k, c1, phi_star_k, phi_new_k, beam, i0, i1, eta_map, eta_dd_star,
                 eta_dd_new, alpha, change, finite):
    """A body's angular acceleration from its input [a; q] by its map pk (3 x 7), its rotation
    increment phi = (alpha - w1) / c1, and a beam's modal accelerations eta'' = eta_map[:, :7]
    [a; q; 1]; returns (change, finite) updated with the largest change of phi or eta'' / c1."""
    for i in range(3):
        alpha[i] = pk[i, 6]
        for c in range(6):
            alpha[i] += pk[i, c] * aq_k[c]
        x = (alpha[i] - w1_k[i]) / c1           # back from w' = c1 phi + w1
        phi_new_k[i] = x
        change = max(change, abs(x - phi_star_k[i]))
        if not np.isfinite(x):
            finite = False
    if beam:
        for i in range(i0, i1):
            e = eta_map[i, 6]
            for c in range(6):
                e += eta_map[i, c] * aq_k[c]
            eta_dd_new[i] = e
            change = max(change, abs(e - eta_dd_star[i]) / c1)
    return change, finite


@njit(cache=True, inline='always', fastmath=CONTRACT)
def adopt_solution(per_body, per_mode):
    """The latest solution becomes the guess: phi* = phi, eta''* = eta'' (per_body's and
    per_mode's rows, the fused and the welded loops' layout)."""
    phi_star, phi_new = per_body[2], per_body[3]
    for k in range(phi_star.shape[0]):
        for i in range(3):
            phi_star[k, i] = phi_new[k, i]
    eta_dd_star, eta_dd_new = per_mode[3], per_mode[4]
    for i in range(eta_dd_star.shape[0]):
        eta_dd_star[i] = eta_dd_new[i]


@loop_piece
def _adopt(loop, run, s, it):
    adopt_solution(fused_tables.per_body(loop), fused_tables.per_mode(loop))


@loop_piece
def _update(loop, run, s, _):
    return update_integrated(run, fused_tables.coefficients(loop), fused_tables.per_body(loop),
                             fused_tables.mats(loop), fused_tables.per_mode(loop))


@njit(cache=True, inline='always', fastmath=CONTRACT)
def update_integrated(run, coefficients, per_body, mats, per_mode):
    """Rotations and modal coordinates over the step from the solution (per_body's phi), with
    mats[2] and mats[5] for scratch; every rate finite?  (The fused and the welded loops'.)"""
    state = run.state
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    omega_dot = state_tables.omega_dot(state)
    pseudo = state_tables.pseudo(state)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    eta_acc = state_tables.eta_acc(state)
    eta_p = state_tables.eta_p(state)
    h, coef = run.settings.h, run.settings.coef
    c1 = coefficients[0]
    phi_new = per_body[3]
    e3, rot_prev = mats[2], mats[5]
    w1e, a1e, eta_dd_new = per_mode[0], per_mode[2], per_mode[4]
    finite = True
    for k in range(rot.shape[0]):
        _advance_history(h, coef, phi_new[k], omega[k], omega_dot[k], pseudo[k])
        expm_so3(phi_new[k], e3)
        for i in range(3):
            for j in range(3):
                rot_prev[i, j] = rot[k, i, j]
        mm3_into(e3, rot_prev, rot[k])
        for i in range(3):
            if not (np.isfinite(omega[k, i]) and np.isfinite(omega_dot[k, i])):
                finite = False
    n_eta = eta.shape[0]
    for i in range(n_eta):
        eta_new = (eta_dd_new[i] - w1e[i]) / c1
        a1e[i] = eta_new - eta[i]               # (the increment)
        eta[i] = eta_new
    _advance_history(h, coef, a1e, eta_d, eta_acc, eta_p)
    for i in range(n_eta):
        if not np.isfinite(eta_d[i]):
            finite = False
    return finite


@njit(cache=True, inline='always', fastmath=CONTRACT)
def record_state(state, rec, slot):
    """The bodies' rotations, angular velocities and accelerations and the modal coordinates
    and rates into the record's slot (every fused loop's _record; its stations apart)."""
    rec_eta = record_tables.eta(rec)
    rec_eta_d = record_tables.eta_d(rec)
    rec_omega = record_tables.omega(rec)
    rec_omega_dot = record_tables.omega_dot(rec)
    rec_rot = record_tables.rot(rec)
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    omega_dot = state_tables.omega_dot(state)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    for k in range(rot.shape[0]):
        for i in range(3):
            rec_omega[slot, k, i] = omega[k, i]
            rec_omega_dot[slot, k, i] = omega_dot[k, i]
            for j in range(3):
                rec_rot[slot, k, i, j] = rot[k, i, j]
    for i in range(eta.shape[0]):
        rec_eta[slot, i] = eta[i]
        rec_eta_d[slot, i] = eta_d[i]


@loop_piece
def _record(loop, run, s, slot):
    vecs = fused_tables.vecs(loop)
    mats = fused_tables.mats(loop)
    per_body = fused_tables.per_body(loop)
    g_rot = input_tables.g_rot(run.inputs)
    z = record_tables.z(run.rec)
    red_aq = sweep_tables.red_aq(run.sweep)
    phi_g = vecs[4]
    _ground_increment(g_rot, s, mats[6], phi_g)
    _write_stations(red_aq, per_body[3], phi_g, z[slot])
    record_state(run.state, run.rec, slot)


@loop_piece
def _finish(loop, run, n_steps, _):
    """The stations' states z after the chunk's last step (the general loop's layout)."""
    vecs = fused_tables.vecs(loop)
    mats = fused_tables.mats(loop)
    per_body = fused_tables.per_body(loop)
    g_rot = input_tables.g_rot(run.inputs)
    red_aq = sweep_tables.red_aq(run.sweep)
    z = state_tables.z(run.state)
    if n_steps > 0:
        phi_g = vecs[4]
        _ground_increment(g_rot, n_steps - 1, mats[6], phi_g)
        _write_stations(red_aq, per_body[3], phi_g, z)


loop_variant(FlatFused, predict=_predict, iterate=_iterate, adopt=_adopt, update=_update,
             record=_record, finish=_finish)
