"""A modal beam's nonlinear relations over a step (docs/beam.md): its modal equations and end
loads from its frame and modal coordinates (beam_relations, twist_relations, the exact
foreshortening's line integrals), its end section's frame and motion (end_section,
end_section_motion), and the quadrature tables they read.  Its transfer over the step, the
relations linearized and the modal accelerations eliminated, is beam.py."""
import numpy as np
from numba import njit

from ...elements.beam import EA, EXACT, GJ, STIFFENING
from .. import CONTRACT, kernel, no_alloc_kernel
from ..algebra.mat3 import (mm3_into, t_mm,
                            t_of_mat)
from ..algebra.so3 import expm_so3, left_jacobian, left_jacobian_derivative


# rows of beam_relations' aux beyond the first four (docs/beam.md, "The w' and eta'' columns"):
# int mu A u', int mu A u'', int mu rho x A u''; A u'(L), A u''(L); J = int mu (|rho|^2 E -
# rho rho^T) (3 rows); C = int mu (A u') rho^T (3 rows); then per mode k < m: F_k = int Y_k f,
# Q_k = int mu Y_k rho, int mu Y_k A u', int mu Y_k A u''; then, with geometric stiffening
# (docs/beam.md), per mode l < m of each plane (v, then w): (D0 x, D1 x, D2 x)_l for x = eta,
# eta', eta'' (foreshortening_row), the axial force's coefficients (N_L, mu gamma_x,
# mu (omega_y^2 + omega_z^2)) and g - a_I (world) (coefficient_row)
SUM_U, SUM_V, SUM_H, END_U, END_V, SUM_J, SUM_C, SUM_MODES = 4, 5, 6, 7, 8, 9, 12, 15


@kernel
def aux_rows(m):
    """Rows of the aux array with every sum (m modes per plane)."""
    return SUM_MODES + 10 * m + 2


@kernel
def foreshortening_row(m, which, plane):
    """First aux row of a plane's (D0 x, D1 x, D2 x), x = eta (which 0), eta' (1), eta'' (2)."""
    return SUM_MODES + (4 + 2 * which + plane) * m


@kernel
def coefficient_row(m):
    """aux row of (N_L, mu gamma_x, mu (omega_y^2 + omega_z^2)); the next holds g - a_I."""
    return SUM_MODES + 10 * m


def quadrature_size(modes_per_plane):
    """Gauss-Legendre points that integrate the beam's modal integrals (run_tables.beam_tables) to
    rounding, for every mode family.  Measured when the kernel still sampled the relations
    themselves (products of up to three mode-shape factors, more than the modal integrals'
    two), against 60 points on random states: the largest relative error is 2e-16 at 12
    points for 1 mode per plane, 2e-16 at 12 for 2 modes, 6e-16 at 14 for 3, 3e-16 at 16 for
    4, 2e-16 at 20 for 6; 24 points leave 5e-13 at 7 modes and 1e-6 at 10 (products of sine
    modes with x^2).  So 2 m + 10 points, and 3 m + 6 beyond 4 modes."""
    m = int(modes_per_plane)
    return max(2 * m + 10, 3 * m + 6)


def gauss_points(length, n_points):
    """n_points Gauss-Legendre points and weights on [0, length]."""
    x, w = np.polynomial.legendre.leggauss(n_points)
    return 0.5 * length * (x + 1.0), 0.5 * length * w


@kernel
def _weighted_coordinates(y, eta, eta_d, eta_dd):
    """sum_l y_l x_l for the v and the w coordinates x of eta, eta' and eta'' (m = len(y) modes
    per plane): the deflection, its rate and its acceleration at a point, with y the mode
    shapes there, or a row of the modal mass matrix times them."""
    m = y.shape[0]
    v = w = vd = wd = vdd = wdd = 0.0
    for l in range(m):
        v += y[l] * eta[l]
        w += y[l] * eta[m + l]
        vd += y[l] * eta_d[l]
        wd += y[l] * eta_d[m + l]
        vdd += y[l] * eta_dd[l]
        wdd += y[l] * eta_dd[m + l]
    return v, w, vd, wd, vdd, wdd


@kernel
def _foreshortening_sums(moments, eta, eta_d, eta_dd, aux, sums):
    """(C0, C0', C0'', C1, C1', C1'', C2, C2') of beam_relations (docs/beam.md, "Geometric
    stiffening"), and with sums the rows D x of aux (foreshortening_row).  Kept out of
    beam_relations, whose loops LLVM optimizes better without this branch."""
    m = moments.shape[0]
    cc0 = cd0 = cdd0 = cc1 = cd1 = cdd1 = cc2 = cd2 = 0.0
    for plane in range(2):
        for l in range(m):
            x0 = x1 = x2 = y0 = y1 = y2 = z0 = z1 = z2 = 0.0     # D eta, D eta', D eta''
            for k in range(m):
                b0, b1, b2 = moments[l, 2 + m + k], moments[l, 2 + 2 * m + k], \
                    moments[l, 2 + 3 * m + k]
                i = plane * m + k
                ek, edk, eddk = eta[i], eta_d[i], eta_dd[i]
                x0 += b0 * ek
                x1 += b1 * ek
                x2 += b2 * ek
                y0 += b0 * edk
                y1 += b1 * edk
                y2 += b2 * edk
                z0 += b0 * eddk
                z1 += b1 * eddk
                z2 += b2 * eddk
            el, edl = eta[plane * m + l], eta_d[plane * m + l]
            cc0 += 0.5 * el * x0
            cd0 += edl * x0
            cdd0 += edl * y0 + el * z0
            cc1 += 0.5 * el * x1
            cd1 += edl * x1
            cdd1 += edl * y1 + el * z1
            cc2 += 0.5 * el * x2
            cd2 += edl * x2
            if sums:
                r = foreshortening_row(m, 0, plane) + l
                aux[r, 0], aux[r, 1], aux[r, 2] = x0, x1, x2
                r = foreshortening_row(m, 1, plane) + l
                aux[r, 0], aux[r, 1], aux[r, 2] = y0, y1, y2
                r = foreshortening_row(m, 2, plane) + l
                aux[r, 0], aux[r, 1], aux[r, 2] = z0, z1, z2
    return cc0, cd0, cdd0, cc1, cd1, cdd1, cc2, cd2


