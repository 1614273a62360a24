"""What a fixed-step run could not resolve, said after the run (docs/solver.md, "Steps that
cannot resolve the motion"; issue 65, item 5).

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
"""
import warnings

import numpy as np

from .elements.beam import EI_V, EI_W, FAMILY, LENGTH, MASS_PER_LENGTH, MODES, mode_shapes
from .elements.kinds import BEAM

MODE_SHARE = 1e-3         # of the run's energy: a mode holding more must be resolved
STEPS_PER_PERIOD = 20     # the advice: 20 steps a period (or a turn)


def unresolved_mode(model, result, dt, max_phase):
    """The worst kept bending mode the step does not resolve and the motion excites, as
    (beam name, plane, mode number, frequency Hz, share of the energy), or None."""
    beams = np.nonzero(model.body_kind == BEAM)[0]
    if not len(beams) or result.modal_coordinates is None or len(result.t) < 2:
        return None
    offsets = np.concatenate([[0], np.cumsum(model.n_modes)])
    eta, eta_dot = np.asarray(result.modal_coordinates), np.asarray(result.modal_velocities)
    candidates, elastic = [], np.zeros(len(result.t))
    for k in beams:
        row = model.beam_params[k]
        m = int(row[MODES])
        _, _, _, mass, stiff = mode_shapes(int(row[FAMILY]), row[LENGTH], m, [0.0])
        modal_mass = row[MASS_PER_LENGTH] * mass
        for plane, ei, first in (("v", row[EI_V], 0), ("w", row[EI_W], m)):
            omega = np.sqrt(ei * stiff / modal_mass)
            q = eta[:, offsets[k] + first:offsets[k] + first + m]
            elastic += 0.5 * (q * q) @ (ei * stiff)
            for j in np.nonzero(omega * dt > max_phase)[0]:
                qd = eta_dot[:, offsets[k] + first + j]
                energy = 0.5 * modal_mass[j] * qd * qd     # its vibration's (kinetic) energy
                candidates.append((model.body_names[k], plane, j + 1,
                                   omega[j] / (2 * np.pi), float(energy.max())))
    if not candidates:
        return None
    total = float(np.max(np.asarray(result.kinetic) + elastic))
    worst = max(candidates, key=lambda c: c[4])
    share = worst[4] / total if total > 0.0 else 0.0
    return worst[:4] + (share,) if share > MODE_SHARE else None


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
