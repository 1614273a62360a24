"""Drives on closing joints (docs/loops.md, "Drives on closing joints"): prescribed motions of a
slide, a revolute angle and either angle of a universal joint, and spring-dampers, in DT-TMM
and in the Newton-Euler reference, against the same drive in the tree, the parallelogram's
exact kinematics and reduction, and the joints' own coordinates."""
import numpy as np
import pytest

from dttmm import (BallJoint, DivergenceError, Ground, JointForce, JointMotion, PrismaticJoint,
                   RevoluteJoint, RigidBody, SpringDamper, System, UniversalJoint, assemble,
                   simulate, simulate_reference)
from dttmm.model.mechanisms import _bar, _frame, slider_crank

from helpers import fitted_order, rot_z


def _sine(amplitude, omega, offset=0.0):
    return JointMotion(position=lambda t: offset + amplitude * np.sin(omega * t),
                       velocity=lambda t: amplitude * omega * np.cos(omega * t),
                       acceleration=lambda t: -amplitude * omega * omega * np.sin(omega * t))


def _slide():
    """The slider's x from 0.2 m out to 0.26 m and back over 1 s, from rest."""
    w = 2.0 * np.pi
    return JointMotion(position=lambda t: 0.2 + 0.03 * (1.0 - np.cos(w * t)),
                       velocity=lambda t: 0.03 * w * np.sin(w * t),
                       acceleration=lambda t: 0.03 * w * w * np.cos(w * t))


def test_a_prescribed_slide_on_the_closing_joint_moves_as_on_the_tree_joint():
    """The IFToMM slider-crank with its slide prescribed (one degree of freedom, one motion:
    the mechanism is driven through its kinematics), once on the closing prismatic joint
    (slider on the rod) and once on the tree's (slider on the ground): the two spanning trees
    give the same motion (to rounding: the projection holds the motion exactly) and the same
    drive force, DT-TMM's converging to the reference's at order 3 (measured 5.0e-7, 6.2e-8,
    7.7e-9 N of 7.1 N at dt = 2e-3, 1e-3, 5e-4), as a prescribed tree slide's does."""
    t_end, t = 0.4, np.linspace(0.0, 0.4, 5)
    closed, tree = (slider_crank(which, crank_rate=0.0, slide=_slide())
                    for which in ("slider on the rod", "slider on the ground"))
    ref = simulate_reference(closed, t_end, t_eval=t, rtol=1e-11, atol=1e-13)
    ref_tree = simulate_reference(tree, t_end, t_eval=t, rtol=1e-11, atol=1e-13)
    assert np.abs(ref.position_output - ref_tree.position_output).max() < 1e-12
    assert np.abs(ref.closure_drive_force[:, 0, 0] - ref_tree.drive_force[:, -1]).max() < 1e-8
    assert abs(ref.closure_drive_force[-1, 0, 0]) > 5.0
    steps, errors = [2e-3, 1e-3, 5e-4], []
    for dt in steps:
        run = simulate(closed, t_end, dt, t_eval=t)
        run_tree = simulate(tree, t_end, dt, t_eval=t)
        assert np.abs(run.position_output - ref.position_output).max() < 1e-12
        assert np.abs(run_tree.position_output - ref.position_output).max() < 1e-12
        force = run.closure_drive_force[:, 0, 0]
        assert np.abs(force - run_tree.drive_force[:, -1]).max() < 1e-9
        # the drive force is the closing joint's force along its axis (world x)
        assert np.abs(force - run.closure_force[:, 0, 0]).max() < 1e-12
        errors.append(np.abs(force - ref.closure_drive_force[:, 0, 0]).max())
        assert run.info["loop_position_residual"] < 1e-10
    order = fitted_order(steps, errors)
    assert 2.7 < order < 3.3, (errors, order)
    assert errors[-1] < 2e-8


def _four_bar(drive, rate=0.0, root_drive=None):
    """One loop of the N-four-bar (mechanisms.n_four_bar's bars, upright, turning at `rate`
    clockwise), closed to the ground at (1, 0) by the revolute joint "O1" with the given drive
    (and root_drive on the tree's "O0")."""
    z = [0, 0, 1.0]
    system = System(gravity=[0, -9.81, 0])
    system.add(_bar("v0", rot_z(np.pi / 2)),
               RevoluteJoint(axis=z, rate=-rate, drive=root_drive, name="O0"))
    system.add(_bar("h1", np.eye(3)), RevoluteJoint(axis=z, name="H1"), parent="v0")
    system.add(_bar("v1", rot_z(-np.pi / 2)), RevoluteJoint(axis=z, name="B1"), parent="h1")
    system.close(RevoluteJoint(axis=z, name="O1", drive=drive), "v1", "ground")
    return assemble(system.build(), keep=["O0"] if rate else [])


