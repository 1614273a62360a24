"""Small measurement helpers for the tests (no physics here)."""
import numpy as np


def crossing_period(t, x):
    """Mean period of a signal from its upward zero crossings (linear interpolation)."""
    x = np.asarray(x) - np.mean(x)
    i = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
    tc = t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])
    assert len(tc) >= 3, "too few crossings to measure a period"
    return (tc[-1] - tc[0]) / (len(tc) - 1)


def fitted_order(dts, errors):
    return np.polyfit(np.log(dts), np.log(errors), 1)[0]


def rot_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
