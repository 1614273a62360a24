"""Scene files: a model and its run in TOML (docs/scenes.md).

    scene = load_scene("pendulum.toml")          # scene.model, scene.run (simulate's options)
    save_scene(model, "copy.toml", run={...})    # and back: the same model's arrays

A scene has [model] (name, gravity, tip), [ground] (position, rotation, or a spin about a fixed
axis), one [[body]] table per body with its [body.joint] (how it hangs from its parent), loads
and drives from named profiles (dttmm/model/profiles.py), and [run] (t_end, dt and simulate's other
options).  Every mistake is reported with the file, the table and the key.
"""
import tomllib
from collections import namedtuple
from pathlib import Path

import numpy as np

from ..elements import (JointForce, JointMotion, PDTracking, SpringDamper)
from ..elements.beam import (ACCURATE, DAMPING_RATIO, EI_V, EI_W, FAMILY, FREQUENCY_CUTOFF, GJ,
                             EXACT, LENGTH,
                             LOAD_AXES, MASS_PER_LENGTH, MODES, PINNED, POLAR_PER_LENGTH,
                             STIFFENING, TORSION_MODES, AXIAL_MODES, EA)
from ..elements.kinds import (AXES, BEAM, BODY_KINDS, COORDINATE_0, JOINT_KIND, JOINT_KINDS,
                              RATE_0, RIGID, ROD, SCENE_TYPE, SLIDE, WITH_COORDINATES,
                              declared_body_kind, limit_of, unimplemented_body_kind)
from ..elements.contact import Contact, Plane
from ..elements.limits import JointLimit
from .scene_shapes import CONTACT_KEYS, PLANE_KEYS, SHAPE_KEYS, contact_tables, plane_table
from ..elements.strain_rod import (ROD_DAMPING, ROD_EA, ROD_EI_V, ROD_EI_W, ROD_GJ, ROD_JP,
                                   ROD_JV, ROD_JW, ROD_LENGTH, ROD_MODES, ROD_MU, ROD_STATIONS,
                                   ROD_STRETCH, ROD_TWIST)
from ..elements.drives import FORCE, MOTION, PD, SPRING_DAMPER
from ..elements.hinges import (BALL, C_ROTATION, C_TRANSLATION, DEFLECTION_0, DEFLECTION_RATE_0,
                               ELASTIC, FIXED, FREE, K_ROTATION, K_TRANSLATION, REST_ROTATION)
from ..elements.rigid_body import INERTIA_INPUT, MASS, TO_MASS_CENTER, TO_OUTPUT
from ..model.loop_kinematics import start_attachment
from ..model.model import Ground, Model, PrescribedMotion, children_of
from ..model.system import System
from ..model.profiles import Profile, ProfileForce, profile

Scene = namedtuple("Scene", ["name", "model", "run", "path"])


class SceneError(ValueError):
    """A scene file that cannot be read: the message names the file, the table and the key."""


# the keys each table takes: key -> kind of value ("number", "int", "bool", "str", "vector",
# "pair", "matrix", "stiffness": a number, 3 numbers or a 3 x 3 matrix, "profile", "table",
# "numbers<n>": n numbers, "drives<n>": a list of n drive tables)
_MODEL = {"name": "str", "gravity": "vector", "tip": "str"}
_GROUND = {"position": "vector", "rotation": "matrix", "spin": "table", "plane": "table"}
_SPIN = {"axis": "vector", "angle": "profile", "position": "vector"}
_RIGID = {"name": "str", "type": "str", "mass": "number", "inertia": "stiffness",
          "inertia_about": "str", "to_mass_center": "vector", "to_output": "vector",
          "rotation": "matrix", "angular_velocity": "vector", "points": "table",
          "force": "profile", "torque": "profile", "joint": "table", "shapes": "bodies",
          "contact": "table"}
_BEAM = {"name": "str", "type": "str", "length": "number", "mass_per_length": "number",
         "density": "number", "area": "number", "bending_stiffness": "pair",
         "polar_inertia_per_length": "number", "modes_per_plane": "modes",
         "frequency_cutoff": "number",
         "damping_ratio": "number", "mode_family": "str", "force_mode_family": "bool",
         "stiffening": "stiffening", "torsion_modes": "int", "torsional_stiffness": "number",
         "load_axes": "str", "axial_modes": "int", "axial_stiffness": "number",
         "initial_modal_coordinates": "list",
         "end_force": "profile", "end_torque": "profile", "distributed_load": "profile",
         "initial_modal_velocities": "list",
         "rotation": "matrix", "angular_velocity": "vector", "joint": "table"}
_ROD = {"name": "str", "type": "str", "length": "number", "mass_per_length": "number",
        "bending_stiffness": "pair", "polar_inertia_per_length": "number",
        "rotary_inertia_per_length": "pair", "strain_modes": "int", "stations": "int",
        "twist": "bool", "stretch": "bool", "torsional_stiffness": "number",
        "axial_stiffness": "number", "damping": "number", "initial_strain": "list",
        "initial_strain_rate": "list", "rotation": "matrix", "angular_velocity": "vector",
        "joint": "table"}
