"""End stops on a joint's coordinate (docs/limits.md): a lower and an upper bound, each a stiff
one-sided spring with a damper in parallel, which pushes the coordinate back and never pulls:

    q > upper:  tau = -max(0, k (q - upper) + c q')
    q < lower:  tau = +max(0, k (lower - q) - c q')
    else:       tau = 0

a generalized force (N m on a turn, N on a slide) on the coordinate, beside its drive.  Given
by its stiffness and damping, or by a restitution coefficient e, an inertia I about (along) the
coordinate and a contact time T (JointLimit.with_restitution): k = I (pi / T)^2 and c = 2 zeta
sqrt(k I), zeta the damping ratio at which this law rebounds a body of inertia I at e times the
rate it struck at (restitution_damping_ratio: exact for one coordinate of constant inertia,
whatever the rate at impact).
"""
import math
from dataclasses import dataclass

import numpy as np

from ._checks import finite_scalar


def stop_force(limit, q, qd):
    """The end stops' generalized force at (q, q'), scalars or arrays alike: the law above for
    limit = (lower, upper, stiffness, damping) (a hinge_params row's, kinds.limit_of).  The
    Python twin of the kernels' kernels/transfers/joint.py::stop_value (which adds its slope),
    for the reference and the Result."""
    lower, upper, k, c = (float(x) for x in limit)
    q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
    above = np.where(q > upper, np.maximum(0.0, k * (q - upper) + c * qd), 0.0)
    below = np.where(q < lower, np.maximum(0.0, k * (lower - q) - c * qd), 0.0)
    return below - above


def restitution_of(zeta):
    """The rebound ratio of the one-sided spring-damper above on a body of constant inertia,
    damping ratio zeta >= 0.  In the time tau = w t and units of v0 / w, the body strikes at 1:
    x'' + 2 zeta x' + x = 0, x(0) = 0, x'(0) = 1, while the stop's force x + 2 zeta x' pushes.
    Below critical damping, r = sqrt(1 - zeta^2): x = e^{-zeta tau} sin(r tau) / r, the force
    ~ sin(r tau + phi), phi = atan2(2 zeta r, 1 - 2 zeta^2), lets go at r tau = pi - phi.
    Above it, x = (e^{a tau} - e^{b tau}) / (a - b), a, b = -zeta +- sqrt(zeta^2 - 1): the
    force lets go at e^{(a - b) tau} = (1 + 2 zeta b) / (1 + 2 zeta a).  e = -x' there; it
    falls from 1 (zeta = 0) through 0.135 (critical) to 0 (zeta -> infinity)."""
    if zeta <= 0.0:
        return 1.0
    if abs(zeta - 1.0) < 1e-9:
        zeta = 1.0 - 1e-9                   # (continuous through critical damping)
    if zeta < 1.0:
        r = math.sqrt(1.0 - zeta * zeta)
        angle = math.pi - math.atan2(2.0 * zeta * r, 1.0 - 2.0 * zeta * zeta)
        return -math.exp(-zeta * angle / r) * (math.cos(angle) - zeta / r * math.sin(angle))
    s = math.sqrt(zeta * zeta - 1.0)
    a, b = -zeta + s, -zeta - s
    tau = math.log((1.0 + 2.0 * zeta * b) / (1.0 + 2.0 * zeta * a)) / (a - b)
    return -(a * math.exp(a * tau) - b * math.exp(b * tau)) / (a - b)


def restitution_damping_ratio(restitution):
    """The damping ratio zeta at which the stop rebounds at `restitution` (0 < e <= 1:
    restitution_of inverted by bisection in log zeta; it falls monotonically)."""
    if restitution >= 1.0:
        return 0.0
    lo, hi = math.log(1e-8), math.log(1e8)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if restitution_of(math.exp(mid)) > restitution:
            lo = mid
        else:
            hi = mid
    return math.exp(0.5 * (lo + hi))


