"""The tree's full-state sweep with a column per closing joint's row (docs/loops.md, "The step
with loops"): sweep_columns carries the step and every row's unit multiplier's response in one
sweep, recover_column recovers one column's stations.  Called by closure.py::solve_with_loops.
"""

import numpy as np

from .. import kernel, loop_tables, no_alloc_kernel
from ..transfers.joint import FREE, PRESCRIBED
from ..algebra.mat3 import add1, add2, matmul, matvec, put1, put2
from .sweep import IDENTITY, JOINT, LOCKED, TRANSFER
from .tree_sweep import _gauss_solve


# The tree's full-state sweep with many load columns (tree_sweep.py::riccati_tree_full, "Trees in
# full state"): the Riccati matrices S once, a P per column.  Column 0 carries the transfers'
# affine parts, the drives' and prescribed motions' values and the ground's motion (the step
# itself); every other column only its loads at the output stations (a unit multiplier's
# response: the same linear step, homogeneous), and only on the bodies it passes (P is zero
# elsewhere: loops.up_ptr, up_idx).  Per element:
#   T = U_ee - S_O U_fe,  S_I = T^-1 (S_O U_ff - U_ef),  P_I,c = T^-1 (S_O u_f,c + P_O,c - u_e,c)
# (u_c = u for column 0, zero otherwise); per joint, with y_c = S_O c'_c + P_O,c,
#   k_c = D^-1 (tau0_F,c - Bl_F^T y_c),  P_J,c = Psi (y_c + G k_c)
# and in the recovery nu_F,c = k_c - D^-1 Bl_F^T S_O Phi f_I,c.


@kernel
def _element_columns(u, s_o, p_o, s_i, p_i, t, x):
    """Through an affine element z_O = U z_I + u: S_I and every column's P_I from the outboard
    S_O and P_O (C, 6), in one solve of T (the comment above; column 0 takes u's affine part);
    t (6, 6), x (6, 6 + C) scratch.  False if T is singular."""
    n_col = p_o.shape[0]
    for i in range(6):
        for j in range(6):
            tv = u[6 + i, 6 + j]
            xv = -u[6 + i, j]
            for m in range(6):
                tv -= s_o[i, m] * u[m, 6 + j]
                xv += s_o[i, m] * u[m, j]
            t[i, j] = tv
            x[i, j] = xv
        for c in range(n_col):
            pv = p_o[c, i]
            if c == 0:
                pv -= u[6 + i, 12]
                for m in range(6):
                    pv += s_o[i, m] * u[m, 12]
            x[i, 6 + c] = pv
    if not _gauss_solve(t, x, 6, 6 + n_col):
        return False
    for i in range(6):
        for j in range(6):
            s_i[i, j] = x[i, j]
        for c in range(n_col):
            p_i[c, i] = x[i, 6 + c]
    return True


