"""Joint drives: what acts along a joint's free coordinate (docs/joints.md, "Drives").

A drive sits on one coordinate q of a revolute joint (an angle, rad), of a prismatic joint (a
slide, m) or of one axis of a universal joint.  It either applies a generalized force (a torque
about the axis, N m, or a force along it, N) on the child, with the reaction on the parent, or
prescribes the coordinate's motion q(t), the joint then applying whatever generalized force
that motion needs (the Result records it).

Forces that are linear in (q, q') with the rest known in time run inside the compiled loop,
chunk by chunk (kernels/transfers/joint.py::drive_value: -k (q - rest) - c q' + f(t)): a
SpringDamper, a PDTracking (k = kp, c = kd, f = kp target + kd target' + feedforward) and a
JointForce of time alone (a profiles.ProfileForce, a scene's force profile), and a JointForce whose
function is numba-compiled (@numba.njit): the loop calls it at every iteration of every step,
through a C callback of FORCE_SIGNATURE (compiled_force), linearized by differences
(kernels/transfers/joint.py::drive_value).  A JointForce of (t, q, q') given as a Python function is
called by the solver once per step.
"""
import threading
from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from ._checks import derivative, finite_scalar, is_text

FORCE, SPRING_DAMPER, MOTION, PD = 0, 1, 2, 3      # a drive's kind (None: no drive)
COMPILED_FORCE = 4      # (the kernels' table only: a FORCE drive whose function is compiled)
FORCE_SIGNATURE = "float64(float64, float64, float64)"     # a compiled f(t, q, q_dot)

_CALLBACKS = {}         # id(numba function) -> (it, its C callback of FORCE_SIGNATURE)
_CALLBACK_LOCK = threading.Lock()


def is_numba_function(function):
    """Whether function is a numba-compiled (@numba.njit) function."""
    from numba.core.registry import CPUDispatcher
    return isinstance(function, CPUDispatcher)


def compiled_force(function):
    """The C callback of FORCE_SIGNATURE of a numba function f(t, q, q_dot), which the compiled
    loop calls (kernels/transfers/joint.py::drive_value), compiled with the function's own options
    (fastmath, error_model, boundscheck); once per process and function (a model pickled to
    another process carries the numba function, not the callback), and kept for the process's
    life (the loop holds its address).  An exception raised inside it cannot stop the loop (a C
    callback returns a number): the loop's checks stop a run whose force is not finite."""
    with _CALLBACK_LOCK:
        entry = _CALLBACKS.get(id(function))
        if entry is None:
            from numba import cfunc
            options = {k: v for k, v in function.targetoptions.items()
                       if k in ("fastmath", "error_model", "boundscheck")}
            entry = _CALLBACKS[id(function)] = (function, cfunc(FORCE_SIGNATURE, **options)(
                function.py_func))
    return entry[1]


def _scalar_of(who, argument, value):
    if is_text(value):
        raise ValueError(f"{who}: {argument} must return a number, got {value!r} (text)")
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{who}: {argument} must return a number, got {value!r}") from None
    if a.size != 1:
        raise ValueError(f"{who}: {argument} must return one number, got shape {a.shape}")
    x = float(a.reshape(-1)[0])
    if not np.isfinite(x):
        raise ValueError(f"{who}: {argument} returned {x} (not finite)")
    return x