@dataclass(frozen=True, eq=False)
class JointLimit:
    """End stops on one coordinate of a joint: a lower and an upper bound (docs/limits.md).

    Past a bound a one-sided spring-damper pushes the coordinate back, never pulls:
    tau = -max(0, k (q - upper) + c q') above the upper bound, +max(0, k (lower - q) - c q')
    below the lower (N m on a turn, N on a slide; stiffness N m/rad or N/m, damping N m s/rad
    or N s/m), added to the coordinate's drive.  A drive that pushes against a stop is held
    there, a penetration of its force / stiffness.  ``JointLimit.with_restitution`` sets the
    stiffness and damping from a restitution coefficient, the inertia the stop stops and the
    contact's duration.  ``Result.limit_force`` holds each stop's force, and
    ``Result.limit_contacts()`` when it engaged.

    Parameters
    ----------
    lower, upper : float, optional
        The bounds, rad or m (default -inf and inf: none on that side); lower < upper.
    stiffness : float
        k > 0, N m/rad or N/m (required).
    damping : float, optional
        c >= 0, N m s/rad or N s/m (default 0: an elastic stop).

    Raises
    ------
    ValueError
        At build time, naming the joint, its coordinate and the argument: bounds that are not
        numbers or not lower < upper; a stiffness not > 0 or a damping < 0.

    Examples
    --------
    A revolute joint stopped at +-0.5 rad, rebounding at half its rate from a 2 kg m^2 link
    within 5 ms:

    >>> import dttmm
    >>> stop = dttmm.JointLimit.with_restitution(-0.5, 0.5, restitution=0.5, inertia=2.0,
    ...                                          contact_time=5e-3)
    >>> joint = dttmm.RevoluteJoint(axis=[0, 0, 1], limits=stop)
    """
    lower: float = -math.inf
    upper: float = math.inf
    stiffness: float = None
    damping: float = 0.0

    @classmethod
    def with_restitution(cls, lower, upper, restitution, inertia, contact_time):
        """The stop that rebounds a coordinate of inertia `inertia` (kg m^2 or kg) at
        `restitution` (0 < e <= 1) times the rate it struck at, its contact lasting about
        `contact_time` s (the undamped half period): k = I (pi / T)^2, c = 2 zeta sqrt(k I)
        (restitution_damping_ratio).  Choose T of at least ~20 steps: a stiffer stop is not
        resolved by the step (the run's error estimate says so)."""
        for name, value in (("restitution", restitution), ("inertia", inertia),
                            ("contact_time", contact_time)):
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"JointLimit.with_restitution: {name} must be a number > 0, "
                                 f"got {value!r}")
        if restitution > 1.0:
            raise ValueError(f"JointLimit.with_restitution: restitution must be in (0, 1], got "
                             f"{restitution!r}")
        k = inertia * (math.pi / contact_time) ** 2
        zeta = restitution_damping_ratio(restitution)
        return cls(lower, upper, k, 2.0 * zeta * math.sqrt(k * inertia))

    def validated(self, who):
        """(lower, upper, stiffness, damping) as floats; ValueError naming who and the
        argument."""
        lower = -math.inf if self.lower == -math.inf else finite_scalar(who, "lower", self.lower)
        upper = math.inf if self.upper == math.inf else finite_scalar(who, "upper", self.upper)
        if not lower < upper:
            raise ValueError(f"{who}: lower ({lower}) must be below upper ({upper})")
        if self.stiffness is None:
            raise ValueError(f"{who}: stiffness must be given (N m/rad or N/m; or build the "
                             f"stop with JointLimit.with_restitution)")
        k = finite_scalar(who, "stiffness", self.stiffness)
        c = finite_scalar(who, "damping", self.damping)
        if not k > 0.0:
            raise ValueError(f"{who}: stiffness must be > 0, got {k}")
        if c < 0.0:
            raise ValueError(f"{who}: damping must be >= 0, got {c}")
        return lower, upper, k, c
