"""The bellow-tank virtual test rig (paper §3): four kinds, ``rig_ramp`` (Fig. 3), ``rig_sine``
(Fig. 5), ``rig_stiffness`` (Fig. 6) and ``rig_table2`` (Table 2). Each scenario has a rig
``circuit`` (``bellow``, ``tank``, ``pipe``, ``p0_Pa``) and a ``test``; each run returns an
:class:`~cosim.results.outcome.Outcome` and the figures drawn from it."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Mapping, Optional, Tuple

import numpy as np
import xarray as xr

from cosim.errors import ScenarioError
from cosim.kinds.base import RigKind
from cosim.results.io import Progress, read_rows
from cosim.results.outcome import Computed, Outcome
from cosim.results.overlay import Selection, case_series
from cosim.results.plots import Curve, Figure, Panel, k_legend, save_panels
from cosim.scenario.circuits import chambers_and_pipe, compile_check, with_preset
from cosim.scenario.model import Scenario
from cosim.scenario.schema import MAX_SAMPLES, MAX_STEPS, build, check_keys, check_range, coerce, k_label, range_of, require
from pneumatics.chamber import Bellow, Tank, quasi_static_stiffness_N_per_m
from pneumatics.gas import ABSOLUTE_PRESSURE, AIR
from pneumatics.pipe import Pipe
from pneumatics.rig import (
    bellow_tank_components,
    dynamic_stiffness_sweep,
    quasi_static_stiffness_table,
    ramp_motion,
    run_time_series,
    sine_motion,
)
from pneumorail.quantities import Range, plausible, positive, ranged

#: the amplitude of a rig test
AMPLITUDE = Range(None, None, unit="m", why="a crushing amplitude; 0 moves nothing", nonzero=True)


# ----------------------------------------------------------------------------------- tests
@dataclass(frozen=True)
class RampTest:
    """Fig. 3: crushing ramp to ``amplitude_m`` in ``ramp_s``, held until ``duration_s``."""

    amplitude_m: float = field(default=0.02, metadata=ranged(AMPLITUDE))
    ramp_s: float = 1.0
    duration_s: float = 30.0
    samples: int = field(default=601, metadata=plausible(2, MAX_SAMPLES, why="stored time points"))
    configurations: Tuple[str, ...] = field(default=("bellow_tank", "bellow_only"), metadata=ranged(non_empty=True,
                                                                                                    unique=True))



@dataclass(frozen=True)
class SineTest:
    """Fig. 5: z = a sin(2 pi f t) for ``duration_s``; the time history is sampled
    ``samples_per_period`` times a period. The run counts as stabilised when the mean bellow
    temperature drifts by less than ``stable_drift_K_per_period`` over the last tenth of it
    (default 1e-3 K: at 1 Hz, less than 4 K an hour)."""

    amplitude_m: float = field(default=0.02, metadata=ranged(AMPLITUDE))
    frequency_Hz: float = field(default=1.0, metadata=ranged(positive("Hz")))
    duration_s: float = 300.0
    samples_per_period: int = field(default=20, metadata=plausible(2, 10_000, why="stored time points per period"))
    stable_drift_K_per_period: float = field(default=1e-3, metadata=ranged(positive("K per period")))



@dataclass(frozen=True)
class StiffnessTest:
    """Fig. 6: K_dyn (eq. 9) on the periodic steady state for each frequency."""

    amplitude_m: float = field(default=0.02, metadata=ranged(AMPLITUDE))
    frequencies_Hz: Tuple[float, ...] = field(default=(0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0),
                                              metadata=ranged(positive("Hz"), non_empty=True, unique=True))



@dataclass(frozen=True)
class QuasiStaticTest:
    """Table 2: slope of a slow small ramp."""

    amplitude_m: float = field(default=1e-4, metadata=ranged(AMPLITUDE))
    ramp_s: float = 20.0





@dataclass(frozen=True)
class RigCircuit:
    """The rig's circuit: a bellow, its tank (None: the bellow alone) and the pipe between them,
    all starting at ``p0_Pa``."""

    bellow: Bellow
    tank: Optional[Tank]
    pipe: Pipe
    p0_Pa: float = field(metadata=ranged(ABSOLUTE_PRESSURE))

    def components(self, with_tank: bool = True) -> Dict[str, object]:
        return bellow_tank_components(self.bellow, self.tank if with_tank else None, self.pipe)

    def initial_pressures(self, components) -> Dict[str, float]:
        return {n: self.p0_Pa for n, c in components.items() if isinstance(c, (Bellow, Tank))}

    def faults_label(self) -> str:
        """The faults in words, as a car circuit says them: a rig has none."""
        return ""


def identify_circuit(scenario: Scenario, with_tank: bool = True):
    """(components, initial pressures) of the rig ``pneumorail identify`` drives: with the tank
    when the scenario has one and ``with_tank``."""
    rig = scenario.circuit
    comps = rig.components(with_tank and rig.tank is not None)
    return comps, rig.initial_pressures(comps)


def load(data: Mapping, path, common: Mapping, experiment: type) -> Scenario:
    """A rig scenario from its checked top level (``common``: the fields every scenario has):
    the ``circuit`` and the ``test`` (an ``experiment``), and the rules between them."""
    rig = _rig_circuit(require(data, "circuit", path, [], dict), path)
    test = build(experiment, data.get("test"), path, ["test"])
    _check_rig_test(test, rig, path)
    return Scenario(**common, experiment=test, circuit=rig)


def _check_rig_test(test, rig: RigCircuit, path) -> None:
    """Rules between the fields of a rig test and its circuit."""
    if isinstance(test, RampTest):
        for i, c in enumerate(test.configurations):
            if c not in ("bellow_tank", "bellow_only"):
                raise ScenarioError(path, ["test", f"configurations[{i}]"], f"expected bellow_tank or bellow_only, "
                                                                            f"got {c!r}")
    stroke = rig.bellow.V0_m3 / rig.bellow.dV_dz_m2
    if not abs(test.amplitude_m) < stroke:
        raise ScenarioError(path, ["test", "amplitude_m"], f"|amplitude| must be below V0/(dV/dz) = {stroke:.4g} m, "
                                                           f"where the bellow volume vanishes; got {test.amplitude_m}")
    if isinstance(test, RampTest):
        if test.ramp_s > test.duration_s:
            raise ScenarioError(path, ["test", "ramp_s"], f"the ramp must end within the run (duration_s = "
                                                          f"{test.duration_s:g} s), got {test.ramp_s:g} s")
        steps = test.duration_s / (test.ramp_s / 50.0)      # the integrator's largest step: ramp_s / 50
        if steps > MAX_STEPS:
            raise ScenarioError(path, ["test", "ramp_s"], f"the integrator steps at most ramp_s/50: a {test.ramp_s:g} s "
                                                          f"ramp in a {test.duration_s:g} s run takes {steps:.3g} steps "
                                                          f"(at most {MAX_STEPS:.0e})")
    if isinstance(test, SineTest):
        periods = test.duration_s * test.frequency_Hz
        if periods < 2:
            raise ScenarioError(path, ["test", "duration_s"], f"expected at least 2 periods of the sine (the summary "
                                                              f"compares periods), got {periods:.3g} "
                                                              f"({test.duration_s:g} s at {test.frequency_Hz:g} Hz)")
        samples = periods * test.samples_per_period + 1
        if samples > MAX_SAMPLES:
            raise ScenarioError(path, ["test", "duration_s"], f"the run would store {samples:.3g} samples (duration_s x "
                                                              f"frequency_Hz x samples_per_period); at most {MAX_SAMPLES:.0e}")
        if periods * 20 > MAX_STEPS:                        # the integrator's largest step: a period / 20
            raise ScenarioError(path, ["test", "duration_s"], f"{periods:.3g} periods take {periods * 20:.3g} integration "
                                                              f"steps (20 a period); at most {MAX_STEPS:.0e}")


def _rig_circuit(data: Mapping, file) -> RigCircuit:
    check_keys(data, ("preset", "bellow", "tank", "pipe", "p0_Pa"), file, ["circuit"])
    data = with_preset(data, file, ("bellow", "tank", "pipe", "p0_Pa"))
    bellow, tank, pipe = chambers_and_pipe(data, file)
    p0 = coerce(require(data, "p0_Pa", file, ["circuit"]), float, file, ["circuit", "p0_Pa"])
    check_range(p0, range_of(RigCircuit, "p0_Pa"), file, ["circuit", "p0_Pa"])
    rig = RigCircuit(bellow, tank, pipe, p0)
    compile_check(rig.components(tank is not None), file, ["circuit"], {"bellow": "bellow", "tank": "tank", "pipe": "pipe"})
    return rig


def run(scenario: Scenario, progress: Progress, stage) -> Computed:
    """A rig scenario: its summary rows and a time series per run from ``stage`` (a kind's
    ``(scenario, progress, diagnoses) -> (rows, series)``), and the diagnoses of early stops."""
    diagnoses: List[str] = []
    rows, series = stage(scenario, progress, diagnoses)
    return Computed(rows, series=series, diagnoses=diagnoses)


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
    test: RampTest = scenario.experiment
    rig = scenario.circuit
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
    test = outcome.scenario.experiment
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
    test: SineTest = scenario.experiment
    rig = scenario.circuit
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
    test = outcome.scenario.experiment
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
    test = scenario.experiment
    rig = scenario.circuit
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
    test, rig = scenario.experiment, scenario.circuit
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


def _table2(scenario: Scenario, progress: Progress, diagnoses: List[str]):
    rig, test = scenario.circuit, scenario.experiment
    progress("quasi-static stiffness (Table 2)")
    table = quasi_static_stiffness_table(rig.bellow, rig.tank, rig.pipe, rig.p0_Pa, AIR.gamma, test.amplitude_m, test.ramp_s)
    return [{"configuration": r.configuration, "regime": r.regime, "analytic_N_per_m": r.analytic_N_per_m,
             "simulated_N_per_m": r.simulated_N_per_m,
             "relative_difference": r.simulated_N_per_m / r.analytic_N_per_m - 1.0} for r in table], {}


def compare_stiffness(infos, out_dir: Path, select: Selection, label, window: str) -> List[Path]:
    """Overlay several stiffness runs: the dynamic stiffness against frequency (the stabilised
    points)."""
    curves = []
    for d, _ in infos:
        rows = [r for r in read_rows(d / "summary.csv") if r["stabilised"] == "True"]
        for k in sorted({float(r["k_W_per_K"]) for r in rows}):
            if select.k is not None and k not in select.k:
                continue
            pts = [r for r in rows if float(r["k_W_per_K"]) == k]
            curves.append(Curve([float(r["frequency_Hz"]) for r in pts],
                                [float(r["K_dyn_N_per_m"]) / 1e3 for r in pts], label(d, f"k = {k_label(k)}"), "o-"))
    return [save_panels(out_dir / "compare_stiffness.png",
                        [Panel(curves, "frequency f [Hz]", "K_dyn [kN/m]", logx=True)], "Dynamic stiffness comparison")]


def compare_time_series(infos, out_dir: Path, select: Selection, label, window: str, kind: str, prefix: str,
                        column: str, ylabel: str) -> List[Path]:
    """Overlay several runs' time series ``<prefix>*.csv``: ``column`` against time."""
    curves = [Curve(data["t_s"], data[column], label(d, k)) for d, _ in infos for k, data in case_series(d, prefix, select)]
    return [save_panels(out_dir / f"compare_{kind}.png", [Panel(curves, "time t [s]", ylabel)],
                        f"{kind} comparison{window}")]


