"""Independent reference solver: global Newton-Euler equations with joint reactions.

This module shares only the model description (dttmm.model, dttmm.elements, dttmm.result) with
the rest of the package; it uses no transfer matrices.

Formulation
-----------
Coordinates.  Each body whose inboard hinge leaves its rotation free (ball joint or elastic
hinge) carries a quaternion q_k (body to world, normalised whenever it is read) and its world
angular velocity w_k.  A body behind a fixed hinge takes A_k = A_{k-1} R0, w_k = w_{k-1} (the
ground frame for k = 0).  Each elastic hinge carries its world deflection d_k and its rate.
Positions and velocities follow from the ground point by kinematics,
    r_in_k = r_out_{k-1} + d_k,   r_out_k = r_in_k + A_k l_IO,
so ball and fixed joints hold exactly (to round-off) by construction.

Equations.  At every right-hand-side evaluation one dense linear system is assembled and solved
for all unknowns at once: the input-point acceleration a_k and angular acceleration alpha_k of
every body, the reaction force F_k of every ball or fixed hinge, and the reaction couple N_k of
every fixed hinge.  Rows are, for each body k (world frame; rho_c = A l_IC, rho_o = A l_IO,
J = A J_I A^T):
    Newton:         M (a_k + alpha_k x rho_c + w x (w x rho_c)) = Q_k - Q_{k+1} + M g + f_k
    Euler about I:  J alpha_k + w x J w + M rho_c x a_k
                        = N_k - N_{k+1} - (rho_o + d_{k+1}) x Q_{k+1} + rho_c x (M g + f_k) + tau_k
where Q_k, N_k are the force and couple (about the input point) the inboard side exerts on body
k: unknown reactions for ball / fixed hinges (N_k = 0 for a ball joint), the spring-damper law for
elastic hinges.  For each ball or fixed hinge the constraint rows at acceleration level
    a_k = a_{k-1} + alpha_{k-1} x rho_o,{k-1} + w_{k-1} x (w_{k-1} x rho_o,{k-1})  (a_ground, k=0)
and for each fixed hinge alpha_k = alpha_{k-1} (alpha_ground for k = 0) close the system.
Elastic hinges add no rows: d_k'' = a_k - a_out_{k-1}.  A tip joined to the ground (Model
tip_pinned, build_chain(tip="ball")) adds its reaction force and the row a_out_{n-1} = 0 (a point
fixed in the world); a chain lying straight between its two fixed points then leaves the tension
along it indeterminate, and the solver takes the solution with the least tip force (SVD), as the
DT-TMM sweeps do.

Euler-Bernoulli beams (docs/beam.md).  A beam body carries, besides its frame (quaternion, w),
its modal coordinates eta = [eta_v (n), eta_w (n)] and their rates; the unknowns gain the modal
accelerations eta'' and the rows gain the 2n modal equations.  In body components, with
p(x) = x e1 + Phi(x) eta the frame-relative position of the section at x, Phi(x) = [e2 Y(x),
e3 Y(x)] (3 x 2n), Y_k = sin(k pi x / L), and the frame's body-frame w_b, alpha_b, a_b:
    A^T r''(x) = a_b + alpha_b x p + w_b x (w_b x p) + 2 w_b x Phi eta' + Phi eta''
and the integrals the equations need are moments of the line mass:
    m = mu L,  s = int mu p,  Q = int mu p p^T,  J_b = tr(Q) E - Q,  P = int mu Phi,
    G = int mu p^ Phi,  C = int mu (Phi eta') p^T,
so that (world; h = A s, J = A (J_b + J_p) A^T, J_p = diag(j_p L, 0, 0)):
    Newton:  m a_I - h^ alpha + A P eta'' - F_k + F_{k+1}
                 = m g - w x (w x h) - 2 w x (A P eta')
    Euler:   J alpha + h^ a_I + A G eta'' - N_k + N_{k+1} + rho_o^ F_{k+1}
                 = h x g - w x J w - 2 A (w_b tr C - C w_b)
    modal:   (A P)^T a_I + (A G)^T alpha + (mu L / 2) eta''
                 = (A P)^T g - int mu Phi^T w_b^ w_b^ p - 2 int mu Phi^T w_b^ Phi eta'
                   - c eta' - k eta
(int mu p x (w x (w x p)) = w x J_b w and int mu p x (w x u') = w tr C - C w).  The moments
are evaluated ANALYTICALLY from the three sine integrals
    int_0^L Y_k = L (1 - (-1)^k) / (k pi),  int_0^L x Y_k = -L^2 (-1)^k / (k pi),
    int_0^L Y_j Y_k = (L / 2) delta_jk,
so they are exact to round-off for any number of modes.  (The energies in dttmm.result are
computed independently, by Gauss-Legendre quadrature of |r'(x)|^2 and g . r(x).)  A beam's
output point is O = r_I + A L e1 (Y_k(L) = 0), so the joint rows are those of a rigid body.

The right-hand side is numba-compiled; the Python wrapper only evaluates the ground motion and
the applied loads at time t and hands them to the kernel as arrays.
"""
import math
import time

import numba
import numpy as np
from scipy.integrate import solve_ivp

from ..elements import BEAM
from ..elements.beam import (DAMPING_RATIO, EI_V, EI_W, FAMILY, LENGTH, MASS_PER_LENGTH, MODES,
                             PINNED, POLAR_PER_LENGTH)
