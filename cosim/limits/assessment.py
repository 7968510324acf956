"""EN 14363 on-track assessment statistics: 2 m sliding means sampled along the track, the track
cut into test zones, per zone the percentiles and quasi-static values of each quantity, each
beside its limit.

What the standard says and what is assumed here (EN 14363:2016, *Railway applications - Testing
and simulation for the acceptance of running characteristics of railway vehicles*; its text was
not available while this was written, so the values below are the widely quoted ones and each is
marked as such; a user bound by the standard checks them against their copy):

* **Sliding mean.** Y, Q, ΣY, Y/Q (and here ΔQ/Q0) are assessed on their mean over a 2 m window
  of track, the window moved in steps of 0.5 m (:data:`WINDOW_M`, :data:`STEP_M`;
  :func:`track_means`). Each mean is the exact average of the sampled signal joined linearly.
* **Test zones.** Straight track, large-radius curves R >= 600 m, small-radius curves 400 <= R <
  600 m, very small radius curves 250 <= R < 400 m (the standard's zones 1 to 4). Metros run on
  tighter curves than the standard covers: R < 250 m is its own zone here, assessed like the
  very small radius zone. Transitions are their own zone (the standard assesses the arcs and
  straights; the transitions are shown, not judged by the quasi-static limits). A 2 m mean
  belongs to the zone of its window's centre (:func:`zone_of`).
* **Statistics per zone and per wheel (wheelset for ΣY).** The 99.85 % and 0.15 % percentiles of
  the 2 m means (numpy's linear interpolation between order statistics), the 50 % percentile as
  the quasi-static value (the standard's statistical method for a section; here one section per
  zone), the largest and smallest mean (:func:`zone_statistics`).
* **Limits** (:func:`limits`): (Y/Q)_2m,99.85 <= Nadal's limit (1.2 for 70°, μ = 0.36);
  |ΣY|_2m,99.85 <= Prud'homme's α (10 kN + 2 Q0/3); Q_2m,99.85 <= min(90 kN + Q0, 160 kN)
  [assumed: the track-loading limit for speeds up to 160 km/h]; Y_qst <= 30 kN + 10.5 MN m / R_m
  and Q_qst <= 145 kN in the curve zones R < 600 m [assumed: the quasi-static guiding and
  vertical force limits]; (ΔQ/Q0)_2m,99.85 <= 0.6, the twist-test unloading limit used as a
  running indicator (EN 14363 has no such limit on track; marked ``indicator``).
* **Running stability** (:func:`sliding_rms`, :func:`dominant_frequency`): ΣY band-pass filtered
  at f0 ± 2 Hz, its rms over a sliding 100 m of track, against half Prud'homme's limit; f0 the
  peak of ΣY's spectrum between 0.5 and 15 Hz (the hunting frequency when the car hunts, the
  dominant lateral frequency otherwise) [the criterion as the issue states it; the standard's
  text was not available]. The carbody's lateral floor acceleration above the bogies in the same
  band and window, against 0.5 m/s² [assumed].
* **Carbody accelerations** (:func:`band_filtered`, :func:`acceleration_statistics`): the lateral
  and vertical floor accelerations above the bogie centres, band-pass filtered 0.4-10 Hz (a
  4th-order Butterworth run forwards and backwards: no phase shift), per zone their largest
  magnitude and rms; limits [assumed] ÿ*_max 3 m/s², z̈*_max 5 m/s², ÿ*_rms 0.5 m/s², z̈*_rms
  1 m/s². The samples are the run's output samples, not anti-alias filtered: content above half
  the output rate folds into the band, so keep ``solver.output_interval_s`` small (<= 0.02 s).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Dict, List, Optional, Sequence

import numpy as np

from cosim.limits.criteria import cumulative_at

#: EN 14363's sliding window [m] and the step it is moved by along the track [m]
WINDOW_M = 2.0
STEP_M = 0.5
#: the statistics of a zone, column suffix -> percentile [%] (None: the extreme)
STATISTICS = {"p9985": 99.85, "p0015": 0.15, "p50": 50.0, "max": None, "min": None}
#: test zones, in track order of a curve entry's curvature classes
ZONES = ("straight", "transition", "R>=600", "400<=R<600", "250<=R<400", "R<250")
#: EN 14363 limits assumed where the text was not available (see the module docstring)
Q_LIMIT_ADD_N, Q_LIMIT_CAP_N = 90e3, 160e3
Y_QST_BASE_N, Y_QST_PER_INV_RADIUS_N_M = 30e3, 10.5e6
Q_QST_LIMIT_N = 145e3
DQQ_INDICATOR = 0.6
#: carbody accelerations: the filter band [Hz] and the limits [m/s^2] (assumed)
ACCELERATION_BAND_HZ = (0.4, 10.0)
ACCELERATION_LIMITS = {"ay_floor": {"max": 3.0, "rms": 0.5}, "az_floor": {"max": 5.0, "rms": 1.0}}


def window_means(x: np.ndarray, values: np.ndarray, ends: np.ndarray, width: float) -> np.ndarray:
    """Mean of ``values`` (samples at ``x``, samples first) over [e - width, e] for each e of
    ``ends`` (each window inside [x_0, x_-1]), exact for the samples joined linearly."""
    ends = np.asarray(ends, dtype=float)
    return (cumulative_at(x, values, ends) - cumulative_at(x, values, ends - width)) / width


@dataclass(frozen=True)
class TrackMeans:
    """2 m sliding means sampled along the track: ``s_m`` (n,) the arc length of each window's
    centre [m] for the quantity's own position (a wheel's, a wheelset's), ``values`` (n, ...) the
    means."""

    s_m: np.ndarray
    values: np.ndarray


def track_means(s_m: np.ndarray, values: np.ndarray, window_m: float = WINDOW_M,
                step_m: float = STEP_M) -> TrackMeans:
    """EN 14363's sliding mean: the mean of ``values`` (samples first; sampled at the increasing
    arc lengths ``s_m`` [m] of the point they belong to) over windows of ``window_m`` of track,
    one every ``step_m`` from the first whole window to the last. The windows' ends lie on the
    multiples of ``step_m``, so that two runs on the same track are assessed at the same places
    whatever their output interval."""
    s = np.asarray(s_m, dtype=float)
    first = math.ceil((s[0] + window_m) / step_m - 1e-9) * step_m
    ends = np.arange(first, s[-1] + 1e-9 * max(1.0, abs(s[-1])), step_m)
    if ends.size == 0:
        return TrackMeans(np.empty(0), np.empty((0,) + np.shape(values)[1:]))
    return TrackMeans(ends - 0.5 * window_m, window_means(s, values, ends, window_m))


def zone_name(kind: str, radius_m: Optional[float] = None) -> str:
    """The test zone of a track segment: ``straight``, ``transition`` or an arc's radius class."""
    if kind != "arc":
        return kind
    if radius_m >= 600.0:
        return "R>=600"
    if radius_m >= 400.0:
        return "400<=R<600"
    return "250<=R<400" if radius_m >= 250.0 else "R<250"


