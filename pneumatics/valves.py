"""Levelling, safety and differential pressure valves (paper §2.3, Fig. 2).

Valve characteristics are tables, linearly interpolated and held constant beyond their ends.
The default values are assumptions (the paper shows the curves only qualitatively); each is
explained where it is defined.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Tuple

import numpy as np

#: Sonic conductance of a fully open levelling valve [m^3/(s Pa)]. Assumed: a large railway
#: levelling valve passes about 1000 l/min ANR, ~0.02 kg/s choked from a 9 bar reservoir, i.e.
#: C ~ 2e-8; half of that is taken, for a valve whose lever is not fully deflected in normal service.
LEVELLING_C_MAX = 1.0e-8


@dataclass(frozen=True)
class LevellingValve:
    """A lever-operated valve that inflates ``bellow`` from ``supply`` or deflates it to ``exhaust``.

    Lever displacement u = ``lever_gain`` x (mean crushing of the ``sensed`` bellows; default: the
    controlled bellow itself). Crushing is positive in compression, so a compressed (too low)
    bellow (u > 0) opens the supply side with conductance C_supply(u), an extended one (u < 0) the
    exhaust side with C_exhaust(-u). Tables start with a dead band of zero conductance (Fig. 2a).
    Defaults: 5 mm dead band, full opening at 25 mm (assumed, typical of railway levelling valves);
    b = 0.4 (assumed, a typical ISO 6358 critical ratio of a spool valve).
    """

    bellow: str
    supply: str = "supply"
    exhaust: str = "atmosphere"
    sensed: Tuple[str, ...] = ()
    lever_gain: float = 1.0
    supply_lever_m: Tuple[float, ...] = (0.0, 0.005, 0.025)
    supply_C_m3_per_sPa: Tuple[float, ...] = (0.0, 0.0, LEVELLING_C_MAX)
    exhaust_lever_m: Tuple[float, ...] = (0.0, 0.005, 0.025)
    exhaust_C_m3_per_sPa: Tuple[float, ...] = (0.0, 0.0, LEVELLING_C_MAX)
    b_critical: float = 0.4

    @property
    def sensed_bellows(self) -> Tuple[str, ...]:
        return self.sensed or (self.bellow,)


@dataclass(frozen=True)
class SafetyValve(LevellingValve):
    """A lever valve of the same form that only vents a grossly over-extended bellow.

    Defaults (assumed): the supply side never opens; the exhaust side opens beyond 60 mm of
    extension and is fully open at 80 mm.
    """

    supply: str = "atmosphere"
    supply_lever_m: Tuple[float, ...] = (0.0, 1.0)
    supply_C_m3_per_sPa: Tuple[float, ...] = (0.0, 0.0)
    exhaust_lever_m: Tuple[float, ...] = (0.0, 0.060, 0.080)
    exhaust_C_m3_per_sPa: Tuple[float, ...] = (0.0, 0.0, 2.0 * LEVELLING_C_MAX)


@dataclass(frozen=True)
class DifferentialPressureValve:
    """Transfers air from the higher- to the lower-pressure of two bellows (four-point circuits).

    Mass flow is a tabulated function of |p_a - p_b| (Fig. 2b), directed from high to low
    pressure, so the valve is antisymmetric. Defaults (assumed): closed below 1.5 bar, the usual
    setting of railway differential valves, rising to 0.02 kg/s at 2.5 bar.
    """

    a: str
    b: str
    dp_Pa: Tuple[float, ...] = (0.0, 1.5e5, 2.5e5)
    q_kg_per_s: Tuple[float, ...] = (0.0, 0.0, 0.02)


def lever_conductance(lever_m, table_lever_m, table_C):
    """Sonic conductance at lever displacement ``lever_m``: > 0 may open this side (beyond the
    table's dead band); <= 0 keeps it shut."""
    return np.interp(np.maximum(lever_m, 0.0), table_lever_m, table_C) * (lever_m > 0.0)


def differential_valve_flow_kg_per_s(p_a_Pa, p_b_Pa, table_dp_Pa, table_q):
    """Signed flow from a to b: sign(p_a - p_b) q(|p_a - p_b|); antisymmetric by construction."""
    dp = p_a_Pa - p_b_Pa
    return np.sign(dp) * np.interp(np.abs(dp), table_dp_Pa, table_q)
