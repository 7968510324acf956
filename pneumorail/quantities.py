"""The allowed values of a number a user writes, declared next to the field that holds it.

A parameter dataclass of any package states the physically plausible range of each of its numbers
as field metadata::

    carbody_mass_kg: float = field(default=17000.0, metadata=plausible(2e3, 1.5e5, "kg", "a carbody"))

so that the range lives with the field, its default and its comment. The application
(``cosim.scenario.schema``) reads it back (:func:`range_of_field`) to check what a scenario gives,
and names the field, the range, its reason and a likely unit slip (tonnes for kg, bar for Pa)
when a value falls outside. The physics packages cannot import the application, so the
:class:`Range` type lives here, importing nothing of theirs.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Dict, NamedTuple, Optional, Tuple

#: field metadata key of a number's :class:`Range` (each item's, for a list)
RANGE = "pneumorail.range"
#: field metadata key of a list's rules: (must be non-empty, must hold no duplicates)
LIST_RULE = "pneumorail.list"


class Range(NamedTuple):
    """Allowed values of a number: ``low``/``high`` bounds (None: unbounded), each inclusive or
    not; ``nonzero`` excludes 0; ``unit`` and ``why`` complete the message."""

    low: Optional[float] = None
    high: Optional[float] = None
    low_inclusive: bool = True
    high_inclusive: bool = True
    unit: str = ""
    why: str = ""
    nonzero: bool = False
    #: 0 (an absent component) and inf (a rigid one) allowed besides the bounds
    zero_or_inf: bool = False
    #: +inf allowed besides the bounds: a limit the model computes exactly (k = inf, isothermal)
    infinite: bool = False

    def admits(self, v: float) -> bool:
        if self.zero_or_inf and (v == 0 or v == math.inf):
            return True
        if self.infinite and v == math.inf:
            return True
        if self.nonzero and v == 0:
            return False
        if self.low is not None and not (v >= self.low if self.low_inclusive else v > self.low):
            return False
        if self.high is not None and not (v <= self.high if self.high_inclusive else v < self.high):
            return False
        return True

    def expected(self, integer: bool = False) -> str:
        """What the range allows, for messages: ``in [2000, 150000] kg (a carbody)``."""
        u = f" {self.unit}" if self.unit else ""
        a = "an integer" if integer else ""
        if self.low is not None and self.high is not None:
            lo, hi = ("[" if self.low_inclusive else "("), ("]" if self.high_inclusive else ")")
            text = f"{a} in {lo}{number_text(self.low)}, {number_text(self.high)}{hi}{u}"
        elif self.low is not None:
            text = f"{a} {'>=' if self.low_inclusive else '>'} {number_text(self.low)}{u}"
        elif self.high is not None:
            text = f"{a} {'<=' if self.high_inclusive else '<'} {number_text(self.high)}{u}"
        else:
            text = a or "a number"
        if self.nonzero:
            text += f" other than 0{u}"
        if self.zero_or_inf:
            text = f"0 (none), inf (rigid) or{text}"
        if self.infinite:
            text += " or .inf"
        text = text.strip()
        return text + (f" ({self.why})" if self.why else "")


def number_text(v) -> str:
    """A bound or a value for messages: 1000000, not 1e+06; 0.005, 1e-08."""
    if isinstance(v, int) or (isinstance(v, float) and v.is_integer() and abs(v) < 1e7):
        return str(int(v))
    return f"{v:g}"


def positive(unit: str = "", why: str = "") -> Range:
    """A quantity that only makes sense > 0 (a volume, a mass, a duration)."""
    return Range(0.0, None, False, True, unit, why)


def nonnegative(unit: str = "", why: str = "") -> Range:
    """A quantity >= 0 (0: none)."""
    return Range(0.0, None, True, True, unit, why)


def ranged(rule: Optional[Range] = None, *, non_empty: bool = False, unique: bool = False) -> Dict[str, object]:
    """Field metadata: ``rule`` for the number (for a list: for each item), and for a list whether
    it must be non-empty and free of duplicates."""
    meta: Dict[str, object] = {}
    if rule is not None:
        meta[RANGE] = rule
    if non_empty or unique:
        meta[LIST_RULE] = (non_empty, unique)
    return meta


def plausible(low: Optional[float], high: Optional[float], unit: str = "", why: str = "", *,
              low_inclusive: bool = True, high_inclusive: bool = True, nonzero: bool = False,
              zero_or_inf: bool = False, infinite: bool = False, non_empty: bool = False,
              unique: bool = False) -> Dict[str, object]:
    """Field metadata of the range [``low``, ``high``] ``unit`` (``why``: what the bounds rest on),
    see :class:`Range` and :func:`ranged`."""
    return ranged(Range(low, high, low_inclusive, high_inclusive, unit, why, nonzero, zero_or_inf, infinite),
                  non_empty=non_empty, unique=unique)


def range_of_field(f: dataclasses.Field) -> Optional[Range]:
    """The range field ``f`` declares (None: none)."""
    return f.metadata.get(RANGE)


def list_rule_of_field(f: dataclasses.Field) -> Optional[Tuple[bool, bool]]:
    """(non-empty, no duplicates) of list field ``f`` (None: no rule)."""
    return f.metadata.get(LIST_RULE)


__all__ = ["RANGE", "LIST_RULE", "Range", "number_text", "positive", "nonnegative", "ranged", "plausible",
           "range_of_field", "list_rule_of_field"]
