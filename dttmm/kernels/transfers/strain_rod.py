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

from .. import CONTRACT
from ..algebra.so3 import expm_so3, left_jacobian, log_so3

SQRT3_12 = np.sqrt(3.0) / 12.0
# the Magnus step's two Gauss points, as fractions of the step (1/2 -+ sqrt(3)/6)
MAGNUS_POINTS = (0.5 - np.sqrt(3.0) / 6.0, 0.5 + np.sqrt(3.0) / 6.0)


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


@njit(cache=True, fastmath=CONTRACT)
def _poly(coefficients, x):
    s = 0.0
    for k in range(len(coefficients) - 1, -1, -1):
        s = s * x + coefficients[k]
    return s


@njit(cache=True, fastmath=CONTRACT)
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


@njit(cache=True, fastmath=CONTRACT)
def jacobian_derivatives_applied(theta, d, dd, u):
    """(DJ_l(theta)[d] u, DJ_l(theta)[dd] u + D2J_l(theta)[d, d] u): the first and second
    derivatives of t(s) = J_l(theta(s)) u along theta(s) = theta + s d + s^2/2 dd at s = 0,
    u fixed.  With J_l u = u + B theta x u + C theta x (theta x u), B(s) = b(|theta(s)|), whose
    derivatives are B' = beta (theta . d), B'' = beta1 (theta . d)^2 + beta (|d|^2 + theta . dd)
    (C's with gamma, gamma1)."""
    th2 = theta @ theta
    b, c, beta, gamma, beta1, gamma1 = jacobian_coefficients(th2)
    td = theta @ d
    dB, dC = beta * td, gamma * td
    ddB = beta1 * td * td + beta * (d @ d + theta @ dd)
    ddC = gamma1 * td * td + gamma * (d @ d + theta @ dd)
    txu = np.cross(theta, u)
    dxu = np.cross(d, u)
    ddxu = np.cross(dd, u)
    txtxu = np.cross(theta, txu)
    first = dB * txu + b * dxu + dC * txtxu + c * (np.cross(d, txu) + np.cross(theta, dxu))
    second = (ddB * txu + 2.0 * dB * dxu + b * ddxu + ddC * txtxu
              + 2.0 * dC * (np.cross(d, txu) + np.cross(theta, dxu))
              + c * (2.0 * np.cross(d, dxu) + np.cross(dd, txu) + np.cross(theta, ddxu)))
    return first, second


@njit(cache=True, fastmath=CONTRACT)
def _bracket(x, y):
    """ad(x) y = [x_w x y_w; x_w x y_v + x_v x y_w] (se(3), [angular; linear])."""
    out = np.empty(6)
    out[:3] = np.cross(x[:3], y[:3])
    out[3:] = np.cross(x[:3], y[3:]) + np.cross(x[3:], y[:3])
    return out


@njit(cache=True, fastmath=CONTRACT)
def station_arrays(n):
    """The outputs of rod_kinematics for n stations: rotations (n, 3, 3), centres, angular
    velocities, velocities, angular accelerations, accelerations (n, 3 each), zeroed."""
    return (np.zeros((n, 3, 3)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)),
            np.zeros((n, 3)), np.zeros((n, 3)))


