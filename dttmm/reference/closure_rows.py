"""The reference's closing joints (newton_euler.py's docstring, "Loops"): each side's point and
frame, the constraint rows and their columns in the global system, and its solve with the
multipliers by a truncated SVD of the Delassus matrix.  The tree's rows are in equations.py.
"""
import numpy as np

from ..kernels import kernel
from ..kernels.algebra.mat3 import dot, matmul, matvec, put1, put2
from .beam_terms import _flex_size
from .rows import _ANGLE_A, _ANGLE_B, _DOT, _FORCE, _GAP_A, _GAP_WORLD, _ROTATION_A, _SPRING_DAMPER
from .rotations import _cross, _log_rot

# singular values of the closing joints' Delassus matrix below this fraction of its largest
# count as zero (redundant constraints; a loop passing a singular position)
LOOP_RCOND = 1e-10



@kernel
def _closure_side(k, local, on_end, rot, omega, r_in, v_in, rho_o, rot_o, omega_o, v_o, acc_v,
                  alpha_v, r_g, v_g, a_g, rot_g, w_g, wd_g):
    """One side of a closing joint (newton_euler.py's docstring, "Loops"): its point's arm from the
    body's input point, position, velocity and the known part of its acceleration (the velocity
    terms; all of it on the ground), and its frame, the frame's angular velocity and the known
    part of its angular acceleration."""
    if k < 0:
        arm = matvec(rot_g, local)
        acc = a_g + _cross(wd_g, arm) + _cross(w_g, _cross(w_g, arm))
        return arm, r_g + arm, v_g + _cross(w_g, arm), acc, rot_g, w_g, wd_g
    if on_end:
        return (rho_o[k], r_in[k] + rho_o[k], v_o[k], acc_v[k], rot_o[k], omega_o[k],
                alpha_v[k])
    arm = matvec(rot[k], local)
    w = omega[k]
    return (arm, r_in[k] + arm, v_in[k] + _cross(w, arm), _cross(w, _cross(w, arm)), rot[k], w,
            np.zeros(3))


@kernel
def _closure_columns(s, row, k, on_end, coef_a, coef_alpha, coef_section, sign, b_r, b_t,
                     e_col0, m_off, body_kind, beam_params, rods):
    """Add sign * (coef_a . a_k + coef_alpha . alpha_k) to a closing joint's row and, on a
    beam's or strain rod's end, sign * (B_r^T coef_a + B_t^T coef_section) to its modal or
    strain columns (the end's point moves with B_r eta'', its section turns with B_t eta'')."""
    if k < 0:
        return
    for i in range(3):
        s[row, 6 * k + i] += sign * coef_a[i]
        s[row, 6 * k + 3 + i] += sign * coef_alpha[i]
    if on_end:
        ce = e_col0 + m_off[k]
        for j in range(_flex_size(k, body_kind, beam_params, rods)):
            for i in range(3):
                s[row, ce + j] += sign * (b_r[k, i, j] * coef_a[i]
                                          + b_t[k, i, j] * coef_section[i])


