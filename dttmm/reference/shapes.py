"""The beams' mode shapes and their constants, evaluated by the reference itself (it does not
call dttmm.elements.beam.mode_shapes; newton_euler.py, "Beams")."""
import math

import numpy as np

from ..elements.beam import (CLAMPED, CLAMPED_LOADED, FAMILY, LENGTH, MODES, PINNED, TORSION_MODES,
                             AXIAL_MODES)

from .rows import N_SHAPE_ROWS, _DYL, _KF, _MF, _SY, _TY, _YL


# b_k L of the clamped-free modes: the roots of 1 + cos x cosh x = 0, and beyond the fifth
# (2k - 1) pi / 2, as docs/beam.md prescribes (off the true root by ~1 / cosh(b_k L): 6e-8 for
# k = 6, so those shapes are orthogonal only to ~1e-8; the mass matrix here is the quadrature
# of int Y_j Y_k, not L delta_jk, so the equations stay consistent with the energy)
_CLAMPED_ROOTS = (1.87510406871196, 4.69409113297418, 7.85475743823761, 10.9955407348755,
                  14.1371683910465)


def clamped_shapes(length, n_modes, x):
    """(Y, Y') of the first n_modes clamped-free eigenfunctions at the points x, each
    (n_modes, len(x)), and b_k (n_modes,): Y = cosh bx - cos bx - s (sinh bx - sin bx), written as
    e^(-bx) + (1 - s) sinh bx - cos bx + s sin bx so that no digits cancel at large b x."""
    x = np.asarray(x, dtype=float).reshape(-1)
    y = np.empty((n_modes, x.size))
    dy = np.empty((n_modes, x.size))
    betas = np.empty(n_modes)
    for j in range(n_modes):
        k = j + 1
        bl = _CLAMPED_ROOTS[j] if k <= len(_CLAMPED_ROOTS) else (2 * k - 1) * math.pi / 2.0
        b = bl / length
        den = math.sinh(bl) + math.sin(bl)
        s = (math.cosh(bl) + math.cos(bl)) / den
        one_minus_s = (math.sin(bl) - math.cos(bl) - math.exp(-bl)) / den
        bx = b * x
        e = np.exp(-bx)
        y[j] = e + one_minus_s * np.sinh(bx) - np.cos(bx) + s * np.sin(bx)
        dy[j] = b * (-e + one_minus_s * np.cosh(bx) + np.sin(bx) + s * np.cos(bx))
        betas[j] = b
    return y, dy, betas


def quadrature_points(n_modes):
    """Gauss-Legendre points used for the clamped integrals of a beam with n_modes per plane."""
    return 48 + 8 * int(n_modes)


def beam_shape_constants(beam_row, n_points=None):
    """Shape constants of one beam: a (N_SHAPE_ROWS, n) array with rows int Y_k, int x Y_k,
    Y_k(L), Y_k'(L), m_k / mu and k_k / EI, and the (n, n) matrix int Y_j Y_k (newton_euler.py's
    docstring: analytic for 'pinned' and the loaded-end modes, Gauss-Legendre quadrature for the
    clamped-free eigenfunctions; n_points overrides the number of points)."""
    length, nm, family = float(beam_row[LENGTH]), int(beam_row[MODES]), int(beam_row[FAMILY])
    vec = np.zeros((N_SHAPE_ROWS, nm))
    k = np.arange(1, nm + 1)
    if family == PINNED:
        sgn = (-1.0) ** k
        vec[_SY] = length * (1.0 - sgn) / (k * np.pi)
        vec[_TY] = -length * length * sgn / (k * np.pi)
        vec[_YL] = 0.0
        vec[_DYL] = (k * np.pi / length) * sgn
        vec[_MF] = 0.5 * length
        vec[_KF] = (k * np.pi / length) ** 4 * 0.5 * length
        mat = np.diag(np.full(nm, 0.5 * length))
    elif family == CLAMPED:
        nq = quadrature_points(nm) if n_points is None else int(n_points)
        xg, wg = np.polynomial.legendre.leggauss(nq)
        x = 0.5 * length * (xg + 1.0)
        wq = 0.5 * length * wg
        y, _, betas = clamped_shapes(length, nm, x)
        y_end, dy_end, _ = clamped_shapes(length, nm, [length])
        vec[_SY] = y @ wq
        vec[_TY] = y @ (wq * x)
        vec[_YL] = y_end[:, 0]
        vec[_DYL] = dy_end[:, 0]
        mat = (y * wq) @ y.T
        vec[_MF] = np.diag(mat)
        vec[_KF] = betas ** 4 * length
    elif family == CLAMPED_LOADED:
        # Y_j = sum_i c_ij (x/L)^p_i, p_i = i + 2: every integral is a polynomial moment
        c, lam = loaded_mode_coefficients(nm)
        p = np.arange(2, nm + 2, dtype=float)
        vec[_SY] = length * (c.T @ (1.0 / (p + 1.0)))
        vec[_TY] = length * length * (c.T @ (1.0 / (p + 2.0)))
        vec[_YL] = c.sum(axis=0)
        vec[_DYL] = (c.T @ p) / length
        mat = length * (c.T @ (1.0 / (p[:, None] + p[None, :] + 1.0)) @ c)
        vec[_MF] = np.diag(mat)
        vec[_KF] = lam / length ** 3
    else:
        raise ValueError(f"simulate_reference: unknown beam mode family {family}")
    return vec, mat


