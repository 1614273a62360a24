"""The end sections and output points of beams and strain rods from their frames and
coordinates (docs/beam.md, "End sections"; docs/strain_rod.md), and a beam's foreshortening
along its length: what the model's builder, the closing joints, the results and the figures
all read, below each of them."""
import numpy as np

from ..elements import BEAM, ROD
from ..elements.kinds import unimplemented_body_kind
from ..elements.beam import (FAMILY, LENGTH, MODES, TORSION_MODES, end_shapes, foreshortening,
                             slope_grams, stretch_along)
from ..elements.rigid_body import TO_MASS_CENTER, TO_OUTPUT
from .rod_motion import rod_end_section, rod_output_offset
from ..kernels.algebra.so3 import expm_so3, left_jacobian
from ..vectors import cross, rows_dot


# Gauss-Legendre rule for the beam integrals in results/result.py::chain_energies (and
# foreshortening_along's): 64 points on [0, L] integrate the products of sin(j pi x / L),
# sin(k pi x / L) (j, k <= 10) times x^2 to ~1e-16 relative (tests/test_reference_beam.py
# checks it against the closed forms).
_GL_X, _GL_W = np.polynomial.legendre.leggauss(64)


def output_section(beam_row, rotation, omega, eta=None, eta_dot=None):
    """Rotation and world angular velocity of a body's output section: the body's own for a
    rigid body; for a beam A_O = A exp(theta_O^), theta_O = [psi(L), -w'(L), v'(L)], and
    w_O = w + A J_l(theta_O) theta_O' (docs/beam.md, "End sections")."""
    m, mt = int(beam_row[MODES]), int(beam_row[TORSION_MODES])
    if m == 0 or eta is None:
        return rotation, omega
    eta_dot = np.zeros(2 * m + mt) if eta_dot is None else eta_dot
    family, length = int(beam_row[FAMILY]), beam_row[LENGTH]
    slope, twist = end_shapes(family, float(length), m, mt)[1:]

    def angles(e):
        return np.array([twist @ e[2 * m:2 * m + mt], -slope @ e[m:2 * m], slope @ e[:m]])
    theta, theta_dot = angles(eta), angles(eta_dot)
    e, jl = np.empty((3, 3)), np.empty((3, 3))
    expm_so3(theta, e)
    left_jacobian(theta, jl)
    return rotation @ e, omega + rotation @ jl @ theta_dot


def log_rotation(r):
    """Rotation vector of r, through the quaternion (accurate at every angle)."""
    w, x, y, z = rotation_to_quaternion(r)
    s = np.sqrt(x * x + y * y + z * z)
    return 2.0 * np.arctan2(s, w) / s * np.array([x, y, z]) if s > 1e-300 else np.zeros(3)


def foreshortening_along(row, points, eta, eta_dot):
    """c(x) = 1/2 int_0^x (v'^2 + w'^2) dxi and its rate at each of the points, (T, points),
    for T states of one beam: each by a Gauss-Legendre rule of its own on [0, x]."""
    nm = int(row[MODES])
    grams = slope_grams(int(row[FAMILY]), row[LENGTH], nm, points, len(_GL_X))
    c, c_dot = np.zeros((len(eta), len(points))), np.zeros((len(eta), len(points)))
    for plane in range(2):          # c = 1/2 eta^T D(x) eta, c' = eta^T D(x) eta' per plane
        e, e_dot = eta[:, plane * nm:(plane + 1) * nm], eta_dot[:, plane * nm:(plane + 1) * nm]
        c += 0.5 * np.einsum("tj,ijk,tk->ti", e, grams, e)
        c_dot += np.einsum("tj,ijk,tk->ti", e, grams, e_dot)
    return c, c_dot


def beam_output_offset(row, rotation, omega, eta, eta_dot):
    """World offset r_O - r_I = A ((L - c(L)) e1 + u(L)) of a beam's output point and its rate
    w x (r_O - r_I) + A (u'(L) - c'(L) e1) (docs/beam.md, "End sections"; c(L) the
    foreshortening, "Geometric stiffening", zero without it; u(L) with the stretch u_x(L),
    "Stretch"); any leading axes (T states)."""
    length, nm = row[LENGTH], int(row[MODES])
    y = end_shapes(int(row[FAMILY]), float(length), nm, 0)[0]
    eta, eta_dot = np.asarray(eta, dtype=float), np.asarray(eta_dot, dtype=float)
    c, c_dot = foreshortening(row, eta, eta_dot)
    u_l, u_l_dot = (stretch_along(row, e, [length])[..., 0] for e in (eta, eta_dot))
    p = np.stack([length - c + u_l, rows_dot(eta[..., :nm], y),
                  rows_dot(eta[..., nm:2 * nm], y)], axis=-1)
    p_dot = np.stack([u_l_dot - c_dot, rows_dot(eta_dot[..., :nm], y),
                      rows_dot(eta_dot[..., nm:2 * nm], y)], axis=-1)
    rho = np.einsum("...ij,...j->...i", rotation, p)
    return rho, cross(omega, rho) + np.einsum("...ij,...j->...i", rotation, p_dot)


