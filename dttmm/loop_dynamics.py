"""DT-TMM's accelerations of a model with closed loops at t = 0: the consistent start with the
closing joints' multipliers (kernels/closure.py; docs/loops.md, "The sweep with closing
joints"), as a function of the model for checks and users.
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
        ``angular_acceleration`` (n, 3, rad/s^2), ``input_acceleration`` (n, 3, m/s^2, each
        body's input point), ``joint_acceleration`` (n, 2: each joint coordinate's), the
        multipliers ``multipliers`` (R,) and the rows' residual ``residual`` (R,, m/s^2 or
        rad/s^2) after the solve.

    Raises
    ------
    ValueError
        Loops the time step does not close yet (beams, elastic hinges, a moving ground).
    """
    from . import solver
    from .kernels.closure import row_residuals
    from .kernels.loop import Monitor, Settings
    if model.n_closures and not model.tip_pinned:
        solver.check_runs_in_sweeps(model, "loop_accelerations")
    km, keep = solver.kernel_model(model)
    mode = solver._mode(km, "riccati", True)
    settings = Settings(mode=mode, h=1.0, coef=solver.Integrator.from_rho_inf(1.0).array(),
                        newton_max=0, newton_tol=0.0, record_every=1, max_step_error=np.inf,
                        stop_unconverged=False, start=False)
    n = km.n_bodies
    monitor = Monitor(pseudo=np.zeros((n, 3)), eta_p=np.zeros(int(km.n_modes.sum())),
                      jqp=np.zeros((n, 2)), defl_pseudo=np.zeros((0, 3)), error=np.zeros(2))
    ws = solver.Workspace(km)
    params = solver.kernel_params(km)
    loops = solver.loop_tables(km)
    solver._consistent_start(km, mode, "riccati", None, params, settings, ws.state, ws.sweep,
                             monitor, 1.0, loops)
    st = ws.state
    residual = np.zeros(len(loops.kind))
    if len(loops.kind):
        row_residuals(loops, st.z, residual)
    return {"input_acceleration": st.z[2 * keep + 1, 0:3].copy(),
            "angular_acceleration": st.z[2 * keep + 1, 3:6].copy(),
            "joint_acceleration": st.jqdd[keep].copy(), "multipliers": loops.lam.copy(),
            "residual": residual}
