"""The flat structures' schemas: every table the kernels read from a model (MODEL), and the
closing joints' tables and scratch (LOOPS), the state (STATE) and the assembly's scratch (SWEEP)
a run writes, in the shape of MuJoCo's mjModel and mjData (docs/flat_model.md).

A layout's tables sit in two flat buffers, `real` (float64) and `int` (int64), one after
another in the order its fields list them; `start` holds each table's offset in its buffer and
`size` the layout's sizes (SIZES: bodies, modal rows, rod steps, ...; LOOP_SIZES: rows, closing
joints, ...; STATE_SIZES, SWEEP_SIZES), so a table's shape is a few numbers the kernels read at
run time, never part of a compiled type.  Each field names a table, its buffer and its shape in
terms of the sizes (a name, "name+1", or a constant).

The kernels read a table through its accessor, generated from the layout (`Layout.write`;
tests/test_schema.py fails where it is stale): ``model_tables.body_params(params)`` is the
(body_rows, BODY_PARAM_SIZE) view of `real` at start[0], ``loop_tables.kind(loops)`` the rows'
kinds.  Python packs a layout's tables with `Layout.pack` (run_tables.kernel_params,
run_tables.loop_tables, run_tables.Workspace) and reads them by name with `Layout.unpack` and
`Layout.table` (a FlatTables reads its tables as attributes: ``loops.stats``, ``state.rot``).
"""
from collections import namedtuple
import math
from pathlib import Path
import textwrap

import numpy as np

from ..elements.beam import BEAM_PARAM_SIZE
from ..elements.contact import CONTACT_SIZE
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
    ("contacts", "the bodies' contact spheres (elements/contact.py), 0 without shapes"),
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
    Field("contacts", REAL, ("contacts", CONTACT_SIZE),
          "elements/contact.py: each contact sphere's row (its BODY and PARENT columns the "
          "kernel model's bodies)"),
)


# The closing joints as the general loop reads them, and its scratch for them (rows R and
# closing joints m in the kernel model's numbering; run_tables.loop_tables; docs/loops.md).
# Without closing joints every table with a row axis is empty.
LOOP_SIZES = (
    ("rows", "R: the closing joints' scalar rows (loop_rows.constraint_rows)"),
    ("closings", "m: the closing joints (0 without rows)"),
    ("bodies", "n: the kernel model's bodies"),
    ("row_bodies", "n where the model has rows, else 0 (the rows' scratch per body)"),
    ("row_stations", "2 n + 1 where the model has rows, else 0"),
    ("modes", "the beams' modal coordinates, all beams"),
    ("up_entries", "entries of up_idx"),
    ("act_entries", "entries of act_idx"),
    ("colrow_entries", "entries of colrow_idx"),
)

