"""Closing joints in the general loop's step (docs/loops.md, "The step with loops").

The tree's full-state sweep (tree_sweep.py::riccati_tree_full) is linear in the loads at its
stations.  Each scalar constraint r of a closing joint acts through one multiplier lam_r, its
loads on the sides' output stations the constraint's Jacobian transposed (a gap row: a force
lam_r e on side b at its point, -lam_r e on side a at a's point; a dot row: a couple
lam_r (y x x) on b, its opposite on a; the angle row of a driven coordinate or of an elastic
hinge's rotation: a couple lam_r n on b, its opposite on a, n the axis).  One sweep carries the
step and a P column per row (sweep_columns: the Riccati matrices once; a row's column only over
the bodies its loads reach), so that the stations are affine functions of the multipliers; the
rows' values

    gap (e world):   e . (a_b - a_a)
    gap (e in a):    e . (a_b - a_a) + (e x d) . alpha_a + (w_a x (w_a x e)) . d + 2 (w_a x e) . d'
    dot:             (y x x) . (alpha_b - alpha_a) + (w_b - w_a) . ((w_b x y) x x + y x (w_a x x))
    angle:           n . (alpha_b - alpha_a) + (w_s x n) . (w_b - w_a)   (n fixed in side s)

(a point's acceleration a = a_O + alpha x arm + w x (w x arm) from its body's output station;
_row_coefficients writes them as the Jacobian applied to the stations plus velocity terms)
are held at zero, the constraints' second derivatives (acceleration level, as the consistent
start and the pinned tip hold theirs), a driven coordinate's at its prescribed acceleration
(loops.target; its position and rate at its motion's in the projection).  After the step the
configuration and then the rates are projected back onto the loops along the step's own
responses to unit multipliers (project_onto_loops), so that every step ends with its loops
closed.

A row's response is zero outside the subtrees of its loaded bodies' topmost moving ancestors
(its active bodies, run_tables._column_bodies): below the ground (fixed, or moving as prescribed),
a loop that closes near it costs the sweep, the Delassus matrix and the projection only its
own bodies.

Scope (refused before a run otherwise, closures.check_runs_in_sweeps): rigid bodies, beams
and strain rods (closed at their output ends: the kernel model's end section is the side), a
fixed or moving ground (set_ground); every joint kind in the tree and closing it.
"""
import numpy as np

from .. import allocating_kernel, kernel, loop_tables, model_tables, no_alloc_kernel, sweep_tables
from ...elements.kinds import (ANGLE_A, ANGLE_B, DEFLECTS, DOT, GAP_A, GAP_WORLD, HAS_SLIDES,
                               ROTATION_A, UNDECLARED_BODY_KIND)
from ...elements import BEAM, RIGID, ROD
from ...elements.drives import FORCE, SPRING_DAMPER
from ...elements.beam import AXIAL_MODES, LENGTH, MODES, STIFFENING, TORSION_MODES
from ..transfers.strain_rod import rod_end, rod_tables_of
from ..transfers.joint import joint_offset
from ..algebra.mat3 import matvec, put1, put2, t_cross, t_mm, t_mmt, t_mv
from .loop_columns import recover_column, sweep_columns


# The closing joints as the loop reads them, and the loop's scratch for them: one flat
# structure (`loops`: kernels/schema.py::LOOPS, a FlatLoops), read through
# kernels/loop_tables.py.

# The rows' geometry on values (kernels/algebra/mat3.py's t_ algebra: 3-vectors as 3-tuples, frames
# as row-major 9-tuples), and the helpers below compiled without numba's reference counting
# (no_alloc_kernel): nothing is allocated per row, and no view or argument costs its pair of
# atomic counts (measured on the slider-crank and the Stewart platform: _side alone, counting
# the model's and the loops' named tuples at every call, took a fifth of the step; docs/loops.md,
# "What runs loops").
@kernel
def _v3(a, i):
    """Row i of an (m, 3) array as a 3-tuple."""
    return (a[i, 0], a[i, 1], a[i, 2])


@kernel
def _m9(a, k):
    """a[k] of an (n, 3, 3) array as a row-major 9-tuple."""
    return (a[k, 0, 0], a[k, 0, 1], a[k, 0, 2], a[k, 1, 0], a[k, 1, 1], a[k, 1, 2],
            a[k, 2, 0], a[k, 2, 1], a[k, 2, 2])


@kernel
def _dot(x, y):
    return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]


@kernel
def _add(x, y):
    return (x[0] + y[0], x[1] + y[1], x[2] + y[2])


@kernel
def _neg(x):
    return (-x[0], -x[1], -x[2])


@kernel
def _sub(x, y):
    return (x[0] - y[0], x[1] - y[1], x[2] - y[2])


