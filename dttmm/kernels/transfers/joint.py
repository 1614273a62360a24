"""Joints with coordinates in the general loop: every kind elements/kinds.py declares, read
from its declaration (docs/joints.md, "In the transfer").

A child behind such a joint is not integrated on its own: its rotation, angular velocity and
acceleration follow from its parent's and from the joint's coordinates q, which carry the
Newmark histories (q'' = c1 dq + w1_q, q' = c3 dq + w3_q, dq the step's increment).  Each
coordinate is a turn about, or a slide along, an axis (its slot of the hinge_params row) fixed
in the parent's frame or in the child's (kinds.py: MOTION, AXIS, TURNS, read here as constant
arrays): the turn fixed in the parent comes first, then R0, then the one fixed in the child (a
kind has at most one of each); the slides move the child's input point along axes fixed in the
parent.

  joint_offset         the child's input point from the attachment point: d = A_P sum n_i q_i
                       over the slides, and its rate
  joint_frame          the child's frame from its parent's and the coordinates (exact)
  joint_linearization  the joint as an element of the sweep, in angular-acceleration slots:
                         f_O = Phi f_I + B nu + c      (f = [a, alpha]; nu: the coordinates' q'')
                         e_I = Psi e_O                 (e = [m, q], loads moved inboard)
                         Bl_i . e_O = tau_i            (the drive's generalized force, free q_i)
  drive_value          tau and d tau / d nu of a free coordinate's drive

kernels/assembly/tree_sweep.py::riccati_tree_full eliminates nu leaves to root (an articulated-body
step).
"""
import numpy as np
from llvmlite import ir
from numba import types
from numba.core.extending import intrinsic

from .. import kernel
from ...elements.drives import COMPILED_FORCE, FORCE, MOTION, SPRING_DAMPER
from ...elements.hinges import BALL
from ...elements.kinds import (AXIS, AXIS_START, CHILD, COORDINATES, HAS_SLIDES, LIMIT_0,
                               LIMIT_SIZE, MAX_COORDINATES, MOTION as MOVES, SLIDE, TURN, TURNS)
from ..algebra.mat3 import t_cross, t_lin3, t_mm, t_mv
from ..algebra.so3 import exp_coefficients

FREE, PRESCRIBED = 1, 2          # sweep.joint_dof: 0 for a coordinate the joint does not have
ZERO3 = (0.0, 0.0, 0.0)

# The declaration's tables (elements/kinds.py) by kind code, as arrays numba compiles in as
# constant data.  Read from the tuples of tuples themselves, at a run-time kind, and with a loop
# over every coordinate slot, joint_frame took 150 ns a call against 94 ns now (a revolute joint,
# one process, CPU family 25; the four-bar calls it ~100 times a step).
_COORDINATES = np.array(COORDINATES, dtype=np.int64)
_MOVES = np.array(MOVES, dtype=np.int64)                    # (kind, coordinate): TURN, SLIDE
_AXIS_AT = np.array([[AXIS_START[a] for a in row] for row in AXIS], dtype=np.int64)  # hp slot
_TURNS = np.array(TURNS, dtype=np.int64)                     # (kind, PARENT/CHILD): i or -1
_HAS_SLIDES = np.array(HAS_SLIDES, dtype=np.int64)


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


@kernel
def joint_axis(hp, kind, i):
    """Coordinate i's axis n_i of a joint kind (its slot of the hinge_params row hp), a
    3-tuple in the frame the declaration fixes it in."""
    a = _AXIS_AT[kind, i]
    return (hp[a], hp[a + 1], hp[a + 2])


