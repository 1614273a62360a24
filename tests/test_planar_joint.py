"""PlanarJoint (docs/joints.md, "Planar joint"): two slides along perpendicular axes n1, n2 of
a plane fixed in the parent and a turn about its normal n1 x n2.  The Newton-Euler reference
against an independent MuJoCo run (tests/data/mujoco_joints.py), DT-TMM against it at order 2,
drives on each coordinate, statics, linearize, loops (in the tree and closing; a closing
joint's drive on theta refused; tree="shortest" taking it from its loop at the gap between its
points), scenes, describe and its build checks."""
from pathlib import Path

import numpy as np
import pytest

import dttmm
from dttmm import (BallJoint, Ground, JointForce, JointMotion, PDTracking, PlanarJoint,
                   RevoluteJoint, RigidBody, SpringDamper, System, UniversalJoint, assemble,
                   simulate, static_equilibrium)
from dttmm.elements.joints import rotation_about
from dttmm.elements.kinds import COORDINATE_0
from dttmm.model.mechanisms import _frame
from dttmm.reference import simulate_reference

DATA = Path(__file__).resolve().parent / "data" / "mujoco_planar.npz"
N1, N2 = np.array([2.0, 2.0, 1.0]) / 3, np.array([-2.0, 1.0, 2.0]) / 3     # (n1 x n2 = N)
N = np.cross(N1, N2)
INERTIA = np.array([[0.020, -0.001, 0.000], [-0.001, 0.025, 0.002], [0.000, 0.002, 0.030]])


def _order(steps, errors):
    return np.polyfit(np.log(steps), np.log(errors), 1)[0]


def _body(g, name):
    return RigidBody(mass=float(g[f"geo_{name}_mass"]), inertia=g[f"geo_{name}_j_c"],
                     inertia_about="mass_center", to_mass_center=g[f"geo_{name}_l_ic"],
                     to_output=g[f"geo_{name}_l_io"], name=name)


def mujoco_case(drives=(None, None, None), rates=None):
    """(model, data): the MuJoCo run's system (tests/data/mujoco_joints.py's header, case
    "planar") rebuilt from the data's geometry: a carrier (offset mass centre, full inertia) on
    PlanarJoint(axis1=(2, 2, 1)/3, axis2=(-2, 1, 2)/3, coordinates=(0.2, -0.1, 0.5),
    rates=(0.3, -0.4, 1.5)) to the ground point, a link on a revolute joint (its z) at the
    carrier's output point; gravity -9.81 along z, which has components along n1, n2 and,
    through the mass centre's offset, a moment about the normal: all three coordinates move."""
    g = np.load(DATA)
    system = System(gravity=list(g["geo_gravity"]))
    system.add(_body(g, "carrier"),
               PlanarJoint(axis1=g["geo_axis1"], axis2=g["geo_axis2"],
                           coordinates=tuple(g["geo_coordinates"]),
                           rates=tuple(g["geo_rates"]) if rates is None else rates,
                           drives=drives, name="table"))
    system.add(_body(g, "link"), RevoluteJoint(axis=g["geo_link_axis"],
                                               angle=float(g["geo_link_angle"]),
                                               rate=float(g["geo_link_rate"]), name="hinge"),
               parent="carrier")
    return system.build(), g


def _off(res, g):
    """Largest difference (m) from the MuJoCo run of the frames' origins and the tip."""
    return max(np.abs(res.position_input - g["position_input"]).max(),
               np.abs(res.position_output[:, 1] - g["tip"]).max())


def test_the_reference_follows_mujoco():
    """The Newton-Euler reference (tight tolerance) against MuJoCo's RK4 run of a slide,
    slide, hinge chain (its own error 7e-14 m, against dt / 2): positions of both frames and
    the tip, and the coordinates in Result's order (x, y, theta, then the link's angle), over
    1 s and 2.7 m of travel (measured 1.9e-12 m, the coordinates 3.0e-12)."""
    model, g = mujoco_case()
    ref = simulate_reference(model, 1.0, t_eval=g["t"], rtol=1e-12, atol=1e-12)
    assert _off(ref, g) < 1e-10, _off(ref, g)
    assert np.abs(ref.joint_coordinates - g["joint_coordinates"]).max() < 1e-10
    assert np.ptp(g["joint_coordinates"][:, :3], axis=0).min() > 0.9    # (each one moves)


