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
consistent start; every element's transfer about the guess is kernels/stepping/linearize.py's.
"""
from collections import namedtuple

import numpy as np
from numba import njit

from .. import (CONTRACT, allocating_kernel, general_tables, input_tables, kernel, loop_piece,
                loop_tables, model_tables, record_tables, state_tables, sweep_tables)
from ..schema import GENERAL_LAYOUT
from ...elements import BEAM, ROD
from ...elements.hinges import ELASTIC, FIXED
from ...elements.kinds import DEFLECTS, MAX_COORDINATES
from ..assembly.closure import set_ground, solve_with_loops, tree_points
from ..assembly.loop_projection import project_onto_loops
from ..transfers.contact import contact_forces
from ..transfers.hinge import elastic_hinge_loads
from ..transfers.joint import drive_share, n_coordinates
from .generalized_alpha import (_advance_body, _advance_deflection, _advance_joint,
                                _advance_modal, _advance_stations, _body_kinematics,
                                _deflection_offsets, _ground_guess, _hinge_deflection,
                                _integrator_coefficients, _joint_adopt, _joint_guess,
                                _locked_frame, _locked_guess, _modal_guess, _offsets_into,
                                _spring_guess, _station_offsets, _stations_guess, _welded_frame,
                                _welded_guess)
from .linearize import _build_elements, has_coordinates
from .loop import NOT_FINITE, OK, SINGULAR, UNSUPPORTED, loop_variant
from ..algebra.mat3 import dot, inv3, put1, put2, put3
from ..assembly.solve import RICCATI_FULL, RICCATI_JOINTS, solve_step






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

# The general loop's structure (kernels/stepping/loop.py, "loop_variant"): its own scratch, flat
# (a FlatGeneral: kernels/schema.py::GENERAL, read through kernels/general_tables.py), and the
# closing joints' tables and scratch (a FlatLoops: kernels/schema.py::LOOPS).
GeneralLoop = namedtuple("GeneralLoop", ["scratch", "loops"])


def general_loop(n, n_eta, h, coef, histories, loops, forces, n_contacts=0):
    """The general loop's scratch for n bodies and n_eta modal coordinates.  histories: the
    paper's scheme's (independent, st_v, st_a, st_p, c_v, c_a, c_p) (run_tables._station_histories);
    the loop adds the w1 offsets of every station point and mass centre.  loops: the closing
    joints (a FlatLoops, run_tables.loop_tables; no rows without them).  forces: the compiled
    JointForces' callbacks' addresses (run_tables.compiled_forces)."""
    c1, _ = _coefficients_py(h, coef)
    independent, st_v, st_a, st_p, c_v, c_a, c_p = histories
    body3, body33, coordinates = (n, 3), (n, 3, 3), (n, MAX_COORDINATES)
    scratch = GENERAL_LAYOUT.pack(
        guess_phi=np.zeros(body3), guess_rot=np.zeros(body33), guess_lam=np.zeros(body33),
        guess_w=np.zeros(body3), guess_wd=np.zeros(body3), guess_dw=np.zeros(body33),
        guess_dwd=np.zeros(body33), w1=np.zeros(body3), w3=np.zeros(body3), w1d=np.zeros(body3),
        w3d=np.zeros(body3), z_star=np.zeros((2 * n + 1, 12)), w1e=np.zeros(n_eta),
        w3e=np.zeros(n_eta), eta_dd_star=np.zeros(n_eta), eta_dd_new=np.zeros(n_eta),
        ground_rot=np.eye(3), ground_lam=np.zeros((3, 3)), ground_w=np.zeros(3),
        ground_wd=np.zeros(3), ground_dwd=c1 * np.eye(3), ground_phi=np.zeros(3),
        root_f=np.zeros(6), e3=np.zeros((3, 3)), g_inv=np.zeros((3, 3)),
        rot_prev=np.zeros((3, 3)), independent=np.int64(bool(independent)), st_v=st_v,
        st_a=st_a, st_p=st_p, c_v=c_v, c_a=c_a, c_p=c_p, w1_st=np.zeros((n + 1, 3)),
        w1_c=np.zeros(body3), q_w1=np.zeros(coordinates), q_w3=np.zeros(coordinates),
        q_star=np.zeros(coordinates), qd_star=np.zeros(coordinates),
        qdd_star=np.zeros(coordinates), eta_g=np.zeros(n_eta), eta_d_g=np.zeros(n_eta),
        defl_g=np.zeros(body3), defl_rate_g=np.zeros(body3),
        forces=np.asarray(forces, dtype=np.int64), **contact_scratch(n, n_contacts))
    return GeneralLoop(scratch, loops)


def contact_capacity(n_contacts):
    """The most contacts the scratch holds at once: one per sphere against the plane and two
    per touching pair of spheres, up to every pair of up to 64 spheres, else 32 pairs a sphere
    (kernels/transfers/contact.py::contact_forces: a run that needs more stops, not finite)."""
    pairs = n_contacts * (n_contacts - 1) // 2 if n_contacts <= 64 else 32 * n_contacts
    return n_contacts + 2 * pairs


def contact_scratch(n, n_contacts):
    """The general loop's contact tables (kernels/schema.py::GENERAL) for n bodies and
    n_contacts spheres, by name."""
    m = contact_capacity(n_contacts)
    return dict(contact_centre=np.zeros((n_contacts, 3)),
                contact_point=np.zeros((m, 3)), contact_offset=np.zeros((m, 3)),
                contact_force=np.zeros((m, 3)), contact_slope=np.zeros((m, 3, 3)),
                contact_next=np.zeros(m, dtype=np.int64),
                contact_body_first=np.full(n, -1, dtype=np.int64),
                contact_count=np.zeros(1, dtype=np.int64))


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _contacts_of(scratch):
    """(the instances' tuple for contact_forces, the bodies' lists for _build_elements, the
    spheres' centres) as views of the general loop's scratch."""
    inst = (general_tables.contact_point(scratch), general_tables.contact_offset(scratch),
            general_tables.contact_force(scratch), general_tables.contact_slope(scratch),
            general_tables.contact_next(scratch), general_tables.contact_body_first(scratch),
            general_tables.contact_count(scratch))
    lists = (inst[5], inst[4], inst[0], inst[1], inst[2], inst[3])
    return inst, lists, general_tables.contact_centre(scratch)


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _guess_of(scratch):
    """Each body's kinematics at the guess (Guess) as views of the general loop's scratch."""
    return Guess(general_tables.guess_phi(scratch), general_tables.guess_rot(scratch),
                 general_tables.guess_lam(scratch), general_tables.guess_w(scratch),
                 general_tables.guess_wd(scratch), general_tables.guess_dw(scratch),
                 general_tables.guess_dwd(scratch))


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _ground_of(scratch):
    """(rot, lam, w, wd, dwd, phi) of the ground over the step (generalized_alpha's ground)."""
    return (general_tables.ground_rot(scratch), general_tables.ground_lam(scratch),
            general_tables.ground_w(scratch), general_tables.ground_wd(scratch),
            general_tables.ground_dwd(scratch), general_tables.ground_phi(scratch))


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _histories_of(scratch):
    """The paper's scheme's (independent, st_v, st_a, st_p, c_v, c_a, c_p, w1_st, w1_c)
    (generalized_alpha's histories)."""
    return (general_tables.independent(scratch) != 0, general_tables.st_v(scratch),
            general_tables.st_a(scratch), general_tables.st_p(scratch),
            general_tables.c_v(scratch), general_tables.c_a(scratch),
            general_tables.c_p(scratch), general_tables.w1_st(scratch),
            general_tables.w1_c(scratch))


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _joints_of(scratch):
    """(w1q, w3q, q*, q'*, q''*): the joint coordinates' offsets and guess."""
    return (general_tables.q_w1(scratch), general_tables.q_w3(scratch),
            general_tables.q_star(scratch), general_tables.qd_star(scratch),
            general_tables.qdd_star(scratch))


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _step_inputs(inputs, s):
    """Step s's prescribed data as views of the chunk's inputs (kernels/schema.py::INPUTS):
    (g_acc, rot_before, rot_now, g_w, g_wd, g_pos, g_vel, target, force, torque, line_load,
    joint_input), the ground's rotation at t_s and t_{s+1}, the rest at t_{s+1}."""
    g_rot = input_tables.g_rot(inputs)
    return (input_tables.g_acc(inputs)[s], g_rot[s], g_rot[s + 1], input_tables.g_w(inputs)[s],
            input_tables.g_wd(inputs)[s], input_tables.g_pos(inputs)[s],
            input_tables.g_vel(inputs)[s], input_tables.closure_target(inputs)[s],
            input_tables.force(inputs)[s], input_tables.torque(inputs)[s],
            input_tables.line_load(inputs)[s], input_tables.joint_input(inputs)[s])


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
def initial_accelerations(params, settings, state, sweep, ground, force, torque, line_load,
                          joint_input, loops, forces, contacts):
    """The consistent start: one linear sweep at acceleration level.  The phi slot of every
    station holds the angular acceleration (w' = 1 * slot, w fixed, no rotation change), and an
    elastic hinge's loads are known from its state (its outboard motion is free); beams' modal
    accelerations come out in state.eta_acc.  ground: (a, R, w, w') of the ground at t = 0;
    force, torque, line_load (n, 3) at t = 0; joint_input (n, 3, 3) the joint coordinates'
    inputs at t = 0 (kernels/stepping/loop.py::Inputs), their accelerations come out in state.jqdd.
    loops: the closing joints (kernels/assembly/closure.py), held at acceleration level.  forces:
    the compiled JointForces' callbacks' addresses (kernels/transfers/joint.py::drive_value).
    contacts = (instances, the bodies' lists, the spheres' centres: _contacts_of): the
    contacts' forces, from the state (kernels/transfers/contact.py).  Returns the status: 0, a
    singularity code (sweep.py), or
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
    joint_drive = model_tables.joint_drive(params)
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
    inst, lists, centre = contacts
    lists[0][:] = -1                    # (no contacts but those found below)
    if kind.shape[0] > 0 or centre.shape[0] > 0:
        tree_points(params, rot, omega, jq, jqd, eta, eta_d,
                    defl, defl_rate, loops, all_bodies)
    if centre.shape[0] > 0:             # (known at the start: no slope)
        contact_forces(params, loops, rot, omega, 0.0, 0.0, centre, True, inst)
    unknown = _build_elements(params, sweep, guess, g, 1.0, 0.0, zero3, zero3,
                              np.zeros(z.shape), force, torque, line_load, n >= 0, rot,
                              zero3, modal,
                              (n < 0, np.zeros((n + 1, 3)), zero3),     # (False)
                              (settings.mode == RICCATI_JOINTS, jq, jqd,
                               joint_input[:, :, 2].copy(), joint_input[:, :, 0], forces),
                              lists)
    # (given: a strided view, as the step's inputs.joint_input[s, :, :, 0], and at_start and
    # the stations' flag run-time bools (n >= 0, n < 0), as the step's: numba compiles a
    # function once per layout and per literal True or False it is passed, and _build_elements
    # with its callees took 10-60 s cold a second time)
    if unknown != 0:
        return -unknown
    for k in range(n):
        if DEFLECTS[hinge_kind[k]]:     # (a free joint's: zero)
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
        status = solve_with_loops(params, sweep, root_f, loops, rot, omega, z)
    else:
        status = solve_step(settings.mode, model_tables.tip_pinned(params), parent, sweep,
                            root_f, z)
    _modal_accelerations(params, eta_map, z, eta_acc)
    for k in range(n):
        for i in range(n_coordinates(hinge_kind[k])):
            jqdd[k, i] = joint_nu[k, i]
            jqp[k, i] = joint_nu[k, i]
            jtau[k, i] = drive_share(hinge_params[hinge_row[k]], joint_drive[k], i,
                                     joint_tau[k, i], jq[k, i], jqd[k, i])
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
    (g_acc, rot_before, rot_now, g_w, g_wd, _, _, _, _, _, _,
     joint_input) = _step_inputs(inputs, s)
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    omega_dot = state_tables.omega_dot(state)
    pseudo = state_tables.pseudo(state)
    z = state_tables.z(state)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    eta_acc = state_tables.eta_acc(state)
    eta_p = state_tables.eta_p(state)
    defl = state_tables.defl(state)
    defl_rate = state_tables.defl_rate(state)
    defl_acc = state_tables.defl_acc(state)
    defl_pseudo = state_tables.defl_pseudo(state)
    jq = state_tables.jq(state)
    jqd = state_tables.jqd(state)
    jqdd = state_tables.jqdd(state)
    jqp = state_tables.jqp(state)
    scratch = loop.scratch
    guess, ground = _guess_of(scratch), _ground_of(scratch)
    w1, w3 = general_tables.w1(scratch), general_tables.w3(scratch)
    w1d, w3d = general_tables.w1d(scratch), general_tables.w3d(scratch)
    w1e, w3e = general_tables.w1e(scratch), general_tables.w3e(scratch)
    eta_dd_star, z_star = general_tables.eta_dd_star(scratch), general_tables.z_star(scratch)
    root_f = general_tables.root_f(scratch)
    histories, (w1q, w3q, q_s, qd_s, qdd_s) = _histories_of(scratch), _joints_of(scratch)
    h, coef, mode = settings.h, settings.coef, settings.mode
    hinge_kind = model_tables.hinge_kind(params)
    hinge_params = model_tables.hinge_params(params)
    hinge_row = model_tables.hinge_row(params)
    parent = model_tables.parent(params)
    locked = model_tables.locked(params)
    lock_rel = model_tables.lock_rel(params)
    joint_drive = model_tables.joint_drive(params)
    body_kind = model_tables.body_kind(params)
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
        if DEFLECTS[hk]:
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
    # (at t_{s+1}: the ground's and the closing joints' targets, for the loops)
    (g_acc, _, rot_now, g_w, g_wd, g_pos, g_vel, target, force, torque, line_load,
     joint_inputs) = _step_inputs(inputs, s)
    z = state_tables.z(state)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    eta_map = state_tables.eta_map(state)
    rot = state_tables.rot(state)
    u = sweep_tables.u(sweep)
    joint_nu = sweep_tables.joint_nu(sweep)
    scratch, loops = loop.scratch, loop.loops
    guess, ground = _guess_of(scratch), _ground_of(scratch)
    w1d, w3d = general_tables.w1d(scratch), general_tables.w3d(scratch)
    z_star, w3 = general_tables.z_star(scratch), general_tables.w3(scratch)
    w1e, w3e = general_tables.w1e(scratch), general_tables.w3e(scratch)
    eta_dd_star = general_tables.eta_dd_star(scratch)
    eta_dd_new = general_tables.eta_dd_new(scratch)
    root_f, g_inv = general_tables.root_f(scratch), general_tables.g_inv(scratch)
    histories, joints_ = _histories_of(scratch), _joints_of(scratch)
    forces = general_tables.forces(scratch)
    at_guess = (general_tables.eta_g(scratch), general_tables.eta_d_g(scratch),
                general_tables.defl_g(scratch), general_tables.defl_rate_g(scratch))
    step_coef = loop_tables.step_coef(loops)
    target_ = loop_tables.target(loops)
    all_bodies = loop_tables.all_bodies(loops)
    kind = loop_tables.kind(loops)
    hinge_kind = model_tables.hinge_kind(params)
    tip_pinned = model_tables.tip_pinned(params)
    parent = model_tables.parent(params)
    inst, contacts, contact_centre = _contacts_of(scratch)
    h, coef, mode = settings.h, settings.coef, settings.mode
    joint_input = joint_inputs[:, :, 0]
    if settings.start:      # the consistent start (Settings.start): one pass, at t
        start = initial_accelerations(params, settings, state, sweep, (g_acc, rot_now, g_w, g_wd),
                                      force, torque, line_load, joint_inputs, loops,
                                      forces, (inst, contacts, contact_centre))
        return (OK, 0, 0.0) if start == 0 else (SINGULAR, start, 0.0)
    c1, c3 = _integrator_coefficients(h, coef)
    phi_star, wd, dwd = guess.phi, guess.wd, guess.dwd
    modal = (eta, eta_d, w1e, w3e, eta_dd_star, eta_map)
    stations = (histories[0], histories[7], histories[8])
    joints = (mode == RICCATI_JOINTS, joints_[2], joints_[3], joints_[4], joint_input, forces)
    contact_change = 0.0
    if kind.shape[0] > 0 or contact_centre.shape[0] > 0:
        # the points at the guess: the closing joints' rows' velocity terms and the
        # multipliers' arms, the contacts' places (the beams' modal coordinates at theirs:
        # eta = (eta''* - w1e) / c1, eta' = c3 eta + w3e; the elastic hinges' deflections
        # likewise from their stations' guess, as _update)
        set_ground(loops, g_pos, g_vel, g_acc, rot_now, g_w, g_wd)
        eta_g, eta_d_g, defl_g, defl_rate_g = at_guess
        for i in range(eta_g.shape[0]):
            eta_g[i] = (eta_dd_star[i] - w1e[i]) / c1
            eta_d_g[i] = c3 * eta_g[i] + w3e[i]
        for k in range(defl_g.shape[0]):
            if DEFLECTS[hinge_kind[k]]:
                d = _hinge_deflection(params, z_star, w1d, c1, k)
                for i in range(3):
                    defl_g[k, i] = d[i]
                    defl_rate_g[k, i] = c3 * d[i] + w3d[k, i]
        tree_points(params, guess.rot, guess.w, joints_[2], joints_[3], eta_g,
                    eta_d_g, defl_g, defl_rate_g, loops, all_bodies)
        if contact_centre.shape[0] > 0:     # (docs/contact.md, "In the step")
            contact_change = contact_forces(params, loops, guess.rot, guess.w, c1, c3,
                                            contact_centre, it == 0, inst)
            if not contact_change == contact_change:      # (NaN: more contacts than held)
                return NOT_FINITE, 0, 0.0
    unknown = _build_elements(params, sweep, guess, ground, c1, c3, w1d, w3d, z_star, force,
                              torque, line_load, settings.start,     # (False)
                              rot, w3, modal, stations, joints, contacts)
    if unknown != 0:
        return UNSUPPORTED, unknown, 0.0
    if not _all_finite(u):
        return NOT_FINITE, 0, 0.0
    if kind.shape[0] > 0:  # closing joints: held at acceleration level
        put2(target_, target)
        step_coef[0] = 1.0 / c1           # a spring's q and q' per unit row acceleration
        step_coef[1] = c3 / c1
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
    change = contact_change
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
    _, _, rot_now, g_w, g_wd, _, _, _, _, _, _, _ = _step_inputs(inputs, s)
    z = state_tables.z(state)
    rot = state_tables.rot(state)
    jq = state_tables.jq(state)
    eta = state_tables.eta(state)
    scratch = loop.scratch
    guess = _guess_of(scratch)
    w1, w3 = general_tables.w1(scratch), general_tables.w3(scratch)
    w1e, w3e = general_tables.w1e(scratch), general_tables.w3e(scratch)
    z_star = general_tables.z_star(scratch)
    eta_dd_star = general_tables.eta_dd_star(scratch)
    eta_dd_new = general_tables.eta_dd_new(scratch)
    w1q, w3q, q_s, qd_s, qdd_s = _joints_of(scratch)
    mode = settings.mode
    hinge_kind = model_tables.hinge_kind(params)
    hinge_params = model_tables.hinge_params(params)
    hinge_row = model_tables.hinge_row(params)
    parent = model_tables.parent(params)
    locked = model_tables.locked(params)
    joint_drive = model_tables.joint_drive(params)
    body_kind = model_tables.body_kind(params)
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
    (g_acc, _, rot_now, g_w, g_wd, g_pos, g_vel, target, _, _, _,
     joint_input) = _step_inputs(inputs, s)
    joint_nu = sweep_tables.joint_nu(sweep)
    joint_tau = sweep_tables.joint_tau(sweep)
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    omega_dot = state_tables.omega_dot(state)
    pseudo = state_tables.pseudo(state)
    z = state_tables.z(state)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    eta_acc = state_tables.eta_acc(state)
    eta_p = state_tables.eta_p(state)
    defl = state_tables.defl(state)
    defl_rate = state_tables.defl_rate(state)
    defl_acc = state_tables.defl_acc(state)
    defl_pseudo = state_tables.defl_pseudo(state)
    jq = state_tables.jq(state)
    jqd = state_tables.jqd(state)
    jqdd = state_tables.jqdd(state)
    jqp = state_tables.jqp(state)
    jtau = state_tables.jtau(state)
    scratch = loop.scratch
    histories, w1q = _histories_of(scratch), general_tables.q_w1(scratch)
    w1d, eta_dd_new = general_tables.w1d(scratch), general_tables.eta_dd_new(scratch)
    w1e, e3 = general_tables.w1e(scratch), general_tables.e3(scratch)
    rot_prev = general_tables.rot_prev(scratch)
    loops = loop.loops
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
        if DEFLECTS[hk]:
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
    state, rec = run.state, run.rec
    closure_wrench = record_tables.closure_wrench(rec)
    rec_rot = record_tables.rot(rec)
    rec_omega = record_tables.omega(rec)
    rec_omega_dot = record_tables.omega_dot(rec)
    rec_z = record_tables.z(rec)
    rec_defl = record_tables.defl(rec)
    rec_defl_rate = record_tables.defl_rate(rec)
    rec_eta = record_tables.eta(rec)
    rec_eta_d = record_tables.eta_d(rec)
    rec_jq = record_tables.jq(rec)
    rec_jqd = record_tables.jqd(rec)
    rec_jtau = record_tables.jtau(rec)
    rec_v_st = record_tables.v_st(rec)
    rec_v_c = record_tables.v_c(rec)
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
    histories = _histories_of(loop.scratch)
    n_closing = loop_tables.kind(loop.loops).shape[0]
    wrench = loop_tables.wrench(loop.loops)
    put3(rec_rot[slot], rot)
    put2(rec_omega[slot], omega)
    put2(rec_omega_dot[slot], omega_dot)
    put2(rec_z[slot], z)
    put2(rec_defl[slot], defl)
    put2(rec_defl_rate[slot], defl_rate)
    put1(rec_eta[slot], eta)
    put1(rec_eta_d[slot], eta_d)
    put2(rec_jq[slot], jq)
    put2(rec_jqd[slot], jqd)
    put2(rec_jtau[slot], jtau)
    if n_closing > 0:
        put2(closure_wrench[slot], wrench)
    if histories[0]:
        put2(rec_v_st[slot], histories[1])
        put2(rec_v_c[slot], histories[4])


@loop_piece
def _finish(loop, run, n_steps, _):
    pass


loop_variant(GeneralLoop, predict=_predict, iterate=_iterate, adopt=_adopt, update=_update,
             record=_record, finish=_finish)