# ----------------------------------------------------------------------------------- the kinds
class _Rig(RigKind):
    """What the four rig kinds share: the rig circuit and a ``test``; each kind's ``stage``
    (``(scenario, progress, diagnoses) -> (rows, series)``) computes its rows."""

    def load(self, data: Mapping, path: Path, common: Mapping) -> Scenario:
        return load(data, path, common, self.experiment)

    def run(self, scenario: Scenario, progress: Progress) -> Computed:
        return run(scenario, progress, self.stage)

    def identify_circuit(self, scenario: Scenario):
        return identify_circuit(scenario)


class _TimeSeriesRig(_Rig):
    """A rig kind whose runs are time histories: ``compare`` overlays ``overlaid`` = (file
    prefix, column, axis label) of several runs against time."""

    overlaid: Tuple[str, str, str]

    def compare(self, infos, out_dir: Path, select: Selection, label, window: str) -> List[Path]:
        return compare_time_series(infos, out_dir, select, label, window, self.name, *self.overlaid)


class RampKind(_TimeSeriesRig):
    """A slow crushing ramp, each configuration (bellow with and without tank) per k (Fig. 3)."""

    name, experiment, identify = "rig_ramp", RampTest, "time"
    overlaid = ("ramp_", "F_bellow_N", "bellow force F [N]")
    stage = staticmethod(_ramp)
    figures = staticmethod(_ramp_figures)

    def identify_circuit(self, scenario: Scenario):
        """With the tank as the first configuration says."""
        return identify_circuit(scenario, scenario.experiment.configurations[0] == "bellow_tank")


class SineKind(_TimeSeriesRig):
    """A sine crushing at one frequency, per k (Fig. 5)."""

    name, experiment, identify = "rig_sine", SineTest, "time"
    overlaid = ("sine_", "T_bellow_K", "bellow temperature T [K]")
    stage = staticmethod(_sine)
    figures = staticmethod(_sine_figures)


class StiffnessKind(_Rig):
    """The dynamic stiffness against frequency, per k (Fig. 6)."""

    name, experiment, identify = "rig_stiffness", StiffnessTest, "table"
    stage = staticmethod(_stiffness)
    figures = staticmethod(_stiffness_figures)
    compare = staticmethod(compare_stiffness)


class Table2Kind(_Rig):
    """The quasi-static stiffness, analytic and simulated (Table 2; no figures: its numbers are
    the summary)."""

    name, experiment = "rig_table2", QuasiStaticTest
    stage = staticmethod(_table2)
    k_fixed = "Table 2 is computed for the adiabatic and isothermal limits"


KINDS = (RampKind(), SineKind(), StiffnessKind(), Table2Kind())
