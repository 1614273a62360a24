"""The time loop: predict, linearize every element, sweep, Newton-correct, update (docs/solver.md).

Integrator: generalized-alpha in the form of Arnold and Bruls (2007), applied to each body's
world rotation increment phi (A_i = exp(phi^) A_{i-1}), to each elastic hinge's deflection d and
to each beam's modal coordinates eta and to each joint coordinate q (revolute, universal,
prismatic; a child behind such a joint is not integrated on its own, its frame follows from its
parent's and q, docs/joints.md):
  x        = h v_n + h^2 (1/2 - beta) p_n + h^2 beta p_{n+1}     (x = phi, d - d_n, eta - eta_n)
  v_{n+1}  = v_n + h (1 - gamma) p_n + h gamma p_{n+1}
  (1 - alpha_f) acc_{n+1} + alpha_f acc_n = (1 - alpha_m) p_{n+1} + alpha_m p_n
with p the pseudo-acceleration.  alpha_m = alpha_f = 1/2, beta = 1/4, gamma = 1/2 (rho_inf = 1)
is the trapezoidal Newmark rule.  Station positions are not integrated: they follow from the
rotations by kinematics, and the transfers work with accelerations, so the joint constraints hold
exactly (no index-3 drift, no alternating mode; docs/solver.md, "stability").  The paper's
scheme, for comparison, gives station points their own position histories (GeneralLoop.histories;
docs/solver.md, "The paper's scheme").

This module is the general loop's pieces (kernels/stepping/loop.py: predict, iterate, adopt, update,
record, finish) for every chain and tree, sweep and the Newmark and paper's schemes, and the
consistent start.
"""
from collections import namedtuple

import numpy as np
from numba import njit

from .. import (CONTRACT, allocating_kernel, kernel, loop_piece, loop_tables, model_tables,
                state_tables, sweep_tables)
from ...elements import BEAM, RIGID, ROD
from ...elements.beam import MODES, TORSION_MODES
from ...elements.hinges import BALL, ELASTIC, FIXED
from ...elements.kinds import MAX_COORDINATES
from ..transfers.beam import beam_transfer, transfer_work_size
from ..transfers.body import rigid_body_transfer, station_history_correction
from ..transfers.strain_rod import rod_tables_of, rod_transfer
from ..assembly.closure import set_ground, solve_with_loops, tree_points
from ..assembly.loop_projection import project_onto_loops
from ..transfers.hinge import elastic_hinge_loads, elastic_hinge_transfer
from ..transfers.joint import joint_linearization, n_coordinates
from .generalized_alpha import (_advance_body, _advance_deflection, _advance_joint,
                                _advance_modal, _advance_stations, _body_kinematics,
                                _deflection_offsets, _ground_guess, _hinge_deflection,
                                _integrator_coefficients, _joint_adopt, _joint_guess,
                                _locked_frame, _locked_guess, _modal_guess, _offsets_into,
                                _spring_guess, _station_offsets, _stations_guess, _welded_frame,
                                _welded_guess)
from .loop import NOT_FINITE, OK, SINGULAR, UNSUPPORTED, loop_variant
from ..algebra.mat3 import dot, inv3, put1, put2, put3
from ..assembly.sweep import IDENTITY, LOCKED, TRANSFER
from ..assembly.solve import RICCATI_FULL, RICCATI_JOINTS, solve_step
from ..assembly.sweep import BALL as EL_BALL
from ..assembly.sweep import JOINT as EL_JOINT



@njit(cache=True, inline='always', fastmath=CONTRACT)
def has_coordinates(kind):
    return n_coordinates(kind) > 0


@kernel
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



@kernel
def _all_finite(a):
    for x in a.flat:
        if not np.isfinite(x):
            return False
    return True


# A body's kinematics at the step's end as functions of its world rotation increment phi, at
# the guess phi*: rotation, left Jacobian J_l(phi*), angular velocity and acceleration and their
# derivatives with respect to phi (docs/solver.md); (n, ...) arrays, one row per body.
Guess = namedtuple("Guess", ["phi", "rot", "lam", "w", "wd", "dw", "dwd"])

# The general loop's own scratch (allocated by the solver, kernels/stepping/step.py::general_loop):
GeneralLoop = namedtuple("GeneralLoop", [
    "guess",                        # Guess
    "w1", "w3",                     # (n, 3) w' = c1 phi + w1, w = c3 phi + w3
    "w1d", "w3d",                   # (n, 3) the same for the elastic hinges' deflections d
    "z_star",                       # (2n + 1, 12) the stations' guess (phi slots)
    "w1e", "w3e",                   # (total modes,) eta'' = c1 eta + w1e, eta' = c3 eta + w3e
    "eta_dd_star", "eta_dd_new",    # (total modes,) the modal accelerations' guess, solution
    "ground",                       # (rot, lam, w, wd, dwd, phi) of the ground over the step
    "root_f",                       # (6,) the ground station's [a, w']
    "e3", "g_inv", "rot_prev",      # 3 x 3 scratch
    "histories",                    # the paper's scheme: (independent, st_v, st_a, st_p, c_v,
                                    # c_a, c_p, w1_st, w1_c), see general_loop
    "joints",                       # (w1q, w3q, q*, q'*, q''*) (n, 3) each: the joint
                                    # coordinates' offsets and guess (kernels/transfers/joint.py)
    "loops",                        # the closing joints and their scratch
    #                                 (kernels/assembly/closure.py)
    "at_guess",                     # (eta, eta', d, d') at the guess, for the loops' rows:
                                    # (total modes,) twice, (n, 3) twice (_iterate)
    "forces",                       # (k,) int64: the compiled JointForces' C callbacks'
                                    # addresses (kernels/transfers/joint.py::drive_value)
])


