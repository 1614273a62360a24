"""What a built model holds, in words: Model.describe() and `dttmm info` (docs/scenes.md)."""
import numpy as np

from ..elements.beam import (ACCURACY, ACCURATE, AXIAL_MODES, CLAMPED, CLAMPED_LOADED, EI_V, EI_W,
                             EXACT, FAMILY, FREQUENCY_CUTOFF, MODES, PINNED, STIFFENING,
                             TORSION_MODES, axial_frequencies, bending_frequencies, largest_basis,
                             torsion_frequencies, truncation_errors)
from ..elements.hinges import ELASTIC, K_ROTATION, K_TRANSLATION
from ..elements.contact import BODY as CONTACT_BODY
from ..elements.contact import NORMAL as CONTACT_NORMAL
from ..elements.contact import ON_PLANE as CONTACT_ON_PLANE
from ..elements.contact import ROLE as CONTACT_ROLE
from ..elements.contact import SOLID as CONTACT_SOLID
from ..elements.contact import OWN_STIFFNESS as CONTACT_OWN_STIFFNESS
from ..elements.contact import STIFFNESS as CONTACT_STIFFNESS
from ..elements.contact import restitution_of_damping
from ..elements.kinds import (BEAM, JOINT_KINDS, RIGID, ROD, SCENE_TYPE, limit_of,
                              unimplemented_body_kind)
from ..elements.rigid_body import INERTIA_INPUT, MASS, TO_OUTPUT
from ..elements.strain_rod import (ROD_EI_V, ROD_EI_W, ROD_LENGTH, ROD_MODES, ROD_STATIONS,
                                   rod_components)
from ..model.rod_motion import rod_frequencies
from ..model.closures import describe_closures
from ..model.loop_kinematics import held_chords, loop_rank
from ..model.model import DESCRIBE

# each joint kind's name (its scene type) and degrees of freedom (elements/kinds.py)
JOINT_NAMES = SCENE_TYPE
JOINT_DOF = {k.code: k.dof for k in JOINT_KINDS}
_FAMILY_WHY = {
    PINNED: "pinned (sine modes in the chord frame): both ends are moment-free",
    CLAMPED: "clamped (the clamped-free eigenfunctions): the input section holds the frame and "
             "the output is the free tip",
    CLAMPED_LOADED: "clamped with a loaded end (polynomial Ritz modes): the input section holds "
                    "the frame and the output carries loads"}


def describe_counts(model):
    """'n bodies (r rigid, b beams[, s strain rods]), d degrees of freedom'."""
    kinds = model.body_kind
    rods = int(np.sum(kinds == ROD))
    head = (f"{model.n_bodies} bodies ({int(np.sum(kinds == RIGID))} rigid, "
            f"{int(np.sum(kinds == BEAM))} beam{'' if np.sum(kinds == BEAM) == 1 else 's'}"
            + (f", {rods} strain rod{'' if rods == 1 else 's'}" if rods else "") + "), ")
    if model.n_closures == 0 or model.tip_pinned:
        return head + f"{degrees_of_freedom(model)} degrees of freedom"
    rows = int(sum(CLOSURE_ROWS[int(k)] for k in model.closure_kind))
    tree = degrees_of_freedom(model)
    rigid, rank = loop_rank(model)
    modal = int(np.sum(model.n_modes))
    return head + (f"{tree} degrees of freedom in the tree, closed by {model.n_closures} "
                   f"joint{'s' if model.n_closures > 1 else ''} with {rows} constraint "
                   f"equations, {rows - rank} of them redundant: mobility {rigid - rank} as a "
                   f"rigid mechanism (Grübler's count {rigid - rows}, corrected by the rank "
                   f"{rank} of the constraint rows)"
                   + (f", plus {modal} modal coordinates" if modal else ""))


# the constraint equations of each closing joint kind (model/closures.py): 6 less its freedoms (an
# elastic hinge's none: elements/kinds.py, Kind.constraints)
CLOSURE_ROWS = {k.code: k.constraints for k in JOINT_KINDS}


