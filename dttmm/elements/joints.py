"""Joints with free coordinates: revolute, universal, prismatic, cylindrical and planar
(docs/joints.md).

Each joins its parent's attachment point (the parent's output section, frame A_P) to its child's
input point.  Axes are unit vectors, normalized here; a joint's coordinates q (angles in rad, a
slide in m) start at the given values and rates, or on a prescribed motion's:

  RevoluteJoint(axis):            A_child = A_P Rot(n, q) R0,  n = axis in the parent's frame
                                  (the same axis R0^T n is fixed in the child); the child's input
                                  point is the attachment point.
  UniversalJoint(axis1, axis2):   A_child = A_P Rot(n1, q1) R0 Rot(n2, q2),  n1 in the parent's
                                  frame, n2 in the child's; n1 and R0 n2 perpendicular.  The
                                  child cannot turn about n1 x (A_child n2).
  PrismaticJoint(axis):           A_child = A_P R0; the child's input point sits at the
                                  attachment point + A_P n q (it slides along n, fixed in the
                                  parent, and does not turn relative to the parent).
  CylindricalJoint(axis):         A_child = A_P Rot(n, theta) R0; the child's input point
                                  sits at the attachment point + A_P n s (it turns about and
                                  slides along n); coordinates (theta, s).
  PlanarJoint(axis1, axis2):      A_child = A_P Rot(n, theta) R0,  n = n1 x n2 the plane's
                                  normal; the child's input point sits at the attachment
                                  point + A_P (n1 x + n2 y) (it moves in the plane of n1 and
                                  n2, fixed in the parent, and turns about its normal);
                                  coordinates (x, y, theta).

R0 is the child's rotation relative to the parent at q = 0: the identity, or, when the child
body is given an initial rotation, whatever makes that rotation hold at the initial q.  A drive
(elements/drives.py) acts on each coordinate: a generalized force, a spring-damper, or a
prescribed motion.
"""
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ._checks import finite_scalar, finite_vector
from .drives import JointMotion, validated_drive
from .limits import JointLimit

REVOLUTE, UNIVERSAL, PRISMATIC, CYLINDRICAL, PLANAR = 3, 4, 5, 6, 7   # Model.hinge_kind


def _label(joint, index):
    where = f"hinge {index}" if index is not None else "hinge"
    kind = type(joint).__name__
    return f"{kind} '{joint.name}' ({where})" if joint.name else f"{kind} ({where})"


def unit_axis(who, argument, value):
    v = finite_vector(who, argument, value)
    scale = np.abs(v).max()          # (any finite length: 1e300 squared would overflow)
    u = v / scale if scale > 0.0 else v
    if np.linalg.norm(u) * scale < 1e-12:
        raise ValueError(f"{who}: {argument} must be a nonzero vector, got {v}")
    return u / np.linalg.norm(u)


def _coordinates(who, values, rates, drives, names):
    """Initial coordinates and rates, from the arguments or from a prescribed motion."""
    q0, qd0, checked = [], [], []
    for i, (q, qd, drive, name) in enumerate(zip(values, rates, drives, names)):
        q = finite_scalar(who, name[0], q)
        qd = finite_scalar(who, name[1], qd)
        if isinstance(drive, JointMotion):
            d = validated_drive(who, drive, q, qd)
            qm, qdm = drive.initial()
            if (q != 0.0 and abs(q - qm) > 1e-12) or (qd != 0.0 and abs(qd - qdm) > 1e-12):
                raise ValueError(f"{who}: {name[0]} = {q}, {name[1]} = {qd} contradict the "
                                 f"prescribed motion's ({qm}, {qdm}) at t = 0; leave them 0")
            q, qd = qm, qdm
        else:
            d = validated_drive(who, drive, q, qd)
        q0.append(q)
        qd0.append(qd)
        checked.append(d)
    return q0, qd0, checked


def _common(axes, q0, qd0, drives, limits):
    """A joint's validated parameters: R0 (the identity until the build reads it from the
    bodies), no springs, its axes by slot (elements/kinds.py::AXES), its coordinates' and
    rates' initial values, its drives and its end stops, one per coordinate (a stop: (lower,
    upper, stiffness, damping) or None)."""
    return dict(rotation=np.eye(3), k_t=np.zeros((3, 3)), c_t=np.zeros((3, 3)),
                k_r=np.zeros((3, 3)), c_r=np.zeros((3, 3)), axes=tuple(axes), q0=list(q0),
                qd0=list(qd0), drives=tuple(drives), limits=tuple(limits))


