"""Small dense algebra by loops: the sweeps and the step invert and multiply many 3 x 3 (and
3 x 13, 6 x 7) matrices, where a BLAS or LAPACK call costs more in its overhead than in its
arithmetic."""
import numpy as np
from numba import njit

from .. import CONTRACT, kernel


# Copies and sums into existing arrays (same shapes), as calls of small kernels.  Written as an
# array statement (`out[:] = x`, `s[k] = s[j]`, `h[:, :] = -g`), numba compiles its broadcasting
# setitem in place, with a shape check whose error message it formats in compiled code: ~0.5 s
# each in a step piece, and the first one of each kind in a process compiled that string
# formatting, 6.5 s of the four-bar's cold compile for one line (docs/solver.md, "Compile time",
# items 3 and 8).

@kernel
def put1(dst, src):
    """dst[:] = src."""
    for i in range(dst.shape[0]):
        dst[i] = src[i]


@kernel
def put2(dst, src):
    """dst[:, :] = src."""
    for i in range(dst.shape[0]):
        for j in range(dst.shape[1]):
            dst[i, j] = src[i, j]


@kernel
def put3(dst, src):
    """dst[:, :, :] = src."""
    for i in range(dst.shape[0]):
        for j in range(dst.shape[1]):
            for k in range(dst.shape[2]):
                dst[i, j, k] = src[i, j, k]


@kernel
def add1(dst, src):
    """dst[:] += src."""
    for i in range(dst.shape[0]):
        dst[i] += src[i]


@kernel
def add2(dst, src):
    """dst[:, :] += src."""
    for i in range(dst.shape[0]):
        for j in range(dst.shape[1]):
            dst[i, j] += src[i, j]


@kernel
def neg2(dst, src):
    """dst[:, :] = -src."""
    for i in range(dst.shape[0]):
        for j in range(dst.shape[1]):
            dst[i, j] = -src[i, j]


@njit(cache=True, inline='always', fastmath=CONTRACT)
def inv3(a, out):
    """out = a^-1 (t_inverse, written to an array); returns the determinant (out is not finite
    when it is 0)."""
    det, inv = t_inverse(t_of_mat(a))
    for i in range(3):
        for j in range(3):
            out[i, j] = inv[3 * i + j]
    return det


@njit(cache=True, inline='always', fastmath=CONTRACT)
def mm3_into(a, b, out):
    """out = a @ b for 3 x 3 blocks (their first three rows and columns; the size fixed, so the
    loops unroll: matmul_into's follow the arrays' shapes)."""
    for i in range(3):
        a0, a1, a2 = a[i, 0], a[i, 1], a[i, 2]
        for j in range(3):
            out[i, j] = a0 * b[0, j] + a1 * b[1, j] + a2 * b[2, j]


@njit(cache=True, inline='always', fastmath=CONTRACT)
def matmul_into(a, b, out):
    """out = a @ b by loops (small matrices: BLAS's call overhead dominates at these sizes)."""
    for i in range(a.shape[0]):
        for j in range(b.shape[1]):
            s = 0.0
            for k in range(a.shape[1]):
                s += a[i, k] * b[k, j]
            out[i, j] = s


@kernel
def matvec_into(a, x, out):
    """out = a @ x by loops."""
    for i in range(a.shape[0]):
        s = 0.0
        for k in range(a.shape[1]):
            s += a[i, k] * x[k]
        out[i] = s


# Products that return a new array, for kernels that allocate (the reference's; the sweeps'
# small blocks, which may be strided views).  numba compiles `a @ b` as a BLAS call and a new
# array: at 3 x 3 about 220 ns a product against 40 ns by these loops (measured in a compiled
# loop); the reference's right-hand side went from 55 to 40 us (docs/reference.md).  Compile
# time is the same either way (the reference's kernels 168 and 165 s cold, side by side).

