"""Tests of the Newton-Euler reference solver's clamped beams and welded end sections
(docs/beam.md, "Mode shapes", "End sections", "Equations of motion"), against results it does
not compute itself: closed-form modal frequencies, Ritz frequencies and the classical cantilever
frequency, energies and joint kinematics rebuilt here from the recorded state with this file's
own mode shapes (textbook formulas; the element's mode_shapes for the loaded-end polynomial
modes, whose basis is the contract between the two solvers)."""
import numpy as np
import pytest
from scipy.linalg import eigh, expm
from scipy.spatial.transform import Rotation

from dttmm import (BallJoint, ElasticHinge, EulerBernoulliBeam, FixedHinge, RigidBody,
                   build_chain)
from dttmm.elements import BEAM
from dttmm.elements.beam import (CLAMPED, CLAMPED_LOADED, EI_V, FAMILY, LENGTH, PINNED,
                                 mode_shapes)
from dttmm.reference import simulate_reference
from dttmm.reference.rotations import (_end_section_rate, _expm, _left_jacobian,
                                       _left_jacobian_derivative, _so3_coefficients)
from dttmm.reference.shapes import (beam_shape_constants, clamped_shapes,
                                    loaded_mode_coefficients, quadrature_points)

MU = 1.32
EI = 2.5e10 * (0.02 ** 4 / 12)          # 333.3 N m^2
JP = 1.32 * 0.02 ** 2 / 6
EI_SOFT = EI / 16                       # for the long energy runs: 4x lower frequencies
G = 9.81
ROOTS = np.array([1.87510406871196, 4.69409113297418, 7.85475743823761])


def beam(length, modes, ei=EI, **kw):
    # the paper's beam (no geometric stiffening) unless a test asks: this file's textbook
    # frequencies, quadrature energies and weld kinematics are the unstiffened beam's (the
    # stiffened one's checks: tests/test_stiffening.py, test_torsion.py, test_stretch.py)
    kw.setdefault("stiffening", False)
    return EulerBernoulliBeam(length=length, mass_per_length=MU, bending_stiffness=ei,
                              polar_inertia_per_length=JP, modes_per_plane=modes, **kw)


def tip_body(**kw):
    """A rigid block, mass 0.2 kg, its mass centre off the axis (so that it twists the beam)."""
    return RigidBody(mass=0.2, inertia=np.diag([2e-4, 3e-4, 4e-4]), inertia_about="mass_center",
                     to_mass_center=[0.05, 0.02, -0.01], to_output=[0.1, 0, 0], **kw)


