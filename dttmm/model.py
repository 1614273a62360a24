"""The chain description: built from elements, validated once, frozen into flat arrays."""
import functools
from dataclasses import dataclass, field, fields, replace
from functools import cached_property
from typing import Optional, Sequence

import numpy as np

from .elements import BALL, BEAM, FIXED, RIGID, ROD, BallJoint
from .elements.beam import (ACCURATE, AUTO, AXIAL_MODES, BEAM_PARAM_SIZE, CLAMPED, CLAMPED_LOADED,
                            EXACT,
                            FAMILY, FREQUENCY_CUTOFF, FROM_STEP, LENGTH, LOAD_AXES,
                            MASS_PER_LENGTH, MAX_LOADED_MODES, MODES, PINNED, STIFFENING,
                            TORSION_MODES,
                            accurate_mode_count, auto_mode_count, auto_part_count,
                            axial_frequencies, modal_size,
                            torsion_frequencies)
from .elements._checks import derivative, finite_scalar, finite_vector, rotation_matrix
from .elements.drives import MOTION
from .elements.kinds import (BODY_KINDS, CHILD, FLEXIBLE, HINGE_KIND_NAMES, JOINT_KIND,
                             JOINT_KINDS, PARENT, TURN, WITH_COORDINATES, body_kind_of,
                             coordinates_of, joint_kind_of, joint_motion, names, pack_hinge,
                             turn_rotations)
from .elements.rigid_body import MASS, pack_body
from .elements.strain_rod import (ROD_LENGTH, ROD_MODES, ROD_MU, ROD_PARAM_SIZE, ROD_STATIONS,
                                  rod_coordinate_count)
from .rod_motion import rod_end_section
from . import closures
from .closures import closure_rows, empty_table, is_pinned_tip, loop_membership
from .sections import output_section
from .spanning_tree import shortest_tree


class PrescribedMotion:
    """Prescribed motion of the ground frame (a driven hub), as functions of time.

    Each argument is a function of t (s), or None for zero / identity: position, velocity and
    acceleration of the ground point (world, m), rotation matrix of the ground frame, and its
    world-frame angular velocity and angular acceleration.  Derivatives are given, not
    differentiated numerically, so the solver sees the exact motion; ``build`` checks them
    against central differences of the motion (``check``), so a derivative left None must be
    zero.  Pass it as ``Ground(motion=...)``; docs/hinges.md, "The root".

    Parameters
    ----------
    position : callable, optional
        position(t) -> 3 numbers: the ground point, world frame, m.  None: the origin.
    velocity : callable, optional
        velocity(t) -> its rate, m/s.  None: zero.
    acceleration : callable, optional
        acceleration(t) -> its second derivative, m/s^2.  None: zero.
    rotation : callable, optional
        rotation(t) -> (3, 3) rotation matrix of the ground frame (ground to world).  None:
        the identity.
    angular_velocity : callable, optional
        angular_velocity(t) -> 3 numbers: the ground frame's angular velocity, world frame,
        rad/s.  None: zero.
    angular_acceleration : callable, optional
        angular_acceleration(t) -> its rate, world frame, rad/s^2.  None: zero.

    Raises
    ------
    ValueError
        Here, for an argument that is neither callable nor None.  At build time
        (``System.build``, ``build_chain``: ``check``), for a derivative that contradicts the
        motion, or a position, rotation or angular velocity at t = 0 that is not finite (or
        not a proper rotation matrix), naming the argument.

    Examples
    --------
    A hub turned about world z at a steady 2 rad/s:

    >>> import numpy as np
    >>> import dttmm
    >>> def hub(t):
    ...     c, s = np.cos(2.0 * t), np.sin(2.0 * t)
    ...     return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    >>> motion = dttmm.PrescribedMotion(rotation=hub,
    ...                                 angular_velocity=lambda t: np.array([0.0, 0.0, 2.0]))
    >>> ground = dttmm.Ground(motion=motion)
    """

    # (unit axis, angle, rate, acceleration) of a spin made by spin_about_axis, else None: the
    # reference evaluates a profile's angle there in compiled code (reference/hub.py)
    spin = None

    def __init__(self, position=None, velocity=None, acceleration=None,
                 rotation=None, angular_velocity=None, angular_acceleration=None):
        self._f = (position, velocity, acceleration, rotation, angular_velocity,
                   angular_acceleration)
        for name, f in zip(("position", "velocity", "acceleration", "rotation",
                            "angular_velocity", "angular_acceleration"), self._f):
            if f is not None and not callable(f):
                raise ValueError(f"PrescribedMotion: {name} must be a function of time or None")

    def check(self, times=(0.0, 0.37, 1.0), eps=1e-5, rtol=1e-4):
        """Raise ValueError if the given derivatives contradict the position and rotation.

        Parameters
        ----------
        times : sequence of float, optional
            The times compared, s (default 0, 0.37 and 1).
        eps : float, optional
            Step of the differences, s (default 1e-5): central ones, forward ones at t < eps
            (the functions are not called before t = 0).
        rtol : float, optional
            Tolerance, relative to max(1, |central difference|) (default 1e-4).

        Raises
        ------
        ValueError
            Naming the derivative, the time, its value and the central difference.
        """
        def fd(f, t):
            return derivative(f, t, eps)

        r, v, a, rot, w, wd = self(0.0)           # what each function returns, checked first
        for name, value in (("position", r), ("velocity", v), ("acceleration", a),
                            ("angular_velocity", w), ("angular_acceleration", wd)):
            finite_vector("PrescribedMotion", f"{name}(0)", value)
        rotation_matrix("PrescribedMotion", "rotation(0)", rot)
        for t in times:
            r, v, a, rot, w, wd = self(t)
            rot_dot = fd(lambda s: self(s)[3], t)
            w_fd = rot_dot @ rot.T
            pairs = (("velocity", v, fd(lambda s: self(s)[0], t)),
                     ("acceleration", a, fd(lambda s: self(s)[1], t)),
                     ("angular_velocity", w, np.array([w_fd[2, 1], w_fd[0, 2], w_fd[1, 0]])),
                     ("angular_acceleration", wd, fd(lambda s: self(s)[4], t)))
            for name, given, numeric in pairs:
                scale = max(1.0, np.abs(numeric).max())
                if not np.all(np.isfinite(given)) or np.abs(given - numeric).max() > rtol * scale:
                    raise ValueError(f"PrescribedMotion: {name}({t:g}) = {given} contradicts the "
                                     f"motion's own derivative {numeric}")

    def __call__(self, t):
        """The ground's state at time t (s).

        Returns
        -------
        tuple of ndarray
            (r, v, a, R, w, w_dot): position (3,) m, velocity (3,) m/s, acceleration (3,)
            m/s^2, rotation (3, 3), angular velocity (3,) rad/s and angular acceleration (3,)
            rad/s^2, world frame (zero / identity for the functions left None).
        """
        r, v, a, rot, w, wd = self._f
        zero = np.zeros(3)
        return (zero if r is None else np.asarray(r(t), float),
                zero if v is None else np.asarray(v(t), float),
                zero if a is None else np.asarray(a(t), float),
                np.eye(3) if rot is None else np.asarray(rot(t), float),
                zero if w is None else np.asarray(w(t), float),
                zero if wd is None else np.asarray(wd(t), float))

    @classmethod
    def spin_about_axis(cls, axis, angle, rate, acceleration, position=(0.0, 0.0, 0.0)):
        """Rotation by angle(t) about a fixed world axis through a fixed point.

        Parameters
        ----------
        axis : array_like of 3
            The world axis, any nonzero length (normalized here; a zero axis raises
            ValueError).
        angle : callable
            angle(t) -> the rotation angle at time t (s), rad.
        rate : callable
            rate(t) -> its first derivative, rad/s.
        acceleration : callable
            acceleration(t) -> its second derivative, rad/s^2.
        position : array_like of 3, optional
            The fixed ground point, world frame, m (default the origin).

        Returns
        -------
        PrescribedMotion
            The spin: rotation Rot(axis, angle(t)), angular velocity rate(t) axis, angular
            acceleration acceleration(t) axis, the point fixed.

        Examples
        --------
        >>> import dttmm
        >>> spin = dttmm.PrescribedMotion.spin_about_axis([0, 0, 1], lambda t: 0.5 * t * t,
        ...                                               lambda t: t, lambda t: 1.0)
        """
        n = finite_vector("PrescribedMotion.spin_about_axis", "axis", axis)
        if not np.linalg.norm(n) > 0.0:
            raise ValueError("PrescribedMotion.spin_about_axis: axis must be nonzero, got "
                             f"{n.tolist()}")
        n = n / np.linalg.norm(n)
        k = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
        p = np.asarray(position, float)

        def rotation(t):
            th = angle(t)
            return np.eye(3) + np.sin(th) * k + (1.0 - np.cos(th)) * k @ k

        motion = cls(position=lambda t: p, rotation=rotation,
                     angular_velocity=lambda t: rate(t) * n,
                     angular_acceleration=lambda t: acceleration(t) * n)
        motion.spin = (n, angle, rate, acceleration)
        return motion


# Model.describe's words, set by the describing layer (describe.py, which knows what runs a
# model: the loops, the schemes, the steps) when dttmm is imported: the model imports nothing
# above it.
DESCRIBE = [lambda model: "(import dttmm to describe a model)"]


