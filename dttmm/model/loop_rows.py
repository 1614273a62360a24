"""The closing joints' rows as the kernels and the reference read them (docs/loops.md): each
closing joint's constraint directions, the directions of its driven coordinates and of an elastic
hinge's springs, the rows' table (constraint_rows), their targets at given times and the
closing joints' drives.  The table of closing joints itself is built in closures.py.
"""
from collections import namedtuple

import numpy as np

from ..elements import BALL, ELASTIC
from ..elements.hinges import C_ROTATION, C_TRANSLATION, K_ROTATION, K_TRANSLATION, REST_ROTATION
from ..elements.kinds import (ANGLE_A, ANGLE_B, CHILD, DOT, GAP_A, GAP_WORLD, PARENT, ROTATION_A,
                              SLIDE, TURN, coordinates_of, row_axes)
from ..elements.drives import FORCE, SPRING_DAMPER

GROUND = -1     # a closing joint's side that is the ground (Model.closure_body)


def _principal_axes(label, part, k, c):
    """(axes (3, 3) as columns, stiffnesses (3,), dampings (3,)): a closing elastic hinge's
    spring K and damper C (part: "translational" or "rotational") in their common principal
    axes (each a row of the loop's table: spring_directions).  ValueError naming the hinge
    when the damper does not share the spring's axes (K C != C K)."""
    stiffness, damping = f"{part}_stiffness", f"{part}_damping"
    scale = max(float(np.max(np.abs(k))), 1e-300)
    c_scale = max(float(np.max(np.abs(c))), 1e-300)
    if np.max(np.abs(k @ c - c @ k)) > 1e-9 * scale * c_scale:
        raise ValueError(f"{label}: {damping} must share the principal axes of {stiffness} in "
                         f"a closing elastic hinge (its springs and dampers act along common "
                         f"axes; K C = C K): give a scalar, 3 entries, or a matrix with the "
                         f"spring's axes")
    # a generic combination's eigenvectors diagonalize both commuting matrices
    _, axes = np.linalg.eigh(k / scale + (np.sqrt(2.0) - 1.0) * c / c_scale)
    if np.linalg.det(axes) < 0.0:
        axes[:, 2] = -axes[:, 2]
    return axes, np.einsum("ji,jk,ki->i", axes, k, axes), np.einsum("ji,jk,ki->i", axes, c, axes)


def spring_directions(model, c):
    """The rows of closing elastic hinge c (docs/loops.md, "An elastic hinge closing a loop"),
    each a force (a SpringDamper's law), none a constraint: [(kind, v1, v2, v3, stiffness,
    damping)], along the common principal axes n_i of its spring and damper (in a's frame):
        GAP_A:      g = n_i . F_a^T (p_b - p_a)             (v1 = n_i)
        ROTATION_A: g = n_i . log(F_a^T F_b R0^T)           (v1, v2 = R0's first two columns,
                    g' = n_i . F_a^T (w_b - w_a)             v3 = n_i)
    each row's force lam = -k_i g - c_i g' (its couple n_i lam, its force n_i lam on b), so
    that the hinge's force and couple on b are -F_a (K_t d + C_t d'), -F_a (K_r psi + C_r
    F_a^T (w_b - w_a)) with d = F_a^T (p_b - p_a), d' its rate in a's frame."""
    if int(model.closure_kind[c]) != ELASTIC:
        return []
    row = model.closure_params[c]
    r0 = row[REST_ROTATION].reshape(3, 3)
    label = f"closing elastic hinge '{model.closure_names[c]}'"
    zero = np.zeros(3)
    rows = []
    for part, kind, k_slot, c_slot in (("translational", GAP_A, K_TRANSLATION, C_TRANSLATION),
                                       ("rotational", ROTATION_A, K_ROTATION, C_ROTATION)):
        axes, k, damping = _principal_axes(label, part, row[k_slot].reshape(3, 3),
                                           row[c_slot].reshape(3, 3))
        for i in range(3):
            if kind == GAP_A:
                rows.append((GAP_A, axes[:, i], zero, zero, k[i], damping[i]))
            else:
                rows.append((ROTATION_A, r0[:, 0], r0[:, 1], axes[:, i], k[i], damping[i]))
    return rows


def _perpendiculars(n):
    """Two unit vectors completing the unit vector n to a right-handed frame (n, p1, p2)."""
    p1 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    p1 /= np.linalg.norm(p1)
    return p1, np.cross(n, p1)


