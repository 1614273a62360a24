"""The strain rod (docs/strain_rod.md): a rod element whose centre line is the exponential
integral of its strain, so that a constant curvature is exact with one element; its strain
field's tables for the kinematics (kernels/transfers/strain_rod.py::rod_kinematics, and the
reference's own, reference/strain_rod.py).
"""
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre

from ._checks import (finite_pair, finite_scalar, finite_vector, physical_frequency,
                      rotation_matrix)
from .rigid_body import straight_line_body

# the rod's parameter row (Model.rod_params; zero rows for the other bodies)
(ROD_LENGTH, ROD_MU, ROD_EI_V, ROD_EI_W, ROD_GJ, ROD_EA, ROD_JP, ROD_JV, ROD_JW, ROD_MODES,
 ROD_TWIST, ROD_STRETCH, ROD_STATIONS, ROD_DAMPING) = range(14)
ROD_PARAM_SIZE = 14
MAX_STRAIN_MODES = 6
DEFAULT_STRAIN_MODES = 2      # strain_modes=None where no end is pinned (model/freeze.py raises it)

# the strain's components, their rows in xi = [angular; linear] (section frame): the twist
# kappa_x, the curvatures kappa_y (bending toward -z) and kappa_z (toward +y), the stretch
# (the linear strain's x; no shear)
COMPONENTS = {"twist": 0, "bend_y": 1, "bend_z": 2, "stretch": 3}
# the Magnus step's two Gauss points, as fractions of the step (1/2 -+ sqrt(3)/6)
MAGNUS_POINTS = (0.5 - np.sqrt(3.0) / 6.0, 0.5 + np.sqrt(3.0) / 6.0)
STRAIGHT = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0])     # the unstrained rod: xi0 = e1 (linear)


def strain_basis(x, length, modes, components):
    """Phi(X) (6 x nq) at the points x: per component, in `components`' order, the Legendre
    polynomials P_0 .. P_(modes-1) of 2 X / L - 1 (so modes = 1 is a constant strain, 2 a
    linear one).  Returns an array (len(x), 6, nq)."""
    x = np.atleast_1d(np.asarray(x, dtype=float))
    s = 2.0 * x / length - 1.0
    nq = modes * len(components)
    phi = np.zeros((len(x), 6, nq))
    for c, name in enumerate(components):
        row = COMPONENTS[name]
        for k in range(modes):
            phi[:, row, c * modes + k] = legendre.legval(s, np.eye(modes)[k])
    return phi


def stations(length, n_points):
    """The rod's stations: the n_points Gauss-Legendre points of [0, L] (where its mass is
    integrated: weights returned) and its end L.  Returns (x, weights) with x of length
    n_points + 1 and the end's weight 0."""
    g, w = legendre.leggauss(n_points)
    x = np.append(0.5 * length * (g + 1.0), length)
    return x, np.append(0.5 * length * w, 0.0)


def kinematics_tables(length, x, modes, components, reference=STRAIGHT):
    """(steps, xi0, phi) for rod_kinematics: the steps from 0 through the stations x (their
    lengths, (n,)), and the reference strain (n, 2, 6) and basis (n, 2, 6, nq) at each step's two
    Magnus points.  `reference` is a constant reference strain (6,): STRAIGHT, or a precurved
    rod's."""
    ends = np.asarray(x, dtype=float)
    starts = np.concatenate([[0.0], ends[:-1]])
    steps = ends - starts
    if np.any(steps <= 0.0):
        raise ValueError("strain rod: stations must increase from 0")
    points = starts[:, None] + steps[:, None] * np.array(MAGNUS_POINTS)[None, :]
    phi = strain_basis(points.ravel(), length, modes, components)
    phi = phi.reshape(len(steps), 2, 6, -1)
    xi0 = np.broadcast_to(np.asarray(reference, dtype=float), (len(steps), 2, 6)).copy()
    return steps, xi0, np.ascontiguousarray(phi)


def rod_components(row):
    """The strain components a rod's parameter row carries, in the coordinates' order: the
    curvatures (bend_z: the deflection v along y; bend_y: w along z), then the twist and the
    stretch if on."""
    return (("bend_z", "bend_y") + (("twist",) if row[ROD_TWIST] else ())
            + (("stretch",) if row[ROD_STRETCH] else ()))


def rod_coordinate_count(row):
    """n_q of a rod's parameter row: strain_modes per component."""
    return int(row[ROD_MODES]) * len(rod_components(row))


def rod_stiffness(row):
    """K (n_q,): the strain energy 1/2 q^T K q = 1/2 int (xi - xi0)^T C (xi - xi0) dX with
    C = diag(GJ, EI_w, EI_v, EA) on (twist, kappa_y, kappa_z, stretch); the Legendre basis is
    orthogonal (int_0^L P_j P_k dX = L / (2k + 1) delta_jk), so K is diagonal."""
    stiffness = {"bend_z": row[ROD_EI_V], "bend_y": row[ROD_EI_W], "twist": row[ROD_GJ],
                 "stretch": row[ROD_EA]}
    m, length = int(row[ROD_MODES]), row[ROD_LENGTH]
    return np.concatenate([stiffness[c] * length / (2.0 * np.arange(m) + 1.0)
                           for c in rod_components(row)])


