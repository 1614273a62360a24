"""Small pure kernels of the reference: 3-vectors and 3 x 3 matrices from rows, rotations,
SO(3)'s exponential, logarithm and left Jacobian with its derivative."""
import math

import numpy as np

from ..kernels import kernel
from ..kernels.algebra.mat3 import matmul, matvec


@kernel
def _mat3(row, start):
    m = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            m[i, j] = row[start + 3 * i + j]
    return m


@kernel
def _vec3(row, start):
    v = np.empty(3)
    for i in range(3):
        v[i] = row[start + i]
    return v


@kernel
def _cross(a, b):
    c = np.empty(3)
    c[0] = a[1] * b[2] - a[2] * b[1]
    c[1] = a[2] * b[0] - a[0] * b[2]
    c[2] = a[0] * b[1] - a[1] * b[0]
    return c


@kernel
def _hat(v):
    m = np.zeros((3, 3))
    m[0, 1] = -v[2]
    m[0, 2] = v[1]
    m[1, 0] = v[2]
    m[1, 2] = -v[0]
    m[2, 0] = -v[1]
    m[2, 1] = v[0]
    return m


@kernel
def _quat_to_rot(q):
    """Rotation matrix of the quaternion [w, x, y, z], normalised first."""
    s = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    w, x, y, z = q[0] / s, q[1] / s, q[2] / s, q[3] / s
    r = np.empty((3, 3))
    r[0, 0] = 1.0 - 2.0 * (y * y + z * z)
    r[0, 1] = 2.0 * (x * y - w * z)
    r[0, 2] = 2.0 * (x * z + w * y)
    r[1, 0] = 2.0 * (x * y + w * z)
    r[1, 1] = 1.0 - 2.0 * (x * x + z * z)
    r[1, 2] = 2.0 * (y * z - w * x)
    r[2, 0] = 2.0 * (x * z - w * y)
    r[2, 1] = 2.0 * (y * z + w * x)
    r[2, 2] = 1.0 - 2.0 * (x * x + y * y)
    return r


@kernel
def _log_rot(r):
    """Rotation vector psi with expm(hat(psi)) = r, |psi| <= pi; robust at every angle (it goes
    through the quaternion of r, largest component first)."""
    tr = r[0, 0] + r[1, 1] + r[2, 2]
    diag_max = max(r[0, 0], r[1, 1], r[2, 2])
    if tr >= diag_max:
        s = 2.0 * math.sqrt(1.0 + tr)
        w = 0.25 * s
        x = (r[2, 1] - r[1, 2]) / s
        y = (r[0, 2] - r[2, 0]) / s
        z = (r[1, 0] - r[0, 1]) / s
    elif r[0, 0] == diag_max:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        w = (r[2, 1] - r[1, 2]) / s
        x = 0.25 * s
        y = (r[0, 1] + r[1, 0]) / s
        z = (r[0, 2] + r[2, 0]) / s
    elif r[1, 1] == diag_max:
        s = 2.0 * math.sqrt(1.0 - r[0, 0] + r[1, 1] - r[2, 2])
        w = (r[0, 2] - r[2, 0]) / s
        x = (r[0, 1] + r[1, 0]) / s
        y = 0.25 * s
        z = (r[1, 2] + r[2, 1]) / s
    else:
        s = 2.0 * math.sqrt(1.0 - r[0, 0] - r[1, 1] + r[2, 2])
        w = (r[1, 0] - r[0, 1]) / s
        x = (r[0, 2] + r[2, 0]) / s
        y = (r[1, 2] + r[2, 1]) / s
        z = 0.25 * s
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    sv = math.sqrt(x * x + y * y + z * z)
    psi = np.empty(3)
    if sv < 1e-12:
        f = 2.0 / w              # angle / sin(angle / 2) -> 2 as angle -> 0
    else:
        f = 2.0 * math.atan2(sv, w) / sv
    psi[0] = f * x
    psi[1] = f * y
    psi[2] = f * z
    return psi


@kernel
def _so3_coefficients(t):
    """Coefficients of exp and of the left Jacobian at the rotation vector t, p = |t|:
    c = sin p / p, a = (1 - cos p)/p^2, b = (p - sin p)/p^3 and a1 = a'(p)/p, b1 = b'(p)/p
    (all even in p).  Taylor series for p < 2 (16 terms, alternating with terms below 2: exact
    to rounding there), closed forms beyond (where they cancel no more than a digit)."""
    p2 = t[0] * t[0] + t[1] * t[1] + t[2] * t[2]
    if p2 < 4.0:
        # c = sum (-1)^n p^2n / (2n+1)!, a = sum (-1)^n p^2n / (2n+2)!,
        # b = sum (-1)^n p^2n / (2n+3)!, a1 = sum_{n>=1} (-1)^n 2n p^(2n-2) / (2n+2)!,
        # b1 = sum_{n>=1} (-1)^n 2n p^(2n-2) / (2n+3)!
        c = a = b = a1 = b1 = 0.0
        pw = 1.0                     # (-1)^n p^2n
        q = -1.0                     # (-1)^n p^(2n-2), from n = 1 on
        f1 = 1.0                     # (2n+1)!
        for n in range(16):
            f2 = f1 * (2 * n + 2)    # (2n+2)!
            f3 = f2 * (2 * n + 3)    # (2n+3)!
            c += pw / f1
            a += pw / f2
            b += pw / f3
            if n >= 1:
                a1 += 2.0 * n * q / f2
                b1 += 2.0 * n * q / f3
                q = -q * p2
            pw = -pw * p2
            f1 = f3                  # (2(n+1)+1)! = (2n+3)!
    else:
        p = math.sqrt(p2)
        sp, cp = math.sin(p), math.cos(p)
        c = sp / p
        a = (1.0 - cp) / p2
        b = (p - sp) / (p2 * p)
        a1 = (p * sp - 2.0 * (1.0 - cp)) / (p2 * p2)
        b1 = (1.0 - cp) / (p2 * p2) - 3.0 * (p - sp) / (p2 * p2 * p)
    return c, a, b, a1, b1


@kernel
def _expm(t):
    """exp(t^), Rodrigues' formula."""
    c, a, _, _, _ = _so3_coefficients(t)
    th = _hat(t)
    e = np.eye(3) + c * th + a * matmul(th, th)
    return e


@kernel
def _left_jacobian(t):
    """J_l(t) = I + a t^ + b t^ t^: exp((t + d)^) = exp((J_l d)^) exp(t^) to first order."""
    _, a, b, _, _ = _so3_coefficients(t)
    th = _hat(t)
    return np.eye(3) + a * th + b * matmul(th, th)


@kernel
def _left_jacobian_derivative(t, u):
    """dJ_l[u] = d/ds J_l(t + s u) at s = 0 = (t.u) (a1 t^ + b1 t^ t^) + a u^ + b (u^ t^ + t^ u^),
    since d p / ds = (t.u) / p and a'(p) dp/ds = a1 (t.u)."""
    _, a, b, a1, b1 = _so3_coefficients(t)
    th = _hat(t)
    uh = _hat(u)
    tu = t[0] * u[0] + t[1] * u[1] + t[2] * u[2]
    return tu * (a1 * th + b1 * matmul(th, th)) + a * uh + b * (matmul(uh, th) + matmul(th, uh))


@kernel
def _end_section_rate(t, t_dot, t_ddot):
    """d/dt [J_l(t) t'] = J_l(t) t'' + dJ_l[t'] t' (body frame), for tests and the kernels."""
    return (matvec(_left_jacobian(t), t_ddot)
            + matvec(_left_jacobian_derivative(t, t_dot), t_dot))