def test_dttmm_follows_the_reference_at_order_two():
    """DT-TMM's trapezoidal step: positions against the reference at dt = 2e-3 .. 2.5e-4 over
    1 s fall at order 2 (measured 1.61e-5, 4.02e-6, 1.01e-6, 2.51e-7 m: 2.000), and the same
    against MuJoCo (1.0e-6 m at dt = 5e-4; the coordinates 5.2e-6)."""
    model, g = mujoco_case()
    steps = np.array([2e-3, 1e-3, 5e-4, 2.5e-4])
    runs = [simulate(model, 1.0, dt, record_every=int(round(0.01 / dt))) for dt in steps]
    ref = simulate_reference(model, 1.0, t_eval=runs[0].t, rtol=1e-12, atol=1e-12)
    errors = np.array([_off(r, {"position_input": ref.position_input,
                                "tip": ref.position_output[:, 1]}) for r in runs])
    assert 1.9 < _order(steps, errors) < 2.1, errors
    assert errors[2] < 2e-6, errors
    assert _off(runs[2], g) < 2e-6, _off(runs[2], g)
    assert np.abs(runs[2].joint_coordinates - g["joint_coordinates"]).max() < 1e-5


@pytest.mark.parametrize("drives", [
    (SpringDamper(60.0, 0.5, rest=0.0), SpringDamper(90.0, 0.8, rest=0.0),
     SpringDamper(0.5, 0.02, rest=0.0)),
    (JointMotion(lambda t: 0.2 + 0.1 * np.sin(3 * t), lambda t: 0.3 * np.cos(3 * t),
                 lambda t: -0.9 * np.sin(3 * t)),
     JointForce(lambda t, q, qd: 2.0 * np.sin(5 * t) - 20.0 * q - 0.5 * qd),
     JointForce(lambda t, q, qd: 0.05 * np.cos(4 * t) - 0.01 * qd)),
    (None, PDTracking(kp=80.0, kd=4.0, target=lambda t: -0.1 + 0.2 * t,
                      target_rate=lambda t: 0.2),
     PDTracking(kp=1.0, kd=0.1, target=lambda t: 0.5 + 1.5 * t, target_rate=lambda t: 1.5)),
], ids=["springs", "motion-and-forces", "pd"])
def test_drives_on_each_coordinate_follow_the_reference(drives):
    """A drive on each coordinate (N along n1 and n2, N m about the normal): DT-TMM against
    the reference at order 2 (dt = 1e-3, 5e-4), positions and the drives' generalized forces
    (measured at 5e-4: springs 1.6e-6 m, their forces 4.8e-6 of the peak; a prescribed x and
    forces on y and theta 5.5e-6 m, 9.5e-6 (x's force, the prescribed motion's); PD on y and
    theta 9.6e-7 m, 2.1e-6)."""
    model, _ = mujoco_case(drives=drives)
    steps = np.array([1e-3, 5e-4])
    runs = [simulate(model, 1.0, dt, record_every=int(round(0.01 / dt))) for dt in steps]
    ref = simulate_reference(model, 1.0, t_eval=runs[0].t, rtol=1e-12, atol=1e-12)
    pos = np.array([np.abs(r.position_output - ref.position_output).max() for r in runs])
    force = np.array([np.abs(r.drive_force - ref.drive_force).max() for r in runs])
    peak = np.abs(ref.drive_force).max()
    assert abs(_order(steps, pos) - 2.0) < 0.1, pos
    assert abs(_order(steps, force) - 2.0) < 0.1, force
    assert pos[-1] < 1e-5, pos
    assert force[-1] < 2e-5 * peak, (force, peak)
    driven = [i for i, d in enumerate(drives) if d is not None]
    assert (np.abs(ref.drive_force[:, driven]).max(axis=0) > 0.05).all()    # (each one acts)


