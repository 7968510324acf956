"""Ride comfort on irregular track (EN 12299): the car with wheel-rail contact at a list of speeds,
on straight track or in a curve, over seeded irregularities, across k and valve settings. Per case
(speed x k x valve setting) the comfort indices at each floor point over the record
(:mod:`cosim.limits.ride_comfort`), and figures of comfort against speed and of the floor accelerations'
power spectra. Kind ``ride``, section ``ride`` (:class:`RideTest`).

Each speed is a run along a track built for it (:func:`curve_at`): the car starts at rest on design
track, the irregularity fades in ahead of it, the record starts ``settle_s`` later (in a curve:
once the whole car is in the arc as well) and lasts ``record_s``. The speeds run on one pool of
``solver.jobs`` processes, a speed's k values on one circuit where the processes allow
(:func:`cosim.runs.track_run.simulate_many`)."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Mapping, Optional, Tuple

import numpy as np

from cosim.errors import ScenarioError
from cosim.kinds.base import CarKind
from cosim.limits.ride_comfort import COLUMNS, comfort_columns
from cosim.results.io import Progress, read_rows
from cosim.results.outcome import Computed, Outcome, warn
from cosim.results.overlay import Selection
from cosim.results.plots import Curve, Figure, Panel, Span, k_legend, save_panels
from cosim.runs.along_track import along_track, track_axis
from cosim.runs.car import fault_columns
from cosim.runs.track_run import make_car as track_car
from cosim.runs.track_run import simulate_many, summary_row, track_twist_warnings
from cosim.runs.track_spec import CANT, RADIUS, SPEED, TRANSITION, CurveTest, IrregularitySpec, parse_irregularity
from cosim.scenario.model import Scenario
from cosim.scenario.schema import build, check_valve_settings
from pneumorail.quantities import plausible, ranged
from vehicle.irregularities import CHANNELS
from vehicle.params import FLOOR_POINTS, VehicleParams

#: the default irregularity: ERRI B176 low level, all four channels
DEFAULT_IRREGULARITY = {"psd": "erri_b176_low", "seed": 0, "channels": list(CHANNELS)}
#: room left on the track after the record [m]
TRACK_MARGIN_M = 30.0
#: a straight ride's track is longer by this [m]: it was the straight with a 15 m transition and a
#: 20 m arc of R = 10 km beyond the car's reach. The irregularity spans the whole track, and on a
#: track longer than PERIOD_FACTOR x the longest wavelength (8 x 150 m) its length sets the PSD's
#: frequency grid (vehicle.irregularities.TrackIrregularity.from_psd): the same length keeps the
#: same seeded track and every ride number on the straight alone. (Tried: without these 35 m every
#: ride_comfort time series changes; a 6100 m and a 6065 m track of seed 0 differ by 5.7 mm.)
STRAIGHT_TAIL_M = 35.0


@dataclass(frozen=True)
class RideTest:
    """A ride at each of ``speeds_m_per_s`` for ``settle_s`` + ``record_s`` (EN 12299 evaluates 5
    minutes: the default), on straight track (``radius_m``: null) or in a curve of ``radius_m``
    with ``cant_rad``, entered over a Bloss transition of ``transition_m`` after a 20 m straight.
    ``irregularity``: as a curve's (:class:`~cosim.runs.track_spec.IrregularitySpec`; default ERRI
    B176 low in all four channels, seed 0). ``valve_settings``: runs with the levelling and
    differential valves disconnected (false) and connected (true)."""

    speeds_m_per_s: Tuple[float, ...] = field(default=(10.0, 20.0), metadata=ranged(SPEED, non_empty=True, unique=True))
    # EN 12299 records 300 s; an hour is twelve of its records (a time in ms falls out). At least
    # one 5 s block: parse
    record_s: float = field(default=300.0, metadata=plausible(
        0.0, 3600.0, "s", "the comfort record (EN 12299: 300 s); at least one 5 s block", low_inclusive=False))
    settle_s: float = field(default=5.0, metadata=plausible(0.0, 3600.0, "s", "the run before the record"))
    radius_m: Optional[float] = field(default=None, metadata=RADIUS)
    cant_rad: float = field(default=0.0, metadata=CANT)
    transition_m: float = field(default=30.0, metadata=TRANSITION)
    valve_settings: Tuple[bool, ...] = field(default=(True,), metadata=ranged(non_empty=True, unique=True))
    irregularity: Optional[IrregularitySpec] = None



def curve_at(ride: RideTest, speed_m_per_s: float, vehicle: VehicleParams) -> Tuple[CurveTest, float]:
    """The curve-entry run of one speed and the time its record starts [s]."""
    car = vehicle.bogie_centre_distance_m + vehicle.wheelbase_m
    v = float(speed_m_per_s)
    if ride.radius_m is None:
        straight = car + v * (ride.settle_s + ride.record_s) + TRACK_MARGIN_M + STRAIGHT_TAIL_M
        curve = CurveTest(speed_m_per_s=v, straight_m=straight, radius_m=None,
                          duration_s=ride.settle_s + ride.record_s, valve_settings=ride.valve_settings,
                          irregularity=ride.irregularity, window_s=min(5.0, ride.settle_s + ride.record_s))
        return curve, ride.settle_s
    # the whole car in the arc: the rear wheelset (at s = v t) past its start
    in_arc = (20.0 + ride.transition_m) / v
    start = max(ride.settle_s, in_arc)
    arc = v * (start + ride.record_s) + car + TRACK_MARGIN_M - 20.0 - ride.transition_m
    curve = CurveTest(speed_m_per_s=v, straight_m=20.0, transition_m=ride.transition_m, radius_m=ride.radius_m,
                      arc_m=arc, cant_rad=ride.cant_rad, duration_s=start + ride.record_s,
                      valve_settings=ride.valve_settings, irregularity=ride.irregularity,
                      window_s=min(5.0, start + ride.record_s))
    return curve, start


def parse(data, vehicle: VehicleParams, path: Path) -> RideTest:
    """The ``ride`` section: speeds, record, track; the irregularity checked (and generated once)
    on the track of every speed."""
    data = dict(data) if isinstance(data, Mapping) else data
    irregularity = data.pop("irregularity", DEFAULT_IRREGULARITY) if isinstance(data, dict) else None
    ride = build(RideTest, data, path, ["ride"])
    if ride.record_s < 5.0:
        raise ScenarioError(path, ["ride", "record_s"], f"the record must hold one 5 s block, got {ride.record_s:g} s")
    check_valve_settings(ride.valve_settings, path, ["ride", "valve_settings"])
    if irregularity is None:
        return ride
    spec = None
    for v in ride.speeds_m_per_s:
        curve, _ = curve_at(ride, v, vehicle)
        try:
            curve.track()
        except ValueError as exc:
            raise ScenarioError(path, ["ride"], f"the track at {v:g} m/s cannot be built: {exc}") from None
        spec = parse_irregularity(irregularity, curve, vehicle, path, ("ride", "irregularity"))
    return dataclasses.replace(ride, irregularity=spec)


def duration_s(ride: RideTest) -> float:
    """How long the longest case runs [s]: in a curve the slowest speed waits longest for the
    whole car to be in the arc."""
    if ride.radius_m is None:
        return ride.settle_s + ride.record_s
    return max(ride.settle_s, (20.0 + ride.transition_m) / min(ride.speeds_m_per_s)) + ride.record_s


def shortest_duration_s(ride: RideTest) -> float:
    """How long the shortest case runs [s] (the fastest speed in a curve): every fault must
    happen within it."""
    if ride.radius_m is None:
        return duration_s(ride)
    return max(ride.settle_s, (20.0 + ride.transition_m) / max(ride.speeds_m_per_s)) + ride.record_s


def valve_settings(ride: RideTest, valves: bool) -> Tuple[bool, ...]:
    return ride.valve_settings


def extra_files(ride: RideTest) -> Tuple[Path, ...]:
    spec = ride.irregularity
    return (Path(spec.file),) if spec is not None and spec.file is not None else ()


def make_car(scenario: Scenario):
    """The car of the first speed's run (:func:`run` builds each speed's through its curve)."""
    ride = scenario.experiment
    return track_car(_speed_scenario(scenario, curve_at(ride, ride.speeds_m_per_s[0], scenario.vehicle)[0]))


def _speed_scenario(scenario: Scenario, curve: CurveTest) -> Scenario:
    """The scenario of one speed: the ride's, running the track run of that speed
    (:mod:`cosim.runs.track_run` reads its experiment)."""
    return dataclasses.replace(scenario, experiment=curve)


def run(scenario: Scenario, progress: Progress) -> Computed:
    """Every speed, k value and valve setting; per case its summary row with the comfort over the
    record."""
    ride = scenario.experiment
    progress(f"ride at {', '.join(f'{v:g}' for v in ride.speeds_m_per_s)} m/s, "
             f"{'straight track' if ride.radius_m is None else f'R = {ride.radius_m:g} m'}, {ride.record_s:g} s "
             f"records; {len(scenario.k_W_per_K)} k values x valves {ride.valve_settings}")
    rows, series, diagnoses = [], {}, []
    runs = [curve_at(ride, v, scenario.vehicle) for v in ride.speeds_m_per_s]
    warnings: List[str] = []
    for message in track_twist_warnings(runs[0][0].track(), scenario.vehicle):  # the same ramp at every speed
        warn(warnings, message)
    # all speeds on one pool: a speed's k values share a process and a circuit where the processes allow
    results = simulate_many([_speed_scenario(scenario, curve) for curve, _ in runs], progress,
                                        [f"{scenario.name} {v:g} m/s" for v in ride.speeds_m_per_s])
    for v, (curve, start), (ds, found) in zip(ride.speeds_m_per_s, runs, results):
        diagnoses += [f"{v:g} m/s: {d}" for d in found]
        series[f"ride_v={v:g}"] = ds
        for j in range(ds.sizes["case"]):
            case = ds.isel(case=j)
            row = {"speed_m_per_s": float(v), **summary_row(case, curve), "record_from_s": start}
            row.update(comfort_columns(case, start))
            row.update(fault_columns(scenario, case))
            rows.append(row)
    shown = ("speed_m_per_s", "valves", "k_W_per_K", *(f"N_MV_{p}" for p in FLOOR_POINTS), "Wz_y_centre", "Wz_z_centre",
             "Cc_y_max_centre_m_per_s2", "Cc_z_max_centre_m_per_s2", "roll_max_rad", "air_injected_kg")
    info = {"record_s": ride.record_s, "speeds_m_per_s": list(ride.speeds_m_per_s),
            "irregularity": None if ride.irregularity is None else ride.irregularity.psd or ride.irregularity.file}
    if ride.record_s < 300.0:
        warn(warnings, f"records of {ride.record_s:g} s: EN 12299 evaluates N_MV over 300 s; the percentiles rest on "
                       f"{int(ride.record_s // 5)} blocks")
    return Computed(rows, shown, series, diagnoses=diagnoses, warnings=warnings, info=info)


def figures(outcome: Outcome) -> List[Figure]:
    """Comfort against speed (a line per k and valve setting, a panel per floor point and index)
    and the power spectra of the lateral and vertical floor accelerations at the car centre."""
    rows = outcome.rows
    if not rows:
        return []
    keys = sorted({(r["valves"], r["k_W_per_K"]) for r in rows})
    multi = len({r["valves"] for r in rows}) > 1

    panels = []
    for column, name in (("N_MV_{}", "N_MV [-]"), ("Wz_y_{}", "Wz lateral [-]"), ("Wz_z_{}", "Wz vertical [-]")):
        for point in FLOOR_POINTS:
            curves = []
            for valves, k in keys:
                mine = sorted((r["speed_m_per_s"], r.get(column.format(point), np.nan)) for r in rows
                              if (r["valves"], r["k_W_per_K"]) == (valves, k))
                curves.append(Curve([m[0] for m in mine], [m[1] for m in mine], legend(valves, k, multi), "o-"))
            panels.append(Panel(curves, "speed v [m/s]", name, f"floor, {point}"))
    out = [Figure("comfort_vs_speed.png", panels, "Ride comfort against speed (EN 12299 N_MV, Sperling Wz)", 3)]
    psd = []
    from scipy.signal import welch
    for name, ds in outcome.series.items():
        t = ds["time"].values
        fs = 1.0 / float(np.median(np.diff(t)))
        start = next(r["record_from_s"] for r in rows if f"ride_v={r['speed_m_per_s']:g}" == name)
        keep = t >= start
        for axis, long in (("y", "lateral"), ("z", "vertical")):
            curves = []
            for j in range(ds.sizes["case"]):
                a = ds[f"floor_a{axis}_m_per_s2"].isel(case=j).sel(floor_point="centre").values[keep]
                if a.size < 16 or not np.isfinite(a).all():
                    continue
                f, p = welch(a - a.mean(), fs=fs, nperseg=min(a.size, int(20 * fs)))
                case = ds.isel(case=j)
                curves.append(Curve(f[1:], p[1:], legend(bool(case["valves"]), float(case["k_W_per_K"]), multi)))
            psd.append(Panel(curves, "frequency f [Hz]", f"PSD of the {long} floor acceleration [(m/s²)²/Hz]",
                             f"{name.split('=')[1]} m/s, car centre", logx=True, logy=True))
    out.append(Figure("psd_floor.png", psd, "Floor accelerations at the car centre: power spectral density (Welch)", 2))
    return out + floor_figures(outcome)


def legend(valves: bool, k: float, valves_named: bool) -> str:
    """A case's legend: its k, after its valve setting when the run has several."""
    return (f"valves {'on' if valves else 'off'}, " if valves_named else "") + k_legend(k)