from ..elements.hinges import (C_ROTATION, C_TRANSLATION, ELASTIC, FIXED, K_ROTATION,
                               K_TRANSLATION, REST_ROTATION)
from ..elements.rigid_body import INERTIA_INPUT, MASS, TO_MASS_CENTER, TO_OUTPUT
from ..model import Model
from ..result import Result, chain_energies, point_positions, rotation_to_quaternion

METHODS = ("RK45", "DOP853")

# offsets into a body_params / hinge_params row, as plain ints for the kernels
_MASS = MASS
_LIC = TO_MASS_CENTER.start
_LIO = TO_OUTPUT.start
_JI = INERTIA_INPUT.start
_R0 = REST_ROTATION.start
_KT = K_TRANSLATION.start
_CT = C_TRANSLATION.start
_KR = K_ROTATION.start
_CR = C_ROTATION.start
_BEAM = BEAM
_BL, _BMU, _BEIV, _BEIW = LENGTH, MASS_PER_LENGTH, EI_V, EI_W
_BJP, _BZETA, _BMODES = POLAR_PER_LENGTH, DAMPING_RATIO, MODES


# ----------------------------------------------------------------------------------------------
# small pure kernels
# ----------------------------------------------------------------------------------------------

@numba.njit(cache=True)
def _mat3(row, start):
    m = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            m[i, j] = row[start + 3 * i + j]
    return m


@numba.njit(cache=True)
def _vec3(row, start):
    v = np.empty(3)
    for i in range(3):
        v[i] = row[start + i]
    return v


@numba.njit(cache=True)
def _cross(a, b):
    c = np.empty(3)
    c[0] = a[1] * b[2] - a[2] * b[1]
    c[1] = a[2] * b[0] - a[0] * b[2]
    c[2] = a[0] * b[1] - a[1] * b[0]
    return c


@numba.njit(cache=True)
def _hat(v):
    m = np.zeros((3, 3))
    m[0, 1] = -v[2]
    m[0, 2] = v[1]
    m[1, 0] = v[2]
    m[1, 2] = -v[0]
    m[2, 0] = -v[1]
    m[2, 1] = v[0]
    return m


@numba.njit(cache=True)
def _quat_to_rot(q):
    """Rotation matrix of the quaternion [w, x, y, z], normalised first."""
    s = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    w, x, y, z = q[0] / s, q[1] / s, q[2] / s, q[3] / s
    r = np.empty((3, 3))
    r[0, 0] = 1.0 - 2.0 * (y * y + z * z)
    r[0, 1] = 2.0 * (x * y - w * z)
    r[0, 2] = 2.0 * (x * z + w * y)
    r[1, 0] = 2.0 * (x * y + w * z)
    r[1, 1] = 1.0 - 2.0 * (x * x + z * z)
    r[1, 2] = 2.0 * (y * z - w * x)
    r[2, 0] = 2.0 * (x * z - w * y)
    r[2, 1] = 2.0 * (y * z + w * x)
    r[2, 2] = 1.0 - 2.0 * (x * x + y * y)
    return r


@numba.njit(cache=True)
def _log_rot(r):
    """Rotation vector psi with expm(hat(psi)) = r, |psi| <= pi; robust at every angle (it goes
    through the quaternion of r, largest component first)."""
    tr = r[0, 0] + r[1, 1] + r[2, 2]
    diag_max = max(r[0, 0], r[1, 1], r[2, 2])
    if tr >= diag_max:
        s = 2.0 * math.sqrt(1.0 + tr)
        w = 0.25 * s
        x = (r[2, 1] - r[1, 2]) / s
        y = (r[0, 2] - r[2, 0]) / s
        z = (r[1, 0] - r[0, 1]) / s
    elif r[0, 0] == diag_max:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        w = (r[2, 1] - r[1, 2]) / s
        x = 0.25 * s
        y = (r[0, 1] + r[1, 0]) / s
        z = (r[0, 2] + r[2, 0]) / s
    elif r[1, 1] == diag_max:
        s = 2.0 * math.sqrt(1.0 - r[0, 0] + r[1, 1] - r[2, 2])
        w = (r[0, 2] - r[2, 0]) / s
        x = (r[0, 1] + r[1, 0]) / s
        y = 0.25 * s
        z = (r[1, 2] + r[2, 1]) / s
    else:
        s = 2.0 * math.sqrt(1.0 - r[0, 0] - r[1, 1] + r[2, 2])
        w = (r[1, 0] - r[0, 1]) / s
        x = (r[0, 2] + r[2, 0]) / s
        y = (r[1, 2] + r[2, 1]) / s
        z = 0.25 * s
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    sv = math.sqrt(x * x + y * y + z * z)
    psi = np.empty(3)
    if sv < 1e-12:
        f = 2.0 / w              # angle / sin(angle / 2) -> 2 as angle -> 0
    else:
        f = 2.0 * math.atan2(sv, w) / sv
    psi[0] = f * x
    psi[1] = f * y
    psi[2] = f * z
    return psi


# ----------------------------------------------------------------------------------------------
# kinematics, hinge laws, global system
# ----------------------------------------------------------------------------------------------

