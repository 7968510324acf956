"""Running the car along a track (:mod:`cosim.runs.track_spec`): the car of a run
(:func:`make_car`), the cases on the process pool with the track's own series (track roll, the
wheel-rail quantities' sliding means: :func:`simulate`, :func:`simulate_many`), the summary row of
a case (:func:`summary_row`: roll, air, wheel unloading, lateral wheel-rail forces), its checkable
metrics (:func:`case_metrics`) and the warnings about the track itself
(:func:`track_twist_warnings`, :func:`ramp_roll_rate_step_rad_per_s`). The kinds that run the car
along a track (``curve_entry``, ``ride``) compose these."""
from __future__ import annotations

from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
import xarray as xr

from cosim.engine.cases import simulate_scenarios
from cosim.limits.checks import CaseMetrics
from cosim.limits.criteria import (
    SLIDING_MEAN_M,
    en14363_twist_limit,
    largest_track_twist,
    nadal_limit,
    prudhomme_limit_N,
    sliding_mean,
    window_mean,
)
from cosim.results.io import Progress
from cosim.results.outcome import largest
from cosim.results.series import WHEELSETS, with_column
from cosim.runs.car import add_wheel_unloading, air_columns
from cosim.runs.track_spec import CurveTest
from cosim.scenario.model import Scenario
from vehicle.params import BELLOWS, WHEELS, VehicleParams
from vehicle.track import TrackGeometry


def make_car(scenario: Scenario):
    """The car running along the curve-entry track (picklable factory for cosim.engine.cases), with
    the curve's guidance, contact parameters and track irregularity (generated from its seed in
    each worker: the same track in every one)."""
    from vehicle.car import MetroCar  # exudyn: imported when a car is built, not to read a scenario
    curve = scenario.experiment
    return MetroCar(scenario.vehicle, step_s=scenario.solver.mechanics_step_s, track=curve.track(),
                    spectral_radius=scenario.solver.spectral_radius, track_structure=scenario.track,
                    speed_m_per_s=curve.speed_m_per_s, guidance=curve.guidance,
                    contact=curve.contact_params() if curve.contact else None,
                    irregularity=curve.track_irregularity(scenario.vehicle), payload=scenario.car_payload)


#: components whose link flows are written to the time series
VALVE_PREFIXES = ("lv_", "dpv_")


def sliding_window_s(curve: CurveTest) -> float:
    """EN 14363's 2 m sliding window as a time [s] at the curve's speed: 2 m / v."""
    return SLIDING_MEAN_M / curve.speed_m_per_s


def _over_time(da: xr.DataArray, fn) -> xr.DataArray:
    """``fn(values)`` on ``da`` with time first, as a DataArray of the same dimensions."""
    dims = ("time",) + tuple(d for d in da.dims if d != "time")
    out = fn(da.transpose(*dims).values)
    return xr.DataArray(out, dims=dims, coords={d: da[d] for d in dims if d in da.coords}).transpose(*da.dims)


def _attrs(da: xr.DataArray, **attrs) -> xr.DataArray:
    """``da`` with exactly ``attrs`` (arithmetic keeps an operand's, e.g. its CSV ``column``)."""
    da = da.copy()
    da.attrs = dict(attrs)
    return da


