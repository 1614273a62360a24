"""The reference's integrator in compiled code, for models whose right-hand side needs no Python
during the run (no drive but spring-dampers, no load or ground motion given as a function, a
ground spun by a profile's angle evaluated here: hub.py; newton_euler.py's simulate_reference
picks it, scipy's solve_ivp otherwise).

It is scipy's DOP853 (Hairer's explicit Runge-Kutta pair of order 8 with errors of orders 5
and 3, and its 7th-degree dense output; E. Hairer, S. P. Norsett, G. Wanner, "Solving
Ordinary Differential Equations I", Sec. II.10), step for step: scipy's Butcher tableau (read
from scipy.integrate.DOP853), its initial step, error norm and step control, its dense output
at the recorded times.  What it saves is the Python between the right-hand sides: scipy's
stage loop and its call of rhs_kernel from Python cost about as much as the right-hand side
itself (docs/reference.md, "Integrator").  tests/test_reference.py checks it against
solve_ivp on the same models.  It is written apart from kernels/stepping/runge_kutta.py (the
same method as DT-TMM's scheme="dop853", which the reference checks): the reference shares no
code with what it tests.

    stages      k_s = f(t + c_s h, y + h sum_{j<s} a_sj k_j),  s = 0..11;  k_12 = f(t + h, y1)
                (f depends on t through a spun ground only)
    step        y1 = y + h sum_j b_j k_j
    error       e5 = sum_j E5_j k_j / sc,  e3 = sum_j E3_j k_j / sc,
                sc = atol + rtol max(|y|, |y1|),
                err = |h| |e5|^2 / sqrt(n (|e5|^2 + 0.01 |e3|^2))
    control     accepted if err < 1: h *= min(10, 0.9 err^(-1/8)) (at most 1 after a rejection);
                else h *= max(0.2, 0.9 err^(-1/8))
    dense       three more stages k_13..15 (at t + c_s h); F0 = y1 - y, F1 = h k_0 - F0,
                F2 = 2 F0 - h (k_12 + k_0), F3..6 = h D k;
                y(t + x h) = y + x (F0 + (1 - x) (F1 + x (F2 + (1 - x) (... F6))))
"""
import math

import numpy as np
from scipy.integrate import DOP853

from ..kernels import kernel
from ..kernels.algebra.mat3 import put1
from .equations import rhs_kernel
from .hub import spun_ground

_STAGES = DOP853.n_stages                                      # 12
# a_sj and c_s of every stage (16 x 16, 16): the step's 12, a zero row for k_12 = f(t + h, y1),
# the dense output's 3
_A = np.ascontiguousarray(np.vstack([np.pad(DOP853.A, ((0, 1), (0, 4))), DOP853.A_EXTRA]))
_C = np.ascontiguousarray(np.concatenate([DOP853.C, [1.0], DOP853.C_EXTRA]))
_B = np.ascontiguousarray(DOP853.B)
_E3 = np.ascontiguousarray(DOP853.E3)
_E5 = np.ascontiguousarray(DOP853.E5)
_D = np.ascontiguousarray(DOP853.D)
_EXPONENT = -1.0 / (DOP853.error_estimator_order + 1)       # -1/8
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0

OK, STEP_TOO_SMALL = 0, -1
_ROT_G, _W_G, _WD_G = 22, 23, 24   # the ground's rotation, angular velocity and acceleration
_JOINTS = 30         # the joints' table among rhs_kernel's arguments after y


@kernel
def _rhs(y, t, args, springs, hub_axis, hub_terms):
    """rhs_kernel at (t, y), a spun ground's rotation and rates at t (hub.py: hub_terms its
    angle's, none for a still ground) and each spring-damper drive's generalized force
    -k (q - rest) - c q' set first in their arguments (newton_euler.py's _Problem.ground and
    joint_inputs); springs: rows [coordinate, stiffness, damping, rest]."""
    spun_ground(hub_axis, hub_terms, t, args[_ROT_G], args[_W_G], args[_WD_G])
    joints = args[_JOINTS]
    c0, nq, drive_value = joints[1], joints[2], joints[5]
    for r in range(springs.shape[0]):
        c = int(springs[r, 0])
        drive_value[c] = (-springs[r, 1] * (y[c0 + c] - springs[r, 3])
                          - springs[r, 2] * y[c0 + nq + c])
    return rhs_kernel(y, *args)


@kernel
def _rms(x, scale):
    """sqrt(mean((x / scale)^2))."""
    s = 0.0
    for i in range(x.shape[0]):
        s += (x[i] / scale[i]) ** 2
    return math.sqrt(s / x.shape[0])


