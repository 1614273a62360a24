"""The reference's beam rows (newton_euler.py's docstring, "Beams"): a beam's end section from its
modal coordinates, its stiffening blocks, and its Newton-Euler and modal terms, to second order in
the coordinates (_beam_terms) or with the foreshortening kept exactly (_beam_terms_exact).  The
global system that assembles them is in equations.py.
"""
import math

import numpy as np

from ..kernels import kernel
from ..kernels.algebra.mat3 import dot, matmul, matvec, put1
from .rows import (N_SHAPE_ROWS, _BEA, _BEAM, _BEIV, _BEIW, _BGJ, _BJP, _BL, _BMODES, _BMU,
                   _BSTIFF, _BSTRETCH, _BTWIST, _BZETA, _DYL, _KF, _MF, _RIGID, _ROD, _SY, _TY,
                   _UNDECLARED_BODY_KIND, _YL)
from .rotations import _cross, _expm, _hat, _left_jacobian, _left_jacobian_derivative


@kernel(entry=True)
def _stiffening_block(my, nm, i):
    """D_i (i = 0, 1, 2; nm x nm, contiguous) of one beam from its shape matrices
    my = [int Y Y^T | D0 | D1 | D2], each block as wide as the widest beam's modes
    (_Problem.shape_mat)."""
    wide = my.shape[1] // 4
    return np.ascontiguousarray(my[:nm, (i + 1) * wide:(i + 1) * wide + nm])


@kernel
def _modal_size(bp):
    """A beam's modal coordinates: v and w bending, then the twist, then the stretch."""
    return 2 * int(bp[_BMODES]) + int(bp[_BTWIST]) + int(bp[_BSTRETCH])


@kernel
def _beam_end(bp, sv, my, a, w, eta, eta_dot):
    """Output point and output section of one beam (newton_euler.py's docstring, "End kinematics"),
    from its frame (A, w), modal coordinates and rates.  Returns rho_O = r_O - r_I, the relative
    velocity v_O - v_I, A_O, w_O, the velocity parts of a_O and alpha_O, B_r = A Phi(L) and
    B_t = A J_l(theta_O) D (3 x 2n each, world).  With geometric stiffening the output point
    moves back by the foreshortening c(L) = 1/2 eta^T D0 eta along e1 (newton_euler.py's docstring),
    so B_r gains -A e1 (D0 eta)^T and the velocity terms its rates."""
    nm = int(bp[_BMODES])
    nt, na = int(bp[_BTWIST]), int(bp[_BSTRETCH])
    tw = sv.shape[1] // 3             # the twist's columns of sv (_Problem.shape_vec)
    nb = 2 * nm + nt + na
    u_l = np.zeros(3)                 # u(L), body frame
    ud_l = np.zeros(3)                # u'(L) (time derivative)
    th = np.zeros(3)                  # theta_O = [psi(L), -w'(L), v'(L)]
    thd = np.zeros(3)
    for j in range(nt):
        th[0] += sv[_YL, tw + j] * eta[2 * nm + j]
        thd[0] += sv[_YL, tw + j] * eta_dot[2 * nm + j]
    for j in range(na):               # the stretch u_x(L)
        u_l[0] += sv[_YL, 2 * tw + j] * eta[2 * nm + nt + j]
        ud_l[0] += sv[_YL, 2 * tw + j] * eta_dot[2 * nm + nt + j]
    for j in range(nm):
        yl, dyl = sv[_YL, j], sv[_DYL, j]
        u_l[1] += yl * eta[j]
        u_l[2] += yl * eta[nm + j]
        ud_l[1] += yl * eta_dot[j]
        ud_l[2] += yl * eta_dot[nm + j]
        th[1] -= dyl * eta[nm + j]
        th[2] += dyl * eta[j]
        thd[1] -= dyl * eta_dot[nm + j]
        thd[2] += dyl * eta_dot[j]
    p_l = u_l.copy()
    p_l[0] += bp[_BL]
    d0_eta = np.zeros(2 * nm)         # D0 eta per plane (the foreshortening's slopes)
    cdd_v = 0.0                       # eta'^T D0 eta': the velocity part of c''(L)
    if bp[_BSTIFF] != 0.0:
        d0 = _stiffening_block(my, nm, 0)
        for plane in range(2):
            e = np.ascontiguousarray(eta[plane * nm:(plane + 1) * nm])
            ed = np.ascontiguousarray(eta_dot[plane * nm:(plane + 1) * nm])
            de = matvec(d0, e)
            put1(d0_eta[plane * nm:(plane + 1) * nm], de)
            p_l[0] -= 0.5 * dot(e, de)
            ud_l[0] -= dot(ed, de)
            cdd_v += dot(ed, matvec(d0, ed))
    rho = matvec(a, p_l)
    aud = matvec(a, ud_l)
    v_rel = _cross(w, rho) + aud
    jl = _left_jacobian(th)
    rot_o = matmul(a, _expm(th))
    ajt = matvec(a, matvec(jl, thd))
    w_o = w + ajt
    acc_v = _cross(w, _cross(w, rho)) + 2.0 * _cross(w, aud) - cdd_v * a[:, 0]
    alpha_v = _cross(w, ajt) + matvec(a, matvec(_left_jacobian_derivative(th, thd), thd))
    br = np.zeros((3, nb))
    d = np.zeros((3, nb))
    for j in range(nt):
        d[0, 2 * nm + j] = sv[_YL, tw + j]
    for j in range(na):
        br[0, 2 * nm + nt + j] = sv[_YL, 2 * tw + j]
    for j in range(nm):
        br[1, j] = sv[_YL, j]
        br[2, nm + j] = sv[_YL, j]
        br[0, j] = -d0_eta[j]
        br[0, nm + j] = -d0_eta[nm + j]
        d[2, j] = sv[_DYL, j]
        d[1, nm + j] = -sv[_DYL, j]
    br = matmul(a, br)
    bt = matmul(a, matmul(jl, d))
    return rho, v_rel, rot_o, w_o, acc_v, alpha_v, br, bt