@kernel(entry=True)
def matmul(a, b):
    """a @ b (2-D, any layouts)."""
    out = np.empty((a.shape[0], b.shape[1]))
    matmul_into(a, b, out)
    return out


@kernel(entry=True)
def matvec(a, x):
    """a @ x (a 2-D, x 1-D)."""
    out = np.empty(a.shape[0])
    matvec_into(a, x, out)
    return out


@kernel(entry=True)
def dot(x, y):
    """x @ y (1-D)."""
    s = 0.0
    for i in range(x.shape[0]):
        s += x[i] * y[i]
    return s


@kernel
def hat_mul(v, b, out):
    """out = v^ @ b (3 x 3): column j is v x b[:, j]."""
    for j in range(3):
        b0, b1, b2 = b[0, j], b[1, j], b[2, j]
        out[0, j] = v[1] * b2 - v[2] * b1
        out[1, j] = v[2] * b0 - v[0] * b2
        out[2, j] = v[0] * b1 - v[1] * b0


@kernel
def mul_hat(a, v, out):
    """out = a @ v^ (3 x 3): row i is a[i] x v."""
    for i in range(3):
        a0, a1, a2 = a[i, 0], a[i, 1], a[i, 2]
        out[i, 0] = a1 * v[2] - a2 * v[1]
        out[i, 1] = a2 * v[0] - a0 * v[2]
        out[i, 2] = a0 * v[1] - a1 * v[0]


# --------------------------------------------------------------------------------------------
# The same algebra on values: 3-vectors as 3-tuples, 3 x 3 matrices as row-major 9-tuples.
# A kernel written with these keeps its intermediates in registers (no scratch arrays that the
# compiler must assume may alias each other); used by kernels/stepping/ball_chain.py::ball_body_map.
# --------------------------------------------------------------------------------------------
@kernel
def t_of_mat(a):
    """A 3 x 3 array as a 9-tuple."""
    return (a[0, 0], a[0, 1], a[0, 2], a[1, 0], a[1, 1], a[1, 2], a[2, 0], a[2, 1], a[2, 2])


@kernel
def t_of_vec(x):
    """A 3-array as a 3-tuple."""
    return (x[0], x[1], x[2])


@kernel
def t_mm(a, b):
    """a @ b."""
    return (a[0] * b[0] + a[1] * b[3] + a[2] * b[6], a[0] * b[1] + a[1] * b[4] + a[2] * b[7],
            a[0] * b[2] + a[1] * b[5] + a[2] * b[8], a[3] * b[0] + a[4] * b[3] + a[5] * b[6],
            a[3] * b[1] + a[4] * b[4] + a[5] * b[7], a[3] * b[2] + a[4] * b[5] + a[5] * b[8],
            a[6] * b[0] + a[7] * b[3] + a[8] * b[6], a[6] * b[1] + a[7] * b[4] + a[8] * b[7],
            a[6] * b[2] + a[7] * b[5] + a[8] * b[8])


@kernel
def t_mmt(a, b):
    """a @ b^T."""
    return (a[0] * b[0] + a[1] * b[1] + a[2] * b[2], a[0] * b[3] + a[1] * b[4] + a[2] * b[5],
            a[0] * b[6] + a[1] * b[7] + a[2] * b[8], a[3] * b[0] + a[4] * b[1] + a[5] * b[2],
            a[3] * b[3] + a[4] * b[4] + a[5] * b[5], a[3] * b[6] + a[4] * b[7] + a[5] * b[8],
            a[6] * b[0] + a[7] * b[1] + a[8] * b[2], a[6] * b[3] + a[7] * b[4] + a[8] * b[5],
            a[6] * b[6] + a[7] * b[7] + a[8] * b[8])


@kernel
def t_mv(a, x):
    """a @ x."""
    return (a[0] * x[0] + a[1] * x[1] + a[2] * x[2], a[3] * x[0] + a[4] * x[1] + a[5] * x[2],
            a[6] * x[0] + a[7] * x[1] + a[8] * x[2])


