"""Dispatch a validated scenario to its runner and gather the outcome (summary, checks, status)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Tuple

from .results import Progress, k_label
from .scenario import RIG_KINDS, Check, Scenario


@dataclass
class CaseMetrics:
    """The checkable metrics of one case (a k value with a valve setting): ``values`` metric ->
    value; ``wheels`` metric -> wheel -> value for the per-wheel ones (their ``values`` entry,
    if any, is ignored: the largest over the wheels is taken from ``wheels``)."""

    k: float
    valves: bool
    values: Dict[str, float] = field(default_factory=dict)
    wheels: Dict[str, Dict[str, float]] = field(default_factory=dict)

    def candidates(self, metric: str, wheel: Optional[str] = None) -> List[Tuple[float, Optional[str]]]:
        """(value, wheel) pairs the metric takes in this case (one wheel, every wheel, or none)."""
        if metric in self.wheels:
            per_wheel = self.wheels[metric]
            return [(per_wheel[wheel], wheel)] if wheel is not None else list((v, w) for w, v in per_wheel.items())
        return [(self.values.get(metric, math.nan), None)]


@dataclass
class Outcome:
    scenario: Scenario
    rows: List[Dict[str, object]]
    metrics: Dict[str, float] = field(default_factory=dict)
    diverged: Optional[str] = None
    cases: List[CaseMetrics] = field(default_factory=list)

    def report(self, columns: Optional[List[str]] = None) -> str:
        """The summary as a plain-text table."""
        if not self.rows:
            return "(no results)"
        cols = columns or list(dict.fromkeys(c for r in self.rows for c in r))
        cells = [[_cell(r.get(c)) for c in cols] for r in self.rows]
        widths = [max(len(c), *(len(row[i]) for row in cells)) for i, c in enumerate(cols)]
        lines = ["  ".join(c.rjust(w) for c, w in zip(cols, widths))]
        lines += ["  ".join(v.rjust(w) for v, w in zip(row, widths)) for row in cells]
        if self.diverged:
            lines.append(f"DIVERGED: {self.diverged}")
        return "\n".join(lines)

    def check_value(self, check: Check) -> Tuple[float, str]:
        """The value a check is about -- the largest over the cases and wheels its selectors leave
        (NaN if one of them is NaN: a diverged case fails every check that includes it) -- and
        where it was found (e.g. ``k = 0, valves off, wheel 3R``)."""
        if not self.cases:        # an outcome with totals only: checks without selectors
            plain = check.wheel is None and check.k is None and check.valves is None
            return (self.metrics.get(check.metric, math.nan) if plain else math.nan), ""
        found = [(v, case, w) for case in self.cases if check.selects(case.k, case.valves)
                 for v, w in case.candidates(check.metric, check.wheel)]
        if not found:
            return math.nan, "no case"
        if any(math.isnan(v) for v, _, _ in found):
            v, case, w = next(f for f in found if math.isnan(f[0]))
        else:
            v, case, w = max(found, key=lambda f: f[0])
        where = [f"k = {k_label(case.k)}"]
        if len({c.valves for c in self.cases}) > 1 or check.valves is not None:
            where.append(f"valves {'on' if case.valves else 'off'}")
        if w is not None:
            where.append(f"wheel {w}")
        return float(v), ", ".join(where)

    def check_results(self):
        return [(c, self.check_value(c)[0]) for c in self.scenario.checks]

    def checks_hold(self) -> bool:
        return all(not math.isnan(v) and c.holds(v) for c, v in self.check_results())

    def check_report(self) -> str:
        """One line per check: its text, the value, PASS/FAIL and the case that gave the value."""
        results = [(c, *self.check_value(c)) for c in self.scenario.checks]
        width = max([len("check")] + [len(c.text) for c, _, _ in results])
        lines = [f"{'check':<{width}}  {'value':>10}  result  at"]
        for c, v, where in results:
            ok = not math.isnan(v) and c.holds(v)
            lines.append(f"{c.text:<{width}}  {v:>10.4g}  {'PASS' if ok else 'FAIL':<6}  {where}")
        lines.append("all limits hold" if self.checks_hold() else "LIMIT VIOLATED")
        return "\n".join(lines)


def _cell(v) -> str:
    if isinstance(v, float):
        return "inf" if math.isinf(v) else f"{v:.5g}"
    return str(v)


def run_scenario(scenario: Scenario, out_dir: Path, progress: Progress) -> Outcome:
    if scenario.kind in RIG_KINDS:
        from .rig_runner import run_rig
        rows, diagnoses = run_rig(scenario, out_dir, progress)
        return Outcome(scenario, rows, diverged="; ".join(diagnoses) or None)
    if scenario.kind == "curve_entry":
        from .curve import run_curve
        return run_curve(scenario, out_dir, progress)
    from .twist import run_twist
    return run_twist(scenario, out_dir, progress)