def general_loop(n, n_eta, h, coef, histories, loops, forces):
    """The general loop's scratch for n bodies and n_eta modal coordinates.  histories: the
    paper's scheme's (independent, st_v, st_a, st_p, c_v, c_a, c_p) (run_tables._station_histories);
    the loop adds the w1 offsets of every station point and mass centre.  loops: the closing
    joints (kernels/assembly/closure.py::Loops; no rows without them).  forces: the compiled
    JointForces' callbacks' addresses (run_tables.compiled_forces)."""
    c1, _ = _coefficients_py(h, coef)
    guess = Guess(np.zeros((n, 3)), np.zeros((n, 3, 3)), np.zeros((n, 3, 3)), np.zeros((n, 3)),
                  np.zeros((n, 3)), np.zeros((n, 3, 3)), np.zeros((n, 3, 3)))
    ground = (np.eye(3), np.zeros((3, 3)), np.zeros(3), np.zeros(3), c1 * np.eye(3), np.zeros(3))
    return GeneralLoop(guess, np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)),
                       np.zeros((n, 3)), np.zeros((2 * n + 1, 12)), np.zeros(n_eta),
                       np.zeros(n_eta), np.zeros(n_eta), np.zeros(n_eta), ground, np.zeros(6),
                       np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3)),
                       tuple(histories) + (np.zeros((n + 1, 3)), np.zeros((n, 3))),
                       tuple(np.zeros((n, MAX_COORDINATES)) for _ in range(5)), loops,
                       (np.zeros(n_eta), np.zeros(n_eta), np.zeros((n, 3)), np.zeros((n, 3))),
                       forces)


def _coefficients_py(h, coef):
    beta, gamma, alpha_m, alpha_f = coef
    return (1.0 - alpha_m) / ((1.0 - alpha_f) * beta * h * h), gamma / (beta * h)


def fused_coefficients(h, coef):
    """(4,) the fused loops' step constants c1, c3, 1 / c1, c3 / c1 (w' = c1 phi + w1,
    w = c3 phi + w3) for a step h: their loop's `coefficients`, set again by an adaptive run's
    segments (run_records._set_step)."""
    c1, c3 = _coefficients_py(h, coef)
    return np.array([c1, c3, 1.0 / c1, c3 / c1])


