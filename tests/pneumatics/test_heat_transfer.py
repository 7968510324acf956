"""A chamber's own heat exchange (:mod:`pneumatics.heat_transfer`, docs/models.md "Heat transfer per
chamber"): a constant k per chamber and k from the convection correlations.

* a closed bellow cooling after a step compression, against the analytic exponential with the
  correlation's k (and the exact solution of M c_v dT/dt = -k(T) (T - T_atm));
* a chamber's own k equal to its case's reproduces the single-k model bit for bit;
* an adiabatic bellow (own k = 0) and an isothermal tank (own k = inf) in a case of k = 10 W/K,
  against the closed forms of a slow compression;
* the correlation's k against a hand computation written here from the textbook's equations
  (Incropera 6th ed. eqs 7.30, 7.38, 7.54, 9.26, 9.34, 9.64; White's Sutherland constants), the
  wall temperatures found by a root solve, not by the module's substitutions;
* the air's properties against Incropera Table A.4; the compiled law against its Python source;
* what the circuit refuses.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from pneumatics.chamber import Bellow, Tank
from pneumatics.circuit import Circuit, CircuitError
from pneumatics.gas import AIR
from pneumatics.heat_transfer import ChamberHeat, sutherland, wall_conductance_W_per_K
from pneumatics.integrate import advance, simulate
from pneumatics.pipe import Pipe
from pneumatics.rig import bellow_tank_components, dynamic_stiffness_sweep, ramp_motion, sine_motion

P0_PA = 4.0e5
T_ATM_K = 293.15
P_ATM_PA = 101_325.0
CORRELATION = ChamberHeat("correlation")
RTOL = 1e-10


def held(z_m: float):
    return lambda t: (np.array([z_m]), np.zeros(1))


# ------------------------------------------------------------------------- cooling after a step
def test_a_closed_bellow_cools_after_a_step_compression_as_the_correlations_k_says():
    """The paper's bellow, closed, crushed by 20 mm in 50 ms (the air heats by ~30 K, adiabatic:
    its time constant M c_v / k is ~25 s), then held: at constant volume and mass the first law
    is M c_v dT/dt = k (T_atm - T) (docs/models.md), k the correlation's at the state."""
    circuit = Circuit({"b": Bellow(p0_Pa=P0_PA, heat=CORRELATION)}, k_W_per_K=123.0)   # the case's k: unused
    step = simulate(circuit, circuit.initial_state(), 0.05, ramp_motion(0.02, 0.05), rtol=RTOL)
    t = np.linspace(0.0, 180.0, 901)
    sol = simulate(circuit, step.y[:, -1], t[-1], held(0.02), t_eval=t, rtol=RTOL)
    assert step.success and sol.success
    lay = circuit.layout
    m, T = sol.y[lay.m][0], sol.y[lay.T][0]
    dT = T - T_ATM_K
    k = circuit.heat_conductances_W_per_K(sol.y, np.full((1, t.size), 0.02))[0]
    C = m[0] * AIR.cv_J_per_kgK
    assert np.ptp(m) == 0.0 and 25.0 < dT[0] < 35.0 and 0.3 < k[0] < 3.0
    # natural convection: k falls as the air cools (Nu ~ Ra^(1/4..1/3), Ra ~ |T - T_atm|)
    assert np.all(np.diff(k) < 0.0)
    # so the decay lies between the exponentials of the largest k (at the step) and of the k at t
    # (the smallest so far): exp(-int_0^t k/C) is squeezed by k(t) t <= int_0^t k <= k(0) t
    slack = 1e-7 * dT[0]                                    # the integration's error, rtol 1e-10
    assert np.all(dT >= dT[0] * np.exp(-k[0] * t / C) - slack)
    assert np.all(dT <= dT[0] * np.exp(-k * t / C) + slack)
    # the analytic exponential with the correlation's k at the step, while the air cools by the
    # first 10 %: k changes there by (1 - k_end/k_0) (1.9 % measured), so the exponent by at most
    # that fraction of k_0 t / C <= ln(1/0.9): a bound of 0.2 % on dT (0.1 % measured), computed
    # from the run's own k, not assumed. Beyond it the exponential drifts: +9 % at t = M c_v / k_0
    window = dT >= 0.9 * dT[0]
    exponential = dT[0] * np.exp(-k[0] * t / C)
    bound = (1.0 - k[window][-1] / k[0]) * k[0] * t[window][-1] / C
    assert bound < 0.003
    assert np.max(np.abs(dT[window] / exponential[window] - 1.0)) <= bound
    # and the exact solution over the whole cooling (30 K to 0.2 K in 180 s): t(dT) = C int_dT^dT0
    # ds / (s k(s)), k(s) the correlation at T_atm + s and the bellow's constant density
    x = np.repeat(sol.y[:, :1], 2, axis=1)

    def k_at(s):
        x[lay.T][0] = T_ATM_K + s
        return circuit.heat_conductances_W_per_K(x, np.full((1, 2), 0.02))[0, 0]
    for i in (100, 300, 600, 900):
        t_exact = C * quad(lambda s: 1.0 / (s * k_at(s)), dT[i], dT[0], epsabs=0.0, epsrel=1e-10)[0]
        assert t_exact == pytest.approx(t[i], rel=1e-6, abs=1e-6)
    assert dT[-1] < 0.01 * dT[0]                            # cooled


