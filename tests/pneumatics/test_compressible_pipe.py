"""The compressible pipe (``model: compressible``, :mod:`pneumatics.compressible_pipe`) against
what it must reproduce: the acoustic modes of a pipe, the inertial pipe of eq. (5) for a short
pipe at low frequency, the conservation of mass and energy, the choked flow at its end, and
Sod's shock tube."""
from __future__ import annotations

import math

import numpy as np
import pytest

from pneumatics.boundary import Supply
from pneumatics.chamber import Bellow, Tank
from pneumatics.circuit import Circuit, CircuitError
from pneumatics.compressible_pipe import (
    PipeCell,
    cell_count,
    choked_mass_flow_kg_per_s,
    darcy_friction_factor,
    expand_compressible_pipes,
)
from pneumatics.integrate import rk4, simulate, stable_step_s
from pneumatics.linear import linearise_circuit
from pneumatics.pipe import Pipe
from pneumatics.rig import bellow_tank_components, dynamic_stiffness_sweep, sine_motion

GAMMA, R, T_ATM = 1.4, 287.0, 293.15
SOUND_M_PER_S = math.sqrt(GAMMA * R * T_ATM)     # the cells start at the atmosphere's 293.15 K
L_M, D_M = 1.0, 0.018
AREA_M2 = math.pi * D_M ** 2 / 4


def pipe_modes_Hz(cells: int, ends: str) -> np.ndarray:
    """The first three acoustic modes of a 1 m pipe without losses, from the eigenvalues of the
    linearised circuit: closed at both ends (two chambers of a millionth of the pipe's volume:
    their compliance is negligible, their own mode far above), or open at end a (a fixed-pressure
    supply) and closed at b."""
    tiny = Tank(V_m3=AREA_M2 * L_M * 1e-6, p0_Pa=4e5)
    comps = {"a": tiny if ends == "closed" else Supply(p_Pa=4e5), "b": tiny,
             "pipe": Pipe("a", "b", length_m=L_M, diameter_m=D_M, zeta=0.0, model="compressible", cells=cells)}
    circuit = Circuit(comps, k_W_per_K=0.0)
    lin = linearise_circuit(circuit, circuit.initial_state())
    f = np.unique(np.round(np.abs(np.linalg.eigvals(lin.A).imag) / (2 * np.pi), 6))
    return f[f > 1.0][:3]


def exact_modes_Hz(ends: str) -> np.ndarray:
    n = np.arange(1, 4)
    return n * SOUND_M_PER_S / (2 * L_M) if ends == "closed" else (2 * n - 1) * SOUND_M_PER_S / (4 * L_M)


#: relative errors [%] of the first three modes against n c / 2L (closed-closed) and
#: (2n - 1) c / 4L (open-closed), as this test computes them (the staggered line's modes are
#: 2 c / dx sin(k pi dx / 2 L'): second order in dx)
#:
#: ======  =============================  =============================
#: cells   closed-closed  (n = 1, 2, 3)   open-closed  (n = 1, 2, 3)
#: ======  =============================  =============================
#:   5     -1.64  -6.45  -14.2            -0.41  -3.66  -9.97
#:  10     -0.41  -1.64  -3.66            -0.10  -0.92  -2.55
#:  20     -0.10  -0.41  -0.92            -0.03  -0.23  -0.64
#:  40     -0.03  -0.10  -0.23            -0.01  -0.06  -0.16
#: ======  =============================  =============================
@pytest.mark.parametrize("ends", ["closed", "open"])
def test_acoustic_modes_within_one_percent_at_20_cells(ends):
    f = pipe_modes_Hz(20, ends)
    # 1 %: the brief's requirement; the table above shows the third mode at 0.92 % (closed)
    np.testing.assert_allclose(f, exact_modes_Hz(ends), rtol=0.01)


@pytest.mark.parametrize("ends", ["closed", "open"])
def test_acoustic_modes_converge_at_second_order(ends):
    errors = np.array([np.abs(pipe_modes_Hz(n, ends) / exact_modes_Hz(ends) - 1) for n in (10, 20, 40)])
    order = np.log2(errors[:-1] / errors[1:])
    # a centred staggered scheme is second order: the error of each mode falls 4-fold per
    # halving of dx; 1.9-2.1 allows the sine's higher terms at 10 cells (mode 3 there: 3.7 %)
    assert np.all((order > 1.9) & (order < 2.1)), order


