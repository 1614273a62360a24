"""A contact sphere's force on its rigid body within the step (docs/contact.md).

The law (elements/contact.py): penetration delta = r + n . p0 - n . x_c, its rate
delta' = -n . v (v the contact point's velocity), rho = sqrt(delta'^2 + w^2 delta^2), and while
delta > 0
  f_n = k delta g,  g = max(0, 1 + a delta' / rho),
  F = f_n (n - mu v_t / s),  v_t = v - (n . v) n,  s = sqrt(|v_t|^2 + v_s^2).

In the step it is implicit: evaluated at the Newton guess and linearized in the contact point's
acceleration a_P, whose position and velocity move with it as the integrator's do
(dx = da_P / c1, dv = c3 / c1 da_P: docs/solver.md), so that the contact adds to the body's
transfer a force F* + S (a_P - a_P*) at the contact point, like a point mass -S:

  d f_n / d delta  = k g - k a delta' w^2 delta^2 / rho^3,
  d f_n / d delta' = k a w^2 delta^3 / rho^3                       (g > 0; else both 0)
  dF/da_P = S = -(n - mu v_t / s) (d f_n / d delta + c3 d f_n / d delta') / c1 n^T
                - mu f_n P / s c3 / c1,

P = E - n n^T the projection on the plane.  The friction's slope is its secant, f_t / v_t,
not its tangent (which lacks - v_t v_t^T / s^3): sliding, the tangent is flat along v_t, and
Newton's steps from it cross zero and come back, so that a box spun on the plane kept 0.7% of
its spin; the secant's iterations converge to the same force from either side.

a_P = a_I + kappa(rho_P) (kernels/transfers/body.py),
rho_P = A l_IP - r n its arm from the input point, so that the transfer of the body
(q_O = q_I + ... + F, m_O = m_I - rho x q_O + ... + rho_P x F) gains

  dq_O = F,  dm_O = (rho_P - rho) x F,    rho = A l_IO,

with their derivatives by a_I (S, (rho_P - rho)^ S) and by phi (S Dkappa_P,
(rho_P - rho)^ S Dkappa_P - F^ (D rho_P - D rho), D rho_X = -(A l_X)^ Lam).

Two bodies' rows i and j touch each other with the same law (elements/contact.py::pair_law)
at their nearest points x_i and x_j (kernels/transfers/contact_geometry.py: two swept rows'
axes, or a row's deepest point x_i in a box and the box's surface point x_j below it), along
n = (x_i - x_j) / |x_i - x_j| (a box's outward normal there), delta = r_i + r_j - |x_i - x_j|
(r_i - sd for a box), at the relative velocity v_i - v_j of their contact points x_i - r_i n
and x_j + r_j n: F on i, -F on j, each at its body's point held through the iterations (the
instance's point, body frame).  Each body's
transfer takes its own force with the slope by its own point's acceleration (the same S for
both: F_j = -F(v_i - v_j)); the other body's motion is the guess's, so the iterations converge
as a block-Jacobi Newton, at a rate S / (M + S) ~ (w h)^2 / 4 per iteration: fast for a contact
the step resolves; friction's damper c = mu f_n / v_s is capped (elements/contact.py::
STICK_DAMPING) so that its share converges as fast.  The pairs are found by sweep and prune
(sorting the rows' extents along world x, O(N log N)), rows of one body and of a body and
its parent excluded.
"""
import numpy as np

from .. import allocating_kernel, kernel, loop_tables, model_tables
from ...elements.contact import (AXES, BODY, CENTRE, CORNER, DAMPING, FRICTION, HALF, LEVEL,
                                 MASS, NORMAL, ON_PLANE, OWN_DAMPING, OWN_FRICTION,
                                 OWN_STICK_VELOCITY, OWN_STIFFNESS, PARENT, RADIUS, RATE, ROLE,
                                 SEGMENT, SOLID, STICK_DAMPING, STICK_VELOCITY, STIFFNESS,
                                 SWEPT)
from ..algebra.so3 import hat
from .body import A, CONST, M, PHI, Q, _kappa_into, _mm_add
from .contact_geometry import box_distance, segment_box_parameter, segment_parameters


