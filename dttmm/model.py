"""The chain description: built from elements, validated once, frozen into flat arrays."""
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np

from .elements import (BALL, BEAM, FIXED, RIGID, BallJoint, ElasticHinge, EulerBernoulliBeam,
                       FixedHinge, RigidBody)
from .elements.beam import (AUTO, BEAM_PARAM_SIZE, CLAMPED, CLAMPED_LOADED, FAMILY, LENGTH,
                            MAX_LOADED_MODES, MODES, PINNED, mode_shapes)
from .elements._checks import finite_vector, rotation_matrix
from .elements.hinges import HINGE_KIND_NAMES, pack_hinge
from .elements.rigid_body import pack_body
from .kernels.so3 import expm_so3, left_jacobian


class PrescribedMotion:
    """Prescribed motion of the ground frame (a driven hub), as functions of time.

    Each argument is a function of t (or None for zero / identity): position, velocity and
    acceleration of the ground point (world, m), rotation matrix of the ground frame, and its
    world-frame angular velocity and angular acceleration.  Derivatives are given, not
    differentiated numerically, so the solver sees the exact motion.
    """

    def __init__(self, position=None, velocity=None, acceleration=None,
                 rotation=None, angular_velocity=None, angular_acceleration=None):
        self._f = (position, velocity, acceleration, rotation, angular_velocity, angular_acceleration)
        for name, f in zip(("position", "velocity", "acceleration", "rotation",
                            "angular_velocity", "angular_acceleration"), self._f):
            if f is not None and not callable(f):
                raise ValueError(f"PrescribedMotion: {name} must be a function of time or None")

    def check(self, times=(0.0, 0.37, 1.0), eps=1e-5, rtol=1e-4):
        """Raise ValueError if the given derivatives contradict the position and rotation
        (central differences at a few times)."""
        def fd(f, t):
            return (np.asarray(f(t + eps)) - np.asarray(f(t - eps))) / (2 * eps)

        for t in times:
            r, v, a, rot, w, wd = self(t)
            rot_dot = (self(t + eps)[3] - self(t - eps)[3]) / (2 * eps)
            w_fd = rot_dot @ rot.T
            pairs = (("velocity", v, fd(lambda s: self(s)[0], t)),
                     ("acceleration", a, fd(lambda s: self(s)[1], t)),
                     ("angular_velocity", w, np.array([w_fd[2, 1], w_fd[0, 2], w_fd[1, 0]])),
                     ("angular_acceleration", wd, fd(lambda s: self(s)[4], t)))
            for name, given, numeric in pairs:
                scale = max(1.0, np.abs(numeric).max())
                if not np.all(np.isfinite(given)) or np.abs(given - numeric).max() > rtol * scale:
                    raise ValueError(f"PrescribedMotion: {name}({t:g}) = {given} contradicts the "
                                     f"motion's own derivative {numeric}")

    def __call__(self, t):
        """(r, v, a, R, w, w_dot) at time t."""
        r, v, a, rot, w, wd = self._f
        zero = np.zeros(3)
        return (zero if r is None else np.asarray(r(t), float),
                zero if v is None else np.asarray(v(t), float),
                zero if a is None else np.asarray(a(t), float),
                np.eye(3) if rot is None else np.asarray(rot(t), float),
                zero if w is None else np.asarray(w(t), float),
                zero if wd is None else np.asarray(wd(t), float))

    @classmethod
    def spin_about_axis(cls, axis, angle, rate, acceleration, position=(0.0, 0.0, 0.0)):
        """Rotation by angle(t) about a fixed world axis through a fixed point; rate and
        acceleration are the first and second derivatives of angle(t)."""
        n = np.asarray(axis, float)
        n = n / np.linalg.norm(n)
        k = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
        p = np.asarray(position, float)

        def rotation(t):
            th = angle(t)
            return np.eye(3) + np.sin(th) * k + (1.0 - np.cos(th)) * k @ k

        return cls(position=lambda t: p, rotation=rotation,
                   angular_velocity=lambda t: rate(t) * n,
                   angular_acceleration=lambda t: acceleration(t) * n)


@dataclass(frozen=True)
class Ground:
    """Where the root hinge attaches: a fixed point and frame, or a prescribed motion."""
    position: object = (0.0, 0.0, 0.0)
    rotation: object = None
    motion: Optional[PrescribedMotion] = None


