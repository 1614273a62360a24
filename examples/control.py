"""A flexible link slewed by its joint's torque: PD feedback against an LQR designed on
dttmm.linearize, both run in closed loop by DT-TMM.

    python examples/control.py --t-end 2 --dt 1e-3 --csv control.csv --plots figures

The paper's beam 4 (1 m, 20 mm square section, E = 2.5e10 Pa, rho = 3300 kg/m^3) with a
0.5 kg tip mass, on a revolute joint about the vertical (world y, no gravity in the slewing
plane: gravity off), is commanded from rest at 0 to 0.5 rad at t = 0. PD (kp = 20 N m/rad,
kd = 4 N m s/rad, on the joint's angle and rate alone: dttmm.PDTracking, inside the compiled
loop) slews it and leaves the beam ringing. The LQR (on dttmm.linearize's A and B about the
rest state: the joint angle, the beam's modal coordinates and their rates, sampled with a
zero-order hold every control period --dt, scipy.linalg.solve_discrete_are; Q weighs the
angle's error and the modal coordinates, R the torque) feeds back the whole state, held over
each period, as a digital controller does: the run steps one period at a time, resuming from
its checkpoint. Printed: the tip's
largest deflection from the link's line, overall and after 1 s, for both. CSV: t,
angle_pd, angle_lqr, tip_pd, tip_lqr, torque_pd, torque_lqr every period.

Measured (defaults): PD overshoots to 0.60 rad and leaves the tip 0.61 mm off the link's line
after 1 s, 1.2e-3 rad off the command at 2 s; the LQR slews as fast, overshoots to 0.52 rad
and leaves 0.14 mm after 1 s, 8e-5 rad at 2 s (its first 0.1 s ring more: the step command
asks its full torque at once, 15 N m against PD's 11).
"""
import argparse
import sys
from pathlib import Path

import numpy as np

import dttmm

COMMAND = 0.5           # rad
KP, KD = 20.0, 4.0      # the PD's gains, N m/rad and N m s/rad
SUBSTEPS = 10           # DT-TMM steps per control period (the beam's second mode: 134 Hz)


def slewing_link(drive):
    """The beam with its tip mass, clamped to a hub on a revolute joint about world y driven
    by `drive`."""
    side, e, rho = 0.02, 2.5e10, 3300.0
    area = side * side
    system = dttmm.System(gravity=[0.0, 0.0, 0.0])
    # the motor's hub, a small rigid body the joint turns and the beam is clamped to
    system.add(dttmm.RigidBody(mass=0.1, inertia=[1e-4] * 3, inertia_about="mass_center",
                               to_mass_center=[0, 0, 0], to_output=[0, 0, 0], name="hub"),
               dttmm.RevoluteJoint(axis=[0.0, 1.0, 0.0], drive=drive, name="joint"))
    system.add(dttmm.EulerBernoulliBeam(length=1.0, density=rho, area=area,
                                        bending_stiffness=e * side ** 4 / 12.0,
                                        polar_inertia_per_length=rho * area * side * side / 6.0,
                                        name="link"),
               dttmm.FixedHinge(name="clamp"), parent="hub")
    system.add(dttmm.RigidBody(mass=0.5, inertia=[1e-4] * 3, inertia_about="mass_center",
                               to_mass_center=[0, 0, 0], to_output=[0, 0, 0], name="tip"),
               dttmm.FixedHinge(name="weld"), parent="link")
    return system.build()


def tip_deflection(model, result):
    """(T,) the tip's distance from the link's line (its input section's x axis), m."""
    link = model.body_names.index("link")
    arm = result.position_output[:, link] - result.position_input[:, link]
    local = np.einsum("tji,tj->ti", result.rotation[:, link], arm)
    return np.hypot(local[:, 1], local[:, 2])


def lqr_gain(model, dt):
    """K of u = -K (x - x_ref) for the joint's torque held over each period dt: the discrete
    LQR of linearize's A, B about rest, sampled with a zero-order hold (exp([[A, B], [0, 0]] dt)
    gives Ad, Bd; scipy.linalg.solve_discrete_are), so that the sampling is part of the design."""
    from scipy.linalg import expm, solve_discrete_are
    lin = dttmm.linearize(model)
    u = lin.inputs.index("joint.torque0")
    a, b = lin.A, lin.B[:, [u]]
    m = len(lin.states) // 2
    q = np.zeros(2 * m)
    q[lin.states.index("joint.q0")] = 1000.0
    q[[i for i, s in enumerate(lin.states) if s.startswith("eta") and s.endswith("'")]] = 1.0
    q[[i for i, s in enumerate(lin.states) if s.startswith("eta") and "'" not in s]] = 1e4
    q[lin.states.index("joint.q0'")] = 1.0
    block = np.zeros((2 * m + 1, 2 * m + 1))
    block[:2 * m, :2 * m], block[:2 * m, 2 * m:] = a, b
    sampled = expm(block * dt)
    ad, bd = sampled[:2 * m, :2 * m], sampled[:2 * m, 2 * m:]
    r = np.array([[1.0]])
    p = solve_discrete_are(ad, bd, np.diag(q), r)
    return np.linalg.solve(r + bd.T @ p @ bd, bd.T @ p @ ad).ravel(), lin.states