def floor_figures(outcome: Outcome) -> List[Figure]:
    """The lateral and vertical (less g) floor accelerations at the car centre, a panel per speed
    and direction, against time and along the track (:func:`cosim.runs.along_track.along_track`:
    each speed's own track, its segments and the comfort record marked)."""
    ride, scenario = outcome.scenario.experiment, outcome.scenario
    multi = len(ride.valve_settings) > 1
    panels, positions, spans = [], [], []
    for v in ride.speeds_m_per_s:
        ds = outcome.series[f"ride_v={v:g}"]
        curve, start = curve_at(ride, v, scenario.vehicle)
        axis = track_axis(_speed_scenario(scenario, curve), ds["time"].values)
        record = Span(float(np.interp(start, ds["time"].values, axis.centre_m)), float(axis.centre_m[-1]),
                      f"comfort record from t = {start:g} s", shade=False)
        for axis_name, long, offset in (("y", "lateral", 0.0),
                                        ("z", "vertical, less g", scenario.vehicle.gravity_m_per_s2)):
            accel = ds[f"floor_a{axis_name}_m_per_s2"].sel(floor_point="centre") - offset
            curves = [Curve(ds["time"].values, accel.isel(case=j).values,
                            legend(bool(ds["valves"].values[j]), float(ds["k_W_per_K"].values[j]), multi))
                      for j in range(ds.sizes["case"])]
            panels.append(Panel(curves, "time t [s]", f"{long} floor acceleration [m/s²]", f"{v:g} m/s, car centre"))
            positions.append(axis.centre_m)
            spans.append([*axis.spans, record])
    where = "straight track" if ride.radius_m is None else f"R = {ride.radius_m:g} m, {axis.outer_text}"
    figure = Figure("floor_accelerations.png", panels, f"Floor accelerations at the car centre ({where})", 2)
    return along_track(figure, positions, spans, "car centre")


