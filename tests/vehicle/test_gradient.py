"""A line's gradient (vehicle/car/gradient.py): every body's weight tilted by the grade. A car
standing on a 4 % gradient against the hand model of tests/vehicle/test_braking.py (the same
equilibrium as a car accelerating at g sin(theta) under a weight of g cos(theta), its springs
preloaded for the level car); the weight turning with the track's heading; a car driven through
its wheels standing and climbing on the gradient."""
from __future__ import annotations

import math

import exudyn as exu
import numpy as np
import pytest
from test_braking import hand_symbols, level_1

from vehicle.car import MetroCar, WheelDrive
from vehicle.params import ContactParams, metro_car_arb_dampers
from vehicle.speed import PhasedSpeedProfile
from vehicle.track import Arc, Straight, TrackGeometry

GRADE = 0.04          #: 4 %: a steep metro gradient (most lines stay below 4-5 %)
H = 0.005


def _run(car, t_end_s: float, every=None):
    F0, k = car.static_bellow_forces_N(), np.full(4, 243e3)
    rows = []
    for n in range(1, int(round(t_end_s / H)) + 1):
        z, _ = car.bellow_crushing()
        car.set_bellow_forces(F0 + k * z, k)
        car.advance(n * H)
        if every is not None:
            rows.append(every(car))
    return rows


def test_a_car_standing_on_a_gradient_is_the_hand_models_equilibrium():
    """Kinematic guidance, linear bellows, 20 s on a 4 % rise (the start at the level car's static
    equilibrium has rung out through the dampers: the 5.5 Hz surge on the traction rods decays
    by e^-34). The wheel loads and the carbody pitch against level_1 of test_braking.py at
    a = g sin(theta) with the weights at g cos(theta): to 1e-6 of the transfer (measured 1.1e-9,
    the solver's tolerance); the load moves to the rear, the lower end."""
    p = metro_car_arb_dampers()
    car = MetroCar(p, grade=lambda s: GRADE)
    _run(car, 20.0)
    Q = car.wheel_loads_N().reshape(4, 2).sum(axis=1)
    pitch = car.mbs.GetObjectOutputBody(car.model.carbody, exu.OutputVariableType.Rotation)[1]
    g, theta = p.gravity_m_per_s2, math.atan(GRADE)
    hand = level_1(p, g * math.sin(theta), weight_g=g * math.cos(theta))
    Q_hand = hand["dQ"] + 2.0 * hand_symbols(p)["Q0"]
    transfer = np.abs(Q_hand - Q_hand.mean()).max()
    assert np.abs(Q - Q_hand).max() < 1e-6 * transfer
    assert pitch == pytest.approx(hand["theta"], rel=1e-6)
    assert Q[3] > Q[0] and pitch < 0.0                      # nose up, the rear loaded
    # the weight the rails carry: (M_tot) g cos(theta), within the solver's tolerance
    total = hand_symbols(p)["M_tot"] * g * math.cos(theta)
    assert Q.sum() == pytest.approx(total, rel=1e-9)


def test_the_tilted_weight_follows_the_heading_at_the_car_centre():
    """On a curve the weight's component along the track turns with it: at the car centre's
    heading psi it is -g sin(theta) (cos psi, sin psi)."""
    p = metro_car_arb_dampers()
    track = TrackGeometry((Straight(30.0), Arc(200.0, 100.0, 1, 0.0)))
    car = MetroCar(p, track=track, speed_profile=PhasedSpeedProfile((0.0, 8.0), (10.0, 10.0)),
                   speed_m_per_s=10.0, grade=lambda s: GRADE)
    _run(car, 8.0)
    load = np.asarray(car.mbs.GetLoad(0)["loadVector"])
    psi = car.hooks.centre_heading_rad
    assert psi > 0.1                                          # well into the arc
    along = -p.gravity_m_per_s2 * math.sin(math.atan(GRADE))
    np.testing.assert_allclose(load, [along * math.cos(psi), along * math.sin(psi),
                                      -p.gravity_m_per_s2 * math.cos(math.atan(GRADE))], rtol=0, atol=1e-12)


def test_a_car_driven_through_its_wheels_holds_and_climbs_the_gradient():
    """Contact guidance, WheelDrive: the car stands 2 s on the 4 % rise, then accelerates uphill at
    0.5 m/s^2 for 6 s. Standing, the brakes hold it (it stays within 1 mm of the profile) and the
    creep forces carry its weight's component along the track, M_tot g sin(theta) (10.4 kN);
    climbing, M_tot (a + g sin(theta)). 1 %: the surge on the traction rods of the start
    (measured 0.2 % over the windows)."""
    p = metro_car_arb_dampers()
    profile = PhasedSpeedProfile((0.0, 2.0, 8.0), (0.0, 0.0, 3.0))
    car = MetroCar(p, track=TrackGeometry((Straight(60.0),)), speed_profile=profile, start_s_m=8.0,
                   guidance="contact", drive=WheelDrive(), contact=ContactParams(min_creep_speed_m_per_s=0.1),
                   grade=lambda s: GRADE)
    rows = np.array(_run(car, 8.0, lambda c: [c.t_s, c.wheelset_longitudinal_forces_N().sum(),
                                              c.hooks.torques.offset_m]))
    M = hand_symbols(p)["M_tot"]
    g_along = p.gravity_m_per_s2 * math.sin(math.atan(GRADE))
    standing = (rows[:, 0] > 1.0) & (rows[:, 0] <= 2.0)
    climbing = (rows[:, 0] > 6.0) & (rows[:, 0] <= 8.0)
    assert rows[standing, 1].mean() == pytest.approx(M * g_along, rel=0.01)
    assert rows[climbing, 1].mean() == pytest.approx(M * (0.5 + g_along), rel=0.01)
    assert np.abs(rows[:, 2]).max() < 1e-3