def test_statics_holds_the_body_where_the_springs_carry_its_weight():
    """On the tilted plane (n1, n2 as above, gravity -9.81 along z) springs on the slides hold
    a 1.5 kg body where k1 x = m g . n1 and k2 y = m g . n2 (the slides' generalized forces
    whatever the angle; to 1e-10), and a torsion spring where k theta = N . (A(theta) c x m g),
    the weight's moment about the normal through the input point (c: the mass centre's
    offset); a run from there stays (1e-9)."""
    m, k1, k2, k_t = 1.5, 400.0, 300.0, 2.0
    gravity = np.array([0.0, 0.0, -9.81])
    offset = np.array([0.05, 0.1, -0.02])
    system = System(gravity=gravity)
    system.add(RigidBody(mass=m, inertia=INERTIA, inertia_about="mass_center",
                         to_mass_center=offset, to_output=[0.2, 0.1, 0.0], name="puck"),
               PlanarJoint(axis1=N1 * 3.0, axis2=N2, coordinates=(0.1, 0.0, 0.3),
                           drives=(SpringDamper(k1, 3.0, rest=0.0),
                                   SpringDamper(k2, 3.0, rest=0.0),
                                   SpringDamper(k_t, 0.1, rest=0.0)), name="table"))
    eq = static_equilibrium(system.build())
    x, y, theta = eq.model.hinge_params[0, COORDINATE_0][:3]
    assert abs(k1 * x - m * gravity @ N1) < 1e-10, (x, m * gravity @ N1 / k1)
    assert abs(k2 * y - m * gravity @ N2) < 1e-10, (y, m * gravity @ N2 / k2)
    moment = N @ np.cross(rotation_about(N, theta) @ offset, m * gravity)
    assert abs(k_t * theta - moment) < 1e-10, (theta, moment)
    run = simulate(eq.model, 0.2, 1e-3)
    assert np.abs(run.joint_coordinates[-1] - [x, y, theta]).max() < 1e-9


@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), (0.05, 0.1, -0.02)],
                         ids=["centred", "offset"])
def test_linearize_gives_the_springs_frequencies(offset):
    """A body on springs k1, k2 (slides) and k_t (turn), no gravity: its linear model's
    frequencies are the closed form's.  Its mass centre at the input point: w^2 = k1 / m,
    k2 / m and k_t / (N . J N) (measured to 1e-12); offset by c: the eigenvalues of
    M^-1 diag(k1, k2, k_t) with the generalized mass
        M = [[m, 0, m n1 . (N x c)], [0, m, m n2 . (N x c)], [., ., m |N x c|^2 + N . J N]]
    (the mass centre's velocity x' n1 + y' n2 + theta' N x c); static_equilibrium's the same.
    The inputs on the joint (table.force0, force1, torque2) accelerate the coordinates by
    M^-1 e_i."""
    m, k1, k2, k_t = 1.5, 60.0, 90.0, 2.0
    c = np.array(offset)
    system = System(gravity=[0.0, 0.0, 0.0])
    system.add(RigidBody(mass=m, inertia=INERTIA, inertia_about="mass_center", to_mass_center=c,
                         to_output=[0.2, 0.1, 0.0], name="puck"),
               PlanarJoint(axis1=N1, axis2=N2, drives=(SpringDamper(k1, 0.0),
                                                       SpringDamper(k2, 0.0),
                                                       SpringDamper(k_t, 0.0)), name="table"))
    model = system.build()
    lin = dttmm.linearize(model)
    assert lin.states[:3] == ("table.q0", "table.q1", "table.q2")
    assert lin.difference_error < 1e-9
    arm = np.cross(N, c)
    mass = np.array([[m, 0.0, m * N1 @ arm], [0.0, m, m * N2 @ arm],
                     [m * N1 @ arm, m * N2 @ arm, m * arm @ arm + N @ INERTIA @ N]])
    exact = np.sort(np.linalg.eigvals(np.linalg.solve(mass, np.diag([k1, k2, k_t]))).real)
    if not c.any():
        np.testing.assert_allclose(exact, np.sort([k1 / m, k2 / m, k_t / (N @ INERTIA @ N)]),
                                   rtol=1e-14)
    squared = np.sort(-(np.linalg.eigvals(lin.A) ** 2).real)
    np.testing.assert_allclose(squared, np.repeat(exact, 2), rtol=1e-8)
    statics = np.sort(static_equilibrium(model).squared_frequencies)
    np.testing.assert_allclose(statics, exact, rtol=1e-8)
    columns = [lin.inputs.index(f"table.{name}") for name in ("force0", "force1", "torque2")]
    np.testing.assert_allclose(lin.B[3:, columns], np.linalg.inv(mass), rtol=0, atol=1e-8)


