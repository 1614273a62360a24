"""The reference's right-hand side: kinematics, hinge and joint laws, the global Newton-Euler
system with its reactions and closing joints, solved at every evaluation (the formulation:
newton_euler.py).  The beams' terms are in beam_terms.py, the closing joints' rows and solve in
closure_rows.py.

One compiled copy runs every kind of model: what a model uses is read from its tables at run
time (docs/reference.md, "Compile time")."""
import math

import numpy as np

from ..elements.hinges import FIXED
from ..elements.kinds import DEFLECTS
from ..kernels import kernel
from ..kernels.algebra.mat3 import matmul, matvec, put1, put2

from .rows import (_AXIS, _AXIS_START, _BAXES, _BEAM, _BMU, _BSTIFF, _CHILD, _CR, _CT, _FRAME,
                   _GAP_A, _GAP_WORLD, _HAS_SLIDES, _JI, _KR, _KT, _LIC, _LIO, _MASS, _MAXC,
                   _MOTION, _N_COORDINATES, _R0, _RIGID, _ROD, _SLIDE, _TURN,
                   _UNDECLARED_BODY_KIND)
from .beam_terms import _beam_end, _beam_terms, _beam_terms_exact, _flex_size, _modal_size
from .closure_rows import _closure_rows, _solve_least_closure_force
from .strain_rod import rod_end, rod_state, rod_terms
from .rotations import _cross, _hat, _log_rot, _mat3, _quat_to_rot, _vec3


@kernel
def _rot_about(n, q):
    """Rot(n, q) = exp(q n^) for a unit axis n (Rodrigues)."""
    k = _hat(n)
    return np.eye(3) + math.sin(q) * k + (1.0 - math.cos(q)) * matmul(k, k)


@kernel
def _joint_coordinates(y, joints, k, kind):
    """(q, q') of joint k, each padded to MAX_COORDINATES entries (newton_euler.py's docstring,
    "Joints with coordinates"; joints = (c_off, c0, n_coord, ...): the coordinates at
    y[c0 + c_off[k] + i], their rates at y[c0 + n_coord + c_off[k] + i])."""
    c_off, c0, n_coord = joints[0], joints[1], joints[2]
    q = np.zeros(_MAXC)
    qd = np.zeros(_MAXC)
    o = c_off[k]
    for i in range(_N_COORDINATES[kind]):
        q[i] = y[c0 + o + i]
        qd[i] = y[c0 + n_coord + o + i]
    return q, qd


@kernel
def _joint_axis(h, kind, i):
    """Coordinate i's axis n_i of a joint kind (its slot of the hinge_params row h), in the
    frame its declaration fixes it in (elements/kinds.py)."""
    return _vec3(h, _AXIS_START[_AXIS[kind][i]])


@kernel
def _joint_frame(kind, h, a_in, w_in, q, qd):
    """Child frame behind a joint with coordinates (newton_euler.py's docstring), from its
    declaration (elements/kinds.py): its rotation A = A_P R_P R0 R_C (R_P, R_C: the turns fixed
    in the parent and in the child), angular velocity w = w_P + sum over turns u_i q_i' (u_i =
    F n_i, F the frame before turn i), and the offset d = A_P sum n_i q_i of its input point
    from the attachment point over the slides, with its rate d' = w_P x d + A_P sum n_i q_i'
    (zero without slides)."""
    r0 = _mat3(h, _R0)
    rot = a_in.copy()
    w = w_in.copy()
    for which in range(2):
        if which == _CHILD:
            rot = matmul(rot, r0)
        for i in range(_MAXC):
            if _MOTION[kind][i] == _TURN and _FRAME[kind][i] == which:
                n = _joint_axis(h, kind, i)
                w = w + matvec(rot, n) * qd[i]
                rot = matmul(rot, _rot_about(n, q[i]))
    d = np.zeros(3)
    v = np.zeros(3)
    for i in range(_MAXC):
        if _MOTION[kind][i] == _SLIDE:
            u = matvec(a_in, _joint_axis(h, kind, i))
            d = d + u * q[i]
            v = v + u * qd[i]
    return rot, w, d, _cross(w_in, d) + v


@kernel
def _joint_directions(kind, h, a_in, rot):
    """World directions s_i (columns, 3 x MAX_COORDINATES) of a joint's coordinates: a slide's
    u = A_P n, a turn's u = A_P n fixed in the parent or A n fixed in the child (a joint has at
    most one turn in each frame: elements/kinds.py); and the number of coordinates."""
    s = np.zeros((3, _MAXC))
    nc = _N_COORDINATES[kind]
    for i in range(nc):
        frame = rot if _MOTION[kind][i] == _TURN and _FRAME[kind][i] == _CHILD else a_in
        put1(s[:, i], matvec(frame, _joint_axis(h, kind, i)))
    return s, nc


