"""Tree sweeps (docs/assembly.md, "Trees" and "Trees with joints"): the reduced Riccati sweep of
bodies joined by ball joints from the leaves to the root, and the full-state sweep of trees with
joints with coordinates (an articulated-body elimination of their free coordinates).  The chains'
sweeps and the element kinds are in sweep.py.
"""
import numpy as np
from numba import njit

from .. import CONTRACT, kernel
from ..transfers.joint import FREE, PRESCRIBED
from ..algebra.mat3 import add1, add2, inv3, matmul, matvec, mm3_into, put1, put2
from .sweep import IDENTITY, JOINT, LOCKED, TRANSFER


# Trees of bodies joined by ball joints: the reduced Riccati sweep from the leaves to the root
# (docs/assembly.md, "Trees").
#
# Every body k has the reduced map of a body between moment-free cuts (the same as in a chain:
# kernels/stepping/ball_chain.py::ball_body_map, kernels/transfers/beam.py::beam_ball_map, or folded
# from its transfer, sweep.py::fold_ball_body):
#     [a_O; q_O] = V [a_I; q_I; 1],  V = [[V_aa, V_aq, v_a], [V_qa, V_qq, v_q]].
# At its output point O its children hang by ball joints: each child's input point is O
# (a_Ic = a_O) and the force body k exerts at O is the sum of the forces on the children,
# q_O = sum_c q_Ic.  Sweeping from the leaves, every child's input already carries
# q_Ic = S_c a_Ic + P_c, so q_O = S_O a_O + P_O with S_O = sum_c S_c, P_O = sum_c P_c (S_O = 0,
# P_O = 0 at a free leaf), and body k's map gives its own input's relation:
#     V_qa a_I + V_qq q_I + v_q = S_O (V_aa a_I + V_aq q_I + v_a) + P_O
#     q_I = S_I a_I + P_I,  T = V_qq - S_O V_aq,  S_I = T^-1 (S_O V_aa - V_qa),
#                           P_I = T^-1 (S_O v_a + P_O - v_q).
# The roots' inputs are the ground point (a_I = the ground's acceleration); the recovery runs from
# the root to the leaves: q_I = S_I a_I + P_I, [a_O; q_O] = V [a_I; q_I; 1], a_Ic = a_O.
# Bodies are numbered parents first (Model.parent[k] < k), so the sweep runs k = n-1 .. 0 and the
# recovery k = 0 .. n-1: O(n) per step, 3 x 3 blocks as in a chain.


@njit(cache=True, inline='always', fastmath=CONTRACT)
def tree_reduced_step(v, s_o, p_o, s_i, p_i, t_inv, t, num):
    """Body k of the leaves-to-root sweep (the comment "Trees" above): from its map v (6 x 7)
    and its output's q_O = S_O a_O + P_O, its input's q_I = S_I a_I + P_I and T^-1.  t, num: 3 x 3
    scratch.  Returns det T (0: singular)."""
    r0 = p_o[0] - v[3, 6]
    r1 = p_o[1] - v[4, 6]
    r2 = p_o[2] - v[5, 6]
    for i in range(3):
        for j in range(3):
            t[i, j] = v[3 + i, 3 + j] - (s_o[i, 0] * v[0, 3 + j] + s_o[i, 1] * v[1, 3 + j]
                                         + s_o[i, 2] * v[2, 3 + j])
            num[i, j] = (s_o[i, 0] * v[0, j] + s_o[i, 1] * v[1, j] + s_o[i, 2] * v[2, j]
                         - v[3 + i, j])
    r0 += s_o[0, 0] * v[0, 6] + s_o[0, 1] * v[1, 6] + s_o[0, 2] * v[2, 6]
    r1 += s_o[1, 0] * v[0, 6] + s_o[1, 1] * v[1, 6] + s_o[1, 2] * v[2, 6]
    r2 += s_o[2, 0] * v[0, 6] + s_o[2, 1] * v[1, 6] + s_o[2, 2] * v[2, 6]
    det = inv3(t, t_inv)
    if det == 0.0:
        return det
    mm3_into(t_inv, num, s_i)
    for i in range(3):
        p_i[i] = t_inv[i, 0] * r0 + t_inv[i, 1] * r1 + t_inv[i, 2] * r2
    return det