def _crank_rod(system):
    """The IFToMM slider-crank's crank and rod (dttmm.model.mechanisms.slider_crank), as
    tests/test_cylindrical_joint.py's; returns the universal joint's cross axis in the rod's
    frame."""
    b, c = np.array([0, 0.1, 0.2]), np.array([0.2, 0, 0])
    system.add(RigidBody(mass=0.12, inertia=[1e-4, 1e-4, 1e-5], inertia_about="mass_center",
                         to_mass_center=[0, 0, 0.04], to_output=[0, 0, 0.08], name="crank",
                         rotation=np.eye(3)), RevoluteJoint(axis=[1, 0, 0], rate=6.0, name="A"))
    rod_frame = _frame(c - b, [0, 0, 1.0])
    system.add(RigidBody(mass=0.5, inertia=[4e-4, 4e-3, 4e-3], inertia_about="mass_center",
                         to_mass_center=[0.15, 0, 0], to_output=[0.3, 0, 0],
                         rotation=rod_frame, name="rod"), BallJoint(name="B"), parent="crank")
    return rod_frame.T @ (np.array([0, -2, 1.0]) / np.sqrt(5))


def table_crank(closing, theta_drive=None):
    """The slider-crank with its slider on a planar joint in the world's x-y plane (free to
    turn about z; springs on x, rest 0.2 m, and y): closing the loop (closing=True: the slider
    hangs from the rod by the universal joint C, the planar joint closes it to the ground;
    theta_drive its drive on theta), or in the tree (the slider on it to the ground, C closes
    the loop).  Returns the System, not built."""
    a = np.array([0, 0.1, 0.12])
    system = System(gravity=[0, 0, -9.81], ground=Ground(position=a))
    across = _crank_rod(system)
    drives = (SpringDamper(40.0, 0.5, rest=0.2), SpringDamper(30.0, 0.5, rest=0.0), theta_drive)
    slider = RigidBody(mass=2.0, inertia=[1.5e-4, 1e-4, 1.2e-4], inertia_about="mass_center",
                       name="slider", **({"rotation": np.eye(3)} if closing else
                                         {"to_mass_center": -a, "to_output": -a}))
    if closing:
        system.add(slider, UniversalJoint(axis1=across, axis2=[1, 0, 0], name="C"),
                   parent="rod")
        system.close(PlanarJoint(axis1=[1, 0, 0], axis2=[0, 1, 0], drives=drives, name="table"),
                     "ground", "slider", at_a=[0, 0, 0])
    else:
        system.add(slider, PlanarJoint(axis1=[1, 0, 0], axis2=[0, 1, 0],
                                       coordinates=(0.2, 0.0, 0.0), drives=drives,
                                       name="table"))
        system.close(UniversalJoint(axis1=[1, 0, 0], axis2=across, name="C"), "slider", "rod")
    return system


