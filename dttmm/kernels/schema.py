"""The flat model's schema: every table the kernels read from a model, in the shape of MuJoCo's
mjModel (docs/flat_model.md).

A model's tables sit in two flat buffers, `real` (float64) and `int` (int64), one after
another in the order MODEL lists them; `start` holds each table's offset in its buffer and `size`
the model's sizes (SIZES: bodies, modal rows, rod steps, ...), so a table's shape is a few
numbers the kernels read at run time, never part of a compiled type.  Each entry of MODEL names
a table, its buffer and its shape in terms of SIZES (a name, "name+1", or a constant).

The kernels read a table through its accessor in kernels/model_tables.py, which is generated
from MODEL (`write` writes it; tests/test_schema.py fails where it
is stale): ``model_tables.body_params(params)`` is the (body_rows, BODY_PARAM_SIZE) view of
`real` at start[0].  Python packs a model's tables with `pack` (run_tables.kernel_params) and
reads them back by name with `unpack`.
"""
from collections import namedtuple
from pathlib import Path
import textwrap

import numpy as np

from ..elements.beam import BEAM_PARAM_SIZE
from ..elements.kinds import HINGE_PARAM_SIZE, MAX_COORDINATES
from ..elements.rigid_body import BODY_PARAM_SIZE

REAL, INT = "real", "int"

# the flat model as the kernels take it: two buffers, each table's offset, the model's sizes
FlatModel = namedtuple("FlatModel", ["real", "int", "start", "size"])
Field = namedtuple("Field", ["name", "buffer", "shape", "doc"])

SIZES = (
    ("bodies", "n: the kernel model's bodies (and joints: joint k joins body k to its parent)"),
    ("body_rows", "rows of the bodies' tables: 1 where every body's are equal "
                  "(model.shared_rows), else n"),
    ("hinge_rows", "rows of the joints' table: 1 where every joint's are equal, else n"),
    ("lock_rows", "rows of lock_rel: n where a fixed hinge locks a body to the ground, else 0"),
    ("drive_rows", "rows of joint_drive: n where a joint has coordinates, else 1"),
    ("beam_rows", "rows of the beams' tables: n where the model has beams, else 0"),
    ("beam_modes", "the most bending modes of a beam in a plane (at least 1)"),
    ("moment_width", "columns of beam_moments (docs/beam.md, 'The integrals in the frame')"),
    ("mode_rows", "the most bending, twist and stretch modes of a beam (at least 1)"),
    ("end_width", "columns of beam_ends"),
    ("rod_lookup", "entries of rod_row: n where the model has strain rods, else 1"),
    ("rods", "rows of the rods' tables: one per distinct rod (at least 1)"),
    ("rod_steps", "the most steps of a rod's quadrature (at least 1)"),
    ("rod_coordinates", "the most strain coordinates of a rod (at least 1)"),
)

# The model's tables (run_tables.kernel_params); the kernels read them and never write them.
MODEL = (
    Field("body_params", REAL, ("body_rows", BODY_PARAM_SIZE),
          "elements/rigid_body.py: body k's at body_row[k]"),
    Field("mass_center_inertia", REAL, ("body_rows", 3, 3),
          "J_C in body axes at body_row[k] (the energy-momentum step)"),
    Field("body_row", INT, ("bodies",),
          "body k's row of body_params and mass_center_inertia"),
    Field("hinge_kind", INT, ("bodies",),
          "BALL / FIXED / ELASTIC / a joint kind (elements/kinds.py): hinge k joins body k to "
          "parent[k] (or the ground)"),
    Field("hinge_params", REAL, ("hinge_rows", HINGE_PARAM_SIZE),
          "elements/kinds.py: joint k's at hinge_row[k]"),
    Field("hinge_row", INT, ("bodies",), "joint k's row of hinge_params"),
    Field("parent", INT, ("bodies",), "Model.parent: body k hangs from body parent[k] "
                                      "(-1: the ground)"),
    Field("gravity", REAL, (3,), "m/s^2, world frame"),
    Field("locked", INT, ("bodies",),
          "1 where body k's rotation is fixed to the ground frame by fixed hinges"),
    Field("lock_rel", REAL, ("lock_rows", 3, 3),
          "a locked body's rotation relative to the ground frame (read where locked[k] only)"),
    Field("tip_pinned", INT, (), "1 where the tip is joined to the ground by a ball joint"),
    Field("joint_drive", REAL, ("drive_rows", MAX_COORDINATES, 4),
          "each joint coordinate's drive [kind, stiffness, damping, rest] (kind -1: none; "
          "elements/drives.py; run_tables.joint_drives)"),
    Field("body_kind", INT, ("bodies",), "RIGID / BEAM / ROD (elements/__init__.py)"),
    Field("beam_params", REAL, ("beam_rows", BEAM_PARAM_SIZE), "elements/beam.py"),
    Field("beam_moments", REAL, ("beam_rows", "beam_modes", "moment_width"),
          "the modal integrals (run_tables.beam_tables)"),
    Field("mode_offset", INT, ("bodies+1",),
          "body k's modal coordinates are mode_offset[k] .. mode_offset[k + 1] - 1"),
    Field("beam_ends", REAL, ("beam_rows", "mode_rows", "end_width"),
          "[Y_k(L), Y_k'(L)], the twist and stretch tables (run_tables.beam_tables)"),
    Field("beam_factors", REAL, ("beam_rows", "beam_modes", 2),
          "[modal mass / mu, modal stiffness / EI]"),
    Field("rod_row", INT, ("rod_lookup",), "body k's row of the rods' tables, -1: not a rod"),
    Field("rod_steps", REAL, ("rods", "rod_steps"),
          "the quadrature's step lengths (a padded step: 0; run_tables.rod_tables)"),
    Field("rod_xi0", REAL, ("rods", "rod_steps", 2, 6), "the reference strains at each step's "
                                                         "two points"),
    Field("rod_phi", REAL, ("rods", "rod_steps", 2, 6, "rod_coordinates"),
          "the strain bases at each step's two points"),
    Field("rod_weights", REAL, ("rods", "rod_steps+1"), "the stations' weights"),
    Field("rod_stiffness", REAL, ("rods", "rod_coordinates"), "K's diagonal"),
    Field("rod_mu_damping", REAL, ("rods", 2), "[mass per length, damping]"),
    Field("rod_section", REAL, ("rods", 3), "the section's inertia per length"),
)


