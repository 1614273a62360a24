"""The loops held after a step (docs/loops.md, "The step with loops", "The energy held"): the
configuration and then the rates projected back onto the closing joints' constraints along the
step's own responses to unit multipliers (project_onto_loops), the bodies whose frames follow
their parents' moved with them (_dependent_frames), and a rigid model's energy held
(start_energy, _hold_energy).  The rows' geometry and the step's solve are in closure.py.
"""

import numpy as np

from .. import (allocating_kernel, kernel, loop_tables, model_tables, no_alloc_kernel,
                state_tables)
from ...elements import BEAM, RIGID, ROD
from ...elements.kinds import DEFLECTS, UNDECLARED_BODY_KIND
from ...elements.beam import MODES, TORSION_MODES
from ...elements.hinges import FIXED
from ..transfers.beam_relations import end_section_motion
from ..transfers.strain_rod import rod_end_frame, rod_tables_of
from ..transfers.joint import joint_frame, n_coordinates
from ..algebra.mat3 import put1, t_cross, t_mv
from ..algebra.so3 import expm_so3
from .closure import (_add, _band_apply, _band_factor, _clear_rows_matrix, _dot, _is_force,
                      _least_apply, _m9, _modal_responses, _v3, row_positions, tree_points)

POSITION_PROJECTIONS = 4     # Gauss-Newton projections of the positions after a step, at most
POSITION_TOL = 1e-13         # m, rad: where they stop
RATE_TOL = 1e-13             # m/s, rad/s: the rates' projection's
ENERGY_STEP_LIMIT = 1e-3     # the energy's projection changes the rates by less than this
                             # fraction in one step, or not at all (a state too slow to carry it)


@no_alloc_kernel(always_inline=True)
def _dependent_frames(params, loops, state, bodies, work):
    """Every given body (in tree order) whose frame follows its parent's, from the parent's
    (as step.py::_update): a joint child's by its coordinates (joint.joint_frame, a slide's
    offset too), a welded body's as the parent's (R0) or its beam's end section's (beam.
    end_section_motion) or its strain rod's (strain_rod.rod_end_frame).  work: (60,) scratch
    (nothing is allocated)."""
    ground_rot = loop_tables.ground_rot(loops)
    ground_motion = loop_tables.ground_motion(loops)
    pseudo = state_tables.pseudo(state)
    omega_dot = state_tables.omega_dot(state)
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    jq = state_tables.jq(state)
    jqd = state_tables.jqd(state)
    jqdd = state_tables.jqdd(state)
    defl = state_tables.defl(state)
    defl_rate = state_tables.defl_rate(state)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    eta_acc = state_tables.eta_acc(state)
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
            rot_p, w_p, wd_p = ground_rot, ground_motion[2], ground_motion[3]
        else:
            rot_p, w_p, wd_p = rot[p], omega[p], omega_dot[p]
        hr = hinge_row[k]             # (the joint's row of the shared table)
        if n_coordinates(hk) > 0:
            joint_frame(hk, hinge_params[hr], rot_p, w_p, wd_p, jq[k],
                        jqd[k], jqdd[k], rot[k], omega[k],
                        omega_dot[k], defl[k], defl_rate[k])
        elif hk == FIXED and p >= 0 and not locked[k]:
            for i in range(3):                 # R0, row-major in hinge_params[hr, 0:9]
                for j in range(3):
                    rest[i, j] = hinge_params[hr, 3 * i + j]
            i0, i1 = mode_off[p], mode_off[p + 1]      # a flexible parent's coordinates
            if body_kind[p] == BEAM:
                m, mt = int(bp[p, MODES]), int(bp[p, TORSION_MODES])
                end_section_motion(ends[p, :m], ends[p, m:m + mt], rot_p, w_p, wd_p,
                                   eta[i0:i1], eta_d[i0:i1], eta_acc[i0:i1],
                                   rest, rot[k], omega[k], omega_dot[k],
                                   scratch)
            elif body_kind[p] == ROD:
                steps, xi0, phi = rod_tables_of(params, p)[:3]
                rod_end_frame(steps, xi0, phi, rot_p, w_p, wd_p, eta[i0:i1],
                              eta_d[i0:i1], eta_acc[i0:i1], rest, rot[k],
                              omega[k], omega_dot[k])
            elif body_kind[p] == RIGID:        # A = A_P R0
                for i in range(3):
                    for j in range(3):
                        rot[k, i, j] = (rot_p[i, 0] * rest[0, j] + rot_p[i, 1] * rest[1, j]
                                              + rot_p[i, 2] * rest[2, j])
                for i in range(3):
                    omega[k, i] = w_p[i]
                    omega_dot[k, i] = wd_p[i]
            else:
                raise ValueError(UNDECLARED_BODY_KIND)
        else:
            continue
        for i in range(3):
            pseudo[k, i] = omega_dot[k, i]


