"""Closing joints in the general loop's step (docs/loops.md, "The step with loops").

The tree's full-state sweep (sweep.py::riccati_tree_full) is linear in the loads at its
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
from collections import namedtuple

import numpy as np

from .. import allocating_kernel, kernel, model_tables, no_alloc_kernel
from ...elements.kinds import (ANGLE_A, ANGLE_B, DOT, GAP_A, GAP_WORLD, HAS_SLIDES,
                               ROTATION_A)
from ...elements import BEAM, ROD
from ...elements.drives import FORCE, SPRING_DAMPER
from ...elements.beam import AXIAL_MODES, LENGTH, MODES, STIFFENING, TORSION_MODES
from ...elements.hinges import ELASTIC, FIXED
from ..transfers.beam_relations import end_section_motion
from ..transfers.strain_rod import rod_end, rod_end_frame, rod_tables_of
from ..transfers.joint import FREE, PRESCRIBED, joint_frame, joint_offset, n_coordinates
from ..algebra.mat3 import (add1, add2, matmul, matvec, put1, put2, t_cross, t_mm, t_mmt,
                            t_mv)
from ..algebra.so3 import expm_so3
from .sweep import IDENTITY, JOINT, LOCKED, TRANSFER, _gauss_solve


# the closing joints as the loop reads them, and the loop's scratch for them (solver.
# loop_tables): rows (R) and closing joints (m) in the kernel model's numbering
Loops = namedtuple("Loops", [
    "kind", "owner", "v1", "v2",     # (R,), (R,), (R, 3), (R, 3): GAP_WORLD / GAP_A / DOT /
                                     # ANGLE_A / ANGLE_B / ROTATION_A, its closing joint, e
                                     # (or x, in a's frame) and y (b's frame); ROTATION_A:
                                     # R0's first two columns
    "v3", "target", "coordinate",    # (R, 3) an angle's axis (closures.driven_directions,
                                     # spring_directions);
                                     # (R, 3) the step's targets (value, rate, acceleration):
                                     # a driven coordinate's motion at the step's end, a
                                     # spring's rest, a JointForce's value (in [2]), else 0;
                                     # (R,) the joint's coordinate a row drives (-1: none)
    "law", "acc", "step_coef",       # (R, 3) a row's drive [kind, stiffness, damping] (kind
                                     # -1: none; a SpringDamper's or a JointForce's row is a
                                     # force, no constraint); (R,) each row's acceleration
                                     # in the last solve; (2,) [1 / c1, c3 / c1] of the step
                                     # (0: the consistent start, springs explicit)
    "body", "point",                 # (m, 2), (m, 2, 3): the sides' bodies and points (in the
                                     # body's frame from its input point; the ground's: in the
                                     # ground frame from the ground point)
    "ground", "ground_rot",          # (3,), (3, 3) the ground point and frame, and (4, 3) the
    "ground_motion",                 # point's velocity and acceleration and the frame's angular
                                     # velocity and acceleration, where the rows are written
                                     # (set_ground: t_{n+1} in a step, 0 at the start)
    "coef", "kappa",                 # (R, 4, 3), (R,): the rows' Jacobian and velocity terms
                                     # (_row_coefficients)
    "z_save", "nu_save", "tau_save",  # (R + 1, ...) column 0's and each row's response's
                                     # stations and joints (on the row's active bodies only)
    "delassus", "lam", "rhs",        # (R, R), (R,), (R,)
    "r_out", "v_out",                # (n, 3) each: the output points' positions, velocities
    "g", "gd",                       # (R,) the rows' positions and rates
    "col_body", "col_load",          # (R + 1, 2), (R + 1, 2, 6): each column's loaded output
                                     # stations (-1: none) and station loads
    "up_ptr", "up_idx",              # CSR over the bodies: the columns c >= 1 whose sweep
                                     # passes each body (its active bodies and their ancestors)
    "act_ptr", "act_idx", "act",     # CSR over the columns (R + 2,): each column's active
                                     # bodies in tree order; (R + 1, n) the same as a mask
    "all_bodies", "all_rows",        # (n,) 0 .. n - 1, (R,) 0 .. R - 1
    "band",                          # (2,) the rows' matrices' lower and upper bandwidths
                                     # where a banded solve pays (_rows_solve), else -1
    "colrow_ptr", "colrow_idx",      # CSR over the rows' columns: the rows with a side body
                                     # among each column's active bodies
    "p_col", "port_col",             # (R + 1, 2n + 1, 6), (R + 1, n, 6): sweep_columns' scratch,
    "h_store", "k_store", "free_store",   # (n, 3, 6), (R + 1, n, 3), (n, 4) int
    "p_comb", "k_comb",              # (2n + 1, 6), (n, 3): the multipliers' superposition
    "eta_col",                       # (R, n_eta) each row's response of the beams' eta''
    "wrench",                        # (m, 10) each closing joint's force and couple on side b
                                     # (world; the couple about its point) from loops.lam,
                                     # then its drives' generalized forces and their
                                     # coordinates' rates (coordinates 1, 2)
    "stats",                         # (4,) the run's largest position residual after a step
                                     # (before the projection), rate residual before and after
                                     # the rates' projection, position residual after its
    "energy",                        # (3,) [held (1) or not (0), the total energy the steps
                                     # hold (set at the start, start_energy), the largest
                                     # relative change of the rates its projection made]
])

POSITION_PROJECTIONS = 4     # Gauss-Newton projections of the positions after a step, at most
POSITION_TOL = 1e-13         # m, rad: where they stop
RATE_TOL = 1e-13             # m/s, rad/s: the rates' projection's
ENERGY_STEP_LIMIT = 1e-3     # the energy's projection changes the rates by less than this
                             # fraction in one step, or not at all (a state too slow to carry it)


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
    for i in range(3):
        loops.ground[i] = r[i]
        loops.ground_motion[0, i] = v[i]
        loops.ground_motion[1, i] = a[i]
        loops.ground_motion[2, i] = w[i]
        loops.ground_motion[3, i] = wd[i]
        for j in range(3):
            loops.ground_rot[i, j] = rot[i, j]


@no_alloc_kernel
def tree_points(params, rot, w, jq, jqd, eta, eta_d, defl, defl_rate, loops, bodies):
    """The output point and its velocity (loops.r_out, v_out) of the given bodies (in tree
    order; the others' are read as they are) from the rotations, angular velocities, joint
    coordinates and rates, the elastic hinges' deflections and rates and the beams' modal
    coordinates and rates: r_in = r_out,P + d (a joint's slides' d = A_P sum n_i q_i,
    kernels/transfers/joint.py::joint_offset, an elastic hinge's its deflection d, world,
    v_in = v_out,P + d'), r_out = r_in + A l_IO (a rigid body) or
    r_in + rho (a beam's deflected end, _beam_offset; a strain rod's, _rod_offset); the kernel
    model hangs every child at its parent's output point."""
    parent = model_tables.parent(params)
    hinge_kind = model_tables.hinge_kind(params)
    hinge_params = model_tables.hinge_params(params)
    body_params, body_row = model_tables.body_params(params), model_tables.body_row(params)
    hinge_row, body_kind = model_tables.hinge_row(params), model_tables.body_kind(params)
    r_out, v_out = loops.r_out, loops.v_out
    for q in range(bodies.shape[0]):
        k = bodies[q]
        p = parent[k]
        if p < 0:               # a root hangs at the ground point (moving with the ground)
            r = (loops.ground[0], loops.ground[1], loops.ground[2])
            v = _v3(loops.ground_motion, 0)
        else:
            r = _v3(r_out, p)
            v = _v3(v_out, p)
        if HAS_SLIDES[hinge_kind[k]]:      # the slides: kernels/transfers/joint.py
            f_p = _frame(rot, loops.ground_rot, p)
            w_p = _v3(loops.ground_motion, 2) if p < 0 else _v3(w, p)
            d, d_rate = joint_offset(hinge_kind[k], hinge_params[hinge_row[k]], f_p, w_p, jq[k],
                                     jqd[k])
            r = _add(r, d)
            v = _add(v, d_rate)
        elif hinge_kind[k] == ELASTIC:
            r = _add(r, _v3(defl, k))
            v = _add(v, _v3(defl_rate, k))
        if body_kind[k] == BEAM:
            arm, arm_rate = _beam_offset(params, k, rot, w, eta, eta_d)
        elif body_kind[k] == ROD:
            arm, arm_rate = _rod_offset(params, k, rot, w, eta, eta_d)
        else:
            row = body_row[k]
            arm = t_mv(_m9(rot, k), (body_params[row, 4], body_params[row, 5],
                                     body_params[row, 6]))
            arm_rate = t_cross(_v3(w, k), arm)
        for i in range(3):
            r_out[k, i] = r[i] + arm[i]
            v_out[k, i] = v[i] + arm_rate[i]


@no_alloc_kernel
def _side(params, loops, rot, w, c, s):
    """(point, velocity, arm from the body's output point, frame, angular velocity) of closing
    joint c's side s, at the output points loops.r_out, v_out and the bodies' rot, w, as
    tuples (the ground's: its point, frame and motion in loops.ground, ground_rot,
    ground_motion, the arm from the ground point)."""
    k = loops.body[c, s]
    point, ground = loops.point, loops.ground
    local = (point[c, s, 0], point[c, s, 1], point[c, s, 2])
    if k < 0:
        f = _frame(rot, loops.ground_rot, k)
        arm = t_mv(f, local)
        w_g = _v3(loops.ground_motion, 2)
        return (_add((ground[0], ground[1], ground[2]), arm),
                _add(_v3(loops.ground_motion, 0), t_cross(w_g, arm)), arm, f, w_g)
    f = _m9(rot, k)
    w_k = _v3(w, k)
    centre, row = model_tables.body_params(params), model_tables.body_row(params)[k]
    arm = t_mv(f, _sub(local, (centre[row, 4], centre[row, 5], centre[row, 6])))
    return (_add(_v3(loops.r_out, k), arm), _add(_v3(loops.v_out, k), t_cross(w_k, arm)), arm,
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
    (an elastic hinge's rest rotation, closures.spring_directions)."""
    c3 = t_cross(c1, c2)
    r0 = (c1[0], c2[0], c3[0], c1[1], c2[1], c3[1], c1[2], c2[2], c3[2])
    f_at = (f_a[0], f_a[3], f_a[6], f_a[1], f_a[4], f_a[7], f_a[2], f_a[5], f_a[8])
    return _rotation_vector(t_mm(f_at, t_mmt(f_b, r0)))


@no_alloc_kernel
def row_positions(params, loops, rot, w, rows):
    """The given rows' positions g and rates g' (loops.g, gd) at the points loops.r_out,
    v_out, less their targets (loops.target; an angle's difference folded into [-pi, pi))."""
    kind, v1, v2, v3 = loops.kind, loops.v1, loops.v2, loops.v3
    target, g, gd = loops.target, loops.g, loops.gd
    for q in range(rows.shape[0]):
        r = rows[q]
        p_a, v_a, _, f_a, w_a = _side(params, loops, rot, w, loops.owner[r], 0)
        p_b, v_b, _, f_b, w_b = _side(params, loops, rot, w, loops.owner[r], 1)
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
    kind, v1, v2, v3 = loops.kind, loops.v1, loops.v2, loops.v3
    zero = (0.0, 0.0, 0.0)
    for r in range(kind.shape[0]):
        p_a, v_a, arm_a, f_a, w_a = _side(params, loops, rot, w, loops.owner[r], 0)
        p_b, v_b, arm_b, f_b, w_b = _side(params, loops, rot, w, loops.owner[r], 1)
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
                loops.coef[r, j, i] = rows[j][i]
        for s in range(2):      # the ground's side: its point's and frame's known accelerations
            if loops.body[loops.owner[r], s] < 0:
                kappa += (_dot(rows[2 * s], _v3(loops.ground_motion, 1))
                          + _dot(rows[2 * s + 1], _v3(loops.ground_motion, 3)))
        loops.kappa[r] = kappa


@no_alloc_kernel
def _row_value(loops, r, z, act):
    """Row r's linear part, coef . (a, alpha), at the stations z (2n + 1, 12) of a column
    whose active bodies are act (elsewhere its response is zero)."""
    v = 0.0
    c = loops.owner[r]
    for s in range(2):
        k = loops.body[c, s]
        if k >= 0 and act[k]:
            for i in range(3):
                v += (loops.coef[r, 2 * s, i] * z[2 * k + 2, i]
                      + loops.coef[r, 2 * s + 1, i] * z[2 * k + 1, 3 + i])
    return v


@no_alloc_kernel(entry=True)
def row_residuals(loops, z, out):
    """Every row's value kappa + J (a, alpha) at the stations z (2n + 1, 12) of the whole
    tree, with the Jacobian of the last solve (_row_coefficients), less its target (a driven
    coordinate's prescribed acceleration)."""
    for r in range(loops.kind.shape[0]):
        out[r] = loops.kappa[r] + _row_value(loops, r, z, loops.act[0]) - loops.target[r, 2]


@no_alloc_kernel
def _column_loads(loops):
    """Each row's unit multiplier's station loads (column r + 1): -[coef alpha; coef a] on each
    side's output station (_row_coefficients)."""
    for r in range(loops.kind.shape[0]):
        for s in range(2):
            for i in range(3):
                loops.col_load[r + 1, s, i] = -loops.coef[r, 2 * s + 1, i]
                loops.col_load[r + 1, s, 3 + i] = -loops.coef[r, 2 * s, i]


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
    m = a.shape[0]
    lower, upper = loops.band[0], loops.band[1]
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
    if loops.band[0] < 0:
        return _least_solve(a, b)
    piv = np.empty(a.shape[0], dtype=np.int64)
    _band_factor(a, loops.band[0], loops.band[1], piv)
    return _band_apply(a, loops.band[0], loops.band[1], piv, b)


@no_alloc_kernel
def closure_wrenches(params, loops, rot):
    """loops.wrench: each closing joint's force and couple on side b (world axes; the couple
    about b's point) from the multipliers loops.lam: a gap row's lam e, a dot row's couple
    lam (y x x), an angle's couple lam n (the module docstring), with the rows' directions at
    the rotations rot; a driven coordinate's row's lam is also its drive's generalized force
    (loops.wrench[c, 6 + i] for coordinate i: a couple about the axis, or a force along it)."""
    wrench, kind, lam = loops.wrench, loops.kind, loops.lam
    wrench[:, :] = 0.0
    for r in range(kind.shape[0]):
        c = loops.owner[r]
        if loops.coordinate[r] >= 0:
            wrench[c, 6 + loops.coordinate[r]] = lam[r]
        f_a = _frame(rot, loops.ground_rot, loops.body[c, 0])
        f_b = _frame(rot, loops.ground_rot, loops.body[c, 1])
        if kind[r] == ANGLE_A or kind[r] == ANGLE_B or kind[r] == ROTATION_A:
            n = t_mv(f_b if kind[r] == ANGLE_B else f_a, _v3(loops.v3, r))
            for i in range(3):
                wrench[c, 3 + i] += lam[r] * n[i]
        elif kind[r] == DOT:
            couple = t_cross(t_mv(f_b, _v3(loops.v2, r)), t_mv(f_a, _v3(loops.v1, r)))
            for i in range(3):
                wrench[c, 3 + i] += lam[r] * couple[i]
        else:
            e = _v3(loops.v1, r) if kind[r] == GAP_WORLD else t_mv(f_a, _v3(loops.v1, r))
            for i in range(3):
                wrench[c, i] += lam[r] * e[i]


@no_alloc_kernel
def _delassus(loops):
    """loops.delassus[r, j]: row r's value in row j's response (column j + 1), from the stored
    responses and the rows' Jacobian (_row_value); zero where row r's bodies are not among
    column j + 1's active bodies."""
    n_rows = loops.kind.shape[0]
    _clear_rows_matrix(loops, loops.delassus)
    for j in range(n_rows):
        z, act = loops.z_save[j + 1], loops.act[j + 1]
        for q in range(loops.colrow_ptr[j], loops.colrow_ptr[j + 1]):
            r = loops.colrow_idx[q]
            loops.delassus[r, j] = _row_value(loops, r, z, act)


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
    n = rot.shape[0]
    n_rows = loops.kind.shape[0]
    # (recover_column's affine flag as run-time bools: numba compiles a function once per
    # literal True or False it is passed)
    step_column, unit_column = n_rows >= 0, n_rows < 0
    sw = sweep
    _row_coefficients(params, loops, rot, w)
    _column_loads(loops)
    parent = model_tables.parent(params)
    status = sweep_columns(sw.kind, sw.u, sw.joint_dof, sw.joint_tau_nu, sw.known_loads,
                           parent, sw.s, sw.tree_s, loops)
    if status != 0:
        return status
    work = np.empty((9, 12))
    status = recover_column(sw.kind, sw.u, sw.joint_dof, sw.joint_tau_nu, sw.known_loads,
                            parent, root_f, sw.s, loops.p_col[0], loops.k_store[0],
                            loops.h_store, loops.free_store, loops.z_save[0], loops.nu_save[0],
                            loops.tau_save[0], step_column, loops.all_bodies, loops.act[0],
                            work)
    for c in range(1, n_rows + 1):
        if status == 0:
            status = recover_column(sw.kind, sw.u, sw.joint_dof, sw.joint_tau_nu,
                                    sw.known_loads, parent, root_f, sw.s, loops.p_col[c],
                                    loops.k_store[c], loops.h_store, loops.free_store,
                                    loops.z_save[c], loops.nu_save[c], loops.tau_save[c],
                                    unit_column,
                                    loops.act_idx[loops.act_ptr[c]:loops.act_ptr[c + 1]],
                                    loops.act[c], work)
    if status != 0:
        return status
    _delassus(loops)
    for r in range(n_rows):
        loops.rhs[r] = loops.target[r, 2] - (loops.kappa[r]
                                             + _row_value(loops, r, loops.z_save[0], loops.act[0]))
    _force_rows(params, loops, rot, w)
    put1(loops.lam, _rows_solve(loops, loops.delassus, loops.rhs))
    # the step with the multipliers' loads: P and k superposed, one recovery over the tree
    p_comb, k_comb = loops.p_comb, loops.k_comb
    put2(p_comb, loops.p_col[0])
    put2(k_comb, loops.k_store[0])
    for k in range(n):
        for q in range(loops.up_ptr[k], loops.up_ptr[k + 1]):
            c = loops.up_idx[q]
            f = loops.lam[c - 1]
            for i in range(6):
                p_comb[2 * k, i] += f * loops.p_col[c, 2 * k, i]
                p_comb[2 * k + 1, i] += f * loops.p_col[c, 2 * k + 1, i]
            for i in range(3):
                k_comb[k, i] += f * loops.k_store[c, k, i]
    status = recover_column(sw.kind, sw.u, sw.joint_dof, sw.joint_tau_nu, sw.known_loads,
                            parent, root_f, sw.s, p_comb, k_comb, loops.h_store,
                            loops.free_store, z, sw.joint_nu, sw.joint_tau, step_column,
                            loops.all_bodies, loops.act[0], work)
    if status != 0:
        return status
    for r in range(n_rows):
        loops.acc[r] = loops.kappa[r] + _row_value(loops, r, z, loops.act[0])
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
    forces = False
    for r in range(loops.kind.shape[0]):
        forces = forces or _is_force(loops.law, r)
    if not forces:
        return
    row_positions(params, loops, rot, w, loops.all_rows)
    for r in range(loops.kind.shape[0]):
        if not _is_force(loops.law, r):
            continue
        k, c = loops.law[r, 1], loops.law[r, 2]
        stiff = k * loops.step_coef[0] + c * loops.step_coef[1]
        b = loops.target[r, 2] - loops.rhs[r]
        for j in range(loops.kind.shape[0]):
            loops.delassus[r, j] *= stiff
        loops.delassus[r, r] += 1.0
        # (a spring's target[r, 2] is 0: closure_targets)
        loops.rhs[r] = (loops.target[r, 2] - k * loops.g[r] - c * loops.gd[r]
                        + stiff * (loops.acc[r] - b))


@no_alloc_kernel
def _modal_responses(params, loops, eta_map):
    """loops.eta_col[j]: row j's response of the beams' eta'' and the strain rods' q'' (eta'' =
    eta_map [z_I; 1] at the element's input station, step.py::_modal_accelerations; homogeneous:
    its linear part), on its active beams and rods (zero elsewhere)."""
    body_kind, mode_off = model_tables.body_kind(params), model_tables.mode_offset(params)
    loops.eta_col[:, :] = 0.0
    for j in range(loops.kind.shape[0]):
        z = loops.z_save[j + 1]
        for q in range(loops.act_ptr[j + 1], loops.act_ptr[j + 2]):
            k = loops.act_idx[q]
            if body_kind[k] == BEAM or body_kind[k] == ROD:
                for i in range(mode_off[k], mode_off[k + 1]):
                    v = 0.0
                    for c in range(12):
                        v += eta_map[i, c] * z[2 * k + 1, c]
                    loops.eta_col[j, i] = v


@no_alloc_kernel
def _dependent_frames(params, loops, state, bodies, work):
    """Every given body (in tree order) whose frame follows its parent's, from the parent's
    (as step.py::_update): a joint child's by its coordinates (joint.joint_frame, a slide's
    offset too), a welded body's as the parent's (R0) or its beam's end section's (beam.
    end_section_motion) or its strain rod's (strain_rod.rod_end_frame).  work: (60,) scratch
    (nothing is allocated)."""
    scratch = work[0:48]
    rest = work[48:57].reshape((3, 3))
    body_kind = model_tables.body_kind(params)
    mode_off = model_tables.mode_offset(params)
    ends = model_tables.beam_ends(params)
    bp = model_tables.beam_params(params)
    hinge_kind, hinge_params = model_tables.hinge_kind(params), model_tables.hinge_params(params)
    hinge_row, parent = model_tables.hinge_row(params), model_tables.parent(params)
    locked = model_tables.locked(params)
    for q in range(bodies.shape[0]):
        k = bodies[q]
        hk = hinge_kind[k]
        p = parent[k]
        if p < 0:
            rot_p, w_p, wd_p = loops.ground_rot, loops.ground_motion[2], loops.ground_motion[3]
        else:
            rot_p, w_p, wd_p = state.rot[p], state.omega[p], state.omega_dot[p]
        hr = hinge_row[k]             # (the joint's row of the shared table)
        if n_coordinates(hk) > 0:
            joint_frame(hk, hinge_params[hr], rot_p, w_p, wd_p, state.jq[k],
                        state.jqd[k], state.jqdd[k], state.rot[k], state.omega[k],
                        state.omega_dot[k], state.defl[k], state.defl_rate[k])
        elif hk == FIXED and p >= 0 and not locked[k]:
            for i in range(3):                 # R0, row-major in hinge_params[hr, 0:9]
                for j in range(3):
                    rest[i, j] = hinge_params[hr, 3 * i + j]
            i0, i1 = mode_off[p], mode_off[p + 1]      # a flexible parent's coordinates
            if body_kind[p] == BEAM:
                m, mt = int(bp[p, MODES]), int(bp[p, TORSION_MODES])
                end_section_motion(ends[p, :m], ends[p, m:m + mt], rot_p, w_p, wd_p,
                                   state.eta[i0:i1], state.eta_d[i0:i1], state.eta_acc[i0:i1],
                                   rest, state.rot[k], state.omega[k], state.omega_dot[k],
                                   scratch)
            elif body_kind[p] == ROD:
                steps, xi0, phi = rod_tables_of(params, p)[:3]
                rod_end_frame(steps, xi0, phi, rot_p, w_p, wd_p, state.eta[i0:i1],
                              state.eta_d[i0:i1], state.eta_acc[i0:i1], rest, state.rot[k],
                              state.omega[k], state.omega_dot[k])
            else:                              # A = A_P R0
                for i in range(3):
                    for j in range(3):
                        state.rot[k, i, j] = (rot_p[i, 0] * rest[0, j] + rot_p[i, 1] * rest[1, j]
                                              + rot_p[i, 2] * rest[2, j])
                for i in range(3):
                    state.omega[k, i] = w_p[i]
                    state.omega_dot[k, i] = wd_p[i]
        else:
            continue
        for i in range(3):
            state.pseudo[k, i] = state.omega_dot[k, i]


@no_alloc_kernel
def _deflection_response(params, loops, z, j, k, i):
    """Row j's response of elastic hinge k's d''_i: its outboard input station's acceleration
    less its inboard output station's (v_in = v_out,P + d', step.py::_update; station 0 the
    ground, a parent outside the row's active bodies does not move)."""
    p = model_tables.parent(params)[k]
    inboard = 0.0 if p < 0 or not loops.act[j + 1, p] else z[2 * p + 2, i]
    return z[2 * k + 1, i] - inboard


@no_alloc_kernel
def _add_rates(params, loops, state, j, f):
    """The angular velocities, the joint coordinates', the elastic hinges' deflections' and
    the modal coordinates' rates += f times row j's response (of w', q'', d'' and eta'') on
    its active bodies (the dependent frames are rebuilt after, _dependent_frames)."""
    mode_off, hinge_kind = model_tables.mode_offset(params), model_tables.hinge_kind(params)
    z, nu = loops.z_save[j + 1], loops.nu_save[j + 1]
    for q in range(loops.act_ptr[j + 1], loops.act_ptr[j + 2]):
        k = loops.act_idx[q]
        for i in range(3):
            state.omega[k, i] += f * z[2 * k + 1, 3 + i]
        if hinge_kind[k] == ELASTIC:
            for i in range(3):
                state.defl_rate[k, i] += f * _deflection_response(params, loops, z, j, k, i)
        for i in range(n_coordinates(hinge_kind[k])):
            state.jqd[k, i] += f * nu[k, i]
        for i in range(mode_off[k], mode_off[k + 1]):
            state.eta_d[i] += f * loops.eta_col[j, i]


@no_alloc_kernel
def _move(params, loops, state, j, f, e3, phi):
    """Turn every active body of row j by f times its response of w' (A <- exp(f dw'^) A) and
    move its joint coordinates, elastic deflection and modal coordinates by f times their
    response of q'', d'' and eta'' (the dependent frames are rebuilt after,
    _dependent_frames); e3 (3, 3), phi (3,) scratch."""
    mode_off, hinge_kind = model_tables.mode_offset(params), model_tables.hinge_kind(params)
    z, nu = loops.z_save[j + 1], loops.nu_save[j + 1]
    for q in range(loops.act_ptr[j + 1], loops.act_ptr[j + 2]):
        k = loops.act_idx[q]
        if hinge_kind[k] == ELASTIC:
            for i in range(3):
                state.defl[k, i] += f * _deflection_response(params, loops, z, j, k, i)
        for i in range(3):
            phi[i] = f * z[2 * k + 1, 3 + i]
        expm_so3(phi, e3)
        rot_k = _m9(state.rot, k)
        for a in range(3):
            for b in range(3):
                state.rot[k, a, b] = (e3[a, 0] * rot_k[b] + e3[a, 1] * rot_k[3 + b]
                                      + e3[a, 2] * rot_k[6 + b])
        for i in range(n_coordinates(hinge_kind[k])):
            state.jq[k, i] += f * nu[k, i]
        for i in range(mode_off[k], mode_off[k + 1]):
            state.eta[i] += f * loops.eta_col[j, i]


@no_alloc_kernel
def _residuals(params, loops, state):
    """The rows' positions and rates at the state (loops.g, gd); their largest (|g|, |g'|)."""
    tree_points(params, state.rot, state.omega, state.jq, state.jqd, state.eta, state.eta_d,
                state.defl, state.defl_rate, loops, loops.all_bodies)
    row_positions(params, loops, state.rot, state.omega, loops.all_rows)
    largest_g, largest_gd = 0.0, 0.0
    for r in range(loops.kind.shape[0]):
        if not _is_force(loops.law, r):           # a drive's force constrains nothing
            largest_g = max(largest_g, abs(loops.g[r]))
            largest_gd = max(largest_gd, abs(loops.gd[r]))
    return largest_g, largest_gd


@kernel
def _constrained(loops, values):
    """-values with a drive's force's rows 0 (the projection moves nothing for them)."""
    out = -values
    for r in range(loops.kind.shape[0]):
        if _is_force(loops.law, r):
            out[r] = 0.0
    return out


@allocating_kernel
def project_onto_loops(params, loops, state):
    """After a step: the configuration and the rates moved back onto the loops along the step's
    responses to unit multipliers, dx_j (row j's response of w', q'' and eta'' on its active
    bodies: the least change in the metric of the step's own matrix; consistent across the
    joints, whose kinematics are linear in the rates and, to first order, in the increments).
    The rows' rates are linear in the rates, so V[:, j] = g'(x' + dx_j) - g'(x') (the tree's
    kinematics over row j's active bodies, for the rows they carry: tree_points, row_positions)
    is exact for the rates, and the positions' Jacobian along dx_j taken as increments.  (Not
    the Delassus matrix J z_j: the step's responses carry its O(w h) terms; docs/loops.md.)  V
    factored once (the banded LU or the SVD, as _rows_solve chooses); Gauss-Newton moves the
    configuration, x <- x + sum_j mu_j dx_j, V mu = -g, until
    |g| <= POSITION_TOL (at most POSITION_PROJECTIONS times), then V mu = -g' moves the rates,
    twice at most; the dependent frames are rebuilt after each move.  Records the largest
    residuals before and after (loops.stats)."""
    n_rows = loops.kind.shape[0]
    e3 = np.empty((3, 3))
    phi = np.empty(3)
    work = np.empty(60)
    _modal_responses(params, loops, state.eta_map)
    g0, gd0 = _residuals(params, loops, state)
    loops.stats[0] = max(loops.stats[0], g0)
    loops.stats[1] = max(loops.stats[1], gd0)
    # V, column by column, over each row's active bodies and the rows they carry
    base = loops.gd.copy()
    v = loops.delassus
    _clear_rows_matrix(loops, v)
    for j in range(n_rows):
        bodies = loops.act_idx[loops.act_ptr[j + 1]:loops.act_ptr[j + 2]]
        rows = loops.colrow_idx[loops.colrow_ptr[j]:loops.colrow_ptr[j + 1]]
        for f in (1.0, -1.0):
            _add_rates(params, loops, state, j, f)
            _dependent_frames(params, loops, state, bodies, work)
            tree_points(params, state.rot, state.omega, state.jq, state.jqd, state.eta,
                        state.eta_d, state.defl, state.defl_rate, loops, bodies)
            if f > 0.0:
                row_positions(params, loops, state.rot, state.omega, rows)
                for q in range(rows.shape[0]):
                    v[rows[q], j] = loops.gd[rows[q]] - base[rows[q]]
    put1(loops.gd, base)
    for r in range(n_rows):             # a drive's force's row: mu_r = 0
        if _is_force(loops.law, r):
            v[r, :] = 0.0
            v[:, r] = 0.0
            v[r, r] = 1.0
    banded = loops.band[0] >= 0
    piv = np.empty(n_rows, dtype=np.int64)
    if banded:
        _band_factor(v, loops.band[0], loops.band[1], piv)
    u, sv, vt = np.linalg.svd(np.eye(1) if banded else v)
    largest = g0
    for _ in range(POSITION_PROJECTIONS):
        if largest <= POSITION_TOL:
            break
        mu = (_band_apply(v, loops.band[0], loops.band[1], piv, _constrained(loops, loops.g))
              if banded else _least_apply(u, sv, vt, _constrained(loops, loops.g)))
        for j in range(n_rows):
            _move(params, loops, state, j, mu[j], e3, phi)
        _dependent_frames(params, loops, state, loops.all_bodies, work)
        largest, _ = _residuals(params, loops, state)
    loops.stats[3] = max(loops.stats[3], largest)
    rates = 0.0
    for _ in range(2):
        _, rates = _residuals(params, loops, state)
        if rates <= RATE_TOL:
            break
        mu = (_band_apply(v, loops.band[0], loops.band[1], piv, _constrained(loops, loops.gd))
              if banded else _least_apply(u, sv, vt, _constrained(loops, loops.gd)))
        for j in range(n_rows):
            _add_rates(params, loops, state, j, mu[j])
        _dependent_frames(params, loops, state, loops.all_bodies, work)
        _, rates = _residuals(params, loops, state)
    loops.stats[2] = max(loops.stats[2], rates)
    for r in range(n_rows):             # the driven coordinates' rates (the drives' power)
        if loops.coordinate[r] >= 0:
            loops.wrench[loops.owner[r], 8 + loops.coordinate[r]] = loops.gd[r] + loops.target[r, 1]
    if loops.energy[0] > 0.0:
        _hold_energy(params, loops, state)


@no_alloc_kernel
def _mechanical_energy(params, loops, state):
    """(T, V) of a model of rigid bodies (docs/loops.md, "The energy held"): every body's
    1/2 m |v_C|^2 + 1/2 (A^T w) . J_C (A^T w) and -m g . r_C, its mass centre from its output
    point (tree_points), r_C = r_O + A (l_IC - l_IO), v_C = v_O + w x A (l_IC - l_IO)."""
    tree_points(params, state.rot, state.omega, state.jq, state.jqd, state.eta, state.eta_d,
                state.defl, state.defl_rate, loops, loops.all_bodies)
    bp = model_tables.body_params(params)
    inertia = model_tables.mass_center_inertia(params)
    g, body_row = model_tables.gravity(params), model_tables.body_row(params)
    kinetic, potential = 0.0, 0.0
    for k in range(body_row.shape[0]):
        row = body_row[k]
        rot_k = _m9(state.rot, k)
        w = _v3(state.omega, k)
        arm = t_mv(rot_k, (bp[row, 1] - bp[row, 4], bp[row, 2] - bp[row, 5],
                           bp[row, 3] - bp[row, 6]))
        r_c = _add(_v3(loops.r_out, k), arm)
        v_c = _add(_v3(loops.v_out, k), t_cross(w, arm))
        w_b = (rot_k[0] * w[0] + rot_k[3] * w[1] + rot_k[6] * w[2],     # A^T w
               rot_k[1] * w[0] + rot_k[4] * w[1] + rot_k[7] * w[2],
               rot_k[2] * w[0] + rot_k[5] * w[1] + rot_k[8] * w[2])
        spin = 0.0
        for i in range(3):
            for j in range(3):
                spin += w_b[i] * inertia[row, i, j] * w_b[j]
        kinetic += 0.5 * (bp[row, 0] * _dot(v_c, v_c) + spin)
        potential -= bp[row, 0] * (g[0] * r_c[0] + g[1] * r_c[1] + g[2] * r_c[2])
    return kinetic, potential


@kernel(entry=True)
def start_energy(params, loops, state):
    """The total energy T + V of the state (at the start of a run: the energy its steps hold,
    loops.energy[1])."""
    kinetic, potential = _mechanical_energy(params, loops, state)
    return kinetic + potential


@no_alloc_kernel
def _hold_energy(params, loops, state):
    """After the loops' projection (docs/loops.md, "The energy held"): every rate scaled by
    s = sqrt((E - V) / T), so that T + V is the run's E again.  T is quadratic in the rates and
    the rows' rates are linear in them (a fixed ground, no driven rows), so the rates stay on
    the loops; the scaling is the least change of the rates, in the kinetic metric, that holds
    E.  Skipped where it would change them by more than ENERGY_STEP_LIMIT (T near 0)."""
    kinetic, potential = _mechanical_energy(params, loops, state)
    want = loops.energy[1] - potential
    if not (kinetic > 0.0 and want > 0.0):
        return
    s = np.sqrt(want / kinetic)
    if abs(s - 1.0) > ENERGY_STEP_LIMIT:
        return
    loops.energy[2] = max(loops.energy[2], abs(s - 1.0))
    hinge_kind = model_tables.hinge_kind(params)
    for k in range(hinge_kind.shape[0]):
        for i in range(3):
            state.omega[k, i] *= s
            state.defl_rate[k, i] *= s
        for i in range(n_coordinates(hinge_kind[k])):
            state.jqd[k, i] *= s


# The tree's full-state sweep with many load columns (sweep.py::riccati_tree_full, "Trees in
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
    inboard loads (sweep.py::riccati_tree_full).  port_s (n, 6, 6) scratch.  Returns 0, or
    j + 1 for the element j whose elimination is singular."""
    n = parent.shape[0]
    p_col, port_p, up_ptr, up_idx = loops.p_col, loops.port_col, loops.up_ptr, loops.up_idx
    most = 1
    for k in range(n):
        most = max(most, 1 + up_ptr[k + 1] - up_ptr[k])
        port_s[k] = 0.0
        port_p[0, k] = 0.0
        for q in range(up_ptr[k], up_ptr[k + 1]):
            port_p[up_idx[q], k] = 0.0
    for c in range(1, loops.col_body.shape[0]):
        for side in range(2):
            kb = loops.col_body[c, side]
            if kb >= 0:
                add1(port_p[c, kb], loops.col_load[c, side])
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
                    loops.free_store[k, mf] = c3
                    mf += 1
            loops.free_store[k, 3] = mf
            s_phi = matmul(s_o, uh[0:6, 0:6])
            for a in range(mf):
                ca = loops.free_store[k, a]
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
                ca = loops.free_store[k, a]
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
                    loops.h_store[k, a, j] = rhs[a, j]
                for c in range(m):
                    loops.k_store[cols[c], k, a] = rhs[a, 6 + c]
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
