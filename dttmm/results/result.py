"""One result object for every solver: recorded samples of the chain's state, and energies."""
import csv
import json

import numpy as np

from ..elements import BEAM, RIGID, ROD
from ..model.rod_motion import rod_energies
from ..vectors import cross, rows_dot
from ..elements.beam import (AXIAL_MODES, EA, EI_V, EI_W, EXACT, FAMILY, GJ, LENGTH,
                             MASS_PER_LENGTH, MODES, POLAR_PER_LENGTH, STIFFENING, TORSION_MODES,
                             mode_shapes, stretch_along,
                             torsion_shapes)
from ..elements.drives import MOTION, SPRING_DAMPER
from ..elements.hinges import ELASTIC, K_ROTATION, K_TRANSLATION, REST_ROTATION
from ..elements.rigid_body import MASS, TO_MASS_CENTER
from ..elements.kinds import limit_of, unimplemented_body_kind
from ..elements.limits import stop_force
from ..model.sections import (_GL_W, _GL_X, foreshortening_along, log_rotation,
                              element_end_section, rotation_to_quaternion)


FIELDS = (
    "method", "t", "position_input", "position_mass_center", "position_output", "rotation",
    "angular_velocity", "angular_acceleration", "force", "moment", "kinetic", "potential",
    "wall_time", "n_steps", "info", "velocity_input", "modal_coordinates", "modal_velocities",
    "joint_coordinates", "joint_rates", "drive_force", "body_names", "checkpoint",
    "energy_work", "closure_force", "closure_moment", "closure_drive_force", "limit_force",
    "contact_force", "contact_point", "contact_normal")
# computed from the stored state on first use, when the solver leaves them to its derivation
DERIVED = ("position_input", "position_mass_center", "position_output", "velocity_input",
           "kinetic", "potential")
# the stored state the derived fields come from
_STATE_OF_DERIVED = {"t", "rotation", "angular_velocity", "modal_coordinates",
                     "modal_velocities", "joint_coordinates"}
_DEFAULTS = dict(wall_time=0.0, n_steps=0, info=None, body_names=None, checkpoint=None)
# the fields a solver's Result (Result._of_run) holds before its own: every field not left to
# the derivation
_RUN_DEFAULTS = {name: _DEFAULTS.get(name) for name in FIELDS if name not in DERIVED}


def _plot_method(name, what, more_options="", missing=None):
    """Result.<name>: dttmm.results.plots.<name> on this result (matplotlib imported when
    called)."""
    def method(self, **options):
        from . import plots
        return getattr(plots, name)(self, **options)

    method.__name__ = method.__qualname__ = name
    method.__doc__ = (
        f"{what} (dttmm.results.plots.{name}).\n\n"
        f"        Parameters\n        ----------\n        **options\n"
        f"            Passed to ``dttmm.results.plots.{name}``: ax (matplotlib axes to draw on, "
        f"default a new\n            figure), title (str){more_options}.\n\n"
        f"        Returns\n        -------\n        matplotlib.figure.Figure\n"
        f"            The figure.\n\n"
        f"        Raises\n        ------\n        ImportError\n"
        f"            Without matplotlib (``pip install 'dttmm[plots]'``).\n"
        + (f"        ValueError\n            {missing}\n" if missing else ""))
    return method


