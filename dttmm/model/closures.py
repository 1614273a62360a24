"""Loop closures: joints that close kinematic loops over the spanning tree (docs/loops.md).

A system is its spanning tree (``Model.parent``, one joint per body) plus a table of closing
joints, each between a point of one side and a point of the other:

    system.close(joint, a, b, at_a=None, at_b=None)

Side a plays the parent's part of a tree joint (the joint's first axis is fixed in its frame),
side b the child's (a universal joint's second axis is fixed in its frame; the joint's force
and couple act on b, their reactions on a).  Either side may be the ground.  The table is flat
arrays on the Model (``closure_*``); this module builds and checks it, and gives the closing
points' positions and frames at t = 0.

Per closing joint c (elements/kinds.py codes, as ``Model.hinge_kind``):
    closure_kind[c]       its kind's code (BALL, FIXED, ELASTIC or a joint with coordinates)
    closure_body[c]       (a, b): body indices, -1 for the ground
    closure_point[c, s]   side s's point in its frame from its input point, m (the ground's:
                          in the ground frame from the ground point)
    closure_on_end[c, s]  the point is a beam's or strain rod's output end (its deflected end
                          section: the point moves and turns with the element's deflection)
    closure_params[c]     a hinge_params row (elements/hinges.py): R0, the axes (axis 1 in a's
                          frame, axis 2 in b's) and the coordinates at t = 0
with F_a, F_b the sides' frames at their points (a rigid body's own, a beam's or rod's end
section at its output end, the ground frame) the joint holds, as a tree joint (docs/joints.md):
    ball:       p_b = p_a
    fixed:      p_b = p_a,  F_b = F_a R0
    revolute:   p_b = p_a,  F_b = F_a Rot(n, q) R0
    universal:  p_b = p_a,  F_b = F_a Rot(n1, q1) R0 Rot(n2, q2)
    prismatic:  p_b = p_a + F_a n q,  F_b = F_a R0
    any joint with coordinates (elements/kinds.py): p_b = p_a + F_a sum n_i q_i over its
                slides, F_b = F_a R_P R0 R_C with R_P, R_C its turns fixed in a and in b
R0 is read from the bodies' frames at t = 0 (at the joint's given angles, default 0); a
slide's coordinate is measured from its points.  An elastic hinge holds nothing: its
springs and dampers act across the deflection d = F_a^T (p_b - p_a) and the rotation
psi = log(F_a^T F_b R0^T), both in a's frame (R0: the frames' at t = 0 unless given), as a tree
elastic hinge's (docs/loops.md, "An elastic hinge closing a loop").
"""
from collections import namedtuple

import numpy as np

from ..elements import (BALL, BEAM, ELASTIC, FIXED, BallJoint, EulerBernoulliBeam, StrainRod)
from ..elements.hinges import (C_ROTATION, C_TRANSLATION, DEFLECTION_0, K_ROTATION,
                               K_TRANSLATION, REST_ROTATION)
from ..elements.kinds import (ANGLE_A, ANGLE_B, CHILD, CLOSING_DRIVES, COORDINATE_0, DOT,
                              FLEXIBLE, GAP_A, GAP_WORLD, HINGE_KIND_NAMES, HINGE_PARAM_SIZE,
                              JOINT_KIND, JOINT_KINDS, PARENT, RATE_0, ROTATION_A, SLIDE, TURN,
                              WITH_COORDINATES, WITH_SLIDES, WITH_TURNS, coordinates_of,
                              joint_kind_of, joint_motion, joint_values, pack_hinge, row_axes,
                              turn_rotations)
from ..elements.drives import FORCE, MOTION, PD, SPRING_DAMPER
from ..elements.rigid_body import TO_OUTPUT
from .sections import element_end_section, element_output_offset, log_rotation

GROUND = -1
CLOSING_KINDS = tuple(k.code for k in JOINT_KINDS)     # (every joint kind closes a loop)


def empty_table():
    """The closure fields of a Model without loops."""
    return dict(closure_kind=np.zeros(0, dtype=np.int64),
                closure_body=np.zeros((0, 2), dtype=np.int64),
                closure_point=np.zeros((0, 2, 3)),
                closure_on_end=np.zeros((0, 2), dtype=bool),
                closure_params=np.zeros((0, HINGE_PARAM_SIZE)),
                closure_names=(), closure_drives=())


def _side_name(model, k):
    return "the ground" if k == GROUND else f"body '{model.body_names[k]}'"