@pytest.mark.parametrize("closing", [True, False], ids=["closing", "in-the-tree"])
def test_in_a_loop_it_follows_the_reference(closing):
    """The slider-crank's slider on a planar joint (table_crank), closing the loop or in the
    tree of a loop: as a closing joint it holds 3 rows (the gap along the normal, the normal
    kept by two dots), none redundant, mobility 3; DT-TMM against the reference at order 2
    over 0.5 s (measured 1.9e-6 / 3.0e-6 m at dt = 5e-4, both 2.00), the slider staying in its
    plane, and a closing joint's spring forces (Result.closure_drive_force) 1.2e-5 of their
    peak."""
    model = assemble(table_crank(closing).build(), keep=["A"])
    text = model.describe()
    assert ("3 constraint equations, 0 of them redundant" if closing else
            "4 constraint equations") in text, text
    assert "mobility 3" in text, text
    steps = np.array([1e-3, 5e-4])
    runs = [simulate(model, 0.5, dt, record_every=int(round(0.01 / dt))) for dt in steps]
    ref = simulate_reference(model, 0.5, t_eval=runs[0].t, rtol=1e-11, atol=1e-11)
    pos = np.array([np.abs(r.position_output - ref.position_output).max() for r in runs])
    assert abs(_order(steps, pos) - 2.0) < 0.1, pos
    assert pos[-1] < 5e-6, pos
    slider = model.body_names.index("slider")
    assert np.ptp(ref.position_input[:, slider], axis=0)[:2].min() > 0.03
    assert np.ptp(runs[-1].position_input[:, slider, 2]) < 1e-9
    if closing:
        force = np.array([np.abs(r.closure_drive_force - ref.closure_drive_force).max()
                          for r in runs])
        assert abs(_order(steps, force) - 2.0) < 0.1, force
        assert force[-1] < 3e-5 * np.abs(ref.closure_drive_force).max(), force


def test_a_closing_planar_joints_drive_on_theta_is_refused():
    """A closing joint's drives go on its first two coordinates (elements/kinds.py,
    CLOSING_DRIVES: the closing joints' records hold two); a drive on a closing planar joint's
    theta is refused at build time, naming the joint and the argument.  In the tree it runs."""
    system = table_crank(True, theta_drive=SpringDamper(1.0, 0.1))
    with pytest.raises(ValueError, match=r"PlanarJoint 'table' \(closure 0\).*first 2 "
                                         r"coordinates.*drives\[2\]"):
        system.build()
    model = assemble(table_crank(False, theta_drive=SpringDamper(1.0, 0.1)).build(),
                     keep=["A"])
    assert np.isfinite(simulate(model, 0.01, 1e-3).position_output).all()


def test_the_shortest_tree_takes_it_from_its_loop_at_the_gap_or_keeps_it():
    """System.build(tree="shortest"): a planar joint closing the loop (table_crank(True)) joins
    the tree, the ground's second edge to the slider, starting at the gap between its points,
    (x, y, theta) = (0.2, 0, 0) (it was refused: taken as it stood, it would have started at
    (0, 0, 0)), the loop closed at t = 0 (measured 7e-17 m); its springs as given (their rests
    given).  One in the tree as added stays there (the same tree here: the same run to
    1e-12 m).  (Its runs from both trees: tests/test_spanning_tree.py.)"""
    model = table_crank(True).build(tree="shortest")
    k = model.body_names.index("slider")
    assert model.hinge_names[k] == "table" and model.parent[k] == -1
    assert model.closure_names == ("C",)
    assert np.abs(model.hinge_params[k, COORDINATE_0] - [0.2, 0.0, 0.0]).max() < 1e-14
    assert dttmm.loop_residuals(model)[0].max() < 1e-12
    assert [d["rest"] for d in model.drives[k][:2]] == [0.2, 0.0]
    system = table_crank(False)
    as_added = assemble(system.build(), keep=["A"])
    shortest = assemble(system.build(tree="shortest"), keep=["A"])
    assert shortest.closure_names == ("C",)
    a, b = simulate(as_added, 0.05, 1e-3), simulate(shortest, 0.05, 1e-3)
    for name in as_added.body_names:
        i, j = as_added.body_names.index(name), shortest.body_names.index(name)
        assert np.abs(a.position_output[:, i] - b.position_output[:, j]).max() < 1e-12


