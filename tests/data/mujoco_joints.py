"""Independent MuJoCo reference runs for dttmm's CylindricalJoint and PlanarJoint, the data
tests/test_cylindrical_joint.py and tests/test_planar_joint.py compare with.  Writes, beside
this file,

    mujoco_cylindrical.npz     a carrier on a cylindrical joint + a link
    mujoco_planar.npz          a carrier on a planar joint (slide, slide, hinge) + a link

subsampled every 10 ms (101 samples over 1 s; a few KB), from a run at dt = 1e-5 with RK4, and
the run's own error estimates (against dt/2 and 2 dt).  The tests read the .npz only: they need
no MuJoCo (this script skips, saying so, without it).

Run:  python tests/data/mujoco_joints.py [cylindrical|planar]   (MuJoCo 3 or later; ~10 s;
      the committed files: MuJoCo 4.0.1; the planar run's own error 6.6e-14 m against dt/2,
      its energy drift 1.7e-14 of the largest kinetic energy, 2.7 m of travel)

GEOMETRY (SI units; every vector in the frame named; "dttmm" lines say how to rebuild it)
=========================================================================================
World: z up, gravity g = (0, 0, -9.81) m/s^2.  The ground frame is the world frame, the ground
point the origin: dttmm.System(gravity=[0, 0, -9.81]) with the default Ground().

Body frames.  Each body's frame origin is its input point I (where its inboard joint acts);
the inertial data below are dttmm's RigidBody arguments in the body's own axes:
    mass, to_mass_center = l_IC (I -> mass centre), inertia = J_C about the mass centre
    (inertia_about="mass_center"), to_output = l_IO (I -> output point O),
and MuJoCo's <inertial pos=l_IC mass fullinertia=J_C (xx yy zz xy xz yz)>.  No body is given
an initial rotation (dttmm: rotation=None, so R0 = I for every joint): at zero coordinates
every body frame is parallel to the world frame.

Case "cylindrical"
------------------
  carrier (body 0), on a cylindrical joint to the ground point:
    axis n = (2/3, 2/3, 1/3) (unit; ground frame)
    coordinates (theta, s) = (0.3 rad, 0.1 m), rates (theta', s') = (2.0 rad/s, -0.5 m/s)
    A_carrier = Rot(n, theta),  input point = 0 + n s
    mass 2.0, l_IC = (0.10, -0.05, 0.20), l_IO = (0.30, 0.00, 0.10),
    J_C = [[0.030, 0.002, -0.001], [0.002, 0.040, 0.003], [-0.001, 0.003, 0.050]]
    dttmm: CylindricalJoint(axis=[2/3, 2/3, 1/3], coordinates=(0.3, 0.1), rates=(2.0, -0.5))
  link (body 1), on a revolute joint at the carrier's output point O:
    axis (0, 1, 0) in the carrier's frame; angle 0.4 rad, rate -1.5 rad/s
    A_link = A_carrier Rot((0, 1, 0), angle)
    mass 1.0, l_IC = (0.25, 0.00, 0.02), l_IO = (0.50, 0.00, 0.00) (the tip),
    J_C = diag(0.002, 0.022, 0.021)
    dttmm: system.add(link, RevoluteJoint(axis=[0, 1, 0], angle=0.4, rate=-1.5),
                      parent="carrier")          (at=None: the carrier's output point)
  MuJoCo: body "carrier" with joints slide(n) then hinge(n), both at its origin; body "link"
  at pos l_IO of the carrier with hinge (0, 1, 0); site "tip" at the link's l_IO.

Case "planar"
-------------
  carrier (body 0), on a planar joint to the ground point:
    axis1 n1 = (2/3, 2/3, 1/3), axis2 n2 = (-2/3, 1/3, 2/3) (unit, perpendicular; ground
    frame), turning axis n3 = n1 x n2 = (1/3, -2/3, 2/3)
    coordinates (s1, s2, theta) = (0.2 m, -0.1 m, 0.5 rad),
    rates (s1', s2', theta') = (0.3 m/s, -0.4 m/s, 1.5 rad/s)
    A_carrier = Rot(n3, theta),  input point = 0 + n1 s1 + n2 s2
    mass 1.5, l_IC = (0.05, 0.10, -0.02), l_IO = (0.20, 0.10, 0.00),
    J_C = [[0.020, -0.001, 0.000], [-0.001, 0.025, 0.002], [0.000, 0.002, 0.030]]
    dttmm: PlanarJoint(axis1=[2/3, 2/3, 1/3], axis2=[-2/3, 1/3, 2/3],
                       coordinates=(0.2, -0.1, 0.5), rates=(0.3, -0.4, 1.5))
  link (body 1), on a revolute joint at the carrier's output point O:
    axis (0, 0, 1) in the carrier's frame; angle -0.2 rad, rate 3.0 rad/s
    mass 0.8, l_IC = (0.20, 0.03, 0.00), l_IO = (0.40, 0.00, 0.00) (the tip),
    J_C = diag(0.001, 0.011, 0.0105)
    dttmm: system.add(link, RevoluteJoint(axis=[0, 0, 1], angle=-0.2, rate=3.0),
                      parent="carrier")
  MuJoCo: body "carrier" with joints slide(n1), slide(n2), hinge(n3) at its origin, in this
  order (MuJoCo applies a body's joints in order, each axis in the frame the previous ones
  left: the slides move the origin along the ground-frame n1, n2, then the hinge turns about
  n3 through the moved origin, which is A = Rot(n3, theta), r_I = n1 s1 + n2 s2).

Dynamics: plain rigid-body dynamics.  No contact, no constraints (no limits, no equality),
no joint damping, stiffness, friction loss or armature (MuJoCo's defaults, and the flags
below), no actuators, no fluid (density = viscosity = 0), inertias from <inertial> only
(inertiafromgeom="false", no geoms at all).  Integrator RK4.

OUTPUT (each .npz; samples every 1e-2 s from t = 0 to 1 s, 101 rows)
====================================================================
  t                     (T,)        s (nominal sample times j * 1e-2; MuJoCo's accumulated
                                    clock within 2e-12 s of them)
  position_input        (T, 2, 3)   world positions of the bodies' frame origins (input
                                    points): dttmm Result.position_input[:, k]
  tip                   (T, 3)      the link's tip: dttmm Result.position_output[:, 1]
  joint_coordinates     (T, m + 1)  the new joint's coordinates in dttmm's order ((theta, s)
                                    or (s1, s2, theta)), then the link's angle: dttmm
                                    Result.joint_coordinates (hinge order)
  energy_drift          ()          max |E(t) - E(0)| / max(kinetic), the main run
  convergence_*         ()          max position difference (m) of the main run (dt) against
                                    dt/2 (and of 2 dt against dt): RK4's error estimate
  dt                    ()          the main run's step
  mujoco_version        ()          str
  plus the geometry above as arrays (gravity, axes, masses, l_IC, l_IO, J_C, link axis,
  initial coordinates and rates), keys "geo_*".
"""
import sys
import time
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent
T_END, RECORD_DT, DT = 1.0, 1e-2, 1e-5
KEEP = ("t", "position_input", "tip", "joint_coordinates")     # (what the .npz keeps)
GRAVITY = np.array([0.0, 0.0, -9.81])

