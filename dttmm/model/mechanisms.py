"""Closed-loop mechanisms of the benchmark libraries, as models (docs/loops.md).

    model = slider_crank()          # the IFToMM spatial slider-crank, assembled
    model = n_four_bar(2)           # the IFToMM / MBS library's N-four-bar (A02), assembled

Each is a spanning tree plus closing joints (``System.close``), assembled at t = 0 keeping the
joint whose rate the benchmark gives.
"""
import numpy as np

from .assembly import assemble
from ..elements.drives import JointMotion
from ..elements import (BallJoint, PrismaticJoint, RevoluteJoint, RigidBody, UniversalJoint)
from .model import Ground
from .system import System
from .profiles import profile


def _frame(x_axis, z_hint):
    """A right-handed frame whose x axis is along x_axis and whose z axis leans to z_hint."""
    x = np.asarray(x_axis, dtype=float) / np.linalg.norm(x_axis)
    y = np.cross(z_hint, x)
    y /= np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


def _rot_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def slider_crank(tree="slider on the rod", crank_rate=6.0, slide=None):
    """The IFToMM spatial slider-crank (SI units; gravity (0, 0, -9.81)).

    Crank: a revolute joint "A" to the ground at A = (0, 0.1, 0.12) about world x, 0.08 m
    long, along +z at t = 0, 0.12 kg, inertia about its mass centre diag(1e-4, 1e-4, 1e-5)
    (x the joint's axis, z along the crank).  Rod: a ball joint "B" at the crank's end
    B = (0, 0.1, 0.2), 0.3 m to C = (0.2, 0, 0), 0.5 kg, inertia 4e-4 along it and 4e-3
    across.  Slider: 2 kg, inertia diag(1e-4, 1e-4, 1e-4), on a prismatic joint "slide" along
    world x through the origin and a universal joint "C" to the rod (first axis world x in the
    slider, second in the rod across it and x, (0, -2, 1) / sqrt 5 at t = 0).  The crank turns
    at crank_rate (rad/s) at t = 0, the rest consistent with it (assembled keeping "A"); its
    energy is then 0.76643568 J (z = 0 the datum).

    Parameters
    ----------
    tree : {"slider on the rod", "slider on the ground"}
        The spanning tree: the slider hanging from the rod by the universal joint, closed to
        the ground by its prismatic joint (default), or sliding on the ground (its point C
        offset from the ground point A) and closed to the rod by the universal joint.
    crank_rate : float
        The crank's rate at t = 0, rad/s (default 6).
    slide : JointMotion, SpringDamper or JointForce, optional
        A drive of the slide (the slider's x, m), on the joint "slide" whichever the tree (a
        closing joint on the first); with a prescribed motion the start is assembled keeping
        it, not the crank (default None: the slide is free).

    Returns
    -------
    Model
        Bodies "crank", "rod", "slider".

    Examples
    --------
    >>> from dttmm.model.mechanisms import slider_crank
    >>> slider_crank().n_closures
    1
    """
    prescribed = isinstance(slide, JointMotion)
    a, b, c = np.array([0, 0.1, 0.12]), np.array([0, 0.1, 0.2]), np.array([0.2, 0, 0])
    system = System(gravity=[0, 0, -9.81], ground=Ground(position=a))
    system.add(RigidBody(mass=0.12, inertia=[1e-4, 1e-4, 1e-5], inertia_about="mass_center",
                         to_mass_center=[0, 0, 0.04], to_output=[0, 0, 0.08], name="crank",
                         rotation=np.eye(3)),
               RevoluteJoint(axis=[1, 0, 0], rate=crank_rate, name="A"))
    rod_frame = _frame(c - b, [0, 0, 1.0])
    system.add(RigidBody(mass=0.5, inertia=[4e-4, 4e-3, 4e-3], inertia_about="mass_center",
                         to_mass_center=[0.15, 0, 0], to_output=[0.3, 0, 0],
                         rotation=rod_frame, name="rod"), BallJoint(name="B"), parent="crank")
    across = rod_frame.T @ (np.array([0, -2, 1.0]) / np.sqrt(5))     # in the rod's frame
    if tree == "slider on the rod":
        system.add(RigidBody(mass=2.0, inertia=[1e-4] * 3, inertia_about="mass_center",
                             name="slider", rotation=np.eye(3)),
                   UniversalJoint(axis1=across, axis2=[1, 0, 0], name="C"), parent="rod")
        system.close(PrismaticJoint(axis=[1, 0, 0], name="slide", drive=slide), "ground",
                     "slider", at_a=[0, 0, 0])
    elif tree == "slider on the ground":
        system.add(RigidBody(mass=2.0, inertia=[1e-4] * 3, inertia_about="mass_center",
                             to_mass_center=-a, to_output=-a, name="slider"),
                   PrismaticJoint(axis=[1, 0, 0], position=0.0 if prescribed else 0.2,
                                  name="slide", drive=slide))
        system.close(UniversalJoint(axis1=[1, 0, 0], axis2=across, name="C"), "slider", "rod")
    else:
        raise ValueError(f"slider_crank: tree must be 'slider on the rod' or 'slider on the "
                         f"ground', got {tree!r}")
    return assemble(system.build(), keep=[] if prescribed else ["A"])


