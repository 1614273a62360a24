"""Transfer of an Euler-Bernoulli modal beam over one time step (docs/beam.md).

Station slots as for the rigid body but with the angular acceleration in the rotation slot (the
sweep's scaling, docs/assembly.md): z = [a, w', m, q].  The beam's modal accelerations eta'' are
internal unknowns, fixed by its modal equations; eliminating them leaves a 12 x 13 transfer like
a rigid body's, plus the affine map eta'' = E [z_in; 1] used to recover them.

The nonlinear relations are evaluated exactly (the integrals along the beam through the beam's
constant modal integrals, docs/beam.md "The integrals in the frame") and linearized about the
guess, every column written out (docs/beam.md) where the output carries no moment; at a weld
and in the paper's scheme the w' and eta'' columns by forward differences.
The affine map reproduces the relations at the guess, so the step's solution is that of the
exact linearization (up to the differences' error in the slope, ~1e-10 relative, where they
are used: second order in the O(h^3) predictor error).
"""
import numpy as np

from ...elements.beam import EXACT, LOAD_AXES, STIFFENING
from .. import kernel, no_alloc_kernel
from .body import kappa_values, point_jacobian_values
from ..algebra.mat3 import (mm3_into, t_cross, t_hat, t_hat_mul, t_inverse, t_lin9, t_mm,
                            t_mul_hat, t_mv, t_of_mat, t_of_vec, t_outer, t_plus_diag, t_scale9)
from .beam_relations import (END_U, END_V, SUM_C, SUM_H, SUM_J, SUM_MODES, SUM_U, SUM_V,
                             add_end_moment, _any, aux_rows, _beam_gravity, beam_relations,
                             coefficient_row, _end_angles_into, end_foreshortening,
                             _end_section_angular_acceleration, _follower_loads, foreshortening_row,
                             _stretch_affine_columns, _twist_end_columns, twist_relations)
from ..algebra.so3 import expm_so3, left_jacobian, left_jacobian_derivative, log_so3


@kernel
def _step_state(phi, c1, c3, w3, rot_n, eta_dd, w1e, w3e, e, rot, w, eta, eta_d):
    """The beam's state at the end of the step for a rotation increment phi and modal
    accelerations eta'' (the integrator's relations, docs/solver.md): w = c3 phi + w3,
    A = exp(phi^) A_n (e: 3 x 3 scratch), eta = (eta'' - w1e) / c1, eta' = c3 eta + w3e."""
    for i in range(3):
        w[i] = c3 * phi[i] + w3[i]
    expm_so3(phi, e)
    mm3_into(e, rot_n, rot)
    for i in range(eta.shape[0]):
        eta[i] = (eta_dd[i] - w1e[i]) / c1
        eta_d[i] = c3 * eta[i] + w3e[i]


@kernel
def _evaluate(bp, tables, outboard, history, gravity, start, rot_n, phi_star, wd_star, c1, c3,
              w3, w_n, w1e, w3e, eta_n, eta_d_n, x, out, residual, aux, work):
    """beam_relations with the state expressed in the step's unknowns
    x = [a_I, w', m_I, q_I, eta''] (the integrator's relations, docs/solver.md).
    tables = (moments, ends, factors, end_force, end_torque, line_load, torsion, axial) (the
    applied loads, world: beam_relations; the distributed load is already in gravity,
    _beam_gravity; torsion: the twist table, twist_relations; axial: the stretch table,
    beam_relations);
    outboard = (welded, R_rel, rotation at t_n, w1):
    with a fixed hinge at the output (welded), the output's rotation slot is the outboard body's
    angular acceleration, c1 phi_out + w1 with A_out,n+1 = exp(phi_out^) A_out,n = A_O R_rel
    (at the start: the end section's angular acceleration).  work: (75 + 2 n) scratch, which
    holds the state (the rotation in work[9:18]), the end moment's scratch and the
    follower loads (beam_transfer)."""
    moments, ends, factors, end_force, end_torque = tables[0], tables[1], tables[2], tables[3], \
        tables[4]
    torsion = tables[6]
    welded, r_rel, rot_out_n, w1_out = outboard
    n = residual.shape[0]
    wd = x[3:6]
    eta_dd = x[12:12 + n]
    if start:
        rot, w, eta, eta_d = rot_n, w_n, eta_n, eta_d_n
    else:
        e = work[0:9].reshape((3, 3))
        rot = work[9:18].reshape((3, 3))
        phi = work[18:21]
        w = work[21:24]
        eta = work[24:24 + n]
        eta_d = work[24 + n:24 + 2 * n]
        for i in range(3):
            phi[i] = phi_star[i] + (wd[i] - wd_star[i]) / c1
        _step_state(phi, c1, c3, w3, rot_n, eta_dd, w1e, w3e, e, rot, w, eta, eta_d)
    scratch = work[24 + 2 * n:66 + 2 * n]
    if bp[LOAD_AXES] != 0.0:
        # followers (docs/beam.md, "Loads on the beam"): the end loads in the end section's
        # axes, the distributed load in the frame's (gravity arrives without it: beam_transfer)
        loads = work[66 + 2 * n:75 + 2 * n].reshape((3, 3))
        _follower_loads(bp, tables, eta, rot, gravity, loads, scratch)
        end_force, end_torque, gravity = loads[0], loads[1], loads[2]
    beam_relations(bp, moments, ends, factors, end_force, end_torque, gravity, rot, w, wd, eta,
                   eta_d, eta_dd, x[0:3], x[6:9], x[9:12], out, residual, aux, tables[7])
    if torsion.shape[0]:
        twist_relations(bp, torsion, rot, w, wd, eta, eta_d, eta_dd, ends.shape[0], out,
                        residual)
    if welded or _any(end_torque):
        add_end_moment(ends, torsion, eta, rot, out, residual, aux, end_torque, scratch)
    independent, dw1 = history
    if independent and not start:
        m = ends.shape[0]
        v_l = w_l = 0.0
        for k in range(m):
            v_l += ends[k, 0] * eta_n[k]
            w_l += ends[k, 0] * eta_n[m + k]
        c_l = end_foreshortening(moments, eta_n) if bp[STIFFENING] != 0.0 else 0.0
        axial = tables[7]
        for j in range(axial.shape[0]):             # the stretch u_x(L) at t_n
            c_l -= axial[j, 0] * eta_n[n - axial.shape[0] + j]
        for i in range(3):
            rho_l_n = (bp[0] - c_l) * rot_n[i, 0] + v_l * rot_n[i, 1] + w_l * rot_n[i, 2]
            out[i] = x[i] + c1 * (aux[1, i] - rho_l_n) + dw1[i]
    if welded:
        if start:
            _end_section_angular_acceleration(ends, torsion, rot, w, wd, eta, eta_d, eta_dd,
                                              out[3:6], scratch)
        else:
            # A_O = A exp(theta_O^), phi_out = log(A_O R_rel A_out,n^T)
            theta, e = scratch[0:3], scratch[12:21].reshape((3, 3))
            a_o, rel = scratch[21:30].reshape((3, 3)), scratch[30:39].reshape((3, 3))
            phi_out = scratch[39:42]
            _end_angles_into(ends, torsion, eta, theta)
            expm_so3(theta, e)
            mm3_into(rot, e, a_o)
            mm3_into(a_o, r_rel, e)
            for i in range(3):
                for j in range(3):
                    rel[i, j] = (e[i, 0] * rot_out_n[j, 0] + e[i, 1] * rot_out_n[j, 1]
                                 + e[i, 2] * rot_out_n[j, 2])
            log_so3(rel, phi_out)
            for i in range(3):
                out[3 + i] = c1 * phi_out[i] + w1_out[i]


