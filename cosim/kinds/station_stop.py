"""A station stop: the car stands at a platform while passengers board and alight (``payload:``),
and the levelling valves bring the floor back to the platform. Kind ``station_stop``, section
``station`` (:class:`StationStop`).

Per case (k value x valve setting) the summary gives, at the door thresholds on the platform side
(the front, centre and rear doors), the floor height relative to its height when the car
arrived (t = 0): at door close, its lowest and highest during the stop; the time the floor
needs to re-level, i.e. to come back for good within the tolerance of its arrival height; the
number of valve openings and when the last valve closed (``valves_settled_s``, from the start of
the payload change); the air injected and exhausted.

Why a kind of its own rather than the twist on level track: what it reports (floor heights at the
doors, a re-levelling time against a step-height tolerance, valve openings) is none of the
twist's wheel unloading, and its figures are the floor against the tolerance band; the car and
the run are the twist's (standing, kinematic guidance, level rails).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Tuple

import numpy as np
import xarray as xr

from cosim.engine.cases import simulate_cases
from cosim.engine.master import Output, Sample
from cosim.errors import ScenarioError
from cosim.kinds.base import CarKind
from cosim.results.io import Progress
from cosim.results.outcome import Computed, Outcome, warn
from cosim.results.plots import Curve, Figure, Panel, Span, k_legend
from cosim.runs.car import air_columns, bellow_panels, fault_columns, of_setting, per_case
from cosim.scenario.model import Scenario
from cosim.scenario.schema import build, check_valve_settings, k_label
from pneumorail.quantities import plausible, positive, ranged
from vehicle.params import FLOOR_POINTS, VehicleParams

#: Step-height tolerance of the floor at the platform [m]: +-5/8 inch, the US ADA's rule for
#: level boarding of rapid-rail cars, "the height of the vehicle floor shall be within plus or
#: minus 5/8 inch of the platform height under all normal passenger load conditions" (49 CFR
#: 38.53(d)(1); quoted from memory of the regulation, not checked against its text here). EN 14752
#: and the PRM TSI give step gaps for main-line stock, not a metro's floor-to-platform tolerance.
ADA_STEP_TOLERANCE_M = 0.625 * 0.0254


@dataclass(frozen=True)
class Doors:
    """The car's doors at a platform: along the car at ``doors_x_m`` (front, centre, rear door;
    from its centre, + forward; **assumed** +-4.5 m and 0 for a 14 m metro car with three doors a
    side), their thresholds ``door_y_m`` from the centre line (**assumed** 1.3 m, half a 2.6 m
    floor); ``tolerance_m``: the floor's step-height tolerance at the doors
    (:data:`ADA_STEP_TOLERANCE_M`)."""

    doors_x_m: Tuple[float, ...] = field(default=(4.5, 0.0, -4.5), metadata=plausible(-20.0, 20.0, "m", "along a carbody"))
    door_y_m: float = field(default=1.3, metadata=plausible(0.0, 2.0, "m", "half a carbody's width"))
    tolerance_m: float = field(default=ADA_STEP_TOLERANCE_M, metadata=plausible(
        0.0, 0.1, "m", "a step height; 0.1 m is a stair, not a tolerance", low_inclusive=False))

    def door_points(self, side: str) -> Tuple[Tuple[float, float], ...]:
        """(x, y) of the door thresholds on the ``side`` (left or right) of the car."""
        y = self.door_y_m if side == "left" else -self.door_y_m
        return tuple((x, y) for x in self.doors_x_m)


def check_doors(doors: Doors, path: Path, section: str) -> None:
    """One door position per floor point (:data:`FLOOR_POINTS`)."""
    if len(doors.doors_x_m) != len(FLOOR_POINTS):
        raise ScenarioError(path, [section, "doors_x_m"], f"expected {len(FLOOR_POINTS)} door positions (the "
                                                          f"{', '.join(FLOOR_POINTS)} door), got {len(doors.doors_x_m)}")


@dataclass(frozen=True)
class StationStop(Doors):
    """The car stands ``duration_s`` at a platform on its ``platform_side``; its doors there
    (:class:`Doors`). The doors close at ``doors_close_s`` (null: when the last payload event ends,
    or at the end of a stop without one). ``valve_settings``: as the twist's (null: one run as
    ``circuit.valves`` says)."""

    duration_s: float = field(default=60.0, metadata=plausible(0.0, 3600.0, "s", "a stop, up to an hour",
                                                                low_inclusive=False))
    platform_side: str = "right"
    doors_close_s: Optional[float] = field(default=None, metadata=ranged(positive("s")))
    valve_settings: Optional[Tuple[bool, ...]] = None

    @property
    def door_points_m(self) -> Tuple[Tuple[float, float], ...]:
        """(x, y) of the door thresholds on the platform side."""
        return self.door_points(self.platform_side)


def parse(data, vehicle: VehicleParams, path: Path) -> StationStop:
    """``station:`` checked (its own keys; the payload is the scenario's ``payload:``)."""
    stop = build(StationStop, data, path, ["station"])
    if stop.platform_side not in ("left", "right"):
        raise ScenarioError(path, ["station", "platform_side"], f"expected left or right, got {stop.platform_side!r}")
    check_doors(stop, path, "station")
    if stop.doors_close_s is not None and not stop.doors_close_s <= stop.duration_s:
        raise ScenarioError(path, ["station", "doors_close_s"], f"the doors must close within the stop "
                                                                f"({stop.duration_s:g} s), got {stop.doors_close_s:g} s")
    if stop.valve_settings is not None:
        check_valve_settings(stop.valve_settings, path, ["station", "valve_settings"])
    return stop


def duration_s(stop: StationStop) -> float:
    return stop.duration_s


def valve_settings(stop: StationStop, valves: bool) -> Tuple[bool, ...]:
    return stop.valve_settings or (valves,)


def make_car(scenario: Scenario):
    """The car standing on level rails with its payload (picklable factory for cosim.engine.cases)."""
    from vehicle.car import MetroCar  # exudyn: imported when a car is built, not to read a scenario
    return MetroCar(scenario.vehicle, step_s=scenario.solver.mechanics_step_s,
                    spectral_radius=scenario.solver.spectral_radius, track_structure=scenario.track,
                    payload=scenario.car_payload)


@dataclass(frozen=True)
class FloorHeights:
    """The read of the floor heights at ``points_xy_m`` (one per :data:`FLOOR_POINTS`) of every
    running car (a frozen dataclass: it travels to the worker processes)."""

    points_xy_m: Tuple[Tuple[float, float], ...]

    def __call__(self, sample: Sample) -> np.ndarray:
        cars, active = sample.sim.cars, sample.sim.active
        out = np.zeros((len(self.points_xy_m), len(cars)))
        for j, car in enumerate(cars):
            if active[j]:
                out[:, j] = car.floor_heights_m(self.points_xy_m)
        return out


def payload_kg(sample: Sample) -> np.ndarray:
    """The payload each running car carries [kg]."""
    return np.array([car.payload_kg() if on else 0.0 for car, on in zip(sample.sim.cars, sample.sim.active)])


def outputs(stop: StationStop) -> Tuple[Output, ...]:
    """What a station stop samples besides every car run's outputs."""
    return (Output("floor_z_m", ("floor_point",), "m", "floor height above rail top at the door thresholds on the "
                   "platform side (front, centre, rear door)", "floor_z_{}_m", FloorHeights(stop.door_points_m)),
            Output("payload_kg", (), "kg", "payload on board", "payload_kg", payload_kg))


def doors_close_s(scenario: Scenario) -> float:
    """When the doors close: ``station.doors_close_s``, else the end of the last payload event, else
    the end of the stop."""
    stop = scenario.experiment
    if stop.doors_close_s is not None:
        return stop.doors_close_s
    events = scenario.payload.events if scenario.payload is not None else ()
    return max((e.end_s for e in events), default=stop.duration_s)


def payload_start_s(scenario: Scenario) -> float:
    """When the payload starts to change (the first event; 0 without one)."""
    events = scenario.payload.events if scenario.payload is not None else ()
    return min((e.t_s for e in events), default=0.0)


def openings(open_s: np.ndarray) -> int:
    """How many times valve sides opened, from their cumulative open times (samples, sides): a
    side opened in a sample interval where its open time grows after one where it did not (or
    at the first). Counted at the sampling interval: a valve that shuts and reopens within one
    interval counts once."""
    growing = np.diff(open_s, axis=0) > 0.0
    if growing.size == 0:
        return 0
    starts = growing[0].sum() + (growing[1:] & ~growing[:-1]).sum()
    return int(starts)


def relevel_s(t_s: np.ndarray, dz_m: np.ndarray, tolerance_m: float, since_s: float) -> float:
    """Time [s] after ``since_s`` from which every door point's floor height stays within
    +-``tolerance_m`` of its arrival height (0: it never left the band; NaN: it is still outside
    at the end of the stop)."""
    outside = np.any(np.abs(dz_m) > tolerance_m, axis=1) & (t_s >= since_s)
    if not outside.any():
        return 0.0
    last = int(np.flatnonzero(outside)[-1])
    if last == len(t_s) - 1:
        return math.nan
    return float(t_s[last + 1] - since_s)


def last_closing_s(t_s: np.ndarray, open_s: np.ndarray, since_s: float) -> float:
    """Time [s] after ``since_s`` at which the last valve side closed for the rest of the stop
    (from the cumulative open times (samples, sides), at the sampling interval; 0: none opened
    after ``since_s``; NaN: one is still open at the end)."""
    growing = np.any(np.diff(open_s, axis=0) > 0.0, axis=1) if open_s.size else np.zeros(len(t_s) - 1, bool)
    growing &= t_s[1:] > since_s
    if not growing.any():
        return 0.0
    last = int(np.flatnonzero(growing)[-1])
    if last == len(growing) - 1:
        return math.nan
    return float(t_s[last + 1] - since_s)


def stop_metrics(case: xr.Dataset, stop: StationStop, close_s: float, since_s: float) -> Dict[str, object]:
    """Summary of one case: the floor at the doors relative to arrival (at door close, lowest,
    highest), the re-levelling time, the valve openings."""
    t = case["time"].values
    z = case["floor_z_m"].transpose("time", "floor_point").values
    dz = z - z[0]
    i_close = int(np.argmin(np.abs(t - close_s)))
    row: Dict[str, object] = {f"floor_dz_close_{p}_m": float(dz[i_close, i]) for i, p in enumerate(FLOOR_POINTS)}
    worst = int(np.argmax(np.abs(dz[i_close])))
    row.update(floor_dz_close_m=float(dz[i_close, worst]), floor_dev_close_m=float(np.abs(dz[i_close]).max()),
               floor_dev_max_m=float(np.abs(dz).max()), floor_dz_min_m=float(dz.min()),
               floor_dz_max_m=float(dz.max()), floor_dz_end_m=float(dz[-1, np.argmax(np.abs(dz[-1]))]),
               relevel_s=relevel_s(t, dz, stop.tolerance_m, since_s))
    sides = {side: case[f"valve_{side}_open_s"].transpose("time", "valve").values if "valve" in case.dims else
             np.zeros((len(t), 0)) for side in ("supply", "exhaust")}
    row.update({f"valve_openings_{side}": openings(v) for side, v in sides.items()})
    row["valve_openings"] = row["valve_openings_supply"] + row["valve_openings_exhaust"]
    row["valves_settled_s"] = last_closing_s(t, np.concatenate(list(sides.values()), axis=1), since_s)
    row["payload_end_kg"] = float(case["payload_kg"].values[-1])
    return row


def run(scenario: Scenario, progress: Progress) -> Computed:
    """Every case of the stop: its summary row (:func:`stop_metrics`, the air) and series."""
    stop = scenario.experiment
    settings = stop.valve_settings or (None,)
    close_s, since_s = doors_close_s(scenario), payload_start_s(scenario)
    payload = scenario.payload.label() if scenario.payload is not None else "no payload change"
    progress(f"station stop {stop.duration_s:g} s, platform on the {stop.platform_side}: {payload}; doors close at "
             f"{close_s:g} s; {len(scenario.k_W_per_K)} k values")
    ds, diagnoses = simulate_cases(scenario, settings, make_car, stop.duration_s, progress, outputs(stop))
    rows: List[Dict[str, object]] = []
    found: List[str] = []
    for j, (k, valves) in enumerate(zip(ds["k_W_per_K"].values, ds["valves"].values)):
        case = ds.isel(case=j)
        row = {"valves": bool(valves), "k_W_per_K": float(k), **stop_metrics(case, stop, close_s, since_s)}
        row.update(air_columns(case))
        row.update(fault_columns(scenario, case))
        rows.append(row)
        if math.isnan(row["relevel_s"]):
            warn(found, f"k = {k_label(float(k))}: the floor is still {row['floor_dz_end_m'] * 1e3:+.1f} mm from its "
                        f"arrival height at the end of the stop, beyond +-{stop.tolerance_m * 1e3:g} mm")
    info = {"doors_close_s": close_s, "payload_start_s": since_s, "tolerance_m": stop.tolerance_m,
            "door_points_m": [list(p) for p in stop.door_points_m], "payload": payload}
    if scenario.payload is not None:
        info.update(normal_payload_kg=scenario.payload.normal_payload_kg,
                    exceptional_payload_kg=scenario.payload.exceptional_payload_kg)
    shown = ("valves", "k_W_per_K", "floor_dz_close_m", "floor_dz_min_m", "floor_dz_end_m", "relevel_s",
             "valves_settled_s", "valve_openings",
             "air_injected_kg", "air_exhausted_kg")
    return Computed(rows, shown, {"station_stop": ds}, diagnoses=diagnoses, warnings=found, info=info)


def figures(outcome: Outcome) -> List[Figure]:
    """Per valve setting: the floor at each door relative to arrival with the tolerance band, a
    panel per k; the payload; the bellows."""
    if not outcome.rows:
        return []
    scenario = outcome.scenario
    stop, ds = scenario.experiment, outcome.series["station_stop"]
    close_s, since_s = doors_close_s(scenario), payload_start_s(scenario)
    tol = stop.tolerance_m * 1e3
    band = [(tol, f"+{tol:.1f} mm"), (-tol, f"-{tol:.1f} mm")]
    doors = [Span(since_s, close_s, "doors open", shade=True)]
    out = []
    for setting in stop.valve_settings or (None,):
        sub = of_setting(ds, setting)
        suffix = "" if setting is None else f"_valves={'on' if setting else 'off'}"
        valves = "" if setting is None else f", valves {'connected' if setting else 'isolated'}"
        panels = []
        for c, k in zip(sub["case"].values, sub["k_W_per_K"].values):
            z = sub["floor_z_m"].sel(case=c).transpose("time", "floor_point")
            t = sub["time"].values
            curves = [Curve(t, (z.values[:, i] - z.values[0, i]) * 1e3, f"{p} door") for i, p in enumerate(FLOOR_POINTS)]
            panels.append(Panel(curves, "time t [s]", "floor height - at arrival [mm]", k_legend(float(k)), hlines=band,
                                spans=doors))
        out += [Figure(f"floor_at_doors{suffix}.png", panels,
                       f"Floor at the {stop.platform_side}-hand doors relative to arrival, tolerance +-{tol:.1f} mm"
                       f"{valves}", 2),
                Figure(f"payload{suffix}.png",
                       [Panel(per_case(sub["payload_kg"]), "time t [s]", "payload on board [kg]", "payload"),
                        Panel(per_case(sub["air_from_supply_kg"], 1e3), "time t [s]", "air injected [g]", "air")],
                       f"Payload and air{valves}", 2),
                Figure(f"bellows{suffix}.png", bellow_panels(sub), f"Bellow pressures and temperatures{valves}", 2)]
    return out


class StationStopKind(CarKind):
    """A station stop: passengers board and alight, the valves re-level the floor."""

    name, section, experiment = "station_stop", "station", StationStop
    # deviations (>= 0) of the floor from its arrival height, so that "largest" is "worst"
    check_metrics = ("floor_dev_close_m", "floor_dev_max_m", "relevel_s", "valve_openings", "air_injected_kg")
    headline_metrics = ("floor_dev_close_m", "floor_dev_max_m", "air_injected_kg")
    total_metrics = ("floor_dev_close_m", "floor_dev_max_m", "relevel_s", "valve_openings", "air_injected_kg")
    plot_metrics = ("floor_dev_close_m", "relevel_s", "air_injected_kg")

    parse = staticmethod(parse)
    duration_s = staticmethod(duration_s)
    valve_settings = staticmethod(valve_settings)
    make_car = staticmethod(make_car)
    run = staticmethod(run)
    figures = staticmethod(figures)


KIND = StationStopKind()