class Result:
    """Samples of a run, one row per recorded time.  Shapes: T samples, n bodies.

    Made by ``simulate`` and ``simulate_reference`` (and ``Result.load_npz``); every field is
    an attribute of the same name.  The positions, velocities and energies of a DT-TMM run are
    computed from the stored state (rotations, rates, beams' and joints' coordinates) the first
    time they are read, all samples at once, and kept; a run that records many samples pays
    for them only if asked.  A Result is read-only (``replace`` makes a changed copy).

    Parameters
    ----------
    derivation : callable, optional
        derivation(name) -> dict of derived fields (any of position_input,
        position_mass_center, position_output, velocity_input, kinetic, potential), called
        the first time one of them is read and not given; the solvers' business.  None
        (default): the fields are as given.
    **values
        The fields below by name; method and t are required, the others default to None
        (wall_time 0, n_steps 0, info {}).

    Attributes
    ----------
    method : str
        The solver: "dttmm", or "newton-euler/DOP853" (or "/RK45") for the reference.
    t : ndarray (T,)
        The recorded times, s.
    position_input, position_mass_center, position_output : ndarray (T, n, 3)
        World positions of each body's input point, mass centre and output point, m (a
        beam's output point deflected; its mass centre deflected in the reference, the
        chord's midpoint in DT-TMM, docs/beam.md).
    velocity_input : ndarray (T, n, 3)
        World velocity of each input point, m/s.
    rotation : ndarray (T, n, 3, 3)
        Body-to-world rotation matrices (a beam's floating frame).
    angular_velocity : ndarray (T, n, 3)
        World frame, rad/s.
    angular_acceleration : ndarray (T, n, 3)
        World frame, rad/s^2.
    force, moment : ndarray (T, n, 3)
        What the inboard side exerts on each body at its input point (moment about that
        point), world frame, N and N m.
    kinetic, potential : ndarray (T,)
        Energies, J; potential counts gravity, the hinges' springs, the drives' springs and
        the beams' strain energy.  ``total_energy`` is their sum.
    modal_coordinates, modal_velocities : ndarray (T, total modes) or None
        The beams' modal coordinates eta (m) and rates (m/s), concatenated in body order (a
        beam's v coordinates first, then w); None when the model has no beams.
    joint_coordinates, joint_rates, drive_force : ndarray (T, total coordinates) or None
        The joints with coordinates (revolute, universal, prismatic), in hinge order, a
        joint's in its own order: coordinates (rad or m), rates (rad/s or m/s), and the
        generalized force (N m or N) each coordinate's drive applies on the child (for a
        prescribed motion, the force the motion needs); None without such joints.
    closure_force, closure_moment : ndarray (T, closing joints, 3) or None
        What each closing joint (``System.close``, in the order closed) exerts on its side b,
        world axes: the force (N) and the couple about b's point (N m); side a receives the
        opposite.  None without closing joints.
    limit_force : ndarray (T, total coordinates) or None
        Each joint coordinate's end stops' generalized force on the child (N m or N;
        JointLimit, docs/limits.md), in joint_coordinates' columns: 0 between the bounds,
        negative against the upper, positive against the lower; not in drive_force.  None
        without stops.  ``limit_contacts()`` lists when each stop engaged.
    contact_force, contact_point, contact_normal : ndarray (T, contact spheres, 3) or None
        Each contact sphere's (a body's shapes', docs/contact.md, in Model.contacts' order)
        force on its body (N, world: 0 while apart), the point it acts at (the sphere's
        point nearest the plane, m) and the plane's normal there; by the contact law from
        the recorded positions and velocities.  None without shapes.  ``contacts()`` lists
        when each touched.
    closure_drive_force : ndarray (T, closing joints, 2) or None
        The generalized force (N m about the axis, or N along a slide) each closing joint's
        drive (a prescribed motion or a spring-damper) applies on side b, per coordinate (0
        for a coordinate without a drive; it is also in closure_moment or closure_force).
        None without such drives.
    body_names : tuple of str (n,) or None
        The bodies' names (columns of save_csv).
    energy_work : ndarray (T,) or None
        J: the work W done on the system since t = 0 by loads, drives, dampers and a moving
        ground, at each sample, where the run kept the energy balance (``max_energy_error``;
        ``dttmm run`` keeps it for driven scenes): E - E(0) - W is the integrator's own error.
        None otherwise.
    wall_time : float
        s: the run's wall-clock time.
    n_steps : int
        The steps taken (accepted steps of an adaptive run; both runs of a Richardson one).
    info : dict
        The solver's statistics (mode, loop, dt, Newton and error statistics; the reference:
        nfev, n_state, n_unknowns).
    checkpoint : Checkpoint or None
        DT-TMM: the state after the last step, to continue the run from:
        ``simulate(..., resume=result.checkpoint)``.

    Raises
    ------
    TypeError
        An unknown field, or method or t missing.

    Examples
    --------
    >>> import numpy as np
    >>> import dttmm
    >>> r = dttmm.Result(method="mine", t=np.linspace(0.0, 1.0, 3))
    >>> r.n_steps, r.info, r.modal_coordinates
    (0, {}, None)
    >>> r.replace(n_steps=2).n_steps
    2
    """

    __slots__ = ("_values", "_derivation")

    def __init__(self, *, derivation=None, **values):
        unknown = set(values) - set(FIELDS)
        if unknown:
            raise TypeError(f"Result: unknown fields {sorted(unknown)}")
        for name in ("method", "t"):
            if name not in values:
                raise TypeError(f"Result: {name} is required")
        full = {name: values.get(name, _DEFAULTS.get(name)) for name in FIELDS}
        if full["info"] is None:
            full["info"] = {}
        if derivation is not None:          # left to the derivation unless given
            for name in DERIVED:
                if values.get(name) is None:
                    del full[name]
        object.__setattr__(self, "_values", {k: _read_only(v) for k, v in full.items()})
        object.__setattr__(self, "_derivation", derivation)

    @classmethod
    def _of_run(cls, derivation, lazy=(), **values):
        """A solver's Result (run_records._result): the fields are known to be valid and the
        arrays new, held by nothing else, so they are made read-only in place rather than
        through views (views of them, such as force and moment, are then read-only too): the
        checks and copies of __init__ cost a short run a third of its fixed cost.  The
        derivation gives the DERIVED fields and those named in lazy when first read."""
        full = dict(_RUN_DEFAULTS)
        for name in lazy:
            del full[name]
        full.update(values)
        for value in values.values():
            if isinstance(value, np.ndarray) and value.flags.writeable:
                value.flags.writeable = False
        if full.get("info", {}) is None:
            full["info"] = {}
        result = object.__new__(cls)
        object.__setattr__(result, "_values", full)
        object.__setattr__(result, "_derivation", derivation)
        return result

    def __getattr__(self, name):
        values = object.__getattribute__(self, "_values")
        if name in values:
            return values[name]
        derivation = object.__getattribute__(self, "_derivation")
        if derivation is not None and name in FIELDS:     # DERIVED, or lazy in _of_run
            values.update({k: _read_only(v) for k, v in derivation(name).items()})
            if name in values:
                return values[name]
        raise AttributeError(f"Result has no field {name!r}")

    def __setattr__(self, name, value):
        raise AttributeError("a Result is read-only (Result.replace makes a changed copy)")

    def __repr__(self):
        return (f"Result(method={self.method!r}, {len(self.t)} samples over "
                f"[{self.t[0]:g}, {self.t[-1]:g}] s, {self.n_steps} steps, "
                f"wall_time={self.wall_time:.3g} s)")

    def __reduce__(self):
        """Pickled (to another process) with its derived fields computed: the derivation is a
        closure over the model."""
        return (_restored, ({name: getattr(self, name) for name in FIELDS},))

    def _timed(self, wall_time):
        """This Result with its wall_time set (a solver's last act: no other field changes, so
        nothing is checked or copied again)."""
        timed = object.__new__(Result)
        object.__setattr__(timed, "_values", dict(object.__getattribute__(self, "_values"),
                                                  wall_time=float(wall_time)))
        object.__setattr__(timed, "_derivation", object.__getattribute__(self, "_derivation"))
        return timed

    def replace(self, **changes):
        """A copy with some fields changed.

        Derived fields not yet computed stay derivable, unless the stored state they come
        from (t, rotation, angular_velocity, modal or joint coordinates) is changed: then the
        derived fields not in changes are computed from this Result's state first and kept.

        Parameters
        ----------
        **changes
            Field name -> new value (the fields of the class docstring).

        Returns
        -------
        Result
            The copy; this Result is unchanged.

        Raises
        ------
        TypeError
            An unknown field.
        """
        values = dict(object.__getattribute__(self, "_values"), **changes)
        derivation = object.__getattribute__(self, "_derivation")
        values.update({name: getattr(self, name) for name in FIELDS     # (lazy in _of_run)
                       if name not in values and name not in DERIVED})
        if derivation is not None and set(changes) & _STATE_OF_DERIVED:
            values.update({name: getattr(self, name) for name in DERIVED
                           if name not in changes})
            derivation = None
        return Result(derivation=derivation, **values)

    def state(self, i=-1):
        """Sample i's state as ``dttmm.forward_dynamics`` takes it: rotation, angular_velocity,
        and where recorded joint_coordinates, joint_rates, modal_coordinates and
        modal_velocities (an elastic hinge's deflection is not a Result field: give it
        yourself, or the model's initial one stands)."""
        out = {"rotation": self.rotation[i], "angular_velocity": self.angular_velocity[i]}
        for key in ("joint_coordinates", "joint_rates", "modal_coordinates", "modal_velocities"):
            value = getattr(self, key)
            if value is not None:
                out[key] = value[i]
        return out

    def limit_contacts(self):
        """Every contact of an end stop: a list of (column, "lower" or "upper", t_on, t_off),
        column in joint_coordinates' columns, t_on and t_off the first and last samples the
        stop pushed at (t_off None while it still pushes at the end); [] without stops."""
        if self.limit_force is None:
            return []
        out = []
        for col in range(self.limit_force.shape[1]):
            force = self.limit_force[:, col]
            for side, pushing in (("lower", force > 0.0), ("upper", force < 0.0)):
                edges = np.flatnonzero(np.diff(np.concatenate([[0], pushing.astype(int), [0]])))
                for start, stop in zip(edges[::2], edges[1::2]):
                    out.append((col, side, float(self.t[start]),
                                None if stop == len(force) else float(self.t[stop - 1])))
        return sorted(out, key=lambda c: (c[2], c[0]))

    def contacts(self):
        """Every touch of a contact sphere: a list of (sphere, t_on, t_off), sphere its index
        in contact_force's columns (Model.contacts' rows), t_on and t_off the first and last
        samples it pushed at (t_off None while it still pushes at the end); [] without
        shapes (results/contact_states.py::touches)."""
        from .contact_states import touches
        return touches(self.t, self.contact_force)

    @property
    def total_energy(self):
        """(T,) kinetic + potential, J."""
        return self.kinetic + self.potential

    @property
    def quaternion(self):
        """(T, n, 4) unit quaternions [w, x, y, z] with w >= 0."""
        return rotation_to_quaternion(self.rotation)

    @property
    def xyz_angles(self):
        """(T, n, 3) the paper's space-fixed x-y-z angles, A = Rz(tz) Ry(ty) Rx(tx); singular
        (and then only one of tx, tz is defined) where ty = +-90 deg."""
        return rotation_to_xyz_angles(self.rotation)

    plot_positions = _plot_method(
        "plot_positions", "The bodies' points, x, y, z (m) against t (s), one axis per "
        "component", ', point ("output", default, "input" or "mass_center")')
    plot_angles = _plot_method(
        "plot_angles", "The bodies' space-fixed x-y-z angles (rad) against t (s), unwrapped")
    plot_energy = _plot_method(
        "plot_energy", "Kinetic, potential and total energy (J), and the total's change from "
        "t = 0 on an axis of its own")
    plot_joints = _plot_method(
        "plot_joints", "Joint coordinates (rad or m) and drive forces (N m or N) against t (s)",
        missing="The result has no joints with coordinates.")
    plot_modal = _plot_method(
        "plot_modal", "The beams' modal coordinates eta (m) against t (s)",
        missing="The result has no beams.")
    plot_contacts = _plot_method(
        "plot_contacts", "Each contact sphere's normal and friction force (N) against t (s)",
        ", model (a Model: its bodies' spheres summed)",
        missing="The result has no contact shapes.")

    def save_npz(self, path):
        """Write every field to a compressed .npz.

        Arrays as they are (derived fields computed if they were not; fields that are None
        left out); method, wall_time, n_steps, body_names and info (as JSON: numpy scalars as
        numbers, anything else json cannot write as text) as entries of their own; plus the
        derived quaternion, xyz_angles and total_energy for readers outside dttmm.
        ``Result.load_npz`` reads it back.  The checkpoint is not written
        (``Checkpoint.save``).

        Parameters
        ----------
        path : str or path-like or file
            Where to write (``numpy.savez_compressed``: ".npz" is appended to a name without
            it).
        """
        arrays = {name: getattr(self, name) for name in FIELDS
                  if name not in ("method", "wall_time", "n_steps", "info", "body_names",
                                  "checkpoint") and getattr(self, name) is not None}
        extra = {} if self.body_names is None else {"body_names": np.array(self.body_names)}
        np.savez_compressed(path, method=self.method, wall_time=self.wall_time,
                            n_steps=self.n_steps,
                            info=json.dumps(self.info, default=_json_value),
                            quaternion=self.quaternion, xyz_angles=self.xyz_angles,
                            total_energy=self.total_energy, **extra, **arrays)

    @classmethod
    def load_npz(cls, path):
        """The Result that save_npz wrote to path.

        Parameters
        ----------
        path : str or path-like or file
            The .npz file.

        Returns
        -------
        Result
            Every field written (info's tuples come back as lists; checkpoint None); the
            derived fields as stored, not derived again.

        Raises
        ------
        ValueError
            A file that is missing, truncated, not a .npz, or a .npz without the entries
            save_npz writes (method, t, wall_time, n_steps, info), naming the file.
        """
        where = f"Result.load_npz({str(path)!r})"
        try:
            with np.load(path, allow_pickle=False) as data:
                values = {k: data[k] for k in data.files if k in FIELDS}
            missing = [k for k in ("method", "t", "wall_time", "n_steps", "info")
                       if k not in values]
            if missing:
                raise ValueError(f"no {', '.join(missing)} in it: not written by "
                                 f"Result.save_npz")
            values["method"] = str(values["method"])
            values["wall_time"] = float(values["wall_time"])
            values["n_steps"] = int(values["n_steps"])
            values["info"] = json.loads(str(values["info"]))
        except FileNotFoundError:
            raise ValueError(f"{where}: no such file") from None
        except Exception as err:        # truncated, not a zip, pickled objects, bad JSON
            raise ValueError(f"{where}: not a result written by Result.save_npz "
                             f"({type(err).__name__}: {err})") from None
        if "body_names" in values:
            values["body_names"] = tuple(str(x) for x in values["body_names"])
        return cls(**values)

    def save_csv(self, path):
        """Write a CSV table: t, then x, y, z of each body's output point, then the energies.

        One row per sample; a header row names the columns: "t" (s), "NAME.x", "NAME.y",
        "NAME.z" (m) for each body (body_names, or body1, body2, ... without them),
        "kinetic", "potential", "total_energy" (J).

        Parameters
        ----------
        path : str or path-like
            The file written (replaced if it exists).
        """
        n = self.position_output.shape[1]
        names = self.body_names if self.body_names is not None else [
            f"body{k}" for k in range(n)]
        head = ["t"] + [f"{name}.{c}" for name in names for c in "xyz"] + [
            "kinetic", "potential", "total_energy"]
        rows = np.column_stack([self.t, self.position_output.reshape(len(self.t), -1),
                                self.kinetic, self.potential, self.total_energy])
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(head)
            w.writerows(rows.tolist())


