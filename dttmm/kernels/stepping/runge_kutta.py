"""High-order integration of the acceleration-level sweep (issue 31; docs/integrators.md):
Dormand and Prince's explicit Runge-Kutta method of order 8 (DOP853: an embedded error
estimate of orders 5 and 3, a dense output of order 7), compiled with the fused loops' sweep
(kernels/stepping/ball_chain.py, tree.py), on the rotation group.

The state is [theta; omega; eta; eta'; x; v] with, per body, theta the rotation vector of
R = exp(theta^) R0 from the step's initial rotation R0 (local exponential coordinates,
recentred after every step: R0 <- exp(theta^) R0, theta <- 0) and omega the world angular
velocity, and per free joint (a root's: kernels/stepping/tree.py) its flight x (the state's
defl) and rate v; its derivative [J_l(theta)^-1 omega; omega'; eta'; eta''; v; a_I] takes the
accelerations from
one pass of the fused loop in its consistent-start form (ball_chain.start_loop: the coefficients
(1, 0, 0, 0) make a body's rotation slot its angular acceleration, and the pass solves the
accelerations of the given state).  Every rotation is exp of a skew matrix times an orthogonal
one: orthogonal to rounding, whatever the tolerance.

The method's coefficients are scipy's (scipy.integrate._ivp.dop853_coefficients), passed as
tables; the error norm and step control follow Hairer, Norsett and Wanner (scipy's DOP853).
"""
from types import FunctionType

import numpy as np
from numba import njit

from .. import (CONTRACT, fused_tables, model_tables, no_alloc_kernel, record_tables,
                runge_kutta_tables, state_tables, sweep_tables)
from ...elements.hinges import FREE
from ..schema import RUNGE_KUTTA_LAYOUT
from .ball_chain import record_state
from .loop import _VARIANTS, ERROR_ESTIMATE, OK, UNSUPPORTED
from ..algebra.mat3 import mm3_into
from ..algebra.so3 import expm_so3

N_STAGES = 12           # DOP853's stages (the 13th is the first of the next step: FSAL)
N_EXTENDED = 16         # ... with the three of its dense output
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
ERROR_EXPONENT = -1.0 / 8.0     # -1 / (order of the error estimate + 1)

def runge_kutta_scratch(n, n_eta, tables, n_free=0):
    """The scratch of an integration of n bodies, n_eta modal coordinates and n_free free
    joints' flights, with the tableau `tables` (dop853_tables) (kernels/schema.py::
    RUNGE_KUTTA)."""
    rk = RUNGE_KUTTA_LAYOUT.zeros(bodies=n, states=6 * n + 2 * n_eta + 6 * n_free)
    (rk.tableau_a[:], rk.tableau_b[:], rk.tableau_c[:], rk.error_e3[:], rk.error_e5[:],
     rk.dense_d[:]) = tables
    return rk


def dop853_tables():
    """scipy's DOP853 coefficients (A, B, C, E3, E5, D) as contiguous float arrays."""
    from scipy.integrate._ivp import dop853_coefficients as c
    return tuple(np.ascontiguousarray(a, dtype=float) for a in (c.A, c.B, c.C, c.E3, c.E5, c.D))


@njit(cache=True, inline='always', fastmath=CONTRACT)
def dexp_inverse(theta, omega, out, at):
    """out[at:at + 3] = J_l(theta)^-1 omega, the rate of the rotation vector theta of
    R = exp(theta^) R0 whose world angular velocity is omega:
    omega - theta x omega / 2 + c (theta x (theta x omega)),
    c = (1 - (x / 2) cot(x / 2)) / x^2, x = |theta| (its series below 1e-4 rad)."""
    t0, t1, t2 = theta[0], theta[1], theta[2]
    w0, w1, w2 = omega[0], omega[1], omega[2]
    x2 = t0 * t0 + t1 * t1 + t2 * t2
    if x2 < 1e-8:
        c = 1.0 / 12.0 + x2 / 720.0
    else:
        x = np.sqrt(x2)
        c = (1.0 - 0.5 * x * np.cos(0.5 * x) / np.sin(0.5 * x)) / x2
    a0, a1, a2 = t1 * w2 - t2 * w1, t2 * w0 - t0 * w2, t0 * w1 - t1 * w0     # theta x omega
    b0, b1, b2 = t1 * a2 - t2 * a1, t2 * a0 - t0 * a2, t0 * a1 - t1 * a0     # theta x a
    out[at] = w0 - 0.5 * a0 + c * b0
    out[at + 1] = w1 - 0.5 * a1 + c * b1
    out[at + 2] = w2 - 0.5 * a2 + c * b2


