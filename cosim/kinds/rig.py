"""The bellow-tank virtual test rig scenarios (paper §3): ramp, sine, dynamic stiffness and Table 2,
each a run returning an :class:`~cosim.results.outcome.Outcome` and the figures drawn from it."""
from __future__ import annotations

import math
import time
from typing import Dict, List

import numpy as np
import xarray as xr

from pneumatics.chamber import quasi_static_stiffness_N_per_m
from pneumatics.gas import AIR
from pneumatics.rig import (dynamic_stiffness_sweep, quasi_static_stiffness_table, ramp_motion, run_time_series,
                            sine_motion)

from cosim.scenario.model import RampTest, Scenario, SineTest
from cosim.results.outcome import Outcome, Runner
from cosim.results.plots import Curve, Figure, Panel, k_legend
from cosim.results.io import Progress, k_label



def run(scenario: Scenario, progress: Progress) -> Outcome:
    """A rig scenario: its summary rows, a time series per run and the diagnoses of early stops."""
    t0 = time.perf_counter()
    diagnoses: List[str] = []
    stage = {"rig_ramp": _ramp, "rig_sine": _sine, "rig_stiffness": _stiffness, "rig_table2": _table2}[scenario.kind]
    rows, series = stage(scenario, progress, diagnoses)
    return Outcome(scenario, rows, series=series, diagnoses=diagnoses, wall_s=time.perf_counter() - t0)


def _keep_diagnosis(ts, diagnoses: List[str], progress: Progress) -> None:
    """Report an early stop (results outside the models' validity are flagged from the summary
    rows, :mod:`cosim.limits.validity`)."""
    if ts.diagnosis:
        diagnoses.append(ts.diagnosis)
        progress(f"stopped early, results kept up to there: {ts.diagnosis}")


def rig_dataset(ts, **attrs) -> xr.Dataset:
    """A rig run's time series (:class:`pneumatics.rig.TimeSeries`) as a labelled Dataset, time x
    chamber; ``attrs`` (k, configuration ...) describe the run."""
    def var(values, units, long_name, column):
        return values, {"units": units, "long_name": long_name, "column": column}
    data = {"z_m": ("time", *var(ts.z_m, "m", "bellow crushing z (+ compression)", "z_m")),
            "F_bellow_N": ("time", *var(ts.force_N, "N", "bellow force F", "F_bellow_N")),
            "pipe_mach": ("time", *var(ts.pipe_mach, "1", "Mach number of the pipe flow", "pipe_mach")),
            "p_Pa": (("chamber", "time"), *var(np.asarray(ts.p_Pa), "Pa", "pressure (absolute)", "p_{}_Pa")),
            "T_K": (("chamber", "time"), *var(np.asarray(ts.T_K), "K", "temperature", "T_{}_K"))}
    ds = xr.Dataset(data, coords={"time": ("time", ts.t_s, {"units": "s"}), "chamber": list(ts.chamber_names)},
                    attrs=attrs)
    for name in ("p_Pa", "T_K"):
        ds[name] = ds[name].transpose("time", "chamber")
    return ds


def _ramp(scenario: Scenario, progress: Progress, diagnoses: List[str]):
    test: RampTest = scenario.test
    rig = scenario.rig
    rows, series = [], {}
    for config in test.configurations:
        comps = rig.components(with_tank=config == "bellow_tank" and rig.tank is not None)
        for k in scenario.k_W_per_K:
            progress(f"ramp {config}, k = {k_label(k)} W/K")
            ts = run_time_series(comps, k, ramp_motion(test.amplitude_m, test.ramp_s), test.duration_s, test.samples,
                                 max_step_s=test.ramp_s / 50, p0_Pa=rig.initial_pressures(comps))
            _keep_diagnosis(ts, diagnoses, progress)
            series[f"ramp_{config}_k={k_label(k)}"] = rig_dataset(ts, k_W_per_K=k, configuration=config)
            rows.append({"configuration": config, "k_W_per_K": k, "F_initial_N": ts.force_N[0],
                         "F_peak_N": ts.force_N.max(), "F_final_N": ts.force_N[-1],
                         "T_bellow_max_K": ts.T_K[0].max(), "T_bellow_final_K": ts.T_K[0][-1],
                         "pipe_mach_max": ts.pipe_mach.max()})
    return rows, series


def _ramp_figures(outcome: Outcome) -> List[Figure]:
    test = outcome.scenario.test
    panels = []
    for config in test.configurations:
        runs = [ds for ds in outcome.series.values() if ds.attrs["configuration"] == config]
        title = "bellow + tank" if config == "bellow_tank" else "bellow alone"
        panels.append(Panel([Curve(ds["time"].values, ds["F_bellow_N"].values / 1e3, k_legend(ds.attrs["k_W_per_K"]))
                             for ds in runs], "time t [s]", "bellow force F [kN]",
                            f"{test.amplitude_m * 1e3:g} mm ramp in {test.ramp_s:g} s, {title}"))
        panels.append(Panel([Curve(ds["time"].values, ds["T_K"].isel(chamber=0).values, k_legend(ds.attrs["k_W_per_K"]))
                             for ds in runs], "time t [s]", "bellow temperature T [K]", title))
    return [Figure("fig3_ramp_force.png", panels, "Bellow reaction force to a compression ramp (paper Fig. 3)", 2)]


