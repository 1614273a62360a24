"""Transfer matrix of a rigid body over one time step (docs/rigid_body.md).

Station state z = [a, phi, m, q] (12 entries, then the affine 1):
  a    world acceleration of the station point,
  phi  world rotation increment of the body over the step, A_i = exp(phi^) A_{i-1}
       (in the consistent-start solve the same slot holds the angular acceleration),
  m, q moment (about the station point) and force that the inboard side exerts on the outboard
       side, world components.
The body's angular velocity and acceleration are linearized about phi* by the integrator
(docs/solver.md): w ~ w* + Dw (phi - phi*), w_dot ~ wd* + Dwd (phi - phi*), and its rotation as
A(phi) l ~ A* l - (A* l)^ Lam (phi - phi*), Lam = J_l(phi*).
"""
import numpy as np

from .. import kernel
from ..algebra.mat3 import (matvec_into, neg2, put1, t_hat, t_lin9, t_mm, t_mul_hat, t_outer,
                            t_plus_diag)
from ..algebra.so3 import hat

A, PHI, M, Q = 0, 3, 6, 9   # offsets of the blocks in the 12-entry station state
CONST = 12                  # column of the affine part


@kernel
def _mm(a, b):
    """a @ b for 3 x 3 matrices, by loops: BLAS's call overhead dominates at this size."""
    out = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            out[i, j] = a[i, 0] * b[0, j] + a[i, 1] * b[1, j] + a[i, 2] * b[2, j]
    return out


@kernel
def _mv(a, v):
    """a @ v for a 3 x 3 matrix and a 3-vector."""
    out = np.empty(3)
    for i in range(3):
        out[i] = a[i, 0] * v[0] + a[i, 1] * v[1] + a[i, 2] * v[2]
    return out


@kernel
def _cross(a, b):
    out = np.empty(3)
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]
    return out


@kernel(entry=True)
def _hat(v):
    out = np.empty((3, 3))
    hat(v, out)
    return out


@kernel
def _kappa(w, wd, rho, dwd, dw, d_rho):
    """kappa = wd x rho + w x (w x rho) and its derivative with respect to phi, given
    d wd/d phi = dwd, d w/d phi = dw and d rho/d phi = d_rho."""
    kappa = np.empty(3)
    d = np.empty((3, 3))
    _kappa_into(w, wd, rho, dwd, dw, d_rho, kappa, d, np.empty((5, 3, 3)))
    return kappa, d


@kernel
def _mm_add(a, b, f, out):
    """out += f a @ b (3 x 3, by loops)."""
    for i in range(3):
        for j in range(3):
            out[i, j] += f * (a[i, 0] * b[0, j] + a[i, 1] * b[1, j] + a[i, 2] * b[2, j])


