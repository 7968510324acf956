"""Final-window statistics, check selectors (parsing, load-time errors, evaluation) and the
validation of the twist's EN 14363 and window keys. No simulation: each test runs in < 1 s."""
from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from cosim.errors import ScenarioError
from cosim.limits.checks import CaseMetrics
from cosim.limits.criteria import window_drift, window_mean
from cosim.load import load_scenario
from cosim.results.outcome import Outcome
from cosim.scenario.checks import Check
from vehicle.car import WHEELS

from helpers import SCENARIOS, short_twist, write_scenario


# ----------------------------------------------------------------------------- window statistics
def test_window_mean_of_an_oscillation_is_its_analytic_mean():
    """x = a + b sin(w t + p) + c t sampled every dt: the mean over [T - W, T] is
    a + c (T - W/2) + b (cos(w (T - W) + p) - cos(w T + p)) / (w W) -- not the last sample."""
    a, b, c, w, p = 0.3, 0.05, 1e-3, 2 * math.pi * 1.1, 0.4
    dt, T, W = 0.02, 40.0, 5.31                    # W: neither whole periods nor whole samples
    t = np.arange(0.0, T + dt / 2, dt)
    x = a + b * np.sin(w * t + p) + c * t
    exact = a + c * (T - W / 2) + b * (math.cos(w * (T - W) + p) - math.cos(w * T + p)) / (w * W)
    # trapezoidal rule: error <= dt^2/12 |x'(T) - x'(T-W)| / W <= dt^2 (b w + c) / (6 W), plus the
    # linear interpolation at the window's opening: <= b w^2 dt^2 / 8 over a part of one interval
    bound = dt ** 2 * (b * w + c) / (6 * W) + b * w ** 2 * dt ** 3 / (8 * W)
    assert abs(window_mean(t, x, W) - exact) <= bound
    assert abs(x[-1] - exact) > 100 * bound        # the last sample is not the mean
    # any trailing shape, samples first: (samples, 8, cases)
    stacked = np.stack([x, 2 * x], axis=-1)[:, None, :].repeat(8, axis=1)
    assert np.allclose(window_mean(t, stacked, W), [[exact, 2 * exact]] * 8, rtol=0, atol=2 * bound)


def test_window_mean_is_exact_for_piecewise_linear_series_and_spans_the_window():
    t = np.array([0.0, 1.0, 2.0, 4.0])
    x = np.array([5.0, 1.0, 3.0, -1.0])
    # window [1.5, 4]: x(1.5) = 2 by interpolation; area 0.5 (2 + 3)/2 + 2 (3 - 1)/2 = 3.25
    assert window_mean(t, x, 2.5) == pytest.approx(3.25 / 2.5, rel=1e-14)
    assert window_mean(t, x, 4.0) == pytest.approx((3.0 + 2.0 + 2.0) / 4.0, rel=1e-14)
    assert math.isnan(window_mean(t, x, 4.5))     # longer than the series: a run that stopped early
    with pytest.raises(ValueError):
        window_mean(t, x, 0.0)
    assert math.isnan(window_mean(t, np.array([1.0, 2.0, np.nan, 1.0]), 2.5))   # a diverged case


def test_window_drift_measures_the_trend_not_the_oscillation():
    dt, T, W = 0.02, 30.0, 5.0
    t = np.arange(0.0, T + dt / 2, dt)
    slope, b, w = 2e-4, 0.02, 2 * math.pi * 0.63        # 0.63 Hz: no whole number of periods in W
    ramp = 0.1 + slope * t
    # a straight line: the window mean moves by slope x W (the trapezoidal rule is exact)
    assert window_drift(t, ramp, W) == pytest.approx(slope * W, rel=1e-9)
    # an oscillation alone: each window mean is within 2 b / (w W) of 0, their difference
    # within 4 b / (w W) (0.2 b here), whatever the phase
    for phase in np.linspace(0.0, 2 * math.pi, 7):
        osc = b * np.sin(w * t + phase)
        assert window_drift(t, osc, W) <= 4 * b / (w * W)
        assert window_drift(t, ramp + osc, W) == pytest.approx(slope * W, abs=4 * b / (w * W))
    # samples first, any trailing shape; no earlier window: unknown (NaN), as for a diverged case
    assert np.allclose(window_drift(t, np.stack([ramp, 2 * ramp], axis=-1), W), [slope * W, 2 * slope * W], rtol=1e-9)
    assert math.isnan(window_drift(t[:11], ramp[:11], 0.2))
    assert math.isnan(window_drift(t, np.where(t > 29.0, np.nan, ramp), W))


