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

kernels/assembly/sweep.py::riccati_tree_full eliminates nu leaves to root (an articulated-body
step).
"""
import numpy as np
from llvmlite import ir
from numba import types
from numba.core.extending import intrinsic

from .. import kernel
from ...elements.drives import COMPILED_FORCE, FORCE, MOTION, SPRING_DAMPER
from ...elements.hinges import AXIS_1, AXIS_2, BALL
from ...elements.joints import PRISMATIC, REVOLUTE, UNIVERSAL
from ...elements.kinds import COORDINATES
from ..algebra.mat3 import t_cross, t_lin3, t_mm, t_mv
from ..algebra.so3 import exp_coefficients

FREE, PRESCRIBED = 1, 2          # sweep.joint_dof: 0 for a coordinate the joint does not have


@kernel
def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


@kernel
def _t_exp(phi):
    """exp(phi^) as a row-major 9-tuple (so3.expm_so3's Rodrigues formula and series, on
    values)."""
    th2 = phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]
    a, b = exp_coefficients(th2)
    d = 1.0 - b * th2
    return (b * phi[0] * phi[0] + d, b * phi[0] * phi[1] - a * phi[2],
            b * phi[0] * phi[2] + a * phi[1], b * phi[1] * phi[0] + a * phi[2],
            b * phi[1] * phi[1] + d, b * phi[1] * phi[2] - a * phi[0],
            b * phi[2] * phi[0] - a * phi[1], b * phi[2] * phi[1] + a * phi[0],
            b * phi[2] * phi[2] + d)


@kernel(entry=True)
def joint_frame(kind, hp, rot_p, w_p, wd_p, q, qd, qdd, rot, w, wd, d, d_rate):
    """The child's rotation, angular velocity and acceleration (world) behind a joint with
    coordinates, from its parent's attachment frame (rot_p, w_p, wd_p) and the coordinates
    q, q', q'' (docs/joints.md, "Kinematics"); d, d_rate: a prismatic child's input point
    relative to the attachment point, and its rate (zero for the others).  Returns the
    coordinates' world directions u1 and v2 (a universal joint's second; zero for the others)
    as 3-tuples.  Allocates nothing (kernels/algebra/mat3.py's tuple algebra)."""
    r0 = (hp[0], hp[1], hp[2], hp[3], hp[4], hp[5], hp[6], hp[7], hp[8])
    a1 = AXIS_1.start
    n1 = (hp[a1], hp[a1 + 1], hp[a1 + 2])
    f_p = (rot_p[0, 0], rot_p[0, 1], rot_p[0, 2], rot_p[1, 0], rot_p[1, 1], rot_p[1, 2],
           rot_p[2, 0], rot_p[2, 1], rot_p[2, 2])
    wp = (w_p[0], w_p[1], w_p[2])
    u1 = t_mv(f_p, n1)
    v2 = (0.0, 0.0, 0.0)
    d_out = (0.0, 0.0, 0.0)
    d_rate_out = (0.0, 0.0, 0.0)
    if kind == REVOLUTE:
        f = t_mm(t_mm(f_p, _t_exp(t_lin3(q[0], n1, 0.0, n1))), r0)
        w_out = t_lin3(1.0, wp, qd[0], u1)
        wd_out = t_lin3(1.0, t_lin3(1.0, (wd_p[0], wd_p[1], wd_p[2]), qdd[0], u1), qd[0],
                        t_cross(wp, u1))
    elif kind == UNIVERSAL:
        a2 = AXIS_2.start
        n2 = (hp[a2], hp[a2 + 1], hp[a2 + 2])
        f = t_mm(t_mm(t_mm(f_p, _t_exp(t_lin3(q[0], n1, 0.0, n1))), r0),
                 _t_exp(t_lin3(q[1], n2, 0.0, n2)))
        v2 = t_mv(f, n2)
        w_out = t_lin3(1.0, t_lin3(1.0, wp, qd[0], u1), qd[1], v2)
        # wd = wd_P + u1 q1'' + v2 q2'' + (w_P x u1) q1' + ((w_P + u1 q1') x v2) q2'
        wd_out = t_lin3(1.0, t_lin3(1.0, (wd_p[0], wd_p[1], wd_p[2]), qdd[0], u1), qdd[1], v2)
        wd_out = t_lin3(1.0, t_lin3(1.0, wd_out, qd[0], t_cross(wp, u1)), qd[1],
                        t_cross(t_lin3(1.0, wp, qd[0], u1), v2))
    else:   # PRISMATIC
        f = t_mm(f_p, r0)
        w_out = wp
        wd_out = (wd_p[0], wd_p[1], wd_p[2])
        d_out = t_lin3(q[0], u1, 0.0, u1)
        d_rate_out = t_lin3(qd[0], u1, 1.0, t_cross(wp, d_out))
    for i in range(3):
        for j in range(3):
            rot[i, j] = f[3 * i + j]
        w[i] = w_out[i]
        wd[i] = wd_out[i]
        d[i] = d_out[i]
        d_rate[i] = d_rate_out[i]
    return u1, v2


@kernel(entry=True)
def n_coordinates(kind):
    """The free coordinates of a joint kind, as its declaration says (elements/kinds.py)."""
    if kind < 0 or kind >= len(COORDINATES):
        return 0
    return COORDINATES[kind]


@intrinsic
def call_force(typingctx, address, t, q, qd):
    """f(t, q, q') of the C function float64(float64, float64, float64) at address (an int64: a
    compiled JointForce's callback, elements/drives.py::compiled_force): an indirect call, so
    that the loop is compiled once for every such function (numba's first-class functions
    would type each callback apart, or box a typed list on every call)."""
    sig = types.float64(types.int64, types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        fnty = ir.FunctionType(ir.DoubleType(), [ir.DoubleType()] * 3)
        return builder.call(builder.inttoptr(args[0], fnty.as_pointer()), args[1:])
    return sig, codegen


@kernel(entry=True)
def drive_value(drive, given, q, qd, c1, c3, at_start, forces):
    """(tau, d tau / d nu) of a free coordinate's drive at (q, q'), nu = q'' (q' = c3/c1 nu +
    const, q = nu / c1 + const over the step; both held at the consistent start).  drive:
    [kind, stiffness, damping, rest] (kind -1: none); given: a FORCE drive's value, or the part
    of a spring-damper's force known in time (a PDTracking's kp target + kd target' +
    feedforward, a JointForce of time alone; 0 for a SpringDamper; run_tables.joint_drives):
        tau = -k (q - rest) - c q' + given;
    without a drive tau = given (0 in a run: dynamics.linearize's generalized force input).
    A COMPILED_FORCE drive is f(t, q, q'), f the C callback at the address forces[int(rest)]
    (a numba JointForce's, elements/drives.py::compiled_force), at the step's time t = given,
    its slope by forward differences: d tau / d nu = (df/dq + c3 df/dq') / c1."""
    kind = int(drive[0])
    if kind == SPRING_DAMPER:
        tau = -drive[1] * (q - drive[3]) - drive[2] * qd + given
        slope = 0.0 if at_start else -(drive[1] + drive[2] * c3) / c1
        return tau, slope
    if kind == FORCE:
        return given, 0.0
    if kind == COMPILED_FORCE:
        address = forces[int(drive[3])]
        tau = call_force(address, given, q, qd)
        if at_start:
            return tau, 0.0
        dq = 1e-7 * (1.0 + abs(q))
        dqd = 1e-7 * (1.0 + abs(qd))
        f_q = (call_force(address, given, q + dq, qd) - tau) / dq
        f_qd = (call_force(address, given, q, qd + dqd) - tau) / dqd
        return tau, (f_q + c3 * f_qd) / c1
    return given, 0.0       # no drive: given is 0, or dynamics.linearize's input on the coordinate


@kernel
def joint_linearization(kind, hp, drive, given, rot_p, w_p, wd_p, q, qd, qdd, c1, c3, at_start,
                        u, dof, tau_nu, forces):
    """The joint's element about the guess (q, q', q'' and the parent's frame), written into
    u (12 x 13; module docstring): u[0:6, 0:6] = Phi, u[0:6, 6:9] = B (one column per
    coordinate), u[0:6, 12] = c, u[6:12, 6:12] = Psi, u[6:12, 0:3] = Bl.  dof[i]: FREE or
    PRESCRIBED per coordinate (0 past the joint's coordinates); tau_nu[i] = (tau0, tau', nu):
    the drive's tau = tau0 + tau' nu of a free coordinate, a prescribed one's nu = q''
    (drive_value; forces: the compiled JointForces' callbacks' addresses).
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
    u1_t, v2_t = joint_frame(kind, hp, rot_p, w_p, wd_p, q, qd, qdd, rot, w, wd, d, d_rate)
    u1 = np.array(u1_t)
    dirs = np.zeros((3, 2))
    for i in range(3):
        dirs[i, 0] = u1_t[i]
        dirs[i, 1] = v2_t[i]
    m = n_coordinates(kind)
    for i in range(m):
        if drive[i, 0] == MOTION:
            dof[i] = PRESCRIBED
            tau_nu[i, 2] = qdd[i]
        else:
            dof[i] = FREE
            tau, slope = drive_value(drive[i], given[i], q[i], qd[i], c1, c3, at_start, forces)
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
    c = _cross(w_p, u1)
    for i in range(3):      # (by loops: docs/solver.md, "Compile time", item 8)
        b[i, 0] = u1[i] + r * c[i]
    phi_aa = np.zeros((3, 3))
    # (c3/c1) d alpha_P x u1 q1' from w_P = c3/c1 alpha_P + const
    x = r * qd[0]
    phi_aa[0, 1], phi_aa[0, 2] = u1[2] * x, -u1[1] * x
    phi_aa[1, 0], phi_aa[1, 2] = -u1[2] * x, u1[0] * x
    phi_aa[2, 0], phi_aa[2, 1] = u1[1] * x, -u1[0] * x
    if kind == UNIVERSAL:
        v2 = dirs[:, 1].copy()
        c = _cross(u1, v2)
        w_v = _cross(w_p + u1 * qd[0], v2)
        for i in range(3):
            b[i, 0] += r * c[i] * qd[1]
            b[i, 1] = v2[i] + r * w_v[i]
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