@kernel
def exact_line_integrals(moments, axial, eta, eta_d, eta_dd, o, al, gm, mu, residual):
    """The line load's integrals with the foreshortening to all orders (stiffening="exact";
    docs/beam.md, "The exact foreshortening"): at the Gauss points of the beam's exact table
    (moments' columns from 2 + 4 m, the stretch table's U_j from 5 + m + ma:
    run_tables.beam_tables) the section p = (x + u_x - c, v, w) in the frame, u_x = U . xi,
    c = 1/2 (eta_v^T D(x) eta_v + eta_w^T D(x) eta_w), p' = (u_x' - c', v', w'),
    p'' = (u_x'' - c'', v'', w''), and the line load per unit mu f = gamma - alpha x p
    - omega x (omega x p) - 2 omega x p' - p'' (o, al, gm: omega, alpha, gamma in the frame).
    Returns (int f, int p x f, int p) per unit mu, frame components, and sets the bending and
    stretch rows of residual to the line load's generalized forces, -mu int (dp/deta_j) . f
    with dp/deta_vj = (-(D eta_v)_j, Y_j, 0), dp/deta_wj = (-(D eta_w)_j, 0, Y_j) and
    dp/dxi_j = (U_j, 0, 0)."""
    m = moments.shape[0]
    ma = axial.shape[0]
    na = eta.shape[0] - ma
    u_col = 5 + m + ma
    base = 2 + 4 * m
    o0, o1, o2 = o
    al0, al1, al2 = al
    gm0, gm1, gm2 = gm
    fb0 = fb1 = fb2 = mb0 = mb1 = mb2 = s0 = s1 = s2 = 0.0
    for r in range(2 * m):
        residual[r] = 0.0
    for j in range(ma):
        residual[na + j] = 0.0
    for g in range(int(moments[0, base])):
        col = base + 1 + g * (3 + m)
        x, weight = moments[0, col], moments[0, col + 1]
        v = w = vd = wd = vdd = wdd = 0.0
        c = cd = cdd = 0.0
        for j in range(ma):             # the stretch u_x = U . xi, and its rates, enter as -c
            u = axial[j, u_col + g]
            c -= u * eta[na + j]
            cd -= u * eta_d[na + j]
            cdd -= u * eta_dd[na + j]
        for j in range(m):
            y = moments[j, col + 2]
            v += y * eta[j]
            w += y * eta[m + j]
            vd += y * eta_d[j]
            wd += y * eta_d[m + j]
            vdd += y * eta_dd[j]
            wdd += y * eta_dd[m + j]
            for plane in range(2):          # c = 1/2 eta^T D eta, c' and c'' (D symmetric)
                dx = dxd = dxdd = 0.0
                for l in range(m):
                    d = moments[j, col + 3 + l]
                    i = plane * m + l
                    dx += d * eta[i]
                    dxd += d * eta_d[i]
                    dxdd += d * eta_dd[i]
                e, ed = eta[plane * m + j], eta_d[plane * m + j]
                c += 0.5 * e * dx
                cd += ed * dx
                cdd += ed * dxd + e * dxdd
        p0, p1, p2 = x - c, v, w
        op0, op1, op2 = o1 * p2 - o2 * p1, o2 * p0 - o0 * p2, o0 * p1 - o1 * p0
        f0 = (gm0 - (al1 * p2 - al2 * p1) - (o1 * op2 - o2 * op1) - 2.0 * (o1 * wd - o2 * vd)
              + cdd)
        f1 = (gm1 - (al2 * p0 - al0 * p2) - (o2 * op0 - o0 * op2) - 2.0 * (o2 * (-cd) - o0 * wd)
              - vdd)
        f2 = (gm2 - (al0 * p1 - al1 * p0) - (o0 * op1 - o1 * op0) - 2.0 * (o0 * vd - o1 * (-cd))
              - wdd)
        fb0 += weight * f0
        fb1 += weight * f1
        fb2 += weight * f2
        mb0 += weight * (p1 * f2 - p2 * f1)
        mb1 += weight * (p2 * f0 - p0 * f2)
        mb2 += weight * (p0 * f1 - p1 * f0)
        s0 += weight * p0
        s1 += weight * p1
        s2 += weight * p2
        for plane in range(2):
            fp = f1 if plane == 0 else f2
            for j in range(m):
                dx = 0.0
                for l in range(m):
                    dx += moments[j, col + 3 + l] * eta[plane * m + l]
                residual[plane * m + j] -= mu * weight * (moments[j, col + 2] * fp - dx * f0)
        for j in range(ma):
            residual[na + j] -= mu * weight * axial[j, u_col + g] * f0
    return fb0, fb1, fb2, mb0, mb1, mb2, s0, s1, s2


@kernel
def _add_geometric_stiffness(moments, eta, n_l, c_g, c_w, residual):
    """residual += G eta, G = N_L D0 + mu gamma_x D1 + mu (omega_y^2 + omega_z^2) D2, per plane
    (docs/beam.md, "Geometric stiffening"); c_g, c_w: the last two coefficients."""
    m = moments.shape[0]
    for plane in range(2):
        for l in range(m):
            d0 = d1 = d2 = 0.0
            for k in range(m):
                ek = eta[plane * m + k]
                d0 += moments[l, 2 + m + k] * ek
                d1 += moments[l, 2 + 2 * m + k] * ek
                d2 += moments[l, 2 + 3 * m + k] * ek
            residual[plane * m + l] += n_l * d0 + c_g * d1 + c_w * d2


