"""The energy balance of a run (docs/solver.md, "Energy balance"): simulate(...,
max_energy_error=f) stops a run whose total energy E (kinetic, gravity, the hinges' and beams'
strain; the drives' springs left out) departs from E(0) + W by more than f times the largest
kinetic energy so far, W the work done on the system since t = 0:

    P = sum F_k . v_Ck + tau_k . w_k                  applied loads (at the mass centre)
      + sum Q_j q'_j                                  joint drives (springs, dampers, forces,
                                                      prescribed motions: their generalized force)
      - sum (A^T (d' - w_in x d)) . C_t A^T d'          elastic hinges' dampers (inboard axes A:
            + w_rel . C_r w_rel                       the force pair's moment works on w_in;
                                                      a closing one's: closures.
                                                      elastic_closure_terms)
      - sum 2 zeta omega_k m_k eta'_k^2               beams' modal damping
      + F_0 . v_g + (M_0 + d_0 x F_0) . w_g           a moving ground, through each root's load
      - F . v_b - M . w_g  (b the ground)             and each closing joint's (F, M on side b,
      + F . v_a + (M + (p_b - p_a) x F) . w_g         the couple about p_b; v_a, v_b the ground
                           (a the ground)             point's velocity)

integrated over every step by the trapezoidal rule.  For a second-order step the balance
closes to O(h^2); a run that breaks it (a step too large, a runaway the estimate missed) stops
with DivergenceError at the end of the chunk where it broke.  It needs every step's state:
the loop records each step of a chunk when the check is on (positions derived per step only
where loads act), so it costs about the positions' price per step.
"""
import numpy as np

from ..elements import BEAM, RIGID
from ..elements.beam import (AXIAL_MODES, DAMPING_RATIO, EA, EI_V, EI_W, FAMILY, GJ, LENGTH,
                             LOAD_AXES, MASS_PER_LENGTH, MODES, POLAR_PER_LENGTH, STIFFENING,
                             TORSION_MODES, foreshortening_integrals, modal_size, mode_shapes,
                             stretch_along)
from ..elements.hinges import C_ROTATION, C_TRANSLATION, ELASTIC
from ..model.loop_kinematics import elastic_closure_terms, side_motions
from ..elements.rigid_body import TO_MASS_CENTER
from ..results.result import _drive_spring_energy
from ..model.sections import beam_output_offset, output_section


def does_work(model):
    """Whether anything outside the total energy works on the model (applied or distributed
    loads, joint drives, dampers of elastic hinges or beams, a moving ground): then the total
    changes by that work, and only the balance E - E(0) - W measures the integrator."""
    damped = any(kinds[k] == ELASTIC and (np.any(params[k, C_TRANSLATION])
                                          or np.any(params[k, C_ROTATION]))
                 for kinds, params in ((model.hinge_kind, model.hinge_params),
                                       (model.closure_kind, model.closure_params))
                 for k in range(len(kinds)))
    return bool(model.has_applied_loads or any(d is not None for ds in model.drives for d in ds)
                or any(d is not None for ds in model.closure_drives for d in ds)
                or damped or np.any(model.beam_params[:, DAMPING_RATIO] > 0.0)
                or model.ground_motion is not None
                or any(f is not None for f in model.line_loads))


