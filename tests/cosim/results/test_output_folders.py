"""Output folders: checked before anything runs, never mixed with another run, marked incomplete
when a run could not write everything."""
from __future__ import annotations

import errno
import subprocess

import pytest

from cosim.cli import main
from cosim.results import io as results
from cosim.results.outdir import INCOMPLETE, LOCK, default_folder

from helpers import SCENARIOS

SHORT = [str(SCENARIOS / "twist_dqq.yaml"), "--k", "0", "--set", "twist.ramp_s=0.2", "--set", "twist.hold_s=0.2",
         "--jobs", "1", "--quiet"]


def test_a_folder_under_a_regular_file_is_refused_before_simulating(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    assert main(["run", *SHORT, "--out", str(tmp_path / "file" / "run")]) == 2
    assert "--out" in capsys.readouterr().err
    assert main(["run", *SHORT, "--out", str(tmp_path / "file")]) == 2


@pytest.mark.slow
def test_a_previous_run_is_refused_unless_overwrite_which_clears_it(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", *SHORT, "--out", str(out)]) == 0
    assert not (out / INCOMPLETE).exists() and not (out / LOCK).exists()
    (out / "stale.csv").write_text("from another run")
    assert main(["run", *SHORT, "--out", str(out)]) == 2
    assert "previous run" in capsys.readouterr().err
    assert main(["run", *SHORT, "--out", str(out), "--overwrite"]) == 0
    assert not (out / "stale.csv").exists() and (out / "summary.csv").exists()


@pytest.mark.slow
def test_a_folder_another_live_run_writes_into_is_refused(tmp_path, capsys):
    out = tmp_path / "run"
    out.mkdir()
    other = subprocess.Popen(["sleep", "30"])
    try:
        (out / LOCK).write_text(str(other.pid))
        assert main(["run", *SHORT, "--out", str(out), "--overwrite"]) == 2
        assert f"process {other.pid}" in capsys.readouterr().err
    finally:
        other.kill()
        other.wait()
    # the lock of a process that no longer exists is stale: --overwrite takes the folder
    assert main(["run", *SHORT, "--out", str(out), "--overwrite"]) == 0


def test_a_write_failure_names_the_file_and_leaves_the_folder_marked_incomplete(tmp_path, capsys, monkeypatch):
    def disk_full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(results.np, "savetxt", disk_full)
    out = tmp_path / "run"
    assert main(["run", *SHORT, "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert "No space left" in err and "timeseries" in err and "Traceback" not in err
    assert (out / INCOMPLETE).exists() and not (out / LOCK).exists()
    assert not list(out.rglob(".*.tmp")) and not list(out.rglob("*.csv"))


def test_the_default_folder_reflects_overrides():
    base = default_folder("twist_dqq")
    assert str(base) == "results/twist_dqq"
    changed = default_folder("twist_dqq", ["twist.hold_s=10"])
    assert changed != base and str(changed).startswith("results/twist_dqq_")
    assert default_folder("twist_dqq", ["twist.hold_s=10"]) == changed          # reproducible
    assert default_folder("twist_dqq", k=[0.0]) not in (base, changed)