CASES = {
    "cylindrical": dict(
        # the new joint: per MuJoCo joint (type, axis in the ground frame), in MuJoCo's order;
        # dttmm's coordinate order as indices into MuJoCo's qpos
        joints=[("slide", (2 / 3, 2 / 3, 1 / 3)), ("hinge", (2 / 3, 2 / 3, 1 / 3))],
        dttmm_order=[1, 0],                 # (theta, s) = (qpos[1], qpos[0])
        coordinates=(0.3, 0.1), rates=(2.0, -0.5),     # dttmm's order: (theta, s)
        axes=dict(axis=(2 / 3, 2 / 3, 1 / 3)),
        carrier=dict(mass=2.0, l_ic=(0.10, -0.05, 0.20), l_io=(0.30, 0.00, 0.10),
                     j_c=((0.030, 0.002, -0.001), (0.002, 0.040, 0.003),
                          (-0.001, 0.003, 0.050))),
        link=dict(axis=(0.0, 1.0, 0.0), angle=0.4, rate=-1.5, mass=1.0,
                  l_ic=(0.25, 0.00, 0.02), l_io=(0.50, 0.00, 0.00),
                  j_c=((0.002, 0, 0), (0, 0.022, 0), (0, 0, 0.021)))),
    "planar": dict(
        joints=[("slide", (2 / 3, 2 / 3, 1 / 3)), ("slide", (-2 / 3, 1 / 3, 2 / 3)),
                ("hinge", (1 / 3, -2 / 3, 2 / 3))],
        dttmm_order=[0, 1, 2],              # (s1, s2, theta)
        coordinates=(0.2, -0.1, 0.5), rates=(0.3, -0.4, 1.5),
        axes=dict(axis1=(2 / 3, 2 / 3, 1 / 3), axis2=(-2 / 3, 1 / 3, 2 / 3)),
        carrier=dict(mass=1.5, l_ic=(0.05, 0.10, -0.02), l_io=(0.20, 0.10, 0.00),
                     j_c=((0.020, -0.001, 0.000), (-0.001, 0.025, 0.002),
                          (0.000, 0.002, 0.030))),
        link=dict(axis=(0.0, 0.0, 1.0), angle=-0.2, rate=3.0, mass=0.8,
                  l_ic=(0.20, 0.03, 0.00), l_io=(0.40, 0.00, 0.00),
                  j_c=((0.001, 0, 0), (0, 0.011, 0), (0, 0, 0.0105)))),
}