def _read_only(value):
    """An array as a read-only view (a Result's arrays cannot be written: positions and
    energies are derived from the stored state when first read); anything else as it is."""
    if isinstance(value, np.ndarray) and value.flags.writeable:
        value = value.view()
        value.flags.writeable = False
    return value


def _restored(values):
    return Result(**values)


def angular_momentum(model, result, point=(0.0, 0.0, 0.0)):
    """(T, 3) world angular momentum of the chain about a fixed point, from a result's state."""
    p = model.body_params
    rot = result.rotation
    rho_c = np.einsum("tkij,kj->tki", rot, p[:, TO_MASS_CENTER])
    v_c = result.velocity_input + cross(result.angular_velocity, rho_c)
    r_c = result.position_input + rho_c - np.asarray(point, float)
    j_c = np.einsum("tkij,kjl,tkml->tkim", rot, model.body_mass_center_inertia, rot)
    spin = np.einsum("tkij,tkj->tki", j_c, result.angular_velocity)
    return np.sum(p[:, MASS][None, :, None] * cross(r_c, v_c) + spin, axis=1)


def _json_value(x):
    """info's values for json: numpy scalars as numbers, anything else as text."""
    return x.item() if isinstance(x, np.generic) else str(x)


def rotation_to_xyz_angles(rot):
    rot = np.asarray(rot)
    ty = np.arcsin(np.clip(-rot[..., 2, 0], -1.0, 1.0))
    tx = np.arctan2(rot[..., 2, 1], rot[..., 2, 2])
    tz = np.arctan2(rot[..., 1, 0], rot[..., 0, 0])
    return np.stack([tx, ty, tz], axis=-1)