# each body kind's keys and required keys, by code; by scene type (its declaration's, elements/
# kinds.py): its class, keys and required keys
_BODY_KEYS = {RIGID: (_RIGID, ("mass", "inertia", "inertia_about")),
              BEAM: (_BEAM, ("length", "bending_stiffness", "polar_inertia_per_length")),
              ROD: (_ROD, ("length", "bending_stiffness", "mass_per_length",
                           "polar_inertia_per_length"))}
_BODY_KINDS = {kind.scene: (kind.cls, *_BODY_KEYS[kind.code]) for kind in BODY_KINDS
               if kind.code in _BODY_KEYS}
_BODY_TYPES = ", ".join(f"'{t}'" for t in list(_BODY_KINDS)[:-1]) + f" or '{list(_BODY_KINDS)[-1]}'"
_JOINT_COMMON = {"type": "str", "name": "str", "parent": "str", "at": "point"}
_CLOSE_COMMON = {"type": "str", "name": "str", "a": "str", "b": "str", "at_a": "point",
                 "at_b": "point"}
# the joints' own keys: those without coordinates here, a joint with coordinates' from its
# declaration (elements/kinds.py: its axes, then its coordinates' values, rates and drives, one
# each for a joint of one coordinate, else lists of one per coordinate), under its scene type
_OWN_KEYS = {
    BALL: {},
    FIXED: {"rotation": "matrix"},
    ELASTIC: {"translational_stiffness": "stiffness", "rotational_stiffness": "stiffness",
              "translational_damping": "stiffness", "rotational_damping": "stiffness",
              "rotation": "matrix", "deflection": "vector"},
    FREE: {"position": "vector", "velocity": "vector"},
}


def _coordinate_keys(kind):
    """A joint with coordinates' keys (Kind.axes and Kind.arguments)."""
    count = len(kind.coordinates)
    values, rates, drives = kind.arguments
    one = count == 1
    return dict({axis: "vector" for axis in kind.axes},
                **{values: "number" if one else f"numbers{count}",
                   rates: "number" if one else f"numbers{count}",
                   drives: "table" if one else f"drives{count}",
                   "limits": "limit" if one else f"limits{count}"})


_JOINTS = {k.scene: (k.cls, _coordinate_keys(k) if k.code in WITH_COORDINATES
                     else _OWN_KEYS[k.code]) for k in JOINT_KINDS}
_DRIVES = ("spring_damper", "force", "motion", "pd", "none")
_RUN = {"t_end": "number", "dt": "number", "method": "str", "scheme": "str",
        "rho_inf": "number", "newton_iterations": "int", "newton_tol": "number",
        "record_every": "int", "record_dt": "number", "max_step_error": "number",
        "full_state": "bool", "richardson": "runs", "rtol": "number", "atol": "number",
        "max_energy_error": "number", "hold_energy": "bool"}


def load_scene(path):
    """Read a scene file (TOML; docs/scenes.md).

    Parameters
    ----------
    path : str or path-like
        The scene file.

    Returns
    -------
    Scene
        A named tuple (name, model, run, path): the [model] table's name (default: the file's
        stem), the built ``Model``, the [run] table as a dict (simulate's options: t_end, dt
        in s, method, scheme, ...; e.g. ``simulate(scene.model, **scene.run)``) and the path
        as a string.

    Raises
    ------
    SceneError
        (a ValueError) naming the file, the table and the key for anything wrong in it: a
        file that cannot be read or is not valid TOML, an unknown key or a value of the wrong
        kind, a missing key, a bad profile, and every check of ``System.build`` (naming the
        element and the argument).

    Examples
    --------
    >>> import dttmm
    >>> from dttmm.interfaces.scene import load_scene
    >>> scene = load_scene("pendulum.toml")  # doctest: +SKIP
    >>> result = dttmm.simulate(scene.model, **scene.run)  # doctest: +SKIP
    """
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except OSError as err:
        raise SceneError(f"{path}: cannot read the scene file ({err.strerror})") from None
    except tomllib.TOMLDecodeError as err:
        raise SceneError(f"{path}: not valid TOML: {err}") from None
    except UnicodeDecodeError as err:
        raise SceneError(f"{path}: not a text file (a scene is TOML, UTF-8 text): byte "
                         f"{err.start} cannot be read") from None
    return scene_from_dict(data, str(path))


