"""Adaptive steps: simulate(model, t_end, rtol=...) chooses the step from the local error
estimate (docs/solver.md, "Adaptive steps").

The compiled loop takes segments of up to SEGMENT equal steps; between segments this controller
compares the segment's largest Zienkiewicz-Xie estimate e (kernels/stepping/loop.py::step_error: rad
for rotations, m or modal units for the rest) with the run's tolerance and either accepts the
segment and sets the next step, or restores the state saved before it and retries with a
smaller step.  The estimate is held per unit time, e / h <= tol / t_end with tol = atol + rtol:
the local errors then add up to about tol over the run, and since e ~ h^3 for a second-order
step, e / h ~ h^2 and the step goes as tol^(1/2), the accumulated error as tol.  Segments land
on the sample times asked for (t_eval, record_dt) and on t_end.
"""
import math

import numpy as np

from ..results.recording import leaves

SEGMENT = 256       # most steps per call of the compiled loop (a call costs ~45 us in Python)
SAFETY = 0.8        # aim below the tolerance
GROW, SHRINK = 1.5, 0.2     # the largest change of the step from one segment to the next
FAILED_SHRINK = 0.25        # after a segment that failed (estimate over max_step_error, NaN)
MIN_STEP = 1e-12    # of t_end: below it the run stops (DivergenceError)


class StepControl:
    """The step h of the next segment from the last one's estimate (an I controller on the
    estimate per unit time, which goes as h^2)."""

    def __init__(self, t_end, rtol, atol, h0):
        self.t_end = float(t_end)
        self.tol = float(atol) + float(rtol)
        self.h = float(h0)
        self.h_min, self.h_max = np.inf, 0.0    # of the accepted segments
        self.rejected = self.rejected_steps = 0     # segments, and the steps they took

    def step_limit(self, h):
        """The largest estimate a step of h may have: the skeleton stops a segment there."""
        return h * self.tol / self.t_end

    def ratio(self, error, h):
        """The segment's estimate per unit time over the one allowed (accept at <= 1)."""
        return error * self.t_end / (h * self.tol)

    def after(self, error, h, steps, failed=False):
        """Judge a segment that took `steps` steps of h, whose largest estimate was error: True
        to accept it.  Sets self.h for the next segment (or the retry)."""
        if failed or not np.isfinite(error):
            self.rejected, self.rejected_steps = self.rejected + 1, self.rejected_steps + steps
            self.h = h * FAILED_SHRINK
            return False
        ratio = self.ratio(error, h)
        factor = GROW if ratio <= 0.0 else min(GROW, max(SHRINK, SAFETY / math.sqrt(ratio)))
        if ratio > 1.0:
            self.rejected, self.rejected_steps = self.rejected + 1, self.rejected_steps + steps
            self.h = h * min(factor, SAFETY)
            return False
        self.h = h * factor
        self.h_min, self.h_max = min(self.h_min, h), max(self.h_max, h)
        return True

    @property
    def too_small(self):
        return self.h < MIN_STEP * self.t_end


def segment(t, h, target, most=SEGMENT):
    """(m, h): the next segment from t: `most` steps of h, or, where that would pass the target
    time, m equal steps landing on it (h shortened by less than a step's worth)."""
    if t + most * h < target - 1e-12 * target:
        return most, h
    m = max(1, math.ceil((target - t) / h - 1e-9))
    return m, (target - t) / m


def checked_times(t_eval):
    """t_eval as a 1-d float array of finite times (simulate's, fixed or adaptive steps)."""
    times = np.atleast_1d(np.asarray(t_eval, dtype=float))
    if times.ndim != 1 or not np.all(np.isfinite(times)):
        raise ValueError("simulate: t_eval must be a 1-d array of finite times, s")
    if times.size == 0:
        raise ValueError("simulate: t_eval is empty: give the times to record (s), or leave "
                         "it out for the default samples")
    return times


def sample_times(t_end, record_dt=None, t_eval=None):
    """The times an adaptive run lands on and records (besides t = 0 and t_end), or None for
    the default: the end of a segment once per t_end / MAX_SAMPLES (run_records.MAX_SAMPLES)."""
    if t_eval is not None:
        times = checked_times(t_eval)
        if np.any(np.diff(times) <= 0) or times[0] < 0.0 or times[-1] > t_end * (1 + 1e-12):
            raise ValueError(f"simulate: t_eval must increase within [0, {t_end:g}] s")
        return times[times > 0.0]
    if record_dt is not None:
        n = max(1, int(round(t_end / record_dt)))
        return np.minimum(np.arange(1, n + 1) * record_dt, t_end)
    return None


class Snapshot:
    """The run's arrays (state, sweep, loop, monitor) saved before each segment and put back
    after a rejected one: the float arrays in one flat buffer (one np.concatenate over views,
    ~5 us for the three-pendulum's 3000 numbers against ~45 us for a copy per array), the rest
    one by one."""

    def __init__(self, structures):
        live = leaves(structures)
        self.flat = [a.reshape(-1) for a in live
                     if a.dtype == np.float64 and a.flags.c_contiguous]   # views
        self.others = [a for a in live if not (a.dtype == np.float64 and a.flags.c_contiguous)]
        self.buffer = np.empty(sum(v.size for v in self.flat))
        self.cuts = np.cumsum([v.size for v in self.flat])[:-1]
        self.kept = [a.copy() for a in self.others]

    def save(self):
        if self.flat:
            np.concatenate(self.flat, out=self.buffer)
        for keep, a in zip(self.kept, self.others):
            np.copyto(keep, a)

    def restore(self):
        for view, part in zip(self.flat, np.split(self.buffer, self.cuts)):
            view[:] = part
        for keep, a in zip(self.kept, self.others):
            np.copyto(a, keep)
