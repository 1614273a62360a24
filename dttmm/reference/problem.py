"""The reference's problem (newton_euler.py's docstring is its formulation): a model's tables as
the reference's kernels read them (its index bookkeeping, the beams' shape tables, the strain
rods' tables, the closing joints' rows with their stabilization), and the per-time evaluation of
the ground's motion, the applied loads and the joints' drives.  simulate_reference
(newton_euler.py) integrates it.
"""
import numpy as np

from ..elements import BEAM, ROD
from ..elements.strain_rod import (ROD_DAMPING, ROD_MU, rod_coordinate_count, rod_section,
                                   rod_stiffness, rod_tables)
from ..elements.beam import (AXIAL_MODES, CLAMPED, CLAMPED_LOADED, EXACT, FAMILY, MODES, PINNED,
                             STIFFENING, TORSION_MODES)
from ..elements.drives import FORCE, MOTION, PD, SPRING_DAMPER
from ..elements.hinges import DEFLECTION_0, DEFLECTION_RATE_0, FIXED
from ..elements.limits import stop_force
from ..elements.kinds import (COORDINATE_0, DEFLECTING, JOINT_KIND, RATE_0, coordinate_count,
                              limit_of)
from ..kernels import python_twin
from ..model.loop_rows import closure_forces, constraint_rows
from ..model.sections import rotation_to_quaternion
from .rows import JOINTS_WITH_COORDINATES, N_SHAPE_ROWS
from .shapes import (beam_shape_constants, exact_foreshortening_table, stiffening_matrices,
                     stretch_shape_constants, twist_shape_constants)
from .equations import _solve_dynamics, rhs_kernel
from .hub import hub_table


# Baumgarte's stabilization of the closing joints' rows, g'' + 2 zeta W g' + W^2 g = 0 with
# zeta = 1 and W = 20 rad/s (newton_euler.py's docstring, "Loops")
LOOP_DAMPING = 20.0


def _loop_rows(model, col0):
    """The closing joints as the kernels read them (_closure_rows): (first multiplier column,
    per row its kind (elements/kinds.py: GAP_WORLD, GAP_A or DOT), its closing joint, x or e,
    y, then per closing joint its sides' bodies, points and end flags, the stabilization's
    gains, per row its angle axis, its targets, its driven coordinate, its drive's law, and its
    (g, g') as the last evaluation found them)."""
    kind, owner, v1, v2, v3, coordinate, law = constraint_rows(model)
    return (col0, kind, owner, v1, v2,
            np.array(model.closure_body, dtype=np.int64).reshape(-1, 2),
            np.array(model.closure_point, dtype=float).reshape(-1, 2, 3),
            np.array(model.closure_on_end, dtype=np.int64).reshape(-1, 2),
            np.array([2.0 * LOOP_DAMPING, LOOP_DAMPING ** 2]), v3, np.zeros((len(kind), 3)),
            coordinate, law, np.zeros((len(kind), 2)))


class _Kernels:
    """The reference's kernels called from Python: the right-hand side as solve_ivp calls it
    (rhs_kernel's twin) and the solved system at a time (_solve_dynamics); one compiled copy
    for every model."""

    def __init__(self):
        self.rhs = python_twin(rhs_kernel)
        self.solve_dynamics = _solve_dynamics


def _finite_number(value, who, what, t):
    """A user function's value as a float; ValueError naming who returned what otherwise."""
    a = np.asarray(value, dtype=float)
    if a.size != 1 or not np.isfinite(a.reshape(-1)[0]):
        raise ValueError(f"simulate_reference: {who}: {what} returned {value!r} at "
                         f"t = {t:.17g} (need one finite number)")
    return float(a.reshape(-1)[0])


