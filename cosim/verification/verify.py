"""Solution verification: run a scenario with every step halved, estimate each metric's
discretisation error by Richardson extrapolation.

Level 0 is the scenario as given; level i divides the macro-step, the multibody step and the
pneumatic step all by 2^i (the output interval stays, so every level samples the same instants)
and multiplies the cells of every compressible pipe by 2^i.
For each metric and case, with f_0 .. f_N the values from the coarsest to the finest level,
the last three give

    r = (f_{N-1} - f_{N-2}) / (f_N - f_{N-1}),   observed order p = log2(r),
    Richardson estimate f* = f_N + (f_N - f_{N-1}) / (r - 1),

and the estimated relative error of the default settings is |f_0 - f*| / S.

The scale S is the largest of three: |f*|; for a per-wheel metric (``dqq_qs_3R``) the largest
|f*| of that metric over all wheels and cases, so that a wheel whose value is near zero is
judged on the scale of the test; and an absolute floor, a fraction of a reference of the
metric's own unit (:data:`FLOORS`), so that a quantity near zero is judged on the scale of what
it is a part of instead of its own: air [kg] on 0.1 % of the air the circuit holds at the start
(~1 g for the metro car), a roll [rad] on 10 % of the case's largest roll, a force [N] on 1 %
of the static wheel load, a ratio (ΔQ/Q0, Y/Q) on 0.01. A result of 1e-7 kg of air whose
relative error is 30 % is then judged by how much it moves (3e-8 kg) against a gram: 3e-5.

Asymptotic range: the estimate is meaningful when the differences shrink as the steps halve at
about the order the schemes have (second order: every coupling and integrator here). A metric is
flagged ``asymptotic = False`` only where the observed order says it is not: r <= 1 (the
differences do not shrink) or p outside [:data:`ORDER_MIN`, :data:`ORDER_MAX`]; its error is
then bounded by the spread of the levels, |f_0 - f_N| + |f_{N-1} - f_N|, instead of the
Richardson estimate. Differences between the levels below 1e-4 of max(|f|, floor)
(:data:`CONVERGED_BELOW`, 1/50 of the default tolerance) count as converged: no order, no flag,
the error |f_0 - f_N| / S.
"""
from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

from cosim.results.io import Progress, atomic_write, cell, jsonable, write_rows
from cosim.scenario.model import Scenario
from pneumatics.compressible_pipe import COMPRESSIBLE, cell_count
from pneumatics.pipe import Pipe
from vehicle.params import WHEELS

#: Differences between levels below this fraction of the scale S count as converged: they are
#: 1/50 of the default tolerance, below anything a result is judged by (no order is reported).
CONVERGED_BELOW = 1e-4
#: Observed orders outside [ORDER_MIN, ORDER_MAX] mark a metric outside the asymptotic range: the
#: schemes are second order, and orders of ~1-3 are usual where one error term dominates.
ORDER_MIN, ORDER_MAX = 0.5, 4.0
#: Absolute floor of the error scale S by the unit suffix of a metric (the first that matches):
#: (suffix, reference column of the case's summary row or None for 1, fraction of it).
FLOORS = (("_kg", "air_initial_kg", 1e-3), ("_rad", "roll_max_rad", 0.1), ("_N", "Q0_N", 0.01), ("", None, 0.01))

#: the steps each level divides by two
STEPS = ("macro_step_s", "mechanics_step_s", "pneumatic_step_s")
#: Columns that identify a case in a summary row, unless the kind declares its own
#: (:attr:`cosim.kinds.base.Kind.case_columns`).
CASE_COLUMNS = ("valves", "k_W_per_K")


@dataclass(frozen=True)
class Estimate:
    """One metric of one case across the levels."""

    metric: str
    case: str
    values: Tuple[float, ...]           # level 0 (the scenario's steps) .. finest
    order: float                        # observed order p (nan outside the asymptotic range)
    richardson: float                   # extrapolated value f*
    error: float                        # estimated relative error of level 0, |f_0 - f*| / |f*|
    asymptotic: bool

    def row(self) -> Dict[str, object]:
        out: Dict[str, object] = {"metric": self.metric, "case": self.case}
        out.update({f"level_{i}": v for i, v in enumerate(self.values)})
        out.update({"observed_order": self.order, "richardson": self.richardson,
                    "estimated_relative_error": self.error, "asymptotic": self.asymptotic})
        return out


