"""Static equilibrium of a model: static_equilibrium(model, ...) -> StaticEquilibrium
(docs/statics.md).

At rest (every velocity zero) a model is in equilibrium exactly when its accelerations vanish:
the accelerations are M(q)^-1 f(q) with the mass matrix M regular, so a(q) = 0 is f(q) = 0.  The
accelerations at rest are what the solver's consistent start computes (the same transfer
matrices as a step, with the velocities zero), so the equilibrium is found by Newton iterations
on the model's configuration q with a(q) as the residual and its Jacobian by differences.  The
configuration is exact (large rotations): each ball-jointed body's rotation, each joint
coordinate, each elastic hinge's deflection (and its outboard body's rotation), each beam's
modal coordinates; a body behind a fixed hinge follows its inboard output section.  At the solution
the Jacobian is -M^-1 K (K the tangent stiffness), so its eigenvalues are minus the squared
circular frequencies of the small vibrations about the equilibrium: all negative means stable.
"""
from collections import namedtuple
from dataclasses import dataclass, replace
import warnings

import numpy as np

from ..model.closures import check_runs_in_sweeps
from ..model.loop_kinematics import closure_residuals, start_state
from ..elements import BEAM, RIGID, ROD
from ..elements.drives import MOTION
from ..elements.hinges import (BALL, DEFLECTION_0, DEFLECTION_RATE_0, ELASTIC, FIXED, FREE,
                               REST_ROTATION)
from ..elements.kinds import (BODY_KIND, COORDINATE_0, JOINT_KIND, MAX_COORDINATES, RATE_0,
                              WITH_COORDINATES, WITH_SLIDES, joint_motion, row_axes,
                              unimplemented_body_kind)
from ..elements.beam import (FAMILY, LENGTH, MODES, STIFFENING, mode_shapes, stretch_along,
                             trusted_frequency)
from ..elements.rigid_body import TO_MASS_CENTER, TO_OUTPUT
from ..elements.strain_rod import ROD_LENGTH
from ..model.rod_motion import rod_centre_line, rod_end_section
from ..kernels.stepping import ball_chain
from ..kernels.schema import MONITOR_LAYOUT
from ..kernels.stepping.loop import Settings
from ..kernels.transfers.joint import joint_frame, n_coordinates
from ..kernels.algebra.so3 import expm_so3
from ..kernels.stepping.loop import run_steps
from ..model.model import Model
from ..model.sections import beam_output_offset, foreshortening_along, log_rotation, output_section
from . import consistent_start, run_checks, run_tables

__all__ = ["StaticEquilibrium", "StaticEquilibriumError", "static_equilibrium"]


class StaticEquilibriumError(RuntimeError):
    """No static equilibrium was found: the iterations did not converge, or the model has none
    (a body that nothing holds, or loads that nothing balances).

    Parameters
    ----------
    message : str
        What went wrong, and what to do about it (the coordinate with the largest residual
        acceleration, or the body that nothing holds).
    """

    def __init__(self, message):
        super().__init__(message)


