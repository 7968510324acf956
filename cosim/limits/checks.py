"""Limits on results: evaluate the scenario's checks (:mod:`cosim.scenario.checks`) on the cases
of a run, report PASS/FAIL/ERROR with the case that gave the value (or why there is none).

A check is about the worst value of a metric over the cases (k value x valve setting) and
wheels its selectors leave -- the largest for an upper limit, the smallest for a lower one. Its
status (:func:`evaluate`) is ``pass``, ``fail`` (a value violates the limit) or ``error``: a
value it covers is missing (NaN, e.g. a case that diverged, or not computed at all) and none
violates the limit -- never a pass, never a violation of NaN. ``pneumorail check`` and
``pneumorail sweep --check`` both judge through :func:`evaluate`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

from cosim.scenario.checks import Check
from cosim.scenario.schema import k_label


# ----------------------------------------------------------------------------------- evaluation
@dataclass
class CaseMetrics:
    """The checkable metrics of one case (a k value with a valve setting): ``values`` metric ->
    value; ``wheels`` metric -> wheel -> value for the per-wheel ones (their ``values`` entry,
    if any, is ignored: the largest over the wheels is taken from ``wheels``); ``zones`` metric ->
    test zone -> wheel (or wheelset) -> value for the per-zone ones."""

    k: float
    valves: bool
    values: Dict[str, float] = field(default_factory=dict)
    wheels: Dict[str, Dict[str, float]] = field(default_factory=dict)
    zones: Dict[str, Dict[str, Dict[str, float]]] = field(default_factory=dict)

    def candidates(self, metric: str, wheel: Optional[str] = None,
                   zone: Optional[str] = None) -> List[Tuple[float, Optional[str]]]:
        """(value, where) pairs the metric takes in this case (one wheel, every wheel, or none;
        for a per-zone metric one zone or every zone); empty when the case did not compute it."""
        if metric in self.zones:
            return [(v, f"{z}, {'wheel' if who[-1].isalpha() else 'wheelset'} {who}")
                    for z, per in self.zones[metric].items() if zone is None or z == zone
                    for who, v in per.items() if wheel is None or who == wheel]
        if metric in self.wheels:
            per_wheel = self.wheels[metric]
            return [(v, w) for w, v in per_wheel.items() if wheel is None or w == wheel]
        return [(self.values[metric], None)] if metric in self.values else []   # absent: none


PASS, FAIL, ERROR = "pass", "fail", "error"


@dataclass(frozen=True)
class CheckResult:
    """A check evaluated on a run's cases: ``value`` the worst of the values it covers, ``where``
    the case (and wheel, zone) that gave it, ``missing`` why each value it covers that is not
    there is missing (a case gave NaN, or does not have the metric). With values missing, the
    worst is unknown (``value`` NaN) unless one that is there already violates the limit."""

    check: Check
    value: float
    where: str
    missing: Tuple[str, ...] = ()

    @property
    def status(self) -> str:
        """``fail`` if a value violates the limit, else ``error`` if one is missing, else ``pass``."""
        if math.isnan(self.value) or (self.missing and self.check.holds(self.value)):
            return ERROR
        return PASS if self.check.holds(self.value) else FAIL

    @property
    def reason(self) -> str:
        """Why a value is missing ('' when none is)."""
        return f"no value: {'; '.join(self.missing)}" if self.missing else ""


def case_label(case: CaseMetrics, cases: Sequence[CaseMetrics], check: Check) -> str:
    """``k = 0`` (``k = 0, valves off`` when the run has both valve settings or the check selects one)."""
    where = [f"k = {k_label(case.k)}"]
    if len({c.valves for c in cases}) > 1 or check.valves is not None:
        where.append(f"valves {'on' if case.valves else 'off'}")
    return ", ".join(where)


def _absent(check: Check, label: str) -> str:
    part = "".join(f" {name} {value}" for name, value in (("in zone", check.zone), ("of wheel", check.wheel)) if value)
    return f"{label} has no {check.metric}{part}"


def evaluate(check: Check, cases: Sequence[CaseMetrics], totals: Dict[str, float] = None) -> CheckResult:
    """The check on ``cases``: the worst value over the cases and wheels (zones) its selectors
    leave (the largest for an upper limit, the smallest for a lower one, :attr:`Check.lower_limit`),
    where it was found (e.g. ``k = 0, valves off, wheel 3R``) and, per case, why a value is missing
    (NaN, or not computed). Without cases, a check without selectors is evaluated on ``totals``."""
    if not cases:
        plain = check.wheel is None and check.k is None and check.valves is None and check.zone is None
        value = (totals or {}).get(check.metric, math.nan) if plain else math.nan
        missing = () if not math.isnan(value) else (f"the run gave no {check.metric}",)
        return CheckResult(check, float(value), "", missing)
    selected = [case for case in cases if check.selects(case.k, case.valves)]
    if not selected:
        return CheckResult(check, math.nan, "no case", ("no case of the run is selected",))
    found, missing = [], []
    for case in selected:
        label = case_label(case, cases, check)
        values = case.candidates(check.metric, check.wheel, check.zone)
        if not values:
            missing.append(_absent(check, label))
        elif any(math.isnan(v) for v, _ in values):
            missing.append(f"{check.metric} is NaN in {label}")
        found += [(float(v), label, w) for v, w in values if not math.isnan(v)]
    if not found:
        return CheckResult(check, math.nan, "", tuple(missing))
    v, label, w = (min if check.lower_limit else max)(found, key=lambda f: f[0])
    if missing and check.holds(v):                      # the worst is among the missing: unknown
        return CheckResult(check, math.nan, "", tuple(missing))
    where = label if w is None else f"{label}, {w if ',' in w else f'wheel {w}'}"
    return CheckResult(check, v, where, tuple(missing))


def check_value(check: Check, cases: Sequence[CaseMetrics], totals: Dict[str, float] = None) -> Tuple[float, str]:
    """The value :func:`evaluate` finds and where: NaN when a value it covers is missing (a
    diverged case)."""
    result = evaluate(check, cases, totals)
    return (math.nan if result.missing else result.value), result.where


def overall(statuses: Sequence[str]) -> str:
    """The status of several: ``fail`` if one fails, else ``error`` if one has no value, else ``pass``."""
    return FAIL if FAIL in statuses else ERROR if ERROR in statuses else PASS


#: the last line of a check report, by overall status
VERDICT_LINE = {PASS: "all limits hold", FAIL: "LIMIT VIOLATED", ERROR: "ERROR: a check has no value"}


def check_report(checks: Sequence[Check], cases: Sequence[CaseMetrics], totals: Dict[str, float] = None) -> str:
    """One line per check: its text, the value, PASS/FAIL/ERROR and the case that gave the value
    (or why there is none)."""
    results = [evaluate(c, cases, totals) for c in checks]
    width = max([len("check")] + [len(r.check.text) for r in results])
    lines = [f"{'check':<{width}}  {'value':>10}  result  at"]
    for r in results:
        at = "; ".join(filter(None, [r.where, r.reason]))
        value = "—" if math.isnan(r.value) else f"{r.value:.4g}"
        lines.append(f"{r.check.text:<{width}}  {value:>10}  {r.status.upper():<6}  {at}")
    lines.append(VERDICT_LINE[overall([r.status for r in results])])
    return "\n".join(lines)
