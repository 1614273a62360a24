"""Systems described body by body (System) or as a chain (build_chain), frozen into a Model
(freeze.py)."""
from typing import Sequence

from ..elements._checks import finite_vector
from ..elements.kinds import BODY_KINDS, JOINT_KINDS, body_kind_of, joint_kind_of, names
from .freeze import _freeze, _who
from .model import Ground, Model
from .spanning_tree import shortest_tree


class System:
    """A multibody system under construction: a tree of bodies, each joined by a joint to its
    parent (the ground or another body) at one of the parent's attachment points
    (docs/topology.md).

    ::

        system = System(gravity=[0, -9.81, 0])
        system.add(link1, BallJoint())                        # to the ground point
        system.add(link2, BallJoint(), parent=link1)          # to link1's output point
        system.add(link4, BallJoint(), parent="link1")        # by name; a second branch
        system.add(link3, BallJoint(), parent=link2, at="p")  # at link2's named point "p"
        model = system.build()

    Bodies may be added in any order; build() resolves the parents, refuses a parent not in
    the system, an attachment point the parent does not have, and a cycle, and freezes the
    system into a Model whose bodies are numbered parents first (in the order added where that
    allows).  build_chain is the same for a chain.

    Parameters
    ----------
    gravity : array_like of 3, optional
        Gravitational acceleration, world frame, m/s^2 (default (0, -9.81, 0)).  Checked at
        build time (3 finite numbers).
    ground : Ground, optional
        Where the root joints attach: a fixed point and frame (default: the origin and the
        identity), or a prescribed motion.

    Examples
    --------
    A two-link pendulum with a third link on a named point of the first:

    >>> import dttmm
    >>> def link(name, **kw):
    ...     return dttmm.RigidBody(mass=1.0, inertia=[1e-4, 1 / 12, 1 / 12],
    ...                            inertia_about="mass_center", to_mass_center=[0.5, 0, 0],
    ...                            to_output=[1.0, 0, 0], name=name, **kw)
    >>> system = dttmm.System(gravity=[0, -9.81, 0])
    >>> link1 = system.add(link("link1", points={"p": [0.5, 0, 0]}), dttmm.BallJoint())
    >>> link2 = system.add(link("link2"), dttmm.BallJoint(), parent=link1)
    >>> link3 = system.add(link("link3"), dttmm.BallJoint(), parent="link1", at="p")
    >>> model = system.build()
    >>> model.parent.tolist(), model.attachment.tolist()
    ([-1, 0, 0], [0, 0, 1])
    """

    def __init__(self, gravity=(0.0, -9.81, 0.0), ground: Ground = Ground()):
        self.gravity = gravity
        self.ground = ground
        self._entries = []          # (body, joint, parent, at) as added
        self._closures = []         # (joint, a, b, at_a, at_b) as closed

    def add(self, body, joint, parent=None, at=None):
        """Join body to parent by joint.

        Nothing is checked here: ``build`` validates every body, joint, parent and attachment
        point.

        Parameters
        ----------
        body : RigidBody or EulerBernoulliBeam
            The body added (each body once).
        joint : BallJoint, FixedHinge, ElasticHinge or a joint with coordinates
            The joint between the parent's attachment point and the body's input point (any
            kind of elements/kinds.py's JOINT_KINDS: RevoluteJoint, UniversalJoint,
            PrismaticJoint, ...).
        parent : RigidBody, EulerBernoulliBeam or str, optional
            None (default) for the ground point, or a body of the system (the body itself or
            its name; it may be added later).
        at : str or array_like of 3, optional
            The parent's attachment point: None (default) or "output" for its output point, or
            the name of one of a rigid body's points (``RigidBody(points={...})``); a beam has
            only its output end.  On the ground (parent None): a point of the ground, in the
            ground frame from the ground point, m (default the ground point itself), so that
            several roots stand at their own places (a mechanism's ground pivots).

        Returns
        -------
        RigidBody or EulerBernoulliBeam
            body, so that it can be named as a later body's parent.
        """
        self._entries.append((body, joint, parent, at))
        return body

    def close(self, joint, a, b="ground", at_a=None, at_b=None):
        """Close a loop: join a point of side a to a point of side b by joint, beside the tree
        (docs/loops.md).

        The bodies' frames at t = 0 define the joint's rest: a joint's relative rotation R0 is
        read from them (at its turns' given angles), a slide's coordinate is measured between
        its points, and its rates follow from the bodies' motion (a rate given is refused).
        Nothing is checked here: ``build`` validates the joint and its sides.

        Parameters
        ----------
        joint : any joint kind (elements/kinds.py's JOINT_KINDS)
            The closing joint: BallJoint, FixedHinge, ElasticHinge, RevoluteJoint,
            UniversalJoint, PrismaticJoint, ...  Side a plays a tree joint's parent (the axes
            fixed in the parent, axis or axis1, are in a's frame; slides run along a's axes),
            side b its child (an axis fixed in the child, a universal joint's axis2, is in b's
            frame; the joint's force and couple act on b).  A closing joint's drives sit on its
            first two coordinates.
        a, b : body, str
            A body of the system, its name, or "ground" (b defaults to the ground).
        at_a, at_b : str or array_like of 3, optional
            Where on each side: None or "output" (the output point; a beam's output end),
            "input" (the input point), a rigid body's named point, or a point in the body's
            frame from its input point (rigid bodies).  On the ground: a world position, or
            None for where the other side's point starts.

        Returns
        -------
        joint
            The joint, as given.

        Examples
        --------
        A unit-square four-bar: the left crank on the ground at the origin, the coupler on its
        tip, the right crank hanging from the coupler's far end, its tip pinned to the ground at
        (1, 0, 0) by a closing revolute joint (the tree's roots sit at the ground point; the loop
        closes anywhere).

        >>> import numpy as np
        >>> import dttmm
        >>> def bar(name, rotation):
        ...     return dttmm.RigidBody(mass=1.0, inertia=[1e-3, 1 / 12, 1 / 12],
        ...                            inertia_about="mass_center", to_mass_center=[0.5, 0, 0],
        ...                            to_output=[1.0, 0, 0], rotation=rotation, name=name)
        >>> up = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]       # a bar's x along world y
        >>> down = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]     # along -y
        >>> z = [0, 0, 1]
        >>> system = dttmm.System(gravity=[0, -9.81, 0])
        >>> _ = system.add(bar("left", up), dttmm.RevoluteJoint(axis=z))
        >>> _ = system.add(bar("coupler", np.eye(3)), dttmm.RevoluteJoint(axis=z), parent="left")
        >>> _ = system.add(bar("right", down), dttmm.RevoluteJoint(axis=z), parent="coupler")
        >>> _ = system.close(dttmm.RevoluteJoint(axis=z, name="pin"), "right", "ground",
        ...                  at_b=[1, 0, 0])
        >>> model = system.build()
        >>> model.n_closures, float(dttmm.loop_residuals(model)[0].max()) < 1e-12
        (1, True)
        """
        self._closures.append((joint, a, b, at_a, at_b))
        return joint

    def build(self, tip="free", step=None, duration=None, tree="as added") -> "Model":
        """Validate and freeze into a Model.

        Parameters
        ----------
        tip : {"free", "ball"}, optional
            "free" (default) or, for a chain only, "ball": the last body's output point is
            joined to the ground by a ball joint where it starts (a fixed point; e.g. a simply
            supported beam).
        step, duration : float, optional
            The time step (s) and the length (s) of the runs the model is for: a beam with
            ``modes_per_plane="auto"`` and no ``frequency_cutoff`` keeps the modes at or below
            a cutoff derived from them (``build_chain``).
        tree : {"as added", "shortest"}, optional
            The spanning tree of a system with closing joints: "as added" (default), or
            "shortest": the breadth-first tree from the ground over every joint, tree and
            closing alike, so that each loop runs through the fewest bodies (a loop's rows
            cost a step over its bodies; docs/loops.md, "Choosing the spanning tree").  A
            body the new tree reaches at another point is the same body described from that
            point, so its input point (``position_input``) is that point; the joints keep
            their names, the ones left out of the tree closing the loops.  A joint with
            coordinates the new tree takes from its loop, or runs the other way, starts where
            the system stands: its slides at the gaps between its points, its rates those of
            the bodies' motion at t = 0.

        Returns
        -------
        Model
            The frozen system, bodies numbered parents first (in the order added where that
            allows).

        Raises
        ------
        ValueError
            No bodies; an entry that is not a body or whose joint is not a joint; a body added
            twice; two bodies of one name; a parent not in the system, the body itself, or
            parents that form a cycle; an attachment point the parent does not have (naming
            the points it has); tip not "free" or "ball", or "ball" for a tree; bad gravity or
            ground; and every element's own checks (naming the element, its index and the
            argument; see each class), and the checks across elements: a beam's mode family
            against its ends, a rotation or angular velocity contradicting the joint before a
            body, a ball-joint body with no inertia about its hinge-to-hinge axis; tree not
            "as added" or "shortest", or a tree="shortest" the system cannot be rebuilt on
            (naming the body or the joint).
        """
        if tree not in ("as added", "shortest"):
            raise ValueError(f"System.build: tree must be 'as added' or 'shortest', got "
                             f"{tree!r}")
        bodies, joints, parents, attach = _resolve_topology(self._entries)
        model = _freeze(bodies, joints, parents, attach, self.gravity, self.ground, tip, step,
                        duration, closures=self._closures)
        if tree == "as added" or not self._closures:
            return model
        rebuilt = shortest_tree(self._entries, self._closures, model, bodies)
        if isinstance(rebuilt, str):
            raise ValueError(f"System.build(tree='shortest'): {rebuilt}; build the tree as "
                             f"added (tree='as added')")
        system = System(gravity=self.gravity, ground=self.ground)
        system._entries, system._closures = rebuilt
        return system.build(tip, step, duration)


