"""Curve entry (paper §4.2, Fig. 9, Table 4): carbody roll and air consumption across k, with the
levelling and differential pressure valves disconnected and connected."""
from __future__ import annotations

import time
from typing import Dict, List, Optional, Tuple

import numpy as np
import xarray as xr

from vehicle.car import MetroCar
from vehicle.params import BELLOWS

from .car_runs import bellow_panels, of_setting, per_case, simulate_cases
from .checks import CaseMetrics
from .criteria import window_mean
from .experiments import CurveTest, Scenario
from .outcome import Outcome, Runner, largest
from .plots import Figure, Panel
from .results import Progress
from .series import with_column

#: components whose link flows are written to the time series
VALVE_PREFIXES = ("lv_", "dpv_")


def make_car(scenario: Scenario) -> MetroCar:
    """The car running along the curve-entry track (picklable factory for cosim.car_runs)."""
    return MetroCar(scenario.vehicle, step_s=scenario.solver.mechanics_step_s, track=scenario.curve.track(),
                    speed_m_per_s=scenario.curve.speed_m_per_s)


def car_centre_s_m(scenario: Scenario, t_s: np.ndarray) -> np.ndarray:
    """Arc length [m] of the car centre (midway between the bogie centres) at times ``t_s``:
    start_s + v t, with MetroCar's default start, the rear wheelset at s = 0, i.e. the car centre
    at (bogie centre distance + wheelbase) / 2."""
    p = scenario.vehicle
    return 0.5 * (p.bogie_centre_distance_m + p.wheelbase_m) + scenario.curve.speed_m_per_s * np.asarray(t_s, dtype=float)


def track_roll_rad(scenario: Scenario, t_s: np.ndarray) -> np.ndarray:
    """Roll [rad] of the track plane at the car centre, in the carbody roll's convention (right
    hand about the forward axis, positive = left side up). ``TrackGeometry.cant_rad(s)`` is
    signed like the curvature, positive raising the right rail (a left-hand curve's outer rail;
    MetroCar._rail_at lowers the left rail and raises the right one by b sin(cant)): the plane's
    roll is minus it."""
    return -np.asarray(scenario.curve.track().cant_rad(car_centre_s_m(scenario, t_s)), dtype=float)


def simulate(scenario: Scenario, progress: Optional[Progress] = None) -> Tuple[xr.Dataset, List[str]]:
    """Every case (k value x valve setting) of the curve entry: the labelled time series (see
    :mod:`cosim.series`) with the track plane's roll, the carbody roll relative to it, and the
    flows through the valves added, and the divergence diagnoses."""
    curve = scenario.curve
    ds, diagnoses = simulate_cases(scenario, curve.valve_settings, make_car, curve.duration_s, progress)
    plane = track_roll_rad(scenario, ds["time"].values)
    ds["roll_track_plane_rad"] = with_column(xr.DataArray(plane, dims="time"), "roll_track_plane_rad", "rad",
                                             "roll of the track plane at the car centre")
    ds["roll_rel_rad"] = with_column(ds["roll_rad"] - ds["roll_track_plane_rad"], "roll_carbody_rel_track_rad", "rad",
                                     "carbody roll relative to the track plane")
    if "link" in ds.dims:
        valves = [name for name in ds["link"].values if str(name).startswith(VALVE_PREFIXES)]
        ds["valve_flow_kg_per_s"] = with_column(ds["link_flow_kg_per_s"].sel(link=valves).rename(link="valve_link"),
                                                "q_{}_kg_per_s", "kg/s", "mass flow through each valve, a -> b",
                                                sparse=True)
    return ds, diagnoses


