"""Independent MuJoCo reference runs for dttmm's FreeJoint (a free-floating chain on ball joints)
and for contact with a ground plane (a chain of capsules dropped flat onto it).  Writes, beside
this file,

    mujoco_free_chain.npz      5 links, a free joint then ball joints, no gravity: 2 s
    mujoco_chain_drop.npz      20 capsule links dropped flat onto a plane, at rest by 2 s

the free chain subsampled every 20 ms (101 samples) from a run at dt = 1e-5 with RK4, the drop
every 10 ms (201 samples) from a run at dt = 1e-4 with RK4, and each run's own error estimate
(against dt/2, and of 2 dt against dt).  The tests read the .npz only: they need no MuJoCo (this
script skips, saying so, without it).

MuJoCo's RK4 is of second order only where bodies turn on quaternion coordinates (free and ball
joints): it sums the stages' angular velocities, each in its own stage's body frame, and turns
the quaternion by the sum (mj_integratePos), without the correction a fourth-order Lie-group
scheme needs.  Measured here: the differences between runs at 2 dt, dt and dt/2 fall by 4 per
halving, not 16 (also for a single tumbling free body).  So the main run's error is about 4/3
of its difference from the run at dt/2 (own_error_m), not 1/15 of it.

Run:  python tests/data/mujoco_contact.py [free_chain|chain_drop]   (MuJoCo 3 or later; ~1 min;
      the committed files: MuJoCo 3.17.0.  free_chain: own error 6.1e-11 m against dt/2
      (2.4e-10 m, 2 dt against dt), momenta kept to 2.6e-10 kg m/s and 4.1e-10 kg m^2/s
      (RK4's second-order error in the turns: both fall by 4 per halving of dt), kinetic
      energy to 3.2e-12 of itself.  chain_drop: at rest from t = 0.2 s (max speed 5e-15 m/s
      at 2 s), the input and output points at z = 0.0199998008 (the two ends) to 0.0199998548
      m (the middle), MuJoCo's penetrations 1.45e-7 to 1.99e-7 m (contact.dist), own error of
      the rest heights 1e-16 m against dt/2 (of the trajectories, through the strike, 3.6e-5 m))

GEOMETRY (SI units; every vector in the frame named; "dttmm" lines say how to rebuild it)
=========================================================================================
World: z up.  The ground frame is the world frame, the ground point the origin (dttmm's
default Ground(), plus the plane in case "chain_drop").

Body frames.  Each body's frame origin is its input point I (where its inboard joint acts);
the inertial data below are dttmm's RigidBody arguments in the body's own axes:
    mass, to_mass_center = l_IC (I -> mass centre), inertia = J_C about the mass centre
    (inertia_about="mass_center"), to_output = l_IO (I -> output point O),
and MuJoCo's <inertial pos=l_IC mass diaginertia=J_C (xx yy zz: J_C is diagonal here, so
MuJoCo's principal axes are the body axes, body_iquat = 1).
Rot(z, a) below is the rotation by a (rad) about z, [[c, -s, 0], [s, c, 0], [0, 0, 1]].

Case "free_chain"
-----------------
  Gravity (0, 0, 0); no contact, no constraint of any kind.
  5 equal links k = 0..4:
    mass 1.0, l_IC = (0.2, 0, 0), l_IO = (0.4, 0, 0), J_C = diag(2e-3, 1.4e-2, 1.5e-2)
  link 0 on a free joint to the ground point; links 1..4 each on a ball joint at the previous
  link's output point (a straight chain of ball joints behind the free one).
  t = 0:
    rotations (body to world)   R_k = Rot(z, 0.3 k)   (each ball joint's relative rotation is
                                Rot(z, 0.3) about its parent's z axis)
    input points (world)        r_I0 = (0, 0, 0),  r_Ik = r_I(k-1) + R_(k-1) l_IO
    the chain turns rigidly: every link's world angular velocity is w = (0.4, -0.3, 2.0) rad/s,
    about link 0's input point, which moves at v = (0.1, 0.2, -0.05) m/s (world); so each
    point x of the chain moves at v + w x (x - r_I0), and each ball joint's relative angular
    velocity is zero.
    dttmm: system = System(gravity=[0, 0, 0])
           link_k = RigidBody(mass=1.0, inertia=[2e-3, 1.4e-2, 1.5e-2],
                              inertia_about="mass_center", to_mass_center=[0.2, 0, 0],
                              to_output=[0.4, 0, 0], rotation=Rot(z, 0.3 k),
                              angular_velocity=[0.4, -0.3, 2.0], name=f"link{k}")
           system.add(link_0, FreeJoint(position=[0, 0, 0], velocity=[0.1, 0.2, -0.05]))
           system.add(link_k, BallJoint(), parent=link_(k-1))        (k = 1..4)
  MuJoCo: body "link0" at the origin with a free joint; body "link{k}" at pos l_IO of
  link{k-1} with a ball joint at its origin; site "out{k}" at each link's l_IO.  MuJoCo's
  conventions, as set here: the free joint's qpos = (r_I0, quaternion (w, x, y, z) of R_0),
  its qvel = (the world velocity of link 0's frame origin, R_0^T w: the angular velocity in
  link 0's frame); a ball joint's qpos = the quaternion of the relative rotation, its qvel =
  the relative angular velocity in the child's frame (zero here).  Checked at t = 0, after
  mj_forward: every link's world angular velocity (mj_objectVelocity) is w and every frame
  origin moves at v + w x r_Ik, to 1e-12, and a central difference of the positions and
  rotations (mj_integratePos by +-1e-6 s) agrees to 1e-8 (the conventions, independently).

Case "chain_drop"
-----------------
  Gravity (0, 0, -9.81).  Ground plane through the origin, outward normal (0, 0, 1) (MJCF
  geom type "plane"); dttmm: Ground(plane=Plane(normal=[0, 0, 1], point=[0, 0, 0])).
  20 equal links k = 0..19:
    mass 0.1, l_IC = (0.05, 0, 0), l_IO = (0.1, 0, 0), J_C = diag(2.0e-5, 1.0e-4, 1.0e-4)
    shape: a capsule of radius 0.02 from (0, 0, 0) to (0.1, 0, 0) (body frame): its two end
    spheres of radius 0.02 centred at I and O
  link 0 on a free joint to the ground point, links 1..19 each on a ball joint at the previous
  link's output point; all along +x, rotations the identity, at rest at t = 0:
    input points r_Ik = (0.1 k, 0, 0.1) (world), so the capsules' lowest points are 0.08 m
    above the plane; they fall 0.08 m (0.128 s, striking at 1.25 m/s) and come to rest.
    dttmm: system = System(gravity=[0, 0, -9.81], ground=Ground(plane=Plane()))
           link_k = RigidBody(mass=0.1, inertia=[2.0e-5, 1.0e-4, 1.0e-4],
                              inertia_about="mass_center", to_mass_center=[0.05, 0, 0],
                              to_output=[0.1, 0, 0], name=f"link{k}",
                              shapes=Capsule(0.02, [0, 0, 0], [0.1, 0, 0]),
                              contact=Contact(..., friction=0.5))
           system.add(link_0, FreeJoint(position=[0, 0, 0.1]))
           system.add(link_k, BallJoint(), parent=link_(k-1))        (k = 1..19)
  Contact: MuJoCo's soft constraint, not dttmm's compliant law (elements/contact.py): the two
  agree on the state at rest (each end sphere on the plane: z_I = z_O = radius, less a
  penetration that each law sets its own way: MuJoCo's is rest_contact_dist) and on the fall
  before the strike, not on the impact itself.  MuJoCo's contact here: condim 3 (sliding
  friction mu = 0.5, pyramidal cone), solref = (0.002 s time constant, damping ratio 1),
  solimp the default (0.9, 0.95, 0.001, 0.5, 2), margin 0; both geoms carry the same
  parameters (so MuJoCo's mixing of a pair's parameters changes nothing).  Only the capsules
  touch the plane: capsules contype 1 conaffinity 0, the plane contype 0 conaffinity 1 (no
  capsule-capsule pairs at all; adjacent capsules overlap at the joints, others never meet).
  The capsules have no mass of their own (mass="0"; inertiafromgeom="false").  Newton solver,
  tolerance 1e-10, 100 iterations.  Integrator RK4 (stable here: no implicit one needed).

Dynamics: plain rigid-body dynamics (plus the contact above).  No joint damping, stiffness,
friction loss or armature, no limits, no equality constraints, no actuators, no fluid
(density = viscosity = 0), inertias from <inertial> only (inertiafromgeom="false"; the free
chain has no geoms, the drop's capsules mass 0).

OUTPUT
======
mujoco_free_chain.npz (samples every 2e-2 s from t = 0 to 2 s, 101 rows)
  t                     (T,)          s (nominal sample times j * 2e-2)
  position_input        (T, 5, 3)     world positions of the links' frame origins (input
                                      points), m: dttmm Result.position_input
  rotation              (T, 5, 3, 3)  body-to-world rotation matrices: dttmm Result.rotation
  position_output       (T, 5, 3)     world positions of the links' output points, m: dttmm
                                      Result.position_output
  angular_velocity      (T, 5, 3)     world angular velocities, rad/s
  linear_momentum       (T, 3)        sum_k m v_Ck, kg m/s (world)
  angular_momentum      (T, 3)        about the world origin, sum_k (r_Ck x m v_Ck +
                                      R_k J_C R_k^T w_k), kg m^2/s (world); both computed here
                                      from MuJoCo's mass-centre positions and velocities
                                      (and checked against MuJoCo's mj_subtreeVel to 1e-12)
  momentum_drift_linear ()            max_t |P(t) - P(0)|, kg m/s (the main run)
  momentum_drift_angular ()           max_t |L(t) - L(0)|, kg m^2/s
  energy_drift          ()            max_t |T(t) - T(0)| / T(0) (kinetic energy, MuJoCo's)
  own_error_m           ()            max |difference| of position_input and position_output
                                      between the main run (dt) and one at dt/2, m
  convergence_2dt_vs_dt ()            the same between runs at 2 dt and dt, m
  dt                    ()            the main run's step, s
  start_check           ()            max error of the t = 0 sample against the geometry above
  mujoco_version        ()            str
  geo_*                               the geometry: gravity, n_links, mass, l_ic, l_io, j_c
                                      (3, 3), turn (0.3 rad: R_k = Rot(z, turn k)), omega (w),
                                      velocity (v), position (r_I0)

mujoco_chain_drop.npz (samples every 1e-2 s from t = 0 to 2 s, 201 rows)
  t                     (T,)          s
  position_input        (T, 20, 3)    world positions of the links' input points, m
  position_output       (T, 20, 3)    world positions of the links' output points, m
  rest_input_z          (20,)         z of the input points at t = 2 s, m
  rest_output_z         (20,)         z of the output points at t = 2 s, m
  rest_contact_dist     (ncon,)       MuJoCo's data.contact.dist of the capsule-plane contacts
                                      at t = 2 s, m (negative: penetration)
  rest_contact_body     (ncon,)       the link each contact belongs to
  rest_contact_pos      (ncon, 3)     MuJoCo's contact positions (midway between the
                                      surfaces), m
  rest_contact_count    ()            ncon (2 per capsule: its end spheres)
  rest_max_speed        ()            max speed of any input or output point at t = 2 s, m/s
  own_error_m           ()            max |difference| of rest_input_z and rest_output_z
                                      between the main run (dt) and one at dt/2, m
  convergence_trajectory_m ()         max |difference| of position_input and position_output
                                      over all samples, dt against dt/2, m
  dt                    ()            the main run's step, s
  start_check           ()            max error of the t = 0 sample against the geometry above
  mujoco_version        ()            str
  geo_*                               the geometry: gravity, n_links, mass, l_ic, l_io, j_c,
                                      radius, height (of the input points at t = 0), friction,
                                      solref, solimp, plane_normal, plane_point
"""
import sys
import time
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent

