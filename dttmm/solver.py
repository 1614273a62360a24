"""DT-TMM time integration of a model (chains, trees, joints with coordinates):
simulate(model, t_end, dt | rtol, ...) -> Result.

The frozen Model is read-only; all mutable state lives in a Workspace allocated once per run.
The time loop runs in numba (one skeleton, kernels/stepping/loop.py, with the scheme's loop variant)
in chunks of fixed steps, or in an adaptive run's segments (adaptive.py); Python only evaluates
the prescribed ground motion, applied loads and joint drives for each chunk, judges segments,
and collects the recorded samples (recording.py).
"""
import functools
import math
import time
from dataclasses import dataclass, replace

import numpy as np

from . import adaptive as adaptive_steps
from .vectors import cross
from .elements import BEAM, RIGID, ROD
from .elements.strain_rod import (ROD_DAMPING, ROD_MODES, ROD_MU, rod_components,
                                  rod_section,
                                  rod_stiffness)
from .elements.strain_rod import rod_tables as rod_element_tables
from .elements.kinds import BODY_KIND, FLEXIBLE, JOINT_KIND, WITH_COORDINATES
from .elements.beam import (AXIAL_MODES, BEAM_PARAM_SIZE, CLAMPED_LOADED, EXACT, FAMILY, LENGTH,
                            MODES, STIFFENING, TORSION_MODES, end_shapes, foreshortening_integrals,
                            mode_shapes, slope_grams, torsion_shapes)
from .elements._checks import is_text
from .elements.drives import (COMPILED_FORCE, FORCE, MOTION, PD, SPRING_DAMPER, compiled_force,
                              known_force, runs_in_loop)
from .elements.hinges import (AXIS_1, BALL, COORDINATE_0, DEFLECTION_0, ELASTIC, FIXED,
                              HINGE_PARAM_SIZE, RATE_0, REST_ROTATION)
from .elements.joints import PRISMATIC
from .elements.rigid_body import TO_MASS_CENTER, TO_OUTPUT
from .kernels.stepping import ball_chain
from .kernels.stepping import weld_chain
from .kernels.stepping import step as kstep
from .kernels import python_twin
from .kernels.assembly.closure import Loops, set_ground
from .kernels.stepping.loop import (ERROR_ESTIMATE, OK, SINGULAR, UNCONVERGED, UNSUPPORTED, Inputs,
                                    Params, Record, Run, State,
                                    Sweep)
# the runners the prepared runs take (read here: tests count their calls)
from .kernels.stepping.loop import run_steps
from .kernels.transfers.beam import gauss_points, quadrature_size
from .kernels.assembly.sweep import DIRECT_TOLERANCE, LOST_ACCURACY
from .closures import (assemble, check_drives_move, check_runs_in_sweeps, closure_forces,
                       closure_targets, constraint_rows, has_closure_drives, loop_residuals)
from .methods import SWEEPS
from .model import (Model, adopt_arrays, children_of, is_shared, kernel_array, model_fact,
                    output_section)
from .energy_balance import does_work
from .recording import (NoCheckpoint, Recording, model_fingerprint)
from .resolution import warn_bent
from .threads import blas_threads
from .result import (DERIVED, FIELDS, Result, beam_output_offset, chain_energies,
                     element_end_section, element_output_offset,
                     point_positions)

MAX_STEP_ERROR = 0.05       # rad or m: simulate's default local error estimate limit per step


class DivergenceError(RuntimeError):
    """A run that cannot go on (docs/solver.md, "Runs that cannot go wrong").

    Raised by ``simulate`` for a step whose error estimate exceeds max_step_error, an
    energy-momentum step that does not converge, a beam deflected beyond its length, a singular
    transfer, NaN, a drive returning a non-finite value, or an adaptive step that fell below
    1e-12 of t_end. The message names the step, the time and the cause.

    Parameters
    ----------
    step : int
        The step at which the run stopped (1 is the first step; 0 the consistent start).
    t : float
        Its time, s.
    cause : str
        What went wrong, and what to do about it where the solver can tell.
    partial : Result, optional
        The samples recorded before the failure (None where there are none).

    Attributes
    ----------
    step, t, cause, partial
        As given.
    """

    def __init__(self, step, t, cause, partial=None):
        super().__init__(f"DT-TMM run stopped at step {step} (t = {t:.6g} s): {cause}")
        self.step = step
        self.t = t
        self.cause = cause
        self.partial = partial


# simulate flags a run whose fastest body turns by more than this per step (rad): the
# trapezoidal rule's phase error, about (w dt)^2 / 12 per radian, passes 1% there
# (docs/solver.md, "Steps that cannot resolve the motion")
MAX_TURN_PER_STEP = 0.35


class UnresolvedMotionWarning(UserWarning):
    """A fixed-step run whose step does not resolve its motion: a body turned by more than
    MAX_TURN_PER_STEP (0.35 rad) in one step, where the trapezoidal rule's phase error passes
    1% per radian; the result may be far off without any other sign (docs/solver.md, "Steps
    that cannot resolve the motion").  ``result.info["turn_per_step_max"]`` holds the
    largest turn per step (rad).

    Parameters
    ----------
    message : str
        The body, its rate, the step and the step that would resolve it.
    """

    def __init__(self, message):
        super().__init__(message)


@dataclass(frozen=True)
class Integrator:
    """Generalized-alpha coefficients (Chung and Hulbert 1993) from the spectral radius at
    infinite frequency rho_inf; rho_inf = 1 is the trapezoidal Newmark rule (beta 1/4,
    gamma 1/2)."""
    beta: float
    gamma: float
    alpha_m: float
    alpha_f: float

    @classmethod
    def from_rho_inf(cls, rho_inf):
        try:
            r = float(rho_inf)
        except (TypeError, ValueError):
            r = np.nan
        if isinstance(rho_inf, (bool, np.bool_)) or not (np.isfinite(r) and 0.0 <= r <= 1.0):
            raise ValueError(f"simulate: rho_inf must be in [0, 1], got {rho_inf!r}")
        alpha_m = (2.0 * r - 1.0) / (r + 1.0)
        alpha_f = r / (r + 1.0)
        gamma = 0.5 + alpha_f - alpha_m
        return cls(beta=0.25 * (gamma + 0.5) ** 2, gamma=gamma, alpha_m=alpha_m, alpha_f=alpha_f)

    def array(self):
        return np.array([self.beta, self.gamma, self.alpha_m, self.alpha_f])


class Workspace:
    """Preallocated state and scratch of one run (nothing here is shared between runs): the
    state the loops advance (kernels/stepping/loop.py::State), the assembly's scratch (Sweep) and
    the beams' tables (beam_tables).  fused: the run takes a fused ball-chain or ball-tree loop,
    which reads the reduced sweep's recursion arrays only (red_s, red_p, red_tinv, red_t,
    red_aq): the full-state sweep's and the general loop's reduced maps (red_v, red_phi) are
    left empty (about 6.5 KB per body: a million bodies' gigabytes)."""

    def __init__(self, model: Model, fused=False):
        n = model.n_bodies
        n_st = 2 * n + 1
        n_full = 0 if fused else n          # the full-state sweep's bodies, elements, stations
        n_el, n_sst = 2 * n_full, (0 if fused else n_st)
        n_eta = int(model.n_modes.sum())
        z3 = lambda: np.zeros((n, 3))                               # noqa: E731
        # a fused loop's ball joints have no offsets, coordinates or mass-centre velocities of
        # their own: those per-body arrays are empty there (a million links: 190 MB)
        n_joint = 0 if fused else n
        off3 = lambda: np.zeros((n_joint, 3))                       # noqa: E731
        # the joints' coordinates and rates at t = 0 (zeros, untouched, without such joints)
        jq, jqd = ((model.hinge_params[:, COORDINATE_0].copy(),
                    model.hinge_params[:, RATE_0].copy()) if has_coordinates(model)
                   else (np.zeros((n_joint, 2)), np.zeros((n_joint, 2))))
        self.state = State(
            rot=model.initial_rotation.copy(), omega=model.initial_angular_velocity.copy(),
            omega_dot=z3(), pseudo=z3(),    # pseudo: the rotation integrator's pseudo-acceleration
            defl=off3(), defl_rate=off3(), defl_acc=off3(), defl_pseudo=off3(),
            z=np.zeros((n_st, 12)),
            # the beams' modal coordinates, rates, accelerations and the integrator's
            # pseudo-accelerations, flat over the beams (v coordinates of a beam, then w)
            eta=model.initial_modal_coordinates.copy(),
            eta_d=model.initial_modal_velocities.copy(), eta_acc=np.zeros(n_eta),
            eta_p=np.zeros(n_eta), eta_map=np.zeros((n_eta, 13)), v_c=off3(),
            # joints with coordinates (kernels/transfers/joint.py): q, q', q'', pseudo, generalized
            # force
            jq=jq, jqd=jqd, jqdd=np.zeros((n_joint, 2)),
            jqp=np.zeros((n_joint, 2)), jtau=np.zeros((n_joint, 2)))
        self.sweep = Sweep(
            kind=np.zeros(n_el, dtype=np.int64), u=np.zeros((n_el, 12, 13)),
            known_loads=np.zeros((n_el, 12)), split=np.zeros(n_sst, dtype=np.int64),
            s=np.zeros((n_sst, 6, 6)), p=np.zeros((n_sst, 6)), tinv=np.zeros((n_el, 6, 6)),
            t=np.zeros((n_el, 6)), g=np.zeros((n_el, 6, 3)), gv=np.zeros((n_el, 6)),
            red_v=np.zeros((n_full, 6, 7)), red_phi=np.zeros((n_full, 3, 7)),
            red_s=np.zeros((n + 1, 3, 3)),
            red_p=np.zeros((n + 1, 3)), red_tinv=np.zeros((n, 3, 3)), red_t=np.zeros((n, 3)),
            red_aq=np.zeros((n + 1, 6)), dir_z=np.zeros((n_sst, 12, 6)),
            dir_o=np.zeros((n_sst, 12)), port_s=np.zeros((n_full, 3, 3)),
            port_p=np.zeros((n_full, 3)), aq_out=np.zeros((n_full, 6)),
            tree_s=np.zeros((n_full, 6, 6)), tree_p=np.zeros((n_full, 6)),
            joint_dof=np.zeros((n_full, 3), dtype=np.int64),
            joint_tau_nu=np.zeros((n_full, 3, 3)), joint_nu=np.zeros((n_full, 3)),
            joint_tau=np.zeros((n_full, 3)))
        self.beams = beam_tables(model)
        _initial_deflections(model, self.state)


def _initial_deflections(model, state):
    """state.defl at t = 0, the offset of each body's input point from its parent's output
    point, which the loops keep from the first step on (the t = 0 sample, the energies and
    positions then place the body where the model says): an elastic hinge's given deflection
    (ElasticHinge.deflection; its rate starts at zero), and a prismatic joint's slide d = u q
    with its rate u q' + w_p x d (u the axis in world, w_p the parent's output section's
    angular velocity; kernels/transfers/joint.py::joint_frame)."""
    for k in range(model.n_bodies):
        if model.hinge_kind[k] == ELASTIC:
            state.defl[k] = model.hinge_params[k, DEFLECTION_0]
        if model.hinge_kind[k] != PRISMATIC:
            continue
        p = model.parent[k]
        if p < 0:
            rot_p, w_p = model.ground_rotation, model.ground_state(0.0)[4]
        else:
            off = int(np.sum(model.n_modes[:p]))
            rot_p, w_p = output_section(
                model.beam_params[p], model.initial_rotation[p],
                model.initial_angular_velocity[p],
                model.initial_modal_coordinates[off:off + model.n_modes[p]],
                model.initial_modal_velocities[off:off + model.n_modes[p]])
        u = rot_p @ model.hinge_params[k, AXIS_1]
        state.defl[k] = u * model.hinge_params[k, COORDINATE_0][0]
        state.defl_rate[k] = u * model.hinge_params[k, RATE_0][0] + cross(w_p, state.defl[k])


@model_fact
def kernel_params(model):
    """The frozen model's arrays as the kernels read them (kernels/stepping/loop.py::Params), once
    per model: the kernels read them and never write them."""
    # a locked body's rotation relative to the ground frame (read only where locked[k]; no
    # rows without locked bodies: a million bodies' 72 MB)
    lock_rel = (np.einsum("ji,kjl->kil", model.ground_rotation, model.initial_rotation,
                          order="C") if model.ground_locked.any() else np.zeros((0, 3, 3)))
    # the model's arrays writable (numba types read-only arrays apart, and every kernel would
    # compile twice), its own memory where it has it: kernel_array; a table whose rows are all
    # equal (model.shared_rows) as its one row, which every body (joint) reads (body_row)
    (body_params, inertia), body_row = _rows(model, "body_params", "body_mass_center_inertia")
    (hinge_params,), hinge_row = _rows(model, "hinge_params")
    return Params(body_params=body_params, hinge_kind=kernel_array(model, "hinge_kind"),
                  hinge_params=hinge_params, gravity=kernel_array(model, "gravity"),
                  beams=beam_tables(model), rods=rod_tables(model),
                  locked=kernel_array(model, "ground_locked"),
                  lock_rel=lock_rel, mass_center_inertia=inertia,
                  tip_pinned=bool(model.tip_pinned),
                  parent=kernel_array(model, "parent", np.int64),
                  joint_drive=joint_drives(model), body_row=body_row, hinge_row=hinge_row)


