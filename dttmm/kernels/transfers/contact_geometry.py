"""The narrow phase of two bodies' contact rows (docs/contact.md, "Bodies touching each
other"): the nearest points of two segments (a sphere or capsule against a sphere or capsule)
and the deepest point of a segment in a box (a sphere, capsule or corner against a box).  The
Python twins, on arrays, are elements/contact.py's segment_parameters, box_distance and
segment_box_parameter."""
import numpy as np

from .. import kernel
from ...elements.contact import GOLDEN_STEPS, TIE


@kernel
def segment_parameters(p1, d1, p2, d2):
    """(s, t) in [0, 1] of the nearest points p1 + s d1 and p2 + t d2 of two segments (Ericson,
    Real-Time Collision Detection, 5.1.9): s from the lines' nearest points, clamped, t from s,
    clamped, s again from t; parallel ones (a e - b^2 <= 1e-12 a e) at the middle of the part
    of segment 1 that segment 2 projects on."""
    r0, r1, r2 = p1[0] - p2[0], p1[1] - p2[1], p1[2] - p2[2]
    a = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2]
    e = d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2]
    b = d1[0] * d2[0] + d1[1] * d2[1] + d1[2] * d2[2]
    c = d1[0] * r0 + d1[1] * r1 + d1[2] * r2
    f = d2[0] * r0 + d2[1] * r1 + d2[2] * r2
    if a <= 0.0 and e <= 0.0:
        return 0.0, 0.0
    if a <= 0.0:
        return 0.0, min(1.0, max(0.0, f / e))
    if e <= 0.0:
        return min(1.0, max(0.0, -c / a)), 0.0
    denom = a * e - b * b
    if denom <= 1e-12 * a * e:
        s = 0.5 * (min(1.0, max(0.0, -c / a)) + min(1.0, max(0.0, (b - c) / a)))
    else:
        s = min(1.0, max(0.0, (b * f - c * e) / denom))
    t = (b * s + f) / e
    if t < 0.0:
        return min(1.0, max(0.0, -c / a)), 0.0
    if t > 1.0:
        return min(1.0, max(0.0, (b - c) / a)), 1.0
    return s, t


@kernel
def box_distance(x0, x1, x2, centre, axes, half, n):
    """The signed distance of the point (x0, x1, x2) from a box (its centre, its axes the
    columns of `axes` (world), its half edges), and into n the box's outward normal there
    (inside, sd < 0: the nearest face's)."""
    y0, y1, y2 = x0 - centre[0], x1 - centre[1], x2 - centre[2]
    l0 = axes[0, 0] * y0 + axes[1, 0] * y1 + axes[2, 0] * y2       # the point in the box's axes
    l1 = axes[0, 1] * y0 + axes[1, 1] * y1 + axes[2, 1] * y2
    l2 = axes[0, 2] * y0 + axes[1, 2] * y1 + axes[2, 2] * y2
    q0, q1, q2 = abs(l0) - half[0], abs(l1) - half[1], abs(l2) - half[2]
    o0, o1, o2 = max(q0, 0.0), max(q1, 0.0), max(q2, 0.0)
    out = np.sqrt(o0 * o0 + o1 * o1 + o2 * o2)
    if out > 0.0:                       # outside: along the nearest point's offset
        g0 = (o0 if l0 > 0.0 else -o0) / out
        g1 = (o1 if l1 > 0.0 else -o1) / out
        g2 = (o2 if l2 > 0.0 else -o2) / out
        sd = out
    else:                               # inside: the nearest face's normal
        sd = max(q0, q1, q2)
        g0 = g1 = g2 = 0.0
        if q0 == sd:
            g0 = 1.0 if l0 >= 0.0 else -1.0
        elif q1 == sd:
            g1 = 1.0 if l1 >= 0.0 else -1.0
        else:
            g2 = 1.0 if l2 >= 0.0 else -1.0
    for j in range(3):
        n[j] = axes[j, 0] * g0 + axes[j, 1] * g1 + axes[j, 2] * g2
    return sd


@kernel
def segment_box_parameter(p, d, centre, axes, half, n):
    """t in [0, 1] of the point p + t d of a segment that goes deepest into a box (or comes
    nearest): its signed distance is convex along the segment, minimized by GOLDEN_STEPS golden
    sections with TIE (t - 1/2)^2 |d| added (a flat minimum, lying on a face, at the middle of
    its span); n: scratch (3)."""
    size = np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    if size == 0.0:
        return 0.0
    g = 0.5 * (np.sqrt(5.0) - 1.0)
    lo, hi = 0.0, 1.0
    for _ in range(GOLDEN_STEPS):
        t1, t2 = hi - g * (hi - lo), lo + g * (hi - lo)
        f1 = box_distance(p[0] + t1 * d[0], p[1] + t1 * d[1], p[2] + t1 * d[2], centre, axes,
                          half, n) + TIE * size * (t1 - 0.5) ** 2
        f2 = box_distance(p[0] + t2 * d[0], p[1] + t2 * d[1], p[2] + t2 * d[2], centre, axes,
                          half, n) + TIE * size * (t2 - 0.5) ** 2
        if f1 < f2:
            hi = t2
        else:
            lo = t1
    return 0.5 * (lo + hi)
