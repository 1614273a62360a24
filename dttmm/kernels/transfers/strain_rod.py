"""The strain rod's kinematics (docs/strain_rod.md): the sections of a rod whose centre line is
the exponential integral of its strain, their poses, velocities and accelerations in the rod's
input-section frame, from the strain coordinates q and their rates.

The strain (curvatures, twist, stretch; no shear) along the rod is xi(X) = xi0(X) + Phi(X) q in
the section's own frame, [angular; linear] (docs/strain_rod.md, "Strain"); the section's pose
g = (R, p) solves g' = g xi^ from g(0) = (I, 0).  Between consecutive stations X_a, X_a + h the
step is Magnus' fourth-order one on two Gauss points (docs/strain_rod.md, "Kinematics"):

    Omega = h/2 (xi_1 + xi_2) + sqrt(3)/12 h^2 ad(xi_1) xi_2,     g_{a+1} = g_a exp(Omega^),

exact for a strain constant over the step (ad(xi) xi = 0).  exp of Omega = [theta; u] is
(exp(theta^), J_l(theta) u).  Differentiating the step in time, with the rod's own motion
(omega, the angular velocity of the section, and p', both in the input frame):

    omega_{a+1} = omega_a + R_a J_l theta'
    p'_{a+1}    = p'_a + omega_a x (R_a t) + R_a t',          t = J_l(theta) u
    alpha_{a+1} = alpha_a + omega_a x (R_a J_l theta') + R_a (DJ_l[theta'] theta' + J_l theta'')
    p''_{a+1}   = p''_a + alpha_a x (R_a t) + omega_a x (omega_a x (R_a t))
                  + 2 omega_a x (R_a t') + R_a t''
    t'  = DJ_l[theta'] u + J_l u'
    t'' = D2J_l[theta', theta'] u + DJ_l[theta''] u + 2 DJ_l[theta'] u' + J_l u''

with Omega' and Omega'' from xi' = Phi q', xi'' = Phi q'' (the bracket's product rule; its
second derivative has the cross term 2 ad(xi'_1) xi'_2).  Everything is exact to rounding: the
velocities are linear in q' at a given q (a unit q' gives a Jacobian column) and the
accelerations at q'' = 0 are the convective terms.
"""
import numpy as np
from numba import njit

from .. import CONTRACT, kernel, model_tables
from ..algebra.mat3 import (dot, matmul, matvec, put1, put2, t_cross, t_hat, t_lin9, t_mm, t_mv,
                            t_of_mat, t_of_vec, t_plus_diag)
from ..algebra.so3 import exp_coefficients, expm_so3, log_so3

SQRT3_12 = np.sqrt(3.0) / 12.0


def _series(sign_shift, terms=14):
    """The Taylor coefficients in x = t^2 of B (shift 2: (1 - cos t)/t^2) or C (shift 3:
    (t - sin t)/t^3), B(x) = sum (-1)^k x^k / (2k + 2)!, and of their first two derivatives
    in x."""
    from math import factorial
    f = [(-1) ** k / factorial(2 * k + sign_shift) for k in range(terms)]
    d1 = [(k + 1) * f[k + 1] for k in range(terms - 1)]
    d2 = [(k + 1) * d1[k + 1] for k in range(terms - 2)]
    return tuple(f), tuple(d1), tuple(d2)


_B, _B1, _B2 = _series(2)
_C, _C1, _C2 = _series(3)
SERIES_BELOW = 4.0          # t^2 below which the coefficients come from their series (t < 2)


@kernel
def _poly(coefficients, x):
    s = 0.0
    for k in range(len(coefficients) - 1, -1, -1):
        s = s * x + coefficients[k]
    return s


@kernel(entry=True)
def jacobian_coefficients(th2):
    """(b, c, beta, gamma, beta1, gamma1) at t^2 = th2: J_l = I + b t^ + c t^^ with
    b = (1 - cos t)/t^2, c = (t - sin t)/t^3, beta = b'(t)/t, gamma = c'(t)/t,
    beta1 = beta'(t)/t, gamma1 = gamma'(t)/t.  As functions of x = t^2, beta = 2 B'(x),
    beta1 = 4 B''(x) (and C's alike): their series below t = 2 (14 terms, remainder below
    4^14 / 30! ~ 1e-24), the closed forms above (whose cancellations lose at most ~1e3 eps
    there)."""
    if th2 < SERIES_BELOW:
        return (_poly(_B, th2), _poly(_C, th2), 2.0 * _poly(_B1, th2), 2.0 * _poly(_C1, th2),
                4.0 * _poly(_B2, th2), 4.0 * _poly(_C2, th2))
    t = np.sqrt(th2)
    s, c = np.sin(t), np.cos(t)
    t4 = th2 * th2
    return ((1.0 - c) / th2, (t - s) / (th2 * t),
            (t * s - 2.0 * (1.0 - c)) / t4,
            (1.0 - c) / t4 - 3.0 * (t - s) / (t4 * t),
            (th2 * c - 5.0 * t * s + 8.0 * (1.0 - c)) / (t4 * th2),
            s / (t4 * t) - 7.0 * (1.0 - c) / (t4 * th2) + 15.0 * (t - s) / (t4 * th2 * t))