def rot_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rot_y(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


# --------------------------------------------------------------------------------------------
# this file's own shapes and energies (independent of the solver's integrals)
# --------------------------------------------------------------------------------------------

def shapes(family, length, modes, x):
    """(Y, Y', stiffness factor k_k / EI) from the textbook formulas: sin(k pi x / L), or
    cosh bx - cos bx - s (sinh bx - sin bx); the element's for the loaded-end modes."""
    x = np.asarray(x, float)
    k = np.arange(1, modes + 1)
    if family == CLAMPED_LOADED:
        y, dy, _, _, stiff = mode_shapes(CLAMPED_LOADED, length, modes, x)
        return y, dy, stiff
    if family == PINNED:
        b = k * np.pi / length
        return (np.sin(np.outer(b, x)), b[:, None] * np.cos(np.outer(b, x)),
                b ** 4 * length / 2)
    b = ROOTS[:modes] / length
    bl = ROOTS[:modes][:, None]
    s = (np.cosh(bl) + np.cos(bl)) / (np.sinh(bl) + np.sin(bl))
    bx = np.outer(b, x)
    y = np.cosh(bx) - np.cos(bx) - s * (np.sinh(bx) - np.sin(bx))
    dy = b[:, None] * (np.sinh(bx) + np.sin(bx) - s * (np.cosh(bx) - np.cos(bx)))
    return y, dy, b ** 4 * length


def beam_state(model, res, k):
    """Family, length, modes, eta and eta' (T, 2n) of beam k."""
    off = int(np.sum(model.n_modes[:k]))
    n2 = int(model.n_modes[k])
    row = model.beam_params[k]
    return (int(row[FAMILY]), row[LENGTH], n2 // 2, res.modal_coordinates[:, off:off + n2],
            res.modal_velocities[:, off:off + n2], row[EI_V])


def energies(model, res, n_q=40):
    """(T,) total energy, by Gauss-Legendre quadrature over each beam (docs/beam.md, "Energy")."""
    g = model.gravity
    xg, wg = np.polynomial.legendre.leggauss(n_q)
    total = np.zeros(len(res.t))
    for k in range(model.n_bodies):
        a = res.rotation[:, k]
        w = res.angular_velocity[:, k]
        r_i, v_i = res.position_input[:, k], res.velocity_input[:, k]
        if model.body_kind[k] == BEAM:
            family, length, m, eta, eta_d, ei = beam_state(model, res, k)
            x = 0.5 * length * (xg + 1)
            wq = 0.5 * length * wg
            y, _, kf = shapes(family, length, m, x)
            p = np.zeros((len(res.t), len(x), 3))
            p[..., 0] = x
            p[..., 1] = eta[:, :m] @ y
            p[..., 2] = eta[:, m:] @ y
            ud = np.zeros_like(p)
            ud[..., 1] = eta_d[:, :m] @ y
            ud[..., 2] = eta_d[:, m:] @ y
            rho = np.einsum("tij,tqj->tqi", a, p)
            v = v_i[:, None] + np.cross(w[:, None], rho) + np.einsum("tij,tqj->tqi", a, ud)
            r = r_i[:, None] + rho
            total += 0.5 * MU * np.einsum("q,tqi,tqi->t", wq, v, v)
            total += 0.5 * JP * length * np.einsum("ti,ti->t", w, a[:, :, 0]) ** 2
            total -= MU * np.einsum("q,tqi,i->t", wq, r, g)
            total += 0.5 * ei * (eta ** 2 @ np.concatenate([kf, kf]))      # EI_v = EI_w here
        else:
            mass = model.body_params[k, 0]
            r_c = res.position_mass_center[:, k]
            v_c = v_i + np.cross(w, r_c - r_i)
            j_w = a @ model.body_mass_center_inertia[k] @ np.swapaxes(a, 1, 2)
            total += 0.5 * mass * np.einsum("ti,ti->t", v_c, v_c)
            total += 0.5 * np.einsum("ti,tij,tj->t", w, j_w, w)
            total -= mass * r_c @ g
    return total


def end_section(model, res, k):
    """r_O (T, 3) and A_O (T, 3, 3) of beam k, rebuilt from its frame and modal coordinates."""
    family, length, m, eta, _, _ = beam_state(model, res, k)
    y, dy, _ = shapes(family, length, m, [length])
    p = np.zeros((len(res.t), 3))
    p[:, 0] = length
    p[:, 1] = eta[:, :m] @ y[:, 0]
    p[:, 2] = eta[:, m:] @ y[:, 0]
    r_o = res.position_input[:, k] + np.einsum("tij,tj->ti", res.rotation[:, k], p)
    theta = np.zeros((len(res.t), 3))
    theta[:, 1] = -eta[:, m:] @ dy[:, 0]
    theta[:, 2] = eta[:, :m] @ dy[:, 0]
    hat = np.zeros((len(res.t), 3, 3))
    hat[:, 0, 1], hat[:, 0, 2], hat[:, 1, 2] = -theta[:, 2], theta[:, 1], -theta[:, 0]
    hat -= np.swapaxes(hat, 1, 2)
    a_o = np.array([a @ expm(h) for a, h in zip(res.rotation[:, k], hat)])
    return r_o, a_o


def check_weld(model, res, k, r_rel=np.eye(3)):
    """Body k + 1 sits on beam k's end section: input point r_O, rotation A_O R_rel."""
    r_o, a_o = end_section(model, res, k)
    assert np.abs(res.position_input[:, k + 1] - r_o).max() < 1e-9
    assert np.abs(res.rotation[:, k + 1] - a_o @ r_rel).max() < 1e-9
    assert np.abs(res.position_output[:, k] - r_o).max() < 1e-9
    return r_o


def dominant_period(t, y):
    """Mean period of y about its mean: linearly interpolated upward crossings, fitted by a line."""
    y = y - 0.5 * (y.max() + y.min())
    i = np.nonzero((y[:-1] < 0) & (y[1:] >= 0))[0]
    tc = t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])
    assert len(tc) >= 4
    return np.polyfit(np.arange(len(tc)), tc, 1)[0]


# --------------------------------------------------------------------------------------------
# shapes, integrals and the end section's rotation
# --------------------------------------------------------------------------------------------

