"""Contact of bodies' shapes with a ground plane (issue 67, item 3; docs/contact.md).

Every check is against physics the code does not compute: a ball's rebound at e times the speed
it struck at, whatever the speed (the law scales with it), and its bounces' heights falling as
e^2; a block sliding down a slope at g (sin a - mu cos a) and held below the friction angle; a
ball rolling down a slope without slipping at 5/7 g sin a (friction's moment through the contact
point's arm); a box and a capsule at rest at the penetration their weight sets, m g / (n k)."""
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import dttmm
from dttmm import (Box, Capsule, Contact, FreeJoint, Ground, Plane, RigidBody, Sphere,
                   build_chain, simulate)
from dttmm.elements.contact import (damping_of_restitution, restitution_of_damping)
from dttmm.model.chains import bouncing_ball, box_on_incline, incline_normal

G = 9.81
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))   # (the examples)


def _ball(radius=0.05, mass=2.0, contact=None, position=(0.0, 0.0, 1.0), velocity=(0, 0, 0),
          gravity=(0.0, 0.0, -G), plane=Plane(), omega=None):
    ball = RigidBody(mass=mass, inertia=0.4 * mass * radius ** 2, inertia_about="mass_center",
                     name="ball", shapes=Sphere(radius), angular_velocity=omega,
                     contact=contact or Contact(contact_time=1e-3, restitution=0.8))
    return build_chain([FreeJoint(position=position, velocity=velocity), ball],
                       gravity=gravity, ground=Ground(plane=plane))


def test_the_laws_restitution_is_its_scaled_rebound():
    """damping_of_restitution inverts restitution_of_damping (a scaled ODE solved by scipy):
    e(0) = 1, falling monotonically; the damping found gives the restitution asked to 1e-9."""
    assert restitution_of_damping(0.0) == 1.0
    values = [restitution_of_damping(a) for a in (0.1, 0.3, 1.0, 3.0)]
    assert all(x > y for x, y in zip(values, values[1:]))
    for e in (0.05, 0.3, 0.8, 0.99):
        assert restitution_of_damping(damping_of_restitution(e)) == pytest.approx(e, abs=1e-9)


@pytest.mark.parametrize("speed", [0.1, 1.0, 10.0])
@pytest.mark.parametrize("restitution", [0.3, 0.8, 1.0])
def test_a_ball_rebounds_at_e_times_its_speed_whatever_the_speed(speed, restitution):
    """Without gravity, a ball struck onto the plane at 0.1, 1 or 10 m/s leaves at e times that
    speed (e = 0.3, 0.8 and 1: energy kept), to 0.1%, with 100 steps a contact: the law is
    homogeneous in (delta, delta'), so the scaled motion is the same at every speed."""
    contact_time = 1e-3
    model = _ball(contact=Contact(contact_time=contact_time, restitution=restitution),
                  position=(0.0, 0.0, 0.05 + 0.5 * speed * contact_time),
                  velocity=(0.0, 0.0, -speed), gravity=(0.0, 0.0, 0.0))
    result = simulate(model, 2.5 * contact_time, contact_time / 100)
    assert result.velocity_input[-1, 0, 2] == pytest.approx(restitution * speed, rel=1e-3)
    assert result.contact_force[-1, 0] == pytest.approx(np.zeros(3), abs=0.0)   # it left


def test_the_bouncing_balls_heights_fall_as_e_squared():
    """The steel ball of examples/bouncing_ball.py (4.11 kg, contacts of ~0.2 ms, restitution
    0.8) dropped from 1 m, steps chosen by the error: its first five rebounds each 0.64 of the
    height before, to 0.1% (the issue asks 2%; gravity during a contact, 1e-4 of its force,
    costs ~3e-4 by the fifth)."""
    import bouncing_ball as example
    result = example.run(3.0)
    heights = example.bounce_heights(result)
    assert len(heights) >= 6
    np.testing.assert_allclose(heights[1:6] / heights[:5], 0.64, rtol=1e-3)
    assert result.info["newton_unconverged_steps"] == 0


@pytest.mark.parametrize("mu,angle", [(0.3, 30.0), (0.1, 15.0)])
def test_a_box_slides_down_the_slope_at_the_closed_form_acceleration(mu, angle):
    """tan a > mu: the box's distance and speed down the slope after 2 s, g (sin a - mu cos a)
    t^2 / 2 and its rate, to 1e-4 (the issue asks 1%)."""
    import incline
    table = incline.columns(incline.run(mu, angle, 2.0, 1e-4), angle)
    s, v = incline.closed_form(mu, angle, table[:, 0])
    assert table[-1, 1] == pytest.approx(s[-1], rel=1e-4)
    assert table[-1, 2] == pytest.approx(v[-1], rel=1e-4)


