"""Assembly: the closest configuration, to the model's joint coordinates, rotations and modal
coordinates, that closes every loop (docs/loops.md, "Assembly"), by Gauss-Newton on the
closing joints' rows (loop_kinematics.py::closure_residuals).  In the model layer (docs/README.md,
"Layout"): it builds an assembled Model from the user's, with numpy alone."""
import numpy as np

from .loop_rows import constraint_rows
from .loop_kinematics import (AssemblyWarning, _coordinates, _start_values, _state_of,
                              check_drives_move, closure_residuals)
from ..elements.kinds import COORDINATE_0, GAP_A, GAP_WORLD, RATE_0
from ..elements.rigid_body import TO_OUTPUT
from .model import adopt_arrays


def assemble(model, keep=(), tol=1e-12, max_iterations=30):
    """Close every loop at t = 0 (docs/loops.md, "Assembly"): move the tree's coordinates the
    least (in the least-squares sense) that makes every closing joint hold, then the rates the
    least that makes the loops' velocities consistent.

    Parameters
    ----------
    model : Model
        A model with closing joints (``System.close``); one without is returned as it is.
    keep : sequence of str, optional
        Joints (or their bodies, by name) whose coordinates and rates are given and stay: a
        crank's angle and rate.  A prescribed motion's coordinates always stay.
    tol : float, optional
        The residual the closure must reach, m and rad (default 1e-12, times the model's
        reach in metres where that is above 1).
    max_iterations : int, optional
        Gauss-Newton iterations for the positions (default 30).

    Returns
    -------
    Model
        The same model with its initial rotations, angular velocities and joint coordinates
        and rates moved onto the loops (``loop_residuals`` reports what is left).

    Raises
    ------
    ValueError
        A loop that cannot close (a rod too short, a kept coordinate that forbids it), naming
        the closing joint and its remaining gap; keep naming nothing of the model.

    Examples
    --------
    >>> import dttmm
    >>> assembled = dttmm.assemble(model, keep=["crank"])  # doctest: +SKIP
    >>> dttmm.loop_residuals(assembled)  # doctest: +SKIP
    """
    from dataclasses import replace
    if model.n_closures == 0:
        return model
    check_drives_move(model, "assemble")
    variables, kept = _coordinates(model, keep)
    x = _start_values(model, variables)
    xd = np.array([model.hinge_params[k, RATE_0.start + i] if what == "q"
                   else model.initial_angular_velocity[k, i] for what, k, i in variables])
    free = np.nonzero(~kept)[0]
    scale = max(1.0, float(np.abs(model.body_params[:, TO_OUTPUT]).sum()))
    limit = tol * scale

    def residual(values):
        return closure_residuals(model, _state_of(model, variables, values, xd))[0]

    rows = constraint_rows(model)
    metres = np.isin(rows.kind, (GAP_WORLD, GAP_A))     # gaps in m; the rest are angles

    def gaps(g):
        """(largest gap in m, largest in rad) of the residuals g."""
        return (float(np.abs(g[metres]).max(initial=0.0)),
                float(np.abs(g[~metres]).max(initial=0.0)))

    start = _state_of(model, variables, x, xd)
    g = closure_residuals(model, start)[0]
    history = [np.abs(g).max()]
    first = best = gaps(g)
    step = 1e-7
    for _ in range(max_iterations):
        if history[-1] <= limit:
            break
        jac = np.zeros((g.size, free.size))
        for j, col in enumerate(free):
            up, down = x.copy(), x.copy()
            up[col] += step
            down[col] -= step
            jac[:, j] = (residual(up) - residual(down)) / (2 * step)
        x[free] -= np.linalg.pinv(jac, rcond=1e-10) @ g
        g = residual(x)
        history.append(np.abs(g).max())
        if history[-1] < max(best):
            best = gaps(g)
        if len(history) > 6 and history[-1] > 0.5 * history[-6]:
            break                               # stalled: the loop cannot close
    owner = rows.owner
    if history[-1] > limit:
        worst = int(owner[np.argmax(np.abs(g))])
        left = gaps(g)
        raise ValueError(f"assemble: closing joint '{model.closure_names[worst]}' cannot close: "
                         f"after {len(history) - 1} iterations a gap of {left[0]:.4g} m and "
                         f"{left[1]:.4g} rad is left (at the start {first[0]:.4g} m and "
                         f"{first[1]:.4g} rad; the smallest reached {best[0]:.4g} m and "
                         f"{best[1]:.4g} rad); the loop's bodies cannot reach (a link too short "
                         f"or too long, a pivot out of reach), or a kept coordinate forbids it")
    # the rates: the loops' velocity residual is linear in them, g' = G xd + g'_0
    def rate_residual(rates):
        return closure_residuals(model, _state_of(model, variables, x, rates))[1]
    gd = rate_residual(xd)
    if free.size and np.abs(gd).max() > limit:
        jac = np.zeros((gd.size, free.size))
        for j, col in enumerate(free):
            unit = xd.copy()
            unit[col] += 1.0
            jac[:, j] = rate_residual(unit) - gd
        xd[free] -= np.linalg.pinv(jac, rcond=1e-10) @ gd
        gd = rate_residual(xd)
    if np.abs(gd).max() > 1e-9 * max(1.0, float(np.abs(xd).max()) * scale):
        worst = int(owner[np.argmax(np.abs(gd))])
        raise ValueError(f"assemble: the kept rates move closing joint "
                         f"'{model.closure_names[worst]}' apart at {np.abs(gd).max():.4g} (m/s or "
                         f"rad/s); keep fewer rates")
    end = _state_of(model, variables, x, xd)
    rot, w = end[:2]
    hinge = np.array(model.hinge_params, order="C")
    for (what, k, i), value, rate in zip(variables, x, xd):
        if what == "q":
            hinge[k, COORDINATE_0.start + i], hinge[k, RATE_0.start + i] = value, rate
        assembled = adopt_arrays(replace(model, initial_rotation=rot, initial_angular_velocity=w,
                                     hinge_params=hinge), model)
    moves = assembly_moves(start, end)
    object.__setattr__(assembled, "_assembly_moves", moves)
    _warn_of_moves(model, moves, scale)
    return assembled