@njit(cache=True, inline='always', fastmath=CONTRACT)
def jacobian_derivatives_applied(coefficients, theta, d, dd, u):
    """(DJ_l(theta)[d] u, DJ_l(theta)[dd] u + D2J_l(theta)[d, d] u): the first and second
    derivatives of t(s) = J_l(theta(s)) u along theta(s) = theta + s d + s^2/2 dd at s = 0,
    u fixed (3-tuples; coefficients: jacobian_coefficients(|theta|^2)).  With J_l u = u +
    B theta x u + C theta x (theta x u), B(s) = b(|theta(s)|), whose derivatives are
    B' = beta (theta . d), B'' = beta1 (theta . d)^2 + beta (|d|^2 + theta . dd) (C's with
    gamma, gamma1)."""
    b, c, beta, gamma, beta1, gamma1 = coefficients
    td = _dot(theta, d)
    dB, dC = beta * td, gamma * td
    rest = _dot(d, d) + _dot(theta, dd)
    ddB = beta1 * td * td + beta * rest
    ddC = gamma1 * td * td + gamma * rest
    txu = t_cross(theta, u)
    dxu = t_cross(d, u)
    ddxu = t_cross(dd, u)
    txtxu = t_cross(theta, txu)
    mixed = _add(t_cross(d, txu), t_cross(theta, dxu))
    first = _sum4(dB, txu, b, dxu, dC, txtxu, c, mixed)
    second = _add(_sum4(ddB, txu, 2.0 * dB, dxu, b, ddxu, ddC, txtxu),
                  _sum4(2.0 * dC, mixed, 2.0 * c, t_cross(d, dxu), c, t_cross(dd, txu),
                        c, t_cross(theta, ddxu)))
    return first, second


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _dot(x, y):
    return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _add(x, y):
    return (x[0] + y[0], x[1] + y[1], x[2] + y[2])


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _sum4(a, x, b, y, c, z, d, v):
    """a x + b y + c z + d v (3-tuples)."""
    return (a * x[0] + b * y[0] + c * z[0] + d * v[0], a * x[1] + b * y[1] + c * z[1] + d * v[1],
            a * x[2] + b * y[2] + c * z[2] + d * v[2])


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _scale(a, x):
    return (a * x[0], a * x[1], a * x[2])


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _apply_jacobian(b, c, theta, v):
    """J_l(theta) v = v + b theta x v + c theta x (theta x v)."""
    txv = t_cross(theta, v)
    return _sum4(1.0, v, b, txv, c, t_cross(theta, txv), 0.0, v)


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _mtv(a, x):
    """a^T x (a a 9-tuple)."""
    return (a[0] * x[0] + a[3] * x[1] + a[6] * x[2], a[1] * x[0] + a[4] * x[1] + a[7] * x[2],
            a[2] * x[0] + a[5] * x[1] + a[8] * x[2])


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _put(row, x):
    row[0], row[1], row[2] = x[0], x[1], x[2]


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _field(base, xi0, phi, q):
    """(angular, linear) 3-tuples of base xi0 + phi q (xi0 (6,), phi (6, n_q))."""
    x0, x1, x2 = base * xi0[0], base * xi0[1], base * xi0[2]
    x3, x4, x5 = base * xi0[3], base * xi0[4], base * xi0[5]
    for j in range(q.shape[0]):
        qj = q[j]
        x0 += phi[0, j] * qj
        x1 += phi[1, j] * qj
        x2 += phi[2, j] * qj
        x3 += phi[3, j] * qj
        x4 += phi[4, j] * qj
        x5 += phi[5, j] * qj
    return (x0, x1, x2), (x3, x4, x5)


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _ad(xw, xv, yw, yv):
    """ad(x) y = [x_w x y_w; x_w x y_v + x_v x y_w] (se(3), [angular; linear]) as 3-tuples."""
    return t_cross(xw, yw), _add(t_cross(xw, yv), t_cross(xv, yw))


@kernel(entry=True)
def station_arrays(n):
    """The outputs of rod_kinematics for n stations: rotations (n, 3, 3), centres, angular
    velocities, velocities, angular accelerations, accelerations (n, 3 each), zeroed."""
    return (np.zeros((n, 3, 3)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)),
            np.zeros((n, 3)), np.zeros((n, 3)))


