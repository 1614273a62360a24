"""Tests of the independent Newton-Euler reference solver against results it does not compute
itself: closed-form periods and frequencies, conservation laws, equivalent models, and hand-
derived hub loads."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from dttmm import (BallJoint, ElasticHinge, FixedHinge, Ground, PrescribedMotion, RigidBody,
                   build_chain)
from dttmm.reference import simulate_reference

G = 9.81


def rot(axis, angle):
    return Rotation.from_rotvec(angle * np.asarray(axis, float)).as_matrix()


def zero_crossings(t, x):
    """Times where x changes sign, by linear interpolation between samples."""
    i = np.nonzero(np.sign(x[:-1]) * np.sign(x[1:]) < 0)[0]
    return t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])


def period_from_crossings(t, x):
    tc = zero_crossings(t, x)
    assert len(tc) >= 3
    return 2.0 * (tc[-1] - tc[0]) / (len(tc) - 1)


def link(**kw):
    return RigidBody(mass=1.0, inertia=np.diag([1 / 6, 5 / 12, 5 / 12]), inertia_about="input",
                     to_mass_center=[0.5, 0, 0], to_output=[1, 0, 0], **kw)


@pytest.fixture(scope="module")
def three_link_run():
    model = build_chain([BallJoint(), link(), BallJoint(), link(), BallJoint(),
                         link(angular_velocity=[0, 0.1, 0])])
    res = simulate_reference(model, 2.0, rtol=1e-12, atol=1e-12,
                             t_eval=np.linspace(0.0, 2.0, 401))
    return model, res


def mass_center_velocities(model, res):
    """v_C of every body rebuilt from the recorded positions and angular velocities alone
    (the ground point is at rest)."""
    w = res.angular_velocity
    v_in = np.zeros_like(w)
    for k in range(1, model.n_bodies):
        v_in[:, k] = v_in[:, k - 1] + np.cross(
            w[:, k - 1], res.position_output[:, k - 1] - res.position_input[:, k - 1])
    return v_in + np.cross(w, res.position_mass_center - res.position_input)


# --------------------------------------------------------------------------------------------
# closed-form periods and frequencies
# --------------------------------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["simple", "compound"])
@pytest.mark.parametrize("swing_axis", [[0, 0, 1], [1, 0, 0]])
def test_small_angle_pendulum_period(kind, swing_axis):
    length, mass = 1.0, 2.0
    if kind == "simple":         # nearly a point mass at the end of a massless rod
        body = RigidBody(mass=mass, inertia=1e-7, inertia_about="mass_center",
                         to_mass_center=[0, -length, 0], to_output=[0, -length, 0],
                         rotation=rot(swing_axis, 0.02))
        expected = 2 * np.pi * np.sqrt(length / G)
    else:                        # uniform slender-ish bar hanging from its end
        j_c = mass * length ** 2 / 12 * np.array([1.0, 0.05, 1.0])
        j_c[1] = 0.1 * j_c[0]
        body = RigidBody(mass=mass, inertia=j_c, inertia_about="mass_center",
                         to_mass_center=[0, -length / 2, 0], to_output=[0, -length, 0],
                         rotation=rot(swing_axis, 0.02))
        j_i = j_c[int(np.argmax(swing_axis))] + mass * (length / 2) ** 2
        expected = 2 * np.pi * np.sqrt(j_i / (mass * G * length / 2))
    model = build_chain([BallJoint(), body], gravity=[0, -G, 0])
    t = np.linspace(0, 2.3 * expected, 3001)
    res = simulate_reference(model, t[-1], t_eval=t)
    angle = Rotation.from_matrix(res.rotation[:, 0]).as_rotvec() @ np.asarray(swing_axis, float)
    period = period_from_crossings(res.t, angle)
    assert abs(period / expected - 1) < 1e-3
    # finite-amplitude correction is 1 + theta0^2 / 16 = 1 + 2.5e-5: much tighter holds too
    assert abs(period / (expected * (1 + 0.02 ** 2 / 16)) - 1) < 1e-5


@pytest.mark.parametrize("offset", [False, True])
def test_elastic_hinge_frequency(offset):
    """Single body on an elastic hinge to a tilted ground, no gravity, small spin about a
    principal axis through the input point: omega = sqrt(k_r / J_I)."""
    k_r = 10.0
    j_c = np.array([0.2, 0.3, 0.4])
    l_ic = np.array([0.3, 0.0, 0.0]) if offset else np.zeros(3)
    j_i_zz = j_c[2] + 1.0 * l_ic @ l_ic
    rot_g = rot([1, 2, 3] / np.sqrt(14), 0.7)
    r0 = rot([0, 1, 0], 0.4)
    axis = rot_g @ r0 @ np.array([0.0, 0.0, 1.0])       # body z axis, world
    hinge = ElasticHinge(translational_stiffness=1e5 if offset else 1e3, rotational_stiffness=k_r,
                         rotation=r0)
    body = RigidBody(mass=1.0, inertia=j_c, inertia_about="mass_center", to_mass_center=l_ic,
                     to_output=[0.5, 0, 0], angular_velocity=0.01 * axis)
    model = build_chain([hinge, body], gravity=[0, 0, 0], ground=Ground(rotation=rot_g))
    omega = np.sqrt(k_r / j_i_zz)
    t = np.linspace(0, 3.2 * 2 * np.pi / omega, 2001)
    res = simulate_reference(model, t[-1], t_eval=t, rtol=1e-9, atol=1e-12)
    a0 = res.rotation[0, 0]
    angle = Rotation.from_matrix(res.rotation[:, 0] @ a0.T).as_rotvec() @ axis
    # angle = (0.01 / omega) sin(omega t): skip the crossing at t = 0
    tc = zero_crossings(res.t[5:], angle[5:])
    freq = np.pi * (len(tc) - 1) / (tc[-1] - tc[0])
    assert abs(freq / omega - 1) < 5e-3
    assert abs(np.abs(angle).max() / (0.01 / omega) - 1) < 5e-3


def test_elastic_hinge_starts_at_its_given_deflection():
    """A body on an elastic hinge whose springs act at its mass centre, started at the given
    deflection d0 (ElasticHinge.deflection) without gravity, oscillates as d0 cos(w t), w =
    sqrt(k / m), in the reference and in DT-TMM (the reference used to start it at d = 0)."""
    from dttmm import simulate
    k, mass, d0 = 1e3, 2.0, np.array([0.01, -0.004, 0.002])
    hinge = ElasticHinge(translational_stiffness=k, rotational_stiffness=10.0, deflection=d0)
    body = RigidBody(mass=mass, inertia=[0.1, 0.2, 0.3], inertia_about="mass_center",
                     to_mass_center=[0, 0, 0], to_output=[0.5, 0, 0])
    model = build_chain([hinge, body], gravity=[0, 0, 0])
    t = np.linspace(0.0, 0.5, 11)
    exact = np.cos(np.sqrt(k / mass) * t)[:, None] * d0 + [0.5, 0.0, 0.0]
    ref = simulate_reference(model, 0.5, t_eval=t, rtol=1e-10, atol=1e-12)
    assert np.abs(ref.position_output[:, 0] - exact).max() < 1e-8
    dttmm = simulate(model, 0.5, 1e-4, t_eval=t)
    assert np.abs(dttmm.position_output[:, 0] - exact).max() < 1e-5 * np.abs(d0).max()


# --------------------------------------------------------------------------------------------
# conservation laws and constraints
# --------------------------------------------------------------------------------------------

def test_three_link_energy_conservation(three_link_run):
    model, res = three_link_run
    energy = res.total_energy
    scale = res.kinetic.max()           # the energy exchanged during the fall (~44 J)
    assert scale > 10.0
    assert np.abs(energy - energy[0]).max() / scale < 1e-8
    # and it really falls: gravity did work
    assert res.potential.min() < res.potential[0] - 10.0


def test_three_link_vertical_angular_momentum(three_link_run):
    model, res = three_link_run
    v_c = mass_center_velocities(model, res)
    mass = model.body_params[:, 0]
    h = np.zeros((len(res.t), 3))
    root = res.position_input[:, 0]
    for k in range(model.n_bodies):
        a = res.rotation[:, k]
        j_world = a @ model.body_mass_center_inertia[k] @ np.swapaxes(a, 1, 2)
        h += mass[k] * np.cross(res.position_mass_center[:, k] - root, v_c[:, k])
        h += np.einsum("tij,tj->ti", j_world, res.angular_velocity[:, k])
    h_y = h[:, 1]
    if getattr(res, "velocity_input", None) is not None:     # the recorded velocities agree
        v_c_rec = res.velocity_input + np.cross(
            res.angular_velocity, res.position_mass_center - res.position_input)
        assert np.abs(v_c_rec - v_c).max() < 1e-12
    assert abs(h_y[0] - (0.1 / 6 + 2.5 * 0.05)) < 1e-12    # J_C,yy w + m r x v of the last link
    assert np.abs(h_y - h_y[0]).max() < 1e-8 * abs(h_y[0])
    # the motion is fully three-dimensional (h_x, h_z do change)
    assert np.abs(h[:, 2]).max() > 1.0


def test_joint_constraints_hold(three_link_run):
    model, res = three_link_run
    gap = np.linalg.norm(res.position_output[:, :-1] - res.position_input[:, 1:], axis=-1)
    assert gap.max() < 1e-9
    assert np.linalg.norm(res.position_input[:, 0] - model.ground_position, axis=-1).max() < 1e-12
    # body points stay where the body geometry puts them, rotations stay orthonormal
    l_io = model.body_params[:, 4:7]
    rel = res.position_output - res.position_input
    assert np.abs(rel - np.einsum("tkij,kj->tki", res.rotation, l_io)).max() < 1e-12
    eye = np.einsum("tkji,tkjl->tkil", res.rotation, res.rotation)
    assert np.abs(eye - np.eye(3)).max() < 1e-12
    # the ball joints pass no moment
    assert np.abs(res.moment).max() == 0.0


def test_joint_constraints_on_moving_ground():
    motion = PrescribedMotion(position=lambda t: np.array([0.3 * np.sin(2 * t), 0.1 * t ** 2, 0]),
                              velocity=lambda t: np.array([0.6 * np.cos(2 * t), 0.2 * t, 0]),
                              acceleration=lambda t: np.array([-1.2 * np.sin(2 * t), 0.2, 0]))
    model = build_chain([BallJoint(), link(angular_velocity=[0.3, 0.2, 0.1]), BallJoint(),
                         link(), FixedHinge(rotation=rot([0, 0, 1], 0.5)), link()],
                        ground=Ground(motion=motion))
    res = simulate_reference(model, 1.5, rtol=1e-10, atol=1e-12)
    ground = np.array([motion(t)[0] for t in res.t])
    assert np.linalg.norm(res.position_input[:, 0] - ground, axis=-1).max() < 1e-12
    gap = np.linalg.norm(res.position_output[:, :-1] - res.position_input[:, 1:], axis=-1)
    assert gap.max() < 1e-9
    r0 = model.hinge_params[2, 0:9].reshape(3, 3)
    assert np.abs(res.rotation[:, 2] - res.rotation[:, 1] @ r0).max() < 1e-12
    assert np.abs(res.angular_velocity[:, 2] - res.angular_velocity[:, 1]).max() < 1e-12


def test_elastic_chain_conserves_energy():
    """Elastic hinges with isotropic rotational springs (and any translational stiffness) are
    conservative with the spring energy chain_energies counts; dampers only dissipate.  The
    chain mixes elastic, ball and fixed hinges (each next to the others)."""
    def chain(damping):
        hinge = lambda: ElasticHinge(translational_stiffness=[2e3, 3e3, 4e3],
                                     rotational_stiffness=50.0, rotational_damping=damping,
                                     translational_damping=damping)
        return build_chain([hinge(), link(angular_velocity=[0.5, -0.3, 1.0]), BallJoint(),
                            link(angular_velocity=[-1.0, 0.4, 0.2]), hinge(),
                            link(angular_velocity=[0.3, 0.0, -0.5]),
                            FixedHinge(rotation=rot([0, 0, 1], 0.8)), link()])
    res = simulate_reference(chain(0.0), 1.0, rtol=1e-11, atol=1e-12)
    energy = res.total_energy
    scale = res.kinetic.max()
    assert np.abs(energy - energy[0]).max() / scale < 1e-7
    damped = simulate_reference(chain(0.5), 1.0, rtol=1e-10, atol=1e-12)
    e = damped.total_energy
    assert np.all(np.diff(e) <= 1e-9 * scale) and e[-1] < e[0] - 0.01 * scale


def test_rotation_through_gimbal_lock():
    """A body spinning about its pivoted mass centre on a principal y axis turns as Ry(w t),
    straight through theta_y = +-90 deg of the x-y-z angles."""
    body = RigidBody(mass=1.0, inertia=[0.3, 0.5, 0.4], inertia_about="mass_center",
                     to_output=[1, 0, 0], angular_velocity=[0, 2.0, 0])
    model = build_chain([BallJoint(), body])
    res = simulate_reference(model, 3.5, t_eval=np.linspace(0, 3.5, 701))
    expected = Rotation.from_rotvec(np.outer(2.0 * res.t, [0, 1, 0])).as_matrix()
    assert np.abs(res.rotation[:, 0] - expected).max() < 1e-8
    ty = res.xyz_angles[:, 0, 1]
    assert ty.max() > np.radians(89.5) and ty.min() < np.radians(-89.5)


def test_applied_force_and_torque():
    """An applied force cancelling gravity at the mass centre plus a torque tau(t) about the
    principal z axis through the pivot: theta'' = tau / J_I,zz, root force = M a_C."""
    mass, j_izz = 2.0, 0.1 + 2.0 * 0.4 ** 2
    tau = lambda t: 0.5 * np.cos(t)
    body = RigidBody(mass=mass, inertia=[0.05, 0.1, 0.1], inertia_about="mass_center",
                     to_mass_center=[0.4, 0, 0], to_output=[1, 0, 0],
                     force=lambda t: np.array([0, mass * G, 0]),
                     torque=lambda t: np.array([0, 0, tau(t)]))
    model = build_chain([BallJoint(), body])
    res = simulate_reference(model, 3.0)
    theta = 0.5 / j_izz * (1 - np.cos(res.t))
    expected = Rotation.from_rotvec(np.outer(theta, [0, 0, 1])).as_matrix()
    assert np.abs(res.rotation[:, 0] - expected).max() < 1e-9
    th1, th2 = 0.5 / j_izz * np.sin(res.t), tau(res.t) / j_izz
    assert np.abs(res.angular_acceleration[:, 0, 2] - th2).max() < 1e-9
    c, s = np.cos(theta), np.sin(theta)
    a_c = 0.4 * (th2[:, None] * np.stack([-s, c, 0 * c], 1)
                 - th1[:, None] ** 2 * np.stack([c, s, 0 * c], 1))
    assert np.abs(res.force[:, 0] - mass * a_c).max() < 1e-9


# --------------------------------------------------------------------------------------------
# equivalent models
# --------------------------------------------------------------------------------------------

def test_fixed_hinge_equals_combined_body():
    r0 = rot([1, 0, 0], 0.3) @ rot([0, 0, 1], 1.0)
    ma, mb = 1.0, 2.0
    j_ca = np.diag([0.02, 0.3, 0.31])
    j_cb = np.array([[0.1, 0.01, 0.0], [0.01, 0.2, 0.02], [0.0, 0.02, 0.25]])
    l_ica, l_ioa = np.array([0.5, 0, 0]), np.array([1.0, 0, 0])
    l_icb, l_iob = np.array([0.3, 0.1, -0.05]), np.array([0.6, 0, 0])
    a0 = rot([0, 1, 0], 0.4) @ rot([0, 0, 1], -0.3)
    w0 = np.array([0.5, -1.0, 2.0])
    body_a = RigidBody(mass=ma, inertia=j_ca, inertia_about="mass_center", to_mass_center=l_ica,
                       to_output=l_ioa, rotation=a0, angular_velocity=w0)
    body_b = RigidBody(mass=mb, inertia=j_cb, inertia_about="mass_center", to_mass_center=l_icb,
                       to_output=l_iob)
    two = build_chain([BallJoint(), body_a, FixedHinge(rotation=r0), body_b])

    def shift(m, c):
        return m * (c @ c * np.eye(3) - np.outer(c, c))
    c_b = l_ioa + r0 @ l_icb                 # body b's mass centre in body a's frame
    j_i = j_ca + shift(ma, l_ica) + r0 @ j_cb @ r0.T + shift(mb, c_b)
    one = build_chain([BallJoint(), RigidBody(
        mass=ma + mb, inertia=j_i, inertia_about="input",
        to_mass_center=(ma * l_ica + mb * c_b) / (ma + mb), to_output=l_ioa + r0 @ l_iob,
        rotation=a0, angular_velocity=w0)])

    t = np.linspace(0, 1.5, 151)
    r2 = simulate_reference(two, 1.5, t_eval=t, rtol=1e-11, atol=1e-12)
    r1 = simulate_reference(one, 1.5, t_eval=t, rtol=1e-11, atol=1e-12)
    assert np.abs(r2.rotation[:, 0] - r1.rotation[:, 0]).max() < 1e-8
    assert np.abs(r2.rotation[:, 1] - r1.rotation[:, 0] @ r0).max() < 1e-8
    assert np.abs(r2.position_output[:, 1] - r1.position_output[:, 0]).max() < 1e-8
    r_c2 = (ma * r2.position_mass_center[:, 0] + mb * r2.position_mass_center[:, 1]) / (ma + mb)
    assert np.abs(r_c2 - r1.position_mass_center[:, 0]).max() < 1e-8
    assert np.abs(r2.angular_acceleration[:, 1] - r1.angular_acceleration[:, 0]).max() < 1e-6
    assert np.abs(r2.force[:, 0] - r1.force[:, 0]).max() < 1e-6
    assert np.abs(r2.total_energy - r1.total_energy).max() < 1e-8
    assert np.abs(r1.rotation[-1, 0] - a0).max() > 0.5         # it did tumble


def test_accelerating_ground_equals_changed_gravity():
    """A chain on a ground point with constant acceleration a under gravity g moves, relative
    to that point, like the chain on a fixed ground under gravity g - a."""
    acc = np.array([1.5, 2.0, -0.7])
    g = np.array([0, -G, 0])
    motion = PrescribedMotion(position=lambda t: 0.5 * acc * t ** 2, velocity=lambda t: acc * t,
                              acceleration=lambda t: acc)

    def elements():
        return [BallJoint(), link(angular_velocity=[0.2, 0.1, -0.4]),
                ElasticHinge(translational_stiffness=500.0, rotational_stiffness=20.0), link()]
    moving = build_chain(elements(), gravity=g, ground=Ground(motion=motion))
    fixed = build_chain(elements(), gravity=g - acc)
    rm = simulate_reference(moving, 1.0, rtol=1e-11, atol=1e-12)
    rf = simulate_reference(fixed, 1.0, rtol=1e-11, atol=1e-12)
    shift = 0.5 * acc * rm.t[:, None, None] ** 2
    assert np.abs(rm.rotation - rf.rotation).max() < 1e-8
    assert np.abs(rm.position_output - shift - rf.position_output).max() < 1e-8
    assert np.abs(rm.force - rf.force).max() < 1e-6
    assert np.abs(rm.moment - rf.moment).max() < 1e-6


# --------------------------------------------------------------------------------------------
# driven hub: loads at a clamped root, derived by hand
# --------------------------------------------------------------------------------------------

def test_driven_hub_root_loads():
    """Body clamped to a hub spinning about world z by theta(t); mass centre at l_IC = (L, 0, h),
    principal J_C = diag(jx, jy, jz), gravity -g e_z.  With c, s = cos, sin theta, P = M L h:
        J_I e_z (world) = (-P c, -P s, jz + M L^2)
        N = theta'' (-P c, -P s, jz + M L^2) + theta'^2 (P s, -P c, 0) + M g L (s, -c, 0)
        Q = M (theta'' (-L s, L c, 0) - theta'^2 (L c, L s, 0)) + (0, 0, M g)."""
    mass, big_l, h, g = 2.0, 0.8, 0.3, 9.81
    jx, jy, jz = 0.05, 0.2, 0.22
    angle = lambda t: 0.3 * t ** 2 + np.sin(2 * t)
    rate = lambda t: 0.6 * t + 2 * np.cos(2 * t)
    accel = lambda t: 0.6 - 4 * np.sin(2 * t)
    hub = PrescribedMotion.spin_about_axis([0, 0, 1], angle, rate, accel, position=[0.1, 0.2, 0.3])
    body = RigidBody(mass=mass, inertia=[jx, jy, jz], inertia_about="mass_center",
                     to_mass_center=[big_l, 0, h], to_output=[1.0, 0, 0])
    model = build_chain([FixedHinge(), body], gravity=[0, 0, -g], ground=Ground(motion=hub))
    assert model.ground_locked[0]
    res = simulate_reference(model, 3.0)
    t = res.t
    c, s, th1, th2 = np.cos(angle(t)), np.sin(angle(t)), rate(t), accel(t)
    p = mass * big_l * h
    zero = np.zeros_like(t)
    n_expected = (th2[:, None] * np.stack([-p * c, -p * s, (jz + mass * big_l ** 2) + zero], 1)
                  + th1[:, None] ** 2 * np.stack([p * s, -p * c, zero], 1)
                  + mass * g * big_l * np.stack([s, -c, zero], 1))
    q_expected = (mass * th2[:, None] * np.stack([-big_l * s, big_l * c, zero], 1)
                  - mass * th1[:, None] ** 2 * np.stack([big_l * c, big_l * s, zero], 1)
                  + np.array([0, 0, mass * g]))
    assert np.abs(res.moment[:, 0] - n_expected).max() < 1e-10
    assert np.abs(res.force[:, 0] - q_expected).max() < 1e-10
    assert np.abs(res.angular_acceleration[:, 0] - th2[:, None] * [0, 0, 1]).max() < 1e-12
    assert res.n_steps == 0 and res.info["nfev"] == 0       # nothing free to integrate


def test_driven_hub_with_outboard_pendulum_balances_root():
    """Clamped hub arm carrying a ball-jointed pendulum: the root loads equal the arm's own
    inertial loads plus what the pendulum pulls with at the arm's output point."""
    angle = lambda t: 0.5 * t ** 2
    rate = lambda t: 1.0 * t
    accel = lambda t: 1.0 + 0 * t
    hub = PrescribedMotion.spin_about_axis([0, 1, 0], angle, rate, accel)
    arm = RigidBody(mass=3.0, inertia=[0.01, 0.1, 0.1], inertia_about="mass_center",
                    to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0])
    model = build_chain([FixedHinge(), arm, BallJoint(), link()], ground=Ground(motion=hub))
    res = simulate_reference(model, 1.0, rtol=1e-10, atol=1e-12)
    m_arm = 3.0
    a = res.rotation[:, 0]
    w, al = res.angular_velocity[:, 0], res.angular_acceleration[:, 0]
    rho_c = a @ np.array([0.5, 0, 0])
    rho_o = a @ np.array([1.0, 0, 0])
    a_c = np.cross(al, rho_c) + np.cross(w, np.cross(w, rho_c))
    g = np.array([0, -G, 0])
    f_out = res.force[:, 1]                    # pendulum pulled by the arm at the output point
    assert np.abs(res.force[:, 0] - (m_arm * a_c - m_arm * g + f_out)).max() < 1e-9
    j_i = np.diag([0.01, 0.1 + 3 * 0.25, 0.1 + 3 * 0.25])
    j_w = a @ j_i @ np.swapaxes(a, 1, 2)
    n_expected = (np.einsum("tij,tj->ti", j_w, al)
                  + np.cross(w, np.einsum("tij,tj->ti", j_w, w))
                  - np.cross(rho_c, m_arm * g) + np.cross(rho_o, f_out))
    assert np.abs(res.moment[:, 0] - n_expected).max() < 1e-9
    assert np.abs(res.angular_acceleration[:, 0] - [0, 1, 0]).max() < 1e-12


