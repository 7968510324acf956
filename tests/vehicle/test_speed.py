"""vehicle.speed.PhasedSpeedProfile: the distance is the exact integral of the speed, the inverse
finds the time a distance is reached, and a car under kinematic guidance runs at it."""
from __future__ import annotations

import math

import numpy as np
import pytest
from linear_bellows import newton_per_step
from scipy.integrate import quad

from vehicle.speed import PhasedSpeedProfile

# stand 2 s, 1 m/s^2 to 10 m/s, cruise 10 s, brake at 2 m/s^2 to a stop, stand
PROFILE = PhasedSpeedProfile((0.0, 2.0, 12.0, 22.0, 27.0, 30.0), (0.0, 0.0, 10.0, 10.0, 0.0, 0.0))


def test_distance_is_the_integral_of_the_speed():
    # quadrature of the piecewise-linear speed, independent of the closed form (1e-9 m: quad's
    # tolerance on a polynomial per phase, the knots given as break points)
    for t in (0.0, 1.0, 2.0, 7.3, 12.0, 15.5, 22.0, 24.9, 27.0, 29.0, 35.0):
        exact = quad(lambda u: float(PROFILE.speed(u)), 0.0, t, points=[2, 12, 22, 27], limit=200)[0] if t > 0 else 0.0
        assert PROFILE.distance(t) == pytest.approx(exact, abs=1e-9)
    # by hand: 50 m accelerating, 100 m cruising, 25 m braking
    assert PROFILE.distance(30.0) == pytest.approx(175.0, abs=1e-12)
    assert np.allclose(PROFILE.distance(np.array([12.0, 22.0])), [50.0, 150.0], atol=1e-12)


def test_time_at_distance_inverts_the_distance():
    for t in (2.5, 5.0, 12.0, 17.0, 22.0, 23.0, 26.9):
        assert PROFILE.time_at_distance(float(PROFILE.distance(t))) == pytest.approx(t, abs=1e-9)
    assert PROFILE.time_at_distance(175.0) == pytest.approx(27.0, abs=1e-6)   # the stop
    assert math.isinf(PROFILE.time_at_distance(176.0))                         # never: it stands
    assert PROFILE.acceleration(5.0) == 1.0 and PROFILE.acceleration(25.0) == -2.0 and PROFILE.acceleration(40.0) == 0.0


@pytest.mark.parametrize("times, speeds", [((0.0,), (0.0,)), ((1.0, 2.0), (0.0, 0.0)), ((0.0, 0.0), (0.0, 1.0)),
                                           ((0.0, 1.0), (0.0, -1.0)), ((0.0, 1.0), (0.0, math.nan))])
def test_a_wrong_profile_is_refused(times, speeds):
    with pytest.raises(ValueError):
        PhasedSpeedProfile(times, speeds)


# jerk-limited, as knots of a(t): stand 2 s; the acceleration ramps at 0.5 m/s^3 to 1 m/s^2 in 2 s
# (to 1 m/s), holds 8 s (9 m/s), ramps out in 2 s (10 m/s); cruise 4 s; the braking ramps at
# 1 m/s^3 to -2 m/s^2 in 2 s (8 m/s), holds 2 s (4 m/s), ramps out at 0.5 m/s^3 in 4 s (0 m/s);
# stand 2 s
JERK_TIMES = (0.0, 2.0, 4.0, 12.0, 14.0, 18.0, 20.0, 22.0, 26.0, 28.0)
JERK_ACCELS = (0.0, 0.0, 1.0, 1.0, 0.0, 0.0, -2.0, -2.0, 0.0, 0.0)


def _integral(times, values, v0=0.0):
    """The running integral of a piecewise-linear function given at knots (trapezoids: exact)."""
    return tuple(np.concatenate([[v0], v0 + np.cumsum(0.5 * (np.add(values[1:], values[:-1])) * np.diff(times))]))


def test_a_jerk_limited_profile_integrates_its_accelerations():
    speeds = _integral(JERK_TIMES, JERK_ACCELS)
    assert speeds[5] == 10.0 and speeds[-1] == 0.0                      # by hand, above
    profile = PhasedSpeedProfile(JERK_TIMES, speeds, JERK_ACCELS)
    # the speed against a quadrature of the acceleration (quad, independent of the closed form),
    # the distance against a quadrature of the speed; 1e-9: quad's tolerance on a polynomial per phase
    breaks = list(JERK_TIMES[1:-1])
    for t in (1.0, 3.0, 4.0, 7.7, 13.0, 16.0, 19.0, 21.5, 23.0, 25.5, 26.0, 27.0, 30.0):
        dv = quad(profile.acceleration, 0.0, t, points=breaks, limit=200)[0]
        assert profile.speed(t) == pytest.approx(dv, abs=1e-9)
        ds = quad(lambda u: float(profile.speed(u)), 0.0, t, points=breaks, limit=200)[0]
        assert profile.distance(t) == pytest.approx(ds, abs=1e-9)
        # the inverse: the time where the car moves (standing, the time is ill-posed: at the stop
        # v ~ j u^2 / 2, a round-off of the distance moves the time by its cube root), else the distance
        back = profile.time_at_distance(profile.distance(t))
        if 2.0 < t < 25.0:
            assert back == pytest.approx(t, abs=1e-9)
        assert profile.distance(back) == pytest.approx(profile.distance(t), abs=1e-12)
    # the acceleration is continuous: on either side of every knot within 1e-9 s of it it differs
    # by at most the jerk times 2e-9 s (the steepest ramp, 1 m/s^3)
    for t in JERK_TIMES[1:-1]:
        assert abs(profile.acceleration(t + 1e-9) - profile.acceleration(t - 1e-9)) <= 1.0 * 2e-9 + 1e-15
    # the speed is vectorised like the piecewise-linear one's
    assert np.allclose(profile.speed(np.array([3.0, 13.0])), [profile.speed(3.0), profile.speed(13.0)], atol=0)


