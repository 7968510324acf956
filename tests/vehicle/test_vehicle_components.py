"""Tests of the optional secondary components of the metro car (vehicle/suspension.py force laws,
their realisation in vehicle/car/, the typical set in vehicle/params.py): anti-roll bar,
secondary dampers (Maxwell elements, bilinear), traction rod, emergency spring and vertical
bumpstop.

Where the pneumatic suspension is needed it is held to a fixed linear law F = F0 + k_b z
(dF/dz = k_b = 243 kN/m per bellow: paper Table 2, adiabatic bellow + tank), set once through
``set_bellow_forces``: without a time rate the law holds exactly for the whole run.

Static results are read after a slow load ramp with generous dampers (they change nothing
static: a damper, or a Maxwell element, carries no force at rest; measured residual motion
< 1e-8 rad over the last second).
"""
import dataclasses
import math

import exudyn
import numpy as np
import pytest
from hand_models import roll_hand_calculation

from vehicle.car import SYMBOLIC_OPS, MetroCar
from vehicle.params import VehicleParams, metro_car_arb_dampers
from vehicle.suspension import (
    FLOAT_OPS,
    airspring_series_bellow_crushing,
    airspring_series_force_N,
    arb_roll_stiffness_N_m_per_rad,
    bilinear_damper_force_N,
    bilinear_damper_velocity_m_per_s,
    maxwell_complex_stiffness_N_per_m,
    maxwell_force_N,
    maxwell_step,
    unilateral_stop_force_N,
)

P = VehicleParams()
K_B = 243e3  # paper Table 2, adiabatic bellow + tank [N/m]
MACRO_S = 5e-3
OUT = exudyn.OutputVariableType
esym = exudyn.symbolic


def ramp(t, duration):
    """0 -> 1 half-cosine ramp."""
    return 0.5 * (1.0 - math.cos(math.pi * min(max(t / duration, 0.0), 1.0)))


def held_bellows(car, k_b=K_B):
    """The bellow law F = F0 + k_b z for the whole run (car at static equilibrium, z = 0)."""
    car.set_bellow_forces(car.static_bellow_forces_N(), np.full(4, k_b))


def run_with_load(car, t_end_s, load, record=None):
    """Advance in macro-steps; ``load(t) -> (force, torque)`` on the carbody at each step start."""
    for i in range(int(round((t_end_s - car.t_s) / MACRO_S))):
        force, torque = load(car.t_s)
        car.set_carbody_load(force, torque)
        car.advance(car.t_s + MACRO_S)
        if record is not None:
            record.append(record_state(car))


def record_state(car):
    z = car.mbs.GetObjectOutputBody(car.model.carbody, OUT.Position)[2] - P.carbody_cog_height_m
    return car.t_s, z, car.carbody_roll_rad()


def bogie_roll_rad(car, ib):
    A = np.asarray(car.mbs.GetObjectOutputBody(car.model.bogies[ib], OUT.RotationMatrix)).reshape(3, 3)
    return math.atan2(A[2, 1], A[2, 2])


# ====================================================================== force laws (pure)
def test_bilinear_damper_law():
    c1, c2, vb = 10e3, 3e3, 0.1
    # linear below the blow-off velocity, odd, continuous at it, slope c2 beyond
    assert bilinear_damper_force_N(0.05, c1, c2, vb) == pytest.approx(500.0, rel=1e-15)
    assert bilinear_damper_force_N(-0.05, c1, c2, vb) == pytest.approx(-500.0, rel=1e-15)
    assert bilinear_damper_force_N(0.1, c1, c2, vb) == pytest.approx(1000.0, rel=1e-15)
    assert bilinear_damper_force_N(0.3, c1, c2, vb) == pytest.approx(1000.0 + 3e3 * 0.2, rel=1e-15)
    assert bilinear_damper_force_N(-0.3, c1, c2, vb) == pytest.approx(-1600.0, rel=1e-15)
    assert bilinear_damper_force_N(0.3, c1) == pytest.approx(3000.0, rel=1e-15)  # inf: linear
    for F in (-1600.0, -500.0, 0.0, 700.0, 1000.0, 2500.0):
        v = bilinear_damper_velocity_m_per_s(F, c1, c2, vb)
        assert bilinear_damper_force_N(v, c1, c2, vb) == pytest.approx(F, abs=1e-9)


