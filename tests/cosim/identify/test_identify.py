"""Identifying k from rig data (cosim.identify): input checks, the complex stiffness against its
closed form, recovery of a known k with an honest interval, the limits k = 0 and inf.

The synthetic records are made by scipy's LSODA (cosim.identify.synthetic), the fits run the
fixed-step RK4 of the model: two integrators, so a recovery is not the model fitting its own
numbers. Tolerances: the issue's 5 % at low noise; the true k within the 95 % interval of one
record, within the 99.9 % one where three records share a seed (a 95 % interval misses the truth
of one record in 20); the estimate the minimum of its own cost (assert_minimum_of_its_cost)."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
import yaml
from scipy.stats import chi2

from cosim import cli
from cosim.errors import ScenarioError
from cosim.identify.data import read_measurements
from cosim.identify.fit import CHI2_95, fit_k
from cosim.identify.model import RigModel
from cosim.identify.synthetic import NOISE, sine_record, write_csv
from pneumatics.chamber import Bellow
from pneumatics.rig import dynamic_stiffness_sweep

from helpers import SCENARIOS


def rig_scenario(tmp_path, duration_s: float, frequency_Hz: float = 1.0):
    data = yaml.safe_load((SCENARIOS / "rig_sine_1hz.yaml").read_text())
    data["test"].update(duration_s=duration_s, frequency_Hz=frequency_Hz)
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def record(tmp_path, k, seed=1, noise_scale=1.0, duration_s=60.0, frequency_Hz=1.0):
    scenario = rig_scenario(tmp_path, duration_s, frequency_Hz)
    noise = {c: v * noise_scale for c, v in NOISE.items()}
    return scenario, write_csv(tmp_path / f"k{k:g}.csv", sine_record(scenario, k, noise, seed))


@pytest.mark.parametrize("text, where, words", [
    ("t_s,F_bellow_N\n" + "".join(f"{i},1\n" for i in range(6)), "z_m", "needs the crushing"),
    ("t_s,z_m,F_N\n" + "".join(f"{i},0,1\n" for i in range(6)), "F_N", "unknown column"),
    ("t_s,z_m,F_bellow_N\n" + "".join(f"{i % 3},0,1\n" for i in range(6)), "t_s", "must increase"),
    ("t_s,z_m,F_bellow_N\n0,0,1\n1,0,x\n2,0,1\n3,0,1\n4,0,1\n5,0,1\n", "line 3.F_bellow_N", "expected a number"),
    ("t_s,z_m,F_bellow_N\n0,0,1\n1,0,1\n", "(top level)", "at least 5 rows"),
    ("frequency_Hz,K_abs_N_per_m\n" + "".join(f"{i + 1},1\n" for i in range(6)), "header", "loss_angle_deg"),
])
def test_bad_data_is_refused_naming_the_column(tmp_path, text, where, words):
    path = tmp_path / "data.csv"
    path.write_text(text)
    with pytest.raises(ScenarioError) as err:
        read_measurements(path)
    assert err.value.path == where and words in err.value.reason


def test_bad_keys_exit_2_before_anything_runs(tmp_path, capsys):
    scenario, data = tmp_path / "rig.yaml", tmp_path / "d.csv"
    scenario.write_text((SCENARIOS / "rig_sine_1hz.yaml").read_text())
    data.write_text("t_s,z_m,F_bellow_N\n" + "".join(f"{i},0,1\n" for i in range(6)))
    for fit, words in (("circuit.pipe.model", "not a number"), ("solver.macro_step_s", "a key of the rig's circuit"),
                       ("circuit.bellow.dA_dz_m", "only a key whose value is > 0")):
        assert cli.main(["identify", str(scenario), "--data", str(data), "--fit", fit]) == cli.EXIT_BAD_INPUT
        err = capsys.readouterr().err
        assert words in err and "Traceback" not in err
    assert cli.main(["identify", str(SCENARIOS / "twist_dqq.yaml"), "--data", str(data)]) == cli.EXIT_BAD_INPUT
    assert "rig scenarios" in capsys.readouterr().err


@pytest.mark.parametrize("k", [0.0, math.inf])
def test_complex_stiffness_of_a_closed_bellow_is_its_polytropic_stiffness_without_loss(k):
    """A closed bellow (no tank, no pipe) under a 0.2 mm sine: adiabatic (k = 0) or isothermal (k =
    inf), the air is a spring without loss: K' = n A^2 p0 / V (n = gamma or 1), K'' = 0. The
    amplitude makes the spring's nonlinearity ~ (A a / V)^2 ~ 5e-6, the RK4 error smaller."""
    bellow = Bellow()
    p0 = 4.0e5
    [point] = dynamic_stiffness_sweep({"bellow": bellow}, [k], [1.0], 2e-4, {"bellow": p0})
    n = 1.4 if k == 0.0 else 1.0
    expected = n * bellow.A0_m2 ** 2 * p0 / bellow.V0_m3
    assert point.K_storage_N_per_m == pytest.approx(expected, rel=1e-4)
    assert abs(point.K_loss_N_per_m) < 1e-6 * expected