@kernel
def _cross_into(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@kernel
def _kappa_into(w, wd, rho, dwd, dw, d_rho, kappa, d, buf):
    """kappa = wd x rho + w x (w x rho) and d = d kappa / d phi
    = -rho^ Dwd + wd^ R - ((w x rho)^ + w^ rho^) Dw + w^ w^ R (R = d rho / d phi);
    buf: (5, 3, 3) scratch."""
    rho_h, wd_h, w_h, m1, m2 = buf[0], buf[1], buf[2], buf[3], buf[4]
    wr0 = w[1] * rho[2] - w[2] * rho[1]
    wr1 = w[2] * rho[0] - w[0] * rho[2]
    wr2 = w[0] * rho[1] - w[1] * rho[0]
    kappa[0] = wd[1] * rho[2] - wd[2] * rho[1] + w[1] * wr2 - w[2] * wr1
    kappa[1] = wd[2] * rho[0] - wd[0] * rho[2] + w[2] * wr0 - w[0] * wr2
    kappa[2] = wd[0] * rho[1] - wd[1] * rho[0] + w[0] * wr1 - w[1] * wr0
    hat(rho, rho_h)
    hat(wd, wd_h)
    hat(w, w_h)
    m1[:, :] = 0.0
    m1[0, 1], m1[0, 2], m1[1, 2] = -wr2, wr1, -wr0          # (w x rho)^
    m1[1, 0], m1[2, 0], m1[2, 1] = wr2, -wr1, wr0
    _mm_add(w_h, rho_h, 1.0, m1)
    m2[:, :] = 0.0
    _mm_add(w_h, d_rho, 1.0, m2)
    d[:, :] = 0.0
    _mm_add(rho_h, dwd, -1.0, d)
    _mm_add(wd_h, d_rho, 1.0, d)
    _mm_add(m1, dw, -1.0, d)
    _mm_add(w_h, m2, 1.0, d)


@kernel
def rigid_body_transfer(p, a_star, lam, dwd, dw, wd, w, z_star, load, torque, u):
    """Fill u (12 x 13) with the affine transfer z_O = u[:, :12] z_I + u[:, 12] of a rigid body,
    linearized about the input state z_star (the rotation at z_star[PHI] is a_star).

    p: body parameter row (mass, l_IC, l_IO, J_I); wd, w: angular acceleration and velocity at
    the guess, dwd, dw their derivatives with respect to phi; load = M g + F (world, at the mass
    centre);
    torque: applied world torque.  Equations (uniform sign convention, docs/rigid_body.md):
      a_O = a_I + kappa(l_IO)
      q_O = q_I + load - M (a_I + kappa(l_IC))
      m_O = m_I - rho x q_O + rho_C x load + torque - (J w_dot + w x J w + M rho_C x a_I)
    (3 x 3 products by loops into one scratch block: the kernel runs once per body and step,
    where BLAS calls and small allocations would cost more than the arithmetic.)
    """
    mass = p[0]
    l_ic = p[1:4]
    l_io = p[4:7]
    j_body = p[7:16].reshape((3, 3))
    a_i = z_star[A:A + 3]
    m_i = z_star[M:M + 3]
    q_i = z_star[Q:Q + 3]
    mat = np.empty((19, 3, 3))
    vec = np.empty((12, 3))
    rho, rho_c, kap_o, kap_c, jwd, jw, q_o, m_o, t0, t1, a_o = (
        vec[0], vec[1], vec[2], vec[3], vec[4], vec[5], vec[6], vec[7], vec[8], vec[9], vec[10])
    rho_h, rhoc_h, d_rho, d_rhoc, dkap_o, dkap_c, j, jt, d_m, h1, h2, h3 = (
        mat[0], mat[1], mat[2], mat[3], mat[4], mat[5], mat[6], mat[7], mat[8], mat[9], mat[10],
        mat[11])
    scratch = mat[12:17]
    w_h, jw_h = mat[17], mat[18]

    matvec_into(a_star, l_io, rho)
    matvec_into(a_star, l_ic, rho_c)
    hat(rho, rho_h)
    hat(rho_c, rhoc_h)
    d_rho[:, :] = 0.0
    _mm_add(rho_h, lam, -1.0, d_rho)          # d(A l_IO)/d phi
    d_rhoc[:, :] = 0.0
    _mm_add(rhoc_h, lam, -1.0, d_rhoc)        # d(A l_IC)/d phi
    _kappa_into(w, wd, rho, dwd, dw, d_rho, kap_o, dkap_o, scratch)
    _kappa_into(w, wd, rho_c, dwd, dw, d_rhoc, kap_c, dkap_c, scratch)

    jt[:, :] = 0.0
    _mm_add(a_star, j_body, 1.0, jt)
    for r in range(3):                        # J = A J_I A^T
        for c in range(3):
            j[r, c] = jt[r, 0] * a_star[c, 0] + jt[r, 1] * a_star[c, 1] + jt[r, 2] * a_star[c, 2]
    matvec_into(j, wd, jwd)
    matvec_into(j, w, jw)
    hat(w, w_h)
    hat(jw, jw_h)

    # values at the linearization point
    for i in range(3):
        q_o[i] = q_i[i] + load[i] - mass * (a_i[i] + kap_c[i])
        a_o[i] = a_i[i] + kap_o[i]
    _cross_into(rho, q_o, t0)
    _cross_into(rho_c, load, t1)
    for i in range(3):
        m_o[i] = m_i[i] - t0[i] + t1[i] + torque[i] - jwd[i]
    _cross_into(w, jw, t0)
    _cross_into(rho_c, a_i, t1)
    for i in range(3):
        m_o[i] -= t0[i] + mass * t1[i]

    for r in range(12):
        for c in range(13):
            u[r, c] = 0.0
    for i in range(3):
        u[A + i, A + i] = 1.0
        u[PHI + i, PHI + i] = 1.0
        u[Q + i, Q + i] = 1.0
        u[Q + i, A + i] = -mass
        u[M + i, M + i] = 1.0
    # d m_O / d phi (docs/rigid_body.md, "Linearization"):
    # -rho x q_O: rho^ (M dkap_c) + q_O^ d_rho ; rho_C x load: -load^ d_rhoc
    d_m[:, :] = 0.0
    _mm_add(rho_h, dkap_c, mass, d_m)
    hat(q_o, h1)
    _mm_add(h1, d_rho, 1.0, d_m)
    hat(load, h1)
    _mm_add(h1, d_rhoc, -1.0, d_m)
    # J w_dot: J Dwd + [-(J wd)^ + J wd^] Lam
    _mm_add(j, dwd, -1.0, d_m)
    hat(jwd, h1)
    neg2(h2, h1)
    hat(wd, h1)
    _mm_add(j, h1, 1.0, h2)
    _mm_add(h2, lam, -1.0, d_m)
    # w x J w: (w^ J - (J w)^) Dw + w^ [-(J w)^ + J w^] Lam
    neg2(h2, jw_h)
    _mm_add(w_h, j, 1.0, h2)
    _mm_add(h2, dw, -1.0, d_m)
    neg2(h2, jw_h)
    _mm_add(j, w_h, 1.0, h2)
    h3[:, :] = 0.0
    _mm_add(h2, lam, 1.0, h3)
    _mm_add(w_h, h3, -1.0, d_m)
    # M rho_C x a_I: -M a_I^ d_rhoc
    hat(a_i, h1)
    _mm_add(h1, d_rhoc, mass, d_m)
    for i in range(3):
        for c in range(3):
            u[A + i, PHI + c] = dkap_o[i, c]
            u[Q + i, PHI + c] = -mass * dkap_c[i, c]
            u[M + i, Q + c] = -rho_h[i, c]
            u[M + i, A + c] = mass * (rho_h[i, c] - rhoc_h[i, c])
            u[M + i, PHI + c] = d_m[i, c]

    affine_part(u, a_o, z_star[PHI:PHI + 3], m_o, q_o, z_star)


@kernel
def affine_part(u, a_o, phi_o, m_o, q_o, z_star):
    """u[:, CONST] such that u [z*; 1] = [a_o, phi_o, m_o, q_o], the transfer's value at the
    guess z* (the linearized map reproduces the relations there)."""
    value = np.empty(12)
    put1(value[A:A + 3], a_o)
    put1(value[PHI:PHI + 3], phi_o)
    put1(value[M:M + 3], m_o)
    put1(value[Q:Q + 3], q_o)
    for r in range(12):
        acc = value[r]
        for c in range(12):
            acc -= u[r, c] * z_star[c]
        u[r, CONST] = acc


@kernel
def station_history_correction(p, rot_n, a_star, lam, dwd, dw, wd, w, c1, w1_in, w1_out, w1_c,
                               z_star, u):
    """The paper's scheme (docs/solver.md, "The paper's scheme"): turn the rigid transfer that
    rigid_body_transfer wrote into u (phi slots) into one where the output point and the mass
    centre carry their own Newmark histories, tied to the input point at position level only:
      a_X = a_I + sigma_X,  sigma_X = c1 (A - A_n) l_X + w1_X - w1_I       (X = O, C)
    in place of the rigid kinematics a_X = a_I + kappa(rho_X).  Newton for the mass centre and
    Euler about it are unchanged, so with Dq = -M (sigma_C - kappa_C)
      q_O' = q_O + Dq,   m_O' = m_O - (rho - rho_C) x Dq.
    w1_in, w1_out, w1_c: the histories' offsets (a_X = c1 dr_X + w1_X)."""
    mass = p[0]
    l_ic = p[1:4]
    l_io = p[4:7]
    rho = _mv(a_star, l_io)
    rho_c = _mv(a_star, l_ic)
    d_rho = -_mm(_hat(rho), lam)
    d_rhoc = -_mm(_hat(rho_c), lam)
    kap_o, dkap_o = _kappa(w, wd, rho, dwd, dw, d_rho)
    kap_c, dkap_c = _kappa(w, wd, rho_c, dwd, dw, d_rhoc)
    sig_o = c1 * (rho - _mv(rot_n, l_io)) + w1_out - w1_in
    sig_c = c1 * (rho_c - _mv(rot_n, l_ic)) + w1_c - w1_in
    dq = -mass * (sig_c - kap_c)
    d_dq = -mass * (c1 * d_rhoc - dkap_c)
    arm = rho - rho_c
    dm = -_cross(arm, dq)
    d_dm = -_mm(_hat(arm), d_dq) + _mm(_hat(dq), d_rho - d_rhoc)
    delta = np.empty(12)
    d_delta = np.zeros((12, 3))
    for i in range(3):
        delta[A + i] = sig_o[i] - kap_o[i]
        delta[PHI + i] = 0.0
        delta[M + i] = dm[i]
        delta[Q + i] = dq[i]
        for c in range(3):
            d_delta[A + i, c] = c1 * d_rho[i, c] - dkap_o[i, c]
            d_delta[M + i, c] = d_dm[i, c]
            d_delta[Q + i, c] = d_dq[i, c]
    for r in range(12):
        shift = delta[r]
        for c in range(3):
            u[r, PHI + c] += d_delta[r, c]
            shift -= d_delta[r, c] * z_star[PHI + c]
        u[r, CONST] += shift


@kernel
def kappa_values(w, wd):
    """K = wd^ + w^ w^ = w w^T - |w|^2 E + wd^ as a 9-tuple (kernels/algebra/mat3.py), so that
    kappa(x) = wd x x + w x (w x x) = K x (the acceleration of a body point at x from the
    reference point, docs/rigid_body.md)."""
    return t_lin9(1.0, t_plus_diag(t_outer(w, w), -(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])),
                  1.0, t_hat(wd))


