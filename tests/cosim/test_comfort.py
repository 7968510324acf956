"""Ride comfort (EN 12299, ISO 2631, Sperling) on records whose answers are known: the weighting
filters against their transfer functions written here as polynomials (not the code's factored
form), indices of sums of sines whose periods divide the 5 s block, a measured-style record at
another rate with gravity and an offset, and the command's refusals."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cosim import cli
from cosim.limits.comfort import comfort, sperling_weighting, weighted


def _poly_response(f_Hz, f1, f2, f3, f4, q4, f5=None, q5=None, f6=None, q6=None, k=1.0):
    """|H(j 2 pi f)| of the standards' weighting as one rational polynomial in s (numerator and
    denominator multiplied out with numpy), an independent route to the same law."""
    w = [2 * math.pi * f if f else None for f in (f1, f2, f3, f4, f5, f6)]
    q1 = 1 / math.sqrt(2)
    num = np.polymul([1, 0, 0], [w[1] ** 2])                                  # high-pass s^2, low-pass w2^2
    den = np.polymul([1, w[0] / q1, w[0] ** 2], [1, w[1] / q1, w[1] ** 2])
    num = np.polymul(num, [w[3] ** 2 / w[2], w[3] ** 2])                      # transition
    den = np.polymul(den, [1, w[3] / q4, w[3] ** 2])
    if f5:
        num = np.polymul(num, np.array([1, w[4] / q5, w[4] ** 2]) * k / w[4] ** 2)
        den = np.polymul(den, np.array([1, w[5] / q6, w[5] ** 2]) / w[5] ** 2)
    else:
        num = num * k
    s = 2j * math.pi * np.asarray(f_Hz)
    return np.abs(np.polyval(num, s) / np.polyval(den, s))


WB = dict(f1=0.4, f2=100, f3=16, f4=16, q4=0.63, f5=2.5, q5=0.8, f6=4, q6=0.8, k=0.4)   # EN 12299 Wb
WD = dict(f1=0.4, f2=100, f3=2, f4=2, q4=0.63)                                          # Wd
FREQUENCIES = (0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 31.5, 63.0, 80.0)


@pytest.mark.parametrize("name, params", [("Wb", WB), ("Wd", WD)])
def test_the_weightings_follow_their_transfer_functions(name, params):
    # a sine of whole periods in a 10 s record at 1 kHz: the FFT weighting is exact for it, so the
    # amplitude ratio equals |H| to round-off (1e-9) at each of 9 frequencies from 0.5 to 80 Hz
    t = np.arange(0.0, 10.0, 0.001)
    for f in FREQUENCIES:
        out = weighted(t, np.sin(2 * math.pi * f * t), name)
        gain = math.sqrt(2 * np.mean(out ** 2))
        assert gain == pytest.approx(_poly_response(f, **params), rel=1e-9), f
    # the shape the standards describe: Wb 0.4 at low frequency rising to 1.024, Wd falling as 2/f
    assert _poly_response(1.0, **WB) == pytest.approx(0.4, rel=0.1) and _poly_response(8.0, **WB) > 0.95
    assert _poly_response(16.0, **WD) == pytest.approx(2 / 16, rel=0.1)


def _sines(t, parts):
    return sum(a * np.sin(2 * math.pi * f * t + 0.3) for a, f in parts)


PARTS = {"x": [(0.10, 1.0)], "y": [(0.20, 0.8), (0.05, 3.0)], "z": [(0.30, 1.2), (0.10, 6.0)]}


def _expected(parts, params):
    """Weighted rms of a sum of sines: √(Σ (|H| a)² / 2), the same in every 5 s block."""
    return math.sqrt(sum((_poly_response(f, **params) * a) ** 2 / 2 for a, f in parts))


def test_n_mv_of_sines_is_analytic():
    t = np.arange(0.0, 300.0, 0.0025)
    result = comfort(t, {a: _sines(t, p) for a, p in PARTS.items()})
    p95 = {"x": _expected(PARTS["x"], WD), "y": _expected(PARTS["y"], WD), "z": _expected(PARTS["z"], WB)}
    for a in "xyz":
        assert result.aP95_m_per_s2[a] == pytest.approx(p95[a], rel=1e-9)
    assert result.N_MV == pytest.approx(6 * math.sqrt(sum(v ** 2 for v in p95.values())), rel=1e-9)
    assert not result.warnings and result.duration_s == pytest.approx(300.0, abs=0.01)
    # Sperling's spectral form of one sine: (B(f)^2 (100 a)^2 / 2)^0.15
    single = comfort(t, {"z": 0.3 * np.sin(2 * math.pi * 2.0 * t)})
    assert single.Wz["z"] == pytest.approx((sperling_weighting(2.0, "z") ** 2 * 30.0 ** 2 / 2) ** 0.15, rel=1e-9)


def test_a_measured_record_at_another_rate_with_gravity_gives_the_same_comfort():
    # the same motion sampled at 400 Hz and at 150 Hz with jittered time stamps (resampled to a
    # uniform grid: the linear interpolation's error on a 6 Hz sine at 150 Hz, (2 pi 6/150)^2/8 =
    # 0.8 %, bounds the tolerance), gravity on az and an offset on ax: the same indices
    fine = np.arange(0.0, 300.0, 1 / 400)
    rng = np.random.default_rng(1)
    coarse = np.arange(0.0, 300.0, 1 / 150) + rng.uniform(-1e-4, 1e-4, 45000)
    coarse[0] = 0.0
    a = comfort(fine, {k: _sines(fine, p) for k, p in PARTS.items()})
    b = comfort(coarse, {"x": _sines(coarse, PARTS["x"]) + 0.05, "y": _sines(coarse, PARTS["y"]),
                         "z": _sines(coarse, PARTS["z"]) + 9.81})
    assert b.N_MV == pytest.approx(a.N_MV, rel=0.01)
    for k in "xyz":
        assert b.Wz[k] == pytest.approx(a.Wz[k], rel=0.01)


def _write(path, t, columns):
    header = "t_s," + ",".join(columns)
    rows = "\n".join(",".join(f"{v:.9g}" for v in row) for row in zip(t, *columns.values()))
    path.write_text(header + "\n" + rows + "\n")
    return path


def test_the_command_writes_the_indices(tmp_path):
    t = np.arange(0.0, 60.0, 0.005)
    record = _write(tmp_path / "ride.csv", t, {f"a{k}_m_per_s2": _sines(t, p) for k, p in PARTS.items()})
    assert cli.main(["comfort", str(record), "--out", str(tmp_path / "out")]) == 0
    info = json.loads((tmp_path / "out" / "comfort.json").read_text())
    for key in ("N_MV", "aXP95_m_per_s2", "aYP95_m_per_s2", "aZP95_m_per_s2", "Wz_y", "Wz_z"):
        assert isinstance(info[key], float), key
    assert "shorter than the 300 s" in info["warnings"][0]          # a minute: the result, with a warning
    assert (tmp_path / "out" / "comfort.png").stat().st_size > 10_000
    assert len((tmp_path / "out" / "comfort.csv").read_text().splitlines()) == 1 + 12   # twelve 5 s blocks


@pytest.mark.parametrize("make, message", [
    (lambda t: {"az_m_per_s2": np.zeros_like(t)}, "shorter than one 5 s block"),
    (lambda t: {"speed": np.zeros_like(t)}, "no acceleration column"),
])
def test_the_command_refuses_what_it_cannot_judge(tmp_path, capsys, make, message):
    t = np.arange(0.0, 4.0, 0.01)
    record = _write(tmp_path / "short.csv", t, make(t))
    assert cli.main(["comfort", str(record)]) == 2
    err = capsys.readouterr().err
    assert str(record) in err and message in err


def test_missing_axes_are_named(tmp_path, capsys):
    t = np.arange(0.0, 20.0, 0.01)
    record = _write(tmp_path / "z_only.csv", t, {"az_m_per_s2": _sines(t, PARTS["z"])})
    assert cli.main(["comfort", str(record), "--out", str(tmp_path / "o")]) == 0
    info = json.loads((tmp_path / "o" / "comfort.json").read_text())
    assert info["N_MV"] is None and any("missing: x, y" in w for w in info["warnings"])


def test_a_car_run_reports_the_comfort_of_each_floor_point():
    # the summary columns are the record's comfort: a Dataset of known floor accelerations
    import xarray as xr

    from cosim.kinds.comfort import comfort_columns
    t = np.arange(0.0, 30.0, 0.005)
    data = {f"floor_a{a}_m_per_s2": (("time", "floor_point"), np.stack([_sines(t, p) * s for s in (1.0, 0.5, 2.0)], 1))
            for a, p in PARTS.items()}
    case = xr.Dataset(data, coords={"time": t, "floor_point": ["front", "centre", "rear"]})
    columns = comfort_columns(case)
    for i, point in enumerate(("front", "centre", "rear")):
        direct = comfort(t, {a: case[f"floor_a{a}_m_per_s2"].values[:, i] for a in "xyz"})
        assert columns[f"N_MV_{point}"] == pytest.approx(direct.N_MV, rel=1e-12)
        assert columns[f"Wz_z_{point}"] == pytest.approx(direct.Wz["z"], rel=1e-12)
        assert columns[f"Cc_y_max_{point}_m_per_s2"] == pytest.approx(direct.Cc_max_m_per_s2["y"], rel=1e-12)
    assert columns["N_MV_rear"] == pytest.approx(4 * columns["N_MV_centre"], rel=1e-9)     # linear in the amplitude
    assert comfort_columns(case.isel(time=slice(0, 500))) == {}                            # 2.5 s: not one block


# ------------------------------------------------------------------------------ the ride kind
def _ride(tmp_path, **ride):
    import yaml

    from helpers import write_scenario
    data = yaml.safe_load((__import__("helpers").SCENARIOS / "ride_comfort.yaml").read_text())
    data["k_W_per_K"] = [float("inf")]
    data["solver"]["jobs"] = 1
    data["ride"].update({"speeds_m_per_s": [10.0, 20.0], "record_s": 6.0, "settle_s": 1.0, **ride})
    return write_scenario(tmp_path, data)


@pytest.mark.slow
def test_a_ride_gives_the_comfort_of_each_speed_over_its_record(tmp_path):
    import csv
    out = tmp_path / "ride"
    assert cli.main(["run", str(_ride(tmp_path)), "--out", str(out), "--quiet"]) == 0
    rows = list(csv.DictReader((out / "summary.csv").open()))
    assert [float(r["speed_m_per_s"]) for r in rows] == [10.0, 20.0]
    assert (out / "comfort_vs_speed.png").exists() and (out / "psd_floor.png").exists()
    # the summary's N_MV is the comfort command's on the same record (the floor point's columns
    # from the record's start on, written to a CSV of its own)
    series = np.genfromtxt(out / "timeseries" / "ride_v=20_valves=on_k=inf.csv", delimiter=",", names=True)
    keep = series["t_s"] >= float(rows[1]["record_from_s"])
    record = _write(tmp_path / "centre.csv", series["t_s"][keep],
                    {f"a{a}_m_per_s2": series[f"a{a}_centre_m_per_s2"][keep] for a in "xyz"})
    assert cli.main(["comfort", str(record), "--out", str(tmp_path / "c")]) == 0
    info = json.loads((tmp_path / "c" / "comfort.json").read_text())
    # the CSV keeps 9 significant digits: the same index to 1e-6
    assert float(rows[1]["N_MV_centre"]) == pytest.approx(info["N_MV"], rel=1e-6)
    assert cli.main(["compare", str(out)]) == 0


@pytest.mark.parametrize("change, where", [({"speeds_m_per_s": [10.0, -5.0]}, "ride.speeds_m_per_s[1]"),
                                            ({"record_s": 3.0}, "ride.record_s"),
                                            ({"radius_m": 0.0}, "ride.radius_m")])
def test_a_bad_ride_is_refused_before_it_runs(tmp_path, capsys, change, where):
    assert cli.main(["validate", str(_ride(tmp_path, **change))]) == 2
    assert where in capsys.readouterr().err


def test_verify_pairs_a_ride_case_by_its_speed():
    # two speeds with the same k and valves are two cases; pairing by k and valves alone would
    # let one speed's row hide the other's (it once did) -- now refused
    from cosim.kinds import KINDS
    from cosim.verification.verify import estimates
    levels = [[{"speed_m_per_s": v, "valves": True, "k_W_per_K": 0.0, "N_MV_centre": v / 10 + 0.01 * 2 ** -i}
               for v in (10.0, 20.0)] for i in range(3)]
    found = estimates(levels, ("N_MV_centre",), KINDS["ride"].case_columns)
    assert sorted(e.case for e in found) == ["speed_m_per_s=10, valves=True, k_W_per_K=0",
                                             "speed_m_per_s=20, valves=True, k_W_per_K=0"]
    with pytest.raises(ValueError, match="not one per"):
        estimates(levels, ("N_MV_centre",))
