"""Curve entry (paper §4.2, Fig. 9, Table 4): carbody roll and air consumption across k, with the
levelling and differential pressure valves disconnected and connected."""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Collection, Dict, List, Sequence

import numpy as np

from pneumatics.circuit import Circuit
from vehicle.car import BELLOWS, MetroCar

from .car_runs import (Figure, _save_figure, bellow_panels, curves_per_k, record_columns, save_figures,
                        simulate_variants)
from .criteria import window_mean
from .plots import Panel
from .results import Progress, k_label, write_columns, write_rows, write_run_json
from .runner import CaseMetrics, Outcome
from .scenario import CurveTest, Scenario

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


def relative_roll_rad(scenario: Scenario, rec: Dict[str, np.ndarray]) -> np.ndarray:
    """(samples, cases) carbody roll relative to the track plane at the car centre: the absolute
    roll (``MetroCar.carbody_roll_rad``) minus the plane's roll, i.e. roll + cant. On uncanted
    track it is the absolute roll."""
    return rec["roll_rad"] - track_roll_rad(scenario, rec["t_s"])[:, None]


def with_valves(scenario: Scenario, valves: bool) -> Scenario:
    return dataclasses.replace(scenario, circuit=dataclasses.replace(scenario.circuit, valves=valves))


def simulate_curve(scenario: Scenario, valves: bool, progress: bool = False):
    """Every k with the valves connected or not: (k values, record arrays, diagnoses, circuit)."""
    return simulate_curves(scenario, [valves], progress)[0]


def simulate_curves(scenario: Scenario, valve_settings: Sequence[bool], progress: bool = False):
    """Every k for each of ``valve_settings``, all cases on one pool of ``solver.jobs`` processes:
    per setting, what :func:`simulate_curve` returns."""
    variants = [with_valves(scenario, valves) for valves in valve_settings]
    labels = [f"{scenario.name} valves {'on' if valves else 'off'}" if progress else None for valves in valve_settings]
    runs = simulate_variants(variants, make_car, scenario.curve.duration_s, labels)
    return [(ks, rec, diagnoses, Circuit(variant.circuit.components()))
            for (ks, rec, diagnoses), variant in zip(runs, variants)]


def run_curve(scenario: Scenario, out: Path, progress: Progress) -> Outcome:
    t0 = time.perf_counter()
    curve = scenario.curve
    progress(f"curve entry at {curve.speed_m_per_s:g} m/s: {curve.straight_m:g} m straight, {curve.transition_m:g} m "
             f"transition, R = {curve.radius_m:g} m; {len(scenario.k_W_per_K)} k values x valves {curve.valve_settings}")
    settings = list(curve.valve_settings)
    variants = [with_valves(scenario, valves) for valves in settings]
    labels = [f"{scenario.name} valves {'on' if valves else 'off'}" if not progress.quiet else None
              for valves in settings]
    per_setting: List[tuple] = [None] * len(settings)  # (rows, cases, diagnoses) per valve setting
    runs_by: List[tuple] = [None] * len(settings)
    drawn = set()  # settings whose bellow figure was drawn while the simulation went on

    def finished(v: int, result, submit) -> None:
        """A valve setting's time series and summary rows (and, while another setting still
        runs, its bellow figure on the worker it freed)."""
        valves = settings[v]
        ks, rec, diag = result
        circuit = Circuit(variants[v].circuit.components())
        rec = {**rec, "roll_rel_rad": relative_roll_rad(scenario, rec)}
        runs_by[v] = (ks, rec)
        tag = "on" if valves else "off"
        rows, cases = [], []
        for j, k in enumerate(ks):
            rows.append(_summary_row(valves, k, rec, j, curve, circuit.valve_names))
            cases.append(CaseMetrics(k, valves, {m: rows[-1][m] for m in ("roll_max_rad", "air_injected_kg", "air_exhausted_kg")}))
            cols = record_columns(rec, j)
            cols["roll_track_plane_rad"] = track_roll_rad(scenario, rec["t_s"])
            cols["roll_carbody_rel_track_rad"] = rec["roll_rel_rad"][:, j]
            cols.update({f"q_{name}_kg_per_s": rec["link_flow_kg_per_s"][:, i, j]
                         for i, name in enumerate(circuit.link_names) if name.startswith(VALVE_PREFIXES)})
            write_columns(out / "timeseries" / f"curve_valves={tag}_k={k_label(k)}.csv", cols)
        per_setting[v] = (rows, cases, [f"valves {tag}: {d}" for d in diag])
        if submit is not None:
            submit(_save_figure, _bellow_figure(out, valves, ks, rec))
            drawn.add(valves)

    simulate_variants(variants, make_car, curve.duration_s, labels, on_done=finished)
    rows = [r for rows_v, _, _ in per_setting for r in rows_v]
    cases = [c for _, cases_v, _ in per_setting for c in cases_v]
    diagnoses = [d for _, _, diag_v in per_setting for d in diag_v]
    runs = {valves: run for valves, run in zip(settings, runs_by)}
    write_rows(out / "summary.csv", rows)
    _plots(out, runs, scenario.solver.jobs, skip=drawn)
    diverged = "; ".join(diagnoses) or None
    metrics = {m: _largest(r[m] for r in rows) for m in ("roll_max_rad", "roll_mean_end_rad", "air_injected_kg",
                                                         "air_exhausted_kg")} if rows else {}
    write_run_json(out, scenario, time.perf_counter() - t0, {"diverged": diverged, "metrics": metrics,
                                                             "window_s": curve.window})
    shown = ("valves", "k_W_per_K", "roll_max_rad", "roll_mean_end_rad", "air_injected_kg", "air_exhausted_kg")
    return Outcome(scenario, [{c: r[c] for c in shown} for r in rows], metrics, diverged, cases)