@kernel
def _joint_velocity_terms(kind, dirs, w_in, w, d, qd):
    """Velocity parts of a joint's constraint rows (newton_euler.py's docstring): of the child's
    angular acceleration, sum over turns (w_(i-1) x u_i) q_i', with w_(i-1) = w_P for the turn
    fixed in the parent and the child's w for the one fixed in it (w x u = (w_(i-1) + u q')
    x u); of its input point's acceleration relative to the attachment point's (with slides),
    w_P x (w_P x d) + 2 w_P x sum u_i q_i' over the slides (revolute: (w_P x u) q'; universal:
    (w_P x u1) q1' + (w x v2) q2'; prismatic: w_P x (w_P x d) + 2 w_P x u q')."""
    rot_v = np.zeros(3)
    slide_v = np.zeros(3)
    if _HAS_SLIDES[kind]:
        slide_v = _cross(w_in, _cross(w_in, d))
    for i in range(_N_COORDINATES[kind]):
        u = np.ascontiguousarray(dirs[:, i])
        if _MOTION[kind][i] == _SLIDE:
            slide_v = slide_v + 2.0 * qd[i] * _cross(w_in, u)
        elif _FRAME[kind][i] == _CHILD:
            rot_v = rot_v + qd[i] * _cross(w, u)
        else:
            rot_v = rot_v + qd[i] * _cross(w_in, u)
    return rot_v, slide_v


@kernel
def _rod_state(k, rods, y, e0, n_modal, m_off):
    """Strain rod k's stations (reference/strain_rod.py::rod_state) and its q, q'."""
    nq = rods[0][k]
    o = m_off[k]
    q = np.ascontiguousarray(y[e0 + o:e0 + o + nq])
    qd = np.ascontiguousarray(y[e0 + n_modal + o:e0 + n_modal + o + nq])
    phi = np.ascontiguousarray(rods[3][k, :, :, :, :nq])
    return rod_state(rods[1][k], rods[2][k], phi, q, qd), q, qd


