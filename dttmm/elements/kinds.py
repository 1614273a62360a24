"""Every element kind, declared once: its class, its code in the model's arrays, and what it
supports (docs/README.md, "Adding an element kind").

The model builder, the solver and the result read these declarations, never a class or a code
of their own: a combination a kind does not declare (a scheme, the fused loop, the direct
sweep) is refused with a ValueError naming the element before a run starts, and every kernel's
dispatch on the codes ends in an explicit refusal (kernels/stepping/loop.py, UNSUPPORTED) rather
than running one kind as another.

A joint with coordinates declares each coordinate (Coordinate: a turn or a slide, its axis's
slot in the hinge_params row, the frame that axis is fixed in), its scene type and its class's
argument names; the kernels (kernels/transfers/joint.py), the reference (reference/equations.py)
and the Python side (the build, closures, statics, linearize, scenes, describe) read that, so a
joint of turns about axes fixed in the parent or the child and slides along axes fixed in the
parent, at most MAX_COORDINATES of them, is its class and one declaration here.
"""
from dataclasses import dataclass

import numpy as np

from .beam import EulerBernoulliBeam
from .hinges import (BALL, ELASTIC, FIXED, FREE, BallJoint, ElasticHinge, FixedHinge, FreeJoint,
                     row_blocks)
from .joints import (CYLINDRICAL, PLANAR, PRISMATIC, REVOLUTE, UNIVERSAL, CylindricalJoint,
                     PlanarJoint, PrismaticJoint, RevoluteJoint, UniversalJoint, rotation_about)
from .rigid_body import RigidBody
from .strain_rod import StrainRod

RIGID, BEAM, ROD = 0, 1, 2      # Model.body_kind
# what a kernel raises on a body kind code its dispatch does not name, rather than run it as
# another kind (the Python layer refuses such a code first, naming the body: declared_body_kind,
# solving/run_checks.py::check_supported)
UNDECLARED_BODY_KIND = "a body kind code this kernel does not implement (elements/kinds.py)"

SCHEMES = ("newmark", "energy_momentum", "paper", "dop853")


# the joints' coordinates: each a turn (an angle, rad; its drive a moment about the axis, N m)
# or a slide (m; a force along the axis, N), about or along an axis fixed in the parent's frame
# (its output section) or in the child's (after R0)
TURN, SLIDE = 1, 2              # (0: no coordinate, in the padded tables below)
PARENT, CHILD = 0, 1
MAX_COORDINATES = 3             # the most coordinates a joint kind has: the width of every
#                                 per-joint table of coordinates, rates, drives and directions
CLOSING_DRIVES = 2              # a closing joint's drivable coordinates (its record's slots:
#                                 kernels/schema.py::LOOPS' wrench, closure_drive_force)


@dataclass(frozen=True)
class Coordinate:
    """One coordinate of a joint kind: its motion (TURN or SLIDE), its axis's slot in the
    hinge_params row (0, 1, 2: AXES[slot]) and the frame that axis is fixed in (PARENT or CHILD;
    slides: PARENT)."""
    motion: int
    axis: int
    frame: int = PARENT


# the joints' slots of a hinge_params row (elements/hinges.py holds the first 45 entries: R0,
# the springs and dampers, an elastic hinge's deflection): three axes, the coordinates and their
# rates at t = 0
AXES = (slice(45, 48), slice(48, 51), slice(57, 60))
AXIS_1, AXIS_2, AXIS_3 = AXES
COORDINATE_0 = slice(51, 51 + MAX_COORDINATES)
RATE_0 = slice(COORDINATE_0.stop, COORDINATE_0.stop + MAX_COORDINATES)
HINGE_PARAM_SIZE = 60
AXIS_START = tuple(a.start for a in AXES)       # (a constant the kernels index)
assert RATE_0.stop == AXIS_3.start and AXIS_3.stop == HINGE_PARAM_SIZE


# a joint with coordinates' end stops (elements/limits.py): (lower, upper, stiffness, damping)
# of coordinate i at LIMIT_0 + LIMIT_SIZE i, in the slots of an elastic hinge's translational
# spring and damper, which it has no use for; stiffness 0: no stop on that coordinate
LIMIT_0, LIMIT_SIZE = 9, 4
assert LIMIT_0 + LIMIT_SIZE * MAX_COORDINATES <= 27


