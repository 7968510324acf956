"""A car run with a compressor filling the main reservoir and a demand drawing from it: the
scenario keys checked at load, the sampled series, the summary's duty cycle and the mass balance;
the co-simulation switching a demand on a schedule at its windows' edges, merged with a fault's
time."""
from __future__ import annotations

import math

import numpy as np
import pytest

from cosim.engine.master import CoSimulation
from cosim.errors import ScenarioError
from cosim.load import load_scenario
from cosim.runner import run
from pneumatics.air_supply import AirDemand, ScheduledDemand, normal_density_kg_per_m3
from pneumatics.boundary import Supply
from pneumatics.circuit import Circuit
from pneumatics.faults import Fault
from pneumatics.gas import AIR

from helpers import SCENARIOS

AIR_SUPPLY = ["circuit.supply.V_m3=0.1", "circuit.supply.p_Pa=8.6e5", "circuit.compressor={}", "circuit.air_demand={}"]


def test_a_compressor_needs_a_reservoir_that_holds_air():
    with pytest.raises(ScenarioError, match="circuit.compressor: needs a main reservoir"):
        load_scenario(SCENARIOS / "twist_dqq.yaml", ["circuit.compressor={}"])
    with pytest.raises(ScenarioError, match="circuit.air_demand.normal_flow_m3_per_s"):
        load_scenario(SCENARIOS / "twist_dqq.yaml", ["circuit.supply.V_m3=0.1", "circuit.air_demand={normal_flow_m3_per_s: 5}"])
    with pytest.raises(ScenarioError, match="p_cut_out_Pa: must be above p_cut_in_Pa"):
        load_scenario(SCENARIOS / "twist_dqq.yaml", ["circuit.supply.V_m3=0.1",
                                                     "circuit.compressor={p_cut_in_Pa: 9e5, p_cut_out_Pa: 8e5}"])


@pytest.mark.slow
def test_a_twist_run_with_a_compressor_accounts_for_every_gram():
    scenario = load_scenario(SCENARIOS / "twist_dqq.yaml", [*AIR_SUPPLY, "solver.jobs=1", "twist.valve_settings=[false, true]"],
                             [0.0, 100.0])
    outcome = run(scenario)
    ds = outcome.series["twist"]
    assert {"compressor_running", "compressor_air_kg", "air_demand_kg"} <= set(ds.data_vars)
    t = ds["time"].values
    for row in outcome.rows:
        # the reservoir starts 0.1 bar above the cut-in: the demand brings it there and the
        # compressor runs within the run, in both valve settings (the reservoir is there either way)
        assert 0.0 < row["compressor_duty"] < 1.0 and row["compressor_air_kg"] > 0.0 and row["air_demand_kg"] > 0.0
        assert row["compressor_min_per_h"] == pytest.approx(60.0 * row["compressor_duty"], rel=1e-12)
        # the compressor delivers its free air delivery's mass flow while it runs
        w_c = 101325.0 / (287.0 * 293.15) / 60.0           # p_atm / (R T_atm) FAD, air as pneumatics.gas has it
        assert row["compressor_air_kg"] == pytest.approx(w_c * row["compressor_duty"] * (t[-1] - t[0]), rel=1e-6)
        # the chambers' air changes by what came in and went out, compressor and demand included,
        # to the integrator's round-off
        assert abs(row["mass_balance_error_kg"]) < 1e-10
        # the energy of compression between its bounds: at ~9 bar, 0.23 MJ/kg isothermal, 0.33 adiabatic
        assert 0.0 < row["compression_isothermal_J"] < row["compression_adiabatic_J"]
        per_kg = row["compression_isothermal_J"] / row["compressor_air_kg"]
        assert 287.0 * 293.15 * math.log(8.4e5 / 101325.0) < per_kg < 287.0 * 293.15 * math.log(10.1e5 / 101325.0)
        if not row["valves"]:
            assert row["air_injected_kg"] == 0.0       # the suspension took nothing from the reservoir
    assert not any(math.isnan(v) for r in outcome.rows for v in (r["compressor_duty"], r["air_demand_kg"]))