def _sine(scenario: Scenario, progress: Progress, diagnoses: List[str]):
    test: SineTest = scenario.test
    rig = scenario.rig
    comps = rig.components(with_tank=rig.tank is not None)
    period = 1.0 / test.frequency_Hz
    n = int(round(test.duration_s / period * test.samples_per_period)) + 1
    rows, series = [], {}
    for k in scenario.k_W_per_K:
        progress(f"sine {test.frequency_Hz:g} Hz, {test.duration_s:g} s, k = {k_label(k)} W/K")
        ts = run_time_series(comps, k, sine_motion(test.amplitude_m, test.frequency_Hz), test.duration_s, n,
                             max_step_s=period / 20, p0_Pa=rig.initial_pressures(comps))
        _keep_diagnosis(ts, diagnoses, progress)
        series[f"sine_{test.frequency_Hz:g}Hz_k={k_label(k)}"] = rig_dataset(ts, k_W_per_K=k)
        rows.append({"k_W_per_K": k, "frequency_Hz": test.frequency_Hz, **_sine_summary(ts, test),
                     "pipe_mach_max": ts.pipe_mach.max()})
    return rows, series


#: a periodic history longer than this many periods is drawn as cycle means with their range
MAX_PERIODS_DRAWN = 40


def cycle_curve(t_s: np.ndarray, y: np.ndarray, samples_per_period: int, label: str, scale: float = 1.0) -> Curve:
    """``y`` against time; over more than :data:`MAX_PERIODS_DRAWN` periods (a solid band at any
    figure size) the mean of each period at its centre, shaded between the period's minimum and
    maximum."""
    n = (len(y) - 1) // samples_per_period
    if n <= MAX_PERIODS_DRAWN:
        return Curve(t_s, y * scale, label)
    cycles = np.asarray(y[:n * samples_per_period]).reshape(n, samples_per_period) * scale
    centres = np.asarray(t_s[:n * samples_per_period]).reshape(n, samples_per_period).mean(axis=1)
    return Curve(centres, cycles.mean(axis=1), f"{label} (cycle mean, range shaded)",
                 lower=cycles.min(axis=1), upper=cycles.max(axis=1))


def _sine_figures(outcome: Outcome) -> List[Figure]:
    test = outcome.scenario.test
    runs = list(outcome.series.values())

    def curves(name, scale=1.0):
        return [cycle_curve(ds["time"].values, ds[name].isel(chamber=0).values, test.samples_per_period,
                            k_legend(ds.attrs["k_W_per_K"]), scale) for ds in runs]
    return [Figure("fig5_bellow_temperature.png",
                   [Panel(curves("T_K"), "time t [s]", "bellow temperature T [K]",
                          f"{test.amplitude_m * 1e3:g} mm sine at {test.frequency_Hz:g} Hz"),
                    Panel(curves("p_Pa", 1e-5), "time t [s]", "bellow pressure p [bar abs]")],
                   "Bellow temperature history (paper Fig. 5)")]