def limit_of(row, i):
    """(lower, upper, stiffness, damping) of coordinate i's end stops in a hinge_params row."""
    return row[LIMIT_0 + LIMIT_SIZE * i:LIMIT_0 + LIMIT_SIZE * (i + 1)]


def pack_hinge(v):
    """A hinge's validated parameters (its validated()) as one hinge_params row: R0, springs and
    dampers, deflection (hinges.py::row_blocks), and a joint's axes, coordinates and rates at
    t = 0 (zero past its own) and its end stops (LIMIT_0)."""
    row = row_blocks(v, np.zeros(HINGE_PARAM_SIZE))
    if "axes" in v:
        for slot, axis in enumerate(v["axes"]):
            row[AXES[slot]] = axis
        q0, qd0 = np.asarray(v["q0"], dtype=float), np.asarray(v["qd0"], dtype=float)
        row[COORDINATE_0.start:COORDINATE_0.start + len(q0)] = q0
        row[RATE_0.start:RATE_0.start + len(qd0)] = qd0
        for i, limit in enumerate(v.get("limits", ())):
            if limit is not None:
                start = LIMIT_0 + LIMIT_SIZE * i
                row[start:start + LIMIT_SIZE] = limit
    return row


@dataclass(frozen=True)
class Kind:
    """One element kind.

    code:        its value in Model.body_kind or Model.hinge_kind.
    cls:         the element class users build it from.
    schemes:     the solver's schemes whose loops implement it (none: built, validated and run by
                 the Newton-Euler reference only, so far).
    fused:       bodies: the fused ball-chain loop (kernels/stepping/ball_chain.py) has its
                 reduced map.
    flexible:    bodies: it has coordinates of its own (Model.n_modes: a beam's modal, a rod's
                 strain coordinates), its output point and output section (its end section)
                 move with them, and it has one attachment point, its output end; else it is
                 rigid: its output section is its own frame.
    moment_free: joints: transmits no moment (the reduced [a; q] form and the fused loop apply
                 across it).
    deflects:    joints: its child's input point is offset from the attachment point by d
                 (world), a Newmark coordinate of the joint (Model state.defl, recorded, in the
                 positions): an elastic hinge's deflection, a free joint's flight.
    carries_loads: joints: False where nothing passes it (a free joint): in the step it is
                 LOCKED with zero loads on both sides (kernels/assembly/sweep.py), the child's
                 subtree's motion solved from its own loads alone.
    coordinates: joints: its free coordinates, Coordinate each, in its own order (each with its
                 drive, its columns in a Result and its rows in the kernels: coordinate_count,
                 kernels/transfers/joint.py).  The family: turns fixed in the parent, then R0,
                 then turns fixed in the child (at most one in each frame), and slides along
                 axes fixed in the parent.
    freedoms:    joints: its degrees of freedom (describe); None: one per coordinate.
    closure_rows: joints: the constraint equations it holds as a closing joint (describe,
                 loop_rows.constraint_directions); None: 6 less its freedoms.
    scene:       its type in scene files (and describe's name for a joint).
    arguments:   joints with coordinates: its class's names of the coordinates' initial values,
                 rates and drives (scalars for a joint of one coordinate, else sequences of one
                 per coordinate); flexible bodies: its class's names of its own coordinates'
                 initial values and rates.
    axes:        joints with coordinates: its class's axis arguments, in slot order (a slot past
                 them its validated() derives, as the planar joint's n1 x n2).
    doc:         the page that derives its equations.
    what:        how messages describe it ("hinge 'spring' is elastic").
    """
    code: int
    cls: type
    schemes: tuple
    fused: bool = False
    flexible: bool = False
    moment_free: bool = False
    deflects: bool = False
    carries_loads: bool = True
    coordinates: tuple = ()
    freedoms: object = None
    closure_rows: object = None
    scene: str = ""
    arguments: tuple = ()
    axes: tuple = ()
    doc: str = ""
    what: str = ""

    @property
    def name(self):
        return self.cls.__name__

    @property
    def dof(self):
        return len(self.coordinates) if self.freedoms is None else self.freedoms

    @property
    def constraints(self):
        return 6 - self.dof if self.closure_rows is None else self.closure_rows


