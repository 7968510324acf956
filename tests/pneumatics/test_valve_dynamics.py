"""Levelling-valve response dynamics (play, dead time, lag) and per-valve outputs.

Every expected value is computed here from the element's own equation (closed forms: the
exponential of a lag, the Erlang distribution of the delay chain, the geometry of a play, the
fraction of a sine period spent beyond the dead band), never taken from a run.

Tolerance budget: the runs use the package's fixed-step RK4 (pneumatics.integrate.rk4) with
h = 1 ms unless stated. For the linear filters the error is RK4's: a mode of rate lambda has a
relative error ~ (h lambda)^5 / 120 per step, negligible here (h lambda <= 0.04). Where a
discontinuous switch is involved (a valve side opening, the play engaging) the fixed step
locates the instant only to within one step, so the tolerances are then one or two steps.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from pneumatics.boundary import Supply
from pneumatics.chamber import Bellow, Tank
from pneumatics.circuit import Circuit, CircuitError, StateLayout
from pneumatics.integrate import rk4
from pneumatics.layouts import car_circuit
from pneumatics.orifice import orifice_flow_kg_per_s
from pneumatics.pipe import Pipe
from pneumatics.valves import LevellingValve, erlang_step_response, lever_conductance

P0 = 4.0e5                  # bellow initial pressure [Pa]
P_SUPPLY = 9.0e5            # main reservoir [Pa]
DEAD_BAND = 0.005           # default tables: closed up to 5 mm of lever ...
FULL_OPEN = 0.025           # ... fully open from 25 mm
H = 1e-3                    # RK4 step [s]


def valve_circuit(n_cases=None, **dynamics):
    """A bellow fed by a levelling valve from a 9 bar supply, exhausting to the atmosphere."""
    comps = {"bellow": Bellow(p0_Pa=P0), "supply": Supply(p_Pa=P_SUPPLY), "lv": LevellingValve("bellow", **dynamics)}
    circuit = Circuit(comps, k_W_per_K=0.0 if n_cases is None else np.zeros(n_cases))
    return circuit, circuit.initial_state()


def run(circuit, x0, motion, t_end_s, h_s=H):
    """RK4 from t = 0; returns the times and states after every step (states, steps[, cases])."""
    ts, xs = [], []

    def f(t, x):
        z, zd = motion(t)
        return circuit.derivatives(x, z, zd)

    rk4(f, x0, 0.0, t_end_s, round(t_end_s / h_s), lambda t, x: (ts.append(t), xs.append(x.copy())))
    return np.array(ts), np.stack(xs, axis=1)


def step_motion(amplitude_m, t_step_s=0.0, n_cases=None):
    """Crushing stepped from 0 to ``amplitude_m`` at grid point ``t_step_s`` (zero rate: the lever
    play is not used with it). The switch is placed a quarter step early so that the stages from
    t_step on see the step whatever the rounding of t_step; the last stage of the step before it
    (also at t_step) sees it too, which shifts the step earlier by about h/6 for the integrator."""
    a = np.asarray(amplitude_m, float).reshape(1, -1) if n_cases else np.array([amplitude_m])

    def motion(t):
        return (a if t > t_step_s - 0.25 * H else np.zeros_like(a)), np.zeros_like(a)
    return motion


def erlang_cdf(x, n):
    """P(n, n x): the fraction of a unit step through an n-stage delay chain of total time 1,
    at x delays after the step (the Erlang distribution, written out)."""
    x = np.maximum(np.asarray(x, float), 0.0)
    terms = sum(np.exp(-n * x) * (n * x) ** k / math.factorial(k) for k in range(n))
    return 1.0 - terms


def erlang_quantile(q, n):
    """x with P(n, n x) = q, by bisection on erlang_cdf."""
    lo, hi = 0.0, 10.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if erlang_cdf(mid, n) < q else (lo, mid)
    return 0.5 * (lo + hi)


# =============================================================================
# Defaults: an instantaneous valve, the former state layout (+ open-time accumulators)
# =============================================================================
def test_default_valve_keeps_former_layout_and_instantaneous_law():
    circuit, x = valve_circuit(n_cases=5)
    lay = circuit.layout
    # bellow (1 chamber), no pipe, links: lv.supply, lv.exhaust. The former layout ends with
    # the three energy accumulators; only the valve's two open-time accumulators follow.
    former = StateLayout(1, 0, 2)
    for group in ("m", "T", "q", "mass_through", "heat_in", "work_in", "enthalpy_in"):
        assert getattr(lay, group) == getattr(former, group)
    assert lay.n_valve_states == 0 and lay.valve_signal == slice(former.size + 2, former.size + 2)
    assert lay.open_time == slice(former.size, former.size + 2) and lay.size == former.size + 2
    # the same valve with every dynamic parameter explicitly 0 is the same circuit
    zero = Circuit({**circuit.components, "lv": LevellingValve("bellow", lag_s=0.0, delay_s=0.0, hysteresis_m=0.0)},
                   k_W_per_K=np.zeros(5))
    assert zero.layout == lay
    # The derivative of the bellow mass is the instantaneous valve law at u = z: the supply
    # side's flow minus the exhaust side's, ISO 6358 at the tabulated conductance, bit for bit.
    z = np.array([[-0.030, -0.012, 0.0, 0.0051, 0.018]])
    zd = np.array([[0.1, -0.2, 0.3, 0.0, -0.05]])
    # (pressure and temperature from the circuit: their own laws are tested in test_pneumatics)
    out = circuit.outputs(x, z)
    p_b, T = out.p_Pa, out.T_K
    atm = circuit.atmosphere
    tables = circuit.components["lv"]
    C_s = lever_conductance(z, tables.supply_lever_m, tables.supply_C_m3_per_sPa)
    C_e = lever_conductance(-z, tables.exhaust_lever_m, tables.exhaust_C_m3_per_sPa)
    assert np.count_nonzero(C_s) == 2 and np.count_nonzero(C_e) == 2   # both sides and the dead band
    w_s = orifice_flow_kg_per_s(C_s, 0.4, np.full_like(z, P_SUPPLY), np.full_like(z, atm.T_K), p_b, T)
    w_e = orifice_flow_kg_per_s(C_e, 0.4, p_b, T, np.full_like(z, atm.p_Pa), np.full_like(z, atm.T_K))
    for c in (circuit, zero):
        dx = c.derivatives(x, z, zd)
        np.testing.assert_array_equal(dx[lay.m], w_s - w_e)
        np.testing.assert_array_equal(dx[lay.mass_through], np.vstack([w_s, w_e]))
        np.testing.assert_array_equal(c.valve_lever_m(x, z), z)


def test_circuit_without_valves_has_exactly_the_former_layout():
    comps = {"bellow": Bellow(p0_Pa=P0), "tank": Tank(p0_Pa=P0), "pipe": Pipe("bellow", "tank")}
    lay = Circuit(comps).layout
    assert lay == StateLayout(2, 1, 1) and lay.size == 2 * 2 + 1 + 1 + 3


# =============================================================================
# Lag
# =============================================================================
def test_lag_follows_first_order_step_response():
    """du_f/dt = (u - u_f)/tau after a lever step A at t = 0: u_f = A (1 - exp(-t/tau)).
    Two cases in one batch: a step into the supply side and one into the exhaust side."""
    tau, A = 0.2, np.array([0.015, -0.020])
    circuit, x0 = valve_circuit(n_cases=2, lag_s=tau)
    assert circuit.layout.n_valve_states == 1
    t, x = run(circuit, x0, step_motion(A, n_cases=2), 1.0)
    u_f = np.array([circuit.valve_lever_m(x[:, i], A[None, :])[0] for i in range(t.size)])
    exact = A * (1.0 - np.exp(-t / tau))[:, None]
    # h / tau = 5e-3: RK4's global relative error ~ (h/tau)^4 / 120 ~ 5e-12
    np.testing.assert_allclose(u_f, exact, rtol=0, atol=1e-10 * np.abs(A).max())
    # A side opens when u_f leaves the dead band: at tau ln(A / (A - dead band)), then stays open
    t_open = tau * np.log(np.abs(A) / (np.abs(A) - DEAD_BAND))
    open_s = circuit.valve_open_time_s(x[:, -1])
    np.testing.assert_allclose([open_s.supply[0, 0], open_s.exhaust[0, 1]], t[-1] - t_open, atol=H)
    assert open_s.exhaust[0, 0] == 0.0 and open_s.supply[0, 1] == 0.0


# =============================================================================
# Dead time (Erlang chain)
# =============================================================================
def test_delay_chain_follows_erlang_response_and_quantifies_its_error():
    """The delayed lever after a step is A P(n, n (t - t0)/T) (Erlang). Against the pure dead
    time it stands for (0 before T, A after), the chain's error is its spread around T:
    the values asserted here are the docstring's accuracy table for n = 16. The step is at
    t0 = 0, so that the input is constant over every RK4 step (a step inside the run is seen
    by the last stage of the step before it, an O(h) time shift of h/6, see the next test)."""
    T, A, t0 = 0.5, 0.010, 0.0
    circuit, x0 = valve_circuit(delay_s=T)
    n = circuit.components["lv"].delay_stages
    assert n == 16 and circuit.layout.n_valve_states == n
    t, x = run(circuit, x0, step_motion(A, t0), t0 + 2.5 * T)
    u_d = np.array([circuit.valve_lever_m(x[:, i], np.array([A]))[0] for i in range(t.size)])
    exact = A * erlang_cdf((t - t0) / T, n)
    # stage rate n/T = 32 1/s, h lambda = 0.032: RK4 error ~1e-9 relative
    np.testing.assert_allclose(u_d, exact, rtol=0, atol=1e-8 * A)
    at = lambda s: u_d[np.argmin(np.abs(t - (t0 + s * T)))] / A
    assert at(0.5) < 0.01 and 0.36 < at(0.9) < 0.38 and at(1.5) > 0.96
    assert abs(erlang_quantile(0.5, n) - 0.979) < 1e-3              # half the step at 0.98 T
    np.testing.assert_allclose(erlang_step_response(t - t0, T, n), exact / A, rtol=1e-12, atol=1e-15)


def test_delayed_valve_opens_only_after_the_delay():
    """A lever step of twice the dead band at t0. "Opens" for the Erlang chain: the supply side's
    conductance becomes > 0 when the delayed lever A P(16, 16 (t - t0)/T) passes the dead band,
    i.e. at t0 + T Q(1/2) = t0 + 0.979 T (Q: the Erlang quantile). So: exactly no supply flow
    until t0 + 0.9 T (the lever has then reached 0.37 A = 3.7 mm, inside the dead band), flowing
    by t0 + 1.5 T at > 80 % of the undelayed valve's initial flow (lever at 0.966 A, so the
    conductance is 93 % of the undelayed one; the bellow's pressure rose by < 1 % in the 0.26 s
    the valve had been open). The undelayed valve flows from the first step."""
    T, A, t0 = 0.5, 2.0 * DEAD_BAND, 0.2
    flows = {}
    for delay in (T, 0.0):
        circuit, x0 = valve_circuit(delay_s=delay)
        t, x = run(circuit, x0, step_motion(A, t0), t0 + 2.0 * T)
        w = np.array([circuit.outputs(x[:, i], np.array([A if ti >= t0 else 0.0])).link_flow_kg_per_s
                      for i, ti in enumerate(t)])
        flows[delay] = (t, w[:, circuit.link_names.index("lv.supply")], circuit.valve_open_time_s(x[:, -1]))
    t, w_undelayed, open_undelayed = flows[0.0]
    first = np.argmax(t > t0)
    assert w_undelayed[first] > 0.0 and np.all(w_undelayed[t < t0] == 0.0)
    assert open_undelayed.supply[0] == pytest.approx(t[-1] - t0, abs=H)
    t, w, open_delayed = flows[T]
    assert np.all(w[t <= t0 + 0.9 * T] == 0.0)
    assert w[np.argmin(np.abs(t - (t0 + 1.5 * T)))] > 0.8 * w_undelayed[first]
    t_open = t0 + T * erlang_quantile(DEAD_BAND / A, 16)
    assert open_delayed.supply[0] == pytest.approx(t[-1] - t_open, abs=2 * H)
    assert open_delayed.exhaust[0] == 0.0


# =============================================================================
# Play (hysteresis)
# =============================================================================
def cosine_path(times, values):
    """Crushing through waypoints ``values`` (waypoints x cases) at ``times``, each leg a half-cosine
    (zero rate at the waypoints), with its exact rate: the play integrates the lever rate."""
    times, values = np.asarray(times, float), np.asarray(values, float)

    def motion(t):
        k = min(max(np.searchsorted(times, t, side="right") - 1, 0), times.size - 2)
        dt = times[k + 1] - times[k]
        s = min(max((t - times[k]) / dt, 0.0), 1.0)
        dz = values[k + 1] - values[k]
        z = values[k] + dz * 0.5 * (1.0 - math.cos(math.pi * s))
        zd = dz * 0.5 * math.pi / dt * math.sin(math.pi * s) if 0.0 < s < 1.0 else 0.0 * dz
        return z[None, :], np.asarray(zd)[None, :]
    return motion


def test_play_holds_output_until_the_input_crosses_the_play_width():
    """Play of width w = 4 mm (output moves only when the input is more than 2 mm from it).
    case 0: up 1.5 mm and back: the output never moves, nor does the valve (it stays shut).
    case 1: up to 12 mm (output dragged to 10 mm), down 3 mm (< w: output held at 10 mm), down
            3 mm more (6 mm in all > w: output dragged down to 6 + 2 = 8 mm).
    case 2: up to 6 mm, beyond the 5 mm dead band: the output reaches only 4 mm, the valve stays
            shut (without the play it would open).
    case 3: up to 8 mm (output 6 mm, valve open), back to 4.5 mm (inside the dead band, where
            an instantaneous valve shuts): the output holds 6 mm, the valve stays open."""
    w, r = 0.004, 0.002
    times = [0.0, 0.5, 1.0, 1.5, 2.0]
    path = np.array([[0, 0.0015, 0.0, 0.0, 0.0],
                     [0, 0.012, 0.009, 0.006, 0.006],
                     [0, 0.006, 0.006, 0.006, 0.006],
                     [0, 0.008, 0.0045, 0.0045, 0.0045]]).T
    motion = cosine_path(times, path)
    circuit, x0 = valve_circuit(n_cases=4, hysteresis_m=w)
    t, x = run(circuit, x0, motion, times[-1])
    out = np.array([circuit.valve_lever_m(x[:, i], motion(ti)[0]) [0] for i, ti in enumerate(t)])
    at = lambda ti: out[np.argmin(np.abs(t - ti))]
    # The play's state may be left behind its side by up to h |du/dt| at the instant the input
    # engages it (see valves.play_rate); the fastest engagement here is case 1's at 2 mm on a
    # 12 mm half-cosine of 0.5 s: |du/dt| <= 12 mm pi / (2 0.5 s) = 0.038 m/s -> 4e-5 m.
    tol = H * 0.012 * math.pi / (2 * 0.5)
    assert np.all(out[:, 0] == 0.0)                                    # never moved, exactly
    assert at(0.5)[1] == pytest.approx(0.012 - r, abs=1e-12)           # while dragged: exact
    held = (t > 0.5) & (t <= 1.0)
    assert np.ptp(out[held, 1]) <= tol                                 # held during the 3 mm fall
    assert abs(out[held, 1][-1] - (0.012 - r)) <= tol
    assert at(1.5)[1] == pytest.approx(0.006 + r, abs=1e-12)           # dragged down again
    assert np.all(out[:, 2] <= 0.006 - r + 1e-12)
    assert at(2.0)[3] == pytest.approx(0.008 - r, abs=tol)
    open_s = circuit.valve_open_time_s(x[:, -1])
    assert open_s.supply[0, 0] == 0.0 and open_s.supply[0, 2] == 0.0
    # case 3 opens when its output passes 5 mm (input 7 mm on the way up) and stays open
    s_open = math.acos(1.0 - 2.0 * 0.007 / 0.008) / math.pi * 0.5
    assert open_s.supply[0, 3] == pytest.approx(times[-1] - s_open, abs=2 * H)
    assert np.all(open_s.exhaust == 0.0)


# =============================================================================
# Per-valve outputs
# =============================================================================
def test_open_time_and_air_per_side_under_constant_crushing():
    """Crushing held at +10 mm, -10 mm and 2 mm (dead band) for T = 0.7 s, one case each: the
    open side's open time is T (the rate is exactly 1 at every RK4 stage), the other side's 0.
    The air through each side accounts for the bellow's change of mass to round-off (the link
    accumulators are a linear invariant, integrated exactly by RK4)."""
    T = 0.7
    z = np.array([[0.010, -0.010, 0.002]])
    circuit, x0 = valve_circuit(n_cases=3)
    x = rk4(lambda t, xx: circuit.derivatives(xx, z, 0.0 * z), x0, 0.0, T, 700)
    open_s, air = circuit.valve_open_time_s(x), circuit.valve_air_kg(x)
    np.testing.assert_allclose(open_s.supply[0], [T, 0.0, 0.0], rtol=1e-12, atol=0)
    np.testing.assert_allclose(open_s.exhaust[0], [0.0, T, 0.0], rtol=1e-12, atol=0)
    assert air.supply[0, 0] > 0 and air.exhaust[0, 1] > 0
    assert air.supply[0, 1] == 0.0 and air.exhaust[0, 0] == 0.0 and np.all(air.supply[0, 2] == air.exhaust[0, 2] == 0.0)
    dm = x[circuit.layout.m][0] - x0[circuit.layout.m][0]
    np.testing.assert_allclose(air.supply[0] - air.exhaust[0], dm, rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(air.supply[0], circuit.mass_from(x, "supply"), rtol=1e-15)
    np.testing.assert_allclose(air.exhaust[0], -circuit.mass_from(x, "atmosphere"), rtol=1e-15)


@pytest.mark.slow
def test_recommended_dynamics_keep_the_valve_shut_in_a_1hz_sway():
    """+-10 mm, 1 Hz sway of the crushing for 4 s. Instantaneous valve: each side is open while
    |z| > 5 mm on its side, i.e. while |sin| > 1/2: a third of each period. With the
    docstring's recommended dynamics (lag 1 s, 16-stage delay 1 s, play 2 mm), the sway reaches
    the tables attenuated 20-fold (plus a start-up transient below 2 mm): the valve never opens."""
    a, f, t_end = 0.010, 1.0, 4.0
    w = 2 * math.pi * f
    motion = lambda t: (np.array([a * math.sin(w * t)]), np.array([a * w * math.cos(w * t)]))
    circuit, x0 = valve_circuit()
    _, x = run(circuit, x0, motion, t_end)
    open_s = circuit.valve_open_time_s(x[:, -1])
    # 8 switching instants per side, each located to within a step
    assert open_s.supply[0] == pytest.approx(t_end / 3, abs=8 * H)
    assert open_s.exhaust[0] == pytest.approx(t_end / 3, abs=8 * H)
    circuit, x0 = valve_circuit(lag_s=1.0, delay_s=1.0, hysteresis_m=0.002)
    t, x = run(circuit, x0, motion, t_end)
    u_f = np.array([circuit.valve_lever_m(x[:, i], motion(ti)[0])[0] for i, ti in enumerate(t)])
    assert np.max(np.abs(u_f)) < 0.4 * DEAD_BAND
    assert circuit.valve_open_time_s(x[:, -1]) == (0.0, 0.0)
    assert np.all(circuit.valve_air_kg(x[:, -1]) == np.zeros((2, 1)))


# =============================================================================
# Vectorisation, rest state, validation
# =============================================================================
def car_with_dynamic_valves(points):
    valve = LevellingValve("", lag_s=0.3, delay_s=0.4, delay_stages=5, hysteresis_m=0.003)
    kw = {"cross_pipe": Pipe("", "")} if points == 2 else {}
    comps = car_circuit(Bellow(p0_Pa=P0), Tank(p0_Pa=P0), Pipe("", ""), levelling=valve, supply=Supply(),
                        points=points, **kw)
    # vary the dynamics from valve to valve, and leave one valve without them
    names = [n for n in comps if n.startswith("lv_")]
    comps[names[0]] = dataclasses.replace(comps[names[0]], delay_stages=3, hysteresis_m=0.0)
    comps[names[-1]] = dataclasses.replace(comps[names[-1]], lag_s=0.0, delay_s=0.0, hysteresis_m=0.0)
    return comps


@pytest.mark.parametrize("points", [4, 2])
def test_batched_cases_equal_single_cases_with_valve_dynamics(points):
    comps = car_with_dynamic_valves(points)
    ks = np.array([0.0, 10.0, math.inf])
    batch = Circuit(comps, k_W_per_K=ks)
    nv = len(batch.valve_names)
    expected_states = sum((v.hysteresis_m > 0) + (v.delay_s > 0) * v.delay_stages + (v.lag_s > 0)
                          for v in (comps[n] for n in batch.valve_names))
    assert batch.layout.n_valve_states == expected_states
    assert batch.layout.open_time.stop - batch.layout.open_time.start == 2 * nv
    rng = np.random.default_rng(7)
    xb = batch.initial_state()
    xb[batch.layout.valve_signal] = rng.uniform(-0.02, 0.02, xb[batch.layout.valve_signal].shape)
    z0, zd = rng.uniform(-0.02, 0.02, (4, 3)), rng.uniform(-0.1, 0.1, (4, 3))
    motion = lambda t: (z0 + zd * t, zd)
    xa = rk4(lambda t, x: batch.derivatives(x, *motion(t)), xb, 0.0, 0.2, 200)
    for i, k in enumerate(ks):
        single = Circuit(comps, k_W_per_K=k)
        xs = rk4(lambda t, x: single.derivatives(x, *(v[:, i] for v in motion(t))), xb[:, i].copy(), 0.0, 0.2, 200)
        np.testing.assert_allclose(xa[:, i], xs, rtol=1e-12, atol=1e-15)


def test_valves_at_rest_are_stationary():
    """Held at a constant crushing, the rest state of every valve element does not move."""
    comps = car_with_dynamic_valves(4)
    circuit = Circuit(comps)
    z = np.array([0.004, -0.006, 0.012, 0.0])
    x = circuit.valves_at_rest(circuit.initial_state(), z)
    dx = circuit.derivatives(x, z, np.zeros(4))
    assert np.all(dx[circuit.layout.valve_signal] == 0.0)
    np.testing.assert_array_equal(circuit.valve_lever_m(x, z), z)          # four-point: u = z


@pytest.mark.parametrize("field, value", [("lag_s", -0.1), ("delay_s", float("nan")), ("hysteresis_m", -1e-3),
                                          ("delay_stages", 0), ("delay_stages", 2.5)])
def test_invalid_dynamics_rejected(field, value):
    with pytest.raises(CircuitError) as err:
        Circuit({"bellow": Bellow(p0_Pa=P0), "supply": Supply(), "lv": LevellingValve("bellow", **{field: value})})
    assert err.value.path == ("lv", field)
