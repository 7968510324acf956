"""The air supply beyond the suspension: a compressor that fills the main reservoir under a
pressure governor, and the other consumers (brakes, doors) as a steady demand.

Sign convention as everywhere in the circuit: a link's mass flow w is positive from its ``a`` node
to its ``b`` node. A compressor is a link from its intake (a boundary node named after it, at the
atmosphere's pressure and the delivery temperature) into its ``reservoir`` (a chamber: a finite
``supply`` or a tank); a demand is a link from its ``node`` to its exhaust (a boundary node named
after it, at the atmosphere's conditions).

Compressor (free air delivery, ISO 1217: the volume flow the compressor takes in, at the intake's
conditions)::

    w_c = s rho_free FAD,      rho_free = p_atm / (R T_atm)

with s the governor's state (1 running, 0 stopped): a relay with hysteresis on the reservoir's
pressure p_r, ``p_cut_in_Pa`` < ``p_cut_out_Pa``::

    s -> 1 when p_r <= p_cut_in,   s -> 0 when p_r >= p_cut_out,   s held in between.

The governor is a discrete state: it switches between the integrator's fixed steps
(:meth:`pneumatics.runtime.CircuitRuntime.update_governors`), at the end of the step in which
the pressure crossed its threshold. The reservoir overshoots the cut-out by up to one step's
filling, (w_c - w_d) h, which the off phase takes (w_c - w_d) h / w_d longer to draw: the
period is O(h) off, by at most h (2 + w_d / (w_c - w_d) + (w_c - w_d) / w_d) (0.17 s of a
147 s cycle at h = 10 ms; the co-simulation's pneumatic step is ~1 ms). The compressed air
arrives after the aftercooler at ``T_delivery_K`` (None: the atmosphere's temperature,
assumed).

Energy of compression: the work to bring the delivered air from the intake (p_atm, T_atm) to the
reservoir's pressure p_r, bounded below by the isothermal compression and above by the one-stage
adiabatic (isentropic) one, per kg::

    w_iso = R T_atm ln(p_r / p_atm),   w_ad = c_p T_atm ((p_r / p_atm)^((gamma - 1) / gamma) - 1)

integrated over what the compressor delivers (a real compressor's shaft work lies between, over
its efficiency; intercooled stages bring it towards the isothermal bound).

Demand (normal volume flow, DIN 1343: 273.15 K, 101 325 Pa)::

    w_d = rho_N Q_N ramp((p - p_atm) / dp_off),   rho_N = 101325 / (R 273.15),
    ramp(x) = min(1, max(0, x))

a consumer drawing its air at a steady rate as long as the node holds it: below ``dp_off_Pa``
above the atmosphere the draw fades to nothing instead of emptying the node into a vacuum (a
model choice: brake and door equipment stop taking air as their supply pressure fails).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional, Tuple

import numpy as np

from pneumorail.quantities import plausible, ranged

from .compiled import scalar
from .gas import ABSOLUTE_PRESSURE, AIR_TEMPERATURE

#: DIN 1343 normal conditions [K], [Pa]: a normal litre (Nl) is a litre of air at these
NORMAL_T_K = 273.15
NORMAL_P_PA = 101_325.0


@dataclass(frozen=True)
class Compressor:
    """A compressor under a pressure governor filling ``reservoir`` (a chamber: a finite supply
    or a tank). ``free_air_delivery_m3_per_s``: the volume of air it takes in per second at the
    atmosphere's conditions (ISO 1217; a metro car's compressor: ~1 m^3/min = 0.0167 m^3/s,
    assumed). Cut-in and cut-out: absolute pressures of the reservoir at which the governor
    starts and stops it (defaults 8.5 and 10 bar absolute: a main reservoir kept at 7.5-9 bar
    gauge, assumed). ``running_at_start``: the governor's state at t = 0 when the reservoir
    starts between the two (below cut-in it runs, above cut-out it does not, whatever this says).
    ``T_delivery_K``: the air's temperature after the aftercooler (None: the atmosphere's)."""

    reservoir: str = "supply"
    # railway compressors deliver 0.2-5 m^3/min of free air (metro car ~1, a locomotive's ~5); a
    # value in m^3/min or l/min falls out
    free_air_delivery_m3_per_s: float = field(default=1.0 / 60.0, metadata=plausible(
        1e-4, 0.5, "m^3/s", "a compressor's free air delivery, 6 l/min to 30 m^3/min"))
    p_cut_in_Pa: float = field(default=8.5e5, metadata=ranged(ABSOLUTE_PRESSURE))
    p_cut_out_Pa: float = field(default=10.0e5, metadata=ranged(ABSOLUTE_PRESSURE))
    running_at_start: bool = False
    T_delivery_K: Optional[float] = field(default=None, metadata=ranged(AIR_TEMPERATURE))


#: a demand's fade-out width: the pressure above the atmosphere's over which its draw fades out
DP_OFF = plausible(1e2, 5e5, "Pa", "the pressure over which the draw fades out near the atmosphere's")


@dataclass(frozen=True)
class AirDemand:
    """Other consumers drawing air from ``node`` (brakes, doors): a steady normal volume flow
    ``normal_flow_m3_per_s`` (DIN 1343; 100 Nl/min = 1.667e-3 m^3/s), fading to nothing within
    ``dp_off_Pa`` of the atmosphere's pressure."""

    node: str = "supply"
    # brakes and doors of a car draw tens to a few hundred Nl/min on average; up to 30 Nm^3/min
    normal_flow_m3_per_s: float = field(default=1.0e-3, metadata=plausible(
        0.0, 0.5, "m^3/s", "a normal volume flow, up to 30 Nm^3/min", low_inclusive=False))
    dp_off_Pa: float = field(default=2.0e4, metadata=DP_OFF)


