"""The EN 14363 twist test (paper §4.1, Figs 7-8): ΔQ/Q across heat-transfer coefficients, with
the levelling valves isolated and/or connected."""
from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

from vehicle.car import WHEELS, MetroCar

from .criteria import DQQ_LIMIT, static_wheel_loads, wheel_unloading, window_drift, window_mean
from .car_runs import Figure, bellow_panels, curves_per_k, record_columns, save_figures, simulate_variants
from .curve import with_valves
from .plots import Panel
from .results import Progress, k_label, write_columns, write_rows, write_run_json
from .runner import CaseMetrics, Outcome
from .scenario import Scenario, TwistTest

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
    """The car standing on rails that follow the twist (picklable factory for cosim.car_runs)."""
    return MetroCar(scenario.vehicle, rail_height_m=rail_heights(scenario.twist), step_s=scenario.solver.mechanics_step_s)


def valve_settings(scenario: Scenario) -> Sequence[Optional[bool]]:
    """The runs: each of ``twist.valve_settings``, or one (None) as ``circuit.valves`` says."""
    return scenario.twist.valve_settings or (None,)


def simulate_twist(scenario: Scenario, progress: Optional[Progress] = None, valves: Optional[bool] = None):
    """Every k of the twist scenario: (k values, record arrays, diagnoses). ``valves``: connect
    (True) or isolate (False) the levelling valves; None: as ``circuit.valves`` says."""
    return simulate_twists(scenario, [valves], progress)[0]


def simulate_twists(scenario: Scenario, settings: Sequence[Optional[bool]], progress: Optional[Progress] = None):
    """:func:`simulate_twist` for each of the valve ``settings``, all cases on one pool of
    ``solver.jobs`` processes."""
    variants = [scenario if valves is None else with_valves(scenario, valves) for valves in settings]
    show = progress is not None and not progress.quiet
    labels = [(scenario.name if valves is None else f"{scenario.name} valves {'on' if valves else 'off'}")
              if show else None for valves in settings]
    return simulate_variants(variants, make_car, scenario.twist.duration_s, labels)


def twist_metrics(t_s: np.ndarray, dqq: np.ndarray, test: TwistTest, j: int) -> Dict[str, object]:
    """Summary of case ``j``: the dynamic maxima of ΔQ/Q0 (over the whole run), the quasi-static
    values (means over the final window), their drift (change of the window mean over one
    window, see :func:`cosim.criteria.window_drift`) and whether it settled: every wheel's drift
    below ``settle_drift``."""
    d = dqq[:, :, j]                                          # (samples, 8)
    worst = np.unravel_index(np.argmax(d), d.shape)
    qs = window_mean(t_s, d, test.window)                     # (8,)
    drift = window_drift(t_s, d, test.window)                 # (8,)
    row: Dict[str, object] = {"dqq_max": float(d.max()), "dqq_max_wheel": WHEELS[worst[1]],
                              "t_dqq_max_s": float(t_s[worst[0]]),
                              "dqq_qs_max": float(qs.max()), "dqq_qs_max_wheel": WHEELS[int(np.argmax(qs))],
                              "dqq_drift": float(drift.max()), "settled": bool(drift.max() < test.settle_drift)}
    row.update({f"dqq_max_{w}": float(d[:, i].max()) for i, w in enumerate(WHEELS)})
    row.update({f"dqq_qs_{w}": float(qs[i]) for i, w in enumerate(WHEELS)})
    row.update({f"dqq_drift_{w}": float(drift[i]) for i, w in enumerate(WHEELS)})
    return row