def _beam_energies(row, a, w, r_in, v_in, eta, eta_dot, gravity,
                   exact_foreshortening=False):
    """Kinetic energy (int 1/2 mu |r'|^2 dx + 1/2 j_p L (w . A e1)^2) and potential energy
    (-int mu g . r dx + sum 1/2 k eta^2) of one beam (docs/beam.md), by quadrature, for T states
    at once: a (T, 3, 3), w, r_in, v_in (T, 3), eta, eta_dot (T, 2 m + mt), the twist's
    energy too (docs/beam.md, "Torsion").  exact_foreshortening: a stiffened beam's sections
    at x + u_x - c(x) along the frame's x, c to all orders (the reference's
    simulate_reference(exact_foreshortening=True)), instead of its terms to first order in c."""
    length, mu, nm = row[LENGTH], row[MASS_PER_LENGTH], int(row[MODES])
    exact = row[STIFFENING] == EXACT or (bool(row[STIFFENING]) and exact_foreshortening)
    x = 0.5 * length * (_GL_X + 1.0)
    wq = 0.5 * length * _GL_W
    y, _, _, _, stiffness = mode_shapes(int(row[FAMILY]), length, nm, x)      # y (m, Q)
    p = np.zeros((len(eta), len(x), 3))                    # x e1 + u(x), body frame
    p[:, :, 0] = x
    p[:, :, 1] = rows_dot(eta[:, :nm], y)
    p[:, :, 2] = rows_dot(eta[:, nm:2 * nm], y)
    p[:, :, 0] += stretch_along(row, eta, x)                # the stretch u_x (docs/beam.md)
    u_dot = np.zeros_like(p)
    u_dot[:, :, 1] = rows_dot(eta_dot[:, :nm], y)
    u_dot[:, :, 2] = rows_dot(eta_dot[:, nm:2 * nm], y)
    u_dot[:, :, 0] = stretch_along(row, eta_dot, x)
    if exact:
        c, c_dot = foreshortening_along(row, x, eta, eta_dot)
        p[:, :, 0] -= c
        u_dot[:, :, 0] -= c_dot
    a_t = np.swapaxes(a, 1, 2)
    rho = p @ a_t                                          # A p, every state and point
    vel = v_in[:, None, :] + cross(w[:, None, :], rho) + u_dot @ a_t
    spin = np.einsum("ti,ti->t", w, a[:, :, 0])
    kinetic = 0.5 * mu * rows_dot(np.sum(vel * vel, axis=2), wq)
    mt = int(row[TORSION_MODES])
    if mt:
        # the sections spin by w . A e1 + psi' (docs/beam.md, "Torsion"):
        # T = 1/2 j_p int (w . A e1 + psi')^2, V = 1/2 G J int psi'^2
        psi, dpsi = torsion_shapes(int(row[FAMILY]), length, mt, x)[:2]
        twist = rows_dot(eta[:, 2 * nm:2 * nm + mt], dpsi)
        twist_rate = rows_dot(eta_dot[:, 2 * nm:2 * nm + mt], psi)
        section_spin = spin[:, None] + twist_rate
        kinetic += 0.5 * row[POLAR_PER_LENGTH] * rows_dot(section_spin * section_spin, wq)
    else:
        twist = np.zeros((len(eta), len(x)))
        kinetic += 0.5 * row[POLAR_PER_LENGTH] * length * spin * spin
    potential = -mu * rows_dot(rows_dot(r_in[:, None, :] + rho, gravity), wq)
    potential += 0.5 * (rows_dot(eta[:, :nm] ** 2, stiffness * row[EI_V])
                        + rows_dot(eta[:, nm:2 * nm] ** 2, stiffness * row[EI_W]))
    potential += 0.5 * row[GJ] * rows_dot(twist * twist, wq)
    ma = int(row[AXIAL_MODES])
    if ma:      # V gains 1/2 E A int u_x'^2 ("Stretch")
        strain = rows_dot(eta[:, eta.shape[1] - ma:],
                          torsion_shapes(int(row[FAMILY]), length, ma, x)[1])
        potential += 0.5 * row[EA] * rows_dot(strain * strain, wq)
    if row[STIFFENING] and not exact:
        # the foreshortening -c(x) A e1 to first order in c (docs/beam.md, "Geometric
        # stiffening"): T gains int mu (v_I + w x A x e1) . (-c w x A e1 - c' A e1), V gains
        # int mu c g . A e1; c(x) = 1/2 int_0^x (v'^2 + w'^2) by its own quadrature on [0, x]
        c, c_dot = foreshortening_along(row, x, eta, eta_dot)
        e1 = a[:, :, 0]
        u = cross(w, e1)
        int_c, int_cd, int_xc = rows_dot(c, wq), rows_dot(c_dot, wq), rows_dot(c, wq * x)
        kinetic -= mu * (np.einsum("ti,ti->t", v_in, u) * int_c
                         + np.einsum("ti,ti->t", v_in, e1) * int_cd
                         + np.einsum("ti,ti->t", u, u) * int_xc)
        potential += mu * rows_dot(e1, gravity) * int_c
    return kinetic, potential