@kernel
def sweep_columns(kind, u, joint_dof, joint_drive, known_loads, parent, s_mat, port_s, loops):
    """The upward half of the full-state tree sweep for the step (column 0, every element) and
    each row's unit multiplier (column r + 1, on the bodies its sweep passes: loops.up_ptr,
    up_idx; the comment above): S for every element into s_mat, each column's P into
    loops.p_col and each joint's k into loops.k_store (h and the free coordinates into
    loops.h_store, free_store).  A column's loads are loops.col_load at loops.col_body's output
    stations.  A LOCKED element (an elastic hinge at the consistent start: its loads known,
    known_loads, its outboard motion free) passes no impedance and, in column 0, its known
    inboard loads (tree_sweep.py::riccati_tree_full).  port_s (n, 6, 6) scratch.  Returns 0, or
    j + 1 for the element j whose elimination is singular."""
    p_col = loop_tables.p_col(loops)
    port_p = loop_tables.port_col(loops)
    up_ptr = loop_tables.up_ptr(loops)
    up_idx = loop_tables.up_idx(loops)
    col_body = loop_tables.col_body(loops)
    col_load = loop_tables.col_load(loops)
    free_store = loop_tables.free_store(loops)
    h_store = loop_tables.h_store(loops)
    k_store = loop_tables.k_store(loops)
    n = parent.shape[0]
    most = 1
    for k in range(n):
        most = max(most, 1 + up_ptr[k + 1] - up_ptr[k])
        port_s[k] = 0.0
        port_p[0, k] = 0.0
        for q in range(up_ptr[k], up_ptr[k + 1]):
            port_p[up_idx[q], k] = 0.0
    for c in range(1, col_body.shape[0]):
        for side in range(2):
            kb = col_body[c, side]
            if kb >= 0:
                add1(port_p[c, kb], col_load[c, side])
    cols = np.empty(most, dtype=np.int64)
    p_o = np.empty((most, 6))
    p_i = np.empty((most, 6))
    t = np.empty((6, 6))
    x = np.empty((6, 6 + most))
    d = np.empty((3, 3))
    rhs = np.empty((3, 6 + most))
    g = np.empty((6, 3))
    y = np.empty((most, 6))
    for k in range(n - 1, -1, -1):
        jb, jh = 2 * k + 1, 2 * k
        m = 1 + up_ptr[k + 1] - up_ptr[k]
        cols[0] = 0
        for q in range(up_ptr[k], up_ptr[k + 1]):
            cols[1 + q - up_ptr[k]] = up_idx[q]
        # the body: T and S_I, and every column's P_I, in one solve
        for a in range(m):
            put1(p_o[a], port_p[cols[a], k])
        if not _element_columns(u[jb], port_s[k], p_o[:m], s_mat[jb], p_i[:m], t, x[:, :6 + m]):
            return jb + 1
        for a in range(m):
            put1(p_col[cols[a], jb], p_i[a])
        kd = kind[jh]
        if kd == IDENTITY:
            put2(s_mat[jh], s_mat[jb])
            for a in range(m):
                put1(p_col[cols[a], jh], p_col[cols[a], jb])
        elif kd == TRANSFER:
            if not _element_columns(u[jh], s_mat[jb], p_i[:m], s_mat[jh], p_o[:m], t,
                                    x[:, :6 + m]):
                return jh + 1
            for a in range(m):
                put1(p_col[cols[a], jh], p_o[a])
        elif kd == LOCKED:
            s_mat[jh] = 0.0
            for a in range(m):
                for i in range(6):
                    p_col[cols[a], jh, i] = known_loads[jh, i] if cols[a] == 0 else 0.0
        elif kd == JOINT:
            uh = u[jh]
            s_o = s_mat[jb]
            mf = 0
            for c3 in range(3):
                if joint_dof[k, c3] == FREE:
                    free_store[k, mf] = c3
                    mf += 1
            free_store[k, 3] = mf
            s_phi = matmul(s_o, uh[0:6, 0:6])
            for a in range(mf):
                ca = free_store[k, a]
                for i in range(6):
                    gv = 0.0
                    for j in range(6):
                        gv += s_o[i, j] * uh[j, 6 + ca]
                    g[i, a] = gv
            # y_c = S_O c'_c + P_O,c: the affine part c' (prescribed coordinates too) in column 0
            for a in range(m):
                put1(y[a], p_i[a])
            for i in range(6):
                ci = uh[i, 12]
                for c3 in range(3):
                    if joint_dof[k, c3] == PRESCRIBED:
                        ci += uh[i, 6 + c3] * joint_drive[k, c3, 2]
                for j in range(6):
                    y[0, j] += s_o[j, i] * ci
            for a in range(mf):
                ca = free_store[k, a]
                for j in range(6):
                    xv = 0.0
                    for i in range(6):
                        xv += uh[6 + i, ca] * s_phi[i, j]
                    rhs[a, j] = xv
                for c in range(m):
                    r = joint_drive[k, ca, 0] if c == 0 else 0.0
                    for i in range(6):
                        r -= uh[6 + i, ca] * y[c, i]
                    rhs[a, 6 + c] = r
                for b in range(mf):
                    xv = 0.0
                    for i in range(6):
                        xv += uh[6 + i, ca] * g[i, b]
                    d[a, b] = xv - (joint_drive[k, ca, 1] if a == b else 0.0)
            if mf > 0 and not _gauss_solve(d, rhs, mf, 6 + m):
                return jh + 1
            psi = uh[6:12, 6:12]
            s_e = s_phi.copy()
            for a in range(mf):
                for j in range(6):
                    h_store[k, a, j] = rhs[a, j]
                for c in range(m):
                    k_store[cols[c], k, a] = rhs[a, 6 + c]
            for i in range(6):
                for a in range(mf):
                    for j in range(6):
                        s_e[i, j] -= g[i, a] * rhs[a, j]
            put2(s_mat[jh], matmul(psi, s_e))
            for c in range(m):
                p_e = y[c].copy()
                for i in range(6):
                    for a in range(mf):
                        p_e[i] += g[i, a] * rhs[a, 6 + c]
                put1(p_col[cols[c], jh], matvec(psi, p_e))
        else:
            return jh + 1
        p = parent[k]
        if p >= 0:
            add2(port_s[p], s_mat[jh])
            for a in range(m):
                add1(port_p[cols[a], p], p_col[cols[a], jh])
    return 0