@allocating_kernel
def _build_elements(params, sweep, guess, ground, c1, c3, w1d, w3d, z_star, force, torque,
                    line_load, at_start, rot, w3, modal, stations, joints):
    """Element kinds and transfers about the guess z_star (phi slots), written in angular
    acceleration slots; returns 0, or j + 1 for an element j (2k: hinge k, 2k + 1: body k) of a
    kind this loop does not know.  at_start: the consistent-start solve, where the phi slots
    already hold angular accelerations and elastic hinges are LOCKED (their loads are set by the
    caller).  guess: each body's kinematics at the guess; ground: (rot, lam, w, wd, dwd, phi) of
    the ground.  rot, w3: the bodies' rotations at the step's start and the integrator's offsets
    (beams).  modal = (eta, eta_d, w1e, w3e, eta_dd_star, eta_map), flat over the beams' modal
    coordinates.  A body welded to a beam's output (fixed hinge) takes its rotation from the
    beam's end section (kernels/transfers/beam.py).  stations = (independent, w1_st, w1_c): in the
    paper's scheme (independent) every station point (w1_st, n + 1 of them: the ground point,
    then each body's output) and every rigid body's mass centre (w1_c) has its own Newmark
    history, a_X = c1 dr_X + w1_X (docs/solver.md, "The paper's scheme").  joints =
    (full_tree, q, q', q'', given, forces): in the full-state tree sweep (RICCATI_JOINTS) ball
    joints and joints with coordinates are JOINT elements (kernels/transfers/joint.py), linearized
    about the coordinates' guess; given (n, 3): each JointForce drive's value over the step (a
    compiled one's: the time it is called at), forces: the compiled JointForces' callbacks'
    addresses."""
    kind = sweep_tables.kind(sweep)
    u = sweep_tables.u(sweep)
    joint_dof = sweep_tables.joint_dof(sweep)
    joint_tau_nu = sweep_tables.joint_tau_nu(sweep)
    independent, w1_st, w1_c = stations
    full_tree, q_j, qd_j, qdd_j, given, forces = joints
    independent = independent and not at_start
    body_params, hinge_kind = model_tables.body_params(params), model_tables.hinge_kind(params)
    hinge_params = model_tables.hinge_params(params)
    parent, gravity = model_tables.parent(params), model_tables.gravity(params)
    hinge_row, body_row = model_tables.hinge_row(params), model_tables.body_row(params)
    joint_drive = model_tables.joint_drive(params)
    body_kind = model_tables.body_kind(params)
    beam_params = model_tables.beam_params(params)
    beam_moments = model_tables.beam_moments(params)
    mode_off = model_tables.mode_offset(params)
    beam_ends = model_tables.beam_ends(params)
    beam_factors = model_tables.beam_factors(params)
    eta, eta_d, w1e, w3e, eta_dd_star, eta_map = modal
    phi_star, rot_star, lam, w, wd, dw, dwd = guess
    n = hinge_kind.shape[0]
    load, w1_out, dw1 = np.empty(3), np.empty(3), np.empty(3)
    most_modes = 0
    for k in range(n):
        most_modes = max(most_modes, mode_off[k + 1] - mode_off[k])
    beam_work = np.empty(transfer_work_size(most_modes))    # (one block for every beam)
    for k in range(n):
        jh = 2 * k
        hk = hinge_kind[k]
        p = parent[k]
        hr, row = hinge_row[k], body_row[k]   # (their rows of the shared tables)
        if full_tree and (hk == BALL or has_coordinates(hk)):
            kind[jh] = EL_JOINT
            if p < 0:
                rot_p, w_p, wd_p = ground[0], ground[2], ground[3]
            else:
                rot_p, w_p, wd_p = rot_star[p], w[p], wd[p]
            drive = joint_drive[k if has_coordinates(hk) else 0]   # (a ball joint's:
            # unread, and the table has one row of none without joints with coordinates)
            joint_linearization(hk, hinge_params[hr], drive, given[k], rot_p,
                                w_p, wd_p, q_j[k], qd_j[k], qdd_j[k], c1, c3, at_start, u[jh],
                                joint_dof[k], joint_tau_nu[k], forces)
        elif hk == BALL:
            kind[jh] = EL_BALL
        elif hk == FIXED:
            kind[jh] = IDENTITY
        elif hk == ELASTIC and at_start:
            kind[jh] = LOCKED
        elif hk == ELASTIC:
            kind[jh] = TRANSFER
            if p < 0:
                rot_in, lam_in, w_in, wd_in, dwd_in, phi_in = ground
                dw_in = dwd_in
            else:
                rot_in, lam_in, w_in, wd_in, dw_in, dwd_in, phi_in = (
                    rot_star[p], lam[p], w[p], wd[p], dw[p], dwd[p], phi_star[p])
            if p == k - 1:
                z_in = z_star[jh]           # the hinge's inboard station: 2k in a chain
            else:                           # in a tree the parent's output station holds the
                z_in = z_star[jh + 1].copy()    # loads of all its children: the hinge's own q
                put1(z_in[3:6], phi_in)         # is its outboard's (a massless hinge passes it)
            elastic_hinge_transfer(hinge_params[hr], rot_in, lam_in, w_in, dw_in, rot_star[k],
                                   lam[k], w[k], dw[k], phi_star[k], c1, c3, w1d[k], w3d[k],
                                   z_in, u[jh])
            _rotation_slots_to_acceleration(u[jh], dwd_in, wd_in, phi_in, dwd[k], wd[k],
                                            phi_star[k])
        else:           # (an unknown kind: the builder's mistake, named by the caller)
            return jh + 1
        kind[jh + 1] = TRANSFER
        if body_kind[k] == BEAM:
            i0, i1 = mode_off[k], mode_off[k + 1]
            m = int(beam_params[k, MODES])
            mt = int(beam_params[k, TORSION_MODES])     # then the twist, then the stretch
            welded = k + 1 < n and hinge_kind[k + 1] == FIXED and parent[k + 1] == k
            kout = k + 1 if welded else k
            for i in range(3):
                w1_out[i] = wd[kout, i] - c1 * phi_star[kout, i]
                dw1[i] = w1_st[k + 1, i] - w1_st[k, i]
            outboard = (welded, hinge_params[hinge_row[kout], 0:9].reshape((3, 3)),
                        rot[kout], w1_out)
            tables = (beam_moments[k, :m, :4 * m + 2], beam_ends[k, :m], beam_factors[k, :m],
                      force[k], torque[k], line_load[k],    # (the loads: docs/beam.md)
                      beam_ends[k, m:m + mt],               # the twist and stretch tables
                      beam_ends[k, m + mt:i1 - i0 - m])     # (run_tables.beam_tables)
            history = (independent, dw1)
            beam_transfer(beam_params[k], tables, outboard, history, gravity, at_start,
                          rot[k], phi_star[k], wd[k], c1, c3, w3[k], w[k], w1e[i0:i1],
                          w3e[i0:i1], eta[i0:i1], eta_d[i0:i1], z_star[jh + 1],
                          eta_dd_star[i0:i1], u[jh + 1], eta_map[i0:i1], beam_work)
        elif body_kind[k] == ROD:
            # a strain rod (kernels/transfers/strain_rod.py; docs/strain_rod.md, "Its
            # transfer"): the beam's contract, its strain rows solved inside the element
            i0, i1 = mode_off[k], mode_off[k + 1]
            welded = k + 1 < n and hinge_kind[k + 1] == FIXED and parent[k + 1] == k
            kout = k + 1 if welded else k
            for i in range(3):
                w1_out[i] = wd[kout, i] - c1 * phi_star[kout, i]
            outboard = (welded, hinge_params[hinge_row[kout], 0:9].reshape((3, 3)),
                        rot[kout], w1_out)
            rod_transfer(rod_tables_of(params, k), outboard, gravity, at_start, rot[k],
                         phi_star[k], wd[k], c1, c3, w3[k], w[k], w1e[i0:i1], w3e[i0:i1],
                         eta[i0:i1], eta_d[i0:i1], z_star[jh + 1], eta_dd_star[i0:i1],
                         u[jh + 1], eta_map[i0:i1])
        elif body_kind[k] == RIGID:
            for i in range(3):
                load[i] = body_params[row, 0] * gravity[i] + force[k, i]
            rigid_body_transfer(body_params[row], rot_star[k], lam[k], dwd[k], dw[k], wd[k],
                                w[k], z_star[jh + 1], load, torque[k], u[jh + 1])
            if independent:
                station_history_correction(body_params[row], rot[k], rot_star[k], lam[k], dwd[k],
                                           dw[k], wd[k], w[k], c1, w1_st[k], w1_st[k + 1],
                                           w1_c[k], z_star[jh + 1], u[jh + 1])
            if not at_start:
                _rotation_slots_to_acceleration(u[jh + 1], dwd[k], wd[k], phi_star[k], dwd[k],
                                                wd[k], phi_star[k])
        else:
            return jh + 2
    return 0




