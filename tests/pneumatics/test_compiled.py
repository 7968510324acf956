"""The circuit's compiled laws (:mod:`pneumatics.compiled`) against the numpy expressions of the
same equations, written out here: equal bit for bit, over random states that cover every branch
(choked, subsonic, the laminar band, either flow direction, table ends, dead bands), NaN included.

Bit for bit, not to a tolerance: the compiled law is the same sequence of correctly rounded IEEE
operations, so any difference would be a different formula (and a co-simulation that should be
unchanged by compilation would then drift from its published results)."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from pneumatics.chamber import (
    isothermal_heat_flow_W,
    temperature_rate_K_per_s,
    upstream_enthalpy_flow_W,
)
from pneumatics.gas import AIR, T_REF_K
from pneumatics.integrate import hermite_motion
from pneumatics.orifice import LAMINAR_RATIO, iso6358_mass_flow_kg_per_s, orifice_flow_kg_per_s
from pneumatics.pipe import pipe_flow_rate_kg_per_s2
from pneumatics.valves import differential_valve_flow_kg_per_s, lever_conductance

RNG = np.random.default_rng(20)
N = 20000


def iso6358_numpy(C, b, p_up, T_up, p_down):
    """Eqs (6)-(7) as numpy operations (the law before it was compiled)."""
    ratio = np.minimum(p_down / p_up, 1.0)
    choked = C * p_up * AIR.rho_ref_kg_per_m3 * np.sqrt(T_REF_K / T_up)
    r_lam = 1.0 - LAMINAR_RATIO
    factor = np.sqrt(np.maximum(1.0 - ((np.maximum(np.minimum(ratio, r_lam), b) - b) / (1.0 - b)) ** 2, 0.0))
    factor = np.where(ratio > r_lam, factor * (1.0 - ratio) / LAMINAR_RATIO, factor)
    return choked * factor


def pressures():
    """(p_a, p_b): far apart, close (the laminar band, 1e-3 relative), equal, and NaN."""
    p_a = RNG.uniform(1e5, 1e6, N)
    close = p_a * (1.0 + RNG.uniform(-2e-3, 2e-3, N))
    far = RNG.uniform(1e5, 1e6, N)
    p_b = np.where(np.arange(N) % 3 == 0, close, far)
    p_b[::97] = p_a[::97]
    p_a[5], p_b[7] = np.nan, np.nan
    return p_a, p_b


def test_orifice_flow_is_the_numpy_law_bit_for_bit():
    p_a, p_b = pressures()
    T_a, T_b = RNG.uniform(250.0, 350.0, N), RNG.uniform(250.0, 350.0, N)
    C, b = RNG.uniform(0.0, 2e-8, N), RNG.uniform(0.1, 0.6, N)
    forward = p_a >= p_b
    with warnings.catch_warnings(), np.errstate(invalid="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)   # the NaN entries
        q = iso6358_numpy(C, b, np.where(forward, p_a, p_b), np.where(forward, T_a, T_b), np.where(forward, p_b, p_a))
        expected = np.where(forward, q, -q)
        got = orifice_flow_kg_per_s(C, b, p_a, T_a, p_b, T_b)
        up, down = np.maximum(p_a, p_b), np.minimum(p_a, p_b)
        got_iso = iso6358_mass_flow_kg_per_s(C, b, up, T_a, down)
        expected_iso = iso6358_numpy(C, b, up, T_a, down)
    np.testing.assert_array_equal(got, expected)
    np.testing.assert_array_equal(got_iso, expected_iso)
    assert np.isnan(got[5]) and np.isnan(got[7])
    # broadcasting as the circuit calls it: (orifices, cases) against (orifices, 1)
    rows = slice(20, 32)                                  # finite entries
    shaped = orifice_flow_kg_per_s(C[rows].reshape(6, 2), b[rows][:6].reshape(6, 1), p_a[rows].reshape(6, 2),
                                   T_a[rows].reshape(6, 2), p_b[rows].reshape(6, 2), T_b[rows].reshape(6, 2))
    np.testing.assert_array_equal(shaped, orifice_flow_kg_per_s(
        C[rows], np.repeat(b[rows][:6], 2), p_a[rows], T_a[rows], p_b[rows], T_b[rows]).reshape(6, 2))


def test_lever_conductance_and_differential_valve_are_the_numpy_laws_bit_for_bit():
    table_lever = np.array([0.0, 0.005, 0.0051, 0.02, 0.05])        # dead band, then rising, then held
    table_C = np.array([0.0, 0.0, 1e-9, 2.3e-8, 2.3e-8])
    lever = np.concatenate([RNG.normal(0.0, 0.03, N), table_lever, -table_lever, [np.nan]]).reshape(-1, 1)
    expected = np.interp(np.maximum(lever, 0.0), table_lever, table_C) * (lever > 0.0)
    np.testing.assert_array_equal(lever_conductance(lever, table_lever, table_C), expected)
    p_a, p_b = RNG.uniform(1e5, 9e5, (N, 2)), RNG.uniform(1e5, 9e5, (N, 2))
    table_dp, table_q = np.array([0.0, 1.5e5, 2.5e5]), np.array([0.0, 0.0, 0.02])
    dp = p_a - p_b
    np.testing.assert_array_equal(differential_valve_flow_kg_per_s(p_a, p_b, table_dp, table_q),
                                  np.sign(dp) * np.interp(np.abs(dp), table_dp, table_q))


def test_pipe_flow_rate_is_the_numpy_law_bit_for_bit():
    q = RNG.normal(0.0, 0.05, (N, 2))
    p_a, p_b = RNG.uniform(1e5, 9e5, (N, 2)), RNG.uniform(1e5, 9e5, (N, 2))
    rho = RNG.uniform(1.0, 10.0, (N, 2))
    L, A, K = np.full((N, 1), 1.3), np.full((N, 1), 2.5e-4), np.full((N, 1), 1.11)
    expected = A / L * ((p_a - p_b) - K * q * np.abs(q) / (2.0 * rho * A ** 2))
    np.testing.assert_array_equal(pipe_flow_rate_kg_per_s2(q, p_a, p_b, rho, L, A, K), expected)


def test_the_chambers_thermal_laws_are_the_numpy_laws_bit_for_bit():
    """Eq. (2), its isothermal heat flow and the upstream enthalpy flow, as the circuit calls them
    (chambers x cases and scalars), either flow direction, zero and NaN."""
    m, T, p = RNG.uniform(0.01, 1.0, (N, 3)), RNG.uniform(250.0, 350.0, (N, 3)), RNG.uniform(1e5, 9e5, (N, 3))
    mdot, Hdot, Vdot = RNG.normal(0.0, 0.05, (N, 3)), RNG.normal(0.0, 1e4, (N, 3)), RNG.normal(0.0, 1e-3, (N, 3))
    k = RNG.uniform(0.0, 1e4, (N, 1))
    T[3], mdot[5], m[7] = np.nan, np.nan, 0.0
    cv, cp = AIR.cv_J_per_kgK, AIR.cp_J_per_kgK
    with np.errstate(all="ignore"):
        Q = k * (293.15 - T)
        np.testing.assert_array_equal(temperature_rate_K_per_s(m, T, p, mdot, Hdot, Q, Vdot, cv),
                                      (Hdot - cv * T * mdot + Q - p * Vdot) / (m * cv))
        np.testing.assert_array_equal(isothermal_heat_flow_W(T, p, mdot, Hdot, Vdot, cv),
                                      cv * T * mdot - Hdot + p * Vdot)
        w = mdot.copy()
        w[9], w[11] = 0.0, -0.0
        T_b = RNG.uniform(250.0, 350.0, (N, 3))
        np.testing.assert_array_equal(upstream_enthalpy_flow_W(w, T, T_b, cp), w * (cp * np.where(w >= 0.0, T, T_b)))


def test_the_hermite_motion_is_the_numpy_expression_bit_for_bit():
    """The master's motion over a macro-step (bellows x cases) and the FMU's (bellows), at its
    ends and inside it."""
    for shape in ((4, 7), (4,)):
        _check_hermite(*(RNG.normal(0.0, 0.02, shape) for _ in range(4)))


def _check_hermite(z0, zd0, z1, zd1):
    t0, t1 = 0.37, 0.38
    motion, H, dz = hermite_motion(t0, t1, z0, zd0, z1, zd1), t1 - t0, z1 - z0
    for t in [t0, t1, t0 + 0.5 * H, *RNG.uniform(t0, t1, 50)]:
        s = (t - t0) / H
        s2, s3 = s * s, s * s * s
        z, zd = motion(t)
        np.testing.assert_array_equal(z, z0 + (3 * s2 - 2 * s3) * dz + (s - 2 * s2 + s3) * H * zd0 + (s3 - s2) * H * zd1)
        np.testing.assert_array_equal(zd, (6 * s - 6 * s2) * dz / H + (1 - 4 * s + 3 * s2) * zd0 + (3 * s2 - 2 * s) * zd1)


@pytest.mark.parametrize("law, args", [
    (orifice_flow_kg_per_s, (1e-8, 0.3, 3e5, 300.0, 2e5, 290.0)),
    (pipe_flow_rate_kg_per_s2, (0.01, 3e5, 2e5, 3.0, 1.0, 2.5e-4, 1.11)),
    (temperature_rate_K_per_s, (0.1, 300.0, 3e5, 0.01, 3e3, 10.0, 1e-4, 717.5)),
    (upstream_enthalpy_flow_W, (-0.01, 300.0, 290.0, 1004.5)),
])
def test_the_compiled_laws_take_floats(law, args):
    """Scalars in, a float out, as the numpy expressions did."""
    assert np.ndim(law(*args)) == 0 and np.isfinite(law(*args))


def test_a_law_compiles_without_the_cache_when_a_source_changed_or_the_cache_is_unwritable(monkeypatch):
    """numba checks a cached law against its own file only; the laws' cache names carry a digest of
    every source they use (pneumatics.compiled.SOURCES), and a source changed since import (here:
    the digest taken at import pretended different) compiles without the cache. A cache that cannot
    be written (numba's RuntimeError) gives a warning and an uncached law, not a failure."""
    from pneumatics import compiled

    def law(a, b):
        return a * b + 1.0

    made = []

    def make(numba, cache):
        made.append(cache)
        if cache:
            raise RuntimeError("cannot cache function 'law': no locator available")
        return numba.vectorize(["float64(float64, float64)"], cache=False)
    monkeypatch.setattr(compiled, "_DIGEST", "0" * 16)
    assert compiled._compiled(law, make)(2.0, 3.0) == 7.0 and made == [False]
    monkeypatch.undo()
    with pytest.warns(RuntimeWarning, match="cannot be cached"):
        assert compiled._compiled(law, make)(2.0, 3.0) == 7.0
    assert made == [False, True, False]
    assert law.__qualname__.endswith(compiled._DIGEST)


def _same(a, b) -> bool:
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("valves", [
    [dict(hysteresis_m=0.002, delay_s=1.0, lag_s=1.0)] * 4,                        # the service's valves
    [dict(hysteresis_m=0.002), dict(delay_s=0.5), dict(lag_s=0.3), {}, dict(hysteresis_m=0.004, delay_s=0.2, lag_s=2.0)],
    [dict(delay_s=1.0)] * 2,
])
def test_the_valve_signal_laws_are_the_numpy_laws_bit_for_bit(valves):
    """The levelling valves' lever chain (play, delay, lag) and its states' rates, compiled
    (pneumatics.valve_signals.CompiledSignals) against lever_chain and signal_rates: random
    signals, states on the play's edges, NaN states, zero crushing rates, 1 to 5 cases."""
    from pneumatics.assembly.valve_dynamics import compile_valve_dynamics
    from pneumatics.valve_signals import CompiledSignals, lever_chain, signal_rates
    from pneumatics.valves import LevellingValve

    dyn = compile_valve_dynamics([LevellingValve("FL", **v) for v in valves])
    compiled = CompiledSignals(dyn)
    lever_play = RNG.normal(size=(dyn.n_play, 4))
    for cases in (1, 2, 5):
        for trial in range(60):
            u = RNG.normal(scale=3e-3, size=(len(valves), cases))
            s = RNG.normal(scale=3e-3, size=(dyn.n_states, cases))
            zdot = RNG.normal(scale=1e-2, size=(4, cases))
            if trial % 5 == 0:
                s[dyn.play] = u[dyn.play_rows] - dyn.play_half_m     # pressing on the play's edge
            if trial % 7 == 0:
                s[RNG.integers(dyn.n_states)] = np.nan
                zdot[RNG.integers(4)] = 0.0
            expected, got = lever_chain(dyn, u, s), compiled.lever_chain(u, s)
            assert all(_same(a, b) for a, b in zip(expected, got))
            assert _same(signal_rates(dyn, s, expected, lever_play, zdot), compiled.signal_rates(s, got, lever_play @ zdot))


def test_the_node_states_and_the_physical_check_are_the_numpy_expressions():
    """Eq. (3) over the chambers with the boundary nodes after them, and the densities (compiled
    node_states), bit for bit; physical_columns as the numpy test (NaN, inf, zero, negative)."""
    from pneumatics.runtime import node_states, physical_columns

    for cases in (1, 2, 7):
        m, T = RNG.uniform(1e-3, 1.0, (9, cases)), RNG.uniform(250.0, 350.0, (9, cases))
        V, p_bnd, T_bnd = RNG.uniform(1e-3, 0.1, (9, cases)), RNG.uniform(1e5, 1e6, (3, cases)), RNG.uniform(250, 350, (3, cases))
        m[0, 0] = np.nan
        p = m * AIR.R_J_per_kgK * T / V
        p_n, T_n = np.concatenate([p, p_bnd]), np.concatenate([T, T_bnd])
        got = node_states(m, T, V, p_bnd, T_bnd, AIR.R_J_per_kgK)
        assert all(_same(a, b) for a, b in zip((p_n, T_n, p_n / (AIR.R_J_per_kgK * T_n)), got))
        x2 = RNG.uniform(0.1, 1.0, (30, cases))
        for j, bad in zip(range(cases), (np.nan, 0.0, -1.0, np.inf, np.nan, 1.0, np.nan)):
            x2[(3 * j) % 30, j] = bad
        chambers = x2[:10]
        expected = (np.all(chambers > 0.0, axis=0) & np.all(np.isfinite(chambers), axis=0)
                    & np.all(np.isfinite(x2[12:20]), axis=0) & np.all(np.isfinite(x2[22:30]), axis=0))
        assert np.array_equal(physical_columns(x2, 10, 12, 20, 22, 30), expected)


def test_the_rk4_combinations_and_the_demand_flow_are_the_numpy_expressions():
    """RK4's stage states and step (pneumatics.integrate, compiled) and the air demand's fade-out
    (the clip ufunc called directly) against the numpy expressions, bit for bit."""
    from pneumatics.air_supply import demand_flow_kg_per_s
    from pneumatics.integrate import _rk4_stage, _rk4_step

    x, k1, k2, k3, k4 = (RNG.normal(size=(125, 3)) * 10.0 ** RNG.integers(-8, 8, (125, 3)) for _ in range(5))
    h = 0.005
    assert _same(_rk4_stage(x, 0.5 * h, k1), x + 0.5 * h * k1)
    assert _same(_rk4_step(x, k1, k2, k3, k4, h / 6.0), x + (h / 6.0) * (k1 + 2.0 * (k2 + k3) + k4))
    p = np.r_[RNG.uniform(0.5e5, 3e5, 200), np.nan, -0.0, 101325.0]
    assert _same(demand_flow_kg_per_s(0.002, p, 101325.0, 2e4), 0.002 * np.clip((p - 101325.0) / 2e4, 0.0, 1.0))