def test_k_is_recovered_within_its_interval_from_a_short_record(tmp_path):
    """10 s of a 20 mm, 1 Hz sine at k = 100 W/K (thermal time constants ~0.4 and ~0.9 s, well inside
    the record), the example's noise: the estimate within 2 % and its 95 % interval holds 100."""
    scenario, path = record(tmp_path, 100.0, duration_s=10.0)
    result = fit_k(RigModel(scenario, (), read_measurements(path)))
    e = result.estimates[0]
    assert e.value == pytest.approx(100.0, rel=0.02) and e.ci_low <= 100.0 <= e.ci_high
    assert e.ci_low < e.value - e.se < e.value + e.se < e.ci_high      # a 95 % interval is wider than +- 1 se
    assert not result.warnings


def cost_at(model, sigma, ks):
    """S at each k of ``ks`` for the noise ``sigma``, from a fresh run of the model (not the fit's)."""
    pred = model.predict(ks)
    return [sum(float(np.sum((pred[c][i] - v) ** 2)) / sigma[c] ** 2 for c, v in model.data.channels.items())
            for i in range(len(ks))]


def assert_minimum_of_its_cost(model, result):
    """The estimate is the minimum of the cost it reports. On its profile: no point below S_min (S
    and S_min are sums of the same three channel terms, so only summation round-off, ~1e-16 of S,
    could differ; 1e-12 of S allows it with room). Off its profile: S from a fresh run of the
    model rises each side at 0.1 standard errors. Near a minimum S - S_min = (offset / se)^2, so
    the rise is 0.1^2 = 0.01, at least 0.01 - 2 x 0.1 x 0.01 = 0.008 from an estimate within the
    fit's 0.01 se of the minimum; an estimate 0.05 se off gives 0 on one side. The margin 0.005
    is far above the model's round-off in S (~3e-6 on the noise-free record, where the residuals
    are smallest against the signals: S's spread over k within 1e-4 se of each other)."""
    e, p = result.estimates[0], result.profiles[0]
    assert np.min(p.delta_S) >= -1e-12 * result.cost, f"S - S_min down to {np.min(p.delta_S):.4g} on the profile"
    step = math.exp(0.1 * e.se / e.value)                   # se / k is the standard error of ln k
    S_minus, S_best, S_plus = cost_at(model, result.sigma, [e.value / step, e.value, e.value * step])
    assert S_best == pytest.approx(result.cost, rel=1e-12)   # the model's columns do not depend on the batch
    assert S_minus - S_best > 0.005 and S_plus - S_best > 0.005, (S_minus - S_best, S_plus - S_best)
    assert e.ci_low < e.value < e.ci_high


class LopsidedModel:
    """A stand-in for RigModel whose cost is known in closed form. One channel of n points: measured
    y_i = +-s alternately (the 'noise', summing to 0), predicted g = exp(c (theta - theta0)) - 1 at
    every point (theta = log10 k), so S = n (g^2 + s^2) / sigma^2: the minimum at theta0 exactly,
    the noise there sigma^2 = n s^2 / (n - 1), the standard error of theta sqrt(2 / S'') =
    sigma / (c sqrt n) = s / (c sqrt(n - 1)), and the 95 % interval where g = +-sqrt(3.84) c se.
    g rises faster than it falls: S is lopsided, by 10 % over a Newton stencil of d = 0.01 (c d =
    0.05 at c = 5), whose steps drift towards where S(theta + d) = S(theta - d), ln(cosh(c d)) / c
    = 2.5e-4 below theta0 (25 standard errors at se = 1e-5)."""

    def __init__(self, theta0: float, c: float, se: float, n: int = 200):
        self.theta0, self.c = theta0, c
        s = se * c * math.sqrt(n - 1)
        self.data = SimpleNamespace(channels={"F_bellow_N": s * (-1.0) ** np.arange(n)}, n=n)

    def predict(self, ks, others=()):
        with np.errstate(divide="ignore"):                   # k = 0: theta = -inf, g = -1
            g = np.expm1(self.c * (np.log10(np.asarray(ks, float)) - self.theta0))
        return {"F_bellow_N": np.repeat(g[:, None], self.data.n, axis=1)}