@no_alloc_kernel
def _affine_columns(bp, moments, ends, welded, rot, aux, d_o, d_r):
    """The Jacobian's columns for a_I (0:3), m_I (6:9) and q_I (9:12), in which the relations
    are affine (docs/beam.md, "The DT-TMM transfer"): with the beam's mass M_b, its first mass
    moment S and rho_L = r_O - r_I (aux),
      d a_O = I da,  d q_O = -M_b da + dq,  d m_O = (M_b rho_L^ - S^) da + dm - rho_L^ dq,
    and the modal rows through the inertia (P_k = int mu Y_k) and the end loads."""
    m = ends.shape[0]
    e2 = (rot[0, 1], rot[1, 1], rot[2, 1])
    e3 = (rot[0, 2], rot[1, 2], rot[2, 2])
    mass = bp[1] * bp[0]
    rl_h = t_hat(t_of_vec(aux[1]))                      # rho_L^
    dm_da = t_lin9(mass, rl_h, -1.0, t_hat(t_of_vec(aux[0])))      # M_b rho_L^ - S^
    for i in range(3):
        d_o[i, i] = 1.0
        d_o[9 + i, i] = -mass
        d_o[9 + i, 9 + i] = 1.0
        d_o[6 + i, 6 + i] = 1.0
        for c in range(3):
            d_o[6 + i, c] = dm_da[3 * i + c]
            d_o[6 + i, 9 + c] = -rl_h[3 * i + c]
    for k in range(m):
        p_k = bp[1] * moments[k, 0]
        y_l, dy_l = ends[k, 0], ends[k, 1]
        for c in range(3):
            # inertia (d r''/d a_I = I) and the end force q_O
            d_r[k, c] = (p_k - mass * y_l) * e2[c]
            d_r[m + k, c] = (p_k - mass * y_l) * e3[c]
            d_r[k, 9 + c] = y_l * e2[c]
            d_r[m + k, 9 + c] = y_l * e3[c]
        if welded:
            # the end moment m_O through A J_l e3 (v) and -A J_l e2 (w)
            gv = t_of_vec(aux[3])
            gw = (-aux[2, 0], -aux[2, 1], -aux[2, 2])
            for c in range(3):
                ga_v = ga_w = gq_v = gq_w = 0.0
                for i in range(3):
                    ga_v += gv[i] * dm_da[3 * i + c]
                    ga_w += gw[i] * dm_da[3 * i + c]
                    gq_v -= gv[i] * rl_h[3 * i + c]
                    gq_w -= gw[i] * rl_h[3 * i + c]
                d_r[k, c] += dy_l * ga_v
                d_r[m + k, c] += dy_l * ga_w
                d_r[k, 9 + c] += dy_l * gq_v
                d_r[m + k, 9 + c] += dy_l * gq_w
                d_r[k, 6 + c] = dy_l * gv[c]
                d_r[m + k, 6 + c] = dy_l * gw[c]
    if bp[STIFFENING] != 0.0:
        # G eta's axial force: d N_L = M_b e1 . da - e1 . dq, d (mu gamma_x) = -mu e1 . da
        for plane in range(2):
            for l in range(m):
                row = plane * m + l
                d = aux[foreshortening_row(m, 0, plane) + l]
                c_a = mass * d[0] - bp[1] * d[1]
                for c in range(3):
                    d_r[row, c] += c_a * rot[c, 0]
                    d_r[row, 9 + c] -= d[0] * rot[c, 0]


