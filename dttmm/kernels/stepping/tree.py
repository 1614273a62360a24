"""The fused loop variant for trees of rigid bodies and beams joined by ball joints: every
body's reduced map (kernels/stepping/ball_chain.py::ball_body_map,
kernels/transfers/beam.py::beam_ball_map) goes straight into the leaves-to-root sweep
(kernels/assembly/tree_sweep.py, "Trees"; docs/assembly.md, "Trees"), then the recovery
from the root to the leaves: a root on the ground moves with it, a root on a free joint (the
high-order scheme's, docs/free_joint.md) carries no load, q_I = 0, which gives its acceleration.
Predict, adopt and update are the fused chain loop's (they do not
depend on the topology)."""
from .. import (fused_tables, input_tables, loop_piece, model_tables, record_tables, state_tables,
                sweep_tables)
from ...elements import BEAM, RIGID
from ...elements.hinges import FREE
from .ball_chain import (_adopt, _ground_increment, _predict, _update, ball_body_map, fused_loop,
                         record_state, recover_body)
from ..schema import FlatFusedTree
from ..transfers.beam import beam_ball_map
from .loop import NOT_FINITE, OK, SINGULAR, UNSUPPORTED, loop_variant
from ..algebra.mat3 import mm3_into, t_inverse, t_mv, t_of_mat
from ..algebra.so3 import expm_so3, left_jacobian
from ..assembly.tree_sweep import (_add_to_port, _clear_ports, tree_reduced_recover,
                                   tree_reduced_step, write_tree_stations)


def fused_tree_loop(n, parent, mode_off, h, coef):
    """The fused tree loop's scratch for n bodies with parents `parent`: the fused chain loop's
    (kernels/stepping/ball_chain.py::fused_loop, whose predict, adopt and update pieces it
    shares) with the tree sweep's tables (kernels/schema.py::FUSED; a FlatFusedTree)."""
    loop = fused_loop(n, mode_off, h, coef, tree=True)
    loop.parent[:] = parent
    return loop


