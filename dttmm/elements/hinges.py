"""Hinge elements: smooth ball-and-socket, fixed, and elastic (spring-damper) hinges.

A hinge joins the output point of its inboard body (or the ground point, for the root hinge) to
the input point of its outboard body.  See docs/hinges.md for the equations.
"""
from dataclasses import dataclass

import numpy as np

from ._checks import finite_vector, matrix3, rotation_matrix, symmetric_positive

BALL, FIXED, ELASTIC = 0, 1, 2        # Model.hinge_kind (declared in kinds.py)
FREE = 8                               # (after the joints with coordinates, 3..7)

# layout of one row of Model.hinge_params (3x3 blocks, row-major); a joint's axes, coordinates
# and rates follow (elements/kinds.py: AXES, COORDINATE_0, RATE_0, HINGE_PARAM_SIZE)
REST_ROTATION = slice(0, 9)        # R0: outboard frame = inboard frame R0 at rest
K_TRANSLATION = slice(9, 18)       # in the inboard body's frame, N/m
C_TRANSLATION = slice(18, 27)      # N s/m
K_ROTATION = slice(27, 36)         # N m/rad
C_ROTATION = slice(36, 45)         # N m s/rad
DEFLECTION_0 = slice(45, 48)       # an elastic hinge's deflection d at t = 0 (world, m), in
#                                    the first axis slot (kinds.AXIS_1), which it has no use for
DEFLECTION_RATE_0 = slice(48, 51)  # its rate at t = 0 (world, m/s; zero for an elastic hinge,
#                                    a free joint's from its velocity), in the second axis slot


@dataclass(frozen=True, eq=False)
class BallJoint:
    """Smooth ball-and-socket hinge: positions and forces pass, no moment, free relative
    rotation (docs/hinges.md, "Smooth ball-and-socket").

    Massless and frictionless: the outboard input point stays on the inboard attachment point
    and the outboard body turns freely.  The outboard body starts in its own given rotation
    (the identity by default; ``RigidBody.rotation``).

    Parameters
    ----------
    name : str, optional
        The hinge's name, in messages and ``Model.hinge_names`` (default "":
        ``BallJoint{k}``).

    Examples
    --------
    >>> import dttmm
    >>> root = dttmm.BallJoint(name="shoulder")
    """
    name: str = ""
    kind = BALL

    def validated(self, index=None):
        return dict(rotation=np.eye(3), k_t=np.zeros((3, 3)), c_t=np.zeros((3, 3)),
                    k_r=np.zeros((3, 3)), c_r=np.zeros((3, 3)))


@dataclass(frozen=True, eq=False)
class FixedHinge:
    """Rigid weld: A_out = A_in @ rotation (a constant relative rotation, identity by default;
    docs/hinges.md, "Fixed hinge").

    The outboard body shares the inboard one's attachment point, angular velocity and
    acceleration; its initial rotation and angular velocity follow from the inboard body's (a
    contradicting ``rotation`` or ``angular_velocity`` given to the outboard body is refused).
    A body joined to the ground by fixed hinges only (through rigid bodies) is locked to the
    ground's motion.  At a beam's output the weld is to the beam's deflected end section.

    Parameters
    ----------
    rotation : array_like (3, 3), optional
        R0, the outboard frame relative to the inboard one (body to body; a proper rotation
        matrix, det +1, to 1e-9).  None (default): the identity.
    name : str, optional
        The hinge's name, in messages and ``Model.hinge_names`` (default "":
        ``FixedHinge{k}``).

    Raises
    ------
    ValueError
        At build time, naming the hinge (its name and index): a rotation that is not a proper
        rotation matrix.

    Examples
    --------
    A clamped root, the body turned 90 degrees about world z:

    >>> import dttmm
    >>> clamp = dttmm.FixedHinge(rotation=[[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    """
    rotation: object = None
    name: str = ""
    kind = FIXED

    def validated(self, index=None):
        who = _label(self, index)
        r = np.eye(3) if self.rotation is None else rotation_matrix(who, "rotation", self.rotation)
        return dict(rotation=r, k_t=np.zeros((3, 3)), c_t=np.zeros((3, 3)),
                    k_r=np.zeros((3, 3)), c_r=np.zeros((3, 3)))