FREE = dict(n=5, mass=1.0, l_ic=(0.2, 0.0, 0.0), l_io=(0.4, 0.0, 0.0),
            j_c=((2e-3, 0, 0), (0, 1.4e-2, 0), (0, 0, 1.5e-2)), turn=0.3,
            omega=(0.4, -0.3, 2.0), velocity=(0.1, 0.2, -0.05), position=(0.0, 0.0, 0.0),
            gravity=(0.0, 0.0, 0.0), t_end=2.0, record_dt=2e-2, dt=1e-5)
DROP = dict(n=20, mass=0.1, l_ic=(0.05, 0.0, 0.0), l_io=(0.1, 0.0, 0.0),
            j_c=((2.0e-5, 0, 0), (0, 1.0e-4, 0), (0, 0, 1.0e-4)), radius=0.02, height=0.1,
            friction=0.5, solref=(0.002, 1.0), solimp=(0.9, 0.95, 0.001, 0.5, 2.0),
            plane_normal=(0.0, 0.0, 1.0), plane_point=(0.0, 0.0, 0.0),
            gravity=(0.0, 0.0, -9.81), t_end=2.0, record_dt=1e-2, dt=1e-4)


def _vec(v):
    return " ".join(repr(float(x)) for x in v)


def _diag_inertia(j):
    j = np.asarray(j, dtype=float)
    assert np.all(j == np.diag(np.diag(j)))     # (diaginertia: MuJoCo keeps the body axes)
    return _vec(np.diag(j))