@dataclass(frozen=True, eq=False)
class JointForce:
    """A generalized force f(t, q, q') on the joint's coordinate (docs/joints.md, "Drives").

    N m about a revolute or universal axis, N along a prismatic axis, on the child, with its
    reaction on the parent: a motor torque f(t), a nonlinear spring, any function of time,
    coordinate and rate.  ``simulate`` evaluates it once per step, at the coordinates the
    constant-acceleration predictor gives (docs/joints.md, "In the transfer");
    ``Result.drive_force`` records its values.

    Parameters
    ----------
    function : callable
        function(t, q, q_dot) -> one number: t in s, q in rad (or m), q_dot in rad/s (or m/s);
        returns the generalized force, N m (or N).  Called at (0, q0, q_dot0) when the model is
        built.  A numba-compiled function (``@numba.njit``, of three floats returning a float)
        runs inside the compiled loop, at every Newton iteration of every step (a feedback law
        then costs no Python per step); a Python function is called once per step, each step
        then one compiled call (docs/joints.md, "Which drives run inside the compiled loop").

    Raises
    ------
    ValueError
        At build time, naming the joint: function not callable, not taking (t, q, q_dot), or
        not returning one finite number at t = 0.  During a run, a value that is not finite
        stops ``simulate`` (``DivergenceError``) and ``simulate_reference`` (ValueError naming
        the joint and the coordinate).

    Examples
    --------
    A motor torque of 2 N m for the first second, with viscous friction 0.01 N m s/rad:

    >>> import dttmm
    >>> motor = dttmm.JointForce(lambda t, q, q_dot: (2.0 if t < 1.0 else 0.0) - 0.01 * q_dot)
    >>> joint = dttmm.RevoluteJoint(axis=[0, 0, 1], drive=motor)

    A feedback law compiled with numba, which runs inside the compiled loop:

    >>> import numba, numpy as np
    >>> @numba.njit
    ... def servo(t, q, q_dot):
    ...     return 200.0 * (0.5 * np.sin(t) - q) - 20.0 * q_dot
    >>> joint = dttmm.RevoluteJoint(axis=[0, 0, 1], drive=dttmm.JointForce(servo))
    """
    function: Callable[[float, float, float], float]
    kind = FORCE

    def validated(self, who, q0, qd0):
        if not callable(self.function):
            raise ValueError(f"{who}: drive function must be callable as f(t, q, q_dot), got "
                             f"{type(self.function).__name__}")
        try:
            value = self.function(0.0, q0, qd0)
        except TypeError as err:
            raise ValueError(f"{who}: drive function must take (t, q, q_dot): {err}") from None
        except Exception as err:
            if not is_numba_function(self.function):
                raise
            raise ValueError(f"{who}: drive function is a numba function that does not compile "
                             f"as f(t, q, q_dot) of three floats ({type(err).__name__}: "
                             f"{str(err).splitlines()[0] if str(err) else ''})") from None
        _scalar_of(who, "drive function(0, q0, q_dot0)", value)
        compiled = is_numba_function(self.function)
        if compiled:
            try:
                compiled_force(self.function)
            except Exception as err:
                raise ValueError(f"{who}: drive function is a numba function that does not "
                                 f"compile with the signature {FORCE_SIGNATURE} "
                                 f"({type(err).__name__}: {str(err).splitlines()[0]})") from None
        return dict(kind=FORCE, function=self.function, stiffness=0.0, damping=0.0, rest=0.0,
                    of_time=bool(getattr(self.function, "of_time_only", False)),
                    compiled=compiled)


@dataclass(frozen=True, eq=False)
class SpringDamper:
    """A linear spring and damper on the joint's coordinate: f = -stiffness (q - rest) -
    damping q' (docs/joints.md, "Drives").

    Its potential 1/2 stiffness (q - rest)^2 counts in the result's energies.

    Parameters
    ----------
    stiffness : float
        k, N m/rad about a revolute or universal axis, N/m along a prismatic one (>= 0).
    damping : float, optional
        c, N m s/rad (or N s/m), >= 0; default 0.
    rest : float, optional
        The coordinate at which the spring is relaxed, rad (or m).  None (default): the
        coordinate's initial value (no force at the start).

    Raises
    ------
    ValueError
        At build time, naming the joint and the argument ("drive stiffness", "drive damping",
        "drive rest"): not a finite number, or a negative stiffness or damping.

    Examples
    --------
    >>> import dttmm
    >>> torsion = dttmm.SpringDamper(stiffness=5.0, damping=0.05, rest=0.0)
    >>> joint = dttmm.RevoluteJoint(axis=[0, 0, 1], angle=0.3, drive=torsion)
    """
    stiffness: float
    damping: float = 0.0
    rest: Optional[float] = None
    kind = SPRING_DAMPER

    def validated(self, who, q0, qd0):
        k = finite_scalar(who, "drive stiffness", self.stiffness, nonnegative=True)
        c = finite_scalar(who, "drive damping", self.damping, nonnegative=True)
        rest = q0 if self.rest is None else finite_scalar(who, "drive rest", self.rest)
        return dict(kind=SPRING_DAMPER, function=None, stiffness=k, damping=c, rest=rest)