@kernel
def law_value(k, a, w, mu, v_s, cap, n, delta, velocity, c1, c3, force, slope):
    """The law's force (world, N) on the body whose contact point moves at `velocity`
    (relative to what it touches) into force, and its slope by the point's acceleration into
    slope (zero where c1 is 0: the consistent start); n the normal pushing the body, delta the
    penetration (m; nothing where <= 0); cap > 0: the stick velocity at least mu f_n / cap
    (two bodies' friction, elements/contact.py::pair_law; its slope as for a constant one)."""
    for i in range(3):
        force[i] = 0.0
        for j in range(3):
            slope[i, j] = 0.0
    if delta <= 0.0:
        return
    vn = n[0] * velocity[0] + n[1] * velocity[1] + n[2] * velocity[2]
    rate = -vn
    rho = np.sqrt(rate * rate + w * w * delta * delta)
    g = 1.0 + a * rate / rho
    if g <= 0.0:
        return
    f_n = k * delta * g
    v_t = np.empty(3)
    for i in range(3):
        v_t[i] = velocity[i] - vn * n[i]
    if cap > 0.0:
        v_s = max(v_s, mu * f_n / cap)
    s = np.sqrt(v_t[0] * v_t[0] + v_t[1] * v_t[1] + v_t[2] * v_t[2] + v_s * v_s)
    direction = np.empty(3)
    for i in range(3):
        direction[i] = n[i] - mu * v_t[i] / s
        force[i] = f_n * direction[i]
    if c1 == 0.0:
        return
    rho3 = rho * rho * rho
    by_depth = k * g - k * a * rate * w * w * delta * delta / rho3
    by_rate = k * a * w * w * delta * delta * delta / rho3
    normal = (by_depth + c3 * by_rate) / c1
    glide = mu * f_n * c3 / c1
    for i in range(3):
        for j in range(3):
            proj = (1.0 if i == j else 0.0) - n[i] * n[j]
            slope[i, j] = (-direction[i] * normal * n[j]
                           - glide * proj / s)


@kernel
def contact_value(row, centre, velocity, c1, c3, force, slope):
    """The plane's force on the contact sphere `row` whose centre is at `centre` and whose
    contact point moves at `velocity` (law_value with the plane's law); returns the
    penetration delta (m; < 0: apart; -inf: the sphere has no plane)."""
    if row[ON_PLANE] == 0.0:
        law_value(0.0, 0.0, 0.0, 0.0, 1.0, 0.0, row[NORMAL], -1.0, velocity, c1, c3, force,
                  slope)
        return -np.inf
    n = row[NORMAL]
    delta = row[RADIUS] + row[LEVEL] - (n[0] * centre[0] + n[1] * centre[1] + n[2] * centre[2])
    law_value(row[STIFFNESS], row[DAMPING], row[RATE], row[FRICTION], row[STICK_VELOCITY], 0.0,
              n, delta, velocity, c1, c3, force, slope)
    return delta


@kernel
def pair_value(row_i, row_j, n, delta, velocity, c1, c3, force, slope):
    """Row j's force on row i (law_value with the pair's law, elements/contact.py::pair_law):
    n from j to i, velocity v_i - v_j at the contact points."""
    k = 1.0 / (1.0 / row_i[OWN_STIFFNESS] + 1.0 / row_j[OWN_STIFFNESS])
    reduced = row_i[MASS] * row_j[MASS] / (row_i[MASS] + row_j[MASS])
    w = np.sqrt(k / reduced)
    law_value(k, max(row_i[OWN_DAMPING], row_j[OWN_DAMPING]), w,
              min(row_i[OWN_FRICTION], row_j[OWN_FRICTION]),
              min(row_i[OWN_STICK_VELOCITY], row_j[OWN_STICK_VELOCITY]),
              STICK_DAMPING * reduced * w, n, delta, velocity, c1, c3, force, slope)


