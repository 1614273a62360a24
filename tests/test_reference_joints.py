"""The Newton-Euler reference on joints with coordinates (revolute, universal, prismatic) and
their drives, against results it does not compute itself: closed-form periods and motions,
inverse dynamics by hand, conservation laws and the joints' geometric constraints
(dttmm/reference/newton_euler.py, "Joints with coordinates"; docs/joints.md)."""
import numpy as np
import pytest
from scipy.integrate import cumulative_simpson

from dttmm import (EulerBernoulliBeam, FixedHinge, Ground, JointForce, JointMotion,
                   PrescribedMotion, PrismaticJoint, RevoluteJoint, RigidBody, SpringDamper,
                   System, UniversalJoint)
from dttmm.model.chains import unit_link
from dttmm.reference import simulate_reference
from dttmm.results.result import angular_momentum
from helpers import crossing_period

G = 9.81
I_O = 1.0 / 6.0 + 0.25          # a unit link about an axis through its input point, normal to it
D = 0.5                          # input point to mass centre, m


def rot(axis, angle):
    """Rot(n, q) from scipy's rotation vector (not the package's Rodrigues)."""
    from scipy.spatial.transform import Rotation
    return Rotation.from_rotvec(angle * np.asarray(axis, float)).as_matrix()


def slider_body(**kw):
    """0.5 kg, inertia 0.01 I about its mass centre, which is its input point."""
    return RigidBody(mass=0.5, inertia=0.01, inertia_about="mass_center", **kw)


def drift_of(res):
    """Largest excursion of the total energy from its start, over the largest kinetic energy."""
    energy = res.total_energy
    return np.abs(energy - energy[0]).max() / res.kinetic.max()


def arm(spring=SpringDamper(50.0, 0.0)):
    """The issue's arm, undriven: revolute (world y, turning at 0.5 rad/s), revolute (link 1's
    z), universal (link 2's z, link 3's y), prismatic (link 3's x) with a spring-damper (rest:
    the initial slide, 0)."""
    system = System(gravity=[0.0, -G, 0.0])
    system.add(unit_link(name="link1"), RevoluteJoint(axis=[0, 1, 0], rate=0.5, name="joint1"))
    system.add(unit_link(name="link2"), RevoluteJoint(axis=[0, 0, 1], name="joint2"),
               parent="link1")
    system.add(unit_link(name="link3"), UniversalJoint(axis1=[0, 0, 1], axis2=[0, 1, 0],
                                                       name="joint3"), parent="link2")
    system.add(slider_body(name="body4"),
               PrismaticJoint(axis=[1, 0, 0], drive=spring, name="joint4"),
               parent="link3")
    return system.build()


# --------------------------------------------------------------------------------------------
# revolute joints
# --------------------------------------------------------------------------------------------

def test_compound_pendulum_period():
    """A unit link on a revolute joint about world z, gravity -y, 1 mrad from hanging straight
    down: period 2 pi sqrt(I_O / (m g d)) (the amplitude adds theta0^2 / 16 = 6e-8)."""
    system = System(gravity=[0.0, -G, 0.0])
    system.add(unit_link(), RevoluteJoint(axis=[0, 0, 1], angle=-np.pi / 2 + 1e-3))
    t = np.linspace(0.0, 10.0, 4001)
    res = simulate_reference(system.build(), 10.0, rtol=1e-12, atol=1e-12, t_eval=t)
    period = crossing_period(t, res.joint_coordinates[:, 0] + np.pi / 2)
    exact = 2 * np.pi * np.sqrt(I_O / (G * D))
    assert abs(period / exact - 1.0) < 1e-4, period / exact - 1.0    # 6.3e-8 measured
    # the link hangs from the origin and turns about z only
    assert np.abs(res.position_input).max() == 0.0
    assert np.abs(res.angular_velocity[:, 0, :2]).max() == 0.0