def test_friction_holds_the_box_below_the_friction_angle():
    """tan a = 0.176 < mu = 0.3: the box stays, creeping by at most 1 mm over 2 s (0.15 mm:
    the smooth law's v_s r / sqrt(1 - r^2), r = tan a / mu, to 2%)."""
    import incline
    table = incline.columns(incline.run(0.3, 10.0, 2.0, 1e-4), 10.0)
    assert abs(table[-1, 1]) < 1e-3
    r = np.tan(np.radians(10.0)) / 0.3
    assert table[-1, 2] == pytest.approx(1e-4 * r / np.sqrt(1 - r * r), rel=0.02)


def test_a_ball_rolls_down_a_slope_without_slipping():
    """A ball (friction 0.5, well above the 2/7 tan a rolling needs) released on a 20 degree
    slope rolls: its centre accelerates at 5/7 g sin a, to 0.5%, and its spin keeps pace,
    w r = v: friction acts at the contact point, turning the ball through its arm."""
    angle, radius = np.radians(20.0), 0.1
    normal = incline_normal(angle)
    model = _ball(radius=radius, mass=1.0, position=radius * normal,
                  contact=Contact(contact_time=2e-3, restitution=0.5, friction=0.5),
                  plane=Plane(normal=normal))
    result = simulate(model, 1.0, 1e-4, record_every=100)
    down = np.array([np.cos(angle), 0.0, -np.sin(angle)])
    v = result.velocity_input[-1, 0] @ down
    assert v == pytest.approx(5.0 / 7.0 * G * np.sin(angle) * 1.0, rel=5e-3)
    assert result.angular_velocity[-1, 0, 1] * radius == pytest.approx(v, rel=5e-3)


def test_a_box_and_a_capsule_rest_at_the_penetration_their_weight_sets():
    """Dropped flat from 1 cm, a 2 kg box settles on its four lower corners at m g / (4 k)
    below its 5 cm half height, and a capsule lying along x on its two end spheres at
    m g / (2 k) below its radius, to 1e-9 m; the contact forces carry its weight, at points on
    the plane, along its normal."""
    k = 1e6
    sides = np.array([0.3, 0.2, 0.1])
    box = RigidBody(mass=2.0, inertia=2.0 * (np.sum(sides ** 2) - sides ** 2) / 12,
                    inertia_about="mass_center", name="box", shapes=Box(sides),
                    contact=Contact(stiffness=k, restitution=0.3))
    capsule = RigidBody(mass=2.0, inertia=[1e-3, 0.02, 0.02], inertia_about="mass_center",
                        name="capsule", shapes=Capsule(0.04, [-0.2, 0, 0], [0.2, 0, 0]),
                        contact=Contact(stiffness=k, restitution=0.3))
    for body, rest, touching in ((box, 0.05, 4), (capsule, 0.04, 2)):
        model = build_chain([FreeJoint(position=[0.0, 0.0, rest + 0.01]), body],
                            gravity=[0.0, 0.0, -G], ground=Ground(plane=Plane()))
        result = simulate(model, 1.5, 2e-4, record_every=50)
        assert result.position_input[-1, 0, 2] == pytest.approx(
            rest - 2.0 * G / (touching * k), abs=1e-9)
        force = result.contact_force[-1]
        assert force.sum(axis=0) == pytest.approx([0.0, 0.0, 2.0 * G], abs=1e-6)
        assert np.count_nonzero(force[:, 2]) == touching
        pushing = force[:, 2] > 0
        assert result.contact_point[-1][pushing, 2] == pytest.approx(
            -2.0 * G / (touching * k), abs=1e-9)
        assert result.contact_normal[-1] == pytest.approx(np.tile([0, 0, 1.0], (len(force), 1)))


def _free_balls(specs, gravity=(0.0, 0.0, 0.0), plane=None):
    """Balls on free joints from the ground: specs of (name, radius, mass, position, velocity,
    Contact)."""
    system = dttmm.System(gravity=list(gravity), ground=Ground(plane=plane))
    for name, radius, mass, position, velocity, contact in specs:
        system.add(RigidBody(mass=mass, inertia=0.4 * mass * radius ** 2,
                             inertia_about="mass_center", name=name, shapes=Sphere(radius),
                             contact=contact), FreeJoint(position=position, velocity=velocity))
    return system.build()