def scene_from_dict(data, where="scene"):
    """The Scene a parsed scene file describes (load_scene without the file).

    Parameters
    ----------
    data : dict
        The parsed TOML (as ``tomllib.load`` or ``scene_of`` gives it).
    where : str, optional
        How messages name the source (default "scene"); its stem is the default name.

    Returns
    -------
    Scene
        As ``load_scene``.

    Raises
    ------
    SceneError
        As ``load_scene``.
    """
    _keys(data, {"model": "table", "ground": "table", "body": "bodies", "close": "bodies",
                 "run": "table"}, where, "the file")
    header = data.get("model", {})
    _keys(header, _MODEL, where, "[model]")
    tip = header.get("tip", "free")
    if tip not in ("free", "ball"):
        raise SceneError(f"{where}: [model] key 'tip': 'free' or 'ball', got {tip!r}")
    system = System(gravity=header.get("gravity", (0.0, -9.81, 0.0)),
                    ground=_ground(data.get("ground", {}), where))
    bodies = data.get("body")
    if not bodies:
        raise SceneError(f"{where}: no bodies: add a [[body]] table per body")
    for i, table in enumerate(bodies):
        body, joint, parent, at = _body(table, i, where)
        system.add(body, joint, parent=parent, at=at)
    for i, table in enumerate(data.get("close", [])):
        label = f"[[close]] {i + 1}"
        _keys(table, dict(_CLOSE_COMMON, **_JOINTS.get(table.get("type"), (None, {}))[1]),
              where, label)
        for key in ("a", "type"):
            if key not in table:
                raise SceneError(f"{where}: {label} needs the key '{key}'")
        joint = _joint(table, where, label, _CLOSE_COMMON)[0]
        system.close(joint, table["a"], table.get("b", "ground"), at_a=table.get("at_a"),
                     at_b=table.get("at_b"))
    run = data.get("run", {})
    _keys(run, _RUN, where, "[run]")
    try:
        # the run's step and length: a beam with modes_per_plane = "auto" and no
        # frequency_cutoff derives its cutoff from them (build_chain)
        model = system.build(tip=tip, step=run.get("dt"), duration=run.get("t_end"))
    except ValueError as err:
        raise SceneError(f"{where}: {err}") from None
    return Scene(name=header.get("name", Path(where).stem), model=model, run=dict(run),
                 path=where)


def _ground(table, where):
    _keys(table, _GROUND, where, "[ground]")
    spin = table.get("spin")
    plane = None
    if "plane" in table:
        _keys(table["plane"], PLANE_KEYS, where, "[ground.plane]")
        plane = Plane(**table["plane"])
    if spin is None:
        return Ground(position=table.get("position", (0.0, 0.0, 0.0)),
                      rotation=table.get("rotation"), plane=plane)
    if plane is not None:
        raise SceneError(f"{where}: [ground]: a plane on a spinning ground does not touch "
                         f"bodies yet")
    if "rotation" in table:
        raise SceneError(f"{where}: [ground]: give rotation or spin, not both")
    _keys(spin, _SPIN, where, "[ground.spin]")
    for key in ("axis", "angle"):
        if key not in spin:
            raise SceneError(f"{where}: [ground.spin] needs the key '{key}'")
    angle = _profile(spin["angle"], where, "[ground.spin] key 'angle'")
    position = spin.get("position", table.get("position", (0.0, 0.0, 0.0)))
    try:
        motion = PrescribedMotion.spin_about_axis(spin["axis"], angle, angle.rate,
                                                  angle.acceleration, position=position)
    except (ValueError, ZeroDivisionError) as err:
        raise SceneError(f"{where}: [ground.spin]: {err}") from None
    motion.scene = {"axis": list(map(float, spin["axis"])), "angle": angle.spec(),
                    "position": list(map(float, position))}
    return Ground(motion=motion)


def _body(table, i, where):
    """(body, joint, parent name or None, attachment point) of the i-th [[body]] table."""
    name = table.get("name")
    label = f"[[body]] {i + 1}" + (f" ('{name}')" if isinstance(name, str) else "")
    kind = table.get("type")
    if kind not in _BODY_KINDS:
        raise SceneError(f"{where}: {label} key 'type': {_BODY_TYPES}, got {kind!r}"
                         if "type" in table else
                         f"{where}: {label} needs the key 'type' ({_BODY_TYPES})")
    element, schema, required = _BODY_KINDS[kind]
    _keys(table, schema, where, label)
    for key in required:
        if key not in table:
            raise SceneError(f"{where}: {label} needs the key '{key}'")
    if "joint" not in table:
        raise SceneError(f"{where}: {label} needs a [body.joint] table (how it hangs from its "
                         f"parent: type = one of {', '.join(_JOINTS)})")
    args = {k: v for k, v in table.items() if k not in ("type", "joint")}
    for key in ("force", "torque", "end_force", "end_torque", "distributed_load"):
        if key in args:
            args[key] = _profile(args[key], where, f"{label} key '{key}'")
    if "points" in args:
        for point, vec in args["points"].items():
            _value(vec, "vector", where, f"{label} key 'points.{point}'")
    if "shapes" in args:
        args["shapes"] = [_shape(t, where, f"{label} shapes[{j}]")
                          for j, t in enumerate(args["shapes"])]
    if "contact" in args:
        _keys(args["contact"], CONTACT_KEYS, where, f"{label} [body.contact]")
        args["contact"] = Contact(**args["contact"])
    try:
        body = element(**args)
        body.validated(i)
    except TypeError as err:
        raise SceneError(f"{where}: {label}: {err}") from None
    except ValueError as err:
        raise SceneError(f"{where}: {label}: {err}") from None
    joint, parent, at = _joint(table["joint"], where, f"{label} [body.joint]")
    return body, joint, parent, at