def _bar(name, rotation):
    """One of the N-four-bar's bars: 1 m, 1 kg, 1/12 kg m^2 about its mass centre across it."""
    return RigidBody(mass=1.0, inertia=[1e-3, 1 / 12, 1 / 12], inertia_about="mass_center",
                     to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0], rotation=rotation,
                     name=name)


def n_four_bar(n=2, theta=0.0, rate=1.0, tree="chain"):
    """The N-four-bar (IFToMM / MBS benchmark library A02): 2n + 1 uniform bars, 1 m and 1 kg
    each (1/12 kg m^2 about the joint axis), n + 1 vertical bars on revolute joints to the
    ground at (i, 0) and n horizontal bars on revolute joints between their tops; axes along
    world z, gravity -9.81 along y.  The tree is the first vertical bar "v0" on the ground point
    (joint "O0"), the horizontal bars "h1".. end to end, each further vertical bar "v1".. hanging
    from a horizontal bar's end; each is closed to the ground at (i, 0) by a revolute joint
    "O1"...

    Parameters
    ----------
    n : int
        The number of horizontal bars (default 2).
    theta : float
        The vertical bars' angle from up, clockwise, rad (default 0: upright).
    rate : float
        theta' at t = 0, rad/s (default 1: the top of the first bar, B_0, moves at (1, 0) m/s
        when upright; every vertical bar turns at -rate about z), the rest assembled.
    tree : {"chain", "shortest", "ground"}
        The spanning tree: "chain" (default) as above, every loop through v0; "shortest": the
        chain as above built with ``System.build(tree="shortest")``, which re-roots every
        vertical bar at its ground pivot and hangs "h{i}" (i >= 2) from v{i}'s top (joint
        "B{i}" reversed), the joints "O{i}" then in the tree and "B1", "H{i}" closing (each
        loop local, as below); "ground": every vertical bar "v0".. "v{n}" is a root on its
        joint "O{i}" at its ground pivot (i, 0) (``System.add(..., at=[i, 0, 0])``), each
        horizontal bar "h{i}" hangs from v{i-1}'s top (joint "H{i}") and is closed to v{i}'s
        top by a revolute joint "B{i}": each loop is then local (its sweep columns pass four
        bars, kernels/assembly/closure.py), the cost linear in n.

    Returns
    -------
    Model

    Examples
    --------
    >>> from dttmm.model.mechanisms import n_four_bar
    >>> n_four_bar(2).n_closures
    2
    """
    z = [0, 0, 1.0]
    system = System(gravity=[0, -9.81, 0])
    if tree == "ground":
        for i in range(n + 1):
            system.add(_bar(f"v{i}", _rot_z(np.pi / 2 - theta)),
                       RevoluteJoint(axis=z, rate=-rate if i == 0 else 0.0, name=f"O{i}"),
                       at=[float(i), 0, 0])
        for i in range(1, n + 1):
            system.add(_bar(f"h{i}", np.eye(3)), RevoluteJoint(axis=z, name=f"H{i}"),
                       parent=f"v{i - 1}")
            system.close(RevoluteJoint(axis=z, name=f"B{i}"), f"h{i}", f"v{i}")
        return assemble(system.build(), keep=["O0"])
    if tree not in ("chain", "shortest"):
        raise ValueError(f"n_four_bar: tree must be 'chain', 'shortest' or 'ground', got "
                         f"{tree!r}")
    system.add(_bar("v0", _rot_z(np.pi / 2 - theta)), RevoluteJoint(axis=z, rate=-rate, name="O0"))
    inboard = "v0"
    for i in range(1, n + 1):
        system.add(_bar(f"h{i}", np.eye(3)), RevoluteJoint(axis=z, name=f"H{i}"), parent=inboard)
        system.add(_bar(f"v{i}", _rot_z(-np.pi / 2 - theta)), RevoluteJoint(axis=z, name=f"B{i}"),
                   parent=f"h{i}")
        system.close(RevoluteJoint(axis=z, name=f"O{i}"), f"v{i}", "ground")
        inboard = f"h{i}"
    return assemble(system.build(tree="as added" if tree == "chain" else tree), keep=["O0"])