@njit(cache=True, inline='always', fastmath=CONTRACT)
def tree_reduced_recover(v, s_i, p_i, a0, a1, a2, aq_in, aq_out):
    """Body k's input [a_I; q_I] (q_I = S_I a_I + P_I, a_I = (a0, a1, a2)) and output
    [a_O; q_O] = V [a_I; q_I; 1]."""
    aq_in[0] = a0
    aq_in[1] = a1
    aq_in[2] = a2
    for i in range(3):
        aq_in[3 + i] = s_i[i, 0] * a0 + s_i[i, 1] * a1 + s_i[i, 2] * a2 + p_i[i]
    for r in range(6):
        x = v[r, 6]
        for c in range(6):
            x += v[r, c] * aq_in[c]
        aq_out[r] = x


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _clear_ports(port_s, port_p):
    for k in range(port_p.shape[0]):
        for i in range(3):
            port_p[k, i] = 0.0
            for j in range(3):
                port_s[k, i, j] = 0.0


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _add_to_port(s_i, p_i, port_s, port_p):
    for i in range(3):
        port_p[i] += p_i[i]
        for j in range(3):
            port_s[i, j] += s_i[i, j]


@kernel
def riccati_tree_reduced(v, parent, a_root, s_in, p_in, t_inv, port_s, port_p, aq_in, aq_out):
    """The reduced sweep of a tree of bodies between ball joints (the comment "Trees" above):
    v (n, 6, 7) every body's map; parent (n,) (-1: the ground point, whose acceleration is
    a_root).  Writes every body's input and output [a; q] into aq_in, aq_out (n, 6).  Scratch:
    s_in, t_inv, port_s (n, 3, 3), p_in, port_p (n, 3).  Returns 0, or k + 1 where body k's T is
    singular."""
    n = v.shape[0]
    t = np.empty((3, 3))
    num = np.empty((3, 3))
    _clear_ports(port_s, port_p)
    for k in range(n - 1, -1, -1):
        if tree_reduced_step(v[k], port_s[k], port_p[k], s_in[k], p_in[k], t_inv[k], t,
                             num) == 0.0:
            return k + 1
        if parent[k] >= 0:
            _add_to_port(s_in[k], p_in[k], port_s[parent[k]], port_p[parent[k]])
    for k in range(n):
        p = parent[k]
        if p < 0:
            tree_reduced_recover(v[k], s_in[k], p_in[k], a_root[0], a_root[1], a_root[2],
                                 aq_in[k], aq_out[k])
        else:
            tree_reduced_recover(v[k], s_in[k], p_in[k], aq_out[p, 0], aq_out[p, 1],
                                 aq_out[p, 2], aq_in[k], aq_out[k])
    return 0


@kernel
def write_tree_stations(parent, a_root, phi_root, aq_in, aq_out, phi, z):
    """The stations' states in the general layout: z[2k + 1], z[2k + 2] body k's input and
    output [a, phi, 0, q]; z[0] the ground point [a, phi, 0, sum of the roots' q]."""
    n = phi.shape[0]
    for r in range(z.shape[0]):
        for c in range(12):
            z[r, c] = 0.0
    for i in range(3):
        z[0, i] = a_root[i]
        z[0, 3 + i] = phi_root[i]
    for k in range(n):
        for i in range(3):
            if parent[k] < 0:
                z[0, 9 + i] += aq_in[k, 3 + i]
            z[2 * k + 1, i] = aq_in[k, i]
            z[2 * k + 1, 3 + i] = phi[k, i]
            z[2 * k + 1, 9 + i] = aq_in[k, 3 + i]
            z[2 * k + 2, i] = aq_out[k, i]
            z[2 * k + 2, 3 + i] = phi[k, i]
            z[2 * k + 2, 9 + i] = aq_out[k, 3 + i]


# Trees in full state (joints with coordinates; docs/assembly.md, "Trees with joints")
#
# Leaves to root, every station's loads e = [m, q] as an affine function of its motion
# f = [a, alpha] (angular-acceleration slots): e = S f + P, S = 0, P = 0 at a free end, summed
# over the children at a parent's output point (they share its motion).  Through an element
# z_O = U z_I + u:  T = U_ee - S_O U_fe,  S_I = T^-1 (S_O U_ff - U_ef),
# P_I = T^-1 (S_O u_f + P_O - u_e).  Through a joint (kernels/transfers/joint.py) the free
# coordinates' nu are eliminated as in an articulated-body step: with G = S_O B_F,
# D = Bl_F^T G - diag(tau'_F), y = S_O c' + P_O (c' = c + B_P nu_P, the prescribed ones),
# nu_F = D^-1 (tau0_F - Bl_F^T y) - D^-1 Bl_F^T S_O Phi f_I, and e_I = Psi e_O.