@dataclass(frozen=True)
class StaticEquilibrium:
    """The result of ``static_equilibrium``.

    Parameters
    ----------
    model : Model
        The model at rest in the equilibrium configuration: ``simulate(result.model, ...)``
        starts from it.
    iterations : int
        Newton iterations taken.
    residual : float
        The largest acceleration left at the equilibrium (rad/s^2 for rotations, m/s^2 times
        the beam's modal scale for modal coordinates).
    stable : bool
        Every small vibration about the equilibrium oscillates (no squared frequency below
        zero, none complex): False past a buckling load, for a pendulum balanced upright, or
        past a follower load's flutter load (complex pairs).
    squared_frequencies : ndarray
        The eigenvalues of M^-1 K about the equilibrium (K the tangent stiffness, M the mass
        matrix), (rad/s)^2, ascending by real part; negative ones are the unstable directions
        (complex pairs, under non-conservative loads, fluttering ones),
        zeros the neutral ones (rotations that change nothing, e.g. a hanging pendulum's spin
        about the vertical).
    coordinates : tuple of str
        The configuration's coordinates, in the order of the Jacobian's columns.
    trusted_below : float
        Hz: frequencies below it are within about 1% of what more modes would give; at or
        above it a beam's kept modes no longer hold its own frequencies to 1% (the lowest over
        the beams of elements/beam.py::trusted_frequency; inf without beams).  ``trusted``
        marks them.
    """
    model: Model
    iterations: int
    residual: float
    stable: bool
    squared_frequencies: np.ndarray
    coordinates: tuple
    trusted_below: float = np.inf

    @property
    def trusted(self):
        """(frequencies,) bool: True for each frequency below ``trusted_below`` (the modes
        kept hold it to about 1%); False for those beyond what the mode counts were chosen
        for (give the beams more modes, or more elements, to trust them)."""
        return np.asarray(self.frequencies < self.trusted_below)

    def positions(self):
        """The bodies' input points, mass centres and output points at the equilibrium, each
        (n, 3), world frame, m (a beam's mass centre: its chord's midpoint, as in Result;
        its output point on the deflected end)."""
        return _positions(self.model)

    def centreline(self, points_per_beam=9):
        """Points along each body at the equilibrium, world frame, m: per body an array (p, 3),
        a beam's at p = points_per_beam stations x_i = i L / (p - 1) of its deflected centre
        line, r_I + A ((x - c(x)) e1 + u(x)) (docs/beam.md; c the foreshortening, zero
        without stiffening), a strain rod's at as many points equally spaced along it
        (elements/strain_rod.py::rod_centre_line, the last its end point), a rigid body's its
        input and output points."""
        m = self.model
        r_in, _, r_o = self.positions()
        off = np.concatenate([[0], np.cumsum(m.n_modes)])
        lines = []
        for k in range(m.n_bodies):
            if m.body_kind[k] == ROD:
                e = m.initial_modal_coordinates[off[k]:off[k + 1]]
                local = rod_centre_line(m.rod_params[k], e[None], int(points_per_beam))[0]
                local[-1] = (r_o[k] - r_in[k]) @ m.initial_rotation[k]    # (its own stations')
                lines.append(r_in[k] + local @ m.initial_rotation[k].T)
                continue
            if m.body_kind[k] == RIGID:
                lines.append(np.array([r_in[k], r_o[k]]))
                continue
            if m.body_kind[k] != BEAM:
                raise unimplemented_body_kind(m.body_kind[k], f"body '{m.body_names[k]}'",
                                              "the static shape's centre lines")
            row = m.beam_params[k]
            nm = int(row[MODES])
            x = np.linspace(0.0, row[LENGTH], int(points_per_beam))
            y = mode_shapes(int(row[FAMILY]), row[LENGTH], nm, x)[0]
            eta = m.initial_modal_coordinates[off[k]:off[k + 1]]
            c = (foreshortening_along(row, x, eta[None], np.zeros((1, len(eta))))[0][0]
                 if row[STIFFENING] else np.zeros(len(x)))
            local = np.stack([x - c + stretch_along(row, eta, x), eta[:nm] @ y,
                              eta[nm:2 * nm] @ y], axis=1)
            lines.append(r_in[k] + local @ m.initial_rotation[k].T)
        return lines

    @property
    def frequencies(self):
        """The small vibrations' frequencies about the equilibrium, Hz (sqrt of the squared
        circular frequencies over 2 pi; NaN for an unstable direction, fluttering ones
        included).  Those at or above ``trusted_below`` are beyond what the beams' mode counts
        were chosen for (``trusted`` is False for them)."""
        lam = np.asarray(self.squared_frequencies)
        big = np.max(np.abs(lam), initial=0.0)
        real = np.real(lam)
        ok = (real >= 0.0) & (np.abs(np.imag(lam)) <= 1e-6 * big)
        with np.errstate(invalid="ignore"):
            return np.where(ok, np.sqrt(np.abs(real)), np.nan) / (2.0 * np.pi)


def _positions(m):
    """(r_in, r_c, r_o), each (n, 3): a model's bodies' input points, mass centres and output
    points in its initial configuration (StaticEquilibrium.positions)."""
    n = m.n_bodies
    off = np.concatenate([[0], np.cumsum(m.n_modes)])
    r_in, r_c, r_o = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
    for k in range(n):
        p = m.parent[k]
        if p < 0:               # its place on the ground
            r_in[k], rot_p = m.ground_position + m.ground_rotation @ m.attachment_point[k], \
                m.ground_rotation
        elif m.attachment[k] == 0:
            r_in[k] = r_o[p]
            rot_p = output_section(m.beam_params[p], m.initial_rotation[p], np.zeros(3),
                                   m.initial_modal_coordinates[off[p]:off[p + 1]])[0]
        else:
            r_in[k] = r_in[p] + m.initial_rotation[p] @ m.attachment_point[k]
            rot_p = m.initial_rotation[p]
        if m.hinge_kind[k] in WITH_SLIDES:        # the slides along the joint's axes
            h = m.hinge_params[k]
            r_in[k] = r_in[k] + joint_motion(m.hinge_kind[k], row_axes(h), np.eye(3), rot_p,
                                             np.zeros(3), h[COORDINATE_0],
                                             np.zeros(MAX_COORDINATES))[2]
        elif m.hinge_kind[k] in (ELASTIC, FREE):  # the hinge's deflection, the flight (world)
            r_in[k] = r_in[k] + m.hinge_params[k, DEFLECTION_0]
        rot = m.initial_rotation[k]
        r_c[k] = r_in[k] + rot @ m.body_params[k, TO_MASS_CENTER]
        r_o[k] = r_in[k] + rot @ m.body_params[k, TO_OUTPUT]
        if m.body_kind[k] == BEAM:
            e = m.initial_modal_coordinates[off[k]:off[k + 1]]
            rho, _ = beam_output_offset(m.beam_params[k], rot, np.zeros(3), e, np.zeros_like(e))
            r_o[k] = r_in[k] + rho
        elif m.body_kind[k] == ROD:       # its end point (the rod's kinematics)
            e = m.initial_modal_coordinates[off[k]:off[k + 1]]
            r_o[k] = r_in[k] + rod_end_section(m.rod_params[k], rot, np.zeros(3), e)[0]
        elif m.body_kind[k] != RIGID:     # (a rigid body's: its output point, above)
            raise unimplemented_body_kind(m.body_kind[k], f"body '{m.body_names[k]}'",
                                          "the static positions")
    return r_in, r_c, r_o


