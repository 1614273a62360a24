"""The high-order scheme (simulate(scheme="dop853"); kernels/stepping/runge_kutta.py,
docs/integrators.md): Dormand-Prince 8(5,3) on the rotation group, compiled with the fused
loops' acceleration sweep.  Its order against the Newton-Euler reference, its error against
rtol, its rotations, its energy, its dense output, and scipy's DOP853 on dttmm.ode."""
import numpy as np
import pytest

import dttmm
from dttmm import simulate, simulate_reference
from dttmm.model.chains import binary_tree, rigid_chain, stiff_cantilever, three_pendulum, unit_link
from dttmm.model.mechanisms import n_four_bar

_REFERENCE = {}


def _reference(name, model, t_end):
    """The reference at rtol = atol = 1e-13 (its error ~1e-14 m here), once per test run."""
    key = (name, t_end)
    if key not in _REFERENCE:
        _REFERENCE[key] = simulate_reference(model, t_end, rtol=1e-13, atol=1e-13)
    return _REFERENCE[key]


def _tip_error(result, reference):
    return float(np.abs(result.position_output[-1] - reference.position_output[-1]).max())


@pytest.mark.parametrize("name, make, t_end, steps", [
    ("3-link chain", lambda: rigid_chain(3), 1.0, (0.2, 0.1, 0.05)),
    ("three-pendulum", lambda: three_pendulum(), 0.5, (0.005, 0.0025, 0.00125))])
def test_the_order_is_eight_against_the_reference(name, make, t_end, steps):
    """Fixed steps (dt without rtol): the tip's error at t_end against the reference falls as
    h^p with p fitted over three steps at least 6.5 (DOP853's order is 8; measured 8.2 on the
    chain, 7.1 and 8.1 between the three-pendulum's pairs; the issue asks at least 5)."""
    model = make()
    reference = _reference(name, model, t_end)
    errors = [_tip_error(simulate(model, t_end, h, scheme="dop853", record_every=10 ** 6),
                         reference) for h in steps]
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert slope > 6.5, (errors, slope)


@pytest.mark.parametrize("name, make, t_end", [
    ("3-link chain", lambda: rigid_chain(3), 1.0),
    ("three-pendulum", lambda: three_pendulum(), 0.5)])
def test_the_error_follows_rtol(name, make, t_end):
    """Steps chosen by the embedded estimate: the tip's error at t_end within 2 rtol at rtol =
    1e-6, 1e-8, 1e-10 (atol = rtol / 100; measured 0.18 rtol on the chain, 3e-4 rtol on the
    three-pendulum, whose stiff beams hold its steps below their stability limit), every
    rotation orthogonal to 1e-14, and the steps and evaluations counted in info."""
    model = make()
    reference = _reference(name, model, t_end)
    for rtol in (1e-6, 1e-8, 1e-10):
        result = simulate(model, t_end, rtol=rtol, atol=rtol / 100, scheme="dop853")
        assert _tip_error(result, reference) < 2 * rtol, rtol
        rot = result.rotation
        assert np.abs(np.einsum("tkji,tkjl->tkil", rot, rot) - np.eye(3)).max() < 1e-14
        assert result.info["loop"] == "runge-kutta (ball-chain)"
        assert result.info["evaluations"] >= 12 * result.n_steps
        assert len(result.t) == 1001 and result.t[-1] == t_end


def test_dense_output_and_the_reference_agree_between_steps():
    """The default samples (1000, far more than the ~30 steps) come from the steps' dense
    output of order 7: every sample of the 3-link chain's tip within 2 rtol of the reference at
    the same times (rtol 1e-9), and the recorded angular accelerations are the sweep's at the
    sampled state (forward_dynamics: 1e-12)."""
    model = rigid_chain(3)
    result = simulate(model, 1.0, rtol=1e-9, atol=1e-11, scheme="dop853")
    assert result.n_steps < 100
    reference = simulate_reference(model, 1.0, t_eval=result.t, rtol=1e-13, atol=1e-13)
    assert np.abs(result.position_output - reference.position_output).max() < 2e-9
    i = 437
    accelerations = dttmm.forward_dynamics(model, result.t[i], result.state(i))
    assert np.abs(accelerations["angular_acceleration"]
                  - result.angular_acceleration[i]).max() < 1e-12


