"""Safety criteria: wheel unloading ΔQ/Q0 (EN 14363), Nadal's Y/Q and Prud'homme's ΣY limits,
the EN 14363 2 m sliding mean; final-window statistics of time series."""
from __future__ import annotations

import math
from typing import Optional

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


def en14363_twist_limit(base_m: float) -> float:
    """Track twist [-] for a base 2a [m]: 7e-3 (2a <= 4 m), (20/2a + 2)e-3 (<= 20 m), 3e-3 above
    (the limit EN 14363's test on twisted track applies, as commonly quoted from it)."""
    if base_m <= 4.0:
        return 7e-3
    if base_m <= 20.0:
        return (20.0 / base_m + 2.0) * 1e-3
    return 3e-3


def largest_track_twist(cant_rad, s_m, base_m: float, rail_base_m: float) -> tuple[float, float]:
    """The largest track twist [-] over a base of ``base_m`` [m] and where it ends [m]: the change
    of cross-level, ``rail_base_m`` sin(cant), from s - base to s, over the base (EN 14363's twist
    g = Δh / 2a), for ``cant_rad``, a function of the arc length [rad], on the grid ``s_m``
    (ascending; a window reaching back before the grid's first point takes that point's cant,
    the level track before a curve when the grid starts at the track's start). Either sense
    counts: a ramp up into a curve to the left or right, or down out of it. (0, s_m[0]) without
    twist."""
    s = np.asarray(s_m, dtype=float)
    height = rail_base_m * np.sin(np.asarray(cant_rad(s), dtype=float))
    behind = rail_base_m * np.sin(np.asarray(cant_rad(np.maximum(s - base_m, s[0])), dtype=float))
    twist = np.abs(height - behind) / base_m
    i = int(np.argmax(twist))
    return float(twist[i]), float(s[i])


#: EN 14363: Y/Q and ΣY are assessed on their sliding mean over 2 m of track
SLIDING_MEAN_M = 2.0


#: the flange angle [deg] and friction coefficient EN 14363 and UIC 518 take Nadal's limit at
NADAL_FLANGE_ANGLE_DEG = 70.0
NADAL_FRICTION = 0.36


def nadal_limit(flange_angle_deg: float = NADAL_FLANGE_ANGLE_DEG, friction: float = NADAL_FRICTION) -> float:
    """Nadal's limit of the flanging wheel's Y/Q (Nadal 1908; EN 14363 and UIC 518 use its
    value for γ = 70°, μ = 0.36):

        (Y/Q)_lim = (tan γ - μ) / (1 + μ tan γ),

    γ the flange angle, μ the friction coefficient at the flange contact. 70° and 0.36 give
    1.2003 (EN 14363's 1.2)."""
    tg = math.tan(math.radians(flange_angle_deg))
    return (tg - friction) / (1.0 + friction * tg)


def prudhomme_limit_N(Q0_N: float, alpha: float = 1.0) -> float:
    """EN 14363's limit of the track shifting force (the 2 m sliding mean of ΣY, the sum of a
    wheelset's lateral wheel forces), after Prud'homme (1967):

        ΣY_lim = α (10 kN + 2 Q0 / 3)   [Q0 the static wheel load],

    i.e. Prud'homme's α (10 + P/3) kN with P = 2 Q0 the static axle load in kN; α = 1 for
    locomotives, power heads and passenger vehicles, 0.85 for freight wagons."""
    return alpha * (10e3 + 2.0 * Q0_N / 3.0)


def cumulative_integral(x: np.ndarray, values: np.ndarray) -> np.ndarray:
    """∫_{x_0}^{x_i} v dx at every sample of ``values`` (samples first) joined linearly: the
    cumulative trapezoid."""
    x = np.asarray(x, dtype=float)
    v = np.asarray(values, dtype=float)
    h = np.diff(x).reshape((-1,) + (1,) * (v.ndim - 1))
    return np.concatenate([np.zeros((1,) + v.shape[1:]), np.cumsum(0.5 * (v[1:] + v[:-1]) * h, axis=0)])


def cumulative_at(x: np.ndarray, values: np.ndarray, points: np.ndarray, cum: Optional[np.ndarray] = None) -> np.ndarray:
    """∫_{x_0}^{p} v dx for every p in ``points`` (within [x_0, x_-1]) of the samples ``values``
    (samples first, any trailing shape) joined linearly: exact for that piecewise-linear signal
    (``cum``: :func:`cumulative_integral` of them, if at hand). NaN samples make every integral
    that reaches them NaN."""
    x = np.asarray(x, dtype=float)
    v = np.asarray(values, dtype=float)
    p = np.asarray(points, dtype=float)
    cum = cumulative_integral(x, v) if cum is None else cum
    j = np.clip(np.searchsorted(x, p, side="right"), 1, x.size - 1)
    shape = (-1,) + (1,) * (v.ndim - 1)
    d = (p - x[j - 1]).reshape(shape)
    hj = (x[j] - x[j - 1]).reshape(shape)
    return cum[j - 1] + (v[j - 1] * d + (v[j] - v[j - 1]) * d * d / (2.0 * hj))


def sliding_mean(t_s: np.ndarray, values: np.ndarray, window_s: float) -> np.ndarray:
    """Trailing sliding mean over ``window_s``: m(t_i) = (1/W) ∫_{t_i - W}^{t_i} v dt for every
    sample time t_i with a whole window behind it (t_i >= t_0 + W), NaN before. The samples
    (``values``: samples first, any trailing shape) are joined linearly and the integral is exact
    for that piecewise-linear signal (cumulative trapezoid, the window's start inside an interval
    integrated exactly). EN 14363's 2 m sliding mean of Y/Q and ΣY at speed v is
    ``sliding_mean(t, y, 2 / v)``. A NaN sample makes every window that holds it NaN."""
    t = np.asarray(t_s, dtype=float)
    v = np.asarray(values, dtype=float)
    if not window_s > 0:
        raise ValueError(f"window_s must be > 0, got {window_s}")
    if t.ndim != 1 or v.shape[:1] != t.shape:
        raise ValueError(f"expected samples first: t {t.shape}, values {v.shape}")
    out = np.full(v.shape, np.nan)
    if t.size < 2:
        return out
    bad = np.isnan(v)
    v0 = np.where(bad, 0.0, v)
    # integral from t_0 to each sample, and the number of intervals touching a NaN sample
    cum = cumulative_integral(t, v0)
    bad_cum = np.concatenate([np.zeros((1,) + v.shape[1:], dtype=int), np.cumsum(bad[1:] | bad[:-1], axis=0)])
    full = np.flatnonzero(t >= t[0] + window_s - 1e-12 * max(1.0, abs(t[0])))
    if full.size == 0:
        return out
    start = np.maximum(t[full] - window_s, t[0])
    mean = (cum[full] - cumulative_at(t, v0, start, cum)) / window_s
    # the interval holding each window's start, for the NaN count
    j = np.clip(np.searchsorted(t, start, side="right"), 1, t.size - 1)
    out[full] = np.where(bad_cum[full] - bad_cum[j - 1] > 0, np.nan, mean)
    return out


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
