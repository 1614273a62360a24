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
    closure_kind[c]       BALL, FIXED, REVOLUTE, UNIVERSAL or PRISMATIC
    closure_body[c]       (a, b): body indices, -1 for the ground
    closure_point[c, s]   side s's point in its frame from its input point, m (the ground's:
                          in the ground frame from the ground point)
    closure_on_end[c, s]  the point is a beam's output end (its deflected end section: the
                          point moves and turns with the beam's deflection)
    closure_params[c]     a hinge_params row (elements/hinges.py): R0, the axes (axis 1 in a's
                          frame, axis 2 in b's) and the coordinates at t = 0
with F_a, F_b the sides' frames at their points (a rigid body's own, a beam's end section at
its output end, the ground frame) the joint holds, as a tree joint (docs/joints.md):
    ball:       p_b = p_a
    fixed:      p_b = p_a,  F_b = F_a R0
    revolute:   p_b = p_a,  F_b = F_a Rot(n, q) R0
    universal:  p_b = p_a,  F_b = F_a Rot(n1, q1) R0 Rot(n2, q2)
    prismatic:  p_b = p_a + F_a n q,  F_b = F_a R0
R0 is read from the bodies' frames at t = 0 (at the joint's given angles, default 0); a
prismatic joint's coordinate is measured from its points.
"""
import numpy as np

from .elements import BALL, BEAM, FIXED, PRISMATIC, REVOLUTE, UNIVERSAL, BallJoint
from .elements.hinges import AXIS_1, HINGE_PARAM_SIZE, pack_hinge
from .elements.joints import rotation_about
from .elements.kinds import HINGE_KIND_NAMES, JOINT_KIND, joint_kind_of
from .elements.rigid_body import TO_OUTPUT

GROUND = -1
CLOSING_KINDS = (BALL, FIXED, REVOLUTE, UNIVERSAL, PRISMATIC)


def empty_table():
    """The closure fields of a Model without loops."""
    return dict(closure_kind=np.zeros(0, dtype=np.int64),
                closure_body=np.zeros((0, 2), dtype=np.int64),
                closure_point=np.zeros((0, 2, 3)),
                closure_on_end=np.zeros((0, 2), dtype=bool),
                closure_params=np.zeros((0, HINGE_PARAM_SIZE)),
                closure_names=())


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
    the tree path between a closing joint's sides (from each side up to their common ancestor),
    those whose output point a closing joint takes, and those where that joint carries a moment
    (any but a ball joint).  Sides that name nothing are skipped here (the
    build refuses them, naming the joint)."""
    n = len(bodies)
    index_of = {id(b): k for k, b in enumerate(bodies)}
    by_name = {b.name: k for k, b in enumerate(bodies) if getattr(b, "name", "")}
    in_loop = np.zeros(n, dtype=bool)
    closed_output = np.zeros(n, dtype=bool)
    output_moment = np.zeros(n, dtype=bool)

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

    for joint, a, b, at_a, at_b in entries:
        ka, kb = index(a), index(b)
        if ka is None or kb is None:
            continue
        pa, pb = path(ka), path(kb)
        common = set(pa) & set(pb)
        for k in pa + pb:
            if k not in common:
                in_loop[k] = True
        for k, at in ((ka, at_a), (kb, at_b)):
            if k >= 0 and (at is None or (isinstance(at, str) and at == "output")):
                closed_output[k] = True
                output_moment[k] |= not isinstance(joint, BallJoint)
    return in_loop, closed_output, output_moment


def start_frames(model):
    """Per body at t = 0: input point r_in, rotation A, output point r_o and output section A_o
    (a beam's deflected end; a rigid body's own frame), from the tree's kinematics."""
    from .statics import _positions        # (statics imports the model module)
    from .model import output_section
    r_in, _, r_o = _positions(model)
    off = np.concatenate([[0], np.cumsum(model.n_modes)])
    a_o = np.array([output_section(model.beam_params[k], model.initial_rotation[k], np.zeros(3),
                                   model.initial_modal_coordinates[off[k]:off[k + 1]])[0]
                    for k in range(model.n_bodies)]).reshape(model.n_bodies, 3, 3)
    return r_in, model.initial_rotation, r_o, a_o


