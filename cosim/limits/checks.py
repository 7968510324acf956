"""Limits on results: evaluate the scenario's checks (:mod:`cosim.scenario.checks`) on the cases
of a run, report PASS/FAIL with the case that gave the value.

A check is about the worst value of a metric over the cases (k value x valve setting) and
wheels its selectors leave -- the largest for an upper limit, the smallest for a lower one; a NaN
among them (a diverged case) fails it.
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
        for a per-zone metric one zone or every zone)."""
        if metric in self.zones:
            return [(v, f"{z}, {'wheel' if who[-1].isalpha() else 'wheelset'} {who}")
                    for z, per in self.zones[metric].items() if zone is None or z == zone
                    for who, v in per.items() if wheel is None or who == wheel]
        if metric in self.wheels:
            per_wheel = self.wheels[metric]
            return [(per_wheel[wheel], wheel)] if wheel is not None else list((v, w) for w, v in per_wheel.items())
        return [(self.values.get(metric, math.nan), None)]


def check_value(check: Check, cases: Sequence[CaseMetrics], totals: Dict[str, float] = None) -> Tuple[float, str]:
    """The value a check is about -- the worst over the cases and wheels its selectors leave (the
    largest for an upper limit, the smallest for a lower one, :attr:`Check.lower_limit`)
    (NaN if one of them is NaN: a diverged case fails every check that includes it) -- and where
    it was found (e.g. ``k = 0, valves off, wheel 3R``). Without cases, a check without
    selectors is evaluated on ``totals``."""
    if not cases:
        plain = check.wheel is None and check.k is None and check.valves is None and check.zone is None
        return ((totals or {}).get(check.metric, math.nan) if plain else math.nan), ""
    found = [(v, case, w) for case in cases if check.selects(case.k, case.valves)
             for v, w in case.candidates(check.metric, check.wheel, check.zone)]
    if not found:
        return math.nan, "no case"
    if any(math.isnan(v) for v, _, _ in found):
        v, case, w = next(f for f in found if math.isnan(f[0]))
    else:
        v, case, w = (min if check.lower_limit else max)(found, key=lambda f: f[0])
    where = [f"k = {k_label(case.k)}"]
    if len({c.valves for c in cases}) > 1 or check.valves is not None:
        where.append(f"valves {'on' if case.valves else 'off'}")
    if w is not None:
        where.append(w if "," in w else f"wheel {w}")
    return float(v), ", ".join(where)


def passes(check: Check, value: float) -> bool:
    return not math.isnan(value) and check.holds(value)


def check_report(checks: Sequence[Check], cases: Sequence[CaseMetrics], totals: Dict[str, float] = None) -> str:
    """One line per check: its text, the value, PASS/FAIL and the case that gave the value."""
    results = [(c, *check_value(c, cases, totals)) for c in checks]
    width = max([len("check")] + [len(c.text) for c, _, _ in results])
    lines = [f"{'check':<{width}}  {'value':>10}  result  at"]
    for c, v, where in results:
        lines.append(f"{c.text:<{width}}  {v:>10.4g}  {'PASS' if passes(c, v) else 'FAIL':<6}  {where}")
    lines.append("all limits hold" if all(passes(c, v) for c, v, _ in results) else "LIMIT VIOLATED")
    return "\n".join(lines)