@allocating_kernel
def initial_accelerations(params, settings, state, sweep, ground, force, torque, line_load,
                          joint_input, loops, forces):
    """The consistent start: one linear sweep at acceleration level.  The phi slot of every
    station holds the angular acceleration (w' = 1 * slot, w fixed, no rotation change), and an
    elastic hinge's loads are known from its state (its outboard motion is free); beams' modal
    accelerations come out in state.eta_acc.  ground: (a, R, w, w') of the ground at t = 0;
    force, torque, line_load (n, 3) at t = 0; joint_input (n, 3, 3) the joint coordinates'
    inputs at t = 0 (kernels/stepping/loop.py::Inputs), their accelerations come out in state.jqdd.
    loops: the closing joints (kernels/assembly/closure.py), held at acceleration level.  forces:
    the compiled JointForces' callbacks' addresses (kernels/transfers/joint.py::drive_value).
    Returns the status: 0, a singularity code (sweep.py), or
    -(j + 1) for an element j of a kind this loop does not know; state.z holds the stations'
    accelerations and loads."""
    all_bodies = loop_tables.all_bodies(loops)
    kind = loop_tables.kind(loops)
    eta = state_tables.eta(state)
    known_loads = sweep_tables.known_loads(sweep)
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    eta_d = state_tables.eta_d(state)
    eta_map = state_tables.eta_map(state)
    z = state_tables.z(state)
    eta_acc = state_tables.eta_acc(state)
    jq = state_tables.jq(state)
    jqd = state_tables.jqd(state)
    defl = state_tables.defl(state)
    defl_rate = state_tables.defl_rate(state)
    jqdd = state_tables.jqdd(state)
    joint_nu = sweep_tables.joint_nu(sweep)
    jqp = state_tables.jqp(state)
    jtau = state_tables.jtau(state)
    joint_tau = sweep_tables.joint_tau(sweep)
    g_acc, g_rot, g_w, g_wd = ground
    hinge_kind, hinge_params = model_tables.hinge_kind(params), model_tables.hinge_params(params)
    hinge_row, parent = model_tables.hinge_row(params), model_tables.parent(params)
    n = hinge_kind.shape[0]
    zero3 = np.zeros((n, 3))
    unit33 = np.zeros((n, 3, 3))
    for k in range(n):
        for i in range(3):
            unit33[k, i, i] = 1.0
    guess = Guess(zero3, rot, np.zeros((n, 3, 3)), omega, zero3, np.zeros((n, 3, 3)), unit33)
    g = (g_rot, np.zeros((3, 3)), g_w, g_wd, np.eye(3), np.zeros(3))
    modal = (eta, eta_d, np.zeros_like(eta), np.zeros_like(eta), np.zeros_like(eta),
             eta_map)
    unknown = _build_elements(params, sweep, guess, g, 1.0, 0.0, zero3, zero3,
                              np.zeros(z.shape), force, torque, line_load, n >= 0, rot,
                              zero3, modal,
                              (n < 0, np.zeros((n + 1, 3)), zero3),     # (False)
                              (settings.mode == RICCATI_JOINTS, jq, jqd,
                               joint_input[:, :, 2].copy(), joint_input[:, :, 0], forces))
    # (given: a strided view, as the step's inputs.joint_input[s, :, :, 0], and at_start and
    # the stations' flag run-time bools (n >= 0, n < 0), as the step's: numba compiles a
    # function once per layout and per literal True or False it is passed, and _build_elements
    # with its callees took 10-60 s cold a second time)
    if unknown != 0:
        return -unknown
    for k in range(n):
        if hinge_kind[k] == ELASTIC:
            p = parent[k]
            rot_in = g_rot if p < 0 else rot[p]
            w_in = g_w if p < 0 else omega[p]
            q, m_in, m_out = elastic_hinge_loads(hinge_params[hinge_row[k]], rot_in,
                                                 w_in, rot[k], omega[k], defl[k],
                                                 defl_rate[k])
            put1(known_loads[2 * k, 0:3], m_in)
            put1(known_loads[2 * k, 3:6], q)
            put1(known_loads[2 * k, 6:9], m_out)
            put1(known_loads[2 * k, 9:12], q)
    root_f = np.empty(6)
    put1(root_f[0:3], g_acc)
    put1(root_f[3:6], g_wd)
    if kind.shape[0] > 0:
        tree_points(params, rot, omega, jq, jqd, eta, eta_d,
                    defl, defl_rate, loops, all_bodies)
        status = solve_with_loops(params, sweep, root_f, loops, rot, omega, z)
    else:
        status = solve_step(settings.mode, model_tables.tip_pinned(params), parent, sweep,
                            root_f, z)
    _modal_accelerations(params, eta_map, z, eta_acc)
    for k in range(n):
        for i in range(n_coordinates(hinge_kind[k])):
            jqdd[k, i] = joint_nu[k, i]
            jqp[k, i] = joint_nu[k, i]
            jtau[k, i] = joint_tau[k, i]
    return status