@numba.njit(cache=True)
def _kinematics(y, body_params, hinge_kind, hinge_params, q_off, w_off, d_off,
                r_g, v_g, rot_g, w_g):
    """Rotations, angular velocities, input-point positions / velocities and the elastic
    deflections (world) of every body, from the state and the ground motion."""
    n = body_params.shape[0]
    rot = np.empty((n, 3, 3))
    omega = np.empty((n, 3))
    r_in = np.empty((n, 3))
    v_in = np.empty((n, 3))
    defl = np.zeros((n, 3))
    defl_rate = np.zeros((n, 3))
    r_prev = r_g.copy()          # output point of the inboard body (ground point for k = 0)
    v_prev = v_g.copy()
    for k in range(n):
        if hinge_kind[k] == FIXED:
            a_in = rot_g if k == 0 else rot[k - 1]
            w_in = w_g if k == 0 else omega[k - 1]
            rot[k] = a_in @ _mat3(hinge_params[k], _R0)
            omega[k] = w_in
        else:
            rot[k] = _quat_to_rot(y[q_off[k]:q_off[k] + 4])
            omega[k] = y[w_off[k]:w_off[k] + 3]
        if hinge_kind[k] == ELASTIC:
            defl[k] = y[d_off[k]:d_off[k] + 3]
            defl_rate[k] = y[d_off[k] + 3:d_off[k] + 6]
        r_in[k] = r_prev + defl[k]
        v_in[k] = v_prev + defl_rate[k]
        rho_o = rot[k] @ _vec3(body_params[k], _LIO)
        r_prev = r_in[k] + rho_o
        v_prev = v_in[k] + _cross(omega[k], rho_o)
    return rot, omega, r_in, v_in, defl, defl_rate


@numba.njit(cache=True)
def _elastic_loads(rot, omega, defl, defl_rate, hinge_kind, hinge_params, rot_g, w_g):
    """Force q and couple m every elastic hinge exerts on its outboard body (world; zero rows for
    the other hinges)."""
    n = rot.shape[0]
    q = np.zeros((n, 3))
    m = np.zeros((n, 3))
    for k in range(n):
        if hinge_kind[k] != ELASTIC:
            continue
        h = hinge_params[k]
        a_in = rot_g if k == 0 else rot[k - 1]
        w_in = w_g if k == 0 else omega[k - 1]
        d_b = a_in.T @ defl[k]
        dd_b = a_in.T @ defl_rate[k]
        q[k] = -(a_in @ (_mat3(h, _KT) @ d_b + _mat3(h, _CT) @ dd_b))
        psi = _log_rot(a_in.T @ rot[k] @ _mat3(h, _R0).T)
        w_rel_b = a_in.T @ (omega[k] - w_in)
        m[k] = -(a_in @ (_mat3(h, _KR) @ psi + _mat3(h, _CR) @ w_rel_b))
    return q, m