class EnergyBalance:
    """The running balance of one run.  result_of(values, steps) -> (Result, the rows
    restricted to the model's bodies) for rows of the kernels' recorded state (run_records._result);
    beams: run_tables.beam_tables(model) of the user's model (its modal factors)."""

    def __init__(self, model, limit, result_of, beams):
        self.model, self.limit, self.result_of = model, float(limit), result_of
        self.work = 0.0
        self.largest_kinetic = 0.0
        self.worst = 0.0            # the largest |E - E0 - W| / largest kinetic energy so far
        self.e0 = None
        self.p_last = None
        n = model.n_bodies
        self.elastic = [k for k in range(n) if model.hinge_kind[k] == ELASTIC]
        for k in self.elastic:
            if model.parent[k] >= 0 and model.body_kind[model.parent[k]] != RIGID:
                raise ValueError(f"simulate(max_energy_error=...): the elastic hinge "
                                 f"{model.hinge_names[k]!r} follows a beam or strain rod "
                                 f"({model.body_names[model.parent[k]]!r}); its damper's work "
                                 f"is not counted yet")
        self.roots = [k for k in range(n) if model.parent[k] < 0]
        self.grounded_closures = [c for c in range(model.n_closures)
                                  if np.any(model.closure_body[c] < 0)]
        self.closing_dampers = any(np.any(model.closure_params[c, C_TRANSLATION])
                                   or np.any(model.closure_params[c, C_ROTATION])
                                   for c in np.nonzero(model.closure_kind == ELASTIC)[0])
        offsets = model.mode_offsets
        self.loaded_beams = [(k, offsets[k]) for k in range(n) if model.body_kind[k] == BEAM
                             and (model.forces[k] is not None or model.torques[k] is not None)]
        # a distributed load's beams, with their constant modal integrals int Y_k and D1
        self.line_loaded = [(k, offsets[k], *_first_moment_integrals(model.beam_params[k]))
                            for k in range(n) if model.body_kind[k] == BEAM
                            and model.line_loads[k] is not None]
        # the beams' modal damping coefficients c_k = 2 zeta omega_k m_k, flat like eta
        c = []
        factors = beams[5]
        for k in range(n):
            if model.body_kind[k] != BEAM:
                continue
            row = model.beam_params[k]
            m, mt = int(row[MODES]), int(row[TORSION_MODES])
            for ei in (row[EI_V], row[EI_W]):           # the v coordinates first, then w
                mass = row[MASS_PER_LENGTH] * factors[k, :m, 0]
                stiffness = ei * factors[k, :m, 1]
                c.extend(2.0 * row[DAMPING_RATIO] * np.sqrt(stiffness * mass))
            twist = beams[4][k, m:m + mt]               # then the twist (run_tables.beam_tables)
            c.extend(2.0 * row[DAMPING_RATIO] * np.sqrt(row[GJ] * twist[:, 3]
                                                        * row[POLAR_PER_LENGTH] * twist[:, 2]))
            stretch = beams[4][k, m + mt:m + mt + int(row[AXIAL_MODES])]    # and the stretch
            c.extend(2.0 * row[DAMPING_RATIO] * np.sqrt(row[EA] * stretch[:, 4]
                                                        * row[MASS_PER_LENGTH] * stretch[:, 3]))
        self.modal_damping = np.array(c)

    def energy(self, res):
        """(E, kinetic) of a one-row Result, the drives' springs left out (their force is in
        the drives' work)."""
        e = res.kinetic[-1] + res.potential[-1]
        if res.joint_coordinates is not None:
            e -= _drive_spring_energy(self.model, res.joint_coordinates[-1:], 1)[0]
        return e, res.kinetic[-1]

    def power(self, res, values, force, torque, line_load):
        """(T,) the power of everything outside E at each row of res (its times t):
        values, the rows' kernel state restricted to the model's bodies (defl, defl_rate);
        force, torque, line_load (T, n, 3) the applied loads at those times."""
        model = self.model
        t = res.t
        p = np.zeros(len(t))
        w = res.angular_velocity
        ground = self.model.ground_states(t)    # (r, v, R, w) of the ground at each t
        _, v_g, g_rot, w_g = ground
        if model.has_applied_loads:
            l_ic = model.body_params[:, TO_MASS_CENTER]
            v_c = res.velocity_input + np.cross(w, np.einsum("tkij,kj->tki", res.rotation, l_ic))
            w_load = w
            if self.loaded_beams:   # a beam's end load: at its output point, on its end section
                v_c, w_load = v_c.copy(), w.copy()
                force, torque = force.copy(), torque.copy()
                for k, off in self.loaded_beams:
                    v_c[:, k], w_load[:, k], a_o = _beam_end_rates(
                        model.beam_params[k], res, k, off)
                    if model.beam_params[k, LOAD_AXES]:     # followers: in the section's axes
                        force[:, k] = np.einsum("tij,tj->ti", a_o, force[:, k])
                        torque[:, k] = np.einsum("tij,tj->ti", a_o, torque[:, k])
            p += np.einsum("tki,tki->t", force, v_c) + np.einsum("tki,tki->t", torque, w_load)
        for k, off, p_k, d1 in self.line_loaded:    # a distributed load p: p . int v(x) dx
            load = line_load[:, k]
            if model.beam_params[k, LOAD_AXES]:         # a follower: in the frame's axes
                load = np.einsum("tij,tj->ti", res.rotation[:, k], load)
            p += np.einsum("ti,ti->t", load,
                           _beam_line_velocity(model.beam_params[k], res, k, off, p_k, d1))
        if res.joint_coordinates is not None:
            p += np.einsum("tj,tj->t", res.drive_force, res.joint_rates)
        if res.closure_drive_force is not None:     # a closing joint's drives: their forces
            rates = values["closure_wrench"][:, :, 8:10]    # times their coordinates' rates
            p += np.einsum("tci,tci->t", res.closure_drive_force, rates)
        for k in self.elastic:
            h = model.hinge_params[k]
            inb = model.parent[k]
            if inb < 0:
                a_in, w_in = g_rot, w_g
            else:
                a_in, w_in = res.rotation[:, inb], w[:, inb]
            # the damper's force -A C_t A^T d' works on the separation's rate seen from the
            # inboard body, A^T (d' - w_in x d) (the pair's moment d x q works against w_in);
            # its moment -A C_r w_rel on the relative angular velocity
            d_dot = values["defl_rate"][:, k]
            dd_b = np.einsum("tji,tj->ti", a_in, d_dot)
            rel_b = np.einsum("tji,tj->ti", a_in, d_dot - np.cross(w_in, values["defl"][:, k]))
            w_b = np.einsum("tji,tj->ti", a_in, w[:, k] - w_in)
            c_t, c_r = h[C_TRANSLATION].reshape(3, 3), h[C_ROTATION].reshape(3, 3)
            p -= np.einsum("ti,ij,tj->t", rel_b, c_t, dd_b) + np.einsum("ti,ij,tj->t", w_b, c_r,
                                                                         w_b)
        if self.closing_dampers:
            p += elastic_closure_terms(model, res.rotation, w, res.position_input,
                                       res.velocity_input, res.modal_coordinates,
                                       res.modal_velocities, ground)[1]
        if self.modal_damping.size and np.any(self.modal_damping):
            p -= (res.modal_velocities ** 2) @ self.modal_damping
        if model.ground_motion is not None and self.grounded_closures:
            p += self._closures_ground_power(res, values, ground)
        if model.ground_motion is not None:
            for k in self.roots:
                f, m = res.force[:, k], res.moment[:, k]
                if model.hinge_kind[k] == ELASTIC:          # the moment about its place
                    m = m + np.cross(values["defl"][:, k], f)
                v_place = v_g + np.cross(w_g, g_rot @ model.attachment_point[k])
                p += np.einsum("ti,ti->t", f, v_place) + np.einsum("ti,ti->t", m, w_g)
        return p

    def _closures_ground_power(self, res, values, ground):
        """(T,) the power a moving ground puts in through the closing joints that meet it:
        minus the power of the joint's load on the ground (its reaction's, for side a);
        ground: _ground's at the rows' times."""
        model = self.model
        w_g = ground[3]
        p = np.zeros(len(res.t))
        for c in self.grounded_closures:
            f, m = values["closure_wrench"][:, c, 0:3], values["closure_wrench"][:, c, 3:6]
            (p_a, v_a, _, _), (p_b, v_b, _, _) = (side_motions(
                model, c, s, res.rotation, res.angular_velocity, res.position_input,
                res.velocity_input, res.modal_coordinates, res.modal_velocities, ground)
                for s in range(2))
            if model.closure_body[c, 1] < 0:
                p -= np.einsum("ti,ti->t", f, v_b) + np.einsum("ti,ti->t", m, w_g)
            else:
                p += np.einsum("ti,ti->t", f, v_a) + np.einsum(
                    "ti,ti->t", m + np.cross(p_b - p_a, f), w_g)
        return p

    def start(self, values, force, torque, line_load):
        """The balance at t = 0 from the initial state's row."""
        res, mapped = self.result_of(values, [0])
        self.e0, self.largest_kinetic = self.energy(res)
        self.p_last = self.power(res, mapped, force, torque, line_load)[0]

    def chunk(self, values, steps, h, force, torque, line_load):
        """Add a chunk of every-step rows (its steps' ends); returns the broken balance's
        message, or None."""
        res, mapped = self.result_of(values, steps)
        p = self.power(res, mapped, force, torque, line_load)
        # W after each step of the chunk (the trapezoidal rule, step by step)
        self.chunk_work = self.work + 0.5 * h * np.cumsum(
            np.concatenate([[self.p_last + p[0]], p[:-1] + p[1:]]))
        self.work = float(self.chunk_work[-1])
        self.p_last = p[-1]
        e, kinetic = self.energy(res)               # (its last row: the chunk's end)
        # over every row (a run from rest to rest in one chunk has no kinetic energy at its
        # ends: the scale was 0 there and any rounding "broke" the balance)
        self.largest_kinetic = max(self.largest_kinetic, kinetic, float(np.max(res.kinetic)))
        gap = e - self.e0 - self.work
        scale = max(self.largest_kinetic, 1e-300)
        self.worst = max(self.worst, abs(gap) / scale)
        if abs(gap) > self.limit * scale:
            return (f"the energy balance broke: E - E(0) - W = {gap:.4g} J, {abs(gap) / scale:.3g}"
                    f" of the largest kinetic energy {scale:.4g} J, above max_energy_error = "
                    f"{self.limit:g} (W: the work of loads, drives, dampers and a moving ground; "
                    f"a smaller dt, or rtol, keeps it)")
        return None


