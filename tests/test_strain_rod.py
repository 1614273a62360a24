"""The strain rod's kinematics (docs/strain_rod.md, kernels/transfers/strain_rod.py): its poses
against the exponential of a constant strain and against an ODE solution of g' = g xi^, the
Magnus step's order, and its velocities and accelerations against differences of its poses."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.spatial.transform import Rotation

from dttmm.elements.strain_rod import STRAIGHT, kinematics_tables, stations, strain_basis
from dttmm.kernels.transfers.strain_rod import (SERIES_BELOW, jacobian_coefficients,
                                                rod_kinematics)
from dttmm.reference.strain_rod import rod_sections

L = 1.2
ALL = ("twist", "bend_y", "bend_z", "stretch")


def _kinematics(x, modes, q, qd=None, qdd=None, components=ALL, kernel=rod_kinematics):
    steps, xi0, phi = kinematics_tables(L, x, modes, components)
    nq = phi.shape[-1]
    qd = np.zeros(nq) if qd is None else qd
    qdd = np.zeros(nq) if qdd is None else qdd
    n = len(steps) + 1
    out = [np.zeros((n, 3, 3))] + [np.zeros((n, 3)) for _ in range(5)]
    kernel(steps, xi0, phi, np.asarray(q, float), qd, qdd, *out)
    return out          # rot, pos, omega, vel, alpha, acc


def _hat6(xi):
    m = np.zeros((4, 4))
    m[:3, :3] = [[0.0, -xi[2], xi[1]], [xi[2], 0.0, -xi[0]], [-xi[1], xi[0], 0.0]]
    m[:3, 3] = xi[3:]
    return m


def test_a_constant_strain_is_exact_with_one_step():
    """One step of a constant strain (twist, both curvatures, stretch: a helix) is the
    exponential of the strain over the rod, as scipy's expm gives it; a curvature 2 pi / L closes
    the circle."""
    q = np.array([0.7, 2.1, -5.2, 0.03])
    rot, pos, *_ = _kinematics([L], 1, q)
    g = expm(_hat6(STRAIGHT + np.array([0.7, 2.1, -5.2, 0.03, 0.0, 0.0])) * L)
    assert np.abs(rot[-1] - g[:3, :3]).max() < 1e-13
    assert np.abs(pos[-1] - g[:3, 3]).max() < 1e-13
    for turn in (0.25, 0.5, 1.0):
        kappa = 2.0 * np.pi * turn / L
        rot, pos, *_ = _kinematics([L], 1, [0.0, 0.0, kappa, 0.0])
        exact = np.array([np.sin(kappa * L), 1.0 - np.cos(kappa * L), 0.0]) / kappa
        assert np.abs(pos[-1] - exact).max() < 1e-15 * 10 * L
        assert np.abs(rot[-1] - Rotation.from_rotvec([0, 0, kappa * L]).as_matrix()).max() < 1e-14


def test_a_varying_strain_converges_at_order_four():
    """A linear strain in every component against scipy's DOP853 on g' = g xi^ (rtol 1e-13):
    the Magnus step's error falls as h^4 (fitted slope of log error against log h)."""
    modes = 2
    q = np.array([0.5, -0.8, 1.5, 2.0, -3.0, 4.0, 0.02, 0.01])

    def rhs(x, y):
        xi = STRAIGHT + strain_basis([x], L, modes, ALL)[0] @ q
        return (y.reshape(4, 4) @ _hat6(xi)).ravel()

    g = solve_ivp(rhs, (0.0, L), np.eye(4).ravel(), method="DOP853", rtol=1e-13,
                  atol=1e-14).y[:, -1].reshape(4, 4)
    counts = np.array([2, 4, 8, 16])
    errors = []
    for m in counts:
        rot, pos, *_ = _kinematics(np.linspace(0.0, L, m + 1)[1:], modes, q)
        errors.append(max(np.abs(pos[-1] - g[:3, 3]).max(), np.abs(rot[-1] - g[:3, :3]).max()))
    slope = np.polyfit(np.log(L / counts), np.log(errors), 1)[0]
    assert 3.8 < slope < 4.4, (errors, slope)
    assert errors[-1] < 2e-5


@pytest.fixture(scope="module")
def moving_rod():
    """A rod of linear strain in every component at the Gauss stations, with random rates."""
    rng = np.random.default_rng(1)
    q = np.array([0.5, -0.8, 1.5, 2.0, -3.0, 4.0, 0.02, 0.01])
    qd, qdd = rng.normal(size=8), rng.normal(size=8)
    x, _ = stations(L, 4)
    return x, q, qd, qdd, _kinematics(x, 2, q, qd, qdd)