@njit(cache=True, fastmath=CONTRACT)
def rod_kinematics(steps, xi0, phi, q, qd, qdd, rot, pos, omega, vel, alpha, acc):
    """The stations' poses, velocities and accelerations in the input-section frame (the module's
    docstring).  steps[a] is the a-th step's length h; xi0[a, i] (6) and phi[a, i] (6 x nq) the
    reference strain and the strain basis at its Gauss point i (MAGNUS_POINTS).  Writes, for the
    stations 0 .. len(steps) (station 0 the input section: identity, zeros), rot (3 x 3), pos,
    omega, vel, alpha, acc (3 each)."""
    n = steps.shape[0]
    rot[0] = np.eye(3)
    pos[0] = 0.0
    omega[0] = 0.0
    vel[0] = 0.0
    alpha[0] = 0.0
    acc[0] = 0.0
    r_step = np.empty((3, 3))
    jl = np.empty((3, 3))
    for a in range(n):
        h = steps[a]
        x1 = xi0[a, 0] + phi[a, 0] @ q
        x2 = xi0[a, 1] + phi[a, 1] @ q
        v1, v2 = phi[a, 0] @ qd, phi[a, 1] @ qd
        w1, w2 = phi[a, 0] @ qdd, phi[a, 1] @ qdd
        k = SQRT3_12 * h * h
        big = 0.5 * h * (x1 + x2) + k * _bracket(x1, x2)
        big_d = 0.5 * h * (v1 + v2) + k * (_bracket(v1, x2) + _bracket(x1, v2))
        big_dd = (0.5 * h * (w1 + w2)
                  + k * (_bracket(w1, x2) + 2.0 * _bracket(v1, v2) + _bracket(x1, w2)))
        theta, u = big[:3].copy(), big[3:].copy()
        th_d, u_d = big_d[:3].copy(), big_d[3:].copy()
        th_dd, u_dd = big_dd[:3].copy(), big_dd[3:].copy()
        expm_so3(theta, r_step)
        left_jacobian(theta, jl)
        t = jl @ u
        dj_u, d2j_u = jacobian_derivatives_applied(theta, th_d, th_dd, u)
        dj_ud, _ = jacobian_derivatives_applied(theta, th_d, th_dd, u_d)
        t_d = dj_u + jl @ u_d
        t_dd = d2j_u + 2.0 * dj_ud + jl @ u_dd          # (d2j_u holds DJ_l[theta''] u)
        # the section's rotation rate: d/dt exp(theta^) = (J_l theta')^ exp(theta^)
        jth_d = jl @ th_d
        dj_thd, _ = jacobian_derivatives_applied(theta, th_d, th_dd, th_d)
        ra = rot[a]
        rt = ra @ t
        r_jthd = ra @ jth_d
        w_a, al_a = omega[a], alpha[a]
        rot[a + 1] = ra @ r_step
        pos[a + 1] = pos[a] + rt
        omega[a + 1] = w_a + r_jthd
        vel[a + 1] = vel[a] + np.cross(w_a, rt) + ra @ t_d
        alpha[a + 1] = al_a + np.cross(w_a, r_jthd) + ra @ (dj_thd + jl @ th_dd)
        acc[a + 1] = (acc[a] + np.cross(al_a, rt) + np.cross(w_a, np.cross(w_a, rt))
                      + 2.0 * np.cross(w_a, ra @ t_d) + ra @ t_dd)


