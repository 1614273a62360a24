"""Shapes touching each other (issue 67, item 3; docs/contact.md, "Bodies touching each
other"): a box on a box, a capsule across a capsule, a ball on a box's face; and friction
that stops a spinning box (its moment about the normal).

The narrow phase is checked against brute force (points sampled along the segments, a box's
signed distance by its definition), the kernels' against their Python twins, and the runs
against the closed forms of bodies at rest (each contact's compression m g / (n k), k the
pair's stiffnesses in series) and of Coulomb friction's constant moment."""
import numpy as np
import pytest

import dttmm
from dttmm import Box, Capsule, Contact, FreeJoint, Ground, Plane, RigidBody, Sphere, simulate
from dttmm.elements.contact import box_distance, segment_box_parameter, segment_parameters
from dttmm.kernels.transfers import contact_geometry

G = 9.81
RNG = np.random.default_rng(67)


def test_the_nearest_points_of_two_segments_are_the_brute_forces():
    """segment_parameters: the distance of its points is the least over 2001 x 2001 samples
    of the two segments (to their spacing's second order), for random segments, parallel ones
    and points; the kernel (its Python twin) gives the same parameters."""
    u = np.linspace(0.0, 1.0, 2001)
    cases = [RNG.normal(size=(4, 3)) for _ in range(20)]
    d = RNG.normal(size=3)
    cases += [np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [1, 0, 0]]),    # parallel
              np.array([[0, 0, 0], d, [0.3, 1, 0], [0, 0, 0]]),     # a point
              np.array([[0, 0, 0], [0, 0, 0], [0.3, 1, 0], [0, 0, 0]])]
    for p1, d1, p2, d2 in cases:
        s, t = segment_parameters(p1, d1, p2, d2)
        assert 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0
        found = np.linalg.norm(p1 + s * d1 - p2 - t * d2)
        a = p1 + u[:, None] * d1
        b = p2 + u[:, None] * d2
        least = np.sqrt(((a[:, None] - b[None]) ** 2).sum(-1).min())
        assert least - 1e-6 <= found <= least + 1e-12
        assert contact_geometry.segment_parameters(p1, d1, p2, d2) == pytest.approx(
            (float(s), float(t)),
                                                                                    abs=1e-12)
    p1, d1, p2, d2 = cases[-3]          # parallel: the middle of the overlap
    s, t = segment_parameters(p1, d1, p2, d2)
    assert s == pytest.approx(0.75) and t == pytest.approx(0.25)


def test_a_boxs_signed_distance_and_a_segments_deepest_point():
    """box_distance: outside, the distance to the box's nearest point (the point clipped to it
    in the box's axes) along its offset; inside, minus the distance to the nearest face, with
    its normal; the deepest point of a segment is the least over 20001 samples; the kernels
    agree with their twins."""
    axes = np.linalg.qr(RNG.normal(size=(3, 3)))[0]
    centre, half = RNG.normal(size=3), np.array([0.3, 0.2, 0.1])
    n = np.empty(3)
    for x in RNG.normal(size=(50, 3)) * 0.4 + centre:
        local = axes.T @ (x - centre)
        nearest = centre + axes @ np.clip(local, -half, half)
        sd, normal = box_distance(x, centre, axes, half)
        if np.all(np.abs(local) < half):
            gap = half - np.abs(local)
            assert sd == pytest.approx(-gap.min(), abs=1e-14)
            face = np.argmin(gap)
            assert normal == pytest.approx(np.sign(local[face]) * axes[:, face], abs=1e-14)
        else:
            assert sd == pytest.approx(np.linalg.norm(x - nearest), abs=1e-14)
            assert normal == pytest.approx((x - nearest) / sd, abs=1e-12)
        assert contact_geometry.box_distance(*x, centre, axes, half, n) == pytest.approx(
            sd, abs=1e-14)
        assert n == pytest.approx(normal, abs=1e-14)
    u = np.linspace(0.0, 1.0, 20001)
    for _ in range(10):
        p, d = centre + RNG.normal(size=3) * 0.4, RNG.normal(size=3) * 0.5
        t = segment_box_parameter(p, d, centre, axes, half)
        brute = box_distance(p + u[:, None] * d, centre, axes, half)[0]
        assert box_distance(p + t * d, centre, axes, half)[0] <= brute.min() + 1e-9
        t_kernel = contact_geometry.segment_box_parameter(p, d, centre, axes, half, n)
        assert box_distance(p + t_kernel * d, centre, axes, half)[0] <= brute.min() + 1e-9


def _box(name, sides, mass, k, friction=0.5, omega=None):
    sides = np.asarray(sides, dtype=float)
    return RigidBody(mass=mass, inertia=mass * (np.sum(sides ** 2) - sides ** 2) / 12,
                     inertia_about="mass_center", name=name, shapes=Box(sides),
                     angular_velocity=omega,
                     contact=Contact(stiffness=k, restitution=0.3, friction=friction))


def _capsule(name, k, rotation=None, mass=1.0):
    return RigidBody(mass=mass, inertia=[1e-3, 0.02, 0.02], inertia_about="mass_center",
                     name=name, rotation=rotation, shapes=Capsule(0.04, [-0.2, 0, 0], [0.2, 0, 0]),
                     contact=Contact(stiffness=k, restitution=0.3, friction=0.5))


