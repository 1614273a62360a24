"""Trees of rigid bodies and beams joined by ball joints: the leaves-to-root Riccati sweep
(kernels/stepping/tree.py) against the chain's sweep, conservation laws, and size."""
import numpy as np
import pytest

from dttmm import BallJoint, ElasticHinge, FixedHinge, System, simulate
from dttmm.model.chains import (TURNED_ABOUT_Y, binary_tree, five_link_tree, rigid_chain,
                          three_pendulum, unit_link)
from dttmm.model.model import Model
from dttmm.reference import simulate_reference
from dttmm.solving import run_plan
from dttmm.solving import run_tables

def angular_momentum(model, res):
    """(T, 3) total angular momentum about the world origin from the recorded state."""
    p = model.body_params
    rho_c = np.einsum("tkij,kj->tki", res.rotation, p[:, 1:4])
    v_c = res.velocity_input + np.cross(res.angular_velocity, rho_c)
    j_c = np.einsum("tkij,kjl,tkml->tkim", res.rotation, model.body_mass_center_inertia,
                    res.rotation)
    spin = np.einsum("tkij,tkj->tki", j_c, res.angular_velocity)
    orbital = p[:, 0][None, :, None] * np.cross(res.position_mass_center, v_c)
    return (orbital + spin).sum(axis=1)


@pytest.mark.parametrize("make, t_end, dt", [(lambda: rigid_chain(5), 1.0, 1e-3),
                                             (lambda: three_pendulum(), 0.2, 1e-4)])
def test_the_tree_sweep_on_a_chain_is_the_chain_sweep(make, t_end, dt, monkeypatch):
    """A chain is a tree: the leaves-to-root sweep and the chain's root-to-tip sweep solve the
    same linear step, so the runs agree to rounding; the general loop's tree mode too."""
    model = make()
    chain = simulate(model, t_end, dt)
    monkeypatch.setattr(Model, "is_chain", property(lambda self: False))
    run_plan.forget(model)          # (its prepared runs are the chain's)
    tree = simulate(model, t_end, dt)
    monkeypatch.setattr(run_tables, "FUSED_BALL_CHAIN", False)
    general = simulate(model, t_end, dt)
    assert chain.info["loop"] == "ball-chain" and tree.info["loop"] == "ball-tree"
    assert general.info["loop"] == "general" and general.info["mode"] == "riccati-tree"
    scale = np.abs(chain.position_output).max()
    for other in (tree, general):
        assert np.abs(other.position_output - chain.position_output).max() < 1e-12 * scale
        assert np.abs(other.force - chain.force).max() < 1e-9 * np.abs(chain.force).max()
        np.testing.assert_allclose(other.total_energy, chain.total_energy, rtol=0, atol=1e-11)


def test_tree_conserves_energy_and_vertical_angular_momentum():
    """The issue's tree, undriven and undamped, 5 s at dt = 1e-4: the energy drifts by at most
    1e-6 of the largest kinetic energy and the angular momentum about the vertical axis through
    the root (a ball joint at the origin, gravity along -y) is conserved to the same order."""
    model = five_link_tree()
    res = simulate(model, 5.0, 1e-4, record_every=100)
    e = res.total_energy
    k_max = res.kinetic.max()
    drift = np.abs(e - e[0]).max() / k_max
    l_y = angular_momentum(model, res)[:, 1]
    l_drift = np.abs(l_y - l_y[0]).max() / max(np.abs(angular_momentum(model, res)).max(), 1e-12)
    print(f"tree: energy drift {drift:.2e} of the largest kinetic energy {k_max:.3g} J; "
          f"L_y drift {l_drift:.2e} relative")
    assert k_max > 1.0            # the tree really moves (it falls)
    assert drift < 1e-6
    assert l_drift < 1e-6
    # the branches stay joined at link 1's output point
    np.testing.assert_allclose(res.position_input[:, 1], res.position_output[:, 0], atol=1e-13)
    np.testing.assert_allclose(res.position_input[:, 3], res.position_output[:, 0], atol=1e-13)
    np.testing.assert_allclose(res.position_input[:, 4], res.position_output[:, 3], atol=1e-13)