@kernel
def contact_correction(l_ip, offset, l_io, rot, lam, w, wd, dw, dwd, force, slope, z_star, u):
    """Add a contact's force F* + S (a_P - a_P*) at the point A l_IP + offset (world; l_IP the
    body's point the contact holds, offset from it to the contact point) to the rigid body's
    transfer u (12 x 13, phi slots, about z_star), as the module's docstring derives."""
    centre, rho_p, rho = np.empty(3), np.empty(3), np.empty(3)
    for i in range(3):
        centre[i] = rot[i, 0] * l_ip[0] + rot[i, 1] * l_ip[1] + rot[i, 2] * l_ip[2]
        rho_p[i] = centre[i] + offset[i]
        rho[i] = rot[i, 0] * l_io[0] + rot[i, 1] * l_io[1] + rot[i, 2] * l_io[2]
    mat = np.empty((12, 3, 3))
    d_rho_p, d_rho, dkap, s_dk, arm_h, f_h, buf = (mat[0], mat[1], mat[2], mat[3], mat[4],
                                                   mat[5], mat[6:11])
    h = mat[11]
    hat(centre, h)
    d_rho_p[:, :] = 0.0
    _mm_add(h, lam, -1.0, d_rho_p)          # d(A l_IP)/d phi (the offset stays put)
    hat(rho, h)
    d_rho[:, :] = 0.0
    _mm_add(h, lam, -1.0, d_rho)
    kap = np.empty(3)
    _kappa_into(w, wd, rho_p, dwd, dw, d_rho_p, kap, dkap, buf)
    s_dk[:, :] = 0.0
    _mm_add(slope, dkap, 1.0, s_dk)
    arm = np.empty(3)
    for i in range(3):
        arm[i] = rho_p[i] - rho[i]
    hat(arm, arm_h)
    hat(force, f_h)
    d_m_a = np.zeros((3, 3))
    _mm_add(arm_h, slope, 1.0, d_m_a)
    d_m_phi = np.zeros((3, 3))
    _mm_add(arm_h, s_dk, 1.0, d_m_phi)
    for i in range(3):
        for j in range(3):
            h[i, j] = d_rho_p[i, j] - d_rho[i, j]
    _mm_add(f_h, h, -1.0, d_m_phi)
    moment = np.empty(3)
    moment[0] = arm[1] * force[2] - arm[2] * force[1]
    moment[1] = arm[2] * force[0] - arm[0] * force[2]
    moment[2] = arm[0] * force[1] - arm[1] * force[0]
    for i in range(3):
        shift_q = force[i]
        shift_m = moment[i]
        for j in range(3):
            u[Q + i, A + j] += slope[i, j]
            u[Q + i, PHI + j] += s_dk[i, j]
            u[M + i, A + j] += d_m_a[i, j]
            u[M + i, PHI + j] += d_m_phi[i, j]
            shift_q -= slope[i, j] * z_star[A + j] + s_dk[i, j] * z_star[PHI + j]
            shift_m -= d_m_a[i, j] * z_star[A + j] + d_m_phi[i, j] * z_star[PHI + j]
        u[Q + i, CONST] += shift_q
        u[M + i, CONST] += shift_m


@kernel
def _point_velocity(r_out, v_out, w, x, out):
    """out = the velocity of the body's point at x (world): v_O + w x (x - r_O)."""
    a0, a1, a2 = x[0] - r_out[0], x[1] - r_out[1], x[2] - r_out[2]
    out[0] = v_out[0] + w[1] * a2 - w[2] * a1
    out[1] = v_out[1] + w[2] * a0 - w[0] * a2
    out[2] = v_out[2] + w[0] * a1 - w[1] * a0


@kernel
def _add_instance(inst, body, point, offset, force, slope, sign):
    """Append a contact (its body's point, body frame from the input point, the offset of the
    contact point from it, world, sign times the force, the slope) to the instances inst =
    (point, offset, force, slope, next, body_first, count) and to body's list; False where
    they are full."""
    i_point, i_offset, i_force, i_slope, i_next, body_first, count = inst
    i = count[0]
    if i >= i_point.shape[0]:
        return False
    for a in range(3):
        i_point[i, a] = point[a]
        i_offset[i, a] = offset[a]
        i_force[i, a] = sign * force[a]
        for b in range(3):
            i_slope[i, a, b] = slope[a, b]
    i_next[i] = body_first[body]
    body_first[body] = i
    count[0] = i + 1
    return True


