"""The EN 14363 twist test (paper §4.1, Figs 7-8): ΔQ/Q across heat-transfer coefficients, with
the levelling valves isolated and/or connected."""
from __future__ import annotations

import math
import time
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
import xarray as xr

from vehicle.car import MetroCar
from vehicle.params import WHEELS

from cosim.kinds.car import add_wheel_unloading, bellow_panels, of_setting, per_case, simulate_cases
from cosim.limits.checks import CaseMetrics
from cosim.limits.criteria import DQQ_LIMIT, window_drift, window_mean
from cosim.scenario.model import Scenario, TwistTest
from cosim.results.outcome import Outcome, Runner, largest, warn
from cosim.results.plots import Figure, Panel
from cosim.results.io import Progress, k_label

#: wheels every twist plot shows (paper Fig. 8); the worst wheels of the run are added
PLOT_WHEELS = ("1L", "1R", "4L", "4R")


def wheelset_x_m(test: TwistTest) -> np.ndarray:
    """(4,) wheelset positions [m] along the track from the car centre, wheelsets 1..4 from the
    front, for the bases of the test (the loader checks that they are the car's)."""
    xb, a = test.base_m / 2.0, (test.bogie_base_m or 0.0) / 2.0
    return np.array([xb + a, xb - a, -xb + a, -xb - a])


def twisted_rail_m(test: TwistTest, x_m) -> np.ndarray:
    """Height [m] of the twisted rail (the raised side) at ``x_m`` along the track (from the car
    centre, forward), fully ramped, for the EN 14363 twist with bogie twist: level under the rear
    bogie (x <= x3), rising linearly to h* - h+/2 at the front bogie's trailing wheelset x2 and on,
    with the bogie twist g+, to h* + h+/2 at its leading wheelset x1 (level beyond), with
    h* = g* 2a* and h+ = g+ 2a+. The front bogie centre then lies h* above the rear one (carbody
    twist g* over 2a*), the front bogie's wheelsets differ by h+ (bogie twist g+ over 2a+), the
    rear bogie is untwisted; between the bogies the rail rises at (h* - h+/2)/(2a* - 2a+)."""
    x1, x2, x3, _ = wheelset_x_m(test)
    h, hb = test.height_m, test.bogie_height_m
    return np.interp(x_m, [x3, x2, x1], [0.0, h - 0.5 * hb, h + 0.5 * hb])


def rail_heights(test: TwistTest):
    """rail_height_m(t) -> (8,): each rail height follows its full value H times the cosine ramp
    0.5 (1 - cos(pi t / ramp)), then holds H.

    Without a bogie twist (``bogie_base_m`` null; the paper's Fig. 7): H = h* = g* 2a* under each
    of ``raised_wheels`` (1R, 2R: the front bogie's right wheels), 0 elsewhere. With it (EN 14363,
    the carbody and the bogie twist together): the raised side's rail follows
    :func:`twisted_rail_m` -- the front bogie's leading wheel at h* + h+/2, its trailing wheel at
    h* - h+/2 -- and the other side stays level. This is the test-bench form of the twisted
    track: one side raised under the front bogie, the other side and the rear bogie level; what
    the car feels is, to first order, the same as on a track whose cross-level changes by g* over
    the bogie centres and by g+ over the front bogie, with both rails moved by half of it: the
    cross-level twists the car, the mean rail height under each wheelset only heaves and pitches
    the carbody and the front bogie frame as rigid bodies (mean heights 0 under the rear bogie,
    h*/2 at the front bogie centre, +-h+/4 across it). Both twists have the same sense, so they
    add up at the leading wheel of the low side (1L for raised right rails), the wheel that
    unloads most.
    """
    raised = np.array([w in test.raised_wheels for w in WHEELS], dtype=float)
    h, ramp = test.height_m, test.ramp_s
    if test.bogie_base_m is None:
        def rail(t: float) -> np.ndarray:
            s = min(max(t / ramp, 0.0), 1.0)
            return raised * (h * 0.5 * (1.0 - math.cos(math.pi * s)))
        return rail
    full = raised * np.repeat(twisted_rail_m(test, wheelset_x_m(test)), 2)

    def twisted(t: float) -> np.ndarray:
        s = min(max(t / ramp, 0.0), 1.0)
        return full * (0.5 * (1.0 - math.cos(math.pi * s)))
    return twisted


def make_car(scenario: Scenario) -> MetroCar:
    """The car standing on rails that follow the twist (picklable factory for cosim.kinds.car)."""
    return MetroCar(scenario.vehicle, rail_height_m=rail_heights(scenario.twist), step_s=scenario.solver.mechanics_step_s,
                    spectral_radius=scenario.solver.spectral_radius, track_structure=scenario.track)


