"""The paper's three-pendulum: DT-TMM against the independent Newton-Euler reference."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import fitted_order

from dttmm import simulate
from dttmm.model.chains import three_pendulum
from dttmm.reference import simulate_reference
from dttmm.results.result import beam_midpoint_deflection

T_END = 2.0
SAMPLE = 0.01
BEAM = 1


@pytest.fixture(scope="module")
def model_and_reference():
    model = three_pendulum(modes_per_plane=2)
    t = np.arange(int(round(T_END / SAMPLE)) + 1) * SAMPLE
    ref = simulate_reference(model, T_END, method="DOP853", rtol=1e-12, atol=1e-13, t_eval=t)
    return model, ref, beam_midpoint_deflection(model, ref, BEAM)


def errors(model, ref, mid_ref, dt):
    res = simulate(model, T_END, dt, record_every=int(round(SAMPLE / dt)))
    pos = np.abs(res.position_output - ref.position_output).max()
    mid = np.abs(beam_midpoint_deflection(model, res, BEAM) - mid_ref).max()
    return pos, mid, res


def test_reference_midpoint_deflection_is_the_papers(model_and_reference):
    """Notes §6: in-plane peak near 0.7 mm, out of plane a few hundredths of a mm over 2 s."""
    _, _, mid = model_and_reference
    assert 0.6e-3 < np.abs(mid[:, 0]).max() < 0.8e-3
    assert 1e-5 < np.abs(mid[:, 1]).max() < 1e-4


def test_second_order_and_accuracy(model_and_reference):
    model, ref, mid_ref = model_and_reference
    # dt = 5e-4 is not yet asymptotic for the 100 Hz second mode (error ratio 3.0 to the next
    # step, 4.1 and 3.9 after): fit over the three smaller steps
    dts = [2.5e-4, 1.25e-4, 6.25e-5]
    pos, mid = zip(*[errors(model, ref, mid_ref, dt)[:2] for dt in dts])
    pos_order, mid_order = fitted_order(dts, pos), fitted_order(dts, mid)
    fine_pos, fine_mid, res = errors(model, ref, mid_ref, 1e-4)
    peak = np.abs(mid_ref).max()
    print(f"three-pendulum: position errors {['%.2e' % e for e in pos]} (order {pos_order:.3f}), "
          f"mid-point errors {['%.2e' % e for e in mid]} (order {mid_order:.3f}); at dt = 1e-4 "
          f"{fine_pos:.2e} m and {fine_mid / peak:.2%} of the peak deflection")
    assert pos_order == pytest.approx(2.0, abs=0.2)
    assert mid_order == pytest.approx(2.0, abs=0.2)
    assert fine_pos <= 2e-6
    assert fine_mid <= 0.005 * peak
    e = res.total_energy
    assert np.abs(e - e[0]).max() < 1e-6 * res.kinetic.max()


def test_mode_count_converges():
    """1 -> 3 -> 5 modes per plane: the bodies move less and less (notes §6: about 6e-5 m from
    1 to 3 modes, about 1e-6 m from 3 to 5, over 2 s)."""
    runs = [simulate(three_pendulum(modes_per_plane=m), T_END, 2.5e-4, record_every=40)
            for m in (1, 3, 5)]
    d13 = np.abs(runs[0].position_output - runs[1].position_output).max()
    d35 = np.abs(runs[1].position_output - runs[2].position_output).max()
    print(f"mode convergence: 1->3 {d13:.2e} m, 3->5 {d35:.2e} m")
    assert d35 < d13 / 5


def test_example_runs(tmp_path):
    root = Path(__file__).resolve().parents[1]
    out = tmp_path / "tp.csv"
    run = subprocess.run([sys.executable, str(root / "examples" / "three_pendulum.py"),
                          "--t-end", "0.1", "--dt", "5e-4", "--modes", "1", "--csv", str(out),
                          "--plots", str(tmp_path / "figs")], capture_output=True, text=True,
                         check=True)
    assert "wall-time ratio" in run.stdout
    head = out.read_text().splitlines()[0]
    assert head == "t,x2,y2,z2,v_mid,w_mid,x6,y6,z6,energy"
    assert len(list((tmp_path / "figs").glob("fig*.png"))) == 4


def test_assembly_modes_agree():
    """Reduced Riccati (default), reduced direct and full-state Riccati sweeps solve the same
    linear steps: over 1 s they agree to rounding (measured 1e-13 m)."""
    model = three_pendulum(modes_per_plane=2)
    runs = [simulate(model, 1.0, 1e-3, record_every=10, **kw)
            for kw in ({}, dict(method="direct"), dict(full_state=True))]
    for other in runs[1:]:
        assert np.abs(other.position_output - runs[0].position_output).max() < 1e-10
        assert np.abs(other.modal_coordinates - runs[0].modal_coordinates).max() < 1e-12


def test_energy_over_five_seconds():
    """Issue 3: total energy (kinetic, gravity, strain) within 1e-4 of the largest kinetic energy
    over 5 s at dt = 1e-4."""
    res = simulate(three_pendulum(modes_per_plane=2), 5.0, 1e-4, record_every=100)
    e = res.total_energy
    drift = np.abs(e - e[0]).max() / res.kinetic.max()
    print(f"three-pendulum energy drift over 5 s at dt = 1e-4: {drift:.2e}")
    assert drift < 1e-4


@pytest.fixture(scope="module")
def reference_60s():
    """The Newton-Euler reference over 60 s (its peak angular acceleration grows from 75 rad/s^2
    in the first 10 s to 240 in the last: the motion is chaotic, the growth physical)."""
    model = three_pendulum(2)
    return simulate_reference(model, 60.0, method="DOP853", rtol=1e-8, atol=1e-10,
                              t_eval=np.arange(12001) * 0.005)


def long_run_ratios(dt, reference):
    """Peak angular acceleration over the reference's, over the run and over its last 10 s
    against the reference's whole run (the motion is chaotic: the two runs' windows do not
    correspond, their envelopes do), and the energy drift over the largest kinetic energy, of a
    60 s DT-TMM run."""
    res = simulate(three_pendulum(2), 60.0, dt, record_every=int(round(0.005 / dt)))
    last = res.t >= 50.0
    acc, ref = np.abs(res.angular_acceleration), np.abs(reference.angular_acceleration)
    e = res.total_energy
    ratios = (acc.max() / ref.max(), acc[last].max() / ref.max())
    drift = np.abs(e - e[0]).max() / res.kinetic.max()
    print(f"three-pendulum 60 s, dt={dt:g}: peak angular acceleration / reference's {ratios}, "
          f"energy drift {drift:.2e}")
    return ratios, drift


@pytest.mark.slow
def test_sixty_seconds_at_large_dt(reference_60s):
    """dt = 1e-3: no growing oscillation (the peak within 1.5x of the reference's, over the run
    and in its last 10 s); energy drift 2.6e-4 of the largest kinetic energy (bounded, O(dt^2))."""
    ratios, drift = long_run_ratios(1e-3, reference_60s)
    assert max(ratios) < 1.5
    assert drift < 1e-3


@pytest.mark.long
def test_sixty_seconds_at_small_dt(reference_60s):
    """dt = 1e-4 (600 000 steps, ~5 min): measured peak 267 rad/s^2 against the reference's 297,
    energy drift 2.0e-6."""
    ratios, drift = long_run_ratios(1e-4, reference_60s)
    assert max(ratios) < 1.5
    assert drift < 1e-4
