"""What compare reads from output folders goes through the one reader (issue 39): a time series
or a summary linked from outside the folder is refused, run.json must be an object, and a
sweep's folder points at its cases."""
from __future__ import annotations

import json

import pytest

from cosim.errors import ScenarioError
from cosim.results.overlay import Selection, case_series, run_info, worst_wheels


def _run(tmp_path):
    folder = tmp_path / "run"
    (folder / "timeseries").mkdir(parents=True)
    (folder / "run.json").write_text(json.dumps({"status": "complete"}))
    return folder


def test_a_time_series_linked_from_outside_is_refused(tmp_path):
    folder = _run(tmp_path)
    (tmp_path / "other.csv").write_text("t_s,x\n0,1\n1,2\n")
    (folder / "timeseries" / "twist_k=inf.csv").symlink_to(tmp_path / "other.csv")
    with pytest.raises(ScenarioError, match="symbolic link"):
        list(case_series(folder, "twist_", Selection()))
    (folder / "timeseries" / "twist_k=inf.csv").unlink()
    (folder / "timeseries" / "twist_k=inf.csv").write_text("t_s,x\n0,1\n1,2\n")
    [(label, data)] = case_series(folder, "twist_", Selection())
    assert label == "k = inf W/K" and list(data["x"]) == [1.0, 2.0]


def test_a_summary_that_is_a_device_is_refused(tmp_path):
    folder = _run(tmp_path)
    (folder / "summary.csv").symlink_to("/dev/zero")
    with pytest.raises(ScenarioError, match="summary.csv"):
        worst_wheels([folder])


def test_run_json_must_be_an_object(tmp_path):
    folder = _run(tmp_path)
    (folder / "run.json").write_text("[]")
    with pytest.raises(ScenarioError, match="JSON object"):
        run_info(folder)


def test_a_sweep_folder_points_at_its_cases(tmp_path):
    (tmp_path / "cases" / "abc").mkdir(parents=True)
    (tmp_path / "cases" / "abc" / "run.json").write_text("{}")
    with pytest.raises(ScenarioError, match="cases/<case>/") as err:
        run_info(tmp_path)
    assert str(tmp_path / "cases" / "abc") in str(err.value)