@numba.njit(cache=True)
def _beam_terms(bp, eta, eta_dot, a, w, gravity):
    """World-frame mass properties, coupling blocks and velocity terms of one pinned beam at its
    current (eta, eta'), from the analytic moments of the module docstring.

    Returns mass, h = A s (first moment about I), J = A (J_b + J_p) A^T, AP = A P and AG = A G
    (3 x 2n), the velocity terms of the Newton and Euler rows (right-hand side), the modal
    equations' right-hand side (gravity, velocity, damping and stiffness terms) and the modal
    mass mu L / 2."""
    length = bp[_BL]
    mu = bp[_BMU]
    nm = int(bp[_BMODES])
    n2 = 2 * nm
    # int_0^L Y_k dx and int_0^L x Y_k dx, analytic
    sy = np.empty(nm)
    ty = np.empty(nm)
    for j in range(nm):
        k = j + 1
        sgn = 1.0 if k % 2 == 0 else -1.0          # (-1)^k
        sy[j] = length * (1.0 - sgn) / (k * math.pi)
        ty[j] = -length * length * sgn / (k * math.pi)
    half = 0.5 * length                            # int Y_j Y_k = (L / 2) delta_jk
    sv = sw = tv = tw = 0.0
    vv = vw = ww = 0.0
    tdv = tdw = dvv = dvw = dwv = dww = 0.0
    for j in range(nm):
        ev, ew, dv, dw = eta[j], eta[nm + j], eta_dot[j], eta_dot[nm + j]
        sv += sy[j] * ev
        sw += sy[j] * ew
        tv += ty[j] * ev
        tw += ty[j] * ew
        vv += ev * ev
        vw += ev * ew
        ww += ew * ew
        tdv += ty[j] * dv
        tdw += ty[j] * dw
        dvv += dv * ev
        dvw += dv * ew
        dwv += dw * ev
        dww += dw * ew
    mass = mu * length
    s_b = np.empty(3)
    s_b[0] = mu * length * length / 2.0
    s_b[1] = mu * sv
    s_b[2] = mu * sw
    q = np.empty((3, 3))                           # int mu p p^T
    q[0, 0] = mu * length ** 3 / 3.0
    q[0, 1] = q[1, 0] = mu * tv
    q[0, 2] = q[2, 0] = mu * tw
    q[1, 1] = mu * half * vv
    q[1, 2] = q[2, 1] = mu * half * vw
    q[2, 2] = mu * half * ww
    tr = q[0, 0] + q[1, 1] + q[2, 2]
    j_b = -q
    for i in range(3):
        j_b[i, i] += tr
    j_b[0, 0] += bp[_BJP] * length                 # polar spin inertia J_p = diag(j_p L, 0, 0)
    p_b = np.zeros((3, n2))                        # int mu Phi
    g_b = np.zeros((3, n2))                        # int mu p^ Phi
    for j in range(nm):
        p_b[1, j] = mu * sy[j]
        p_b[2, nm + j] = mu * sy[j]
        g_b[2, j] = mu * ty[j]                     # p x (Y_k e2): T_k e3 - (L/2) eta_w,k e1
        g_b[0, j] = -mu * half * eta[nm + j]
        g_b[1, nm + j] = -mu * ty[j]               # p x (Y_k e3): -T_k e2 + (L/2) eta_v,k e1
        g_b[0, nm + j] = mu * half * eta[j]
    c = np.zeros((3, 3))                           # int mu (Phi eta') p^T
    c[1, 0] = mu * tdv
    c[2, 0] = mu * tdw
    c[1, 1] = mu * half * dvv
    c[1, 2] = mu * half * dvw
    c[2, 1] = mu * half * dwv
    c[2, 2] = mu * half * dww
    w_b = a.T @ w
    trc = c[0, 0] + c[1, 1] + c[2, 2]
    cor_b = 2.0 * (trc * w_b - c @ w_b)            # int mu p x (2 w x u')
    ap = a @ p_b
    ag = a @ g_b
    h = a @ s_b
    j_w = a @ j_b @ a.T
    ud = ap @ eta_dot                              # A int mu u' dx
    newton_v = -2.0 * _cross(w, ud)
    euler_v = -(a @ cor_b)
    # modal right-hand side
    ww2 = w_b[0] * w_b[0] + w_b[1] * w_b[1] + w_b[2] * w_b[2]
    mm = np.outer(w_b, w_b)                        # w^ w^ = w w^T - |w|^2 E
    for i in range(3):
        mm[i, i] -= ww2
    g_w = ap.T @ gravity                           # (A P)^T g
    modal = np.empty(n2)
    m_k = mu * half
    for j in range(nm):
        k = j + 1
        ev, ew, dv, dw = eta[j], eta[nm + j], eta_dot[j], eta_dot[nm + j]
        beta4 = (k * math.pi / length) ** 4
        kv = bp[_BEIV] * beta4 * half
        kw = bp[_BEIW] * beta4 * half
        cv = 2.0 * bp[_BZETA] * math.sqrt(kv / m_k) * m_k
        cw = 2.0 * bp[_BZETA] * math.sqrt(kw / m_k) * m_k
        cent_v = mu * (ty[j] * mm[1, 0] + half * (mm[1, 1] * ev + mm[1, 2] * ew))
        cent_w = mu * (ty[j] * mm[2, 0] + half * (mm[2, 1] * ev + mm[2, 2] * ew))
        cori_v = -2.0 * m_k * w_b[0] * dw          # 2 int mu Y_k e2 . (w_b x Phi eta')
        cori_w = 2.0 * m_k * w_b[0] * dv
        modal[j] = g_w[j] - cent_v - cori_v - cv * dv - kv * ev
        modal[nm + j] = g_w[nm + j] - cent_w - cori_w - cw * dw - kw * ew
    return mass, h, j_w, ap, ag, newton_v, euler_v, modal, m_k