@no_alloc_kernel
def _deflection_response(params, loops, z, j, k, i):
    """Row j's response of elastic hinge k's d''_i: its outboard input station's acceleration
    less its inboard output station's (v_in = v_out,P + d', step.py::_update; station 0 the
    ground, a parent outside the row's active bodies does not move)."""
    act = loop_tables.act(loops)
    p = model_tables.parent(params)[k]
    inboard = 0.0 if p < 0 or not act[j + 1, p] else z[2 * p + 2, i]
    return z[2 * k + 1, i] - inboard


@no_alloc_kernel
def _add_rates(params, loops, state, j, f):
    """The angular velocities, the joint coordinates', the elastic hinges' deflections' and
    the modal coordinates' rates += f times row j's response (of w', q'', d'' and eta'') on
    its active bodies (the dependent frames are rebuilt after, _dependent_frames)."""
    z_save = loop_tables.z_save(loops)
    nu_save = loop_tables.nu_save(loops)
    act_ptr = loop_tables.act_ptr(loops)
    act_idx = loop_tables.act_idx(loops)
    eta_col = loop_tables.eta_col(loops)
    omega = state_tables.omega(state)
    jqd = state_tables.jqd(state)
    eta_d = state_tables.eta_d(state)
    defl_rate = state_tables.defl_rate(state)
    mode_off, hinge_kind = model_tables.mode_offset(params), model_tables.hinge_kind(params)
    z, nu = z_save[j + 1], nu_save[j + 1]
    for q in range(act_ptr[j + 1], act_ptr[j + 2]):
        k = act_idx[q]
        for i in range(3):
            omega[k, i] += f * z[2 * k + 1, 3 + i]
        if DEFLECTS[hinge_kind[k]]:
            for i in range(3):
                defl_rate[k, i] += f * _deflection_response(params, loops, z, j, k, i)
        for i in range(n_coordinates(hinge_kind[k])):
            jqd[k, i] += f * nu[k, i]
        for i in range(mode_off[k], mode_off[k + 1]):
            eta_d[i] += f * eta_col[j, i]


@no_alloc_kernel
def _keep_rates(params, loops, state, bodies, saved, save):
    """Save (save) or put back what a column of project_onto_loops changes on the given bodies:
    _add_rates' rates (w, the elastic hinges' d', the joints' q', the modal eta'), what
    _dependent_frames derives from them (w' and the pseudo-acceleration of a body whose frame
    follows its parent's) and tree_points' output velocities; saved: ((n, 6, >= 3) per body:
    w, w', pseudo, d', v_out, q'; (n_eta,) eta').  The positions, frames and output points the
    column computes again come out of unchanged values, bit for bit."""
    v_out = loop_tables.v_out(loops)
    omega = state_tables.omega(state)
    omega_dot = state_tables.omega_dot(state)
    pseudo = state_tables.pseudo(state)
    defl_rate = state_tables.defl_rate(state)
    jqd = state_tables.jqd(state)
    eta_d = state_tables.eta_d(state)
    mode_off = model_tables.mode_offset(params)
    rates, modal = saved
    for q in range(bodies.shape[0]):
        k = bodies[q]
        if save:
            for i in range(3):
                rates[k, 0, i] = omega[k, i]
                rates[k, 1, i] = omega_dot[k, i]
                rates[k, 2, i] = pseudo[k, i]
                rates[k, 3, i] = defl_rate[k, i]
                rates[k, 4, i] = v_out[k, i]
            for i in range(jqd.shape[1]):
                rates[k, 5, i] = jqd[k, i]
            for i in range(mode_off[k], mode_off[k + 1]):
                modal[i] = eta_d[i]
        else:
            for i in range(3):
                omega[k, i] = rates[k, 0, i]
                omega_dot[k, i] = rates[k, 1, i]
                pseudo[k, i] = rates[k, 2, i]
                defl_rate[k, i] = rates[k, 3, i]
                v_out[k, i] = rates[k, 4, i]
            for i in range(jqd.shape[1]):
                jqd[k, i] = rates[k, 5, i]
            for i in range(mode_off[k], mode_off[k + 1]):
                eta_d[i] = modal[i]