# ------------------------------------------------------------------------- the single-k model kept
def _rig(bellow_heat=None, tank_heat=None):
    """The paper's bellow, pipe and tank (the rig's names), at 4 bar."""
    return bellow_tank_components(Bellow(p0_Pa=P0_PA, heat=bellow_heat), Tank(p0_Pa=P0_PA, heat=tank_heat), Pipe("", ""))


@pytest.mark.parametrize("k", [0.0, 3.7, 10.0, math.inf])
def test_a_chambers_own_k_equal_to_its_cases_is_the_single_k_model_bit_for_bit(k):
    own = ChamberHeat(k_W_per_K=k)
    single = Circuit(_rig(), k_W_per_K=k)
    per_chamber = Circuit(_rig(own, own), k_W_per_K=55.0)      # the case's k: unused by either chamber
    x = single.initial_state()
    assert np.array_equal(x, per_chamber.initial_state())
    rng = np.random.default_rng(3)
    for _ in range(5):                                          # hot, cold, flowing, crushed
        y = x.copy()
        y[single.layout.T] += rng.normal(0.0, 10.0, 2) * (not math.isinf(k))
        y[single.layout.q] = rng.normal(0.0, 0.05)
        z, zd = rng.normal(0.0, 0.01, 1), rng.normal(0.0, 0.1, 1)
        assert np.array_equal(single.derivatives(y, z, zd), per_chamber.derivatives(y, z, zd))
        assert np.array_equal(single.bellow_stiffness_N_per_m(y, z), per_chamber.bellow_stiffness_N_per_m(y, z))
    motion = sine_motion(0.02, 2.0)
    ends = [advance(c, c.initial_state(), 0.0, 1.0, motion, h_max_s=2e-3) for c in (single, per_chamber)]
    assert np.array_equal(*ends)


def test_the_periodic_state_of_chambers_isothermal_by_their_own_k_is_the_isothermal_cases():
    """The rig's dynamic stiffness (periodic shooting, its Floquet map without the held
    temperatures): both chambers isothermal by their own k, in a case of k = 10, are the case k =
    inf to the bit; an isothermal bellow on an adiabatic tank lies between the two limits."""
    inf, zero = ChamberHeat(k_W_per_K=math.inf), ChamberHeat(k_W_per_K=0.0)
    sweep = lambda comps, k: dynamic_stiffness_sweep(comps, [k], [0.5, 2.0], 0.01, n_min=200)
    uniform, own = sweep(_rig(), math.inf), sweep(_rig(inf, inf), 10.0)
    for a, b in zip(uniform, own):
        assert a.stabilised and b.stabilised
        assert (a.K_dyn_N_per_m, a.floquet_max, a.residual) == (b.K_dyn_N_per_m, b.floquet_max, b.residual)
    mixed = sweep(_rig(inf, zero), 10.0)
    adiabatic = sweep(_rig(), 0.0)
    for lo, mid, hi in zip(uniform, mixed, adiabatic):
        assert mid.stabilised and lo.K_dyn_N_per_m < mid.K_dyn_N_per_m < hi.K_dyn_N_per_m