def test_two_balls_part_at_e_times_the_speed_they_closed_at():
    """Two free balls of 1 and 3 kg striking head on along a slanted line, no gravity, e = 0.8
    (the pair's law: the stiffnesses in series, w from the reduced mass): they part at 0.8 of
    their closing speed, to 1e-3, with the momentum before (to 1e-8 kg m/s: the forces are
    equal and opposite at the guess, and the two bodies' steps apply them to the Newton
    tolerance, k newton_tol ~ 1e-6 N a step; measured 6e-10), v_1 = -2.05 and v_2 = 0.35 m/s
    along the line."""
    line = np.array([1.0, 2.0, 2.0]) / 3.0
    contact = Contact(contact_time=1e-3, restitution=0.8)
    model = _free_balls([("a", 0.05, 1.0, -0.2 * line, 2.0 * line, contact),
                         ("b", 0.07, 3.0, 0.2 * line, -1.0 * line, contact)])
    result = simulate(model, 0.2, 1e-5, record_every=1000)
    v = result.velocity_input[-1] @ line
    assert v[0] == pytest.approx(-2.05, rel=1e-3) and v[1] == pytest.approx(0.35, rel=1e-3)
    assert (v[1] - v[0]) / 3.0 == pytest.approx(0.8, rel=1e-3)
    momentum = result.velocity_input[:, 0] * 1.0 + result.velocity_input[:, 1] * 3.0
    assert np.abs(momentum - momentum[0]).max() < 1e-8
    assert np.abs(result.velocity_input[-1] - np.outer(v, line)).max() < 1e-9


def test_a_ball_rests_on_a_ball_on_the_plane():
    """Two balls stacked on the plane under gravity come to rest at the compressions their
    weights set: the lower at r1 - (m1 + m2) g / k1 (its sphere's stiffness against the
    plane's rigid default), the upper a further r1 + r2 - m2 g / k12 (the two in series), to
    1e-9 m; the contact forces carry the weights."""
    k1, k2 = 2e5, 3e5
    model = _free_balls([("low", 0.05, 2.0, [0, 0, 0.05], [0, 0, 0],
                          Contact(stiffness=k1, restitution=0.3)),
                         ("high", 0.04, 1.0, [0, 0, 0.1401], [0, 0, 0],
                          Contact(stiffness=k2, restitution=0.3))],
                        gravity=(0.0, 0.0, -G), plane=Plane())
    result = simulate(model, 1.0, 1e-4, record_every=100)
    z = result.position_input[-1, :, 2]
    low = 0.05 - 3.0 * G / k1
    assert z[0] == pytest.approx(low, abs=1e-9)
    assert z[1] == pytest.approx(low + 0.09 - 1.0 * G / (k1 * k2 / (k1 + k2)), abs=1e-9)
    force = result.contact_force[-1]
    assert force[0] == pytest.approx([0, 0, 2.0 * G], abs=1e-6)   # the plane's less the top's
    assert force[1] == pytest.approx([0, 0, 1.0 * G], abs=1e-6)


def test_the_result_lists_each_touch():
    """Result.contacts(): the dropped ball's touch, a few tenths of a millisecond long, when its
    fall reaches the plane, sqrt(2 (1 - r) / g) s."""
    result = simulate(bouncing_ball(), 0.5, rtol=1e-6, record_dt=5e-5)
    touches = result.contacts()
    assert len(touches) == 1
    (sphere, t_on, t_off), = touches
    assert sphere == 0
    assert t_on == pytest.approx(np.sqrt(2 * 0.95 / G), abs=5e-5)
    assert 1e-4 < t_off - t_on < 3e-4


def test_a_contact_the_step_cannot_resolve_is_flagged():
    """A contact of ~1 ms struck with steps of 1 ms: an UnresolvedMotionWarning naming the body
    and the step that resolves it; with 0.05 ms steps, none."""
    model = _ball(position=(0.0, 0.0, 0.06))
    with pytest.warns(dttmm.UnresolvedMotionWarning, match="contact of body 'ball'"):
        simulate(model, 0.2, 1e-3)
    with warnings.catch_warnings():
        warnings.simplefilter("error", dttmm.UnresolvedMotionWarning)
        simulate(model, 0.2, 5e-5)


def test_the_scene_of_a_model_with_contact_runs_the_same():
    """save_scene / load_scene keep the shapes (as their contact spheres), the law and the
    plane: the loaded model's run equals the model's to rounding."""
    from dttmm.interfaces.scene import load_scene, save_scene
    model = box_on_incline(0.3, np.radians(30.0))
    import tempfile
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "incline.toml"
        save_scene(model, path, {"t_end": 0.05, "dt": 1e-4})
        loaded = load_scene(path).model
    a, b = simulate(model, 0.05, 1e-4), simulate(loaded, 0.05, 1e-4)
    np.testing.assert_allclose(b.position_input, a.position_input, atol=1e-12)


