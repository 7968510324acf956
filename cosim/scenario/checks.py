"""The ``checks:`` section of a car scenario: thresholds on summary metrics,
``metric[selectors] op number`` (:class:`Check`), parsed and checked against the scenario's kind,
k values and valve settings. They are evaluated on a run's cases by :mod:`cosim.limits.checks`.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Dict, Optional, Sequence, Tuple

from cosim.errors import ScenarioError
from cosim.scenario.schema import k_label
from vehicle.params import WHEELS


@dataclass(frozen=True)
class Check:
    """A threshold on a summary metric, e.g. ``dqq_max <= 0.6``, optionally for one wheel, one k,
    one valve setting and one test zone of the track: ``dqq_max[3R] <= 0.6``,
    ``dqq_qs_max[k=0, valves=on] <= 0.6``, ``yq_2m_p9985[zone=R<250] <= 1.2``. The value checked
    is the worst over the cases (k, valve setting), wheels and zones the selectors leave (no
    selector: over all of them): the largest for an upper limit (``<=``, ``<``), the smallest for
    a lower one (``>=``, ``>``, e.g. ``critical_speed_m_per_s >= 30``)."""

    metric: str
    op: str
    limit: float
    text: str
    wheel: Optional[str] = None
    k: Optional[float] = None
    valves: Optional[bool] = None
    zone: Optional[str] = None

    def holds(self, value: float) -> bool:
        return {"<=": value <= self.limit, "<": value < self.limit, ">=": value >= self.limit,
                ">": value > self.limit}[self.op]

    @property
    def lower_limit(self) -> bool:
        """A lower limit (``>=``, ``>``): the smallest value is the one that decides."""
        return self.op in (">=", ">")

    def selects(self, k: float, valves: bool) -> bool:
        """Whether the case (k, valve setting) is one the check is about."""
        return (self.k is None or k == self.k) and (self.valves is None or valves == self.valves)


_NUMBER = r"[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?\d+)?"
_CHECK = re.compile(r"^\s*([A-Za-z_]\w*)\s*((?:\[[^\[\]]*\]\s*)*)(<=|<|>=|>)\s*(" + _NUMBER + r")\s*$")
_SELECTOR = re.compile(r"^\s*(?:(?P<wheel>[0-9]+[A-Za-z]+)|k\s*=\s*(?P<k>" + _NUMBER + r"|[-+]?\.?inf(?:inity)?)"
                       r"|valves\s*=\s*(?P<valves>on|off|true|false)|zone\s*=\s*(?P<zone>[^,]+?))\s*$", re.IGNORECASE)




def checks_hint(kind) -> str:
    """What to add to a scenario of ``kind`` that has no checks (an example and the metrics)."""
    metrics = kind.check_metrics
    if not metrics:
        return f"{kind.name} scenarios have no checkable metrics"
    return f"add e.g. checks: ['{metrics[0]} <= ...'] (metrics: {', '.join(metrics)})"


def parse_checks(value, kind, experiment, file, k_values: Sequence[float] = (),
                 valve_settings: Sequence[bool] = ()) -> Tuple[Check, ...]:
    """``metric[selectors] op number``; selectors (comma-separated, in one or more brackets): a
    wheel (1L ... 4R, for the kind's per-wheel metrics), ``k=<value>`` (one of the scenario's k
    values, ``inf`` for isothermal), ``valves=on|off`` (one of its valve settings) and
    ``zone=<zone>`` (a test zone of the track, for the kind's per-zone metrics:
    :mod:`cosim.limits.assessment`). ``kind``:
    the scenario's :class:`~cosim.kinds.base.Kind` (its ``check_metrics`` and ``wheel_metrics``;
    its module's ``refuse_check(metric, experiment)`` refuses a metric the experiment cannot give,
    e.g. lateral wheel forces without wheel-rail contact, and ``refuse_limit(metric, op, limit,
    experiment)`` a limit it cannot decide, e.g. a critical speed above the speeds it scans)."""
    refuse, refuse_limit = kind.refuse_check, kind.refuse_limit
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
        if metric not in kind.check_metrics:
            raise ScenarioError(file, where, f"unknown metric {metric!r} for a {kind.name} scenario "
                                             f"(known: {', '.join(kind.check_metrics)})")
        reason = refuse(metric, experiment) or refuse_limit(metric, op, limit, experiment)
        if reason:
            raise ScenarioError(file, where, reason)
        chosen: Dict[str, Any] = {}
        items = [item for group in re.findall(r"\[([^\[\]]*)\]", selectors) for item in group.split(",")]
        for item in items:
            sel = _SELECTOR.match(item)
            if not sel:
                raise ScenarioError(file, where, f"unknown selector {item.strip()!r} in {text!r} (expected a wheel "
                                                 f"{WHEELS[0]} ... {WHEELS[-1]}, k=<value>, valves=on|off or "
                                                 f"zone=<test zone>)")
            name = next(n for n in ("wheel", "k", "valves", "zone") if sel.group(n) is not None)
            if name in chosen:
                raise ScenarioError(file, where, f"{name} selected twice in {text!r}")
            raw = sel.group(name)
            if name == "wheel":
                wheel = raw.upper()
                if wheel not in WHEELS:
                    raise ScenarioError(file, where, f"unknown wheel {raw!r} in {text!r} (wheels: {', '.join(WHEELS)})")
                if metric not in kind.wheel_metrics:
                    raise ScenarioError(file, where, f"{metric} is not a per-wheel metric: no wheel selector "
                                                     f"(per-wheel: {', '.join(kind.wheel_metrics) or 'none'})")
                chosen[name] = wheel
            elif name == "k":
                k = float(re.sub(r"\.?inf(inity)?$", "inf", raw.lower()))   # .inf, inf, -.inf
                if k not in k_values:
                    raise ScenarioError(file, where, f"k = {raw} is not one of the scenario's k values "
                                                     f"({', '.join(k_label(v) for v in k_values)})")
                chosen[name] = k
            elif name == "zone":
                zone = raw.strip()
                if metric not in kind.zone_metrics:
                    raise ScenarioError(file, where, f"{metric} is not assessed per test zone: no zone selector "
                                                     f"(per zone: {', '.join(kind.zone_metrics) or 'none'})")
                present = kind.zones(experiment)
                if zone not in present:
                    raise ScenarioError(file, where, f"zone {zone!r} is not a test zone of this track (its zones: "
                                                     f"{', '.join(present)})")
                reason = kind.refuse_zone(metric, zone, experiment)
                if reason:
                    raise ScenarioError(file, where, reason)
                chosen[name] = zone
            else:
                on = raw.lower() in ("on", "true")
                if on not in valve_settings:
                    shown = ", ".join("on" if v else "off" for v in valve_settings)
                    raise ScenarioError(file, where, f"valves={raw} is not a valve setting of the scenario ({shown})")
                chosen[name] = on
        out.append(Check(metric, op, limit, text.strip(), **chosen))
    return tuple(out)