@dataclass(frozen=True)
class ScheduledDemand:
    """A demand from ``node`` that draws only within its ``windows``, each (t_on_s, t_off_s,
    normal_flow_m3_per_s): the normal flow over [t_on, t_off), the sum where windows overlap, 0
    outside every window; fading out within ``dp_off_Pa`` of the atmosphere's pressure as an
    :class:`AirDemand` (module docstring). Not a component: :meth:`at` is the steady demand it is
    from an instant on, which a circuit holds; :meth:`switch_times`, when that changes."""

    windows: Tuple[Tuple[float, float, float], ...]
    node: str = "supply"
    dp_off_Pa: float = 2.0e4

    def at(self, t_s: float) -> AirDemand:
        """The steady demand it is from ``t_s`` until its next switch time."""
        flow = sum((q for t_on, t_off, q in self.windows if t_on <= t_s < t_off), 0.0)
        return AirDemand(self.node, flow, self.dp_off_Pa)

    def switch_times(self) -> Tuple[float, ...]:
        """The instants its rate may change (every window's edges), in order."""
        return tuple(sorted({t for t_on, t_off, _ in self.windows for t in (t_on, t_off)}))

    def normal_volume_m3(self) -> float:
        """The normal volume its windows draw in all, while the node holds air [m^3]."""
        return sum((q * (t_off - t_on) for t_on, t_off, q in self.windows), 0.0)


def free_air_density_kg_per_m3(p_atm_Pa, T_atm_K, R_J_per_kgK):
    """Density of the air a compressor takes in [kg/m^3]: the atmosphere's."""
    return p_atm_Pa / (R_J_per_kgK * T_atm_K)


def normal_density_kg_per_m3(R_J_per_kgK):
    """Density of air at DIN 1343 normal conditions [kg/m^3] (1.292 for R = 287.05)."""
    return NORMAL_P_PA / (R_J_per_kgK * NORMAL_T_K)


def governor(running, p_reservoir_Pa, p_cut_in_Pa, p_cut_out_Pa):
    """The governor's next state (1.0 running, 0.0 stopped) from its state and the reservoir's
    pressure: on at or below cut-in, off at or above cut-out, held in between."""
    running = np.where(p_reservoir_Pa <= p_cut_in_Pa, 1.0, running)
    return np.where(p_reservoir_Pa >= p_cut_out_Pa, 0.0, running)


def compression_work_J_per_kg(p_Pa, p_atm_Pa, T_atm_K, gas):
    """(isothermal, adiabatic) work per kg of air compressed from the atmosphere to ``p_Pa`` [J/kg]
    (0 at or below the atmosphere's pressure)."""
    return compression_work(p_Pa, p_atm_Pa, T_atm_K, gas.R_J_per_kgK, gas.cp_J_per_kgK, gas.gamma)


@scalar
def compression_work(p_Pa, p_atm_Pa, T_atm_K, R, cp, gamma):
    """:func:`compression_work_J_per_kg` of the gas constants (R, c_p, gamma): numpy's on arrays,
    and the compiled macro-step's (:mod:`pneumatics.compiled_step`) the same law compiled."""
    ratio = np.maximum(p_Pa / p_atm_Pa, 1.0)
    isothermal = R * T_atm_K * np.log(ratio)
    adiabatic = cp * T_atm_K * (ratio ** ((gamma - 1.0) / gamma) - 1.0)
    return isothermal, adiabatic


def demand_flow_kg_per_s(w_max_kg_per_s, p_Pa, p_atm_Pa, dp_off_Pa):
    """A demand's mass flow [kg/s]: its full rate, faded out linearly within ``dp_off_Pa`` of
    the atmosphere's pressure."""
    return w_max_kg_per_s * _clip((p_Pa - p_atm_Pa) / dp_off_Pa, 0.0, 1.0)


#: the ufunc that ``np.clip`` calls on float arrays (the same numbers; called directly it costs
#: ~1 us instead of np.clip's ~7 us of Python dispatch, at every stage of the integrator)
_clip = getattr(getattr(np, "_core", getattr(np, "core", None)).umath, "clip", np.clip)
