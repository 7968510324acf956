"""Curve entry (paper §4.2, Fig. 9, Table 4): carbody roll and air consumption across k, with the
levelling and differential pressure valves disconnected and connected; with ``curve.guidance:
contact`` also the wheel-rail forces and the running-safety quantities of EN 14363 (Y/Q against
Nadal's limit, ΣY against Prud'homme's, wheel unloading ΔQ/Q0; docs/wheel_rail.md, "Curve runs
with contact guidance"). Kind ``curve_entry``, section ``curve`` (:class:`CurveTest`)."""
from __future__ import annotations

from pathlib import Path
from typing import List, Optional, Sequence, Tuple

import numpy as np

from cosim.kinds.base import CarKind
from cosim.limits import en14363
from cosim.limits.assessment import STEP_M
from cosim.limits.criteria import (
    SLIDING_MEAN_M,
    nadal_limit,
    prudhomme_limit_N,
)
from cosim.limits.ride_comfort import comfort_columns
from cosim.results.io import Progress, read_rows
from cosim.results.outcome import Computed, Outcome, warn
from cosim.results.overlay import Selection, case_series
from cosim.results.plots import Curve, Figure, Panel, save_panels
from cosim.results.series import WHEELSETS
from cosim.runs.along_track import along_track, track_axis, wheel_rail_figures
from cosim.runs.car import bellow_panels, fault_columns, fault_figure, of_setting, per_case
from cosim.runs.track_run import (
    car_centre_s_m,
    case_metrics,
    make_car,
    ramp_roll_rate_step_rad_per_s,
    simulate,
    summary_row,
    track_twist_warnings,
)
from cosim.runs.track_spec import CurveTest, duration_s, extra_files, parse, valve_settings
from cosim.scenario.model import Scenario
from vehicle.params import BELLOWS, WHEELS

#: checkable metrics of the lateral wheel-rail forces: they need ``curve.guidance: contact``
CONTACT_METRICS = ("yq_max", "sum_y_max", "yq_2m_p9985", "sum_y_2m_p9985", "Y_2m_p50", "sum_y_rms_max")


def refuse_check(metric: str, curve: CurveTest) -> Optional[str]:
    """Why ``checks`` cannot name ``metric`` for this curve (None: it can)."""
    if metric in CONTACT_METRICS and not curve.contact:
        return (f"{metric} needs curve.guidance: contact (with {curve.guidance} guidance no lateral wheel-rail force "
                f"is computed)")
    if metric in en14363.QUASI_STATIC and not any(z in en14363.CURVE_ZONES for z in zones(curve)):
        return f"{metric} is a quasi-static value of a curve R < 600 m, and this track has none ({_track_words(curve)})"
    return None


def refuse_zone(metric: str, zone: str, curve: CurveTest) -> Optional[str]:
    """Why ``checks`` cannot name ``metric`` in ``zone`` (None: it can): EN 14363 assesses the
    quasi-static values in the arcs R < 600 m only."""
    if metric in en14363.QUASI_STATIC and zone not in en14363.CURVE_ZONES:
        curves = [z for z in zones(curve) if z in en14363.CURVE_ZONES]
        return (f"{metric} is a quasi-static value of an arc R < 600 m: zone {zone!r} has none (this track's: "
                f"{', '.join(curves)})")
    return None


def _track_words(curve: CurveTest) -> str:
    """The track in words: ``20 m straight, 15 m transition, R = 100 m`` or ``400 m straight alone``."""
    if curve.radius_m is None:
        return f"{curve.straight_m:g} m straight alone"
    return f"{curve.straight_m:g} m straight, {curve.transition_m:g} m transition, R = {curve.radius_m:g} m"


def zones(curve: CurveTest) -> Tuple[str, ...]:
    """The test zones of the curve's track (:mod:`cosim.limits.assessment`), in track order."""
    return tuple(dict.fromkeys(en14363.zone_table(curve.track())[1]))