def axes(shape):
    """[(size name or None, constant, plus)] of a schema shape's axes."""
    dims = []
    for axis in shape:
        if isinstance(axis, str):
            name, _, plus = axis.partition("+")
            dims.append((name, 0, int(plus or 0)))
        else:
            dims.append((None, int(axis), 0))
    return dims


def size_index():
    """{size name: its index in FlatModel.size}."""
    return {name: i for i, (name, _) in enumerate(SIZES)}


def table_of(flat, field, buffer, shape):
    """Table `field` (its index in the schema; of `buffer`, of the schema's `shape`) of a
    FlatModel as a numpy view of its buffer (a table without axes: its one value)."""
    index = size_index()
    extents = tuple(constant if name is None else int(flat.size[index[name]]) + plus
                    for name, constant, plus in axes(shape))
    start = int(flat.start[field])
    view = getattr(flat, buffer)[start:start + int(np.prod(extents, dtype=np.int64))]
    return view.reshape(extents)[()]


def pack(fields=MODEL, **arrays):
    """The FlatModel of the tables `arrays` (by their schema names; every field of `fields`):
    the sizes read from the arrays' shapes (an axis named twice must agree), the tables copied
    into the two buffers in the schema's order."""
    index = size_index()
    size = np.full(len(SIZES), -1, dtype=np.int64)
    missing = [f.name for f in fields if f.name not in arrays]
    extra = sorted(set(arrays) - {f.name for f in fields})
    if missing or extra:
        raise TypeError(f"pack: missing tables {missing}, unknown tables {extra}")
    values = []
    for f in fields:
        a = np.asarray(arrays[f.name])
        dims = axes(f.shape)
        if a.ndim != len(dims):
            raise ValueError(f"pack: {f.name} has shape {a.shape}, the schema says {f.shape}")
        for extent, (name, constant, plus) in zip(a.shape, dims):
            if name is None:
                if extent != constant:
                    raise ValueError(f"pack: {f.name} has shape {a.shape}, the schema says "
                                     f"{f.shape}")
                continue
            value = extent - plus
            if size[index[name]] not in (-1, value):
                raise ValueError(f"pack: {f.name}'s axis {name} is {value}, another table's "
                                 f"is {size[index[name]]}")
            size[index[name]] = value
        values.append(a)
    size[size < 0] = 0      # (a size no table of `fields` names)
    start = np.zeros(len(fields), dtype=np.int64)
    used = {REAL: 0, INT: 0}
    for i, (f, a) in enumerate(zip(fields, values)):
        start[i] = used[f.buffer]
        used[f.buffer] += a.size
    real, integer = np.empty(used[REAL]), np.empty(used[INT], dtype=np.int64)
    for i, (f, a) in enumerate(zip(fields, values)):
        buffer = real if f.buffer == REAL else integer
        buffer[start[i]:start[i] + a.size] = a.ravel()
    return FlatModel(real, integer, start, size)


def unpack(flat, fields=MODEL):
    """{name: view} of a FlatModel's tables (the kernels' accessors' views, for Python)."""
    return {f.name: table_of(flat, i, f.buffer, f.shape) for i, f in enumerate(fields)}


def _accessor(i, f):
    doc = textwrap.wrap(f"{f.buffer}: {f.doc}", 96, initial_indent="# ", subsequent_indent="# ")
    shape = ", ".join(f'"{a}"' if isinstance(a, str) else str(a) for a in f.shape)
    shape += "," if len(f.shape) == 1 else ""
    return "\n".join(doc + [f'{f.name} = table_view({i}, "{f.buffer}", ({shape}))'])


def generated_source():
    """kernels/model_tables.py's text, generated from MODEL."""
    head = ('"""The flat model\'s tables by name: one accessor per entry of kernels/schema.py\'s '
            'MODEL,\neach giving, called on a flat model in a kernel, its table\'s view of the '
            'buffers,\nof the schema\'s shape (kernels/views.py::table_view). Generated by\n'
            'kernels/schema.py::write from the schema; do not edit."""\n'
            "from .views import table_view\n")
    return head + "".join(f"\n{_accessor(i, f)}\n" for i, f in enumerate(MODEL))


GENERATED = Path(__file__).with_name("model_tables.py")


def write():
    """(Re)write kernels/model_tables.py from the schema: after an edit of MODEL or SIZES,
    ``python -c "from dttmm.kernels import schema; schema.write()"``."""
    GENERATED.write_text(generated_source())