@kernel(entry=True)
def rod_kinematics(steps, xi0, phi, q, qd, qdd, rot, pos, omega, vel, alpha, acc):
    """The stations' poses, velocities and accelerations in the input-section frame (the module's
    docstring).  steps[a] is the a-th step's length h; xi0[a, i] (6) and phi[a, i] (6 x nq) the
    reference strain and the strain basis at its Gauss point i
    (elements/strain_rod.py::MAGNUS_POINTS).  Writes, for the stations 0 .. len(steps) (station
    0 the input section: identity, zeros), rot (3 x 3), pos, omega, vel, alpha, acc (3 each).
    On values (mat3's 3-tuples): it allocates nothing."""
    section = _input_section()
    _store(rot[0], pos[0], omega[0], vel[0], alpha[0], acc[0], section)
    for a in range(steps.shape[0]):
        section = _magnus_step(steps[a], xi0[a], phi[a], q, qd, qdd, section)
        _store(rot[a + 1], pos[a + 1], omega[a + 1], vel[a + 1], alpha[a + 1], acc[a + 1],
               section)


@kernel
def rod_end(steps, xi0, phi, q, qd, qdd):
    """The end section's (R_L (9-tuple, row-major), p_L, omega_L, p_L', alpha_L, p_L'') in the
    input-section frame: rod_kinematics' last station, on values (no station arrays; callable
    from kernels compiled without reference counting)."""
    section = _input_section()
    for a in range(steps.shape[0]):
        section = _magnus_step(steps[a], xi0[a], phi[a], q, qd, qdd, section)
    return section


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _input_section():
    """Station 0, the input section: (R, p, omega, p', alpha, p'') = (I, 0, ..., 0)."""
    zero = (0.0, 0.0, 0.0)
    return (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0), zero, zero, zero, zero, zero


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _magnus_step(h, xi0, phi, q, qd, qdd, section):
    """One Magnus step of length h from the section (R_a, p_a, omega_a, p_a', alpha_a, p_a'')
    to the next (the module's docstring); xi0 (2, 6), phi (2, 6, nq) at its Gauss points."""
    ra, p_a, w_a, v_a, al_a, ac_a = section
    k = SQRT3_12 * h * h
    x1w, x1v = _field(1.0, xi0[0], phi[0], q)      # the strain at the Gauss points
    x2w, x2v = _field(1.0, xi0[1], phi[1], q)
    v1w, v1v = _field(0.0, xi0[0], phi[0], qd)     # its rate
    v2w, v2v = _field(0.0, xi0[1], phi[1], qd)
    a1w, a1v = _field(0.0, xi0[0], phi[0], qdd)    # its acceleration
    a2w, a2v = _field(0.0, xi0[1], phi[1], qdd)
    # Omega = h/2 (x1 + x2) + k ad(x1) x2 and its time derivatives (the product rule)
    bw, bv = _ad(x1w, x1v, x2w, x2v)
    theta = _sum4(0.5 * h, x1w, 0.5 * h, x2w, k, bw, 0.0, bw)
    u = _sum4(0.5 * h, x1v, 0.5 * h, x2v, k, bv, 0.0, bv)
    b1w, b1v = _ad(v1w, v1v, x2w, x2v)
    b2w, b2v = _ad(x1w, x1v, v2w, v2v)
    th_d = _sum4(0.5 * h, v1w, 0.5 * h, v2w, k, b1w, k, b2w)
    u_d = _sum4(0.5 * h, v1v, 0.5 * h, v2v, k, b1v, k, b2v)
    c1w, c1v = _ad(a1w, a1v, x2w, x2v)
    c2w, c2v = _ad(x1w, x1v, a2w, a2v)
    c3w, c3v = _ad(v1w, v1v, v2w, v2v)
    th_dd = _add(_sum4(0.5 * h, a1w, 0.5 * h, a2w, k, c1w, k, c2w), _scale(2.0 * k, c3w))
    u_dd = _add(_sum4(0.5 * h, a1v, 0.5 * h, a2v, k, c1v, k, c2v), _scale(2.0 * k, c3v))
    # exp(Omega^) = (exp(theta^), J_l(theta) u)
    th2 = _dot(theta, theta)
    coefficients = jacobian_coefficients(th2)
    b, c = coefficients[0], coefficients[1]
    sa, sb = exp_coefficients(th2)
    hat = t_hat(theta)
    r_step = t_plus_diag(t_lin9(sa, hat, sb, t_mm(hat, hat)), 1.0)
    t = _apply_jacobian(b, c, theta, u)
    dj_u, d2j_u = jacobian_derivatives_applied(coefficients, theta, th_d, th_dd, u)
    dj_ud, _ = jacobian_derivatives_applied(coefficients, theta, th_d, th_dd, u_d)
    t_d = _add(dj_u, _apply_jacobian(b, c, theta, u_d))
    t_dd = _sum4(1.0, d2j_u, 2.0, dj_ud, 1.0, _apply_jacobian(b, c, theta, u_dd), 0.0, t)
    # the section's rotation rate: d/dt exp(theta^) = (J_l theta')^ exp(theta^)
    jth_d = _apply_jacobian(b, c, theta, th_d)
    dj_thd, _ = jacobian_derivatives_applied(coefficients, theta, th_d, th_dd, th_d)
    rt = t_mv(ra, t)
    r_jthd = t_mv(ra, jth_d)
    r_td = t_mv(ra, t_d)
    wxrt = t_cross(w_a, rt)
    p_n = _add(p_a, rt)
    w_n = _add(w_a, r_jthd)
    v_n = _sum4(1.0, v_a, 1.0, wxrt, 1.0, r_td, 0.0, v_a)
    al_n = _sum4(1.0, al_a, 1.0, t_cross(w_a, r_jthd), 1.0,
                 t_mv(ra, _add(dj_thd, _apply_jacobian(b, c, theta, th_dd))), 0.0, al_a)
    ac_n = _add(_sum4(1.0, ac_a, 1.0, t_cross(al_a, rt), 1.0, t_cross(w_a, wxrt), 2.0,
                      t_cross(w_a, r_td)), t_mv(ra, t_dd))
    return t_mm(ra, r_step), p_n, w_n, v_n, al_n, ac_n


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _store(rot, pos, omega, vel, alpha, acc, section):
    """A station's values (R, p, omega, p', alpha, p'') into its rows of rod_kinematics'
    outputs."""
    r = section[0]
    for i in range(3):
        for j in range(3):
            rot[i, j] = r[3 * i + j]
    _put(pos, section[1])
    _put(omega, section[2])
    _put(vel, section[3])
    _put(alpha, section[4])
    _put(acc, section[5])


