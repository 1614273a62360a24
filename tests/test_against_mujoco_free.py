"""dttmm against MuJoCo (issue 67): a free-floating 5-link chain spun without gravity, and a chain
of 20 capsules dropped flat onto the ground.  The MuJoCo runs are data (tests/data/
mujoco_contact.py wrote them, MuJoCo 3.17.0: RK4 at 1e-5 s and 1e-4 s; its header gives the
geometry, which the data also carry): the tests need no MuJoCo.

The free chain: a free joint and ball joints, spun rigidly at w = (0.4, -0.3, 2) rad/s with its
root moving at (0.1, 0.2, -0.05) m/s, then left to itself for 2 s; MuJoCo's own error is ~8e-11 m
(its RK4 is of second order on rotations: the data's header).  The drop: 20 links on ball
joints, the first on a free joint, each a capsule of 0.02 m radius, from 0.1 m onto the plane
z = 0 with friction 0.5; at rest from 0.2 s.  The two contact laws differ (MuJoCo's soft
constraint against dttmm's compliant law, docs/contact.md): the fall before the strike and the
rest after it are the same physics, the strike is not."""
from pathlib import Path

import numpy as np

from dttmm import BallJoint, FreeJoint, RigidBody, build_chain, simulate
from dttmm.elements.joints import rotation_about
from dttmm.model.chains import capsule_chain
from dttmm.results.result import momenta

DATA = Path(__file__).resolve().parent / "data"


def _free_chain():
    g = np.load(DATA / "mujoco_free_chain.npz")
    links = []
    for k in range(int(g["geo_n_links"])):
        body = RigidBody(mass=float(g["geo_mass"]), inertia=g["geo_j_c"],
                         inertia_about="mass_center", to_mass_center=g["geo_l_ic"],
                         to_output=g["geo_l_io"], name=f"link{k}",
                         rotation=rotation_about([0, 0, 1.0], float(g["geo_turn"]) * k),
                         angular_velocity=g["geo_omega"])
        joint = (FreeJoint(position=g["geo_position"], velocity=g["geo_velocity"]) if k == 0
                 else BallJoint())
        links += [joint, body]
    return build_chain(links, gravity=list(g["geo_gravity"])), g


def test_the_free_chain_moves_as_mujocos_and_holds_its_momenta():
    """Every link's input and output point over 2 s against MuJoCo's: the error falls at order
    2 in the step (fitted over dt = 2, 1, 0.5 ms; measured 9.6e-6, 2.4e-6, 6.0e-7 m), and
    Richardson's extrapolation of three runs (richardson=3) meets MuJoCo to 5e-10 m (measured
    1.4e-10, MuJoCo's own error ~8e-11).  The linear and angular momentum (about the origin),
    which nothing changes, are held at order 2 in the step too (the Newmark step holds them
    to O(dt^2): 1.4e-5 kg m/s and 1.7e-5 kg m^2/s at 1 ms, of 10.3 and 13.0)."""
    model, g = _free_chain()
    points = np.concatenate([g["position_input"], g["position_output"]], axis=1)
    steps = (2e-3, 1e-3, 5e-4)
    errors, drifts = [], []
    for dt in steps:
        result = simulate(model, 2.0, dt, record_every=int(round(0.02 / dt)))
        assert np.allclose(result.t, g["t"], atol=1e-12)
        ours = np.concatenate([result.position_input, result.position_output], axis=1)
        errors.append(np.abs(ours - points).max())
        _, _, linear, angular = momenta(model, result)
        drifts.append(max(np.abs(linear - g["linear_momentum"][0]).max(),
                          np.abs(angular - g["angular_momentum"][0]).max()))
    for values in (errors, drifts):
        order = np.polyfit(np.log(steps), np.log(values), 1)[0]
        assert 1.9 < order < 2.1, (values, order)
    assert errors[1] < 5e-6 and drifts[1] < 3e-5
    best = simulate(model, 2.0, 2e-3, record_every=10, richardson=3)
    ours = np.concatenate([best.position_input, best.position_output], axis=1)
    assert np.abs(ours - points).max() < 5e-10


def test_the_high_order_scheme_runs_the_free_chain_to_mujocos_accuracy():
    """scheme="dop853" on the free chain (its root on the free joint: the reduced tree sweep's
    free base, kernels/stepping/tree.py; the flight integrated with the rotations): at rtol
    1e-10 every point meets MuJoCo's to 5e-10 m (MuJoCo's own error ~8e-11), and its momenta
    are held to 1e-9 (nothing changes them; the scheme holds them to its tolerance)."""
    model, g = _free_chain()
    points = np.concatenate([g["position_input"], g["position_output"]], axis=1)
    result = simulate(model, 2.0, scheme="dop853", rtol=1e-10, atol=1e-12, t_eval=g["t"])
    assert result.info["loop"] == "runge-kutta (ball-tree)"
    ours = np.concatenate([result.position_input, result.position_output], axis=1)
    assert np.abs(ours - points).max() < 5e-10
    _, _, linear, angular = momenta(model, result)
    assert np.abs(linear - linear[0]).max() < 1e-9 and np.abs(angular - angular[0]).max() < 1e-9
    assert np.abs(linear[0] - g["linear_momentum"][0]).max() < 1e-12


def test_the_dropped_chain_falls_and_rests_as_mujocos():
    """20 capsule links dropped flat: before the strike (t < 0.12 s) every input point falls as
    MuJoCo's, to 1e-9 m; at rest (0.6 s) the chain lies straight where MuJoCo's lies (x and y
    to 1e-7 m) and every point's height is the radius less the contact's compression, within
    the two laws' compressions of MuJoCo's (ours m g / (2 k) = 5e-7 m, MuJoCo's 1.5e-7 to
    2e-7 m)."""
    g = np.load(DATA / "mujoco_chain_drop.npz")
    n, radius = int(g["geo_n_links"]), float(g["geo_radius"])
    model = capsule_chain(n, length=float(g["geo_l_io"][0]), radius=radius,
                          mass=float(g["geo_mass"]), height=float(g["geo_height"]),
                          contact_time=1e-3, restitution=0.01,
                          friction=float(g["geo_friction"]))
    np.testing.assert_allclose(model.body_mass_center_inertia[0], g["geo_j_c"])
    result = simulate(model, 0.6, 5e-5, record_every=200)
    assert np.allclose(result.t, g["t"][:61], atol=1e-12)
    falling = result.t < 0.12
    np.testing.assert_allclose(result.position_input[falling],
                               g["position_input"][:61][falling], atol=1e-9)
    rest = np.concatenate([result.position_input[-1], result.position_output[-1]])
    theirs = np.concatenate([g["position_input"][60], g["position_output"][60]])
    np.testing.assert_allclose(rest[:, :2], theirs[:, :2], atol=1e-7)
    ours_in = radius - 9.81 * float(g["geo_mass"]) / (2 * 0.1 * (np.pi / 1e-3) ** 2)
    assert np.all(np.abs(rest[:, 2] - ours_in) < 1e-7)
    assert np.all(np.abs(rest[:, 2] - theirs[:, 2]) < 1e-6)
    assert np.abs(result.velocity_input[-1]).max() < 1e-5