def _rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _skew(a):
    return np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def _chain(c, joint, extra=""):
    """The nested bodies of a chain: link0 on `joint` at height c["height"] (0 by default),
    link1..n-1 on ball joints at the previous link's l_IO; extra: more of each body's lines."""
    inertial = (f'<inertial pos="{_vec(c["l_ic"])}" mass="{c["mass"]:.17g}" '
                f'diaginertia="{_diag_inertia(c["j_c"])}"/>')
    text, close = [], []
    for k in range(c["n"]):
        pad = "  " * (k + 2)
        if k == 0:
            text.append(f'{pad}<body name="link0" pos="{_vec((0, 0, c.get("height", 0.0)))}">')
            text.append(f"{pad}  {joint}")
        else:
            text.append(f'{pad}<body name="link{k}" pos="{_vec(c["l_io"])}">')
            text.append(f'{pad}  <joint name="ball{k}" type="ball" pos="0 0 0"/>')
        text.append(f"{pad}  {inertial}")
        text.append(f'{pad}  <site name="out{k}" pos="{_vec(c["l_io"])}"/>')
        if extra:
            text.append(f"{pad}  {extra.format(k=k)}")
        close.append(f"{pad}</body>")
    return "\n".join(text + close[::-1])


def mjcf_free_chain(dt):
    c = FREE
    bodies = _chain(c, '<freejoint name="free"/>')
    return f"""
<mujoco model="free_chain">
  <compiler angle="radian" inertiafromgeom="false" autolimits="true" balanceinertia="false"/>
  <option timestep="{dt:.17g}" integrator="RK4" gravity="{_vec(c['gravity'])}" density="0"
          viscosity="0">
    <flag contact="disable" constraint="disable" equality="disable" limit="disable"
          frictionloss="disable" spring="disable" damper="disable" actuation="disable"
          energy="enable"/>
  </option>
  <worldbody>
{bodies}
  </worldbody>
</mujoco>
"""