@no_alloc_kernel
def _frame(rot, ground_rot, k):
    """Body k's frame (the ground's for k < 0) as a 9-tuple."""
    if k < 0:
        return (ground_rot[0, 0], ground_rot[0, 1], ground_rot[0, 2], ground_rot[1, 0],
                ground_rot[1, 1], ground_rot[1, 2], ground_rot[2, 0], ground_rot[2, 1],
                ground_rot[2, 2])
    return _m9(rot, k)


@no_alloc_kernel
def _beam_offset(params, k, rot, w, eta, eta_d):
    """Beam k's output point from its input point, rho = A p and its rate w x rho + A p', with
    p = [L - c(L) + u_x(L), v(L), w(L)] (docs/beam.md, "End sections": c(L) the
    foreshortening with geometric stiffening, beam.end_foreshortening; u_x(L) the stretch;
    sections.beam_output_offset in Python)."""
    bp, moments = model_tables.beam_params(params), model_tables.beam_moments(params)
    mode_off, ends = model_tables.mode_offset(params), model_tables.beam_ends(params)
    i0 = mode_off[k]
    m, mt, ma = int(bp[k, MODES]), int(bp[k, TORSION_MODES]), int(bp[k, AXIAL_MODES])
    px, py, pz = bp[k, LENGTH], 0.0, 0.0
    dx, dy, dz = 0.0, 0.0, 0.0
    for j in range(m):
        py += ends[k, j, 0] * eta[i0 + j]
        pz += ends[k, j, 0] * eta[i0 + m + j]
        dy += ends[k, j, 0] * eta_d[i0 + j]
        dz += ends[k, j, 0] * eta_d[i0 + m + j]
    if bp[k, STIFFENING] != 0.0:    # c = 1/2 eta^T D0 eta per plane, c' = eta'^T D0 eta
        for plane in range(2):
            for a in range(m):
                for b in range(m):
                    d0 = moments[k, a, 2 + m + b]
                    ea = eta[i0 + plane * m + a]
                    px -= 0.5 * ea * d0 * eta[i0 + plane * m + b]
                    dx -= eta_d[i0 + plane * m + a] * d0 * eta[i0 + plane * m + b]
    for j in range(ma):
        i = i0 + 2 * m + mt + j
        px += ends[k, m + mt + j, 0] * eta[i]
        dx += ends[k, m + mt + j, 0] * eta_d[i]
    f = _m9(rot, k)
    rho = t_mv(f, (px, py, pz))
    return rho, _add(t_cross(_v3(w, k), rho), t_mv(f, (dx, dy, dz)))


@no_alloc_kernel
def _rod_offset(params, k, rot, w, eta, eta_d):
    """Strain rod k's output point from its input point, rho = A p_L and its rate
    w x rho + A p_L' (strain_rod.rod_end: its end station in its frame; result.
    rod_output_offset in Python)."""
    steps, xi0, phi = rod_tables_of(params, k)[:3]
    mode_off = model_tables.mode_offset(params)
    i0, i1 = mode_off[k], mode_off[k + 1]
    q, qd = eta[i0:i1], eta_d[i0:i1]
    _, p_l, _, v_l, _, _ = rod_end(steps, xi0, phi, q, qd, qd)      # (accelerations unused)
    f = _m9(rot, k)
    rho = t_mv(f, p_l)
    return rho, _add(t_cross(_v3(w, k), rho), t_mv(f, v_l))


@no_alloc_kernel(entry=True)
def set_ground(loops, r, v, a, rot, w, wd):
    """The ground point's position r, velocity v and acceleration a and the ground frame's
    rotation rot, angular velocity w and acceleration wd where the rows are next written (a
    step's end, or t = 0): what a moving ground (Model.ground_state) brings into the rows."""
    ground = loop_tables.ground(loops)
    ground_motion = loop_tables.ground_motion(loops)
    ground_rot = loop_tables.ground_rot(loops)
    for i in range(3):
        ground[i] = r[i]
        ground_motion[0, i] = v[i]
        ground_motion[1, i] = a[i]
        ground_motion[2, i] = w[i]
        ground_motion[3, i] = wd[i]
        for j in range(3):
            ground_rot[i, j] = rot[i, j]