def test_a_prescribed_closing_revolute_turns_the_parallelogram_exactly():
    """The closing revolute joint's angle (v1 against the ground, about z) prescribed as
    0.8 sin 2t: the parallelogram's bars all turn by it (clockwise from up as seen from +z: the
    ground turns by q relative to v1), so B_0 = (sin q, cos q) exactly, which DT-TMM and the
    reference hold to rounding; the torque the motion needs agrees to 1e-7 N m of 19 N m."""
    q_of = _sine(0.8, 2.0)
    model = _four_bar(q_of)
    t = np.linspace(0.0, 2.0, 9)
    q = np.array([q_of.position(ti) for ti in t])
    exact = np.stack([np.sin(q), np.cos(q)], axis=1)
    run = simulate(model, 2.0, 1e-3, t_eval=t)
    ref = simulate_reference(model, 2.0, t_eval=t, rtol=1e-11, atol=1e-13)
    assert np.abs(run.position_output[:, 0, :2] - exact).max() < 1e-12
    assert np.abs(ref.position_output[:, 0, :2] - exact).max() < 1e-11
    torque = run.closure_drive_force[:, 0, 0]
    assert np.abs(torque - ref.closure_drive_force[:, 0, 0]).max() < 1e-7
    assert np.abs(torque).max() > 15.0
    assert np.abs(torque - run.closure_moment[:, 0, 2]).max() < 1e-12


def _slider_crank_driven_at_c(coordinate):
    """The slider-crank on its ground tree, closed by the universal joint "C" (slider: axis1
    world x; rod: axis2 across it), angle `coordinate` prescribed as 0.1 sin 2 pi t."""
    a, b, c = np.array([0, 0.1, 0.12]), np.array([0, 0.1, 0.2]), np.array([0.2, 0, 0])
    system = System(gravity=[0, 0, -9.81], ground=Ground(position=a))
    system.add(RigidBody(mass=0.12, inertia=[1e-4, 1e-4, 1e-5], inertia_about="mass_center",
                         to_mass_center=[0, 0, 0.04], to_output=[0, 0, 0.08], name="crank",
                         rotation=np.eye(3)), RevoluteJoint(axis=[1, 0, 0], name="A"))
    rod_frame = _frame(c - b, [0, 0, 1.0])
    system.add(RigidBody(mass=0.5, inertia=[4e-4, 4e-3, 4e-3], inertia_about="mass_center",
                         to_mass_center=[0.15, 0, 0], to_output=[0.3, 0, 0], rotation=rod_frame,
                         name="rod"), BallJoint(name="B"), parent="crank")
    across = rod_frame.T @ (np.array([0, -2, 1.0]) / np.sqrt(5))
    system.add(RigidBody(mass=2.0, inertia=[1e-4] * 3, inertia_about="mass_center",
                         to_mass_center=-a, to_output=-a, name="slider"),
               PrismaticJoint(axis=[1, 0, 0], position=0.2, name="slide"))
    drives = [None, None]
    drives[coordinate] = _sine(0.1, 2.0 * np.pi)
    system.close(UniversalJoint(axis1=[1, 0, 0], axis2=across, drives=tuple(drives), name="C"),
                 "slider", "rod")
    return assemble(system.build()), across


def _axis(angle, n):
    """Rot(n, angle) (Rodrigues)."""
    k = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * k @ k


