"""Traction and braking through the wheels (vehicle/car/wheel_drive.py): the driver's law, and a
contact car on straight track that starts, accelerates, brakes to a stop and stands, moved only
by torques on its wheelsets. The quasi-static hand model of the pitch and the load transfer is in
tests/vehicle/test_wheel_braking.py."""
from __future__ import annotations

import numpy as np
import pytest

from vehicle.car import MetroCar, WheelDrive
from vehicle.params import ContactParams, metro_car_arb_dampers
from vehicle.speed import PhasedSpeedProfile
from vehicle.track import Straight, TrackGeometry

A = 1.0            #: acceleration and braking [m/s^2]
PHASE_S = 4.0      #: accelerating, then braking [s]
H = 0.005          #: bellow-law update and car step [s]


@pytest.mark.parametrize("bad", [(), (0,), (5,), (1, 1), (1.0,), (True,)])
def test_motored_wheelsets_are_checked(bad):
    with pytest.raises(ValueError, match="motored_wheelsets"):
        WheelDrive(motored_wheelsets=bad)


@pytest.mark.parametrize("name", ["tracking_frequency_Hz", "tracking_damping_ratio"])
@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), float("inf")])
def test_tracking_gains_are_checked(name, value):
    with pytest.raises(ValueError, match=name):
        WheelDrive(**{name: value})


def test_a_drive_needs_contact_guidance():
    with pytest.raises(ValueError, match="guidance='contact'"):
        MetroCar(metro_car_arb_dampers(), drive=WheelDrive())


def test_traction_on_the_motored_wheelsets_braking_on_all():
    """The shares of the total force: equal on the motored wheelsets in traction, on all four in
    braking; they sum to the force (exactly: 1/n of a float and back)."""
    from vehicle.car.wheel_drive import WheelTorques

    torques = WheelTorques(WheelDrive(motored_wheelsets=(2, 3)), [], [], 0.42, 100.0, 25_000.0)
    np.testing.assert_allclose(torques.shares(1000.0), [0.0, 500.0, 500.0, 0.0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(torques.shares(-1000.0), [-250.0] * 4, rtol=0, atol=1e-12)
    # the feed-forward alone: the translating mass plus the four spins' inertia reduced to the rail
    assert torques.force(1.0, 0.0, 0.0, 2_000.0) == pytest.approx(27_000.0 + 4 * 100.0 / 0.42 ** 2, rel=1e-15)
    # the feedback: a car ahead of the profile (e > 0) or faster (de/dt > 0) is held back
    assert torques.force(0.0, 1e-3, 0.0, 0.0) < 0.0 and torques.force(0.0, 0.0, 1e-3, 0.0) < 0.0


@pytest.fixture(scope="module")
def trip():
    """Stand 1 s, accelerate at A for PHASE_S, brake at A to a stop, stand 3 s; linear bellows
    (as benchmarks/bench_vehicle.py); per macro-step the torques, the wheelsets' longitudinal
    creep forces (track frame, both wheels) and the wheel loads."""
    p = metro_car_arb_dampers()
    t1, t2, t3 = 1.0, 1.0 + PHASE_S, 1.0 + 2 * PHASE_S
    profile = PhasedSpeedProfile((0.0, t1, t2, t3, t3 + 3.0), (0.0, 0.0, A * PHASE_S, 0.0, 0.0))
    car = MetroCar(p, track=TrackGeometry((Straight(60.0),)), speed_profile=profile, start_s_m=8.0,
                   guidance="contact", drive=WheelDrive(), contact=ContactParams(min_creep_speed_m_per_s=0.1))
    F0, k = car.static_bellow_forces_N(), np.full(4, 243e3)
    rows = []
    for n in range(1, int(round((t3 + 3.0) / H)) + 1):
        z, _ = car.bellow_crushing()
        car.set_bellow_forces(F0 + k * z, k)
        car.advance(n * H)
        fx = car.outputs.contact_state().force_track_N[:, 0].reshape(4, 2).sum(axis=1)
        rows.append([n * H, car.hooks.torques.force_N, car.hooks.torques.offset_m, *fx])
    return p, profile, car, np.array(rows)


def test_the_creep_forces_carry_the_cars_inertia(trip):
    """In the second half of each phase the wheelsets' longitudinal creep forces sum to the
    translating mass times the profile's acceleration (the spins' inertia is the torques'
    business, not the rails'): Newton's law along the track through the wheels."""
    p, profile, car, rows = trip
    mass = p.carbody_mass_kg + 2 * p.bogie_mass_kg + 4 * p.wheelset_mass_kg
    for lo, hi, a in ((3.0, 5.0, A), (7.0, 9.0, -A)):
        window = (rows[:, 0] > lo) & (rows[:, 0] <= hi)
        total = rows[window, 3:7].sum(axis=1)
        # the carbody's 5.5 Hz surge on the traction rods (damping ratio ~0.05) is still ringing in
        # the window: each sample within 1 % (measured 0.36 %), the 2 s mean within 0.1 %
        # (measured 1.1e-4 accelerating, 2.2e-4 braking)
        assert total.mean() == pytest.approx(mass * a, rel=1e-3)
        assert np.abs(total - mass * a).max() < 0.01 * mass * A


def test_the_car_follows_its_profile_and_stops_where_it_says(trip):
    """The car ends where the profile puts it and stands there: its mean offset from the profile
    within 1 mm at the end (measured 7 um: the feedback's spring holds it against the residual
    ~12 N), the braking equal on every wheelset (within 0.1 %; measured 8.7e-5)."""
    p, profile, car, rows = trip
    assert abs(rows[-1, 2]) < 1e-3
    assert np.abs(rows[:, 2]).max() < 5e-3     # never more than 5 mm off the timetable (measured 2.1 mm)
    braking = (rows[:, 0] > 6.0) & (rows[:, 0] <= 9.0)
    fx = rows[braking, 3:7]
    np.testing.assert_allclose(fx, np.broadcast_to(fx.mean(axis=1, keepdims=True), fx.shape), rtol=1e-3)
    # the brakes hold the standing car: the creep forces at the end ~0 (1 % of M A)
    assert np.abs(rows[-1, 3:7]).sum() < 0.01 * 26_000.0 * A
