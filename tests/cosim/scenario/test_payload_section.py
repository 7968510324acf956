"""``payload:`` read and checked at load (cosim/scenario/payload.py): the reference masses, the
schedule the car receives, and every error before anything runs, with its key path."""
import copy

import pytest
import yaml

from cosim.errors import ScenarioError
from cosim.load import load_scenario

from helpers import SCENARIOS

STOP = yaml.safe_load((SCENARIOS / "station_stop.yaml").read_text())


def scenario_with(tmp_path, payload, base=STOP, name="stop.yaml"):
    data = copy.deepcopy(base)
    data["payload"] = payload
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def error_for(tmp_path, payload, base=STOP) -> ScenarioError:
    with pytest.raises(ScenarioError) as info:
        load_scenario(scenario_with(tmp_path, payload, base))
    return info.value


def test_reference_masses_and_schedule(tmp_path):
    """Normal payload m_p (seats + 4/m2 x area), exceptional (seats + 6/m2 x area); an event's
    mass ramps linearly over its duration at its place on the floor."""
    s = load_scenario(scenario_with(tmp_path, {"seats": 20, "standing_area_m2": 30.0, "initial": {"passengers": 10},
                                               "events": [{"t_s": 10, "duration_s": 20, "passengers": 40,
                                                           "position": "rear_left"}]})).payload
    assert s.normal_payload_kg == pytest.approx(70.0 * (20 + 4 * 30.0))
    assert s.exceptional_payload_kg == pytest.approx(70.0 * (20 + 6 * 30.0))
    assert s.total_kg(0.0) == 700.0 and s.total_kg(20.0) == pytest.approx(700.0 + 0.5 * 2800.0)
    initial, event = s.blocks_at(20.0)
    assert (initial.mass_kg, initial.length_m, initial.width_m) == (700.0, 14.0, 2.6)
    assert (event.mass_kg, event.x_m, event.y_m, event.length_m, event.width_m) == pytest.approx(
        (1400.0, -3.5, 0.65, 7.0, 1.3))
    assert s.blocks_at(31.0)[1].mass_kg == 2800.0


def test_a_point_in_metres(tmp_path):
    s = load_scenario(scenario_with(tmp_path, {"events": [{"t_s": 1, "duration_s": 2, "mass_kg": 500,
                                                           "position": {"x_m": -6.0, "y_m": 1.2}}]})).payload
    block = s.blocks_at(5.0)[1]
    assert (block.mass_kg, block.x_m, block.y_m, block.length_m) == (500.0, -6.0, 1.2, 0.0)


def test_alighting_is_a_negative_amount(tmp_path):
    s = load_scenario(scenario_with(tmp_path, {"initial": {"passengers": 100},
                                               "events": [{"t_s": 1, "duration_s": 2, "passengers": -40,
                                                           "position": "front"}]})).payload
    assert s.total_kg(3.0) == pytest.approx(60 * 70.0)


@pytest.mark.parametrize("payload, where, words", [
    ({"events": [{"t_s": 50, "duration_s": 20, "passengers": 10}]}, "payload.events[0].duration_s", "within the run"),
    ({"events": [{"t_s": -1, "duration_s": 2, "passengers": 10}]}, "payload.events[0].t_s", ">= 0"),
    ({"events": [{"t_s": 1, "duration_s": 0, "passengers": 10}]}, "payload.events[0].duration_s", "> 0"),
    ({"events": [{"t_s": 1, "duration_s": 2, "passengers": 10, "mass_kg": 700}]}, "payload.events[0]", "exactly one"),
    ({"events": [{"t_s": 1, "duration_s": 2}]}, "payload.events[0]", "exactly one"),
    ({"events": [{"t_s": 1, "duration_s": 2, "passengers": 10.5}]}, "payload.events[0].passengers", "whole number"),
    ({"events": [{"t_s": 1, "duration_s": 2, "passengers": 10, "position": "roof"}]}, "payload.events[0].position",
     "unknown position"),
    ({"events": [{"t_s": 1, "duration_s": 2, "passengers": 10, "position": {"x_m": 9.0}}]},
     "payload.events[0].position.x_m", "on the floor"),
    ({"events": [{"t_s": 1, "duration_s": 2, "passengers": 10, "position": {"y_m": -1.5}}]},
     "payload.events[0].position.y_m", "on the floor"),
    ({"events": [{"t_s": 1, "duration_s": 2, "passengers": 300}]}, "payload.events[0]", "exceptional payload"),
    ({"events": [{"t_s": 1, "duration_s": 2, "passengers": -1}]}, "payload.events[0]", "tare"),
    ({"initial": {"normal_fraction": 1.6}}, "payload.initial", "exceptional payload"),
    ({"passenger_mass_kg": 7000}, "payload.passenger_mass_kg", "kg"),
    ({"exceptional_standing_per_m2": 3}, "payload.exceptional_standing_per_m2", "normal density"),
    ({"events": {"t_s": 1}}, "payload.events", "a list"),
    ({"stops": 1}, "payload.stops", "unknown key"),
])
def test_errors_name_the_key(tmp_path, payload, where, words):
    err = error_for(tmp_path, payload)
    assert err.path == where and words in err.reason


def test_every_event_counts_in_the_total(tmp_path):
    """Two boardings that are each within the crush load but not together: the second's end is named."""
    err = error_for(tmp_path, {"events": [{"t_s": 1, "duration_s": 2, "passengers": 150},
                                          {"t_s": 5, "duration_s": 2, "passengers": 100}]})
    assert err.path == "payload.events[1]" and "exceptional payload" in err.reason


def test_the_run_starts_carrying_the_initial_payload(tmp_path):
    """The circuit's start is checked with the loaded car (its bellows carry the initial payload)."""
    scenario = load_scenario(scenario_with(tmp_path, {"initial": {"normal_fraction": 1.0}}))
    assert scenario.payload.initial_kg == pytest.approx(scenario.payload.normal_payload_kg)


def test_stability_refuses_a_payload(tmp_path):
    base = yaml.safe_load((SCENARIOS / "stability.yaml").read_text())
    err = error_for(tmp_path, {"initial": {"passengers": 10}}, base=base)
    assert err.path == "payload" and "stability" in err.reason


def test_other_car_kinds_take_a_payload(tmp_path):
    base = yaml.safe_load((SCENARIOS / "twist_dqq.yaml").read_text())
    path = scenario_with(tmp_path, {"events": [{"t_s": 1, "duration_s": 2, "passengers": 20, "position": "left"}]},
                         base=base)
    scenario = load_scenario(path)
    assert scenario.car_payload(10.0)[1].mass_kg == 1400.0