BODY_KINDS = (
    Kind(RIGID, RigidBody, SCHEMES, fused=True, scene="rigid", doc="docs/rigid_body.md",
         what="a rigid body"),
    Kind(BEAM, EulerBernoulliBeam, ("newmark", "paper", "dop853"), fused=True, flexible=True,
         scene="beam", arguments=("initial_modal_coordinates", "initial_modal_velocities"),
         doc="docs/beam.md", what="a beam"),
    Kind(ROD, StrainRod, ("newmark",), flexible=True, scene="rod",
         arguments=("initial_strain", "initial_strain_rate"), doc="docs/strain_rod.md",
         what="a strain rod"),
)
FLEXIBLE = tuple(k.code for k in BODY_KINDS if k.flexible)     # (their codes: Model.n_modes)

_VALUES = ("coordinates", "rates", "drives")

JOINT_KINDS = (
    Kind(BALL, BallJoint, SCHEMES, moment_free=True, freedoms=3, scene="ball",
         doc="docs/hinges.md", what="a ball joint"),
    Kind(FIXED, FixedHinge, ("newmark", "energy_momentum", "paper"), freedoms=0, scene="fixed",
         doc="docs/hinges.md", what="a fixed hinge"),
    Kind(ELASTIC, ElasticHinge, ("newmark",), freedoms=6, closure_rows=0, deflects=True,
         scene="elastic", doc="docs/hinges.md", what="elastic"),
    Kind(FREE, FreeJoint, ("newmark", "energy_momentum", "dop853"), freedoms=6, closure_rows=0,
         deflects=True, carries_loads=False, scene="free", doc="docs/free_joint.md",
         what="a free joint"),
    # joints with coordinates and drives (kernels/transfers/joint.py): the general loop's full-state
    # tree sweep
    Kind(REVOLUTE, RevoluteJoint, ("newmark",), coordinates=(Coordinate(TURN, 0),),
         scene="revolute", arguments=("angle", "rate", "drive"), axes=("axis",),
         doc="docs/joints.md", what="a revolute joint"),
    Kind(UNIVERSAL, UniversalJoint, ("newmark",),
         coordinates=(Coordinate(TURN, 0), Coordinate(TURN, 1, CHILD)), scene="universal",
         arguments=("angles", "rates", "drives"), axes=("axis1", "axis2"), doc="docs/joints.md",
         what="a universal joint"),
    Kind(PRISMATIC, PrismaticJoint, ("newmark",), coordinates=(Coordinate(SLIDE, 0),),
         scene="prismatic", arguments=("position", "rate", "drive"), axes=("axis",),
         doc="docs/joints.md", what="a prismatic joint"),
    Kind(CYLINDRICAL, CylindricalJoint, ("newmark",),
         coordinates=(Coordinate(TURN, 0), Coordinate(SLIDE, 0)), scene="cylindrical",
         arguments=("coordinates", "rates", "drives"), axes=("axis",), doc="docs/joints.md",
         what="a cylindrical joint"),
    # two slides in the plane of axis1 and axis2 and a turn about its normal axis1 x axis2
    # (slot 2, which validated() derives); closing, 3 rows and drives on x and y only
    # (CLOSING_DRIVES)
    Kind(PLANAR, PlanarJoint, ("newmark",),
         coordinates=(Coordinate(SLIDE, 0), Coordinate(SLIDE, 1), Coordinate(TURN, 2)),
         scene="planar", arguments=("coordinates", "rates", "drives"), axes=("axis1", "axis2"),
         doc="docs/joints.md", what="a planar joint"),
)

