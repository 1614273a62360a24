"""What Python evaluates for the kernels at given times: the prescribed ground motion, the applied
loads, the joints' drives; and the points and frames of the bodies from a recorded state
(docs/solver.md, "Steps and records")."""
import functools

import numpy as np

from ..vectors import cross
from ..elements import BEAM, RIGID
from ..elements._checks import is_text
from ..elements.drives import (FORCE, MOTION, PD, known_force, runs_in_loop)
from ..elements.kinds import MAX_COORDINATES
from ..elements.rigid_body import TO_MASS_CENTER, TO_OUTPUT
from ..model.sections import (element_output_offset,
                            point_positions)
from .run_tables import _sum_before
from .run_checks import UserFunctionError


def _joint_inputs(model, times, state=None, dt=0.0):
    """(len(times), n, MAX_COORDINATES, 3): per joint coordinate, a prescribed motion's
    (q, q', q''), a drive's force known in time (elements/drives.py::known_force) and a JointForce's
    value f(t, q, q') at each time (kernels/stepping/loop.py::Inputs).  A JointForce of the state is
    evaluated at the coordinates the constant-acceleration predictor gives from the state (one step
    ahead of it: the solver then takes one step per chunk); docs/joints.md, "In the transfer"."""
    out = np.zeros((len(times), model.n_bodies, MAX_COORDINATES, 3))
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
    mode_off = model.mode_offsets
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
