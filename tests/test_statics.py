"""Static equilibrium (dttmm/solving/statics.py, docs/statics.md) against analytic answers: a
pendulum hanging and its small-vibration frequency, the elastica rolled up by a tip moment (and
its convergence order in the number of elements), Euler's buckling load; and the errors."""
import warnings

import numpy as np
import pytest

import dttmm
from dttmm.model import chains

EI = 100.0          # N m^2: the cantilever (L = 1 m)


def rod(**kwargs):
    return dttmm.RigidBody(mass=1.0, inertia=[1e-4, 1 / 12, 1 / 12], inertia_about="mass_center",
                           to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0], **kwargs)


def cantilever(n_elements, tip_force=None, tip_torque=None, modes=2, length=1.0):
    """n welded stiffened beam elements clamped to the ground along x, a light tip body welded
    to the end carrying the loads (no gravity)."""
    elements = []
    for _ in range(n_elements):
        elements += [dttmm.FixedHinge(),
                     dttmm.EulerBernoulliBeam(length=length / n_elements, bending_stiffness=EI,
                                              polar_inertia_per_length=1e-4, mass_per_length=1.0,
                                              modes_per_plane=modes, stiffening=True)]
    elements += [dttmm.FixedHinge(),
                 dttmm.RigidBody(mass=1.0, inertia=[1e-2] * 3, inertia_about="mass_center",
                                 to_mass_center=[0, 0, 0], to_output=[0, 0, 0],
                                 force=None if tip_force is None else lambda t: tip_force,
                                 torque=None if tip_torque is None else lambda t: tip_torque)]
    return dttmm.build_chain(elements, gravity=(0.0, 0.0, 0.0))


def test_pendulum_hangs_and_its_frequency_is_analytic():
    """From horizontal (where gravity does not stiffen it at all) to hanging straight down;
    the swing's squared frequency m g l / I_pivot = 9.81 * 0.5 / (1/3) in both planes, the
    spin about the vertical neutral."""
    eq = dttmm.static_equilibrium(dttmm.build_chain([dttmm.BallJoint(), rod()]))
    axis = eq.model.initial_rotation[0] @ [1.0, 0.0, 0.0]
    assert np.allclose(axis, [0.0, -1.0, 0.0], atol=1e-9)
    assert eq.stable
    assert eq.squared_frequencies[0] == 0.0
    assert np.allclose(eq.squared_frequencies[1:], 9.81 * 0.5 * 3.0, rtol=1e-6)
    r_in, r_c, r_o = eq.positions()
    assert np.allclose(r_o[0], [0.0, -1.0, 0.0], atol=1e-9)


def test_a_run_from_the_equilibrium_stays_at_rest():
    """The three-pendulum's hanging equilibrium (13 coordinates, beam modes included) is a
    state of rest of the dynamics too: 0.5 s of DT-TMM moves nothing by more than 1e-9 m."""
    eq = dttmm.static_equilibrium(chains.three_pendulum())
    assert eq.stable and eq.residual < 1e-8
    res = dttmm.simulate(eq.model, 0.5, 1e-3)
    drift = np.abs(res.position_output - res.position_output[0]).max()
    assert drift < 1e-9, drift


@pytest.mark.parametrize("lam", [0.25, 0.5])
def test_elastica_tip_and_order(lam):
    """A cantilever rolled up by a tip moment M = lam 2 pi EI / L (phi = M L / EI = pi / 2 and
    pi): the tip within 1e-3 L of (L sin phi / phi, L (1 - cos phi) / phi) with 16 elements,
    and the error falls as K^-p with p ~ 3 (measured 3.0: 2.3e-3, 2.8e-4, 3.6e-5 at pi / 2;
    1.3e-2, 1.6e-3, 2.0e-4 at pi; each stiffened element carries its arc to third order)."""
    phi = lam * 2.0 * np.pi
    exact = np.array([np.sin(phi) / phi, (1.0 - np.cos(phi)) / phi, 0.0])
    errors = []
    counts = (4, 8, 16) if lam < 0.5 else (8, 16)
    for k in counts:
        guess = None
        for step in np.linspace(0.25, lam, int(round(lam / 0.25))):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                guess = dttmm.static_equilibrium(
                    cantilever(k, tip_torque=[0.0, 0.0, step * 2.0 * np.pi * EI]), guess=guess)
        errors.append(np.linalg.norm(guess.positions()[2][-1] - exact))
    assert errors[-1] < 1e-3, errors
    order = -np.polyfit(np.log(counts), np.log(errors), 1)[0]
    assert 2.7 < order < 3.3, (order, errors)