def run(scenario: Scenario, progress: Progress) -> Outcome:
    """The curve entry: every case, its summary row (:func:`summary_row`) and checkable metrics."""
    t0 = time.perf_counter()
    curve = scenario.curve
    progress(f"curve entry at {curve.speed_m_per_s:g} m/s: {curve.straight_m:g} m straight, {curve.transition_m:g} m "
             f"transition, R = {curve.radius_m:g} m; {len(scenario.k_W_per_K)} k values x valves {curve.valve_settings}")
    ds, diagnoses = simulate(scenario, progress)
    rows, cases = [], []
    for j in range(ds.sizes["case"]):
        case = ds.isel(case=j)
        row = summary_row(case, curve)
        rows.append(row)
        cases.append(CaseMetrics(row["k_W_per_K"], row["valves"],
                                 {m: row[m] for m in ("roll_max_rad", "air_injected_kg", "air_exhausted_kg")}))
    metrics = {m: largest(r[m] for r in rows) for m in ("roll_max_rad", "roll_mean_end_rad", "air_injected_kg",
                                                        "air_exhausted_kg")} if rows else {}
    shown = ("valves", "k_W_per_K", "roll_max_rad", "roll_mean_end_rad", "air_injected_kg", "air_exhausted_kg")
    return Outcome(scenario, rows, shown, {"curve": ds}, metrics, cases, diagnoses, [], {"window_s": curve.window},
                   time.perf_counter() - t0)


def summary_row(case: xr.Dataset, curve: CurveTest) -> Dict[str, object]:
    """The summary of one case (``case``: the Dataset of :func:`simulate` at one case): roll
    relative to the track plane (largest |roll| over the run, and its mean over the final window:
    the steady roll in the arc, not wherever the ~1 Hz sway is at the last sample), air exchanged
    (cumulative: its last sample), bellow crushing (final-window means), and per levelling valve
    the air through its supply and exhaust sides and the fraction of the run each side was open."""
    t = case["time"].values
    roll = case["roll_rel_rad"].values
    row = {"valves": bool(case["valves"]), "k_W_per_K": float(case["k_W_per_K"]),
           "roll_max_rad": float(np.abs(roll).max()),
           "roll_mean_end_rad": float(window_mean(t, roll, curve.window)),
           "air_injected_kg": float(case["air_from_supply_kg"].values[-1]),
           "air_exhausted_kg": float(case["air_to_atmosphere_kg"].values[-1]) + 0.0}  # no "-0"
    z = window_mean(t, case["crushing_m"].transpose("time", "bellow").values, curve.window)
    row.update({f"z_mean_end_{b}_m": float(z[i]) for i, b in enumerate(BELLOWS)})
    duration = float(t[-1] - t[0])
    if "valve" in case.dims:
        for v in case["valve"].values:
            if np.isnan(case["valve_supply_air_kg"].sel(valve=v).values[-1]):
                continue                             # a valve of another setting's circuit
            at_end = {name: float(case[name].sel(valve=v).values[-1]) for name in
                      ("valve_supply_air_kg", "valve_exhaust_air_kg", "valve_supply_open_s", "valve_exhaust_open_s")}
            row[f"{v}_supply_air_kg"] = at_end["valve_supply_air_kg"]
            row[f"{v}_exhaust_air_kg"] = at_end["valve_exhaust_air_kg"]
            row[f"{v}_supply_open_fraction"] = at_end["valve_supply_open_s"] / duration
            row[f"{v}_exhaust_open_fraction"] = at_end["valve_exhaust_open_s"] / duration
    T = case["bellow_T_K"].values
    row["T_bellow_min_K"], row["T_bellow_max_K"] = float(T.min()), float(T.max())
    # closes to the integrator's round-off: air in the chambers changes only by what crosses the boundary
    m = case["total_mass_kg"].values
    row["mass_balance_error_kg"] = float(m[-1] - m[0] - case["air_from_supply_kg"].values[-1]
                                         + case["air_to_atmosphere_kg"].values[-1])
    return row


def figures(outcome: Outcome) -> List[Figure]:
    """Carbody roll (paper Fig. 9), per valve setting the bellows, and the air consumption."""
    if not outcome.rows:
        return []
    ds = outcome.series["curve"]
    settings = outcome.scenario.curve.valve_settings
    roll = [Panel(per_case(of_setting(ds, v)["roll_rel_rad"], 1e3), "time t [s]",
                  "carbody roll to the track plane [mrad]", f"valves {'connected' if v else 'disconnected'}")
            for v in settings]
    out = [Figure("fig9_roll.png", roll, "Carbody roll entering a curve (paper Fig. 9)", len(roll))]
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
    return out


RUNNERS = {"curve_entry": Runner(run, figures)}
