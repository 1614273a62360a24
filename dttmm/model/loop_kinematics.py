"""The closed loops' kinematics on the Python side (docs/loops.md): the sides' points and frames
and their motions, the tree's state from its coordinates, the loops' residuals and rank, and the
coordinates, state and rate Jacobian that closing the loops at t = 0 (model/assembly.py) and
the drives' check solve over.  The table of closing joints is built in closures.py.
"""
import numpy as np

from ..elements import BALL, ELASTIC, FIXED
from ..elements.hinges import (C_ROTATION, C_TRANSLATION, DEFLECTION_0, DEFLECTION_RATE_0,
                               K_ROTATION, K_TRANSLATION, REST_ROTATION)
from ..elements.kinds import (ANGLE_A, ANGLE_B, COORDINATE_0, DEFLECTING, DOT, FLEXIBLE, GAP_A,
                              RATE_0, RIGID,
                              SLIDE, WITH_COORDINATES, WITH_SLIDES, coordinates_of, joint_motion,
                              row_axes, unimplemented_body_kind)
from ..elements.drives import FORCE, MOTION, SPRING_DAMPER
from ..elements.rigid_body import TO_OUTPUT
from .loop_rows import GROUND, closure_targets, constraint_rows, has_closure_drives
from .sections import element_end_section, element_output_offset, log_rotation


def start_state(model):
    """The tree's kinematics at t = 0 (tree_state at the model's own coordinates and rates)."""
    return tree_state(model, np.zeros((model.n_bodies, 3)), model.hinge_params[:, COORDINATE_0],
                      model.initial_angular_velocity, model.hinge_params[:, RATE_0])


def start_attachment(model, k):
    """(r, v, F, w) at t = 0 of body k's attachment point: its position and velocity, the
    frame its joint is fixed in (the parent's output section, or the ground's) and that
    frame's angular velocity."""
    state = start_state(model)
    return _attachment(model, k, model.ground_state(0.0), *state)


def _attachment(model, k, ground, rot, w, r_in, v_in, rot_o, w_o, r_o, v_o):
    """(r, v, F, w) of body k's attachment point from its parent's motion (tree_state's
    arrays, filled for the bodies before k) or the ground's (model.ground_state)."""
    p = model.parent[k]
    r_g, v_g, _, rot_g, w_g, _ = ground
    if p < 0:               # its place on the ground
        arm = rot_g @ model.attachment_point[k]
        return r_g + arm, v_g + np.cross(w_g, arm), rot_g, w_g
    if model.attachment[k] == 0:
        return r_o[p], v_o[p], rot_o[p], w_o[p]
    arm = rot[p] @ model.attachment_point[k]
    return r_in[p] + arm, v_in[p] + np.cross(w[p], arm), rot[p], w[p]


def closure_points(model):
    """(p_a, p_b, F_a, F_b) at t = 0 of every closing joint: world points (m) and frames."""
    state = start_state(model)
    sides = [[_side_motion(model, state, c, s) for s in range(2)]
             for c in range(model.n_closures)]
    p = np.array([[side[0] for side in pair] for pair in sides]).reshape(-1, 2, 3)
    f = np.array([[side[2] for side in pair] for pair in sides]).reshape(-1, 2, 3, 3)
    return p[:, 0], p[:, 1], f[:, 0], f[:, 1]


def closure_gaps(model):
    """(m,) each closing joint's positional gap at t = 0, m: |p_b - p_a| (a joint with slides'
    across its slides' axes, which are perpendicular)."""
    p_a, p_b, f_a, _ = closure_points(model)
    gap = p_b - p_a
    for c in np.nonzero(np.isin(model.closure_kind, WITH_SLIDES))[0]:
        axes = row_axes(model.closure_params[c])
        for spec in coordinates_of(model.closure_kind[c]):
            if spec.motion == SLIDE:
                u = f_a[c] @ axes[spec.axis]
                gap[c] = gap[c] - u * (u @ gap[c])
    return np.linalg.norm(gap, axis=1)