def test_short_pipe_tends_to_the_inertial_pipe_below_5_Hz():
    """K_dyn of the paper's bellow-pipe-tank (Table 1) by the rig's sweep, inertial and
    compressible (4 cells: the pipe's first mode at ~170 Hz, far above 5 Hz), at an amplitude of
    2 mm (pipe Mach number < 0.1 at 5 Hz: at the rig's 20 mm it reaches 0.6 near 5 Hz, where the
    pipe's compressibility, its momentum flux and its choked exit are no longer small) and
    k = 100 W/K."""
    f = [0.5, 2.0, 5.0]
    K = {}
    for model in ("dynamic", "compressible"):
        comps = bellow_tank_components(Bellow(), Tank(), Pipe("", "", model=model, cells=4))
        points = dynamic_stiffness_sweep(comps, [100.0], f, 0.002, p0_Pa={"bellow": 4e5, "tank": 4e5})
        assert all(p.stabilised for p in points)
        K[model] = np.array([p.K_dyn_N_per_m for p in points])
    # 1 %: the brief's bound. The compressible pipe holds A L = 0.25 dm^3 of air more than the
    # inertial pipe's 39 dm^3 (0.65 % more compliance), its only difference at low frequency
    np.testing.assert_allclose(K["compressible"], K["dynamic"], rtol=0.01)


def rig_run(k_W_per_K: float, friction_factor=0.0, t_end_s: float = 0.6):
    comps = bellow_tank_components(Bellow(), Tank(), Pipe("", "", model="compressible", cells=10,
                                                           friction_factor=friction_factor))
    circuit = Circuit(comps, k_W_per_K=k_W_per_K)
    x0 = circuit.initial_state({"bellow": 4e5, "tank": 4e5})
    sol = simulate(circuit, x0, t_end_s, sine_motion(0.02, 5.0), rtol=1e-10)
    assert sol.success
    return circuit, x0, sol.y[:, -1]


def air_energy_J(circuit: Circuit, x: np.ndarray) -> float:
    """Internal energy of every chamber and cell, plus the cells' kinetic energy m u^2 / 2, u the
    mean of its two links' flows over rho A."""
    lay, cells = circuit.layout, circuit.assembly.pipes.cells
    q, m = x[lay.q], x[lay.m]
    flow = 0.5 * (q[cells.left] + q[cells.right])
    kinetic = flow ** 2 * cells.dx_m[:, 0] ** 2 / (2 * m[cells.rows])
    return circuit.gas.cv_J_per_kgK * m @ x[lay.T] + kinetic.sum()


@pytest.mark.parametrize("k, friction_factor", [(0.0, 0.0), (100.0, None)])
def test_mass_and_energy_are_conserved_over_a_rig_run(k, friction_factor):
    """Three cycles of 20 mm at 5 Hz (the pipe's air at up to Mach ~0.6): the air's mass does not
    change, and its energy (internal, and the cells' kinetic) changes by the bellow's work and the
    heat from outside."""
    circuit, x0, x1 = rig_run(k, friction_factor)
    lay = circuit.layout
    mass0, mass1 = x0[lay.m].sum(), x1[lay.m].sum()
    energy0, energy1 = air_energy_J(circuit, x0), air_energy_J(circuit, x1)
    assert energy1 - energy0 != pytest.approx(0.0, abs=1e-3 * energy0)     # the run did change it
    # mass: its rate sums to zero exactly (every link leaves one node and enters another), so
    # only round-off remains (1e-14 of the mass per step over ~1e4 steps)
    assert abs(mass1 / mass0 - 1) < 1e-12
    # energy: the balance is exact in the equations; the integrator's error on U - W - Q is its
    # tolerance (rtol 1e-10) on ~1e4 J over a few thousand steps: 1e-8 of U leaves a margin of 10
    balance = energy1 - energy0 - x1[lay.work_in] - x1[lay.heat_in]
    assert abs(balance) < 1e-8 * energy0, balance