LOOPS = (
    Field("kind", INT, ("rows",), "GAP_WORLD / GAP_A / DOT / ANGLE_A / ANGLE_B / ROTATION_A "
                                  "(elements/kinds.py)"),
    Field("owner", INT, ("rows",), "each row's closing joint"),
    Field("v1", REAL, ("rows", 3), "e (or x, in side a's frame); ROTATION_A: R0's first column"),
    Field("v2", REAL, ("rows", 3), "y (side b's frame); ROTATION_A: R0's second column"),
    Field("v3", REAL, ("rows", 3), "an angle's axis (loop_rows.driven_directions, "
                                   "spring_directions)"),
    Field("target", REAL, ("rows", 3),
          "the step's targets (value, rate, acceleration): a driven coordinate's motion at the "
          "step's end, a spring's rest, a JointForce's value (in [2]), else 0"),
    Field("coordinate", INT, ("rows",), "the joint's coordinate a row drives (-1: none)"),
    Field("law", REAL, ("rows", 3),
          "a row's drive [kind, stiffness, damping] (kind -1: none; a SpringDamper's or a "
          "JointForce's row is a force, no constraint)"),
    Field("acc", REAL, ("rows",), "each row's acceleration in the last solve"),
    Field("step_coef", REAL, (2,), "[1 / c1, c3 / c1] of the step (0: the consistent start, "
                                   "springs explicit)"),
    Field("body", INT, ("closings", 2), "the sides' bodies (-1: the ground)"),
    Field("point", REAL, ("closings", 2, 3),
          "the sides' points, in the body's frame from its input point (the ground's: in the "
          "ground frame from the ground point)"),
    Field("ground", REAL, (3,), "the ground point"),
    Field("ground_rot", REAL, (3, 3), "the ground frame"),
    Field("ground_motion", REAL, (4, 3),
          "the ground point's velocity and acceleration and the frame's angular velocity and "
          "acceleration where the rows are written (set_ground: t_{n+1} in a step, 0 at the "
          "start)"),
    Field("coef", REAL, ("rows", 4, 3), "the rows' Jacobian terms (_row_coefficients)"),
    Field("kappa", REAL, ("rows",), "the rows' velocity terms (_row_coefficients)"),
    Field("z_save", REAL, ("rows+1", "row_stations", 12),
          "column 0's and each row's response's stations (on the row's active bodies only)"),
    Field("nu_save", REAL, ("rows+1", "row_bodies", 3), "the same, the joints' nu"),
    Field("tau_save", REAL, ("rows+1", "row_bodies", 3), "the same, the joints' tau"),
    Field("delassus", REAL, ("rows", "rows"), "the rows' matrix"),
    Field("lam", REAL, ("rows",), "the rows' multipliers"),
    Field("rhs", REAL, ("rows",), "the rows' right-hand side"),
    Field("r_out", REAL, ("row_bodies", 3), "the output points' positions"),
    Field("v_out", REAL, ("row_bodies", 3), "the output points' velocities"),
    Field("g", REAL, ("rows",), "the rows' positions"),
    Field("gd", REAL, ("rows",), "the rows' rates"),
    Field("col_body", INT, ("rows+1", 2), "each column's loaded output stations (-1: none)"),
    Field("col_load", REAL, ("rows+1", 2, 6), "each column's station loads"),
    Field("up_ptr", INT, ("bodies+1",),
          "CSR over the bodies: the columns c >= 1 whose sweep passes each body (its active "
          "bodies and their ancestors)"),
    Field("up_idx", INT, ("up_entries",), "up_ptr's entries"),
    Field("act_ptr", INT, ("rows+2",), "CSR over the columns: each column's active bodies in "
                                       "tree order"),
    Field("act_idx", INT, ("act_entries",), "act_ptr's entries"),
    Field("act", INT, ("rows+1", "bodies"), "each column's active bodies as a mask (1: active)"),
    Field("all_bodies", INT, ("row_bodies",), "0 .. n - 1"),
    Field("all_rows", INT, ("rows",), "0 .. R - 1"),
    Field("band", INT, (2,), "the rows' matrices' lower and upper bandwidths where a banded "
                             "solve pays (_rows_solve), else -1"),
    Field("colrow_ptr", INT, ("rows+1",), "CSR over the rows' columns: the rows with a side "
                                          "body among each column's active bodies"),
    Field("colrow_idx", INT, ("colrow_entries",), "colrow_ptr's entries"),
    Field("p_col", REAL, ("rows+1", "row_stations", 6), "sweep_columns' scratch"),
    Field("port_col", REAL, ("rows+1", "row_bodies", 6), "sweep_columns' scratch"),
    Field("h_store", REAL, ("row_bodies", 3, 6), "sweep_columns' scratch"),
    Field("k_store", REAL, ("rows+1", "row_bodies", 3), "sweep_columns' scratch"),
    Field("free_store", INT, ("row_bodies", 4), "sweep_columns' scratch"),
    Field("p_comb", REAL, ("row_stations", 6), "the multipliers' superposition"),
    Field("k_comb", REAL, ("row_bodies", 3), "the multipliers' superposition"),
    Field("eta_col", REAL, ("rows", "modes"), "each row's response of the beams' eta''"),
    Field("wrench", REAL, ("closings", 10),
          "each closing joint's force and couple on side b (world; the couple about its point) "
          "from lam, then its drives' generalized forces and their coordinates' rates "
          "(coordinates 1, 2)"),
    Field("stats", REAL, (4,),
          "the run's largest position residual after a step (before the projection), rate "
          "residual before and after the rates' projection, position residual after its"),
    Field("energy", REAL, (3,),
          "[held (1) or not (0), the total energy the steps hold (set at the start, "
          "start_energy), the largest relative change of the rates its projection made]"),
)


# The state a run advances in place (run_tables.Workspace; kernels/stepping/loop.py, "The
# step"): world frame; the joints' and the elastic hinges' per-body tables have no rows where a
# fused loop runs (its ball joints have none: a million links' 190 MB).
STATE_SIZES = (
    ("bodies", "n: the kernel model's bodies"),
    ("joint_bodies", "n, or 0 where a fused loop runs (no joints with coordinates, no elastic "
                     "hinges, no mass-centre velocities of their own)"),
    ("stations", "2 n + 1: the ground station, then each body's input and output"),
    ("modes", "the beams' modal coordinates, flat over the beams (v of a beam, then w)"),
)

STATE = (
    Field("rot", REAL, ("bodies", 3, 3), "each body's rotation"),
    Field("omega", REAL, ("bodies", 3), "angular velocities, rad/s"),
    Field("omega_dot", REAL, ("bodies", 3), "angular accelerations, rad/s^2"),
    Field("pseudo", REAL, ("bodies", 3), "the rotation integrator's pseudo-accelerations"),
    Field("defl", REAL, ("joint_bodies", 3), "the elastic hinges' deflections (a joint's "
                                             "offset of its body's input point)"),
    Field("defl_rate", REAL, ("joint_bodies", 3), "their rates"),
    Field("defl_acc", REAL, ("joint_bodies", 3), "their accelerations"),
    Field("defl_pseudo", REAL, ("joint_bodies", 3), "their pseudo-accelerations"),
    Field("z", REAL, ("stations", 12), "the stations' states"),
    Field("eta", REAL, ("modes",), "the beams' modal coordinates"),
    Field("eta_d", REAL, ("modes",), "their rates"),
    Field("eta_acc", REAL, ("modes",), "their accelerations"),
    Field("eta_p", REAL, ("modes",), "their pseudo-accelerations"),
    Field("eta_map", REAL, ("modes", 13), "eta'' on the input state"),
    Field("v_c", REAL, ("joint_bodies", 3), "mass-centre velocities (the energy-momentum "
                                            "scheme)"),
    Field("jq", REAL, ("joint_bodies", MAX_COORDINATES), "joint coordinates "
                                                         "(kernels/transfers/joint.py)"),
    Field("jqd", REAL, ("joint_bodies", MAX_COORDINATES), "their rates"),
    Field("jqdd", REAL, ("joint_bodies", MAX_COORDINATES), "their accelerations"),
    Field("jqp", REAL, ("joint_bodies", MAX_COORDINATES), "their pseudo-accelerations"),
    Field("jtau", REAL, ("joint_bodies", MAX_COORDINATES), "their generalized forces"),
)

