"""What a run folder's results say against their limits, as one list the report draws everything
from: the EN 14363 assessment (``assessment_limits.csv``), the checks (``check.json``) and what
``run.json`` and ``summary.csv`` say about the run itself (stopped early, outside the models'
validity). Each item (:class:`Judged`) is a value beside its limit with its status; the verdict
(:func:`verdict`) is read from the same items the assessment and checks tables show, so it cannot
contradict them: FAIL if a criterion or check fails, NOT ASSESSED if nothing was assessed or a
value is missing, PASS only when every one of them holds."""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Dict, List, Mapping, Optional, Sequence

from cosim.limits.assessment import ZONES
from cosim.limits.validity import failures

PASS, FAIL, NOT_ASSESSED = "pass", "fail", "not assessed"
#: a check's status in check.json -> its status here (``error``: a value it covers is missing)
CHECK_STATUS = {"pass": PASS, "fail": FAIL, "error": NOT_ASSESSED}
#: what a limit rests on
STATED, ASSUMED = "stated by the standard", "assumed"
INDICATOR = "indicator (the standard has no such limit on track)"
SCENARIO = "the scenario's (checks:)"
#: a summary column's unit from its name's suffix (longest first)
UNIT_SUFFIXES = (("_m_per_s2", "m/s2"), ("_m_per_s", "m/s"), ("_N", "N"), ("_rad", "rad"), ("_kg", "kg"),
                 ("_Hz", "Hz"), ("_K", "K"), ("_m", "m"), ("_s", "s"))


@dataclass(frozen=True)
class Judged:
    """One value beside its limit. ``table``: where it is shown (``EN 14363``, ``check``, or
    ``run`` for what run.json says); ``name``: the quantity or the check's text; ``op``: how the
    value must stand to the limit (``<=``, ``<``, ``>=``, ``>``); ``counts``: it decides the verdict
    (an EN 14363 indicator does not); ``basis``: what the limit rests on (:data:`STATED`,
    :data:`ASSUMED`, :data:`INDICATOR`, :data:`SCENARIO` ...); ``source``: the limit's formula or
    origin; ``case``: which case (valve setting, k); ``zone``: the test zone, ``where``: the wheel
    (wheelset, floor point) or where a check found its value; ``message``: why an item without a
    value failed (a divergence)."""

    table: str
    name: str
    value: float
    limit: float
    status: str
    counts: bool = True
    op: str = "<="
    unit: str = ""
    basis: str = ""
    source: str = ""
    case: str = ""
    zone: str = ""
    where: str = ""
    message: str = ""

    @property
    def place(self) -> str:
        """The zone and the wheel, as one text."""
        return ", ".join(filter(None, (f"zone {self.zone}" if self.zone else "", self.where)))

    @property
    def lower(self) -> bool:
        """A lower limit: the value must not fall below it."""
        return self.op in (">=", ">")

    @property
    def margin(self) -> float:
        """How far the value is from its limit, positive on the safe side (in the value's unit)."""
        return self.value - self.limit if self.lower else self.limit - self.value

    @property
    def utilisation(self) -> float:
        """1 at the limit, 0 at no load (upper limits), above 1 beyond it; NaN without a value."""
        return 1.0 - self.margin / abs(self.limit) if self.limit else -self.margin


@dataclass(frozen=True)
class Verdict:
    """PASS, FAIL or NOT ASSESSED; ``worst``: the item that decides it (the failing or missing one,
    else the one closest to its limit), ``reason``: why, when no item decides it."""

    status: str
    worst: Optional[Judged]
    counted: int
    failed: int
    reason: str = ""


def number(text) -> float:
    """A CSV or JSON cell as a float (NaN when it holds none)."""
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def unit_of(column: str) -> str:
    """The unit a summary column's name ends in ("" when it names none)."""
    return next((unit for suffix, unit in UNIT_SUFFIXES if column.endswith(suffix)), "")


def case_text(valves, k) -> str:
    """``valves off, k = inf W/K`` of a row's ``valves`` and ``k_W_per_K`` (as CSV text or values)."""
    on = str(valves).lower() in ("true", "on", "1")
    return f"valves {'on' if on else 'off'}, k = {k} W/K"


def outer_rail(info: Mapping) -> Optional[str]:
    """``right`` or ``left``: the outer rail of the run's curve (``direction`` 1, a left-hand
    curve: the right rail); None when the run has no curve (straight track, standing still)."""
    section = info.get("resolved", {}).get(info.get("section") or "", {})
    if not isinstance(section, dict) or section.get("radius_m") in (None, "inf"):
        return None
    return "right" if number(section.get("direction", 1)) >= 0 else "left"


def rail_of(wheel: str, outer: Optional[str]) -> str:
    """`` (outer rail)`` or `` (inner rail)`` for a wheel (``1R``) of a run with a curve, else ""."""
    if outer is None or not re.fullmatch(r"\d[LR]", wheel):
        return ""
    return " (outer rail)" if wheel[-1] == outer[0].upper() else " (inner rail)"


def where_text(at: str, zone: str, outer: Optional[str]) -> str:
    """Who gave an assessed value in ``zone``: a wheel (with its rail where the zone curves), a
    wheelset or a floor point."""
    if re.fullmatch(r"\d[LR]", at):
        return f"wheel {at}{rail_of(at, outer) if zone != 'straight' else ''}"
    return f"wheelset {at}" if at.isdigit() else f"floor above the {at} bogie"