@no_alloc_kernel
def tree_points(params, rot, w, jq, jqd, eta, eta_d, defl, defl_rate, loops, bodies):
    """The output point and its velocity (loops.r_out, v_out) of the given bodies (in tree
    order; the others' are read as they are) from the rotations, angular velocities, joint
    coordinates and rates, the elastic hinges' deflections and rates and the beams' modal
    coordinates and rates: r_in = r_out,P + d (a joint's slides' d = A_P sum n_i q_i,
    kernels/transfers/joint.py::joint_offset, an elastic hinge's its deflection d, world,
    v_in = v_out,P + d'), r_out = r_in + A l_IO (a rigid body) or
    r_in + rho (a beam's deflected end, _beam_offset; a strain rod's, _rod_offset); the kernel
    model hangs every child at its parent's output point.  A body kind code none of these names
    is refused (elements/kinds.py, UNDECLARED_BODY_KIND)."""
    r_out = loop_tables.r_out(loops)
    v_out = loop_tables.v_out(loops)
    ground_motion = loop_tables.ground_motion(loops)
    ground_rot = loop_tables.ground_rot(loops)
    ground = loop_tables.ground(loops)
    parent = model_tables.parent(params)
    hinge_kind = model_tables.hinge_kind(params)
    hinge_params = model_tables.hinge_params(params)
    body_params, body_row = model_tables.body_params(params), model_tables.body_row(params)
    hinge_row, body_kind = model_tables.hinge_row(params), model_tables.body_kind(params)
    for q in range(bodies.shape[0]):
        k = bodies[q]
        p = parent[k]
        if p < 0:               # a root hangs at the ground point (moving with the ground)
            r = (ground[0], ground[1], ground[2])
            v = _v3(ground_motion, 0)
        else:
            r = _v3(r_out, p)
            v = _v3(v_out, p)
        if HAS_SLIDES[hinge_kind[k]]:      # the slides: kernels/transfers/joint.py
            f_p = _frame(rot, ground_rot, p)
            w_p = _v3(ground_motion, 2) if p < 0 else _v3(w, p)
            d, d_rate = joint_offset(hinge_kind[k], hinge_params[hinge_row[k]], f_p, w_p, jq[k],
                                     jqd[k])
            r = _add(r, d)
            v = _add(v, d_rate)
        elif DEFLECTS[hinge_kind[k]]:    # an elastic hinge's deflection, a free joint's flight
            r = _add(r, _v3(defl, k))
            v = _add(v, _v3(defl_rate, k))
        if body_kind[k] == BEAM:
            arm, arm_rate = _beam_offset(params, k, rot, w, eta, eta_d)
        elif body_kind[k] == ROD:
            arm, arm_rate = _rod_offset(params, k, rot, w, eta, eta_d)
        elif body_kind[k] == RIGID:
            row = body_row[k]
            arm = t_mv(_m9(rot, k), (body_params[row, 4], body_params[row, 5],
                                     body_params[row, 6]))
            arm_rate = t_cross(_v3(w, k), arm)
        else:
            raise ValueError(UNDECLARED_BODY_KIND)
        for i in range(3):
            r_out[k, i] = r[i] + arm[i]
            v_out[k, i] = v[i] + arm_rate[i]


@no_alloc_kernel
def _side(params, loops, rot, w, c, s):
    """(point, velocity, arm from the body's output point, frame, angular velocity) of closing
    joint c's side s, at the output points loops.r_out, v_out and the bodies' rot, w, as
    tuples (the ground's: its point, frame and motion in loops.ground, ground_rot,
    ground_motion, the arm from the ground point)."""
    body = loop_tables.body(loops)
    point = loop_tables.point(loops)
    ground = loop_tables.ground(loops)
    ground_rot = loop_tables.ground_rot(loops)
    ground_motion = loop_tables.ground_motion(loops)
    r_out = loop_tables.r_out(loops)
    v_out = loop_tables.v_out(loops)
    k = body[c, s]
    local = (point[c, s, 0], point[c, s, 1], point[c, s, 2])
    if k < 0:
        f = _frame(rot, ground_rot, k)
        arm = t_mv(f, local)
        w_g = _v3(ground_motion, 2)
        return (_add((ground[0], ground[1], ground[2]), arm),
                _add(_v3(ground_motion, 0), t_cross(w_g, arm)), arm, f, w_g)
    f = _m9(rot, k)
    w_k = _v3(w, k)
    centre, row = model_tables.body_params(params), model_tables.body_row(params)[k]
    arm = t_mv(f, _sub(local, (centre[row, 4], centre[row, 5], centre[row, 6])))
    return (_add(_v3(r_out, k), arm), _add(_v3(v_out, k), t_cross(w_k, arm)), arm,
            f, w_k)


@kernel
def _rotation_vector(m):
    """The rotation vector psi of the rotation m (9-tuple; exp(psi^) = m), its angle
    atan2(|vee(m - m^T)| / 2, (tr m - 1) / 2) in [0, pi) (so3.log_so3, accurate at small
    angles as at large)."""
    w0, w1, w2 = m[7] - m[5], m[2] - m[6], m[3] - m[1]
    s = 0.5 * np.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    th = np.arctan2(s, 0.5 * (m[0] + m[4] + m[8] - 1.0))
    f = 0.5 + th * th / 12.0 if th < 1e-6 else 0.5 * th / s
    return (f * w0, f * w1, f * w2)