def wheel_rail_series(ds: xr.Dataset, curve: CurveTest) -> None:
    """Add the running-safety series to a curve run's Dataset (in place): ``dqq`` (ΔQ/Q0 per
    wheel, Q0 the static wheel load at t = 0, mean of the wheelset's two wheels, EN 14363),
    ``dqq_2m`` (its 2 m sliding mean, NaN for the first 2 m) and, with contact guidance,
    ``y_over_q`` (Y/Q per wheel; 0 on a wheel that carries nothing), ``y_over_q_2m`` and
    ``sum_y_2m_N`` (their EN 14363 2 m sliding means, NaN for the first 2 m)."""
    t = ds["time"].values
    add_wheel_unloading(ds)
    W = sliding_window_s(curve)
    ds["dqq_2m"] = with_column(_over_time(ds["dqq"], lambda v: sliding_mean(t, v, W)), "dqq_2m_{}", "1",
                               f"ΔQ/Q0 per wheel, sliding mean over {SLIDING_MEAN_M:g} m")
    if "lateral_wheel_force_N" not in ds:
        return
    Q = ds["wheel_load_N"]
    Y = ds["lateral_wheel_force_N"]
    with np.errstate(invalid="ignore", divide="ignore"):
        yq = xr.where(Q > 0.0, Y / Q, xr.where(Q.isnull() | Y.isnull(), np.nan, 0.0))
    ds["y_over_q"] = _attrs(yq, units="1", long_name="Y/Q per wheel")
    ds["y_over_q_2m"] = with_column(_over_time(yq, lambda v: sliding_mean(t, v, W)), "YQ_2m_{}", "1",
                                    f"Y/Q per wheel, EN 14363 sliding mean over {SLIDING_MEAN_M:g} m")
    ds["sum_y_2m_N"] = with_column(_over_time(ds["wheelset_lateral_force_N"], lambda v: sliding_mean(t, v, W)),
                                   "sumY_2m_{}_N", "N", f"ΣY per wheelset, EN 14363 sliding mean over {SLIDING_MEAN_M:g} m")


def car_centre_s_m(scenario: Scenario, t_s: np.ndarray) -> np.ndarray:
    """Arc length [m] of the car centre (midway between the bogie centres) at times ``t_s``:
    start_s + v t, with MetroCar's default start, the rear wheelset at s = 0, i.e. the car centre
    at (bogie centre distance + wheelbase) / 2."""
    p = scenario.vehicle
    return 0.5 * (p.bogie_centre_distance_m + p.wheelbase_m) + scenario.experiment.speed_m_per_s * np.asarray(t_s, dtype=float)


def track_roll_rad(scenario: Scenario, t_s: np.ndarray) -> np.ndarray:
    """Roll [rad] of the track plane under the car: the mean of the design cant at the two bogie
    centres (the carbody rests on the bogies, so this is the plane it would settle parallel to; at
    the car centre alone the reference kinks where the centre passes a cant ramp's end while the
    bogies do not), in the carbody roll's convention (right hand about the forward axis, positive =
    left side up). ``TrackGeometry.cant_rad(s)`` is signed like the curvature, positive raising the
    right rail (a left-hand curve's outer rail): the plane's roll is minus it."""
    return plane_roll_rad(scenario.experiment.track(), car_centre_s_m(scenario, t_s), scenario.vehicle.bogie_x_m)


def plane_roll_rad(track: TrackGeometry, centre_s_m: np.ndarray, bogie_x_m) -> np.ndarray:
    """:func:`track_roll_rad` of a car whose centre is at arc lengths ``centre_s_m`` on ``track``
    (bogie centres ``bogie_x_m`` from it)."""
    cants = [np.asarray(track.cant_rad(np.clip(centre_s_m + x, 0.0, track.total_length_m)), dtype=float)
             for x in bogie_x_m]
    return -0.5 * (cants[0] + cants[1])


def simulate(scenario: Scenario, progress: Optional[Progress] = None) -> Tuple[xr.Dataset, List[str]]:
    """Every case (k value x valve setting) of the curve entry: the labelled time series (see
    :mod:`cosim.results.series`) with the track plane's roll, the carbody roll relative to it, and the
    flows through the valves added, and the divergence diagnoses."""
    return simulate_many([scenario], progress)[0]