def valve_settings(scenario: Scenario) -> Sequence[Optional[bool]]:
    """The runs: each of ``twist.valve_settings``, or one (None) as ``circuit.valves`` says."""
    return scenario.twist.valve_settings or (None,)


def simulate(scenario: Scenario, progress: Optional[Progress] = None) -> Tuple[xr.Dataset, List[str]]:
    """Every case (k value x valve setting) of the twist scenario: the labelled time series (see
    :mod:`cosim.results.series`) with the wheel unloading ``dqq`` (ΔQ/Q0, time x wheel x case) added, and
    the divergence diagnoses."""
    ds, diagnoses = simulate_cases(scenario, valve_settings(scenario), make_car, scenario.twist.duration_s, progress)
    add_wheel_unloading(ds, column="dqq_{}")
    return ds, diagnoses


def twist_metrics(t_s: np.ndarray, dqq: np.ndarray, test: TwistTest, j: int) -> Dict[str, object]:
    """Summary of case ``j``: the dynamic maxima of ΔQ/Q0 (over the whole run), the quasi-static
    values (means over the final window), their drift (change of the window mean over one
    window, see :func:`cosim.limits.criteria.window_drift`) and whether it settled: every wheel's drift
    below ``settle_drift``."""
    d = dqq[:, :, j]                                          # (samples, 8)
    worst = np.unravel_index(np.argmax(d), d.shape)
    qs = window_mean(t_s, d, test.window)                     # (8,)
    drift = window_drift(t_s, d, test.window)                 # (8,)
    row: Dict[str, object] = {"dqq_max": float(d.max()), "dqq_max_wheel": WHEELS[worst[1]],
                              "t_dqq_max_s": float(t_s[worst[0]]),
                              "dqq_qs_max": float(qs.max()), "dqq_qs_max_wheel": WHEELS[int(np.argmax(qs))],
                              "dqq_drift": float(drift.max()), "settled": bool(drift.max() < test.settle_drift)}
    if np.isnan(d).any():           # a diverged case: no maximum, so no wheel or time to name
        row.update(dqq_max=math.nan, dqq_max_wheel="", t_dqq_max_s=math.nan)
    if np.isnan(qs).any():
        row.update(dqq_qs_max=math.nan, dqq_qs_max_wheel="")
    row.update({f"dqq_max_{w}": float(d[:, i].max()) for i, w in enumerate(WHEELS)})
    row.update({f"dqq_qs_{w}": float(qs[i]) for i, w in enumerate(WHEELS)})
    row.update({f"dqq_drift_{w}": float(drift[i]) for i, w in enumerate(WHEELS)})
    return row


def run(scenario: Scenario, progress: Progress) -> Outcome:
    """The twist test: every case, its summary row (:func:`twist_metrics`, the end roll, the
    bellow temperature range) and checkable metrics."""
    t0 = time.perf_counter()
    test = scenario.twist
    settings = valve_settings(scenario)
    bogie = (f" + bogie twist {test.bogie_twist * 1e3:g} permille over {test.bogie_base_m:g} m "
             f"({test.bogie_height_m * 1e3:.1f} mm across the front bogie)" if test.bogie_base_m is not None else "")
    valves_text = "" if settings == (None,) else f" x valves {['on' if v else 'off' for v in settings]}"
    progress(f"twist {test.twist * 1e3:g} permille over {test.base_m:g} m -> rail raised {test.height_m * 1e3:.1f} mm under "
             f"{', '.join(test.raised_wheels)}{bogie}; {len(scenario.k_W_per_K)} k values{valves_text}, "
             f"{test.duration_s:g} s simulated")
    ds, diagnoses = simulate(scenario, progress)
    t = ds["time"].values
    dqq = ds["dqq"].transpose("time", "wheel", "case").values
    rows: List[Dict[str, object]] = []
    cases: List[CaseMetrics] = []
    found: List[str] = []
    named = settings != (None,)
    for j, (k, valves) in enumerate(zip(ds["k_W_per_K"].values, ds["valves"].values)):
        k, valves = float(k), bool(valves)
        row = {"valves": valves, "k_W_per_K": k, **twist_metrics(t, dqq, test, j)}
        row["roll_carbody_mean_end_rad"] = float(window_mean(t, ds["roll_rad"].values[:, j], test.window))
        T = ds["bellow_T_K"].isel(case=j).values
        row["T_bellow_max_K"], row["T_bellow_min_K"] = float(T.max()), float(T.min())
        rows.append(row)
        cases.append(CaseMetrics(k, valves, wheels={m: {w: row[f"{prefix}_{w}"] for w in WHEELS} for m, prefix in
                                                    (("dqq_max", "dqq_max"), ("dqq_qs_max", "dqq_qs"),
                                                     ("dqq_drift", "dqq_drift"))}))
        if not row["settled"]:
            where = f"valves {'on' if valves else 'off'}, " if named else ""
            warn(found, f"{where}k = {k_label(k)}: not settled, the {test.window:g} s mean of ΔQ/Q0 still moves by "
                        f"{row['dqq_drift']:.2g} from one window to the next (limit {test.settle_drift:g})")
    metrics = {m: largest(r[m] for r in rows) for m in ("dqq_max", "dqq_qs_max", "dqq_drift")} if rows else {}
    info = {"twist_height_m": test.height_m, "twist_per_mille": test.twist * 1e3,
            "bogie_twist_height_m": test.bogie_height_m, "bogie_twist_per_mille": test.bogie_twist * 1e3,
            "rail_heights_m": {w: float(h) for w, h in zip(WHEELS, rail_heights(test)(test.duration_s))},
            "window_s": test.window, "settle_drift": test.settle_drift,
            "Q0_N": {w: float(q) for w, q in zip(WHEELS, ds["Q0_N"].values[:, 0])} if ds.sizes["case"] else {}}
    shown = ("valves", "k_W_per_K", "dqq_max", "dqq_max_wheel", "t_dqq_max_s", "dqq_qs_max", "dqq_qs_max_wheel",
             "dqq_drift", "settled", "T_bellow_max_K")
    return Outcome(scenario, rows, shown, {"twist": ds}, metrics, cases, diagnoses, found, info,
                   time.perf_counter() - t0)