def side_motions(model, c, s, rotation, omega, r_in, v_in, eta, eta_dot, ground):
    """(p, v, F, w) of closing joint c's side s at T recorded states: its point, the point's
    velocity, the side's frame and angular velocity, (T, ...) each.  rotation, omega, r_in,
    v_in: (T, n, ...) the bodies'; eta, eta_dot (T, total modes) the beams' and strain rods'
    (None without); ground: (r, v, rot, w) of the ground frame, (T, ...) each."""
    k, local = model.closure_body[c, s], model.closure_point[c, s]
    if k == GROUND:
        r_g, v_g, rot_g, w_g = ground
        arm = rot_g @ local
        return r_g + arm, v_g + np.cross(w_g, arm), rot_g, w_g
    rot, w = rotation[:, k], omega[:, k]
    if model.closure_on_end[c, s]:      # a beam's or rod's output end: its deflected end section
        i0 = int(np.sum(model.n_modes[:k]))
        e, e_d = eta[:, i0:i0 + model.n_modes[k]], eta_dot[:, i0:i0 + model.n_modes[k]]
        rho, rate = element_output_offset(model, k, rot, w, e, e_d)
        sections = [element_end_section(model, k, rot[t], w[t], e[t], e_d[t])
                    for t in range(len(rot))]
        return (r_in[:, k] + rho, v_in[:, k] + rate, np.array([f for f, _ in sections]),
                np.array([w_o for _, w_o in sections]))
    arm = rot @ local
    return r_in[:, k] + arm, v_in[:, k] + np.cross(w, arm), rot, w


def elastic_closure_terms(model, rotation, omega, r_in, v_in, eta, eta_dot, ground):
    """(strain, power), (T,) each: the closing elastic hinges' spring energy
    1/2 d . K_t d + 1/2 psi . K_r psi and their dampers' power -(d' . C_t d' + w_r . C_r w_r),
    with d = F_a^T (p_b - p_a), d' = F_a^T (v_b - v_a - w_a x (p_b - p_a)) its rate in a's
    frame, psi = log(F_a^T F_b R0^T), w_r = F_a^T (w_b - w_a) (docs/loops.md, "An elastic
    hinge closing a loop"); arguments as side_motions'."""
    n_t = len(rotation)
    strain, power = np.zeros(n_t), np.zeros(n_t)
    for c in np.nonzero(model.closure_kind == ELASTIC)[0]:
        h = model.closure_params[c]
        (p_a, v_a, f_a, w_a), (p_b, v_b, f_b, w_b) = (
            side_motions(model, c, s, rotation, omega, r_in, v_in, eta, eta_dot, ground)
            for s in range(2))
        gap = p_b - p_a
        d = np.einsum("tji,tj->ti", f_a, gap)
        d_rate = np.einsum("tji,tj->ti", f_a, v_b - v_a - np.cross(w_a, gap))
        w_r = np.einsum("tji,tj->ti", f_a, w_b - w_a)
        r0 = h[REST_ROTATION].reshape(3, 3)
        psi = np.array([log_rotation(f_a[t].T @ f_b[t] @ r0.T) for t in range(n_t)]).reshape(n_t, 3)
        k_t, k_r = h[K_TRANSLATION].reshape(3, 3), h[K_ROTATION].reshape(3, 3)
        c_t, c_r = h[C_TRANSLATION].reshape(3, 3), h[C_ROTATION].reshape(3, 3)
        strain += 0.5 * (np.einsum("ti,ij,tj->t", d, k_t, d)
                         + np.einsum("ti,ij,tj->t", psi, k_r, psi))
        power -= (np.einsum("ti,ij,tj->t", d_rate, c_t, d_rate)
                  + np.einsum("ti,ij,tj->t", w_r, c_r, w_r))
    return strain, power