def _derivative(loop, run, info, rk, y, out):
    """out = the state y's derivative; the run's state holds y (rotations, rates, modal
    coordinates), its accelerations (state.omega_dot, state.eta_acc) and its stations
    (state.z); False where the sweep fails (info[0] says why)."""
    rot0 = runge_kutta_tables.rot0(rk)
    e3 = runge_kutta_tables.e3(rk)[0]
    per_body = fused_tables.per_body(loop)
    per_mode = fused_tables.per_mode(loop)
    state, sweep = run.state, run.sweep
    red_aq = sweep_tables.red_aq(sweep)
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    eta_acc = state_tables.eta_acc(state)
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    omega_dot = state_tables.omega_dot(state)
    n, m = rot.shape[0], eta.shape[0]
    w1, w3, phi_star, accel = per_body[0], per_body[1], per_body[2], per_body[3]
    hinge_kind = model_tables.hinge_kind(run.params)
    defl, defl_rate = state_tables.defl(state), state_tables.defl_rate(state)
    at = 6 * n + 2 * m                          # (the flights: a free root's x and v)
    for k in range(n):
        if hinge_kind[k] == FREE:
            for i in range(3):
                defl[k, i] = y[at + i]
                defl_rate[k, i] = y[at + 3 + i]
                out[at + i] = y[at + 3 + i]
            at += 6
    for k in range(n):
        expm_so3(y[3 * k:3 * k + 3], e3)
        mm3_into(e3, rot0[k], rot[k])
        for i in range(3):
            omega[k, i] = y[3 * n + 3 * k + i]
            w1[k, i] = 0.0                      # (ball_chain.start_loop)
            w3[k, i] = omega[k, i]
            phi_star[k, i] = 0.0
    for i in range(m):
        eta[i] = y[6 * n + i]
        eta_d[i] = y[6 * n + m + i]
        per_mode[0, i] = -eta[i]
        per_mode[1, i] = eta_d[i]
        per_mode[3, i] = 0.0
    red_aq[:, :] = 0.0
    # the skeleton's consistent-start pass (loop.py::_run_steps with settings.start): one
    # iterate, then finish writes the stations; the variant's pieces are bound by _integrator
    status, detail, _ = iterate(loop, run, 0, 0)        # noqa: F821
    if status != OK:
        info[0], info[2] = status, detail
        return False
    finish(loop, run, 1, 0)                             # noqa: F821
    info[0] = OK
    for k in range(n):
        dexp_inverse(y[3 * k:3 * k + 3], omega[k], out, 3 * k)
        for i in range(3):
            omega_dot[k, i] = accel[k, i]
            out[3 * n + 3 * k + i] = accel[k, i]
    for i in range(m):
        eta_acc[i] = per_mode[4, i]
        out[6 * n + i] = eta_d[i]
        out[6 * n + m + i] = per_mode[4, i]
    at = 6 * n + 2 * m
    for k in range(n):
        if hinge_kind[k] == FREE:               # v' = a_I, the root's input acceleration
            for i in range(3):
                out[at + 3 + i] = red_aq[k, i]
            at += 6
    return True


@njit(cache=True, inline='always', fastmath=CONTRACT)
def _scale(y, y_new, n_rot, rtol, atol, i):
    """The error's scale of component i: atol + rtol max(|y|, |y_new|), and atol + rtol for a
    rotation vector (a motion of order one radian: the rotations' local coordinates start
    from zero each step)."""
    if i < n_rot:
        return atol + rtol
    return atol + rtol * max(abs(y[i]), abs(y_new[i]))