@kernel(entry=True)
def rod_relations(steps, xi0, phi, weights, mu, section, stiffness, damping, gravity, rot, w,
                  wd, q, qd, qdd, a_i, m_i, q_i, out, residual):
    """The rod's exact relations in a given state, in the transfer's form (docs/strain_rod.md,
    "Its relations in DT-TMM's form"): the stations' kinematics (rod_kinematics), their
    Jacobians (rod_jacobians), then rod_sums.  Returns rod_sums' end section."""
    n = steps.shape[0] + 1
    kin = station_arrays(n)
    rod_kinematics(steps, xi0, phi, q, qd, qdd, *kin)
    jp, jr = rod_jacobians(steps, xi0, phi, q)
    return rod_sums(kin, jp, jr, weights, mu, section, stiffness, damping, gravity, rot, w, wd,
                    q, qd, a_i, m_i, q_i, out, residual)


@kernel(entry=True)
def rod_jacobians(steps, xi0, phi, q):
    """(Jp, Jr) (stations, n_q, 3): each station's velocity and angular velocity in the input
    frame for a unit rate of each strain coordinate, the velocity half of rod_kinematics at
    q' = e_j (the velocities are linear in q' at a given q), every column in one pass over the
    stations: the step's pose (Omega, exp, J_l) once, then per column Omega' from the basis'
    column j, t' = DJ_l[theta'] u + J_l u', and
        Jp_{a+1} = Jp_a + Jr_a x (R_a t) + R_a t',     Jr_{a+1} = Jr_a + R_a J_l theta'."""
    n = steps.shape[0]
    nq = q.shape[0]
    jp, jr = np.zeros((n + 1, nq, 3)), np.zeros((n + 1, nq, 3))
    ra = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    for a in range(n):
        h = steps[a]
        k = SQRT3_12 * h * h
        x1w, x1v = _field(1.0, xi0[a, 0], phi[a, 0], q)
        x2w, x2v = _field(1.0, xi0[a, 1], phi[a, 1], q)
        bw, bv = _ad(x1w, x1v, x2w, x2v)
        theta = _sum4(0.5 * h, x1w, 0.5 * h, x2w, k, bw, 0.0, bw)
        u = _sum4(0.5 * h, x1v, 0.5 * h, x2v, k, bv, 0.0, bv)
        th2 = _dot(theta, theta)
        coefficients = jacobian_coefficients(th2)
        b, c = coefficients[0], coefficients[1]
        rt = t_mv(ra, _apply_jacobian(b, c, theta, u))
        p1, p2 = phi[a, 0], phi[a, 1]
        for j in range(nq):
            v1w, v1v = (p1[0, j], p1[1, j], p1[2, j]), (p1[3, j], p1[4, j], p1[5, j])
            v2w, v2v = (p2[0, j], p2[1, j], p2[2, j]), (p2[3, j], p2[4, j], p2[5, j])
            b1w, b1v = _ad(v1w, v1v, x2w, x2v)
            b2w, b2v = _ad(x1w, x1v, v2w, v2v)
            th_d = _sum4(0.5 * h, v1w, 0.5 * h, v2w, k, b1w, k, b2w)
            u_d = _sum4(0.5 * h, v1v, 0.5 * h, v2v, k, b1v, k, b2v)
            dj_u, _ = jacobian_derivatives_applied(coefficients, theta, th_d, th_d, u)
            t_d = t_mv(ra, _add(dj_u, _apply_jacobian(b, c, theta, u_d)))
            w_a = t_of_vec(jr[a, j])
            v_n = _sum4(1.0, t_of_vec(jp[a, j]), 1.0, t_cross(w_a, rt), 1.0, t_d, 0.0, t_d)
            w_n = _add(w_a, t_mv(ra, _apply_jacobian(b, c, theta, th_d)))
            _put(jp[a + 1, j], v_n)
            _put(jr[a + 1, j], w_n)
        sa, sb = exp_coefficients(th2)
        hat = t_hat(theta)
        ra = t_mm(ra, t_plus_diag(t_lin9(sa, hat, sb, t_mm(hat, hat)), 1.0))
    return jp, jr


