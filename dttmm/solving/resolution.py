"""What a run could not resolve, said after it (docs/solver.md, "Steps that cannot resolve the
motion"; issue 65, item 5): a fixed step's unresolved mode, and (any run) a bent element.

- A kept bending mode that the step does not resolve, omega_k dt > MAX_TURN_PER_STEP (0.35 rad
  of its phase a step, about 18 steps a period: the trapezoidal rule's phase error, about
  (omega dt)^2 / 12 per radian, passes 1% there, as for a body's turn), and whose vibration
  holds more than MODE_SHARE of the run's energy: its largest kinetic energy 1/2 m_k eta_k'^2
  over the samples against the largest kinetic energy plus the beams' elastic energy.  Its
  kinetic energy, not its elastic: a stiff mode that slow loads bend quasi-statically (each
  element of a fine mesh) stores elastic energy without vibrating, which the trapezoidal rule
  resolves at any step.  A mode vibrating below the share moves the result by at most about
  sqrt(1e-3) ~ 3% of the elastic motion whatever its phase; the trapezoidal rule keeps such
  stiff modes bounded, which is why it is used.  The advice: 20 steps a period of that mode.
An UnresolvedMotionWarning, naming the beam, the mode and what would resolve it.

- A beam element that rings while bent far (docs/beam.md, "How far an element bends"): its
  sections do not follow the arc, and its ringing runs slow by about c b^2 (b: the ringing bend,
  its end section against its input, rad; c by what its output carries, `softening`), so the
  phase drifts by Omega c b^2 a second.  For a ringing bend beta = B sin(Omega t) the mean of
  (beta'/Omega)^2 is B^2 / 2 and Omega^2 = int beta'^2 / int beta^2, which gives the drift
  over the run without a window:  2 c sqrt(int beta'^2 dt int (beta - mean)^2 dt)  (a slow
  bend, as a spin-up's, drifts little).  The deflection is then off by about the drift, of its
  peak.  An element welded end to end with others into one longer beam drifts as its share of
  that beam's length squared, (l / L)^2: the mast of 2 elements then predicts 1.9% (measured
  2.02%), of 4 0.17% (0.27%), of one 11.6% (9.4%).  Above BEND_DRIFT it warns, naming the
  element, its largest bend and the elements that hold it (1 / n^2 for n elements).  Measured
  on elements whose input section holds the frame and whose output is free to follow the arc:
  not said of a pinned family's element nor of one with a pinned end (behind a revolute joint,
  held by a closing joint), whose ends move otherwise.
"""
import warnings

import numpy as np

from ..elements.beam import (EI_V, EI_W, FAMILY, LENGTH, MASS_PER_LENGTH, MODES, PINNED,
                             mode_shapes)
from ..elements.contact import BODY as CONTACT_BODY
from ..elements.contact import MASS as CONTACT_MASS
from ..elements.contact import ON_PLANE as CONTACT_ON_PLANE
from ..elements.contact import OWN_STIFFNESS as CONTACT_OWN_STIFFNESS
from ..elements.contact import RATE as CONTACT_RATE
from ..elements.hinges import FIXED
from ..elements.kinds import BEAM
from ..model.model import model_fact

MODE_SHARE = 1e-3         # of the run's energy: a mode holding more must be resolved
STEPS_PER_PERIOD = 20     # the advice: 20 steps a period (or a turn)
BEND_DRIFT = 0.02         # a bent element's phase drift (rad: its error, of the peak) that warns


def softening(end_mass_ratio):
    """c of a bent element's ringing, f = f_fine (1 - c b^2), by r = the mass its output carries
    over its own: measured on a mast of one element against 16 (docs/beam.md), c = 0.012,
    0.14 and 0.171 at r = 0, 1.05 and 10.5; the tip's inertia along the arc it cannot follow."""
    r = end_mass_ratio
    return 0.012 + 0.16 * r / (r + 0.2)


def _integral(f, t):
    """The trapezoidal rule's integral of the samples f(t)."""
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(t)))


