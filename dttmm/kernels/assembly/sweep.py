"""Assembly sweeps: solve one step's chain of affine transfers with its boundary conditions.

Full-state sweep (docs/assembly.md).  Stations j = 0 .. 2n: station 0 is the ground, station
2k+1 body k's input point, station 2k+2 its output point; element j joins station j to j+1.
Each station's 12 entries are split into f (6) and e (6), carried as f = S e + P (the Riccati
transform of Horner and Pilkey).  The split changes where the boundary makes it:
  SPLIT_A  f = [a, m], e = [phi, q]   after a ball joint (m = 0 there)
  SPLIT_B  f = [a, phi], e = [m, q]   from the ground (a and phi prescribed)
  SPLIT_C  f = [m, q], e = [a, phi]   after a hinge whose loads are known (consistent start)
Element kinds: TRANSFER (affine matrix), IDENTITY (fixed hinge), BALL (m = 0 inboard, outboard
rotation free), LOCKED (inboard loads known, outboard motion free), JOINT (a joint with free
coordinates, kernels/transfers/joint.py: the full-state tree sweep only, tree_sweep.py).

Full-state direct sweep: every station as z = Z x + o in terms of a 6-parameter vector x, the
matrices multiplied out from the root (the paper's way).  A ball joint or a LOCKED hinge swaps
parameters instead: the inboard conditions fix some of x, the outboard's free entries join it.

Reduced sweeps (all ball joints): each body folds into a 6 x 7 map on [a; q; 1], solved either by
Riccati (f = a, e = q) or by multiplying the maps out (direct).
"""
import numpy as np
from numba import njit

from .. import CONTRACT, kernel, no_alloc_kernel
from ..algebra.mat3 import (add1, inv3, least_norm_solve3, matmul, matmul_into, matvec,
                            matvec_into, put1, put2, t_inverse, t_of_mat)

TRANSFER, IDENTITY, BALL, LOCKED, JOINT = 0, 1, 2, 3, 4
LOST_ACCURACY = 1 << 30      # status of a direct sweep whose products cancelled
DIRECT_TOLERANCE = 1e-4      # largest relative transfer residual a direct solution may leave
SPLIT_A, SPLIT_B, SPLIT_C = 0, 1, 2
F_IDX = np.array([[0, 1, 2, 6, 7, 8], [0, 1, 2, 3, 4, 5], [6, 7, 8, 9, 10, 11]], dtype=np.int64)
E_IDX = np.array([[3, 4, 5, 9, 10, 11], [6, 7, 8, 9, 10, 11], [0, 1, 2, 3, 4, 5]], dtype=np.int64)
# A pinned tip's least-norm solves drop singular values below TIP_RCOND times the largest.
TIP_RCOND = 1e-12


@kernel
def _station_basis(split, s_mat, p_vec, basis, offset):
    """z = basis e + offset for a station carried as f = S e + P."""
    f_idx = F_IDX[split]
    e_idx = E_IDX[split]
    for r in range(12):
        offset[r] = 0.0
        for c in range(6):
            basis[r, c] = 0.0
    for r in range(6):
        offset[f_idx[r]] = p_vec[r]
        basis[e_idx[r], r] = 1.0
        for c in range(6):
            basis[f_idx[r], c] = s_mat[r, c]


@kernel
def _station_state(split, s_mat, p_vec, e, z):
    """z = basis e + offset (_station_basis) without the basis: z_e = e, z_f = S e + P."""
    f_idx = F_IDX[split]
    e_idx = E_IDX[split]
    for r in range(6):
        x = p_vec[r]
        for c in range(6):
            x += s_mat[r, c] * e[c]
        z[f_idx[r]] = x
        z[e_idx[r]] = e[r]


@kernel
def _tip_system(basis, offset, tip_pinned):
    """W e = rhs for the tip: m = 0 and q = 0 (free), or a = 0 and m = 0 (joined to the ground by
    a ball joint)."""
    w = np.empty((6, 6))
    rhs = np.empty(6)
    first = 0 if tip_pinned else 9
    for r in range(3):
        rhs[r] = -offset[6 + r]
        rhs[3 + r] = -offset[first + r]
        for c in range(6):
            w[r, c] = basis[6 + r, c]
            w[3 + r, c] = basis[first + r, c]
    return w, rhs


