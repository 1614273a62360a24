"""Named functions of time for loads, drives and ground motion (docs/scenes.md, "Profiles"):
each gives its value, rate and acceleration in closed form (a prescribed motion needs all three,
not numerical derivatives) and says what it is (spec), so that a model built from them can be
written back to a scene file.

    profile({"profile": "sine", "amplitude": 2.0, "frequency": 0.5})      # 2 sin(pi t)
    profile({"profile": "spin_up", "omega": 6.0, "period": 15.0})        # seed 000's hub angle

Kinds (values may be scalars or vectors of one length):
  constant   value
  linear     offset + slope t
  sine       offset + amplitude sin(w t + phase), w = angular_frequency (rad/s) or
             2 pi frequency (Hz)
  ramp       value min(t / duration, 1)                              (from 0 to value)
  pulse      value for 0 <= t < duration, then 0; value / 2 at t = duration itself (the
             trapezoidal rule's impulse over a step ending or starting there is then exact)
  spin_up    (omega / T)(t^2 / 2 + (T / 2 pi)^2 (cos(2 pi t / T) - 1)) for t <= T = period,
             then omega (t - T / 2): a hub angle reaching the rate omega smoothly at T
  table      linear interpolation of values at times t (held beyond them)
  sum        the sum of the profiles in terms
"""
import numpy as np

KINDS = ("constant", "linear", "sine", "ramp", "pulse", "spin_up", "table", "sum")


class Profile:
    """A function of time with its first two derivatives (closed form) and its spec.

    Made by ``profile(spec)``, which checks the parameters; called as ``p(t)``, with
    ``p.rate(t)`` and ``p.acceleration(t)``, it serves as a load (``RigidBody(force=p)``), a
    prescribed motion (``JointMotion(p, p.rate, p.acceleration)``), a joint force
    (``JointForce(ProfileForce(p))``) or a ground spin angle.  The units are those of what it
    stands for (values in N, N m, rad or m; times in s).

    Parameters
    ----------
    kind : str
        One of the module's kinds: "constant", "linear", "sine", "ramp", "pulse", "spin_up",
        "table", "sum".
    **params
        The kind's parameters, checked by ``profile`` (not here): numbers or arrays of one
        length, "terms" a list of Profiles.

    Examples
    --------
    >>> from dttmm.model.profiles import profile
    >>> p = profile({"profile": "ramp", "value": 2.0, "duration": 0.5})
    >>> p(0.25), p.rate(0.25), p.acceleration(0.25), p(1.0)
    (1.0, 4.0, 0.0, 2.0)
    """

    def __init__(self, kind, **params):
        self.kind = kind
        self.params = params

    def spec(self):
        """The table that makes this profile again (``profile(spec)``).

        Returns
        -------
        dict
            {"profile": kind, parameter: value, ...}, arrays as lists, "terms" as their
            specs.
        """
        out = {"profile": self.kind}
        for key, value in self.params.items():
            if key == "terms":
                out[key] = [term.spec() for term in value]
            else:
                out[key] = value.tolist() if isinstance(value, np.ndarray) else value
        return out

    def __repr__(self):
        return f"profile({self.spec()!r})"

    def __call__(self, t):
        """The value at time t (s): a float, or an ndarray for vector parameters."""
        return self._eval(float(t), 0)

    def rate(self, t):
        """The first derivative at time t (s), per second, in closed form.

        Parameters
        ----------
        t : float
            Time, s.

        Returns
        -------
        float or ndarray
            d/dt of the value (at a ramp's or a table's knot, the slope of the piece after
            it; zero after a ramp, and at and beyond a table's first and last times).
        """
        return self._eval(float(t), 1)

    def acceleration(self, t):
        """The second derivative at time t (s), per second squared, in closed form.

        Parameters
        ----------
        t : float
            Time, s.

        Returns
        -------
        float or ndarray
            d^2/dt^2 of the value (zero for the piecewise-linear ramp and table).
        """
        return self._eval(float(t), 2)

    def _eval(self, t, order):
        p = self.params
        kind = self.kind
        if kind == "constant":
            return p["value"] * (1.0 if order == 0 else 0.0)
        if kind == "linear":
            return (p.get("offset", 0.0) + p["slope"] * t, p["slope"] + 0.0 * t,
                    0.0 * p["slope"])[order]
        if kind == "sine":
            w = p["angular_frequency"] if "angular_frequency" in p else 2.0 * np.pi * p["frequency"]
            arg = w * t + p.get("phase", 0.0)
            a = p["amplitude"]
            return (p.get("offset", 0.0) + a * np.sin(arg), a * w * np.cos(arg),
                    -a * w * w * np.sin(arg))[order]
        if kind == "ramp":
            d, v = p["duration"], p["value"]
            if t >= d:
                return (v, 0.0 * v, 0.0 * v)[order]
            return (v * t / d, v / d, 0.0 * v)[order]
        if kind == "pulse":
            d, v = p["duration"], p["value"]
            at_switch = abs(t - d) <= 1e-9 * d
            return ((0.5 * v if at_switch else v if t < d else 0.0 * v), 0.0 * v,
                    0.0 * v)[order]
        if kind == "spin_up":
            om, per = p["omega"], p["period"]
            if t > per:
                return (om * (t - 0.5 * per), om, 0.0)[order]
            c = 2.0 * np.pi / per
            if order == 0:
                return om / per * (0.5 * t * t + (np.cos(c * t) - 1.0) / (c * c))
            if order == 1:
                return om / per * (t - np.sin(c * t) / c)
            return om / per * (1.0 - np.cos(c * t))
        if kind == "table":
            times, values = p["t"], p["value"]
            i = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2))
            if t <= times[0] or t >= times[-1]:
                end = values[0] if t <= times[0] else values[-1]
                return (end, 0.0 * end, 0.0 * end)[order]
            slope = (values[i + 1] - values[i]) / (times[i + 1] - times[i])
            return (values[i] + slope * (t - times[i]), slope, 0.0 * slope)[order]
        if kind == "sum":
            return sum(term._eval(t, order) for term in p["terms"])
        raise AssertionError(kind)