def degrees_of_freedom(model):
    """Each joint's own freedoms (a ball 3, an elastic hinge 6, a revolute 1, ...) plus the
    beams' modal coordinates, less 3 for a tip pinned to the ground."""
    return int(sum(JOINT_DOF[int(k)] for k in model.hinge_kind) + np.sum(model.n_modes)
               - (3 if model.tip_pinned else 0))


def beam_frequencies(model, k):
    """(Hz) the retained modes' own frequencies of beam k, sqrt(k_j / m_j) / 2 pi with the
    modal stiffness and mass (docs/beam.md), per plane: (v plane, w plane)."""
    return bending_frequencies(model.beam_params[k])


def suggested_dt(model):
    """A step that resolves the model's fastest retained motion: 20 steps per period of the
    highest retained beam mode (a strain rod's highest own frequency) and of every elastic
    hinge's springs against the body they carry (sqrt(k / m) with its stiffest translational
    spring and the body's mass, sqrt(k / J) with its stiffest rotational spring and the body's
    least inertia about the hinge: above the hinge's own frequencies, which the bodies beyond
    it only lower), and 0.02 rad per step
    of the fastest initial spin or of a pendulum swing sqrt(g / L) over the shortest body
    (rounded down to 1, 2 or 5 x 10^k s)."""
    rates = [float(np.linalg.norm(w)) for w in model.initial_angular_velocity]
    g = float(np.linalg.norm(model.gravity))
    lengths = [float(np.linalg.norm(model.body_params[k, TO_OUTPUT]))
               for k in range(model.n_bodies)]
    lengths = [x for x in lengths if x > 0]
    if g > 0 and lengths:
        rates.append(np.sqrt(g / min(lengths)))
    dt = 0.02 / max(max(rates, default=0.0), 1e-3)
    for k in np.nonzero(model.body_kind == BEAM)[0]:
        f = max(float(np.max(fs, initial=0.0)) for fs in beam_frequencies(model, k)
                + (torsion_frequencies(model.beam_params[k]),
                   axial_frequencies(model.beam_params[k])))
        dt = min(dt, 1.0 / (20.0 * f))
    for row in {model.rod_params[k].tobytes(): model.rod_params[k]
                for k in np.nonzero(model.body_kind == ROD)[0]}.values():
        dt = min(dt, 1.0 / (20.0 * float(rod_frequencies(row).max())))
    for k in np.nonzero(model.hinge_kind == ELASTIC)[0]:
        h, body = model.hinge_params[k], model.body_params[k]
        least = float(np.linalg.eigvalsh(body[INERTIA_INPUT].reshape(3, 3)).min())
        for spring, inertia in ((h[K_TRANSLATION], float(body[MASS])), (h[K_ROTATION], least)):
            stiffest = float(np.linalg.eigvals(spring.reshape(3, 3)).real.max())
            if stiffest > 0.0 and inertia > 0.0:
                dt = min(dt, 2.0 * np.pi / (20.0 * np.sqrt(stiffest / inertia)))
    for row in model.contacts:          # 20 steps a contact (docs/contact.md)
        mass = float(model.body_params[int(row[CONTACT_BODY]), MASS])
        dt = min(dt, np.pi / (20.0 * np.sqrt(row[CONTACT_OWN_STIFFNESS] / mass)))
    exponent = np.floor(np.log10(dt))
    mantissa = dt / 10 ** exponent
    return float(max(m for m in (1.0, 2.0, 5.0) if m <= mantissa) * 10 ** exponent)


