"""Contact of bodies' shapes with a ground plane (docs/contact.md): the shapes, the contact law's
parameters and how a body's and the plane's combine, and the law itself in Python (the kernels'
twin is kernels/transfers/contact.py).

Every shape is a set of contact rows, each a centre fixed in the body frame and a radius: a
sphere is one, a capsule its two end spheres, a box its eight corners (radius 0).  Against a
plane these are exactly the shape's points that can touch first: a capsule's and a box's
deepest point is always one of them (or a whole edge or face of them, at once).  Against
other bodies a capsule is its whole axis swept by its radius, and a box is also solid (a row
of its own): see ROLE below and touching_pairs.

Each contact sphere pushes on its body at the point of it nearest the plane, by a compliant
law.  With n the plane's unit normal, x_c the sphere's centre, r its radius, the penetration
and its rate are

    delta = r - (n . x_c - n . p0),   delta' = -n . v       (v: the contact point's velocity)

and the force on the body, while delta > 0,

    normal:   f_n = k delta max(0, 1 + a delta' / rho),   rho = sqrt(delta'^2 + w^2 delta^2)
    friction: f_t = -mu f_n v_t / sqrt(|v_t|^2 + v_s^2),    v_t = v - (n . v) n

with w = sqrt(k / m), m the body's mass: a linear spring whose damping (Hunt and Crossley's
form, k delta times a function of the rates) is homogeneous of degree one in (delta,
delta'), so that a body of mass m striking on one sphere at any speed rebounds at the same
ratio e(a) of it: the law scales with the speed.  e(a) is the rebound of x'' = -x max(0, 1 +
a x' / sqrt(x'^2 + x^2)), x(0) = 0, x'(0) = 1 (restitution_of_damping, solved once by scipy),
and `a` the damping that gives the restitution asked for (damping_of_restitution).  The force
rises from zero at the touch (no jump, which the step would place to within a step only) and
never pulls; resting, the damper is viscous, c = a sqrt(k m).  Coulomb's friction is made
smooth below the stick velocity v_s: a body held by friction creeps at most at about v_s
(v_s r / sqrt(1 - r^2) at a ratio r < 1 of the friction it needs to what the contact can give).
"""
import functools
import math
from dataclasses import dataclass

import numpy as np

from ._checks import finite_scalar, finite_vector, rotation_matrix

# layout of one contact sphere's row (Model.contacts; the kernels' contacts table)
BODY = 0                # the body (the user's index in Model.contacts, the kernel model's there)
CENTRE = slice(1, 4)    # the sphere's centre from the body's input point, body frame, m
RADIUS = 4              # its radius, m
NORMAL = slice(5, 8)    # the plane's unit normal, world
LEVEL = 8               # n . p0 of the plane, m
STIFFNESS = 9           # k, N/m
DAMPING = 10            # a, the law's damping (dimensionless: damping_of_restitution)
FRICTION = 11           # mu
STICK_VELOCITY = 12     # v_s, m/s
RATE = 13               # w = sqrt(k / m), rad/s (m: the body's mass)
# ... and the body's own law, which two bodies' spheres combine when they touch each other
OWN_STIFFNESS = 14      # k_body, N/m
OWN_DAMPING = 15        # a of the body's restitution
OWN_FRICTION = 16       # mu_body
OWN_STICK_VELOCITY = 17  # v_s of the body
MASS = 18               # the body's mass, kg
ON_PLANE = 19           # 1: it touches the plane (NORMAL .. RATE hold that law), 0: no plane
PARENT = 20             # the body's parent (-1: the ground), whose spheres it does not touch
SEGMENT = slice(21, 24)  # a capsule's axis, from CENTRE to its other end, body frame, m (else 0)
ROLE = 24               # what the row touches other bodies as (below)
HALF = slice(25, 28)    # a box's half edges, m (its SOLID row)
AXES = slice(28, 37)    # a box's axes, the columns of a 3 x 3 matrix in the body frame, row major
CONTACT_SIZE = 37

# roles: SWEPT a sphere swept along SEGMENT (a sphere, a capsule's start row: its whole axis),
# END a capsule's end sphere (the plane only: its SWEPT row touches bodies), CORNER a box's
# corner (the plane, and other bodies' boxes), SOLID a box (other bodies' spheres, capsules and
# corners; not the plane, which its corners touch)
SWEPT, END, CORNER, SOLID = 0, 1, 2, 3

