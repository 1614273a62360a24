"""The reference's own strain-rod kinematics (docs/strain_rod.md), by another road than the
kernel's (kernels/transfers/strain_rod.py): the same Magnus step Omega(t) per station, but its
exponential and that exponential's first two time derivatives from one power series of 4 x 4
homogeneous matrices over truncated polynomials, no J_l and no closed forms.

Along the motion, X(t + s) = Omega^ + s Omega'^ + s^2/2 Omega''^ + O(s^3), and in the ring of
polynomials in s modulo s^3 (a triple (M0, M1, M2) is M0 + s M1 + s^2 M2; products
(A B)_k = sum_{i+j=k} A_i B_j) exp(X) = E + s E' + s^2/2 E'' + O(s^3): its Taylor series by
Horner's rule after scaling by 2^-j, then j squarings.  The stations' poses then follow
G_{a+1} = G_a E, G' = G'_a E + G_a E', G'' = G''_a E + 2 G'_a E' + G_a E'', and with G = (R, p)
the angular velocity omega = vee(R' R^T) and acceleration alpha = vee(R'' R^T) (R'' R^T's skew
part: d/dt (R' R^T) = R'' R^T + R' R'^T, the latter symmetric).
"""
import numpy as np

from ..kernels import kernel
from ..kernels.algebra.mat3 import add2, matmul, matvec, put1, put2

_SQRT3_12 = np.sqrt(3.0) / 12.0
_TAYLOR_TERMS = 16          # after scaling to norm < 1/2: remainder below 2^-16 / 16! ~ 1e-18


@kernel
def _jet_mul(a, b):
    out = np.zeros((3, 4, 4))
    put2(out[0], matmul(a[0], b[0]))
    put2(out[1], matmul(a[0], b[1]) + matmul(a[1], b[0]))
    put2(out[2], matmul(a[0], b[2]) + matmul(a[1], b[1]) + matmul(a[2], b[0]))
    return out


@kernel
def _jet_exp(x):
    """exp of the jet x (3, 4, 4): (E, E', E''/2) of exp(X(s))."""
    norm = np.abs(x[0]).sum(axis=1).max() + np.abs(x[1]).sum(axis=1).max() \
        + np.abs(x[2]).sum(axis=1).max()
    squarings = 0
    while norm > 0.5:
        norm *= 0.5
        squarings += 1
    y = x / 2.0 ** squarings
    out = np.zeros((3, 4, 4))
    put2(out[0], np.eye(4))
    for k in range(_TAYLOR_TERMS, 0, -1):        # exp(y) = I + y (I + y/2 (I + y/3 (...)))
        out = _jet_mul(y, out) / k
        add2(out[0], np.eye(4))
    for _ in range(squarings):
        out = _jet_mul(out, out)
    return out


@kernel
def _twist_matrix(xi):
    m = np.zeros((4, 4))
    m[0, 1], m[0, 2], m[1, 2] = -xi[2], xi[1], -xi[0]
    m[1, 0], m[2, 0], m[2, 1] = xi[2], -xi[1], xi[0]
    m[0, 3], m[1, 3], m[2, 3] = xi[3], xi[4], xi[5]
    return m


@kernel
def _matrix_bracket(a, b):
    return matmul(a, b) - matmul(b, a)