def _side(model, k, at, who, argument, frames, named):
    """(point in the side's frame, on a beam's end, world point, world frame) at t = 0 of side
    k's point at (None for the ground: placed later)."""
    r_in, rot, r_o, a_o = frames
    if k == GROUND:
        if at is None:
            return None
        if isinstance(at, str):
            raise ValueError(f"{who}: {argument} on the ground is a position (3 numbers, world "
                             f"frame, m), or None for where the other side's point starts; got "
                             f"{at!r}")
        from .elements._checks import finite_vector
        p = finite_vector(who, argument, at)
        return model.ground_rotation.T @ (p - model.ground_position), False, p, \
            model.ground_rotation
    beam = model.body_kind[k] == BEAM
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
        raise ValueError(f"{who}: {argument}: a beam is closed at one of its ends ('output' or "
                         f"'input'), got {at!r}")
    else:
        from .elements._checks import finite_vector
        local = finite_vector(who, argument, at)
    return local, False, r_in[k] + rot[k] @ local, rot[k]


def _weld_group(model):
    """Each body's rigid unit: bodies joined by fixed hinges through rigid bodies share one
    (GROUND for those welded to the ground)."""
    group = np.arange(model.n_bodies)
    for k in range(model.n_bodies):
        p = model.parent[k]
        if model.hinge_kind[k] == FIXED and (p < 0 or model.body_kind[p] != BEAM):
            group[k] = GROUND if p < 0 else group[p]
    return group


def closure_rows(model, entries, index_of, named):
    """The closure fields (empty_table's keys) of a tree model and the closing joints as given:
    entries = [(joint, a, b, at_a, at_b), ...]; index_of: body id -> index; named: each
    body's named points (RigidBody.points, {} for the rest).  ValueError naming the joint for
    a side that is not in the system, a joint that closes a body to itself, to a body welded
    to it or the ground to itself, a point the side does not have, an axis that is zero or
    not finite, axes that are not perpendicular at the start, a rotation that contradicts the
    bodies' frames and a drive (closing joints carry none yet)."""
    rows = empty_table()
    if not entries:
        return rows
    frames = start_frames(model)
    group = _weld_group(model)
    kinds, bodies, points, ends, params, names = [], [], [], [], [], []
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
        ga = GROUND if ka == GROUND else group[ka]
        gb = GROUND if kb == GROUND else group[kb]
        if ga == gb:
            raise ValueError(f"{label}: {_side_name(model, ka)} and {_side_name(model, kb)} are "
                             f"welded to each other by fixed hinges (one rigid unit): a joint "
                             f"between them closes no loop")
        v = joint.validated(c)
        drives = v.get("drives", ())
        if any(d is not None for d in drives):
            raise ValueError(f"{label}: drives on closing joints do not run yet; drive a joint "
                             f"of the tree instead (choose the spanning tree so that it holds "
                             f"the driven joint)")
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
        f_a, f_b = side_a[3], side_b[3]
        v = dict(v)
        if kind.code in (REVOLUTE, UNIVERSAL, PRISMATIC):
            n1, n2 = v["axis1"], v["axis2"]
            q1, q2 = v["q0"]
            if kind.code == PRISMATIC:
                if q1 != 0.0:
                    raise ValueError(f"{label}: a closing prismatic joint's position is "
                                     f"measured between its points; leave position 0")
                q1 = float((f_a @ n1) @ (side_b[2] - side_a[2]))
                v["q0"] = np.array([q1, 0.0])
            r1 = rotation_about(n1, q1) if kind.code != PRISMATIC else np.eye(3)
            r2 = rotation_about(n2, q2) if kind.code == UNIVERSAL else np.eye(3)
            v["rotation"] = r1.T @ f_a.T @ f_b @ r2.T
            cosine = float(n1 @ (v["rotation"] @ n2))
            if kind.code == UNIVERSAL and abs(cosine) > 1e-9:
                angle = np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))
                raise ValueError(f"{label}: axis1 (in a's frame) and axis2 (in b's frame) must "
                                 f"be perpendicular at the start; at t = 0 they make "
                                 f"{angle:.4g} deg")
            v["qd0"] = np.zeros(2)
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
    return dict(closure_kind=np.array(kinds, dtype=np.int64),
                closure_body=np.array(bodies, dtype=np.int64).reshape(-1, 2),
                closure_point=np.array(points, dtype=float).reshape(-1, 2, 3),
                closure_on_end=np.array(ends, dtype=bool).reshape(-1, 2),
                closure_params=np.array(params).reshape(-1, HINGE_PARAM_SIZE),
                closure_names=tuple(names))


