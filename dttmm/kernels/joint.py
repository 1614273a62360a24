"""Joints with coordinates in the general loop: revolute, universal, prismatic (docs/joints.md,
"In the transfer").

A child behind such a joint is not integrated on its own: its rotation, angular velocity and
acceleration follow from its parent's and from the joint's coordinates q, which carry the
Newmark histories (q'' = c1 dq + w1_q, q' = c3 dq + w3_q, dq the step's increment).

  joint_frame          the child's frame from its parent's and the coordinates (exact)
  joint_linearization  the joint as an element of the sweep, in angular-acceleration slots:
                         f_O = Phi f_I + B nu + c      (f = [a, alpha]; nu: the coordinates' q'')
                         e_I = Psi e_O                 (e = [m, q], loads moved inboard)
                         Bl_i . e_O = tau_i            (the drive's generalized force, free q_i)
  drive_value          tau and d tau / d nu of a free coordinate's drive

kernels/sweep.py::riccati_tree_full eliminates nu leaves to root (an articulated-body step).
"""
import numpy as np
from numba import njit

from . import CONTRACT
from ..elements.drives import FORCE, MOTION, SPRING_DAMPER
from ..elements.hinges import AXIS_1, AXIS_2, BALL
from ..elements.joints import PRISMATIC, REVOLUTE, UNIVERSAL
from .so3 import expm_so3

FREE, PRESCRIBED = 1, 2          # sweep.joint_dof: 0 for a coordinate the joint does not have


@njit(cache=True, fastmath=CONTRACT)
def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


@njit(cache=True, fastmath=CONTRACT)
def _rot_about(axis, angle):
    e = np.empty((3, 3))
    expm_so3(axis * angle, e)
    return e


@njit(cache=True, fastmath=CONTRACT)
def joint_frame(kind, hp, rot_p, w_p, wd_p, q, qd, qdd, rot, w, wd, d, d_rate):
    """The child's rotation, angular velocity and acceleration (world) behind a joint with
    coordinates, from its parent's attachment frame (rot_p, w_p, wd_p) and the coordinates
    q, q', q'' (docs/joints.md, "Kinematics"); d, d_rate: a prismatic child's input point
    relative to the attachment point, and its rate (zero for the others).  Returns the
    coordinates' world directions (3, 2): u1 (and v2 of a universal joint)."""
    r0 = hp[0:9].copy().reshape((3, 3))
    n1 = hp[AXIS_1].copy()
    dirs = np.zeros((3, 2))
    u1 = rot_p @ n1
    dirs[:, 0] = u1
    d[:] = 0.0
    d_rate[:] = 0.0
    if kind == REVOLUTE:
        rot[:, :] = rot_p @ _rot_about(n1, q[0]) @ r0
        w[:] = w_p + u1 * qd[0]
        wd[:] = wd_p + u1 * qdd[0] + _cross(w_p, u1) * qd[0]
    elif kind == UNIVERSAL:
        n2 = hp[AXIS_2].copy()
        rot[:, :] = rot_p @ _rot_about(n1, q[0]) @ r0 @ _rot_about(n2, q[1])
        v2 = rot @ n2
        dirs[:, 1] = v2
        w[:] = w_p + u1 * qd[0] + v2 * qd[1]
        wd[:] = (wd_p + u1 * qdd[0] + v2 * qdd[1] + _cross(w_p, u1) * qd[0]
                 + _cross(w_p + u1 * qd[0], v2) * qd[1])
    else:   # PRISMATIC
        rot[:, :] = rot_p @ r0
        w[:] = w_p
        wd[:] = wd_p
        d[:] = u1 * q[0]
        d_rate[:] = u1 * qd[0] + _cross(w_p, d)
    return dirs


@njit(cache=True, fastmath=CONTRACT)
def n_coordinates(kind):
    if kind == UNIVERSAL:
        return 2
    if kind == REVOLUTE or kind == PRISMATIC:
        return 1
    return 0


@njit(cache=True, fastmath=CONTRACT)
def drive_value(drive, given, q, qd, c1, c3, at_start):
    """(tau, d tau / d nu) of a free coordinate's drive at (q, q'), nu = q'' (q' = c3/c1 nu +
    const, q = nu / c1 + const over the step; both held at the consistent start).  drive:
    [kind, stiffness, damping, rest] (kind -1: none); given: a FORCE drive's value (inputs)."""
    kind = int(drive[0])
    if kind == SPRING_DAMPER:
        tau = -drive[1] * (q - drive[3]) - drive[2] * qd
        slope = 0.0 if at_start else -(drive[1] + drive[2] * c3) / c1
        return tau, slope
    if kind == FORCE:
        return given, 0.0
    return 0.0, 0.0