def test_the_energy_and_the_rotations_hold_over_a_long_spin():
    """A 5-link chain swinging and spinning for 20 s at rtol 1e-9: the total energy within
    1e-7 of the largest kinetic energy (rtol-scaled: measured 1.5e-9) and every rotation
    orthogonal to 1e-14 at the end (the local coordinates are recentred every step)."""
    model = rigid_chain(5, tip_angular_velocity=(0.0, 3.0, 2.0))
    result = simulate(model, 20.0, rtol=1e-9, atol=1e-11, scheme="dop853")
    energy = result.total_energy
    assert np.abs(energy - energy[0]).max() < 1e-7 * result.kinetic.max()
    rot = result.rotation[-1]
    assert np.abs(np.einsum("kji,kjl->kil", rot, rot) - np.eye(3)).max() < 1e-14


def test_trees_run_and_follow_the_reference():
    """A binary tree of 7 unit links (the fused tree loop's sweep): the tip positions within
    1e-8 m of the reference after 1 s at rtol 1e-10."""
    model = binary_tree(3)
    result = simulate(model, 1.0, rtol=1e-10, atol=1e-12, scheme="dop853", t_eval=[0.5, 1.0])
    reference = simulate_reference(model, 1.0, t_eval=[0.0, 0.5, 1.0], rtol=1e-13, atol=1e-13)
    assert result.info["loop"] == "runge-kutta (ball-tree)"
    assert np.abs(result.position_output - reference.position_output).max() < 1e-8


def test_scipys_dop853_on_dttmm_ode_gives_the_same_trajectory():
    """The same method on the same equations by two routes: scipy's DOP853 on dttmm.ode's
    right-hand side (quaternions) and the compiled scheme (local rotation vectors), at rtol
    1e-10: the three-pendulum's tip and modal coordinates agree within 1e-8 after 0.2 s."""
    from scipy.integrate import solve_ivp
    model = three_pendulum()
    system = dttmm.ode(model)
    sol = solve_ivp(system.fun, (0.0, 0.2), system.y0, method="DOP853", rtol=1e-10,
                    atol=1e-12)
    ours = simulate(model, 0.2, rtol=1e-10, atol=1e-12, scheme="dop853", t_eval=[0.2])
    state = system.state(sol.y[:, -1])
    assert np.abs(state["modal_coordinates"] - ours.modal_coordinates[-1]).max() < 1e-8
    rotation, _ = system.frames(0.2, sol.y[:, -1])
    assert np.abs(rotation - ours.rotation[-1]).max() < 1e-8


def test_a_second_run_is_bitwise_and_a_run_that_cannot_step_says_why():
    """A rerun of the same model gives the same numbers (its prepared run kept); an explicit
    step far beyond the stiff beams' stability limit stops at once with the step, the time
    and the cause, not NaN samples."""
    model = three_pendulum()
    a = simulate(model, 0.05, rtol=1e-7, scheme="dop853")
    b = simulate(model, 0.05, rtol=1e-7, scheme="dop853")
    np.testing.assert_array_equal(a.position_output, b.position_output)
    with pytest.raises(dttmm.DivergenceError, match="dop853: an acceleration is not finite"):
        simulate(model, 0.5, 0.05, scheme="dop853")


@pytest.mark.parametrize("make, kwargs, words", [
    (lambda: stiff_cantilever(3), {}, ["hinge", "fixed hinge", "ball joints"]),
    (lambda: n_four_bar(1), {}, ["closed loops"]),
    (lambda: dttmm.build_chain([dttmm.BallJoint(), unit_link(force=lambda t: [0, 0, 1.0])]),
     {}, ["applied loads"]),
    (lambda: rigid_chain(2), {"rho_inf": 0.5}, ["rho_inf"]),
    (lambda: rigid_chain(2), {"richardson": True}, ["richardson"]),
    (lambda: rigid_chain(2), {"method": "direct"}, ["method='direct'"]),
])
def test_what_the_scheme_does_not_run_is_refused_naming_it(make, kwargs, words):
    with pytest.raises(ValueError) as err:
        simulate(make(), 0.1, 1e-3, scheme="dop853", **kwargs)
    for word in words:
        assert word in str(err.value), str(err.value)


def test_describe_says_which_schemes_run_a_model():
    """describe() lists the schemes that run the model (the table of methods, each checked
    against it) and the one for tight tolerances."""
    line = rigid_chain(3).describe().splitlines()[-1]
    assert "dop853" in line and "scheme='dop853' with rtol" in line
    line = stiff_cantilever(3).describe().splitlines()[-1]
    assert "dop853" not in line and "richardson=3" in line