@pytest.mark.parametrize("coordinate", [0, 1])
def test_either_angle_of_a_closing_universal_joint_follows_its_motion(coordinate):
    """q1 (about world x, fixed in the slider) or q2 (about the rod's cross axis, fixed in the
    rod) of the closing universal joint prescribed: the rod's frame against the slider's is
    the joint's own F_b = F_a Rot(n1, q1) R0 Rot(n2, q2) with the prescribed angle (the other
    angle read from it, its axis kept: 1e-12), DT-TMM's motion is the reference's to 1e-12 m
    and its drive couple converges to the reference's at order 3."""
    model, across = _slider_crank_driven_at_c(coordinate)
    t_end, t = 0.5, np.linspace(0.0, 0.5, 6)
    ref = simulate_reference(model, t_end, t_eval=t, rtol=1e-11, atol=1e-13)
    r0 = model.closure_params[0, 0:9].reshape(3, 3)
    n1, n2 = np.array([1.0, 0, 0]), across
    steps, errors = [1e-3, 5e-4, 2.5e-4], []
    for dt in steps:
        run = simulate(model, t_end, dt, t_eval=t)
        assert np.abs(run.position_output - ref.position_output).max() < 1e-12
        errors.append(np.abs(run.closure_drive_force[:, 0, coordinate]
                             - ref.closure_drive_force[:, 0, coordinate]).max())
    for i, ti in enumerate(t):
        f_a, f_b = run.rotation[i, 2], run.rotation[i, 1]        # slider, rod
        q = 0.1 * np.sin(2.0 * np.pi * ti)
        if coordinate == 0:     # R0^T Rot(n1, q1)^T F_a^T F_b = Rot(n2, q2) keeps n2
            rest = r0.T @ _axis(q, n1).T @ f_a.T @ f_b
            assert np.abs(rest @ n2 - n2).max() < 1e-12
        else:                   # F_a^T F_b Rot(n2, q2)^T R0^T = Rot(n1, q1) keeps n1
            rest = f_a.T @ f_b @ _axis(q, n2).T @ r0.T
            assert np.abs(rest @ n1 - n1).max() < 1e-12
    order = fitted_order(steps, errors)
    assert 2.7 < order < 3.3, (errors, order)
    assert np.abs(ref.closure_drive_force[:, 0, coordinate]).max() > 0.1


def test_drives_on_closing_joints_that_do_not_run_are_refused():
    """A prescribed closing angle that a prescribed tree angle locks (the four-bar: one degree
    of freedom, two motions) is refused when the loop is assembled; a closing JointForce that
    returns no finite number stops the run at its step, naming the closing joint."""
    with pytest.raises(ValueError, match="cannot move"):
        _four_bar(_sine(0.8, 2.0), root_drive=_sine(0.5, 3.0))
    bad = _four_bar(JointForce(lambda t, q, qd: np.nan if t > 0.0105 else -q), rate=1.0)
    with pytest.raises(DivergenceError, match="closing joint 'O1'.*coordinate 1") as err:
        simulate(bad, 0.1, 1e-3)
    assert err.value.step == 11


def test_a_closing_joints_drive_goes_through_a_scene_file(tmp_path):
    """A closing joint's prescribed motion from a profile is written to the scene's [[close]]
    table and read back: the same motion, and the same run to the last bit."""
    from dttmm.model.profiles import profile
    from dttmm.interfaces.scene import load_scene, save_scene
    p = profile({"profile": "sine", "amplitude": 0.5, "angular_frequency": 2.0})
    model = _four_bar(JointMotion(p, p.rate, p.acceleration))
    save_scene(model, tmp_path / "four_bar.toml")
    back = load_scene(tmp_path / "four_bar.toml").model
    drive = back.closure_drives[0][0]
    assert [f(0.3) for f in drive["function"]] == [p(0.3), p.rate(0.3), p.acceleration(0.3)]
    a, b = simulate(model, 0.05, 1e-3), simulate(back, 0.05, 1e-3)
    assert np.array_equal(a.position_output, b.position_output)


def test_the_energy_balance_closes_with_the_closing_drives_work():
    """E - E(0) = W with W the work of the closing joint's prescribed motion (its force times
    the motion's rate): the four-bar's balance closes at order 2 (measured 4.3e-6 and 1.1e-6 of
    the largest kinetic energy at dt = 1e-3, 5e-4 over 2 s); the slider-crank driven from rest
    to rest in 0.5 s keeps its balance to 1.1e-5 at dt = 1e-3 (the balance's scale is the
    largest kinetic energy over the run's steps, not only at its chunks' ends, where it is 0)."""
    model = _four_bar(_sine(0.8, 2.0))
    gaps = [simulate(model, 2.0, dt, max_energy_error=1e-3).info["energy_balance_error"]
            for dt in (1e-3, 5e-4)]
    assert gaps[1] < 2e-6 and gaps[0] / gaps[1] > 3.2, gaps
    run = simulate(slider_crank("slider on the rod", crank_rate=0.0, slide=_slide()), 0.5, 1e-3,
                   max_energy_error=1e-4)
    assert run.info["energy_balance_error"] < 2e-5


