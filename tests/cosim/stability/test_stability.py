"""Running stability (cosim/stability, kind ``stability``): the coupled linearisation against finite
differences of the nonlinear car and circuit, the air's linear model against the Helmholtz
resonator and the static stiffness in closed form, and the kind end to end."""
from __future__ import annotations

import dataclasses
import math

import exudyn as exu
import numpy as np
import pytest
import yaml

from cosim.errors import ScenarioError
from cosim.kinds.stability import static_stiffness_N_per_m
from cosim.load import load_scenario
from cosim.runner import run
from cosim.scenario.presets import VEHICLE_PRESETS
from cosim.stability import couple, modes
from pneumatics.chamber import Bellow, Tank
from pneumatics.circuit import Circuit
from pneumatics.layouts import static_pressures
from pneumatics.linear import linearise_circuit
from pneumatics.pipe import Pipe
from vehicle.car import MetroCar
from vehicle.car.linear import linearise_car
from vehicle.linear import ode2_rhs

from helpers import SCENARIOS, write_scenario

GAMMA = 1.4


def _scenario(tmp_path, **stability):
    data = yaml.safe_load((SCENARIOS / "stability.yaml").read_text())
    data["stability"].update(stability)
    data["k_W_per_K"] = [0, 10, float("inf")]
    data.pop("checks", None)
    return load_scenario(write_scenario(tmp_path, data))


# ------------------------------------------------------------------ the air's linear model
def _bellow_tank(k):
    components = {"B": Bellow(), "T": Tank(), "p": Pipe(a="B", b="T")}
    circuit = Circuit(components, k_W_per_K=k)
    return circuit, circuit.initial_state({"B": 4.2e5, "T": 4.2e5})


@pytest.mark.parametrize("k, n", [(0.0, GAMMA), (math.inf, 1.0)])
def test_bellow_tank_resonates_at_helmholtz_frequency(k, n):
    """Bellow and tank joined by the pipe, the bellow held: the linearised circuit's oscillatory
    eigenvalue is the Helmholtz resonator's, w^2 = (A/L) c^2 (1/V_b + 1/V_t), c^2 = n p / rho (n = gamma
    adiabatic at k = 0, 1 isothermal at k = inf), to round-off (1e-6: the central differences), and
    undamped: the pipe's loss is quadratic in the flow, it has no linear part at rest (the central
    difference of q |q| over +-h gives h, a damping ratio of ~4e-9 here: bounded at 1e-8, two orders
    below the tolerance at which cosim.stability calls a mode growing)."""
    circuit, x0 = _bellow_tank(k)
    air = linearise_circuit(circuit, x0)
    values = np.linalg.eigvals(air.A)
    w = max(values.imag)
    b, t, pipe = (circuit.components[c] for c in ("B", "T", "p"))
    rho = 4.2e5 / (circuit.gas.R_J_per_kgK * circuit.atmosphere.T_K)
    expected = math.sqrt(pipe.area_m2 / pipe.length_m * n * 4.2e5 / rho * (1 / b.V0_m3 + 1 / t.V_m3))
    assert w == pytest.approx(expected, rel=1e-6)
    pair = max(values, key=lambda v: v.imag)
    assert abs(pair.real) / abs(pair) < 1e-8


def test_heat_exchange_damps_the_helmholtz_mode():
    """Between the two limits (k = 10 W/K) the resonator loses energy through the walls: damped."""
    circuit, x0 = _bellow_tank(10.0)
    values = np.linalg.eigvals(linearise_circuit(circuit, x0).A)
    pair = max(values, key=lambda v: v.imag)
    assert -pair.real / abs(pair) > 1e-4