@kernel
def rod_sums(kin, jp, jr, weights, mu, section, stiffness, damping, gravity, rot, w, wd, q, qd,
             a_i, m_i, q_i, out, residual):
    """The rod's relations from its stations' kinematics kin = (rotations, centres, angular
    velocities, velocities, angular accelerations, accelerations) in the input frame
    (rod_kinematics) and their Jacobians (rod_jacobians): out = [a_O, w' (the frame's), m_O,
    q_O] from the input's a_I, m_I, q_I and the frame's motion (rotation A, w, w'), and
    residual = the strain rows' left minus right sides, with the end loads' generalized forces.
    With the stations' accelerations a_i = a_I + w' x rho_i + w x (w x rho_i) + 2 w x A p'_i +
    A p''_i and their sections' alpha_i = w' + w x A omega_i + A alpha_rel,i, each station's
    load (gravity minus inertia) F_i = f (g - a_i) and couple N_i = -(Theta alpha_i + W_i x
    Theta W_i) (f = mu w_i, Theta = w_i A R_i diag(section) R_i^T A^T, W_i = w + A omega_i):
        q_O = q_I + sum F_i,   m_O = m_I - rho_L x q_O + sum (rho_i x F_i + N_i)
        r_j = -sum (A Jp_i,j . F_i + A Jr_i,j . N_i) + A Jp_L,j . q_O + A Jr_L,j . m_O
              + (K (q + damping q'))_j
    Returns the end section's rotation A R_L and angular acceleration w' + w x A omega_L +
    A alpha_rel,L (world; a weld at the output reads them: _rod_evaluate).
    The sums run in the input frame (each vector v as A^T v), the couples in each section's
    own (R_i^T A^T v, where Theta is w_i diag(section)); the end's values are turned to world.
    On values (mat3's 3-tuples): it allocates two (stations, 3) arrays and its two returns."""
    rot_s, pos, om, vel, al, acc = kin
    n = pos.shape[0]
    nq = q.shape[0]
    ra = t_of_mat(rot)
    a_in, wd_in = _mtv(ra, a_i), _mtv(ra, wd)
    w_in, g_in = _mtv(ra, w), _mtv(ra, gravity)
    loc_f = np.zeros((n, 3))        # A^T F_i
    loc_n = np.zeros((n, 3))        # A^T N_i
    q_sum, m_sum = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    for i in range(n):
        if weights[i] == 0.0:
            continue
        f = mu * weights[i]
        rho = t_of_vec(pos[i])
        wxrho = t_cross(w_in, rho)
        a_st = _add(_sum4(1.0, a_in, 1.0, t_cross(wd_in, rho), 1.0, t_cross(w_in, wxrho), 2.0,
                          t_cross(w_in, t_of_vec(vel[i]))), t_of_vec(acc[i]))
        force = _sum4(f, g_in, -f, a_st, 0.0, a_st, 0.0, a_st)
        om_i = t_of_vec(om[i])
        big_w = _add(w_in, om_i)
        al_st = _add(_add(wd_in, t_cross(w_in, om_i)), t_of_vec(al[i]))
        ri = t_of_mat(rot_s[i])
        w_sec, al_sec = _mtv(ri, big_w), _mtv(ri, al_st)
        th_w = (section[0] * w_sec[0], section[1] * w_sec[1], section[2] * w_sec[2])
        th_al = (section[0] * al_sec[0], section[1] * al_sec[1], section[2] * al_sec[2])
        couple = t_mv(ri, _scale(-weights[i], _add(th_al, t_cross(w_sec, th_w))))
        _put(loc_f[i], force)
        _put(loc_n[i], couple)
        q_sum = _add(q_sum, force)
        m_sum = _sum4(1.0, m_sum, 1.0, t_cross(rho, force), 1.0, couple, 0.0, couple)
    rho_l = t_of_vec(pos[n - 1])
    q_loc = _add(_mtv(ra, q_i), q_sum)
    m_loc = _sum4(1.0, _mtv(ra, m_i), 1.0, m_sum, -1.0, t_cross(rho_l, q_loc), 0.0, m_sum)
    a_rel = _add(_sum4(1.0, t_cross(wd_in, rho_l), 1.0, t_cross(w_in, t_cross(w_in, rho_l)),
                       2.0, t_cross(w_in, t_of_vec(vel[n - 1])), 0.0, rho_l),
                 t_of_vec(acc[n - 1]))
    a_o = _add(t_of_vec(a_i), t_mv(ra, a_rel))
    q_o, m_o = t_mv(ra, q_loc), t_mv(ra, m_loc)
    for i in range(3):
        out[i] = a_o[i]
        out[3 + i] = wd[i]
        out[6 + i] = m_o[i]
        out[9 + i] = q_o[i]
    end_rotation = np.empty((3, 3))
    end = t_mm(ra, t_of_mat(rot_s[n - 1]))
    om_l = t_of_vec(om[n - 1])
    end_al = t_mv(ra, _add(_add(wd_in, t_cross(w_in, om_l)), t_of_vec(al[n - 1])))
    end_alpha = np.empty(3)
    for i in range(3):
        end_alpha[i] = end_al[i]
        for j in range(3):
            end_rotation[i, j] = end[3 * i + j]
    # the strain rows by virtual work, a Jacobian column (a unit rate's velocities) at a time
    for j in range(nq):
        r = stiffness[j] * (q[j] + damping * qd[j])
        for i in range(n):
            if weights[i] != 0.0:
                for c in range(3):
                    r -= jp[i, j, c] * loc_f[i, c] + jr[i, j, c] * loc_n[i, c]
        for c in range(3):
            r += jp[n - 1, j, c] * q_loc[c] + jr[n - 1, j, c] * m_loc[c]
        residual[j] = r
    return end_rotation, end_alpha