@dataclass(frozen=True)
class Ground:
    """Where the root hinge attaches: a fixed point and frame, or a prescribed motion.

    Parameters
    ----------
    position : array_like of 3, optional
        The ground point, world frame, m (default the origin).  Refused beside a motion.
    rotation : array_like (3, 3), optional
        The ground frame (ground to world; a proper rotation matrix), the inboard frame of the
        root joint.  None (default): the identity.  Refused beside a motion (which gives it).
    motion : PrescribedMotion, optional
        A prescribed motion of the ground point and frame (a driven hub); its position and
        rotation at t = 0 become ``Model.ground_position`` and ``Model.ground_rotation``.
        None (default): the ground is fixed.

    Raises
    ------
    ValueError
        At build time (``System.build``, ``build_chain``), naming "Ground" and the argument: a
        position without 3 finite entries, a rotation that is not a proper rotation matrix, or
        a motion that fails ``PrescribedMotion.check`` or is not finite at t = 0, or a position
        or rotation given beside a motion.

    Examples
    --------
    >>> import dttmm
    >>> ground = dttmm.Ground(position=[0.0, 1.0, 0.0])
    """
    position: object = (0.0, 0.0, 0.0)
    rotation: object = None
    motion: Optional[PrescribedMotion] = None


def model_fact(function):
    """A function of a frozen model (and hashable options) evaluated once per model and
    options: its value is kept on the model, which cannot change after build() (issue 30: a
    short run does not redo its setup).  The value is shared between calls: arrays in it are
    read, never written, by its users (tests/test_short_runs.py checks the kernels' tables)."""
    @functools.wraps(function)
    def fact(model, *args):
        facts = model.__dict__.get("_facts")
        if facts is None:
            facts = {}
            object.__setattr__(model, "_facts", facts)
        key = (function, args, closures.PINNED_TIP_SWEEP)   # (a switch of how loops run)
        if key not in facts:
            facts[key] = function(model, *args)
        return facts[key]
    return fact


# the model's tables the kernels read in place (kernel_array): arrays the builders make
KERNEL_TABLES = ("body_params", "hinge_kind", "hinge_params", "ground_locked",
                 "body_mass_center_inertia", "parent", "body_kind", "beam_params")


def adopt_arrays(model, source=None):
    """Keep the kernel tables a builder made for model (KERNEL_TABLES, each owning its memory)
    writable behind the read-only views the model shows, for kernel_array: the kernels then
    read the model's own memory (a million bodies' tables are not copied for them).  source:
    the model that model was replaced from; the tables it shares with it keep its memory.
    Only the builders call it, on arrays they made (never on a caller's: it would keep a
    writable alias into a frozen model).  Returns model."""
    own = dict(model.__dict__.get("_kernel_arrays", {}))
    kept = {} if source is None else source.__dict__.get("_kernel_arrays", {})
    for name in KERNEL_TABLES:
        value = getattr(model, name)
        if source is not None and value is getattr(source, name) and name in kept:
            own[name] = kept[name]
        elif value.base is None and value.flags.c_contiguous:   # (its own memory, laid out
            # as the kernels take it: writable again for them; else kernel_array copies it)
            value.flags.writeable = True
            view = value.view()
            view.flags.writeable = False
            object.__setattr__(model, name, view)
            own[name] = value
    object.__setattr__(model, "_kernel_arrays", own)
    return model


_NO_BEAM = np.zeros(BEAM_PARAM_SIZE)     # a rigid body's row of beam_params
_NO_ROD = np.zeros(ROD_PARAM_SIZE)       # the row of rod_params of a body that is not a rod

# the per-body tables a model shows as one row where every body's (joint's) row is equal
SHARED_TABLES = ("body_params", "hinge_params", "body_mass_center_inertia", "beam_params",
                 "rod_params", "initial_rotation", "initial_angular_velocity")


def shared_rows(table):
    """table, or where its rows are all equal (a chain of equal links) its first row shown
    len(table) times: a read-only view of stride 0 that reads as the table in every numpy
    operation and holds one row (a million bodies' tables in a few hundred bytes; the kernels
    read the one row: run_tables.kernel_params)."""
    if len(table) < 2 or is_shared(table) or not (table == table[0]).all():
        return table
    return _shown_for_all(table[0], len(table))


def _shown_for_all(row, n):
    """row shown n times: a read-only (n, ...) view of stride 0 on a copy of row (not a view
    of the table it came from, which is then free to go)."""
    return np.broadcast_to(row[None].copy(), (n,) + row.shape)


def is_shared(table):
    """Whether table is a shared_rows view (one row shown for all)."""
    return table.ndim > 0 and len(table) > 1 and table.strides[0] == 0


def kernel_array(model, name, dtype=None):
    """The model's array `name` as the kernels take it, writable: the model's own memory where
    a builder kept it (adopt_arrays), else a copy.  The kernels read it and never write it."""
    own = model.__dict__.get("_kernel_arrays", {}).get(name)
    value = np.array(getattr(model, name), order="C") if own is None else own   # (a shared
    # table's copy: order "K" would lay its rows out along the stride-0 axis, Fortran-like)
    return value if dtype is None else value.astype(dtype, copy=False)


