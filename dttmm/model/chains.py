"""Ready-made chains and trees used by the examples, tests and benchmarks."""
import numba
import numpy as np

from ..elements import (BallJoint, Box, Capsule, Contact, EulerBernoulliBeam, FixedHinge,
                        FreeJoint, Plane, RigidBody, Sphere)
from .model import Ground
from .profiles import profile
from .system import System, build_chain

# +90 degrees about world y: a body's x axis along world -z
TURNED_ABOUT_Y = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])


# the unit link's vectors, shared by every link (immutable): a million links each with their
# own three lists held 420 MB of the million-link chain's 2.3 GB peak (issue 65, item 11)
_UNIT_INERTIA, _UNIT_MASS_CENTER, _UNIT_OUTPUT = (1.0 / 6.0, 5.0 / 12.0, 5.0 / 12.0), \
    (0.5, 0.0, 0.0), (1.0, 0.0, 0.0)


def unit_link(**kwargs):
    """The paper's 1 m, 1 kg link: mass centre at [0.5, 0, 0], output point at [1, 0, 0] m,
    inertia about the input point diag(1/6, 5/12, 5/12) kg m^2 (a uniform 1 m cube)."""
    return RigidBody(mass=1.0, inertia=_UNIT_INERTIA, inertia_about="input",
                     to_mass_center=_UNIT_MASS_CENTER, to_output=_UNIT_OUTPUT, **kwargs)


def rigid_chain(n_links, gravity=(0.0, -9.81, 0.0), tip_angular_velocity=(0.0, 0.1, 0.0)):
    """n_links unit links joined by ball-and-socket hinges, link 1 to the ground at the origin,
    all along +x at rest except the last, which spins at tip_angular_velocity."""
    if int(n_links) != n_links or n_links < 1:
        raise ValueError(f"rigid_chain: n_links must be an integer >= 1, got {n_links!r}")
    elements = []
    for k in range(int(n_links)):
        w = np.asarray(tip_angular_velocity, float) if k == n_links - 1 else None
        elements += [BallJoint(), unit_link(name=f"link{k + 1}", angular_velocity=w)]
    return build_chain(elements, gravity=gravity)


def three_pendulum(modes_per_plane=2, damping_ratio=0.0, gravity=(0.0, -9.81, 0.0),
                   stiffness_factor=1.0, tip_angular_velocity=(0.0, 0.1, 0.0), stiffening=False):
    """The paper's Section 5 system (notes §6): rigid body 2, ball joint, beam 4 (1 m, 1.32 kg,
    E = 2.5e10 Pa, rho = 3300 kg/m^3, 20 mm square section), ball joint, rigid body 6; joint 1
    joins body 2 to the ground at the origin.  All along +x at rest, except body 6 with angular
    velocity tip_angular_velocity ([0, 0.1, 0] rad/s).  stiffness_factor multiplies the beam's
    modulus (a stiff variant for the stability study); stiffening: the beam's geometric
    stiffening (docs/beam.md; off by default here: the paper's beam, the main job's)."""
    from ..elements import EulerBernoulliBeam
    side = 0.02
    area = side * side
    beam = EulerBernoulliBeam(length=1.0, density=3300.0, area=area,
                              bending_stiffness=stiffness_factor * 2.5e10 * side ** 4 / 12.0,
                              polar_inertia_per_length=3300.0 * area * side * side / 6.0,
                              modes_per_plane=modes_per_plane, damping_ratio=damping_ratio,
                              stiffening=stiffening, name="beam4")
    return build_chain([BallJoint(name="joint1"), unit_link(name="body2"),
                        BallJoint(name="joint3"), beam,
                        BallJoint(name="joint5"),
                        unit_link(name="body6", angular_velocity=tip_angular_velocity)],
                       gravity=gravity)


def stiff_cantilever(n_elements, length=5.0, joint=FixedHinge):
    """A cantilever of n_elements beam elements (EI = 1e4 N m^2, 2 kg/m, two modes per plane)
    welded end to end by fixed hinges: the stiff beam chain of the stability study.  joint:
    the hinge class before every element (BallJoint: a hanging chain of the same elements)."""
    from ..elements import EulerBernoulliBeam
    elements = []
    for _ in range(n_elements):
        elements += [joint(),
                     EulerBernoulliBeam(length=length / n_elements, bending_stiffness=1e4,
                                        mass_per_length=2.0, polar_inertia_per_length=1e-3,
                                        modes_per_plane=2)]
    return build_chain(elements)


