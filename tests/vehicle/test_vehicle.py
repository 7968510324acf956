"""Tests of the exudyn metro-car model (vehicle/car/) and its parameters.

Where a test needs the pneumatic suspension, it is emulated here by a stiff bellow linearised
about the static state, F = F0 + k z with dF/dz = k (k = 243 kN/m: paper Table 2, bellow + tank,
adiabatic), updated every 5 ms macro-step as the co-simulation master does. With the bellow
forces *held* (dF/dz = 0) the carbody has no vertical or roll stiffness: its sway/roll mode is then
unstable (gravity above the bellows, 17 t x 9.81 x 0.45 m = 75 kN m/rad against no spring), so
only short runs are meaningful with held forces.
"""
import subprocess
import sys
from dataclasses import fields

import exudyn
import numpy as np
import pytest

from vehicle.car import (
    BELLOWS,
    EXUDYN_TESTED_MINOR,
    WHEELS,
    CarOptions,
    MetroCar,
    ModelOptions,
    RunSettings,
    SolverSettings,
)
from vehicle.params import VehicleParams

P = VehicleParams()
WEIGHT_N = (P.carbody_mass_kg + 2 * P.bogie_mass_kg + 4 * P.wheelset_mass_kg) * P.gravity_m_per_s2
K_BELLOW_N_PER_M = 243e3  # paper Table 2, adiabatic bellow + tank quasi-static stiffness
MACRO_S = 5e-3


def index(name, names=WHEELS):
    return names.index(name)


def emulate_pneumatics(car, t_end_s, k=K_BELLOW_N_PER_M, record=None):
    """Advance ``car`` to ``t_end_s`` in macro-steps with linearised stiff bellows."""
    F0 = car.static_bellow_forces_N()
    K = np.full(4, k)
    t_start, n = car.t_s, int(round((t_end_s - car.t_s) / MACRO_S))
    for i in range(n):
        z, _ = car.bellow_crushing()
        car.set_bellow_forces(F0 + K * z, K)
        car.advance(t_start + (i + 1) * MACRO_S)
        if record is not None:
            record.append((car.t_s, car.wheel_loads_N(), car.bellow_crushing()[0]))


def smooth_ramp(t, duration):
    """0 -> 1 half-cosine ramp (continuous rate: no shock on the 250 Hz contact modes)."""
    return 0.5 * (1.0 - np.cos(np.pi * min(max(t / duration, 0.0), 1.0)))


def raise_front_right(amount_m, duration_s):
    def rail(t):
        z = np.zeros(8)
        z[index("1R")] = z[index("2R")] = amount_m * smooth_ramp(t, duration_s)
        return z
    return rail


# ---------------------------------------------------------------- environment and parameters
def test_exudyn_version_is_the_tested_minor():
    # The exudyn API changes between minor versions (renamed settings/arguments, symbolic user
    # functions): anything but 1.13.x must fail here, loudly, before subtler failures elsewhere.
    assert exudyn.__version__.startswith(EXUDYN_TESTED_MINOR + "."), (
        f"vehicle/ was written and measured against exudyn {EXUDYN_TESTED_MINOR}.x; "
        f"installed: {exudyn.__version__}")


def test_vehicle_does_not_import_pneumatics_or_cosim():
    # design rule: only cosim knows both sides (fresh interpreter: nothing else imported)
    code = ("import sys, vehicle.car, vehicle.params; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('pneumatics', 'cosim')]; "
            "assert not bad, bad")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_params_fields_are_plain_numbers_with_units():
    for f in fields(VehicleParams):
        assert f.type in (float, int), f.name  # real classes, not string annotations
        assert f.name.endswith(("_kg", "_m", "_kg_m2", "_N_per_m", "_N_s_per_m", "_m_per_s2",
                                "_N_per_m1_5", "_N_m_per_rad", "_m_per_s")), f.name


