"""The shortest spanning tree of a system with closed loops (docs/loops.md, "Choosing the
spanning tree"; issue 65, item 1).

A loop's rows cost a step over every body between the loop's joints and their common ancestor
(the sweep's columns), so a tree through which every loop runs back to one body (a chain closed
to the ground at every link) costs rows x bodies.  `shortest_tree` takes every joint, tree and
closing alike, as an edge between two bodies (or a body and the ground) and picks the tree by
breadth-first search from the ground (each body from the first joint that reaches it, in the
order added): each loop then runs through the fewest bodies.  A joint the new tree takes keeps
its sides where it can (side a the parent); a joint it leaves becomes a closing joint with its
own sides (a the parent's, b the child's; its slides then measured between its points, as
every closing joint's).  A body reached at a point other than its input point is the same
rigid body described from that point (its mass centre, output and named points shifted; its
inertia about the mass centre).  A joint with coordinates the new tree takes from its loop, or
runs the other way (its child now its parent: an undriven joint whose coordinates are all
about or along axes fixed in its parent, those axes turned into the new parent's frame, its
turns' angles negated), starts where the system as built stands (`_placed`): each slide the
gap between its points along its axis, each turn as given (R0 comes from the bodies' frames),
and the rates those of the bodies' motion at t = 0; a ball joint runs either way as it is.
Every body keeps its initial rotation, and a body behind a ball joint its angular velocity; a
body on its own tree joint is kept as it is.
"""
from collections import deque
from dataclasses import replace

import numpy as np

from .loop_kinematics import _side_motion, start_state
from ..elements import BallJoint, ElasticHinge, RigidBody
from ..elements.drives import MOTION
from ..elements.kinds import CHILD, SLIDE, TURN, joint_kind_of, joint_motion, turn_rotations
from ..elements.rigid_body import parallel_axis

GROUND = -1


def _point(body, spec):
    """The body-frame vector from body's input point to the point spec names ("input",
    "output", a named point, or 3 numbers), or None where the body cannot say (a beam's point
    other than its ends)."""
    if isinstance(spec, str) and spec == "input":
        return np.zeros(3)
    if not isinstance(body, RigidBody):
        return None
    if spec is None or (isinstance(spec, str) and spec == "output"):
        return np.asarray(body.to_output, dtype=float)
    if isinstance(spec, str):
        return np.asarray((body.points or {})[spec], dtype=float)
    return np.asarray(spec, dtype=float)


def _from_point(body, p, rotation, angular_velocity):
    """RigidBody `body` described from its point p (body frame, from its input point), with its
    initial rotation and angular velocity (None: the joint before it says).  Its output point
    is then its old input point, where the old tree joint held it (a bar turned end for end;
    the joints' points stay ends: a joint at a named point costs a massless anchor body, and
    a loop through two such anchors at the four-bar's flat position ran off)."""
    mass_center = np.asarray(body.to_mass_center, dtype=float)
    inertia = np.asarray(body.inertia, dtype=float)
    if inertia.ndim < 2:
        inertia = inertia * np.eye(3) if inertia.ndim == 0 else np.diag(inertia)
    if body.inertia_about == "input":
        inertia = inertia - parallel_axis(body.mass, mass_center)
    points = {k: np.asarray(v, dtype=float) - p for k, v in (body.points or {}).items()}
    return replace(body, inertia=inertia, inertia_about="mass_center",
                   to_mass_center=mass_center - p,
                   to_output=-p if p.any() else np.asarray(body.to_output, dtype=float),
                   points=points or None, rotation=rotation, angular_velocity=angular_velocity)


def _attachment(model, state, k):
    """((point, velocity, frame, angular velocity) of tree body k's attachment point, the same
    of its input point) at t = 0 (state: loop_kinematics.start_state; the parent's side as
    loop_kinematics.tree_state places it)."""
    rot, w, r_in, v_in, rot_o, w_o, r_o, v_o = state
    p = model.parent[k]
    if p < 0:
        r_g, v_g, _, rot_g, w_g, _ = model.ground_state(0.0)
        arm = rot_g @ model.attachment_point[k]
        side_a = (r_g + arm, v_g + np.cross(w_g, arm), rot_g, w_g)
    elif model.attachment[k] == 0:
        side_a = (r_o[p], v_o[p], rot_o[p], w_o[p])
    else:
        arm = rot[p] @ model.attachment_point[k]
        side_a = (r_in[p] + arm, v_in[p] + np.cross(w[p], arm), rot[p], w[p])
    return side_a, (r_in[k], v_in[k], rot[k], w[k])


def _value(kind, values):
    """A joint class's argument of its coordinates' values (a scalar for one coordinate)."""
    values = tuple(float(x) for x in values)
    return values[0] if len(kind.coordinates) == 1 else values