def test_elastic_hinge_on_spinning_hub_energy():
    """A body co-rotating with a hub on an elastic root hinge barely deflects: the spring
    energy must be measured against the hub's current frame, not its frame at t = 0."""
    hub = PrescribedMotion.spin_about_axis([0, 0, 1], lambda t: t, lambda t: 1.0, lambda t: 0.0)
    model = build_chain([ElasticHinge(translational_stiffness=1e4, rotational_stiffness=100.0),
                         link(angular_velocity=[0, 0, 1.0])], gravity=[0, 0, 0],
                        ground=Ground(motion=hub))
    res = simulate_reference(model, 1.0, rtol=1e-10, atol=1e-12)
    spring = np.linalg.norm(res.moment[:, 0], axis=-1)
    assert spring.max() < 1e-2                               # |m| = k_r |psi|, tiny
    assert np.abs(res.potential).max() < 2e-4    # (not 0.5 k_r theta^2 = 50 J at t = 1)
    assert np.abs(res.kinetic - 0.5 * 5 / 12).max() < 1e-3   # J_I,zz w^2 / 2, nearly


# --------------------------------------------------------------------------------------------
# API
# --------------------------------------------------------------------------------------------

def test_result_fields(three_link_run):
    model, res = three_link_run
    n, t = model.n_bodies, len(res.t)
    assert res.method == "newton-euler/DOP853"
    for name in ("position_input", "position_mass_center", "position_output", "angular_velocity",
                 "angular_acceleration", "force", "moment"):
        assert getattr(res, name).shape == (t, n, 3), name
    assert res.rotation.shape == (t, n, 3, 3)
    assert res.kinetic.shape == res.potential.shape == (t,)
    assert res.n_steps > 0 and res.info["nfev"] > res.n_steps and res.wall_time > 0
    default = simulate_reference(model, 0.1, method="RK45", rtol=1e-8, atol=1e-10)
    assert len(default.t) == 201 and default.t[-1] == 0.1
    assert default.method == "newton-euler/RK45"