def simulate_many(scenarios: Sequence[Scenario], progress: Optional[Progress] = None,
                  names: Optional[Sequence[str]] = None) -> List[Tuple[xr.Dataset, List[str]]]:
    """:func:`simulate` for several curve entries at once (e.g. a ride's speeds), on one pool of
    processes (:func:`cosim.engine.cases.simulate_scenarios`: a scenario's k values share a process
    and a circuit where the processes allow). All must have the same valve settings."""
    settings = scenarios[0].experiment.valve_settings
    if any(s.experiment.valve_settings != settings for s in scenarios):
        raise ValueError("simulate_many: the scenarios' valve settings differ")
    results = simulate_scenarios(scenarios, settings, make_car, [s.experiment.duration_s for s in scenarios], progress, names)
    return [(_with_track_series(scenario, ds), diagnoses) for scenario, (ds, diagnoses) in zip(scenarios, results)]


def _with_track_series(scenario: Scenario, ds: xr.Dataset) -> xr.Dataset:
    """The run's time series with the track plane's roll, the carbody roll relative to it, the
    wheel-rail series and the flows through the valves added."""
    curve = scenario.experiment
    plane = track_roll_rad(scenario, ds["time"].values)
    ds["roll_track_plane_rad"] = with_column(xr.DataArray(plane, dims="time"), "roll_track_plane_rad", "rad",
                                             "roll of the track plane under the car (mean of the bogie centres)")
    ds["roll_rel_rad"] = with_column(ds["roll_rad"] - ds["roll_track_plane_rad"], "roll_carbody_rel_track_rad", "rad",
                                     "carbody roll relative to the track plane")
    wheel_rail_series(ds, curve)
    if "link" in ds.dims:
        valves = [name for name in ds["link"].values if str(name).startswith(VALVE_PREFIXES)]
        ds["valve_flow_kg_per_s"] = with_column(ds["link_flow_kg_per_s"].sel(link=valves).rename(link="valve_link"),
                                                "q_{}_kg_per_s", "kg/s", "mass flow through each valve, a -> b",
                                                sparse=True)
    return ds


#: grid of the arc length on which :func:`track_twist_warnings` looks for the largest twist [m]
TWIST_GRID_M = 0.05


def track_twist_warnings(track: TrackGeometry, vehicle: VehicleParams) -> List[str]:
    """A warning for each base, the bogie's wheelbase 2a+ and the bogie centre distance 2a*, over
    which the design cant twists the track more than EN 14363's limit track twist for that base
    (:func:`~cosim.limits.criteria.en14363_twist_limit`, the twist of its test on twisted track: what
    the standard asks a vehicle to negotiate): a steep cant ramp, e.g. 0.1 rad over 10 m (22 per
    mille over a 2 m wheelbase), on which the car may unload a wheel or climb a flange because of
    the track. The cross-level is taken over ``contact_spacing_m``."""
    s = np.append(np.arange(0.0, track.total_length_m, TWIST_GRID_M), track.total_length_m)
    found = []
    for name, base in (("wheelbase 2a+", vehicle.wheelbase_m), ("bogie centre distance 2a*",
                                                                 vehicle.bogie_centre_distance_m)):
        twist, at = largest_track_twist(track.cant_rad, s, base, vehicle.contact_spacing_m)
        limit = en14363_twist_limit(base)
        if twist > limit:
            found.append(f"the cant ramp twists the track by {1e3 * twist:.3g} per mille over the {name} "
                         f"({base:g} m, ending at s = {at:.1f} m): steeper than the {1e3 * limit:g} per mille EN 14363 "
                         f"asks a vehicle to negotiate over that base (its test on twisted track); the wheel "
                         f"unloading there includes the ramp's own twist")
    return found


def ramp_roll_rate_step_rad_per_s(curve: CurveTest) -> float:
    """The step of the rails' roll rate at the ends of a linear cant ramp, v c / L [rad/s] (0 for
    a smoothed transition, or without cant)."""
    if curve.transition_shape != "linear" or curve.cant_rad == 0.0:
        return 0.0
    return curve.speed_m_per_s * abs(curve.cant_rad) / curve.transition_m