@pytest.mark.parametrize("build,match", [
    (lambda: build_chain([FreeJoint(), RigidBody(mass=1.0, inertia=1.0, inertia_about="input",
                                                 shapes=Sphere(0.1), contact=Contact(1e5))]),
     "nothing to touch"),
    (lambda: _ball(contact=Contact()), "stiffness .* or a contact_time"),
    (lambda: _ball(contact=Contact(stiffness=-1.0)), "stiffness must be > 0"),
    (lambda: _ball(contact=Contact(stiffness=1e5, restitution=1.5)), "restitution must be in"),
    (lambda: _ball(contact=Contact(stiffness=1e5, friction=-0.1)), "friction must be >= 0"),
    (lambda: _ball(plane=Plane(normal=[0, 0, 0])), "normal must not be zero"),
    (lambda: build_chain([FreeJoint(), RigidBody(mass=1.0, inertia=1.0, inertia_about="input",
                                                 shapes=[Sphere(0.1)])],
                         ground=Ground(plane=Plane())), "needs contact="),
    (lambda: build_chain([FreeJoint(), RigidBody(mass=1.0, inertia=1.0, inertia_about="input",
                                                 shapes=["ball"], contact=Contact(1e5))],
                         ground=Ground(plane=Plane())), "Sphere, Capsule or Box"),
    (lambda: build_chain([FreeJoint(), RigidBody(mass=1.0, inertia=1.0, inertia_about="input",
                                                 shapes=Sphere(-0.1), contact=Contact(1e5))],
                         ground=Ground(plane=Plane())), "radius must be >= 0"),
])
def test_bad_contact_input_is_refused_at_build_time(build, match):
    with pytest.raises(ValueError, match=match):
        build()


def test_what_does_not_take_contact_says_so():
    """The energy-momentum scheme, statics, linear models and the reference refuse a model with
    shapes, naming why."""
    model = _ball()
    with pytest.raises(ValueError, match="contact shapes"):
        simulate(model, 0.01, 1e-3, scheme="energy_momentum")
    with pytest.raises(ValueError, match="contact shapes"):
        dttmm.static_equilibrium(build_chain(
            [dttmm.BallJoint(), RigidBody(mass=1.0, inertia=1.0, inertia_about="input",
                                          to_output=[1, 0, 0], shapes=Sphere(0.1),
                                          contact=Contact(1e5))],
            gravity=[0, 0, -G], ground=Ground(plane=Plane(point=[0, 0, -2.0]))))
    with pytest.raises(ValueError, match="contact shapes"):
        dttmm.linearize(model)
    with pytest.raises(ValueError, match="work of contacts"):
        simulate(model, 0.01, 1e-3, max_energy_error=1e-3)
    with pytest.raises(ValueError, match="contact shapes"):
        dttmm.simulate_reference(model, 0.01)


def test_describe_says_how_each_body_touches():
    text = bouncing_ball().describe()
    assert "touches the plane" in text and "restitution 0.8" in text
    assert "suggested dt: 1e-05 s" in text


def test_the_examples_write_their_tables(tmp_path):
    """examples/bouncing_ball.py and examples/incline.py write the issue's columns, sampled
    from t = 0 (every 0.1 ms and 1 ms), and their figures."""
    import bouncing_ball
    import incline
    csv = tmp_path / "ball.csv"
    assert bouncing_ball.main(["--t-end", "0.6", "--csv", str(csv), "--plots",
                               str(tmp_path)]) == 0
    table = np.genfromtxt(csv, delimiter=",", names=True)
    assert table.dtype.names == ("t", "z", "vz")
    np.testing.assert_allclose(np.diff(table["t"]), 1e-4, atol=1e-9)
    assert table["z"][0] == 1.0 and table["z"].min() > 0.049
    csv = tmp_path / "incline.csv"
    assert incline.main(["--t-end", "0.2", "--csv", str(csv), "--plots", str(tmp_path)]) == 0
    table = np.genfromtxt(csv, delimiter=",", names=True)
    assert table.dtype.names == ("t", "s", "v")
    np.testing.assert_allclose(np.diff(table["t"]), 1e-3, atol=1e-9)
    for name in ("bouncing_ball.png", "incline.png"):
        assert (tmp_path / name).stat().st_size > 1000
