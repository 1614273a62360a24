"""Every element's transfer about the step's guess (docs/solver.md, "The step"; docs/assembly.md,
"scaling"): the general loop's linearization, which the step (kernels/stepping/step.py::_iterate)
and the consistent start (step.py::initial_accelerations) sweep."""
import numpy as np
from numba import njit

from .. import CONTRACT, allocating_kernel, kernel, model_tables, sweep_tables
from ...elements import BEAM, RIGID, ROD
from ...elements.beam import MODES, TORSION_MODES
from ...elements.hinges import BALL, ELASTIC, FIXED, FREE
from ..transfers.beam import beam_transfer, transfer_work_size
from ..transfers.body import rigid_body_transfer, station_history_correction
from ..transfers.contact import contact_correction
from ..transfers.strain_rod import rod_tables_of, rod_transfer
from ..transfers.hinge import elastic_hinge_transfer
from ..transfers.joint import joint_linearization, n_coordinates
from ..algebra.mat3 import inv3, put1
from ..assembly.sweep import IDENTITY, LOCKED, TRANSFER
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


@allocating_kernel
def _build_elements(params, sweep, guess, ground, c1, c3, w1d, w3d, z_star, force, torque,
                    line_load, at_start, rot, w3, modal, stations, joints, contacts):
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
    addresses.  contacts = (body_first, next, point, offset, force, slope): each body's
    contacts at the guess, a list through next from body_first (-1 ends it), their forces and
    slopes (kernels/transfers/contact.py::contact_forces), added to its rigid body's transfer
    (contact_correction)."""
    kind = sweep_tables.kind(sweep)
    u = sweep_tables.u(sweep)
    known_loads = sweep_tables.known_loads(sweep)
    joint_dof = sweep_tables.joint_dof(sweep)
    joint_tau_nu = sweep_tables.joint_tau_nu(sweep)
    independent, w1_st, w1_c = stations
    full_tree, q_j, qd_j, qdd_j, given, forces = joints
    contact_first, contact_next, contact_point, contact_offset, contact_force, contact_slope = \
        contacts
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
        elif hk == FREE:            # nothing passes it (docs/free_joint.md): both sides' loads
            kind[jh] = LOCKED       # are zero, its child's motion solved from its own subtree
            for i in range(12):
                known_loads[jh, i] = 0.0
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
            c = contact_first[k] if contact_first.shape[0] > k else -1
            while c >= 0:           # (its contacts: kernels/transfers/contact.py)
                contact_correction(contact_point[c], contact_offset[c],
                                   body_params[row, 4:7], rot_star[k], lam[k], w[k], wd[k],
                                   dw[k], dwd[k], contact_force[c], contact_slope[c],
                                   z_star[jh + 1], u[jh + 1])
                c = contact_next[c]
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
