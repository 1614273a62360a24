"""CylindricalJoint (docs/joints.md, "Cylindrical joint"): a turn about and a slide
along one axis fixed in the parent.  The Newton-Euler reference against an independent MuJoCo
run (tests/data/mujoco_joints.py), DT-TMM against both (order 2 against the reference), drives
on each coordinate, statics, loops (in the tree and closing), scenes, describe and its build
checks."""
from pathlib import Path

import numpy as np
import pytest

from dttmm import (BallJoint, CylindricalJoint, Ground, JointForce, JointMotion, PDTracking,
                   RevoluteJoint, RigidBody, SpringDamper, System, UniversalJoint, assemble,
                   simulate, static_equilibrium)
from dttmm.elements.kinds import COORDINATE_0
from dttmm.model.mechanisms import _frame
from dttmm.reference import simulate_reference

DATA = Path(__file__).resolve().parent / "data" / "mujoco_cylindrical.npz"


def _order(steps, errors):
    return np.polyfit(np.log(steps), np.log(errors), 1)[0]


def _body(g, name):
    return RigidBody(mass=float(g[f"geo_{name}_mass"]), inertia=g[f"geo_{name}_j_c"],
                     inertia_about="mass_center", to_mass_center=g[f"geo_{name}_l_ic"],
                     to_output=g[f"geo_{name}_l_io"], name=name)


def mujoco_case(drives=(None, None), rates=None):
    """(model, data): the MuJoCo run's system (tests/data/mujoco_joints.py's header) rebuilt
    from the data's geometry: a carrier on CylindricalJoint(axis=(2, 2, 1)/3, coordinates=(0.3,
    0.1), rates=(2, -0.5)) to the ground point, a link on a revolute joint (its y) at the
    carrier's output point; gravity -9.81 along z."""
    g = np.load(DATA)
    system = System(gravity=list(g["geo_gravity"]))
    system.add(_body(g, "carrier"),
               CylindricalJoint(axis=g["geo_axis"], coordinates=tuple(g["geo_coordinates"]),
                                rates=tuple(g["geo_rates"]) if rates is None else rates,
                                drives=drives, name="sleeve"))
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
    """The Newton-Euler reference (tight tolerance) against MuJoCo's RK4 run (its own error
    3e-14 m, against dt / 2): positions of both frames and the tip, and the coordinates in
    Result's order (theta, s, then the link's angle), over 1 s (measured 2.8e-12 m)."""
    model, g = mujoco_case()
    ref = simulate_reference(model, 1.0, t_eval=g["t"], rtol=1e-12, atol=1e-12)
    assert _off(ref, g) < 1e-9
    assert np.abs(ref.joint_coordinates - g["joint_coordinates"]).max() < 1e-9
    assert np.abs(ref.position_output[:, 0] - ref.position_input[:, 1]).max() < 1e-15


def test_dttmm_follows_mujoco_and_the_reference_at_order_two():
    """DT-TMM's trapezoidal step: positions against the reference at dt = 2e-3 .. 2.5e-4 over
    1 s fall at order 2 (measured 1.07e-5, 2.69e-6, 6.72e-7, 1.68e-7 m: 2.000), so the error
    is C dt^2 with C = 2.7 m/s^2.  At dt = 5e-4 that predicts 6.7e-7 m against MuJoCo too (the
    reference is 2.5e-12 m from it): within 1e-6 m over the run's 1.7 m of travel, the
    coordinates within 3e-6 (measured 2.1e-6: theta's, the larger)."""
    model, g = mujoco_case()
    steps = np.array([2e-3, 1e-3, 5e-4, 2.5e-4])
    runs = [simulate(model, 1.0, dt, record_every=int(round(0.01 / dt))) for dt in steps]
    ref = simulate_reference(model, 1.0, t_eval=runs[0].t, rtol=1e-12, atol=1e-12)
    errors = np.array([_off(r, {"position_input": ref.position_input,
                                "tip": ref.position_output[:, 1]}) for r in runs])
    assert abs(_order(steps, errors) - 2.0) < 0.05, errors
    assert _off(runs[2], g) < 1e-6, _off(runs[2], g)
    assert np.abs(runs[2].joint_coordinates - g["joint_coordinates"]).max() < 3e-6