def mjcf_chain_drop(dt):
    c = DROP
    contact = (f'friction="{c["friction"]:.17g} 0.005 0.0001" solref="{_vec(c["solref"])}" '
               f'solimp="{_vec(c["solimp"])}" condim="3" margin="0" gap="0"')
    capsule = (f'<geom name="capsule{{k}}" type="capsule" size="{c["radius"]:.17g}" '
               f'fromto="0 0 0 {_vec(c["l_io"])}" mass="0" contype="1" conaffinity="0" '
               f'{contact}/>')
    bodies = _chain(c, '<freejoint name="free"/>', extra=capsule)
    return f"""
<mujoco model="chain_drop">
  <compiler angle="radian" inertiafromgeom="false" autolimits="true" balanceinertia="false"/>
  <option timestep="{dt:.17g}" integrator="RK4" gravity="{_vec(c['gravity'])}" density="0"
          viscosity="0" solver="Newton" iterations="100" tolerance="1e-10" cone="pyramidal">
    <flag equality="disable" limit="disable" frictionloss="disable" spring="disable"
          damper="disable" actuation="disable"/>
  </option>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 1" pos="{_vec(c['plane_point'])}"
          zaxis="{_vec(c['plane_normal'])}" contype="0" conaffinity="1" {contact}/>
{bodies}
  </worldbody>
</mujoco>
"""


def _check_model(model, c):
    assert model.nbody == c["n"] + 1 and model.nv == 6 + 3 * (c["n"] - 1)
    assert np.all(model.dof_damping == 0.0) and np.all(model.dof_armature == 0.0)
    assert np.all(model.jnt_stiffness == 0.0) and np.all(model.dof_frictionloss == 0.0)
    np.testing.assert_allclose(model.body_mass[1:], c["mass"], rtol=0, atol=0)
    np.testing.assert_allclose(model.body_ipos[1:], np.tile(c["l_ic"], (c["n"], 1)), atol=1e-15)
    np.testing.assert_allclose(model.body_inertia[1:], np.tile(np.diag(c["j_c"]), (c["n"], 1)),
                               rtol=1e-14)
    np.testing.assert_allclose(model.body_iquat[1:], np.tile([1.0, 0, 0, 0], (c["n"], 1)),
                               atol=1e-15)