class _Problem:
    """Index bookkeeping and the per-time evaluation of ground motion, applied loads and joint
    drives."""

    def __init__(self, model, exact_foreshortening=False):
        if len(model.contacts):
            raise ValueError("simulate_reference: the model's bodies have contact shapes "
                             "(docs/contact.md), which the reference does not take yet: "
                             "simulate them with dttmm.simulate")
        n = model.n_bodies
        # writable copies of the model's read-only arrays (numba types read-only arrays apart)
        kinds = np.array(model.hinge_kind, dtype=np.int64)
        self.model = model
        self.n = n
        self.kinds = kinds
        self.body_params = np.array(model.body_params, dtype=float, order="C")
        self.hinge_params = np.array(model.hinge_params, dtype=float, order="C")
        self.gravity = np.array(model.gravity, dtype=float)
        # a quaternion and w of its own: bodies behind ball joints, elastic hinges and free
        # joints (a fixed hinge's or a joint's child follows its parent and the joint's
        # coordinates); d and d' of its own: behind elastic hinges and free joints (DEFLECTING)
        free = [k for k in range(n) if kinds[k] != FIXED and kinds[k] not in
                JOINTS_WITH_COORDINATES]
        elastic = [k for k in range(n) if kinds[k] in DEFLECTING]
        self.q_off = np.full(n, -1, dtype=np.int64)
        self.w_off = np.full(n, -1, dtype=np.int64)
        self.d_off = np.full(n, -1, dtype=np.int64)
        o = 0
        for k in free:
            self.q_off[k] = o
            o += 4
        for k in free:
            self.w_off[k] = o
            o += 3
        for k in elastic:
            self.d_off[k] = o
            o += 6
        # beams: all modal coordinates (concatenated in body order, v then w of each beam), then
        # all their rates
        self.body_kind = np.array(model.body_kind, dtype=np.int64)
        self.beam_params = np.array(model.beam_params, dtype=float, order="C")
        beams = [k for k in range(n) if self.body_kind[k] == BEAM]
        for k in beams:
            if int(self.beam_params[k, FAMILY]) not in (PINNED, CLAMPED, CLAMPED_LOADED):
                raise ValueError(f"simulate_reference: body {k}: unknown beam mode family "
                                 f"{self.beam_params[k, FAMILY]}")
        # shape constants of every beam, padded to the widest beam (newton_euler.py's docstring)
        mmax = max([1] + [int(self.beam_params[k, MODES]) for k in beams])
        tmax = max([0] + [int(self.beam_params[k, TORSION_MODES]) for k in beams])
        amax = max([0] + [int(self.beam_params[k, AXIAL_MODES]) for k in beams])
        # bending in columns :m, the twist in tw:tw + mt, the stretch in 2 tw:2 tw + ma (with
        # its products with the bending shapes in rows N_SHAPE_ROWS + l)
        tw = max(mmax, tmax, amax)
        self.shape_vec = np.zeros((n, N_SHAPE_ROWS + mmax, 3 * tw))
        self.shape_mat = np.zeros((n, mmax, 4 * mmax))   # int Y Y^T, then D0, D1, D2
        for k in beams:
            vec, mat = beam_shape_constants(self.beam_params[k])
            m = vec.shape[1]
            self.shape_vec[k, :N_SHAPE_ROWS, :m] = vec
            twist = twist_shape_constants(self.beam_params[k])
            self.shape_vec[k, :N_SHAPE_ROWS, tw:tw + twist.shape[1]] = twist
            stretch = stretch_shape_constants(self.beam_params[k])
            self.shape_vec[k, :stretch.shape[0], 2 * tw:2 * tw + stretch.shape[1]] = stretch
            self.shape_mat[k, :m, :m] = mat
            for i, d in enumerate(stiffening_matrices(self.beam_params[k])):
                self.shape_mat[k, :m, (i + 1) * mmax:(i + 1) * mmax + m] = d
        # the exact foreshortening's quadrature tables (shapes.exact_foreshortening_table),
        # padded to the longest and widest (zero weights: no contribution); no columns for the
        # second-order foreshortening
        tables = {k: exact_foreshortening_table(self.beam_params[k]) for k in beams
                  if self.beam_params[k, STIFFENING] == EXACT
                  or (exact_foreshortening and self.beam_params[k, STIFFENING] != 0.0)}
        self.exact = np.zeros((n, max([1] + [t.shape[0] for t in tables.values()]),
                               max([0] + [t.shape[1] for t in tables.values()])))
        for k, table in tables.items():
            self.exact[k, :table.shape[0], :table.shape[1]] = table
        self.rods = _rod_tables(model)
        n_modes = np.asarray(model.n_modes, dtype=np.int64)
        self.m_off = np.full(n, -1, dtype=np.int64)
        nm = 0
        for k in range(n):
            if n_modes[k] > 0:
                self.m_off[k] = nm
                nm += int(n_modes[k])
        self.n_modal = nm
        self.e0 = o
        o += 2 * nm
        # joints with coordinates: all coordinates (hinge order, a joint's in its own order, as
        # Result.joint_coordinates), then all their rates
        self.c_off = np.full(n, -1, dtype=np.int64)
        self.coordinates = []                   # (hinge, index in the joint, validated drive)
        for k in range(n):
            if kinds[k] in JOINTS_WITH_COORDINATES:
                self.c_off[k] = len(self.coordinates)
                drives = model.drives[k]
                for i in range(coordinate_count(kinds[k])):
                    self.coordinates.append((k, i, drives[i] if i < len(drives) else None))
        nq = len(self.coordinates)
        self.n_coord = nq
        self.c0 = o
        o += 2 * nq
        self.n_state = o
        self.f_col = np.full(n, -1, dtype=np.int64)
        self.m_col = np.full(n, -1, dtype=np.int64)
        c = 6 * n
        for k in range(n):
            if kinds[k] not in DEFLECTING:      # (their loads: the springs')
                self.f_col[k] = c
                c += 3
            if kinds[k] == FIXED or kinds[k] in JOINTS_WITH_COORDINATES:
                self.m_col[k] = c
                c += 3
        self.e_col0 = c
        c += nm
        self.c_col0 = c
        c += nq
        self.loops = _loop_rows(model, c)
        # the rows of closing joints' driven coordinates: their motions fill loops' targets
        rows = constraint_rows(model)
        owner, coordinate = rows.owner, rows.coordinate
        self._closure_motions = [(r, model.closure_drives[owner[r]][coordinate[r]]["function"],
                                  f"closing joint '{model.closure_names[owner[r]]}', "
                                  f"coordinate {coordinate[r] + 1}")
                                 for r in np.nonzero(rows.law[:, 0] == MOTION)[0]]
        self._closure_forces = closure_forces(model, rows)
        for r in np.nonzero((rows.law[:, 0] == SPRING_DAMPER) & (coordinate >= 0))[0]:
            # a drive's spring: its row's value q - rest (an elastic hinge's rest is 0)
            self.loops[10][r, 0] = model.closure_drives[owner[r]][coordinate[r]]["rest"]
        c += self.loops[1].shape[0]
        self.n_unknowns = c
        self._still_ground = None
        self.forces = np.zeros((n, 3))
        self.torques = np.zeros((n, 3))
        self.line_loads = np.zeros((n, 3))
        self._line_load_fns = [(k, f) for k, f in enumerate(model.line_loads) if f is not None]
        self._force_fns = [(k, f) for k, f in enumerate(model.forces) if f is not None]
        self._torque_fns = [(k, f) for k, f in enumerate(model.torques) if f is not None]
        # the tree: each body's parent and its children (CSR: child_list[child_start[k]:
        # child_start[k + 1]]), and where each hinge attaches: Model.attachment_point, the point
        # in its parent's frame from the parent's input point (a rigid parent's output point or
        # one of its named points; a beam parent's output point, which the kernels take from
        # the beam's deflected end instead)
        parent = np.array(model.parent, dtype=np.int64)
        children = [[c for c in range(n) if parent[c] == k] for k in range(n)]
        self.topology = (parent, np.cumsum([0] + [len(c) for c in children]).astype(np.int64),
                         np.array([c for cs in children for c in cs], dtype=np.int64))
        self.attachment_point = np.array(model.attachment_point, dtype=float)
        # the drives, evaluated in Python at every right-hand side (joint_inputs)
        self.prescribed = np.zeros(nq, dtype=np.int64)
        self.drive_value = np.zeros(nq)
        self._motions, self._springs, self._drive_fns, self._pds = [], [], [], []
        for c, (k, i, d) in enumerate(self.coordinates):
            if d is None:
                continue
            if d["kind"] == MOTION:
                self.prescribed[c] = 1
                self._motions.append((c, d["function"]))
            elif d["kind"] == SPRING_DAMPER:
                self._springs.append((c, d["stiffness"], d["damping"], d["rest"]))
            elif d["kind"] == FORCE:
                self._drive_fns.append((c, d["function"]))
            elif d["kind"] == PD:
                self._pds.append((c, d["stiffness"], d["damping"]) + tuple(d["function"]))
            else:
                raise ValueError(f"simulate_reference: {self.coordinate_label(c)}: unknown drive "
                                 f"kind {d['kind']}")
        # the end stops of the free coordinates (elements/limits.py): (coordinate, whether it
        # has a drive, its stops (lower, upper, stiffness, damping)), their generalized forces
        # (added to drive_value) in stop_value
        self._stops = [(c, d is not None, limit_of(self.hinge_params[k], i))
                       for c, (k, i, d) in enumerate(self.coordinates)
                       if limit_of(self.hinge_params[k], i)[2] != 0.0 and not self.prescribed[c]]
        self.stop_value = np.zeros(nq)
        self.has_stops = bool(self._stops)
        self.joints = (self.c_off, self.c0, nq, self.c_col0, self.prescribed, self.drive_value)
        self.kernels = _Kernels()

    def coordinate_label(self, c):
        """How messages name coordinate c: its joint, hinge index and coordinate."""
        k, i, _ = self.coordinates[c]
        kind = JOINT_KIND[int(self.kinds[k])].name
        return f"{kind} '{self.model.hinge_names[k]}' (hinge {k}), coordinate {i}"

    def initial_state(self):
        m = self.model
        y = np.zeros(self.n_state)
        for k in range(self.n):
            if self.q_off[k] >= 0:
                y[self.q_off[k]:self.q_off[k] + 4] = rotation_to_quaternion(m.initial_rotation[k])
                y[self.w_off[k]:self.w_off[k] + 3] = m.initial_angular_velocity[k]
            if self.d_off[k] >= 0:  # an elastic hinge's deflection (its rate: 0), a free
                d = self.d_off[k]       # joint's flight and its rate (world: model/freeze.py)
                y[d:d + 3] = self.hinge_params[k, DEFLECTION_0]
                y[d + 3:d + 6] = self.hinge_params[k, DEFLECTION_RATE_0]
        nm = self.n_modal
        if nm > 0:
            y[self.e0:self.e0 + nm] = np.asarray(m.initial_modal_coordinates, dtype=float)
            y[self.e0 + nm:self.e0 + 2 * nm] = np.asarray(m.initial_modal_velocities,
                                                          dtype=float)
        for c, (k, i, _) in enumerate(self.coordinates):
            y[self.c0 + c] = self.hinge_params[k, COORDINATE_0][i]
            y[self.c0 + self.n_coord + c] = self.hinge_params[k, RATE_0][i]
        return y

    def _number(self, c, what, t, value):
        """A drive's value as a float; ValueError naming the joint and coordinate otherwise."""
        return _finite_number(value, self.coordinate_label(c), what, t)

    def joint_inputs(self, t, y):
        """The state with every prescribed coordinate and rate taken from its motion at time t,
        and each coordinate's drive value (joints[5]): the generalized force f(t, q, q') or
        -k (q - rest) - c q' of a free coordinate's drive (0 without one), the prescribed
        acceleration of a driven one (newton_euler.py's docstring, "Joints with coordinates")."""
        c0, nq = self.c0, self.n_coord
        if self._motions:
            y = y.copy()
        for c, (position, velocity, acceleration) in self._motions:
            y[c0 + c] = self._number(c, "prescribed position", t, position(t))
            y[c0 + nq + c] = self._number(c, "prescribed velocity", t, velocity(t))
            self.drive_value[c] = self._number(c, "prescribed acceleration", t, acceleration(t))
        for c, stiffness, damping, rest in self._springs:
            self.drive_value[c] = -stiffness * (y[c0 + c] - rest) - damping * y[c0 + nq + c]
        for c, f in self._drive_fns:
            self.drive_value[c] = self._number(c, "drive function(t, q, q_dot)", t,
                                               f(t, y[c0 + c], y[c0 + nq + c]))
        for c, kp, kd, target, rate, feedforward in self._pds:
            # f = kp (target - q) + kd (target' - q') + feedforward
            self.drive_value[c] = (
                kp * (self._number(c, "PDTracking target", t, target(t)) - y[c0 + c])
                + kd * (self._number(c, "PDTracking target_rate", t, rate(t)) - y[c0 + nq + c])
                + (0.0 if feedforward is None else
                   self._number(c, "PDTracking feedforward", t, feedforward(t))))
        for c, driven, limit in self._stops:
            # past a bound a one-sided spring-damper pushes back, never pulls (docs/limits.md)
            self.stop_value[c] = stop_force(limit, y[c0 + c], y[c0 + nq + c])
            self.drive_value[c] = (self.drive_value[c] if driven else 0.0) + self.stop_value[c]
        return y

    def ground(self, t):
        """The ground's (r, v, a, R, w, w') at time t as float arrays (_ground_arrays; a still
        ground's made once: the kernels only read them)."""
        if self.model.ground_motion is None:
            if self._still_ground is None:
                self._still_ground = _ground_arrays(self.model.ground_state(0.0))
            return self._still_ground
        return _ground_arrays(self.model.ground_state(t))

    def time_inputs(self, t):
        """Ground motion and applied loads at time t, as float arrays for the kernel."""
        r_g, v_g, a_g, rot_g, w_g, wd_g = self.ground(t)
        for k, f in self._force_fns:
            self.forces[k] = f(t)
        for k, f in self._torque_fns:
            self.torques[k] = f(t)
        for k, f in self._line_load_fns:
            self.line_loads[k] = f(t)
        return (r_g, v_g, a_g, rot_g, w_g, wd_g, self.forces, self.torques,
                self.line_loads)

    def _args(self, y, t):
        r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques, line_loads = self.time_inputs(t)
        y = self.joint_inputs(t, y)
        target = self.loops[10]
        for r, functions, who in self._closure_motions:
            for i, (what, f) in enumerate(zip(("position", "velocity", "acceleration"),
                                              functions)):
                target[r, i] = _finite_number(f(t), who, f"prescribed {what}", t)
        args = (y, self.body_params, self.kinds, self.hinge_params, self.body_kind,
                self.beam_params, self.shape_vec, self.shape_mat, self.q_off, self.w_off,
                self.d_off, self.m_off, self.e0, self.n_modal, self.e_col0, self.f_col,
                self.m_col, self.loops, self.n_unknowns, self.gravity, r_g, v_g, a_g, rot_g, w_g,
                wd_g, forces, torques, line_loads, self.topology, self.attachment_point,
                self.joints, self.exact, self.rods)
        if self._closure_forces:    # a closing JointForce: f(t, q, q') at this state's q, q',
            self.kernels.solve_dynamics(*args)   # which one evaluation leaves in loops[13]
            values = self.loops[13]
            for r, f, who in self._closure_forces:
                target[r, 2] = _finite_number(f(t, values[r, 0], values[r, 1]), who,
                                              "drive function(t, q, q_dot)", t)
        return args

    def rhs(self, t, y):
        return self.kernels.rhs(*self._args(np.ascontiguousarray(y, dtype=float), t))

    def fixed_args(self):
        """(rhs_kernel's arguments after y, the spring-damper drives as rows [coordinate,
        stiffness, damping, rest], the ground's spin axis and its angle's terms: hub.py's
        hub_table) when nothing in them runs Python (no drive but springs, applied load, closing
        joint's motion or force, or ground motion given as functions other than a spin by a
        profile's angle): integrator.py runs such a model in compiled code, setting the springs'
        forces as joint_inputs does and the spun ground as ground does; None otherwise."""
        hub = hub_table(self.model.ground_motion)
        if (self._motions or self._drive_fns or self._pds or self._stops or self._force_fns
                or self._torque_fns or self._line_load_fns or self._closure_motions
                or self._closure_forces or hub is None):
            return None
        springs = np.array([list(row) for row in self._springs], dtype=float).reshape(-1, 4)
        # (the ground's arrays among the arguments are the run's own, made at t = 0: the
        # integrator writes a spun ground's motion into them)
        return (self._args(self.initial_state(), 0.0)[1:], springs) + hub

    def evaluate(self, t, y):
        """Everything Result records at one time, from the state (see _solve_dynamics)."""
        return self.kernels.solve_dynamics(*self._args(np.ascontiguousarray(y, dtype=float), t))


