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

import numpy as np

from ..elements import BALL, ELASTIC, FIXED, BallJoint
from ..elements.hinges import K_ROTATION, K_TRANSLATION
from ..elements.kinds import (CHILD, CLOSING_DRIVES, FLEXIBLE, HINGE_KIND_NAMES, HINGE_PARAM_SIZE,
                              JOINT_KIND, JOINT_KINDS, PARENT, SLIDE, TURN, WITH_COORDINATES,
                              WITH_TURNS, body_kind_of, declared_body_kind, joint_kind_of,
                              joint_values, pack_hinge, turn_rotations)
from ..elements.drives import FORCE, MOTION, PD, SPRING_DAMPER
from ..elements.rigid_body import TO_OUTPUT
from .loop_kinematics import closure_gaps, start_state
from .loop_rows import GROUND, _principal_axes

# (every joint kind that passes loads closes a loop: a free joint closes none)
CLOSING_KINDS = tuple(k.code for k in JOINT_KINDS if k.carries_loads)


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
                body_kind_of(bodies[k]).flexible:                           # the loop
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
        if not kind.carries_loads:
            raise ValueError(f"{label}: {kind.what} passes no force and no moment: between two "
                             f"bodies it closes no loop; leave it out (a body on a free joint "
                             f"closed to others: give it the free joint in the tree)")
        if kind.code not in CLOSING_KINDS:
            raise ValueError(f"{label}: {kind.what} does not close a loop yet (closing joints: "
                             f"{', '.join(HINGE_KIND_NAMES[k] for k in CLOSING_KINDS)})")
        ka = _body_index(model, a, label, "a", index_of)
        kb = _body_index(model, b, label, "b", index_of)
        if ka == kb:
            raise ValueError(f"{label}: closes {_side_name(model, ka)} to itself; a closing "
                             f"joint joins two different bodies (or a body and the ground)")
        v = joint.validated(c)
        if any(limit is not None for limit in v.get("limits", ())):
            raise ValueError(f"{label}: end stops (limits) on a closing joint do not run yet; "
                             f"give them to a joint of the tree")
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
    slide given a value (without a JointMotion), a rate given (the bodies' motion sets it),
    axes of a turn in each frame that are not perpendicular at the start, a drive past the
    closing joints' CLOSING_DRIVES coordinates."""
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
    rates = joint_values(joint)[1]
    moving = [i for i, rate in enumerate(rates) if rate != 0.0]
    if moving:          # (they were dropped without a word until 2026-12-07)
        name = kind.arguments[1] if len(spec) == 1 else f"{kind.arguments[1]}[{moving[0]}]"
        raise ValueError(f"{label}: a closing joint's rates follow from the motion of the "
                         f"bodies it joins (their angular velocities and the tree's joint "
                         f"rates at t = 0); leave {name} 0 and give that motion to the tree")
    v["qd0"] = [0.0] * len(spec)
    return tuple(drives)


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
            elif declared_body_kind(model.body_kind[k], f"body '{model.body_names[k]}'").flexible:
                sides.append(f"'{model.body_names[k]}' (input end)")
            else:       # a rigid body, at its point
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


