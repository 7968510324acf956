"""Hostile comfort records (issue 39): time in ms, Unix time stamps, values beyond any car,
accelerations in g, a column twice, --point that does not exist, an --out that is a file, a device.
Each is refused (exit 2, no traceback) or warned with the file, the line or column or option, and
the unit it looks like; the editor's line numbers (comment lines count)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cosim import cli
from cosim.errors import ScenarioError
from cosim.results.comfort_files import read_record

#: a ride-like record: 30 s at 200 Hz (the shipped ride's output interval), sines on each axis,
#: gravity on z (an accelerometer at rest reads 1 g up)
T = np.arange(0.0, 30.0, 0.005)
ACCELERATIONS = {"x": 0.1 * np.sin(2 * math.pi * 1.0 * T), "y": 0.2 * np.sin(2 * math.pi * 1.5 * T),
                 "z": 9.81 + 0.3 * np.sin(2 * math.pi * 4.0 * T)}


def _write(path, t=T, columns=None, head="", header=None):
    columns = columns or {f"a{a}_m_per_s2": v for a, v in ACCELERATIONS.items()}
    header = header or "t_s," + ",".join(columns)
    rows = "\n".join(",".join(f"{v:.15g}" for v in row) for row in zip(t, *columns.values()))
    path.write_text(head + header + "\n" + rows + "\n")
    return path


def _refused(tmp_path, capsys, record, *extra):
    assert cli.main(["comfort", str(record), "--out", str(tmp_path / "out"), *extra]) == 2
    err = capsys.readouterr().err
    assert str(record) in err and "Traceback" not in err
    assert not (tmp_path / "out" / "comfort.json").exists()
    return err


def test_a_plain_record_is_accepted_with_gravity_in_m_per_s2(tmp_path):
    record = read_record(_write(tmp_path / "r.csv"))
    assert record.warnings == [] and record.t_s[0] == 0.0 and set(record.accelerations) == set("xyz")


def test_time_in_milliseconds_is_refused_naming_the_unit(tmp_path, capsys):
    # before: ZeroDivisionError (a 5 s block of 0 samples at a 5 "s" step)
    err = _refused(tmp_path, capsys, _write(tmp_path / "ms.csv", T * 1000.0))
    assert "t_s" in err and "milliseconds" in err


def test_unix_time_stamps_are_taken_from_the_first_sample_with_a_warning(tmp_path):
    shifted = read_record(_write(tmp_path / "unix.csv", T + 1.7e9))
    plain = read_record(_write(tmp_path / "plain.csv"))
    assert shifted.t_s[0] == 0.0 and "Unix" in shifted.warnings[0]
    # float64 keeps 1.7e9 s to 2.4e-7 s: the steps are the same to well within 1e-6 of 5 ms
    assert np.allclose(shifted.t_s, plain.t_s, atol=1e-6)


def test_one_unix_time_stamp_among_seconds_is_a_gap_at_its_line(tmp_path, capsys):
    # before: the resampler asked for 1.24 TiB
    t = T.copy()
    t[-1] = 1.7e9
    err = _refused(tmp_path, capsys, _write(tmp_path / "stamp.csv", t, head="# logger export\n"))
    assert f"line {T.size + 2}" in err and "Unix" in err         # the comment line counts


def test_a_value_beyond_any_car_is_refused(tmp_path, capsys):
    # before: StopIteration
    columns = {"az_m_per_s2": np.where(np.arange(T.size) == 7, 1e200, 9.81)}
    err = _refused(tmp_path, capsys, _write(tmp_path / "huge.csv", columns=columns))
    assert "line 9" in err and "az_m_per_s2" in err and "mm/s²" in err


def test_accelerations_in_g_are_refused_naming_g(tmp_path, capsys):
    # before: N_MV 0.060, exit 0
    columns = {f"a{a}_m_per_s2": v / 9.81 for a, v in ACCELERATIONS.items()}
    err = _refused(tmp_path, capsys, _write(tmp_path / "g.csv", columns=columns))
    assert "az_m_per_s2" in err and "in g" in err


def test_a_duplicated_column_is_refused(tmp_path, capsys):
    columns = {"az_m_per_s2": ACCELERATIONS["z"], "az": ACCELERATIONS["z"] * 2}
    record = _write(tmp_path / "twice.csv", columns=columns, header="t_s,az_m_per_s2,az_m_per_s2")
    err = _refused(tmp_path, capsys, record)
    assert "line 1.az_m_per_s2" in err and "twice" in err


def test_line_numbers_count_comment_lines(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("# exported\n# by a logger\nt_s,az_m_per_s2\n0,9.8\n0.005,x\n")
    with pytest.raises(ScenarioError) as err:
        read_record(path)
    assert err.value.path == "line 5"


def test_a_missing_floor_point_blames_the_option(tmp_path, capsys):
    columns = {f"a{a}_front_m_per_s2": v for a, v in ACCELERATIONS.items()}
    err = _refused(tmp_path, capsys, _write(tmp_path / "car.csv", columns=columns), "--point", "center")
    assert "--point" in err and "line 1" not in err and "front" in err


def test_an_out_that_is_a_file_is_refused_before_computing(tmp_path, capsys):
    # before: computed, then exit 1 claiming an INCOMPLETE marker
    out = tmp_path / "taken"
    out.write_text("")
    assert cli.main(["comfort", str(_write(tmp_path / "r.csv")), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--out" in err and "not a folder" in err and "INCOMPLETE" not in err


@pytest.mark.parametrize("path, words", [("/dev/zero", "device"), ("/", "folder")])
def test_what_is_not_a_file_is_refused(tmp_path, capsys, path, words):
    assert cli.main(["comfort", path, "--out", str(tmp_path / "o")]) == 2
    assert words in capsys.readouterr().err


def test_a_binary_record_is_refused(tmp_path, capsys):
    record = tmp_path / "bin.csv"
    record.write_bytes(bytes(range(256)) * 8)
    assert "UTF-8" in _refused(tmp_path, capsys, record)


def test_the_warning_reaches_comfort_json(tmp_path):
    out = tmp_path / "out"
    assert cli.main(["comfort", str(_write(tmp_path / "unix.csv", T + 1.7e9)), "--out", str(out)]) == 0
    assert any("Unix" in w for w in json.loads((out / "comfort.json").read_text())["warnings"])