@kernel
def _elastic_forces(bp, sv, eta, eta_dot):
    """The generalized forces of one beam's springs and dampers on its coordinates, -c q' - k q
    each: bending k = EI int Y''^2, twist G J int Psi'^2, stretch E A int U'^2, and
    c = 2 zeta sqrt(k m) with the coordinate's modal mass m (newton_euler.py's docstring)."""
    mu = bp[_BMU]
    nm = int(bp[_BMODES])
    nt, na = int(bp[_BTWIST]), int(bp[_BSTRETCH])
    tw = sv.shape[1] // 3
    n2 = 2 * nm
    out = np.empty(n2 + nt + na)
    for i in range(n2):
        m_k = mu * sv[_MF, i % nm]
        k = (bp[_BEIV] if i < nm else bp[_BEIW]) * sv[_KF, i % nm]
        out[i] = -2.0 * bp[_BZETA] * math.sqrt(k / m_k) * m_k * eta_dot[i] - k * eta[i]
    for j in range(nt):
        m_t = bp[_BJP] * sv[_MF, tw + j]
        k_t = bp[_BGJ] * sv[_KF, tw + j]
        out[n2 + j] = (-2.0 * bp[_BZETA] * math.sqrt(k_t / m_t) * m_t * eta_dot[n2 + j]
                       - k_t * eta[n2 + j])
    for j in range(na):
        m_a = mu * sv[_MF, 2 * tw + j]
        k_a = bp[_BEA] * sv[_KF, 2 * tw + j]
        i = n2 + nt + j
        out[i] = -2.0 * bp[_BZETA] * math.sqrt(k_a * m_a) * eta_dot[i] - k_a * eta[i]
    return out