def _start(loop, run, info, rk, rtol, atol, first_step, t_end):
    """rk's state from the run's (theta = 0) and its derivative; the first step: first_step
    where given (> 0), else Hairer-Norsett-Wanner's choice from the derivative's size
    (II.4, scipy's select_initial_step).  False where the sweep fails."""
    control = runge_kutta_tables.control(rk)
    y = runge_kutta_tables.y(rk)
    f = runge_kutta_tables.f(rk)
    rot0 = runge_kutta_tables.rot0(rk)
    y_stage = runge_kutta_tables.y_stage(rk)
    stages = runge_kutta_tables.k(rk)
    state = run.state
    eta = state_tables.eta(state)
    eta_d = state_tables.eta_d(state)
    rot = state_tables.rot(state)
    omega = state_tables.omega(state)
    n, m = rot.shape[0], eta.shape[0]
    for k in range(n):
        for i in range(3):
            y[3 * k + i] = 0.0
            y[3 * n + 3 * k + i] = omega[k, i]
            for j in range(3):
                rot0[k, i, j] = rot[k, i, j]
    for i in range(m):
        y[6 * n + i] = eta[i]
        y[6 * n + m + i] = eta_d[i]
    hinge_kind = model_tables.hinge_kind(run.params)
    defl, defl_rate = state_tables.defl(state), state_tables.defl_rate(state)
    at = 6 * n + 2 * m
    for k in range(n):
        if hinge_kind[k] == FREE:
            for i in range(3):
                y[at + i] = defl[k, i]
                y[at + 3 + i] = defl_rate[k, i]
            at += 6
    if not _derivative(loop, run, info, rk, y, f):
        return False
    h = first_step
    if not h > 0.0:
        size = y.shape[0]
        d0, d1 = 0.0, 0.0
        for i in range(size):
            sc = _scale(y, y, 3 * n, rtol, atol, i)
            d0 += (y[i] / sc) ** 2
            d1 += (f[i] / sc) ** 2
        d0, d1 = np.sqrt(d0 / size), np.sqrt(d1 / size)
        h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
        h0 = min(h0, t_end)
        if not h0 > 1e-12 * t_end:
            h0 = 1e-12 * t_end
        for i in range(size):
            y_stage[i] = y[i] + h0 * f[i]
        if not _derivative(loop, run, info, rk, y_stage, stages[1]):
            return False
        d2 = 0.0
        for i in range(size):
            d2 += ((stages[1, i] - f[i]) / _scale(y, y, 3 * n, rtol, atol, i)) ** 2
        d2 = np.sqrt(d2 / size) / h0
        if max(d1, d2) <= 1e-15:
            h1 = max(1e-6, 1e-3 * h0)
        else:
            h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
        h = min(100.0 * h0, h1)
    control[0], control[1] = 0.0, h
    control[2:6] = 0.0
    control[6], control[7] = np.inf, 0.0
    return True