def _shape(table, where, label):
    """A body's shape from its table: type = "sphere", "capsule" or "box" and its keys."""
    kind = table.get("type") if isinstance(table, dict) else None
    if kind not in SHAPE_KEYS:
        raise SceneError(f"{where}: {label} key 'type': one of {', '.join(SHAPE_KEYS)}, got "
                         f"{kind!r}")
    cls, keys = SHAPE_KEYS[kind]
    _keys(table, keys, where, label)
    try:
        return cls(**{k: v for k, v in table.items() if k != "type"})
    except TypeError as err:
        raise SceneError(f"{where}: {label}: {err}") from None


def _joint(table, where, label, common=_JOINT_COMMON):
    kind = table.get("type")
    if kind not in _JOINTS:
        raise SceneError(f"{where}: {label} key 'type': one of {', '.join(_JOINTS)}, got "
                         f"{kind!r}" if "type" in table else
                         f"{where}: {label} needs the key 'type' (one of {', '.join(_JOINTS)})")
    cls, own = _JOINTS[kind]
    _keys(table, dict(common, **own), where, label)
    args = {k: v for k, v in table.items() if k not in common or k == "name"}
    for key, value in own.items():          # (a joint with coordinates' drives and lists)
        if key not in args:
            continue
        if value == "table":
            args[key] = _drive(args[key], where, f"{label} key '{key}'")
        elif value.startswith("drives"):
            args[key] = tuple(_drive(d, where, f"{label} key '{key}[{j}]'")
                              for j, d in enumerate(args[key]))
        elif value.startswith("numbers"):
            args[key] = tuple(args[key])
        elif value == "limit":
            args[key] = _limit(args[key], where, f"{label} key '{key}'")
        elif value.startswith("limits"):
            args[key] = tuple(_limit(d, where, f"{label} key '{key}[{j}]'")
                              for j, d in enumerate(args[key]))
    try:
        joint = cls(**args)
        joint.validated()
    except ValueError as err:
        raise SceneError(f"{where}: {label}: {err}") from None
    parent = table.get("parent", "ground")
    return joint, (None if parent == "ground" else parent), table.get("at")


def _limit(table, where, label):
    """A JointLimit from its table {lower, upper, stiffness, damping} ({}: none)."""
    if not isinstance(table, dict):
        raise SceneError(f"{where}: {label}: a table with keys lower, upper, stiffness, damping "
                         f"({{}} for none), got {table!r}")
    if not table:
        return None
    unknown = set(table) - {"lower", "upper", "stiffness", "damping"}
    if unknown:
        raise SceneError(f"{where}: {label}: unknown key '{sorted(unknown)[0]}' (a limit takes "
                         f"lower, upper, stiffness, damping)")
    return JointLimit(**table)


def _drive(table, where, label):
    if not isinstance(table, dict) or table.get("type") not in _DRIVES:
        raise SceneError(f"{where}: {label}: a table with type = one of {', '.join(_DRIVES)}, "
                         f"got {table!r}")
    kind = table["type"]
    rest = {k: v for k, v in table.items() if k != "type"}
    if kind == "none":
        return None
    if kind == "spring_damper":
        _keys(rest, {"stiffness": "number", "damping": "number", "rest": "number"}, where, label)
        if "stiffness" not in rest:
            raise SceneError(f"{where}: {label}: a spring_damper drive needs the key 'stiffness'")
        return SpringDamper(**rest)
    if kind == "pd":            # kp (target - q) + kd (target' - q') + feedforward, profiles
        _keys(rest, {"kp": "number", "kd": "number", "target": "profile",
                     "feedforward": "profile"}, where, label)
        for key in ("kp", "kd", "target"):
            if key not in rest:
                raise SceneError(f"{where}: {label}: a pd drive needs the key '{key}'")
        target = _profile(rest["target"], where, f"{label} key 'target'")
        feedforward = (_profile(rest["feedforward"], where, f"{label} key 'feedforward'")
                       if "feedforward" in rest else None)
        return PDTracking(kp=rest["kp"], kd=rest["kd"], target=target, target_rate=target.rate,
                          feedforward=feedforward)
    prof = _profile(rest, where, label)
    if kind == "force":
        return JointForce(ProfileForce(prof))
    return JointMotion(position=prof, velocity=prof.rate, acceleration=prof.acceleration)


def _profile(spec, where, label):
    try:
        return profile(spec, label)
    except ValueError as err:
        raise SceneError(f"{where}: {err}") from None


def _keys(table, schema, where, label):
    if not isinstance(table, dict):
        raise SceneError(f"{where}: {label} must be a table, got {table!r}")
    for key, value in table.items():
        if key not in schema:
            raise SceneError(f"{where}: {label}: unknown key '{key}' (it takes "
                             f"{', '.join(schema)})")
        _value(value, schema[key], where, f"{label} key '{key}'")