@no_alloc_kernel
def _rotation_columns(bp, ends, rot, lam, w, wd, s, r, a_i, q_o, gravity, aux, d_o, d_r):
    """The Jacobian's w' columns (3:6) for a beam whose output carries no moment (docs/beam.md,
    "The w' columns"): every relation through w' itself, w (r = c3/c1) and the frame's rotation
    (s Lam, s = 1/c1; s = r = 0 at the consistent start), from the sums of beam_relations (aux):
      d q_O = -D(S, int mu U, int mu V),   d a_O = D(rho_L, U_L, V_L)  (D: point_jacobian_values)
      d m_O = -rho_L^ d q_O - J + r Dw + s Theta Lam - d T,
        Dw    = -(w^ J - (J w)^) - 2 (tr C E - C)
        Theta = -q_O^ rho_L^ + (g - a_I)^ S^ + (J w')^ - J w'^ + w^ ((J w)^ - J w^)
                - 2 (C w)^ + 2 C w^ + H^
        T     = j_p L (e1 (e1 . w') + (e1 . w) w x e1),  e1 = A e1
      d residual_(plane, l) = g^T D(Q_l, int mu Y_l U, int mu Y_l V)
                              + s (F_l x g + Y_l(L) g x q_O)^T Lam + Y_l(L) g^T d q_O.
    On values (3- and 9-tuples, kernels/algebra/mat3.py), like
    kernels/stepping/ball_chain.py::ball_body_map; x^ y^ = y x^T - (x . y) E throughout."""
    m = ends.shape[0]
    jp = bp[4] * bp[0]
    w_, wd_, lm = t_of_vec(w), t_of_vec(wd), t_of_mat(lam)
    kmat = kappa_values(w_, wd_)
    s_vec, rho_l = t_of_vec(aux[0]), t_of_vec(aux[1])
    sj, sc = t_of_mat(aux[SUM_J:SUM_J + 3]), t_of_mat(aux[SUM_C:SUM_C + 3])
    qo = t_of_vec(q_o)
    # a_O, the rotation slot (w' itself), q_O
    dcol = point_jacobian_values(rho_l, t_of_vec(aux[END_U]), t_of_vec(aux[END_V]), w_, kmat, lm,
                                 s, r)
    dq = t_scale9(-1.0, point_jacobian_values(s_vec, t_of_vec(aux[SUM_U]), t_of_vec(aux[SUM_V]),
                                              w_, kmat, lm, s, r))
    for i in range(3):
        for j in range(3):
            d_o[i, 3 + j] = dcol[3 * i + j]
            d_o[3 + i, 3 + j] = 1.0 if i == j else 0.0
            d_o[9 + i, 3 + j] = dq[3 * i + j]
    # m_O
    e1 = (rot[0, 0], rot[1, 0], rot[2, 0])
    jw, jwd, cw = t_mv(sj, w_), t_mv(sj, wd_), t_mv(sc, w_)
    ga = (gravity[0] - a_i[0], gravity[1] - a_i[1], gravity[2] - a_i[2])
    tr_c = sc[0] + sc[4] + sc[8]
    e1w = e1[0] * w[0] + e1[1] * w[1] + e1[2] * w[2]
    e1wd = e1[0] * wd[0] + e1[1] * wd[1] + e1[2] * wd[2]
    wxe = t_cross(w_, e1)
    exwd = t_cross(e1, wd_)
    # Theta (the rotation's part), then times Lam:
    # -q_O^ rho_L^ + (g - a_I)^ S^ - J w'^ + w^ ((J w)^ - J w^) + 2 C w^ + ((J w')^ - 2 (C w)^ + H^)
    qr = qo[0] * rho_l[0] + qo[1] * rho_l[1] + qo[2] * rho_l[2]
    gs = ga[0] * s_vec[0] + ga[1] * s_vec[1] + ga[2] * s_vec[2]
    theta = t_plus_diag(t_lin9(-1.0, t_outer(rho_l, qo), 1.0, t_outer(s_vec, ga)), qr - gs)
    theta = t_lin9(1.0, theta, -1.0, t_mul_hat(sj, wd_))
    theta = t_lin9(1.0, theta, 1.0,
                   t_hat_mul(w_, t_lin9(1.0, t_hat(jw), -1.0, t_mul_hat(sj, w_))))
    theta = t_lin9(1.0, theta, 2.0, t_mul_hat(sc, w_))
    sh = aux[SUM_H]
    theta = t_lin9(1.0, theta, 1.0, t_hat((jwd[0] - 2.0 * cw[0] + sh[0],
                                          jwd[1] - 2.0 * cw[1] + sh[1],
                                          jwd[2] - 2.0 * cw[2] + sh[2])))
    # minus T's rotation part: j_p L [-(e1 . w') e1^ + e1 (e1 x w')^T + (w x e1)(e1 x w)^T
    #                                 - (e1 . w) w^ e1^],  w^ e1^ = e1 w^T - (w . e1) E
    t_rot = t_lin9(1.0, t_outer(e1, exwd), -1.0, t_outer(wxe, wxe))
    t_rot = t_plus_diag(t_lin9(1.0, t_rot, -e1w, t_outer(e1, w_)), e1w * e1w)
    t_rot = t_lin9(1.0, t_rot, -e1wd, t_hat(e1))
    th_l = t_mm(t_lin9(1.0, theta, -jp, t_rot), lm)
    # d m_O = -rho_L^ dq - J + r Dw + s Theta Lam - (T's w' and w parts: j_p L e1 e1^T and
    # j_p L ((w x e1) e1^T - (e1 . w) e1^)), Dw = -(w^ J - (J w)^) - 2 (tr C E - C)
    dw = t_lin9(-1.0, t_hat_mul(w_, sj), 2.0, sc)
    dw = t_lin9(1.0, dw, -jp, t_outer(wxe, e1))
    dw = t_plus_diag(dw, -2.0 * tr_c)
    dw = t_lin9(1.0, dw, 1.0, t_hat((jw[0] + jp * e1w * e1[0], jw[1] + jp * e1w * e1[1],
                                    jw[2] + jp * e1w * e1[2])))
    dm = t_lin9(-1.0, t_hat_mul(rho_l, dq), -1.0, sj)
    dm = t_lin9(1.0, dm, s, th_l)
    dm = t_lin9(1.0, dm, -jp, t_outer(e1, e1))
    dm = t_lin9(1.0, dm, r, dw)
    for i in range(3):
        for j in range(3):
            d_o[6 + i, 3 + j] = dm[3 * i + j]
    # modal rows (D(Q_l, ..) is the same for both planes)
    for l in range(m):
        y_l = ends[l, 0]
        dcol = point_jacobian_values(t_of_vec(aux[SUM_MODES + m + l]),
                                     t_of_vec(aux[SUM_MODES + 2 * m + l]),
                                     t_of_vec(aux[SUM_MODES + 3 * m + l]), w_, kmat, lm, s, r)
        f_l = t_of_vec(aux[SUM_MODES + l])
        for plane in range(2):
            g = (rot[0, 1 + plane], rot[1, 1 + plane], rot[2, 1 + plane])
            gq = t_cross(g, qo)
            fg = t_cross(f_l, g)
            vec = (fg[0] + y_l * gq[0], fg[1] + y_l * gq[1], fg[2] + y_l * gq[2])
            row = plane * m + l
            for j in range(3):
                x = s * (vec[0] * lm[j] + vec[1] * lm[3 + j] + vec[2] * lm[6 + j])
                for i in range(3):
                    x += g[i] * (dcol[3 * i + j] + y_l * dq[3 * i + j])
                d_r[row, 3 + j] = x
    if bp[STIFFENING] != 0.0:
        # G eta through the frame's rotation (d theta = s Lam e_j) and w (r e_j):
        # d N_L = -d theta . (e1 x q_O) - e1 . d q_O, d gamma_x = d theta . (e1 x (g - a_I)),
        # d (omega_y^2 + omega_z^2) = 2 r w_j - 2 (e1 . w) (r e1_j + d theta . (e1 x w))
        mu = bp[1]
        e1q, e1g, e1x = t_cross(e1, qo), t_cross(e1, ga), t_cross(e1, w_)
        for j in range(3):
            l0, l1, l2 = lm[j], lm[3 + j], lm[6 + j]
            dn = (-s * (l0 * e1q[0] + l1 * e1q[1] + l2 * e1q[2])
                  - (e1[0] * dq[j] + e1[1] * dq[3 + j] + e1[2] * dq[6 + j]))
            dg = mu * s * (l0 * e1g[0] + l1 * e1g[1] + l2 * e1g[2])
            dw2 = mu * (2.0 * r * w[j]
                        - 2.0 * e1w * (r * e1[j] + s * (l0 * e1x[0] + l1 * e1x[1] + l2 * e1x[2])))
            for plane in range(2):
                for l in range(m):
                    d = aux[foreshortening_row(m, 0, plane) + l]
                    d_r[plane * m + l, 3 + j] += dn * d[0] + dg * d[1] + dw2 * d[2]