@dataclass(frozen=True, eq=False)
class ElasticHinge:
    """Linear translational and rotational springs with optional viscous dampers
    (docs/hinges.md, "Elastic hinge").

    The outboard input point sits at the inboard output point plus a deflection d (world); the
    outboard frame is A_out = A_in expm(psi^) R0.  Springs and dampers act in the inboard
    body's frame (at a beam's output: its deflected end section)::

        q (force on the outboard side)       = -A_in (K_t d_b + C_t d'_b),  d_b = A_in^T d,
                                                                             d'_b = A_in^T d/dt(d)
        m (couple on the outboard side, about its input point)
                                             = -A_in (K_r psi + C_r A_in^T (w_out - w_in)).

    The hinge starts at the given deflection (``deflection``; d = 0 by default, or where
    ``static_equilibrium`` left it); the outboard body starts in the inboard frame turned
    by R0 unless it is given a rotation of its own (``RigidBody.rotation``).  Stiffnesses are
    scalars (times the identity), 3 diagonal entries or symmetric positive definite 3x3
    matrices; dampings likewise but may be zero (positive semidefinite).  Newmark scheme only.

    Parameters
    ----------
    translational_stiffness : float, array_like of 3, or array_like (3, 3)
        K_t, N/m (symmetric positive definite).
    rotational_stiffness : float, array_like of 3, or array_like (3, 3)
        K_r, N m/rad (symmetric positive definite).
    translational_damping : float, array_like of 3, or array_like (3, 3), optional
        C_t, N s/m (symmetric positive semidefinite); default 0.
    rotational_damping : float, array_like of 3, or array_like (3, 3), optional
        C_r, N m s/rad (symmetric positive semidefinite); default 0.
    rotation : array_like (3, 3), optional
        R0, the rest rotation of the outboard frame relative to the inboard one (a proper
        rotation matrix, det +1, to 1e-9).  None (default): the identity.
    name : str, optional
        The hinge's name, in messages and ``Model.hinge_names`` (default "":
        ``ElasticHinge{k}``).
    deflection : array_like of 3, optional
        d at t = 0, world frame, m (the outboard input point's offset from the inboard output
        point; its rate starts at zero).  None (default): undeflected.

    Raises
    ------
    ValueError
        At build time, naming the hinge (its name and index) and the argument: a stiffness or
        damping that is not a scalar, 3 entries or a 3x3 matrix, has non-finite entries, is
        not symmetric, or is not positive definite (stiffness) or semidefinite (damping); a
        rotation that is not a proper rotation matrix; a deflection that is not 3 finite
        numbers.

    Examples
    --------
    >>> import dttmm
    >>> spring = dttmm.ElasticHinge(translational_stiffness=1e6, rotational_stiffness=[50, 50, 80],
    ...                             rotational_damping=0.1)
    """
    translational_stiffness: object
    rotational_stiffness: object
    translational_damping: object = 0.0
    rotational_damping: object = 0.0
    rotation: object = None
    name: str = ""
    deflection: object = None
    kind = ELASTIC

    def validated(self, index=None):
        who = _label(self, index)
        r = np.eye(3) if self.rotation is None else rotation_matrix(who, "rotation", self.rotation)
        k_t = symmetric_positive(who, "translational_stiffness",
                                 matrix3(who, "translational_stiffness",
                                         self.translational_stiffness))
        k_r = symmetric_positive(who, "rotational_stiffness",
                                 matrix3(who, "rotational_stiffness", self.rotational_stiffness))
        c_t = symmetric_positive(who, "translational_damping",
                                 matrix3(who, "translational_damping", self.translational_damping),
                                 semidefinite=True)
        c_r = symmetric_positive(who, "rotational_damping",
                                 matrix3(who, "rotational_damping", self.rotational_damping),
                                 semidefinite=True)
        d0 = (np.zeros(3) if self.deflection is None
              else finite_vector(who, "deflection", self.deflection, size=3))
        return dict(rotation=r, k_t=k_t, c_t=c_t, k_r=k_r, c_r=c_r, d0=d0)


@dataclass(frozen=True, eq=False)
class FreeJoint:
    """Six degrees of freedom: the body flies free (docs/free_joint.md).

    Nothing passes the joint: no force, no moment.  The body's input point starts at
    ``position`` from the attachment point, in the parent's frame (the ground's for a root),
    moving at ``velocity`` (world frame, absolute, like ``RigidBody.angular_velocity``); the
    body turns freely from its own ``rotation`` and world-frame ``angular_velocity``, as behind
    a ball joint.  Behind it a whole subtree flies: a free rigid body, a hub with flexible
    panels, a chain of links on ball joints.  Its offset from the attachment point is a
    Newmark coordinate of the joint, as an elastic hinge's deflection (``Result`` positions
    and velocities include it).

    Parameters
    ----------
    position : array_like of 3, optional
        The body's input point at t = 0 relative to the attachment point, in the parent's
        frame (the ground's for a root), m.  Default (0, 0, 0).
    velocity : array_like of 3, optional
        The input point's velocity at t = 0, world frame, m/s (absolute, not relative to the
        parent).  Default (0, 0, 0).
    name : str, optional
        The joint's name, in messages and ``Model.hinge_names`` (default "": ``FreeJoint{k}``).

    Raises
    ------
    ValueError
        At build time, naming the joint (its name and index) and the argument: a position or
        velocity that is not 3 finite numbers.

    Examples
    --------
    A box tumbling in space, its input point at its mass centre:

    >>> import dttmm
    >>> box = dttmm.RigidBody(mass=1.0, inertia=[0.00417, 0.00833, 0.01083],
    ...                       inertia_about="mass_center", angular_velocity=[1e-3, 4.0, 1e-3])
    >>> model = dttmm.build_chain([dttmm.FreeJoint(), box], gravity=[0, 0, 0])
    """
    position: object = (0.0, 0.0, 0.0)
    velocity: object = (0.0, 0.0, 0.0)
    name: str = ""
    kind = FREE

    def validated(self, index=None):
        who = _label(self, index)
        zero = np.zeros((3, 3))
        return dict(rotation=np.eye(3), k_t=zero, c_t=zero, k_r=zero, c_r=zero,
                    d0=finite_vector(who, "position", self.position, size=3),
                    d_rate0=finite_vector(who, "velocity", self.velocity, size=3))


def _label(hinge, index):
    where = f"hinge {index}" if index is not None else "hinge"
    kind = type(hinge).__name__
    return f"{kind} '{hinge.name}' ({where})" if hinge.name else f"{kind} ({where})"


def row_blocks(v, row):
    """The hinge's R0, springs, dampers and deflection (validated()'s dict v) into its
    hinge_params row (elements/kinds.py::pack_hinge packs the rest); returns row."""
    row[REST_ROTATION] = v["rotation"].reshape(-1)
    row[K_TRANSLATION] = v["k_t"].reshape(-1)
    row[C_TRANSLATION] = v["c_t"].reshape(-1)
    row[K_ROTATION] = v["k_r"].reshape(-1)
    row[C_ROTATION] = v["c_r"].reshape(-1)
    if "d0" in v:
        row[DEFLECTION_0] = v["d0"]
    if "d_rate0" in v:
        row[DEFLECTION_RATE_0] = v["d_rate0"]
    return row
