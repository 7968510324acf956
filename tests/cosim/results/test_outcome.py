"""The application layer: runs return an in-memory Outcome with labelled time series, one writer
turns it into files, warnings are not progress."""
from __future__ import annotations

import csv
import subprocess
import sys

import numpy as np
import pytest

from cosim import cli
from cosim.load import load_scenario
from cosim.results.io import Progress
from cosim.runner import run, run_scenario
from vehicle.params import BELLOWS, WHEELS

from helpers import ROOT, SCENARIOS, short_twist, write_scenario


@pytest.fixture(scope="module")
def twist(tmp_path_factory):
    """A short twist, valves isolated and connected, k = 0 and inf, run in memory."""
    folder = tmp_path_factory.mktemp("twist")
    path = write_scenario(folder, short_twist(**{"twist.valve_settings": [False, True]}))
    return run(load_scenario(path)), folder


def test_a_car_run_returns_labelled_time_series(twist):
    outcome, _ = twist
    ds = outcome.series["twist"]
    assert list(ds["wheel"].values) == list(WHEELS) and list(ds["bellow"].values) == list(BELLOWS)
    # one case per valve setting x k, named as its CSV file, with its k and setting as coordinates
    assert list(ds["case"].values) == ["valves=off_k=0", "valves=off_k=inf", "valves=on_k=0", "valves=on_k=inf"]
    assert list(ds["valves"].values) == [False, False, True, True]
    assert ds["k_W_per_K"].values[1] == np.inf
    assert ds["wheel_load_N"].dims == ("time", "wheel", "case")
    for name in ("wheel_load_N", "bellow_p_Pa", "dqq", "roll_rad"):
        assert ds[name].attrs["units"] and ds[name].attrs["long_name"]
    # the summary rows are the labelled data's: dqq_max of every case is the max over time and wheels
    for row, case in zip(outcome.rows, ds["case"].values):
        assert row["dqq_max"] == ds["dqq"].sel(case=case).max().item()
        assert row["k_W_per_K"] == ds["k_W_per_K"].sel(case=case).item()
    # static equilibrium at t = 0: Q0 is each wheelset's mean load, ΔQ/Q0 starts at round-off
    assert np.abs(ds["dqq"].isel(time=0)).max() < 1e-9


@pytest.mark.slow
def test_the_writer_keeps_the_csv_layout_and_the_values(twist, tmp_path):
    outcome, _ = twist
    from cosim.kinds import twist as kind
    from cosim.results.writer import write_outcome
    write_outcome(outcome, tmp_path, kind.figures(outcome))
    ds = outcome.series["twist"]
    path = tmp_path / "timeseries" / "twist_valves=on_k=inf.csv"
    with path.open() as fh:
        header = next(csv.reader(fh))
    assert header[:2] == ["t_s", "Q_1L_N"] and "p_bellow_RR_Pa" in header and header[-1] == "dqq_4R"
    data = np.genfromtxt(path, delimiter=",", names=True)
    # written with 10 significant digits
    assert np.allclose(data["Q_3R_N"], ds["wheel_load_N"].sel(wheel="3R", case="valves=on_k=inf"), rtol=1e-9)
    assert np.allclose(data["t_s"], ds["time"], rtol=1e-9)
    rows = list(csv.DictReader((tmp_path / "summary.csv").open()))
    assert len(rows) == 4 and float(rows[2]["dqq_max"]) == pytest.approx(outcome.rows[2]["dqq_max"], rel=1e-9)
    assert {p.name for p in tmp_path.glob("*.png")} == {
        f"{f}_valves={v}.png" for f in ("fig8_wheel_loads", "dqq", "bellows") for v in ("on", "off")} | {
        "twist_along_track.png"}
    assert (tmp_path / "run.json").exists()


@pytest.mark.slow
def test_warnings_are_not_progress(tmp_path, capsys):
    # a 2 s twist does not settle: the warning is printed once among the progress lines; --quiet
    # hides both, and run.json keeps the warning either way
    import json
    path = write_scenario(tmp_path, short_twist(k_W_per_K=[0]))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "loud")]) == 0
    err = capsys.readouterr().err
    assert err.count("warning: k = 0: not settled") == 1 and "[" in err
    assert cli.main(["run", str(path), "--quiet", "--out", str(tmp_path / "out")]) == 0
    assert capsys.readouterr().err == ""           # no progress line ("[name  0.0 s] ..."), no warning
    for out in ("loud", "out"):
        info = json.loads((tmp_path / out / "run.json").read_text())
        assert any("not settled" in w for w in info["warnings"])


@pytest.mark.slow
def test_a_rig_runs_without_exudyn():
    # a fresh interpreter: loading and running a rig scenario needs only the pneumatics
    code = ("import sys; from cosim.load import load_scenario; from cosim.runner import run; "
            f"o = run(load_scenario({str(SCENARIOS / 'rig_table2.yaml')!r})); "
            "print(len(o.rows), any('exudyn' in m for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT).stdout
    assert out.split() == ["4", "False"]


def test_rig_time_series_are_labelled(tmp_path):
    s = load_scenario(SCENARIOS / "rig_ramp.yaml", ["test.duration_s=2", "test.samples=21", "test.ramp_s=1",
                                                    "test.configurations=[bellow_tank]"], [0.0])
    outcome = run_scenario(s, tmp_path, Progress("test", quiet=True))
    ds = outcome.series["ramp_bellow_tank_k=0"]
    assert list(ds["chamber"].values) == ["bellow", "tank"] and ds.attrs["k_W_per_K"] == 0.0
    data = np.genfromtxt(tmp_path / "timeseries" / "ramp_bellow_tank_k=0.csv", delimiter=",", names=True)
    assert list(data.dtype.names) == ["t_s", "z_m", "F_bellow_N", "pipe_mach", "p_bellow_Pa", "p_tank_Pa",
                                      "T_bellow_K", "T_tank_K"]
    assert np.allclose(data["F_bellow_N"], ds["F_bellow_N"], rtol=1e-9)
