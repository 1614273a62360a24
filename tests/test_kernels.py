"""Each kernel against a plain-numpy (or scipy) statement of what it computes."""
import numpy as np
import pytest
from scipy.linalg import expm
from scipy.spatial.transform import Rotation

from dttmm.kernels.transfers.body import rigid_body_transfer
from dttmm.kernels.transfers.hinge import elastic_hinge_loads, elastic_hinge_transfer
from dttmm.kernels.algebra.so3 import expm_so3, hat, left_jacobian, log_so3

rng = np.random.default_rng(7)


def skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


@pytest.mark.parametrize("scale", [1e-9, 1e-3, 0.5, 2.5])
def test_so3_kernels_match_scipy(scale):
    phi = rng.normal(size=3) * scale
    out = np.empty((3, 3))
    hat(phi, out)
    assert np.allclose(out, skew(phi))
    expm_so3(phi, out)
    assert np.allclose(out, expm(skew(phi)), atol=1e-15)
    back = np.empty(3)
    log_so3(out, back)
    assert np.allclose(back, Rotation.from_matrix(out).as_rotvec(), atol=1e-12)
    # left Jacobian: exp((phi + e)^) = exp((J_l e)^) exp(phi^) to first order in e
    left_jacobian(phi, out)
    eps = 1e-6
    for i in range(3):
        e = np.zeros(3)
        e[i] = eps
        d = expm(skew(phi + e)) @ expm(skew(phi)).T
        w = np.array([d[2, 1] - d[1, 2], d[0, 2] - d[2, 0], d[1, 0] - d[0, 1]]) / 2
        assert np.allclose(w / eps, out[:, i], atol=1e-6)


@pytest.mark.parametrize("angle", [1e-5, 3e-3, 0.0099, 0.0101, 0.3])
def test_so3_series_branch_is_exact_to_rounding(angle):
    """exp and J_l switch from series to closed forms at |phi| = 1e-2 (kernels/algebra/so3.py): they
    match scipy's expm and J_l = int_0^1 exp(s phi^) ds (10-point Gauss-Legendre of scipy's
    expm, exact to rounding here) to 4e-16 on the series side; the closed forms lose digits to
    cancellation just above it (measured 2e-15 at 0.0101), hence 1e-14 there."""
    direction = rng.normal(size=3)
    phi = angle * direction / np.linalg.norm(direction)
    tol = 4e-16 if angle < 1e-2 else 1e-14
    out = np.empty((3, 3))
    expm_so3(phi, out)
    assert np.abs(out - expm(skew(phi))).max() < tol
    x, w = np.polynomial.legendre.leggauss(10)
    jl = sum(0.5 * wk * expm(0.5 * (xk + 1.0) * skew(phi)) for xk, wk in zip(x, w))
    left_jacobian(phi, out)
    assert np.abs(out - jl).max() < tol


def body_outputs(p, rot_prev, c1, c3, w1, w3, z, load, torque):
    """The rigid body's nonlinear transfer, written out with numpy (docs/rigid_body.md)."""
    mass, l_ic, l_io, j_b = p[0], p[1:4], p[4:7], p[7:16].reshape(3, 3)
    a_i, phi, m_i, q_i = z[0:3], z[3:6], z[6:9], z[9:12]
    rot = expm(skew(phi)) @ rot_prev
    wd, w = c1 * phi + w1, c3 * phi + w3
    rho, rho_c = rot @ l_io, rot @ l_ic
    j = rot @ j_b @ rot.T
    a_o = a_i + np.cross(wd, rho) + np.cross(w, np.cross(w, rho))
    a_c = a_i + np.cross(wd, rho_c) + np.cross(w, np.cross(w, rho_c))
    q_o = q_i + load - mass * a_c
    m_o = (m_i - np.cross(rho, q_o) + np.cross(rho_c, load) + torque
           - (j @ wd + np.cross(w, j @ w) + mass * np.cross(rho_c, a_i)))
    return np.concatenate([a_o, phi, m_o, q_o])


@pytest.mark.parametrize("angle", [1e-5, 1e-3, 0.05, 0.0999, 0.1001, 0.5, 2.0])
def test_left_jacobian_derivative_matches_differences(angle):
    """DJ_l(phi)[delta] (the end moment's eta'' columns, docs/beam.md) against central
    differences of left_jacobian, on both sides of its series switch (|phi| = 0.1): measured
    1.1e-9 at most, the differences' own error."""
    from dttmm.kernels.algebra.so3 import left_jacobian, left_jacobian_derivative
    gen = np.random.default_rng(3)
    phi = gen.normal(size=3)
    phi *= angle / np.linalg.norm(phi)
    delta = gen.normal(size=3)
    got = np.empty((3, 3))
    left_jacobian_derivative(phi, delta, got)
    eps = 1e-5 * max(angle, 1e-2)
    plus, minus = np.empty((3, 3)), np.empty((3, 3))
    left_jacobian(phi + eps * delta, plus)
    left_jacobian(phi - eps * delta, minus)
    assert np.abs(got - (plus - minus) / (2 * eps)).max() < 1e-8