def test_bumpstop_is_zero_inside_the_clearance_and_linear_beyond():
    c, k = 0.04, 10e6
    for d in (-0.2, -0.01, 0.0, 0.02, 0.04):
        assert unilateral_stop_force_N(d, c, k) == 0.0
    for d in (0.041, 0.05, 0.1):
        assert unilateral_stop_force_N(d, c, k) == pytest.approx(k * (d - c), rel=1e-12)
    # stiffness beyond the clearance: dF/dd = k
    assert (unilateral_stop_force_N(0.06, c, k) - unilateral_stop_force_N(0.05, c, k)) / 0.01 \
        == pytest.approx(k, rel=1e-9)


def test_anti_roll_bar_roll_stiffness_from_the_bar_and_its_geometry():
    # 50 mm steel bar, 1.8 m: k_t = G pi d^4 / (32 L); 0.3 m levers, links 2.0 m apart
    k_t = 80e9 * math.pi * 0.05 ** 4 / 32 / 1.8
    assert k_t == pytest.approx(27.3e3, rel=2e-3)  # the value quoted in params.py
    assert arb_roll_stiffness_N_m_per_rad(k_t, 0.3, 2.0) == pytest.approx(k_t * (2.0 / 0.3) ** 2,
                                                                         rel=1e-15)
    # virtual work: a relative roll phi twists the bar by s phi / l
    phi = 1e-3
    twist = 2.0 * phi / 0.3
    energy = 0.5 * k_t * twist ** 2
    assert arb_roll_stiffness_N_m_per_rad(k_t, 0.3, 2.0) == pytest.approx(2 * energy / phi ** 2,
                                                                         rel=1e-12)
    with pytest.raises(ValueError):
        arb_roll_stiffness_N_m_per_rad(k_t, 0.0, 2.0)


@pytest.mark.parametrize("omega", [0.01, 0.1, 1.0, 10.0, 100.0])
def test_maxwell_element_follows_its_complex_stiffness(omega):
    # Drive the trapezoidal Maxwell element with d = D sin(w t), omega in units of k_s / c
    # (corner frequency), and project the steady force on sin/cos: F / D against
    # K*(w) = k_s i w c / (k_s + i w c). Low frequency: the damper (i w c), high: the spring
    # (k_s). Step w h = 2 pi / 400: the trapezoidal rule's error ~(w h)^2 / 12 = 2e-5
    # (measured 2.1e-5 ... 2e-7 relative); tolerance 1e-4 of |K*|.
    k_s, c = 2e6, 10e3
    w = omega * k_s / c
    D = 1e-3
    # settle 8 periods and 20 relaxation times c / k_s (the damper's mean position creeps back
    # with that time constant, many periods at high frequency), then measure over 4 periods
    n_per_period = 400
    periods = 12 + math.ceil(20 * c / k_s / (2 * math.pi / w))
    h = 2 * math.pi / w / n_per_period
    y = ydot = 0.0
    t = np.arange(1, n_per_period * periods + 1) * h
    F = np.empty_like(t)
    for i, ti in enumerate(t):
        F[i], y, ydot = maxwell_step(D * math.sin(w * ti), y, ydot, h, k_s, c)
    last = slice(-n_per_period * 4, None)  # 4 whole periods
    s, co = np.sin(w * t[last]), np.cos(w * t[last])
    K = complex(2 * np.mean(F[last] * s), 2 * np.mean(F[last] * co)) / D  # F = Re(K* D e^{iwt})
    K_exact = maxwell_complex_stiffness_N_per_m(w, k_s, c)
    assert abs(K - K_exact) < 1e-4 * abs(K_exact)
    # a hundredth of the corner frequency: the damper, to 1 % (the deviation is the frequency
    # ratio, w c / k_s); a hundred times it: the series spring, to 1 % (k_s / (w c))
    if omega <= 0.01:
        assert abs(K / (1j * w * c) - 1) < 1.01 * omega
    if omega >= 100.0:
        assert abs(K / k_s - 1) < 1.01 / omega


