"""Limits on results (the ``checks:`` section): parse ``metric[selectors] op number``, evaluate it
on the cases of a run, report PASS/FAIL with the case that gave the value.

A check is about the largest value of a metric over the cases (k value x valve setting) and
wheels its selectors leave; a NaN among them (a diverged case) fails it.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple

from vehicle.params import WHEELS

from cosim.results.io import k_label
from cosim.scenario.schema import ScenarioError


@dataclass(frozen=True)
class Check:
    """A threshold on a summary metric, e.g. ``dqq_max <= 0.6``, optionally for one wheel, one k
    and one valve setting: ``dqq_max[3R] <= 0.6``, ``dqq_qs_max[k=0, valves=on] <= 0.6``. The
    value checked is the largest over the cases (k, valve setting) and wheels the selectors
    leave (no selector: over all of them)."""

    metric: str
    op: str
    limit: float
    text: str
    wheel: Optional[str] = None
    k: Optional[float] = None
    valves: Optional[bool] = None

    def holds(self, value: float) -> bool:
        return {"<=": value <= self.limit, "<": value < self.limit, ">=": value >= self.limit,
                ">": value > self.limit}[self.op]

    def selects(self, k: float, valves: bool) -> bool:
        """Whether the case (k, valve setting) is one the check is about."""
        return (self.k is None or k == self.k) and (self.valves is None or valves == self.valves)


#: checkable metrics per scenario kind (each the largest over the selected cases)
CHECK_METRICS = {"twist": ("dqq_max", "dqq_qs_max", "dqq_drift"),
                 "curve_entry": ("roll_max_rad", "air_injected_kg", "air_exhausted_kg", "yq_max", "sum_y_max",
                                 "dqq_max", "dqq_2m_max")}
#: metrics that can name a wheel (``dqq_max[3R]``): without one, the largest over the wheels
WHEEL_METRICS = ("dqq_max", "dqq_qs_max", "dqq_drift", "yq_max", "dqq_2m_max")
#: curve_entry metrics of the lateral wheel-rail forces: they need ``curve.guidance: contact``
#: (kinematic guidance has no lateral wheel-rail force: Y is NaN)
CONTACT_METRICS = ("yq_max", "sum_y_max")
_NUMBER = r"[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?\d+)?"
_CHECK = re.compile(r"^\s*([A-Za-z_]\w*)\s*((?:\[[^\[\]]*\]\s*)*)(<=|<|>=|>)\s*(" + _NUMBER + r")\s*$")
_SELECTOR = re.compile(r"^\s*(?:(?P<wheel>[0-9]+[A-Za-z]+)|k\s*=\s*(?P<k>" + _NUMBER + r"|[-+]?\.?inf(?:inity)?)"
                       r"|valves\s*=\s*(?P<valves>on|off|true|false))\s*$", re.IGNORECASE)




def parse_checks(value, kind, file, k_values: Sequence[float] = (), valve_settings: Sequence[bool] = (),
                 guidance: Optional[str] = None) -> Tuple[Check, ...]:
    """``metric[selectors] op number``; selectors (comma-separated, in one or more brackets): a
    wheel (1L ... 4R, for the per-wheel metrics), ``k=<value>`` (one of the scenario's k values,
    ``inf`` for isothermal) and ``valves=on|off`` (one of its valve settings). ``guidance``: the
    curve's (``kinematic`` refuses :data:`CONTACT_METRICS`)."""
    if not isinstance(value, list):
        raise ScenarioError(file, ["checks"], f"expected a list like ['dqq_max <= 0.6'], got {type(value).__name__}")
    out = []
    for i, text in enumerate(value):
        where = [f"checks[{i}]"]
        m = _CHECK.match(text) if isinstance(text, str) else None
        if not m:
            raise ScenarioError(file, where, f"expected 'metric <= number' (or <, >=, >; optionally "
                                             f"metric[3R, k=0, valves=on]), got {text!r}")
        metric, selectors, op, limit = m.group(1), m.group(2), m.group(3), float(m.group(4))
        if metric not in CHECK_METRICS[kind]:
            raise ScenarioError(file, where, f"unknown metric {metric!r} for a {kind} scenario "
                                             f"(known: {', '.join(CHECK_METRICS[kind])})")
        if kind == "curve_entry" and metric in CONTACT_METRICS and guidance != "contact":
            raise ScenarioError(file, where, f"{metric} needs curve.guidance: contact (with {guidance or 'kinematic'} "
                                             f"guidance no lateral wheel-rail force is computed)")
        chosen: Dict[str, Any] = {}
        items = [item for group in re.findall(r"\[([^\[\]]*)\]", selectors) for item in group.split(",")]
        for item in items:
            sel = _SELECTOR.match(item)
            if not sel:
                raise ScenarioError(file, where, f"unknown selector {item.strip()!r} in {text!r} (expected a wheel "
                                                 f"{WHEELS[0]} ... {WHEELS[-1]}, k=<value> or valves=on|off)")
            name = next(n for n in ("wheel", "k", "valves") if sel.group(n) is not None)
            if name in chosen:
                raise ScenarioError(file, where, f"{name} selected twice in {text!r}")
            raw = sel.group(name)
            if name == "wheel":
                wheel = raw.upper()
                if wheel not in WHEELS:
                    raise ScenarioError(file, where, f"unknown wheel {raw!r} in {text!r} (wheels: {', '.join(WHEELS)})")
                if metric not in WHEEL_METRICS:
                    raise ScenarioError(file, where, f"{metric} is not a per-wheel metric: no wheel selector "
                                                     f"(per-wheel: {', '.join(m for m in WHEEL_METRICS if m in CHECK_METRICS[kind]) or 'none'})")
                chosen[name] = wheel
            elif name == "k":
                k = float(re.sub(r"\.?inf(inity)?$", "inf", raw.lower()))   # .inf, inf, -.inf
                if k not in k_values:
                    raise ScenarioError(file, where, f"k = {raw} is not one of the scenario's k values "
                                                     f"({', '.join(k_label(v) for v in k_values)})")
                chosen[name] = k
            else:
                on = raw.lower() in ("on", "true")
                if on not in valve_settings:
                    shown = ", ".join("on" if v else "off" for v in valve_settings)
                    raise ScenarioError(file, where, f"valves={raw} is not a valve setting of the scenario ({shown})")
                chosen[name] = on
        out.append(Check(metric, op, limit, text.strip(), **chosen))
    return tuple(out)


