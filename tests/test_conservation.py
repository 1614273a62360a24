"""Energy and angular momentum of the conservative chain under the Newmark scheme: small drift,
shrinking as dt^2 (the energy-momentum scheme conserves both: test_energy_momentum.py)."""
import numpy as np
import pytest

from dttmm import simulate
from dttmm.model.chains import rigid_chain
from dttmm.results.result import angular_momentum


def drifts(n_links, dt, t_end=10.0):
    """Largest total-energy change over the largest kinetic energy, and largest change of the
    angular momentum about the vertical axis through the pivot over its initial value."""
    model = rigid_chain(n_links)
    res = simulate(model, t_end, dt, record_every=int(round(0.01 / dt)))
    e = res.total_energy
    l_y = angular_momentum(model, res)[:, 1]
    return (np.abs(e - e[0]).max() / res.kinetic.max(),
            np.abs(l_y - l_y[0]).max() / abs(l_y[0]))


@pytest.fixture(scope="module")
def chain3_drifts():
    return drifts(3, 1e-3), drifts(3, 5e-4)


def test_energy_drift_is_small_and_second_order(chain3_drifts):
    (e1, _), (e2, _) = chain3_drifts
    assert e1 < 1e-4
    assert 3.5 < e1 / e2 < 4.5


def test_angular_momentum_drift_is_second_order(chain3_drifts):
    (_, l1), (_, l2) = chain3_drifts
    assert 3.5 < l1 / l2 < 4.5


@pytest.mark.xfail(strict=True, reason="the trapezoidal Lie-group Newmark rule does not conserve "
                   "angular momentum exactly: L_y drifts 3.4e-4 of its (small) initial value over "
                   "10 s at dt = 1e-3; scheme='energy_momentum' conserves it "
                   "(test_energy_momentum.py)")
def test_angular_momentum_drift_below_1e_4(chain3_drifts):
    (_, l1), _ = chain3_drifts
    assert l1 < 1e-4
