"""Small dense algebra by loops: the sweeps and the step invert and multiply many 3 x 3 (and
3 x 13, 6 x 7) matrices, where a BLAS or LAPACK call costs more in its overhead than in its
arithmetic."""
import numpy as np
from numba import njit


@njit(cache=True)
def inv3(a, out):
    """out = a^-1 (adjugate over determinant); returns the determinant (out is not finite when
    it is 0)."""
    c00 = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    c01 = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    c02 = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    det = a[0, 0] * c00 + a[0, 1] * c01 + a[0, 2] * c02
    f = 1.0 / det if det != 0.0 else np.inf
    out[0, 0] = c00 * f
    out[1, 0] = c01 * f
    out[2, 0] = c02 * f
    out[0, 1] = (a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2]) * f
    out[1, 1] = (a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0]) * f
    out[2, 1] = (a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1]) * f
    out[0, 2] = (a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]) * f
    out[1, 2] = (a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2]) * f
    out[2, 2] = (a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]) * f
    return det


@njit(cache=True)
def matmul_into(a, b, out):
    """out = a @ b by loops (small matrices: BLAS's call overhead dominates at these sizes)."""
    for i in range(a.shape[0]):
        for j in range(b.shape[1]):
            s = 0.0
            for k in range(a.shape[1]):
                s += a[i, k] * b[k, j]
            out[i, j] = s


@njit(cache=True)
def matvec_into(a, x, out):
    """out = a @ x by loops."""
    for i in range(a.shape[0]):
        s = 0.0
        for k in range(a.shape[1]):
            s += a[i, k] * x[k]
        out[i] = s


@njit(cache=True)
def hat_mul(v, b, out):
    """out = v^ @ b (3 x 3): column j is v x b[:, j]."""
    for j in range(3):
        b0, b1, b2 = b[0, j], b[1, j], b[2, j]
        out[0, j] = v[1] * b2 - v[2] * b1
        out[1, j] = v[2] * b0 - v[0] * b2
        out[2, j] = v[0] * b1 - v[1] * b0


@njit(cache=True)
def mul_hat(a, v, out):
    """out = a @ v^ (3 x 3): row i is a[i] x v."""
    for i in range(3):
        a0, a1, a2 = a[i, 0], a[i, 1], a[i, 2]
        out[i, 0] = a1 * v[2] - a2 * v[1]
        out[i, 1] = a2 * v[0] - a0 * v[2]
        out[i, 2] = a0 * v[1] - a1 * v[0]
