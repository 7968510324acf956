"""Faults of the air system: what breaks, where and when (issue "When the air fails").

A :class:`Fault` names a component of the circuit by its name, the kind of failure and the time
it happens. The circuit (:class:`pneumatics.circuit.Circuit`) compiles every fault it is given
from the start, inactive, so that its state vector does not change when one happens; the
co-simulation switches to ``circuit.with_active_faults(...)`` at each fault's time.

=================  =====================  ======================================================
kind               component              law once it has happened
=================  =====================  ======================================================
``burst``          bellow, tank, finite   an orifice to the atmosphere opens: ISO 6358 flow
``leak``           supply (a chamber)     (eqs 6-7) through ``C_m3_per_sPa``, or through an
                                          ideal nozzle of effective area ``area_m2``
                                          (:func:`nozzle_conductance`); the two kinds differ
                                          only in name
``blocked``        pipe, orifice          no flow through it
``ruptured``       pipe                   severed: no flow through it, and each of its ends
                                          that is a chamber vents to the atmosphere through the
                                          pipe's bore (or ``area_m2`` / ``C_m3_per_sPa``)
``stuck_closed``   levelling or safety    both sides shut, whatever the lever
                   valve
``stuck_open``     levelling or safety    the side ``side`` (supply or exhaust) fully open (its
                   valve                  table's last conductance), the other shut
``stuck_at``       levelling or safety    the valve acts on the lever displacement ``lever_m``
                   valve                  (+ opens the supply side) whatever the bellow height
``stuck_closed``   differential valve     no flow
``stuck_open``     differential valve     open at any pressure difference: its flow table with
                                          the dead band removed, q(|dp|) = table(|dp| + dp_0),
                                          dp_0 the largest difference at which it passes nothing
``supply_lost``    supply                 isolated: no flow through any link that touches it
=================  =====================  ======================================================

Air that leaves through a fault's opening is counted apart from the air the valves exhaust
(:meth:`Circuit.air_lost_kg`), so the mass balance of the circuit reads

    m(t) - m(0) = supplied - exhausted - lost     (every term cumulative, kg).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

from pneumorail.quantities import nonnegative, plausible, ranged

from .gas import AIR, T_REF_K, Gas
from .orifice import CRITICAL_RATIO

#: fault kind -> what it needs besides the component and the time
FAULT_KINDS = ("burst", "leak", "blocked", "ruptured", "stuck_closed", "stuck_open", "stuck_at", "supply_lost")
VALVE_SIDES = ("supply", "exhaust")


@dataclass(frozen=True)
class Fault:
    """A failure of one component of the circuit at time ``t_s``.

    ``area_m2``: effective flow area of the opening (geometric area times its discharge
    coefficient, ~0.6 for a sharp-edged hole) of a ``burst``, ``leak`` or ``ruptured`` pipe;
    or ``C_m3_per_sPa``, its ISO 6358 sonic conductance (with ``b_critical``). ``side``: which
    side of a levelling valve is ``stuck_open``; ``lever_m``: the lever displacement a valve is
    ``stuck_at``.
    """

    kind: str
    component: str
    t_s: float = field(default=0.0, metadata=ranged(nonnegative("s", "when the fault happens; 0: from the start")))
    area_m2: Optional[float] = field(default=None, metadata=plausible(
        0.0, 0.1, "m^2", "an opening's effective area (a bellow's is ~0.13 m^2)", low_inclusive=False))
    C_m3_per_sPa: Optional[float] = field(default=None, metadata=plausible(
        0.0, 1e-4, "m^3/(s Pa)", "an ISO 6358 sonic conductance", low_inclusive=False))
    b_critical: Optional[float] = field(default=None, metadata=ranged(CRITICAL_RATIO))
    side: Optional[str] = None
    lever_m: Optional[float] = field(default=None, metadata=plausible(
        -0.2, 0.2, "m", "a levelling valve's lever displacement (+ opens the supply side)"))

    def label(self) -> str:
        """A short description for summary rows and figure titles: ``FL burst 1 cm² at 2 s``."""
        detail = ""
        if self.area_m2 is not None:
            detail = f" {self.area_m2 * 1e4:.3g} cm²"
        elif self.C_m3_per_sPa is not None:
            detail = f" C {self.C_m3_per_sPa:.3g} m³/(s Pa)"
        if self.side is not None:
            detail += f" ({self.side})"
        if self.lever_m is not None:
            detail += f" at lever {self.lever_m * 1e3:.3g} mm"
        return f"{self.component} {self.kind.replace('_', ' ')}{detail} at {self.t_s:g} s"


def nozzle_conductance(area_m2: float, gas: Gas = AIR) -> tuple[float, float]:
    """(C [m^3/(s Pa)], b) of an ideal convergent nozzle of throat area ``area_m2`` in ISO 6358
    terms: the choked isentropic mass flow A p1 sqrt(gamma / (R T1)) (2/(gamma+1))^((gamma+1)/
    (2(gamma-1))) equals C p1 rho_ref sqrt(T_ref / T1) (eq. 6), and b is the nozzle's critical
    pressure ratio (2/(gamma+1))^(gamma/(gamma-1)) (0.528 for air). For air C = 1.99e-3 A, the
    familiar "C [dm^3/(s bar)] ~ 0.2 A [mm^2]"."""
    g = gas.gamma
    choked = math.sqrt(g / gas.R_J_per_kgK) * (2.0 / (g + 1.0)) ** ((g + 1.0) / (2.0 * (g - 1.0)))
    C = area_m2 * choked / (gas.rho_ref_kg_per_m3 * math.sqrt(T_REF_K))
    return C, (2.0 / (g + 1.0)) ** (g / (g - 1.0))