def _velocities(model, data, bodies, kind):
    """Per body: (world angular velocity, world linear velocity of the point kind names:
    mjOBJ_XBODY its frame origin, mjOBJ_BODY its mass centre)."""
    import mujoco
    vel = np.zeros(6)
    w, v = [], []
    for b in bodies:
        mujoco.mj_objectVelocity(model, data, kind, b, vel, 0)
        w.append(vel[0:3].copy())
        v.append(vel[3:6].copy())
    return np.array(w), np.array(v)


def _momenta(model, data, bodies, c):
    """(P, L about the world origin) from the mass centres' positions and velocities and the
    world inertias R J_C R^T."""
    import mujoco
    w, v_c = _velocities(model, data, bodies, mujoco.mjtObj.mjOBJ_BODY)
    r_c = data.xipos[bodies]
    rot = data.xmat[bodies].reshape(-1, 3, 3)
    m, j_c = c["mass"], np.array(c["j_c"])
    p = (m * v_c).sum(axis=0)
    ang = (np.cross(r_c, m * v_c) + np.einsum("kij,jl,kml,km->ki", rot, j_c, rot, w)).sum(axis=0)
    return p, ang


def _set_free_chain_start(model, data):
    """The free chain's t = 0 state in MuJoCo's coordinates (see the header)."""
    import mujoco
    c = FREE
    r0 = _rot_z(0.0)                       # R_0
    q0 = np.zeros(4)
    mujoco.mju_mat2Quat(q0, r0.reshape(-1))
    data.qpos[0:3] = c["position"]
    data.qpos[3:7] = q0
    half = 0.5 * c["turn"]
    for k in range(1, c["n"]):
        a = model.jnt_qposadr[model.joint(f"ball{k}").id]
        data.qpos[a:a + 4] = (np.cos(half), 0.0, 0.0, np.sin(half))   # Rot(z, 0.3), (w, x, y, z)
    data.qvel[:] = 0.0
    data.qvel[0:3] = c["velocity"]                   # world velocity of link 0's origin
    data.qvel[3:6] = r0.T @ np.array(c["omega"])      # link 0's angular velocity, its frame
    # (ball joints: relative angular velocity zero)


def _expected_free_chain_start(c):
    rot = np.array([_rot_z(c["turn"] * k) for k in range(c["n"])])
    r_i = [np.array(c["position"], dtype=float)]
    for k in range(1, c["n"]):
        r_i.append(r_i[-1] + rot[k - 1] @ np.array(c["l_io"]))
    r_i = np.array(r_i)
    r_o = r_i + rot @ np.array(c["l_io"])
    w = np.array(c["omega"])
    v_i = np.array(c["velocity"]) + np.cross(w, r_i - r_i[0])
    return rot, r_i, r_o, v_i


def _check_free_chain_start(model, data, bodies):
    """MuJoCo's conventions at t = 0: every link turns at w (world), every frame origin moves
    at v + w x r_Ik (mj_objectVelocity, to 1e-12), and a central difference of the positions
    and rotations agrees (independently of mj_objectVelocity's meaning; 1e-8).  Returns the
    largest errors (object velocity, finite difference)."""
    import mujoco
    c = FREE
    rot, r_i, r_o, v_i = _expected_free_chain_start(c)
    w = np.array(c["omega"])
    ang, lin = _velocities(model, data, bodies, mujoco.mjtObj.mjOBJ_XBODY)
    err_obj = max(np.abs(ang - w).max(), np.abs(lin - v_i).max())
    # cvel's angular part (world orientation) is the bodies' angular velocity too
    err_obj = max(err_obj, np.abs(data.cvel[bodies, 0:3] - w).max())
    assert err_obj < 1e-12, err_obj
    h = 1e-6
    states = []
    for sign in (1.0, -1.0):
        d2 = mujoco.MjData(model)
        d2.qpos[:] = data.qpos
        mujoco.mj_integratePos(model, d2.qpos, data.qvel, sign * h)
        mujoco.mj_kinematics(model, d2)
        states.append((d2.xpos[bodies].copy(), d2.xmat[bodies].reshape(-1, 3, 3).copy()))
    (xp, rp), (xm, rm) = states
    v_fd = (xp - xm) / (2 * h)
    rdot = (rp - rm) / (2 * h)
    w_fd = []
    for k in range(c["n"]):
        s = rdot[k] @ rot[k].T                 # = skew(w_k)
        w_fd.append([s[2, 1], s[0, 2], s[1, 0]])
    err_fd = max(np.abs(v_fd - v_i).max(), np.abs(np.array(w_fd) - w).max())
    assert err_fd < 1e-8, err_fd
    return err_obj, err_fd