@no_alloc_kernel
def _move(params, loops, state, j, f, e3, phi):
    """Turn every active body of row j by f times its response of w' (A <- exp(f dw'^) A) and
    move its joint coordinates, elastic deflection and modal coordinates by f times their
    response of q'', d'' and eta'' (the dependent frames are rebuilt after,
    _dependent_frames); e3 (3, 3), phi (3,) scratch."""
    z_save = loop_tables.z_save(loops)
    nu_save = loop_tables.nu_save(loops)
    act_ptr = loop_tables.act_ptr(loops)
    act_idx = loop_tables.act_idx(loops)
    eta_col = loop_tables.eta_col(loops)
    rot = state_tables.rot(state)
    jq = state_tables.jq(state)
    eta = state_tables.eta(state)
    defl = state_tables.defl(state)
    mode_off, hinge_kind = model_tables.mode_offset(params), model_tables.hinge_kind(params)
    z, nu = z_save[j + 1], nu_save[j + 1]
    for q in range(act_ptr[j + 1], act_ptr[j + 2]):
        k = act_idx[q]
        if DEFLECTS[hinge_kind[k]]:
            for i in range(3):
                defl[k, i] += f * _deflection_response(params, loops, z, j, k, i)
        for i in range(3):
            phi[i] = f * z[2 * k + 1, 3 + i]
        expm_so3(phi, e3)
        rot_k = _m9(rot, k)
        for a in range(3):
            for b in range(3):
                rot[k, a, b] = (e3[a, 0] * rot_k[b] + e3[a, 1] * rot_k[3 + b]
                                      + e3[a, 2] * rot_k[6 + b])
        for i in range(n_coordinates(hinge_kind[k])):
            jq[k, i] += f * nu[k, i]
        for i in range(mode_off[k], mode_off[k + 1]):
            eta[i] += f * eta_col[j, i]


@no_alloc_kernel(always_inline=True)
def _residuals(params, loops, state):
    """The rows' positions and rates at the state (loops.g, gd); their largest (|g|, |g'|)."""
    all_bodies = loop_tables.all_bodies(loops)
    all_rows = loop_tables.all_rows(loops)
    kind = loop_tables.kind(loops)
    law = loop_tables.law(loops)
    g = loop_tables.g(loops)
    gd = loop_tables.gd(loops)
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    jq = state_tables.jq(state)
    jqd = state_tables.jqd(state)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    defl = state_tables.defl(state)
    defl_rate = state_tables.defl_rate(state)
    tree_points(params, rot, omega, jq, jqd, eta, eta_d,
                defl, defl_rate, loops, all_bodies)
    row_positions(params, loops, rot, omega, all_rows)
    largest_g, largest_gd = 0.0, 0.0
    for r in range(kind.shape[0]):
        if not _is_force(law, r):           # a drive's force constrains nothing
            largest_g = max(largest_g, abs(g[r]))
            largest_gd = max(largest_gd, abs(gd[r]))
    return largest_g, largest_gd


