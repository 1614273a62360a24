"""The time loop: predict, linearize every element, sweep, Newton-correct, update (docs/solver.md).

Integrator: generalized-alpha in the form of Arnold and Bruls (2007), applied to each body's
world rotation increment phi (A_i = exp(phi^) A_{i-1}), to each elastic hinge's deflection d and
to each beam's modal coordinates eta:
  x        = h v_n + h^2 (1/2 - beta) p_n + h^2 beta p_{n+1}     (x = phi, d - d_n, eta - eta_n)
  v_{n+1}  = v_n + h (1 - gamma) p_n + h gamma p_{n+1}
  (1 - alpha_f) acc_{n+1} + alpha_f acc_n = (1 - alpha_m) p_{n+1} + alpha_m p_n
with p the pseudo-acceleration.  alpha_m = alpha_f = 1/2, beta = 1/4, gamma = 1/2 (rho_inf = 1)
is the trapezoidal Newmark rule.  Station positions are not integrated: they follow from the
rotations by kinematics, and the transfers work with accelerations, so the joint constraints hold
exactly (no index-3 drift, no alternating mode; docs/solver.md, "stability").  The paper's
scheme, for comparison, gives station points their own position histories (the histories
argument of advance; docs/solver.md, "The paper's scheme").
"""
import numpy as np
from numba import njit

from . import CONTRACT
from ..elements import BEAM
from ..elements.hinges import BALL, ELASTIC, FIXED
from .beam import beam_transfer
from .body import rigid_body_transfer, station_history_correction
from .hinge import elastic_hinge_loads, elastic_hinge_transfer
from .mat3 import inv3, matmul_into
from .so3 import expm_so3, left_jacobian, log_so3
from .sweep import (IDENTITY, LOCKED, TRANSFER, direct_full, direct_reduced, fold_ball_body,
                    riccati_full, riccati_reduced)
from .sweep import BALL as EL_BALL

RICCATI_FULL, RICCATI_REDUCED, DIRECT_REDUCED, DIRECT_FULL = 0, 1, 2, 3
OK, SINGULAR, NOT_FINITE = 0, 1, 2


@njit(cache=True, fastmath=CONTRACT)
def _integrator_coefficients(h, coef):
    beta, gamma, alpha_m, alpha_f = coef[0], coef[1], coef[2], coef[3]
    c1 = (1.0 - alpha_m) / ((1.0 - alpha_f) * beta * h * h)
    c3 = gamma / (beta * h)
    return c1, c3


@njit(cache=True, fastmath=CONTRACT)
def _offsets(h, coef, v, acc, p):
    """w1, w3 with acc_{n+1} = c1 x + w1, v_{n+1} = c3 x + w3 (x the increment over the step)."""
    w1 = np.empty_like(v)
    w3 = np.empty_like(v)
    _offsets_into(h, coef, v, acc, p, w1, w3, np.empty_like(v))
    return w1, w3


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _offsets_into(h, coef, v, acc, p, w1, w3, x_pred):
    """_offsets in place, with the constant-acceleration predictor x_pred = h v + h^2 p / 2
    (elementwise, no temporaries: it runs for every body and step)."""
    beta, gamma, alpha_m, alpha_f = coef[0], coef[1], coef[2], coef[3]
    ratio = (1.0 - alpha_m) / (1.0 - alpha_f)
    for i in range(v.shape[0]):
        known = h * v[i] + h * h * (0.5 - beta) * p[i]
        w1[i] = (-ratio * known / (beta * h * h)
                 + (alpha_m * p[i] - alpha_f * acc[i]) / (1.0 - alpha_f))
        w3[i] = v[i] + h * (1.0 - gamma) * p[i] - gamma / (beta * h) * known
        x_pred[i] = h * v[i] + 0.5 * h * h * p[i]


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _advance_history(h, coef, x, v, acc, p):
    """In place: v, acc, p at t_{n+1} from the increment x."""
    beta, gamma, alpha_m, alpha_f = coef[0], coef[1], coef[2], coef[3]
    for i in range(x.shape[0]):
        p_new = (x[i] - h * v[i] - h * h * (0.5 - beta) * p[i]) / (beta * h * h)
        v[i] += h * (1.0 - gamma) * p[i] + h * gamma * p_new
        acc[i] = ((1.0 - alpha_m) * p_new + alpha_m * p[i] - alpha_f * acc[i]) / (1.0 - alpha_f)
        p[i] = p_new