@kernel
def joint_offset(kind, hp, f_p, wp, q, qd):
    """(d, d'): the child's input point relative to the attachment point behind a joint with
    slides, and its rate, as 3-tuples: d = sum u_i q_i, d' = w_P x d + sum u_i q_i' over the
    slides, u_i = A_P n_i (f_p: A_P as a row-major 9-tuple, wp: w_P; zero without slides).
    The one offset of joint_frame, the loops' tree points (kernels/assembly/closure.py::
    tree_points) and the run's first state (run_tables._initial_deflections)."""
    d = ZERO3
    for i in range(MAX_COORDINATES):
        if _MOVES[kind, i] == SLIDE:
            d = t_lin3(1.0, d, q[i], t_mv(f_p, joint_axis(hp, kind, i)))
    v = t_cross(wp, d)
    for i in range(MAX_COORDINATES):
        if _MOVES[kind, i] == SLIDE:
            v = t_lin3(1.0, v, qd[i], t_mv(f_p, joint_axis(hp, kind, i)))
    return d, v


@kernel
def _with_coordinate(dirs, befores, i, u, before):
    """(dirs, befores), the per-coordinate 3-tuples of joint_frame, with coordinate i's set."""
    if i == 0:
        return (u, dirs[1], dirs[2]), (before, befores[1], befores[2])
    if i == 1:
        return (dirs[0], u, dirs[2]), (befores[0], before, befores[2])
    return (dirs[0], dirs[1], u), (befores[0], befores[1], before)


@kernel(entry=True)
def joint_frame(kind, hp, rot_p, w_p, wd_p, q, qd, qdd, rot, w, wd, d, d_rate):
    """The child's rotation, angular velocity and acceleration (world) behind a joint with
    coordinates, from its parent's attachment frame (rot_p, w_p, wd_p) and the coordinates
    q, q', q'' (docs/joints.md, "Kinematics"), written into rot, w, wd; d, d_rate: the child's
    input point relative to the attachment point and its rate (joint_offset; zero without
    slides).  The turn fixed in the parent, then R0, then the turn fixed in the child
    (kinds.py: TURNS), each
        u_i = F n_i,  F <- F Rot(n_i, q_i),  w' <- w' + u_i q_i'' + (w x u_i) q_i',
        w <- w + u_i q_i'
    from F = A_P, w = w_P, w' = w_P'; a slide's u_i = A_P n_i.  Returns per coordinate its
    world direction u_i and, for a turn, the angular velocity w_(i-1) it turns on (the one
    before it), as two 3-tuples of 3-tuples (zero past the joint's coordinates).  Allocates
    nothing (kernels/algebra/mat3.py's tuple algebra)."""
    r0 = (hp[0], hp[1], hp[2], hp[3], hp[4], hp[5], hp[6], hp[7], hp[8])
    f_p = (rot_p[0, 0], rot_p[0, 1], rot_p[0, 2], rot_p[1, 0], rot_p[1, 1], rot_p[1, 2],
           rot_p[2, 0], rot_p[2, 1], rot_p[2, 2])
    wp = (w_p[0], w_p[1], w_p[2])
    f = f_p
    w_out = wp
    wd_out = (wd_p[0], wd_p[1], wd_p[2])
    dirs, befores = (ZERO3, ZERO3, ZERO3), (ZERO3, ZERO3, ZERO3)
    for side in range(2):                  # PARENT, CHILD
        if side == CHILD:
            f = t_mm(f, r0)
        i = _TURNS[kind, side]
        if i < 0:
            continue
        n = joint_axis(hp, kind, i)
        u = t_mv(f, n)
        f = t_mm(f, _t_exp(t_lin3(q[i], n, 0.0, n)))
        wd_out = t_lin3(1.0, t_lin3(1.0, wd_out, qdd[i], u), qd[i], t_cross(w_out, u))
        dirs, befores = _with_coordinate(dirs, befores, i, u, w_out)
        w_out = t_lin3(1.0, w_out, qd[i], u)
    d_out, d_rate_out = ZERO3, ZERO3
    if _HAS_SLIDES[kind]:
        for i in range(MAX_COORDINATES):
            if _MOVES[kind, i] == SLIDE:
                dirs, befores = _with_coordinate(dirs, befores, i,
                                                 t_mv(f_p, joint_axis(hp, kind, i)), ZERO3)
        d_out, d_rate_out = joint_offset(kind, hp, f_p, wp, q, qd)
    for i in range(3):
        for j in range(3):
            rot[i, j] = f[3 * i + j]
        w[i] = w_out[i]
        wd[i] = wd_out[i]
        d[i] = d_out[i]
        d_rate[i] = d_rate_out[i]
    return dirs, befores


