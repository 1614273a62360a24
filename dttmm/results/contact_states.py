"""The contact rows' forces, points and normals at a Result's samples (Result.contact_force,
contact_point, contact_normal; docs/contact.md), and the touches they make (Result.contacts)."""
import numpy as np

from ..elements.contact import (AXES, BODY, CENTRE, NORMAL, RADIUS, SEGMENT, contact_forces,
                                law_forces, pair_geometry, pair_law, touching_pairs)


def contact_states(model, rotation, angular_velocity, position_input, velocity_input):
    """{"contact_force", "contact_point", "contact_normal"}: (T, N, 3) each, the model's contact
    rows (Model.contacts) at a run's samples from its bodies' rotations (T, n, 3, 3), angular
    velocities, input points and their velocities (T, n, 3), by the contact law
    (elements/contact.py): each row's total force (the plane's and every other body's on it),
    and the point and normal of the one pushing hardest (the plane's where none pushes); None
    each for a model without shapes."""
    rows = np.asarray(model.contacts)
    if not len(rows):
        return dict(contact_force=None, contact_point=None, contact_normal=None)
    body = rows[:, BODY].astype(np.int64)
    rot = rotation[:, body]                                  # (T, N, 3, 3)
    origin = position_input[:, body]
    centre = origin + np.einsum("tnij,nj->tni", rot, rows[:, CENTRE])      # A l_IP
    segment = np.einsum("tnij,nj->tni", rot, rows[:, SEGMENT])
    axes = np.einsum("tnij,njk->tnik", rot, rows[:, AXES].reshape(-1, 3, 3))
    omega = angular_velocity[:, body]

    def velocity(c, point):     # of row c's body's point at `point` (T, 3)
        return velocity_input[:, body[c]] + np.cross(omega[:, c], point - origin[:, c])

    normal = np.array(np.broadcast_to(rows[:, NORMAL], centre.shape))
    point = centre - rows[:, RADIUS, None] * normal
    v_point = np.stack([velocity(c, point[:, c]) for c in range(len(rows))], axis=1)
    force, _ = contact_forces(rows, centre, v_point)
    push = np.einsum("tni,tni->tn", force, normal)
    total = force.copy()
    for i, j in touching_pairs(rows):
        delta, n, p_i, p_j = pair_geometry(rows[i], rows[j], centre[:, i], segment[:, i],
                                           centre[:, j], segment[:, j], axes[:, j])
        if not np.any(delta > 0.0):
            continue
        *law, cap = pair_law(rows[i], rows[j])
        f = law_forces(*law, n, delta, velocity(i, p_i) - velocity(j, p_j), cap=cap)
        total[:, i] += f
        total[:, j] -= f
        f_n = np.einsum("ti,ti->t", f, n)
        for c, at, sign in ((i, p_i, 1.0), (j, p_j, -1.0)):
            harder = f_n > push[:, c]
            point[harder, c] = at[harder]
            normal[harder, c] = sign * n[harder]
            push[harder, c] = f_n[harder]
    return dict(contact_force=total, contact_point=point, contact_normal=normal)


def touches(t, contact_force):
    """Every touch of a contact sphere: (sphere, t_on, t_off) in time order, t_on and t_off
    the first and last samples of t it pushed at (t_off None while it pushes at the end); []
    for contact_force None (no shapes)."""
    if contact_force is None:
        return []
    out = []
    pushing = np.linalg.norm(contact_force, axis=2) > 0.0
    for c in range(pushing.shape[1]):
        edges = np.flatnonzero(np.diff(np.concatenate([[0], pushing[:, c].astype(int), [0]])))
        for start, stop in zip(edges[::2], edges[1::2]):
            out.append((c, float(t[start]),
                        None if stop == pushing.shape[0] else float(t[stop - 1])))
    return sorted(out, key=lambda c: (c[1], c[0]))
