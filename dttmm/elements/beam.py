"""Uniform Euler-Bernoulli beam with modal bending in two planes (docs/beam.md).

Floating frame at the input end I, x along the reference axis (the chord I -> O); a section at
x sits at r(x) = r_I + A (x e1 + u(x)), u = [0, v, w], v = sum_k Y_k(x) eta_v[k],
w = sum_k Y_k(x) eta_w[k]; the sections twist by psi = sum_k Psi_k(x) eta_t[k] on request
(torsion_modes), and the centreline stretches by u_x = sum_k U_k(x) eta_a[k] on request
(axial_modes); geometric stiffening on request (docs/beam.md).
The section's rotary inertia is left out (Euler-Bernoulli, like the paper), but its small
polar inertia is kept for the frame's (and the twist's) spin about x.
"""
from dataclasses import dataclass
from functools import lru_cache
from typing import Callable, Optional

import numpy as np

from ._checks import (finite_pair, finite_scalar, finite_vector, optional_function,
                      physical_frequency, rotation_matrix)
from ..vectors import rows_dot
from .rigid_body import straight_line_body

PINNED = 0            # sin(k pi x / L) in the chord frame: between moment-free ends
CLAMPED = 1           # clamped-free eigenfunctions in the input section's frame: a free tip
CLAMPED_LOADED = 2    # input section's frame, polynomial Ritz modes: an output that carries loads
AUTO = -1             # chosen by build_chain from the beam's two ends
EXACT = 2.0           # beam_params[STIFFENING] of stiffening="exact" (on: 1.0, off: 0.0)
MODE_FAMILY_NAMES = {"pinned": PINNED, "clamped": CLAMPED, "auto": AUTO}
MAX_LOADED_MODES = 6  # the polynomial basis x^2 .. x^(m+1) is well conditioned up to here
CLAMPED_ROOTS = (1.87510406871196, 4.69409113297418, 7.85475743823761, 10.9955407348755,
                 14.1371683910465)     # b_k L, the roots of 1 + cos x cosh x = 0


def clamped_root(k):
    """b_k L of the k-th clamped-free mode (k = 1, 2, ...)."""
    return CLAMPED_ROOTS[k - 1] if k <= len(CLAMPED_ROOTS) else (2 * k - 1) * np.pi / 2


def mode_shapes(family, length, n_modes, x):
    """(Y, Y', Y'') of the family's first n_modes shapes at the points x, each (n_modes, len(x)),
    and the modal mass and stiffness factors (m_k / mu, k_k / EI), each (n_modes,)
    (docs/beam.md, "Mode shapes")."""
    x = np.asarray(x, dtype=float)
    y, dy, ddy = (np.empty((n_modes, x.size)) for _ in range(3))
    mass, stiff = np.empty(n_modes), np.empty(n_modes)
    for j in range(n_modes):
        if family == PINNED:
            b = (j + 1) * np.pi / length
            y[j], dy[j], ddy[j] = np.sin(b * x), b * np.cos(b * x), -b * b * np.sin(b * x)
            mass[j], stiff[j] = 0.5 * length, 0.5 * length * b ** 4
        elif family == CLAMPED:
            bl = clamped_root(j + 1)
            b = bl / length
            s = (np.cosh(bl) + np.cos(bl)) / (np.sinh(bl) + np.sin(bl))
            one_s = (np.sin(bl) - np.cos(bl) - np.exp(-bl)) / (np.sinh(bl) + np.sin(bl))
            bx = b * x
            # cosh - s sinh = e^-bx + (1 - s) sinh: no cancellation at large b x
            y[j] = np.exp(-bx) + one_s * np.sinh(bx) - np.cos(bx) + s * np.sin(bx)
            dy[j] = b * (-np.exp(-bx) + one_s * np.cosh(bx) + np.sin(bx) + s * np.cos(bx))
            ddy[j] = b * b * (np.exp(-bx) + one_s * np.sinh(bx) + np.cos(bx) - s * np.sin(bx))
            mass[j], stiff[j] = length, length * b ** 4
        elif family != CLAMPED_LOADED:
            raise ValueError(f"mode_shapes: unknown family {family!r}")
    if family == CLAMPED_LOADED:
        coef, lam = _loaded_modes(n_modes)
        t = x / length
        for j in range(n_modes):
            y[j] = dy[j] = ddy[j] = 0.0
            for i in range(coef.shape[0]):   # (x/L)^(i+2) and its derivatives
                p = i + 2
                y[j] += coef[i, j] * t ** p
                dy[j] += coef[i, j] * p * t ** (p - 1) / length
                ddy[j] += coef[i, j] * p * (p - 1) * t ** (p - 2) / length ** 2
            mass[j], stiff[j] = length, length * lam[j] / length ** 4
    return y, dy, ddy, mass, stiff


@lru_cache(maxsize=4096)
def end_shapes(family, length, n_modes, n_twist):
    """(Y_k(L), Y_k'(L), Psi_k(L)), each (n,): the bending shapes, their slopes and the twists
    at a beam's output end, which place its output point and turn its output section
    (sections.output_section, sections.beam_output_offset, run_checks._beam_tips; docs/beam.md, "End
    sections"): evaluated once per kind of beam (read-only arrays)."""
    y, slope = (v[:, 0] for v in mode_shapes(family, length, n_modes, [length])[:2])
    twist = torsion_shapes(family, length, n_twist, [length])[0][:, 0]
    for v in (y, slope, twist):
        v.setflags(write=False)
    return y, slope, twist


