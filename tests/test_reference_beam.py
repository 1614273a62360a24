"""Tests of the Newton-Euler reference solver's Euler-Bernoulli beam (docs/beam.md) against results
it does not compute itself: conservation laws (energies and momenta evaluated by quadrature, not
from the solver's analytic moments), the rigid limit, closed-form modal responses of a beam whose
chord is held still, and convergence in the number of modes."""
import numpy as np
import pytest

from dttmm import BallJoint, EulerBernoulliBeam, RigidBody, build_chain
from dttmm.elements import BEAM, RIGID
from dttmm.reference import simulate_reference
from dttmm.results.result import _GL_W, _GL_X, beam_midpoint_deflection, chain_energies

G = 9.81
MU, L = 1.32, 1.0
EI = 2.5e10 * (0.02 ** 4 / 12)          # 333.3 N m^2: the paper's beam, omega_1 = 156.8 rad/s
JP = 1.32 * 0.02 ** 2 / 6               # polar mass moment per length of the 2 cm square section
GRAVITY = np.array([0.0, -G, 0.0])


def link(**kw):
    return RigidBody(mass=1.0, inertia=np.diag([1 / 6, 5 / 12, 5 / 12]), inertia_about="input",
                     to_mass_center=[0.5, 0, 0], to_output=[1, 0, 0], **kw)


def beam(modes=3, ei=EI, **kw):
    # the paper's beam (no geometric stiffening): this file's closed-form responses and
    # quadrature energies are the unstiffened beam's (tests/test_stiffening.py has its own)
    kw.setdefault("stiffening", False)
    return EulerBernoulliBeam(length=L, mass_per_length=MU, bending_stiffness=ei,
                              polar_inertia_per_length=JP, modes_per_plane=modes, **kw)


def three_pendulum(middle, first=None):
    """The paper's three-pendulum: link, ball joint, `middle`, ball joint, link spinning at
    [0, 0.1, 0]; root ball joint at the origin, all along +x, gravity -9.81 e_y."""
    return build_chain([BallJoint(), first or link(), BallJoint(), middle, BallJoint(),
                        link(angular_velocity=[0, 0.1, 0])], gravity=GRAVITY)


def modal_constants(modes, ei, zeta=0.0):
    """Modal stiffness, mass, frequency, damping and int Y_k of one plane (docs/beam.md)."""
    k = np.arange(1, modes + 1)
    stiff = ei * (k * np.pi / L) ** 4 * L / 2
    mass = MU * L / 2
    omega = (k * np.pi / L) ** 2 * np.sqrt(ei / MU)
    int_y = L * (1 - (-1.0) ** k) / (k * np.pi)
    return stiff, mass, omega, 2 * zeta * omega * mass, int_y


def beam_fields(model, res, body):
    """Positions r(x) and velocities r'(x) of a beam's sections at the quadrature points, shape
    (T, Q, 3), built from the recorded frame state and modal coordinates alone; and the weights."""
    nm = int(model.n_modes[body]) // 2
    off = int(np.sum(model.n_modes[:body]))
    x = 0.5 * L * (_GL_X + 1)
    wq = 0.5 * L * _GL_W
    y = np.sin(np.outer(x, np.arange(1, nm + 1)) * np.pi / L)
    eta = res.modal_coordinates[:, off:off + 2 * nm]
    eta_dot = res.modal_velocities[:, off:off + 2 * nm]
    p = np.zeros((len(res.t), len(x), 3))
    p[..., 0] = x
    p[..., 1] = eta[:, :nm] @ y.T
    p[..., 2] = eta[:, nm:] @ y.T
    u_dot = np.zeros_like(p)
    u_dot[..., 1] = eta_dot[:, :nm] @ y.T
    u_dot[..., 2] = eta_dot[:, nm:] @ y.T
    rot = res.rotation[:, body]
    rho = np.einsum("tij,tqj->tqi", rot, p)
    w = res.angular_velocity[:, body][:, None, :]
    r = res.position_input[:, body][:, None, :] + rho
    v = (res.velocity_input[:, body][:, None, :] + np.cross(w, rho)
         + np.einsum("tij,tqj->tqi", rot, u_dot))
    return r, v, wq


