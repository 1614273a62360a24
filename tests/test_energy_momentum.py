"""The energy-momentum scheme (docs/solver.md): its transfer against a numpy statement of the step
equations, exact conservation, second order against the Newton-Euler reference (the 60 s runs are in
test_against_reference.py, beside the Newmark scheme's)."""
import numpy as np
import pytest
from helpers import fitted_order, rot_z

from dttmm import BallJoint, ElasticHinge, FixedHinge, build_chain, simulate
from dttmm.model.chains import rigid_chain, unit_link
from dttmm.kernels.transfers.em_body import rigid_body_transfer_em
from dttmm.reference import simulate_reference
from dttmm.results.result import angular_momentum

rng = np.random.default_rng(11)
EM = dict(scheme="energy_momentum")


def skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def em_outputs(mass, l_ic, l_io, j_c, rot_n, w_n, v_c_n, h, z, load, torque):
    """A body's step equations EM1-EM4 written out with numpy: the Cayley map as
    (I - phi^/2)^-1 (I + phi^/2), the momenta from their definitions."""
    a_i, b, m_i, q_i = z[0:3], z[3:6], z[6:9], z[9:12]
    phi = 0.5 * h * h * b
    rot = np.linalg.solve(np.eye(3) - skew(phi) / 2, np.eye(3) + skew(phi) / 2) @ rot_n
    dx_i = 0.5 * h * h * a_i
    dx_c = dx_i + rot @ l_ic - rot_n @ l_ic
    dx_o = dx_i + rot @ l_io - rot_n @ l_io
    v_c = 2 * dx_c / h - v_c_n
    q_o = q_i + load - mass * (v_c - v_c_n) / h
    w_body = 2 * rot_n.T @ phi / h - rot_n.T @ w_n
    pi1, pi0 = rot @ j_c @ w_body, rot_n @ j_c @ rot_n.T @ w_n
    rho_c = (rot @ l_ic + rot_n @ l_ic) / 2
    rho_o = (rot @ l_io + rot_n @ l_io) / 2
    m_o = m_i - np.cross(rho_c, q_i) - np.cross(rho_o - rho_c, q_o) + torque - (pi1 - pi0) / h
    return np.concatenate([2 * dx_o / (h * h), b, m_o, q_o])


def test_em_transfer_is_the_exact_linearization():
    mass, h = 2.0, 1e-2
    j_c = np.array([[0.3, 0.02, -0.01], [0.02, 0.5, 0.03], [-0.01, 0.03, 0.4]])
    l_ic, l_io = np.array([0.4, 0.1, -0.05]), np.array([1.0, 0.2, 0.1])
    p = np.concatenate([[mass], l_ic, l_io, np.zeros(9)])
    rot_n = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    rot_n *= np.linalg.det(rot_n)
    w_n, v_c_n = rng.normal(size=3) * 2, rng.normal(size=3)
    load, torque = np.array([0.5, -19.6, 0.2]), np.array([0.1, 0.0, -0.3])
    z = np.concatenate([rng.normal(size=3) * 100, rng.normal(size=3) * 1e3,
                        rng.normal(size=3), rng.normal(size=3) * 10])
    u = np.empty((12, 13))
    rigid_body_transfer_em(p, j_c, rot_n, w_n, v_c_n, h, z, load, torque, u)
    args = (mass, l_ic, l_io, j_c, rot_n, w_n, v_c_n, h)
    value = em_outputs(*args, z, load, torque)
    assert np.allclose(u[:, :12] @ z + u[:, 12], value, rtol=1e-13, atol=1e-10)
    for c in range(12):
        eps = 1e-4 * max(1.0, abs(z[c]))
        zp, zm = z.copy(), z.copy()
        zp[c] += eps
        zm[c] -= eps
        column = (em_outputs(*args, zp, load, torque) - em_outputs(*args, zm, load, torque))
        assert np.allclose(u[:, c], column / (2 * eps), rtol=1e-6, atol=1e-7), c