@njit(cache=True, fastmath=CONTRACT)
def _body_kinematics(c1, c3, rot_n, phi, w1, w3, rot, lam, w, wd, dw, dwd):
    """A body's rotation, angular velocity and acceleration at the end of the step as functions
    of its world rotation increment phi, with their derivatives (docs/solver.md):
    A = exp(phi^) A_n, w = c3 phi + w3, w' = c1 phi + w1."""
    e3 = np.empty((3, 3))
    expm_so3(phi, e3)
    matmul_into(e3, rot_n, rot)
    left_jacobian(phi, lam)
    for i in range(3):
        w[i] = c3 * phi[i] + w3[i]
        wd[i] = c1 * phi[i] + w1[i]
        for j in range(3):
            dw[i, j] = c3 if i == j else 0.0
            dwd[i, j] = c1 if i == j else 0.0


@njit(cache=True, fastmath=CONTRACT)
def _rotation_slots_to_acceleration(u, dwd_in, wd_in, phi_in, dwd_out, wd_out, phi_out):
    """Rewrite a transfer linearized in phi slots as one in angular-acceleration slots
    (docs/assembly.md, "scaling"): phi_in = phi_in* + Dwd_in^-1 (w'_in - wd_in*) and
    w'_out = wd_out* + Dwd_out (phi_out - phi_out*).  Angular accelerations are ~ m/s^2 like the
    a slots, where phi is ~ h^2 times smaller: the sweep's 6 x 6 matrices would otherwise mix
    scales 1e8 apart."""
    g_in = np.empty((3, 3))
    inv3(dwd_in, g_in)
    for r in range(12):
        u3, u4, u5 = u[r, 3], u[r, 4], u[r, 5]
        shift = u3 * phi_in[0] + u4 * phi_in[1] + u5 * phi_in[2]
        for i in range(3):
            new = u3 * g_in[0, i] + u4 * g_in[1, i] + u5 * g_in[2, i]
            u[r, 3 + i] = new
            shift -= new * wd_in[i]
        u[r, 12] += shift
    for c in range(13):
        r0, r1, r2 = u[3, c], u[4, c], u[5, c]
        for i in range(3):
            u[3 + i, c] = dwd_out[i, 0] * r0 + dwd_out[i, 1] * r1 + dwd_out[i, 2] * r2
    for i in range(3):
        u[3 + i, 12] += wd_out[i] - (dwd_out[i, 0] * phi_out[0] + dwd_out[i, 1] * phi_out[1]
                                     + dwd_out[i, 2] * phi_out[2])


@njit(cache=True, fastmath=CONTRACT)
def report(out_info, status, step, detail, n_rec):
    """The time loops' outcome in out_info: [status, the failing step (or the steps taken),
    detail (the singular element's code for SINGULAR, the most Newton iterations used for OK,
    0 for NOT_FINITE), samples recorded]; out_info[4] (unconverged steps) is the loop's own."""
    out_info[0] = status
    out_info[1] = step
    out_info[2] = detail
    out_info[3] = n_rec


@njit(cache=True, fastmath=CONTRACT)
def _all_finite(a):
    for x in a.flat:
        if not np.isfinite(x):
            return False
    return True