# ----------------------------------------------------------------------------- check selectors
def en_data(**twist) -> dict:
    data = yaml.safe_load((SCENARIOS / "twist_en14363.yaml").read_text())
    data["vehicle"] = "paper_metro_car"
    data["twist"].update(twist)
    return data


def load(tmp_path, data):
    return load_scenario(write_scenario(tmp_path, data))


def checks_of(tmp_path, checks, data=None):
    data = data or en_data()
    data["checks"] = checks
    return load(tmp_path, data).checks


def test_check_selectors_parse(tmp_path):
    c = checks_of(tmp_path, ["dqq_max <= 0.6", "dqq_max[3R] <= 0.6", "dqq_max[k=0] <= 0.6", "dqq_qs_max <= 0.6",
                             "dqq_qs_max[1l, k=inf][valves=on] < 0.5", "dqq_drift[k = 100, valves=off] <= 1e-3",
                             "dqq_max[k=.inf]>=0"])
    assert c[0] == Check("dqq_max", "<=", 0.6, "dqq_max <= 0.6")
    assert (c[1].wheel, c[1].k, c[1].valves) == ("3R", None, None)
    assert (c[2].wheel, c[2].k, c[2].valves) == (None, 0.0, None)
    assert c[3].metric == "dqq_qs_max" and c[3].wheel is None
    assert (c[4].metric, c[4].op, c[4].limit, c[4].wheel, c[4].k, c[4].valves) == ("dqq_qs_max", "<", 0.5, "1L", math.inf, True)
    assert (c[5].metric, c[5].k, c[5].valves) == ("dqq_drift", 100.0, False)
    assert (c[6].op, c[6].k) == (">=", math.inf)
    # a twist without valve_settings has the one setting of circuit.valves
    assert checks_of(tmp_path, ["dqq_max[valves=off] <= 0.6"], short_twist())[0].valves is False


@pytest.mark.parametrize("text, reason", [
    ("dqq_max[9Z] <= 0.6", "unknown wheel '9Z'"),
    ("dqq_max[3r, 4L] <= 0.6", "wheel selected twice"),
    ("dqq_max[k=10] <= 0.6", "k = 10 is not one of the scenario's k values (0, 100, inf)"),
    ("dqq_max[k=0][k=inf] <= 0.6", "k selected twice"),
    ("dqq_max[k=-.inf] <= 0.6", "k = -.inf is not one of the scenario's k values"),
    ("dqq_max[valves=maybe] <= 0.6", "unknown selector 'valves=maybe'"),
    ("dqq_max[speed=3] <= 0.6", "unknown selector 'speed=3'"),
    ("dqq_max[3R <= 0.6", "expected 'metric <= number'"),
    ("dqq_max[3R] <= 1.2.3", "expected 'metric <= number'"),
    ("roll_max_rad <= 0.1", "unknown metric 'roll_max_rad' for a twist scenario"),
])
def test_bad_check_selectors_are_bad_input(tmp_path, text, reason):
    with pytest.raises(ScenarioError) as info:
        checks_of(tmp_path, ["dqq_max <= 0.6", text])
    assert info.value.path == "checks[1]" and reason in info.value.reason, info.value.reason


