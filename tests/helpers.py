"""Small measurement helpers for the tests (no physics here)."""
import numpy as np


def crossing_period(t, x):
    """Mean period of a signal from its upward zero crossings (linear interpolation)."""
    x = np.asarray(x) - np.mean(x)
    i = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
    tc = t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])
    assert len(tc) >= 3, "too few crossings to measure a period"
    return (tc[-1] - tc[0]) / (len(tc) - 1)


def fitted_order(dts, errors):
    return np.polyfit(np.log(dts), np.log(errors), 1)[0]


def output_errors_against_reference(model, steps, t_end=1.0):
    """DT-TMM's largest output-point error at t_end against the Newton-Euler reference
    (rtol 1e-11, atol 1e-13), one per step of `steps`."""
    from dttmm import simulate, simulate_reference
    t = np.linspace(0.0, t_end, 11)
    ref = simulate_reference(model, t_end, rtol=1e-11, atol=1e-13, t_eval=t)
    return [np.abs(simulate(model, t_end, h, t_eval=t).position_output[-1]
                   - ref.position_output[-1]).max() for h in steps]


def energy_drift(model, t_end, dt):
    """A DT-TMM run's largest |E - E(0)| (kinetic + potential) over its default samples, as a
    fraction of its largest kinetic energy."""
    from dttmm import simulate
    result = simulate(model, t_end, dt)
    energy = result.kinetic + result.potential
    return np.abs(energy - energy[0]).max() / result.kinetic.max()


def rot_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def fitted_frequencies(t, x, count, span=0.05):
    """Angular frequencies of the count strongest components of a signal, one at a time: the
    peak of the windowed spectrum of what the components found so far leave unexplained starts
    each new one, then every frequency is refined by scanning around it (the amplitudes, cosine
    and sine of every component and a constant, fitted linearly at each trial)."""
    t = np.asarray(t)
    x = np.asarray(x)
    freqs = 2 * np.pi * np.fft.rfftfreq(8 * len(x), t[1] - t[0])

    def fit(w):
        cols = [np.ones_like(t)] + [f(wi * t) for wi in w for f in (np.cos, np.sin)]
        a = np.column_stack(cols)
        return a @ np.linalg.lstsq(a, x, rcond=None)[0] - x

    omega = []
    for _ in range(count):
        rest = -fit(omega)
        spec = np.abs(np.fft.rfft((rest - rest.mean()) * np.hanning(len(x)), n=8 * len(x)))
        omega.append(freqs[int(np.argmax(spec[1:])) + 1])
        for width in (span, span / 20, span / 400):
            for k in range(len(omega)):
                grid = omega[k] * (1 + np.linspace(-width, width, 201))
                costs = [np.linalg.norm(fit(omega[:k] + [g] + omega[k + 1:])) for g in grid]
                omega[k] = grid[int(np.argmin(costs))]
    return np.sort(omega)


def driven_arm_on_two_elements(**beam):
    """Two welded stiffened elements with 2 modes per plane and 2 twist modes on a hub driven
    about z, a body on an arm welded to the tip (its weight twists the beam), gravity -z;
    beam: further EulerBernoulliBeam arguments for both elements (e.g. stretch modes).  The
    order tests of test_torsion and test_stretch."""
    from dttmm import (EulerBernoulliBeam, FixedHinge, Ground, PrescribedMotion, RigidBody,
                       build_chain)
    hub = PrescribedMotion.spin_about_axis([0, 0, 1], lambda t: 1.5 * t * t, lambda t: 3.0 * t,
                                           lambda t: 3.0)
    parts = []
    for _ in range(2):
        parts += [FixedHinge(), EulerBernoulliBeam(
            length=0.5, mass_per_length=1.0, bending_stiffness=[30.0, 40.0],
            polar_inertia_per_length=5e-3, modes_per_plane=2, torsion_modes=2,
            torsional_stiffness=2.0, stiffening=True, **beam)]
    arm = RigidBody(mass=0.2, inertia=np.diag([1e-3, 2e-3, 2e-3]), inertia_about="mass_center",
                    to_mass_center=(0.0, 0.2, 0.0), to_output=(0.0, 0.2, 0.0))
    parts += [FixedHinge(), arm]
    return build_chain(parts, gravity=[0.0, 0.0, -9.81], ground=Ground(motion=hub))


