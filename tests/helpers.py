"""Test helpers: a short, fast version of the twist scenario, written to a temporary file."""
from __future__ import annotations

from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"


def short_twist(**changes) -> dict:
    """The shipped twist scenario, shortened (1 s ramp, 1 s hold, k = 0 and inf, one process)."""
    data = yaml.safe_load((SCENARIOS / "twist_dqq.yaml").read_text())
    data["vehicle"] = "paper_metro_car"
    data["k_W_per_K"] = [0, float("inf")]
    data["twist"].update(ramp_s=1.0, hold_s=1.0)
    data["solver"].update(jobs=1)
    for key, value in changes.items():
        node = data
        *parents, last = key.split(".")
        for p in parents:
            node = node.setdefault(p, {})
        node[last] = value
    return data


def write_scenario(tmp_path: Path, data: dict, name: str = "scenario.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def vehicle_file(folder: Path, preset: str = "paper_metro_car") -> Path:
    """A vehicle parameter file written from a preset (``pneumorail presets NAME``)."""
    from cosim.scenario.presets import preset_yaml
    path = Path(folder) / f"{preset}.yaml"
    path.write_text(preset_yaml(preset))
    return path
