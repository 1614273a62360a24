"""The time loop of the energy-momentum scheme (docs/solver.md, "Energy-momentum scheme").

Each step solves the chain's nonlinear step equations (kernels/em_body.py) by Newton's method:
every body's transfer is linearized about the latest guess, the same sweeps as the Newmark loop
solve the linear chain, and the guess is updated until the rotation increments change by less
than newton_tol.  The converged step conserves the total energy and the angular momentum about
any axis the external loads have no moment about, for rigid chains with ball and fixed hinges
on a fixed ground.
"""
import numpy as np
from numba import njit

from . import CONTRACT
from ..elements.hinges import BALL
from .em_body import em_body_kinematics, rigid_body_transfer_em
from .step import NOT_FINITE, OK, SINGULAR, _solve
from .sweep import IDENTITY, TRANSFER
from .sweep import BALL as EL_BALL


@njit(cache=True, fastmath=CONTRACT)
def advance_em(mode, tip_pinned, h, newton_max, newton_tol, body_params, j_c, hinge_kind,
               gravity, force, torque, rot, omega, omega_dot, v_c, z,
               kind, u, known_loads, sc_split, sc_s, sc_p, sc_tinv, sc_t, sc_g, sc_gv,
               red_v, red_phi, red_s, red_p, red_tinv, red_t, red_aq, dir_z, dir_o,
               record_every, rec_rot, rec_omega, rec_omega_dot, rec_v_c, rec_z, out_info):
    """Take force.shape[0] steps; force, torque (steps, n, 3): the applied loads' step means.
    rot, omega, v_c: each body's rotation, world angular velocity and mass-centre velocity,
    omega_dot: (w_{n+1} - w_n) / h of the last step (the predictor's slope); z: the last step's
    station states [a, b, m, q] (see kernels/em_body.py), updated in place.
    out_info: [status, failing step, most Newton iterations used, recorded count, steps whose
    iterations stopped above newton_tol (accumulated)]."""
    n = body_params.shape[0]
    n_steps = force.shape[0]
    s_half = 0.5 * h * h
    z_star = np.empty(z.shape)
    root_f = np.zeros(6)                  # a fixed ground: no displacement, no rotation
    rot_new = np.empty((3, 3))
    omega_new = np.empty(3)
    max_iter = 0
    n_rec = 0
    for k in range(n):
        kind[2 * k] = EL_BALL if hinge_kind[k] == BALL else IDENTITY
        kind[2 * k + 1] = TRANSFER
    for s in range(n_steps):
        z_star[:, :] = z
        for k in range(n):
            # predictor: phi = h w_n + h^2 w'_n / 2, in b = 2 phi / h^2 units
            b = (2.0 / h) * omega[k] + omega_dot[k]
            z_star[2 * k + 1, 3:6] = b
            z_star[2 * k + 2, 3:6] = b
        change = 0.0
        for it in range(newton_max + 1):
            for k in range(n):
                load = body_params[k, 0] * gravity + force[s, k]
                rigid_body_transfer_em(body_params[k], j_c[k], rot[k], omega[k], v_c[k], h,
                                       z_star[2 * k + 1], load, torque[s, k], u[2 * k + 1])
            if not np.all(np.isfinite(u)):
                out_info[0] = NOT_FINITE
                out_info[1] = s
                return
            status = _solve(mode, tip_pinned, kind, u, known_loads, root_f, sc_split, sc_s, sc_p,
                            sc_tinv, sc_t, sc_g, sc_gv, red_v, red_phi, red_s, red_p, red_tinv,
                            red_t, red_aq, dir_z, dir_o, z)
            if status != 0:
                out_info[0] = SINGULAR
                out_info[1] = s
                out_info[2] = status
                return
            change = 0.0
            for k in range(n):
                for i in range(3):
                    change = max(change, s_half * abs(z[2 * k + 1, 3 + i]
                                                      - z_star[2 * k + 1, 3 + i]))
            max_iter = max(max_iter, it)
            if change <= newton_tol:
                break
            z_star[:, :] = z
        if change > newton_tol:
            out_info[4] += 1
        finite = True
        for k in range(n):
            zi = z[2 * k + 1]
            em_body_kinematics(rot[k], omega[k], zi[3:6], h, rot_new, omega_new)
            # v_C,n+1 = 2 dx_C / h - v_C,n,  dx_C = dx_I + A_{n+1} l_IC - A_n l_IC
            l_ic = body_params[k, 1:4]
            dx_c = s_half * zi[0:3] + rot_new @ l_ic - rot[k] @ l_ic
            v_c[k] = (2.0 / h) * dx_c - v_c[k]
            omega_dot[k] = (omega_new - omega[k]) / h
            omega[k] = omega_new
            rot[k] = rot_new
            for i in range(3):
                if not (np.isfinite(omega[k, i]) and np.isfinite(v_c[k, i])):
                    finite = False
        if not finite:
            out_info[0] = NOT_FINITE
            out_info[1] = s
            return
        if (s + 1) % record_every == 0:
            rec_rot[n_rec] = rot
            rec_omega[n_rec] = omega
            rec_omega_dot[n_rec] = omega_dot
            rec_v_c[n_rec] = v_c
            rec_z[n_rec] = z
            n_rec += 1
    out_info[0] = OK
    out_info[1] = n_steps
    out_info[2] = max_iter
    out_info[3] = n_rec