@allocating_kernel
def _modal_accelerations(params, eta_map, z, eta_acc):
    """eta'' of every beam (a strain rod's q'') from its input station (angular-acceleration
    slots)."""
    body_kind, mode_off = model_tables.body_kind(params), model_tables.mode_offset(params)
    zin = np.empty(13)
    zin[12] = 1.0
    for k in range(body_kind.shape[0]):
        if body_kind[k] == BEAM or body_kind[k] == ROD:
            put1(zin[0:12], z[2 * k + 1])
            for i in range(mode_off[k], mode_off[k + 1]):
                eta_acc[i] = dot(eta_map[i], zin)


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _welded(hinge_kind, parent, locked, body_kind, mode, k):
    """In the full-state tree sweep, a body welded to another (a fixed hinge; not to the ground)
    is not integrated on its own: its frame is its parent's (R0), or the end section's of a
    parent beam (run_tables.kernel_model's end section: the parent frame of a joint with
    coordinates or an elastic hinge there); in a chain's full-state sweep, likewise a body
    welded to a beam's end (rotating beam no. 2's arm, or the next element of a welded chain:
    integrated on its own, its angular acceleration alternated from step to step and grew
    away at rho_inf = 1).
    Integrated on its own, a body whose parent's rotation is set at position level (a joint
    child, a beam's end) would drift from it, and differencing a rotation held at position level
    with the trapezoidal rule's relations leaves a step-to-step mode in the acceleration that
    grows without bound (docs/joints.md, "Beams")."""
    if hinge_kind[k] != FIXED or parent[k] < 0 or locked[k]:
        return False
    if mode == RICCATI_JOINTS:
        return True
    # in a chain's full-state sweep, a body on a beam's or a strain rod's end (as the fused
    # welded-chain loop's beams, kernels/stepping/weld_chain.py::_follow_welds)
    kind_p = body_kind[parent[k]]
    return mode == RICCATI_FULL and (kind_p == BEAM or kind_p == ROD)


@loop_piece
def _predict(loop, run, s, _):
    """The general loop's guess for step s: every body's phi* by the constant-acceleration
    predictor (a locked body's from the ground's motion), the integrator's offsets of every
    rotation, deflection, modal coordinate (and, in the paper's scheme, station point), and the
    stations' guess z_star.  Ground data per step s: g_acc[s], g_w[s], g_wd[s] at t_{s+1} and
    g_rot[s], g_rot[s + 1] at t_s, t_{s+1}.  The array work is in called kernels, not written
    here: each statement on arrays in a piece is compiled into the skeleton's own code
    (docs/solver.md, "Compile time"); and every field is read first, in the piece's first
    block (item 6 there)."""
    params, state, inputs, settings = run.params, run.state, run.inputs, run.settings
    rot_ = state_tables.rot(state)
    omega_ = state_tables.omega(state)
    omega_dot_ = state_tables.omega_dot(state)
    pseudo_ = state_tables.pseudo(state)
    z_ = state_tables.z(state)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    eta_acc = state_tables.eta_acc(state)
    eta_p = state_tables.eta_p(state)
    defl_ = state_tables.defl(state)
    defl_rate_ = state_tables.defl_rate(state)
    defl_acc_ = state_tables.defl_acc(state)
    defl_pseudo_ = state_tables.defl_pseudo(state)
    jq = state_tables.jq(state)
    jqd = state_tables.jqd(state)
    jqdd = state_tables.jqdd(state)
    jqp = state_tables.jqp(state)
    guess, ground, w1, w3, w1d, w3d = (loop.guess, loop.ground, loop.w1, loop.w3, loop.w1d,
                                       loop.w3d)
    w1e, w3e, eta_dd_star, z_star, root_f = (loop.w1e, loop.w3e, loop.eta_dd_star, loop.z_star,
                                             loop.root_f)
    histories, (w1q, w3q, q_s, qd_s, qdd_s) = loop.histories, loop.joints
    h, coef, mode = settings.h, settings.coef, settings.mode
    hinge_kind = model_tables.hinge_kind(params)
    hinge_params = model_tables.hinge_params(params)
    hinge_row = model_tables.hinge_row(params)
    parent = model_tables.parent(params)
    locked = model_tables.locked(params)
    lock_rel = model_tables.lock_rel(params)
    joint_drive = model_tables.joint_drive(params)
    body_kind = model_tables.body_kind(params)
    rot, omega, omega_dot, pseudo, z = (rot_, omega_, omega_dot_, pseudo_,
                                        z_)
    defl, defl_rate, defl_acc, defl_pseudo = (defl_, defl_rate_, defl_acc_,
                                              defl_pseudo_)
    rot_before, rot_now = inputs.g_rot[s], inputs.g_rot[s + 1]
    g_w, g_wd = inputs.g_w[s], inputs.g_wd[s]
    g_acc, joint_input = inputs.g_acc[s], inputs.joint_input[s]
    c1, c3 = _integrator_coefficients(h, coef)
    phi_star, rot_star, lam, w, wd, dw, dwd = guess
    n = hinge_kind.shape[0]
    _ground_guess(rot_before, rot_now, g_w, g_wd, ground)
    if eta.shape[0] > 0:
        _modal_guess(h, coef, c1, c3, eta, eta_d, eta_acc, eta_p, w1e, w3e, eta_dd_star)
    for k in range(n):
        hk = hinge_kind[k]
        if has_coordinates(hk):
            p = parent[k]
            frame = ((rot_now, g_w, g_wd) if p < 0 else (rot_star[p], w[p], wd[p]))
            _joint_guess(hk, hinge_params[hinge_row[k]], joint_drive[k], joint_input[k], h,
                         coef, c1, c3, jq[k], jqd[k], jqdd[k], jqp[k], w1q[k], w3q[k], q_s[k],
                         qd_s[k], qdd_s[k], frame, rot[k], phi_star[k], w1[k], w3[k],
                         rot_star[k], lam[k], w[k], wd[k], dw[k], dwd[k])
        elif _welded(hinge_kind, parent, locked, body_kind, mode, k):
            _welded_guess(params, k, c1, c3, w1e, w3e, eta, eta_dd_star, rot[k], guess, w1[k],
                          w3[k])
        elif locked[k]:
            _locked_guess(lock_rel[k], ground, c1, c3, phi_star[k], rot_star[k], lam[k], w[k],
                          wd[k], dw[k], dwd[k], w1[k], w3[k])
        else:
            _offsets_into(h, coef, omega[k], omega_dot[k], pseudo[k], w1[k], w3[k],
                          phi_star[k])   # phi* by the predictor
            _body_kinematics(c1, c3, rot[k], phi_star[k], w1[k], w3[k], rot_star[k], lam[k],
                             w[k], wd[k], dw[k], dwd[k])
        if hk == ELASTIC:
            _deflection_offsets(h, coef, c1, c3, defl[k], defl_rate[k], defl_acc[k],
                                defl_pseudo[k], w1d[k], w3d[k])
    if histories[0]:
        _station_offsets(h, coef, histories)
    _stations_guess(z, ground[5], phi_star, z_star)
    for k in range(n):
        if hinge_kind[k] == ELASTIC:
            p = parent[k]
            _spring_guess(hinge_params[hinge_row[k]], rot_now if p < 0 else rot_star[p],
                          rot_star[k], g_w, defl[k], defl_rate[k], defl_pseudo[k], h, c3,
                          w3d[k], p == k - 1, z_star[2 * k], z_star[2 * k + 1])
    for i in range(3):
        root_f[i] = g_acc[i]
        root_f[3 + i] = g_wd[i]