@kernel
def _jacobian_terms(x, y, t, w, lam, s, r):
    """-y^ - r R(x) - s t Lam, R(x) = 2 x w^T - w x^T - (w . x) E (point_jacobian_values)."""
    out = t_lin9(-2.0 * r, t_outer(x, w), r, t_outer(w, x))
    out = t_lin9(1.0, t_plus_diag(out, r * (w[0] * x[0] + w[1] * x[1] + w[2] * x[2])), -s,
                 t_mm(t, lam))
    return t_lin9(1.0, out, -1.0, t_hat(y))


@kernel
def point_jacobian_values(x, u, v, w, kmat, lam, s, r):
    """d r''/d w' for r'' = a_I + w' x x + w x (w x x) + 2 w x U + V (a point, or a
    mass-weighted sum of points: it is linear in x, U = A u', V = A u''), through w' itself,
    w (d w = r d w') and the frame's rotation (d theta = s Lam d w', x, U, V turning with it):
      -x^ - r (R(x) + 2 U^) - s (K x^ + 2 w^ U^ + V^) Lam,
    R(x) = (w x x)^ + w^ x^ = 2 x w^T - w x^T - (w . x) E, K = w'^ + w^ w^.
    Every argument and the result on values (3- and 9-tuples, kernels/algebra/mat3.py)."""
    # K x^ + 2 w^ U^ + V^,  w^ U^ = U w^T - (w . U) E
    t = t_lin9(1.0, t_mul_hat(kmat, x), 2.0, t_outer(u, w))
    t = t_lin9(1.0, t_plus_diag(t, -2.0 * (w[0] * u[0] + w[1] * u[1] + w[2] * u[2])), 1.0,
               t_hat(v))
    y = (x[0] + 2.0 * r * u[0], x[1] + 2.0 * r * u[1], x[2] + 2.0 * r * u[2])
    return _jacobian_terms(x, y, t, w, lam, s, r)


@kernel
def rigid_point_jacobian_values(x, w, kmat, lam, s, r):
    """point_jacobian_values of a point of a rigid body (U = V = 0): -x^ - r R(x) - s K x^ Lam."""
    return _jacobian_terms(x, x, t_mul_hat(kmat, x), w, lam, s, r)
