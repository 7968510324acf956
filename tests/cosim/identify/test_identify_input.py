"""Hostile identification input (issue 39): records in other units, a column twice, line numbers
as the editor shows them, a nominal --k that has no logarithm, the default output folder. Each
refusal names the file, the line or option, the column and the unit it looks like."""
from __future__ import annotations

import csv

import pytest

from cosim import cli
from cosim.errors import ScenarioError
from cosim.identify.data import read_measurements

from helpers import ROOT

EXAMPLE = ROOT / "examples" / "identify"
SCENARIO = EXAMPLE / "rig_sine_60s.yaml"


def _example(tmp_path, change=None, name="data.csv"):
    """The shipped synthetic record (a comment line, then the header at line 2) with ``change``
    applied to each data row (a dict column -> value, floats)."""
    with (EXAMPLE / "sine_k10.csv").open() as fh:
        lines = fh.read().splitlines()
    header = lines[1].split(",")
    rows = [dict(zip(header, map(float, line.split(",")))) for line in lines[2:]]
    for row in rows:
        (change or (lambda r: None))(row)
    path = tmp_path / name
    with path.open("w", newline="") as fh:
        fh.write(lines[0] + "\n")
        writer = csv.DictWriter(fh, header)
        writer.writeheader()
        writer.writerows(rows)
    return path


def _scale(column, factor, offset=0.0):
    def change(row):
        row[column] = row[column] * factor + offset
    return change


@pytest.mark.parametrize("column, change, unit", [
    ("p_bellow_Pa", _scale("p_bellow_Pa", 1e-5), "bar"),
    ("p_bellow_Pa", _scale("p_bellow_Pa", 1e-3), "kPa"),
    ("T_bellow_K", _scale("T_bellow_K", 1.0, -273.15), "°C"),
    ("z_m", _scale("z_m", 1e3), "millimetres"),
])
def test_a_column_in_another_unit_is_refused_naming_the_unit(tmp_path, column, change, unit):
    path = _example(tmp_path, change)
    with pytest.raises(ScenarioError) as err:
        read_measurements(path)
    line, name = err.value.path.split(".", 1)
    assert name == column and line.startswith("line ") and unit in err.value.reason and str(path) in str(err.value)
    # the line is the editor's: the comment line counts (header at 2, first row at 3)
    n = int(line.split()[1]) - 1
    assert path.read_text().splitlines()[n].split(",")[0] != "t_s"


def test_the_unchanged_example_is_accepted(tmp_path):
    data = read_measurements(_example(tmp_path))
    assert data.kind == "time" and set(data.channels) == {"F_bellow_N", "p_bellow_Pa", "T_bellow_K"}


def test_line_numbers_count_comment_lines(tmp_path):
    path = tmp_path / "data.csv"
    path.write_text("# a comment\n\n# another\nt_s,z_m,F_bellow_N\n0,0,1\n1,0,1\n2,0,x\n3,0,1\n4,0,1\n5,0,1\n")
    with pytest.raises(ScenarioError) as err:
        read_measurements(path)
    assert err.value.path == "line 7.F_bellow_N"


def test_a_duplicated_column_is_refused(tmp_path):
    path = tmp_path / "data.csv"
    path.write_text("t_s,z_m,F_bellow_N,F_bellow_N\n" + "".join(f"{i},0,1,2\n" for i in range(6)))
    with pytest.raises(ScenarioError, match="appears twice") as err:
        read_measurements(path)
    assert err.value.path == "line 1.F_bellow_N"


@pytest.mark.parametrize("k", ["-1", "nan", "inf", "0"])
def test_plan_refuses_a_nominal_k_without_a_logarithm(capsys, k):
    assert cli.main(["identify", str(SCENARIO), "--plan", "--k", k]) == 2
    err = capsys.readouterr().err
    assert "--k" in err and str(SCENARIO) in err and "Traceback" not in err


def test_a_device_as_data_is_refused_before_anything_runs(capsys):
    assert cli.main(["identify", str(SCENARIO), "--data", "/dev/zero"]) == 2
    err = capsys.readouterr().err
    assert "/dev/zero" in err and "--data" in err and "device" in err


def test_an_out_that_is_a_file_is_refused_before_the_fit(tmp_path, capsys):
    out = tmp_path / "taken"
    out.write_text("")
    assert cli.main(["identify", str(SCENARIO), "--data", str(_example(tmp_path)), "--out", str(out)]) == 2
    assert "--out" in capsys.readouterr().err and out.read_text() == ""


def test_the_default_output_is_under_results_not_beside_the_data():
    # before: examples/identify/identify_sine_k10/, in the source tree
    from pathlib import Path

    def out(*extra):
        args = cli.build_parser().parse_args(["identify", str(SCENARIO), "--data", str(EXAMPLE / "sine_k10.csv"), *extra])
        return cli._identify_out(args, args.fit.split(","))
    assert out() == Path("results") / "identify_sine_k10"
    assert out("--fit", "k_W_per_K,circuit.pipe.zeta").name.startswith("identify_sine_k10_")
    assert out("--out", "x") == Path("x")
