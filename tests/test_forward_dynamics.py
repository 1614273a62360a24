"""dttmm.forward_dynamics (dttmm/dynamics.py, docs/dynamics.md): the accelerations of any state
at any time by DT-TMM's sweep, against the Newton-Euler reference's right-hand side at the same
state, and against the time step's own accelerations."""
import numpy as np
import pytest

import dttmm
from dttmm import forward_dynamics, simulate, simulate_reference
from dttmm.chains import arm, five_link_tree, rigid_chain, three_pendulum
from dttmm.mechanisms import slider_crank
from dttmm.reference.newton_euler import _Problem
from dttmm.result import rotation_to_quaternion


def _reference_state(prob, state):
    """The reference's state vector y of a state given as forward_dynamics takes it."""
    y = prob.initial_state()
    for k in range(prob.n):
        if prob.q_off[k] >= 0:
            y[prob.q_off[k]:prob.q_off[k] + 4] = rotation_to_quaternion(state["rotation"][k])
            y[prob.w_off[k]:prob.w_off[k] + 3] = state["angular_velocity"][k]
    nm = prob.n_modal
    if nm:
        y[prob.e0:prob.e0 + nm] = state["modal_coordinates"]
        y[prob.e0 + nm:prob.e0 + 2 * nm] = state["modal_velocities"]
    nq = len(prob.coordinates)
    for c in range(nq):
        y[prob.c0 + c] = state["joint_coordinates"][c]
        y[prob.c0 + nq + c] = state["joint_rates"][c]
    return y


def _against_the_reference(model, t):
    """forward_dynamics and the reference's right-hand side at the reference's own state at t
    (mid-run, moving): the largest difference of each acceleration, and their sizes."""
    state = simulate_reference(model, t, t_eval=[0.0, t]).state(-1)
    out = forward_dynamics(model, t, state)
    prob = _Problem(model)
    ref = prob.evaluate(t, _reference_state(prob, state))
    pairs = {"angular": (out["angular_acceleration"], ref[6]),
             "input": (out["input_acceleration"], ref[5]),
             "force": (out["force"], ref[7]), "moment": (out["moment"], ref[8])}
    if model.has_beams:
        pairs["modal"] = (out["modal_acceleration"], ref[9])
    if len(prob.coordinates):
        pairs["joint"] = (out["joint_acceleration"], ref[13])
    return {key: (np.abs(a - b).max(), np.abs(b).max()) for key, (a, b) in pairs.items()}


@pytest.mark.parametrize("name, model, t, tolerance", [
    ("flexible arm", arm("torque", flexible=True), 0.3, 1e-12),
    ("rigid arm under PD", arm("pd"), 0.3, 1e-12),
    ("five-link tree", five_link_tree(), 0.3, 1e-12),
    ("10-link chain", rigid_chain(10), 0.3, 1e-12),
    ("three-pendulum", three_pendulum(stiffening=True), 0.3, 1e-12),
    ("slider-crank", slider_crank(), 0.4, 1e-10)])
def test_forward_dynamics_is_the_reference_right_hand_side(name, model, t, tolerance):
    """At a state the reference reached mid-run (moving, deflected, driven): every body's
    angular and input-point acceleration, its input loads, every joint coordinate's and every
    modal acceleration as the reference's equations give them, to 1e-12 of their size (two
    independent formulations: DT-TMM's transfer sweep at acceleration level and the reference's
    assembled Newton-Euler equations; docs/dynamics.md has the measured values); 1e-10 on the
    slider-crank, whose state closes its loop to the reference's tolerance only (measured
    1e-11)). The flexible arm: revolute, universal and prismatic joints, a beam between them
    (an end section in the kernel model), a torque drive and a spring-damper; the PD arm a
    feedback drive; a tree and a chain of rigid bodies on ball joints; the three-pendulum:
    beams on ball joints with geometric stiffening (the ball joints' moments are 0 in both);
    the slider-crank: a closed loop."""
    compared = _against_the_reference(model, t)
    assert compared["angular"][1] > 1.0                  # (it accelerates)
    for key, (difference, size) in compared.items():
        assert difference <= tolerance * max(size, 1.0), (name, key, difference, size)


