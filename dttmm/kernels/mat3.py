"""3 x 3 inverse by cofactors: the sweeps and the step invert many 3 x 3 matrices, where a LAPACK
call costs more in its overhead than in its arithmetic."""
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
