"""Thermal relaxation of air shut in after a fast inflation, against the analytic exponentials of
the first law (pneumatics level: the car is not needed, its bellow carries a constant load).

A chamber is filled from the 9 bar supply through an orifice in 0.2 s (the air arrives hot: the
supply's enthalpy c_p T pushes into the chamber's, eq. 2), then the orifice is blocked (a fault at
the end of the fill) and the closed air exchanges heat with the atmosphere, dQ/dt = k (T_atm - T)
(eq. 8). With the mass M fixed, eq. 2 reduces to

* at constant volume (a rigid chamber): M c_v dT/dt = k (T_atm - T), so T - T_atm and with it
  p - p_inf = M R (T - T_atm) / V decay as exp(-t / tau_v), **tau_v = M c_v / k**;
* at constant pressure (a bellow carrying a constant load, constant effective area: the car's
  standing carbody on a bellow shut off by its valve): p V = M R T with p fixed, so
  p dV/dt = M R dT/dt and M c_v dT/dt = k (T_atm - T) - M R dT/dt: M c_p dT/dt = k (T_atm - T).
  The volume, and the bellow's height with it (V = V0 - A z), drift as exp(-t / tau_p),
  **tau_p = M c_p / k** = gamma tau_v: the cooling air does work on it as it shrinks, so a loaded
  bellow relaxes 1.4 times slower than the closed rigid chamber.

The circuit's rates are integrated by LSODA at rtol 1e-10; the constant load enters as the
constraint p(M, T, z) = p*: at every evaluation z follows from it and dz/dt from its time
derivative (the rates are affine in dz/dt, so two evaluations give it exactly). Asked: within
2 % of the initial excess; k in {1, 10, 100} W/K.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pneumatics.boundary import Supply
from pneumatics.chamber import Bellow, Tank
from pneumatics.circuit import Circuit
from pneumatics.faults import Fault
from pneumatics.gas import AIR
from pneumatics.integrate import absolute_tolerances, simulate
from pneumatics.orifice import Orifice

P0_PA = 4.0e5               # before the fill
FILL_S = 0.2                # the fill: fast against every tau here (>= 2 s)
C_FILL = 5.0e-7             # [m^3/(s Pa)]: ~0.1 kg/s from 9 bar, +50 % of the air in 0.2 s
RTOL = 1e-10
#: within 2 % of the initial excess (the issue's tolerance); the integration is good to ~1e-8
TOLERANCE = 0.02


def held(t):
    return np.zeros(1), np.zeros(1)


def fill_then_shut(chamber, k: float):
    """(closed circuit, state at the end of the fill): the chamber at P0 and T_atm filled through
    an orifice for FILL_S, then the orifice blocked."""
    components = {"B": chamber, "supply": Supply(), "fill": Orifice("supply", "B", C_FILL)}
    circuit = Circuit(components, k_W_per_K=k, faults=[Fault("blocked", "fill", t_s=FILL_S)])
    sol = simulate(circuit, circuit.initial_state({"B": P0_PA}), FILL_S, held, rtol=RTOL)
    assert sol.success
    return circuit.with_active_faults([0]), sol.y[:, -1]


@pytest.mark.parametrize("k", [1.0, 10.0, 100.0])
def test_closed_rigid_chamber_relaxes_with_m_cv_over_k(k):
    circuit, x1 = fill_then_shut(Tank(V_m3=0.039), k)
    lay, gas, T_atm = circuit.layout, AIR, circuit.atmosphere.T_K
    M, T1 = float(x1[lay.m][0]), float(x1[lay.T][0])
    assert T1 > T_atm + 20.0                                  # the fill heated the air
    tau = M * gas.cv_J_per_kgK / k
    t = np.array([0.25, 0.5, 1.0, 2.0, 3.0]) * tau
    sol = simulate(circuit, x1, t[-1], held, t_eval=t, rtol=RTOL)
    assert sol.success and np.all(sol.y[lay.m] == pytest.approx(M, rel=1e-12))   # shut: no air moves
    p, _ = circuit.chamber_states(sol.y, np.zeros((1, len(t))))
    V = 0.039
    p_inf, p1 = M * gas.R_J_per_kgK * T_atm / V, M * gas.R_J_per_kgK * T1 / V
    expected = p_inf + (p1 - p_inf) * np.exp(-t / tau)
    assert np.abs(p[0] - expected).max() <= TOLERANCE * (p1 - p_inf)


def loaded_bellow_rates(circuit: Circuit, bellow: Bellow, p_load_Pa: float):
    """f(t, x) of the closed bellow whose crushing keeps its pressure at ``p_load_Pa`` (a constant
    load on a constant effective area), and z(x)."""
    lay, R = circuit.layout, AIR.R_J_per_kgK

    def crushing(x):
        V = x[lay.m][0] * R * x[lay.T][0] / p_load_Pa
        return (bellow.V0_m3 - V) / bellow.dV_dz_m2

    def f(t, x):
        z = np.array([crushing(x)])
        d0, d1 = circuit.derivatives(x, z, np.zeros(1)), circuit.derivatives(x, z, np.ones(1))
        # V = M R T / p*, M fixed: -dV/dz zd = (M R / p*) (dT/dt(0) + (dT/dt(1) - dT/dt(0)) zd)
        c = x[lay.m][0] * R / p_load_Pa
        a, b = d0[lay.T][0], d1[lay.T][0] - d0[lay.T][0]
        zd = -c * a / (bellow.dV_dz_m2 + c * b)
        return d0 + (d1 - d0) * zd
    return f, crushing


@pytest.mark.parametrize("k", [1.0, 10.0, 100.0])
def test_loaded_bellow_height_drifts_with_m_cp_over_k(k):
    bellow = Bellow()                                         # 12 dm^3, A = 0.13 m^2 constant
    circuit, x1 = fill_then_shut(bellow, k)
    lay, gas, T_atm = circuit.layout, AIR, circuit.atmosphere.T_K
    M = float(x1[lay.m][0])
    p_load, _ = circuit.chamber_states(x1, np.zeros(1))       # the load it carries from the end of the fill on
    f, crushing = loaded_bellow_rates(circuit, bellow, float(np.ravel(p_load)[0]))
    tau = M * gas.cp_J_per_kgK / k
    t = np.array([0.25, 0.5, 1.0, 2.0, 3.0]) * tau
    sol = solve_ivp(f, (0.0, t[-1]), x1, method="LSODA", t_eval=t, rtol=RTOL,
                    atol=absolute_tolerances(circuit, RTOL))
    assert sol.success
    z = np.array([crushing(x) for x in sol.y.T])
    z1 = crushing(x1)
    z_inf = (bellow.V0_m3 - M * gas.R_J_per_kgK * T_atm / np.ravel(p_load)[0]) / bellow.dV_dz_m2
    assert z_inf - z1 > 1e-3                                   # it sinks by millimetres as it cools
    expected = z_inf + (z1 - z_inf) * np.exp(-t / tau)
    assert np.abs(z - expected).max() <= TOLERANCE * (z_inf - z1)
    # the closed chamber's constant would be wrong here by 12 % of the excess at t = tau_p: six
    # times the tolerance, so the test tells the two apart
    assert abs(np.exp(-1.0) - np.exp(-gas.gamma)) > 5 * TOLERANCE
