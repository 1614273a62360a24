"""A ground spun about a fixed axis by a profile's angle, evaluated in compiled code for the
reference's integrator (integrator.py): the model's PrescribedMotion.spin_about_axis with a
dttmm.model.profiles Profile as its angle, read here as a table of terms, so that a run of a
driven hub (seed 000's spin-up, a scene's [ground.spin]) needs no Python between its right-hand
sides.

    angle(t) = sum of the terms' values (a "sum" profile's terms, flattened), each in closed
    form as dttmm/model/profiles.py gives it:
      constant  v                                     0                  0
      linear    o + s t                               s                  0
      sine      o + a sin(w t + p)                    a w cos(w t + p)   -a w^2 sin(w t + p)
      ramp      v min(t / d, 1)                       v / d (t < d)      0
      spin_up   (W / T)(t^2 / 2 + (cos(c t) - 1) / c^2),  c = 2 pi / T, for t <= T;
                W (t - T / 2) after                   its derivatives
    R(t) = exp(angle [n]x)   (n the unit axis; rotations.py's _expm: Rodrigues' formula)
    w(t) = angle'(t) n,   w'(t) = angle''(t) n;   the ground point fixed (v = a = 0)

A profile of any other kind (a table), of vector values, or an angle given as a plain function
is not read: such a run keeps scipy's solve_ivp, which calls the model's own functions.
"""
import math

import numpy as np

from ..kernels import kernel
from ..kernels.algebra.mat3 import put2
from ..model.profiles import Profile
from .rotations import _expm

CONSTANT, LINEAR, SINE, RAMP, SPIN_UP = 0, 1, 2, 3, 4
ROW = 5             # a term's row: [kind, its parameters (zero-padded)]


def _terms(angle):
    """The profile's terms as rows [kind, parameters...], or None where one is not a scalar
    term of a kind listed above."""
    if not isinstance(angle, Profile):
        return None
    if angle.kind == "sum":
        rows = [_terms(term) for term in angle.params["terms"]]
        return None if any(r is None for r in rows) else [row for r in rows for row in r]
    p = angle.params
    if any(np.ndim(value) != 0 for value in p.values()):
        return None
    if angle.kind == "constant":
        return [[CONSTANT, p["value"]]]
    if angle.kind == "linear":
        return [[LINEAR, p.get("offset", 0.0), p["slope"]]]
    if angle.kind == "sine":
        w = p["angular_frequency"] if "angular_frequency" in p else 2.0 * np.pi * p["frequency"]
        return [[SINE, p.get("offset", 0.0), p["amplitude"], w, p.get("phase", 0.0)]]
    if angle.kind == "ramp":
        return [[RAMP, p["value"], p["duration"]]]
    if angle.kind == "spin_up":
        return [[SPIN_UP, p["omega"], p["period"]]]
    return None


def hub_table(motion):
    """(axis (3,), terms (m, ROW)) of a ground spun by a profile's angle (module docstring); None
    for any other motion.  No motion at all: the axis zero and no terms (the ground still)."""
    if motion is None:
        return np.zeros(3), np.zeros((0, ROW))
    spin = getattr(motion, "spin", None)
    if spin is None:
        return None
    axis, angle, rate, acceleration = spin
    if rate != getattr(angle, "rate", None) or acceleration != getattr(angle, "acceleration",
                                                                         None):
        return None                     # derivatives of the user's own, not the profile's
    rows = _terms(angle)
    if rows is None:
        return None
    table = np.zeros((len(rows), ROW))
    for i, row in enumerate(rows):
        table[i, :len(row)] = [float(x) for x in row]
    return np.array(axis, dtype=float), table


@kernel
def _angle(terms, t):
    """The angle and its first two derivatives at t (module docstring)."""
    a = 0.0
    a_dot = 0.0
    a_ddot = 0.0
    for i in range(terms.shape[0]):
        kind = int(terms[i, 0])
        if kind == CONSTANT:
            a += terms[i, 1]
        elif kind == LINEAR:
            a += terms[i, 1] + terms[i, 2] * t
            a_dot += terms[i, 2]
        elif kind == SINE:
            amplitude, w = terms[i, 2], terms[i, 3]
            arg = w * t + terms[i, 4]
            a += terms[i, 1] + amplitude * math.sin(arg)
            a_dot += amplitude * w * math.cos(arg)
            a_ddot -= amplitude * w * w * math.sin(arg)
        elif kind == RAMP:
            value, duration = terms[i, 1], terms[i, 2]
            if t >= duration:
                a += value
            else:
                a += value * t / duration
                a_dot += value / duration
        else:                                           # SPIN_UP
            omega, period = terms[i, 1], terms[i, 2]
            if t > period:
                a += omega * (t - 0.5 * period)
                a_dot += omega
            else:
                c = 2.0 * math.pi / period
                a += omega / period * (0.5 * t * t + (math.cos(c * t) - 1.0) / (c * c))
                a_dot += omega / period * (t - math.sin(c * t) / c)
                a_ddot += omega / period * (1.0 - math.cos(c * t))
    return a, a_dot, a_ddot


@kernel
def spun_ground(axis, terms, t, rot, w, w_dot):
    """The hub's rotation, angular velocity and acceleration at t into rot, w, w_dot (module
    docstring); nothing for a still ground (no terms)."""
    if terms.shape[0] == 0:
        return
    a, a_dot, a_ddot = _angle(terms, t)
    put2(rot, _expm(a * axis))
    for i in range(3):
        w[i] = a_dot * axis[i]
        w_dot[i] = a_ddot * axis[i]