def test_rigid_body_transfer_is_the_exact_linearization():
    j_c = np.array([[0.3, 0.02, -0.01], [0.02, 0.5, 0.03], [-0.01, 0.03, 0.4]])
    l_ic, l_io = np.array([0.4, 0.1, -0.05]), np.array([1.0, 0.2, 0.1])
    mass = 2.0
    j_i = j_c + mass * (l_ic @ l_ic * np.eye(3) - np.outer(l_ic, l_ic))
    p = np.concatenate([[mass], l_ic, l_io, j_i.ravel()])
    rot_prev = Rotation.from_rotvec([0.3, -0.7, 0.2]).as_matrix()
    h = 1e-3
    c1, c3 = 1 / (0.25 * h * h), 0.5 / (0.25 * h)
    w1, w3 = rng.normal(size=3) * 10, rng.normal(size=3)
    load, torque = rng.normal(size=3), rng.normal(size=3)
    z_star = np.concatenate([rng.normal(size=3), rng.normal(size=3) * 1e-3, rng.normal(size=3),
                             rng.normal(size=3)])
    u = np.empty((12, 13))
    rot_star = expm(skew(z_star[3:6])) @ rot_prev
    lam = np.empty((3, 3))
    left_jacobian(z_star[3:6], lam)
    phi = z_star[3:6]
    rigid_body_transfer(p, rot_star, lam, c1 * np.eye(3), c3 * np.eye(3), c1 * phi + w1,
                        c3 * phi + w3, z_star, load, torque, u)
    exact = body_outputs(p, rot_prev, c1, c3, w1, w3, z_star, load, torque)
    assert np.allclose(u[:, :12] @ z_star + u[:, 12], exact, rtol=1e-12, atol=1e-9)
    # Jacobian by central differences, column by column
    for c in range(12):
        e = np.zeros(12)
        step = 1e-7 if 3 <= c < 6 else 1e-4
        e[c] = step
        fd = (body_outputs(p, rot_prev, c1, c3, w1, w3, z_star + e, load, torque)
              - body_outputs(p, rot_prev, c1, c3, w1, w3, z_star - e, load, torque)) / (2 * step)
        scale = max(1.0, np.abs(fd).max())
        assert np.allclose(u[:, c], fd, atol=2e-6 * scale), f"column {c}"


def test_elastic_hinge_transfer_reproduces_the_spring_law():
    """At the linearization point the hinge's affine map gives the outboard state that satisfies
    the spring-damper law written out independently."""
    k_t, c_t = np.diag([1e4, 2e4, 3e4]), np.diag([10.0, 20.0, 5.0])
    k_r, c_r = np.diag([500.0, 600.0, 700.0]), np.diag([1.0, 2.0, 3.0])
    r0 = Rotation.from_rotvec([0.1, 0.2, -0.1]).as_matrix()
    hrow = np.concatenate([r0.ravel(), k_t.ravel(), c_t.ravel(), k_r.ravel(), c_r.ravel()])
    rot_in = Rotation.from_rotvec([0.2, 0.1, 0.3]).as_matrix()
    psi_true = np.array([0.01, -0.02, 0.015])
    rot_out = rot_in @ expm(skew(psi_true)) @ r0
    w_in, w_out = np.array([0.1, 0.2, 0.3]), np.array([0.2, 0.1, 0.4])
    d, d_dot = np.array([1e-4, -2e-4, 3e-4]), np.array([1e-3, 0.0, -1e-3])
    q, m_in, m_out = elastic_hinge_loads(hrow, rot_in, w_in, rot_out, w_out, d, d_dot)
    assert np.allclose(q, -rot_in @ (k_t @ rot_in.T @ d + c_t @ rot_in.T @ d_dot))
    assert np.allclose(m_out, -rot_in @ (k_r @ psi_true + c_r @ rot_in.T @ (w_out - w_in)))
    assert np.allclose(m_in, m_out + np.cross(d, q))
    # integrator coefficients chosen so that this state is the step's outcome
    c1, c3 = 4e6, 1e3
    w3d = d_dot - c3 * d
    w1d = 5.0 - c1 * d
    z_in = np.concatenate([np.ones(3), np.zeros(3), m_in, q])
    lam = np.eye(3)
    u = np.empty((12, 13))
    phi_out_star = np.array([0.3, 0.2, 0.1])
    dw = c3 * np.eye(3)
    elastic_hinge_transfer(hrow, rot_in, lam, w_in, dw, rot_out, lam, w_out, dw, phi_out_star,
                           c1, c3, w1d, w3d, z_in, u)
    z_out = u[:, :12] @ z_in + u[:, 12]
    assert np.allclose(z_out[9:12], q)
    assert np.allclose(z_out[6:9], m_out, atol=1e-12)
    assert np.allclose(z_out[0:3], 1.0 + c1 * d + w1d)          # a_out = a_in + d_ddot
    assert np.allclose(z_out[3:6], phi_out_star, atol=1e-10)    # the guess satisfies the law