def foreshortening_fields(model, res, body):
    """The foreshortening's displacement -c(x) A e1 and velocity -c(x) w x A e1 - c'(x) A e1
    at the quadrature points (T, Q, 3), c(x) = 1/2 int_0^x (v'^2 + w'^2) (docs/beam.md,
    "Geometric stiffening"), each c(x) by a 40-point rule on [0, x] of the sine modes'
    slopes."""
    nm = int(model.n_modes[body]) // 2
    off = int(np.sum(model.n_modes[:body]))
    eta = res.modal_coordinates[:, off:off + 2 * nm]
    eta_dot = res.modal_velocities[:, off:off + 2 * nm]
    x = 0.5 * L * (_GL_X + 1)
    t, wt = np.polynomial.legendre.leggauss(40)
    c, c_dot = np.zeros((len(res.t), len(x))), np.zeros((len(res.t), len(x)))
    k = np.arange(1, nm + 1)
    for i, xi in enumerate(x):
        xs, ws = 0.5 * xi * (t + 1), 0.5 * xi * wt
        slope = (k * np.pi / L) * np.cos(np.outer(xs, k) * np.pi / L)          # (40, nm)
        for plane in range(2):
            sl = eta[:, plane * nm:(plane + 1) * nm] @ slope.T
            sd = eta_dot[:, plane * nm:(plane + 1) * nm] @ slope.T
            c[:, i] += 0.5 * (sl * sl) @ ws
            c_dot[:, i] += (sl * sd) @ ws
    e1 = res.rotation[:, body, :, 0][:, None, :]
    w = res.angular_velocity[:, body][:, None, :]
    return -c[..., None] * e1, -c[..., None] * np.cross(w, e1) - c_dot[..., None] * e1


def angular_momentum_about(model, res, point):
    """(T, 3) angular momentum of a chain of rigid bodies and beams about a fixed point; a
    beam's foreshortening counts to first order in c (its products with the rigid x e1 only,
    as the energies: docs/beam.md, "Geometric stiffening")."""
    h = np.zeros((len(res.t), 3))
    for k in range(model.n_bodies):
        a = res.rotation[:, k]
        w = res.angular_velocity[:, k]
        if model.body_kind[k] == BEAM:
            r, v, wq = beam_fields(model, res, k)
            h += MU * np.einsum("q,tqi->ti", wq, np.cross(r - point, v))
            if model.beam_params[k, 8]:
                d, d_dot = foreshortening_fields(model, res, k)
                x = 0.5 * L * (_GL_X + 1)
                rho0 = x[None, :, None] * a[:, None, :, 0]                     # A x e1
                r0 = res.position_input[:, k][:, None, :] + rho0
                v0 = res.velocity_input[:, k][:, None, :] + np.cross(w[:, None, :], rho0)
                h += MU * np.einsum("q,tqi->ti", wq, np.cross(r0 - point, d_dot)
                                    + np.cross(d, v0))
            e1 = a[:, :, 0]                     # polar spin: J_p,w w = j_p L (w . A e1) A e1
            h += JP * L * np.einsum("ti,ti->t", w, e1)[:, None] * e1
        else:
            mass = model.body_params[k, 0]
            r_c = res.position_mass_center[:, k]
            v_c = res.velocity_input[:, k] + np.cross(w, r_c - res.position_input[:, k])
            j_w = a @ model.body_mass_center_inertia[k] @ np.swapaxes(a, 1, 2)
            h += mass * np.cross(r_c - point, v_c) + np.einsum("tij,tj->ti", j_w, w)
    return h


@pytest.fixture(scope="module")
def pendulum_runs():
    """The three-pendulum with 1, 3 and 5 modes per plane, over 1 s; its beam with geometric
    stiffening (docs/beam.md: the energies and the angular momentum count the foreshortening)."""
    t = np.linspace(0.0, 1.0, 401)
    out = {}
    for modes in (1, 3, 5):
        model = three_pendulum(beam(modes, stiffening=True))
        out[modes] = model, simulate_reference(model, 1.0, rtol=1e-10, atol=1e-12, t_eval=t)
    return out