def test_forward_dynamics_gives_the_steps_own_accelerations():
    """A Newmark step ends in equilibrium at its new state: the rigid arm's recorded angular
    accelerations after 0.2 s are forward_dynamics' of the recorded state, to the Newton
    iterations' tolerance (measured 2.7e-13 relative)."""
    model = arm("pd")
    result = simulate(model, 0.2, 1e-3)
    out = forward_dynamics(model, 0.2, result.state(-1))
    expected = result.angular_acceleration[-1]
    assert np.abs(out["angular_acceleration"] - expected).max() < 1e-8 * np.abs(expected).max()


def test_forward_dynamics_of_the_initial_state_is_the_consistent_start():
    """Without a state: the model's initial state, as the loops' own start takes it."""
    from dttmm.loop_dynamics import loop_accelerations
    model = slider_crank()
    out = forward_dynamics(model)
    start = loop_accelerations(model)
    np.testing.assert_array_equal(out["angular_acceleration"], start["angular_acceleration"])
    assert np.abs(out["residual"]).max() < 1e-10


def test_forward_dynamics_refuses_a_bad_state():
    model = arm("torque")
    state = simulate(model, 0.01, 1e-3).state(-1)
    with pytest.raises(ValueError, match="no 'velocity'"):
        forward_dynamics(model, 0.01, dict(state, velocity=np.zeros(3)))
    with pytest.raises(ValueError, match=r"state\['angular_velocity'\] must have shape"):
        forward_dynamics(model, 0.01, dict(state, angular_velocity=np.zeros(3)))
    with pytest.raises(ValueError, match="is not finite"):
        forward_dynamics(model, 0.01, dict(state, joint_rates=np.full(5, np.nan)))
    turned = state["rotation"].copy()
    turned[1] = turned[1] @ np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])
    with pytest.raises(ValueError, match="off what its joint"):
        forward_dynamics(model, 0.01, dict(state, rotation=turned))
    with pytest.raises(ValueError, match="is not a rotation"):
        forward_dynamics(model, 0.01, dict(state, rotation=2.0 * state["rotation"]))
    spun = state["angular_velocity"].copy()
    spun[2] += 1.0
    with pytest.raises(ValueError, match="angular_velocity of body"):
        forward_dynamics(model, 0.01, dict(state, angular_velocity=spun))
    with pytest.raises(ValueError, match="finite time"):
        forward_dynamics(model, np.inf)
    with pytest.raises(ValueError, match="must be a Model"):
        forward_dynamics("arm")
    assert dttmm.forward_dynamics is forward_dynamics


@pytest.mark.parametrize("name, model", [
    ("three-pendulum", three_pendulum(stiffening=True)),
    ("flexible arm", arm("torque", flexible=True))])
def test_any_integrator_runs_the_sweeps_equations(name, model):
    """dttmm.ode: scipy's DOP853 on the sweep's accelerations (quaternions for the free
    rotations) follows the reference over 0.2 s, every body's rotation, the joint and modal
    coordinates within 1e-8 (both at rtol 1e-11; measured 4e-15 and 4e-16 in the rotations)."""
    from scipy.integrate import solve_ivp
    system = dttmm.ode(model)
    assert len(system.names) == len(system.y0)
    sol = solve_ivp(system.fun, (0.0, 0.2), system.y0, method="DOP853", rtol=1e-11,
                    atol=1e-12)
    assert sol.success
    rotation, _ = system.frames(0.2, sol.y[:, -1])
    ref = simulate_reference(model, 0.2, t_eval=[0.0, 0.2], rtol=1e-11, atol=1e-12)
    assert np.abs(rotation - ref.rotation[-1]).max() < 1e-8
    state = system.state(sol.y[:, -1])
    for key in ("joint_coordinates", "modal_coordinates"):
        value = getattr(ref, key)
        if value is not None:
            assert np.abs(state[key] - value[-1]).max() < 1e-8, key
    with pytest.raises(ValueError, match="closed loops"):
        dttmm.ode(slider_crank())