def test_constant_and_timed_torque():
    """No gravity, a torque tau(t) = 0.3 + 2 sin(pi t) about the joint's axis: q'' = tau / I_O,
    q = q0 + (0.3 / 2) t^2 / I_O + 2 / (I_O pi) (t - sin(pi t) / pi) exactly."""
    system = System(gravity=[0.0, 0.0, 0.0])
    torque = JointForce(lambda t, q, qd: 0.3 + 2.0 * np.sin(np.pi * t))
    system.add(unit_link(), RevoluteJoint(axis=[0, 0, 1], angle=0.2, drive=torque))
    t = np.linspace(0.0, 2.0, 41)
    res = simulate_reference(system.build(), 2.0, rtol=1e-12, atol=1e-12, t_eval=t)
    q = 0.2 + 0.15 * t ** 2 / I_O + 2.0 / (I_O * np.pi) * (t - np.sin(np.pi * t) / np.pi)
    qd = 0.3 * t / I_O + 2.0 / (I_O * np.pi) * (1.0 - np.cos(np.pi * t))
    assert np.abs(res.joint_coordinates[:, 0] - q).max() < 1e-10
    assert np.abs(res.joint_rates[:, 0] - qd).max() < 1e-10
    assert np.abs(res.drive_force[:, 0] - (0.3 + 2.0 * np.sin(np.pi * t))).max() < 1e-14


def test_double_pendulum_stays_in_its_plane_and_conserves_energy():
    """Two links on parallel revolute axes (world z, then link 1's z): every point keeps z = 0
    to rounding, and the energy is conserved."""
    system = System(gravity=[0.0, -G, 0.0])
    system.add(unit_link(name="a"), RevoluteJoint(axis=[0, 0, 1], angle=-0.4, rate=1.5))
    system.add(unit_link(name="b"), RevoluteJoint(axis=[0, 0, 1], angle=0.9, rate=-2.0),
               parent="a")
    t = np.linspace(0.0, 2.0, 401)
    res = simulate_reference(system.build(), 2.0, rtol=1e-11, atol=1e-12, t_eval=t)
    for points in (res.position_input, res.position_mass_center, res.position_output):
        assert np.abs(points[..., 2]).max() < 1e-12
    assert np.abs(res.angular_velocity[..., :2]).max() < 1e-12
    assert res.kinetic.max() > 5.0
    assert drift_of(res) < 1e-8, drift_of(res)       # 1.2e-11 measured
    # link b turns by its joint angle relative to link a
    rel = np.einsum("tji,tjk->tik", res.rotation[:, 0], res.rotation[:, 1])
    q2 = res.joint_coordinates[:, 1]
    assert np.abs(rel[:, 0, 0] - np.cos(q2)).max() < 1e-12
    assert np.abs(rel[:, 1, 0] - np.sin(q2)).max() < 1e-12


def test_prescribed_motion_needs_the_inverse_dynamics_torque():
    """A unit link driven along q(t) = 0.5 t + 0.2 (1 - cos 2t) about world z, gravity -y: the
    joint applies tau = I_O q'' + m g d cos q (Euler about the fixed input point: the weight's
    moment is -m g d cos q), recorded as drive_force; the link follows the motion."""
    motion = JointMotion(lambda t: 0.5 * t + 0.2 * (1.0 - np.cos(2.0 * t)),
                         lambda t: 0.5 + 0.4 * np.sin(2.0 * t),
                         lambda t: 0.8 * np.cos(2.0 * t))
    system = System(gravity=[0.0, -G, 0.0])
    system.add(unit_link(), RevoluteJoint(axis=[0, 0, 1], drive=motion))
    t = np.linspace(0.0, 3.0, 61)
    res = simulate_reference(system.build(), 3.0, rtol=1e-10, atol=1e-12, t_eval=t)
    q = 0.5 * t + 0.2 * (1.0 - np.cos(2.0 * t))
    tau = I_O * 0.8 * np.cos(2.0 * t) + 1.0 * G * D * np.cos(q)
    assert np.abs(res.drive_force[:, 0] - tau).max() < 1e-8, \
        np.abs(res.drive_force[:, 0] - tau).max()              # 4e-16 measured
    assert np.abs(res.joint_coordinates[:, 0] - q).max() < 1e-15
    tip = np.stack([np.cos(q), np.sin(q), 0.0 * q], axis=1)
    assert np.abs(res.position_output[:, 0] - tip).max() < 1e-14
    # the motor's torque is the couple the ground exerts about z
    assert np.abs(res.moment[:, 0, 2] - tau).max() < 1e-8


# --------------------------------------------------------------------------------------------
# prismatic joints
# --------------------------------------------------------------------------------------------

