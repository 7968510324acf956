"""The kind contract (cosim.kinds.base): every registered kind goes through every command a user
gives it on a tiny scenario, and a new kind is one class in one file (a toy kind, registered only
here, runs, checks and reports like the shipped ones)."""
from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Tuple

import numpy as np
import pytest
import yaml

from cosim import cli
from cosim.engine.master import OUTPUTS, Output
from cosim.kinds import KINDS
from cosim.kinds.base import CarKind, Kind
from cosim.results.outcome import Computed

from helpers import SCENARIOS

#: a tiny scenario of every registered kind: a shipped file and the --set that shrink it, and the
#: sweep's two cases (a --grid)
TINY = {
    "rig_ramp": ("rig_ramp.yaml", ["test.duration_s=2", "test.samples=21", "test.ramp_s=1",
                                   "test.configurations=[bellow_tank]"], "k_W_per_K=0,.inf"),
    "rig_sine": ("rig_sine_1hz.yaml", ["test.duration_s=2", "test.samples_per_period=10"], "k_W_per_K=0,.inf"),
    "rig_stiffness": ("rig_stiffness.yaml", ["test.frequencies_Hz=[1,10]"], "k_W_per_K=10,.inf"),
    "rig_table2": ("rig_table2.yaml", ["test.ramp_s=2"], "test.amplitude_m=0.0001,0.0002"),
    "twist": ("twist_dqq.yaml", ["twist.ramp_s=0.5", "twist.hold_s=0.5", "solver.jobs=1"], "k_W_per_K=0,.inf"),
    "curve_entry": ("curve_entry.yaml", ["curve.duration_s=1", "curve.valve_settings=[false]", "solver.jobs=1"],
                    "k_W_per_K=0,.inf"),
    "ride": ("ride_comfort.yaml", ["ride.speeds_m_per_s=[10]", "ride.record_s=5", "ride.settle_s=0.5", "solver.jobs=1"],
             "k_W_per_K=0,.inf"),
    "station_stop": ("station_stop.yaml", ["station.duration_s=1", "payload.events[0].t_s=0.2",
                                           "payload.events[0].duration_s=0.5", "payload.events[0].normal_fraction=0.05",
                                           "solver.jobs=1"], "k_W_per_K=0,.inf"),
    "service": ("service_line.yaml", ["service.stations=[{name: A, at_m: 0, dwell_s: 2, boarding: 3}, "
                                      "{name: B, at_m: 13, dwell_s: 2, alighting: 3}]", "service.curves=[]",
                                      "service.round_trip=false", "service.door_open_delay_s=0.5",
                                      "service.door_close_s=0.5", "service.spread_s=3", "solver.jobs=1"],
                "k_W_per_K=0,.inf"),
    "stability": ("stability.yaml", ["stability.speeds_m_per_s=[30,50]", "stability.resolution_m_per_s=5",
                                     "stability.reference_speed_m_per_s=30", "solver.jobs=1"], "k_W_per_K=0,.inf"),
}


def test_every_registered_kind_has_a_tiny_scenario():
    assert sorted(TINY) == sorted(KINDS)


def _sets(overrides) -> list:
    return [a for o in overrides for a in ("--set", o)]


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(TINY))
def test_every_kind_goes_through_every_command(name, tmp_path, capsys):
    """validate, run, check (where the scenario has checks), verify at two levels (car kinds; its least),
    compare (kinds that overlay), report and a sweep of two cases, each without a traceback and
    with the exit code its result asks for (0, or 1 for a limit the tiny run does not hold)."""
    file, overrides, grid = TINY[name]
    kind, path, sets = KINDS[name], SCENARIOS / file, _sets(overrides)
    k = ["--k", "inf"] if not kind.k_fixed else []
    assert cli.main(["validate", str(path)]) == cli.EXIT_OK
    run = tmp_path / "run"
    assert cli.main(["run", str(path), *sets, *k, "--out", str(run), "--quiet"]) == cli.EXIT_OK
    assert (run / "summary.csv").exists() and json.loads((run / "run.json").read_text())["status"] == "complete"
    if yaml.safe_load(path.read_text()).get("checks"):
        assert cli.main(["check", str(path), *sets, *k, "--out", str(tmp_path / "check"), "--quiet"]) in (0, 1)
        assert json.loads((tmp_path / "check" / "check.json").read_text())["status"] in ("pass", "fail", "error")
    if kind.car:
        assert cli.main(["verify", str(path), *sets, *k, "--levels", "2", "--out", str(tmp_path / "verify"),
                         "--quiet"]) in (0, 1)
    if kind.compares:
        assert cli.main(["compare", str(run), str(run), "--out", str(tmp_path / "compare")]) == cli.EXIT_OK
        assert list((tmp_path / "compare").glob("*.png"))
    assert cli.main(["report", str(run), "--out", str(tmp_path / "report.html")]) == cli.EXIT_OK
    sweep = tmp_path / "sweep"
    assert cli.main(["sweep", str(path), *sets, "--grid", grid, "--out", str(sweep), "--jobs", "1", "--quiet"]) == 0
    assert len(list((sweep / "cases").iterdir())) == 2
    assert "Traceback" not in capsys.readouterr().err


