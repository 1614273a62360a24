"""The cost of each part of the beam element per step (issue 16), ratios measured in one
process, interleaved (these machines are noisy):

    python benchmarks/beam_parts.py [--pairs 9] [--steps 3000]

One clamped element with a free tip on a hub driven about z (3 bending modes per plane,
gravity), as: the plain beam (its w' and eta'' Jacobian columns written out); with geometric
stiffening; with 2 twist modes (docs/beam.md, "Torsion": the columns are then differenced);
with both; with 2 stretch modes ("Stretch", differenced too); with all three; with an end
torque (differenced, as at a weld).  Each variant's median us per step and its median ratio
to the plain beam's, pair by pair.

Measured (stop 24, 9 pairs of 3000 steps): plain 24.9 us, stiffening 1.02x, twist 1.27x,
stiffening + twist 1.37x, stretch 1.36x, all three 1.57x, end torque 1.29x.  The parts'
own arithmetic is small; most of the cost is the differenced w' and eta'' columns they
switch on (the end torque's 1.29x has the same cause).

Measured again 2026-11-26 (5 pairs, a test run beside it), the element now in the fused
welded-chain loop with the end moment's columns written out: plain 16.2 us, stiffening 1.04x,
twist 1.34x, stiffening + twist 1.45x, stretch 1.47x, all three 1.79x, end torque 1.12x.
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from dttmm import (EulerBernoulliBeam, FixedHinge, Ground, PrescribedMotion,  # noqa: E402
                   build_chain, simulate)


def cantilever(stiffening=False, twist=0, stretch=0, end_torque=False):
    hub = PrescribedMotion.spin_about_axis([0, 0, 1], lambda t: 0.5 * t * t, lambda t: t,
                                           lambda t: 1.0)
    beam = EulerBernoulliBeam(length=1.0, mass_per_length=2.0, bending_stiffness=[60.0, 80.0],
                              polar_inertia_per_length=2e-3, modes_per_plane=3,
                              stiffening=stiffening, torsion_modes=twist,
                              torsional_stiffness=8.0 if twist else None, axial_modes=stretch,
                              axial_stiffness=3000.0 if stretch else None,
                              end_torque=(lambda t: [0.1, 0.0, 0.0]) if end_torque else None)
    return build_chain([FixedHinge(), beam], gravity=[0.0, 0.0, -9.81],
                       ground=Ground(motion=hub))


VARIANTS = {"plain": {}, "stiffening": {"stiffening": True}, "twist (2 modes)": {"twist": 2},
            "stiffening + twist": {"stiffening": True, "twist": 2},
            "stretch (2 modes)": {"stretch": 2},
            "all three": {"stiffening": True, "twist": 2, "stretch": 2},
            "end torque": {"end_torque": True}}


def us_per_step(model, steps):
    t0 = time.perf_counter()
    simulate(model, steps * 1e-3, 1e-3, record_every=steps, progress=False)
    return (time.perf_counter() - t0) / steps * 1e6


def measure(pairs=9, steps=3000):
    """{variant: (median us per step, median ratio to the plain beam's, pair by pair)}."""
    models = {name: cantilever(**kw) for name, kw in VARIANTS.items()}
    for model in models.values():
        us_per_step(model, 20)                                   # compile
    times = {name: [] for name in models}
    for _ in range(pairs):
        for name, model in models.items():
            times[name].append(us_per_step(model, steps))
    plain = np.array(times["plain"])
    return {name: (float(np.median(t)), float(np.median(np.array(t) / plain)))
            for name, t in times.items()}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=9)
    ap.add_argument("--steps", type=int, default=3000)
    args = ap.parse_args(argv)
    for name, (us, ratio) in measure(args.pairs, args.steps).items():
        print(f"{name:20} {us:7.2f} us/step   {ratio:5.2f}x the plain beam")


if __name__ == "__main__":
    main()
