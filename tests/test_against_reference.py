"""DT-TMM against the independent Newton-Euler reference: order, accuracy, long runs."""
import numpy as np
import pytest
from helpers import fitted_order

from dttmm import BallJoint, ElasticHinge, FixedHinge, build_chain, simulate
from dttmm.model.chains import rigid_chain, unit_link
from dttmm.reference import simulate_reference

T_END = 2.0
SAMPLE = 0.02          # compare on a 20 ms grid (a multiple of every dt)
DTS = [4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4]


def reference_on_grid(model, t_end, rtol=1e-12, atol=1e-12):
    t = np.arange(int(round(t_end / SAMPLE)) + 1) * SAMPLE
    return simulate_reference(model, t_end, method="DOP853", rtol=rtol, atol=atol, t_eval=t)


def position_error(model, ref, dt, **kw):
    res = simulate(model, ref.t[-1], dt, record_every=int(round(SAMPLE / dt)), **kw)
    assert np.allclose(res.t, ref.t)
    return np.abs(res.position_output - ref.position_output).max(), res


@pytest.fixture(scope="module", params=[3, 10])
def chain_and_reference(request):
    model = rigid_chain(request.param)
    return request.param, model, reference_on_grid(model, T_END)


def test_second_order_convergence_and_accuracy(chain_and_reference):
    n, model, ref = chain_and_reference
    errors = [position_error(model, ref, dt)[0] for dt in DTS]
    order = fitted_order(DTS, errors)
    fine, _ = position_error(model, ref, 1e-4)
    print(f"N={n}: errors {['%.2e' % e for e in errors]}, order {order:.3f}, "
          f"error at dt=1e-4 {fine:.2e} m")
    assert order == pytest.approx(2.0, abs=0.2)
    assert fine <= 2e-6


def test_direct_and_riccati_agree():
    model = rigid_chain(3)
    a = simulate(model, T_END, 1e-3, method="riccati", record_every=10)
    b = simulate(model, T_END, 1e-3, method="direct", record_every=10)
    c = simulate(model, T_END, 1e-3, method="riccati", full_state=True, record_every=10)
    assert np.abs(a.position_output - b.position_output).max() < 1e-9
    assert np.abs(a.position_output - c.position_output).max() < 1e-9


def mixed_chain():
    """Every hinge kind and the split changes between them: an elastic root (anisotropic,
    damped), a welded pair, a ball joint, an elastic hinge with a rest rotation."""
    from test_analytic import body_b, rot_z
    return build_chain([
        ElasticHinge([2e4, 3e4, 4e4], 2e3, translational_damping=5.0, rotational_damping=0.5),
        unit_link(angular_velocity=[0.3, 1.0, -0.5]), FixedHinge(rotation=rot_z(0.4)), body_b(),
        BallJoint(), unit_link(angular_velocity=[0, 0, 1.0]),
        ElasticHinge(1e4, [500, 800, 1000], rotation=rot_z(-0.3)), body_b()])


def test_mixed_chain_convergence_both_methods():
    model = mixed_chain()
    ref = reference_on_grid(model, 1.0, rtol=1e-12, atol=1e-13)
    dts = [1e-3, 5e-4, 2.5e-4, 1.25e-4]
    errors = {"riccati": [], "direct": []}
    for dt in dts:
        for method in errors:
            err, res = position_error(model, ref, dt, method=method)
            errors[method].append(err)
    force_error = np.abs(res.force - ref.force).max() / np.abs(ref.force).max()
    for method, errs in errors.items():
        print(f"mixed chain, {method}: errors {['%.2e' % e for e in errs]}, "
              f"order {fitted_order(dts, errs):.3f}")
        assert fitted_order(dts, errs) == pytest.approx(2.0, abs=0.2)
        assert errs[-1] < 3e-6
    assert force_error < 1e-3     # hinge loads, relative to their peak, at dt = 1.25e-4


def falling_from_upright():
    """Two links standing up (body x along world +y), leaning 0.1 rad towards +z, falling in 3D:
    the links' x axes pass through world z, where the x-y-z angle theta_y is -90 deg."""
    c, s = np.cos(0.1), np.sin(0.1)
    up = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    lean = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])      # about world x: +y tilts to +z
    rot = lean @ up
    return build_chain([BallJoint(), unit_link(rotation=rot, angular_velocity=[0.3, 0.0, 0.01]),
                        BallJoint(), unit_link(rotation=rot)])


