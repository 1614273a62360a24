"""DT-TMM against analytical results it did not compute: periods, frequencies, torques."""
import numpy as np
import pytest
from helpers import crossing_period, rot_z

from dttmm import (BallJoint, ElasticHinge, FixedHinge, Ground, PrescribedMotion, RigidBody,
                   build_chain, simulate)
from dttmm.model.chains import unit_link

G = 9.81


def test_small_angle_compound_pendulum_period():
    # a unit link hanging straight down from a ball joint, swinging in the x-y plane
    j_zz, mass, l_c = 5.0 / 12.0, 1.0, 0.5
    omega_n = np.sqrt(mass * G * l_c / j_zz)
    model = build_chain([BallJoint(), unit_link(rotation=rot_z(-np.pi / 2),
                                                angular_velocity=[0, 0, 1e-3 * omega_n])])
    res = simulate(model, 12.0, 1e-3)
    period = crossing_period(res.t, res.position_output[:, 0, 0])
    assert period == pytest.approx(2 * np.pi / omega_n, rel=1e-3)
    assert period == pytest.approx(2 * np.pi / omega_n, rel=1e-5)   # trapezoidal: O((w dt)^2)


def body_b(**kwargs):
    return RigidBody(mass=2.0, inertia=[[0.2, 0.01, 0.0], [0.01, 0.3, 0.02], [0.0, 0.02, 0.25]],
                     inertia_about="mass_center", to_mass_center=[0.3, 0.1, 0.0],
                     to_output=[0.6, 0.0, 0.1], **kwargs)


def combined_body(r0, **kwargs):
    """Unit link and body_b welded at the link's output point with relative rotation r0, as one
    body: mass, mass centre and inertia about the input point by hand (parallel axes)."""
    a, b = unit_link(), body_b()
    m_a, m_b = a.mass, b.mass
    c_a = np.array(a.to_mass_center)
    c_b = np.array(a.to_output) + r0 @ np.array(b.to_mass_center)
    j_ca = np.diag([1 / 6, 1 / 6, 1 / 6])
    j_cb = r0 @ np.array(b.inertia) @ r0.T

    def about(c, m):
        return m * (c @ c * np.eye(3) - np.outer(c, c))

    j_i = j_ca + about(c_a, m_a) + j_cb + about(c_b, m_b)
    c = (m_a * c_a + m_b * c_b) / (m_a + m_b)
    out = np.array(a.to_output) + r0 @ np.array(b.to_output)
    return RigidBody(mass=m_a + m_b, inertia=j_i, inertia_about="input", to_mass_center=c,
                     to_output=out, **kwargs)


def test_fixed_hinge_moves_as_one_body():
    r0 = rot_z(0.4) @ np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0.0]])
    w0 = [0.3, 1.0, -0.5]
    welded = build_chain([BallJoint(), unit_link(angular_velocity=w0), FixedHinge(rotation=r0),
                          body_b()])
    single = build_chain([BallJoint(), combined_body(r0, angular_velocity=w0)])
    a = simulate(welded, 2.0, 1e-3, record_every=10)
    b = simulate(single, 2.0, 1e-3, record_every=10)
    assert np.abs(a.position_output[:, 1] - b.position_output[:, 0]).max() < 1e-9
    assert np.abs(a.rotation[:, 1] - b.rotation[:, 0] @ r0).max() < 1e-9


def test_stiff_elastic_hinges_approach_the_fixed_hinge():
    r0 = rot_z(0.4)
    w0 = [0.3, 1.0, -0.5]
    fixed = simulate(build_chain([BallJoint(), unit_link(angular_velocity=w0),
                                  FixedHinge(rotation=r0), body_b()]), 1.0, 1e-4, record_every=100)
    gaps = []
    for k in (1e5, 1e7):
        model = build_chain([BallJoint(), unit_link(angular_velocity=w0),
                             ElasticHinge(k, k / 10, rotation=r0), body_b(angular_velocity=w0)])
        res = simulate(model, 1.0, 1e-4, record_every=100)
        gaps.append(np.abs(res.position_output[:, 1] - fixed.position_output[:, 1]).max())
    # the gap is the springs' static deflection, O(load / k) (1.7e-3 m at k = 1e5): 1/k scaling
    assert gaps[0] < 5e-3
    assert gaps[0] / 150 < gaps[1] < gaps[0] / 70


def test_body_on_rotational_spring_oscillates_at_sqrt_k_over_j():
    j, k = 0.4, 250.0
    body = RigidBody(mass=3.0, inertia=[0.5, 0.6, j], inertia_about="mass_center",
                     to_output=[1.0, 0, 0], angular_velocity=[0, 0, 1e-3])
    model = build_chain([ElasticHinge(translational_stiffness=1e6, rotational_stiffness=k), body],
                        gravity=[0, 0, 0])
    res = simulate(model, 3.0, 1e-4)
    period = crossing_period(res.t, res.angular_velocity[:, 0, 2])
    assert period == pytest.approx(2 * np.pi / np.sqrt(k / j), rel=1e-4)


def test_driven_root_moment_equals_the_spin_up_torque():
    """A body with products of inertia clamped to a hub spun up about world z, theta = a t^2 / 2.
    About the fixed hub point: M = J e_z alpha + w^2 e_z x (J e_z), J = A J_I A^T (world);
    the force is M a_C = M (alpha e_z x rho_C - w^2 rho_C_perp)."""
    alpha = 3.0
    j_c = np.array([[0.4, 0.05, 0.08], [0.05, 0.6, -0.06], [0.08, -0.06, 0.7]])
    l_c = np.array([0.5, 0.1, 0.2])
    mass = 2.0
    j_i = j_c + mass * (l_c @ l_c * np.eye(3) - np.outer(l_c, l_c))
    hub = PrescribedMotion.spin_about_axis([0, 0, 1], angle=lambda t: 0.5 * alpha * t * t,
                                           rate=lambda t: alpha * t, acceleration=lambda t: alpha)
    body = RigidBody(mass=mass, inertia=j_i, inertia_about="input", to_mass_center=l_c,
                     to_output=[1.0, 0, 0])
    model = build_chain([FixedHinge(), body], gravity=[0, 0, 0], ground=Ground(motion=hub))
    res = simulate(model, 1.5, 1e-3, record_every=50)
    ez = np.array([0, 0, 1.0])
    for i, t in enumerate(res.t):
        a = rot_z(0.5 * alpha * t * t)
        w = alpha * t
        j_ez = a @ j_i @ ez
        moment = alpha * j_ez + w * w * np.cross(ez, j_ez)
        rho = a @ l_c
        force = mass * (alpha * np.cross(ez, rho) - w * w * np.array([rho[0], rho[1], 0.0]))
        assert np.allclose(res.moment[i, 0], moment, atol=1e-9 * (1 + np.abs(moment).max()))
        assert np.allclose(res.force[i, 0], force, atol=1e-9 * (1 + np.abs(force).max()))
        assert np.allclose(res.rotation[i, 0], a, atol=1e-10)