@no_alloc_kernel
def _modal_columns(bp, tables, rot, w, wd, s, r, q_o, aux, d_o, d_r, scratch):
    """The Jacobian's eta'' columns (12 + p) for a beam whose output carries no moment
    (docs/beam.md, "The eta'' columns"): eta''_p moves eta_p by s = 1/c1 and eta'_p by
    r = c3/c1 (s = r = 0 at the consistent start), so every point's acceleration by Y_k(x) G
    with g = A e2 (v plane) or A e3 (w plane) and G = g + 2 r w x g + s (w' x g + w x (w x g));
    with P_k = int mu Y_k, F_k = int Y_k f, Q_k = int mu Y_k rho (aux) and M_kl = int mu Y_k Y_l:
      d a_O = Y_k(L) G,  d q_O = -P_k G,
      d m_O = -s Y_k(L) g x q_O - rho_L x d q_O + s g x F_k - Q_k x G,
      d residual_(plane', l) = M_lk g'.G + Y_l(L) g'.d q_O  (+ r 2 zeta omega_k M_k + s K_k on
      the diagonal: damping and stiffness).  scratch: 6 entries."""
    moments, ends, factors = tables[0], tables[1], tables[2]
    mu, ei_v, ei_w, zeta = bp[1], bp[2], bp[3], bp[5]
    stiff = bp[STIFFENING] != 0.0
    m = ends.shape[0]
    rho_l = aux[1]
    big_g, d_q = scratch[0:3], scratch[3:6]
    for plane in range(2):
        g = rot[:, 1 + plane]
        g0, g1, g2 = g[0], g[1], g[2]
        wg0, wg1, wg2 = w[1] * g2 - w[2] * g1, w[2] * g0 - w[0] * g2, w[0] * g1 - w[1] * g0
        big_g[0] = g0 + 2.0 * r * wg0 + s * (wd[1] * g2 - wd[2] * g1 + w[1] * wg2 - w[2] * wg1)
        big_g[1] = g1 + 2.0 * r * wg1 + s * (wd[2] * g0 - wd[0] * g2 + w[2] * wg0 - w[0] * wg2)
        big_g[2] = g2 + 2.0 * r * wg2 + s * (wd[0] * g1 - wd[1] * g0 + w[0] * wg1 - w[1] * wg0)
        for k in range(m):
            col = 12 + plane * m + k
            p_k = mu * moments[k, 0]
            y_l = ends[k, 0]
            f_k = aux[SUM_MODES + k]
            q_k = aux[SUM_MODES + m + k]
            for i in range(3):
                d_q[i] = -p_k * big_g[i]
            for i in range(3):
                i1, i2 = (i + 1) % 3, (i + 2) % 3
                d_o[i, col] = y_l * big_g[i]
                d_o[3 + i, col] = 0.0
                d_o[6 + i, col] = (-s * y_l * (g[i1] * q_o[i2] - g[i2] * q_o[i1])   # d rho_L x q_O
                                   + s * (g[i1] * f_k[i2] - g[i2] * f_k[i1])
                                   - (q_k[i1] * big_g[i2] - q_k[i2] * big_g[i1]))
            if stiff:
                _foreshortening_column(mu, m, plane, k, s, r, rot, w, wd, q_o, aux, d_q, d_o,
                                       col)
            for i in range(3):
                i1, i2 = (i + 1) % 3, (i + 2) % 3
                d_o[6 + i, col] -= rho_l[i1] * d_q[i2] - rho_l[i2] * d_q[i1]
                d_o[9 + i, col] = d_q[i]
            for plane2 in range(2):
                h0, h1, h2 = rot[0, 1 + plane2], rot[1, 1 + plane2], rot[2, 1 + plane2]
                h_dot_g = h0 * big_g[0] + h1 * big_g[1] + h2 * big_g[2]
                h_dot_q = h0 * d_q[0] + h1 * d_q[1] + h2 * d_q[2]
                for l in range(m):
                    d_r[plane2 * m + l, col] = (mu * moments[l, 2 + k] * h_dot_g
                                                + ends[l, 0] * h_dot_q)
            modal_mass = mu * factors[k, 0]
            stiffness = (ei_v if plane == 0 else ei_w) * factors[k, 1]
            omega_k = np.sqrt(stiffness / modal_mass)
            d_r[plane * m + k, col] += r * 2.0 * zeta * omega_k * modal_mass + s * stiffness
            if stiff:
                # G eta: eta_k moves by s (G's column k), N_L by -e1 . d q_O
                e1q = rot[0, 0] * d_q[0] + rot[1, 0] * d_q[1] + rot[2, 0] * d_q[2]
                for plane2 in range(2):
                    for l in range(m):
                        d_r[plane2 * m + l, col] -= \
                            e1q * aux[foreshortening_row(m, 0, plane2) + l, 0]
                coef = aux[coefficient_row(m)]
                for l in range(m):
                    d_r[plane * m + l, col] += s * (coef[0] * moments[l, 2 + m + k]
                                                    + coef[1] * moments[l, 2 + 2 * m + k]
                                                    + coef[2] * moments[l, 2 + 3 * m + k])