# ------------------------------------------------------------------------- an adiabatic bellow, an isothermal tank
def test_an_adiabatic_bellow_on_an_isothermal_tank_in_a_case_of_k_10():
    """A slow 20 mm compression (20 s) of the paper's bellow (own k = 0) and tank (own k = inf), in
    a case whose k (10 W/K) neither takes. The bellow's air only leaves it, without heat: what
    stays is compressed isentropically, T_b = T0 (p/p0)^((g-1)/g). The tank is held at T_atm, so
    its mass is p V_t / (R T_atm), and the air's total mass M0 gives p at the end:
        p V_b / (R T_b(p)) + p V_t / (R T_atm) = M0.
    The tank gives off what its isothermal filling with air at T_b takes, per kg c_p T_b - c_v
    T_atm, dm = V_t dp / (R T_atm):
        Q_in = V_t / (R T_atm) [c_v T_atm (p - p0) - c_p T0 p0 / (1 + a) ((p/p0)^(1 + a) - 1)],
    a = (g - 1)/g. The pipe's pressure drop at this flow is ~1 Pa (2e-6 of p)."""
    gas, bellow, tank = AIR, Bellow(p0_Pa=P0_PA, heat=ChamberHeat(k_W_per_K=0.0)), Tank(p0_Pa=P0_PA,
                                                                                       heat=ChamberHeat(k_W_per_K=math.inf))
    circuit = Circuit(bellow_tank_components(bellow, tank, Pipe("", "")), k_W_per_K=10.0)
    x0 = circuit.initial_state()
    sol = simulate(circuit, x0, 20.0, ramp_motion(0.02, 20.0), rtol=RTOL)
    assert sol.success
    x, lay = sol.y[:, -1], circuit.layout
    R, a = gas.R_J_per_kgK, (gas.gamma - 1.0) / gas.gamma
    M0 = circuit.total_mass_kg(x0)
    Vb, Vt = bellow.volume_m3(0.02), tank.V_m3
    T_b = lambda p: T_ATM_K * (p / P0_PA) ** a
    p = brentq(lambda p: p * Vb / (R * T_b(p)) + p * Vt / (R * T_ATM_K) - M0, P0_PA, 2 * P0_PA, xtol=1e-9, rtol=1e-15)
    p_sim, T_sim = circuit.chamber_states(x, np.array([0.02]))
    assert p_sim[:, 0] == pytest.approx([p, p], rel=1e-5)
    assert T_sim[0, 0] == pytest.approx(T_b(p), rel=1e-6)
    assert T_sim[1, 0] == T_ATM_K                                  # held exactly
    Q = Vt / (R * T_ATM_K) * (gas.cv_J_per_kgK * T_ATM_K * (p - P0_PA)
                              - gas.cp_J_per_kgK * T_ATM_K * P0_PA / (1 + a) * ((p / P0_PA) ** (1 + a) - 1))
    assert x[lay.heat_in] == pytest.approx(Q, rel=1e-4)
    assert Q < -50.0                                               # it is the tank's, and not small
    # the case's k, had the chambers taken it, would have given another pressure
    single = Circuit(_rig(), k_W_per_K=10.0)
    other = simulate(single, single.initial_state(), 20.0, ramp_motion(0.02, 20.0), rtol=RTOL).y[:, -1]
    assert abs(single.chamber_states(other, np.array([0.02]))[0][0, 0] / p - 1.0) > 1e-3


# ------------------------------------------------------------------------- the correlation by hand
G = 9.80665


def mu_air(T):                      # White, Viscous Fluid Flow, eq. 1-36, Table 1-2
    return 1.716e-5 * (T / 273.0) ** 1.5 * (273.0 + 111.0) / (T + 111.0)


