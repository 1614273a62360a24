"""The time loop fused for chains of rigid bodies and beams joined by ball joints
(docs/assembly.md, "The fused ball-chain step").

The same step as kernels/step.py::advance in RICCATI_REDUCED mode (Newmark scheme), on
preallocated arrays: each rigid body's reduced 6 x 7 map on [a; q; 1] is written directly in
angular-acceleration slots (no 12 x 13 transfer), a beam's transfer (kernels/beam.py, already in
those slots) is folded, and each map goes straight into its Riccati step.  Results agree with
the general loop to rounding (tests/test_ball_chain.py).
"""
import numpy as np
from numba import njit

from ..elements import BEAM
from .beam import beam_transfer
from .body import kappa_matrix, point_jacobian
from .mat3 import hat_mul, inv3, mul_hat
from .so3 import expm_so3, left_jacobian, log_so3
from .step import NOT_FINITE, OK, SINGULAR, _advance_history, _integrator_coefficients, \
    _offsets_into, report
from .sweep import (fold_ball_body, riccati_reduced_recover, riccati_reduced_step,
                    riccati_reduced_tip)


@njit(cache=True)
def _mm(a, b, out):
    """out = a @ b (3 x 3)."""
    for i in range(3):
        a0, a1, a2 = a[i, 0], a[i, 1], a[i, 2]
        for j in range(3):
            out[i, j] = a0 * b[0, j] + a1 * b[1, j] + a2 * b[2, j]