def test_clamped_shapes_and_integrals():
    """The solver's shapes are the clamped-free eigenfunctions (this file's textbook form and the
    element's), its quadrature integrals are converged (twice the points agree) and orthonormal
    as docs/beam.md says (int Y_j Y_k = L delta_jk); the end values are |Y_k(L)| = 2."""
    length, m = 0.7, 3
    x = np.linspace(0.0, length, 11)
    y, dy, _ = clamped_shapes(length, m, x)
    y_ref, dy_ref, _ = shapes(CLAMPED, length, m, x)
    assert np.abs(y - y_ref).max() < 1e-12 and np.abs(dy - dy_ref).max() < 1e-10
    y_el, dy_el, _, mass, stiff = mode_shapes(CLAMPED, length, m, x)
    assert np.abs(y - y_el).max() < 1e-13 and np.abs(dy - dy_el).max() < 1e-12
    assert np.allclose(mass, length) and np.allclose(stiff, (ROOTS / length) ** 4 * length)
    for modes in (3, 5, 8):
        model = build_chain([FixedHinge(), beam(length, modes)], gravity=[0, 0, 0])
        vec, mat = beam_shape_constants(model.beam_params[0])
        vec2, mat2 = beam_shape_constants(model.beam_params[0],
                                          n_points=2 * quadrature_points(modes))
        assert np.abs(vec - vec2).max() < 1e-13 * np.abs(vec).max()
        assert np.abs(mat - mat2).max() < 1e-13 * length
        # orthonormal to rounding with the five tabulated roots; beyond, docs/beam.md's
        # b_k L = (2k - 1) pi / 2 is off the true root by ~1 / cosh(b_k L) (6e-8 for k = 6)
        tol = 1e-13 if modes <= 5 else 1e-7
        assert np.abs(mat - length * np.eye(modes)).max() < tol * length
        assert np.allclose(np.abs(vec[2, :5]), 2.0, rtol=1e-12, atol=0)
    # int Y_1 and int x Y_1 against a fine Simpson rule of the textbook shape
    xs = np.linspace(0.0, length, 20001)
    ys = shapes(CLAMPED, length, 1, xs)[0][0]
    simpson = lambda f: (xs[1] - xs[0]) / 3 * (f[0] + f[-1] + 4 * f[1:-1:2].sum()  # noqa: E731
                                              + 2 * f[2:-1:2].sum())
    assert abs(vec[0, 0] - simpson(ys)) < 1e-12 and abs(vec[1, 0] - simpson(xs * ys)) < 1e-12


def test_loaded_end_modes_and_integrals():
    """The loaded-end modes (docs/beam.md): the solver's coefficients give the element's shapes,
    one mode is (x/L)^2 with lam = 20; the solver's analytic moments, end values and stiffness
    factors equal quadratures of the element's shapes; int Y_j Y_k = L delta_jk."""
    c1, lam1 = loaded_mode_coefficients(1)
    assert abs(c1[0, 0] - np.sqrt(5.0)) < 1e-14 and abs(lam1[0] - 20.0) < 1e-12
    length = 0.8
    xg, wg = np.polynomial.legendre.leggauss(30)
    x, wq = 0.5 * length * (xg + 1), 0.5 * length * wg
    for modes in (1, 2, 4, 6):
        c, _ = loaded_mode_coefficients(modes)
        p = np.arange(2, modes + 2)
        y, dy, ddy, _, stiff = mode_shapes(CLAMPED_LOADED, length, modes, x)
        assert np.abs(c.T @ (x[None] / length) ** p[:, None] - y).max() < 1e-11
        model = build_chain([FixedHinge(), beam(length, modes), BallJoint(), tip_body()],
                            gravity=[0, 0, 0])
        assert model.beam_params[0, FAMILY] == CLAMPED_LOADED
        vec, mat = beam_shape_constants(model.beam_params[0])
        y_end, dy_end, _, _, _ = mode_shapes(CLAMPED_LOADED, length, modes, [length])
        tol = 1e-13 + 1e-16 * np.abs(c).max() ** 2             # the monomials' conditioning
        assert np.abs(vec[0] - y @ wq).max() < tol
        assert np.abs(vec[1] - y @ (wq * x)).max() < tol
        assert np.abs(mat - (y * wq) @ y.T).max() < tol
        assert np.abs(mat - length * np.eye(modes)).max() < tol
        assert np.abs(vec[2] - y_end[:, 0]).max() < tol and np.all(vec[2] > 0)
        assert np.abs(vec[3] - dy_end[:, 0]).max() < 10 * tol
        assert np.allclose(vec[5], stiff, rtol=1e-12, atol=0)
        assert np.allclose((ddy * wq) @ ddy.T, np.diag(stiff), rtol=0, atol=1e-8 * stiff.max())


def test_left_jacobian_and_its_derivative():
    """J_l(t): exp((t + d)^) = exp((J_l d)^) exp(t^) to first order; dJ_l[u] and
    d/dt [J_l(t) t'] against central differences (4th-order Richardson), for |t| < 0.1 (series)
    and |t| ~ 2 (closed forms)."""
    rng = np.random.default_rng(3)
    for scale in (1e-9, 0.03, 0.09, 0.7, 2.0):
        t = rng.normal(size=3)
        t *= scale / np.linalg.norm(t)
        u = rng.normal(size=3)
        h = 1e-6
        e_plus = expm(_hat(t + h * u)) @ expm(_hat(t - h * u)).T
        jl_u_fd = _vee(e_plus - e_plus.T) / 4 / h
        assert np.abs(_left_jacobian(t) @ u - jl_u_fd).max() < 1e-8
        assert np.abs(_expm(t) - expm(_hat(t))).max() < 1e-15
        d = 1e-3

        def jl(s):
            return _left_jacobian(t + s * u)
        fd = (8 * (jl(d) - jl(-d)) - (jl(2 * d) - jl(-2 * d))) / (12 * d)
        assert np.abs(_left_jacobian_derivative(t, u) - fd).max() < 1e-11, scale
        # a trajectory theta(s) = t + s t' + s^2 t''/2: d/ds [J_l theta'] at s = 0
        td, tdd = rng.normal(size=3), rng.normal(size=3)

        def f(s):
            return _left_jacobian(t + s * td + 0.5 * s * s * tdd) @ (td + s * tdd)
        fd = (8 * (f(d) - f(-d)) - (f(2 * d) - f(-2 * d))) / (12 * d)
        assert np.abs(_end_section_rate(t, td, tdd) - fd).max() < 1e-10, scale
    # the series (|t| < 2) and the closed forms meet continuously
    t = np.array([0.0, 1.2, 1.6]) * (1 - 1e-15)
    t2 = np.array([0.0, 1.2, 1.6]) * (1 + 1e-15)
    u = np.array([0.3, -0.2, 0.5])
    assert np.abs(_left_jacobian_derivative(t, u) - _left_jacobian_derivative(t2, u)).max() < 1e-14


