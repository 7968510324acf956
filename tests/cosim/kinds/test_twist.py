"""The co-simulated twist test: equilibrium, symmetry, physics trends, macro-step convergence, CLI checks."""
from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from cosim import cli
from cosim.engine.cases import build_cosimulation
from cosim.kinds.twist import make_car, rail_heights, simulate, wheelset_x_m
from cosim.limits.criteria import static_wheel_loads, wheel_unloading, window_mean
from cosim.load import load_scenario
from vehicle.car import WHEELS, MetroCar

from helpers import SCENARIOS, short_twist, write_scenario


def scenario(tmp_path, **changes):
    return load_scenario(write_scenario(tmp_path, short_twist(**changes)))


def en_scenario(tmp_path, name="en.yaml", **changes):
    """The shipped EN 14363 twist (carbody + bogie twist), shortened: 1 s ramp, 1 s hold, 0.5 s
    final window, isothermal only, valves isolated, one process; ``changes``: twist keys."""
    data = yaml.safe_load((SCENARIOS / "twist_en14363.yaml").read_text())
    data["vehicle"] = "paper_metro_car"
    data["k_W_per_K"] = [float("inf")]
    data["solver"]["jobs"] = 1
    data["twist"].update(ramp_s=1.0, hold_s=1.0, window_s=0.5, valve_settings=[False])
    data["twist"].update(changes)
    return load_scenario(write_scenario(tmp_path, data, name))


def quasi_static_dqq(s, valves=False):
    """(8, cases) ΔQ/Q0 averaged over the final window, and the full (samples, 8, cases) series;
    levelling valves isolated unless ``valves``."""
    ds, diag = simulate(s.with_experiment(valve_settings=(valves,)))
    assert not diag
    dqq = ds["dqq"].transpose("time", "wheel", "case").values
    return window_mean(ds["time"].values, dqq, s.experiment.window), dqq


def wheel_loads(s):
    """(samples, 8, cases) wheel loads Q of the twist scenario ``s`` (asserting no divergence),
    and the k values of the cases."""
    ds, diag = simulate(s)
    assert not diag
    return ds["wheel_load_N"].transpose("time", "wheel", "case").values, list(ds["k_W_per_K"].values)


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
    Q, _ = wheel_loads(s)
    dqq = wheel_unloading(Q, static_wheel_loads(Q[0]))
    # 1e-6 (0.03 N on a 29 kN wheel): a car left at rest with its static pressures must not
    # move; a force imbalance or coupling drift would show at the 1e-3 level within the 2 s.
    assert np.abs(dqq).max() < 1e-6


def test_adiabatic_unloads_more_than_isothermal_and_diagonal_pattern(tmp_path):
    s = scenario(tmp_path)
    Q, ks = wheel_loads(s)
    assert ks == [0.0, math.inf]
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


@pytest.mark.slow
def test_macro_step_convergence(tmp_path):
    """H = 5, 2, 1, 0.5 ms approach each other. The multibody step is held at 0.5 ms in every run
    so that only the coupling changes: the exchange interval H and with it the pneumatic RK4
    step min(H, 5 ms) (exudyn's own time-step error is a separate matter)."""
    results = {}
    for H in (0.005, 0.002, 0.001, 0.0005):
        s = scenario(tmp_path, k_W_per_K=[10.0], **{"solver.macro_step_s": H, "solver.mechanics_step_s": 0.0005,
                                                    "solver.output_interval_s": 0.01})
        results[H] = wheel_loads(s)[0][:, :, 0]
    ref = results[0.0005]
    errors = [np.abs(results[H] - ref).max() for H in (0.005, 0.002, 0.001)]
    assert errors[0] > errors[1] > errors[2], errors
    # the scheme is better than first order: going from 5 to 1 ms cuts the error more than 5 times
    assert errors[0] > 5 * errors[2], errors
    # at the default H = 5 ms the coupling error stays below 0.1 % of the static wheel load,
    # two orders below the ΔQ/Q0 differences between k values the test is about
    assert errors[0] < 1e-3 * ref[0].mean(), errors