@kernel
def _solve_tip(w, rhs, tip_pinned):
    """(solved, e) of the tip's W e = rhs.  A pinned tip takes the least-norm solution: a chain
    closed between two fixed points can leave the force along an inextensible member statically
    indeterminate (no pre-stress is assumed; docs/assembly.md)."""
    if tip_pinned:
        return True, matvec(np.linalg.pinv(w, rcond=TIP_RCOND), rhs)
    if abs(np.linalg.det(w)) == 0.0:
        return False, rhs
    return True, np.linalg.solve(w, rhs)


@kernel
def _moment_force_system(basis, offset, target):
    """W e = rhs: the rows of z = basis e + offset that fix [m; q] = target."""
    w = np.empty((6, 6))
    rhs = np.empty(6)
    for r in range(6):
        rhs[r] = target[r] - offset[6 + r]
        for c in range(6):
            w[r, c] = basis[6 + r, c]
    return w, rhs


@no_alloc_kernel
def riccati_step(u, s, p, s_new, p_new, t_inv, t_vec, work):
    """One affine element of the full Riccati sweep (docs/assembly.md), u's rows and columns in
    the station's split order, f = z[0:6], e = z[6:12] (SPLIT_B's own order; riccati_full
    gathers the other splits' with _split_order): with the element's blocks U_ff, U_fe, U_ef,
    U_ee and constants c_f, c_e and the inboard f = S e + P,
      T = U_ef S + U_ee,  t = U_ef P + c_e,  S' = (U_ff S + U_fe) T^-1,  P' = U_ff P + c_f - S' t,
    so that e_in = T^-1 (e_out - t) on the way back.  In loops of fixed bounds on the 6 x 6
    blocks (no BLAS or LAPACK call, no allocation: work is 6 x 13); False if T is singular (a
    zero pivot).  (Fixed bounds and no index tables: 0.44 against 0.61 us per call, measured in
    one process.)"""
    # work[:, :6] = T, work[:, 6:12] = I (becomes T^-1), work[:, 12] = U_ff S + U_fe's scratch
    for r in range(6):
        tv = u[6 + r, 12]
        for k in range(6):
            tv += u[6 + r, k] * p[k]
        t_vec[r] = tv
        for c in range(6):
            x = u[6 + r, 6 + c]
            for k in range(6):
                x += u[6 + r, k] * s[k, c]
            work[r, c] = x
            work[r, 6 + c] = 1.0 if r == c else 0.0
    # Gauss-Jordan with partial pivoting on [T | I]
    for c in range(6):
        piv = c
        big = abs(work[c, c])
        for r in range(c + 1, 6):
            if abs(work[r, c]) > big:
                piv = r
                big = abs(work[r, c])
        if big == 0.0:
            return False
        if piv != c:
            for j in range(12):
                work[c, j], work[piv, j] = work[piv, j], work[c, j]
        inv = 1.0 / work[c, c]
        for j in range(12):
            work[c, j] *= inv
        for r in range(6):
            if r != c:
                f = work[r, c]
                for j in range(12):
                    work[r, j] -= f * work[c, j]
    for r in range(6):
        for c in range(6):
            t_inv[r, c] = work[r, 6 + c]
    # S' = (U_ff S + U_fe) T^-1, P' = U_ff P + c_f - S' t
    for r in range(6):
        for c in range(6):
            x = u[r, 6 + c]
            for k in range(6):
                x += u[r, k] * s[k, c]
            work[c, 12] = x
        pv = u[r, 12]
        for k in range(6):
            pv += u[r, k] * p[k]
        for c in range(6):
            x = 0.0
            for k in range(6):
                x += work[k, 12] * t_inv[k, c]
            s_new[r, c] = x
        for k in range(6):
            pv -= s_new[r, k] * t_vec[k]
        p_new[r] = pv
    return True