def build_chain(elements: Sequence, gravity=(0.0, -9.81, 0.0), ground: Ground = Ground(),
                tip="free", step=None, duration=None) -> "Model":
    """Validate a chain described root to tip and freeze it into a Model (a System whose every
    body hangs from the output point of the one before it; the same model as ``System.add``
    body by body).

    Parameters
    ----------
    elements : sequence
        Hinges and bodies alternately, starting with the root hinge (which joins the first
        body to the ground) and ending with the tip body::

            [hinge_0, body_0, hinge_1, body_1, ..., hinge_{n-1}, body_{n-1}]

        Hinges: any joint kind (BallJoint, FixedHinge, ElasticHinge, RevoluteJoint,
        UniversalJoint, PrismaticJoint, ...: elements/kinds.py); bodies: RigidBody,
        EulerBernoulliBeam.
    gravity : array_like of 3, optional
        Gravitational acceleration, world frame, m/s^2 (default (0, -9.81, 0)).
    ground : Ground, optional
        Where the root hinge attaches (default: the origin and the identity frame, fixed).
    tip : {"free", "ball"}, optional
        "free" (default), or "ball": the tip body's output point is joined to the ground by a
        ball-and-socket joint where it starts (a fixed point; e.g. a simply supported beam).
    step : float, optional
        The time step the model will run at, s.  A beam with ``modes_per_plane="auto"`` and
        no ``frequency_cutoff`` keeps the modes at or below 1 / (20 step) Hz (what the step
        resolves, about 20 steps per period), lowered, with ``duration``, to ten times the
        drives' bandwidth: the frequency below which 99% of the energy of the prescribed
        motions' accelerations (the ground's, JointMotion drives') lies over [0, duration]
        (modes well above what drives the system follow it quasi-statically).  Gravity and
        initial conditions excite every mode; where they matter, give frequency_cutoff.
        ``model.describe()`` says which cutoff was kept and why.
    duration : float, optional
        The runs' length, s (with step): the span over which the drives' bandwidth is taken.

    Returns
    -------
    Model
        The frozen chain, body k the k-th body of elements.

    Raises
    ------
    ValueError
        An empty or odd-length elements list; a hinge or body where the other is expected
        (naming the element's position); tip not "free" or "ball"; bad gravity or ground; and
        every element's own checks and the checks across elements, as ``System.build``.

    Examples
    --------
    A triple pendulum of unit rods:

    >>> import dttmm
    >>> def rod():
    ...     return dttmm.RigidBody(mass=1.0, inertia=[1e-4, 1 / 12, 1 / 12],
    ...                            inertia_about="mass_center", to_mass_center=[0.5, 0, 0],
    ...                            to_output=[1.0, 0, 0])
    >>> model = dttmm.build_chain([dttmm.BallJoint(), rod(), dttmm.BallJoint(), rod(),
    ...                            dttmm.BallJoint(), rod()])
    >>> model.n_bodies
    3
    """
    elements = list(elements)
    if len(elements) == 0:
        raise ValueError("Chain: elements is empty; a chain needs at least a root hinge and a body")
    if len(elements) % 2 != 0:
        raise ValueError("Chain: elements must alternate hinge, body, hinge, body, ... and end "
                         f"with a body; got {len(elements)} elements")
    hinges, bodies = elements[0::2], elements[1::2]
    for k, h in enumerate(hinges):
        if joint_kind_of(h) is None:
            raise ValueError(f"Chain: element {2 * k} must be a hinge ({names(JOINT_KINDS)}), "
                             f"got {type(h).__name__}")
    for k, b in enumerate(bodies):
        if body_kind_of(b) is None:
            raise ValueError(f"Chain: element {2 * k + 1} must be a body ({names(BODY_KINDS)}), "
                             f"got {type(b).__name__}")
    parents = [-1] + list(range(len(bodies) - 1))
    return _freeze(bodies, hinges, parents, [0] * len(bodies), gravity, ground, tip, step,
                   duration)


