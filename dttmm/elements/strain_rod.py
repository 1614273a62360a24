"""The strain rod's strain field and stations (docs/strain_rod.md): a rod element whose centre
line is the exponential integral of its strain, so that a constant curvature is exact with one
element.  This module holds the field's tables for the kinematics kernel
(kernels/transfers/strain_rod.py::rod_kinematics); the element class that runs in the solvers
builds on them.
"""
import numpy as np
from numpy.polynomial import legendre

from ..kernels.transfers.strain_rod import MAGNUS_POINTS

# the strain's components, their rows in xi = [angular; linear] (section frame): the twist
# kappa_x, the curvatures kappa_y (bending toward -z) and kappa_z (toward +y), the stretch
# (the linear strain's x; no shear)
COMPONENTS = {"twist": 0, "bend_y": 1, "bend_z": 2, "stretch": 3}
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