@dataclass(frozen=True, eq=False)
class Model:
    """A frozen system: flat float arrays for the kernels plus the description it came from.

    Built by ``System.build`` or ``build_chain`` (which validate the elements), not by hand;
    every argument is also a read-only attribute of the same name, and the arrays cannot be
    written (a value changed after the build would skip its validation).  A per-body table
    whose rows are all equal (SHARED_TABLES: a chain of equal links) holds its one row, shown
    for every body (shared_rows); copy one with ``np.array(table, order="C")``.  Bodies are numbered
    0..n-1, parents first; hinge k joins body parent[k] (the ground for -1) at its attachment
    point to body k.  In a chain parent[k] = k - 1, every body hangs from its parent's output
    point, and the last body's output point is the tip.  Shapes: n bodies.

    Parameters
    ----------
    n_bodies : int
        n.
    body_params : ndarray (n, 16)
        Per body: mass (kg), l_IC (3, m), l_IO (3, m), and J_I, the inertia about the input
        point in body axes (9, row-major, kg m^2); for a beam, the undeformed beam as a rigid
        body (elements/rigid_body.py).
    hinge_kind : ndarray (n,) of int
        The joint before each body: 0 ball, 1 fixed, 2 elastic, 3 revolute, 4 universal,
        5 prismatic, ... (elements/kinds.py, JOINT_KINDS).
    hinge_params : ndarray (n, 60)
        Per joint: the rest rotation R0 (9), K_t (9, N/m), C_t (9, N s/m), K_r (9, N m/rad),
        C_r (9, N m s/rad), all row-major, and for joints with coordinates axis 1 (3), axis 2
        (3), the coordinates (3, rad or m), rates (3, rad/s or m/s) at t = 0 and axis 3 (3),
        each axis in the frame its declaration says (elements/hinges.py, elements/kinds.py:
        AXES, COORDINATE_0, RATE_0).
    gravity : ndarray (3,)
        World frame, m/s^2.
    ground_position : ndarray (3,)
        The ground point, world frame, m: at rest, or at t = 0 under a motion.
    ground_rotation : ndarray (3, 3)
        The ground frame (ground to world): at rest, or at t = 0 under a motion.
    ground_motion : PrescribedMotion or None
        The ground's prescribed motion, None for a fixed ground.
    initial_rotation : ndarray (n, 3, 3)
        Each body's rotation (body to world) at t = 0.
    initial_angular_velocity : ndarray (n, 3)
        Each body's angular velocity at t = 0, world frame, rad/s.
    ground_locked : ndarray (n,) of bool
        The body's rotation is fixed to the ground frame by fixed hinges (through rigid bodies
        only): it is not integrated (docs/solver.md, "Bodies locked to the ground").
    forces : tuple
        Per body: None or f(t) -> the applied world force at the mass centre, N (for a beam:
        at its output end, ``end_force``).
    torques : tuple
        Per body: None or f(t) -> the applied world torque, N m (for a beam: on its output
        end section, ``end_torque``).
    line_loads : tuple
        Per body: None or f(t) -> a beam's distributed load per length, world, N/m
        (``distributed_load``); None for a rigid body.
    body_names : tuple of str
        The bodies' names (``body{k}`` for a body without one).
    hinge_names : tuple of str
        The joints' names (the class name and index, e.g. ``BallJoint0``, for a joint
        without one).
    body_mass_center_inertia : ndarray (n, 3, 3)
        J_C, the inertia about the mass centre in body axes, kg m^2 (for the energies).
    body_kind : ndarray (n,) of int
        0 rigid body, 1 beam, 2 strain rod.
    beam_params : ndarray (n, 10)
        Per beam: length (m), mass per length (kg/m), EI_v and EI_w (N m^2), polar inertia
        per length (kg m), damping ratio, modes per plane, the mode family resolved
        (0 pinned, 1 clamped, 2 clamped with a loaded end), geometric stiffening (1 or 0) and
        the frequency cutoff of modes_per_plane="auto" (Hz; 0 for a given count;
        elements/beam.py); zero rows for rigid bodies.
    rod_params : ndarray (n, 14)
        Per strain rod: length (m), mass per length (kg/m), EI_v, EI_w, GJ (N m^2), EA (N), the
        sections' inertias per length j_p, rho I_v, rho I_w (kg m), strain modes, twist and
        stretch (1 or 0), stations and damping (s) (elements/strain_rod.py); zero rows for the
        other bodies.
    initial_modal_coordinates : ndarray (total modes,)
        The beams' modal coordinates at t = 0, m, flat in body order (a beam's v coordinates
        first, then w).
    initial_modal_velocities : ndarray (total modes,)
        Their rates at t = 0, m/s, in the same order.
    drives : tuple
        Per joint: for a joint with coordinates, one validated drive (a dict,
        elements/drives.py) or None per coordinate; else ().
    parent : ndarray (n,) of int
        The parent body of body k (< k), -1 for the ground.
    attachment : ndarray (n,) of int
        Where on the parent: 0 its output point, j >= 1 its j-th named point
        (``RigidBody.points``).
    attachment_point : ndarray (n, 3)
        That point in the parent's frame from its input point, m; a root's: its place on
        the ground, in the ground frame from the ground point (System.add(..., at=[x, y, z])).
    frequency_cutoff_reasons : tuple of str
        Per body: where the cutoff of a beam with ``modes_per_plane="auto"`` and no
        ``frequency_cutoff`` came from (the build's step and the drives' bandwidth); "" for
        every other body.
    beam_ends : tuple
        Per body: a beam's (root pinned, tip pinned), whether in some bending plane its root
        turns freely and its output is held at a point, turning freely (its mode count is
        estimated for those ends; elements/beam.py::truncation_errors); None for other bodies.
    closure_kind, closure_body, closure_point, closure_on_end, closure_params, closure_names
        The loop-closing joints (``System.close``; m of them): kind (m,), the two sides' bodies
        (m, 2; -1 the ground), each side's point in its frame (m, 2, 3; the ground's in the
        ground frame), whether it is a beam's output end (m, 2), a hinge_params row (m, 60:
        R0 and the axes) and names (dttmm/closures.py, docs/loops.md).  Empty for a tree.
    closure_drives : tuple
        Per closing joint, per coordinate, its drive as ``drives`` (a prescribed motion or a
        spring-damper) or None.

    Examples
    --------
    >>> import dttmm
    >>> rod = dttmm.RigidBody(mass=1.0, inertia=[1e-4, 1 / 12, 1 / 12],
    ...                       inertia_about="mass_center", to_mass_center=[0.5, 0, 0],
    ...                       to_output=[1.0, 0, 0])
    >>> model = dttmm.build_chain([dttmm.BallJoint(), rod])
    >>> model.n_bodies, model.body_names, model.is_chain
    (1, ('body0',), True)
    """
    n_bodies: int
    body_params: np.ndarray          # (n, BODY_PARAM_SIZE), see elements/rigid_body.py
    hinge_kind: np.ndarray           # (n,) elements/kinds.py: BALL, FIXED, ELASTIC, REVOLUTE, ...
    hinge_params: np.ndarray         # (n, HINGE_PARAM_SIZE), see elements/hinges.py
    gravity: np.ndarray              # (3,) world, m/s^2
    ground_position: np.ndarray      # (3,) at rest (motion is None) or at t = 0
    ground_rotation: np.ndarray      # (3, 3)
    ground_motion: Optional[PrescribedMotion]
    initial_rotation: np.ndarray     # (n, 3, 3)
    initial_angular_velocity: np.ndarray  # (n, 3) world
    ground_locked: np.ndarray        # (n,) bool: rotation fixed to the ground frame by fixed hinges
    forces: tuple                    # per body: None or f(t) -> world force at the mass centre
    torques: tuple                   # per body: None or f(t) -> world torque
    line_loads: tuple                # per body: None or f(t) -> a beam's distributed load, N/m
    body_names: tuple
    hinge_names: tuple
    body_mass_center_inertia: np.ndarray  # (n, 3, 3) J_C in body axes (for energies)
    body_kind: np.ndarray            # (n,) RIGID / BEAM
    beam_params: np.ndarray          # (n, BEAM_PARAM_SIZE), zero rows for rigid bodies; for a
                                     # beam, body_params holds the undeformed beam as a rigid body
                                     # (its FAMILY column resolved: PINNED, CLAMPED or
                                     # CLAMPED_LOADED)
    rod_params: np.ndarray           # (n, ROD_PARAM_SIZE), zero rows but for strain rods
                                     # (elements/strain_rod.py)
    initial_modal_coordinates: np.ndarray  # (total modes,) flat in body order (v then w; a
                                           # strain rod's strain coordinates)
    initial_modal_velocities: np.ndarray
    drives: tuple                    # per hinge: one validated drive (elements/drives.py) or None
                                     # per coordinate of a joint with coordinates, else ()
    parent: np.ndarray               # (n,) the parent body of body k (< k), -1 for the ground
    attachment: np.ndarray           # (n,) where on the parent: 0 its output point, j >= 1 its
                                     # j-th named point (RigidBody.points)
    attachment_point: np.ndarray     # (n, 3) that point in the parent's frame from its input
                                     # point, m (a root's: its place on the ground)
    frequency_cutoff_reasons: tuple = ()  # per body: where a derived "auto" cutoff came from
    beam_ends: tuple = ()   # per body: a beam's (root pinned, tip pinned) in some plane, or None
    # the loop-closing joints (closures.py): m rows
    closure_kind: np.ndarray = field(default_factory=lambda: empty_table()["closure_kind"])
    closure_body: np.ndarray = field(default_factory=lambda: empty_table()["closure_body"])
    closure_point: np.ndarray = field(default_factory=lambda: empty_table()["closure_point"])
    closure_on_end: np.ndarray = field(default_factory=lambda: empty_table()["closure_on_end"])
    closure_params: np.ndarray = field(default_factory=lambda: empty_table()["closure_params"])
    closure_names: tuple = ()
    closure_drives: tuple = ()   # per closing joint, per coordinate: a drive's parameters or None

    def __post_init__(self):
        # frozen through and through: the arrays cannot be written either (a negative mass
        # written after build() would otherwise simulate); the kernels get writable arrays
        # through kernel_array (adopt_arrays)
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, np.ndarray):
                value.flags.writeable = False
        object.__setattr__(self, "_kernel_arrays", {})

    def __getstate__(self):
        # (a pickle carries the fields, not the facts derived from them: model_fact)
        return {f.name: getattr(self, f.name) for f in fields(self)}

    def __setstate__(self, state):
        state = dict(state)
        for name in SHARED_TABLES:          # (a pickle holds every row)
            state[name] = shared_rows(state[name])
        self.__dict__.update(state)
        self.__post_init__()
        adopt_arrays(self)          # (the unpickled arrays are its own)

    @property
    def tip_pinned(self):
        """Whether the loops are one ball joint from a chain's tip to a fixed ground
        (``tip="ball"``): the one closure the DT-TMM sweeps run so far (closures.py)."""
        return is_pinned_tip(self)

    @cached_property
    def n_closures(self):
        """The number of loop-closing joints."""
        return len(self.closure_kind)

    @cached_property
    def is_chain(self):
        """Every body hangs from the output point of the body before it (or the ground)."""
        return bool(np.all(self.parent == np.arange(self.n_bodies) - 1)
                    and np.all(self.attachment == 0))

    @cached_property
    def n_modes(self):
        """(n,) modal coordinates of each body: 2 x modes per plane plus the twist and stretch
        modes for a beam (elements/beam.py::modal_size), a strain rod's strain coordinates
        (elements/strain_rod.py::rod_coordinate_count), 0 if rigid."""
        n_modes = np.where(self.body_kind == BEAM, 2 * self.beam_params[:, MODES]
                           + self.beam_params[:, TORSION_MODES] + self.beam_params[:, AXIAL_MODES],
                           0).astype(np.int64)
        for k in np.nonzero(self.body_kind == ROD)[0]:
            n_modes[k] = rod_coordinate_count(self.rod_params[k])
        n_modes.flags.writeable = False
        return n_modes

    @cached_property
    def mode_offsets(self):
        """(n + 1,) where each body's own coordinates start in the run's modal vector (every
        flexible body's n_modes in body order): body k's are [mode_offsets[k],
        mode_offsets[k + 1])."""
        offsets = np.concatenate([[0], np.cumsum(self.n_modes)]).astype(np.int64)
        offsets.flags.writeable = False
        return offsets

    @cached_property
    def has_twist(self):
        """Whether a beam has twist modes (it runs in the general loop: docs/beam.md,
        "Torsion")."""
        return bool(np.any((self.body_kind == BEAM) & (self.beam_params[:, TORSION_MODES] > 0)))

    @cached_property
    def has_beams(self):
        """Whether any body is a beam."""
        return bool(np.any(self.body_kind == BEAM))

    @cached_property
    def all_ball(self):
        """True when every hinge is moment-free (a ball joint): the reduced [a; q] transfer
        applies (elements/kinds.py)."""
        return all(JOINT_KIND[int(c)].moment_free for c in self.hinge_kind)

    @cached_property
    def has_beam_end_torque(self):
        """Whether a beam carries an applied end torque (its modal equations then depend on its
        end section's rotation, and it runs in the general loop: docs/beam.md)."""
        return any(self.torques[k] is not None for k in range(self.n_bodies)
                   if self.body_kind[k] == BEAM)

    @cached_property
    def needs_general_loop(self):
        """Whether a beam's w' and eta'' columns are differenced in every step (an end torque,
        twist modes or loads in body axes), so the model runs in the general loop, not the fused one
        (kernels/transfers/beam.py::beam_transfer)."""
        return (self.has_beam_end_torque or self.has_twist or self.has_stretch
                or self.has_follower_loads or self.has_exact_foreshortening)

    @cached_property
    def has_exact_foreshortening(self):
        """Whether a beam keeps its foreshortening to all orders (stiffening="exact":
        docs/beam.md, "The exact foreshortening"; its columns are differenced)."""
        return bool(np.any((self.body_kind == BEAM) & (self.beam_params[:, STIFFENING] == EXACT)))

    @cached_property
    def has_stretch(self):
        """Whether a beam has stretch modes (docs/beam.md, "Stretch")."""
        return bool(np.any((self.body_kind == BEAM) & (self.beam_params[:, AXIAL_MODES] > 0)))

    @cached_property
    def has_follower_loads(self):
        """Whether a beam carries loads in its own axes (load_axes="body": they turn with it,
        so its w' and eta'' columns are differenced: docs/beam.md, "Loads on the beam")."""
        return any(self.beam_params[k, LOAD_AXES] != 0.0 and any(
            f is not None for f in (self.forces[k], self.torques[k], self.line_loads[k]))
            for k in range(self.n_bodies) if self.body_kind[k] == BEAM)

    @cached_property
    def has_applied_loads(self):
        """Whether any body has an applied force or torque."""
        return any(f is not None for f in self.forces + self.torques + self.line_loads)

    def carried_masses(self):
        """Per body: the mass of everything attached beyond it (its descendants), kg."""
        return outboard_masses(np.asarray(self.body_params)[:, MASS], self.parent)

    def ends_of(self, k):
        """Body k's (root pinned, tip pinned) as the build found them (``beam_ends``);
        (False, False) for a body that is not a beam, or a model made without them."""
        ends = self.beam_ends[k] if k < len(self.beam_ends) else None
        return ends or (False, False)

    def describe(self):
        """The model in words (as ``dttmm info`` prints it).

        Returns
        -------
        str
            Its bodies, joints and degrees of freedom; each beam's modes with their
            frequencies, the mode family and why the beam's ends select it, what
            ``modes_per_plane="auto"`` kept below its cutoff, and whether geometric stiffening
            is on; a step that resolves the fastest retained motion.
        """
        return DESCRIBE[0](self)

    def ground_state(self, t):
        """(r, v, a, R, w, w_dot) of the ground frame at time t (s): position m, velocity
        m/s, acceleration m/s^2, rotation (3, 3), angular velocity rad/s and angular
        acceleration rad/s^2, world frame (``PrescribedMotion.__call__``)."""
        if self.ground_motion is None:
            z = np.zeros(3)
            return self.ground_position, z, z, self.ground_rotation, z, z
        return self.ground_motion(t)

    def ground_states(self, times):
        """(r, v, R, w) of the ground point and frame at the times (T,), (T, ...) each (one
        state shown for every time where the ground is at rest)."""
        states = [self.ground_state(t) for t in (times if self.ground_motion is not None
                                                  else times[:1])]
        return tuple(np.broadcast_to(np.array([g[i] for g in states], dtype=float),
                                     (len(times),) + np.shape(states[0][i])) for i in (0, 1, 3, 4))