def _beam_end_rates(row, res, k, offset):
    """(T, 3) each: the velocity of beam k's output point and the angular velocity of its end
    section (docs/beam.md, "End sections"), where its applied end load works, and (T, 3, 3)
    the end section's rotation."""
    n = modal_size(row)
    eta = res.modal_coordinates[:, offset:offset + n]
    eta_dot = res.modal_velocities[:, offset:offset + n]
    rot, w = res.rotation[:, k], res.angular_velocity[:, k]
    _, rate = beam_output_offset(row, rot, w, eta, eta_dot)
    sections = [output_section(row, rot[t], w[t], eta[t], eta_dot[t]) for t in range(len(rot))]
    return (res.velocity_input[:, k] + rate, np.array([s[1] for s in sections]),
            np.array([s[0] for s in sections]))


def _first_moment_integrals(row):
    """(P, D1) of a beam row: P_k = int Y_k (Gauss-Legendre, exact for its modes as in
    run_tables.beam_tables) and the foreshortening's D1 (None without stiffening)."""
    m = int(row[MODES])
    length, family = row[LENGTH], int(row[FAMILY])
    t, wt = np.polynomial.legendre.leggauss(2 * m + 10)
    x, wt = 0.5 * length * (t + 1.0), 0.5 * length * wt
    p = mode_shapes(family, length, m, x)[0] @ wt
    d1 = foreshortening_integrals(family, length, m)[1] if row[STIFFENING] else None
    return p, d1