def test_elastica_closes_into_a_circle():
    """M = 2 pi EI / L (phi = 2 pi), 16 elements, the load in quarter turns: the tip back at
    the root (the analytic (L sin phi / phi, L (1 - cos phi) / phi) = 0) within 1e-3 L, and,
    since that point alone is fixed by symmetry, every centre-line point within 1e-3 L of the
    circle of radius L / (2 pi) through the root (measured: tip 1.3e-8 m, centre line 5.2e-4
    m)."""
    guess = None
    for step in (0.25, 0.5, 0.75, 1.0):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            guess = dttmm.static_equilibrium(
                cantilever(16, tip_torque=[0.0, 0.0, step * 2.0 * np.pi * EI]), guess=guess)
    assert np.linalg.norm(guess.positions()[2][-1]) < 1e-3
    radius = 1.0 / (2.0 * np.pi)
    points = np.concatenate(guess.centreline())
    off_circle = np.abs(np.linalg.norm(points - [0.0, radius, 0.0], axis=1) - radius)
    assert off_circle.max() < 1e-3, off_circle.max()
    assert np.ptp(points[:, 1]) > 1.9 * radius       # it went round, not stayed straight


def _column(load, on):
    """A clamped-free column along x, compressed at its tip by `load` N: through a tip body
    (cantilever) or as the beam's own end force (docs/beam.md, "Loads on the beam")."""
    if on == "tip body":
        return cantilever(1, tip_force=[-load, 0, 0], modes=4)
    return dttmm.build_chain([dttmm.FixedHinge(), dttmm.EulerBernoulliBeam(
        length=1.0, bending_stiffness=EI, polar_inertia_per_length=1e-4, mass_per_length=1.0,
        modes_per_plane=4, stiffening=True, end_force=lambda t: [-load, 0.0, 0.0])],
        gravity=(0.0, 0.0, 0.0))


@pytest.mark.parametrize("on", ["tip body", "end force"])
def test_euler_buckling(on):
    """A clamped-free column under a compressive tip load: stable just below pi^2 EI / (4 L^2),
    flagged (warning, stable False) just above; the lowest squared frequency crosses zero
    there, linear in the load."""
    p_cr = np.pi ** 2 * EI / 4.0
    below = dttmm.static_equilibrium(_column(0.97 * p_cr, on))
    assert below.stable
    with pytest.warns(UserWarning, match="unstable"):
        above = dttmm.static_equilibrium(_column(1.03 * p_cr, on))
    assert not above.stable
    # the lowest squared frequency is linear in the load: its zero is the buckling load
    lo, hi = below.squared_frequencies[0], above.squared_frequencies[0]
    crossing = 0.97 + (1.03 - 0.97) * lo / (lo - hi)
    assert abs(crossing - 1.0) < 2e-3, crossing


def test_spring_loaded_revolute_link_is_analytic():
    """A link on a revolute joint about z with a torsional spring (k = 15 N m/rad, rest 0),
    under gravity -y: k theta + m g l_c cos theta = 0 (solved by brentq), and the squared
    frequency (k - m g l_c sin theta) / I_pivot of the small swing; the joint coordinate is a
    coordinate of the solve (measured: the angle to 1e-14 rad)."""
    from scipy.optimize import brentq
    mass, l_c, i_c, k = 2.0, 0.5, 1.0 / 6.0, 15.0
    link = dttmm.RigidBody(mass=mass, inertia=[1e-3, i_c, i_c], inertia_about="mass_center",
                           to_mass_center=[l_c, 0, 0], to_output=[1.0, 0, 0])
    model = dttmm.build_chain([dttmm.RevoluteJoint(axis=[0, 0, 1], drive=dttmm.SpringDamper(
        stiffness=k, damping=0.1, rest=0.0)), link], gravity=[0, -9.81, 0])
    eq = dttmm.static_equilibrium(model)
    exact = brentq(lambda x: k * x + mass * 9.81 * l_c * np.cos(x), -np.pi / 2, 0.0)
    assert eq.coordinates == ("RevoluteJoint0 coordinate 1",)
    assert abs(eq.model.hinge_params[0, 51] - exact) < 1e-10
    omega2 = (k - mass * 9.81 * l_c * np.sin(exact)) / (i_c + mass * l_c ** 2)
    assert np.allclose(eq.squared_frequencies, [omega2], rtol=1e-7)