def _beam_lines(model, k, end_mass, chord_held=False):
    row = model.beam_params[k]
    m = int(row[MODES])
    fv, fw = beam_frequencies(model, k)
    lines = [f"{m} mode{'s' if m > 1 else ''} per plane, own frequencies (Hz): "
             f"v {np.array2string(fv, precision=4)}, w {np.array2string(fw, precision=4)}",
             f"mode family {_FAMILY_WHY[int(row[FAMILY])]}"]
    ends = model.ends_of(k)
    if any(ends):
        said = [what for what, on in zip(("the root turns freely (a joint's free rotation: "
                                          "pinned in that plane)",
                                          "the output is held at a point and turns freely "
                                          "(a closing joint: pinned in that plane)"), ends) if on]
        lines.append(f"ends: {' and '.join(said)}; the modes are counted for those ends")
    errors = truncation_errors(row, m, end_mass, ends)
    on = (f", with {end_mass:.4g} kg beyond its output as an end mass"
          if int(row[FAMILY]) == CLAMPED_LOADED and not ends[1] else "")
    lines.append(f"estimated truncation error{on}: "
                 + ", ".join(f"{what} {e:+.2%}" for what, e in errors.items())
                 + " (against the family's largest basis; docs/beam.md, 'How many modes')")
    cutoff = row[FREQUENCY_CUTOFF]
    cutoff_counted = cutoff == ACCURATE or cutoff > 0.0
    if cutoff == ACCURATE:
        lines.append(f"modes_per_plane=None (default): the fewest modes with every estimate "
                     f"within {ACCURACY:.1%}")
    if cutoff > 0.0:
        # auto_mode_count's measure: the frequencies of the family's largest basis
        cap = largest_basis(row)
        spectrum = np.minimum(*bending_frequencies(row, cap))
        why = f"modes_per_plane='auto': kept the modes at or below {cutoff:.4g} Hz"
        if m < cap and spectrum[m] > cutoff:
            why += f" (the next at {spectrum[m]:.4g} Hz)"
        else:
            why += f" (at least one, at most {cap})"
        if int(row[FAMILY]) == CLAMPED_LOADED:
            why += (f"; frequencies of the {cap}-mode basis: with {m} the polynomial modes' "
                    f"are higher (Ritz)")
        lines.append(why)
        reasons = model.frequency_cutoff_reasons
        if k < len(reasons) and reasons[k]:
            lines.append(f"the cutoff: {reasons[k]}")
    mt, ma = int(row[TORSION_MODES]), int(row[AXIAL_MODES])
    lines.append(f"{mt} twist mode{'s' if mt > 1 else ''}, own frequencies (Hz): "
                 f"{np.array2string(torsion_frequencies(row), precision=4)}" if mt else
                 "no twist (torsion_modes 0)")
    lines.append(f"{ma} stretch mode{'s' if ma > 1 else ''}, own frequencies (Hz): "
                 f"{np.array2string(axial_frequencies(row), precision=4)}" if ma else
                 "no stretch (axial_modes 0)")
    if row[STIFFENING] == EXACT:
        lines.append("geometric stiffening on, the foreshortening to all orders "
                     "(stiffening='exact': every section at x - c(x); its w' and eta'' columns "
                     "differenced, the general loop; docs/beam.md, 'The exact foreshortening')"
                     + ("; the default where the build counts 3 or more modes for a pinned "
                        "end, whose second-order energy holds only to a bend of ~0.08 rad or "
                        "less" if any(ends) and m >= 3 and cutoff_counted else ""))
    elif row[STIFFENING]:
        from ..solving.run_checks import STIFFENED_BEND_LIMIT
        limit = STIFFENED_BEND_LIMIT.get(m) if int(row[FAMILY]) == CLAMPED_LOADED else None
        lines.append("geometric stiffening on" + (
            f", to second order in the modes: holds while the beam bends less than ~{limit:g} "
            f"rad over its length with {m} modes per plane (~{STIFFENED_BEND_LIMIT[1]:g} with "
            f"one; docs/beam.md, 'Where the second-order energy stops'; stiffening='exact' "
            f"holds beyond)" if limit else ""))
    elif chord_held:
        lines.append("geometric stiffening off (the paper's beam): the loops hold this beam's "
                     "chord, so its inextensible centreline could not bow under stiffening (the "
                     "default's choice here, or stiffening=False); give it axial_modes and "
                     "axial_stiffness to stiffen it (docs/loops.md, 'Flexible links')")
    else:
        lines.append("geometric stiffening off (the paper's beam)")
    return lines


