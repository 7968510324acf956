"""vehicle.speed.PhasedSpeedProfile: the distance is the exact integral of the speed, the inverse
finds the time a distance is reached, and a car under kinematic guidance runs at it."""
from __future__ import annotations

import math

import numpy as np
import pytest
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
    F0, k = car.static_bellow_forces_N(), np.full(4, 1.1e6)
    it, counts = car.solver.main.it, []
    for n in range(1, int(round(29.0 / 0.005)) + 1):
        z, _ = car.bellow_crushing()
        car.set_bellow_forces(F0 + k * z, k)
        n0 = it.newtonStepsCount
        car.advance(n * 0.005)
        if n * 0.005 > 26.0:                      # standing, a second after the stop
            counts.append(it.newtonStepsCount - n0)
    return float(np.mean(counts))


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