@pytest.mark.parametrize("drives", [
    (SpringDamper(8.0, 0.3, rest=0.0), SpringDamper(150.0, 2.0, rest=0.0)),
    (JointForce(lambda t, q, qd: 0.5 * np.sin(5 * t) - 0.2 * qd),
     JointMotion(lambda t: 0.1 - 0.125 * np.sin(4 * t), lambda t: -0.5 * np.cos(4 * t),
                 lambda t: 2.0 * np.sin(4 * t))),
    (PDTracking(kp=20.0, kd=1.0, target=lambda t: 0.3 + 0.5 * t, target_rate=lambda t: 0.5),
     None),
], ids=["springs", "force-and-motion", "pd"])
def test_drives_on_each_coordinate_follow_the_reference(drives):
    """A drive on each coordinate (N m on theta, N along s): DT-TMM against the reference at
    order 2 (dt = 1e-3, 5e-4), positions and the drives' generalized forces (measured at
    5e-4: springs 2.3e-6 m, their forces 2.9e-6 of the peak; a force on theta and a prescribed
    slide 6.9e-7 m, the slide's force 7.9e-7 of the peak; PD on theta 1.5e-6 m)."""
    model, _ = mujoco_case(drives=drives)
    steps = np.array([1e-3, 5e-4])
    runs = [simulate(model, 1.0, dt, record_every=int(round(0.01 / dt))) for dt in steps]
    ref = simulate_reference(model, 1.0, t_eval=runs[0].t, rtol=1e-12, atol=1e-12)
    pos = np.array([np.abs(r.position_output - ref.position_output).max() for r in runs])
    force = np.array([np.abs(r.drive_force - ref.drive_force).max() for r in runs])
    peak = np.abs(ref.drive_force).max()
    assert abs(_order(steps, pos) - 2.0) < 0.1, pos
    assert pos[-1] < 5e-6, pos
    assert force[-1] < 1e-5 * peak, (force, peak)


def test_statics_holds_a_body_where_the_spring_carries_its_weight():
    """A vertical cylindrical joint (axis along -g) with a SpringDamper on its slide holds a
    2 kg body where k s = -m g (s = -m g / k along the axis), its turn on a torsion spring at
    its rest (a free turn about the vertical would be neutral)."""
    k, m, g = 400.0, 2.0, 9.81
    system = System(gravity=[0.0, 0.0, -g])
    system.add(RigidBody(mass=m, inertia=[0.02, 0.03, 0.04], inertia_about="mass_center",
                         to_mass_center=[0.05, 0.0, 0.1], to_output=[0.1, 0.0, 0.2],
                         name="body"),
               CylindricalJoint(axis=[0, 0, 2.0], coordinates=(0.2, 0.0),
                                drives=(SpringDamper(3.0, 0.1, rest=0.5),
                                        SpringDamper(k, 5.0, rest=0.0)), name="sleeve"))
    eq = static_equilibrium(system.build())
    theta, s = eq.model.hinge_params[0, COORDINATE_0][:2]
    assert abs(s + m * g / k) < 1e-10 and abs(theta - 0.5) < 1e-10, (theta, s)
    run = simulate(eq.model, 0.2, 1e-3)
    assert np.abs(run.joint_coordinates[-1] - [0.5, -m * g / k]).max() < 1e-9


def _crank_rod(system):
    """The IFToMM slider-crank's crank and rod (dttmm.model.mechanisms.slider_crank); returns the
    universal joint's cross axis in the rod's frame."""
    b, c = np.array([0, 0.1, 0.2]), np.array([0.2, 0, 0])
    system.add(RigidBody(mass=0.12, inertia=[1e-4, 1e-4, 1e-5], inertia_about="mass_center",
                         to_mass_center=[0, 0, 0.04], to_output=[0, 0, 0.08], name="crank",
                         rotation=np.eye(3)), RevoluteJoint(axis=[1, 0, 0], rate=6.0, name="A"))
    rod_frame = _frame(c - b, [0, 0, 1.0])
    system.add(RigidBody(mass=0.5, inertia=[4e-4, 4e-3, 4e-3], inertia_about="mass_center",
                         to_mass_center=[0.15, 0, 0], to_output=[0.3, 0, 0],
                         rotation=rod_frame, name="rod"), BallJoint(name="B"), parent="crank")
    return rod_frame.T @ (np.array([0, -2, 1.0]) / np.sqrt(5))


def sleeve_crank(closing):
    """The slider-crank with its slider on a cylindrical joint along world x (free to turn
    about it too, on a torsion spring): closing the loop (closing=True: the slider hangs from
    the rod by the universal joint C, the sleeve closes it to the ground), or in the tree
    (the slider on the sleeve to the ground, C closes the loop); assembled keeping "A"."""
    a = np.array([0, 0.1, 0.12])
    system = System(gravity=[0, 0, -9.81], ground=Ground(position=a))
    across = _crank_rod(system)
    drives = (SpringDamper(0.05, 1e-3), SpringDamper(40.0, 0.5, rest=0.2))
    slider = RigidBody(mass=2.0, inertia=[1.5e-4, 1e-4, 1e-4], inertia_about="mass_center",
                       name="slider", **({"rotation": np.eye(3)} if closing else
                                         {"to_mass_center": -a, "to_output": -a}))
    if closing:
        system.add(slider, UniversalJoint(axis1=across, axis2=[1, 0, 0], name="C"),
                   parent="rod")
        system.close(CylindricalJoint(axis=[1, 0, 0], drives=drives, name="sleeve"), "ground",
                     "slider", at_a=[0, 0, 0])
    else:
        system.add(slider, CylindricalJoint(axis=[1, 0, 0], coordinates=(0.0, 0.2),
                                            drives=drives, name="sleeve"))
        system.close(UniversalJoint(axis1=[1, 0, 0], axis2=across, name="C"), "slider", "rod")
    return assemble(system.build(), keep=["A"])