def parallelogram(n, t, theta=0.0, rate=1.0):
    """B_0(t) = (sin th, cos th) of the N-four-bar's exact one-degree-of-freedom reduction: the
    vertical bars turn alike by th (clockwise from up), the horizontal bars translate, so
    I th'' = 9.81 c sin th with I = (n + 1) / 3 + n and c = (n + 1) / 2 + n (scipy's DOP853 at
    rtol 1e-13)."""
    from scipy.integrate import solve_ivp
    inertia, c = (n + 1) / 3 + n, (n + 1) / 2 + n
    t = np.asarray(t, dtype=float)
    sol = solve_ivp(lambda _, y: [y[1], 9.81 * c * np.sin(y[0]) / inertia], (0, t[-1]),
                    [theta, rate], method="DOP853", rtol=1e-13, atol=1e-14, t_eval=t)
    return np.stack([np.sin(sol.y[0]), np.cos(sol.y[0])], axis=1)


STEWART_BASE_ANGLES = (-10.0, 10.0, 110.0, 130.0, 230.0, 250.0)        # deg, about z from +x
STEWART_PLATFORM_ANGLES = (-50.0, 50.0, 70.0, 170.0, 190.0, 290.0)


def stewart_reference_slide(i, t):
    """Leg i's (0-based) reference slide s_i(t) = +-0.05 (1 - cos 2 pi t), m (+ for legs 1, 3, 5;
    - for 2, 4, 6), with its rate and acceleration."""
    sign = 1.0 if i % 2 == 0 else -1.0
    w = 2.0 * np.pi
    return (sign * 0.05 * (1.0 - np.cos(w * t)), sign * 0.05 * w * np.sin(w * t),
            sign * 0.05 * w * w * np.cos(w * t))