LONG_LOOP_ROWS = 20     # rows from which describe() advises a tree of local loops (4 loops)


def _loop_reach(model):
    """How far the closing joints' sweep columns reach (run_tables.loop_tables): the cost of a step
    grows with it, and a spanning tree whose loops close near the ground keeps it small."""
    from ..solving import run_tables
    from ..model.loop_rows import constraint_rows
    km = run_tables.kernel_model(model)[0]
    owner = constraint_rows(km)[1]
    body = np.array(km.closure_body, dtype=np.int64).reshape(-1, 2)
    _, _, _, act_ptr, _, band = run_tables.loop_columns(km, owner, body)
    rows = len(owner)
    reach = np.diff(act_ptr[1:]).mean() if rows else 0.0
    solve = "a banded LU" if band[0] >= 0 else "a truncated SVD"
    line = (f"(each of the {rows} rows' sweep columns passes {reach:.3g} of the {km.n_bodies} "
            f"bodies of the kernel model on average, the rows solved by {solve}: loops that "
            f"close near the ground, on a spanning tree of short paths, cost least)")
    if rows >= LONG_LOOP_ROWS and reach > 0.5 * km.n_bodies:
        line += ("\n  the loops share most bodies, so a step costs rows x bodies, O(N^2) in a "
                 "mechanism's size: build it with System.build(tree=\"shortest\"), which "
                 "roots each body by its nearest joint to the ground, or root each loop's "
                 "bodies at their own ground pivots (System.add(body, joint, at=[x, y, z])) "
                 "and close each loop between neighbours, and each column passes a few bodies "
                 "(docs/loops.md, \"Choosing the spanning tree\": the 40-four-bar 14x faster "
                 "a step)")
    return line


def _rod_line(row):
    """A strain rod's strain field in words (docs/strain_rod.md)."""
    modes = int(row[ROD_MODES])
    field = {1: "constant", 2: "linear", 3: "quadratic"}.get(modes, f"degree {modes - 1}")
    return (f"strain rod, {row[ROD_LENGTH]:.4g} m: a {field} strain ({modes} coefficient"
            f"{'s' if modes > 1 else ''} each) in {', '.join(rod_components(row))}, mass "
            f"integrated at {int(row[ROD_STATIONS])} Gauss points; own frequencies clamped "
            f"(Hz): {np.array2string(rod_frequencies(row), precision=4)}")


# a chain's sag under its own weight (a cantilever's tip deflection over its length) above
# which describe() calls its beams far-bending
FAR = 0.1


def element_advice(model):
    """Which flexible element suits the model's beams or rods, in words: their line's sag under
    its own weight, mu g L^3 / (8 EI) over its whole welded length (a cantilever's tip
    deflection over its length, linear theory), says whether they bend far (above FAR); the
    modal beam holds ~0.17 rad of bending per element with 2 modes per plane (docs/beam.md,
    "Where the second-order energy stops"; its exact foreshortening goes on), a strain rod a
    constant curvature exactly and costs about 2.4 modal elements per step
    (docs/strain_rod.md, "In the sweep").  None for a model without either."""
    flexible = np.nonzero((model.body_kind == BEAM) | (model.body_kind == ROD))[0]
    if not len(flexible):
        return None
    g = float(np.linalg.norm(model.gravity))
    length = sum(float(np.linalg.norm(model.body_params[k, TO_OUTPUT])) for k in flexible)
    mass = sum(float(model.body_params[k, MASS]) for k in flexible)
    stiffness = min(_bending_stiffness(model, k) for k in flexible)
    sag = mass / length * g * length ** 3 / (8.0 * stiffness) if stiffness > 0 else np.inf
    rods = bool((model.body_kind == ROD).any())
    far = sag > FAR
    how = (f"sag under its own weight {sag:.3g} of its length (mu g L^3 / 8 EI over "
           f"{length:.4g} m)" if g > 0 else "no gravity to judge by")
    if far and not rods:
        return (f"elements: far-bending ({how}): the modal beam holds ~0.17 rad of bending per "
                f"element with 2 modes per plane (its exact foreshortening goes on, with many "
                f"elements); StrainRod carries a constant curvature exactly and a varying one at "
                f"order 4 in its length (the soft pendulum: 8 rods within 1e-2 m of 32 modal "
                f"elements; docs/strain_rod.md)")
    if rods and not far and g > 0:
        return (f"elements: bending little ({how}): the modal beam (EulerBernoulliBeam) is "
                f"~2.4x cheaper per element and step than a strain rod and as accurate "
                f"there")
    return (f"elements: {'strain rods' if rods else 'modal beams'} ({how}); StrainRod for "
            f"elements that bend far, the modal beam for small deflections (docs/strain_rod.md)")


