"""Loads on beams (docs/beam.md, "Loads on the beam"): a force and a torque applied at a beam's
output end, world axes, functions of time.  Against the analytic cantilever, the elastica, the
Newton-Euler reference (order 2), and the energy balance (their work counted)."""
import warnings

import numpy as np
import pytest

import dttmm
from dttmm import (EulerBernoulliBeam, FixedHinge, Ground, PrescribedMotion, build_chain,
                   simulate, static_equilibrium)
from helpers import fitted_order, output_errors_against_reference

EI, L = 100.0, 1.0


def cantilever(n_elements=1, force=None, torque=None, modes=2, stiffening=True, **beam):
    """n welded elements clamped along x, the loads at the last one's free end, no gravity."""
    parts = []
    for k in range(n_elements):
        last = k == n_elements - 1
        parts += [FixedHinge(), EulerBernoulliBeam(
            length=L / n_elements, bending_stiffness=EI, mass_per_length=1.0,
            polar_inertia_per_length=1e-3, modes_per_plane=modes, stiffening=stiffening,
            end_force=(lambda t: force) if last and force is not None else None,
            end_torque=(lambda t: torque) if last and torque is not None else None, **beam)]
    return build_chain(parts, gravity=[0.0, 0.0, 0.0])


@pytest.mark.parametrize("n_elements", [1, 3])
def test_small_tip_loads_bend_the_cantilever_as_euler_bernoulli_says(n_elements):
    """A tip force P along y: v(L) = P L^3 / (3 EI), slope P L^2 / (2 EI); a tip torque M about z:
    v(L) = M L^2 / (2 EI), slope M L / EI; out of the plane (w) the same.  The loaded end takes
    the polynomial modes, which hold these cubics exactly (one element or three); loads of
    1e-4 of the buckling scale keep the foreshortening's second order below 1e-7 relative."""
    p, m = 1e-3, 1e-3
    for force, torque, want_v, want_w in (
            ([0.0, p, 0.0], None, p * L ** 3 / (3 * EI), 0.0),
            ([0.0, 0.0, p], None, 0.0, p * L ** 3 / (3 * EI)),
            (None, [0.0, 0.0, m], m * L ** 2 / (2 * EI), 0.0),
            (None, [0.0, -m, 0.0], 0.0, m * L ** 2 / (2 * EI))):
        model = cantilever(n_elements, force, torque)
        assert model.beam_params[-1, 7] == 2           # the loaded-end family, chosen for the load
        tip = static_equilibrium(model).positions()[2][-1]
        assert abs(tip[1] - want_v) < 1e-6 * max(abs(want_v), 1e-6), (tip, want_v)
        assert abs(tip[2] - want_w) < 1e-6 * max(abs(want_w), 1e-6), (tip, want_w)


def test_uniform_load_bends_the_cantilever_as_euler_bernoulli_says():
    """A uniform load q per length across the beam: v(L) = q L^4 / (8 EI).  A distributed load
    leaves the free tip free, so the beam keeps the clamped-free eigenfunctions, whose series
    converges to it: measured relative errors 1.3e-2, -9.1e-4, 1.6e-4, -4.2e-5, -6.1e-6 with
    1, 2, 3, 4, 6 modes per plane."""
    q = 1e-3
    for modes, tol in ((2, 1.5e-3), (4, 6e-5), (6, 1e-5)):
        model = build_chain([FixedHinge(), EulerBernoulliBeam(
            length=L, bending_stiffness=EI, mass_per_length=1.0, polar_inertia_per_length=1e-3,
            modes_per_plane=modes, stiffening=True, distributed_load=lambda t: [0.0, q, 0.0])],
            gravity=[0.0, 0.0, 0.0])
        assert model.beam_params[0, 7] == 1            # clamped-free eigenfunctions
        tip = static_equilibrium(model).positions()[2][-1]
        assert abs(tip[1] / (q * L ** 4 / (8 * EI)) - 1.0) < tol, (modes, tip)


