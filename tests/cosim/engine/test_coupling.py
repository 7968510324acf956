"""The co-simulation coupling: a force continuous in time, converged air consumption, and the
``verify`` command (Richardson extrapolation, exit codes)."""
from __future__ import annotations

import dataclasses
import json
import math

import exudyn
import numpy as np
import pytest

from cosim.cli import main
from cosim.engine.cases import build_cosimulation
from cosim.kinds.twist import make_car as twist_car
from cosim.load import load_scenario
from cosim.runner import run
from cosim.verification.verify import estimates, floor_of, richardson

from helpers import SCENARIOS


def _applied_forces(car) -> np.ndarray:
    """The axial bellow forces the car applies now [N] (the connector's -f_z on the bogie)."""
    out = exudyn.OutputVariableType.ForceLocal
    return -np.array([car.mbs.GetObjectOutput(co, out)[2] for co in car._bellows])


def _twist_ramp_forces(H: float):
    """Twist ramp (1 s), k = 0, every step H: the forces the car's law gives at the start and
    at the end of each macro-step, and their largest distance from the circuit's own force
    F(x, z) at the step ends."""
    scenario = load_scenario(SCENARIOS / "twist_dqq.yaml", k_override=[0.0],
                             overrides=[f"solver.macro_step_s={H}", f"solver.mechanics_step_s={H}",
                                        f"solver.pneumatic_step_s={H}"])
    scenario = scenario.with_experiment(ramp_s=1.0)
    cosim = build_cosimulation(scenario, scenario.k_W_per_K, twist_car)
    car = cosim.cars[0]
    at_start = []
    advance = car.advance

    def recording_advance(t_end_s):
        at_start.append(_applied_forces(car))          # new law at t_n, before integrating
        advance(t_end_s)
    car.advance = recording_advance
    at_end, drift = [], 0.0
    for _ in range(round(1.0 / H)):
        cosim.step()
        at_end.append(_applied_forces(car))           # old law at t_{n+1}, from the car's state
        F_pneumatic = cosim.circuit.bellow_forces_N(cosim.x, cosim.z)[:, 0]
        drift = max(drift, np.abs(at_end[-1] - F_pneumatic).max())
    return np.array(at_start), np.array(at_end), drift


def test_force_felt_by_the_car_is_continuous_across_macro_steps():
    # The law the car evaluates at the start of each macro-step (new law, state and time of the
    # boundary) equals what it evaluated at the end of the previous one (old law, same state
    # and time): no jump, to round-off (1e-9 of the 42 kN).
    at_start, at_end, drift = _twist_ramp_forces(0.005)
    assert np.abs(at_start[1:] - at_end[:-1]).max() <= 1e-9 * 42e3
    assert np.abs(np.diff(at_end, axis=0)).max() > 1.0   # not vacuous: the force does change
    # It stays anchored to the pneumatic force: the distance is the O(H^2) local error of the
    # slow part's extrapolation, so halving H divides it by 4 (measured 3.26 -> 0.82 -> 0.21 N,
    # ratio 3.96-3.99); a first-order (held) slow part would give 2.
    _, _, drift_half = _twist_ramp_forces(0.0025)
    assert 0.0 < drift < 10.0
    assert 3.5 < drift / drift_half < 4.5


@pytest.mark.slow
def test_short_curve_air_injected_is_converged_at_the_default_steps():
    # Valves connected, k = 0, a 5 s entry (12 m straight, 15 m transition, into the arc):
    # halving every step (macro, multibody, pneumatic) changes the air injected by less than
    # 0.5 %, the bound for the default settings (measured: 0.011 % for the first
    # halving, 0.003 % for the next, ratio 3.8: second order).
    scenario = load_scenario(SCENARIOS / "curve_entry.yaml", k_override=[0.0],
                             overrides=["curve.straight_m=12", "curve.duration_s=5", "solver.jobs=1"])
    air = []
    for factor in (1.0, 0.5):
        s = scenario.solver
        variant = dataclasses.replace(scenario, solver=dataclasses.replace(
            s, macro_step_s=s.macro_step_s * factor, mechanics_step_s=s.mechanics_step_s * factor,
            pneumatic_step_s=s.pneumatic_step_s * factor))
        outcome = run(variant.with_experiment(valve_settings=(True,)))
        assert not outcome.diagnoses
        air.append(outcome.rows[0]["air_injected_kg"])
    assert air[0] > 1e-4                              # the valves do inject air (not vacuous)
    assert abs(air[0] - air[1]) / air[1] < 0.005


# ---------------------------------------------------------------- Richardson extrapolation
def test_richardson_recovers_order_and_limit_of_a_power_law():
    # f(h) = f* + C h^p at h, h/2, h/4: r = 2^p exactly, f* recovered to round-off
    for p in (1.0, 2.0, 3.0):
        f = [1.25 + 0.3 * (0.1 / 2 ** i) ** p for i in range(3)]
        e = richardson(f)
        assert e.order == pytest.approx(p, rel=1e-9)
        assert e.richardson == pytest.approx(1.25, rel=1e-12)
        assert e.error == pytest.approx(abs(f[0] - 1.25) / 1.25, rel=1e-9)
        assert e.asymptotic