def _dqq_limit(scenario: Scenario) -> float:
    """The limit to draw: the scenario's own ΔQ/Q0 checks, else EN 14363's 0.6."""
    limits = [c.limit for c in scenario.checks if c.metric in ("dqq_max", "dqq_qs_max") and c.op in ("<=", "<")]
    return min(limits) if limits else DQQ_LIMIT


def plot_wheels(rows) -> List[str]:
    """Fig. 8's wheels and the worst ones of the run (largest dynamic and quasi-static ΔQ/Q0 over
    every case), in wheel order."""
    worst = set()
    for prefix in ("dqq_max_", "dqq_qs_"):
        values = {w: max((r[prefix + w] for r in rows), key=lambda v: -math.inf if math.isnan(v) else v) for w in WHEELS}
        worst.add(max(WHEELS, key=lambda w: -math.inf if math.isnan(values[w]) else values[w]))
    return [w for w in WHEELS if w in PLOT_WHEELS or w in worst]


def figures(outcome: Outcome) -> List[Figure]:
    """Per valve setting: the wheel loads (paper Fig. 8), ΔQ/Q0 with its limit, the bellows."""
    if not outcome.rows:
        return []
    test, ds = outcome.scenario.twist, outcome.series["twist"]
    wheels = plot_wheels(outcome.rows)
    limit = _dqq_limit(outcome.scenario)
    extra = [w for w in wheels if w not in PLOT_WHEELS]
    shown = "wheelsets 1 and 4" + (f" and the worst wheel{'s' if len(extra) > 1 else ''} {', '.join(extra)}" if extra else "")
    height = f"rail raised {test.height_m * 1e3:.0f} mm" + (
        f", bogie twisted {test.bogie_height_m * 1e3:.0f} mm" if test.bogie_base_m is not None else "")
    out = []
    for setting in valve_settings(outcome.scenario):
        sub = of_setting(ds, setting)
        suffix = "" if setting is None else f"_valves={'on' if setting else 'off'}"
        valves = "" if setting is None else f", valves {'connected' if setting else 'isolated'}"
        out += [Figure(f"fig8_wheel_loads{suffix}.png",
                       [Panel(per_case(sub["wheel_load_N"].sel(wheel=w), 1e-3), "time t [s]", f"wheel load Q_{w} [kN]",
                              f"wheel {w}") for w in wheels],
                       f"Vertical wheel-rail forces during the twist test, {shown} (paper Fig. 8); {height}{valves}", 2),
                Figure(f"dqq{suffix}.png",
                       [Panel(per_case(sub["dqq"].sel(wheel=w)), "time t [s]", f"ΔQ/Q0 of wheel {w} [-]", f"wheel {w}",
                              hlines=[(limit, f"limit {limit:g}")]) for w in wheels],
                       f"Wheel unloading ΔQ/Q0 (positive: unloaded){valves}", 2),
                Figure(f"bellows{suffix}.png", bellow_panels(sub), f"Bellow pressures and temperatures{valves}", 2)]
    return out


RUNNERS = {"twist": Runner(run, figures)}
