"""What a run can be refused for, and why one stopped: the checks before a run (check_supported,
the schemes and sweeps that run a model), the errors and warnings a run raises, and the causes
and hints its messages give (docs/solver.md, "Failure", "Runs that cannot go wrong")."""
import math

import numpy as np

from ..elements import BEAM, ROD
from ..elements.kinds import BODY_KIND, JOINT_KIND, WITH_COORDINATES
from ..elements.beam import (CLAMPED_LOADED, EXACT, FAMILY, LENGTH,
                             MODES, STIFFENING, TORSION_MODES, end_shapes)
from ..elements.hinges import (BALL, ELASTIC, FIXED, FREE)
from ..kernels.assembly import solve as ksolve
from ..kernels.stepping import step as kstep
from ..kernels.stepping.loop import (ERROR_ESTIMATE, UNCONVERGED)
from ..kernels.assembly.sweep import DIRECT_TOLERANCE, LOST_ACCURACY
from ..model.assembly import assemble
from ..model.closures import check_runs_in_sweeps
from ..model.loop_kinematics import check_drives_move, loop_residuals
from ..model.model import model_fact
from .energy_balance import does_work
from .run_tables import (free_ball_tree, full_tree, has_coordinates, has_loops, kernel_model)


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
    iterate to newton_tol by default (without iterations a flexible link there is not stable);
    so do contacts, whose forces are evaluated at the guess.  Asked of the kernels' model
    (kernel_model: an end section is welded to its beam)."""
    model = kernel_model(model)[0]
    if has_loops(model):            # closing joints: their rows converge with the iterations
        return True
    if len(model.contacts):         # contacts: their forces (docs/contact.md, "In the step")
        return True
    return has_coordinates(model) or (full_tree(model, full_state) and any(
        model.hinge_kind[k] == FIXED and model.parent[k] >= 0
        and model.body_kind[model.parent[k]] == BEAM for k in range(model.n_bodies)))


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


class UserFunctionError(ValueError):
    """A user's function (a load, a drive, the ground's motion) failed or returned a value
    that is not finite during a run (simulate turns it into DivergenceError with the step)."""

    def __init__(self, t, message):
        super().__init__(message)
        self.t = float(t)


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


@model_fact
def check_supported(model, scheme, method="riccati", full_state=False):
    """Refuse, before a run, what the solver does not implement for this model: an element
    kind whose declaration (elements/kinds.py) does not list the scheme; the energy-momentum
    and paper's schemes need a fixed ground; trees and joints with coordinates run (so far) with
    the Newmark scheme and the Riccati sweep (_check_full_tree, _check_tree); closed loops of
    rigid bodies and beams (closures.check_runs_in_sweeps)."""
    check_runs_in_sweeps(model, "simulate", moving_ground=True)
    if len(model.contacts) and scheme != "newmark":
        raise ValueError(f"simulate(scheme={scheme!r}): the model's bodies have contact shapes "
                         f"(docs/contact.md), whose law is in the Newmark step's iterations: "
                         f"use scheme='newmark'")
    if scheme == "dop853":
        _check_runge_kutta(model, method, full_state)
    if has_loops(model) and (scheme != "newmark" or method != "riccati"):
        raise ValueError(f"simulate: closed loops run with scheme='newmark' and "
                         f"method='riccati' so far, got scheme={scheme!r}, method={method!r}")
    if scheme == "dop853" and free_ball_tree(model):
        pass                            # (the reduced tree sweep, free roots: _mode)
    elif full_tree(model, full_state):
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
    chains and trees of rigid bodies and beams on ball joints (bending modes only), their roots
    on the ground or on free joints from it, on a fixed ground with gravity alone (its compiled
    stages evaluate no function of the user's)."""
    where = "simulate(scheme='dop853')"
    joint = next((k for k in range(model.n_bodies) if model.hinge_kind[k] != BALL
                  and not (model.hinge_kind[k] == FREE and model.parent[k] < 0)), None)
    locked = next((k for k in range(model.n_bodies) if model.ground_locked[k]), None)
    why = ("the model has closed loops" if has_loops(model) or model.tip_pinned
           else f"hinge '{model.hinge_names[joint]}' is "
                f"{JOINT_KIND[int(model.hinge_kind[joint])].what} (ball joints only, and "
                f"free joints from the ground)"
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


_DIRECT_HINT = ("method='direct' multiplies the transfer matrices out and loses all accuracy on "
                "long or stiff chains; use method='riccati'")


def _singular_cause(model, mode, status, where):
    """status: j + 1 for element j of the full-state sweeps (2k: hinge k, 2k + 1: body k), or
    k + 1 for body k of the reduced sweeps; past the last element: the tip's equations."""
    j = status - 1
    reduced = mode in (ksolve.RICCATI_REDUCED, ksolve.DIRECT_REDUCED, ksolve.RICCATI_TREE)
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
    offsets = model.mode_offsets
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