@pytest.mark.parametrize("kwargs, word", [
    (dict(t_end=0.0), "t_end"), (dict(t_end=-1.0), "t_end"), (dict(t_end="x"), "t_end"),
    (dict(t_end=1.0, method="Euler"), "method"), (dict(t_end=1.0, rtol=0.0), "rtol"),
    (dict(t_end=1.0, rtol=1e-20), "rtol"), (dict(t_end=1.0, atol=-1.0), "atol"),
    (dict(t_end=1.0, atol=np.nan), "atol"), (dict(t_end=1.0, t_eval=[0.0, 2.0]), "t_eval"),
    (dict(t_end=1.0, t_eval=[0.5, 0.2]), "t_eval")])
def test_bad_arguments(kwargs, word):
    model = build_chain([BallJoint(), link()])
    with pytest.raises(ValueError, match=word):
        simulate_reference(model, **kwargs)


def test_the_references_kernels_compile_once_for_every_kind_of_model():
    """The reference's kernels take arguments of the same types for every model: rigid links,
    a closed loop, modal beams on a spinning hub (a prescribed ground), strain rods.  A model
    that typed any apart (no rods' tables, a moving ground's read-only arrays) compiled the
    kernels a second time, 40-75 s on a cold cache."""
    import sys
    from pathlib import Path

    from dttmm import StrainRod
    from dttmm.model.chains import three_pendulum
    from dttmm.kernels import python_twin
    from dttmm.model.mechanisms import slider_crank
    from dttmm.reference import equations
    from dttmm.reference.integrator import integrate_dop853
    from dttmm.reference.problem import _Problem
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "examples"))
    import spin_up
    rod = build_chain([BallJoint(), StrainRod(length=1.0, bending_stiffness=2.0,
                                              mass_per_length=0.5,
                                              polar_inertia_per_length=1e-3)])
    models = (build_chain([BallJoint(), link()]), slider_crank(), three_pendulum(),
              spin_up.tube(1, 2, 4.0), rod)
    for model in models:
        problem = _Problem(model)
        assert np.all(np.isfinite(problem.rhs(0.1, problem.initial_state())))
        fixed = problem.fixed_args()
        if fixed is not None:
            integrate_dop853(*fixed, problem.initial_state(), 1e-300, 1.0, 1.0, np.zeros(0))
    for kernel in (equations.rhs_kernel, python_twin(equations.rhs_kernel),
                   equations._solve_dynamics, integrate_dop853):
        assert len(getattr(kernel, "signatures", [None])) <= 1, kernel.signatures