class _Configuration:
    """The model's configuration as a flat vector q (each free body's rotation increment, world
    axes: behind a ball joint or an elastic hinge; each joint coordinate that no motion
    prescribes; each elastic hinge's deflection, world, m; then every beam's modal
    coordinates), and the accelerations at rest a(q) by the solver's consistent start.  Works on
    the kernel model (run_tables.kernel_model), whose extra massless bodies are welded and so follow
    their inboard bodies."""

    def __init__(self, model, where):
        self.user = model
        unrun = [code for code, kind in BODY_KIND.items() if not kind.schemes]
        for k in np.nonzero(np.isin(model.body_kind, unrun))[0][:1]:
            kind = BODY_KIND[int(model.body_kind[k])]
            raise ValueError(f"{where}: body '{model.body_names[k]}' is {kind.what} "
                             f"({kind.name}), which DT-TMM's sweep does not run yet (the "
                             f"static solve takes its consistent start); the Newton-Euler "
                             f"reference runs it (dttmm.reference.simulate_reference)")
        if len(model.contacts):
            raise ValueError(f"{where}: the model's bodies have contact shapes "
                             f"(docs/contact.md); the static solve does not take contact "
                             f"forces yet: simulate the model with damping to rest instead")
        km, self.keep = run_tables.kernel_model(model)
        self.model = km
        n = km.n_bodies
        for k in range(n):
            kind = int(km.hinge_kind[k])
            if not JOINT_KIND[kind].carries_loads and not run_tables.has_loops(km):
                raise ValueError(f"{where}: joint '{km.hinge_names[k]}' is "
                                 f"{JOINT_KIND[kind].what}: nothing holds the body behind it, "
                                 f"which has no static equilibrium (it flies); simulate it "
                                 f"instead, or hold it by closing joints (System.close)")
            if kind not in (BALL, FIXED, ELASTIC, FREE) + WITH_COORDINATES:
                raise ValueError(f"{where}: joint '{km.hinge_names[k]}' is "
                                 f"{JOINT_KIND[kind].what}; the static solve takes ball joints, "
                                 f"fixed and elastic hinges and joints with coordinates so far "
                                 f"(run the model with damping to rest instead)")
        self.free = [k for k in range(n)
                     if km.hinge_kind[k] in (BALL, ELASTIC, FREE) and not km.ground_locked[k]]
        self.n_rot = 3 * len(self.free)
        # joint coordinates: free unless a motion prescribes them (then held at their value)
        self.coords = [(k, i) for k in range(n) for i in range(n_coordinates(km.hinge_kind[k]))
                       if not (km.drives[k] and km.drives[k][i] is not None
                               and km.drives[k][i]["kind"] == MOTION)]
        self.n_q = len(self.coords)
        self.jq0 = np.array(km.hinge_params[:, COORDINATE_0], order="C")
        # elastic hinges' deflections and free joints' flights (world, m): after the joint
        # coordinates (a free joint: an elastic hinge of no stiffness, held by closing joints)
        self.elastic = [k for k in range(n) if km.hinge_kind[k] in (ELASTIC, FREE)]
        self.d0 = self.n_rot + self.n_q
        self.defl0 = np.where(np.isin(km.hinge_kind, (ELASTIC, FREE))[:, None],
                              km.hinge_params[:, DEFLECTION_0], 0.0)
        self.n_eta = len(km.initial_modal_coordinates)
        mode_off = np.concatenate([[0], np.cumsum(km.n_modes)])
        # the scale of each coordinate: rad, m, or the beam's length for its modal coordinates
        self.e0 = self.d0 + 3 * len(self.elastic)       # where the modal coordinates start
        scale = np.ones(self.e0 + self.n_eta)           # rad, m (a slide, a deflection),
        #                                                 beam lengths
        labels = [f"{km.body_names[k]} rotation {'xyz'[i]}" for k in self.free for i in range(3)]
        labels += [f"{km.hinge_names[k]} coordinate {i + 1}" for k, i in self.coords]
        labels += [f"{km.hinge_names[k]} deflection {'xyz'[i]}" for k in self.elastic
                   for i in range(3)]
        for k in range(n):
            if km.body_kind[k] == BEAM:
                i0, i1 = mode_off[k], mode_off[k + 1]
                scale[self.e0 + i0:self.e0 + i1] = km.beam_params[k, LENGTH]
                labels += [f"{km.body_names[k]} mode {j}" for j in range(i1 - i0)]
            elif km.body_kind[k] == ROD:        # (a strain times the length: rad or m)
                i0, i1 = mode_off[k], mode_off[k + 1]
                scale[self.e0 + i0:self.e0 + i1] = km.rod_params[k, ROD_LENGTH]
                labels += [f"{km.body_names[k]} strain {j}" for j in range(i1 - i0)]
        self.scale = scale
        self.labels = tuple(labels)
        self.mode_off = mode_off
        # closed loops: the constraint closure(q) = 0 beside a(q) = 0 (docs/statics.md,
        # "Closed loops"): a tip joined to the ground stays where it starts; closing joints
        # hold their rows (loop_kinematics.closure_residuals)
        self.closed = model.n_closures > 0
        self.pin = _positions(model)[2][-1] if km.tip_pinned else None
        self.rot0 = np.array(km.initial_rotation, order="C")
        self.eta0 = np.array(km.initial_modal_coordinates)
        # one workspace for every evaluation (the beams' tables do not change)
        self.mode = run_tables._mode(km, "riccati", False)
        self.ws = run_tables.Workspace(km)
        self.params = run_tables.kernel_params(km)
        self.settings = Settings(mode=self.mode, h=1.0, coef=run_tables.Integrator.from_rho_inf(1.0)
                                 .array(), newton_max=0, newton_tol=0.0, record_every=1,
                                 max_step_error=np.inf, stop_unconverged=False, start=False)
        self.monitor = MONITOR_LAYOUT.zeros(
            bodies=n, modes=self.n_eta, elastic_bodies=0,
            coordinate_bodies=n if run_tables.has_coordinates(km) else 0)
        self.fused = None
        if (run_tables.FUSED_BALL_CHAIN and self.mode == run_tables.ksolve.RICCATI_REDUCED
                and not km.needs_general_loop
                and all(BODY_KIND[int(c)].fused for c in km.body_kind)):
            self.fused = (run_steps,
                          ball_chain.fused_loop(n, km.mode_offsets, 1.0, self.settings.coef))

    def vector(self, rot, jq, eta, defl):
        """q of a configuration given by rotations, joint coordinates (n, 3), modal
        coordinates and hinge deflections (n, 3) (rotations relative to the model's own)."""
        q = np.zeros(self.e0 + self.n_eta)
        for i, k in enumerate(self.free):
            q[3 * i:3 * i + 3] = log_rotation(rot[k] @ self.rot0[k].T)
        for j, (k, i) in enumerate(self.coords):
            q[self.n_rot + j] = jq[k, i]
        for j, k in enumerate(self.elastic):
            q[self.d0 + 3 * j:self.d0 + 3 * j + 3] = defl[k]
        q[self.e0:] = eta
        return q

    def rebase(self, q):
        """The same configuration with the free bodies' rotations as the new reference (their
        increments zero): the Jacobian's rotation columns are then world rotations about the
        current configuration, and M^-1 K's eigenvalues come out right."""
        if self.n_rot == 0:
            return q
        rot = self.state(q)[0]
        self.rot0[self.free] = rot[self.free]
        q = q.copy()
        q[:self.n_rot] = 0.0
        return q

    def state(self, q):
        """(rotations, joint coordinates (n, 3), modal coordinates, hinge deflections (n, 3))
        of q: the free bodies turned by their increments, every welded body placed on its
        inboard output section, a body behind a joint with coordinates on its joint's frame
        (kernels/transfers/joint.py)."""
        km = self.model
        rot = self.rot0.copy()
        jq = self.jq0.copy()
        for j, (k, i) in enumerate(self.coords):
            jq[k, i] = q[self.n_rot + j]
        defl = np.zeros((km.n_bodies, 3))
        for j, k in enumerate(self.elastic):
            defl[k] = q[self.d0 + 3 * j:self.d0 + 3 * j + 3]
        eta = q[self.e0:]
        e = np.empty((3, 3))
        for i, k in enumerate(self.free):
            expm_so3(np.ascontiguousarray(q[3 * i:3 * i + 3]), e)
            rot[k] = e @ self.rot0[k]
        zero = np.zeros(3)
        w, wd, d, d_rate = (np.zeros(3) for _ in range(4))
        for k in range(km.n_bodies):
            kind = int(km.hinge_kind[k])
            if kind in (BALL, ELASTIC, FREE) or (kind == FIXED and km.ground_locked[k]):
                continue
            p = km.parent[k]
            if p < 0:
                a_in = km.ground_rotation
            else:
                a_in, _ = output_section(km.beam_params[p], rot[p], zero,
                                         eta[self.mode_off[p]:self.mode_off[p + 1]])
            if kind == FIXED:
                rot[k] = a_in @ km.hinge_params[k, REST_ROTATION].reshape(3, 3)
            else:
                out = np.empty((3, 3))
                joint_frame(kind, np.array(km.hinge_params[k]), np.array(a_in, dtype=float),
                            zero, zero, jq[k].copy(), np.zeros(MAX_COORDINATES),
                            np.zeros(MAX_COORDINATES), out, w, wd, d, d_rate)
                rot[k] = out
        return rot, jq, np.array(eta), defl

    def accelerations(self, q):
        """a(q): the free bodies' angular accelerations, the free joint coordinates' and
        elastic deflections' accelerations and the modal accelerations at rest."""
        rot, jq, eta, defl = self.state(q)
        st = self.ws.state
        st.rot[:] = rot
        st.omega[:] = 0.0
        st.jq[:] = jq
        st.eta[:] = eta
        st.eta_d[:] = 0.0
        st.jqd[:] = 0.0
        for k in self.elastic:
            st.defl[k] = defl[k]
            st.defl_rate[k] = 0.0
        st.z[:] = 0.0
        consistent_start._consistent_start(self.model, self.mode, "riccati", self.fused,
                                           self.params,
                                 self.settings, st, self.ws.sweep, self.monitor, 1.0,
                                 in_skeleton=True)
        a = np.empty(self.e0 + self.n_eta)
        for i, k in enumerate(self.free):
            a[3 * i:3 * i + 3] = st.omega_dot[k]
        for j, (k, i) in enumerate(self.coords):
            a[self.n_rot + j] = st.jqdd[k, i]
        for j, k in enumerate(self.elastic):
            a[self.d0 + 3 * j:self.d0 + 3 * j + 3] = st.defl_acc[k]
        a[self.e0:] = st.eta_acc
        return a

    def jacobian(self, q):
        """da/dq by central differences, steps 1e-5 of each coordinate's scale.  (Not forward
        ones: M^-1 K spans five decades and more where a light body or a high mode is in the
        model, and forward differences' error, ~1e-3 of the largest entry, spoils its soft
        directions: measured on the elastica, convergence slowed to a few percent per
        iteration.)"""
        return self._central_differences(self.accelerations, q, len(q))

    def vibration_jacobian(self, q):
        """da/dq for the small vibrations: central differences at steps h and h / 2 (h = 1e-5
        of each coordinate's scale) extrapolated, (4 D(h/2) - D(h)) / 3, their h^2 error gone.
        The stiff modes' accelerations are far from linear over h: on a mast of 16 welded
        elements of 3 modes (squared frequencies to 4e11 (rad/s)^2) D(h) alone left the first
        frequency 0.29% low, D(h / 10) 0.003%; extrapolated 1e-6 (tests/test_statics.py)."""
        coarse = self._central_differences(self.accelerations, q, len(q))
        fine = self._central_differences(self.accelerations, q, len(q), 0.5)
        return (4.0 * fine - coarse) / 3.0

    def closure(self, q):
        """The closed loops' constraints at q: the pinned tip's output point less its pin,
        world, m; or every closing joint's rows (loop_kinematics.closure_residuals: gaps, m, and
        dots)."""
        model = self.result_model(q)
        if self.pin is not None:
            return _positions(model)[2][-1] - self.pin
        return closure_residuals(model, start_state(model))[0]

    def closure_jacobian(self, q, rows):
        """d closure / dq (rows x n) by central differences, as jacobian's."""
        return self._central_differences(self.closure, q, rows)

    def _central_differences(self, f, q, rows, fraction=1.0):
        """df/dq (rows x n) by central differences, steps 1e-5 of each coordinate's scale (times
        fraction)."""
        jac = np.empty((rows, len(q)))
        for j in range(len(q)):
            h = 1e-5 * fraction * self.scale[j]
            qp, qm = q.copy(), q.copy()
            qp[j] += h
            qm[j] -= h
            jac[:, j] = (f(qp) - f(qm)) / (2.0 * h)
        return jac

    def result_model(self, q):
        """The user's model at rest in configuration q."""
        rot, jq, eta, defl = self.state(q)
        user = self.user
        hinge_params = np.array(user.hinge_params, order="C")
        hinge_params[:, COORDINATE_0] = jq[self.keep]
        hinge_params[:, RATE_0] = 0.0
        elastic = np.isin(user.hinge_kind, (ELASTIC, FREE))    # (a free joint's flight at rest)
        hinge_params[elastic, DEFLECTION_0] = defl[self.keep][elastic]
        hinge_params[elastic, DEFLECTION_RATE_0] = 0.0
        return replace(user, initial_rotation=rot[self.keep],
                       initial_angular_velocity=np.zeros((user.n_bodies, 3)),
                       hinge_params=hinge_params, initial_modal_coordinates=eta,
                       initial_modal_velocities=np.zeros_like(eta))