def zone_of(segment_start_m: np.ndarray, segment_zones: Sequence[str], s_m: np.ndarray) -> np.ndarray:
    """The zone of each arc length ``s_m`` (beyond the ends: the first / last segment's)."""
    idx = np.clip(np.searchsorted(np.asarray(segment_start_m), np.asarray(s_m), side="right") - 1,
                  0, len(segment_zones) - 1)
    return np.asarray(segment_zones, dtype=object)[idx]


def zone_statistics(means: np.ndarray, zones: np.ndarray) -> Dict[str, Dict[str, np.ndarray]]:
    """Per zone present in ``zones`` (n,) the :data:`STATISTICS` of ``means`` (n, m) over its
    points, per column, and ``n`` the number of means: zone -> statistic -> (m,). NaN means (a
    stopped case) give NaN statistics."""
    out: Dict[str, Dict[str, np.ndarray]] = {}
    for zone in ZONES:
        inside = means[zones == zone]
        if inside.shape[0] == 0:
            continue
        count = {"n": np.full(inside.shape[1:], inside.shape[0])}
        if np.isnan(inside).any():
            out[zone] = {**{name: np.full(inside.shape[1:], np.nan) for name in STATISTICS}, **count}
            continue
        out[zone] = {**{name: (np.percentile(inside, q, axis=0) if q is not None
                               else (inside.max(axis=0) if name == "max" else inside.min(axis=0)))
                        for name, q in STATISTICS.items()}, **count}
    return out