def test_a_distributed_load_is_gravity_on_that_beam():
    """p = mu g' per length on the beam, no gravity, moves it exactly as gravity g' does."""
    def pendulum(g, p):
        beam = EulerBernoulliBeam(length=1.0, bending_stiffness=[30.0, 50.0],
                                  mass_per_length=2.0, polar_inertia_per_length=1e-3,
                                  modes_per_plane=2, stiffening=True,
                                  distributed_load=None if p is None else (lambda t: p))
        return build_chain([dttmm.RevoluteJoint(axis=[0, 0, 1]), beam], gravity=g)
    g = np.array([0.0, -9.81, 0.0])
    by_gravity = simulate(pendulum(g, None), 0.5, 1e-3)
    by_load = simulate(pendulum(np.zeros(3), 2.0 * g), 0.5, 1e-3)
    assert np.abs(by_gravity.position_output - by_load.position_output).max() < 1e-12
    assert np.abs(by_gravity.modal_coordinates - by_load.modal_coordinates).max() < 1e-12


def test_elastica_by_an_end_torque_on_the_beam():
    """The elastica of tests/test_statics.py with the moment on the last element's end instead
    of a tip body: the same tip within 2e-4 L of the arc at phi = pi / 2 (8 elements: 2.8e-4
    with the tip body; the body's own small rotation apart, the same equations)."""
    phi = np.pi / 2
    guess = None
    for lam in (0.5, 1.0):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            guess = static_equilibrium(cantilever(8, torque=[0.0, 0.0, lam * phi * EI / L]),
                                       guess=guess)
    exact = np.array([np.sin(phi) / phi, (1.0 - np.cos(phi)) / phi, 0.0]) * L
    assert np.linalg.norm(guess.positions()[2][-1] - exact) < 4e-4


def test_a_follower_torque_rolls_the_same_circle():
    """A tip moment about the end section's own z axis (load_axes="body") is the world-axes
    moment about z while the beam bends in the xy plane: the same equilibrium (8 elements,
    phi = pi / 2 in two load steps), to 1e-8 m: each solve stops at its own residual
    tolerance (1e-10 in the accelerations), which leaves ~1e-9 m here (measured 1.08e-9 in
    one run, below 1e-9 in another)."""
    tips = []
    for axes in ("world", "body"):
        guess = None
        for lam in (0.5, 1.0):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                torque = [0.0, 0.0, lam * np.pi / 2 * EI / L]
                guess = static_equilibrium(cantilever(8, torque=torque, load_axes=axes),
                                           guess=guess)
        tips.append(guess.positions()[2][-1])
    assert np.linalg.norm(tips[0] - tips[1]) < 1e-8, tips


def becks_column(load):
    """Beck's column: a clamped-free column of 3 welded elements (3 modes per plane each)
    under a follower force at its tip, compressive along the end section's tangent."""
    return cantilever(3, force=[-load, 0.0, 0.0], modes=3, load_axes="body")


@pytest.mark.parametrize("fraction, stable", [(0.99, True), (1.01, False)])
def test_a_follower_force_makes_the_column_flutter_at_becks_load(fraction, stable):
    """Beck's column (a tangential follower force at the free end, non-conservative) does not
    buckle; its two lowest bending frequencies meet and turn complex (flutter) at
    P = 20.05 EI / L^2 (Beck 1952; Timoshenko & Gere).  The static solve's small vibrations:
    stable at 0.99 of it, flutter (complex squared frequencies, flagged unstable, warned) at
    1.01 (measured by bisection: 20.058 EI / L^2, 4e-4 above; one element with 4 modes:
    20.40)."""
    load = fraction * 20.05 * EI / L ** 2
    if stable:
        st = static_equilibrium(becks_column(load))
        assert np.all(np.isreal(st.squared_frequencies))
    else:
        with pytest.warns(UserWarning, match="flutter"):
            st = static_equilibrium(becks_column(load))
        lowest = st.squared_frequencies[0]
        assert abs(lowest.imag) > 0.01 * abs(lowest), lowest
    assert st.stable == stable
    # the straight column is the equilibrium either way (the force stays along it)
    assert np.abs(st.positions()[2][-1] - [L, 0.0, 0.0]).max() < 1e-12