def test_richardson_flags_sequences_outside_the_asymptotic_range():
    e = richardson([1.0, 1.1, 1.0])                   # oscillating: no order
    assert not e.asymptotic and math.isnan(e.order)
    assert e.error == pytest.approx(0.1)              # bounded by the spread
    assert richardson([0.0, 0.0, 0.0]).error == 0.0   # identically zero: converged
    assert richardson([2.0, 2.0, 2.0 * (1 + 1e-12)]).error < 1e-9  # at the noise floor
    assert richardson([1.0, math.nan, 1.0]).error == math.inf
    # an order far from the schemes' (p = 6 here) marks the range as not asymptotic: the error
    # is bounded by the spread, not extrapolated
    f = [1.0 + 0.1 * 64.0 ** -i for i in range(3)]
    e = richardson(f)
    assert e.order == pytest.approx(6.0) and not e.asymptotic
    assert e.error == pytest.approx((abs(f[0] - f[2]) + abs(f[1] - f[2])) / f[2])


def test_richardson_judges_a_quantity_near_zero_on_its_floor():
    """1e-7 kg of air that moves by 30 % between levels: a relative error of ~30 % on its own
    scale, 3e-5 on a floor of 1 g (the absolute floor of verify's air metrics)."""
    f = [1.0e-7, 1.3e-7, 1.2e-7]
    e = richardson(f)
    assert e.error > 0.2 and not e.asymptotic
    # on the floor its differences (3e-5 of 1 g) are below CONVERGED_BELOW: converged, no flag
    e = richardson(f, floor=1e-3)
    assert e.asymptotic and e.error == pytest.approx(0.2e-7 / 1e-3)
    # differences of 1e-5 of the value, in no order, count as converged too
    assert richardson([0.381908, 0.381901, 0.381911]).asymptotic
    # a value above its floor is judged on itself, as without one
    g = [1.25 + 0.3 * (0.01 / 2 ** i) ** 2 for i in range(3)]
    assert richardson(g, floor=1e-3).error == richardson(g).error


def test_verify_floors_follow_the_metric_unit():
    row = {"air_initial_kg": "0.9", "roll_max_rad": "0.02", "Q0_N": "29430"}
    assert floor_of("air_exhausted_kg", row) == pytest.approx(0.9e-3)
    assert floor_of("roll_mean_end_rad", row) == pytest.approx(2e-3)
    assert floor_of("sum_y_max_N", row) == pytest.approx(294.3)
    assert floor_of("dqq_2m_max", row) == pytest.approx(0.01)
    assert floor_of("dqq_max_3R", {}) == pytest.approx(0.01)   # per-wheel: the family's unit
    assert floor_of("air_injected_kg", {}) == 0.0              # no reference: no floor


# ---------------------------------------------------------------- the verify command
SHORT_TWIST = ["--k", "0", "--set", "twist.ramp_s=0.5", "--set", "twist.hold_s=0.5", "--set", "solver.jobs=1",
               "--quiet"]


@pytest.mark.slow
def test_verify_exit_codes(tmp_path, capsys):
    # a 1 s twist is still swaying (not asymptotic): a loose tolerance passes, a strict one fails
    twist = str(SCENARIOS / "twist_dqq.yaml")
    assert main(["verify", twist, *SHORT_TWIST, "--set", "verify.tolerance=0.5", "--out", str(tmp_path / "ok")]) == 0
    out = capsys.readouterr().out
    assert "dqq_max" in out and "Richardson" in out
    assert (tmp_path / "ok" / "verify.csv").exists()
    info = json.loads((tmp_path / "ok" / "verify.json").read_text())
    steps = [[lv[k] for k in ("macro_step_s", "mechanics_step_s", "pneumatic_step_s")] for lv in info["levels"]]
    assert len(steps) == 3 and np.allclose(steps[1:], np.array(steps[:-1]) / 2, rtol=1e-12)  # every step halved
    assert {e["metric"] for e in info["estimates"]} >= {"dqq_max", "dqq_qs_max"}
    assert main(["verify", twist, *SHORT_TWIST, "--set", "verify.tolerance=1e-12",
                 "--out", str(tmp_path / "strict")]) == 1
    # bad input: exit 2 before anything runs
    assert main(["verify", twist, *SHORT_TWIST, "--levels", "1", "--out", str(tmp_path / "bad")]) == 2
    assert main(["verify", twist, *SHORT_TWIST, "--set", "verify.tolerance=-1", "--out", str(tmp_path / "bad")]) == 2
    assert main(["verify", str(SCENARIOS / "rig_table2.yaml"), "--out", str(tmp_path / "bad")]) == 2
    assert not (tmp_path / "bad").exists()


def test_verify_judges_a_wheel_near_zero_on_the_scale_of_the_test():
    """A wheel whose ΔQ/Q0 is 0.03 at the shipped steps and 1e-4 once refined, beside a wheel at
    0.40: its level-0 error, 0.03 of 0.40, is 7.5 % (it failed 0.074 % before the scale of the
    family became a floor of its own); an exactly zero finest level does not divide by zero."""
    rows = [[{"valves": "False", "k_W_per_K": "0", "dqq_qs_1L": a, "dqq_qs_1R": b}]
            for a, b in (("0.030", "0.40"), ("0.0003", "0.40"), ("0.0001", "0.40"))]
    found = {e.metric: e for e in estimates(rows, ("dqq_qs_1L", "dqq_qs_1R"))}
    assert found["dqq_qs_1L"].error == pytest.approx(0.0299 / 0.40, rel=0.02)
    for f in ([1e-3, 5e-4, 0.0], [1.0, 1.0, 0.0], [0.0, 1e-3, 0.0]):
        assert math.isfinite(richardson(f, floor=0.01).error)
        assert richardson(f).error == math.inf
