"""The EN 14363 assessment of a car run on track (:mod:`cosim.limits.assessment` does the
statistics): where each wheel is along the track, the track's test zones, per case the zone
statistics of Y, Q, ΣY, Y/Q and ΔQ/Q0 as 2 m means every 0.5 m, and the values beside their limits.
Shared by the car kinds that run on a track (``curve_entry``)."""
from __future__ import annotations

import math
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
import xarray as xr

from cosim.limits.assessment import (
    STABILITY_AY_LIMIT,
    STABILITY_WINDOW_M,
    STATISTICS,
    ZONES,
    Limit,
    acceleration_statistics,
    band_filtered,
    dominant_frequency,
    limits,
    stability_rms,
    track_means,
    zone_name,
    zone_of,
    zone_statistics,
)
from vehicle.params import WHEELS, WHEELSETS, VehicleParams
from vehicle.track import Arc, Straight, TrackGeometry

#: quantity -> (Dataset variable, per wheel or wheelset, unit, long name); contact-only where the
#: variable exists only with contact guidance
QUANTITIES = {
    "yq": ("y_over_q", "wheel", "1", "Y/Q"),
    "Y": ("lateral_wheel_force_N", "wheel", "N", "lateral wheel force Y (+ towards the track centre)"),
    "Q": ("wheel_load_N", "wheel", "N", "vertical wheel force Q"),
    "sum_y": ("wheelset_lateral_force_N", "wheelset", "N", "ΣY per wheelset (+ left)"),
    "dqq": ("dqq", "wheel", "1", "wheel unloading ΔQ/Q0"),
}
#: the carbody accelerations (not 2 m means): quantity -> (per, unit, long name)
ACCELERATIONS = {
    "ay_floor": ("floor_point", "m/s2", "lateral floor acceleration above the bogie, 0.4-10 Hz"),
    "az_floor": ("floor_point", "m/s2", "vertical floor acceleration above the bogie, 0.4-10 Hz"),
}
#: checkable metrics of the assessment: metric -> (quantity, statistic, summary column); the
#: check's value is the worst over the zones and wheels (wheelsets) its selectors leave; for
#: ``sum_y`` the larger of the 99.85 % and minus the 0.15 % percentile (|ΣY|)
METRICS = {
    "yq_2m_p9985": ("yq", "p9985", "yq_2m_p9985"),
    "sum_y_2m_p9985": ("sum_y", "p9985", "sum_y_2m_p9985_N"),
    "Q_2m_p9985": ("Q", "p9985", "Q_2m_p9985_N"),
    "Y_2m_p50": ("Y", "p50", "Y_2m_p50_N"),
    "Q_2m_p50": ("Q", "p50", "Q_2m_p50_N"),
    "dqq_2m_p9985": ("dqq", "p9985", "dqq_2m_p9985"),
    "ay_floor_max": ("ay_floor", "max", "ay_floor_max_m_per_s2"),
    "ay_floor_rms": ("ay_floor", "rms", "ay_floor_rms_m_per_s2"),
    "az_floor_max": ("az_floor", "max", "az_floor_max_m_per_s2"),
    "az_floor_rms": ("az_floor", "rms", "az_floor_rms_m_per_s2"),
}
#: the metrics judged only in the curve zones R < 600 m (quasi-static values), and those zones
QUASI_STATIC = ("Y_2m_p50", "Q_2m_p50")
CURVE_ZONES = ("400<=R<600", "250<=R<400", "R<250")


def zone_table(track: TrackGeometry) -> Tuple[np.ndarray, List[str], Dict[str, float]]:
    """(segment starts [m], each segment's zone, zone -> smallest arc radius [m] in it)."""
    zones, radius = [], {}
    for seg in track.segments:
        if isinstance(seg, Arc):
            zone = zone_name("arc", seg.radius_m)
            radius[zone] = min(radius.get(zone, math.inf), seg.radius_m)
        else:
            zone = zone_name("straight" if isinstance(seg, Straight) else "transition")
        zones.append(zone)
    return np.asarray(track.segment_start_m), zones, radius


def zones_run(track: TrackGeometry, vehicle: VehicleParams, s_centre_m: Sequence[float]) -> Tuple[str, ...]:
    """The zones the wheels' 2 m windows fall in while the car centre goes over ``s_centre_m``
    (its first and last arc length), in track order."""
    starts, zones, _ = zone_table(track)
    lo = min(s_centre_m) + min(vehicle.wheelset_x_m)
    hi = max(s_centre_m) + max(vehicle.wheelset_x_m)
    ends = [*starts[1:], track.total_length_m]
    return tuple(dict.fromkeys(z for z, a, b in zip(zones, starts, ends) if a < hi and b > lo))