def test_order_through_the_xyz_angle_singularity():
    model = falling_from_upright()
    ref = reference_on_grid(model, 1.5)
    theta_y = np.degrees(ref.xyz_angles[:, :, 1])
    assert np.abs(np.abs(theta_y) - 90.0).min() < 1.0        # the motion does pass through +-90
    dts = DTS[1:]
    errors = [position_error(model, ref, dt)[0] for dt in dts]
    order = fitted_order(dts, errors)
    print(f"through theta_y = 90 deg: errors {['%.2e' % e for e in errors]}, order {order:.3f}")
    assert order == pytest.approx(2.0, abs=0.2)


LONG_RUN = 60.0


@pytest.fixture(scope="module")
def long_references():
    """60 s references, sampled every 5 ms like the DT-TMM runs.  The motion is chaotic: the
    reference's own peak angular acceleration over 60 s moves with its tolerance (10 links:
    1.22e3 at rtol 1e-9, 1.45e3 at 1e-12, 1.7e3 at 1e-8), so only gross growth is detectable."""
    t = np.arange(int(round(LONG_RUN / 0.005)) + 1) * 0.005
    return {n: simulate_reference(rigid_chain(n), LONG_RUN, method="DOP853", rtol=1e-9,
                                  atol=1e-11, t_eval=t) for n in (3, 10)}


def long_run(n_links, dt, references, scheme="newmark"):
    """Peak angular acceleration over the reference's, and the largest energy change over the
    largest kinetic energy, for a 60 s DT-TMM run."""
    res = simulate(rigid_chain(n_links), LONG_RUN, dt, record_every=int(round(0.005 / dt)),
                   scheme=scheme)
    ref = references[n_links]
    ratio = np.abs(res.angular_acceleration).max() / np.abs(ref.angular_acceleration).max()
    e = res.total_energy
    drift = np.abs(e - e[0]).max() / res.kinetic.max()
    print(f"N={n_links} dt={dt:g} {scheme}: peak angular acceleration / reference {ratio:.3f}, "
          f"energy drift {drift:.2e}")
    return ratio, drift


@pytest.mark.slow
@pytest.mark.parametrize("n_links", [3, 10])
def test_long_runs_stay_bounded_at_small_dt(n_links, long_references):
    """60 s at dt = 1e-4: no growing oscillation (the largest angular acceleration within 1.5x
    of the reference's) and the energy within 1e-4 of the largest kinetic energy."""
    ratio, drift = long_run(n_links, 1e-4, long_references)
    assert ratio < 1.5
    assert drift < 1e-4


@pytest.mark.slow
def test_long_run_three_links_at_large_dt(long_references):
    ratio, drift = long_run(3, 1e-3, long_references)
    assert ratio < 1.5
    assert drift < 1e-3     # see the next test for the 1e-4 bound


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="at dt = 1e-3 the whip events (angular accelerations of "
                   "2e2 rad/s^2 for 3 links, 1e3 for 10) are under-resolved by a fixed-step "
                   "second-order method: each event adds an energy error (3 links: 2.3e-4, 10 "
                   "links: 1.3e-3 of the largest kinetic energy over 60 s, flat between events, "
                   "so no drift); the 10-link peak acceleration is 1.4x-1.8x the reference's, "
                   "moving with rounding (the motion is chaotic).  The energy-momentum scheme "
                   "meets both bounds (next test)")
@pytest.mark.parametrize("n_links", [3, 10])
def test_long_runs_energy_bound_at_large_dt(n_links, long_references):
    ratio, drift = long_run(n_links, 1e-3, long_references)
    assert ratio < 1.5 and drift < 1e-4


@pytest.mark.slow
@pytest.mark.parametrize("n_links", [3, 10])
def test_long_runs_at_large_dt_energy_momentum(n_links, long_references):
    """The energy-momentum scheme at dt = 1e-3 over 60 s: energy conserved throughout (to the
    Newton tolerance), no growth of the largest angular acceleration.  The motion is chaotic:
    the 10-link peak, 1.56x the reference's on one machine, was under 1.5x on another with the
    same code (rounding, amplified), and the reference's own peak spans 1.4x across its
    tolerances (long_references); a growing oscillation would be orders of magnitude, so the
    bound is 2x."""
    ratio, drift = long_run(n_links, 1e-3, long_references, scheme="energy_momentum")
    assert ratio < 2.0
    assert drift < 1e-4