def _ground_arrays(state):
    """The ground's (r, v, a, R, w, w') as writable float arrays: a moving ground's profiles may
    give read-only ones, which numba types apart (the kernels compiled a second time, ~40 s)."""
    return tuple(np.array(x, dtype=float) for x in state)


def _rod_tables(model):
    """The strain rods' tables for the kernels, padded to the longest and widest rod (a padded
    step has length 0 and weight 0: it adds nothing): (n_q (n,), steps (n, S), xi0
    (n, S, 2, 6), phi (n, S, 2, 6, Q), weights (n, S + 1), K (n, Q), [mu, damping] (n, 2),
    the section's inertia per length diag(j_p, rho I_w, rho I_v) (n, 3)); without rods the same
    tables with no steps and no strain columns.  The strain field is the model's description
    (elements/strain_rod.py); the kinematics are the reference's own (reference/strain_rod.py).
    Every model passes tables of the same types, so the reference's kernels compile once for
    all models, rod code included (cold, the suite's first model 63 -> 99 s; a first model with
    rods then compiled them all again, ~70 s, and the suite's two workers did so at once)."""
    n = model.n_bodies
    rods = [k for k in range(n) if model.body_kind[k] == ROD]
    tables = {k: rod_tables(model.rod_params[k]) for k in rods}
    s_max = max([0] + [len(t[0]) for t in tables.values()])
    q_max = max([0] + [t[2].shape[-1] for t in tables.values()])
    nq = np.zeros(n, dtype=np.int64)
    steps = np.zeros((n, s_max))
    xi0 = np.zeros((n, s_max, 2, 6))
    phi = np.zeros((n, s_max, 2, 6, q_max))
    weights = np.zeros((n, s_max + 1))
    stiffness = np.zeros((n, q_max))
    mu_damping = np.zeros((n, 2))
    section = np.zeros((n, 3))
    for k, (st, x0, ph, wt) in tables.items():
        row = model.rod_params[k]
        nq[k] = rod_coordinate_count(row)
        m = len(st)
        steps[k, :m], xi0[k, :m], phi[k, :m, :, :, :nq[k]] = st, x0, ph
        weights[k, :m + 1] = wt
        stiffness[k, :nq[k]] = rod_stiffness(row)
        mu_damping[k] = row[ROD_MU], row[ROD_DAMPING]
        section[k] = rod_section(row)
    return nq, steps, xi0, phi, weights, stiffness, mu_damping, section