@pytest.mark.parametrize("k, n", [(0.0, GAMMA), (10.0, 1.0), (math.inf, 1.0)])
def test_static_stiffness_is_the_polytropic_one_of_bellow_and_tank(k, n):
    """The airspring's static stiffness (the dynamic stiffness at w -> 0) in closed form: n p A^2 /
    (V_b + V_t) with the tank's volume joined, adiabatic (n = gamma) at k = 0 (nothing relaxes the
    temperature), isothermal for any k > 0 (the walls have all the time they need)."""
    circuit, x0 = _bellow_tank(k)
    air = linearise_circuit(circuit, x0)
    b, t = circuit.components["B"], circuit.components["T"]
    expected = n * 4.2e5 * b.A0_m2 ** 2 / (b.V0_m3 + t.V_m3)     # A = A0 and dV/dz = A0 here
    assert b.dV_dz_m2 == b.A0_m2 and b.dA_dz_m == 0.0
    assert static_stiffness_N_per_m(air)[0, 0] == pytest.approx(expected, rel=1e-5)


# ------------------------------------------------------------------ the coupled linearisation
def _nonlinear_rate(car, circuit, x_full0, lin, model, X):
    """d/dt of the coupled state X (the layout of :class:`CoupledModel`) from the nonlinear car and
    circuit: the car's coordinates and rates, the Maxwell dampers' elongations and the air's state
    set from X, the bellow force law anchored at the air's force at the bellows' current crushing,
    exudyn's right-hand side solved for the reduced accelerations, the circuit's derivatives at
    the car's crushing and rate."""
    mbs, solver, sys = car.mbs, car._solver, lin.system
    n = sys.M.shape[0]
    eta = np.zeros(n)
    eta[model.position_coordinates] = X[model.positions]
    q = car._lin_q0 + sys.N @ eta
    v = car._lin_v0 + sys.N @ X[model.rates]
    mbs.systemData.SetODE2Coordinates(q, exu.ConfigurationType.Current)
    mbs.systemData.SetODE2Coordinates_t(v, exu.ConfigurationType.Current)
    w = X[model.maxwell]
    for d, wi in zip(car._maxwell, w):
        d.y_sym.SetValue(d.y + wi)
    out = [X[model.rates][model.position_coordinates]]
    x = x_full0.copy()
    car._bellow_t = None
    z, zd = car.bellow_crushing()
    if model.air is not None:
        # the law F_air(x, z_b) to first order about the anchor z_b0: F_air(x, z_b0) + G_z (z_b - z_b0);
        # with an emergency spring in series the bellow's own crushing rate depends on the rate of
        # the air's force too: a fixed point, dF/dt from the circuit's derivatives
        x[model.air.index] += X[model.pneumatic]
        F, rate = circuit.bellow_forces_N(x, car._lin_z0), np.zeros(4)
        for _ in range(4 if car.airspring_in_series else 1):
            car.set_bellow_forces(F, np.diag(model.air.G_z), rate, z_anchor_m=car._lin_z0)
            z, zd = car.bellow_crushing()
            xdot = circuit.derivatives(x, z, zd)
            eps = 1e-3
            rate = (circuit.bellow_forces_N(x + eps * xdot, car._lin_z0)
                    - circuit.bellow_forces_N(x - eps * xdot, car._lin_z0)) / (2 * eps)
    eta_dd = np.linalg.solve(sys.M, sys.N.T @ ode2_rhs(mbs, solver))
    out.append(eta_dd)
    get = mbs.GetObjectOutput
    d_now = np.array([get(d.connector, exu.OutputVariableType.DisplacementLocal)[d.axis] for d in car._maxwell])
    out.append(lin.maxwell_rate_per_s * (d_now - np.array([d.y for d in car._maxwell]) - w))
    if model.air is not None:
        out.append(circuit.derivatives(x, z, zd)[model.air.index])
    return np.concatenate(out)


@pytest.mark.parametrize("preset, with_air", [("paper_metro_car", True), ("metro_car_arb_dampers", False),
                                              ("metro_car_arb_dampers", True)])
