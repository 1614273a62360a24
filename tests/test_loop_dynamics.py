"""DT-TMM's sweep with closing joints at acceleration level (dttmm/solving/loop_dynamics.py,
docs/loops.md "The sweep with closing joints"): against the parallelogram's exact reduction and
the Newton-Euler reference."""
import numpy as np
import pytest

from dttmm.solving.loop_dynamics import loop_accelerations
from dttmm.model.mechanisms import n_four_bar, slider_crank
from dttmm.reference.problem import _Problem


@pytest.mark.parametrize("n", [1, 3])
def test_the_sweep_with_closing_joints_gives_the_parallelogram_its_exact_acceleration(n):
    """theta'' = 9.81 c sin(theta) / I (c = (n + 1) / 2 + n, I = (n + 1) / 3 + n): every
    vertical bar turns at -theta'' about z, every horizontal bar not at all, whatever the
    redundant closing joints' multipliers."""
    theta, rate = 0.7, 1.3
    model = n_four_bar(n, theta, rate)
    out = loop_accelerations(model)
    exact = 9.81 * ((n + 1) / 2 + n) * np.sin(theta) / ((n + 1) / 3 + n)
    names = model.body_names
    for k, name in enumerate(names):
        expected = [0.0, 0.0, -exact if name.startswith("v") else 0.0]
        assert np.allclose(out["angular_acceleration"][k], expected, rtol=0, atol=1e-11)
    assert np.abs(out["residual"]).max() < 1e-11


@pytest.mark.parametrize("tree", ["slider on the rod", "slider on the ground"])
def test_the_sweep_with_closing_joints_agrees_with_the_reference(tree):
    """The IFToMM slider-crank turning at 6 rad/s under gravity (ball, universal, revolute and
    prismatic joints, a prismatic or a universal joint closing): every body's angular
    acceleration, input-point acceleration and joint acceleration as the reference's right-hand
    side gives them, to 1e-10 (measured 4e-12)."""
    model = slider_crank(tree)
    out = loop_accelerations(model)
    prob = _Problem(model)
    ref = prob.evaluate(0.0, prob.initial_state())
    assert np.abs(out["angular_acceleration"] - ref[6]).max() < 1e-10
    assert np.abs(out["input_acceleration"] - ref[5]).max() < 1e-10
    joint = np.array([out["joint_acceleration"][k, i] for k, i, _ in prob.coordinates])
    assert np.abs(joint - ref[13]).max() < 1e-10
    assert np.abs(ref[6]).max() > 10.0               # (it accelerates)
