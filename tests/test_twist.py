"""The co-simulated twist test: equilibrium, symmetry, physics trends, macro-step convergence, CLI checks."""
from __future__ import annotations

import math

import numpy as np
import pytest

from cosim import cli
from cosim.criteria import static_wheel_loads, wheel_unloading
from cosim.scenario import load_scenario
from cosim.car_runs import build_cosimulation
from cosim.twist import make_car, simulate_twist
from helpers import short_twist, write_scenario
from vehicle.car import WHEELS


def scenario(tmp_path, **changes):
    return load_scenario(write_scenario(tmp_path, short_twist(**changes)))


def test_starts_in_static_equilibrium(tmp_path):
    s = scenario(tmp_path)
    cosim = build_cosimulation(s, [0.0], make_car)
    Q = cosim.cars[0].wheel_loads_N()
    p = s.vehicle
    weight = 9.81 * (p.carbody_mass_kg + 2 * p.bogie_mass_kg + 4 * p.wheelset_mass_kg)
    # 1e-6 relative, the acceptance level: the equilibrium is set analytically, so only
    # round-off (~1e-13) separates them.
    assert Q.sum() == pytest.approx(weight, rel=1e-6)
    # level track: left and right wheels of each wheelset carry the same load (round-off level)
    assert np.allclose(Q[0::2], Q[1::2], rtol=1e-9)
    # the circuit's initial bellow forces are exactly the static forces the car was built for
    F = cosim.circuit.bellow_forces_N(cosim.x, cosim.z)[:, 0]
    assert np.allclose(F, cosim.cars[0].static_bellow_forces_N(), rtol=1e-12)


def test_zero_twist_gives_no_unloading(tmp_path):
    s = scenario(tmp_path, **{"twist.twist_per_mille": 0.0})
    ks, rec, diag = simulate_twist(s)
    assert not diag
    Q = rec["wheel_load_N"]
    dqq = wheel_unloading(Q, static_wheel_loads(Q[0]))
    # 1e-6 (0.03 N on a 29 kN wheel): a car left at rest with its static pressures must not
    # move; a force imbalance or coupling drift would show at the 1e-3 level within the 2 s.
    assert np.abs(dqq).max() < 1e-6


def test_adiabatic_unloads_more_than_isothermal_and_diagonal_pattern(tmp_path):
    s = scenario(tmp_path)
    ks, rec, diag = simulate_twist(s)
    assert not diag and ks == [0.0, math.inf]
    Q = rec["wheel_load_N"]
    dqq = wheel_unloading(Q, static_wheel_loads(Q[0]))
    adiabatic, isothermal = dqq[..., 0].max(), dqq[..., 1].max()
    # γ = 1.4 stiffer bellows: the adiabatic car must unload clearly more (paper Fig. 8)
    assert adiabatic > 1.1 * isothermal > 0
    # raising the front right rails: 1L unloads, 1R loads; the rear bogie shows the opposite
    # diagonal (4L loads, 4R unloads): the carbody transmits the twist as a roll moment
    end = dqq[-1, :, 0]
    i = WHEELS.index
    assert end[i("1L")] > 0 > end[i("1R")]
    assert end[i("4R")] > 0 > end[i("4L")]


def test_macro_step_convergence(tmp_path):
    """H = 5, 2, 1, 0.5 ms approach each other. The multibody step is held at 0.5 ms in every run
    so that only the coupling changes: the exchange interval H and with it the pneumatic RK4
    step min(H, 5 ms) (exudyn's own time-step error is a separate matter)."""
    results = {}
    for H in (0.005, 0.002, 0.001, 0.0005):
        s = scenario(tmp_path, k_W_per_K=[10.0], **{"solver.macro_step_s": H, "solver.mechanics_step_s": 0.0005,
                                                    "solver.output_interval_s": 0.01})
        ks, rec, diag = simulate_twist(s)
        assert not diag
        results[H] = rec["wheel_load_N"][:, :, 0]
    ref = results[0.0005]
    errors = [np.abs(results[H] - ref).max() for H in (0.005, 0.002, 0.001)]
    assert errors[0] > errors[1] > errors[2], errors
    # the scheme is better than first order: going from 5 to 1 ms cuts the error more than 5 times
    assert errors[0] > 5 * errors[2], errors
    # at the default H = 5 ms the coupling error stays below 0.1 % of the static wheel load,
    # two orders below the ΔQ/Q0 differences between k values the test is about
    assert errors[0] < 1e-3 * ref[0].mean(), errors