STICK_VELOCITY_DEFAULT = 1e-4   # m/s
# Two bodies' friction below the stick velocity is a damper, c = mu f_n / v_s, coupling them;
# the step's block-Jacobi iterations (kernels/transfers/contact.py) converge at c h/2 / (m + c
# h/2) per iteration (m the pair's reduced mass), slowly where c h/2 >> m.  So the pair's stick
# velocity is at least mu f_n / (STICK_DAMPING m w): c <= STICK_DAMPING m w, and a step that
# resolves the contact (w h <= pi / 20) converges at 0.24 or better per iteration.
STICK_DAMPING = 4.0
LEAST_RESTITUTION = 0.01        # (a restitution below it: ask for 0.01, a dead stop)


def restitution_of_damping(a):
    """e(a): the rebound ratio of the law's scaled contact, x'' = -x max(0, 1 + a x' / sqrt(x'^2
    + x^2)) from x(0) = 0, x'(0) = 1 until x returns to 0 (time in units of 1 / w, x in v0 / w);
    where the force lets go first (1 + a x' / |(x, x')| = 0 on the way out, a > 1) the body
    leaves at the rate it has there.  e(0) = 1, falling to 0 as a grows."""
    from scipy.integrate import solve_ivp
    if a <= 0.0:
        return 1.0

    def rates(_, y):
        x, v = y
        r = math.hypot(x, v)
        return [v, -x * max(0.0, 1.0 + a * v / r) if r > 0.0 else 0.0]

    def back(_, y):
        return y[0]

    def lets_go(_, y):
        return 1.0 + a * y[1] / max(math.hypot(y[0], y[1]), 1e-300) if y[1] < 0.0 else 1.0

    back.terminal = lets_go.terminal = True
    back.direction = lets_go.direction = -1
    sol = solve_ivp(rates, (0.0, 100.0), [0.0, 1.0], method="DOP853", events=(back, lets_go),
                    rtol=1e-12, atol=1e-14, first_step=1e-6)
    ends = [y[0][1] for y in sol.y_events if len(y)]
    if not ends:
        raise RuntimeError(f"restitution_of_damping({a}): the scaled contact did not end")
    return -ends[0]


@functools.lru_cache(maxsize=256)
def damping_of_restitution(restitution):
    """The law's damping a at which it rebounds at `restitution` (0 < e <= 1; e(a) inverted by
    Brent's method to 1e-12)."""
    from scipy.optimize import brentq
    if restitution >= 1.0:
        return 0.0
    return brentq(lambda a: restitution_of_damping(a) - restitution, 0.0, 200.0, xtol=1e-13,
                  rtol=1e-13)


def _positive(who, name, value, allow_inf=False):
    """finite_scalar(..., positive=True), or infinity where allow_inf (a rigid plane's)."""
    if allow_inf and isinstance(value, (int, float)) and value == math.inf:
        return math.inf
    return finite_scalar(who, name, value, positive=True)


@dataclass(frozen=True, eq=False)
class Contact:
    """The contact law's parameters of a body's shapes or of a plane (docs/contact.md).

    Parameters
    ----------
    stiffness : float, optional
        k, N/m, of each contact sphere (a box's corner, a capsule's end).  Give it or
        contact_time, not both.
    contact_time : float, optional
        T, s: the stiffness that makes the body's contact on one sphere last about T (its
        undamped half period), k = m (pi / T)^2 with m the body's mass.  Choose T of at least
        ~20 steps: a stiffer contact is not resolved by the step (the run says so).
    restitution : float, optional
        e in [0.01, 1] (default 1): the law's damping (damping_of_restitution) rebounds the
        body, striking on one sphere, at e times the speed it struck at, whatever that speed.
    friction : float, optional
        mu >= 0, Coulomb's coefficient, static = kinetic (default 0: frictionless).
    stick_velocity : float, optional
        v_s > 0, m/s (default 1e-4): below it friction is smooth, so a body it holds creeps
        at about v_s at most.

    A plane's Contact combines with a body's: the stiffnesses in series (1/k = 1/k_body +
    1/k_plane), the smaller restitution, the smaller friction, the smaller stick velocity.
    ``Plane``'s default (stiffness and friction infinite, restitution 1) leaves the body's.

    Examples
    --------
    >>> import dttmm
    >>> steel = dttmm.Contact(stiffness=1e8, restitution=0.8, friction=0.3)
    """
    stiffness: float = None
    contact_time: float = None
    restitution: float = 1.0
    friction: float = 0.0
    stick_velocity: float = STICK_VELOCITY_DEFAULT

    def validated(self, who, mass=None):
        """(k, e, mu, v_s) as floats; k from contact_time needs the body's mass.  ValueError
        naming who and the argument."""
        if (self.stiffness is None) == (self.contact_time is None):
            raise ValueError(f"{who}: Contact needs a stiffness (N/m) or a contact_time (s), "
                             f"exactly one")
        if self.stiffness is not None:
            k = _positive(who, "Contact stiffness", self.stiffness, allow_inf=True)
        else:
            t = _positive(who, "Contact contact_time", self.contact_time)
            if mass is None:
                raise ValueError(f"{who}: a plane's Contact takes a stiffness, not a "
                                 f"contact_time (it has no mass of its own)")
            k = mass * (math.pi / t) ** 2
        e = finite_scalar(who, "Contact restitution", self.restitution)
        if not LEAST_RESTITUTION <= e <= 1.0:
            raise ValueError(f"{who}: Contact restitution must be in [{LEAST_RESTITUTION}, 1], "
                             f"got {self.restitution!r}")
        if self.friction == math.inf:
            mu = math.inf
        else:
            mu = finite_scalar(who, "Contact friction", self.friction, nonnegative=True)
        v_s = _positive(who, "Contact stick_velocity", self.stick_velocity, allow_inf=True)
        return k, e, mu, v_s