def wrap_angle(a):
    """a folded into [-pi, pi)."""
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def tree_state(model, theta, q, omega, qd, stretch_rate=None):
    """The tree's kinematics from its coordinates: theta (n, 3), each free body's rotation
    change (A = exp(theta^) A_0, a ball joint's or an elastic hinge's body), q (n, 3) the
    joints' coordinates, omega (n, 3) the free bodies' angular velocities, qd (n, 3) the
    joints' rates (rows of other bodies unused).  Returns (rot, w, r_in, v_in, rot_o, w_o, r_o,
    v_o), each (n, ...): rotations, angular velocities, input points and their velocities, and
    the output sections and points (a beam's or strain rod's deflected end; the beams' modal
    coordinates, the rods' strain coordinates, their rates and the elastic hinges' deflections
    are the model's).  stretch_rate (n,), optional: each flexible body's output point also moves
    along its chord at this rate, m/s, and all that hangs from it with it (held_chords)."""
    from ..kernels.algebra.so3 import expm_so3
    n = model.n_bodies
    off = np.concatenate([[0], np.cumsum(model.n_modes)])
    rot, w = np.zeros((n, 3, 3)), np.zeros((n, 3))
    r_in, v_in = np.zeros((n, 3)), np.zeros((n, 3))
    rot_o, w_o = np.zeros((n, 3, 3)), np.zeros((n, 3))
    r_o, v_o = np.zeros((n, 3)), np.zeros((n, 3))
    ground = model.ground_state(0.0)
    e3 = np.empty((3, 3))
    for k in range(n):
        kind, h = int(model.hinge_kind[k]), model.hinge_params[k]
        r_att, v_att, f_in, w_in = _attachment(model, k, ground, rot, w, r_in, v_in, rot_o, w_o,
                                               r_o, v_o)
        r0 = h[REST_ROTATION].reshape(3, 3)
        d, d_rate = np.zeros(3), np.zeros(3)
        if kind in WITH_COORDINATES:                # elements/kinds.py::joint_motion
            rot[k], w[k], d, d_rate, _ = joint_motion(kind, row_axes(h), r0, f_in, w_in, q[k],
                                                      qd[k])
        elif kind == FIXED:
            rot[k], w[k] = f_in @ r0, w_in
        elif kind == BALL or kind in DEFLECTING:    # free rotation
            expm_so3(np.ascontiguousarray(theta[k], dtype=float), e3)
            rot[k], w[k] = e3 @ model.initial_rotation[k], omega[k]
            if kind in DEFLECTING:      # the deflection or flight, as given (world)
                d, d_rate = h[DEFLECTION_0], h[DEFLECTION_RATE_0]
        else:
            raise ValueError(f"tree_state: joint '{model.hinge_names[k]}' has no kinematics "
                             f"here (kind {kind})")
        r_in[k], v_in[k] = r_att + d, v_att + d_rate
        eta = model.initial_modal_coordinates[off[k]:off[k + 1]]
        eta_d = model.initial_modal_velocities[off[k]:off[k + 1]]
        if model.body_kind[k] in FLEXIBLE:      # its end section and deflected end point
            rot_o[k], w_o[k] = element_end_section(model, k, rot[k], w[k], eta, eta_d)
            rho, rho_rate = element_output_offset(model, k, rot[k], w[k], eta, eta_d)
            if stretch_rate is not None and stretch_rate[k]:
                rho_rate = rho_rate + stretch_rate[k] * rho / np.linalg.norm(rho)
        elif model.body_kind[k] == RIGID:       # its own frame, its output point
            rot_o[k], w_o[k] = rot[k], w[k]
            rho = rot[k] @ model.body_params[k, TO_OUTPUT]
            rho_rate = np.cross(w[k], rho)
        else:
            raise unimplemented_body_kind(model.body_kind[k], f"body '{model.body_names[k]}'",
                                          "the loops' kinematics (model/loop_kinematics.py)")
        r_o[k], v_o[k] = r_in[k] + rho, v_in[k] + rho_rate
    return rot, w, r_in, v_in, rot_o, w_o, r_o, v_o