def _body_index(model, side, who, argument, index_of):
    """A side given as a body, a body's name or "ground" -> its index (GROUND for the ground)."""
    if isinstance(side, str):
        if side == "ground":
            return GROUND
        if side not in model.body_names:
            raise ValueError(f"{who}: {argument} = {side!r} is not a body of the system "
                             f"(bodies: {', '.join(model.body_names)}; or 'ground')")
        return model.body_names.index(side)
    if id(side) in index_of:
        return index_of[id(side)]
    raise ValueError(f"{who}: {argument} must be a body of the system, its name or 'ground', "
                     f"got {type(side).__name__}")


def loop_membership(entries, bodies, parent):
    """Before the build: (in_loop, closed_output, output_moment), (n,) bools: the bodies on
    the tree path between a closing joint's sides (from each side up to their common ancestor;
    a beam or strain rod closed at its input end from its parent),
    those whose output point a closing joint takes, and those where that joint carries a moment
    (any but a ball joint); and output_pinned: those whose output a ball joint or a joint with a
    turn holds while it turns freely in some plane (the beams' mode counts,
    elements/beam.py::truncation_errors).  Sides that name nothing are skipped here (the
    build refuses them, naming the joint)."""
    n = len(bodies)
    index_of = {id(b): k for k, b in enumerate(bodies)}
    by_name = {b.name: k for k, b in enumerate(bodies) if getattr(b, "name", "")}
    in_loop = np.zeros(n, dtype=bool)
    closed_output = np.zeros(n, dtype=bool)
    output_moment = np.zeros(n, dtype=bool)
    output_pinned = np.zeros(n, dtype=bool)

    def index(side):
        if isinstance(side, str):
            return GROUND if side == "ground" else by_name.get(side)
        return index_of.get(id(side))

    def path(k):
        out = []
        while k is not None and k >= 0:
            out.append(k)
            k = parent[k]
        return out

    def start(k, at):       # a beam or rod closed at its input end: its length is not in
        if k >= 0 and isinstance(at, str) and at == "input" and \
                isinstance(bodies[k], (EulerBernoulliBeam, StrainRod)):      # the loop
            return parent[k]
        return k

    for joint, a, b, at_a, at_b in entries:
        ka, kb = index(a), index(b)
        if ka is None or kb is None:
            continue
        pa, pb = path(start(ka, at_a)), path(start(kb, at_b))
        common = set(pa) & set(pb)
        for k in pa + pb:
            if k not in common:
                in_loop[k] = True
        for k, at in ((ka, at_a), (kb, at_b)):
            if k >= 0 and (at is None or (isinstance(at, str) and at == "output")):
                closed_output[k] = True
                output_moment[k] |= not isinstance(joint, BallJoint)   # (an elastic
                # hinge's couple too)
                kind = joint_kind_of(joint)
                output_pinned[k] |= isinstance(joint, BallJoint) or (
                    kind is not None and kind.code in WITH_TURNS)
    return in_loop, closed_output, output_moment, output_pinned


def start_state(model):
    """The tree's kinematics at t = 0 (tree_state at the model's own coordinates and rates)."""
    return tree_state(model, np.zeros((model.n_bodies, 3)), model.hinge_params[:, COORDINATE_0],
                      model.initial_angular_velocity, model.hinge_params[:, RATE_0])


def _side(model, k, at, who, argument, frames, named):
    """(point in the side's frame, on a beam's end, world point, world frame) at t = 0 of side
    k's point at (None for the ground: placed later)."""
    rot, _, r_in, _, a_o, _, r_o, _ = frames
    if k == GROUND:
        if at is None:
            return None
        if isinstance(at, str):
            raise ValueError(f"{who}: {argument} on the ground is a position (3 numbers, world "
                             f"frame, m), or None for where the other side's point starts; got "
                             f"{at!r}")
        from ..elements._checks import finite_vector
        p = finite_vector(who, argument, at)
        return model.ground_rotation.T @ (p - model.ground_position), False, p, \
            model.ground_rotation
    beam = model.body_kind[k] in FLEXIBLE        # a modal beam or a strain rod
    if at is None or at == "output":
        if beam:
            return np.zeros(3), True, r_o[k], a_o[k]
        local = np.array(model.body_params[k, TO_OUTPUT])
    elif isinstance(at, str) and at == "input":
        local = np.zeros(3)
    elif isinstance(at, str):
        points = named[k]
        if at not in points:
            raise ValueError(f"{who}: {argument} = {at!r}: {_side_name(model, k)} has no point "
                             f"{at!r} (it has: {', '.join(['output', 'input', *points])})")
        local = np.array(points[at], dtype=float)
    elif beam:
        raise ValueError(f"{who}: {argument}: a beam or strain rod is closed at one of its ends "
                         f"('output' or 'input'), got {at!r}")
    else:
        from ..elements._checks import finite_vector
        local = finite_vector(who, argument, at)
    return local, False, r_in[k] + rot[k] @ local, rot[k]