def static_equilibrium(model: Model, *, guess=None, tol=1e-10, max_iterations=50,
                       max_increment=0.5):
    """The model's static equilibrium under its gravity, applied loads (at t = 0) and the
    ground's state at t = 0, by Newton iterations on its configuration (docs/statics.md).

    Parameters
    ----------
    model : Model
        Built by ``build_chain`` or ``System.build``: ball joints, fixed and elastic hinges
        (the equilibrium's deflections are the result model's ``ElasticHinge.deflection``),
        joints with
        coordinates (a coordinate that a JointMotion prescribes is held at its value at t = 0),
        rigid bodies and beams, in an open chain or tree, a chain whose tip is pinned to
        the ground (``tip="ball"``: the tip stays on its pin, where it starts) or a tree with
        closing joints (``System.close``, on a fixed ground, elastic hinges in the tree or
        closing a loop; the model assembled, ``dttmm.assemble``): closed loops
        (docs/statics.md, "Closed loops").  Its initial rotations, joint
        coordinates and modal coordinates are the first guess; its velocities are ignored
        (the equilibrium is at rest).
    guess : StaticEquilibrium or Model, optional
        Start from this configuration instead (the same bodies and modes): the equilibrium
        under a smaller load, when a load is applied in steps (continuation).
    tol : float, optional
        Converged when a Newton step moves no coordinate by more than tol (rad, or the beam's
        length for its modal coordinates).  Default 1e-10.
    max_iterations : int, optional
        Give up after this many iterations (StaticEquilibriumError).  Default 50.
    max_increment : float, optional
        The largest change of any coordinate in one iteration (rad, or beam lengths); a longer
        Newton step is shortened to it.  Default 0.5.

    Returns
    -------
    StaticEquilibrium
        ``.model`` at rest in the equilibrium, ``.stable``, ``.squared_frequencies`` of the
        small vibrations about it, ``.iterations``, ``.residual``.

    Raises
    ------
    StaticEquilibriumError
        The iterations did not converge (apply the load in steps, passing each result as the
        next ``guess``), or the model has no equilibrium: a body that nothing holds (no
        gravity, load or spring acts on its rotation), or one whose loads nothing balances;
        or the equilibrium found bends a beam beyond its modal description's validity (a tip
        deflection above its length, a twist beyond half a turn: split it into elements).
    ValueError
        A guess that does not fit the model.

    Warns
    -----
    UserWarning
        When the equilibrium is unstable (``stable`` False): e.g. a column loaded past its
        buckling load stays straight in equilibrium, but any disturbance makes it buckle.

    Examples
    --------
    >>> import dttmm
    >>> rod = dttmm.RigidBody(mass=1.0, inertia=[1e-4, 1 / 12, 1 / 12],
    ...                       inertia_about="mass_center", to_mass_center=[0.5, 0, 0],
    ...                       to_output=[1.0, 0, 0])
    >>> eq = dttmm.static_equilibrium(dttmm.build_chain([dttmm.BallJoint(), rod]))
    >>> [round(float(x), 6) + 0.0 for x in eq.model.initial_rotation[0] @ [1.0, 0.0, 0.0]]
    [0.0, -1.0, 0.0]
    """
    where = "static_equilibrium"
    if not isinstance(model, Model):
        raise TypeError(f"{where}: model must be a dttmm.Model (build_chain or System.build), "
                        f"got {type(model).__name__}")
    tol = run_checks._check_positive("tol", tol, where)
    max_increment = run_checks._check_positive("max_increment", max_increment, where)
    max_iterations = run_checks._check_count("max_iterations", max_iterations, 1, where)
    check_runs_in_sweeps(model, where)
    cfg = _Configuration(model, where)
    q = cfg.vector(cfg.rot0, cfg.jq0, cfg.eta0, cfg.defl0)
    if guess is not None:
        start = guess.model if isinstance(guess, StaticEquilibrium) else guess
        if not isinstance(start, Model) or start.n_bodies != model.n_bodies or (
                start.initial_modal_coordinates.shape != model.initial_modal_coordinates.shape):
            raise ValueError(f"{where}: guess must be a StaticEquilibrium or Model of the same "
                             f"bodies and modes as the model")
        rot_k = cfg.rot0.copy()
        rot_k[cfg.keep] = start.initial_rotation
        jq = cfg.jq0.copy()
        jq[cfg.keep] = start.hinge_params[:, COORDINATE_0]
        defl = cfg.defl0.copy()
        defl[cfg.keep] = np.where(np.isin(start.hinge_kind, (ELASTIC, FREE))[:, None],
                                  start.hinge_params[:, DEFLECTION_0], 0.0)
        q = cfg.vector(rot_k, jq, start.initial_modal_coordinates, defl)
    a = a0 = cfg.accelerations(q)
    weight = 1.0 / cfg.scale           # residuals in rad/s^2 (modal: per beam length)
    iterations = 0
    converged = False
    previous = np.inf
    tau = None
    while iterations < max_iterations:
        iterations += 1
        q = cfg.rebase(q)
        # M^-1 K in scaled coordinates
        k = -cfg.jacobian(q) * cfg.scale[None, :] * weight[:, None]
        r = weight * a
        if not cfg.closed:
            newton = np.linalg.lstsq(k, r, rcond=1e-13)[0] if len(r) else r
        else:               # a closed loop: Newton's step along the loop's tangent space
            loop = _closed_loop(cfg, q)
            newton = loop.restore + loop.tangent @ np.linalg.lstsq(
                k @ loop.tangent, r - k @ loop.restore, rcond=LOOP_RCOND)[0]
        # converged: Newton's step is below tol, and what it leaves of the residual (in the
        # directions nothing stiffens) would move the stiffest coordinate by less than tol
        big = np.max(np.abs(np.linalg.eigvals(k)), initial=0.0) if len(r) else 0.0
        if (np.max(np.abs(newton), initial=0.0) <= tol
                and np.linalg.norm(k @ newton - r) <= tol * big):
            converged = True        # the last Newton step still taken: its error, ~tol^2
            a_last = _accelerations_or_nan(cfg, q + newton * cfg.scale)
            if np.all(np.isfinite(a_last)):
                q, a = q + newton * cfg.scale, a_last
            break
        size = np.max(np.abs(newton), initial=0.0)
        if (size <= np.sqrt(tol) and size >= 0.5 * previous
                and np.linalg.norm(k @ newton - r) <= np.sqrt(tol) * big):
            converged = True        # Newton has stopped converging: the residual is at its
            break                   # round-off (with stiff modes, ~1e-6 rad/s^2)
        previous = size
        if not cfg.closed:
            if tau is None:         # the settling flow's first step: at most max_increment
                tau = max_increment / max(np.max(np.abs(r)), 1e-300)
            q_new, a, tau, took_newton = _settling_step(cfg, q, a, k, r, newton, tau,
                                                        max_increment)
            if not took_newton:     # (Newton's stall test above judges Newton's steps only)
                previous = np.inf
        else:
            q_new, a = _damped_closed_step(cfg, q, a, k, r, loop, newton, max_increment)
        if np.array_equal(q_new, q):
            break                   # no step passed: nothing more to gain by iterating
        q = q_new
    if not converged:
        start, left = np.max(np.abs(weight * a0)), np.max(np.abs(weight * a))
        if left > 0.5 * start and iterations >= 10:
            hint = (f"the residual has not fallen ({start:.3g} at the start): the model seems "
                    f"to have no equilibrium it can settle into (a body whose loads nothing "
                    f"balances, e.g. a torque on a ball-jointed body without gravity or "
                    f"spring); if one exists away from this start, pass it as guess=")
        else:
            hint = (f"it fell from {start:.3g} at the start: raise max_iterations, or apply "
                    f"the loads in steps, passing each result as the next guess=")
        raise StaticEquilibriumError(
            f"{where}: no convergence in {iterations} iterations (the largest acceleration "
            f"left is {np.max(np.abs(a)):.3g}, at "
            f"{cfg.labels[int(np.argmax(np.abs(weight * a)))]}); {hint}"
            + ("; in a closed loop, beam elements without stretch modes keep their length, "
               "so a chain of them held straight between its pins cannot sag: give them "
               "axial_modes and axial_stiffness" if cfg.closed else ""))
    q = cfg.rebase(q)
    _check_within_validity(cfg, q, where)
    jac = cfg.vibration_jacobian(q)
    if not cfg.closed:
        _check_held(cfg, jac, where)
        lam = np.linalg.eigvals(-jac)
    else:
        # the small vibrations keep the loop closed: dq = N y along its tangent space, where
        # J N = N C (a(q) stays in it), so the squared frequencies are -C's eigenvalues
        tangent = _closed_loop(cfg, q).tangent
        _check_held(cfg, jac, where, tangent)
        scaled = jac * cfg.scale[None, :] * weight[:, None]
        lam = np.linalg.eigvals(-(tangent.T @ scaled @ tangent))
    lam = lam[np.argsort(lam.real)]
    if np.max(np.abs(lam.imag), initial=0.0) <= 1e-9 * np.max(np.abs(lam), initial=0.0):
        lam = np.real(lam)          # (a conservative system's are real)
    big = np.max(np.abs(lam), initial=0.0)
    lam = np.where(np.abs(lam) <= 1e-9 * big, 0.0, lam)     # neutral directions
    # unstable: a squared frequency below zero (divergence, e.g. buckling), or a complex
    # pair (flutter: non-conservative loads, e.g. a follower force; s^2 = -lam then has a root
    # with a positive real part), beyond the central differences' ~1e-8 error in J
    diverging = np.real(lam) < -1e-9 * big
    fluttering = np.abs(np.imag(lam)) > 1e-6 * big
    stable = not bool(np.any(diverging | fluttering))
    if not stable:
        k = int(np.argmin(np.real(lam)))
        kind = (f"{int(np.sum(diverging))} direction(s); squared frequency "
                f"{np.real(lam[k]):.4g} (rad/s)^2" if np.any(diverging) else
                f"{int(np.sum(fluttering))} complex squared frequencies (flutter), e.g. "
                f"{lam[np.argmax(np.abs(np.imag(lam)))]:.4g} (rad/s)^2")
        warnings.warn(f"{where}: the equilibrium is unstable ({kind}): a disturbance grows "
                      f"from it (e.g. a column past its buckling load, or under a follower "
                      f"force past its flutter load)", stacklevel=2)
    model = cfg.result_model(q)
    return StaticEquilibrium(model=model, iterations=iterations,
                             residual=float(np.max(np.abs(a), initial=0.0)), stable=stable,
                             squared_frequencies=lam, coordinates=cfg.labels,
                             trusted_below=_trusted_below(model))


