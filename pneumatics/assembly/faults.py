"""The faults (:mod:`pneumatics.faults`) compiled into the circuit: each checked against the
component it names; the openings to the atmosphere they make (links of their own, shut while
the fault is inactive); what the active ones change besides (links that carry nothing, the
levers of stuck valves)."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Dict, Mapping, NamedTuple, Optional, Sequence, Tuple

import numpy as np

from ..boundary import Supply
from ..chamber import Bellow, Tank
from ..errors import CircuitError
from ..faults import FAULT_KINDS, VALVE_SIDES, Fault, nozzle_conductance
from ..gas import Gas
from ..orifice import Orifice
from ..pipe import Pipe
from ..valves import DifferentialPressureValve, LevellingValve
from .arrays import column, read_only
from .components import TYPE_WORDS, type_word

#: fault kind -> (component types it applies to, fields it takes besides kind, component, t_s)
FAULT_RULES = {
    "burst": ((Bellow, Tank, Supply), ("area_m2", "C_m3_per_sPa", "b_critical")),
    "leak": ((Bellow, Tank, Supply), ("area_m2", "C_m3_per_sPa", "b_critical")),
    "blocked": ((Pipe, Orifice), ()),
    "ruptured": ((Pipe,), ("area_m2", "C_m3_per_sPa", "b_critical")),
    "stuck_closed": ((LevellingValve, DifferentialPressureValve), ()),
    "stuck_open": ((LevellingValve, DifferentialPressureValve), ("side",)),
    "stuck_at": ((LevellingValve,), ("lever_m",)),
    "supply_lost": ((Supply,), ()),
}


def without_dead_band(valve: DifferentialPressureValve) -> DifferentialPressureValve:
    """A differential valve stuck open: its flow table shifted so that it opens at dp = 0, the
    flow it passed at dp_0 + dp now passing at dp (dp_0: the last table point of zero flow)."""
    dp, q = np.asarray(valve.dp_Pa, float), np.asarray(valve.q_kg_per_s, float)
    if q[0] > 0 or not np.any(q > 0):         # no dead band to remove (or a valve that never passes air)
        return valve
    last_shut = int(np.flatnonzero(q > 0)[0]) - 1
    return dataclasses.replace(valve, dp_Pa=tuple(dp[last_shut:] - dp[last_shut]), q_kg_per_s=tuple(q[last_shut:]))


def check_faults(faults: Sequence[Fault], active: frozenset, components: Mapping[str, object],
                 chamber_names: Sequence[str]) -> Dict[str, object]:
    """Every fault names a component of the right type, with the fields its kind needs (and no
    other), each in range. Returns the components as the circuit compiles them: an active
    stuck-open differential valve's table without its dead band (:mod:`pneumatics.faults`)."""
    compiled = dict(components)
    chambers = set(chamber_names)
    for i, f in enumerate(faults):
        where = f"faults[{i}]"
        if f.kind not in FAULT_KINDS:
            raise CircuitError([where, "kind"], f"unknown fault kind {f.kind!r} (expected one of {', '.join(FAULT_KINDS)})")
        comp = compiled.get(f.component)
        if comp is None:
            known = ", ".join(compiled)
            raise CircuitError([where, "component"], f"{f.component!r} is not a component of the circuit "
                                                     f"(components: {known})")
        allowed, needs = FAULT_RULES[f.kind]
        if not (isinstance(comp, allowed) and (f.kind not in ("burst", "leak") or f.component in chambers)):
            what = "a chamber (bellow, tank or finite supply)" if f.kind in ("burst", "leak") else \
                " or ".join(TYPE_WORDS[t] for t in allowed)
            raise CircuitError([where, "component"], f"a {f.kind} fault needs {what}; {f.component!r} is a "
                                                     f"{type_word(comp)}")
        if not (math.isfinite(f.t_s) and f.t_s >= 0.0):
            raise CircuitError([where, "t_s"], f"must be a finite time >= 0 s, got {f.t_s}")
        if isinstance(comp, DifferentialPressureValve):
            needs = ()                               # a differential valve has no sides or lever
        for field in ("area_m2", "C_m3_per_sPa", "b_critical", "side", "lever_m"):
            value = getattr(f, field)
            if value is not None and field not in needs:
                raise CircuitError([where, field], f"is not used by a {f.kind} fault of a {type_word(comp)}")
        _check_fault_values(f, where, comp)
        if f.kind == "stuck_open" and isinstance(comp, DifferentialPressureValve) and i in active:
            compiled[f.component] = without_dead_band(comp)
    return compiled


