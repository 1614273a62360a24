"""Adaptive steps (docs/solver.md, "Adaptive steps"): simulate(model, t_end, rtol=...) against
a tight, independent reference (the Newton-Euler equations under DOP853 at rtol 1e-12): the
error shrinks in proportion to rtol over three decades and stays within 10x of it (rad and m:
the motions here are of order one radian and one metre); the steps it takes (rejected ones
counted) are no more than 1.5x those of the fixed step reaching the same error; the last step
lands on t_end and on the times asked for; the divergence cases adapt instead of blowing up."""
import numpy as np
import pytest

from dttmm import DivergenceError, simulate, simulate_reference
from dttmm.model.chains import arm, rigid_chain, three_pendulum

T_END = 1.0
RTOLS = (1e-4, 1e-5, 1e-6, 1e-7)


@pytest.fixture(scope="module", params=["three_pendulum", "chain30"])
def case(request):
    model = three_pendulum() if request.param == "three_pendulum" else rigid_chain(30)
    ref = simulate_reference(model, T_END, rtol=1e-12, atol=1e-14, t_eval=[0.0, T_END])
    return request.param, model, ref.position_output[-1]


def _error(run, tip):
    return float(np.abs(run.position_output[-1] - tip).max())


def test_the_error_follows_rtol_over_three_decades(case):
    """Measured (m) at rtol 1e-4 .. 1e-7: three-pendulum 1.0e-5, 9.8e-7, 9.1e-8, 8.2e-9;
    30-link chain 2.8e-5, 4.0e-6, 3.8e-7, 4.0e-8: 0.08-0.4 rtol, slopes 1.03 and 0.96."""
    name, model, tip = case
    errors = [_error(simulate(model, T_END, rtol=rtol, t_eval=[T_END]), tip) for rtol in RTOLS]
    slope = np.polyfit(np.log(RTOLS), np.log(errors), 1)[0]
    print(name, ["%.2e" % e for e in errors], slope)
    assert all(e <= 10 * rtol for e, rtol in zip(errors, RTOLS))
    assert 0.8 < slope < 1.3, slope


def test_the_adaptive_run_takes_no_more_steps_than_the_fixed_step_of_equal_error(case):
    """Steps (rejected ones counted) against the fixed step reaching the same error, the fixed
    step's error interpolated as C dt^2 from its two nearest runs: at most 1.5x (the wall-time
    ratio, which adds ~45 us of Python per segment of up to 256 steps, is
    benchmarks/adaptive.py's).  Measured: three-pendulum 1247 / 992 (rtol 1e-4), 9043 / 8277
    (1e-6); 30-link chain 732 / 644, 5822 / 5551."""
    name, model, tip = case
    fixed_dts = (2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4)
    fixed = [(_error(simulate(model, T_END, dt, t_eval=[T_END]), tip), T_END / dt)
             for dt in fixed_dts]
    for rtol in (1e-4, 1e-6):
        run = simulate(model, T_END, rtol=rtol, t_eval=[T_END])
        err = _error(run, tip)
        # the fixed run of the same error: steps n with error c / n^2, c from the nearest run
        e_fix, n_fix = min(fixed, key=lambda p: abs(np.log(p[0] / err)))
        n_equal = n_fix * np.sqrt(e_fix / err)
        taken = run.n_steps + run.info["steps_rejected"]
        print(name, rtol, taken, round(n_equal))
        assert taken <= 1.5 * n_equal


def test_the_last_step_lands_on_t_end_and_the_asked_times():
    model = three_pendulum()
    times = [0.013, 0.25, 0.5, 0.7]
    run = simulate(model, 0.7, rtol=1e-4, t_eval=times)
    np.testing.assert_array_equal(run.t, [0.0] + times)
    run = simulate(model, 0.7, rtol=1e-4, record_dt=0.1)
    np.testing.assert_allclose(run.t, np.arange(8) * 0.1, rtol=0, atol=1e-15)
    assert run.t[-1] == 0.7
    run = simulate(model, 0.7, rtol=1e-4)                   # default: bounded samples, the end
    assert run.t[-1] == 0.7 and 2 < len(run.t) <= 1001
    assert np.all(np.diff(run.t) > 0)
    assert run.info["dt"] is None and run.info["dt_min"] <= run.info["dt_max"]