@pytest.mark.slow
def test_a_curve_run_reports_its_air_supply_too():
    # the track run's summary row (curve, ride) carries the compressor's columns as the twist's does
    scenario = load_scenario(SCENARIOS / "curve_entry.yaml", [*AIR_SUPPLY, "solver.jobs=1", "curve.duration_s=12",
                                                             "curve.valve_settings=[true]"], [math.inf])
    row = run(scenario).rows[0]
    assert row["compressor_air_kg"] > 0.0 and 0.0 < row["compressor_duty"] < 1.0
    assert 0.0 < row["compression_isothermal_J"] < row["compression_adiabatic_J"]
    assert abs(row["mass_balance_error_kg"]) < 1e-10


class _StillCar:
    """A car without bellows that stands still: the co-simulation's air alone."""

    def bellow_crushing(self):
        return np.zeros(0), np.zeros(0)

    def set_bellow_forces(self, *laws):
        pass

    def advance(self, t_s):
        pass


def test_the_master_switches_a_scheduled_demand_at_its_windows_edges_within_the_macro_steps():
    # windows whose edges fall inside 10 ms macro-steps, a steady demand beside it and a leak that
    # opens between two windows: one list of switches, by time
    windows = ((0.013, 0.517, 2e-3), (0.7043, 1.3, 1e-3))
    scheduled = ScheduledDemand(windows)
    components = {"supply": Supply(p_Pa=9e5, V_m3=0.1), "stops": scheduled.at(0.0),
                  "steady": AirDemand("supply", 1e-3)}
    circuit = Circuit(components, k_W_per_K=np.array([math.inf]), faults=(Fault("leak", "supply", 0.6, area_m2=1e-6),))
    x0 = circuit.initial_state()
    sim = CoSimulation([_StillCar()], circuit, x0, 0.01, 0.005, scheduled_demands={"stops": scheduled})
    assert [t for t, _ in sim._switches] == [0.013, 0.517, 0.6, 0.7043, 1.3]
    t, stops, steady = [0.0], [0.0], [0.0]
    for _ in range(150):
        sim.step()
        drawn = sim.circuit.demand_air_kg(sim.x)[:, 0]
        t.append(sim.t)
        stops.append(float(drawn[0]))
        steady.append(float(drawn[1]))
    t, stops = np.array(t), np.array(stops)
    rho_n = normal_density_kg_per_m3(AIR.R_J_per_kgK)
    # the reservoir stays near 9 bar (the draw at its full rate): each window draws rho_N Q (t_off - t_on),
    # a constant rate that RK4 integrates exactly; 1e-12: round-off over 300 sub-steps
    for (t_on, t_off, q), i_on, i_off in zip(windows, (0, 60), (60, 140)):
        assert stops[i_off] - stops[i_on] == pytest.approx(rho_n * q * (t_off - t_on), rel=1e-12)
    # nothing in a macro-step outside the windows, bit for bit; something in every one that overlaps one
    within = np.array([any(a < t_off and t_on < b for t_on, t_off, _ in windows) for a, b in zip(t, t[1:])])
    assert np.all(np.diff(stops)[~within] == 0.0) and np.all(np.diff(stops)[within] > 0.0)
    assert (~within).sum() == 1 + 18 + 20            # the steps within 0-0.013, 0.517-0.7043, 1.3-1.5 s
    assert steady[-1] == pytest.approx(rho_n * 1e-3 * 1.5, rel=1e-12)    # the steady demand unaffected
    assert sim.circuit.active_faults == frozenset({0})                       # the leak opened too
    balance = sim.circuit.total_mass_kg(sim.x) - circuit.total_mass_kg(x0) - sim.circuit.net_inflow_kg(sim.x)
    assert abs(balance[0]) < 1e-13                                           # round-off on 0.9 kg of air