def _spring_parallelogram(t, stiffness, damping, forcing=lambda t: 0.0):
    """B_0(t) of the one-loop four-bar with a torsion spring-damper on its closing joint:
    I th'' = 9.81 c sin th - k th - d th' + tau(t) (I = 5/3 kg m^2, c = 2 kg m: the
    parallelogram's reduction, mechanisms.parallelogram, n = 1; the spring's angle is th; tau
    the forcing), from th = 0, th' = 1 rad/s (scipy's DOP853 at rtol 1e-13)."""
    from scipy.integrate import solve_ivp
    sol = solve_ivp(lambda s, y: [y[1], (9.81 * 2.0 * np.sin(y[0]) - stiffness * y[0]
                                         - damping * y[1] + forcing(s)) / (5.0 / 3.0)],
                    (0, t[-1]), [0.0, 1.0], method="DOP853", rtol=1e-13, atol=1e-14, t_eval=t)
    return np.stack([np.sin(sol.y[0]), np.cos(sol.y[0])], axis=1), sol.y[1]


def test_a_spring_damper_on_a_closing_joint_against_the_exact_reduction():
    """A torsion spring-damper (k = 50 N m/rad, c = 2 N m s/rad) on the four-bar's closing
    revolute joint: B_0 converges at order 2 to the parallelogram's exact reduction with the
    spring (measured 3.7e-6, 9.3e-7, 2.3e-7 m at dt = 2e-3, 1e-3, 5e-4 over 3 s), the reference
    meets it to 1e-10 m (2.4e-12), the spring's torque is -k q - c q' (Result.
    closure_drive_force: 1.1e-5 N m of the reduction's at 5e-4), and undamped the energy
    balance (E plus the spring's work) closes at order 2 (6.2e-6, 1.7e-6 of the largest
    kinetic energy at dt = 1e-3, 5e-4)."""
    _closing_torque_against_the_reduction(
        SpringDamper(stiffness=50.0, damping=2.0), SpringDamper(stiffness=50.0),
        lambda t: 0.0 * t, error_tol=5e-7, torque_tol=3e-5, gap_tol=3e-6)


def _closing_torque_against_the_reduction(drive, undamped, forcing, error_tol, torque_tol,
                                          gap_tol):
    """The one-loop four-bar with `drive` on its closing revolute joint, a torque -50 q - 2 q'
    + forcing(t) (N m), against the parallelogram's exact reduction with that torque over 3 s:
    DT-TMM at order 2 (dt = 2e-3, 1e-3, 5e-4; below error_tol m at the finest, the loop closed
    to 1e-10 m), its torque (Result.closure_drive_force) the law's at the exact angle to
    torque_tol, the reference within 1e-10 m; with the model's `undamped` drive instead, the
    energy balance closes at order 2, below gap_tol of the largest kinetic energy at dt =
    5e-4.  Returns the model, the reference's run and the exact torque."""
    t = np.linspace(0.0, 3.0, 31)
    exact, rate = _spring_parallelogram(t, 50.0, 2.0, forcing)
    model = _four_bar(drive, rate=1.0)
    steps, errors = [2e-3, 1e-3, 5e-4], []
    for dt in steps:
        run = simulate(model, 3.0, dt, t_eval=t)
        errors.append(np.abs(run.position_output[:, 0, :2] - exact).max())
        assert run.info["loop_position_residual"] < 1e-10
    order = fitted_order(steps, errors)
    assert abs(order - 2.0) < 0.2, (errors, order)
    assert errors[-1] < error_tol
    theta = np.arctan2(exact[:, 0], exact[:, 1])
    torque = -50.0 * theta - 2.0 * rate + forcing(t)
    assert np.abs(run.closure_drive_force[:, 0, 0] - torque).max() < torque_tol
    ref = simulate_reference(model, 3.0, t_eval=t, rtol=1e-11, atol=1e-13)
    assert np.abs(ref.position_output[:, 0, :2] - exact).max() < 1e-10
    free = _four_bar(undamped, rate=1.0)
    gaps = [simulate(free, 3.0, dt, max_energy_error=1e-3).info["energy_balance_error"]
            for dt in (1e-3, 5e-4)]
    assert gaps[1] < gap_tol and gaps[0] / gaps[1] > 3.2, gaps
    return model, ref, torque