# The assembly's scratch (run_tables.Workspace): the elements' transfers and the sweeps'
# recursions.  A fused loop reads the reduced sweep's alone: the full-state sweep's tables
# have no rows there (about 6.5 KB per body).
SWEEP_SIZES = (
    ("bodies", "n: the kernel model's bodies"),
    ("full_bodies", "n, or 0 where a fused loop runs"),
    ("elements", "2 n, or 0 where a fused loop runs: hinge k is element 2k, body k 2k + 1"),
    ("full_stations", "2 n + 1, or 0 where a fused loop runs"),
)

SWEEP = (
    Field("kind", INT, ("elements",), "each element's kind (kernels/assembly/sweep.py)"),
    Field("u", REAL, ("elements", 12, 13), "each element's transfer"),
    Field("known_loads", REAL, ("elements", 12), "each element's known loads"),
    Field("split", INT, ("full_stations",), "the full-state Riccati sweep (sweep.py)"),
    Field("s", REAL, ("full_stations", 6, 6), "its Riccati matrices"),
    Field("p", REAL, ("full_stations", 6), "its Riccati vectors"),
    Field("tinv", REAL, ("elements", 6, 6), "its eliminations"),
    Field("t", REAL, ("elements", 6), "its eliminated vectors"),
    Field("g", REAL, ("elements", 6, 3), "its gains"),
    Field("gv", REAL, ("elements", 6), "its gains' vectors"),
    Field("red_v", REAL, ("full_bodies", 6, 7), "the reduced sweep's maps"),
    Field("red_phi", REAL, ("full_bodies", 3, 7), "the reduced sweep's maps"),
    Field("red_s", REAL, ("bodies+1", 3, 3), "the reduced sweep's Riccati matrices"),
    Field("red_p", REAL, ("bodies+1", 3), "the reduced sweep's Riccati vectors"),
    Field("red_tinv", REAL, ("bodies", 3, 3), "the reduced sweep's eliminations"),
    Field("red_t", REAL, ("bodies", 3), "the reduced sweep's eliminated vectors"),
    Field("red_aq", REAL, ("bodies+1", 6), "the reduced sweep's stations [a; q]"),
    Field("dir_z", REAL, ("full_stations", 12, 6), "the direct full-state sweep"),
    Field("dir_o", REAL, ("full_stations", 12), "the direct full-state sweep"),
    Field("port_s", REAL, ("full_bodies", 3, 3), "the reduced tree sweep "
                                                 "(kernels/stepping/tree.py)"),
    Field("port_p", REAL, ("full_bodies", 3), "the reduced tree sweep"),
    Field("aq_out", REAL, ("full_bodies", 6), "the reduced tree sweep"),
    Field("tree_s", REAL, ("full_bodies", 6, 6), "the full-state tree sweep (tree_sweep.py)"),
    Field("tree_p", REAL, ("full_bodies", 6), "the full-state tree sweep"),
    Field("joint_dof", INT, ("full_bodies", 3), "its joints' coordinates: FREE / PRESCRIBED / 0 "
                                                "(kernels/transfers/joint.py)"),
    Field("joint_tau_nu", REAL, ("full_bodies", 3, 3), "its joints' eliminations"),
    Field("joint_nu", REAL, ("full_bodies", 3), "its joints' nu"),
    Field("joint_tau", REAL, ("full_bodies", 3), "its joints' tau"),
)


# The general loop's own scratch (kernels/stepping/step.py::general_loop): the step's guess of
# every body's kinematics, the integrator's offsets, the ground's motion over the step, the
# paper's scheme's point histories, the joints' guess, the loops' arms at the guess.
GENERAL_SIZES = (
    ("bodies", "n: the kernel model's bodies"),
    ("stations", "2 n + 1"),
    ("modes", "the beams' modal coordinates"),
    ("history_points", "n + 1 where the paper's scheme runs (its station points), else 1"),
    ("history_centres", "n where the paper's scheme runs (its mass centres), else 1"),
    ("forces", "the compiled JointForces' callbacks"),
    ("contacts", "the contact spheres (elements/contact.py)"),
    ("instances", "the most contacts at once: a plane's per sphere, two per touching pair "
                  "(step.py::contact_capacity)"),
)