def _limits(who, limits, count):
    """The end stops of a joint of `count` coordinates (elements/limits.py): `limits` a
    JointLimit or None for one coordinate, else None or a tuple or list of count of them;
    ValueError naming the joint, the argument and the entry otherwise."""
    if limits is None:
        return (None,) * count
    entries = (limits,) if count == 1 and not isinstance(limits, (tuple, list)) else limits
    if not isinstance(entries, (tuple, list)) or len(entries) != count:
        raise ValueError(f"{who}: limits must be None or {count} entries (a JointLimit or None "
                         f"per coordinate), got {limits!r}")
    out = []
    for i, limit in enumerate(entries):
        label = f"{who}: limits" + ("" if count == 1 else f"[{i}]")
        if limit is None:
            out.append(None)
        elif isinstance(limit, JointLimit):
            out.append(limit.validated(label))
        else:
            raise ValueError(f"{label} must be a JointLimit or None, got {limit!r}")
    return tuple(out)


def _per_coordinate(who, joint, names, count, what="one per axis"):
    """The initial coordinates, rates and drives (_coordinates) of a joint whose arguments
    `names` (values, rates, drives) hold one entry per coordinate: ValueError naming the
    argument unless each is a tuple or list of count entries."""
    for argument in names:
        value = getattr(joint, argument)
        if not isinstance(value, (tuple, list)) or len(value) != count:
            kind = "a pair" if count == 2 else f"{count} entries"
            raise ValueError(f"{who}: {argument} must be {kind} ({what}), got {value!r}")
    values, rates, drives = (getattr(joint, argument) for argument in names)
    return _coordinates(who, values, rates, drives,
                        [(f"{names[0]}[{i}]", f"{names[1]}[{i}]") for i in range(count)])


@dataclass(frozen=True, eq=False)
class RevoluteJoint:
    """A hinge about one axis fixed in the parent: A_child = A_P Rot(n, q) R0 (docs/joints.md).

    The child's input point is the parent's attachment point; the child turns relative to the
    parent about n only, w = w_P + (A_P n) q'.  R0 is the identity, or, when the child body is
    given an initial rotation, whatever makes that rotation hold at the initial angle.  Joints
    with coordinates run in ``simulate_reference`` and in ``simulate``'s Newmark scheme (the
    full-state tree sweep; not method="direct", nor a chain with tip="ball").

    Parameters
    ----------
    axis : array_like of 3
        n, the hinge axis in the parent's frame (the parent's output section; the ground frame
        for a root joint); any nonzero length, normalized here.
    angle : float, optional
        q at t = 0, rad (default 0).  With a JointMotion drive leave it 0: the joint starts on
        the motion.
    rate : float, optional
        q' at t = 0, rad/s (default 0); likewise.
    drive : JointForce, SpringDamper or JointMotion, optional
        What acts on the angle: a generalized torque about the axis (N m), a spring-damper, or
        a prescribed angle.  None (default): the joint turns freely.
    name : str, optional
        The joint's name, in messages and ``Model.hinge_names`` (default "":
        ``RevoluteJoint{k}``).
    limits : JointLimit, optional
        End stops on the angle (elements/limits.py, docs/limits.md): a one-sided
        spring-damper past a lower and an upper bound.  None (default): none.

    Raises
    ------
    ValueError
        At build time, naming the joint (its name and index; the child body for its angular
        velocity) and the argument: an axis that is zero or not 3 finite numbers; an initial
        value that is not a finite number; a drive that is not a JointForce, SpringDamper,
        JointMotion or None, or that fails its own checks (see each drive); initial values that
        contradict a prescribed motion's at t = 0; a child's given angular velocity that
        contradicts the joint's rates.

    Examples
    --------
    A motor about the parent's z axis with a constant torque of 0.5 N m:

    >>> import dttmm
    >>> motor = dttmm.RevoluteJoint(axis=[0, 0, 1], drive=dttmm.JointForce(lambda t, q, qd: 0.5))
    """
    axis: object
    angle: float = 0.0
    rate: float = 0.0
    drive: Optional[object] = None
    name: str = ""
    limits: Optional[object] = None
    kind = REVOLUTE

    def validated(self, index=None):
        who = _label(self, index)
        n = unit_axis(who, "axis", self.axis)
        q0, qd0, drives = _coordinates(who, [self.angle], [self.rate], [self.drive],
                                       [("angle", "rate")])
        return _common([n], q0, qd0, drives, _limits(who, self.limits, 1))


