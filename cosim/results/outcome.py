"""What a run computed, in memory: :class:`Outcome`. The runners (:mod:`cosim.runner`) return
it, :mod:`cosim.results.writer` turns it into files, ``check`` and sweeps evaluate it."""
from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

from cosim.limits.checks import FAIL, PASS, VERDICT_LINE, CaseMetrics, CheckResult, check_report, check_value, evaluate, overall
from cosim.limits.validity import failures
from cosim.scenario.checks import Check
from cosim.scenario.model import Scenario

#: warnings about results (validity, settling) go here, not through the progress lines; the CLI
#: prints them on stderr unless --quiet (they stay in run.json and check.json)
LOG = logging.getLogger("pneumorail")


@dataclass
class Computed:
    """What a kind's :meth:`~cosim.kinds.base.Kind.run` computed; the runner (:mod:`cosim.runner`)
    alone builds the :class:`Outcome` from it (timing, totals, validity flags, faults column).

    Attributes
    ----------
    rows : list of dict
        The summary, one row per case (see :attr:`Outcome.rows`).
    shown : tuple of str
        The columns of :meth:`Outcome.report` (empty: every column).
    series, tables, diagnoses, warnings, info
        As in :class:`Outcome`; ``warnings`` are those the kind kept (logged as they arose).
    cases : list of CaseMetrics, optional
        The checkable metrics of each case, when they need more than its row (e.g. the EN 14363
        statistics per zone); None: the runner takes them from the rows
        (:meth:`~cosim.kinds.base.Kind.case_metrics`).
    """

    rows: List[Dict[str, object]]
    shown: Tuple[str, ...] = ()
    series: Dict[str, object] = field(default_factory=dict)
    tables: Dict[str, List[Dict[str, object]]] = field(default_factory=dict)
    cases: Optional[List[CaseMetrics]] = None
    diagnoses: List[str] = field(default_factory=list)
    warnings: List[str] = field(default_factory=list)
    info: Dict[str, object] = field(default_factory=dict)