def shaft_shape_constants(length, family, count, x=None):
    """The closed-form shape constants of a second-order (twist or stretch) field on a beam:
    a (N_SHAPE_ROWS, count) array with rows _SY = int U_j, _TY = int x U_j, _YL = U_j(L),
    _MF = int U_j^2, _KF = int U_j'^2 (newton_euler.py's docstring, "Torsion" and "Stretch"), and
    the shapes U_j at the points x (count, len(x)) if given.  For a moment-free output (families
    pinned and clamped) U_j = sqrt(2) sin(b x), b = (2j - 1) pi / (2 L); for a loaded output the
    Ritz modes of the field fixed at 0 in the monomials (x/L)^1 .. (x/L)^count, every integral
    a polynomial moment."""
    from scipy.linalg import eigh      # (when used: import dttmm stays light)
    vec = np.zeros((N_SHAPE_ROWS, count))
    x = np.zeros(0) if x is None else np.asarray(x, dtype=float)
    if count == 0:
        return vec, np.zeros((0, x.size))
    if family == CLAMPED_LOADED:
        p = np.arange(1, count + 1, dtype=float)
        gram = 1.0 / (p[:, None] + p[None, :] + 1.0)
        lam, c = eigh(np.outer(p, p) / (p[:, None] + p[None, :] - 1.0), gram)
        c = c / np.sqrt(np.einsum("ij,ik,kj->j", c, gram, c))
        c = c * np.where(c.sum(axis=0) < 0.0, -1.0, 1.0)
        vec[_SY] = length * (c.T @ (1.0 / (p + 1.0)))
        vec[_TY] = length * length * (c.T @ (1.0 / (p + 2.0)))
        vec[_YL] = c.sum(axis=0)
        vec[_MF] = length * np.einsum("ij,ik,kj->j", c, gram, c)
        vec[_KF] = lam / length
        return vec, c.T @ (x / length)[None, :] ** p[:, None]
    b = (2.0 * np.arange(1, count + 1) - 1.0) * math.pi / (2.0 * length)
    vec[_SY] = math.sqrt(2.0) / b                 # sqrt(2) (1 - cos(b L)) / b, cos(b L) = 0
    vec[_TY] = math.sqrt(2.0) * np.sin(b * length) / (b * b)
    vec[_YL] = math.sqrt(2.0) * np.sin(b * length)
    vec[_MF] = length
    vec[_KF] = length * b * b
    return vec, math.sqrt(2.0) * np.sin(np.outer(b, x))


def twist_shape_constants(beam_row):
    """The twist's shape constants of one beam (newton_euler.py's docstring, "Torsion"):
    shaft_shape_constants with its torsion_modes (rows _SY = int Psi_k, _YL = Psi_k(L),
    _MF = int Psi_k^2, _KF = int Psi_k'^2 used)."""
    return shaft_shape_constants(float(beam_row[LENGTH]), int(beam_row[FAMILY]),
                                 int(beam_row[TORSION_MODES]))[0]