@dataclass(frozen=True, eq=False)
class Model:
    """A frozen chain: flat float arrays for the kernels plus the description it came from.

    Bodies are numbered 0..n-1 from the root; hinge k joins body k-1 (the ground for k = 0) to
    body k.  The last body's output point is the free tip.
    """
    n_bodies: int
    body_params: np.ndarray          # (n, BODY_PARAM_SIZE), see elements/rigid_body.py
    hinge_kind: np.ndarray           # (n,) BALL / FIXED / ELASTIC
    hinge_params: np.ndarray         # (n, HINGE_PARAM_SIZE), see elements/hinges.py
    gravity: np.ndarray              # (3,) world, m/s^2
    ground_position: np.ndarray      # (3,) at rest (motion is None) or at t = 0
    ground_rotation: np.ndarray      # (3, 3)
    ground_motion: Optional[PrescribedMotion]
    initial_rotation: np.ndarray     # (n, 3, 3)
    initial_angular_velocity: np.ndarray  # (n, 3) world
    ground_locked: np.ndarray        # (n,) bool: rotation fixed to the ground frame by fixed hinges
    forces: tuple                    # per body: None or f(t) -> world force at the mass centre
    torques: tuple                   # per body: None or f(t) -> world torque
    body_names: tuple
    hinge_names: tuple
    body_mass_center_inertia: np.ndarray  # (n, 3, 3) J_C in body axes (for energies)
    tip_pinned: bool                 # the tip is joined to the ground by a ball joint (else free)
    body_kind: np.ndarray            # (n,) RIGID / BEAM
    beam_params: np.ndarray          # (n, BEAM_PARAM_SIZE), zero rows for rigid bodies; for a
                                     # beam, body_params holds the undeformed beam as a rigid body
                                     # (its FAMILY column resolved: PINNED, CLAMPED or
                                     # CLAMPED_LOADED)
    initial_modal_coordinates: np.ndarray  # (total modes,) flat in body order (v then w)
    initial_modal_velocities: np.ndarray

    @property
    def n_modes(self):
        """(n,) modal coordinates of each body: 2 x modes per plane for a beam, 0 if rigid."""
        return np.where(self.body_kind == BEAM, 2 * self.beam_params[:, MODES], 0).astype(np.int64)

    @property
    def has_beams(self):
        return bool(np.any(self.body_kind == BEAM))

    @property
    def all_ball(self):
        """True when every hinge is a ball joint: the reduced [a; q] transfer applies."""
        return bool(np.all(self.hinge_kind == BALL))

    @property
    def has_applied_loads(self):
        return any(f is not None for f in self.forces + self.torques)

    def ground_state(self, t):
        """(r, v, a, R, w, w_dot) of the ground frame at time t."""
        if self.ground_motion is None:
            z = np.zeros(3)
            return self.ground_position, z, z, self.ground_rotation, z, z
        return self.ground_motion(t)