def five_link_tree(gravity=(0.0, -9.81, 0.0)):
    """Five unit links joined by ball joints (examples/tree.py): link 1 on the ground at the
    origin; links 2 and 4 both on link 1's output point; link 3 on link 2's, link 5 on link 4's.
    Links 1-3 along +x; links 4 and 5 turned by +90 deg about world y (along -z: link 4's output
    at (1, 0, -1), link 5's at (1, 0, -2)).  All at rest except link 3, world angular velocity
    [0, 0.1, 0] rad/s, and link 5, [0.2, 0, 0] rad/s."""
    system = System(gravity=gravity)
    system.add(unit_link(name="link1"), BallJoint(name="joint1"))
    system.add(unit_link(name="link2"), BallJoint(name="joint2"), parent="link1")
    system.add(unit_link(name="link3", angular_velocity=[0.0, 0.1, 0.0]),
               BallJoint(name="joint3"), parent="link2")
    system.add(unit_link(name="link4", rotation=TURNED_ABOUT_Y), BallJoint(name="joint4"),
               parent="link1")
    system.add(unit_link(name="link5", rotation=TURNED_ABOUT_Y, angular_velocity=[0.2, 0.0, 0.0]),
               BallJoint(name="joint5"), parent="link4")
    return system.build()


def binary_tree(depth, gravity=(0.0, -9.81, 0.0)):
    """2^depth - 1 unit links joined by ball joints, each carrying two children on its output
    point (node i's parent is (i - 1) // 2, breadth first), the root on the ground at the
    origin.  The children are turned alternately by +-0.3 rad about world y, so the tree
    spreads; every fifth link spins at [0, 0, 0.3] rad/s, the rest are at rest."""
    if int(depth) != depth or depth < 1:
        raise ValueError(f"binary_tree: depth must be an integer >= 1, got {depth!r}")
    c, s = np.cos(0.3), np.sin(0.3)
    turn = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    system = System(gravity=gravity)
    system.add(unit_link(name="n0"), BallJoint())
    for i in range(1, 2 ** int(depth) - 1):
        system.add(unit_link(name=f"n{i}", rotation=turn if i % 2 else turn.T,
                             angular_velocity=[0.0, 0.0, 0.3] if i % 5 == 0 else None),
                   BallJoint(), parent=f"n{(i - 1) // 2}")
    return system.build()


@numba.njit
def arm_servo(t, q, q_dot):
    """The arm's joint-1 feedback law compiled with numba (drive "pd-njit"): kp (target - q) +
    kd (target' - q'), kp = 200 N m/rad, kd = 20 N m s/rad, target = 0.5 t + 0.2 (1 - cos 2t)
    rad; the same law as drive "pd"'s PDTracking."""
    target = 0.5 * t + 0.2 * (1.0 - np.cos(2.0 * t))
    rate = 0.5 + 0.4 * np.sin(2.0 * t)
    return 200.0 * (target - q) + 20.0 * (rate - q_dot)


def arm(drive="torque", flexible=False, gravity=(0.0, -9.81, 0.0), undriven=False, stop=None):
    """The arm of examples/arm.py (docs/joints.md): link 1 on a revolute joint at the origin
    about world y; link 2 on a revolute joint at link 1's output point about link 1's body z;
    link 3 on a universal joint at link 2's output point (first axis link 2's body z, second
    link 3's body y); body 4 (0.5 kg, inertia diag(0.01) kg m^2 about its mass centre, which is
    its joint point) on a prismatic joint along link 3's body x through link 3's output point,
    with a 50 N/m spring and a 0.5 N s/m damper.  All along +x, joint 1 turning at 0.5 rad/s.
    drive "torque": 2 sin(pi t) N m on joint 1; "motion": joint 1's angle prescribed as
    0.5 t + 0.2 (1 - cos 2t) rad; "pd": joint 1 tracks that angle by PD feedback, kp = 200 N
    m/rad, kd = 20 N m s/rad (a PDTracking, inside the compiled loop); "pd-njit": the same
    law written as a numba-compiled JointForce (arm_servo), also inside it.  flexible: link 2 is
    the paper's beam 4 (1 m, 20 mm square section, E = 2.5e10 Pa, rho = 3300 kg/m^3).
    undriven: no drive on joint 1 and no damper
    (the energy test).  stop: a JointLimit on joint 1 (examples/end_stop.py)."""
    from ..elements import (EulerBernoulliBeam, JointForce, JointMotion, PDTracking,
                            PrismaticJoint, RevoluteJoint, SpringDamper, UniversalJoint)
    from .profiles import ProfileForce, profile
    if drive not in ("torque", "motion", "pd", "pd-njit"):
        raise ValueError(f"arm: drive must be 'torque', 'motion', 'pd' or 'pd-njit', got "
                         f"{drive!r}")
    if undriven:
        first = None
    elif drive == "pd-njit":
        first = JointForce(arm_servo)
    elif drive == "torque":
        first = JointForce(ProfileForce(profile(       # 2 sin(pi t), N m
            {"profile": "sine", "amplitude": 2.0, "frequency": 0.5})))
    else:                                               # 0.5 t + 0.2 (1 - cos 2t), rad
        angle = profile({"profile": "sum", "terms": [
            {"profile": "linear", "slope": 0.5},
            {"profile": "sine", "amplitude": -0.2, "angular_frequency": 2.0,
             "phase": np.pi / 2, "offset": 0.2}]})
        first = (JointMotion(position=angle, velocity=angle.rate,
                             acceleration=angle.acceleration) if drive == "motion" else
                 PDTracking(kp=200.0, kd=20.0, target=angle, target_rate=angle.rate))
    if flexible:
        side = 0.02
        area = side * side
        link2 = EulerBernoulliBeam(length=1.0, density=3300.0, area=area,
                                   bending_stiffness=2.5e10 * side ** 4 / 12.0,
                                   polar_inertia_per_length=3300.0 * area * side * side / 6.0,
                                   modes_per_plane=1, name="link2")
        # (one mode: with the default's two (the second at 88 Hz) the joints' order tests at
        # dt 5e-4 and 2.5e-4 s measured order 1.5, outside the asymptotic range; describe()
        # shows what one mode leaves out: 17% on the first frequency)
    else:
        link2 = unit_link(name="link2")
    system = System(gravity=gravity)
    system.add(unit_link(name="link1"), RevoluteJoint(axis=[0, 1, 0], rate=0.5, drive=first,
                                                      name="joint1", limits=stop))
    system.add(link2, RevoluteJoint(axis=[0, 0, 1], name="joint2"), parent="link1")
    system.add(unit_link(name="link3"), UniversalJoint(axis1=[0, 0, 1], axis2=[0, 1, 0],
                                                       name="joint3"), parent="link2")
    system.add(RigidBody(mass=0.5, inertia=[0.01, 0.01, 0.01], inertia_about="mass_center",
                         name="body4"),
               PrismaticJoint(axis=[1, 0, 0], name="joint4",
                              drive=SpringDamper(50.0, 0.0 if undriven else 0.5)),
               parent="link3")
    return system.build()