@kernel
def _rod_state(x, start, rot_n, phi_star, wd_star, c1, c3, w3, w_n, w1e, w3e, q_n, qd_n):
    """The rod's state for the step's unknowns x = [a_I, w', m_I, q_I, q''] (the integrator's
    relations, docs/solver.md): at the consistent start the rotation, rates and strains are
    given; in a step phi = phi* + (w' - w'*)/c1, w = c3 phi + w3, A = exp(phi^) A_n,
    q = (q'' - w1e)/c1, q' = c3 q + w3e."""
    nq = q_n.shape[0]
    if start:
        return rot_n.copy(), w_n.copy(), q_n.copy(), qd_n.copy()
    phi = phi_star + (x[3:6] - wd_star) / c1
    e = np.empty((3, 3))
    expm_so3(phi, e)
    q = (x[12:12 + nq] - w1e) / c1
    return matmul(e, rot_n), c3 * phi + w3, q, c3 * q + w3e


@kernel
def _rod_evaluate(tables, outboard, gravity, start, c1, kin, jp, jr, rot, w, q, qd, x, out,
                  residual):
    """rod_sums at the step's unknowns x = [a_I, w', m_I, q_I, q''] in the state (A, w, q, q')
    they give (_rod_state) with its stations' kinematics and Jacobians; with a fixed hinge at
    the output (outboard = (welded, R_rel, the outboard's rotation at t_n, w1)) the output's
    rotation slot is the outboard body's angular acceleration, as the modal beam's
    (kernels/transfers/beam.py::_evaluate): at the start the end section's, w' + w x A omega_L +
    A alpha_L; in a step c1 phi_out + w1 with exp(phi_out^) A_out,n = A R_L R_rel."""
    _, _, _, weights, mu, section, stiffness, damping = tables
    welded, r_rel, rot_out_n, w1_out = outboard
    end_rotation, end_alpha = rod_sums(
        kin, jp, jr, weights, mu, section, stiffness, damping, gravity, rot, w, x[3:6].copy(),
        q, qd, x[0:3].copy(), x[6:9].copy(), x[9:12].copy(), out, residual)
    if welded and start:
        put1(out[3:6], end_alpha)
    elif welded:
        phi_out = np.empty(3)
        log_so3(matmul(matmul(end_rotation, r_rel), rot_out_n.T), phi_out)
        put1(out[3:6], c1 * phi_out + w1_out)