def run(scenario: Scenario, progress: Progress) -> Computed:
    """The curve entry: every case, its summary row (:func:`summary_row`) and checkable metrics."""
    curve = scenario.experiment
    progress(f"curve entry at {curve.speed_m_per_s:g} m/s: {_track_words(curve)}, {curve.guidance} guidance"
             f"{', irregular track' if curve.irregularity else ''}; {len(scenario.k_W_per_K)} k values x valves "
             f"{curve.valve_settings}")
    track, warnings = curve.track(), []
    for message in track_twist_warnings(track, scenario.vehicle):
        warn(warnings, message)
    ds, diagnoses = simulate(scenario, progress)
    rows, cases, statistics, assessed = [], [], [], []
    s_centre = car_centre_s_m(scenario, ds["time"].values)
    yq_lim = nadal_limit(curve.nadal_flange_angle_deg, curve.nadal_friction)
    for j in range(ds.sizes["case"]):
        case = ds.isel(case=j)
        row = summary_row(case, curve)
        sum_y_lim = prudhomme_limit_N(float(case["Q0_N"].min()), curve.prudhomme_alpha)
        stats, found = en14363.assess_case(case, s_centre, track, scenario.vehicle, yq_lim, sum_y_lim)
        row.update(en14363.summary_columns(found))
        row.update(en14363.stability_columns(case, curve.speed_m_per_s, sum_y_lim))
        row.update(comfort_columns(case))
        row.update(fault_columns(scenario, case))
        rows.append(row)
        cases.append(case_metrics(row, en14363.zone_metrics(found, stats)))
        statistics += en14363.statistics_rows(stats, row["valves"], row["k_W_per_K"])
        assessed += en14363.limit_rows(found, row["valves"], row["k_W_per_K"])
    shown = ("valves", "k_W_per_K", "roll_max_rad", "roll_mean_end_rad", "air_injected_kg", "air_exhausted_kg",
             "dqq_2m_p9985", "Q_2m_p9985_N")
    if curve.contact:
        shown += ("yq_2m_p9985", "sum_y_2m_p9985_N")
    shown += ("en14363_failed",)
    info = {"window_s": curve.window, "guidance": curve.guidance}
    info.update(sliding_mean_m=SLIDING_MEAN_M, assessment_step_m=STEP_M,
                zones=list(en14363.zones_run(track, scenario.vehicle, s_centre[[0, -1]])))
    if curve.contact:
        info.update(yq_lim=rows[0]["yq_lim"] if rows else None, sum_y_lim_N=rows[0]["sum_y_lim_N"] if rows else None)
    if curve.irregularity is not None:
        info["irregularity"] = curve.track_irregularity(scenario.vehicle).source
    coarse = en14363.acceleration_warning(ds["time"].values)
    if coarse:
        warn(warnings, coarse)
    step = ramp_roll_rate_step_rad_per_s(curve)
    if step:
        warn(warnings, f"the linear cant ramp steps the rails' roll rate by {step:.3g} rad/s where a wheelset "
                       f"enters and leaves it (curve.transition_shape: linear): that rings each wheelset on its "
                       f"contacts (~240 Hz on a rigid track), beyond the step, so sampled peaks there (dqq_raw_max, "
                       f"Y_raw_max_N) depend on the step; the 2 m means hold better. transition_shape: bloss or cosine has "
                       f"no step")
    return Computed(rows, shown, {"curve": ds}, {"assessment": statistics, "assessment_limits": assessed}, cases,
                    diagnoses, warnings, info)


def figures(outcome: Outcome) -> List[Figure]:
    """Carbody roll (paper Fig. 9), per valve setting the bellows, and the air consumption; the roll
    and, with contact, the wheel-rail quantities also along the track (:func:`along_track`), each
    such figure named after its time figure with ``_along_track``."""
    if not outcome.rows:
        return []
    ds = outcome.series["curve"]
    curve = outcome.scenario.experiment
    axis = track_axis(outcome.scenario, ds["time"].values)
    settings = curve.valve_settings
    roll = [Panel(per_case(of_setting(ds, v)["roll_rel_rad"], 1e3), "time t [s]",
                  "carbody roll to the track plane [mrad]", f"valves {'connected' if v else 'disconnected'}")
            for v in settings]
    out = along_track(Figure("fig9_roll.png", roll, "Carbody roll entering a curve (paper Fig. 9)", len(roll)),
                      [axis.centre_m for _ in roll], [axis.spans] * len(roll), "car centre", axis.outer_text)
    for valves in settings:
        sub = of_setting(ds, valves)
        tag = "on" if valves else "off"
        heights = [Panel(per_case(sub["crushing_m"].sel(bellow=b), 1e3), "time t [s]", f"crushing z_{b} [mm]",
                         f"bellow {b}") for b in BELLOWS]
        out.append(Figure(f"bellows_valves={tag}.png", heights + bellow_panels(sub),
                          f"Bellow crushing (+ compression), pressure and temperature, valves {tag}", 2))
        if valves:
            out.append(Figure("air_consumption.png",
                              [Panel(per_case(sub["air_from_supply_kg"], 1e3), "time t [s]",
                                     "air injected from the supply [g]"),
                               Panel(per_case(sub["air_to_atmosphere_kg"], 1e3), "time t [s]",
                                     "air exhausted to the atmosphere [g]")],
                              "Air consumption of the levelling valves (paper Table 4)", 2))
        out += fault_figure(outcome.scenario, sub, f"_valves={tag}", f", valves {tag}")
    if curve.contact:
        out += wheel_rail_figures(ds, curve, outcome.rows, axis)
    return out


def _worst(run_dirs, columns: Sequence[str]) -> Optional[str]:
    """The label (wheel or wheelset) whose summary column ``<metric>_<label>...`` is largest over
    the runs' cases; ``columns``: (label, column) pairs."""
    best, where = -np.inf, None
    for d in run_dirs:
        for row in read_rows(d / "summary.csv") if (d / "summary.csv").exists() else []:
            for label, column in columns:
                try:
                    value = float(row.get(column, "nan"))
                except ValueError:
                    continue
                if value > best:
                    best, where = value, label
    return where


