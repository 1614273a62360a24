"""A system's elements validated once and frozen into a Model's flat arrays (_freeze and its
checks; System.build and build_chain call it)."""
from dataclasses import fields, replace

import numpy as np

from . import loop_kinematics
from .closures import closure_rows, loop_membership
from ..elements import BALL, BEAM, FIXED, FREE, RIGID, ROD, BallJoint
from ..elements.hinges import DEFLECTION_0, DEFLECTION_RATE_0
from ..elements._checks import finite_scalar, finite_vector, rotation_matrix
from ..elements.beam import (
     ACCURATE,
     AUTO,
     AXIAL_MODES,
     BEAM_PARAM_SIZE,
     CLAMPED,
     CLAMPED_LOADED,
     EXACT,
     FAMILY,
     FREQUENCY_CUTOFF,
     FROM_STEP,
     LENGTH,
     MASS_PER_LENGTH,
     MAX_LOADED_MODES,
     MODES,
     PINNED,
     STIFFENING,
     TORSION_MODES,
     accurate_mode_count,
     auto_mode_count,
     auto_part_count,
     axial_frequencies,
     modal_size,
     torsion_frequencies,
 )
from ..elements.contact import CONTACT_SIZE, Plane, contact_rows
from ..elements.drives import MOTION
from ..elements.kinds import (
     BODY_KIND,
     CHILD,
     FLEXIBLE,
     HINGE_KIND_NAMES,
     JOINT_KIND,
     PARENT,
     TURN,
     WITH_COORDINATES,
     body_kind_of,
     coordinates_of,
     joint_kind_of,
     joint_motion,
     pack_hinge,
     turn_rotations,
     unimplemented_body_kind,
 )
from ..elements.rigid_body import pack_body
from ..elements.strain_rod import ROD_LENGTH, ROD_MODES, ROD_MU, ROD_STATIONS, rod_coordinate_count
from .model import (
    _NO_BEAM,
    _NO_ROD,
    SHARED_TABLES,
    Ground,
    Model,
    _shown_for_all,
    adopt_arrays,
    children_of,
    outboard_masses,
    shared_rows,
)
from .rod_motion import rod_end_section
from .sections import output_section


def _who(body, index=None):
    where = f" (entry {index})" if index is not None else ""
    name = getattr(body, "name", "")
    return f"{type(body).__name__} '{name}'{where}" if name else f"{type(body).__name__}{where}"


MAX_GRAVITY = 1e6      # m/s^2 (1e5 g): System's gravity beyond it is refused as non-physical


