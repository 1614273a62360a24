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
Elastic hinges add no rows: d_k'' = a_k - a_out_{k-1}.

The right-hand side is numba-compiled; the Python wrapper only evaluates the ground motion and
the applied loads at time t and hands them to the kernel as arrays.
"""
import math
import time

import numba
import numpy as np
from scipy.integrate import solve_ivp

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
def _assemble(rot, omega, defl, q_el, m_el, body_params, hinge_kind, f_col, m_col, n_unknowns,
              gravity, a_g, wd_g, forces, torques):
    """The global Newton-Euler system  S x = b  for x = [a_0, alpha_0, ..., a_{n-1},
    alpha_{n-1}, reactions].  Column f_col[k] (m_col[k]) holds the reaction force (couple) of
    hinge k, or -1 when the hinge has none; the matching constraint equation uses the same row
    index, so S is square."""
    n = rot.shape[0]
    s = np.zeros((n_unknowns, n_unknowns))
    b = np.zeros(n_unknowns)
    for k in range(n):
        p = body_params[k]
        mass = p[_MASS]
        a = rot[k]
        w = omega[k]
        rho_c = a @ _vec3(p, _LIC)
        rho_o = a @ _vec3(p, _LIO)
        j_w = a @ _mat3(p, _JI) @ a.T
        hc = _hat(rho_c)
        rn, re = 6 * k, 6 * k + 3          # Newton rows, Euler rows
        ca, cal = 6 * k, 6 * k + 3         # a_k, alpha_k columns
        weight = mass * gravity + forces[k]
        # Newton: M a - M hat(rho_c) alpha - F_k + F_{k+1} = M g + f - M w x (w x rho_c) + q_k - q_{k+1}
        bn = weight - mass * _cross(w, _cross(w, rho_c))
        # Euler about I: J alpha + M hat(rho_c) a - N_k + N_{k+1} + hat(rho_o + d_{k+1}) F_{k+1}
        #                = -w x J w + rho_c x (M g + f) + tau + m_k - m_{k+1} - (rho_o + d_{k+1}) x q_{k+1}
        be = -_cross(w, j_w @ w) + _cross(rho_c, weight) + torques[k]
        for i in range(3):
            s[rn + i, ca + i] = mass
            for j in range(3):
                s[rn + i, cal + j] = -mass * hc[i, j]
                s[re + i, cal + j] = j_w[i, j]
                s[re + i, ca + j] = mass * hc[i, j]
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
    return s, b


@numba.njit(cache=True)
def _solve_dynamics(y, body_params, hinge_kind, hinge_params, q_off, w_off, d_off, f_col, m_col,
                    n_unknowns, gravity, r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques):
    """Kinematics plus the solved accelerations and hinge loads of every body."""
    rot, omega, r_in, v_in, defl, defl_rate = _kinematics(
        y, body_params, hinge_kind, hinge_params, q_off, w_off, d_off, r_g, v_g, rot_g, w_g)
    q_el, m_el = _elastic_loads(rot, omega, defl, defl_rate, hinge_kind, hinge_params, rot_g, w_g)
    s, b = _assemble(rot, omega, defl, q_el, m_el, body_params, hinge_kind, f_col, m_col,
                     n_unknowns, gravity, a_g, wd_g, forces, torques)
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
    return rot, omega, r_in, v_in, defl, acc, alpha, force, moment


@numba.njit(cache=True)
def rhs_kernel(y, body_params, hinge_kind, hinge_params, q_off, w_off, d_off, f_col, m_col,
               n_unknowns, gravity, r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques):
    """dy/dt of the state [quaternions, angular velocities, (d, d') of elastic hinges]."""
    rot, omega, r_in, v_in, defl, acc, alpha, force, moment = _solve_dynamics(
        y, body_params, hinge_kind, hinge_params, q_off, w_off, d_off, f_col, m_col, n_unknowns,
        gravity, r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques)
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
        return (y, self.body_params, self.kinds, self.hinge_params, self.q_off, self.w_off,
                self.d_off, self.f_col, self.m_col, self.n_unknowns, self.gravity,
                r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques)

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
    state variables and unknowns of the global system.
    """
    t_end, t_eval = _check_args(model, t_end, method, rtol, atol, t_eval)
    prob = _Problem(model)
    y0 = prob.initial_state()
    n, nt = prob.n, len(t_eval)

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
    for i, t in enumerate(t_eval):
        rk, wk, rik, vik, dk, _, ak, fk, mk = prob.evaluate(t, ys[i])
        rot[i], omega[i], r_in[i], v_in[i] = rk, wk, rik, vik
        alpha[i], force[i], moment[i] = ak, fk, mk
        kinetic[i], potential[i] = chain_energies(model, rk, wk, rik, vik, dk,
                                                    ground_rotation=model.ground_state(t)[3])
    r_c, r_o = point_positions(model, rot, r_in)

    return Result(method=f"newton-euler/{method}", t=np.array(t_eval), position_input=r_in,
                  position_mass_center=r_c, position_output=r_o, rotation=rot,
                  angular_velocity=omega, angular_acceleration=alpha, force=force, moment=moment,
                  kinetic=kinetic, potential=potential, wall_time=wall, n_steps=n_steps,
                  info={"nfev": nfev, "n_state": prob.n_state, "n_unknowns": prob.n_unknowns},
                  velocity_input=v_in)