def constraint_directions(model, c):
    """The closing joint c's scalar constraints (closure_rows' count, Kind.constraints in
    elements/kinds.py), in the sides' own frames:
        points: [(frame, e)], the rows e . (p_b - p_a) = 0 with e fixed in side a's frame
                (frame "a") or in the world (frame "w");
        dots:   [(x, y)], the rows (F_a x) . (F_b y) = 0, x fixed in a's frame, y in b's.
    From the joint's declaration: the points hold the gap across its slides' axes (the three
    world components without slides; a's two directions across one slide's axis, or the normal
    of two slides' plane); the dots hold what its turns leave: without turns the relative
    rotation's three dots (F_a R0 e_i) . (F_b e_j), (i, j) = (2, 3), (3, 1), (1, 2); with one
    turn fixed in a (b) its axis kept perpendicular to the two directions across it in the
    other frame (revolute: F_b R0^T n against a's two across n); with one in each frame their
    axes perpendicular (universal: n1 . n2 = 0).  A ball joint: the gap alone; an elastic
    hinge: none (its rows are forces: spring_directions)."""
    kind, row = int(model.closure_kind[c]), model.closure_params[c]
    if kind == ELASTIC:
        return [], []
    r0 = row[REST_ROTATION].reshape(3, 3)
    axes, spec = row_axes(row), coordinates_of(kind)
    e = np.eye(3)
    slides = [axes[x.axis] for x in spec if x.motion == SLIDE]
    turns = {x.frame: axes[x.axis] for x in spec if x.motion == TURN}
    if not slides:
        points = [("w", e[i]) for i in range(3)]
    elif len(slides) == 1:
        points = [("a", p) for p in _perpendiculars(slides[0])]
    elif len(slides) == 2:
        normal = np.cross(slides[0], slides[1])
        points = [("a", normal / np.linalg.norm(normal))]
    else:
        points = []
    if kind == BALL:
        dots = []
    elif not turns:
        dots = [(r0 @ e[i], e[j]) for i, j in ((1, 2), (2, 0), (0, 1))]
    elif len(turns) == 2:
        dots = [(turns[PARENT], turns[CHILD])]
    elif PARENT in turns:
        dots = [(p, r0.T @ turns[PARENT]) for p in _perpendiculars(turns[PARENT])]
    else:
        dots = [(p, turns[CHILD]) for p in _perpendiculars(r0 @ turns[CHILD])]
    return points, dots


def driven_directions(model, c):
    """The rows of closing joint c's driven coordinates (JointMotion or SpringDamper): [(i,
    kind, v1, v2, v3)] for coordinate i.  A slide is the gap along a's axis (GAP_A, e = n); a
    turn's angle is
        q = atan2(n . (x x y), x . y),  q' = n . (w_b - w_a)
    with x = F_a v1, y = F_b v2 and the axis n = F v3 (F_a: ANGLE_A, F_b: ANGLE_B), from the
    joint's declaration (F_b = F_a R_P R0 R_C):
        a turn fixed in a, alone:          x = u, y = R0^T u (u across n), n in a (revolute)
        fixed in a, with one fixed in b:   x = R0 m, y = m (m the other axis), n in a
                                           (universal q1)
        fixed in b, with one fixed in a:   x = m, y = R0^T m, n in b (universal q2)
        fixed in b, alone:                 x = u, y = R0^T u (u across R0 n), n in b
    (docs/loops.md, "Drives on closing joints")."""
    kind, row = int(model.closure_kind[c]), model.closure_params[c]
    r0 = row[REST_ROTATION].reshape(3, 3)
    axes, spec = row_axes(row), coordinates_of(kind)
    turns = {x.frame: axes[x.axis] for x in spec if x.motion == TURN}
    zero = np.zeros(3)
    rows = []
    for i, d in enumerate(model.closure_drives[c] if model.closure_drives else ()):
        if d is None:
            continue
        n = axes[spec[i].axis]
        if spec[i].motion == SLIDE:
            rows.append((i, GAP_A, n, zero, zero))
        elif spec[i].frame == PARENT and CHILD in turns:
            rows.append((i, ANGLE_A, r0 @ turns[CHILD], turns[CHILD], n))
        elif spec[i].frame == PARENT:
            u = _perpendiculars(n)[0]
            rows.append((i, ANGLE_A, u, r0.T @ u, n))
        elif PARENT in turns:
            rows.append((i, ANGLE_B, turns[PARENT], r0.T @ turns[PARENT], n))
        else:
            u = _perpendiculars(r0 @ n)[0]
            rows.append((i, ANGLE_B, u, r0.T @ u, n))
    return rows


Rows = namedtuple("Rows", ["kind", "owner", "v1", "v2", "v3", "coordinate", "law"])