@dataclass(frozen=True, eq=False)
class Plane:
    """A plane of the ground that bodies' shapes touch (docs/contact.md): the half-space behind
    it is solid.  Pass it as ``Ground(plane=...)``.

    Parameters
    ----------
    normal : array_like of 3, optional
        Its outward normal in the ground frame (default (0, 0, 1)); normalized.
    point : array_like of 3, optional
        A point of it in the ground frame, m (default the origin).
    contact : Contact, optional
        Its own contact parameters (default: rigid, friction infinite, restitution 1, so
        that every body's are used as they are).

    Examples
    --------
    >>> import dttmm
    >>> floor = dttmm.Plane(normal=[0, 0, 1], point=[0, 0, 0])
    >>> ground = dttmm.Ground(plane=floor)
    """
    normal: object = (0.0, 0.0, 1.0)
    point: object = (0.0, 0.0, 0.0)
    contact: Contact = Contact(stiffness=math.inf, friction=math.inf,
                               stick_velocity=math.inf)

    def validated(self, rotation, position):
        """(n, level) in the world for a ground frame at (rotation, position)."""
        who = "Plane"
        n = finite_vector(who, "normal", self.normal)
        size = float(np.linalg.norm(n))
        if not size > 1e-12:
            raise ValueError(f"{who}: normal must not be zero, got {self.normal!r}")
        if not isinstance(self.contact, Contact):
            raise ValueError(f"{who}: contact must be a Contact, got {self.contact!r}")
        n = rotation @ (n / size)
        p = rotation @ finite_vector(who, "point", self.point) + position
        return n, float(n @ p), self.contact.validated(who)


@dataclass(frozen=True, eq=False)
class Sphere:
    """A ball of the body that touches planes (docs/contact.md): one contact sphere.

    Parameters
    ----------
    radius : float
        m, >= 0 (0: a point of the body that touches).
    center : array_like of 3, optional
        Its centre from the body's input point, body frame, m (default the input point).
    """
    radius: float
    center: object = (0.0, 0.0, 0.0)

    def primitives(self, who):
        radius = finite_scalar(who, "Sphere radius", self.radius)
        if radius < 0.0:
            raise ValueError(f"{who}: Sphere radius must be >= 0 (0: a point), got "
                             f"{self.radius!r}")
        return [_primitive(finite_vector(who, "Sphere center", self.center), radius)]


@dataclass(frozen=True, eq=False)
class Capsule:
    """A cylinder with hemispherical ends (docs/contact.md): its two end spheres touch a plane,
    its whole axis (a swept sphere) touches other bodies.

    Parameters
    ----------
    radius : float
        m, > 0.
    start, end : array_like of 3
        Its axis' ends from the body's input point, body frame, m.
    """
    radius: float
    start: object = (0.0, 0.0, 0.0)
    end: object = (0.0, 0.0, 0.0)

    def primitives(self, who):
        r = _positive(who, "Capsule radius", self.radius)
        start = finite_vector(who, "Capsule start", self.start)
        end = finite_vector(who, "Capsule end", self.end)
        return [_primitive(start, r, segment=end - start), _primitive(end, r, role=END)]