@dataclass(frozen=True, eq=False)
class JointMotion:
    """The coordinate prescribed: position(t), velocity(t), acceleration(t) (docs/joints.md,
    "Drives").

    The derivatives are given, not differentiated numerically; the joint applies whatever
    generalized force the motion needs (``Result.drive_force``), and starts on the motion (its
    initial coordinate and rate are position(0) and velocity(0)).

    Parameters
    ----------
    position : callable
        position(t) -> one number: the coordinate at time t (s), rad (or m).
    velocity : callable
        velocity(t) -> its first derivative, rad/s (or m/s).  Required, although it defaults
        to None.
    acceleration : callable
        acceleration(t) -> its second derivative, rad/s^2 (or m/s^2).  Required, although it
        defaults to None.

    Raises
    ------
    ValueError
        At build time, naming the joint: a function missing or not callable, or not returning
        one finite number at t = 0; velocity or acceleration contradicting the difference
        (step 1e-5 s; a forward one at t = 0, so no function is called before t = 0) of the
        function before it at t = 0, 0.37 and 1 s by more than 1e-4 max(1, |difference|); a
        joint's initial value given (nonzero) that differs from the motion's at t = 0.  During
        ``simulate_reference``, a value that is not one finite number (ValueError naming the
        joint and the coordinate).

    Examples
    --------
    A crank turned at 2 rad/s:

    >>> import dttmm
    >>> crank = dttmm.JointMotion(position=lambda t: 2.0 * t, velocity=lambda t: 2.0,
    ...                           acceleration=lambda t: 0.0)
    >>> joint = dttmm.RevoluteJoint(axis=[0, 0, 1], drive=crank)
    """
    position: Callable[[float], float]
    velocity: Optional[Callable[[float], float]] = None
    acceleration: Optional[Callable[[float], float]] = None
    kind = MOTION

    def validated(self, who, q0, qd0):
        for name in ("position", "velocity", "acceleration"):
            f = getattr(self, name)
            if f is None:
                raise ValueError(f"{who}: a prescribed joint motion needs its {name} (a function "
                                 f"of time; give position, velocity and acceleration)")
            if not callable(f):
                raise ValueError(f"{who}: prescribed {name} must be a function of time")
            _scalar_of(who, f"prescribed {name}(0)", f(0.0))
        eps = 1e-5
        for t in (0.0, 0.37, 1.0):
            for name, f, deriv in (("velocity", self.position, self.velocity),
                                   ("acceleration", self.velocity, self.acceleration)):
                numeric = float(derivative(lambda s: _scalar_of(who, name, f(s)), t, eps))
                given = _scalar_of(who, f"prescribed {name}({t:g})", deriv(t))
                if abs(given - numeric) > 1e-4 * max(1.0, abs(numeric)):
                    raise ValueError(f"{who}: prescribed {name}({t:g}) = {given} contradicts the "
                                     f"derivative of the motion, {numeric}")
        return dict(kind=MOTION, function=(self.position, self.velocity, self.acceleration),
                    stiffness=0.0, damping=0.0, rest=0.0)

    def initial(self):
        """(q(0), q'(0)): the joint starts on the prescribed motion."""
        return float(np.asarray(self.position(0.0), dtype=float).reshape(-1)[0]), \
            float(np.asarray(self.velocity(0.0), dtype=float).reshape(-1)[0])


