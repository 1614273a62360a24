"""Uniform Euler-Bernoulli beam with modal bending in two planes (docs/beam.md).

Floating frame at the input end I, x along the reference axis (the chord I -> O); a section at
x sits at r(x) = r_I + A (x e1 + u(x)), u = [0, v, w], v = sum_k Y_k(x) eta_v[k],
w = sum_k Y_k(x) eta_w[k].  No axial or torsional deformation, no geometric stiffening; the
section's rotary inertia is left out (Euler-Bernoulli, like the paper), but its small polar
inertia is kept for the frame's spin about x.
"""
from dataclasses import dataclass

import numpy as np

from ._checks import finite_scalar, finite_vector, rotation_matrix

PINNED = 0            # sin(k pi x / L): between two moment-free cuts (ball joints, free tip)
MODE_FAMILY_NAMES = {"pinned": PINNED}

# layout of one row of Model.beam_params
LENGTH, MASS_PER_LENGTH, EI_V, EI_W, POLAR_PER_LENGTH, DAMPING_RATIO, MODES, FAMILY = range(8)
BEAM_PARAM_SIZE = 8


@dataclass(frozen=True, eq=False)
class EulerBernoulliBeam:
    """A uniform beam.

    length:            m, > 0.
    mass_per_length:   kg/m, > 0 (or give density and area).
    bending_stiffness: (EI_v, EI_w) N m^2, for deflection v along body y (bending about z) and
                       w along body z (bending about y); a scalar for both.
    polar_inertia_per_length: kg m, the section's polar mass moment per length (rho I_p, e.g.
                       mu a^2 / 6 for a square section of side a); > 0: it keeps the frame's
                       spin about its own axis well posed.
    modes_per_plane:   number of bending modes in each plane, >= 1.
    damping_ratio:     modal damping ratio (>= 0).
    mode_family:       "pinned" (sine modes in a chord frame; needs moment-free cuts at both
                       ends: ball joints or the free tip).
    rotation, angular_velocity: initial frame rotation and world angular velocity, as for
                       RigidBody.
    """
    length: float
    bending_stiffness: object
    polar_inertia_per_length: float
    mass_per_length: float = None
    density: float = None
    area: float = None
    modes_per_plane: int = 1
    damping_ratio: float = 0.0
    mode_family: str = "pinned"
    rotation: object = None
    angular_velocity: object = None
    name: str = ""

    def label(self, index=None):
        where = f"body {index}" if index is not None else "body"
        return (f"EulerBernoulliBeam '{self.name}' ({where})" if self.name
                else f"EulerBernoulliBeam ({where})")

    def validated(self, index=None):
        who = self.label(index)
        length = finite_scalar(who, "length", self.length, positive=True)
        if self.mass_per_length is not None:
            if self.density is not None or self.area is not None:
                raise ValueError(f"{who}: give mass_per_length, or density and area, not both")
            mu = finite_scalar(who, "mass_per_length", self.mass_per_length, positive=True)
        elif self.density is not None and self.area is not None:
            mu = (finite_scalar(who, "density", self.density, positive=True)
                  * finite_scalar(who, "area", self.area, positive=True))
        else:
            raise ValueError(f"{who}: mass_per_length (or density and area) is required")
        ei = np.broadcast_to(np.asarray(self.bending_stiffness, dtype=float), (2,)).copy() \
            if np.ndim(self.bending_stiffness) == 0 else finite_vector(
                who, "bending_stiffness", self.bending_stiffness, size=2)
        for v in ei:
            finite_scalar(who, "bending_stiffness", v, positive=True)
        polar = finite_scalar(who, "polar_inertia_per_length", self.polar_inertia_per_length,
                              positive=True)
        if int(self.modes_per_plane) != self.modes_per_plane or self.modes_per_plane < 1:
            raise ValueError(f"{who}: modes_per_plane must be an integer >= 1, "
                             f"got {self.modes_per_plane!r}")
        zeta = finite_scalar(who, "damping_ratio", self.damping_ratio, nonnegative=True)
        if self.mode_family not in MODE_FAMILY_NAMES:
            raise ValueError(f"{who}: mode_family must be one of {sorted(MODE_FAMILY_NAMES)}, "
                             f"got {self.mode_family!r}")
        rotation = None if self.rotation is None else rotation_matrix(who, "rotation", self.rotation)
        omega = None if self.angular_velocity is None else finite_vector(
            who, "angular_velocity", self.angular_velocity)
        mass = mu * length
        # the undeformed beam as a rigid body (line mass on the x axis plus the polar inertia)
        j_c = np.diag([polar * length, mass * length ** 2 / 12, mass * length ** 2 / 12])
        l_ic = np.array([length / 2, 0.0, 0.0])
        shift = mass * (l_ic @ l_ic * np.eye(3) - np.outer(l_ic, l_ic))
        row = np.zeros(BEAM_PARAM_SIZE)
        row[LENGTH], row[MASS_PER_LENGTH], row[EI_V], row[EI_W] = length, mu, ei[0], ei[1]
        row[POLAR_PER_LENGTH], row[DAMPING_RATIO] = polar, zeta
        row[MODES], row[FAMILY] = int(self.modes_per_plane), MODE_FAMILY_NAMES[self.mode_family]
        return dict(mass=mass, l_ic=l_ic, l_io=np.array([length, 0.0, 0.0]), j_c=j_c,
                    j_i=j_c + shift, force=None, torque=None, rotation=rotation, omega=omega,
                    beam=row)