@kernel
def _gauss_solve(a, b, n, m):
    """Solve a[:n, :n] x = b[:n, :m] in place (x in b; a destroyed), partial pivoting; False if
    a pivot vanishes against the matrix's scale."""
    scale = 0.0
    for i in range(n):
        for j in range(n):
            scale = max(scale, abs(a[i, j]))
    if not scale > 0.0:
        return n == 0
    for c in range(n):
        piv = c
        for r in range(c + 1, n):
            if abs(a[r, c]) > abs(a[piv, c]):
                piv = r
        if not abs(a[piv, c]) > 1e-14 * scale:
            return False
        if piv != c:
            for j in range(n):
                a[c, j], a[piv, j] = a[piv, j], a[c, j]
            for j in range(m):
                b[c, j], b[piv, j] = b[piv, j], b[c, j]
        inv = 1.0 / a[c, c]
        for r in range(c + 1, n):
            f = a[r, c] * inv
            if f != 0.0:
                for j in range(c, n):
                    a[r, j] -= f * a[c, j]
                for j in range(m):
                    b[r, j] -= f * b[c, j]
    for c in range(n - 1, -1, -1):
        inv = 1.0 / a[c, c]
        for j in range(m):
            x = b[c, j]
            for k in range(c + 1, n):
                x -= a[c, k] * b[k, j]
            b[c, j] = x * inv
    return True


@kernel
def _element_to_inboard(u, s_o, p_o, s_i, p_i):
    """S_I, P_I through an affine element from the outboard S_O, P_O; False if T is singular."""
    t = np.empty((6, 6))
    x = np.empty((6, 7))
    for i in range(6):
        for j in range(6):
            tv = u[6 + i, 6 + j]
            xv = -u[6 + i, j]
            for k in range(6):
                tv -= s_o[i, k] * u[k, 6 + j]
                xv += s_o[i, k] * u[k, j]
            t[i, j] = tv
            x[i, j] = xv
        pv = p_o[i] - u[6 + i, 12]
        for k in range(6):
            pv += s_o[i, k] * u[k, 12]
        x[i, 6] = pv
    if not _gauss_solve(t, x, 6, 7):
        return False
    for i in range(6):
        p_i[i] = x[i, 6]
        for j in range(6):
            s_i[i, j] = x[i, j]
    return True


@kernel
def _joint_parts(u, dof, tau_nu, s_o, p_o, free, d_inv_bl_s_phi, d_inv_r, g):
    """The joint's elimination (the comment above): free coordinates' indices, H = D^-1 Bl_F^T
    S_O Phi (mf x 6), D^-1 r (mf) and G = S_O B_F (6 x mf), with r = tau0_F - Bl_F^T y; returns
    (mf, y) or mf = -1 if D is singular."""
    y = np.empty(6)
    for i in range(6):
        ci = u[i, 12]
        for c in range(3):
            if dof[c] == PRESCRIBED:
                ci += u[i, 6 + c] * tau_nu[c, 2]
        y[i] = ci
    sy = matvec(s_o, y) + p_o
    mf = 0
    for c in range(3):
        if dof[c] == FREE:
            free[mf] = c
            mf += 1
    if mf == 0:
        return 0, sy
    s_phi = matmul(s_o, u[0:6, 0:6])
    d = np.empty((3, 3))
    rhs = np.empty((3, 7))
    for a in range(mf):
        ca = free[a]
        for i in range(6):
            gv = 0.0
            for k in range(6):
                gv += s_o[i, k] * u[k, 6 + ca]
            g[i, a] = gv
    for a in range(mf):
        ca = free[a]
        r = tau_nu[ca, 0]
        for i in range(6):
            r -= u[6 + i, ca] * sy[i]
        rhs[a, 6] = r
        for j in range(6):
            x = 0.0
            for i in range(6):
                x += u[6 + i, ca] * s_phi[i, j]
            rhs[a, j] = x
        for b in range(mf):
            x = 0.0
            for i in range(6):
                x += u[6 + i, ca] * g[i, b]
            d[a, b] = x - (tau_nu[ca, 1] if a == b else 0.0)
    if not _gauss_solve(d, rhs, mf, 7):
        return -1, sy
    for a in range(mf):
        d_inv_r[a] = rhs[a, 6]
        for j in range(6):
            d_inv_bl_s_phi[a, j] = rhs[a, j]
    return mf, sy