def _system(*pairs):
    system = dttmm.System(gravity=[0.0, 0.0, -G], ground=Ground(plane=Plane()))
    for body, position in pairs:
        system.add(body, FreeJoint(position=position))
    return system.build()


def test_a_box_rests_on_a_box():
    """A 1 kg box (10 cm cube) on a 2 kg one (20 x 20 x 10 cm) on the plane, stiffnesses 1e6
    and 2e6 N/m: the lower rests on its four lower corners at 3 g / (4 k1) below its half
    height, the upper on its four lower corners inside the lower box, at g / (4 k12) more
    (k12 the two in series), to 1e-9 m; the upper's corners carry its weight, the lower box's
    solid (its row) the opposite; nothing turns."""
    k1, k2 = 1e6, 2e6
    model = _system((_box("low", [0.2, 0.2, 0.1], 2.0, k1), [0, 0, 0.05]),
                    (_box("high", [0.1, 0.1, 0.1], 1.0, k2), [0, 0, 0.1505]))
    result = simulate(model, 1.0, 2e-4, record_every=50)
    z = result.position_input[-1, :, 2]
    low = 0.05 - 3.0 * G / (4.0 * k1)
    assert z[0] == pytest.approx(low, abs=1e-9)
    assert z[1] == pytest.approx(low + 0.1 - G / (4.0 / (1.0 / k1 + 1.0 / k2)), abs=1e-9)
    force = result.contact_force[-1]
    assert force[9:17].sum(axis=0) == pytest.approx([0, 0, G], abs=1e-6)    # the upper's corners
    assert force[8] == pytest.approx([0, 0, -G], abs=1e-6)                 # the lower's solid
    assert np.abs(result.angular_velocity[-1]).max() < 1e-9
    assert result.contact_normal[-1, 10] == pytest.approx([0, 0, 1.0])


def test_a_capsule_rests_across_a_capsule():
    """A capsule along y lying across the middle of one along x on the plane: the lower's two
    end spheres carry both weights, the upper rests on the lower's side (its axis' nearest
    point) at 2 r - g / k12 above it, to 1e-9 m, touching at the point between their axes."""
    k1, k2 = 1e6, 2e6
    across = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    model = _system((_capsule("low", k1), [0, 0, 0.04]),
                    (_capsule("high", k2, across), [0, 0, 0.121]))
    result = simulate(model, 1.0, 2e-4, record_every=50)
    z = result.position_input[-1, :, 2]
    low = 0.04 - 2.0 * G / (2.0 * k1)
    assert z[0] == pytest.approx(low, abs=1e-9)
    assert z[1] == pytest.approx(low + 0.08 - G / (1.0 / (1.0 / k1 + 1.0 / k2)), abs=1e-9)
    assert result.contact_force[-1, 2] == pytest.approx([0, 0, G], abs=1e-6)   # its swept row
    assert result.contact_point[-1, 2] == pytest.approx([0, 0, z[1] - 0.04], abs=1e-9)


def test_a_ball_rests_on_a_boxs_face():
    """A ball on the top face of a heavy box on the plane rests at its radius less m g / k12
    above the face, to 1e-9 m."""
    k = 1e6
    for body, rest in ((RigidBody(mass=1.0, inertia=4e-4, inertia_about="mass_center",
                                  name="ball", shapes=Sphere(0.03),
                                  contact=Contact(stiffness=k, restitution=0.3)), 0.03),):
        model = _system((_box("table", [1.0, 1.0, 0.1], 50.0, 1e8), [0, 0, 0.05]),
                        (body, [0.05, -0.02, 0.1 + rest + 1e-4]))
        result = simulate(model, 1.0, 2e-4, record_every=50)
        top = result.position_input[-1, 0, 2] + 0.05
        assert result.position_input[-1, 1, 2] - top == pytest.approx(
            rest - G / (1.0 / (1.0 / k + 1.0 / 1e8)), abs=1e-9)
        assert np.abs(result.angular_velocity[-1, 1]).max() < 1e-6


def test_friction_stops_a_spinning_box_at_its_constant_moment():
    """A box spun about the normal on its four corners: Coulomb's moment mu m g r (r the
    corners' distance from the axis) stops it at I w0 / (mu m g r), the spin falling linearly,
    to 1% (before the secant slope, Newton's iterations crossed zero and the box kept 0.7% of
    its spin for ever)."""
    sides, mass, mu, w0 = np.array([0.2, 0.2, 0.1]), 2.0, 0.5, 1.0
    model = _system((_box("box", sides, mass, 1e6, mu, omega=[0, 0, w0]),
                     [0, 0, 0.05 - mass * G / 4e6]))
    result = simulate(model, 0.1, 1e-4, record_every=10)
    r = np.hypot(0.1, 0.1)
    i_zz = mass * (sides[0] ** 2 + sides[1] ** 2) / 12.0
    t_stop = i_zz * w0 / (mu * mass * G * r)
    spin = result.angular_velocity[:, 0, 2]
    sliding = result.t < 0.8 * t_stop
    assert spin[sliding] == pytest.approx(w0 * (1.0 - result.t[sliding] / t_stop), abs=0.01)
    assert np.abs(spin[result.t > 1.2 * t_stop]).max() < 1e-6