GENERAL = (
    Field("guess_phi", REAL, ("bodies", 3), "each body's rotation increment phi* (the guess; "
                                            "step.py::Guess)"),
    Field("guess_rot", REAL, ("bodies", 3, 3), "its rotation at the guess"),
    Field("guess_lam", REAL, ("bodies", 3, 3), "its left Jacobian J_l(phi*)"),
    Field("guess_w", REAL, ("bodies", 3), "its angular velocity at the guess"),
    Field("guess_wd", REAL, ("bodies", 3), "its angular acceleration at the guess"),
    Field("guess_dw", REAL, ("bodies", 3, 3), "dw / dphi"),
    Field("guess_dwd", REAL, ("bodies", 3, 3), "dw' / dphi"),
    Field("w1", REAL, ("bodies", 3), "w' = c1 phi + w1"),
    Field("w3", REAL, ("bodies", 3), "w = c3 phi + w3"),
    Field("w1d", REAL, ("bodies", 3), "the same for the elastic hinges' deflections d"),
    Field("w3d", REAL, ("bodies", 3), "the same for the elastic hinges' deflections d"),
    Field("z_star", REAL, ("stations", 12), "the stations' guess (phi slots)"),
    Field("w1e", REAL, ("modes",), "eta'' = c1 eta + w1e"),
    Field("w3e", REAL, ("modes",), "eta' = c3 eta + w3e"),
    Field("eta_dd_star", REAL, ("modes",), "the modal accelerations' guess"),
    Field("eta_dd_new", REAL, ("modes",), "the modal accelerations' solution"),
    Field("ground_rot", REAL, (3, 3), "the ground's rotation over the step"),
    Field("ground_lam", REAL, (3, 3), "its left Jacobian"),
    Field("ground_w", REAL, (3,), "its angular velocity"),
    Field("ground_wd", REAL, (3,), "its angular acceleration"),
    Field("ground_dwd", REAL, (3, 3), "dw' / dphi of the ground: c1 I (run_records._set_step)"),
    Field("ground_phi", REAL, (3,), "its rotation increment"),
    Field("root_f", REAL, (6,), "the ground station's [a, w']"),
    Field("e3", REAL, (3, 3), "3 x 3 scratch"),
    Field("g_inv", REAL, (3, 3), "3 x 3 scratch"),
    Field("rot_prev", REAL, (3, 3), "3 x 3 scratch"),
    Field("independent", INT, (), "1 where the paper's scheme gives every station point and "
                                  "mass centre its own Newmark history"),
    Field("st_v", REAL, ("history_points", 3), "the station points' velocities (the paper's "
                                               "scheme; run_tables._station_histories)"),
    Field("st_a", REAL, ("history_points", 3), "their accelerations"),
    Field("st_p", REAL, ("history_points", 3), "their pseudo-accelerations"),
    Field("c_v", REAL, ("history_centres", 3), "the mass centres' velocities"),
    Field("c_a", REAL, ("history_centres", 3), "their accelerations"),
    Field("c_p", REAL, ("history_centres", 3), "their pseudo-accelerations"),
    Field("w1_st", REAL, ("bodies+1", 3), "the station points' w1 offsets"),
    Field("w1_c", REAL, ("bodies", 3), "the mass centres' w1 offsets"),
    Field("q_w1", REAL, ("bodies", MAX_COORDINATES), "the joint coordinates' offsets "
                                                      "(kernels/transfers/joint.py)"),
    Field("q_w3", REAL, ("bodies", MAX_COORDINATES), "the joint coordinates' offsets"),
    Field("q_star", REAL, ("bodies", MAX_COORDINATES), "their guess q*"),
    Field("qd_star", REAL, ("bodies", MAX_COORDINATES), "q'*"),
    Field("qdd_star", REAL, ("bodies", MAX_COORDINATES), "q''*"),
    Field("eta_g", REAL, ("modes",), "eta at the guess, for the loops' rows (_iterate)"),
    Field("eta_d_g", REAL, ("modes",), "eta' at the guess"),
    Field("defl_g", REAL, ("bodies", 3), "d at the guess"),
    Field("defl_rate_g", REAL, ("bodies", 3), "d' at the guess"),
    Field("forces", INT, ("forces",), "the compiled JointForces' C callbacks' addresses "
                                      "(kernels/transfers/joint.py::drive_value)"),
    Field("contact_centre", REAL, ("contacts", 3), "each contact row's centre at the guess "
                                                   "(the Newton iterations' change)"),
    Field("contact_point", REAL, ("instances", 3), "each contact at the guess: its body's "
                                                   "point, body frame (transfers/contact.py)"),
    Field("contact_offset", REAL, ("instances", 3), "the contact point from it, world"),
    Field("contact_force", REAL, ("instances", 3), "its force on the sphere's body, world, N"),
    Field("contact_slope", REAL, ("instances", 3, 3), "the force's derivative by its point's "
                                                      "acceleration"),
    Field("contact_next", INT, ("instances",), "the next contact of its body (-1: none)"),
    Field("contact_body_first", INT, ("bodies",), "each body's first contact (-1: none)"),
    Field("contact_count", INT, (1,), "the contacts at the guess"),
)


# One chunk's prescribed data (solving/drivers.py::Stepping.inputs_for; kernels/stepping/loop.py,
# "The step"): step s's values at t_{s+1}, the ground's rotations at t_s (s = 0 .. steps).
INPUT_SIZES = (
    ("steps", "m: the chunk's steps"),
    ("bodies", "n: the kernel model's bodies"),
    ("rows", "R: the closing joints' rows"),
)

INPUTS = (
    Field("g_acc", REAL, ("steps", 3), "the ground's acceleration"),
    Field("g_rot", REAL, ("steps+1", 3, 3), "the ground's rotation at t_s"),
    Field("g_w", REAL, ("steps", 3), "the ground's angular velocity"),
    Field("g_wd", REAL, ("steps", 3), "the ground's angular acceleration"),
    Field("g_pos", REAL, ("steps", 3), "the ground point's position (where closing joints "
                                       "meet a moving ground)"),
    Field("g_vel", REAL, ("steps", 3), "its velocity"),
    Field("force", REAL, ("steps", "bodies", 3), "applied forces (the energy-momentum scheme: "
                                                 "the step's means)"),
    Field("torque", REAL, ("steps", "bodies", 3), "applied couples (likewise)"),
    Field("line_load", REAL, ("steps", "bodies", 3), "a beam's distributed load per length, "
                                                     "world"),
    Field("joint_input", REAL, ("steps", "bodies", MAX_COORDINATES, 3),
          "per joint coordinate: a prescribed motion's (q, q', q''), a JointForce's value"),
    Field("closure_target", REAL, ("steps", "rows", 3),
          "per closing joints' row: a driven coordinate's (q, q', q''), else 0 "
          "(model/closures.py)"),
)

