"""Transfer of an elastic hinge over one time step (docs/hinges.md).

Inboard station z_in = [a, phi_in, m, q] at the inboard output point; outboard station
z_out = [a_out, phi_out, m_out, q] at the outboard input point, offset by the deflection d.
  q = -(K_w d + C_w d_dot),   K_w = A_in K_t A_in^T, C_w = A_in C_t A_in^T
  d_ddot = c1 d + w1d,  d_dot = c3 d + w3d          (the integrator on the world vector d)
  a_out = a + d_ddot
  m_out = m - d x q                                 (equilibrium of the massless hinge)
  m_out = -A_in (K_r psi + C_r A_in^T (w_out - w_in)),  exp(psi^) = A_in^T A_out R0^T
The last line is solved for phi_out, linearized about the guess (its Jacobian drops the small
terms in psi and d, which changes the convergence rate of Newton iterations, not the solution).
"""
import numpy as np

from .. import kernel
from .body import A, CONST, M, PHI, Q, _cross, _mm, _mv
from ..algebra.mat3 import put1, put2
from ..algebra.so3 import hat, log_so3


@kernel
def elastic_hinge_transfer(h, rot_in, lam_in, w_in, dw_in, rot_out, lam_out, w_out, dw_out,
                           phi_out_star, c1, c3, w1d, w3d, z_star, u):
    """Fill u (12 x 13) with z_out = u[:, :12] z_in + u[:, 12], linearized about z_star (the
    inboard station guess).  rot/lam/w/dw: rotation, left Jacobian, angular velocity and its
    derivative with respect to phi of the inboard and outboard bodies at the guess;
    phi_out_star: the outboard body's guessed phi; c1, c3, w1d, w3d: the integrator on d."""
    r0 = h[0:9].reshape((3, 3))
    k_t = h[9:18].reshape((3, 3))
    c_t = h[18:27].reshape((3, 3))
    k_r = h[27:36].reshape((3, 3))
    c_r = h[36:45].reshape((3, 3))
    k_w = _mm(_mm(rot_in, k_t), rot_in.T)
    c_w = _mm(_mm(rot_in, c_t), rot_in.T)
    kr_w = _mm(_mm(rot_in, k_r), rot_in.T)
    cr_w = _mm(_mm(rot_in, c_r), rot_in.T)

    d_of_q = -np.linalg.inv(k_w + c3 * c_w)      # d = d_of_q q + d0
    d0 = _mv(d_of_q, _mv(c_w, w3d))
    q_star = z_star[Q:Q + 3]
    phi_in_star = z_star[PHI:PHI + 3]
    d_star = _mv(d_of_q, q_star) + d0

    psi = np.empty(3)
    log_so3(_mm(_mm(rot_in.T, rot_out), r0.T), psi)
    n_star = -_mv(rot_in, _mv(k_r, psi) + _mv(c_r, _mv(rot_in.T, w_out - w_in)))
    n_out = -_mm(kr_w, lam_out) - _mm(cr_w, dw_out)
    n_in = _mm(kr_w, lam_in) + _mm(cr_w, dw_in)
    n_out_inv = np.linalg.inv(n_out)

    dh = np.empty((3, 3))
    hat(d_star, dh)
    qh = np.empty((3, 3))
    hat(q_star, qh)
    dm_dq = -dh + _mm(qh, d_of_q)                # m_out = m + dm_dq q + m0
    m0 = _mv(qh, d0) - _mv(qh, d_star)

    for r in range(12):
        for c in range(13):
            u[r, c] = 0.0
    for i in range(3):
        u[A + i, A + i] = 1.0
        u[M + i, M + i] = 1.0
        u[Q + i, Q + i] = 1.0
    put2(u[A:A + 3, Q:Q + 3], c1 * d_of_q)
    put1(u[A:A + 3, CONST], c1 * d0 + w1d)
    put2(u[M:M + 3, Q:Q + 3], dm_dq)
    put1(u[M:M + 3, CONST], m0)
    # phi_out = phi_out* + n_out^-1 (m_out - n* - n_in (phi_in - phi_in*))
    put2(u[PHI:PHI + 3, M:M + 3], n_out_inv)
    put2(u[PHI:PHI + 3, Q:Q + 3], _mm(n_out_inv, dm_dq))
    put2(u[PHI:PHI + 3, PHI:PHI + 3], -_mm(n_out_inv, n_in))
    put1(u[PHI:PHI + 3, CONST],
         phi_out_star + _mv(n_out_inv, m0 - n_star + _mv(n_in, phi_in_star)))


@kernel
def elastic_hinge_loads(h, rot_in, w_in, rot_out, w_out, d, d_dot):
    """Spring-damper force q and couples (m_in about the inboard point, m_out about the outboard
    point) of an elastic hinge in a given state: used where the state is known (the consistent
    start)."""
    r0 = h[0:9].reshape((3, 3))
    k_t = h[9:18].reshape((3, 3))
    c_t = h[18:27].reshape((3, 3))
    k_r = h[27:36].reshape((3, 3))
    c_r = h[36:45].reshape((3, 3))
    q = -_mv(rot_in, _mv(k_t, _mv(rot_in.T, d)) + _mv(c_t, _mv(rot_in.T, d_dot)))
    psi = np.empty(3)
    log_so3(_mm(_mm(rot_in.T, rot_out), r0.T), psi)
    m_out = -_mv(rot_in, _mv(k_r, psi) + _mv(c_r, _mv(rot_in.T, w_out - w_in)))
    m_in = m_out + _cross(d, q)
    return q, m_in, m_out
