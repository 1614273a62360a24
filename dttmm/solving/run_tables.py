"""A model's tables as the kernels take them (docs/solver.md): the kernel model (the user's model
with the bodies locked to the ground folded in), its parameter rows, the beams' and strain rods'
tables, the closing joints' tables, the drives, the Workspace a run steps in, and the facts
(model_fact) the solver asks of a model."""
from dataclasses import dataclass, replace

import numpy as np

from ..vectors import cross
from ..elements import BEAM, RIGID, ROD
from ..elements.strain_rod import (ROD_DAMPING, ROD_MODES, ROD_MU, rod_components,
                                   rod_section,
                                   rod_stiffness)
from ..elements.strain_rod import rod_tables as rod_element_tables
from ..elements.kinds import (COORDINATE_0, DEFLECTING, FLEXIBLE, HINGE_PARAM_SIZE,
                              MAX_COORDINATES, RATE_0, WITH_COORDINATES, WITH_SLIDES,
                              unimplemented_body_kind)
from ..elements.beam import (AXIAL_MODES, BEAM_PARAM_SIZE, EXACT, FAMILY, LENGTH,
                             MODES, STIFFENING, TORSION_MODES, foreshortening_integrals,
                             mode_shapes, slope_grams, torsion_shapes)
from ..elements.contact import BODY as CONTACT_BODY
from ..elements.contact import PARENT as CONTACT_PARENT
from ..elements.drives import (COMPILED_FORCE, FORCE, PD, SPRING_DAMPER, compiled_force)
from ..elements.hinges import (BALL, DEFLECTION_0, DEFLECTION_RATE_0, ELASTIC, FIXED, FREE,
                               REST_ROTATION)