@lru_cache(maxsize=1024)
def foreshortening_integrals(family, length, n_modes):
    """D0, D1, D2 (3, n_modes, n_modes): int_0^L w(x) Y_j'(x) Y_k'(x) dx for w = 1, L - x and
    (L^2 - x^2) / 2, the geometric stiffness integrals of docs/beam.md ("Geometric
    stiffening"): c(L) = 1/2 eta^T D0 eta, int c = 1/2 eta^T D1 eta, int x c = 1/2 eta^T D2 eta
    per plane.  By Gauss-Legendre quadrature with 3 n_modes + 12 points (the integrands are
    products of two slopes and a quadratic, like the modal integrals of
    kernels/transfers/beam_relations.py::quadrature_size); once per kind of beam (read-only)."""
    t, wt = np.polynomial.legendre.leggauss(3 * int(n_modes) + 12)
    x, wt = 0.5 * length * (t + 1.0), 0.5 * length * wt
    dy = mode_shapes(family, length, n_modes, x)[1]
    out = np.empty((3, n_modes, n_modes))
    for i, weight in enumerate((wt, wt * (length - x), wt * 0.5 * (length * length - x * x))):
        gram = (dy * weight) @ dy.T
        out[i] = 0.5 * (gram + gram.T)
    out.setflags(write=False)
    return out


def slope_grams(family, length, n_modes, points, order):
    """(len(points), n_modes, n_modes): D(x) = int_0^x Y_j'(xi) Y_k'(xi) dxi at each of the
    points, each by a Gauss-Legendre rule of `order` points on [0, x] (symmetrized): the
    foreshortening c(x) = 1/2 eta^T D(x) eta per plane of the exact foreshortening
    (docs/beam.md, "The exact foreshortening"; run_tables.exact_section_table,
    sections.foreshortening_along)."""
    t, wt = np.polynomial.legendre.leggauss(int(order))
    out = np.empty((len(points), n_modes, n_modes))
    for i, x in enumerate(points):
        dy = mode_shapes(family, length, n_modes, 0.5 * x * (t + 1.0))[1]
        gram = (dy * (0.5 * x * wt)) @ dy.T
        out[i] = 0.5 * (gram + gram.T)
    return out


def foreshortening(beam_row, eta, eta_dot=None):
    """(c(L), c'(L)): how far a beam's tip has moved back along its frame's axis, m, and its
    rate, m/s (docs/beam.md, "Geometric stiffening"), for eta (..., 2 m) (any leading axes);
    zero without geometric stiffening."""
    eta = np.asarray(eta, dtype=float)
    m = int(beam_row[MODES])
    if not beam_row[STIFFENING] or m == 0:
        zero = np.zeros(eta.shape[:-1])
        return zero, zero.copy()
    d0 = foreshortening_integrals(int(beam_row[FAMILY]), beam_row[LENGTH], m)[0]
    eta_dot = np.zeros_like(eta) if eta_dot is None else np.asarray(eta_dot, dtype=float)
    c = c_dot = 0.0
    for plane in range(2):
        e, ed = eta[..., plane * m:(plane + 1) * m], eta_dot[..., plane * m:(plane + 1) * m]
        c = c + 0.5 * np.einsum("...j,jk,...k->...", e, d0, e)
        c_dot = c_dot + np.einsum("...j,jk,...k->...", ed, d0, e)
    return c, c_dot


@lru_cache(maxsize=64)
def _loaded_modes(n_modes):
    """Coefficients c (n, n) of the loaded-end modes Y_j(x) = sum_i c_ij (x/L)^(i+2) on a unit
    length, and their eigenvalues lam_j (EI d4Y/dx4 = lam mu Y on a unit length): the Ritz
    eigenvectors of the beam clamped at x = 0 in the polynomial space x^2 .. x^(n+1), which holds
    the exact static deflection under any end force and moment (n >= 2; one mode is x^2, the
    deflection under an end moment: the lowest Ritz mode of x^2, x^3 would be stiffer in a chain
    of elements, since it nearly drops the end curvature).  Normalized to
    int_0^1 Y_j^2 = 1 and Y_j(1) > 0, so int_0^L Y_j Y_k dx = L delta_jk on any length.  Solved
    once per count (read-only arrays): a static solve evaluates the shapes thousands of times."""
    from scipy.linalg import eigh      # (when used: import dttmm stays light)
    p = np.arange(2, n_modes + 2)
    mass = 1.0 / (p[:, None] + p[None, :] + 1.0)                     # int t^(p_i + p_j)
    pp = p * (p - 1.0)
    stiff = np.outer(pp, pp) / (p[:, None] + p[None, :] - 3.0)       # int Y_i'' Y_j''
    lam, coef = eigh(stiff, mass)
    coef = coef / np.sqrt(np.einsum("ij,ik,kj->j", coef, mass, coef))
    coef = coef * np.sign(coef.sum(axis=0))
    coef.setflags(write=False)
    lam.setflags(write=False)
    return coef, lam

# layout of one row of Model.beam_params
(LENGTH, MASS_PER_LENGTH, EI_V, EI_W, POLAR_PER_LENGTH, DAMPING_RATIO, MODES, FAMILY,
 STIFFENING, FREQUENCY_CUTOFF, TORSION_MODES, GJ, LOAD_AXES, AXIAL_MODES, EA) = range(15)
BEAM_PARAM_SIZE = 15
LOAD_AXES_NAMES = {"world": 0.0, "body": 1.0}   # the applied loads' axes (docs/beam.md)


def modal_size(beam_row):
    """How many modal coordinates a beam row has: 2 x modes_per_plane bending (v, then w), then
    torsion_modes twist coordinates (docs/beam.md, "Torsion"), then axial_modes stretch
    coordinates ("Stretch")."""
    return 2 * int(beam_row[MODES]) + int(beam_row[TORSION_MODES]) + int(beam_row[AXIAL_MODES])