def _trusted_below(model):
    """Hz: the lowest over the beams of the own frequency their kept modes no longer hold to
    1% (elements/beam.py::trusted_frequency, with what hangs on each and its ends)."""
    beams = np.nonzero(model.body_kind == BEAM)[0]
    if not len(beams):
        return np.inf
    end_mass = model.carried_masses()
    return float(min(trusted_frequency(model.beam_params[k], end_mass[k], model.ends_of(k))
                     for k in beams))


def _settling_step(cfg, q, a, k, r, newton, tau, max_increment):
    """One step toward an open system's equilibrium, in scaled coordinates (x = q / scale,
    residuals r = a / scale, k = -da/dx; docs/statics.md, "Getting there").  Newton's step
    k^+ r where the residual lies in k's range, the step moves no coordinate by more than
    max_increment and it passes Deuflhard's natural monotonicity test |k^+ r_new| < |k^+ r|;
    otherwise one implicit Euler step of the settling flow dx/ds = r(x), the model's motion
    with its own mass matrix as the damping (a = M^-1 f: the potential energy falls along it,
    to a stable equilibrium):

        (I / tau + k) dx = r,

    its pseudo-time step tau held to a local error (tau / 2) |r_new - r| of at most
    max_increment (the difference from the explicit step), as an adaptive ODE solver does:
    where the flow has settled, tau grows (at most tenfold a step) and the step becomes
    Newton's.  A step whose sweep breaks down or whose error is too large is retried with a
    shorter tau.  Returns (q, a, tau, whether Newton's step was taken), q unchanged when no
    step passed."""
    size = np.max(np.abs(newton), initial=0.0)
    outside = np.max(np.abs(r - k @ newton), initial=0.0)
    if 0.0 < size <= max_increment and outside <= 1e-3 * np.max(np.abs(r)):
        a_new = _accelerations_or_nan(cfg, q + newton * cfg.scale)
        if (np.all(np.isfinite(a_new)) and np.linalg.norm(np.linalg.lstsq(
                k, a_new / cfg.scale, rcond=1e-13)[0]) < np.linalg.norm(newton)):
            return q + newton * cfg.scale, a_new, 10.0 * tau, True
    eye = np.eye(len(r))
    for _ in range(30):
        dx = np.linalg.lstsq(eye / tau + k, r, rcond=1e-13)[0]
        biggest = np.max(np.abs(dx), initial=0.0)
        if biggest > max_increment:
            dx *= max_increment / biggest
        a_new = _accelerations_or_nan(cfg, q + dx * cfg.scale)
        error = 0.5 * tau * np.max(np.abs(a_new / cfg.scale - r))
        if np.isfinite(error) and error <= max_increment:
            grow = 10.0 if error == 0.0 else min(10.0, 0.9 * np.sqrt(max_increment / error))
            return q + dx * cfg.scale, a_new, tau * max(grow, 1.0), False
        tau *= 0.25 if not np.isfinite(error) else max(0.2, 0.9 * np.sqrt(max_increment / error))
    return q, a, tau, False