def _largest(values) -> float:
    """The largest value; NaN if any is NaN (a diverged case)."""
    values = list(values)
    return float("nan") if any(v != v for v in values) else max(values)


def _summary_row(valves: bool, k: float, rec: Dict[str, np.ndarray], j: int, curve: CurveTest,
                 valve_names=()) -> Dict[str, object]:
    """Roll relative to the track plane (largest |roll| over the run, and its mean over the final
    window: the steady roll in the arc, not wherever the ~1 Hz sway is at the last sample), air
    exchanged (cumulative: its last sample), bellow crushing (final-window means), and per
    levelling valve the air through its supply and exhaust sides and the fraction of the run each
    side was open."""
    t = rec["t_s"]
    roll = rec["roll_rel_rad"][:, j]
    row = {"valves": valves, "k_W_per_K": k, "roll_max_rad": float(np.abs(roll).max()),
           "roll_mean_end_rad": float(window_mean(t, roll, curve.window)),
           "air_injected_kg": float(rec["air_from_supply_kg"][-1, j]),
           "air_exhausted_kg": float(rec["air_to_atmosphere_kg"][-1, j]) + 0.0}  # no "-0"
    z = window_mean(t, rec["crushing_m"][:, :, j], curve.window)
    row.update({f"z_mean_end_{b}_m": float(z[i]) for i, b in enumerate(BELLOWS)})
    duration = float(t[-1] - t[0])
    for i, v in enumerate(valve_names):
        row[f"{v}_supply_air_kg"] = float(rec["valve_supply_air_kg"][-1, i, j])
        row[f"{v}_exhaust_air_kg"] = float(rec["valve_exhaust_air_kg"][-1, i, j])
        row[f"{v}_supply_open_fraction"] = float(rec["valve_supply_open_s"][-1, i, j]) / duration
        row[f"{v}_exhaust_open_fraction"] = float(rec["valve_exhaust_open_s"][-1, i, j]) / duration
    row["T_bellow_min_K"] = float(rec["bellow_T_K"][:, :, j].min())
    row["T_bellow_max_K"] = float(rec["bellow_T_K"][:, :, j].max())
    # closes to the integrator's round-off: air in the chambers changes only by what crosses the boundary
    row["mass_balance_error_kg"] = float(rec["total_mass_kg"][-1, j] - rec["total_mass_kg"][0, j]
                                         - rec["air_from_supply_kg"][-1, j] + rec["air_to_atmosphere_kg"][-1, j])
    return row


def _bellow_figure(out: Path, valves: bool, ks, rec) -> Figure:
    """The bellow crushing, pressure and temperature figure of one valve setting."""
    tag = "on" if valves else "off"
    per_k = curves_per_k(rec["t_s"], ks)
    heights = [Panel(per_k(rec["crushing_m"][:, i], 1e3), "time t [s]", f"crushing z_{b} [mm]", f"bellow {b}")
               for i, b in enumerate(BELLOWS)]
    return (out / f"bellows_valves={tag}.png", heights + bellow_panels(rec, ks),
            f"Bellow crushing (+ compression), pressure and temperature, valves {tag}", 2)


def _plots(out: Path, runs, jobs: int = 1, skip: Collection[bool] = ()) -> None:
    """The curve's figures, drawn on up to ``jobs`` processes (``skip``: valve settings whose
    bellow figure is drawn already)."""
    panels: List[Panel] = []
    for valves, (ks, rec) in runs.items():
        per_k = curves_per_k(rec["t_s"], ks)
        panels.append(Panel(per_k(rec["roll_rel_rad"], 1e3), "time t [s]", "carbody roll to the track plane [mrad]",
                            f"valves {'connected' if valves else 'disconnected'}"))
    figures = [(out / "fig9_roll.png", panels, "Carbody roll entering a curve (paper Fig. 9)", len(panels))]
    for valves, (ks, rec) in runs.items():
        per_k = curves_per_k(rec["t_s"], ks)
        if valves not in skip:
            figures.append(_bellow_figure(out, valves, ks, rec))
        if valves:
            figures.append((out / "air_consumption.png",
                            [Panel(per_k(rec["air_from_supply_kg"], 1e3), "time t [s]", "air injected from the supply [g]"),
                             Panel(per_k(rec["air_to_atmosphere_kg"], 1e3), "time t [s]",
                                   "air exhausted to the atmosphere [g]")],
                            "Air consumption of the levelling valves (paper Table 4)", 2))
    save_figures(figures, jobs)