def tumbling_box(sides=(0.3, 0.2, 0.1), mass=1.0, angular_velocity=(1e-3, 4.0, 1e-3)):
    """A uniform box (m, kg) on a free joint at the origin, its input point at its mass centre,
    the identity rotation, spun at angular_velocity (rad/s; body axes = world at t = 0), no
    gravity: Dzhanibekov's nut (examples/tumbling_body.py; docs/free_joint.md)."""
    sides = np.asarray(sides, dtype=float)
    inertia = mass * (np.sum(sides ** 2) - sides ** 2) / 12.0      # (b^2 + c^2) m / 12, ...
    box = RigidBody(mass=mass, inertia=inertia, inertia_about="mass_center",
                    angular_velocity=angular_velocity, name="box")
    return build_chain([FreeJoint(name="free"), box], gravity=[0.0, 0.0, 0.0])


def slew_torque(torque=10.0, duration=2.0):
    """The spacecraft's slew: a couple of `torque` N m about world z until `duration` s, then
    none (a pulse profile: their mean at the switch itself, where the trapezoidal rule's
    impulse is then exact; model/profiles.py)."""
    return profile({"profile": "pulse", "value": [0.0, 0.0, float(torque)],
                    "duration": float(duration)})


def spacecraft(hub_mass=200.0, hub_side=1.0, panel_length=2.0, panel_width=0.5,
               panel_thickness=2e-3, young=70e9, density=2700.0, torque=slew_torque(),
               modes_per_plane=None):
    """A free rigid hub (a uniform cube, kg, m) with two flat panels (beams: aluminium by
    default, Pa, kg/m^3) clamped at the centres of its +x and -x faces and extending along x,
    their thickness in the x-y plane (the slew's): "panel+x", "panel-x" on fixed hinges to the
    hub's named points.  The hub on a free joint at the origin, at rest; `torque(t)` (N m, a
    callable or 3 numbers) acts on it; no gravity (examples/spacecraft.py; docs/free_joint.md).
    The panels' foreshortening is kept to all orders (stiffening="exact"): their positions,
    and the momenta from them, are the model's own to every order."""
    half = 0.5 * hub_side
    hub = RigidBody(mass=hub_mass, inertia=hub_mass * hub_side ** 2 / 6.0,
                    inertia_about="mass_center", torque=torque, name="hub",
                    points={"+x": [half, 0.0, 0.0], "-x": [-half, 0.0, 0.0]})
    area = panel_width * panel_thickness
    in_plane = young * panel_width * panel_thickness ** 3 / 12.0     # bending along y
    out_of_plane = young * panel_thickness * panel_width ** 3 / 12.0    # along z
    polar = density * (panel_width * panel_thickness ** 3 + panel_thickness
                       * panel_width ** 3) / 12.0
    system = System(gravity=[0.0, 0.0, 0.0])
    system.add(hub, FreeJoint(name="free"))
    for side, turn in (("+x", np.eye(3)), ("-x", np.diag([-1.0, -1.0, 1.0]))):
        panel = EulerBernoulliBeam(length=panel_length, density=density, area=area,
                                   bending_stiffness=[in_plane, out_of_plane],
                                   polar_inertia_per_length=polar, stiffening="exact",
                                   modes_per_plane=modes_per_plane, name=f"panel{side}")
        system.add(panel, FixedHinge(rotation=turn, name=f"clamp{side}"), parent="hub", at=side)
    return system.build()


