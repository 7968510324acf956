"""A car run with a compressor filling the main reservoir and a demand drawing from it: the
scenario keys checked at load, the sampled series, the summary's duty cycle and the mass balance."""
from __future__ import annotations

import math

import pytest

from cosim.errors import ScenarioError
from cosim.load import load_scenario
from cosim.runner import run

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