def test_so3_coefficients_exact_to_rounding():
    """The series behind J_l and dJ_l (|t| < 1) and the closed forms beyond, against 40-digit
    arithmetic: sin p / p, (1 - cos p)/p^2, (p - sin p)/p^3 and a'(p)/p, b'(p)/p."""
    mpmath = pytest.importorskip("mpmath")
    mpmath.mp.dps = 40
    for p in (1e-7, 1e-3, 0.05, 0.0999, 0.5, 1.0, 1.99, 2.01, 3.0):
        q = mpmath.mpf(p)
        c = mpmath.sin(q) / q
        a = (1 - mpmath.cos(q)) / q ** 2
        b = (q - mpmath.sin(q)) / q ** 3
        a1 = mpmath.diff(lambda z: (1 - mpmath.cos(z)) / z ** 2, q) / q
        b1 = mpmath.diff(lambda z: (z - mpmath.sin(z)) / z ** 3, q) / q
        got = _so3_coefficients(np.array([0.0, 0.6 * p, 0.8 * p]))
        for value, exact in zip(got, (c, a, b, a1, b1)):
            tol = 4e-16 if p < 0.1 else 1e-14        # the closed forms cancel a little near 2
            assert abs(value - float(exact)) <= tol * abs(float(exact)), (p, value, exact)