def run_pd(t_end, dt):
    model = slewing_link(dttmm.PDTracking(KP, KD, target=lambda t: COMMAND,
                                          target_rate=lambda t: 0.0))
    result = dttmm.simulate(model, t_end, dt / SUBSTEPS, record_every=SUBSTEPS)
    return model, result, result.t, result.joint_coordinates[:, 0], result.drive_force[:, 0]


def run_lqr(t_end, dt):
    held = [0.0]        # the torque held over the current period (zero-order hold)
    model = slewing_link(dttmm.JointForce(lambda t, q, qd: held[0]))
    gain, names = lqr_gain(slewing_link(None), dt)
    reference = np.zeros(len(names))
    reference[names.index("joint.q0")] = COMMAND
    steps = int(round(t_end / dt))
    checkpoint, parts, torques = None, [], []
    for i in range(steps):
        if checkpoint is None:          # at rest
            state = np.zeros(len(names))
        else:                           # linearize's states: q, eta, then q', eta'
            last = parts[-1]
            state = np.concatenate([[last.joint_coordinates[-1, 0]],
                                    last.modal_coordinates[-1],
                                    [last.joint_rates[-1, 0]], last.modal_velocities[-1]])
        held[0] = float(-gain @ (state - reference))
        torques.append(held[0])
        part = dttmm.simulate(model, (i + 1) * dt, dt / SUBSTEPS, resume=checkpoint,
                              record_every=SUBSTEPS)
        checkpoint = part.checkpoint
        parts.append(part)
    t = np.concatenate([[0.0]] + [p.t[1:] for p in parts])
    angle = np.concatenate([parts[0].joint_coordinates[:1, 0]]
                           + [p.joint_coordinates[1:, 0] for p in parts])
    tip = np.concatenate([tip_deflection(model, parts[0])[:1]]
                         + [tip_deflection(model, p)[1:] for p in parts])
    torque = np.array(torques + torques[-1:])
    return t, angle, tip, torque


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=2.0, help="end time, s (default 2)")
    ap.add_argument("--dt", type=float, default=1e-3,
                    help="time step and control period, s (default 1e-3)")
    ap.add_argument("--csv", help="write t, angle_pd, angle_lqr, tip_pd, tip_lqr, torque_pd, "
                                  "torque_lqr every period")
    ap.add_argument("--plots", help="directory for the figure (PNG)")
    args = ap.parse_args(argv)
    if not (args.t_end > 1.0 and args.dt > 0.0):
        print("error: --t-end must be above 1 s and --dt positive", file=sys.stderr)
        return 2
    model, pd, t, angle_pd, torque_pd = run_pd(args.t_end, args.dt)
    tip_pd = tip_deflection(model, pd)
    t_l, angle_lqr, tip_lqr, torque_lqr = run_lqr(args.t_end, args.dt)
    late = t >= 1.0
    print(f"flexible link slewed to {COMMAND} rad, dt = {args.dt:g} s:")
    for name, angle, tip, torque in (("PD ", angle_pd, tip_pd, torque_pd),
                                     ("LQR", angle_lqr, tip_lqr, torque_lqr)):
        print(f"  {name}: tip deflection max {1e3 * np.abs(tip).max():.3f} mm, after 1 s "
              f"{1e3 * np.abs(tip[late]).max():.4f} mm; angle at the end {angle[-1]:.5f} rad; "
              f"torque max {np.abs(torque).max():.3f} N m")
    if args.csv:
        data = np.column_stack([t, angle_pd, angle_lqr, tip_pd, tip_lqr, torque_pd,
                                torque_lqr])
        np.savetxt(args.csv, data, delimiter=",", comments="", fmt="%.12g",
                   header="t,angle_pd,angle_lqr,tip_pd,tip_lqr,torque_pd,torque_lqr")
        print(f"wrote {args.csv}")
    if args.plots:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        out = Path(args.plots)
        out.mkdir(parents=True, exist_ok=True)
        fig, ax = plt.subplots(1, 3, figsize=(14, 4.2))
        for name, angle, tip, torque in (("PD", angle_pd, tip_pd, torque_pd),
                                         ("LQR", angle_lqr, tip_lqr, torque_lqr)):
            ax[0].plot(t, angle, lw=0.9, label=name)
            ax[1].plot(t, 1e3 * tip, lw=0.9, label=name)
            ax[2].plot(t, torque, lw=0.9, label=name)
        ax[0].set(xlabel="t, s", ylabel="joint angle, rad", title="Slew to 0.5 rad")
        ax[1].set(xlabel="t, s", ylabel="tip deflection, mm",
                  title="Tip's distance from the link's line")
        ax[2].set(xlabel="t, s", ylabel="joint torque, N m", title="Torque")
        for a in ax:
            a.legend()
        fig.suptitle("A flexible link slewed by PD and by an LQR on dttmm.linearize's model")
        fig.tight_layout()
        path = out / "control.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