# ----------------------------------------------------------------------------------- evaluation
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


def check_value(check: Check, cases: Sequence[CaseMetrics], totals: Dict[str, float] = None) -> Tuple[float, str]:
    """The value a check is about -- the largest over the cases and wheels its selectors leave
    (NaN if one of them is NaN: a diverged case fails every check that includes it) -- and where
    it was found (e.g. ``k = 0, valves off, wheel 3R``). Without cases, a check without
    selectors is evaluated on ``totals``."""
    if not cases:
        plain = check.wheel is None and check.k is None and check.valves is None
        return ((totals or {}).get(check.metric, math.nan) if plain else math.nan), ""
    found = [(v, case, w) for case in cases if check.selects(case.k, case.valves)
             for v, w in case.candidates(check.metric, check.wheel)]
    if not found:
        return math.nan, "no case"
    if any(math.isnan(v) for v, _, _ in found):
        v, case, w = next(f for f in found if math.isnan(f[0]))
    else:
        v, case, w = max(found, key=lambda f: f[0])
    where = [f"k = {k_label(case.k)}"]
    if len({c.valves for c in cases}) > 1 or check.valves is not None:
        where.append(f"valves {'on' if case.valves else 'off'}")
    if w is not None:
        where.append(f"wheel {w}")
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
