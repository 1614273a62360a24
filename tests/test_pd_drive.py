"""Drives that run inside the compiled loop: forces linear in (q, q') with the rest known in time
(elements/drives.py: PDTracking, a JointForce of time alone) and JointForces compiled with
numba (kernels/transfers/joint.py::drive_value, call_force): against closed forms, the reference,
and the per-step path they replace."""
import numba
import numpy as np
import pytest

import dttmm
from dttmm import PDTracking, RevoluteJoint, RigidBody, System, simulate, simulate_reference
from dttmm.solving import run_tables
from dttmm.model.chains import arm, arm_servo
from dttmm.solving import run_plan

from helpers import fitted_order

J = 2.0                                     # the rotor's inertia about its axis, kg m^2
KP, KD = 50.0, 4.0                          # omega_0 = 5 rad/s, zeta = 0.2


def rotor(feedforward):
    """A rotor on a revolute joint about z (no gravity), from rest at q = 0, tracking
    0.2 sin 3t; with feedforward J target'' the tracking error obeys
    J e'' + kd e' + kp e = 0 exactly (e = target - q)."""
    system = System(gravity=[0.0, 0.0, 0.0])
    pd = PDTracking(kp=KP, kd=KD, target=lambda t: 0.2 * np.sin(3.0 * t),
                    target_rate=lambda t: 0.6 * np.cos(3.0 * t),
                    feedforward=(lambda t: -1.8 * J * np.sin(3.0 * t)) if feedforward else None)
    system.add(RigidBody(mass=1.0, inertia=[1.0, 1.0, J], inertia_about="mass_center",
                         to_output=[0.1, 0.0, 0.0], name="rotor"),
               RevoluteJoint(axis=[0, 0, 1], drive=pd, name="motor"))
    return system.build()


def exact_angle(t):
    """q = target - e, e'' + (kd/J) e' + (kp/J) e = 0, e(0) = 0, e'(0) = 0.6."""
    w0, zeta = np.sqrt(KP / J), KD / (2.0 * np.sqrt(KP * J))
    wd = w0 * np.sqrt(1.0 - zeta ** 2)
    e = 0.6 / wd * np.exp(-zeta * w0 * t) * np.sin(wd * t)
    return 0.2 * np.sin(3.0 * t) - e


def with_joint1_force(model, function):
    """The arm with joint 1 driven by JointForce(function) instead (the same model otherwise:
    its checked drive swapped in, at joint 1's initial angle 0 and rate 0.5 rad/s)."""
    from dataclasses import replace
    drive = dttmm.JointForce(function).validated("joint1", 0.0, 0.5)
    return replace(model, drives=((drive,),) + tuple(model.drives[1:]))


def test_pd_tracking_with_feedforward_against_the_closed_form():
    """The tracking error's closed form (a damped oscillator from e'(0) = 0.6 rad/s): DT-TMM
    converges to it at order 2 (measured 5.9e-7, 1.5e-7, 3.7e-8 rad at dt = 1e-3, 5e-4,
    2.5e-4), the reference to 1e-8; the drive force is the law's at the computed state;
    without the feedforward the rotor lags by 0.12 rad (so a dropped feedforward fails)."""
    t = np.linspace(0.0, 2.0, 21)
    model = rotor(feedforward=True)
    ref = simulate_reference(model, 2.0, t_eval=t, rtol=1e-11, atol=1e-13)
    assert np.abs(ref.joint_coordinates[:, 0] - exact_angle(t)).max() < 1e-8
    steps, errors = [1e-3, 5e-4, 2.5e-4], []
    for dt in steps:
        result = simulate(model, 2.0, dt, t_eval=t)
        errors.append(np.abs(result.joint_coordinates[:, 0] - exact_angle(t)).max())
    assert abs(fitted_order(steps, errors) - 2.0) < 0.1, errors
    assert errors[-1] < 1e-6
    q, qd = result.joint_coordinates[:, 0], result.joint_rates[:, 0]
    law = KP * (0.2 * np.sin(3 * t) - q) + KD * (0.6 * np.cos(3 * t) - qd) \
        - 1.8 * J * np.sin(3 * t)
    assert np.abs(result.drive_force[:, 0] - law).max() < 1e-9 * np.abs(law).max()
    lagging = simulate(rotor(feedforward=False), 2.0, 2.5e-4, t_eval=t)
    assert np.abs(lagging.joint_coordinates[:, 0] - exact_angle(t)).max() > 1e-2