@loop_piece
def _iterate(loop, run, s, it):
    """Every body's map and its step of the sweep, from the leaves to the root; then the
    recovery from the root to the leaves, with each body's angular (and a beam's modal)
    accelerations.  Returns (status, detail, change)."""
    parent = fused_tables.parent(loop)
    mats = fused_tables.mats(loop)
    vecs = fused_tables.vecs(loop)
    pmap = fused_tables.pmap(loop)
    maps = fused_tables.maps(loop)
    aq_out = fused_tables.aq_out(loop)
    s_in = fused_tables.s_in(loop)
    p_in = fused_tables.p_in(loop)
    t_inv = fused_tables.t_inv(loop)
    port_s = fused_tables.port_s(loop)
    port_p = fused_tables.port_p(loop)
    coefficients = fused_tables.coefficients(loop)
    per_body = fused_tables.per_body(loop)
    per_mode = fused_tables.per_mode(loop)
    beam_work = fused_tables.beam_work(loop)
    aq_in = sweep_tables.red_aq(run.sweep)
    params, state, inputs = run.params, run.state, run.inputs
    force = input_tables.force(inputs)
    torque = input_tables.torque(inputs)
    line_load = input_tables.line_load(inputs)
    g_acc = input_tables.g_acc(inputs)
    eta_map = state_tables.eta_map(state)
    rot_ = state_tables.rot(state)
    c1, c3, s_c, r_c = coefficients[0], coefficients[1], coefficients[2], coefficients[3]
    w1, w3, phi_star, phi_new = per_body[0], per_body[1], per_body[2], per_body[3]
    t_buf, num_buf, e3, rot_star, lam = mats[0], mats[1], mats[2], mats[3], mats[4]
    w, wd, alpha, load = vecs[0], vecs[1], vecs[2], vecs[3]
    w1e, w3e, eta_dd_star, eta_dd_new = per_mode[0], per_mode[1], per_mode[3], per_mode[4]
    body_params, body_row = model_tables.body_params(params), model_tables.body_row(params)
    gravity, rot = model_tables.gravity(params), rot_
    body_kind = model_tables.body_kind(params)
    beam_params = model_tables.beam_params(params)
    beam_moments = model_tables.beam_moments(params)
    mode_off = model_tables.mode_offset(params)
    beam_ends = model_tables.beam_ends(params)
    beam_factors = model_tables.beam_factors(params)
    n = rot.shape[0]
    _clear_ports(port_s, port_p)
    for k in range(n - 1, -1, -1):
        phi = phi_star[k]
        for i in range(3):
            w[i] = c3 * phi[i] + w3[k, i]
            wd[i] = c1 * phi[i] + w1[k, i]
        if body_kind[k] == BEAM:                # (its own kinematics: kernels/transfers/beam.py)
            i0, i1 = mode_off[k], mode_off[k + 1]
            m = (i1 - i0) // 2              # (no twist here: Model.has_twist runs general)
            tables = (beam_moments[k, :m, :4 * m + 2], beam_ends[k, :m], beam_factors[k, :m],
                      force[s, k], torque[s, k], line_load[s, k])   # (docs/beam.md)
            beam_ball_map(beam_params[k], tables, gravity, rot[k], phi, wd, coefficients,
                          w3[k], w1e[i0:i1], w3e[i0:i1], aq_in[k, 0:3], aq_in[k, 3:6],
                          eta_dd_star[i0:i1], beam_work, maps[k], pmap[k], eta_map[i0:i1])
        elif body_kind[k] == RIGID:
            expm_so3(phi, e3)
            mm3_into(e3, rot[k], rot_star)
            left_jacobian(phi, lam)
            row = body_row[k]         # (the body's row of the shared table)
            for i in range(3):
                load[i] = body_params[row, 0] * gravity[i] + force[s, k, i]
            ball_body_map(body_params[row], rot_star, lam, w, wd, s_c, r_c, aq_in[k, 0:3],
                          aq_in[k, 3:6], load, torque[s, k], maps[k], pmap[k])
        else:
            return UNSUPPORTED, 2 * k + 2, 0.0
        if tree_reduced_step(maps[k], port_s[k], port_p[k], s_in[k], p_in[k], t_inv[k], t_buf,
                             num_buf) == 0.0:
            return SINGULAR, k + 1, 0.0
        if parent[k] >= 0:
            _add_to_port(s_in[k], p_in[k], port_s[parent[k]], port_p[parent[k]])
    change = 0.0
    finite = True
    hinge_kind = model_tables.hinge_kind(params)
    for k in range(n):
        p = parent[k]
        if p < 0 and hinge_kind[k] == FREE:     # q_I = S_I a_I + P_I = 0: a_I = -S_I^-1 P_I
            det, g = t_inverse(t_of_mat(s_in[k]))
            if det == 0.0:
                return SINGULAR, k + 1, 0.0
            a_free = t_mv(g, (p_in[k, 0], p_in[k, 1], p_in[k, 2]))
            tree_reduced_recover(maps[k], s_in[k], p_in[k], -a_free[0], -a_free[1],
                                 -a_free[2], aq_in[k], aq_out[k])
        elif p < 0:
            tree_reduced_recover(maps[k], s_in[k], p_in[k], g_acc[s, 0],
                                 g_acc[s, 1], g_acc[s, 2], aq_in[k], aq_out[k])
        else:
            tree_reduced_recover(maps[k], s_in[k], p_in[k], aq_out[p, 0], aq_out[p, 1],
                                 aq_out[p, 2], aq_in[k], aq_out[k])
        change, finite = recover_body(pmap[k], aq_in[k], w1[k], c1, phi_star[k], phi_new[k],
                                      body_kind[k] == BEAM, mode_off[k], mode_off[k + 1],
                                      eta_map, eta_dd_star, eta_dd_new, alpha, change, finite)
    if not finite:
        return NOT_FINITE, 0, change
    return OK, 0, change


@loop_piece
def _write(loop, run, s, z):
    vecs = fused_tables.vecs(loop)
    parent = fused_tables.parent(loop)
    aq_out = fused_tables.aq_out(loop)
    mats = fused_tables.mats(loop)
    per_body = fused_tables.per_body(loop)
    g_rot = input_tables.g_rot(run.inputs)
    g_acc = input_tables.g_acc(run.inputs)
    red_aq = sweep_tables.red_aq(run.sweep)
    phi_g = vecs[4]
    _ground_increment(g_rot, s, mats[6], phi_g)
    write_tree_stations(parent, g_acc[s], phi_g, red_aq, aq_out,
                        per_body[3], z)


@loop_piece
def _record(loop, run, s, slot):
    z = record_tables.z(run.rec)
    _write(loop, run, s, z[slot])
    record_state(run.state, run.rec, slot)


@loop_piece
def _finish(loop, run, n_steps, _):
    z = state_tables.z(run.state)
    if n_steps > 0:
        _write(loop, run, n_steps - 1, z)


loop_variant(FlatFusedTree, predict=_predict, iterate=_iterate, adopt=_adopt, update=_update,
             record=_record, finish=_finish)