def k_air(T):                       # White, eq. 1-44, Table 1-3
    return 0.0241 * (T / 273.0) ** 1.5 * (273.0 + 194.0) / (T + 194.0)


def air(T_film, p):
    """nu, alpha, Pr, k, rho at the film temperature and pressure p."""
    rho = p / (AIR.R_J_per_kgK * T_film)
    nu, alpha = mu_air(T_film) / rho, k_air(T_film) / (rho * AIR.cp_J_per_kgK)
    return nu, alpha, nu / alpha, k_air(T_film), rho


def ra(dT, L, T_film, p):
    nu, alpha, *_ = air(T_film, p)
    return G * abs(dT) * L ** 3 / (T_film * nu * alpha)


def nu_vertical_plate(Ra, Pr):          # Incropera eq. 9.26
    return (0.825 + 0.387 * Ra ** (1 / 6) / (1 + (0.492 / Pr) ** (9 / 16)) ** (8 / 27)) ** 2


def nu_horizontal_cylinder(Ra, Pr):     # eq. 9.34
    return (0.60 + 0.387 * Ra ** (1 / 6) / (1 + (0.559 / Pr) ** (9 / 16)) ** (8 / 27)) ** 2


def nu_flat_plate(Re, Pr):              # eq. 7.30 to Re_x,c = 5e5, eq. 7.38 beyond
    return 0.664 * Re ** 0.5 * Pr ** (1 / 3) if Re <= 5e5 else (0.037 * Re ** 0.8 - 871) * Pr ** (1 / 3)


def nu_cross_flow(Re, Pr):              # eq. 7.54
    return (0.3 + 0.62 * Re ** 0.5 * Pr ** (1 / 3) / (1 + (0.4 / Pr) ** (2 / 3)) ** 0.25
            * (1 + (Re / 282000) ** (5 / 8)) ** (4 / 5))


def hand_k(T, p, inflow, geometry, wall, air_speed, tank):
    """k = A q / |T - T_atm|, q the flux through inside film, wall and outside film in series
    (eq. 9.64 mixes natural and forced convection on each side; outside, radiation in parallel,
    emissivity 0.9, surroundings at T_atm); the films' temperature
    differences found by root solves of h(d) d = q, q by a root solve of their sum."""
    area, height, D, port_area = geometry
    rho_c = p / (AIR.R_J_per_kgK * T)
    u_c = inflow / (rho_c * math.sqrt(port_area * math.pi * D * D / 4))
    dT = T - T_ATM_K
    sign, size = math.copysign(1.0, dT), abs(dT)

    def h_in(d):                        # d: the inside film's temperature difference, >= 0
        Tf = T - sign * d / 2
        nu, _, Pr, k, _ = air(Tf, p)
        h_n = nu_vertical_plate(ra(d, height, Tf, p), Pr) * k / height
        h_f = nu_flat_plate(u_c * D / nu, Pr) * k / D
        return (h_n ** 3 + h_f ** 3) ** (1 / 3)

    def h_out(d):
        Tf = T_ATM_K + sign * d / 2
        nu, _, Pr, k, _ = air(Tf, P_ATM_PA)
        h_n = (nu_horizontal_cylinder(ra(d, D, Tf, P_ATM_PA), Pr) * k / D if tank
               else nu_vertical_plate(ra(d, height, Tf, P_ATM_PA), Pr) * k / height)
        h_f = nu_cross_flow(air_speed * D / nu, Pr) * k / D if air_speed > 0 else 0.0
        T_wall = T_ATM_K + sign * d
        h_r = 0.9 * 5.670374419e-8 * (T_wall + T_ATM_K) * (T_wall ** 2 + T_ATM_K ** 2)   # eq. 1.9, eps 0.9
        return (h_n ** 3 + h_f ** 3) ** (1 / 3) + h_r

    def film(h, q):
        return brentq(lambda d: h(d) * d - q, 0.0, size, xtol=1e-15, rtol=1e-15)

    # up to this flux neither film's difference exceeds |T - T_atm|; at it one of them equals it
    q_max = min(h_in(size), h_out(size)) * size
    q = brentq(lambda q: film(h_in, q) + q * wall + film(h_out, q) - size, 0.0, q_max, xtol=1e-13, rtol=1e-15)
    return area * q / size


