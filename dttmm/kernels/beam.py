"""Transfer of an Euler-Bernoulli modal beam over one time step (docs/beam.md).

Station slots as for the rigid body but with the angular acceleration in the rotation slot (the
sweep's scaling, docs/assembly.md): z = [a, w', m, q].  The beam's modal accelerations eta'' are
internal unknowns, fixed by its modal equations; eliminating them leaves a 12 x 13 transfer like
a rigid body's, plus the affine map eta'' = E [z_in; 1] used to recover them.

The nonlinear relations are evaluated exactly (Gauss-Legendre quadrature along the beam) and
linearized by central differences about the guess: the affine map reproduces the relations at
the guess, so the step's solution is that of the exact linearization up to the differences'
error in the slope (~1e-10 relative), which is second order in the O(h^3) predictor error.
"""
import numpy as np
from numba import njit

from .so3 import expm_so3, left_jacobian, log_so3

def quadrature_size(modes_per_plane):
    """Gauss-Legendre points that integrate the beam's relations to rounding: 24 points are exact
    to 1e-15 up to 6 modes per plane, 5e-13 at 7 and 1e-6 at 10 (products of sine modes with
    x^2), so 3 m + 6 points."""
    return max(24, 3 * int(modes_per_plane) + 6)


def gauss_points(length, n_points):
    """n_points Gauss-Legendre points and weights on [0, length]."""
    x, w = np.polynomial.legendre.leggauss(n_points)
    return 0.5 * length * (x + 1.0), 0.5 * length * w


@njit(cache=True)
def beam_relations(bp, xq, wq, modes, ends, factors, end_moment, gravity, rot, w, wd, eta, eta_d,
                   eta_dd, a_i, m_i, q_i, out, residual):
    """The beam's exact relations in a given state (docs/beam.md):
    out = [a_O, w' (the frame's), m_O, q_O]; residual = the modal equations' left minus right
    sides, with the end loads' generalized forces (the moment's only if end_moment: a fixed hinge
    at the output; elsewhere m_O = 0).  bp: beam parameter row; xq, wq: quadrature; modes
    (m, N_QUAD): Y_k at the points; ends (m, 2): Y_k(L), Y_k'(L); factors (m, 2): modal mass
    over mu and modal stiffness over EI."""
    length, mu, ei_v, ei_w, j_p, zeta = bp[0], bp[1], bp[2], bp[3], bp[4], bp[5]
    m = modes.shape[0]
    e1 = rot[:, 0].copy()
    e2 = rot[:, 1].copy()
    e3 = rot[:, 2].copy()
    sum_f = np.zeros(3)
    sum_m = np.zeros(3)
    for r in range(2 * m):
        residual[r] = 0.0
    for j in range(xq.shape[0]):
        v = w_ = vd = wdd = vdd = wddd = 0.0
        for k in range(m):
            y = modes[k, j]
            v += y * eta[k]
            w_ += y * eta[m + k]
            vd += y * eta_d[k]
            wdd += y * eta_d[m + k]
            vdd += y * eta_dd[k]
            wddd += y * eta_dd[m + k]
        rho = xq[j] * e1 + v * e2 + w_ * e3
        u_dot = vd * e2 + wdd * e3
        u_ddot = vdd * e2 + wddd * e3
        acc = (a_i + np.cross(wd, rho) + np.cross(w, np.cross(w, rho)) + 2.0 * np.cross(w, u_dot)
               + u_ddot)
        f = mu * wq[j] * (gravity - acc)          # force on the segment: gravity minus inertia
        sum_f += f
        sum_m += np.cross(rho, f)
        f2 = e2[0] * f[0] + e2[1] * f[1] + e2[2] * f[2]
        f3 = e3[0] * f[0] + e3[1] * f[1] + e3[2] * f[2]
        for k in range(m):
            residual[k] -= modes[k, j] * f2
            residual[m + k] -= modes[k, j] * f3
    for k in range(m):
        modal_mass = mu * factors[k, 0]
        for r, ei in ((k, ei_v), (m + k, ei_w)):
            stiffness = ei * factors[k, 1]
            omega_k = np.sqrt(stiffness / modal_mass)
            residual[r] += 2.0 * zeta * omega_k * modal_mass * eta_d[r] + stiffness * eta[r]
    # the output point O = r_I + A (L e1 + u(L)) and its acceleration
    v_l = w_l = vd_l = wd_l = vdd_l = wdd_l = 0.0
    for k in range(m):
        y = ends[k, 0]
        v_l += y * eta[k]
        w_l += y * eta[m + k]
        vd_l += y * eta_d[k]
        wd_l += y * eta_d[m + k]
        vdd_l += y * eta_dd[k]
        wdd_l += y * eta_dd[m + k]
    rho_l = length * e1 + v_l * e2 + w_l * e3
    q_o = q_i + sum_f
    jp = j_p * length
    spin = jp * (e1 @ wd) * e1 + jp * (e1 @ w) * np.cross(w, e1)   # J_p,w w' + w x J_p,w w
    out[0:3] = (a_i + np.cross(wd, rho_l) + np.cross(w, np.cross(w, rho_l))
                + 2.0 * np.cross(w, vd_l * e2 + wd_l * e3) + vdd_l * e2 + wdd_l * e3)
    out[3:6] = wd
    out[6:9] = m_i - np.cross(rho_l, q_o) + sum_m - spin
    out[9:12] = q_o
    # generalized forces of the outboard's -q_O (at O) and -m_O (docs/beam.md, modal equations)
    q2 = q_o @ e2
    q3 = q_o @ e3
    mv = mw = 0.0
    if end_moment:
        theta = np.zeros(3)
        for k in range(m):
            theta[1] -= ends[k, 1] * eta[m + k]
            theta[2] += ends[k, 1] * eta[k]
        jl = np.empty((3, 3))
        left_jacobian(theta, jl)
        m_o = out[6:9]
        mv = m_o @ (rot @ jl[:, 2])
        mw = -(m_o @ (rot @ jl[:, 1]))
    for k in range(m):
        residual[k] += q2 * ends[k, 0] + mv * ends[k, 1]
        residual[m + k] += q3 * ends[k, 0] + mw * ends[k, 1]