def test_coupled_linearisation_is_the_derivative_of_the_nonlinear_system(tmp_path, preset, with_air):
    """A d for random directions d against central differences of the nonlinear coupled rate
    (:func:`_nonlinear_rate`) at +-d, d small enough for the remainder and large enough to be a
    derivative of the real functions, not of the linearisation's own differences (positions 1e-7 m
    and rates 1e-5 m/s, 10 and 10 times the linearisation's steps; air 1e-6 of its state). The
    paper's car with its four-point circuit (k = 10: every air term alive), and the car with
    dampers (Maxwell elements, emergency springs in series with the bellows) with the air frozen
    and with its circuit. (The last case was added after the PSD check of the ride found the
    bellow input of in-series airsprings wrong: its differences had moved the law's anchor.) Measured: at most ~3e-6 of
    the largest entry of each block of A d, falling as d shrinks (positions 1e-6 m gave 6e-5: the
    Hertz contacts' nonlinearity over d); tolerance 1e-4."""
    s = _scenario(tmp_path, speeds_m_per_s=[30.0])
    s = dataclasses.replace(s, vehicle=VEHICLE_PRESETS[preset]())
    car = MetroCar(s.vehicle, step_s=2e-3, speed_m_per_s=30.0, guidance="contact")
    F0 = car.static_bellow_forces_N()
    circuit = s.circuit.compile(10.0)
    x0 = circuit.initial_state(static_pressures(s.circuit.components(), F0, circuit.atmosphere.p_Pa))
    air = linearise_circuit(circuit, x0)
    lin = linearise_car(car, F0, np.diag(air.G_z))
    car._lin_q0 = np.array(car.mbs.systemData.GetODE2Coordinates())
    car._lin_v0 = np.array(car.mbs.systemData.GetODE2Coordinates_t())
    car._lin_z0 = np.array([law[3] for law in car._bellow_law])
    model = couple(lin, air if with_air else None)
    rng = np.random.default_rng(3)
    size = model.A.shape[0]
    scale = np.ones(size)
    scale[model.positions], scale[model.rates], scale[model.maxwell] = 1e-7, 1e-5, 1e-7
    if with_air:
        scale[model.pneumatic] = 1e-6 * np.abs(x0[air.index]) + 1e-9
    for _ in range(3):
        d = rng.standard_normal(size) * scale
        plus = _nonlinear_rate(car, circuit, x0, lin, model, d)
        minus = _nonlinear_rate(car, circuit, x0, lin, model, -d)
        numeric = (plus - minus) / 2.0
        linear = model.A @ d
        for block in (model.positions, model.rates, model.maxwell, model.pneumatic):
            if linear[block].size:
                err = np.max(np.abs(numeric[block] - linear[block]))
                assert err <= 1e-4 * np.max(np.abs(linear[block])), (block, err, np.max(np.abs(linear[block])))
    if not with_air:
        assert model.maxwell.stop > model.maxwell.start      # the Maxwell elements were in it


# ------------------------------------------------------------------ the kind
def test_stability_run_gives_critical_speeds_modes_and_figures(tmp_path):
    """The shipped scenario at a few speeds: every case row has a critical speed inside its scan
    bracket found to the resolution, the mode that loses damping is a bogie hunting mode, the
    carbody modes are in the rows, modes.csv lists them, and the check decides on the worst k."""
    data = yaml.safe_load((SCENARIOS / "stability.yaml").read_text())
    data["stability"].update(speeds_m_per_s=[10.0, 30.0, 50.0], resolution_m_per_s=0.5)
    data["k_W_per_K"] = [0, float("inf")]
    data["checks"] = ["critical_speed_m_per_s >= 33.3", "min_damping_ratio >= 0"]
    out = run(load_scenario(write_scenario(tmp_path, data)))
    assert len(out.rows) == 4                             # 2 k x (circuit, static)
    for row in out.rows:
        assert 30.0 < row["critical_speed_m_per_s"] < 50.0
        assert "hunting" in row["critical_mode"] and 3.0 < row["critical_frequency_Hz"] < 10.0
        assert 0.5 < row["f_bounce_Hz"] < 2.0 and 0.0 < row["zeta_bounce"] < 0.5
    results = dict((c.text, v) for c, v in out.check_results())
    assert results["critical_speed_m_per_s >= 33.3"] == min(r["critical_speed_m_per_s"] for r in out.rows
                                                            if r["airspring"] == "circuit")
    assert results["min_damping_ratio >= 0"] < 0.0 and not out.checks_hold()
    assert {m["mode"] for m in out.tables["modes"]} >= {"carbody bounce", "carbody pitch", "carbody yaw"}
    from cosim.kinds.stability import figures
    assert [f.name for f in figures(out)] == ["stability_valves=off_circuit.png", "stability_valves=off_static.png"]
    assert all(len(f.panels) == 4 for f in figures(out))     # per k: root locus, damping against speed


