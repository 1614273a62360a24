"""The chain description: built from elements, validated once, frozen into flat arrays."""
import functools
from dataclasses import dataclass, field, fields
from functools import cached_property
from typing import Optional

import numpy as np

from . import closures
from .closures import empty_table, is_pinned_tip
from ..elements import BEAM, ROD
from ..elements._checks import derivative, finite_vector, rotation_matrix
from ..elements.beam import (
     AXIAL_MODES,
     BEAM_PARAM_SIZE,
     EXACT,
     LOAD_AXES,
     MODES,
     STIFFENING,
     TORSION_MODES,
 )
from ..elements.kinds import (
     JOINT_KIND,
 )
from ..elements.contact import CONTACT_SIZE
from ..elements.rigid_body import MASS
from ..elements.strain_rod import (
     ROD_PARAM_SIZE,
     rod_coordinate_count,
 )


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


# Model.describe's words, set by the describing layer (interfaces/describe.py, which knows what
# runs a model: the loops, the schemes, the steps) when dttmm is imported: the model imports
# nothing above it.
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
    plane : Plane, optional
        A plane of the ground (in the ground frame) that the bodies' shapes touch
        (docs/contact.md).  None (default): nothing touches.  Refused beside a motion.

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
    plane: object = None


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
        R0 and the axes) and names (dttmm/model/closures.py, docs/loops.md).  Empty for a tree.
    closure_drives : tuple
        Per closing joint, per coordinate, its drive as ``drives`` (a prescribed motion or a
        spring-damper) or None.
    contacts : ndarray (n_contacts, CONTACT_SIZE)
        The rigid bodies' contact spheres against the ground's plane, one row each
        (elements/contact.py: the body, the sphere's centre and radius, the plane, the contact
        law's parameters; docs/contact.md).  Empty without shapes.

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
    contacts: np.ndarray = field(default_factory=lambda: np.zeros((0, CONTACT_SIZE)))
    # (n_contacts, CONTACT_SIZE): the bodies' contact spheres against the ground's plane, body
    # by body (elements/contact.py)

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
                or self.has_follower_loads or self.has_exact_foreshortening
                or len(self.contacts) > 0)

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
