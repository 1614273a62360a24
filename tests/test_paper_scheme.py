"""The paper's scheme (scheme="paper": every station point and mass centre with its own Newmark
position history, tied to the rotations at position level; docs/solver.md): it is a consistent,
second-order discretization, and it develops the step-to-step alternating mode that the
project's scheme does not (notes §1, stability trap)."""
import numpy as np
import pytest
from helpers import fitted_order

from dttmm import (BallJoint, DivergenceError, ElasticHinge, Ground, PrescribedMotion,
                   build_chain, simulate)
from dttmm.model.chains import rigid_chain, three_pendulum, unit_link
from dttmm.reference import simulate_reference


def end_error(model, ref, dt, **kw):
    res = simulate(model, ref.t[-1], dt, record_every=int(round(ref.t[-1] / dt)), **kw)
    return np.abs(res.position_output[-1] - ref.position_output[-1]).max()


def test_second_order_rigid_chain():
    model = rigid_chain(3)
    t_end = 1.0
    ref = simulate_reference(model, t_end, rtol=1e-12, atol=1e-13, t_eval=[0.0, t_end])
    dts = [4e-3, 2e-3, 1e-3, 5e-4]
    errors = [end_error(model, ref, dt, scheme="paper") for dt in dts]
    print(f"paper's scheme, 3 links: errors {['%.2e' % e for e in errors]}, "
          f"order {fitted_order(dts, errors):.3f}")
    assert fitted_order(dts, errors) == pytest.approx(2.0, abs=0.1)
    assert errors[-1] < 1e-5


def test_second_order_with_a_beam():
    """The beam's output point carries its own history too (kernels/transfers/beam.py,
    _evaluate)."""
    model = three_pendulum(2)
    t_end = 0.2
    ref = simulate_reference(model, t_end, method="DOP853", rtol=1e-12, atol=1e-13,
                             t_eval=[0.0, t_end])
    dts = [2e-4, 1e-4, 5e-5]          # asymptotic from 2e-4 (the beam mode)
    errors = [end_error(model, ref, dt, scheme="paper") for dt in dts]
    print(f"paper's scheme, three-pendulum: errors {['%.2e' % e for e in errors]}, "
          f"order {fitted_order(dts, errors):.3f}")
    assert fitted_order(dts, errors) == pytest.approx(2.0, abs=0.2)
    assert errors[-1] < 1e-8


def alternating_part(res, t0, half_width=50):
    """Largest step-to-step second difference of the angular accelerations around t0 (recorded
    every step): ~4x the amplitude of an alternating mode, ~h^2 x the third derivative else."""
    i = int(round(t0 / (res.t[1] - res.t[0])))
    seg = res.angular_acceleration[i - half_width:i + half_width]
    return np.abs(seg[2:] - 2 * seg[1:-1] + seg[:-2]).max()


def test_alternating_mode_grows_and_the_run_diverges():
    """3 links at dt = 1e-3 (the notes: diverges at about 8 s): the paper's scheme stops with a
    DivergenceError before 10 s, the alternating part of its accelerations growing by orders of
    magnitude from t = 1 s; the project's scheme stays smooth over the same time."""
    model = rigid_chain(3)
    with pytest.raises(DivergenceError) as caught:
        simulate(model, 10.0, 1e-3, scheme="paper", record_every=1)
    err = caught.value
    paper = err.partial
    assert 3.0 < err.t < 10.0
    assert paper.t[-1] >= err.t - 1.5e-3          # recorded up to the step before
    newmark = simulate(model, 10.0, 1e-3, record_every=1)
    grow = [float(alternating_part(paper, t)) for t in (1.0, 3.0, err.t - 0.5)]
    smooth = [float(alternating_part(newmark, t)) for t in (1.0, 3.0, err.t - 0.5)]
    print(f"diverged at t = {err.t} s; second differences (rad/s^2) paper {grow}, "
          f"project's {smooth}")
    assert grow[1] > 100 * grow[0] and grow[2] > 100 * grow[1]
    assert max(smooth) < 0.1
    # up to where the mode is still small, both schemes describe the same motion
    i = int(round(1.0 / 1e-3))
    assert np.abs(paper.position_output[i] - newmark.position_output[i]).max() < 1e-3


def test_ten_links_at_small_dt():
    """The notes: a 10-link chain at dt = 1e-4 shows angular accelerations 50x too large by 2 s
    (smaller steps make the mode grow faster)."""
    model = rigid_chain(10)
    t_end = 3.0
    runs = {}
    for scheme in ("newmark", "paper"):
        try:
            runs[scheme] = simulate(model, t_end, 1e-4, scheme=scheme, record_every=10)
        except DivergenceError as err:
            runs[scheme] = err.partial
    late = {s: float(np.abs(r.angular_acceleration[r.t > 2.0]).max()) for s, r in runs.items()}
    early = {s: float(np.abs(r.angular_acceleration[r.t < 1.0]).max()) for s, r in runs.items()}
    print(f"10 links, dt = 1e-4: peak angular acceleration before 1 s {early}, after 2 s {late}")
    assert early["paper"] == pytest.approx(early["newmark"], rel=1e-2)
    assert late["paper"] > 50 * late["newmark"]


def test_scope_is_checked():
    with pytest.raises(ValueError, match="hinge 'spring' is elastic"):
        simulate(build_chain([ElasticHinge(1e4, 1e3, name="spring"), unit_link()]), 0.01, 1e-3,
                 scheme="paper")
    hub = PrescribedMotion(position=lambda t: [0.1 * t, 0.0, 0.0],
                           velocity=lambda t: [0.1, 0.0, 0.0])
    moving = build_chain([BallJoint(), unit_link()], ground=Ground(motion=hub))
    with pytest.raises(ValueError, match="fixed ground"):
        simulate(moving, 0.01, 1e-3, scheme="paper")
