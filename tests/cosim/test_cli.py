"""A CLI that explains itself: --version, --help with exit codes and examples, validate, options
that do not apply refused, check's machine-readable verdict, validity flags, compare selection."""
from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import pytest

from cosim import cli
from cosim.limits.validity import PIPE_MACH_MAX, T_RANGE_K, failures, flag_rows
from cosim.results.plots import curve_style

from helpers import SCENARIOS, short_twist, write_scenario


def test_version_and_help(capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["--version"])
    assert exc.value.code == 0 and capsys.readouterr().out.startswith("pneumorail ")
    with pytest.raises(SystemExit):
        cli.main(["--help"])
    text = capsys.readouterr().out
    assert "exit codes:" in text and "examples:" in text and "pneumorail validate" in text
    for code in ("0 ", "1 ", "2 ", "130"):
        assert f"\n  {code}" in text


def test_validate_runs_nothing_and_says_what_is_wrong(tmp_path, capsys):
    shipped = sorted(str(p) for p in SCENARIOS.glob("*.yaml")) + sorted(str(p) for p in (SCENARIOS / "sweeps").glob("*.yaml"))
    assert cli.main(["validate", *shipped]) == cli.EXIT_OK
    out = capsys.readouterr().out
    assert out.count("valid") == len(shipped)
    bad = write_scenario(tmp_path, short_twist(**{"twist.ramp_s": "fast"}))
    assert cli.main(["validate", shipped[0], str(bad)]) == cli.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert str(bad) in err and "twist.ramp_s" in err and "Traceback" not in err
    assert not (tmp_path / "results").exists()


@pytest.mark.parametrize("argv, key", [
    (["run", str(SCENARIOS / "rig_ramp.yaml"), "--jobs", "2"], "--jobs"),       # a rig runs in one process
    (["run", str(SCENARIOS / "rig_table2.yaml"), "--k", "0"], "--k"),           # Table 2: adiabatic and isothermal
])
def test_options_that_do_not_apply_are_refused(argv, key, capsys, tmp_path):
    assert cli.main([*argv, "--out", str(tmp_path / "out")]) == cli.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert key in err and "does not apply" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_check_writes_a_json_and_junit_verdict(tmp_path, capsys):
    # two checks: one holds, one cannot (ΔQ/Q0 >= 0.5 on a 2 s twist that unloads < 0.1)
    path = write_scenario(tmp_path, short_twist(k_W_per_K=[0], checks=["dqq_max <= 0.6", "dqq_max[3R] >= 0.5"]))
    out = tmp_path / "out"
    assert cli.main(["check", str(path), "--quiet", "--out", str(out)]) == cli.EXIT_FAILED
    verdict = json.loads((out / "check.json").read_text())
    assert verdict["status"] == "fail"
    assert [c["status"] for c in verdict["checks"]] == ["pass", "fail"]
    assert verdict["checks"][1]["at"] == "k = 0, wheel 3R" and 0 < verdict["checks"][1]["value"] < 0.5
    suite = ET.parse(out / "check.xml").getroot()
    assert suite.tag == "testsuite" and suite.get("tests") == "2" and suite.get("failures") == "1"
    cases = suite.findall("testcase")
    assert cases[0].find("failure") is None and cases[1].find("failure") is not None


def test_validity_flags():
    rows = [{"k_W_per_K": 1.0, "pipe_mach_max": PIPE_MACH_MAX * 1.01, "T_bellow_max_K": 300.0},
            {"k_W_per_K": 2.0, "pipe_mach_max": PIPE_MACH_MAX * 0.99, "T_bellow_max_K": T_RANGE_K[1] + 1.0},
            {"k_W_per_K": 3.0, "stabilised": False, "T_bellow_min_K": T_RANGE_K[0] - 1.0},
            {"k_W_per_K": 4.0, "pipe_mach_max": float("nan"), "stabilised": True}]
    counts = flag_rows(rows)
    assert [r["validity"] for r in rows] == ["pipe_mach", "temperature", "temperature;unstabilised", "ok"]
    assert counts == {"pipe_mach": 1, "temperature": 2, "unstabilised": 1}
    assert failures(rows, allowed=("temperature",)) == ["k = 1: pipe_mach", "k = 3: unstabilised"]