def stewart_platform(drive="motion", gravity=(0.0, 0.0, -9.81), slide_rates=None):
    """A Stewart platform (issue 29's data; SI units, gravity -9.81 along z).

    Six legs; leg i joins the base point b_i (radius 1, z = 0, angle beta_i) to the platform
    point p_i (radius 0.5 in the platform's plane, angle pi_i), STEWART_BASE_ANGLES and
    STEWART_PLATFORM_ANGLES.  Platform: 10 kg, inertia about its centre diag(0.5, 0.5, 0.8),
    centre (0, 0, 1), as the world at t = 0.  Each leg: a lower body "lower{i}" (2 kg, mass
    centre 0.3 m from b_i along the leg, inertia 0.002 along it and 0.06 across) on a universal
    joint "U{i}" at b_i (first axis world z, second across z and the leg), an upper body
    "upper{i}" (1 kg, mass centre 0.3 m from p_i along the leg, inertia 0.001 along, 0.03 across)
    on a prismatic joint "P{i}" along the leg, and a ball joint at p_i.  The tree: a base welded
    to the ground carries the six b_i as named points; the platform hangs from leg 1's upper
    body by its ball joint; legs 2-6 close on it by ball joints "S2".."S6" (5 loops, 6 degrees
    of freedom).

    Parameters
    ----------
    drive : {"motion", "force", "free"}
        "motion": each slide follows stewart_reference_slide from rest; "force": each slide
        is pushed by 2e4 (s_ref - s) - 500 s' N (a Python JointForce); "free": no drive.
    gravity : array_like of 3
        m/s^2 (default (0, 0, -9.81)).
    slide_rates : sequence of 6 float, optional
        The slides' rates at t = 0 (m/s; free drives), the rest assembled consistent with them
        (a least-change projection, so they come out close to, not exactly, these).

    Returns
    -------
    Model
    """
    from ..elements import FixedHinge, JointForce, JointMotion
    beta = np.radians(STEWART_BASE_ANGLES)
    gamma = np.radians(STEWART_PLATFORM_ANGLES)
    b = np.stack([np.cos(beta), np.sin(beta), np.zeros(6)], axis=1)
    centre = np.array([0.0, 0.0, 1.0])
    p = centre + 0.5 * np.stack([np.cos(gamma), np.sin(gamma), np.zeros(6)], axis=1)
    system = System(gravity=gravity)
    system.add(RigidBody(mass=1.0, inertia=[1.0, 1.0, 1.0], inertia_about="mass_center",
                         name="base",
                         points={f"b{i + 1}": b[i] for i in range(6)}),
               FixedHinge(name="base weld"))
    for i in range(6):
        leg = p[i] - b[i]
        length = float(np.linalg.norm(leg))
        frame = _frame(leg, [0, 0, 1.0])
        across = np.cross([0, 0, 1.0], leg)
        across /= np.linalg.norm(across)
        if drive == "motion":           # a profile, so that the model saves to a scene
            sign = 1.0 if i % 2 == 0 else -1.0
            slide = profile({"profile": "sine", "amplitude": -0.05 * sign,
                             "angular_frequency": 2.0 * np.pi, "phase": 0.5 * np.pi,
                             "offset": 0.05 * sign})
            d = JointMotion(position=slide, velocity=slide.rate, acceleration=slide.acceleration)
        elif drive == "force":
            d = JointForce(lambda t, q, qd, i=i: 2e4 * (stewart_reference_slide(i, t)[0] - q)
                           - 500.0 * qd)
        elif drive == "free":
            d = None
        else:
            raise ValueError(f"stewart_platform: drive must be 'motion', 'force' or 'free', got "
                             f"{drive!r}")
        system.add(RigidBody(mass=2.0, inertia=[0.002, 0.06, 0.06], inertia_about="mass_center",
                             to_mass_center=[0.3, 0, 0], to_output=[0.0, 0, 0], rotation=frame,
                             name=f"lower{i + 1}"),
                   UniversalJoint(axis1=[0, 0, 1.0], axis2=frame.T @ across, name=f"U{i + 1}"),
                   parent="base", at=f"b{i + 1}")
        system.add(RigidBody(mass=1.0, inertia=[0.001, 0.03, 0.03], inertia_about="mass_center",
                             to_mass_center=[length - 0.3, 0, 0], to_output=[length, 0, 0],
                             rotation=frame, name=f"upper{i + 1}"),
                   PrismaticJoint(axis=[1.0, 0, 0], drive=d, name=f"P{i + 1}",
                                  rate=0.0 if slide_rates is None else slide_rates[i]),
                   parent=f"lower{i + 1}")
    system.add(RigidBody(mass=10.0, inertia=[0.5, 0.5, 0.8], inertia_about="mass_center",
                         to_mass_center=centre - p[0], to_output=centre - p[0],
                         rotation=np.eye(3), name="platform",
                         points={f"p{i + 1}": p[i] - p[0] for i in range(1, 6)}),
               BallJoint(name="S1"), parent="upper1")
    for i in range(1, 6):
        system.close(BallJoint(name=f"S{i + 1}"), f"upper{i + 1}", "platform",
                     at_b=f"p{i + 1}")
    return assemble(system.build())