@dataclass(frozen=True, eq=False)
class Box:
    """A rectangular box of the body (docs/contact.md): its eight corners touch a plane and
    other boxes, its faces other bodies' spheres, capsules and corners.

    Parameters
    ----------
    size : array_like of 3
        Its edges along its own x, y, z, m, each > 0.
    center : array_like of 3, optional
        Its centre from the body's input point, body frame, m (default the input point).
    rotation : array_like (3, 3), optional
        Its axes in the body frame (default the body's).
    """
    size: object
    center: object = (0.0, 0.0, 0.0)
    rotation: object = None

    def primitives(self, who):
        size = finite_vector(who, "Box size", self.size)
        if not np.all(size > 0.0):
            raise ValueError(f"{who}: Box size must be 3 lengths > 0, got {self.size!r}")
        centre = finite_vector(who, "Box center", self.center)
        rot = np.eye(3) if self.rotation is None else rotation_matrix(who, "Box rotation",
                                                                      self.rotation)
        corners = [_primitive(centre + rot @ (0.5 * size * np.array([sx, sy, sz])), 0.0,
                              role=CORNER)
                   for sx in (-1.0, 1.0) for sy in (-1.0, 1.0) for sz in (-1.0, 1.0)]
        return corners + [_primitive(centre, 0.0, role=SOLID, half=0.5 * size, axes=rot)]


def _primitive(centre, radius, segment=(0.0, 0.0, 0.0), role=SWEPT, half=(0.0, 0.0, 0.0),
               axes=np.zeros((3, 3))):
    """One row's geometry (the layout above)."""
    return dict(centre=centre, radius=radius, segment=segment, role=role, half=half,
                axes=np.asarray(axes).ravel())


SHAPES = (Sphere, Capsule, Box)


def contact_rows(who, body, parent, mass, shapes, contact, plane):
    """The rows (CONTACT_SIZE each) of a rigid body's shapes: one per contact sphere, the
    body's own law, and against the plane (plane: (n, level, plane's (k, e, mu, v_s)), or
    None) the combined law's parameters."""
    if not isinstance(shapes, (list, tuple)):
        shapes = [shapes]
    for s in shapes:
        if not isinstance(s, SHAPES):
            raise ValueError(f"{who}: shapes must be Sphere, Capsule or Box, got {s!r}")
    if contact is None:
        raise ValueError(f"{who}: a body with shapes needs contact=Contact(stiffness=... or "
                         f"contact_time=..., restitution=..., friction=...)")
    if not isinstance(contact, Contact):
        raise ValueError(f"{who}: contact must be a Contact, got {contact!r}")
    k_b, e_b, mu_b, vs_b = contact.validated(who, mass)
    if not math.isfinite(k_b):
        raise ValueError(f"{who}: Contact stiffness must be finite for a body's shapes")
    if plane is not None:
        n, level, (k_p, e_p, mu_p, vs_p) = plane
        k = 1.0 / (1.0 / k_b + 1.0 / k_p)
        e, mu, v_s = min(e_b, e_p), min(mu_b, mu_p), min(vs_b, vs_p)
    rows = []
    for s in shapes:
        for p in s.primitives(who):
            row = np.zeros(CONTACT_SIZE)
            row[BODY], row[PARENT] = body, parent
            row[CENTRE], row[RADIUS], row[SEGMENT] = p["centre"], p["radius"], p["segment"]
            row[ROLE], row[HALF], row[AXES] = p["role"], p["half"], p["axes"]
            row[OWN_STIFFNESS], row[OWN_DAMPING] = k_b, damping_of_restitution(e_b)
            row[OWN_FRICTION], row[OWN_STICK_VELOCITY], row[MASS] = mu_b, vs_b, mass
            if plane is not None:
                row[NORMAL] = n                 # (a box's SOLID row: its Result's normal)
            if plane is not None and p["role"] != SOLID:
                row[ON_PLANE] = 1.0
                row[LEVEL] = level
                row[STIFFNESS], row[DAMPING] = k, damping_of_restitution(e)
                row[FRICTION], row[STICK_VELOCITY] = mu, v_s
                row[RATE] = math.sqrt(k / mass)
            rows.append(row)
    return rows