def _ramp(t):
    """0 -> 1 over the first second with zero rate at both ends (t^2 (3 - 2 t)): a load switched
    on suddenly rings the elements' highest modes (hundreds of rad/s here), which no dt of this
    test resolves, and their phase error swamps the order (measured with the torque switched on
    at t = 0: errors 2.1e-4, 1.4e-4 and 2.8e-4 m at dt 4e-3, 2e-3 and 1e-3)."""
    return t * t * (3.0 - 2.0 * t) if t < 1.0 else 1.0


def _driven_loaded_cantilever(load_axes="world"):
    """A soft stiffened cantilever (two welded elements) on a hub driven about z, gravity -y,
    a time-varying end force (with a compressive part along the beam) and end torque on the
    outer element, a distributed load on the inner one, ramped on; in world axes or, with
    load_axes="body", following the end section and the frame."""
    def angle(t):
        return 1.5 * t * t
    hub = PrescribedMotion.spin_about_axis([0, 0, 1], angle, lambda t: 3.0 * t, lambda t: 3.0)
    parts = []
    for k in range(2):
        parts += [FixedHinge(), EulerBernoulliBeam(
            length=0.5, mass_per_length=1.0, bending_stiffness=[3.0, 4.0],
            polar_inertia_per_length=1e-3, modes_per_plane=2, stiffening=True,
            end_force=(lambda t: _ramp(t) * np.array([-0.5 * np.cos(3 * t),
                                                      0.4 * np.sin(2 * t), 0.3])) if k else None,
            end_torque=(lambda t: _ramp(t) * np.array([0.05, -0.1 * t, 0.2 * np.cos(t)]))
            if k else None,
            distributed_load=(lambda t: _ramp(t) * np.array([0.3, 0.5 * np.sin(2 * t), -0.4]))
            if k == 0 else None, load_axes=load_axes)]
    return build_chain(parts, gravity=[0.0, -9.81, 0.0], ground=Ground(motion=hub))


# (bent far on purpose, 0.9-1.1 rad in one element: an integration test against the reference,
# which shares the modes; the run's warning that a real beam would differ is beside its point)
@pytest.mark.filterwarnings("ignore:simulate. beam .* rings while bent:"
                            "dttmm.solving.solver.UnresolvedMotionWarning")
@pytest.mark.parametrize("load_axes", ["world", "body"])
def test_end_loads_converge_to_the_reference_at_order_2(load_axes):
    """DT-TMM against the Newton-Euler reference (which adds the loads to its own Newton,
    Euler and modal rows: F, rho_O x F + T, B_r^T F + B_t^T T, and the distributed load p
    as g + p / mu in the beam's terms; followers turned by A_O and A first); output points
    at t = 1 s, dt 4e-3 / 2e-3 / 1e-3: fitted order 2 +- 0.2."""
    model = _driven_loaded_cantilever(load_axes)
    steps = np.array([4e-3, 2e-3, 1e-3])
    errors = output_errors_against_reference(model, steps)
    slope = fitted_order(steps, errors)
    assert abs(slope - 2.0) < 0.2, (errors, slope)
    assert errors[-1] < 1e-4, errors


# (bent far on purpose, 0.9-1.1 rad in one element: an integration test against the reference,
# which shares the modes; the run's warning that a real beam would differ is beside its point)
@pytest.mark.filterwarnings("ignore:simulate. beam .* rings while bent:"
                            "dttmm.solving.solver.UnresolvedMotionWarning")
@pytest.mark.parametrize("load_axes", ["world", "body"])
def test_end_loads_work_is_counted_in_the_energy_balance(load_axes):
    """E - E(0) - W, W the work of the loads (F . v_O + T . w_O, p . int v dx, followers
    turned into the world first) and of the hub's drive, closes at order 2 in dt (the gap at
    dt 1e-3 a quarter of dt 2e-3's)."""
    model = _driven_loaded_cantilever(load_axes)
    gaps = []
    for h in (2e-3, 1e-3):
        res = simulate(model, 1.0, h, max_energy_error=1.0)
        gaps.append(res.info["energy_balance_error"])
    assert gaps[1] < 1e-4 and gaps[0] / gaps[1] > 3.0, gaps