def is_pinned_tip(model):
    """The closure table is one ball joint from a chain's last output point to a point of a
    fixed ground: the loop the DT-TMM sweeps close at the tip (docs/assembly.md, "A tip joined
    to the ground"), holding it where it starts (its gap is checked before a run)."""
    if len(model.closure_kind) != 1 or model.closure_kind[0] != BALL or not model.is_chain:
        return False
    (a, b), n = model.closure_body[0], model.n_bodies
    if model.ground_motion is not None or b != GROUND or a != n - 1:
        return False
    beam = model.body_kind[a] == BEAM
    on_output = (model.closure_on_end[0, 0] if beam
                 else np.array_equal(model.closure_point[0, 0], model.body_params[a, TO_OUTPUT]))
    return bool(on_output)


def closure_points(model, frames=None):
    """(p_a, p_b, F_a, F_b) at t = 0 of every closing joint: world points (m) and frames."""
    r_in, rot, r_o, a_o = start_frames(model) if frames is None else frames
    m = len(model.closure_kind)
    p = np.zeros((m, 2, 3))
    f = np.zeros((m, 2, 3, 3))
    for c in range(m):
        for s in range(2):
            k, local = model.closure_body[c, s], model.closure_point[c, s]
            if k == GROUND:
                f[c, s] = model.ground_rotation
                p[c, s] = model.ground_position + model.ground_rotation @ local
            elif model.closure_on_end[c, s]:
                f[c, s], p[c, s] = a_o[k], r_o[k]
            else:
                f[c, s], p[c, s] = rot[k], r_in[k] + rot[k] @ local
    return p[:, 0], p[:, 1], f[:, 0], f[:, 1]


def closure_gaps(model):
    """(m,) each closing joint's positional gap at t = 0, m: |p_b - p_a| (a prismatic joint's
    across its axis)."""
    p_a, p_b, f_a, _ = closure_points(model)
    gap = p_b - p_a
    for c in np.nonzero(model.closure_kind == PRISMATIC)[0]:
        u = f_a[c] @ model.closure_params[c, AXIS_1]
        gap[c] = gap[c] - u * (u @ gap[c])
    return np.linalg.norm(gap, axis=1)


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
            else:
                point = np.round(model.closure_point[c, s], 6).tolist()
                sides.append(f"'{model.body_names[k]}' at {point}")
        lines.append(f"closure {c} '{model.closure_names[c]}': {JOINT_KIND[int(kind)].what} "
                     f"from {sides[0]} to {sides[1]}")
    return lines



def check_runs_in_sweeps(model, who):
    """Refuse, before a DT-TMM run or static solve, the loops its sweeps do not close yet: any
    but one ball joint from a chain's tip to a fixed ground, and that one with a gap at t = 0
    (the sweeps hold the tip where it starts)."""
    if model.n_closures == 0:
        return
    if not model.tip_pinned:
        lines = "; ".join(describe_closures(model))
        raise ValueError(f"{who}: the model's loops ({lines}) do not run in DT-TMM yet: of the "
                         f"closed loops its sweeps close a chain's tip joined to a fixed ground "
                         f"by a ball joint (tip='ball'); the Newton-Euler reference runs every "
                         f"loop (dttmm.simulate_reference)")
    gap = closure_gaps(model)[0]
    if gap > 1e-9:
        raise ValueError(f"{who}: closure '{model.closure_names[0]}' (the tip's ball joint) is "
                         f"open by {gap:.3g} m at t = 0: its ground point must be where the tip "
                         f"starts (at_b=None)")