def test_the_arm_under_pd_feedback_converges_to_the_reference():
    """chains.arm(drive="pd"): joint 1 tracks 0.5 t + 0.2 (1 - cos 2t) rad at kp = 200, kd =
    20 over 1 s; every link's end converges to the reference at order 2 (measured 9.2e-6,
    2.3e-6, 5.8e-7 m at dt = 1e-3, 5e-4, 2.5e-4)
    and joint 1 stays within 0.1 rad of its target (0.083 rad at 1 s, against the links'
    weight: kp = 200 is a soft loop)."""
    model = arm("pd")
    t = np.linspace(0.0, 1.0, 11)
    ref = simulate_reference(model, 1.0, t_eval=t, rtol=1e-10, atol=1e-12)
    target = 0.5 * t + 0.2 * (1 - np.cos(2 * t))
    assert np.abs(ref.joint_coordinates[:, 0] - target).max() < 0.1
    steps, errors = [1e-3, 5e-4, 2.5e-4], []
    for dt in steps:
        result = simulate(model, 1.0, dt, t_eval=t)
        errors.append(np.abs(result.position_output - ref.position_output).max())
    assert abs(fitted_order(steps, errors) - 2.0) < 0.2, errors


def test_a_force_of_time_alone_runs_in_chunks_as_the_step_by_step_function_did():
    """The arm's 2 sin(pi t) torque as a profile (ProfileForce: inside the loop, in chunks) and
    as a Python JointForce of (t, q, q') (one compiled call per step): the same run to 1e-12."""
    chunked = arm("torque")
    assert chunked.drives[0][0]["of_time"]
    a = simulate(chunked, 0.5, 1e-3)
    # the same model, its drive a function with the state's signature
    b = simulate(with_joint1_force(chunked, lambda t, q, qd: 2.0 * np.sin(np.pi * t)), 0.5,
                 1e-3)
    assert np.abs(a.position_output - b.position_output).max() < 1e-12
    assert np.abs(a.drive_force - b.drive_force).max() < 1e-12


def test_pd_drives_in_scenes_and_where_they_are_refused():
    from dttmm.interfaces.scene import scene_from_dict, scene_of
    model = arm("pd")
    data = scene_of(model, name="arm_pd")
    drive = data["body"][0]["joint"]["drive"]
    assert drive["type"] == "pd" and drive["kp"] == 200.0 and drive["kd"] == 20.0
    again = scene_from_dict(data).model
    a, b = simulate(model, 0.2, 1e-3), simulate(again, 0.2, 1e-3)
    assert np.abs(a.position_output - b.position_output).max() < 1e-12
    with pytest.raises(ValueError, match="motor.*drive kp"):
        dttmm.build_chain([RevoluteJoint(axis=[0, 0, 1], name="motor", drive=PDTracking(
            kp=-1.0, kd=0.0, target=lambda t: t, target_rate=lambda t: 1.0)),
            RigidBody(mass=1.0, inertia=1.0, inertia_about="mass_center")])
    with pytest.raises(ValueError, match="target_rate.*contradicts"):
        dttmm.build_chain([RevoluteJoint(axis=[0, 0, 1], drive=PDTracking(
            kp=1.0, kd=0.0, target=lambda t: t, target_rate=lambda t: 2.0)),
            RigidBody(mass=1.0, inertia=1.0, inertia_about="mass_center")])
    system = System()
    system.add(RigidBody(mass=1.0, inertia=[1e-3, 0.1, 0.1], inertia_about="mass_center",
                         to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0], name="bar"),
               RevoluteJoint(axis=[0, 0, 1]))
    system.close(RevoluteJoint(axis=[0, 0, 1], name="pin", drive=PDTracking(
        kp=1.0, kd=0.0, target=lambda t: 0.0, target_rate=lambda t: 0.0)), "bar", "ground")
    with pytest.raises(ValueError, match="'pin'.*PDTracking runs on tree joints"):
        system.build()


@numba.njit
def _pendulum_torque(t, q, q_dot):
    """A nonlinear law of (t, q, q'): a pendulum's restoring torque, quadratic drag and a
    forcing (N m)."""
    return -50.0 * np.sin(q) - 0.5 * q_dot * abs(q_dot) + 5.0 * np.cos(3.0 * t)


def test_a_numba_joint_force_runs_inside_the_loop_and_is_the_pd_law(monkeypatch):
    """chains.arm(drive="pd-njit"): the PD law written as an @numba.njit JointForce runs in
    chunks of many steps (one compiled call for 500 steps; the same law as a Python function:
    one per step) and gives the PDTracking's run to rounding (measured 1e-14 m: both iterate
    to the same implicit step, its slope taken by differences).  (The consistent start is one
    more call of the skeleton, Settings.start: not counted.)"""
    calls = []
    real = run_plan.run_steps

    def counted(loop, run, *args, **kwargs):
        if not run.settings.start:
            calls.append(1)
        return real(loop, run, *args, **kwargs)
    monkeypatch.setattr(run_plan, "run_steps", counted)
    compiled = arm("pd-njit")
    assert compiled.drives[0][0]["compiled"]
    b = simulate(compiled, 0.5, 1e-3)
    assert len(calls) == 1
    a = simulate(arm("pd"), 0.5, 1e-3)
    assert np.abs(a.position_output - b.position_output).max() < 1e-10
    assert np.abs(a.drive_force - b.drive_force).max() < 1e-8 * np.abs(a.drive_force).max()
    calls.clear()
    stepwise = with_joint1_force(compiled, arm_servo.py_func)
    assert not stepwise.drives[0][0]["compiled"]
    c = simulate(stepwise, 0.05, 1e-3)
    assert len(calls) == 50
    assert np.abs(c.position_output - b.position_output[:51]).max() < 1e-3   # (explicit)