@no_alloc_kernel
def beam_relations(bp, moments, ends, factors, end_force, end_torque, gravity, rot, w, wd, eta,
                   eta_d, eta_dd, a_i, m_i, q_i, out, residual, aux, axial):
    """The beam's exact relations in a given state (docs/beam.md):
    out = [a_O, w' (the frame's), m_O, q_O]; residual = the modal equations' left minus right
    sides, with the end force's generalized forces (an end moment's: add_end_moment, at a fixed
    hinge at the output; elsewhere m_O = 0).  bp: beam parameter row; moments (m, m + 2): the
    modal integrals [int Y_k, int x Y_k, int Y_k Y_l] (run_tables.beam_tables); ends (m, 2):
    Y_k(L), Y_k'(L); factors (m, 2): modal mass over mu and modal stiffness over EI;
    end_force, end_torque (3,): the applied force F and torque T at the output end, world
    (docs/beam.md, "Loads on the beam"; they add to q_O and m_O, and the net end force
    q_O - F is what the modal equations and the axial force see).  aux (4, 3)
    receives what the analytic columns of the linearization need (beam_transfer): the first
    mass moment S = int mu rho, rho_L = r_O - r_I, and zeros (add_end_moment's A J_l(theta_O)
    e2, e3); given the rows of aux_rows(m) (beam_transfer's base evaluation), also the sums the
    analytic w' and eta'' columns need (_rotation_columns, _modal_columns; the row layout:
    aux_rows).
    The integrals along the beam are linear and quadratic in eta, so they are written with the
    modal integrals in the beam's frame (docs/beam.md, "The integrals in the frame"): with
    rho = x e1 + u (frame components), s = int rho, Pi = int rho rho^T, J = tr(Pi) E - Pi,
    C = int u' rho^T, H = int rho x u'' (per unit mu), and omega, alpha, gamma = A^T (w, w',
    g - a_I):
      int f / mu        = L gamma - (alpha x s + omega x (omega x s) + 2 omega x s' + s'')
      int rho x f / mu  = s x gamma - (J alpha + omega x J omega + 2 (tr C omega - C omega) + H)
      int Y_k f / mu    = P_k gamma - (alpha x Q_k + omega x (omega x Q_k) + 2 omega x Q_k'
                                       + Q_k''),   Q_k = int Y_k rho = [X_k, (M eta_v)_k,
                                                                        (M eta_w)_k]
    (f the line load, gravity minus inertia).  Written in scalars: it runs 3 + n + 1 times per
    beam and step where columns are differenced.
    axial (ma, 5 + m + ma): the stretch table (run_tables.beam_tables; docs/beam.md, "Stretch"):
    with ma > 0 the last ma coordinates xi stretch the centreline, rho = (x + U . xi) e1 + ...,
    and every integral above gains its terms exactly (s_x, Pi, C, H, Q_k's first entry, the
    output point), and the stretch's own rows follow the bending rows' rule with e1."""
    length, mu, ei_v, ei_w, j_p, zeta = bp[0], bp[1], bp[2], bp[3], bp[4], bp[5]
    m = ends.shape[0]
    e10, e11, e12 = rot[0, 0], rot[1, 0], rot[2, 0]
    e20, e21, e22 = rot[0, 1], rot[1, 1], rot[2, 1]
    e30, e31, e32 = rot[0, 2], rot[1, 2], rot[2, 2]
    w0, w1, w2 = w[0], w[1], w[2]
    wd0, wd1, wd2 = wd[0], wd[1], wd[2]
    a0, a1, a2 = a_i[0], a_i[1], a_i[2]
    ga0, ga1, ga2 = gravity[0] - a0, gravity[1] - a1, gravity[2] - a2
    # omega, alpha, gamma: w, w', g - a_I in the frame
    o0, o1, o2 = (e10 * w0 + e11 * w1 + e12 * w2, e20 * w0 + e21 * w1 + e22 * w2,
                  e30 * w0 + e31 * w1 + e32 * w2)
    al0, al1, al2 = (e10 * wd0 + e11 * wd1 + e12 * wd2, e20 * wd0 + e21 * wd1 + e22 * wd2,
                     e30 * wd0 + e31 * wd1 + e32 * wd2)
    gm0, gm1, gm2 = (e10 * ga0 + e11 * ga1 + e12 * ga2, e20 * ga0 + e21 * ga1 + e22 * ga2,
                     e30 * ga0 + e31 * ga1 + e32 * ga2)
    sums = aux.shape[0] > 4
    # the modal sums: P.eta, X.eta (and their rates), and the quadratic forms of M
    pv = pw = pdv = pdw = pddv = pddw = 0.0
    xv = xw = xdv = xdw = xddv = xddw = 0.0
    vv = vw = ww = dvv = dvw = dwv = dww = hx = 0.0
    # the stretch xi = eta[na:] (docs/beam.md, "Stretch"): its sums P_a . xi, X_a . xi (and
    # rates), xi^T M_aa xi, xi'^T M_aa xi, and xi's products with the bending coordinates
    ma = axial.shape[0]
    na = eta.shape[0] - ma
    pa = pda = pdda = xa = xda = aa = daa = 0.0
    av = aw = dav = daw = vda = wda = hav = haw = vha = wha = 0.0
    for j in range(ma):
        e, ed, edd = eta[na + j], eta_d[na + j], eta_dd[na + j]
        pa += axial[j, 1] * e
        pda += axial[j, 1] * ed
        pdda += axial[j, 1] * edd
        xa += axial[j, 2] * e
        xda += axial[j, 2] * ed
        for i in range(ma):
            g = axial[j, 5 + m + i]
            aa += e * g * eta[na + i]
            daa += ed * g * eta[na + i]
        for l in range(m):
            g = axial[j, 5 + l]
            av += e * g * eta[l]                 # int u_x v, int u_x w
            aw += e * g * eta[m + l]
            dav += ed * g * eta[l]               # int u_x' v, int u_x' w
            daw += ed * g * eta[m + l]
            vda += e * g * eta_d[l]              # int u_x v', int u_x w'
            wda += e * g * eta_d[m + l]
            hav += edd * g * eta[l]              # int u_x'' v, int u_x'' w
            haw += edd * g * eta[m + l]
            vha += e * g * eta_dd[l]             # int u_x v'', int u_x w''
            wha += e * g * eta_dd[m + l]
    for k in range(m):
        p_k, x_k = moments[k, 0], moments[k, 1]
        ev, ew, edv, edw = eta[k], eta[m + k], eta_d[k], eta_d[m + k]
        eddv, eddw = eta_dd[k], eta_dd[m + k]
        pv += p_k * ev
        pw += p_k * ew
        pdv += p_k * edv
        pdw += p_k * edw
        pddv += p_k * eddv
        pddw += p_k * eddw
        xv += x_k * ev
        xw += x_k * ew
        xdv += x_k * edv
        xdw += x_k * edw
        xddv += x_k * eddv
        xddw += x_k * eddw
        # (M eta_v)_k, (M eta_w)_k and their rates: the last entries of Q_k, Q_k' and Q_k''
        mv, mw, mdv, mdw, mddv, mddw = _weighted_coordinates(moments[k, 2:2 + m], eta, eta_d,
                                                             eta_dd)
        vv += ev * mv
        vw += ev * mw
        ww += ew * mw
        dvv += edv * mv
        dvw += edv * mw
        dwv += edw * mv
        dww += edw * mw
        hx += ev * mddw - ew * mddv
        # int Y_k f / mu in the frame (docstring); q: Q_k, u: Q_k', v: Q_k''; the stretch adds
        # (M_ka xi, M_ka xi', M_ka xi'') to their first entries
        ka = kda = kdda = 0.0
        for j in range(ma):
            g = axial[j, 5 + k]
            ka += g * eta[na + j]
            kda += g * eta_d[na + j]
            kdda += g * eta_dd[na + j]
        q0, q1, q2 = x_k + ka, mv, mw
        oq0, oq1, oq2 = o1 * q2 - o2 * q1, o2 * q0 - o0 * q2, o0 * q1 - o1 * q0
        f1 = (p_k * gm1 - (al2 * q0 - al0 * q2) - (o2 * oq0 - o0 * oq2)
              - 2.0 * (o2 * kda - o0 * mdw) - mddv)
        f2 = (p_k * gm2 - (al0 * q1 - al1 * q0) - (o0 * oq1 - o1 * oq0)
              - 2.0 * (o0 * mdv - o1 * kda) - mddw)
        residual[k] = -mu * f1
        residual[m + k] = -mu * f2
        if sums:
            f0 = (p_k * gm0 - (al1 * q2 - al2 * q1) - (o1 * oq2 - o2 * oq1)
                  - 2.0 * (o1 * mdw - o2 * mdv) - kdda)
            for i in range(3):
                c0, c1, c2 = rot[i, 0], rot[i, 1], rot[i, 2]
                aux[SUM_MODES + k, i] = mu * (c0 * f0 + c1 * f1 + c2 * f2)          # F_k
                aux[SUM_MODES + m + k, i] = mu * (c0 * q0 + c1 * q1 + c2 * q2)      # Q_k
                aux[SUM_MODES + 2 * m + k, i] = mu * (c0 * kda + c1 * mdv + c2 * mdw)
                aux[SUM_MODES + 3 * m + k, i] = mu * (c0 * kdda + c1 * mddv + c2 * mddw)
    # the foreshortening c(x) = 1/2 int_0^x (v'^2 + w'^2) (docs/beam.md, "Geometric
    # stiffening"): C0 = c(L), C1 = int c, C2 = int x c = 1/2 eta^T (D0, D1, D2) eta over both
    # planes, and their rates (D symmetric: C' = eta'^T D eta, C'' = eta'^T D eta' + eta^T D eta'')
    stiff = bp[STIFFENING] != 0.0
    cc0 = cd0 = cdd0 = cc1 = cd1 = cdd1 = cc2 = cd2 = 0.0
    if stiff:
        cc0, cd0, cdd0, cc1, cd1, cdd1, cc2, cd2 = _foreshortening_sums(moments, eta, eta_d,
                                                                        eta_dd, aux, sums)
    # s, s', s'' and the second moments Pi (per unit mu, in the frame; with the foreshortening
    # -c e1 to first order in c: s_x = L^2/2 - C1, Pi_xx = L^3/3 - 2 C2)
    # (the stretch: s_x += P_a . xi, Pi_xx += 2 X_a . xi + xi^T M_aa xi, Pi_xv += int u_x v, ..)
    s0, s1, s2 = 0.5 * length * length - cc1 + pa, pv, pw
    sd0, sdd0 = -cd1 + pda, -cdd1 + pdda
    pxx = length * length * length / 3.0 - 2.0 * cc2 + 2.0 * xa + aa
    # J = tr(Pi) E - Pi
    j00, j11, j22 = vv + ww, pxx + ww, pxx + vv
    j01, j02, j12 = -(xv + av), -(xw + aw), -vw
    # C = int rho' rho^T (its first row (-C2', 0, 0) without stretch), H = int rho x rho''
    # (c adds nothing)
    c00, c01, c02 = -cd2 + xda + daa, dav, daw
    c10, c11, c12, c20, c21, c22 = xdv + vda, dvv, dvw, xdw + wda, dwv, dww
    h0, h1, h2 = hx, -xddw + haw - wha, xddv + vha - hav
    # int f / mu: L gamma - (alpha x s + omega x (omega x s) + 2 omega x s' + s''), s' = (sd0,
    # pdv, pdw), s'' = (sdd0, pddv, pddw)
    os0, os1, os2 = o1 * s2 - o2 * s1, o2 * s0 - o0 * s2, o0 * s1 - o1 * s0
    fb0 = (length * gm0 - (al1 * s2 - al2 * s1) - (o1 * os2 - o2 * os1)
           - 2.0 * (o1 * pdw - o2 * pdv) - sdd0)
    fb1 = (length * gm1 - (al2 * s0 - al0 * s2) - (o2 * os0 - o0 * os2)
           - 2.0 * (o2 * sd0 - o0 * pdw) - pddv)
    fb2 = (length * gm2 - (al0 * s1 - al1 * s0) - (o0 * os1 - o1 * os0)
           - 2.0 * (o0 * pdv - o1 * sd0) - pddw)
    # int rho x f / mu: s x gamma - (J alpha + omega x J omega + 2 (tr C omega - C omega) + H)
    jo0 = j00 * o0 + j01 * o1 + j02 * o2
    jo1 = j01 * o0 + j11 * o1 + j12 * o2
    jo2 = j02 * o0 + j12 * o1 + j22 * o2
    tr_c = c00 + c11 + c22
    co0 = c00 * o0 + c01 * o1 + c02 * o2
    co1 = c10 * o0 + c11 * o1 + c12 * o2
    co2 = c20 * o0 + c21 * o1 + c22 * o2
    mb0 = (s1 * gm2 - s2 * gm1 - (j00 * al0 + j01 * al1 + j02 * al2) - (o1 * jo2 - o2 * jo1)
           - 2.0 * (tr_c * o0 - co0) - h0)
    mb1 = (s2 * gm0 - s0 * gm2 - (j01 * al0 + j11 * al1 + j12 * al2) - (o2 * jo0 - o0 * jo2)
           - 2.0 * (tr_c * o1 - co1) - h1)
    mb2 = (s0 * gm1 - s1 * gm0 - (j02 * al0 + j12 * al1 + j22 * al2) - (o0 * jo1 - o1 * jo0)
           - 2.0 * (tr_c * o2 - co2) - h2)
    exact = bp[STIFFENING] == EXACT
    if exact:   # the foreshortening to all orders: the integrals and the bending rows' inertia
        fb0, fb1, fb2, mb0, mb1, mb2, s0, s1, s2 = exact_line_integrals(
            moments, axial, eta, eta_d, eta_dd, (o0, o1, o2), (al0, al1, al2), (gm0, gm1, gm2),
            mu, residual)
    # back to the world: int f, int rho x f, S = int mu rho
    sf0 = mu * (e10 * fb0 + e20 * fb1 + e30 * fb2)
    sf1 = mu * (e11 * fb0 + e21 * fb1 + e31 * fb2)
    sf2 = mu * (e12 * fb0 + e22 * fb1 + e32 * fb2)
    sm0 = mu * (e10 * mb0 + e20 * mb1 + e30 * mb2)
    sm1 = mu * (e11 * mb0 + e21 * mb1 + e31 * mb2)
    sm2 = mu * (e12 * mb0 + e22 * mb1 + e32 * mb2)
    if sums:
        for i in range(3):
            c0, c1, c2 = rot[i, 0], rot[i, 1], rot[i, 2]
            aux[SUM_U, i] = mu * (c0 * sd0 + c1 * pdv + c2 * pdw)
            aux[SUM_V, i] = mu * (c0 * sdd0 + c1 * pddv + c2 * pddw)
            aux[SUM_H, i] = mu * (c0 * h0 + c1 * h1 + c2 * h2)
            # A J and A C, then times A^T below
            aux[SUM_J + i, 0] = c0 * j00 + c1 * j01 + c2 * j02
            aux[SUM_J + i, 1] = c0 * j01 + c1 * j11 + c2 * j12
            aux[SUM_J + i, 2] = c0 * j02 + c1 * j12 + c2 * j22
            aux[SUM_C + i, 0] = c0 * c00 + c1 * c10 + c2 * c20
            aux[SUM_C + i, 1] = c0 * c01 + c1 * c11 + c2 * c21
            aux[SUM_C + i, 2] = c0 * c02 + c1 * c12 + c2 * c22
        for base in (SUM_J, SUM_C):
            for i in range(3):
                b0, b1, b2 = aux[base + i, 0], aux[base + i, 1], aux[base + i, 2]
                for j in range(3):
                    aux[base + i, j] = mu * (b0 * rot[j, 0] + b1 * rot[j, 1] + b2 * rot[j, 2])
    s0, s1, s2 = (mu * (e10 * s0 + e20 * s1 + e30 * s2), mu * (e11 * s0 + e21 * s1 + e31 * s2),
                  mu * (e12 * s0 + e22 * s1 + e32 * s2))
    # the stretch's rows (docs/beam.md, "Stretch"): -mu e1 . int U_j f / mu (frame), with
    # Q_a,j = int U_j rho = [X_a,j + (M_aa xi)_j, (M_av eta_v)_j, (M_av eta_w)_j] and its rates,
    # plus damping and stiffness (the end force's share below, with q_O)
    uaL = uadL = uaddL = 0.0
    for j in range(ma):
        e, ed, edd = eta[na + j], eta_d[na + j], eta_dd[na + j]
        uaL += axial[j, 0] * e
        uadL += axial[j, 0] * ed
        uaddL += axial[j, 0] * edd
        # (only the e1 component is needed: Q_a,j, the y and z entries of Q_a,j', the x entry
        # of Q_a,j'')
        q0, q1, q2 = axial[j, 2], 0.0, 0.0
        u1 = u2 = v0 = 0.0
        for i in range(ma):
            g = axial[j, 5 + m + i]
            q0 += g * eta[na + i]
            v0 += g * eta_dd[na + i]
        for l in range(m):
            g = axial[j, 5 + l]
            q1 += g * eta[l]
            q2 += g * eta[m + l]
            u1 += g * eta_d[l]
            u2 += g * eta_d[m + l]
        oq1, oq2 = o2 * q0 - o0 * q2, o0 * q1 - o1 * q0
        f0 = (axial[j, 1] * gm0 - (al1 * q2 - al2 * q1) - (o1 * oq2 - o2 * oq1)
              - 2.0 * (o1 * u2 - o2 * u1) - v0)
        modal_mass = mu * axial[j, 3]
        stiffness = bp[EA] * axial[j, 4]
        inertia = residual[na + j] if exact else -mu * f0       # (exact_line_integrals')
        residual[na + j] = (inertia + 2.0 * zeta * np.sqrt(stiffness * modal_mass) * ed
                            + stiffness * e)
    for k in range(m):
        modal_mass = mu * factors[k, 0]
        for r, ei in ((k, ei_v), (m + k, ei_w)):
            stiffness = ei * factors[k, 1]
            omega_k = np.sqrt(stiffness / modal_mass)
            residual[r] += 2.0 * zeta * omega_k * modal_mass * eta_d[r] + stiffness * eta[r]
    # the output point O = r_I + A (L e1 + u(L)) and its acceleration
    v_l, w_l, vd_l, wd_l, vdd_l, wdd_l = _weighted_coordinates(ends[:, 0], eta, eta_d, eta_dd)
    # (in scalars: this tail runs once per evaluation, where small temporaries would cost more
    # than the arithmetic)
    for i in range(3):                                                       # rho_L
        aux[1, i] = (length - cc0 + uaL) * rot[i, 0] + v_l * rot[i, 1] + w_l * rot[i, 2]
    r0, r1, r2 = aux[1, 0], aux[1, 1], aux[1, 2]
    qo0, qo1, qo2 = q_i[0] + sf0, q_i[1] + sf1, q_i[2] + sf2
    jp = j_p * length
    s_wd = jp * (e10 * wd0 + e11 * wd1 + e12 * wd2)
    s_w = jp * (e10 * w0 + e11 * w1 + e12 * w2)
    wr0, wr1, wr2 = w1 * r2 - w2 * r1, w2 * r0 - w0 * r2, w0 * r1 - w1 * r0      # w x rho_L
    # A rho_L' and A rho_L'' in the frame's rates (u(L), the stretch u_x(L) and the
    # foreshortening -c(L) e1)
    xd_l, xdd_l = uadL - cd0, uaddL - cdd0
    d0 = xd_l * e10 + vd_l * rot[0, 1] + wd_l * rot[0, 2]
    d1 = xd_l * e11 + vd_l * rot[1, 1] + wd_l * rot[1, 2]
    d2 = xd_l * e12 + vd_l * rot[2, 1] + wd_l * rot[2, 2]
    dd0 = xdd_l * e10 + vdd_l * rot[0, 1] + wdd_l * rot[0, 2]
    dd1 = xdd_l * e11 + vdd_l * rot[1, 1] + wdd_l * rot[1, 2]
    dd2 = xdd_l * e12 + vdd_l * rot[2, 1] + wdd_l * rot[2, 2]
    if sums:
        aux[END_U, 0], aux[END_U, 1], aux[END_U, 2] = d0, d1, d2
        aux[END_V, 0], aux[END_V, 1], aux[END_V, 2] = dd0, dd1, dd2
    # a_O = a_I + w' x rho_L + w x (w x rho_L) + 2 w x A rho_L' + A rho_L''
    out[0] = a0 + wd1 * r2 - wd2 * r1 + w1 * wr2 - w2 * wr1 + 2.0 * (w1 * d2 - w2 * d1) + dd0
    out[1] = a1 + wd2 * r0 - wd0 * r2 + w2 * wr0 - w0 * wr2 + 2.0 * (w2 * d0 - w0 * d2) + dd1
    out[2] = a2 + wd0 * r1 - wd1 * r0 + w0 * wr1 - w1 * wr0 + 2.0 * (w0 * d1 - w1 * d0) + dd2
    out[3], out[4], out[5] = wd0, wd1, wd2
    # m_O = m_I - rho_L x q_O + int rho x f - (J_p,w w' + w x J_p,w w), J_p,w = jp e1 e1^T
    out[6] = m_i[0] - (r1 * qo2 - r2 * qo1) + sm0 - (s_wd * e10 + s_w * (w1 * e12 - w2 * e11))
    out[7] = m_i[1] - (r2 * qo0 - r0 * qo2) + sm1 - (s_wd * e11 + s_w * (w2 * e10 - w0 * e12))
    out[8] = m_i[2] - (r0 * qo1 - r1 * qo0) + sm2 - (s_wd * e12 + s_w * (w0 * e11 - w1 * e10))
    # the applied end load (docs/beam.md, "Loads on the beam"): q_O gains F, m_O gains T; the
    # outboard's net pull q_O - F = q_I + int f stays in qo below (modal terms, N_L)
    out[6], out[7], out[8] = out[6] + end_torque[0], out[7] + end_torque[1], out[8] + end_torque[2]
    out[9], out[10], out[11] = qo0 + end_force[0], qo1 + end_force[1], qo2 + end_force[2]
    aux[0, 0], aux[0, 1], aux[0, 2] = s0, s1, s2
    aux[2:4] = 0.0
    # generalized forces of the outboard's -q_O (at O) and -m_O (docs/beam.md, modal equations)
    q2 = qo0 * rot[0, 1] + qo1 * rot[1, 1] + qo2 * rot[2, 1]
    q3 = qo0 * rot[0, 2] + qo1 * rot[1, 2] + qo2 * rot[2, 2]
    for k in range(m):
        residual[k] += q2 * ends[k, 0]
        residual[m + k] += q3 * ends[k, 0]
    if ma:
        pull = qo0 * e10 + qo1 * e11 + qo2 * e12        # the stretch's: dr_O / dxi_j = e1 U_j(L)
        for j in range(ma):
            residual[na + j] += pull * axial[j, 0]
    if stiff:
        # geometric stiffening (docs/beam.md, "Geometric stiffening"): the generalized forces of
        # the foreshortening, residual += G eta, G = N_L D0 + mu gamma_x D1
        # + mu (omega_y^2 + omega_z^2) D2, N_L = -e1 . q_O the axial force at O (tension > 0):
        # N_L D0 eta is the end force's work through c(L), the rest the line load's
        # (exact: the line load's share is in exact_line_integrals' rows, the end force's here)
        n_l = -(qo0 * e10 + qo1 * e11 + qo2 * e12)
        c_g = 0.0 if exact else mu * gm0
        c_w = 0.0 if exact else mu * (o1 * o1 + o2 * o2)
        _add_geometric_stiffness(moments, eta, n_l, c_g, c_w, residual)
        if sums:
            r_c = coefficient_row(m)
            aux[r_c, 0], aux[r_c, 1], aux[r_c, 2] = n_l, c_g, c_w
            aux[r_c + 1, 0], aux[r_c + 1, 1], aux[r_c + 1, 2] = ga0, ga1, ga2