@kernel
def _kinematics(y, body_params, hinge_kind, hinge_params, body_kind, beam_params, shape_vec,
                shape_mat, q_off, w_off, d_off, m_off, e0, n_modal, r_g, v_g, rot_g, w_g, topology,
                attachment_point, joints, rods):
    """Rotations, angular velocities, input-point positions / velocities and the elastic
    deflections and slides (world) of every body, from the state and the ground motion (a
    prismatic joint's offset d = A_P n q and its rate take the deflection's place); and each body's
    output point and section: rho_O = r_O - r_I, A_O, w_O, the velocity parts of a_O and
    alpha_O, (beams) B_r, B_t padded to the widest beam's 2n columns, and v_O.  Also, per body k
    with a parent P, where its hinge attaches (newton_euler.py's docstring, "Attachment points"):
    rho_att[k] = r_att,k - r_in,P (A_P x_k on a rigid parent, x_k = attachment_point[k] in its
    frame; a beam parent's rho_O) and acc_v_att[k], the velocity part of a_att,k (w_P x (w_P x
    rho_att,k) on a rigid parent, the beam's a_O velocity part); a root's rho_att is its place
    on the ground from the ground point, A_g x_k (x_k in the ground frame), and its acc_v_att
    zero (the ground's known w_g' x rho_att + w_g x (w_g x rho_att) join a_g where it is used,
    _ground_place_acceleration)."""
    n = body_params.shape[0]
    n2max = 2 * shape_vec.shape[2]
    n2max = max(n2max, rods[3].shape[4])
    rot = np.empty((n, 3, 3))
    omega = np.empty((n, 3))
    r_in = np.empty((n, 3))
    v_in = np.empty((n, 3))
    defl = np.zeros((n, 3))
    defl_rate = np.zeros((n, 3))
    rho_o = np.empty((n, 3))
    v_o = np.empty((n, 3))
    rot_o = np.empty((n, 3, 3))
    omega_o = np.empty((n, 3))
    acc_v = np.empty((n, 3))
    alpha_v = np.zeros((n, 3))
    b_r = np.zeros((n, 3, n2max))
    b_t = np.zeros((n, 3, n2max))
    rho_att = np.zeros((n, 3))
    acc_v_att = np.zeros((n, 3))
    parent = topology[0]
    for k in range(n):           # parents first (Model.parent[k] < k)
        kp = parent[k]
        if kp < 0:               # its place on the ground: r_g + A_g x_k, v_g + w_g x (A_g x_k)
            arm = matvec(rot_g, attachment_point[k])
            put1(rho_att[k], arm)
            r_prev, v_prev = r_g + arm, v_g + _cross(w_g, arm)
        elif body_kind[kp] == _BEAM or body_kind[kp] == _ROD:   # its one attachment point: its
            # output point
            put1(rho_att[k], rho_o[kp])
            put1(acc_v_att[k], acc_v[kp])
            r_prev, v_prev = r_in[kp] + rho_o[kp], v_o[kp]
        elif body_kind[kp] == _RIGID:
            # a rigid parent's attachment point x_k (its output point l_IO or a named point):
            # r_att = r_in,P + A_P x_k,  v_att = v_in,P + w_P x rho_att,
            # a_att = a_P + alpha_P x rho_att + w_P x (w_P x rho_att)
            arm = matvec(rot[kp], attachment_point[k])
            v_arm = _cross(omega[kp], arm)
            put1(rho_att[k], arm)
            put1(acc_v_att[k], _cross(omega[kp], v_arm))
            r_prev, v_prev = r_in[kp] + arm, v_in[kp] + v_arm
        else:
            raise ValueError(_UNDECLARED_BODY_KIND)
        # the inboard frame: the parent's output section (a rigid parent's own frame, A_O = A,
        # w_O = w, whichever of its points the hinge is at; a beam's end section), or the ground
        if hinge_kind[k] == FIXED:   # welded to the inboard frame
            a_in = rot_g if kp < 0 else rot_o[kp]
            w_in = w_g if kp < 0 else omega_o[kp]
            put2(rot[k], matmul(a_in, _mat3(hinge_params[k], _R0)))
            put1(omega[k], w_in)
        elif joints[0][k] >= 0:  # a joint with coordinates, on the inboard frame
            a_in = rot_g if kp < 0 else rot_o[kp]
            w_in = w_g if kp < 0 else omega_o[kp]
            q, qd = _joint_coordinates(y, joints, k, hinge_kind[k])
            rot_k, omega_k, defl_k, defl_rate_k = _joint_frame(
                hinge_kind[k], hinge_params[k], a_in, w_in, q, qd)
            put2(rot[k], rot_k)
            put1(omega[k], omega_k)
            put1(defl[k], defl_k)
            put1(defl_rate[k], defl_rate_k)
        else:
            put2(rot[k], _quat_to_rot(y[q_off[k]:q_off[k] + 4]))
            put1(omega[k], y[w_off[k]:w_off[k] + 3])
        if DEFLECTS[hinge_kind[k]]:
            put1(defl[k], y[d_off[k]:d_off[k] + 3])
            put1(defl_rate[k], y[d_off[k] + 3:d_off[k] + 6])
        put1(r_in[k], r_prev + defl[k])
        put1(v_in[k], v_prev + defl_rate[k])
        if body_kind[k] == _BEAM:
            nm2 = _modal_size(beam_params[k])
            o = m_off[k]
            rho, v_rel, ro, wo, av, alv, br, bt = _beam_end(
                beam_params[k], shape_vec[k], shape_mat[k], rot[k], omega[k],
                y[e0 + o:e0 + o + nm2],
                y[e0 + n_modal + o:e0 + n_modal + o + nm2])
            put1(rho_o[k], rho)
            put2(rot_o[k], ro)
            put1(omega_o[k], wo)
            put1(acc_v[k], av)
            put1(alpha_v[k], alv)
            put2(b_r[k, :, :nm2], br)
            put2(b_t[k, :, :nm2], bt)
        elif body_kind[k] == _ROD:
            state, _, _ = _rod_state(k, rods, y, e0, n_modal, m_off)
            rho, v_rel, ro, wo, av, alv, br, bt = rod_end(state, rot[k], omega[k])
            put1(rho_o[k], rho)
            put2(rot_o[k], ro)
            put1(omega_o[k], wo)
            put1(acc_v[k], av)
            put1(alpha_v[k], alv)
            nq = rods[0][k]
            put2(b_r[k, :, :nq], br)
            put2(b_t[k, :, :nq], bt)
        elif body_kind[k] == _RIGID:
            rho = matvec(rot[k], _vec3(body_params[k], _LIO))
            v_rel = _cross(omega[k], rho)
            put1(rho_o[k], rho)
            put2(rot_o[k], rot[k])
            put1(omega_o[k], omega[k])
            put1(acc_v[k], _cross(omega[k], v_rel))
        else:
            raise ValueError(_UNDECLARED_BODY_KIND)
        put1(v_o[k], v_in[k] + v_rel)
    return (rot, omega, r_in, v_in, defl, defl_rate, rho_o, rot_o, omega_o, acc_v, alpha_v,
            b_r, b_t, v_o, rho_att, acc_v_att)


@kernel
def _elastic_loads(rot, omega, rot_o, omega_o, defl, defl_rate, hinge_kind, hinge_params, rot_g,
                   w_g, parent):
    """Force q and couple m every elastic hinge exerts on its outboard body (world; zero rows for
    the other hinges).  The hinge's inboard frame is the inboard body's output section (A_O,
    w_O): the body itself for a rigid body, the deflected end section for a beam."""
    n = rot.shape[0]
    q = np.zeros((n, 3))
    m = np.zeros((n, 3))
    for k in range(n):
        if not DEFLECTS[hinge_kind[k]]:
            continue
        h = hinge_params[k]
        a_in = rot_g if parent[k] < 0 else rot_o[parent[k]]
        w_in = w_g if parent[k] < 0 else omega_o[parent[k]]
        d_b = matvec(a_in.T, defl[k])
        dd_b = matvec(a_in.T, defl_rate[k])
        put1(q[k], -matvec(a_in, matvec(_mat3(h, _KT), d_b) + matvec(_mat3(h, _CT), dd_b)))
        psi = _log_rot(matmul(matmul(a_in.T, rot[k]), _mat3(h, _R0).T))
        w_rel_b = matvec(a_in.T, omega[k] - w_in)
        put1(m[k], -matvec(a_in, matvec(_mat3(h, _KR), psi) + matvec(_mat3(h, _CR), w_rel_b)))
    return q, m