def test_binary_tree_of_1023_links():
    """Depth 10, 1 s in the Riccati mode: energy within 1e-4 of the largest kinetic energy."""
    model = binary_tree(10)
    assert model.n_bodies == 1023
    assert np.array_equal(model.parent[1:], (np.arange(1, 1023) - 1) // 2)
    res = simulate(model, 1.0, 1e-3, record_every=50)
    drift = np.abs(res.total_energy - res.total_energy[0]).max() / res.kinetic.max()
    print(f"binary tree, 1023 links: energy drift {drift:.2e}, wall {res.wall_time:.2f} s")
    assert res.info["loop"] == "ball-tree"
    assert drift < 1e-4


def test_what_trees_do_not_run_is_refused():
    tree = five_link_tree()
    with pytest.raises(ValueError, match="direct.*does not extend to .*tree.*riccati"):
        simulate(tree, 0.01, 1e-3, method="direct")
    with pytest.raises(ValueError, match="energy_momentum.*tree"):
        simulate(tree, 0.01, 1e-3, scheme="energy_momentum")


def _beam():
    from dttmm import EulerBernoulliBeam
    return EulerBernoulliBeam(length=1.0, density=3300.0, area=4e-4, bending_stiffness=333.3,
                              polar_inertia_per_length=0.00088, name="beam")


def test_a_tree_with_an_elastic_hinge_matches_the_reference():
    """An elastic hinge on a branch (the full-state sweep: an affine element, LOCKED at the
    consistent start) converges at order 2 to the independent reference."""
    system = System(gravity=[0.0, -9.81, 0.0])
    system.add(unit_link(name="a"), BallJoint())
    system.add(unit_link(name="b", angular_velocity=[0.0, 0.3, 0.0]), BallJoint(), parent="a")
    system.add(unit_link(name="c", rotation=TURNED_ABOUT_Y),
               ElasticHinge(2e4, 300.0, rotation=TURNED_ABOUT_Y, name="spring"), parent="a")
    system.add(unit_link(name="d"), BallJoint(), parent="c")
    model = system.build()
    steps = np.array([1e-3, 5e-4])
    runs = [simulate(model, 0.5, dt, record_every=int(round(0.01 / dt))) for dt in steps]
    assert runs[0].info["mode"] == "riccati-joints"
    ref = simulate_reference(model, 0.5, t_eval=runs[0].t, rtol=1e-12, atol=1e-12)
    errors = [np.abs(r.position_output - ref.position_output).max() for r in runs]
    assert abs(np.log(errors[0] / errors[1]) / np.log(2.0) - 2.0) < 0.2, errors
    assert errors[-1] < 1e-5


def test_the_full_state_tree_sweep_is_the_reduced_one():
    """The same tree through the reduced sweep (fused loop) and through the full-state sweep
    (general loop, an articulated-body step per ball joint): the same linear step, solved two
    ways (docs/assembly.md, "Trees" and "Trees with joints")."""
    tree = five_link_tree()
    reduced = simulate(tree, 0.5, 1e-3)
    full = simulate(tree, 0.5, 1e-3, full_state=True)
    assert (reduced.info["mode"], full.info["mode"]) == ("riccati-tree", "riccati-joints")
    np.testing.assert_allclose(full.position_output, reduced.position_output, rtol=0, atol=1e-11)
    np.testing.assert_allclose(full.angular_velocity, reduced.angular_velocity, rtol=0,
                               atol=1e-10)
    np.testing.assert_allclose(full.force, reduced.force, rtol=0, atol=1e-8)


def test_a_tree_with_welds_matches_the_reference():
    """Fixed hinges in a tree (the full-state sweep): welded bodies move with their parents
    exactly and the whole converges at order 2 to the independent reference."""
    turn = np.array([[np.cos(0.5), -np.sin(0.5), 0], [np.sin(0.5), np.cos(0.5), 0], [0, 0, 1]])
    system = System(gravity=[0.0, -9.81, 0.0])
    system.add(unit_link(name="a"), BallJoint())
    system.add(unit_link(name="b"), FixedHinge(rotation=turn, name="weld_b"), parent="a")
    system.add(unit_link(name="c", angular_velocity=[0.0, 0.4, 0.2]), BallJoint(), parent="b")
    system.add(unit_link(name="d", rotation=TURNED_ABOUT_Y), BallJoint(), parent="a")
    system.add(unit_link(name="e"), FixedHinge(name="weld_e"), parent="d")
    model = system.build()
    steps = np.array([1e-3, 5e-4])
    runs = [simulate(model, 1.0, dt, record_every=int(round(0.01 / dt))) for dt in steps]
    assert runs[0].info["mode"] == "riccati-joints"
    relative = np.einsum("tji,tjk->tik", runs[-1].rotation[:, 0], runs[-1].rotation[:, 1])
    assert np.abs(relative - turn).max() < 1e-12
    ref = simulate_reference(model, 1.0, t_eval=runs[0].t, rtol=1e-12, atol=1e-12)
    errors = [np.abs(r.position_output - ref.position_output).max() for r in runs]
    assert abs(np.log(errors[0] / errors[1]) / np.log(2.0) - 2.0) < 0.2, errors
    assert errors[-1] < 1e-5


def test_tree_against_the_newton_euler_reference():
    """The issue's tree over 2 s against the independent Newton-Euler reference (global
    equations, DOP853 at rtol 1e-11): second order (fitted slope 2 +- 0.2 over dt <= 5e-4) and
    within 2e-6 m at dt = 1e-4."""
    from dttmm.reference import simulate_reference
    from helpers import fitted_order
    model = five_link_tree()
    t_eval = np.linspace(0.0, 2.0, 201)
    ref = simulate_reference(model, 2.0, rtol=1e-11, atol=1e-13, t_eval=t_eval)
    dts = [5e-4, 2.5e-4, 1.25e-4]
    errors = []
    for dt in dts:
        res = simulate(model, 2.0, dt, record_every=int(round(0.01 / dt)))
        assert np.allclose(res.t, t_eval)
        errors.append(np.abs(res.position_output - ref.position_output).max())
    order = fitted_order(dts, errors)
    at_1e4 = np.abs(simulate(model, 2.0, 1e-4, record_every=100).position_output
                    - ref.position_output).max()
    print(f"tree vs reference: errors {errors} m, order {order:.3f}; at dt = 1e-4 {at_1e4:.2e} m")
    assert 1.8 < order < 2.2
    assert at_1e4 < 2e-6


def test_tree_example(tmp_path):
    import subprocess
    import sys
    from pathlib import Path
    root = Path(__file__).resolve().parents[1]
    out_csv = tmp_path / "tree.csv"
    run = subprocess.run([sys.executable, str(root / "examples" / "tree.py"), "--t-end", "0.05",
                          "--dt", "1e-3", "--csv", str(out_csv), "--plots", str(tmp_path)],
                         capture_output=True, text=True, check=True)
    assert "energy drift" in run.stdout and "ball-tree" in run.stdout
    rows = np.loadtxt(out_csv, delimiter=",", skiprows=1)
    head = open(out_csv).readline().strip().split(",")
    assert head == ["t"] + [f"{c}{k}" for k in range(1, 6) for c in "xyz"]
    assert rows.shape == (6, 16)
    np.testing.assert_allclose(rows[0, 1:], [1, 0, 0, 2, 0, 0, 3, 0, 0, 1, 0, -1, 1, 0, -2],
                               atol=1e-12)
    assert (tmp_path / "tree.png").stat().st_size > 1000
    direct = subprocess.run([sys.executable, str(root / "examples" / "tree.py"), "--t-end",
                             "0.01", "--dt", "1e-3", "--method", "direct"], capture_output=True,
                            text=True)
    assert direct.returncode == 2 and "method='direct'" in direct.stderr


def test_a_weld_on_a_beams_end_in_a_tree_matches_the_reference():
    """A body welded to a beam's end, beside a ball-joint branch there: its frame is the end
    section's (step.py::_welded), the steps iterate, and the whole converges at order 2."""
    system = System(gravity=[0.0, -9.81, 0.0])
    system.add(_beam(), BallJoint())
    system.add(unit_link(name="welded"), FixedHinge(name="weld"), parent="beam")
    system.add(unit_link(name="hanging", angular_velocity=[0.0, 0.3, 0.2]), BallJoint(),
               parent="beam")
    model = system.build()
    steps = np.array([1e-3, 5e-4])
    runs = [simulate(model, 0.5, dt, record_every=int(round(0.01 / dt))) for dt in steps]
    assert runs[0].info["newton_iterations_used"] >= 1
    ref = simulate_reference(model, 0.5, t_eval=runs[0].t, rtol=1e-12, atol=1e-12)
    errors = [np.abs(r.position_output - ref.position_output).max() for r in runs]
    assert abs(np.log(errors[0] / errors[1]) / np.log(2.0) - 2.0) < 0.2, errors   # 2.00
    assert errors[-1] < 1e-5                                                     # 3.5e-6 m
