"""Curve entry co-simulated with the full four-point circuit (valves): consumption, levelling, mass balance."""
from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from cosim.limits.criteria import window_mean
from cosim.load import load_scenario
from cosim.runs.track_run import car_centre_s_m, make_car, simulate, summary_row, track_roll_rad

from helpers import SCENARIOS, write_scenario


def curve_scenario(tmp_path, k=(0.0,), **curve):
    data = yaml.safe_load((SCENARIOS / "curve_entry.yaml").read_text())
    data["vehicle"] = "paper_metro_car"
    data["k_W_per_K"] = list(k)
    data["solver"]["jobs"] = 1
    data["curve"].update(curve)
    return load_scenario(write_scenario(tmp_path, data))


def simulate_curve(s, valves):
    """The curve scenario ``s`` with the valves connected or not: (k values, arrays by name with
    time first and the case last, as (samples, ..., cases), diagnoses, labelled Dataset)."""
    ds, diag = simulate(s.with_experiment(valve_settings=(valves,)))
    arrays = {name: ds[name].transpose("time", ..., "case").values for name in ds.data_vars
              if {"time", "case"} <= set(ds[name].dims)}
    arrays["t_s"] = ds["time"].values
    return list(ds["k_W_per_K"].values), arrays, diag, ds


def test_straight_run_stays_level_and_consumes_no_air(tmp_path):
    # 3 s along a 400 m straight (the curve lies beyond the end of the run)
    s = curve_scenario(tmp_path, straight_m=400.0, duration_s=3.0)
    ks, rec, diag, _ = simulate_curve(s, valves=True)
    assert not diag
    # the car starts in equilibrium at speed: nothing may move the valves out of their dead band
    assert np.abs(rec["crushing_m"]).max() < 1e-6
    assert np.abs(rec["roll_rad"]).max() < 1e-6
    assert rec["air_from_supply_kg"][-1, 0] == 0.0
    assert rec["air_to_atmosphere_kg"][-1, 0] == 0.0


@pytest.fixture(scope="module")
def curve_runs(tmp_path_factory):
    """A short curve entry (16 s: 8 m run-up, 15 m transition, ~137 m of arc) for k = 0 and inf."""
    s = curve_scenario(tmp_path_factory.mktemp("curve"), k=(0.0, float("inf")), duration_s=16.0, arc_m=150.0)
    return s, {v: simulate_curve(s, valves=v) for v in (False, True)}


@pytest.mark.slow
def test_valves_bring_the_bellows_back_into_the_dead_band(curve_runs):
    s, runs = curve_runs
    ks, rec, diag, _ = runs[True]
    assert not diag
    dead_band = s.circuit.levelling_valve.supply_lever_m[1] / s.circuit.levelling_valve.lever_gain
    last = rec["t_s"] > rec["t_s"][-1] - 3.0                  # the last 3 s, in the arc
    # without valves the roll in the arc crushes the bellows well beyond the dead band...
    z_off = np.abs(runs[False][1]["crushing_m"][last]).mean(axis=0)
    assert np.all(z_off > 2 * dead_band)
    # ...with valves every bellow is back at its edge: the mean |z| over the last 3 s is within the
    # dead band plus 1 mm (the car has no dampers: a ~1 Hz sway of about +-1 mm persists)
    z_on = np.abs(rec["crushing_m"][last]).mean(axis=0)
    assert np.all(z_on < dead_band + 1e-3), z_on
    # air went in (outer bellows) and out (inner bellows)
    assert np.all(rec["air_from_supply_kg"][-1] > 0) and np.all(rec["air_to_atmosphere_kg"][-1] > 0)


def test_circuit_mass_balance_closes(curve_runs):
    _, runs = curve_runs
    ks, rec, diag, _ = runs[True]
    change = rec["total_mass_kg"][-1] - rec["total_mass_kg"][0]
    exchanged = rec["air_from_supply_kg"][-1] - rec["air_to_atmosphere_kg"][-1]
    # RK4 integrates the chamber masses and the cumulative link flows with the same stages:
    # the balance closes to round-off relative to the ~0.5 kg of air in the circuit
    assert np.allclose(change, exchanged, rtol=0, atol=1e-12)


def test_isothermal_rolls_more_without_valves(curve_runs):
    _, runs = curve_runs
    ks, rec, diag, _ = runs[False]
    # the steady roll: mean over the last 3 s in the arc, whatever phase the ~1 Hz sway is in
    roll_end = np.abs(window_mean(rec["t_s"], rec["roll_rad"], 3.0))
    # softer isothermal bellows (A^2 p / V instead of gamma A^2 p / V): more roll (paper Fig. 9)
    assert roll_end[ks.index(float("inf"))] > roll_end[ks.index(0.0)]