def pair_law(row_a, row_b):
    """(k, a, w, mu, v_s, cap) of two bodies' rows touching each other: the stiffnesses in
    series, the smaller restitution (the larger damping a), the smaller friction and stick
    velocity, and w = sqrt(k / m) with m = m_a m_b / (m_a + m_b), the pair's reduced mass:
    two free bodies striking on one sphere each, head on, part at e times the speed they
    closed at.  cap = STICK_DAMPING m w: the stick velocity is at least mu f_n / cap (see
    STICK_DAMPING).  The Python twin of kernels/transfers/contact.py::pair_value's."""
    k = 1.0 / (1.0 / row_a[OWN_STIFFNESS] + 1.0 / row_b[OWN_STIFFNESS])
    reduced = row_a[MASS] * row_b[MASS] / (row_a[MASS] + row_b[MASS])
    w = math.sqrt(k / reduced)
    return (k, max(row_a[OWN_DAMPING], row_b[OWN_DAMPING]), w,
            min(row_a[OWN_FRICTION], row_b[OWN_FRICTION]),
            min(row_a[OWN_STICK_VELOCITY], row_b[OWN_STICK_VELOCITY]),
            STICK_DAMPING * reduced * w)


def law_forces(k, a, w, mu, v_s, n, delta, velocity, cap=0.0):
    """The law (the module's docstring) on arrays: the force (..., 3) on a body whose contact
    point moves at `velocity` (..., 3; relative to what it touches), n (..., 3) the normal
    pushing it, delta (...) the penetration; the parameters scalars or arrays (...); cap > 0:
    the stick velocity at least mu f_n / cap (pair_law).  The Python twin of
    kernels/transfers/contact.py::law_value (which adds its slope)."""
    vn = np.einsum("...i,...i->...", velocity, n)
    inside = delta > 0.0
    depth = np.where(inside, delta, 0.0)
    rho = np.hypot(vn, w * depth)
    share = np.where(inside, -vn / np.where(inside, rho, 1.0), 0.0)
    f_n = k * depth * np.maximum(0.0, 1.0 + a * share)
    v_t = velocity - vn[..., None] * n
    if cap > 0.0:
        v_s = np.maximum(v_s, mu * f_n / cap)
    s = np.sqrt(np.einsum("...i,...i->...", v_t, v_t) + v_s ** 2)
    glide = np.divide(mu, s, out=np.zeros(np.broadcast(mu, s).shape), where=s > 0.0)
    return f_n[..., None] * (n - glide[..., None] * v_t)


def contact_forces(rows, centre, velocity):
    """The plane's force (..., N, 3) on contact spheres (rows (N, CONTACT_SIZE)) whose centres
    are at centre (..., N, 3) and whose contact points move at velocity (..., N, 3), and the
    penetration (..., N; -inf for a sphere without a plane), m."""
    rows = np.asarray(rows, dtype=float)
    n = rows[:, NORMAL]
    delta = np.where(rows[:, ON_PLANE] > 0.0, rows[:, RADIUS] + rows[:, LEVEL]
                     - np.einsum("...i,...i->...", centre, n), -np.inf)
    force = law_forces(rows[:, STIFFNESS], rows[:, DAMPING], rows[:, RATE], rows[:, FRICTION],
                       rows[:, STICK_VELOCITY], n, delta, velocity)
    return force, delta


def touching_pairs(rows):
    """The pairs (i, j) of contact rows that may touch each other, j the box where one is (a
    sphere or capsule with a sphere or capsule, either with a box, a box's corner with another
    box): of two bodies, neither the other's parent (kernels/transfers/contact.py::
    contact_forces' exclusions)."""
    rows = np.asarray(rows, dtype=float)
    body, parent = rows[:, BODY].astype(int), rows[:, PARENT].astype(int)
    role = rows[:, ROLE].astype(int)
    out = []
    for i in range(len(rows)):
        for j in range(i + 1, len(rows)):
            if body[i] == body[j] or parent[i] == body[j] or parent[j] == body[i]:
                continue
            if role[i] == SOLID:
                i_, j_ = j, i
            else:
                i_, j_ = i, j
            if (role[i_] == SWEPT and role[j_] in (SWEPT, SOLID)) or (
                    role[i_] == CORNER and role[j_] == SOLID):
                out.append((i_, j_))
    return out


# the narrow phase (docs/contact.md, "Bodies touching each other"), on arrays (..., 3): the
# Python twins of kernels/transfers/contact_geometry.py's