def test_the_least_damped_modes_are_labelled_by_what_moves(tmp_path):
    """At 10 m/s the car with dampers has its textbook modes, named from their kinetic energy:
    carbody bounce, pitch, yaw, lower and upper sway (the upper sway, rolling about a point below
    the body, the lower in frequency) and an air mode; every mode below 20 Hz stable."""
    s = _scenario(tmp_path, speeds_m_per_s=[10.0])
    from cosim.kinds.stability import _air, _Cars, contact_params, make_car
    car = make_car(s, 10.0)
    F0 = car.static_bellow_forces_N()
    air = _air(s, False, 10.0, F0)
    found = modes(couple(_Cars(s, F0, np.diag(air.G_z), contact_params(s.experiment, s.vehicle))(10.0), air))
    low = [m for m in found if 0.0 < m.frequency_Hz < 20.0]
    labels = {m.label for m in low}
    assert {"carbody bounce", "carbody pitch", "carbody yaw", "carbody lower sway", "carbody upper sway", "air"} <= labels
    f = {m.label: m.frequency_Hz for m in sorted(low, key=lambda m: -m.frequency_Hz)}
    assert f["carbody upper sway"] < f["carbody lower sway"]
    assert all(m.damping_ratio > 0.0 for m in low)


def test_contact_pair_keys_are_checked(tmp_path):
    data = yaml.safe_load((SCENARIOS / "stability.yaml").read_text())
    data["stability"].update(conicity=0.2, wheel_profile="worn.prw")
    with pytest.raises(ScenarioError, match=r"stability\.wheel_profile.*not both"):
        load_scenario(write_scenario(tmp_path, data))
    data["stability"].pop("conicity")
    with pytest.raises(ScenarioError, match=r"stability\.wheel_profile.*does not exist"):
        load_scenario(write_scenario(tmp_path, data))
    data["stability"].pop("wheel_profile")
    data["stability"]["conicity"] = 1.5
    with pytest.raises(ScenarioError, match=r"stability\.conicity"):
        load_scenario(write_scenario(tmp_path, data))


@pytest.mark.slow
def test_brute_force_onset_on_a_cone_agrees_with_the_linear_critical_speed(tmp_path):
    """The car with dampers on a 0.2 cone (linear critical speed 54.49 m/s): released at 0.5 mm, the
    co-simulated car's hunting dies at 5 % below the linear critical speed and grows at 5 % above,
    so the brute-force onset lies within 5 % of it (the issue's tolerance; measured 54.76 m/s,
    0.5 %); below it, the measured decay rate is the linear model's (Re lambda of the least damped
    hunting mode, -0.7111 /s against -0.7106 /s measured at 51.77 m/s: 0.07 %; asked within 5 %:
    the run's 5 ms steps and the small amplitude's nonlinearity)."""
    data = {"kind": "stability", "name": "cone", "k_W_per_K": [10], "vehicle": "metro_car_arb_dampers",
            "circuit": {"layout": "four_point", "preset": "paper_table1", "valves": False},
            "stability": {"speeds_m_per_s": [40.0, 50.0, 60.0], "conicity": 0.2, "nonlinear_s": 6.0,
                          "disturbances_m": [0.0005]},
            "solver": {"jobs": 1}}
    first = run(load_scenario(write_scenario(tmp_path, data)))
    v_lin = first.rows[0]["critical_speed_m_per_s"]
    assert 50.0 < v_lin < 60.0
    data["stability"]["nonlinear_speeds_m_per_s"] = [0.95 * v_lin, 1.05 * v_lin]
    out = run(load_scenario(write_scenario(tmp_path, data, "nonlinear.yaml")))
    below, above = sorted(out.tables["nonlinear"], key=lambda r: r["speed_m_per_s"])
    assert below["growth_rate_per_s"] < 0.0 < above["growth_rate_per_s"]
    row = next(r for r in out.rows if r["airspring"] == "circuit")
    assert abs(row["nonlinear_onset_m_per_s"] / v_lin - 1.0) < 0.05
    s = load_scenario(write_scenario(tmp_path, data, "nonlinear.yaml"))
    from cosim.kinds.stability import _air, _Cars, contact_params, make_car
    F0 = make_car(s, 10.0).static_bellow_forces_N()
    air = _air(s, False, 10.0, F0)
    linear = modes(couple(_Cars(s, F0, np.diag(air.G_z), contact_params(s.experiment, s.vehicle))(below["speed_m_per_s"]), air))
    sigma = max(m.eigenvalue.real for m in linear if m.frequency_Hz > 0 and "hunting" in m.label)
    assert below["growth_rate_per_s"] == pytest.approx(sigma, rel=0.05)