def _weld_group(model):
    """Each body's rigid unit: bodies joined by fixed hinges through rigid bodies share one
    (GROUND for those welded to the ground; a beam's or strain rod's end moves on its own)."""
    group = np.arange(model.n_bodies)
    for k in range(model.n_bodies):
        p = model.parent[k]
        if model.hinge_kind[k] == FIXED and (p < 0 or model.body_kind[p] not in FLEXIBLE):
            group[k] = GROUND if p < 0 else group[p]
    return group


def closure_rows(model, entries, index_of, named):
    """The closure fields (empty_table's keys) of a tree model and the closing joints as given:
    entries = [(joint, a, b, at_a, at_b), ...]; index_of: body id -> index; named: each
    body's named points (RigidBody.points, {} for the rest).  ValueError naming the joint for
    a side that is not in the system, a joint that closes a body to itself, to a body welded
    to it or the ground to itself, a point the side does not have, an axis that is zero or
    not finite, axes that are not perpendicular at the start, and a rotation that contradicts
    the bodies' frames."""
    rows = empty_table()
    if not entries:
        return rows
    frames = start_state(model)
    group = _weld_group(model)
    kinds, bodies, points, ends, params, names, all_drives = [], [], [], [], [], [], []
    for c, (joint, a, b, at_a, at_b) in enumerate(entries):
        kind = joint_kind_of(joint)
        label = (f"{type(joint).__name__} '{joint.name}' (closure {c})" if
                 getattr(joint, "name", "") else f"{type(joint).__name__} (closure {c})")
        if kind is None:
            raise ValueError(f"System.close (closure {c}): joint must be one of "
                             f"{', '.join(HINGE_KIND_NAMES[k] for k in CLOSING_KINDS)}, got "
                             f"{type(joint).__name__}")
        if kind.code not in CLOSING_KINDS:
            raise ValueError(f"{label}: {kind.what} does not close a loop yet (closing joints: "
                             f"{', '.join(HINGE_KIND_NAMES[k] for k in CLOSING_KINDS)})")
        ka = _body_index(model, a, label, "a", index_of)
        kb = _body_index(model, b, label, "b", index_of)
        if ka == kb:
            raise ValueError(f"{label}: closes {_side_name(model, ka)} to itself; a closing "
                             f"joint joins two different bodies (or a body and the ground)")
        v = joint.validated(c)
        drives = tuple(v.get("drives", ()))
        if any(d is not None and d["kind"] == PD for d in drives):
            raise ValueError(f"{label}: a closing joint's coordinate takes a JointMotion, "
                             f"SpringDamper or JointForce so far; PDTracking runs on tree "
                             f"joints (or give the law as a JointForce)")
        side_a = _side(model, ka, at_a, label, "at_a", frames, named)
        side_b = _side(model, kb, at_b, label, "at_b", frames, named)
        if side_a is None:                # the ground's point: where b's starts
            p = side_b[2]
            side_a = (model.ground_rotation.T @ (p - model.ground_position), False, p,
                      model.ground_rotation)
        if side_b is None:
            p = side_a[2]
            side_b = (model.ground_rotation.T @ (p - model.ground_position), False, p,
                      model.ground_rotation)
        # two points of one rigid unit (a beam's output end moves on its own)
        ga = GROUND if ka == GROUND else (-2 - ka if side_a[1] else group[ka])
        gb = GROUND if kb == GROUND else (-2 - kb if side_b[1] else group[kb])
        if ga == gb:
            raise ValueError(f"{label}: {_side_name(model, ka)} and {_side_name(model, kb)} are "
                             f"welded to each other by fixed hinges (one rigid unit): a joint "
                             f"between them closes no loop")
        f_a, f_b = side_a[3], side_b[3]
        v = dict(v)
        if kind.code in WITH_COORDINATES:
            drives = _closing_coordinates(label, joint, kind, v, drives, f_a, side_a[2], f_b,
                                          side_b[2])
        elif kind.code == ELASTIC:
            if joint.deflection is not None:
                raise ValueError(f"{label}: a closing elastic hinge's deflection is measured "
                                 f"between its points (at_a, at_b); leave deflection None")
            if joint.rotation is None:      # the rest rotation: the frames' at the start
                v["rotation"] = f_a.T @ f_b
            for part, k, c_ in (("translational", "k_t", "c_t"), ("rotational", "k_r", "c_r")):
                _principal_axes(label, part, v[k], v[c_])
        else:
            relative = f_a.T @ f_b
            if kind.code == FIXED and getattr(joint, "rotation", None) is not None and \
                    not np.allclose(v["rotation"], relative, atol=1e-9):
                raise ValueError(f"{label}: rotation contradicts the bodies' frames at the "
                                 f"start (F_b = F_a R0 there); leave it None")
            v["rotation"] = relative
        kinds.append(kind.code)
        bodies.append((ka, kb))
        points.append((side_a[0], side_b[0]))
        ends.append((side_a[1], side_b[1]))
        params.append(pack_hinge(v))
        names.append(joint.name or f"{HINGE_KIND_NAMES[kind.code]}_closure{c}")
        all_drives.append(drives)
    return dict(closure_kind=np.array(kinds, dtype=np.int64),
                closure_body=np.array(bodies, dtype=np.int64).reshape(-1, 2),
                closure_point=np.array(points, dtype=float).reshape(-1, 2, 3),
                closure_on_end=np.array(ends, dtype=bool).reshape(-1, 2),
                closure_params=np.array(params).reshape(-1, HINGE_PARAM_SIZE),
                closure_names=tuple(names), closure_drives=tuple(all_drives))


