"""Steps and records: chunks of steps, the samples kept, Richardson extrapolation of runs, and
the Result built from a recording (docs/solver.md, "Steps and records")."""
from typing import NamedTuple

import numpy as np

from . import adaptive as adaptive_steps
from ..kernels.stepping import step as kstep
from ..elements.kinds import MAX_COORDINATES
from ..model.loop_rows import has_closure_drives
from ..model.model import model_fact
from ..results.recording import NoCheckpoint
from ..results.contact_states import contact_states
from ..results.result import (DERIVED, FIELDS, Result, chain_energies, stop_forces,
                              stopped_columns)
from .run_tables import (column_names, coordinate_columns)
from .run_checks import (_check_count, _check_positive)
from .run_inputs import (_points, _zeros, nearest_rotations)


def _set_step(loop, h, coef):
    """A new step in the loop variant's step-dependent constants (an adaptive run's segment;
    the skeleton's pieces take h itself from Settings): the fused loops' (c1, c3, 1/c1, c3/c1)
    and the general loop's ground d(w')/d(phi) = c1 I (kernels/stepping/step.py::general_loop)."""
    if isinstance(loop, kstep.GeneralLoop):
        loop.scratch.ground_dwd[...] = kstep._coefficients_py(h, coef)[0] * np.eye(3)
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
                "closure_drive_force", "limit_force", "contact_force", "contact_point",
                "contact_normal", "kinetic", "potential")
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


CONTACT_FIELDS = ("contact_force", "contact_point", "contact_normal")   # (derived when read)


class _ResultFacts(NamedTuple):
    """What every Result of a model holds whatever the run (_result_facts)."""
    body_names: tuple           # Result.body_names
    has_modes: bool             # modal coordinates recorded (beams or strain rods)
    coordinate_columns: object  # (k, i) -> the flat columns of the recorded (T, n * 3) jq,
    #                             jqd, jtau (None without joints with coordinates)
    closure_drives: bool        # closure_drive_force recorded
    has_stops: bool             # end stops on some joint coordinate (Result.limit_force)
    coordinate_names: tuple     # info's column names (run_tables.column_names)
    modal_names: tuple


@model_fact
def _result_facts(model):
    """A model's _ResultFacts, kept on it (a short run's fixed cost: ~10 us a call)."""
    columns = coordinate_columns(model)
    names = column_names(model)
    return _ResultFacts(
        body_names=tuple(model.body_names), has_modes=bool(model.n_modes.any()),
        coordinate_columns=(np.array([k * MAX_COORDINATES + i for k, i in columns], np.int64)
                            if columns else None),
        closure_drives=has_closure_drives(model),
        has_stops=bool(stopped_columns(model)),
        coordinate_names=tuple(names["coordinate_names"]),
        modal_names=tuple(names["modal_names"]))


def _result(model, recording, h, wall, n_steps, info, checkpoint=None):
    """The Result of a run's recording: the stored state as recorded; positions, velocities and
    energies left to _derived, computed when first read."""
    facts = _result_facts(model)
    values = recording.arrays()
    t = (np.asarray(recording.times) if recording.times
         else np.asarray(recording.steps, dtype=float) * h)
    rot, omega, eta, eta_d = values["rot"], values["omega"], values["eta"], values["eta_d"]
    joints = {}
    if "jq" in values and facts.coordinate_columns is not None:   # (T, n, MAX_COORDINATES)
        for name, key in (("joint_coordinates", "jq"), ("joint_rates", "jqd"),    # -> (T, C)
                          ("drive_force", "jtau")):
            recorded = np.asarray(values[key])
            joints[name] = np.take(recorded.reshape(len(recorded), -1),
                                   facts.coordinate_columns, axis=1)
        if facts.has_stops:     # the end stops' forces (not in drive_force: docs/limits.md)
            joints["limit_force"] = stop_forces(model, joints["joint_coordinates"],
                                                joints["joint_rates"])
    if "closure_wrench" in values:
        joints["closure_force"] = values["closure_wrench"][:, :, :3]
        joints["closure_moment"] = values["closure_wrench"][:, :, 3:6]
        if facts.closure_drives:
            joints["closure_drive_force"] = values["closure_wrench"][:, :, 6:8]
    derived = {}

    def derivation(name):
        """The points' positions and velocities, and (when asked) the energies from them."""
        if "defl" not in values:            # (not recorded without joints that offset)
            values["defl"] = values["defl_rate"] = _zeros(rot.shape[:2] + (3,))
        if not derived:
            derived.update(_points(model, t, rot, omega, values["defl"], values["defl_rate"],
                                   eta, eta_d, values.get("v_st"), values.get("v_c")))
        if name in CONTACT_FIELDS and "contact_force" not in derived:
            derived.update(contact_states(model, rot, omega, derived["position_input"],
                                          derived["velocity_input"]))
        if name in ("kinetic", "potential") and "kinetic" not in derived:
            ground_r, _, ground_rot, _ = model.ground_states(t)
            derived["kinetic"], derived["potential"] = chain_energies(
                model, rot, omega, derived["position_input"], derived["velocity_input"],
                values["defl"], ground_rotation=ground_rot, eta=eta, eta_dot=eta_d,
                joint_coordinates=joints.get("joint_coordinates"), ground_position=ground_r)
        return derived

    loads = values["z"]                     # every body's input [m; q]
    info = dict(info, coordinate_names=list(facts.coordinate_names),    # (each Result's own
                modal_names=list(facts.modal_names))                    # lists)
    return Result._of_run(derivation, method="dttmm", t=t, rotation=rot, angular_velocity=omega,
                          angular_acceleration=values["omega_dot"], force=loads[:, :, 3:6],
                          moment=loads[:, :, 0:3], wall_time=wall, n_steps=n_steps, info=info,
                          modal_coordinates=eta if facts.has_modes else None,
                          modal_velocities=eta_d if facts.has_modes else None,
                          body_names=facts.body_names, checkpoint=checkpoint,
                          lazy=CONTACT_FIELDS if len(model.contacts) else (), **joints)