def _freeze(bodies, hinges, parents, attach, gravity, ground, tip, step=None, duration=None,
            closures=()):
    """Validate every element and the system, and freeze them into a Model.  bodies, hinges:
    in topological order; parents[k] < k the parent body of body k (-1: the ground); attach[k]
    its attachment point on the parent (0: the output point, j: the parent's j-th named
    point); closures: the loop-closing joints as System.close took them (tip="ball" adds one
    from the last body's output point to the ground)."""
    if tip not in ("free", "ball"):
        raise ValueError(f"System: tip must be 'free' or 'ball', got {tip!r}")
    n = len(bodies)
    for k, element in enumerate(list(bodies) + list(hinges)):
        name = getattr(element, "name", "")
        if not isinstance(name, str):
            raise ValueError(f"{type(element).__name__} ({'body' if k < n else 'hinge'} "
                             f"{k if k < n else k - n}): name must be a string, got {name!r}")
        if k < n and name == "ground":
            raise ValueError(f"{type(element).__name__} (body {k}): the name {name!r} is the "
                             f"ground's (parent='ground' means the ground): choose another")
    parent = np.array(parents, dtype=np.int64)
    ground_points = {k: a for k, a in enumerate(attach) if not np.isscalar(a)}
    attachment = np.array([0 if k in ground_points else a for k, a in enumerate(attach)],
                          dtype=np.int64)
    chain = bool(np.all(parent == np.arange(n) - 1) and np.all(attachment == 0))
    if tip == "ball" and not chain:
        raise ValueError("System: tip='ball' joins the last body of a chain to the ground; this "
                         "system is a tree: close its loops with System.close(joint, body, "
                         "'ground')")
    if tip == "ball" and ground.motion is not None:
        raise ValueError("System: tip='ball' pins the tip to a point of the ground, and loops on "
                         "a moving ground do not run in DT-TMM yet")
    g = finite_vector("System", "gravity", gravity)
    if np.abs(g).max() > MAX_GRAVITY:
        raise ValueError(f"System: gravity {g} m/s^2 is beyond any physical system's (at most "
                         f"{MAX_GRAVITY:g} m/s^2, 1e5 g, here): a slip of units? Give it in m/s^2")
    if not isinstance(ground, Ground):
        raise ValueError("System: ground must be a Ground")
    if ground.motion is not None:
        if ground.rotation is not None or np.any(finite_vector("Ground", "position",
                                                               ground.position) != 0.0):
            raise ValueError("Ground: with a motion, the ground's position and rotation are the "
                             "motion's: give them to the PrescribedMotion, not to Ground")
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

    bv = _validated(bodies)
    hv = _validated(hinges)
    kinds = np.array([joint_kind_of(h).code for h in hinges], dtype=np.int64)
    body_kind = np.array([body_kind_of(b).code for b in bodies], dtype=np.int64)
    children = children_of(parent)
    beam_params = _packed(bv, lambda v: v.get("beam", _NO_BEAM))
    if (body_kind == BEAM).any():           # (written per beam below: its own rows)
        beam_params = np.array(beam_params, order="C")
    rod_params = _packed(bv, lambda v: v.get("rod", _NO_ROD))
    attachment_point = np.zeros((n, 3))
    for k in range(n):
        p = parent[k]
        if p < 0:               # a root's place on the ground (ground frame, from its point)
            attachment_point[k] = ground_points.get(k, 0.0)
            continue
        if body_kind[p] in FLEXIBLE and attachment[k] != 0:
            raise ValueError(f"{bodies[k].label(k)}: {BODY_KIND[body_kind[p]].what} has one "
                             f"attachment point, its output end")
        attachment_point[k] = (bv[p]["l_io"] if attachment[k] == 0
                               else list(bv[p]["points"].values())[attachment[k] - 1])
    derived = None
    from_step = (body_kind == BEAM) & (beam_params[:, FREQUENCY_CUTOFF] == FROM_STEP)
    if np.any(from_step):
        derived = _derived_cutoff(step, duration, ground, hv, bodies, beam_params)
    closures = list(closures)
    if tip == "ball":
        closures.append((BallJoint(name="tip"), bodies[-1], "ground", None, None))
    loops = loop_membership(closures, bodies, parent)
    beam_ends, loop_stiffened = _resolve_mode_families(
        bodies, bv, hv, kinds, body_kind, beam_params, parent, children, loops,
        None if derived is None else derived[0])
    if (body_kind == ROD).any():
        rod_params = _count_rod_strains(bodies, bv, hv, kinds, body_kind, rod_params, parent,
                                        loops)
    _check_ball_lookahead(bodies, bv, kinds, body_kind, children, attachment)

    rotations = np.zeros((n, 3, 3))
    omegas = np.zeros((n, 3))
    locked = np.zeros(n, dtype=bool)
    for k in range(n):
        p = parent[k]
        if p < 0:
            a_in, w_in = rot_g, w_g
        elif attachment[k] == 0 and body_kind[p] == ROD:      # its end section
            _, a_in, w_in = rod_end_section(rod_params[p], rotations[p], omegas[p],
                                            bv[p]["eta0"], bv[p]["eta_d0"])
        elif attachment[k] == 0 and body_kind[p] == BEAM:     # its end section
            a_in, w_in = output_section(beam_params[p], rotations[p], omegas[p],
                                        bv[p].get("eta0"), bv[p].get("eta_d0"))
        elif body_kind[p] == RIGID:     # its own frame, at its output point or a named one
            a_in, w_in = rotations[p], omegas[p]
        else:
            raise unimplemented_body_kind(body_kind[p], bodies[p].label(p),
                                          "the build's inboard frames (model/freeze.py)")
        locked[k] = kinds[k] == FIXED and (p < 0 or (locked[p] and body_kind[p] == RIGID))
        if kinds[k] in WITH_COORDINATES:
            hv[k] = dict(hv[k])     # (its own: _validated's dicts are shared)
            rot, om, hv[k]["rotation"] = _joint_start(kinds[k], hv[k], a_in, w_in,
                                                      bv[k]["rotation"], bv[k]["omega"],
                                                      hinges[k].__class__.__name__,
                                                      bodies[k].label(k))
        elif kinds[k] == FIXED:
            rot, om = a_in @ hv[k]["rotation"], w_in
            for key, implied in (("rotation", rot), ("omega", om)):
                given = bv[k][key]
                if given is not None and not np.allclose(given, implied, atol=1e-9):
                    arg = "rotation" if key == "rotation" else "angular_velocity"
                    raise ValueError(f"{bodies[k].label(k)}: {arg} contradicts the fixed hinge "
                                     f"before it (the body moves with its inboard neighbour); "
                                     f"leave it None")
        else:
            default = a_in @ hv[k]["rotation"] if kinds[k] not in (BALL, FREE) else np.eye(3)
            rot = default if bv[k]["rotation"] is None else bv[k]["rotation"]
            om = np.zeros(3) if bv[k]["omega"] is None else bv[k]["omega"]
        rotations[k], omegas[k] = rot, om
    flexible = [k for k in range(n) if body_kind[k] in FLEXIBLE]

    tree = Model(
        n_bodies=n,
        body_params=_packed(bv, pack_body),
        hinge_kind=kinds,
        hinge_params=_packed(hv, pack_hinge),
        gravity=g,
        ground_position=r_g,
        ground_rotation=rot_g,
        ground_motion=ground.motion,
        initial_rotation=rotations,
        initial_angular_velocity=omegas,
        ground_locked=locked,
        forces=tuple(v["force"] for v in bv),
        torques=tuple(v["torque"] for v in bv),
        line_loads=tuple(v.get("line_load") for v in bv),
        body_names=tuple(_own_copy(b.name or f"body{k}") for k, b in enumerate(bodies)),
        hinge_names=tuple(_own_copy(h.name or f"{HINGE_KIND_NAMES[h.kind]}{k}")
                          for k, h in enumerate(hinges)),
        body_mass_center_inertia=_packed(bv, lambda v: v["j_c"]),
        body_kind=body_kind,
        beam_params=beam_params,
        rod_params=rod_params,
        initial_modal_coordinates=np.concatenate([np.zeros(0)]
                                                 + [bv[k]["eta0"] for k in flexible]),
        initial_modal_velocities=np.concatenate([np.zeros(0)]
                                                + [bv[k]["eta_d0"] for k in flexible]),
        parent=parent,
        attachment=attachment,
        attachment_point=attachment_point,
        drives=tuple(v.get("drives", ()) for v in hv),
        frequency_cutoff_reasons=tuple(derived[1] if f else "" for f in from_step),
        beam_ends=tuple(beam_ends),
    )
    tree = _free_joints_in_world(tree)
    contacts = _contact_rows(bodies, bv, body_kind, parent, ground, rot_g, r_g)
    if len(contacts):
        tree = replace(tree, contacts=contacts)
    tree = replace(tree, **{name: shared_rows(getattr(tree, name)) for name in SHARED_TABLES})
    adopt_arrays(tree)
    if not closures:
        return tree
    index_of = {id(b): k for k, b in enumerate(bodies)}
    named = [dict(v.get("points") or {}) for v in bv]
    return _unstiffen_held_chords(adopt_arrays(
        replace(tree, **closure_rows(tree, closures, index_of, named)), tree), loop_stiffened)