def test_link_on_an_elastic_hinge_is_analytic():
    """A link on an elastic hinge at the ground (translational spring k_t = 2000 N/m, rotational
    K_r = diag(30, 30, 15) N m/rad), under gravity -y: the hinge deflects by m g / k_t down and
    turns by theta about z with k_r,z theta + m g l_c cos theta = 0 (the spring's moment about
    the deflected hinge point); the deflection is a coordinate of the solve and the result's
    ElasticHinge.deflection, which a scene keeps; DT-TMM from the equilibrium moves nothing by
    1e-9 m over 0.5 s."""
    from scipy.optimize import brentq
    from dttmm.interfaces.scene import scene_from_dict, scene_of
    mass, l_c, i_c, k_t, k_z = 2.0, 0.5, 1.0 / 6.0, 2000.0, 15.0
    link = dttmm.RigidBody(mass=mass, inertia=[1e-3, i_c, i_c], inertia_about="mass_center",
                           to_mass_center=[l_c, 0, 0], to_output=[1.0, 0, 0])
    hinge = dttmm.ElasticHinge(translational_stiffness=k_t, rotational_stiffness=[30, 30, k_z],
                               rotational_damping=0.1)
    model = dttmm.build_chain([hinge, link], gravity=[0, -9.81, 0])
    eq = dttmm.static_equilibrium(model)
    assert "ElasticHinge0 deflection y" in eq.coordinates and eq.stable
    d = eq.model.hinge_params[0, 45:48]
    assert np.abs(d - [0.0, -mass * 9.81 / k_t, 0.0]).max() < 1e-12, d
    theta = brentq(lambda x: k_z * x + mass * 9.81 * l_c * np.cos(x), -np.pi / 2, 0.0)
    x_axis = eq.model.initial_rotation[0] @ [1.0, 0, 0]
    assert abs(np.arctan2(x_axis[1], x_axis[0]) - theta) < 1e-10
    res = dttmm.simulate(eq.model, 0.5, 1e-3)
    assert np.abs(res.position_output - res.position_output[0]).max() < 1e-9
    assert np.allclose(res.position_input[0, 0], d, atol=1e-15)
    assert np.allclose(res.position_output[0], eq.positions()[2], atol=1e-12)
    again = scene_from_dict(scene_of(eq.model)).model
    assert np.array_equal(again.hinge_params[0, 45:48], d)


def test_arm_on_joints_with_coordinates_hangs():
    """The arm of examples/arm.py without its drive: joint 2 hangs link 2 straight down
    (-pi / 2), the prismatic spring stretches by m g / k = 0.5 * 9.81 / 50 m, joint 1 (about the
    vertical) is neutral; DT-TMM from the equilibrium moves nothing by 1e-9 m over 0.5 s.  With
    joint 1's angle prescribed (a JointMotion) and link 2 flexible, joint 1 is held, not solved."""
    eq = dttmm.static_equilibrium(chains.arm(undriven=True))
    q = eq.model.hinge_params[:, 51]
    assert abs(q[1] + np.pi / 2) < 1e-9 and abs(q[3] - 0.5 * 9.81 / 50.0) < 1e-12, q
    assert eq.stable and eq.squared_frequencies[0] == 0.0
    res = dttmm.simulate(eq.model, 0.5, 1e-3)
    assert np.abs(res.position_output - res.position_output[0]).max() < 1e-9
    assert np.allclose(res.position_output[0], eq.positions()[2], atol=1e-12)
    held = dttmm.static_equilibrium(chains.arm(drive="motion", flexible=True))
    assert "joint1 coordinate 1" not in held.coordinates
    assert "link2 mode 0" in held.coordinates and held.residual < 1e-9