def _placed(joint, forward, side_a, side_b):
    """A joint with coordinates as the new tree takes it, from its side a's point to its side
    b's (forward) or the other way, starting where the system as built stands: side_a, side_b
    its sides' (point, velocity, frame, angular velocity) at t = 0 (world).  Its frames
    F_P, F_C and points p_P, p_C (the new parent's and child's) and the joint's kinematics
    (elements/kinds.py::joint_motion: F_C = F_P R_P R0 R_C, p_C = p_P + F_P sum n_i q_i over
    its slides) give
        each slide       q_i = (F_P n_i) . (p_C - p_P)   (its axes perpendicular, as
                         closures._closing_coordinates measures a closing joint's),
        each turn        q_i as given, or its negative run the other way (R0, which the build
                         reads from the bodies' frames, takes up the rest),
        the rates        least squares of  sum_turns u_i q_i' = w_C - w_P,
                         sum_slides u_i q_i' = v_C - v_P - w_P x d  (d = sum_slides u_i q_i)
    (a coordinate on a JointMotion starts on its motion, as given).  Run the other way (its
    child now its parent), each axis, fixed in the old parent, is turned into the new parent's
    frame, F_C^T F_P n, which holds for a joint whose coordinates are all about or along axes
    fixed in its parent; a driven one (its drives would act on other coordinates) or one with a
    turn fixed in the child: None."""
    kind = joint_kind_of(joint)
    v = joint.validated()
    spec, axes = kind.coordinates, [np.asarray(n, dtype=float) for n in v["axes"]]
    q, qd = np.array(v["q0"], dtype=float), np.array(v["qd0"], dtype=float)
    prescribed = np.array([d is not None and d["kind"] == MOTION for d in v["drives"]])
    changes = {}
    if not forward:
        if any(d is not None for d in v["drives"]) or any(c.frame == CHILD for c in spec):
            return None
        turn = side_b[2].T @ side_a[2]          # old parent's frame -> new parent's
        axes = [turn @ n for n in axes]
        changes = {name: axes[slot] for slot, name in enumerate(kind.axes)}
        q = -q
        side_a, side_b = side_b, side_a
    (p_p, v_p, f_p, w_p), (p_c, v_c, f_c, w_c) = side_a, side_b
    for i, c in enumerate(spec):
        if c.motion == SLIDE and not prescribed[i]:
            q[i] = (f_p @ axes[c.axis]) @ (p_c - p_p)
    r_p, r_c = turn_rotations(kind.code, axes, q)
    r0 = r_p.T @ f_p.T @ f_c @ r_c.T
    _, _, d, _, u = joint_motion(kind.code, axes, r0, f_p, w_p, q, np.zeros(len(spec)))
    jac = np.zeros((6, len(spec)))
    for i, c in enumerate(spec):
        rows = slice(0, 3) if c.motion == TURN else slice(3, 6)
        jac[rows, i] = u[:, i]
    rhs = np.concatenate([w_c - w_p, v_c - v_p - np.cross(w_p, d)]) - \
        jac[:, prescribed] @ qd[prescribed]
    qd[~prescribed] = np.linalg.lstsq(jac[:, ~prescribed], rhs, rcond=None)[0]
    changes[kind.arguments[0]] = _value(kind, q)
    changes[kind.arguments[1]] = _value(kind, qd)
    return replace(joint, **changes)


def _closing(joint):
    """A tree joint the new tree leaves, as a closing joint: its slides measured between its
    points (given 0; one on a JointMotion as given: closing, it holds the gap on the motion),
    its rates those of the bodies' motion (given 0: the model's bodies already move as its
    rates made them)."""
    kind = joint_kind_of(joint)
    if kind is None or not kind.coordinates:
        return joint
    v = joint.validated()
    values = [0.0 if c.motion == SLIDE and not (d is not None and d["kind"] == MOTION) else q
              for c, d, q in zip(kind.coordinates, v["drives"], v["q0"])]
    return replace(joint, **{kind.arguments[0]: _value(kind, values),
                             kind.arguments[1]: _value(kind, [0.0] * len(kind.coordinates))})