def test_spring_slider_frequency():
    """A 0.5 kg body on a prismatic joint along world x with a 50 N/m spring, no gravity:
    x(t) = 0.1 cos(sqrt(k / m) t), sqrt(k / m) = 10 rad/s."""
    system = System(gravity=[0.0, 0.0, 0.0])
    system.add(slider_body(), PrismaticJoint(axis=[1, 0, 0], position=0.1,
                                             drive=SpringDamper(50.0, rest=0.0)))
    t = np.linspace(0.0, 6.0, 6001)
    res = simulate_reference(system.build(), 6.0, rtol=1e-12, atol=1e-13, t_eval=t)
    omega = 2 * np.pi / crossing_period(t, res.joint_coordinates[:, 0])
    assert abs(omega / 10.0 - 1.0) < 1e-6, omega / 10.0 - 1.0        # 5.7e-10 measured
    assert np.abs(res.joint_coordinates[:, 0] - 0.1 * np.cos(10.0 * t)).max() < 1e-10
    # the body's input point is where the slide puts it, and the spring's energy counts
    assert np.abs(res.position_input[:, 0, 0] - res.joint_coordinates[:, 0]).max() == 0.0
    assert abs(res.total_energy[0] - 0.5 * 50.0 * 0.01) < 1e-15
    assert drift_of(res) < 1e-9


def test_bead_on_a_spinning_rod():
    """A slider on a rod that the ground turns at a constant 2 rad/s about world z, no gravity,
    starting at rest on the rod 0.2 m out: q = 0.2 cosh(2 t), and the rod pushes it sideways
    with the Coriolis force 2 m Omega q' (along the rod, nothing)."""
    omega = 2.0
    spin = PrescribedMotion.spin_about_axis([0, 0, 1], lambda t: omega * t, lambda t: omega,
                                            lambda t: 0.0)
    system = System(gravity=[0.0, 0.0, 0.0], ground=Ground(motion=spin))
    system.add(slider_body(), PrismaticJoint(axis=[1, 0, 0], position=0.2))
    t = np.linspace(0.0, 1.5, 31)
    res = simulate_reference(system.build(), 1.5, rtol=1e-12, atol=1e-13, t_eval=t)
    q = 0.2 * np.cosh(omega * t)
    assert np.abs(res.joint_coordinates[:, 0] / q - 1.0).max() < 1e-10
    rod = np.stack([np.cos(omega * t), np.sin(omega * t), 0.0 * t], axis=1)
    side = np.stack([-np.sin(omega * t), np.cos(omega * t), 0.0 * t], axis=1)
    assert np.abs(res.position_input[:, 0] - q[:, None] * rod).max() < 1e-10
    coriolis = 2.0 * 0.5 * omega * (0.2 * omega * np.sinh(omega * t))
    force = res.force[:, 0]
    assert np.abs(np.einsum("ti,ti->t", force, side) - coriolis).max() < 1e-9
    assert np.abs(np.einsum("ti,ti->t", force, rod)).max() < 1e-12
    assert np.abs(res.drive_force).max() == 0.0
    # it turns with the rod: no couple needed for its (spherical) inertia
    assert np.abs(res.moment[:, 0]).max() < 1e-12
    assert np.abs(res.angular_velocity[:, 0] - [0.0, 0.0, omega]).max() < 1e-14


# --------------------------------------------------------------------------------------------
# universal joints
# --------------------------------------------------------------------------------------------

def universal_link(gravity):
    system = System(gravity=gravity)
    system.add(unit_link(), UniversalJoint(axis1=[0, 0, 1], axis2=[0, 1, 0], angles=(0.3, -0.4),
                                           rates=(1.0, 0.7)))
    t = np.linspace(0.0, 2.0, 201)
    return system.build(), simulate_reference(system.build(), 2.0, rtol=1e-11, atol=1e-12,
                                              t_eval=t)