def test_inv3_matches_numpy():
    from dttmm.kernels.algebra.mat3 import inv3
    a = rng.normal(size=(3, 3)) + 3 * np.eye(3)
    out = np.empty((3, 3))
    det = inv3(a, out)
    assert det == pytest.approx(np.linalg.det(a), rel=1e-13)
    assert np.allclose(out, np.linalg.inv(a), rtol=1e-13, atol=1e-15)
    assert inv3(np.ones((3, 3)), out) == 0.0 and not np.all(np.isfinite(out))


def test_small_products_match_numpy():
    """mat3.matmul, matvec and dot (the loops that replace numba's BLAS `@` in the kernels that
    allocate) against numpy's @, on contiguous arrays, transposes and strided views, and on
    empty sizes."""
    from dttmm.kernels.algebra.mat3 import dot, matmul, matvec
    a, b = rng.normal(size=(3, 5)), rng.normal(size=(5, 4))
    big = rng.normal(size=(6, 9))
    for x, y in ((a, b), (b.T, a.T), (big[::2, 1:6], big[1:6, ::3]), (a[:, :0], b[:0])):
        assert np.allclose(matmul(x, y), x @ y, rtol=1e-14, atol=1e-15)
        v = big[0, :x.shape[1]]
        assert np.allclose(matvec(x, v), x @ v, rtol=1e-14, atol=1e-15)
        assert dot(v, v) == pytest.approx(v @ v, rel=1e-14)
    assert dot(np.zeros(0), np.zeros(0)) == 0.0


def test_least_norm_solve3_matches_the_pseudo_inverse():
    """The pinned tip's 3 x 3 least-norm solve (kernels/algebra/mat3.py::least_norm_solve3, a Jacobi
    SVD that allocates nothing) against numpy's pinv with the same rcond: on full-rank, rank-2,
    rank-1 and zero matrices the same solution; on matrices scaled over 12 decades (some
    singular values cut off) residuals as small as numpy's."""
    from dttmm.kernels.algebra.mat3 import least_norm_solve3
    rng = np.random.default_rng(3)
    for trial in range(400):
        a = rng.normal(size=(3, 3))
        kind = trial % 4
        if kind == 1:
            a[:, 2] = rng.normal() * a[:, 0] + rng.normal() * a[:, 1]
        elif kind == 2:
            a = np.outer(rng.normal(size=3), rng.normal(size=3))
        elif kind == 3:
            a = a @ np.diag(10.0 ** rng.uniform(-6.0, 6.0, 3))
        b = rng.normal(size=3)
        x = np.array(least_norm_solve3(a, b, 1e-12))
        ref = np.linalg.pinv(a, rcond=1e-12) @ b
        if kind < 3:
            assert np.allclose(x, ref, rtol=1e-10, atol=1e-12), (trial, x, ref)
        else:
            res = np.abs(a @ x - b).max() / (np.abs(a).max() * np.abs(x).max())
            res_ref = np.abs(a @ ref - b).max() / (np.abs(a).max() * np.abs(ref).max())
            assert res <= 10.0 * res_ref + 1e-15, (trial, res, res_ref)
    assert least_norm_solve3(np.zeros((3, 3)), np.ones(3), 1e-12) == (0.0, 0.0, 0.0)


def test_small_solve_matches_lapack_and_flags_singular():
    """The beam's modal systems are solved without LAPACK (kernels/transfers/beam.py,
    _solve_in_place): it must agree with numpy's solve, pivoting included, on the first n_rhs
    columns of b and the first n columns of a (the beam map's work rows are wider), leave the rest
    alone, and leave NaN (for the step's finite check) on a singular matrix."""
    from dttmm.kernels.transfers.beam import _solve_in_place
    rng = np.random.default_rng(7)
    for n in (2, 4, 12):
        a = rng.normal(size=(n, n))
        a[0, 0] = 0.0                                  # needs a row exchange
        b = rng.normal(size=(n, 13))
        padded = np.hstack([a, np.full((n, 3), np.inf)])
        x = b.copy()
        _solve_in_place(padded, x, 10)
        assert np.allclose(x[:, :10], np.linalg.solve(a, b[:, :10]), rtol=1e-10, atol=1e-12)
        assert np.array_equal(x[:, 10:], b[:, 10:])
    x = np.ones((3, 2))
    _solve_in_place(np.zeros((3, 3)), x, 2)
    assert np.isnan(x).all()