@kernel
def _joint_rows(s, b, k, kind, h, kp, a_in, w_in, alpha_in, rot, w, d, qd, b_t_in, pce, f_col,
                m_col, joints):
    """Joint k's share of the global system (newton_euler.py's docstring, "Joints with
    coordinates"), on top of the weld's rows that _assemble wrote (a_k = a_O,P, alpha_k =
    alpha_O,P): each coordinate's -s_i q_i'' in the rotation rows (revolute, universal) or the
    translation rows (slide), the velocity terms, the slide's alpha_P x d, and the coordinate rows
        s_i . N_k (or F_k) = tau_i     (a free coordinate: the drive's generalized force)
        q_i'' = q_p''(t)               (a prescribed coordinate),
    both from joints[5] (drive_value).  (a_in, w_in): the parent's output section or the ground
    frame (kp < 0); alpha_in: the velocity part of the parent's alpha_O (the ground's angular
    acceleration for kp < 0); b_t_in, pce: the parent beam's B_t and first modal column."""
    c_off, c_col0, prescribed, drive_value = joints[0], joints[3], joints[4], joints[5]
    dirs, nc = _joint_directions(kind, h, a_in, rot)
    rot_v, slide_v = _joint_velocity_terms(kind, dirs, w_in, w, d, qd)
    rf, rm = f_col[k], m_col[k]
    for i in range(nc):
        # the rows (and reaction) a coordinate moves: a slide's the force's, a turn's the couple's
        rs = rf if _MOTION[kind][i] == _SLIDE else rm
        c = c_off[k] + i
        cq = c_col0 + c
        for j in range(3):
            s[rs + j, cq] = -dirs[j, i]
        if prescribed[c]:
            s[cq, cq] = 1.0
        else:
            for j in range(3):
                s[cq, rs + j] = dirs[j, i]
        b[cq] = drive_value[c]
    for j in range(3):
        b[rm + j] += rot_v[j]
        b[rf + j] += slide_v[j]
    if _HAS_SLIDES[kind]:
        # a_k - ... - alpha_O,P x d = ...: on the left d^ alpha_O,P, with alpha_O,P =
        # alpha_P + B_t eta''_P + alpha_in; alpha_in x d on the right
        hd = _hat(d)
        b_v = _cross(alpha_in, d)
        for i in range(3):
            b[rf + i] += b_v[i]
        if kp >= 0:
            hdb = matmul(hd, b_t_in)
            for i in range(3):
                for j in range(3):
                    s[rf + i, 6 * kp + 3 + j] += hd[i, j]
                for j in range(hdb.shape[1]):
                    s[rf + i, pce + j] += hdb[i, j]