def test_a_scene_file_writes_and_reads_it_back(tmp_path):
    """save_scene / load_scene: the same model (its arrays), the same run; and a scene written
    by hand with type "planar" builds the same joint as Python does."""
    from dttmm.model.profiles import profile
    from dttmm.interfaces.scene import load_scene, save_scene
    p = profile({"profile": "sine", "amplitude": 0.05, "frequency": 0.5, "offset": 0.2}, "x")
    model, _ = mujoco_case(drives=(JointMotion(p, p.rate, p.acceleration),
                                   SpringDamper(8.0, 0.3, rest=0.1), None),
                           rates=(0.0, -0.4, 1.5))
    path = tmp_path / "table.toml"
    save_scene(model, path)
    text = path.read_text()
    assert 'type = "planar"' in text and "axis1 = [" in text and "axis2 = [" in text
    again = load_scene(path).model
    for key in ("hinge_kind", "hinge_params", "initial_rotation", "initial_angular_velocity"):
        assert np.allclose(getattr(again, key), getattr(model, key), rtol=0, atol=1e-15), key
    a, b = simulate(model, 0.05, 1e-3), simulate(again, 0.05, 1e-3)
    assert np.abs(a.position_output - b.position_output).max() < 1e-14

    by_hand = tmp_path / "puck.toml"
    by_hand.write_text("""
[model]
gravity = [0.0, 0.0, -9.81]

[[body]]
name = "puck"
type = "rigid"
mass = 1.5
inertia = [0.02, 0.025, 0.03]
inertia_about = "mass_center"

[body.joint]
type = "planar"
name = "table"
parent = "ground"
axis1 = [1.0, 0.0, 0.0]
axis2 = [0.0, 0.0, 1.0]
coordinates = [0.1, 0.2, 0.3]
rates = [0.0, 0.5, 0.0]
drives = [{ type = "spring_damper", stiffness = 50.0, damping = 0.5 }, { type = "none" },
          { type = "none" }]
""")
    built = load_scene(by_hand).model
    system = System(gravity=[0.0, 0.0, -9.81])
    system.add(RigidBody(mass=1.5, inertia=[0.02, 0.025, 0.03], inertia_about="mass_center",
                         name="puck"),
               PlanarJoint(axis1=[1, 0, 0], axis2=[0, 0, 1], coordinates=(0.1, 0.2, 0.3),
                           rates=(0.0, 0.5, 0.0), drives=(SpringDamper(50.0, 0.5), None, None),
                           name="table"))
    direct = system.build()
    assert built.hinge_names == ("table",)
    np.testing.assert_array_equal(built.hinge_params, direct.hinge_params)
    np.testing.assert_array_equal(built.hinge_kind, direct.hinge_kind)
    assert "on a planar joint 'table'" in built.describe()