def _accelerations_or_nan(cfg, q):
    """a(q), or NaN where the sweep breaks down (a step too far)."""
    try:
        return cfg.accelerations(q)
    except run_checks.DivergenceError:
        return np.full(len(q), np.nan)


# A closed loop's least-squares solves along its tangent space, (k N)^+, drop singular values
# below LOOP_RCOND of the largest (an open chain's keep 1e-13): a link's spin about its own axis
# is neutral, its singular value the central differences' noise (~1e-11 of the largest,
# measured on a four-bar), and off the loop's tangent space (a step opens the loop at second
# order) the residual has a part along it that 1e-13 blows up by 1e4 and more.
LOOP_RCOND = 1e-9
_ClosedLoop = namedtuple("_ClosedLoop", "tangent restore to_closure")


def _closed_loop(cfg, q):
    """The closed loop's linearized constraint at q, in scaled coordinates x = q / scale: G =
    d closure / dx (3 x n), G = U S V^T; tangent (n x m): an orthonormal basis of G's null
    space (the moves that keep the tip on its pin); restore = -G^+ closure(q), the least move
    that closes the loop; to_closure = G^+ (n x 3).  Singular values below 1e-7 of the
    largest count as zero: an inextensible beam between the pins cannot move its tip along
    its chord, so that row of G vanishes."""
    g = cfg.closure(q)
    gj = cfg.closure_jacobian(q, len(g)) * cfg.scale[None, :]
    u, s, vt = np.linalg.svd(gj)
    rank = int(np.sum(s > 1e-7 * s[0])) if s.size and s[0] > 0.0 else 0
    pinv = vt[:rank].T @ (u[:, :rank].T / s[:rank, None])
    return _ClosedLoop(vt[rank:].T, -pinv @ g, pinv)