def _side_motion(model, state, c, s):
    """(point, its velocity, frame, its angular velocity) of closing joint c's side s."""
    rot, w, r_in, v_in, rot_o, w_o, r_o, v_o = state
    k, local = model.closure_body[c, s], model.closure_point[c, s]
    if k == GROUND:
        r_g, v_g, _, rot_g, w_g, _ = model.ground_state(0.0)
        arm = rot_g @ local
        return r_g + arm, v_g + np.cross(w_g, arm), rot_g, w_g
    if model.closure_on_end[c, s]:
        return r_o[k], v_o[k], rot_o[k], w_o[k]
    arm = rot[k] @ local
    return r_in[k] + arm, v_in[k] + np.cross(w[k], arm), rot[k], w[k]


def closure_residuals(model, state, t=0.0):
    """(g, g') over every closing joint's rows (constraint_rows: its constraints, then its
    driven coordinates less their prescribed motion at time t; 0 for a SpringDamper's or a
    JointForce's, which constrain nothing), at the tree's state (tree_state): positions (m,
    or dimensionless for the dots, rad for the angles) and their rates, and the index of the
    closing joint of each row."""
    rows = constraint_rows(model)
    targets = (closure_targets(model, [t], rows)[0] if has_closure_drives(model)
               else np.zeros((len(rows.kind), 3)))
    sides = [(_side_motion(model, state, c, 0), _side_motion(model, state, c, 1))
             for c in range(model.n_closures)]
    g, gd = np.zeros(len(rows.kind)), np.zeros(len(rows.kind))
    for r, kind in enumerate(rows.kind):
        if rows.law[r, 0] in (SPRING_DAMPER, FORCE):    # a drive's force: no constraint
            continue
        (p_a, v_a, f_a, w_a), (p_b, v_b, f_b, w_b) = sides[rows.owner[r]]
        if kind == DOT:
            x, y = f_a @ rows.v1[r], f_b @ rows.v2[r]
            g[r], gd[r] = x @ y, (w_b - w_a) @ np.cross(y, x)
        elif kind in (ANGLE_A, ANGLE_B):
            x, y = f_a @ rows.v1[r], f_b @ rows.v2[r]
            n = (f_a if kind == ANGLE_A else f_b) @ rows.v3[r]
            g[r] = wrap_angle(np.arctan2(n @ np.cross(x, y), x @ y) - targets[r, 0])
            gd[r] = n @ (w_b - w_a) - targets[r, 1]
        elif kind == GAP_A:                             # e turns with side a
            e = f_a @ rows.v1[r]
            g[r] = e @ (p_b - p_a) - targets[r, 0]
            gd[r] = np.cross(w_a, e) @ (p_b - p_a) + e @ (v_b - v_a) - targets[r, 1]
        else:
            e = rows.v1[r]
            g[r], gd[r] = e @ (p_b - p_a), e @ (v_b - v_a)
    return g, gd, rows.owner


def held_chords(model, beams):
    """Of the bodies `beams` (flexible, in closed loops), those whose chord length the loops
    hold: a unit rate of the chord's stretch (the output point and all that hangs from it moving
    along the chord) that no rates of the tree's free coordinates (those no JointMotion
    prescribes) make up in the loops' rate Jacobian G (exact: g' = G x' + g'_0), as
    check_drives_move tests a drive.  A beam without stretch modes held so cannot bow under
    geometric stiffening (its foreshortening would need the ends to approach): the build leaves
    its stiffening off there (docs/loops.md, "Flexible links").  A four-bar's coupler, whose
    ends the crank and the rocker carry, is not held."""
    if model.n_closures == 0 or not len(beams):
        return []
    variables, kept = _coordinates(model, ())
    x = _start_values(model, variables)
    free = np.nonzero(~kept)[0]
    base, jac, _ = _rate_jacobian(model, variables, x, free)
    held = []
    for k in beams:
        stretch = np.zeros(model.n_bodies)
        stretch[k] = 1.0
        column = closure_residuals(model, _state_of(model, variables, x,
                                                    np.zeros(len(variables)), stretch))[1] - base
        left = column
        if free.size:
            left = column + jac @ np.linalg.lstsq(jac, -column, rcond=1e-10)[0]
        if np.abs(left).max() > 1e-6 * max(1.0, np.abs(column).max()):
            held.append(int(k))
    return held