class System:
    """A multibody system under construction: a tree of bodies, each joined by a joint to its
    parent (the ground or another body) at one of the parent's attachment points
    (docs/topology.md).

    ::

        system = System(gravity=[0, -9.81, 0])
        system.add(link1, BallJoint())                        # to the ground point
        system.add(link2, BallJoint(), parent=link1)          # to link1's output point
        system.add(link4, BallJoint(), parent="link1")        # by name; a second branch
        system.add(link3, BallJoint(), parent=link2, at="p")  # at link2's named point "p"
        model = system.build()

    Bodies may be added in any order; build() resolves the parents, refuses a parent not in
    the system, an attachment point the parent does not have, and a cycle, and freezes the
    system into a Model whose bodies are numbered parents first (in the order added where that
    allows).  build_chain is the same for a chain.

    Parameters
    ----------
    gravity : array_like of 3, optional
        Gravitational acceleration, world frame, m/s^2 (default (0, -9.81, 0)).  Checked at
        build time (3 finite numbers).
    ground : Ground, optional
        Where the root joints attach: a fixed point and frame (default: the origin and the
        identity), or a prescribed motion.

    Examples
    --------
    A two-link pendulum with a third link on a named point of the first:

    >>> import dttmm
    >>> def link(name, **kw):
    ...     return dttmm.RigidBody(mass=1.0, inertia=[1e-4, 1 / 12, 1 / 12],
    ...                            inertia_about="mass_center", to_mass_center=[0.5, 0, 0],
    ...                            to_output=[1.0, 0, 0], name=name, **kw)
    >>> system = dttmm.System(gravity=[0, -9.81, 0])
    >>> link1 = system.add(link("link1", points={"p": [0.5, 0, 0]}), dttmm.BallJoint())
    >>> link2 = system.add(link("link2"), dttmm.BallJoint(), parent=link1)
    >>> link3 = system.add(link("link3"), dttmm.BallJoint(), parent="link1", at="p")
    >>> model = system.build()
    >>> model.parent.tolist(), model.attachment.tolist()
    ([-1, 0, 0], [0, 0, 1])
    """

    def __init__(self, gravity=(0.0, -9.81, 0.0), ground: Ground = Ground()):
        self.gravity = gravity
        self.ground = ground
        self._entries = []          # (body, joint, parent, at) as added
        self._closures = []         # (joint, a, b, at_a, at_b) as closed

    def add(self, body, joint, parent=None, at=None):
        """Join body to parent by joint.

        Nothing is checked here: ``build`` validates every body, joint, parent and attachment
        point.

        Parameters
        ----------
        body : RigidBody or EulerBernoulliBeam
            The body added (each body once).
        joint : BallJoint, FixedHinge, ElasticHinge or a joint with coordinates
            The joint between the parent's attachment point and the body's input point (any
            kind of elements/kinds.py's JOINT_KINDS: RevoluteJoint, UniversalJoint,
            PrismaticJoint, ...).
        parent : RigidBody, EulerBernoulliBeam or str, optional
            None (default) for the ground point, or a body of the system (the body itself or
            its name; it may be added later).
        at : str or array_like of 3, optional
            The parent's attachment point: None (default) or "output" for its output point, or
            the name of one of a rigid body's points (``RigidBody(points={...})``); a beam has
            only its output end.  On the ground (parent None): a point of the ground, in the
            ground frame from the ground point, m (default the ground point itself), so that
            several roots stand at their own places (a mechanism's ground pivots).

        Returns
        -------
        RigidBody or EulerBernoulliBeam
            body, so that it can be named as a later body's parent.
        """
        self._entries.append((body, joint, parent, at))
        return body

    def close(self, joint, a, b="ground", at_a=None, at_b=None):
        """Close a loop: join a point of side a to a point of side b by joint, beside the tree
        (docs/loops.md).

        The bodies' frames at t = 0 define the joint's rest: a joint's relative rotation R0 is
        read from them (at its turns' given angles), a slide's coordinate is measured between
        its points.  Nothing is checked here: ``build`` validates the joint and its sides.

        Parameters
        ----------
        joint : any joint kind (elements/kinds.py's JOINT_KINDS)
            The closing joint: BallJoint, FixedHinge, ElasticHinge, RevoluteJoint,
            UniversalJoint, PrismaticJoint, ...  Side a plays a tree joint's parent (the axes
            fixed in the parent, axis or axis1, are in a's frame; slides run along a's axes),
            side b its child (an axis fixed in the child, a universal joint's axis2, is in b's
            frame; the joint's force and couple act on b).  A closing joint's drives sit on its
            first two coordinates.
        a, b : body, str
            A body of the system, its name, or "ground" (b defaults to the ground).
        at_a, at_b : str or array_like of 3, optional
            Where on each side: None or "output" (the output point; a beam's output end),
            "input" (the input point), a rigid body's named point, or a point in the body's
            frame from its input point (rigid bodies).  On the ground: a world position, or
            None for where the other side's point starts.

        Returns
        -------
        joint
            The joint, as given.

        Examples
        --------
        A unit-square four-bar: the left crank on the ground at the origin, the coupler on its
        tip, the right crank hanging from the coupler's far end, its tip pinned to the ground at
        (1, 0, 0) by a closing revolute joint (the tree's roots sit at the ground point; the loop
        closes anywhere).

        >>> import numpy as np
        >>> import dttmm
        >>> def bar(name, rotation):
        ...     return dttmm.RigidBody(mass=1.0, inertia=[1e-3, 1 / 12, 1 / 12],
        ...                            inertia_about="mass_center", to_mass_center=[0.5, 0, 0],
        ...                            to_output=[1.0, 0, 0], rotation=rotation, name=name)
        >>> up = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]       # a bar's x along world y
        >>> down = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]     # along -y
        >>> z = [0, 0, 1]
        >>> system = dttmm.System(gravity=[0, -9.81, 0])
        >>> _ = system.add(bar("left", up), dttmm.RevoluteJoint(axis=z))
        >>> _ = system.add(bar("coupler", np.eye(3)), dttmm.RevoluteJoint(axis=z), parent="left")
        >>> _ = system.add(bar("right", down), dttmm.RevoluteJoint(axis=z), parent="coupler")
        >>> _ = system.close(dttmm.RevoluteJoint(axis=z, name="pin"), "right", "ground",
        ...                  at_b=[1, 0, 0])
        >>> model = system.build()
        >>> model.n_closures, float(dttmm.loop_residuals(model)[0].max()) < 1e-12
        (1, True)
        """
        self._closures.append((joint, a, b, at_a, at_b))
        return joint

    def build(self, tip="free", step=None, duration=None, tree="as added") -> "Model":
        """Validate and freeze into a Model.

        Parameters
        ----------
        tip : {"free", "ball"}, optional
            "free" (default) or, for a chain only, "ball": the last body's output point is
            joined to the ground by a ball joint where it starts (a fixed point; e.g. a simply
            supported beam).
        step, duration : float, optional
            The time step (s) and the length (s) of the runs the model is for: a beam with
            ``modes_per_plane="auto"`` and no ``frequency_cutoff`` keeps the modes at or below
            a cutoff derived from them (``build_chain``).
        tree : {"as added", "shortest"}, optional
            The spanning tree of a system with closing joints: "as added" (default), or
            "shortest": the breadth-first tree from the ground over every joint, tree and
            closing alike, so that each loop runs through the fewest bodies (a loop's rows
            cost a step over its bodies; docs/loops.md, "Choosing the spanning tree").  A
            body the new tree reaches at another point is the same body described from that
            point, so its input point (``position_input``) is that point; the joints keep
            their names, the ones left out of the tree closing the loops.  A joint with
            coordinates the new tree takes from its loop, or runs the other way, starts where
            the system stands: its slides at the gaps between its points, its rates those of
            the bodies' motion at t = 0.

        Returns
        -------
        Model
            The frozen system, bodies numbered parents first (in the order added where that
            allows).

        Raises
        ------
        ValueError
            No bodies; an entry that is not a body or whose joint is not a joint; a body added
            twice; two bodies of one name; a parent not in the system, the body itself, or
            parents that form a cycle; an attachment point the parent does not have (naming
            the points it has); tip not "free" or "ball", or "ball" for a tree; bad gravity or
            ground; and every element's own checks (naming the element, its index and the
            argument; see each class), and the checks across elements: a beam's mode family
            against its ends, a rotation or angular velocity contradicting the joint before a
            body, a ball-joint body with no inertia about its hinge-to-hinge axis; tree not
            "as added" or "shortest", or a tree="shortest" the system cannot be rebuilt on
            (naming the body or the joint).
        """
        if tree not in ("as added", "shortest"):
            raise ValueError(f"System.build: tree must be 'as added' or 'shortest', got "
                             f"{tree!r}")
        bodies, joints, parents, attach = _resolve_topology(self._entries)
        model = _freeze(bodies, joints, parents, attach, self.gravity, self.ground, tip, step,
                        duration, closures=self._closures)
        if tree == "as added" or not self._closures:
            return model
        rebuilt = shortest_tree(self._entries, self._closures, model, bodies)
        if isinstance(rebuilt, str):
            raise ValueError(f"System.build(tree='shortest'): {rebuilt}; build the tree as "
                             f"added (tree='as added')")
        system = System(gravity=self.gravity, ground=self.ground)
        system._entries, system._closures = rebuilt
        return system.build(tip, step, duration)


