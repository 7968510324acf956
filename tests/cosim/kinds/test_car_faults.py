"""Faults in car runs: deflated running against a hand model, the air accounting, the instant a
fault happens, faults named in the results and sweepable."""
from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from cosim.kinds.twist import simulate
from cosim.limits.criteria import window_mean
from cosim.load import load_scenario
from cosim.runner import run
from vehicle.car import MetroCar

from helpers import SCENARIOS, write_scenario

WHEELS = ("1L", "1R", "2L", "2R", "3L", "3R", "4L", "4R")


def deflated_twist(tmp_path, name="deflated.yaml", **twist):
    """scenarios/twist_deflated_all.yaml shortened: every bellow bursts at t = 0, the carbody
    twist alone (no bogie twist) from 6 s, 2 s ramp, 2 s hold, 1 s window, k = inf."""
    data = yaml.safe_load((SCENARIOS / "twist_deflated_all.yaml").read_text())
    data["k_W_per_K"] = [float("inf")]
    data["solver"]["jobs"] = 1
    data["twist"].update({"start_s": 6.0, "ramp_s": 2.0, "hold_s": 2.0, "window_s": 1.0, "bogie_base_m": None,
                          "valve_settings": [False], **twist})
    return load_scenario(write_scenario(tmp_path, data, name))


def test_deflated_twist_matches_the_hand_model_of_the_emergency_springs(tmp_path):
    """All four bellows deflated, valves isolated: the carbody rests on each corner's bumpstop
    (k_stop) in series with its emergency spring (k_e), k_sec = 1/(1/k_e + 1/k_stop). A rigid
    carbody twisted by h under the front bogie's right rail (track roll phi_t = h/(2b), 2b the
    contact spacing): per bogie the secondary roll stiffness K_s = k_arb + 2 k_sec b_s^2 in series
    with the primary's K_p = 4 k_z b_p^2, K = 1/(1/K_s + 1/K_p); the carbody rolls by phi_t/2 and
    each bogie carries the moment M = K phi_t / 2 on its two wheelsets over 2b:
        ΔQ/Q0 = K h / (4 (2b)^2 Q0),
    unloading 1L, 2L, 3R, 4R. What the hand model leaves out is a whole-car roll (the same on
    both bogies) that the twist combination (front - rear)/2 of the left-minus-right unloadings
    cancels, and gravity's destabilising terms (the weights over the roll centres, estimated at
    ~2 % each over the secondary and the primary): 5 %, the issue's tolerance."""
    s = deflated_twist(tmp_path)
    ds, diagnoses = simulate(s)
    assert not diagnoses
    dqq = window_mean(ds["time"].values, ds["dqq"].transpose("time", "wheel", "case").values[:, :, 0], s.experiment.window)
    d = dict(zip(WHEELS, dqq))
    front = (d["1L"] - d["1R"] + d["2L"] - d["2R"]) / 4.0
    rear = (d["3L"] - d["3R"] + d["4L"] - d["4R"]) / 4.0
    p = s.vehicle
    k_sec = 1.0 / (1.0 / p.emergency_spring_stiffness_N_per_m + 1.0 / p.vertical_bumpstop_stiffness_N_per_m)
    K_s = p.arb_roll_stiffness_N_m_per_rad + 2.0 * k_sec * (p.airspring_lateral_spacing_m / 2.0) ** 2
    K_p = 4.0 * p.primary_stiffness_z_N_per_m * (p.primary_lateral_spacing_m / 2.0) ** 2
    K = 1.0 / (1.0 / K_s + 1.0 / K_p)
    expected = K * s.experiment.height_m / (4.0 * p.contact_spacing_m ** 2 * MetroCar(p).Q_static_N)
    print(f"deflated twist: model {(front - rear) / 2.0:.5f}, hand model {expected:.5f}")
    assert (front - rear) / 2.0 == pytest.approx(expected, rel=0.05), ((front - rear) / 2.0, expected)
    # the bellows are empty: each rests on its stop (beyond the 40 mm clearance), at the atmosphere's pressure
    z = ds["crushing_m"].isel(time=-1, case=0).values
    p_end = ds["bellow_p_Pa"].isel(time=-1, case=0).values
    assert np.all(z > p.vertical_bumpstop_clearance_m)
    assert np.allclose(p_end, 101_325.0, rtol=2e-3)


