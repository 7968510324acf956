"""Bad scenario input fails before any simulation, naming the file, the key path and what was expected."""
from __future__ import annotations

import copy
import dataclasses

import pytest
import yaml

from cosim import cli
from cosim.errors import ScenarioError
from cosim.load import load_scenario

from helpers import SCENARIOS, short_twist, vehicle_file, write_scenario

RIG = yaml.safe_load((SCENARIOS / "rig_ramp.yaml").read_text())


def rig(**changes):
    data = copy.deepcopy(RIG)
    for key, value in changes.items():
        node = data
        *parents, last = key.split(".")
        for p in parents:
            node = node.setdefault(p, {})
        if value is _DELETE:
            del node[last]
        else:
            node[last] = value
    return data


_DELETE = object()


def error_for(tmp_path, data) -> ScenarioError:
    path = write_scenario(tmp_path, data)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.file == str(path)
    return info.value


@pytest.mark.parametrize("name", sorted(p.name for p in SCENARIOS.glob("*.yaml")))
def test_shipped_scenarios_are_valid(name):
    scenario = load_scenario(SCENARIOS / name)
    assert scenario.k_W_per_K


def test_missing_key(tmp_path):
    # without the preset (which gives the rig's 4 bar) the initial pressure must be written
    err = error_for(tmp_path, rig(**{"circuit.preset": _DELETE}))
    assert err.path == "circuit.p0_Pa" and "missing" in err.reason


def test_wrong_type(tmp_path):
    err = error_for(tmp_path, rig(**{"circuit.bellow.V0_m3": "twelve litres"}))
    assert err.path == "circuit.bellow.V0_m3" and "expected a number" in err.reason


def test_negative_volume(tmp_path):
    err = error_for(tmp_path, rig(**{"circuit.tank.V_m3": -0.027}))
    assert err.path == "circuit.tank.V_m3" and "[0.001, 10] m^3" in err.reason


def test_negative_k(tmp_path):
    err = error_for(tmp_path, rig(k_W_per_K=[0, -1]))
    assert err.path.startswith("k_W_per_K") and ">= 0" in err.reason


def test_unknown_key_lists_the_allowed_ones(tmp_path):
    err = error_for(tmp_path, rig(**{"circuit.bellow.volume": 0.012}))
    assert err.path == "circuit.bellow.volume" and "V0_m3" in err.reason


def test_unknown_kind(tmp_path):
    err = error_for(tmp_path, rig(kind="rig_teleport"))
    assert err.path == "kind" and "rig_ramp" in err.reason


def test_yaml_exponent_without_sign_is_read_as_a_number(tmp_path):
    # PyYAML reads 4.0e5 as a string; the loader accepts the obvious intent.
    path = tmp_path / "s.yaml"
    path.write_text((SCENARIOS / "rig_ramp.yaml").read_text().replace("4.0e+5", "4.0e5"))
    assert load_scenario(path).circuit.p0_Pa == 4.0e5


def _explicit_circuit():
    comps = {}
    for b in ("FL", "FR", "RL", "RR"):
        comps[b] = {"type": "bellow"}
        comps[f"tank_{b}"] = {"type": "tank", "V_m3": 0.027}
        comps[f"pipe_{b}"] = {"type": "pipe", "a": b, "b": f"tank_{b}"}
    return {"components": comps}


def test_explicit_circuit_is_accepted(tmp_path):
    scenario = load_scenario(write_scenario(tmp_path, short_twist(circuit=_explicit_circuit())))
    assert set(scenario.circuit.components()) >= {"FL", "tank_RR", "pipe_RL"}


def test_unknown_component_type(tmp_path):
    circuit = _explicit_circuit()
    circuit["components"]["valve_X"] = {"type": "flux_capacitor"}
    err = error_for(tmp_path, short_twist(circuit=circuit))
    assert err.path == "circuit.components.valve_X.type" and "pipe" in err.reason


def test_connection_to_missing_component(tmp_path):
    circuit = _explicit_circuit()
    circuit["components"]["pipe_FL"]["b"] = "tank_XX"
    err = error_for(tmp_path, short_twist(circuit=circuit))
    assert err.path == "circuit.components.pipe_FL.b" and "tank_XX" in err.reason


def test_unknown_wheel_and_bad_check(tmp_path):
    err = error_for(tmp_path, short_twist(**{"twist.raised_wheels": ["1R", "9Z"]}))
    assert err.path == "twist.raised_wheels[1]"
    err = error_for(tmp_path, short_twist(checks=["dqq_max is small"]))
    assert err.path == "checks[0]"
    err = error_for(tmp_path, short_twist(checks=["roll_max <= 0.1"]))
    assert "unknown metric" in err.reason


def test_vehicle_parameter_error_names_the_parameter_file(tmp_path):
    params = yaml.safe_load(vehicle_file(tmp_path).read_text())
    params["carbody_mass_kg"] = -17000
    (tmp_path / "car.yaml").write_text(yaml.safe_dump(params))
    path = write_scenario(tmp_path, short_twist(vehicle="car.yaml"))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.file.endswith("car.yaml") and info.value.path == "carbody_mass_kg"


def test_cli_bad_input_exits_2_before_simulating(tmp_path, capsys):
    path = write_scenario(tmp_path, rig(**{"circuit.tank.V_m3": -1.0}))
    out = tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out)]) == cli.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert str(path) in err and "circuit.tank.V_m3" in err
    assert not out.exists()          # nothing ran, nothing written


def test_set_override_is_validated(tmp_path):
    path = write_scenario(tmp_path, rig())
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, overrides=["test.ramp_s=-1"])
    assert info.value.path == "test.ramp_s"
    assert load_scenario(path, overrides=["test.ramp_s=2"]).experiment.ramp_s == 2.0