def _vec(v):
    return " ".join(f"{float(x):.17g}" for x in v)


def _full_inertia(j):
    j = np.asarray(j, dtype=float)
    return _vec([j[0, 0], j[1, 1], j[2, 2], j[0, 1], j[0, 2], j[1, 2]])


def mjcf(case, dt):
    c = CASES[case]
    car, link = c["carrier"], c["link"]
    joints = "\n".join(f'      <joint name="j{i}" type="{kind}" axis="{_vec(axis)}" pos="0 0 0"/>'
                       for i, (kind, axis) in enumerate(c["joints"]))
    return f"""
<mujoco model="{case}">
  <compiler angle="radian" inertiafromgeom="false" autolimits="true" balanceinertia="false"/>
  <option timestep="{dt:.17g}" integrator="RK4" gravity="{_vec(GRAVITY)}" density="0"
          viscosity="0">
    <flag contact="disable" constraint="disable" equality="disable" limit="disable"
          frictionloss="disable" spring="disable" damper="disable" actuation="disable"
          energy="enable"/>
  </option>
  <worldbody>
    <body name="carrier" pos="0 0 0">
{joints}
      <inertial pos="{_vec(car['l_ic'])}" mass="{car['mass']:.17g}"
                fullinertia="{_full_inertia(car['j_c'])}"/>
      <site name="carrier_output" pos="{_vec(car['l_io'])}"/>
      <body name="link" pos="{_vec(car['l_io'])}">
        <joint name="link" type="hinge" axis="{_vec(link['axis'])}" pos="0 0 0"/>
        <inertial pos="{_vec(link['l_ic'])}" mass="{link['mass']:.17g}"
                  fullinertia="{_full_inertia(link['j_c'])}"/>
        <site name="tip" pos="{_vec(link['l_io'])}"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def simulate(case, dt, t_end=T_END, record_dt=RECORD_DT):
    import mujoco
    c = CASES[case]
    model = mujoco.MjModel.from_xml_string(mjcf(case, dt))
    assert model.nv == len(c["joints"]) + 1 and np.all(model.dof_damping == 0.0)
    assert np.all(model.dof_armature == 0.0) and np.all(model.jnt_stiffness == 0.0)
    assert np.all(model.dof_frictionloss == 0.0) and np.all(model.qpos0 == 0.0)
    data = mujoco.MjData(model)
    m = len(c["joints"])
    order = c["dttmm_order"]
    for i_dttmm, i_mj in enumerate(order):
        data.qpos[i_mj] = c["coordinates"][i_dttmm]
        data.qvel[i_mj] = c["rates"][i_dttmm]
    data.qpos[m] = c["link"]["angle"]
    data.qvel[m] = c["link"]["rate"]
    per = int(round(record_dt / dt))
    n_rec = int(round(t_end / record_dt)) + 1
    bodies = [model.body("carrier").id, model.body("link").id]
    sites = [model.site("carrier_output").id, model.site("tip").id]
    out = {k: [] for k in ("t", "t_mujoco", "position_input", "position_output",
                           "position_mass_center", "rotation", "angular_velocity",
                           "joint_coordinates", "joint_rates", "kinetic", "potential")}
    vel = np.zeros(6)
    for j in range(n_rec):
        if j:
            mujoco.mj_step(model, data, nstep=per)
        mujoco.mj_forward(model, data)      # (positions, energies of the current state)
        out["t"].append(j * record_dt)      # (nominal; MuJoCo's own clock: t_mujoco)
        out["t_mujoco"].append(data.time)
        out["position_input"].append(data.xpos[bodies].copy())
        out["position_output"].append(data.site_xpos[sites].copy())
        out["position_mass_center"].append(data.xipos[bodies].copy())
        out["rotation"].append(data.xmat[bodies].reshape(2, 3, 3).copy())
        w = []
        for b in bodies:        # world angular velocity (object velocity, world orientation)
            mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_BODY, b, vel, 0)
            w.append(vel[0:3].copy())
        out["angular_velocity"].append(np.array(w))
        out["joint_coordinates"].append(np.r_[data.qpos[order], data.qpos[m]])
        out["joint_rates"].append(np.r_[data.qvel[order], data.qvel[m]])
        out["potential"].append(data.energy[0])
        out["kinetic"].append(data.energy[1])
    out = {k: np.array(v) for k, v in out.items()}
    out["tip"] = out["position_output"][:, 1].copy()
    return out


def _check_start(case, run):
    """The t = 0 sample against the geometry written above (the kinematics as dttmm states
    them), so that the header and the MJCF cannot drift apart."""
    c = CASES[case]

    def rot(n, q):
        n = np.asarray(n, dtype=float)
        k = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
        return np.eye(3) + np.sin(q) * k + (1 - np.cos(q)) * k @ k
    if case == "cylindrical":
        n = np.array(c["axes"]["axis"])
        theta, s = c["coordinates"]
        a_c, r_i = rot(n, theta), n * s
    else:
        n1, n2 = np.array(c["axes"]["axis1"]), np.array(c["axes"]["axis2"])
        s1, s2, theta = c["coordinates"]
        a_c, r_i = rot(np.cross(n1, n2), theta), n1 * s1 + n2 * s2
    a_l = a_c @ rot(c["link"]["axis"], c["link"]["angle"])
    r_o = r_i + a_c @ np.array(c["carrier"]["l_io"])
    tip = r_o + a_l @ np.array(c["link"]["l_io"])
    err = max(np.abs(run["rotation"][0, 0] - a_c).max(), np.abs(run["rotation"][0, 1] - a_l).max(),
              np.abs(run["position_input"][0, 0] - r_i).max(),
              np.abs(run["position_input"][0, 1] - r_o).max(), np.abs(run["tip"][0] - tip).max())
    assert err < 1e-12, (case, err)
    return err


def main(cases=None):
    try:
        import mujoco
    except ImportError:
        print("mujoco_joints.py: MuJoCo is not installed (pip install mujoco); nothing written "
              "(the tests read the committed .npz files)")
        return
    for case in cases or CASES:
        start = time.perf_counter()
        main_run = simulate(case, DT)
        fine = simulate(case, DT / 2)
        coarse = simulate(case, 2 * DT)
        wall = time.perf_counter() - start

        def diff(a, b):
            return max(np.abs(a["position_input"] - b["position_input"]).max(),
                       np.abs(a["tip"] - b["tip"]).max())
        start_err = _check_start(case, main_run)
        energy = main_run["kinetic"] + main_run["potential"]
        drift = np.abs(energy - energy[0]).max() / np.abs(main_run["kinetic"]).max()
        c = CASES[case]
        geo = {"geo_gravity": GRAVITY, "geo_coordinates": np.array(c["coordinates"]),
               "geo_rates": np.array(c["rates"])}
        geo.update({f"geo_{k}": np.array(v) for k, v in c["axes"].items()})
        for body in ("carrier", "link"):
            geo.update({f"geo_{body}_{k}": np.array(v) for k, v in c[body].items()})
        np.savez_compressed(OUT / f"mujoco_{case}.npz", **{k: main_run[k] for k in KEEP},
                            **geo, dt=DT, energy_drift=drift,
                            convergence_dt_vs_half=diff(main_run, fine),
                            convergence_2dt_vs_dt=diff(coarse, main_run), start_check=start_err,
                            mujoco_version=mujoco.__version__)
        travel = np.abs(main_run["position_input"][-1] - main_run["position_input"][0]).max()
        print(f"{case}: dt = {DT:g}: |x(dt) - x(dt/2)| = {diff(main_run, fine):.2e} m, "
              f"|x(2dt) - x(dt)| = {diff(coarse, main_run):.2e} m; energy drift "
              f"{drift:.2e} of max T (E(0) = {energy[0]:.6f} J); start vs header "
              f"{start_err:.1e}; body travel {travel:.3f} m; final coordinates "
              f"{np.array2string(main_run['joint_coordinates'][-1], precision=6)}; "
              f"{wall:.1f} s (3 runs)")


if __name__ == "__main__":
    main(sys.argv[1:] or None)