@njit(cache=True)
def end_section(ends, eta, rot, out):
    """out = A exp(theta_O^): the output section's rotation, theta_O = [0, -w'(L), v'(L)]."""
    m = ends.shape[0]
    theta = np.zeros(3)
    for k in range(m):
        theta[1] -= ends[k, 1] * eta[m + k]
        theta[2] += ends[k, 1] * eta[k]
    e = np.empty((3, 3))
    expm_so3(theta, e)
    out[:, :] = rot @ e


@njit(cache=True)
def _end_section_angular_acceleration(ends, rot, w, wd, eta, eta_d, eta_dd):
    """w'_O = w' + w x (A J_l theta') + A (J_l theta'' + (d J_l / dt) theta') of the output
    section (the consistent start; d J_l / dt by a central difference along theta')."""
    m = ends.shape[0]
    th = np.zeros(3)
    th_d = np.zeros(3)
    th_dd = np.zeros(3)
    for k in range(m):
        s = ends[k, 1]
        th[1] -= s * eta[m + k]
        th[2] += s * eta[k]
        th_d[1] -= s * eta_d[m + k]
        th_d[2] += s * eta_d[k]
        th_dd[1] -= s * eta_dd[m + k]
        th_dd[2] += s * eta_dd[k]
    jl = np.empty((3, 3))
    left_jacobian(th, jl)
    jp = np.empty((3, 3))
    jm = np.empty((3, 3))
    eps = 1e-6
    left_jacobian(th + eps * th_d, jp)
    left_jacobian(th - eps * th_d, jm)
    jl_dot_thd = (jp - jm) @ th_d / (2.0 * eps)
    return wd + np.cross(w, rot @ (jl @ th_d)) + rot @ (jl @ th_dd + jl_dot_thd)