def torsion_shapes(family, length, n_modes, x):
    """(Psi, Psi') of the first n_modes twist shapes at the points x, each (n_modes, len(x)),
    and the modal mass and stiffness factors (m_k / j_p, k_k / GJ), each (n_modes,)
    (docs/beam.md, "Torsion"); the stretch's shapes too (the same operator: E A u'' = mu u'',
    with m_k / mu and k_k / E A; "Stretch").  Psi_k(0) = 0 (the twist is measured from the
    frame, which is the input section's about x) and int_0^L Psi_j Psi_k dx = L delta_jk.  A
    free or
    moment-free output (families PINNED, CLAMPED): the clamped-free eigenfunctions
    sqrt(2) sin((2k - 1) pi x / (2 L)); an output that carries loads (CLAMPED_LOADED): the Ritz
    eigenvectors in the polynomial space x/L .. (x/L)^n, which holds the uniform twist an end
    torque makes."""
    x = np.asarray(x, dtype=float)
    psi, dpsi = np.empty((n_modes, x.size)), np.empty((n_modes, x.size))
    mass, stiff = np.full(n_modes, float(length)), np.empty(n_modes)
    if family == CLAMPED_LOADED:
        coef, lam = _loaded_twist_modes(n_modes)
        t = x / length
        for j in range(n_modes):
            psi[j] = dpsi[j] = 0.0
            for i in range(coef.shape[0]):       # (x/L)^(i+1) and its derivative
                p = i + 1
                psi[j] += coef[i, j] * t ** p
                dpsi[j] += coef[i, j] * p * t ** (p - 1) / length
            stiff[j] = lam[j] / length
    else:
        for j in range(n_modes):
            b = (2 * j + 1) * np.pi / (2 * length)
            psi[j] = np.sqrt(2.0) * np.sin(b * x)
            dpsi[j] = np.sqrt(2.0) * b * np.cos(b * x)
            stiff[j] = length * b * b
    return psi, dpsi, mass, stiff


def stretch_along(beam_row, eta, x):
    """u_x(x) = U(x) . xi, the stretch of a beam row's centreline at the points x (docs/beam.md,
    "Stretch"), for eta (..., modal_size) (any leading axes; xi its last axial_modes entries):
    (..., len(x)); zeros without stretch modes."""
    eta = np.asarray(eta, dtype=float)
    ma = int(beam_row[AXIAL_MODES])
    shapes = torsion_shapes(int(beam_row[FAMILY]), beam_row[LENGTH], ma, x)[0]   # (ma, len(x))
    return rows_dot(eta[..., eta.shape[-1] - ma:], shapes)    # (per row as for any T)


def axial_frequencies(beam_row, n_modes=None):
    """(Hz) the first n_modes (default: the row's) stretch frequencies of a beam row's resolved
    family, sqrt(k_j E A / (m_j mu)) / 2 pi (docs/beam.md, "Stretch": the twist's shapes)."""
    n = int(beam_row[AXIAL_MODES]) if n_modes is None else int(n_modes)
    _, _, mass, stiff = torsion_shapes(int(beam_row[FAMILY]), beam_row[LENGTH], n, [0.0])
    return np.sqrt(beam_row[EA] * stiff / (beam_row[MASS_PER_LENGTH] * mass)) / (2 * np.pi)


@lru_cache(maxsize=64)
def _loaded_twist_modes(n_modes):
    """Coefficients c (n, n) of the loaded-end twist modes Psi_j = sum_i c_ij (x/L)^(i+1) on a
    unit length and their eigenvalues lam_j (GJ Psi'' = -lam j_p Psi there): the Ritz
    eigenvectors of the shaft fixed at x = 0 in the space x .. x^n, normalized to
    int_0^1 Psi_j^2 = 1 and Psi_j(1) > 0.  Solved once per count (read-only arrays)."""
    from scipy.linalg import eigh      # (when used: import dttmm stays light)
    p = np.arange(1, n_modes + 1)
    mass = 1.0 / (p[:, None] + p[None, :] + 1.0)                          # int t^(p_i + p_j)
    stiff = np.outer(p, p) / (p[:, None] + p[None, :] - 1.0)              # int Psi_i' Psi_j'
    lam, coef = eigh(stiff, mass)
    coef = coef / np.sqrt(np.einsum("ij,ik,kj->j", coef, mass, coef))
    coef = coef * np.sign(coef.sum(axis=0))
    coef.setflags(write=False)
    lam.setflags(write=False)
    return coef, lam


def torsion_frequencies(beam_row, n_modes=None):
    """(Hz) the first n_modes (default: the row's) twist frequencies of a beam row's resolved
    family, sqrt(k_j GJ / (m_j j_p)) / 2 pi (docs/beam.md, "Torsion")."""
    n = int(beam_row[TORSION_MODES]) if n_modes is None else int(n_modes)
    _, _, mass, stiff = torsion_shapes(int(beam_row[FAMILY]), beam_row[LENGTH], n, [0.0])
    return np.sqrt(beam_row[GJ] * stiff / (beam_row[POLAR_PER_LENGTH] * mass)) / (2 * np.pi)
MAX_AUTO_MODES = 10   # modes_per_plane="auto" keeps at most this many (6 for loaded-end modes)
FROM_STEP = -1.0      # FREQUENCY_CUTOFF of "auto" without a cutoff: the build derives it
ACCURATE = -2.0       # FREQUENCY_CUTOFF of modes_per_plane=None: the build counts by ACCURACY
ACCURACY = 5e-3       # modes_per_plane=None (default): each beam's estimated truncation error
#                       (first and second frequency, static deflection; truncation_errors) at
#                       most this


def largest_basis(beam_row):
    """The most modes per plane a beam row's resolved family takes: MAX_LOADED_MODES for the
    loaded-end polynomial modes, else MAX_AUTO_MODES."""
    return MAX_LOADED_MODES if int(beam_row[FAMILY]) == CLAMPED_LOADED else MAX_AUTO_MODES