@no_alloc_kernel
def _end_moment_columns(ends, eta, rot, lam, s, start, m_net, welded, phi_out, aux, d_o, d_r,
                        scratch):
    """The end moment's share of the w' (3:6) and eta'' (12 + p) columns (docs/beam.md, "The
    end moment's columns"), after _modal_columns and _rotation_columns have filled d_o's m_O
    rows: add_end_moment's r_v,k += Y_k'(L) m . a3, r_w,k -= Y_k'(L) m . a2, a_i = A J_l e_i,
    J_l = J_l(theta_O), m = m_O - T (m_net), change by
      d/dw'_j:    Y_k'(L) (dm_O/dw'_j . a3 + s (a3 x m) . Lam e_j)     (A turns by s Lam dw')
      d/deta''_p: Y_k'(L) (dm_O/deta''_p . a3 + s m . A DJ_l[theta_p] e3)
    (w alike with a2 and the sign), theta_p = d theta_O / d eta_p (e3 Y_p'(L) in the v plane,
    -e2 Y_p'(L) in the w plane).  welded: the output's rotation slot c1 phi_out + w1 with
    J_l(phi_out) dphi_out = s Lam dw' + A J_l theta_p s deta''_p (A_out = A exp(theta_O^) R_rel),
    so its columns are J_l(phi_out)^-1 Lam and J_l(phi_out)^-1 A J_l theta_p (c1 s = 1); at
    the start I and A J_l theta_p.  eta: the modal coordinates at the guess; scratch: 30."""
    m = ends.shape[0]
    a2, a3 = aux[2], aux[3]
    theta, delta = scratch[0:3], scratch[3:6]
    dj = scratch[6:15].reshape((3, 3))
    jinv = scratch[15:24].reshape((3, 3))
    tmp = scratch[24:30]
    _end_angles_into(ends, ends[:0], eta, theta)     # theta_O (no twist here)
    # the w' columns
    x3 = t_cross((a3[0], a3[1], a3[2]), (m_net[0], m_net[1], m_net[2]))
    x2 = t_cross((a2[0], a2[1], a2[2]), (m_net[0], m_net[1], m_net[2]))
    for j in range(3):
        dv = dw = 0.0
        for i in range(3):
            dv += d_o[6 + i, 3 + j] * a3[i] + s * x3[i] * lam[i, j]
            dw -= d_o[6 + i, 3 + j] * a2[i] + s * x2[i] * lam[i, j]
        for k in range(m):
            d_r[k, 3 + j] += ends[k, 1] * dv
            d_r[m + k, 3 + j] += ends[k, 1] * dw
    # the eta'' columns: DJ_l is linear in theta_p = Y_p'(L) (e3 or -e2), so the two
    # directions' s m . A DJ_l[e_d] e_i = s (A^T m) . DJ_l[e_d] e_i serve every mode
    for i in range(3):
        tmp[i] = s * (rot[0, i] * m_net[0] + rot[1, i] * m_net[1] + rot[2, i] * m_net[2])
    delta[0] = delta[1] = 0.0
    delta[2] = 1.0
    left_jacobian_derivative(theta, delta, dj)              # the v plane: theta_p = e3 Y_p'
    kv3 = tmp[0] * dj[0, 2] + tmp[1] * dj[1, 2] + tmp[2] * dj[2, 2]
    kv2 = tmp[0] * dj[0, 1] + tmp[1] * dj[1, 1] + tmp[2] * dj[2, 1]
    delta[1] = -1.0
    delta[2] = 0.0
    left_jacobian_derivative(theta, delta, dj)              # the w plane: theta_p = -e2 Y_p'
    kw3 = tmp[0] * dj[0, 2] + tmp[1] * dj[1, 2] + tmp[2] * dj[2, 2]
    kw2 = tmp[0] * dj[0, 1] + tmp[1] * dj[1, 1] + tmp[2] * dj[2, 1]
    for p in range(2 * m):
        col = 12 + p
        dy = ends[p % m, 1]
        dv = dy * (kw3 if p >= m else kv3)
        dw = -dy * (kw2 if p >= m else kv2)
        for i in range(3):
            dv += d_o[6 + i, col] * a3[i]
            dw -= d_o[6 + i, col] * a2[i]
        for k in range(m):
            d_r[k, col] += ends[k, 1] * dv
            d_r[m + k, col] += ends[k, 1] * dw
    if not welded:
        return
    # the output's rotation slot
    if start:
        for i in range(3):
            for j in range(3):
                jinv[i, j] = 1.0 if i == j else 0.0
    else:
        left_jacobian(phi_out, dj)
        inv = t_inverse(t_of_mat(dj))[1]
        for i in range(3):
            for j in range(3):
                jinv[i, j] = inv[3 * i + j]
    for i in range(3):
        for j in range(3):
            d_o[3 + i, 3 + j] = (lam[0, j] * jinv[i, 0] + lam[1, j] * jinv[i, 1]
                                 + lam[2, j] * jinv[i, 2]) if not start else jinv[i, j]
    for i in range(3):
        tmp[i] = jinv[i, 0] * a3[0] + jinv[i, 1] * a3[1] + jinv[i, 2] * a3[2]
        tmp[3 + i] = -(jinv[i, 0] * a2[0] + jinv[i, 1] * a2[1] + jinv[i, 2] * a2[2])
    for k in range(m):
        for i in range(3):
            d_o[3 + i, 12 + k] = ends[k, 1] * tmp[i]
            d_o[3 + i, 12 + m + k] = ends[k, 1] * tmp[3 + i]


@kernel
def _foreshortening_column(mu, m, plane, k, s, r, rot, w, wd, q_o, aux, d_q, d_o, col):
    """The foreshortening's share of an eta'' column (docs/beam.md, "Geometric stiffening"):
    eta''_k moves C_i = 1/2 eta^T D_i eta by s (D_i eta)_k, C_i' by r (D_i eta)_k + s (D_i eta')_k
    and C_i'' by (D_i eta)_k + 2 r (D_i eta')_k + s (D_i eta'')_k; with e1 = A e1,
    K(x) = w' x x + w x (w x x) and gamma = g - a_I:
      d q_O += mu (dC1 K(e1) + 2 dC1' w x e1 + dC1'' e1)            (d_q, before its uses)
      d a_O -= dC0 K(e1) + 2 dC0' w x e1 + dC0'' e1
      d m_O += dC0 e1 x q_O + mu (-dC1 e1 x gamma + 2 dC2 (w' - e1 (e1 . w'))
               - 2 dC2 (e1 . w) w x e1 + 2 dC2' (w - e1 (e1 . w)))     (-rho_L x d q_O apart)."""
    x = aux[foreshortening_row(m, 0, plane) + k]
    y = aux[foreshortening_row(m, 1, plane) + k]
    z = aux[foreshortening_row(m, 2, plane) + k]
    ga = aux[coefficient_row(m) + 1]
    dc0, dcd0, dcdd0 = s * x[0], r * x[0] + s * y[0], x[0] + 2.0 * r * y[0] + s * z[0]
    dc1, dcd1, dcdd1 = s * x[1], r * x[1] + s * y[1], x[1] + 2.0 * r * y[1] + s * z[1]
    dc2, dcd2 = s * x[2], r * x[2] + s * y[2]
    e = (rot[0, 0], rot[1, 0], rot[2, 0])
    we = t_cross((w[0], w[1], w[2]), e)
    wde = t_cross((wd[0], wd[1], wd[2]), e)
    wwe = t_cross((w[0], w[1], w[2]), we)
    e_w = e[0] * w[0] + e[1] * w[1] + e[2] * w[2]
    e_wd = e[0] * wd[0] + e[1] * wd[1] + e[2] * wd[2]
    eq = t_cross(e, (q_o[0], q_o[1], q_o[2]))
    eg = t_cross(e, (ga[0], ga[1], ga[2]))
    for i in range(3):
        ke = wde[i] + wwe[i]
        d_q[i] += mu * (dc1 * ke + 2.0 * dcd1 * we[i] + dcdd1 * e[i])
        d_o[i, col] -= dc0 * ke + 2.0 * dcd0 * we[i] + dcdd0 * e[i]
        d_o[6 + i, col] += dc0 * eq[i] + mu * (-dc1 * eg[i] + 2.0 * dc2 * (wd[i] - e[i] * e_wd)
                                               - 2.0 * dc2 * e_w * we[i]
                                               + 2.0 * dcd2 * (w[i] - e[i] * e_w))


