"""Scene files' contact tables (docs/scenes.md, docs/contact.md): the keys of a ground's plane,
a body's shapes and their contact law, and their tables written from a model (its shapes read
back from its contact rows, Model.contacts)."""
from ..elements.contact import (AXES, BODY, CENTRE, HALF, LEVEL, NORMAL, OWN_DAMPING,
                                OWN_FRICTION, OWN_STICK_VELOCITY, OWN_STIFFNESS, RADIUS, ROLE,
                                SEGMENT, SOLID, SWEPT, Box, Capsule, Sphere,
                                restitution_of_damping)

PLANE_KEYS = {"normal": "vector", "point": "vector"}
CONTACT_KEYS = {"stiffness": "number", "contact_time": "number", "restitution": "number",
                "friction": "number", "stick_velocity": "number"}
# a shape's class and keys by its type
SHAPE_KEYS = {"sphere": (Sphere, {"type": "str", "radius": "number", "center": "vector"}),
              "capsule": (Capsule, {"type": "str", "radius": "number", "start": "vector",
                                    "end": "vector"}),
              "box": (Box, {"type": "str", "size": "vector", "center": "vector",
                            "rotation": "matrix"})}


def plane_table(model):
    """The ground's [ground.plane] table: its normal and a point of it, in the ground frame."""
    row = model.contacts[0]
    normal = model.ground_rotation.T @ row[NORMAL]
    point = model.ground_rotation.T @ (row[LEVEL] * row[NORMAL] - model.ground_position)
    return {"normal": normal.tolist(), "point": point.tolist()}


def contact_tables(model, k):
    """Body k's "shapes" (its spheres, capsules and boxes, read back from its contact rows:
    elements/contact.py's ROLE) and "contact" (its own law: the restitution its damping
    gives, to 10 digits) keys; {} without shapes."""
    rows = [row for row in model.contacts if int(row[BODY]) == k]
    if not rows:
        return {}
    shapes = []
    for r in rows:
        role = int(r[ROLE])
        if role == SWEPT and not r[SEGMENT].any():
            shapes.append({"type": "sphere", "radius": float(r[RADIUS]),
                           "center": r[CENTRE].tolist()})
        elif role == SWEPT:
            shapes.append({"type": "capsule", "radius": float(r[RADIUS]),
                           "start": r[CENTRE].tolist(), "end": (r[CENTRE] + r[SEGMENT]).tolist()})
        elif role == SOLID:
            shapes.append({"type": "box", "size": (2.0 * r[HALF]).tolist(),
                           "center": r[CENTRE].tolist(),
                           "rotation": r[AXES].reshape(3, 3).tolist()})
    row = rows[0]
    restitution = restitution_of_damping(row[OWN_DAMPING])
    return {"shapes": shapes,
            "contact": {"stiffness": float(row[OWN_STIFFNESS]),
                        "restitution": float(f"{restitution:.10g}"),
                        "friction": float(row[OWN_FRICTION]),
                        "stick_velocity": float(row[OWN_STICK_VELOCITY])}}
