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
from numba import njit

from .so3 import hat

A, PHI, M, Q = 0, 3, 6, 9   # offsets of the blocks in the 12-entry station state
CONST = 12                  # column of the affine part


@njit(cache=True)
def _kappa(w, wd, rho, dwd, dw, d_rho):
    """kappa = wd x rho + w x (w x rho) and its derivative with respect to phi, given
    d wd/d phi = dwd, d w/d phi = dw and d rho/d phi = d_rho."""
    w_rho = np.cross(w, rho)
    kappa = np.cross(wd, rho) + np.cross(w, w_rho)
    rho_h = np.empty((3, 3))
    hat(rho, rho_h)
    w_h = np.empty((3, 3))
    hat(w, w_h)
    wd_h = np.empty((3, 3))
    hat(wd, wd_h)
    wr_h = np.empty((3, 3))
    hat(w_rho, wr_h)
    d = -rho_h @ dwd + wd_h @ d_rho + (-wr_h - w_h @ rho_h) @ dw + w_h @ (w_h @ d_rho)
    return kappa, d


@njit(cache=True)
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
    """
    mass = p[0]
    l_ic = p[1:4]
    l_io = p[4:7]
    j_body = p[7:16].reshape((3, 3))
    a_i = z_star[A:A + 3]
    phi = z_star[PHI:PHI + 3]
    m_i = z_star[M:M + 3]
    q_i = z_star[Q:Q + 3]

    rho = a_star @ l_io
    rho_c = a_star @ l_ic
    rho_h = np.empty((3, 3))
    hat(rho, rho_h)
    rhoc_h = np.empty((3, 3))
    hat(rho_c, rhoc_h)
    d_rho = -rho_h @ lam          # d(A l_IO)/d phi
    d_rhoc = -rhoc_h @ lam        # d(A l_IC)/d phi
    kap_o, dkap_o = _kappa(w, wd, rho, dwd, dw, d_rho)
    kap_c, dkap_c = _kappa(w, wd, rho_c, dwd, dw, d_rhoc)

    j = a_star @ j_body @ a_star.T
    jwd = j @ wd
    jw = j @ w
    w_h = np.empty((3, 3))
    hat(w, w_h)
    tmp = np.empty((3, 3))

    # values at the linearization point
    q_o = q_i + load - mass * (a_i + kap_c)
    m_o = (m_i - np.cross(rho, q_o) + np.cross(rho_c, load) + torque
           - (jwd + np.cross(w, jw) + mass * np.cross(rho_c, a_i)))

    for r in range(12):
        for c in range(13):
            u[r, c] = 0.0
    # a_O row
    for i in range(3):
        u[A + i, A + i] = 1.0
        u[PHI + i, PHI + i] = 1.0
        u[Q + i, Q + i] = 1.0
        u[Q + i, A + i] = -mass
        u[M + i, M + i] = 1.0
    u[A:A + 3, PHI:PHI + 3] = dkap_o
    u[Q:Q + 3, PHI:PHI + 3] = -mass * dkap_c
    # m_O row: d/d q_I, d/d a_I, d/d phi
    u[M:M + 3, Q:Q + 3] = -rho_h
    u[M:M + 3, A:A + 3] = mass * rho_h - mass * rhoc_h
    # -rho x q_O: rho^ (M dkap_c) + q_O^ d_rho ; rho_C x load: -load^ d_rhoc
    hat(q_o, tmp)
    d_m = mass * (rho_h @ dkap_c) + tmp @ d_rho
    hat(load, tmp)
    d_m -= tmp @ d_rhoc
    # J w_dot: J Dwd + [-(J wd)^ + J wd^] Lam
    t1 = np.empty((3, 3))
    hat(jwd, t1)
    t2 = np.empty((3, 3))
    hat(wd, t2)
    d_j_wd = -t1 + j @ t2
    d_m -= j @ dwd + d_j_wd @ lam
    # w x J w: (w^ J - (J w)^) Dw + w^ [-(J w)^ + J w^] Lam
    hat(jw, t1)
    d_m -= (w_h @ j - t1) @ dw + w_h @ (-t1 + j @ w_h) @ lam
    # M rho_C x a_I: -M a_I^ d_rhoc
    hat(a_i, tmp)
    d_m += mass * (tmp @ d_rhoc)
    u[M:M + 3, PHI:PHI + 3] = d_m

    # affine part: u z* + const = value at z*
    value = np.empty(12)
    value[A:A + 3] = a_i + kap_o
    value[PHI:PHI + 3] = phi
    value[M:M + 3] = m_o
    value[Q:Q + 3] = q_o
    for r in range(12):
        s = value[r]
        for c in range(12):
            s -= u[r, c] * z_star[c]
        u[r, CONST] = s