def richardson(values: Sequence[float], metric: str = "", case: str = "", floor: float = 0.0) -> Estimate:
    """Observed order, Richardson estimate and relative error of ``values[0]`` (module doc);
    ``floor``: the absolute floor of the error scale, in the metric's unit."""
    f = [float(v) for v in values]
    if len(f) < 3:
        raise ValueError("Richardson extrapolation needs at least three levels")
    if not all(math.isfinite(v) for v in f):
        return Estimate(metric, case, tuple(f), math.nan, math.nan, math.inf, False)
    scale = max(max(abs(v) for v in f), floor)
    d1, d2 = f[-2] - f[-3], f[-1] - f[-2]
    noise = CONVERGED_BELOW * scale

    def error(best: float, change: float) -> float:  # change: of level 0 from best
        S = max(abs(best), floor)
        return change / S if S > 0.0 else (0.0 if change == 0.0 else math.inf)

    if scale == 0.0 or (abs(d1) <= noise and abs(d2) <= noise):
        return Estimate(metric, case, tuple(f), math.nan, f[-1], error(f[-1], abs(f[0] - f[-1])), True)
    if d2 != 0.0 and d1 / d2 > 1.0:
        r = d1 / d2
        order, best = math.log2(r), f[-1] + d2 / (r - 1.0)
        if ORDER_MIN <= order <= ORDER_MAX:
            return Estimate(metric, case, tuple(f), order, best, error(best, abs(f[0] - best)), True)
    else:
        order = math.nan
    spread = abs(f[0] - f[-1]) + abs(f[-2] - f[-1])
    return Estimate(metric, case, tuple(f), order, f[-1], error(f[-1], spread), False)


def refined(scenario: Scenario, level: int) -> Scenario:
    """The scenario with every step divided by 2**level, and every compressible pipe's cells
    multiplied by it (its space step halved with the time steps: both second order)."""
    s, factor = scenario.solver, 2.0 ** -level
    solver = dataclasses.replace(s, **{step: getattr(s, step) * factor for step in STEPS})
    return dataclasses.replace(scenario, solver=solver, circuit=finer_pipes(scenario.circuit, 2 ** level))


def finer_pipes(circuit, factor: int):
    """``circuit`` (a car's or a rig's) with the cells of each compressible pipe (its ``pipe``,
    ``cross_pipe`` and explicit components) multiplied by ``factor``; itself when it has none."""
    def finer(c):
        if isinstance(c, Pipe) and c.model == COMPRESSIBLE and factor != 1:
            return dataclasses.replace(c, cells=cell_count(c) * factor)
        return c
    if circuit is None:
        return circuit
    changes = {name: finer(getattr(circuit, name)) for name in ("pipe", "cross_pipe") if hasattr(circuit, name)}
    if getattr(circuit, "explicit", None) is not None:
        changes["explicit"] = tuple((n, finer(c)) for n, c in circuit.explicit)
    if all(v is getattr(circuit, k) or (k == "explicit" and v == circuit.explicit) for k, v in changes.items()):
        return circuit
    return dataclasses.replace(circuit, **changes)


def _case(row: Dict[str, object], columns: Sequence[str] = CASE_COLUMNS) -> str:
    """The case of a summary row as its CSV shows it (``valves=True, k_W_per_K=inf``)."""
    return ", ".join(f"{c}={cell(row[c])}" for c in columns if c in row)


def _family(metric: str) -> str:
    """``dqq_qs_3R`` -> ``dqq_qs``: per-wheel metrics share one scale."""
    head, _, tail = metric.rpartition("_")
    return head if tail in WHEELS else metric


def floor_of(metric: str, row: Dict[str, str]) -> float:
    """The absolute floor of ``metric``'s error scale in the case of summary ``row``
    (:data:`FLOORS`; 0 when the reference column is absent)."""
    for suffix, column, fraction in FLOORS:
        if metric.endswith(suffix) or _family(metric).endswith(suffix):
            if column is None:
                return fraction
            try:
                return fraction * abs(float(row[column]))
            except (KeyError, TypeError, ValueError):
                return 0.0
    return 0.0