def _stiffened_cantilever(twist=0, stretch=0):
    """One clamped beam (free tip) on a hub: geometric stiffening on, the clamped family; with
    twist > 0 that many twist modes (docs/beam.md, "Torsion"), stretch > 0 stretch modes
    ("Stretch")."""
    from dttmm import EulerBernoulliBeam, FixedHinge, build_chain
    return build_chain([FixedHinge(), EulerBernoulliBeam(
        length=2.0, mass_per_length=3.0, bending_stiffness=[40.0, 60.0],
        polar_inertia_per_length=0.01, modes_per_plane=3, stiffening=True, torsion_modes=twist,
        torsional_stiffness=25.0 if twist else None, axial_modes=stretch,
        axial_stiffness=900.0 if stretch else None)])


@pytest.mark.parametrize("start", [False, True])
@pytest.mark.parametrize("system", ["three_pendulum", "cantilever", "cantilever, end torque",
                                    "twisting cantilever", "twisting cantilever, end torque",
                                    "stretching cantilever", "stretching cantilever, end torque",
                                    "welded cantilever", "welded cantilever, end torque",
                                    "welded twisting cantilever"])
def test_beam_transfer_is_the_linearization_of_the_beam_relations(start, system):
    """The beam's transfer (every column written out where the output carries no moment:
    _affine_columns, _modal_columns, _rotation_columns) against central differences of its exact
    relations (_evaluate) in every unknown, eliminated through the modal equations the same way
    (docs/beam.md).  Measured: 7e-12 (u) and 2.5e-11 (eta_map) relative, the central
    differences' own error; the kernel with its w' and eta'' columns forward-differenced gave
    7e-11 here.  With an end moment (a weld, or an applied end torque) the modal equations
    feel the end section's rotation and m_I (add_end_moment: _end_moment_columns), and a weld's
    output slot is the welded body's angular acceleration.  A beam with twist modes
    (twist_relations) or stretch modes has its w' and eta'' columns differenced; its twist
    rows' a_I, m_I, q_I columns at an end moment are _twist_end_columns'."""
    from dttmm.model.chains import three_pendulum
    from dttmm.kernels.transfers.beam import _evaluate, beam_transfer, transfer_work_size
    from dttmm.solving.run_tables import beam_tables
    model, k = ((three_pendulum(2, damping_ratio=0.03, stiffening=True), 1)
                if system == "three_pendulum"
                else (_stiffened_cantilever(2 if "twist" in system else 0,
                                            2 if system.startswith("stretch") else 0), 0))
    _, bp, moments, mode_off, ends, factors = beam_tables(model)
    assert bp[k, 8] == 1.0                      # geometric stiffening on (the default)
    m, mt = int(bp[k, 6]), int(bp[k, 10])
    n = mode_off[k + 1] - mode_off[k]           # 2 m bending, then the twist, the stretch
    # applied loads (docs/beam.md, "Loads on the beam"): an end force (the written-out columns
    # take the outboard's net pull), an end torque in one case (the w' and eta'' columns are
    # then differenced), a distributed load (part of gravity for the beam: _beam_gravity)
    tables = (moments[k, :m, :4 * m + 2], ends[k, :m], factors[k, :m],
              np.array([3.0, -2.0, 1.5]),
              np.array([0.5, 2.0, -1.0]) if system.endswith("torque") else np.zeros(3),
              np.array([0.7, -1.1, 0.4]),         # and a distributed load (N/m)
              ends[k, m:m + mt], ends[k, m + mt:n - m])   # the twist and stretch tables
    gen = np.random.default_rng(11)
    h = 1e-4
    c1, c3 = 1 / (0.25 * h * h), 0.5 / (0.25 * h)
    rot_n = Rotation.from_rotvec([0.4, -0.2, 0.9]).as_matrix()
    # a state of the size a step meets: rates ~ 1 rad/s, accelerations ~ 10 (w1 and w1e then
    # cancel c1 phi* and c1 eta*)
    phi_star, w3, w_n = gen.normal(size=3) * 1e-4, gen.normal(size=3), gen.normal(size=3)
    wd_star = gen.normal(size=3) * 10
    eta_n, eta_d_n = gen.normal(size=n) * 1e-4, gen.normal(size=n) * 1e-3
    eta_dd_star = gen.normal(size=n) * 10
    w1e, w3e = eta_dd_star - c1 * (eta_n + 1e-8), gen.normal(size=n) * 1e-2
    z_star = np.concatenate([gen.normal(size=3), wd_star, np.zeros(3), gen.normal(size=3)])
    outboard = (False, np.eye(3), np.eye(3), np.zeros(3))
    if system.startswith("welded"):
        # a body welded to the output (fixed hinge, relative rotation r_rel): its rotation slot
        # is c1 phi_out + w1 with exp(phi_out^) A_out,n = A_O r_rel; A_out,n a little behind
        # the guess's A_O r_rel, w1 such that the slot holds an acceleration ~10
        from dttmm.kernels.transfers.beam_relations import end_section
        rot_star = Rotation.from_rotvec(phi_star).as_matrix() @ rot_n
        a_o = np.empty((3, 3))
        end_section(ends[k, :m], ends[k, m:m + mt], (eta_dd_star - w1e) / c1, rot_star, a_o)
        r_rel = Rotation.from_rotvec([0.3, 0.1, -0.5]).as_matrix()
        back = gen.normal(size=3) * 1e-4
        rot_out_n = Rotation.from_rotvec(-back).as_matrix() @ a_o @ r_rel
        outboard = (True, r_rel, rot_out_n, gen.normal(size=3) * 10 - c1 * back)
    args = (bp[k], tables, outboard, (False, np.zeros(3)),
            model.gravity, start, rot_n, phi_star, wd_star, c1, c3, w3, w_n, w1e, w3e, eta_n,
            eta_d_n)
    u, eta_map = np.empty((12, 13)), np.empty((n, 13))
    beam_transfer(*args, z_star, eta_dd_star, u, eta_map, np.empty(transfer_work_size(n)))

    # _evaluate takes gravity with the distributed load in it (g + p / mu, as beam_transfer
    # hands it on)
    g_beam = model.gravity + tables[5] / bp[k, 1]
    evaluate_args = args[:4] + (g_beam,) + args[5:]

    def relations(x):
        out, res = np.empty(12), np.empty(n)
        _evaluate(*evaluate_args, x, out, res, np.empty((4, 3)), np.empty(75 + 2 * n))
        return np.concatenate([out, res])

    x0 = np.concatenate([z_star, eta_dd_star])
    # central differences of 1e-4 (relative), 1e-2 where the output carries a moment: there the
    # differences' rounding dominates (the end moment's rows, and a weld's rotation slot
    # c1 log(...), c1 = 4e8), measured 2e-8 (1e-5 in the slot) at 1e-4, 4e-10 (3e-8) at 1e-2;
    # the relations are affine in a_I, m_I, q_I and in w', eta'' up to terms of 1 / c1
    moment = system.startswith("welded") or system.endswith("torque")
    fd_step = 1e-2 if moment else 1e-4
    jac = np.empty((12 + n, 12 + n))
    for c in range(12 + n):
        step = fd_step * (1.0 + abs(x0[c]))
        e = np.zeros(12 + n)
        e[c] = step
        jac[:, c] = (relations(x0 + e) - relations(x0 - e)) / (2 * step)
    e_z = -np.linalg.solve(jac[12:, 12:], jac[12:, :12])
    u_fd = jac[:12, :12] + jac[:12, 12:] @ e_z
    # (with an end torque the w' and eta'' columns are forward differences, whose error is
    # 1e-8 here: measured 1.8e-8 (u) and 1.7e-8 (eta_map); written out, 7e-12)
    # (with stretch modes, 1e-6: their eta_map rows are ~200 times smaller than the bending
    # rows they couple to (largest entries 1.4 against 285), so the forward differences' 1e-8
    # in the coupled solve shows as 3.8e-7 of those rows (measured; 2e-8 in the others))
    # (a weld's rotation slot: 1e-7, its differences' 3e-8 above; 3e-6 where the kernel
    # differences it itself (a twisting beam), whose forward steps of 1e-3 meet the same
    # rounding: measured 1.8e-6)
    tol = (3e-6 if system == "welded twisting cantilever" else
           1e-6 if system.startswith("stretch") else
           1e-7 if "twist" in system or system.startswith("welded") else 1e-9)

    for name, got, want in (("u", u[:, :12], u_fd), ("eta_map", eta_map[:, :12], e_z)):
        scale = np.abs(want).max(axis=1, keepdims=True) + 1e-300
        assert np.abs((got - want) / scale).max() < tol, name