def _steps(loop, run, info, rk, times, rec, sample_steps, rtol, atol, h_min):
    """Steps from rk's t (rk.control[0]) until every time in `times` (increasing, after t; the
    last one ends the chunk) is recorded into rec's slots (its state by the dense output, its
    accelerations and stations by one more pass of the sweep) and sample_steps (the steps
    taken by then).  info: [status, steps, the failing pass's status, samples recorded, passes];
    a step is taken again with a quarter of its length where a pass fails, and the run stops
    with ERROR_ESTIMATE once the step falls below h_min.  rtol = 0: fixed steps of rk's h (no
    error estimate; its last step lands on the chunk's end)."""
    a = runge_kutta_tables.tableau_a(rk)   # (the nodes c unread: the models it runs have
    b = runge_kutta_tables.tableau_b(rk)   # no time-dependent input, _check_runge_kutta)
    e3_w = runge_kutta_tables.error_e3(rk)
    e5_w = runge_kutta_tables.error_e5(rk)
    d = runge_kutta_tables.dense_d(rk)
    control = runge_kutta_tables.control(rk)
    y = runge_kutta_tables.y(rk)
    f = runge_kutta_tables.f(rk)
    y_new = runge_kutta_tables.y_new(rk)
    y_stage = runge_kutta_tables.y_stage(rk)
    kk = runge_kutta_tables.k(rk)
    dense = runge_kutta_tables.dense(rk)
    e3_pair = runge_kutta_tables.e3(rk)
    rot0 = runge_kutta_tables.rot0(rk)
    rec_z = record_tables.z(rec)
    rec_defl, rec_defl_rate = record_tables.defl(rec), record_tables.defl_rate(rec)
    state = run.state
    rot = state_tables.rot(state)
    z = state_tables.z(state)
    defl, defl_rate = state_tables.defl(state), state_tables.defl_rate(state)
    n = rot.shape[0]
    size = y.shape[0]
    t, h = control[0], control[1]
    rejected_last = False
    n_rec = 0
    t_last = times[times.shape[0] - 1]
    while n_rec < times.shape[0]:
        h = min(h, t_last - t)
        if t + h > t_last - 1e-12 * abs(t_last):      # (land on the chunk's end)
            h = t_last - t
        # the stages (FSAL: the first is the last step's end)
        for i in range(size):
            kk[0, i] = f[i]
        failed = False
        for s in range(1, N_STAGES + 1):
            target = y_new if s == N_STAGES else y_stage
            for i in range(size):
                acc = 0.0
                for j in range(s):
                    acc += (b[j] if s == N_STAGES else a[s, j]) * kk[j, i]
                target[i] = y[i] + h * acc
            control[4] += 1.0
            if not _derivative(loop, run, info, rk, target, kk[s]):
                failed = True
                break
        err = np.inf
        if not failed and not rtol > 0.0:   # fixed steps: every step taken, none changed
            err = -1.0
        elif not failed:
            e5, e3 = 0.0, 0.0
            for i in range(size):
                x5, x3 = 0.0, 0.0
                for j in range(N_STAGES + 1):
                    x5 += e5_w[j] * kk[j, i]
                    x3 += e3_w[j] * kk[j, i]
                sc = _scale(y, y_new, 3 * n, rtol, atol, i)
                e5 += (x5 / sc) ** 2
                e3 += (x3 / sc) ** 2
            err = 0.0 if e5 == 0.0 and e3 == 0.0 else abs(h) * e5 / np.sqrt(
                (e5 + 0.01 * e3) * size)
        elif info[0] == UNSUPPORTED or not rtol > 0.0:     # (fixed steps stop at once)
            info[1], info[3] = int(control[2]), n_rec
            control[0], control[1] = t, h
            return
        if not err < 1.0:
            control[3] += 1.0
            factor = 0.25 if failed or not rtol > 0.0 else max(
                MIN_FACTOR, SAFETY * err ** ERROR_EXPONENT)
            h *= factor
            rejected_last = True
            if h < h_min:
                info[2] = info[0] if failed else OK
                info[0] = ERROR_ESTIMATE
                control[0], control[1] = t, h
                info[1], info[3] = int(control[2]), n_rec
                return
            continue
        # accepted: the samples in (t, t + h] from the dense output, before the recentring
        t_new = t + h
        if n_rec < times.shape[0] and times[n_rec] <= t_new:
            for s in range(N_STAGES + 1, N_EXTENDED):
                for i in range(size):
                    acc = 0.0
                    for j in range(s):
                        acc += a[s, j] * kk[j, i]
                    y_stage[i] = y[i] + h * acc
                control[4] += 1.0
                if not _derivative(loop, run, info, rk, y_stage, kk[s]):
                    info[1], info[2], info[3] = int(control[2]), info[0], n_rec
                    return
            for i in range(size):
                dy = y_new[i] - y[i]
                dense[0, i] = dy
                dense[1, i] = h * kk[0, i] - dy
                dense[2, i] = 2.0 * dy - h * (kk[N_STAGES, i] + kk[0, i])
                for r in range(4):
                    acc = 0.0
                    for j in range(N_EXTENDED):
                        acc += d[r, j] * kk[j, i]
                    dense[3 + r, i] = h * acc
            while n_rec < times.shape[0] and times[n_rec] <= t_new:
                x = (times[n_rec] - t) / h
                for i in range(size):
                    v = 0.0
                    for r in range(6, -1, -1):
                        v += dense[r, i]
                        v *= x if (6 - r) % 2 == 0 else 1.0 - x
                    y_stage[i] = y[i] + v
                control[4] += 1.0
                if not _derivative(loop, run, info, rk, y_stage, kk[N_STAGES + 1]):
                    info[1], info[2], info[3] = int(control[2]), info[0], n_rec
                    return
                record_state(state, rec, n_rec)
                for k in range(defl.shape[0]):          # (the free joints' flights)
                    for i in range(3):
                        rec_defl[n_rec, k, i] = defl[k, i]
                        rec_defl_rate[n_rec, k, i] = defl_rate[k, i]
                for st in range(z.shape[0]):
                    for i in range(12):
                        rec_z[n_rec, st, i] = z[st, i]
                sample_steps[n_rec] = int(control[2]) + 1
                n_rec += 1
        # recentre: R0 <- exp(theta^) R0, theta <- 0; the next step's first stage is this
        # step's end, its rotation rate J_l(0)^-1 omega = omega
        e3, before = e3_pair[0], e3_pair[1]
        for k in range(n):
            expm_so3(y_new[3 * k:3 * k + 3], e3)
            for i in range(3):
                for j in range(3):
                    before[i, j] = rot0[k, i, j]
            mm3_into(e3, before, rot0[k])
        for i in range(size):
            y[i] = y_new[i]
            f[i] = kk[N_STAGES, i]
        for k in range(n):
            for i in range(3):
                y[3 * k + i] = 0.0
                f[3 * k + i] = y[3 * n + 3 * k + i]
        control[2] += 1.0
        control[6] = min(control[6], h)
        control[7] = max(control[7], h)
        t = t_new
        factor = (1.0 if err < 0.0 else MAX_FACTOR if err == 0.0
                  else min(MAX_FACTOR, SAFETY * err ** ERROR_EXPONENT))
        if rejected_last:
            factor = min(1.0, factor)
        rejected_last = False
        h *= factor
    control[0], control[1] = t, h
    info[0], info[1], info[3] = OK, int(control[2]), n_rec
    info[4] = int(control[4])