@dataclass(frozen=True, kw_only=True)
class Outcome:
    """The result of running one scenario, built once by the runner (:func:`cosim.runner.run`)
    from what the kind computed (:class:`Computed`); frozen, its fields given by name.

    Attributes
    ----------
    scenario : Scenario
        What ran (validated, with overrides applied).
    rows : list of dict
        The summary: one row per case (k value, valve setting, rig configuration ...), column
        names with units (``roll_max_rad``, ``T_bellow_max_K``), each with its validity flags
        (:mod:`cosim.limits.validity`) and, with faults, what failed; ``summary.csv``.
    shown : tuple of str
        The columns of :meth:`report` (empty: every column).
    series : dict of str to xarray.Dataset
        Labelled time series (units in each variable's ``units`` attribute), by name: for a car
        run one Dataset, dimensions ``time`` x ``wheel`` / ``bellow`` / ``valve`` / ``link`` x
        ``case`` (see :mod:`cosim.results.series`); for a rig one Dataset per run. Written as
        ``timeseries/<name>[_<case>].csv``.
    metrics : dict of str to float
        Totals over the cases (:meth:`~cosim.kinds.base.Kind.totals`: the largest of each
        headline metric, the lowest critical speed; NaN if a case diverged).
    cases : list of CaseMetrics
        The checkable metrics of each case (what ``checks:`` are evaluated on).
    diagnoses : list of str
        Why cases stopped early (divergence); empty when every case ran to its end.
    warnings : list of str
        Results outside the model's validity or not settled (also logged as they arise).
    info : dict
        Further run facts for ``run.json`` (e.g. the twist height, the static wheel loads).
    wall_s : float
        Wall time of the computation [s].
    interrupted : bool
        The run was stopped by Ctrl-C or SIGTERM (:mod:`cosim.interrupts`): its results end
        there (``run.json``: status ``interrupted``).
    tables : dict of str to list of dict
        Further tables by name, rows of columns with units (e.g. ``assessment``: the EN 14363
        statistics per zone and wheel); ``<name>.csv``.
    """

    scenario: Scenario
    rows: List[Dict[str, object]]
    shown: Tuple[str, ...] = ()
    series: Dict[str, object] = field(default_factory=dict)
    metrics: Dict[str, float] = field(default_factory=dict)
    cases: List[CaseMetrics] = field(default_factory=list)
    diagnoses: List[str] = field(default_factory=list)
    warnings: List[str] = field(default_factory=list)
    info: Dict[str, object] = field(default_factory=dict)
    wall_s: float = 0.0
    interrupted: bool = False
    tables: Dict[str, List[Dict[str, object]]] = field(default_factory=dict)

    @property
    def diverged(self) -> Optional[str]:
        """The diagnoses in one line, or None when every case ran to its end."""
        return "; ".join(self.diagnoses) or None

    def report(self, columns: Optional[Sequence[str]] = None) -> str:
        """The summary as a plain-text table."""
        if not self.rows:
            return "(no results)"
        cols = list(columns or self.shown or dict.fromkeys(c for r in self.rows for c in r))
        cells = [[_cell(r.get(c)) for c in cols] for r in self.rows]
        widths = [max(len(c), *(len(row[i]) for row in cells)) for i, c in enumerate(cols)]
        lines = ["  ".join(c.rjust(w) for c, w in zip(cols, widths))]
        lines += ["  ".join(v.rjust(w) for v, w in zip(row, widths)) for row in cells]
        if self.diverged:
            lines.append(f"DIVERGED: {self.diverged}")
        return "\n".join(lines)

    def check_value(self, check: Check) -> Tuple[float, str]:
        """See :func:`cosim.limits.checks.check_value`."""
        return check_value(check, self.cases, self.metrics)

    def check_results(self) -> List[Tuple[Check, float]]:
        return [(c, self.check_value(c)[0]) for c in self.scenario.checks]

    def evaluate(self, check: Check) -> CheckResult:
        """See :func:`cosim.limits.checks.evaluate`."""
        return evaluate(check, self.cases, self.metrics)

    def validity_failures(self) -> List[str]:
        """``case: flag`` for every validity flag (:mod:`cosim.limits.validity`) the scenario does not
        ``allow``."""
        return failures(self.rows, self.scenario.allow)

    def checks_hold(self) -> bool:
        """Every limit holds, every case ran to its end and none left the models' validity
        (unless allowed)."""
        return self.verdict()["status"] == PASS

    def check_report(self) -> str:
        lines = check_report(self.scenario.checks, self.cases, self.metrics).splitlines()[:-1]
        for failure in self.validity_failures():
            lines.append(f"outside the model's validity: {failure} (FAIL; list it under the scenario's allow: to accept it)")
        if self.diverged:
            lines.append(f"diverged: {self.diverged} (FAIL)")
        lines.append(VERDICT_LINE[self.verdict()["status"]])
        return "\n".join(lines)

    def verdict(self) -> Dict[str, object]:
        """The machine-readable result of ``check`` (``check.json``): overall status, and every
        check, validity flag and divergence with its own status."""
        items = [self.check_item(self.evaluate(c)) for c in self.scenario.checks]
        items += [{"name": f"validity: {f}", "status": FAIL, "message": "outside the model's validity"}
                  for f in self.validity_failures()]
        if self.diverged:
            items.append({"name": "run completes", "status": FAIL, "message": self.diverged})
        return {"scenario": str(self.scenario.file), "name": self.scenario.name, "kind": self.scenario.kind,
                "status": overall([i["status"] for i in items]), "checks": items}

    def check_item(self, r: CheckResult) -> Dict[str, object]:
        """A check's entry of :meth:`verdict`; one whose value is missing says why in ``message``
        (and that the run diverged, if it did: the ``run completes`` entry has the diagnosis)."""
        item = {"name": r.check.text, "metric": r.check.metric, "op": r.check.op, "limit": r.check.limit,
                "value": r.value, "at": r.where, "status": r.status}
        if r.missing:
            item["message"] = r.reason + (" (the run diverged)" if self.diverged else "")
        return item


def warn(found: List[str], message: str) -> None:
    """Keep a warning for the outcome (and run.json), and log it now."""
    found.append(message)
    LOG.warning(message)


def largest(values) -> float:
    """The largest value; NaN if any is NaN (a diverged case)."""
    values = [float(v) for v in values]
    return math.nan if any(math.isnan(v) for v in values) else max(values)


def _cell(v) -> str:
    if v is None:                                  # a column this row does not have
        return "-"
    if isinstance(v, float):
        return "inf" if math.isinf(v) else f"{v:.5g}"
    return str(v)