@kernel(entry=True)
def rod_sections(steps, xi0, phi, q, qd, qdd, rot, pos, omega, vel, alpha, acc):
    """The same outputs as kernels/transfers/strain_rod.py::rod_kinematics (stations 0 .. n in
    the input frame: rotation, centre, angular velocity, velocity, angular acceleration,
    acceleration), computed as the module's docstring says.  The Magnus step is written in
    4 x 4 matrices: Omega^ = h/2 (X_1 + X_2) + sqrt(3)/12 h^2 [X_1, X_2], X_i = xi_i^."""
    n = steps.shape[0]
    g = np.eye(4)
    g1 = np.zeros((4, 4))
    g2 = np.zeros((4, 4))
    for a in range(n + 1):
        if a > 0:
            h = steps[a - 1]
            k = _SQRT3_12 * h * h
            x1 = _twist_matrix(xi0[a - 1, 0] + matvec(phi[a - 1, 0], q))
            x2 = _twist_matrix(xi0[a - 1, 1] + matvec(phi[a - 1, 1], q))
            v1 = _twist_matrix(matvec(phi[a - 1, 0], qd))
            v2 = _twist_matrix(matvec(phi[a - 1, 1], qd))
            w1 = _twist_matrix(matvec(phi[a - 1, 0], qdd))
            w2 = _twist_matrix(matvec(phi[a - 1, 1], qdd))
            jet = np.zeros((3, 4, 4))
            put2(jet[0], 0.5 * h * (x1 + x2) + k * _matrix_bracket(x1, x2))
            put2(jet[1], 0.5 * h * (v1 + v2)
                 + k * (_matrix_bracket(v1, x2) + _matrix_bracket(x1, v2)))
            put2(jet[2], 0.5 * (0.5 * h * (w1 + w2) + k * (_matrix_bracket(w1, x2)
                                                            + 2.0 * _matrix_bracket(v1, v2)
                                                            + _matrix_bracket(x1, w2))))
            e = _jet_exp(jet)
            g, g1, g2 = (matmul(g, e[0]), matmul(g1, e[0]) + matmul(g, e[1]),
                         matmul(g2, e[0]) + 2.0 * matmul(g1, e[1]) + 2.0 * matmul(g, e[2]))
        r, r1, r2 = g[:3, :3].copy(), g1[:3, :3].copy(), g2[:3, :3].copy()
        put2(rot[a], r)
        put1(pos[a], g[:3, 3])
        put1(vel[a], g1[:3, 3])
        put1(acc[a], g2[:3, 3])
        rt = r.T
        w = matmul(r1, rt)
        omega[a, 0], omega[a, 1], omega[a, 2] = w[2, 1], w[0, 2], w[1, 0]
        al = matmul(r2, rt)
        alpha[a, 0] = 0.5 * (al[2, 1] - al[1, 2])
        alpha[a, 1] = 0.5 * (al[0, 2] - al[2, 0])
        alpha[a, 2] = 0.5 * (al[1, 0] - al[0, 1])


@kernel(entry=True)
def station_arrays(n):
    """rod_sections' outputs for n stations, zeroed (rotations (n, 3, 3), then five (n, 3))."""
    return (np.zeros((n, 3, 3)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)),
            np.zeros((n, 3)), np.zeros((n, 3)))


@kernel
def rod_state(steps, xi0, phi, q, qd):
    """Per station (its padded steps have length 0 and weight 0): rotation, centre, the
    section's angular velocity and the centre's velocity relative to the frame, the convective
    accelerations (those at q'' = 0), and the Jacobians Jp, Jr (3 x n_q: a unit q'_j's velocity
    and angular velocity), all in the input-section frame (rod_sections)."""
    n = steps.shape[0] + 1
    nq = q.shape[0]
    zero = np.zeros(nq)
    rot, pos, om, vel, al, acc = station_arrays(n)
    rod_sections(steps, xi0, phi, q, qd, zero, rot, pos, om, vel, al, acc)
    jp = np.zeros((n, 3, nq))
    jr = np.zeros((n, 3, nq))
    r2, p2, o2, v2, a2, c2 = station_arrays(n)
    for j in range(nq):
        unit = np.zeros(nq)
        unit[j] = 1.0
        rod_sections(steps, xi0, phi, q, unit, zero, r2, p2, o2, v2, a2, c2)
        for i in range(n):
            put1(jp[i, :, j], v2[i])
            put1(jr[i, :, j], o2[i])
    return rot, pos, om, vel, al, acc, jp, jr