# ---------------------------------------------------------------- static equilibrium
def test_static_equilibrium_on_level_track():
    car = MetroCar(P)
    Q = car.wheel_loads_N()
    # Sum of wheel loads = total weight: the analytic reference configuration is exact up to
    # round-off (~1e-13 measured); 1e-6 relative is the required bound.
    assert Q.sum() == pytest.approx(WEIGHT_N, rel=1e-6)
    # Symmetric car on level track: every wheel carries the same load (round-off only).
    assert np.allclose(Q, car.Q_static_N, rtol=1e-9, atol=0.0)
    assert np.allclose(Q[0::2], Q[1::2], rtol=1e-12, atol=0.0)  # left == right
    # Hertz law at the static load
    delta = (car.Q_static_N / P.hertz_constant_N_per_m1_5) ** (2 / 3)
    assert P.hertz_constant_N_per_m1_5 * delta ** 1.5 == pytest.approx(car.Q_static_N, rel=1e-12)
    z, zdot = car.bellow_crushing()
    assert np.all(np.abs(z) < 1e-12) and np.all(np.abs(zdot) < 1e-12)
    assert car.static_bellow_forces_N().sum() == pytest.approx(
        P.carbody_mass_kg * P.gravity_m_per_s2, rel=1e-12)
    assert car.carbody_roll_rad() == 0.0


def test_car_stays_still_with_static_bellow_forces():
    car = MetroCar(P)
    Q0 = car.wheel_loads_N()
    for i in range(600):  # 3 s in 5 ms macro-steps
        car.set_bellow_forces(car.static_bellow_forces_N())
        car.advance((i + 1) * MACRO_S)
    assert car.t_s == pytest.approx(3.0, abs=1e-12)
    # No settling transient and no drift: displacements stay at round-off (~1e-16 m measured).
    # 1e-9 m is far below anything physical (contact deflection 4e-5 m, primary 3.7e-2 m).
    q = car.mbs.systemData.GetODE2Coordinates()
    assert np.max(np.abs(q)) < 1e-9
    assert np.max(np.abs(car.wheel_loads_N() / Q0 - 1.0)) < 1e-9
    z, zdot = car.bellow_crushing()
    assert np.max(np.abs(z)) < 1e-9 and np.max(np.abs(zdot)) < 1e-9


# ---------------------------------------------------------------- interface semantics
def test_bellow_force_pair_lifts_the_carbody():
    # +dF on all four bellows, held: only the carbody feels it vertically (the shear springs
    # have no vertical stiffness) -> uniform acceleration a = 4 dF / m_c. The velocity gain
    # between two instants after the jump is a dt exactly (1e-9 relative measured; 1e-6
    # allows for Newton tolerance). The displacement is not used: a force jump at a macro-step
    # boundary enters generalized-alpha with ~half a step of delay (start acceleration is the
    # old one), i.e. z = a (t - h/2)^2 / 2, not a t^2 / 2.
    car = MetroCar(P)
    dF = 1000.0
    car.set_bellow_forces(car.static_bellow_forces_N() + dF)
    velocity = exudyn.OutputVariableType.Velocity
    car.advance(0.1)
    v1 = car.mbs.GetObjectOutputBody(car.model.carbody, velocity)[2]
    car.advance(0.2)
    v2 = car.mbs.GetObjectOutputBody(car.model.carbody, velocity)[2]
    assert (v2 - v1) / 0.1 == pytest.approx(4 * dF / P.carbody_mass_kg, rel=1e-6)
    # the force pair pushes the bogies down: the bellows extend (z < 0) by more than the
    # carbody alone rises
    z_cb = car.mbs.GetObjectOutputBody(car.model.carbody, exudyn.OutputVariableType.Displacement)[2]
    z, _ = car.bellow_crushing()
    assert z_cb > 0 and np.all(z < -z_cb)


def test_force_law_is_linearised_about_the_crushing_and_time_at_call():
    car = MetroCar(P, rail_height_m=raise_front_right(0.004, 0.3))
    car.advance(0.1)
    z_call, _ = car.bellow_crushing()
    F = np.array([40e3, 41e3, 42e3, 43e3])
    k = np.array([1e5, 2e5, 3e5, 4e5])
    Fdot = np.array([-2e3, 1e3, 5e2, 3e3])
    car.set_bellow_forces(F, k, Fdot)
    car.advance(0.2)
    z, _ = car.bellow_crushing()
    force_on_bogie = np.array([car.mbs.GetObjectOutput(co, exudyn.OutputVariableType.ForceLocal)[2]
                               for co in car.model.airsprings.connectors])
    # connector force f acts as +f on the lower plate (bogie): f_z = -F(t, z) pushes it down,
    # along the bellow axis (z of the connector's mid-frame, in which z is measured too)
    assert np.allclose(-force_on_bogie, F + Fdot * (0.2 - 0.1) + k * (z - z_call), rtol=1e-12, atol=1e-6)
    assert np.max(np.abs(z - z_call)) > 1e-4  # the test is not vacuous