# --------------------------------------------------------------------------------------------
# the quadrature the energies use
# --------------------------------------------------------------------------------------------

def test_energy_quadrature_is_exact_for_ten_modes():
    """The 64-point Gauss-Legendre rule of dttmm.results.result integrates the products of modes
    (times 1, x, x^2) that |r'(x)|^2 and g . r(x) contain, for up to 10 modes, to round-off."""
    x = 0.5 * L * (_GL_X + 1)
    wq = 0.5 * L * _GL_W
    k = np.arange(1, 11)
    y = np.sin(np.outer(x, k) * np.pi / L)
    assert np.abs(wq @ y - L * (1 - (-1.0) ** k) / (k * np.pi)).max() < 1e-14
    assert np.abs(wq @ (x[:, None] * y) + L ** 2 * (-1.0) ** k / (k * np.pi)).max() < 1e-14
    assert np.abs(np.einsum("q,qj,qk->jk", wq, y, y) - L / 2 * np.eye(10)).max() < 1e-14
    # x^2 Y_j Y_k, the hardest term of |w x rho|^2 (closed form by a 4000-point Simpson rule)
    xs = np.linspace(0.0, L, 4001)
    ys = np.sin(np.outer(xs, k) * np.pi / L)
    f = xs[:, None, None] ** 2 * ys[:, :, None] * ys[:, None, :]
    simpson = (xs[1] - xs[0]) / 3 * (f[0] + f[-1] + 4 * f[1:-1:2].sum(0) + 2 * f[2:-1:2].sum(0))
    gl = np.einsum("q,qj,qk->jk", wq * x ** 2, y, y)
    assert np.abs(gl - simpson).max() < 1e-10          # Simpson's own error, ~1e-11


# --------------------------------------------------------------------------------------------
# the paper's three-pendulum with a flexible middle body
# --------------------------------------------------------------------------------------------

def test_three_pendulum_energy_conserved(pendulum_runs):
    for modes, (model, res) in pendulum_runs.items():
        energy = res.total_energy
        scale = res.kinetic.max()
        assert scale > 10.0
        assert np.abs(energy - energy[0]).max() / scale < 1e-10, modes
        assert res.potential.min() < res.potential[0] - 10.0


def test_three_pendulum_vertical_angular_momentum(pendulum_runs):
    model, res = pendulum_runs[3]
    h = angular_momentum_about(model, res, np.zeros(3))
    assert abs(h[0, 1] - (0.1 / 6 + 2.5 * 0.05)) < 1e-12     # the spinning tip link's
    assert np.abs(h[:, 1] - h[0, 1]).max() < 1e-10 * abs(h[0, 1])
    assert np.abs(h[:, 2]).max() > 1.0                      # a 3-D motion: h_z does change


def test_three_pendulum_joints_and_mass_centre(pendulum_runs):
    model, res = pendulum_runs[3]
    gap = np.linalg.norm(res.position_output[:, :-1] - res.position_input[:, 1:], axis=-1)
    assert gap.max() < 1e-9
    # the pinned beam's chord: L less the foreshortening c(L) = pi^2 / (4 L) sum k^2 eta_k^2
    # (the sine modes' slopes are orthogonal; docs/beam.md, "Geometric stiffening")
    chord = res.position_output[:, 1] - res.position_input[:, 1]
    k = np.arange(1, 4)
    eta = res.modal_coordinates[:, :6]
    c_l = np.pi ** 2 / (4 * L) * (eta[:, :3] ** 2 + eta[:, 3:] ** 2) @ k ** 2
    assert c_l.max() > 1e-7
    assert np.abs(np.linalg.norm(chord, axis=-1) - (L - c_l)).max() < 1e-12
    # the recorded mass centre of the beam is the mean of its deflected sections
    r, _, wq = beam_fields(model, res, 1)
    r = r + foreshortening_fields(model, res, 1)[0]
    assert np.abs(np.einsum("q,tqi->ti", wq, r) / L - res.position_mass_center[:, 1]).max() < 1e-13
    assert np.abs(res.moment).max() == 0.0