@kernel
def add_end_moment(ends, torsion, eta, rot, out, residual, aux, end_torque, scratch):
    """At a fixed hinge at the output, the generalized forces of the outboard's -m_O (about O)
    on the modal equations (docs/beam.md, equations of motion): residual_v,k += m_O . (A J_l e3)
    Y_k'(L), residual_w,k -= m_O . (A J_l e2) Y_k'(L), residual_t,k += m_O . (A J_l e1)
    Psi_k(L) (the twist, docs/beam.md "Torsion"), J_l = J_l(theta_O); aux[2], aux[3] =
    A J_l e2, A J_l e3; with an applied end torque T (end_torque) the net m_O - T.  out,
    residual, aux, end_torque: beam_relations'; torsion: the twist table (twist_relations);
    scratch: 12 entries.  (Kept out of beam_relations, whose loops LLVM optimizes better
    without this branch: measured 0.34 against 0.25 us per evaluation.)"""
    m = ends.shape[0]
    theta = scratch[0:3]
    jl = scratch[3:12].reshape((3, 3))
    _end_angles_into(ends, torsion, eta, theta)
    left_jacobian(theta, jl)
    for i in range(3):
        aux[2, i] = rot[i, 0] * jl[0, 1] + rot[i, 1] * jl[1, 1] + rot[i, 2] * jl[2, 1]
        aux[3, i] = rot[i, 0] * jl[0, 2] + rot[i, 1] * jl[1, 2] + rot[i, 2] * jl[2, 2]
    mv = mw = mt = 0.0
    for i in range(3):
        m_net = out[6 + i] - end_torque[i]
        mv += m_net * aux[3, i]
        mw -= m_net * aux[2, i]
        mt += m_net * (rot[i, 0] * jl[0, 0] + rot[i, 1] * jl[1, 0] + rot[i, 2] * jl[2, 0])
    for k in range(m):
        residual[k] += mv * ends[k, 1]
        residual[m + k] += mw * ends[k, 1]
    for k in range(torsion.shape[0]):
        residual[2 * m + k] += mt * torsion[k, 0]