def test_selectors_are_checked_against_the_scenario(tmp_path):
    # the k list of --k overrides the file's
    path = write_scenario(tmp_path, {**en_data(), "checks": ["dqq_max[k=100] <= 0.6"]})
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, k_override=[0.0, math.inf])
    assert info.value.path == "checks[0]" and "(0, inf)" in info.value.reason
    # a valve setting the scenario does not run
    with pytest.raises(ScenarioError) as info:
        checks_of(tmp_path, ["dqq_max[valves=on] <= 0.6"], short_twist())
    assert info.value.path == "checks[0]" and "valves=on is not a valve setting of the scenario (off)" in info.value.reason
    # curve metrics have no wheel
    curve = yaml.safe_load((SCENARIOS / "curve_entry.yaml").read_text())
    curve["vehicle"] = "paper_metro_car"
    with pytest.raises(ScenarioError) as info:
        checks_of(tmp_path, ["roll_max_rad[1L] <= 0.05"], curve)
    assert info.value.path == "checks[0]" and "not a per-wheel metric" in info.value.reason
    c = checks_of(tmp_path, ["air_injected_kg[k=inf, valves=on] <= 0.05"], curve)[0]
    assert (c.k, c.valves, c.wheel) == (math.inf, True, None)


def _outcome(scenario, cases):
    return Outcome(scenario=scenario, rows=[{"k_W_per_K": c.k} for c in cases], cases=cases)


def test_checks_take_the_largest_value_over_the_selected_cases(tmp_path):
    s = load(tmp_path, {**en_data(), "checks": ["dqq_max <= 0.6", "dqq_max[1L] <= 0.3", "dqq_max[k=0] <= 0.3",
                                                "dqq_qs_max[valves=off, k=inf] <= 0.1", "dqq_max[4R][k=100][valves=on] > 0.25"]})
    rng = np.random.default_rng(1)
    cases = []
    for valves in (False, True):
        for k in (0.0, 100.0, math.inf):
            per_wheel = {w: float(v) for w, v in zip(WHEELS, rng.uniform(0.0, 0.2, 8))}
            cases.append(CaseMetrics(k, valves, wheels={"dqq_max": per_wheel,
                                                        "dqq_qs_max": {w: v / 2 for w, v in per_wheel.items()},
                                                        "dqq_drift": {w: 0.0 for w in WHEELS}}))
    cases[4].wheels["dqq_max"]["3R"] = 0.7              # valves on, k = 100, wheel 3R: the worst
    cases[4].wheels["dqq_max"]["4R"] = 0.3
    out = _outcome(s, cases)
    values = dict((c.text, out.check_value(c)) for c in s.checks)
    assert values["dqq_max <= 0.6"] == (0.7, "k = 100, valves on, wheel 3R")
    assert values["dqq_max[1L] <= 0.3"][0] == max(c.wheels["dqq_max"]["1L"] for c in cases)
    assert values["dqq_max[k=0] <= 0.3"][0] == max(max(c.wheels["dqq_max"].values()) for c in cases if c.k == 0)
    assert values["dqq_qs_max[valves=off, k=inf] <= 0.1"][0] == max(cases[2].wheels["dqq_qs_max"].values())
    assert values["dqq_max[4R][k=100][valves=on] > 0.25"] == (0.3, "k = 100, valves on, wheel 4R")
    held = [c.holds(v) for c, v in out.check_results()]
    assert held == [False, True, True, True, True] and not out.checks_hold()
    report = out.check_report()
    assert "dqq_max <= 0.6" in report and "FAIL" in report and "PASS" in report and "LIMIT VIOLATED" in report
    first = report.splitlines()[1]
    assert first.startswith("dqq_max <= 0.6") and "0.7" in first and "FAIL" in first and "k = 100, valves on, wheel 3R" in first
    # a diverged case (NaN) fails every check that includes it, not the others
    cases[0].wheels["dqq_max"]["2L"] = math.nan          # valves off, k = 0
    nan_out = _outcome(s, cases)
    assert math.isnan(nan_out.check_value(s.checks[0])[0]) and math.isnan(nan_out.check_value(s.checks[2])[0])
    assert nan_out.check_value(s.checks[4])[0] == 0.3