def case_metrics(row: Dict[str, object], zoned: Dict[str, Dict[str, Dict[str, float]]]) -> CaseMetrics:
    """The checkable metrics of a summary row (:attr:`KIND.check_metrics <cosim.kinds.base.Kind.check_metrics>`): the wheel
    metrics per wheel; ``yq_max`` and ``sum_y_max`` [N] only with contact guidance; the EN 14363
    assessment's per zone and wheel (``zoned``, :func:`cosim.limits.en14363.zone_metrics`)."""
    values = {m: row[m] for m in ("roll_max_rad", "air_injected_kg", "air_exhausted_kg", "air_lost_kg")}
    wheels = {m: {w: row[f"{m}_{w}"] for w in WHEELS} for m in ("dqq_raw_max", "dqq_2m_max")}
    if "sum_y_rms_max_N" in row:
        values["sum_y_rms_max"] = row["sum_y_rms_max_N"]
    if "yq_max" in row:
        values["sum_y_max"] = row["sum_y_max_N"]
        wheels["yq_max"] = {w: row[f"yq_max_{w}"] for w in WHEELS}
    return CaseMetrics(row["k_W_per_K"], row["valves"], values, wheels, zoned)


def _largest_after(t: np.ndarray, values: np.ndarray, t_from: float) -> np.ndarray:
    """Largest sample (over time, the first axis) from ``t_from`` on; NaN if one of them is NaN
    (a diverged case) or there is none."""
    keep = t >= t_from - 1e-9
    if not keep.any():
        return np.full(values.shape[1:], np.nan)
    return values[keep].max(axis=0)


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
           "roll_mean_end_rad": float(window_mean(t, roll, curve.window))}
    # the air exchanged, and with a compressor or demands their air, duty and energy (the mass
    # balance's error takes its place at the end of the row)
    air = air_columns(case)
    row.update({name: value for name, value in air.items() if name != "mass_balance_error_kg"})
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
    row["air_initial_kg"] = float(m[0])  # the air the circuit holds at the start (verify's floor for air)
    row["Q0_N"] = float(case["Q0_N"].mean())  # the static wheel load (verify's floor for forces)
    row["mass_balance_error_kg"] = air["mass_balance_error_kg"]
    row.update(wheel_rail_summary(case, curve))
    return row


