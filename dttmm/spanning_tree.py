"""The shortest spanning tree of a system with closed loops (docs/loops.md, "Choosing the
spanning tree"; issue 65, item 1).

A loop's rows cost a step over every body between the loop's joints and their common ancestor
(the sweep's columns), so a tree through which every loop runs back to one body (a chain closed
to the ground at every link) costs rows x bodies.  `shortest_tree` takes every joint, tree and
closing alike, as an edge between two bodies (or a body and the ground) and picks the tree by
breadth-first search from the ground (each body from the first joint that reaches it, in the
order added): each loop then runs through the fewest bodies.  A joint the new tree takes keeps
its sides where it can (side a the parent); a joint it leaves becomes a closing joint with its
own sides (a the parent's, b the child's).  A body reached at a point other than its input
point is the same rigid body described from that point (its mass centre, output and named
points shifted; its inertia about the mass centre); a joint the new tree runs the other way
(its child now its parent) is a ball joint, or a revolute joint whose axis is turned into the
new parent's frame and whose angle and rate change sign (a planar joint is refused unless it
stays where it is: in the tree, or closing its loop).  Every body keeps its initial rotation,
and a body behind a ball joint its angular velocity; a body on its own tree joint is kept as
it is.
"""
from collections import deque
from dataclasses import replace

import numpy as np

from .elements import BallJoint, PlanarJoint, RevoluteJoint, RigidBody
from .elements.rigid_body import parallel_axis

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


def _reversed(joint, rot_old_parent, rot_new_parent):
    """joint taken the other way (its child now its parent), or None where it cannot be."""
    if isinstance(joint, BallJoint):
        return joint
    if isinstance(joint, RevoluteJoint) and joint.drive is None:
        axis = rot_new_parent.T @ (rot_old_parent @ np.asarray(joint.axis, dtype=float))
        return replace(joint, axis=axis, angle=-joint.angle, rate=-joint.rate)
    return None


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

    # each body's new input point (from its old one), and the joint before it
    shift, joint_before = {}, {}
    for i, body in enumerate(bodies):
        e, forward = via[i]
        joint, a, at_a, b, at_b, closing = edges[e]
        if isinstance(joint, PlanarJoint) and (closing or not forward):
            return (f"planar joint '{joint.name or type(joint).__name__}' would "
                    + ("run the other way" if not forward else "join the tree from its loop")
                    + ", and a planar joint is kept only where it is (in the tree as added, or "
                      "closing its loop)")
        p = _point(body, at_b if forward else at_a)
        if p is None:
            return (f"body '{body.name}' would hang from a point other than its input, and a "
                    f"beam's input end is its root")
        shift[i] = p
        if not forward:
            joint = _reversed(joint, rotation(b), rotation(a))
            if joint is None:
                j = edges[e][0]
                return (f"joint '{j.name or type(j).__name__}' would run the other way, and "
                        f"only ball joints and undriven revolute joints can")
        joint_before[i] = joint

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
        new_closures.append((joint, side(a), side(b), point_spec(a, at_a), point_spec(b, at_b)))
    return new_entries, new_closures