def test_advance_accepts_spans_that_are_not_multiples_of_the_step():
    car = MetroCar(P, step_s=5e-3)
    for t in (0.0123, 0.0131, 0.05, 0.0501):
        car.advance(t)
        assert car.t_s == t
    car.advance(0.0501)  # zero span: no-op
    with pytest.raises(ValueError):
        car.advance(0.04)


def test_macro_steps_continue_the_state_exactly():
    # One advance over 0.5 s and 100 advances of 5 ms take the same internal steps; the solver
    # is continued, not restarted, so both agree to round-off / Newton tolerance (1e-4 N
    # residual on ~1e9 N/m contacts: < 1e-12 m). Loads compared at 1e-6 N.
    rail = raise_front_right(0.003, 0.4)
    one = MetroCar(P, rail_height_m=rail)
    one.advance(0.5)
    many = MetroCar(P, rail_height_m=rail)
    for i in range(100):
        many.advance((i + 1) * MACRO_S)
    assert np.allclose(one.wheel_loads_N(), many.wheel_loads_N(), rtol=0, atol=1e-6)
    assert np.allclose(one.bellow_crushing()[0], many.bellow_crushing()[0], rtol=0, atol=1e-12)


def test_jacobian_reuse_does_not_change_the_solution():
    # Reusing the Newton Jacobian across macro-steps changes only the Newton path: results
    # agree within the Newton tolerance (measured 2e-5 N on loads of 3e4 N, 1e-10 m on z).
    rail = raise_front_right(0.005, 1.0)
    cars = [MetroCar(P, rail_height_m=rail, reuse_jacobian=r) for r in (True, False)]
    for car in cars:
        emulate_pneumatics(car, 1.5)
    assert cars[0].jacobian_count <= 2  # the point of the reuse
    assert np.allclose(cars[0].wheel_loads_N(), cars[1].wheel_loads_N(), rtol=0, atol=1e-2)
    assert np.allclose(cars[0].bellow_crushing()[0], cars[1].bellow_crushing()[0],
                       rtol=0, atol=1e-8)


def test_options_grouped_build_the_car_the_keywords_build():
    """MetroCar(params, options=CarOptions(...)) is MetroCar(params, **keywords), bit for bit
    (rail heights, step and a run setting and a solver setting through each way); a keyword no
    group has, or options given both ways, is a TypeError, as for any function."""
    rail = raise_front_right(0.003, 0.1)
    by_keywords = MetroCar(P, rail, 4e-3, newton_abs_tol=1e-5, carbody_load=True)
    grouped = MetroCar(P, options=CarOptions(model=ModelOptions(carbody_load=True),
                                             run=RunSettings(rail_height_m=rail),
                                             solver=SolverSettings(step_s=4e-3, newton_abs_tol=1e-5)))
    assert by_keywords.options == grouped.options
    for car in (by_keywords, grouped):
        car.set_carbody_load(torque_N_m=(2e4, 0.0, 0.0))
        emulate_pneumatics(car, 0.2)
    assert by_keywords.wheel_loads_N().tobytes() == grouped.wheel_loads_N().tobytes()
    with pytest.raises(TypeError, match="'speed_m_per_sec'"):
        MetroCar(P, speed_m_per_sec=10.0)
    with pytest.raises(TypeError, match="not both"):
        MetroCar(P, step_s=1e-3, options=CarOptions())


def test_rail_height_function_must_return_eight_values():
    with pytest.raises(ValueError):
        MetroCar(P, rail_height_m=lambda t: np.zeros(4))


# ---------------------------------------------------------------- contact
def test_wheel_over_a_far_dropped_rail_lifts_with_zero_load():
    # The rail under 1L drops 0.2 m (far more than the wheel can follow: the primary static
    # deflection is ~37 mm): the wheel lifts and its load is exactly zero (unilateral contact).
    def rail(t):
        z = np.zeros(8)
        z[index("1L")] = -0.2 * smooth_ramp(t, 1.0)
        return z

    car = MetroCar(P, rail_height_m=rail)
    record = []
    emulate_pneumatics(car, 2.0, record=record)
    Q = car.wheel_loads_N()
    assert Q[index("1L")] == 0.0
    assert np.all(Q >= 0.0)
    assert Q[index("1R")] > car.Q_static_N  # wheelset 1 stands on its right wheel
    assert all(np.all(q >= 0.0) for _, q, _ in record)  # the contact never pulls