@pytest.mark.parametrize("family, m, stiffening, stretch", [
    (0, 2, 1, 0), (1, 3, 1, 0), (2, 2, 0, 0), (2, 4, 1, 0), (1, 3, 1, 2), (2, 2, 0, 3)])
def test_beam_relations_match_a_direct_quadrature(family, m, stiffening, stretch):
    """beam_relations writes the integrals along the beam with the modal integrals in the
    beam's frame (docs/beam.md, "The integrals in the frame").  Here every integral is taken
    directly, as docs/beam.md states it, by 40-point Gauss-Legendre quadrature of the line load
    f = mu (g - r''(x)), r'' = a_I + w' x rho + w x (w x rho) + 2 w x A u' + A u'', in world
    components: the outputs (a_O, m_O, q_O), the modal residuals and every sum the analytic
    columns use.  With geometric stiffening (docs/beam.md, "Geometric stiffening"): every
    section also moves back by c(x) e1, c = 1/2 int_0^x (v'^2 + w'^2) (each c(x) and its rates
    by a quadrature of its own over [0, x]), exactly in the line load's integral and the
    output point, and to first order in c in the moment and the second moments (c's products
    with the rigid x e1 and the rigid line load only); the residuals gain
    int N(x) Y_k' u'(x) dx with the axial force N(x) = -e1 . q_O + int_x^L e1 . f_rigid
    (f_rigid = mu (g - a_I - w' x x e1 - w x (w x x e1))), each N(x) by its own quadrature over
    [x, L].  With stretch modes (docs/beam.md, "Stretch") the sections also move by
    u_x = U . xi along e1, exactly in every integral, and the stretch rows are
    -int U_j e1 . f + damping + stiffness + (q_O . e1) U_j(L)."""
    from dttmm.elements.beam import (AXIAL_MODES, BEAM_PARAM_SIZE, EA, mode_shapes,
                                     torsion_shapes)
    from dttmm.kernels.transfers.beam_relations import (END_U, END_V, SUM_C, SUM_H, SUM_J,
                                                        SUM_MODES, SUM_U, SUM_V, aux_rows,
                                                        beam_relations)
    from dttmm.solving.run_tables import beam_tables
    from types import SimpleNamespace
    gen = np.random.default_rng(3 + family + m)
    length, mu, ei_v, ei_w, j_p, zeta = 1.3, 2.1, 40.0, 55.0, 0.02, 0.04
    bp = np.zeros(BEAM_PARAM_SIZE)
    bp[:9] = length, mu, ei_v, ei_w, j_p, zeta, m, family, stiffening
    bp[AXIAL_MODES], bp[EA] = stretch, 700.0
    model = SimpleNamespace(n_bodies=1, body_kind=np.array([1]), beam_params=bp[None, :],
                            n_modes=np.array([2 * m + stretch]))
    _, _, moments, _, ends, factors = beam_tables(model)
    n = 2 * m + stretch
    rot = Rotation.from_rotvec(gen.normal(size=3)).as_matrix()
    w, wd, a_i, m_i, q_i, g = (gen.normal(size=3) for _ in range(6))
    eta, eta_d, eta_dd = (gen.normal(size=n) * s for s in (0.05, 0.5, 5.0))
    out, res, aux = np.empty(12), np.empty(n), np.empty((aux_rows(m), 3))
    # an applied end force F and torque T (docs/beam.md, "Loads on the beam"): q_O and m_O gain
    # them; the modal equations and the axial force see the outboard's net pull q_O - F
    f_end, t_end = gen.normal(size=3), gen.normal(size=3)
    beam_relations(bp, moments[0], ends[0, :m], factors[0], f_end, t_end, g, rot, w, wd, eta,
                   eta_d, eta_dd, a_i, m_i, q_i, out, res, aux, ends[0, m:m + stretch])

    t, wt = np.polynomial.legendre.leggauss(40)
    x, wt = 0.5 * length * (t + 1.0), 0.5 * length * wt
    y = mode_shapes(family, length, m, x)[0]                       # (m, points)
    e1, e2, e3 = rot[:, 0], rot[:, 1], rot[:, 2]

    u_shape, _, u_mass, u_stiff = torsion_shapes(family, length, stretch, x)   # the stretch's
    u_end = torsion_shapes(family, length, stretch, [length])[0][:, 0]

    def world(c):                                          # frame (v, w, u_x) -> world
        return (np.outer(y.T @ c[:m], e2) + np.outer(y.T @ c[m:2 * m], e3)
                + np.outer(u_shape.T @ c[2 * m:], e1))
    rho = np.outer(x, e1) + world(eta)
    vel, acc = world(eta_d), world(eta_dd)                         # A u', A u''
    r_dd = (a_i + np.cross(wd, rho) + np.cross(w, np.cross(w, rho)) + 2 * np.cross(w, vel)
            + acc)
    f = mu * (g - r_dd)

    def shortening(at):                     # c, c', c'' at the points `at`, each (len(at),)
        out = np.zeros((3, len(at)))
        ts, ws = np.polynomial.legendre.leggauss(40)
        for i, xi in enumerate(at):
            dys = mode_shapes(family, length, m, 0.5 * xi * (ts + 1.0))[1]
            for p in range(2):
                sl, sd, sdd = (dys.T @ v[p * m:(p + 1) * m] for v in (eta, eta_d, eta_dd))
                out[:, i] += 0.5 * xi * ws @ np.array([0.5 * sl * sl, sl * sd,
                                                       sd * sd + sl * sdd]).T
        return out if stiffening else 0.0 * out
    c, c_d, c_dd = shortening(x)
    c_l, c_d_l, c_dd_l = shortening([length])[:, 0]
    fore, fore_d, fore_dd = (-np.outer(v, e1) for v in (c, c_d, c_dd))   # -c e1 and rates
    fore_acc = (np.cross(wd, fore) + np.cross(w, np.cross(w, fore)) + 2 * np.cross(w, fore_d)
                + fore_dd)
    f_rigid = mu * (g - a_i - np.cross(wd, np.outer(x, e1))
                    - np.cross(w, np.cross(w, np.outer(x, e1))))
    q_o = q_i + wt @ (f - mu * fore_acc)
    y_l = ends[0, :m, 0]

    def at_end(c):                                         # u(L) (frame v, w, u_x) in the world
        return (y_l @ c[:m]) * e2 + (y_l @ c[m:2 * m]) * e3 + (u_end @ c[2 * m:]) * e1
    end_u = at_end(eta_d) - c_d_l * e1
    end_v = at_end(eta_dd) - c_dd_l * e1
    rho_l = (length - c_l) * e1 + at_end(eta)
    jp_w = j_p * length * np.outer(e1, e1)
    m_o = m_i - np.cross(rho_l, q_o) + wt @ np.cross(rho, f) - (jp_w @ wd
                                                                + np.cross(w, jp_w @ w))
    m_o += wt @ (np.cross(fore, f_rigid) - mu * np.cross(np.outer(x, e1), fore_acc))
    mass_k, stiff_k = factors[0, :m, 0] * mu, factors[0, :m, 1]
    res_want = np.empty(n)
    for p, (e, ei) in enumerate(((e2, ei_v), (e3, ei_w))):
        for k in range(m):
            i = p * m + k
            stiffness = ei * stiff_k[k]
            omega = np.sqrt(stiffness / mass_k[k])
            res_want[i] = (-(wt * y[k]) @ (f @ e) + 2 * zeta * omega * mass_k[k] * eta_d[i]
                           + stiffness * eta[i] + (q_o @ e) * ends[0, k, 0])
    for j in range(stretch):
        i = 2 * m + j
        modal_mass, stiffness = mu * u_mass[j], 700.0 * u_stiff[j]
        res_want[i] = (-(wt * u_shape[j]) @ (f @ e1) + 2 * zeta * np.sqrt(stiffness * modal_mass)
                       * eta_d[i] + stiffness * eta[i] + (q_o @ e1) * u_end[j])
    if stiffening:
        dy = mode_shapes(family, length, m, x)[1]
        axial = np.empty_like(x)
        for i, xi in enumerate(x):
            ts, ws = np.polynomial.legendre.leggauss(40)
            xs, ws = xi + 0.5 * (length - xi) * (ts + 1.0), 0.5 * (length - xi) * ws
            f_rigid = mu * (g - a_i - np.cross(wd, np.outer(xs, e1))
                            - np.cross(w, np.cross(w, np.outer(xs, e1))))
            axial[i] = -(q_o @ e1) + ws @ (f_rigid @ e1)
        for p in range(2):
            slope = dy.T @ eta[p * m:(p + 1) * m]                   # v'(x) or w'(x)
            res_want[p * m:(p + 1) * m] += (dy * (wt * axial * slope)).sum(axis=1)
    a_o = a_i + np.cross(wd, rho_l) + np.cross(w, np.cross(w, rho_l)) + 2 * np.cross(w, end_u) \
        + end_v
    mw = mu * wt
    want = {
        "a_O": (out[0:3], a_o), "m_O": (out[6:9], m_o + t_end), "q_O": (out[9:12], q_o + f_end),
        "residual": (res, res_want),
        "S": (aux[0], mw @ (rho + fore)), "rho_L": (aux[1], rho_l),
        "int mu A u'": (aux[SUM_U], mw @ (vel + fore_d)),
        "int mu A u''": (aux[SUM_V], mw @ (acc + fore_dd)),
        "H": (aux[SUM_H], mw @ np.cross(rho, acc)),
        "J": (aux[SUM_J:SUM_J + 3], (mw * (rho * rho).sum(1)).sum() * np.eye(3)
              - (rho.T * mw) @ rho - 2 * (mw * x) @ c * (np.eye(3) - np.outer(e1, e1))),
        "C": (aux[SUM_C:SUM_C + 3], (vel.T * mw) @ rho + ((fore_d.T * mw) @ np.outer(x, e1))),
        "A u'(L)": (aux[END_U], end_u), "A u''(L)": (aux[END_V], end_v),
        "F_k": (aux[SUM_MODES:SUM_MODES + m], (y * wt) @ f),
        "Q_k": (aux[SUM_MODES + m:SUM_MODES + 2 * m], (y * mw) @ rho),
        "int mu Y_k A u'": (aux[SUM_MODES + 2 * m:SUM_MODES + 3 * m], (y * mw) @ vel),
        "int mu Y_k A u''": (aux[SUM_MODES + 3 * m:SUM_MODES + 4 * m], (y * mw) @ acc),
    }
    for name, (got, ref) in want.items():
        scale = np.abs(ref).max() + 1e-300
        assert np.abs(got - ref).max() < 1e-12 * scale, name