def element_output_offset(model, k, rotation, omega, eta, eta_dot):
    """(rho, rho'): a beam's or strain rod's output point from its input point and its rate,
    world (beam_output_offset, elements/strain_rod.py::rod_output_offset), for one state
    (rotation (3, 3)) or T states (T, 3, 3); shaped (..., 3) as rotation's leading axes."""
    if model.body_kind[k] == ROD:
        rho, rate = rod_output_offset(model.rod_params[k], rotation, omega, eta, eta_dot)
    elif model.body_kind[k] == BEAM:
        rho, rate = beam_output_offset(model.beam_params[k], rotation, omega, eta, eta_dot)
    else:
        raise unimplemented_body_kind(model.body_kind[k], f"body '{model.body_names[k]}'",
                                      "element_output_offset (model/sections.py)")
    shape = np.shape(rotation)[:-1]
    return np.reshape(rho, shape), np.reshape(rate, shape)


def element_end_section(model, k, rotation, omega, eta, eta_dot):
    """(A_O, w_O) of a beam's or strain rod's output end section, one state (model.
    output_section, elements/strain_rod.py::rod_end_section)."""
    if model.body_kind[k] == ROD:
        return rod_end_section(model.rod_params[k], rotation, omega, eta, eta_dot)[1:]
    if model.body_kind[k] == BEAM:
        return output_section(model.beam_params[k], rotation, omega, eta, eta_dot)
    raise unimplemented_body_kind(model.body_kind[k], f"body '{model.body_names[k]}'",
                                  "element_end_section (model/sections.py)")


def rotation_to_quaternion(rot):
    rot = np.asarray(rot)
    shape = rot.shape[:-2]
    r = rot.reshape(-1, 3, 3)
    q = np.empty((len(r), 4))
    for i, m in enumerate(r):
        tr = m[0, 0] + m[1, 1] + m[2, 2]
        k = np.argmax([tr, m[0, 0], m[1, 1], m[2, 2]])
        if k == 0:
            s = 2.0 * np.sqrt(1.0 + tr)
            q[i] = [0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s,
                    (m[1, 0] - m[0, 1]) / s]
        elif k == 1:
            s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
            q[i] = [(m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s,
                    (m[0, 2] + m[2, 0]) / s]
        elif k == 2:
            s = 2.0 * np.sqrt(1.0 - m[0, 0] + m[1, 1] - m[2, 2])
            q[i] = [(m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s,
                    (m[1, 2] + m[2, 1]) / s]
        else:
            s = 2.0 * np.sqrt(1.0 - m[0, 0] - m[1, 1] + m[2, 2])
            q[i] = [(m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s,
                    0.25 * s]
        if q[i, 0] < 0:
            q[i] = -q[i]
    return q.reshape(shape + (4,))


def point_positions(model, rotation, r_in, eta=None):
    """Mass-centre and output-point positions from input points and rotations ((T, n, ...) or
    (n, ...) arrays); eta (T, total modes) or (total modes,) moves the beams' and strain rods'
    output points."""
    p = model.body_params
    r_c = r_in + np.einsum("...ij,...j->...i", rotation, p[:, TO_MASS_CENTER])
    r_o = r_in + np.einsum("...ij,...j->...i", rotation, p[:, TO_OUTPUT])
    flexible = np.nonzero((model.body_kind == BEAM) | (model.body_kind == ROD))[0]
    if eta is not None and len(flexible):
        eta = np.asarray(eta, dtype=float)
        offsets = model.mode_offsets
        for k in flexible:
            e = eta[..., offsets[k]:offsets[k + 1]]
            rho, _ = element_output_offset(model, k, rotation[..., k, :, :],
                                           np.zeros(e.shape[:-1] + (3,)), e, np.zeros_like(e))
            r_o[..., k, :] = r_in[..., k, :] + rho
    return r_c, r_o
