"""The EN 14363 twist test (paper §4.1, Figs 7-8): ΔQ/Q across heat-transfer coefficients."""
from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Optional

import numpy as np

from vehicle.car import WHEELS, MetroCar

from .criteria import DQQ_LIMIT, static_wheel_loads, wheel_unloading
from .car_runs import bellow_panels, curves_per_k, record_columns, simulate
from .plots import Panel, save_panels
from .results import Progress, k_label, write_columns, write_rows, write_run_json
from .runner import Outcome
from .scenario import Scenario, TwistTest


def rail_heights(test: TwistTest):
    """rail_height_m(t) -> (8,): the raised wheels follow 0.5 h (1 - cos(pi t / ramp)), then h."""
    raised = np.array([w in test.raised_wheels for w in WHEELS], dtype=float)
    h, ramp = test.height_m, test.ramp_s

    def rail(t: float) -> np.ndarray:
        s = min(max(t / ramp, 0.0), 1.0)
        return raised * (h * 0.5 * (1.0 - math.cos(math.pi * s)))
    return rail


def make_car(scenario: Scenario) -> MetroCar:
    """The car standing on rails that follow the twist (picklable factory for cosim.car_runs)."""
    return MetroCar(scenario.vehicle, rail_height_m=rail_heights(scenario.twist), step_s=scenario.solver.mechanics_step_s)


def simulate_twist(scenario: Scenario, progress: Optional[Progress] = None):
    """Every k of the twist scenario: (k values, record arrays, diagnoses)."""
    return simulate(scenario, make_car, scenario.twist.duration_s,
                    scenario.name if progress is not None and not progress.quiet else None)


def run_twist(scenario: Scenario, out: Path, progress: Progress) -> Outcome:
    t0 = time.perf_counter()
    test = scenario.twist
    progress(f"twist {test.twist * 1e3:g} permille over {test.base_m:g} m -> rail raised {test.height_m * 1e3:.1f} mm under "
             f"{', '.join(test.raised_wheels)}; {len(scenario.k_W_per_K)} k values, {test.duration_s:g} s simulated")
    ks, rec, diagnoses = simulate_twist(scenario, progress)
    Q = rec["wheel_load_N"]                       # (samples, 8, cases)
    Q0 = static_wheel_loads(Q[0])                 # (8, cases)
    dqq = wheel_unloading(Q, Q0)                  # (samples, 8, cases)
    t = rec["t_s"]
    rows = []
    for j, k in enumerate(ks):
        worst = np.unravel_index(np.argmax(dqq[:, :, j]), dqq[:, :, j].shape)
        row = {"k_W_per_K": k, "dqq_max": float(dqq[:, :, j].max()), "dqq_max_wheel": WHEELS[worst[1]],
               "t_dqq_max_s": float(t[worst[0]])}
        row.update({f"dqq_max_{w}": float(dqq[:, i, j].max()) for i, w in enumerate(WHEELS)})
        row.update({f"dqq_end_{w}": float(dqq[-1, i, j]) for i, w in enumerate(WHEELS)})
        row["roll_carbody_end_rad"] = float(rec["roll_rad"][-1, j])
        row["T_bellow_max_K"] = float(rec["bellow_T_K"][:, :, j].max())
        row["T_bellow_min_K"] = float(rec["bellow_T_K"][:, :, j].min())
        rows.append(row)
        write_columns(out / "timeseries" / f"twist_k={k_label(k)}.csv",
                      {**record_columns(rec, j), **{f"dqq_{w}": dqq[:, i, j] for i, w in enumerate(WHEELS)}})
    write_rows(out / "summary.csv", rows)
    _plots(out, ks, rec, dqq, test, _dqq_limit(scenario))
    diverged = "; ".join(diagnoses) or None
    metrics = {"dqq_max": max(r["dqq_max"] for r in rows)} if rows else {}
    write_run_json(out, scenario, time.perf_counter() - t0,
                   {"twist_height_m": test.height_m, "twist_per_mille": test.twist * 1e3,
                    "diverged": diverged, "metrics": metrics,
                    "Q0_N": {w: float(Q0[i, 0]) for i, w in enumerate(WHEELS)}})
    outcome = Outcome(scenario, [{c: r[c] for c in ("k_W_per_K", "dqq_max", "dqq_max_wheel", "t_dqq_max_s",
                                                    "dqq_end_1L", "dqq_end_4R", "T_bellow_max_K")} for r in rows],
                      metrics, diverged)
    return outcome


def _dqq_limit(scenario: Scenario) -> float:
    """The limit to draw: the scenario's own dqq_max check, else EN 14363's 0.6."""
    limits = [c.limit for c in scenario.checks if c.metric == "dqq_max"]
    return min(limits) if limits else DQQ_LIMIT


def _plots(out: Path, ks, rec, dqq, test: TwistTest, limit: float) -> None:
    Q = rec["wheel_load_N"]
    per_k = curves_per_k(rec["t_s"], ks)
    wheels = ("1L", "1R", "4L", "4R")
    save_panels(out / "fig8_wheel_loads.png",
                [Panel(per_k(Q[:, WHEELS.index(w)], 1e-3), "time t [s]", f"wheel load Q_{w} [kN]", f"wheel {w}")
                 for w in wheels], f"Vertical wheel-rail forces during the twist test, wheelsets 1 and 4 (paper Fig. 8); "
                                   f"rail raised {test.height_m * 1e3:.0f} mm", ncols=2)
    save_panels(out / "dqq.png",
                [Panel(per_k(dqq[:, WHEELS.index(w)]), "time t [s]", f"ΔQ/Q0 of wheel {w} [-]", f"wheel {w}",
                       hlines=[(limit, f"limit {limit:g}")]) for w in wheels],
                "Wheel unloading ΔQ/Q0 (positive: unloaded)", ncols=2)
    save_panels(out / "bellows.png", bellow_panels(rec, ks), "Bellow pressures and temperatures", ncols=2)