def test_maxwell_element_blows_off():
    # Slow ramp of the deflection at 0.5 m/s: the spring force settles where the damper's
    # bilinear law gives 0.5 m/s: c1 v_b + c2 (0.5 - v_b); the damper then moves at 0.5 m/s.
    k_s, c1, c2, vb, v = 2e6, 10e3, 3e3, 0.1, 0.5
    y = ydot = 0.0
    h = 1e-4
    for i in range(1, 2001):
        F, y, ydot = maxwell_step(v * i * h, y, ydot, h, k_s, c1, c2, vb)
    assert F == pytest.approx(c1 * vb + c2 * (v - vb), rel=1e-9)
    assert ydot == pytest.approx(v, rel=1e-9)


def test_airspring_in_series_solves_both_springs():
    Fs, ke, kst, c = 41.7e3, 2e6, 10e6, 0.04
    for z, A, K in ((0.01, Fs, K_B), (-0.02, Fs + 1e3, K_B), (0.08, Fs, K_B), (0.06, 0.0, 0.0),
                    (0.03, 0.0, 0.0)):
        F, zb, _ = airspring_series_bellow_crushing(z, 0.0, A, K, 0.0, Fs, ke, kst, c)
        # the emergency spring takes the same force, the bellow and its stop share it
        assert zb + (F - Fs) / ke == pytest.approx(z, abs=1e-15)
        assert A + K * zb + unilateral_stop_force_N(zb, c, kst) == pytest.approx(F, rel=1e-12,
                                                                                  abs=1e-9)
    # at static equilibrium nothing moves
    assert airspring_series_force_N(0.0, Fs, K_B, Fs, ke, kst, c) == pytest.approx(Fs, rel=1e-15)
    # the rate: z_b' = (k_e z' - F_b') / (k_e + K) (stop free), by finite differences
    dz, rate = 1e-7, 0.02
    _, zb0, zb_rate = airspring_series_bellow_crushing(0.01, rate, Fs, K_B, 0.0, Fs, ke, kst, c)
    _, zb1, _ = airspring_series_bellow_crushing(0.01 + dz, rate, Fs, K_B, 0.0, Fs, ke, kst, c)
    assert zb_rate == pytest.approx((zb1 - zb0) / dz * rate, rel=1e-6)


def test_symbolic_laws_equal_the_float_laws():
    # the same law code builds the connectors' symbolic (C++) user functions: every branch
    # must give the float result
    x = esym.Real("x", 0.0)
    state = {SYMBOLIC_OPS: (esym.Real("y", 1e-4), esym.Real("yd", 0.02), esym.Real("h", 5e-3)),
             FLOAT_OPS: (1e-4, 0.02, 5e-3)}
    laws = [
        (lambda o, v: bilinear_damper_force_N(v, 10e3, 3e3, 0.1, o), (-0.4, -0.05, 0.0, 0.07, 0.3)),
        (lambda o, v: maxwell_force_N(v, *state[o], 2e6, 10e3, 3e3, 0.1, o),
         (-2e-3, -1e-4, 0.0, 2e-4, 1e-3)),
        (lambda o, v: unilateral_stop_force_N(v, 0.04, 1e7, o), (-0.1, 0.0, 0.039, 0.041, 0.2)),
        (lambda o, v: airspring_series_force_N(v, 41e3, K_B, 41.7e3, 2e6, 1e7, 0.04, o),
         (-0.05, 0.0, 0.03, 0.045, 0.1)),
        (lambda o, v: airspring_series_force_N(v, 0.0, 0.0, 41.7e3, 2e6, 1e7, 0.04, o),
         (0.0, 0.04, 0.05)),
    ]
    for law, values in laws:
        expression = law(SYMBOLIC_OPS, x)
        for v in values:
            x.SetValue(v)
            assert expression.Evaluate() == pytest.approx(law(FLOAT_OPS, v), rel=1e-12, abs=1e-9)


# ====================================================================== parameters
def test_components_are_off_by_default():
    # the paper's car: nothing built, the same model as before these components existed
    car = MetroCar(P)
    optional = car.model.optional
    assert optional.anti_roll_bars == [] and optional.traction_rods == [] and optional.dampers == []
    assert not car.airspring_in_series
    assert car.damper_forces_N() == {} and car.anti_roll_bar_moments_N_m().size == 0
    assert np.array_equal(car.airspring_crushing_m(), car.bellow_crushing()[0])