_INTEGRATORS = {}


def _integrator(function, loop_class):
    """function (_start or _steps) with _derivative bound to a loop variant's pieces (iterate,
    finish: inlined), compiled (and cached) on its own without numba's reference counting (it
    allocates nothing), as loop.py::_skeleton binds them into the step's skeleton."""
    key = (function.__name__, loop_class)
    compiled = _INTEGRATORS.get(key)
    if compiled is None:
        pieces = _VARIANTS.get(loop_class)
        if pieces is None:
            raise TypeError(f"runge_kutta: no loop variant declares {loop_class.__name__}")
        suffix = loop_class.__name__
        env = dict(globals(), iterate=pieces["iterate"], finish=pieces["finish"])
        derivative = FunctionType(_derivative.__code__, env, f"_derivative_{suffix}")
        derivative.__qualname__ = derivative.__name__
        env["_derivative"] = no_alloc_kernel(derivative)
        fn = FunctionType(function.__code__, env, f"{function.__name__}_{suffix}")
        fn.__qualname__ = fn.__name__   # (numba's cache files are named after it)
        fn.__doc__ = function.__doc__
        compiled = _INTEGRATORS[key] = no_alloc_kernel(fn, entry=True)
    return compiled


def start(loop, run, info, rk, rtol, atol, first_step, t_end):
    """_start for the loop's variant."""
    return _integrator(_start, type(loop))(loop, run, info, rk, rtol, atol, first_step, t_end)


def steps(loop, run, info, rk, times, rec, sample_steps, rtol, atol, h_min):
    """_steps for the loop's variant."""
    _integrator(_steps, type(loop))(loop, run, info, rk, times, rec, sample_steps, rtol, atol,
                                    h_min)
