"""Where multiplied-out transfers fail and the Riccati sweep does not (notes §5, issue 4)."""
import warnings

import numpy as np
import pytest

from dttmm import (DivergenceError, ElasticHinge, FixedHinge, RigidBody,
                   build_chain, simulate)
from dttmm.model.chains import rigid_chain, stiff_cantilever, three_pendulum, unit_link

H = 1e-3
K_SPRING = 1e4


def spring_chain(n):
    """The notes' 1-D chain in the library's elements: n point masses of 1 kg hanging from the
    ground on springs of k = 1e4 N/m (elastic hinges; the rotations carry no lever arms and stay
    at rest)."""
    elements = []
    for _ in range(n):
        elements += [ElasticHinge(K_SPRING, 1e2),
                     RigidBody(mass=1.0, inertia=[1e-2] * 3, inertia_about="mass_center",
                               to_mass_center=[0, 0, 0], to_output=[0, 0, 0])]
    return build_chain(elements, gravity=[0, -9.81, 0])


def dense_first_step(n, g=9.81):
    """The same trapezoidal step for the same chain, as one dense solve:
    (4 M / h^2 + K) y_1 = M (4 (y_0 + h v_0) / h^2 + a_0) + f = -2 g (from rest, unstretched)."""
    k = np.zeros((n, n))
    for i in range(n):
        k[i, i] += K_SPRING
        if i + 1 < n:
            k[i, i] += K_SPRING
            k[i, i + 1] -= K_SPRING
            k[i + 1, i] -= K_SPRING
    return np.linalg.solve(4 / H ** 2 * np.eye(n) + k, np.full(n, -2 * g))


@pytest.mark.parametrize("n", [3, 10, 100, 1000])
def test_riccati_matches_a_dense_solve_of_the_step(n):
    expected = dense_first_step(n)
    res = simulate(spring_chain(n), H, H)
    y = res.position_output[-1, :, 1]
    assert np.abs(y - expected).max() <= 1e-12 * np.abs(expected).max()


def test_direct_fails_by_ten_masses():
    """The products hold 4 M / h^2 = 4e6 beside k = 1e4: at 3 masses the direct sweep is still
    right (7e-12 relative), at 5 it has lost 9 digits (1.2e-7), at 10 it is wrong (relative
    error 4e2, measured before the check existed) and now stops saying so."""
    expected = dense_first_step(3)
    res = simulate(spring_chain(3), H, H, method="direct")
    assert np.abs(res.position_output[-1, :, 1] - expected).max() <= 1e-9 * np.abs(expected).max()
    with pytest.raises(DivergenceError, match="direct sweep lost its accuracy"):
        simulate(spring_chain(10), H, H, method="direct")


@pytest.mark.parametrize("model_name", ["rigid100", "beams50"])
def test_long_chains_run_in_riccati_mode(model_name):
    """1 s at dt = 1e-3 without warnings, the energy within 1e-4 of the largest kinetic energy
    (measured: 4.8e-8 for 100 links; 7.7e-5 for 50 stiff beam elements, whose element modes
    reach 2.5e5 rad/s, 250 / dt)."""
    model = rigid_chain(100) if model_name == "rigid100" else stiff_cantilever(50)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = simulate(model, 1.0, 1e-3, record_every=10)
    e = res.total_energy
    assert np.abs(e - e[0]).max() < 1e-4 * res.kinetic.max()


def test_reduced_and_full_state_agree():
    model = rigid_chain(10)
    a = simulate(model, 1.0, 1e-3, record_every=10)
    b = simulate(model, 1.0, 1e-3, record_every=10, full_state=True)
    assert a.info["mode"] == "riccati-reduced" and b.info["mode"] == "riccati-full"
    assert np.abs(a.position_output - b.position_output).max() < 1e-12 * 10
    assert np.abs(a.force - b.force).max() < 1e-12 * np.abs(a.force).max() * 1e2


def elastic_clamped_chain():
    return build_chain([FixedHinge(), unit_link(), ElasticHinge(1e5, 1e3), unit_link(),
                        ElasticHinge(1e5, [1e3, 2e3, 3e3]), unit_link()])


# (the two sweeps compared on the same steps: the stiff cantilever's 636 Hz modes unresolved at
# dt = 1e-3 on purpose, 0.1% of the energy)
@pytest.mark.parametrize("name", ["rigid3", "three_pendulum", "elastic_clamped", "cantilever4"])
@pytest.mark.filterwarnings("ignore:simulate. the step does not resolve beam:"
                            "dttmm.solving.solver.UnresolvedMotionWarning")
def test_direct_and_riccati_agree_on_short_systems(name):
    model = {"rigid3": lambda: rigid_chain(3), "three_pendulum": lambda: three_pendulum(2),
             "elastic_clamped": elastic_clamped_chain,
             "cantilever4": lambda: stiff_cantilever(4, 1.0)}[name]()
    runs = [simulate(model, 0.5, 1e-3, method=m, record_every=50) for m in ("riccati", "direct")]
    scale = np.abs(runs[0].position_output).max()
    assert np.abs(runs[0].position_output - runs[1].position_output).max() <= 1e-10 * scale


@pytest.mark.long
@pytest.mark.parametrize("name", ["three_pendulum", "chain10"])
def test_two_minutes_at_small_dt(name):
    """120 s at dt = 1e-4 (1.2 million steps; minutes each, so opt-in: pytest -m long): the
    energy within 1e-4 of the largest kinetic energy throughout (measured 2.6e-6 and 1.2e-5): a
    growing oscillation would have to feed on it.  For the three-pendulum also the largest
    angular acceleration of the last 20 s against the first 100 s (measured per 20 s window:
    180, 317, 267, 305, 239, 253 rad/s^2).  Not for the 10-link chain: its whips are chaotic
    single events (window peaks 995, 1370, 935, 1024, 955, 2384 rad/s^2 with the energy held to
    1.2e-5), so a window's peak says nothing about growth there."""
    model = three_pendulum(2) if name == "three_pendulum" else rigid_chain(10)
    res = simulate(model, 120.0, 1e-4, record_every=50)
    e = res.total_energy
    assert np.abs(e - e[0]).max() < 1e-4 * res.kinetic.max()
    if name == "three_pendulum":
        acc = np.abs(res.angular_acceleration).max(axis=(1, 2))
        late = res.t > 100.0
        assert acc[late].max() < 1.5 * acc[~late].max()