def build_chain(elements: Sequence, gravity=(0.0, -9.81, 0.0), ground: Ground = Ground(),
                tip="free", step=None, duration=None) -> "Model":
    """Validate a chain described root to tip and freeze it into a Model (a System whose every
    body hangs from the output point of the one before it; the same model as ``System.add``
    body by body).

    Parameters
    ----------
    elements : sequence
        Hinges and bodies alternately, starting with the root hinge (which joins the first
        body to the ground) and ending with the tip body::

            [hinge_0, body_0, hinge_1, body_1, ..., hinge_{n-1}, body_{n-1}]

        Hinges: any joint kind (BallJoint, FixedHinge, ElasticHinge, RevoluteJoint,
        UniversalJoint, PrismaticJoint, ...: elements/kinds.py); bodies: RigidBody,
        EulerBernoulliBeam.
    gravity : array_like of 3, optional
        Gravitational acceleration, world frame, m/s^2 (default (0, -9.81, 0)).
    ground : Ground, optional
        Where the root hinge attaches (default: the origin and the identity frame, fixed).
    tip : {"free", "ball"}, optional
        "free" (default), or "ball": the tip body's output point is joined to the ground by a
        ball-and-socket joint where it starts (a fixed point; e.g. a simply supported beam).
    step : float, optional
        The time step the model will run at, s.  A beam with ``modes_per_plane="auto"`` and
        no ``frequency_cutoff`` keeps the modes at or below 1 / (20 step) Hz (what the step
        resolves, about 20 steps per period), lowered, with ``duration``, to ten times the
        drives' bandwidth: the frequency below which 99% of the energy of the prescribed
        motions' accelerations (the ground's, JointMotion drives') lies over [0, duration]
        (modes well above what drives the system follow it quasi-statically).  Gravity and
        initial conditions excite every mode; where they matter, give frequency_cutoff.
        ``model.describe()`` says which cutoff was kept and why.
    duration : float, optional
        The runs' length, s (with step): the span over which the drives' bandwidth is taken.

    Returns
    -------
    Model
        The frozen chain, body k the k-th body of elements.

    Raises
    ------
    ValueError
        An empty or odd-length elements list; a hinge or body where the other is expected
        (naming the element's position); tip not "free" or "ball"; bad gravity or ground; and
        every element's own checks and the checks across elements, as ``System.build``.

    Examples
    --------
    A triple pendulum of unit rods:

    >>> import dttmm
    >>> def rod():
    ...     return dttmm.RigidBody(mass=1.0, inertia=[1e-4, 1 / 12, 1 / 12],
    ...                            inertia_about="mass_center", to_mass_center=[0.5, 0, 0],
    ...                            to_output=[1.0, 0, 0])
    >>> model = dttmm.build_chain([dttmm.BallJoint(), rod(), dttmm.BallJoint(), rod(),
    ...                            dttmm.BallJoint(), rod()])
    >>> model.n_bodies
    3
    """
    elements = list(elements)
    if len(elements) == 0:
        raise ValueError("Chain: elements is empty; a chain needs at least a root hinge and a body")
    if len(elements) % 2 != 0:
        raise ValueError("Chain: elements must alternate hinge, body, hinge, body, ... and end "
                         f"with a body; got {len(elements)} elements")
    hinges, bodies = elements[0::2], elements[1::2]
    for k, h in enumerate(hinges):
        if joint_kind_of(h) is None:
            raise ValueError(f"Chain: element {2 * k} must be a hinge ({names(JOINT_KINDS)}), "
                             f"got {type(h).__name__}")
    for k, b in enumerate(bodies):
        if body_kind_of(b) is None:
            raise ValueError(f"Chain: element {2 * k + 1} must be a body ({names(BODY_KINDS)}), "
                             f"got {type(b).__name__}")
    parents = [-1] + list(range(len(bodies) - 1))
    return _freeze(bodies, hinges, parents, [0] * len(bodies), gravity, ground, tip, step,
                   duration)


def _resolve_topology(entries):
    """(bodies, joints, parent index, attachment index) in topological order (parents first,
    otherwise as added) from System entries; ValueError for a parent not in the system, an
    attachment point the parent lacks, a body added twice and a cycle."""
    if not entries:
        raise ValueError("System: no bodies; add at least one (System.add(body, joint))")
    for i, (body, joint, _, _) in enumerate(entries):
        if body_kind_of(body) is None:
            raise ValueError(f"System: entry {i}: {body!r} is not a body ({names(BODY_KINDS)})")
        if joint_kind_of(joint) is None:
            raise ValueError(f"System: {_who(body, i)}: joint must be one of "
                             f"{names(JOINT_KINDS)}, got {type(joint).__name__}")
    by_id = {}
    by_name = {}
    for i, (body, _, _, _) in enumerate(entries):
        if id(body) in by_id:
            raise ValueError(f"System: {_who(body, i)} is added twice")
        by_id[id(body)] = i
        if body.name:
            if body.name in by_name:
                raise ValueError(f"System: two bodies are named '{body.name}'; names must be "
                                 f"unique")
            by_name[body.name] = i
    parent_of = []
    for i, (body, _, parent, _) in enumerate(entries):
        if parent is None or (isinstance(parent, str) and parent == "ground"):
            parent_of.append(-1)
        elif isinstance(parent, str):
            if parent not in by_name:
                raise ValueError(f"System: {_who(body, i)}: parent '{parent}' is not in the "
                                 f"system (bodies: {', '.join(sorted(by_name)) or 'none named'})")
            parent_of.append(by_name[parent])
        elif id(parent) in by_id:
            parent_of.append(by_id[id(parent)])
        else:
            raise ValueError(f"System: {_who(body, i)}: parent {_who(parent)} is not in the "
                             f"system (add it too)")
        if parent_of[-1] == i:
            raise ValueError(f"System: {_who(body, i)} is its own parent")
    order, state = [], [0] * len(entries)           # 0 new, 1 on the path, 2 placed

    def place(i, path):
        if state[i] == 2:
            return
        if state[i] == 1:
            cycle = " -> ".join(_who(entries[j][0], j) for j in path[path.index(i):] + [i])
            raise ValueError(f"System: the parents form a cycle: {cycle}")
        state[i] = 1
        if parent_of[i] >= 0:
            place(parent_of[i], path + [i])
        state[i] = 2
        order.append(i)

    for i in range(len(entries)):
        place(i, [])
    new_index = {i: k for k, i in enumerate(order)}
    bodies = [entries[i][0] for i in order]
    joints = [entries[i][1] for i in order]
    parents = [new_index[parent_of[i]] if parent_of[i] >= 0 else -1 for i in order]
    attach = []
    for k, i in enumerate(order):
        at, p = entries[i][3], parents[k]
        if p < 0 and at is not None and not isinstance(at, str):    # a point of the ground
            at = finite_vector(f"System: {_who(bodies[k], i)}", "at (a point of the ground)", at)
            attach.append(at)
            continue
        if at is None or at == "output":
            attach.append(0)
            continue
        if p < 0:
            raise ValueError(f"System: {_who(bodies[k], i)}: at={at!r}: the ground has no named "
                             f"points; give a root's place on the ground as [x, y, z] (m, in "
                             f"the ground frame from the ground point), or leave at=None")
        pts = getattr(bodies[p], "points", None) or {}
        if at not in pts:
            raise ValueError(f"System: {_who(bodies[k], i)}: at={at!r}: {_who(bodies[p])} has no "
                             f"attachment point {at!r} (it has: {', '.join(['output', *pts])})")
        attach.append(1 + list(pts).index(at))
    return bodies, joints, parents, attach


def _who(body, index=None):
    where = f" (entry {index})" if index is not None else ""
    name = getattr(body, "name", "")
    return f"{type(body).__name__} '{name}'{where}" if name else f"{type(body).__name__}{where}"


MAX_GRAVITY = 1e6      # m/s^2 (1e5 g): System's gravity beyond it is refused as non-physical