@njit(cache=True, fastmath=CONTRACT)
def _build_elements(body_params, hinge_kind, hinge_params, gravity, kind, u,
                    g_rot, g_lam, g_w, g_wd, g_dwd, g_phi, rot_star, lam, phi_star, w, wd, dw, dwd,
                    c1, c3, w1d, w3d, z_star, force, torque, at_start, rot, w3, beams, modal,
                    stations):
    """Element kinds and transfers about the guess z_star (phi slots), written in angular
    acceleration slots.  at_start: the consistent-start solve, where the phi slots already hold
    angular accelerations and elastic hinges are LOCKED (their loads are set by the caller).
    rot, w3: the bodies' rotations at the step's start and the integrator's offsets (beams).
    beams = (body_kind, beam_params, moments, mode_off, ends, factors) (solver.beam_tables);
    modal = (eta, eta_d, w1e, w3e, eta_dd_star, eta_map), flat over the beams' modal
    coordinates.  A body welded to a beam's output (fixed hinge) takes its rotation from the
    beam's end section (kernels/beam.py).  stations = (independent, w1_st, w1_c): in the
    paper's scheme (independent) every station point (w1_st, n + 1 of them: the ground point,
    then each body's output) and every rigid body's mass centre (w1_c) has its own Newmark
    history, a_X = c1 dr_X + w1_X (docs/solver.md, "The paper's scheme")."""
    independent, w1_st, w1_c = stations
    independent = independent and not at_start
    body_kind, beam_params, beam_moments, mode_off, beam_ends, beam_factors = beams
    eta, eta_d, w1e, w3e, eta_dd_star, eta_map = modal
    n = body_params.shape[0]
    load = np.empty(3)
    for k in range(n):
        jh = 2 * k
        hk = hinge_kind[k]
        if hk == BALL:
            kind[jh] = EL_BALL
        elif hk == FIXED:
            kind[jh] = IDENTITY
        elif at_start:
            kind[jh] = LOCKED
        else:
            kind[jh] = TRANSFER
            if k == 0:
                rot_in, lam_in, w_in, wd_in, dw_in, dwd_in, phi_in = (
                    g_rot, g_lam, g_w, g_wd, g_dwd, g_dwd, g_phi)
            else:
                rot_in, lam_in, w_in, wd_in, dw_in, dwd_in, phi_in = (
                    rot_star[k - 1], lam[k - 1], w[k - 1], wd[k - 1], dw[k - 1], dwd[k - 1],
                    phi_star[k - 1])
            elastic_hinge_transfer(hinge_params[k], rot_in, lam_in, w_in, dw_in, rot_star[k],
                                   lam[k], w[k], dw[k], phi_star[k], c1, c3, w1d[k], w3d[k],
                                   z_star[jh], u[jh])
            _rotation_slots_to_acceleration(u[jh], dwd_in, wd_in, phi_in, dwd[k], wd[k],
                                            phi_star[k])
        kind[jh + 1] = TRANSFER
        if body_kind[k] == BEAM:
            i0, i1 = mode_off[k], mode_off[k + 1]
            m = (i1 - i0) // 2
            zs = z_star[jh + 1].copy()
            zs[3:6] = wd[k]                           # the guess in angular-acceleration slots
            welded = k + 1 < n and hinge_kind[k + 1] == FIXED
            kout = k + 1 if welded else k
            outboard = (welded, hinge_params[kout, 0:9].copy().reshape((3, 3)), rot[kout],
                        wd[kout] - c1 * phi_star[kout])
            tables = (beam_moments[k, :m, :m + 2], beam_ends[k, :m], beam_factors[k, :m])
            history = (independent, w1_st[k + 1] - w1_st[k])
            beam_transfer(beam_params[k], tables, outboard, history, gravity, at_start, rot[k],
                          phi_star[k], wd[k], c1, c3, w3[k], w[k], w1e[i0:i1], w3e[i0:i1],
                          eta[i0:i1], eta_d[i0:i1], zs, eta_dd_star[i0:i1], u[jh + 1],
                          eta_map[i0:i1])
            continue
        for i in range(3):
            load[i] = body_params[k, 0] * gravity[i] + force[k, i]
        rigid_body_transfer(body_params[k], rot_star[k], lam[k], dwd[k], dw[k], wd[k], w[k],
                            z_star[jh + 1], load, torque[k], u[jh + 1])
        if independent:
            station_history_correction(body_params[k], rot[k], rot_star[k], lam[k], dwd[k],
                                       dw[k], wd[k], w[k], c1, w1_st[k], w1_st[k + 1], w1_c[k],
                                       z_star[jh + 1], u[jh + 1])
        if not at_start:
            _rotation_slots_to_acceleration(u[jh + 1], dwd[k], wd[k], phi_star[k], dwd[k], wd[k],
                                            phi_star[k])