@dataclass(frozen=True, eq=False)
class UniversalJoint:
    """Two perpendicular hinges: A_child = A_P Rot(n1, q1) R0 Rot(n2, q2) (docs/joints.md).

    axis1 (n1) is fixed in the parent, axis2 (n2) in the child; they must be perpendicular at
    q = 0 (n1 . R0 n2 = 0, checked at build time) and then stay so: the child cannot turn
    about n1 x (A_child n2).  The child's input point is the parent's attachment point;
    w = w_P + (A_P n1) q1' + (A_child n2) q2'.  R0 is the identity, or, when the child body is
    given an initial rotation, whatever makes that rotation hold at the initial angles.  Runs
    where ``RevoluteJoint`` does.

    Parameters
    ----------
    axis1 : array_like of 3
        n1, the first axis, in the parent's frame; any nonzero length, normalized here.
    axis2 : array_like of 3
        n2, the second axis, in the child's frame; any nonzero length, normalized here.
    angles : pair of float, optional
        (q1, q2) at t = 0, rad (default (0, 0)).  A coordinate with a JointMotion drive
        starts on the motion (leave its entry 0).
    rates : pair of float, optional
        (q1', q2') at t = 0, rad/s (default (0, 0)).
    drives : pair, optional
        The drive on each angle: JointForce (N m about the axis), SpringDamper, JointMotion or
        None (default (None, None): both turn freely).
    name : str, optional
        The joint's name, in messages and ``Model.hinge_names`` (default "":
        ``UniversalJoint{k}``).
    limits : pair, optional
        End stops on each coordinate, a JointLimit or None each (elements/limits.py,
        docs/limits.md).  None (default): none.

    Raises
    ------
    ValueError
        At build time, naming the joint (its name and index; the child body for its angular
        velocity) and the argument: an axis that is zero or not 3 finite numbers; axes that are
        not perpendicular at q = 0; angles, rates or drives that are not a pair (tuple or list
        of 2); an initial value that is not a finite number; a drive that is not a JointForce,
        SpringDamper, JointMotion or None, or that fails its own checks (see each drive);
        initial values that contradict a prescribed motion's at t = 0; a child's given angular
        velocity that contradicts the joint's rates.

    Examples
    --------
    >>> import dttmm
    >>> cardan = dttmm.UniversalJoint(axis1=[0, 0, 1], axis2=[0, 1, 0],
    ...                               drives=(dttmm.SpringDamper(2.0, 0.1), None))
    """
    axis1: object
    axis2: object
    angles: tuple = (0.0, 0.0)
    rates: tuple = (0.0, 0.0)
    drives: tuple = (None, None)
    name: str = ""
    limits: Optional[tuple] = None
    kind = UNIVERSAL

    def validated(self, index=None):
        who = _label(self, index)
        n1 = unit_axis(who, "axis1", self.axis1)
        n2 = unit_axis(who, "axis2", self.axis2)
        q0, qd0, drives = _per_coordinate(who, self, ("angles", "rates", "drives"), 2)
        return _common([n1, n2], q0, qd0, drives, _limits(who, self.limits, 2))