def test_choked_flow_at_the_end_of_a_pipe_to_the_atmosphere():
    """A short pipe without losses from a 5 bar supply to the atmosphere (pressure ratio 0.2 <
    0.528: choked): the steady flow it delivers is the isentropic choked flow of the supply's
    state within 2 % from below, never above it. (It gives 0.990 m*: the air enters the pipe
    isentropically, the exit sees no pressure below the critical one, and the end link passes
    q / (1 + (q/m*)^20)^(1/20) of its state q = 1.09 m*; the pipe's Mach number is 0.89, not 1,
    where the lumped line's last cell stands for the whole exit.)"""
    p0, T0 = 5e5, T_ATM
    comps = {"supply": Supply(p_Pa=p0, T_K=T0), "pipe": Pipe("supply", "atmosphere", length_m=0.2, diameter_m=D_M,
                                                             zeta=0.0, model="compressible", cells=4)}
    circuit = Circuit(comps, k_W_per_K=0.0)
    x0 = circuit.initial_state()
    sol = simulate(circuit, x0, 0.05, lambda t: (np.zeros(0), np.zeros(0)), rtol=1e-9)
    assert sol.success
    w = circuit.outputs(sol.y[:, -1], np.zeros(0)).link_flow_kg_per_s
    exit_flow = w[circuit.link_names.index("pipe.seg4")]
    m_star = AREA_M2 * p0 * math.sqrt(GAMMA / (R * T0)) * (2 / (GAMMA + 1)) ** ((GAMMA + 1) / (2 * (GAMMA - 1)))
    assert choked_mass_flow_kg_per_s(AREA_M2, p0, T0, R, GAMMA) == pytest.approx(m_star, rel=1e-15)
    assert 0.98 * m_star < exit_flow <= m_star
    # steady: every link of the pipe carries the same flow (to the integrator's tolerance)
    np.testing.assert_allclose(w, exit_flow, rtol=1e-4)


def sod_density_L1(cells: int) -> float:
    """Sod's shock tube in a 1 m tube of 50 mm bore closed at both ends, 1e5 Pa and 1 kg/m^3 on
    the left, 1e4 Pa and 0.125 kg/m^3 on the right, at t = 0.2 L / sqrt(p_L / rho_L): L1 error of
    the cells' density against the exact Riemann solution [kg/m^3 . m]."""
    area = math.pi * 0.05 ** 2 / 4
    end = area / cells          # the ends: chambers of a cell's volume (no wave reaches them by t_end)
    comps = {"left": Tank(V_m3=end, p0_Pa=1e5, T0_K=1e5 / R), "right": Tank(V_m3=end, p0_Pa=1e4, T0_K=1e4 / (0.125 * R)),
             "tube": Pipe("left", "right", length_m=1.0, diameter_m=0.05, zeta=0.0, model="compressible", cells=cells)}
    circuit = Circuit(comps, k_W_per_K=0.0)
    lay, x = circuit.layout, circuit.initial_state()
    rows = [circuit.chamber_names.index(f"tube.cell{i}") for i in range(1, cells + 1)]
    xc = (np.arange(cells) + 0.5) / cells
    V = area / cells
    rho0 = np.where(xc < 0.5, 1.0, 0.125)
    p0 = np.where(xc < 0.5, 1e5, 1e4)
    x[lay.m][rows], x[lay.T][rows] = rho0 * V, p0 / (rho0 * R)
    t_end = 0.2 / math.sqrt(1e5)
    f = lambda t, xx: circuit.derivatives(xx, np.zeros(0), np.zeros(0))
    x = rk4(f, x, 0.0, t_end, int(math.ceil(t_end / stable_step_s(circuit, x, 1.0))))
    return float(np.mean(np.abs(x[lay.m][rows] / V - sod_exact_density(xc, t_end))))


def sod_exact_density(x: np.ndarray, t: float) -> np.ndarray:
    """The exact Riemann solution of Sod's problem (Toro, ch. 4): density at x, diaphragm at 0.5."""
    g, (pL, rL, pR, rR) = GAMMA, (1e5, 1.0, 1e4, 0.125)
    cL, cR = math.sqrt(g * pL / rL), math.sqrt(g * pR / rR)

    def f(p, pk, rk, ck):
        if p > pk:
            a, b = 2 / ((g + 1) * rk), (g - 1) / (g + 1) * pk
            return (p - pk) * math.sqrt(a / (p + b))
        return 2 * ck / (g - 1) * ((p / pk) ** ((g - 1) / (2 * g)) - 1)
    lo, hi = 1.0, pL
    for _ in range(200):                       # bisection for the star pressure
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if f(mid, pL, rL, cL) + f(mid, pR, rR, cR) > 0 else (mid, hi)
    ps = 0.5 * (lo + hi)
    us = 0.5 * (f(ps, pR, rR, cR) - f(ps, pL, rL, cL))
    shock = math.sqrt(g * pR / rR) * math.sqrt((g + 1) / (2 * g) * ps / pR + (g - 1) / (2 * g))
    s = (x - 0.5) / t
    fan = rL * (2 / (g + 1) - (g - 1) / ((g + 1) * cL) * s) ** (2 / (g - 1))
    tail = us - cL * (ps / pL) ** ((g - 1) / (2 * g))
    r_star_R = rR * (ps / pR + (g - 1) / (g + 1)) / ((g - 1) / (g + 1) * ps / pR + 1)
    return np.select([s < -cL, s < tail, s < us, s < shock], [rL, fan, rL * (ps / pL) ** (1 / g), r_star_R], rR)


