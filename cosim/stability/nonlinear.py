"""Deciding from a time history whether a disturbed car's hunting grows or dies, and where it
starts to grow (the brute-force nonlinear critical speed).

:func:`growth_rate_per_s` fits the exponential envelope of a lateral displacement's oscillation
(its peaks after the first second, when the faster modes have died, and below an amplitude
where the motion is still small: the linear growth, not the saturation of a limit cycle): > 0
grows, < 0 decays. :func:`onset_speed` interpolates where the growth rate of a list of speeds crosses
zero. A limit cycle (a grown oscillation saturated by the flange) has a growth rate near zero
and a large :func:`final_amplitude_m`. :func:`limit_cycle_end` reads a ramp-down: the time (and
so the speed) at which a limit cycle's amplitude has fallen to a fraction of what it was.
"""
from __future__ import annotations

import math
from typing import Optional, Sequence

import numpy as np

__all__ = ["growth_rate_per_s", "final_amplitude_m", "hunts", "onset_speed", "envelope", "limit_cycle_end"]

#: peaks below this [m] are round-off, not an oscillation (1 nm)
PEAK_FLOOR_M = 1e-9
#: a hunting run whose fitted growth rate is below this [1/s] sits on its limit cycle already
#: (fits there give +-5e-4 /s), not growing: its rate says nothing about where the onset is
SATURATED_BELOW_PER_S = 0.01


def growth_rate_per_s(t_s: np.ndarray, y_m: np.ndarray, skip_s: float = 1.0,
                      max_amplitude_m: float = math.inf) -> float:
    """The slope of log|peak| against time [1/s] over the peaks of |y| after ``skip_s`` up to the
    first that exceeds ``max_amplitude_m``; NaN with fewer than 4 such peaks (no oscillation to
    judge). y oscillates about 0 (the track centre line)."""
    t, y = np.asarray(t_s, float), np.asarray(y_m, float)
    if t.size < 3:
        return math.nan
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
    """Half the peak-to-peak range of y over the last ``window_s`` of the record [m] (NaN: no record)."""
    t, y = np.asarray(t_s, float), np.asarray(y_m, float)
    if t.size == 0:
        return math.nan
    last = y[t >= t[-1] - window_s]
    return float(0.5 * (last.max() - last.min()))


def onset_speed(speeds_m_per_s: Sequence[float], rates_per_s: Sequence[float],
                hunts: Sequence[bool]) -> tuple[Optional[float], str]:
    """(the speed where hunting sets in, how it was found): between the last speed where the
    disturbance dies and the first where the car hunts (``hunts``: its oscillation is still there
    at the end), where the growth rate crosses zero (linear interpolation), or the bracket's middle
    when the hunting run sits on a limit cycle already (its small-amplitude growth rate below
    :data:`SATURATED_BELOW_PER_S`) or left the track before its growth could be measured (inf);
    None when the speeds do not bracket a change."""
    runs = sorted(zip(speeds_m_per_s, rates_per_s, hunts))
    if runs and runs[0][2]:
        return None, f"the car hunts already at {runs[0][0]:g} m/s, the lowest brute-force speed"
    for (v0, r0, h0), (v1, r1, h1) in zip(runs, runs[1:]):
        if not h0 and h1:
            if r0 < 0.0 and SATURATED_BELOW_PER_S < r1 < math.inf:   # inf: derailed before it was measured
                return v0 + (v1 - v0) * (-r0) / (r1 - r0), f"growth rate crosses zero between {v0:g} and {v1:g} m/s"
            return 0.5 * (v0 + v1), f"dies at {v0:g}, hunts at {v1:g} m/s (a limit cycle): the middle"
    return None, "the car hunts at none of the brute-force speeds"


def hunts(final_amplitude_m: float, disturbance_m: float) -> bool:
    """Still hunting at the end of a brute-force run: the oscillation has not fallen below half
    the disturbance it was released with (a decaying one falls by orders of magnitude)."""
    return not final_amplitude_m < 0.5 * disturbance_m


def envelope(t_s: np.ndarray, y_m: np.ndarray, window_s: float = 1.0,
             hop_s: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """(window starts [s], the largest |y| in each window [m]): windows of ``window_s`` (several
    hunting periods: 3-8 Hz) every ``hop_s``. A window below a threshold says the oscillation
    stays below it from the window's start on, for at least a window. A window without samples
    (samples sparser than the window) is NaN; a record shorter than a window gives none."""
    t, a = np.asarray(t_s, float), np.abs(np.asarray(y_m, float))
    if t.size == 0:
        return np.zeros(0), np.zeros(0)
    starts = np.arange(t[0], t[-1] - window_s + 1e-12, hop_s)
    peaks = np.array([a[(t >= s0) & (t < s0 + window_s)].max(initial=-1.0) for s0 in starts])
    return starts, np.where(peaks < 0.0, math.nan, peaks)


def limit_cycle_end(t_s: np.ndarray, y_m: np.ndarray, hold_s: float, fraction: float = 0.05,
                    window_s: float = 1.0) -> tuple[float, float]:
    """(the time the limit cycle died [s], its amplitude [m]): the amplitude is the largest |y| over
    the last ``window_s`` of the hold (the car at its start speed, on its limit cycle); the limit
    cycle has died at the start of the first window after the hold whose envelope is below
    ``fraction`` of it (NaN: it never does within the record, or the record has no hold of a
    window to read the amplitude from)."""
    t, y = np.asarray(t_s, float), np.asarray(y_m, float)
    held = (t >= hold_s - window_s) & (t <= hold_s)
    if t.size == 0 or t[0] > hold_s - window_s + 1e-9 or not held.any():
        return math.nan, math.nan
    amplitude = float(np.abs(y[held]).max())
    tc, env = envelope(t, y, window_s)
    after = np.flatnonzero((tc > hold_s) & (env < fraction * amplitude))
    return (float(tc[after[0]]) if after.size else math.nan), amplitude