def _hat(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _vee(m):
    return np.array([m[2, 1], m[0, 2], m[1, 0]])


# --------------------------------------------------------------------------------------------
# dynamics
# --------------------------------------------------------------------------------------------

def test_single_clamped_beam_modal_frequencies():
    """A beam clamped to the ground, no gravity: each modal coordinate oscillates alone at
    omega_k = b_k^2 sqrt(EI / mu) (periods measured from the response), the frame stays put."""
    length, eta0 = 1.0, np.array([1e-3, 2e-4, 1e-4, 0.0, 5e-4, 3e-5])
    model = build_chain([FixedHinge(), beam(length, 3, initial_modal_coordinates=eta0)],
                        gravity=[0, 0, 0])
    assert model.beam_params[0, FAMILY] == CLAMPED
    t = np.linspace(0.0, 0.6, 6001)
    res = simulate_reference(model, 0.6, rtol=1e-11, atol=1e-14, t_eval=t)
    eta = res.modal_coordinates
    assert np.abs(eta[0] - eta0).max() == 0.0
    assert np.abs(eta[:, 3]).max() < 1e-15                  # never excited
    omega = (ROOTS / length) ** 2 * np.sqrt(EI / MU)
    for col, k in ((0, 0), (1, 1), (2, 2), (4, 1), (5, 2)):
        measured = 2 * np.pi / dominant_period(t, eta[:, col])
        assert abs(measured / omega[k] - 1) < 1e-7, (col, measured, omega[k])
        # and it is the free vibration eta0 cos(omega t), amplitude kept
        assert np.abs(eta[:, col] - eta0[col] * np.cos(omega[k] * t)).max() < 1e-7 * eta0[col]
    assert np.abs(res.position_input).max() == 0.0 and np.abs(res.angular_velocity).max() == 0.0
    r_o = check_weld_free_end(model, res)
    assert abs(r_o[0, 1] - 2 * (eta0[0] - eta0[1] + eta0[2])) < 1e-15


def check_weld_free_end(model, res):
    r_o, _ = end_section(model, res, model.n_bodies - 1)
    assert np.abs(res.position_output[:, -1] - r_o).max() < 1e-12
    return r_o


R_REL = rot_z(0.2) @ rot_y(-0.1)        # a kinked weld


def run_energy(elements, gravity, t_end=1.0):
    model = build_chain(elements, gravity=gravity)
    res = simulate_reference(model, t_end, rtol=1e-11, atol=1e-14,
                             t_eval=np.linspace(0.0, t_end, 201))
    energy = energies(model, res)
    scale = res.kinetic.max()
    drift = np.abs(energy - energy[0]).max() / scale
    return model, res, energy, drift


@pytest.mark.parametrize("gravity", [[0.0, 0.0, 0.0], [0.0, -G, 0.0]])
def test_two_element_cantilever_energy_and_weld(gravity):
    """Two clamped beams welded by a kinked fixed hinge, deflected and moving in both planes at
    t = 0: energy (this file's quadrature) conserved, the outboard beam's input point and frame
    on the inboard beam's deflected end section (r_O, A_O R_rel)."""
    model, res, energy, drift = run_energy(
        [FixedHinge(),
         beam(0.5, 3, EI_SOFT, initial_modal_coordinates=[2e-3, -3e-4, 1e-4, 1e-3, 0, 2e-4],
              initial_modal_velocities=[0, 0.05, 0, -0.1, 0, 0]),
         FixedHinge(rotation=R_REL),
         beam(0.5, 2, EI_SOFT, initial_modal_coordinates=[1e-3, 0, -5e-4, 1e-4])], gravity)
    assert list(model.beam_params[:, FAMILY]) == [CLAMPED_LOADED, CLAMPED]
    assert res.kinetic.max() > 0.05
    assert drift < 1e-9, drift                     # ~1.5e-11 measured
    assert np.abs(energy - res.total_energy).max() < 1e-12 * res.kinetic.max()
    r_o = check_weld(model, res, 0, R_REL)
    assert np.ptp(r_o[:, 1]) > 1e-3                # the weld point does move with the deflection
    check_weld_free_end(model, res)
    # the modal coordinates and rates start at the model's
    assert np.abs(res.modal_coordinates[0] - model.initial_modal_coordinates).max() == 0.0
    assert np.abs(res.modal_velocities[0] - model.initial_modal_velocities).max() == 0.0


@pytest.mark.parametrize("gravity", [[0.0, 0.0, 0.0], [0.0, -G, 0.0]])
def test_cantilever_with_tip_body_energy_and_weld(gravity):
    """A rigid block welded (kinked) to the end section of a clamped beam, its mass centre off
    the axis: the end couple and the end rotation's work enter the modal equations."""
    model, res, energy, drift = run_energy(
        [FixedHinge(),
         beam(1.0, 3, EI_SOFT, initial_modal_coordinates=[3e-3, -3e-4, 1e-4, 2e-3, 0, 2e-4]),
         FixedHinge(rotation=R_REL), tip_body()], gravity)
    assert model.beam_params[0, FAMILY] == CLAMPED_LOADED
    assert res.kinetic.max() > 3e-3
    assert drift < 1e-9, drift
    check_weld(model, res, 0, R_REL)
    # the tip body turns with the end section: its angular velocity is w_O, not the frame's 0
    assert np.abs(res.angular_velocity[:, 0]).max() == 0.0
    assert np.abs(res.angular_velocity[:, 1]).max() > 1e-2


def test_swinging_link_clamped_beam_and_tip_body():
    """A rigid link on a ball joint, a beam clamped to it (kinked) and a block welded to the
    beam's end, falling under gravity: large motion, energy conserved, both welds hold."""
    link = RigidBody(mass=1.0, inertia=np.diag([1 / 6, 5 / 12, 5 / 12]), inertia_about="input",
                     to_mass_center=[0.5, 0, 0], to_output=[1, 0, 0], angular_velocity=[0, 0.5, 0])
    clamp = rot_z(-0.3)
    model, res, energy, drift = run_energy(
        [BallJoint(), link, FixedHinge(rotation=clamp), beam(0.6, 2, EI_SOFT),
         FixedHinge(rotation=R_REL), tip_body()], [0.0, -G, 0.0])
    assert res.kinetic.max() > 10.0
    assert drift < 1e-9, drift
    assert np.abs(res.position_input[:, 1] - res.position_output[:, 0]).max() < 1e-12
    assert np.abs(res.rotation[:, 1] - res.rotation[:, 0] @ clamp).max() < 1e-12
    check_weld(model, res, 1, R_REL)
    assert np.abs(res.modal_coordinates).max() > 1e-4         # the fall does bend the beam


def test_ball_jointed_beam_with_welded_tip_body():
    """A beam on a ball joint with a block welded to its end section (a clamped beam in its input
    section's free frame, loaded-end modes): the end slopes turn the block, the end couple does
    modal work; energy conserved."""
    model, res, energy, drift = run_energy(
        [BallJoint(), beam(1.0, 2, EI_SOFT, initial_modal_coordinates=[2e-3, 0, 0, 1e-3]),
         FixedHinge(rotation=R_REL), tip_body()], [0.0, -G, 0.0])
    assert model.beam_params[0, FAMILY] == CLAMPED_LOADED
    assert res.kinetic.max() > 1.0
    assert drift < 1e-9, drift
    r_o = check_weld(model, res, 0, R_REL)
    chord = np.linalg.norm(r_o - res.position_input[:, 0], axis=1)
    assert np.ptp(chord) > 1e-7                        # u(L) != 0: the end point moves


def ritz_cantilever(modes, l1, l2, n_q=60):
    """First Ritz frequency and mode of two clamped beams welded in line (one plane, linear):
    w(x) = sum_i a_i (x / l1)^(i+2) on the first (the loaded-end modes' space, in the monomial
    basis), w1(l1) + w1'(l1) s + sum_k Y_k(s) zeta_k (clamped-free) on the second (s = x - l1).
    Returns omega_1 and [a, zeta]."""
    xg, wg = np.polynomial.legendre.leggauss(n_q)
    m = modes
    p = np.arange(2, m + 2)
    mass = np.zeros((2 * m, 2 * m))
    stiff = np.zeros((2 * m, 2 * m))
    x, wq = 0.5 * l1 * (xg + 1), 0.5 * l1 * wg
    y = (x[None] / l1) ** p[:, None]
    ddy = p[:, None] * (p[:, None] - 1) * (x[None] / l1) ** (p[:, None] - 2) / l1 ** 2
    mass[:m, :m] = MU * (y * wq) @ y.T
    stiff[:m, :m] = EI * (ddy * wq) @ ddy.T
    s, wq = 0.5 * l2 * (xg + 1), 0.5 * l2 * wg
    z, _, kf2 = shapes(CLAMPED, l2, m, s)
    basis = np.vstack([1.0 + (p[:, None] / l1) * s[None], z])      # t^p and its slope at t = 1
    mass += MU * (basis * wq) @ basis.T
    stiff[m:, m:] = EI * np.diag(kf2)
    val, vec = eigh(stiff, mass)
    return np.sqrt(val[0]), vec[:, 0]


def test_two_element_cantilever_first_frequency():
    """Two clamped beams (2 modes each: loaded-end modes, then clamped-free) welded in line,
    started in their first Ritz mode: the tip oscillates at that mode's frequency (computed
    here independently, in the monomial basis: this checks the weld's end-section coupling),
    which is close to the cantilever's 1.8751^2 sqrt(EI / (mu L^4)) (1.6e-5 high: the inboard
    beam's two polynomial modes hold the static deflection under the end loads exactly)."""
    modes, l1, l2 = 2, 0.5, 0.5
    omega_ritz, vec = ritz_cantilever(modes, l1, l2)
    # monomial amplitudes a -> the loaded-end modal coordinates: a = c eta, c read off the
    # element's shapes at two points
    t_pts = np.array([0.4, 0.9])
    y_el = mode_shapes(CLAMPED_LOADED, 1.0, modes, t_pts)[0]
    c = np.linalg.solve(t_pts[:, None] ** np.arange(2, modes + 2)[None], y_el.T)
    eta1 = np.linalg.solve(c, vec[:modes])
    y2 = shapes(CLAMPED, l2, modes, [l2])[0][:, 0]
    scale = 1e-4 / abs(vec[:modes] @ (1.0 + np.arange(2, modes + 2) / l1 * l2) + vec[modes:] @ y2)
    zero = np.zeros(modes)
    model = build_chain([FixedHinge(), beam(l1, modes, initial_modal_coordinates=np.concatenate(
                             [scale * eta1, zero])),
                         FixedHinge(), beam(l2, modes, initial_modal_coordinates=np.concatenate(
                             [scale * vec[modes:], zero]))], gravity=[0.0, 0.0, 0.0])
    assert list(model.beam_params[:, FAMILY]) == [CLAMPED_LOADED, CLAMPED]
    t = np.linspace(0.0, 0.6, 3001)
    res = simulate_reference(model, 0.6, rtol=1e-10, atol=1e-14, t_eval=t)
    tip = res.position_output[:, 1, 1]
    assert abs(abs(tip[0]) - 1e-4) < 1e-9
    omega = 2 * np.pi / dominant_period(t, tip)
    assert abs(omega / omega_ritz - 1) < 1e-7, (omega, omega_ritz)
    # a single mode: the tip amplitude neither grows nor leaks into other modes
    assert np.abs(tip - tip[0] * np.cos(omega_ritz * t)).max() < 1e-6 * abs(tip[0])
    exact = ROOTS[0] ** 2 * np.sqrt(EI / (MU * (l1 + l2) ** 4))
    assert 0.0 < omega / exact - 1 < 1e-4, (omega, exact)      # a Ritz value: from above


def test_clamped_beam_with_pinned_tip():
    """A beam clamped at the ground, its tip on a ball joint fixed in the world (tip="ball":
    loaded-end modes): the deflected end point r_O stays put, energy conserved."""
    model = build_chain([FixedHinge(), beam(1.0, 3, EI_SOFT,
                                            initial_modal_coordinates=[2e-3, 0, 0, 0, 1e-3, 0])],
                        gravity=[0.0, -G, 0.0], tip="ball")
    assert model.beam_params[0, FAMILY] == CLAMPED_LOADED
    res = simulate_reference(model, 0.5, rtol=1e-11, atol=1e-14)
    energy = energies(model, res)
    assert np.abs(energy - energy[0]).max() < 1e-9 * res.kinetic.max()      # 4e-12 measured
    r_o, _ = end_section(model, res, 0)
    assert np.abs(r_o - r_o[0]).max() < 1e-12
    assert np.abs(r_o[0, 1]) > 1e-3                   # held where the deflected tip started
    assert np.abs(res.modal_coordinates[:, 0] - 2e-3).max() > 1e-4


def test_elastic_hinge_at_beam_input():
    """A beam held by an elastic hinge at the ground (elastically clamped: loaded-end modes, as a
    block is welded to its end), swinging and bouncing under gravity: energy (with the hinge's
    springs) conserved, the weld holds."""
    # isotropic K_r: the hinge law -K_r psi is conservative only then (docs/hinges.md)
    k_t, k_r = np.diag([4e3, 3e3, 5e3]), 70.0 * np.eye(3)
    model = build_chain([ElasticHinge(translational_stiffness=k_t, rotational_stiffness=k_r),
                         beam(0.6, 2, EI_SOFT, initial_modal_coordinates=[1e-3, 0, 0, 5e-4],
                              angular_velocity=[0.5, 0.0, 1.0]),
                         FixedHinge(rotation=R_REL), tip_body()], gravity=[0.0, -G, 0.0])
    assert model.beam_params[0, FAMILY] == CLAMPED_LOADED
    res = simulate_reference(model, 1.0, rtol=1e-11, atol=1e-14,
                             t_eval=np.linspace(0.0, 1.0, 201))
    d = res.position_input[:, 0]                      # ground point at the origin, frame I
    psi = Rotation.from_matrix(res.rotation[:, 0]).as_rotvec()
    springs = 0.5 * (np.einsum("ti,ij,tj->t", d, k_t, d) + np.einsum("ti,ij,tj->t", psi, k_r, psi))
    energy = energies(model, res) + springs
    assert springs.max() > 1e-2 and res.kinetic.max() > 1e-1
    assert np.abs(energy - energy[0]).max() < 1e-9 * res.kinetic.max()      # 2e-12 measured
    check_weld(model, res, 0, R_REL)


# --------------------------------------------------------------------------------------------
# an elastic hinge at a beam's output: its inboard frame is the beam's end section
# --------------------------------------------------------------------------------------------

def beam_then_elastic(hinge, etad0=None, w=None):
    """A clamped beam (loaded-end modes: its output carries the hinge) deflected in both planes,
    `hinge` at its output, then the off-axis block."""
    return [FixedHinge(),
            beam(1.0, 2, EI_SOFT, initial_modal_coordinates=[3e-3, -3e-4, 2e-3, 2e-4],
                 initial_modal_velocities=etad0),
            hinge, tip_body(angular_velocity=w)]


def hinge_after_beam(model, res, k_t, k_r, r0):
    """Hinge 1 after beam 0, rebuilt with this file's end section (A_O, r_O): deflection d
    (world), psi with exp(psi^) = A_O^T A_1 R0^T, the spring force -A_O K_t A_O^T d, the spring
    couple -A_O K_r psi (world) and the spring energy (T,)."""
    r_o, a_o = end_section(model, res, 0)
    d = res.position_input[:, 1] - r_o
    d_b = np.einsum("tji,tj->ti", a_o, d)
    rel = np.einsum("tji,tjk,lk->til", a_o, res.rotation[:, 1], r0)
    psi = Rotation.from_matrix(rel).as_rotvec()
    force = -np.einsum("tij,jk,tk->ti", a_o, k_t, d_b)
    couple = -np.einsum("tij,jk,tk->ti", a_o, k_r, psi)
    energy = 0.5 * (np.einsum("ti,ij,tj->t", d_b, k_t, d_b)
                    + np.einsum("ti,ij,tj->t", psi, k_r, psi))
    return d, psi, force, couple, energy


@pytest.mark.parametrize("gravity, k_t", [([0.0, 0.0, 0.0], 3e3 * np.eye(3)),
                                          ([0.0, -G, 0.0], 3e3 * np.eye(3)),
                                          ([0.0, -G, 0.0], np.diag([2e3, 3e3, 5e3]))])
def test_elastic_hinge_at_beam_output_energy(gravity, k_t):
    """Beam -> elastic hinge (kinked rest rotation) -> block, the beam bending and the block
    spinning at t = 0: the hinge's springs act in the beam's END SECTION (A_O, w_O), its loads
    do modal work at O; total energy (this file's quadrature plus the springs in the end
    section's frame) conserved; the recorded hinge loads are the law in that frame.  The
    anisotropic K_t checks the couple d x q on the end section (isotropic K_t is central)."""
    k_r = 40.0 * np.eye(3)              # isotropic: the law -K_r psi is conservative only then
    model = build_chain(beam_then_elastic(
        ElasticHinge(translational_stiffness=k_t, rotational_stiffness=k_r, rotation=R_REL),
        etad0=[0.05, 0.0, -0.1, 0.0], w=[0.3, -0.5, 1.0]), gravity=gravity)
    assert model.beam_params[0, FAMILY] == CLAMPED_LOADED
    res = simulate_reference(model, 1.0, rtol=1e-11, atol=1e-14,
                             t_eval=np.linspace(0.0, 1.0, 201))
    d, psi, force, couple, springs = hinge_after_beam(model, res, k_t, k_r, R_REL)
    energy = energies(model, res) + springs
    assert res.kinetic.max() > 1e-2 and springs.max() > 1e-3          # J: 1.8e-3, 1.5e-2
    assert np.abs(psi).max() > 3e-3 and np.abs(d).max() > 5e-4
    drift = np.abs(energy - energy[0]).max() / res.kinetic.max()
    assert drift < 1e-9, drift                                     # 5e-14 to 1e-12 measured
    # chain_energies (dttmm.results.result) agrees: it too takes the end section as the inboard
    # frame
    assert np.abs(energy - res.total_energy).max() < 1e-12 * res.kinetic.max()
    scale_f, scale_m = np.abs(force).max(), np.abs(couple).max()
    assert np.abs(res.force[:, 1] - force).max() < 1e-9 * scale_f
    assert np.abs(res.moment[:, 1] - couple).max() < 1e-9 * scale_m
    # the end section's rotation is not the beam's frame here: the law in A would differ
    a = res.rotation[:, 0]
    rel_a = np.einsum("tji,tjk,lk->til", a, res.rotation[:, 1], R_REL)
    couple_a = -np.einsum("tij,jk,tk->ti", a, k_r, Rotation.from_matrix(rel_a).as_rotvec())
    assert np.abs(couple_a - couple).max() > scale_m                 # 5x to 25x measured


def test_stiff_elastic_hinge_at_beam_output_approaches_weld():
    """With springs of stiffness k the chain approaches the same chain with a fixed hinge (same
    rest rotation) at the beam's output, the gap shrinking like 1 / k (the hinge sags by ~ the
    end loads / k, and oscillates about that)."""
    t_end, t = 0.05, np.linspace(0.0, 0.05, 51)

    def run(hinge):
        model = build_chain(beam_then_elastic(hinge), gravity=[0.0, -G, 0.0])
        return model, simulate_reference(model, t_end, rtol=1e-9, atol=1e-12, t_eval=t)

    weld_model, weld = run(FixedHinge(rotation=R_REL))
    gaps = []
    for k in (1e7, 1e8):
        model, res = run(ElasticHinge(translational_stiffness=k, rotational_stiffness=1e-3 * k,
                                      rotation=R_REL))
        assert model.beam_params[0, FAMILY] == weld_model.beam_params[0, FAMILY]
        gaps.append((np.abs(res.position_output[:, 1] - weld.position_output[:, 1]).max(),
                     np.abs(res.rotation[:, 1] - weld.rotation[:, 1]).max(),
                     np.abs(res.modal_coordinates - weld.modal_coordinates).max()))
    gaps = np.array(gaps)
    ratio = gaps[0] / gaps[1]
    assert np.all((ratio > 7.0) & (ratio < 14.0)), (gaps, ratio)   # ~1 / k: 8.5-10.6 measured
    assert gaps[1, 0] < 1e-6 and gaps[1, 1] < 1e-5                 # 2.2e-7 m, 2.4e-6 at k = 1e8
    # ... against motion of the block and bending of the beam that are not small
    assert np.ptp(weld.position_output[:, 1, 1]) > 5e-3              # 1.6e-2 m
    assert np.ptp(weld.modal_coordinates, axis=0).max() > 1e-4


def test_damped_elastic_hinge_at_beam_output_dissipates():
    """Dampers in the elastic hinge after the beam (C_t, C_r on d' and w_1 - w_O): the total
    energy decreases at every sample, by a clear amount over the run."""
    k_t, k_r = 3e3 * np.eye(3), 40.0 * np.eye(3)
    model = build_chain(beam_then_elastic(
        ElasticHinge(translational_stiffness=k_t, rotational_stiffness=k_r,
                     translational_damping=10.0, rotational_damping=0.1, rotation=R_REL),
        etad0=[0.05, 0.0, -0.1, 0.0], w=[0.3, -0.5, 1.0]), gravity=[0.0, -G, 0.0])
    res = simulate_reference(model, 1.0, rtol=1e-11, atol=1e-14,
                             t_eval=np.linspace(0.0, 1.0, 401))
    energy = energies(model, res) + hinge_after_beam(model, res, k_t, k_r, R_REL)[4]
    scale = res.kinetic.max()
    assert np.abs(energy - res.total_energy).max() < 1e-12 * scale
    assert np.diff(energy).max() < 0.0, np.diff(energy).max() / scale     # -8e-8 measured
    assert energy[0] - energy[-1] > 5e-3 * scale                          # 1.6e-2 measured