def chain_energies(model, rotation, omega, r_in, v_in, deflection, ground_rotation=None,
                   eta=None, eta_dot=None, joint_coordinates=None, ground_position=None,
                   exact_foreshortening=False):
    """Kinetic and potential energy of one state, or of T states at once, from positions and
    velocities alone.

    rotation (n,3,3), omega (n,3), r_in, v_in (n,3) input-point positions and velocities,
    deflection (n,3): world deflection d of each elastic hinge (ignored for other hinges),
    ground_rotation (3,3): the ground frame at this time (default: the model's, at rest or
    t = 0), eta, eta_dot: the beams' modal coordinates and rates, flat and concatenated in body
    order (a beam's v coordinates first, then w), as Result.modal_coordinates; None for zero.
    With a leading axis of T states on every array (ground_rotation (T,3,3) or one frame), the
    energies come back as two (T,) arrays.  A beam counts int 1/2 mu |r'(x)|^2 dx +
    1/2 j_p L (w . A e1)^2 kinetic and -int mu g . r(x) dx + sum 1/2 k_k eta_k^2 potential
    energy (docs/beam.md).  joint_coordinates: the coordinates q of the joints with coordinates,
    flat in hinge order (as Result.joint_coordinates); given, the potential counts
    1/2 k (q - rest)^2 of every SpringDamper drive (docs/joints.md, "Drives"); None (default):
    no drive springs are counted.  The potential counts the closing elastic hinges' springs
    (loop_kinematics.elastic_closure_terms); ground_position (3,) or (T, 3): the ground point at
    this time (default: the model's), where a closing joint meets the ground.
    exact_foreshortening: the stiffened beams' foreshortening to all orders (_beam_energies;
    a beam of stiffening="exact" takes it always).
    """
    rotation = np.asarray(rotation, dtype=float)
    single = rotation.ndim == 3
    rotation, omega, r_in, v_in, deflection = (
        np.asarray(x, dtype=float)[None] if single else np.asarray(x, dtype=float)
        for x in (rotation, omega, r_in, v_in, deflection))
    n_t = rotation.shape[0]
    ground_rot = model.ground_rotation if ground_rotation is None else ground_rotation
    ground_rot = np.broadcast_to(np.asarray(ground_rot, dtype=float), (n_t, 3, 3))
    n_modes = model.n_modes
    total = int(np.sum(n_modes))
    eta = np.zeros((n_t, total)) if eta is None else np.asarray(eta, dtype=float).reshape(n_t, -1)
    eta_dot = (np.zeros((n_t, total)) if eta_dot is None
               else np.asarray(eta_dot, dtype=float).reshape(n_t, -1))
    if eta.shape[1] != total or eta_dot.shape[1] != total:
        raise ValueError(f"chain_energies: eta and eta_dot must hold {total} modal coordinates "
                         f"(got {eta.shape[1]} and {eta_dot.shape[1]})")
    kinetic, potential = np.zeros(n_t), np.zeros(n_t)
    mode_off = model.mode_offsets
    rigid = np.nonzero(model.body_kind == RIGID)[0]     # every rigid body at once
    if len(rigid):
        p = model.body_params[rigid]
        a = rotation[:, rigid]
        rho_c = np.einsum("tkij,kj->tki", a, p[:, TO_MASS_CENTER])
        v_c = v_in[:, rigid] + cross(omega[:, rigid], rho_c)
        w_body = np.einsum("tkji,tkj->tki", a, omega[:, rigid])          # A^T w
        kinetic += 0.5 * np.einsum("k,tki,tki->t", p[:, MASS], v_c, v_c)
        kinetic += 0.5 * np.einsum("tki,kij,tkj->t", w_body,
                                   model.body_mass_center_inertia[rigid], w_body)
        potential -= np.einsum("k,tki,i->t", p[:, MASS], r_in[:, rigid] + rho_c, model.gravity)
    for k in range(model.n_bodies):
        a = rotation[:, k]
        j0, j1 = mode_off[k], mode_off[k + 1]
        if model.body_kind[k] == BEAM:
            t_k, v_k = _beam_energies(model.beam_params[k], a, omega[:, k], r_in[:, k],
                                      v_in[:, k], eta[:, j0:j1], eta_dot[:, j0:j1],
                                      model.gravity, exact_foreshortening)
            kinetic += t_k
            potential += v_k
        elif model.body_kind[k] == ROD:
            t_k, v_k = rod_energies(model.rod_params[k], a, omega[:, k], r_in[:, k],
                                    v_in[:, k], eta[:, j0:j1], eta_dot[:, j0:j1], model.gravity)
            kinetic += t_k
            potential += v_k
        elif model.body_kind[k] != RIGID:       # (the rigid bodies': above, all at once)
            raise unimplemented_body_kind(model.body_kind[k], f"body '{model.body_names[k]}'",
                                          "the energies (results/result.py::chain_energies)")
        if model.hinge_kind[k] == ELASTIC:
            h = model.hinge_params[k]
            for i in range(n_t):                # (a log per state: elastic hinges only)
                inb = model.parent[k]                    # the hinge's inboard body
                a_in = ground_rot[i] if inb < 0 else rotation[i, inb]
                if inb >= 0 and model.body_kind[inb] != RIGID:  # a beam's or rod's end section
                    a_in = element_end_section(model, inb, a_in, np.zeros(3),
                                               eta[i, mode_off[inb]:mode_off[inb + 1]],
                                               None)[0]
                d_b = a_in.T @ deflection[i, k]
                psi = log_rotation(a_in.T @ a[i] @ h[REST_ROTATION].reshape(3, 3).T)
                potential[i] += 0.5 * d_b @ h[K_TRANSLATION].reshape(3, 3) @ d_b
                potential[i] += 0.5 * psi @ h[K_ROTATION].reshape(3, 3) @ psi
    if np.any(model.closure_kind == ELASTIC):
        from ..model.loop_kinematics import elastic_closure_terms
        r_g = np.broadcast_to(np.asarray(model.ground_position if ground_position is None
                                         else ground_position, dtype=float), (n_t, 3))
        zero = np.zeros((n_t, 3))
        potential += elastic_closure_terms(model, rotation, omega, r_in, v_in, eta, eta_dot,
                                           (r_g, zero, ground_rot, zero))[0]
    if joint_coordinates is not None:
        potential += _drive_spring_energy(model, joint_coordinates, n_t)
    if single:
        return float(kinetic[0]), float(potential[0])
    return kinetic, potential