@no_alloc_kernel
def _solve_in_place(a, b, n_rhs):
    """b[:, :n_rhs] <- a^-1 b[:, :n_rhs] by Gaussian elimination with partial pivoting (a is
    overwritten; its first a.shape[0] columns are the matrix): the modal systems are small
    (2 .. 12), where LAPACK's call overhead dominates.  A singular a leaves b NaN, which the
    step's finite check reports (rather than a division error)."""
    n = a.shape[0]
    for k in range(n):
        p = k
        for r in range(k + 1, n):
            if abs(a[r, k]) > abs(a[p, k]):
                p = r
        if p != k:
            for c in range(n):
                a[k, c], a[p, c] = a[p, c], a[k, c]
            for c in range(n_rhs):
                b[k, c], b[p, c] = b[p, c], b[k, c]
        piv = a[k, k]
        if piv == 0.0:
            for r in range(n):
                for c in range(n_rhs):
                    b[r, c] = np.nan
            return
        for r in range(k + 1, n):
            f = a[r, k] / piv
            if f != 0.0:
                for c in range(k + 1, n):
                    a[r, c] -= f * a[k, c]
                for c in range(n_rhs):
                    b[r, c] -= f * b[k, c]
    for k in range(n - 1, -1, -1):
        inv = 1.0 / a[k, k]
        for c in range(n_rhs):
            s = b[k, c]
            for j in range(k + 1, n):
                s -= a[k, j] * b[j, c]
            b[k, c] = s * inv