@model_fact
def rod_tables(model):
    """The strain rods' tables as the kernels read them (kernels/transfers/strain_rod.py), padded
    to the longest and widest rod (a padded step has length 0 and weight 0: it adds nothing; a
    rod reads its first n_q coordinates' columns): (rod_row (n,) int64, body k's row or -1;
    steps (R, S), xi0 (R, S, 2, 6), phi (R, S, 2, 6, Q), weights (R, S + 1) of the stations
    0 .. S, K (R, Q), [mu, damping] (R, 2), the sections' inertia per length (R, 3)), one row per
    rod (rods of equal parameters share theirs), one row of zeros without rods (and rod_row
    of one entry: a million rigid bodies keep their 8 MB)."""
    rod_row = np.full(model.n_bodies if (model.body_kind == ROD).any() else 1, -1,
                      dtype=np.int64)
    rows, tables = {}, []
    for k in np.nonzero(model.body_kind == ROD)[0]:
        row = model.rod_params[k]
        key = row.tobytes()
        if key not in rows:
            rows[key] = len(tables)
            tables.append((row,) + rod_element_tables(row))
        rod_row[k] = rows[key]
    s_max = max([1] + [len(t[1]) for t in tables])
    q_max = max([1] + [t[3].shape[-1] for t in tables])
    r = max(1, len(tables))
    steps, xi0 = np.zeros((r, s_max)), np.zeros((r, s_max, 2, 6))
    phi, weights = np.zeros((r, s_max, 2, 6, q_max)), np.zeros((r, s_max + 1))
    stiffness, mu_damping, section = np.zeros((r, q_max)), np.zeros((r, 2)), np.zeros((r, 3))
    for i, (row, st, x0, ph, wt) in enumerate(tables):
        m, nq = len(st), ph.shape[-1]
        steps[i, :m], xi0[i, :m], phi[i, :m, :, :, :nq], weights[i, :m + 1] = st, x0, ph, wt
        stiffness[i, :nq] = rod_stiffness(row)
        mu_damping[i] = row[ROD_MU], row[ROD_DAMPING]
        section[i] = rod_section(row)
    return rod_row, steps, xi0, phi, weights, stiffness, mu_damping, section


def _rows(model, *names):
    """(the model's tables `names` as the kernels read them, each body's row of them): one row
    read by every body where all the tables are shared (model.shared_rows), else every body's
    own (their rows k)."""
    n = model.n_bodies
    if all(is_shared(getattr(model, name)) for name in names):
        return (tuple(np.array(getattr(model, name)[:1], order="C") for name in names),
                np.zeros(n, dtype=np.int64))
    return tuple(kernel_array(model, name) for name in names), np.arange(n, dtype=np.int64)


def joint_drives(model):
    """(n, 2, 4): each joint coordinate's drive as the kernels read it, [kind, stiffness,
    damping, rest], kind -1 for none (elements/drives.py).  A drive with a part known in time
    (a PDTracking, a JointForce of time alone) is a spring-damper about 0 there, its known
    part in the inputs (_joint_inputs; kernels/transfers/joint.py::drive_value); a compiled
    JointForce is COMPILED_FORCE with its callback's index in compiled_forces in place of the rest.
    One row of none for a model without joints with coordinates (the kernels read a joint's row
    only; the full-state tree sweep hands a ball joint row 0, unread)."""
    table = np.zeros((model.n_bodies if has_coordinates(model) else 1, 2, 4))
    table[:, :, 0] = -1.0
    for k, drives in enumerate(model.drives):
        for i, d in enumerate(drives):
            if d is None or d.get("compiled"):
                continue
            if d["kind"] == PD or (d["kind"] == FORCE and d.get("of_time")):
                table[k, i] = [SPRING_DAMPER, d["stiffness"], d["damping"], 0.0]
            else:
                table[k, i] = [d["kind"], d["stiffness"], d["damping"], d["rest"]]
    for index, (k, i, _) in enumerate(_compiled_drives(model)):
        table[k, i] = [COMPILED_FORCE, 0.0, 0.0, index]
    return table


def _compiled_drives(model):
    """[(joint, coordinate, drive)] of the compiled JointForces, in the order their callbacks
    are numbered (joint_drives, compiled_forces)."""
    return [(k, i, d) for k, drives in enumerate(model.drives) for i, d in enumerate(drives)
            if d is not None and d.get("compiled")]


@model_fact
def compiled_forces(model):
    """(k,) int64: the addresses of the compiled JointForces' C callbacks, numbered as in
    joint_drives (elements/drives.py::compiled_force; each process compiles its own)."""
    return np.array([compiled_force(d["function"]).address
                     for _, _, d in _compiled_drives(model)], dtype=np.int64)


@model_fact
def has_coordinates(model):
    return bool(np.isin(model.hinge_kind, WITH_COORDINATES).any())


@model_fact
def has_offsets(model):
    """A joint offsets its body's input point from its parent's output point (state.defl): an
    elastic hinge's deflection, a prismatic joint's slide."""
    return bool(np.isin(model.hinge_kind, (ELASTIC, PRISMATIC)).any())


@model_fact
def has_loops(model):
    """Closing joints other than a chain's pinned tip (kernels/assembly/closure.py)."""
    return model.n_closures > 0 and not model.tip_pinned


@model_fact
def full_tree(model, full_state=False):
    """Whether the model runs in the full-state tree sweep (mode "riccati-joints",
    docs/assembly.md "Trees with joints"): joints with coordinates anywhere, closing joints, a
    tree with fixed hinges, or a tree asked to run in full state; ball-joint trees otherwise
    run reduced."""
    return (has_coordinates(model) or has_loops(model)
            or (not model.is_chain and (full_state or not model.all_ball)))


# loops with more rows than this whose rows' matrices are banded (half the rows wide at most)
# are solved by a regularized banded LU, fewer by the truncated SVD
# (kernels/assembly/closure.py::_rows_solve; at 50 rows the SVD costs 1.3 ms, the band's LU ~10 us)
BANDED_ROWS = 20


def _column_bodies(model, loaded):
    """(up, active) of a column loaded at the bodies `loaded` (kernels/assembly/closure.py): its
    active bodies are the subtrees of its loaded bodies' topmost moving ancestors (below the ground
    and the bodies locked to it, whose kinematics a load does not change), where its response
    is not zero; up adds the loaded bodies' other ancestors, which its upward sweep passes
    too (their loads, for the step's own recovery)."""
    parent, locked = model.parent, np.asarray(model.ground_locked, dtype=bool)
    up, tops = set(), set()
    for b in loaded:
        k = int(b)
        top = None if locked[k] else k
        while k >= 0:
            up.add(k)
            if not locked[k]:
                top = k
            k = int(parent[k])
        if top is not None:
            tops.add(top)
    active = np.zeros(model.n_bodies, dtype=bool)
    for k in range(model.n_bodies):           # (parents come first)
        p = int(parent[k])
        active[k] = k in tops or (p >= 0 and active[p])
    return up | set(np.nonzero(active)[0].tolist()), active


def loop_columns(model, owner, body, banded_rows=None):
    """Where each row's sweep column runs (kernels/assembly/closure.py): (act (R + 1, n) the active
    bodies per column, column 0 all; ups, body -> the columns c >= 1 its upward sweep passes (bodies
    that pass none left out: a million empty lists held 56 MB); act_idx
    and act_ptr, each column's active bodies in tree order; colrows, per row's column the rows
    with a side body among its active bodies; (lower, upper) the rows' matrices' bandwidths, or
    (-1, -1) where the truncated SVD solves them).  owner: each row's closing joint; body
    (m, 2): the closing joints' sides (-1 the ground), in the kernel model's numbering."""
    n, r = model.n_bodies, len(owner)
    act = np.zeros((r + 1, n), dtype=bool)
    act[0] = True
    ups = {}
    act_idx = []
    act_ptr = [0, 0]
    per_closure = {}
    for row in range(r):
        c = int(owner[row])
        if c not in per_closure:
            per_closure[c] = _column_bodies(model, [b for b in body[c] if b >= 0])
        up, active = per_closure[c]
        act[row + 1] = active
        for k in sorted(up):
            ups.setdefault(k, []).append(row + 1)
        act_idx.extend(np.nonzero(active)[0].tolist())
        act_ptr.append(len(act_idx))
    sides = body[np.asarray(owner, dtype=np.int64)]                   # (R, 2), -1 the ground
    reach = np.concatenate([act, np.zeros((r + 1, 1), dtype=bool)], axis=1)[1:][:, sides]
    colrows = [np.nonzero(hit.any(axis=1))[0].tolist() for hit in reach]     # (R, R, 2)
    # the rows' matrices' band (row q of column j's rows): solved banded where it is narrow
    lower = max([q - j for j, rows in enumerate(colrows) for q in rows], default=0)
    upper = max([j - q for j, rows in enumerate(colrows) for q in rows], default=0)
    banded_rows = BANDED_ROWS if banded_rows is None else banded_rows
    band = (lower, upper) if r > banded_rows and 2 * (lower + upper + 1) <= r else (-1, -1)
    return act, ups, act_idx, act_ptr, colrows, band


def loop_tables(model):
    """The closing joints as the general loop reads them (kernels/assembly/closure.py::Loops), in
    the kernel model's numbering, with their scratch; no rows without loops.  Column 0 of the
    sweep is the step, column r + 1 row r's unit multiplier, which passes the bodies of
    loop_columns.  Each call's own copy (a run writes its scratch) of the tables built once
    per model."""
    return Loops(*(a.copy() for a in _loop_tables(model, BANDED_ROWS)))


@model_fact
def _loop_tables(model, banded_rows):
    n = model.n_bodies
    kind, owner, v1, v2, v3, coordinate, law = constraint_rows(
        model, None if has_loops(model) else ())
    m = model.n_closures if len(kind) else 0
    r = len(kind)
    point = np.array(model.closure_point[:m], dtype=float).reshape(m, 2, 3)
    body = np.array(model.closure_body[:m], dtype=np.int64).reshape(m, 2)
    act, ups, act_idx, act_ptr, colrows, band = loop_columns(model, owner, body, banded_rows)
    nb = n if r else 0          # the rows' scratch per body (kernels/assembly/closure.py;
    st = 2 * nb + 1 if r else 0  # none without rows: a million bodies' 900 B each)
    up_ptr = np.zeros(n + 1, dtype=np.int64)      # (body k's columns: up_idx[up_ptr[k]:..])
    for k, u in ups.items():
        up_ptr[k + 1] = len(u)
    np.cumsum(up_ptr, out=up_ptr)
    col_body = np.full((r + 1, 2), -1, dtype=np.int64)
    col_body[1:] = body[np.asarray(owner, dtype=np.int64)]
    return Loops(kind=kind, owner=owner, v1=v1, v2=v2, v3=v3, target=np.zeros((r, 3)),
                 coordinate=coordinate, law=law, acc=np.zeros(r), step_coef=np.zeros(2),
                 body=body, point=point, ground=np.array(model.ground_position, dtype=float),
                 ground_rot=np.array(model.ground_rotation, dtype=float),
                 ground_motion=np.zeros((4, 3)), coef=np.zeros((r, 4, 3)), kappa=np.zeros(r),
                 z_save=np.zeros((r + 1, st, 12)),
                 nu_save=np.zeros((r + 1, nb, 3)), tau_save=np.zeros((r + 1, nb, 3)),
                 delassus=np.zeros((r, r)), lam=np.zeros(r), rhs=np.zeros(r),
                 r_out=np.zeros((nb, 3)), v_out=np.zeros((nb, 3)), g=np.zeros(r),
                 gd=np.zeros(r), col_body=col_body, col_load=np.zeros((r + 1, 2, 6)),
                 up_ptr=up_ptr, up_idx=np.array([c for k in sorted(ups) for c in ups[k]],
                                                 dtype=np.int64),
                 act_ptr=np.array(act_ptr, dtype=np.int64),
                 act_idx=np.array(act_idx, dtype=np.int64), act=act,
                 all_bodies=np.arange(nb, dtype=np.int64),
                 all_rows=np.arange(r, dtype=np.int64),
                 band=np.array(band, dtype=np.int64),
                 colrow_ptr=np.cumsum([0] + [len(c) for c in colrows]).astype(np.int64),
                 colrow_idx=np.array([q for c in colrows for q in c], dtype=np.int64),
                 p_col=np.zeros((r + 1, st, 6)), port_col=np.zeros((r + 1, nb, 6)),
                 h_store=np.zeros((nb, 3, 6)), k_store=np.zeros((r + 1, nb, 3)),
                 free_store=np.zeros((nb, 4), dtype=np.int64),
                 p_comb=np.zeros((st, 6)), k_comb=np.zeros((nb, 3)),
                 eta_col=np.zeros((r, int(np.sum(model.n_modes)))), wrench=np.zeros((m, 10)),
                 stats=np.zeros(4), energy=np.array([0.0, np.nan, 0.0]))


def _loop_info(loops):
    """A run's info on its closing joints (kernels/assembly/closure.py::Loops.stats, energy): the
    largest residuals after any step's projections, and before them, and where the energy is
    held the largest relative change of the rates that held it; nothing without loops."""
    if not len(loops.kind):
        return {}
    return {"loop_position_residual": float(loops.stats[3]),
            "loop_rate_residual": float(loops.stats[2]),
            "loop_position_residual_unprojected": float(loops.stats[0]),
            "loop_rate_residual_unprojected": float(loops.stats[1]),
            **({"energy_correction": float(loops.energy[2])} if loops.energy[0] else {})}