@kernel
def _assemble(y, rot, omega, defl, rho_o, rot_o, omega_o, acc_v, alpha_v, b_r, b_t, rho_att,
              acc_v_att, q_el, m_el, body_params, hinge_kind, hinge_params, body_kind,
              beam_params, shape_vec, shape_mat, m_off, e0, n_modal, e_col0, f_col, m_col, loops,
              n_unknowns, gravity, a_g, rot_g, w_g, wd_g, forces, torques, line_loads, topology,
              joints, exact, rods):
    """The global Newton-Euler system  S x = b  for x = [a_0, alpha_0, ..., a_{n-1},
    alpha_{n-1}, reactions, modal accelerations].  Column f_col[k] (m_col[k]) holds the reaction
    force (couple) of hinge k, or -1 when the hinge has none; the matching constraint equation
    uses the same row index, so S is square.  Beam k's modal accelerations sit in the columns
    e_col0 + m_off[k] + (0..2n-1), its modal equations in the same rows; its coordinates and
    rates are y[e0 + m_off[k] + ...] and y[e0 + n_modal + m_off[k] + ...].  A joint with
    coordinates has both reaction columns and its coordinates' accelerations in the columns
    joints[3] + c_off[k] + (0, 1), its coordinate rows in the same rows (_joint_rows).  Hinge k
    attaches at rho_att[k] from its parent's input point, with the velocity part acc_v_att[k] of
    that point's acceleration (_kinematics; newton_euler.py's docstring, "Attachment points")."""
    n = rot.shape[0]
    parent, child_start, child_list = topology
    s = np.zeros((n_unknowns, n_unknowns))
    b = np.zeros(n_unknowns)
    for k in range(n):
        p = body_params[k]
        a = rot[k]
        w = omega[k]
        rn, re = 6 * k, 6 * k + 3          # Newton rows, Euler rows
        ca, cal = 6 * k, 6 * k + 3         # a_k, alpha_k columns
        nm2 = 0
        ce = -1
        geo = np.zeros((3, 0))
        if body_kind[k] == _BEAM:
            nm2 = _modal_size(beam_params[k])
            o = m_off[k]
            eta = y[e0 + o:e0 + o + nm2]
            eta_dot = y[e0 + n_modal + o:e0 + n_modal + o + nm2]
            # a distributed load p per length acts as gravity does: g + p / mu on this beam;
            # loads in body axes (followers) turn with the end section (F, T) and the frame (p)
            f_k, t_k, p_k = forces[k], torques[k], line_loads[k]
            if beam_params[k, _BAXES] != 0.0:
                f_k, t_k, p_k = matvec(rot_o[k], f_k), matvec(rot_o[k], t_k), matvec(a, p_k)
            g_k = gravity + p_k / beam_params[k, _BMU]
            if exact.shape[2] > 0 and beam_params[k, _BSTIFF] != 0.0:
                mass, h, j_w, ap, ag, newton_v, euler_v, modal, m_ee, geo = _beam_terms_exact(
                    beam_params[k], shape_vec[k], exact[k], eta, eta_dot, a, w, g_k)
            else:
                mass, h, j_w, ap, ag, newton_v, euler_v, modal, m_ee, geo = _beam_terms(
                    beam_params[k], shape_vec[k], shape_mat[k], eta, eta_dot, a, w, g_k)
            # an applied end force F and torque T (docs/beam.md, "Loads on the beam") act at
            # the output point and on the end section: F in Newton, rho_O x F + T about I,
            # and their generalized forces B_r^T F + B_t^T T in the modal rows (below)
            weight = mass * g_k + f_k
            bn = weight - _cross(w, _cross(w, h)) + newton_v
            be = (-_cross(w, matvec(j_w, w)) + _cross(h, g_k) + euler_v + t_k
                  + _cross(rho_o[k], f_k))
            ce = e_col0 + o
            for j in range(nm2):
                for i in range(3):
                    # translation: + A P eta'' (and the foreshortening's -mu A e1 (D1 eta)^T)
                    s[rn + i, ce + j] = ap[i, j] - beam_params[k, _BMU] * a[i, 0] * geo[1, j]
                    s[re + i, ce + j] = ag[i, j]      # rotation:    + A G eta''
                    s[ce + j, ca + i] = ap[i, j]      # modal:  (A P)^T a + (A G)^T alpha
                    s[ce + j, cal + i] = ag[i, j]
                b[ce + j] = modal[j]
                for i in range(3):
                    b[ce + j] += b_r[k, i, j] * f_k[i] + b_t[k, i, j] * t_k[i]
            for j in range(nm2):                      # the modal mass
                for i in range(nm2):
                    s[ce + j, ce + i] = m_ee[j, i]
            for j in range(nm2):                      # geometric stiffening: -mu e1 . a_I
                for i in range(3):
                    s[ce + j, ca + i] -= beam_params[k, _BMU] * a[i, 0] * geo[1, j]
        elif body_kind[k] == _ROD:
            # a strain rod (reference/strain_rod.py::rod_terms): the beam's rows with its
            # Jacobians; no applied loads of its own yet
            nm2 = rods[0][k]
            state, q, qd = _rod_state(k, rods, y, e0, n_modal, m_off)
            mass, h, j_w, ap, ag, newton_v, euler_v, modal, m_ee, geo = rod_terms(
                state, rods[4][k], rods[6][k, 0], rods[7][k], rods[5][k, :nm2], rods[6][k, 1],
                q, qd, a, w, gravity)
            bn = mass * gravity - _cross(w, _cross(w, h)) + newton_v
            be = -_cross(w, matvec(j_w, w)) + _cross(h, gravity) + euler_v
            ce = e_col0 + m_off[k]
            for j in range(nm2):
                for i in range(3):
                    s[rn + i, ce + j] = ap[i, j]
                    s[re + i, ce + j] = ag[i, j]
                    s[ce + j, ca + i] = ap[i, j]
                    s[ce + j, cal + i] = ag[i, j]
                b[ce + j] = modal[j]
                for i in range(nm2):
                    s[ce + j, ce + i] = m_ee[j, i]
        elif body_kind[k] == _RIGID:
            mass = p[_MASS]
            rho_c = matvec(a, _vec3(p, _LIC))
            h = mass * rho_c
            j_w = matmul(matmul(a, _mat3(p, _JI)), a.T)
            weight = mass * gravity + forces[k]
            # Newton: M a - hat(h) alpha - F_k + F_{k+1} = M g + f - w x (w x h) + q_k - q_{k+1}
            bn = weight - _cross(w, _cross(w, h))
            # Euler about I: J alpha + hat(h) a - N_k + sum_c [N_c + hat(rho_att,c + d_c) F_c]
            #     = -w x J w + rho_c x (M g + f) + tau + m_k - sum_c [m_c + (rho_att,c + d_c) x q_c]
            # over the children c (rho_att,c = rho_o for a chain's output point)
            be = -_cross(w, matvec(j_w, w)) + _cross(rho_c, weight) + torques[k]
        else:
            raise ValueError(_UNDECLARED_BODY_KIND)
        hc = _hat(h)
        for i in range(3):
            s[rn + i, ca + i] = mass
            for j in range(3):
                s[rn + i, cal + j] = -hc[i, j]
                s[re + i, cal + j] = j_w[i, j]
                s[re + i, ca + j] = hc[i, j]
        # the inboard hinge acting on body k
        if DEFLECTS[hinge_kind[k]]:
            bn += q_el[k]
            be += m_el[k]
        else:
            c = f_col[k]
            for i in range(3):
                s[rn + i, c + i] = -1.0
            if m_col[k] >= 0:              # a fixed hinge or a joint with coordinates
                c = m_col[k]
                for i in range(3):
                    s[re + i, c + i] = -1.0
        # each outboard hinge c (joining a child c at its attachment point r_att,c: a beam's
        # output point, any point of a rigid body) acting on body k: force -F_c at
        # r_att,c + d_c, couple -N_c; a beam's modal rows get their generalized forces
        # B_r^T F_c + B_t^T (N_c + d_c x F_c) (d_c: an elastic hinge's deflection or a slide,
        # zero otherwise)
        for ci in range(child_start[k], child_start[k + 1]):
            kc = child_list[ci]
            arm = rho_att[kc] + defl[kc]
            if DEFLECTS[hinge_kind[kc]]:
                # -q at r_att and the couple -m_in = -(m_out + d x q) about r_att; on a beam
                # their generalized forces -(B_r^T q + B_t^T m_in), as a weld's reactions'
                bn -= q_el[kc]
                be -= m_el[kc] + _cross(arm, q_el[kc])
                m_in = m_el[kc] + _cross(defl[kc], q_el[kc])
                for j in range(nm2):
                    gen = 0.0
                    for i in range(3):
                        gen += b_r[k, i, j] * q_el[kc, i] + b_t[k, i, j] * m_in[i]
                    b[ce + j] -= gen
            else:
                c = f_col[kc]
                ha = _hat(arm)
                for i in range(3):
                    s[rn + i, c + i] = 1.0
                    for j in range(3):
                        s[re + i, c + j] = ha[i, j]
                    for j in range(nm2):
                        s[ce + j, c + i] = b_r[k, i, j]
                if _HAS_SLIDES[hinge_kind[kc]] and nm2 > 0:
                    # B_t^T (d x F) = B_t^T d^ F: column i gets -(d^ B_t)[i, :]
                    hdb = matmul(_hat(defl[kc]), b_t[k, :, :nm2])
                    for i in range(3):
                        for j in range(nm2):
                            s[ce + j, c + i] -= hdb[i, j]
                if m_col[kc] >= 0:
                    c = m_col[kc]
                    for i in range(3):
                        s[re + i, c + i] = 1.0
                        for j in range(nm2):
                            s[ce + j, c + i] = b_t[k, i, j]
        for i in range(3):
            b[rn + i] = bn[i]
            b[re + i] = be[i]
        # constraint rows of the inboard hinge (acceleration level), P = parent[k]:
        #     a_k = a_att,k = a_P + alpha_P x rho_att,k + B_r eta''_P + acc_v_att,k,
        #     alpha_k = alpha_O,P (fixed hinge)
        if not DEFLECTS[hinge_kind[k]]:
            r = f_col[k]
            for i in range(3):
                s[r + i, ca + i] = 1.0
            if parent[k] < 0:
                a_place = _ground_place_acceleration(rho_att[k], a_g, w_g, wd_g)
                for i in range(3):
                    b[r + i] = a_place[i]
            else:
                kp = parent[k]
                hpo = _hat(rho_att[k])
                pn2 = _flex_size(kp, body_kind, beam_params, rods)
                pce = e_col0 + m_off[kp]
                for i in range(3):
                    s[r + i, 6 * kp + i] = -1.0
                    for j in range(3):
                        s[r + i, 6 * kp + 3 + j] = hpo[i, j]
                    for j in range(pn2):
                        s[r + i, pce + j] = -b_r[kp, i, j]
                    b[r + i] = acc_v_att[k, i]
            if m_col[k] >= 0:
                r = m_col[k]
                for i in range(3):
                    s[r + i, cal + i] = 1.0
                    if parent[k] < 0:
                        b[r + i] = wd_g[i]
                    else:
                        kp = parent[k]
                        pn2 = _flex_size(kp, body_kind, beam_params, rods)
                        pce = e_col0 + m_off[kp]
                        s[r + i, 6 * kp + 3 + i] = -1.0
                        for j in range(pn2):
                            s[r + i, pce + j] = -b_t[kp, i, j]
                        b[r + i] = alpha_v[kp, i]
            if joints[0][k] >= 0:
                kp = parent[k]
                _, qd = _joint_coordinates(y, joints, k, hinge_kind[k])
                if kp < 0:
                    _joint_rows(s, b, k, hinge_kind[k], hinge_params[k], kp, rot_g, w_g, wd_g,
                                rot[k], omega[k], defl[k], qd, np.zeros((3, 0)), 0, f_col,
                                m_col, joints)
                else:
                    pn2 = _flex_size(kp, body_kind, beam_params, rods)
                    _joint_rows(s, b, k, hinge_kind[k], hinge_params[k], kp, rot_o[kp],
                                omega_o[kp], alpha_v[kp], rot[k], omega[k], defl[k], qd,
                                np.ascontiguousarray(b_t[kp, :, :pn2]), e_col0 + m_off[kp],
                                f_col, m_col, joints)
    return s, b