@pytest.mark.parametrize("case", ["three_pendulum", "joints", "spun hub"])
def test_the_compiled_integrator_is_scipys_dop853(case, monkeypatch):
    """A model with nothing in Python during the run integrates in compiled code
    (reference/integrator.py: scipy's DOP853 step for step, the joints' arm's spring-damper
    slide set as in Python, a hub spun by a profile's angle evaluated in compiled code:
    reference/hub.py); the same run through solve_ivp (the compiled path turned off) gives the
    same states to rounding, in as many steps to one.  Not the spun tube's steps: its stiff
    modes make the count chaotic, for scipy's integrator too (seed 000's tube with a mass over
    2 s: 710 to 2269 steps from four starts 1e-15 apart), so there the states alone."""
    import sys
    from pathlib import Path

    from helpers import joints_arm

    from dttmm.model.chains import three_pendulum
    from dttmm.reference.problem import _Problem
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "examples"))
    import spin_up
    model = {"three_pendulum": three_pendulum(2), "joints": joints_arm(),
             "spun hub": spin_up.tube(1, 2, 6.0)}[case]
    assert _Problem(model).fixed_args() is not None
    t_end = 0.3 if case != "spun hub" else 2.0
    t = np.linspace(0.0, t_end, 31)
    compiled = simulate_reference(model, t_end, t_eval=t)
    monkeypatch.setattr(_Problem, "fixed_args", lambda self: None)
    scipy_run = simulate_reference(model, t_end, t_eval=t)
    for field in ("position_output", "velocity_input", "angular_velocity"):
        assert np.allclose(getattr(compiled, field), getattr(scipy_run, field),
                           rtol=0.0, atol=1e-11 if case != "spun hub" else 1e-9), field
    if case != "spun hub":
        assert abs(compiled.n_steps - scipy_run.n_steps) <= 1
        assert compiled.info["nfev"] <= scipy_run.info["nfev"]