@kernel
def twist_relations(bp, torsion, rot, w, wd, eta, eta_d, eta_dd, m, out, residual):
    """The twist's share of the relations (docs/beam.md, "Torsion"), after beam_relations: the
    sections spin by w . A e1 + psi', psi = sum_k Psi_k(x) eta_t,k (eta[2 m:]), with
    T = 1/2 j_p int (w . A e1 + psi')^2 dx and V = 1/2 G J int psi'^2 dx, so
      residual_t,k = j_p (P_k alpha_x + L psi_k'') + c_k psi_k' + k_k psi_k
                     (+ the end moment's m_O . (A J_l e1) Psi_k(L): add_end_moment),
      m_O -= j_p (P . psi'') A e1 + j_p (P . psi') w x A e1   (the rate of the sections' spin
                                                              momentum beyond the frame's),
    alpha_x = w' . A e1, P_k = int Psi_k, int Psi_j Psi_k = L delta_jk, m_k = j_p L,
    k_k = G J int Psi_k'^2, c_k = 2 zeta omega_k m_k.  torsion (mt, 4): Psi_k(L), P_k,
    m_k / j_p, k_k / G J (run_tables.beam_tables)."""
    j_p, zeta, gj = bp[4], bp[5], bp[GJ]
    e0, e1, e2 = rot[0, 0], rot[1, 0], rot[2, 0]
    alpha_x = wd[0] * e0 + wd[1] * e1 + wd[2] * e2
    p_dd = p_d = 0.0
    for k in range(torsion.shape[0]):
        r = 2 * m + k
        p_k = torsion[k, 1]
        p_d += p_k * eta_d[r]
        p_dd += p_k * eta_dd[r]
        modal_mass = j_p * torsion[k, 2]
        stiffness = gj * torsion[k, 3]
        damping = 2.0 * zeta * np.sqrt(stiffness / modal_mass) * modal_mass
        residual[r] = (j_p * p_k * alpha_x + modal_mass * eta_dd[r] + damping * eta_d[r]
                       + stiffness * eta[r])
    s_dd, s_d = j_p * p_dd, j_p * p_d
    out[6] -= s_dd * e0 + s_d * (w[1] * e2 - w[2] * e1)
    out[7] -= s_dd * e1 + s_d * (w[2] * e0 - w[0] * e2)
    out[8] -= s_dd * e2 + s_d * (w[0] * e1 - w[1] * e0)


