"""The time loop fused for chains of beam elements welded end to end by fixed hinges, the first
to the ground (docs/assembly.md, "The fused welded-chain step").

The same step as the general loop (kernels/stepping/step.py) in RICCATI_FULL mode (Newmark scheme),
as a loop variant of the one skeleton (kernels/stepping/loop.py), on preallocated arrays: each
beam's 12 x 13 transfer in angular-acceleration slots (kernels/transfers/beam.py::beam_transfer,
into one scratch matrix) goes straight into its full Riccati step (sweep.py::riccati_step, the
station split [a, w'] | [m, q] of a chain from the ground), and the way back recovers each
body's rotation increment and modal accelerations.  Nothing else of the general loop's
per-body work runs: no guess kinematics (the beam evaluates its own state), no station copies,
no element kinds.  Results agree with the general loop to rounding
(tests/test_weld_chain.py).
"""
import numpy as np
from numba import njit

from .. import (CONTRACT, input_tables, kernel, loop_piece, model_tables, record_tables,
                state_tables, weld_tables)
from .ball_chain import (_ground_increment, adopt_solution, predict_offsets, record_state,
                         update_integrated)
from ..schema import WELD_LAYOUT, FlatWeld
from ..transfers.beam import beam_transfer, transfer_work_size
from ..transfers.beam_relations import end_section_motion
from .loop import NOT_FINITE, OK, SINGULAR, loop_variant
from ..algebra.mat3 import mm3_into
from ..algebra.so3 import expm_so3, log_so3
from .step import _all_finite, fused_coefficients
from ..assembly.sweep import riccati_step
from ...elements.beam import MODES, TORSION_MODES

# The loop's own scratch (kernels/schema.py::WELD, made by weld_loop; the skeleton is compiled
# without numba's reference counting, as every loop's: loop.py::_skeleton).
def weld_loop(n, mode_off, h, coef, z):
    """The welded-chain loop's scratch for n beams whose modal coordinates start at mode_off,
    its stations' guess from the stations' states z (the general loop's layout: z[2k + 1] body
    k's input, z[2n] the tip)."""
    most = int(np.max(np.diff(mode_off))) if n else 0
    loop = WELD_LAYOUT.zeros(bodies=n, modes=int(mode_off[-1]), work=transfer_work_size(most))
    loop.coefficients[:] = fused_coefficients(h, coef)
    loop.stations[:n] = z[1:2 * n:2]
    loop.stations[n] = z[2 * n]
    return loop


def start_loop(loop, run):
    """The welded-chain loop set for the consistent start, which the skeleton runs as one pass
    of its iterate (Settings.start; docs/solver.md, "The consistent start"), as
    ball_chain.start_loop does for the ball chains: beam_transfer at the start keeps every
    rotation, rate and modal state and takes w' and eta'' as the unknowns (a welded output's slot
    the end section's w'), so with (c1, c3) = (1, 0), w1 = 0, w3 = w_n and the root's [a, w'] the
    ground's, one sweep solves the linear relations and each body's phi comes out as its w'.
    Set in place, as ball_chain.start_loop; returns the step's coefficients, for the caller to
    put back."""
    w1, w3, phi_star = loop.per_body[0], loop.per_body[1], loop.per_body[2]
    w1[:] = 0.0
    w3[:] = run.state.omega
    phi_star[:] = 0.0
    loop.per_mode[0] = -run.state.eta
    loop.per_mode[1] = run.state.eta_d
    loop.per_mode[3] = 0.0
    loop.root[:3] = run.inputs.g_acc[0]
    loop.root[3:] = run.inputs.g_wd[0]
    loop.vecs[4] = run.inputs.g_wd[0]       # (the ground station's slot: z[0] = [a, w']_g)
    step_coefficients = loop.coefficients.copy()
    loop.coefficients[:] = 1.0, 0.0, 1.0, 0.0
    return step_coefficients