def welded_lengths(model):
    """Per body: the length of the beam it is part of, m: a beam element and the beam elements
    welded to it end to end (a FixedHinge at an output point); 0 for other bodies."""
    beam = np.asarray(model.body_kind) == BEAM
    head = np.arange(model.n_bodies)        # each body's first element of its welded run
    for j in range(model.n_bodies):         # (parents first)
        p = model.parent[j]
        if (p >= 0 and beam[j] and beam[p] and model.hinge_kind[j] == FIXED
                and model.attachment[j] == 0):
            head[j] = head[p]
    lengths = np.zeros(model.n_bodies)
    np.add.at(lengths, head[beam], np.asarray(model.beam_params)[beam, LENGTH])
    return np.where(beam, lengths[head], 0.0)


def bent_element(model, result):
    """The beam element whose bent ringing drifts the most, as (name, largest bend rad,
    predicted drift, elements that hold it), where that drift passes BEND_DRIFT; else None."""
    if not model.has_beams or result.modal_coordinates is None or len(result.t) < 3:
        return None
    beams = np.nonzero(model.body_kind == BEAM)[0]
    t = np.asarray(result.t)
    offsets = model.mode_offsets
    carried = model.carried_masses()
    whole = welded_lengths(model)
    eta, eta_dot = np.asarray(result.modal_coordinates), np.asarray(result.modal_velocities)
    worst = None
    for k in beams:
        row = model.beam_params[k]
        if row[FAMILY] == PINNED or any(model.ends_of(k)):
            continue        # (measured on clamped elements only: see the module's notes)
        m, length = int(row[MODES]), row[LENGTH]
        _, dy, _, _, _ = mode_shapes(int(row[FAMILY]), length, m, [0.0, length])
        slope = dy[:, 1] - dy[:, 0]                 # the bend per coordinate
        c = softening(carried[k] / (row[MASS_PER_LENGTH] * length)) * (
            length / whole[k]) ** 2
        for first in (0, m):
            cols = slice(offsets[k] + first, offsets[k] + first + m)
            beta, rate = eta[:, cols] @ slope, eta_dot[:, cols] @ slope
            still = beta - _integral(beta, t) / (t[-1] - t[0])
            drift = 2 * c * np.sqrt(_integral(rate * rate, t) * _integral(still * still, t))
            if worst is None or drift > worst[2]:
                worst = (model.body_names[k], float(np.abs(beta).max()), drift)
    if worst is None or worst[2] <= BEND_DRIFT:
        return None
    return worst + (int(np.ceil(np.sqrt(worst[2] / BEND_DRIFT))),)     # (per element)


@model_fact
def _bending_modes(model):
    """Each beam's bending modes per plane, as (name, plane, its first modal column, the modes'
    angular frequencies rad/s, modal masses and stiffnesses, the largest of those frequencies):
    a fact of the model, kept on it
    (unresolved_mode runs after every fixed-step run: ~60 us a call for the three-pendulum's
    two beams)."""
    modes = []
    offsets = model.mode_offsets
    for k in np.nonzero(model.body_kind == BEAM)[0]:
        row = model.beam_params[k]
        m = int(row[MODES])
        _, _, _, mass, stiff = mode_shapes(int(row[FAMILY]), row[LENGTH], m, [0.0])
        modal_mass = row[MASS_PER_LENGTH] * mass
        for plane, ei, first in (("v", row[EI_V], 0), ("w", row[EI_W], m)):
            omega = np.sqrt(ei * stiff / modal_mass)
            modes.append((model.body_names[k], plane, offsets[k] + first, omega, modal_mass,
                          ei * stiff, float(omega.max()) if m else 0.0))
    return modes


def unresolved_mode(model, result, dt, max_phase):
    """The worst kept bending mode the step does not resolve and the motion excites, as
    (beam name, plane, mode number, frequency Hz, share of the energy), or None."""
    if not model.has_beams or result.modal_coordinates is None or len(result.t) < 2:
        return None
    eta_dot = np.asarray(result.modal_velocities)
    candidates = []
    for name, plane, first, omega, modal_mass, _, fastest in _bending_modes(model):
        if not fastest * dt > max_phase:        # (no mode of the plane: one comparison)
            continue
        for j in np.nonzero(omega * dt > max_phase)[0]:
            qd = eta_dot[:, first + j]
            energy = 0.5 * modal_mass[j] * qd * qd     # its vibration's (kinetic) energy
            candidates.append((name, plane, j + 1, omega[j] / (2 * np.pi), float(energy.max())))
    if not candidates:
        return None
    eta = np.asarray(result.modal_coordinates)
    elastic = np.zeros(len(result.t))           # (the bending modes' strain energy)
    for _, _, first, omega, _, stiffness, _ in _bending_modes(model):
        q = eta[:, first:first + len(omega)]
        elastic += 0.5 * (q * q) @ stiffness
    total = float(np.max(np.asarray(result.kinetic) + elastic))
    worst = max(candidates, key=lambda c: c[4])
    share = worst[4] / total if total > 0.0 else 0.0
    return worst[:4] + (share,) if share > MODE_SHARE else None