@kernel
def _beam_terms(bp, sv, my, eta, eta_dot, a, w, gravity):
    """World-frame mass properties, coupling blocks and velocity terms of one beam at its
    current (eta, eta'), from the shape integrals sv (int Y, int x Y, ...) and my = int Y Y^T
    (newton_euler.py's docstring).

    Returns mass, h = A s (first moment about I), J = A (J_b + J_p) A^T, AP = A P and AG = A G
    (3 x 2n), the velocity terms of the Newton and Euler rows (right-hand side), the modal
    equations' right-hand side (gravity, velocity, damping and stiffness terms), the modal mass
    matrix over all the beam's coordinates and geo (D0, D1, D2 eta per plane: the foreshortening's
    couplings with a_I, _assemble)."""
    length = bp[_BL]
    mu = bp[_BMU]
    nm = int(bp[_BMODES])
    nt, na = int(bp[_BTWIST]), int(bp[_BSTRETCH])
    tw = sv.shape[1] // 3             # the twist's columns of sv (_Problem.shape_vec)
    n2 = 2 * nm
    nb = n2 + nt + na
    sa = n2 + nt                      # the stretch's first coordinate
    # the stretch xi (newton_euler.py's docstring, "Stretch"): int U_j, int x U_j, int U_j^2 and the
    # products int U_j Y_l, M_av (na x nm); p = (x + U . xi, v, w)
    pa = np.ascontiguousarray(sv[_SY, 2 * tw:2 * tw + na])
    xa = np.ascontiguousarray(sv[_TY, 2 * tw:2 * tw + na])
    maa = np.ascontiguousarray(sv[_MF, 2 * tw:2 * tw + na])
    mav = np.ascontiguousarray(sv[N_SHAPE_ROWS:N_SHAPE_ROWS + nm, 2 * tw:2 * tw + na].T)
    xi = np.ascontiguousarray(eta[sa:nb])
    xid = np.ascontiguousarray(eta_dot[sa:nb])
    mva_xi = matvec(mav.T, xi)                # int Y_l u_x, int Y_l u_x' (per bending mode)
    mva_xid = matvec(mav.T, xid)
    sy = sv[_SY, :nm]
    ty = sv[_TY, :nm]
    myy = np.ascontiguousarray(my[:nm, :nm])
    ev = np.ascontiguousarray(eta[:nm])
    ew = np.ascontiguousarray(eta[nm:n2])
    dv = np.ascontiguousarray(eta_dot[:nm])
    dw = np.ascontiguousarray(eta_dot[nm:n2])
    mev = matvec(myy, ev)                          # int Y v, int Y w, int Y v', int Y w'
    mew = matvec(myy, ew)
    mdv = matvec(myy, dv)
    mdw = matvec(myy, dw)
    mass = mu * length
    # the foreshortening -c(x) e1 to first order in c (newton_euler.py's docstring, "Geometric
    # stiffening"): C1 = int c, C2 = int x c = 1/2 eta^T (D1, D2) eta, their rates, and
    # eta'^T D1 eta' (the velocity part of C1'')
    geo = np.zeros((3, nb))           # D0 eta, D1 eta, D2 eta per plane (none for the twist)
    c1 = c1_dot = c2 = c2_dot = c1_vel = 0.0
    if bp[_BSTIFF] != 0.0:
        for i in range(3):
            d = _stiffening_block(my, nm, i)
            put1(geo[i, :nm], matvec(d, ev))
            put1(geo[i, nm:n2], matvec(d, ew))
        d1 = _stiffening_block(my, nm, 1)
        c1 = 0.5 * (dot(ev, geo[1, :nm]) + dot(ew, geo[1, nm:n2]))
        c1_dot = dot(dv, geo[1, :nm]) + dot(dw, geo[1, nm:n2])
        c1_vel = dot(dv, matvec(d1, dv)) + dot(dw, matvec(d1, dw))
        c2 = 0.5 * (dot(ev, geo[2, :nm]) + dot(ew, geo[2, nm:n2]))
        c2_dot = dot(dv, geo[2, :nm]) + dot(dw, geo[2, nm:n2])
    s_b = np.empty(3)
    s_b[0] = mu * (length * length / 2.0 - c1 + dot(pa, xi))
    s_b[1] = mu * dot(sy, ev)
    s_b[2] = mu * dot(sy, ew)
    q = np.empty((3, 3))                           # int mu p p^T
    q[0, 0] = mu * (length ** 3 / 3.0 - 2.0 * c2 + 2.0 * dot(xa, xi) + dot(xi, maa * xi))
    q[0, 1] = q[1, 0] = mu * (dot(ty, ev) + dot(mva_xi, ev))
    q[0, 2] = q[2, 0] = mu * (dot(ty, ew) + dot(mva_xi, ew))
    q[1, 1] = mu * dot(ev, mev)
    q[1, 2] = q[2, 1] = mu * dot(ev, mew)
    q[2, 2] = mu * dot(ew, mew)
    tr = q[0, 0] + q[1, 1] + q[2, 2]
    j_b = -q
    for i in range(3):
        j_b[i, i] += tr
    j_b[0, 0] += bp[_BJP] * length                 # polar spin inertia J_p = diag(j_p L, 0, 0)
    p_b = np.zeros((3, nb))                        # int mu Phi
    g_b = np.zeros((3, nb))                        # int mu p^ Phi; the twist's j_p int Psi e1
    p_t = 0.0                                      # j_p int psi' (the twist's spin momentum)
    for j in range(nt):
        g_b[0, n2 + j] = bp[_BJP] * sv[_SY, tw + j]
        p_t += bp[_BJP] * sv[_SY, tw + j] * eta_dot[n2 + j]
    for j in range(nm):
        p_b[1, j] = mu * sy[j]
        p_b[2, nm + j] = mu * sy[j]
        g_b[2, j] = mu * (ty[j] + mva_xi[j])       # p x (Y_j e2) = Y_j (-w, 0, x + u_x)
        g_b[0, j] = -mu * mew[j]
        g_b[1, nm + j] = -mu * (ty[j] + mva_xi[j])  # p x (Y_j e3) = Y_j (v, -(x + u_x), 0)
        g_b[0, nm + j] = mu * mev[j]
    mav_v, mav_w = matvec(mav, ev), matvec(mav, ew)    # int U_j v, int U_j w
    mav_dv, mav_dw = matvec(mav, dv), matvec(mav, dw)
    for j in range(na):
        p_b[0, sa + j] = mu * pa[j]
        g_b[1, sa + j] = mu * mav_w[j]             # p x (U_j e1) = U_j (0, w, -v)
        g_b[2, sa + j] = -mu * mav_v[j]
    c = np.zeros((3, 3))                           # int mu p' p^T
    c[0, 0] = mu * (-c2_dot + dot(xa, xid) + dot(xid, maa * xi))
    c[0, 1] = mu * dot(xid, mav_v)
    c[0, 2] = mu * dot(xid, mav_w)
    c[1, 0] = mu * (dot(ty, dv) + dot(mva_xi, dv))
    c[2, 0] = mu * (dot(ty, dw) + dot(mva_xi, dw))
    c[1, 1] = mu * dot(dv, mev)
    c[1, 2] = mu * dot(dv, mew)
    c[2, 1] = mu * dot(dw, mev)
    c[2, 2] = mu * dot(dw, mew)
    w_b = matvec(a.T, w)
    trc = c[0, 0] + c[1, 1] + c[2, 2]
    cor_b = 2.0 * (trc * w_b - matvec(c, w_b))     # int mu p x (2 w x u')
    ap = matmul(a, p_b)
    ag = matmul(a, g_b)
    h = matvec(a, s_b)
    j_w = matmul(matmul(a, j_b), a.T)
    e1 = np.ascontiguousarray(a[:, 0])
    ud = matvec(ap, eta_dot) - mu * c1_dot * e1         # A int mu p' dx
    # the velocity terms; A int mu p'' = A P eta'' - mu (eta'^T D1 eta' + (D1 eta)^T eta'') e1
    newton_v = -2.0 * _cross(w, ud) + mu * c1_vel * e1
    euler_v = -matvec(a, cor_b) - p_t * _cross(w, e1)  # and the twist's spin momentum turning
    # modal right-hand side
    ww2 = w_b[0] * w_b[0] + w_b[1] * w_b[1] + w_b[2] * w_b[2]
    mm = np.outer(w_b, w_b)                        # w^ w^ = w w^T - |w|^2 E
    for i in range(3):
        mm[i, i] -= ww2
    g_w = matvec(ap.T, gravity)                   # (A P)^T g
    modal = _elastic_forces(bp, sv, eta, eta_dot)
    for j in range(nm):
        x_j = ty[j] + mva_xi[j]                   # int Y_j (x + u_x)
        cent_v = mu * (x_j * mm[1, 0] + mm[1, 1] * mev[j] + mm[1, 2] * mew[j])
        cent_w = mu * (x_j * mm[2, 0] + mm[2, 1] * mev[j] + mm[2, 2] * mew[j])
        # 2 int mu Y_j e2 . (w_b x u'), u' = (u_x', v', w')
        cori_v = 2.0 * mu * (w_b[2] * mva_xid[j] - w_b[0] * mdw[j])
        cori_w = 2.0 * mu * (w_b[0] * mdv[j] - w_b[1] * mva_xid[j])
        modal[j] += g_w[j] - cent_v - cori_v
        modal[nm + j] += g_w[nm + j] - cent_w - cori_w
    for j in range(na):                            # the stretch: e1 . int mu U_j (...)
        cent_a = mu * ((xa[j] + maa[j] * xi[j]) * mm[0, 0] + mm[0, 1] * mav_v[j]
                       + mm[0, 2] * mav_w[j])
        cori_a = 2.0 * mu * (w_b[1] * mav_dw[j] - w_b[2] * mav_dv[j])
        modal[sa + j] += g_w[sa + j] - cent_a - cori_a
    # geometric stiffening: + mu e1.(g - a_I) D1 eta + mu (w_y^2 + w_z^2) D2 eta on the left
    # (newton_euler.py's docstring; N_L D0 eta is the end force's work through B_r); the a_I term
    # goes to the matrix (_assemble, with geo), the rest here
    if bp[_BSTIFF] != 0.0:
        known = mu * dot(e1, gravity) * geo[1] + mu * (w_b[1] ** 2 + w_b[2] ** 2) * geo[2]
        for j in range(n2):
            modal[j] -= known[j]
    m_ee = np.zeros((nb, nb))                      # the modal mass: mu int Y Y^T per plane,
    for j in range(nm):                            # j_p int Psi^2 (twist), mu int U^2 (stretch)
        for i in range(nm):
            m_ee[j, i] = m_ee[nm + j, nm + i] = mu * myy[j, i]
    for j in range(nt):
        m_ee[n2 + j, n2 + j] = bp[_BJP] * sv[_MF, tw + j]
    for j in range(na):
        m_ee[sa + j, sa + j] = mu * maa[j]
    return mass, h, j_w, ap, ag, newton_v, euler_v, modal, m_ee, geo


