"""Hinge elements: smooth ball-and-socket, fixed, and elastic (spring-damper) hinges.

A hinge joins the output point of its inboard body (or the ground point, for the root hinge) to
the input point of its outboard body.  See docs/hinges.md for the equations.
"""
from dataclasses import dataclass

import numpy as np

from ._checks import matrix3, rotation_matrix, symmetric_positive

BALL, FIXED, ELASTIC = 0, 1, 2        # Model.hinge_kind (declared in kinds.py)

# layout of one row of Model.hinge_params (3x3 blocks, row-major)
REST_ROTATION = slice(0, 9)        # R0: outboard frame = inboard frame R0 at rest
K_TRANSLATION = slice(9, 18)       # in the inboard body's frame, N/m
C_TRANSLATION = slice(18, 27)      # N s/m
K_ROTATION = slice(27, 36)         # N m/rad
C_ROTATION = slice(36, 45)         # N m s/rad
AXIS_1 = slice(45, 48)             # joints with coordinates (joints.py): the (first) axis,
AXIS_2 = slice(48, 51)             # parent frame; a universal joint's second, child frame
COORDINATE_0 = slice(51, 53)       # their coordinates (rad or m) and rates at t = 0
RATE_0 = slice(53, 55)
HINGE_PARAM_SIZE = 55


@dataclass(frozen=True, eq=False)
class BallJoint:
    """Smooth ball-and-socket hinge: positions and forces pass, no moment, free relative
    rotation."""
    name: str = ""
    kind = BALL

    def validated(self, index=None):
        return dict(rotation=np.eye(3), k_t=np.zeros((3, 3)), c_t=np.zeros((3, 3)),
                    k_r=np.zeros((3, 3)), c_r=np.zeros((3, 3)))


@dataclass(frozen=True, eq=False)
class FixedHinge:
    """Rigid weld: A_out = A_in @ rotation (a constant relative rotation, identity by default)."""
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
    """Linear translational and rotational springs with optional viscous dampers.

    The outboard input point sits at the inboard output point plus a deflection d; the outboard
    frame is A_out = A_in expm(psi^) R0.  Springs and dampers act in the inboard body's frame:
        q (force on the outboard side)       = -A_in (K_t d_b + C_t d'_b),  d_b = A_in^T d,
                                                                             d'_b = A_in^T d/dt(d)
        m (couple on the outboard side, about its input point)
                                             = -A_in (K_r psi + C_r A_in^T (w_out - w_in)).
    Stiffnesses are scalars, 3 diagonal entries or symmetric positive definite 3x3 matrices;
    dampings likewise but may be zero.
    """
    translational_stiffness: object
    rotational_stiffness: object
    translational_damping: object = 0.0
    rotational_damping: object = 0.0
    rotation: object = None
    name: str = ""
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
        return dict(rotation=r, k_t=k_t, c_t=c_t, k_r=k_r, c_r=c_r)


def _label(hinge, index):
    where = f"hinge {index}" if index is not None else "hinge"
    kind = type(hinge).__name__
    return f"{kind} '{hinge.name}' ({where})" if hinge.name else f"{kind} ({where})"


def pack_hinge(v):
    row = np.zeros(HINGE_PARAM_SIZE)
    row[REST_ROTATION] = v["rotation"].reshape(-1)
    row[K_TRANSLATION] = v["k_t"].reshape(-1)
    row[C_TRANSLATION] = v["c_t"].reshape(-1)
    row[K_ROTATION] = v["k_r"].reshape(-1)
    row[C_ROTATION] = v["c_r"].reshape(-1)
    if "axis1" in v:
        row[AXIS_1] = v["axis1"]
        row[AXIS_2] = v["axis2"]
        row[COORDINATE_0] = v["q0"]
        row[RATE_0] = v["qd0"]
    return row