def _freeze(bodies, hinges, parents, attach, gravity, ground, tip, step=None, duration=None,
            closures=()):
    """Validate every element and the system, and freeze them into a Model.  bodies, hinges:
    in topological order; parents[k] < k the parent body of body k (-1: the ground); attach[k]
    its attachment point on the parent (0: the output point, j: the parent's j-th named
    point); closures: the loop-closing joints as System.close took them (tip="ball" adds one
    from the last body's output point to the ground)."""
    if tip not in ("free", "ball"):
        raise ValueError(f"System: tip must be 'free' or 'ball', got {tip!r}")
    n = len(bodies)
    for k, element in enumerate(list(bodies) + list(hinges)):
        name = getattr(element, "name", "")
        if not isinstance(name, str):
            raise ValueError(f"{type(element).__name__} ({'body' if k < n else 'hinge'} "
                             f"{k if k < n else k - n}): name must be a string, got {name!r}")
        if k < n and name == "ground":
            raise ValueError(f"{type(element).__name__} (body {k}): the name {name!r} is the "
                             f"ground's (parent='ground' means the ground): choose another")
    parent = np.array(parents, dtype=np.int64)
    ground_points = {k: a for k, a in enumerate(attach) if not np.isscalar(a)}
    attachment = np.array([0 if k in ground_points else a for k, a in enumerate(attach)],
                          dtype=np.int64)
    chain = bool(np.all(parent == np.arange(n) - 1) and np.all(attachment == 0))
    if tip == "ball" and not chain:
        raise ValueError("System: tip='ball' joins the last body of a chain to the ground; this "
                         "system is a tree: close its loops with System.close(joint, body, "
                         "'ground')")
    if tip == "ball" and ground.motion is not None:
        raise ValueError("System: tip='ball' pins the tip to a point of the ground, and loops on "
                         "a moving ground do not run in DT-TMM yet")
    g = finite_vector("System", "gravity", gravity)
    if np.abs(g).max() > MAX_GRAVITY:
        raise ValueError(f"System: gravity {g} m/s^2 is beyond any physical system's (at most "
                         f"{MAX_GRAVITY:g} m/s^2, 1e5 g, here): a slip of units? Give it in m/s^2")
    if not isinstance(ground, Ground):
        raise ValueError("System: ground must be a Ground")
    if ground.motion is not None:
        if ground.rotation is not None or np.any(finite_vector("Ground", "position",
                                                               ground.position) != 0.0):
            raise ValueError("Ground: with a motion, the ground's position and rotation are the "
                             "motion's: give them to the PrescribedMotion, not to Ground")
        ground.motion.check()
        r_g, _, _, rot_g, w_g, _ = ground.motion(0.0)
        r_g = finite_vector("Ground", "motion position(0)", r_g)
        rot_g = rotation_matrix("Ground", "motion rotation(0)", rot_g)
        w_g = finite_vector("Ground", "motion angular_velocity(0)", w_g)
    else:
        r_g = finite_vector("Ground", "position", ground.position)
        rot_g = np.eye(3) if ground.rotation is None else rotation_matrix("Ground", "rotation",
                                                                          ground.rotation)
        w_g = np.zeros(3)

    bv = _validated(bodies)
    hv = _validated(hinges)
    kinds = np.array([joint_kind_of(h).code for h in hinges], dtype=np.int64)
    body_kind = np.array([body_kind_of(b).code for b in bodies], dtype=np.int64)
    children = children_of(parent)
    beam_params = _packed(bv, lambda v: v.get("beam", _NO_BEAM))
    if (body_kind == BEAM).any():           # (written per beam below: its own rows)
        beam_params = np.array(beam_params, order="C")
    rod_params = _packed(bv, lambda v: v.get("rod", _NO_ROD))
    attachment_point = np.zeros((n, 3))
    for k in range(n):
        p = parent[k]
        if p < 0:               # a root's place on the ground (ground frame, from its point)
            attachment_point[k] = ground_points.get(k, 0.0)
            continue
        if body_kind[p] in FLEXIBLE and attachment[k] != 0:
            what = "a beam" if body_kind[p] == BEAM else "a strain rod"
            raise ValueError(f"{bodies[k].label(k)}: {what} has one attachment point, its "
                             f"output end")
        attachment_point[k] = (bv[p]["l_io"] if attachment[k] == 0
                               else list(bv[p]["points"].values())[attachment[k] - 1])
    derived = None
    from_step = (body_kind == BEAM) & (beam_params[:, FREQUENCY_CUTOFF] == FROM_STEP)
    if np.any(from_step):
        derived = _derived_cutoff(step, duration, ground, hv, bodies, beam_params)
    closures = list(closures)
    if tip == "ball":
        closures.append((BallJoint(name="tip"), bodies[-1], "ground", None, None))
    loops = loop_membership(closures, bodies, parent)
    beam_ends, loop_stiffened = _resolve_mode_families(
        bodies, bv, hv, kinds, body_kind, beam_params, parent, children, loops,
        None if derived is None else derived[0])
    if (body_kind == ROD).any():
        rod_params = _count_rod_strains(bodies, bv, hv, kinds, body_kind, rod_params, parent,
                                        loops)
    _check_ball_lookahead(bodies, bv, kinds, body_kind, children, attachment)

    rotations = np.zeros((n, 3, 3))
    omegas = np.zeros((n, 3))
    locked = np.zeros(n, dtype=bool)
    for k in range(n):
        p = parent[k]
        if p < 0:
            a_in, w_in = rot_g, w_g
        elif attachment[k] == 0 and body_kind[p] == ROD:      # its end section
            _, a_in, w_in = rod_end_section(rod_params[p], rotations[p], omegas[p],
                                            bv[p]["eta0"], bv[p]["eta_d0"])
        elif attachment[k] == 0:     # the parent's output section (a beam's end section)
            a_in, w_in = output_section(beam_params[p], rotations[p], omegas[p],
                                        bv[p].get("eta0"), bv[p].get("eta_d0"))
        else:
            a_in, w_in = rotations[p], omegas[p]
        locked[k] = kinds[k] == FIXED and (p < 0 or (locked[p] and body_kind[p] == RIGID))
        if kinds[k] in WITH_COORDINATES:
            hv[k] = dict(hv[k])     # (its own: _validated's dicts are shared)
            rot, om, hv[k]["rotation"] = _joint_start(kinds[k], hv[k], a_in, w_in,
                                                      bv[k]["rotation"], bv[k]["omega"],
                                                      hinges[k].__class__.__name__,
                                                      bodies[k].label(k))
        elif kinds[k] == FIXED:
            rot, om = a_in @ hv[k]["rotation"], w_in
            for key, implied in (("rotation", rot), ("omega", om)):
                given = bv[k][key]
                if given is not None and not np.allclose(given, implied, atol=1e-9):
                    arg = "rotation" if key == "rotation" else "angular_velocity"
                    raise ValueError(f"{bodies[k].label(k)}: {arg} contradicts the fixed hinge "
                                     f"before it (the body moves with its inboard neighbour); "
                                     f"leave it None")
        else:
            default = a_in @ hv[k]["rotation"] if kinds[k] != BALL else np.eye(3)
            rot = default if bv[k]["rotation"] is None else bv[k]["rotation"]
            om = np.zeros(3) if bv[k]["omega"] is None else bv[k]["omega"]
        rotations[k], omegas[k] = rot, om
    flexible = [k for k in range(n) if body_kind[k] in FLEXIBLE]

    tree = Model(
        n_bodies=n,
        body_params=_packed(bv, pack_body),
        hinge_kind=kinds,
        hinge_params=_packed(hv, pack_hinge),
        gravity=g,
        ground_position=r_g,
        ground_rotation=rot_g,
        ground_motion=ground.motion,
        initial_rotation=rotations,
        initial_angular_velocity=omegas,
        ground_locked=locked,
        forces=tuple(v["force"] for v in bv),
        torques=tuple(v["torque"] for v in bv),
        line_loads=tuple(v.get("line_load") for v in bv),
        body_names=tuple(_own_copy(b.name or f"body{k}") for k, b in enumerate(bodies)),
        hinge_names=tuple(_own_copy(h.name or f"{HINGE_KIND_NAMES[h.kind]}{k}")
                          for k, h in enumerate(hinges)),
        body_mass_center_inertia=_packed(bv, lambda v: v["j_c"]),
        body_kind=body_kind,
        beam_params=beam_params,
        rod_params=rod_params,
        initial_modal_coordinates=np.concatenate([np.zeros(0)]
                                                 + [bv[k]["eta0"] for k in flexible]),
        initial_modal_velocities=np.concatenate([np.zeros(0)]
                                                + [bv[k]["eta_d0"] for k in flexible]),
        parent=parent,
        attachment=attachment,
        attachment_point=attachment_point,
        drives=tuple(v.get("drives", ()) for v in hv),
        frequency_cutoff_reasons=tuple(derived[1] if f else "" for f in from_step),
        beam_ends=tuple(beam_ends),
    )
    tree = replace(tree, **{name: shared_rows(getattr(tree, name)) for name in SHARED_TABLES})
    adopt_arrays(tree)
    if not closures:
        return tree
    index_of = {id(b): k for k, b in enumerate(bodies)}
    named = [dict(v.get("points") or {}) for v in bv]
    return _unstiffen_held_chords(adopt_arrays(
        replace(tree, **closure_rows(tree, closures, index_of, named)), tree), loop_stiffened)


def _unstiffen_held_chords(model, candidates):
    """Resolve stiffening=None of the inextensible beams in closed loops (the candidates,
    stiffened so far): off where the loops hold the beam's chord length (closures.held_chords:
    held between points that cannot approach, it could not bow), on elsewhere (a four-bar's
    coupler: its ends move)."""
    held = closures.held_chords(model, candidates)
    if not held:
        return model
    params = np.array(model.beam_params, order="C")
    params[held, STIFFENING] = 0.0
    return adopt_arrays(replace(model, beam_params=params), model)