def compare(infos, out_dir: Path, select: Selection, label, window: str) -> List[Path]:
    """N_MV and Wz at the car centre against speed, a line per run and k."""
    panels = []
    for column, name in (("N_MV_centre", "N_MV, car centre [-]"), ("Wz_y_centre", "Wz lateral, car centre [-]"),
                         ("Wz_z_centre", "Wz vertical, car centre [-]")):
        curves = []
        for d, _ in infos:
            rows = read_rows(d / "summary.csv") if (d / "summary.csv").exists() else []
            by_case: Dict[Tuple[str, str], List[Tuple[float, float]]] = {}
            for r in rows:
                if select.k is not None and float(r["k_W_per_K"]) not in select.k:
                    continue
                by_case.setdefault((r["valves"], r["k_W_per_K"]), []).append((float(r["speed_m_per_s"]), float(r[column])))
            for (valves, k), points in by_case.items():
                points.sort()
                curves.append(Curve([p[0] for p in points], [p[1] for p in points],
                                    label(d, f"valves {'on' if valves == 'True' else 'off'}, k = {k} W/K"), "o-"))
        panels.append(Panel(curves, "speed v [m/s]", name))
    return [save_panels(out_dir / "compare_ride.png", panels, f"Ride comfort comparison{window}", ncols=3)]


class RideKind(CarKind):
    """Ride comfort on irregular track at a list of speeds."""

    name, section, experiment = "ride", "ride", RideTest
    check_metrics = tuple(c.format(p) for c in COLUMNS for p in FLOOR_POINTS)
    # the comfort indices over the record; roll and air as in a curve run
    # the indices over the record; the Cc maxima are in the summary and checkable
    headline_metrics = (*(c.format(p) for c in COLUMNS[:3] for p in FLOOR_POINTS), "roll_max_rad", "air_injected_kg")
    plot_metrics = ("N_MV_centre", "Wz_y_centre", "Wz_z_centre")
    # a case is a speed as well as a k value and valve setting
    case_columns = ("speed_m_per_s", "valves", "k_W_per_K")

    parse = staticmethod(parse)
    duration_s = staticmethod(duration_s)
    shortest_duration_s = staticmethod(shortest_duration_s)
    valve_settings = staticmethod(valve_settings)
    extra_files = staticmethod(extra_files)
    make_car = staticmethod(make_car)
    run = staticmethod(run)
    figures = staticmethod(figures)
    compare = staticmethod(compare)


KIND = RideKind()