def test_velocities_and_accelerations_are_the_poses_derivatives(moving_rod):
    """Along q(s) = q + s q' + s^2/2 q'', the stations' velocities p', omega (R' R^T) and
    accelerations p'', alpha (omega's derivative, the kernel's omega at q(s), q' + s q'')
    against central differences at s = +-1e-4: agreement to the differences' own error
    (O(s^2) ~ 1e-9, and rounding / s^2 ~ 1e-8 for the second difference)."""
    x, q, qd, qdd, (rot, pos, omega, vel, alpha, acc) = moving_rod
    s = 1e-4
    plus = _kinematics(x, 2, q + s * qd + 0.5 * s * s * qdd, qd + s * qdd)
    minus = _kinematics(x, 2, q - s * qd + 0.5 * s * s * qdd, qd - s * qdd)
    assert np.abs((plus[1] - minus[1]) / (2 * s) - vel).max() < 5e-9
    assert np.abs((plus[1] - 2.0 * pos + minus[1]) / s ** 2 - acc).max() < 2e-7
    rate = np.einsum("kij,klj->kil", (plus[0] - minus[0]) / (2 * s), rot)
    assert np.abs(rate + rate.transpose(0, 2, 1)).max() < 1e-8            # skew
    assert np.abs(rate[:, [2, 0, 1], [1, 2, 0]] - omega).max() < 5e-9
    assert np.abs((plus[2] - minus[2]) / (2 * s) - alpha).max() < 5e-9
    assert np.abs(acc).max() > 0.1 and np.abs(alpha).max() > 0.1        # (not trivially 0)


def test_velocities_are_linear_in_the_rates(moving_rod):
    """A station's velocity is J(q) q': the velocities of q' are the sum of each rate's
    column (a unit rate at a time), the accelerations at q'' = 0 are the convective terms and
    the rest is J q'' (linear)."""
    x, q, qd, qdd, (rot, pos, omega, vel, alpha, acc) = moving_rod
    columns = [_kinematics(x, 2, q, np.eye(8)[j]) for j in range(8)]
    assert np.abs(sum(c[3] * qd[j] for j, c in enumerate(columns)) - vel).max() < 1e-13
    assert np.abs(sum(c[2] * qd[j] for j, c in enumerate(columns)) - omega).max() < 1e-13
    convective = _kinematics(x, 2, q, qd)
    assert np.abs(acc - convective[5] - sum(c[3] * qdd[j] for j, c in enumerate(columns))
                  ).max() < 1e-12
    assert np.abs(alpha - convective[4] - sum(c[2] * qdd[j] for j, c in enumerate(columns))
                  ).max() < 1e-12


def test_the_jacobian_coefficients_join_at_their_threshold():
    """J_l's coefficients and their derivatives (series below t = 2, closed forms above) agree
    across the threshold to 1e-12 relative, and match differences of b and c."""
    below = np.array(jacobian_coefficients(SERIES_BELOW * (1 - 1e-13)))
    above = np.array(jacobian_coefficients(SERIES_BELOW * (1 + 1e-13)))
    assert np.abs(below - above).max() < 1e-12 * np.abs(below).max()
    for t in (0.3, 1.7, 2.5):
        h = 1e-5
        bm, cm, *_ = jacobian_coefficients((t - h) ** 2)
        b0, c0, beta, gamma, beta1, gamma1 = jacobian_coefficients(t * t)
        bp, cp, *_ = jacobian_coefficients((t + h) ** 2)
        assert abs((bp - bm) / (2 * h) / t - beta) < 1e-9
        assert abs((cp - cm) / (2 * h) / t - gamma) < 1e-9
        betas = [jacobian_coefficients(u * u)[2:4] for u in (t - h, t + h)]
        assert abs((betas[1][0] - betas[0][0]) / (2 * h) / t - beta1) < 1e-8
        assert abs((betas[1][1] - betas[0][1]) / (2 * h) / t - gamma1) < 1e-8


def test_the_reference_computes_the_same_kinematics_its_own_way(moving_rod):
    """The reference's kinematics (reference/strain_rod.py: the exponential and its two time
    derivatives from one power series of 4 x 4 matrices over truncated polynomials; no J_l, no
    closed forms) against the kernel's, on the moving rod and on a full circle turning: every
    output to 1e-12 of its scale."""
    x, q, qd, qdd, ours = moving_rod
    theirs = _kinematics(x, 2, q, qd, qdd, kernel=rod_sections)
    for mine, other in zip(ours, theirs):
        assert np.abs(mine - other).max() < 1e-12 * max(1.0, np.abs(mine).max())
    circle = [0.1, 0.0, 0.0, 0.0, 2 * np.pi / L, 0.3, 0.0, 0.0]
    rates = np.array([0.0, 0.0, 0.5, 0.0, 1.0, -2.0, 0.0, 0.0])
    ours = _kinematics(x, 2, circle, rates, -rates)
    theirs = _kinematics(x, 2, circle, rates, -rates, kernel=rod_sections)
    for mine, other in zip(ours, theirs):
        assert np.abs(mine - other).max() < 1e-12 * max(1.0, np.abs(mine).max())