def _value(value, kind, where, label):
    def number(x):
        return isinstance(x, (int, float)) and not isinstance(x, bool)

    ok = {"number": number(value), "int": isinstance(value, int) and not isinstance(value, bool),
          "bool": isinstance(value, bool), "str": isinstance(value, str),
          "vector": isinstance(value, list) and len(value) == 3 and all(map(number, value)),
          "pair": number(value) or (isinstance(value, list) and len(value) == 2
                                    and all(map(number, value))),
          "list": isinstance(value, list) and all(map(number, value)),
          "matrix": isinstance(value, list) and len(value) == 3 and all(
              isinstance(r, list) and len(r) == 3 and all(map(number, r)) for r in value),
          "table": isinstance(value, dict), "bodies": isinstance(value, list),
          "drives": isinstance(value, list) and len(value) == 2,
          **{f"numbers{n}": isinstance(value, list) and len(value) == n
             and all(map(number, value)) for n in (2, 3)},
          **{f"drives{n}": isinstance(value, list) and len(value) == n for n in (2, 3)},
          "limit": isinstance(value, dict),
          **{f"limits{n}": isinstance(value, list) and len(value) == n
             and all(isinstance(x, dict) for x in value) for n in (2, 3)},
          "profile": number(value) or isinstance(value, dict)}
    ok["point"] = ok["str"] or ok["vector"]
    ok["stiffness"] = number(value) or ok["vector"] or ok["matrix"]
    ok["modes"] = ok["int"] or value == "auto"
    ok["runs"] = ok["bool"] or ok["int"]
    ok["stiffening"] = ok["bool"] or value == "exact"
    if not ok[kind]:
        what = {"number": "a number", "int": "an integer", "bool": "true or false",
                "str": "a string", "vector": "3 numbers", "pair": "a number or 2 numbers",
                "list": "a list of numbers", "matrix": "a 3 x 3 matrix (3 rows of 3)",
                "table": "a table", "bodies": "an array of tables ([[body]])",
                "drives": "a list of two drive tables", "profile": "a number or a profile table",
                "numbers2": "2 numbers", "numbers3": "3 numbers",
                "drives2": "a list of 2 drive tables", "drives3": "a list of 3 drive tables",
                "stiffness": "a number, 3 numbers or a 3 x 3 matrix",
                "modes": 'an integer or "auto"', "stiffening": 'true, false or "exact"',
                "runs": "true, false or the number of runs (2 to 4)"}[kind]
        raise SceneError(f"{where}: {label}: {what}, got {value!r}")


# --- writing ---------------------------------------------------------------------------------

def scene_of(model, run=None, name=None):
    """The scene (a dict, as load_scene reads it) of a model: every body, joint, load and drive
    from the model's arrays, so that it builds the same model again.

    Loads, drives and ground motion must be profiles (dttmm/model/profiles.py; ``ProfileForce`` for
    a joint force, a ground spin read from a scene file); a Python function cannot be written.
    A rigid body's inertia is written about its input point, a beam's mode family resolved
    ("pinned" or "clamped", with force_mode_family where needed), the initial rotations of
    bodies behind ball, elastic and coordinate joints, and a rigid body's named points in use
    as "p1", "p2", ... up to the largest index in use, in the order of its points (a point no
    joint uses, before one that is used, is written as a stand-in at the input point: the
    model's arrays come back the same).

    Parameters
    ----------
    model : Model
        The model written.
    run : dict, optional
        simulate's options (t_end, dt in s, method, scheme, ...), written as the [run] table;
        None or empty (default): no [run] table.
    name : str, optional
        The [model] table's name (default "model").

    Returns
    -------
    dict
        The scene: "model", "ground", "body" (a list of body tables, each with its "joint"
        table) and, with run, "run".

    Raises
    ------
    ValueError
        A model that is not a Model; a ground motion, force, torque or drive given as a Python
        function rather than a profile (naming the body or joint).
    """
    if not isinstance(model, Model):
        raise ValueError("save_scene: model must be a Model")
    data = {"model": {"name": name or "model", "gravity": model.gravity.tolist(),
                      "tip": "ball" if model.tip_pinned else "free"}}
    if model.ground_motion is not None:
        spec = getattr(model.ground_motion, "scene", None)
        if spec is None:
            raise ValueError("save_scene: the ground's motion is a PrescribedMotion of Python "
                             "functions; only a spin from a scene file ([ground.spin]) can be "
                             "written")
        data["ground"] = {"spin": spec}
    else:
        data["ground"] = {"position": model.ground_position.tolist(),
                          "rotation": model.ground_rotation.tolist()}
        if len(model.contacts):     # the plane, in the ground frame
            data["ground"]["plane"] = plane_table(model)
    offsets = model.mode_offsets
    children = children_of(model.parent)
    named = [sorted({int(model.attachment[c]) for c in children[k] if model.attachment[c]})
             for k in range(model.n_bodies)]
    bodies = []
    for k in range(model.n_bodies):
        who = f"body '{model.body_names[k]}'"
        kind = int(model.hinge_kind[k])
        table = {"name": model.body_names[k]}
        body = declared_body_kind(model.body_kind[k], f"save_scene: {who}")
        # a beam's or rod's own coordinates and rates at t = 0, under its class's names
        for key, values in zip(body.arguments,
                               (model.initial_modal_coordinates, model.initial_modal_velocities)):
            if np.any(values[offsets[k]:offsets[k + 1]]):
                table[key] = values[offsets[k]:offsets[k + 1]].tolist()
        if body.code not in _BODY_TABLES:
            raise unimplemented_body_kind(body.code, f"save_scene: {who}", "scene files")
        table["type"] = body.scene
        table.update(_BODY_TABLES[body.code](model, k, who, children, named))
        if kind in (BALL, ELASTIC, FREE):    # (else the joint sets them)
            table["rotation"] = model.initial_rotation[k].tolist()
            table["angular_velocity"] = model.initial_angular_velocity[k].tolist()
        elif kind in WITH_COORDINATES:       # (its R0 read again from it; w from the rates)
            table["rotation"] = model.initial_rotation[k].tolist()
        table["joint"] = _joint_table(model, k, who)
        bodies.append(table)
    data["body"] = bodies
    if model.n_closures and not model.tip_pinned:
        data["close"] = [_close_table(model, c) for c in range(model.n_closures)]
    if run:
        data["run"] = dict(run)
    return data