def simulate_free_chain(dt):
    import mujoco
    c = FREE
    model = mujoco.MjModel.from_xml_string(mjcf_free_chain(dt))
    _check_model(model, c)
    assert model.ngeom == 0
    data = mujoco.MjData(model)
    _set_free_chain_start(model, data)
    mujoco.mj_forward(model, data)
    bodies = [model.body(f"link{k}").id for k in range(c["n"])]
    sites = [model.site(f"out{k}").id for k in range(c["n"])]
    check = _check_free_chain_start(model, data, bodies)
    per = int(round(c["record_dt"] / dt))
    n_rec = int(round(c["t_end"] / c["record_dt"])) + 1
    out = {k: [] for k in ("t", "t_mujoco", "position_input", "rotation", "position_output",
                           "angular_velocity", "linear_momentum", "angular_momentum",
                           "kinetic", "momentum_vs_mujoco")}
    total = c["mass"] * c["n"]
    for j in range(n_rec):
        if j:
            mujoco.mj_step(model, data, nstep=per)
        mujoco.mj_forward(model, data)
        mujoco.mj_subtreeVel(model, data)
        out["t"].append(j * c["record_dt"])
        out["t_mujoco"].append(data.time)
        out["position_input"].append(data.xpos[bodies].copy())
        out["rotation"].append(data.xmat[bodies].reshape(-1, 3, 3).copy())
        out["position_output"].append(data.site_xpos[sites].copy())
        w, _ = _velocities(model, data, bodies, mujoco.mjtObj.mjOBJ_XBODY)
        out["angular_velocity"].append(w)
        p, ang = _momenta(model, data, bodies, c)
        out["linear_momentum"].append(p)
        out["angular_momentum"].append(ang)
        out["kinetic"].append(data.energy[1])
        # MuJoCo's own: subtree linear velocity (of its mass centre) and angular momentum
        # about the subtree's mass centre, of link 0's subtree (the whole chain)
        p_mj = total * data.subtree_linvel[bodies[0]]
        l_mj = data.subtree_angmom[bodies[0]] + np.cross(data.subtree_com[bodies[0]], p_mj)
        out["momentum_vs_mujoco"].append(max(np.abs(p - p_mj).max(), np.abs(ang - l_mj).max()))
    out = {k: np.array(v) for k, v in out.items()}
    out["start_conventions"] = np.array(check)
    return out


def _check_free_chain_sample(run):
    rot, r_i, r_o, _ = _expected_free_chain_start(FREE)
    err = max(np.abs(run["rotation"][0] - rot).max(), np.abs(run["position_input"][0] - r_i).max(),
              np.abs(run["position_output"][0] - r_o).max(),
              np.abs(run["angular_velocity"][0] - np.array(FREE["omega"])).max())
    assert err < 1e-12, err
    return err


def simulate_chain_drop(dt):
    import mujoco
    c = DROP
    model = mujoco.MjModel.from_xml_string(mjcf_chain_drop(dt))
    _check_model(model, c)
    assert np.all(model.geom_friction[:, 0] == c["friction"])
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    bodies = [model.body(f"link{k}").id for k in range(c["n"])]
    sites = [model.site(f"out{k}").id for k in range(c["n"])]
    floor = model.geom("floor").id
    per = int(round(c["record_dt"] / dt))
    n_rec = int(round(c["t_end"] / c["record_dt"])) + 1
    out = {k: [] for k in ("t", "t_mujoco", "position_input", "position_output", "max_speed",
                           "ncon")}
    for j in range(n_rec):
        if j:
            mujoco.mj_step(model, data, nstep=per)
        mujoco.mj_forward(model, data)
        out["t"].append(j * c["record_dt"])
        out["t_mujoco"].append(data.time)
        out["position_input"].append(data.xpos[bodies].copy())
        out["position_output"].append(data.site_xpos[sites].copy())
        w, v_i = _velocities(model, data, bodies, mujoco.mjtObj.mjOBJ_XBODY)
        rot = data.xmat[bodies].reshape(-1, 3, 3)
        v_o = v_i + np.cross(w, rot @ np.array(c["l_io"]))
        out["max_speed"].append(max(np.linalg.norm(v_i, axis=1).max(),
                                    np.linalg.norm(v_o, axis=1).max()))
        out["ncon"].append(data.ncon)
    out = {k: np.array(v) for k, v in out.items()}
    con = [data.contact[i] for i in range(data.ncon)]
    for ct in con:
        assert floor in (ct.geom1, ct.geom2), (ct.geom1, ct.geom2)   # capsule-plane only
    other = [ct.geom2 if ct.geom1 == floor else ct.geom1 for ct in con]
    body_of = {b: k for k, b in enumerate(bodies)}
    out["rest_contact_dist"] = np.array([ct.dist for ct in con])
    out["rest_contact_pos"] = np.array([ct.pos.copy() for ct in con]).reshape(-1, 3)
    out["rest_contact_body"] = np.array([body_of[model.geom_bodyid[g]] for g in other], dtype=int)
    out["rest_contact_count"] = data.ncon
    out["rest_input_z"] = out["position_input"][-1, :, 2].copy()
    out["rest_output_z"] = out["position_output"][-1, :, 2].copy()
    out["rest_max_speed"] = out["max_speed"][-1]
    return out