@pytest.mark.parametrize("closing", [True, False], ids=["closing", "in-the-tree"])
def test_in_a_loop_it_follows_the_reference(closing):
    """The slider-crank's slider on a cylindrical joint (sleeve_crank), closing the loop or in
    the tree of a loop: 4 constraint equations as a closing joint (describe; the universal
    joint's 4 too), and DT-TMM against the reference at order 2 over 0.5 s (measured 3.0e-6 /
    1.7e-6 m at dt = 5e-4, both 2.00)."""
    model = sleeve_crank(closing)
    text = model.describe()
    assert "4 constraint equations" in text, text      # (the sleeve's, or C's)
    steps = np.array([1e-3, 5e-4])
    runs = [simulate(model, 0.5, dt, record_every=int(round(0.01 / dt))) for dt in steps]
    ref = simulate_reference(model, 0.5, t_eval=runs[0].t, rtol=1e-11, atol=1e-11)
    pos = np.array([np.abs(r.position_output - ref.position_output).max() for r in runs])
    assert abs(_order(steps, pos) - 2.0) < 0.1, pos
    assert pos[-1] < 5e-6, pos


def test_a_scene_file_writes_and_reads_it_back(tmp_path):
    """save_scene / load_scene: the same model (its arrays and drives), the same run."""
    from dttmm.model.profiles import profile
    from dttmm.interfaces.scene import load_scene, save_scene
    p = profile({"profile": "sine", "amplitude": 0.05, "frequency": 0.5, "offset": 0.1}, "s")
    model, _ = mujoco_case(drives=(SpringDamper(8.0, 0.3, rest=0.1),
                                   JointMotion(p, p.rate, p.acceleration)), rates=(2.0, 0.0))
    path = tmp_path / "sleeve.toml"
    save_scene(model, path)
    text = path.read_text()
    assert 'type = "cylindrical"' in text and "coordinates = [" in text
    again = load_scene(path).model
    for key in ("hinge_kind", "hinge_params", "initial_rotation", "initial_angular_velocity"):
        assert np.allclose(getattr(again, key), getattr(model, key), rtol=0, atol=1e-15), key
    a, b = simulate(model, 0.05, 1e-3), simulate(again, 0.05, 1e-3)
    assert np.abs(a.position_output - b.position_output).max() < 1e-14


@pytest.mark.parametrize("joint, words", [
    (CylindricalJoint(axis=[0, 0, 0], name="j"), "'j'.*axis must be a nonzero vector"),
    (CylindricalJoint(axis=[0, 0, 1], coordinates=(0.1,), name="j"),
     "'j'.*coordinates must be a pair"),
    (CylindricalJoint(axis=[0, 0, 1], coordinates=0.1, name="j"),
     "'j'.*coordinates must be a pair"),
    (CylindricalJoint(axis=[0, 0, 1], rates=(0.0, 0.0, 0.0), name="j"),
     "'j'.*rates must be a pair"),
    (CylindricalJoint(axis=[0, 0, 1], drives=(None,), name="j"), "'j'.*drives must be a pair"),
    (CylindricalJoint(axis=[0, 0, 1], drives=(None, 3.0), name="j"),
     "'j'.*drive must be a JointForce"),
    (CylindricalJoint(axis=[0, 0, 1], coordinates=(0.0, np.nan), name="j"),
     "'j'.*coordinates\\[1\\]"),
])
def test_bad_input_names_the_joint_and_argument(joint, words):
    system = System()
    system.add(RigidBody(mass=1.0, inertia=0.1, inertia_about="mass_center"), joint)
    with pytest.raises(ValueError, match=words):
        system.build()


def test_it_is_declared_once():
    """Its declaration (elements/kinds.py): a turn and a slide about one axis fixed in the
    parent, its scene type, two degrees of freedom, four constraint equations as a closing
    joint; Result's columns follow it."""
    from dttmm.elements.kinds import JOINT_KIND, PARENT, SLIDE, TURN, joint_kind_of
    kind = joint_kind_of(CylindricalJoint(axis=[0, 0, 1]))
    assert [(c.motion, c.axis, c.frame) for c in kind.coordinates] == [(TURN, 0, PARENT),
                                                                       (SLIDE, 0, PARENT)]
    assert (kind.scene, kind.dof, kind.constraints) == ("cylindrical", 2, 4)
    assert JOINT_KIND[kind.code] is kind
    model, _ = mujoco_case()
    res = simulate(model, 2e-3, 1e-3)
    assert res.info["coordinate_names"][:2] == ["sleeve 1", "sleeve 2"]
    assert "on a cylindrical joint 'sleeve'" in model.describe()