@pytest.mark.slow
def test_ramp_down_follows_the_limit_cycle_below_the_linear_critical_speed(tmp_path):
    """The car with dampers on S1002 / UIC60, released at 3 mm at 45 m/s (above its linear critical
    speed, 40.3 m/s), settles on a hunting limit cycle (~1.8 mm at the leading wheelset) and keeps
    it while slowing down far below the linear critical speed (the bifurcation is subcritical; the
    pair's conicity at small amplitude, above its conicity at the centre, would explain it, not
    isolated: docs/stability.md) until it collapses near 27-28 m/s. Halving the deceleration (1 -> 0.5 m/s^2)
    moves that speed by 0.75 m/s (2.7 %): asked within 5 %. 25 s of wall time."""
    data = {"kind": "stability", "name": "ramp", "k_W_per_K": [10], "vehicle": "metro_car_arb_dampers",
            "circuit": {"layout": "four_point", "preset": "paper_table1", "valves": False},
            "stability": {"speeds_m_per_s": [20.0, 40.0, 45.0], "ramp_from_m_per_s": 45.0, "ramp_to_m_per_s": 20.0,
                          "ramp_decelerations_m_per_s2": [1.0, 0.5], "ramp_hold_s": 3.0, "ramp_disturbance_m": 0.003},
            "solver": {"jobs": 2}}
    out = run(load_scenario(write_scenario(tmp_path, data)))
    ramps = {r["deceleration_m_per_s2"]: r for r in out.tables["ramp"]}
    circuit = next(r for r in out.rows if r["airspring"] == "circuit")
    v_lin = circuit["linear_critical_speed_m_per_s"]
    assert all(r["limit_cycle_amplitude_m"] > 1e-3 for r in ramps.values())
    fast, slow = ramps[1.0]["limit_cycle_ends_m_per_s"], ramps[0.5]["limit_cycle_ends_m_per_s"]
    assert fast < slow < v_lin - 5.0
    assert abs(fast / slow - 1.0) < 0.05
    assert out.rows[0]["limit_cycle_ends_m_per_s"] == slow
    # the verdict is the lower of the two, named: the linear speed passes a car that hunts far below it
    assert circuit["critical_speed_m_per_s"] == slow and circuit["critical_speed_by"] == "ramp-down"
    assert out.metrics["critical_speed_m_per_s"] == slow < out.metrics["linear_critical_speed_m_per_s"]