@kernel
def _row_mv(a, i, x, m):
    """Row i of a's first m columns times x[:m]."""
    v = 0.0
    for j in range(m):
        v += a[i, j] * x[j]
    return v


@no_alloc_kernel
def recover_column(kind, u, joint_dof, joint_drive, known_loads, parent, root_f, s_mat, p_col,
                   k_col, h_store, free_store, z, nu, tau, affine, bodies, act, work):
    """The downward half for one column (P p_col (2n + 1, 6), joints' k k_col (n, 3)): the
    stations z, the joints' nu and tau of the given bodies, in tree order (a LOCKED
    element's outboard input station from its known outboard loads, in the step's column:
    S_I f = e_known - P_I).  affine: the step
    (the transfers' affine parts, the drives' values, the ground's motion root_f; every body);
    otherwise a homogeneous response, whose kinematics are zero at a parent outside act (the
    bodies of bodies).  work (9, 12) scratch: nothing is allocated."""
    f_i = work[0, 0:6]
    f_o = work[0, 6:12]
    zi = work[1]
    if affine:
        for i in range(6):
            z[0, i] = root_f[i]
            z[0, 6 + i] = 0.0
    for q in range(bodies.shape[0]):
        k = bodies[q]
        jb, jh = 2 * k + 1, 2 * k
        p = parent[k]
        for i in range(6):
            if p < 0:
                f_i[i] = z[0, i] if affine else 0.0
            elif affine or act[p]:
                f_i[i] = z[2 * p + 2, i]
            else:
                f_i[i] = 0.0
        if p < 0 and affine:
            for i in range(6):
                z[0, 6 + i] += _row_mv(s_mat[jh], i, f_i, 6) + p_col[jh, i]
        kd = kind[jh]
        if kd == IDENTITY:
            for i in range(6):
                f_o[i] = f_i[i]
        elif kd == TRANSFER:
            s_h, u_h = s_mat[jh], u[jh]
            for i in range(6):
                zi[i] = f_i[i]
                zi[6 + i] = _row_mv(s_h, i, f_i, 6) + p_col[jh, i]
            for i in range(6):
                f_o[i] = _row_mv(u_h, i, zi, 12) + (u_h[i, 12] if affine else 0.0)
        elif kd == LOCKED:
            a6 = work[2:8, 0:6]
            x = work[2:8, 6:7]
            for i in range(6):
                for j in range(6):
                    a6[i, j] = s_mat[jb, i, j]
                x[i, 0] = (known_loads[jh, 6 + i] if affine else 0.0) - p_col[jb, i]
            if not _gauss_solve(a6, x, 6, 1):
                return jh + 1
            for i in range(6):
                f_o[i] = x[i, 0]
        else:                           # JOINT
            for c3 in range(3):
                nu[k, c3] = (joint_drive[k, c3, 2] if affine and
                             joint_dof[k, c3] == PRESCRIBED else 0.0)
            mf = free_store[k, 3]
            for a in range(mf):
                xv = k_col[k, a]
                for j in range(6):
                    xv -= h_store[k, a, j] * f_i[j]
                nu[k, free_store[k, a]] = xv
            u_h = u[jh]
            for i in range(6):
                f_o[i] = _row_mv(u_h, i, f_i, 6) + (u_h[i, 12] if affine else 0.0)
            for c3 in range(3):
                if joint_dof[k, c3] != 0:
                    for i in range(6):
                        f_o[i] += u[jh, i, 6 + c3] * nu[k, c3]
        s_b = s_mat[jb]
        for i in range(6):
            z[jb, i] = f_o[i]
            z[jb, 6 + i] = _row_mv(s_b, i, f_o, 6) + p_col[jb, i]
        if kd == JOINT:
            for c3 in range(3):
                xv = 0.0
                if joint_dof[k, c3] != 0:
                    for i in range(6):
                        xv += u[jh, 6 + i, c3] * z[jb, 6 + i]
                tau[k, c3] = xv
        zb, u_b = z[jb], u[jb]
        for i in range(12):
            z[jb + 1, i] = _row_mv(u_b, i, zb, 12) + (u_b[i, 12] if affine else 0.0)
    return 0