@pytest.mark.parametrize("joint, words", [
    (PlanarJoint(axis1=[0, 0, 0], axis2=[0, 1, 0], name="j"),
     "'j'.*axis1 must be a nonzero vector"),
    (PlanarJoint(axis1=[1, 0, 0], axis2=[0, 0, 0], name="j"),
     "'j'.*axis2 must be a nonzero vector"),
    (PlanarJoint(axis1=[1, 0, 0], axis2=[1, 1e-3, 0], name="j"),
     "'j'.*axis1 and axis2 must be perpendicular"),
    (PlanarJoint(axis1=[1, 0, 0], axis2=[2, 0, 0], name="j"),
     "'j'.*axis1 and axis2 must be perpendicular.*0 deg"),
    (PlanarJoint(axis1=[1, 0, 0, 0], axis2=[0, 1, 0], name="j"), "'j'.*axis1 must have 3"),
    (PlanarJoint(axis1=[1, 0, np.inf], axis2=[0, 1, 0], name="j"),
     "'j'.*axis1 contains NaN or infinite"),
    (PlanarJoint(axis1=[1, 0, 0], axis2=[0, 1, 0], coordinates=(0.1, 0.2), name="j"),
     "'j'.*coordinates must be 3 entries"),
    (PlanarJoint(axis1=[1, 0, 0], axis2=[0, 1, 0], coordinates=0.1, name="j"),
     "'j'.*coordinates must be 3 entries"),
    (PlanarJoint(axis1=[1, 0, 0], axis2=[0, 1, 0], rates=(0.0, 0.0), name="j"),
     "'j'.*rates must be 3 entries"),
    (PlanarJoint(axis1=[1, 0, 0], axis2=[0, 1, 0], drives=(None, None), name="j"),
     "'j'.*drives must be 3 entries"),
    (PlanarJoint(axis1=[1, 0, 0], axis2=[0, 1, 0], drives=(None, None, 3.0), name="j"),
     "'j'.*drive must be a JointForce"),
    (PlanarJoint(axis1=[1, 0, 0], axis2=[0, 1, 0], coordinates=(0.0, 0.0, np.nan), name="j"),
     "'j'.*coordinates\\[2\\]"),
    (PlanarJoint(axis1=[1, 0, 0], axis2=[0, 1, 0], rates=(np.inf, 0.0, 0.0), name="j"),
     "'j'.*rates\\[0\\]"),
    (PlanarJoint(axis1=[1, 0, 0], axis2=[0, 1, 0], coordinates=(0.0, "1", 0.0), name="j"),
     "'j'.*coordinates\\[1\\] must be a number"),
])
def test_bad_input_names_the_joint_and_argument(joint, words):
    system = System()
    system.add(RigidBody(mass=1.0, inertia=0.1, inertia_about="mass_center"), joint)
    with pytest.raises(ValueError, match=words):
        system.build()


def test_it_is_declared_once():
    """Its declaration (elements/kinds.py): slides along axes 1 and 2 and a turn about axis 3
    (the normal validated() derives), all fixed in the parent; its scene type, three degrees
    of freedom, three constraint equations as a closing joint; Result's columns follow it, and
    its axes and coordinates are where the declaration says."""
    from dttmm.elements.kinds import (AXES, JOINT_KIND, PARENT, SLIDE, TURN, joint_kind_of,
                                      joint_motion, row_axes)
    kind = joint_kind_of(PlanarJoint(axis1=[1, 0, 0], axis2=[0, 1, 0]))
    assert [(c.motion, c.axis, c.frame) for c in kind.coordinates] == [
        (SLIDE, 0, PARENT), (SLIDE, 1, PARENT), (TURN, 2, PARENT)]
    assert (kind.scene, kind.dof, kind.constraints) == ("planar", 3, 3)
    assert kind.axes == ("axis1", "axis2") and JOINT_KIND[kind.code] is kind
    model, g = mujoco_case()
    h = model.hinge_params[0]
    np.testing.assert_allclose([h[a] for a in AXES], [N1, N2, N], rtol=0, atol=1e-15)
    q, qd = h[COORDINATE_0][:3], np.array([0.3, -0.4, 1.5])
    rot, w, d, d_rate, _ = joint_motion(kind.code, row_axes(h), np.eye(3), np.eye(3),
                                        np.zeros(3), q, qd)
    np.testing.assert_allclose(rot, rotation_about(N, 0.5), atol=1e-15)
    np.testing.assert_allclose(d, 0.2 * N1 - 0.1 * N2, atol=1e-15)
    np.testing.assert_allclose(w, 1.5 * N, atol=1e-15)
    np.testing.assert_allclose(d_rate, 0.3 * N1 - 0.4 * N2, atol=1e-15)
    res = simulate(model, 2e-3, 1e-3)
    assert res.info["coordinate_names"][:3] == ["table 1", "table 2", "table 3"]
    assert "on a planar joint 'table'" in model.describe()
    assert dttmm.PlanarJoint is PlanarJoint and "PlanarJoint" in dttmm.__all__