def test_three_pendulum_deflection_converges(pendulum_runs):
    """Mid-span deflection of the beam: of order 1e-3 m in the plane of the fall, much smaller out
    of it (the tip link's small spin), and converging with the number of modes per plane."""
    d = {m: beam_midpoint_deflection(model, res, 1) for m, (model, res) in pendulum_runs.items()}
    peak = np.abs(d[5]).max(axis=0)
    assert 3e-4 < peak[0] < 3e-3
    assert 1e-6 < peak[1] < 0.1 * peak[0]
    diff13 = np.abs(d[1] - d[3]).max()
    diff35 = np.abs(d[3] - d[5]).max()
    assert diff35 < 0.3 * diff13
    assert diff13 < 0.05 * peak[0]
    # the modal coordinates are recorded for every body in order: the beam's only
    for modes, (model, res) in pendulum_runs.items():
        assert res.modal_coordinates.shape == res.modal_velocities.shape == (len(res.t), 2 * modes)
        assert list(model.body_kind) == [RIGID, BEAM, RIGID]
        assert np.all(res.modal_coordinates[0] == 0) and np.all(res.modal_velocities[0] == 0)


@pytest.mark.parametrize("scale", [1e2, 1e3])
def test_stiff_beam_matches_rigid_body(scale):
    """A stiff beam moves like the rigid body with its mass and inertia about the input point,
    diag(j_p L, mu L^3 / 3, mu L^3 / 3); the difference falls like 1 / EI.  (EI x 1e6 would need
    ~4e6 right-hand sides of the explicit integrator for its 1.6e5 rad/s mode; the measured trend
    4.4e-6 m at x100, 4.4e-7 m at x1000 extrapolates to ~4e-10 m there.)"""
    rigid = RigidBody(mass=MU * L, inertia=np.diag([JP * L, MU * L ** 3 / 3, MU * L ** 3 / 3]),
                      inertia_about="input", to_mass_center=[L / 2, 0, 0], to_output=[L, 0, 0])
    t = np.linspace(0.0, 1.0, 101)
    rb = simulate_reference(three_pendulum(beam(1, ei=EI * scale)), 1.0, rtol=1e-10, atol=1e-12,
                            t_eval=t)
    rr = simulate_reference(three_pendulum(rigid), 1.0, rtol=1e-10, atol=1e-12, t_eval=t)
    diff = np.abs(rb.position_output - rr.position_output).max()
    assert diff < 1e-3 / scale               # ~4.4e-4 / scale measured
    assert diff > 1e-5 / scale               # ... and really from the flexibility
    assert np.abs(rb.total_energy - rr.total_energy).max() < 1e-2 / scale
    assert np.abs(rb.position_output[-1] - rb.position_output[0]).max() > 0.5    # it did fall


def test_soft_beam_energy_and_damping():
    """A soft beam (EI / 100, deflections of a few cm, EI_v != EI_w) in a tumbling chain: the
    terms of second order in eta matter, and energy is still conserved; modal damping only
    dissipates."""
    def chain(zeta):
        b = beam(2, ei=[EI / 100, EI / 140], damping_ratio=zeta,
                 angular_velocity=[2.0, 0.5, -0.3])
        return three_pendulum(b, first=link(angular_velocity=[0.3, 0.0, 0.5]))
    model = chain(0.0)
    res = simulate_reference(model, 1.0, rtol=1e-10, atol=1e-12)
    d = beam_midpoint_deflection(model, res, 1)
    assert np.abs(d).max() > 0.01
    assert np.abs(d[:, 1]).max() > 1e-3
    scale = res.kinetic.max()
    assert np.abs(res.total_energy - res.total_energy[0]).max() / scale < 1e-9
    h = angular_momentum_about(model, res, np.zeros(3))[:, 1]
    assert np.abs(h - h[0]).max() < 1e-9 * np.abs(h).max()
    damped = simulate_reference(chain(0.05), 1.0, rtol=1e-10, atol=1e-12)
    e = damped.total_energy
    assert np.all(np.diff(e) <= 1e-9 * scale) and e[-1] < e[0] - 1e-3 * scale


# --------------------------------------------------------------------------------------------
# a beam with its chord held still: closed-form modal responses
# --------------------------------------------------------------------------------------------