def _profiles(model, k, who, loads):
    """{key: its profile's spec} of body k's applied loads (key, the load or None) that are
    given; a Python function cannot be written."""
    table = {}
    for key, f in loads:
        if f is not None:
            if not isinstance(f, Profile):
                raise ValueError(f"save_scene: {who}'s {key} is a Python function; "
                                 f"only profiles (dttmm.model.profiles) can be written")
            table[key] = f.spec()
    return table


def _rigid_table(model, k, who, children, named):
    """A rigid body's keys (its inertia about its input point, its named points in use: named[k]
    their indices; scene_of)."""
    p = model.body_params[k]
    table = dict(mass=p[MASS], inertia=p[INERTIA_INPUT].reshape(3, 3).tolist(),
                 inertia_about="input", to_mass_center=p[TO_MASS_CENTER].tolist(),
                 to_output=p[TO_OUTPUT].tolist())
    if named[k]:        # p1 .. p(largest index in use), so that the indices stay
        used = {int(model.attachment[c]): model.attachment_point[c].tolist()
                for c in children[k] if model.attachment[c]}
        table["points"] = {f"p{j}": used.get(j, [0.0, 0.0, 0.0])   # (unused: a stand-in)
                           for j in range(1, max(named[k]) + 1)}
    table.update(_profiles(model, k, who, (("force", model.forces[k]),
                                           ("torque", model.torques[k]))))
    table.update(contact_tables(model, k))      # (its shapes and their law, if any)
    return table


def _beam_table(model, k, who, children, named):
    """A beam's keys from its row of Model.beam_params (elements/beam.py): its mode family
    resolved, with force_mode_family where needed (scene_of)."""
    row = model.beam_params[k]
    m = int(row[MODES])
    ball_ends = model.hinge_kind[k] == BALL and (not children[k] or all(
        model.hinge_kind[c] == BALL for c in children[k]))
    table = dict(length=row[LENGTH], mass_per_length=row[MASS_PER_LENGTH],
                 bending_stiffness=[row[EI_V], row[EI_W]],
                 polar_inertia_per_length=row[POLAR_PER_LENGTH], modes_per_plane=m,
                 damping_ratio=row[DAMPING_RATIO],
                 mode_family="pinned" if row[FAMILY] == PINNED else "clamped")
    if row[FAMILY] != PINNED and ball_ends:
        table["force_mode_family"] = True
    table["stiffening"] = ("exact" if row[STIFFENING] == EXACT   # (on by default)
                           else bool(row[STIFFENING]))
    if row[TORSION_MODES]:
        table["torsion_modes"] = int(row[TORSION_MODES])
    if row[GJ] > 0.0:
        table["torsional_stiffness"] = row[GJ]
    if row[LOAD_AXES]:
        table["load_axes"] = "body"
    if row[AXIAL_MODES]:
        table["axial_modes"] = int(row[AXIAL_MODES])
    if row[EA] > 0.0:
        table["axial_stiffness"] = row[EA]
    if row[FREQUENCY_CUTOFF] > 0.0:     # "auto": the same count when built again
        table.update(modes_per_plane="auto", frequency_cutoff=row[FREQUENCY_CUTOFF])
    elif row[FREQUENCY_CUTOFF] == ACCURATE:     # the default: counted again the same
        del table["modes_per_plane"]
    table.update(_profiles(model, k, who, (("end_force", model.forces[k]),
                                           ("end_torque", model.torques[k]),
                                           ("distributed_load", model.line_loads[k]))))
    return table