@loop_piece
def _iterate(loop, run, s, it):
    """Linearize every element about the guess, sweep, and recover every body's phi and the
    beams' modal accelerations; returns (status, detail, change): change is the largest update
    of a phi (rad) or of a modal coordinate (eta'' / c1).  Every field is read first, as in
    _predict."""
    params, settings, state, sweep, inputs = (run.params, run.settings, run.state, run.sweep,
                                              run.inputs)
    z = state_tables.z(state)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    eta_map = state_tables.eta_map(state)
    rot = state_tables.rot(state)
    u = sweep_tables.u(sweep)
    joint_nu = sweep_tables.joint_nu(sweep)
    guess, ground, w1d, w3d, z_star, w3 = (loop.guess, loop.ground, loop.w1d, loop.w3d,
                                           loop.z_star, loop.w3)
    w1e, w3e, eta_dd_star, eta_dd_new = loop.w1e, loop.w3e, loop.eta_dd_star, loop.eta_dd_new
    root_f, g_inv, histories, joints_, forces = (loop.root_f, loop.g_inv, loop.histories,
                                                 loop.joints, loop.forces)
    loops, at_guess = loop.loops, loop.at_guess
    step_coef = loop_tables.step_coef(loops)
    target_ = loop_tables.target(loops)
    all_bodies = loop_tables.all_bodies(loops)
    kind = loop_tables.kind(loops)
    hinge_kind = model_tables.hinge_kind(params)
    tip_pinned = model_tables.tip_pinned(params)
    parent = model_tables.parent(params)
    h, coef, mode = settings.h, settings.coef, settings.mode
    force, torque, line_load, joint_input = (inputs.force[s], inputs.torque[s],
                                             inputs.line_load[s], inputs.joint_input[s, :, :, 0])
    # (at t_{s+1}: the ground's and the closing joints' targets, for the loops)
    target, g_pos, g_vel = inputs.closure_target[s], inputs.g_pos[s], inputs.g_vel[s]
    g_acc, rot_now, g_w, g_wd = (inputs.g_acc[s], inputs.g_rot[s + 1], inputs.g_w[s],
                                 inputs.g_wd[s])
    if settings.start:      # the consistent start (Settings.start): one pass, at t
        start = initial_accelerations(params, settings, state, sweep, (g_acc, rot_now, g_w, g_wd),
                                      force, torque, line_load, inputs.joint_input[s], loops,
                                      forces)
        return (OK, 0, 0.0) if start == 0 else (SINGULAR, start, 0.0)
    c1, c3 = _integrator_coefficients(h, coef)
    phi_star, wd, dwd = guess.phi, guess.wd, guess.dwd
    modal = (eta, eta_d, w1e, w3e, eta_dd_star, eta_map)
    stations = (histories[0], histories[7], histories[8])
    joints = (mode == RICCATI_JOINTS, joints_[2], joints_[3], joints_[4], joint_input, forces)
    unknown = _build_elements(params, sweep, guess, ground, c1, c3, w1d, w3d, z_star, force,
                              torque, line_load, settings.start,     # (False)
                              rot, w3, modal, stations, joints)
    if unknown != 0:
        return UNSUPPORTED, unknown, 0.0
    if not _all_finite(u):
        return NOT_FINITE, 0, 0.0
    if kind.shape[0] > 0:  # closing joints: held at acceleration level
        put2(target_, target)
        set_ground(loops, g_pos, g_vel, g_acc, rot_now, g_w, g_wd)
        step_coef[0] = 1.0 / c1           # a spring's q and q' per unit row acceleration
        step_coef[1] = c3 / c1
        # the rows' velocity terms and the multipliers' arms at the guess (the beams' modal
        # coordinates at theirs: eta = (eta''* - w1e) / c1, eta' = c3 eta + w3e; the elastic
        # hinges' deflections likewise from their stations' guess, as _update)
        eta_g, eta_d_g, defl_g, defl_rate_g = at_guess
        for i in range(eta_g.shape[0]):
            eta_g[i] = (eta_dd_star[i] - w1e[i]) / c1
            eta_d_g[i] = c3 * eta_g[i] + w3e[i]
        for k in range(defl_g.shape[0]):
            if hinge_kind[k] == ELASTIC:
                d = _hinge_deflection(params, z_star, w1d, c1, k)
                for i in range(3):
                    defl_g[k, i] = d[i]
                    defl_rate_g[k, i] = c3 * d[i] + w3d[k, i]
        tree_points(params, guess.rot, guess.w, joints_[2], joints_[3], eta_g,
                    eta_d_g, defl_g, defl_rate_g, loops, all_bodies)
        status = solve_with_loops(params, sweep, root_f, loops, guess.rot,
                                  guess.w, z)
    else:
        status = solve_step(mode, tip_pinned, parent, sweep, root_f, z)
    if status != 0:
        return SINGULAR, status, 0.0
    _modal_accelerations(params, eta_map, z, eta_dd_new)
    # back from angular-acceleration to phi slots
    for i in range(3):
        z[0, 3 + i] = ground[5][i]
    change = 0.0
    for i in range(eta_dd_new.shape[0]):
        change = max(change, abs(eta_dd_new[i] - eta_dd_star[i]) / c1)
    qdd_s = joints_[4]
    for k in range(hinge_kind.shape[0]):
        for i in range(n_coordinates(hinge_kind[k])):
            change = max(change, abs(joint_nu[k, i] - qdd_s[k, i]) / c1)
    for k in range(hinge_kind.shape[0]):
        inv3(dwd[k], g_inv)
        dw0 = z[2 * k + 1, 3] - wd[k, 0]
        dw1 = z[2 * k + 1, 4] - wd[k, 1]
        dw2 = z[2 * k + 1, 5] - wd[k, 2]
        for i in range(3):
            phi_i = phi_star[k, i] + g_inv[i, 0] * dw0 + g_inv[i, 1] * dw1 + g_inv[i, 2] * dw2
            z[2 * k + 1, 3 + i] = phi_i
            z[2 * k + 2, 3 + i] = phi_i
            change = max(change, abs(phi_i - phi_star[k, i]))
    return OK, 0, change