@kernel
def t_cross(x, y):
    """x x y."""
    return (x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0])


@kernel
def t_hat_mul(v, b):
    """v^ @ b: column j is v x b[:, j]."""
    return (v[1] * b[6] - v[2] * b[3], v[1] * b[7] - v[2] * b[4], v[1] * b[8] - v[2] * b[5],
            v[2] * b[0] - v[0] * b[6], v[2] * b[1] - v[0] * b[7], v[2] * b[2] - v[0] * b[8],
            v[0] * b[3] - v[1] * b[0], v[0] * b[4] - v[1] * b[1], v[0] * b[5] - v[1] * b[2])


@kernel
def t_mul_hat(a, v):
    """a @ v^: row i is a[i] x v."""
    return (a[1] * v[2] - a[2] * v[1], a[2] * v[0] - a[0] * v[2], a[0] * v[1] - a[1] * v[0],
            a[4] * v[2] - a[5] * v[1], a[5] * v[0] - a[3] * v[2], a[3] * v[1] - a[4] * v[0],
            a[7] * v[2] - a[8] * v[1], a[8] * v[0] - a[6] * v[2], a[6] * v[1] - a[7] * v[0])


@kernel
def t_hat(v):
    """v^ (v^ x = v x x)."""
    return (0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0)


@kernel
def t_outer(x, y):
    """x y^T."""
    return (x[0] * y[0], x[0] * y[1], x[0] * y[2], x[1] * y[0], x[1] * y[1], x[1] * y[2],
            x[2] * y[0], x[2] * y[1], x[2] * y[2])


@kernel
def t_lin3(a, x, b, y):
    """a x + b y (3-tuples)."""
    return (a * x[0] + b * y[0], a * x[1] + b * y[1], a * x[2] + b * y[2])


@kernel
def t_lin9(a, x, b, y):
    """a x + b y (9-tuples)."""
    return (a * x[0] + b * y[0], a * x[1] + b * y[1], a * x[2] + b * y[2],
            a * x[3] + b * y[3], a * x[4] + b * y[4], a * x[5] + b * y[5],
            a * x[6] + b * y[6], a * x[7] + b * y[7], a * x[8] + b * y[8])


@kernel
def t_scale9(a, x):
    """a x (9-tuple)."""
    return (a * x[0], a * x[1], a * x[2], a * x[3], a * x[4], a * x[5], a * x[6], a * x[7],
            a * x[8])


@kernel
def t_plus_diag(a, c):
    """a + c E."""
    return (a[0] + c, a[1], a[2], a[3], a[4] + c, a[5], a[6], a[7], a[8] + c)


@kernel
def t_inverse(a):
    """(det a, a^-1) by the adjugate (the inverse is not finite when det a = 0)."""
    c00 = a[4] * a[8] - a[5] * a[7]
    c01 = a[5] * a[6] - a[3] * a[8]
    c02 = a[3] * a[7] - a[4] * a[6]
    det = a[0] * c00 + a[1] * c01 + a[2] * c02
    f = 1.0 / det if det != 0.0 else np.inf
    return det, (c00 * f, (a[2] * a[7] - a[1] * a[8]) * f, (a[1] * a[5] - a[2] * a[4]) * f,
                 c01 * f, (a[0] * a[8] - a[2] * a[6]) * f, (a[2] * a[3] - a[0] * a[5]) * f,
                 c02 * f, (a[1] * a[6] - a[0] * a[7]) * f, (a[0] * a[4] - a[1] * a[3]) * f)