def _closing_coordinates(label, joint, kind, v, drives, f_a, p_a, f_b, p_b):
    """A closing joint with coordinates (v: its validated parameters, changed here): each slide
    measured between its points, (F_a n_i) . (p_b - p_a) (a SpringDamper's rest, if not given,
    that slide), the turns as given, R0 = R_P^T F_a^T F_b R_C^T from the sides' frames, the
    rates 0; its drives, a slide's spring's rest filled in.  ValueError naming the joint: a
    slide given a value (without a JointMotion), axes of a turn in each frame that are not
    perpendicular at the start, a drive past the closing joints' CLOSING_DRIVES coordinates."""
    axes, spec = v["axes"], kind.coordinates
    given = joint_values(joint)[2]
    names = kind.arguments[0:1] if len(spec) == 1 else \
        [f"{kind.arguments[0]}[{i}]" for i in range(len(spec))]
    q0 = list(v["q0"])
    drives = list(drives) + [None] * (len(spec) - len(drives))
    for i, c in enumerate(spec):
        if c.motion != SLIDE:
            continue
        if q0[i] != 0.0 and (drives[i] is None or drives[i]["kind"] != MOTION):
            raise ValueError(f"{label}: a closing joint's slide is measured between its "
                             f"points; leave {names[i]} 0")
        q0[i] = float((f_a @ axes[c.axis]) @ (p_b - p_a))
        if (drives[i] is not None and drives[i]["kind"] == SPRING_DAMPER
                and getattr(given[i], "rest", 0.0) is None):
            drives[i] = dict(drives[i], rest=q0[i])  # a spring's rest by default: the slide
    late = [i for i in range(CLOSING_DRIVES, len(spec)) if drives[i] is not None]
    if late:
        raise ValueError(f"{label}: a closing joint carries drives on its first "
                         f"{CLOSING_DRIVES} coordinates so far, got {kind.arguments[2]}"
                         f"[{late[0]}] on {names[late[0]]}; build the loop with this joint in "
                         f"the tree (System.add) and close it at another joint")
    v["q0"] = q0
    r_p, r_c = turn_rotations(kind.code, axes, q0)
    v["rotation"] = r_p.T @ f_a.T @ f_b @ r_c.T
    turns = {c.frame: c.axis for c in spec if c.motion == TURN}
    if len(turns) == 2:
        first, second = kind.axes[turns[PARENT]], kind.axes[turns[CHILD]]
        cosine = float(axes[turns[PARENT]] @ (v["rotation"] @ axes[turns[CHILD]]))
        if abs(cosine) > 1e-9:
            angle = np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))
            raise ValueError(f"{label}: {first} (in a's frame) and {second} (in b's frame) must "
                             f"be perpendicular at the start; at t = 0 they make {angle:.4g} "
                             f"deg")
    v["qd0"] = [0.0] * len(spec)
    return tuple(drives)


def _principal_axes(label, part, k, c):
    """(axes (3, 3) as columns, stiffnesses (3,), dampings (3,)): a closing elastic hinge's
    spring K and damper C (part: "translational" or "rotational") in their common principal
    axes (each a row of the loop's table: spring_directions).  ValueError naming the hinge
    when the damper does not share the spring's axes (K C != C K)."""
    stiffness, damping = f"{part}_stiffness", f"{part}_damping"
    scale = max(float(np.max(np.abs(k))), 1e-300)
    c_scale = max(float(np.max(np.abs(c))), 1e-300)
    if np.max(np.abs(k @ c - c @ k)) > 1e-9 * scale * c_scale:
        raise ValueError(f"{label}: {damping} must share the principal axes of {stiffness} in "
                         f"a closing elastic hinge (its springs and dampers act along common "
                         f"axes; K C = C K): give a scalar, 3 entries, or a matrix with the "
                         f"spring's axes")
    # a generic combination's eigenvectors diagonalize both commuting matrices
    _, axes = np.linalg.eigh(k / scale + (np.sqrt(2.0) - 1.0) * c / c_scale)
    if np.linalg.det(axes) < 0.0:
        axes[:, 2] = -axes[:, 2]
    return axes, np.einsum("ji,jk,ki->i", axes, k, axes), np.einsum("ji,jk,ki->i", axes, c, axes)