def test_typical_metro_car_set():
    p = metro_car_arb_dampers()
    assert p.carbody_mass_kg == P.carbody_mass_kg  # the paper's car underneath
    assert p.arb_roll_stiffness_N_m_per_rad == 1.0e6
    assert p.yaw_damping_N_s_per_m == 0.0  # metro cars: no yaw dampers
    car = MetroCar(p)
    assert len(car.model.optional.anti_roll_bars) == 2 and len(car.model.optional.traction_rods) == 2
    assert sorted(car.damper_forces_N()) == sorted(
        ["vertical_FL", "vertical_FR", "vertical_RL", "vertical_RR", "lateral_F", "lateral_R"])
    assert car.airspring_in_series
    # the yaw dampers, when given, are built too (longitudinal, two per bogie)
    car = MetroCar(dataclasses.replace(p, yaw_damping_N_s_per_m=300e3,
                                       yaw_damper_series_stiffness_N_per_m=8e6,
                                       yaw_damper_blowoff_velocity_m_per_s=0.02,
                                       yaw_damper_blowoff_damping_N_s_per_m=20e3))
    assert {"yaw_FL", "yaw_FR", "yaw_RL", "yaw_RR"} <= set(car.damper_forces_N())


@pytest.mark.parametrize("change", [
    dict(arb_roll_stiffness_N_m_per_rad=1e6, arb_torsion_stiffness_N_m_per_rad=3e4,
         arb_lever_arm_m=0.3, arb_link_spacing_m=2.0),  # both forms
    dict(arb_torsion_stiffness_N_m_per_rad=3e4),  # no geometry
    dict(secondary_lateral_damping_N_s_per_m=-1.0),
    dict(secondary_vertical_damper_series_stiffness_N_per_m=0.0),
    dict(yaw_damper_blowoff_velocity_m_per_s=0.0),
    dict(emergency_spring_stiffness_N_per_m=-1e6),
    dict(traction_rod_stiffness_N_per_m=math.nan),
])
def test_inconsistent_component_parameters_are_refused(change):
    with pytest.raises(ValueError):
        MetroCar(dataclasses.replace(P, **change))


# ====================================================================== anti-roll bar
@pytest.mark.parametrize("k_arb", [1.0e6, 0.0], ids=["with anti-roll bar", "bellows only"])
def test_static_roll_stiffness_matches_the_hand_calculation(k_arb):
    # Roll moment M = 20 kN m on the carbody (ramped over 3 s, read at 12 s), bellows held at
    # 243 kN/m. Measured: 0.011166 rad against 0.011097 by hand with the bar (+0.6 %), i.e. a
    # static roll stiffness of 1.791 MN m/rad against 1.802 (the suspension alone, without
    # gravity's terms: 1.922); without the bar 0.027991 against 0.027835 rad (+0.6 %; 0.715
    # against 0.719 MN m/rad). What the hand calculation leaves out is second-order geometry
    # (tilt of the intrinsic connectors' mid-frames), as in the curve test. Tolerance 2 %.
    M = 20e3
    p = dataclasses.replace(P, arb_roll_stiffness_N_m_per_rad=k_arb,
                            secondary_vertical_damping_N_s_per_m=30e3,
                            secondary_lateral_damping_N_s_per_m=60e3)
    car = MetroCar(p, carbody_load=True)
    held_bellows(car)
    rec = []
    run_with_load(car, 12.0, lambda t: ((0, 0, 0), (M * ramp(t, 3.0), 0, 0)), rec)
    roll = np.array([r[2] for r in rec])
    assert np.ptp(roll[-200:]) < 1e-4 * abs(roll[-1])  # at rest (measured < 3e-6 relative)
    hand = roll_hand_calculation(p, K_B, k_arb, M / 2)
    assert roll[-1] == pytest.approx(hand["phi_c"], rel=0.02)
    stiffness = M / roll[-1]  # the car's static roll stiffness [N m/rad]
    assert stiffness == pytest.approx(M / hand["phi_c"], rel=0.02)
    # the bar's moment is its stiffness times the relative roll, on each bogie (a pure couple
    # in the mid-frame: measured equal to 1e-12)
    if k_arb:
        moments = car.anti_roll_bar_moments_N_m()
        for ib in range(2):
            relative = roll[-1] - bogie_roll_rad(car, ib)
            assert moments[ib] == pytest.approx(-k_arb * relative, rel=1e-6)
    # the dampers carry no static force (measured < 0.002 N)
    assert max(abs(f) for f in car.damper_forces_N().values()) < 1.0