@kernel
def _relative_rotation(f_a, f_b, c1, c2):
    """log(F_a^T F_b R0^T) (in a's frame), R0 = [c1, c2, c1 x c2] from its first two columns
    (an elastic hinge's rest rotation, loop_rows.spring_directions)."""
    c3 = t_cross(c1, c2)
    r0 = (c1[0], c2[0], c3[0], c1[1], c2[1], c3[1], c1[2], c2[2], c3[2])
    f_at = (f_a[0], f_a[3], f_a[6], f_a[1], f_a[4], f_a[7], f_a[2], f_a[5], f_a[8])
    return _rotation_vector(t_mm(f_at, t_mmt(f_b, r0)))


@no_alloc_kernel(always_inline=True)
def row_positions(params, loops, rot, w, rows):
    """The given rows' positions g and rates g' (loops.g, gd) at the points loops.r_out,
    v_out, less their targets (loops.target; an angle's difference folded into [-pi, pi))."""
    kind = loop_tables.kind(loops)
    v1 = loop_tables.v1(loops)
    v2 = loop_tables.v2(loops)
    v3 = loop_tables.v3(loops)
    target = loop_tables.target(loops)
    g = loop_tables.g(loops)
    gd = loop_tables.gd(loops)
    owner = loop_tables.owner(loops)
    for q in range(rows.shape[0]):
        r = rows[q]
        p_a, v_a, _, f_a, w_a = _side(params, loops, rot, w, owner[r], 0)
        p_b, v_b, _, f_b, w_b = _side(params, loops, rot, w, owner[r], 1)
        if kind[r] == ROTATION_A:
            # an elastic hinge's g = n . log(F_a^T F_b R0^T), g' = (F_a n) . (w_b - w_a)
            psi = _relative_rotation(f_a, f_b, _v3(v1, r), _v3(v2, r))
            g[r] = _dot(_v3(v3, r), psi) - target[r, 0]
            gd[r] = _dot(t_mv(f_a, _v3(v3, r)), _sub(w_b, w_a)) - target[r, 1]
        elif kind[r] == ANGLE_A or kind[r] == ANGLE_B:
            # q = atan2(n . (x x y), x . y), q' = n . (w_b - w_a)
            x = t_mv(f_a, _v3(v1, r))
            y = t_mv(f_b, _v3(v2, r))
            n = t_mv(f_a if kind[r] == ANGLE_A else f_b, _v3(v3, r))
            angle = np.arctan2(_dot(n, t_cross(x, y)), _dot(x, y)) - target[r, 0]
            g[r] = (angle + np.pi) % (2.0 * np.pi) - np.pi
            gd[r] = _dot(n, _sub(w_b, w_a)) - target[r, 1]
        elif kind[r] == DOT:
            x = t_mv(f_a, _v3(v1, r))
            y = t_mv(f_b, _v3(v2, r))
            g[r] = _dot(x, y)
            gd[r] = _dot(_sub(w_b, w_a), t_cross(y, x))
        else:
            e = _v3(v1, r) if kind[r] == GAP_WORLD else t_mv(f_a, _v3(v1, r))
            d = _sub(p_b, p_a)
            g[r] = _dot(e, d) - target[r, 0]
            gd[r] = _dot(e, _sub(v_b, v_a)) - target[r, 1]
            if kind[r] == GAP_A:
                gd[r] += _dot(t_cross(w_a, e), d)