def bouncing_ball(radius=0.05, density=7850.0, height=1.0, restitution=0.8, contact_time=2e-4):
    """A uniform ball (m, kg/m^3) on a free joint, its centre `height` m above the plane z = 0
    at rest, gravity -9.81 along z; its contact (docs/contact.md) rebounds it at `restitution`
    and lasts about contact_time s (a steel ball's on steel: Hertz's law gives ~0.2 ms at the
    4.3 m/s of a 1 m drop) (examples/bouncing_ball.py)."""
    mass = density * 4.0 / 3.0 * np.pi * radius ** 3
    ball = RigidBody(mass=mass, inertia=0.4 * mass * radius ** 2, inertia_about="mass_center",
                     name="ball", shapes=Sphere(radius),
                     contact=Contact(contact_time=contact_time, restitution=restitution))
    return build_chain([FreeJoint(position=[0.0, 0.0, height], name="free"), ball],
                       gravity=[0.0, 0.0, -9.81], ground=Ground(plane=Plane()))


def incline_normal(angle):
    """The unit normal of a plane through the origin inclined by `angle` rad about y, which
    falls along +x: (sin a, 0, cos a); down its slope is (cos a, 0, -sin a)."""
    return np.array([np.sin(angle), 0.0, np.cos(angle)])


def box_on_incline(friction=0.3, angle=np.radians(30.0), sides=(0.2, 0.2, 0.1), mass=1.0,
                   contact_time=2e-3, restitution=0.5):
    """A uniform box (m, kg) resting on its largest face on a plane through the origin inclined
    by `angle` rad (incline_normal), at rest, its corners just touching; each corner's
    stiffness is the one that would hold the whole box for contact_time s (docs/contact.md:
    k = m (pi / T)^2, so the box on its four lasts about T / 2), Coulomb's friction, static =
    kinetic; gravity -9.81 along z (examples/incline.py)."""
    sides = np.asarray(sides, dtype=float)
    inertia = mass * (np.sum(sides ** 2) - sides ** 2) / 12.0
    c, s = np.cos(angle), np.sin(angle)
    tilt = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])     # its z along the normal
    box = RigidBody(mass=mass, inertia=inertia, inertia_about="mass_center", rotation=tilt,
                    name="box", shapes=Box(sides),
                    contact=Contact(contact_time=contact_time, restitution=restitution,
                                    friction=friction))
    normal = incline_normal(angle)
    return build_chain([FreeJoint(position=0.5 * sides[2] * normal, name="free"), box],
                       gravity=[0.0, 0.0, -9.81], ground=Ground(plane=Plane(normal=normal)))


def capsule_chain(n=20, length=0.1, radius=0.02, mass=0.1, height=0.1, contact_time=2e-3,
                  restitution=0.5, friction=0.5, plane_at=0.0, shapes=True):
    """n links (m, kg) on ball joints, the first on a free joint, all along +x at rest with
    their input points at `height` above the plane z = plane_at (gravity -9.81 along z), each
    a capsule of `radius` from its input to its output point (docs/contact.md; its contact
    lasting about contact_time s on one sphere), mass centre at mid-length, inertia
    diag(2e-4, 1e-3, 1e-3) m (m^2): the chain dropped flat onto the ground
    (tests/test_contact_mujoco.py, benchmarks/contact.py).  shapes=False: the same chain
    without shapes (and no plane)."""
    links = []
    for k in range(n):
        body = RigidBody(
            mass=mass, inertia=mass * np.array([2e-4, 1e-3, 1e-3]), inertia_about="mass_center",
            to_mass_center=[0.5 * length, 0.0, 0.0], to_output=[length, 0.0, 0.0],
            name=f"link{k}",
            **(dict(shapes=Capsule(radius, [0.0, 0.0, 0.0], [length, 0.0, 0.0]),
                    contact=Contact(contact_time=contact_time, restitution=restitution,
                                    friction=friction)) if shapes else {}))
        links += [FreeJoint(position=[0.0, 0.0, height]) if k == 0 else BallJoint(), body]
    ground = Ground(plane=Plane(point=[0.0, 0.0, plane_at])) if shapes else Ground()
    return build_chain(links, gravity=[0.0, 0.0, -9.81], ground=ground)