@njit(cache=True, fastmath=CONTRACT)
def _solve(mode, tip_pinned, kind, u, known_loads, root_f, sc_split, sc_s, sc_p, sc_tinv, sc_t,
           sc_g, sc_gv, red_v, red_phi, red_s, red_p, red_tinv, red_t, red_aq, dir_z, dir_o, z):
    """Solve the assembled step into z (stations' states); returns 0 or a singularity code."""
    if mode == RICCATI_FULL:
        return riccati_full(kind, u, known_loads, root_f, tip_pinned, sc_split, sc_s, sc_p,
                            sc_tinv, sc_t, sc_g, sc_gv, z)
    if mode == DIRECT_FULL:
        return direct_full(kind, u, known_loads, root_f, tip_pinned, dir_z, dir_o, sc_gv, sc_g, z)
    n = red_v.shape[0]
    for k in range(n):
        fold_ball_body(u[2 * k + 1], red_v[k], red_phi[k])
    if mode == RICCATI_REDUCED:
        status = riccati_reduced(red_v, root_f[0:3], tip_pinned, red_s, red_p, red_tinv, red_t,
                                 red_aq)
    else:
        status = direct_reduced(red_v, root_f[0:3], tip_pinned, red_aq)
    if status != 0:
        return status
    z[:, :] = 0.0
    z[0, 0:3] = root_f[0:3]
    z[0, 3:6] = root_f[3:6]
    z[0, 9:12] = red_aq[0, 3:6]
    for k in range(n):
        for i in range(3):
            phi = red_phi[k, i, 6]
            for c in range(6):
                phi += red_phi[k, i, c] * red_aq[k, c]
            z[2 * k + 1, 3 + i] = phi
            z[2 * k + 2, 3 + i] = phi
        z[2 * k + 1, 0:3] = red_aq[k, 0:3]
        z[2 * k + 1, 9:12] = red_aq[k, 3:6]
        z[2 * k + 2, 0:3] = red_aq[k + 1, 0:3]
        z[2 * k + 2, 9:12] = red_aq[k + 1, 3:6]
    return 0


@njit(cache=True, fastmath=CONTRACT)
def initial_accelerations(mode, tip_pinned, body_params, hinge_kind, hinge_params, gravity,
                          g_acc, g_rot, g_w, g_wd, force, torque,
                          rot, omega, defl, defl_rate,
                          kind, u, known_loads, sc_split, sc_s, sc_p, sc_tinv, sc_t, sc_g, sc_gv,
                          red_v, red_phi, red_s, red_p, red_tinv, red_t, red_aq, dir_z, dir_o,
                          z, beams, eta, eta_d, eta_acc, eta_map):
    """The consistent start: one linear sweep at acceleration level.  The phi slot of every
    station holds the angular acceleration (w' = 1 * slot, w fixed, no rotation change), and an
    elastic hinge's loads are known from its state (its outboard motion is free); beams' modal
    accelerations come out in eta_acc.  Returns the status; z holds the stations' accelerations
    and loads."""
    n = body_params.shape[0]
    zero3 = np.zeros((n, 3))
    zero33 = np.zeros((n, 3, 3))
    unit33 = np.zeros((n, 3, 3))
    for k in range(n):
        unit33[k] = np.eye(3)
    z_star = np.zeros(z.shape)
    _build_elements(body_params, hinge_kind, hinge_params, gravity, kind, u,
                    g_rot, np.zeros((3, 3)), g_w, g_wd, np.eye(3), np.zeros(3), rot, zero33, zero3,
                    omega, zero3, zero33, unit33, 1.0, 0.0, zero3, zero3, z_star, force, torque,
                    True, rot, zero3, beams, (eta, eta_d, np.zeros_like(eta), np.zeros_like(eta),
                                              np.zeros_like(eta), eta_map),
                    (False, np.zeros((n + 1, 3)), zero3))
    for k in range(n):
        if hinge_kind[k] == ELASTIC:
            rot_in = g_rot if k == 0 else rot[k - 1]
            w_in = g_w if k == 0 else omega[k - 1]
            q, m_in, m_out = elastic_hinge_loads(hinge_params[k], rot_in, w_in, rot[k], omega[k],
                                                 defl[k], defl_rate[k])
            known_loads[2 * k, 0:3] = m_in
            known_loads[2 * k, 3:6] = q
            known_loads[2 * k, 6:9] = m_out
            known_loads[2 * k, 9:12] = q
    root_f = np.empty(6)
    root_f[0:3] = g_acc
    root_f[3:6] = g_wd
    status = _solve(mode, tip_pinned, kind, u, known_loads, root_f, sc_split, sc_s, sc_p, sc_tinv, sc_t,
                    sc_g, sc_gv, red_v, red_phi, red_s, red_p, red_tinv, red_t, red_aq, dir_z,
                    dir_o, z)
    _modal_accelerations(beams, eta_map, z, eta_acc)
    return status