def _joint_start(kind, v, a_in, w_in, given_rot, given_omega, joint_name, who):
    """A child's rotation and angular velocity at t = 0 behind a joint with coordinates, and the
    joint's R0 (elements/joints.py): A = A_P R_P R0 R_C, R_P and R_C the joint's turns fixed in
    the parent and in the child (A_P Rot(n, q) R0 for a revolute joint, A_P Rot(n1, q1) R0
    Rot(n2, q2) for a universal one, A_P R0 for a prismatic one); w = w_P + the turns' rates
    about their axes (elements/kinds.py::joint_motion).  A kind with a turn in each frame needs
    their axes perpendicular at q = 0 (its closing row keeps them so)."""
    axes, q0, qd0 = v["axes"], v["q0"], v["qd0"]
    r_p, r_c = turn_rotations(kind, axes, q0)
    r0 = np.eye(3) if given_rot is None else r_p.T @ a_in.T @ given_rot @ r_c.T
    turns = {c.frame: c.axis for c in coordinates_of(kind) if c.motion == TURN}
    if len(turns) == 2:
        names = JOINT_KIND[int(kind)].axes
        first, second = names[turns[PARENT]], names[turns[CHILD]]
        dot = float(axes[turns[PARENT]] @ (r0 @ axes[turns[CHILD]]))
        if abs(dot) > 1e-9:
            raise ValueError(f"{joint_name} before {who}: {first} and {second} must be "
                             f"perpendicular ({first} . {second} in the parent's frame at q = 0: "
                             f"{dot:.3g})")
    rot, omega, _, _, _ = joint_motion(kind, axes, r0, a_in, w_in, q0, qd0)
    if given_omega is not None and not np.allclose(given_omega, omega, atol=1e-9):
        raise ValueError(f"{who}: angular_velocity {given_omega} contradicts the {joint_name} "
                         f"before it (the body turns with its parent and the joint's rates: "
                         f"{omega}); leave it None and give the joint's rates")
    return rot, omega, r0


def _derived_cutoff(step, duration, ground, hv, bodies, beam_params):
    """(cutoff, why) for the beams with modes_per_plane="auto" and no frequency_cutoff
    (build_chain's step and duration): 1 / (20 step) Hz, lowered to ten times the drives'
    bandwidth over [0, duration] where the model has prescribed motions that vary."""
    if step is None:
        k = int(np.nonzero(beam_params[:, FREQUENCY_CUTOFF] == FROM_STEP)[0][0])
        raise ValueError(f"{bodies[k].label(k)}: modes_per_plane='auto' without a "
                         f"frequency_cutoff takes its cutoff from the step the model will run "
                         f"at: build it with step=dt (and duration=t_end, to bound it by the "
                         f"drives' bandwidth), or give frequency_cutoff (Hz)")
    step = finite_scalar("System", "step", step, positive=True)
    f_step = 1.0 / (20.0 * step)
    why = f"from the step {step:g} s: 1 / (20 step) = {f_step:.4g} Hz"
    if duration is None:
        return f_step, why
    duration = finite_scalar("System", "duration", duration, positive=True)
    bandwidth = drives_bandwidth(step, duration, ground.motion,
                                 [d for v in hv for d in v.get("drives", ())
                                  if d is not None and d["kind"] == MOTION])
    if bandwidth is None:
        return f_step, why + " (no prescribed motion varies to bound it)"
    if 10.0 * bandwidth < f_step:
        return 10.0 * bandwidth, (f"ten times the drives' bandwidth, {bandwidth:.4g} Hz (99% of "
                                  f"their acceleration's energy below it over {duration:g} s; "
                                  f"the step {step:g} s would resolve {f_step:.4g} Hz)")
    return f_step, why + f" (below ten times the drives' bandwidth, {bandwidth:.4g} Hz)"


def drives_bandwidth(step, duration, ground_motion, motions, max_samples=1 << 15):
    """The drives' bandwidth, Hz: the largest, over the ground's acceleration and angular
    acceleration components and each JointMotion's acceleration sampled every step over
    [0, duration] (at most max_samples points), of the frequency below which 99% of the
    signal's energy (its spectrum's, mean removed) lies; None when no prescribed motion varies
    (no motion, or constant accelerations)."""
    n = int(min(max_samples, np.floor(duration / step) + 1))
    t = np.linspace(0.0, duration, n)
    signals = []
    if ground_motion is not None:
        states = [ground_motion(ti) for ti in t]
        signals += list(np.array([s[2] for s in states]).T)
        signals += list(np.array([s[5] for s in states]).T)
    for drive in motions:
        acceleration = drive["function"][2]
        signals.append(np.array([float(acceleration(ti)) for ti in t]))
    best = None
    for s in signals:
        s = np.asarray(s, dtype=float) - np.mean(s)
        if not np.any(np.abs(s) > 1e-12 * (1.0 + np.max(np.abs(s)))):
            continue
        power = np.abs(np.fft.rfft(s)) ** 2
        share = np.cumsum(power) / np.sum(power)
        f99 = np.fft.rfftfreq(n, t[1] - t[0])[int(np.searchsorted(share, 0.99))]
        best = f99 if best is None else max(best, f99)
    return best


def _resolve_mode_families(bodies, bv, hv, kinds, body_kind, beam_params, parent, children,
                           loops, derived_cutoff=None):
    """Write each beam's mode family into beam_params (docs/beam.md, "Mode shapes").  "auto":
    pinned between moment-free ends (ball joints, the free or pinned tip); otherwise clamped in
    the input section's frame, with the clamped-free eigenfunctions when the output is the free
    tip and the loaded-end polynomial modes when it carries loads.  An explicit choice that
    contradicts the hinges is refused (clamped between moment-free ends only if the user
    insists).  An elastic hinge at the input clamps the beam elastically (the frame is the input
    section's, as after a fixed hinge); one at the output loads it (loaded-end modes).
    loops = (in_loop, closed_output, output_moment, output_pinned) per body
    (closures.loop_membership): a closing joint at a beam's output end holds it like a child's
    joint (a ball joint: moment-free).  The mode count of modes_per_plane=None is estimated for
    the beam's own ends (root_pinned, output_pinned; elements/beam.py::truncation_errors);
    returns them per body ((root pinned, tip pinned) for a beam, None for another body), and
    the beams whose stiffening=None waits for the loops (in a loop without stretch modes)."""
    n = len(bodies)
    in_loop, closed_output, output_moment, output_pinned = loops
    end_mass = outboard_masses([v["mass"] for v in bv], parent)
    ends, candidates = [None] * n, []
    for k in range(n):
        if body_kind[k] != BEAM:
            continue
        who = bodies[k].label(k)
        input_free = kinds[k] == BALL
        leaf = not children[k]
        # an applied end load (docs/beam.md, "Loads on the beam") loads the output: the free
        # tip's eigenfunctions carry none, and a torque needs the sections' rotations
        loaded = bv[k]["force"] is not None or bv[k]["torque"] is not None
        free_tip = leaf and not closed_output[k] and not loaded
        # a leaf's output is the tip (free or pinned); otherwise every joint there moment-free
        output_free = ((leaf or all(kinds[c] == BALL for c in children[k]))
                       and bv[k]["torque"] is None and not output_moment[k])
        family = int(beam_params[k, FAMILY])
        if family == PINNED and not (input_free and output_free):
            raise ValueError(f"{who}: mode_family 'pinned' needs moment-free ends (a ball joint "
                             f"or the tip at both ends, no end_torque); a fixed or elastic "
                             f"hinge, or an end torque, holds this beam: use 'clamped' (or "
                             f"'auto')")
        if family == CLAMPED and input_free and output_free and not bv[k]["force_mode_family"]:
            raise ValueError(f"{who}: mode_family 'clamped' contradicts the moment-free ends of "
                             f"the beam (pass force_mode_family=True to insist)")
        if family == AUTO and input_free and output_free:
            family = PINNED
        elif family != PINNED:
            family = CLAMPED if free_tip else CLAMPED_LOADED
        beam_params[k, FAMILY] = family
        ends[k] = (family != PINNED and root_pinned(bodies[k], kinds[k], hv[k]),
                   family != PINNED and bool(output_pinned[k]))
        if beam_params[k, FREQUENCY_CUTOFF] == FROM_STEP:   # derived (build_chain's step)
            beam_params[k, FREQUENCY_CUTOFF] = derived_cutoff
        if beam_params[k, FREQUENCY_CUTOFF] == ACCURATE:    # modes_per_plane=None
            beam_params[k, MODES] = accurate_mode_count(beam_params[k], end_mass[k], ends[k])
            bv[k] = dict(bv[k], eta0=np.zeros(modal_size(beam_params[k])),    # (its own dict:
                         eta_d0=np.zeros(modal_size(beam_params[k])))       # copy on write)
        if beam_params[k, FREQUENCY_CUTOFF] > 0.0:          # modes_per_plane="auto"
            beam_params[k, MODES] = max(auto_mode_count(beam_params[k]),
                                        accurate_mode_count(beam_params[k], end_mass[k],
                                                            ends[k]))
            for part, frequencies in ((TORSION_MODES, torsion_frequencies),
                                      (AXIAL_MODES, axial_frequencies)):
                if beam_params[k, part] == AUTO:           # "auto" twist or stretch
                    beam_params[k, part] = auto_part_count(beam_params[k], frequencies)
            bv[k] = dict(bv[k], eta0=np.zeros(modal_size(beam_params[k])),
                         eta_d0=np.zeros(modal_size(beam_params[k])))
        if beam_params[k, STIFFENING] == AUTO:
            # stiffening=None: on; to all orders where the build counted 3 or more modes for a
            # pinned end (the second-order energy then holds only to a bend of 0.08 rad or
            # less, which a swinging or coupled link passes: docs/beam.md, "Where the
            # second-order energy stops"); an inextensible beam (no stretch modes) in a closed
            # loop is a candidate, which the build turns off where the loops hold its chord (it
            # could not bow: _unstiffen_held_chords)
            counted = (beam_params[k, FREQUENCY_CUTOFF] == ACCURATE
                       or beam_params[k, FREQUENCY_CUTOFF] > 0.0)
            beam_params[k, STIFFENING] = (EXACT if counted and any(ends[k])
                                          and beam_params[k, MODES] >= 3 else 1.0)
            if in_loop[k] and beam_params[k, AXIAL_MODES] == 0:
                candidates.append(k)
        if family == CLAMPED_LOADED and beam_params[k, MODES] > MAX_LOADED_MODES:
            raise ValueError(f"{who}: modes_per_plane must be <= {MAX_LOADED_MODES} for a "
                             f"clamped beam whose output carries loads (polynomial modes), got "
                             f"{int(beam_params[k, MODES])}")
        beam_params[k, FAMILY] = family
    return ends, candidates