def energy_gaps_with_an_arm(beam, gravity, steps=(1e-3, 5e-4), t_end=0.5):
    """A cantilever of `beam` with a 0.5 kg body on an arm welded across its tip (its mass
    centre 0.3 m off the axis), released under `gravity`, run t_end at each step: per run the
    largest change of kinetic plus potential energy over the largest kinetic energy, and the
    runs.  The energy tests of test_torsion and test_stretch."""
    from dttmm import FixedHinge, RigidBody, build_chain, simulate
    arm = RigidBody(mass=0.5, inertia=np.diag([1e-3, 2e-3, 2e-3]), inertia_about="mass_center",
                    to_mass_center=(0.0, 0.3, 0.0), to_output=(0.0, 0.3, 0.0))
    model = build_chain([FixedHinge(), beam, FixedHinge(), arm], gravity=gravity)
    runs = [simulate(model, t_end, h) for h in steps]
    gaps = [np.abs(r.kinetic + r.potential - r.kinetic[0] - r.potential[0]).max()
            / r.kinetic.max() for r in runs]
    return gaps, runs


def fused_and_general(monkeypatch, model, t_end, dt, loop, **kwargs):
    """The same run through the fused loop named `loop` (result.info["loop"]) and through the
    general loop (run_tables.FUSED_BALL_CHAIN = False), checking which loop each took."""
    from dttmm import simulate
    from dttmm.solving import run_tables
    fused = simulate(model, t_end, dt, **kwargs)
    monkeypatch.setattr(run_tables, "FUSED_BALL_CHAIN", False)
    general = simulate(model, t_end, dt, **kwargs)
    monkeypatch.setattr(run_tables, "FUSED_BALL_CHAIN", True)
    assert fused.info["loop"] == loop and general.info["loop"] == "general"
    return fused, general


def rot_y(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def joints_arm(drive=None, gravity=(0.0, -9.81, 0.0), slide_axis=(1.0, 0.0, 0.0), slide=None,
               body4=None, slide_position=0.0):
    """The joints' arm (tests/test_joints.py): revolute (world y), revolute (link 1's z),
    universal (link 2's z, link 3's y), prismatic (link 3's slide_axis) with `slide` (default
    a spring-damper 50 N/m, 0.5 N s/m); joint 1 turning at 0.5 rad/s under `drive`; body4
    the slider (default 0.5 kg, inertia 0.01 about its mass centre at its input point)."""
    from dttmm import (PrismaticJoint, RevoluteJoint, RigidBody, SpringDamper, System,
                       UniversalJoint)
    from dttmm.model.chains import unit_link
    system = System(gravity=gravity)
    system.add(unit_link(name="link1"), RevoluteJoint(axis=[0, 1, 0], rate=0.5, drive=drive,
                                                      name="joint1"))
    system.add(unit_link(name="link2"), RevoluteJoint(axis=[0, 0, 1], name="joint2"),
               parent="link1")
    system.add(unit_link(name="link3"), UniversalJoint(axis1=[0, 0, 1], axis2=[0, 1, 0],
                                                       name="joint3"), parent="link2")
    system.add(body4 if body4 is not None else
               RigidBody(mass=0.5, inertia=0.01, inertia_about="mass_center", name="body4"),
               PrismaticJoint(axis=list(slide_axis), position=slide_position, name="joint4",
                              drive=SpringDamper(50.0, 0.5) if slide is None else slide),
               parent="link3")
    return system.build()