@njit(cache=True)
def ball_body_map(p, rot, lam, w, wd, s, r, a_i, q_i, load, torque, v, pmap, buf, vec):
    """Body k's reduced map in angular-acceleration slots (docs/assembly.md, "The fused
    ball-chain step"), linearized about the guess (phi*, a_I*, q_I*):
      [a_O; q_O] = v [a_I; q_I; 1],   alpha = pmap [a_I; q_I; 1]  (the angular acceleration).
    p: body parameter row (mass, l_IC, l_IO, J_I); rot, lam: A* and J_l(phi*); w, wd: angular
    velocity and acceleration at phi*; s = 1/c1, r = c3/c1 (d w / d alpha = r I, d phi / d alpha
    = s I); load = M g + F at the mass centre, torque applied; buf (14, 3, 3), vec (12, 3)
    scratch."""
    mass = p[0]
    j_body = p[7:16].reshape((3, 3))
    rho, rho_c, kap_o, kap_c, q_o, m_o, jw, jwd, ext, arm, r_m, zero = (
        vec[0], vec[1], vec[2], vec[3], vec[4], vec[5], vec[6], vec[7], vec[8], vec[9], vec[10],
        vec[11])
    kmat, n_o, n_c, d_o, d_c, d_m, jm, t1, t2, b, g, p_q, p_a, _ = (
        buf[0], buf[1], buf[2], buf[3], buf[4], buf[5], buf[6], buf[7], buf[8], buf[9], buf[10],
        buf[11], buf[12], buf[13])
    for i in range(3):
        rho[i] = rot[i, 0] * p[4] + rot[i, 1] * p[5] + rot[i, 2] * p[6]        # A* l_IO
        rho_c[i] = rot[i, 0] * p[1] + rot[i, 1] * p[2] + rot[i, 2] * p[3]      # A* l_IC
    kappa_matrix(w, wd, kmat)                   # kappa(x) = K x = wd x x + w x (w x x)
    for i in range(3):
        kap_o[i] = kmat[i, 0] * rho[0] + kmat[i, 1] * rho[1] + kmat[i, 2] * rho[2]
        kap_c[i] = kmat[i, 0] * rho_c[0] + kmat[i, 1] * rho_c[1] + kmat[i, 2] * rho_c[2]
    # d rho / d phi = -rho^ Lam = -N_o; d kappa / d alpha = -rho^ - s K N_o - r R(rho)
    # (a point of a rigid body: point_jacobian without deformation rates)
    hat_mul(rho, lam, n_o)
    hat_mul(rho_c, lam, n_c)
    zero[:] = 0.0
    point_jacobian(rho, zero, zero, w, kmat, lam, s, r, d_o, t1, t2)
    point_jacobian(rho_c, zero, zero, w, kmat, lam, s, r, d_c, t1, t2)
    # J = A* J_I A*^T, and the moment relation's values at the guess (docs/rigid_body.md):
    # m_O = -rho x q_O + rho_C x load + torque - (J wd + w x J w + M rho_C x a_I)
    _mm(rot, j_body, t1)
    for i in range(3):
        for j in range(3):
            jm[i, j] = t1[i, 0] * rot[j, 0] + t1[i, 1] * rot[j, 1] + t1[i, 2] * rot[j, 2]
    for i in range(3):
        jw[i] = jm[i, 0] * w[0] + jm[i, 1] * w[1] + jm[i, 2] * w[2]
        jwd[i] = jm[i, 0] * wd[0] + jm[i, 1] * wd[1] + jm[i, 2] * wd[2]
        q_o[i] = q_i[i] + load[i] - mass * (a_i[i] + kap_c[i])
    for i in range(3):
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        m_o[i] = (-(rho[i1] * q_o[i2] - rho[i2] * q_o[i1])
                  + rho_c[i1] * load[i2] - rho_c[i2] * load[i1] + torque[i] - jwd[i]
                  - (w[i1] * jw[i2] - w[i2] * jw[i1])
                  - mass * (rho_c[i1] * a_i[i2] - rho_c[i2] * a_i[i1]))
    # d m_O / d alpha = M rho^ D_c - J - r (w^ J - (J w)^)
    #   + s [-q_O^ N_o + (load - M a_I)^ N_c + B Lam],  B = (J wd)^ - J wd^ - w^ (J w^ - (J w)^)
    mul_hat(jm, w, t1)                          # J w^
    t1[0, 1] += jw[2]                           # J w^ - (J w)^
    t1[0, 2] -= jw[1]
    t1[1, 0] -= jw[2]
    t1[1, 2] += jw[0]
    t1[2, 0] += jw[1]
    t1[2, 1] -= jw[0]
    hat_mul(w, t1, t2)                          # w^ (J w^ - (J w)^)
    mul_hat(jm, wd, b)
    for i in range(3):
        for j in range(3):
            b[i, j] = -b[i, j] - t2[i, j]
    b[0, 1] -= jwd[2]
    b[0, 2] += jwd[1]
    b[1, 0] += jwd[2]
    b[1, 2] -= jwd[0]
    b[2, 0] -= jwd[1]
    b[2, 1] += jwd[0]
    _mm(b, lam, t1)                             # B Lam
    hat_mul(q_o, n_o, t2)
    for i in range(3):
        for j in range(3):
            t1[i, j] -= t2[i, j]
    for i in range(3):
        ext[i] = load[i] - mass * a_i[i]
    hat_mul(ext, n_c, t2)
    hat_mul(rho, d_c, b)                        # rho^ D_c
    for i in range(3):
        for j in range(3):
            d_m[i, j] = mass * b[i, j] + s * (t1[i, j] + t2[i, j]) - jm[i, j]
    hat_mul(w, jm, t1)                          # w^ J - (J w)^
    t1[0, 1] += jw[2]
    t1[0, 2] -= jw[1]
    t1[1, 0] -= jw[2]
    t1[1, 2] += jw[0]
    t1[2, 0] += jw[1]
    t1[2, 1] -= jw[0]
    for i in range(3):
        for j in range(3):
            d_m[i, j] -= r * t1[i, j]
    # fold (m_I = m_O = 0): 0 = r_m - rho^ q_I + M (rho - rho_C)^ a_I + D_m (alpha - wd),
    # r_m = m_O* + rho^ q_I* - M (rho - rho_C)^ a_I*
    if inv3(d_m, g) == 0.0:
        g[:, :] = np.nan                        # reported by the sweep's finite check
    mul_hat(g, rho, p_q)                        # alpha = P_a a_I + P_q q_I + p0
    for i in range(3):
        arm[i] = rho[i] - rho_c[i]
    mul_hat(g, arm, p_a)
    for i in range(3):
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        r_m[i] = (m_o[i] + rho[i1] * q_i[i2] - rho[i2] * q_i[i1]
                  - mass * (arm[i1] * a_i[i2] - arm[i2] * a_i[i1]))
    for i in range(3):
        g_r = g[i, 0] * r_m[0] + g[i, 1] * r_m[1] + g[i, 2] * r_m[2]
        for j in range(3):
            pmap[i, j] = -mass * p_a[i, j]
            pmap[i, 3 + j] = p_q[i, j]
        pmap[i, 6] = wd[i] - g_r
    # [a_O; q_O]: a_O = a_I + kappa_O + D_o (alpha - wd),
    #             q_O = q_I + load - M a_I - M kappa_C - M D_c (alpha - wd)
    for i in range(3):
        for c in range(7):
            do = d_o[i, 0] * pmap[0, c] + d_o[i, 1] * pmap[1, c] + d_o[i, 2] * pmap[2, c]
            dc = d_c[i, 0] * pmap[0, c] + d_c[i, 1] * pmap[1, c] + d_c[i, 2] * pmap[2, c]
            v[i, c] = do
            v[3 + i, c] = -mass * dc
        v[i, i] += 1.0
        v[3 + i, i] -= mass
        v[3 + i, 3 + i] += 1.0
        shift_o = d_o[i, 0] * wd[0] + d_o[i, 1] * wd[1] + d_o[i, 2] * wd[2]
        shift_c = d_c[i, 0] * wd[0] + d_c[i, 1] * wd[1] + d_c[i, 2] * wd[2]
        v[i, 6] += kap_o[i] - shift_o
        v[3 + i, 6] += load[i] - mass * kap_c[i] + mass * shift_c