@pytest.mark.slow
def test_a_run_outside_validity_is_flagged_and_fails_check(tmp_path, capsys):
    # the 15 Hz sine with k = 1 near the pipe resonance: a thermal runaway (paper §3)
    out = tmp_path / "out"
    code = cli.main(["run", str(SCENARIOS / "rig_sine_15hz.yaml"), "--k", "1", "--set", "test.duration_s=20",
                     "--out", str(out)])                 # not --quiet: it hides the printed warnings
    assert code == cli.EXIT_OK
    import csv
    row = next(csv.DictReader((out / "summary.csv").open()))
    assert "pipe_mach" in row["validity"]
    assert "outside the model's validity" in capsys.readouterr().err


def test_every_curve_of_a_panel_looks_different():
    styles = [curve_style(i) for i in range(40)]
    assert len(set(styles)) == 40


def test_errors_raised_in_workers_survive_pickling():
    # a worker's exception crosses the process boundary by pickle: it must arrive as itself
    import pickle

    from cosim.errors import ScenarioError
    from pneumatics.circuit import CircuitDiverged, CircuitError
    for error in (ScenarioError("s.yaml", ["circuit", "tank", "V_m3"], "must be > 0"),
                  CircuitError(["tank_FL", "p0_Pa"], "initial pressure is not set"),
                  CircuitDiverged(1.5, "FL", {"m_kg": -1.0}, "mass is not finite and positive")):
        copy = pickle.loads(pickle.dumps(error))
        assert type(copy) is type(error) and str(copy) == str(error)
        assert getattr(copy, "path", None) == getattr(error, "path", None)


def test_allowed_validity_flags_do_not_fail_check():
    import dataclasses

    from cosim.load import load_scenario
    from cosim.results.outcome import Outcome
    # no limits: the validity flag alone decides (with the scenario's dqq_max check and no
    # cases, the check's NaN value would fail it whatever the flags)
    s = dataclasses.replace(load_scenario(SCENARIOS / "twist_dqq.yaml"), checks=())
    rows = [{"k_W_per_K": 0.0, "validity": "temperature"}]
    assert Outcome(scenario=s, rows=rows).validity_failures() == ["k = 0: temperature"]
    assert not Outcome(scenario=s, rows=rows).checks_hold()
    allowed = dataclasses.replace(s, allow=("temperature",))
    assert Outcome(scenario=allowed, rows=rows).validity_failures() == []
    assert Outcome(scenario=allowed, rows=rows).checks_hold()


def test_an_explicit_circuits_valve_label_is_what_it_contains(tmp_path):
    # the throttled-tank example has no levelling valve: its runs are labelled valves off
    from cosim.load import load_scenario
    s = load_scenario(SCENARIOS / "twist_throttled_tanks.yaml")
    assert s.circuit.valves is False and s.experiment.valve_settings == (False,)


@pytest.mark.parametrize("quiet", [False, True])
def test_every_warning_of_a_run_is_printed_once_and_kept(tmp_path, capsys, monkeypatch, quiet):
    """One path for warnings, whatever the kind: one the kind only kept (as the ride's short record
    was) and one it logged as it went are each printed once on stderr, none with --quiet, and both
    are in run.json either way."""
    from cosim.kinds import KINDS
    from cosim.results.outcome import warn
    kind = KINDS["rig_table2"]
    original = kind.run

    def run_with_warnings(scenario, progress):
        outcome = original(scenario, progress)
        outcome.warnings.append("kept only")
        warn(outcome.warnings, "kept and logged")
        return outcome

    monkeypatch.setattr(kind, "run", run_with_warnings)
    out = tmp_path / "out"
    argv = ["run", str(SCENARIOS / "rig_table2.yaml"), "--out", str(out)] + (["--quiet"] if quiet else [])
    assert cli.main(argv) == cli.EXIT_OK
    err = capsys.readouterr().err
    for message in ("kept only", "kept and logged"):
        assert err.count(f"warning: {message}") == (0 if quiet else 1), err
        assert message in json.loads((out / "run.json").read_text())["warnings"]