def stop_forces(model, q, qd):
    """(T, C) the end stops' generalized forces at joint coordinates q and rates qd (T, C; C
    in Result.joint_coordinates' columns), by the stops' law (elements/limits.py: past a bound
    -max(0, k (q - upper) + c q') or max(0, k (lower - q) - c q'), the force a run applied at
    each sample to its Newton tolerance); 0 for a coordinate without stops or prescribed (its
    motion rules); None for a model without stops."""
    stopped = stopped_columns(model)
    if not stopped:
        return None
    q, qd = np.atleast_2d(q), np.atleast_2d(qd)
    forces = np.zeros(q.shape)
    for col, limit in stopped:
        forces[:, col] = stop_force(limit, q[:, col], qd[:, col])
    return forces


def stopped_columns(model):
    """[(column, its stops (lower, upper, stiffness, damping))] of every free joint coordinate
    with end stops, columns in Result.joint_coordinates' order (a prescribed coordinate's stops
    do not act: its motion rules)."""
    columns = [(k, i) for k in range(model.n_bodies) for i in range(len(model.drives[k]))]
    return [(col, limit_of(model.hinge_params[k], i)) for col, (k, i) in enumerate(columns)
            if limit_of(model.hinge_params[k], i)[2] != 0.0
            and not (model.drives[k][i] is not None and model.drives[k][i]["kind"] == MOTION)]