@kernel
def _stretch_affine_columns(bp, axial, rot, d_r):
    """The stretch rows' a_I and q_I columns (docs/beam.md, "Stretch"): like a bending row's
    with e1, d r_a,j = (mu int U_j - M_b U_j(L)) e1 . da + U_j(L) e1 . dq (the inertia through
    g - a_I and the end force through q_O); no m_I column (the stretch does not turn the end
    section)."""
    mass = bp[1] * bp[0]
    n = d_r.shape[0]
    ma = axial.shape[0]
    for j in range(ma):
        row = n - ma + j
        u_l = axial[j, 0]
        for c in range(3):
            d_r[row, c] = (bp[1] * axial[j, 1] - mass * u_l) * rot[c, 0]
            d_r[row, 9 + c] = u_l * rot[c, 0]


@kernel
def _twist_end_columns(ends, torsion, eta, rot, d_o, d_r, scratch):
    """The twist rows' a_I, m_I, q_I columns at an end moment (add_end_moment): residual_t,k
    depends on them through m_O only, d r_t,k = Psi_k(L) (A J_l e1) . d m_O (d_o's rows 6:9,
    _affine_columns).  scratch: 12 entries."""
    m = ends.shape[0]
    theta, jl = scratch[0:3], scratch[3:12].reshape((3, 3))
    _end_angles_into(ends, torsion, eta, theta)
    left_jacobian(theta, jl)
    g0 = rot[0, 0] * jl[0, 0] + rot[0, 1] * jl[1, 0] + rot[0, 2] * jl[2, 0]
    g1 = rot[1, 0] * jl[0, 0] + rot[1, 1] * jl[1, 0] + rot[1, 2] * jl[2, 0]
    g2 = rot[2, 0] * jl[0, 0] + rot[2, 1] * jl[1, 0] + rot[2, 2] * jl[2, 0]
    for c in range(12):
        if 3 <= c < 6:
            continue
        dm = g0 * d_o[6, c] + g1 * d_o[7, c] + g2 * d_o[8, c]
        for k in range(torsion.shape[0]):
            d_r[2 * m + k, c] = torsion[k, 0] * dm


