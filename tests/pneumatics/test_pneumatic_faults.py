"""Faults of the air system (pneumatics.faults): blow-down against the analytic blow-down of a
fixed volume, stuck valves, blocked and ruptured pipes, a lost supply, the air accounting.

The blow-down references are written here from the ISO 6358 law itself (eqs 6-7) and the first
law for a fixed volume, independently of the circuit: isothermal, m = pV/(RT) with T fixed; adiabatic,
the gas left in the volume expands isentropically, p/p0 = (T/T0)^(gamma/(gamma-1)). The choked
phase has a closed form in both cases; the subsonic phase is the quadrature t = int dp / (dp/dt)
of the same law (scipy.integrate.quad, relative error ~1e-10). The circuit is integrated by
LSODA at rtol 1e-10, so the two agree to ~1e-6; the issue asks for 2 %.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from pneumatics.boundary import Supply
from pneumatics.chamber import Bellow, Tank
from pneumatics.circuit import Circuit, CircuitError
from pneumatics.faults import Fault, nozzle_conductance
from pneumatics.gas import AIR, T_REF_K
from pneumatics.integrate import rk4, simulate
from pneumatics.layouts import car_circuit
from pneumatics.pipe import Pipe
from pneumatics.valves import DifferentialPressureValve, LevellingValve

P_ATM = 101_325.0
T_ATM = 293.15
P0 = 5.0e5
V = 0.012 + 0.027                     # a bellow at rest with its tank's volume: a fixed volume here
C = 2.0e-8                            # sonic conductance of the rupture [m^3/(s Pa)]
B = 0.3                               # critical pressure ratio
R, GAMMA = AIR.R_J_per_kgK, AIR.gamma
RHO_REF = 1.0e5 / (R * T_REF_K)


def still(t):
    return np.zeros(1), np.zeros(1)


def blow_down(k, t_end_s=120.0, n=2401):
    """Pressure [Pa] of a fixed volume V at P0 whose burst (C, B) opens at t = 0, on a time grid."""
    comps = {"B": Bellow(V0_m3=V, p0_Pa=P0)}
    circuit = Circuit(comps, k_W_per_K=k, faults=[Fault("burst", "B", C_m3_per_sPa=C, b_critical=B)]).with_active_faults([0])
    t = np.linspace(0.0, t_end_s, n)
    sol = simulate(circuit, circuit.initial_state(), t_end_s, still, t_eval=t, rtol=1e-10)
    assert sol.success
    p, _ = circuit.chamber_states(sol.y, np.zeros((1, sol.y.shape[1])))
    return sol.t, p[0]


def flow_factor(p):
    """The ISO 6358 subsonic factor sqrt(1 - ((p_atm/p - b)/(1 - b))^2), 1 while choked."""
    r = P_ATM / p
    return np.where(r <= B, 1.0, np.sqrt(np.clip(1.0 - ((r - B) / (1.0 - B)) ** 2, 0.0, None)))


def isothermal_time_to(p_end):
    """t(p_end): dm/dt = -C rho_ref sqrt(T_ref/T) p f(p), m = pV/(RT): dp/dt = -p f(p) / tau,
    tau = V / (C rho_ref R sqrt(T_ref T)); choked (f = 1) down to p* = p_atm/b: tau ln(P0/p*)."""
    tau = V / (C * RHO_REF * R * math.sqrt(T_REF_K * T_ATM))
    p_star = P_ATM / B
    choked = tau * math.log(P0 / max(p_star, p_end))
    if p_end >= p_star:
        return choked
    return choked + quad(lambda p: tau / (p * float(flow_factor(p))), p_end, p_star, epsrel=1e-12)[0]


def adiabatic_time_to(p_end):
    """Isentropic expansion of the air left: m = m0 (p/P0)^(1/gamma), T = T0 (p/P0)^((gamma-1)/gamma).
    dm/dt = (m0/(gamma P0)) (p/P0)^(1/gamma - 1) dp/dt = -C rho_ref sqrt(T_ref/T) p f(p), so
    dp/dt = -K p^(1 + e) f(p), e = (gamma-1)/(2 gamma), K = gamma C rho_ref sqrt(T_ref/T0) R T0 / (V P0^e)
    (with m0 = P0 V/(R T0)); choked: p^(-e) = P0^(-e) + e K t."""
    e = (GAMMA - 1.0) / (2.0 * GAMMA)
    K = GAMMA * C * RHO_REF * math.sqrt(T_REF_K / T_ATM) * R * T_ATM / (V * P0 ** e)
    p_star = P_ATM / B
    choked = ((max(p_star, p_end)) ** -e - P0 ** -e) / (e * K)
    if p_end >= p_star:
        return choked
    integrand = lambda p: 1.0 / (K * p ** (1.0 + e) * float(flow_factor(p)))
    return choked + quad(integrand, p_end, p_star, epsrel=1e-12)[0]


@pytest.mark.parametrize("k, reference", [(math.inf, isothermal_time_to), (0.0, adiabatic_time_to)],
                         ids=["isothermal", "adiabatic"])
def test_blow_down_time_matches_the_analytic_blow_down_of_a_fixed_volume(k, reference):
    """Times at which the gauge pressure has fallen to 50 %, 10 % (choked, then subsonic) and
    1 % of the initial gauge pressure, against the analytic ones. The issue asks for 2 %; they
    agree far closer, so the test holds them to 2e-4: what linear interpolation of the output
    grid can cost (the pressure's curvature over a 0.05 s interval)."""
    t, p = blow_down(k)
    for fraction in (0.5, 0.1, 0.01):
        p_end = P_ATM + fraction * (P0 - P_ATM)
        t_model = np.interp(-p_end, -p, t)                    # p decreases
        assert t_model == pytest.approx(reference(p_end), rel=2e-4), (fraction, t_model, reference(p_end))


def test_an_ideal_nozzle_area_gives_the_isentropic_choked_flow():
    """C of an area A: the choked flow of eq. (6) equals the isentropic nozzle's
    A p sqrt(gamma/(R T)) (2/(gamma+1))^((gamma+1)/(2(gamma-1))); air's rule of thumb
    C [dm^3/(s bar)] ~ 0.2 A [mm^2]; b = 0.528."""
    A, p, T = 1e-4, 6e5, 300.0
    C_A, b = nozzle_conductance(A)
    nozzle = A * p * math.sqrt(GAMMA / (R * T)) * (2 / (GAMMA + 1)) ** ((GAMMA + 1) / (2 * (GAMMA - 1)))
    assert C_A * p * RHO_REF * math.sqrt(T_REF_K / T) == pytest.approx(nozzle, rel=1e-12)
    assert C_A * 1e3 * 1e5 == pytest.approx(0.2 * A * 1e6, rel=0.01)
    assert b == pytest.approx(0.5283, abs=1e-4)


# ------------------------------------------------------------------------------- valves
def valve_circuit(fault=None):
    comps = {"bellow": Bellow(p0_Pa=4.0e5), "supply": Supply(p_Pa=9.0e5), "lv": LevellingValve("bellow")}
    circuit = Circuit(comps, k_W_per_K=math.inf, faults=[fault] if fault else [])
    return (circuit.with_active_faults([0]) if fault else circuit), circuit.initial_state()


def run_rk4(circuit, x0, z_m, t_end_s=2.0, h=1e-3):
    f = lambda t, x: circuit.derivatives(x, np.array([z_m]), np.zeros(1))
    return rk4(f, x0, 0.0, t_end_s, round(t_end_s / h))


def bellow_p(circuit, x, z_m=0.0):
    return circuit.chamber_states(x, np.array([z_m]))[0][0]


def test_a_valve_stuck_closed_passes_no_air_whatever_the_lever():
    for z in (0.03, -0.03):                       # a healthy valve would fill / drain
        healthy, x0 = valve_circuit()
        stuck, _ = valve_circuit(Fault("stuck_closed", "lv"))
        assert abs(bellow_p(healthy, run_rk4(healthy, x0, z), z) - bellow_p(healthy, x0, z)) > 1e4
        x = run_rk4(stuck, x0, z)
        air = stuck.valve_air_kg(x)
        assert air.supply[0] == 0.0 and air.exhaust[0] == 0.0
        assert stuck.total_mass_kg(x) == stuck.total_mass_kg(x0)


@pytest.mark.parametrize("side, p_end", [("supply", 9.0e5), ("exhaust", P_ATM)])
def test_a_valve_stuck_open_fills_from_the_supply_or_drains_to_the_atmosphere(side, p_end):
    """At the bellow's nominal height (lever in the dead band) a stuck-open side still passes
    air until the bellow reaches that side's pressure; the other side stays shut."""
    circuit, x0 = valve_circuit(Fault("stuck_open", "lv", side=side))
    x = run_rk4(circuit, x0, 0.0, t_end_s=60.0, h=5e-3)
    assert bellow_p(circuit, x) == pytest.approx(p_end, rel=1e-3)
    air = circuit.valve_air_kg(x)
    other = air.exhaust if side == "supply" else air.supply
    assert other[0] == 0.0
    assert (air.supply[0] > 0) if side == "supply" else (air.exhaust[0] > 0)


def test_a_valve_stuck_at_a_lever_acts_on_it_whatever_the_height():
    """Stuck at +10 mm (past the 5 mm dead band): fills although the bellow is extended by 30 mm."""
    circuit, x0 = valve_circuit(Fault("stuck_at", "lv", lever_m=0.010))
    x = run_rk4(circuit, x0, -0.03, t_end_s=2.0)
    air = circuit.valve_air_kg(x)
    assert air.supply[0] > 0.0 and air.exhaust[0] == 0.0


def test_a_lost_supply_delivers_nothing_though_the_valve_opens():
    circuit, x0 = valve_circuit(Fault("supply_lost", "supply"))
    x = run_rk4(circuit, x0, 0.03, t_end_s=2.0)
    assert circuit.valve_air_kg(x).supply[0] == 0.0
    assert circuit.valve_open_time_s(x).supply[0] == pytest.approx(2.0, abs=2e-3)   # it opened all along
    assert circuit.total_mass_kg(x) == circuit.total_mass_kg(x0)


def dpv_circuit(fault, dp):
    comps = {"L": Bellow(p0_Pa=4.0e5 + dp), "R": Bellow(p0_Pa=4.0e5), "dpv": DifferentialPressureValve("L", "R")}
    circuit = Circuit(comps, k_W_per_K=math.inf, faults=[fault]).with_active_faults([0])
    return circuit, circuit.initial_state()


def test_a_differential_valve_stuck_open_passes_below_its_opening_pressure_and_stuck_closed_never():
    z = np.zeros(2)
    closed, x0 = dpv_circuit(Fault("stuck_closed", "dpv"), 2.0e5)   # would open at 1.5 bar
    assert closed.outputs(x0, z).link_flow_kg_per_s[0] == 0.0
    opened, x0 = dpv_circuit(Fault("stuck_open", "dpv"), 0.5e5)      # 0.5 bar: a healthy valve is shut
    # the table (0, 0), (1.5 bar, 0), (2.5 bar, 0.02 kg/s) without its dead band: 0.01 kg/s at 0.5 bar
    assert opened.outputs(x0, z).link_flow_kg_per_s[0] == pytest.approx(0.01, rel=1e-12)


# ------------------------------------------------------------------------------- pipes
def bellow_tank(fault):
    comps = {"B": Bellow(p0_Pa=4.0e5), "T": Tank(p0_Pa=4.0e5), "pipe": Pipe("B", "T")}
    circuit = Circuit(comps, k_W_per_K=math.inf, faults=[fault]).with_active_faults([0])
    return circuit, circuit.initial_state()


def test_a_blocked_pipe_isolates_the_tank():
    """Crushing the bellow by 20 mm with the pipe blocked: the bellow alone is compressed
    (isothermal p V = const), the tank keeps its pressure."""
    circuit, x0 = bellow_tank(Fault("blocked", "pipe"))
    z = 0.02
    x = rk4(lambda t, x: circuit.derivatives(x, np.array([z * min(t, 1.0)]), np.array([z if t < 1.0 else 0.0])),
            x0, 0.0, 2.0, 2000)
    p, _ = circuit.chamber_states(x, np.array([z]))
    assert p[0] == pytest.approx(4.0e5 * 0.012 / (0.012 - 0.13 * z), rel=1e-9)
    assert p[1] == pytest.approx(4.0e5, rel=1e-12)


def test_a_ruptured_pipe_vents_both_ends_through_its_bore():
    circuit, x0 = bellow_tank(Fault("ruptured", "pipe"))
    assert circuit.link_names == ["pipe", "pipe.ruptured@B", "pipe.ruptured@T"]
    x = run_rk4(circuit, x0, 0.0, t_end_s=3.0)
    p, _ = circuit.chamber_states(x, np.zeros(1))
    assert np.allclose(p, P_ATM, rtol=1e-3)
    assert circuit.air_lost_kg(x) == pytest.approx(circuit.total_mass_kg(x0) - circuit.total_mass_kg(x), rel=1e-12)


# ------------------------------------------------------------------------------- accounting
def test_the_mass_balance_closes_with_a_burst_valves_and_a_moving_bellow():
    """The four-point car circuit with levelling and differential valves; FL bursts at 1 s
    while the bellows are crushed up and down: the air in the chambers changes by exactly
    what the supply gave, minus what the valves exhausted, minus what the burst lost (to
    round-off of the accumulated sums: every term is integrated with the same RK4 stages)."""
    comps = car_circuit(Bellow(), Tank(), Pipe("", ""), levelling=LevellingValve(""),
                        differential=DifferentialPressureValve("", ""))
    healthy = Circuit(comps, k_W_per_K=np.array([0.0, 10.0, math.inf]),
                      faults=[Fault("burst", "FL", t_s=1.0, area_m2=2e-4)])
    p0 = {n: 5.0e5 for n in healthy.chamber_names if n != "supply"}
    x = healthy.initial_state(p0)
    m0 = healthy.total_mass_kg(x)
    phase = np.array([0.0, 1.0, 2.0, 3.0])[:, None]

    def f_of(circuit):
        def f(t, x):
            z = 0.03 * np.sin(2 * math.pi * 0.5 * t + phase) * np.ones((4, 3))
            zd = 0.03 * math.pi * np.cos(2 * math.pi * 0.5 * t + phase) * np.ones((4, 3))
            return circuit.derivatives(x, z, zd)
        return f

    x = rk4(f_of(healthy), x, 0.0, 1.0, 1000)
    burst = healthy.with_active_faults([0])
    x = rk4(f_of(burst), x, 1.0, 4.0, 3000)
    supplied = burst.mass_from(x, "supply")
    exhausted = -burst.mass_from(x, "atmosphere")
    lost = burst.air_lost_kg(x)
    assert np.all(lost > 0.05) and np.all(exhausted > 0) and np.all(supplied > 0)
    assert np.allclose(burst.total_mass_kg(x) - m0, supplied - exhausted - lost, rtol=0, atol=1e-12)
    assert burst.layout == healthy.layout


# ------------------------------------------------------------------------------- input
@pytest.mark.parametrize("fault, path, words", [
    (Fault("burst", "XX", area_m2=1e-4), ("faults[0]", "component"), "not a component"),
    (Fault("burst", "pipe", area_m2=1e-4), ("faults[0]", "component"), "needs a chamber"),
    (Fault("blocked", "B"), ("faults[0]", "component"), "needs pipe or orifice"),
    (Fault("burst", "B"), ("faults[0]", "area_m2"), "one of them"),
    (Fault("burst", "B", area_m2=-1.0), ("faults[0]", "area_m2"), "> 0"),
    (Fault("burst", "B", area_m2=1e-4, side="supply"), ("faults[0]", "side"), "not used"),
    (Fault("explode", "B"), ("faults[0]", "kind"), "unknown fault kind"),
    (Fault("blocked", "pipe", t_s=-1.0), ("faults[0]", "t_s"), ">= 0"),
])
def test_bad_faults_are_refused_naming_the_field(fault, path, words):
    comps = {"B": Bellow(p0_Pa=4.0e5), "T": Tank(p0_Pa=4.0e5), "pipe": Pipe("B", "T")}
    with pytest.raises(CircuitError) as err:
        Circuit(comps, faults=[fault])
    assert err.value.path == path and words in err.value.reason


def test_two_openings_on_one_chamber_get_their_own_links_and_the_later_stuck_fault_wins():
    comps = {"bellow": Bellow(p0_Pa=4.0e5), "supply": Supply(p_Pa=9.0e5), "lv": LevellingValve("bellow")}
    faults = [Fault("burst", "bellow", 1.0, area_m2=1e-4), Fault("burst", "bellow", 2.0, area_m2=1e-4),
              Fault("stuck_closed", "lv", 2.0), Fault("stuck_at", "lv", 1.0, lever_m=0.02)]
    circuit = Circuit(comps, faults=faults)
    assert circuit.link_names == ["bellow.burst[0]", "bellow.burst[1]", "lv.supply", "lv.exhaust"]
    both = circuit.with_active_faults([0, 1, 2, 3])           # stuck at 1 s, closed at 2 s: closed
    x0 = both.initial_state()
    assert both.valve_air_kg(run_rk4(both, x0, 0.0, t_end_s=0.1)).supply[0] == 0.0
    at = circuit.with_active_faults([3])
    assert at.valve_air_kg(run_rk4(at, x0, 0.0, t_end_s=0.1)).supply[0] > 0.0


@pytest.mark.parametrize("dp, q, flow_at_1bar", [
    ((1.0e5, 2.0e5), (0.01, 0.02), 0.01),                   # open from its first point: unchanged
    ((0.0, 1.0e5), (0.0, 0.0), 0.0),                        # never passes air: unchanged
    ((0.0, 0.5e5, 1.0e5, 2.0e5), (0.0, 0.0, 0.0, 0.02), 0.02),   # dead band to 1 bar removed
])
def test_a_stuck_open_differential_valve_loses_only_its_dead_band(dp, q, flow_at_1bar):
    comps = {"L": Bellow(p0_Pa=5.0e5), "R": Bellow(p0_Pa=4.0e5), "dpv": DifferentialPressureValve("L", "R", dp, q)}
    circuit = Circuit(comps, faults=[Fault("stuck_open", "dpv")]).with_active_faults([0])
    flow = circuit.outputs(circuit.initial_state(), np.zeros(2)).link_flow_kg_per_s[0]
    assert flow == pytest.approx(flow_at_1bar, rel=1e-12)


def test_the_balance_of_a_finite_supply_that_bursts():
    """A finite main reservoir is a chamber: what it delivers moves within the circuit; its own
    burst vents even with the supply lost (a lost supply isolates its links, not its hole)."""
    comps = {"bellow": Bellow(p0_Pa=4.0e5), "supply": Supply(p_Pa=9.0e5, V_m3=0.1), "lv": LevellingValve("bellow")}
    faults = [Fault("burst", "supply", area_m2=1e-5), Fault("supply_lost", "supply")]
    circuit = Circuit(comps, k_W_per_K=math.inf, faults=faults).with_active_faults([0, 1])
    x0 = circuit.initial_state()
    x = run_rk4(circuit, x0, 0.03, t_end_s=1.0)
    lost = circuit.air_lost_kg(x)
    assert lost > 0.0 and circuit.valve_air_kg(x).supply[0] == 0.0
    assert circuit.total_mass_kg(x) - circuit.total_mass_kg(x0) == pytest.approx(circuit.net_inflow_kg(x), abs=1e-13)
    assert circuit.net_inflow_kg(x) == pytest.approx(-lost, rel=1e-12)