def test_the_divergence_cases_adapt_their_step():
    """The 3-link chain that a fixed dt = 0.5 s blows up (energy to 1.8e31 J) runs through from
    a first step of 0.5 s with rtol, rejecting the first segments, and keeps its energy; the
    chain spun at 100 rad/s from dt = 1e-2 likewise."""
    run = simulate(rigid_chain(3), 5.0, 0.5, rtol=1e-4)
    assert run.info["steps_rejected"] >= 1 and run.info["dt_max"] < 0.5
    e = run.total_energy
    assert np.abs(e - e[0]).max() < 1e-3 * run.kinetic.max()
    from test_divergence import _spinning_chain
    run = simulate(_spinning_chain(), 0.2, 1e-2, rtol=1e-5)
    e = run.total_energy
    assert run.info["steps_rejected"] >= 1 and abs(e[-1] - e[0]) < 1e-5 * e[0]


def test_prescribed_motions_and_drives_are_taken_at_the_adaptive_times():
    """The flexible arm driven by a prescribed joint motion (the general loop, inputs evaluated
    per segment at its own times): adaptive at rtol 1e-4 within rtol of a fixed-step run at
    dt = 2.5e-5 (measured 6.9e-7 m in 884 steps).  Its estimate is dominated by the link's
    unresolved high modes (it goes as h^2, not h^3), which makes the steps small at tight
    tolerances (rtol 1e-5: 7531 steps, 5.6e-9 m)."""
    model = arm("motion", flexible=True)
    fine = simulate(model, 0.3, 2.5e-5, t_eval=[0.3])
    run = simulate(model, 0.3, rtol=1e-4, t_eval=[0.3])
    assert _error(run, fine.position_output[-1]) < 1e-4


def test_a_moving_ground_is_taken_at_the_adaptive_times():
    """A two-link chain hanging from a hub spun up at 2 rad/s^2 (ground motion evaluated per
    segment): adaptive at rtol 1e-5 within 1e-5 m of a fixed-step run at dt = 2.5e-5."""
    from dttmm import BallJoint, FixedHinge, Ground, PrescribedMotion, build_chain
    from dttmm.model.chains import unit_link
    hub = PrescribedMotion.spin_about_axis([0, 1, 0], lambda t: t * t, lambda t: 2.0 * t,
                                           lambda t: 2.0)
    model = build_chain([FixedHinge(), unit_link(), BallJoint(), unit_link()],
                        ground=Ground(motion=hub))
    fine = simulate(model, 1.0, 2.5e-5, t_eval=[1.0])
    run = simulate(model, 1.0, rtol=1e-5, t_eval=[1.0])
    assert _error(run, fine.position_output[-1]) < 1e-5


def test_a_step_that_cannot_be_made_small_enough_stops():
    """A torque growing without bound: the adaptive run shrinks its step until it falls below
    1e-12 of t_end and stops with DivergenceError, keeping its samples."""
    from dttmm import BallJoint, build_chain
    from dttmm.model.chains import unit_link
    spinning = unit_link(torque=lambda t: [0.0, 0.0, 1e300 * t * t])
    with pytest.raises(DivergenceError, match="adaptive steps: the step fell below") as err:
        simulate(build_chain([BallJoint(), spinning]), 1.0, rtol=1e-4)
    assert err.value.partial is not None


@pytest.mark.parametrize("kwargs, message", [
    (dict(record_every=2), "record_every"),
    (dict(scheme="energy_momentum"), "scheme"),
    (dict(richardson=True), "richardson"),
    (dict(atol=-1.0), "atol"),
    (dict(rtol=0.0), "rtol"),
])
def test_what_adaptive_steps_refuse(kwargs, message):
    kwargs = dict(dict(rtol=1e-4), **kwargs)
    with pytest.raises(ValueError, match=message):
        simulate(rigid_chain(2), 1.0, **kwargs)
    with pytest.raises(ValueError, match="give the step dt"):
        simulate(rigid_chain(2), 1.0)
