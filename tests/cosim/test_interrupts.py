"""SIGINT (Ctrl-C) and SIGTERM stop a run promptly, workers included, keep what it computed and
exit 130 / 143."""
from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

import pytest

from helpers import SCENARIOS


def _children(pid: int):
    out = subprocess.run(["ps", "-o", "pid=", "--ppid", str(pid)], capture_output=True, text=True).stdout
    return [int(p) for p in out.split()]


@pytest.mark.slow
@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_stops_the_run_keeps_its_results_and_leaves_no_worker(sig, code, tmp_path):
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-m", "cosim.cli", "run", str(SCENARIOS / "twist_dqq.yaml"),
                             "--k", "0,inf", "--jobs", "2", "--set", "twist.hold_s=600", "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 60
    while time.time() < deadline and len(_children(proc.pid)) < 2:   # both workers simulating
        time.sleep(0.2)
    time.sleep(2.0)
    workers = _children(proc.pid)
    proc.send_signal(sig)                    # to the main process only: it forwards to its workers
    try:
        _, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        pytest.fail("the run did not stop within 60 s of the signal")
    assert proc.returncode == code, err
    assert "Traceback" not in err and f"interrupted by {sig.name}" in err
    info = json.loads((out / "run.json").read_text())
    assert info["status"] == "interrupted"
    assert (out / "INCOMPLETE").exists() and (out / "summary.csv").exists()
    series = sorted((out / "timeseries").glob("*.csv"))
    assert len(series) == 2 and all(len(f.read_text().splitlines()) > 10 for f in series)   # computed samples kept
    time.sleep(0.5)
    alive = [p for p in workers if subprocess.run(["kill", "-0", str(p)], capture_output=True).returncode == 0]
    assert alive == []                       # no orphan worker