@kernel
def _split_order(u, split, out):
    """out = u with rows and columns in the split's order [f; e] (riccati_step's)."""
    order = np.empty(12, dtype=np.int64)
    for i in range(6):
        order[i] = F_IDX[split, i]
        order[6 + i] = E_IDX[split, i]
    for r in range(12):
        for c in range(12):
            out[r, c] = u[order[r], order[c]]
        out[r, 12] = u[order[r], 12]


@kernel
def riccati_full(kind, u, known_loads, root_f, tip_pinned, split, s_mat, p_vec, t_inv, t_vec,
                 g_mat, g_vec, z):
    """Solve one step; returns 0, or j + 1 if element j (or the tip, j = n_el) is singular.

    kind (n_el,), u (n_el, 12, 13): element transfers; known_loads (n_el, 12): for LOCKED
    elements [m_in, q_in, m_out, q_out]; root_f: [a, phi] of the ground station; tip_pinned: the
    tip is joined to the ground by a ball joint (else free).
    Scratch: split, s_mat, p_vec (stations), t_inv, t_vec, g_mat, g_vec (elements).  Output z
    (n_el + 1, 12): every station's state.
    """
    n_el = kind.shape[0]
    basis = np.empty((12, 6))
    offset = np.empty(12)
    work = np.empty((6, 13))
    ordered = np.empty((12, 13))
    split[0] = SPLIT_B
    s_mat[0, :, :] = 0.0
    put1(p_vec[0], root_f)
    for j in range(n_el):
        sp = split[j]
        k = kind[j]
        if k == IDENTITY:
            split[j + 1] = sp
            put2(s_mat[j + 1], s_mat[j])
            put1(p_vec[j + 1], p_vec[j])
        elif k == TRANSFER:
            split[j + 1] = sp
            if sp == SPLIT_B:
                done = riccati_step(u[j], s_mat[j], p_vec[j], s_mat[j + 1], p_vec[j + 1],
                                    t_inv[j], t_vec[j], work)
            else:
                _split_order(u[j], sp, ordered)
                done = riccati_step(ordered, s_mat[j], p_vec[j], s_mat[j + 1], p_vec[j + 1],
                                    t_inv[j], t_vec[j], work)
            if not done:
                return j + 1
        else:
            _station_basis(sp, s_mat[j], p_vec[j], basis, offset)
            if k == BALL:
                w, rhs = _moment_force_system(basis, offset, np.zeros(6))
            else:
                w, rhs = _moment_force_system(basis, offset, known_loads[j, 0:6])
            if abs(np.linalg.det(w)) == 0.0:
                return j + 1
            wi = np.linalg.inv(w)
            put1(g_vec[j], matvec(wi, rhs))
            s_mat[j + 1, :, :] = 0.0
            p_vec[j + 1, :] = 0.0
            if k == BALL:
                # inboard e = g + G q; outboard f = [a, m] = [(basis G) q + basis g + offset; 0]
                put2(g_mat[j], wi[:, 3:6])
                bg = matmul(basis, g_mat[j])
                bo = matvec(basis, g_vec[j]) + offset
                split[j + 1] = SPLIT_A
                put2(s_mat[j + 1, 0:3, 3:6], bg[0:3])
                put1(p_vec[j + 1, 0:3], bo[0:3])
            else:
                g_mat[j, :, :] = 0.0
                split[j + 1] = SPLIT_C
                put1(p_vec[j + 1], known_loads[j, 6:12])
    _station_basis(split[n_el], s_mat[n_el], p_vec[n_el], basis, offset)
    w, rhs = _tip_system(basis, offset, tip_pinned)
    solved, e = _solve_tip(w, rhs, tip_pinned)
    if not solved:
        return n_el + 1
    _station_state(split[n_el], s_mat[n_el], p_vec[n_el], e, z[n_el])
    e_in = np.empty(6)
    for j in range(n_el - 1, -1, -1):
        k = kind[j]
        e_out = E_IDX[split[j + 1]]
        for r in range(6):
            if k == IDENTITY:
                x = z[j + 1, e_out[r]]
            elif k == TRANSFER:         # e_in = T^-1 (e_out - t)
                x = 0.0
                for c in range(6):
                    x += t_inv[j, r, c] * (z[j + 1, e_out[c]] - t_vec[j, c])
            else:                       # a ball joint or LOCKED: e = g + G q_out
                x = g_vec[j, r]
                for c in range(3):
                    x += g_mat[j, r, c] * z[j + 1, 9 + c]
            e_in[r] = x
        _station_state(split[j], s_mat[j], p_vec[j], e_in, z[j])
    return 0