@loop_piece
def _adopt(loop, run, s, it):
    """The latest solution becomes the guess: phi*, the bodies' kinematics, eta''* (every field
    read first, as in _predict)."""
    joint_nu = sweep_tables.joint_nu(run.sweep)
    params, state, inputs, settings = run.params, run.state, run.inputs, run.settings
    z = state_tables.z(state)
    rot = state_tables.rot(state)
    jq = state_tables.jq(state)
    eta = state_tables.eta(state)
    guess, w1, w3, w1e, w3e = loop.guess, loop.w1, loop.w3, loop.w1e, loop.w3e
    z_star, eta_dd_star, eta_dd_new = loop.z_star, loop.eta_dd_star, loop.eta_dd_new
    w1q, w3q, q_s, qd_s, qdd_s = loop.joints
    mode = settings.mode
    hinge_kind = model_tables.hinge_kind(params)
    hinge_params = model_tables.hinge_params(params)
    hinge_row = model_tables.hinge_row(params)
    parent = model_tables.parent(params)
    locked = model_tables.locked(params)
    joint_drive = model_tables.joint_drive(params)
    body_kind = model_tables.body_kind(params)
    rot_now, g_w, g_wd = inputs.g_rot[s + 1], inputs.g_w[s], inputs.g_wd[s]
    c1, c3 = _integrator_coefficients(settings.h, settings.coef)
    phi_star, rot_star, lam, w, wd, dw, dwd = guess
    put2(z_star, z)
    put1(eta_dd_star, eta_dd_new)
    for k in range(phi_star.shape[0]):
        hk = hinge_kind[k]
        if has_coordinates(hk):
            p = parent[k]
            frame = ((rot_now, g_w, g_wd) if p < 0 else (rot_star[p], w[p], wd[p]))
            _joint_adopt(hk, hinge_params[hinge_row[k]], joint_drive[k], c1, c3, jq[k], w1q[k],
                         w3q[k], joint_nu[k], q_s[k], qd_s[k], qdd_s[k], frame, rot[k],
                         phi_star[k], w1[k], w3[k], rot_star[k], lam[k], w[k], wd[k], dw[k],
                         dwd[k], z_star[2 * k + 1], z_star[2 * k + 2])
        elif _welded(hinge_kind, parent, locked, body_kind, mode, k):
            _welded_guess(params, k, c1, c3, w1e, w3e, eta, eta_dd_star, rot[k], guess, w1[k],
                          w3[k])
            for i in range(3):
                z_star[2 * k + 1, 3 + i] = phi_star[k, i]
                z_star[2 * k + 2, 3 + i] = phi_star[k, i]
        elif not locked[k]:
            for i in range(3):
                phi_star[k, i] = z[2 * k + 1, 3 + i]
            _body_kinematics(c1, c3, rot[k], phi_star[k], w1[k], w3[k], rot_star[k], lam[k],
                             w[k], wd[k], dw[k], dwd[k])