def _bellow_geometry(z):
    A, V = 0.13, 0.012 - 0.13 * z
    D = math.sqrt(4 * A / math.pi)
    return math.pi * D * V / A + 2 * A, V / A, D, math.pi * 0.018 ** 2 / 4


def _tank_geometry(V, D=None):
    D = D or (4 * V / (math.pi * 2)) ** (1 / 3)                 # two diameters long
    L = 4 * V / (math.pi * D * D)
    return math.pi * D * L + math.pi * D * D / 2, D, D, math.pi * 0.018 ** 2 / 4


@pytest.mark.parametrize("label, z, T, inflow, air_speed, diameter, tank", [
    ("bellow at rest, hot", 0.0, T_ATM_K + 30, 0.0, 0.0, None, False),
    ("bellow crushed, filling (laminar, Re 2e5)", 0.02, T_ATM_K + 5, 0.05, 0.0, None, False),
    ("bellow, a fast fill (Re 2e6), in the wind", 0.0, T_ATM_K + 60, 0.5, 30.0, None, False),
    ("tank at rest, cold", 0.0, T_ATM_K - 20, 0.0, 0.0, None, True),
    ("tank of 0.2 m filling in the wind", 0.0, T_ATM_K + 80, 0.02, 20.0, 0.2, True),
])
def test_the_correlations_k_is_the_hand_computation(label, z, T, inflow, air_speed, diameter, tank):
    heat = ChamberHeat("correlation", air_speed_m_per_s=air_speed or None, diameter_m=diameter)
    geometry, wall = (_tank_geometry(0.027, diameter), 0.003 / 50) if tank else (_bellow_geometry(z), 0.006 / 0.25)
    comps = {"c": Tank(p0_Pa=P0_PA, heat=heat)} if tank else {"c": Bellow(p0_Pa=P0_PA, heat=heat)}
    comps |= {"source": Tank(p0_Pa=P0_PA), "p": Pipe("source", "c")}  # the pipe's flow a -> b: into c
    circuit = Circuit(comps, k_W_per_K=0.0)
    x = circuit.initial_state()
    x[circuit.layout.T][0] = T
    x[circuit.layout.q] = inflow
    p = float(circuit.chamber_states(x, np.array([z] * (not tank)))[0][0, 0])
    got = float(circuit.heat_conductances_W_per_K(x, np.array([z] * (not tank)))[0, 0])
    expected = hand_k(T, p, inflow, geometry, wall, air_speed, tank)
    assert got == pytest.approx(expected, rel=1e-6), label
    # air flowing out stirs nothing: the chamber at rest's k
    x[circuit.layout.q] = -inflow
    at_rest = hand_k(T, p, 0.0, geometry, wall, air_speed, tank)
    assert float(circuit.heat_conductances_W_per_K(x, np.array([z] * (not tank)))[0, 0]) == pytest.approx(at_rest, rel=1e-6)


def test_the_paper_chambers_k_at_rest_as_docs_models_quotes_it():
    """The paper's bellow and tank at 4 bar, 5 K above the atmosphere, still air, no flow."""
    circuit = Circuit(_rig(CORRELATION, CORRELATION))
    x = circuit.initial_state()
    x[circuit.layout.T] += 5.0
    k = circuit.heat_conductances_W_per_K(x, np.zeros(1))[:, 0]
    assert k == pytest.approx([1.24, 1.68], rel=0.01)


def test_the_air_properties_are_incroperas_table_a4():
    """Sutherland's law against Incropera Table A.4 (air at 1 atm): mu 159.6, 184.6, 208.2 e-7 Pa s
    and k 22.3, 26.3, 30.0 e-3 W/(m K) at 250, 300, 350 K; within 1.5 %."""
    for T, mu, k in ((250.0, 159.6e-7, 22.3e-3), (300.0, 184.6e-7, 26.3e-3), (350.0, 208.2e-7, 30.0e-3)):
        assert sutherland(T, 1.716e-5, 111.0) == pytest.approx(mu, rel=0.015)
        assert sutherland(T, 0.0241, 194.0) == pytest.approx(k, rel=0.015)