def test_anti_roll_bar_by_geometry_equals_its_equivalent_roll_stiffness():
    # the same car, the bar given by torsion stiffness, lever and link spacing: the same roll
    k_t, lever, spacing = 22.5e3, 0.3, 2.0
    k_roll = k_t * (spacing / lever) ** 2  # 1.0 MN m/rad
    rolls = []
    for change in (dict(arb_roll_stiffness_N_m_per_rad=k_roll),
                   dict(arb_torsion_stiffness_N_m_per_rad=k_t, arb_lever_arm_m=lever,
                        arb_link_spacing_m=spacing)):
        car = MetroCar(dataclasses.replace(P, **change), carbody_load=True)
        held_bellows(car)
        run_with_load(car, 0.5, lambda t: ((0, 0, 0), (20e3 * ramp(t, 0.5), 0, 0)))
        rolls.append(car.carbody_roll_rad())
    assert rolls[0] == pytest.approx(rolls[1], rel=1e-9)


# ====================================================================== dampers
def free_bounce(p, t_end_s=5.0):
    """Carbody bounce after a 0.3 s half-sine vertical force pulse (5 kN peak): (t, z)."""
    car = MetroCar(p, carbody_load=True)
    held_bellows(car)
    rec = []

    def pulse(t):
        return (0, 0, -5e3 * math.sin(math.pi * t / 0.3) if t < 0.3 else 0.0), (0, 0, 0)

    run_with_load(car, t_end_s, pulse, rec)
    t, z, _ = np.array(rec).T
    return t, z


def decrement_and_period(t, z, t_start=0.6, cycles=3):
    """Mean logarithmic decrement and period of the positive peaks of z after t_start."""
    m = t >= t_start
    t, z = t[m], z[m]
    i = [k for k in range(1, len(z) - 1) if z[k] > 0 and z[k] > z[k - 1] and z[k] >= z[k + 1]]
    peaks, times = z[i][:cycles + 1], t[i][:cycles + 1]
    assert len(peaks) == cycles + 1
    return float(np.mean(np.log(peaks[:-1] / peaks[1:]))), float(np.mean(np.diff(times)))


def single_dof_bounce(p, c, k_s, k_b=K_B):
    """Damping ratio and damped period [s] of the carbody bounce by a single-dof estimate.

    Carbody mass m on the secondary (4 bellows k_b) in series with the primary (8 axleboxes),
    the bogies' mass neglected: k = 2 (2 k_b)(4 k_z) / (2 k_b + 4 k_z). The four vertical
    dampers act across the secondary, which takes the share r = 4 k_z / (2 k_b + 4 k_z) of the
    carbody's motion: each adds r^2 K*(w) (its complex stiffness, Maxwell element) to the
    single dof's dynamic stiffness: k_eff = k + 4 r^2 Re K*, c_eff = 4 r^2 Im K* / w.
    zeta = c_eff / (2 sqrt(k_eff m)), w = sqrt(k_eff / m) sqrt(1 - zeta^2), iterated on w.
    """
    m = p.carbody_mass_kg
    ksec, kp = 2 * k_b, 4 * p.primary_stiffness_z_N_per_m
    k, r = 2 * ksec * kp / (ksec + kp), kp / (ksec + kp)
    w = math.sqrt(k / m)
    for _ in range(100):
        K = maxwell_complex_stiffness_N_per_m(w, k_s, c) if math.isfinite(k_s) else 1j * w * c
        k_eff = k + 4 * r * r * K.real
        zeta = 4 * r * r * K.imag / w / (2 * math.sqrt(k_eff * m))
        w = math.sqrt(k_eff / m) * math.sqrt(1 - zeta ** 2)
    return zeta, 2 * math.pi / w


def log_decrement(zeta):
    return 2 * math.pi * zeta / math.sqrt(1 - zeta ** 2)


@pytest.fixture(scope="module")
def bounce_without_dampers():
    return decrement_and_period(*free_bounce(P))


@pytest.mark.parametrize("c, k_s", [(10e3, 2e6), (10e3, 70e3), (20e3, math.inf)],
                         ids=["Maxwell 2 MN/m", "Maxwell soft (w c / k_s ~ 1)", "rigid mounting"])