MOVE_TOLERANCE = 0.01   # of the model's reach (m), and rad: assemble warns of a body moved more


def assembly_moves(start, end):
    """(n, 2): how far assemble moved each body, the largest displacement of its input and
    output points (m) and the angle of its rotation (rad), between two tree_states."""
    moved = np.maximum(np.linalg.norm(end[2] - start[2], axis=1),
                       np.linalg.norm(end[6] - start[6], axis=1))
    turn = np.einsum("kij,kij->k", end[0], start[0])        # trace(A_end A_start^T)
    angle = np.arccos(np.clip(0.5 * (turn - 1.0), -1.0, 1.0))
    return np.column_stack([moved, angle])


def _warn_of_moves(model, moves, reach):
    """AssemblyWarning naming the bodies assemble moved beyond MOVE_TOLERANCE x reach (m) or
    MOVE_TOLERANCE rad: 1% of the mechanism's size changes its geometry visibly (a pivot in
    the wrong place), where the rounding of hand-given coordinates (three or four digits) stays
    well below it."""
    far = [k for k in range(model.n_bodies)
           if moves[k, 0] > MOVE_TOLERANCE * reach or moves[k, 1] > MOVE_TOLERANCE]
    if not far:
        return
    import warnings
    said = ", ".join(f"'{model.body_names[k]}' {moves[k, 0]:.3g} m and {moves[k, 1]:.3g} rad"
                     for k in far[:6]) + (f" and {len(far) - 6} more" if len(far) > 6 else "")
    warnings.warn(f"assemble: closing the loops moved bodies beyond {MOVE_TOLERANCE:g} of the "
                  f"model's reach ({MOVE_TOLERANCE * reach:.3g} m) or {MOVE_TOLERANCE:g} rad: "
                  f"{said}; the mechanism simulated is not the one given: place the bodies "
                  f"where the loops close, or keep=[...] the coordinates that are right",
                  AssemblyWarning, stacklevel=3)
