"""ISO 6358 orifice flow (paper §2.3, eqs 6-7) in either direction."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from pneumorail.quantities import Range, ranged

from .compiled import elementwise, scalar
from .gas import AIR, T_REF_K, Gas

#: Below this relative pressure difference 1 - p2/p1 the subsonic law (slope -> infinity at
#: p2 = p1) is replaced by its chord to zero: linear ("laminar") in the pressure difference,
#: continuous at the threshold. It keeps the flow Lipschitz for the integrator; like ISO 6358-3's
#: laminar region, it changes the flow only within 0.1 % of pressure equality.
LAMINAR_RATIO = 1e-3


#: the range of an ISO 6358 critical pressure ratio b (field metadata): a pressure ratio below 1
CRITICAL_RATIO = Range(0.0, 1.0, True, False, why="ISO 6358 critical pressure ratio")


@dataclass(frozen=True)
class Orifice:
    """A fixed restriction between two nodes: sonic conductance C [m^3/(s Pa)] and critical ratio b."""

    a: str
    b: str
    C_m3_per_sPa: float
    b_critical: float = field(default=0.5, metadata=ranged(CRITICAL_RATIO))


@scalar
def _iso6358(C, b, p_up_Pa, T_up_K, p_down_Pa, rho_ref_kg_per_m3):
    """Eqs (6)-(7) for one orifice (see :func:`iso6358_mass_flow_kg_per_s`)."""
    ratio = np.minimum(p_down_Pa / p_up_Pa, 1.0)
    choked = C * p_up_Pa * rho_ref_kg_per_m3 * math.sqrt(T_REF_K / T_up_K)
    r_lam = 1.0 - LAMINAR_RATIO
    r_sub = np.minimum(ratio, r_lam)
    x = (np.maximum(r_sub, b) - b) / (1.0 - b)
    factor = math.sqrt(np.maximum(1.0 - x * x, 0.0))
    # In the laminar band scale the value at the band edge linearly down to 0 at ratio 1.
    if ratio > r_lam:
        factor = factor * (1.0 - ratio) / LAMINAR_RATIO
    return choked * factor


@elementwise(6)
def _iso6358_flow(C, b, p_up_Pa, T_up_K, p_down_Pa, rho_ref_kg_per_m3):
    return _iso6358(C, b, p_up_Pa, T_up_K, p_down_Pa, rho_ref_kg_per_m3)


@elementwise(7)
def _signed_flow(C, b, p_a_Pa, T_a_K, p_b_Pa, T_b_K, rho_ref_kg_per_m3):
    if p_a_Pa >= p_b_Pa:
        return _iso6358(C, b, p_a_Pa, T_a_K, p_b_Pa, rho_ref_kg_per_m3)
    return -_iso6358(C, b, p_b_Pa, T_b_K, p_a_Pa, rho_ref_kg_per_m3)


def iso6358_mass_flow_kg_per_s(C, b, p_up_Pa, T_up_K, p_down_Pa, gas: Gas = AIR):
    """Mass flow from upstream (p_up >= p_down) to downstream, eqs (6)-(7).

    Choked (p2/p1 <= b): q = C p1 rho_ref sqrt(T_ref/T1); subsonic: times
    sqrt(1 - ((p2/p1 - b)/(1 - b))^2); zero at equal pressures (with the laminar rounding
    described at LAMINAR_RATIO). Arrays broadcast (compiled, :mod:`pneumatics.compiled`).
    """
    return _iso6358_flow(C, b, p_up_Pa, T_up_K, p_down_Pa, gas.rho_ref_kg_per_m3)


def orifice_flow_kg_per_s(C, b, p_a_Pa, T_a_K, p_b_Pa, T_b_K, gas: Gas = AIR):
    """Signed ISO 6358 flow from node a to node b (negative when b is upstream); the upstream
    node's temperature. Arrays broadcast (compiled, :mod:`pneumatics.compiled`)."""
    return _signed_flow(C, b, p_a_Pa, T_a_K, p_b_Pa, T_b_K, gas.rho_ref_kg_per_m3)