@kernel
def least_norm_solve3(a, b, rcond):
    """The least-norm least-squares solution of a x = b (3 x 3), as np.linalg.pinv(a, rcond) @ b
    but without allocating: by a one-sided Jacobi SVD (Hestenes), whose singular values are
    accurate to rounding relative to the largest (those of a^T a would square the relative
    error).  Columns p, q of u = a v are rotated until orthogonal (_jacobi_rotation, the pairs
    (0, 1), (0, 2), (1, 2) in turn); then a = u v^T with u's columns sigma_j u_j, and
    x = sum over sigma_j > rcond sigma_max of v_j (u_j . b) / sigma_j.  The columns are 3-tuples
    named apiece, not a 9-tuple indexed by the pair: numba typed each runtime index into a tuple
    as a branch per entry, and the kernel took 7.4 s of the three-pendulum's cold compile
    (under 2 s so)."""
    u0 = (a[0, 0], a[1, 0], a[2, 0])
    u1 = (a[0, 1], a[1, 1], a[2, 1])
    u2 = (a[0, 2], a[1, 2], a[2, 2])
    v0, v1, v2 = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
    for _ in range(30):
        u0, u1, v0, v1, rotated01 = _jacobi_rotation(u0, u1, v0, v1)
        u0, u2, v0, v2, rotated02 = _jacobi_rotation(u0, u2, v0, v2)
        u1, u2, v1, v2, rotated12 = _jacobi_rotation(u1, u2, v1, v2)
        if not (rotated01 or rotated02 or rotated12):
            break
    sigma0 = np.sqrt(u0[0] * u0[0] + u0[1] * u0[1] + u0[2] * u0[2])
    sigma1 = np.sqrt(u1[0] * u1[0] + u1[1] * u1[1] + u1[2] * u1[2])
    sigma2 = np.sqrt(u2[0] * u2[0] + u2[1] * u2[1] + u2[2] * u2[2])
    cutoff = rcond * max(sigma0, sigma1, sigma2)
    x = _add_singular_term((0.0, 0.0, 0.0), u0, v0, sigma0, cutoff, b)
    x = _add_singular_term(x, u1, v1, sigma1, cutoff, b)
    return _add_singular_term(x, u2, v2, sigma2, cutoff, b)


@kernel
def _jacobi_rotation(up, uq, vp, vq):
    """One Jacobi rotation of the columns up, uq of u (and vp, vq of v) that makes up . uq zero:
    (up, uq, vp, vq, whether rotated); none where they are orthogonal to 1e-15 already."""
    alpha = up[0] * up[0] + up[1] * up[1] + up[2] * up[2]
    beta = uq[0] * uq[0] + uq[1] * uq[1] + uq[2] * uq[2]
    gamma = up[0] * uq[0] + up[1] * uq[1] + up[2] * uq[2]
    if abs(gamma) <= 1e-15 * np.sqrt(alpha * beta):
        return up, uq, vp, vq, False
    zeta = (beta - alpha) / (2.0 * gamma)
    t = (1.0 if zeta >= 0.0 else -1.0) / (abs(zeta) + np.sqrt(1.0 + zeta * zeta))
    c = 1.0 / np.sqrt(1.0 + t * t)
    s = c * t
    up, uq = _rotated_pair(up, uq, c, s)
    vp, vq = _rotated_pair(vp, vq, c, s)
    return up, uq, vp, vq, True


@kernel
def _rotated_pair(p, q, c, s):
    """(c p - s q, s p + c q) of two 3-vectors."""
    return ((c * p[0] - s * q[0], c * p[1] - s * q[1], c * p[2] - s * q[2]),
            (s * p[0] + c * q[0], s * p[1] + c * q[1], s * p[2] + c * q[2]))


@kernel
def _add_singular_term(x, u, v, sigma, cutoff, b):
    """x + v (u . b) / sigma^2 (u = sigma times the left singular vector), or x where sigma is
    at or below the cutoff."""
    if sigma <= cutoff:
        return x
    f = (u[0] * b[0] + u[1] * b[1] + u[2] * b[2]) / (sigma * sigma)
    return x[0] + f * v[0], x[1] + f * v[1], x[2] + f * v[2]