@numba.njit(cache=True)
def _assemble(y, rot, omega, defl, q_el, m_el, body_params, hinge_kind, body_kind, beam_params,
              m_off, e0, n_modal, e_col0, f_col, m_col, t_col, n_unknowns, gravity, a_g, wd_g,
              forces, torques):
    """The global Newton-Euler system  S x = b  for x = [a_0, alpha_0, ..., a_{n-1},
    alpha_{n-1}, reactions, modal accelerations].  Column f_col[k] (m_col[k]) holds the reaction
    force (couple) of hinge k, or -1 when the hinge has none; the matching constraint equation
    uses the same row index, so S is square.  Beam k's modal accelerations sit in the columns
    e_col0 + m_off[k] + (0..2n-1), its modal equations in the same rows; its coordinates and
    rates are y[e0 + m_off[k] + ...] and y[e0 + n_modal + m_off[k] + ...]."""
    n = rot.shape[0]
    s = np.zeros((n_unknowns, n_unknowns))
    b = np.zeros(n_unknowns)
    for k in range(n):
        p = body_params[k]
        a = rot[k]
        w = omega[k]
        rho_o = a @ _vec3(p, _LIO)
        rn, re = 6 * k, 6 * k + 3          # Newton rows, Euler rows
        ca, cal = 6 * k, 6 * k + 3         # a_k, alpha_k columns
        if body_kind[k] == _BEAM:
            nm2 = 2 * int(beam_params[k, _BMODES])
            o = m_off[k]
            eta = y[e0 + o:e0 + o + nm2]
            eta_dot = y[e0 + n_modal + o:e0 + n_modal + o + nm2]
            mass, h, j_w, ap, ag, newton_v, euler_v, modal, m_k = _beam_terms(
                beam_params[k], eta, eta_dot, a, w, gravity)
            weight = mass * gravity + forces[k]
            bn = weight - _cross(w, _cross(w, h)) + newton_v
            be = -_cross(w, j_w @ w) + _cross(h, gravity) + euler_v + torques[k]
            ce = e_col0 + o
            for j in range(nm2):
                for i in range(3):
                    s[rn + i, ce + j] = ap[i, j]      # translation: + A P eta''
                    s[re + i, ce + j] = ag[i, j]      # rotation:    + A G eta''
                    s[ce + j, ca + i] = ap[i, j]      # modal:  (A P)^T a + (A G)^T alpha
                    s[ce + j, cal + i] = ag[i, j]
                s[ce + j, ce + j] = m_k
                b[ce + j] = modal[j]
        else:
            mass = p[_MASS]
            rho_c = a @ _vec3(p, _LIC)
            h = mass * rho_c
            j_w = a @ _mat3(p, _JI) @ a.T
            weight = mass * gravity + forces[k]
            # Newton: M a - hat(h) alpha - F_k + F_{k+1} = M g + f - w x (w x h) + q_k - q_{k+1}
            bn = weight - _cross(w, _cross(w, h))
            # Euler about I: J alpha + hat(h) a - N_k + N_{k+1} + hat(rho_o + d_{k+1}) F_{k+1}
            #     = -w x J w + rho_c x (M g + f) + tau + m_k - m_{k+1} - (rho_o + d_{k+1}) x q_{k+1}
            be = -_cross(w, j_w @ w) + _cross(rho_c, weight) + torques[k]
        hc = _hat(h)
        for i in range(3):
            s[rn + i, ca + i] = mass
            for j in range(3):
                s[rn + i, cal + j] = -hc[i, j]
                s[re + i, cal + j] = j_w[i, j]
                s[re + i, ca + j] = hc[i, j]
        # the inboard hinge acting on body k
        if hinge_kind[k] == ELASTIC:
            bn += q_el[k]
            be += m_el[k]
        else:
            c = f_col[k]
            for i in range(3):
                s[rn + i, c + i] = -1.0
            if hinge_kind[k] == FIXED:
                c = m_col[k]
                for i in range(3):
                    s[re + i, c + i] = -1.0
        # the outboard hinge acting on body k (its force acts at r_out_k + d_{k+1})
        if k + 1 < n:
            arm = rho_o + defl[k + 1]
            if hinge_kind[k + 1] == ELASTIC:
                bn -= q_el[k + 1]
                be -= m_el[k + 1] + _cross(arm, q_el[k + 1])
            else:
                c = f_col[k + 1]
                ha = _hat(arm)
                for i in range(3):
                    s[rn + i, c + i] = 1.0
                    for j in range(3):
                        s[re + i, c + j] = ha[i, j]
                if hinge_kind[k + 1] == FIXED:
                    c = m_col[k + 1]
                    for i in range(3):
                        s[re + i, c + i] = 1.0
        for i in range(3):
            b[rn + i] = bn[i]
            b[re + i] = be[i]
        # constraint rows of the inboard hinge (acceleration level)
        if hinge_kind[k] != ELASTIC:
            r = f_col[k]
            for i in range(3):
                s[r + i, ca + i] = 1.0
            if k == 0:
                for i in range(3):
                    b[r + i] = a_g[i]
            else:
                rho_po = rot[k - 1] @ _vec3(body_params[k - 1], _LIO)
                wp = omega[k - 1]
                hpo = _hat(rho_po)
                cent = _cross(wp, _cross(wp, rho_po))
                for i in range(3):
                    s[r + i, 6 * (k - 1) + i] = -1.0
                    for j in range(3):
                        s[r + i, 6 * (k - 1) + 3 + j] = hpo[i, j]
                    b[r + i] = cent[i]
            if hinge_kind[k] == FIXED:
                r = m_col[k]
                for i in range(3):
                    s[r + i, cal + i] = 1.0
                    if k == 0:
                        b[r + i] = wd_g[i]
                    else:
                        s[r + i, 6 * (k - 1) + 3 + i] = -1.0
    if t_col >= 0:
        # tip joined to a fixed point by a ball joint: the tip body receives -F_t at its output
        # point (F_t = q at the tip station, uniform convention), and a_out = 0 there
        k = n - 1
        rho_o = rot[k] @ _vec3(body_params[k], _LIO)
        ha = _hat(rho_o)
        cent = _cross(omega[k], _cross(omega[k], rho_o))
        for i in range(3):
            s[6 * k + i, t_col + i] = 1.0
            s[t_col + i, 6 * k + i] = -1.0
            for j in range(3):
                s[6 * k + 3 + i, t_col + j] = ha[i, j]
                s[t_col + i, 6 * k + 3 + j] = ha[i, j]
            b[t_col + i] = cent[i]
    return s, b


@numba.njit(cache=True)
def _solve_least_tip_force(s, b, t_col):
    """Solve S x = b where S may be singular: with the tip joined to a fixed point, a chain that
    lies straight between its two fixed points leaves the tension along it statically
    indeterminate.  Of all solutions, return the one with the least tip force |x[t_col:+3]|
    (the DT-TMM sweeps' choice); the accelerations do not depend on it.  Singular values below
    1e-12 of the largest count as zero."""
    u, sv, vt = np.linalg.svd(s)
    m = sv.shape[0]
    rank = 0
    for i in range(m):
        if sv[i] > 1e-12 * sv[0]:
            rank += 1
    ub = u.T @ b
    x = np.zeros(m)
    for i in range(rank):
        x += (ub[i] / sv[i]) * vt[i]
    if rank < m:
        null = np.ascontiguousarray(vt[rank:])               # (m - rank, m)
        e = np.ascontiguousarray(null[:, t_col:t_col + 3].T)  # tip force of each null vector
        c = -(np.linalg.pinv(e, rcond=1e-12) @ x[t_col:t_col + 3])
        x += null.T @ c
    return x


