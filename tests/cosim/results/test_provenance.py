"""run.json: strict JSON holding every parameter value used, the hash of every file read, the
package versions and the source commit."""
from __future__ import annotations

import hashlib
import json

import pytest

from cosim.cli import main

from helpers import SCENARIOS


def _strict(text):
    def refuse(name):
        raise ValueError(f"bare {name} in run.json")
    return json.loads(text, parse_constant=refuse)


@pytest.mark.slow
def test_run_json_records_resolved_parameters_and_file_hashes(tmp_path):
    out = tmp_path / "run"
    assert main(["run", str(SCENARIOS / "twist_dqq.yaml"), "--k", "0,inf", "--set", "twist.ramp_s=0.5",
                 "--set", "twist.hold_s=0.5", "--set", "vehicle.carbody_mass_kg=16000", "--jobs", "1",
                 "--quiet", "--out", str(out)]) == 0
    info = _strict((out / "run.json").read_text())
    # files read, relative to the scenario file, with the hashes of their bytes
    assert info["files_sha256"] == {"twist_dqq.yaml": hashlib.sha256((SCENARIOS / "twist_dqq.yaml").read_bytes()).hexdigest()}
    resolved = info["resolved"]
    assert resolved["vehicle"]["carbody_mass_kg"] == 16000.0                # the override
    assert resolved["vehicle"]["bogie_mass_kg"] == 1900.0                   # from the preset paper_metro_car
    assert resolved["circuit_components"]["tank_FL"]["V_m3"] == 0.027       # a default actually used
    assert resolved["solver"]["macro_step_s"] > 0 and resolved["twist"]["hold_s"] == 0.5
    assert info["k_W_per_K"] == ["0", "inf"]
    assert "exudyn" in info["versions"]
    assert set(info["source"]) in (set(), {"commit", "dirty"})


def test_an_irregularity_file_is_hashed_with_the_scenario(tmp_path):
    import yaml
    data = yaml.safe_load((SCENARIOS / "straight_irregular.yaml").read_text())
    data["curve"]["irregularity"] = {"file": "track.csv"}
    (tmp_path / "track.csv").write_text("s_m,lateral_m\n0,0\n20,0\n30,0.001\n40,0\n")
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    from cosim.load import load_scenario
    files = dict(load_scenario(tmp_path / "s.yaml").files_sha256)
    assert files["track.csv"] == hashlib.sha256((tmp_path / "track.csv").read_bytes()).hexdigest()
    assert set(files) == {"s.yaml", "track.csv"}