def spring_directions(model, c):
    """The rows of closing elastic hinge c (docs/loops.md, "An elastic hinge closing a loop"),
    each a force (a SpringDamper's law), none a constraint: [(kind, v1, v2, v3, stiffness,
    damping)], along the common principal axes n_i of its spring and damper (in a's frame):
        GAP_A:      g = n_i . F_a^T (p_b - p_a)             (v1 = n_i)
        ROTATION_A: g = n_i . log(F_a^T F_b R0^T)           (v1, v2 = R0's first two columns,
                    g' = n_i . F_a^T (w_b - w_a)             v3 = n_i)
    each row's force lam = -k_i g - c_i g' (its couple n_i lam, its force n_i lam on b), so
    that the hinge's force and couple on b are -F_a (K_t d + C_t d'), -F_a (K_r psi + C_r
    F_a^T (w_b - w_a)) with d = F_a^T (p_b - p_a), d' its rate in a's frame."""
    if int(model.closure_kind[c]) != ELASTIC:
        return []
    row = model.closure_params[c]
    r0 = row[REST_ROTATION].reshape(3, 3)
    label = f"closing elastic hinge '{model.closure_names[c]}'"
    zero = np.zeros(3)
    rows = []
    for part, kind, k_slot, c_slot in (("translational", GAP_A, K_TRANSLATION, C_TRANSLATION),
                                       ("rotational", ROTATION_A, K_ROTATION, C_ROTATION)):
        axes, k, damping = _principal_axes(label, part, row[k_slot].reshape(3, 3),
                                           row[c_slot].reshape(3, 3))
        for i in range(3):
            if kind == GAP_A:
                rows.append((GAP_A, axes[:, i], zero, zero, k[i], damping[i]))
            else:
                rows.append((ROTATION_A, r0[:, 0], r0[:, 1], axes[:, i], k[i], damping[i]))
    return rows


# True: a chain's tip ball-jointed to a fixed ground closes in the sweeps' own tip condition
# (is_pinned_tip); False: as a row of the loops' table, like any closing joint (the same
# physics; benchmarks/loops.py measures what the tip condition saves, tests compare the two)
PINNED_TIP_SWEEP = True


def is_pinned_tip(model):
    """The closure table is one ball joint from a chain's last output point to a point of a
    fixed ground: the loop the DT-TMM sweeps close at the tip (docs/assembly.md, "A tip joined
    to the ground"), holding it where it starts (its gap is checked before a run); chosen from
    the table, where PINNED_TIP_SWEEP is on."""
    if (not PINNED_TIP_SWEEP or len(model.closure_kind) != 1 or model.closure_kind[0] != BALL
            or not model.is_chain):
        return False
    (a, b), n = model.closure_body[0], model.n_bodies
    if model.ground_motion is not None or b != GROUND or a != n - 1:
        return False
    flexible = model.body_kind[a] in FLEXIBLE
    on_output = (model.closure_on_end[0, 0] if flexible
                 else np.array_equal(model.closure_point[0, 0], model.body_params[a, TO_OUTPUT]))
    return bool(on_output)


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


def describe_closures(model):
    """Lines for describe(): each closing joint, its sides and points."""
    lines = []
    for c, kind in enumerate(model.closure_kind):
        sides = []
        for s in range(2):
            k = model.closure_body[c, s]
            if k == GROUND:
                sides.append("the ground")
            elif model.closure_on_end[c, s]:
                sides.append(f"'{model.body_names[k]}' (output end)")
            elif model.body_kind[k] == BEAM:
                sides.append(f"'{model.body_names[k]}' (input end)")
            else:
                point = np.round(model.closure_point[c, s], 6).tolist()
                sides.append(f"'{model.body_names[k]}' at {point}")
        drives = [f"coordinate {i + 1} " + ("prescribed (JointMotion)" if d["kind"] == MOTION
                                             else "driven by a force (JointForce)"
                                             if d["kind"] == FORCE
                                             else f"on a spring-damper (k = {d['stiffness']:g}, "
                                                  f"c = {d['damping']:g})")
                  for i, d in enumerate(model.closure_drives[c] if model.closure_drives else ())
                  if d]
        if kind == ELASTIC:         # its springs along their principal axes (spring_directions)
            h = model.closure_params[c]
            k_t, k_r = (np.linalg.eigvalsh(h[slot].reshape(3, 3))
                        for slot in (K_TRANSLATION, K_ROTATION))
            drives = [f"springs of {', '.join(f'{k:.4g}' for k in k_t)} N/m and "
                      f"{', '.join(f'{k:.4g}' for k in k_r)} N m/rad along their axes, at rest "
                      f"with its points together and its frames at R0 (it constrains nothing; "
                      f"its force and couple: Result.closure_force, closure_moment)"]
        lines.append(f"closure {c} '{model.closure_names[c]}': {JOINT_KIND[int(kind)].what} "
                     f"from {sides[0]} to {sides[1]}"
                     + (f", {drives[0]}" if kind == ELASTIC else
                        f", {', '.join(drives)} (its force: Result.closure_drive_force)"
                        if drives else ""))
    moves = model.__dict__.get("_assembly_moves")
    if moves is not None and len(moves):
        m, r = int(np.argmax(moves[:, 0])), int(np.argmax(moves[:, 1]))
        lines.append(f"assembled (assemble: the loops closed at t = 0): bodies moved at most "
                     f"{moves[m, 0]:.3g} m ('{model.body_names[m]}') and {moves[r, 1]:.3g} rad "
                     f"('{model.body_names[r]}')")
    return lines