def test_vertical_dampers_raise_the_bounce_decrement_as_their_damping_ratio_predicts(
        c, k_s, bounce_without_dampers):
    # Measured increase of the decrement against the single-dof estimate: 0.761 / 0.766
    # (2 MN/m, zeta 0.121), 0.338 / 0.341 (soft: the series spring halves the damping and
    # stiffens the mode, period 0.903 -> 0.852 s, predicted 0.850), 1.575 / 1.576 (rigid,
    # 20 kN s/m, zeta 0.243; period 0.913 s, predicted 0.930). Without dampers 0.0113 (primary
    # dampers only). Tolerance 10 % on the increase, 3 % on the period (the estimate neglects
    # the bogie masses).
    delta0, _ = bounce_without_dampers
    p = dataclasses.replace(P, secondary_vertical_damping_N_s_per_m=c,
                            secondary_vertical_damper_series_stiffness_N_per_m=k_s)
    delta, period = decrement_and_period(*free_bounce(p))
    zeta, period_hand = single_dof_bounce(p, c, k_s)
    zeta0 = delta0 / math.hypot(2 * math.pi, delta0)  # inverse of log_decrement
    predicted = log_decrement(zeta0 + zeta) - delta0
    assert delta - delta0 == pytest.approx(predicted, rel=0.10)
    assert period == pytest.approx(period_hand, rel=0.03)


#: period of the carbody's lower sway mode on 243 kN/m bellows [s] (measured: 1.73-1.75 s)
SWAY_PERIOD_S = 1.75


def resonant_sway(p, cycles_driven=10, cycles_free=5, force_N=250.0):
    """The carbody's lower sway mode, excited alone: a lateral force at the carbody's centre of
    gravity at the mode's frequency for ``cycles_driven`` periods (the resonance builds up that
    mode, ~20 mm, inside the 40 mm lateral bumpstop clearance), then free. Per macro-step: (t,
    carbody y, kinetic energy of carbody and bogie frames, front and rear lateral damper forces),
    and the release time."""
    car = MetroCar(p, carbody_load=True)
    held_bellows(car)
    bodies = [(car.model.carbody, p.carbody_mass_kg, (p.carbody_inertia_xx_kg_m2, p.carbody_inertia_yy_kg_m2,
                                                 p.carbody_inertia_zz_kg_m2))]
    bodies += [(b, p.bogie_mass_kg, (p.bogie_inertia_xx_kg_m2, p.bogie_inertia_yy_kg_m2, p.bogie_inertia_zz_kg_m2))
               for b in car.model.bogies]
    release = cycles_driven * SWAY_PERIOD_S
    rec = []
    for _ in range(int(round((release + cycles_free * SWAY_PERIOD_S) / MACRO_S))):
        t = car.t_s
        force = force_N * math.sin(2 * math.pi * t / SWAY_PERIOD_S) if t < release else 0.0
        car.set_carbody_load((0.0, force, 0.0), (0.0, 0.0, 0.0))
        car.advance(car.t_s + MACRO_S)
        T = 0.0
        for body, m, inertia in bodies:
            v = np.asarray(car.mbs.GetObjectOutputBody(body, OUT.Velocity))
            w = np.asarray(car.mbs.GetObjectOutputBody(body, OUT.AngularVelocity))
            T += 0.5 * m * (v @ v) + 0.5 * sum(i * x * x for i, x in zip(inertia, w))
        forces = car.damper_forces_N()
        rec.append((car.t_s, car.mbs.GetObjectOutputBody(car.model.carbody, OUT.Position)[1], T,
                    forces.get("lateral_F", 0.0), forces.get("lateral_R", 0.0)))
    return np.array(rec).T, release


def positive_peaks(t, y, t_start, n=5):
    m = t >= t_start
    t, y = t[m], y[m]
    i = [k for k in range(1, len(y) - 1) if y[k] > 0 and y[k] > y[k - 1] and y[k] >= y[k + 1]][:n]
    assert len(i) == n
    return t[i], y[i]