@no_alloc_kernel
def _row_coefficients(params, loops, rot, w):
    """The rows' Jacobian at the points loops.r_out, v_out (tree_points) and the rotations and
    angular velocities rot, w: row r's value (the module docstring) is
        kappa_r + coef[r, 0] . a_a + coef[r, 1] . alpha_a + coef[r, 2] . a_b + coef[r, 3] . alpha_b
    (a the side body's output station's acceleration, alpha its angular acceleration), its rate
    the same linear form of the velocities without kappa, and its unit multiplier's loads on
    the sides' output stations are -[coef alpha; coef a] (the Jacobian transposed):
        gap:  a_a: -e, alpha_a: -(arm_a x e) (+ e x d, e in a's frame), a_b: e, alpha_b: arm_b x e
        dot:  alpha_a: -(y x x), alpha_b: y x x
        angle: alpha_a: -n, alpha_b: n, kappa = (w_s x n) . (w_b - w_a), s the side holding n
               (an elastic hinge's rotation row: s = a)
    with arm the point from its body's output point and d = p_b - p_a."""
    kind = loop_tables.kind(loops)
    v1 = loop_tables.v1(loops)
    v2 = loop_tables.v2(loops)
    v3 = loop_tables.v3(loops)
    kappa_ = loop_tables.kappa(loops)
    owner = loop_tables.owner(loops)
    coef = loop_tables.coef(loops)
    body = loop_tables.body(loops)
    ground_motion = loop_tables.ground_motion(loops)
    zero = (0.0, 0.0, 0.0)
    for r in range(kind.shape[0]):
        p_a, v_a, arm_a, f_a, w_a = _side(params, loops, rot, w, owner[r], 0)
        p_b, v_b, arm_b, f_b, w_b = _side(params, loops, rot, w, owner[r], 1)
        if kind[r] == ANGLE_A or kind[r] == ANGLE_B or kind[r] == ROTATION_A:
            a_side = kind[r] != ANGLE_B
            n = t_mv(f_a if a_side else f_b, _v3(v3, r))
            rows = (zero, _neg(n), zero, n)
            kappa = _dot(t_cross(w_a if a_side else w_b, n), _sub(w_b, w_a))
        elif kind[r] == DOT:
            x = t_mv(f_a, _v3(v1, r))
            y = t_mv(f_b, _v3(v2, r))
            yx = t_cross(y, x)
            rows = (zero, _neg(yx), zero, yx)
            kappa = _dot(_sub(w_b, w_a), _add(t_cross(t_cross(w_b, y), x),
                                              t_cross(y, t_cross(w_a, x))))
        else:
            e = _v3(v1, r) if kind[r] == GAP_WORLD else t_mv(f_a, _v3(v1, r))
            ma = t_cross(arm_a, e)
            kappa = _dot(e, _sub(t_cross(w_b, t_cross(w_b, arm_b)),
                                 t_cross(w_a, t_cross(w_a, arm_a))))
            if kind[r] == GAP_A:
                d = _sub(p_b, p_a)
                ma = _sub(ma, t_cross(e, d))
                we = t_cross(w_a, e)
                kappa += _dot(t_cross(w_a, we), d) + 2.0 * _dot(we, _sub(v_b, v_a))
            rows = (_neg(e), _neg(ma), e, t_cross(arm_b, e))
        for j in range(4):
            for i in range(3):
                coef[r, j, i] = rows[j][i]
        for s in range(2):      # the ground's side: its point's and frame's known accelerations
            if body[owner[r], s] < 0:
                kappa += (_dot(rows[2 * s], _v3(ground_motion, 1))
                          + _dot(rows[2 * s + 1], _v3(ground_motion, 3)))
        kappa_[r] = kappa


@no_alloc_kernel
def _row_value(loops, r, z, act):
    """Row r's linear part, coef . (a, alpha), at the stations z (2n + 1, 12) of a column
    whose active bodies are act (elsewhere its response is zero)."""
    owner = loop_tables.owner(loops)
    body = loop_tables.body(loops)
    coef = loop_tables.coef(loops)
    v = 0.0
    c = owner[r]
    for s in range(2):
        k = body[c, s]
        if k >= 0 and act[k]:
            for i in range(3):
                v += (coef[r, 2 * s, i] * z[2 * k + 2, i]
                      + coef[r, 2 * s + 1, i] * z[2 * k + 1, 3 + i])
    return v


@no_alloc_kernel(entry=True)
def row_residuals(loops, z, out):
    """Every row's value kappa + J (a, alpha) at the stations z (2n + 1, 12) of the whole
    tree, with the Jacobian of the last solve (_row_coefficients), less its target (a driven
    coordinate's prescribed acceleration)."""
    kind = loop_tables.kind(loops)
    target = loop_tables.target(loops)
    kappa = loop_tables.kappa(loops)
    act = loop_tables.act(loops)
    for r in range(kind.shape[0]):
        out[r] = kappa[r] + _row_value(loops, r, z, act[0]) - target[r, 2]


@no_alloc_kernel
def _column_loads(loops):
    """Each row's unit multiplier's station loads (column r + 1): -[coef alpha; coef a] on each
    side's output station (_row_coefficients)."""
    kind = loop_tables.kind(loops)
    col_load = loop_tables.col_load(loops)
    coef = loop_tables.coef(loops)
    for r in range(kind.shape[0]):
        for s in range(2):
            for i in range(3):
                col_load[r + 1, s, i] = -coef[r, 2 * s + 1, i]
                col_load[r + 1, s, 3 + i] = -coef[r, 2 * s, i]


@kernel
def _least_apply(u, sv, vt, b):
    """The least-norm x of a x = b from a's SVD a = u diag(sv) vt, truncated at relative
    1e-10."""
    x = np.zeros(vt.shape[1])
    if sv.shape[0] == 0:
        return x
    ub = matvec(u.T, b)
    for i in range(sv.shape[0]):
        if sv[i] > 1e-10 * sv[0]:
            x += (ub[i] / sv[i]) * vt[i]
    return x


@kernel
def _least_solve(a, b):
    """The least-norm x of a x = b by a truncated SVD (relative 1e-10)."""
    u, sv, vt = np.linalg.svd(a)
    return _least_apply(u, sv, vt, b)


BAND_REGULARIZATION = 1e-12     # of the largest diagonal entry, added to the diagonal


@no_alloc_kernel
def _clear_rows_matrix(loops, a):
    """a <- 0 where the rows' solve reads it: within the band and its LU fill (columns i -
    lower .. i + lower + upper of row i) where loops.band holds the bandwidths, everywhere
    otherwise (O(R l), not O(R^2), for the banded solve's many rows)."""
    band = loop_tables.band(loops)
    m = a.shape[0]
    lower, upper = band[0], band[1]
    if lower < 0:
        for i in range(m):
            for j in range(m):
                a[i, j] = 0.0
        return
    for i in range(m):
        for j in range(max(0, i - lower), min(m, i + lower + upper + 1)):
            a[i, j] = 0.0


