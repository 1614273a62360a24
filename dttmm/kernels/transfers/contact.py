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
                - mu f_n (P / s - v_t v_t^T / s^3) c3 / c1,

P = E - n n^T the projection on the plane.  a_P = a_I + kappa(rho_P) (kernels/transfers/body.py),
rho_P = A l_IP - r n its arm from the input point, so that the transfer of the body
(q_O = q_I + ... + F, m_O = m_I - rho x q_O + ... + rho_P x F) gains

  dq_O = F,  dm_O = (rho_P - rho) x F,    rho = A l_IO,

with their derivatives by a_I (S, (rho_P - rho)^ S) and by phi (S Dkappa_P,
(rho_P - rho)^ S Dkappa_P - F^ (D rho_P - D rho), D rho_X = -(A l_X)^ Lam).
"""
import numpy as np

from .. import allocating_kernel, kernel, loop_tables, model_tables
from ...elements.contact import (CENTRE, DAMPING, FRICTION, LEVEL, NORMAL, RADIUS, RATE,
                                 STICK_VELOCITY, STIFFNESS)
from ..algebra.so3 import hat
from ...elements.rigid_body import TO_OUTPUT
from .body import A, CONST, M, PHI, Q, _kappa_into, _mm_add


@kernel
def contact_value(row, centre, velocity, c1, c3, force, slope):
    """The force (world, N) of the contact sphere `row` whose centre is at `centre` and whose
    contact point moves at `velocity` into force, its derivative by the contact point's
    acceleration into slope (zero where c1 is 0: the consistent start, positions and velocities
    known); returns the penetration delta (m; < 0: apart)."""
    n = row[NORMAL]
    delta = row[RADIUS] + row[LEVEL] - (n[0] * centre[0] + n[1] * centre[1] + n[2] * centre[2])
    vn = n[0] * velocity[0] + n[1] * velocity[1] + n[2] * velocity[2]
    for i in range(3):
        force[i] = 0.0
        for j in range(3):
            slope[i, j] = 0.0
    if delta <= 0.0:
        return delta
    k, a, w = row[STIFFNESS], row[DAMPING], row[RATE]
    rate = -vn
    rho = np.sqrt(rate * rate + w * w * delta * delta)
    g = 1.0 + a * rate / rho
    if g <= 0.0:
        return delta
    f_n = k * delta * g
    mu, v_s = row[FRICTION], row[STICK_VELOCITY]
    v_t = np.empty(3)
    for i in range(3):
        v_t[i] = velocity[i] - vn * n[i]
    s = np.sqrt(v_t[0] * v_t[0] + v_t[1] * v_t[1] + v_t[2] * v_t[2] + v_s * v_s)
    direction = np.empty(3)
    for i in range(3):
        direction[i] = n[i] - mu * v_t[i] / s
        force[i] = f_n * direction[i]
    if c1 == 0.0:
        return delta
    rho3 = rho * rho * rho
    by_depth = k * g - k * a * rate * w * w * delta * delta / rho3
    by_rate = k * a * w * w * delta * delta * delta / rho3
    normal = (by_depth + c3 * by_rate) / c1
    glide = mu * f_n * c3 / c1
    for i in range(3):
        for j in range(3):
            proj = (1.0 if i == j else 0.0) - n[i] * n[j]
            slope[i, j] = (-direction[i] * normal * n[j]
                           - glide * (proj / s - v_t[i] * v_t[j] / (s * s * s)))
    return delta


@kernel
def contact_arm(row, rot):
    """(A l_IP, rho_P = A l_IP - r n): the contact sphere's centre and its contact point from
    the body's input point, world."""
    centre = np.empty(3)
    point = np.empty(3)
    l_ip, n, r = row[CENTRE], row[NORMAL], row[RADIUS]
    for i in range(3):
        centre[i] = rot[i, 0] * l_ip[0] + rot[i, 1] * l_ip[1] + rot[i, 2] * l_ip[2]
        point[i] = centre[i] - r * n[i]
    return centre, point


@kernel
def contact_correction(row, l_io, rot, lam, w, wd, dw, dwd, force, slope, z_star, u):
    """Add the contact's force F* + S (a_P - a_P*) to the rigid body's transfer u (12 x 13, phi
    slots, about z_star), as the module's docstring derives."""
    centre, rho_p = contact_arm(row, rot)
    rho = np.empty(3)
    for i in range(3):
        rho[i] = rot[i, 0] * l_io[0] + rot[i, 1] * l_io[1] + rot[i, 2] * l_io[2]
    mat = np.empty((12, 3, 3))
    d_rho_p, d_rho, dkap, s_dk, arm_h, f_h, buf = (mat[0], mat[1], mat[2], mat[3], mat[4],
                                                   mat[5], mat[6:11])
    h = mat[11]
    hat(centre, h)
    d_rho_p[:, :] = 0.0
    _mm_add(h, lam, -1.0, d_rho_p)          # d(A l_IP)/d phi (the offset -r n stays put)
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


@allocating_kernel
def contact_forces(params, loops, rot, w, c1, c3, force, slope, centre_before, first):
    """Every contact sphere's force and slope (contact_value) at the bodies' rotations rot,
    angular velocities w and output points loops.r_out, v_out (kernels/assembly/closure.py::
    tree_points, at the same state); returns the Newton iterations' change for the contacts,
    m: the largest move of a sphere's centre since the iteration before (centre_before, which
    takes the new ones), over the spheres within reach of the plane (delta > -4 |v| c3 / c1,
    about two steps' travel); in the first iteration (first) infinite where any is, so that a
    contact is never taken from the predictor alone."""
    rows = model_tables.contacts(params)
    first_row = model_tables.contact_first(params)
    body_params, body_row = model_tables.body_params(params), model_tables.body_row(params)
    r_out, v_out = loop_tables.r_out(loops), loop_tables.v_out(loops)
    change = 0.0
    x_c, v_p = np.empty(3), np.empty(3)
    for k in range(first_row.shape[0] - 1):
        l_io = body_params[body_row[k], TO_OUTPUT]
        for c in range(first_row[k], first_row[k + 1]):
            row = rows[c]
            centre, point = contact_arm(row, rot[k])       # (point: reused below)
            wk = w[k]
            for i in range(3):          # from the output point: r_in = r_out - A l_IO
                x_c[i] = r_out[k, i] + centre[i] - (rot[k, i, 0] * l_io[0]
                                                    + rot[k, i, 1] * l_io[1]
                                                    + rot[k, i, 2] * l_io[2])
            for i in range(3):          # arm from the output point to the contact point
                point[i] = x_c[i] - row[RADIUS] * row[NORMAL][i] - r_out[k, i]
            v_p[0] = v_out[k, 0] + wk[1] * point[2] - wk[2] * point[1]
            v_p[1] = v_out[k, 1] + wk[2] * point[0] - wk[0] * point[2]
            v_p[2] = v_out[k, 2] + wk[0] * point[1] - wk[1] * point[0]
            delta = contact_value(row, x_c, v_p, c1, c3, force[c], slope[c])
            if c1 > 0.0:
                speed = np.sqrt(v_p[0] * v_p[0] + v_p[1] * v_p[1] + v_p[2] * v_p[2])
                if delta > -4.0 * speed * c3 / c1:
                    if first:
                        change = np.inf
                    else:
                        for i in range(3):
                            change = max(change, abs(x_c[i] - centre_before[c, i]))
            for i in range(3):
                centre_before[c, i] = x_c[i]
    return change