@kernel
def direct_full(kind, u, known_loads, root_f, tip_pinned, zmat, zoff, x0, nmat, z):
    """Multiply the transfers out from the root; returns 0 or j + 1 for a singular element j.

    zmat (n_el + 1, 12, 6), zoff (n_el + 1, 12): stations as z = Z x + o; x0 (n_el, 6),
    nmat (n_el, 6, 3): at a transition j the inboard parameters are x0[j] + nmat[j] y, with y
    the first three outboard parameters (a ball joint; nmat = 0 for a LOCKED hinge)."""
    n_el = kind.shape[0]
    # ground station: a, phi known; x = [m, q]
    zmat[0, :, :] = 0.0
    zoff[0, :] = 0.0
    put1(zoff[0, 0:6], root_f)
    for i in range(6):
        zmat[0, 6 + i, i] = 1.0
    for j in range(n_el):
        k = kind[j]
        if k == IDENTITY:
            put2(zmat[j + 1], zmat[j])
            put1(zoff[j + 1], zoff[j])
        elif k == TRANSFER:
            uj = u[j, :, 0:12]
            matmul_into(uj, zmat[j], zmat[j + 1])
            matvec_into(uj, zoff[j], zoff[j + 1])
            add1(zoff[j + 1], u[j, :, 12])
        elif k == BALL:
            cm = zmat[j, 6:9, :]
            if np.linalg.matrix_rank(cm) < 3:
                return j + 1
            # x = x0 + N y with cm x0 = -o_m (least norm) and N spanning the null space of cm
            _, _, vt = np.linalg.svd(cm)
            matvec_into(np.linalg.pinv(cm), -zoff[j, 6:9], x0[j])
            put2(nmat[j], vt[3:6].T)
            inner_z = matmul(zmat[j], nmat[j])
            inner_o = matvec(zmat[j], x0[j]) + zoff[j]
            zmat[j + 1, :, :] = 0.0
            zoff[j + 1, :] = 0.0
            for r in (0, 1, 2, 9, 10, 11):
                zoff[j + 1, r] = inner_o[r]
                for c in range(3):
                    zmat[j + 1, r, c] = inner_z[r, c]
            for i in range(3):
                zmat[j + 1, 3 + i, 3 + i] = 1.0      # the outboard rotation is a new parameter
        else:
            w = zmat[j, 6:12, :]
            if abs(np.linalg.det(w)) == 0.0:
                return j + 1
            put1(x0[j], np.linalg.solve(w, known_loads[j, 0:6] - zoff[j, 6:12]))
            nmat[j, :, :] = 0.0
            zmat[j + 1, :, :] = 0.0
            zoff[j + 1, :] = 0.0
            put1(zoff[j + 1, 6:12], known_loads[j, 6:12])
            for i in range(6):
                zmat[j + 1, i, i] = 1.0              # outboard a and phi are new parameters
    w, rhs = _tip_system(zmat[n_el], zoff[n_el], tip_pinned)
    solved, x = _solve_tip(w, rhs, tip_pinned)
    if not solved:
        return n_el + 1
    matvec_into(zmat[n_el], x, z[n_el])
    add1(z[n_el], zoff[n_el])
    for j in range(n_el - 1, -1, -1):
        if kind[j] == BALL or kind[j] == LOCKED:
            x = x0[j] + matvec(nmat[j], x[0:3])
        matvec_into(zmat[j], x, z[j])
        add1(z[j], zoff[j])
    if transfer_residual(kind, u, z) > DIRECT_TOLERANCE:
        return LOST_ACCURACY
    return 0


