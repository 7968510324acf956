"""What the car kinds share besides running their cases (:mod:`cosim.engine.cases`): the wheel
unloading of a run's Dataset, its per-case curves and bellow panels, the air accounts and the
columns and figure of a fault."""
from __future__ import annotations

import math
from typing import Dict, List, Optional

import numpy as np
import xarray as xr

from cosim.limits.criteria import static_wheel_loads, wheel_unloading
from cosim.results.plots import Curve, Figure, Panel, k_legend
from cosim.scenario.model import Scenario
from pneumatics.valves import DifferentialPressureValve
from vehicle.params import BELLOWS


def add_wheel_unloading(ds: xr.Dataset, column: Optional[str] = None) -> None:
    """Add the static wheel loads ``Q0_N`` (wheel x case: each wheelset's mean load at t = 0, the
    car at rest on level track; EN 14363) and the wheel unloading ``dqq`` = (Q0 - Q)/Q0 (time x
    wheel x case, positive: unloaded) to a car run's Dataset, in place; ``column``: its CSV
    column pattern (None: not written to the time series)."""
    Q = ds["wheel_load_N"].transpose("time", "wheel", "case")
    Q0 = static_wheel_loads(Q.values[0])                                   # (8, cases)
    ds["Q0_N"] = (("wheel", "case"), Q0, {"units": "N", "long_name": "static wheel load Q0 (wheelset mean, level track)"})
    attrs = {"units": "1", "long_name": "wheel unloading ΔQ/Q0 = (Q0 - Q)/Q0 (positive: unloaded)"}
    ds["dqq"] = (("time", "wheel", "case"), wheel_unloading(Q.values, Q0), {**attrs, **({"column": column} if column else {})})


def per_case(da: xr.DataArray, scale: float = 1.0, label: str = "") -> List[Curve]:
    """One curve per case of ``da`` (time x case) against time, labelled by its k."""
    return [Curve(da["time"].values, da.sel(case=c).values * scale, f"{label}{k_legend(float(k))}")
            for c, k in zip(da["case"].values, da["k_W_per_K"].values)]


def bellow_panels(ds: xr.Dataset) -> List[Panel]:
    """Pressure and temperature of each bellow, one curve per case of ``ds``."""
    return ([Panel(per_case(ds["bellow_p_Pa"].sel(bellow=b), 1e-5), "time t [s]", f"p_{b} [bar abs]", f"bellow {b}")
             for b in BELLOWS] +
            [Panel(per_case(ds["bellow_T_K"].sel(bellow=b)), "time t [s]", f"T_{b} [K]", f"bellow {b}")
             for b in BELLOWS])


def of_setting(ds: xr.Dataset, valves: Optional[bool]) -> xr.Dataset:
    """The cases of one valve setting (None: every case)."""
    return ds if valves is None else ds.isel(case=np.flatnonzero(ds["valves"].values == valves))


def air_columns(case: xr.Dataset) -> Dict[str, float]:
    """The air a case exchanged (cumulative, at its last sample) [kg]: injected from the supply,
    exhausted by the valves, lost through the faults' openings; and the error of the mass balance
    air(end) - air(start) - net inflow from outside (= injected - exhausted - lost with a fixed
    supply; a finite supply is a chamber, its air moves within), which closes to the
    integrator's round-off (the circuit holds every term as a state)."""
    m = case["total_mass_kg"].values
    columns = {"air_injected_kg": float(case["air_from_supply_kg"].values[-1]),
               "air_exhausted_kg": float(case["air_to_atmosphere_kg"].values[-1]) + 0.0,   # no "-0"
               "air_lost_kg": float(case["air_lost_kg"].values[-1]) + 0.0,
               "mass_balance_error_kg": float(m[-1] - m[0] - case["net_inflow_kg"].values[-1])}
    return {**columns, **air_supply_columns(case)}