def energy_not_held(model, rho_inf=1.0):
    """Why the loops' projection does not hold the total energy of a run of this model
    (docs/loops.md, "The energy held"), or None where it does: closed loops of rigid bodies on
    which nothing works (no loads but gravity, no drives, dampers or moving ground), stepped
    without numerical damping."""
    if not has_loops(model):
        return "it has no closed loops (the loops' projection holds it)"
    if np.any(model.body_kind == BEAM):
        return "it has beams"
    if np.any(model.body_kind == ROD):
        return "it has strain rods"
    if np.any(model.hinge_kind == ELASTIC) or np.any(np.asarray(model.closure_kind) == ELASTIC):
        return "it has elastic hinges"
    if does_work(model):
        return "work is done on it (applied loads, drives, dampers or a moving ground)"
    if float(rho_inf) != 1.0:
        return f"numerical damping (rho_inf = {rho_inf:g} < 1) takes energy out by design"
    return None


@model_fact
def _iterates(model, full_state):
    """Joint children and bodies welded to a beam's end in the full-state tree sweep have a
    Jacobian exact only to O(dt) terms (kernels/transfers/joint.py, step.py::_welded): their steps
    iterate to newton_tol by default (without iterations a flexible link there is not stable).
    Asked of the kernels' model (kernel_model: an end section is welded to its beam)."""
    model = kernel_model(model)[0]
    if has_loops(model):            # closing joints: their rows converge with the iterations
        return True
    return has_coordinates(model) or (full_tree(model, full_state) and any(
        model.hinge_kind[k] == FIXED and model.parent[k] >= 0
        and model.body_kind[model.parent[k]] == BEAM for k in range(model.n_bodies)))


def _joint_inputs(model, times, state=None, dt=0.0):
    """(len(times), n, 2, 3): per joint coordinate, a prescribed motion's (q, q', q''), a
    drive's force known in time (elements/drives.py::known_force) and a JointForce's value
    f(t, q, q') at each time (kernels/stepping/loop.py::Inputs).  A JointForce of the state is
    evaluated at the coordinates the constant-acceleration predictor gives from the state (one step
    ahead of it: the solver then takes one step per chunk); docs/joints.md, "In the
    transfer"."""
    out = np.zeros((len(times), model.n_bodies, 2, 3))
    for k, drives in enumerate(model.drives):
        for i, d in enumerate(drives):
            if d is None or d["kind"] not in (FORCE, MOTION, PD):
                continue
            who = f"the drive of '{model.hinge_names[k]}' (coordinate {i + 1})"
            if d.get("compiled"):           # (the loop calls it at the step's time)
                out[:, k, i, 0] = times
                continue
            for j, t in enumerate(times):
                if d["kind"] == MOTION:
                    out[j, k, i] = [_drive_number(f(t), who, t) for f in d["function"]]
                elif runs_in_loop(d):
                    out[j, k, i, 0] = _drive_number(_known(d, t, who), who, t)
                else:
                    q, qd, qdd = state.jq[k, i], state.jqd[k, i], state.jqdd[k, i]
                    if t > 0.0:
                        q, qd = q + dt * qd + 0.5 * dt * dt * qdd, qd + dt * qdd
                    out[j, k, i, 0] = _drive_number(d["function"](t, q, qd), who, t)
    return out


def additive_joint_force(drive):
    """Whether a generalized force on a joint coordinate with this drive (Model.drives' entry)
    adds to the force its known-force slot carries into the loop (_joint_inputs' [.., 0],
    kernels/transfers/joint.py::drive_value): no drive, a spring-damper, a PD tracking or a
    force of time in Python; not a prescribed motion (the slot holds q) nor a compiled
    JointForce (it holds t)."""
    return drive is None or not (drive["kind"] == MOTION or drive.get("compiled"))


def _known(d, t, who):
    try:
        return known_force(d, t)
    except Exception as err:
        raise UserFunctionError(t, f"{who} failed at t = {t:.6g} s ({type(err).__name__}: "
                                f"{err})") from None


def _drive_number(value, who, t):
    """A drive function's value as a float, or UserFunctionError naming the drive and t: one
    finite number (not text, not several)."""
    if is_text(value) or np.size(value) != 1:
        raise UserFunctionError(t, f"{who} returned {value!r} at t = {t:.6g} s: it must return "
                                f"one number")
    try:
        x = float(np.squeeze(value))
    except (TypeError, ValueError):
        x = np.nan
    if not np.isfinite(x):
        raise UserFunctionError(t, f"{who} returned {value!r} at t = {t:.6g} s (not finite)")
    return x


def exact_points(modes):
    """Gauss-Legendre points of a beam's exact foreshortening (beam_tables), for m bending
    modes per plane and ma stretch modes (modes = m + ma): its integrands (docs/beam.md, "The
    exact foreshortening") are polynomials of degree up to 6 m + 3 for the loaded-end modes
    (p x p'' with c c'', times D eta in the modal rows), integrated exactly by 3 m + 2 points;
    3 (m + ma) + 8 leaves room for the stretch and the trigonometric families."""
    return 3 * int(modes) + 8


def exact_section_table(family, length, m, x, weights):
    """(m, 1 + n (3 + m)) for the n Gauss-Legendre points x (weights) on [0, length]: n, then
    per point [x, weight, Y_j(x), D(x)[j, :]] for mode j's row, D(x) = int_0^x Y' Y'^T by a
    Gauss-Legendre rule of its own on [0, x] (exact for the loaded-end modes' polynomial
    slopes; elements/beam.py::slope_grams) (beam_tables)."""
    n = len(x)
    y = mode_shapes(family, length, m, x)[0]
    grams = slope_grams(family, length, m, x, 2 * m + 8)
    table = np.zeros((m, 1 + n * (3 + m)))
    table[:, 0] = n
    for g in range(n):
        col = 1 + g * (3 + m)
        table[:, col], table[:, col + 1], table[:, col + 2] = x[g], weights[g], y[:, g]
        table[:, col + 3:col + 3 + m] = grams[g]
    return table


@model_fact
def beam_tables(model):
    """(body_kind, beam_params, modal integrals, offsets of each body's modal coordinates,
    [Y_k(L), Y_k'(L)], [modal mass / mu, stiffness / EI]) for the kernels (docs/beam.md, "Mode
    shapes" and "The integrals in the frame").  The modal integrals of beam k, moments[k, j] =
    [int Y_j, int x Y_j, int Y_j Y_0, .., int Y_j Y_(m-1)] over [0, L], by Gauss-Legendre
    quadrature exact to rounding for the mode families (kernels/transfers/beam.py::quadrature_size),
    then the geometric stiffness integrals int w(x) Y_j' Y_l' for w = 1, L - x, (L^2 - x^2) / 2
    (D0, D1, D2 of docs/beam.md, "Geometric stiffening"), m columns each.  ends[k, m:m + mt]
    is beam k's twist table (docs/beam.md, "Torsion"; kernels/transfers/beam.py::twist_relations):
    [Psi_j(L), int Psi_j, modal mass / j_p, modal stiffness / G J] per twist mode j, and
    ends[k, m + mt:m + mt + ma] its stretch table ("Stretch"; beam_relations): [U_j(L),
    int U_j, int x U_j, modal mass / mu, modal stiffness / E A, int U_j Y_l (m), int U_j U_l
    (ma)].  With stiffening="exact" (docs/beam.md, "The exact foreshortening"), moments[k, j]
    goes on from column 2 + 4 m with the beam's sections at n Gauss-Legendre points: n, then
    per point [x, weight, Y_j(x), D(x)[j, 0..m-1]], D(x) = int_0^x Y' Y'^T, and the stretch
    table with U_j at those points, from column 5 + m + ma
    (kernels/transfers/beam.py::exact_line_integrals).  The tables but body_kind and the
    offsets have no rows in a model without beams (the kernels read a beam's rows only; a
    million rigid bodies' 0.2 GB)."""
    n = model.n_bodies if (model.body_kind == BEAM).any() else 0
    max_modes = max(1, int(model.beam_params[:, MODES].max()))
    bp = model.beam_params
    max_rows = max(1, int((bp[:, MODES] + bp[:, TORSION_MODES] + bp[:, AXIAL_MODES]).max()))
    exact = (model.body_kind == BEAM) & (bp[:, STIFFENING] == EXACT)
    points = exact_points(max_modes + int(bp[:, AXIAL_MODES].max()))
    moments = np.zeros((n, max_modes, 4 * max_modes + 2
                        + (1 + points * (3 + max_modes) if exact.any() else 0)))
    ends = np.zeros((n, max_rows, 5 + max_modes + int(bp[:, AXIAL_MODES].max())
                     + (points if (exact & (bp[:, AXIAL_MODES] > 0)).any() else 0)))
    factors = np.ones((n, max_modes, 2))
    for k in range(n):      # (none without beams)
        if model.body_kind[k] == BEAM:
            length = model.beam_params[k, LENGTH]
            family, m = int(model.beam_params[k, FAMILY]), int(model.beam_params[k, MODES])
            x, wq = gauss_points(length, quadrature_size(m))
            y = mode_shapes(family, length, m, x)[0]
            moments[k, :m, 0] = y @ wq
            moments[k, :m, 1] = y @ (wq * x)
            gram = (y * wq) @ y.T
            moments[k, :m, 2:2 + m] = 0.5 * (gram + gram.T)
            for i, d in enumerate(foreshortening_integrals(family, length, m)):
                moments[k, :m, 2 + (i + 1) * m:2 + (i + 2) * m] = d
            ma = int(model.beam_params[k, AXIAL_MODES])
            if exact[k]:        # (its sections' points: the table's and the stretch's)
                x_exact = gauss_points(length, exact_points(m + ma))
                table = exact_section_table(family, length, m, *x_exact)
                moments[k, :m, 2 + 4 * m:2 + 4 * m + table.shape[1]] = table
            y, dy, _, mass, stiffness = mode_shapes(family, length, m, [length])
            ends[k, :m, 0], ends[k, :m, 1] = y[:, 0], dy[:, 0]
            factors[k, :m, 0], factors[k, :m, 1] = mass, stiffness
            mt = int(model.beam_params[k, TORSION_MODES])
            if mt:
                xt, wt = gauss_points(length, quadrature_size(mt))
                psi = torsion_shapes(family, length, mt, xt)[0]
                psi_l, _, t_mass, t_stiff = torsion_shapes(family, length, mt, [length])
                ends[k, m:m + mt, :4] = np.column_stack([psi_l[:, 0], psi @ wt, t_mass, t_stiff])
            if ma:
                # the stretch: U_j(L), int U_j, int x U_j, m_j / mu, k_j / E A, then
                # int U_j Y_l (l < m) and int U_j U_l (l < ma) (docs/beam.md, "Stretch"); with
                # stiffening="exact", U_j at the exact table's points
                xa, wa = gauss_points(length, quadrature_size(max(m, ma)))
                u = torsion_shapes(family, length, ma, xa)[0]
                y_a = mode_shapes(family, length, m, xa)[0]
                u_l, _, a_mass, a_stiff = torsion_shapes(family, length, ma, [length])
                r = m + mt
                ends[k, r:r + ma, :5] = np.column_stack([u_l[:, 0], u @ wa, u @ (wa * xa),
                                                         a_mass, a_stiff])
                ends[k, r:r + ma, 5:5 + m] = (u * wa) @ y_a.T
                gram = (u * wa) @ u.T
                ends[k, r:r + ma, 5 + m:5 + m + ma] = 0.5 * (gram + gram.T)
                if exact[k]:
                    xg = x_exact[0]
                    ends[k, r:r + ma, 5 + m + ma:5 + m + ma + len(xg)] = torsion_shapes(
                        family, length, ma, xg)[0]
    mode_off = np.concatenate([[0], np.cumsum(model.n_modes)]).astype(np.int64)
    beam_params = kernel_array(model, "beam_params") if n else np.zeros((0, BEAM_PARAM_SIZE))
    return kernel_array(model, "body_kind"), beam_params, moments, mode_off, ends, factors


def _steps(t_end, dt):
    """(n, h): n = ceil(t_end / dt) equal steps of h = t_end / n, so that the last one lands on
    t_end; h = dt where dt divides t_end (to 1e-9 of a step)."""
    n = max(1, int(np.ceil(t_end / dt - 1e-9)))
    return n, (dt if abs(n * dt - t_end) <= 1e-9 * dt else t_end / n)