def segment_parameters(p1, d1, p2, d2):
    """(s, t) in [0, 1] of the nearest points p1 + s d1 and p2 + t d2 of two segments (Ericson,
    Real-Time Collision Detection, 5.1.9); parallel ones at the middle of their overlap."""
    dot = lambda a, b: np.einsum("...i,...i->...", a, b)    # noqa: E731
    r = p1 - p2
    a, e, b, c, f = dot(d1, d1), dot(d2, d2), dot(d1, d2), dot(d1, r), dot(d2, r)
    a_ = np.where(a > 0.0, a, 1.0)
    e_ = np.where(e > 0.0, e, 1.0)
    denom = a * e - b * b
    parallel = denom <= 1e-12 * a * e
    s = np.where(parallel, 0.5 * (np.clip(-c / a_, 0, 1) + np.clip((b - c) / a_, 0, 1)),
                 np.clip((b * f - c * e) / np.where(parallel, 1.0, denom), 0.0, 1.0))
    s = np.where(a > 0.0, s, 0.0)
    t = (b * s + f) / e_
    s = np.where(t < 0.0, np.clip(-c / a_, 0, 1), np.where(t > 1.0, np.clip((b - c) / a_, 0, 1),
                                                              s))
    s = np.where(a > 0.0, s, 0.0)
    t = np.where(e > 0.0, np.clip(t, 0.0, 1.0), 0.0)
    return s, t


def box_distance(x, centre, axes, half):
    """(sd, n): the signed distance of x from a box (centre, its axes the columns of `axes`
    (3, 3), its half edges) and the box's outward normal there (inside: sd < 0, the face
    nearest)."""
    local = np.einsum("...i,...ij->...j", x - centre, axes)
    q = np.abs(local) - half
    out = np.maximum(q, 0.0)
    d_out = np.linalg.norm(out, axis=-1)
    sign = np.where(local < 0.0, -1.0, 1.0)
    face = np.argmax(q, axis=-1)
    inside = d_out == 0.0
    n_in = np.take_along_axis(sign, face[..., None], axis=-1) * (
        np.arange(3) == face[..., None])
    n_out = sign * out / np.where(inside, 1.0, d_out)[..., None]
    n_local = np.where(inside[..., None], n_in, n_out)
    return np.where(inside, np.max(q, axis=-1), d_out), np.einsum("...ij,...j->...i", axes,
                                                                  n_local)


GOLDEN_STEPS = 48       # golden-section steps of segment_box_parameter: 0.618^48 ~ 1e-10
TIE = 1e-9              # its tie-breaking curvature (m): flat minima at the middle


def segment_box_parameter(p, d, centre, axes, half):
    """t in [0, 1] of the point p + t d of a segment that goes deepest into a box (or nearest
    to it): the signed distance is convex along the segment, minimized by golden sections,
    with TIE (t - 1/2)^2 |d| added so that a flat minimum (lying on a face) is taken at the
    middle of its span."""
    size = np.linalg.norm(d, axis=-1)
    lo, hi = np.zeros(size.shape), np.ones(size.shape)
    g = 0.5 * (np.sqrt(5.0) - 1.0)

    def f(t):
        return box_distance(p + t[..., None] * d, centre, axes, half)[0] + TIE * size * (
            t - 0.5) ** 2

    for _ in range(GOLDEN_STEPS):
        t1, t2 = hi - g * (hi - lo), lo + g * (hi - lo)
        lower = f(t1) < f(t2)
        hi, lo = np.where(lower, t2, hi), np.where(lower, lo, t1)
    return np.where(size > 0.0, 0.5 * (lo + hi), 0.0)


def pair_geometry(row_i, row_j, x_i, seg_i, x_j, seg_j, axes_j):
    """(delta, n, point_i, point_j): a pair's penetration, its normal from j to i and the
    contact points on each (world), rows i and j at centres x (..., 3), axes seg (world) and
    j's box axes axes_j (..., 3, 3; world) where j is a box (touching_pairs' order)."""
    if int(row_j[ROLE]) == SOLID:
        t = segment_box_parameter(x_i, seg_i, x_j, axes_j, row_j[HALF])
        c_i = x_i + t[..., None] * seg_i
        sd, n = box_distance(c_i, x_j, axes_j, row_j[HALF])
        return row_i[RADIUS] - sd, n, c_i - row_i[RADIUS] * n, c_i - sd[..., None] * n
    s, t = segment_parameters(x_i, seg_i, x_j, seg_j)
    c_i, c_j = x_i + s[..., None] * seg_i, x_j + t[..., None] * seg_j
    dist = np.linalg.norm(c_i - c_j, axis=-1)
    n = (c_i - c_j) / np.where(dist > 0.0, dist, 1.0)[..., None]
    delta = np.where(dist > 0.0, row_i[RADIUS] + row_j[RADIUS] - dist, -np.inf)
    return delta, n, c_i - row_i[RADIUS] * n, c_j + row_j[RADIUS] * n