# Where one chunk's samples are written (solving/consistent_start.py::record_for; read back by
# results/recording.py): the paper's scheme's point velocities, the mass centres' velocities and
# the closing joints' wrenches have slots only where they are recorded.
RECORD_SIZES = (
    ("slots", "the chunk's samples"),
    ("bodies", "n: the kernel model's bodies"),
    ("stations", "2 n + 1"),
    ("modes", "the beams' modal coordinates"),
    ("point_slots", "slots where the paper's scheme's station points are recorded, else 1"),
    ("centre_slots", "slots where the mass centres' velocities are recorded, else 1"),
    ("wrench_slots", "slots where the closing joints' wrenches are recorded, else 1"),
    ("closings", "the closing joints"),
)

RECORD = (
    Field("rot", REAL, ("slots", "bodies", 3, 3), "each body's rotation"),
    Field("omega", REAL, ("slots", "bodies", 3), "angular velocities, rad/s"),
    Field("omega_dot", REAL, ("slots", "bodies", 3), "angular accelerations, rad/s^2"),
    Field("z", REAL, ("slots", "stations", 12), "the stations' states"),
    Field("defl", REAL, ("slots", "bodies", 3), "the elastic hinges' deflections"),
    Field("defl_rate", REAL, ("slots", "bodies", 3), "their rates"),
    Field("eta", REAL, ("slots", "modes"), "the beams' modal coordinates"),
    Field("eta_d", REAL, ("slots", "modes"), "their rates"),
    Field("v_st", REAL, ("point_slots", "bodies+1", 3), "the paper's scheme's station points' "
                                                        "velocities"),
    Field("v_c", REAL, ("centre_slots", "bodies", 3), "the mass centres' velocities (the "
                                                      "energy-momentum scheme)"),
    Field("jq", REAL, ("slots", "bodies", MAX_COORDINATES), "joint coordinates"),
    Field("jqd", REAL, ("slots", "bodies", MAX_COORDINATES), "their rates"),
    Field("jtau", REAL, ("slots", "bodies", MAX_COORDINATES), "their generalized forces"),
    Field("closure_wrench", REAL, ("wrench_slots", "closings", 10),
          "the closing joints' force and couple on side b (world), their drives' generalized "
          "forces and their coordinates' rates"),
)

# The step's local error estimate's memory (docs/solver.md, "Runs that cannot go wrong"): the
# state's pseudo-accelerations before a step, and the run's largest estimate.
MONITOR_SIZES = (
    ("bodies", "n: the kernel model's bodies"),
    ("modes", "the beams' modal coordinates"),
    ("coordinate_bodies", "n where joints have coordinates, else 0"),
    ("elastic_bodies", "n where elastic hinges deflect, else 0"),
)

MONITOR = (
    Field("pseudo", REAL, ("bodies", 3), "the rotations' pseudo-accelerations before a step"),
    Field("eta_p", REAL, ("modes",), "the modal coordinates'"),
    Field("jqp", REAL, ("coordinate_bodies", MAX_COORDINATES), "the joint coordinates'"),
    Field("defl_pseudo", REAL, ("elastic_bodies", 3), "the elastic hinges' deflections'"),
    Field("error", REAL, (2,), "the run's largest local error estimate so far; the failing "
                               "step's"),
)


# The fused loops' own scratch (kernels/stepping/ball_chain.py, tree.py: a chain's and a tree's
# of ball joints; the tree's tables have no rows in a chain's).
FUSED_SIZES = (
    ("bodies", "n: the kernel model's bodies"),
    ("modes", "the beams' modal coordinates"),
    ("work_rows", "rows of beam_ball_map's work block (transfers/beam.py::ball_map_work_shape)"),
    ("work_columns", "its columns"),
    ("tree_bodies", "n in a tree, 0 in a chain"),
)

FUSED = (
    Field("coefficients", REAL, (4,), "c1, c3, 1 / c1, c3 / c1 (w' = c1 phi + w1, "
                                      "w = c3 phi + w3)"),
    Field("per_body", REAL, (4, "bodies", 3), "w1, w3, phi*, phi (the latest solution)"),
    Field("pmap", REAL, ("bodies", 3, 7), "each body's angular acceleration "
                                          "w' = pmap [a_I; q_I; 1]"),
    Field("v", REAL, (6, 7), "one body's reduced map [a_O; q_O] = v [a_I; q_I; 1]"),
    Field("mats", REAL, (7, 3, 3), "T, its numerator, exp(phi^), A*, J_l(phi*), A_n, the "
                                   "ground's relative rotation"),
    Field("vecs", REAL, (5, 3), "w, w', alpha, the load, the ground's increment"),
    Field("per_mode", REAL, (5, "modes"), "w1e, w3e, the offsets' scratch, eta''*, eta''"),
    Field("beam_work", REAL, ("work_rows", "work_columns"), "beam_ball_map's work block"),
    Field("parent", INT, ("tree_bodies",), "the tree's Model.parent"),
    Field("maps", REAL, ("tree_bodies", 6, 7), "every body's map V (the recovery needs them "
                                               "all)"),
    Field("s_in", REAL, ("tree_bodies", 3, 3), "q_I = S_I a_I + P_I"),
    Field("p_in", REAL, ("tree_bodies", 3), "P_I"),
    Field("t_inv", REAL, ("tree_bodies", 3, 3), "T^-1 of each body's Riccati step"),
    Field("port_s", REAL, ("tree_bodies", 3, 3), "q_O = S_O a_O + P_O, summed over the "
                                                 "children"),
    Field("port_p", REAL, ("tree_bodies", 3), "P_O"),
    Field("aq_out", REAL, ("tree_bodies", 6), "every body's output [a; q] (its input's is "
                                              "the sweep's red_aq[k])"),
)