def _bending_stiffness(model, k):
    """The least bending stiffness EI of beam or rod k, N m^2."""
    if model.body_kind[k] == ROD:
        return float(min(model.rod_params[k, ROD_EI_V], model.rod_params[k, ROD_EI_W]))
    if model.body_kind[k] == BEAM:
        return float(min(model.beam_params[k, EI_V], model.beam_params[k, EI_W]))
    raise unimplemented_body_kind(model.body_kind[k], f"body '{model.body_names[k]}'",
                                  "describe's bending stiffness")


def describe(model):
    """The model in words: its counts, gravity and tip, every body with its joint and parent,
    each beam's modes (their frequencies, the family and why, what modes_per_plane='auto'
    kept, the twist modes), and a step that resolves it."""
    out = [describe_counts(model),
           f"gravity {model.gravity.tolist()} m/s^2; "
           + ("tip pinned" if model.tip_pinned else
              f"closed by {model.n_closures} joint{'s' if model.n_closures > 1 else ''}"
              if model.n_closures else "tip free"),
           "bodies:"]
    end_masses = model.carried_masses()
    # the unstiffened beams without stretch whose chord the loops hold (one Jacobian for all)
    unstiffened = np.nonzero((model.body_kind == BEAM) & (model.beam_params[:, STIFFENING] == 0.0)
                             & (model.beam_params[:, AXIAL_MODES] == 0))[0]
    held = set(held_chords(model, unstiffened)) if model.n_closures else set()
    for k in range(model.n_bodies):
        kind = {BEAM: "beam", ROD: "rod"}.get(int(model.body_kind[k]), "rigid")
        p = model.parent[k]
        parent = "the ground" if p < 0 else f"'{model.body_names[p]}'"
        if p < 0 and model.attachment_point[k].any():
            parent += f" at {np.array2string(model.attachment_point[k], precision=4)} m"
        joint = JOINT_NAMES[int(model.hinge_kind[k])]
        out.append(f"  {model.body_names[k]:<14} {kind:<5} {model.body_params[k, MASS]:8.4g} kg, "
                   f"on {'an' if joint[0] in 'aeio' else 'a'} {joint} joint "
                   f"'{model.hinge_names[k]}' to {parent}")
        for i in range(len(model.drives[k])):     # its end stops (docs/limits.md)
            lower, upper, stiffness, damping = limit_of(model.hinge_params[k], i)
            if stiffness:
                out.append(f"  {'':<14} coordinate {i}: end stops at [{lower:.6g}, {upper:.6g}], "
                           f"stiffness {stiffness:.4g}, damping {damping:.4g} (docs/limits.md)")
        out += [f"  {'':<14} {line}" for line in _contact_lines(model, k)]
        if kind == "beam":
            out += [f"  {'':<14} {line}" for line in _beam_lines(model, k, end_masses[k],
                                                                 k in held)]
        elif kind == "rod":
            out.append(f"  {'':<14} {_rod_line(model.rod_params[k])}")
    if model.n_closures and not model.tip_pinned:
        out += ["closing joints:"] + [f"  {line}" for line in describe_closures(model)]
        out.append("  (simulate: held at acceleration level in every Newton iteration, up to 16 "
                   "by default, positions and rates projected back onto the loops after every "
                   "step; docs/loops.md)")
        out.append("  " + _loop_reach(model))
        from ..solving.run_checks import energy_not_held
        why_not = energy_not_held(model)
        out.append("  energy: " + ("held after every step by scaling the rates (nothing works "
                                   "on these rigid loops; hold_energy=False steps without it)"
                                   if why_not is None else f"not held ({why_not}): the "
                                   "balance E - E(0) - W moves at the step's second order")
                   + "; docs/loops.md, \"The energy held\"")
    advice = element_advice(model)
    if advice is not None:
        out.append(advice)
    out.append(f"suggested dt: {suggested_dt(model):g} s (20 steps per period of the fastest "
               f"retained mode or elastic hinge, and per contact; 0.02 rad per step of the "
               f"fastest spin or swing)")
    out.append(_kernels_line(model))
    out.append(_schemes_line(model))
    return "\n".join(out)