def test_the_compiled_law_is_its_python_source():
    """numba runs the same operations; pow may round differently in the last bit (1 ulp seen)."""
    rng = np.random.default_rng(7)
    n = 400
    args = [T_ATM_K + rng.uniform(-100, 120, n), 10 ** rng.uniform(-0.5, 1.3, n), rng.choice([0.0, 0.01, 1.0], n),
            np.full(n, T_ATM_K), np.full(n, P_ATM_PA), rng.uniform(0.1, 2.0, n), rng.uniform(0.05, 1.0, n),
            rng.uniform(0.1, 1.0, n), np.full(n, 2.5e-4), rng.choice([6e-5, 0.024], n), rng.choice([0.0, 25.0], n),
            rng.choice([0.0, 0.9], n), rng.choice([0.0, 1.0], n), np.full(n, AIR.cp_J_per_kgK), np.full(n, AIR.R_J_per_kgK)]
    compiled = wall_conductance_W_per_K(*args)
    python = np.array([wall_conductance_W_per_K.py_func(*(a[i] for a in args)) for i in range(n)])
    np.testing.assert_allclose(compiled, python, rtol=1e-13, atol=0.0)


# ------------------------------------------------------------------------- what the circuit refuses
@pytest.mark.parametrize("heat, path, phrase", [
    (ChamberHeat(), ["b", "heat", "k_W_per_K"], "needs its k"),
    (ChamberHeat(k_W_per_K=-1.0), ["b", "heat", "k_W_per_K"], ">= 0"),
    (ChamberHeat(k_W_per_K=math.nan), ["b", "heat", "k_W_per_K"], ">= 0"),
    (ChamberHeat(k_W_per_K=2.0, wall_thickness_m=0.005), ["b", "heat", "wall_thickness_m"], "model: correlation"),
    (ChamberHeat("correlation", k_W_per_K=2.0), ["b", "heat", "k_W_per_K"], "computes k"),
    (ChamberHeat("radiation"), ["b", "heat", "model"], "constant, correlation"),
    (ChamberHeat("correlation", diameter_m=0.3), ["b", "heat", "diameter_m"], "a tank's"),
    (ChamberHeat("correlation", wall_thickness_m=0.0), ["b", "heat", "wall_thickness_m"], "> 0"),
    (ChamberHeat("correlation", air_speed_m_per_s=-1.0), ["b", "heat", "air_speed_m_per_s"], ">= 0"),
    (ChamberHeat("correlation", emissivity=1.5), ["b", "heat", "emissivity"], "at most 1"),
    (ChamberHeat("correlation", port_diameter_m=0.5), ["b", "heat", "port_diameter_m"], "wider than its port"),
    ("hot", ["b", "heat"], "expected a ChamberHeat"),
])
def test_a_law_that_cannot_be_meant_is_refused_naming_its_key(heat, path, phrase):
    with pytest.raises(CircuitError) as info:
        Circuit({"b": Bellow(p0_Pa=P0_PA, heat=heat)})
    assert list(info.value.path) == path and phrase in info.value.reason


def test_an_isothermal_chamber_must_start_at_the_atmospheres_temperature_the_others_need_not():
    hot = dataclasses.replace(Tank(p0_Pa=P0_PA), T0_K=320.0)
    with pytest.raises(CircuitError, match="atmosphere's temperature"):
        Circuit({"t": dataclasses.replace(hot, heat=ChamberHeat(k_W_per_K=math.inf))}).initial_state()
    # an adiabatic tank may start hot in a case of k = inf (its own k holds)
    x = Circuit({"t": dataclasses.replace(hot, heat=ChamberHeat(k_W_per_K=0.0))}, k_W_per_K=math.inf).initial_state()
    assert x[1] == 320.0