def _consistent_start(model, mode, method, fused, params, settings, state, sweep, monitor, dt,
                      loops=None, t=0.0, extra_loads=None,
                      extra_joint_forces=None, in_skeleton=False):
    """The accelerations of the state at time t (a run's start: t = 0; docs/solver.md,
    "Consistent start") into state: by the fused loop's own sweep (fused: its (runner, loop)) or
    kernels/stepping/step.py::initial_accelerations, with the closing joints (loops: loop_tables)
    held at acceleration level; in_skeleton: as one pass of the general loop's skeleton (a run on
    it: it then compiles no start of its own), else the start alone (statics, linear models,
    forward dynamics, the energy-momentum scheme: initial_accelerations' twin, with entry
    points).  extra_loads: (force, torque), (n, 3) each, world,
    added to the applied loads (at the mass centres; dynamics.linearize's inputs);
    extra_joint_forces: (n, 2) generalized forces added to the joint coordinates' (where
    additive_joint_force says they add)."""
    loops = loop_tables(model) if loops is None else loops
    n = model.n_bodies
    g_acc, g_rot, g_w, g_wd, g_pos, g_vel = _ground(model, [t])
    force, torque, line_load = _loads(model, [t])
    if extra_loads is not None:
        force[0] += extra_loads[0]
        torque[0] += extra_loads[1]
    joint_input = _joint_inputs(model, [t], state, dt)
    if extra_joint_forces is not None:      # (n, 2): onto the drives' known forces
        joint_input[0, :, :, 0] += extra_joint_forces
    try:
        if fused:       # the fused loop's own sweep (compiles nothing else)
            status = _fused_start(*fused, start_pass(
                params, settings, state, sweep, monitor,
                (g_acc, g_rot, g_w, g_wd, g_pos, g_vel), (force, torque, line_load),
                joint_input, len(loops.kind)))
        else:
            set_ground(loops, g_pos[0], g_vel[0], g_acc[0], g_rot[0], g_w[0], g_wd[0])
            if has_closure_drives(model):   # a driven closing coordinate's q''(0), a
                loops.target[:, :] = closure_targets(model, [t], loops)[0]  # spring's rest
                loops.step_coef[:] = 0.0        # the springs' forces explicit

            if in_skeleton:     # one pass of the general loop's skeleton (Settings.start),
                # on a throwaway scratch: the run that follows compiles nothing else for it
                loop = kstep.general_loop(n, len(state.eta), settings.h, settings.coef,
                                          _station_histories(model, state, False), loops,
                                          compiled_forces(model))
                run = start_pass(params, settings, state, sweep, monitor,
                                 (g_acc, g_rot, g_w, g_wd, g_pos, g_vel),
                                 (force, torque, line_load), joint_input, len(loops.kind))

                def start():
                    info = np.zeros(5, dtype=np.int64)
                    run_steps(loop, run, info)
                    return _start_status(info)
            else:               # the start alone: its copy's twin, with entry points
                start_alone = python_twin(kstep.initial_accelerations)

                def start():
                    return start_alone(
                        params, settings, state, sweep, (g_acc[0], g_rot[0], g_w[0], g_wd[0]),
                        force[0], torque[0], line_load[0], joint_input[0], loops,
                        compiled_forces(model))
            status = start()
            forces = closure_forces(model, loops)
            if forces and status == 0:  # a closing JointForce's f(0, q, q'): the start's
                for r, law, who in forces:  # force rows leave q, q' in loops.g, gd
                    loops.target[r, 2] = _drive_number(law(t, loops.g[r], loops.gd[r]), who, t)
                status = start()
            for r in np.nonzero(loops.coordinate >= 0)[0]:   # the drives' rates at t = 0
                loops.wrench[loops.owner[r], 8 + loops.coordinate[r]] = (
                    loops.target[r, 1] if loops.law[r, 0] == MOTION else loops.gd[r])
    except np.linalg.LinAlgError as err:
        raise DivergenceError(0, t, f"consistent start: a matrix of the sweep is singular "
                              f"or not finite ({err})"
                              + (f"; {_DIRECT_HINT}" if method == "direct" else "")) from None
    if status == LOST_ACCURACY:
        raise DivergenceError(0, t, "consistent start: the direct sweep lost its accuracy; "
                              + _DIRECT_HINT)
    if status == _NOT_FINITE_START:
        raise DivergenceError(0, t, "consistent start: the accelerations are NaN or infinite "
                              "(check the model's masses, inertias and initial state)")
    if status < 0:
        raise ValueError(_unsupported_cause(model, -status, "the consistent start"))
    if status != 0:
        raise DivergenceError(0, t, _singular_cause(model, mode, status, "consistent start"))
    for k in range(n):
        state.omega_dot[k] = g_wd[0] if model.ground_locked[k] else state.z[2 * k + 1, 3:6]
        if model.hinge_kind[k] == ELASTIC:
            st = 2 * model.parent[k] + 2            # the inboard station (0: the ground)
            state.defl_acc[k] = state.z[2 * k + 1, 0:3] - state.z[st, 0:3]
    state.pseudo[:] = state.omega_dot
    state.eta_p[:] = state.eta_acc
    state.defl_pseudo[:] = state.defl_acc


def start_pass(params, settings, state, sweep, monitor, ground, loads, joint_input,
               n_closures):
    """The Run of one pass of a loop's consistent start at one time (_fused_start, the general
    loop's in _consistent_start; the high-order scheme's stages,
    kernels/stepping/runge_kutta.py): ground = _ground's six (1, ...) arrays, loads = _loads'
    three, joint_input = _joint_inputs'; no Newton iteration, no record."""
    g_acc, g_rot, g_w, g_wd, g_pos, g_vel = ground
    force, torque, line_load = loads
    return Run(params, settings._replace(newton_max=0, start=True), state, sweep,
               Inputs(g_acc=g_acc, g_rot=np.concatenate([g_rot, g_rot]), g_w=g_w, g_wd=g_wd,
                      g_pos=g_pos, g_vel=g_vel, force=force, torque=torque,
                      line_load=line_load, joint_input=joint_input,
                      closure_target=np.zeros((1, n_closures, 3))),
               _record(0, len(state.rot), len(state.eta)), monitor)


def _record(n_rec_max, n, n_eta, v_st=False, v_c=False, n_closures=0):
    """Where a chunk's samples are written (kernels/stepping/loop.py::Record): n_rec_max of each;
    the paper scheme's station velocities, the mass-centre velocities and the closing joints'
    wrenches only where recorded."""
    return Record(rot=np.empty((n_rec_max, n, 3, 3)), omega=np.empty((n_rec_max, n, 3)),
                  omega_dot=np.empty((n_rec_max, n, 3)), z=np.empty((n_rec_max, 2 * n + 1, 12)),
                  defl=np.zeros((n_rec_max, n, 3)), defl_rate=np.zeros((n_rec_max, n, 3)),
                  eta=np.zeros((n_rec_max, n_eta)), eta_d=np.zeros((n_rec_max, n_eta)),
                  v_st=np.zeros((n_rec_max if v_st else 1, n + 1, 3)),
                  v_c=np.zeros((n_rec_max if v_c else 1, n, 3)),
                  jq=np.zeros((n_rec_max, n, 2)), jqd=np.zeros((n_rec_max, n, 2)),
                  jtau=np.zeros((n_rec_max, n, 2)),
                  closure_wrench=np.zeros((n_rec_max if n_closures else 1, n_closures, 10)))


_NOT_FINITE_START = -(1 << 30)      # a start pass's status for accelerations not finite


def _fused_start(runner, loop, run):
    """The consistent start of the fused loops: their own iterate, once, at acceleration level
    (kernels/stepping/ball_chain.py::start_loop; run.settings.start).  Leaves the stations' states
    in state.z (angular accelerations in the phi slots) and the beams' modal accelerations in
    state.eta_acc, as kernels/stepping/step.py::initial_accelerations does; returns its status
    codes."""
    info = np.zeros(5, dtype=np.int64)
    if isinstance(loop, weld_chain.WeldLoop):
        runner(weld_chain.start_loop(loop, run), run, info)
    else:
        runner(ball_chain.start_loop(loop, run.state, run.sweep), run, info)
    run.state.eta_acc[:] = loop.per_mode[4]
    return _start_status(info)


def _start_status(info):
    """The status code of a start pass (_fused_start's, the general loop's in _consistent_start)
    from its loop's info (kernels/stepping/loop.py::report): 0 done; SINGULAR's detail (the
    singular element, or the general loop's start's own code: kernels/stepping/step.py::_iterate
    under Settings.start); minus UNSUPPORTED's element (elements' codes are j + 1, never 0:
    _singular_cause); _NOT_FINITE_START for any other status, which never reads as done."""
    if info[0] == OK:
        return 0
    if info[0] == SINGULAR:
        return int(info[2])
    if info[0] == UNSUPPORTED:
        return -int(info[2])
    return _NOT_FINITE_START


def _check_positive(name, value, where="simulate"):
    """value as a float, finite and > 0, or a ValueError naming `where` and the argument."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{where}: {name} must be a number, got {value!r}") from None
    if not np.isfinite(x) or x <= 0.0:
        raise ValueError(f"{where}: {name} must be finite and > 0, got {value!r}")
    return x


def _check_count(name, value, minimum, where="simulate"):
    """value as an int >= minimum, or a ValueError naming `where` and the argument (a bool,
    a string, NaN, inf or a fraction is refused, not converted)."""
    if (isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer,
                                                                      np.floating))
            or not np.isfinite(value) or int(value) != value or value < minimum):
        raise ValueError(f"{where}: {name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def _mode(model, method, full_state):
    if method not in SWEEPS:
        raise ValueError(f"simulate: method must be one of {tuple(SWEEPS)}, got {method!r}")
    reduced = model.all_ball and not full_state
    if full_tree(model, full_state):    # (check_supported has refused the rest)
        return kstep.RICCATI_JOINTS
    if not model.is_chain:
        return kstep.RICCATI_TREE
    if method == "direct":
        return kstep.DIRECT_REDUCED if reduced else kstep.DIRECT_FULL
    return kstep.RICCATI_REDUCED if reduced else kstep.RICCATI_FULL


def _loads(model, times):
    """(steps, n, 3) each: the applied forces, torques and beams' distributed loads at the given
    times."""
    n = model.n_bodies
    out = np.zeros((3, len(times), n, 3))
    for k in range(n):
        for which, fn in enumerate((model.forces[k], model.torques[k], model.line_loads[k])):
            if fn is not None:
                i = 0
                try:
                    for i, t in enumerate(times):
                        out[which, i, k] = fn(t)
                except Exception as err:
                    raise UserFunctionError(times[i], f"the {_LOAD_NAMES[which]} of body "
                                            f"'{model.body_names[k]}' failed at t = "
                                            f"{times[i]:.6g} s ({type(err).__name__}: {err}); "
                                            f"it must return 3 finite numbers") from None
                bad = ~np.isfinite(out[which, :, k]).all(axis=1)
                if bad.any():
                    i = int(np.argmax(bad))
                    raise UserFunctionError(times[i], f"the {_LOAD_NAMES[which]} of body "
                                            f"'{model.body_names[k]}' returned "
                                            f"{out[which, i, k].tolist()} at t = "
                                            f"{times[i]:.6g} s (not finite)")
    return out[0], out[1], out[2]


_LOAD_NAMES = ("force (N)", "torque (N m)", "distributed load (N/m)")


class UserFunctionError(ValueError):
    """A user's function (a load, a drive, the ground's motion) failed or returned a value
    that is not finite during a run (simulate turns it into DivergenceError with the step)."""

    def __init__(self, t, message):
        super().__init__(message)
        self.t = float(t)


def _ground(model, times):
    """Ground acceleration, rotation, angular velocity and acceleration, and the ground
    point's position and velocity, at the given times."""
    m = len(times)
    acc, w, wd = np.zeros((m, 3)), np.zeros((m, 3)), np.zeros((m, 3))
    pos, vel = np.zeros((m, 3)), np.zeros((m, 3))
    rot = np.empty((m, 3, 3))
    if model.ground_motion is None:             # at rest: one frame for every time
        rot[:] = model.ground_rotation
        pos[:] = model.ground_position
        return acc, rot, w, wd, pos, vel
    i = 0
    try:
        for i, t in enumerate(times):
            pos[i], vel[i], acc[i], rot[i], w[i], wd[i] = model.ground_state(t)
    except Exception as err:
        raise UserFunctionError(times[i], f"the ground's motion failed at t = {times[i]:.6g} s "
                                f"({type(err).__name__}: {err})") from None
    bad = ~(np.isfinite(acc).all(axis=1) & np.isfinite(rot).all(axis=(1, 2))
            & np.isfinite(w).all(axis=1) & np.isfinite(wd).all(axis=1)
            & np.isfinite(pos).all(axis=1) & np.isfinite(vel).all(axis=1))
    if bad.any():
        i = int(np.argmax(bad))
        raise UserFunctionError(times[i], f"the ground's motion is not finite at t = "
                                f"{times[i]:.6g} s")
    return acc, rot, w, wd, pos, vel