@njit(cache=True)
def _evaluate(bp, tables, outboard, gravity, start, rot_n, phi_star, wd_star, c1, c3, w3, w_n,
              w1e, w3e, eta_n, eta_d_n, x, out, residual):
    """beam_relations with the state expressed in the step's unknowns
    x = [a_I, w', m_I, q_I, eta''] (the integrator's relations, docs/solver.md).
    tables = (xq, wq, modes, ends, factors); outboard = (welded, R_rel, rotation at t_n, w1):
    with a fixed hinge at the output (welded), the output's rotation slot is the outboard body's
    angular acceleration, c1 phi_out + w1 with A_out,n+1 = exp(phi_out^) A_out,n = A_O R_rel
    (at the start: the end section's angular acceleration)."""
    xq, wq, modes, ends, factors = tables
    welded, r_rel, rot_out_n, w1_out = outboard
    n = residual.shape[0]
    wd = x[3:6]
    eta_dd = x[12:12 + n]
    if start:
        rot, w, eta, eta_d = rot_n, w_n, eta_n, eta_d_n
    else:
        phi = phi_star + (wd - wd_star) / c1
        e = np.empty((3, 3))
        expm_so3(phi, e)
        rot = e @ rot_n
        w = c3 * phi + w3
        eta = (eta_dd - w1e) / c1
        eta_d = c3 * eta + w3e
    beam_relations(bp, xq, wq, modes, ends, factors, welded, gravity, rot, w, wd, eta, eta_d,
                   eta_dd, x[0:3], x[6:9], x[9:12], out, residual)
    if welded:
        if start:
            out[3:6] = _end_section_angular_acceleration(ends, rot, w, wd, eta, eta_d, eta_dd)
        else:
            a_o = np.empty((3, 3))
            end_section(ends, eta, rot, a_o)
            phi_out = np.empty(3)
            log_so3(a_o @ r_rel @ rot_out_n.T, phi_out)
            out[3:6] = c1 * phi_out + w1_out


@njit(cache=True)
def beam_transfer(bp, tables, outboard, gravity, start, rot_n, phi_star, wd_star, c1, c3, w3,
                  w_n, w1e, w3e, eta_n, eta_d_n, z_star, eta_dd_star, u, eta_map):
    """Fill u (12 x 13) with z_O = u [z_I; 1] in angular-acceleration slots, and eta_map
    (n x 13) with eta'' = eta_map [z_I; 1], linearized about (z_star, eta_dd_star).

    start: the consistent-start solve (rotation, rates and modal state fixed, w' and eta''
    free).  Otherwise phi = phi* + (w' - wd*) / c1, w = c3 phi + w3, eta = (eta'' - w1e) / c1,
    eta' = c3 eta + w3e.  tables, outboard: see _evaluate."""
    welded = outboard[0]
    n = eta_dd_star.shape[0]
    nx = 12 + n
    x0 = np.empty(nx)
    x0[0:12] = z_star
    x0[12:] = eta_dd_star
    o0 = np.empty(12)
    r0 = np.empty(n)
    _evaluate(bp, tables, outboard, gravity, start, rot_n, phi_star, wd_star, c1, c3, w3, w_n,
              w1e, w3e, eta_n, eta_d_n, x0, o0, r0)
    d_o = np.zeros((12, nx))
    d_r = np.zeros((n, nx))
    op = np.empty(12)
    om = np.empty(12)
    rp = np.empty(n)
    rm = np.empty(n)
    xp = x0.copy()
    for c in range(nx):
        if 6 <= c < 9 and not welded:
            d_o[c, c] = 1.0              # m_O = m_I + ...: exactly linear, no difference needed
            continue
        step = 1e-3 * (1.0 + abs(x0[c]))
        xp[c] = x0[c] + step
        _evaluate(bp, tables, outboard, gravity, start, rot_n, phi_star, wd_star, c1, c3, w3,
                  w_n, w1e, w3e, eta_n, eta_d_n, xp, op, rp)
        xp[c] = x0[c] - step
        _evaluate(bp, tables, outboard, gravity, start, rot_n, phi_star, wd_star, c1, c3, w3,
                  w_n, w1e, w3e, eta_n, eta_d_n, xp, om, rm)
        xp[c] = x0[c]
        d_o[:, c] = (op - om) / (2.0 * step)
        d_r[:, c] = (rp - rm) / (2.0 * step)
    # modal equations: r0 + d_r[:, :12] dz + d_r[:, 12:] dy = 0
    r_y_inv = np.linalg.inv(np.ascontiguousarray(d_r[:, 12:]))
    e_z = -r_y_inv @ np.ascontiguousarray(d_r[:, :12])
    e_0 = eta_dd_star - r_y_inv @ r0 - e_z @ z_star
    eta_map[:, 0:12] = e_z
    eta_map[:, 12] = e_0
    o_y = np.ascontiguousarray(d_o[:, 12:])
    u_z = np.ascontiguousarray(d_o[:, :12]) + o_y @ e_z
    u[:, 0:12] = u_z
    u[:, 12] = o0 + o_y @ (e_0 + e_z @ z_star - eta_dd_star) - u_z @ z_star