# ----------------------------------------------------------------------------- twist keys
@pytest.mark.parametrize("changes, where, reason", [
    (dict(window_s=200.0), "twist.window_s", "within the hold"),
    (dict(window_s=0.0), "twist.window_s", "> 0"),
    (dict(settle_drift=0.0), "twist.settle_drift", "> 0"),
    (dict(valve_settings=[]), "twist.valve_settings", "at least one"),
    (dict(valve_settings=[True, True]), "twist.valve_settings", "at most once"),
    (dict(bogie_base_m=2.5), "twist.bogie_base_m", "vehicle.wheelbase_m = 2 m"),
    (dict(base_m=12.0), "twist.base_m", "vehicle.bogie_centre_distance_m = 10 m"),
    (dict(raised_wheels=["1R", "3R"]), "twist.raised_wheels", "one side of the front bogie"),
    (dict(bogie_base_m=None, bogie_twist_per_mille=7.0), "twist.bogie_twist_per_mille", "needs its base"),
])
def test_bad_twist_keys(tmp_path, changes, where, reason):
    with pytest.raises(ScenarioError) as info:
        load(tmp_path, en_data(**changes))
    assert info.value.path == where and reason in info.value.reason, info.value


def test_twist_defaults_keep_the_papers_arrangement(tmp_path):
    s = load(tmp_path, short_twist())
    t = s.experiment
    assert t.bogie_base_m is None and t.bogie_height_m == 0.0 and t.valve_settings is None
    assert t.window == 1.0                      # default 5 s, clipped to the 1 s hold
    assert load_scenario(SCENARIOS / "twist_dqq.yaml").experiment.window == 5.0
    en = load_scenario(SCENARIOS / "twist_en14363.yaml").experiment
    assert en.height_m == pytest.approx(0.040, rel=1e-12) and en.bogie_height_m == pytest.approx(0.014, rel=1e-12)
    assert en.valve_settings == (False, True)


def test_curve_window_must_lie_within_the_run(tmp_path):
    curve = yaml.safe_load((SCENARIOS / "curve_entry.yaml").read_text())
    curve["vehicle"] = "paper_metro_car"
    curve["curve"]["window_s"] = 31.0
    with pytest.raises(ScenarioError) as info:
        load(tmp_path, curve)
    assert info.value.path == "curve.window_s" and "within the run" in info.value.reason


def test_a_lower_limit_is_about_the_smallest_value(tmp_path):
    """``metric >= limit`` is decided by the worst case, the smallest value (a critical speed that
    one k fails must fail the check, whatever the other k give)."""
    s = load(tmp_path, {**en_data(), "checks": ["dqq_max >= 0.05", "dqq_max[k=0] > 0.1", "dqq_max <= 0.6"]})
    cases = [CaseMetrics(k, valves, wheels={"dqq_max": {w: 0.2 + 0.01 * i + (0.1 if k else 0.0) for i, w in enumerate(WHEELS)},
                                            "dqq_qs_max": {w: 0.0 for w in WHEELS}, "dqq_drift": {w: 0.0 for w in WHEELS}})
             for valves in (False, True) for k in (0.0, 100.0, math.inf)]
    cases[3].wheels["dqq_max"]["2R"] = 0.01               # valves on, k = 0: the worst for a lower limit
    out = _outcome(s, cases)
    values = dict((c.text, out.check_value(c)) for c in s.checks)
    assert values["dqq_max >= 0.05"] == (0.01, "k = 0, valves on, wheel 2R")
    assert values["dqq_max[k=0] > 0.1"][0] == 0.01
    assert values["dqq_max <= 0.6"][0] == pytest.approx(0.37)
    assert [c.holds(v) for c, v in out.check_results()] == [False, False, True]


# ----------------------------------------------------------------------------- missing values
def _zoned(**zones) -> CaseMetrics:
    return CaseMetrics(0.0, False, zones={"yq_2m_p9985": {z: {"1L": v} for z, v in zones.items()}})