def limit_forces(model, result):
    """(forces (T, C), contacts): the end stops' generalized forces (Result.limit_force, or
    stop_forces from the recorded coordinates and rates of a Result without it) and their
    contacts (Result.limit_contacts); zeros and [] for a model without stops."""
    forces = result.limit_force
    if forces is None and result.joint_coordinates is not None:
        forces = stop_forces(model, result.joint_coordinates, result.joint_rates)
    if forces is None:
        width = 0 if result.joint_coordinates is None else result.joint_coordinates.shape[1]
        return np.zeros((len(result.t), width)), []
    return forces, result.replace(limit_force=forces).limit_contacts()


def momenta(model, result):
    """The bodies' mass, and at every sample their first moment of mass, linear momentum and
    angular momentum about the world's origin, from the Result's positions, velocities, rates
    and modal coordinates (a run of `model`).

    Returns (mass, first (T, 3), linear (T, 3), angular (T, 3)): kg, kg m, kg m/s, kg m^2/s.
    The mass centre is first / mass; the angular momentum about it is
    angular - (first / mass) x linear.  A rigid body counts m r_C, m v_C and
    A J_C A^T w + m r_C x v_C; a beam int mu r dx, int mu r' dx and int mu r x r' dx +
    j_p L (w . A e1) A e1 over its sections r(x) = r_I + A (x e1 + u(x)) by quadrature (with
    its foreshortening -c(x) e1 where it is stiffened, docs/beam.md; its twist's rate too).
    Strain rods are not counted yet (a ValueError names the body)."""
    t = len(result.t)
    rot, w = result.rotation, result.angular_velocity
    r_in, v_in = result.position_input, result.velocity_input
    eta = result.modal_coordinates
    eta_d = result.modal_velocities
    mode_off = model.mode_offsets
    mass, first = 0.0, np.zeros((t, 3))
    linear, angular = np.zeros((t, 3)), np.zeros((t, 3))
    for k in range(model.n_bodies):
        a = rot[:, k]
        if model.body_kind[k] == RIGID:
            m = model.body_params[k, MASS]
            rho = np.einsum("tij,j->ti", a, model.body_params[k, TO_MASS_CENTER])
            r_c, v_c = r_in[:, k] + rho, v_in[:, k] + cross(w[:, k], rho)
            spin = np.einsum("tij,jk,tlk,tl->ti", a, model.body_mass_center_inertia[k], a,
                             w[:, k])
            mass += m
            first += m * r_c
            linear += m * v_c
            angular += spin + m * cross(r_c, v_c)
        elif model.body_kind[k] == BEAM:
            row = model.beam_params[k]
            j0, j1 = mode_off[k], mode_off[k + 1]
            x, wq, r, vel, section_spin = _beam_sections(row, a, w[:, k], r_in[:, k],
                                                        v_in[:, k], eta[:, j0:j1],
                                                        eta_d[:, j0:j1])
            mu = row[MASS_PER_LENGTH]
            mass += mu * row[LENGTH]
            first += mu * np.einsum("tqi,q->ti", r, wq)
            linear += mu * np.einsum("tqi,q->ti", vel, wq)
            angular += mu * np.einsum("tqi,q->ti", cross(r, vel), wq)
            angular += row[POLAR_PER_LENGTH] * rows_dot(section_spin, wq)[:, None] * a[:, :, 0]
        else:
            raise unimplemented_body_kind(model.body_kind[k], f"body '{model.body_names[k]}'",
                                          "momenta (results/result.py)")
    return mass, first, linear, angular