# the kinds of a closing joint's constraint rows (model/loop_rows.py::constraint_rows, read by
# kernels/assembly/closure.py and the reference): gaps e . (p_b - p_a) with e fixed in the world
# or in a's frame, dots (F_a x) . (F_b y), a driven coordinate's angle about an axis fixed in a's
# or in b's frame (model/loop_rows.py::driven_directions), and an elastic hinge's rotation about an
# axis fixed in a's frame (model/loop_rows.py::spring_directions)
GAP_WORLD, GAP_A, DOT, ANGLE_A, ANGLE_B, ROTATION_A = 0, 1, 2, 3, 4, 5

BODY_KIND = {k.code: k for k in BODY_KINDS}
JOINT_KIND = {k.code: k for k in JOINT_KINDS}
HINGE_KIND_NAMES = {k.code: k.name for k in JOINT_KINDS}
SCENE_TYPE = {k.code: k.scene for k in JOINT_KINDS}         # code -> its scene type
for _kind in JOINT_KINDS:              # the family the generic kernels and twins implement
    _turns = [c for c in _kind.coordinates if c.motion == TURN]
    assert len(_kind.coordinates) <= MAX_COORDINATES and all(
        c.motion in (TURN, SLIDE) and 0 <= c.axis < len(AXES) and c.frame in (PARENT, CHILD)
        for c in _kind.coordinates), _kind
    assert all(c.frame == PARENT for c in _kind.coordinates if c.motion == SLIDE), _kind
    assert all(sum(c.frame == f for c in _turns) <= 1 for f in (PARENT, CHILD)), _kind
    assert not _kind.coordinates or len(_kind.arguments) == 3, _kind


def _table(field):
    """(per code) a tuple of MAX_COORDINATES ints: each coordinate's field, 0 past the kind's
    coordinates (a homogeneous tuple the kernels index: numba reads it as a constant)."""
    out = []
    for code in range(max(JOINT_KIND) + 1):
        spec = JOINT_KIND[code].coordinates if code in JOINT_KIND else ()
        out.append(tuple(getattr(c, field) for c in spec) + (0,) * (MAX_COORDINATES - len(spec)))
    return tuple(out)


# each joint code's free coordinates, by code (a tuple the kernels index: numba reads it as a
# constant; kernels/transfers/joint.py::n_coordinates), and per coordinate its motion (TURN,
# SLIDE; 0 past them), axis slot and frame
COORDINATES = tuple(len(JOINT_KIND[code].coordinates) if code in JOINT_KIND else 0
                    for code in range(max(JOINT_KIND) + 1))
MOTION, AXIS, FRAME = _table("motion"), _table("axis"), _table("frame")

WITH_COORDINATES = tuple(k.code for k in JOINT_KINDS if k.coordinates)    # (their codes)
DEFLECTING = tuple(k.code for k in JOINT_KINDS if k.deflects)             # (their codes)
# (per code) 1 where the joint's child's input point is offset by the joint's own Newmark
# coordinate d (state.defl), else 0: a tuple the kernels index (numba reads it as a constant)
DEFLECTS = tuple(int(code in DEFLECTING) for code in range(max(JOINT_KIND) + 1))
WITH_SLIDES = tuple(k.code for k in JOINT_KINDS if any(c.motion == SLIDE for c in k.coordinates))
WITH_TURNS = tuple(k.code for k in JOINT_KINDS if any(c.motion == TURN for c in k.coordinates))
HAS_SLIDES = tuple(int(code in WITH_SLIDES) for code in range(max(JOINT_KIND) + 1))
# (per code) the index of its turn fixed in the parent and of its turn fixed in the child, -1
# where it has none (at most one each, asserted above): the order joint_frame turns them in
TURNS = tuple(tuple(next((i for i, c in enumerate(JOINT_KIND[code].coordinates)
                          if c.motion == TURN and c.frame == frame), -1)
                    if code in JOINT_KIND else -1 for frame in (PARENT, CHILD))
              for code in range(max(JOINT_KIND) + 1))


def coordinate_count(kind):
    """The free coordinates of a joint kind (its code), as its declaration says."""
    return COORDINATES[kind] if 0 <= kind < len(COORDINATES) else 0


def coordinates_of(kind):
    """The Coordinate declarations of a joint kind (its code; () for a kind without)."""
    return JOINT_KIND[int(kind)].coordinates if int(kind) in JOINT_KIND else ()