@njit(cache=True)
def _write_stations(aq, phi, phi_g, z):
    """The stations' states in the general loop's layout (kernels/step.py::_solve): z[0] the
    ground point [a, phi_g, 0, q]; z[2k + 1], z[2k + 2] body k's input and output."""
    n = phi.shape[0]
    z[:, :] = 0.0
    z[0, 0:3] = aq[0, 0:3]
    z[0, 3:6] = phi_g
    z[0, 9:12] = aq[0, 3:6]
    for k in range(n):
        for i in range(3):
            z[2 * k + 1, i] = aq[k, i]
            z[2 * k + 1, 3 + i] = phi[k, i]
            z[2 * k + 1, 9 + i] = aq[k, 3 + i]
            z[2 * k + 2, i] = aq[k + 1, i]
            z[2 * k + 2, 3 + i] = phi[k, i]
            z[2 * k + 2, 9 + i] = aq[k + 1, 3 + i]


@njit(cache=True)
def _ground_increment(g_rot, s, out):
    """The ground's rotation increment over step s: log(R_{s+1} R_s^T)."""
    rel = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            rel[i, j] = (g_rot[s + 1, i, 0] * g_rot[s, j, 0] + g_rot[s + 1, i, 1] * g_rot[s, j, 1]
                         + g_rot[s + 1, i, 2] * g_rot[s, j, 2])
    log_so3(rel, out)