@njit(cache=True, fastmath=CONTRACT)
def _modal_accelerations(beams, eta_map, z, eta_acc):
    """eta'' of every beam from its input station (angular-acceleration slots)."""
    body_kind, mode_off = beams[0], beams[3]
    zin = np.empty(13)
    zin[12] = 1.0
    for k in range(body_kind.shape[0]):
        if body_kind[k] == BEAM:
            zin[0:12] = z[2 * k + 1]
            for i in range(mode_off[k], mode_off[k + 1]):
                eta_acc[i] = eta_map[i] @ zin


@njit(cache=True, fastmath=CONTRACT)
def advance(mode, tip_pinned, h, coef, newton_max, newton_tol,
            body_params, hinge_kind, hinge_params, gravity, locked, lock_rel,
            g_acc, g_rot, g_w, g_wd, force, torque,
            rot, omega, omega_dot, pseudo,
            defl, defl_rate, defl_acc, defl_pseudo, z,
            kind, u, known_loads, sc_split, sc_s, sc_p, sc_tinv, sc_t, sc_g, sc_gv,
            red_v, red_phi, red_s, red_p, red_tinv, red_t, red_aq, dir_z, dir_o,
            record_every, rec_rot, rec_omega, rec_omega_dot, rec_z, rec_defl, rec_defl_rate,
            out_info, beams, eta, eta_d, eta_acc, eta_p, eta_map, rec_eta, rec_eta_d, histories):
    """Take g_acc.shape[0] steps.  Ground data per step s: g_acc[s], g_w[s], g_wd[s] at t_{s+1}
    and g_rot[s], g_rot[s + 1] at t_s, t_{s+1}; force/torque (steps, n, 3) at t_{s+1} (world).
    omega, omega_dot, pseudo: the rotation integrator's velocity, acceleration and
    pseudo-acceleration (world frame); eta, eta_d, eta_acc, eta_p: the same for the beams'
    modal coordinates (flat), with their coordinates themselves.
    histories = (independent, st_v, st_a, st_p, c_v, c_a, c_p, rec_st_v, rec_c_v): the paper's
    scheme (independent): the Newmark histories of the station points (ground point, then each
    body's output; (n + 1, 3)) and of the rigid bodies' mass centres ((n, 3)), and where their
    velocities are recorded (docs/solver.md, "The paper's scheme").
    Records after every record_every-th step (counting from the chunk's start).
    out_info: [status, failing step, newton iterations used (max), recorded count (also when
    the run fails), steps whose Newton iterations stopped above newton_tol (accumulated over
    chunks)]."""
    n = body_params.shape[0]
    n_steps = g_acc.shape[0]
    independent, st_v, st_a, st_p, c_v, c_a, c_p, rec_st_v, rec_c_v = histories
    w1_st = np.zeros((n + 1, 3))
    w1_c = np.zeros((n, 3))
    stations = (independent, w1_st, w1_c)
    c1, c3 = _integrator_coefficients(h, coef)
    phi_star = np.empty((n, 3))
    rot_star = np.empty((n, 3, 3))
    lam = np.empty((n, 3, 3))
    w = np.empty((n, 3))
    wd = np.empty((n, 3))
    dw = np.empty((n, 3, 3))
    dwd = np.empty((n, 3, 3))
    w1 = np.empty((n, 3))
    w3 = np.empty((n, 3))
    w1d = np.zeros((n, 3))
    w3d = np.zeros((n, 3))
    z_star = np.empty(z.shape)
    n_eta = eta.shape[0]
    w1e = np.zeros(n_eta)
    w3e = np.zeros(n_eta)
    eta_dd_star = np.zeros(n_eta)
    eta_dd_new = np.zeros(n_eta)
    modal = (eta, eta_d, w1e, w3e, eta_dd_star, eta_map)
    e3 = np.empty((3, 3))
    g_lam = np.empty((3, 3))
    g_dwd = c1 * np.eye(3)
    phi_g = np.empty(3)
    root_f = np.empty(6)
    max_iter = 0
    n_rec = 0
    g_inv = np.empty((3, 3))
    rot_prev = np.empty((3, 3))
    rel = np.empty((3, 3))
    for s in range(n_steps):
        rot_now = g_rot[s + 1]
        for i in range(3):
            for j in range(3):
                rel[i, j] = (rot_now[i, 0] * g_rot[s, j, 0] + rot_now[i, 1] * g_rot[s, j, 1]
                             + rot_now[i, 2] * g_rot[s, j, 2])
        log_so3(rel, phi_g)
        left_jacobian(phi_g, g_lam)
        for k in range(n):
            if locked[k]:
                phi_star[k] = phi_g
                rot_star[k] = rot_now @ lock_rel[k]
                lam[k] = g_lam
                w[k] = g_w[s]
                wd[k] = g_wd[s]
                dw[k] = c3 * np.eye(3)
                dwd[k] = g_dwd
                w1[k] = g_wd[s] - c1 * phi_g        # so that w' = c1 phi + w1, w = c3 phi + w3
                w3[k] = g_w[s] - c3 * phi_g         # hold the ground's values (beams use them)
            else:
                _offsets_into(h, coef, omega[k], omega_dot[k], pseudo[k], w1[k], w3[k],
                              phi_star[k])          # phi* by the constant-acceleration predictor
                _body_kinematics(c1, c3, rot[k], phi_star[k], w1[k], w3[k], rot_star[k],
                                 lam[k], w[k], wd[k], dw[k], dwd[k])
            if hinge_kind[k] == ELASTIC:
                a1, a3 = _offsets(h, coef, defl_rate[k], defl_acc[k], defl_pseudo[k])
                w1d[k] = a1 - c1 * defl[k]
                w3d[k] = a3 - c3 * defl[k]
        if n_eta > 0:
            a1, a3 = _offsets(h, coef, eta_d, eta_acc, eta_p)
            w1e[:] = a1 - c1 * eta
            w3e[:] = a3 - c3 * eta
            eta_dd_star[:] = c1 * (eta + h * eta_d + 0.5 * h * h * eta_p) + w1e
        if independent:
            for j in range(n + 1):
                w1_st[j], _ = _offsets(h, coef, st_v[j], st_a[j], st_p[j])
            for k in range(n):
                w1_c[k], _ = _offsets(h, coef, c_v[k], c_a[k], c_p[k])
        z_star[:, :] = z
        z_star[0, 3:6] = phi_g
        for k in range(n):
            z_star[2 * k + 1, 3:6] = phi_star[k]
            z_star[2 * k + 2, 3:6] = phi_star[k]
            if hinge_kind[k] == ELASTIC:
                # the spring force at the predicted deflection: an O(h^3) guess, where the last
                # step's force is only O(h) (the hinge's d x q is bilinear in two unknowns)
                d_pred = defl[k] + h * defl_rate[k] + 0.5 * h * h * defl_pseudo[k]
                rot_in = rot_now if k == 0 else rot_star[k - 1]
                # (the force does not depend on the angular velocities: any will do for them)
                q_pred, _, _ = elastic_hinge_loads(hinge_params[k], rot_in, g_w[s], rot_star[k],
                                                   g_w[s], d_pred, c3 * d_pred + w3d[k])
                z_star[2 * k, 9:12] = q_pred
                z_star[2 * k + 1, 9:12] = q_pred
        root_f[0:3] = g_acc[s]
        root_f[3:6] = g_wd[s]
        for it in range(newton_max + 1):
            _build_elements(body_params, hinge_kind, hinge_params, gravity, kind, u,
                            rot_now, g_lam, g_w[s], g_wd[s], g_dwd, phi_g, rot_star, lam,
                            phi_star, w, wd, dw, dwd, c1, c3, w1d, w3d, z_star, force[s],
                            torque[s], False, rot, w3, beams, modal, stations)
            if not _all_finite(u):
                report(out_info, NOT_FINITE, s, 0, n_rec)
                return
            status = _solve(mode, tip_pinned, kind, u, known_loads, root_f, sc_split, sc_s, sc_p, sc_tinv,
                            sc_t, sc_g, sc_gv, red_v, red_phi, red_s, red_p, red_tinv, red_t,
                            red_aq, dir_z, dir_o, z)
            if status != 0:
                report(out_info, SINGULAR, s, status, n_rec)
                return
            _modal_accelerations(beams, eta_map, z, eta_dd_new)
            # back from angular-acceleration to phi slots
            z[0, 3:6] = phi_g
            change = 0.0
            for i in range(n_eta):
                change = max(change, abs(eta_dd_new[i] - eta_dd_star[i]) / c1)
            for k in range(n):
                inv3(dwd[k], g_inv)
                dw0 = z[2 * k + 1, 3] - wd[k, 0]
                dw1 = z[2 * k + 1, 4] - wd[k, 1]
                dw2 = z[2 * k + 1, 5] - wd[k, 2]
                for i in range(3):
                    phi_i = phi_star[k, i] + g_inv[i, 0] * dw0 + g_inv[i, 1] * dw1 + \
                        g_inv[i, 2] * dw2
                    z[2 * k + 1, 3 + i] = phi_i
                    z[2 * k + 2, 3 + i] = phi_i
                    change = max(change, abs(phi_i - phi_star[k, i]))
            max_iter = max(max_iter, it)
            if it == newton_max or change <= newton_tol:
                break
            z_star[:, :] = z
            eta_dd_star[:] = eta_dd_new
            for k in range(n):
                if not locked[k]:
                    phi_star[k] = z[2 * k + 1, 3:6]
                    _body_kinematics(c1, c3, rot[k], phi_star[k], w1[k], w3[k],
                                     rot_star[k], lam[k], w[k], wd[k], dw[k], dwd[k])
        if newton_max > 0 and change > newton_tol:
            out_info[4] += 1
        # update the histories
        if independent:
            for k in range(n):
                # a_X = c1 dr_X + w1_X: each point's displacement over the step
                x_in = (z[2 * k + 1, 0:3] - w1_st[k]) / c1
                x_out = (z[2 * k + 2, 0:3] - w1_st[k + 1]) / c1
                if beams[0][k] != BEAM:
                    if locked[k]:
                        rot_new = rot_now @ lock_rel[k]
                    else:
                        expm_so3(z[2 * k + 1, 3:6], e3)
                        rot_new = e3 @ rot[k]
                    x_c = x_in + (rot_new - rot[k]) @ body_params[k, 1:4]
                    _advance_history(h, coef, x_c, c_v[k], c_a[k], c_p[k])
                _advance_history(h, coef, x_out, st_v[k + 1], st_a[k + 1], st_p[k + 1])
        finite = True
        for k in range(n):
            phi = z[2 * k + 1, 3:6]
            if locked[k]:
                matmul_into(rot_now, lock_rel[k], rot[k])
                omega[k] = g_w[s]
                omega_dot[k] = g_wd[s]
            else:
                _advance_history(h, coef, phi, omega[k], omega_dot[k], pseudo[k])
                expm_so3(phi, e3)
                rot_prev[:, :] = rot[k]
                matmul_into(e3, rot_prev, rot[k])
            if hinge_kind[k] == ELASTIC:
                d_new = (z[2 * k + 1, 0:3] - z[2 * k, 0:3] - w1d[k]) / c1
                x = d_new - defl[k]
                _advance_history(h, coef, x, defl_rate[k], defl_acc[k], defl_pseudo[k])
                defl[k] = d_new
            for i in range(3):
                if not (np.isfinite(omega[k, i]) and np.isfinite(omega_dot[k, i])):
                    finite = False
        if n_eta > 0:
            eta_new = (eta_dd_new - w1e) / c1
            _advance_history(h, coef, eta_new - eta, eta_d, eta_acc, eta_p)
            eta[:] = eta_new
            if not np.all(np.isfinite(eta_d)):
                finite = False
        if not finite:
            report(out_info, NOT_FINITE, s, 0, n_rec)
            return
        if (s + 1) % record_every == 0:
            rec_rot[n_rec] = rot
            rec_omega[n_rec] = omega
            rec_omega_dot[n_rec] = omega_dot
            rec_z[n_rec] = z
            rec_defl[n_rec] = defl
            rec_defl_rate[n_rec] = defl_rate
            rec_eta[n_rec] = eta
            rec_eta_d[n_rec] = eta_d
            if independent:
                rec_st_v[n_rec] = st_v
                rec_c_v[n_rec] = c_v
            n_rec += 1
    report(out_info, OK, n_steps, max_iter, n_rec)