def check_runs_in_sweeps(model, who, moving_ground=False):
    """Refuse, before a DT-TMM run or static solve, the loops its sweeps do not close yet,
    naming them: loops of rigid bodies, beams (at either end) and elastic hinges
    (kernels/assembly/closure.py), on a fixed ground or, in a run (moving_ground=True), a moving
    one, and a chain's tip joined to a fixed ground by a ball joint anywhere.  The pinned tip must
    start on its pin (the sweeps hold it where it starts)."""
    if model.n_closures == 0:
        return
    if model.tip_pinned:
        gap = closure_gaps(model)[0]
        if gap > 1e-9:
            raise ValueError(f"{who}: closure '{model.closure_names[0]}' (the tip's ball joint) "
                             f"is open by {gap:.3g} m at t = 0: its ground point must be where "
                             f"the tip starts (at_b=None)")
        return
    lines = "; ".join(describe_closures(model))
    if model.ground_motion is not None and not moving_ground:
        raise ValueError(f"{who}: the model's loops ({lines}) are solved here on a fixed ground "
                         f"so far, and the ground moves; simulate and the Newton-Euler "
                         f"reference (dttmm.simulate_reference) run them")


# ----------------------------------------------------------------------------------------------
# The closing joints' constraints and assembly (docs/loops.md, "Constraints", "Assembly")
# ----------------------------------------------------------------------------------------------

def _perpendiculars(n):
    """Two unit vectors completing the unit vector n to a right-handed frame (n, p1, p2)."""
    p1 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    p1 /= np.linalg.norm(p1)
    return p1, np.cross(n, p1)


def constraint_directions(model, c):
    """The closing joint c's scalar constraints (closure_rows' count, Kind.constraints in
    elements/kinds.py), in the sides' own frames:
        points: [(frame, e)], the rows e . (p_b - p_a) = 0 with e fixed in side a's frame
                (frame "a") or in the world (frame "w");
        dots:   [(x, y)], the rows (F_a x) . (F_b y) = 0, x fixed in a's frame, y in b's.
    From the joint's declaration: the points hold the gap across its slides' axes (the three
    world components without slides; a's two directions across one slide's axis, or the normal
    of two slides' plane); the dots hold what its turns leave: without turns the relative
    rotation's three dots (F_a R0 e_i) . (F_b e_j), (i, j) = (2, 3), (3, 1), (1, 2); with one
    turn fixed in a (b) its axis kept perpendicular to the two directions across it in the
    other frame (revolute: F_b R0^T n against a's two across n); with one in each frame their
    axes perpendicular (universal: n1 . n2 = 0).  A ball joint: the gap alone; an elastic
    hinge: none (its rows are forces: spring_directions)."""
    kind, row = int(model.closure_kind[c]), model.closure_params[c]
    if kind == ELASTIC:
        return [], []
    r0 = row[REST_ROTATION].reshape(3, 3)
    axes, spec = row_axes(row), coordinates_of(kind)
    e = np.eye(3)
    slides = [axes[x.axis] for x in spec if x.motion == SLIDE]
    turns = {x.frame: axes[x.axis] for x in spec if x.motion == TURN}
    if not slides:
        points = [("w", e[i]) for i in range(3)]
    elif len(slides) == 1:
        points = [("a", p) for p in _perpendiculars(slides[0])]
    elif len(slides) == 2:
        normal = np.cross(slides[0], slides[1])
        points = [("a", normal / np.linalg.norm(normal))]
    else:
        points = []
    if kind == BALL:
        dots = []
    elif not turns:
        dots = [(r0 @ e[i], e[j]) for i, j in ((1, 2), (2, 0), (0, 1))]
    elif len(turns) == 2:
        dots = [(turns[PARENT], turns[CHILD])]
    elif PARENT in turns:
        dots = [(p, r0.T @ turns[PARENT]) for p in _perpendiculars(turns[PARENT])]
    else:
        dots = [(p, turns[CHILD]) for p in _perpendiculars(r0 @ turns[CHILD])]
    return points, dots