def _damped_closed_step(cfg, q, a, k, r, loop, newton, max_increment):
    """A closed loop's damped Newton step: newton (restore + tangent y), no coordinate moved by
    more than max_increment, halved until the natural monotonicity test, with the loop's
    closure added, passes: |(k N)^+ r_new| + |G^+ closure_new| below the same at q (each in
    scaled coordinates, so they add; (k N)^+ with LOOP_RCOND).  Returns (q, a); q unchanged
    if no step passed."""
    reduced = k @ loop.tangent

    def merit(res, q_new):
        y = np.linalg.lstsq(reduced, res, rcond=LOOP_RCOND)[0]
        return np.linalg.norm(y) + np.linalg.norm(loop.to_closure @ cfg.closure(q_new))

    dx = newton.copy()
    biggest = np.max(np.abs(dx), initial=0.0)
    if biggest > max_increment:
        dx *= max_increment / biggest
    before = merit(r, q)
    for _ in range(12):
        q_new = q + dx * cfg.scale
        a_new = _accelerations_or_nan(cfg, q_new)
        if np.all(np.isfinite(a_new)) and merit(a_new / cfg.scale, q_new) < before:
            return q_new, a_new
        dx *= 0.5
    return q, a


def _check_within_validity(cfg, q, where):
    """Refuse an equilibrium that bends a beam beyond what its modal description holds: a tip
    deflection larger than the beam's length, or a twist beyond half a turn (the time loop's
    check, run_checks._beam_beyond_its_length); such a configuration solves the modal equations
    but is no beam's shape (one element rolled into a full circle puts its tip 5.6 m from a
    1 m beam's root)."""
    model = cfg.result_model(q)
    cause = run_checks._beam_beyond_its_length(model, run_checks._beam_tips(model),
                                           model.initial_modal_coordinates)
    if cause:
        cause = cause.split(":")[0]
        raise StaticEquilibriumError(
            f"{where}: the equilibrium found is outside the beam model's validity ({cause}): "
            f"the modal beam describes moderate deflections of each element; split the beam "
            f"into several elements welded end to end by FixedHinge (each then bends less), "
            f"and apply large loads in steps, passing each result as the next guess=")


def _check_held(cfg, jac, where, tangent=None):
    """Refuse a body that nothing holds: all three of its rotation's directions neutral (in a
    closed loop, among the directions that keep it closed: tangent's columns, scaled)."""
    if cfg.n_rot == 0:
        return
    js = jac * cfg.scale[None, :]
    if tangent is not None:
        js = js @ tangent
    u, s, vt = np.linalg.svd(js)
    big = s[0] if len(s) else 0.0
    null = vt[s <= 1e-9 * big] if big > 0.0 else np.eye(js.shape[1])
    if tangent is not None:
        null = null @ tangent.T
    for i, k in enumerate(cfg.free):
        block = null[:, 3 * i:3 * i + 3]
        if np.linalg.matrix_rank(block, tol=1e-6) == 3:
            raise StaticEquilibriumError(
                f"{where}: body '{cfg.model.body_names[k]}' is free: no gravity, load or spring "
                f"holds its rotation about its ball joint in any direction, so every "
                f"orientation is an equilibrium (weld it with a FixedHinge, or load it)")
