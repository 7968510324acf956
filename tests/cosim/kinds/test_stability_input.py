"""A stability scenario's wheel profile is read at load (issue 39): garbage, a profile in metres or
a rail profile is refused by ``validate`` (exit 2, the key and the file named), not after the run
started with a traceback."""
from __future__ import annotations

import pytest
import yaml

from cosim import cli

from helpers import ROOT, SCENARIOS, write_scenario

DATA = ROOT / "vehicle" / "wheelrail" / "data"


def _scenario(tmp_path, profile_name):
    data = yaml.safe_load((SCENARIOS / "stability.yaml").read_text())
    data["stability"]["wheel_profile"] = profile_name
    return write_scenario(tmp_path, data)


def _metres(tmp_path):
    """The shipped S1002 wheel as a y z table in metres instead of mm."""
    from vehicle.wheelrail.profiles import read_profile
    wheel = read_profile(DATA / "MBench_S1002_v3.prw")
    path = tmp_path / "wheel_m.txt"
    path.write_text("\n".join(f"{float(y) / 1000!r} {float(z) / 1000!r}" for y, z in zip(wheel.y_mm, wheel.z_mm)) + "\n")
    return path.name, "metres"


def _garbage(tmp_path):
    (tmp_path / "wheel.txt").write_text("this is not\na profile at all\n")
    return "wheel.txt", "not a table"


def _binary(tmp_path):
    (tmp_path / "wheel.prw").write_bytes(bytes(range(256)) * 8)
    return "wheel.prw", "binary"


def _rail(tmp_path):
    return str(DATA / "MBench_UIC60_v3.prr"), "'rail'"


@pytest.mark.parametrize("make", [_metres, _garbage, _binary, _rail])
def test_a_bad_wheel_profile_is_refused_at_load(tmp_path, capsys, make):
    name, words = make(tmp_path)
    scenario = _scenario(tmp_path, name)
    assert cli.main(["validate", str(scenario)]) == 2
    err = capsys.readouterr().err
    assert "stability.wheel_profile" in err and str(scenario) in err and words in err and "Traceback" not in err
    assert name.split("/")[-1] in err                                # the profile file named too


def test_the_shipped_wheel_profile_is_accepted(tmp_path, capsys):
    assert cli.main(["validate", str(_scenario(tmp_path, str(DATA / "MBench_S1002_v3.prw")))]) == 0