def build_chain(elements: Sequence, gravity=(0.0, -9.81, 0.0), ground: Ground = Ground(),
                tip="free") -> Model:
    """Validate a chain described root to tip and freeze it into a Model.

    elements alternates hinges and bodies, starting with the root hinge (which joins the first
    body to the ground) and ending with the tip body:
        [hinge_0, body_0, hinge_1, body_1, ..., hinge_{n-1}, body_{n-1}]
    tip: "free" (default), or "ball": the tip body's output point is joined to the ground by a
    ball-and-socket joint where it starts (a fixed point; e.g. a simply supported beam).
    """
    if tip not in ("free", "ball"):
        raise ValueError(f"Chain: tip must be 'free' or 'ball', got {tip!r}")
    elements = list(elements)
    if len(elements) == 0:
        raise ValueError("Chain: elements is empty; a chain needs at least a root hinge and a body")
    if len(elements) % 2 != 0:
        raise ValueError("Chain: elements must alternate hinge, body, hinge, body, ... and end with "
                         f"a body; got {len(elements)} elements")
    hinges, bodies = elements[0::2], elements[1::2]
    for k, h in enumerate(hinges):
        if not isinstance(h, (BallJoint, FixedHinge, ElasticHinge)):
            raise ValueError(f"Chain: element {2 * k} must be a hinge (BallJoint, FixedHinge, "
                             f"ElasticHinge), got {type(h).__name__}")
    for k, b in enumerate(bodies):
        if not isinstance(b, (RigidBody, EulerBernoulliBeam)):
            raise ValueError(f"Chain: element {2 * k + 1} must be a body (RigidBody, "
                             f"EulerBernoulliBeam), got {type(b).__name__}")
    g = finite_vector("Chain", "gravity", gravity)
    if not isinstance(ground, Ground):
        raise ValueError("Chain: ground must be a Ground")
    if ground.motion is not None:
        ground.motion.check()
        r_g, _, _, rot_g, w_g, _ = ground.motion(0.0)
        r_g = finite_vector("Ground", "motion position(0)", r_g)
        rot_g = rotation_matrix("Ground", "motion rotation(0)", rot_g)
        w_g = finite_vector("Ground", "motion angular_velocity(0)", w_g)
    else:
        r_g = finite_vector("Ground", "position", ground.position)
        rot_g = np.eye(3) if ground.rotation is None else rotation_matrix("Ground", "rotation",
                                                                          ground.rotation)
        w_g = np.zeros(3)

    n = len(bodies)
    bv = [b.validated(k) for k, b in enumerate(bodies)]
    hv = [h.validated(k) for k, h in enumerate(hinges)]
    kinds = np.array([h.kind for h in hinges], dtype=np.int64)

    body_kind = np.array([BEAM if isinstance(b, EulerBernoulliBeam) else RIGID for b in bodies],
                         dtype=np.int64)
    beam_params = np.array([v.get("beam", np.zeros(BEAM_PARAM_SIZE)) for v in bv])
    _resolve_mode_families(bodies, bv, kinds, body_kind, beam_params, tip)
    _check_ball_lookahead(bodies, bv, kinds, body_kind)

    rotations = np.zeros((n, 3, 3))
    omegas = np.zeros((n, 3))
    locked = np.zeros(n, dtype=bool)
    for k in range(n):
        if k == 0:
            a_in, w_in = rot_g, w_g
        else:   # the inboard's output section (a beam's end section, docs/beam.md)
            a_in, w_in = output_section(beam_params[k - 1], rotations[k - 1], omegas[k - 1],
                                        bv[k - 1].get("eta0"), bv[k - 1].get("eta_d0"))
        locked[k] = kinds[k] == FIXED and (k == 0 or (locked[k - 1]
                                                      and body_kind[k - 1] == RIGID))
        if kinds[k] == FIXED:
            rot, om = a_in @ hv[k]["rotation"], w_in
            for key, implied in (("rotation", rot), ("omega", om)):
                given = bv[k][key]
                if given is not None and not np.allclose(given, implied, atol=1e-9):
                    arg = "rotation" if key == "rotation" else "angular_velocity"
                    raise ValueError(f"{bodies[k].label(k)}: {arg} contradicts the fixed hinge "
                                     f"before it (the body moves with its inboard neighbour); "
                                     f"leave it None")
        else:
            default = a_in @ hv[k]["rotation"] if kinds[k] != BALL else np.eye(3)
            rot = default if bv[k]["rotation"] is None else bv[k]["rotation"]
            om = np.zeros(3) if bv[k]["omega"] is None else bv[k]["omega"]
        rotations[k], omegas[k] = rot, om
    beams = [k for k in range(n) if body_kind[k] == BEAM]

    return Model(
        n_bodies=n,
        body_params=np.array([pack_body(v) for v in bv]),
        hinge_kind=kinds,
        hinge_params=np.array([pack_hinge(v) for v in hv]),
        gravity=g,
        ground_position=r_g,
        ground_rotation=rot_g,
        ground_motion=ground.motion,
        initial_rotation=rotations,
        initial_angular_velocity=omegas,
        ground_locked=locked,
        forces=tuple(v["force"] for v in bv),
        torques=tuple(v["torque"] for v in bv),
        body_names=tuple(b.name or f"body{k}" for k, b in enumerate(bodies)),
        hinge_names=tuple(h.name or f"{HINGE_KIND_NAMES[h.kind]}{k}" for k, h in enumerate(hinges)),
        body_mass_center_inertia=np.array([v["j_c"] for v in bv]),
        tip_pinned=tip == "ball",
        body_kind=body_kind,
        beam_params=beam_params,
        initial_modal_coordinates=np.concatenate([np.zeros(0)] + [bv[k]["eta0"] for k in beams]),
        initial_modal_velocities=np.concatenate([np.zeros(0)] + [bv[k]["eta_d0"] for k in beams]),
    )