def shortest_tree(entries, closures, model, in_model):
    """The (entries, closures) of a System (as System.add and System.close take them) of the
    same bodies and joints as `entries` and `closures`, built as `model` (its bodies in the
    order `in_model` lists them), its spanning tree the breadth-first one from the ground; or a
    sentence saying why they cannot be made."""
    bodies = [e[0] for e in entries]
    index = {id(b): k for k, b in enumerate(in_model)}
    k_of = [index[id(b)] for b in bodies]
    entry_of = {k: i for i, k in enumerate(k_of)}

    def node(k):        # the build's body index (its parents and sides resolved) -> entry
        return GROUND if k < 0 else entry_of[int(k)]

    edges = []          # (joint, side a, point on a, side b, point on b, closing): a the parent's
    for i, (_, joint, _, at) in enumerate(entries):
        a = node(model.parent[k_of[i]])
        edges.append((joint, a, at if a == GROUND else (at or "output"), i, "input", False))
    for c, (joint, _, _, at_a, at_b) in enumerate(closures):
        a, b = (node(k) for k in model.closure_body[c])
        edges.append((joint, a, at_a if a == GROUND else (at_a or "output"), b,
                      at_b if b == GROUND else (at_b or "output"), True))
    touching = {}
    for e, (_, a, _, b, _, _) in enumerate(edges):
        touching.setdefault(a, []).append(e)
        touching.setdefault(b, []).append(e)
    via, queue = {}, deque([GROUND])          # body -> (its edge, taken from side a to b)
    while queue:
        u = queue.popleft()
        for e in touching.get(u, []):
            _, a, _, b, _, _ = edges[e]
            v = b if a == u else a
            if v != GROUND and v not in via:
                via[v] = (e, a == u)
                queue.append(v)
    ground_rot = np.asarray(model.ground_rotation)
    ground_pos = np.asarray(model.ground_position)

    def rotation(node):
        return ground_rot if node == GROUND else np.asarray(model.initial_rotation[k_of[node]])

    state = start_state(model)

    def sides(e):
        """Edge e's sides at t = 0, (point, velocity, frame, angular velocity) each, as the
        system as built places them."""
        if e >= len(entries):
            return tuple(_side_motion(model, state, e - len(entries), s) for s in (0, 1))
        return _attachment(model, state, k_of[e])

    # each body's new input point (from its old one), and the joint before it
    shift, joint_before = {}, {}
    for i, body in enumerate(bodies):
        e, forward = via[i]
        joint, a, at_a, b, at_b, closing = edges[e]
        p = _point(body, at_b if forward else at_a)
        if p is None:
            return (f"body '{body.name}' would hang from a point other than its input, and a "
                    f"beam's input end is its root")
        shift[i] = p
        kind = joint_kind_of(joint)
        if closing and isinstance(joint, ElasticHinge):
            return (f"elastic hinge '{joint.name or 'ElasticHinge'}' closes a loop, and in the "
                    f"tree its deflection and rest rotation would start from zero, not from "
                    f"where its two points stand")
        if kind is not None and kind.coordinates and (closing or not forward):
            placed = _placed(joint, forward, *sides(e))
        else:       # (a ball joint runs either way; a fixed or elastic hinge only forward)
            placed = joint if forward or isinstance(joint, BallJoint) else None
        if placed is None:
            return (f"joint '{joint.name or type(joint).__name__}' would run the other way, "
                    f"and only ball joints and undriven joints whose coordinates are all about "
                    f"or along axes fixed in the parent (revolute, prismatic, cylindrical, "
                    f"planar) can")
        joint_before[i] = placed

    def point_spec(node, spec):
        """spec's point on node, as the rebuilt system names it: a body described from another
        point has its old input as its output and its named points shifted (the ground's as
        given)."""
        if node == GROUND or not shift[node].any() or (isinstance(spec, str) and spec not in
                                                        ("input", "output")):
            return spec
        old = _point(bodies[node], spec)
        if not old.any():
            return "output"
        here = old - shift[node]
        return "input" if not here.any() else here.tolist()

    # the tree's entries: (body, parent, its point); points a parent must name
    extra, tree = {}, []
    for i in via:                                     # (breadth-first order)
        e, forward = via[i]
        joint, a, at_a, b, at_b, closing = edges[e]
        parent, at = (a, at_a) if forward else (b, at_b)
        if parent == GROUND:
            if closing:        # the ground's point, as the build placed it (ground frame)
                at = model.closure_point[e - len(entries), 0 if forward else 1].tolist()
        else:
            at = point_spec(parent, at)
            if at == "input" or (at is not None and not isinstance(at, str)):
                if at == "input":
                    at = [0.0, 0.0, 0.0]
                if not isinstance(bodies[parent], RigidBody):
                    return (f"body '{bodies[i].name}' would hang from a point of beam "
                            f"'{bodies[parent].name}' other than its output end")
                name = f"tree_{e}"
                extra.setdefault(parent, {})[name] = at
                at = name
        tree.append((i, parent, at))

    new_body = {}
    for i, body in enumerate(bodies):
        e, forward = via[i]
        if edges[e][5] or not forward:      # (else on its own tree joint: as it was)
            ball = isinstance(joint_before[i], BallJoint)
            w = np.asarray(model.initial_angular_velocity[k_of[i]]) if ball else None
            body = (_from_point(body, shift[i], rotation(i), w) if isinstance(body, RigidBody)
                    else replace(body, rotation=rotation(i), angular_velocity=w))
        if i in extra:
            body = replace(body, points={**(body.points or {}), **extra[i]})
        new_body[i] = body

    def side(node):
        return "ground" if node == GROUND else new_body[node]

    new_entries = [(new_body[i], joint_before[i], None if parent == GROUND else new_body[parent],
                    at) for i, parent, at in tree]
    new_closures = []
    taken = {via[i][0] for i in via}
    for e, (joint, a, at_a, b, at_b, closing) in enumerate(edges):
        if e in taken:
            continue
        if a == GROUND and not closing:    # a root's place -> its world point
            at_a = (ground_pos + ground_rot @ (np.zeros(3) if at_a is None else
                                               np.asarray(at_a, dtype=float))).tolist()
        new_closures.append((joint if closing else _closing(joint), side(a), side(b),
                             point_spec(a, at_a), point_spec(b, at_b)))
    return new_entries, new_closures
