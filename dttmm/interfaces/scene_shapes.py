"""Scene files' contact tables (docs/scenes.md, docs/contact.md): the keys of a ground's plane,
a body's shapes and their contact law, and their tables written from a model (its contact
spheres, Model.contacts, each as a sphere: a box's corners of radius 0)."""
from ..elements.contact import (BODY, CENTRE, DAMPING, FRICTION, LEVEL, NORMAL, RADIUS,
                                STICK_VELOCITY, STIFFNESS, Box, Capsule, Sphere,
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
    """Body k's "shapes" (every contact sphere as a sphere) and "contact" (its law: the
    restitution its damping gives, to 10 digits) keys; {} without shapes."""
    rows = [row for row in model.contacts if int(row[BODY]) == k]
    if not rows:
        return {}
    row = rows[0]
    restitution = restitution_of_damping(row[DAMPING])
    return {"shapes": [{"type": "sphere", "radius": float(r[RADIUS]),
                        "center": r[CENTRE].tolist()} for r in rows],
            "contact": {"stiffness": float(row[STIFFNESS]),
                        "restitution": float(f"{restitution:.10g}"),
                        "friction": float(row[FRICTION]),
                        "stick_velocity": float(row[STICK_VELOCITY])}}
