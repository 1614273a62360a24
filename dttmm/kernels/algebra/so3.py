"""Rotation kernels: hat map, exponential, logarithm and left Jacobian of SO(3)
(docs/conventions.md).

exp and J_l take their coefficients from series below |phi| = 1e-2: a step's rotation increment
is ~1e-4 rad, where the closed forms cost a square root, a sine and a cosine and lose digits
((1 - cos t) / t^2 carries a relative error ~eps / t^2, 1e-8 at t = 1e-4).  Four terms leave a
remainder below t^8 / 9! < 3e-22 there."""
import numpy as np
from numba import njit

from .. import CONTRACT, kernel

SERIES_BELOW = 1e-4       # |phi|^2 below which exp and J_l use their series (docstring)


@kernel(entry=True)
def hat(v, out):
    """out = v^ (the cross-product matrix: v^ w = v x w)."""
    out[0, 0] = 0.0
    out[0, 1] = -v[2]
    out[0, 2] = v[1]
    out[1, 0] = v[2]
    out[1, 1] = 0.0
    out[1, 2] = -v[0]
    out[2, 0] = -v[1]
    out[2, 1] = v[0]
    out[2, 2] = 0.0


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _identity_plus(a, b, phi, th2, out):
    """out = I + a phi^ + b phi^ phi^, with phi^ phi^ = phi phi^T - |phi|^2 I (th2 = |phi|^2),
    in scalars (it runs for every body and step)."""
    for i in range(3):
        for j in range(3):
            out[i, j] = b * phi[i] * phi[j]
        out[i, i] += 1.0 - b * th2
    out[0, 1] -= a * phi[2]
    out[0, 2] += a * phi[1]
    out[1, 0] += a * phi[2]
    out[1, 2] -= a * phi[0]
    out[2, 0] -= a * phi[1]
    out[2, 1] += a * phi[0]


@njit(cache=True, inline='always', fastmath=CONTRACT)
def expm_so3(phi, out):
    """out = exp(phi^), Rodrigues' formula (series below |phi| = 1e-2)."""
    th2 = phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]
    a, b = exp_coefficients(th2)
    _identity_plus(a, b, phi, th2, out)


@kernel
def exp_coefficients(th2):
    """(sin t / t, (1 - cos t) / t^2) at t^2 = th2, exp(phi^) = I + a phi^ + b phi^ phi^ (their
    series below th2 = SERIES_BELOW)."""
    if th2 < SERIES_BELOW:
        return (1.0 - th2 / 6.0 * (1.0 - th2 / 20.0 * (1.0 - th2 / 42.0)),
                0.5 - th2 / 24.0 * (1.0 - th2 / 30.0 * (1.0 - th2 / 56.0)))
    th = np.sqrt(th2)
    return np.sin(th) / th, (1.0 - np.cos(th)) / th2


@njit(cache=True, inline='always', fastmath=CONTRACT)
def left_jacobian(phi, out):
    """out = J_l(phi) = I + (1-cos t)/t^2 phi^ + (t - sin t)/t^3 phi^^, so that
    exp((phi + dphi)^) = exp((J_l dphi)^) exp(phi^) to first order."""
    th2 = phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]
    if th2 < SERIES_BELOW:
        b = 0.5 - th2 / 24.0 * (1.0 - th2 / 30.0 * (1.0 - th2 / 56.0))
        c = 1.0 / 6.0 - th2 / 120.0 * (1.0 - th2 / 42.0 * (1.0 - th2 / 72.0))
    else:
        th = np.sqrt(th2)
        b = (1.0 - np.cos(th)) / th2
        c = (th - np.sin(th)) / (th2 * th)
    _identity_plus(b, c, phi, th2, out)