@kernel
def _affine_columns(pos, jp, jr, weights, mu, rot, d_o, d_r):
    """The relations' columns in a_I (0:3), m_I (6:9) and q_I (9:12), in which they are affine
    (rod_sums; docs/strain_rod.md, "Its transfer"), in closed form: with the mass M = sum f_i,
    c = sum f_i rho_i and rho_L in the input frame (f_i = mu w_i), d = A^T delta,
      a_I: a_O += delta, q_O -= M delta, m_O += A (M rho_L - c) x d,
           r_j += (sum f_i Jp_i,j - M Jp_L,j + Jr_L,j x (M rho_L - c)) . d
      m_I: m_O += delta, r_j += Jr_L,j . d
      q_I: q_O += delta, m_O -= A rho_L x d, r_j += (Jp_L,j - Jr_L,j x rho_L) . d
    (the rotation slot, w' or a weld's, does not move with them)."""
    n = pos.shape[0]
    nq = jp.shape[1]
    ra = t_of_mat(rot)
    mass, c = 0.0, (0.0, 0.0, 0.0)
    for i in range(n):
        f = mu * weights[i]
        mass += f
        c = _sum4(1.0, c, f, t_of_vec(pos[i]), 0.0, c, 0.0, c)
    rho_l = t_of_vec(pos[n - 1])
    e = _sum4(mass, rho_l, -1.0, c, 0.0, c, 0.0, c)
    for r in range(12):
        for col in (0, 1, 2, 6, 7, 8, 9, 10, 11):
            d_o[r, col] = 0.0
    for k in range(3):
        unit = (1.0 if k == 0 else 0.0, 1.0 if k == 1 else 0.0, 1.0 if k == 2 else 0.0)
        d = _mtv(ra, unit)                      # A^T e_k
        dm_a = t_mv(ra, t_cross(e, d))          # m_O's column in a_I
        dm_q = t_mv(ra, t_cross(rho_l, d))      # minus m_O's column in q_I
        d_o[k, k] = 1.0
        d_o[9 + k, k] = -mass
        d_o[6 + k, 6 + k] = 1.0
        d_o[9 + k, 9 + k] = 1.0
        for i in range(3):
            d_o[6 + i, k] = dm_a[i]
            d_o[6 + i, 9 + k] = -dm_q[i]
    for j in range(nq):
        g = (0.0, 0.0, 0.0)
        for i in range(n):
            g = _sum4(1.0, g, mu * weights[i], t_of_vec(jp[i, j]), 0.0, g, 0.0, g)
        jp_l, jr_l = t_of_vec(jp[n - 1, j]), t_of_vec(jr[n - 1, j])
        g_a = t_mv(ra, _sum4(1.0, g, -mass, jp_l, 1.0, t_cross(jr_l, e), 0.0, g))
        g_m = t_mv(ra, jr_l)
        g_q = t_mv(ra, _sum4(1.0, jp_l, -1.0, t_cross(jr_l, rho_l), 0.0, jp_l, 0.0, jp_l))
        for k in range(3):
            d_r[j, k] = g_a[k]
            d_r[j, 6 + k] = g_m[k]
            d_r[j, 9 + k] = g_q[k]


@kernel(entry=True)
def rod_transfer(tables, outboard, gravity, start, rot_n, phi_star, wd_star, c1, c3, w3, w_n,
                 w1e, w3e, q_n, qd_n, z_star, qdd_star, u, q_map):
    """Fill u (12 x 13) with z_O = u [z_I; 1] (angular-acceleration slots) and q_map (n_q x 13)
    with q'' = q_map [z_I; 1], the rod's relations (rod_sums) linearized about
    (z_star, qdd_star), as the modal beam's beam_transfer does (docs/strain_rod.md, "Its
    transfer"): the relations' columns in x = [a_I, w', m_I, q_I, q''] by forward differences
    (exact for a_I, m_I, q_I, in which they are affine; w' and q'' move the state by 1/c1 of
    their step, steps 1e-3 (1 + |x|)), the strain rows solved inside the element:
        q'' - q''* = -D_rq^-1 (r0 + D_rz (z - z*)),   z_O = o0 + D_oz (z - z*) + D_oq (q'' - q''*)
    The stations' kinematics and Jacobians run once at the guess and once per q'' column: a_I,
    m_I, q_I and w' leave the rod's own motion as it is (only the frame's sums change).  (Keeping
    the guess's Jacobians in the q'' columns too, their change with q left out, is ~2x faster
    per call but 1e-3 off the linearization in tests/test_strain_rod.py: the iterations would
    converge at that rate instead of quadratically.)
    tables = (steps, xi0, phi, weights, mu, section, stiffness, damping) (rod_sums);
    outboard = (welded, R_rel, the outboard's rotation at t_n, w1) (_rod_evaluate).  z_star's
    rotation slots are not read (the guess there is wd_star).  start: the consistent-start
    solve (rotation, rates and strains given, w' and q'' free)."""
    steps, xi0, phi = tables[0], tables[1], tables[2]
    n = steps.shape[0] + 1
    nq = qdd_star.shape[0]
    nx = 12 + nq
    x0 = np.empty(nx)
    put1(x0[:12], z_star)
    put1(x0[3:6], wd_star)
    put1(x0[12:], qdd_star)
    rot, w, q, qd = _rod_state(x0, start, rot_n, phi_star, wd_star, c1, c3, w3, w_n, w1e, w3e,
                               q_n, qd_n)
    kin = station_arrays(n)
    rod_kinematics(steps, xi0, phi, q, qd, x0[12:].copy(), *kin)
    jp, jr = rod_jacobians(steps, xi0, phi, q)
    o0 = np.empty(12)
    r0 = np.empty(nq)
    _rod_evaluate(tables, outboard, gravity, start, c1, kin, jp, jr, rot, w, q, qd, x0, o0, r0)
    d_o = np.empty((12, nx))
    d_r = np.empty((nq, nx))
    o1 = np.empty(12)
    r1 = np.empty(nq)
    kin_j = station_arrays(n)
    _affine_columns(kin[1], jp, jr, tables[3], tables[4], rot, d_o, d_r)
    for c in range(3 + nq):         # the w' and q'' columns (a_I, m_I, q_I: _affine_columns)
        j = 3 + c if c < 3 else 9 + c
        h = 1e-3 * (1.0 + abs(x0[j]))
        x = x0.copy()
        x[j] += h
        rot_j, w_j, q_j, qd_j = _rod_state(x, start, rot_n, phi_star, wd_star, c1, c3, w3, w_n,
                                           w1e, w3e, q_n, qd_n)
        if j < 12:          # w': the rod's own motion as at the guess
            _rod_evaluate(tables, outboard, gravity, start, c1, kin, jp, jr, rot_j, w_j, q, qd,
                          x, o1, r1)
        else:
            rod_kinematics(steps, xi0, phi, q_j, qd_j, x[12:].copy(), *kin_j)
            jp_j, jr_j = rod_jacobians(steps, xi0, phi, q_j)
            _rod_evaluate(tables, outboard, gravity, start, c1, kin_j, jp_j, jr_j, rot, w, q_j,
                          qd_j, x, o1, r1)
        put1(d_o[:, j], (o1 - o0) / h)
        put1(d_r[:, j], (r1 - r0) / h)
    rhs = np.empty((nq, 13))
    put2(rhs[:, :12], d_r[:, :12])
    put1(rhs[:, 12], r0)
    solved = np.linalg.solve(np.ascontiguousarray(d_r[:, 12:]), rhs)
    z0 = x0[:12]
    for i in range(nq):
        for j in range(12):
            q_map[i, j] = -solved[i, j]
        q_map[i, 12] = qdd_star[i] - solved[i, 12] - dot(q_map[i, :12], z0)
    d_oq = d_o[:, 12:]
    put2(u[:, :12], d_o[:, :12] + matmul(d_oq, q_map[:, :12]))
    shift = matvec(d_oq, solved[:, 12])
    for i in range(12):
        u[i, 12] = o0[i] - shift[i] - dot(u[i, :12], z0)