def _end_ratio(beam_row, end_mass):
    """end_mass / (mu L) for the loaded-end family (what hangs on its output; 0 for the others),
    to 2 digits: the unit problems' cache key (2 digits are plenty there)."""
    if int(beam_row[FAMILY]) != CLAMPED_LOADED:
        return 0.0
    return float(f"{end_mass / (beam_row[MASS_PER_LENGTH] * beam_row[LENGTH]):.2g}")


def truncation_errors(beam_row, n_modes, end_mass=0.0, ends=(False, False)):
    """{estimate: relative error} of n_modes per plane against the family's largest basis
    (MAX_LOADED_MODES, else MAX_AUTO_MODES): the Ritz problem of the beam alone with the ends
    it has (docs/beam.md, "How many modes"), the loaded-end family's output carrying end_mass
    (kg: what hangs on it, as a point mass), under a uniform load along its length plus that
    mass's weight.  ends = (root pinned, tip pinned): whether, in some bending plane, the root
    turns freely (a ball, revolute or universal joint whose coordinate nothing prescribes) or
    the output is held at a point and turns freely (a closing ball, revolute or universal
    joint).  Clamped ends: the first frequency and the largest static deflection.  A pinned end:
    the first two flexible frequencies (the swing's inertial load, linear along the beam,
    excites the second) and the static deflection from the chord (with a free tip the beam
    swings about its root: the rigid turn takes the load's moment, the modes the rest).  Ratios
    of the same beam's numbers, so they depend on the family, n_modes, end_mass / (mu L) and the
    ends only."""
    family, ratio = int(beam_row[FAMILY]), _end_ratio(beam_row, end_mass)
    cap = largest_basis(beam_row)
    n = min(int(n_modes), cap)
    root, tip = bool(ends[0]), bool(ends[1])
    if family == PINNED or not (root or tip):
        f, d = _unit_beam_statics(family, n, ratio)
        f_ref, d_ref = _unit_beam_statics(family, cap, ratio)
        errors = {"first frequency": f / f_ref - 1.0, "static deflection": d / d_ref - 1.0}
        if family == CLAMPED_LOADED:      # (welded on to what it carries: the second, too)
            errors["second frequency"] = _second_frequency(n, ratio) / _second_frequency(
                cap, ratio) - 1.0
        return errors
    f, d = _unit_beam_with_ends(family, n, ratio, root, tip)
    f_ref, d_ref = _unit_beam_with_ends(family, cap, ratio, root, tip)
    f, f_ref = f + (np.inf, np.inf), f_ref + (np.inf, np.inf)
    return {"first frequency": f[0] / f_ref[0] - 1.0,
            "second frequency": f[1] / f_ref[1] - 1.0,
            "static deflection from the chord": d / d_ref - 1.0}


FREQUENCY_TRUST = 0.01      # a beam's own frequency is trusted within 1% of the largest basis'


def trusted_frequency(beam_row, end_mass=0.0, ends=(False, False)):
    """Hz: the beam's own frequencies below this one come out within FREQUENCY_TRUST of the
    family's largest basis with the modes it keeps; the first that does not, or the first it
    does not keep (of the largest basis), is returned (of the softer plane), inf where every
    own frequency of the largest basis is held.  The unit Ritz problem of truncation_errors
    (the beam alone with its ends and end mass), all its flexible frequencies.  A system's
    frequency at or above the lowest of these over its beams may be off by more than 1%
    (StaticEquilibrium.trusted)."""
    family, ratio = int(beam_row[FAMILY]), _end_ratio(beam_row, end_mass)
    cap, n = largest_basis(beam_row), int(beam_row[MODES])
    f = _unit_beam_with_ends(family, min(n, cap), ratio, bool(ends[0]), bool(ends[1]))[0]
    f_ref = _unit_beam_with_ends(family, cap, ratio, bool(ends[0]), bool(ends[1]))[0]
    scale = np.sqrt(min(beam_row[EI_V], beam_row[EI_W])
                    / (beam_row[MASS_PER_LENGTH] * beam_row[LENGTH] ** 4)) / (2 * np.pi)
    for j, reference in enumerate(f_ref):
        if j >= len(f) or abs(f[j] / reference - 1.0) > FREQUENCY_TRUST:
            return float(reference * scale)
    return np.inf


@lru_cache(maxsize=4096)
def _unit_beam_statics(family, n_modes, end_ratio):
    """(first circular frequency, largest deflection) of a unit beam (L = mu = EI = 1) of the
    family with n_modes, an end mass end_ratio at its output (loaded-end family), under a unit
    uniform load and that mass's unit weight."""
    from scipy.linalg import eigh      # (when used: import dttmm stays light)
    xg, wg = np.polynomial.legendre.leggauss(24)
    x, w = 0.5 * (xg + 1.0), 0.5 * wg
    along = np.linspace(0.0, 1.0, 101)
    y, _, _, mass, stiff = mode_shapes(family, 1.0, n_modes, np.concatenate([x, along, [1.0]]))
    tip = y[:, -1]
    m = np.diag(mass) + end_ratio * np.outer(tip, tip)
    first = eigh(np.diag(stiff), m, eigvals_only=True, subset_by_index=[0, 0])[0]
    eta = (y[:, :len(x)] @ w + end_ratio * tip) / stiff
    return float(np.sqrt(first)), float(np.max(np.abs(eta @ y[:, len(x):-1])))


@lru_cache(maxsize=4096)
def _second_frequency(n_modes, end_ratio):
    """The second circular frequency of a unit loaded-end beam with n_modes, clamped, its
    output carrying end_ratio as a point mass (inf with one mode)."""
    f = _unit_beam_with_ends(CLAMPED_LOADED, n_modes, end_ratio, False, False)[0]
    return f[1] if len(f) > 1 else np.inf