def driven_directions(model, c):
    """The rows of closing joint c's driven coordinates (JointMotion or SpringDamper): [(i,
    kind, v1, v2, v3)] for coordinate i.  A slide is the gap along a's axis (GAP_A, e = n); a
    turn's angle is
        q = atan2(n . (x x y), x . y),  q' = n . (w_b - w_a)
    with x = F_a v1, y = F_b v2 and the axis n = F v3 (F_a: ANGLE_A, F_b: ANGLE_B), from the
    joint's declaration (F_b = F_a R_P R0 R_C):
        a turn fixed in a, alone:          x = u, y = R0^T u (u across n), n in a (revolute)
        fixed in a, with one fixed in b:   x = R0 m, y = m (m the other axis), n in a
                                           (universal q1)
        fixed in b, with one fixed in a:   x = m, y = R0^T m, n in b (universal q2)
        fixed in b, alone:                 x = u, y = R0^T u (u across R0 n), n in b
    (docs/loops.md, "Drives on closing joints")."""
    kind, row = int(model.closure_kind[c]), model.closure_params[c]
    r0 = row[REST_ROTATION].reshape(3, 3)
    axes, spec = row_axes(row), coordinates_of(kind)
    turns = {x.frame: axes[x.axis] for x in spec if x.motion == TURN}
    zero = np.zeros(3)
    rows = []
    for i, d in enumerate(model.closure_drives[c] if model.closure_drives else ()):
        if d is None:
            continue
        n = axes[spec[i].axis]
        if spec[i].motion == SLIDE:
            rows.append((i, GAP_A, n, zero, zero))
        elif spec[i].frame == PARENT and CHILD in turns:
            rows.append((i, ANGLE_A, r0 @ turns[CHILD], turns[CHILD], n))
        elif spec[i].frame == PARENT:
            u = _perpendiculars(n)[0]
            rows.append((i, ANGLE_A, u, r0.T @ u, n))
        elif PARENT in turns:
            rows.append((i, ANGLE_B, turns[PARENT], r0.T @ turns[PARENT], n))
        else:
            u = _perpendiculars(r0 @ n)[0]
            rows.append((i, ANGLE_B, u, r0.T @ u, n))
    return rows


Rows = namedtuple("Rows", ["kind", "owner", "v1", "v2", "v3", "coordinate", "law"])


def constraint_rows(model, closures=None):
    """The closing joints' scalar rows (constraint_directions, then each joint's driven
    coordinates, driven_directions, or an elastic hinge's springs, spring_directions; closures:
    which closing joints, default all), a Rows of flat arrays: kind (R,) GAP_WORLD, GAP_A,
    DOT, ANGLE_A, ANGLE_B or ROTATION_A, the closing joint of
    each (R,), v1 (e or x), v2 (y; zero for a gap), v3 (an angle's axis) (R, 3) each, the
    driven coordinate of each (R,; -1 for a constraint of the joint itself) and its drive's law
    (R, 3): [kind (elements/drives.py; -1 for none), stiffness, damping]."""
    kind, owner, v1, v2, v3, coordinate, law = [], [], [], [], [], [], []
    zero = np.zeros(3)

    def add(k, c, a, b, n, i, spring=None):
        kind.append(k)
        owner.append(c)
        v1.append(a)
        v2.append(b)
        v3.append(n)
        coordinate.append(i)
        d = model.closure_drives[c][i] if i >= 0 else None
        law.append([SPRING_DAMPER, *spring] if spring is not None else
                   [-1.0, 0.0, 0.0] if d is None else [d["kind"], d["stiffness"], d["damping"]])

    for c in range(model.n_closures) if closures is None else closures:
        points, dots = constraint_directions(model, c)
        for frame, e in points:
            add(GAP_WORLD if frame == "w" else GAP_A, c, e, zero, zero, -1)
        for x, y in dots:
            add(DOT, c, x, y, zero, -1)
        for i, k, a, b, n in driven_directions(model, c):
            add(k, c, a, b, n, i)
        for k, a, b, n, stiffness, damping in spring_directions(model, c):
            add(k, c, a, b, n, -1, (stiffness, damping))
    return Rows(np.array(kind, dtype=np.int64), np.array(owner, dtype=np.int64),
                np.array(v1, dtype=float).reshape(-1, 3), np.array(v2, dtype=float).reshape(-1, 3),
                np.array(v3, dtype=float).reshape(-1, 3), np.array(coordinate, dtype=np.int64),
                np.array(law, dtype=float).reshape(-1, 3))