@njit(cache=True, fastmath=CONTRACT)
def rod_relations(steps, xi0, phi, weights, mu, section, stiffness, damping, gravity, rot, w,
                  wd, q, qd, qdd, a_i, m_i, q_i, out, residual):
    """The rod's exact relations in a given state, in the transfer's form (docs/strain_rod.md,
    "Its relations in DT-TMM's form"): out = [a_O, w' (the frame's), m_O, q_O] from the input's
    a_I, m_I, q_I and the frame's motion (rotation A, w, w'), and residual = the strain rows'
    left minus right sides, with the end loads' generalized forces.  With the stations'
    accelerations a_i = a_I + w' x rho_i + w x (w x rho_i) + 2 w x A p'_i + A p''_i and their
    sections' alpha_i = w' + w x A omega_i + A alpha_rel,i, each station's load (gravity minus
    inertia) F_i = f (g - a_i) and couple N_i = -(Theta alpha_i + W_i x Theta W_i)
    (f = mu w_i, Theta = w_i A R_i diag(section) R_i^T A^T, W_i = w + A omega_i):
        q_O = q_I + sum F_i,   m_O = m_I - rho_L x q_O + sum (rho_i x F_i + N_i)
        r_j = -sum (A Jp_i,j . F_i + A Jr_i,j . N_i) + A Jp_L,j . q_O + A Jr_L,j . m_O
              + (K (q + damping q'))_j
    (Jp, Jr: the stations' Jacobians, a unit rate's velocities: rod_kinematics).  Returns the
    end section's rotation A R_L and angular acceleration w' + w x A omega_L + A alpha_rel,L
    (world; a weld at the output reads them: _rod_evaluate).  It allocates its scratch."""
    n = steps.shape[0] + 1
    nq = q.shape[0]
    rot_s, pos, om, vel, al, acc = station_arrays(n)
    rod_kinematics(steps, xi0, phi, q, qd, qdd, rot_s, pos, om, vel, al, acc)
    forces = np.zeros((n, 3))
    couples = np.zeros((n, 3))
    q_o = q_i.copy()
    m_o = m_i.copy()
    for i in range(n):
        rho = rot @ pos[i]
        if weights[i] != 0.0:
            f = mu * weights[i]
            a_st = (a_i + np.cross(wd, rho) + np.cross(w, np.cross(w, rho))
                    + 2.0 * np.cross(w, rot @ vel[i]) + rot @ acc[i])
            rs = rot @ rot_s[i]
            theta = weights[i] * (rs @ np.diag(section) @ rs.T)
            big_w = w + rot @ om[i]
            al_st = wd + np.cross(w, rot @ om[i]) + rot @ al[i]
            forces[i] = f * (gravity - a_st)
            couples[i] = -(theta @ al_st + np.cross(big_w, theta @ big_w))
            q_o += forces[i]
            m_o += np.cross(rho, forces[i]) + couples[i]
    rho_l = rot @ pos[n - 1]
    m_o -= np.cross(rho_l, q_o)
    a_o = (a_i + np.cross(wd, rho_l) + np.cross(w, np.cross(w, rho_l))
           + 2.0 * np.cross(w, rot @ vel[n - 1]) + rot @ acc[n - 1])
    out[0:3] = a_o
    out[3:6] = wd
    out[6:9] = m_o
    out[9:12] = q_o
    end_rotation = rot @ rot_s[n - 1]
    end_alpha = wd + np.cross(w, rot @ om[n - 1]) + rot @ al[n - 1]
    # the strain rows by virtual work, a Jacobian column (a unit rate's velocities) at a time
    zero = np.zeros(nq)
    r2, p2, o2, v2, a2, c2 = station_arrays(n)
    for j in range(nq):
        unit = np.zeros(nq)
        unit[j] = 1.0
        rod_kinematics(steps, xi0, phi, q, unit, zero, r2, p2, o2, v2, a2, c2)
        r = stiffness[j] * (q[j] + damping * qd[j])
        for i in range(n):
            if weights[i] != 0.0:
                r -= (rot @ v2[i]) @ forces[i] + (rot @ o2[i]) @ couples[i]
        r += (rot @ v2[n - 1]) @ q_o + (rot @ o2[n - 1]) @ m_o
        residual[j] = r
    return end_rotation, end_alpha


@njit(cache=True, fastmath=CONTRACT)
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
    return e @ rot_n, c3 * phi + w3, q, c3 * q + w3e


@njit(cache=True, fastmath=CONTRACT)
def _rod_evaluate(tables, outboard, gravity, start, rot_n, phi_star, wd_star, c1, c3, w3, w_n,
                  w1e, w3e, q_n, qd_n, x, out, residual):
    """rod_relations with the state from the step's unknowns x (_rod_state); with a fixed hinge
    at the output (outboard = (welded, R_rel, the outboard's rotation at t_n, w1)) the output's
    rotation slot is the outboard body's angular acceleration, as the modal beam's
    (kernels/transfers/beam.py::_evaluate): at the start the end section's, w' + w x A omega_L +
    A alpha_L; in a step c1 phi_out + w1 with exp(phi_out^) A_out,n = A R_L R_rel."""
    steps, xi0, phi, weights, mu, section, stiffness, damping = tables
    welded, r_rel, rot_out_n, w1_out = outboard
    rot, w, q, qd = _rod_state(x, start, rot_n, phi_star, wd_star, c1, c3, w3, w_n, w1e, w3e,
                               q_n, qd_n)
    end_rotation, end_alpha = rod_relations(
        steps, xi0, phi, weights, mu, section, stiffness, damping, gravity, rot, w,
        x[3:6].copy(), q, qd, x[12:].copy(), x[0:3].copy(), x[6:9].copy(), x[9:12].copy(), out,
        residual)
    if welded and start:
        out[3:6] = end_alpha
    elif welded:
        phi_out = np.empty(3)
        log_so3(end_rotation @ r_rel @ rot_out_n.T, phi_out)
        out[3:6] = c1 * phi_out + w1_out