def _contact_rows(bodies, bv, body_kind, parent, ground, rot_g, r_g):
    """The bodies' contact spheres (elements/contact.py::contact_rows), body by body, against
    the ground's plane if it has one and each other; ValueError for shapes on a body that is
    not rigid, or a plane on a moving ground."""
    shaped = [k for k, b in enumerate(bodies) if getattr(b, "shapes", ())]
    plane = ground.plane
    if plane is not None and not isinstance(plane, Plane):
        raise ValueError(f"Ground: plane must be a Plane, got {plane!r}")
    if plane is not None and ground.motion is not None:
        raise ValueError("Ground: a plane on a moving ground does not touch bodies yet; give "
                         "the plane to a fixed Ground")
    if not shaped:
        return np.zeros((0, CONTACT_SIZE))
    for k in shaped:
        if body_kind[k] != RIGID:
            raise ValueError(f"{bodies[k].label(k)}: shapes are rigid bodies' (a beam's or "
                             f"rod's centre line does not touch yet): carry the shape on a "
                             f"rigid body welded to it")
    if plane is None and len(shaped) < 2:
        k = shaped[0]
        raise ValueError(f"{bodies[k].label(k)}: has shapes, but nothing to touch: give the "
                         f"System a Ground(plane=dttmm.Plane(...)), or other bodies shapes")
    plane_values = None if plane is None else plane.validated(rot_g, r_g)
    rows = [row for k in shaped
            for row in contact_rows(bodies[k].label(k), k, int(parent[k]), bv[k]["mass"],
                                    bodies[k].shapes, bodies[k].contact, plane_values)]
    return np.array(rows)