#: Sod's shock tube, L1 error of density [kg/m^3 . m] against the exact solution, as
#: ``python -c "from test_compressible_pipe import *; print([sod_density_L1(n) for n in ...])"``
#: gives it: 50 cells 0.0180, 100 0.0114, 200 0.0073, 400 0.0048; observed orders 0.65, 0.65, 0.62
#: (first order in smooth flow, ~0.5-1 with a shock and a contact: the upwind enthalpy and
#: momentum fluxes smear them over a few cells)
def test_sod_shock_tube_converges_at_the_order_of_an_upwind_scheme():
    errors = np.array([sod_density_L1(n) for n in (100, 200, 400)])
    # the exact solution checked against Toro's table 4.2 (rho*_R = 0.26557 behind the shock)
    assert sod_exact_density(np.array([0.6]), 0.1 / 316.2)[0] == pytest.approx(0.26557, rel=1e-3)
    order = np.log2(errors[:-1] / errors[1:])
    # 0.5-1: what a first-order scheme gives near a shock and a contact (the brief's range); the
    # error at 400 cells, 0.48 % of rho_L (x 1 m), below 1 %: the shock's position and plateaus
    # are right (a model without the rho u^2 flux and the kinetic energy stayed at 6.5 %)
    assert np.all((order > 0.5) & (order < 1.0)), order
    assert errors[-1] < 0.01, errors


def test_expansion_and_checks():
    pipe = Pipe("a", "b", length_m=1.0, model="compressible")
    assert cell_count(pipe) == 20                          # 1 m of 0.05 m cells
    assert cell_count(Pipe("a", "b", length_m=1.01, model="compressible")) == 21
    assert cell_count(Pipe("a", "b", model="compressible", cells=7)) == 7
    comps = expand_compressible_pipes({"a": Tank(p0_Pa=4e5), "b": Tank(p0_Pa=3e5), "p": Pipe("a", "b", model="compressible",
                                                                                             cells=3, zeta=1.5)})
    assert list(comps) == ["a", "b", "p", "p.seg1", "p.seg2", "p.seg3", "p.cell1", "p.cell2", "p.cell3"]
    assert sum(c.length_m for c in comps.values() if isinstance(c, Pipe)) == pytest.approx(1.0, rel=1e-15)
    # the fittings' share: zeta less the exit's velocity head, which the line models itself
    assert sum(c.zeta for c in comps.values() if isinstance(c, Pipe)) == 0.5
    assert sum(c.V_m3 for c in comps.values() if isinstance(c, PipeCell)) == pytest.approx(AREA_M2, rel=1e-15)
    circuit = Circuit({"a": Tank(p0_Pa=4e5), "b": Tank(p0_Pa=3e5), "p": Pipe("a", "b", model="compressible", cells=3)})
    p = circuit.chamber_states(circuit.initial_state(), np.zeros(0))[0][:, 0]
    np.testing.assert_allclose(p, [4e5, 3e5, 4e5 - 1e5 / 6, 3.5e5, 3e5 + 1e5 / 6])   # cells between the ends
    with pytest.raises(CircuitError, match="friction_factor"):
        Circuit({"a": Tank(p0_Pa=4e5), "b": Tank(p0_Pa=3e5), "p": Pipe("a", "b", friction_factor=None)})
    with pytest.raises(CircuitError, match="cells"):
        Circuit({"a": Tank(p0_Pa=4e5), "b": Tank(p0_Pa=3e5), "p": Pipe("a", "b", model="compressible", cells=-1)})
    with pytest.raises(CircuitError, match="model"):
        Circuit({"a": Tank(p0_Pa=4e5), "b": Tank(p0_Pa=3e5), "p": Pipe("a", "b", model="compresible")})


def test_friction_factor_of_the_reynolds_number():
    # laminar: 64 / Re to 1e-6 at Re = 100 (Churchill's turbulent term is (37530/Re)^-24 there)
    assert darcy_friction_factor(100.0) == pytest.approx(0.64, rel=1e-6)
    # turbulent smooth pipe: Blasius 0.3164 Re^-1/4 within 3 % at Re = 2e4 (Churchill's fit of the
    # Colebrook smooth-pipe line, which Blasius follows to ~2 % up to 1e5)
    assert darcy_friction_factor(2e4) == pytest.approx(0.3164 * 2e4 ** -0.25, rel=0.03)