@njit(cache=True, fastmath=CONTRACT)
def rod_transfer(tables, outboard, gravity, start, rot_n, phi_star, wd_star, c1, c3, w3, w_n,
                 w1e, w3e, q_n, qd_n, z_star, qdd_star, u, q_map):
    """Fill u (12 x 13) with z_O = u [z_I; 1] (angular-acceleration slots) and q_map (n_q x 13)
    with q'' = q_map [z_I; 1], the rod's relations (rod_relations) linearized about
    (z_star, qdd_star), as the modal beam's beam_transfer does (docs/strain_rod.md, "Its
    transfer"): the relations' columns in x = [a_I, w', m_I, q_I, q''] by forward differences
    (exact for a_I, m_I, q_I, in which they are affine; w' and q'' move the state by 1/c1 of
    their step, steps 1e-3 (1 + |x|)), the strain rows solved inside the element:
        q'' - q''* = -D_rq^-1 (r0 + D_rz (z - z*)),   z_O = o0 + D_oz (z - z*) + D_oq (q'' - q''*)
    tables = (steps, xi0, phi, weights, mu, section, stiffness, damping) (rod_relations);
    outboard = (welded, R_rel, the outboard's rotation at t_n, w1) (_rod_evaluate).  z_star's
    rotation slots are not read (the guess there is wd_star).  start: the consistent-start
    solve (rotation, rates and strains given, w' and q'' free)."""
    nq = qdd_star.shape[0]
    nx = 12 + nq
    x0 = np.empty(nx)
    x0[:12] = z_star
    x0[3:6] = wd_star
    x0[12:] = qdd_star
    o0 = np.empty(12)
    r0 = np.empty(nq)
    _rod_evaluate(tables, outboard, gravity, start, rot_n, phi_star, wd_star, c1, c3, w3, w_n,
                  w1e, w3e, q_n, qd_n, x0, o0, r0)
    d_o = np.empty((12, nx))
    d_r = np.empty((nq, nx))
    o1 = np.empty(12)
    r1 = np.empty(nq)
    for j in range(nx):
        affine = j < 3 or 6 <= j < 12
        h = (1.0 if affine else 1e-3) * (1.0 + abs(x0[j]))
        x = x0.copy()
        x[j] += h
        _rod_evaluate(tables, outboard, gravity, start, rot_n, phi_star, wd_star, c1, c3, w3,
                      w_n, w1e, w3e, q_n, qd_n, x, o1, r1)
        d_o[:, j] = (o1 - o0) / h
        d_r[:, j] = (r1 - r0) / h
    rhs = np.empty((nq, 13))
    rhs[:, :12] = d_r[:, :12]
    rhs[:, 12] = r0
    solved = np.linalg.solve(np.ascontiguousarray(d_r[:, 12:]), rhs)
    z0 = x0[:12]
    for i in range(nq):
        for j in range(12):
            q_map[i, j] = -solved[i, j]
        q_map[i, 12] = qdd_star[i] - solved[i, 12] - q_map[i, :12] @ z0
    d_oq = np.ascontiguousarray(d_o[:, 12:])
    u[:, :12] = d_o[:, :12] + d_oq @ np.ascontiguousarray(q_map[:, :12])
    shift = d_oq @ np.ascontiguousarray(solved[:, 12])
    for i in range(12):
        u[i, 12] = o0[i] - shift[i] - u[i, :12] @ z0
