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


def test_every_helper_pool_leaves_ctrl_c_to_its_parent():
    # a pool worker without a SIGINT disposition of its own prints a "Process ForkProcess-N:
    # Traceback ... KeyboardInterrupt" into the command's clean "interrupted" message: every
    # ProcessPoolExecutor of the application names an initializer (ignore_in_worker, or the
    # run's install_in_worker)
    import ast

    from helpers import ROOT
    bare = []
    for path in (ROOT / "cosim").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if (isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", "")) == "ProcessPoolExecutor"
                    and not any(k.arg == "initializer" for k in node.keywords)):
                bare.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert not bare, bare


def test_ctrl_c_inside_compiled_code_interrupts_a_serial_sweep_instead_of_failing_the_case():
    # exudyn turns a KeyboardInterrupt raised in a user function into a ModelError; a sweep in
    # one process then reported the case failed, with the traceback, and exited 1
    import os

    from cosim.sweep.executors import Serial

    def case(n):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1)
        except KeyboardInterrupt:
            raise RuntimeError("ModelError: KeyboardInterrupt in a user function") from None
        return n
    before = signal.getsignal(signal.SIGINT)
    with pytest.raises(KeyboardInterrupt):
        list(Serial().run(case, [("a", (1,)), ("b", (2,))]))
    assert signal.getsignal(signal.SIGINT) is before                    # restored
    assert [d.result for d in Serial().run(lambda n: n, [("a", (1,))])] == [1]