@numba.njit(cache=True)
def _solve_dynamics(y, body_params, hinge_kind, hinge_params, body_kind, beam_params, q_off,
                    w_off, d_off, m_off, e0, n_modal, e_col0, f_col, m_col, t_col, n_unknowns,
                    gravity, r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques):
    """Kinematics plus the solved accelerations, hinge loads and modal accelerations."""
    rot, omega, r_in, v_in, defl, defl_rate = _kinematics(
        y, body_params, hinge_kind, hinge_params, q_off, w_off, d_off, r_g, v_g, rot_g, w_g)
    q_el, m_el = _elastic_loads(rot, omega, defl, defl_rate, hinge_kind, hinge_params, rot_g, w_g)
    s, b = _assemble(y, rot, omega, defl, q_el, m_el, body_params, hinge_kind, body_kind,
                     beam_params, m_off, e0, n_modal, e_col0, f_col, m_col, t_col, n_unknowns,
                     gravity, a_g, wd_g, forces, torques)
    if t_col >= 0:
        x = _solve_least_tip_force(s, b, t_col)
    else:
        x = np.linalg.solve(s, b)
    n = body_params.shape[0]
    acc = np.empty((n, 3))
    alpha = np.empty((n, 3))
    force = np.zeros((n, 3))
    moment = np.zeros((n, 3))
    for k in range(n):
        acc[k] = x[6 * k:6 * k + 3]
        alpha[k] = x[6 * k + 3:6 * k + 6]
        if hinge_kind[k] == ELASTIC:
            force[k] = q_el[k]
            moment[k] = m_el[k]
        else:
            force[k] = x[f_col[k]:f_col[k] + 3]
            if hinge_kind[k] == FIXED:
                moment[k] = x[m_col[k]:m_col[k] + 3]
    modal_acc = x[e_col0:e_col0 + n_modal].copy()
    return rot, omega, r_in, v_in, defl, acc, alpha, force, moment, modal_acc


@numba.njit(cache=True)
def rhs_kernel(y, body_params, hinge_kind, hinge_params, body_kind, beam_params, q_off, w_off,
               d_off, m_off, e0, n_modal, e_col0, f_col, m_col, t_col, n_unknowns, gravity, r_g,
               v_g, a_g, rot_g, w_g, wd_g, forces, torques):
    """dy/dt of the state [quaternions, angular velocities, (d, d') of elastic hinges,
    modal coordinates of all beams, their rates]."""
    rot, omega, r_in, v_in, defl, acc, alpha, force, moment, modal_acc = _solve_dynamics(
        y, body_params, hinge_kind, hinge_params, body_kind, beam_params, q_off, w_off, d_off,
        m_off, e0, n_modal, e_col0, f_col, m_col, t_col, n_unknowns, gravity, r_g, v_g, a_g,
        rot_g, w_g, wd_g, forces, torques)
    n = body_params.shape[0]
    dy = np.zeros(y.shape[0])
    for k in range(n):
        if hinge_kind[k] != FIXED:
            o = q_off[k]
            qw, qx, qy, qz = y[o], y[o + 1], y[o + 2], y[o + 3]
            wx, wy, wz = omega[k, 0], omega[k, 1], omega[k, 2]
            # q' = 1/2 [0, w] (x) q  (w in the world frame, A = R(q) body to world)
            dy[o] = -0.5 * (wx * qx + wy * qy + wz * qz)
            dy[o + 1] = 0.5 * (qw * wx + wy * qz - wz * qy)
            dy[o + 2] = 0.5 * (qw * wy + wz * qx - wx * qz)
            dy[o + 3] = 0.5 * (qw * wz + wx * qy - wy * qx)
            dy[w_off[k]:w_off[k] + 3] = alpha[k]
        if hinge_kind[k] == ELASTIC:
            o = d_off[k]
            dy[o:o + 3] = y[o + 3:o + 6]
            if k == 0:
                a_prev_out = a_g
            else:
                rho_po = rot[k - 1] @ _vec3(body_params[k - 1], _LIO)
                a_prev_out = (acc[k - 1] + _cross(alpha[k - 1], rho_po)
                              + _cross(omega[k - 1], _cross(omega[k - 1], rho_po)))
            dy[o + 3:o + 6] = acc[k] - a_prev_out
    for i in range(n_modal):
        dy[e0 + i] = y[e0 + n_modal + i]
        dy[e0 + n_modal + i] = modal_acc[i]
    return dy


# ----------------------------------------------------------------------------------------------
# Python layer
# ----------------------------------------------------------------------------------------------