def assess_case(case: xr.Dataset, s_centre_m: np.ndarray, track: TrackGeometry, vehicle: VehicleParams,
                yq_lim: float, sum_y_lim_N: float) -> Tuple[Dict[str, Dict[str, Dict[str, np.ndarray]]], List[Limit]]:
    """The statistics (quantity -> zone -> statistic -> per wheel or wheelset) and the limits of
    one case (``case``: the Dataset at one case, ``s_centre_m``: the car centre's arc length at
    each sample). Each wheel's means are taken along its own position, the car centre's plus its
    wheelset's x."""
    starts, zones, radius = zone_table(track)
    x_ws = np.asarray(vehicle.wheelset_x_m)
    stats: Dict[str, Dict[str, Dict[str, np.ndarray]]] = {}
    for quantity, (name, per, _, _) in QUANTITIES.items():
        if name not in case:
            continue
        labels = WHEELS if per == "wheel" else WHEELSETS
        values = case[name].transpose("time", per).values
        per_label = {}
        for i, label in enumerate(labels):
            ws = i // 2 if per == "wheel" else i
            means = track_means(s_centre_m + x_ws[ws], values[:, i])
            per_label[label] = zone_statistics(means.values[:, None], zone_of(starts, zones, means.s_m))
        stats[quantity] = _by_zone(per_label)
    stats.update(_accelerations(case, s_centre_m, vehicle, starts, zones))
    Q0 = float(case["Q0_N"].min())
    return stats, limits(stats, radius, yq_lim, sum_y_lim_N, Q0)


def _accelerations(case: xr.Dataset, s_centre_m: np.ndarray, vehicle: VehicleParams, starts, zones) -> Dict[str, dict]:
    """The carbody's lateral and vertical floor accelerations above the bogie centres, band
    filtered, per zone of each point's own position (none when the output is too coarse for the
    band: the run warns)."""
    out = {}
    t = case["time"].values
    if acceleration_warning(t):
        return out
    for quantity, axis in (("ay_floor", "y"), ("az_floor", "z")):
        name = f"floor_a{axis}_m_per_s2"
        if name not in case:
            continue
        per_label = {}
        for point, x in (("front", vehicle.bogie_x_m[0]), ("rear", vehicle.bogie_x_m[1])):
            filtered = band_filtered(t, case[name].sel(floor_point=point).values)
            per_label[point] = acceleration_statistics(filtered[:, None], zone_of(starts, zones, s_centre_m + x))
        out[quantity] = _by_zone(per_label, ("max", "rms", "n"))
    return out


def acceleration_warning(t_s: np.ndarray) -> Optional[str]:
    """Why a run's carbody accelerations cannot be assessed (its output too coarse), or None."""
    try:
        band_filtered(t_s, np.zeros(len(t_s)))
    except ValueError as exc:
        return f"carbody accelerations not assessed: {exc}"
    return None


def _by_zone(per_label: Dict[str, Dict[str, Dict[str, np.ndarray]]],
             statistics: Sequence[str] = (*STATISTICS, "n")) -> Dict[str, Dict[str, object]]:
    """label -> zone -> statistic -> (1,) into zone -> {``who``: the labels that were in the zone,
    statistic -> (len(who),)}: near the ends of a run a zone may hold some wheels' windows only."""
    out: Dict[str, Dict[str, object]] = {}
    for zone in ZONES:
        who = [label for label, zs in per_label.items() if zone in zs]
        if who:
            out[zone] = {"who": who, **{stat: np.array([per_label[w][zone][stat][0] for w in who])
                                         for stat in statistics}}
    return out


def statistics_rows(stats, valves: bool, k: float) -> List[Dict[str, object]]:
    """``assessment.csv``: one row per quantity, zone and wheel (wheelset), the statistics as columns."""
    rows = []
    for quantity, per_zone in stats.items():
        if quantity in ACCELERATIONS:
            per, unit, _ = ACCELERATIONS[quantity]
            name, counted = f"{quantity}_0.4-10Hz", "n_samples"
        else:
            _, per, unit, _ = QUANTITIES[quantity]
            name, counted = f"{quantity}_2m", "n_means"
        for zone, values in per_zone.items():
            for i, label in enumerate(values["who"]):
                rows.append({"valves": valves, "k_W_per_K": k, "quantity": name, "unit": unit, "zone": zone,
                             "per": per, "at": label, "n": int(values["n"][i]), "counts": counted,
                             **{stat: float(values[stat][i]) if stat in values else float("nan")
                                for stat in (*STATISTICS, "rms")}})
    return rows