@kernel
def _initial_step(args, springs, hub_axis, hub_terms, t_end, y0, f0, rtol, atol):
    """scipy's select_initial_step (Hairer's II.4) for an error of order 8; and its one
    evaluation of the right-hand side."""
    scale = atol + np.abs(y0) * rtol
    d0, d1 = _rms(y0, scale), _rms(f0, scale)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, t_end)
    f1 = _rhs(y0 + h0 * f0, h0, args, springs, hub_axis, hub_terms)
    d2 = _rms(f1 - f0, scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (-_EXPONENT)
    return min(100.0 * h0, h1, t_end)


@kernel
def _stage_state(y, k, h, coefficients, count, out):
    """out = y + h sum_{j<count} c_j k_j: a stage's state (c = a_s., count = s) or the step's
    y1 (c = b, count = 12)."""
    for i in range(y.shape[0]):
        acc = 0.0
        for j in range(count):
            acc += coefficients[j] * k[j, i]
        out[i] = y[i] + h * acc


@kernel
def _error_norm(y, y1, k, h, rtol, atol):
    """DOP853's error estimate of the step (module docstring)."""
    n = y.shape[0]
    e5 = 0.0
    e3 = 0.0
    for i in range(n):
        sc = atol + max(abs(y[i]), abs(y1[i])) * rtol
        a5 = 0.0
        a3 = 0.0
        for j in range(_STAGES + 1):
            a5 += k[j, i] * _E5[j]
            a3 += k[j, i] * _E3[j]
        e5 += (a5 / sc) ** 2
        e3 += (a3 / sc) ** 2
    if e5 == 0.0 and e3 == 0.0:
        return 0.0
    return abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * n)


@kernel
def _dense_output(args, springs, hub_axis, hub_terms, t, h, y, y1, k, t_eval, first, last,
                  out):
    """The step's interpolant (module docstring) at t_eval[first:last], into out's rows."""
    n = y.shape[0]
    tmp = np.empty(n)
    for s in range(_STAGES + 1, 16):
        _stage_state(y, k, h, _A[s], s, tmp)
        put1(k[s], _rhs(tmp, t + _C[s] * h, args, springs, hub_axis, hub_terms))
    f = np.empty((7, n))
    for i in range(n):
        dy = y1[i] - y[i]
        f[0, i] = dy
        f[1, i] = h * k[0, i] - dy
        f[2, i] = 2.0 * dy - h * (k[_STAGES, i] + k[0, i])
        for r in range(4):
            acc = 0.0
            for j in range(16):
                acc += _D[r, j] * k[j, i]
            f[3 + r, i] = h * acc
    for p in range(first, last):
        x = (t_eval[p] - t) / h
        for i in range(n):
            v = 0.0
            for r in range(6, -1, -1):          # Horner's rule from F6, x and 1 - x by turns
                v += f[r, i]
                v *= x if (6 - r) % 2 == 0 else 1.0 - x
            out[p, i] = v + y[i]


@kernel(entry=True)
def integrate_dop853(args, springs, hub_axis, hub_terms, y0, t_end, rtol, atol, t_eval):
    """Integrate dy/dt = rhs_kernel(y, *args) (with the springs' forces and the spun ground's
    motion, hub_axis and hub_terms as hub.py's hub_table gives them: _rhs) from y0 at
    t = 0 to t_end (module docstring); returns the states at t_eval (increasing, within
    [0, t_end]; one row each), the number of steps and of right-hand sides, a status (OK, or
    STEP_TOO_SMALL: the step fell below ten spacings of the floating-point numbers at t, as
    scipy's) and the time reached."""
    n = y0.shape[0]
    ys = np.empty((t_eval.shape[0], n))
    k = np.empty((16, n))
    tmp = np.empty(n)
    y = y0.copy()
    f = _rhs(y, 0.0, args, springs, hub_axis, hub_terms)
    h_abs = _initial_step(args, springs, hub_axis, hub_terms, t_end, y, f, rtol, atol)
    nfev, n_steps = 2, 0
    p = 0
    while p < t_eval.shape[0] and t_eval[p] <= 0.0:
        put1(ys[p], y0)
        p += 1
    t = 0.0
    while t < t_end:
        min_step = 10.0 * (np.nextafter(t, np.inf) - t)
        h_abs = max(h_abs, min_step)
        rejected = False
        while True:
            if h_abs < min_step:
                return ys[:p], n_steps, nfev, STEP_TOO_SMALL, t
            t_new = min(t + h_abs, t_end)
            h = t_new - t
            h_abs = h
            put1(k[0], f)
            for s in range(1, _STAGES):
                _stage_state(y, k, h, _A[s], s, tmp)
                put1(k[s], _rhs(tmp, t + _C[s] * h, args, springs, hub_axis, hub_terms))
            y1 = np.empty(n)
            _stage_state(y, k, h, _B, _STAGES, y1)
            put1(k[_STAGES], _rhs(y1, t + h, args, springs, hub_axis, hub_terms))
            nfev += _STAGES
            err = _error_norm(y, y1, k, h, rtol, atol)
            if err < 1.0:
                factor = MAX_FACTOR if err == 0.0 else min(MAX_FACTOR,
                                                           SAFETY * err ** _EXPONENT)
                h_abs *= min(1.0, factor) if rejected else factor
                break
            # a step whose estimate is not finite shrinks as far as a rejected step may
            h_abs *= max(MIN_FACTOR, SAFETY * err ** _EXPONENT) if err < np.inf else MIN_FACTOR
            rejected = True
        last = p
        while last < t_eval.shape[0] and t_eval[last] <= t_new:
            last += 1
        if last > p:
            _dense_output(args, springs, hub_axis, hub_terms, t, h, y, y1, k, t_eval, p, last,
                          ys)
            nfev += 16 - _STAGES - 1
            p = last
        y = y1
        f = k[_STAGES].copy()
        t = t_new
        n_steps += 1
    return ys[:p], n_steps, nfev, OK, t