class _Problem:
    """Index bookkeeping and the per-time evaluation of ground motion and applied loads."""

    def __init__(self, model):
        n = model.n_bodies
        kinds = np.asarray(model.hinge_kind, dtype=np.int64)
        self.model = model
        self.n = n
        self.kinds = kinds
        self.body_params = np.ascontiguousarray(model.body_params, dtype=float)
        self.hinge_params = np.ascontiguousarray(model.hinge_params, dtype=float)
        self.gravity = np.asarray(model.gravity, dtype=float)
        free = [k for k in range(n) if kinds[k] != FIXED]
        elastic = [k for k in range(n) if kinds[k] == ELASTIC]
        self.q_off = np.full(n, -1, dtype=np.int64)
        self.w_off = np.full(n, -1, dtype=np.int64)
        self.d_off = np.full(n, -1, dtype=np.int64)
        o = 0
        for k in free:
            self.q_off[k] = o
            o += 4
        for k in free:
            self.w_off[k] = o
            o += 3
        for k in elastic:
            self.d_off[k] = o
            o += 6
        # beams: all modal coordinates (concatenated in body order, v then w of each beam), then
        # all their rates
        self.body_kind = np.ascontiguousarray(model.body_kind, dtype=np.int64)
        self.beam_params = np.ascontiguousarray(model.beam_params, dtype=float)
        for k in range(n):
            if self.body_kind[k] == BEAM and self.beam_params[k, FAMILY] != PINNED:
                raise ValueError(f"simulate_reference: body {k}: only the 'pinned' beam mode "
                                 f"family is implemented")
        n_modes = np.asarray(model.n_modes, dtype=np.int64)
        self.m_off = np.full(n, -1, dtype=np.int64)
        nm = 0
        for k in range(n):
            if n_modes[k] > 0:
                self.m_off[k] = nm
                nm += int(n_modes[k])
        self.n_modal = nm
        self.e0 = o
        o += 2 * nm
        self.n_state = o
        self.f_col = np.full(n, -1, dtype=np.int64)
        self.m_col = np.full(n, -1, dtype=np.int64)
        c = 6 * n
        for k in range(n):
            if kinds[k] != ELASTIC:
                self.f_col[k] = c
                c += 3
            if kinds[k] == FIXED:
                self.m_col[k] = c
                c += 3
        self.e_col0 = c
        c += nm
        self.t_col = -1
        if getattr(model, "tip_pinned", False):
            self.t_col = c
            c += 3
        self.n_unknowns = c
        self.forces = np.zeros((n, 3))
        self.torques = np.zeros((n, 3))
        self._force_fns = [(k, f) for k, f in enumerate(model.forces) if f is not None]
        self._torque_fns = [(k, f) for k, f in enumerate(model.torques) if f is not None]

    def initial_state(self):
        m = self.model
        y = np.zeros(self.n_state)
        for k in range(self.n):
            if self.q_off[k] >= 0:
                y[self.q_off[k]:self.q_off[k] + 4] = rotation_to_quaternion(m.initial_rotation[k])
                y[self.w_off[k]:self.w_off[k] + 3] = m.initial_angular_velocity[k]
        return y

    def time_inputs(self, t):
        """Ground motion and applied loads at time t, as float arrays for the kernel."""
        r_g, v_g, a_g, rot_g, w_g, wd_g = (np.asarray(x, dtype=float)
                                           for x in self.model.ground_state(t))
        for k, f in self._force_fns:
            self.forces[k] = f(t)
        for k, f in self._torque_fns:
            self.torques[k] = f(t)
        return r_g, v_g, a_g, rot_g, w_g, wd_g, self.forces, self.torques

    def _args(self, y, t):
        r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques = self.time_inputs(t)
        return (y, self.body_params, self.kinds, self.hinge_params, self.body_kind,
                self.beam_params, self.q_off, self.w_off, self.d_off, self.m_off, self.e0,
                self.n_modal, self.e_col0, self.f_col, self.m_col, self.t_col, self.n_unknowns,
                self.gravity, r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques)

    def rhs(self, t, y):
        return rhs_kernel(*self._args(np.ascontiguousarray(y, dtype=float), t))

    def evaluate(self, t, y):
        """Everything Result records at one time, from the state."""
        return _solve_dynamics(*self._args(np.ascontiguousarray(y, dtype=float), t))