@dataclass(frozen=True, eq=False)
class PDTracking:
    """Feedback that makes the coordinate track a target, with feed-forward (docs/joints.md,
    "Drives"):

        f = kp (target(t) - q) + kd (target_rate(t) - q') + feedforward(t)

    on the child (its reaction on the parent), N m (or N).  It runs inside the compiled loop,
    implicit in q and q' as a SpringDamper (no Python call per step): the loop sees a spring
    and damper about q = 0 and the force kp target + kd target' + feedforward, known in time.
    ``Result.drive_force`` records f.

    Parameters
    ----------
    kp : float
        Proportional gain, N m/rad (or N/m), >= 0.
    kd : float
        Derivative gain, N m s/rad (or N s/m), >= 0.
    target : callable
        target(t) -> the coordinate to track at time t (s), rad (or m).
    target_rate : callable
        target_rate(t) -> its derivative, rad/s (or m/s).  Required, although it defaults to
        None (a profile's is ``profile.rate``).
    feedforward : callable, optional
        feedforward(t) -> a force added to the feedback, N m (or N).  None (default): zero.

    Raises
    ------
    ValueError
        At build time, naming the joint: a negative or non-finite gain; a function missing, not
        callable, or not returning one finite number at t = 0; target_rate contradicting the
        difference of target (as JointMotion's checks); on a closing joint (not yet).

    Examples
    --------
    Joint 1 of the arm tracking 0.5 t + 0.2 (1 - cos 2t) rad:

    >>> import numpy as np
    >>> import dttmm
    >>> pd = dttmm.PDTracking(kp=200.0, kd=20.0,
    ...                       target=lambda t: 0.5 * t + 0.2 * (1 - np.cos(2 * t)),
    ...                       target_rate=lambda t: 0.5 + 0.4 * np.sin(2 * t))
    >>> joint = dttmm.RevoluteJoint(axis=[0, 1, 0], drive=pd)
    """
    kp: float
    kd: float
    target: Callable[[float], float]
    target_rate: Optional[Callable[[float], float]] = None
    feedforward: Optional[Callable[[float], float]] = None
    kind = PD

    def validated(self, who, q0, qd0):
        kp = finite_scalar(who, "drive kp", self.kp, nonnegative=True)
        kd = finite_scalar(who, "drive kd", self.kd, nonnegative=True)
        for name in ("target", "target_rate") + (("feedforward",) if self.feedforward
                                                  is not None else ()):
            f = getattr(self, name)
            if f is None:
                raise ValueError(f"{who}: PDTracking needs its {name} (a function of time)")
            if not callable(f):
                raise ValueError(f"{who}: PDTracking {name} must be a function of time")
            _scalar_of(who, f"PDTracking {name}(0)", f(0.0))
        for t in (0.0, 0.37, 1.0):
            numeric = float(derivative(lambda s: _scalar_of(who, "target", self.target(s)), t,
                                       1e-5))
            given = _scalar_of(who, f"PDTracking target_rate({t:g})", self.target_rate(t))
            if abs(given - numeric) > 1e-4 * max(1.0, abs(numeric)):
                raise ValueError(f"{who}: PDTracking target_rate({t:g}) = {given} contradicts "
                                 f"the derivative of the target, {numeric}")
        return dict(kind=PD, function=(self.target, self.target_rate, self.feedforward),
                    stiffness=kp, damping=kd, rest=0.0)


def known_force(d, t):
    """The part of a drive's force known in time at t (module docstring): a PDTracking's
    kp target + kd target' + feedforward, a JointForce of time alone's value; 0 otherwise."""
    if d["kind"] == PD:
        target, rate, feedforward = d["function"]
        value = d["stiffness"] * target(t) + d["damping"] * rate(t)
        return value + (feedforward(t) if feedforward is not None else 0.0)
    if d["kind"] == FORCE and d.get("of_time"):
        return d["function"](t, 0.0, 0.0)
    return 0.0


def runs_in_loop(d):
    """Whether the drive runs inside the compiled loop's chunks (module docstring): all but a
    JointForce of the state given as a Python function, which the solver calls once per
    step."""
    return d is None or d["kind"] != FORCE or bool(d.get("of_time") or d.get("compiled"))


DRIVE_CLASSES = (JointForce, SpringDamper, JointMotion, PDTracking)


def validated_drive(who, drive, q0, qd0):
    """The drive's checked parameters (None for no drive); ValueError naming the joint."""
    if drive is None:
        return None
    if not isinstance(drive, DRIVE_CLASSES):
        raise ValueError(f"{who}: drive must be a JointForce, SpringDamper, JointMotion or "
                         f"PDTracking (or None), got {type(drive).__name__}")
    return drive.validated(who, q0, qd0)