@loop_piece
def _predict(loop, run, s, _):
    """The fused ball chain's predictor (phi*, the offsets of every rotation and modal
    coordinate), then the bodies locked to the ground (the first beam) follow the ground's
    increment exactly, as in the general loop: phi* = phi_g, w1 = g_w' - c1 phi_g,
    w3 = g_w - c3 phi_g; and the root's known [a, w']."""
    vecs = weld_tables.vecs(loop)
    coefficients = weld_tables.coefficients(loop)
    per_body = weld_tables.per_body(loop)
    mats = weld_tables.mats(loop)
    root = weld_tables.root(loop)
    predict_offsets(run, coefficients, per_body, weld_tables.per_mode(loop))
    inputs = run.inputs
    g_rot = input_tables.g_rot(inputs)
    g_w_steps = input_tables.g_w(inputs)
    g_wd_steps = input_tables.g_wd(inputs)
    g_acc = input_tables.g_acc(inputs)
    c1, c3 = coefficients[0], coefficients[1]
    w1, w3, phi_star = per_body[0], per_body[1], per_body[2]
    phi_g = vecs[4]
    _ground_increment(g_rot, s, mats[6], phi_g)
    g_w, g_wd = g_w_steps[s], g_wd_steps[s]
    locked = model_tables.locked(run.params)
    for k in range(locked.shape[0]):
        if locked[k]:
            for i in range(3):
                phi_star[k, i] = phi_g[i]
                w1[k, i] = g_wd[i] - c1 * phi_g[i]
                w3[k, i] = g_w[i] - c3 * phi_g[i]
    for i in range(3):
        root[i] = g_acc[s, i]
        root[3 + i] = g_wd[i]
    _follow_welds(loop, run)


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _follow_welds(loop, run):
    """Every beam after the first follows its inboard's end section at the guess
    (docs/beam.md, "End sections"; kernels/stepping/step.py::_welded_guess): from the inboard's
    guess (A_p* = exp(phi_p*^) A_p,n, w_p* = c3 phi_p* + w3_p, w_p'* = c1 phi_p* + w1_p, eta* =
    (eta''* - w1e) / c1, eta'* = c3 eta* + w3e) the section's A*, w*, w'*
    (beam.end_section_motion); then phi* = log(A* A_n^T), and the offsets w1 = w'* - c1 phi*,
    w3 = w* - c3 phi*, so that the weld's slot is w'* there.  In order from the root: each
    beam's guess is its inboard's."""
    modal = weld_tables.follow_modal(loop)
    mats = weld_tables.follow_mats(loop)
    vecs = weld_tables.follow_vecs(loop)
    scratch = weld_tables.follow_work(loop)
    coefficients = weld_tables.coefficients(loop)
    per_body = weld_tables.per_body(loop)
    per_mode = weld_tables.per_mode(loop)
    params, state = run.params, run.state
    rot = state_tables.rot(state)
    c1, c3 = coefficients[0], coefficients[1]
    w1, w3, phi_star = per_body[0], per_body[1], per_body[2]
    w1e, w3e, eta_dd_star = per_mode[0], per_mode[1], per_mode[3]
    rot_p, rot_k, rel = mats[0], mats[1], mats[2]
    w_p, wd_p, w_k, wd_k = vecs[0], vecs[1], vecs[2], vecs[3]
    beam_params = model_tables.beam_params(params)
    mode_off = model_tables.mode_offset(params)
    beam_ends = model_tables.beam_ends(params)
    hinge_params, hinge_row = model_tables.hinge_params(params), model_tables.hinge_row(params)
    for k in range(1, phi_star.shape[0]):
        p = k - 1
        expm_so3(phi_star[p], rel)
        mm3_into(rel, rot[p], rot_p)
        for i in range(3):
            w_p[i] = c3 * phi_star[p, i] + w3[p, i]
            wd_p[i] = c1 * phi_star[p, i] + w1[p, i]
        i0, i1 = mode_off[p], mode_off[p + 1]
        for i in range(i0, i1):
            modal[0, i] = (eta_dd_star[i] - w1e[i]) / c1
            modal[1, i] = c3 * modal[0, i] + w3e[i]
        m = int(beam_params[p, MODES])
        mt = int(beam_params[p, TORSION_MODES])
        end_section_motion(beam_ends[p, :m], beam_ends[p, m:m + mt], rot_p, w_p, wd_p,
                           modal[0, i0:i1], modal[1, i0:i1], eta_dd_star[i0:i1],
                           hinge_params[hinge_row[k], 0:9].reshape((3, 3)), rot_k, w_k, wd_k,
                           scratch)
        for i in range(3):
            for j in range(3):
                rel[i, j] = (rot_k[i, 0] * rot[k, j, 0] + rot_k[i, 1] * rot[k, j, 1]
                             + rot_k[i, 2] * rot[k, j, 2])
        log_so3(rel, phi_star[k])
        for i in range(3):
            w1[k, i] = wd_k[i] - c1 * phi_star[k, i]
            w3[k, i] = w_k[i] - c3 * phi_star[k, i]