def test_a_spring_on_the_closing_slide_acts_as_on_the_tree_slide():
    """A spring-damper on the slider-crank's slide (k = 200 N/m, c = 1 N s/m, at rest where the
    slider starts: the default rest of a closing slide is its measured slide, 0.2 m), the crank
    free at 6 rad/s: closed by that prismatic joint or with it in the tree, the reference moves
    alike (1e-8 m over 0.5 s), and DT-TMM's closed model converges to it at order 2."""
    closed, errors = _slide_drive_on_either_tree(SpringDamper(stiffness=200.0, damping=1.0),
                                                 1e-8, 1e-6)
    assert closed.closure_drives[0][0]["rest"] == pytest.approx(0.2, abs=1e-12)


def _slide_drive_on_either_tree(drive, motion_tol, force_tol):
    """The slider-crank with `drive` on its slide, closed by that prismatic joint and with it
    in the tree: the references' motions agree to motion_tol m and the drive's force to
    force_tol N over 0.5 s, and DT-TMM's closed model converges to the reference at order 2
    (dt = 1e-3, 5e-4, 2.5e-4).  Returns the closed model and the errors."""
    closed, tree = (slider_crank(which, slide=drive)
                    for which in ("slider on the rod", "slider on the ground"))
    t = np.linspace(0.0, 0.5, 6)
    ref = simulate_reference(closed, 0.5, t_eval=t, rtol=1e-11, atol=1e-13)
    ref_tree = simulate_reference(tree, 0.5, t_eval=t, rtol=1e-11, atol=1e-13)
    assert np.abs(ref.position_output - ref_tree.position_output).max() < motion_tol
    assert (np.abs(ref.closure_drive_force[:, 0, 0] - ref_tree.drive_force[:, -1]).max()
            < force_tol)
    steps, errors = [1e-3, 5e-4, 2.5e-4], []
    for dt in steps:
        run = simulate(closed, 0.5, dt, t_eval=t)
        errors.append(np.abs(run.position_output - ref.position_output).max())
    order = fitted_order(steps, errors)
    assert abs(order - 2.0) < 0.2, (errors, order)
    return closed, errors


def _forcing(t):
    return 5.0 * np.sin(3.0 * t)


def test_a_joint_force_on_a_closing_joint_against_the_exact_reduction():
    """A JointForce f(t, q, q') = -50 q - 2 q' + 5 sin 3t (N m) on the four-bar's closing
    revolute joint, evaluated like a tree joint's at the step's predictor: B_0 converges at
    order 2 to the parallelogram's exact reduction with that torque (measured 2.6e-6, 6.4e-7,
    1.6e-7 m at dt = 2e-3, 1e-3, 5e-4 over 3 s), its torque (Result.closure_drive_force) is
    the law's at the exact angle to 5.9e-6 N m at 5e-4, the reference meets the reduction to
    2.0e-12 m and 1.1e-10 N m, the energy balance counts the drive's work (5.2e-6, 1.3e-6 of
    the largest kinetic energy at dt = 1e-3, 5e-4) and describe() names the drive."""
    model, ref, torque = _closing_torque_against_the_reduction(
        JointForce(lambda s, q, qd: -50.0 * q - 2.0 * qd + _forcing(s)),
        JointForce(lambda s, q, qd: -50.0 * q + _forcing(s)), _forcing,
        error_tol=3e-7, torque_tol=1e-5, gap_tol=2e-6)
    assert "coordinate 1 driven by a force (JointForce)" in model.describe()
    assert np.abs(ref.closure_drive_force[:, 0, 0] - torque).max() < 1e-9


def test_a_joint_force_on_the_closing_slide_acts_as_on_the_tree_slide():
    """The slider-crank's slide pulled by f(t, q, q') = -200 (q - 0.2) - q' + 2 sin 4t (N), on
    the closing prismatic joint or on the tree's: the reference moves alike (5e-14 m over
    0.5 s), DT-TMM's closed model converges to it at order 2 (5.0e-7, 1.3e-7, 3.1e-8 m at
    dt = 1e-3, 5e-4, 2.5e-4) and its checkpoint resumes bit for bit (the force's predictor
    reads the loop's last step, which the checkpoint keeps)."""
    law = JointForce(lambda s, q, qd: -200.0 * (q - 0.2) - qd + 2.0 * np.sin(4.0 * s))
    closed, errors = _slide_drive_on_either_tree(law, 1e-10, 1e-8)
    assert errors[-1] < 5e-8
    whole = simulate(closed, 0.1, 1e-3)
    half = simulate(closed, 0.05, 1e-3)
    rest = simulate(closed, 0.1, 1e-3, resume=half.checkpoint)
    assert np.array_equal(whole.position_output[-1], rest.position_output[-1])
