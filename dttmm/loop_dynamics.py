"""DT-TMM's accelerations of a model with closed loops, by the tree's sweep and the closing
joints' multipliers (docs/loops.md, "The sweep with closing joints").

The sweep of the spanning tree is linear in the loads applied to it.  Each scalar constraint r
of a closing joint (closures.constraint_directions) acts on its sides through one multiplier
lam_r: a force lam_r e on side b at its point and its reaction on side a (a gap row), or a
couple lam_r (y x x) on b and its reaction on a (a dot row).  One sweep without them and one per
row with lam_r = 1 give every acceleration as an affine function of the multipliers,

    x(lam) = x_0 + sum_r lam_r (x_r - x_0),

and the rows' acceleration-level conditions, g''_r(x) = 0, are R equations in R unknowns:
C lam = -g''(x_0) with C[:, r] = g''(x_r) - g''(x_0), the Delassus matrix seen through the
sweep.  It is solved by a truncated SVD (the least multipliers where rows are redundant, as a
planar loop's spatial joints are).  This is the consistent start of a run with loops and the
acceleration level the time step will close its loops at; the sweeps here are the consistent
start's own (kernels/step.py::initial_accelerations), one per row, which the step will replace
by responses carried along the paths to the closing joints.
"""
from dataclasses import replace

import numpy as np

from .closures import GROUND, constraint_directions, tree_state
from .elements import BEAM
from .elements.rigid_body import TO_MASS_CENTER

LOOP_RCOND = 1e-10        # the Delassus matrix's singular values below this fraction are cut


def _constant(value):
    value = np.array(value, dtype=float)
    return lambda t: value


def _side_kinematics(model, state, c, s):
    """(body, point, velocity, arm from the input point, frame, angular velocity) of closing
    joint c's side s at t = 0, from the tree's kinematics (closures.tree_state)."""
    rot, w, r_in, v_in = state[:4]
    k, local = int(model.closure_body[c, s]), model.closure_point[c, s]
    if k == GROUND:
        r_g, v_g, _, rot_g, w_g, _ = model.ground_state(0.0)
        arm = rot_g @ local
        return k, r_g + arm, v_g + np.cross(w_g, arm), arm, rot_g, w_g
    arm = rot[k] @ local
    return k, r_in[k] + arm, v_in[k] + np.cross(w[k], arm), arm, rot[k], w[k]


def _rows(model, state):
    """Every scalar constraint at t = 0: (closing joint, kind, e or x, y) with its sides'
    kinematics, and for each the loads a unit multiplier applies: [(body, force, point)],
    [(body, couple)]."""
    rows = []
    for c in range(model.n_closures):
        side_a = _side_kinematics(model, state, c, 0)
        side_b = _side_kinematics(model, state, c, 1)
        points, dots = constraint_directions(model, c)
        for frame, e in points:
            e = side_a[4] @ e if frame == "a" else e
            forces = [(side_b[0], e, side_b[1]), (side_a[0], -e, side_b[1])]
            rows.append(("a" if frame == "a" else "w", e, None, side_a, side_b, forces, []))
        for x, y in dots:
            x, y = side_a[4] @ x, side_b[4] @ y
            couple = np.cross(y, x)
            rows.append(("dot", x, y, side_a, side_b, [], [(side_b[0], couple),
                                                          (side_a[0], -couple)]))
    return rows


def _row_values(rows, acc, alpha, ground):
    """g''_r of every row from the bodies' input-point accelerations acc (n, 3) and angular
    accelerations alpha (n, 3) (docs/loops.md, "Constraints")."""
    a_g, wd_g = ground
    out = np.zeros(len(rows))

    def point(side):
        k, _, _, arm, _, w = side
        if k == GROUND:
            return a_g + np.cross(wd_g, arm) + np.cross(w, np.cross(w, arm)), wd_g
        return acc[k] + np.cross(alpha[k], arm) + np.cross(w, np.cross(w, arm)), alpha[k]

    for r, (kind, e, y, side_a, side_b, _, _) in enumerate(rows):
        acc_a, al_a = point(side_a)
        acc_b, al_b = point(side_b)
        w_a, w_b = side_a[5], side_b[5]
        if kind == "dot":
            x = e
            out[r] = (np.cross(y, x) @ (al_b - al_a)
                      + (w_b - w_a) @ (np.cross(np.cross(w_b, y), x)
                                       + np.cross(y, np.cross(w_a, x))))
        else:
            out[r] = e @ (acc_b - acc_a)
            if kind == "a":                 # e turns with side a
                d, dd = side_b[1] - side_a[1], side_b[2] - side_a[2]
                we = np.cross(w_a, e)
                out[r] += np.cross(e, d) @ al_a + np.cross(w_a, we) @ d + 2.0 * (we @ dd)
    return out