def band_filtered(t_s: np.ndarray, values: np.ndarray, band_hz=ACCELERATION_BAND_HZ, order: int = 4) -> np.ndarray:
    """``values`` (samples first, uniformly sampled at ``t_s``) band-pass filtered forwards and
    backwards (zero phase) by a Butterworth filter of ``order`` on ``band_hz``. Raises
    ValueError when the sampling is too coarse for the band (the upper edge above 0.8 of the
    Nyquist frequency)."""
    from scipy.signal import butter, sosfiltfilt
    t = np.asarray(t_s, dtype=float)
    fs = 1.0 / float(np.median(np.diff(t)))
    if band_hz[1] > 0.4 * fs * (1.0 + 1e-6):             # round-off in the sample times must not flip it
        raise ValueError(f"sampled at {fs:g} Hz: too coarse for a band up to {band_hz[1]:g} Hz "
                         f"(output interval at most {0.4 / band_hz[1]:g} s)")
    sos = butter(order, band_hz, btype="bandpass", fs=fs, output="sos")
    v = np.asarray(values, dtype=float)
    if v.shape[0] <= 3 * (2 * order + 1):
        return np.full(v.shape, np.nan)
    return sosfiltfilt(sos, v, axis=0)


def acceleration_statistics(filtered: np.ndarray, zones: np.ndarray) -> Dict[str, Dict[str, np.ndarray]]:
    """Per zone present in ``zones`` (n,) the largest magnitude (``max``), the rms (``rms``) of the
    filtered accelerations ``filtered`` (n, m) over its samples, and ``n`` their number."""
    out: Dict[str, Dict[str, np.ndarray]] = {}
    for zone in ZONES:
        inside = filtered[zones == zone]
        if inside.shape[0]:
            out[zone] = {"max": np.abs(inside).max(axis=0), "rms": np.sqrt((inside ** 2).mean(axis=0)),
                         "n": np.full(inside.shape[1:], inside.shape[0])}
    return out


#: running stability: the sliding window [m], the half-width of the band around f0 [Hz], where f0
#: is looked for [Hz], and the carbody's lateral acceleration limit in that band [m/s^2] (assumed)
STABILITY_WINDOW_M = 100.0
STABILITY_HALF_BAND_HZ = 2.0
STABILITY_SEARCH_HZ = (0.5, 15.0)
STABILITY_AY_LIMIT = 0.5


def sliding_rms(t_s: np.ndarray, values: np.ndarray, window_s: float) -> np.ndarray:
    """rms of ``values`` (uniform samples first, any trailing shape) over the trailing
    ``window_s`` at every sample with a whole window behind it (NaN before)."""
    v = np.asarray(values, dtype=float)
    dt = float(np.median(np.diff(t_s)))
    n = int(round(window_s / dt))
    out = np.full(v.shape, np.nan)
    if n < 1 or n > v.shape[0]:
        return out
    cum = np.concatenate([np.zeros((1,) + v.shape[1:]), np.cumsum(v * v, axis=0)])
    out[n - 1:] = np.sqrt(np.maximum(cum[n:] - cum[:-n], 0.0) / n)
    return out


def dominant_frequency(t_s: np.ndarray, values: np.ndarray, band_hz=STABILITY_SEARCH_HZ) -> float:
    """The frequency [Hz] of the largest peak of the (Welch) spectrum of ``values`` (1-D, uniform
    samples) within ``band_hz``; NaN when the record holds no such frequency."""
    from scipy.signal import welch
    v = np.asarray(values, dtype=float)
    if v.size < 16 or not np.isfinite(v).all():
        return math.nan
    fs = 1.0 / float(np.median(np.diff(t_s)))
    f, p = welch(v - v.mean(), fs=fs, nperseg=min(v.size, int(round(8 * fs))))
    inside = (f >= band_hz[0]) & (f <= min(band_hz[1], 0.4 * fs))
    return float(f[inside][np.argmax(p[inside])]) if inside.any() else math.nan


def stability_rms(t_s: np.ndarray, values: np.ndarray, f0_Hz: float, window_s: float) -> np.ndarray:
    """``values`` band-passed at f0 ± 2 Hz (zero phase), their largest sliding rms over
    ``window_s`` per column (samples first): the stability criterion's quantity."""
    lo = max(f0_Hz - STABILITY_HALF_BAND_HZ, 0.2)
    filtered = band_filtered(t_s, values, (lo, f0_Hz + STABILITY_HALF_BAND_HZ))
    return np.nanmax(sliding_rms(t_s, filtered, window_s), axis=0)