def pinned_beam(gravity, modes=3, ei=EI, zeta=0.0, spin=0.0):
    """Beam along +x between a ball joint at the origin and a ball joint to a 1e8 kg anchor whose
    weight is cancelled by an applied force: the anchor moves by ~3e-10 m, so the beam is
    pinned-pinned and only its own weight loads it."""
    g = np.asarray(gravity, float)
    heavy = 1e8
    anchor = RigidBody(mass=heavy, inertia=0.01 * heavy, inertia_about="mass_center",
                       to_output=[0.1, 0, 0], force=lambda t: -heavy * g)
    return build_chain([BallJoint(), beam(modes, ei=ei, damping_ratio=zeta,
                                          angular_velocity=[spin, 0, 0]), BallJoint(), anchor],
                       gravity=g)


@pytest.mark.parametrize("plane, zeta", [(0, 0.0), (1, 0.0), (1, 0.05)])
def test_pinned_beam_modal_step_response(plane, zeta):
    """Weight switched on at rest: each mode is a damped oscillator of the analytic frequency
    omega_k and damping c_k, stepped from 0 to the static value eta_s,k = mu g int Y_k / k_k:
        eta(t) = eta_s (1 - exp(-zeta omega t) (cos omega_d t
                                                + zeta / sqrt(1 - zeta^2) sin omega_d t)).
    Gravity along -y loads the v plane (EI_v), along -z the w plane (EI_w)."""
    ei = np.array([EI, 2.0 * EI])
    g = np.zeros(3)
    g[1 + plane] = -G
    model = pinned_beam(g, modes=3, ei=ei, zeta=zeta)
    t = np.linspace(0.0, 0.1, 401)
    res = simulate_reference(model, 0.1, rtol=1e-10, atol=1e-14, t_eval=t)
    stiff, _, omega, _, int_y = modal_constants(3, ei[plane], zeta)
    eta_s = MU * int_y * (-G) / stiff
    wd = omega * np.sqrt(1 - zeta ** 2)
    tt = t[:, None]
    expected = eta_s * (1 - np.exp(-zeta * omega * tt) * (np.cos(wd * tt)
                                                          + zeta / np.sqrt(1 - zeta ** 2)
                                                          * np.sin(wd * tt)))
    eta = res.modal_coordinates
    assert np.abs(eta[:, 3 * plane:3 * plane + 3] - expected).max() < 1e-6 * np.abs(eta_s).max()
    assert np.abs(eta[:, 3 * (1 - plane):3 * (2 - plane)]).max() < 1e-12 * np.abs(eta_s).max()
    assert abs(eta[:, 3 * plane].max() - eta[:, 3 * plane].min()) > 1.5 * abs(eta_s[0])
    # the frame and the anchor stay put
    assert np.abs(res.position_output[:, 0] - [L, 0, 0]).max() < 1e-8
    assert np.abs(res.angular_velocity[:, 0]).max() < 1e-6


def test_pinned_beam_spinning_about_its_chord():
    """The same beam spinning about its chord at 60 rad/s (0.4 omega_1): with EI_v = EI_w and
    no section inertia, the world-frame deflection does not feel the spin, so the mid-span
    deflection is still sum_k eta_s,k sin(k pi / 2) (1 - cos omega_k t) in the plane of gravity
    and zero out of it.  In the body frame this takes the Coriolis and centrifugal terms and the
    spin exchange between frame and modes."""
    model = pinned_beam([0, -G, 0], modes=3, spin=60.0)
    t = np.linspace(0.0, 0.1, 401)
    res = simulate_reference(model, 0.1, rtol=1e-10, atol=1e-14, t_eval=t)
    stiff, _, omega, _, int_y = modal_constants(3, EI)
    eta_s = MU * int_y * (-G) / stiff
    mid = np.sin(np.arange(1, 4) * np.pi / 2)
    expected = (eta_s * mid * (1 - np.cos(omega * t[:, None]))).sum(1)
    d = beam_midpoint_deflection(model, res, 0)
    assert np.abs(d[:, 0] - expected).max() < 1e-6 * np.abs(expected).max()
    assert np.abs(d[:, 1]).max() < 1e-9 * np.abs(expected).max()
    # in the body frame the deflection really does turn between the planes
    assert np.abs(res.modal_coordinates[:, 3]).max() > 0.5 * np.abs(expected).max()
    assert np.abs(res.angular_velocity[:, 0, 0] - 60.0).max() < 1e-6