def joint_values(element):
    """(values, rates, drives) of a joint with coordinates as its class's arguments give them,
    a list of one per coordinate each (Kind.arguments)."""
    kind = joint_kind_of(element)
    out = [getattr(element, name) for name in kind.arguments]
    if len(kind.coordinates) == 1:
        return [[v] for v in out]
    return [list(v) for v in out]


def row_axes(row):
    """A hinge_params row's three axes, by slot (AXES)."""
    return tuple(np.asarray(row[a], dtype=float) for a in AXES)


def turn_rotations(kind, axes, q):
    """(R_P, R_C): the product of a joint's turns fixed in the parent (applied before R0) and
    of those fixed in the child (after it) at the coordinates q, A = A_P R_P R0 R_C; axes: the
    axes by slot (hinge_params' AXES, or validated()'s "axes")."""
    rots = [np.eye(3), np.eye(3)]
    for i, c in enumerate(coordinates_of(kind)):
        if c.motion == TURN:
            rots[c.frame] = rots[c.frame] @ rotation_about(np.asarray(axes[c.axis]), q[i])
    return rots[0], rots[1]


def joint_motion(kind, axes, r0, a_p, w_p, q, qd):
    """The child's frame behind a joint with coordinates, in numpy (the Python twin of
    kernels/transfers/joint.py::joint_frame, its velocities): (A, w, d, d', u) with
        A = A_P R_P R0 R_C,  w = w_P + sum over turns u_i q_i',
        d = sum over slides u_i q_i,  d' = w_P x d + sum over slides u_i q_i'
    (u (3, MAX_COORDINATES): each coordinate's world direction, u_i = A_P n_i for a slide or a
    turn fixed in the parent, A n_i for a turn fixed in the child; docs/joints.md)."""
    spec = coordinates_of(kind)
    u = np.zeros((3, MAX_COORDINATES))
    frame, w = np.asarray(a_p, dtype=float), np.array(w_p, dtype=float)
    for which in (PARENT, CHILD):
        if which == CHILD:
            frame = frame @ r0
        for i, c in enumerate(spec):
            if c.motion == TURN and c.frame == which:
                n = np.asarray(axes[c.axis], dtype=float)
                u[:, i] = frame @ n
                frame = frame @ rotation_about(n, q[i])
                w = w + u[:, i] * qd[i]
    d, d_rate = np.zeros(3), np.zeros(3)
    for i, c in enumerate(spec):
        if c.motion == SLIDE:
            u[:, i] = np.asarray(a_p) @ np.asarray(axes[c.axis], dtype=float)
            d = d + u[:, i] * q[i]
            d_rate = d_rate + u[:, i] * qd[i]
    return frame, w, d, d_rate + np.cross(w_p, d), u


def declared_body_kind(code, who="body"):
    """The Kind declaring body kind code `code` (Model.body_kind), or a ValueError naming who
    (a body's label) and the code: a table's code no declaration names is refused, never run as
    another kind's."""
    kind = BODY_KIND.get(int(code))
    if kind is None:
        raise ValueError(f"{who} has kind code {int(code)}, which no body kind declares "
                         f"(elements/kinds.py, BODY_KINDS: {names(BODY_KINDS)})")
    return kind


def unimplemented_body_kind(code, who, where):
    """The ValueError for body kind code `code` (of who, a body's label) at a dispatch, where,
    that has no branch for it: a code no kind declares (declared_body_kind raises), or a declared
    kind that place does not implement yet (docs/README.md, "Adding an element kind").  Every
    dispatch on the body kinds ends in it rather than running one kind as another."""
    kind = declared_body_kind(code, who)
    return ValueError(f"{who} is {kind.what} ({kind.name}), which {where} does not implement "
                      f"(docs/README.md, \"Adding an element kind\")")


def body_kind_of(element):
    """The Kind of a body element, or None if it is not one."""
    return next((k for k in BODY_KINDS if type(element) is k.cls), None)


def joint_kind_of(element):
    """The Kind of a joint element, or None if it is not one."""
    return next((k for k in JOINT_KINDS if type(element) is k.cls), None)


def names(kinds):
    return ", ".join(k.name for k in kinds)