@no_alloc_kernel
def _band_factor(a, lower, upper, piv):
    """a <- its LU factors with partial pivoting, a banded matrix of lower and upper bandwidths
    (kept dense; the factors fill only lower and lower + upper bands), after adding
    BAND_REGULARIZATION times its largest diagonal entry to the diagonal: the rows a planar
    loop's spatial joints make redundant are zero rows and columns of the Delassus matrix
    (their multipliers come out zero), and where rows are redundant in general the motion does
    not depend on how the multipliers split (D = J A J^T: its null space is J^T's).  O(R l (l +
    u)) for R rows, where the truncated SVD is O(R^3)."""
    m = a.shape[0]
    big = 0.0
    for i in range(m):
        big = max(big, abs(a[i, i]))
    eps = BAND_REGULARIZATION * big if big > 0.0 else 1e-300
    for i in range(m):
        a[i, i] += eps
    for k in range(m):
        last = min(m - 1, k + lower)
        best, at = abs(a[k, k]), k
        for i in range(k + 1, last + 1):
            if abs(a[i, k]) > best:
                best, at = abs(a[i, k]), i
        piv[k] = at
        right = min(m - 1, k + lower + upper)
        if at != k:
            for j in range(k, right + 1):
                a[k, j], a[at, j] = a[at, j], a[k, j]
        if a[k, k] == 0.0:
            a[k, k] = eps
        for i in range(k + 1, last + 1):
            f = a[i, k] / a[k, k]
            a[i, k] = f
            if f != 0.0:
                for j in range(k + 1, right + 1):
                    a[i, j] -= f * a[k, j]


@kernel
def _band_apply(lu, lower, upper, piv, b):
    """x with A x = b from _band_factor's factors."""
    m = lu.shape[0]
    x = b.copy()
    for k in range(m):
        if piv[k] != k:
            x[k], x[piv[k]] = x[piv[k]], x[k]
        for i in range(k + 1, min(m - 1, k + lower) + 1):
            x[i] -= lu[i, k] * x[k]
    for k in range(m - 1, -1, -1):
        for j in range(k + 1, min(m - 1, k + lower + upper) + 1):
            x[k] -= lu[k, j] * x[j]
        x[k] /= lu[k, k]
    return x


@kernel
def _rows_solve(loops, a, b):
    """The multipliers of a x = b for the rows' matrix a (the Delassus matrix or V): the
    truncated SVD (_least_solve), or where loops.band holds its bandwidths (many rows, a
    narrow band) the regularized banded LU (_band_factor; a is overwritten)."""
    band = loop_tables.band(loops)
    if band[0] < 0:
        return _least_solve(a, b)
    piv = np.empty(a.shape[0], dtype=np.int64)
    _band_factor(a, band[0], band[1], piv)
    return _band_apply(a, band[0], band[1], piv, b)


@no_alloc_kernel
def closure_wrenches(params, loops, rot):
    """loops.wrench: each closing joint's force and couple on side b (world axes; the couple
    about b's point) from the multipliers loops.lam: a gap row's lam e, a dot row's couple
    lam (y x x), an angle's couple lam n (the module docstring), with the rows' directions at
    the rotations rot; a driven coordinate's row's lam is also its drive's generalized force
    (loops.wrench[c, 6 + i] for coordinate i: a couple about the axis, or a force along it)."""
    wrench = loop_tables.wrench(loops)
    kind = loop_tables.kind(loops)
    lam = loop_tables.lam(loops)
    owner = loop_tables.owner(loops)
    ground_rot = loop_tables.ground_rot(loops)
    coordinate = loop_tables.coordinate(loops)
    body = loop_tables.body(loops)
    v3 = loop_tables.v3(loops)
    v1 = loop_tables.v1(loops)
    v2 = loop_tables.v2(loops)
    wrench[:, :] = 0.0
    for r in range(kind.shape[0]):
        c = owner[r]
        if coordinate[r] >= 0:
            wrench[c, 6 + coordinate[r]] = lam[r]
        f_a = _frame(rot, ground_rot, body[c, 0])
        f_b = _frame(rot, ground_rot, body[c, 1])
        if kind[r] == ANGLE_A or kind[r] == ANGLE_B or kind[r] == ROTATION_A:
            n = t_mv(f_b if kind[r] == ANGLE_B else f_a, _v3(v3, r))
            for i in range(3):
                wrench[c, 3 + i] += lam[r] * n[i]
        elif kind[r] == DOT:
            couple = t_cross(t_mv(f_b, _v3(v2, r)), t_mv(f_a, _v3(v1, r)))
            for i in range(3):
                wrench[c, 3 + i] += lam[r] * couple[i]
        else:
            e = _v3(v1, r) if kind[r] == GAP_WORLD else t_mv(f_a, _v3(v1, r))
            for i in range(3):
                wrench[c, i] += lam[r] * e[i]