def test_pinned_beam_static_sag():
    """Heavily damped (zeta = 0.3), the beam settles to its static sag; with 5 modes per plane
    the mid-span deflection is the truncated series sum_k odd 4 mu g L^4 / (EI pi^5 k^5) (-1)^j,
    within 6e-5 of the exact pinned-pinned 5 mu g L^4 / (384 EI)."""
    model = pinned_beam([0, -G, 0], modes=5, zeta=0.3)
    res = simulate_reference(model, 0.6, rtol=1e-10, atol=1e-14, t_eval=np.linspace(0, 0.6, 61))
    d = beam_midpoint_deflection(model, res, 0)[-1]
    k = np.arange(1, 6, 2)
    series = -np.sum(4 * MU * G * L ** 4 / (EI * np.pi ** 5 * k ** 5) * np.sin(k * np.pi / 2))
    exact = -5 * MU * G * L ** 4 / (384 * EI)
    assert abs(d[0] - series) < 1e-8 * abs(series)
    assert abs(d[0] / exact - 1) < 1e-4
    assert abs(d[1]) < 1e-15
    # settled: every mode at its static value mu g int Y_k / k_k, at rest
    stiff, _, _, _, int_y = modal_constants(5, EI)
    assert np.abs(res.modal_coordinates[-1, :5] + MU * G * int_y / stiff).max() < 1e-8 * abs(exact)
    assert np.abs(res.modal_velocities[-1]).max() < 1e-6 * abs(exact)


# --------------------------------------------------------------------------------------------
# tip joined to the ground (build_chain(tip="ball"))
# --------------------------------------------------------------------------------------------

def test_simply_supported_beam_equals_heavy_anchor():
    """tip="ball" holds the tip at a fixed point: the simply supported beam moves as the beam
    pinned to the 1e8 kg anchor, and carries half its weight at each end once settled."""
    t = np.linspace(0.0, 0.1, 401)
    anchored = simulate_reference(pinned_beam(GRAVITY, modes=3), 0.1, rtol=1e-10, atol=1e-14,
                                  t_eval=t)
    model = build_chain([BallJoint(), beam(3)], gravity=GRAVITY, tip="ball")
    res = simulate_reference(model, 0.1, rtol=1e-10, atol=1e-14, t_eval=t)
    scale = np.abs(anchored.modal_coordinates).max()
    assert np.abs(res.modal_coordinates - anchored.modal_coordinates).max() < 1e-7 * scale
    assert np.abs(res.force[:, 0] - anchored.force[:, 0]).max() < 1e-6
    assert np.abs(res.position_output[:, 0] - [L, 0, 0]).max() < 1e-12
    damped = simulate_reference(
        build_chain([BallJoint(), beam(3, damping_ratio=0.3)], gravity=GRAVITY, tip="ball"), 0.6,
        rtol=1e-10, atol=1e-14, t_eval=np.linspace(0.0, 0.6, 7))
    assert np.abs(damped.force[-1, 0] - [0, MU * L * G / 2, 0]).max() < 1e-8


def test_closed_chain_with_beam_conserves_energy():
    """Link, beam, link between two fixed points (a closed loop, not straight): energy is
    conserved and the tip stays where it started."""
    def rz(angle):
        c, s = np.cos(angle), np.sin(angle)
        return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    model = build_chain([BallJoint(), link(rotation=rz(0.5)), BallJoint(),
                         beam(2, rotation=rz(-0.5)), BallJoint(), link(rotation=rz(-0.3))],
                        gravity=GRAVITY, tip="ball")
    res = simulate_reference(model, 1.0, rtol=1e-10, atol=1e-12)
    assert res.kinetic.max() > 5.0
    assert np.abs(res.total_energy - res.total_energy[0]).max() < 1e-10 * res.kinetic.max()
    assert np.abs(res.position_output[:, 2] - res.position_output[0, 2]).max() < 1e-10
    gap = np.linalg.norm(res.position_output[:, :-1] - res.position_input[:, 1:], axis=-1)
    assert gap.max() < 1e-10