@pytest.mark.slow
@pytest.mark.parametrize("c", [2e3, 5e3, 20e3])
def test_lateral_dampers_raise_the_sway_decrement_as_their_damping_ratio_predicts(c):
    # The lower sway mode couples lateral motion and roll: no single-dof formula. The prediction
    # comes from the undamped mode itself (energy method): with lateral dampers of 1 N s/m the
    # free sway's damper velocities v_d and kinetic energy T are recorded over one cycle; dampers
    # c then dissipate E = c * (integral of the sum of v_d^2) per cycle, which adds the damping
    # ratio zeta = E / (4 pi T_max) (first order in the damping: the mode shape unchanged).
    # Measured increase of the log decrement against the prediction: 0.0422 / 0.0413 (2 kN s/m),
    # 0.1039 / 0.1034 (5), 0.401 / 0.414 (20); without them 0.0065 (primary damping). Tolerance
    # 10 %, as for the bounce: first order in the damping, and the undamped decay's slight
    # beating with the other modes.
    c_probe = 1.0
    (t, y, T, f_front, f_rear), release = resonant_sway(dataclasses.replace(P, secondary_lateral_damping_N_s_per_m=c_probe))
    peaks_t, peaks_y = positive_peaks(t, y, release)
    assert np.diff(peaks_t).mean() == pytest.approx(SWAY_PERIOD_S, rel=0.02)   # driven at its resonance
    delta0 = float(np.mean(np.log(peaks_y[:-1] / peaks_y[1:])))
    cycle = (t >= peaks_t[0]) & (t < peaks_t[1])
    dissipated_per_c = np.trapezoid((f_front[cycle] / c_probe) ** 2 + (f_rear[cycle] / c_probe) ** 2, t[cycle])
    zeta_added = c * dissipated_per_c / (4 * math.pi * T[cycle].max())
    (t, y, *_), release = resonant_sway(dataclasses.replace(P, secondary_lateral_damping_N_s_per_m=c))
    _, damped_y = positive_peaks(t, y, release)
    delta = float(np.mean(np.log(damped_y[:-1] / damped_y[1:])))
    zeta0 = delta0 / math.hypot(2 * math.pi, delta0)
    predicted = log_decrement(zeta0 + zeta_added) - delta0
    assert delta - delta0 == pytest.approx(predicted, rel=0.10)


def test_macro_steps_continue_the_maxwell_states_exactly():
    # The Maxwell states are committed once per accepted step (PostStep), also across
    # advance() calls (exudyn calls PostStep again at the start of each SolveSteps: it must do
    # nothing then). One advance over 0.5 s and 100 of 5 ms: the same steps, the same result
    # to Newton tolerance (measured ~1e-12 relative).
    def rail(t):
        z = np.zeros(8)
        z[1] = z[3] = 0.004 * ramp(t, 0.4)
        return z

    p = metro_car_arb_dampers()
    one = MetroCar(p, rail_height_m=rail)
    held_bellows(one)
    one.advance(0.5)
    many = MetroCar(p, rail_height_m=rail)
    held_bellows(many)
    for i in range(100):
        many.advance((i + 1) * MACRO_S)
    assert np.allclose(one.wheel_loads_N(), many.wheel_loads_N(), rtol=0, atol=1e-5)
    f1, f2 = one.damper_forces_N(), many.damper_forces_N()
    assert max(abs(f1[k]) for k in f1) > 10.0  # not vacuous: the dampers work during the ramp
    assert all(f1[k] == pytest.approx(f2[k], rel=1e-6, abs=1e-6) for k in f1)


# ====================================================================== traction rod
def test_traction_rods_carry_the_longitudinal_force():
    # 20 kN along x on the carbody, applied at the rods' height (force at the CoG plus the
    # couple (h_rod - h_cog) e_z x F e_x) so that it does not pitch the carbody. Each rod and the
    # two bellows' shear of its bogie share F/2 in proportion to their stiffness:
    # k_rod / (k_rod + 2 k_shear) = 97.7 % on the rods. Measured 9813 N against 9766 N per rod
    # (+0.5 %: the bellows' shear acts 0.43 m above the rods and the carbody's small pitch
    # shifts the share). Tolerance 2 %.
    p = dataclasses.replace(P, traction_rod_stiffness_N_per_m=10e6,
                            traction_rod_damping_N_s_per_m=30e3,
                            secondary_vertical_damping_N_s_per_m=30e3)
    car = MetroCar(p, carbody_load=True)
    held_bellows(car)
    F, h = 20e3, p.traction_rod_height_m - p.carbody_cog_height_m
    run_with_load(car, 4.0, lambda t: ((F * ramp(t, 1.0), 0, 0), (0, F * h * ramp(t, 1.0), 0)))
    rods = car.traction_rod_forces_N()
    share = p.traction_rod_stiffness_N_per_m / (p.traction_rod_stiffness_N_per_m
                                                + 2 * p.bellow_shear_stiffness_N_per_m)
    assert np.allclose(rods, -F / 2 * share, rtol=0.02)  # on the carbody: against the load
    shear = [car.mbs.GetObjectOutput(co, OUT.ForceLocal)[0] for co in car.model.airsprings.connectors]
    assert -rods.sum() + sum(shear) == pytest.approx(F, rel=0.01)  # the whole load is carried