@kernel
def transfer_residual(kind, u, z):
    """Largest relative residual of the TRANSFER elements' relations z_j+1 = U_j z_j + u_j, by
    block (a, phi, m, q): max |residual| over max (|z_j+1| + |U_j| |z_j| + |u_j|) of the block's
    rows.  What a solution built from multiplied-out transfers has lost to cancellation (a
    Riccati solution leaves rounding)."""
    worst = 0.0
    for j in range(kind.shape[0]):
        if kind[j] != TRANSFER:
            continue
        for b in range(4):
            res_max = 0.0
            scale_max = 0.0
            for r in range(3 * b, 3 * b + 3):
                res = z[j + 1, r] - u[j, r, 12]
                scale = abs(z[j + 1, r]) + abs(u[j, r, 12])
                for c in range(12):
                    res -= u[j, r, c] * z[j, c]
                    scale += abs(u[j, r, c] * z[j, c])
                res_max = max(res_max, abs(res))
                scale_max = max(scale_max, scale)
            if scale_max > 0.0:
                worst = max(worst, res_max / scale_max)
    return worst


@kernel
def fold_ball_body(u, v, phi_map):
    """Fold a body between moment-free cuts into v (6 x 7): [a_O; q_O] = v [a_I; q_I; 1], and
    phi_map (3 x 7): phi = phi_map [a_I; q_I; 1], from its full transfer u with m_I = m_O = 0:
    0 = U_ma a + U_mphi phi + U_mq q + u_m.  (Columns and rows [a; q; 1] of u: 0..2, 9..12.)"""
    _, ump_inv = t_inverse(t_of_mat(u[6:9, 3:6]))        # (not finite where singular)
    for i in range(3):
        for c in range(7):
            cc = c if c < 3 else c + 6
            phi_map[i, c] = -(ump_inv[3 * i] * u[6, cc] + ump_inv[3 * i + 1] * u[7, cc]
                              + ump_inv[3 * i + 2] * u[8, cc])
    for r in range(6):
        rr = r if r < 3 else r + 6
        for c in range(7):
            cc = c if c < 3 else c + 6
            v[r, c] = (u[rr, cc] + u[rr, 3] * phi_map[0, c] + u[rr, 4] * phi_map[1, c]
                       + u[rr, 5] * phi_map[2, c])


@njit(cache=True, inline='always', fastmath=CONTRACT)
def riccati_reduced_step(v, s_in, p_in, s_out, p_out, t_inv, t_vec, t, num):
    """One body of the reduced Riccati sweep, a = S q + P at its input -> at its output:
    q_I = T^-1 (q_O - tv), T = V_qa S + V_qq, tv = V_qa P + v_q;
    a_O = S' q_O + P', S' = (V_aa S + V_aq) T^-1, P' = V_aa P + v_a - S' tv.
    v (6, 7); t, num: 3 x 3 scratch.  Returns det T (0: singular)."""
    for i in range(3):
        tvi = v[3 + i, 6]
        for j in range(3):
            t[i, j] = (v[3 + i, 3 + j] + v[3 + i, 0] * s_in[0, j] + v[3 + i, 1] * s_in[1, j]
                       + v[3 + i, 2] * s_in[2, j])
            num[i, j] = (v[i, 3 + j] + v[i, 0] * s_in[0, j] + v[i, 1] * s_in[1, j]
                         + v[i, 2] * s_in[2, j])
            tvi += v[3 + i, j] * p_in[j]
        t_vec[i] = tvi
    det = inv3(t, t_inv)
    if det == 0.0:
        return det
    matmul_into(num, t_inv, s_out)
    for i in range(3):
        pi = v[i, 6]
        for j in range(3):
            pi += v[i, j] * p_in[j] - s_out[i, j] * t_vec[j]
        p_out[i] = pi
    return det


