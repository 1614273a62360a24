"""Every element kind, declared once: its class, its code in the model's arrays, and what it
supports (docs/README.md, "Adding an element kind").

The model builder, the solver and the result read these declarations, never a class or a code
of their own: a combination a kind does not declare (a scheme, the fused loop, the direct
sweep) is refused with a ValueError naming the element before a run starts, and every kernel's
dispatch on the codes ends in an explicit refusal (kernels/stepping/loop.py, UNSUPPORTED) rather
than running one kind as another.
"""
from dataclasses import dataclass

from .beam import EulerBernoulliBeam
from .hinges import BALL, ELASTIC, FIXED, BallJoint, ElasticHinge, FixedHinge
from .joints import PRISMATIC, REVOLUTE, UNIVERSAL, PrismaticJoint, RevoluteJoint, UniversalJoint
from .rigid_body import RigidBody
from .strain_rod import StrainRod

RIGID, BEAM, ROD = 0, 1, 2      # Model.body_kind

SCHEMES = ("newmark", "energy_momentum", "paper", "dop853")


@dataclass(frozen=True)
class Kind:
    """One element kind.

    code:        its value in Model.body_kind or Model.hinge_kind.
    cls:         the element class users build it from.
    schemes:     the solver's schemes whose loops implement it (none: built, validated and run by
                 the Newton-Euler reference only, so far).
    fused:       bodies: the fused ball-chain loop (kernels/stepping/ball_chain.py) has its
                 reduced map.
    moment_free: joints: transmits no moment (the reduced [a; q] form and the fused loop apply
                 across it).
    coordinates: joints: its free coordinates (each with its drive, its columns in a Result and
                 its rows in the kernels: coordinate_count, kernels/transfers/joint.py).
    doc:         the page that derives its equations.
    what:        how messages describe it ("hinge 'spring' is elastic").
    """
    code: int
    cls: type
    schemes: tuple
    fused: bool = False
    moment_free: bool = False
    coordinates: int = 0
    doc: str = ""
    what: str = ""

    @property
    def name(self):
        return self.cls.__name__


BODY_KINDS = (
    Kind(RIGID, RigidBody, SCHEMES, fused=True, doc="docs/rigid_body.md", what="a rigid body"),
    Kind(BEAM, EulerBernoulliBeam, ("newmark", "paper", "dop853"), fused=True, doc="docs/beam.md",
         what="a beam"),
    Kind(ROD, StrainRod, ("newmark",), doc="docs/strain_rod.md", what="a strain rod"),
)
FLEXIBLE = (BEAM, ROD)      # the body kinds with coordinates of their own (Model.n_modes)

JOINT_KINDS = (
    Kind(BALL, BallJoint, SCHEMES, moment_free=True, doc="docs/hinges.md", what="a ball joint"),
    Kind(FIXED, FixedHinge, ("newmark", "energy_momentum", "paper"), doc="docs/hinges.md",
         what="a fixed hinge"),
    Kind(ELASTIC, ElasticHinge, ("newmark",), doc="docs/hinges.md", what="elastic"),
    # joints with coordinates and drives (kernels/transfers/joint.py): the general loop's full-state
    # tree sweep
    Kind(REVOLUTE, RevoluteJoint, ("newmark",), coordinates=1, doc="docs/joints.md",
         what="a revolute joint"),
    Kind(UNIVERSAL, UniversalJoint, ("newmark",), coordinates=2, doc="docs/joints.md",
         what="a universal joint"),
    Kind(PRISMATIC, PrismaticJoint, ("newmark",), coordinates=1, doc="docs/joints.md",
         what="a prismatic joint"),
)

# the kinds of a closing joint's constraint rows (closures.py::constraint_rows, read by
# kernels/assembly/closure.py and the reference): gaps e . (p_b - p_a) with e fixed in the world
# or in a's frame, dots (F_a x) . (F_b y), a driven coordinate's angle about an axis fixed in a's
# or in b's frame (closures.py::driven_directions), and an elastic hinge's rotation about an
# axis fixed in a's frame (closures.py::spring_directions)
GAP_WORLD, GAP_A, DOT, ANGLE_A, ANGLE_B, ROTATION_A = 0, 1, 2, 3, 4, 5

BODY_KIND = {k.code: k for k in BODY_KINDS}
JOINT_KIND = {k.code: k for k in JOINT_KINDS}
HINGE_KIND_NAMES = {k.code: k.name for k in JOINT_KINDS}
# each joint code's free coordinates, by code (a tuple the kernels index: numba reads it as a
# constant; kernels/transfers/joint.py::n_coordinates)
COORDINATES = tuple(JOINT_KIND[code].coordinates if code in JOINT_KIND else 0
                    for code in range(max(JOINT_KIND) + 1))


WITH_COORDINATES = tuple(k.code for k in JOINT_KINDS if k.coordinates)    # (their codes)


def coordinate_count(kind):
    """The free coordinates of a joint kind (its code), as its declaration says."""
    return COORDINATES[kind] if 0 <= kind < len(COORDINATES) else 0


def body_kind_of(element):
    """The Kind of a body element, or None if it is not one."""
    return next((k for k in BODY_KINDS if type(element) is k.cls), None)


def joint_kind_of(element):
    """The Kind of a joint element, or None if it is not one."""
    return next((k for k in JOINT_KINDS if type(element) is k.cls), None)


def names(kinds):
    return ", ".join(k.name for k in kinds)