@kernel
def _follower_loads(bp, tables, eta, rot, gravity, out, scratch):
    """World components of body-axes loads (load_axes="body", docs/beam.md "Loads on the
    beam") into out's rows: A_O F, A_O T, g + A p / mu, A_O = A exp(theta_O^) the output end
    section's rotation (end_section), A the frame's.  scratch: 12 entries."""
    theta, e = scratch[0:3], scratch[3:12].reshape((3, 3))
    _end_angles_into(tables[1], tables[6], eta, theta)
    expm_so3(theta, e)
    a_o = t_mm(t_of_mat(rot), t_of_mat(e))
    f, t, p = tables[3], tables[4], tables[5]
    for i in range(3):
        out[0, i] = a_o[3 * i] * f[0] + a_o[3 * i + 1] * f[1] + a_o[3 * i + 2] * f[2]
        out[1, i] = a_o[3 * i] * t[0] + a_o[3 * i + 1] * t[1] + a_o[3 * i + 2] * t[2]
        out[2, i] = gravity[i] + (rot[i, 0] * p[0] + rot[i, 1] * p[1] + rot[i, 2] * p[2]) / bp[1]


@kernel
def _beam_gravity(bp, gravity, line_load, out):
    """out = g + p / mu: a uniform distributed load p (N/m, world) acts on the beam exactly as
    gravity does, so the beam's relations and columns take it as part of g (docs/beam.md,
    "Loads on the beam")."""
    for i in range(3):
        out[i] = gravity[i] + line_load[i] / bp[1]