def constraint_rows(model, closures=None):
    """The closing joints' scalar rows (constraint_directions, then each joint's driven
    coordinates, driven_directions, or an elastic hinge's springs, spring_directions; closures:
    which closing joints, default all), a Rows of flat arrays: kind (R,) GAP_WORLD, GAP_A,
    DOT, ANGLE_A, ANGLE_B or ROTATION_A, the closing joint of
    each (R,), v1 (e or x), v2 (y; zero for a gap), v3 (an angle's axis) (R, 3) each, the
    driven coordinate of each (R,; -1 for a constraint of the joint itself) and its drive's law
    (R, 3): [kind (elements/drives.py; -1 for none), stiffness, damping]."""
    kind, owner, v1, v2, v3, coordinate, law = [], [], [], [], [], [], []
    zero = np.zeros(3)

    def add(k, c, a, b, n, i, spring=None):
        kind.append(k)
        owner.append(c)
        v1.append(a)
        v2.append(b)
        v3.append(n)
        coordinate.append(i)
        d = model.closure_drives[c][i] if i >= 0 else None
        law.append([SPRING_DAMPER, *spring] if spring is not None else
                   [-1.0, 0.0, 0.0] if d is None else [d["kind"], d["stiffness"], d["damping"]])

    for c in range(model.n_closures) if closures is None else closures:
        points, dots = constraint_directions(model, c)
        for frame, e in points:
            add(GAP_WORLD if frame == "w" else GAP_A, c, e, zero, zero, -1)
        for x, y in dots:
            add(DOT, c, x, y, zero, -1)
        for i, k, a, b, n in driven_directions(model, c):
            add(k, c, a, b, n, i)
        for k, a, b, n, stiffness, damping in spring_directions(model, c):
            add(k, c, a, b, n, -1, (stiffness, damping))
    return Rows(np.array(kind, dtype=np.int64), np.array(owner, dtype=np.int64),
                np.array(v1, dtype=float).reshape(-1, 3), np.array(v2, dtype=float).reshape(-1, 3),
                np.array(v3, dtype=float).reshape(-1, 3), np.array(coordinate, dtype=np.int64),
                np.array(law, dtype=float).reshape(-1, 3))


def closure_targets(model, times, rows=None):
    """(len(times), R, 3): each row's target (value, rate, acceleration) at the times, R and the
    rows' order as constraint_rows: a driven coordinate's prescribed motion, a SpringDamper's
    rest (its row's value is then q - rest), zero for the constraints.  A function's failure or
    a value that is not finite: ValueError naming the closing joint and its coordinate.  rows:
    constraint_rows(model) (or the kernels' flat loops, which carry its owner and coordinate),
    when the caller has them."""
    rows = constraint_rows(model) if rows is None else rows
    owner, coordinate = rows.owner, rows.coordinate
    out = np.zeros((len(times), len(owner), 3))
    for r in np.nonzero(coordinate >= 0)[0]:
        c, i = owner[r], coordinate[r]
        if model.closure_drives[c][i]["kind"] == SPRING_DAMPER:
            out[:, r, 0] = model.closure_drives[c][i]["rest"]
            continue
        if model.closure_drives[c][i]["kind"] == FORCE:     # its value: the solver's (state)
            continue
        functions = model.closure_drives[c][i]["function"]
        who = f"the prescribed motion of closing joint '{model.closure_names[c]}' " \
              f"(coordinate {i + 1})"
        for j, t in enumerate(times):
            for m, f in enumerate(functions):
                try:
                    value = float(np.asarray(f(t), dtype=float).reshape(-1)[0])
                except Exception as err:
                    raise ValueError(f"{who} failed at t = {t:g} s: {err}") from None
                if not np.isfinite(value):
                    raise ValueError(f"{who} returned {value} at t = {t:g} s (not finite)")
                out[j, r, m] = value
    return out


def closure_forces(model, rows=None):
    """[(row, f, who)]: each closing joint's coordinate driven by a JointForce f(t, q, q'),
    its row in constraint_rows' order and how messages name it.  Its q is the row's value (an
    angle's in [-pi, pi)), q' its rate.  rows: constraint_rows' table (or the kernels' loops,
    which carries its law, owner and coordinate), when the caller has it."""
    rows = constraint_rows(model) if rows is None else rows
    out = []
    for r in np.nonzero(rows.law[:, 0] == FORCE)[0]:
        c, i = rows.owner[r], rows.coordinate[r]
        out.append((int(r), model.closure_drives[c][i]["function"],
                    f"the drive of closing joint '{model.closure_names[c]}' (coordinate {i + 1})"))
    return out


def has_closure_drives(model):
    """Whether any closing joint's coordinate is driven."""
    return any(d is not None for ds in model.closure_drives for d in ds)