@kernel
def _beam_terms_exact(bp, sv, table, eta, eta_dot, a, w, gravity):
    """_beam_terms with the foreshortening kept exactly (newton_euler.py's docstring, "Geometric
    stiffening, exact"): every section is a point of the quadrature `table`
    (shapes.exact_foreshortening_table) at p = (x + u_x - c, v, w) in the frame, its velocity
    relative to the frame Phi eta' and the velocity part of its acceleration kappa =
    -(eta_v'^T D eta_v' + eta_w'^T D eta_w') e1, with Phi's columns d p / d eta_j:
    (-(D eta_v)_j, Y_j, 0) and (-(D eta_w)_j, 0, Y_j) for the bending, (U_j, 0, 0) for the
    stretch, none for the twist (its terms are _beam_terms').  The mass properties are the sums
    of mu weight over the points of p, p p^T, Phi, p^ Phi and Phi^T Phi, the Newton, Euler and
    modal velocity terms those of -(2 w x Phi eta' + kappa), and the modal rows' right-hand side
    Phi^T A^T g - Phi^T (w x (w x p) + 2 w x Phi eta' + kappa) - damping - stiffness.  Returns
    what _beam_terms does, with the modal mass over all the beam's coordinates and no `geo`
    (the foreshortening's couplings are in A P, the modal mass and the velocity terms)."""
    length = bp[_BL]
    mu = bp[_BMU]
    nm = int(bp[_BMODES])
    nt, na = int(bp[_BTWIST]), int(bp[_BSTRETCH])
    tw = sv.shape[1] // 3
    n2 = 2 * nm
    nb = n2 + nt + na
    sa = n2 + nt
    w_b = matvec(a.T, w)
    g_b = matvec(a.T, gravity)
    s_b = np.zeros(3)
    pi = np.zeros((3, 3))
    p_b = np.zeros((3, nb))
    gg_b = np.zeros((3, nb))
    m_ee = np.zeros((nb, nb))
    ud_b = np.zeros(3)
    kap_b = np.zeros(3)
    lcor = np.zeros(3)
    modal = np.zeros(nb)
    phi = np.zeros((3, nb))
    for g in range(table.shape[0]):
        x, wt = table[g, 0], table[g, 1]
        if wt == 0.0:                  # (a padded row: _Problem's table is the widest beam's)
            continue
        y = table[g, 2:2 + nm]
        d = np.ascontiguousarray(table[g, 2 + nm:2 + nm + nm * nm]).reshape((nm, nm))
        u = table[g, 2 + nm + nm * nm:2 + nm + nm * nm + na]
        ev, ew = eta[:nm], eta[nm:n2]
        dv, dw = eta_dot[:nm], eta_dot[nm:n2]
        dev, dew = matvec(d, ev), matvec(d, ew)
        phi[:, :] = 0.0
        for j in range(nm):
            phi[0, j] = -dev[j]
            phi[1, j] = y[j]
            phi[0, nm + j] = -dew[j]
            phi[2, nm + j] = y[j]
        for j in range(na):
            phi[0, sa + j] = u[j]
        pos = np.empty(3)
        pos[0] = x - 0.5 * (dot(ev, dev) + dot(ew, dew))
        pos[1] = dot(y, ev)
        pos[2] = dot(y, ew)
        for j in range(na):
            pos[0] += u[j] * eta[sa + j]
        vel = matvec(phi, eta_dot)
        kap = np.zeros(3)
        kap[0] = -(dot(dv, matvec(d, dv)) + dot(dw, matvec(d, dw)))
        acc_v = _cross(w_b, _cross(w_b, pos)) + 2.0 * _cross(w_b, vel) + kap
        f = mu * wt
        s_b += f * pos
        pi += f * np.outer(pos, pos)
        p_b += f * phi
        gg_b += f * matmul(_hat(pos), phi)
        m_ee += f * matmul(phi.T, phi)
        ud_b += f * vel
        kap_b += f * kap
        lcor += f * _cross(pos, 2.0 * _cross(w_b, vel) + kap)
        modal += f * matvec(phi.T, g_b - acc_v)
    mass = mu * length
    j_b = -pi
    tr = pi[0, 0] + pi[1, 1] + pi[2, 2]
    for i in range(3):
        j_b[i, i] += tr
    j_b[0, 0] += bp[_BJP] * length                 # polar spin inertia J_p = diag(j_p L, 0, 0)
    p_t = 0.0                                      # j_p int psi' (the twist's spin momentum)
    for j in range(nt):
        gg_b[0, n2 + j] = bp[_BJP] * sv[_SY, tw + j]
        p_t += bp[_BJP] * sv[_SY, tw + j] * eta_dot[n2 + j]
        m_ee[n2 + j, n2 + j] = bp[_BJP] * sv[_MF, tw + j]
    e1 = np.ascontiguousarray(a[:, 0])
    newton_v = -2.0 * _cross(w, matvec(a, ud_b)) - matvec(a, kap_b)
    euler_v = -matvec(a, lcor) - p_t * _cross(w, e1)
    modal += _elastic_forces(bp, sv, eta, eta_dot)
    return (mass, matvec(a, s_b), matmul(matmul(a, j_b), a.T), matmul(a, p_b), matmul(a, gg_b),
            newton_v, euler_v, modal, m_ee,
            np.zeros((3, nb)))


@kernel
def _flex_size(k, body_kind, beam_params, rods):
    """The coordinates of body k's own: a beam's modal ones, a strain rod's strain ones, a rigid
    body's none (another code is refused: elements/kinds.py, UNDECLARED_BODY_KIND).
    rods: the strain rods' tables (newton_euler.py::_rod_tables), n_q[k] = 0 for other bodies."""
    if body_kind[k] == _BEAM:
        return _modal_size(beam_params[k])
    if body_kind[k] == _ROD:
        return rods[0][k]
    if body_kind[k] == _RIGID:
        return 0
    raise ValueError(_UNDECLARED_BODY_KIND)
