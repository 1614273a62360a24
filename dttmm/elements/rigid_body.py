"""Rigid body element: its parameters, their validation, and the flat row the kernels read.

A body has an input point I (where the inboard hinge attaches), a mass centre C and an output
point O (where the outboard hinge attaches), all fixed in the body frame.  Its rotation matrix A
maps body-frame components to world components.  See docs/rigid_body.md.
"""
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

from ._checks import (finite_scalar, finite_vector, matrix3, optional_function, rotation_matrix,
                      symmetric_positive)

# layout of one row of Model.body_params
MASS = 0
TO_MASS_CENTER = slice(1, 4)    # l_IC, body frame
TO_OUTPUT = slice(4, 7)         # l_IO, body frame
INERTIA_INPUT = slice(7, 16)    # J_I about the input point, body frame, row-major 3x3
BODY_PARAM_SIZE = 16


@dataclass(frozen=True, eq=False)
class RigidBody:
    """A rigid body of the chain (docs/rigid_body.md).

    The body has an input point I (where its inboard joint attaches), a mass centre C and an
    output point O (where an outboard joint attaches by default), all fixed in the body frame;
    its rotation matrix A maps body-frame components to world components.  The arguments are
    checked when the model is built (``System.build`` or ``build_chain``), not here.

    Parameters
    ----------
    mass : float
        Mass M, kg (> 0).
    inertia : float, array_like of 3, or array_like (3, 3)
        Mass moment of inertia, kg m^2, in body axes, about the point inertia_about names: a
        3x3 matrix, its 3 diagonal entries, or a scalar (times the identity).  About the mass
        centre it must be symmetric positive definite and satisfy the triangle inequality of
        its principal moments (I1 + I2 >= I3).  Given about the input point it is moved to the
        mass centre by the parallel-axis term, J_C = J_I - M (|l_IC|^2 E - l_IC l_IC^T).
    inertia_about : {"mass_center", "input"}
        The point the inertia is given about (no default, so that it is always said).
    to_mass_center : array_like of 3, optional
        l_IC: body-frame vector from the input point to the mass centre, m; default zero.
    to_output : array_like of 3, optional
        l_IO: body-frame vector from the input point to the output point, m; default zero.
    force : callable or array_like of 3, optional
        force(t) -> 3 numbers: a world-frame force applied at the mass centre at time t (s),
        N; 3 numbers for a constant one.  None (default): no applied force.  Evaluated at
        t = 0 when the model is built.
    torque : callable or array_like of 3, optional
        torque(t) -> 3 numbers: a world-frame torque applied to the body at time t (s), N m;
        3 numbers for a constant one.  None (default): no applied torque.  Evaluated at t = 0
        when the model is built.
    rotation : array_like (3, 3), optional
        Initial rotation matrix A (body to world; proper orthonormal, det +1, to 1e-9).  None
        (default): the identity behind a ball joint, and the inboard body's frame turned by
        the hinge's rest rotation behind an elastic hinge.  Bodies joined to their inboard
        neighbour by a fixed hinge take theirs from that hinge (a given one that contradicts
        it is refused); behind a joint with coordinates a given rotation is the body's
        rotation at the joint's initial coordinates and sets the joint's R0 (elements/joints.py).
    angular_velocity : array_like of 3, optional
        Initial world-frame angular velocity, rad/s.  None (default): zero (at rest in the
        world, not relative to the inboard body).  Taken from the inboard body across a fixed
        hinge, and from the parent and the joint's rates behind a joint with coordinates (a
        given one that contradicts them is refused).
    name : str, optional
        The body's name: in messages, as a parent for ``System.add(..., parent=NAME)``, and in
        ``Model.body_names`` and ``Result.body_names`` (default "": ``body{k}``).  Unique
        within a System.
    points : dict, optional
        Further attachment points for other bodies' joints (``dttmm.System.add(...,
        at=NAME)``): name -> body-frame vector from the input point, m.  Names are non-empty
        strings other than "output" and "input"; the output point is the attachment point
        "output".
    shapes : Sphere, Capsule, Box or a list of them, optional
        The body's shapes that touch the ground's plane (``Ground(plane=...)``;
        docs/contact.md), in the body frame from the input point.  Default: none.
    contact : Contact, optional
        Their contact law's parameters (stiffness or contact time, restitution, friction);
        required with shapes.

    Raises
    ------
    ValueError
        At build time (``System.build``, ``build_chain``), naming the body (its name and index)
        and the argument: a mass that is not > 0; a vector without 3 finite entries; an
        inertia that is not a scalar, 3 entries or a 3x3 matrix, is not symmetric positive
        definite about the mass centre or violates the triangle inequality; inertia_about not
        one of the two; a rotation that is not a proper rotation matrix; a force or torque
        that is not callable or does not return 3 finite numbers at t = 0; a bad points dict
        or point name; a rotation or angular velocity contradicting a fixed hinge or joint
        before the body; no inertia about the hinge-to-hinge axis of a body between two ball
        joints (or a ball joint and the free tip).

    Examples
    --------
    A uniform rod of 1 kg and 1 m along its body x axis, hanging from its input end:

    >>> import dttmm
    >>> rod = dttmm.RigidBody(mass=1.0, inertia=[1e-4, 1 / 12, 1 / 12],
    ...                       inertia_about="mass_center", to_mass_center=[0.5, 0, 0],
    ...                       to_output=[1.0, 0, 0], name="rod")
    >>> model = dttmm.build_chain([dttmm.BallJoint(), rod])
    """
    mass: float
    inertia: object
    inertia_about: str
    to_mass_center: object = (0.0, 0.0, 0.0)
    to_output: object = (0.0, 0.0, 0.0)
    force: Optional[Callable[[float], object]] = None
    torque: Optional[Callable[[float], object]] = None
    rotation: object = None
    angular_velocity: object = None
    name: str = ""
    points: Optional[dict] = None
    shapes: object = ()
    contact: object = None
    _valid: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def label(self, index=None):
        where = f"body {index}" if index is not None else "body"
        return f"RigidBody '{self.name}' ({where})" if self.name else f"RigidBody ({where})"

    def validated(self, index=None):
        """Checked, converted parameters; raises ValueError naming the body and the argument."""
        who = self.label(index)
        mass = finite_scalar(who, "mass", self.mass, positive=True)
        l_ic = finite_vector(who, "to_mass_center", self.to_mass_center)
        l_io = finite_vector(who, "to_output", self.to_output)
        inertia = matrix3(who, "inertia", self.inertia)
        if self.inertia_about not in ("mass_center", "input"):
            raise ValueError(f"{who}: inertia_about must be 'mass_center' or 'input', "
                             f"got {self.inertia_about!r}")
        shift = parallel_axis(mass, l_ic)
        if self.inertia_about == "mass_center":
            j_c = inertia
        else:
            j_c = inertia - shift
        j_c = symmetric_positive(who, f"inertia (about the mass centre, from inertia_about="
                                      f"'{self.inertia_about}')", j_c)
        p = np.linalg.eigvalsh(j_c)
        tol = 1e-9 * p.max()
        if p[0] + p[1] < p[2] - tol:
            raise ValueError(f"{who}: inertia violates the triangle inequality: principal moments "
                             f"about the mass centre {p} (need I1 + I2 >= I3)")
        rotation = (None if self.rotation is None
                    else rotation_matrix(who, "rotation", self.rotation))
        omega = None if self.angular_velocity is None else finite_vector(
            who, "angular_velocity", self.angular_velocity)
        points = {}
        if self.points is not None:
            if not isinstance(self.points, dict):
                raise ValueError(f"{who}: points must be a dict of name -> body-frame vector, "
                                 f"got {type(self.points).__name__}")
            for key, value in self.points.items():
                if not isinstance(key, str) or not key or key in ("output", "input"):
                    raise ValueError(f"{who}: points: {key!r} is not a valid point name (a "
                                     f"non-empty string other than 'output' and 'input')")
                points[key] = finite_vector(who, f"points[{key!r}]", value)
        return dict(mass=mass, l_ic=l_ic, l_io=l_io, j_c=j_c, j_i=j_c + shift, points=points,
                    force=optional_function(who, "force", self.force),
                    torque=optional_function(who, "torque", self.torque),
                    rotation=rotation, omega=omega)