@njit(cache=True, fastmath=CONTRACT)
def joint_linearization(kind, hp, drive, given, rot_p, w_p, wd_p, q, qd, qdd, c1, c3, at_start,
                        u, dof, tau_nu):
    """The joint's element about the guess (q, q', q'' and the parent's frame), written into
    u (12 x 13; module docstring): u[0:6, 0:6] = Phi, u[0:6, 6:9] = B (one column per
    coordinate), u[0:6, 12] = c, u[6:12, 6:12] = Psi, u[6:12, 0:3] = Bl.  dof[i]: FREE or
    PRESCRIBED per coordinate (0 past the joint's coordinates); tau_nu[i] = (tau0, tau', nu):
    the drive's tau = tau0 + tau' nu of a free coordinate, a prescribed one's nu = q''.
    A ball joint is the same element with the three angular accelerations free and tau = 0.
    Jacobians hold the terms of order 1 and c3/c1 (the parent's w and q' follow nu and alpha_P
    by c3/c1); the O(1/c1) dependence of the axes on the parent's rotation is left out: the
    constant c makes f_O exact at the guess, so Newton iterations converge to the exact step."""
    u[:, :] = 0.0
    for i in range(6):
        u[i, i] = 1.0
        u[6 + i, 6 + i] = 1.0
    for i in range(3):
        dof[i] = 0
        tau_nu[i, 0] = 0.0
        tau_nu[i, 1] = 0.0
        tau_nu[i, 2] = 0.0
    if kind == BALL:
        for i in range(3):
            u[3 + i, 6 + i] = 1.0           # alpha_O = alpha_I + nu
            u[6 + i, i] = 1.0               # m_O . e_i = 0
            dof[i] = FREE
        return
    r = 0.0 if at_start else c3 / c1       # d q' / d nu
    s = 0.0 if at_start else 1.0 / c1      # d q / d nu
    rot = np.empty((3, 3))
    w = np.empty(3)
    wd = np.empty(3)
    d = np.empty(3)
    d_rate = np.empty(3)
    dirs = joint_frame(kind, hp, rot_p, w_p, wd_p, q, qd, qdd, rot, w, wd, d, d_rate)
    u1 = dirs[:, 0].copy()
    m = n_coordinates(kind)
    for i in range(m):
        if drive[i, 0] == MOTION:
            dof[i] = PRESCRIBED
            tau_nu[i, 2] = qdd[i]
        else:
            dof[i] = FREE
            tau, slope = drive_value(drive[i], given[i], q[i], qd[i], c1, c3, at_start)
            tau_nu[i, 0] = tau - slope * qdd[i]
            tau_nu[i, 1] = slope
    if kind == PRISMATIC:
        wxu = _cross(w_p, u1)
        # a_O = a_I + u q'' + 2 w_P x u q' + alpha_P x d + w_P x (w_P x d)
        b_a = u1 + 2.0 * r * wxu + s * (_cross(wd_p, u1) + _cross(w_p, wxu))
        a_rel = (u1 * qdd[0] + 2.0 * qd[0] * wxu + _cross(wd_p, d)
                 + _cross(w_p, _cross(w_p, d)))
        for i in range(3):
            u[i, 6] = b_a[i]
            u[9 + i, 0] = u1[i]            # Bl: the force along u
        # Phi_a,alpha = -d^ (alpha_P x d);  Psi_m,q = d^ (m_I = m_O + d x q_O)
        u[0, 4], u[0, 5] = d[2], -d[1]
        u[1, 3], u[1, 5] = -d[2], d[0]
        u[2, 3], u[2, 4] = d[1], -d[0]
        u[6, 10], u[6, 11] = -d[2], d[1]
        u[7, 9], u[7, 11] = d[2], -d[0]
        u[8, 9], u[8, 10] = -d[1], d[0]
        for i in range(3):
            lin = b_a[i] * qdd[0]
            for j in range(3):
                lin += u[i, 3 + j] * wd_p[j]
            u[i, 12] = a_rel[i] - lin
        return
    # rotational joints: a passes; alpha_O = Phi alpha_I + B nu + c
    b = np.zeros((3, 2))
    b[:, 0] = u1 + r * _cross(w_p, u1)
    phi_aa = np.zeros((3, 3))
    # (c3/c1) d alpha_P x u1 q1' from w_P = c3/c1 alpha_P + const
    x = r * qd[0]
    phi_aa[0, 1], phi_aa[0, 2] = u1[2] * x, -u1[1] * x
    phi_aa[1, 0], phi_aa[1, 2] = -u1[2] * x, u1[0] * x
    phi_aa[2, 0], phi_aa[2, 1] = u1[1] * x, -u1[0] * x
    if kind == UNIVERSAL:
        v2 = dirs[:, 1].copy()
        b[:, 0] += r * _cross(u1, v2) * qd[1]
        b[:, 1] = v2 + r * _cross(w_p + u1 * qd[0], v2)
        y = r * qd[1]
        phi_aa[0, 1] += v2[2] * y
        phi_aa[0, 2] -= v2[1] * y
        phi_aa[1, 0] -= v2[2] * y
        phi_aa[1, 2] += v2[0] * y
        phi_aa[2, 0] += v2[1] * y
        phi_aa[2, 1] -= v2[0] * y
    for i in range(3):
        for j in range(3):
            u[3 + i, 3 + j] += phi_aa[i, j]
        for c in range(m):
            u[3 + i, 6 + c] = b[i, c]
            u[6 + i, c] = dirs[i, c]        # Bl: the moment about each axis
    for i in range(3):
        lin = wd_p[i]
        for j in range(3):
            lin += phi_aa[i, j] * wd_p[j]
        for c in range(m):
            lin += b[i, c] * qdd[c]
        u[3 + i, 12] = wd[i] - lin