def test_a_nonlinear_numba_joint_force_converges_to_the_reference():
    """A rotor (J = 2 kg m^2 about the revolute axis) under -50 sin q - 0.5 q'|q'| + 5 cos 3t
    N m, compiled: DT-TMM converges to the reference (which calls the same function from
    Python) at order 2 over 2 s (measured 8.0e-6, 2.0e-6, 5.0e-7 rad at dt = 2e-3, 1e-3,
    5e-4; the rotor swings over 0.5 rad)."""
    system = System(gravity=[0.0, 0.0, 0.0])
    system.add(RigidBody(mass=1.0, inertia=[1.0, 1.0, J], inertia_about="mass_center",
                         to_output=[0.1, 0.0, 0.0], name="rotor"),
               RevoluteJoint(axis=[0, 0, 1], angle=0.3, drive=dttmm.JointForce(
                   _pendulum_torque), name="motor"))
    model = system.build()
    t = np.linspace(0.0, 2.0, 21)
    ref = simulate_reference(model, 2.0, t_eval=t, rtol=1e-11, atol=1e-13)
    steps, errors = [2e-3, 1e-3, 5e-4], []
    for dt in steps:
        result = simulate(model, 2.0, dt, t_eval=t)
        errors.append(np.abs(result.joint_coordinates[:, 0] - ref.joint_coordinates[:, 0]).max())
    assert abs(fitted_order(steps, errors) - 2.0) < 0.1, errors
    assert np.ptp(ref.joint_coordinates[:, 0]) > 0.4
    q, qd = result.joint_coordinates[:, 0], result.joint_rates[:, 0]
    law = -50.0 * np.sin(q) - 0.5 * qd * np.abs(qd) + 5.0 * np.cos(3.0 * t)
    assert np.abs(result.drive_force[:, 0] - law).max() < 1e-9 * np.abs(law).max()


def test_a_numba_joint_force_that_does_not_fit_is_refused_at_build():
    @numba.njit
    def two(t, q):
        return q

    @numba.njit
    def pair(t, q, q_dot):
        return (q, q_dot)

    for function, message in ((two, "'motor'.*drive function"),
                              (pair, "'motor'.*one number")):
        with pytest.raises(ValueError, match=message):
            dttmm.build_chain([RevoluteJoint(axis=[0, 0, 1], name="motor",
                                             drive=dttmm.JointForce(function)),
                               RigidBody(mass=1.0, inertia=1.0, inertia_about="mass_center")])


def test_a_python_joint_force_of_the_state_is_said_to_run_step_by_step_once(capsys,
                                                                             monkeypatch):
    from dttmm.results import feedback
    monkeypatch.setattr(feedback, "_noted", set())
    compiled = arm("pd-njit")
    stepwise = with_joint1_force(compiled, arm_servo.py_func)
    simulate(compiled, 0.005, 1e-3)     # (compiled: a cold cache says so first)
    simulate(stepwise, 0.005, 1e-3)
    monkeypatch.setattr(feedback, "_noted", set())
    capsys.readouterr()
    simulate(compiled, 0.005, 1e-3)
    assert capsys.readouterr().err == ""
    simulate(stepwise, 0.005, 1e-3)
    err = capsys.readouterr().err
    assert "joint 'joint1'" in err and "one step per compiled call" in err and "numba" in err
    simulate(stepwise, 0.005, 1e-3)
    assert capsys.readouterr().err == ""


def test_a_run_with_a_numba_joint_force_resumes_with_this_process_callbacks():
    """A checkpoint holds the general loop's arrays, the compiled forces' addresses among them
    (another process's, once saved): a resumed run calls this process's callbacks (the
    checkpoint's addresses are overwritten; a zeroed one would crash), and the two halves
    equal the whole run bit for bit."""
    from dataclasses import replace
    model = arm("pd-njit")
    whole = simulate(model, 0.1, 1e-3)
    half = simulate(model, 0.05, 1e-3)
    address = run_tables.compiled_forces(run_tables.kernel_model(model)[0])[0]
    arrays = tuple(np.where(a == address, 0, a)       # (the general loop's int buffer)
                   if a.dtype == np.int64 and (a == address).any() else a
                   for a in half.checkpoint.arrays)
    assert sum(a is not b for a, b in zip(arrays, half.checkpoint.arrays)) == 1
    rest = simulate(model, 0.1, 1e-3, resume=replace(half.checkpoint, source=arrays))
    np.testing.assert_array_equal(rest.position_output[-1], whole.position_output[-1])