@lru_cache(maxsize=4096)
def _unit_beam_with_ends(family, n_modes, end_ratio, root_pinned, tip_pinned):
    """((every flexible circular frequency, ascending), largest static deflection from the
    chord) of a unit beam (L = mu = EI = 1) with n_modes of the family in its input section's frame:
    root_pinned adds the frame's turn about the root, w = theta x, as a coordinate without
    stiffness; tip_pinned holds the output on the root's line, w(L) = 0 (the constraint
    eliminated by its null space).  A free tip carries end_ratio as a point mass.  The
    deflection under a unit uniform load and the end mass's unit weight: with a pinned root and
    a free tip the beam cannot stand, and the load turns it at theta'' = f_theta / M_theta_theta
    while the modes take f - M theta'' (the quasi-static swing, inertia relief)."""
    from scipy.linalg import eigh, null_space
    xg, wg = np.polynomial.legendre.leggauss(48)
    x, w = 0.5 * (xg + 1.0), 0.5 * wg
    along = np.linspace(0.0, 1.0, 101)
    points = np.concatenate([x, along, [1.0]])
    y, _, ddy, _, _ = mode_shapes(family, 1.0, n_modes, points)
    shapes, curvatures = y, ddy
    if root_pinned:
        shapes = np.vstack([points, y])
        curvatures = np.vstack([np.zeros_like(points), ddy])
    q = len(x)
    mass = (shapes[:, :q] * w) @ shapes[:, :q].T
    stiff = (curvatures[:, :q] * w) @ curvatures[:, :q].T
    tip = shapes[:, -1]
    load = shapes[:, :q] @ w
    if not tip_pinned:
        mass = mass + end_ratio * np.outer(tip, tip)
        load = load + end_ratio * tip
    basis = null_space(tip[None, :]) if tip_pinned else np.eye(len(tip))
    if basis.shape[1] <= int(root_pinned and not tip_pinned):
        return (), np.inf                          # no flexible coordinate left
    mass, stiff, load = basis.T @ mass @ basis, basis.T @ stiff @ basis, basis.T @ load
    values = eigh(stiff, mass, eigvals_only=True)
    flexible = np.sqrt(values[values > 1e-9 * values.max()])
    if root_pinned and not tip_pinned:
        turn = load[0] / mass[0, 0]
        coordinates = np.zeros(len(load))
        coordinates[1:] = np.linalg.solve(stiff[1:, 1:], load[1:] - mass[1:, 0] * turn)
    else:
        coordinates = np.linalg.solve(stiff, load)
    deflection = (basis @ coordinates) @ shapes[:, q:-1]
    deflection = deflection - along * deflection[-1]          # from the chord
    return tuple(float(f) for f in flexible), float(np.max(np.abs(deflection)))


def accurate_mode_count(beam_row, end_mass=0.0, ends=(False, False)):
    """modes_per_plane=None: the fewest modes per plane whose truncation_errors (for the beam's
    ends) are all at most ACCURACY (the largest basis if none is).  Needs the family
    resolved."""
    cap = largest_basis(beam_row)
    for n in range(1, cap + 1):
        errors = truncation_errors(beam_row, n, end_mass, ends)
        if max(abs(e) for e in errors.values()) <= ACCURACY:
            return n
    return cap


def bending_frequencies(beam_row, n_modes=None):
    """(Hz) the first n_modes (default: the row's) bending frequencies of a beam row's resolved
    family, sqrt(k_j / m_j) / 2 pi (docs/beam.md, "Mode shapes"), per plane: (v, w)."""
    m = int(beam_row[MODES]) if n_modes is None else int(n_modes)
    _, _, _, mass, stiff = mode_shapes(int(beam_row[FAMILY]), beam_row[LENGTH], m, [0.0])
    mu = beam_row[MASS_PER_LENGTH]
    return tuple(np.sqrt(beam_row[ei] * stiff / (mu * mass)) / (2 * np.pi) for ei in (EI_V, EI_W))


def auto_mode_count(beam_row):
    """modes_per_plane="auto": how many modes per plane to keep, every mode whose frequency in
    either plane is at or below the row's FREQUENCY_CUTOFF (Hz), at least one, at most
    MAX_AUTO_MODES (MAX_LOADED_MODES for the loaded-end family, whose Ritz frequencies are taken
    from its largest basis, the best estimates).  Needs the family resolved."""
    cap = largest_basis(beam_row)
    fv, fw = bending_frequencies(beam_row, cap)
    below = int(np.sum(np.minimum(fv, fw) <= beam_row[FREQUENCY_CUTOFF]))
    return min(max(below, 1), cap)


def auto_part_count(beam_row, frequencies):
    """torsion_modes or axial_modes "auto": how many twist or stretch modes to keep, every one
    whose frequency (frequencies(row, n), Hz, of the resolved family) is at or below the row's
    FREQUENCY_CUTOFF, none at least (the part then stays off), MAX_LOADED_MODES at most (the
    frequencies of the largest basis: the best estimates for the Ritz modes)."""
    return int(np.sum(frequencies(beam_row, MAX_LOADED_MODES) <= beam_row[FREQUENCY_CUTOFF]))