@njit(cache=True)
def advance_ball_chain(tip_pinned, h, coef, newton_max, newton_tol, body_params, gravity,
                       g_acc, g_rot, force, torque, rot, omega, omega_dot, pseudo, z,
                       s_mat, p_vec, t_inv, t_vec, aq, record_every, rec_rot, rec_omega,
                       rec_omega_dot, rec_z, out_info, beams, eta, eta_d, eta_acc, eta_p,
                       eta_map, rec_eta, rec_eta_d):
    """kernels/step.py::advance for a chain of rigid bodies and beams joined by ball joints
    (RICCATI_REDUCED mode, Newmark scheme), the same arguments' meaning; z holds the stations'
    states (input guess and output) in the general loop's layout.  Per step and Newton iteration
    one forward pass (kinematics, reduced map, Riccati step per body) and one backward pass
    (recovery, beams' modal accelerations)."""
    n = body_params.shape[0]
    n_steps = g_acc.shape[0]
    c1, c3 = _integrator_coefficients(h, coef)
    s_c, r_c = 1.0 / c1, c3 / c1
    w1 = np.empty((n, 3))
    w3 = np.empty((n, 3))
    phi_star = np.empty((n, 3))
    phi_new = np.empty((n, 3))
    pmap = np.empty((n, 3, 7))
    v = np.empty((6, 7))
    buf = np.empty((16, 3, 3))
    vec = np.empty((12, 3))
    e3 = np.empty((3, 3))
    rot_star = np.empty((3, 3))
    lam = np.empty((3, 3))
    rot_prev = np.empty((3, 3))
    w = np.empty(3)
    wd = np.empty(3)
    alpha = np.empty(3)
    load = np.empty(3)
    phi_g = np.zeros(3)
    body_kind, beam_params, beam_xq, beam_wq, beam_modes, mode_off, beam_ends, beam_factors = beams
    n_eta = eta.shape[0]
    w1e = np.zeros(n_eta)
    w3e = np.zeros(n_eta)
    a1e = np.zeros(n_eta)
    eta_dd_star = np.zeros(n_eta)
    eta_dd_new = np.zeros(n_eta)
    u = np.empty((12, 13))
    z_in = np.zeros(12)                             # a beam's input guess [a, w', 0, q]
    outboard = (False, np.eye(3), np.eye(3), np.zeros(3))   # a ball joint at every output
    history = (False, np.zeros(3))                  # (the paper's scheme: never here)
    for k in range(n):                              # the guess: the last solution
        for i in range(3):
            aq[k, i] = z[2 * k + 1, i]
            aq[k, 3 + i] = z[2 * k + 1, 9 + i]
    for i in range(3):
        aq[n, i] = z[2 * n, i]
        aq[n, 3 + i] = z[2 * n, 9 + i]
    max_iter = 0
    n_rec = 0
    for s in range(n_steps):
        for k in range(n):
            _offsets_into(h, coef, omega[k], omega_dot[k], pseudo[k], w1[k], w3[k],
                          phi_star[k])              # phi* by the constant-acceleration predictor
        if n_eta > 0:                               # eta'' = c1 eta + w1e, eta' = c3 eta + w3e
            # (eta_dd_star first receives the predicted increment of eta)
            _offsets_into(h, coef, eta_d, eta_acc, eta_p, a1e, w3e, eta_dd_star)
            for i in range(n_eta):
                w1e[i] = a1e[i] - c1 * eta[i]
                w3e[i] -= c3 * eta[i]
                eta_dd_star[i] = c1 * (eta[i] + eta_dd_star[i]) + w1e[i]
        for it in range(newton_max + 1):
            s_mat[0, :, :] = 0.0
            p_vec[0, :] = g_acc[s]
            for k in range(n):
                phi = phi_star[k]
                expm_so3(phi, e3)
                _mm(e3, rot[k], rot_star)
                left_jacobian(phi, lam)
                for i in range(3):
                    w[i] = c3 * phi[i] + w3[k, i]
                    wd[i] = c1 * phi[i] + w1[k, i]
                    load[i] = body_params[k, 0] * gravity[i] + force[s, k, i]
                if body_kind[k] == BEAM:
                    i0, i1 = mode_off[k], mode_off[k + 1]
                    m = (i1 - i0) // 2
                    for i in range(3):
                        z_in[i] = aq[k, i]
                        z_in[3 + i] = wd[i]
                        z_in[9 + i] = aq[k, 3 + i]
                    tables = (beam_xq[k], beam_wq[k], beam_modes[k, :m], beam_ends[k, :m],
                              beam_factors[k, :m])
                    beam_transfer(beam_params[k], tables, outboard, history, gravity, False,
                                  rot[k], phi, wd, c1, c3, w3[k], w, w1e[i0:i1], w3e[i0:i1],
                                  eta[i0:i1], eta_d[i0:i1], z_in, eta_dd_star[i0:i1], u,
                                  eta_map[i0:i1])
                    fold_ball_body(u, v, pmap[k])
                else:
                    ball_body_map(body_params[k], rot_star, lam, w, wd, s_c, r_c, aq[k, 0:3],
                                  aq[k, 3:6], load, torque[s, k], v, pmap[k], buf, vec)
                if riccati_reduced_step(v, s_mat[k], p_vec[k], s_mat[k + 1], p_vec[k + 1],
                                        t_inv[k], t_vec[k], buf[14], buf[15]) == 0.0:
                    report(out_info, SINGULAR, s, k + 1, n_rec)
                    return
            riccati_reduced_tip(tip_pinned, s_mat[n], p_vec[n], aq[n])
            change = 0.0
            finite = True
            for k in range(n - 1, -1, -1):
                riccati_reduced_recover(k, s_mat, p_vec, t_inv, t_vec, aq)
                pk = pmap[k]
                for i in range(3):
                    alpha[i] = pk[i, 6]
                    for c in range(6):
                        alpha[i] += pk[i, c] * aq[k, c]
                    x = (alpha[i] - w1[k, i]) / c1  # back from w' = c1 phi + w1
                    phi_new[k, i] = x
                    change = max(change, abs(x - phi_star[k, i]))
                    if not np.isfinite(x):
                        finite = False
                if body_kind[k] == BEAM:            # eta'' = eta_map [a, w', 0, q; 1]
                    for i in range(mode_off[k], mode_off[k + 1]):
                        e = eta_map[i, 12]
                        for c in range(3):
                            e += (eta_map[i, c] * aq[k, c] + eta_map[i, 3 + c] * alpha[c]
                                  + eta_map[i, 9 + c] * aq[k, 3 + c])
                        eta_dd_new[i] = e
                        change = max(change, abs(e - eta_dd_star[i]) / c1)
            if not finite:
                report(out_info, NOT_FINITE, s, 0, n_rec)
                return
            max_iter = max(max_iter, it)
            if it == newton_max or change <= newton_tol:
                break
            phi_star[:, :] = phi_new
            eta_dd_star[:] = eta_dd_new
        if newton_max > 0 and change > newton_tol:
            out_info[4] += 1
        for k in range(n):                          # update the histories
            _advance_history(h, coef, phi_new[k], omega[k], omega_dot[k], pseudo[k])
            expm_so3(phi_new[k], e3)
            rot_prev[:, :] = rot[k]
            _mm(e3, rot_prev, rot[k])
            for i in range(3):
                if not (np.isfinite(omega[k, i]) and np.isfinite(omega_dot[k, i])):
                    finite = False
        for i in range(n_eta):
            eta_new = (eta_dd_new[i] - w1e[i]) / c1
            a1e[i] = eta_new - eta[i]               # (the increment)
            eta[i] = eta_new
        _advance_history(h, coef, a1e, eta_d, eta_acc, eta_p)
        for i in range(n_eta):
            if not np.isfinite(eta_d[i]):
                finite = False
        if not finite:
            report(out_info, NOT_FINITE, s, 0, n_rec)
            return
        if (s + 1) % record_every == 0:
            _ground_increment(g_rot, s, phi_g)
            _write_stations(aq, phi_new, phi_g, rec_z[n_rec])
            rec_rot[n_rec] = rot
            rec_omega[n_rec] = omega
            rec_omega_dot[n_rec] = omega_dot
            rec_eta[n_rec] = eta
            rec_eta_d[n_rec] = eta_d
            n_rec += 1
    if n_steps > 0:
        _ground_increment(g_rot, n_steps - 1, phi_g)
        _write_stations(aq, phi_new, phi_g, z)
    report(out_info, OK, n_steps, max_iter, n_rec)
