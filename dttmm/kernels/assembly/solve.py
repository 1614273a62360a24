"""One step's boundary solve on the elements' transfers, by the sweep a run's mode names
(docs/assembly.md): the full-state Riccati sweep of a chain (RICCATI_FULL) or of a tree with
joints with coordinates (RICCATI_JOINTS), the reduced sweeps of ball chains and trees
(RICCATI_REDUCED, RICCATI_TREE), and the paper's direct products (DIRECT_FULL, DIRECT_REDUCED).
The general loop (kernels/stepping/step.py) and the energy-momentum step call solve_step.
"""
import numpy as np

from .. import allocating_kernel, kernel, sweep_tables
from ..algebra.mat3 import put1
from .sweep import direct_full, direct_reduced, fold_ball_body, riccati_full, riccati_reduced
from .tree_sweep import riccati_tree_full, riccati_tree_reduced, write_tree_stations

RICCATI_FULL, RICCATI_REDUCED, DIRECT_REDUCED, DIRECT_FULL, RICCATI_TREE, RICCATI_JOINTS = range(6)

# a sweep mode no sweep implements (the solver's mistake, never the user's)
_UNKNOWN_SWEEP = "unknown sweep mode (kernels/assembly/sweep.py)"


@allocating_kernel
def solve_step(mode, tip_pinned, parent, sweep, root_f, z):
    """Solve the assembled step (sweep.kind, sweep.u, sweep.known_loads) into z (the stations'
    states) by the mode's sweep; returns 0 or a singularity code (sweep.py).  parent: the
    bodies' parents (RICCATI_TREE; a chain's are k - 1)."""
    sw = sweep
    red_aq = sweep_tables.red_aq(sw)
    red_phi = sweep_tables.red_phi(sw)
    kind = sweep_tables.kind(sw)
    u = sweep_tables.u(sw)
    known_loads = sweep_tables.known_loads(sw)
    joint_dof = sweep_tables.joint_dof(sw)
    joint_tau_nu = sweep_tables.joint_tau_nu(sw)
    s = sweep_tables.s(sw)
    p = sweep_tables.p(sw)
    tree_s = sweep_tables.tree_s(sw)
    tree_p = sweep_tables.tree_p(sw)
    joint_nu = sweep_tables.joint_nu(sw)
    joint_tau = sweep_tables.joint_tau(sw)
    split = sweep_tables.split(sw)
    tinv = sweep_tables.tinv(sw)
    t = sweep_tables.t(sw)
    g = sweep_tables.g(sw)
    gv = sweep_tables.gv(sw)
    dir_z = sweep_tables.dir_z(sw)
    dir_o = sweep_tables.dir_o(sw)
    red_v = sweep_tables.red_v(sw)
    red_s = sweep_tables.red_s(sw)
    red_p = sweep_tables.red_p(sw)
    red_tinv = sweep_tables.red_tinv(sw)
    red_t = sweep_tables.red_t(sw)
    if mode == RICCATI_JOINTS:
        return riccati_tree_full(kind, u, known_loads, joint_dof, joint_tau_nu,
                                 parent, root_f, s, p, tree_s, tree_p, joint_nu,
                                 joint_tau, z)
    if mode == RICCATI_FULL:
        return riccati_full(kind, u, known_loads, root_f, tip_pinned, split, s,
                            p, tinv, t, g, gv, z)
    if mode == DIRECT_FULL:
        return direct_full(kind, u, known_loads, root_f, tip_pinned, dir_z,
                           dir_o, gv, g, z)
    if mode not in (RICCATI_TREE, RICCATI_REDUCED, DIRECT_REDUCED):
        raise ValueError(_UNKNOWN_SWEEP)
    n = red_v.shape[0]
    for k in range(n):
        fold_ball_body(u[2 * k + 1], red_v[k], red_phi[k])
    if mode == RICCATI_TREE:
        return _solve_tree(sw, parent, root_f, z)
    if mode == RICCATI_REDUCED:
        status = riccati_reduced(red_v, root_f[0:3], tip_pinned, red_s, red_p,
                                 red_tinv, red_t, red_aq)
    elif mode == DIRECT_REDUCED:
        status = direct_reduced(red_v, root_f[0:3], tip_pinned, red_aq)
    else:
        raise ValueError(_UNKNOWN_SWEEP)
    if status != 0:
        return status
    z[:, :] = 0.0
    put1(z[0, 0:6], root_f[0:6])
    put1(z[0, 9:12], red_aq[0, 3:6])
    for k in range(n):
        for i in range(3):
            phi = red_phi[k, i, 6]
            for c in range(6):
                phi += red_phi[k, i, c] * red_aq[k, c]
            z[2 * k + 1, 3 + i] = phi
            z[2 * k + 2, 3 + i] = phi
        put1(z[2 * k + 1, 0:3], red_aq[k, 0:3])
        put1(z[2 * k + 1, 9:12], red_aq[k, 3:6])
        put1(z[2 * k + 2, 0:3], red_aq[k + 1, 0:3])
        put1(z[2 * k + 2, 9:12], red_aq[k + 1, 3:6])
    return 0


@kernel
def _solve_tree(sw, parent, root_f, z):
    """The reduced tree sweep (kernels/stepping/tree.py) on the folded maps, into z."""
    red_v = sweep_tables.red_v(sw)
    red_s = sweep_tables.red_s(sw)
    red_p = sweep_tables.red_p(sw)
    red_tinv = sweep_tables.red_tinv(sw)
    port_s = sweep_tables.port_s(sw)
    port_p = sweep_tables.port_p(sw)
    red_aq = sweep_tables.red_aq(sw)
    aq_out = sweep_tables.aq_out(sw)
    red_phi = sweep_tables.red_phi(sw)
    n = red_v.shape[0]
    status = riccati_tree_reduced(red_v, parent, root_f[0:3], red_s, red_p, red_tinv,
                                  port_s, port_p, red_aq, aq_out)
    if status != 0:
        return status
    phi = np.empty((n, 3))
    for k in range(n):
        for i in range(3):
            x = red_phi[k, i, 6]
            for c in range(6):
                x += red_phi[k, i, c] * red_aq[k, c]
            phi[k, i] = x
    write_tree_stations(parent, root_f[0:3], root_f[3:6], red_aq, aq_out, phi, z)
    return 0