def _resolve_topology(entries):
    """(bodies, joints, parent index, attachment index) in topological order (parents first,
    otherwise as added) from System entries; ValueError for a parent not in the system, an
    attachment point the parent lacks, a body added twice and a cycle."""
    if not entries:
        raise ValueError("System: no bodies; add at least one (System.add(body, joint))")
    for i, (body, joint, _, _) in enumerate(entries):
        if body_kind_of(body) is None:
            raise ValueError(f"System: entry {i}: {body!r} is not a body ({names(BODY_KINDS)})")
        if joint_kind_of(joint) is None:
            raise ValueError(f"System: {_who(body, i)}: joint must be one of "
                             f"{names(JOINT_KINDS)}, got {type(joint).__name__}")
    by_id = {}
    by_name = {}
    for i, (body, _, _, _) in enumerate(entries):
        if id(body) in by_id:
            raise ValueError(f"System: {_who(body, i)} is added twice")
        by_id[id(body)] = i
        if body.name:
            if body.name in by_name:
                raise ValueError(f"System: two bodies are named '{body.name}'; names must be "
                                 f"unique")
            by_name[body.name] = i
    parent_of = []
    for i, (body, _, parent, _) in enumerate(entries):
        if parent is None or (isinstance(parent, str) and parent == "ground"):
            parent_of.append(-1)
        elif isinstance(parent, str):
            if parent not in by_name:
                raise ValueError(f"System: {_who(body, i)}: parent '{parent}' is not in the "
                                 f"system (bodies: {', '.join(sorted(by_name)) or 'none named'})")
            parent_of.append(by_name[parent])
        elif id(parent) in by_id:
            parent_of.append(by_id[id(parent)])
        else:
            raise ValueError(f"System: {_who(body, i)}: parent {_who(parent)} is not in the "
                             f"system (add it too)")
        if parent_of[-1] == i:
            raise ValueError(f"System: {_who(body, i)} is its own parent")
    order, state = [], [0] * len(entries)           # 0 new, 1 on the path, 2 placed

    def place(i, path):
        if state[i] == 2:
            return
        if state[i] == 1:
            cycle = " -> ".join(_who(entries[j][0], j) for j in path[path.index(i):] + [i])
            raise ValueError(f"System: the parents form a cycle: {cycle}")
        state[i] = 1
        if parent_of[i] >= 0:
            place(parent_of[i], path + [i])
        state[i] = 2
        order.append(i)

    for i in range(len(entries)):
        place(i, [])
    new_index = {i: k for k, i in enumerate(order)}
    bodies = [entries[i][0] for i in order]
    joints = [entries[i][1] for i in order]
    parents = [new_index[parent_of[i]] if parent_of[i] >= 0 else -1 for i in order]
    attach = []
    for k, i in enumerate(order):
        at, p = entries[i][3], parents[k]
        if p < 0 and at is not None and not isinstance(at, str):    # a point of the ground
            at = finite_vector(f"System: {_who(bodies[k], i)}", "at (a point of the ground)", at)
            attach.append(at)
            continue
        if at is None or at == "output":
            attach.append(0)
            continue
        if p < 0:
            raise ValueError(f"System: {_who(bodies[k], i)}: at={at!r}: the ground has no named "
                             f"points; give a root's place on the ground as [x, y, z] (m, in "
                             f"the ground frame from the ground point), or leave at=None")
        pts = getattr(bodies[p], "points", None) or {}
        if at not in pts:
            raise ValueError(f"System: {_who(bodies[k], i)}: at={at!r}: {_who(bodies[p])} has no "
                             f"attachment point {at!r} (it has: {', '.join(['output', *pts])})")
        attach.append(1 + list(pts).index(at))
    return bodies, joints, parents, attach