def test_a_jerk_limited_profile_refuses_speeds_its_accelerations_do_not_give():
    speeds = _integral(JERK_TIMES, JERK_ACCELS)
    with pytest.raises(ValueError, match="integral"):
        PhasedSpeedProfile(JERK_TIMES, (0.0, *speeds[1:-1], 0.5), JERK_ACCELS)
    with pytest.raises(ValueError, match="one per knot"):
        PhasedSpeedProfile(JERK_TIMES, speeds, JERK_ACCELS[:-1])
    # a ramp from -1 to +1 m/s^2 over 2 s from 0.5 m/s dips to 0 at 1 s and below:
    # v(1) = 0.5 - 1 + 0.5 = 0 ... so from 0.4 m/s it reaches -0.1 m/s
    with pytest.raises(ValueError, match="below 0"):
        PhasedSpeedProfile((0.0, 2.0), (0.4, 0.4), (-1.0, 1.0))


@pytest.mark.slow
def test_a_kinematic_car_runs_at_the_profile_and_stops_where_it_says():
    import exudyn as exu

    from vehicle.car import MetroCar
    from vehicle.params import VehicleParams, metro_car_arb_dampers
    from vehicle.track import Straight, TrackGeometry

    # with traction rods (10 MN/m, 30 kN s/m): the paper's car holds its carbody along the track by
    # the bellows' shear alone, undamped, and it surges +-27 mm for long after the stop
    car = MetroCar(metro_car_arb_dampers(), track=TrackGeometry((Straight(300.0),)), speed_profile=PROFILE)
    F0, k = car.static_bellow_forces_N(), np.full(4, 243e3)

    def carbody_x_m():
        return car.mbs.GetObjectOutputBody(car.model.carbody, exu.OutputVariableType.Position, localPosition=[0, 0, 0])[0]

    x0 = carbody_x_m()
    for i in range(1, int(round(32.0 / 0.005)) + 1):
        z, _ = car.bellow_crushing()
        car.set_bellow_forces(F0 + k * z, k)
        car.advance(i * 0.005)
    # the carbody follows its wheelsets through the suspension: 5 s after the stop it stands where
    # the profile stopped, its surge on the rods (17 t x 2 m/s^2 / 20.5 MN/m = 1.7 mm while braking) died away (0.1 mm)
    assert carbody_x_m() - x0 == pytest.approx(175.0, abs=1e-4)
    with pytest.raises(ValueError, match="kinematic"):
        MetroCar(VehicleParams(), track=TrackGeometry((Straight(300.0),)), speed_profile=PROFILE, guidance="contact")


def _newton_per_standing_step(speed_tol_m_per_s: float, monkeypatch) -> float:
    """Newton iterations per 5 ms step of a car (kinematic guidance) that runs through a 0.4 rad
    curve at 10 m/s, brakes to a stop on the straight after it and stands 4 s, on static bellow
    laws; with the Jacobian renewed on a speed change of ``speed_tol_m_per_s``."""
    from vehicle.car import MetroCar
    from vehicle.car.solver import CarSolver
    from vehicle.params import metro_car_arb_dampers
    from vehicle.track import Arc, Straight, TrackGeometry

    monkeypatch.setattr(CarSolver, "JACOBIAN_SPEED_TOL_M_PER_S", speed_tol_m_per_s)
    v = 10.0
    profile = PhasedSpeedProfile((0.0, 10.0, 15.0, 25.0, 29.0), (0.0, v, v, 0.0, 0.0))   # 150 m, stop at 160 m
    track = TrackGeometry((Straight(30.0), Arc(100.0, 40.0, +1), Straight(150.0)))
    car = MetroCar(metro_car_arb_dampers(), track=track, speed_profile=profile, start_s_m=10.0)
    return newton_per_step(car, 29.0, 1.1e6, counted_after_s=26.0)   # standing, a second after the stop


@pytest.mark.slow
def test_the_kept_jacobian_is_renewed_when_the_car_stops(monkeypatch):
    """The Newton Jacobian kept across steps holds terms that follow the speed: kept
    from a curve at speed into a stand (the heading rule renews it only while the track turns) it
    slows modified Newton to ~5 iterations per step (here 5.11; 5.3 after a 0.4 rad curve at
    19 m/s, 1.4 with a fresh Jacobian every iteration). Renewed on every 1 m/s of speed change the
    standing car takes 2.32. The bounds sit between the two measured regimes."""
    kept = _newton_per_standing_step(math.inf, monkeypatch)
    renewed = _newton_per_standing_step(1.0, monkeypatch)
    assert kept > 4.0 and renewed < 3.0, (kept, renewed)