@no_alloc_kernel
def _delassus(loops):
    """loops.delassus[r, j]: row r's value in row j's response (column j + 1), from the stored
    responses and the rows' Jacobian (_row_value); zero where row r's bodies are not among
    column j + 1's active bodies."""
    delassus = loop_tables.delassus(loops)
    kind = loop_tables.kind(loops)
    z_save = loop_tables.z_save(loops)
    act_ = loop_tables.act(loops)
    colrow_ptr = loop_tables.colrow_ptr(loops)
    colrow_idx = loop_tables.colrow_idx(loops)
    n_rows = kind.shape[0]
    _clear_rows_matrix(loops, delassus)
    for j in range(n_rows):
        z, act = z_save[j + 1], act_[j + 1]
        for q in range(colrow_ptr[j], colrow_ptr[j + 1]):
            r = colrow_idx[q]
            delassus[r, j] = _row_value(loops, r, z, act)


@allocating_kernel
def solve_with_loops(params, sweep, root_f, loops, rot, w, z):
    """The sweep with the closing joints' multipliers (the module docstring).  rot, w: the
    bodies' rotations and angular velocities the rows are written at, with their points in
    loops.r_out, v_out (tree_points).  One upward sweep carries the step (column 0) and each
    row's unit multiplier (column r + 1) over the bodies that column reaches (sweep_columns);
    column 0 is recovered over the tree, each row's column over its active bodies only
    (recover_column: elsewhere its response is zero), into loops.z_save, nu_save, tau_save.
    The Delassus matrix of the rows' values (_delassus), the multipliers holding the rows at
    zero (acceleration level), then the step with the multipliers' loads, recovered once
    over the tree into z, sweep.joint_nu, joint_tau (P and k superposed, P_c = 0 where
    column c does not pass).  Returns the sweep's status."""
    h_store = loop_tables.h_store(loops)
    free_store = loop_tables.free_store(loops)
    all_bodies = loop_tables.all_bodies(loops)
    lam = loop_tables.lam(loops)
    p_comb = loop_tables.p_comb(loops)
    k_comb = loop_tables.k_comb(loops)
    kind = loop_tables.kind(loops)
    p_col = loop_tables.p_col(loops)
    k_store = loop_tables.k_store(loops)
    z_save = loop_tables.z_save(loops)
    nu_save = loop_tables.nu_save(loops)
    tau_save = loop_tables.tau_save(loops)
    act = loop_tables.act(loops)
    rhs = loop_tables.rhs(loops)
    delassus = loop_tables.delassus(loops)
    acc = loop_tables.acc(loops)
    target = loop_tables.target(loops)
    up_ptr = loop_tables.up_ptr(loops)
    up_idx = loop_tables.up_idx(loops)
    kappa = loop_tables.kappa(loops)
    act_idx = loop_tables.act_idx(loops)
    act_ptr = loop_tables.act_ptr(loops)
    n = rot.shape[0]
    n_rows = kind.shape[0]
    # (recover_column's affine flag as run-time bools: numba compiles a function once per
    # literal True or False it is passed)
    step_column, unit_column = n_rows >= 0, n_rows < 0
    sw = sweep
    element_kind = sweep_tables.kind(sw)
    u = sweep_tables.u(sw)
    joint_dof = sweep_tables.joint_dof(sw)
    joint_tau_nu = sweep_tables.joint_tau_nu(sw)
    known_loads = sweep_tables.known_loads(sw)
    s = sweep_tables.s(sw)
    tree_s = sweep_tables.tree_s(sw)
    joint_nu = sweep_tables.joint_nu(sw)
    joint_tau = sweep_tables.joint_tau(sw)
    _row_coefficients(params, loops, rot, w)
    _column_loads(loops)
    parent = model_tables.parent(params)
    status = sweep_columns(element_kind, u, joint_dof, joint_tau_nu, known_loads,
                           parent, s, tree_s, loops)
    if status != 0:
        return status
    work = np.empty((9, 12))
    status = recover_column(element_kind, u, joint_dof, joint_tau_nu, known_loads,
                            parent, root_f, s, p_col[0], k_store[0],
                            h_store, free_store, z_save[0], nu_save[0],
                            tau_save[0], step_column, all_bodies, act[0],
                            work)
    for c in range(1, n_rows + 1):
        if status == 0:
            status = recover_column(element_kind, u, joint_dof, joint_tau_nu,
                                    known_loads, parent, root_f, s, p_col[c],
                                    k_store[c], h_store, free_store,
                                    z_save[c], nu_save[c], tau_save[c],
                                    unit_column,
                                    act_idx[act_ptr[c]:act_ptr[c + 1]],
                                    act[c], work)
    if status != 0:
        return status
    _delassus(loops)
    for r in range(n_rows):
        rhs[r] = target[r, 2] - (kappa[r]
                                             + _row_value(loops, r, z_save[0], act[0]))
    _force_rows(params, loops, rot, w)
    put1(lam, _rows_solve(loops, delassus, rhs))
    # the step with the multipliers' loads: P and k superposed, one recovery over the tree
    put2(p_comb, p_col[0])
    put2(k_comb, k_store[0])
    for k in range(n):
        for q in range(up_ptr[k], up_ptr[k + 1]):
            c = up_idx[q]
            f = lam[c - 1]
            for i in range(6):
                p_comb[2 * k, i] += f * p_col[c, 2 * k, i]
                p_comb[2 * k + 1, i] += f * p_col[c, 2 * k + 1, i]
            for i in range(3):
                k_comb[k, i] += f * k_store[c, k, i]
    status = recover_column(element_kind, u, joint_dof, joint_tau_nu, known_loads,
                            parent, root_f, s, p_comb, k_comb, h_store,
                            free_store, z, joint_nu, joint_tau, step_column,
                            all_bodies, act[0], work)
    if status != 0:
        return status
    for r in range(n_rows):
        acc[r] = kappa[r] + _row_value(loops, r, z, act[0])
    closure_wrenches(params, loops, rot)
    return 0