def _check_chain_drop_sample(run):
    c = DROP
    r_i = np.array([[c["l_io"][0] * k, 0.0, c["height"]] for k in range(c["n"])])
    err = max(np.abs(run["position_input"][0] - r_i).max(),
              np.abs(run["position_output"][0] - r_i - np.array(c["l_io"])).max())
    assert err < 1e-12, err
    return err


def _geo(c, keys):
    geo = {f"geo_{k}": np.array(c[k]) for k in keys}
    geo["geo_n_links"] = np.array(c["n"])
    return geo


def run_free_chain(mujoco_version):
    c = FREE
    start = time.perf_counter()
    main_run = simulate_free_chain(c["dt"])
    wall_main = time.perf_counter() - start
    fine = simulate_free_chain(c["dt"] / 2)
    coarse = simulate_free_chain(2 * c["dt"])
    wall = time.perf_counter() - start

    def diff(a, b):
        return max(np.abs(a["position_input"] - b["position_input"]).max(),
                   np.abs(a["position_output"] - b["position_output"]).max())
    start_err = _check_free_chain_sample(main_run)
    p, ang = main_run["linear_momentum"], main_run["angular_momentum"]
    drift_p = np.linalg.norm(p - p[0], axis=1).max()
    drift_l = np.linalg.norm(ang - ang[0], axis=1).max()
    kin = main_run["kinetic"]
    drift_e = np.abs(kin - kin[0]).max() / kin[0]
    vs_mj = main_run["momentum_vs_mujoco"].max()
    assert vs_mj < 1e-12, vs_mj
    assert np.abs(main_run["t_mujoco"] - main_run["t"]).max() < 1e-9
    geo = _geo(c, ("gravity", "mass", "l_ic", "l_io", "j_c", "turn", "omega", "velocity",
                   "position"))
    keep = ("t", "position_input", "rotation", "position_output", "angular_velocity",
            "linear_momentum", "angular_momentum")
    path = OUT / "mujoco_free_chain.npz"
    np.savez_compressed(path, **{k: main_run[k] for k in keep}, **geo, dt=c["dt"],
                        momentum_drift_linear=drift_p, momentum_drift_angular=drift_l,
                        energy_drift=drift_e, own_error_m=diff(main_run, fine),
                        convergence_2dt_vs_dt=diff(coarse, main_run), start_check=start_err,
                        mujoco_version=mujoco_version)
    err_obj, err_fd = main_run["start_conventions"]
    travel = np.linalg.norm(main_run["position_input"][-1, 0] - main_run["position_input"][0, 0])
    print(f"free_chain: dt = {c['dt']:g}: own error |x(dt) - x(dt/2)| = "
          f"{diff(main_run, fine):.2e} m, |x(2dt) - x(dt)| = {diff(coarse, main_run):.2e} m; "
          f"momentum drift |P - P0| <= {drift_p:.2e} kg m/s (P0 = "
          f"{np.array2string(p[0], precision=6)}), |L - L0| <= {drift_l:.2e} kg m^2/s (L0 = "
          f"{np.array2string(ang[0], precision=6)}); kinetic energy drift {drift_e:.2e} of "
          f"T0 = {kin[0]:.6f} J; momenta vs MuJoCo's mj_subtreeVel {vs_mj:.1e}; start: "
          f"object velocities vs w, v + w x r {err_obj:.1e}, central difference {err_fd:.1e}, "
          f"sample vs header {start_err:.1e}; link 0 travel {travel:.4f} m; "
          f"{wall_main:.1f} s main run, {wall:.1f} s (3 runs); "
          f"{path.stat().st_size / 1024:.1f} KB")