def test_air_lost_is_counted_apart_and_the_mass_balance_closes(tmp_path):
    """Valves connected: the levelling valves feed the burst bellows in vain. What the chambers
    hold changes by exactly injected - exhausted - lost (each integrated as a state of the
    circuit: the balance closes to round-off, ~1e-14 kg on ~1 kg); the burst loses air, the
    rows and the figures name the faults."""
    s = deflated_twist(tmp_path, valve_settings=[True])
    outcome = run(s)
    row = outcome.rows[0]
    assert row["faults"] == "FL burst 5 cm² at 0 s; RL burst 5 cm² at 0 s; FR burst 5 cm² at 0 s; RR burst 5 cm² at 0 s"
    assert row["air_lost_kg"] > 0.5 and row["air_injected_kg"] > 0.1
    assert abs(row["mass_balance_error_kg"]) < 1e-11


def burst_in_curve(tmp_path, macro_step_s, name):
    """scenarios/curve_burst.yaml cut to 1.5 s around a burst at 1.0123 s, k = inf, valves
    isolated. The steps 5 and 4 ms have no boundary in common near it (1.010 / 1.015 s against
    1.012 / 1.016 s), so a fault moved to either boundary would differ between them."""
    data = yaml.safe_load((SCENARIOS / "curve_burst.yaml").read_text())
    data["k_W_per_K"] = [float("inf")]
    data["faults"][0]["t_s"] = 1.0123
    data["curve"].update(duration_s=1.5, valve_settings=[False])
    data["solver"].update(jobs=1, macro_step_s=macro_step_s, mechanics_step_s=macro_step_s,
                          pneumatic_step_s=macro_step_s, output_interval_s=0.02)
    data["checks"] = []
    return load_scenario(write_scenario(tmp_path, data, name))


def test_a_fault_happens_at_its_own_time_whatever_the_steps(tmp_path):
    """The air is integrated up to the fault's instant and on from it, inside the macro-step: the
    air lost 0.1 s after the burst agrees between macro-steps of 5 and 4 ms to 0.1 %. Had the
    burst been moved to a boundary (to the one before: 1.010 against 1.012 s; after: 1.015
    against 1.016 s), the two would differ by the air lost in 1-2 ms, > 1 % of it (checked below
    from the run itself)."""
    lost = {}
    for H in (0.005, 0.004):
        outcome = run(burst_in_curve(tmp_path, H, f"burst_{H}.yaml"))
        assert not outcome.diagnoses
        ds = outcome.series["curve"].isel(case=0)
        t = ds["time"].values
        lost[H] = (t, ds["air_lost_kg"].values)
        assert np.all(lost[H][1][t < 1.0123 - 1e-9] == 0.0)
    at = 1.0123 + 0.1
    a, b = (np.interp(at, *lost[H]) for H in (0.005, 0.004))
    assert a == pytest.approx(b, rel=1e-3)
    t, m = lost[0.004]
    rate = (np.interp(1.0123 + 0.02, t, m) - 0.0) / 0.02       # mean rate over the first 20 ms [kg/s]
    assert rate * 0.001 > 0.01 * a                             # a 1 ms shift would cost > 1 %


def test_faults_are_set_and_swept_like_any_key(tmp_path):
    """``--set faults[0].component=RR`` (and so ``--grid``) changes a fault of the list."""
    path = SCENARIOS / "curve_burst.yaml"
    s = load_scenario(path, overrides=["faults[0].component=RR", "faults[0].t_s=12.5"])
    fault = s.circuit.faults[0]
    assert (fault.component, fault.t_s, fault.kind) == ("RR", 12.5, "burst")
    from cosim.sweep.study import SweepSpec, prepare
    prepared = prepare(SweepSpec(path, grid={"faults[0].component": ["FL", "FR"]}))
    scenarios = [prepared.scenarios[case.key] for case in prepared.cases]
    assert [s.circuit.faults[0].component for s in scenarios] == ["FL", "FR"]
    assert math.isclose(scenarios[0].circuit.faults[0].t_s, 15.0)


def test_a_run_that_stopped_before_its_fault_keeps_its_rows(tmp_path):
    """Interrupted (or every case stopped) before the fault: no transient columns, no error."""
    import xarray as xr

    from cosim.runs.car import fault_columns
    s = burst_in_curve(tmp_path, 0.005, "early.yaml")
    t = np.arange(0.0, 0.5, 0.01)
    case = xr.Dataset({"roll_rad": ("time", np.zeros_like(t)), "dqq": (("time", "wheel"), np.zeros((t.size, 8)))},
                      coords={"time": t, "wheel": list(WHEELS)})
    assert fault_columns(s, case) == {}