@kernel
def _is_force(law, r):
    """Whether row r is a drive's force (a SpringDamper's or a JointForce's), not a
    constraint."""
    return law[r, 0] == SPRING_DAMPER or law[r, 0] == FORCE


@no_alloc_kernel
def _force_rows(params, loops, rot, w):
    """A drive's row is its force, not a constraint.  A SpringDamper's, lam = -k (q - rest) -
    c q' at the step's end: with q, q' at the guess (row_positions: g = q - rest, g' = q') and
    their change with the row's acceleration, dq = da / c1, dq' = (c3 / c1) da from the guess's
    a_g (loops.acc, the last solve's),
        lam + K (a - a_g) = F0,   F0 = -k g - c g',   K = (k + c c3) / c1,
    its Delassus row scaled by K plus the unit diagonal, its right side F0 + K (a_g - b) (b the
    row's value without multipliers); K = 0 at the consistent start (the force explicit).  A
    JointForce's (k = c = 0): lam = F, its value in loops.target[r, 2] (solver: f(t, q, q')
    at the predictor, as a tree joint's), its row the unit row."""
    all_rows = loop_tables.all_rows(loops)
    delassus = loop_tables.delassus(loops)
    rhs = loop_tables.rhs(loops)
    kind = loop_tables.kind(loops)
    law = loop_tables.law(loops)
    target = loop_tables.target(loops)
    step_coef = loop_tables.step_coef(loops)
    gd = loop_tables.gd(loops)
    acc = loop_tables.acc(loops)
    g = loop_tables.g(loops)
    forces = False
    for r in range(kind.shape[0]):
        forces = forces or _is_force(law, r)
    if not forces:
        return
    row_positions(params, loops, rot, w, all_rows)
    for r in range(kind.shape[0]):
        if not _is_force(law, r):
            continue
        k, c = law[r, 1], law[r, 2]
        stiff = k * step_coef[0] + c * step_coef[1]
        b = target[r, 2] - rhs[r]
        for j in range(kind.shape[0]):
            delassus[r, j] *= stiff
        delassus[r, r] += 1.0
        # (a spring's target[r, 2] is 0: closure_targets)
        rhs[r] = (target[r, 2] - k * g[r] - c * gd[r]
                        + stiff * (acc[r] - b))


@no_alloc_kernel
def _modal_responses(params, loops, eta_map):
    """loops.eta_col[j]: row j's response of the beams' eta'' and the strain rods' q'' (eta'' =
    eta_map [z_I; 1] at the element's input station, step.py::_modal_accelerations; homogeneous:
    its linear part), on its active beams and rods (zero elsewhere)."""
    eta_col = loop_tables.eta_col(loops)
    z_save = loop_tables.z_save(loops)
    kind = loop_tables.kind(loops)
    act_ptr = loop_tables.act_ptr(loops)
    act_idx = loop_tables.act_idx(loops)
    body_kind, mode_off = model_tables.body_kind(params), model_tables.mode_offset(params)
    eta_col[:, :] = 0.0
    for j in range(kind.shape[0]):
        z = z_save[j + 1]
        for q in range(act_ptr[j + 1], act_ptr[j + 2]):
            k = act_idx[q]
            if body_kind[k] == BEAM or body_kind[k] == ROD:
                for i in range(mode_off[k], mode_off[k + 1]):
                    v = 0.0
                    for c in range(12):
                        v += eta_map[i, c] * z[2 * k + 1, c]
                    eta_col[j, i] = v

