"""simulate(..., richardson=True): the extrapolation (4 y_dt/2 - y_dt) / 3 of two Newmark runs.
The trapezoidal rule's global error expands in even powers of dt, so the extrapolated result
must converge at fourth order against the independent Newton-Euler reference (fitted slope of
log error against log dt), where the plain runs converge at second order."""
import numpy as np
import pytest
from helpers import fitted_order

from dttmm import BallJoint, DivergenceError, build_chain, simulate
from dttmm.solving import run_inputs
from dttmm.model.chains import rigid_chain, three_pendulum, unit_link
from dttmm.reference import simulate_reference
from dttmm.results.result import beam_midpoint_deflection
from dttmm.solving import run_tables

DTS = (5e-3, 2.5e-3, 1.25e-3)


@pytest.fixture(scope="module")
def chain_and_reference():
    model = rigid_chain(5)
    t = np.linspace(0.0, 1.0, 11)
    return model, simulate_reference(model, 1.0, method="DOP853", rtol=1e-12, atol=1e-14,
                                     t_eval=t)


@pytest.mark.parametrize("fused", [True, False])
@pytest.mark.parametrize("rho_inf", [1.0, 0.8])
def test_rigid_chain_fourth_order(chain_and_reference, monkeypatch, fused, rho_inf):
    """5 swinging links over 1 s, both time loops.  Measured: slope 4.0 at rho_inf 1 and 0.8
    (errors 1.4e-5 -> 3.4e-9 m from dt = 1e-2), against 2.0 for the plain runs."""
    model, ref = chain_and_reference
    monkeypatch.setattr(run_tables, "FUSED_BALL_CHAIN", fused)
    errors, plain_errors = [], []
    for dt in DTS:
        res = simulate(model, 1.0, dt, rho_inf=rho_inf, richardson=True,
                       record_every=int(round(0.1 / dt)))
        plain = simulate(model, 1.0, dt / 2, rho_inf=rho_inf, record_every=int(round(0.2 / dt)))
        assert np.allclose(res.t, ref.t, rtol=0.0, atol=1e-12)
        assert res.info["richardson"] and res.n_steps == 3 * int(round(1.0 / dt))
        errors.append(np.abs(res.position_output - ref.position_output).max())
        plain_errors.append(np.abs(plain.position_output - ref.position_output).max())
        # the correction made is the dt/2 run's error, to leading order
        assert 0.8 < res.info["richardson_correction_m"] / plain_errors[-1] < 1.25
        # the rotations stay rotations, and they converge with the positions
        rt_r = np.einsum("tkji,tkjl->tkil", res.rotation, res.rotation)
        assert np.abs(rt_r - np.eye(3)).max() < 1e-12
        assert np.allclose(np.linalg.det(res.rotation), 1.0, atol=1e-12)
        assert np.abs(res.rotation - ref.rotation).max() < 3.0 * errors[-1]
    assert 3.7 < fitted_order(DTS, errors) < 4.3, errors
    assert 1.8 < fitted_order(DTS, plain_errors) < 2.2, plain_errors
    assert errors[-1] < plain_errors[-1] / 100.0


def test_beam_chain_fourth_order():
    """The three-pendulum with one mode per plane over 0.5 s: body positions and the beam's
    mid-point deflection.  Measured: slope 4.0 on both (9.9e-8 -> 3.9e-10 m for the positions).
    (With two modes per plane the second mode's frequency keeps dt = 1e-3 .. 2.5e-4 out of the
    asymptotic range: the orders there are 1.3 to 3.6.)"""
    model = three_pendulum(1)
    t = np.linspace(0.0, 0.5, 11)
    ref = simulate_reference(model, 0.5, method="DOP853", rtol=1e-12, atol=1e-13, t_eval=t)
    mid_ref = beam_midpoint_deflection(model, ref, 1)
    dts = (1e-3, 5e-4, 2.5e-4)
    pos, mid = [], []
    for dt in dts:
        res = simulate(model, 0.5, dt, richardson=True, record_every=int(round(0.05 / dt)))
        pos.append(np.abs(res.position_output - ref.position_output).max())
        mid.append(np.abs(beam_midpoint_deflection(model, res, 1) - mid_ref).max())
    assert 3.7 < fitted_order(dts, pos) < 4.3, pos
    assert 3.7 < fitted_order(dts, mid) < 4.3, mid