@kernel
def left_jacobian_derivative(phi, delta, out):
    """out = D J_l(phi)[delta], the derivative of J_l along delta (docs/beam.md, "The end
    moment's columns"): with J_l = I + b phi^ + c phi^^, b = (1 - cos t)/t^2,
    c = (t - sin t)/t^3, t = |phi|, and beta = b'(t)/t, gamma = c'(t)/t,
      D = b delta^ + c (delta^ phi^ + phi^ delta^) + (phi . delta) (beta phi^ + gamma phi^^),
    delta^ phi^ = phi delta^T - (phi . delta) I.  Series below t^2 = 1e-2 (four terms; the
    closed forms of beta and gamma lose eps / t^4 to cancellation)."""
    th2 = phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]
    if th2 < 1e-2:
        b = 0.5 - th2 / 24.0 * (1.0 - th2 / 30.0 * (1.0 - th2 / 56.0))
        c = 1.0 / 6.0 - th2 / 120.0 * (1.0 - th2 / 42.0 * (1.0 - th2 / 72.0))
        beta = -1.0 / 12.0 + th2 / 180.0 - th2 * th2 / 6720.0 + th2 * th2 * th2 / 453600.0
        gamma = -1.0 / 60.0 + th2 / 1260.0 - th2 * th2 / 60480.0 + th2 * th2 * th2 / 4989600.0
    else:
        th = np.sqrt(th2)
        cos_t, sin_t = np.cos(th), np.sin(th)
        b = (1.0 - cos_t) / th2
        c = (th - sin_t) / (th2 * th)
        beta = (th * sin_t - 2.0 * (1.0 - cos_t)) / (th2 * th2)
        gamma = (1.0 - cos_t) / (th2 * th2) - 3.0 * (th - sin_t) / (th2 * th2 * th)
    pd = phi[0] * delta[0] + phi[1] * delta[1] + phi[2] * delta[2]
    g = pd * gamma
    for i in range(3):
        for j in range(3):
            out[i, j] = c * (phi[i] * delta[j] + delta[i] * phi[j]) + g * phi[i] * phi[j]
        out[i, i] -= 2.0 * c * pd + g * th2
    v0 = b * delta[0] + pd * beta * phi[0]
    v1 = b * delta[1] + pd * beta * phi[1]
    v2 = b * delta[2] + pd * beta * phi[2]
    out[0, 1] -= v2
    out[0, 2] += v1
    out[1, 0] += v2
    out[1, 2] -= v0
    out[2, 0] -= v1
    out[2, 1] += v0


@kernel(entry=True)
def log_so3(r, out):
    """out = the rotation vector of r (angle in [0, pi))."""
    c = 0.5 * (r[0, 0] + r[1, 1] + r[2, 2] - 1.0)
    c = min(1.0, max(-1.0, c))
    th = np.arccos(c)
    w0 = r[2, 1] - r[1, 2]
    w1 = r[0, 2] - r[2, 0]
    w2 = r[1, 0] - r[0, 1]
    if th < 1e-6:
        f = 0.5 + th * th / 12.0
    else:
        f = th / (2.0 * np.sin(th))
    out[0] = f * w0
    out[1] = f * w1
    out[2] = f * w2


@kernel
def cayley(phi, out):
    """out = cay(phi) = (I - phi^/2)^-1 (I + phi^/2) = I + 4/(4 + |phi|^2) (phi^ + phi^^/2):
    the rotation by 2 atan(|phi|/2) about phi (docs/solver.md, energy-momentum scheme)."""
    f = 4.0 / (4.0 + phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2])
    k = np.empty((3, 3))
    hat(phi, k)
    for i in range(3):
        for j in range(3):
            kk = k[i, 0] * k[0, j] + k[i, 1] * k[1, j] + k[i, 2] * k[2, j]
            out[i, j] = f * (k[i, j] + 0.5 * kk)
        out[i, i] += 1.0


@kernel
def cayley_tangent(phi, out):
    """out = D(phi) = 4/(4 + |phi|^2) (I + phi^/2), so that
    cay(phi + dphi) = cay((D dphi)^) cay(phi) to first order."""
    f = 4.0 / (4.0 + phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2])
    hat(phi, out)
    for i in range(3):
        for j in range(3):
            out[i, j] *= 0.5 * f
        out[i, i] += f


@kernel
def cayley_log(r, out):
    """out = the Cayley vector phi of r (cay(phi) = r): 2 vee(r - r^T) / (1 + tr r); rotations
    by less than pi."""
    f = 2.0 / (1.0 + r[0, 0] + r[1, 1] + r[2, 2])
    out[0] = f * (r[2, 1] - r[1, 2])
    out[1] = f * (r[0, 2] - r[2, 0])
    out[2] = f * (r[1, 0] - r[0, 1])