@pytest.mark.slow
def test_check_exit_codes(tmp_path, capsys):
    passing = write_scenario(tmp_path, short_twist(checks=["dqq_max <= 0.6", "dqq_max[3R] <= 0.6",
                                                           "dqq_qs_max[k=inf, valves=off] <= 0.6"]), "pass.yaml")
    failing = write_scenario(tmp_path, short_twist(checks=["dqq_max <= 0.001"]), "fail.yaml")
    assert cli.main(["check", str(passing), "--out", str(tmp_path / "p"), "--quiet"]) == cli.EXIT_OK
    lines = capsys.readouterr().out.splitlines()
    # one line per check: its text, the value, PASS and the case (and wheel) that gave the value
    for text in ("dqq_max <= 0.6", "dqq_max[3R] <= 0.6", "dqq_qs_max[k=inf, valves=off] <= 0.6"):
        line = next(x for x in lines if x.startswith(text + " "))
        assert "PASS" in line and "wheel" in line and float(line[len(text):].split()[0]) > 0
    assert "wheel 3R" in next(x for x in lines if x.startswith("dqq_max[3R]"))
    assert cli.main(["check", str(failing), "--out", str(tmp_path / "f"), "--quiet"]) == cli.EXIT_FAILED
    assert "FAIL" in capsys.readouterr().out
    bad = write_scenario(tmp_path, short_twist(checks=["dqq_max <= lots"]), "bad.yaml")
    assert cli.main(["check", str(bad), "--out", str(tmp_path / "b"), "--quiet"]) == cli.EXIT_BAD_INPUT
    # outputs of the passing run
    out = tmp_path / "p"
    assert (out / "summary.csv").exists() and (out / "run.json").exists() and (out / "fig8_wheel_loads.png").exists()
    header = (out / "summary.csv").read_text().splitlines()[0].split(",")
    assert {"valves", "k_W_per_K", "dqq_max", "dqq_max_wheel", "dqq_max_1L", "dqq_qs_4R", "dqq_qs_max",
            "dqq_drift", "settled", "roll_carbody_mean_end_rad"} <= set(header)
    # compare overlays the two runs
    assert cli.main(["compare", str(out), str(tmp_path / "f"), "--out", str(tmp_path / "cmp")]) == cli.EXIT_OK
    assert (tmp_path / "cmp" / "compare_Q.png").exists() and (tmp_path / "cmp" / "compare_dqq.png").exists()
    # a folder that is not a run is bad input
    assert cli.main(["compare", str(tmp_path), "--out", str(tmp_path / "cmp2")]) == cli.EXIT_BAD_INPUT
    # a run that did not finish is refused, naming why, unless it is allowed and marked
    import shutil
    cut = tmp_path / "cut"
    shutil.copytree(out, cut)
    (cut / "INCOMPLETE").write_text("interrupted\n")
    capsys.readouterr()
    assert cli.main(["compare", str(out), str(cut), "--out", str(tmp_path / "cmp3")]) == cli.EXIT_BAD_INPUT
    assert "INCOMPLETE marker" in capsys.readouterr().err
    assert cli.main(["compare", str(out), str(cut), "--out", str(tmp_path / "cmp3"), "--allow-incomplete"]) == cli.EXIT_OK
    # a run.json cut short (a full disk) names the file instead of a JSON traceback
    (cut / "INCOMPLETE").unlink()
    (cut / "run.json").write_text((out / "run.json").read_text()[:200])
    assert cli.main(["compare", str(cut), "--out", str(tmp_path / "cmp4")]) == cli.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert str(cut / "run.json") in err and "did not finish writing it" in err