def test_end_time_not_a_multiple_of_dt():
    """Both runs stop on t_end, with n = ceil(t_end / dt) equal steps of t_end / n and twice as
    many of half that, and record together."""
    res = simulate(rigid_chain(2), 0.1, 0.03, richardson=True)
    assert np.allclose(res.t, [0.0, 0.025, 0.05, 0.075, 0.1], atol=1e-15)
    assert res.info["dt_runs"] == (0.025, 0.0125)


def test_bad_input():
    with pytest.raises(ValueError, match="richardson=True needs scheme='newmark'"):
        simulate(rigid_chain(2), 0.1, 0.01, scheme="energy_momentum", richardson=True)


def test_divergence_names_the_run():
    """A run that cannot go on stops with the step, the time and which of the two runs."""
    spinning = unit_link(torque=lambda t: [0.0, 0.0, 1e300 * t])
    runaway = build_chain([BallJoint(), unit_link(), BallJoint(), spinning])
    with pytest.raises(DivergenceError, match=r"in the Richardson run at dt = 0\.01 s"):
        simulate(runaway, 1.0, 0.01, richardson=True)


def test_energy_drift_fourth_order():
    """The chain conserves energy; the extrapolated result's largest drift over 1 s falls at
    fourth order (measured: 2.1e-5, 1.25e-6, 7.5e-8 J of a 121 J peak kinetic energy, slope 4.1),
    where the dt/2 run's falls at second order (2.3e-3 .. 1.4e-4 J)."""
    model = rigid_chain(5)
    drifts = []
    for dt in DTS:
        res = simulate(model, 1.0, dt, richardson=True, record_every=int(round(0.05 / dt)))
        drifts.append(np.abs(res.total_energy - res.total_energy[0]).max())
    assert 3.7 < fitted_order(DTS, drifts) < 4.5, drifts
    assert drifts[-1] < 1e-6 * res.kinetic.max()


# (the warning: the 50 ms run)
@pytest.mark.filterwarnings("ignore::dttmm.solving.solver.UnresolvedMotionWarning")
@pytest.mark.parametrize("runs, dts, low, high", [
    (3, (2e-2, 1e-2, 5e-3), 5.6, 6.5),
    (4, (5e-2, 2.5e-2, 1.25e-2), 7.0, 8.8)])
def test_romberg_gives_orders_six_and_eight(runs, dts, low, high):
    """richardson=3 and 4: Romberg's rule on the even powers of the step over runs at dt,
    dt/2, dt/4 (, dt/8), each iterated to newton_tol (the implicit trapezoidal rule on the
    rotation group is symmetric; the one-linearization step is not quite: 5.3 with three runs).
    5-link chain over 1 s against the reference at rtol 1e-13: measured 5.97 (5.3e-8 -> 1.3e-11
    m) and 7.5 (6.2e-8 -> 1.8e-12 m, the last near the reference's floor; its coarsest run,
    at 50 ms, turns a link 0.56 rad per step and warns so)."""
    model = rigid_chain(5)
    t = np.linspace(0.0, 1.0, 11)
    ref = simulate_reference(model, 1.0, method="DOP853", rtol=1e-13, atol=1e-15, t_eval=t)
    errors = []
    for dt in dts:
        res = simulate(model, 1.0, dt, richardson=runs, newton_iterations=8, newton_tol=1e-14,
                       record_every=int(round(0.1 / dt)))
        assert res.info["richardson_runs"] == runs and len(res.info["dt_runs"]) == runs
        errors.append(np.abs(res.position_output - ref.position_output).max())
    assert low < fitted_order(dts, errors) < high, errors