def _beam_sections(row, a, w, r_in, v_in, eta, eta_dot):
    """A beam's quadrature points x (Q,), weights (Q,), their world positions and velocities
    (T, Q, 3), and the sections' spin rates about the beam's axis (T, Q): r = r_I + A p,
    p = x e1 + u(x) (the stretch along x, the foreshortening -c(x) along x where stiffened),
    r' = v_I + w x A p + A p'."""
    length, nm = row[LENGTH], int(row[MODES])
    x = 0.5 * length * (_GL_X + 1.0)
    wq = 0.5 * length * _GL_W
    y = mode_shapes(int(row[FAMILY]), length, nm, x)[0]
    p = np.zeros((len(eta), len(x), 3))
    p[:, :, 0] = x + stretch_along(row, eta, x)
    p[:, :, 1] = rows_dot(eta[:, :nm], y)
    p[:, :, 2] = rows_dot(eta[:, nm:2 * nm], y)
    p_dot = np.zeros_like(p)
    p_dot[:, :, 0] = stretch_along(row, eta_dot, x)
    p_dot[:, :, 1] = rows_dot(eta_dot[:, :nm], y)
    p_dot[:, :, 2] = rows_dot(eta_dot[:, nm:2 * nm], y)
    if row[STIFFENING]:
        c, c_dot = foreshortening_along(row, x, eta, eta_dot)
        p[:, :, 0] -= c
        p_dot[:, :, 0] -= c_dot
    a_t = np.swapaxes(a, 1, 2)
    rho = p @ a_t
    vel = v_in[:, None, :] + cross(w[:, None, :], rho) + p_dot @ a_t
    spin = np.broadcast_to(np.einsum("ti,ti->t", w, a[:, :, 0])[:, None], (len(eta), len(x)))
    mt = int(row[TORSION_MODES])
    if mt:
        psi = torsion_shapes(int(row[FAMILY]), length, mt, x)[0]
        spin = spin + rows_dot(eta_dot[:, 2 * nm:2 * nm + mt], psi)
    return x, wq, r_in[:, None, :] + rho, vel, spin


def _drive_spring_energy(model, joint_coordinates, n_t):
    """(T,) sum of 1/2 k (q - rest)^2 over every SpringDamper drive (docs/joints.md, "Drives");
    joint_coordinates (T, total coordinates) or (total coordinates,), Model.drives' order."""
    drives = [d for per_joint in model.drives for d in per_joint]
    q = np.asarray(joint_coordinates, dtype=float).reshape(n_t, -1)
    if q.shape[1] != len(drives):
        raise ValueError(f"chain_energies: joint_coordinates must hold {len(drives)} joint "
                         f"coordinates (got {q.shape[1]})")
    energy = np.zeros(n_t)
    for c, d in enumerate(drives):
        if d is not None and d["kind"] == SPRING_DAMPER:
            energy += 0.5 * d["stiffness"] * (q[:, c] - d["rest"]) ** 2
    return energy


def beam_midpoint_deflection(model, result, body):
    """(T, 2) mid-span deflection of beam `body` relative to its chord I -> O (the mid-point's
    offset from the chord's middle, less its part along the chord; A u(L/2) for pinned modes,
    whose chord is the frame's x axis), projected on e2 and e3: e1 = A e1 is the chord
    direction, e3 the unit part of world z orthogonal to e1,
    e2 = e3 x e1 (for a chord in the world x-y plane: e2 is in that plane, e3 = world z).
    Undefined (NaN) while the chord is along world z."""
    body = int(body)
    if not 0 <= body < model.n_bodies or model.body_kind[body] != BEAM:
        raise ValueError(f"beam_midpoint_deflection: body {body} is not an EulerBernoulliBeam")
    if result.modal_coordinates is None:
        raise ValueError("beam_midpoint_deflection: the result holds no modal coordinates")
    n_modes = model.n_modes
    offset = int(np.sum(n_modes[:body]))
    row = model.beam_params[body]
    nm, length = int(row[MODES]), row[LENGTH]
    eta = np.asarray(result.modal_coordinates)[:, offset:offset + 2 * nm]
    y = mode_shapes(int(row[FAMILY]), length, nm, [0.5 * length, length])[0]
    rot = np.asarray(result.rotation)[:, body]
    # frame-relative mid-point and output point; the deflection is the mid-point's offset from
    # the chord's middle, without its part along the chord
    p_mid = np.zeros((len(eta), 3))
    p_mid[:, 0] = 0.5 * length
    p_mid[:, 1] = rows_dot(eta[:, :nm], y[:, 0])
    p_mid[:, 2] = rows_dot(eta[:, nm:2 * nm], y[:, 0])
    p_out = np.zeros((len(eta), 3))
    p_out[:, 0] = length
    p_out[:, 1] = rows_dot(eta[:, :nm], y[:, 1])
    p_out[:, 2] = rows_dot(eta[:, nm:2 * nm], y[:, 1])
    chord = np.einsum("tij,tj->ti", rot, p_out)
    e1 = chord / np.linalg.norm(chord, axis=1, keepdims=True)
    d = np.einsum("tij,tj->ti", rot, p_mid - 0.5 * p_out)
    d -= np.einsum("ti,ti->t", d, e1)[:, None] * e1
    z = np.array([0.0, 0.0, 1.0])
    e3 = z - e1[:, 2:3] * e1
    norm = np.linalg.norm(e3, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        e3 = np.where(norm > 1e-12, e3 / norm, np.nan)
    e2 = cross(e3, e1)
    return np.stack([np.einsum("ti,ti->t", d, e2), np.einsum("ti,ti->t", d, e3)], axis=1)


