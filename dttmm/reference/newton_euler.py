"""Independent reference solver: global Newton-Euler equations with joint reactions.

This module shares only the model description (dttmm.model, dttmm.elements, dttmm.results) with
the rest of the package; it uses no transfer matrices, and it evaluates the beams' mode shapes
itself (it does not call dttmm.elements.beam.mode_shapes).

Formulation
-----------
Coordinates.  Each body whose inboard hinge leaves its rotation free (ball joint or elastic
hinge) carries a quaternion q_k (body to world, normalised whenever it is read) and its world
angular velocity w_k.  A body behind a fixed hinge is welded to its inboard neighbour's OUTPUT
SECTION: A_k = A_O,{k-1} R0, w_k = w_O,{k-1} (the ground frame for k = 0), where the output
section of a rigid body is the body itself and that of a beam is its deflected end section
(docs/beam.md, "End sections"):
    A_O = A exp(theta_O^),  theta_O = [psi(L), -w'(L), v'(L)],  w_O = w + A J_l(theta_O) theta_O'.
Each elastic hinge carries its world deflection d_k and its rate.  Positions and velocities
follow from the ground point by kinematics,
    r_in_k = r_O,{k-1} + d_k,   r_O,k = r_in_k + rho_O,k,
with rho_O = A l_IO for a rigid body and rho_O = A (L e1 + u(L)) for a beam, so ball and fixed
joints hold exactly (to round-off) by construction.

Equations.  At every right-hand-side evaluation one dense linear system is assembled and solved
for all unknowns at once: the input-point acceleration a_k and angular acceleration alpha_k of
every body, the reaction force F_k of every ball or fixed hinge, the reaction couple N_k of
every fixed hinge, and the beams' modal accelerations (joints with coordinates add their
reactions F_k, N_k and coordinate accelerations q'': "Joints with coordinates" below).  Rows
are, for each rigid body k (world frame; rho_c = A l_IC, J = A J_I A^T):
    Newton:         M (a_k + alpha_k x rho_c + w x (w x rho_c)) = Q_k - Q_{k+1} + M g + f_k
    Euler about I:  J alpha_k + w x J w + M rho_c x a_k
                        = N_k - N_{k+1} - (rho_O + d_{k+1}) x Q_{k+1} + rho_c x (M g + f_k) + tau_k
where Q_k, N_k are the force and couple the inboard side exerts on body k at its input point:
unknown reactions for ball / fixed hinges (N_k = 0 for a ball joint), the spring-damper law for
elastic hinges.  Hinge k's force acts at r_in_k, which for a ball or fixed hinge is the inboard
output point O, so N_{k+1} is also the couple about O (the contract's m_O).

End kinematics.  Every body exposes its output point and output section, linear in its
accelerations (B_r = dr_O/d eta = A Phi(L), B_t = A J_l(theta_O) D with D = d theta_O / d eta;
zero for a rigid body):
    a_O     = a_I + alpha x rho_O + B_r eta'' + [w x (w x rho_O) + 2 w x (A u'(L))]
    alpha_O = alpha + B_t eta'' + [w x (A J_l theta_O') + A (dJ_l[theta_O'] theta_O')]
where dJ_l[u] is the derivative of J_l(theta) along u (see _so3_coefficients):
    J_l    = I + a t^ + b t^ t^,      a = (1 - cos p)/p^2,  b = (p - sin p)/p^3,  p = |t|,
    dJ_l[u] = (t.u) (a1 t^ + b1 t^ t^) + a u^ + b (u^ t^ + t^ u^),  a1 = a'(p)/p, b1 = b'(p)/p,
so d/dt [J_l(t) t'] = J_l t'' + dJ_l[t'] t' exactly; a, b, a1, b1 come from their Taylor series
for p < 2 (exact to rounding) and from the closed forms above.  The constraint rows of a ball or
fixed hinge k are a_k = a_O,{k-1} (a_ground for k = 0) and, for a fixed hinge, alpha_k =
alpha_O,{k-1} (alpha_ground).  Their reactions enter the inboard body's rows with the transposed
Jacobians (virtual work): Newton + F_k, Euler about I + rho_O x F_k + N_k, and a beam's modal
rows + B_r^T F_k + B_t^T N_k, i.e. the generalized forces of the outboard's force -q_O and
couple -m_O in docs/beam.md's modal equations, with the end section's virtual rotation (world)
A J_l(theta_O) d theta_O.  The system matrix is then symmetric in its constraint blocks, and
the reactions do no work on any motion the constraints allow: energy is conserved.
Elastic hinges add no rows: d_k'' = a_k - a_O,{k-1}, and their loads are known from the state.
Their inboard frame is the inboard body's output section (the ground frame for k = 0): with
A_in := A_O,{k-1}, w_in := w_O,{k-1} (for a beam its deflected end section, for a rigid body the
body itself) the law of docs/hinges.md reads
    q     = -A_O (K_t A_O^T d_k + C_t A_O^T d_k'),     d_k = r_in_k - r_O,{k-1}
    m_out = -A_O (K_r psi + C_r A_O^T (w_k - w_O)),   exp(psi^) = A_O^T A_k R0^T
    m_in  = m_out + d_k x q,
spring energy 1/2 (A_O^T d)^T K_t (A_O^T d) + 1/2 psi^T K_r psi.  Body k gets q, m_out in its
Newton / Euler rows; the inboard body gets -q at r_O and the couple -m_in (Newton - q, Euler
about I - m_in - rho_O x q) and, for a beam, the same generalized forces as a weld's reactions,
- B_r^T q - B_t^T m_in in its modal rows (right-hand side).  An elastic hinge at a beam's input
acts at I and does no modal work there (Y_k(0) = Y_k'(0) = 0 for the clamped families).

Loops (docs/loops.md).  Each closing joint (System.close; build_chain(tip="ball") is one) is a
set of scalar constraints between its sides' points p_a, p_b and frames F_a, F_b
(loop_rows.constraint_directions): gaps g = e . (p_b - p_a), e fixed in the world or in a's
frame (a slide's two directions across its axis), and dots g = (F_a x) . (F_b y).  Per row one
multiplier, the column -J^T in the dynamic rows (a force lam e on b at p_b and -lam e on a,
for a gap; a couple lam (y x x) on b and its opposite on a, for a dot; a beam's end takes
B_r^T e and B_t^T (y x x) in its modal rows), so that they do no work on what the joint allows,
and the row
    g'' + 2 W g' + W^2 g = 0                                 (Baumgarte, W = LOOP_DAMPING)
linear in the accelerations:  for a gap e . (a_b - a_a) (+ with e turning with a:
(alpha_a x e) . d + (w_a x (w_a x e)) . d + 2 (w_a x e) . d', d = p_b - p_a), for a dot
(alpha_b - alpha_a) . (y x x) + (w_b - w_a) . ((w_b x y) x x + y x (w_a x x)).  A closing
joint's coordinate driven by a prescribed motion s(t) adds its row (loop_rows.driven_directions:
a slide's gap along a's axis, or an angle atan2(n . (x x y), x . y) with the rate n . (w_b -
w_a) and the acceleration n . (alpha_b - alpha_a) + (w_s x n) . (w_b - w_a), its multiplier a
couple lam n on b), held as (g - s)'' + 2 W (g - s)' + W^2 (g - s) = 0; a SpringDamper's row
is its force instead, lam = -k (q - rest) - c q' from the state, and a JointForce's lam = f(t,
q, q') (q, q' the row's values, which one evaluation of the state finds first).  A closing
elastic hinge is six such spring rows (loop_rows.spring_directions): gaps n_i . (F_a^T (p_b -
p_a)) and rotations n_i . log(F_a^T F_b R0^T), the rates of the latter n_i . F_a^T (w_b - w_a),
along the common principal axes n_i of its springs and dampers.  The system is
solved by eliminating the tree first and then the multipliers from the Delassus matrix by a
truncated SVD (_solve_least_closure_force): the least multipliers, where constraints are
redundant (a planar loop of spatial revolute joints; a chain straight between two fixed points,
whose tension is then indeterminate, as the DT-TMM sweeps take it) or singular (a
parallelogram lying flat).  A run starts from an assembled state (assembly.assemble, applied
when the loops are open by more than 1e-10 at t = 0).

Attachment points.  In a tree "k - 1" above reads parent[k] = P, and hinge k sits at P's
attachment point r_att,k (Model.attachment_point): a beam's output point, its only one, with
its end section as the inboard frame, exactly as above; on a rigid parent any point x_k fixed in
its frame (its output point l_IO or a named point, body frame from its input point), with the
body's own frame (A_P, w_P, alpha_P) as the inboard frame:
    rho_att,k = A_P x_k,   r_att,k = r_in,P + rho_att,k,   v_att,k = v_in,P + w_P x rho_att,k,
    a_att,k = a_P + alpha_P x rho_att,k + w_P x (w_P x rho_att,k),
so for x_k = l_IO these are r_O, v_O and a_O of the rigid body (rho_att = rho_O) and a chain
runs exactly as before.  Everything above takes r_att,k in place of the inboard output point for
hinge k: r_in_k = r_att,k + d_k, the constraint rows a_k = a_att,k (columns -1 at a_P and
rho_att,k^ at alpha_P, right-hand side w_P x (w_P x rho_att,k)), the reactions' share of the
parent's Euler row + (rho_att,k + d_k) x F_k + N_k (the transposes of those columns, so the
reactions still do no work), an elastic hinge's -q at r_att,k and d_k'' = a_k - a_att,k.  Each
child of one parent carries its own arm.

Strain rods (docs/strain_rod.md).  A rod's strain coordinates and rates sit with the beams' modal
ones; its stations' poses, rates and Jacobians are the reference's own (strain_rod.py::
rod_sections: the Magnus step's exponential and its time derivatives from a power series over
truncated polynomials), its rows a beam's with them (strain_rod.py::rod_terms: the stations'
masses and section inertias, the strain rows by virtual work) and its end its last station
(rod_end: rho_O, A_O, w_O, B_r = A Jp_L, B_t = A Jr_L and the velocity parts of a_O and alpha_O).

Joints with coordinates (revolute, universal, prismatic; docs/joints.md).  Their coordinates q
and rates q' (one each, two for a universal joint) are states (all coordinates in hinge order,
then all rates: Result.joint_coordinates' order); the child carries no quaternion of its own but
follows its parent's output section (A_P, w_P, alpha_P; the ground frame for a root joint) and
the coordinates, with n, n1 fixed in the parent's section, n2 in the child, R0 the hinge's rest
rotation and u = A_P n, u1 = A_P n1, v2 = A n2 (world):
    revolute:   A = A_P Rot(n, q) R0,                w = w_P + u q'
    universal:  A = A_P Rot(n1, q1) R0 Rot(n2, q2),  w = w_P + u1 q1' + v2 q2'
    prismatic:  A = A_P R0,                          w = w_P,
                r_in = r_O,P + d,  d = u q,  d' = w_P x d + u q'
(Rot(n, q) = exp(q n^); the prismatic d takes an elastic hinge's deflection's place in the
kinematics, in the parent's arm rho_O + d and in the energies' input points).  Differentiating,
with u' = w_P x u (u is fixed in the parent's section) and v2' = w x v2 (fixed in the child):
    revolute:   alpha = alpha_P + u q'' + (w_P x u) q'
    universal:  alpha = alpha_P + u1 q1'' + v2 q2'' + (w_P x u1) q1' + (w x v2) q2'
                (w x v2 = (w_P + u1 q1') x v2: the q1' q2' term is the cross-coupling)
    prismatic:  alpha = alpha_P,
                a_in  = a_O,P + alpha_P x d + u q'' + w_P x (w_P x d) + 2 w_P x u q'
and these are the joint's constraint rows, the weld's rows with the coordinate terms added
(a_in = a_O,P for revolute and universal joints); for a beam parent alpha_P = alpha_O,P =
alpha_kp + B_t eta''_kp + [velocity part] (End kinematics), so the slide's alpha_P x d puts
d^ B_t in the row's modal columns.  Each such joint has a reaction force F_k and couple N_k (the
total loads the parent exerts on the child at its input point, the drive's included: Result
force and moment) and, per coordinate, one more unknown, q_i'', and one more row:
    free coordinate:        s_i . N_k = tau_i   (s_i . F_k for the slide)
    prescribed (MOTION):    q_i'' = q_p''(t)
with s_i the coordinate's world direction (u, u1, v2; the slide's u) and tau_i the drive's
generalized force: FORCE f(t, q, q'), SPRING_DAMPER -k (q - rest) - c q', PD kp (target(t) - q)
+ kd (target'(t) - q') + feedforward(t), no drive 0.  The
virtual power of the joint loads on a relative motion is N . (w - w_P) = sum (s_i . N) q_i'
(F . u q' for the slide, whose relative angular velocity is zero), so s_i . N is coordinate i's
generalized force; for a prescribed coordinate it is what the solve returns (Result
drive_force), and its q, q' are read from the motion at every evaluation (their state entries
only carry them along).  On the parent the loads are -F_k at r_O,P + d and -N_k: Euler row
+ (rho_O + d) x F_k + N_k, a beam parent's modal rows + B_r^T F_k + B_t^T (N_k + d x F_k), the
transposes of the constraint rows' parent columns as for a weld.  The drive springs store
1/2 k (q - rest)^2 (dttmm.results.result.chain_energies(joint_coordinates=...)), the dampers
dissipate c q'^2, a FORCE drive does the work tau q'.

Euler-Bernoulli beams (docs/beam.md).  A beam body carries, besides its frame (quaternion, w, or
the inboard output section through a fixed hinge), its modal coordinates eta = [eta_v (n),
eta_w (n)] and their rates; the unknowns gain the modal accelerations eta'' and the rows gain
the 2n modal equations.  In body components, with p(x) = x e1 + Phi(x) eta the frame-relative
position of the section at x, Phi(x) = [e2 Y(x), e3 Y(x)] (3 x 2n), and the frame's body-frame
w_b, alpha_b, a_b:
    A^T r''(x) = a_b + alpha_b x p + w_b x (w_b x p) + 2 w_b x Phi eta' + Phi eta''
and the integrals the equations need are moments of the line mass:
    m = mu L,  s = int mu p,  Q = int mu p p^T,  J_b = tr(Q) E - Q,  P = int mu Phi,
    G = int mu p^ Phi,  C = int mu (Phi eta') p^T,
so that (world; h = A s, J = A (J_b + J_p) A^T, J_p = diag(j_p L, 0, 0), M_Y = int Y Y^T):
    Newton:  m a_I - h^ alpha + A P eta'' - F_k + F_{k+1}
                 = m g - w x (w x h) - 2 w x (A P eta')
    Euler:   J alpha + h^ a_I + A G eta'' - N_k + N_{k+1} + rho_O^ F_{k+1}
                 = h x g - w x J w - 2 A (w_b tr C - C w_b)
    modal:   (A P)^T a_I + (A G)^T alpha + mu blockdiag(M_Y, M_Y) eta''
                 + B_r^T F_{k+1} + B_t^T N_{k+1}
                 = (A P)^T g - int mu Phi^T w_b^ w_b^ p - 2 int mu Phi^T w_b^ Phi eta'
                   - c eta' - k eta
(int mu p x (w x (w x p)) = w x J_b w and int mu p x (w x u') = w tr C - C w).  All of these
follow from three integrals of the shapes, int_0^L Y_k, int_0^L x Y_k and int_0^L Y_j Y_k, and
the end values Y_k(L), Y_k'(L):
  pinned:  Y_k = sin(k pi x / L), ANALYTIC: int Y_k = L (1 - (-1)^k) / (k pi),
           int x Y_k = -L^2 (-1)^k / (k pi), int Y_j Y_k = (L / 2) delta_jk, Y_k(L) = 0,
           Y_k'(L) = (k pi / L) (-1)^k; modal mass mu L / 2, stiffness EI (k pi / L)^4 L / 2.
  clamped (free tip): Y_k = e^(-b x) + (1 - s) sinh b x - cos b x + s sin b x (the
           clamped-free eigenfunctions, b = b_k from the roots of 1 + cos bL cosh bL = 0),
           integrals by GAUSS-LEGENDRE QUADRATURE with 48 + 8 n points on [0, L] (exact to
           ~1e-14 relative; tests/test_reference_clamped.py checks it against twice the points),
           Y_k(L), Y_k'(L) from the closed form; modal mass mu int Y_k^2 (= mu L), stiffness
           EI b_k^4 L.
  clamped, loaded end (CLAMPED_LOADED: a ball joint, fixed hinge or the pinned tip at the
           output): Y_j = sum_i c_ij (x/L)^(i+2), c the Ritz eigenvectors of docs/beam.md (solved
           here by scipy.linalg.eigh, normalized int_0^L Y_j Y_k = L delta_jk, Y_j(L) > 0); the
           integrals are polynomial moments, ANALYTIC (int t^p = 1 / (p + 1)); modal mass mu L,
           stiffness EI lam_j / L^3.
Damping c_k = 2 zeta omega_k m_k, omega_k = sqrt(k_k / m_k), per plane.

Geometric stiffening (docs/beam.md; a beam's STIFFENING flag): the section at x also moves back
along e1 by the foreshortening c(x) = 1/2 int_0^x (v'^2 + w'^2), kept to first order in c:
p(x) = x e1 + Phi eta - c e1 in s (s_x -= mu int c), Q (Q_xx -= 2 mu int x c) and C
(C_xx = -mu d/dt int x c); the Newton row's A int mu p'' gains -mu A e1 (eta'^T D1 eta' +
(D1 eta)^T eta''), the output point r_O moves back by c(L) (B_r gains -A e1 (D0 eta)^T, so
the end forces work through it), and the modal rows gain mu e1 . (g - a_I) D1 eta +
mu (w_y^2 + w_z^2) D2 eta on the left, with D0, D1, D2 = int (1, L - x, (L^2 - x^2) / 2) Y' Y'^T
(stiffening_matrices: polynomial moments or quadrature of the slopes).  These are Lagrange's
equations of the kinetic and potential energy to second order in eta, whose terms in c
dttmm.results.result.chain_energies counts by its own quadrature of c(x).  (The energies in
dttmm.results.result are computed independently, by quadrature of |r'(x)|^2 and g . r(x).)

Geometric stiffening, exact (simulate_reference(exact_foreshortening=True); docs/beam.md, "Where
the second-order energy stops"): the energies to second order in eta are not positive where an
element's modes turn back its frame's turn, so the reference can keep c to all orders instead.
Every section of a stiffened beam is then a point of a Gauss-Legendre rule
(shapes.exact_foreshortening_table: x, weight, Y(x), D(x) = int_0^x Y' Y'^T, U(x)) at
p = (x + u_x - c, v, w), with c = 1/2 (eta_v^T D eta_v + eta_w^T D eta_w) and
d p / d eta_j = (-(D eta_v)_j, Y_j, 0), (-(D eta_w)_j, 0, Y_j) for the bending coordinates,
(U_j, 0, 0) for the stretch: s, Q, P, G and the modal mass are the sums of mu weight p,
p p^T, Phi, p^ Phi and Phi^T Phi over the points, the velocity terms those of
2 w x Phi eta' + kappa (kappa = -(eta_v'^T D eta_v' + eta_w'^T D eta_w') e1, the velocity part of
p''), and the modal rows Phi^T (A^T g - w x (w x p) - 2 w x Phi eta' - kappa) (_beam_terms_exact):
Lagrange's equations of the kinetic energy 1/2 int mu |r'|^2 exactly, positive for every
motion, and of the potential energy with the same sections.  The output point is the same as
above (exact in c already), and
dttmm.results.result.chain_energies(exact_foreshortening=True) counts the energies with the same
sections.  The stiffening terms above (G eta, the Newton row's
-mu A e1 (D1 eta)^T eta'') are the first-order parts of these sums.

Torsion (docs/beam.md; a beam's TORSION_MODES): the sections twist by psi(x) = Psi(x) . eta_t
(the beam's last coordinates) about the frame's x axis and spin by w . A e1 + psi', with
T = 1/2 j_p int (w . A e1 + psi')^2 and V = 1/2 G J int psi'^2 (twist_shape_constants, closed
forms).  The Euler row about I gains j_p (int Psi)^T eta_t'' A e1 (a column of A G, so the
twist rows get the transposed (A e1 j_p int Psi)^T alpha) and the velocity term
-j_p (int Psi . eta_t') w x A e1; the twist rows have the mass j_p int Psi_k^2, stiffness
G J int Psi_k'^2 and the damping of the bending modes' rule; the end section's rotation
theta_O gains psi(L) in its first entry, so B_t gains the columns A J_l e1 Psi_k(L) and the
outboard's couple works on the twist through them.

Stretch (docs/beam.md; a beam's AXIAL_MODES): the sections also move along the frame's x by
u_x(x) = U(x) . xi (the beam's last coordinates), exactly: p = (x + u_x - c, v, w), so s, Q,
C and the columns of P and G gain their terms (int U_j, int x U_j, int U_j^2 and the products
int U_j Y_l: stretch_shape_constants, the twist's closed-form shapes), the modal rows' first
moments int Y_j p_x, the Coriolis terms 2 int mu Phi_j . (w x u') their u_x' parts, and the
stretch rows are e1 . int mu U_j (g - r'') with mass mu int U_j^2 and stiffness
E A int U_j'^2; r_O gains A e1 u_x(L) (B_r's columns A e1 U_j(L)).

Loads in body axes (a beam's LOAD_AXES, docs/beam.md "Loads on the beam"): the end force and
torque are turned by the output section's rotation A_O, the distributed load by the frame's A,
before they enter the rows above (followers).

The right-hand side is numba-compiled; the Python wrapper only evaluates the ground motion and
the applied loads at time t and hands them to the kernel as arrays.
"""
import time