def drifts(model, dt, t_end, axis=1, **kw):
    """Largest energy change over the largest kinetic energy, and largest change of the angular
    momentum about the given world axis through the origin over its initial value."""
    res = simulate(model, t_end, dt, record_every=int(round(0.01 / dt)), **EM, **kw)
    e = res.total_energy
    ell = angular_momentum(model, res)[:, axis]
    return (np.abs(e - e[0]).max() / res.kinetic.max(),
            np.abs(ell - ell[0]).max() / abs(ell[0]), res)


@pytest.mark.parametrize("n_links", [3, 10])
def test_energy_and_angular_momentum_are_conserved(n_links):
    """The issue's bound is 1e-4 of the largest kinetic energy and of the initial L_y over 10 s
    at dt = 1e-3; the converged step conserves both to rounding and the Newton tolerance."""
    energy, l_y, res = drifts(rigid_chain(n_links), 1e-3, 10.0)
    print(f"N={n_links}: energy drift {energy:.2e}, L_y drift {l_y:.2e}, "
          f"Newton iterations {res.info['newton_iterations_used'] + 1}")
    assert energy < 1e-9
    assert l_y < 1e-8
    assert res.info["newton_unconverged_steps"] == 0


def test_conservation_with_fixed_hinges_and_a_pinned_tip():
    """Fixed hinges (with a relative rotation) conserve energy and momentum too; a tip pinned to
    the ground conserves energy (the pin does no work; its force has a moment about the axis)."""
    welded = build_chain([BallJoint(), unit_link(angular_velocity=[0.5, 2.0, -1.0]),
                          FixedHinge(rotation=rot_z(0.7)), unit_link(),
                          BallJoint(), unit_link(angular_velocity=[0.0, 0.0, 3.0])])
    energy, l_y, _ = drifts(welded, 1e-3, 3.0)
    assert energy < 1e-9 and l_y < 1e-8
    closed = build_chain([BallJoint(), unit_link(angular_velocity=[0.0, 1.0, 0.0]),
                          BallJoint(), unit_link(rotation=rot_z(-np.pi / 2)),
                          BallJoint(), unit_link(rotation=rot_z(np.pi))], tip="ball")
    energy, _, res = drifts(closed, 1e-3, 3.0)
    assert energy < 1e-9
    tip = res.position_output[:, -1]
    assert np.abs(tip - tip[0]).max() < 1e-12            # the tip stays on its pin


def test_second_order_against_the_reference():
    model = rigid_chain(3)
    t = np.arange(101) * 0.02
    ref = simulate_reference(model, 2.0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=t)
    dts = [4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4]
    errors = []
    for dt in dts:
        res = simulate(model, 2.0, dt, record_every=int(round(0.02 / dt)), **EM)
        errors.append(np.abs(res.position_output - ref.position_output).max())
    order = fitted_order(dts[:-1], errors[:-1])
    print(f"energy-momentum, N=3: errors {['%.2e' % e for e in errors]}, order {order:.3f}")
    assert order == pytest.approx(2.0, abs=0.2)
    assert errors[-1] <= 2e-6
    # mean forces over a step are second-order values at the step's midpoint
    mid = simulate(model, 0.02, 1e-4, **EM)
    f_ref = simulate_reference(model, 0.02, method="DOP853", rtol=1e-12, atol=1e-12,
                               t_eval=[0.02 - 0.5e-4]).force[0]
    assert np.abs(mid.force[-1] - f_ref).max() < 1e-5 * np.abs(f_ref).max()


def test_sweeps_agree():
    model = rigid_chain(3)
    runs = [simulate(model, 1.0, 1e-3, method=m, full_state=f, record_every=10, **EM)
            for m, f in (("riccati", False), ("direct", False), ("riccati", True),
                         ("direct", True))]
    for other in runs[1:]:
        assert np.abs(other.position_output - runs[0].position_output).max() < 1e-9


def test_scope_is_checked_at_the_call():
    with pytest.raises(ValueError, match="scheme must be one of"):
        simulate(rigid_chain(2), 0.1, 1e-3, scheme="midpoint")
    elastic = build_chain([ElasticHinge(1e4, 1e3), unit_link()])
    with pytest.raises(ValueError, match="is elastic"):
        simulate(elastic, 0.1, 1e-3, **EM)