def loop_rank(model):
    """(rigid coordinates of the tree, rank of the loops' constraint rows over them): the rate
    Jacobian G of every closing joint's rows (g' = G x' + g'_0, exact) over the tree's joint
    coordinates and free rotations (_coordinates; the beams' modal coordinates left
    out), its rank by SVD to 1e-9 of its largest singular value.  The rigid mechanism's
    mobility is their difference (Grübler's count, corrected by the rows that are redundant,
    as a planar loop's spatial joints are; describe)."""
    variables, _ = _coordinates(model, ())
    if model.n_closures == 0 or not variables:
        return len(variables), 0
    jac = _rate_jacobian(model, variables, _start_values(model, variables))[1]
    sv = np.linalg.svd(jac, compute_uv=False)
    return len(variables), int(np.sum(sv > 1e-9 * sv.max(initial=0.0))) if sv.size else 0


def loop_residuals(model):
    """How far each closing joint is from holding at t = 0 (docs/loops.md, "Constraints").

    Parameters
    ----------
    model : Model
        A model with closing joints (``System.close``).

    Returns
    -------
    positions, rates : ndarray (closing joints,)
        Each joint's largest position residual (its gaps in m, its dots dimensionless) and
        largest rate residual (m/s, rad/s).

    Examples
    --------
    >>> import dttmm
    >>> positions, rates = dttmm.loop_residuals(model)  # doctest: +SKIP
    """
    g, gd, owner = closure_residuals(model, start_state(model))
    pos, vel = np.zeros(model.n_closures), np.zeros(model.n_closures)
    np.maximum.at(pos, owner, np.abs(g))
    np.maximum.at(vel, owner, np.abs(gd))
    return pos, vel


def check_drives_move(model, who):
    """Refuse a prescribed motion (JointMotion) on a joint coordinate the loops lock: one that
    the other coordinates cannot follow, with the other prescribed motions held, without
    opening a closing joint (the loops' rate Jacobian G, g' = G x' + g'_0, is exact: a unit
    rate of the driven coordinate that no rates of the others compensate, |G_o y + G_d| > 0
    at the least-squares y, is locked); a closing joint's driven coordinate likewise (its row
    of G at 1, the others at 0: |G_o y - e_d| > 0).  The ValueError names the joint, its
    coordinate and the closing joints that lock it.  A model that passed is not checked again
    (it is frozen; the check costs tens of ms on a Stewart platform, more than a short run)."""
    if model.n_closures == 0 or getattr(model, "_drives_move", False):
        return
    variables, _ = _coordinates(model, ())
    driven = [j for j, (what, k, i) in enumerate(variables)
              if what == "q" and len(model.drives[k]) > i and model.drives[k][i] is not None
              and model.drives[k][i]["kind"] == MOTION]
    rows = constraint_rows(model)
    owner, coordinate = rows.owner, rows.coordinate
    driven_rows = np.nonzero(rows.law[:, 0] == MOTION)[0]
    if not driven and not len(driven_rows):
        return
    jac = _rate_jacobian(model, variables, _start_values(model, variables))[1]
    others = [j for j in range(len(variables)) if j not in driven]

    def left_over(column):
        """column + G_o y at the least-squares y: what the free coordinates cannot make up."""
        if not others:
            return column
        y = np.linalg.lstsq(jac[:, others], -column, rcond=1e-10)[0]
        return column + jac[:, others] @ y

    def locking(left):
        return ", ".join(repr(n) for n in sorted(
            {model.closure_names[c] for c in owner[np.abs(left) > 1e-6 * np.abs(left).max()]}))

    for j in driven:
        column = jac[:, j]
        left = left_over(column)
        if np.abs(left).max() > 1e-6 * max(1.0, np.abs(column).max()):
            _, k, i = variables[j]
            raise ValueError(f"{who}: the prescribed motion of joint '{model.hinge_names[k]}' "
                             f"(coordinate {i + 1}) cannot move: closing joint(s) "
                             f"{locking(left)} lock it (with the other prescribed motions "
                             f"held, no motion of the rest keeps the loops closed); drive a "
                             f"coordinate the loops leave free, or drop the drive")
    for r in driven_rows:
        unit = np.zeros(jac.shape[0])
        unit[r] = -1.0
        left = left_over(unit)
        if np.abs(left).max() > 1e-6:
            raise ValueError(f"{who}: the prescribed motion of closing joint "
                             f"'{model.closure_names[owner[r]]}' (coordinate "
                             f"{coordinate[r] + 1}) cannot move: closing joint(s) "
                             f"{locking(left)} lock it (with the other prescribed motions "
                             f"held, no motion of the tree keeps the loops closed); drive a "
                             f"coordinate the loops leave free, or drop the drive")
    if hasattr(model, "__dict__"):
        object.__setattr__(model, "_drives_move", True)