def _part(who, modes_arg, modes, stiffness_arg, stiffness, what, unit, auto):
    """(count, stiffness) of the twist or the stretch, checked: an integer 0 .. 6 of modes
    (or "auto" with modes_per_plane="auto": count AUTO, resolved at the build by
    auto_part_count), and a finite stiffness > 0 where there are modes (one without modes is
    kept, unused: the part switched off)."""
    if isinstance(modes, str) and modes == "auto":
        if not auto:
            raise ValueError(f"{who}: {modes_arg}='auto' keeps the {what} modes at or below "
                             f"frequency_cutoff: give modes_per_plane='auto' and a "
                             f"frequency_cutoff too")
        if stiffness is None:
            raise ValueError(f"{who}: {modes_arg}='auto' needs {stiffness_arg} ({unit})")
        return AUTO, finite_scalar(who, stiffness_arg, stiffness, positive=True)
    if (isinstance(modes, (str, bool)) or not np.isscalar(modes) or int(modes) != modes
            or modes < 0):
        raise ValueError(f"{who}: {modes_arg} must be an integer >= 0 (0: no {what}) or "
                         f"'auto', got {modes!r}")
    count = int(modes)
    if count > MAX_LOADED_MODES:
        raise ValueError(f"{who}: {modes_arg} is at most {MAX_LOADED_MODES}, got {count}")
    if count and stiffness is None:
        raise ValueError(f"{who}: {modes_arg}={count} needs {stiffness_arg} ({unit})")
    return count, (0.0 if stiffness is None else
                   finite_scalar(who, stiffness_arg, stiffness, positive=True))