def stretch_shape_constants(beam_row):
    """The stretch's shape constants of one beam (newton_euler.py's docstring, "Stretch"): a
    (N_SHAPE_ROWS + m, ma) array with the rows of shaft_shape_constants (the twist's shapes:
    the same operator) and, from row N_SHAPE_ROWS on, int U_j Y_l (l < m, the bending shapes),
    by Gauss-Legendre quadrature of this module's own bending shapes
    (quadrature_points(max(m, ma)) points)."""
    length, m, ma, family = float(beam_row[LENGTH]), int(beam_row[MODES]), \
        int(beam_row[AXIAL_MODES]), int(beam_row[FAMILY])
    vec = np.zeros((N_SHAPE_ROWS + m, ma))
    if ma == 0:
        return vec
    xg, wg = np.polynomial.legendre.leggauss(quadrature_points(max(m, ma)))
    x, wq = 0.5 * length * (xg + 1.0), 0.5 * length * wg
    vec[:N_SHAPE_ROWS], u = shaft_shape_constants(length, family, ma, x)
    if family == CLAMPED_LOADED:
        pb = np.arange(2, m + 2, dtype=float)
        y = loaded_mode_coefficients(m)[0].T @ (x / length)[None, :] ** pb[:, None]
    elif family == PINNED:
        y = np.sin(np.arange(1, m + 1)[:, None] * math.pi * x[None, :] / length)
    else:
        y = clamped_shapes(length, m, x)[0]
    vec[N_SHAPE_ROWS:] = (y * wq) @ u.T
    return vec


def stiffening_matrices(beam_row):
    """The geometric stiffness integrals of one beam, (3, n, n): int_0^L w(x) Y_j'(x) Y_k'(x) dx
    for w = 1, L - x and (L^2 - x^2) / 2 (newton_euler.py's docstring, "Geometric stiffening"): for
    the loaded-end modes as polynomial moments, otherwise by Gauss-Legendre quadrature of the
    slopes with quadrature_points(n) points (products of two trigonometric or hyperbolic slopes
    and a quadratic weight)."""
    length, nm, family = float(beam_row[LENGTH]), int(beam_row[MODES]), int(beam_row[FAMILY])
    out = np.empty((3, nm, nm))
    if family == CLAMPED_LOADED:
        # Y_j' = (1/L) sum_i c_ij p_i t^(p_i - 1): int_0^L t^a Y_j' Y_k' dx = (1/L) c^T T_a c,
        # (T_a)_il = p_i p_l / (p_i + p_l - 1 + a)
        c, _ = loaded_mode_coefficients(nm)
        p = np.arange(2, nm + 2, dtype=float)
        moment = [(c.T @ (np.outer(p, p) / (p[:, None] + p[None, :] - 1.0 + a)) @ c) / length
                  for a in range(3)]
        out[0] = moment[0]
        out[1] = length * (moment[0] - moment[1])
        out[2] = 0.5 * length * length * (moment[0] - moment[2])
        return out
    xg, wg = np.polynomial.legendre.leggauss(quadrature_points(nm))
    x = 0.5 * length * (xg + 1.0)
    wq = 0.5 * length * wg
    if family == PINNED:
        k = np.arange(1, nm + 1)[:, None]
        dy = (k * np.pi / length) * np.cos(k * np.pi * x[None, :] / length)
    else:
        dy = clamped_shapes(length, nm, x)[1]
    for i, weight in enumerate((np.ones_like(x), length - x, 0.5 * (length * length - x * x))):
        out[i] = (dy * (wq * weight)) @ dy.T
    return out