@kernel
def _ground_place_acceleration(arm, a_g, w_g, wd_g):
    """A root's place on the ground, at arm from the ground point: its acceleration
    a_g + w_g' x arm + w_g x (w_g x arm)."""
    return a_g + _cross(wd_g, arm) + _cross(w_g, _cross(w_g, arm))


@kernel(entry=True)
def _solve_dynamics(y, body_params, hinge_kind, hinge_params, body_kind, beam_params, shape_vec,
                    shape_mat, q_off, w_off, d_off, m_off, e0, n_modal, e_col0, f_col, m_col,
                    loops, n_unknowns, gravity, r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques,
                    line_loads, topology, attachment_point, joints, exact, rods):
    """Kinematics plus the solved accelerations, hinge loads and modal accelerations; also each
    body's rho_O = r_O - r_I, the velocity part of a_O and B_r = d r_O / d eta, per joint
    coordinate (joints) its acceleration q'' and the joint loads' generalized force s_i . N
    (s_i . F for a slide), and per hinge its attachment point's arm rho_att and the velocity part
    of its acceleration acc_v_att (_kinematics).  exact: the beams' quadrature tables of the
    exact foreshortening (shapes.exact_foreshortening_table, one per body), or no columns for the
    second-order one (_beam_terms_exact).  rods: the strain rods' tables
    (newton_euler.py::_rod_tables; their rows: reference/strain_rod.py)."""
    (rot, omega, r_in, v_in, defl, defl_rate, rho_o, rot_o, omega_o, acc_v, alpha_v, b_r,
     b_t, v_o, rho_att, acc_v_att) = _kinematics(
        y, body_params, hinge_kind, hinge_params, body_kind, beam_params, shape_vec, shape_mat,
        q_off, w_off, d_off, m_off, e0, n_modal, r_g, v_g, rot_g, w_g, topology,
        attachment_point, joints, rods)
    q_el, m_el = _elastic_loads(rot, omega, rot_o, omega_o, defl, defl_rate, hinge_kind,
                                hinge_params, rot_g, w_g, topology[0])
    s, b = _assemble(y, rot, omega, defl, rho_o, rot_o, omega_o, acc_v, alpha_v, b_r, b_t,
                     rho_att, acc_v_att, q_el, m_el, body_params, hinge_kind, hinge_params,
                     body_kind, beam_params, shape_vec, shape_mat, m_off, e0, n_modal, e_col0,
                     f_col, m_col, loops, n_unknowns, gravity, a_g, rot_g, w_g, wd_g, forces,
                     torques, line_loads, topology, joints, exact, rods)
    n_rows = loops[1].shape[0]
    if n_rows > 0:
        directions = _closure_rows(s, b, loops, rot, omega, r_in, v_in, rho_o, rot_o, omega_o,
                                   v_o, acc_v, alpha_v, b_r, b_t, e_col0, m_off, body_kind,
                                   beam_params, rods, r_g, v_g, a_g, rot_g, w_g, wd_g)
        x = _solve_least_closure_force(s, b, loops[0], n_rows)
    else:
        directions = np.zeros((0, 3))
        x = np.linalg.solve(s, b)
    # each closing joint's force and couple on side b (world; the couple a pure one), then its
    # drives' generalized forces (a driven coordinate's row's multiplier)
    closure_load = np.zeros((loops[5].shape[0], 8))
    for r in range(n_rows):
        lam = x[loops[0] + r]
        if loops[11][r] >= 0:
            closure_load[loops[2][r], 6 + loops[11][r]] = lam
        at = 0 if loops[1][r] == _GAP_A or loops[1][r] == _GAP_WORLD else 3
        for i in range(3):
            closure_load[loops[2][r], at + i] += lam * directions[r, i]
    n = body_params.shape[0]
    acc = np.empty((n, 3))
    alpha = np.empty((n, 3))
    force = np.zeros((n, 3))
    moment = np.zeros((n, 3))
    for k in range(n):
        put1(acc[k], x[6 * k:6 * k + 3])
        put1(alpha[k], x[6 * k + 3:6 * k + 6])
        if DEFLECTS[hinge_kind[k]]:
            put1(force[k], q_el[k])
            put1(moment[k], m_el[k])
        else:
            put1(force[k], x[f_col[k]:f_col[k] + 3])
            if m_col[k] >= 0:
                put1(moment[k], x[m_col[k]:m_col[k] + 3])
    modal_acc = x[e_col0:e_col0 + n_modal].copy()
    c_off, n_coord, c_col0 = joints[0], joints[2], joints[3]
    coord_acc = x[c_col0:c_col0 + n_coord].copy()
    generalized = np.zeros(n_coord)
    for k in range(n):
        if c_off[k] < 0:
            continue
        kp = topology[0][k]
        a_in = rot_g if kp < 0 else rot_o[kp]
        dirs, nc = _joint_directions(hinge_kind[k], hinge_params[k], a_in, rot[k])
        for i in range(nc):
            load = force[k] if _MOTION[hinge_kind[k]][i] == _SLIDE else moment[k]
            generalized[c_off[k] + i] = dirs[0, i] * load[0] + dirs[1, i] * load[1] + \
                dirs[2, i] * load[2]
    return (rot, omega, r_in, v_in, defl, acc, alpha, force, moment, modal_acc, rho_o, acc_v,
            b_r, coord_acc, generalized, rho_att, acc_v_att, closure_load)


