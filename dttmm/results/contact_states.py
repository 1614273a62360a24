"""The contact spheres' forces, points and normals at a Result's samples (Result.contact_force,
contact_point, contact_normal; docs/contact.md), and the touches they make (Result.contacts)."""
import numpy as np

from ..elements.contact import (BODY, CENTRE, NORMAL, RADIUS, contact_forces, law_forces,
                                pair_law, touching_pairs)


def contact_states(model, result):
    """{"contact_force", "contact_point", "contact_normal"}: (T, N, 3) each, the model's contact
    spheres (Model.contacts) at the result's samples from its bodies' input points, rotations
    and velocities, by the contact law (elements/contact.py): each sphere's total force (the
    plane's and every other sphere's on it), and the point and normal of the one pushing
    hardest (the plane's where none pushes); None each for a model without shapes."""
    rows = np.asarray(model.contacts)
    if not len(rows):
        return dict(contact_force=None, contact_point=None, contact_normal=None)
    body = rows[:, BODY].astype(np.int64)
    rot = result.rotation[:, body]                                  # (T, N, 3, 3)
    arm = np.einsum("tnij,nj->tni", rot, rows[:, CENTRE])           # A l_IP
    centre = result.position_input[:, body] + arm
    omega = result.angular_velocity[:, body]
    v_centre = result.velocity_input[:, body] + np.cross(omega, arm)
    normal = np.array(np.broadcast_to(rows[:, NORMAL], centre.shape))
    offset = -rows[:, RADIUS, None] * normal
    force, _ = contact_forces(rows, centre, v_centre + np.cross(omega, offset))
    point = centre + offset
    push = np.einsum("tni,tni->tn", force, normal)
    total = force.copy()
    for i, j in touching_pairs(rows):
        d = centre[:, i] - centre[:, j]
        dist = np.linalg.norm(d, axis=1)
        delta = rows[i, RADIUS] + rows[j, RADIUS] - dist
        if not np.any(delta > 0.0):
            continue
        n = d / np.where(dist > 0.0, dist, 1.0)[:, None]
        off_i, off_j = -rows[i, RADIUS] * n, rows[j, RADIUS] * n
        velocity = (v_centre[:, i] + np.cross(omega[:, i], off_i)
                    - v_centre[:, j] - np.cross(omega[:, j], off_j))
        f = law_forces(*pair_law(rows[i], rows[j]), n, delta, velocity)
        total[:, i] += f
        total[:, j] -= f
        f_n = np.einsum("ti,ti->t", f, n)
        for c, off, sign in ((i, off_i, 1.0), (j, off_j, -1.0)):
            harder = f_n > push[:, c]
            point[harder, c] = centre[harder, c] + off[harder]
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