def test_the_verdict_is_the_lowest_speed_any_analysis_shows_hunting():
    """verdict_columns on rows whose answers follow from its definition: linear alone; a ramp-down
    and a brute force below the linear speed (the lowest decides, named); a brute force whose larger
    disturbance hunts below the smallest one's onset; a time domain above the linear speed (the
    linear decides); a limit cycle that never died (unknown: NaN, so a lower limit fails); a brute
    force that found no hunting (the linear decides)."""
    from cosim.kinds.stability import verdict_columns
    base = {"valves": False, "k_W_per_K": 10.0, "linear_critical_speed_m_per_s": 40.3}
    assert verdict_columns(base) == {"linear_critical_speed_m_per_s": 40.3, "critical_speed_m_per_s": 40.3,
                                     "critical_speed_by": "linear"}
    both = verdict_columns({**base, "nonlinear_onset_m_per_s": 28.5, "limit_cycle_ends_m_per_s": 28.26})
    assert (both["critical_speed_m_per_s"], both["critical_speed_by"]) == (28.26, "ramp-down")
    assert both["nonlinear_critical_speed_m_per_s"] == 28.26
    runs = [{"valves": False, "k_W_per_K": 10.0, "speed_m_per_s": v, "hunts": h, "disturbance_m": d}
            for v, h, d in ((24.0, False, 5e-4), (30.0, True, 5e-4), (27.0, True, 3e-3))]
    runs.append({**runs[2], "k_W_per_K": 0.0, "speed_m_per_s": 20.0})     # another case's run: not this row's
    brute = verdict_columns({**base, "nonlinear_onset_m_per_s": 28.5}, runs)
    assert (brute["critical_speed_m_per_s"], brute["critical_speed_by"]) == (27.0, "brute force")
    above = verdict_columns({**base, "nonlinear_onset_m_per_s": 41.0, "limit_cycle_ends_m_per_s": 40.9})
    assert (above["critical_speed_m_per_s"], above["critical_speed_by"]) == (40.3, "linear")
    never = verdict_columns({**base, "limit_cycle_ends_m_per_s": math.nan})
    assert math.isnan(never["critical_speed_m_per_s"]) and "did not die" in never["critical_speed_by"]
    quiet = verdict_columns({**base, "nonlinear_onset_m_per_s": math.nan}, runs[:1])
    assert (quiet["critical_speed_m_per_s"], quiet["critical_speed_by"]) == (40.3, "linear")
    assert math.isnan(quiet["nonlinear_critical_speed_m_per_s"])


def test_a_linear_only_run_says_so_and_refuses_a_nonlinear_check(tmp_path):
    """Without a time-domain analysis the run warns that its critical speed is the linear one, and a
    check on the nonlinear critical speed is refused at load, naming the keys that would run one."""
    data = yaml.safe_load((SCENARIOS / "stability.yaml").read_text())
    data["checks"] = ["nonlinear_critical_speed_m_per_s >= 20"]
    with pytest.raises(ScenarioError, match=r"ramp_from_m_per_s"):
        load_scenario(write_scenario(tmp_path, data))
    from cosim.kinds.stability import LINEAR_ONLY_WARNING
    data["stability"].update(speeds_m_per_s=[30.0, 50.0], resolution_m_per_s=2.0)
    data["k_W_per_K"], data["checks"] = [0], ["linear_critical_speed_m_per_s >= 33.3"]
    out = run(load_scenario(write_scenario(tmp_path, data)))
    assert out.warnings == [LINEAR_ONLY_WARNING]
    assert all(r["critical_speed_by"] == "linear" for r in out.rows) and out.checks_hold()


