"""Deciding from a time history whether a disturbed car's hunting grows or dies, and where it
starts to grow (the brute-force nonlinear critical speed).

:func:`growth_rate_per_s` fits the exponential envelope of a lateral displacement's oscillation
(its peaks after the first second, when the faster modes have died, and below an amplitude
where the motion is still small: the linear growth, not the saturation of a limit cycle): > 0
grows, < 0 decays. :func:`onset_speed` interpolates where the growth rate of a list of speeds crosses
zero. A limit cycle (a grown oscillation saturated by the flange) has a growth rate near zero
and a large :func:`final_amplitude_m`.
"""
from __future__ import annotations

import math
from typing import Optional, Sequence

import numpy as np

__all__ = ["growth_rate_per_s", "final_amplitude_m", "onset_speed"]

#: peaks below this [m] are round-off, not an oscillation (1 nm)
PEAK_FLOOR_M = 1e-9


def growth_rate_per_s(t_s: np.ndarray, y_m: np.ndarray, skip_s: float = 1.0,
                      max_amplitude_m: float = math.inf) -> float:
    """The slope of log|peak| against time [1/s] over the peaks of |y| after ``skip_s`` up to the
    first that exceeds ``max_amplitude_m``; NaN with fewer than 4 such peaks (no oscillation to
    judge). y oscillates about 0 (the track centre line)."""
    t, y = np.asarray(t_s, float), np.asarray(y_m, float)
    keep = t >= t[0] + skip_s
    t, a = t[keep], np.abs(y[keep])
    if a.size < 3:
        return math.nan
    inner = (a[1:-1] > a[:-2]) & (a[1:-1] >= a[2:]) & (a[1:-1] > PEAK_FLOOR_M)
    peaks = np.flatnonzero(inner) + 1
    large = np.flatnonzero(a[peaks] > max_amplitude_m)
    if large.size:
        peaks = peaks[:large[0]]
    if peaks.size < 4:
        return math.nan
    return float(np.polyfit(t[peaks], np.log(a[peaks]), 1)[0])


def final_amplitude_m(t_s: np.ndarray, y_m: np.ndarray, window_s: float = 1.0) -> float:
    """Half the peak-to-peak range of y over the last ``window_s`` of the record [m]."""
    t, y = np.asarray(t_s, float), np.asarray(y_m, float)
    last = y[t >= t[-1] - window_s]
    return float(0.5 * (last.max() - last.min()))


def onset_speed(speeds_m_per_s: Sequence[float], rates_per_s: Sequence[float]) -> Optional[float]:
    """The speed where the growth rate first crosses zero upwards, linearly interpolated between
    the last speed where it decays and the first where it grows; None without such a pair."""
    pairs = [(v, r) for v, r in sorted(zip(speeds_m_per_s, rates_per_s)) if not math.isnan(r)]
    for (v0, r0), (v1, r1) in zip(pairs, pairs[1:]):
        if r0 < 0.0 <= r1:
            return v0 + (v1 - v0) * (-r0) / (r1 - r0)
    return None