@kernel
def riccati_reduced_tip(tip_pinned, s_tip, p_tip, aq_tip):
    """[a; q] at the tip from a = S q + P there: q = 0 (free) or a = 0 (tip_pinned; the least-norm
    q, as _solve_tip's, by least_norm_solve3: it allocates nothing)."""
    if tip_pinned:
        q = least_norm_solve3(s_tip, (-p_tip[0], -p_tip[1], -p_tip[2]), TIP_RCOND)
        for i in range(3):
            aq_tip[i] = 0.0
            aq_tip[3 + i] = q[i]
    else:
        for i in range(3):
            aq_tip[i] = p_tip[i]
            aq_tip[3 + i] = 0.0


@njit(cache=True, inline='always', fastmath=CONTRACT)
def riccati_reduced_recover(k, s_mat, p_vec, t_inv, t_vec, aq):
    """[a; q] at body k's input from its output's: q_I = T^-1 (q_O - tv), a_I = S q_I + P."""
    for i in range(3):
        aq[k, 3 + i] = (t_inv[k, i, 0] * (aq[k + 1, 3] - t_vec[k, 0])
                        + t_inv[k, i, 1] * (aq[k + 1, 4] - t_vec[k, 1])
                        + t_inv[k, i, 2] * (aq[k + 1, 5] - t_vec[k, 2]))
    for i in range(3):
        aq[k, i] = (s_mat[k, i, 0] * aq[k, 3] + s_mat[k, i, 1] * aq[k, 4]
                    + s_mat[k, i, 2] * aq[k, 5] + p_vec[k, i])


@kernel
def riccati_reduced(v, a_root, tip_pinned, s_mat, p_vec, t_inv, t_vec, aq):
    """Reduced Riccati sweep on [a; q]: a = S q + P.  v (n, 6, 7); aq (n + 1, 6) output.
    Tip: q = 0 (free) or a = 0 (tip_pinned)."""
    n = v.shape[0]
    s_mat[0, :, :] = 0.0
    put1(p_vec[0], a_root)
    t = np.empty((3, 3))
    num = np.empty((3, 3))
    for k in range(n):
        if riccati_reduced_step(v[k], s_mat[k], p_vec[k], s_mat[k + 1], p_vec[k + 1], t_inv[k],
                                t_vec[k], t, num) == 0.0:
            return k + 1
    riccati_reduced_tip(tip_pinned, s_mat[n], p_vec[n], aq[n])
    for k in range(n - 1, -1, -1):
        riccati_reduced_recover(k, s_mat, p_vec, t_inv, t_vec, aq)
    return 0


@kernel
def direct_reduced(v, a_root, tip_pinned, aq):
    """Multiply the reduced maps out (the paper's way), solve q_0 from the tip (free: q_N = 0;
    pinned: a_N = 0), and propagate forward.  Loses accuracy on long or stiff chains
    (docs/assembly.md)."""
    n = v.shape[0]
    prod = np.eye(7)
    step = np.eye(7)
    for k in range(n):
        put2(step[0:6, :], v[k])
        prod = matmul(step, prod)
    r = 0 if tip_pinned else 3
    pqq = np.ascontiguousarray(prod[r:r + 3, 3:6])
    rhs = matvec(prod[r:r + 3, 0:3], a_root) + prod[r:r + 3, 6]
    put1(aq[0, 0:3], a_root)
    solved, q0 = _solve_tip(pqq, -rhs, tip_pinned)     # least norm in the root's unknowns
    if not solved:
        return n + 1
    put1(aq[0, 3:6], q0)
    for k in range(n):
        matvec_into(v[k, :, 0:6], aq[k], aq[k + 1])
        add1(aq[k + 1], v[k, :, 6])
    # propagated forward, the tip condition shows what the products lost
    first = 0 if tip_pinned else 3
    scale = 0.0
    for k in range(n + 1):
        for i in range(3):
            scale = max(scale, abs(aq[k, first + i]))
    for i in range(3):
        if abs(aq[n, first + i]) > DIRECT_TOLERANCE * scale:
            return LOST_ACCURACY
    return 0