def test_growth_rate_envelope_and_onset_from_synthetic_records():
    """The time-history readers on records whose answers are known: a sine growing or decaying at
    sigma (its fitted rate to 1e-3, the peaks sampled every 2 ms at 5 Hz), saturating at an
    amplitude (the fit stops at the amplitude bound); a limit cycle that fades linearly from
    2 mm at t = 10 s to 0 at t = 30 s, read at 5 % of its amplitude (t = 29 s, to the 0.05 s hop);
    the onset between a dying and a growing run, and between a dying run and a limit cycle."""
    from cosim.stability.nonlinear import final_amplitude_m, growth_rate_per_s, limit_cycle_end, onset_speed
    t = np.arange(0.0, 8.0, 0.002)
    for sigma in (-0.7, 0.4):
        y = 1e-3 * np.exp(sigma * t) * np.sin(2 * np.pi * 5.0 * t)
        assert growth_rate_per_s(t, y) == pytest.approx(sigma, rel=1e-3)
    grown = np.minimum(1e-4 * np.exp(0.8 * t), 5e-3) * np.sin(2 * np.pi * 5.0 * t)
    assert growth_rate_per_s(t, grown, max_amplitude_m=2e-3) == pytest.approx(0.8, rel=1e-2)
    t = np.arange(0.0, 35.0, 0.002)
    fading = 2e-3 * np.clip((30.0 - t) / 20.0, 0.0, 1.0) * np.sin(2 * np.pi * 5.0 * t)
    t_end, amplitude = limit_cycle_end(t, fading, hold_s=10.0)
    assert amplitude == pytest.approx(2e-3, rel=1e-3) and t_end == pytest.approx(29.0, abs=0.06)
    assert onset_speed([50.0, 60.0], [-1.0, 1.0], [False, True])[0] == pytest.approx(55.0)
    assert onset_speed([27.0, 30.0], [-2.7, 1e-4], [False, True])[0] == pytest.approx(28.5)
    assert onset_speed([30.0, 36.0], [1e-4, 1e-4], [True, True])[0] is None
    assert onset_speed([50.0, 60.0], [-1.0, math.inf], [False, True])[0] == pytest.approx(55.0)   # derailed
    # a hold off the envelope's grid, a record starting later, empty and sparse records
    t_end, amplitude = limit_cycle_end(t + 0.013, fading, hold_s=10.37)
    assert amplitude == pytest.approx(2e-3, rel=2e-2) and t_end == pytest.approx(29.013, abs=0.06)
    assert all(math.isnan(v) for v in limit_cycle_end(t, fading, hold_s=0.5))    # no second of hold
    assert math.isnan(growth_rate_per_s([], [])) and math.isnan(final_amplitude_m([], []))
    from cosim.stability.nonlinear import envelope
    _, sparse = envelope(np.arange(0.0, 10.0, 2.0), np.ones(5))
    assert np.isnan(sparse).any() and not (sparse < 0.5).any()


@pytest.mark.slow
def test_a_wheel_profile_file_gives_the_table_derived_from_it(tmp_path):
    """``wheel_profile``: the S1002 profile given as a file derives the very table the car ships
    for its 0.42 m wheels (the same pair, rail and setup): the same critical speed."""
    import shutil

    from vehicle.wheelrail.geometry import DEFAULT_WHEEL
    shutil.copy(DEFAULT_WHEEL, tmp_path / "my_wheel.prw")
    data = {"kind": "stability", "name": "profile", "k_W_per_K": [10], "vehicle": "metro_car_arb_dampers",
            "circuit": {"layout": "four_point", "preset": "paper_table1", "valves": False},
            "stability": {"speeds_m_per_s": [35.0, 45.0], "resolution_m_per_s": 0.5}}
    shipped = run(load_scenario(write_scenario(tmp_path, data)))
    data["stability"]["wheel_profile"] = "my_wheel.prw"
    derived = run(load_scenario(write_scenario(tmp_path, data, "profile.yaml")))
    assert derived.info["contact_table"].endswith(".csv")
    assert derived.rows[0]["critical_speed_m_per_s"] == pytest.approx(shipped.rows[0]["critical_speed_m_per_s"], rel=1e-9)
    # and another profile is not ignored: the same wheel with its points tilted (z + 0.05 y, an
    # equivalent conicity of 0.39 instead of 0.63 at 0.5 mm) hunts at another speed
    lines = []
    for line in (tmp_path / "my_wheel.prw").read_text().splitlines():
        parts = line.split("\t")
        if len(parts) == 2 and not line.startswith("!"):
            y, z = map(float, parts)
            line = f"{y:.7E}\t{z + 0.05 * y:.7E}"
        lines.append(line)
    (tmp_path / "tilted.prw").write_text("\n".join(lines) + "\n")
    data["stability"]["wheel_profile"] = "tilted.prw"
    tilted = run(load_scenario(write_scenario(tmp_path, data, "tilted.yaml")))
    assert tilted.info["contact_table"] != derived.info["contact_table"]
    assert abs(tilted.rows[0]["critical_speed_m_per_s"] - shipped.rows[0]["critical_speed_m_per_s"]) > 1.0