def test_bad_end_loads_are_refused_naming_the_beam():
    with pytest.raises(ValueError, match="'arm'.*end_force must be 3 finite numbers"):
        build_chain([FixedHinge(), EulerBernoulliBeam(        # (3 numbers: a constant load)
            length=1.0, bending_stiffness=EI, mass_per_length=1.0,
            polar_inertia_per_length=1e-3, end_force=[0.0, 1.0], name="arm")])
    with pytest.raises(ValueError, match="'arm'.*end_torque"):
        build_chain([FixedHinge(), EulerBernoulliBeam(
            length=1.0, bending_stiffness=EI, mass_per_length=1.0,
            polar_inertia_per_length=1e-3, end_torque=lambda t: [0.0, 1.0], name="arm")])
    with pytest.raises(ValueError, match="'arm'.*load_axes must be 'world' or 'body'"):
        build_chain([FixedHinge(), EulerBernoulliBeam(
            length=1.0, bending_stiffness=EI, mass_per_length=1.0,
            polar_inertia_per_length=1e-3, load_axes="local", name="arm")])
    with pytest.raises(ValueError, match="'arm'.*pinned.*end torque"):
        build_chain([dttmm.BallJoint(), EulerBernoulliBeam(
            length=1.0, bending_stiffness=EI, mass_per_length=1.0,
            polar_inertia_per_length=1e-3, mode_family="pinned",
            end_torque=lambda t: [0.0, 0.0, 1.0], name="arm")])


@pytest.mark.parametrize("bad, match", [
    (dict(distributed_load=[0.0, 1.0]), "distributed_load must be 3 finite numbers"),
    (dict(distributed_load=lambda t: [0.0, 1.0]), r"distributed_load\(0\) must have 3 entries"),
    (dict(distributed_load=lambda t: [0.0, np.nan, 1.0]), r"distributed_load\(0\) contains NaN"),
    (dict(modes_per_plane=0), "modes_per_plane must be an integer >= 1"),
    (dict(modes_per_plane=-2), "modes_per_plane must be an integer >= 1"),
    (dict(modes_per_plane=2.5), "modes_per_plane must be an integer >= 1"),
])
def test_bad_distributed_load_and_mode_count_are_refused_naming_the_beam(bad, match):
    """Issue 16's bad input: a distributed load of the wrong shape, a zero, negative or
    fractional bending mode count, each refused at the build, naming the beam."""
    with pytest.raises(ValueError, match="'arm'.*" + match):
        build_chain([FixedHinge(), EulerBernoulliBeam(
            length=1.0, bending_stiffness=EI, mass_per_length=1.0,
            polar_inertia_per_length=1e-3, name="arm", **bad)])


def test_end_loads_in_a_scene_round_trip(tmp_path):
    """A scene's beam takes end_force and end_torque as profiles, and save_scene writes them
    back: the same arrays and the same loads."""
    from dttmm.model.profiles import profile
    from dttmm.interfaces.scene import load_scene, save_scene
    ramp = profile({"profile": "ramp", "value": [0.0, 0.0, 2.0], "duration": 1.0})
    model = build_chain([FixedHinge(), EulerBernoulliBeam(
        length=1.0, bending_stiffness=EI, mass_per_length=1.0, polar_inertia_per_length=1e-3,
        modes_per_plane=2,
        end_force=profile({"profile": "constant", "value": [0.0, -1.0, 0.0]}),
        end_torque=ramp, distributed_load=profile({"profile": "sine", "amplitude": [0.0, 0.0, 1.0],
                                                   "frequency": 2.0}), name="arm")])
    save_scene(model, tmp_path / "loaded.toml")
    again = load_scene(tmp_path / "loaded.toml").model
    assert np.array_equal(again.beam_params, model.beam_params)
    assert np.allclose(again.forces[0](0.3), [0.0, -1.0, 0.0])
    assert np.allclose(again.torques[0](0.5), [0.0, 0.0, 1.0])
    assert np.allclose(again.line_loads[0](0.1), model.line_loads[0](0.1))