@dataclass(frozen=True, eq=False)
class EulerBernoulliBeam:
    """A uniform Euler-Bernoulli beam with modal bending in two planes (docs/beam.md).

    Floating frame at the input end I, x along the reference axis (the chord I -> O for the
    pinned family, the input section's tangent for the clamped ones); a section at x sits at
    r(x) = r_I + A (x e1 + u(x)), u = [0, v, w], v = sum_k Y_k(x) eta_v[k],
    w = sum_k Y_k(x) eta_w[k]; the sections twist by psi = sum_k Psi_k(x) eta_t[k] with
    torsion_modes >= 1, and the centreline stretches with axial_modes >= 1 (u gains
    u_x = sum_k U_k(x) eta_a[k]).  Geometric stiffening on
    request (``stiffening``); the section's rotary inertia is left out, its polar inertia
    kept for the frame's spin about x.  The arguments are checked when the model is built
    (``System.build`` or ``build_chain``), not here.

    Parameters
    ----------
    length : float
        L, m (> 0).
    bending_stiffness : float or array_like of 2
        (EI_v, EI_w), N m^2 (each > 0): EI_v for the deflection v along body y (bending about
        z), EI_w for w along body z (bending about y); a scalar for both.
    polar_inertia_per_length : float
        j_p = rho I_p, kg m: the section's polar mass moment per length (e.g. mu a^2 / 6 for a
        square section of side a); > 0: it keeps the frame's spin about its own axis well
        posed (its value barely matters).
    mass_per_length : float, optional
        mu, kg/m (> 0).  Give it, or density and area, not both.
    density : float, optional
        rho, kg/m^3 (> 0), with area: mu = density * area.
    area : float, optional
        Cross-section area, m^2 (> 0), with density.
    modes_per_plane : int, "auto" or None, optional
        Number of bending modes in each plane, >= 1; at most 6 for a clamped beam whose output
        carries loads (its polynomial modes).  The beam has 2 x modes_per_plane modal
        coordinates.  None (default): the fewest whose estimated truncation error (first
        frequency and static deflection of the beam with what hangs on it) is at most 0.5%,
        counted at the build (docs/beam.md, "How many modes"; or the count that given initial
        modal coordinates imply).  "auto": every mode whose frequency (in either plane, of the
        family the beam's ends select) is at or below frequency_cutoff, at least the default's
        count, at most 10 (6 for polynomial modes); ``Model.describe()`` says what was kept.
    damping_ratio : float, optional
        Modal damping ratio zeta (>= 0, default 0), dimensionless: each mode's damping
        c_k = 2 zeta omega_k m_k, acting in the beam's (rotating) frame.
    mode_family : {"auto", "pinned", "clamped"}, optional
        "auto" (default): "pinned" between moment-free ends (ball joints, the free or the
        pinned tip), otherwise "clamped" in the input section's frame (clamped-free
        eigenfunctions when the output is the free tip, loaded-end polynomial modes when it
        carries loads).  "pinned": sine modes in the chord frame (refused where a fixed or
        elastic hinge holds the beam).  "clamped": the input section's frame (refused between
        moment-free ends unless force_mode_family).  docs/beam.md, "Mode shapes".
    force_mode_family : bool, optional
        Accept "clamped" between moment-free ends, e.g. after a ball joint (admissible but slow
        to converge: each shape carries a spurious input moment).  Default False.
    initial_modal_coordinates : array_like of 2 x modes_per_plane + torsion_modes + axial_modes
        eta at t = 0, m (the mode shapes have unit amplitude): the v coordinates, then the w
        coordinates, the twist coordinates (rad), the stretch coordinates (m).  None
        (default): zero (undeformed).
    initial_modal_velocities : array_like of as many, optional
        eta' at t = 0, m/s (rad/s for the twist), in the same order.  None (default): zero.
    rotation : array_like (3, 3), optional
        Initial frame rotation (body to world), as for ``RigidBody``.
    angular_velocity : array_like of 3, optional
        Initial world-frame angular velocity of the frame, rad/s, as for ``RigidBody``.
    name : str, optional
        The body's name, as for ``RigidBody`` (default "": ``body{k}``).
    frequency_cutoff : float, optional
        Hz (> 0), with modes_per_plane="auto" (and only then): the highest frequency to keep.
        None (default) with "auto": derived when the model is built with ``step=`` (and
        ``duration=``): what the step resolves, 1 / (20 step) (about 20 steps per period),
        lowered to ten times the drives' bandwidth (``build_chain``, docs/beam.md "Mode
        shapes").
    end_force : callable or array_like of 3, optional
        end_force(t) -> 3 numbers: a world-frame force applied at the beam's output end at
        time t (s), N (docs/beam.md, "Loads on the beam").  None (default): none.  Each of
        the three loads may be given as 3 numbers for a constant one.
    end_torque : callable or array_like of 3, optional
        end_torque(t) -> 3 numbers: a world-frame torque applied to the beam's output end
        section, N m.  None (default): none.  A loaded output takes the clamped family's
        loaded-end modes (the free-tip eigenfunctions carry no end load; a torque also rules
        out the pinned family, whose sections' rotations are not modelled).
    distributed_load : callable or array_like of 3, optional
        distributed_load(t) -> 3 numbers: a uniform world-frame load per length along the
        beam at time t (s), N/m (docs/beam.md, "Loads on the beam"; it acts like gravity on
        this beam alone).  None (default): none.
    load_axes : {"world", "body"}, optional
        The axes of end_force, end_torque and distributed_load: "world" (default), or "body":
        followers, the end loads in the output end section's axes (they turn with it, e.g. a
        thrust along the tip's tangent), the distributed load in the beam frame's.
    stiffening : bool, "exact" or None, optional
        Geometric stiffening of bending by the axial force (docs/beam.md, "Geometric
        stiffening"): the foreshortening of the deflected centreline kept to second order in
        the energy, so inertia (centrifugal loads included), gravity and the end loads stiffen
        or soften the bending modes.  None (default): on, except for a beam without stretch
        modes in a closed loop (a chain whose tip is pinned): its centreline is then
        inextensible, and held between fixed points it could not bow, so there it stays off
        (the paper's beam) unless asked for; ``model.describe()`` says which.  False: the
        paper's beam.  "exact": the foreshortening kept to all orders (every section at
        x - c(x) along the frame; docs/beam.md, "The exact foreshortening"), for an element
        that bends further than the second-order energy holds (~0.17 rad over its length with
        two modes per plane); its w' and eta'' columns are differenced (the general loop, or
        the welded-chain loop's differenced transfer).

    torsion_modes : int or "auto", optional
        Number of twist modes, >= 0, at most 6 (default 0: the beam does not twist); "auto"
        (with modes_per_plane="auto"): those at or below frequency_cutoff, maybe none.
        docs/beam.md, "Torsion".  A beam with twist runs in the general loop.
    axial_modes : int or "auto", optional
        Number of stretch modes (axial displacement along the frame's x), >= 0, at most 6
        (default 0: the centreline does not stretch); "auto" as for torsion_modes.
        docs/beam.md, "Stretch".  A beam with stretch runs in the general loop.
    axial_stiffness : float, optional
        E A, N (> 0); needed with axial_modes >= 1 (with 0 it is kept and unused).
    torsional_stiffness : float, optional
        G J, N m^2 (> 0); needed with torsion_modes >= 1 (with 0 it is kept and unused: the
        twist switched off).

    Raises
    ------
    ValueError
        At build time, naming the beam (its name and index) and the argument: a length,
        stiffness, polar inertia, mass per length, density or area that is not a finite
        number > 0; mass_per_length given with density or area, or neither; modes_per_plane
        not an integer >= 1 (or above 6 for loaded-end modes) or "auto", "auto" without a
        frequency_cutoff > 0 or with initial modal coordinates, a frequency_cutoff with a
        fixed mode count; a negative damping ratio; an
        unknown mode family, or one that contradicts the beam's ends; initial modal
        coordinates or velocities without 2 x modes_per_plane + torsion_modes + axial_modes
        finite entries; a bad rotation or angular velocity; stiffening not a bool;
        torsion_modes or axial_modes not an integer in 0 .. 6, or >= 1 without its stiffness;
        a torsional_stiffness or axial_stiffness that is not a finite number > 0; load_axes not
        "world" or "body".

    Examples
    --------
    A steel strip, 1 m long, two modes per plane, pinned between ball joints:

    >>> import dttmm
    >>> beam = dttmm.EulerBernoulliBeam(length=1.0, density=7800.0, area=1e-4,
    ...                                 bending_stiffness=[20.0, 200.0],
    ...                                 polar_inertia_per_length=1e-5, modes_per_plane=2)
    >>> model = dttmm.build_chain([dttmm.BallJoint(), beam])
    """
    length: float
    bending_stiffness: object
    polar_inertia_per_length: float
    mass_per_length: float = None
    density: float = None
    area: float = None
    modes_per_plane: object = None
    damping_ratio: float = 0.0
    mode_family: str = "auto"
    force_mode_family: bool = False
    initial_modal_coordinates: object = None
    initial_modal_velocities: object = None
    rotation: object = None
    angular_velocity: object = None
    name: str = ""
    stiffening: Optional[bool] = None
    frequency_cutoff: float = None
    end_force: Optional[Callable[[float], object]] = None
    end_torque: Optional[Callable[[float], object]] = None
    distributed_load: Optional[Callable[[float], object]] = None
    torsional_stiffness: float = None
    torsion_modes: int = 0
    load_axes: str = "world"
    axial_stiffness: float = None
    axial_modes: int = 0

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
        ei = finite_pair(who, "bending_stiffness", self.bending_stiffness, positive=True)
        polar = finite_scalar(who, "polar_inertia_per_length", self.polar_inertia_per_length,
                              positive=True)
        physical_frequency(who, "bending_stiffness", 1.875 ** 2 / (2 * np.pi) * np.sqrt(
            max(ei) / (mu * length ** 4)))
        auto = isinstance(self.modes_per_plane, str) and self.modes_per_plane == "auto"
        accurate = self.modes_per_plane is None      # the default: counted at the build
        if accurate and self.frequency_cutoff is not None:
            raise ValueError(f"{who}: frequency_cutoff applies to modes_per_plane='auto' only "
                             f"(the default, None, keeps as many modes as the beam needs for "
                             f"{ACCURACY:.1%} accuracy)")
        if auto:
            # no cutoff: FROM_STEP, derived by the build from its step= (model/freeze.py)
            cutoff = (FROM_STEP if self.frequency_cutoff is None else
                      finite_scalar(who, "frequency_cutoff", self.frequency_cutoff,
                                    positive=True))
            for arg in ("initial_modal_coordinates", "initial_modal_velocities"):
                if getattr(self, arg) is not None:
                    raise ValueError(f"{who}: {arg} needs a fixed modes_per_plane (with 'auto' "
                                     f"the count is known only when the model is built)")
        elif accurate:
            pass
        elif (isinstance(self.modes_per_plane, (str, bool, np.bool_))
              or not isinstance(self.modes_per_plane, (int, float, np.integer, np.floating))
              or not np.isfinite(self.modes_per_plane)
              or int(self.modes_per_plane) != self.modes_per_plane or self.modes_per_plane < 1):
            raise ValueError(f"{who}: modes_per_plane must be an integer >= 1, 'auto' or None "
                             f"(the default: as many as {ACCURACY:.1%} accuracy needs), got "
                             f"{self.modes_per_plane!r}")
        elif self.frequency_cutoff is not None:
            raise ValueError(f"{who}: frequency_cutoff applies to modes_per_plane='auto' only "
                             f"(this beam keeps {self.modes_per_plane} modes per plane)")
        zeta = finite_scalar(who, "damping_ratio", self.damping_ratio, nonnegative=True)
        if self.mode_family not in MODE_FAMILY_NAMES:
            raise ValueError(f"{who}: mode_family must be one of {sorted(MODE_FAMILY_NAMES)}, "
                             f"got {self.mode_family!r}")
        n_twist, gj = _part(who, "torsion_modes", self.torsion_modes, "torsional_stiffness",
                            self.torsional_stiffness, "twist", "G J, N m^2", auto)
        n_axial, ea = _part(who, "axial_modes", self.axial_modes, "axial_stiffness",
                            self.axial_stiffness, "stretch", "E A, N", auto)
        physical_frequency(who, "axial_stiffness", np.sqrt(ea / mu) / (4 * length))
        physical_frequency(who, "torsional_stiffness", np.sqrt(gj / polar) / (4 * length))
        per_plane = self.modes_per_plane
        if accurate:
            # initial modal coordinates given: their size says how many modes; otherwise the
            # build counts them (model/freeze.py::_resolve_mode_families, accurate_mode_count)
            given = [np.size(v) for v in (self.initial_modal_coordinates,
                                          self.initial_modal_velocities) if v is not None]
            bending = (given[0] - n_twist - n_axial) if given else 0
            if given and (bending < 2 or bending % 2):
                raise ValueError(f"{who}: initial_modal_coordinates must have 2 x "
                                 f"modes_per_plane + torsion_modes + axial_modes entries; give "
                                 f"modes_per_plane with them (got {given[0]} entries)")
            per_plane = bending // 2 if given else None
            accurate = per_plane is None
        n_coord = 0 if (auto or accurate) else 2 * int(per_plane) + n_twist + n_axial
        given = (("initial_modal_coordinates", self.initial_modal_coordinates),
                 ("initial_modal_velocities", self.initial_modal_velocities))
        eta0, eta_d0 = (np.zeros(n_coord) if v is None
                        else finite_vector(who, arg, v, size=n_coord) for arg, v in given)
        rotation = (None if self.rotation is None
                    else rotation_matrix(who, "rotation", self.rotation))
        omega = None if self.angular_velocity is None else finite_vector(
            who, "angular_velocity", self.angular_velocity)
        row = np.zeros(BEAM_PARAM_SIZE)
        row[LENGTH], row[MASS_PER_LENGTH], row[EI_V], row[EI_W] = length, mu, ei[0], ei[1]
        row[POLAR_PER_LENGTH], row[DAMPING_RATIO] = polar, zeta
        # "auto" and None: set at the build
        row[MODES] = 0 if (auto or accurate) else int(per_plane)
        row[FREQUENCY_CUTOFF] = cutoff if auto else (ACCURATE if accurate else 0.0)
        row[TORSION_MODES], row[GJ] = n_twist, gj
        row[AXIAL_MODES], row[EA] = n_axial, ea
        if not isinstance(self.load_axes, str) or self.load_axes not in LOAD_AXES_NAMES:
            raise ValueError(f"{who}: load_axes must be 'world' or 'body', got "
                             f"{self.load_axes!r}")
        row[LOAD_AXES] = LOAD_AXES_NAMES[self.load_axes]
        row[FAMILY] = MODE_FAMILY_NAMES[self.mode_family]
        exact = isinstance(self.stiffening, str) and self.stiffening == "exact"
        if not exact and self.stiffening is not None and not isinstance(self.stiffening,
                                                                         (bool, np.bool_)):
            raise ValueError(f"{who}: stiffening must be True, False, 'exact' or None (on unless "
                             f"the beam would lock: the default), got {self.stiffening!r}")
        # None: AUTO, resolved by build_chain (model/freeze.py::_resolve_mode_families)
        row[STIFFENING] = (AUTO if self.stiffening is None else EXACT if exact
                           else float(self.stiffening))
        # the undeformed beam as a rigid body (line mass on the x axis plus the polar inertia)
        return dict(straight_line_body(length, mu, polar),
                    force=optional_function(who, "end_force", self.end_force),
                    torque=optional_function(who, "end_torque", self.end_torque),
                    line_load=optional_function(who, "distributed_load",
                                                self.distributed_load),
                    rotation=rotation, omega=omega,
                    beam=row, eta0=eta0, eta_d0=eta_d0,
                    force_mode_family=bool(self.force_mode_family))