def test_check_exit_codes(tmp_path, capsys):
    passing = write_scenario(tmp_path, short_twist(checks=["dqq_max <= 0.6"]), "pass.yaml")
    failing = write_scenario(tmp_path, short_twist(checks=["dqq_max <= 0.001"]), "fail.yaml")
    assert cli.main(["check", str(passing), "--out", str(tmp_path / "p"), "--quiet"]) == cli.EXIT_OK
    assert "PASS" in capsys.readouterr().out
    assert cli.main(["check", str(failing), "--out", str(tmp_path / "f"), "--quiet"]) == cli.EXIT_FAILED
    assert "FAIL" in capsys.readouterr().out
    bad = write_scenario(tmp_path, short_twist(checks=["dqq_max <= lots"]), "bad.yaml")
    assert cli.main(["check", str(bad), "--out", str(tmp_path / "b"), "--quiet"]) == cli.EXIT_BAD_INPUT
    # outputs of the passing run
    out = tmp_path / "p"
    assert (out / "summary.csv").exists() and (out / "run.json").exists() and (out / "fig8_wheel_loads.png").exists()
    header = (out / "summary.csv").read_text().splitlines()[0].split(",")
    assert {"k_W_per_K", "dqq_max", "dqq_max_wheel", "dqq_max_1L", "dqq_end_4R"} <= set(header)
    # compare overlays the two runs
    assert cli.main(["compare", str(out), str(tmp_path / "f"), "--out", str(tmp_path / "cmp")]) == cli.EXIT_OK
    assert (tmp_path / "cmp" / "compare_Q.png").exists() and (tmp_path / "cmp" / "compare_dqq.png").exists()
    # a folder that is not a run is bad input
    assert cli.main(["compare", str(tmp_path), "--out", str(tmp_path / "cmp2")]) == cli.EXIT_BAD_INPUT


class _StandingCar:
    """A stand-in with the MetroCar interface: bellows held at z = 0; it can fail at a given time."""

    def __init__(self, fail_at_s=math.inf):
        self.t, self.fail_at_s = 0.0, fail_at_s

    def static_bellow_forces_N(self):
        return np.full(4, 40e3)

    def bellow_crushing(self):
        return np.zeros(4), np.zeros(4)

    def set_bellow_forces(self, F_N, dF_dz_N_per_m=None):
        pass

    def advance(self, t_end_s):
        if t_end_s > self.fail_at_s:
            raise RuntimeError("solver gave up")
        self.t = t_end_s

    def wheel_loads_N(self):
        return np.full(8, 30e3)

    def carbody_roll_rad(self):
        return 0.0


def test_a_diverging_case_stops_alone_and_keeps_its_record(tmp_path):
    from cosim.car_runs import static_pressures
    from cosim.master import CoSimulation
    from pneumatics.circuit import Circuit
    s = scenario(tmp_path)
    comps = s.circuit.components()
    circuit = Circuit(comps, k_W_per_K=np.array([0.0, 10.0]))
    x0 = circuit.initial_state(static_pressures(comps, np.full(4, 40e3), circuit.atmosphere.p_Pa), n_cases=2)
    cosim = CoSimulation([_StandingCar(), _StandingCar(fail_at_s=0.1)], circuit, x0, 0.005, 0.005,
                         case_labels=["k = 0", "k = 10"])
    record, diagnosis = cosim.run(0.3, 0.01)
    Q = np.asarray(record.wheel_load_N)
    t = np.asarray(record.t_s)
    assert t[-1] == pytest.approx(0.3)                      # the healthy case ran to the end
    assert np.all(np.isfinite(Q[:, :, 0]))
    assert np.all(np.isfinite(Q[t < 0.1, :, 1])) and np.all(np.isnan(Q[t > 0.1, :, 1]))
    assert diagnosis.startswith("k = 10: multibody solver failed advancing from t = 0.095 to 0.1 s")