@kernel(entry=True)
def n_coordinates(kind):
    """The free coordinates of a joint kind, as its declaration says (elements/kinds.py)."""
    if kind < 0 or kind >= _COORDINATES.shape[0]:
        return 0
    return _COORDINATES[kind]


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
def stop_value(hp, i, q, qd, c1, c3, at_start):
    """(tau, d tau / d nu) of coordinate i's end stops (elements/limits.py; docs/limits.md) at
    (q, q'): past a bound a one-sided spring-damper pushes back and never pulls,
        q > upper:  tau = -max(0, k (q - upper) + c q'),
        q < lower:  tau = max(0, k (lower - q) - c q'),
    its slope -(k + c c3) / c1 while it pushes (q = nu / c1 + const, q' = c3 / c1 nu + const
    over the step; 0 at the consistent start).  hp: the joint's hinge_params row (its stops at
    LIMIT_0 + LIMIT_SIZE i: lower, upper, stiffness, damping; stiffness 0: none)."""
    j = LIMIT_0 + LIMIT_SIZE * i
    k, c = hp[j + 2], hp[j + 3]
    if k == 0.0:
        return 0.0, 0.0
    if q > hp[j + 1]:
        push = k * (q - hp[j + 1]) + c * qd
        if push > 0.0:
            return -push, 0.0 if at_start else -(k + c * c3) / c1
    elif q < hp[j]:
        push = k * (hp[j] - q) - c * qd
        if push > 0.0:
            return push, 0.0 if at_start else -(k + c * c3) / c1
    return 0.0, 0.0