def _rod_table(model, k, who, children, named):
    """A strain rod's keys from its row of Model.rod_params (elements/strain_rod.py)."""
    row = model.rod_params[k]
    table = dict(length=row[ROD_LENGTH], mass_per_length=row[ROD_MU],
                 bending_stiffness=[row[ROD_EI_V], row[ROD_EI_W]],
                 polar_inertia_per_length=row[ROD_JP],
                 rotary_inertia_per_length=[row[ROD_JV], row[ROD_JW]],
                 strain_modes=int(row[ROD_MODES]), stations=int(row[ROD_STATIONS]),
                 damping=row[ROD_DAMPING])
    if row[ROD_TWIST]:
        table.update(twist=True, torsional_stiffness=row[ROD_GJ])
    if row[ROD_STRETCH]:
        table.update(stretch=True, axial_stiffness=row[ROD_EA])
    return table


# each body kind's writer of its keys, by code (a kind of elements/kinds.py's BODY_KINDS with a
# scene type needs one; tests/test_scenes.py checks that every one has it)
_BODY_TABLES = {RIGID: _rigid_table, BEAM: _beam_table, ROD: _rod_table}


def _close_table(model, c):
    """A [[close]] table of closing joint c (docs/loops.md): its kind, sides, points and axes
    (its rest rotation is read again from the frames at t = 0; an elastic hinge's is written)."""
    kind = int(model.closure_kind[c])
    h = model.closure_params[c]
    table = {"type": SCENE_TYPE[kind], "name": model.closure_names[c]}
    if kind == ELASTIC:         # its springs, and its rest rotation as built
        table.update(translational_stiffness=h[K_TRANSLATION].reshape(3, 3).tolist(),
                     rotational_stiffness=h[K_ROTATION].reshape(3, 3).tolist(),
                     translational_damping=h[C_TRANSLATION].reshape(3, 3).tolist(),
                     rotational_damping=h[C_ROTATION].reshape(3, 3).tolist(),
                     rotation=h[REST_ROTATION].reshape(3, 3).tolist())
    for s, side in enumerate("ab"):
        k = int(model.closure_body[c, s])
        table[side] = "ground" if k < 0 else model.body_names[k]
        local = model.closure_point[c, s]
        if k < 0:
            point = model.ground_position + model.ground_rotation @ local
        elif model.closure_on_end[c, s]:
            point = "output"
        else:
            point = local
        table[f"at_{side}"] = point if isinstance(point, str) else np.asarray(point).tolist()
    if kind in WITH_COORDINATES:     # its axes, its turns' angles (slides: from the points)
        drives = model.closure_drives[c] if model.closure_drives else ()
        table.update(_coordinate_table(JOINT_KIND[kind], h, drives,
                                       f"closing joint '{model.closure_names[c]}'", True))
    return table


def _coordinate_table(kind, h, drives, who, closing=False):
    """A joint with coordinates' keys (its declaration's names, elements/kinds.py): its axes,
    its coordinates' values and rates at t = 0 and its drives (a closing joint: its turns'
    values where not 0, no rates (they start at 0), drives where any)."""
    count = len(kind.coordinates)
    values_key, rates_key, drives_key = kind.arguments
    table = {name: h[AXES[slot]].tolist() for slot, name in enumerate(kind.axes)}
    values = h[COORDINATE_0][:count].tolist()
    if closing:                     # a slide's value: measured between its points again
        values = [0.0 if c.motion == SLIDE else v for c, v in zip(kind.coordinates, values)]
    if not closing or any(values):
        table[values_key] = values[0] if count == 1 else values
    if not closing:
        rates = h[RATE_0][:count].tolist()
        table[rates_key] = rates[0] if count == 1 else rates
    written = [_drive_table(d, who) for d in (list(drives) + [None] * count)[:count]]
    if count == 1:
        if written[0]["type"] != "none":
            table[drives_key] = written[0]
    elif not closing or any(d is not None for d in drives):
        table[drives_key] = written
    limits = [_limit_table(limit_of(h, i)) for i in range(count)]
    if not closing and any(limits):
        table["limits"] = limits[0] if count == 1 else limits
    return table


def _limit_table(limit):
    """A coordinate's end stops as a scene table ({} for none; an infinite bound left out)."""
    lower, upper, stiffness, damping = (float(x) for x in limit)
    if stiffness == 0.0:
        return {}
    table = {"lower": lower, "upper": upper, "stiffness": stiffness, "damping": damping}
    return {k: v for k, v in table.items() if np.isfinite(v)}