def test_a_check_without_a_value_is_an_error_naming_the_case_and_the_metric():
    """A value a check covers that is missing -- NaN (a case that stopped) or never computed -- is
    an ``error`` saying which case and metric, never a violation of NaN and never a pass; a value
    that violates the limit fails the check whatever else is missing."""
    from cosim.limits.checks import ERROR, FAIL, PASS, evaluate
    check = Check("yq_2m_p9985", "<=", 1.2, "yq_2m_p9985 <= 1.2")
    zoned = Check("yq_2m_p9985", "<=", 1.2, "z", zone="R<250")
    fine, stopped = _zoned(straight=0.4), CaseMetrics(math.inf, False, zones={"yq_2m_p9985": {"straight": {"1L": math.nan}}})
    r = evaluate(check, [fine])
    assert (r.status, r.value, r.where, r.reason) == (PASS, 0.4, "k = 0, straight, wheel 1L", "")
    r = evaluate(check, [fine, stopped])                          # the worst may be the one missing
    assert r.status == ERROR and math.isnan(r.value) and r.reason == "no value: yq_2m_p9985 is NaN in k = inf"
    r = evaluate(check, [CaseMetrics(0.0, False)])             # the case has no such metric at all
    assert r.status == ERROR and math.isnan(r.value) and r.reason == "no value: k = 0 has no yq_2m_p9985"
    r = evaluate(zoned, [fine])                                  # the run did not reach the zone
    assert r.status == ERROR and r.reason == "no value: k = 0 has no yq_2m_p9985 in zone R<250"
    r = evaluate(check, [_zoned(straight=1.3), stopped])         # a violation is a violation
    assert r.status == FAIL and r.value == 1.3 and "is NaN in k = inf" in r.reason
    for metric in ("roll_max_rad", "dqq_max"):                   # plain and per-wheel metrics alike
        r = evaluate(Check(metric, "<=", 1.0, metric, wheel="3R" if metric == "dqq_max" else None),
                     [CaseMetrics(0.0, True, {"roll_max_rad": math.nan}, {"dqq_max": {"1L": 0.1}})])
        assert r.status == ERROR and math.isnan(r.value), r


def test_check_and_its_files_say_error_for_a_check_without_a_value(tmp_path):
    """``pneumorail check``'s verdict (check.json, check.xml, the text) through the same path: the
    check without a value is an error with its reason (a JUnit <error>), the run's status
    ``error``, the last line not a violation."""
    import xml.etree.ElementTree as ET

    from cosim.results.writer import write_verdict
    s = load(tmp_path, {**en_data(), "checks": ["dqq_max <= 0.6", "dqq_qs_max <= 0.6"]})
    cases = [CaseMetrics(k, v, wheels={"dqq_max": {w: 0.2 for w in WHEELS}}) for v in (False, True)
             for k in (0.0, 100.0, math.inf)]
    out = _outcome(s, cases)
    verdict = out.verdict()
    assert verdict["status"] == "error" and [c["status"] for c in verdict["checks"]] == ["pass", "error"]
    assert verdict["checks"][1]["message"].startswith("no value: k = 0, valves off has no dqq_qs_max;")
    report = out.check_report().splitlines()
    assert "ERROR" in report[2] and "k = inf, valves on has no dqq_qs_max" in report[2] and "nan" not in report[2]
    assert report[-1] == "ERROR: a check has no value" and not out.checks_hold()
    write_verdict(out, tmp_path)
    suite = ET.parse(tmp_path / "check.xml").getroot()
    assert (suite.get("failures"), suite.get("errors")) == ("0", "1")
    assert suite.find("testcase[@name='dqq_qs_max <= 0.6']/error").get("message") == verdict["checks"][1]["message"]
    # a diverged run: its NaN is an error that says the run diverged; the divergence fails the run
    import dataclasses
    cases[0].wheels["dqq_max"]["2L"] = math.nan
    stopped = dataclasses.replace(_outcome(s, cases), diagnoses=["k = 0, valves off: diverged at t = 3 s"])
    items = stopped.verdict()["checks"]
    assert items[0]["status"] == "error" and items[0]["message"].endswith("(the run diverged)")
    assert items[-1] == {"name": "run completes", "status": "fail", "message": "k = 0, valves off: diverged at t = 3 s"}
    assert stopped.verdict()["status"] == "fail" and stopped.check_report().endswith("LIMIT VIOLATED")