import numpy as np

from ..elements import BEAM, ROD
from ..elements.kinds import declared_body_kind
from ..elements.beam import AXIAL_MODES, LENGTH, MODES, STIFFENING, TORSION_MODES
from ..model.assembly import assemble
from ..model.loop_rows import has_closure_drives
from ..model.loop_kinematics import check_drives_move, loop_residuals
from ..model.model import Model
from ..results.result import Result, chain_energies
from ..model.sections import point_positions
from .rows import _SY
from .beam_terms import _stiffening_block
from .problem import _Problem
from .strain_rod import rod_sections, station_arrays


METHODS = ("RK45", "DOP853")


# ----------------------------------------------------------------------------------------------
# Python layer
# ----------------------------------------------------------------------------------------------


def _check_args(model, t_end, method, rtol, atol, t_eval):
    if not isinstance(model, Model):
        raise ValueError(f"simulate_reference: model must be a dttmm Model (from build_chain), "
                         f"got {type(model).__name__}")
    for k, code in enumerate(model.body_kind):     # (its kernels would refuse it mid-run)
        declared_body_kind(code, f"simulate_reference: body '{model.body_names[k]}'")
    try:
        t_end = float(t_end)
    except (TypeError, ValueError):
        raise ValueError(f"simulate_reference: t_end must be a number, got {t_end!r}") from None
    if not np.isfinite(t_end) or t_end <= 0.0:
        raise ValueError(f"simulate_reference: t_end must be finite and > 0, got {t_end}")
    if method not in METHODS:
        raise ValueError(f"simulate_reference: method must be one of {METHODS}, got {method!r}")
    for name, v in (("rtol", rtol), ("atol", atol)):
        try:
            x = float(v)
        except (TypeError, ValueError):
            raise ValueError(f"simulate_reference: {name} must be a number, got {v!r}") from None
        if not np.isfinite(x) or x <= 0.0:
            raise ValueError(f"simulate_reference: {name} must be finite and > 0, got {x}")
    if float(rtol) < 100.0 * np.finfo(float).eps:
        raise ValueError(f"simulate_reference: rtol must be >= {100 * np.finfo(float).eps:.3g} "
                         f"(100 machine epsilons), got {rtol}")
    if t_eval is None:
        t_eval = np.linspace(0.0, t_end, 201)
    else:
        try:
            t_eval = np.array(t_eval, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise ValueError("simulate_reference: t_eval must be a 1-D array of times") from None
        if t_eval.size == 0 or not np.all(np.isfinite(t_eval)):
            raise ValueError("simulate_reference: t_eval must be a non-empty array of finite times")
        if t_eval[0] < 0.0 or t_eval[-1] > t_end or np.any(np.diff(t_eval) <= 0.0):
            raise ValueError(f"simulate_reference: t_eval must be strictly increasing within "
                             f"[0, t_end] = [0, {t_end}]")
    return t_end, t_eval


def simulate_reference(model, t_end, *, method="DOP853", rtol=1e-10, atol=1e-12, t_eval=None,
                       exact_foreshortening=False):
    """Integrate the model with the global Newton-Euler equations and scipy's solve_ivp (its
    DOP853 run in compiled code when nothing in the model runs Python during the run, a hub
    spun by a profile's angle included: reference/integrator.py, reference/hub.py;
    docs/reference.md, "Integrator").

    An independent check of DT-TMM (docs/reference.md; the formulation is in this module's
    docstring): it shares only the model description with the rest of the package.  Every
    element and topology runs: trees with every hinge kind at any attachment point (a beam's
    output point, a rigid body's output point or one of its named points;
    Model.attachment_point; module docstring, "Attachment points"), and joints with
    coordinates (revolute, universal, prismatic; module docstring) and their drives, with
    beams as parents and children too.

    Parameters
    ----------
    model : Model
        The frozen system (``dttmm.System(...).build()`` or ``dttmm.build_chain``).  The
        initial modal coordinates and rates are the model's.  A chain built with tip="ball"
        has its tip held at its starting point (fixed in the world, a_tip = 0, also when the
        ground moves); the initial angular velocities must leave it at rest there.
    t_end : float
        End time, s (finite, > 0).
    method : {"DOP853", "RK45"}
        solve_ivp's integrator (default "DOP853").
    rtol : float
        solve_ivp's relative tolerance (default 1e-10; finite, >= 100 machine epsilons).
    atol : float
        solve_ivp's absolute tolerance (default 1e-12; finite, > 0), in the state's units
        (quaternion entries, rad/s, m, m/s, modal and joint coordinates and rates).
    t_eval : array_like, optional
        The recorded times, s: strictly increasing within [0, t_end]; default 201 points over
        [0, t_end].  Sampled from the integrator's dense output (the state at t = 0 exactly
        as given).
    exact_foreshortening : bool
        Stiffened beams with the foreshortening kept exactly in their kinetic and potential
        energy (module docstring, "Geometric stiffening, exact"; docs/beam.md, "Where the
        second-order energy stops"), by quadrature of their sections, and the energies counted
        the same way; default False: to second order, as DT-TMM's kernels do for
        stiffening=True.  A beam given stiffening="exact" is exact either way, as in DT-TMM.

    Returns
    -------
    Result
        ``dttmm.Result`` with method "newton-euler/DOP853" (or "/RK45"): positions, velocities,
        rotations, angular velocities and accelerations, the forces and moments at every
        body's input, the energies (``dttmm.results.result.chain_energies``) at every recorded time;
        wall_time (s, the integration only), n_steps (the integrator's steps) and info, which
        holds nfev and the number of state variables (n_state) and unknowns (n_unknowns) of
        the global system.  For models with EulerBernoulliBeam bodies (every mode family of
        docs/beam.md) it also holds modal_coordinates and modal_velocities (T, total modes;
        body order, a beam's v coordinates first, then w), the energies count the beams'
        deflection, position_mass_center is each beam's deflected mass centre and
        position_output its deflected output point r_I + A (L e1 + u(L)).  With joints with
        coordinates it holds joint_coordinates, joint_rates (a prescribed coordinate's from
        its motion) and drive_force (T, total coordinates; hinge order), a prismatic child's
        input point moves by its slide, and the potential energy counts the drive springs.

    Raises
    ------
    ValueError
        A model that is not a Model, or a bad t_end, method, rtol, atol or t_eval (naming the
        argument); a tip joined to a fixed point that the initial angular velocities move; a
        drive that returns a non-finite or non-scalar value during the run (naming the joint
        and coordinate).
    RuntimeError
        The integration failed (the time and why: solve_ivp's message, or the compiled
        integrator's step fallen below the spacing of the numbers near t).

    Examples
    --------
    >>> import dttmm
    >>> rod = dttmm.RigidBody(mass=1.0, inertia=[1e-4, 1 / 12, 1 / 12],
    ...                       inertia_about="mass_center", to_mass_center=[0.5, 0, 0],
    ...                       to_output=[1.0, 0, 0], angular_velocity=[0, 0, 1.0])
    >>> model = dttmm.build_chain([dttmm.BallJoint(), rod])
    >>> ref = dttmm.simulate_reference(model, 1.0, t_eval=[0.0, 0.5, 1.0])  # doctest: +SKIP
    >>> ref.position_output.shape  # doctest: +SKIP
    (3, 1, 3)
    """
    from scipy.integrate import solve_ivp      # (when used: import dttmm stays light)

    from .integrator import OK, integrate_dop853
    t_end, t_eval = _check_args(model, t_end, method, rtol, atol, t_eval)
    assembly = None
    if model.n_closures:
        before = [float(np.max(r, initial=0.0)) for r in loop_residuals(model)]
        if max(before) > 1e-10:          # close the loops first (assembly.assemble, which
            model = assemble(model)      # refuses a drive the loops lock)
        else:
            check_drives_move(model, "simulate_reference")
        assembly = {"before": before,
                    "after": [float(np.max(r, initial=0.0)) for r in loop_residuals(model)]}
    prob = _Problem(model, bool(exact_foreshortening))
    y0 = prob.initial_state()
    n, nt = prob.n, len(t_eval)
    fixed = prob.fixed_args() if method == "DOP853" else None
    if prob.n_state > 0 and fixed is not None:
        # scipy's DOP853 in compiled code (integrator.py); its first call, over a vanishing
        # interval, compiles or loads it outside the timing
        integrate = integrate_dop853
        integrate(*fixed, y0, 1e-300, 1.0, 1.0, np.zeros(0))
        t0 = time.perf_counter()
        ys, n_steps, nfev, status, t_reached = integrate(
            *fixed, y0, t_end, float(rtol), float(atol), t_eval)
        wall = time.perf_counter() - t0
        if status != OK:
            raise RuntimeError(f"simulate_reference: integration failed at t = {t_reached}: "
                               f"the step fell below the spacing of the numbers near t "
                               f"(a singular or diverging motion)")
        ys = ys.copy()
        if t_eval[0] == 0.0:
            ys[0] = y0
    elif prob.n_state > 0:
        prob.rhs(0.0, y0)                      # compile / load the kernels outside the timing
        t0 = time.perf_counter()
        sol = solve_ivp(prob.rhs, (0.0, t_end), y0, method=method, rtol=float(rtol),
                        atol=float(atol), dense_output=True)
        wall = time.perf_counter() - t0
        if sol.status != 0:
            raise RuntimeError(f"simulate_reference: integration failed at t = {sol.t[-1]}: "
                               f"{sol.message}")
        ys = sol.sol(t_eval).T
        if t_eval[0] == 0.0:
            ys[0] = y0
        n_steps, nfev = len(sol.t) - 1, int(sol.nfev)
    else:                                       # everything prescribed: nothing to integrate
        ys = np.zeros((nt, 0))
        wall, n_steps, nfev = 0.0, 0, 0

    rot = np.empty((nt, n, 3, 3))
    omega = np.empty((nt, n, 3))
    r_in = np.empty((nt, n, 3))
    v_in = np.empty((nt, n, 3))
    alpha = np.empty((nt, n, 3))
    force = np.empty((nt, n, 3))
    moment = np.empty((nt, n, 3))
    deflection = np.empty((nt, n, 3))
    ground_rot = np.empty((nt, 3, 3))
    ground_pos = np.empty((nt, 3))
    nm, e0 = prob.n_modal, prob.e0
    eta = np.ascontiguousarray(ys[:, e0:e0 + nm])
    eta_dot = np.ascontiguousarray(ys[:, e0 + nm:e0 + 2 * nm])
    rho_out = np.empty((nt, n, 3))
    nq, c0 = prob.n_coord, prob.c0
    q_rec = np.empty((nt, nq))
    qd_rec = np.empty((nt, nq))
    drive = np.empty((nt, nq))
    stops = np.empty((nt, nq))
    closure_load = np.empty((nt, model.n_closures, 8))
    for i, t in enumerate(t_eval):
        out = prob.evaluate(t, ys[i])
        closure_load[i] = out[17]
        rk, wk, rik, vik, dk, _, ak, fk, mk, _, rho_out[i] = out[:11]
        rot[i], omega[i], r_in[i], v_in[i] = rk, wk, rik, vik
        alpha[i], force[i], moment[i] = ak, fk, mk
        # the coordinates as the kinematics saw them (a prescribed one from its motion); a
        # free coordinate's drive force as applied, a prescribed one's as the joint loads' s.N
        y_i = prob.joint_inputs(t, ys[i])
        q_rec[i], qd_rec[i] = y_i[c0:c0 + nq], y_i[c0 + nq:c0 + 2 * nq]
        drive[i] = np.where(prob.prescribed == 1, out[14], prob.drive_value - prob.stop_value)
        stops[i] = prob.stop_value
        deflection[i] = dk
        ground = model.ground_state(t)
        ground_rot[i], ground_pos[i] = ground[3], ground[0]
    # every sample's energies at once (their beams' shape tables made once, not per sample)
    kinetic, potential = chain_energies(model, rot, omega, r_in, v_in, deflection,
                                        ground_rotation=ground_rot, eta=eta, eta_dot=eta_dot,
                                        joint_coordinates=q_rec if nq else None,
                                        ground_position=ground_pos,
                                        exact_foreshortening=exact_foreshortening)
    r_c, r_o = point_positions(model, rot, r_in)
    for k in range(n):                          # a beam's mass centre and output point move
        if prob.body_kind[k] == BEAM:           # with its deflection
            r_c[:, k] = r_in[:, k] + np.einsum("tij,tj->ti", rot[:, k],
                                               _beam_mass_center(prob.beam_params[k],
                                                                 prob.shape_vec[k],
                                                                 prob.shape_mat[k],
                                                                 eta[:, prob.m_off[k]:]))
            r_o[:, k] = r_in[:, k] + rho_out[:, k]
        elif prob.body_kind[k] == ROD:          # its stations' mass centre, its end point
            r_c[:, k] = r_in[:, k] + np.einsum("tij,tj->ti", rot[:, k], _rod_mass_center(
                prob.rods, k, eta[:, prob.m_off[k]:]))
            r_o[:, k] = r_in[:, k] + rho_out[:, k]

    return Result(method=f"newton-euler/{method}", t=np.array(t_eval), position_input=r_in,
                  position_mass_center=r_c, position_output=r_o, rotation=rot,
                  angular_velocity=omega, angular_acceleration=alpha, force=force, moment=moment,
                  kinetic=kinetic, potential=potential, wall_time=wall, n_steps=n_steps,
                  info={"nfev": nfev, "n_state": prob.n_state, "n_unknowns": prob.n_unknowns,
                        **({"assembly": assembly} if assembly else {})},
                  closure_force=closure_load[:, :, :3] if assembly else None,
                  closure_moment=closure_load[:, :, 3:6] if assembly else None,
                  closure_drive_force=(closure_load[:, :, 6:] if assembly
                                       and has_closure_drives(model) else None),
                  velocity_input=v_in,
                  modal_coordinates=eta if nm > 0 else None,
                  modal_velocities=eta_dot if nm > 0 else None,
                  joint_coordinates=q_rec if nq > 0 else None,
                  joint_rates=qd_rec if nq > 0 else None,
                  drive_force=drive if nq > 0 else None,
                  limit_force=stops if prob.has_stops else None,
                  body_names=tuple(model.body_names))


def _rod_mass_center(rods, k, q):
    """(T, 3) body-frame mass centre of strain rod k: its stations' centres weighted by their
    Gauss weights (q: its strain coordinates in the first n_q columns)."""
    nq = rods[0][k]
    phi = np.ascontiguousarray(rods[3][k, :, :, :, :nq])
    out = np.zeros((len(q), 3))
    zero = np.zeros(nq)
    stations = station_arrays(rods[1].shape[1] + 1)
    for i in range(len(q)):         # (the centres only: no Jacobians)
        rod_sections(rods[1][k], rods[2][k], phi, np.ascontiguousarray(q[i, :nq]), zero, zero,
                     *stations)
        out[i] = rods[4][k] @ stations[1] / rods[4][k].sum()
    return out


def _beam_mass_center(bp, sv, my, eta):
    """(T, 3) body-frame mass centre of a beam, s / (mu L) with s = int mu p dx; sv: the beam's
    shape constants (row _SY = int Y_k dx), my its matrices (int Y Y^T, D0, D1, D2: with
    geometric stiffening s_x loses mu int c = mu/2 eta^T D1 eta); eta holds its coordinates in
    its first 2n columns."""
    length, nm = bp[LENGTH], int(bp[MODES])
    sy = sv[_SY, :nm]
    out = np.zeros((len(eta), 3))
    out[:, 0] = length / 2.0
    if bp[STIFFENING]:
        d1 = _stiffening_block(my, nm, 1)
        for plane in range(2):
            e = eta[:, plane * nm:(plane + 1) * nm]
            out[:, 0] -= 0.5 * np.einsum("tj,jk,tk->t", e, d1, e) / length
    out[:, 1] = eta[:, :nm] @ sy / length
    out[:, 2] = eta[:, nm:2 * nm] @ sy / length
    na = int(bp[AXIAL_MODES])                      # the stretch: s_x gains int U . xi
    if na:
        tw = sv.shape[1] // 3
        first = 2 * nm + int(bp[TORSION_MODES])
        out[:, 0] += eta[:, first:first + na] @ sv[_SY, 2 * tw:2 * tw + na] / length
    return out