def _check_args(model, t_end, method, rtol, atol, t_eval):
    if not isinstance(model, Model):
        raise ValueError(f"simulate_reference: model must be a dttmm Model (from build_chain), "
                         f"got {type(model).__name__}")
    try:
        t_end = float(t_end)
    except (TypeError, ValueError):
        raise ValueError(f"simulate_reference: t_end must be a number, got {t_end!r}") from None
    if not np.isfinite(t_end) or t_end <= 0.0:
        raise ValueError(f"simulate_reference: t_end must be finite and > 0, got {t_end}")
    if method not in METHODS:
        raise ValueError(f"simulate_reference: method must be one of {METHODS}, got {method!r}")
    for name, v in (("rtol", rtol), ("atol", atol)):
        try:
            x = float(v)
        except (TypeError, ValueError):
            raise ValueError(f"simulate_reference: {name} must be a number, got {v!r}") from None
        if not np.isfinite(x) or x <= 0.0:
            raise ValueError(f"simulate_reference: {name} must be finite and > 0, got {x}")
    if float(rtol) < 100.0 * np.finfo(float).eps:
        raise ValueError(f"simulate_reference: rtol must be >= {100 * np.finfo(float).eps:.3g} "
                         f"(100 machine epsilons), got {rtol}")
    if t_eval is None:
        t_eval = np.linspace(0.0, t_end, 201)
    else:
        try:
            t_eval = np.array(t_eval, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise ValueError("simulate_reference: t_eval must be a 1-D array of times") from None
        if t_eval.size == 0 or not np.all(np.isfinite(t_eval)):
            raise ValueError("simulate_reference: t_eval must be a non-empty array of finite times")
        if t_eval[0] < 0.0 or t_eval[-1] > t_end or np.any(np.diff(t_eval) <= 0.0):
            raise ValueError(f"simulate_reference: t_eval must be strictly increasing within "
                             f"[0, t_end] = [0, {t_end}]")
    return t_end, t_eval


def simulate_reference(model, t_end, *, method="DOP853", rtol=1e-10, atol=1e-12, t_eval=None):
    """Integrate the chain with the global Newton-Euler equations and scipy's solve_ivp.

    model: a dttmm Model; t_end > 0 (s); method "DOP853" or "RK45"; rtol, atol: solve_ivp
    tolerances; t_eval: recorded times (default 201 points over [0, t_end]), sampled from the
    integrator's dense output.  Returns a dttmm.result.Result; info holds nfev and the number of
    state variables and unknowns of the global system.  For chains with EulerBernoulliBeam
    bodies the result also holds modal_coordinates and modal_velocities (T, total modes; body
    order, a beam's v coordinates first, then w), the energies count the beams' deflection, and
    position_mass_center is each beam's deflected mass centre.  A chain built with tip="ball"
    has its tip held at its starting point (fixed in the world, a_tip = 0, also when the ground
    moves); the initial angular velocities must leave it at rest there.
    """
    t_end, t_eval = _check_args(model, t_end, method, rtol, atol, t_eval)
    prob = _Problem(model)
    y0 = prob.initial_state()
    n, nt = prob.n, len(t_eval)
    if prob.t_col >= 0:
        rk, wk, _, vik = prob.evaluate(0.0, y0)[:4]
        v_tip = vik[-1] + np.cross(wk[-1], rk[-1] @ model.body_params[-1, _LIO:_LIO + 3])
        reach = float(np.linalg.norm(model.body_params[:, _LIO:_LIO + 3], axis=1).sum())
        scale = max(1.0, float(np.abs(wk).max()) * reach)
        if np.abs(v_tip).max() > 1e-12 * scale:
            raise ValueError(f"simulate_reference: the tip is joined to a fixed point but the "
                             f"initial angular velocities move it at {v_tip} m/s")

    if prob.n_state > 0:
        prob.rhs(0.0, y0)                      # compile / load the kernels outside the timing
        t0 = time.perf_counter()
        sol = solve_ivp(prob.rhs, (0.0, t_end), y0, method=method, rtol=float(rtol),
                        atol=float(atol), dense_output=True)
        wall = time.perf_counter() - t0
        if sol.status != 0:
            raise RuntimeError(f"simulate_reference: integration failed at t = {sol.t[-1]}: "
                               f"{sol.message}")
        ys = sol.sol(t_eval).T
        if t_eval[0] == 0.0:
            ys[0] = y0
        n_steps, nfev = len(sol.t) - 1, int(sol.nfev)
    else:                                       # everything prescribed: nothing to integrate
        ys = np.zeros((nt, 0))
        wall, n_steps, nfev = 0.0, 0, 0

    rot = np.empty((nt, n, 3, 3))
    omega = np.empty((nt, n, 3))
    r_in = np.empty((nt, n, 3))
    v_in = np.empty((nt, n, 3))
    alpha = np.empty((nt, n, 3))
    force = np.empty((nt, n, 3))
    moment = np.empty((nt, n, 3))
    kinetic = np.empty(nt)
    potential = np.empty(nt)
    nm, e0 = prob.n_modal, prob.e0
    eta = np.ascontiguousarray(ys[:, e0:e0 + nm])
    eta_dot = np.ascontiguousarray(ys[:, e0 + nm:e0 + 2 * nm])
    for i, t in enumerate(t_eval):
        rk, wk, rik, vik, dk, _, ak, fk, mk, _ = prob.evaluate(t, ys[i])
        rot[i], omega[i], r_in[i], v_in[i] = rk, wk, rik, vik
        alpha[i], force[i], moment[i] = ak, fk, mk
        kinetic[i], potential[i] = chain_energies(model, rk, wk, rik, vik, dk,
                                                    ground_rotation=model.ground_state(t)[3],
                                                    eta=eta[i], eta_dot=eta_dot[i])
    r_c, r_o = point_positions(model, rot, r_in)
    for k in range(n):                          # a beam's mass centre moves with its deflection
        if prob.body_kind[k] == BEAM:
            r_c[:, k] = r_in[:, k] + np.einsum("tij,tj->ti", rot[:, k],
                                               _beam_mass_center(prob.beam_params[k],
                                                                 eta[:, prob.m_off[k]:]))

    return Result(method=f"newton-euler/{method}", t=np.array(t_eval), position_input=r_in,
                  position_mass_center=r_c, position_output=r_o, rotation=rot,
                  angular_velocity=omega, angular_acceleration=alpha, force=force, moment=moment,
                  kinetic=kinetic, potential=potential, wall_time=wall, n_steps=n_steps,
                  info={"nfev": nfev, "n_state": prob.n_state, "n_unknowns": prob.n_unknowns},
                  velocity_input=v_in,
                  modal_coordinates=eta if nm > 0 else None,
                  modal_velocities=eta_dot if nm > 0 else None)


def _beam_mass_center(bp, eta):
    """(T, 3) body-frame mass centre of a pinned beam, s / (mu L) with s = int mu p dx; eta holds
    the beam's coordinates in its first 2n columns."""
    length, nm = bp[LENGTH], int(bp[MODES])
    k = np.arange(1, nm + 1)
    sy = length * (1.0 - (-1.0) ** k) / (k * np.pi)       # int_0^L Y_k dx
    out = np.zeros((len(eta), 3))
    out[:, 0] = length / 2.0
    out[:, 1] = eta[:, :nm] @ sy / length
    out[:, 2] = eta[:, nm:2 * nm] @ sy / length
    return out