@kernel
def _cross3(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


@kernel
def rod_end(state, a, w):
    """The rod's output point and section (world) as the reference's _kinematics takes a body's
    (equations.py, "End kinematics"): rho_O = A p_L, the relative velocity v_O - v_I,
    A_O = A R_L, w_O = w + A omega_L, the velocity parts of a_O, w x (w x rho) + 2 w x A p'_L +
    A c_p,L, and of alpha_O, w x A omega_L + A c_r,L, and B_r = A Jp_L, B_t = A Jr_L."""
    rot, pos, om, vel, al, acc, jp, jr = state
    last = pos.shape[0] - 1
    rho = matvec(a, pos[last])
    avel = matvec(a, vel[last])
    aom = matvec(a, om[last])
    v_rel = _cross3(w, rho) + avel
    acc_v = _cross3(w, _cross3(w, rho)) + 2.0 * _cross3(w, avel) + matvec(a, acc[last])
    alpha_v = _cross3(w, aom) + matvec(a, al[last])
    return (rho, v_rel, matmul(a, rot[last]), w + aom, acc_v, alpha_v, matmul(a, jp[last]),
            matmul(a, jr[last]))


@kernel
def rod_terms(state, weights, mu, section, stiffness, damping, q, qd, a, w, gravity):
    """The rod's share of the reference's rows, in the form _beam_terms returns a beam's
    (equations.py; docs/strain_rod.md, "The rod's equations"): mass, first moment h = A s,
    inertia about I (world, with the sections' own: section = diag(j_p, rho I_w, rho I_v) per
    length in the section's axes), A P = A sum f Jp, A G = A sum (f p^ Jp + Theta Jr), the
    Newton and Euler velocity terms (those beyond -w x (w x h) and -w x J w), the strain rows'
    right-hand side and their mass matrix, f = mu w_i, Theta_i = w_i R_i section R_i^T:
        newton_v = -A sum f (2 w x p' + c_p)
        euler_v  = -A sum [f p x (2 w x p' + c_p) + Theta (w x om + c_r) + w x Theta om
                           + om x Theta w + om x Theta om]
        modal    = sum f Jp^T (g - w x (w x p) - 2 w x p' - c_p)
                   - Jr^T (Theta (w x om + c_r) + (w + om) x Theta (w + om)) - K q - d K q'
    (w, g in the frame; om, p', c_p, c_r the station's relative rates and convective terms)."""
    rot, pos, om, vel, al, acc, jp, jr = state
    nq = q.shape[0]
    w_b = matvec(a.T, w)
    g_b = matvec(a.T, gravity)
    s_b = np.zeros(3)
    pi = np.zeros((3, 3))
    theta_sum = np.zeros((3, 3))
    p_b = np.zeros((3, nq))
    gg_b = np.zeros((3, nq))
    m_ee = np.zeros((nq, nq))
    nv = np.zeros(3)
    ev = np.zeros(3)
    modal = np.zeros(nq)
    for i in range(weights.shape[0]):
        wt = weights[i]
        if wt == 0.0:
            continue
        f = mu * wt
        r = rot[i]
        theta = wt * matmul(matmul(r, np.diag(section)), r.T)
        p, pd, o = pos[i], vel[i], om[i]
        jpi, jri = np.ascontiguousarray(jp[i]), np.ascontiguousarray(jr[i])
        s_b += f * p
        pi += f * np.outer(p, p)
        theta_sum += theta
        p_b += f * jpi
        hp = np.zeros((3, 3))
        hp[0, 1], hp[0, 2], hp[1, 2] = -p[2], p[1], -p[0]
        hp[1, 0], hp[2, 0], hp[2, 1] = p[2], -p[1], p[0]
        gg_b += f * matmul(hp, jpi) + matmul(theta, jri)
        m_ee += f * matmul(jpi.T, jpi) + matmul(matmul(jri.T, theta), jri)
        lin = 2.0 * _cross3(w_b, pd) + acc[i]
        nv += f * lin
        rate = matvec(theta, _cross3(w_b, o) + al[i])
        wo = w_b + o
        ev += (f * _cross3(p, lin) + rate + _cross3(w_b, matvec(theta, o))
               + _cross3(o, matvec(theta, w_b)) + _cross3(o, matvec(theta, o)))
        modal += f * matvec(jpi.T, g_b - _cross3(w_b, _cross3(w_b, p)) - lin)
        modal -= matvec(jri.T, rate + _cross3(wo, matvec(theta, wo)))
    modal -= stiffness * (q + damping * qd)
    mass = mu * weights.sum()
    j_b = theta_sum - pi
    tr = pi[0, 0] + pi[1, 1] + pi[2, 2]
    for i in range(3):
        j_b[i, i] += tr
    return (mass, matvec(a, s_b), matmul(matmul(a, j_b), a.T), matmul(a, p_b), matmul(a, gg_b),
            -matvec(a, nv), -matvec(a, ev), modal, m_ee,
            np.zeros((3, nq)))