def estimates(rows_per_level: Sequence[List[Dict[str, str]]], metrics: Sequence[str],
              case_columns: Sequence[str] = CASE_COLUMNS) -> List[Estimate]:
    """Richardson estimates of every metric (present in the rows) of every case (a case: the
    values of ``case_columns``; two rows of one case would hide each other, so they are refused)."""
    by_level = []
    for rows in rows_per_level:
        level = {_case(r, case_columns): r for r in rows}
        if len(level) != len(rows):
            raise ValueError(f"summary rows are not one per ({', '.join(case_columns)})")
        by_level.append(level)
    series = [(metric, case, [float(level[case].get(metric, math.nan)) if case in level else math.nan
                              for level in by_level],
               floor_of(metric, row))
              for metric in metrics for case, row in by_level[0].items() if metric in row]
    # a per-wheel metric is judged on the scale of its family: the largest |estimate| of that
    # metric over all wheels and cases, taken as a floor of its own scale
    family: Dict[str, float] = {}
    for metric, case, values, floor in series:
        e = richardson(values, metric, case, floor)
        if _family(metric) != metric and math.isfinite(e.richardson):
            family[_family(metric)] = max(family.get(_family(metric), 0.0), abs(e.richardson))
    return [richardson(values, metric, case, max(floor, family.get(_family(metric), 0.0)))
            for metric, case, values, floor in series]


def verify(scenario: Scenario, out: Path, levels: int, progress: Progress) -> Tuple[List[Estimate], Optional[str]]:
    """Run the levels into ``out/level_<i>`` (each an output folder of its own) and estimate the
    error from their summary rows (in memory); write ``verify.csv`` and ``verify.json`` (the
    levels' steps, the tolerance and the estimates). Returns the estimates and the diagnoses of
    diverged runs."""
    from cosim.kinds import KINDS
    from cosim.runner import run_scenario
    rows, diverged, steps = [], [], []
    for level in range(levels + 1):
        variant = refined(scenario, level)
        s = variant.solver
        progress(f"level {level}: macro-step {s.macro_step_s:g} s, multibody {s.mechanics_step_s:g} s, "
                 f"pneumatic {s.pneumatic_step_s:g} s")
        outcome = run_scenario(variant, out / f"level_{level}", progress)
        if outcome.diverged:
            diverged.append(f"level {level}: {outcome.diverged}")
        rows.append(outcome.rows)
        steps.append({"level": level, "folder": f"level_{level}", **{k: getattr(s, k) for k in STEPS}})
    kind = KINDS[scenario.kind]
    found = estimates(rows, kind.headline_metrics, kind.case_columns)
    write_rows(out / "verify.csv", [e.row() for e in found])
    info = {"scenario_file": str(scenario.file), "name": scenario.name, "kind": scenario.kind,
            "tolerance": scenario.verify.tolerance, "levels": steps, "diverged": diverged,
            "estimates": [e.row() for e in found]}
    with atomic_write(out / "verify.json") as fh:
        fh.write(json.dumps(jsonable(info), indent=2, allow_nan=False) + "\n")
    return found, "; ".join(diverged) or None


def report(found: Sequence[Estimate], tolerance: float) -> str:
    """The estimates as a plain-text table; a line per metric and case."""
    if not found:
        return "(no metrics to verify)"
    n = len(found[0].values)
    head = (f"{'metric':<20} {'case':<28} " + " ".join(f"{f'level {i}':>12}" for i in range(n))
            + f" {'order':>6} {'Richardson':>12} {'error':>9}")
    lines = [head]
    for e in found:
        order = "  -   " if math.isnan(e.order) else f"{e.order:6.2f}"
        flag = "" if e.error <= tolerance else "  > tolerance"
        flag += "" if e.asymptotic else "  (not asymptotic)"
        lines.append(f"{e.metric:<20} {e.case:<28} " + " ".join(f"{v:12.6g}" for v in e.values)
                     + f" {order} {e.richardson:12.6g} {100 * e.error:8.3f}%{flag}")
    worst = max(found, key=lambda e: e.error)
    lines.append(f"largest estimated error {100 * worst.error:.3f} % ({worst.metric}, {worst.case}); "
                 f"tolerance {100 * tolerance:g} %")
    return "\n".join(lines)