def rod_section(row):
    """The sections' inertia per length in their own axes, the diagonal (j_p, rho I_w, rho I_v)
    about (x, y, z): the polar moment, and the rotary moments of bending toward z and y."""
    return np.array([row[ROD_JP], row[ROD_JW], row[ROD_JV]])


def rod_tables(row):
    """(steps, xi0, phi, weights) of a rod's parameter row: kinematics_tables through its
    stations (Gauss points and the end) and the weights of the kinematics' stations 0 .. n (the
    input section and the end weigh 0)."""
    x, weights = stations(row[ROD_LENGTH], int(row[ROD_STATIONS]))
    steps, xi0, phi = kinematics_tables(row[ROD_LENGTH], x, int(row[ROD_MODES]),
                                        rod_components(row))
    return steps, xi0, phi, np.concatenate([[0.0], weights])


def _strain_part(who, flag, name, stiffness, what):
    if not isinstance(flag, (bool, np.bool_)):
        raise ValueError(f"{who}: {name} must be True or False, got {flag!r}")
    if not flag:
        return 0.0
    if stiffness is None:
        raise ValueError(f"{who}: {name}=True needs its stiffness ({what})")
    return finite_scalar(who, what, stiffness, positive=True)


@dataclass(frozen=True, eq=False)
class StrainRod:
    """A uniform rod whose centre line is the exponential integral of its strain
    (docs/strain_rod.md): the curvatures in both planes (and on request the twist and the
    stretch) are polynomial fields of strain_modes coefficients each along the rod, so a
    constant curvature is exact with one element whatever the angle it turns through.  No
    shear (the sections stay normal to the centre line).  The frame is the input section's;
    the undeformed rod lies along its x axis.  Next to every joint kind, in chains, trees
    and closed loops (inside them, or as a closing joint's side at either end),
    with ``simulate`` (the Newmark scheme), ``static_equilibrium`` and the Newton-Euler
    reference (``dttmm.simulate_reference``); scene files take it as type "rod".  It carries
    no loads of its own yet (a body welded to its end does).  The arguments are checked when
    the model is built.

    Parameters
    ----------
    length : float
        L, m (> 0), undeformed.
    bending_stiffness : float or array_like of 2
        (EI_v, EI_w), N m^2 (each > 0): EI_v for bending toward body y (the curvature kappa_z),
        EI_w toward body z (kappa_y); a scalar for both.
    mass_per_length : float
        mu, kg/m (> 0).
    polar_inertia_per_length : float
        j_p = rho I_p, kg m (> 0): the sections' polar mass moment per length.
    rotary_inertia_per_length : float or array_like of 2, optional
        (rho I_v, rho I_w), kg m (>= 0): the sections' mass moments about their bending axes
        (z, y) per length.  Default 0 (Euler-Bernoulli, as the modal beam).
    strain_modes : int, optional
        Coefficients per strain component (>= 1, at most 6): 1 a constant strain along the
        element, 2 a linear one, ... (Legendre polynomials).  None (default): 2, or as many as
        the rod's ends need where one is pinned in a bending plane (a root behind a ball, or a
        revolute or universal joint no JointMotion holds; an output held by a closing ball,
        revolute or universal joint), counted at the build as a modal beam's
        (elements/beam.py::accurate_mode_count: its deflection's polynomials x^2 .. x^(m+1) are
        the loaded-end modes'): 4 behind a revolute joint (2 left a double pendulum's mid-span
        deflection 42% off); or the count initial_strain implies.
    stations : int, optional
        Gauss points where the rod's mass is integrated and its kinematics stepped (>= 1).
        Default strain_modes + 3.
    twist, stretch : bool, optional
        Whether the rod twists (needs torsional_stiffness) and stretches (needs
        axial_stiffness).  Default False: neither.
    torsional_stiffness : float, optional
        G J, N m^2 (> 0), with twist=True.
    axial_stiffness : float, optional
        E A, N (> 0), with stretch=True.
    damping : float, optional
        Stiffness-proportional damping of the strain rates, s (>= 0, default 0): the
        generalized forces -damping K q'.
    initial_strain : array_like of n_q, optional
        q at t = 0 (the strain coordinates: per component, in the order bend_z, bend_y, twist,
        stretch, its strain_modes Legendre coefficients; 1/m for curvatures and twist).  None:
        straight.
    initial_strain_rate : array_like of n_q, optional
        q' at t = 0.  None: zero.
    rotation, angular_velocity, name
        As for ``RigidBody``.

    Raises
    ------
    ValueError
        At build time, naming the rod and the argument: a length, stiffness, mass or inertia
        per length that is not a finite number > 0 (>= 0 for the rotary inertia); strain_modes
        or stations not an integer in range; twist or stretch not a bool, or True without its
        stiffness; initial strains or rates without n_q finite entries.

    Examples
    --------
    A rod rolled into a quarter circle at rest (a constant curvature pi / (2 L)):

    >>> import numpy as np, dttmm
    >>> rod = dttmm.StrainRod(length=1.0, bending_stiffness=2.0, mass_per_length=0.5,
    ...                       polar_inertia_per_length=1e-4, strain_modes=1,
    ...                       initial_strain=[np.pi / 2, 0.0])
    >>> model = dttmm.build_chain([dttmm.FixedHinge(), rod], gravity=[0, 0, 0])
    """
    length: float
    bending_stiffness: object
    mass_per_length: float
    polar_inertia_per_length: float
    rotary_inertia_per_length: object = 0.0
    strain_modes: int = None
    stations: int = None
    twist: bool = False
    stretch: bool = False
    torsional_stiffness: float = None
    axial_stiffness: float = None
    damping: float = 0.0
    initial_strain: object = None
    initial_strain_rate: object = None
    rotation: object = None
    angular_velocity: object = None
    name: str = ""

    def label(self, index=None):
        where = f"body {index}" if index is not None else "body"
        return f"StrainRod '{self.name}' ({where})" if self.name else f"StrainRod ({where})"

    def validated(self, index=None):
        who = self.label(index)
        length = finite_scalar(who, "length", self.length, positive=True)
        mu = finite_scalar(who, "mass_per_length", self.mass_per_length, positive=True)
        ei = finite_pair(who, "bending_stiffness", self.bending_stiffness, positive=True)
        polar = finite_scalar(who, "polar_inertia_per_length", self.polar_inertia_per_length,
                              positive=True)
        rotary = finite_pair(who, "rotary_inertia_per_length", self.rotary_inertia_per_length,
                             nonnegative=True)
        components = 2 + int(bool(self.twist)) + int(bool(self.stretch))
        given = [np.size(v) for v in (self.initial_strain, self.initial_strain_rate)
                 if v is not None]
        if self.strain_modes is None and given and given[0] % components == 0:
            modes = given[0] // components        # (the count the initial strain implies)
        elif self.strain_modes is None:
            modes = DEFAULT_STRAIN_MODES          # (raised at the build for pinned ends)
        else:
            modes = _count(who, "strain_modes", self.strain_modes, 1, MAX_STRAIN_MODES)
        n_stations = (modes + 3 if self.stations is None
                      else _count(who, "stations", self.stations, 1, 64))
        gj = _strain_part(who, self.twist, "twist", self.torsional_stiffness,
                          "torsional_stiffness")
        ea = _strain_part(who, self.stretch, "stretch", self.axial_stiffness, "axial_stiffness")
        for argument, frequency in (     # (the modal beam's own first frequencies, Hz)
                ("bending_stiffness", 0.56 * np.sqrt(max(ei) / (mu * length ** 4))),
                ("axial_stiffness", np.sqrt(ea / mu) / (4 * length)),
                ("torsional_stiffness", np.sqrt(gj / polar) / (4 * length))):
            physical_frequency(who, argument, frequency)
        damping = finite_scalar(who, "damping", self.damping, nonnegative=True)
        row = np.zeros(ROD_PARAM_SIZE)
        row[ROD_LENGTH], row[ROD_MU], row[ROD_EI_V], row[ROD_EI_W] = length, mu, ei[0], ei[1]
        row[ROD_GJ], row[ROD_EA], row[ROD_JP] = gj, ea, polar
        row[ROD_JV], row[ROD_JW] = rotary
        row[ROD_MODES], row[ROD_STATIONS], row[ROD_DAMPING] = modes, n_stations, damping
        row[ROD_TWIST], row[ROD_STRETCH] = float(self.twist), float(self.stretch)
        nq = rod_coordinate_count(row)
        q0, qd0 = (np.zeros(nq) if v is None else finite_vector(who, arg, v, size=nq)
                   for arg, v in (("initial_strain", self.initial_strain),
                                  ("initial_strain_rate", self.initial_strain_rate)))
        rotation = (None if self.rotation is None
                    else rotation_matrix(who, "rotation", self.rotation))
        omega = None if self.angular_velocity is None else finite_vector(
            who, "angular_velocity", self.angular_velocity)
        # the straight rod as a rigid body (what the model's rigid-body rows show of it)
        return dict(straight_line_body(length, mu, polar, rotary), force=None, torque=None,
                    line_load=None, rotation=rotation, omega=omega, rod=row, eta0=q0,
                    eta_d0=qd0, counted=self.strain_modes is None and not given,
                    stations_given=self.stations is not None)


def _count(who, name, value, low, high):
    if (isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer))
            or not low <= value <= high):
        raise ValueError(f"{who}: {name} must be an integer from {low} to {high}, got "
                         f"{value!r}")
    return int(value)