@kernel
def _body_point(rot, r_out, l_io, x, out):
    """out = the body's point at x (world) in its frame from its input point:
    A^T (x - r_O) + l_IO."""
    for i in range(3):
        out[i] = (rot[0, i] * (x[0] - r_out[0]) + rot[1, i] * (x[1] - r_out[1])
                  + rot[2, i] * (x[2] - r_out[2]) + l_io[i])


@allocating_kernel
def contact_forces(params, loops, rot, w, c1, c3, centre_before, first, inst):
    """Every contact at rotations rot, angular velocities w and output points loops.r_out,
    v_out (kernels/assembly/closure.py::tree_points, at the same state): each row but a box's
    solid against the plane (contact_value), each pair of rows of two bodies the sweep and
    prune finds (elements/contact.py::touching_pairs' kinds; kernels/transfers/
    contact_geometry.py; pair_value), written as instances inst = (point, offset, force,
    slope, next, body_first, count) for the bodies' transfers (contact_correction).  Returns
    the Newton iterations' change for the contacts, m: the largest move of a row's centre since
    the iteration before (centre_before, which takes the new ones), over the rows within reach
    of the plane or of another (two steps' travel, 4 |v| c3 / c1); in the first iteration
    (first) infinite where any is, so that a contact is never taken from the predictor alone;
    NaN where the instances are full."""
    rows = model_tables.contacts(params)
    body_params, body_row = model_tables.body_params(params), model_tables.body_row(params)
    r_out, v_out = loop_tables.r_out(loops), loop_tables.v_out(loops)
    body_first, count = inst[5], inst[6]
    count[0] = 0
    for k in range(body_first.shape[0]):
        body_first[k] = -1
    n_rows = rows.shape[0]
    x_c, v_c, seg = np.empty((n_rows, 3)), np.empty((n_rows, 3)), np.zeros((n_rows, 3))
    axes = np.zeros((n_rows, 3, 3))
    reach, low, high = np.zeros(n_rows), np.empty(n_rows), np.empty(n_rows)
    near = np.zeros(n_rows, dtype=np.bool_)
    step = 2.0 * c3 / c1 if c1 > 0.0 else 0.0           # (h, for gamma = 1/2)
    v_p, v_j, offset, offset_j = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    n_ij, c_i, c_j, local = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    force, slope = np.empty(3), np.empty((3, 3))
    ok = True
    for c in range(n_rows):            # the rows' centres, axes, boxes, velocities, extents
        row = rows[c]
        k = int(row[BODY])
        l_io = body_params[body_row[k], 4:7]
        for i in range(3):              # from the output point: A (l_IP - l_IO)
            x_c[c, i] = r_out[k, i]
            for j in range(3):
                x_c[c, i] += rot[k, i, j] * (row[CENTRE][j] - l_io[j])
                seg[c, i] += rot[k, i, j] * row[SEGMENT][j]
                for m in range(3):
                    axes[c, i, j] += rot[k, i, m] * row[AXES][3 * m + j]
        _point_velocity(r_out[k], v_out[k], w[k], x_c[c], v_c[c])
        size = row[RADIUS] + np.sqrt(seg[c, 0] ** 2 + seg[c, 1] ** 2 + seg[c, 2] ** 2)
        half_x = 0.0
        for i in range(3):
            size += row[HALF][i]
            half_x += abs(axes[c, 0, i]) * row[HALF][i]
        wk = w[k]
        speed = np.sqrt(v_c[c, 0] ** 2 + v_c[c, 1] ** 2 + v_c[c, 2] ** 2
                        + (wk[0] ** 2 + wk[1] ** 2 + wk[2] ** 2) * size ** 2)
        reach[c] = 2.0 * speed * step
        low[c] = min(x_c[c, 0], x_c[c, 0] + seg[c, 0]) - row[RADIUS] - half_x - reach[c]
        high[c] = max(x_c[c, 0], x_c[c, 0] + seg[c, 0]) + row[RADIUS] + half_x + reach[c]
    for c in range(n_rows):            # against the plane
        row = rows[c]
        k = int(row[BODY])
        for i in range(3):
            offset[i] = -row[RADIUS] * row[NORMAL][i]
            c_i[i] = x_c[c, i] + offset[i]
        _point_velocity(r_out[k], v_out[k], w[k], c_i, v_p)
        delta = contact_value(row, x_c[c], v_p, c1, c3, force, slope)
        if delta > -reach[c]:
            near[c] = True
        if delta > 0.0:
            ok = ok and _add_instance(inst, k, row[CENTRE], offset, force, slope, 1.0)
    if n_rows > 1:                     # pairs: sweep and prune along world x
        order = np.argsort(low)
        for ii in range(n_rows):
            a = order[ii]
            for jj in range(ii + 1, n_rows):
                b = order[jj]
                if low[b] > high[a]:
                    break
                i, j = (b, a) if int(rows[a, ROLE]) == SOLID else (a, b)
                row_i, row_j = rows[i], rows[j]
                bi, bj = int(row_i[BODY]), int(row_j[BODY])
                if bi == bj or int(row_i[PARENT]) == bj or int(row_j[PARENT]) == bi:
                    continue
                role_i, role_j = int(row_i[ROLE]), int(row_j[ROLE])
                if role_j == SOLID and (role_i == SWEPT or role_i == CORNER):
                    t = segment_box_parameter(x_c[i], seg[i], x_c[j], axes[j], row_j[HALF],
                                              n_ij)
                    for m in range(3):
                        c_i[m] = x_c[i, m] + t * seg[i, m]
                    sd = box_distance(c_i[0], c_i[1], c_i[2], x_c[j], axes[j], row_j[HALF],
                                      n_ij)
                    delta = row_i[RADIUS] - sd
                    for m in range(3):
                        c_j[m] = c_i[m] - sd * n_ij[m]          # (on the box's surface)
                        offset_j[m] = 0.0
                elif role_i == SWEPT and role_j == SWEPT:
                    s, t = segment_parameters(x_c[i], seg[i], x_c[j], seg[j])
                    dist = 0.0
                    for m in range(3):
                        c_i[m] = x_c[i, m] + s * seg[i, m]
                        c_j[m] = x_c[j, m] + t * seg[j, m]
                        n_ij[m] = c_i[m] - c_j[m]
                        dist += n_ij[m] * n_ij[m]
                    dist = np.sqrt(dist)
                    if dist == 0.0:
                        continue
                    for m in range(3):
                        n_ij[m] /= dist
                        offset_j[m] = row_j[RADIUS] * n_ij[m]
                    delta = row_i[RADIUS] + row_j[RADIUS] - dist
                else:
                    continue
                if delta <= -(reach[i] + reach[j]):
                    continue
                near[i] = True
                near[j] = True
                if delta <= 0.0:
                    continue
                for m in range(3):
                    offset[m] = -row_i[RADIUS] * n_ij[m]
                    v_p[m] = c_i[m] + offset[m]
                    v_j[m] = c_j[m] + offset_j[m]
                _point_velocity(r_out[bi], v_out[bi], w[bi], v_p, v_p)
                _point_velocity(r_out[bj], v_out[bj], w[bj], v_j, v_j)
                for m in range(3):
                    v_p[m] -= v_j[m]
                pair_value(row_i, row_j, n_ij, delta, v_p, c1, c3, force, slope)
                _body_point(rot[bi], r_out[bi], body_params[body_row[bi], 4:7], c_i, local)
                ok = ok and _add_instance(inst, bi, local, offset, force, slope, 1.0)
                _body_point(rot[bj], r_out[bj], body_params[body_row[bj], 4:7], c_j, local)
                ok = ok and _add_instance(inst, bj, local, offset_j, force, slope, -1.0)
    change = 0.0
    for c in range(n_rows):
        if near[c] and c1 > 0.0:
            if first:
                change = np.inf
            else:
                for i in range(3):
                    change = max(change, abs(x_c[c, i] - centre_before[c, i]))
        for i in range(3):
            centre_before[c, i] = x_c[c, i]
    return change if ok else np.nan