def _contact_lines(model, k):
    """Body k's contact spheres, one line per distinct law (docs/contact.md): what they touch,
    the stiffness and how long a contact lasts on the body, the restitution its damping gives,
    the friction."""
    rows = [row for row in model.contacts
            if int(row[CONTACT_BODY]) == k and int(row[CONTACT_ROLE]) != CONTACT_SOLID]
    if not rows:
        return []
    mass = float(model.body_params[k, MASS])
    out = []
    laws = {}
    for row in rows:
        on_plane = bool(row[CONTACT_ON_PLANE])
        law = (on_plane,) + tuple(row[CONTACT_STIFFNESS:CONTACT_STIFFNESS + 4] if on_plane
                                  else row[CONTACT_OWN_STIFFNESS:CONTACT_OWN_STIFFNESS + 4])
        laws[law] = laws.get(law, 0) + 1
    normal = np.array2string(rows[0][CONTACT_NORMAL], precision=4)
    for (on_plane, stiffness, damping, mu, v_s), count in laws.items():
        omega = np.sqrt(stiffness / mass)
        what = (f"the plane (normal {normal}) and other bodies' shapes" if on_plane
                else "other bodies' shapes")
        out.append(f"touches {what} at {count} contact sphere{'s' if count > 1 else ''}: "
                   f"stiffness {stiffness:.4g} N/m (a contact lasts ~{np.pi / omega:.3g} s on "
                   f"this body), restitution {restitution_of_damping(damping):.3g}, friction "
                   f"{mu:.3g} (sticks to within {v_s:.2g} m/s) (docs/contact.md)")
    return out


def _kernels_line(model):
    """Which loop runs the model (Newmark, Riccati) and what it compiles."""
    from ..solving.methods import SCHEMES
    from ..solving.run_plan import kernels_used
    try:
        loop = kernels_used(model, SCHEMES["newmark"])
    except ValueError:
        return "kernels: none run this model with the default scheme"
    if loop == "general":
        return ("kernels: the general loop, the core every kind of model runs (compiled once "
                "per install, by `dttmm compile` or the first run; docs/solver.md, \"Compile "
                "time\")")
    return (f"kernels: the fused {loop} loop (compiled once per install for every model it "
            f"runs, by `dttmm compile` or its first use)")


def _schemes_line(model):
    """Which of simulate's schemes run the model (dttmm/solving/methods.py), and which to take for
    tight tolerances."""
    from ..solving.methods import SCHEMES
    from ..solving.run_checks import check_supported
    runs, why = [], {}
    for name in SCHEMES:
        try:
            check_supported(model, name)
        except ValueError as error:
            why[name] = str(error)
            continue
        runs.append(name)
    if not runs:
        return f"schemes: none ({why['newmark']})"
    tight = ("scheme='dop853' with rtol (order 8, explicit: docs/integrators.md)"
             if "dop853" in runs else "richardson=3 with newton_iterations (order 6: "
             "docs/solver.md)")
    return (f"schemes: {', '.join(runs) or 'none'}; for tight tolerances (below ~1e-7 m) "
            f"{tight}")


DESCRIBE[0] = describe          # Model.describe (model/model.py)