# ------------------------------------------------------------------------------ a new kind
@dataclass(frozen=True)
class BrakingTest:
    """The toy kind's section: the car standing on level track for ``duration_s``."""

    duration_s: float = 1.0
    valve_settings: Tuple[bool, ...] = (False,)


def _carbody_lateral_m(sample) -> np.ndarray:
    """The toy kind's own output: each car's carbody lateral displacement (module level: the
    outputs travel to the worker processes)."""
    return np.array([car.carbody_lateral_m() for car in sample.sim.cars])


class BrakingKind(CarKind):
    """A new kind as a user would sketch one: a section, a car, a run, a checkable metric and an
    output of its own; the rest (figures, zones, checks refused, compare) the contract's
    defaults."""

    name, section, experiment = "braking", "braking", BrakingTest
    check_metrics = headline_metrics = ("roll_max_rad",)
    outputs = (Output("carbody_lateral_m", (), "m", "carbody lateral displacement", "y_carbody_m", _carbody_lateral_m),)

    def parse(self, data, vehicle, path):
        from cosim.scenario.schema import build
        return build(BrakingTest, data, path, ["braking"])

    def duration_s(self, experiment):
        return experiment.duration_s

    def make_car(self, scenario):
        from vehicle.car import MetroCar
        return MetroCar(scenario.vehicle, step_s=scenario.solver.mechanics_step_s, track_structure=scenario.track)

    def run(self, scenario, progress):
        from cosim.engine.cases import simulate_cases
        ds, diagnoses = simulate_cases(scenario, scenario.experiment.valve_settings, self.make_car,
                                       scenario.experiment.duration_s, progress, self.outputs)
        rows = [{"valves": bool(ds["valves"].values[j]), "k_W_per_K": float(ds["k_W_per_K"].values[j]),
                 "roll_max_rad": float(np.abs(ds["roll_rad"].values[:, j]).max())} for j in range(ds.sizes["case"])]
        # the rows, series and diagnoses: the runner builds the Outcome (totals, checkable metrics)
        return Computed(rows, ("valves", "k_W_per_K", "roll_max_rad"), {"braking": ds}, diagnoses=diagnoses)


def test_a_kind_without_its_required_methods_cannot_be_registered():
    class Half(CarKind):
        name, section, experiment = "half", "half", BrakingTest

        def run(self, scenario, progress):
            return None

    with pytest.raises(TypeError, match="parse"):
        Half()
    assert Kind.figures(BrakingKind(), None) == [] and not BrakingKind().compares


@pytest.mark.slow
def test_a_new_kind_is_one_class_in_one_file(tmp_path, monkeypatch, capsys):
    """The toy kind, registered here and nowhere else (the files a new kind touches: its own, and
    the registry's line to ship it), loads, runs, checks its metric, writes its files and a report,
    and its section's keys are checked like a shipped kind's."""
    monkeypatch.setitem(KINDS, "braking", BrakingKind())
    data = yaml.safe_load((SCENARIOS / "twist_dqq.yaml").read_text())
    data.pop("twist")
    data.update(kind="braking", name="braking", k_W_per_K=[0.0], braking={"duration_s": 0.5},
                checks=["roll_max_rad <= 0.01"])
    path = tmp_path / "braking.yaml"
    path.write_text(yaml.safe_dump(data))
    out = tmp_path / "out"
    assert cli.main(["check", str(path), "--out", str(out), "--quiet"]) == cli.EXIT_OK
    assert json.loads((out / "check.json").read_text())["checks"][0]["status"] == "pass"
    assert (out / "timeseries").is_dir() and (out / "summary.csv").exists()
    # its own output is sampled in its runs, labelled and written, and in no other kind's
    columns = (out / "timeseries" / "braking_valves=off_k=0.csv").read_text().splitlines()[0].split(",")
    assert "y_carbody_m" in columns and "Q_1L_N" in columns
    assert not any(o.name == "carbody_lateral_m" for o in OUTPUTS)
    assert cli.main(["report", str(out), "--out", str(tmp_path / "report.html")]) == cli.EXIT_OK
    data["braking"]["duration"] = 1.0                       # a mistyped key of the new section
    path.write_text(yaml.safe_dump(data))
    assert cli.main(["validate", str(path)]) == cli.EXIT_BAD_INPUT
    assert "braking.duration" in capsys.readouterr().err