def wheel_rail_summary(case: xr.Dataset, curve: CurveTest) -> Dict[str, object]:
    """The running-safety columns of one case (``case``: the Dataset of :func:`simulate` at one
    case, with :func:`wheel_rail_series`):

    * ``dqq_raw_max_<wheel>``, ``dqq_raw_max``: the largest sampled ΔQ/Q0 over the run (raw: no
      filter, no mean), per wheel and over the wheels (both guidances; kinematic Q is vertical, contact Q
      normal to the track plane); ``dqq_2m_max_<wheel>``, ``dqq_2m_max``: the same for its 2 m
      sliding mean (the sampled peak of a flange impact's ~45 Hz ringing depends on where the
      samples fall: on the R = 150 m twisted curve it moves by 9 % as the steps are halved,
      while the 2 m mean holds to 4 digits; docs/wheel_rail.md);

    with contact guidance also, the 2 m sliding means (EN 14363) counted from the first whole
    window on:

    * ``Y_raw_max_<wheel>_N``, ``Y_raw_max_N``: the largest sampled Y (raw; + towards the track centre);
    * ``yq_max_<wheel>``, ``yq_max``: the largest (Y/Q)_2m, against ``yq_lim`` (Nadal,
      :func:`cosim.limits.criteria.nadal_limit`);
    * ``sum_y_max_<wheelset>_N``, ``sum_y_max_N``: the largest |ΣY_2m| per wheelset and over
      them, against ``sum_y_lim_N`` (Prud'homme as EN 14363 states it, Q0 the static wheel load;
      :func:`cosim.limits.criteria.prudhomme_limit_N`);
    * ``y_ws_max_<wheelset>_m``, ``y_ws_rails_max_<wheelset>_m``, ``aoa_max_<wheelset>_rad``:
      the largest |lateral displacement| from the design centre line and relative to the rails
      (they differ by the alignment irregularity), and |angle of attack| per wheelset;
    * ``flange_fraction_<wheel>``, ``flange_fraction``: the fraction of the samples a wheel is in
      flange contact, and the largest over the wheels."""
    t = case["time"].values
    t_full = t[0] + sliding_window_s(curve)
    dqq = case["dqq"].transpose("time", "wheel").values
    worst = dqq.max(axis=0)
    row: Dict[str, object] = {f"dqq_raw_max_{w}": float(v) for w, v in zip(WHEELS, worst)}
    row["dqq_raw_max"] = largest(worst)
    worst = _largest_after(t, case["dqq_2m"].transpose("time", "wheel").values, t_full)
    row.update({f"dqq_2m_max_{w}": float(v) for w, v in zip(WHEELS, worst)})
    row["dqq_2m_max"] = largest(worst)
    if "y_over_q_2m" not in case:
        return row
    Y = case["lateral_wheel_force_N"].transpose("time", "wheel").values
    Y_max = Y.max(axis=0)
    row.update({f"Y_raw_max_{w}_N": float(v) for w, v in zip(WHEELS, Y_max)})
    row["Y_raw_max_N"] = largest(Y_max)
    yq = _largest_after(t, case["y_over_q_2m"].transpose("time", "wheel").values, t_full)
    row.update({f"yq_max_{w}": float(v) for w, v in zip(WHEELS, yq)})
    row["yq_max"] = largest(yq)
    row["yq_lim"] = nadal_limit(curve.nadal_flange_angle_deg, curve.nadal_friction)
    sum_y = _largest_after(t, np.abs(case["sum_y_2m_N"].transpose("time", "wheelset").values), t_full)
    row.update({f"sum_y_max_{ws}_N": float(v) for ws, v in zip(WHEELSETS, sum_y)})
    row["sum_y_max_N"] = largest(sum_y)
    # each wheelset's own static wheel load; the smallest limit (the lightest wheelset) is reported
    row["sum_y_lim_N"] = prudhomme_limit_N(float(case["Q0_N"].min()), curve.prudhomme_alpha)
    for name, column in (("wheelset_lateral_m", "y_ws_max_{}_m"), ("wheelset_lateral_to_rails_m", "y_ws_rails_max_{}_m"),
                         ("angle_of_attack_rad", "aoa_max_{}_rad")):
        worst = np.abs(case[name].transpose("time", "wheelset").values).max(axis=0)
        row.update({column.format(ws): float(v) for ws, v in zip(WHEELSETS, worst)})
    flange = case["flange_contact"].transpose("time", "wheel").values.mean(axis=0)
    row.update({f"flange_fraction_{w}": float(v) for w, v in zip(WHEELS, flange)})
    row["flange_fraction"] = largest(flange)
    return row


def record_headlines(scenario: Scenario, rec: Dict[str, np.ndarray], j: int = 0,
                     window_s: Optional[float] = None) -> Dict[str, float]:
    """Headlines of case ``j`` of raw record arrays (``CoSimulation.run``'s or the monolithic
    reference's: :mod:`cosim.verification.monolithic`): largest |roll| relative to the track
    plane, its mean over the final window (``window_s``, default the scenario's), air injected
    and exhausted [kg]."""
    t = np.asarray(rec["t_s"])
    roll = rec["roll_rad"][:, j] - track_roll_rad(scenario, t)
    w = window_s if window_s is not None else scenario.experiment.window
    return {"roll_max_rad": float(np.abs(roll).max()),
            "roll_mean_end_rad": float(window_mean(t, roll, min(w, t[-1] - t[0]))),
            "air_injected_kg": float(rec["air_from_supply_kg"][-1, j]),
            "air_exhausted_kg": float(rec["air_to_atmosphere_kg"][-1, j])}