@kernel
def _closure_rows(s, b, loops, rot, omega, r_in, v_in, rho_o, rot_o, omega_o, v_o, acc_v,
                  alpha_v, b_r, b_t, e_col0, m_off, body_kind, beam_params, rods, r_g, v_g, a_g,
                  rot_g, w_g, wd_g):
    """The closing joints' rows and their multipliers' columns (newton_euler.py's docstring,
    "Loops"): per scalar constraint g (a gap e . (p_b - p_a), e fixed in the world or in side a's
    frame, or a dot (F_a x) . (F_b y)), the row g'' + 2 zeta W g' + W^2 g = 0 (linear in the
    accelerations) and, in the dynamic rows, the column -J^T of its multiplier (the joint's
    force and couple do no work on what the joint allows).  Returns the world direction of
    every row's multiplier on side b (a force for a gap, a couple for a dot)."""
    col0, kind, owner, v1, v2, bodies, points, ends, gains, v3, target, _, law, values = loops
    directions = np.zeros((kind.shape[0], 3))
    for r in range(kind.shape[0]):
        c = owner[r]
        row = col0 + r
        ka, kb = bodies[c, 0], bodies[c, 1]
        end_a, end_b = ends[c, 0] != 0, ends[c, 1] != 0
        arm_a, p_a, v_a, acc_a, f_a, w_a, al_a = _closure_side(
            ka, points[c, 0], end_a, rot, omega, r_in, v_in, rho_o, rot_o, omega_o, v_o, acc_v,
            alpha_v, r_g, v_g, a_g, rot_g, w_g, wd_g)
        arm_b, p_b, v_b, acc_b, f_b, w_b, al_b = _closure_side(
            kb, points[c, 1], end_b, rot, omega, r_in, v_in, rho_o, rot_o, omega_o, v_o, acc_v,
            alpha_v, r_g, v_g, a_g, rot_g, w_g, wd_g)
        zero = np.zeros(3)
        if kind[r] == _ANGLE_A or kind[r] == _ANGLE_B or kind[r] == _ROTATION_A:
            # a driven angle, or an elastic hinge's rotation n . log(F_a^T F_b R0^T) about n
            # fixed in a's frame; its rate n . (w_b - w_a)
            n = matvec(f_b if kind[r] == _ANGLE_B else f_a, v3[r])
            dw = w_b - w_a
            if kind[r] == _ROTATION_A:
                r0 = np.empty((3, 3))
                put1(r0[:, 0], v1[r])
                put1(r0[:, 1], v2[r])
                put1(r0[:, 2], _cross(v1[r], v2[r]))
                g = dot(v3[r], _log_rot(matmul(matmul(f_a.T, f_b), r0.T))) - target[r, 0]
            else:
                x = matvec(f_a, v1[r])
                y = matvec(f_b, v2[r])
                g = np.arctan2(dot(n, _cross(x, y)), dot(x, y)) - target[r, 0]
                g = (g + np.pi) % (2.0 * np.pi) - np.pi
            gd = dot(n, dw)
            kappa = dot(_cross(w_b if kind[r] == _ANGLE_B else w_a, n), dw) + dot(n, al_b - al_a)
            _closure_columns(s, row, kb, end_b, zero, n, n, 1.0, b_r, b_t, e_col0, m_off,
                             body_kind, beam_params, rods)
            _closure_columns(s, row, ka, end_a, zero, n, n, -1.0, b_r, b_t, e_col0, m_off,
                             body_kind, beam_params, rods)
            put1(directions[r], n)
        elif kind[r] == _DOT:               # (F_a x) . (F_b y) = 0
            x = matvec(f_a, v1[r])
            y = matvec(f_b, v2[r])
            cv = _cross(y, x)
            dw = w_b - w_a
            g = dot(x, y)
            gd = dot(dw, cv)
            kappa = (dot(dw, _cross(_cross(w_b, y), x) + _cross(y, _cross(w_a, x)))
                     + dot(cv, al_b - al_a))
            _closure_columns(s, row, kb, end_b, zero, cv, cv, 1.0, b_r, b_t, e_col0, m_off,
                             body_kind, beam_params, rods)
            _closure_columns(s, row, ka, end_a, zero, cv, cv, -1.0, b_r, b_t, e_col0, m_off,
                             body_kind, beam_params, rods)
            put1(directions[r], cv)
        else:                               # e . (p_b - p_a) = 0
            e = v1[r] if kind[r] == _GAP_WORLD else matvec(f_a, v1[r])
            d = p_b - p_a
            dd = v_b - v_a
            g = dot(e, d)
            gd = dot(e, dd)
            kappa = dot(e, acc_b - acc_a)
            if kind[r] == _GAP_A:           # e turns with side a: its rates enter
                we = _cross(w_a, e)
                gd += dot(we, d)
                kappa += dot(_cross(w_a, we), d) + 2.0 * dot(we, dd)
                ed = _cross(e, d)           # (alpha_a x e) . d = alpha_a . (e x d)
                kappa += dot(ed, al_a)
                _closure_columns(s, row, ka, end_a, zero, ed, ed, 1.0, b_r, b_t, e_col0, m_off,
                                 body_kind, beam_params, rods)
            _closure_columns(s, row, kb, end_b, e, _cross(arm_b, e), zero, 1.0, b_r, b_t,
                             e_col0, m_off, body_kind, beam_params, rods)
            _closure_columns(s, row, ka, end_a, e, _cross(arm_a, e), zero, -1.0, b_r, b_t,
                             e_col0, m_off, body_kind, beam_params, rods)
            put1(directions[r], e)
            g -= target[r, 0]
        # a driven coordinate's row: (g - s)'' + 2 zeta W (g - s)' + W^2 (g - s) = 0
        gd -= target[r, 1]
        kappa -= target[r, 2]
        b[row] = -(kappa + gains[0] * gd + gains[1] * g)
        for j in range(col0):
            s[j, row] = -s[row, j]
        values[r, 0] = g                    # (a JointForce's row: q and q' themselves)
        values[r, 1] = gd
        if law[r, 0] == _SPRING_DAMPER or law[r, 0] == _FORCE:
            # a drive's row is its force: lam = -k (q - rest) - c q' (a spring), or
            # lam = f(t, q, q') in target[r, 2] (a JointForce; _Problem._args)
            for j in range(col0):
                s[row, j] = 0.0
            s[row, row] = 1.0
            b[row] = target[r, 2] - law[r, 1] * g - law[r, 2] * gd
    return directions


@kernel
def _solve_least_closure_force(s, b, col0, count):
    """Solve S x = b with the closing joints' multipliers in x[col0:col0 + count] (module
    docstring, "Loops"): the tree's system first, x = x0 - X lam with S_tree x0 = b_tree and
    S_tree X = (the multipliers' columns), then the constraints J x = b_c give the Delassus
    system (J X - S_cc) lam = J x0 - b_c (S_cc: a closing joint's spring's row, lam_r = F),
    solved by a truncated SVD: of the multipliers that satisfy
    it, the least (closing joints may be redundant, as a planar loop's spatial joints are, and a
    chain straight between two fixed points leaves its tension indeterminate: the DT-TMM
    sweeps' choice at a pinned tip), and a loop passing a singular position (a flat
    parallelogram) loses the direction that becomes singular there instead of dividing by
    it.  The accelerations do not depend on the choice."""
    tree = np.ascontiguousarray(s[:col0, :col0])
    rhs = np.empty((col0, count + 1))
    put1(rhs[:, 0], b[:col0])
    put2(rhs[:, 1:], s[:col0, col0:col0 + count])
    sol = np.linalg.solve(tree, rhs)
    jac = np.ascontiguousarray(s[col0:col0 + count, :col0])
    # a spring's row is lam_r = F (its S_cc 1, its J 0; a constraint's S_cc 0)
    delassus = matmul(jac, sol[:, 1:]) - s[col0:col0 + count, col0:col0 + count]
    target = matvec(jac, sol[:, 0]) - b[col0:col0 + count]
    u, sv, vt = np.linalg.svd(delassus)
    lam = np.zeros(count)
    ut = matvec(u.T, target)
    for i in range(count):
        if sv[i] > LOOP_RCOND * sv[0]:
            lam += (ut[i] / sv[i]) * vt[i]
    x = np.empty(col0 + count)
    put1(x[:col0], sol[:, 0] - matvec(sol[:, 1:], lam))
    put1(x[col0:], lam)
    return x