def test_extrapolation_is_stable_at_steps_far_above_a_stiff_beams_periods():
    """The stiff cantilever of examples/stability.py (20 welded elements, shortest period
    0.1 ms) released under gravity, at dt = 10 ms (100x that period) for 2 s: every run of
    the trapezoidal rule stays bounded whatever the step, so their extrapolation does; three
    runs (order 6 where the step resolves the motion) follow a run at dt = 1e-4 to 5.7e-4 m at
    the tip (the plain run at 10 ms: 5.6e-3 m; the tip swings 0.31 m), with the energy held to
    1e-6 J."""
    from dttmm.model.chains import stiff_cantilever
    model = stiff_cantilever(20)
    shortest = 1.0 / np.max(dttmm_frequencies(model))
    dt = 0.01
    assert dt > 90 * shortest
    fine = simulate(model, 2.0, 1e-4, record_every=500)
    plain = simulate(model, 2.0, dt, newton_iterations=8, record_every=5)
    res = simulate(model, 2.0, dt, richardson=3, newton_iterations=8, record_every=5)
    tip = lambda r: r.position_output[:, -1, 1]                     # noqa: E731
    error, plain_error = (np.abs(tip(r) - tip(fine)).max() for r in (res, plain))
    assert error < 1e-3 and error < plain_error / 5, (error, plain_error)
    assert np.abs(res.total_energy - res.total_energy[0]).max() < 1e-5


def dttmm_frequencies(model):
    from dttmm import static_equilibrium
    return static_equilibrium(model).frequencies


def test_a_scene_takes_the_number_of_runs(tmp_path):
    """[run] richardson = 3 in a scene file: three runs, as simulate(richardson=3)."""
    from importlib import resources
    from dttmm.interfaces.scene import SceneError, load_scene
    text = (resources.files("dttmm.interfaces") / "scenes" / "rigid_chain.toml").read_text()
    path = tmp_path / "chain.toml"
    path.write_text(text.replace("dt = 0.001", "dt = 0.01\nrichardson = 3"))
    scene = load_scene(path)
    run = dict(scene.run, t_end=0.1)
    assert simulate(scene.model, **run).info["richardson_runs"] == 3
    path.write_text(text.replace("dt = 0.001", "dt = 0.01\nrichardson = \"three\""))
    with pytest.raises(SceneError, match="richardson"):
        load_scene(path)


def test_nearest_rotations_is_the_polar_factor():
    """The extrapolated rotations are projected by Newton-Schulz near a rotation and by the
    SVD far from one: both the polar factor U V^T of numpy's SVD, to rounding."""
    rng = np.random.default_rng(3)
    q = np.linalg.qr(rng.standard_normal((200, 3, 3)))[0]
    q *= np.sign(np.linalg.det(q))[:, None, None]           # rotations
    for scale in (0.0, 1e-9, 1e-5, 1e-2, 0.3):
        m = q + scale * rng.standard_normal(q.shape)
        u, _, vt = np.linalg.svd(m)
        polar = u @ vt
        proper = np.linalg.det(polar) > 0                    # (a reflection: no rotation near)
        near = run_inputs.nearest_rotations(m)
        assert np.abs(near - polar)[proper].max() < 1e-13, scale
        assert np.abs(np.swapaxes(near, 1, 2) @ near - np.eye(3)).max() < 1e-14, scale
        assert np.all(np.linalg.det(near) > 0)


def test_the_combined_result_reads_as_any_other():
    """The Richardson Result combines its fields when first read: its info and fields are those
    of the combination however they are reached (read, replaced, pickled)."""
    import pickle
    model = rigid_chain(3)
    coarse, fine = (simulate(model, 0.1, dt, record_every=k) for dt, k in ((1e-2, 1), (5e-3, 2)))
    res = simulate(model, 0.1, 1e-2, richardson=True)
    expected = (4.0 * fine.position_output - coarse.position_output) / 3.0
    for copy in (res.replace(method="copied"), pickle.loads(pickle.dumps(res)), res):
        assert copy.info["richardson_runs"] == 2 and copy.info["dt_runs"] == (1e-2, 5e-3)
        assert copy.info["richardson_correction_m"] == pytest.approx(
            np.abs(expected - fine.position_output).max(), rel=1e-12)
        assert np.abs(copy.position_output - expected).max() < 1e-15
        with pytest.raises(ValueError):
            copy.position_output[0, 0, 0] = 1.0
