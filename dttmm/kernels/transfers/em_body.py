"""Transfer matrix of a rigid body over one step of the energy-momentum scheme (docs/solver.md,
"Energy-momentum scheme").

Station state z = [a, b, m, q] (12 entries, then the affine 1), the same layout as the Newmark
transfer (kernels/transfers/body.py) with step quantities in the slots:
  a = 2 dx / h^2   the station point's displacement over the step, dx, in acceleration units,
  b = 2 phi / h^2  the body's world Cayley rotation increment, A_{n+1} = cay(phi) A_n, likewise,
  m, q             the step's mean moment (about the station point) and force that the inboard
                   side exerts on the outboard side, world components.
With A_mid l = (A_n l + A_{n+1} l) / 2, rho_C = A_mid l_IC, rho_O = A_mid l_IO, the body's step
equations are (EM1-EM4):
  a_O = a_I + b x rho_O                                 (A_{n+1} l - A_n l = phi x A_mid l)
  q_O = q_I + load - M (a_C - 2 v_C,n / h),  a_C = a_I + b x rho_C
                                                        (M (v_C,n+1 - v_C,n) = h F)
  m_O = m_I - rho_C x q_I - (rho_O - rho_C) x q_O + torque - (pi_{n+1} - pi_n) / h
  pi = A J_C W, W_{n+1} = 2 Theta / h - W_n, Theta = A_n^T phi    (body-frame midpoint rule)
"""
import numpy as np

from .. import allocating_kernel
from .body import _cross, _mm, _mv, affine_part
from ..algebra.mat3 import matvec_into, mm3_into
from ..algebra.so3 import cayley, cayley_tangent, hat

A, B, M, Q = 0, 3, 6, 9


@allocating_kernel
def em_body_kinematics(rot_n, omega_n, b, h, rot_new, omega_new):
    """A_{n+1} and the world angular velocity w_{n+1} = A_{n+1} W_{n+1} for the slot value b."""
    phi = 0.5 * h * h * b
    c = np.empty((3, 3))
    cayley(phi, c)
    mm3_into(c, rot_n, rot_new)
    w_body = (2.0 / h) * _mv(rot_n.T, phi) - _mv(rot_n.T, omega_n)
    matvec_into(rot_new, w_body, omega_new)


@allocating_kernel(entry=True)
def rigid_body_transfer_em(p, j_c, rot_n, omega_n, v_c_n, h, z_star, load, torque, u):
    """Fill u (12 x 13) with the affine transfer z_O = u[:, :12] z_I + u[:, 12] of a rigid body
    over one energy-momentum step, linearized about the input state z_star (exact Jacobian).

    p: body parameter row (mass, l_IC, l_IO, ...); j_c: inertia about the mass centre, body
    frame; rot_n, omega_n, v_c_n: rotation, world angular velocity and mass-centre velocity at
    t_n; load: M g + F, torque: applied world torque, both the step's means."""
    mass = p[0]
    l_ic = p[1:4]
    l_io = p[4:7]
    a_i = z_star[A:A + 3]
    b = z_star[B:B + 3]
    m_i = z_star[M:M + 3]
    q_i = z_star[Q:Q + 3]
    s = 0.5 * h * h                       # phi = s b
    phi = s * b

    cay = np.empty((3, 3))
    cayley(phi, cay)
    tangent = np.empty((3, 3))
    cayley_tangent(phi, tangent)
    rot = _mm(cay, rot_n)
    rc1 = _mv(rot, l_ic)
    ro1 = _mv(rot, l_io)
    rho_c = 0.5 * (_mv(rot_n, l_ic) + rc1)
    rho_o = 0.5 * (_mv(rot_n, l_io) + ro1)
    r_oc = rho_o - rho_c
    tmp = np.empty((3, 3))
    # d(A_{n+1} l)/db = -(A_{n+1} l)^ D s
    hat(rc1, tmp)
    d_rho_c = -0.5 * s * _mm(tmp, tangent)
    hat(ro1, tmp)
    d_rho_o = -0.5 * s * _mm(tmp, tangent)
    b_h = np.empty((3, 3))
    hat(b, b_h)
    rhoc_h = np.empty((3, 3))
    hat(rho_c, rhoc_h)
    rhoo_h = np.empty((3, 3))
    hat(rho_o, rhoo_h)
    roc_h = np.empty((3, 3))
    hat(r_oc, roc_h)

    # EM1, EM2
    a_o = a_i + _cross(b, rho_o)
    d_ao = -rhoo_h + _mm(b_h, d_rho_o)
    a_c = a_i + _cross(b, rho_c)
    d_ac = -rhoc_h + _mm(b_h, d_rho_c)
    q_o = q_i + load - mass * (a_c - (2.0 / h) * v_c_n)
    d_qo = -mass * d_ac

    # EM3, EM4: pi_{n+1} = A J_C (2 A_n^T phi / h - A_n^T w_n)
    w_body = (2.0 / h) * _mv(rot_n.T, phi) - _mv(rot_n.T, omega_n)
    pi1 = _mv(rot, _mv(j_c, w_body))
    pi0 = _mv(rot_n, _mv(j_c, _mv(rot_n.T, omega_n)))
    hat(pi1, tmp)
    d_pi1 = s * (-_mm(tmp, tangent) + (2.0 / h) * _mm(_mm(rot, j_c), rot_n.T))
    m_o = (m_i - _cross(rho_c, q_i) - _cross(r_oc, q_o) + torque - (pi1 - pi0) / h)
    qi_h = np.empty((3, 3))
    hat(q_i, qi_h)
    qo_h = np.empty((3, 3))
    hat(q_o, qo_h)
    d_mo = (_mm(qi_h, d_rho_c) - _mm(roc_h, d_qo) + _mm(qo_h, d_rho_o - d_rho_c)
            - d_pi1 / h)

    for r in range(12):
        for c in range(13):
            u[r, c] = 0.0
    for i in range(3):
        u[A + i, A + i] = 1.0
        u[B + i, B + i] = 1.0
        u[M + i, M + i] = 1.0
        u[Q + i, Q + i] = 1.0
        u[Q + i, A + i] = -mass
    u[A:A + 3, B:B + 3] = d_ao
    u[Q:Q + 3, B:B + 3] = d_qo
    u[M:M + 3, A:A + 3] = mass * roc_h
    u[M:M + 3, Q:Q + 3] = -rhoo_h
    u[M:M + 3, B:B + 3] = d_mo

    affine_part(u, a_o, b, m_o, q_o, z_star)
