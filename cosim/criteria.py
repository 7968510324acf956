"""Safety criteria: wheel unloading ΔQ/Q0 (EN 14363); final-window statistics of time series."""
from __future__ import annotations

import numpy as np

#: EN 14363 limit on the wheel unloading ΔQ/Q0 on twisted track.
DQQ_LIMIT = 0.6


def static_wheel_loads(Q_level_N: np.ndarray) -> np.ndarray:
    """Q0 per wheel: the static vertical wheel force on level track, as the mean of the two wheels
    of the wheelset (EN 14363). ``Q_level_N``: (8, ...) in the order 1L 1R 2L 2R ... 4R."""
    pairs = Q_level_N.reshape(4, 2, *Q_level_N.shape[1:]).mean(axis=1)
    return np.repeat(pairs, 2, axis=0)


def wheel_unloading(Q_N: np.ndarray, Q0_N: np.ndarray) -> np.ndarray:
    """ΔQ/Q0 = (Q0 - Q) / Q0: positive when the wheel unloads; 1 for a lifted wheel (Q = 0)."""
    return (Q0_N - Q_N) / Q0_N


def _span_mean(t: np.ndarray, v: np.ndarray, t0: float, t1: float) -> np.ndarray:
    """Trapezoidal time average of the samples ``v`` (samples first) over [t0, t1] (t[0] <= t0 <
    t1 <= t[-1]), the ends interpolated linearly between their neighbouring samples."""
    def at(time):
        i = min(max(int(np.searchsorted(t, time, side="right")), 1), len(t) - 1)
        w = (time - t[i - 1]) / (t[i] - t[i - 1])
        return (1.0 - w) * v[i - 1] + w * v[i]
    inside = (t > t0) & (t < t1)
    tt = np.concatenate([[t0], t[inside], [t1]])
    vv = np.concatenate([at(t0)[None], v[inside], at(t1)[None]])
    dt = np.diff(tt).reshape((-1,) + (1,) * (vv.ndim - 1))
    return (0.5 * (vv[1:] + vv[:-1]) * dt).sum(axis=0) / (t1 - t0)


def _checked(t_s, values, window_s: float):
    """The series as arrays, or None when it is shorter than the window: the window is
    validated against the planned duration at load time, so a shorter series is a run that
    stopped early (every case diverged) and has no final window."""
    t = np.asarray(t_s, dtype=float)
    v = np.asarray(values, dtype=float)
    if not window_s > 0:
        raise ValueError(f"window_s must be > 0, got {window_s}")
    if t[-1] - window_s < t[0] - 1e-9 * max(1.0, abs(t[0])):
        return None
    return t, v


def _nan_like(values) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    return np.full(v.shape[1:], np.nan) if v.ndim > 1 else np.float64(np.nan)


def window_mean(t_s: np.ndarray, values: np.ndarray, window_s: float) -> np.ndarray:
    """Time average of ``values`` (samples first, any trailing shape) over the final window
    [t_end - window_s, t_end], by the trapezoidal rule on the samples (exact for a piecewise-linear
    signal; for a sampled oscillation of period P the error is O((dt/P)^2) of its amplitude).
    A quasi-static end value that does not depend on where an oscillation happens to be at the
    last sample. NaN samples (a diverged case) or a series shorter than the window (a run that
    stopped early) give NaN."""
    checked = _checked(t_s, values, window_s)
    if checked is None:
        return _nan_like(values)
    t, v = checked
    return _span_mean(t, v, max(t[-1] - window_s, t[0]), t[-1])


def window_drift(t_s: np.ndarray, values: np.ndarray, window_s: float) -> np.ndarray:
    """|change of the window mean over one window|: the mean over the final window
    [t_end - W, t_end] minus the mean over the window before it, [t_end - 2W, t_end - W] (cut at
    the start of the series). A trend of rate c gives c W; an oscillation of amplitude b and
    angular frequency w at most 4 b / (w W), however the windows fall on its periods. NaN when
    there is no earlier window (the final window is the whole series, or longer) or a sample is
    NaN."""
    checked = _checked(t_s, values, window_s)
    if checked is None:
        return _nan_like(values)
    t, v = checked
    t1 = t[-1] - window_s
    if not t1 > t[0]:
        return _nan_like(v)
    last = _span_mean(t, v, t1, t[-1])
    before = _span_mean(t, v, max(t1 - window_s, t[0]), t1)
    return np.abs(last - before)