def test_straight_chain_between_fixed_points_least_tip_force():
    """A straight chain between two fixed points under gravity along it: the load split between
    the ends is indeterminate; the reference takes the least tip force (zero), so the root
    carries the whole weight; nothing moves."""
    model = build_chain([BallJoint(), link(), BallJoint(), beam(2), BallJoint(), link()],
                        gravity=[-G, 0, 0], tip="ball")
    res = simulate_reference(model, 0.2, t_eval=np.linspace(0, 0.2, 11))
    weight = (2.0 + MU * L) * G
    assert np.abs(res.force[:, 0] - [weight, 0, 0]).max() < 1e-9
    assert np.abs(res.force[:, 2] - [1.0 * G, 0, 0]).max() < 1e-9    # the tip link hangs on it
    assert np.abs(res.angular_velocity).max() < 1e-9                # round-off only
    assert np.abs(res.modal_coordinates).max() < 1e-12


def test_a_tip_joint_that_the_start_moves_is_assembled_first():
    """The initial rates move the pinned tip (the last link turns at 0.1 rad/s about z): the
    reference assembles the loop before the run (dttmm.assemble; until stop 29 it refused), and
    the tip then rests on its pin.  (A straight chain between its pins could not move at all:
    its tip's pin holds it at second order, which the rates' projection does not see.)"""
    down = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    model = build_chain([BallJoint(), link(), BallJoint(), beam(1), BallJoint(),
                         link(angular_velocity=[0, 0, 0.1], rotation=down)], tip="ball")
    res = simulate_reference(model, 0.1, t_eval=[0.0, 0.05, 0.1])
    before, after = res.info["assembly"]["before"], res.info["assembly"]["after"]
    assert before[0] < 1e-15 and abs(before[1] - 0.1) < 1e-12      # m, m/s
    assert max(after) < 1e-14
    assert np.abs(res.position_output[:, -1] - res.position_output[0, -1]).max() < 1e-10


# --------------------------------------------------------------------------------------------
# result helpers
# --------------------------------------------------------------------------------------------

def test_chain_energies_of_a_deflected_beam():
    """chain_energies against hand-made values: a beam along +x at rest with eta_v,1 = e, no
    gravity: potential = k_1 e^2 / 2; moving with velocity v and eta_w,2' = r:
    kinetic = mu L |v|^2 / 2 + (mu L / 2) r^2 / 2 + mu v_z r int Y_2 (= 0)."""
    model = build_chain([BallJoint(), beam(2, ei=[EI, 3 * EI])], gravity=[0, 0, 0])
    stiff, _, _, _, _ = modal_constants(2, EI)
    rot, omega, r_in = np.eye(3)[None], np.zeros((1, 3)), np.zeros((1, 3))
    kin, pot = chain_energies(model, rot, omega, r_in, np.zeros((1, 3)), np.zeros((1, 3)),
                              eta=[0.01, 0, 0, 0], eta_dot=[0, 0, 0, 0])
    assert kin == 0 and abs(pot - 0.5 * stiff[0] * 1e-4) < 1e-12 * pot
    v = np.array([[0.3, -0.2, 0.5]])
    kin, pot = chain_energies(model, rot, omega, r_in, v, np.zeros((1, 3)),
                              eta=[0, 0, 0, 0.02], eta_dot=[0, 0, 0, 0.7])
    assert abs(kin - (0.5 * MU * L * v[0] @ v[0] + 0.25 * MU * L * 0.49)) < 1e-14
    assert abs(pot - 0.5 * 3 * stiff[1] * 4e-4) < 1e-12 * pot
    with pytest.raises(ValueError, match="eta"):
        chain_energies(model, rot, omega, r_in, v, np.zeros((1, 3)), eta=[0.0])


def test_midpoint_deflection_helper_errors(pendulum_runs):
    model, res = pendulum_runs[1]
    with pytest.raises(ValueError, match="not an EulerBernoulliBeam"):
        beam_midpoint_deflection(model, res, 0)
    rigid = simulate_reference(three_pendulum(link()), 0.01)
    assert rigid.modal_coordinates is None and rigid.modal_velocities is None