def _beam_line_velocity(row, res, k, offset, p, d1):
    """(T, 3): int_0^L v(x) dx of beam k, the velocity a distributed load works on:
    L v_I + w x (A s) + A s', s = (L^2 / 2 - C1, P . eta_v, P . eta_w) its first moment in the
    frame (docs/beam.md, "The integrals in the frame"; C1 = int c, the foreshortening's);
    p, d1: _first_moment_integrals(row)."""
    m = int(row[MODES])
    length = row[LENGTH]
    eta = res.modal_coordinates[:, offset:offset + 2 * m]
    eta_dot = res.modal_velocities[:, offset:offset + 2 * m]
    s = np.zeros((len(eta), 3))
    s_dot = np.zeros((len(eta), 3))
    s[:, 0] = 0.5 * length * length
    if d1 is not None:
        for plane in range(2):
            e, ed = eta[:, plane * m:(plane + 1) * m], eta_dot[:, plane * m:(plane + 1) * m]
            s[:, 0] -= 0.5 * np.einsum("tj,jk,tk->t", e, d1, e)
            s_dot[:, 0] -= np.einsum("tj,jk,tk->t", ed, d1, e)
    s[:, 1], s[:, 2] = eta[:, :m] @ p, eta[:, m:] @ p
    s_dot[:, 1], s_dot[:, 2] = eta_dot[:, :m] @ p, eta_dot[:, m:] @ p
    ma = int(row[AXIAL_MODES])
    if ma:          # the stretch: s_x gains int u_x = (int U) . xi ("Stretch")
        t, wt = np.polynomial.legendre.leggauss(ma + 10)
        x, wt = 0.5 * length * (t + 1.0), 0.5 * length * wt
        full = slice(offset + modal_size(row) - ma, offset + modal_size(row))
        p_a = stretch_along(row, np.eye(ma), x) @ wt
        s[:, 0] += res.modal_coordinates[:, full] @ p_a
        s_dot[:, 0] += res.modal_velocities[:, full] @ p_a
    rot, w = res.rotation[:, k], res.angular_velocity[:, k]
    a_s = np.einsum("tij,tj->ti", rot, s)
    return (length * res.velocity_input[:, k] + np.cross(w, a_s)
            + np.einsum("tij,tj->ti", rot, s_dot))