def test_beam_ball_map_folds_the_beam_transfer():
    """The fused loop's beam map (beam_ball_map: the moment and modal rows solved together by
    blocks) against the general loop's path for the same state: beam_transfer (modal solve,
    12 x 13 transfer in angular-acceleration slots), then fold_ball_body (m_I = m_O = 0) and
    eta'' recovered from the input station with the folded w'.  Measured: 2e-15 (v), 1e-14
    (pmap) and 4e-16 (eta map) relative to each row's largest entry."""
    from dttmm.model.chains import three_pendulum
    from dttmm.kernels.transfers.beam import (ball_map_work_shape, beam_ball_map, beam_transfer,
                                              transfer_work_size)
    from dttmm.kernels.assembly.sweep import fold_ball_body
    from dttmm.solving.run_tables import beam_tables
    model = three_pendulum(2, damping_ratio=0.03)
    _, bp, moments, mode_off, ends, factors = beam_tables(model)
    k, m = 1, 2
    n = 2 * m
    tables = (moments[k, :m, :4 * m + 2], ends[k, :m], factors[k, :m],
              np.array([3.0, -2.0, 1.5]), np.zeros(3), np.array([0.7, -1.1, 0.4]),
              ends[k, m:m], ends[k, m:m])         # (no twist, no stretch)
    gen = np.random.default_rng(5)
    h = 1e-3
    c1, c3 = 1 / (0.25 * h * h), 0.5 / (0.25 * h)
    rot_n = Rotation.from_rotvec([-0.3, 0.7, 0.2]).as_matrix()
    phi_star, w3 = gen.normal(size=3) * 1e-3, gen.normal(size=3)
    wd_star = gen.normal(size=3) * 10
    eta_n, eta_d_n = gen.normal(size=n) * 1e-4, gen.normal(size=n) * 1e-3
    eta_dd_star = gen.normal(size=n) * 10
    w1e, w3e = eta_dd_star - c1 * (eta_n + 1e-7), gen.normal(size=n) * 1e-2
    a_i, q_i = gen.normal(size=3), gen.normal(size=3)
    w = c3 * phi_star + w3
    z_star = np.concatenate([a_i, wd_star, np.zeros(3), q_i])
    u, eta_map = np.empty((12, 13)), np.empty((n, 13))
    beam_transfer(bp[k], tables, (False, np.eye(3), np.eye(3), np.zeros(3)), (False, np.zeros(3)),
                  model.gravity, False, rot_n, phi_star, wd_star, c1, c3, w3, w, w1e, w3e, eta_n,
                  eta_d_n, z_star, eta_dd_star, u, eta_map, np.empty(transfer_work_size(n)))
    v_want, p_want = np.empty((6, 7)), np.empty((3, 7))
    fold_ball_body(u, v_want, p_want)
    # eta'' = eta_map [a, w', 0, q; 1] with w' = p_want [a; q; 1]
    e_want = eta_map[:, [0, 1, 2, 9, 10, 11, 12]] + eta_map[:, 3:6] @ p_want
    v, pmap, emap = np.empty((6, 7)), np.empty((3, 7)), np.full((n, 13), np.nan)
    beam_ball_map(bp[k], tables, model.gravity, rot_n, phi_star, wd_star,
                  np.array([c1, c3, 1.0 / c1, c3 / c1]), w3, w1e, w3e, a_i, q_i, eta_dd_star,
                  np.empty(ball_map_work_shape(n)), v, pmap, emap)
    for name, got, want in (("v", v, v_want), ("pmap", pmap, p_want),
                            ("eta map", emap[:, :7], e_want)):
        scale = np.abs(want).max(axis=1, keepdims=True)
        assert np.abs((got - want) / scale).max() < 1e-11, name