# each kind's parameters: (required, optional)
_PARAMS = {"constant": (("value",), ()), "linear": (("slope",), ("offset",)),
           "sine": (("amplitude",), ("frequency", "angular_frequency", "phase", "offset")),
           "ramp": (("value", "duration"), ()), "pulse": (("value", "duration"), ()),
           "spin_up": (("omega", "period"), ()),
           "table": (("t", "value"), ()), "sum": (("terms",), ())}


def profile(spec, where="profile"):
    """The Profile a table describes (docs/scenes.md, "Profiles").

    Parameters
    ----------
    spec : dict, float or Profile
        A table {"profile": KIND, key: value, ...} with the kind's keys (module docstring):
        constant (value), linear (slope; offset), sine (amplitude, and one of frequency in Hz
        or angular_frequency in rad/s; phase in rad, offset), ramp and pulse (value,
        duration in s),
        spin_up (omega in rad/s, period in s), table (t: at least two increasing times, s;
        value: one per time), sum (terms: a non-empty list of profiles).  Values are numbers
        or lists of numbers of one length (a vector profile: a force, a torque).  A number
        stands for a constant profile; a Profile is returned as it is.
    where : str, optional
        How messages name the profile (default "profile"; the scene reader passes the file,
        the table and the key).

    Returns
    -------
    Profile
        The checked profile.

    Raises
    ------
    ValueError
        Naming `where` and the key: not a number or a table with the key "profile"; an
        unknown kind; a missing or unknown key; a value that is not finite numbers; a sine
        with neither or both of frequency and angular_frequency; a duration or period not
        > 0; table times not at least two and increasing, or values not one per time.

    Examples
    --------
    >>> from dttmm.model.profiles import profile
    >>> p = profile({"profile": "sine", "amplitude": 2.0, "frequency": 0.5})   # 2 sin(pi t)
    >>> float(p(0.5)), round(float(p.rate(0.0)), 6)
    (2.0, 6.283185)
    >>> profile({"profile": "spin_up", "omega": 6.0, "period": 15.0}).rate(20.0)
    6.0
    """
    if isinstance(spec, Profile):
        return spec
    if isinstance(spec, (int, float)) and not isinstance(spec, bool):
        return Profile("constant", value=float(spec))
    if not isinstance(spec, dict) or "profile" not in spec:
        raise ValueError(f"{where}: a profile is a number or a table with a key 'profile' (one "
                         f"of {', '.join(KINDS)}), got {spec!r}")
    kind = spec["profile"]
    if kind not in _PARAMS:
        raise ValueError(f"{where}: key 'profile': unknown profile {kind!r} (one of "
                         f"{', '.join(KINDS)})")
    required, optional = _PARAMS[kind]
    given = set(spec) - {"profile"}
    for key in required:
        if key not in given:
            raise ValueError(f"{where}: the {kind} profile needs the key '{key}'")
    unknown = given - set(required) - set(optional)
    if unknown:
        raise ValueError(f"{where}: key '{sorted(unknown)[0]}' is not a parameter of the {kind} "
                         f"profile (it takes {', '.join(required + optional)})")
    params = {}
    for key in sorted(given, key=lambda k: (required + optional).index(k)):
        value = spec[key]
        if key == "terms":
            if not isinstance(value, list) or not value:
                raise ValueError(f"{where}: key 'terms': a list of profiles")
            params[key] = [profile(term, f"{where}, terms[{i}]") for i, term in enumerate(value)]
            continue
        params[key] = _numbers(value, f"{where}: key '{key}'")
    if kind == "sine" and ("frequency" in params) == ("angular_frequency" in params):
        raise ValueError(f"{where}: the sine profile needs one of 'frequency' (Hz) and "
                         f"'angular_frequency' (rad/s)")
    for key in ("duration", "period"):
        if key in params and not np.all(params[key] > 0):
            raise ValueError(f"{where}: key '{key}' must be > 0 (s), got {spec[key]!r}")
    if kind == "table":
        t = np.atleast_1d(params["t"])
        if t.ndim != 1 or len(t) < 2 or np.any(np.diff(t) <= 0):
            raise ValueError(f"{where}: key 't': at least two increasing times, s")
        if np.ndim(params["value"]) == 0 or len(params["value"]) != len(t):
            raise ValueError(f"{where}: key 'value': one value per time ({len(t)}), got "
                             f"{spec['value']!r}")
    return Profile(kind, **params)


def _numbers(value, where):
    try:
        out = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{where}: a number or a list of numbers, got {value!r}") from None
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{where}: finite numbers, got {value!r}")
    return float(out) if out.ndim == 0 else out


class ProfileForce:
    """A joint drive's generalized force f(t, q, q') = profile(t) (elements/drives.JointForce).

    A function of time only that ``save_scene`` can write (a scene's drive of type "force").

    Parameters
    ----------
    prof : Profile
        The force against time, N m (revolute, universal) or N (prismatic).

    Examples
    --------
    >>> import dttmm
    >>> from dttmm.model.profiles import ProfileForce, profile
    >>> torque = profile({"profile": "ramp", "value": 1.0, "duration": 2.0})
    >>> drive = dttmm.JointForce(ProfileForce(torque))
    """

    of_time_only = True         # (elements/drives.py: it runs inside the compiled loop)

    def __init__(self, prof):
        self.profile = prof

    def __call__(self, t, q, q_dot):
        return self.profile(t)