def run_chain_drop(mujoco_version):
    c = DROP
    start = time.perf_counter()
    main_run = simulate_chain_drop(c["dt"])
    wall_main = time.perf_counter() - start
    fine = simulate_chain_drop(c["dt"] / 2)
    wall = time.perf_counter() - start
    own = max(np.abs(main_run["rest_input_z"] - fine["rest_input_z"]).max(),
              np.abs(main_run["rest_output_z"] - fine["rest_output_z"]).max())
    trajectory = max(np.abs(main_run["position_input"] - fine["position_input"]).max(),
                     np.abs(main_run["position_output"] - fine["position_output"]).max())
    start_err = _check_chain_drop_sample(main_run)
    rest_speed = main_run["rest_max_speed"]
    assert rest_speed < 1e-6, rest_speed
    assert main_run["rest_contact_count"] == 2 * c["n"], main_run["rest_contact_count"]
    assert np.abs(main_run["t_mujoco"] - main_run["t"]).max() < 1e-9
    geo = _geo(c, ("gravity", "mass", "l_ic", "l_io", "j_c", "radius", "height", "friction",
                   "solref", "solimp", "plane_normal", "plane_point"))
    keep = ("t", "position_input", "position_output", "rest_input_z", "rest_output_z",
            "rest_contact_dist", "rest_contact_body", "rest_contact_pos", "rest_contact_count",
            "rest_max_speed")
    path = OUT / "mujoco_chain_drop.npz"
    np.savez_compressed(path, **{k: main_run[k] for k in keep}, **geo, dt=c["dt"],
                        own_error_m=own, convergence_trajectory_m=trajectory,
                        start_check=start_err, mujoco_version=mujoco_version)
    z_i, z_o = main_run["rest_input_z"], main_run["rest_output_z"]
    z = np.r_[z_i, z_o]
    dist = main_run["rest_contact_dist"]
    drift = np.abs(main_run["position_input"][-1, :, :2] - main_run["position_input"][0, :, :2])
    first_touch = main_run["t"][np.argmax(main_run["ncon"] > 0)]
    settle = main_run["t"][np.nonzero(main_run["max_speed"] > 1e-6)[0].max() + 1]
    print(f"chain_drop: dt = {c['dt']:g}: rest heights z_I in [{z_i.min():.9f}, "
          f"{z_i.max():.9f}] m, z_O in [{z_o.min():.9f}, {z_o.max():.9f}] m (spread "
          f"{z.max() - z.min():.2e} m; radius {c['radius']} m, so radius - z = "
          f"{c['radius'] - z.mean():.3e} m); MuJoCo's contact.dist ({len(dist)} contacts) in "
          f"[{dist.min():.6e}, {dist.max():.6e}] m; max speed at t = {c['t_end']:g} s "
          f"{rest_speed:.1e} m/s (< 1e-6 from t = {settle:g} s); first contact at t = "
          f"{first_touch:g} s; horizontal drift of the input points {drift.max():.1e} m; "
          f"own error |z(dt) - z(dt/2)| = {own:.2e} m (trajectories {trajectory:.2e} m); "
          f"start vs header {start_err:.1e}; {wall_main:.1f} s main run, {wall:.1f} s (2 runs); "
          f"{path.stat().st_size / 1024:.1f} KB")
    print(f"chain_drop: rest_input_z = {np.array2string(z_i, precision=10, max_line_width=96)}")
    print(f"chain_drop: rest_output_z = {np.array2string(z_o, precision=10, max_line_width=96)}")
    order = np.lexsort((main_run["rest_contact_pos"][:, 0], main_run["rest_contact_body"]))
    print(f"chain_drop: rest_contact_dist (by link, then x) = "
          f"{np.array2string(dist[order], precision=4, max_line_width=96)}")


CASES = {"free_chain": run_free_chain, "chain_drop": run_chain_drop}


def main(cases=None):
    try:
        import mujoco
    except ImportError:
        print("mujoco_contact.py: MuJoCo is not installed (pip install mujoco); nothing written "
              "(the tests read the committed .npz files)")
        return
    for case in cases or CASES:
        if case not in CASES:
            raise SystemExit(f"mujoco_contact.py: unknown case {case!r}: "
                             f"one of {', '.join(CASES)}")
        CASES[case](mujoco.__version__)


if __name__ == "__main__":
    main(sys.argv[1:] or None)
