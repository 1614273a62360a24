"""dttmm.forward_dynamics (dttmm/solving/dynamics.py, docs/dynamics.md): the accelerations of any
state at any time by DT-TMM's sweep, against the Newton-Euler reference's right-hand side at the
same state, and against the time step's own accelerations."""
import numpy as np
import pytest

import dttmm
from dttmm import forward_dynamics, simulate, simulate_reference
from dttmm.model.chains import arm, five_link_tree, rigid_chain, three_pendulum
from dttmm.model.mechanisms import slider_crank
from dttmm.reference.newton_euler import _Problem
from dttmm.results.result import rotation_to_quaternion
from helpers import joints_arm


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
    from dttmm.solving.loop_dynamics import loop_accelerations
    model = slider_crank()
    out = forward_dynamics(model)
    start = loop_accelerations(model)
    np.testing.assert_array_equal(out["angular_acceleration"], start["angular_acceleration"])
    assert np.abs(out["residual"]).max() < 1e-10



def test_a_kept_workspace_gives_a_new_ones_result_bit_for_bit():
    """A model keeps forward_dynamics' workspace (dynamics.py::_Evaluation, its arrays put back
    to their fresh values before each call): calls at interleaved states, and calls from two
    threads at once (one of them on a workspace of its own), give what a copy of the model that
    never evaluated anything gives, bit for bit."""
    import pickle
    import threading
    for model in (arm(drive="motion"), slider_crank()):
        run = simulate(model, 0.02, 1e-3)
        samples = (3, 12, 3, 20)
        kept = [forward_dynamics(model, float(run.t[i]), run.state(i)) for i in samples]
        fresh = [forward_dynamics(pickle.loads(pickle.dumps(model)), float(run.t[i]),
                                  run.state(i)) for i in samples]
        threaded = {}

        def evaluate(i):
            threaded[i] = forward_dynamics(model, float(run.t[i]), run.state(i))
        threads = [threading.Thread(target=evaluate, args=(i,)) for i in (12, 20)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        for a, b in zip(kept + [threaded[12], threaded[20]], fresh + [fresh[1], fresh[3]]):
            for key in a:
                assert np.array_equal(np.asarray(a[key]), np.asarray(b[key])), key


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


def _hanging_chain(n, length=1.0, mass=1.0):
    """n uniform rods on ball joints hanging straight down (gravity -y), at rest."""
    down = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # body x along -y
    system = dttmm.System(gravity=[0.0, -9.81, 0.0])
    for i in range(n):
        system.add(dttmm.RigidBody(mass=mass, inertia=[1e-4, mass * length ** 2 / 12,
                                                        mass * length ** 2 / 12],
                                   inertia_about="mass_center", to_mass_center=[0.5 * length, 0, 0],
                                   to_output=[length, 0, 0], rotation=down, name=f"rod{i}"),
                   dttmm.BallJoint(), parent=None if i == 0 else f"rod{i - 1}")
    return system.build()


def _chain_matrices(n):
    """The hanging chain of n unit rods' small swings in one plane, angles from the vertical:
    mass centre j at sum_{i<j} th_i + th_j / 2 sideways, so M = a^T a + I / 12 (a_ji = 1 for
    i < j, 1/2 for i = j), and K = g diag(1/2 + n - 1 - i)."""
    a = np.tril(np.ones((n, n)), -1) + 0.5 * np.eye(n)
    return a.T @ a + np.eye(n) / 12.0, 9.81 * np.diag(0.5 + np.arange(n - 1, -1, -1.0))


@pytest.mark.parametrize("n", [2, 3])
def test_linearize_gives_the_hanging_chains_frequencies_and_response(n):
    """About the hanging chain of n uniform rods: A's eigenvalues are +-i w for the closed
    form's squared frequencies (_chain_matrices; each twice, one per swing plane), equal to
    static_equilibrium's; a torque about z on the top rod accelerates the swing angles by
    M^-1 e_1 (B); turning the top rod about z moves every output point by e_z x (0, -1, 0)
    (C)."""
    model = _hanging_chain(n)
    lin = dttmm.linearize(model)
    assert lin.A.shape == (12 * n // 2, 12 * n // 2) and lin.B.shape == (6 * n, 6 * n)
    assert lin.C.shape == (3 * n, 6 * n) and len(lin.states) == 6 * n
    assert lin.difference_error < 1e-9
    mass_matrix, stiffness = _chain_matrices(n)
    exact = np.sort(np.linalg.eigvals(np.linalg.solve(mass_matrix, stiffness)).real)
    squared = np.sort(-(np.linalg.eigvals(lin.A) ** 2).real)
    assert np.abs(squared[:2 * n]).max() < 1e-6                 # the rods' spins: no stiffness
    np.testing.assert_allclose(squared[2 * n:], np.repeat(exact, 4), rtol=1e-7)
    statics = np.sort(dttmm.static_equilibrium(model).squared_frequencies)
    np.testing.assert_allclose(statics[n:], np.repeat(exact, 2), rtol=1e-7)
    torque_z = lin.inputs.index("rod0.mz")
    rows = [lin.states.index(f"rod{i}.thz'") for i in range(n)]
    unit = np.zeros(n)
    unit[0] = 1.0
    np.testing.assert_allclose(lin.B[rows, torque_z], np.linalg.solve(mass_matrix, unit),
                               rtol=1e-7)
    turn = lin.states.index("rod0.thz")
    np.testing.assert_allclose(lin.C[:, turn], np.tile([1.0, 0.0, 0.0], n), atol=1e-8)


def test_linearize_the_arm_as_the_reference_equations_difference():
    """The rigid arm (revolute, revolute, universal, prismatic joints: its states are its
    joint coordinates and rates, as the reference's) mid-run under its torque: A equals the
    central differences of the reference's right-hand side at the same state (to 1e-6 of its
    largest entry), and joint 1's torque input is the torque about its axis (world y) on link
    1."""
    model = arm("torque")
    ref = simulate_reference(model, 0.3, t_eval=[0.0, 0.3])
    state = ref.state(-1)
    lin = dttmm.linearize(model, state, 0.3)
    prob = _Problem(model)
    y = _reference_state(prob, state)
    jac = np.zeros((len(y), len(y)))
    for j in range(len(y)):
        step = np.zeros(len(y))
        step[j] = 1e-6
        jac[:, j] = (prob.rhs(0.3, y + step) - prob.rhs(0.3, y - step)) / 2e-6
    assert lin.A.shape == jac.shape
    assert np.abs(lin.A - jac).max() < 1e-6 * np.abs(jac).max()
    np.testing.assert_allclose(lin.B[:, lin.inputs.index("joint1.torque0")],
                               lin.B[:, lin.inputs.index("link1.my")], rtol=0, atol=1e-9)


def _arm_across(extra=None):
    """chains.arm("torque") (2 sin(pi t) N m on joint 1, gravity) with its prismatic joint
    sliding across link 3 (axis y of link 3, so that the slide's line misses link 3's mass
    centre) and its spring-damper (50 N/m, 0.5 N s/m) as a JointForce law of the slide that
    adds the force `extra`, N (None: the SpringDamper itself)."""
    from dttmm import JointForce, RigidBody
    return joints_arm(JointForce(lambda t, q, qd: 2.0 * np.sin(np.pi * t)),
                      slide_axis=(0.0, 1.0, 0.0), slide_position=0.1,
                      slide=None if extra is None else JointForce(
                          lambda t, q, qd: -50.0 * q - 0.5 * qd + extra),
                      body4=RigidBody(mass=0.5, inertia=[0.01, 0.02, 0.03],
                                      inertia_about="mass_center",
                                      to_mass_center=[0.1, 0.0, 0.05], name="body4"))


def test_linearize_a_slide_force_as_the_joints_own_drive():
    """Issue 31: linearize's input on a prismatic joint (a force along the slide, on one line
    through the child's input point, equal and opposite on the parent) has the response of
    the joint's own drive: on the arm with its slide across link 3 (the line misses both
    mass centres, so each side's moment counts), its B column equals the central difference
    of the reference's joint accelerations (its own equations and drive evaluation) over a
    drive that adds +-1e-4 N to the slide's spring, to 1e-7 of the column, mid-run where every
    link moves."""
    model = _arm_across()
    state = simulate(model, 0.3, 1e-3, record_every=300).state(-1)
    lin = dttmm.linearize(model, state, 0.3)
    column = lin.B[:, lin.inputs.index("joint4.force")]
    m = len(lin.states) // 2
    problems = [_Problem(_arm_across(f)) for f in (1e-4, -1e-4)]
    acc = [prob.evaluate(0.3, _reference_state(prob, state))[13] for prob in problems]
    expected = (acc[0] - acc[1]) / 2e-4
    assert np.abs(column[:m]).max() == 0.0
    assert np.abs(expected).max() > 1.0                 # (the slide and the links answer)
    np.testing.assert_allclose(column[m:], expected, rtol=0, atol=1e-7 * np.abs(expected).max())


def test_linearize_the_cantilever_with_a_tip_mass_at_its_sag():
    """A steel cantilever with a 0.2 kg tip mass (tests/test_auto_modes.py's), linearized about
    its static equilibrium under gravity (static_equilibrium's model): its squared frequencies
    are static_equilibrium's (to 1e-6) and the first within 1% of the frequency equation's
    1 + cos b cosh b + r b (cos b sinh b - sin b cosh b) = 0."""
    from scipy.optimize import brentq
    e, rho, a, length, tip = 210e9, 7850.0, 0.01, 1.0, 0.2
    ei, mu = e * a ** 4 / 12.0, rho * a * a
    model = dttmm.build_chain([
        dttmm.FixedHinge(),
        dttmm.EulerBernoulliBeam(length=length, bending_stiffness=ei, mass_per_length=mu,
                                 polar_inertia_per_length=rho * a ** 4 / 6.0, name="steel"),
        dttmm.FixedHinge(),
        dttmm.RigidBody(mass=tip, inertia=[1e-9] * 3, inertia_about="mass_center",
                        to_mass_center=[0, 0, 0], to_output=[0, 0, 0])],
        gravity=[0.0, -9.81, 0.0])
    eq = dttmm.static_equilibrium(model)
    lin = dttmm.linearize(eq.model)
    squared = np.sort(-(np.linalg.eigvals(lin.A) ** 2).real)[::2]
    statics = np.sort(np.real(eq.squared_frequencies))
    np.testing.assert_allclose(squared, statics, rtol=1e-6)
    r = tip / (mu * length)
    root = brentq(lambda b: 1 + np.cos(b) * np.cosh(b)
                  + r * b * (np.cos(b) * np.sinh(b) - np.sin(b) * np.cosh(b)), 0.5, 1.875)
    exact = root ** 2 * np.sqrt(ei / mu) / length ** 2
    assert abs(np.sqrt(squared[0]) / exact - 1.0) < 0.01


@pytest.mark.slow
def test_the_lqr_example_quiets_the_flexible_link(capsys):
    """examples/control.py over 1.5 s: the LQR designed on dttmm.linearize, run in closed
    loop by DT-TMM, leaves the tip less than half PD's deflection after 1 s (measured over 2 s:
    0.14 against 0.61 mm) and ends nearer the command."""
    import re
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
    import control
    assert control.main(["--t-end", "1.5"]) == 0
    text = capsys.readouterr().out
    late = [float(x) for x in re.findall(r"after 1 s ([0-9.]+) mm", text)]
    end = [float(x) for x in re.findall(r"angle at the end ([0-9.]+) rad", text)]
    assert len(late) == 2 and len(end) == 2, text
    assert late[1] < 0.5 * late[0], text
    assert abs(end[1] - 0.5) < abs(end[0] - 0.5), text


def _flexible_arm(extra=(0.0, 0.0, 0.0, 0.0)):
    """chains.arm("torque", flexible=True) (link 2 the paper's beam 4 between joint 2, a
    revolute joint, and joint 3, a universal joint), with generalized forces `extra` added on
    joint 2's angle and joint 3's two angles as JointForces of time (N m), and extra[3] as the
    beam's end force along world x (N)."""
    from dttmm import (EulerBernoulliBeam, JointForce, PrismaticJoint, RevoluteJoint,
                       RigidBody, SpringDamper, System, UniversalJoint)
    from dttmm.model.chains import unit_link
    side, area = 0.02, 0.02 ** 2
    system = System(gravity=(0.0, -9.81, 0.0))
    system.add(unit_link(name="link1"), RevoluteJoint(
        axis=[0, 1, 0], rate=0.5, drive=JointForce(lambda t, q, qd: 2.0 * np.sin(np.pi * t)),
        name="joint1"))
    system.add(EulerBernoulliBeam(length=1.0, density=3300.0, area=area,
                                  bending_stiffness=2.5e10 * side ** 4 / 12.0,
                                  polar_inertia_per_length=3300.0 * area * side * side / 6.0,
                                  modes_per_plane=1, name="link2",
                                  end_force=lambda t: [extra[3], 0.0, 0.0]),
               RevoluteJoint(axis=[0, 0, 1], name="joint2",
                             drive=JointForce(lambda t, q, qd: extra[0])), parent="link1")
    system.add(unit_link(name="link3"), UniversalJoint(
        axis1=[0, 0, 1], axis2=[0, 1, 0], name="joint3",
        drives=(JointForce(lambda t, q, qd: extra[1]),
                JointForce(lambda t, q, qd: extra[2]))),
        parent="link2")
    system.add(RigidBody(mass=0.5, inertia=[0.01, 0.01, 0.01], inertia_about="mass_center",
                         name="body4"),
               PrismaticJoint(axis=[1, 0, 0], name="joint4", drive=SpringDamper(50.0, 0.5)),
               parent="link3")
    return system.build()


def test_linearize_the_joints_next_to_a_beam_as_the_reference():
    """Issue 31: a joint's torque input acts between the joint's two frames, also where a beam
    is the joint's child (joint 2, at the beam's root) or its parent (joint 3, at the beam's
    end section), which body loads cannot express (a beam's load acts at its output end).  On
    the flexible arm mid-run, without drives on joints 2 and 3, each such column of B equals
    the central difference of the reference's right-hand side (its independent Newton-Euler
    equations, its own evaluation of the drives) over JointForces of +-1e-3 N m added on that
    angle: every joint and modal acceleration, to 1e-8 of the column.  And a beam's force
    input is its end force (at its output end section), as the reference's end_force."""
    model = _flexible_arm()
    ref = simulate_reference(model, 0.3, t_eval=[0.0, 0.3])
    state = ref.state(-1)
    lin = dttmm.linearize(model, state, 0.3)
    m = len(lin.states) // 2
    n_q = len(state["joint_coordinates"])
    names = ("joint2.torque0", "joint3.torque0", "joint3.torque1", "link2.fx")
    for which, name in enumerate(names):
        accelerations = []
        for sign in (1.0, -1.0):
            extra = np.zeros(4)
            extra[which] = sign * 1e-3
            prob = _Problem(_flexible_arm(tuple(extra)))
            out = prob.evaluate(0.3, _reference_state(prob, state))
            accelerations.append(np.concatenate([out[13], out[9]]))
        expected = (accelerations[0] - accelerations[1]) / 2e-3
        column = lin.B[:, lin.inputs.index(name)]
        rows = [lin.states.index(s) for s in lin.states[m:]
                if s.startswith(("joint", "eta"))]
        assert len(rows) == n_q + len(state["modal_coordinates"])
        assert np.abs(expected).max() > 0.1, name       # (the arm answers)
        np.testing.assert_allclose(column[rows], expected, rtol=0,
                                   atol=1e-8 * np.abs(expected).max(), err_msg=name)


def test_linearize_a_closed_loop_in_its_independent_coordinate():
    """Issue 31: the N-four-bar (n = 2: two closing revolute joints, redundant spatial rows of a
    planar loop) moving, 0.7 rad from upright at 1.3 rad/s: its linear model lives in one
    coordinate, the first bar's joint angle (the dependent ones follow the loops), and is the
    exact reduction's: I th'' = g c sin th (mechanisms.parallelogram, I = (n + 1) / 3 + n,
    c = (n + 1) / 2 + n) linearized, so A = [[0, 1], [g c cos th / I, 0]]; its joint torque
    gives q'' = tau / I; the first bar's tip moves 1 m per rad.  At the hanging equilibrium
    its squared frequency is static_equilibrium's (the loop's tangent space, another path)."""
    from dttmm.model.mechanisms import n_four_bar
    n, theta = 2, 0.7
    inertia, c = (n + 1) / 3 + n, (n + 1) / 2 + n
    lin = dttmm.linearize(n_four_bar(n, theta=theta, rate=1.3))
    assert lin.states == ("O0.q0", "O0.q0'")
    expected = [[0.0, 1.0], [9.81 * c * np.cos(theta) / inertia, 0.0]]
    np.testing.assert_allclose(lin.A, expected, rtol=0, atol=1e-8)
    b = lin.B[:, lin.inputs.index("O0.torque0")]
    np.testing.assert_allclose(b, [0.0, 1.0 / inertia], rtol=0, atol=1e-9)
    tip = [lin.outputs.index(f"v0.r{a}") for a in "xyz"]
    assert abs(np.linalg.norm(lin.C[tip, 0]) - 1.0) < 1e-8
    eq = dttmm.static_equilibrium(n_four_bar(n, theta=3.0, rate=0.0))
    hanging = dttmm.linearize(eq.model)
    swing = eq.squared_frequencies[eq.squared_frequencies != 0.0]
    squared = (-np.linalg.eigvals(hanging.A) ** 2).real        # (+-i w: w^2 twice)
    np.testing.assert_allclose(squared, [swing[0]] * 2, rtol=1e-7)


def test_linearize_refuses_what_its_loops_do_not_cover():
    from dttmm.model.mechanisms import flexible_slider_crank, stewart_platform
    with pytest.raises(ValueError, match="closed loops are linearized for rigid bodies"):
        dttmm.linearize(flexible_slider_crank())
    with pytest.raises(ValueError, match="no freedom left"):
        dttmm.linearize(stewart_platform())


def test_a_compiled_joint_force_is_an_input_between_rigid_bodies_only():
    """linearize offers a compiled JointForce's coordinate force as a pair of body loads (the
    joint's own slot holds t): between rigid bodies its B column is the joint element's own
    (the same coordinate without a compiled drive, applied inside the joint: an independent
    path, to 1e-9). A strain rod carries no loads, so next to one the pair lost its rod half
    and the column came out as minus the first joint's, quietly (an entry of 17.7 where the
    joint's own column has 451); like a beam's there, it is not offered."""
    from numba import njit
    from dttmm import JointForce, RevoluteJoint, StrainRod, build_chain, linearize
    from dttmm.model.chains import unit_link

    @njit
    def law(t, q, qd):
        return 0.0

    def model(drive):
        rod = StrainRod(length=1.0, bending_stiffness=50.0, mass_per_length=1.0,
                        polar_inertia_per_length=1e-4, strain_modes=2)
        return build_chain([RevoluteJoint(axis=[0, 0, 1], drive=drive), unit_link(),
                            RevoluteJoint(axis=[0, 0, 1], drive=drive), rod])

    compiled, own = linearize(model(JointForce(law))), linearize(model(None))
    torques = [name for name in own.inputs if "torque" in name]
    assert torques == ["RevoluteJoint0.torque0", "RevoluteJoint1.torque0"]
    assert [name for name in compiled.inputs if "torque" in name] == torques[:1]
    first = own.inputs.index(torques[0])
    np.testing.assert_allclose(compiled.B[:, compiled.inputs.index(torques[0])],
                               own.B[:, first], atol=1e-9 * np.abs(own.B[:, first]).max())


def test_linearize_names_its_argument_order_when_given_forward_dynamics_order():
    """linearize takes (model, state, t) and forward_dynamics (model, t, state): the order of
    the other is refused with both named, not numpy's float() error."""
    model = rigid_chain(2)
    state = simulate(model, 0.01, 1e-3).state(-1)
    with pytest.raises(ValueError, match=r"linearize: the arguments are \(model, state=None"):
        dttmm.linearize(model, 0.01, state)
    assert dttmm.linearize(model, state, 0.01).A.shape == (12, 12)