@loop_piece
def _iterate(loop, run, s, it):
    """One forward pass (each beam's transfer about the guess, its Riccati step) and one
    backward pass (the stations, then each body's phi and modal accelerations); returns
    (status, detail, change)."""
    s_mat = weld_tables.riccati_s(loop)
    p_vec = weld_tables.riccati_p(loop)
    t_inv = weld_tables.riccati_t_inv(loop)
    t_vec = weld_tables.riccati_t(loop)
    u = weld_tables.transfer(loop)
    work = weld_tables.transfer_work(loop)
    z = weld_tables.stations(loop)
    coefficients = weld_tables.coefficients(loop)
    per_body = weld_tables.per_body(loop)
    vecs = weld_tables.vecs(loop)
    per_mode = weld_tables.per_mode(loop)
    root = weld_tables.root(loop)
    beam_work = weld_tables.beam_work(loop)
    params, state, inputs = run.params, run.state, run.inputs
    force_steps = input_tables.force(inputs)
    torque_steps = input_tables.torque(inputs)
    line_load_steps = input_tables.line_load(inputs)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    eta_map = state_tables.eta_map(state)
    rot = state_tables.rot(state)
    c1, c3 = coefficients[0], coefficients[1]
    w1, w3, phi_star, phi_new = per_body[0], per_body[1], per_body[2], per_body[3]
    w, wd, w1_out, zero3 = vecs[0], vecs[1], vecs[2], vecs[3]
    w1e, w3e, eta_dd_star, eta_dd_new = per_mode[0], per_mode[1], per_mode[3], per_mode[4]
    beam_params = model_tables.beam_params(params)
    beam_moments = model_tables.beam_moments(params)
    mode_off = model_tables.mode_offset(params)
    beam_ends = model_tables.beam_ends(params)
    beam_factors = model_tables.beam_factors(params)
    hinge_params, hinge_row = model_tables.hinge_params(params), model_tables.hinge_row(params)
    gravity = model_tables.gravity(params)
    force, torque, line_load = force_steps[s], torque_steps[s], line_load_steps[s]
    n = phi_star.shape[0]
    for r in range(6):
        p_vec[0, r] = root[r]
        for c in range(6):
            s_mat[0, r, c] = 0.0
    for k in range(n):
        i0, i1 = mode_off[k], mode_off[k + 1]
        m = int(beam_params[k, MODES])
        mt = int(beam_params[k, TORSION_MODES])
        for i in range(3):
            w[i] = c3 * phi_star[k, i] + w3[k, i]
            wd[i] = c1 * phi_star[k, i] + w1[k, i]
        welded = k + 1 < n                      # the next beam on the output's fixed hinge
        kout = k + 1 if welded else k
        for i in range(3):
            w1_out[i] = w1[kout, i]             # (its w' = c1 phi_out + w1_out)
        outboard = (welded, hinge_params[hinge_row[kout], 0:9].reshape((3, 3)),
                    rot[kout], w1_out)
        tables = (beam_moments[k, :m, :4 * m + 2], beam_ends[k, :m], beam_factors[k, :m],
                  force[k], torque[k], line_load[k], beam_ends[k, m:m + mt],
                  beam_ends[k, m + mt:i1 - i0 - m])          # (as kernels/stepping/step.py)
        if run.settings.start:      # (the flag a literal: the step's copy keeps no start code)
            beam_transfer(beam_params[k], tables, outboard, (False, zero3), gravity,
                          True, rot[k], phi_star[k], wd, c1, c3, w3[k], w, w1e[i0:i1],
                          w3e[i0:i1], eta[i0:i1], eta_d[i0:i1], z[k], eta_dd_star[i0:i1], u,
                          eta_map[i0:i1], beam_work)
        else:
            beam_transfer(beam_params[k], tables, outboard, (False, zero3), gravity,
                          False, rot[k], phi_star[k], wd, c1, c3, w3[k], w, w1e[i0:i1],
                          w3e[i0:i1], eta[i0:i1], eta_d[i0:i1], z[k], eta_dd_star[i0:i1], u,
                          eta_map[i0:i1], beam_work)
        if not _all_finite(u):
            return NOT_FINITE, 0, 0.0
        if not riccati_step(u, s_mat[k], p_vec[k], s_mat[k + 1], p_vec[k + 1], t_inv[k],
                            t_vec[k], work):
            return SINGULAR, 2 * k + 2, 0.0
    # the free tip: [m, q] = 0, [a, w'] = P_n; then e_in = T^-1 (e_out - t), f = S e + P
    for r in range(6):
        z[n, r] = p_vec[n, r]
        z[n, 6 + r] = 0.0
    change = 0.0
    for k in range(n - 1, -1, -1):
        for r in range(6):
            x = 0.0
            for c in range(6):
                x += t_inv[k, r, c] * (z[k + 1, 6 + c] - t_vec[k, c])
            z[k, 6 + r] = x
        for r in range(6):
            x = p_vec[k, r]
            for c in range(6):
                x += s_mat[k, r, c] * z[k, 6 + c]
            z[k, r] = x
        for i in range(3):                      # back from w' = c1 phi + w1
            x = (z[k, 3 + i] - w1[k, i]) / c1
            phi_new[k, i] = x
            change = max(change, abs(x - phi_star[k, i]))
        for i in range(mode_off[k], mode_off[k + 1]):
            e = eta_map[i, 12]
            for c in range(12):
                e += eta_map[i, c] * z[k, c]
            eta_dd_new[i] = e
            change = max(change, abs(e - eta_dd_star[i]) / c1)
    if not np.isfinite(change):
        return NOT_FINITE, 0, change
    return OK, 0, change