@loop_piece
def _update(loop, run, s, _):
    """Advance the histories over step s from the solution in state.z: rotations (a locked
    body's from the ground's), elastic deflections, modal coordinates, and in the paper's scheme
    every station point and mass centre; returns whether every rate is finite (every field read
    first, as in _predict)."""
    params, state, inputs, settings, sweep = (run.params, run.state, run.inputs, run.settings,
                                              run.sweep)
    joint_nu = sweep_tables.joint_nu(sweep)
    joint_tau = sweep_tables.joint_tau(sweep)
    rot_ = state_tables.rot(state)
    omega_ = state_tables.omega(state)
    omega_dot_ = state_tables.omega_dot(state)
    pseudo_ = state_tables.pseudo(state)
    z_ = state_tables.z(state)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    eta_acc = state_tables.eta_acc(state)
    eta_p = state_tables.eta_p(state)
    defl_ = state_tables.defl(state)
    defl_rate_ = state_tables.defl_rate(state)
    defl_acc_ = state_tables.defl_acc(state)
    defl_pseudo_ = state_tables.defl_pseudo(state)
    jq = state_tables.jq(state)
    jqd = state_tables.jqd(state)
    jqdd = state_tables.jqdd(state)
    jqp = state_tables.jqp(state)
    jtau = state_tables.jtau(state)
    histories, w1q, w1d = loop.histories, loop.joints[0], loop.w1d
    eta_dd_new, w1e, e3, rot_prev = loop.eta_dd_new, loop.w1e, loop.e3, loop.rot_prev
    loops, target, g_pos, g_vel, g_acc = (loop.loops, inputs.closure_target[s], inputs.g_pos[s],
                                          inputs.g_vel[s], inputs.g_acc[s])
    target_ = loop_tables.target(loops)
    kind = loop_tables.kind(loops)
    h, coef, mode = settings.h, settings.coef, settings.mode
    hinge_kind = model_tables.hinge_kind(params)
    hinge_params = model_tables.hinge_params(params)
    hinge_row = model_tables.hinge_row(params)
    parent = model_tables.parent(params)
    locked = model_tables.locked(params)
    lock_rel = model_tables.lock_rel(params)
    joint_drive = model_tables.joint_drive(params)
    body_kind = model_tables.body_kind(params)
    body_params = model_tables.body_params(params)
    body_row = model_tables.body_row(params)
    rot, omega, omega_dot, pseudo, z = (rot_, omega_, omega_dot_, pseudo_,
                                        z_)
    defl, defl_rate, defl_acc, defl_pseudo = (defl_, defl_rate_, defl_acc_,
                                              defl_pseudo_)
    rot_now, g_w, g_wd, joint_input = (inputs.g_rot[s + 1], inputs.g_w[s], inputs.g_wd[s],
                                       inputs.joint_input[s])
    c1, _ = _integrator_coefficients(h, coef)
    n = hinge_kind.shape[0]
    if histories[0]:
        _advance_stations(h, coef, c1, z, rot_now, rot, body_kind, locked, lock_rel,
                          body_params, body_row, histories)
    finite = True
    if eta.shape[0] > 0:
        finite = _advance_modal(h, coef, c1, eta_dd_new, w1e, eta, eta_d, eta_acc, eta_p)
    for k in range(n):
        hk = hinge_kind[k]
        if has_coordinates(hk):
            # the coordinates' histories, then the child's frame from its parent's new one
            p = parent[k]
            frame = ((rot_now, g_w, g_wd) if p < 0 else (rot[p], omega[p], omega_dot[p]))
            _advance_joint(hk, hinge_params[hinge_row[k]], joint_drive[k], joint_input[k], h,
                           coef, c1, joint_nu[k], joint_tau[k], w1q[k], jq[k], jqd[k],
                           jqdd[k], jqp[k], jtau[k], frame, rot[k], omega[k], omega_dot[k],
                           defl[k], defl_rate[k], pseudo[k])
        elif _welded(hinge_kind, parent, locked, body_kind, mode, k):
            _welded_frame(params, k, rot, omega, omega_dot, eta, eta_d, eta_acc, rot[k],
                          omega[k], omega_dot[k])
            put1(pseudo[k], omega_dot[k])
        elif locked[k]:
            _locked_frame(rot_now, lock_rel[k], g_w, g_wd, rot[k], omega[k], omega_dot[k])
        else:
            _advance_body(h, coef, z[2 * k + 1, 3:6], rot[k], omega[k], omega_dot[k],
                          pseudo[k], e3, rot_prev)
        if hk == ELASTIC:
            _advance_deflection(params, z, w1d, c1, k, h, coef, defl[k], defl_rate[k],
                                defl_acc[k], defl_pseudo[k])
        for i in range(3):
            if not (np.isfinite(omega[k, i]) and np.isfinite(omega_dot[k, i])):
                finite = False
    if kind.shape[0] > 0:    # back onto the loops (closure.py)
        put2(target_, target)
        set_ground(loops, g_pos, g_vel, g_acc, rot_now, g_w, g_wd)
        project_onto_loops(params, loops, state)
    return finite


@loop_piece
def _record(loop, run, s, slot):
    """Write the state into run.rec at slot (every field read first, as in _predict)."""
    wrench_ = loop_tables.wrench(loop.loops)
    kind = loop_tables.kind(loop.loops)
    state, rec = run.state, run.rec
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    omega_dot = state_tables.omega_dot(state)
    z = state_tables.z(state)
    defl = state_tables.defl(state)
    defl_rate = state_tables.defl_rate(state)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    jq = state_tables.jq(state)
    jqd = state_tables.jqd(state)
    jtau = state_tables.jtau(state)
    histories = loop.histories
    n_closing, wrench, closure_wrench = (kind.shape[0],
                                         wrench_, rec.closure_wrench)
    put3(rec.rot[slot], rot)
    put2(rec.omega[slot], omega)
    put2(rec.omega_dot[slot], omega_dot)
    put2(rec.z[slot], z)
    put2(rec.defl[slot], defl)
    put2(rec.defl_rate[slot], defl_rate)
    put1(rec.eta[slot], eta)
    put1(rec.eta_d[slot], eta_d)
    put2(rec.jq[slot], jq)
    put2(rec.jqd[slot], jqd)
    put2(rec.jtau[slot], jtau)
    if n_closing > 0:
        put2(closure_wrench[slot], wrench)
    if histories[0]:
        put2(rec.v_st[slot], histories[1])
        put2(rec.v_c[slot], histories[4])


@loop_piece
def _finish(loop, run, n_steps, _):
    pass


loop_variant(GeneralLoop, predict=_predict, iterate=_iterate, adopt=_adopt, update=_update,
             record=_record, finish=_finish)