def _count_rod_strains(bodies, bv, hv, kinds, body_kind, rod_params, parent, loops):
    """strain_modes=None of a strain rod with a pinned end (its root behind a ball joint or a
    free revolute or universal joint, its output held by a closing ball, revolute or universal
    joint): the count of a loaded-end modal beam with those ends and what hangs on it
    (elements/beam.py::accurate_mode_count; the rod's deflection polynomials are those modes'),
    its stations count + 3 unless given, its strain coordinates zero.  Other rods keep 2."""
    output_pinned = loops[3]
    end_mass = outboard_masses([v["mass"] for v in bv], parent)
    rods = np.array(rod_params, order="C")
    for k in np.nonzero(body_kind == ROD)[0]:
        if not bv[k].get("counted"):
            continue
        ends = (root_pinned(bodies[k], kinds[k], hv[k]),
                bool(output_pinned[k]))
        if not any(ends):
            continue
        row = np.zeros(BEAM_PARAM_SIZE)
        row[LENGTH], row[MASS_PER_LENGTH] = rods[k, ROD_LENGTH], rods[k, ROD_MU]
        row[FAMILY] = CLAMPED_LOADED
        count = accurate_mode_count(row, end_mass[k], ends)
        rods[k, ROD_MODES] = count
        if not bv[k].get("stations_given"):
            rods[k, ROD_STATIONS] = count + 3
        nq = rod_coordinate_count(rods[k])
        bv[k] = dict(bv[k], eta0=np.zeros(nq), eta_d0=np.zeros(nq))
    return rods


def root_pinned(body, kind, joint):
    """Whether a body's root joint lets it turn freely in some bending plane of its own: a
    joint with a turn that no JointMotion prescribes (elements/kinds.py's declaration), about an
    axis not along the body's x (R0 is the identity unless the body was given a rotation; then
    the axis in its frame is not known before the build's kinematics, and a free turn counts
    as pinned).  A ball joint: always."""
    if kind == BALL:
        return True
    for c, drive in zip(coordinates_of(kind), joint.get("drives", ())):
        if c.motion != TURN or (drive is not None and drive["kind"] == MOTION):
            continue
        if getattr(body, "rotation", None) is not None or abs(joint["axes"][c.axis][0]) < \
                1.0 - 1e-9:
            return True
    return False


def _validated(elements):
    """Each element's checked parameters (its validated(k)), each distinct set of parameters
    checked once: a chain of 10^6 copies of one link checks one link, not 10^6 (a check is
    ~0.3 ms of small numpy calls; the key ~5 us).  Elements with equal parameters (their
    names aside, which only the messages read) share the one dict (the build replaces an
    element's dict where it changes one: copy on write; a million shallow copies held 0.7 GB
    during a build); the first of them is the one a message names."""
    checked, out = {}, []
    for k, element in enumerate(elements):
        key = _parameters_key(element)
        if key is None:
            out.append(element.validated(k))
            continue
        try:
            done = checked.get(key)
        except TypeError:               # nested sequences: the deep key
            key = _parameters_key(element, deep=True)
            done = checked.get(key)
        if done is None:
            done = checked[key] = element.validated(k)
        out.append(done)
    return out


def _own_copy(name):
    """A new string equal to name, the model's own.  The caller's names were made between its
    elements, and each one kept would pin the allocator's pages that held the elements after
    they are gone: a million links named in a loop left 340 B a body resident (issue 65, item
    11); the copies are made together."""
    return name.encode().decode()


def _packed(checked, pack):
    """(n, ...) rows pack(v) of the elements' checked parameters, each packed once per set of
    the same values (_validated's shared dicts, unless the build replaced one); one row shown
    n times where they are all the same (shared_rows, without making the n rows)."""
    rows, done = [], {}
    for v in checked:
        key = id(v)
        row = done.get(key)
        if row is None:
            row = done[key] = np.asarray(pack(v), dtype=float)
        rows.append(row)
    if len(rows) > 1 and len(done) == 1:
        return _shown_for_all(rows[0], len(rows))
    return np.array(rows)


_KEY_FIELDS = {}     # an element class's parameter fields (_parameters_key)
_SCALARS = (float, int, str, bool, type(None))


def _frozen(value):
    """A hashable stand-in of a parameter's value, to any depth (functions and other objects:
    their identity)."""
    if type(value) in _SCALARS:
        return value
    if isinstance(value, (list, tuple)):
        return ("seq",) + tuple(map(_frozen, value))
    if isinstance(value, np.ndarray):
        return ("array", value.shape, value.dtype.str, value.tobytes())
    if isinstance(value, dict):
        return ("dict",) + tuple((_frozen(k), _frozen(v)) for k, v in value.items())
    if isinstance(value, np.generic):
        return value.item()
    return ("id", id(value))


def _parameters_key(element, deep=False):
    """A key of an element's parameters (its dataclass fields but its name), or None where
    one cannot be made (not a dataclass).  Shallow (the common case, fast): a sequence is
    the tuple of its items, which is not hashable where they are lists; deep: _frozen."""
    cls = type(element)
    names = _KEY_FIELDS.get(cls)
    if names is None:
        try:
            names = tuple(f.name for f in fields(element)
                          if f.name != "name" and not f.name.startswith("_"))
        except TypeError:
            return None
        _KEY_FIELDS[cls] = names
    if deep:
        return (cls,) + tuple(_frozen(getattr(element, name)) for name in names)
    key = [cls]
    for name in names:
        value = getattr(element, name)
        kind = type(value)
        if kind is list or kind is tuple:
            value = ("seq", tuple(value))
        elif kind is np.ndarray:
            value = ("array", value.shape, value.dtype.str, value.tobytes())
        elif kind not in _SCALARS:
            value = ("id", id(value))
        key.append(value)
    return tuple(key)


def children_of(parent):
    """Each body's children in order, from the parents (-1: the ground), in one pass (a scan
    of every body per body is quadratic: minutes at 10^5 bodies)."""
    children = [[] for _ in range(len(parent))]
    for c, p in enumerate(np.asarray(parent).tolist()):
        if p >= 0:
            children[p].append(c)
    return children


def outboard_masses(masses, parent):
    """Per body: the mass of everything attached beyond it (its descendants), kg; a child's
    index is above its parent's (parent[k] < k, -1 for the ground)."""
    total = np.array(masses, dtype=float)
    for k in range(len(total) - 1, -1, -1):
        if parent[k] >= 0:
            total[parent[k]] += total[k]
    return total - np.array(masses, dtype=float)


def _check_ball_lookahead(bodies, bv, kinds, body_kind, children, attachment):
    """A body between two moment-free cuts (ball joints or the free tip) finds its rotation from
    its own moment equation, whose matrix is -chi1 (J_I + M l_IO^ l_IC^) (docs/rigid_body.md).
    If that matrix is singular (no inertia about the hinge-to-hinge axis) the step is undefined.
    (Checked for a leaf and for a body with one child at its output.)"""
    checked, leaves = [], []
    for k in range(len(bodies)):
        leaf = not children[k]
        single = len(children[k]) == 1 and attachment[children[k][0]] == 0
        outboard_free = leaf or (single and kinds[children[k][0]] == BALL)
        if kinds[k] == BALL and outboard_free and body_kind[k] == RIGID:
            checked.append(k)
            leaves.append(leaf)
    if not checked:
        return
    # all at once (a million bodies): J_I, or J_I + M l_IO^ l_IC^ below a ball joint (a free
    # tip takes no force at its output point)
    j_i = np.array([bv[k]["j_i"] for k in checked])
    mass = np.array([bv[k]["mass"] for k in checked])
    l_io = np.array([bv[k]["l_io"] for k in checked])
    l_ic = np.array([bv[k]["l_ic"] for k in checked])
    arm = np.where(np.array(leaves)[:, None, None], 0.0,
                   mass[:, None, None] * _hat(l_io) @ _hat(l_ic))
    s = np.linalg.svd(j_i + arm, compute_uv=False)
    bad = s[:, -1] <= 1e-10 * np.maximum(s[:, 0], 1e-300)
    if bad.any():
        i = int(np.argmax(bad))
        k = checked[i]
        raise ValueError(f"{bodies[k].label(k)}: inertia: the ball-joint look-ahead is "
                         f"singular (singular values of J_I + M l_IO^ l_IC^: {s[i]}); the body "
                         f"has no inertia about its hinge-to-hinge axis")


def _hat(v):
    """v^ of (m, 3) vectors: (m, 3, 3)."""
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2], out[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    out[..., 1, 0], out[..., 2, 0], out[..., 2, 1] = v[..., 2], -v[..., 1], v[..., 0]
    return out