def _joint_table(model, k, who):
    kind = int(model.hinge_kind[k])
    h = model.hinge_params[k]
    p = model.parent[k]
    table = {"type": SCENE_TYPE[kind],
             "name": model.hinge_names[k],
             "parent": "ground" if p < 0 else model.body_names[p]}
    if model.attachment[k]:
        table["at"] = f"p{int(model.attachment[k])}"
    elif p < 0 and model.attachment_point[k].any():     # a root's place on the ground
        table["at"] = model.attachment_point[k].tolist()
    rest = h[REST_ROTATION].reshape(3, 3)
    if kind == FIXED:
        table["rotation"] = rest.tolist()
    elif kind == ELASTIC:
        table.update(translational_stiffness=h[K_TRANSLATION].reshape(3, 3).tolist(),
                     rotational_stiffness=h[K_ROTATION].reshape(3, 3).tolist(),
                     translational_damping=h[C_TRANSLATION].reshape(3, 3).tolist(),
                     rotational_damping=h[C_ROTATION].reshape(3, 3).tolist(),
                     rotation=rest.tolist())
        if np.any(h[DEFLECTION_0]):
            table["deflection"] = h[DEFLECTION_0].tolist()
    elif kind == FREE:      # as given: the position in the parent's frame (the world's for
        _, v_att, frame, _ = start_attachment(model, k)     # the ground), the velocity absolute
        frame = np.eye(3) if p < 0 else frame
        table.update(position=(frame.T @ h[DEFLECTION_0]).tolist(),
                     velocity=(h[DEFLECTION_RATE_0] + v_att).tolist())
    elif kind in WITH_COORDINATES:
        table.update(_coordinate_table(JOINT_KIND[kind], h, model.drives[k], who))
    return table


def _drive_table(d, who):
    if d is None:
        return {"type": "none"}
    if d["kind"] == SPRING_DAMPER:
        return {"type": "spring_damper", "stiffness": d["stiffness"], "damping": d["damping"],
                "rest": d["rest"]}
    if d["kind"] == FORCE and isinstance(d["function"], ProfileForce):
        return dict(type="force", **d["function"].profile.spec())
    if d["kind"] == MOTION and isinstance(d["function"][0], Profile):
        return dict(type="motion", **d["function"][0].spec())
    target, _, feedforward = d["function"] if d["kind"] == PD else (None, None, None)
    if isinstance(target, Profile) and (feedforward is None or isinstance(feedforward, Profile)):
        return dict(type="pd", kp=d["stiffness"], kd=d["damping"], target=target.spec(),
                    **({} if feedforward is None else {"feedforward": feedforward.spec()}))
    raise ValueError(f"save_scene: the drive of the joint before {who} is a Python function; "
                     f"only profiles (dttmm.model.profiles) can be written")


def save_scene(model, path, run=None, name=None):
    """Write a model (and optionally simulate's options, run) to a scene file.

    Loading it builds the same model's arrays (``scene_of``: what is written, and what
    cannot be).

    Parameters
    ----------
    model : Model
        The model written.
    path : str or path-like
        The TOML file (replaced if it exists).
    run : dict, optional
        simulate's options (t_end, dt in s, method, scheme, ...) for the [run] table.
    name : str, optional
        The [model] table's name (default "model").

    Raises
    ------
    ValueError
        As ``scene_of``: a model that is not a Model, or loads, drives or ground motion that
        are Python functions rather than profiles.
    TypeError
        A value in run that TOML cannot hold (e.g. None).

    Examples
    --------
    >>> import dttmm
    >>> from dttmm.interfaces.scene import load_scene, save_scene
    >>> rod = dttmm.RigidBody(mass=1.0, inertia=[1e-4, 1 / 12, 1 / 12],
    ...                       inertia_about="mass_center", to_mass_center=[0.5, 0, 0],
    ...                       to_output=[1.0, 0, 0])
    >>> model = dttmm.build_chain([dttmm.BallJoint(), rod])
    >>> save_scene(model, "rod.toml", run={"t_end": 1.0, "dt": 1e-3})  # doctest: +SKIP
    >>> load_scene("rod.toml").run  # doctest: +SKIP
    {'t_end': 1.0, 'dt': 0.001}
    """
    Path(path).write_text(to_toml(scene_of(model, run, name)))


def to_toml(data):
    """TOML text of a scene dict (tables, arrays of tables, numbers, strings, lists, inline
    tables for profiles and drives); floats written exactly (repr)."""
    lines = []

    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (int, np.integer)):
            return str(int(v))
        if isinstance(v, (float, np.floating)):
            return repr(float(v))
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, (list, tuple, np.ndarray)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        raise TypeError(f"to_toml: cannot write {type(v).__name__}")

    def table(name, t, array=False):
        lines.append(f"\n[[{name}]]" if array else f"\n[{name}]")
        nested = []
        for k, v in t.items():
            if isinstance(v, dict) and k in ("joint", "spin", "points"):
                nested.append((k, v))
            else:
                lines.append(f"{k} = {value(v)}")
        for k, v in nested:
            table(f"{name}.{k}", v)

    for key in ("model", "ground"):
        if key in data:
            table(key, data[key])
    for body in data.get("body", []):
        table("body", body, array=True)
    for closing in data.get("close", []):
        table("close", closing, array=True)
    if "run" in data:
        table("run", data["run"])
    return "\n".join(lines).lstrip() + "\n"