def output_section(beam_row, rotation, omega, eta=None, eta_dot=None):
    """Rotation and world angular velocity of a body's output section: the body's own for a
    rigid body; for a beam A_O = A exp(theta_O^), theta_O = [0, -w'(L), v'(L)], and
    w_O = w + A J_l(theta_O) theta_O' (docs/beam.md, "End sections")."""
    m = int(beam_row[MODES])
    if m == 0 or eta is None:
        return rotation, omega
    eta_dot = np.zeros(2 * m) if eta_dot is None else eta_dot
    _, dy, _, _, _ = mode_shapes(int(beam_row[FAMILY]), beam_row[LENGTH], m, [beam_row[LENGTH]])
    slope = dy[:, 0]
    theta = np.array([0.0, -slope @ eta[m:], slope @ eta[:m]])
    theta_dot = np.array([0.0, -slope @ eta_dot[m:], slope @ eta_dot[:m]])
    e, jl = np.empty((3, 3)), np.empty((3, 3))
    expm_so3(theta, e)
    left_jacobian(theta, jl)
    return rotation @ e, omega + rotation @ jl @ theta_dot


def _resolve_mode_families(bodies, bv, kinds, body_kind, beam_params, tip):
    """Write each beam's mode family into beam_params (docs/beam.md, "Mode shapes").  "auto":
    pinned between moment-free ends (ball joints, the free or pinned tip); otherwise clamped in
    the input section's frame, with the clamped-free eigenfunctions when the output is the free
    tip and the loaded-end polynomial modes when it carries loads.  An explicit choice that
    contradicts the hinges is refused (clamped between moment-free ends only if the user
    insists).  An elastic hinge at the input clamps the beam elastically (the frame is the input
    section's, as after a fixed hinge); one at the output loads it (loaded-end modes)."""
    n = len(bodies)
    for k in range(n):
        if body_kind[k] != BEAM:
            continue
        who = bodies[k].label(k)
        input_free = kinds[k] == BALL
        free_tip = k == n - 1 and tip == "free"
        output_free = k == n - 1 or kinds[k + 1] == BALL      # the tip (free or pinned) too
        family = int(beam_params[k, FAMILY])
        if family == PINNED and not (input_free and output_free):
            raise ValueError(f"{who}: mode_family 'pinned' needs moment-free ends (a ball joint "
                             f"or the tip at both ends); a fixed or elastic hinge holds this "
                             f"beam: use 'clamped' (or 'auto')")
        if family == CLAMPED and input_free and output_free and not bv[k]["force_mode_family"]:
            raise ValueError(f"{who}: mode_family 'clamped' contradicts the moment-free ends of "
                             f"the beam (pass force_mode_family=True to insist)")
        if family == AUTO and input_free and output_free:
            family = PINNED
        elif family != PINNED:
            family = CLAMPED if free_tip else CLAMPED_LOADED
        if family == CLAMPED_LOADED and beam_params[k, MODES] > MAX_LOADED_MODES:
            raise ValueError(f"{who}: modes_per_plane must be <= {MAX_LOADED_MODES} for a "
                             f"clamped beam whose output carries loads (polynomial modes), got "
                             f"{int(beam_params[k, MODES])}")
        beam_params[k, FAMILY] = family


def _check_ball_lookahead(bodies, bv, kinds, body_kind):
    """A body between two moment-free cuts (ball joints or the free tip) finds its rotation from
    its own moment equation, whose matrix is -chi1 (J_I + M l_IO^ l_IC^) (docs/rigid_body.md).
    If that matrix is singular (no inertia about the hinge-to-hinge axis) the step is undefined."""
    n = len(bodies)
    for k in range(n):
        outboard_free = k == n - 1 or kinds[k + 1] == BALL
        if kinds[k] != BALL or not outboard_free or body_kind[k] != RIGID:
            continue
        v = bv[k]
        l_io, l_ic = v["l_io"], v["l_ic"]
        if k == n - 1:
            mat = v["j_i"]       # free tip: no force at the output point
        else:
            mat = v["j_i"] + v["mass"] * _hat(l_io) @ _hat(l_ic)
        s = np.linalg.svd(mat, compute_uv=False)
        if s[-1] <= 1e-10 * max(s[0], 1e-300):
            raise ValueError(f"{bodies[k].label(k)}: inertia: the ball-joint look-ahead is singular "
                             f"(singular values of J_I + M l_IO^ l_IC^: {s}); the body has no "
                             f"inertia about its hinge-to-hinge axis")


def _hat(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