def run_twist(scenario: Scenario, out: Path, progress: Progress) -> Outcome:
    t0 = time.perf_counter()
    test = scenario.twist
    settings = valve_settings(scenario)
    bogie = (f" + bogie twist {test.bogie_twist * 1e3:g} permille over {test.bogie_base_m:g} m "
             f"({test.bogie_height_m * 1e3:.1f} mm across the front bogie)" if test.bogie_base_m is not None else "")
    valves_text = "" if settings == (None,) else f" x valves {['on' if v else 'off' for v in settings]}"
    progress(f"twist {test.twist * 1e3:g} permille over {test.base_m:g} m -> rail raised {test.height_m * 1e3:.1f} mm under "
             f"{', '.join(test.raised_wheels)}{bogie}; {len(scenario.k_W_per_K)} k values{valves_text}, "
             f"{test.duration_s:g} s simulated")
    rows: List[Dict[str, object]] = []
    cases: List[CaseMetrics] = []
    runs = {}
    diagnoses: List[str] = []
    Q0_N = None
    for setting, (ks, rec, diag) in zip(settings, simulate_twists(scenario, settings, progress)):
        valves = scenario.circuit.valves if setting is None else setting
        tag = "" if setting is None else f"valves={'on' if valves else 'off'}_"
        diagnoses += diag if setting is None else [f"valves {'on' if valves else 'off'}: {d}" for d in diag]
        Q = rec["wheel_load_N"]                       # (samples, 8, cases)
        Q0 = static_wheel_loads(Q[0])                 # (8, cases)
        Q0_N = Q0 if Q0_N is None else Q0_N
        dqq = wheel_unloading(Q, Q0)                  # (samples, 8, cases)
        t = rec["t_s"]
        runs[setting] = (ks, rec, dqq)
        for j, k in enumerate(ks):
            row = {"valves": valves, "k_W_per_K": k, **twist_metrics(t, dqq, test, j)}
            row["roll_carbody_mean_end_rad"] = float(window_mean(t, rec["roll_rad"][:, j], test.window))
            row["T_bellow_max_K"] = float(rec["bellow_T_K"][:, :, j].max())
            row["T_bellow_min_K"] = float(rec["bellow_T_K"][:, :, j].min())
            rows.append(row)
            cases.append(CaseMetrics(k, valves, wheels={m: {w: row[f"{prefix}_{w}"] for w in WHEELS} for m, prefix in
                                                        (("dqq_max", "dqq_max"), ("dqq_qs_max", "dqq_qs"),
                                                         ("dqq_drift", "dqq_drift"))}))
            if not row["settled"]:
                progress(f"{tag.rstrip('_').replace('=', ' ')} k = {k_label(k)}: not settled, the {test.window:g} s mean "
                         f"of ΔQ/Q0 still moves by {row['dqq_drift']:.2g} from one window to the next "
                         f"(limit {test.settle_drift:g})".lstrip())
            write_columns(out / "timeseries" / f"twist_{tag}k={k_label(k)}.csv",
                          {**record_columns(rec, j), **{f"dqq_{w}": dqq[:, i, j] for i, w in enumerate(WHEELS)}})
    write_rows(out / "summary.csv", rows)
    shown = _plot_wheels(rows)
    save_figures([figure for setting, (ks, rec, dqq) in runs.items()
                  for figure in _figures(out, ks, rec, dqq, test, _dqq_limit(scenario), shown, setting)],
                 scenario.solver.jobs)
    diverged = "; ".join(diagnoses) or None
    metrics = {m: _largest(r[m] for r in rows) for m in ("dqq_max", "dqq_qs_max", "dqq_drift")} if rows else {}
    write_run_json(out, scenario, time.perf_counter() - t0,
                   {"twist_height_m": test.height_m, "twist_per_mille": test.twist * 1e3,
                    "bogie_twist_height_m": test.bogie_height_m, "bogie_twist_per_mille": test.bogie_twist * 1e3,
                    "rail_heights_m": {w: float(h) for w, h in zip(WHEELS, rail_heights(test)(test.duration_s))},
                    "window_s": test.window, "settle_drift": test.settle_drift,
                    "diverged": diverged, "metrics": metrics,
                    "Q0_N": {w: float(Q0_N[i, 0]) for i, w in enumerate(WHEELS)} if Q0_N is not None else {}})
    columns = ("valves", "k_W_per_K", "dqq_max", "dqq_max_wheel", "t_dqq_max_s", "dqq_qs_max", "dqq_qs_max_wheel",
               "dqq_drift", "settled", "T_bellow_max_K")
    return Outcome(scenario, [{c: r[c] for c in columns} for r in rows], metrics, diverged, cases)


def _largest(values) -> float:
    """The largest value; NaN if any is NaN (a diverged case)."""
    values = list(values)
    return math.nan if any(math.isnan(v) for v in values) else max(values)


def _dqq_limit(scenario: Scenario) -> float:
    """The limit to draw: the scenario's own ΔQ/Q0 checks, else EN 14363's 0.6."""
    limits = [c.limit for c in scenario.checks if c.metric in ("dqq_max", "dqq_qs_max") and c.op in ("<=", "<")]
    return min(limits) if limits else DQQ_LIMIT


def _plot_wheels(rows) -> List[str]:
    """Fig. 8's wheels and the worst ones of the run (largest dynamic and quasi-static ΔQ/Q0 over
    every case), in wheel order."""
    worst = set()
    for key, prefix in (("dqq_max", "dqq_max_"), ("dqq_qs_max", "dqq_qs_")):
        values = {w: max((r[prefix + w] for r in rows), key=lambda v: -math.inf if math.isnan(v) else v) for w in WHEELS}
        worst.add(max(WHEELS, key=lambda w: -math.inf if math.isnan(values[w]) else values[w]))
    return [w for w in WHEELS if w in PLOT_WHEELS or w in worst]


def _figures(out: Path, ks, rec, dqq, test: TwistTest, limit: float, wheels: Sequence[str],
             setting: Optional[bool]) -> List[Figure]:
    """The figures of one valve setting (see :func:`cosim.car_runs.save_figures`)."""
    Q = rec["wheel_load_N"]
    per_k = curves_per_k(rec["t_s"], ks)
    suffix = "" if setting is None else f"_valves={'on' if setting else 'off'}"
    valves = "" if setting is None else f", valves {'connected' if setting else 'isolated'}"
    extra = [w for w in wheels if w not in PLOT_WHEELS]
    shown = "wheelsets 1 and 4" + (f" and the worst wheel{'s' if len(extra) > 1 else ''} {', '.join(extra)}" if extra else "")
    height = f"rail raised {test.height_m * 1e3:.0f} mm" + (
        f", bogie twisted {test.bogie_height_m * 1e3:.0f} mm" if test.bogie_base_m is not None else "")
    return [(out / f"fig8_wheel_loads{suffix}.png",
             [Panel(per_k(Q[:, WHEELS.index(w)], 1e-3), "time t [s]", f"wheel load Q_{w} [kN]", f"wheel {w}")
              for w in wheels], f"Vertical wheel-rail forces during the twist test, {shown} (paper Fig. 8); "
                                f"{height}{valves}", 2),
            (out / f"dqq{suffix}.png",
             [Panel(per_k(dqq[:, WHEELS.index(w)]), "time t [s]", f"ΔQ/Q0 of wheel {w} [-]", f"wheel {w}",
                    hlines=[(limit, f"limit {limit:g}")]) for w in wheels],
             f"Wheel unloading ΔQ/Q0 (positive: unloaded){valves}", 2),
            (out / f"bellows{suffix}.png", bellow_panels(rec, ks), f"Bellow pressures and temperatures{valves}", 2)]
