"""DT-TMM's accelerations of a model with closed loops at t = 0: the consistent start with the
closing joints' multipliers (kernels/assembly/closure.py; docs/loops.md, "The sweep with closing
joints"): dttmm.forward_dynamics of the model's initial state, its joint accelerations per
joint (n, MAX_COORDINATES).
"""
import numpy as np


def loop_accelerations(model):
    """DT-TMM's accelerations at t = 0 of a model with closing joints (the module docstring).

    Parameters
    ----------
    model : Model
        An assembled model (``dttmm.assemble``) whose closing joints join rigid bodies or the
        ground (beams in loops: not yet).

    Returns
    -------
    dict
        ``angular_acceleration`` (n, 3, rad/s^2), ``input_acceleration`` (n, 3, m/s^2, each body's
        input point), ``joint_acceleration`` (n, 3: each joint coordinate's; 0 past a joint's own),
        the multipliers ``multipliers`` (R,) and the rows' residual ``residual`` (R,, m/s^2 or
        rad/s^2) after the solve.

    Raises
    ------
    ValueError
        Loops the time step does not close yet (beams, elastic hinges, a moving ground).
    """
    from .dynamics import forward_dynamics
    from .run_tables import coordinate_columns
    out = forward_dynamics(model)
    from ..elements.kinds import MAX_COORDINATES
    joints = np.zeros((model.n_bodies, MAX_COORDINATES))
    for c, (k, i) in enumerate(coordinate_columns(model)):
        joints[k, i] = out["joint_acceleration"][c]
    return {"input_acceleration": out["input_acceleration"],
            "angular_acceleration": out["angular_acceleration"],
            "joint_acceleration": joints, "multipliers": out["multipliers"],
            "residual": out["residual"]}