@pytest.mark.slow
def test_floor_acceleration_rms_against_the_linearised_model(tmp_path):
    """The car with dampers at 20 m/s over ERRI B176 (low) vertical level alone, 40 s record, k = 10,
    valves isolated: the rms vertical floor acceleration at the car centre from the time domain
    against the linearised car and circuit (cosim/stability) driven by the level's spectrum,
    sigma^2 = integral |H(V Omega)|^2 S(Omega) dOmega over the generated band, each wheelset meeting
    the level x_i / V before the centre. Measured 0.0427 against 0.0422 m/s^2 (1 %); asked 10 %.
    With every step halved twice the measurement is 0.04267 / 0.04277 / 0.04280 (order 2.0,
    Richardson 0.0428: 1.4 % from the prediction).
    The generator's amplitudes are the spectrum's own (random phases only), so the record's
    rms scatters little around the prediction. (This check found the linearisation's bellow input
    wrong for airsprings with an emergency spring in series: the prediction had been 19 % high.)"""
    from cosim.kinds.stability import _air, _Cars, contact_params, make_car
    from cosim.stability.coupled import level_response
    from vehicle.irregularities import psd
    V, k = 20.0, 10.0
    data = yaml.safe_load((SCENARIOS / "ride_comfort.yaml").read_text())
    data["k_W_per_K"] = [k]
    data["ride"].update(speeds_m_per_s=[V], record_s=40.0, valve_settings=[False])
    data["ride"]["irregularity"]["channels"] = ["vertical"]
    data.pop("checks", None)
    out = run(load_scenario(write_scenario(tmp_path, data)))
    ds = out.series[f"ride_v={V:g}"]
    az = ds["floor_az_m_per_s2"].sel(floor_point="centre").isel(case=0).values
    measured = np.std(az[ds["time"].values >= out.rows[0]["record_from_s"]])
    linear = {**data, "kind": "stability", "stability": {"speeds_m_per_s": [V]}, "solver": {"jobs": 1}}
    linear.pop("ride")
    s = load_scenario(write_scenario(tmp_path, linear, "linear.yaml"))
    car = make_car(s, V)
    F0 = car.static_bellow_forces_N()
    air = _air(s, False, k, F0)
    model = couple(_Cars(s, F0, np.diag(air.G_z), contact_params(s.experiment, s.vehicle), rail_inputs=True)(V), air)
    shortest, longest = data["ride"]["irregularity"]["wavelength_range_m"]
    omega = np.linspace(2 * np.pi / longest, 2 * np.pi / shortest, 20001)
    H = level_response(model, omega * V, car.wheelset_x_m, ("carbody", "z"))
    predicted = np.sqrt(np.trapezoid(np.abs(H) ** 2 * psd("erri_b176_low", "vertical", omega), omega))
    assert measured == pytest.approx(predicted, rel=0.10)


def test_a_car_unstable_at_every_scanned_speed_fails_a_critical_speed_check(tmp_path):
    """A 0.4 cone scanned at 90 m/s only (hunting grows there): the critical speed lies below the
    scan, unknown: NaN, said in the note, and a lower limit on it fails (reporting the lowest speed
    would have passed ``>= 50``)."""
    data = {"kind": "stability", "name": "fast", "k_W_per_K": [10], "vehicle": "metro_car_arb_dampers",
            "circuit": {"layout": "four_point", "preset": "paper_table1", "valves": False},
            "stability": {"speeds_m_per_s": [90.0], "conicity": 0.4},
            "checks": ["critical_speed_m_per_s >= 50"]}
    out = run(load_scenario(write_scenario(tmp_path, data)))
    row = next(r for r in out.rows if r["airspring"] == "circuit")
    assert math.isnan(row["critical_speed_m_per_s"]) and "already at 90" in row["critical_note"]
    assert "hunting" in row["critical_mode"]
    assert not out.checks_hold()


def test_faults_are_refused_not_ignored(tmp_path):
    """A burst bellow in a stability scenario had run as the intact car (every mode the intact
    car's, the rows labelled with the fault): refused at load, naming faults and why."""
    data = yaml.safe_load((SCENARIOS / "stability.yaml").read_text())
    data["faults"] = [{"kind": "burst", "component": "FR", "t_s": 0.0, "area_m2": 5e-4}]
    with pytest.raises(ScenarioError, match=r"faults.*does not honour faults"):
        load_scenario(write_scenario(tmp_path, data))