def air_supply_columns(case: xr.Dataset) -> Dict[str, float]:
    """With a compressor or air demands (:mod:`pneumatics.air_supply`; none without): the air the
    compressor delivered and the demands drew [kg], the compressor's duty cycle (its running time
    over the run's), its running minutes per hour of service, and the energy of compression of
    what it delivered, between its isothermal and adiabatic bounds [J]."""
    if "compressor_air_kg" not in case:
        return {}
    t = case["time"].values
    duty = float(case["compressor_run_time_s"].values[-1] / (t[-1] - t[0])) if t[-1] > t[0] else math.nan
    return {"compressor_air_kg": float(case["compressor_air_kg"].values[-1]),
            "air_demand_kg": float(case["air_demand_kg"].values[-1]),
            "compressor_duty": duty, "compressor_min_per_h": 60.0 * duty,
            "compression_isothermal_J": float(case["compression_isothermal_J"].values[-1]),
            "compression_adiabatic_J": float(case["compression_adiabatic_J"].values[-1])}


def fault_figure(scenario: Scenario, ds: xr.Dataset, suffix: str = "", valves_text: str = "") -> List[Figure]:
    """With faults: the air lost through their openings, the flow of every differential valve
    and the flow through every faulted link (each against time, one curve per case); none
    without faults."""
    faults = scenario.circuit.faults
    if not faults:
        return []
    panels = [Panel(per_case(ds["air_lost_kg"], 1e3), "time t [s]", "air lost [g]", "through the faults' openings")]
    circuit = scenario.circuit.compile()
    ends = dict(zip(circuit.link_names, circuit.link_ends()))
    links = [str(n) for n in ds["link"].values] if "link" in ds.dims else []
    named = {f.component for f in faults}
    shown = [n for n in links if n in ends and (isinstance(circuit.components.get(n), DifferentialPressureValve)
                                                or n.split(".")[0] in named or named & set(ends[n]))]
    for link in shown:
        flow = ds["link_flow_kg_per_s"].sel(link=link)
        if np.all(np.isnan(flow.values)):
            continue                                  # a link of the other valve setting's circuit
        a, b = ends[link]
        panels.append(Panel(per_case(flow, 1e3), "time t [s]", f"flow {a} → {b} [g/s]", link))
    return [Figure(f"faults{suffix}.png", panels, f"Air lost and flows of the faulted and differential valves"
                                                  f"{valves_text}", 2)]


#: the window before a fault over which the state it strikes is averaged [s]
BEFORE_FAULT_S = 1.0


def fault_columns(scenario: Scenario, case: xr.Dataset) -> Dict[str, float]:
    """The transient after the first fault that happens during the run (t > 0; none: no columns):
    ``roll_before_fault_rad``, the carbody roll (to the track plane where the run has it)
    averaged over the second before; ``roll_max_after_fault_rad``, its largest magnitude after;
    ``dqq_max_after_fault``, the largest wheel unloading ΔQ/Q0 after (its EN 14363 2 m mean where
    the run has it); ``yq_2m_max_after_fault`` likewise for Y/Q on the wheel-rail contact."""
    times = [f.t_s for f in scenario.circuit.faults if f.t_s > 0.0]
    if not times:
        return {}
    t_fault = min(times)
    t = case["time"].values
    after, before = t >= t_fault, (t >= t_fault - BEFORE_FAULT_S) & (t < t_fault)
    if not after.any():                               # the run stopped before the fault
        return {}
    roll = case["roll_rel_rad"] if "roll_rel_rad" in case else case["roll_rad"]
    dqq = case["dqq_2m"] if "dqq_2m" in case else case["dqq"]
    columns = {"roll_before_fault_rad": float(np.mean(roll.values[before])) if before.any() else float("nan"),
               "roll_max_after_fault_rad": float(np.max(np.abs(roll.values[after]))),
               "dqq_max_after_fault": float(np.max(dqq.transpose("time", "wheel").values[after]))}
    if "y_over_q_2m" in case:
        columns["yq_2m_max_after_fault"] = float(np.max(case["y_over_q_2m"].transpose("time", "wheel").values[after]))
    return columns