@kernel
def rhs_kernel(y, body_params, hinge_kind, hinge_params, body_kind, beam_params, shape_vec,
               shape_mat, q_off, w_off, d_off, m_off, e0, n_modal, e_col0, f_col, m_col, loops,
               n_unknowns, gravity, r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques, line_loads,
               topology, attachment_point, joints, exact, rods):
    """dy/dt of the state [quaternions, angular velocities, (d, d') of elastic hinges,
    modal coordinates of all beams, their rates, joint coordinates, their rates].  A callee: the
    compiled integrator links it (integrator.py); solve_ivp calls its twin with entry points
    (newton_euler.py's _Problem.rhs), compiled only when a run goes through solve_ivp: as an
    entry itself its code was optimized and made into machine code once more (~30 s) wherever
    numba's cache was cold (docs/solver.md, "Compile time", item 9)."""
    (rot, omega, r_in, v_in, defl, acc, alpha, force, moment, modal_acc, rho_o, acc_v,
     b_r, coord_acc, _, rho_att, acc_v_att, _) = _solve_dynamics(
        y, body_params, hinge_kind, hinge_params, body_kind, beam_params, shape_vec, shape_mat,
        q_off, w_off, d_off, m_off, e0, n_modal, e_col0, f_col, m_col, loops, n_unknowns,
        gravity, r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques, line_loads, topology,
        attachment_point, joints, exact, rods)
    n = body_params.shape[0]
    dy = np.zeros(y.shape[0])
    for k in range(n):
        if q_off[k] >= 0:
            o = q_off[k]
            qw, qx, qy, qz = y[o], y[o + 1], y[o + 2], y[o + 3]
            wx, wy, wz = omega[k, 0], omega[k, 1], omega[k, 2]
            # q' = 1/2 [0, w] (x) q  (w in the world frame, A = R(q) body to world)
            dy[o] = -0.5 * (wx * qx + wy * qy + wz * qz)
            dy[o + 1] = 0.5 * (qw * wx + wy * qz - wz * qy)
            dy[o + 2] = 0.5 * (qw * wy + wz * qx - wx * qz)
            dy[o + 3] = 0.5 * (qw * wz + wx * qy - wy * qx)
            put1(dy[w_off[k]:w_off[k] + 3], alpha[k])
        if DEFLECTS[hinge_kind[k]]:
            o = d_off[k]
            put1(dy[o:o + 3], y[o + 3:o + 6])
            kp = topology[0][k]
            # d'' = a_k - a_att,k, the attachment point's acceleration (the ground's for a root;
            # a_P + alpha_P x rho_att + velocity part, + B_r eta''_P on a beam's or a strain
            # rod's end)
            if kp < 0:
                a_att = _ground_place_acceleration(rho_att[k], a_g, w_g, wd_g)
            else:
                a_att = acc[kp] + _cross(alpha[kp], rho_att[k]) + acc_v_att[k]
                nm2 = _flex_size(kp, body_kind, beam_params, rods)
                if nm2 > 0:
                    a_att = a_att + matvec(b_r[kp, :, :nm2], modal_acc[m_off[kp]:m_off[kp] + nm2])
            put1(dy[o + 3:o + 6], acc[k] - a_att)
    for i in range(n_modal):
        dy[e0 + i] = y[e0 + n_modal + i]
        dy[e0 + n_modal + i] = modal_acc[i]
    c0, n_coord = joints[1], joints[2]
    for i in range(n_coord):
        dy[c0 + i] = y[c0 + n_coord + i]
        dy[c0 + n_coord + i] = coord_acc[i]
    return dy