def _check_fault_values(f: Fault, where: str, comp) -> None:
    for field in ("area_m2", "C_m3_per_sPa"):
        value = getattr(f, field)
        if value is not None and not (math.isfinite(value) and value > 0.0):
            raise CircuitError([where, field], f"must be a finite number > 0, got {value}")
    if f.kind in ("burst", "leak") and (f.area_m2 is None) == (f.C_m3_per_sPa is None):
        raise CircuitError([where, "area_m2"], "give the opening's effective area (area_m2) or its sonic "
                                               "conductance (C_m3_per_sPa), one of them")
    if f.area_m2 is not None and f.C_m3_per_sPa is not None:
        raise CircuitError([where, "C_m3_per_sPa"], "give area_m2 or C_m3_per_sPa, not both")
    if f.b_critical is not None:
        if f.C_m3_per_sPa is None:
            raise CircuitError([where, "b_critical"], "goes with C_m3_per_sPa (an area is an ideal nozzle, b = 0.528)")
        if not 0.0 <= f.b_critical < 1.0:
            raise CircuitError([where, "b_critical"], f"must be in [0, 1), got {f.b_critical}")
    if f.kind == "stuck_open" and isinstance(comp, LevellingValve) and f.side not in VALVE_SIDES:
        raise CircuitError([where, "side"], f"which side is stuck open: expected one of {', '.join(VALVE_SIDES)}, "
                                            f"got {f.side!r}")
    if f.kind == "stuck_at" and not (f.lever_m is not None and math.isfinite(f.lever_m)):
        raise CircuitError([where, "lever_m"], f"the lever displacement the valve is stuck at [m] (+ opens the "
                                               f"supply side), a finite number; got {f.lever_m}")


class Opening(NamedTuple):
    """An opening to the atmosphere that a fault makes: its link's name, the fault's index, the
    chamber it vents, its sonic conductance and critical ratio (ISO 6358, eqs 6-7), and whether
    the fault has happened (else the opening is shut)."""

    link: str
    fault: int
    node: str
    C_m3_per_sPa: float
    b_critical: float
    active: bool


def fault_openings(faults: Sequence[Fault], active: frozenset, components: Mapping[str, object],
                   chamber_names: Sequence[str], gas: Gas) -> Tuple[Opening, ...]:
    """The openings to the atmosphere the faults make: a burst or leak at its chamber
    (``<component>.<kind>``), a ruptured pipe at each end that is a chamber
    (``<pipe>.ruptured@<end>``); a second opening of the same name gets the fault's index."""
    out = []
    for i, f in enumerate(faults):
        if f.kind in ("burst", "leak"):
            out.append((f"{f.component}.{f.kind}", i, f.component, *_opening(f, None, gas)))
        elif f.kind == "ruptured":
            pipe = components[f.component]
            for end in dict.fromkeys((pipe.a, pipe.b)):
                if end in chamber_names:
                    out.append((f"{f.component}.ruptured@{end}", i, end, *_opening(f, pipe.area_m2, gas)))
    names = [o[0] for o in out]
    return tuple(Opening(name if names.count(name) == 1 else f"{name}[{i}]", i, *rest, i in active)
                 for name, i, *rest in out)


def _opening(f: Fault, bore_m2: Optional[float], gas: Gas) -> Tuple[float, float]:
    """(C, b) of a fault's opening: its conductance, its area's ideal nozzle, or the bore's."""
    if f.C_m3_per_sPa is not None:
        return f.C_m3_per_sPa, (0.5 if f.b_critical is None else f.b_critical)
    return nozzle_conductance(f.area_m2 if f.area_m2 is not None else bore_m2, gas)


@dataclass(frozen=True, eq=False)
class ActiveFaults:
    """What the active faults change besides their openings: the links that carry nothing (None:
    none), the dynamic pipes among them (their air column stands still), the stuck valves (their
    rows among the valves) and the levers they are stuck at (stuck valves, 1)."""

    blocked_links: Optional[np.ndarray]
    blocked_pipes: Optional[np.ndarray]
    stuck_valves: Optional[np.ndarray]
    stuck_lever_m: np.ndarray


def compile_active_faults(faults: Sequence[Fault], active: frozenset, components: Mapping[str, object],
                          link_names: Sequence[str], link_a: np.ndarray, link_b: np.ndarray, fault_links: slice,
                          node_index: Mapping[str, int], valve_names: Sequence[str], n_pipes: int) -> ActiveFaults:
    """Links that carry nothing (blocked, ruptured, a shut differential valve, every link of a
    lost supply but the faults' own openings), the pipe states that stop with them, and the
    levers of stuck valves; the latest fault on a valve wins."""
    blocked, stuck = [], {}
    openings = set(range(fault_links.start, fault_links.stop))
    for i in sorted(active, key=lambda i: (faults[i].t_s, i)):   # the latest fault wins
        f = faults[i]
        if f.kind in ("blocked", "ruptured") or (f.kind == "stuck_closed" and f.component in link_names):
            blocked.append(link_names.index(f.component))
        elif f.kind == "supply_lost":                  # every link but a fault's own opening
            node = node_index[f.component]
            blocked += [j for j in range(len(link_names)) if node in (link_a[j], link_b[j]) and j not in openings]
        elif isinstance(components[f.component], LevellingValve):   # stuck closed, open or at
            stuck[valve_names.index(f.component)] = _stuck_lever_m(f, components[f.component])
    blocked = sorted(set(blocked))
    pipes = [j for j in blocked if j < n_pipes]
    return ActiveFaults(read_only(np.array(blocked, dtype=int)) if blocked else None,
                        read_only(np.array(pipes, dtype=int)) if pipes else None,
                        read_only(np.array(list(stuck), dtype=int)) if stuck else None, column(list(stuck.values())))


def _stuck_lever_m(f: Fault, valve: LevellingValve) -> float:
    """The lever displacement a stuck levelling valve acts on."""
    if f.kind == "stuck_at":
        return f.lever_m
    if f.kind == "stuck_closed":
        return 0.0                                 # inside the dead band: both sides shut
    return max(valve.supply_lever_m) if f.side == "supply" else -max(valve.exhaust_lever_m)  # the side's table end