class _StandingCar:
    """A stand-in with the MetroCar interface: bellows held at z = 0; it can fail at a given time."""

    def __init__(self, fail_at_s=math.inf):
        self.t, self.fail_at_s = 0.0, fail_at_s

    def static_bellow_forces_N(self):
        return np.full(4, 40e3)

    def bellow_crushing(self):
        return np.zeros(4), np.zeros(4)

    def set_bellow_forces(self, F_N, dF_dz_N_per_m=None, dF_dt_N_per_s=None):
        pass

    def advance(self, t_end_s):
        if t_end_s > self.fail_at_s:
            raise RuntimeError("solver gave up")
        self.t = t_end_s

    def wheel_loads_N(self):
        return np.full(8, 30e3)

    def carbody_roll_rad(self):
        return 0.0

    def floor_accelerations_m_per_s2(self):
        return np.array([[0.0] * 3, [0.0] * 3, [9.81] * 3])      # at rest: 1 g upwards


def test_a_diverging_case_stops_alone_and_keeps_its_record(tmp_path):
    from cosim.engine.master import CoSimulation
    from pneumatics.circuit import Circuit
    from pneumatics.layouts import static_pressures
    s = scenario(tmp_path)
    comps = s.circuit.components()
    circuit = Circuit(comps, k_W_per_K=np.array([0.0, 10.0]))
    x0 = circuit.initial_state(static_pressures(comps, np.full(4, 40e3), circuit.atmosphere.p_Pa), n_cases=2)
    cosim = CoSimulation([_StandingCar(), _StandingCar(fail_at_s=0.1)], circuit, x0, 0.005, 0.005,
                         case_labels=["k = 0", "k = 10"])
    record, diagnosis = cosim.run(0.3, 0.01)
    Q = record.arrays()["wheel_load_N"]
    t = np.asarray(record.t_s)
    assert t[-1] == pytest.approx(0.3)                      # the healthy case ran to the end
    assert np.all(np.isfinite(Q[:, :, 0]))
    assert np.all(np.isfinite(Q[t < 0.1, :, 1])) and np.all(np.isnan(Q[t > 0.1, :, 1]))
    assert diagnosis.startswith("k = 10: multibody solver failed advancing from t = 0.095 to 0.1 s")


class _PumpingCar(_StandingCar):
    """A stand-in whose bellows are crushed by 3 mm sines (different per bellow): the air flows."""

    bellow_height_m = 0.25

    def roll_to_track_rad(self):
        return np.zeros(3)

    def airspring_crushing_m(self):
        return self.bellow_crushing()[0]

    def bellow_crushing(self):
        w = 2 * np.pi * np.array([1.0, 1.3, 0.7, 2.1])
        return 3e-3 * np.sin(w * self.t), 3e-3 * w * np.cos(w * self.t)


def _pumping_run(tmp_path, reuse: bool):
    from cosim.engine.master import CoSimulation
    from pneumatics.circuit import Circuit
    from pneumatics.layouts import static_pressures
    comps = scenario(tmp_path).circuit.components()
    circuit = Circuit(comps, k_W_per_K=np.array([0.0, 10.0]))
    x0 = circuit.initial_state(static_pressures(comps, np.full(4, 40e3), circuit.atmosphere.p_Pa), n_cases=2)
    cosim = CoSimulation([_PumpingCar(), _PumpingCar()], circuit, x0, 0.005, 0.005)
    if not reuse:
        cosim._evaluation_now = lambda: None
    record, diagnosis = cosim.run(0.5, 0.005)       # a sample after every macro-step
    assert diagnosis is None
    return cosim, record.arrays()


def test_the_next_step_reuses_the_sampled_evaluation_with_the_same_numbers(tmp_path):
    """CoSimulation.sample evaluates the circuit at the state the next macro-step starts from; the
    step takes that evaluation instead of computing it again: the record is the same, bit for
    bit, as without the reuse. An evaluation of a state that has been replaced is not used."""
    cosim, reused = _pumping_run(tmp_path, reuse=True)
    _, fresh = _pumping_run(tmp_path, reuse=False)
    assert reused.keys() == fresh.keys()
    for name in reused:
        np.testing.assert_array_equal(reused[name], fresh[name], err_msg=name)
    assert np.ptp(reused["bellow_p_Pa"]) > 1e3                      # the air did something
    assert cosim._evaluation_now() is not None
    cosim.x = cosim.x.copy()                                         # a caller replaced the state
    assert cosim._evaluation_now() is None