@kernel(entry=True)
def transfer_work_size(n):
    """The length of beam_transfer's work block for a beam of n modal coordinates."""
    nx, nw, na = 12 + n, 75 + 2 * n, 3 * aux_rows(n // 2)
    return 2 * nx + 24 + 2 * n + 12 + na + 2 * nw + 12 * nx + n * nx + 13 * n + n * n + 57


@no_alloc_kernel
def beam_transfer(bp, tables, outboard, history, gravity, start, rot_n, phi_star, wd_star, c1,
                  c3, w3, w_n, w1e, w3e, eta_n, eta_d_n, z_star, eta_dd_star, u, eta_map, block):
    """Fill u (12 x 13) with z_O = u [z_I; 1] in angular-acceleration slots, and eta_map
    (n x 13) with eta'' = eta_map [z_I; 1], linearized about (z_star, eta_dd_star); z_star's
    rotation slots are not read (the guess there is wd_star).  block: the work, at least
    transfer_work_size(n) long (nothing is allocated: the general loop passes its own).

    start: the consistent-start solve (rotation, rates and modal state fixed, w' and eta''
    free).  Otherwise phi = phi* + (w' - wd*) / c1, w = c3 phi + w3, eta = (eta'' - w1e) / c1,
    eta' = c3 eta + w3e.  tables, outboard, history: see _evaluate."""
    welded = outboard[0]
    ends = tables[1]
    # an end moment works on the modes: at a weld (the outboard's couple) or under an applied
    # end torque; then the modal equations depend on m_I and their w', eta'' columns are
    # differenced (add_end_moment)
    end_moment = welded or _any(tables[4])
    twist = tables[6].shape[0] > 0
    stretch = tables[7].shape[0] > 0
    n = eta_dd_star.shape[0]
    nx = 12 + n
    # every array of the linearization carved out of the one block
    nw = 75 + 2 * n
    na = 3 * aux_rows(n // 2)
    x0, xp = block[0:nx], block[nx:2 * nx]
    o = 2 * nx
    o0, op, r0, rp = block[o:o + 12], block[o + 12:o + 24], block[o + 24:o + 24 + n], \
        block[o + 24 + n:o + 24 + 2 * n]
    o += 24 + 2 * n
    aux = block[o:o + na].reshape((na // 3, 3))             # with every sum
    aux_fd = block[o + na:o + na + 12].reshape((4, 3))
    o += na + 12
    work, work_fd = block[o:o + nw], block[o + nw:o + 2 * nw]
    o += 2 * nw
    d_o = block[o:o + 12 * nx].reshape((12, nx))
    o += 12 * nx
    d_r = block[o:o + n * nx].reshape((n, nx))
    o += n * nx
    rhs = block[o:o + 13 * n].reshape((n, 13))
    o += 13 * n
    modal = block[o:o + n * n].reshape((n, n))
    o += n * n
    lam = block[o:o + 9].reshape((3, 3))
    columns_scratch = block[o + 9:o + 15]
    q_net = block[o + 15:o + 18]
    g_beam = block[o + 18:o + 21]
    moment_scratch = block[o + 21:o + 57]      # _end_moment_columns' (30), m_net, phi_out
    follower = bp[LOAD_AXES] != 0.0
    if follower:                 # the distributed load turns with the frame: _evaluate adds it
        for i in range(3):
            g_beam[i] = gravity[i]
    else:
        _beam_gravity(bp, gravity, tables[5], g_beam)
    for i in range(12):         # (element by element: a slice copy needs numba's runtime)
        x0[i] = wd_star[i - 3] if 3 <= i < 6 else z_star[i]
    for i in range(n):
        x0[12 + i] = eta_dd_star[i]
    _evaluate(bp, tables, outboard, history, g_beam, start, rot_n, phi_star, wd_star, c1,
              c3, w3, w_n, w1e, w3e, eta_n, eta_d_n, x0, o0, r0, aux, work)
    rot = rot_n if start else work[9:18].reshape((3, 3))      # (the state _evaluate left)
    d_o[:, :] = 0.0
    d_r[:, :] = 0.0
    _affine_columns(bp, tables[0], ends, end_moment, rot, aux, d_o, d_r)
    if twist and end_moment:
        _twist_end_columns(ends, tables[6], eta_n if start else work[24:24 + n], rot, d_o, d_r,
                           moment_scratch[:12])
    if stretch:
        _stretch_affine_columns(bp, tables[7], rot, d_r)
    # w' and eta'' columns written out unless the beam twists (docs/beam.md, "Torsion") or
    # stretches, keeps its foreshortening exactly, its loads follow it (load_axes="body") or the
    # output has its own history (the paper's scheme); there, forward differences
    analytic = (not twist and not stretch and not follower and bp[STIFFENING] != EXACT
                and not (history[0] and not start))
    if analytic:
        w = w_n if start else work[21:24]
        s_c, r_c = (0.0, 0.0) if start else (1.0 / c1, c3 / c1)
        left_jacobian(phi_star, lam)
        for i in range(3):              # the outboard's net pull (an applied end force apart)
            q_net[i] = o0[9 + i] - tables[3][i]
        _modal_columns(bp, tables, rot, w, x0[3:6], s_c, r_c, q_net, aux, d_o, d_r,
                       columns_scratch)
        _rotation_columns(bp, ends, rot, lam, w, x0[3:6], s_c, r_c, x0[0:3], q_net, g_beam,
                          aux, d_o, d_r)
        if end_moment:      # a weld's or an applied end torque's moment on the modes
            m_net, phi_out = moment_scratch[30:33], moment_scratch[33:36]
            for i in range(3):
                m_net[i] = o0[6 + i] - tables[4][i]
                phi_out[i] = (o0[3 + i] - outboard[3][i]) / c1
            _end_moment_columns(ends, eta_n if start else work[24:24 + n], rot, lam, s_c, start,
                                m_net, welded, phi_out, aux, d_o, d_r, moment_scratch[:30])
    for i in range(nx):
        xp[i] = x0[i]
    for c in range(3, nx):
        if 6 <= c < 12 or analytic:
            continue                     # a_I, m_I, q_I (_affine_columns), the rest where
            #                              written out (_modal_columns, _rotation_columns)
        # one-sided: the relations are affine in w' and eta'' up to terms scaled by 1 / c1 (w'
        # and eta'' reach the rotation and eta through phi = phi* + (w' - wd*) / c1 and
        # eta = (eta'' - w1e) / c1), so a forward difference is as exact as a central one
        # (measured: the stiff cantilever's accelerations agree to 1e-10 after the first steps)
        step = 1e-3 * (1.0 + abs(x0[c]))
        xp[c] = x0[c] + step
        _evaluate(bp, tables, outboard, history, g_beam, start, rot_n, phi_star, wd_star, c1,
                  c3, w3, w_n, w1e, w3e, eta_n, eta_d_n, xp, op, rp, aux_fd, work_fd)
        xp[c] = x0[c]
        for r in range(12):
            d_o[r, c] = (op[r] - o0[r]) / step
        for r in range(n):
            d_r[r, c] = (rp[r] - r0[r]) / step
    # modal equations r0 + d_r[:, :12] dz + d_r[:, 12:] dy = 0, solved for dy (dz = z - z*):
    # X = -d_r[:, 12:]^-1 [d_r[:, :12], r0] (rhs, the columns of z then the constant), so
    # eta'' = eta_map [z; 1] with eta_map = [X_z, eta''* + x_c - X_z z*]
    for r in range(n):
        for c in range(12):
            rhs[r, c] = -d_r[r, c]
        rhs[r, 12] = -r0[r]
        for c in range(n):
            modal[r, c] = d_r[r, 12 + c]
    _solve_in_place(modal, rhs, 13)
    for r in range(n):
        e0 = eta_dd_star[r] + rhs[r, 12]
        for c in range(12):
            eta_map[r, c] = rhs[r, c]
            e0 -= rhs[r, c] * x0[c]
        eta_map[r, 12] = e0
    # outputs: o0 + d_o[:, :12] dz + d_o[:, 12:] dy  =  u [z; 1], by rows (the inner loop along
    # a row of rhs: measured twice as fast as the column-by-column sums); a zero entry of d_o's
    # modal columns (the w' slot's rows where the columns are written out and the output is not
    # welded: _modal_columns) skips its row of rhs
    for r in range(12):
        for c in range(12):
            u[r, c] = d_o[r, c]
        u[r, 12] = o0[r]
        for i in range(n):
            f = d_o[r, 12 + i]
            if f != 0.0:
                for c in range(13):
                    u[r, c] += f * rhs[i, c]
        const = u[r, 12]
        for c in range(12):
            const -= u[r, c] * x0[c]
        u[r, 12] = const


@kernel(entry=True)
def ball_map_work_shape(n):
    """Shape of beam_ball_map's work block for up to n modal coordinates, rows of 12 + n entries:
    19 rows of vectors and 3 x 3 blocks, aux, d_o (12), d_r, kmat, xm (n each), g (3 + n)."""
    return 19 + aux_rows(n // 2) + 12 + 3 * n + 3 + n, 12 + n


@no_alloc_kernel
def beam_ball_map(bp, tables, gravity, rot_n, phi_star, wd_star, coefficients, w3, w1e, w3e, a_i,
                  q_i, eta_dd_star, work, v, pmap, emap):
    """A beam between moment-free cuts (ball joints, the free tip; Newmark steps), folded
    straight into the fused loop's reduced maps (docs/beam.md, "Between ball joints"):
      [a_O; q_O] = v [a_I; q_I; 1],   w' = pmap [a_I; q_I; 1],   eta'' = emap[:, :7] [a_I; q_I; 1],
    linearized about (a_I*, w'*, q_I*, eta''*) = (a_i, wd_star, q_i, eta_dd_star).  The same
    relations and columns as beam_transfer (beam_relations, _affine_columns, _modal_columns,
    _rotation_columns) with m_I = 0; the moment rows (m_O = 0) and the modal rows are solved
    together for (w', eta'') by blocks (the modal system, then a 3 x 3 Schur complement),
    which replaces beam_transfer's modal solve, its 12 x 13 product and sweep.fold_ball_body.
    coefficients: (c1, c3, s, r), the integrator's w' = c1 phi + w1, w = c3 phi + w3 and the
    sensitivities s = d phi / d w', r = d w / d w' of the rotation and the modal coordinates
    (1 / c1 and c3 / c1 in a step; 0 at the consistent start, where nothing but the
    accelerations moves: kernels/stepping/ball_chain.py::start_loop).  The other arguments as for
    beam_transfer (eta and eta' come from eta''* through w1e and w3e).  work: a block of at
    least ball_map_work_shape(n) (no allocation), carved by rows:
    each array below is a block of whole rows (or a row's start), which keeps it contiguous (a
    reshape costs a call into numba's runtime, and a block of columns is strided)."""
    moments, ends = tables[0], tables[1]
    c1, c3, s_c, r_c = coefficients[0], coefficients[1], coefficients[2], coefficients[3]
    n = eta_dd_star.shape[0]
    nx, ny = 12 + n, 3 + n
    x0, o0, r0, w = work[0][0:nx], work[1][0:12], work[2][0:n], work[3][0:3]
    eta, eta_d, scratch = work[4][0:n], work[5][0:n], work[6][0:6]
    e, rot, lam, smat = work[7:10], work[10:13], work[13:16], work[16:19]   # 3 x 3 (in rows)
    o = 19
    na = aux_rows(n // 2)
    aux = work[o:o + na]
    o += na
    d_o = work[o:o + 12]
    o += 12
    d_r = work[o:o + n]
    o += n
    kmat = work[o:o + n]
    o += n
    xm = work[o:o + n]                       # its first 10 columns
    o += n
    g = work[o:o + ny]                       # its first 7 columns
    for i in range(3):
        x0[i], x0[3 + i], x0[6 + i], x0[9 + i] = a_i[i], wd_star[i], 0.0, q_i[i]
    for i in range(n):
        x0[12 + i] = eta_dd_star[i]
    _step_state(phi_star, c1, c3, w3, rot_n, eta_dd_star, w1e, w3e, e, rot, w, eta, eta_d)
    g_beam = work[3][6:9]                    # gravity and the distributed load per unit mass
    _beam_gravity(bp, gravity, tables[5], g_beam)
    beam_relations(bp, moments, ends, tables[2], tables[3], tables[4], g_beam, rot, w, wd_star,
                   eta, eta_d, eta_dd_star, a_i, x0[6:9], q_i, o0, r0, aux, ends[:0])
    d_o[:, :] = 0.0
    d_r[:, :] = 0.0
    _affine_columns(bp, moments, ends, False, rot, aux, d_o, d_r)
    left_jacobian(phi_star, lam)
    q_net = work[3][3:6]                     # the outboard's net pull (an end force apart)
    for i in range(3):
        q_net[i] = o0[9 + i] - tables[3][i]
    _modal_columns(bp, tables, rot, w, wd_star, s_c, r_c, q_net, aux, d_o, d_r, scratch)
    _rotation_columns(bp, ends, rot, lam, w, wd_star, s_c, r_c, a_i, q_net, g_beam, aux,
                      d_o, d_r)
    # rows m_O (d_o 6:9) and the modal residuals (d_r) in the unknowns y = [w', eta''] (columns
    # 3:6, 12:): K (y - y*) = -(B (z - z*) + c), z = [a_I; q_I] (columns 0:3, 9:12), so
    # y = y* + G [z - z*; 1] with G = -K^-1 [B, c].  By blocks, K = [[K_mw, K_me], [K_rw, K_re]]:
    # X = K_re^-1 [K_rw, -B_r, -c_r] (the modal system), the Schur complement
    # S = K_mw - K_me X_w, then G_w = S^-1 (-[B_m, c_m] - K_me X_z), G_eta = X_z - X_w G_w
    for i in range(n):
        for j in range(n):
            kmat[i, j] = d_r[i, 12 + j]
        for j in range(3):
            xm[i, j] = d_r[i, 3 + j]
        for c in range(6):
            xm[i, 3 + c] = -d_r[i, c if c < 3 else c + 6]
        xm[i, 9] = -r0[i]
    _solve_in_place(kmat, xm, 10)
    # S in smat, -[B_m, c_m] - K_me X_z in g's first rows; every product below by rows (the
    # inner loops along a row, free of chained sums: measured, the column-by-column products
    # were latency-bound)
    for i in range(3):
        r = 6 + i
        for c in range(7):
            g[i, c] = -(d_o[r, c if c < 3 else c + 6] if c < 6 else o0[r])
        for j in range(3):
            smat[i, j] = d_o[r, 3 + j]
        for l in range(n):
            k_l = d_o[r, 12 + l]
            for j in range(3):
                smat[i, j] -= k_l * xm[l, j]
            for c in range(7):
                g[i, c] -= k_l * xm[l, 3 + c]
    det, s_inv = t_inverse(t_of_mat(smat))
    if det == 0.0:
        s_inv = (np.nan, np.nan, np.nan, np.nan, np.nan, np.nan, np.nan, np.nan, np.nan)
    for c in range(7):                       # G_w = S^-1 (-[B_m, c_m] - K_me X_z)
        r_0, r_1, r_2 = g[0, c], g[1, c], g[2, c]
        for i in range(3):
            g[i, c] = s_inv[3 * i] * r_0 + s_inv[3 * i + 1] * r_1 + s_inv[3 * i + 2] * r_2
    for l in range(n):                       # G_eta = X_z - X_w G_w
        x_0, x_1, x_2 = xm[l, 0], xm[l, 1], xm[l, 2]
        for c in range(7):
            g[3 + l, c] = xm[l, 3 + c] - (x_0 * g[0, c] + x_1 * g[1, c] + x_2 * g[2, c])
    for i in range(ny):                      # the maps of w' and eta'' over [a_I; q_I; 1]
        const = (wd_star[i] if i < 3 else eta_dd_star[i - 3]) + g[i, 6]
        for c in range(6):
            const -= g[i, c] * (a_i[c] if c < 3 else q_i[c - 3])
            if i < 3:
                pmap[i, c] = g[i, c]
            else:
                emap[i - 3, c] = g[i, c]
        if i < 3:
            pmap[i, 6] = const
        else:
            emap[i - 3, 6] = const
    for r in range(6):                       # [a_O; q_O] = o0 + D_z (z - z*) + D_y G [z - z*; 1]
        row = d_o[r if r < 3 else r + 6]
        for c in range(7):
            v[r, c] = row[c if c < 3 else c + 6] if c < 6 else o0[r if r < 3 else r + 6]
        for j in range(ny):
            d_j = row[3 + j if j < 3 else 9 + j]
            for c in range(7):
                v[r, c] += d_j * g[j, c]
        for c in range(6):
            v[r, 6] -= v[r, c] * (a_i[c] if c < 3 else q_i[c - 3])