def parallel_axis(mass, offset):
    """m (|c|^2 E - c c^T): what a mass m whose centre is at c adds to the inertia about the
    origin over its own about c (the parallel-axis theorem)."""
    return mass * (offset @ offset * np.eye(3) - np.outer(offset, offset))


def straight_line_body(length, mass_per_length, polar, rotary=(0.0, 0.0)):
    """A uniform straight line of mass along x from the input point (a beam's or rod's
    undeformed shape) as a rigid body: its mass, l_IC, l_IO, J_C and J_I, with the sections'
    polar inertia and rotary inertias (about z, about y) per length."""
    mass = mass_per_length * length
    j_c = np.diag([polar * length, rotary[1] * length + mass * length ** 2 / 12,
                   rotary[0] * length + mass * length ** 2 / 12])
    l_ic = np.array([length / 2, 0.0, 0.0])
    return dict(mass=mass, l_ic=l_ic, l_io=np.array([length, 0.0, 0.0]), j_c=j_c,
                j_i=j_c + parallel_axis(mass, l_ic))


def pack_body(v):
    row = np.zeros(BODY_PARAM_SIZE)
    row[MASS] = v["mass"]
    row[TO_MASS_CENTER] = v["l_ic"]
    row[TO_OUTPUT] = v["l_io"]
    row[INERTIA_INPUT] = v["j_i"].reshape(-1)
    return row