def test_free_body_is_refused():
    """Nothing holds a ball-jointed body without gravity: every orientation is an equilibrium."""
    model = dttmm.build_chain([dttmm.BallJoint(), rod()], gravity=(0.0, 0.0, 0.0))
    with pytest.raises(dttmm.StaticEquilibriumError, match="body0.*free"):
        dttmm.static_equilibrium(model)


def test_loaded_free_body_and_no_convergence_say_what_to_do():
    """A torque that nothing balances has no equilibrium; too few iterations say so too."""
    model = dttmm.build_chain([dttmm.BallJoint(), rod(torque=lambda t: [0.0, 0.0, 1.0])],
                              gravity=(0.0, 0.0, 0.0))
    with pytest.raises(dttmm.StaticEquilibriumError, match="no convergence.*guess="):
        dttmm.static_equilibrium(model, max_iterations=10)
    with pytest.raises(dttmm.StaticEquilibriumError, match="no convergence in 1 iter"):
        dttmm.static_equilibrium(chains.three_pendulum(), max_iterations=1)


def test_bad_arguments():
    model = dttmm.build_chain([dttmm.BallJoint(), rod()])
    with pytest.raises(ValueError, match="static_equilibrium: tol must be finite and > 0"):
        dttmm.static_equilibrium(model, tol=-1.0)
    with pytest.raises(ValueError, match="max_iterations"):
        dttmm.static_equilibrium(model, max_iterations=0)
    with pytest.raises(ValueError, match="guess"):
        dttmm.static_equilibrium(model, guess=chains.three_pendulum())
    with pytest.raises(TypeError, match="Model"):
        dttmm.static_equilibrium("model.toml")



