"""Dispatch a validated scenario to its runner and gather the outcome (summary, checks, status)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional

from .results import Progress
from .scenario import RIG_KINDS, Scenario


@dataclass
class Outcome:
    scenario: Scenario
    rows: List[Dict[str, object]]
    metrics: Dict[str, float] = field(default_factory=dict)
    diverged: Optional[str] = None

    def report(self, columns: Optional[List[str]] = None) -> str:
        """The summary as a plain-text table."""
        if not self.rows:
            return "(no results)"
        cols = columns or list(self.rows[0])
        cells = [[_cell(r.get(c)) for c in cols] for r in self.rows]
        widths = [max(len(c), *(len(row[i]) for row in cells)) for i, c in enumerate(cols)]
        lines = ["  ".join(c.rjust(w) for c, w in zip(cols, widths))]
        lines += ["  ".join(v.rjust(w) for v, w in zip(row, widths)) for row in cells]
        if self.diverged:
            lines.append(f"DIVERGED: {self.diverged}")
        return "\n".join(lines)

    def check_results(self):
        return [(c, self.metrics.get(c.metric, math.nan)) for c in self.scenario.checks]

    def checks_hold(self) -> bool:
        return all(not math.isnan(v) and c.holds(v) for c, v in self.check_results())

    def check_report(self) -> str:
        lines = ["check                          value      result"]
        for c, v in self.check_results():
            ok = not math.isnan(v) and c.holds(v)
            lines.append(f"{c.text:<28} {v:>9.4f}      {'PASS' if ok else 'FAIL'}")
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