# The welded-chain loop's own scratch (kernels/stepping/weld_chain.py).
WELD_SIZES = (
    ("bodies", "n: the beams"),
    ("modes", "the beams' modal coordinates"),
    ("work", "beam_transfer's work block (transfers/beam.py::transfer_work_size)"),
)

WELD = (
    Field("coefficients", REAL, (4,), "c1, c3, 1 / c1, c3 / c1"),
    Field("per_body", REAL, (4, "bodies", 3), "w1, w3, phi*, phi (the latest solution)"),
    Field("mats", REAL, (7, 3, 3), "scratch: [2], [5] for _update, [6] the ground's increment"),
    Field("vecs", REAL, (5, 3), "w, w', the weld's offset w1_out, zero, the ground's increment"),
    Field("per_mode", REAL, (5, "modes"), "w1e, w3e, the offsets' scratch, eta''*, eta''"),
    Field("stations", REAL, ("bodies+1", 12), "[a, w', m, q] at each body's input, then the "
                                              "tip's output"),
    Field("riccati_s", REAL, ("bodies+1", 6, 6), "the Riccati sweep's S"),
    Field("riccati_p", REAL, ("bodies+1", 6), "its P"),
    Field("riccati_t_inv", REAL, ("bodies", 6, 6), "its T^-1"),
    Field("riccati_t", REAL, ("bodies", 6), "its t"),
    Field("transfer", REAL, (12, 13), "one beam's transfer"),
    Field("transfer_work", REAL, (6, 13), "its work for the Riccati step"),
    Field("root", REAL, (6,), "the ground station's [a, w']"),
    Field("beam_work", REAL, ("work",), "beam_transfer's work block"),
    Field("follow_modal", REAL, (2, "modes"), "eta, eta' at the guess (_follow_welds)"),
    Field("follow_mats", REAL, (3, 3, 3), "A_p*, A*, A* A_n^T"),
    Field("follow_vecs", REAL, (4, 3), "w_p*, w_p'*, w*, w'*"),
    Field("follow_work", REAL, (48,), "_follow_welds' scratch"),
)

# The energy-momentum loop's own scratch (kernels/stepping/em_step.py).
MOMENTUM_SIZES = (
    ("stations", "2 n + 1"),
)

MOMENTUM = (
    Field("z_star", REAL, ("stations", 12), "the stations' guess"),
    Field("root_f", REAL, (6,), "a fixed ground: no displacement, no rotation"),
    Field("rot_new", REAL, (3, 3), "scratch"),
    Field("omega_new", REAL, (3,), "scratch"),
    Field("load", REAL, (3,), "scratch: a body's applied force with its weight"),
)

# The high-order scheme's scratch and tableau (kernels/stepping/runge_kutta.py: DOP853's 12
# stages, the next step's first and three of the dense output, 16 in all).
RUNGE_KUTTA_SIZES = (
    ("bodies", "n: the kernel model's bodies"),
    ("states", "6 n + 2 (modal coordinates): the integrated state's length"),
)