def test_universal_joint_never_turns_about_the_cross_axis():
    """axis1 = world z on the ground, axis2 = the link's y, gravity -y: the link's angular
    velocity has no component along n1 x (A n2), its rotation is Rot(n1, q1) Rot(n2, q2) of the
    recorded angles (scipy's rotations), and the energy is conserved."""
    _, res = universal_link([0.0, -G, 0.0])
    n1 = np.array([0.0, 0.0, 1.0])
    v2 = res.rotation[:, 0] @ np.array([0.0, 1.0, 0.0])
    cross = np.cross(n1, v2)
    assert np.abs(np.einsum("ti,ti->t", res.angular_velocity[:, 0], cross)).max() < 1e-10
    q = res.joint_coordinates
    rebuilt = np.array([rot(n1, a) @ rot([0, 1, 0], b) for a, b in q])
    assert np.abs(res.rotation[:, 0] - rebuilt).max() < 1e-12
    assert np.ptp(q[:, 1]) > 0.3                        # it does swing about both axes
    assert np.ptp(q[:, 0]) > 0.5
    assert drift_of(res) < 1e-8, drift_of(res)          # 3.8e-12 measured
    # the joint transmits no couple about either axis (no drive)
    assert np.abs(res.moment[:, 0, 2]).max() < 1e-10
    assert np.abs(np.einsum("ti,ti->t", res.moment[:, 0], v2)).max() < 1e-10


def test_universal_joint_conserves_momentum_about_its_fixed_axis():
    """Gravity along -z (the ground axis): no moment about z acts (the joint's force at the
    fixed point, its couple normal to z), so the angular momentum's z part is conserved."""
    model, res = universal_link([0.0, 0.0, -G])
    lz = angular_momentum(model, res)[:, 2]
    assert np.abs(lz - lz[0]).max() < 1e-9 * np.abs(lz).max(), np.abs(lz - lz[0]).max()
    assert drift_of(res) < 1e-8


# --------------------------------------------------------------------------------------------
# the arm: all three joints, a tree of four bodies
# --------------------------------------------------------------------------------------------

def test_the_arm_conserves_energy_with_its_spring():
    """The issue's arm with an undamped 50 N/m spring on the slider: the total energy, the
    spring's 1/2 k q^2 included, is conserved; the slider sits on link 3's x axis."""
    model = arm()
    t = np.linspace(0.0, 2.0, 201)
    res = simulate_reference(model, 2.0, rtol=1e-11, atol=1e-12, t_eval=t)
    assert res.joint_coordinates.shape == (201, 5)
    assert drift_of(res) < 1e-8, drift_of(res)          # 1.9e-11 measured
    q4 = res.joint_coordinates[:, 4]
    slide = np.einsum("tij,tj->ti", res.rotation[:, 2], np.stack([q4, 0 * q4, 0 * q4], axis=1))
    assert np.abs(res.position_input[:, 3] - res.position_output[:, 2] - slide).max() < 1e-12
    assert np.abs(res.rotation[:, 3] - res.rotation[:, 2]).max() < 1e-12
    # the spring acts: the slide moves, its force is -k q, and without it the energy differs
    assert np.ptp(q4) > 0.05
    assert np.abs(res.drive_force[:, 4] + 50.0 * q4).max() < 1e-12
    spring = 0.5 * 50.0 * q4 ** 2
    assert spring.max() > 0.05
    # link 2 and link 3 stay joined at link 2's output point
    assert np.abs(res.position_input[:, 2] - res.position_output[:, 1]).max() < 1e-12


def test_the_arm_with_a_damper_loses_what_the_damper_dissipates():
    """With damping c: E(t) - E(0) = -int c q'^2 dt (Simpson's rule on a fine grid)."""
    model = arm(SpringDamper(50.0, 0.5))
    t = np.linspace(0.0, 1.0, 2001)
    res = simulate_reference(model, 1.0, rtol=1e-11, atol=1e-12, t_eval=t)
    power = 0.5 * res.joint_rates[:, 4] ** 2
    dissipated = cumulative_simpson(power, x=t, initial=0.0)
    energy = res.total_energy - res.total_energy[0]
    assert dissipated[-1] > 0.1
    error = np.abs(energy + dissipated).max() / dissipated[-1]
    assert error < 1e-8, error


# --------------------------------------------------------------------------------------------
# beams behind and before joints
# --------------------------------------------------------------------------------------------

def soft_beam(length, modes, **kw):
    return EulerBernoulliBeam(length=length, mass_per_length=1.32, bending_stiffness=20.0,
                              polar_inertia_per_length=1.32 * 0.02 ** 2 / 6,
                              modes_per_plane=modes, **kw)