def _free_joints_in_world(model):
    """model with each free joint's start in the world, as its deflection d and rate (the
    elastic hinge's slots, DEFLECTION_0 and DEFLECTION_RATE_0): d = F p (p the position given
    in the parent's frame F; the world's for the ground), d' = v - v_att (v the velocity given,
    absolute; v_att the attachment point's), parents first (a free joint's attachment moves
    with any free joint before it)."""
    for k in np.nonzero(model.hinge_kind == FREE)[0]:
        _, v_att, frame, _ = loop_kinematics.start_attachment(model, k)
        if model.parent[k] < 0:
            frame = np.eye(3)
        params = np.array(model.hinge_params)
        params[k, DEFLECTION_0] = frame @ model.hinge_params[k, DEFLECTION_0]
        params[k, DEFLECTION_RATE_0] = model.hinge_params[k, DEFLECTION_RATE_0] - v_att
        model = replace(model, hinge_params=params)
    return model


def _unstiffen_held_chords(model, candidates):
    """Resolve stiffening=None of the inextensible beams in closed loops (the candidates,
    stiffened so far): off where the loops hold the beam's chord length
    (loop_kinematics.held_chords: held between points that cannot approach, it could not bow), on
    elsewhere (a four-bar's coupler: its ends move)."""
    held = loop_kinematics.held_chords(model, candidates)
    if not held:
        return model
    params = np.array(model.beam_params, order="C")
    params[held, STIFFENING] = 0.0
    return adopt_arrays(replace(model, beam_params=params), model)


def _joint_start(kind, v, a_in, w_in, given_rot, given_omega, joint_name, who):
    """A child's rotation and angular velocity at t = 0 behind a joint with coordinates, and the
    joint's R0 (elements/joints.py): A = A_P R_P R0 R_C, R_P and R_C the joint's turns fixed in
    the parent and in the child (A_P Rot(n, q) R0 for a revolute joint, A_P Rot(n1, q1) R0
    Rot(n2, q2) for a universal one, A_P R0 for a prismatic one); w = w_P + the turns' rates
    about their axes (elements/kinds.py::joint_motion).  A kind with a turn in each frame needs
    their axes perpendicular at q = 0 (its closing row keeps them so)."""
    axes, q0, qd0 = v["axes"], v["q0"], v["qd0"]
    r_p, r_c = turn_rotations(kind, axes, q0)
    r0 = np.eye(3) if given_rot is None else r_p.T @ a_in.T @ given_rot @ r_c.T
    turns = {c.frame: c.axis for c in coordinates_of(kind) if c.motion == TURN}
    if len(turns) == 2:
        names = JOINT_KIND[int(kind)].axes
        first, second = names[turns[PARENT]], names[turns[CHILD]]
        dot = float(axes[turns[PARENT]] @ (r0 @ axes[turns[CHILD]]))
        if abs(dot) > 1e-9:
            raise ValueError(f"{joint_name} before {who}: {first} and {second} must be "
                             f"perpendicular ({first} . {second} in the parent's frame at q = 0: "
                             f"{dot:.3g})")
    rot, omega, _, _, _ = joint_motion(kind, axes, r0, a_in, w_in, q0, qd0)
    if given_omega is not None and not np.allclose(given_omega, omega, atol=1e-9):
        raise ValueError(f"{who}: angular_velocity {given_omega} contradicts the {joint_name} "
                         f"before it (the body turns with its parent and the joint's rates: "
                         f"{omega}); leave it None and give the joint's rates")
    return rot, omega, r0