# ---------------------------------------------------------------- twist
def test_twist_with_stiff_bellows_unloads_the_diagonal():
    # Raise the rails under 1R and 2R by 5 mm, bellows with adiabatic stiffness. Physically
    # certain (paper section 4.1): FR and RL bellows are crushed, FL and RR extended; the
    # front bogie loads its right wheels and unloads its left ones, the rear bogie the other way
    # round (diagonal unloading of 1L/2L and 3R/4R).
    twist = 0.005
    car = MetroCar(P, rail_height_m=raise_front_right(twist, 2.0))
    emulate_pneumatics(car, 3.0)
    Q, Q0 = car.wheel_loads_N(), car.Q_static_N
    z, _ = car.bellow_crushing()
    zb = dict(zip(BELLOWS, z))
    assert zb["FR"] > 0 and zb["RL"] > 0 and zb["FL"] < 0 and zb["RR"] < 0
    for w in ("1R", "2R", "3L", "4L"):
        assert Q[index(w)] > Q0, w
    for w in ("1L", "2L", "3R", "4R"):
        assert Q[index(w)] < Q0, w
    # Order of magnitude: a linear model (rigid carbody and bogie frames, bellow k, primary
    # roll stiffness K = 4 kz b^2 per bogie, b = 1 m) gives a bellow force change
    # f = (k theta / 2) / (1 + 2 k / K), theta = twist / contact spacing, and a wheel load
    # change 2 f b / 2 / contact spacing = 229 N. The vertical bellow forces (42 kN) acting on
    # the tilted bogie and the carbody roll (P-delta) shift the result by tens of percent
    # (measured with moment-balanced force pairs: front +-113..123 N, rear +-249 N), so only
    # the order of magnitude is checked.
    b = P.primary_lateral_spacing_m / 2
    K_roll = 4 * P.primary_stiffness_z_N_per_m * b ** 2
    theta = twist / P.contact_spacing_m
    f = K_BELLOW_N_PER_M * theta / 2 / (1 + 2 * K_BELLOW_N_PER_M / K_roll)
    dQ_linear = f * (P.airspring_lateral_spacing_m / 2) / P.contact_spacing_m
    for w in ("1R", "4L"):
        assert 0.3 * dQ_linear < abs(Q[index(w)] - Q0) < 2.0 * dQ_linear, w
    # left/right of one wheelset change in opposite directions by similar amounts
    assert (Q[index("1R")] - Q0) * (Q[index("1L")] - Q0) < 0
    assert car.carbody_roll_rad() < 0  # carbody follows the raised right side (left side down)


def test_bellow_crushing_follows_the_front_bogie_with_held_forces():
    # Held forces, short run: the front bogie follows its rails (right rails raised by d:
    # heave d/2 and roll d/1.5 m, primary forces unchanged to first order) while the carbody,
    # under constant forces, stays. Lower plates at y = +-1 m therefore move by
    # d (1/2 + 1/1.5) = 1.167 d (FR, compressed) and d (1/2 - 1/1.5) = -0.167 d (FL, extended);
    # the rear bellows barely move. The wheelsets roll about their rail-level point (where the
    # guidance holds them), so the front bogie also shifts laterally by z_w d/1.5 (0.29 d)
    # and the shear springs start the carbody swaying: measured 0.16 d at the rear bellows
    # and 0.15 d added to the front ones 0.7 s in. Tolerance 0.2 d covers that sway and the
    # residual bogie oscillation (8.5 Hz, primary damping only) 0.1 s after the ramp.
    d = 0.002
    car = MetroCar(P, rail_height_m=raise_front_right(d, 0.4))
    car.advance(0.2)
    _, zdot = car.bellow_crushing()
    assert zdot[index("FR", BELLOWS)] > 0 and zdot[index("FL", BELLOWS)] < 0  # mid-ramp
    car.advance(0.5)
    z, _ = car.bellow_crushing()
    expected = np.array([0.5 - 1 / 1.5, 0.5 + 1 / 1.5, 0.0, 0.0]) * d
    assert np.allclose(z, expected, rtol=0, atol=0.2 * d)