def _pumping_car(_scenario):
    return _PumpingCar()


def test_scenarios_run_together_give_what_each_gives_alone(tmp_path):
    """cosim.engine.cases.simulate_scenarios (a ride's speeds on one pool, a scenario's k values on one
    circuit) gives each scenario the Dataset simulate_cases gives it alone, bit for bit, each run
    for its own duration, with both valve settings."""
    import dataclasses

    from cosim.engine.cases import simulate_cases, simulate_scenarios
    base = scenario(tmp_path)
    one = dataclasses.replace(base, solver=dataclasses.replace(base.solver, jobs=1), k_W_per_K=(0.0, 10.0))
    two = dataclasses.replace(one, k_W_per_K=(100.0, float("inf")))
    together = simulate_scenarios([one, two], (False, True), _pumping_car, [0.2, 0.3])
    for sc, duration, (ds, diagnoses) in zip((one, two), (0.2, 0.3), together):
        alone, alone_diagnoses = simulate_cases(sc, (False, True), _pumping_car, duration)
        assert diagnoses == alone_diagnoses == []
        assert float(ds["time"][-1]) == pytest.approx(duration)
        assert list(ds["k_W_per_K"].values) == 2 * list(sc.k_W_per_K)
        for name in alone.data_vars:
            np.testing.assert_array_equal(ds[name].values, alone[name].values, err_msg=name)


def test_a_case_does_not_depend_on_the_cases_its_circuit_batches(tmp_path):
    """The pneumatic step is the scenario's (all its k values), not the batched circuit's: k = 0
    alone and k = 0 beside k = 1e5 W/K (whose thermal rate shortens the step below the 5 ms asked)
    get the same step; and the chambers' total mass has the same last bit for one case as for
    several (numpy's sum orders one column differently). So ``solver.jobs`` and the grouping of
    runs onto processes do not move a number."""
    import dataclasses

    from cosim.engine.cases import build_cosimulation
    base = scenario(tmp_path)
    s = dataclasses.replace(base, k_W_per_K=(0.0, 1e5))
    alone = build_cosimulation(s, [0.0], _pumping_car)
    together = build_cosimulation(s, [0.0, 1e5], _pumping_car)
    assert alone.h_pneumatic == together.h_pneumatic < 0.5 * s.solver.pneumatic_step_s
    rng = np.random.default_rng(5)
    for _ in range(20):                 # numpy's orders differ in the last bit for ~40 % of such draws
        x = together.x[:, :1].copy()
        x[together.circuit.layout.m, 0] = rng.uniform(0.01, 1.0, len(together.circuit.chamber_names))
        mass_one = together.circuit.total_mass_kg(x)
        mass_two = together.circuit.total_mass_kg(np.column_stack([x[:, 0], x[:, 0]]))
        assert mass_one[0] == mass_two[0] == mass_two[1]