@dataclass(frozen=True)
class Limit:
    """One assessed value beside its limit: ``quantity`` (e.g. ``yq_2m_p9985``), ``zone``,
    ``where`` (the wheel or wheelset that gave the value), ``value``, ``limit`` and whether it is
    an EN 14363 criterion or an ``indicator``."""

    quantity: str
    zone: str
    where: str
    value: float
    limit: float
    unit: str
    criterion: str
    source: str

    @property
    def passed(self) -> bool:
        return not math.isnan(self.value) and self.value <= self.limit


def q_limit_N(Q0_N: float) -> float:
    """Q_2m,99.85 limit: 90 kN + Q0, at most 160 kN (assumed, see the module docstring)."""
    return min(Q_LIMIT_ADD_N + Q0_N, Q_LIMIT_CAP_N)


def y_qst_limit_N(radius_m: float) -> float:
    """Quasi-static guiding force limit 30 kN + 10.5 MN m / R_m (assumed)."""
    return Y_QST_BASE_N + Y_QST_PER_INV_RADIUS_N_M / radius_m


def worst(per_who: np.ndarray, labels: Sequence[str]) -> tuple:
    """(largest value, its label); NaN and the first NaN's label if there is one."""
    per_who = np.asarray(per_who, dtype=float)
    nan = np.flatnonzero(np.isnan(per_who))
    i = int(nan[0]) if nan.size else int(np.argmax(per_who))
    return float(per_who[i]), labels[i]


def limits(stats: Dict[str, Dict[str, Dict[str, object]]], zone_radius_m: Dict[str, float], yq_lim: float,
           sum_y_lim_N: float, Q0_N: float) -> List[Limit]:
    """The assessed values beside their limits, one per quantity and zone (the worst wheel or
    wheelset). ``stats``: quantity -> zone -> {``who``: the wheels (wheelsets), statistic ->
    (len(who),) of :func:`zone_statistics`} for ``yq``, ``sum_y`` [N], ``Q`` [N], ``Y`` [N] and
    ``dqq``, and ``max`` / ``rms`` for ``ay_floor``, ``az_floor`` [m/s^2] (those present);
    ``zone_radius_m``: an arc zone's radius (the smallest of its arcs)."""
    out: List[Limit] = []

    def add(zone, quantity, stat, per_who, limit, unit, criterion, source, name=None):
        value, where = worst(per_who, stats[quantity][zone]["who"])
        out.append(Limit(name or f"{quantity}_2m_{stat}", zone, where, value, limit, unit, criterion, source))

    for zone in ZONES:

        if zone in stats.get("yq", {}):
            add(zone, "yq", "p9985", stats["yq"][zone]["p9985"], yq_lim, "1", "criterion", "Nadal")
        if zone in stats.get("sum_y", {}):
            s = stats["sum_y"][zone]
            add(zone, "sum_y", "p9985", np.maximum(s["p9985"], -s["p0015"]), sum_y_lim_N, "N", "criterion",
                "Prud'homme, |ΣY|")
        if zone in stats.get("Q", {}):
            add(zone, "Q", "p9985", stats["Q"][zone]["p9985"], q_limit_N(Q0_N), "N", "criterion",
                "90 kN + Q0, at most 160 kN (assumed)")
        radius = zone_radius_m.get(zone)
        if radius is not None and radius < 600.0:
            if zone in stats.get("Y", {}):
                add(zone, "Y", "p50", stats["Y"][zone]["p50"], y_qst_limit_N(radius), "N", "criterion",
                    f"Y_qst: 30 kN + 10.5 MN m / R (R = {radius:g} m; assumed)")
            if zone in stats.get("Q", {}):
                add(zone, "Q", "p50", stats["Q"][zone]["p50"], Q_QST_LIMIT_N, "N", "criterion",
                    "Q_qst <= 145 kN (assumed)")
        if zone in stats.get("dqq", {}):
            add(zone, "dqq", "p9985", stats["dqq"][zone]["p9985"], DQQ_INDICATOR, "1", "indicator",
                "twist-test unloading limit 0.6, as an indicator")
        for quantity, limit in ACCELERATION_LIMITS.items():
            if zone in stats.get(quantity, {}):
                for stat in ("max", "rms"):
                    add(zone, quantity, stat, stats[quantity][zone][stat], limit[stat], "m/s2", "criterion",
                        f"carbody, {ACCELERATION_BAND_HZ[0]:g}-{ACCELERATION_BAND_HZ[1]:g} Hz (assumed)",
                        name=f"{quantity}_{stat}")
    return out