def _derived_cutoff(step, duration, ground, hv, bodies, beam_params):
    """(cutoff, why) for the beams with modes_per_plane="auto" and no frequency_cutoff
    (build_chain's step and duration): 1 / (20 step) Hz, lowered to ten times the drives'
    bandwidth over [0, duration] where the model has prescribed motions that vary."""
    if step is None:
        k = int(np.nonzero(beam_params[:, FREQUENCY_CUTOFF] == FROM_STEP)[0][0])
        raise ValueError(f"{bodies[k].label(k)}: modes_per_plane='auto' without a "
                         f"frequency_cutoff takes its cutoff from the step the model will run "
                         f"at: build it with step=dt (and duration=t_end, to bound it by the "
                         f"drives' bandwidth), or give frequency_cutoff (Hz)")
    step = finite_scalar("System", "step", step, positive=True)
    f_step = 1.0 / (20.0 * step)
    why = f"from the step {step:g} s: 1 / (20 step) = {f_step:.4g} Hz"
    if duration is None:
        return f_step, why
    duration = finite_scalar("System", "duration", duration, positive=True)
    bandwidth = drives_bandwidth(step, duration, ground.motion,
                                 [d for v in hv for d in v.get("drives", ())
                                  if d is not None and d["kind"] == MOTION])
    if bandwidth is None:
        return f_step, why + " (no prescribed motion varies to bound it)"
    if 10.0 * bandwidth < f_step:
        return 10.0 * bandwidth, (f"ten times the drives' bandwidth, {bandwidth:.4g} Hz (99% of "
                                  f"their acceleration's energy below it over {duration:g} s; "
                                  f"the step {step:g} s would resolve {f_step:.4g} Hz)")
    return f_step, why + f" (below ten times the drives' bandwidth, {bandwidth:.4g} Hz)"


def drives_bandwidth(step, duration, ground_motion, motions, max_samples=1 << 15):
    """The drives' bandwidth, Hz: the largest, over the ground's acceleration and angular
    acceleration components and each JointMotion's acceleration sampled every step over
    [0, duration] (at most max_samples points), of the frequency below which 99% of the
    signal's energy (its spectrum's, mean removed) lies; None when no prescribed motion varies
    (no motion, or constant accelerations)."""
    n = int(min(max_samples, np.floor(duration / step) + 1))
    t = np.linspace(0.0, duration, n)
    signals = []
    if ground_motion is not None:
        states = [ground_motion(ti) for ti in t]
        signals += list(np.array([s[2] for s in states]).T)
        signals += list(np.array([s[5] for s in states]).T)
    for drive in motions:
        acceleration = drive["function"][2]
        signals.append(np.array([float(acceleration(ti)) for ti in t]))
    best = None
    for s in signals:
        s = np.asarray(s, dtype=float) - np.mean(s)
        if not np.any(np.abs(s) > 1e-12 * (1.0 + np.max(np.abs(s)))):
            continue
        power = np.abs(np.fft.rfft(s)) ** 2
        share = np.cumsum(power) / np.sum(power)
        f99 = np.fft.rfftfreq(n, t[1] - t[0])[int(np.searchsorted(share, 0.99))]
        best = f99 if best is None else max(best, f99)
    return best