RUNGE_KUTTA = (
    Field("rot0", REAL, ("bodies", 3, 3), "the rotations the step's local coordinates start "
                                          "from"),
    Field("y", REAL, ("states",), "the state at t (theta = 0)"),
    Field("f", REAL, ("states",), "its derivative"),
    Field("y_new", REAL, ("states",), "the state after the step (theta from rot0)"),
    Field("y_stage", REAL, ("states",), "a stage's state, a sample's state"),
    Field("k", REAL, (16, "states"), "the stages' derivatives (12 of the step, the next "
                                     "step's first, three of the dense output)"),
    Field("dense", REAL, (7, "states"), "the step's interpolant (scipy's F)"),
    Field("e3", REAL, (2, 3, 3), "scratch"),
    Field("control", REAL, (8,), "t, h, steps, rejected steps, evaluations, the last step "
                                 "rejected, smallest and largest step"),
    Field("tableau_a", REAL, (16, 16), "DOP853's A (scipy's dop853_coefficients)"),
    Field("tableau_b", REAL, (12,), "its B"),
    Field("tableau_c", REAL, (16,), "its C"),
    Field("error_e3", REAL, (13,), "its E3"),
    Field("error_e5", REAL, (13,), "its E5"),
    Field("dense_d", REAL, (4, 16), "its D"),
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


def size_index(sizes=SIZES):
    """{size name: its index in the flat structure's `size`}."""
    return {name: i for i, (name, _) in enumerate(sizes)}


def table_of(flat, field, buffer, shape, sizes=SIZES):
    """Table `field` (its index in the schema; of `buffer`, of the schema's `shape` in terms of
    `sizes`) of a flat structure as a numpy view of its buffer (a table without axes: its one
    value)."""
    return _view(flat, field, buffer, _dims(shape, size_index(sizes)))


def _dims(shape, index):
    """[(its size's index in `size` or None, constant, plus)] per axis of a schema shape."""
    return [(None if name is None else index[name], constant, plus)
            for name, constant, plus in axes(shape)]


def _view(flat, field, buffer, dims):
    size = flat.size
    extents = tuple(constant if k is None else int(size[k]) + plus for k, constant, plus in dims)
    start = int(flat.start[field])
    return getattr(flat, buffer)[start:start + math.prod(extents)].reshape(extents)[()]


class Layout:
    """One flat structure's schema: its sizes, its fields (tables), the class it packs into
    and the module of its kernels' accessors (generated: `write`)."""

    def __init__(self, title, sizes_name, fields, cls, module):
        self.title, self.fields, self.cls = title, fields, cls
        self.sizes_name, self.sizes = sizes_name, globals()[sizes_name]
        self.generated = Path(__file__).with_name(module)
        self._index = {f.name: i for i, f in enumerate(fields)}
        self._size = size_index(self.sizes)
        self._reads = {f.name: (i, f.buffer, _dims(f.shape, self._size))
                       for i, f in enumerate(fields)}

    def pack(self, **arrays):
        """The flat structure of the tables `arrays` (by their schema names; every field): the
        sizes read from the arrays' shapes (an axis named twice must agree), the tables copied
        into the buffers of that size (zeros) in the schema's order."""
        size = np.full(len(self.sizes), -1, dtype=np.int64)
        missing = [f.name for f in self.fields if f.name not in arrays]
        extra = sorted(set(arrays) - set(self._index))
        if missing or extra:
            raise TypeError(f"pack: missing tables {missing}, unknown tables {extra}")
        values = []
        for f in self.fields:
            a = np.asarray(arrays[f.name])
            dims = axes(f.shape)
            if a.ndim != len(dims):
                raise ValueError(f"pack: {f.name} has shape {a.shape}, the schema says "
                                 f"{f.shape}")
            for extent, (name, constant, plus) in zip(a.shape, dims):
                if name is None:
                    if extent != constant:
                        raise ValueError(f"pack: {f.name} has shape {a.shape}, the schema says "
                                         f"{f.shape}")
                    continue
                value = extent - plus
                if size[self._size[name]] not in (-1, value):
                    raise ValueError(f"pack: {f.name}'s axis {name} is {value}, another "
                                     f"table's is {size[self._size[name]]}")
                size[self._size[name]] = value
            values.append(a)
        size[size < 0] = 0      # (a size no table names)
        flat = self.zeros(**{name: int(v) for (name, _), v in zip(self.sizes, size)})
        for i, (f, a) in enumerate(zip(self.fields, values)):
            buffer = flat.real if f.buffer == REAL else flat.int
            buffer[flat.start[i]:flat.start[i] + a.size] = a.ravel()
        return flat

    def unpack(self, flat):
        """{name: view} of a flat structure's tables (the kernels' accessors' views, for
        Python)."""
        return {f.name: table_of(flat, i, f.buffer, f.shape, self.sizes)
                for i, f in enumerate(self.fields)}

    def table(self, flat, name):
        """Table `name` of a flat structure as a view of its buffer."""
        return _view(flat, *self._reads[name])

    def size(self, flat, name):
        """Size `name` of a flat structure."""
        return int(flat.size[self._size[name]])

    def zeros(self, **sizes):
        """The flat structure of these sizes (by name; every size), its tables zero."""
        size = np.array([sizes[name] for name, _ in self.sizes], dtype=np.int64)
        start = np.zeros(len(self.fields), dtype=np.int64)
        used = {REAL: 0, INT: 0}
        for i, f in enumerate(self.fields):
            start[i] = used[f.buffer]
            used[f.buffer] += math.prod(constant if name is None else sizes[name] + plus
                                        for name, constant, plus in axes(f.shape))
        return self.cls(np.zeros(used[REAL]), np.zeros(used[INT], dtype=np.int64), start, size)

    def copy(self, flat):
        """A flat structure's own copy, of its class (a run's: every array its own, as a
        checkpoint that restores into it or marks it read-only expects)."""
        return type(flat)(*(a.copy() for a in flat))

    def _accessor(self, i, f):
        doc = textwrap.wrap(f"{f.buffer}: {f.doc}", 96, initial_indent="# ",
                            subsequent_indent="# ")
        shape = ", ".join(f'"{a}"' if isinstance(a, str) else str(a) for a in f.shape)
        shape += "," if len(f.shape) == 1 else ""
        return "\n".join(doc + [f'{f.name} = table_view({i}, "{f.buffer}", ({shape}), '
                                f'{self.sizes_name})'])

    def generated_source(self):
        """The accessors' module's text, generated from the layout."""
        text = (f"{self.title} by name: one accessor per field of kernels/schema.py's layout, "
                "each giving, called on the flat structure in a kernel, its table's view of the "
                "buffers, of the schema's shape (kernels/views.py::table_view). Generated by "
                "kernels/schema.py::Layout.write from the schema; do not edit.")
        head = ('"""' + "\n".join(textwrap.wrap(text, 96)) + '"""\n'
                f"from .schema import {self.sizes_name}\n"
                "from .views import table_view\n")
        return head + "".join(f"\n{self._accessor(i, f)}\n" for i, f in enumerate(self.fields))

    def write(self):
        """(Re)write the accessors' module from the layout (schema.write: every layout)."""
        self.generated.write_text(self.generated_source())


class FlatTables(FlatModel):
    """A flat structure Python reads by name: ``flat.stats`` is its layout's table (a view of
    the buffers, kept on the instance after its first read; the kernels read the same table
    through the generated accessors)."""
    layout = None       # (each subclass's Layout)

    def __getattr__(self, name):
        layout = type(self).layout
        if layout is None or name not in layout._reads:
            raise AttributeError(f"{type(self).__name__} has no table {name!r}")
        view = layout.table(self, name)
        if isinstance(view, np.ndarray):
            self.__dict__[name] = view
        return view

    def __reduce__(self):       # (its buffers alone: a copy's views are of its own buffers)
        return (type(self), tuple(self))

    def tables(self):
        """{name: table} of every table of its layout."""
        return {name: getattr(self, name) for name in type(self).layout._index}


class FlatLoops(FlatTables):
    """The closing joints' tables and scratch, flat (LOOPS; the kernels read them through
    kernels/loop_tables.py)."""

    @property
    def rows(self):
        """R: the closing joints' rows (0: no loops)."""
        return int(self.size[0])


class FlatState(FlatTables):
    """The state a run advances, flat (STATE; kernels/state_tables.py)."""


class FlatSweep(FlatTables):
    """The assembly's scratch, flat (SWEEP; kernels/sweep_tables.py)."""


class FlatGeneral(FlatTables):
    """The general loop's own scratch, flat (GENERAL; kernels/general_tables.py)."""


class FlatInputs(FlatTables):
    """One chunk's prescribed data, flat (INPUTS; kernels/input_tables.py)."""

    @property
    def steps(self):
        """m: the chunk's steps."""
        return int(self.size[0])


class FlatRecord(FlatTables):
    """Where one chunk's samples are written, flat (RECORD; kernels/record_tables.py)."""


class FlatMonitor(FlatTables):
    """The step's error estimate's memory, flat (MONITOR; kernels/monitor_tables.py)."""


class FlatFused(FlatTables):
    """The fused ball-chain loop's scratch, flat (FUSED; kernels/fused_tables.py)."""


class FlatFusedTree(FlatFused):
    """The fused ball-tree loop's scratch, flat (FUSED, its tree's tables sized; a class of
    its own: the skeleton's variant is chosen by the scratch's class, loop.py::loop_variant)."""


class FlatWeld(FlatTables):
    """The welded-chain loop's scratch, flat (WELD; kernels/weld_tables.py)."""


class FlatMomentum(FlatTables):
    """The energy-momentum loop's scratch, flat (MOMENTUM; kernels/momentum_tables.py)."""


class FlatRungeKutta(FlatTables):
    """The high-order scheme's scratch and tableau, flat (RUNGE_KUTTA;
    kernels/runge_kutta_tables.py)."""


MODEL_LAYOUT = Layout("The flat model's tables", "SIZES", MODEL, FlatModel, "model_tables.py")
LOOP_LAYOUT = Layout("The closing joints' flat tables and scratch", "LOOP_SIZES", LOOPS,
                     FlatLoops, "loop_tables.py")
STATE_LAYOUT = Layout("The run's flat state", "STATE_SIZES", STATE, FlatState,
                      "state_tables.py")
SWEEP_LAYOUT = Layout("The assembly's flat scratch", "SWEEP_SIZES", SWEEP, FlatSweep,
                      "sweep_tables.py")
GENERAL_LAYOUT = Layout("The general loop's flat scratch", "GENERAL_SIZES", GENERAL, FlatGeneral,
                        "general_tables.py")
FlatLoops.layout, FlatState.layout, FlatSweep.layout = LOOP_LAYOUT, STATE_LAYOUT, SWEEP_LAYOUT
INPUT_LAYOUT = Layout("One chunk's flat inputs", "INPUT_SIZES", INPUTS, FlatInputs,
                      "input_tables.py")
RECORD_LAYOUT = Layout("One chunk's flat record", "RECORD_SIZES", RECORD, FlatRecord,
                       "record_tables.py")
MONITOR_LAYOUT = Layout("The step's flat error monitor", "MONITOR_SIZES", MONITOR, FlatMonitor,
                        "monitor_tables.py")
FlatGeneral.layout, FlatInputs.layout = GENERAL_LAYOUT, INPUT_LAYOUT
FlatRecord.layout, FlatMonitor.layout = RECORD_LAYOUT, MONITOR_LAYOUT
FUSED_LAYOUT = Layout("The fused loops' flat scratch", "FUSED_SIZES", FUSED, FlatFused,
                      "fused_tables.py")
WELD_LAYOUT = Layout("The welded-chain loop's flat scratch", "WELD_SIZES", WELD, FlatWeld,
                     "weld_tables.py")
MOMENTUM_LAYOUT = Layout("The energy-momentum loop's flat scratch", "MOMENTUM_SIZES", MOMENTUM,
                         FlatMomentum, "momentum_tables.py")
RUNGE_KUTTA_LAYOUT = Layout("The high-order scheme's flat scratch", "RUNGE_KUTTA_SIZES",
                            RUNGE_KUTTA, FlatRungeKutta, "runge_kutta_tables.py")
FlatFused.layout = FlatFusedTree.layout = FUSED_LAYOUT
FlatWeld.layout, FlatMomentum.layout = WELD_LAYOUT, MOMENTUM_LAYOUT
FlatRungeKutta.layout = RUNGE_KUTTA_LAYOUT
LAYOUTS = (MODEL_LAYOUT, LOOP_LAYOUT, STATE_LAYOUT, SWEEP_LAYOUT, GENERAL_LAYOUT, INPUT_LAYOUT,
           RECORD_LAYOUT, MONITOR_LAYOUT, FUSED_LAYOUT, WELD_LAYOUT, MOMENTUM_LAYOUT,
           RUNGE_KUTTA_LAYOUT)

pack, unpack = MODEL_LAYOUT.pack, MODEL_LAYOUT.unpack


def write():
    """(Re)write every layout's accessors (kernels/model_tables.py, loop_tables.py,
    state_tables.py, sweep_tables.py, general_tables.py, input_tables.py, record_tables.py,
    monitor_tables.py, fused_tables.py, weld_tables.py, momentum_tables.py,
    runge_kutta_tables.py) after an edit of the schema:
    ``python -c "from dttmm.kernels import schema; schema.write()"``."""
    for layout in LAYOUTS:
        layout.write()