def check_where(at: str, outer: Optional[str]) -> str:
    """A check's ``at`` (``k = inf, valves off, 250<=R<400, wheel 1R``) with the wheel's rail named
    where its zone curves."""
    parts = [p.strip() for p in str(at).split(",")]
    if any(p == "straight" for p in parts) or not any(p in ZONES for p in parts):
        return str(at)
    return re.sub(r"wheel (\d[LR])\b", lambda m: f"wheel {m.group(1)}{rail_of(m.group(1), outer)}", str(at))


def limit_basis(kind: str, source: str) -> str:
    """What an EN 14363 limit rests on: an indicator, an assumed value, or the standard."""
    if kind == "indicator":
        return INDICATOR
    return ASSUMED if "assumed" in source.lower() else STATED


def assessment_items(rows: Sequence[Mapping[str, str]], outer: Optional[str]) -> List[Judged]:
    """The rows of ``assessment_limits.csv``: a missing value (a case that stopped) is not
    assessed, not failed."""
    out = []
    for row in rows:
        value = number(row["value"])
        out.append(Judged("EN 14363", row["quantity"], value, number(row["limit"]),
                          NOT_ASSESSED if math.isnan(value) else row["status"], row["kind"] == "criterion",
                          unit=row["unit"], basis=limit_basis(row["kind"], row["source"]), source=row["source"],
                          case=case_text(row["valves"], row["k_W_per_K"]), zone=row["zone"],
                          where=where_text(row["at"], row["zone"], outer)))
    return out


def _check_basis(metric: str, limit: float, assessed: Sequence[Judged]) -> Optional[Judged]:
    """The assessed item whose limit the check's equals (the same quantity), if any."""
    return next((a for a in assessed if a.name == metric and math.isclose(a.limit, limit, rel_tol=1e-3)), None)


def check_items(check: Mapping, assessed: Sequence[Judged], outer: Optional[str]) -> List[Judged]:
    """The items of ``check.json``: each check (a missing value, status ``error``, is not
    assessed), each validity flag and the run's completion; a check's limit is the scenario's,
    named as the EN 14363 limit it equals where it equals one."""
    out = []
    for c in check.get("checks", []):
        if "value" not in c:
            out.append(Judged("check", c["name"], math.nan, math.nan, c["status"], basis="the run",
                              message=c.get("message", "")))
            continue
        value, limit = number(c["value"]), number(c["limit"])
        same = _check_basis(c["metric"], limit, assessed)
        basis = f"{SCENARIO}; {same.basis}: {same.source}" if same else SCENARIO
        status = NOT_ASSESSED if math.isnan(value) else CHECK_STATUS.get(c["status"], c["status"])
        out.append(Judged("check", c["name"], value, limit, status, op=c.get("op", "<="),
                          unit=same.unit if same else unit_of(c["metric"]), basis=basis,
                          where=check_where(c.get("at", ""), outer), message=c.get("message", "")))
    return out


def run_items(info: Mapping, summary: Sequence[Mapping[str, str]], check: Optional[Mapping]) -> List[Judged]:
    """What run.json and summary.csv say against the run itself, where ``check.json`` does not
    already say it: a run that diverged fails; one that was interrupted is not assessed; a case
    outside the models' validity (not under the scenario's ``allow:``) fails, as ``check`` fails it."""
    named = {c["name"] for c in (check or {}).get("checks", [])}
    out = []
    if info.get("diverged") and "run completes" not in named:
        out.append(Judged("run", "run completes", math.nan, math.nan, FAIL, basis="the run", message=info["diverged"]))
    elif info.get("status", "complete") != "complete":
        out.append(Judged("run", "run completes", math.nan, math.nan, NOT_ASSESSED, basis="the run",
                          message=f"run.json says status {info['status']}: the results end early"))
    allowed = (info.get("settings") or {}).get("allow") or ()
    for failure in failures(list(summary), allowed):
        if f"validity: {failure}" not in named:
            out.append(Judged("run", f"validity: {failure}", math.nan, math.nan, FAIL, basis="the model's validity",
                              message="outside the model's validity"))
    return out


def judged(info: Mapping, summary, limits, check: Optional[Mapping]) -> Dict[str, List[Judged]]:
    """Every item of a run folder, by table: ``EN 14363``, ``check`` and ``run``."""
    outer = outer_rail(info)
    assessed = assessment_items(limits, outer)
    return {"EN 14363": assessed, "check": check_items(check, assessed, outer) if check else [],
            "run": run_items(info, summary, check)}


#: how bad a status is: the worst item of a set is a failing one, then a missing one
SEVERITY = {PASS: 0, NOT_ASSESSED: 1, FAIL: 2}


def worst_of(items: Sequence[Judged]) -> Judged:
    """The item that says most against the set: a failing one before a missing one before a
    passing one; among them the one furthest beyond (nearest to) its limit, one without a value
    (a divergence) first."""
    return max(items, key=lambda i: (SEVERITY[i.status], math.inf if math.isnan(i.utilisation) else i.utilisation))


def verdict(items: Sequence[Judged]) -> Verdict:
    """PASS only when every item that counts holds; FAIL when one fails; NOT ASSESSED when none
    counts or one has no value (and none fails). ``worst``: :func:`worst_of` the counted items."""
    counted = [i for i in items if i.counts]
    if not counted:
        return Verdict("NOT ASSESSED", None, 0, 0, "nothing was assessed: no EN 14363 assessment (made for curve "
                                                   "runs) and no checks (pneumorail check evaluates the scenario's "
                                                   "checks:)")
    worst = worst_of(counted)
    failed = sum(i.status == FAIL for i in counted)
    status = {FAIL: "FAIL", NOT_ASSESSED: "NOT ASSESSED", PASS: "PASS"}[worst.status]
    return Verdict(status, worst, len(counted), failed, "a value is missing" if worst.status == NOT_ASSESSED else "")