def _resolve_mode_families(bodies, bv, hv, kinds, body_kind, beam_params, parent, children,
                           loops, derived_cutoff=None):
    """Write each beam's mode family into beam_params (docs/beam.md, "Mode shapes").  "auto":
    pinned between moment-free ends (ball joints, the free or pinned tip); otherwise clamped in
    the input section's frame, with the clamped-free eigenfunctions when the output is the free
    tip and the loaded-end polynomial modes when it carries loads.  An explicit choice that
    contradicts the hinges is refused (clamped between moment-free ends only if the user
    insists).  An elastic hinge at the input clamps the beam elastically (the frame is the input
    section's, as after a fixed hinge); one at the output loads it (loaded-end modes).
    loops = (in_loop, closed_output, output_moment, output_pinned) per body
    (closures.loop_membership): a closing joint at a beam's output end holds it like a child's
    joint (a ball joint: moment-free).  The mode count of modes_per_plane=None is estimated for
    the beam's own ends (root_pinned, output_pinned; elements/beam.py::truncation_errors);
    returns them per body ((root pinned, tip pinned) for a beam, None for another body), and
    the beams whose stiffening=None waits for the loops (in a loop without stretch modes)."""
    n = len(bodies)
    in_loop, closed_output, output_moment, output_pinned = loops
    end_mass = outboard_masses([v["mass"] for v in bv], parent)
    ends, candidates = [None] * n, []
    for k in range(n):
        if body_kind[k] != BEAM:
            continue
        who = bodies[k].label(k)
        input_free = kinds[k] == BALL
        leaf = not children[k]
        # an applied end load (docs/beam.md, "Loads on the beam") loads the output: the free
        # tip's eigenfunctions carry none, and a torque needs the sections' rotations
        loaded = bv[k]["force"] is not None or bv[k]["torque"] is not None
        free_tip = leaf and not closed_output[k] and not loaded
        # a leaf's output is the tip (free or pinned); otherwise every joint there moment-free
        output_free = ((leaf or all(kinds[c] == BALL for c in children[k]))
                       and bv[k]["torque"] is None and not output_moment[k])
        family = int(beam_params[k, FAMILY])
        if family == PINNED and not (input_free and output_free):
            raise ValueError(f"{who}: mode_family 'pinned' needs moment-free ends (a ball joint "
                             f"or the tip at both ends, no end_torque); a fixed or elastic "
                             f"hinge, or an end torque, holds this beam: use 'clamped' (or "
                             f"'auto')")
        if family == CLAMPED and input_free and output_free and not bv[k]["force_mode_family"]:
            raise ValueError(f"{who}: mode_family 'clamped' contradicts the moment-free ends of "
                             f"the beam (pass force_mode_family=True to insist)")
        if family == AUTO and input_free and output_free:
            family = PINNED
        elif family != PINNED:
            family = CLAMPED if free_tip else CLAMPED_LOADED
        beam_params[k, FAMILY] = family
        ends[k] = (family != PINNED and root_pinned(bodies[k], kinds[k], hv[k]),
                   family != PINNED and bool(output_pinned[k]))
        if beam_params[k, FREQUENCY_CUTOFF] == FROM_STEP:   # derived (build_chain's step)
            beam_params[k, FREQUENCY_CUTOFF] = derived_cutoff
        if beam_params[k, FREQUENCY_CUTOFF] == ACCURATE:    # modes_per_plane=None
            beam_params[k, MODES] = accurate_mode_count(beam_params[k], end_mass[k], ends[k])
            bv[k] = dict(bv[k], eta0=np.zeros(modal_size(beam_params[k])),    # (its own dict:
                         eta_d0=np.zeros(modal_size(beam_params[k])))       # copy on write)
        if beam_params[k, FREQUENCY_CUTOFF] > 0.0:          # modes_per_plane="auto"
            beam_params[k, MODES] = max(auto_mode_count(beam_params[k]),
                                        accurate_mode_count(beam_params[k], end_mass[k],
                                                            ends[k]))
            for part, frequencies in ((TORSION_MODES, torsion_frequencies),
                                      (AXIAL_MODES, axial_frequencies)):
                if beam_params[k, part] == AUTO:           # "auto" twist or stretch
                    beam_params[k, part] = auto_part_count(beam_params[k], frequencies)
            bv[k] = dict(bv[k], eta0=np.zeros(modal_size(beam_params[k])),
                         eta_d0=np.zeros(modal_size(beam_params[k])))
        if beam_params[k, STIFFENING] == AUTO:
            # stiffening=None: on; to all orders where the build counted 3 or more modes for a
            # pinned end (the second-order energy then holds only to a bend of 0.08 rad or
            # less, which a swinging or coupled link passes: docs/beam.md, "Where the
            # second-order energy stops"); an inextensible beam (no stretch modes) in a closed
            # loop is a candidate, which the build turns off where the loops hold its chord (it
            # could not bow: _unstiffen_held_chords)
            counted = (beam_params[k, FREQUENCY_CUTOFF] == ACCURATE
                       or beam_params[k, FREQUENCY_CUTOFF] > 0.0)
            beam_params[k, STIFFENING] = (EXACT if counted and any(ends[k])
                                          and beam_params[k, MODES] >= 3 else 1.0)
            if in_loop[k] and beam_params[k, AXIAL_MODES] == 0:
                candidates.append(k)
        if family == CLAMPED_LOADED and beam_params[k, MODES] > MAX_LOADED_MODES:
            raise ValueError(f"{who}: modes_per_plane must be <= {MAX_LOADED_MODES} for a "
                             f"clamped beam whose output carries loads (polynomial modes), got "
                             f"{int(beam_params[k, MODES])}")
        beam_params[k, FAMILY] = family
    return ends, candidates