FLEXIBLE_CRANK_RATE = 150.0          # rad/s, seed 000's prescribed crank speed


def flexible_slider_crank(elements=1, modes=3, axial_modes=1, crank_rate=FLEXIBLE_CRANK_RATE,
                          crank_mass=0.1):
    """The flexible slider-crank of seed 000 (section 1.4; planar, no gravity; SI units).

    Crank OA: a rigid bar 0.15 m long on a revolute joint "O" about world z at the origin,
    turned at a prescribed crank_rate (rad/s, counterclockwise) from theta = 0 (A on +x);
    crank_mass (kg, uniform bar; the benchmark leaves it open, and under the prescribed motion
    only the drive's torque depends on it).  Rod AB: an Euler-Bernoulli beam of steel, 0.3 m,
    circular section d = 6 mm (E = 2e11 Pa, rho = 7870 kg/m^3, so mu = 0.2225 kg/m, EI = 12.72
    N m^2, EA = 5.65e6 N), stretching (axial_modes), on a revolute joint "A" about z at the
    crank's end, made of `elements` beams welded end to end ("rod1".., each with `modes` bending
    modes per plane).  Slider B: a point mass of half the rod's mass, "slider", on a prismatic
    joint "slide" along world x; the rod's output end is closed to it by a revolute joint "B"
    about z.  At t = 0 the rod lies straight along +x with rigid-body velocities (assembled
    keeping the crank's drive).

    Returns
    -------
    Model
        Bodies "crank", "rod1".. "rod{elements}", "slider".
    """
    from ..elements import EulerBernoulliBeam, FixedHinge, JointMotion
    crank, rod = 0.15, 0.3
    d = 6e-3
    area, second_moment = np.pi * d * d / 4, np.pi * d ** 4 / 64
    density, young = 7870.0, 2e11
    mu = density * area
    z = [0, 0, 1.0]
    system = System(gravity=[0, 0, 0])
    angle = profile({"profile": "linear", "slope": float(crank_rate)})    # (saves to a scene)
    drive = JointMotion(position=angle, velocity=angle.rate, acceleration=angle.acceleration)
    system.add(RigidBody(mass=crank_mass, inertia=[1e-6, crank_mass * crank ** 2 / 12,
                                                   crank_mass * crank ** 2 / 12],
                         inertia_about="mass_center", to_mass_center=[crank / 2, 0, 0],
                         to_output=[crank, 0, 0], rotation=np.eye(3), name="crank"),
               RevoluteJoint(axis=z, drive=drive, name="O"))
    length = rod / elements
    for i in range(elements):
        beam = EulerBernoulliBeam(length=length, density=density, area=area,
                                  bending_stiffness=young * second_moment,
                                  polar_inertia_per_length=density * 2 * second_moment,
                                  modes_per_plane=modes, axial_modes=axial_modes,
                                  axial_stiffness=young * area, rotation=np.eye(3),
                                  name=f"rod{i + 1}")
        joint = RevoluteJoint(axis=z, name="A") if i == 0 else FixedHinge(name=f"weld{i}")
        system.add(beam, joint, parent="crank" if i == 0 else f"rod{i}")
    slider_mass = 0.5 * mu * rod
    system.add(RigidBody(mass=slider_mass, inertia=[1e-9] * 3, inertia_about="mass_center",
                         name="slider", rotation=np.eye(3)),
               PrismaticJoint(axis=[1.0, 0, 0], position=crank + rod, name="slide"))
    system.close(RevoluteJoint(axis=z, name="B"), f"rod{elements}", "slider")
    return assemble(system.build(), keep=["O"])