# ----------------------------------------------------------------------------- EN 14363 geometry
def test_en14363_rail_heights_give_both_twists(tmp_path):
    s = en_scenario(tmp_path)
    test, car = s.experiment, MetroCar(s.vehicle)
    # the loader holds the bases to the car's: the rail profile is evaluated at the real wheelsets
    assert np.allclose(wheelset_x_m(test), car.wheelset_x_m, rtol=0, atol=1e-12)
    h = rail_heights(test)(test.duration_s).reshape(4, 2)       # (wheelset, left/right)
    cross = h[:, 1] - h[:, 0]                                      # cross-level, right minus left
    centre = 0.5 * (cross[0:2].sum() - cross[2:4].sum())           # front minus rear bogie centre
    # EN 14363 limits: 20/10 + 2 = 4 permille over the 10 m bogie centres, 7 permille over 2 m
    assert centre / 10.0 == pytest.approx(4e-3, rel=1e-12)
    assert (cross[0] - cross[1]) / 2.0 == pytest.approx(7e-3, rel=1e-12)
    assert cross[2] == cross[3] == 0.0 and np.all(h[:, 0] == 0.0)  # rear bogie and left rail level
    # ramped by the cosine: half-way through the ramp every height is at half its final value
    assert np.allclose(rail_heights(test)(0.5 * test.ramp_s), 0.5 * rail_heights(test)(test.duration_s), rtol=1e-12)
    assert np.all(rail_heights(test)(0.0) == 0.0)
    # without the bogie twist: the paper's Fig. 7, 40 mm under 1R and 2R, exactly as before
    fig7 = rail_heights(scenario(tmp_path).experiment)(10.0)
    assert np.array_equal(fig7, np.array([0, 0.04, 0, 0.04, 0, 0, 0, 0]) * (fig7[1] / 0.04))
    assert fig7[1] == pytest.approx(0.04, rel=1e-12)


def test_en14363_zero_twist_gives_no_unloading(tmp_path):
    """The EN 14363 car, circuit and valves, with both twists set to zero: nothing may move."""
    s = en_scenario(tmp_path, twist_per_mille=0.0, bogie_twist_per_mille=0.0, valve_settings=[False, True])
    for valves in (False, True):
        _, dqq = quasi_static_dqq(s, valves)
        # 1e-6 (0.03 N of a 29 kN wheel load), as for Fig. 7: the car starts in its static
        # equilibrium, the valves inside their dead band; the solver's Newton tolerance (1e-4 N)
        # is far below it, a coupling or force-balance error would show at 1e-3
        assert np.abs(dqq).max() < 1e-6, valves


def test_en14363_unloading_grows_in_proportion_to_the_twist(tmp_path):
    """Half and full EN 14363 twist (adiabatic bellows, valves isolated): ΔQ/Q0 grows with the
    twist, in proportion while every wheel stays on the rail."""
    results = {}
    for scale in (0.5, 1.0):
        s = en_scenario(tmp_path, f"en_{scale}.yaml", twist_per_mille=4.0 * scale, bogie_twist_per_mille=7.0 * scale)
        s = s.__class__(**{**s.__dict__, "k_W_per_K": (0.0,)})
        results[scale] = quasi_static_dqq(s)
    (half, half_t), (full, full_t) = results[0.5], results[1.0]
    assert full_t.max() < 1.0                                  # no wheel lifted: the contact stays linearisable
    assert full.max() > half.max() > 0.0                       # monotone
    # proportional to 5 % of the largest value: the departures from linearity are second order --
    # the gas law over volume changes of ~2 % (A z / V, z of a few mm, V = bellow + tank 39 l) and
    # the Hertz contact (1 GN/m against 0.68 MN/m of primary) -- at most ~2 % of the response
    assert np.abs(full - 2.0 * half).max() < 0.05 * np.abs(full).max(), (full, half)
    assert np.abs(full_t - 2.0 * half_t).max() < 0.05 * np.abs(full_t).max()