@kernel
def _constrained(loops, values):
    """-values with a drive's force's rows 0 (the projection moves nothing for them)."""
    law = loop_tables.law(loops)
    kind = loop_tables.kind(loops)
    out = -values
    for r in range(kind.shape[0]):
        if _is_force(law, r):
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
    v = loop_tables.delassus(loops)
    stats = loop_tables.stats(loops)
    gd = loop_tables.gd(loops)
    kind = loop_tables.kind(loops)
    act_idx = loop_tables.act_idx(loops)
    colrow_idx = loop_tables.colrow_idx(loops)
    law = loop_tables.law(loops)
    band = loop_tables.band(loops)
    all_bodies = loop_tables.all_bodies(loops)
    energy = loop_tables.energy(loops)
    coordinate = loop_tables.coordinate(loops)
    wrench = loop_tables.wrench(loops)
    act_ptr = loop_tables.act_ptr(loops)
    colrow_ptr = loop_tables.colrow_ptr(loops)
    g = loop_tables.g(loops)
    target = loop_tables.target(loops)
    owner = loop_tables.owner(loops)
    eta_map = state_tables.eta_map(state)
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    jq = state_tables.jq(state)
    jqd = state_tables.jqd(state)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    defl = state_tables.defl(state)
    defl_rate = state_tables.defl_rate(state)
    n_rows = kind.shape[0]
    e3 = np.empty((3, 3))
    phi = np.empty(3)
    work = np.empty(60)
    _modal_responses(params, loops, eta_map)
    g0, gd0 = _residuals(params, loops, state)
    stats[0] = max(stats[0], g0)
    stats[1] = max(stats[1], gd0)
    # V, column by column, over each row's active bodies and the rows they carry
    base = gd.copy()
    _clear_rows_matrix(loops, v)
    saved = (np.empty((omega.shape[0], 6, max(3, jqd.shape[1]))),
             np.empty(eta_d.shape[0]))
    for j in range(n_rows):
        bodies = act_idx[act_ptr[j + 1]:act_ptr[j + 2]]
        rows = colrow_idx[colrow_ptr[j]:colrow_ptr[j + 1]]
        _keep_rates(params, loops, state, bodies, saved, True)
        _add_rates(params, loops, state, j, 1.0)
        _dependent_frames(params, loops, state, bodies, work)
        tree_points(params, rot, omega, jq, jqd, eta,
                    eta_d, defl, defl_rate, loops, bodies)
        row_positions(params, loops, rot, omega, rows)
        for q in range(rows.shape[0]):
            v[rows[q], j] = gd[rows[q]] - base[rows[q]]
        _keep_rates(params, loops, state, bodies, saved, False)
    put1(gd, base)
    for r in range(n_rows):             # a drive's force's row: mu_r = 0
        if _is_force(law, r):
            v[r, :] = 0.0
            v[:, r] = 0.0
            v[r, r] = 1.0
    banded = band[0] >= 0
    piv = np.empty(n_rows, dtype=np.int64)
    if banded:
        _band_factor(v, band[0], band[1], piv)
    u, sv, vt = np.linalg.svd(np.eye(1) if banded else v)
    largest = g0
    for _ in range(POSITION_PROJECTIONS):
        if largest <= POSITION_TOL:
            break
        mu = (_band_apply(v, band[0], band[1], piv, _constrained(loops, g))
              if banded else _least_apply(u, sv, vt, _constrained(loops, g)))
        for j in range(n_rows):
            _move(params, loops, state, j, mu[j], e3, phi)
        _dependent_frames(params, loops, state, all_bodies, work)
        largest, _ = _residuals(params, loops, state)
    stats[3] = max(stats[3], largest)
    rates = 0.0
    for _ in range(2):
        _, rates = _residuals(params, loops, state)
        if rates <= RATE_TOL:
            break
        mu = (_band_apply(v, band[0], band[1], piv, _constrained(loops, gd))
              if banded else _least_apply(u, sv, vt, _constrained(loops, gd)))
        for j in range(n_rows):
            _add_rates(params, loops, state, j, mu[j])
        _dependent_frames(params, loops, state, all_bodies, work)
        _, rates = _residuals(params, loops, state)
    stats[2] = max(stats[2], rates)
    for r in range(n_rows):             # the driven coordinates' rates (the drives' power)
        if coordinate[r] >= 0:
            wrench[owner[r], 8 + coordinate[r]] = gd[r] + target[r, 1]
    if energy[0] > 0.0:
        _hold_energy(params, loops, state)


@no_alloc_kernel
def _mechanical_energy(params, loops, state):
    """(T, V) of a model of rigid bodies (docs/loops.md, "The energy held"): every body's
    1/2 m |v_C|^2 + 1/2 (A^T w) . J_C (A^T w) and -m g . r_C, its mass centre from its output
    point (tree_points), r_C = r_O + A (l_IC - l_IO), v_C = v_O + w x A (l_IC - l_IO)."""
    all_bodies = loop_tables.all_bodies(loops)
    r_out = loop_tables.r_out(loops)
    v_out = loop_tables.v_out(loops)
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    jq = state_tables.jq(state)
    jqd = state_tables.jqd(state)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    defl = state_tables.defl(state)
    defl_rate = state_tables.defl_rate(state)
    tree_points(params, rot, omega, jq, jqd, eta, eta_d,
                defl, defl_rate, loops, all_bodies)
    bp = model_tables.body_params(params)
    inertia = model_tables.mass_center_inertia(params)
    g, body_row = model_tables.gravity(params), model_tables.body_row(params)
    kinetic, potential = 0.0, 0.0
    for k in range(body_row.shape[0]):
        row = body_row[k]
        rot_k = _m9(rot, k)
        w = _v3(omega, k)
        arm = t_mv(rot_k, (bp[row, 1] - bp[row, 4], bp[row, 2] - bp[row, 5],
                           bp[row, 3] - bp[row, 6]))
        r_c = _add(_v3(r_out, k), arm)
        v_c = _add(_v3(v_out, k), t_cross(w, arm))
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
    energy = loop_tables.energy(loops)
    omega = state_tables.omega(state)
    defl_rate = state_tables.defl_rate(state)
    jqd = state_tables.jqd(state)
    kinetic, potential = _mechanical_energy(params, loops, state)
    want = energy[1] - potential
    if not (kinetic > 0.0 and want > 0.0):
        return
    s = np.sqrt(want / kinetic)
    if abs(s - 1.0) > ENERGY_STEP_LIMIT:
        return
    energy[2] = max(energy[2], abs(s - 1.0))
    hinge_kind = model_tables.hinge_kind(params)
    for k in range(hinge_kind.shape[0]):
        for i in range(3):
            omega[k, i] *= s
            defl_rate[k, i] *= s
        for i in range(n_coordinates(hinge_kind[k])):
            jqd[k, i] *= s