def loop_accelerations(model):
    """DT-TMM's accelerations at t = 0 of a model with closing joints (the module docstring).

    Parameters
    ----------
    model : Model
        An assembled model (``dttmm.assemble``) whose closing joints join rigid bodies or the
        ground (beams in loops: not yet).

    Returns
    -------
    dict
        ``angular_acceleration`` (n, 3, rad/s^2), ``input_acceleration`` (n, 3, m/s^2, each
        body's input point), ``joint_acceleration`` (n, 2: each joint coordinate's), the
        multipliers ``multipliers`` (R,) and the rows' residual ``residual`` (R,, m/s^2 or
        rad/s^2) after the solve.

    Raises
    ------
    ValueError
        A closing joint on a beam (not yet).
    """
    from . import solver
    from .kernels.loop import Monitor, Settings
    for c in range(model.n_closures):
        for k in model.closure_body[c]:
            if k >= 0 and model.body_kind[k] == BEAM:
                raise ValueError(f"loop_accelerations: closing joint '{model.closure_names[c]}' "
                                 f"joins beam '{model.body_names[k]}': beams in loops do not "
                                 f"run in DT-TMM yet")
    state = tree_state(model, np.zeros((model.n_bodies, 3)), model.hinge_params[:, 51:53],
                       model.initial_angular_velocity, model.hinge_params[:, 53:55])
    rows = _rows(model, state)
    rot, r_in = state[0], state[2]
    km, keep = solver.kernel_model(model)
    mode = solver._mode(km, "riccati", True)
    settings = Settings(mode=mode, h=1.0, coef=solver.Integrator.from_rho_inf(1.0).array(),
                        newton_max=0, newton_tol=0.0, record_every=1, max_step_error=np.inf,
                        stop_unconverged=False, start=False)
    n_k = km.n_bodies
    monitor = Monitor(pseudo=np.zeros((n_k, 3)), eta_p=np.zeros(int(km.n_modes.sum())),
                      jqp=np.zeros((n_k, 2)), defl_pseudo=np.zeros((0, 3)), error=np.zeros(2))
    base_force, base_torque = solver._loads(km, [0.0])[:2]
    base_force, base_torque = base_force[0], base_torque[0]

    def sweep(forces, couples):
        """One consistent start with extra loads: [(body, force, point)], [(body, couple)]."""
        force, torque = base_force.copy(), base_torque.copy()
        for k, f, p in forces:
            if k >= 0:
                r_c = r_in[k] + rot[k] @ model.body_params[k, TO_MASS_CENTER]
                force[keep[k]] += f
                torque[keep[k]] += np.cross(p - r_c, f)
        for k, m in couples:
            if k >= 0:
                torque[keep[k]] += m
        loaded = replace(km, forces=tuple(map(_constant, force)),
                         torques=tuple(map(_constant, torque)))
        ws = solver.Workspace(loaded)
        params = solver.kernel_params(loaded, ws.beams)
        solver._consistent_start(loaded, mode, "riccati", None, params, settings, ws.state,
                                 ws.sweep, monitor, 1.0)
        st = ws.state
        return (st.z[2 * keep + 1, 0:3].copy(), st.omega_dot[keep].copy(),
                st.jqdd[keep].copy())

    g_acc, _, g_w, g_wd = (x[0] for x in solver._ground(model, [0.0]))
    ground = (g_acc, g_wd)
    base = sweep([], [])
    v0 = _row_values(rows, base[0], base[1], ground)
    responses = [sweep(row[5], row[6]) for row in rows]
    delassus = np.column_stack([_row_values(rows, x[0], x[1], ground) - v0
                                for x in responses]) if rows else np.zeros((0, 0))
    lam = -np.linalg.pinv(delassus, rcond=LOOP_RCOND) @ v0 if rows else np.zeros(0)
    out = [b + sum(l_r * (x[i] - b) for l_r, x in zip(lam, responses))
           for i, b in enumerate(base)]
    return {"input_acceleration": out[0], "angular_acceleration": out[1],
            "joint_acceleration": out[2], "multipliers": lam,
            "residual": _row_values(rows, out[0], out[1], ground)}