def _sine_summary(ts, test: SineTest) -> Dict[str, object]:
    """Mean bellow temperature over the first and last periods, and its drift per period over the
    last tenth of the run: ``stabilised`` when that drift is below the test's threshold."""
    spp = test.samples_per_period
    T = ts.T_K[0]
    n_per = (T.size - 1) // spp
    if n_per < 2:                       # stopped within the first periods
        return {"T_bellow_max_K": T.max(), "T_bellow_min_K": T.min(), "stabilised": False}
    means = np.array([T[i * spp:(i + 1) * spp].mean() for i in range(n_per)])
    tail = means[-max(2, n_per // 10):]
    drift = (tail[-1] - tail[0]) / max(tail.size - 1, 1)
    return {"T_bellow_mean_first_period_K": means[0], "T_bellow_mean_last_period_K": means[-1],
            "T_bellow_max_K": T.max(), "T_bellow_min_K": T.min(),
            "T_mean_drift_K_per_period": drift, "stabilised": bool(abs(drift) < test.stable_drift_K_per_period),
            "p_bellow_mean_last_period_Pa": ts.p_Pa[0][-spp:].mean()}


def _stiffness(scenario: Scenario, progress: Progress, diagnoses: List[str]):
    test = scenario.test
    rig = scenario.rig
    comps = rig.components(with_tank=rig.tank is not None)
    t0 = time.perf_counter()
    points = dynamic_stiffness_sweep(comps, scenario.k_W_per_K, test.frequencies_Hz, test.amplitude_m,
                                     p0_Pa=rig.initial_pressures(comps), progress=progress)
    wall = time.perf_counter() - t0
    rows = []
    for p in points:
        rows.append({"k_W_per_K": p.k_W_per_K, "frequency_Hz": p.frequency_Hz,
                     # a case that has not stabilised gets no stiffness, only its diagnosis
                     "K_dyn_N_per_m": p.K_dyn_N_per_m if p.stabilised else math.nan,
                     "T_bellow_mean_K": p.T_bellow_mean_K if p.stabilised else math.nan,
                     "T_bellow_max_K": p.T_bellow_max_K if p.stabilised else math.nan,
                     "stabilised": p.stabilised, "periodicity_residual": p.residual,
                     "floquet_max": p.floquet_max, "cycles_to_settle": p.cycles_to_settle,
                     "pipe_mach_max": p.pipe_mach_max if p.stabilised else math.nan})
    series = {}
    loops = [p for p in points if p.stabilised]
    if loops:
        def column(values, units, long_name, name):
            return "point", np.concatenate(values), {"units": units, "long_name": long_name, "column": name}
        series["stiffness_loops"] = xr.Dataset({
            "k_W_per_K": column([np.full(p.loop_phase.size, p.k_W_per_K) for p in loops], "W/K",
                                "heat transfer coefficient k", "k_W_per_K"),
            "frequency_Hz": column([np.full(p.loop_phase.size, p.frequency_Hz) for p in loops], "Hz", "frequency f",
                                   "frequency_Hz"),
            "phase": column([p.loop_phase for p in loops], "1", "phase of the period (0 ... 1)", "phase"),
            "z_m": column([test.amplitude_m * np.sin(2 * np.pi * p.loop_phase) for p in loops], "m", "crushing z", "z_m"),
            "F_bellow_N": column([p.loop_F_N for p in loops], "N", "bellow force F", "F_bellow_N"),
            "T_bellow_K": column([p.loop_T_K for p in loops], "K", "bellow temperature T", "T_bellow_K")})
    progress(f"sweep of {len(points)} cases took {wall:.1f} s")
    return rows, series


def _stiffness_figures(outcome: Outcome) -> List[Figure]:
    scenario, rows = outcome.scenario, outcome.rows
    test, rig = scenario.test, scenario.rig
    curves = []
    for k in scenario.k_W_per_K:
        pts = [r for r in rows if r["k_W_per_K"] == k and r["stabilised"]]
        if pts:
            curves.append(Curve([r["frequency_Hz"] for r in pts], [r["K_dyn_N_per_m"] / 1e3 for r in pts], k_legend(k), "o-"))
    b, t = rig.bellow, rig.tank
    V_all = b.V0_m3 + (t.V_m3 if t else 0.0)
    ref = [(quasi_static_stiffness_N_per_m(b, rig.p0_Pa, V_all, n) / 1e3, f"{name}, V = {V_all * 1e3:g} dm3")
           for n, name in ((AIR.gamma, "adiabatic"), (1.0, "isothermal"))]
    ref += [(quasi_static_stiffness_N_per_m(b, rig.p0_Pa, b.V0_m3, n) / 1e3, f"{name}, bellow alone")
            for n, name in ((AIR.gamma, "adiabatic"), (1.0, "isothermal"))] if t else []
    return [Figure("fig6_dynamic_stiffness.png",
                   [Panel(curves, "frequency f [Hz]", "dynamic stiffness K_dyn [kN/m]",
                          f"{test.amplitude_m * 1e3:g} mm amplitude, periodic steady state (unstabilised cases omitted)",
                          logx=True, logy=_spans_decades(curves), hlines=ref)],
                   "Dynamic stiffness of the bellow-tank subsystem (paper Fig. 6)")]


def _spans_decades(curves) -> bool:
    """Log axis when the values span more than a factor 10 (small k near resonance run away)."""
    values = [v for c in curves for v in c.y if v > 0]
    return bool(values) and max(values) > 10 * min(values)


def _no_figures(outcome: Outcome) -> List[Figure]:
    return []


def _table2(scenario: Scenario, progress: Progress, diagnoses: List[str]):
    rig, test = scenario.rig, scenario.test
    progress("quasi-static stiffness (Table 2)")
    table = quasi_static_stiffness_table(rig.bellow, rig.tank, rig.pipe, rig.p0_Pa, AIR.gamma, test.amplitude_m, test.ramp_s)
    return [{"configuration": r.configuration, "regime": r.regime, "analytic_N_per_m": r.analytic_N_per_m,
             "simulated_N_per_m": r.simulated_N_per_m,
             "relative_difference": r.simulated_N_per_m / r.analytic_N_per_m - 1.0} for r in table], {}


RUNNERS = {"rig_ramp": Runner(run, _ramp_figures), "rig_sine": Runner(run, _sine_figures),
           "rig_stiffness": Runner(run, _stiffness_figures), "rig_table2": Runner(run, _no_figures)}