@kernel
def riccati_tree_full(kind, u, known_loads, joint_dof, joint_drive, parent, root_f, s_mat,
                      p_vec, port_s, port_p, joint_nu, joint_tau, z):
    """The full-state sweep of a tree (the comment above): kind, u (2n elements: 2k hinge k,
    2k + 1 body k), parent (n,), root_f (6,) the ground's [a, alpha].  Scratch: s_mat (2n + 1,
    6, 6), p_vec (2n + 1, 6) (s[2k]: hinge k's inboard relation, s[2k + 1]: body k's input),
    port_s, port_p (n, 6, 6), (n, 6).  Writes every station into z, each joint's nu (its
    coordinates' q'', or a ball joint's relative angular acceleration) into joint_nu and its
    generalized forces Bl . e_O into joint_tau.  Returns 0, or j + 1 for the element j whose
    elimination is singular (kernels/assembly/loop_columns.py::sweep_columns is this sweep for
    many load columns at once)."""
    n = parent.shape[0]
    free = np.zeros(3, dtype=np.int64)
    h_mat = np.empty((3, 6))
    k0 = np.empty(3)
    g = np.empty((6, 3))
    port_s[:, :, :] = 0.0
    port_p[:, :] = 0.0
    for k in range(n - 1, -1, -1):
        jb, jh = 2 * k + 1, 2 * k
        if not _element_to_inboard(u[jb], port_s[k], port_p[k], s_mat[jb], p_vec[jb]):
            return jb + 1
        s_o, p_o = s_mat[jb], p_vec[jb]
        kd = kind[jh]
        if kd == IDENTITY:
            put2(s_mat[jh], s_o)
            put1(p_vec[jh], p_o)
        elif kd == TRANSFER:
            if not _element_to_inboard(u[jh], s_o, p_o, s_mat[jh], p_vec[jh]):
                return jh + 1
        elif kd == LOCKED:
            s_mat[jh] = 0.0
            put1(p_vec[jh], known_loads[jh, 0:6])
        else:   # JOINT
            mf, sy = _joint_parts(u[jh], joint_dof[k], joint_drive[k], s_o, p_o, free, h_mat,
                                  k0, g)
            if mf < 0:
                return jh + 1
            psi = u[jh, 6:12, 6:12]
            s_e = matmul(s_o, u[jh, 0:6, 0:6])
            p_e = sy.copy()
            for i in range(6):
                for a in range(mf):
                    p_e[i] += g[i, a] * k0[a]
                    for j in range(6):
                        s_e[i, j] -= g[i, a] * h_mat[a, j]
            put2(s_mat[jh], matmul(psi, s_e))
            put1(p_vec[jh], matvec(psi, p_e))
        p = parent[k]
        if p >= 0:
            add2(port_s[p], s_mat[jh])
            add1(port_p[p], p_vec[jh])
    for r in range(z.shape[0]):
        for c in range(12):
            z[r, c] = 0.0
    put1(z[0, 0:6], root_f)
    f_i = np.empty(6)
    f_o = np.empty(6)
    for k in range(n):
        jb, jh = 2 * k + 1, 2 * k
        p = parent[k]
        st = 0 if p < 0 else 2 * p + 2
        put1(f_i, z[st, 0:6])
        if p < 0:
            add1(z[0, 6:12], matvec(s_mat[jh], f_i) + p_vec[jh])
        kd = kind[jh]
        if kd == IDENTITY:
            put1(f_o, f_i)
        elif kd == TRANSFER:
            zi = np.empty(12)
            put1(zi[0:6], f_i)
            put1(zi[6:12], matvec(s_mat[jh], f_i) + p_vec[jh])
            put1(f_o, matvec(u[jh, 0:6, 0:12], zi) + u[jh, 0:6, 12])
        elif kd == LOCKED:
            a = s_mat[jb].copy()
            x = np.empty((6, 1))
            put1(x[:, 0], known_loads[jh, 6:12] - p_vec[jb])
            if not _gauss_solve(a, x, 6, 1):
                return jh + 1
            put1(f_o, x[:, 0])
        else:
            s_o, p_o = s_mat[jb], p_vec[jb]
            mf, _ = _joint_parts(u[jh], joint_dof[k], joint_drive[k], s_o, p_o, free, h_mat,
                                 k0, g)
            if mf < 0:
                return jh + 1
            for c in range(3):
                joint_nu[k, c] = joint_drive[k, c, 2] if joint_dof[k, c] == PRESCRIBED else 0.0
            for a in range(mf):
                x = k0[a]
                for j in range(6):
                    x -= h_mat[a, j] * f_i[j]
                joint_nu[k, free[a]] = x
            put1(f_o, matvec(u[jh, 0:6, 0:6], f_i) + u[jh, 0:6, 12])
            for c in range(3):
                if joint_dof[k, c] != 0:
                    for i in range(6):
                        f_o[i] += u[jh, i, 6 + c] * joint_nu[k, c]
        put1(z[jb, 0:6], f_o)
        put1(z[jb, 6:12], matvec(s_mat[jb], f_o) + p_vec[jb])
        if kd == JOINT:
            for c in range(3):
                x = 0.0
                if joint_dof[k, c] != 0:
                    for i in range(6):
                        x += u[jh, 6 + i, c] * z[jb, 6 + i]
                joint_tau[k, c] = x
        put1(z[jb + 1], matvec(u[jb, :, 0:12], z[jb]) + u[jb, :, 12])
    return 0