def _count_rod_strains(bodies, bv, hv, kinds, body_kind, rod_params, parent, loops):
    """strain_modes=None of a strain rod with a pinned end (its root behind a ball joint or a
    free revolute or universal joint, its output held by a closing ball, revolute or universal
    joint): the count of a loaded-end modal beam with those ends and what hangs on it
    (elements/beam.py::accurate_mode_count; the rod's deflection polynomials are those modes'),
    its stations count + 3 unless given, its strain coordinates zero.  Other rods keep 2."""
    output_pinned = loops[3]
    end_mass = outboard_masses([v["mass"] for v in bv], parent)
    rods = np.array(rod_params, order="C")
    for k in np.nonzero(body_kind == ROD)[0]:
        if not bv[k].get("counted"):
            continue
        ends = (root_pinned(bodies[k], kinds[k], hv[k]),
                bool(output_pinned[k]))
        if not any(ends):
            continue
        row = np.zeros(BEAM_PARAM_SIZE)
        row[LENGTH], row[MASS_PER_LENGTH] = rods[k, ROD_LENGTH], rods[k, ROD_MU]
        row[FAMILY] = CLAMPED_LOADED
        count = accurate_mode_count(row, end_mass[k], ends)
        rods[k, ROD_MODES] = count
        if not bv[k].get("stations_given"):
            rods[k, ROD_STATIONS] = count + 3
        nq = rod_coordinate_count(rods[k])
        bv[k] = dict(bv[k], eta0=np.zeros(nq), eta_d0=np.zeros(nq))
    return rods


def root_pinned(body, kind, joint):
    """Whether a body's root joint lets it turn freely in some bending plane of its own: a
    joint with a turn that no JointMotion prescribes (elements/kinds.py's declaration), about an
    axis not along the body's x (R0 is the identity unless the body was given a rotation; then
    the axis in its frame is not known before the build's kinematics, and a free turn counts
    as pinned).  A ball joint: always."""
    if kind == BALL:
        return True
    for c, drive in zip(coordinates_of(kind), joint.get("drives", ())):
        if c.motion != TURN or (drive is not None and drive["kind"] == MOTION):
            continue
        if getattr(body, "rotation", None) is not None or abs(joint["axes"][c.axis][0]) < \
                1.0 - 1e-9:
            return True
    return False


def _validated(elements):
    """Each element's checked parameters (its validated(k)), each distinct set of parameters
    checked once: a chain of 10^6 copies of one link checks one link, not 10^6 (a check is
    ~0.3 ms of small numpy calls; the key ~5 us).  Elements with equal parameters (their
    names aside, which only the messages read) share the one dict (the build replaces an
    element's dict where it changes one: copy on write; a million shallow copies held 0.7 GB
    during a build); the first of them is the one a message names."""
    checked, out = {}, []
    for k, element in enumerate(elements):
        key = _parameters_key(element)
        if key is None:
            out.append(element.validated(k))
            continue
        try:
            done = checked.get(key)
        except TypeError:               # nested sequences: the deep key
            key = _parameters_key(element, deep=True)
            done = checked.get(key)
        if done is None:
            done = checked[key] = element.validated(k)
        out.append(done)
    return out


def _own_copy(name):
    """A new string equal to name, the model's own.  The caller's names were made between its
    elements, and each one kept would pin the allocator's pages that held the elements after
    they are gone: a million links named in a loop left 340 B a body resident (issue 65, item
    11); the copies are made together."""
    return name.encode().decode()