@kernel
def rod_end_frame(steps, xi0, phi, rot, w, wd, q, qd, qdd, rest, rot_out, w_out, wd_out):
    """The frame welded to a rod's end section (rest: the weld's R0) from the rod's frame (A,
    w, w') and its strain coordinates, rates and accelerations (rod_end: R_L, omega_L, alpha_L
    in the input frame): A_O = A R_L R0, w_O = w + A omega_L, w_O' = w' + w x (A omega_L)
    + A alpha_L (as the modal beam's end section,
    kernels/stepping/generalized_alpha.py::_end_section_frame).  Allocates nothing."""
    r_l, _, om, _, al, _ = rod_end(steps, xi0, phi, q, qd, qdd)
    ra = t_of_mat(rot)
    end = t_mm(t_mm(ra, r_l), t_of_mat(rest))
    a_om = t_mv(ra, om)
    alpha = _add(_add(t_of_vec(wd), t_cross(t_of_vec(w), a_om)), t_mv(ra, al))
    for i in range(3):
        w_out[i] = w[i] + a_om[i]
        wd_out[i] = alpha[i]
        for j in range(3):
            rot_out[i, j] = end[3 * i + j]


@kernel(entry=True)
def rod_end_points(steps, xi0, phi, q, qd):
    """(p_L, p_L') (T, 3): a rod's end point and its velocity relative to its frame, in the
    input frame, for T states of its strain coordinates and rates q, qd (T, n_q)."""
    m = q.shape[0]
    p_end, v_end = np.zeros((m, 3)), np.zeros((m, 3))
    for t in range(m):
        q_t, qd_t = np.ascontiguousarray(q[t]), np.ascontiguousarray(qd[t])
        _, p, _, v, _, _ = rod_end(steps, xi0, phi, q_t, qd_t, qd_t)   # (accelerations unused)
        _put(p_end[t], p)
        _put(v_end[t], v)
    return p_end, v_end


@njit(cache=True, inline='always', fastmath=CONTRACT)
def rod_tables_of(params, k):
    """Strain rod k's tables as the kernels take them, from the flat model's (params; its
    rod_* tables, run_tables.rod_tables): (steps, xi0, phi, weights, mu, section, stiffness,
    damping)."""
    r = model_tables.rod_row(params)[k]
    mu_damping = model_tables.rod_mu_damping(params)
    return (model_tables.rod_steps(params)[r], model_tables.rod_xi0(params)[r],
            model_tables.rod_phi(params)[r], model_tables.rod_weights(params)[r],
            mu_damping[r, 0], model_tables.rod_section(params)[r],
            model_tables.rod_stiffness(params)[r], mu_damping[r, 1])
