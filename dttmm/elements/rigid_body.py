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
    """A rigid body of the chain.

    mass:            kg, > 0.
    inertia:         kg m^2; a 3x3 matrix, 3 diagonal entries or a scalar, in body axes.
    inertia_about:   "mass_center" or "input": the point the inertia is given about (no default,
                     so that it is always said).
    to_mass_center:  body-frame vector from the input point to the mass centre, m.
    to_output:       body-frame vector from the input point to the output point, m.
    force, torque:   optional functions of time t returning a world-frame force applied at the
                     mass centre (N) and a world-frame torque (N m).
    rotation:        initial rotation matrix (body to world); None for identity behind a ball
                     joint, and for the inboard body's frame turned by the hinge's rest rotation
                     behind an elastic hinge.  Bodies joined to their inboard neighbour by a fixed
                     hinge take theirs from that hinge.
    angular_velocity: initial world-frame angular velocity, rad/s; None for zero (at rest in the
                     world, not relative to the inboard body).  Taken from the inboard body
                     across a fixed hinge.
    points:          further attachment points for other bodies' joints (dttmm.System.add(...,
                     at=NAME)): a dict of name -> body-frame vector from the input point, m.  The
                     output point is the attachment point "output".
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
        shift = mass * (l_ic @ l_ic * np.eye(3) - np.outer(l_ic, l_ic))   # parallel-axis term
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


def pack_body(v):
    row = np.zeros(BODY_PARAM_SIZE)
    row[MASS] = v["mass"]
    row[TO_MASS_CENTER] = v["l_ic"]
    row[TO_OUTPUT] = v["l_io"]
    row[INERTIA_INPUT] = v["j_i"].reshape(-1)
    return row