@loop_piece
def _adopt(loop, run, s, it):
    """The latest solution becomes the guess (the fused ball chain's), the welded beams follow
    their inboard sections at it."""
    adopt_solution(weld_tables.per_body(loop), weld_tables.per_mode(loop))
    _follow_welds(loop, run)


@loop_piece
def _update(loop, run, s, _):
    """The fused ball chain's update (rotations, rates, modal coordinates); then a beam locked
    to the ground takes the ground's motion at t_n+1 (A = R_g A_rel, w = w_g, w' = w_g', as
    the general loop's locked bodies: the trapezoidal rule's relations on the ground's
    increments would alternate from step to step), and every beam after the first its
    inboard's end section's motion (beam.end_section_motion), its pseudo-acceleration its
    angular acceleration (as step.py's welded bodies); every rate finite?"""
    scratch = weld_tables.follow_work(loop)
    finite = update_integrated(run, weld_tables.coefficients(loop), weld_tables.per_body(loop),
                               weld_tables.mats(loop), weld_tables.per_mode(loop))
    params, state, inputs = run.params, run.state, run.inputs
    g_rot = input_tables.g_rot(inputs)
    g_w = input_tables.g_w(inputs)
    g_wd = input_tables.g_wd(inputs)
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    omega_dot = state_tables.omega_dot(state)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    eta_acc = state_tables.eta_acc(state)
    pseudo = state_tables.pseudo(state)
    beam_params = model_tables.beam_params(params)
    mode_off = model_tables.mode_offset(params)
    beam_ends = model_tables.beam_ends(params)
    hinge_params, hinge_row = model_tables.hinge_params(params), model_tables.hinge_row(params)
    locked, lock_rel = model_tables.locked(params), model_tables.lock_rel(params)
    for k in range(rot.shape[0]):
        if locked[k]:
            mm3_into(g_rot[s + 1], lock_rel[k], rot[k])
            for i in range(3):
                omega[k, i] = g_w[s, i]
                omega_dot[k, i] = g_wd[s, i]
    for k in range(1, rot.shape[0]):
        p = k - 1
        i0, i1 = mode_off[p], mode_off[p + 1]
        m = int(beam_params[p, MODES])
        mt = int(beam_params[p, TORSION_MODES])
        end_section_motion(beam_ends[p, :m], beam_ends[p, m:m + mt], rot[p], omega[p],
                           omega_dot[p], eta[i0:i1], eta_d[i0:i1],
                           eta_acc[i0:i1],
                           hinge_params[hinge_row[k], 0:9].reshape((3, 3)),
                           rot[k], omega[k], omega_dot[k], scratch)
        for i in range(3):
            pseudo[k, i] = omega_dot[k, i]
            if not (np.isfinite(omega[k, i]) and np.isfinite(omega_dot[k, i])):
                finite = False
    return finite


@kernel
def _write_stations(stations, phi, phi_g, z):
    """The stations' states in the general loop's layout (kernels/stepping/step.py::_solve): z[0]
    the ground point, z[2k + 1] and z[2k + 2] body k's input and output (the same station across a
    fixed hinge), each with the body's phi in its rotation slots (the ground's at z[0])."""
    n = phi.shape[0]
    for j in range(12):
        z[0, j] = stations[0, j]
    for i in range(3):
        z[0, 3 + i] = phi_g[i]
    for k in range(n):
        for j in range(12):
            z[2 * k + 1, j] = stations[k, j]
            z[2 * k + 2, j] = stations[k + 1, j]
        for i in range(3):
            z[2 * k + 1, 3 + i] = phi[k, i]
            z[2 * k + 2, 3 + i] = phi[k, i]


@loop_piece
def _record(loop, run, s, slot):
    stations = weld_tables.stations(loop)
    per_body = weld_tables.per_body(loop)
    vecs = weld_tables.vecs(loop)
    z = record_tables.z(run.rec)
    _write_stations(stations, per_body[3], vecs[4], z[slot])
    record_state(run.state, run.rec, slot)


@loop_piece
def _finish(loop, run, n_steps, _):
    """The stations' states z after the chunk's last step (the general loop's layout)."""
    stations = weld_tables.stations(loop)
    per_body = weld_tables.per_body(loop)
    vecs = weld_tables.vecs(loop)
    z = state_tables.z(run.state)
    if n_steps > 0:
        _write_stations(stations, per_body[3], vecs[4], z)


loop_variant(FlatWeld, predict=_predict, iterate=_iterate, adopt=_adopt, update=_update,
             record=_record, finish=_finish)