@kernel
def drive_share(hp, drive, i, tau, q, qd):
    """The part of coordinate i's generalized force tau (Bl . e_O, all that acts on it) its
    drive applies: tau less its end stops' at (q, q') where the coordinate is free (a prescribed
    one's stops are not applied: its motion rules)."""
    if drive[i, 0] == MOTION:
        return tau
    return tau - stop_value(hp, i, q, qd, 1.0, 0.0, True)[0]


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
    Per coordinate (docs/joints.md, "In the transfer"; r = c3/c1 = dq'/dnu, s = 1/c1 = dq/dnu):
        a turn:   B_i = [0; u_i + r w_(i-1) x u_i + r sum_(later turns j) (u_i x u_j) q_j'],
                  Bl_i = [u_i; 0] (the moment about u_i), Phi_alpha,alpha -= r q_i' u_i^;
        a slide:  B_i = [u_i + 2 r w_P x u_i + s (w_P' x u_i + w_P x (w_P x u_i)); 0],
                  Bl_i = [0; u_i] (the force along u_i);
    with slides Phi_a,alpha = -d^ (alpha_P x d) and Psi_m,q = d^ (m_I = m_O + d x q_O); c makes
    f_O exact at the guess.  Jacobians hold the terms of order 1 and c3/c1 (the parent's w and
    q' follow nu and alpha_P by c3/c1); the O(1/c1) dependence of the axes on the parent's
    rotation, and a slide's O(c3/c1) one of its a-rows on alpha_P through w_P, are left out:
    the constant c makes f_O exact at the guess, so Newton iterations converge to the exact
    step."""
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
    dirs, before = joint_frame(kind, hp, rot_p, w_p, wd_p, q, qd, qdd, rot, w, wd, d, d_rate)
    m = n_coordinates(kind)
    for i in range(m):
        if drive[i, 0] == MOTION:
            dof[i] = PRESCRIBED
            tau_nu[i, 2] = qdd[i]
        else:
            dof[i] = FREE
            tau, slope = drive_value(drive[i], given[i], q[i], qd[i], c1, c3, at_start, forces)
            stop, stop_slope = stop_value(hp, i, q[i], qd[i], c1, c3, at_start)
            tau += stop
            slope += stop_slope
            tau_nu[i, 0] = tau - slope * qdd[i]
            tau_nu[i, 1] = slope
    wp = (w_p[0], w_p[1], w_p[2])
    wdp = (wd_p[0], wd_p[1], wd_p[2])
    phi_aa = np.zeros((3, 3))
    for c in range(m):
        ui = dirs[c]
        if _MOVES[kind, c] == TURN:
            # alpha_O = ... + u_i q_i'' + (w_(i-1) x u_i) q_i': B_i, and (c3/c1) d alpha_P x u_i
            # q_i' from w_P = c3/c1 alpha_P + const in Phi
            b = t_lin3(1.0, ui, r, t_cross(before[c], ui))
            for j in range(c + 1, m):
                if _MOVES[kind, j] == TURN:
                    b = t_lin3(1.0, b, r * qd[j], t_cross(ui, dirs[j]))
            x = r * qd[c]
            phi_aa[0, 1] += ui[2] * x
            phi_aa[0, 2] -= ui[1] * x
            phi_aa[1, 0] -= ui[2] * x
            phi_aa[1, 2] += ui[0] * x
            phi_aa[2, 0] += ui[1] * x
            phi_aa[2, 1] -= ui[0] * x
            for i in range(3):      # (by loops: docs/solver.md, "Compile time", item 8)
                u[3 + i, 6 + c] = b[i]
                u[6 + i, c] = ui[i]             # Bl: the moment about u_i
        else:
            # a_O = a_I + u q'' + 2 w_P x u q' + alpha_P x d + w_P x (w_P x d)
            wxu = t_cross(wp, ui)
            b = t_lin3(1.0, t_lin3(1.0, ui, 2.0 * r, wxu), s,
                       t_lin3(1.0, t_cross(wdp, ui), 1.0, t_cross(wp, wxu)))
            for i in range(3):
                u[i, 6 + c] = b[i]
                u[9 + i, c] = ui[i]             # Bl: the force along u_i
    if _HAS_SLIDES[kind]:
        # Phi_a,alpha = -d^ (alpha_P x d);  Psi_m,q = d^ (m_I = m_O + d x q_O)
        u[0, 4], u[0, 5] = d[2], -d[1]
        u[1, 3], u[1, 5] = -d[2], d[0]
        u[2, 3], u[2, 4] = d[1], -d[0]
        u[6, 10], u[6, 11] = -d[2], d[1]
        u[7, 9], u[7, 11] = d[2], -d[0]
        u[8, 9], u[8, 10] = -d[1], d[0]
        dt = (d[0], d[1], d[2])
        # a_O - a_I = sum (u_i q_i'' + 2 q_i' w_P x u_i) + alpha_P x d + w_P x (w_P x d)
        a_rel = ZERO3
        for c in range(m):
            if _MOVES[kind, c] == SLIDE:
                a_rel = t_lin3(1.0, t_lin3(1.0, a_rel, qdd[c], dirs[c]), 2.0 * qd[c],
                               t_cross(wp, dirs[c]))
        a_rel = t_lin3(1.0, t_lin3(1.0, a_rel, 1.0, t_cross(wdp, dt)), 1.0,
                       t_cross(wp, t_cross(wp, dt)))
        for i in range(3):
            lin = 0.0
            for c in range(m):
                lin += u[i, 6 + c] * qdd[c]
            for j in range(3):
                lin += u[i, 3 + j] * wd_p[j]
            u[i, 12] = a_rel[i] - lin
    # alpha_O = Phi alpha_I + B nu + c
    for i in range(3):
        for j in range(3):
            u[3 + i, 3 + j] += phi_aa[i, j]
    for i in range(3):
        lin = wd_p[i]
        for j in range(3):
            lin += phi_aa[i, j] * wd_p[j]
        for c in range(m):
            lin += u[3 + i, 6 + c] * qdd[c]
        u[3 + i, 12] = wd[i] - lin