# ====================================================================== emergency spring, bumpstop
def emergency_car(**change):
    p = dataclasses.replace(P, emergency_spring_stiffness_N_per_m=2e6,
                            vertical_bumpstop_stiffness_N_per_m=10e6,
                            vertical_bumpstop_clearance_m=0.04,
                            secondary_vertical_damping_N_s_per_m=30e3,
                            secondary_lateral_damping_N_s_per_m=60e3, **change)
    return p, MetroCar(p, carbody_load=True)


def test_emergency_spring_acts_in_series_with_the_inflated_bellow():
    # 8 kN more on the carbody: each airspring takes 2 kN; the bellow crushes by 2 kN / k_b
    # (its own law, the quantity the pneumatics see), the whole airspring by
    # 2 kN (1/k_b + 1/k_e). Static, exact but for the settling (measured 1e-6 relative).
    p, car = emergency_car()
    held_bellows(car)
    dF = 8e3
    run_with_load(car, 5.0, lambda t: ((0, 0, -dF * ramp(t, 2.0)), (0, 0, 0)))
    z_bellow, _ = car.bellow_crushing()
    z_total = car.airspring_crushing_m()
    assert np.allclose(z_bellow, dF / 4 / K_B, rtol=1e-3)
    assert np.allclose(z_total, dF / 4 * (1 / K_B + 1 / p.emergency_spring_stiffness_N_per_m),
                       rtol=1e-3)
    # the bellow force law is kept: F = F0 + k_b z_bellow
    force_on_bogie = np.array([car.mbs.GetObjectOutput(co, OUT.ForceLocal)[2]
                               for co in car.model.airsprings.connectors])
    assert np.allclose(-force_on_bogie, car.static_bellow_forces_N() + K_B * z_bellow, rtol=1e-9)


def test_deflated_bellows_land_on_the_bumpstops_and_the_emergency_springs():
    # All four bellows deflate (force law ramped to zero over 2 s through dF/dt, then F = 0):
    # the carbody sinks until the stops carry its weight: bellow crushing
    # clearance + F_static / k_stop = 40 mm + 4.2 mm; the emergency springs carry the same
    # load as before, so the whole airspring crushes by the same amount. Inside the clearance the
    # stop carried nothing (the inflated car stood at z = 0).
    p, car = emergency_car()
    F0 = car.static_bellow_forces_N()
    car.set_bellow_forces(F0, None, -F0 / 2.0)
    car.advance(2.0)
    z_b, _ = car.bellow_crushing()
    assert np.all(z_b > p.vertical_bumpstop_clearance_m)  # already on the stops
    car.set_bellow_forces(np.zeros(4))
    run_with_load(car, 10.0, lambda t: ((0, 0, 0), (0, 0, 0)))
    # a carbody-against-bogies bounce on the stiff stops, damped mostly by the primary dampers,
    # is still decaying: measured amplitude 2e-4 relative at 10 s; tolerance 1e-3
    z_b, zdot = car.bellow_crushing()
    expected = p.vertical_bumpstop_clearance_m + F0 / p.vertical_bumpstop_stiffness_N_per_m
    assert np.allclose(z_b, expected, rtol=1e-3)
    assert np.allclose(car.airspring_crushing_m(), expected, rtol=1e-3)
    assert np.all(np.abs(zdot) < 1e-4)
    assert car.carbody_roll_rad() == pytest.approx(0.0, abs=1e-9)  # the car stays level