from ..elements.rigid_body import TO_MASS_CENTER, TO_OUTPUT
from ..kernels.assembly import solve as ksolve
from ..kernels.schema import LOOP_LAYOUT, STATE_LAYOUT, SWEEP_LAYOUT, pack
from ..kernels.transfers.beam_relations import (gauss_points, quadrature_size)
from ..model.loop_rows import constraint_rows
from .methods import SWEEPS
from ..model.model import Model, adopt_arrays, children_of, is_shared, kernel_array, model_fact
from ..model.sections import beam_output_offset, element_end_section, output_section


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
    state the loops advance (a FlatState: kernels/schema.py::STATE) and the assembly's scratch
    (a FlatSweep: SWEEP).  fused: the run takes a fused ball-chain or ball-tree loop,
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
        n_joint = 0 if fused and not has_offsets(model) else n     # (a free root's flight)
        off3 = lambda: np.zeros((n_joint, 3))                       # noqa: E731
        # the joints' coordinates and rates at t = 0 (zeros, untouched, without such joints)
        jq, jqd = ((model.hinge_params[:, COORDINATE_0].copy(),
                    model.hinge_params[:, RATE_0].copy()) if has_coordinates(model)
                   else (np.zeros((n_joint, MAX_COORDINATES)),
                         np.zeros((n_joint, MAX_COORDINATES))))
        self.state = STATE_LAYOUT.pack(
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
            jq=jq, jqd=jqd, jqdd=np.zeros((n_joint, MAX_COORDINATES)),
            jqp=np.zeros((n_joint, MAX_COORDINATES)), jtau=np.zeros((n_joint, MAX_COORDINATES)))
        self.sweep = SWEEP_LAYOUT.pack(
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
        _initial_deflections(model, self.state)


def _initial_deflections(model, state):
    """state.defl at t = 0, the offset of each body's input point from its parent's output
    point, which the loops keep from the first step on (the t = 0 sample, the energies and
    positions then place the body where the model says): an elastic hinge's given deflection
    (ElasticHinge.deflection; its rate starts at zero) or a free joint's offset and rate (world,
    as the build set them: model/freeze.py), and a joint's slides d = A_P sum n_i q_i
    with its rate (w_p, the parent's output section's angular velocity;
    kernels/transfers/joint.py::joint_frame and its joint_offset)."""
    from ..kernels.transfers.joint import joint_frame
    for k in range(model.n_bodies):
        if model.hinge_kind[k] in DEFLECTING:
            state.defl[k] = model.hinge_params[k, DEFLECTION_0]
            state.defl_rate[k] = model.hinge_params[k, DEFLECTION_RATE_0]
        if model.hinge_kind[k] not in WITH_SLIDES:
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
        zero = np.zeros(3)
        joint_frame(int(model.hinge_kind[k]), np.array(model.hinge_params[k], dtype=float),
                    np.array(rot_p, dtype=float), np.array(w_p, dtype=float), zero,
                    np.array(model.hinge_params[k, COORDINATE_0], dtype=float),
                    np.array(model.hinge_params[k, RATE_0], dtype=float),
                    np.zeros(MAX_COORDINATES), np.empty((3, 3)), np.empty(3), np.empty(3),
                    state.defl[k], state.defl_rate[k])


@model_fact
def kernel_params(model):
    """The frozen model's tables as the kernels read them, once per model: one flat model
    (kernels/schema.py::FlatModel, its tables named and shaped by the schema's MODEL); the
    kernels read them and never write them."""
    # a locked body's rotation relative to the ground frame (read only where locked[k]; no
    # rows without locked bodies: a million bodies' 72 MB)
    lock_rel = (np.einsum("ji,kjl->kil", model.ground_rotation, model.initial_rotation,
                          order="C") if model.ground_locked.any() else np.zeros((0, 3, 3)))
    # a table whose rows are all equal (model.shared_rows) as its one row, which every body
    # (joint) reads (body_row)
    (body_params, inertia), body_row = _rows(model, "body_params", "body_mass_center_inertia")
    (hinge_params,), hinge_row = _rows(model, "hinge_params")
    body_kind, beam_params, beam_moments, mode_offset, beam_ends, beam_factors = \
        beam_tables(model)
    rod_row, steps, xi0, phi, weights, stiffness, mu_damping, section = rod_tables(model)
    return pack(body_params=body_params, mass_center_inertia=inertia, body_row=body_row,
                hinge_kind=model.hinge_kind, hinge_params=hinge_params, hinge_row=hinge_row,
                parent=model.parent, gravity=model.gravity, locked=model.ground_locked,
                lock_rel=lock_rel, tip_pinned=bool(model.tip_pinned),
                joint_drive=joint_drives(model), body_kind=body_kind, beam_params=beam_params,
                beam_moments=beam_moments, mode_offset=mode_offset, beam_ends=beam_ends,
                beam_factors=beam_factors, rod_row=rod_row, rod_steps=steps, rod_xi0=xi0,
                rod_phi=phi, rod_weights=weights, rod_stiffness=stiffness,
                rod_mu_damping=mu_damping, rod_section=section,
                contacts=np.array(model.contacts, dtype=float, order="C"))



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
    """(n, MAX_COORDINATES, 4): each joint coordinate's drive as the kernels read it, [kind,
    stiffness, damping, rest], kind -1 for none (elements/drives.py).  A drive with a part known in
    time (a PDTracking, a JointForce of time alone) is a spring-damper about 0 there, its known part
    in the inputs (_joint_inputs; kernels/transfers/joint.py::drive_value); a compiled JointForce is
    COMPILED_FORCE with its callback's index in compiled_forces in place of the rest. One row of
    none for a model without joints with coordinates (the kernels read a joint's row only; the
    full-state tree sweep hands a ball joint row 0, unread)."""
    table = np.zeros((model.n_bodies if has_coordinates(model) else 1, MAX_COORDINATES, 4))
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
    elastic hinge's deflection, a free joint's flight (DEFLECTING), a joint's slides
    (elements/kinds.py: WITH_SLIDES)."""
    return bool(np.isin(model.hinge_kind, DEFLECTING + WITH_SLIDES).any())


@model_fact
def free_ball_tree(model):
    """Ball joints throughout but at the roots, of which one or more are free joints from the
    ground: the reduced tree sweep runs it, each free root's input acceleration from its load
    q_I = 0 (kernels/stepping/tree.py; the high-order scheme's)."""
    free = model.hinge_kind == FREE
    return bool(free.any() and np.all(model.parent[free] < 0)
                and np.all((model.hinge_kind == BALL) | free) and not has_loops(model))


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
    """The closing joints as the general loop reads them (a FlatLoops: kernels/schema.py::LOOPS),
    in the kernel model's numbering, with their scratch; no rows without loops.  Column 0 of the
    sweep is the step, column r + 1 row r's unit multiplier, which passes the bodies of
    loop_columns.  Each call's own copy (a run writes its scratch) of the tables built once
    per model."""
    return LOOP_LAYOUT.copy(_loop_tables(model, BANDED_ROWS))


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
    nb = n if r or len(model.contacts) else 0   # the rows' scratch per body (the contacts
    # read the points of it: kernels/transfers/contact.py; kernels/assembly/closure.py;
    st = 2 * nb + 1 if r else 0  # none without rows: a million bodies' 900 B each)
    up_ptr = np.zeros(n + 1, dtype=np.int64)      # (body k's columns: up_idx[up_ptr[k]:..])
    for k, u in ups.items():
        up_ptr[k + 1] = len(u)
    np.cumsum(up_ptr, out=up_ptr)
    col_body = np.full((r + 1, 2), -1, dtype=np.int64)
    col_body[1:] = body[np.asarray(owner, dtype=np.int64)]
    tables = dict(kind=kind, owner=owner, v1=v1, v2=v2, v3=v3, target=np.zeros((r, 3)),
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
                  act_idx=np.array(act_idx, dtype=np.int64), act=act.astype(np.int64),
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
    return LOOP_LAYOUT.pack(**tables)


def _loop_info(loops):
    """A run's info on its closing joints (kernels/schema.py::LOOPS' stats, energy): the
    largest residuals after any step's projections, and before them, and where the energy is
    held the largest relative change of the rates that held it; nothing without loops."""
    if not loops.rows:
        return {}
    return {"loop_position_residual": float(loops.stats[3]),
            "loop_rate_residual": float(loops.stats[2]),
            "loop_position_residual_unprojected": float(loops.stats[0]),
            "loop_rate_residual_unprojected": float(loops.stats[1]),
            **({"energy_correction": float(loops.energy[2])} if loops.energy[0] else {})}


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
    quadrature exact to rounding for the mode families
    (kernels/transfers/beam_relations.py::quadrature_size), then the geometric stiffness integrals
    int w(x) Y_j' Y_l' for w = 1, L - x, (L^2 - x^2) / 2 (D0, D1, D2 of docs/beam.md, "Geometric
    stiffening"), m columns each.  ends[k, m:m + mt] is beam k's twist table (docs/beam.md,
    "Torsion"; kernels/transfers/beam_relations.py::twist_relations): [Psi_j(L), int Psi_j, modal
    mass / j_p, modal stiffness / G J] per twist mode j, and ends[k, m + mt:m + mt + ma] its
    stretch table ("Stretch"; beam_relations): [U_j(L), int U_j, int x U_j, modal mass / mu, modal
    stiffness / E A, int U_j Y_l (m), int U_j U_l (ma)].  With stiffening="exact" (docs/beam.md,
    "The exact foreshortening"), moments[k, j] goes on from column 2 + 4 m with the beam's sections
    at n Gauss-Legendre points: n, then per point [x, weight, Y_j(x), D(x)[j, 0..m-1]], D(x) =
    int_0^x Y' Y'^T, and the stretch table with U_j at those points, from column 5 + m + ma
    (kernels/transfers/beam_relations.py::exact_line_integrals).  The tables but body_kind and the
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
    # (from n_modes: beam_tables also reads a model-like namespace; writable, as every array the
    # kernels take)
    mode_off = np.concatenate([[0], np.cumsum(model.n_modes)]).astype(np.int64)
    beam_params = kernel_array(model, "beam_params") if n else np.zeros((0, BEAM_PARAM_SIZE))
    return kernel_array(model, "body_kind"), beam_params, moments, mode_off, ends, factors


def _mode(model, method, full_state, high_order=False):
    """The sweep a model runs in; high_order: the high-order scheme's (a tree of ball joints
    on free roots runs in the reduced tree sweep: free_ball_tree)."""
    if method not in SWEEPS:
        raise ValueError(f"simulate: method must be one of {tuple(SWEEPS)}, got {method!r}")
    if high_order and free_ball_tree(model) and not full_state:
        return ksolve.RICCATI_TREE
    reduced = model.all_ball and not full_state
    if full_tree(model, full_state):    # (check_supported has refused the rest)
        return ksolve.RICCATI_JOINTS
    if not model.is_chain:
        return ksolve.RICCATI_TREE
    if method == "direct":
        return ksolve.DIRECT_REDUCED if reduced else ksolve.DIRECT_FULL
    return ksolve.RICCATI_REDUCED if reduced else ksolve.RICCATI_FULL


FUSED_BALL_CHAIN = True     # False: every chain through the general loop (tests compare the two)
_MODE_NAMES = ["riccati-full", "riccati-reduced", "direct-reduced", "direct-full", "riccati-tree",
               "riccati-joints"]


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
    mode_off = model.mode_offsets
    for k in range(n):
        w, wd = state.omega[k], state.omega_dot[k]
        if model.body_kind[k] == BEAM:
            j0, j1 = mode_off[k], mode_off[k + 1]
            _, rho_dot = beam_output_offset(model.beam_params[k], state.rot[k], w, state.eta[j0:j1],
                                            state.eta_d[j0:j1])
        elif model.body_kind[k] == RIGID:
            rho_c = state.rot[k] @ model.body_params[k, TO_MASS_CENTER]
            c_v[k] = st_v[k] + cross(w, rho_c)
            c_a[k] = (state.z[2 * k + 1, 0:3] + cross(wd, rho_c)
                      + cross(w, cross(w, rho_c)))
            rho_dot = cross(w, state.rot[k] @ model.body_params[k, TO_OUTPUT])
        else:       # (the paper's scheme runs rigid bodies and beams: elements/kinds.py)
            raise unimplemented_body_kind(model.body_kind[k], f"body '{model.body_names[k]}'",
                                          "the paper's scheme's station histories")
        st_v[k + 1] = st_v[k] + rho_dot
        st_a[k + 1] = state.z[2 * k + 2, 0:3]
    return (True, st_v, st_a, st_a.copy(), c_v, c_a, c_a.copy())


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
    mode_off = model.mode_offsets
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
    contacts = np.array(model.contacts)            # the contact spheres' bodies (and their
    kept = np.concatenate([np.asarray(keep, dtype=float), [-1.0]])      # parents), renumbered
    for column in (CONTACT_BODY, CONTACT_PARENT):
        contacts[:, column] = kept[contacts[:, column].astype(np.int64)]
    return adopt_arrays(replace(model, n_bodies=len(parent), parent=parent, closure_body=body,
                                contacts=contacts,
                                attachment=np.zeros(len(parent), dtype=np.int64),
                                attachment_point=attachment_point, frequency_cutoff_reasons=(),
                                **arrays), model), np.array(keep)


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