def _packed(checked, pack):
    """(n, ...) rows pack(v) of the elements' checked parameters, each packed once per set of
    the same values (_validated's shared dicts, unless the build replaced one); one row shown
    n times where they are all the same (shared_rows, without making the n rows)."""
    rows, done = [], {}
    for v in checked:
        key = id(v)
        row = done.get(key)
        if row is None:
            row = done[key] = np.asarray(pack(v), dtype=float)
        rows.append(row)
    if len(rows) > 1 and len(done) == 1:
        return _shown_for_all(rows[0], len(rows))
    return np.array(rows)


_KEY_FIELDS = {}     # an element class's parameter fields (_parameters_key)


_SCALARS = (float, int, str, bool, type(None))


def _frozen(value):
    """A hashable stand-in of a parameter's value, to any depth (functions and other objects:
    their identity)."""
    if type(value) in _SCALARS:
        return value
    if isinstance(value, (list, tuple)):
        return ("seq",) + tuple(map(_frozen, value))
    if isinstance(value, np.ndarray):
        return ("array", value.shape, value.dtype.str, value.tobytes())
    if isinstance(value, dict):
        return ("dict",) + tuple((_frozen(k), _frozen(v)) for k, v in value.items())
    if isinstance(value, np.generic):
        return value.item()
    return ("id", id(value))


def _parameters_key(element, deep=False):
    """A key of an element's parameters (its dataclass fields but its name), or None where
    one cannot be made (not a dataclass).  Shallow (the common case, fast): a sequence is
    the tuple of its items, which is not hashable where they are lists; deep: _frozen."""
    cls = type(element)
    names = _KEY_FIELDS.get(cls)
    if names is None:
        try:
            names = tuple(f.name for f in fields(element)
                          if f.name != "name" and not f.name.startswith("_"))
        except TypeError:
            return None
        _KEY_FIELDS[cls] = names
    if deep:
        return (cls,) + tuple(_frozen(getattr(element, name)) for name in names)
    key = [cls]
    for name in names:
        value = getattr(element, name)
        kind = type(value)
        if kind is list or kind is tuple:
            value = ("seq", tuple(value))
        elif kind is np.ndarray:
            value = ("array", value.shape, value.dtype.str, value.tobytes())
        elif kind not in _SCALARS:
            value = ("id", id(value))
        key.append(value)
    return tuple(key)


def _check_ball_lookahead(bodies, bv, kinds, body_kind, children, attachment):
    """A body between two moment-free cuts (ball joints or the free tip) finds its rotation from
    its own moment equation, whose matrix is -chi1 (J_I + M l_IO^ l_IC^) (docs/rigid_body.md).
    If that matrix is singular (no inertia about the hinge-to-hinge axis) the step is undefined.
    (Checked for a leaf and for a body with one child at its output.)"""
    checked, leaves = [], []
    for k in range(len(bodies)):
        leaf = not children[k]
        single = len(children[k]) == 1 and attachment[children[k][0]] == 0
        outboard_free = leaf or (single and kinds[children[k][0]] == BALL)
        if kinds[k] == BALL and outboard_free and body_kind[k] == RIGID:
            checked.append(k)
            leaves.append(leaf)
    if not checked:
        return
    # all at once (a million bodies): J_I, or J_I + M l_IO^ l_IC^ below a ball joint (a free
    # tip takes no force at its output point)
    j_i = np.array([bv[k]["j_i"] for k in checked])
    mass = np.array([bv[k]["mass"] for k in checked])
    l_io = np.array([bv[k]["l_io"] for k in checked])
    l_ic = np.array([bv[k]["l_ic"] for k in checked])
    arm = np.where(np.array(leaves)[:, None, None], 0.0,
                   mass[:, None, None] * _hat(l_io) @ _hat(l_ic))
    s = np.linalg.svd(j_i + arm, compute_uv=False)
    bad = s[:, -1] <= 1e-10 * np.maximum(s[:, 0], 1e-300)
    if bad.any():
        i = int(np.argmax(bad))
        k = checked[i]
        raise ValueError(f"{bodies[k].label(k)}: inertia: the ball-joint look-ahead is "
                         f"singular (singular values of J_I + M l_IO^ l_IC^: {s[i]}); the body "
                         f"has no inertia about its hinge-to-hinge axis")


def _hat(v):
    """v^ of (m, 3) vectors: (m, 3, 3)."""
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2], out[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    out[..., 1, 0], out[..., 2, 0], out[..., 2, 1] = v[..., 2], -v[..., 1], v[..., 0]
    return out