def limit_rows(found: Sequence[Limit], valves: bool, k: float) -> List[Dict[str, object]]:
    """``assessment_limits.csv``: every assessed value beside its limit."""
    return [{"valves": valves, "k_W_per_K": k, "quantity": lim.quantity, "zone": lim.zone, "at": lim.where,
             "value": lim.value, "limit": lim.limit, "unit": lim.unit, "kind": lim.criterion,
             "status": "pass" if lim.passed else "fail", "source": lim.source} for lim in found]


def summary_columns(found: Sequence[Limit]) -> Dict[str, float]:
    """The summary's processed headline values: per metric of :data:`METRICS` the worst over the
    zones (the quasi-static ones over the curve zones R < 600 m only), and the number of failed
    criteria (indicators not counted)."""
    out: Dict[str, float] = {}
    for metric, (_, _, column) in METRICS.items():
        values = [lim.value for lim in found if lim.quantity == metric]
        if values:
            out[column] = math.nan if any(math.isnan(v) for v in values) else max(values)
    out["en14363_failed"] = sum(1 for lim in found if lim.criterion == "criterion" and not lim.passed)
    return out


def zone_metrics(found: Sequence[Limit], stats) -> Dict[str, Dict[str, Dict[str, float]]]:
    """metric -> zone -> wheel (wheelset) -> value, for the checks' ``zone=`` and wheel selectors."""
    out: Dict[str, Dict[str, Dict[str, float]]] = {}
    for metric, (quantity, stat, _) in METRICS.items():
        zones = {lim.zone for lim in found if lim.quantity == metric}
        if quantity not in stats or not zones:
            continue
        out[metric] = {}
        for zone in zones:
            s = stats[quantity][zone]
            values = np.maximum(s["p9985"], -s["p0015"]) if quantity == "sum_y" else s[stat]
            out[metric][zone] = {label: float(v) for label, v in zip(s["who"], values)}
    return out


def stability_columns(case: xr.Dataset, speed_m_per_s: float, sum_y_lim_N: float) -> Dict[str, float]:
    """The running-stability criterion's columns of one contact case (:mod:`cosim.limits.assessment`,
    "Running stability"): ``f0_Hz`` (the peak of the leading wheelset's ΣY spectrum),
    ``sum_y_rms_max_<wheelset>_N`` and ``sum_y_rms_max_N`` (ΣY at f0 ± 2 Hz, largest rms over a
    sliding 100 m), ``sum_y_rms_lim_N`` (half Prud'homme's limit), ``ay_stability_rms_max_m_per_s2``
    (the carbody's lateral floor acceleration above the bogies, the same way) and its limit. Empty
    without contact, for a run shorter than 100 m, or a case that stopped (NaN)."""
    if "wheelset_lateral_force_N" not in case:
        return {}
    t = case["time"].values
    window = STABILITY_WINDOW_M / speed_m_per_s
    if t.size < 2 or t[-1] - t[0] < window:
        return {}
    sum_y = case["wheelset_lateral_force_N"].transpose("time", "wheelset").values
    if not np.isfinite(sum_y).all():
        return {"sum_y_rms_max_N": math.nan}
    f0 = dominant_frequency(t, sum_y[:, 0])
    if not math.isfinite(f0):
        return {}
    try:
        rms = stability_rms(t, sum_y, f0, window)
    except ValueError:                      # output too coarse for the band: the run warns
        return {}
    out = {"f0_Hz": f0, **{f"sum_y_rms_max_{ws}_N": float(v) for ws, v in zip(WHEELSETS, rms)},
           "sum_y_rms_max_N": float(rms.max()), "sum_y_rms_lim_N": 0.5 * sum_y_lim_N}
    if "floor_ay_m_per_s2" in case:
        ay = case["floor_ay_m_per_s2"].sel(floor_point=["front", "rear"]).transpose("time", "floor_point").values
        out["ay_stability_rms_max_m_per_s2"] = float(stability_rms(t, ay, f0, window).max())
        out["ay_stability_rms_lim_m_per_s2"] = STABILITY_AY_LIMIT
    return out
