"""The reference's own strain-rod kinematics (docs/strain_rod.md), by another road than the
kernel's (kernels/transfers/strain_rod.py): the same Magnus step Omega(t) per station, but its
exponential and that exponential's first two time derivatives from one power series of 4 x 4
homogeneous matrices over truncated polynomials, no J_l and no closed forms.

Along the motion, X(t + s) = Omega^ + s Omega'^ + s^2/2 Omega''^ + O(s^3), and in the ring of
polynomials in s modulo s^3 (a triple (M0, M1, M2) is M0 + s M1 + s^2 M2; products
(A B)_k = sum_{i+j=k} A_i B_j) exp(X) = E + s E' + s^2/2 E'' + O(s^3): its Taylor series by
Horner's rule after scaling by 2^-j, then j squarings.  The stations' poses then follow
G_{a+1} = G_a E, G' = G'_a E + G_a E', G'' = G''_a E + 2 G'_a E' + G_a E'', and with G = (R, p)
the angular velocity omega = vee(R' R^T) and acceleration alpha = vee(R'' R^T) (R'' R^T's skew
part: d/dt (R' R^T) = R'' R^T + R' R'^T, the latter symmetric).
"""
import numba
import numpy as np

from ..kernels import CONTRACT

_SQRT3_12 = np.sqrt(3.0) / 12.0
_TAYLOR_TERMS = 16          # after scaling to norm < 1/2: remainder below 2^-16 / 16! ~ 1e-18


@numba.njit(cache=True, fastmath=CONTRACT)
def _jet_mul(a, b):
    out = np.zeros((3, 4, 4))
    out[0] = a[0] @ b[0]
    out[1] = a[0] @ b[1] + a[1] @ b[0]
    out[2] = a[0] @ b[2] + a[1] @ b[1] + a[2] @ b[0]
    return out


@numba.njit(cache=True, fastmath=CONTRACT)
def _jet_exp(x):
    """exp of the jet x (3, 4, 4): (E, E', E''/2) of exp(X(s))."""
    norm = np.abs(x[0]).sum(axis=1).max() + np.abs(x[1]).sum(axis=1).max() \
        + np.abs(x[2]).sum(axis=1).max()
    squarings = 0
    while norm > 0.5:
        norm *= 0.5
        squarings += 1
    y = x / 2.0 ** squarings
    out = np.zeros((3, 4, 4))
    out[0] = np.eye(4)
    for k in range(_TAYLOR_TERMS, 0, -1):        # exp(y) = I + y (I + y/2 (I + y/3 (...)))
        out = _jet_mul(y, out) / k
        out[0] += np.eye(4)
    for _ in range(squarings):
        out = _jet_mul(out, out)
    return out


@numba.njit(cache=True, fastmath=CONTRACT)
def _twist_matrix(xi):
    m = np.zeros((4, 4))
    m[0, 1], m[0, 2], m[1, 2] = -xi[2], xi[1], -xi[0]
    m[1, 0], m[2, 0], m[2, 1] = xi[2], -xi[1], xi[0]
    m[0, 3], m[1, 3], m[2, 3] = xi[3], xi[4], xi[5]
    return m


@numba.njit(cache=True, fastmath=CONTRACT)
def _matrix_bracket(a, b):
    return a @ b - b @ a


@numba.njit(cache=True, fastmath=CONTRACT)
def rod_sections(steps, xi0, phi, q, qd, qdd, rot, pos, omega, vel, alpha, acc):
    """The same outputs as kernels/transfers/strain_rod.py::rod_kinematics (stations 0 .. n in
    the input frame: rotation, centre, angular velocity, velocity, angular acceleration,
    acceleration), computed as the module's docstring says.  The Magnus step is written in
    4 x 4 matrices: Omega^ = h/2 (X_1 + X_2) + sqrt(3)/12 h^2 [X_1, X_2], X_i = xi_i^."""
    n = steps.shape[0]
    g = np.eye(4)
    g1 = np.zeros((4, 4))
    g2 = np.zeros((4, 4))
    for a in range(n + 1):
        if a > 0:
            h = steps[a - 1]
            k = _SQRT3_12 * h * h
            x1 = _twist_matrix(xi0[a - 1, 0] + phi[a - 1, 0] @ q)
            x2 = _twist_matrix(xi0[a - 1, 1] + phi[a - 1, 1] @ q)
            v1 = _twist_matrix(phi[a - 1, 0] @ qd)
            v2 = _twist_matrix(phi[a - 1, 1] @ qd)
            w1 = _twist_matrix(phi[a - 1, 0] @ qdd)
            w2 = _twist_matrix(phi[a - 1, 1] @ qdd)
            jet = np.zeros((3, 4, 4))
            jet[0] = 0.5 * h * (x1 + x2) + k * _matrix_bracket(x1, x2)
            jet[1] = 0.5 * h * (v1 + v2) + k * (_matrix_bracket(v1, x2) + _matrix_bracket(x1, v2))
            jet[2] = 0.5 * (0.5 * h * (w1 + w2) + k * (_matrix_bracket(w1, x2)
                                                        + 2.0 * _matrix_bracket(v1, v2)
                                                        + _matrix_bracket(x1, w2)))
            e = _jet_exp(jet)
            g, g1, g2 = g @ e[0], g1 @ e[0] + g @ e[1], g2 @ e[0] + 2.0 * g1 @ e[1] + 2.0 * g @ e[2]
        r, r1, r2 = g[:3, :3].copy(), g1[:3, :3].copy(), g2[:3, :3].copy()
        rot[a] = r
        pos[a] = g[:3, 3]
        vel[a] = g1[:3, 3]
        acc[a] = g2[:3, 3]
        rt = np.ascontiguousarray(r.T)
        w = r1 @ rt
        omega[a, 0], omega[a, 1], omega[a, 2] = w[2, 1], w[0, 2], w[1, 0]
        al = r2 @ rt
        alpha[a, 0] = 0.5 * (al[2, 1] - al[1, 2])
        alpha[a, 1] = 0.5 * (al[0, 2] - al[2, 0])
        alpha[a, 2] = 0.5 * (al[1, 0] - al[0, 1])