def test_bogie_twist_alone_loads_the_wheels_through_the_primary_roll_stiffness(tmp_path):
    """The bogie twist of the EN 14363 scenario alone (carbody twist 0): h+ = 14 mm rolls
    wheelset 1 against wheelset 2 by h+/(2b) (2b: contact spacing), each by phi = h+/(2 (2b))
    against the bogie frame, which by symmetry does not roll. Each wheelset rolls about its
    guidance point at rail level, so the axleboxes (height r, the wheel radius) move sideways by
    r phi, opposite for the two wheelsets: the frame yaws until its longitudinal springs k_x
    (at +-b_p) balance the lateral ones k_y (at +-a, a = half the wheelbase), leaving a lateral
    deflection chi r phi, chi = k_x b_p^2 / (k_x b_p^2 + k_y a^2). Roll moment on a wheelset:
    2 k_z b_p^2 phi (vertical springs) + 2 k_y r^2 chi phi (lateral springs), carried by the
    wheel loads over 2b:
        ΔQ/Q0 = +-(k_z b_p^2 + k_y r^2 chi) h+ / ((2b)^2 Q0),
    1L and 2R unloading, 1R and 2L loading; the carbody and the rear bogie see nothing."""
    s = en_scenario(tmp_path, twist_per_mille=0.0, ramp_s=2.0, hold_s=1.0)
    assert s.experiment.height_m == 0.0 and s.experiment.bogie_height_m == pytest.approx(0.014, rel=1e-12)
    qs, _ = quasi_static_dqq(s)
    p, Q0 = s.vehicle, MetroCar(s.vehicle).Q_static_N
    two_b, b_p, a, r = p.contact_spacing_m, p.primary_lateral_spacing_m / 2.0, p.wheelbase_m / 2.0, p.wheel_radius_m
    kx, ky, kz = p.primary_stiffness_x_N_per_m, p.primary_stiffness_y_N_per_m, p.primary_stiffness_z_N_per_m
    chi = kx * b_p ** 2 / (kx * b_p ** 2 + ky * a ** 2)
    expected = (kz * b_p ** 2 + ky * r ** 2 * chi) * s.experiment.bogie_height_m / two_b ** 2 / Q0
    sign = np.array([1, -1, -1, 1, 0, 0, 0, 0])              # 1L 1R 2L 2R 3L 3R 4L 4R
    # 2 % of the bogie-twist term: the hand model leaves out couplings below that -- the frame
    # pitches (its wheelsets heave by +-h+/4), which shears the bellows and pitches the carbody:
    # what the rear bogie shows, < 1 % of the term; the bellows' shear against the frame's yaw
    # (0.24 against 70 MNm/rad: 0.3 %); the contact compliance in series (1 GN/m against
    # 0.68 MN/m: 0.1 %)
    assert np.allclose(qs[:, 0], sign * expected, rtol=0, atol=0.02 * expected), (qs[:, 0], expected)


def test_a_diverged_case_names_no_worst_wheel(tmp_path):
    # NaN from the divergence on: there is no maximum, so no wheel or time to name
    from cosim.kinds.twist import twist_metrics
    s = scenario(tmp_path)
    t = np.linspace(0.0, 2.0, 201)
    dqq = np.zeros((201, 8, 1))
    dqq[:100, 2, 0] = 0.1
    dqq[150:, :, 0] = np.nan
    row = twist_metrics(t, dqq, s.experiment, 0)
    assert math.isnan(row["dqq_max"]) and row["dqq_max_wheel"] == "" and math.isnan(row["t_dqq_max_s"])
    assert math.isnan(row["dqq_qs_max"]) and row["dqq_qs_max_wheel"] == ""
    healthy = twist_metrics(t[:150], dqq[:150], s.experiment, 0)
    assert healthy["dqq_max"] == 0.1 and healthy["dqq_max_wheel"] == "2L"


def test_twist_runs_with_a_compressible_pipe(tmp_path):
    """The car's circuit cut into cells like the rig's (``circuit.pipe.model: compressible``):
    the twist runs, and its wheel unloading is the inertial pipe's within 2 % of its largest
    value. The compressible pipe holds 0.65 % more air volume (A L over bellow and tank) and its
    5 cells add waves at ~170 Hz and above that a 1 s ramp barely excites: 2 % bounds both."""
    out = {}
    for model in ("dynamic", "compressible"):
        ds, diag = simulate(scenario(tmp_path, **{"circuit.pipe": {"model": model, "cells": 5}}))
        assert not diag
        out[model] = ds["dqq"].values
    scale = np.abs(out["dynamic"]).max()
    assert np.abs(out["compressible"] - out["dynamic"]).max() < 0.02 * scale