def compare(infos, out_dir: Path, select: Selection, label, window: str) -> List[Path]:
    """Overlay the carbody roll (to the track plane) and the air injected of several curve runs;
    with contact guidance also (ΔQ/Q0)_2m and (Y/Q)_2m of the worst wheel and (ΣY)_2m of the
    worst wheelset over the runs (or of the wheels ``select.wheels`` names)."""
    run_dirs = [d for d, _ in infos]

    def panel(column, scale, ylabel, title="", hlines=()):
        curves = [Curve(data["t_s"], data[column] * scale, label(d, case))
                  for d in run_dirs for case, data in case_series(d, "curve_", select) if column in data.dtype.names]
        return Panel(curves, "time t [s]", ylabel, title, hlines=list(hlines)) if curves else None

    panels = [panel("roll_carbody_rel_track_rad", 1e3, "carbody roll to the track plane [mrad]"),
              panel("air_from_supply_kg", 1e3, "air injected from the supply [g]")]
    info = infos[0][1]
    nadal = [(info["yq_lim"], f"Nadal limit {info['yq_lim']:.2f}")] if info.get("yq_lim") else []
    prud = ([(sign * info["sum_y_lim_N"] * 1e-3, "Prud'homme limit") for sign in (1.0, -1.0)]
            if info.get("sum_y_lim_N") else [])
    for column, name, ranked, limit in (("dqq_2m_{}", "(ΔQ/Q0)_2m", "dqq_2m_max_{}", []),
                                        ("YQ_2m_{}", "(Y/Q)_2m", "yq_max_{}", nadal)):
        worst = _worst(run_dirs, [(w, ranked.format(w)) for w in WHEELS])
        for w in select.wheels or ((worst,) if worst else ()):
            tag = f"wheel {w}" + (" (the worst)" if w == worst else "")
            panels.append(panel(column.format(w), 1.0, f"{name}, wheel {w} [-]", tag, limit))
    ws = _worst(run_dirs, [(n, f"sum_y_max_{n}_N") for n in WHEELSETS])
    if ws is not None:
        panels.append(panel(f"sumY_2m_{ws}_N", 1e-3, f"(ΣY)_2m, wheelset {ws} [kN]", f"wheelset {ws} (the worst)",
                            prud))
    panels = [p for p in panels if p is not None]
    return [save_panels(out_dir / "compare_curve.png", panels, f"Curve entry comparison{window}", ncols=2)]


class CurveEntryKind(CarKind):
    """A run into a curve (paper §4.2)."""

    name, section, experiment = "curve_entry", "curve", CurveTest
    check_metrics = ("roll_max_rad", "air_injected_kg", "air_exhausted_kg", "air_lost_kg", "yq_max", "sum_y_max",
                     "dqq_raw_max",
                     "dqq_2m_max", "sum_y_rms_max", *en14363.METRICS)
    wheel_metrics = ("dqq_raw_max", "yq_max", "dqq_2m_max",
                     *(m for m, (q, _, _) in en14363.METRICS.items() if en14363.QUANTITIES.get(q, ("", ""))[1] == "wheel"))
    zone_metrics = tuple(en14363.METRICS)
    # the processed quantities an engineer is judged by: EN 14363's statistics of the 2 m
    # means along the track (cosim.limits.en14363), the roll (largest, and its mean over the
    # final window), the air; not the raw sampled peaks (dqq_raw_max, Y_raw_max_N: one sample
    # of a transient the step may not resolve); a column that is absent (yq_2m_p9985 and
    # sum_y_2m_p9985_N without contact, Y_2m_p50_N without an arc R < 600 m) is skipped; the
    # carbody accelerations by their rms: their largest filtered value is one output sample
    # (checkable, in the summary and the report, but a single sample; on curve_canted it is
    # 0.53 % from its Richardson estimate, and the sampling at the output interval can miss a
    # 10 Hz peak by more)
    headline_metrics = ("roll_max_rad", "roll_end_rad", "roll_mean_end_rad", "air_injected_kg",
                        "air_exhausted_kg", "dqq_2m_p9985", "Q_2m_p9985_N", "Q_2m_p50_N", "Y_2m_p50_N",
                        "yq_2m_p9985", "sum_y_2m_p9985_N", "ay_floor_rms_m_per_s2", "az_floor_rms_m_per_s2")
    plot_metrics = ("roll_max_rad", "roll_mean_end_rad", "air_injected_kg", "air_exhausted_kg")

    parse = staticmethod(parse)
    duration_s = staticmethod(duration_s)
    valve_settings = staticmethod(valve_settings)
    extra_files = staticmethod(extra_files)
    refuse_check = staticmethod(refuse_check)
    refuse_zone = staticmethod(refuse_zone)
    zones = staticmethod(zones)
    make_car = staticmethod(make_car)
    run = staticmethod(run)
    figures = staticmethod(figures)
    compare = staticmethod(compare)


KIND = CurveEntryKind()
