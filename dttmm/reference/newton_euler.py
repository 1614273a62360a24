"""Independent reference solver: global Newton-Euler equations with joint reactions.

This module shares only the model description (dttmm.model, dttmm.elements, dttmm.result) with
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
(closures.constraint_directions): gaps g = e . (p_b - p_a), e fixed in the world or in a's
frame (a slide's two directions across its axis), and dots g = (F_a x) . (F_b y).  Per row one
multiplier, the column -J^T in the dynamic rows (a force lam e on b at p_b and -lam e on a,
for a gap; a couple lam (y x x) on b and its opposite on a, for a dot; a beam's end takes
B_r^T e and B_t^T (y x x) in its modal rows), so that they do no work on what the joint allows,
and the row
    g'' + 2 W g' + W^2 g = 0                                 (Baumgarte, W = LOOP_DAMPING)
linear in the accelerations:  for a gap e . (a_b - a_a) (+ with e turning with a:
(alpha_a x e) . d + (w_a x (w_a x e)) . d + 2 (w_a x e) . d', d = p_b - p_a), for a dot
(alpha_b - alpha_a) . (y x x) + (w_b - w_a) . ((w_b x y) x x + y x (w_a x x)).  A closing
joint's coordinate driven by a prescribed motion s(t) adds its row (closures.driven_directions:
a slide's gap along a's axis, or an angle atan2(n . (x x y), x . y) with the rate n . (w_b -
w_a) and the acceleration n . (alpha_b - alpha_a) + (w_s x n) . (w_b - w_a), its multiplier a
couple lam n on b), held as (g - s)'' + 2 W (g - s)' + W^2 (g - s) = 0; a SpringDamper's row
is its force instead, lam = -k (q - rest) - c q' from the state, and a JointForce's lam = f(t,
q, q') (q, q' the row's values, which one evaluation of the state finds first).  A closing
elastic hinge is six such spring rows (closures.spring_directions): gaps n_i . (F_a^T (p_b -
p_a)) and rotations n_i . log(F_a^T F_b R0^T), the rates of the latter n_i . F_a^T (w_b - w_a),
along the common principal axes n_i of its springs and dampers.  The system is
solved by eliminating the tree first and then the multipliers from the Delassus matrix by a
truncated SVD (_solve_least_closure_force): the least multipliers, where constraints are
redundant (a planar loop of spatial revolute joints; a chain straight between two fixed points,
whose tension is then indeterminate, as the DT-TMM sweeps take it) or singular (a
parallelogram lying flat).  A run starts from an assembled state (closures.assemble, applied
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
1/2 k (q - rest)^2 (dttmm.result.chain_energies(joint_coordinates=...)), the dampers dissipate
c q'^2, a FORCE drive does the work tau q'.

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
dttmm.result.chain_energies counts by its own quadrature of c(x).  (The energies in
dttmm.result are computed independently, by quadrature of |r'(x)|^2 and g . r(x).)

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
import math
import time

import numba
import numpy as np
from scipy.integrate import solve_ivp
from scipy.linalg import eigh

from ..elements import BEAM
from ..elements.beam import (CLAMPED, CLAMPED_LOADED, DAMPING_RATIO, EI_V, EI_W, FAMILY, GJ,
                             LENGTH, LOAD_AXES, MASS_PER_LENGTH, MODES, PINNED,
                             POLAR_PER_LENGTH, STIFFENING, TORSION_MODES, AXIAL_MODES, EA)
from ..elements.drives import FORCE, MOTION, PD, SPRING_DAMPER
from ..elements.hinges import (AXIS_1, AXIS_2, C_ROTATION, C_TRANSLATION, COORDINATE_0,
                               DEFLECTION_0, ELASTIC, FIXED, K_ROTATION, K_TRANSLATION, RATE_0,
                               REST_ROTATION)
from ..elements.joints import PRISMATIC, REVOLUTE, UNIVERSAL, coordinate_count
from ..elements.kinds import JOINT_KIND
from ..elements.rigid_body import INERTIA_INPUT, MASS, TO_MASS_CENTER, TO_OUTPUT
from ..kernels import CONTRACT
from ..closures import (ANGLE_A, ANGLE_B, DOT, GAP_A, GAP_WORLD, ROTATION_A, assemble,
                        check_drives_move,
                        closure_forces, constraint_rows, has_closure_drives, loop_residuals)
from ..model import Model
from ..result import Result, chain_energies, point_positions, rotation_to_quaternion

METHODS = ("RK45", "DOP853")

# offsets into a body_params / hinge_params row, as plain ints for the kernels
_MASS = MASS
_LIC = TO_MASS_CENTER.start
_LIO = TO_OUTPUT.start
_JI = INERTIA_INPUT.start
_R0 = REST_ROTATION.start
_KT = K_TRANSLATION.start
_CT = C_TRANSLATION.start
_KR = K_ROTATION.start
_CR = C_ROTATION.start
_BEAM = BEAM
_DOT, _GAP_A, _GAP_WORLD, _ANGLE_A, _ANGLE_B, _ROTATION_A = (DOT, GAP_A, GAP_WORLD, ANGLE_A,
                                                            ANGLE_B, ROTATION_A)
_SPRING_DAMPER = SPRING_DAMPER
_FORCE = FORCE
_BL, _BMU, _BEIV, _BEIW = LENGTH, MASS_PER_LENGTH, EI_V, EI_W
_BJP, _BZETA, _BMODES, _BSTIFF = POLAR_PER_LENGTH, DAMPING_RATIO, MODES, STIFFENING
_BTWIST, _BGJ, _BAXES = TORSION_MODES, GJ, LOAD_AXES
_BSTRETCH, _BEA = AXIAL_MODES, EA
_AX1 = AXIS_1.start
_AX2 = AXIS_2.start
_REVOLUTE, _UNIVERSAL, _PRISMATIC = REVOLUTE, UNIVERSAL, PRISMATIC
JOINTS_WITH_COORDINATES = (REVOLUTE, UNIVERSAL, PRISMATIC)

# rows of the per-beam shape constants (_Problem.shape_vec[k, row, mode])
_SY, _TY, _YL, _DYL, _MF, _KF = range(6)
N_SHAPE_ROWS = 6

# b_k L of the clamped-free modes: the roots of 1 + cos x cosh x = 0, and beyond the fifth
# (2k - 1) pi / 2, as docs/beam.md prescribes (off the true root by ~1 / cosh(b_k L): 6e-8 for
# k = 6, so those shapes are orthogonal only to ~1e-8; the mass matrix here is the quadrature
# of int Y_j Y_k, not L delta_jk, so the equations stay consistent with the energy)
_CLAMPED_ROOTS = (1.87510406871196, 4.69409113297418, 7.85475743823761, 10.9955407348755,
                  14.1371683910465)


def clamped_shapes(length, n_modes, x):
    """(Y, Y') of the first n_modes clamped-free eigenfunctions at the points x, each
    (n_modes, len(x)), and b_k (n_modes,): Y = cosh bx - cos bx - s (sinh bx - sin bx), written as
    e^(-bx) + (1 - s) sinh bx - cos bx + s sin bx so that no digits cancel at large b x."""
    x = np.asarray(x, dtype=float).reshape(-1)
    y = np.empty((n_modes, x.size))
    dy = np.empty((n_modes, x.size))
    betas = np.empty(n_modes)
    for j in range(n_modes):
        k = j + 1
        bl = _CLAMPED_ROOTS[j] if k <= len(_CLAMPED_ROOTS) else (2 * k - 1) * math.pi / 2.0
        b = bl / length
        den = math.sinh(bl) + math.sin(bl)
        s = (math.cosh(bl) + math.cos(bl)) / den
        one_minus_s = (math.sin(bl) - math.cos(bl) - math.exp(-bl)) / den
        bx = b * x
        e = np.exp(-bx)
        y[j] = e + one_minus_s * np.sinh(bx) - np.cos(bx) + s * np.sin(bx)
        dy[j] = b * (-e + one_minus_s * np.cosh(bx) + np.sin(bx) + s * np.cos(bx))
        betas[j] = b
    return y, dy, betas


def quadrature_points(n_modes):
    """Gauss-Legendre points used for the clamped integrals of a beam with n_modes per plane."""
    return 48 + 8 * int(n_modes)


def beam_shape_constants(beam_row, n_points=None):
    """Shape constants of one beam: a (N_SHAPE_ROWS, n) array with rows int Y_k, int x Y_k,
    Y_k(L), Y_k'(L), m_k / mu and k_k / EI, and the (n, n) matrix int Y_j Y_k (module docstring:
    analytic for 'pinned' and the loaded-end modes, Gauss-Legendre quadrature for the
    clamped-free eigenfunctions; n_points overrides the number of points)."""
    length, nm, family = float(beam_row[LENGTH]), int(beam_row[MODES]), int(beam_row[FAMILY])
    vec = np.zeros((N_SHAPE_ROWS, nm))
    k = np.arange(1, nm + 1)
    if family == PINNED:
        sgn = (-1.0) ** k
        vec[_SY] = length * (1.0 - sgn) / (k * np.pi)
        vec[_TY] = -length * length * sgn / (k * np.pi)
        vec[_YL] = 0.0
        vec[_DYL] = (k * np.pi / length) * sgn
        vec[_MF] = 0.5 * length
        vec[_KF] = (k * np.pi / length) ** 4 * 0.5 * length
        mat = np.diag(np.full(nm, 0.5 * length))
    elif family == CLAMPED:
        nq = quadrature_points(nm) if n_points is None else int(n_points)
        xg, wg = np.polynomial.legendre.leggauss(nq)
        x = 0.5 * length * (xg + 1.0)
        wq = 0.5 * length * wg
        y, _, betas = clamped_shapes(length, nm, x)
        y_end, dy_end, _ = clamped_shapes(length, nm, [length])
        vec[_SY] = y @ wq
        vec[_TY] = y @ (wq * x)
        vec[_YL] = y_end[:, 0]
        vec[_DYL] = dy_end[:, 0]
        mat = (y * wq) @ y.T
        vec[_MF] = np.diag(mat)
        vec[_KF] = betas ** 4 * length
    elif family == CLAMPED_LOADED:
        # Y_j = sum_i c_ij (x/L)^p_i, p_i = i + 2: every integral is a polynomial moment
        c, lam = loaded_mode_coefficients(nm)
        p = np.arange(2, nm + 2, dtype=float)
        vec[_SY] = length * (c.T @ (1.0 / (p + 1.0)))
        vec[_TY] = length * length * (c.T @ (1.0 / (p + 2.0)))
        vec[_YL] = c.sum(axis=0)
        vec[_DYL] = (c.T @ p) / length
        mat = length * (c.T @ (1.0 / (p[:, None] + p[None, :] + 1.0)) @ c)
        vec[_MF] = np.diag(mat)
        vec[_KF] = lam / length ** 3
    else:
        raise ValueError(f"simulate_reference: unknown beam mode family {family}")
    return vec, mat


def shaft_shape_constants(length, family, count, x=None):
    """The closed-form shape constants of a second-order (twist or stretch) field on a beam:
    a (N_SHAPE_ROWS, count) array with rows _SY = int U_j, _TY = int x U_j, _YL = U_j(L),
    _MF = int U_j^2, _KF = int U_j'^2 (module docstring, "Torsion" and "Stretch"), and the
    shapes U_j at the points x (count, len(x)) if given.  For a moment-free output (families
    pinned and clamped) U_j = sqrt(2) sin(b x), b = (2j - 1) pi / (2 L); for a loaded output the
    Ritz modes of the field fixed at 0 in the monomials (x/L)^1 .. (x/L)^count, every integral
    a polynomial moment."""
    vec = np.zeros((N_SHAPE_ROWS, count))
    x = np.zeros(0) if x is None else np.asarray(x, dtype=float)
    if count == 0:
        return vec, np.zeros((0, x.size))
    if family == CLAMPED_LOADED:
        p = np.arange(1, count + 1, dtype=float)
        gram = 1.0 / (p[:, None] + p[None, :] + 1.0)
        lam, c = eigh(np.outer(p, p) / (p[:, None] + p[None, :] - 1.0), gram)
        c = c / np.sqrt(np.einsum("ij,ik,kj->j", c, gram, c))
        c = c * np.where(c.sum(axis=0) < 0.0, -1.0, 1.0)
        vec[_SY] = length * (c.T @ (1.0 / (p + 1.0)))
        vec[_TY] = length * length * (c.T @ (1.0 / (p + 2.0)))
        vec[_YL] = c.sum(axis=0)
        vec[_MF] = length * np.einsum("ij,ik,kj->j", c, gram, c)
        vec[_KF] = lam / length
        return vec, c.T @ (x / length)[None, :] ** p[:, None]
    b = (2.0 * np.arange(1, count + 1) - 1.0) * math.pi / (2.0 * length)
    vec[_SY] = math.sqrt(2.0) / b                 # sqrt(2) (1 - cos(b L)) / b, cos(b L) = 0
    vec[_TY] = math.sqrt(2.0) * np.sin(b * length) / (b * b)
    vec[_YL] = math.sqrt(2.0) * np.sin(b * length)
    vec[_MF] = length
    vec[_KF] = length * b * b
    return vec, math.sqrt(2.0) * np.sin(np.outer(b, x))


def twist_shape_constants(beam_row):
    """The twist's shape constants of one beam (module docstring, "Torsion"):
    shaft_shape_constants with its torsion_modes (rows _SY = int Psi_k, _YL = Psi_k(L),
    _MF = int Psi_k^2, _KF = int Psi_k'^2 used)."""
    return shaft_shape_constants(float(beam_row[LENGTH]), int(beam_row[FAMILY]),
                                 int(beam_row[TORSION_MODES]))[0]


def stretch_shape_constants(beam_row):
    """The stretch's shape constants of one beam (module docstring, "Stretch"): a
    (N_SHAPE_ROWS + m, ma) array with the rows of shaft_shape_constants (the twist's shapes:
    the same operator) and, from row N_SHAPE_ROWS on, int U_j Y_l (l < m, the bending shapes),
    by Gauss-Legendre quadrature of this module's own bending shapes
    (quadrature_points(max(m, ma)) points)."""
    length, m, ma, family = float(beam_row[LENGTH]), int(beam_row[MODES]), \
        int(beam_row[AXIAL_MODES]), int(beam_row[FAMILY])
    vec = np.zeros((N_SHAPE_ROWS + m, ma))
    if ma == 0:
        return vec
    xg, wg = np.polynomial.legendre.leggauss(quadrature_points(max(m, ma)))
    x, wq = 0.5 * length * (xg + 1.0), 0.5 * length * wg
    vec[:N_SHAPE_ROWS], u = shaft_shape_constants(length, family, ma, x)
    if family == CLAMPED_LOADED:
        pb = np.arange(2, m + 2, dtype=float)
        y = loaded_mode_coefficients(m)[0].T @ (x / length)[None, :] ** pb[:, None]
    elif family == PINNED:
        y = np.sin(np.arange(1, m + 1)[:, None] * math.pi * x[None, :] / length)
    else:
        y = clamped_shapes(length, m, x)[0]
    vec[N_SHAPE_ROWS:] = (y * wq) @ u.T
    return vec


def stiffening_matrices(beam_row):
    """The geometric stiffness integrals of one beam, (3, n, n): int_0^L w(x) Y_j'(x) Y_k'(x) dx
    for w = 1, L - x and (L^2 - x^2) / 2 (module docstring, "Geometric stiffening"): for the
    loaded-end modes as polynomial moments, otherwise by Gauss-Legendre quadrature of the
    slopes with quadrature_points(n) points (products of two trigonometric or hyperbolic slopes
    and a quadratic weight)."""
    length, nm, family = float(beam_row[LENGTH]), int(beam_row[MODES]), int(beam_row[FAMILY])
    out = np.empty((3, nm, nm))
    if family == CLAMPED_LOADED:
        # Y_j' = (1/L) sum_i c_ij p_i t^(p_i - 1): int_0^L t^a Y_j' Y_k' dx = (1/L) c^T T_a c,
        # (T_a)_il = p_i p_l / (p_i + p_l - 1 + a)
        c, _ = loaded_mode_coefficients(nm)
        p = np.arange(2, nm + 2, dtype=float)
        moment = [(c.T @ (np.outer(p, p) / (p[:, None] + p[None, :] - 1.0 + a)) @ c) / length
                  for a in range(3)]
        out[0] = moment[0]
        out[1] = length * (moment[0] - moment[1])
        out[2] = 0.5 * length * length * (moment[0] - moment[2])
        return out
    xg, wg = np.polynomial.legendre.leggauss(quadrature_points(nm))
    x = 0.5 * length * (xg + 1.0)
    wq = 0.5 * length * wg
    if family == PINNED:
        k = np.arange(1, nm + 1)[:, None]
        dy = (k * np.pi / length) * np.cos(k * np.pi * x[None, :] / length)
    else:
        dy = clamped_shapes(length, nm, x)[1]
    for i, weight in enumerate((np.ones_like(x), length - x, 0.5 * (length * length - x * x))):
        out[i] = (dy * (wq * weight)) @ dy.T
    return out


def loaded_mode_coefficients(n_modes):
    """The loaded-end modes of docs/beam.md on a unit length: c (n, n) with
    Y_j(t) = sum_i c_ij t^(i+2), and lam_j, from K c = lam M c with M_ij = 1 / (p_i + p_j + 1),
    K_ij = p_i (p_i - 1) p_j (p_j - 1) / (p_i + p_j - 3), p_i = i + 2; normalized to
    int_0^1 Y_j^2 = 1 (c^T M c = I) and Y_j(1) = sum_i c_ij > 0."""
    p = np.arange(2, n_modes + 2, dtype=float)
    m = 1.0 / (p[:, None] + p[None, :] + 1.0)
    pp = p * (p - 1.0)
    k = np.outer(pp, pp) / (p[:, None] + p[None, :] - 3.0)
    lam, c = eigh(k, m)
    c = c / np.sqrt(np.einsum("ij,ik,kj->j", c, m, c))
    c = c * np.where(c.sum(axis=0) < 0.0, -1.0, 1.0)
    return c, lam


# ----------------------------------------------------------------------------------------------
# small pure kernels
# ----------------------------------------------------------------------------------------------

@numba.njit(cache=True, fastmath=CONTRACT)
def _mat3(row, start):
    m = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            m[i, j] = row[start + 3 * i + j]
    return m


@numba.njit(cache=True, fastmath=CONTRACT)
def _vec3(row, start):
    v = np.empty(3)
    for i in range(3):
        v[i] = row[start + i]
    return v


@numba.njit(cache=True, fastmath=CONTRACT)
def _cross(a, b):
    c = np.empty(3)
    c[0] = a[1] * b[2] - a[2] * b[1]
    c[1] = a[2] * b[0] - a[0] * b[2]
    c[2] = a[0] * b[1] - a[1] * b[0]
    return c


@numba.njit(cache=True, fastmath=CONTRACT)
def _hat(v):
    m = np.zeros((3, 3))
    m[0, 1] = -v[2]
    m[0, 2] = v[1]
    m[1, 0] = v[2]
    m[1, 2] = -v[0]
    m[2, 0] = -v[1]
    m[2, 1] = v[0]
    return m


@numba.njit(cache=True, fastmath=CONTRACT)
def _quat_to_rot(q):
    """Rotation matrix of the quaternion [w, x, y, z], normalised first."""
    s = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    w, x, y, z = q[0] / s, q[1] / s, q[2] / s, q[3] / s
    r = np.empty((3, 3))
    r[0, 0] = 1.0 - 2.0 * (y * y + z * z)
    r[0, 1] = 2.0 * (x * y - w * z)
    r[0, 2] = 2.0 * (x * z + w * y)
    r[1, 0] = 2.0 * (x * y + w * z)
    r[1, 1] = 1.0 - 2.0 * (x * x + z * z)
    r[1, 2] = 2.0 * (y * z - w * x)
    r[2, 0] = 2.0 * (x * z - w * y)
    r[2, 1] = 2.0 * (y * z + w * x)
    r[2, 2] = 1.0 - 2.0 * (x * x + y * y)
    return r


@numba.njit(cache=True, fastmath=CONTRACT)
def _log_rot(r):
    """Rotation vector psi with expm(hat(psi)) = r, |psi| <= pi; robust at every angle (it goes
    through the quaternion of r, largest component first)."""
    tr = r[0, 0] + r[1, 1] + r[2, 2]
    diag_max = max(r[0, 0], r[1, 1], r[2, 2])
    if tr >= diag_max:
        s = 2.0 * math.sqrt(1.0 + tr)
        w = 0.25 * s
        x = (r[2, 1] - r[1, 2]) / s
        y = (r[0, 2] - r[2, 0]) / s
        z = (r[1, 0] - r[0, 1]) / s
    elif r[0, 0] == diag_max:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        w = (r[2, 1] - r[1, 2]) / s
        x = 0.25 * s
        y = (r[0, 1] + r[1, 0]) / s
        z = (r[0, 2] + r[2, 0]) / s
    elif r[1, 1] == diag_max:
        s = 2.0 * math.sqrt(1.0 - r[0, 0] + r[1, 1] - r[2, 2])
        w = (r[0, 2] - r[2, 0]) / s
        x = (r[0, 1] + r[1, 0]) / s
        y = 0.25 * s
        z = (r[1, 2] + r[2, 1]) / s
    else:
        s = 2.0 * math.sqrt(1.0 - r[0, 0] - r[1, 1] + r[2, 2])
        w = (r[1, 0] - r[0, 1]) / s
        x = (r[0, 2] + r[2, 0]) / s
        y = (r[1, 2] + r[2, 1]) / s
        z = 0.25 * s
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    sv = math.sqrt(x * x + y * y + z * z)
    psi = np.empty(3)
    if sv < 1e-12:
        f = 2.0 / w              # angle / sin(angle / 2) -> 2 as angle -> 0
    else:
        f = 2.0 * math.atan2(sv, w) / sv
    psi[0] = f * x
    psi[1] = f * y
    psi[2] = f * z
    return psi


@numba.njit(cache=True, fastmath=CONTRACT)
def _so3_coefficients(t):
    """Coefficients of exp and of the left Jacobian at the rotation vector t, p = |t|:
    c = sin p / p, a = (1 - cos p)/p^2, b = (p - sin p)/p^3 and a1 = a'(p)/p, b1 = b'(p)/p
    (all even in p).  Taylor series for p < 2 (16 terms, alternating with terms below 2: exact
    to rounding there), closed forms beyond (where they cancel no more than a digit)."""
    p2 = t[0] * t[0] + t[1] * t[1] + t[2] * t[2]
    if p2 < 4.0:
        # c = sum (-1)^n p^2n / (2n+1)!, a = sum (-1)^n p^2n / (2n+2)!,
        # b = sum (-1)^n p^2n / (2n+3)!, a1 = sum_{n>=1} (-1)^n 2n p^(2n-2) / (2n+2)!,
        # b1 = sum_{n>=1} (-1)^n 2n p^(2n-2) / (2n+3)!
        c = a = b = a1 = b1 = 0.0
        pw = 1.0                     # (-1)^n p^2n
        q = -1.0                     # (-1)^n p^(2n-2), from n = 1 on
        f1 = 1.0                     # (2n+1)!
        for n in range(16):
            f2 = f1 * (2 * n + 2)    # (2n+2)!
            f3 = f2 * (2 * n + 3)    # (2n+3)!
            c += pw / f1
            a += pw / f2
            b += pw / f3
            if n >= 1:
                a1 += 2.0 * n * q / f2
                b1 += 2.0 * n * q / f3
                q = -q * p2
            pw = -pw * p2
            f1 = f3                  # (2(n+1)+1)! = (2n+3)!
    else:
        p = math.sqrt(p2)
        sp, cp = math.sin(p), math.cos(p)
        c = sp / p
        a = (1.0 - cp) / p2
        b = (p - sp) / (p2 * p)
        a1 = (p * sp - 2.0 * (1.0 - cp)) / (p2 * p2)
        b1 = (1.0 - cp) / (p2 * p2) - 3.0 * (p - sp) / (p2 * p2 * p)
    return c, a, b, a1, b1


@numba.njit(cache=True, fastmath=CONTRACT)
def _expm(t):
    """exp(t^), Rodrigues' formula."""
    c, a, _, _, _ = _so3_coefficients(t)
    th = _hat(t)
    e = np.eye(3) + c * th + a * (th @ th)
    return e


@numba.njit(cache=True, fastmath=CONTRACT)
def _left_jacobian(t):
    """J_l(t) = I + a t^ + b t^ t^: exp((t + d)^) = exp((J_l d)^) exp(t^) to first order."""
    _, a, b, _, _ = _so3_coefficients(t)
    th = _hat(t)
    return np.eye(3) + a * th + b * (th @ th)


@numba.njit(cache=True, fastmath=CONTRACT)
def _left_jacobian_derivative(t, u):
    """dJ_l[u] = d/ds J_l(t + s u) at s = 0 = (t.u) (a1 t^ + b1 t^ t^) + a u^ + b (u^ t^ + t^ u^),
    since d p / ds = (t.u) / p and a'(p) dp/ds = a1 (t.u)."""
    _, a, b, a1, b1 = _so3_coefficients(t)
    th = _hat(t)
    uh = _hat(u)
    tu = t[0] * u[0] + t[1] * u[1] + t[2] * u[2]
    return tu * (a1 * th + b1 * (th @ th)) + a * uh + b * (uh @ th + th @ uh)


@numba.njit(cache=True, fastmath=CONTRACT)
def _end_section_rate(t, t_dot, t_ddot):
    """d/dt [J_l(t) t'] = J_l(t) t'' + dJ_l[t'] t' (body frame), for tests and the kernels."""
    return _left_jacobian(t) @ t_ddot + _left_jacobian_derivative(t, t_dot) @ t_dot


# ----------------------------------------------------------------------------------------------
# kinematics, hinge laws, global system
# ----------------------------------------------------------------------------------------------

@numba.njit(cache=True, fastmath=CONTRACT)
def _stiffening_block(my, nm, i):
    """D_i (i = 0, 1, 2; nm x nm, contiguous) of one beam from its shape matrices
    my = [int Y Y^T | D0 | D1 | D2], each block as wide as the widest beam's modes
    (_Problem.shape_mat)."""
    wide = my.shape[1] // 4
    return np.ascontiguousarray(my[:nm, (i + 1) * wide:(i + 1) * wide + nm])


@numba.njit(cache=True, fastmath=CONTRACT)
def _modal_size(bp):
    """A beam's modal coordinates: v and w bending, then the twist, then the stretch."""
    return 2 * int(bp[_BMODES]) + int(bp[_BTWIST]) + int(bp[_BSTRETCH])


@numba.njit(cache=True, fastmath=CONTRACT)
def _beam_end(bp, sv, my, a, w, eta, eta_dot):
    """Output point and output section of one beam (module docstring, "End kinematics"), from
    its frame (A, w), modal coordinates and rates.  Returns rho_O = r_O - r_I, the relative
    velocity v_O - v_I, A_O, w_O, the velocity parts of a_O and alpha_O, B_r = A Phi(L) and
    B_t = A J_l(theta_O) D (3 x 2n each, world).  With geometric stiffening the output point
    moves back by the foreshortening c(L) = 1/2 eta^T D0 eta along e1 (module docstring), so
    B_r gains -A e1 (D0 eta)^T and the velocity terms its rates."""
    nm = int(bp[_BMODES])
    nt, na = int(bp[_BTWIST]), int(bp[_BSTRETCH])
    tw = sv.shape[1] // 3             # the twist's columns of sv (_Problem.shape_vec)
    nb = 2 * nm + nt + na
    u_l = np.zeros(3)                 # u(L), body frame
    ud_l = np.zeros(3)                # u'(L) (time derivative)
    th = np.zeros(3)                  # theta_O = [psi(L), -w'(L), v'(L)]
    thd = np.zeros(3)
    for j in range(nt):
        th[0] += sv[_YL, tw + j] * eta[2 * nm + j]
        thd[0] += sv[_YL, tw + j] * eta_dot[2 * nm + j]
    for j in range(na):               # the stretch u_x(L)
        u_l[0] += sv[_YL, 2 * tw + j] * eta[2 * nm + nt + j]
        ud_l[0] += sv[_YL, 2 * tw + j] * eta_dot[2 * nm + nt + j]
    for j in range(nm):
        yl, dyl = sv[_YL, j], sv[_DYL, j]
        u_l[1] += yl * eta[j]
        u_l[2] += yl * eta[nm + j]
        ud_l[1] += yl * eta_dot[j]
        ud_l[2] += yl * eta_dot[nm + j]
        th[1] -= dyl * eta[nm + j]
        th[2] += dyl * eta[j]
        thd[1] -= dyl * eta_dot[nm + j]
        thd[2] += dyl * eta_dot[j]
    p_l = u_l.copy()
    p_l[0] += bp[_BL]
    d0_eta = np.zeros(2 * nm)         # D0 eta per plane (the foreshortening's slopes)
    cdd_v = 0.0                       # eta'^T D0 eta': the velocity part of c''(L)
    if bp[_BSTIFF] != 0.0:
        d0 = _stiffening_block(my, nm, 0)
        for plane in range(2):
            e = np.ascontiguousarray(eta[plane * nm:(plane + 1) * nm])
            ed = np.ascontiguousarray(eta_dot[plane * nm:(plane + 1) * nm])
            de = d0 @ e
            d0_eta[plane * nm:(plane + 1) * nm] = de
            p_l[0] -= 0.5 * (e @ de)
            ud_l[0] -= ed @ de
            cdd_v += ed @ (d0 @ ed)
    rho = a @ p_l
    aud = a @ ud_l
    v_rel = _cross(w, rho) + aud
    jl = _left_jacobian(th)
    rot_o = a @ _expm(th)
    ajt = a @ (jl @ thd)
    w_o = w + ajt
    acc_v = _cross(w, _cross(w, rho)) + 2.0 * _cross(w, aud) - cdd_v * a[:, 0]
    alpha_v = _cross(w, ajt) + a @ (_left_jacobian_derivative(th, thd) @ thd)
    br = np.zeros((3, nb))
    d = np.zeros((3, nb))
    for j in range(nt):
        d[0, 2 * nm + j] = sv[_YL, tw + j]
    for j in range(na):
        br[0, 2 * nm + nt + j] = sv[_YL, 2 * tw + j]
    for j in range(nm):
        br[1, j] = sv[_YL, j]
        br[2, nm + j] = sv[_YL, j]
        br[0, j] = -d0_eta[j]
        br[0, nm + j] = -d0_eta[nm + j]
        d[2, j] = sv[_DYL, j]
        d[1, nm + j] = -sv[_DYL, j]
    br = a @ br
    bt = a @ (jl @ d)
    return rho, v_rel, rot_o, w_o, acc_v, alpha_v, br, bt


@numba.njit(cache=True, fastmath=CONTRACT)
def _rot_about(n, q):
    """Rot(n, q) = exp(q n^) for a unit axis n (Rodrigues)."""
    k = _hat(n)
    return np.eye(3) + math.sin(q) * k + (1.0 - math.cos(q)) * (k @ k)


@numba.njit(cache=True, fastmath=CONTRACT)
def _joint_coordinates(y, joints, k, kind):
    """(q, q') of joint k, each padded to 2 entries (module docstring, "Joints with
    coordinates"; joints = (c_off, c0, n_coord, ...): the coordinates at y[c0 + c_off[k] + i],
    their rates at y[c0 + n_coord + c_off[k] + i])."""
    c_off, c0, n_coord = joints[0], joints[1], joints[2]
    q = np.zeros(2)
    qd = np.zeros(2)
    o = c_off[k]
    for i in range(2 if kind == _UNIVERSAL else 1):
        q[i] = y[c0 + o + i]
        qd[i] = y[c0 + n_coord + o + i]
    return q, qd


@numba.njit(cache=True, fastmath=CONTRACT)
def _joint_frame(kind, h, a_in, w_in, q, qd):
    """Child frame behind a joint with coordinates (module docstring): its rotation A, angular
    velocity w and, for a slide, the offset d = A_P n q of its input point from the attachment
    point and its rate d' = w_P x d + A_P n q' (zero for revolute and universal joints)."""
    n1 = _vec3(h, _AX1)
    r0 = _mat3(h, _R0)
    d = np.zeros(3)
    d_rate = np.zeros(3)
    if kind == _REVOLUTE:                   # A = A_P Rot(n, q) R0,  w = w_P + (A_P n) q'
        rot = a_in @ _rot_about(n1, q[0]) @ r0
        w = w_in + (a_in @ n1) * qd[0]
    elif kind == _UNIVERSAL:                # A = A_P Rot(n1, q1) R0 Rot(n2, q2),
        n2 = _vec3(h, _AX2)                 # w = w_P + (A_P n1) q1' + (A n2) q2'
        rot = a_in @ _rot_about(n1, q[0]) @ r0 @ _rot_about(n2, q[1])
        w = w_in + (a_in @ n1) * qd[0] + (rot @ n2) * qd[1]
    else:                                   # prismatic: A = A_P R0, w = w_P, d = (A_P n) q
        rot = a_in @ r0
        w = w_in.copy()
        u = a_in @ n1
        d = u * q[0]
        d_rate = _cross(w_in, d) + u * qd[0]
    return rot, w, d, d_rate


@numba.njit(cache=True, fastmath=CONTRACT)
def _joint_directions(kind, h, a_in, rot):
    """World directions s_i (columns, 3 x 2) of a joint's coordinates: the rotation axes u = A_P n
    (revolute), u1 = A_P n1 and v2 = A n2 (universal), the slide direction u = A_P n
    (prismatic); and the number of coordinates."""
    s = np.zeros((3, 2))
    s[:, 0] = a_in @ _vec3(h, _AX1)
    if kind == _UNIVERSAL:
        s[:, 1] = rot @ _vec3(h, _AX2)
        return s, 2
    return s, 1


@numba.njit(cache=True, fastmath=CONTRACT)
def _joint_velocity_terms(kind, dirs, w_in, w, d, qd):
    """Velocity parts of a joint's constraint rows (module docstring): of the child's angular
    acceleration, (w_P x u) q' (revolute), (w_P x u1) q1' + (w x v2) q2' (universal), 0
    (prismatic); of its input point's acceleration relative to the attachment point's,
    w_P x (w_P x d) + 2 w_P x u q' (prismatic), 0 otherwise."""
    rot_v = np.zeros(3)
    slide_v = np.zeros(3)
    u = np.ascontiguousarray(dirs[:, 0])
    if kind == _PRISMATIC:
        slide_v = _cross(w_in, _cross(w_in, d)) + 2.0 * qd[0] * _cross(w_in, u)
    else:
        rot_v = qd[0] * _cross(w_in, u)
        if kind == _UNIVERSAL:
            rot_v = rot_v + qd[1] * _cross(w, np.ascontiguousarray(dirs[:, 1]))
    return rot_v, slide_v


@numba.njit(cache=True, fastmath=CONTRACT)
def _kinematics(y, body_params, hinge_kind, hinge_params, body_kind, beam_params, shape_vec,
                shape_mat, q_off, w_off, d_off, m_off, e0, n_modal, r_g, v_g, rot_g, w_g, topology,
                attachment_point, joints):
    """Rotations, angular velocities, input-point positions / velocities and the elastic
    deflections and slides (world) of every body, from the state and the ground motion (a
    prismatic joint's offset d = A_P n q and its rate take the deflection's place); and each body's
    output point and section: rho_O = r_O - r_I, A_O, w_O, the velocity parts of a_O and
    alpha_O, (beams) B_r, B_t padded to the widest beam's 2n columns, and v_O.  Also, per body k
    with a parent P, where its hinge attaches (module docstring, "Attachment points"):
    rho_att[k] = r_att,k - r_in,P (A_P x_k on a rigid parent, x_k = attachment_point[k] in its
    frame; a beam parent's rho_O) and acc_v_att[k], the velocity part of a_att,k (w_P x (w_P x
    rho_att,k) on a rigid parent, the beam's a_O velocity part); zero rows for the roots."""
    n = body_params.shape[0]
    n2max = 2 * shape_vec.shape[2]
    rot = np.empty((n, 3, 3))
    omega = np.empty((n, 3))
    r_in = np.empty((n, 3))
    v_in = np.empty((n, 3))
    defl = np.zeros((n, 3))
    defl_rate = np.zeros((n, 3))
    rho_o = np.empty((n, 3))
    v_o = np.empty((n, 3))
    rot_o = np.empty((n, 3, 3))
    omega_o = np.empty((n, 3))
    acc_v = np.empty((n, 3))
    alpha_v = np.zeros((n, 3))
    b_r = np.zeros((n, 3, n2max))
    b_t = np.zeros((n, 3, n2max))
    rho_att = np.zeros((n, 3))
    acc_v_att = np.zeros((n, 3))
    parent = topology[0]
    for k in range(n):           # parents first (Model.parent[k] < k)
        kp = parent[k]
        if kp < 0:               # the ground point
            r_prev, v_prev = r_g, v_g
        elif body_kind[kp] == _BEAM:     # a beam's one attachment point: its output point
            rho_att[k] = rho_o[kp]
            acc_v_att[k] = acc_v[kp]
            r_prev, v_prev = r_in[kp] + rho_o[kp], v_o[kp]
        else:
            # a rigid parent's attachment point x_k (its output point l_IO or a named point):
            # r_att = r_in,P + A_P x_k,  v_att = v_in,P + w_P x rho_att,
            # a_att = a_P + alpha_P x rho_att + w_P x (w_P x rho_att)
            arm = rot[kp] @ attachment_point[k]
            v_arm = _cross(omega[kp], arm)
            rho_att[k] = arm
            acc_v_att[k] = _cross(omega[kp], v_arm)
            r_prev, v_prev = r_in[kp] + arm, v_in[kp] + v_arm
        # the inboard frame: the parent's output section (a rigid parent's own frame, A_O = A,
        # w_O = w, whichever of its points the hinge is at; a beam's end section), or the ground
        if hinge_kind[k] == FIXED:   # welded to the inboard frame
            a_in = rot_g if kp < 0 else rot_o[kp]
            w_in = w_g if kp < 0 else omega_o[kp]
            rot[k] = a_in @ _mat3(hinge_params[k], _R0)
            omega[k] = w_in
        elif joints[0][k] >= 0:      # a joint with coordinates, on the inboard frame
            a_in = rot_g if kp < 0 else rot_o[kp]
            w_in = w_g if kp < 0 else omega_o[kp]
            q, qd = _joint_coordinates(y, joints, k, hinge_kind[k])
            rot[k], omega[k], defl[k], defl_rate[k] = _joint_frame(
                hinge_kind[k], hinge_params[k], a_in, w_in, q, qd)
        else:
            rot[k] = _quat_to_rot(y[q_off[k]:q_off[k] + 4])
            omega[k] = y[w_off[k]:w_off[k] + 3]
        if hinge_kind[k] == ELASTIC:
            defl[k] = y[d_off[k]:d_off[k] + 3]
            defl_rate[k] = y[d_off[k] + 3:d_off[k] + 6]
        r_in[k] = r_prev + defl[k]
        v_in[k] = v_prev + defl_rate[k]
        if body_kind[k] == _BEAM:
            nm2 = _modal_size(beam_params[k])
            o = m_off[k]
            rho, v_rel, ro, wo, av, alv, br, bt = _beam_end(
                beam_params[k], shape_vec[k], shape_mat[k], rot[k], omega[k],
                y[e0 + o:e0 + o + nm2],
                y[e0 + n_modal + o:e0 + n_modal + o + nm2])
            rho_o[k], rot_o[k], omega_o[k], acc_v[k], alpha_v[k] = rho, ro, wo, av, alv
            b_r[k, :, :nm2] = br
            b_t[k, :, :nm2] = bt
        else:
            rho = rot[k] @ _vec3(body_params[k], _LIO)
            v_rel = _cross(omega[k], rho)
            rho_o[k], rot_o[k], omega_o[k] = rho, rot[k], omega[k]
            acc_v[k] = _cross(omega[k], v_rel)
        v_o[k] = v_in[k] + v_rel
    return (rot, omega, r_in, v_in, defl, defl_rate, rho_o, rot_o, omega_o, acc_v, alpha_v,
            b_r, b_t, v_o, rho_att, acc_v_att)


@numba.njit(cache=True, fastmath=CONTRACT)
def _elastic_loads(rot, omega, rot_o, omega_o, defl, defl_rate, hinge_kind, hinge_params, rot_g,
                   w_g, parent):
    """Force q and couple m every elastic hinge exerts on its outboard body (world; zero rows for
    the other hinges).  The hinge's inboard frame is the inboard body's output section (A_O,
    w_O): the body itself for a rigid body, the deflected end section for a beam."""
    n = rot.shape[0]
    q = np.zeros((n, 3))
    m = np.zeros((n, 3))
    for k in range(n):
        if hinge_kind[k] != ELASTIC:
            continue
        h = hinge_params[k]
        a_in = rot_g if parent[k] < 0 else rot_o[parent[k]]
        w_in = w_g if parent[k] < 0 else omega_o[parent[k]]
        d_b = a_in.T @ defl[k]
        dd_b = a_in.T @ defl_rate[k]
        q[k] = -(a_in @ (_mat3(h, _KT) @ d_b + _mat3(h, _CT) @ dd_b))
        psi = _log_rot(a_in.T @ rot[k] @ _mat3(h, _R0).T)
        w_rel_b = a_in.T @ (omega[k] - w_in)
        m[k] = -(a_in @ (_mat3(h, _KR) @ psi + _mat3(h, _CR) @ w_rel_b))
    return q, m




@numba.njit(cache=True, fastmath=CONTRACT)
def _beam_terms(bp, sv, my, eta, eta_dot, a, w, gravity):
    """World-frame mass properties, coupling blocks and velocity terms of one beam at its
    current (eta, eta'), from the shape integrals sv (int Y, int x Y, ...) and my = int Y Y^T
    (module docstring).

    Returns mass, h = A s (first moment about I), J = A (J_b + J_p) A^T, AP = A P and AG = A G
    (3 x 2n), the velocity terms of the Newton and Euler rows (right-hand side), the modal
    equations' right-hand side (gravity, velocity, damping and stiffness terms) and the modal
    mass matrix of one plane, mu int Y Y^T (n x n)."""
    length = bp[_BL]
    mu = bp[_BMU]
    nm = int(bp[_BMODES])
    nt, na = int(bp[_BTWIST]), int(bp[_BSTRETCH])
    tw = sv.shape[1] // 3             # the twist's columns of sv (_Problem.shape_vec)
    n2 = 2 * nm
    nb = n2 + nt + na
    sa = n2 + nt                      # the stretch's first coordinate
    # the stretch xi (module docstring, "Stretch"): int U_j, int x U_j, int U_j^2 and the
    # products int U_j Y_l, M_av (na x nm); p = (x + U . xi, v, w)
    pa = np.ascontiguousarray(sv[_SY, 2 * tw:2 * tw + na])
    xa = np.ascontiguousarray(sv[_TY, 2 * tw:2 * tw + na])
    maa = np.ascontiguousarray(sv[_MF, 2 * tw:2 * tw + na])
    mav = np.ascontiguousarray(sv[N_SHAPE_ROWS:N_SHAPE_ROWS + nm, 2 * tw:2 * tw + na].T)
    xi = np.ascontiguousarray(eta[sa:nb])
    xid = np.ascontiguousarray(eta_dot[sa:nb])
    mva_xi = mav.T @ xi                # int Y_l u_x, int Y_l u_x' (per bending mode)
    mva_xid = mav.T @ xid
    sy = sv[_SY, :nm]
    ty = sv[_TY, :nm]
    myy = np.ascontiguousarray(my[:nm, :nm])
    ev = np.ascontiguousarray(eta[:nm])
    ew = np.ascontiguousarray(eta[nm:n2])
    dv = np.ascontiguousarray(eta_dot[:nm])
    dw = np.ascontiguousarray(eta_dot[nm:n2])
    mev = myy @ ev                                 # int Y v, int Y w, int Y v', int Y w'
    mew = myy @ ew
    mdv = myy @ dv
    mdw = myy @ dw
    mass = mu * length
    # the foreshortening -c(x) e1 to first order in c (module docstring, "Geometric
    # stiffening"): C1 = int c, C2 = int x c = 1/2 eta^T (D1, D2) eta, their rates, and
    # eta'^T D1 eta' (the velocity part of C1'')
    geo = np.zeros((3, nb))           # D0 eta, D1 eta, D2 eta per plane (none for the twist)
    c1 = c1_dot = c2 = c2_dot = c1_vel = 0.0
    if bp[_BSTIFF] != 0.0:
        for i in range(3):
            d = _stiffening_block(my, nm, i)
            geo[i, :nm] = d @ ev
            geo[i, nm:n2] = d @ ew
        d1 = _stiffening_block(my, nm, 1)
        c1 = 0.5 * (ev @ geo[1, :nm] + ew @ geo[1, nm:n2])
        c1_dot = dv @ geo[1, :nm] + dw @ geo[1, nm:n2]
        c1_vel = dv @ (d1 @ dv) + dw @ (d1 @ dw)
        c2 = 0.5 * (ev @ geo[2, :nm] + ew @ geo[2, nm:n2])
        c2_dot = dv @ geo[2, :nm] + dw @ geo[2, nm:n2]
    s_b = np.empty(3)
    s_b[0] = mu * (length * length / 2.0 - c1 + pa @ xi)
    s_b[1] = mu * (sy @ ev)
    s_b[2] = mu * (sy @ ew)
    q = np.empty((3, 3))                           # int mu p p^T
    q[0, 0] = mu * (length ** 3 / 3.0 - 2.0 * c2 + 2.0 * (xa @ xi) + xi @ (maa * xi))
    q[0, 1] = q[1, 0] = mu * (ty @ ev + mva_xi @ ev)
    q[0, 2] = q[2, 0] = mu * (ty @ ew + mva_xi @ ew)
    q[1, 1] = mu * (ev @ mev)
    q[1, 2] = q[2, 1] = mu * (ev @ mew)
    q[2, 2] = mu * (ew @ mew)
    tr = q[0, 0] + q[1, 1] + q[2, 2]
    j_b = -q
    for i in range(3):
        j_b[i, i] += tr
    j_b[0, 0] += bp[_BJP] * length                 # polar spin inertia J_p = diag(j_p L, 0, 0)
    p_b = np.zeros((3, nb))                        # int mu Phi
    g_b = np.zeros((3, nb))                        # int mu p^ Phi; the twist's j_p int Psi e1
    p_t = 0.0                                      # j_p int psi' (the twist's spin momentum)
    for j in range(nt):
        g_b[0, n2 + j] = bp[_BJP] * sv[_SY, tw + j]
        p_t += bp[_BJP] * sv[_SY, tw + j] * eta_dot[n2 + j]
    for j in range(nm):
        p_b[1, j] = mu * sy[j]
        p_b[2, nm + j] = mu * sy[j]
        g_b[2, j] = mu * (ty[j] + mva_xi[j])       # p x (Y_j e2) = Y_j (-w, 0, x + u_x)
        g_b[0, j] = -mu * mew[j]
        g_b[1, nm + j] = -mu * (ty[j] + mva_xi[j])  # p x (Y_j e3) = Y_j (v, -(x + u_x), 0)
        g_b[0, nm + j] = mu * mev[j]
    mav_v, mav_w = mav @ ev, mav @ ew              # int U_j v, int U_j w
    mav_dv, mav_dw = mav @ dv, mav @ dw
    for j in range(na):
        p_b[0, sa + j] = mu * pa[j]
        g_b[1, sa + j] = mu * mav_w[j]             # p x (U_j e1) = U_j (0, w, -v)
        g_b[2, sa + j] = -mu * mav_v[j]
    c = np.zeros((3, 3))                           # int mu p' p^T
    c[0, 0] = mu * (-c2_dot + xa @ xid + xid @ (maa * xi))
    c[0, 1] = mu * (xid @ mav_v)
    c[0, 2] = mu * (xid @ mav_w)
    c[1, 0] = mu * (ty @ dv + mva_xi @ dv)
    c[2, 0] = mu * (ty @ dw + mva_xi @ dw)
    c[1, 1] = mu * (dv @ mev)
    c[1, 2] = mu * (dv @ mew)
    c[2, 1] = mu * (dw @ mev)
    c[2, 2] = mu * (dw @ mew)
    w_b = a.T @ w
    trc = c[0, 0] + c[1, 1] + c[2, 2]
    cor_b = 2.0 * (trc * w_b - c @ w_b)            # int mu p x (2 w x u')
    ap = a @ p_b
    ag = a @ g_b
    h = a @ s_b
    j_w = a @ j_b @ a.T
    e1 = np.ascontiguousarray(a[:, 0])
    ud = ap @ eta_dot - mu * c1_dot * e1           # A int mu p' dx
    # the velocity terms; A int mu p'' = A P eta'' - mu (eta'^T D1 eta' + (D1 eta)^T eta'') e1
    newton_v = -2.0 * _cross(w, ud) + mu * c1_vel * e1
    euler_v = -(a @ cor_b) - p_t * _cross(w, e1)  # and the twist's spin momentum turning
    # modal right-hand side
    ww2 = w_b[0] * w_b[0] + w_b[1] * w_b[1] + w_b[2] * w_b[2]
    mm = np.outer(w_b, w_b)                        # w^ w^ = w w^T - |w|^2 E
    for i in range(3):
        mm[i, i] -= ww2
    g_w = ap.T @ gravity                           # (A P)^T g
    modal = np.empty(nb)
    for j in range(nt):                            # the twist: -c psi' - k psi
        m_t = bp[_BJP] * sv[_MF, tw + j]
        k_t = bp[_BGJ] * sv[_KF, tw + j]
        modal[n2 + j] = (-2.0 * bp[_BZETA] * math.sqrt(k_t / m_t) * m_t * eta_dot[n2 + j]
                         - k_t * eta[n2 + j])
    for j in range(nm):
        m_k = mu * sv[_MF, j]
        kv = bp[_BEIV] * sv[_KF, j]
        kw = bp[_BEIW] * sv[_KF, j]
        cv = 2.0 * bp[_BZETA] * math.sqrt(kv / m_k) * m_k
        cw = 2.0 * bp[_BZETA] * math.sqrt(kw / m_k) * m_k
        x_j = ty[j] + mva_xi[j]                   # int Y_j (x + u_x)
        cent_v = mu * (x_j * mm[1, 0] + mm[1, 1] * mev[j] + mm[1, 2] * mew[j])
        cent_w = mu * (x_j * mm[2, 0] + mm[2, 1] * mev[j] + mm[2, 2] * mew[j])
        # 2 int mu Y_j e2 . (w_b x u'), u' = (u_x', v', w')
        cori_v = 2.0 * mu * (w_b[2] * mva_xid[j] - w_b[0] * mdw[j])
        cori_w = 2.0 * mu * (w_b[0] * mdv[j] - w_b[1] * mva_xid[j])
        modal[j] = g_w[j] - cent_v - cori_v - cv * dv[j] - kv * ev[j]
        modal[nm + j] = g_w[nm + j] - cent_w - cori_w - cw * dw[j] - kw * ew[j]
    for j in range(na):                            # the stretch: e1 . int mu U_j (...)
        m_a = mu * maa[j]
        k_a = bp[_BEA] * sv[_KF, 2 * tw + j]
        cent_a = mu * ((xa[j] + maa[j] * xi[j]) * mm[0, 0] + mm[0, 1] * mav_v[j]
                       + mm[0, 2] * mav_w[j])
        cori_a = 2.0 * mu * (w_b[1] * mav_dw[j] - w_b[2] * mav_dv[j])
        modal[sa + j] = (g_w[sa + j] - cent_a - cori_a
                         - 2.0 * bp[_BZETA] * math.sqrt(k_a * m_a) * xid[j] - k_a * xi[j])
    # geometric stiffening: + mu e1.(g - a_I) D1 eta + mu (w_y^2 + w_z^2) D2 eta on the left
    # (module docstring; N_L D0 eta is the end force's work through B_r); the a_I term goes to
    # the matrix (_assemble, with geo), the rest here
    if bp[_BSTIFF] != 0.0:
        known = mu * (e1 @ gravity) * geo[1] + mu * (w_b[1] ** 2 + w_b[2] ** 2) * geo[2]
        for j in range(n2):
            modal[j] -= known[j]
    return mass, h, j_w, ap, ag, newton_v, euler_v, modal, mu * myy, geo


@numba.njit(cache=True, fastmath=CONTRACT)
def _joint_rows(s, b, k, kind, h, kp, a_in, w_in, alpha_in, rot, w, d, qd, b_t_in, pce, f_col,
                m_col, joints):
    """Joint k's share of the global system (module docstring, "Joints with coordinates"), on
    top of the weld's rows that _assemble wrote (a_k = a_O,P, alpha_k = alpha_O,P): each
    coordinate's -s_i q_i'' in the rotation rows (revolute, universal) or the translation rows
    (slide), the velocity terms, the slide's alpha_P x d, and the coordinate rows
        s_i . N_k (or F_k) = tau_i     (a free coordinate: the drive's generalized force)
        q_i'' = q_p''(t)               (a prescribed coordinate),
    both from joints[5] (drive_value).  (a_in, w_in): the parent's output section or the ground
    frame (kp < 0); alpha_in: the velocity part of the parent's alpha_O (the ground's angular
    acceleration for kp < 0); b_t_in, pce: the parent beam's B_t and first modal column."""
    c_off, c_col0, prescribed, drive_value = joints[0], joints[3], joints[4], joints[5]
    dirs, nc = _joint_directions(kind, h, a_in, rot)
    rot_v, slide_v = _joint_velocity_terms(kind, dirs, w_in, w, d, qd)
    rf, rm = f_col[k], m_col[k]
    rs = rf if kind == _PRISMATIC else rm       # the rows (and reaction) a coordinate moves
    for i in range(nc):
        c = c_off[k] + i
        cq = c_col0 + c
        for j in range(3):
            s[rs + j, cq] = -dirs[j, i]
        if prescribed[c]:
            s[cq, cq] = 1.0
        else:
            for j in range(3):
                s[cq, rs + j] = dirs[j, i]
        b[cq] = drive_value[c]
    for j in range(3):
        b[rm + j] += rot_v[j]
        b[rf + j] += slide_v[j]
    if kind == _PRISMATIC:
        # a_k - ... - alpha_O,P x d = ...: on the left d^ alpha_O,P, with alpha_O,P =
        # alpha_P + B_t eta''_P + alpha_in; alpha_in x d on the right
        hd = _hat(d)
        b_v = _cross(alpha_in, d)
        for i in range(3):
            b[rf + i] += b_v[i]
        if kp >= 0:
            hdb = hd @ b_t_in
            for i in range(3):
                for j in range(3):
                    s[rf + i, 6 * kp + 3 + j] += hd[i, j]
                for j in range(hdb.shape[1]):
                    s[rf + i, pce + j] += hdb[i, j]


@numba.njit(cache=True, fastmath=CONTRACT)
def _assemble(y, rot, omega, defl, rho_o, rot_o, omega_o, acc_v, alpha_v, b_r, b_t, rho_att,
              acc_v_att, q_el, m_el, body_params, hinge_kind, hinge_params, body_kind,
              beam_params, shape_vec, shape_mat, m_off, e0, n_modal, e_col0, f_col, m_col, loops,
              n_unknowns, gravity, a_g, rot_g, w_g, wd_g, forces, torques, line_loads, topology,
              joints):
    """The global Newton-Euler system  S x = b  for x = [a_0, alpha_0, ..., a_{n-1},
    alpha_{n-1}, reactions, modal accelerations].  Column f_col[k] (m_col[k]) holds the reaction
    force (couple) of hinge k, or -1 when the hinge has none; the matching constraint equation
    uses the same row index, so S is square.  Beam k's modal accelerations sit in the columns
    e_col0 + m_off[k] + (0..2n-1), its modal equations in the same rows; its coordinates and
    rates are y[e0 + m_off[k] + ...] and y[e0 + n_modal + m_off[k] + ...].  A joint with
    coordinates has both reaction columns and its coordinates' accelerations in the columns
    joints[3] + c_off[k] + (0, 1), its coordinate rows in the same rows (_joint_rows).  Hinge k
    attaches at rho_att[k] from its parent's input point, with the velocity part acc_v_att[k] of
    that point's acceleration (_kinematics; module docstring, "Attachment points")."""
    n = rot.shape[0]
    parent, child_start, child_list = topology
    s = np.zeros((n_unknowns, n_unknowns))
    b = np.zeros(n_unknowns)
    for k in range(n):
        p = body_params[k]
        a = rot[k]
        w = omega[k]
        rn, re = 6 * k, 6 * k + 3          # Newton rows, Euler rows
        ca, cal = 6 * k, 6 * k + 3         # a_k, alpha_k columns
        nm2 = 0
        ce = -1
        geo = np.zeros((3, 0))
        if body_kind[k] == _BEAM:
            nm = int(beam_params[k, _BMODES])
            nm2 = _modal_size(beam_params[k])
            o = m_off[k]
            eta = y[e0 + o:e0 + o + nm2]
            eta_dot = y[e0 + n_modal + o:e0 + n_modal + o + nm2]
            # a distributed load p per length acts as gravity does: g + p / mu on this beam;
            # loads in body axes (followers) turn with the end section (F, T) and the frame (p)
            f_k, t_k, p_k = forces[k], torques[k], line_loads[k]
            if beam_params[k, _BAXES] != 0.0:
                f_k, t_k, p_k = rot_o[k] @ f_k, rot_o[k] @ t_k, a @ p_k
            g_k = gravity + p_k / beam_params[k, _BMU]
            mass, h, j_w, ap, ag, newton_v, euler_v, modal, m_yy, geo = _beam_terms(
                beam_params[k], shape_vec[k], shape_mat[k], eta, eta_dot, a, w, g_k)
            # an applied end force F and torque T (docs/beam.md, "Loads on the beam") act at
            # the output point and on the end section: F in Newton, rho_O x F + T about I,
            # and their generalized forces B_r^T F + B_t^T T in the modal rows (below)
            weight = mass * g_k + f_k
            bn = weight - _cross(w, _cross(w, h)) + newton_v
            be = (-_cross(w, j_w @ w) + _cross(h, g_k) + euler_v + t_k + _cross(rho_o[k], f_k))
            ce = e_col0 + o
            for j in range(nm2):
                for i in range(3):
                    # translation: + A P eta'' (and the foreshortening's -mu A e1 (D1 eta)^T)
                    s[rn + i, ce + j] = ap[i, j] - beam_params[k, _BMU] * a[i, 0] * geo[1, j]
                    s[re + i, ce + j] = ag[i, j]      # rotation:    + A G eta''
                    s[ce + j, ca + i] = ap[i, j]      # modal:  (A P)^T a + (A G)^T alpha
                    s[ce + j, cal + i] = ag[i, j]
                b[ce + j] = modal[j]
                for i in range(3):
                    b[ce + j] += b_r[k, i, j] * f_k[i] + b_t[k, i, j] * t_k[i]
            for j in range(nm):                       # modal mass, one block per plane
                for i in range(nm):
                    s[ce + j, ce + i] = m_yy[j, i]
                    s[ce + nm + j, ce + nm + i] = m_yy[j, i]
            tw = shape_vec.shape[2] // 3
            nt = int(beam_params[k, _BTWIST])
            for j in range(2 * nm, 2 * nm + nt):      # the twist's, j_p int Psi_j^2
                s[ce + j, ce + j] = beam_params[k, _BJP] * shape_vec[k, _MF, tw + j - 2 * nm]
            for j in range(2 * nm + nt, nm2):         # the stretch's, mu int U_j^2
                s[ce + j, ce + j] = (beam_params[k, _BMU]
                                     * shape_vec[k, _MF, 2 * tw + j - 2 * nm - nt])
            for j in range(nm2):                      # geometric stiffening: -mu e1 . a_I
                for i in range(3):
                    s[ce + j, ca + i] -= beam_params[k, _BMU] * a[i, 0] * geo[1, j]
        else:
            mass = p[_MASS]
            rho_c = a @ _vec3(p, _LIC)
            h = mass * rho_c
            j_w = a @ _mat3(p, _JI) @ a.T
            weight = mass * gravity + forces[k]
            # Newton: M a - hat(h) alpha - F_k + F_{k+1} = M g + f - w x (w x h) + q_k - q_{k+1}
            bn = weight - _cross(w, _cross(w, h))
            # Euler about I: J alpha + hat(h) a - N_k + sum_c [N_c + hat(rho_att,c + d_c) F_c]
            #     = -w x J w + rho_c x (M g + f) + tau + m_k - sum_c [m_c + (rho_att,c + d_c) x q_c]
            # over the children c (rho_att,c = rho_o for a chain's output point)
            be = -_cross(w, j_w @ w) + _cross(rho_c, weight) + torques[k]
        hc = _hat(h)
        for i in range(3):
            s[rn + i, ca + i] = mass
            for j in range(3):
                s[rn + i, cal + j] = -hc[i, j]
                s[re + i, cal + j] = j_w[i, j]
                s[re + i, ca + j] = hc[i, j]
        # the inboard hinge acting on body k
        if hinge_kind[k] == ELASTIC:
            bn += q_el[k]
            be += m_el[k]
        else:
            c = f_col[k]
            for i in range(3):
                s[rn + i, c + i] = -1.0
            if m_col[k] >= 0:              # a fixed hinge or a joint with coordinates
                c = m_col[k]
                for i in range(3):
                    s[re + i, c + i] = -1.0
        # each outboard hinge c (joining a child c at its attachment point r_att,c: a beam's
        # output point, any point of a rigid body) acting on body k: force -F_c at
        # r_att,c + d_c, couple -N_c; a beam's modal rows get their generalized forces
        # B_r^T F_c + B_t^T (N_c + d_c x F_c) (d_c: an elastic hinge's deflection or a slide,
        # zero otherwise)
        for ci in range(child_start[k], child_start[k + 1]):
            kc = child_list[ci]
            arm = rho_att[kc] + defl[kc]
            if hinge_kind[kc] == ELASTIC:
                # -q at r_att and the couple -m_in = -(m_out + d x q) about r_att; on a beam
                # their generalized forces -(B_r^T q + B_t^T m_in), as a weld's reactions'
                bn -= q_el[kc]
                be -= m_el[kc] + _cross(arm, q_el[kc])
                m_in = m_el[kc] + _cross(defl[kc], q_el[kc])
                for j in range(nm2):
                    gen = 0.0
                    for i in range(3):
                        gen += b_r[k, i, j] * q_el[kc, i] + b_t[k, i, j] * m_in[i]
                    b[ce + j] -= gen
            else:
                c = f_col[kc]
                ha = _hat(arm)
                for i in range(3):
                    s[rn + i, c + i] = 1.0
                    for j in range(3):
                        s[re + i, c + j] = ha[i, j]
                    for j in range(nm2):
                        s[ce + j, c + i] = b_r[k, i, j]
                if hinge_kind[kc] == _PRISMATIC and nm2 > 0:
                    # B_t^T (d x F) = B_t^T d^ F: column i gets -(d^ B_t)[i, :]
                    hdb = _hat(defl[kc]) @ np.ascontiguousarray(b_t[k, :, :nm2])
                    for i in range(3):
                        for j in range(nm2):
                            s[ce + j, c + i] -= hdb[i, j]
                if m_col[kc] >= 0:
                    c = m_col[kc]
                    for i in range(3):
                        s[re + i, c + i] = 1.0
                        for j in range(nm2):
                            s[ce + j, c + i] = b_t[k, i, j]
        for i in range(3):
            b[rn + i] = bn[i]
            b[re + i] = be[i]
        # constraint rows of the inboard hinge (acceleration level), P = parent[k]:
        #     a_k = a_att,k = a_P + alpha_P x rho_att,k + B_r eta''_P + acc_v_att,k,
        #     alpha_k = alpha_O,P (fixed hinge)
        if hinge_kind[k] != ELASTIC:
            r = f_col[k]
            for i in range(3):
                s[r + i, ca + i] = 1.0
            if parent[k] < 0:
                for i in range(3):
                    b[r + i] = a_g[i]
            else:
                kp = parent[k]
                hpo = _hat(rho_att[k])
                pn2 = _modal_size(beam_params[kp]) if body_kind[kp] == _BEAM else 0
                pce = e_col0 + m_off[kp]
                for i in range(3):
                    s[r + i, 6 * kp + i] = -1.0
                    for j in range(3):
                        s[r + i, 6 * kp + 3 + j] = hpo[i, j]
                    for j in range(pn2):
                        s[r + i, pce + j] = -b_r[kp, i, j]
                    b[r + i] = acc_v_att[k, i]
            if m_col[k] >= 0:
                r = m_col[k]
                for i in range(3):
                    s[r + i, cal + i] = 1.0
                    if parent[k] < 0:
                        b[r + i] = wd_g[i]
                    else:
                        kp = parent[k]
                        pn2 = _modal_size(beam_params[kp]) if body_kind[kp] == _BEAM else 0
                        pce = e_col0 + m_off[kp]
                        s[r + i, 6 * kp + 3 + i] = -1.0
                        for j in range(pn2):
                            s[r + i, pce + j] = -b_t[kp, i, j]
                        b[r + i] = alpha_v[kp, i]
            if joints[0][k] >= 0:
                kp = parent[k]
                _, qd = _joint_coordinates(y, joints, k, hinge_kind[k])
                if kp < 0:
                    _joint_rows(s, b, k, hinge_kind[k], hinge_params[k], kp, rot_g, w_g, wd_g,
                                rot[k], omega[k], defl[k], qd, np.zeros((3, 0)), 0, f_col,
                                m_col, joints)
                else:
                    pn2 = _modal_size(beam_params[kp]) if body_kind[kp] == _BEAM else 0
                    _joint_rows(s, b, k, hinge_kind[k], hinge_params[k], kp, rot_o[kp],
                                omega_o[kp], alpha_v[kp], rot[k], omega[k], defl[k], qd,
                                np.ascontiguousarray(b_t[kp, :, :pn2]), e_col0 + m_off[kp],
                                f_col, m_col, joints)
    return s, b


@numba.njit(cache=True, fastmath=CONTRACT)
def _closure_side(k, local, on_end, rot, omega, r_in, v_in, rho_o, rot_o, omega_o, v_o, acc_v,
                  alpha_v, r_g, v_g, a_g, rot_g, w_g, wd_g):
    """One side of a closing joint (module docstring, "Loops"): its point's arm from the body's
    input point, position, velocity and the known part of its acceleration (the velocity
    terms; all of it on the ground), and its frame, the frame's angular velocity and the known
    part of its angular acceleration."""
    if k < 0:
        arm = rot_g @ local
        acc = a_g + _cross(wd_g, arm) + _cross(w_g, _cross(w_g, arm))
        return arm, r_g + arm, v_g + _cross(w_g, arm), acc, rot_g, w_g, wd_g
    if on_end:
        return (rho_o[k], r_in[k] + rho_o[k], v_o[k], acc_v[k], rot_o[k], omega_o[k],
                alpha_v[k])
    arm = rot[k] @ local
    w = omega[k]
    return (arm, r_in[k] + arm, v_in[k] + _cross(w, arm), _cross(w, _cross(w, arm)), rot[k], w,
            np.zeros(3))


@numba.njit(cache=True, fastmath=CONTRACT)
def _closure_columns(s, row, k, on_end, coef_a, coef_alpha, coef_section, sign, b_r, b_t,
                     e_col0, m_off, body_kind, beam_params):
    """Add sign * (coef_a . a_k + coef_alpha . alpha_k) to a closing joint's row and, on a
    beam's end, sign * (B_r^T coef_a + B_t^T coef_section) to its modal columns (the end's
    point moves with B_r eta'', its section turns with B_t eta'')."""
    if k < 0:
        return
    for i in range(3):
        s[row, 6 * k + i] += sign * coef_a[i]
        s[row, 6 * k + 3 + i] += sign * coef_alpha[i]
    if on_end and body_kind[k] == _BEAM:
        ce = e_col0 + m_off[k]
        for j in range(_modal_size(beam_params[k])):
            for i in range(3):
                s[row, ce + j] += sign * (b_r[k, i, j] * coef_a[i]
                                          + b_t[k, i, j] * coef_section[i])


@numba.njit(cache=True, fastmath=CONTRACT)
def _closure_rows(s, b, loops, rot, omega, r_in, v_in, rho_o, rot_o, omega_o, v_o, acc_v,
                  alpha_v, b_r, b_t, e_col0, m_off, body_kind, beam_params, r_g, v_g, a_g, rot_g,
                  w_g, wd_g):
    """The closing joints' rows and their multipliers' columns (module docstring, "Loops"):
    per scalar constraint g (a gap e . (p_b - p_a), e fixed in the world or in side a's frame,
    or a dot (F_a x) . (F_b y)), the row g'' + 2 zeta W g' + W^2 g = 0 (linear in the
    accelerations) and, in the dynamic rows, the column -J^T of its multiplier (the joint's
    force and couple do no work on what the joint allows).  Returns the world direction of
    every row's multiplier on side b (a force for a gap, a couple for a dot)."""
    col0, kind, owner, v1, v2, bodies, points, ends, gains, v3, target, _, law, values = loops
    directions = np.zeros((kind.shape[0], 3))
    for r in range(kind.shape[0]):
        c = owner[r]
        row = col0 + r
        ka, kb = bodies[c, 0], bodies[c, 1]
        end_a, end_b = ends[c, 0] != 0, ends[c, 1] != 0
        arm_a, p_a, v_a, acc_a, f_a, w_a, al_a = _closure_side(
            ka, points[c, 0], end_a, rot, omega, r_in, v_in, rho_o, rot_o, omega_o, v_o, acc_v,
            alpha_v, r_g, v_g, a_g, rot_g, w_g, wd_g)
        arm_b, p_b, v_b, acc_b, f_b, w_b, al_b = _closure_side(
            kb, points[c, 1], end_b, rot, omega, r_in, v_in, rho_o, rot_o, omega_o, v_o, acc_v,
            alpha_v, r_g, v_g, a_g, rot_g, w_g, wd_g)
        zero = np.zeros(3)
        if kind[r] == _ANGLE_A or kind[r] == _ANGLE_B or kind[r] == _ROTATION_A:
            # a driven angle, or an elastic hinge's rotation n . log(F_a^T F_b R0^T) about n
            # fixed in a's frame; its rate n . (w_b - w_a)
            n = (f_b if kind[r] == _ANGLE_B else f_a) @ v3[r]
            dw = w_b - w_a
            if kind[r] == _ROTATION_A:
                r0 = np.empty((3, 3))
                r0[:, 0], r0[:, 1], r0[:, 2] = v1[r], v2[r], _cross(v1[r], v2[r])
                g = v3[r] @ _log_rot(f_a.T @ f_b @ r0.T) - target[r, 0]
            else:
                x = f_a @ v1[r]
                y = f_b @ v2[r]
                g = np.arctan2(n @ _cross(x, y), x @ y) - target[r, 0]
                g = (g + np.pi) % (2.0 * np.pi) - np.pi
            gd = n @ dw
            kappa = _cross(w_b if kind[r] == _ANGLE_B else w_a, n) @ dw + n @ (al_b - al_a)
            _closure_columns(s, row, kb, end_b, zero, n, n, 1.0, b_r, b_t, e_col0, m_off,
                             body_kind, beam_params)
            _closure_columns(s, row, ka, end_a, zero, n, n, -1.0, b_r, b_t, e_col0, m_off,
                             body_kind, beam_params)
            directions[r] = n
        elif kind[r] == _DOT:               # (F_a x) . (F_b y) = 0
            x = f_a @ v1[r]
            y = f_b @ v2[r]
            cv = _cross(y, x)
            dw = w_b - w_a
            g = x @ y
            gd = dw @ cv
            kappa = (dw @ (_cross(_cross(w_b, y), x) + _cross(y, _cross(w_a, x)))
                     + cv @ (al_b - al_a))
            _closure_columns(s, row, kb, end_b, zero, cv, cv, 1.0, b_r, b_t, e_col0, m_off,
                             body_kind, beam_params)
            _closure_columns(s, row, ka, end_a, zero, cv, cv, -1.0, b_r, b_t, e_col0, m_off,
                             body_kind, beam_params)
            directions[r] = cv
        else:                               # e . (p_b - p_a) = 0
            e = v1[r] if kind[r] == _GAP_WORLD else f_a @ v1[r]
            d = p_b - p_a
            dd = v_b - v_a
            g = e @ d
            gd = e @ dd
            kappa = e @ (acc_b - acc_a)
            if kind[r] == _GAP_A:           # e turns with side a: its rates enter
                we = _cross(w_a, e)
                gd += we @ d
                kappa += _cross(w_a, we) @ d + 2.0 * (we @ dd)
                ed = _cross(e, d)           # (alpha_a x e) . d = alpha_a . (e x d)
                kappa += ed @ al_a
                _closure_columns(s, row, ka, end_a, zero, ed, ed, 1.0, b_r, b_t, e_col0, m_off,
                                 body_kind, beam_params)
            _closure_columns(s, row, kb, end_b, e, _cross(arm_b, e), zero, 1.0, b_r, b_t,
                             e_col0, m_off, body_kind, beam_params)
            _closure_columns(s, row, ka, end_a, e, _cross(arm_a, e), zero, -1.0, b_r, b_t,
                             e_col0, m_off, body_kind, beam_params)
            directions[r] = e
            g -= target[r, 0]
        # a driven coordinate's row: (g - s)'' + 2 zeta W (g - s)' + W^2 (g - s) = 0
        gd -= target[r, 1]
        kappa -= target[r, 2]
        b[row] = -(kappa + gains[0] * gd + gains[1] * g)
        for j in range(col0):
            s[j, row] = -s[row, j]
        values[r, 0] = g                    # (a JointForce's row: q and q' themselves)
        values[r, 1] = gd
        if law[r, 0] == _SPRING_DAMPER or law[r, 0] == _FORCE:
            # a drive's row is its force: lam = -k (q - rest) - c q' (a spring), or
            # lam = f(t, q, q') in target[r, 2] (a JointForce; _Problem._args)
            for j in range(col0):
                s[row, j] = 0.0
            s[row, row] = 1.0
            b[row] = target[r, 2] - law[r, 1] * g - law[r, 2] * gd
    return directions


# singular values of the closing joints' Delassus matrix below this fraction of its largest
# count as zero (redundant constraints; a loop passing a singular position)
LOOP_RCOND = 1e-10


@numba.njit(cache=True, fastmath=CONTRACT)
def _solve_least_closure_force(s, b, col0, count):
    """Solve S x = b with the closing joints' multipliers in x[col0:col0 + count] (module
    docstring, "Loops"): the tree's system first, x = x0 - X lam with S_tree x0 = b_tree and
    S_tree X = (the multipliers' columns), then the constraints J x = b_c give the Delassus
    system (J X - S_cc) lam = J x0 - b_c (S_cc: a closing joint's spring's row, lam_r = F),
    solved by a truncated SVD: of the multipliers that satisfy
    it, the least (closing joints may be redundant, as a planar loop's spatial joints are, and a
    chain straight between two fixed points leaves its tension indeterminate: the DT-TMM
    sweeps' choice at a pinned tip), and a loop passing a singular position (a flat
    parallelogram) loses the direction that becomes singular there instead of dividing by
    it.  The accelerations do not depend on the choice."""
    tree = np.ascontiguousarray(s[:col0, :col0])
    rhs = np.empty((col0, count + 1))
    rhs[:, 0] = b[:col0]
    rhs[:, 1:] = s[:col0, col0:col0 + count]
    sol = np.linalg.solve(tree, rhs)
    jac = np.ascontiguousarray(s[col0:col0 + count, :col0])
    # a spring's row is lam_r = F (its S_cc 1, its J 0; a constraint's S_cc 0)
    delassus = jac @ np.ascontiguousarray(sol[:, 1:]) - s[col0:col0 + count, col0:col0 + count]
    target = jac @ np.ascontiguousarray(sol[:, 0]) - b[col0:col0 + count]
    u, sv, vt = np.linalg.svd(delassus)
    lam = np.zeros(count)
    ut = u.T @ target
    for i in range(count):
        if sv[i] > LOOP_RCOND * sv[0]:
            lam += (ut[i] / sv[i]) * vt[i]
    x = np.empty(col0 + count)
    x[:col0] = sol[:, 0] - np.ascontiguousarray(sol[:, 1:]) @ lam
    x[col0:] = lam
    return x


@numba.njit(cache=True, fastmath=CONTRACT)
def _solve_dynamics(y, body_params, hinge_kind, hinge_params, body_kind, beam_params, shape_vec,
                    shape_mat, q_off, w_off, d_off, m_off, e0, n_modal, e_col0, f_col, m_col,
                    loops, n_unknowns, gravity, r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques,
                    line_loads, topology, attachment_point, joints):
    """Kinematics plus the solved accelerations, hinge loads and modal accelerations; also each
    body's rho_O = r_O - r_I, the velocity part of a_O and B_r = d r_O / d eta, per joint
    coordinate (joints) its acceleration q'' and the joint loads' generalized force s_i . N
    (s_i . F for a slide), and per hinge its attachment point's arm rho_att and the velocity part
    of its acceleration acc_v_att (_kinematics)."""
    (rot, omega, r_in, v_in, defl, defl_rate, rho_o, rot_o, omega_o, acc_v, alpha_v, b_r,
     b_t, v_o, rho_att, acc_v_att) = _kinematics(
        y, body_params, hinge_kind, hinge_params, body_kind, beam_params, shape_vec, shape_mat,
        q_off, w_off, d_off, m_off, e0, n_modal, r_g, v_g, rot_g, w_g, topology,
        attachment_point, joints)
    q_el, m_el = _elastic_loads(rot, omega, rot_o, omega_o, defl, defl_rate, hinge_kind,
                                hinge_params, rot_g, w_g, topology[0])
    s, b = _assemble(y, rot, omega, defl, rho_o, rot_o, omega_o, acc_v, alpha_v, b_r, b_t,
                     rho_att, acc_v_att, q_el, m_el, body_params, hinge_kind, hinge_params,
                     body_kind, beam_params, shape_vec, shape_mat, m_off, e0, n_modal, e_col0,
                     f_col, m_col, loops, n_unknowns, gravity, a_g, rot_g, w_g, wd_g, forces,
                     torques, line_loads, topology, joints)
    n_rows = loops[1].shape[0]
    if n_rows > 0:
        directions = _closure_rows(s, b, loops, rot, omega, r_in, v_in, rho_o, rot_o, omega_o,
                                   v_o, acc_v, alpha_v, b_r, b_t, e_col0, m_off, body_kind,
                                   beam_params, r_g, v_g, a_g, rot_g, w_g, wd_g)
        x = _solve_least_closure_force(s, b, loops[0], n_rows)
    else:
        directions = np.zeros((0, 3))
        x = np.linalg.solve(s, b)
    # each closing joint's force and couple on side b (world; the couple a pure one), then its
    # drives' generalized forces (a driven coordinate's row's multiplier)
    closure_load = np.zeros((loops[5].shape[0], 8))
    for r in range(n_rows):
        lam = x[loops[0] + r]
        if loops[11][r] >= 0:
            closure_load[loops[2][r], 6 + loops[11][r]] = lam
        at = 0 if loops[1][r] == _GAP_A or loops[1][r] == _GAP_WORLD else 3
        for i in range(3):
            closure_load[loops[2][r], at + i] += lam * directions[r, i]
    n = body_params.shape[0]
    acc = np.empty((n, 3))
    alpha = np.empty((n, 3))
    force = np.zeros((n, 3))
    moment = np.zeros((n, 3))
    for k in range(n):
        acc[k] = x[6 * k:6 * k + 3]
        alpha[k] = x[6 * k + 3:6 * k + 6]
        if hinge_kind[k] == ELASTIC:
            force[k] = q_el[k]
            moment[k] = m_el[k]
        else:
            force[k] = x[f_col[k]:f_col[k] + 3]
            if m_col[k] >= 0:
                moment[k] = x[m_col[k]:m_col[k] + 3]
    modal_acc = x[e_col0:e_col0 + n_modal].copy()
    c_off, n_coord, c_col0 = joints[0], joints[2], joints[3]
    coord_acc = x[c_col0:c_col0 + n_coord].copy()
    generalized = np.zeros(n_coord)
    for k in range(n):
        if c_off[k] < 0:
            continue
        kp = topology[0][k]
        a_in = rot_g if kp < 0 else rot_o[kp]
        dirs, nc = _joint_directions(hinge_kind[k], hinge_params[k], a_in, rot[k])
        load = force[k] if hinge_kind[k] == _PRISMATIC else moment[k]
        for i in range(nc):
            generalized[c_off[k] + i] = dirs[0, i] * load[0] + dirs[1, i] * load[1] + \
                dirs[2, i] * load[2]
    return (rot, omega, r_in, v_in, defl, acc, alpha, force, moment, modal_acc, rho_o, acc_v,
            b_r, coord_acc, generalized, rho_att, acc_v_att, closure_load)


@numba.njit(cache=True, fastmath=CONTRACT)
def rhs_kernel(y, body_params, hinge_kind, hinge_params, body_kind, beam_params, shape_vec,
               shape_mat, q_off, w_off, d_off, m_off, e0, n_modal, e_col0, f_col, m_col, loops,
               n_unknowns, gravity, r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques, line_loads,
               topology, attachment_point, joints):
    """dy/dt of the state [quaternions, angular velocities, (d, d') of elastic hinges,
    modal coordinates of all beams, their rates, joint coordinates, their rates]."""
    (rot, omega, r_in, v_in, defl, acc, alpha, force, moment, modal_acc, rho_o, acc_v,
     b_r, coord_acc, _, rho_att, acc_v_att, _) = _solve_dynamics(
        y, body_params, hinge_kind, hinge_params, body_kind, beam_params, shape_vec, shape_mat,
        q_off, w_off, d_off, m_off, e0, n_modal, e_col0, f_col, m_col, loops, n_unknowns,
        gravity, r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques, line_loads, topology,
        attachment_point, joints)
    n = body_params.shape[0]
    dy = np.zeros(y.shape[0])
    for k in range(n):
        if q_off[k] >= 0:
            o = q_off[k]
            qw, qx, qy, qz = y[o], y[o + 1], y[o + 2], y[o + 3]
            wx, wy, wz = omega[k, 0], omega[k, 1], omega[k, 2]
            # q' = 1/2 [0, w] (x) q  (w in the world frame, A = R(q) body to world)
            dy[o] = -0.5 * (wx * qx + wy * qy + wz * qz)
            dy[o + 1] = 0.5 * (qw * wx + wy * qz - wz * qy)
            dy[o + 2] = 0.5 * (qw * wy + wz * qx - wx * qz)
            dy[o + 3] = 0.5 * (qw * wz + wx * qy - wy * qx)
            dy[w_off[k]:w_off[k] + 3] = alpha[k]
        if hinge_kind[k] == ELASTIC:
            o = d_off[k]
            dy[o:o + 3] = y[o + 3:o + 6]
            kp = topology[0][k]
            # d'' = a_k - a_att,k, the attachment point's acceleration (the ground's for a root;
            # a_P + alpha_P x rho_att + velocity part, + B_r eta''_P on a beam's end)
            if kp < 0:
                a_att = a_g
            else:
                a_att = acc[kp] + _cross(alpha[kp], rho_att[k]) + acc_v_att[k]
                if body_kind[kp] == _BEAM:
                    nm2 = _modal_size(beam_params[kp])
                    br = np.ascontiguousarray(b_r[kp, :, :nm2])
                    a_att = a_att + br @ modal_acc[m_off[kp]:m_off[kp] + nm2]
            dy[o + 3:o + 6] = acc[k] - a_att
    for i in range(n_modal):
        dy[e0 + i] = y[e0 + n_modal + i]
        dy[e0 + n_modal + i] = modal_acc[i]
    c0, n_coord = joints[1], joints[2]
    for i in range(n_coord):
        dy[c0 + i] = y[c0 + n_coord + i]
        dy[c0 + n_coord + i] = coord_acc[i]
    return dy


# ----------------------------------------------------------------------------------------------
# Python layer
# ----------------------------------------------------------------------------------------------

# Baumgarte's stabilization of the closing joints' rows, g'' + 2 zeta W g' + W^2 g = 0 with
# zeta = 1 and W = 20 rad/s (module docstring, "Loops")
LOOP_DAMPING = 20.0


def _loop_rows(model, col0):
    """The closing joints as the kernels read them (_closure_rows): (first multiplier column,
    per row its kind (closures.GAP_WORLD, GAP_A or DOT), its closing joint, x or e, y, then per
    closing joint its sides' bodies, points and end flags, the stabilization's gains, per row
    its angle axis, its targets, its driven coordinate, its drive's law, and its (g, g') as the
    last evaluation found them)."""
    kind, owner, v1, v2, v3, coordinate, law = constraint_rows(model)
    return (col0, kind, owner, v1, v2,
            np.array(model.closure_body, dtype=np.int64).reshape(-1, 2),
            np.array(model.closure_point, dtype=float).reshape(-1, 2, 3),
            np.array(model.closure_on_end, dtype=np.int64).reshape(-1, 2),
            np.array([2.0 * LOOP_DAMPING, LOOP_DAMPING ** 2]), v3, np.zeros((len(kind), 3)),
            coordinate, law, np.zeros((len(kind), 2)))


def _finite_number(value, who, what, t):
    """A user function's value as a float; ValueError naming who returned what otherwise."""
    a = np.asarray(value, dtype=float)
    if a.size != 1 or not np.isfinite(a.reshape(-1)[0]):
        raise ValueError(f"simulate_reference: {who}: {what} returned {value!r} at "
                         f"t = {t:.17g} (need one finite number)")
    return float(a.reshape(-1)[0])


class _Problem:
    """Index bookkeeping and the per-time evaluation of ground motion, applied loads and joint
    drives."""

    def __init__(self, model):
        n = model.n_bodies
        # writable copies of the model's read-only arrays (numba types read-only arrays apart)
        kinds = np.array(model.hinge_kind, dtype=np.int64)
        self.model = model
        self.n = n
        self.kinds = kinds
        self.body_params = np.array(model.body_params, dtype=float, order="C")
        self.hinge_params = np.array(model.hinge_params, dtype=float, order="C")
        self.gravity = np.array(model.gravity, dtype=float)
        # a quaternion and w of its own: bodies behind ball joints and elastic hinges (a fixed
        # hinge's or a joint's child follows its parent and the joint's coordinates)
        free = [k for k in range(n) if kinds[k] != FIXED and kinds[k] not in
                JOINTS_WITH_COORDINATES]
        elastic = [k for k in range(n) if kinds[k] == ELASTIC]
        self.q_off = np.full(n, -1, dtype=np.int64)
        self.w_off = np.full(n, -1, dtype=np.int64)
        self.d_off = np.full(n, -1, dtype=np.int64)
        o = 0
        for k in free:
            self.q_off[k] = o
            o += 4
        for k in free:
            self.w_off[k] = o
            o += 3
        for k in elastic:
            self.d_off[k] = o
            o += 6
        # beams: all modal coordinates (concatenated in body order, v then w of each beam), then
        # all their rates
        self.body_kind = np.array(model.body_kind, dtype=np.int64)
        self.beam_params = np.array(model.beam_params, dtype=float, order="C")
        beams = [k for k in range(n) if self.body_kind[k] == BEAM]
        for k in beams:
            if int(self.beam_params[k, FAMILY]) not in (PINNED, CLAMPED, CLAMPED_LOADED):
                raise ValueError(f"simulate_reference: body {k}: unknown beam mode family "
                                 f"{self.beam_params[k, FAMILY]}")
        # shape constants of every beam, padded to the widest beam (module docstring)
        mmax = max([1] + [int(self.beam_params[k, MODES]) for k in beams])
        tmax = max([0] + [int(self.beam_params[k, TORSION_MODES]) for k in beams])
        amax = max([0] + [int(self.beam_params[k, AXIAL_MODES]) for k in beams])
        # bending in columns :m, the twist in tw:tw + mt, the stretch in 2 tw:2 tw + ma (with
        # its products with the bending shapes in rows N_SHAPE_ROWS + l)
        tw = max(mmax, tmax, amax)
        self.shape_vec = np.zeros((n, N_SHAPE_ROWS + mmax, 3 * tw))
        self.shape_mat = np.zeros((n, mmax, 4 * mmax))   # int Y Y^T, then D0, D1, D2
        for k in beams:
            vec, mat = beam_shape_constants(self.beam_params[k])
            m = vec.shape[1]
            self.shape_vec[k, :N_SHAPE_ROWS, :m] = vec
            twist = twist_shape_constants(self.beam_params[k])
            self.shape_vec[k, :N_SHAPE_ROWS, tw:tw + twist.shape[1]] = twist
            stretch = stretch_shape_constants(self.beam_params[k])
            self.shape_vec[k, :stretch.shape[0], 2 * tw:2 * tw + stretch.shape[1]] = stretch
            self.shape_mat[k, :m, :m] = mat
            for i, d in enumerate(stiffening_matrices(self.beam_params[k])):
                self.shape_mat[k, :m, (i + 1) * mmax:(i + 1) * mmax + m] = d
        n_modes = np.asarray(model.n_modes, dtype=np.int64)
        self.m_off = np.full(n, -1, dtype=np.int64)
        nm = 0
        for k in range(n):
            if n_modes[k] > 0:
                self.m_off[k] = nm
                nm += int(n_modes[k])
        self.n_modal = nm
        self.e0 = o
        o += 2 * nm
        # joints with coordinates: all coordinates (hinge order, a joint's in its own order, as
        # Result.joint_coordinates), then all their rates
        self.c_off = np.full(n, -1, dtype=np.int64)
        self.coordinates = []                   # (hinge, index in the joint, validated drive)
        for k in range(n):
            if kinds[k] in JOINTS_WITH_COORDINATES:
                self.c_off[k] = len(self.coordinates)
                drives = model.drives[k]
                for i in range(coordinate_count(kinds[k])):
                    self.coordinates.append((k, i, drives[i] if i < len(drives) else None))
        nq = len(self.coordinates)
        self.n_coord = nq
        self.c0 = o
        o += 2 * nq
        self.n_state = o
        self.f_col = np.full(n, -1, dtype=np.int64)
        self.m_col = np.full(n, -1, dtype=np.int64)
        c = 6 * n
        for k in range(n):
            if kinds[k] != ELASTIC:
                self.f_col[k] = c
                c += 3
            if kinds[k] == FIXED or kinds[k] in JOINTS_WITH_COORDINATES:
                self.m_col[k] = c
                c += 3
        self.e_col0 = c
        c += nm
        self.c_col0 = c
        c += nq
        self.loops = _loop_rows(model, c)
        # the rows of closing joints' driven coordinates: their motions fill loops' targets
        rows = constraint_rows(model)
        owner, coordinate = rows.owner, rows.coordinate
        self._closure_motions = [(r, model.closure_drives[owner[r]][coordinate[r]]["function"],
                                  f"closing joint '{model.closure_names[owner[r]]}', "
                                  f"coordinate {coordinate[r] + 1}")
                                 for r in np.nonzero(rows.law[:, 0] == MOTION)[0]]
        self._closure_forces = closure_forces(model, rows)
        for r in np.nonzero((rows.law[:, 0] == SPRING_DAMPER) & (coordinate >= 0))[0]:
            # a drive's spring: its row's value q - rest (an elastic hinge's rest is 0)
            self.loops[10][r, 0] = model.closure_drives[owner[r]][coordinate[r]]["rest"]
        c += self.loops[1].shape[0]
        self.n_unknowns = c
        self.forces = np.zeros((n, 3))
        self.torques = np.zeros((n, 3))
        self.line_loads = np.zeros((n, 3))
        self._line_load_fns = [(k, f) for k, f in enumerate(model.line_loads) if f is not None]
        self._force_fns = [(k, f) for k, f in enumerate(model.forces) if f is not None]
        self._torque_fns = [(k, f) for k, f in enumerate(model.torques) if f is not None]
        # the tree: each body's parent and its children (CSR: child_list[child_start[k]:
        # child_start[k + 1]]), and where each hinge attaches: Model.attachment_point, the point
        # in its parent's frame from the parent's input point (a rigid parent's output point or
        # one of its named points; a beam parent's output point, which the kernels take from
        # the beam's deflected end instead)
        parent = np.array(model.parent, dtype=np.int64)
        children = [[c for c in range(n) if parent[c] == k] for k in range(n)]
        self.topology = (parent, np.cumsum([0] + [len(c) for c in children]).astype(np.int64),
                         np.array([c for cs in children for c in cs], dtype=np.int64))
        self.attachment_point = np.array(model.attachment_point, dtype=float)
        # the drives, evaluated in Python at every right-hand side (joint_inputs)
        self.prescribed = np.zeros(nq, dtype=np.int64)
        self.drive_value = np.zeros(nq)
        self._motions, self._springs, self._drive_fns, self._pds = [], [], [], []
        for c, (k, i, d) in enumerate(self.coordinates):
            if d is None:
                continue
            if d["kind"] == MOTION:
                self.prescribed[c] = 1
                self._motions.append((c, d["function"]))
            elif d["kind"] == SPRING_DAMPER:
                self._springs.append((c, d["stiffness"], d["damping"], d["rest"]))
            elif d["kind"] == FORCE:
                self._drive_fns.append((c, d["function"]))
            elif d["kind"] == PD:
                self._pds.append((c, d["stiffness"], d["damping"]) + tuple(d["function"]))
            else:
                raise ValueError(f"simulate_reference: {self.coordinate_label(c)}: unknown drive "
                                 f"kind {d['kind']}")
        self.joints = (self.c_off, self.c0, nq, self.c_col0, self.prescribed, self.drive_value)

    def coordinate_label(self, c):
        """How messages name coordinate c: its joint, hinge index and coordinate."""
        k, i, _ = self.coordinates[c]
        kind = JOINT_KIND[int(self.kinds[k])].name
        return f"{kind} '{self.model.hinge_names[k]}' (hinge {k}), coordinate {i}"

    def initial_state(self):
        m = self.model
        y = np.zeros(self.n_state)
        for k in range(self.n):
            if self.q_off[k] >= 0:
                y[self.q_off[k]:self.q_off[k] + 4] = rotation_to_quaternion(m.initial_rotation[k])
                y[self.w_off[k]:self.w_off[k] + 3] = m.initial_angular_velocity[k]
            if self.d_off[k] >= 0:          # an elastic hinge's deflection (its rate: 0)
                y[self.d_off[k]:self.d_off[k] + 3] = self.hinge_params[k, DEFLECTION_0]
        nm = self.n_modal
        if nm > 0:
            y[self.e0:self.e0 + nm] = np.asarray(m.initial_modal_coordinates, dtype=float)
            y[self.e0 + nm:self.e0 + 2 * nm] = np.asarray(m.initial_modal_velocities,
                                                          dtype=float)
        for c, (k, i, _) in enumerate(self.coordinates):
            y[self.c0 + c] = self.hinge_params[k, COORDINATE_0][i]
            y[self.c0 + self.n_coord + c] = self.hinge_params[k, RATE_0][i]
        return y

    def _number(self, c, what, t, value):
        """A drive's value as a float; ValueError naming the joint and coordinate otherwise."""
        return _finite_number(value, self.coordinate_label(c), what, t)

    def joint_inputs(self, t, y):
        """The state with every prescribed coordinate and rate taken from its motion at time t,
        and each coordinate's drive value (joints[5]): the generalized force f(t, q, q') or
        -k (q - rest) - c q' of a free coordinate's drive (0 without one), the prescribed
        acceleration of a driven one (module docstring, "Joints with coordinates")."""
        c0, nq = self.c0, self.n_coord
        if self._motions:
            y = y.copy()
        for c, (position, velocity, acceleration) in self._motions:
            y[c0 + c] = self._number(c, "prescribed position", t, position(t))
            y[c0 + nq + c] = self._number(c, "prescribed velocity", t, velocity(t))
            self.drive_value[c] = self._number(c, "prescribed acceleration", t, acceleration(t))
        for c, stiffness, damping, rest in self._springs:
            self.drive_value[c] = -stiffness * (y[c0 + c] - rest) - damping * y[c0 + nq + c]
        for c, f in self._drive_fns:
            self.drive_value[c] = self._number(c, "drive function(t, q, q_dot)", t,
                                               f(t, y[c0 + c], y[c0 + nq + c]))
        for c, kp, kd, target, rate, feedforward in self._pds:
            # f = kp (target - q) + kd (target' - q') + feedforward
            self.drive_value[c] = (
                kp * (self._number(c, "PDTracking target", t, target(t)) - y[c0 + c])
                + kd * (self._number(c, "PDTracking target_rate", t, rate(t)) - y[c0 + nq + c])
                + (0.0 if feedforward is None else
                   self._number(c, "PDTracking feedforward", t, feedforward(t))))
        return y

    def time_inputs(self, t):
        """Ground motion and applied loads at time t, as float arrays for the kernel."""
        r_g, v_g, a_g, rot_g, w_g, wd_g = (np.asarray(x, dtype=float)
                                           for x in self.model.ground_state(t))
        for k, f in self._force_fns:
            self.forces[k] = f(t)
        for k, f in self._torque_fns:
            self.torques[k] = f(t)
        for k, f in self._line_load_fns:
            self.line_loads[k] = f(t)
        return (r_g, v_g, a_g, rot_g, w_g, wd_g, self.forces, self.torques,
                self.line_loads)

    def _args(self, y, t):
        r_g, v_g, a_g, rot_g, w_g, wd_g, forces, torques, line_loads = self.time_inputs(t)
        y = self.joint_inputs(t, y)
        target = self.loops[10]
        for r, functions, who in self._closure_motions:
            for i, (what, f) in enumerate(zip(("position", "velocity", "acceleration"),
                                              functions)):
                target[r, i] = _finite_number(f(t), who, f"prescribed {what}", t)
        args = (y, self.body_params, self.kinds, self.hinge_params, self.body_kind,
                self.beam_params, self.shape_vec, self.shape_mat, self.q_off, self.w_off,
                self.d_off, self.m_off, self.e0, self.n_modal, self.e_col0, self.f_col,
                self.m_col, self.loops, self.n_unknowns, self.gravity, r_g, v_g, a_g, rot_g, w_g,
                wd_g, forces, torques, line_loads, self.topology, self.attachment_point,
                self.joints)
        if self._closure_forces:    # a closing JointForce: f(t, q, q') at this state's q, q',
            _solve_dynamics(*args)  # which one evaluation leaves in loops[13]
            values = self.loops[13]
            for r, f, who in self._closure_forces:
                target[r, 2] = _finite_number(f(t, values[r, 0], values[r, 1]), who,
                                              "drive function(t, q, q_dot)", t)
        return args

    def rhs(self, t, y):
        return rhs_kernel(*self._args(np.ascontiguousarray(y, dtype=float), t))

    def evaluate(self, t, y):
        """Everything Result records at one time, from the state (see _solve_dynamics)."""
        return _solve_dynamics(*self._args(np.ascontiguousarray(y, dtype=float), t))

    def end_sections(self, t, y):
        """Every body's output point and section at one time, world: (rho_O = r_O - r_I, v_O,
        A_O, w_O), each (n, ...)."""
        r_g, v_g, _, rot_g, w_g, _ = (np.asarray(x, dtype=float)
                                      for x in self.model.ground_state(t))
        y = self.joint_inputs(t, np.ascontiguousarray(y, dtype=float))
        out = _kinematics(y, self.body_params, self.kinds,
                          self.hinge_params, self.body_kind, self.beam_params, self.shape_vec,
                          self.shape_mat, self.q_off, self.w_off, self.d_off, self.m_off,
                          self.e0, self.n_modal,
                          r_g, v_g, rot_g, w_g, self.topology, self.attachment_point,
                          self.joints)
        return out[6], out[13], out[7], out[8]


def _check_args(model, t_end, method, rtol, atol, t_eval):
    if not isinstance(model, Model):
        raise ValueError(f"simulate_reference: model must be a dttmm Model (from build_chain), "
                         f"got {type(model).__name__}")
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


def simulate_reference(model, t_end, *, method="DOP853", rtol=1e-10, atol=1e-12, t_eval=None):
    """Integrate the model with the global Newton-Euler equations and scipy's solve_ivp.

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

    Returns
    -------
    Result
        ``dttmm.Result`` with method "newton-euler/DOP853" (or "/RK45"): positions, velocities,
        rotations, angular velocities and accelerations, the forces and moments at every
        body's input, the energies (``dttmm.result.chain_energies``) at every recorded time;
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
        solve_ivp failed (the time and its message).

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
    t_end, t_eval = _check_args(model, t_end, method, rtol, atol, t_eval)
    assembly = None
    if model.n_closures:
        before = [float(np.max(r, initial=0.0)) for r in loop_residuals(model)]
        if max(before) > 1e-10:          # close the loops first (closures.assemble, which
            model = assemble(model)      # refuses a drive the loops lock)
        else:
            check_drives_move(model, "simulate_reference")
        assembly = {"before": before,
                    "after": [float(np.max(r, initial=0.0)) for r in loop_residuals(model)]}
    prob = _Problem(model)
    y0 = prob.initial_state()
    n, nt = prob.n, len(t_eval)
    if prob.n_state > 0:
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
    kinetic = np.empty(nt)
    potential = np.empty(nt)
    nm, e0 = prob.n_modal, prob.e0
    eta = np.ascontiguousarray(ys[:, e0:e0 + nm])
    eta_dot = np.ascontiguousarray(ys[:, e0 + nm:e0 + 2 * nm])
    rho_out = np.empty((nt, n, 3))
    nq, c0 = prob.n_coord, prob.c0
    q_rec = np.empty((nt, nq))
    qd_rec = np.empty((nt, nq))
    drive = np.empty((nt, nq))
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
        drive[i] = np.where(prob.prescribed == 1, out[14], prob.drive_value)
        ground = model.ground_state(t)
        kinetic[i], potential[i] = chain_energies(model, rk, wk, rik, vik, dk,
                                                    ground_rotation=ground[3],
                                                    eta=eta[i], eta_dot=eta_dot[i],
                                                    joint_coordinates=q_rec[i] if nq else None,
                                                    ground_position=ground[0])
    r_c, r_o = point_positions(model, rot, r_in)
    for k in range(n):                          # a beam's mass centre and output point move
        if prob.body_kind[k] == BEAM:           # with its deflection
            r_c[:, k] = r_in[:, k] + np.einsum("tij,tj->ti", rot[:, k],
                                               _beam_mass_center(prob.beam_params[k],
                                                                 prob.shape_vec[k],
                                                                 prob.shape_mat[k],
                                                                 eta[:, prob.m_off[k]:]))
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
                  body_names=tuple(model.body_names))


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