def closure_targets(model, times, rows=None):
    """(len(times), R, 3): each row's target (value, rate, acceleration) at the times, R and the
    rows' order as constraint_rows: a driven coordinate's prescribed motion, a SpringDamper's
    rest (its row's value is then q - rest), zero for the constraints.  A function's failure or
    a value that is not finite: ValueError naming the closing joint and its coordinate.  rows:
    constraint_rows(model) (or the kernels' Loops, which carries its owner and coordinate),
    when the caller has them."""
    rows = constraint_rows(model) if rows is None else rows
    owner, coordinate = rows.owner, rows.coordinate
    out = np.zeros((len(times), len(owner), 3))
    for r in np.nonzero(coordinate >= 0)[0]:
        c, i = owner[r], coordinate[r]
        if model.closure_drives[c][i]["kind"] == SPRING_DAMPER:
            out[:, r, 0] = model.closure_drives[c][i]["rest"]
            continue
        if model.closure_drives[c][i]["kind"] == FORCE:     # its value: the solver's (state)
            continue
        functions = model.closure_drives[c][i]["function"]
        who = f"the prescribed motion of closing joint '{model.closure_names[c]}' " \
              f"(coordinate {i + 1})"
        for j, t in enumerate(times):
            for m, f in enumerate(functions):
                try:
                    value = float(np.asarray(f(t), dtype=float).reshape(-1)[0])
                except Exception as err:
                    raise ValueError(f"{who} failed at t = {t:g} s: {err}") from None
                if not np.isfinite(value):
                    raise ValueError(f"{who} returned {value} at t = {t:g} s (not finite)")
                out[j, r, m] = value
    return out


def closure_forces(model, rows=None):
    """[(row, f, who)]: each closing joint's coordinate driven by a JointForce f(t, q, q'),
    its row in constraint_rows' order and how messages name it.  Its q is the row's value (an
    angle's in [-pi, pi)), q' its rate.  rows: constraint_rows' table (or the kernels' Loops,
    which carries its law, owner and coordinate), when the caller has it."""
    rows = constraint_rows(model) if rows is None else rows
    out = []
    for r in np.nonzero(rows.law[:, 0] == FORCE)[0]:
        c, i = rows.owner[r], rows.coordinate[r]
        out.append((int(r), model.closure_drives[c][i]["function"],
                    f"the drive of closing joint '{model.closure_names[c]}' (coordinate {i + 1})"))
    return out


def has_closure_drives(model):
    """Whether any closing joint's coordinate is driven."""
    return any(d is not None for ds in model.closure_drives for d in ds)


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
    r_g, v_g, _, rot_g, w_g, _ = model.ground_state(0.0)
    e3 = np.empty((3, 3))
    for k in range(n):
        p, kind, h = model.parent[k], int(model.hinge_kind[k]), model.hinge_params[k]
        if p < 0:               # its place on the ground
            arm = rot_g @ model.attachment_point[k]
            r_att, v_att, f_in, w_in = r_g + arm, v_g + np.cross(w_g, arm), rot_g, w_g
        elif model.attachment[k] == 0:
            r_att, v_att, f_in, w_in = r_o[p], v_o[p], rot_o[p], w_o[p]
        else:
            arm = rot[p] @ model.attachment_point[k]
            r_att, v_att = r_in[p] + arm, v_in[p] + np.cross(w[p], arm)
            f_in, w_in = rot[p], w[p]
        r0 = h[REST_ROTATION].reshape(3, 3)
        d, d_rate = np.zeros(3), np.zeros(3)
        if kind in WITH_COORDINATES:                # elements/kinds.py::joint_motion
            rot[k], w[k], d, d_rate, _ = joint_motion(kind, row_axes(h), r0, f_in, w_in, q[k],
                                                      qd[k])
        elif kind == FIXED:
            rot[k], w[k] = f_in @ r0, w_in
        elif kind in (BALL, ELASTIC):               # free rotation
            expm_so3(np.ascontiguousarray(theta[k], dtype=float), e3)
            rot[k], w[k] = e3 @ model.initial_rotation[k], omega[k]
            if kind == ELASTIC:
                d = model.hinge_params[k, DEFLECTION_0]     # the deflection, as given
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
        else:
            rot_o[k], w_o[k] = rot[k], w[k]
            rho = rot[k] @ model.body_params[k, TO_OUTPUT]
            rho_rate = np.cross(w[k], rho)
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
    coordinates and free rotations (closures._coordinates; the beams' modal coordinates left
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
