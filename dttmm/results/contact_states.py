"""The contact spheres' forces, points and normals at a Result's samples (Result.contact_force,
contact_point, contact_normal; docs/contact.md), and the touches they make (Result.contacts)."""
import numpy as np

from ..elements.contact import BODY, CENTRE, NORMAL, RADIUS, contact_forces


def contact_states(model, result):
    """{"contact_force", "contact_point", "contact_normal"}: (T, N, 3) each, the model's contact
    spheres (Model.contacts) at the result's samples, by the contact law
    (elements/contact.py::contact_forces) from its bodies' input points, rotations and
    velocities; None each for a model without shapes."""
    rows = np.asarray(model.contacts)
    if not len(rows):
        return dict(contact_force=None, contact_point=None, contact_normal=None)
    body = rows[:, BODY].astype(np.int64)
    rot = result.rotation[:, body]                                  # (T, N, 3, 3)
    arm = np.einsum("tnij,nj->tni", rot, rows[:, CENTRE])   # A l_IP
    centre = result.position_input[:, body] + arm
    normal = np.broadcast_to(rows[:, NORMAL], centre.shape)
    to_point = arm - rows[:, RADIUS, None] * rows[:, NORMAL]
    velocity = (result.velocity_input[:, body]
                + np.cross(result.angular_velocity[:, body], to_point))
    force, _ = contact_forces(rows, centre, velocity)
    point = centre - rows[:, RADIUS, None] * rows[:, NORMAL]
    return dict(contact_force=force, contact_point=point, contact_normal=np.array(normal))


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