@kernel
def _any(v):
    """Whether a 3-vector has a nonzero entry (an applied end torque)."""
    return v[0] != 0.0 or v[1] != 0.0 or v[2] != 0.0


@kernel
def end_foreshortening(moments, eta):
    """c(L) = 1/2 (eta_v^T D0 eta_v + eta_w^T D0 eta_w): how far the tip has moved back along the
    frame's axis (docs/beam.md, "Geometric stiffening"); moments: the beam's modal integrals."""
    m = moments.shape[0]
    c = 0.0
    for plane in range(2):
        for l in range(m):
            for k in range(m):
                c += 0.5 * eta[plane * m + l] * moments[l, 2 + m + k] * eta[plane * m + k]
    return c


@kernel
def end_angles(ends, torsion, eta):
    """theta_O = [psi(L), -w'(L), v'(L)]: the output section's rotation vector in the frame,
    from the modal coordinates (or their rates), the end slopes Y_k'(L) and the end twists
    Psi_k(L) (torsion[:, 0]; docs/beam.md, "End sections" and "Torsion")."""
    theta = np.empty(3)
    _end_angles_into(ends, torsion, eta, theta)
    return theta


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _end_angles_into(ends, torsion, eta, theta):
    """theta = end_angles(ends, torsion, eta), into a given 3-vector."""
    m = ends.shape[0]
    theta[0] = theta[1] = theta[2] = 0.0
    for k in range(m):
        theta[1] -= ends[k, 1] * eta[m + k]
        theta[2] += ends[k, 1] * eta[k]
    for k in range(torsion.shape[0]):
        theta[0] += torsion[k, 0] * eta[2 * m + k]


@kernel
def end_section(ends, torsion, eta, rot, out):
    """out = A exp(theta_O^): the output section's rotation."""
    e = np.empty((3, 3))
    expm_so3(end_angles(ends, torsion, eta), e)
    mm3_into(rot, e, out)


@kernel
def _end_section_angular_acceleration(ends, torsion, rot, w, wd, eta, eta_d, eta_dd, out,
                                      scratch):
    """out = w'_O = w' + w x (A J_l theta') + A (J_l theta'' + DJ_l(theta)[theta'] theta') of
    the output section (docs/beam.md, "End sections"; so3.left_jacobian_derivative).  scratch:
    39 entries; it leaves theta_O, theta_O' in scratch[0:6], J_l theta_O' in scratch[9:12] and
    J_l(theta_O) in scratch[12:21] (end_section_motion takes them)."""
    th, th_d, th_dd, v = scratch[0:3], scratch[3:6], scratch[6:9], scratch[9:12]
    jl, dj = scratch[12:21].reshape((3, 3)), scratch[21:30].reshape((3, 3))
    y, av = scratch[30:33], scratch[33:36]
    _end_angles_into(ends, torsion, eta, th)
    _end_angles_into(ends, torsion, eta_d, th_d)
    _end_angles_into(ends, torsion, eta_dd, th_dd)
    left_jacobian(th, jl)
    left_jacobian_derivative(th, th_d, dj)
    for i in range(3):
        v[i] = jl[i, 0] * th_d[0] + jl[i, 1] * th_d[1] + jl[i, 2] * th_d[2]
        y[i] = (jl[i, 0] * th_dd[0] + jl[i, 1] * th_dd[1] + jl[i, 2] * th_dd[2]
                + dj[i, 0] * th_d[0] + dj[i, 1] * th_d[1] + dj[i, 2] * th_d[2])
    for i in range(3):                                          # A J_l theta'
        av[i] = rot[i, 0] * v[0] + rot[i, 1] * v[1] + rot[i, 2] * v[2]
    out[0] = wd[0] + w[1] * av[2] - w[2] * av[1]
    out[1] = wd[1] + w[2] * av[0] - w[0] * av[2]
    out[2] = wd[2] + w[0] * av[1] - w[1] * av[0]
    for i in range(3):
        out[i] += rot[i, 0] * y[0] + rot[i, 1] * y[1] + rot[i, 2] * y[2]


@kernel
def end_section_motion(ends, torsion, rot, w, wd, eta, eta_d, eta_dd, rest, rot_out, w_out,
                       wd_out, scratch):
    """The motion of a frame welded to the output section (docs/beam.md, "End sections"):
    rot_out = A exp(theta_O^) R_rel, w_out = w + A J_l(theta_O) theta_O', wd_out = w'_O
    (_end_section_angular_acceleration, whose theta_O and J_l theta_O' it takes from the
    scratch), from the beam's frame (rot, w, wd) and modal state; rest: R_rel.  scratch: 48
    entries (nothing is allocated)."""
    _end_section_angular_acceleration(ends, torsion, rot, w, wd, eta, eta_d, eta_dd, wd_out,
                                      scratch[:39])
    th, v = scratch[0:3], scratch[9:12]
    e, a_o = scratch[21:30].reshape((3, 3)), scratch[39:48].reshape((3, 3))
    expm_so3(th, e)
    mm3_into(rot, e, a_o)
    mm3_into(a_o, rest, rot_out)
    for i in range(3):
        w_out[i] = w[i] + rot[i, 0] * v[0] + rot[i, 1] * v[1] + rot[i, 2] * v[2]