def test_beam_on_a_revolute_joint_with_a_link_at_its_end():
    """A beam (clamped in its input section, which the revolute joint turns) swinging about
    world z with a unit link on a revolute joint about the beam's end section's y: energy
    conserved; the link's input point is the beam's deflected end."""
    system = System(gravity=[0.0, -G, 0.0])
    system.add(soft_beam(0.6, 2, name="beam", initial_modal_coordinates=[2e-3, 0, -1e-3, 5e-4]),
               RevoluteJoint(axis=[0, 0, 1], rate=1.0))
    system.add(unit_link(name="link"), RevoluteJoint(axis=[0, 1, 0], angle=0.3, rate=-1.0),
               parent="beam")
    t = np.linspace(0.0, 1.0, 201)
    res = simulate_reference(system.build(), 1.0, rtol=1e-11, atol=1e-13, t_eval=t)
    assert drift_of(res) < 1e-8, drift_of(res)          # 1.1e-13 measured
    assert np.abs(res.modal_coordinates).max() > 1e-3
    assert np.abs(res.position_input[:, 1] - res.position_output[:, 0]).max() < 1e-12


def test_slider_on_a_beam_end():
    """A cantilever (welded to the ground) with a spring slider across its end section (along
    the end section's y): the slide's offset couples to the end rotation; energy conserved."""
    system = System(gravity=[0.0, -G, 0.0])
    system.add(soft_beam(0.5, 2, name="beam", initial_modal_coordinates=[3e-3, 0, 2e-3, 0]),
               FixedHinge())
    system.add(slider_body(name="slider"),
               PrismaticJoint(axis=[0, 1, 0], position=0.05, rate=0.2,
                              drive=SpringDamper(20.0, rest=0.0)), parent="beam")
    t = np.linspace(0.0, 1.0, 201)
    res = simulate_reference(system.build(), 1.0, rtol=1e-11, atol=1e-13, t_eval=t)
    # 1.2e-12 measured; 0.26 with the slide's d^ B_t terms left out of the system
    assert drift_of(res) < 1e-8, drift_of(res)
    assert np.ptp(res.joint_coordinates[:, 0]) > 0.02
    # the slider moves along the end section's y from the beam's deflected end point
    offset = res.position_input[:, 1] - res.position_output[:, 0]
    along = res.rotation[:, 1] @ np.array([0.0, 1.0, 0.0])
    assert np.abs(offset - res.joint_coordinates[:, :1] * along).max() < 1e-12


# --------------------------------------------------------------------------------------------
# what the reference refuses
# --------------------------------------------------------------------------------------------

def test_a_drive_that_fails_during_the_run_names_its_joint():
    """A drive function valid at t = 0 (checked at build time) that returns NaN later."""
    system = System()
    bad = JointForce(lambda t, q, qd: 0.0 if t < 0.05 else np.nan)
    system.add(unit_link(), UniversalJoint([0, 0, 1], [0, 1, 0], drives=(None, bad),
                                           name="wrist"))
    with pytest.raises(ValueError, match="UniversalJoint 'wrist' \\(hinge 0\\), coordinate 1: "
                                         "drive function.*returned nan"):
        simulate_reference(system.build(), 0.1)


def test_chain_energies_counts_drive_springs_only_when_given_the_coordinates():
    """chain_energies(joint_coordinates=q) adds 1/2 k (q - rest)^2 per SpringDamper (by hand
    here); without the argument (the DT-TMM solver's call) the energies are unchanged."""
    from dttmm.results.result import chain_energies
    model = arm(SpringDamper(50.0, 0.5, rest=0.02))
    n = model.n_bodies
    args = (model.initial_rotation, model.initial_angular_velocity, np.zeros((n, 3)),
            np.zeros((n, 3)), np.zeros((n, 3)))
    kin, pot = chain_energies(model, *args)
    q = np.array([0.1, -0.2, 0.3, 0.4, 0.07])
    kin_q, pot_q = chain_energies(model, *args, joint_coordinates=q)
    assert kin_q == kin
    assert abs(pot_q - pot - 0.5 * 50.0 * 0.05 ** 2) < 1e-15
    with pytest.raises(ValueError, match="joint_coordinates must hold 5"):
        chain_energies(model, *args, joint_coordinates=q[:4])