@pytest.mark.slow
def test_roll_is_measured_from_the_track_plane_at_the_car_centre(tmp_path):
    """Cant raises the outer (right) rail of a left-hand curve: the track plane rolls right side
    up (negative carbody roll) and the carbody's outward roll relative to it scales with the
    lateral acceleration left uncompensated in the plane, a_u = (v^2/R) cos c - g sin c. Half the
    balancing cant (c = atan(v^2/(g R)) / 2, 76 mm over 1.5 m) halves the relative roll; with the
    sign of the cant taken the wrong way round the ratio would be ~3."""
    g = 9.81
    runs = {}
    for name, cant in (("level", 0.0), ("canted", 0.5 * math.atan(10.0 ** 2 / (g * 100.0)))):
        s = curve_scenario(tmp_path, k=(float("inf"),), cant_rad=cant, duration_s=8.0, arc_m=100.0)
        ks, rec, diag, _ = simulate_curve(s, valves=False)
        assert not diag
        runs[name] = s, rec
    s, rec = runs["canted"]
    c, v, R = s.experiment.cant_rad, s.experiment.speed_m_per_s, s.experiment.radius_m
    # the car centre starts where MetroCar puts it: the rear wheelset at s = 0
    assert car_centre_s_m(s, np.array([0.0]))[0] == pytest.approx(make_car(s).start_s_m, abs=1e-12)
    t = rec["t_s"]
    assert track_roll_rad(s, t)[0] == 0.0 and track_roll_rad(s, t)[-1] == pytest.approx(-c, rel=1e-12)   # in the arc
    rel = rec["roll_rel_rad"]
    assert np.array_equal(rel, rec["roll_rad"] - track_roll_rad(s, t)[:, None])
    level = window_mean(runs["level"][1]["t_s"], runs["level"][1]["roll_rad"][:, 0], 3.0)
    canted = window_mean(t, rel[:, 0], 3.0)
    assert level > 0 and canted > 0                       # outward (left side up) in a left-hand curve
    # 10 %: the window mean over 3 s leaves up to ~3 % of the undamped ~1 Hz sway, and the load
    # normal to the plane, g cos c + (v^2/R) sin c, is 2.5 % above g, stiffening the bellows
    a_u = (v * v / R) * math.cos(c) - g * math.sin(c)
    assert canted / level == pytest.approx(a_u / (v * v / R), rel=0.10)
    # the absolute roll is the plane's plus the relative one
    assert window_mean(t, rec["roll_rad"][:, 0], 3.0) == pytest.approx(canted - c, rel=1e-9)



def test_two_point_layout():
    """One levelling valve per bogie, driven by the mean height of both bellows, feeding the left
    one; the cross pipe joins the bellows of a bogie whether or not the valves are connected."""
    from pneumatics.chamber import Bellow, Tank
    from pneumatics.circuit import Circuit
    from pneumatics.layouts import car_circuit
    from pneumatics.pipe import Pipe
    from pneumatics.valves import LevellingValve
    cross = Pipe("", "", diameter_m=0.003)
    with_valves = car_circuit(Bellow(), Tank(), Pipe("", ""), levelling=LevellingValve(""), points=2, cross_pipe=cross)
    assert with_valves["lv_F"].sensed == ("FL", "FR") and with_valves["lv_F"].bellow == "FL"
    assert (with_valves["cross_R"].a, with_valves["cross_R"].b) == ("RL", "RR")
    isolated = car_circuit(Bellow(), Tank(), Pipe("", ""), points=2, cross_pipe=cross)
    assert "cross_F" in isolated and "lv_F" not in isolated
    # the lever of lv_F sees the mean crushing of FL and FR: +5 mm / -5 mm -> 0, inside the dead band
    circuit = Circuit(with_valves, k_W_per_K=0.0)
    x = circuit.initial_state({n: 4.2e5 for n in circuit.chamber_names})
    z = np.array([0.03, -0.03, 0.0, 0.0])          # FL compressed, FR extended: a pure roll
    flows = dict(zip(circuit.link_names, circuit.outputs(x, z).link_flow_kg_per_s))
    assert flows["lv_F.supply"] == 0.0 and flows["lv_F.exhaust"] == 0.0   # a two-point valve cannot level roll


def test_per_valve_air_adds_up_to_the_supply_total_and_open_fractions_are_fractions(curve_runs):
    # The supply's air can only reach the car through the levelling valves' supply sides (the
    # differential valves join two bellows): their sum is the total injected, to round-off.
    s, runs = curve_runs
    ks, _, _, ds = runs[True]
    valve_names = list(ds["valve"].values)
    assert valve_names
    for j, k in enumerate(ks):
        row = summary_row(ds.isel(case=j), s.experiment)
        supplied = sum(row[f"{v}_supply_air_kg"] for v in valve_names)
        assert supplied == pytest.approx(row["air_injected_kg"], rel=1e-9, abs=1e-12)
        assert row["air_injected_kg"] > 0
        fractions = [row[f"{v}_{side}_open_fraction"] for v in valve_names for side in ("supply", "exhaust")]
        assert all(0.0 <= f <= 1.0 for f in fractions) and max(fractions) > 0.0