@dataclass(frozen=True, eq=False)
class PrismaticJoint:
    """A slider along one axis fixed in the parent: A_child = A_P R0 (docs/joints.md).

    The child's input point sits at the parent's attachment point + A_P n q: it slides along n
    and does not turn relative to the parent (w = w_P).  R0 is the identity, or the child's
    given initial rotation relative to the parent.  Runs where ``RevoluteJoint`` does.

    Parameters
    ----------
    axis : array_like of 3
        n, the sliding direction in the parent's frame; any nonzero length, normalized here.
    position : float, optional
        The slide q at t = 0, m (default 0).  With a JointMotion drive leave it 0: the joint
        starts on the motion.
    rate : float, optional
        q' at t = 0, m/s (default 0); likewise.
    drive : JointForce, SpringDamper or JointMotion, optional
        What acts on the slide: a generalized force along the axis (N), a spring-damper
        (N/m, N s/m), or a prescribed slide.  None (default): it slides freely.
    name : str, optional
        The joint's name, in messages and ``Model.hinge_names`` (default "":
        ``PrismaticJoint{k}``).
    limits : JointLimit, optional
        End stops on the slide (elements/limits.py, docs/limits.md): a one-sided
        spring-damper past a lower and an upper bound.  None (default): none.

    Raises
    ------
    ValueError
        At build time, naming the joint (its name and index; the child body for its angular
        velocity) and the argument: an axis that is zero or not 3 finite numbers; an initial
        value that is not a finite number; a drive that is not a JointForce, SpringDamper,
        JointMotion or None, or that fails its own checks (see each drive); initial values that
        contradict a prescribed motion's at t = 0; a child's given angular velocity that
        contradicts the joint's rates.

    Examples
    --------
    >>> import dttmm
    >>> slider = dttmm.PrismaticJoint(axis=[1, 0, 0], drive=dttmm.SpringDamper(100.0, 1.0))
    """
    axis: object
    position: float = 0.0
    rate: float = 0.0
    drive: Optional[object] = None
    name: str = ""
    limits: Optional[object] = None
    kind = PRISMATIC

    def validated(self, index=None):
        who = _label(self, index)
        n = unit_axis(who, "axis", self.axis)
        q0, qd0, drives = _coordinates(who, [self.position], [self.rate], [self.drive],
                                       [("position", "rate")])
        return _common([n], q0, qd0, drives, _limits(who, self.limits, len(q0)))


@dataclass(frozen=True, eq=False)
class CylindricalJoint:
    """A turn about and a slide along one axis fixed in the parent: A_child = A_P Rot(n, theta)
    R0, the child's input point at the attachment point + A_P n s (docs/joints.md).

    The child slides along n and turns about it (a revolute joint and a prismatic one on the
    same axis): w = w_P + (A_P n) theta'.  The axis is fixed in the child too (R0^T n), so the
    turn does not move the input point and the slide does not turn the child.  R0 is the
    identity, or, when the child body is given an initial rotation, whatever makes that
    rotation hold at the initial angle.  Runs where ``RevoluteJoint`` does.

    Parameters
    ----------
    axis : array_like of 3
        n, the axis in the parent's frame; any nonzero length, normalized here.
    coordinates : pair of float, optional
        (theta, s) at t = 0: the angle (rad) and the slide (m) (default (0, 0)).  A coordinate
        with a JointMotion drive starts on the motion (leave its entry 0).
    rates : pair of float, optional
        (theta', s') at t = 0, rad/s and m/s (default (0, 0)).
    drives : pair, optional
        The drive on each coordinate: JointForce (N m about the axis on theta, N along it on
        s), SpringDamper, JointMotion, PDTracking or None (default (None, None): both free).
    name : str, optional
        The joint's name, in messages and ``Model.hinge_names`` (default "":
        ``CylindricalJoint{k}``).
    limits : pair, optional
        End stops on each coordinate, a JointLimit or None each (elements/limits.py,
        docs/limits.md).  None (default): none.

    Raises
    ------
    ValueError
        At build time, naming the joint (its name and index; the child body for its angular
        velocity) and the argument: an axis that is zero or not 3 finite numbers; coordinates,
        rates or drives that are not a pair (tuple or list of 2); an initial value that is not
        a finite number; a drive that is not a JointForce, SpringDamper, JointMotion,
        PDTracking or None, or that fails its own checks (see each drive); initial values that
        contradict a prescribed motion's at t = 0; a child's given angular velocity that
        contradicts the joint's rates.

    Examples
    --------
    A sleeve on a vertical rod, sliding on a spring and turning freely:

    >>> import dttmm
    >>> sleeve = dttmm.CylindricalJoint(axis=[0, 0, 1], coordinates=(0.0, 0.1),
    ...                                 drives=(None, dttmm.SpringDamper(200.0, 2.0)))
    """
    axis: object
    coordinates: tuple = (0.0, 0.0)
    rates: tuple = (0.0, 0.0)
    drives: tuple = (None, None)
    name: str = ""
    limits: Optional[tuple] = None
    kind = CYLINDRICAL

    def validated(self, index=None):
        who = _label(self, index)
        n = unit_axis(who, "axis", self.axis)
        q0, qd0, drives = _per_coordinate(who, self, ("coordinates", "rates", "drives"), 2,
                                          "one per coordinate: theta, s")
        return _common([n], q0, qd0, drives, _limits(who, self.limits, len(q0)))


