"""Validation helpers shared by the element classes: every failure names the element and the
argument."""
import numpy as np


def is_text(value):
    """A string, bytes or bool, or an array or list holding one: what a number must not be
    silently made of ('1.5' -> 1.5, True -> 1.0)."""
    if isinstance(value, (str, bytes, bool, np.bool_)):
        return True
    if isinstance(value, (int, float, np.number)):      # (the common case, per drive call)
        return False
    raw = value if isinstance(value, np.ndarray) else np.asarray(value, dtype=object)
    return raw.dtype.kind in "USb" or (raw.dtype == object and raw.ndim > 0 and any(
        isinstance(x, (str, bytes, bool, np.bool_)) for x in raw.reshape(-1)))


def finite_vector(element, argument, value, size=3):
    if is_text(value):
        raise ValueError(f"{element}: {argument} must be a vector of {size} numbers, "
                         f"got {value!r}")
    try:
        v = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{element}: {argument} must be a vector of {size} numbers, "
                         f"got {value!r}") from None
    if v.ndim > 1:
        raise ValueError(f"{element}: {argument} must be a flat vector of {size} numbers, got "
                         f"shape {v.shape}")
    v = v.reshape(-1)
    if v.size != size:
        raise ValueError(f"{element}: {argument} must have {size} entries, got {v.size}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{element}: {argument} contains NaN or infinite entries: {v}")
    return v


MAX_FREQUENCY = 1e12     # Hz: an element's own frequency beyond it is refused as non-physical


def physical_frequency(element, argument, frequency):
    """Refuse a stiffness that gives an element an own frequency (Hz) above MAX_FREQUENCY,
    beyond any structure (a MEMS resonator's are below 1e10 Hz): a slip of units, whose step
    would carry energies of 1e200 and more (issue 65: EI = 1e300 ran, its energy 1e260 times
    the kinetic)."""
    if not frequency <= MAX_FREQUENCY:
        raise ValueError(f"{element}: {argument} gives the element an own frequency of "
                         f"{frequency:.3g} Hz, beyond any physical structure's (at most "
                         f"{MAX_FREQUENCY:g} Hz here): a slip of units? Give N m^2 for a "
                         f"bending or torsional stiffness, N for an axial one, with the mass per "
                         f"length in kg/m")


def finite_scalar(element, argument, value, positive=False, nonnegative=False):
    if is_text(value):
        raise ValueError(f"{element}: {argument} must be a number, got {value!r}")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{element}: {argument} must be a number, got {value!r}") from None
    if not np.isfinite(x):
        raise ValueError(f"{element}: {argument} must be finite, got {x}")
    if positive and x <= 0.0:
        raise ValueError(f"{element}: {argument} must be > 0, got {x}")
    if nonnegative and x < 0.0:
        raise ValueError(f"{element}: {argument} must be >= 0, got {x}")
    return x


def finite_pair(element, argument, value, positive=False, nonnegative=False):
    """Two numbers (a beam's or rod's two bending planes) from a scalar, for both, or 2 entries,
    each finite (and > 0 or >= 0 when asked)."""
    pair = (np.full(2, finite_scalar(element, argument, value)) if np.ndim(value) == 0
            else finite_vector(element, argument, value, size=2))
    for v in pair:
        finite_scalar(element, argument, v, positive=positive, nonnegative=nonnegative)
    return pair


def matrix3(element, argument, value):
    """A 3x3 matrix from a scalar (times identity), 3 diagonal entries, or a 3x3 array."""
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{element}: {argument} must be a scalar, 3 diagonal entries or a 3x3 "
                         f"matrix") from None
    if a.ndim == 0:
        a = a * np.eye(3)
    elif a.shape == (3,):
        a = np.diag(a)
    elif a.shape != (3, 3):
        raise ValueError(f"{element}: {argument} must be a scalar, 3 diagonal entries or a 3x3 "
                         f"matrix, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{element}: {argument} contains NaN or infinite entries")
    return a


def symmetric_positive(element, argument, a, semidefinite=False):
    if not np.allclose(a, a.T, rtol=1e-10, atol=1e-12 * max(1.0, np.abs(a).max())):
        raise ValueError(f"{element}: {argument} must be symmetric, got\n{a}")
    eig = np.linalg.eigvalsh(0.5 * (a + a.T))
    scale = max(np.abs(eig).max(), 1e-300)
    if semidefinite:
        if eig.min() < -1e-12 * scale:
            raise ValueError(f"{element}: {argument} must be positive semidefinite, "
                             f"eigenvalues {eig}")
    elif eig.min() <= 1e-12 * scale:
        raise ValueError(f"{element}: {argument} must be positive definite, eigenvalues {eig}")
    return 0.5 * (a + a.T)


def rotation_matrix(element, argument, value):
    a = matrix3(element, argument, value)
    if not np.allclose(a @ a.T, np.eye(3), atol=1e-9) or np.linalg.det(a) < 0.0:
        raise ValueError(f"{element}: {argument} must be a proper rotation matrix (orthonormal, "
                         f"det +1)")
    # re-orthonormalise the 1e-9 slack away
    u, _, vt = np.linalg.svd(a)
    return u @ vt


class ConstantLoad:
    """A load given as 3 numbers: the function of time that returns them (a class, not a
    closure, so that a model with it pickles for a parameter sweep's workers)."""

    def __init__(self, vector):
        self.vector = vector

    def __call__(self, t):
        return self.vector.copy()

    def __repr__(self):
        return f"ConstantLoad({self.vector.tolist()})"


def optional_function(element, argument, value):
    """A load: None, a function of time returning 3 finite numbers (checked at t = 0), or 3
    finite numbers (a constant load, ConstantLoad)."""
    if value is None:
        return None
    if not callable(value):
        try:
            return ConstantLoad(finite_vector(element, argument, value))
        except ValueError:
            raise ValueError(f"{element}: {argument} must be 3 finite numbers, a function of "
                             f"time returning them, or None; got {value!r}") from None
    out = finite_vector(element, f"{argument}(0)", value(0.0))
    del out
    return value


def derivative(f, t, eps=1e-5):
    """The derivative of f (a function of time returning numbers) at t, for checking a given
    derivative: central differences, second-order forward ones where t - eps < 0 (a motion
    may be defined for t >= 0 only, e.g. sqrt(t))."""
    if t - eps >= 0.0:
        return (np.asarray(f(t + eps), dtype=float) - np.asarray(f(t - eps), dtype=float)) \
            / (2 * eps)
    return (-3.0 * np.asarray(f(t), dtype=float) + 4.0 * np.asarray(f(t + eps), dtype=float)
            - np.asarray(f(t + 2 * eps), dtype=float)) / (2 * eps)