def simulate(model: Model, t_end, dt=None, *, rtol=None, atol=0.0, method="riccati",
             scheme="newmark", rho_inf=1.0, newton_iterations=None, newton_tol=1e-12,
             record_every=None, record_dt=None, t_eval=None, full_state=False, richardson=False,
             progress=None, max_step_error=MAX_STEP_ERROR, max_energy_error=None,
             hold_energy=None, resume=None, stream=None, threads=None) -> Result:
    """Integrate a model from t = 0 to t_end by DT-TMM.

    Parameters
    ----------
    model : Model
        The frozen system (``dttmm.System(...).build()`` or ``dttmm.build_chain``).
    t_end : float
        End time, s (> 0).
    dt : float, optional
        The step, s (> 0). The run takes n = ceil(t_end / dt) equal steps of t_end / n (dt
        itself where it divides t_end), so the last step lands on t_end; ``info["dt"]`` is the
        step taken. With rtol: the first step (default t_end / 1000).
    rtol, atol : float, optional
        Adaptive steps (Newmark scheme): the step is chosen from the local error estimate so
        that the error accumulated over the run stays near atol + rtol (rad for rotations, m
        for displacements; rtol is relative to a motion of order one radian, atol an absolute
        floor, default 0). Segments of up to 256 equal steps run compiled; one whose estimate
        per unit time exceeds (atol + rtol) / t_end is taken again with a smaller step
        (growth at most 1.5x, shrink at most 5x per segment). ``n_steps`` counts the accepted
        steps; ``info`` reports ``steps_rejected`` (and ``segments_rejected``), ``dt_min`` and
        ``dt_max`` (docs/solver.md, "Adaptive steps").
    method : {"riccati", "direct"}
        "riccati" (default; stable for long and stiff chains) or "direct" (multiplies the
        transfer matrices out, as the paper does; chains only; loses accuracy on long or stiff
        chains).
    scheme : {"newmark", "energy_momentum", "paper", "dop853"}
        The table of schemes is ``dttmm.methods.SCHEMES``.
        "newmark" (default): generalized-alpha, every element and topology.
        "energy_momentum": rigid chains with ball and fixed hinges on a fixed ground; a
        second-order step that conserves the total energy and the angular momentum to
        newton_tol (docs/solver.md). "paper": the paper's scheme, for comparison only (every
        station point with its own position history; it develops a growing step-to-step
        oscillation in long runs; docs/solver.md, "The paper's scheme"). "dop853": the
        explicit Runge-Kutta method of order 8 on the rotation group, compiled with the
        acceleration sweep (docs/integrators.md): chains and trees of rigid bodies and beams
        on ball joints, a fixed ground and gravity; with rtol its steps are chosen by its
        embedded estimate (the local error of each coordinate within atol + rtol |y|, of each
        rotation within atol + rtol rad; atol at least 1e-6 rtol) and its samples come from
        its dense output; with dt alone, fixed steps of dt. Explicit: stiff beams hold its
        steps below their stability limit.
    rho_inf : float
        Generalized-alpha spectral radius at infinite frequency, in [0, 1]; 1 (default) is the
        trapezoidal Newmark rule, smaller values damp high frequencies. Newmark scheme only.
    newton_iterations : int, optional
        Extra linearizations about the latest solution per step, stopping once the update is
        below newton_tol (rad, or scaled modal units). Default: 0 for Newmark (one
        linearization about the predictor is second-order accurate); 8 with joints with
        coordinates or a weld on a beam's end in a tree (their linearization is exact only to
        O(dt) terms; docs/joints.md); 20 for the energy-momentum scheme. Steps that use them
        all without reaching newton_tol are counted in ``info["newton_unconverged_steps"]``.
    newton_tol : float
        See newton_iterations (rad; default 1e-12).
    record_every : int, optional
        Record every k-th step.
    record_dt : float, optional
        Record every record_dt seconds (rounded to a whole number of steps).
    t_eval : array_like, optional
        Record at these times, s (increasing, on the step grid: multiples of dt; an adaptive
        run lands its steps on them). Give at most one of record_every, record_dt and t_eval.
        Default: every step of a run of up to 1000 steps, else every ceil(steps / 1000)-th step
        (at most ~1000 samples, and no more than about 256 MB of them: fewer for models of
        more than ~270 bodies, the first and last state of a million; adaptive: the first
        segment end after each t_end / 1000). The first and the final state are always
        recorded. Derived quantities (positions,
        energies) are computed when first read (``Result``).
    full_state : bool
        Use the 13-entry state even where the reduced [a; q] form applies (a tree: the
        full-state tree sweep, docs/assembly.md "Trees with joints").
    richardson : bool or int
        True: run at dt and dt/2 and return their Richardson extrapolation
        (4 y_dt/2 - y_dt) / 3 at the recorded times (Newmark only): fourth-order accurate where
        dt resolves the motion, for 3x the steps. An int L from 2 to 4: L runs at dt, dt/2, ...
        dt/2^(L-1), combined by Romberg's rule on the even powers of the step (orders 4, 6, 8
        with Newton iterations to newton_tol; each run is the trapezoidal rule, stable at any
        step, so the combination stays bounded where dt is far above a stiff beam's periods).
        ``info["richardson_correction_m"]`` is the largest change it made to a recorded point
        position; wall_time and n_steps count every run (docs/solver.md, "Richardson
        extrapolation").
    progress : bool, optional
        A tqdm progress bar on stderr once the run is expected to take more than about two
        seconds: None (default) when stderr is a terminal, True always, False never.
    max_step_error : float, optional
        Stop at the first step whose local error estimate (Zienkiewicz-Xie, |beta - 1/6| h^2
        max |p_{n+1} - p_n| over every rotation, modal and joint coordinate and deflection; rad
        or m) exceeds it; default 0.05; None never stops. ``info["step_error_max"]`` is the
        run's largest estimate (docs/solver.md, "Runs that cannot go wrong").
    max_energy_error : float, optional
        Stop when the energy balance breaks: |E - E(0) - W| above this fraction of the largest
        kinetic energy so far, E the total energy (the drives' springs left out), W the work of
        the applied loads, the joint drives, the elastic hinges' and beams' dampers and a
        moving ground since t = 0 (checked at the end of every chunk of up to 1000 steps;
        fixed steps). ``info["energy_balance_error"]`` is the run's largest. Default None: not
        checked (it derives every step's velocities; docs/solver.md, "Energy balance").
    hold_energy : bool, optional
        Closed loops of rigid bodies on which nothing works (gravity, no loads, drives,
        dampers or moving ground; rho_inf = 1): after each step's projection onto the loops,
        every rate is scaled so that the total energy is its value at the start (the least
        change of the rates, in the kinetic metric, that holds it; the positions keep the
        step's own second-order error; docs/loops.md, "The energy held"). None (default): held
        wherever it applies; False: never; True: held, or a ValueError saying why it cannot
        be. ``info["energy_held"]`` says which, ``info["energy_correction"]`` the largest
        relative change of the rates it made in one step.
    resume : Checkpoint, optional
        Continue the run that wrote it (``result.checkpoint``, or ``Checkpoint.load``) from
        its last step to t_end, with the same model, dt and options: the continued run takes
        the same steps on the same numbers, so the two halves equal the whole run bit for bit.
        Its first sample is the checkpoint's state.
    stream : str or path, optional
        A directory to write the samples to as they are recorded, instead of keeping them in
        memory (for long, densely recorded runs): one raw file per recorded quantity and an
        index, rewritten after each chunk. The Result's stored arrays are then read-only
        memory maps of those files; ``dttmm.load_stream(model, path)`` reads them again, also
        those of a run that stopped or was killed (the samples written so far). A stream
        already in the directory is replaced.
    threads : int, optional
        BLAS threads the run may use (the loops' small LAPACK calls). Default: 1, or the
        environment variable DTTMM_BLAS_THREADS; the process's own limit is restored after the
        run (dttmm/threads.py; docs/solver.md, "Threads").

    Returns
    -------
    Result
        The recorded samples (``dttmm.Result``: times in s, positions in m, rotations,
        angular velocities in rad/s, interior forces in N and moments in N m at every body's
        input, energies in J, joint coordinates and drive forces), ``wall_time`` (s, the whole
        call), ``info`` (mode, loop, dt, Newton and error statistics) and ``checkpoint`` (the
        state after the last step, for ``resume``).

    Raises
    ------
    ValueError
        Before the run: a bad argument, or what the solver does not run for this model
        (naming the element).
    DivergenceError
        A run that cannot go on: a step's error estimate above max_step_error, an
        energy-momentum step that does not converge, a beam deflected beyond its length, a
        singular transfer, or NaN. Its message names the step, the time and the cause;
        ``err.partial`` holds the Result recorded before it.
    """
    wall0 = time.perf_counter()
    with blas_threads(threads):
        return _simulate(wall0, threads, model, t_end, dt, rtol=rtol, atol=atol, method=method,
                         scheme=scheme, rho_inf=rho_inf, newton_iterations=newton_iterations,
                         newton_tol=newton_tol, record_every=record_every,
                         record_dt=record_dt, t_eval=t_eval, full_state=full_state,
                         richardson=richardson, progress=progress,
                         max_step_error=max_step_error, max_energy_error=max_energy_error,
                         hold_energy=hold_energy, resume=resume, stream=stream)


def _simulate(wall0, threads, model, t_end, dt, **options):
    """simulate's run, inside its BLAS thread limit (Richardson's runs take the same)."""
    opts = run_options(model, t_end, dt, **options)
    if opts.richardson > 1:
        return drivers.richardson(opts, functools.partial(simulate, threads=threads))
    check_supported(opts.model, opts.scheme.name, opts.method, opts.full_state)
    with prepared_run(opts) as plan:
        run = drivers.Stepping(plan, opts, wall0)
        result = (drivers.runge_kutta if opts.scheme.loop == "runge_kutta"
                  else drivers.adaptive if opts.adaptive else drivers.fixed_steps)(run)
    warn_bent(model, result, UnresolvedMotionWarning)
    return result._timed(time.perf_counter() - wall0)

def load_stream(model, path):
    """The Result of the samples a run streamed to a directory.

    Parameters
    ----------
    model : Model
        The model that run simulated (the positions and energies are derived from it).
    path : str or path
        The directory given as ``simulate(..., stream=path)``.

    Returns
    -------
    Result
        The samples written (all of them, or those before the run stopped or was killed), its
        stored arrays read-only memory maps of the stream's files; ``n_steps`` is the step of
        the last sample, ``info`` the run's options.

    Raises
    ------
    ValueError
        No stream in the directory, a damaged one, or one of another model (its number of
        bodies, or its fingerprint: recording.model_fingerprint).
    """
    if not isinstance(model, Model):
        raise ValueError(f"load_stream: model must be the Model the run simulated, got "
                         f"{type(model).__name__}")
    try:
        recording = Recording.from_stream(path)
        meta = recording.stream.meta
        arrays = recording.arrays()
    except ValueError as err:
        if str(err).startswith("load_stream"):
            raise
        raise ValueError(f"load_stream: the stream in {str(path)!r} is damaged ({err})") from None
    except (OSError, KeyError, TypeError) as err:
        raise ValueError(f"load_stream: the stream in {str(path)!r} is damaged or not a "
                         f"stream's ({type(err).__name__}: {err})") from None
    if len(recording.steps) and arrays["rot"].shape[1] != model.n_bodies:
        raise ValueError(f"load_stream: the stream in {str(path)!r} holds "
                         f"{arrays['rot'].shape[1]} bodies; the model has {model.n_bodies}")
    written = meta.get("info", {}).get("model_fingerprint")
    if written is not None and written != model_fingerprint(model):
        raise ValueError(f"load_stream: the stream in {str(path)!r} was written by a run of "
                         f"another model (its fingerprint differs): load it with that model")
    return _result(model, recording, meta["dt"], 0.0, recording.last_step, dict(meta["info"]))


def _set_step(loop, h, coef):
    """A new step in the loop variant's step-dependent constants (an adaptive run's segment;
    the skeleton's pieces take h itself from Settings): the fused loops' (c1, c3, 1/c1, c3/c1)
    and the general loop's ground d(w')/d(phi) = c1 I (kernels/stepping/step.py::general_loop)."""
    if isinstance(loop, kstep.GeneralLoop):
        loop.ground[4][...] = kstep._coefficients_py(h, coef)[0] * np.eye(3)
    elif hasattr(loop, "coefficients"):
        loop.coefficients[:] = kstep.fused_coefficients(h, coef)


CHUNK = 1000        # steps per call of the compiled loop (their inputs are prepared per chunk)
CHUNK_BYTES = 2 ** 27       # at most this much of a chunk's per-step inputs and records ...
CHUNK_STEP_BYTES = 600      # ... at about this much per body and step (loads, joint inputs,
#                             the record's rotation, rates and stations)
MAX_SAMPLES = 1000  # simulate's default: every step up to this many, then every k-th step
RECORD_BYTES = 2 ** 28      # ... and no more than this much of samples by default ...
RECORD_SAMPLE_BYTES = 1000  # ... at about this much per body and sample (the record and the
#                             Result's arrays derived from it)