def loaded_mode_coefficients(n_modes):
    """The loaded-end modes of docs/beam.md on a unit length: c (n, n) with
    Y_j(t) = sum_i c_ij t^(i+2), and lam_j, from K c = lam M c with M_ij = 1 / (p_i + p_j + 1),
    K_ij = p_i (p_i - 1) p_j (p_j - 1) / (p_i + p_j - 3), p_i = i + 2; normalized to
    int_0^1 Y_j^2 = 1 (c^T M c = I) and Y_j(1) = sum_i c_ij > 0."""
    from scipy.linalg import eigh      # (when used: import dttmm stays light)
    p = np.arange(2, n_modes + 2, dtype=float)
    m = 1.0 / (p[:, None] + p[None, :] + 1.0)
    pp = p * (p - 1.0)
    k = np.outer(pp, pp) / (p[:, None] + p[None, :] - 3.0)
    lam, c = eigh(k, m)
    c = c / np.sqrt(np.einsum("ij,ik,kj->j", c, m, c))
    c = c * np.where(c.sum(axis=0) < 0.0, -1.0, 1.0)
    return c, lam


def _bending_shapes(length, family, n_modes, x):
    """(Y, Y') of one beam's bending shapes at the points x, each (n_modes, len(x)), by this
    module's own forms."""
    x = np.asarray(x, dtype=float)
    if family == PINNED:
        b = np.arange(1, n_modes + 1)[:, None] * math.pi / length
        return np.sin(b * x[None, :]), b * np.cos(b * x[None, :])
    if family == CLAMPED:
        y, dy, _ = clamped_shapes(length, n_modes, x)
        return y, dy
    c, _ = loaded_mode_coefficients(n_modes)
    p = np.arange(2, n_modes + 2, dtype=float)[:, None]
    t = (x / length)[None, :]
    return c.T @ t ** p, c.T @ (p * t ** (p - 1.0)) / length


def exact_foreshortening_table(beam_row, n_points=None):
    """One beam's sections at Gauss-Legendre points, for the exact foreshortening (newton_euler.py's
    docstring, "Geometric stiffening, exact"): a (n_points, 2 + m + m^2 + ma) array whose rows are
    [x, weight, Y_k(x) (m), D(x) = int_0^x Y' Y'^T (m x m, row-major), U_a(x) (ma)].  D(x) by
    polynomial moments for the loaded-end modes, else by a Gauss-Legendre rule of its own on
    [0, x]; quadrature_points(m + ma) points by default (the integrands are polynomials of degree
    up to 4 m + 4 for the loaded-end modes, and products of four trigonometric or hyperbolic shapes
    otherwise)."""
    length, nm, family = float(beam_row[LENGTH]), int(beam_row[MODES]), int(beam_row[FAMILY])
    ma = int(beam_row[AXIAL_MODES])
    nq = quadrature_points(nm + ma) if n_points is None else int(n_points)
    xg, wg = np.polynomial.legendre.leggauss(nq)
    x, wq = 0.5 * length * (xg + 1.0), 0.5 * length * wg
    table = np.zeros((nq, 2 + nm + nm * nm + ma))
    table[:, 0], table[:, 1] = x, wq
    table[:, 2:2 + nm] = _bending_shapes(length, family, nm, x)[0].T
    if family == CLAMPED_LOADED:
        # Y_j' = (1/L) sum_i c_ij p_i t^(p_i - 1): int_0^x Y_j' Y_k' = (1/L) c^T T(t) c with
        # T_il = p_i p_l t^(p_i + p_l - 1) / (p_i + p_l - 1), t = x / L
        c, _ = loaded_mode_coefficients(nm)
        p = np.arange(2, nm + 2, dtype=float)
        q = p[:, None] + p[None, :] - 1.0
        for g, t in enumerate(x / length):
            d = c.T @ (np.outer(p, p) * t ** q / q) @ c / length
            table[g, 2 + nm:2 + nm + nm * nm] = d.reshape(-1)
    else:
        ti, wi = np.polynomial.legendre.leggauss(nq)
        for g, xe in enumerate(x):
            dy = _bending_shapes(length, family, nm, 0.5 * xe * (ti + 1.0))[1]
            d = (dy * (0.5 * xe * wi)) @ dy.T
            table[g, 2 + nm:2 + nm + nm * nm] = d.reshape(-1)
    if ma:
        table[:, 2 + nm + nm * nm:] = shaft_shape_constants(length, family, ma, x)[1].T
    return table