class AssemblyWarning(UserWarning):
    """assemble moved a body further than MOVE_TOLERANCE to close the loops: the mechanism
    simulated is not the one given (docs/loops.md, "Assembly")."""


def _coordinates(model, keep):
    """The assembly's variables: per body, ("rot", k, i) for a free body's rotation (a ball
    joint's or an elastic hinge's body; 3 each) and ("q", k, i) for a joint's coordinate, with
    whether each is kept (named in keep: a hinge's or its body's name; a prescribed motion's
    coordinate always)."""
    from ..elements.kinds import coordinate_count
    names = set(keep)
    unknown = names - set(model.hinge_names) - set(model.body_names)
    if unknown:
        raise ValueError(f"assemble: keep names no joint or body of the model: "
                         f"{', '.join(sorted(map(str, unknown)))} (joints: "
                         f"{', '.join(model.hinge_names)})")
    variables, kept = [], []
    for k in range(model.n_bodies):
        kind = int(model.hinge_kind[k])
        named = model.hinge_names[k] in names or model.body_names[k] in names
        if kind in WITH_COORDINATES:
            for i in range(coordinate_count(kind)):
                drive = model.drives[k][i] if len(model.drives[k]) > i else None
                variables.append(("q", k, i))
                kept.append(named or (drive is not None and drive["kind"] == MOTION))
        elif kind != FIXED:
            for i in range(3):
                variables.append(("rot", k, i))
                kept.append(named)
    return variables, np.array(kept, dtype=bool)


def _state_of(model, variables, x, xd, stretch_rate=None):
    n = model.n_bodies
    theta, q = np.zeros((n, 3)), np.array(model.hinge_params[:, COORDINATE_0], order="C")
    omega = np.array(model.initial_angular_velocity, order="C")
    qd = np.array(model.hinge_params[:, RATE_0], order="C")
    for (what, k, i), value, rate in zip(variables, x, xd):
        if what == "q":
            q[k, i], qd[k, i] = value, rate
        else:
            theta[k, i], omega[k, i] = value, rate
    return tree_state(model, theta, q, omega, qd, stretch_rate)


def _start_values(model, variables):
    """The assembly's variables at t = 0: each joint coordinate as given, each free body's
    rotation change 0."""
    return np.array([model.hinge_params[k, COORDINATE_0.start + i] if what == "q" else 0.0
                     for what, k, i in variables])


def _rate_jacobian(model, variables, x, columns=None):
    """(g'_0, G, owner): the loops' rate residual at positions x with every rate zero, its
    Jacobian over the variables `columns` (default: all), exact since g' = G x' + g'_0 is
    linear in the rates (one unit rate a column), and each row's closing joint."""
    xd = np.zeros(len(variables))
    _, base, owner = closure_residuals(model, _state_of(model, variables, x, xd))
    columns = range(len(variables)) if columns is None else columns
    jac = np.zeros((base.size, len(columns)))
    for j, col in enumerate(columns):
        unit = xd.copy()
        unit[col] = 1.0
        jac[:, j] = closure_residuals(model, _state_of(model, variables, x, unit))[1] - base
    return base, jac, owner