def warn_bent(model, result, warning, stacklevel=4):
    """Warn (`warning`, UnresolvedMotionWarning) of an element a finished run bent too far for
    its accuracy (any scheme: the element's, not the step's)."""
    bent = bent_element(model, result)
    if bent is not None:
        name, bend, drift, elements = bent
        warnings.warn(warning(
            f"simulate: beam '{name}' rings while bent by up to {bend:.3g} rad, where one "
            f"element's sections no longer follow the arc: its vibration runs slow, and the "
            f"phase drift it predicts over this run leaves its deflection about {drift:.1%} "
            f"of the peak off (docs/beam.md, 'How far an element bends'); build it of "
            f"{elements} or more welded elements (each bends less), whatever its modes or "
            f"stiffening"), stacklevel=stacklevel)


def warn_unresolved(model, result, dt, warning, max_phase, stacklevel=4):
    """Warn (`warning`, UnresolvedMotionWarning) of an unresolved mode of a finished fixed-step
    run."""
    mode = unresolved_mode(model, result, dt, max_phase)
    if mode is not None:
        name, plane, j, f, share = mode
        warnings.warn(warning(
            f"simulate: the step does not resolve beam '{name}''s bending mode {j} "
            f"(plane {plane}, {f:.4g} Hz), which holds {share:.1%} of the run's energy: "
            f"{f * dt:.3g} periods a step, where the trapezoidal rule's phase error may leave "
            f"the deflection far off; take dt <= {1.0 / (STEPS_PER_PERIOD * f):.2g} s "
            f"({STEPS_PER_PERIOD} steps a period), or fewer modes (modes_per_plane)"),
            stacklevel=stacklevel)


def unresolved_contact(model, result, dt, max_phase):
    """The stiffest contact sphere that touched in the run and that the step does not resolve,
    omega dt > max_phase with omega = sqrt(k / m) (k its stiffness, m its body's mass: the
    contact lasts about pi / omega, docs/contact.md), as (body name, sphere, omega), or None."""
    if not len(model.contacts) or result.contact_force is None:
        return None
    touched = np.any(result.contact_force != 0.0, axis=(0, 2))
    worst = None
    for c in np.nonzero(touched)[0]:
        row = model.contacts[c]
        k = int(row[CONTACT_BODY])
        omega = float(row[CONTACT_RATE] if row[CONTACT_ON_PLANE]      # (against another
                      else np.sqrt(row[CONTACT_OWN_STIFFNESS] / row[CONTACT_MASS]))  # body: ~)
        if omega * dt > max_phase and (worst is None or omega > worst[2]):
            worst = (model.body_names[k], int(c), omega)
    return worst


def warn_contact(model, result, dt, warning, max_phase, stacklevel=4):
    """Warn (`warning`, UnresolvedMotionWarning) of a contact a finished fixed-step run touched
    with too long a step."""
    found = unresolved_contact(model, result, dt, max_phase)
    if found is not None:
        name, c, omega = found
        duration = np.pi / omega
        warnings.warn(warning(
            f"simulate: the step does not resolve the contact of body '{name}' (contact sphere "
            f"{c}): it lasts about {duration:.3g} s, {duration / dt:.3g} steps of {dt:g} s, "
            f"where the rebound's speed and the contact force may be far off; take dt <= "
            f"{duration / STEPS_PER_PERIOD:.2g} s ({STEPS_PER_PERIOD} steps a contact), or a "
            f"softer contact (Contact(contact_time=...))"), stacklevel=stacklevel)
