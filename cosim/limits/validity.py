"""Validity flags: results the models cannot vouch for.

A run can finish and still leave the range its models hold in. Each summary row gets a
``validity`` column (``ok``, or the names of the flags it raises, ``;``-separated), the outcome a
warning per flag, the figures a note in their title, and ``pneumorail check`` fails on a flagged
case unless the scenario lists the flag under ``allow:``.

Flags (:data:`FLAGS`):

* ``pipe_mach``: the pipe flow's Mach number exceeds :data:`PIPE_MACH_MAX` somewhere in the run:
  the pipe law (eq. 5) is incompressible, its error grows as Ma^2 (about 2 % density change at
  0.2, 5 % at 0.3; the usual incompressible-flow bound).
* ``temperature``: a bellow's air leaves :data:`T_RANGE_K`: the constant-heat-capacity ideal gas
  and the heat-exchange law hold over ordinary temperatures, and rubber bellows are rated for
  about -40 ... +70 degC; a few hundred kelvin beyond is a thermal runaway, not a suspension state
  (the 15 Hz k = 1 rig reaches 23 000 K).
* ``unstabilised``: a periodic run did not reach its steady state (its summary values are not
  those of the periodic regime).
"""
from __future__ import annotations

import math
from typing import Dict, List, Mapping

#: largest pipe Mach number for which the incompressible pipe law (eq. 5) is trusted
PIPE_MACH_MAX = 0.3
#: plausible range of the air temperature in a bellow [K] (-73 ... +127 degC)
T_RANGE_K = (200.0, 400.0)

FLAGS = {"pipe_mach": f"pipe flow above Mach {PIPE_MACH_MAX} (the incompressible pipe law, eq. 5, no longer holds)",
         "temperature": f"bellow air temperature outside {T_RANGE_K[0]:g} ... {T_RANGE_K[1]:g} K",
         "unstabilised": "the periodic steady state was not reached"}


def _above(row: Mapping[str, object], key: str, limit: float) -> bool:
    value = row.get(key)
    return isinstance(value, (int, float)) and not isinstance(value, bool) and not math.isnan(value) and value > limit


def _below(row: Mapping[str, object], key: str, limit: float) -> bool:
    value = row.get(key)
    return isinstance(value, (int, float)) and not isinstance(value, bool) and not math.isnan(value) and value < limit


def row_flags(row: Mapping[str, object]) -> List[str]:
    """The flags a summary row raises, from its columns ``pipe_mach_max``, ``T_bellow_max_K`` /
    ``T_bellow_min_K`` and ``stabilised`` (a column it lacks raises nothing)."""
    flags = []
    if _above(row, "pipe_mach_max", PIPE_MACH_MAX):
        flags.append("pipe_mach")
    if _above(row, "T_bellow_max_K", T_RANGE_K[1]) or _below(row, "T_bellow_min_K", T_RANGE_K[0]):
        flags.append("temperature")
    if row.get("stabilised") is False:
        flags.append("unstabilised")
    return flags


def flag_rows(rows: List[Dict[str, object]]) -> Dict[str, int]:
    """Add the ``validity`` column to every row; returns how many rows raise each flag."""
    counts: Dict[str, int] = {}
    for row in rows:
        flags = row_flags(row)
        row["validity"] = ";".join(flags) or "ok"
        for f in flags:
            counts[f] = counts.get(f, 0) + 1
    return counts


def case_label(row: Mapping[str, object]) -> str:
    """``configuration bellow_tank, k = 1, 15 Hz`` ...: which case a summary row is."""
    from cosim.scenario.schema import k_label
    parts = []
    if "configuration" in row:
        parts.append(str(row["configuration"]))
    if "valves" in row:                      # a bool, or its text as read back from summary.csv
        parts.append(f"valves {'on' if row['valves'] in (True, 'True', 'true') else 'off'}")
    if "k_W_per_K" in row:
        parts.append(f"k = {k_label(float(row['k_W_per_K']))}")
    if "frequency_Hz" in row:
        parts.append(f"{float(row['frequency_Hz']):g} Hz")
    return ", ".join(parts) or "the run"


def warnings_for(rows: List[Mapping[str, object]]) -> List[str]:
    """One line per flag raised: what it means and which cases raise it (the first few)."""
    out = []
    for flag, meaning in FLAGS.items():
        cases = [case_label(r) for r in rows if flag in str(r.get("validity", "")).split(";")]
        if cases:
            shown = "; ".join(cases[:4]) + (f"; and {len(cases) - 4} more" if len(cases) > 4 else "")
            out.append(f"outside the model's validity in {len(cases)} of {len(rows)} cases ({flag}): {meaning}: "
                       f"{shown}")
    return out


def failures(rows: List[Mapping[str, object]], allowed=()) -> List[str]:
    """``case: flag`` for every flag a row raises that is not ``allowed``."""
    return [f"{case_label(r)}: {flag}" for r in rows for flag in str(r.get("validity", "ok")).split(";")
            if flag not in ("ok", "") and flag not in allowed]