def test_a_hub_spun_by_a_profile_is_evaluated_in_compiled_code_as_the_profile():
    """reference/hub.py: the hub's rotation, angular velocity and acceleration from its angle's
    terms in compiled code equal the motion's own Python functions (dttmm.model.profiles through
    PrescribedMotion.spin_about_axis) for every kind it reads, at times before and after a
    ramp's and a spin-up's end, to rounding (the kernels' fused multiply-adds: 1e-13 here); an
    angle it does not read (a table, a plain function, derivatives not the profile's own, a
    motion not made by spin_about_axis) gives no table, and such a run keeps solve_ivp."""
    from dttmm.model.profiles import profile
    from dttmm.reference.hub import hub_table, spun_ground
    from dttmm.reference.problem import _Problem
    kinds = [{"profile": "constant", "value": 0.3},
             {"profile": "linear", "slope": 2.0, "offset": -0.5},
             {"profile": "sine", "amplitude": 0.7, "frequency": 1.3, "phase": 0.2, "offset": 1.0},
             {"profile": "sine", "amplitude": -0.4, "angular_frequency": 5.0},
             {"profile": "ramp", "value": 1.5, "duration": 0.8},
             {"profile": "spin_up", "omega": 6.0, "period": 1.5}]
    specs = kinds + [{"profile": "sum", "terms": kinds}]
    for spec in specs:
        angle = profile(spec)
        motion = PrescribedMotion.spin_about_axis([1.0, -2.0, 0.5], angle, angle.rate,
                                                  angle.acceleration, position=[0.1, 0.2, 0.3])
        axis, terms = hub_table(motion)
        for t in (0.0, 0.37, 0.8, 1.2, 1.5, 2.9):
            rot, w, w_dot = np.zeros((3, 3)), np.zeros(3), np.zeros(3)
            spun_ground(axis, terms, t, rot, w, w_dot)
            _, _, _, rot_py, w_py, w_dot_py = motion(t)
            for got, want in ((rot, rot_py), (w, w_py), (w_dot, w_dot_py)):
                assert np.allclose(got, want, rtol=1e-13, atol=1e-13), (spec, t, got, want)
    angle = profile({"profile": "spin_up", "omega": 6.0, "period": 1.5})
    table = profile({"profile": "table", "t": [0.0, 1.0], "value": [0.0, 2.0]})
    unread = [PrescribedMotion.spin_about_axis([0, 0, 1], lambda t: t, lambda t: 1.0,
                                               lambda t: 0.0),
              PrescribedMotion.spin_about_axis([0, 0, 1], angle, lambda t: angle.rate(t),
                                               angle.acceleration),
              PrescribedMotion.spin_about_axis([0, 0, 1], table, table.rate, table.acceleration),
              PrescribedMotion(rotation=lambda t: np.eye(3))]
    for motion in unread:
        assert hub_table(motion) is None
    hub = build_chain([BallJoint(), link()], ground=Ground(motion=unread[0]))
    assert _Problem(hub).fixed_args() is None


def test_a_model_with_python_inputs_integrates_through_scipy():
    """A drive, load or ground motion given as a function keeps solve_ivp (it runs Python at
    every right-hand side)."""
    from dttmm.reference.integrator import _JOINTS
    from dttmm.reference.problem import _Problem
    pushed = build_chain([BallJoint(), link(force=lambda t: [0.0, np.sin(t), 0.0])])
    assert _Problem(pushed).fixed_args() is None
    problem = _Problem(build_chain([BallJoint(), link()]))
    args, springs, hub_axis, hub_terms = problem.fixed_args()
    assert hub_terms.shape == (0, 5)                                   # a still ground
    assert args[_JOINTS] is problem.joints and springs.shape == (0, 4)   # where _rhs sets them
