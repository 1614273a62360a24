"""Geometric stiffening's cost (issue 16), ratios measured in one process, interleaved:

    python benchmarks/stiffening.py

- the three-pendulum per step with its beam stiffened against without (target <= 1.2x);
- seed 000's spin-up to 6 rad/s over 8 s: one stiffened element against the chain of 20 welded
  elements of the paper's beam that was needed before (wall time), and their minima.
"""
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "examples"))

from dttmm import simulate  # noqa: E402
from dttmm.model.chains import three_pendulum  # noqa: E402


def us_per_step(model, steps):
    t0 = time.perf_counter()
    simulate(model, steps * 1e-3, 1e-3, record_every=steps, progress=False)
    return (time.perf_counter() - t0) / steps * 1e6


def stiffening_ratio(pairs=15, steps=4000):
    """Median of interleaved pairs: (stiffened, plain, ratio) us per step of the
    three-pendulum (2 modes per plane)."""
    plain, stiff = three_pendulum(2), three_pendulum(2, stiffening=True)
    us_per_step(plain, 50), us_per_step(stiff, 50)           # compile
    rows = []
    for _ in range(pairs):
        a, b = us_per_step(stiff, steps), us_per_step(plain, steps)
        rows.append((a, b, a / b))
    return tuple(float(np.median([r[i] for r in rows])) for i in range(3))


def spin_up_walls(omega=6.0, t_end=8.0, pairs=3):
    """(one element's wall, 20 elements' wall, ratio, their v_tip minima) over t_end."""
    import spin_up
    one, chain = spin_up.tube(1, 3, omega), spin_up.tube(20, 3, omega, stiffening=False)
    walls, lows = {"one": [], "chain": []}, {}
    for name, model in (("one", one), ("chain", chain)):
        simulate(model, 0.01, 1e-3, progress=False)           # compile
    for _ in range(pairs):
        for name, model in (("one", one), ("chain", chain)):
            t0 = time.perf_counter()
            res = simulate(model, t_end, 1e-3, record_dt=0.01, progress=False)
            walls[name].append(time.perf_counter() - t0)
            lows[name] = float(spin_up.tip_in_hub_frame(model, res)[1].min())
    w1, w20 = float(np.median(walls["one"])), float(np.median(walls["chain"]))
    return w1, w20, w20 / w1, lows


def main():
    a, b, r = stiffening_ratio()
    print(f"three-pendulum: stiffened {a:.2f} us/step, plain {b:.2f}, ratio {r:.3f}")
    w1, w20, ratio, lows = spin_up_walls()
    print(f"spin-up to 6 rad/s, 8 s: one stiffened element {w1:.2f} s, 20 plain elements "
          f"{w20:.2f} s, {ratio:.1f}x; v_tip minima {lows}")


if __name__ == "__main__":
    main()