def test_amplitude_beyond_the_bellow_stroke_is_rejected(tmp_path):
    # V = V0 - (dV/dz) z vanishes at z = 0.012 / 0.13 = 92 mm
    err = error_for(tmp_path, rig(**{"test.amplitude_m": 0.1}))
    assert err.path == "test.amplitude_m" and "V0/(dV/dz)" in err.reason


def test_a_run_that_diverges_keeps_its_results_and_says_where(tmp_path, capsys):
    """A ramp driving a bellow (alone) beyond its stroke makes the air non-physical; the run must
    stop with a diagnosis and keep the series up to there (the runner then reports it and the
    CLI exits 1) -- provoked through the API, since the scenario loader refuses such input."""
    import numpy as np

    from pneumatics.chamber import Bellow
    from pneumatics.rig import ramp_motion, run_time_series
    stroke = 0.012 / 0.13
    ts = run_time_series({"bellow": Bellow(p0_Pa=4e5)}, 0.0, ramp_motion(1.5 * stroke, 1.0), 2.0, 201)
    assert ts.diagnosis is not None and "t = " in ts.diagnosis and "T_K_bellow" in ts.diagnosis
    assert 0.5 < ts.t_s[-1] < 2.0 and np.all(np.isfinite(ts.force_N))


def test_inconsistent_car_parameters_are_bad_input(tmp_path):
    err = error_for(tmp_path, short_twist(vehicle={"preset": "paper_metro_car",
                                                   "airspring_upper_height_m": 0.5}))
    assert err.path == "vehicle" and "airspring_upper_height_m" in err.reason


@pytest.mark.parametrize("name", ["paper_metro_car", "metro_car_arb_dampers", "manchester_vehicle_1"])
def test_a_printed_vehicle_preset_loads_back_as_the_preset(tmp_path, name):
    # pneumorail presets NAME > car.yaml gives a file that is the preset, field by field (exact:
    # the YAML holds the literals)
    from cosim.scenario.presets import VEHICLE_PRESETS
    s = load_scenario(write_scenario(tmp_path, short_twist(vehicle=str(vehicle_file(tmp_path, name)))))
    assert s.vehicle == VEHICLE_PRESETS[name]()


def test_presets_resolve_and_overrides_apply_to_single_fields():
    from cosim.scenario.presets import VEHICLE_PRESETS
    s = load_scenario(SCENARIOS / "two_point_twist.yaml", ["vehicle.carbody_mass_kg=21000", "circuit.tank.V_m3=0.04"])
    arb = VEHICLE_PRESETS["metro_car_arb_dampers"]()
    assert s.vehicle == dataclasses.replace(arb, carbody_mass_kg=21000.0)
    assert s.circuit.tank.V_m3 == 0.04 and s.circuit.bellow.V0_m3 == 0.012 and s.circuit.pipe.zeta == 1.11
    with pytest.raises(ScenarioError, match="unknown circuit preset"):
        load_scenario(SCENARIOS / "twist_dqq.yaml", ["circuit.preset=paper_table9"])
    with pytest.raises(ScenarioError) as info:
        load_scenario(SCENARIOS / "twist_dqq.yaml", ["vehicle.preset=no_car"])
    assert info.value.path == "vehicle.preset"


def test_set_overrides_a_single_field_of_a_vehicle_parameter_file():
    # the scenario names the preset paper_metro_car; --set vehicle.FIELD changes that field alone
    base = load_scenario(SCENARIOS / "curve_entry.yaml")
    changed = load_scenario(SCENARIOS / "curve_entry.yaml", ["vehicle.carbody_cog_height_m=1.8"])
    assert changed.vehicle.carbody_cog_height_m == 1.8
    assert changed.vehicle.carbody_cog_height_m != base.vehicle.carbody_cog_height_m
    others = {f: getattr(base.vehicle, f) for f in vars(base.vehicle) if f != "carbody_cog_height_m"}
    assert all(getattr(changed.vehicle, f) == v for f, v in others.items())
    with pytest.raises(ScenarioError, match="vehicle"):
        load_scenario(SCENARIOS / "curve_entry.yaml", ["vehicle.no_such_field=1"])


@pytest.mark.slow
@pytest.mark.parametrize("name", ["rig_table2.yaml", "rig_stiffness.yaml"])
def test_loading_a_rig_scenario_imports_no_exudyn(name):
    # a fresh interpreter: the rig needs only the pneumatics
    import subprocess
    import sys
    code = ("import sys; from cosim.load import load_scenario; "
            f"load_scenario({str(SCENARIOS / name)!r}); print(any('exudyn' in m for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


@pytest.mark.slow
def test_the_throttled_explicit_circuit_starts_at_rest_and_runs(tmp_path):
    # Tanks joined to their bellows by orifices (no pipe) take the bellows' static pressure:
    # without twist nothing moves (|ΔQ/Q0| at round-off of the static equilibrium, < 1e-6).
    out = tmp_path / "run"
    assert cli.main(["run", str(SCENARIOS / "twist_throttled_tanks.yaml"), "--k", "0,inf", "--jobs", "1", "--quiet",
                     "--set", "twist.twist_per_mille=0", "--set", "twist.ramp_s=0.5", "--set", "twist.hold_s=0.5",
                     "--out", str(out)]) == 0
    import csv
    rows = list(csv.DictReader((out / "summary.csv").open()))
    assert len(rows) == 2
    assert all(abs(float(r["dqq_max"])) < 1e-6 and abs(float(r["dqq_qs_max"])) < 1e-6 for r in rows)