def _rz(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _bar(length, mass, angle):
    """A uniform rod along its x axis, turned by angle about z."""
    j = mass * length ** 2 / 12.0
    return dttmm.RigidBody(mass=mass, inertia=[1e-4 * mass, j, j], inertia_about="mass_center",
                           to_mass_center=[length / 2, 0, 0], to_output=[length, 0, 0],
                           rotation=_rz(angle))


def test_four_bar_hangs_and_swings_at_its_analytic_frequency():
    """A closed loop: a parallelogram four-bar of ball-jointed rods (cranks l = 1 m, m = 1 kg;
    coupler 1.5 m, M = 2 kg; its tip pinned where it starts, tip="ball") from cranks 0.6 rad
    off the vertical: the cranks hang straight down, the tip stays on its pin, the swing's
    squared frequency is (m + M) g l / (2 m l^2 / 3 + M l^2) (the coupler translates), three
    spins are neutral, and DT-TMM from the equilibrium stays at rest."""
    l, d, m, big_m, start = 1.0, 1.5, 1.0, 2.0, 0.6
    model = dttmm.build_chain([dttmm.BallJoint(), _bar(l, m, start - np.pi / 2),
                               dttmm.BallJoint(), _bar(d, big_m, 0.0),
                               dttmm.BallJoint(), _bar(l, m, start + np.pi / 2)],
                              gravity=(0.0, -9.81, 0.0), tip="ball")
    pin = np.array([d, 0.0, 0.0])
    eq = dttmm.static_equilibrium(model)
    r_o = eq.positions()[2]
    assert np.abs(r_o - [[0.0, -l, 0.0], [d, -l, 0.0], pin]).max() < 1e-9, r_o
    assert eq.stable
    swing = (m + big_m) * 9.81 * l / (2.0 * m * l ** 2 / 3.0 + big_m * l ** 2)
    lam = eq.squared_frequencies
    assert np.sum(lam == 0.0) == 3, lam
    assert np.min(np.abs(lam / swing - 1.0)) < 1e-6, (lam, swing)
    res = dttmm.simulate(eq.model, 0.5, 1e-3)
    assert np.abs(res.position_output - res.position_output[0]).max() < 1e-9


@pytest.mark.parametrize("elements, stretch, tolerance", [(1, False, 5e-4), (4, True, 1e-5)])
def test_beam_between_pins_sags_as_the_simply_supported_beam(elements, stretch, tolerance):
    """A closed loop: a beam (L = 2 m) on a ball joint with its tip pinned, under gravity: the
    midspan sags by 5 mu g L^4 / (384 EI) (one element of the pinned family, 3 modes: 2.7e-4
    below it, the series' fifth-order term left out; four welded elements with stretch modes
    and EA / EI = 100 / m^2, so the sag's membrane force is negligible: 3.6e-7), and the first
    two bending frequencies in each plane are the simply supported beam's, (n pi / L)^2
    sqrt(EI / mu) (measured 4e-7 and 1.4e-4)."""
    length, ei, mu = 2.0, 5e4, 3.0
    parts = [dttmm.BallJoint()]
    for k in range(elements):
        parts += [dttmm.FixedHinge()] if k else []
        parts.append(dttmm.EulerBernoulliBeam(
            length=length / elements, mass_per_length=mu, bending_stiffness=ei,
            polar_inertia_per_length=1e-3, modes_per_plane=3,
            **(dict(axial_modes=2, axial_stiffness=100.0 * ei) if stretch else {})))
    eq = dttmm.static_equilibrium(dttmm.build_chain(parts, gravity=(0.0, -9.81, 0.0),
                                                    tip="ball"))
    assert eq.stable
    points = np.concatenate(eq.centreline(points_per_beam=9))
    mid = points[np.argmin(np.abs(points[:, 0] - length / 2))]
    sag = 5.0 * mu * 9.81 * length ** 4 / (384.0 * ei)
    assert abs(mid[0] - length / 2) < 1e-6 and abs(-mid[1] / sag - 1.0) < tolerance, mid
    assert np.abs(eq.positions()[2][-1] - [length, 0.0, 0.0]).max() < 1e-12
    first = (np.pi / length) ** 4 * ei / mu
    lam = eq.squared_frequencies
    assert lam[0] == 0.0                           # the spin about the chord
    assert np.allclose(lam[1:5], [first, first, 16 * first, 16 * first], rtol=2e-4), lam


def test_a_straight_inextensible_chain_between_pins_is_explained():
    """Welded elements without stretch modes, held straight between pins exactly their length
    apart, cannot sag (the closure holds only at second order along the chord): the solve
    stops and says to give them stretch modes."""
    parts = [dttmm.BallJoint()]
    for k in range(4):
        parts += [dttmm.FixedHinge()] if k else []
        parts.append(dttmm.EulerBernoulliBeam(length=0.5, mass_per_length=3.0,
                                              bending_stiffness=50.0,
                                              polar_inertia_per_length=1e-3, modes_per_plane=3))
    model = dttmm.build_chain(parts, gravity=(0.0, -9.81, 0.0), tip="ball")
    with pytest.raises(dttmm.StaticEquilibriumError, match="closed loop.*axial_modes"):
        dttmm.static_equilibrium(model)


@pytest.mark.parametrize("links", [2, 3, 10])
def test_ball_chains_settle_from_the_horizontal(links):
    """A chain of uniform links held out horizontally (where gravity stiffens nothing and
    Newton's step is undefined) settles to hanging straight down: the tip at -links m to
    1e-9 m, stable, its lowest squared frequency positive.  Before the settling flow
    (docs/statics.md, "Getting there") the 2-link chain of the README stalled at a residual of
    1.27 rad/s^2, whatever max_iterations."""
    link = lambda **kw: dttmm.RigidBody(mass=1.0, inertia=[1 / 6, 5 / 12, 5 / 12],
                                        inertia_about="input", to_mass_center=[0.5, 0, 0],
                                        to_output=[1, 0, 0], **kw)
    parts = []
    for _ in range(links):
        parts += [dttmm.BallJoint(), link()]
    eq = dttmm.static_equilibrium(dttmm.build_chain(parts, gravity=[0, -9.81, 0]))
    assert np.allclose(eq.positions()[2][-1], [0.0, -links, 0.0], atol=1e-9)
    assert eq.stable and eq.iterations < 30
    assert eq.squared_frequencies[eq.squared_frequencies > 0].min() > 0.1


@pytest.mark.parametrize("name", ["rigid_chain", "tree", "arm", "arm_motion", "flexible_arm",
                                  "cantilever", "three_pendulum"])
def test_the_shipped_scenes_reach_their_equilibrium(name):
    """dttmm run --static-start's solve on every shipped scene (rigid_chain and tree start
    horizontal; before stop 28 both failed): it converges, and DT-TMM from it stays at rest
    (1e-9 m over 0.05 s)."""
    from dttmm.interfaces.scene import load_scene
    from dttmm.interfaces.cli import shipped_scenes
    model = load_scene(shipped_scenes()[name]).model
    eq = dttmm.static_equilibrium(model)
    assert eq.residual < 1e-8
    if name in ("rigid_chain", "tree"):
        res = dttmm.simulate(eq.model, 0.05, 1e-3)
        assert np.abs(res.position_output - res.position_output[0]).max() < 1e-9


def test_an_element_bent_beyond_its_validity_is_refused():
    """One modal element rolled up by M = 2 pi EI / L solves the modal equations with its tip
    at (-5.58, 3.14) m for a 1 m beam: refused (the time loop's check), naming the beam and
    saying to split it; at a quarter turn (tip deflection 0.79 L) it is returned."""
    one = lambda lam: cantilever(1, tip_torque=[0.0, 0.0, lam * 2.0 * np.pi * EI])
    with pytest.raises(dttmm.StaticEquilibriumError, match="body0.*deflects 3.14 m.*split"):
        dttmm.static_equilibrium(one(1.0))
    assert dttmm.static_equilibrium(one(0.25)).positions()[2][-1][0] > 0.0


@pytest.mark.parametrize("n", [1, 2])
def test_closed_n_four_bar_hangs_and_swings_at_its_exact_frequency(n):
    """The N-four-bar (closing revolute joints, dttmm.model.mechanisms.n_four_bar; redundant spatial
    rows of a planar loop) from its vertical bars 3 rad off upright: they hang straight down
    (B_0 at (0, -1)), the horizontal bars above them, and its one swing has the exact
    reduction's squared frequency g c / I, I = (n + 1) / 3 + n, c = (n + 1) / 2 + n
    (mechanisms.parallelogram); DT-TMM from the equilibrium stays at rest."""
    from dttmm.model.mechanisms import n_four_bar
    eq = dttmm.static_equilibrium(n_four_bar(n, theta=3.0, rate=0.0))
    r_o = eq.positions()[2]
    assert np.abs(r_o[0] - [0.0, -1.0, 0.0]).max() < 1e-9, r_o[0]
    assert eq.stable
    swing = 9.81 * ((n + 1) / 2 + n) / ((n + 1) / 3 + n)
    lam = eq.squared_frequencies[eq.squared_frequencies != 0.0]
    assert len(lam) == 1 and abs(lam[0] / swing - 1.0) < 1e-6, (eq.squared_frequencies, swing)
    res = dttmm.simulate(eq.model, 0.2, 1e-3)
    assert np.abs(res.position_output - res.position_output[0]).max() < 1e-9


# (the crank turned to 2.5 rad and the loop assembled around it on purpose: AssemblyWarning)
@pytest.mark.filterwarnings("ignore::dttmm.model.loop_kinematics.AssemblyWarning")
def test_the_slider_crank_hangs_its_crank_down_and_swings_as_the_reference():
    """The IFToMM spatial slider-crank under gravity (closed by its prismatic joint): its
    potential, g (0.12 (0.12 + 0.04 cos th) + 0.5 (0.12 + 0.08 cos th) / 2), is least with the
    crank hanging down, th = pi, where the slider sits at x = sqrt(0.3^2 - 0.1^2 - 0.04^2) =
    0.28 m; the one small vibration's frequency equals the reference's swing from 0.01 rad off
    (its period measured over 2 s)."""
    from dttmm.model.mechanisms import slider_crank
    from helpers import crossing_period
    model = slider_crank(crank_rate=0.0)
    eq = dttmm.static_equilibrium(dttmm.assemble(_with_crank(model, 2.5), keep=["A"]))
    crank_tip, slider = eq.positions()[2][0], eq.positions()[0][2]
    assert np.abs(crank_tip - [0.0, 0.1, 0.04]).max() < 1e-9, crank_tip
    assert abs(slider[0] - 0.28) < 1e-9, slider
    assert eq.stable
    lam = eq.squared_frequencies[eq.squared_frequencies != 0.0]
    assert len(lam) == 1, eq.squared_frequencies
    t = np.linspace(0.0, 2.0, 2001)
    swing = dttmm.simulate_reference(
        dttmm.assemble(_with_crank(eq.model, np.pi + 0.01), keep=["A"]), 2.0, t_eval=t,
        rtol=1e-10, atol=1e-12)
    period = crossing_period(t, swing.joint_coordinates[:, 0])
    assert abs((2 * np.pi / period) ** 2 / lam[0] - 1.0) < 2e-3, (period, lam)


def _with_crank(model, angle):
    """The model with the crank's joint coordinate set to angle (rad), at rest."""
    from dataclasses import replace
    from dttmm.elements.kinds import COORDINATE_0, RATE_0
    hinge_params = np.array(model.hinge_params, order="C")
    hinge_params[0, COORDINATE_0.start] = angle
    hinge_params[:, RATE_0] = 0.0
    return replace(model, hinge_params=hinge_params,
                   initial_angular_velocity=np.zeros((model.n_bodies, 3)))


def test_frequencies_beyond_the_mode_count_are_marked():
    """Issue 65, item 6: the guide's cantilever (steel, 1 m, 10 mm square, a 0.2 kg tip mass)
    keeps 3 modes per plane, chosen for the first two frequencies: its first and second are
    within 1% of Euler-Bernoulli's (5.857, 42.35 Hz) and trusted; its third comes out 197.8 Hz
    where Euler-Bernoulli's is 125.88 Hz (+57%) and is marked untrusted.  (With 2 modes, the
    count before the second frequency was held, the second was 58.8 Hz, +39%, unflagged before
    the marks.)"""
    e, rho, side = 210e9, 7850.0, 0.01
    second = side ** 4 / 12
    beam = dttmm.EulerBernoulliBeam(length=1.0, bending_stiffness=e * second, density=rho,
                                    area=side * side, polar_inertia_per_length=rho * 2 * second)
    tip = dttmm.RigidBody(mass=0.2, inertia=[1e-6] * 3, inertia_about="mass_center")
    eq = dttmm.static_equilibrium(dttmm.build_chain([dttmm.FixedHinge(), beam,
                                                     dttmm.FixedHinge(), tip],
                                                    gravity=[0.0, -9.81, 0.0]))
    f = eq.frequencies
    assert f[0] == pytest.approx(5.857, rel=0.01) and eq.trusted[0] and eq.trusted[1]
    assert f[2] == pytest.approx(42.35, rel=0.01) and eq.trusted[2] and eq.trusted[3]
    assert f[4] > 1.3 * 125.88 and not eq.trusted[4] and not eq.trusted[5]
    assert 125.88 <= eq.trusted_below < 125.88 * 1.01   # the third mode, of the 6-mode basis


def test_many_welded_elements_give_the_cantilevers_frequencies():
    """A 1 m aluminium cantilever (15 mm round) of 16 welded elements, 3 modes each (the inner
    ones' default): its first two frequencies within 1e-5 of Euler-Bernoulli's (1.8751^2 and
    4.6941^2 sqrt(EI / mu) / 2 pi L^2).  The stiff modes' accelerations are far from linear
    over a central difference's step: the step alone left the first 0.29% low."""
    e, rho, d = 70e9, 2700.0, 0.015
    area, second = np.pi * d ** 2 / 4, np.pi * d ** 4 / 64
    elements = []
    for i in range(16):
        elements += [dttmm.FixedHinge(), dttmm.EulerBernoulliBeam(
            length=1.0 / 16, density=rho, area=area, bending_stiffness=e * second,
            polar_inertia_per_length=2 * rho * second, name=f"e{i}")]
    model = dttmm.build_chain(elements, gravity=[0.0, 0.0, 0.0])
    assert model.n_modes[0] == 6
    scale = np.sqrt(e * second / (rho * area)) / (2 * np.pi)
    f = dttmm.static_equilibrium(model).frequencies
    assert f[0] == pytest.approx(1.8751040687 ** 2 * scale, rel=1e-5)
    assert f[2] == pytest.approx(4.6940911330 ** 2 * scale, rel=1e-5)