def test_estimate_is_the_minimum_of_a_lopsided_cost_known_in_closed_form():
    """The estimate within the fit's 0.01 standard errors of the exact minimum; the standard error
    exact but for the stencil's even part, (7/12) (c d)^2 = 0.15 % of S'' (so 0.3 % allowed); the
    interval's ends at the exact crossings to 1 % of the half-width (the linear interpolation
    loses at most 0.5 %)."""
    theta0, c, se = math.log10(7.0), 5.0, 1e-5
    result = fit_k(LopsidedModel(theta0, c, se))
    e, p = result.estimates[0], result.profiles[0]
    theta, se_fit = math.log10(e.value), e.se / (e.value * math.log(10))
    assert abs(theta - theta0) <= 0.01 * se, (theta - theta0) / se
    assert np.min(p.delta_S) >= -1e-12 * result.cost           # the profile: sums of the same terms
    assert se_fit == pytest.approx(se, rel=3e-3)
    for end, side in ((e.ci_low, -1), (e.ci_high, 1)):
        exact = theta0 + math.log1p(side * math.sqrt(CHI2_95) * c * se) / c
        assert math.log10(end) == pytest.approx(exact, abs=0.01 * abs(exact - theta0))


def test_noise_free_estimate_is_the_minimum_of_its_lopsided_cost(tmp_path):
    """A noise-free 10 s record at k = 10 W/K: the residuals are the fitting model's own error
    (RK4 and a spline through the crushing against LSODA), so the standard error of k is ~2e-6
    of k and the cost, lopsided over a stencil 2.3 % of k wide (1.3 % between its sides, 12000
    standard errors out), is a parabola over the interval (its cubic part there ~2e-6). So: the
    estimate is the minimum of its cost; each side of its interval is sqrt(3.84) standard errors
    to 2 % (the linear interpolation of the crossing may lose 0.5 %; S'' on the stencil and on
    +-1 standard error differ by 4e-5 here); k is recovered to 1e-4: the quintic spline's rate
    biases k by ~3e-5 (a cubic's by 6e-4, docs/identify.md, ~20 times less), RK4 at 2 ms is
    ~4e-8 of the force (cosim.identify.model)."""
    scenario, path = record(tmp_path, 10.0, noise_scale=0.0, duration_s=10.0)
    model = RigModel(scenario, (), read_measurements(path))
    result = fit_k(model)
    assert_minimum_of_its_cost(model, result)
    e = result.estimates[0]
    half = math.sqrt(CHI2_95) * e.se / e.value                 # the quadratic half-width in ln k
    assert math.log(e.value / e.ci_low) == pytest.approx(half, rel=0.02)
    assert math.log(e.ci_high / e.value) == pytest.approx(half, rel=0.02)
    assert e.value == pytest.approx(10.0, rel=1e-4)
    assert not result.warnings


def test_noisy_estimate_is_the_minimum_of_its_cost(tmp_path):
    """A 10 s record at the example's noise, k = 10 W/K: the estimate is the minimum of its own
    cost and profile, and its interval holds it."""
    scenario, path = record(tmp_path, 10.0, duration_s=10.0)
    model = RigModel(scenario, (), read_measurements(path))
    assert_minimum_of_its_cost(model, fit_k(model))


@pytest.mark.slow
@pytest.mark.parametrize("k", [0.5, 10.0, 100.0])
def test_recovery_at_low_noise(tmp_path, k):
    """The issue's recovery table: 60 s records at a tenth of the example's noise: within 5 % of the
    truth (measured: within 0.3 % at the full noise), the estimate the minimum of its cost, and the
    truth inside the 99.9 % profile interval: S(k) - S_min below chi2_1(0.999) = 10.8. Not the
    95 % one, which misses the truth of one record in 20, as it does at this seed for k = 100
    (the minimum 2.0 standard errors from 100): its coverage over 50 seeds is
    benchmarks/identify_coverage.py's."""
    scenario, path = record(tmp_path, k, seed=11, noise_scale=0.1)
    model = RigModel(scenario, (), read_measurements(path))
    result = fit_k(model)
    e = result.estimates[0]
    assert e.value == pytest.approx(k, rel=0.05), e
    assert_minimum_of_its_cost(model, result)
    [S_true] = cost_at(model, result.sigma, [k])
    assert S_true - result.cost < chi2.ppf(0.999, 1), (e, S_true - result.cost)


@pytest.mark.slow
@pytest.mark.parametrize("k, limit", [(0.0, "0"), (math.inf, "inf")])
def test_the_limits_are_identified_as_limits(tmp_path, k, limit):
    """Adiabatic and isothermal data give the limit itself with a one-sided interval, not a large
    finite number with a huge error."""
    scenario, path = record(tmp_path, k, seed=5, duration_s=20.0)
    e = fit_k(RigModel(scenario, (), read_measurements(path))).estimates[0]
    assert e.limit == limit and e.value == k and math.isnan(e.se)
    if limit == "0":
        assert e.ci_low == 0.0 and 0.0 < e.ci_high < 1.0
    else:
        assert math.isinf(e.ci_high) and e.ci_low >= 100.0