@dataclass(frozen=True, eq=False)
class PlanarJoint:
    """The child moves in a plane fixed in the parent: two slides along perpendicular axes n1,
    n2 of the plane and a turn about its normal n = n1 x n2.  A_child = A_P Rot(n, theta) R0,
    the child's input point at the attachment point + A_P (n1 x + n2 y) (docs/joints.md,
    "Planar joint").

    The user gives the plane by its two in-plane axes (as ``UniversalJoint`` its two axes), so
    that x and y are measured along directions of the user's choosing; the turning axis is
    their right-handed normal n = n1 x n2 (normal to the plane, fixed in the parent and, as
    R0^T n, in the child): w = w_P + (A_P n) theta'.  The turn does not move the input point
    and the slides do not turn the child.  R0 is the identity, or, when the child body is given
    an initial rotation, whatever makes that rotation hold at the initial angle.  Runs where
    ``RevoluteJoint`` does; as a closing joint (``System.close``) its drives go on x and y only.

    Parameters
    ----------
    axis1 : array_like of 3
        n1, the direction of x, in the parent's frame; any nonzero length, normalized here.
    axis2 : array_like of 3
        n2, the direction of y, in the parent's frame, perpendicular to n1; any nonzero length,
        normalized here.
    coordinates : 3 floats, optional
        (x, y, theta) at t = 0: the slides (m) along n1 and n2 and the angle (rad) about n1 x n2
        (default (0, 0, 0)).  A coordinate with a JointMotion drive starts on the motion (leave
        its entry 0).
    rates : 3 floats, optional
        (x', y', theta') at t = 0, m/s and rad/s (default (0, 0, 0)).
    drives : 3 entries, optional
        The drive on each coordinate: JointForce (N along n1 on x, along n2 on y, N m about the
        normal on theta), SpringDamper, JointMotion, PDTracking or None (default (None, None,
        None): all free).
    name : str, optional
        The joint's name, in messages and ``Model.hinge_names`` (default "":
        ``PlanarJoint{k}``).
    limits : 3 entries, optional
        End stops on each coordinate, a JointLimit or None each (elements/limits.py,
        docs/limits.md).  None (default): none.

    Raises
    ------
    ValueError
        At build time, naming the joint (its name and index; the child body for its angular
        velocity) and the argument: an axis that is zero or not 3 finite numbers; axes that are
        not perpendicular; coordinates, rates or drives that are not 3 entries (tuple or list);
        an initial value that is not a finite number; a drive that is not a JointForce,
        SpringDamper, JointMotion, PDTracking or None, or that fails its own checks (see each
        drive); initial values that contradict a prescribed motion's at t = 0; a child's given
        angular velocity that contradicts the joint's rates; as a closing joint, a drive on
        theta.

    Examples
    --------
    A puck on a horizontal table (the plane of x and y, turning about z), held by a spring
    along x:

    >>> import dttmm
    >>> puck = dttmm.PlanarJoint(axis1=[1, 0, 0], axis2=[0, 1, 0], coordinates=(0.1, 0.0, 0.0),
    ...                          drives=(dttmm.SpringDamper(50.0, 0.5), None, None))
    """
    axis1: object
    axis2: object
    coordinates: tuple = (0.0, 0.0, 0.0)
    rates: tuple = (0.0, 0.0, 0.0)
    drives: tuple = (None, None, None)
    name: str = ""
    limits: Optional[tuple] = None
    kind = PLANAR

    def validated(self, index=None):
        who = _label(self, index)
        n1 = unit_axis(who, "axis1", self.axis1)
        n2 = unit_axis(who, "axis2", self.axis2)
        cosine = float(n1 @ n2)
        if abs(cosine) > 1e-9:
            angle = np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))
            raise ValueError(f"{who}: axis1 and axis2 must be perpendicular (the plane's two "
                             f"axes; its normal is axis1 x axis2), they make {angle:.6g} deg")
        q0, qd0, drives = _per_coordinate(who, self, ("coordinates", "rates", "drives"), 3,
                                          "one per coordinate: x, y, theta")
        normal = np.cross(n1, n2)
        return _common([n1, n2, normal / np.linalg.norm(normal)], q0, qd0, drives,
                       _limits(who, self.limits, 3))


def rotation_about(axis, angle):
    """Rot(n, q) = exp(q n^) for a unit axis n (Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