def _sampling(n_steps, h, record_every, record_dt, t_eval, start=0, n_bodies=1):
    """The steps a run records (besides its first and its last state): every k-th step (an
    int k), or the given steps (an increasing array).  Default: every step of a run of up to
    MAX_SAMPLES steps, else every ceil(n_steps / MAX_SAMPLES)-th; and no more samples than
    RECORD_BYTES hold at RECORD_SAMPLE_BYTES per body (a million bodies: the first and the
    last state; record_every, record_dt or t_eval ask for more)."""
    given = [name for name, v in (("record_every", record_every), ("record_dt", record_dt),
                                  ("t_eval", t_eval)) if v is not None]
    if len(given) > 1:
        raise ValueError(f"simulate: give one of record_every, record_dt and t_eval, got "
                         f"{' and '.join(given)}")
    if record_every is not None:
        return _check_count("record_every", record_every, 1)
    if record_dt is not None:
        record_dt = _check_positive("record_dt", record_dt)
        return max(1, int(round(record_dt / h)))
    if t_eval is not None:
        times = adaptive_steps.checked_times(t_eval)
        steps = np.round(times / h)
        off = np.abs(steps * h - times) > 1e-6 * h
        if off.any():
            i = int(np.argmax(off))
            raise ValueError(f"simulate: t_eval[{i}] = {times[i]:g} s is not on the step grid "
                             f"(multiples of dt = {h:g} s): the run records the state after "
                             f"whole steps; take a dt that divides the times, or record_dt")
        if np.any(np.diff(steps) <= 0) or steps[0] < start or steps[-1] > n_steps:
            raise ValueError(f"simulate: t_eval must increase within [{start * h:g}, "
                             f"{n_steps * h:g}] s")
        return steps[steps > start].astype(np.int64)
    samples = max(1, min(MAX_SAMPLES, RECORD_BYTES // (RECORD_SAMPLE_BYTES * n_bodies)))
    return max(1, -(-(n_steps - start) // samples))


def _sample_count(sampling, start, n_steps):
    """The samples a fixed-step run from step `start` to n_steps records (_sampling's steps
    after start, its first and its final state)."""
    if isinstance(sampling, int):
        inner, last = n_steps // sampling - start // sampling, n_steps % sampling == 0
    else:
        later = sampling[sampling > start]
        inner, last = len(later), bool(len(later)) and later[-1] == n_steps
    return 1 + inner + (0 if last else 1)


def _fastest_rate(omega):
    """(the largest |w| over the samples omega (m, n, 3), rad/s; its body): what
    MAX_TURN_PER_STEP judges (sampled: a spike between records can pass unseen)."""
    if omega.shape[1] == 0:
        return (0.0, 0)
    if omega.size <= 96:                # (a few bodies' few samples: faster without numpy)
        squares = [x * x + y * y + z * z for x, y, z in omega.reshape(-1, 3).tolist()]
        at = squares.index(max(squares))
        return (math.sqrt(squares[at]), at % omega.shape[1])
    squares = np.einsum("mki,mki->mk", omega, omega)
    at = int(squares.argmax())          # (one reduction over samples and bodies)
    return (float(np.sqrt(squares.flat[at])), at % omega.shape[1])


def _next_chunk(done, n_steps, sampling, size):
    """(m, every): the next chunk's steps and its record stride (the compiled loop records after
    every every-th step of the chunk; every > m: none), so that the run records the steps
    `sampling` asks for (_sampling) and a chunk holds at most `size` steps."""
    if isinstance(sampling, int):
        k = sampling
        if k <= size and done % k == 0:
            return min(k * (size // k), n_steps - done), k
        target = done + k - done % k
    else:
        later = sampling[sampling > done]
        target = int(later[0]) if len(later) else n_steps + 1
    m = min(size, target - done, n_steps - done)
    return m, (m if done + m == target else m + 1)


FUSED_BALL_CHAIN = True     # False: every chain through the general loop (tests compare the two)
_MODE_NAMES = ["riccati-full", "riccati-reduced", "direct-reduced", "direct-full", "riccati-tree",
               "riccati-joints"]


@model_fact
def check_supported(model, scheme, method="riccati", full_state=False):
    """Refuse, before a run, what the solver does not implement for this model: an element
    kind whose declaration (elements/kinds.py) does not list the scheme; the energy-momentum
    and paper's schemes need a fixed ground; trees and joints with coordinates run (so far) with
    the Newmark scheme and the Riccati sweep (_check_full_tree, _check_tree); closed loops of
    rigid bodies and beams (closures.check_runs_in_sweeps)."""
    check_runs_in_sweeps(model, "simulate", moving_ground=True)
    if scheme == "dop853":
        _check_runge_kutta(model, method, full_state)
    if has_loops(model) and (scheme != "newmark" or method != "riccati"):
        raise ValueError(f"simulate: closed loops run with scheme='newmark' and "
                         f"method='riccati' so far, got scheme={scheme!r}, method={method!r}")
    if full_tree(model, full_state):
        _check_full_tree(model, scheme, method)
    elif not model.is_chain and scheme != "dop853":
        _check_tree(model, scheme, method)
    where = f"simulate(scheme='{scheme}')"
    for k in range(model.n_bodies):
        for role, kinds, code, name in (("body", BODY_KIND, model.body_kind[k],
                                         model.body_names[k]),
                                        ("hinge", JOINT_KIND, model.hinge_kind[k],
                                         model.hinge_names[k])):
            kind = kinds.get(int(code))
            if kind is None:
                raise ValueError(f"simulate: {role} '{name}' has kind code {int(code)}, which no "
                                 f"element kind declares (elements/kinds.py)")
            if not kind.schemes:
                raise ValueError(f"simulate: {role} '{name}' is {kind.what} ({kind.name}), "
                                 f"which DT-TMM does not run yet; the Newton-Euler reference "
                                 f"does (dttmm.reference.simulate_reference)")
            if scheme not in kind.schemes:
                covered = [kd.name for kd in kinds.values() if scheme in kd.schemes]
                raise ValueError(f"{where}: {role} '{name}' is {kind.what} ({kind.name}); the "
                                 f"scheme covers {', '.join(covered)} only (use "
                                 f"scheme='newmark')")
    if scheme != "newmark" and model.ground_motion is not None:
        raise ValueError(f"{where}: the ground has a prescribed motion; the scheme needs a "
                         f"fixed ground (use scheme='newmark')")


def _check_runge_kutta(model, method, full_state):
    """The high-order scheme (kernels/stepping/runge_kutta.py) integrates the fused loops' sweep:
    chains and trees of rigid bodies and beams on ball joints (bending modes only), on a fixed
    ground with gravity alone (its compiled stages evaluate no function of the user's)."""
    where = "simulate(scheme='dop853')"
    joint = next((k for k in range(model.n_bodies) if model.hinge_kind[k] != BALL), None)
    locked = next((k for k in range(model.n_bodies) if model.ground_locked[k]), None)
    why = ("the model has closed loops" if has_loops(model) or model.tip_pinned
           else f"hinge '{model.hinge_names[joint]}' is "
                f"{JOINT_KIND[int(model.hinge_kind[joint])].what} (ball joints only)"
           if joint is not None
           else "method='direct' (its stages take the Riccati sweep)" if method != "riccati"
           else "full_state=True (its stages take the reduced sweep)" if full_state
           else "the ground has a prescribed motion" if model.ground_motion is not None
           else "it has applied loads (functions of time, which its compiled stages cannot "
                "call)" if model.has_applied_loads
           else f"body '{model.body_names[locked]}' is locked to the ground"
           if locked is not None
           else "a beam has twist or stretch modes, an end torque or loads in body axes "
                "(its columns are differenced: the general loop)" if model.needs_general_loop
           else None)
    if why is not None:
        raise ValueError(f"{where}: {why}; the scheme runs chains and trees of rigid bodies "
                         f"and beams on ball joints, a fixed ground and gravity; use "
                         f"scheme='newmark' (rtol= for adaptive steps)")


def _check_full_tree(model, scheme, method):
    """The full-state tree sweep (full_tree) runs every joint kind, with the Newmark scheme and
    the Riccati sweep only."""
    k = next((k for k in range(model.n_bodies)
              if model.hinge_kind[k] in WITH_COORDINATES), None)
    if k is not None:
        what = (f"hinge '{model.hinge_names[k]}' is "
                f"{JOINT_KIND[int(model.hinge_kind[k])].what}: joints with coordinates")
    else:
        what = f"{_first_branch(model)}: a tree"
    if method == "direct":
        raise ValueError(f"simulate: {what} run in the Riccati sweep from the leaves to the root; "
                         f"method='direct' multiplies the transfer matrices out along a chain "
                         f"and does not extend to them; use method='riccati'")
    if scheme != "newmark":
        raise ValueError(f"simulate(scheme='{scheme}'): {what} run with the Newmark scheme; the "
                         f"scheme runs chains; use scheme='newmark'")
    if model.tip_pinned:
        raise ValueError(f"simulate: {what}: a pinned tip (a closed loop) does not run with "
                         f"them yet")


def _first_branch(model):
    """The first body off the chain, said as where it hangs (for the messages)."""
    k = next((k for k in range(model.n_bodies)
              if model.parent[k] != k - 1 or model.attachment[k] != 0), 0)
    p = model.parent[k]
    return (f"body '{model.body_names[k]}' hangs from "
            + ("the ground" if p < 0 else f"body '{model.body_names[p]}'"))


def _check_tree(model, scheme, method):
    """Ball-joint trees run the reduced tree sweep (kernels/stepping/tree.py); full_state=True and
    fixed or elastic hinges send a tree to the full-state sweep (_check_full_tree)."""
    branch = _first_branch(model)
    if method == "direct":
        raise ValueError(f"simulate: method='direct' multiplies the transfer matrices out along "
                         f"a chain and does not extend to the branches of a tree ({branch}); use "
                         f"method='riccati'")
    if scheme != "newmark":
        raise ValueError(f"simulate(scheme='{scheme}'): the scheme runs chains; the model is a "
                         f"tree ({branch}); use scheme='newmark'")


def _station_histories(model, state, independent):
    """The paper's scheme's state (kernels/stepping/step.py, advance): velocity, acceleration and
    pseudo-acceleration of the ground point and every body's output point ((n + 1, 3) each), and
    of every rigid body's mass centre ((n, 3)), at t = 0 from the consistent start (state.z
    holds the stations' accelerations and state.omega_dot the angular ones).  Empty unless
    independent."""
    n = model.n_bodies
    if not independent:
        empty = np.zeros((1, 3))
        return (False, empty, empty, empty, empty, empty, empty)
    st_v, st_a = np.zeros((n + 1, 3)), np.zeros((n + 1, 3))
    c_v, c_a = np.zeros((n, 3)), np.zeros((n, 3))
    mode_off = np.concatenate([[0], np.cumsum(model.n_modes)])
    for k in range(n):
        w, wd = state.omega[k], state.omega_dot[k]
        if model.body_kind[k] == BEAM:
            j0, j1 = mode_off[k], mode_off[k + 1]
            _, rho_dot = beam_output_offset(model.beam_params[k], state.rot[k], w, state.eta[j0:j1],
                                            state.eta_d[j0:j1])
        else:
            rho_c = state.rot[k] @ model.body_params[k, TO_MASS_CENTER]
            c_v[k] = st_v[k] + cross(w, rho_c)
            c_a[k] = (state.z[2 * k + 1, 0:3] + cross(wd, rho_c)
                      + cross(w, cross(w, rho_c)))
            rho_dot = cross(w, state.rot[k] @ model.body_params[k, TO_OUTPUT])
        st_v[k + 1] = st_v[k] + rho_dot
        st_a[k + 1] = state.z[2 * k + 2, 0:3]
    return (True, st_v, st_a, st_a.copy(), c_v, c_a, c_a.copy())


def _initial_mass_center_velocities(model, rot, omega):
    """(n, 3) mass-centre velocities from the initial rotations and angular velocities."""
    p = model.body_params
    v_in = model.ground_state(0.0)[1].copy()
    v_c = np.empty((model.n_bodies, 3))
    for k in range(model.n_bodies):
        v_c[k] = v_in + cross(omega[k], rot[k] @ p[k, TO_MASS_CENTER])
        v_in = v_in + cross(omega[k], rot[k] @ p[k, TO_OUTPUT])
    return v_c


def kernel_model(model):
    """The model the kernels integrate, and the kernel index of each of the model's bodies
    (results are mapped back, recording.Recording).  Three kinds of massless rigid body,
    welded to their parent, stand in where a sweep needs a frame or a point that the model
    gives implicitly (docs/topology.md, "What the kernels integrate"):
    - an end section, welded to a beam's or strain rod's end with zero length, carries the
      section's rotation history (docs/beam.md, "End sections") where a hinge there needs it:
      an elastic hinge or a joint with coordinates, or in a tree any hinge but a ball joint,
      except a lone weld on the body right after the element (which its transfer takes
      itself), and where a closing joint takes the element's output end.  The element's
      children then hang from it.
    - an attachment offset reaches from a rigid body's output point to one of its named points
      (RigidBody(points=...)); the bodies hanging there hang from its output point.  Every
      sweep then joins children at output points only.
    - a ground anchor reaches from the ground point to a root's place on the ground
      (System.add(..., at=[x, y, z])), welded to the ground (moving with it); the roots placed
      there hang from its output point.  Every sweep then starts at the ground point.
    - an input section, where a closing joint takes a beam's or rod's input end: it takes its
      hinge (its joint, coordinates, drives, deflection) with zero length, and the beam is
      welded to it (R0 = I), so that the closing joint's side is a rigid body at the beam's
      input point in the beam's frame (the kernel index of the user's beam is the section's:
      its rotation, angular velocity, input loads and joint are the section's).
    The mass, momentum and energy of all four are zero; a chain without them is the model
    itself."""
    km, keep = _kernel_model_kept(model)
    return (model if km is None else km), keep


@model_fact
def _kernel_model_kept(model):
    """kernel_model's, kept on the model: None for the model itself (no reference cycle
    through its facts, which would leave a million bodies' arrays to the cycle collector)."""
    km, keep = _kernel_model(model)
    keep.flags.writeable = False
    return (None if km is model else km), keep


def _kernel_model(model):
    n = model.n_bodies
    chain = model.is_chain

    # beams and strain rods whose output end closes a loop (not a chain's pinned tip): the
    # closing joint's side is the end section (kernels/assembly/closure.py reads rigid sides
    # only)
    closed_ends, closed_inputs = set(), set()
    if model.n_closures and not model.tip_pinned:
        on_end = np.asarray(model.closure_on_end, dtype=bool)
        sides = np.asarray(model.closure_body)
        closed_ends = {int(k) for k in sides[on_end]}
        closed_inputs = {int(k) for k in sides[~on_end & (sides >= 0)]
                         if model.body_kind[k] in FLEXIBLE}
    placed = np.any(model.attachment_point[model.parent < 0])    # roots off the ground point
    if not (closed_ends or np.any(model.body_kind != RIGID) or np.any(model.attachment)
            or placed):
        return model, np.arange(n)      # (no end sections, no offsets: the model itself)
    children = children_of(model.parent)

    def needs_section(k):
        hinges = [int(model.hinge_kind[c]) for c in children[k]]
        if k in closed_ends:
            return True
        if model.body_kind[k] not in FLEXIBLE or not hinges:
            return False
        if any(h == ELASTIC or h in WITH_COORDINATES for h in hinges):
            return True
        return (not chain and FIXED in hinges
                and not (children[k] == [k + 1] and hinges == [FIXED]))

    ends = {k for k in range(n) if needs_section(k)}
    if not ends and not closed_inputs and not np.any(model.attachment) and not placed:
        return model, np.arange(n)
    names = ("body_params", "hinge_kind", "hinge_params", "body_kind", "beam_params",
             "rod_params", "initial_rotation", "initial_angular_velocity", "ground_locked",
             "forces", "torques", "line_loads", "body_names", "hinge_names",
             "body_mass_center_inertia", "drives")
    rows = {name: [] for name in names}
    parent, keep, hub, offsets = [], [], {}, {}
    mode_off = np.concatenate([[0], np.cumsum(model.n_modes)])
    identity = np.zeros(HINGE_PARAM_SIZE)
    identity[REST_ROTATION] = np.eye(3).reshape(-1)

    def add_massless(inboard, to_output, rot, omega, locked, body_name, hinge_name):
        body_params = np.zeros_like(model.body_params[0])
        body_params[TO_OUTPUT] = to_output
        row = dict(body_params=body_params, hinge_kind=FIXED, hinge_params=identity,
                   body_kind=RIGID, beam_params=np.zeros_like(model.beam_params[0]),
                   rod_params=np.zeros_like(model.rod_params[0]), initial_rotation=rot,
                   initial_angular_velocity=omega, ground_locked=locked, forces=None,
                   torques=None, line_loads=None, body_names=body_name, hinge_names=hinge_name,
                   body_mass_center_inertia=np.zeros((3, 3)), drives=())
        for name in names:
            rows[name].append(row[name])
        parent.append(inboard)
        return len(parent) - 1

    anchors = {}
    for k in range(n):
        p = model.parent[k]
        if p < 0 and model.attachment_point[k].any():     # one anchor per place in use
            key = tuple(model.attachment_point[k])
            if key not in anchors:
                anchors[key] = add_massless(
                    -1, model.attachment_point[k], model.ground_rotation,
                    model.ground_state(0.0)[4], True, f"ground anchor {len(anchors)}",
                    f"ground anchor {len(anchors)} weld")
            inboard = anchors[key]
        elif p < 0:
            inboard = -1
        elif model.attachment[k] == 0:
            inboard = hub[p]
        else:                           # one offset per named point in use
            key = (p, int(model.attachment[k]))
            if key not in offsets:
                offsets[key] = add_massless(
                    keep[p], model.attachment_point[k] - model.body_params[p, TO_OUTPUT],
                    model.initial_rotation[p], model.initial_angular_velocity[p],
                    model.ground_locked[p], f"{model.body_names[p]} point {key[1]}",
                    f"{model.body_names[p]} point {key[1]} weld")
            inboard = offsets[key]
        row = {name: getattr(model, name)[k] for name in names}
        if k in closed_inputs:          # the input section takes the hinge, the beam a weld
            section = dict(row, body_params=np.zeros_like(model.body_params[0]),
                           body_kind=RIGID, beam_params=np.zeros_like(model.beam_params[0]),
                           rod_params=np.zeros_like(model.rod_params[0]),
                           forces=None, torques=None, line_loads=None,
                           body_names=f"{model.body_names[k]} input section",
                           body_mass_center_inertia=np.zeros((3, 3)))
            for name in names:
                rows[name].append(section[name])
            parent.append(inboard)
            inboard = len(parent) - 1
            row.update(hinge_kind=FIXED, hinge_params=identity, drives=(),
                       hinge_names=f"{model.body_names[k]} input weld")
        for name in names:
            rows[name].append(row[name])
        parent.append(inboard)
        keep.append(inboard if k in closed_inputs else len(parent) - 1)
        hub[k] = len(parent) - 1
        if k in ends:
            eta0 = model.initial_modal_coordinates[mode_off[k]:mode_off[k + 1]]
            eta_d0 = model.initial_modal_velocities[mode_off[k]:mode_off[k + 1]]
            rot, omega = element_end_section(model, k, model.initial_rotation[k],
                                             model.initial_angular_velocity[k], eta0, eta_d0)
            hub[k] = add_massless(hub[k], np.zeros(3), rot, omega, False,
                                  f"{model.body_names[k]} end section",
                                  f"{model.body_names[k]} end weld")
    arrays = {name: (tuple(v) if name in ("forces", "torques", "line_loads", "body_names",
                                          "hinge_names", "drives")
                     else np.array(v)) for name, v in rows.items()}
    parent = np.array(parent, dtype=np.int64)
    attachment_point = np.zeros((len(parent), 3))
    inner = parent >= 0
    attachment_point[inner] = arrays["body_params"][parent[inner]][:, TO_OUTPUT]
    body = np.array(model.closure_body)             # the closing joints' sides, renumbered:
    for c, s in zip(*np.nonzero(body >= 0)):        # a beam's output end to its end section
        k = int(body[c, s])
        body[c, s] = hub[k] if k in closed_ends and model.closure_on_end[c, s] else keep[k]
    return adopt_arrays(replace(model, n_bodies=len(parent), parent=parent, closure_body=body,
                                attachment=np.zeros(len(parent), dtype=np.int64),
                                attachment_point=attachment_point, frequency_cutoff_reasons=(),
                                **arrays), model), np.array(keep)


_DIRECT_HINT = ("method='direct' multiplies the transfer matrices out and loses all accuracy on "
                "long or stiff chains; use method='riccati'")


def _singular_cause(model, mode, status, where):
    """status: j + 1 for element j of the full-state sweeps (2k: hinge k, 2k + 1: body k), or
    k + 1 for body k of the reduced sweeps; past the last element: the tip's equations."""
    j = status - 1
    reduced = mode in (kstep.RICCATI_REDUCED, kstep.DIRECT_REDUCED, kstep.RICCATI_TREE)
    n_el = model.n_bodies if reduced else 2 * model.n_bodies
    if j >= n_el:
        return f"{where}: the boundary equations at the free tip are singular"
    if reduced:
        return (f"{where}: the transfer across hinge '{model.hinge_names[j]}' and body "
                f"'{model.body_names[j]}' is singular")
    k = j // 2
    what = f"hinge '{model.hinge_names[k]}'" if j % 2 == 0 else f"body '{model.body_names[k]}'"
    return f"{where}: the transfer at {what} is singular"


def _unsupported_cause(model, code, where):
    """code: j + 1 for element j (2k: hinge k, 2k + 1: body k) of a kind the loop does not know
    (a safety net: simulate refuses unsupported combinations before the run)."""
    j = code - 1
    k = j // 2
    what = (f"hinge '{model.hinge_names[k]}' (kind {int(model.hinge_kind[k])})" if j % 2 == 0
            else f"body '{model.body_names[k]}' (kind {int(model.body_kind[k])})")
    return f"simulate: {where} does not support {what}"


@model_fact
def _beam_tips(model):
    """Per beam: (name, length, its modal coordinates' slice, the mode shapes at its tip, the
    twist's there, the mode shapes' slopes there, its body index)."""
    offsets = np.concatenate([[0], np.cumsum(model.n_modes)])
    tips = []
    for k in np.nonzero(model.body_kind == BEAM)[0]:
        row = model.beam_params[k]
        length, nm = row[LENGTH], int(row[MODES])
        y, slope, psi = end_shapes(int(row[FAMILY]), float(length), nm,
                                   int(row[TORSION_MODES]))
        tips.append((model.body_names[k], length, slice(offsets[k], offsets[k + 1]), y, psi,
                     slope, k))
    return tips


def _beam_beyond_its_length(model, tips, eta):
    """The cause, if a beam's tip deflection exceeds its length (checked after every chunk of
    steps): the modal beam is a small-deflection model, and such a deflection only comes from a
    run gone wrong; "" otherwise."""
    for name, length, part, y, psi, _, _ in tips:
        e = eta[part]
        nm = len(y)
        twist = float(e[2 * nm:2 * nm + len(psi)] @ psi)
        if not abs(twist) <= np.pi:
            return (f"the tip section of beam '{name}' twists by {twist:.3g} rad, more than half "
                    f"a turn: the modal twist describes small angles, so the run has gone wrong "
                    f"(a step too large for the motion, or an unstable model)")
        tip = float(np.hypot(e[:nm] @ y, e[nm:2 * nm] @ y))
        if not tip <= length:
            return (f"the tip of beam '{name}' deflects {tip:.3g} m, more than the beam's "
                    f"length, {length:g} m: the modal beam describes small deflections, so the "
                    f"run has gone wrong (a step too large for the motion, or a beam spun past its "
                    f"first bending frequency, which the beam without geometric stiffening "
                    f"cannot carry)")
    return ""


# The end rotation (rad, relative to the input section) at which the second-order energy of a
# stiffened beam with loaded-end modes stops being positive, per modes per plane (docs/beam.md,
# "Where the second-order energy stops"): the first sign change of the reference's
# Newton-Euler system as the first of 2 welded elements bends in its first mode.
STIFFENED_BEND_LIMIT = {1: 0.95, 2: 0.17, 3: 0.083, 4: 0.048, 5: 0.034, 6: 0.021}


def _stiffened_bend_hint(model, partial):
    """Why a run may have stopped, where it did: the stiffened beam with loaded-end modes bent
    furthest, at the last sample, to within 20% of STIFFENED_BEND_LIMIT; "" where none was (or
    nothing was recorded)."""
    if partial is None or partial.modal_coordinates is None or not len(partial.t):
        return ""
    eta = partial.modal_coordinates[-1]
    worst = None
    for name, _, part, _, _, slope, k in _beam_tips(model):
        row = model.beam_params[k]
        m = int(row[MODES])
        if row[STIFFENING] in (0.0, EXACT) or int(row[FAMILY]) != CLAMPED_LOADED or m not in \
                STIFFENED_BEND_LIMIT:
            continue
        e = eta[part]
        bend = float(np.hypot(e[:m] @ slope, e[m:2 * m] @ slope))
        share = bend / STIFFENED_BEND_LIMIT[m]
        if share >= 0.8 and (worst is None or share > worst[0]):
            worst = (share, name, bend, m)
    if worst is None:
        return ""
    _, name, bend, m = worst
    return (f"; beam '{name}' (geometric stiffening, {m} modes per plane) had bent by {bend:.2g} "
            f"rad over its length, near the {STIFFENED_BEND_LIMIT[m]:g} rad where its second-order "
            f"energy stops being positive (docs/beam.md, \"Where the second-order energy "
            f"stops\"): give its elements stiffening='exact' (the foreshortening to all "
            f"orders)" + (", or modes_per_plane=1, or use more elements "
                                                 "(each then bends less)" if m > 1 else
                                                 ", or use more elements (each then bends less)"))


def _failure_cause(model, mode, info, monitor, settings):
    code = int(info[0])
    if code == ERROR_ESTIMATE:
        return (f"the step's local error estimate, {monitor.error[1]:.3g} (rad or m), exceeds "
                f"max_step_error = {settings.max_step_error:g}: the step is too large for the "
                f"motion (take a smaller dt), or the motion runs away (an unstable model; "
                f"or, if a smaller dt stops as early, the undamped rule's own growth on stiff "
                f"modes the step does not resolve: rho_inf=0.9 damps them)")
    if code == UNCONVERGED:
        return (f"the energy-momentum step's Newton iterations did not converge to newton_tol "
                f"= {settings.newton_tol:g} in {settings.newton_max} iterations, so it "
                f"conserves nothing: take a smaller dt")
    if code == kstep.SINGULAR and int(info[2]) == LOST_ACCURACY:
        return (f"the direct sweep lost its accuracy: the multiplied-out transfers cancel (a "
                f"transfer relation is violated by more than {DIRECT_TOLERANCE:g} of its terms)")
    if code == kstep.SINGULAR:
        return _singular_cause(model, mode, int(info[2]), "step")
    return ("the state became NaN or infinite (the step is too large for the motion, or the "
            "model is unstable)")


def _closed(model):
    """The model with its loops closed at t = 0 (docs/loops.md): itself where they are closed
    to 1e-10, else dttmm.assemble's (which refuses a drive the loops lock), once per model."""
    assembled = _assembled(model)
    return model if assembled is None else assembled


@model_fact
def _assembled(model):
    """_closed's, kept on the model: None for the model itself (no reference cycle)."""
    if max(np.max(r, initial=0.0) for r in loop_residuals(model)) > 1e-10:
        check_runs_in_sweeps(model, "simulate", moving_ground=True)
        return assemble(model)
    check_drives_move(model, "simulate")
    return None


def richardson_extrapolation(*runs):
    """The Romberg extrapolation of Results at steps h, h/2, h/4, ... (coarsest first), recorded
    at the same times, on the even powers of the step: two runs give (4 y_h/2 - y_h) / 3 (order
    4), three order 6, four order 8 (docs/solver.md, "Richardson extrapolation"); rotations
    projected onto SO(3)."""
    if len(runs) < 2:
        raise ValueError("richardson_extrapolation: give at least two runs (steps h, h/2, ...)")
    coarse, fine = runs[0], runs[-1]
    for other in runs[1:]:
        if coarse.t.shape != other.t.shape or not np.abs(coarse.t - other.t).max() <= 1e-9:
            raise ValueError("richardson_extrapolation: the runs are not recorded at the same "
                             "times")

    done = {}           # (the positions serve both their fields and info's correction)

    def combine(name):
        if name not in done:
            table = [getattr(run, name) for run in runs]
            if table[0] is not None:    # T[i, k] = T[i, k-1] + (T[i, k-1] - T[i-1, k-1])
                for k in range(1, len(runs)):                                   # / (4^k - 1)
                    table = [table[i] + (table[i] - table[i - 1]) / (4.0 ** k - 1.0)
                             for i in range(1, len(table))]
            done[name] = table[0]
        return done[name]

    combined = ("position_input", "position_mass_center", "position_output",
                "angular_velocity", "angular_acceleration", "force", "moment",
                "velocity_input", "modal_coordinates", "modal_velocities", "joint_coordinates",
                "joint_rates", "drive_force", "closure_force", "closure_moment",
                "closure_drive_force", "kinetic", "potential")
    points = ("position_input", "position_mass_center", "position_output")
    lazy = ("rotation", "info") + tuple(name for name in combined if name not in DERIVED)

    def derivation(name):
        """Every field combined when first read, as a run's positions are derived (each
        run's positions cost ~50 us a run to derive): the call itself costs no more than
        its runs."""
        if name == "rotation":
            return {name: nearest_rotations(combine("rotation"))}
        if name == "info":
            correction = max(float(np.abs(combine(p) - getattr(fine, p)).max())
                             for p in points)
            return {name: dict(coarse.info, richardson=True, richardson_runs=len(runs),
                               dt_runs=tuple(run.info["dt"] for run in runs),
                               richardson_correction_m=correction,
                               newton_iterations_used=max(
                                   run.info.get("newton_iterations_used", 0) for run in runs),
                               newton_unconverged_steps=sum(
                                   run.info.get("newton_unconverged_steps", 0)
                                   for run in runs))}
        return {name: combine(name)} if name in combined else {}

    kept = {name: getattr(coarse, name) for name in FIELDS
            if name not in combined and name not in lazy}
    kept.update(wall_time=sum(run.wall_time for run in runs),
                n_steps=sum(run.n_steps for run in runs),
                checkpoint=NoCheckpoint("a Richardson extrapolation (richardson=) keeps no "
                                        "checkpoint: it combines runs"))
    return Result._of_run(derivation, lazy=lazy, **kept)


def nearest_rotations(m):
    """(..., 3, 3): the rotations nearest to matrices m (their orthogonal polar factor).  Near
    rotations by the Newton-Schulz iteration X <- X (3 I - X^T X) / 2, whose error squares each
    step (Higham, Functions of Matrices, 8.3): off = |X^T X - I| <= 1e-8 leaves 1e-16 after
    one more; matrices far from a rotation by the SVD's U V^T, the sign of det fixed."""
    x = np.asarray(m, dtype=float)
    for _ in range(6):
        gram = np.swapaxes(x, -1, -2) @ x
        off = np.abs(gram - np.eye(3)).max(initial=0.0)
        if not off <= 0.25:                 # (NaN too)
            break
        x = x @ (1.5 * np.eye(3) - 0.5 * gram)
        if off <= 1e-8:
            return x
    u, _, vt = np.linalg.svd(m)
    u[..., :, 2] *= np.sign(np.linalg.det(u @ vt))[..., None]
    return u @ vt


def _root_place(model, k, r_ground, v_ground, rot_ground, w_ground):
    """(T, 3) root k's place on the ground (Model.attachment_point[k], ground frame) and its
    velocity, from the ground point's (T, 3) position and velocity and the ground frame's
    (T, 3, 3) rotation and (T, 3) angular velocity."""
    local = model.attachment_point[k]
    if not local.any():
        return r_ground, v_ground
    arm = rot_ground @ local
    return r_ground + arm, v_ground + cross(w_ground, arm)


def _tree_inputs(model, rot, omega, rho, rho_dot, defl, defl_rate, ground):
    """(T, n, 3) input points' positions and velocities of a tree, parents first: body k's
    input is its parent's attachment point (the output point, rho, a named point fixed in
    the parent, or a root's place on the ground) plus its joint's deflection.  ground: the
    ground point's position and velocity, the ground frame's rotation and angular velocity,
    (T, ...) each."""
    r_in, v_in = np.empty_like(rho), np.empty_like(rho)
    for k in range(model.n_bodies):
        p = model.parent[k]
        if p < 0:
            r_att, v_att = _root_place(model, k, *ground)
            r_in[:, k], v_in[:, k] = r_att + defl[:, k], v_att + defl_rate[:, k]
            continue
        if model.attachment[k] == 0:
            arm, arm_dot = rho[:, p], rho_dot[:, p]
        else:
            arm = rot[:, p] @ model.attachment_point[k]
            arm_dot = cross(omega[:, p], arm)
        r_in[:, k] = r_in[:, p] + arm + defl[:, k]
        v_in[:, k] = v_in[:, p] + arm_dot + defl_rate[:, k]
    return r_in, v_in


def _sum_before(x):
    """(T, n, 3): for each body, the sum of x over the bodies before it."""
    out = np.zeros_like(x)
    np.cumsum(x[:, :-1], axis=1, out=out[:, 1:])
    return out


@model_fact
def coordinate_columns(model):
    """Every joint coordinate as (body, its index in the joint), in Result's
    joint_coordinates order (Model.drives': hinge by hinge)."""
    return tuple((k, i) for k in range(model.n_bodies) for i in range(len(model.drives[k])))


def loaded_bodies(model, kernel, keep):
    """The kernel model's body that carries each of the model's bodies' applied loads: its
    kept body (keep), but a beam's own where an input section stands in for its recorded
    state (kernel_model: the beam right after its section)."""
    return keep + ((model.body_kind == BEAM) & (kernel.body_kind[keep] != BEAM))


def column_names(model):
    """{"coordinate_names": the joint coordinates' columns (the joint's name, and its
    coordinate's number where it has two), "modal_names": the modal coordinates' (the beam's
    name, the plane or part and the mode's number)}: the legends of Result.plot_joints and
    plot_modal (kept in Result.info; each call's own lists)."""
    return {key: list(names) for key, names in _column_names(model).items()}


@model_fact
def _column_names(model):
    joints = [model.hinge_names[k] + (f" {i + 1}" if len(model.drives[k]) > 1 else "")
              for k, i in coordinate_columns(model)]
    modal = []
    for k in np.nonzero((model.body_kind == BEAM) | (model.body_kind == ROD))[0]:
        name = model.body_names[k]
        if model.body_kind[k] == ROD:        # its strain coefficients, component by component
            row = model.rod_params[k]
            m = int(row[ROD_MODES])
            modal += [f"{name} {part}{j + 1}" for part in rod_components(row) for j in range(m)]
            continue
        row = model.beam_params[k]
        m = int(row[MODES])
        modal += [f"{name} {plane}{j + 1}" for plane in ("v", "w") for j in range(m)]
        modal += [f"{name} twist{j + 1}" for j in range(int(row[TORSION_MODES]))]
        modal += [f"{name} stretch{j + 1}" for j in range(int(row[AXIAL_MODES]))]
    return dict(coordinate_names=joints, modal_names=modal)


def _result(model, recording, h, wall, n_steps, info, checkpoint=None):
    """The Result of a run's recording: the stored state as recorded; positions, velocities and
    energies left to _derived, computed when first read."""
    values = recording.arrays()
    t = (np.asarray(recording.times) if recording.times
         else np.asarray(recording.steps, dtype=float) * h)
    rot, omega, eta, eta_d = values["rot"], values["omega"], values["eta"], values["eta_d"]
    if "defl" not in values:                # (not recorded without joints that offset)
        values["defl"] = values["defl_rate"] = _zeros(rot.shape[:2] + (3,))
    joints = {}
    columns = coordinate_columns(model)
    if "jq" in values and columns:
        for name, key in (("joint_coordinates", "jq"), ("joint_rates", "jqd"),
                          ("drive_force", "jtau")):
            joints[name] = np.stack([values[key][:, k, i] for k, i in columns], axis=1)
    if "closure_wrench" in values:
        joints["closure_force"] = values["closure_wrench"][:, :, :3]
        joints["closure_moment"] = values["closure_wrench"][:, :, 3:6]
        if has_closure_drives(model):
            joints["closure_drive_force"] = values["closure_wrench"][:, :, 6:8]
    derived = {}

    def derivation(name):
        """The points' positions and velocities, and (when asked) the energies from them."""
        if not derived:
            derived.update(_points(model, t, rot, omega, values["defl"], values["defl_rate"],
                                   eta, eta_d, values.get("v_st"), values.get("v_c")))
        if name in ("kinetic", "potential") and "kinetic" not in derived:
            ground_r, _, ground_rot, _ = model.ground_states(t)
            derived["kinetic"], derived["potential"] = chain_energies(
                model, rot, omega, derived["position_input"], derived["velocity_input"],
                values["defl"], ground_rotation=ground_rot, eta=eta, eta_dot=eta_d,
                joint_coordinates=joints.get("joint_coordinates"), ground_position=ground_r)
        return derived

    loads = values["z"]                     # every body's input [m; q]
    info = dict(info, **column_names(model))
    return Result._of_run(derivation, method="dttmm", t=t, rotation=rot, angular_velocity=omega,
                  angular_acceleration=values["omega_dot"], force=loads[:, :, 3:6],
                  moment=loads[:, :, 0:3], wall_time=wall, n_steps=n_steps, info=info,
                  modal_coordinates=eta if model.n_modes.any() else None,
                  modal_velocities=eta_d if model.n_modes.any() else None,
                  body_names=tuple(model.body_names), checkpoint=checkpoint, **joints)


_ZERO = np.zeros(1)
_ZERO.flags.writeable = False


@functools.lru_cache(maxsize=64)
def _zeros(shape):
    """Zeros of the given shape, read-only, without memory of their own (strides 0; one array
    per shape, shared: nothing can write it)."""
    return np.ndarray(shape, dtype=float, buffer=_ZERO, strides=(0,) * len(shape))


def _points(model, t, rot, omega, defl, defl_rate, eta, eta_d, v_st, v_c):
    """Positions of every body's points and velocities of its input, for all samples."""
    n = model.n_bodies
    l_io = model.body_params[:, TO_OUTPUT]
    mode_off = np.concatenate([[0], np.cumsum(model.n_modes)])
    ground = model.ground_states(t)     # the ground point and frame at every sample
    # each body's output point relative to its input point, every body and sample at once
    rho = np.einsum("tkij,kj->tki", rot, l_io)
    rho_dot = cross(omega, rho)
    for k in np.nonzero(model.body_kind != RIGID)[0]:
        j0, j1 = mode_off[k], mode_off[k + 1]
        rho[:, k], rho_dot[:, k] = element_output_offset(model, k, rot[:, k], omega[:, k],
                                                         eta[:, j0:j1], eta_d[:, j0:j1])
    # down the chain: r_in,k = r_ground + sum_{j<k} (d_j + rho_j) + d_k (d: hinge deflections)
    if model.is_chain:
        r_root, v_root = _root_place(model, 0, *ground)
        r_in = r_root[:, None] + _sum_before(defl + rho) + defl
        v_in = v_root[:, None] + _sum_before(defl_rate + rho_dot) + defl_rate
    else:
        r_in, v_in = _tree_inputs(model, rot, omega, rho, rho_dot, defl, defl_rate, ground)
    if v_st is not None:                    # the paper's scheme: a beam's input point's own
        beams = model.body_kind == BEAM
        v_in[:, beams] = v_st[:, :n][:, beams]
    if v_c is not None:
        # energy-momentum and paper's schemes: every (rigid) mass centre carries its own
        # velocity, which with the rigid-body field about it defines the input point's
        # (docs/solver.md)
        rigid = model.body_kind != BEAM if v_st is not None else np.ones(n, dtype=bool)
        rho_c = np.einsum("tkij,kj->tki", rot[:, rigid], model.body_params[rigid, TO_MASS_CENTER])
        v_in[:, rigid] = v_c[:, rigid] - cross(omega[:, rigid], rho_c)
    r_c, r_o = point_positions(model, rot, r_in, eta)
    return dict(position_input=r_in, position_mass_center=r_c, position_output=r_o,
                velocity_input=v_in)


# the reshaped solver's layers (issue 31: options, prepared runs, drivers), imported last:
# they read this module's helpers
from . import drivers  # noqa: E402
from .run_options import run_options  # noqa: E402
from .run_plan import prepared_run  # noqa: E402
