"""Newton's absolute tolerance follows the round-off of the car's coordinates far from the origin
(vehicle/car/solver.py, CarSolver.ROUNDOFF_SAFETY)."""
from __future__ import annotations

import math

import numpy as np
import pytest
from linear_bellows import newton_per_step

from vehicle.car.solver import CarSolver
from vehicle.speed import PhasedSpeedProfile

#: away 17 km, the shipped line's way back: ulp(17 km) = 3.6e-12 m
FAR_M = 17000.0
PROFILE = PhasedSpeedProfile((0.0, 2.0, 4.0), (0.0, 10.0, 10.0))   # moving: standing, the floor does not show


def _run(start_s_m: float, monkeypatch, roundoff_safety: float | None = None):
    """The same kinematic car, started ``start_s_m`` along a straight, 4 s at PROFILE: its wheel
    loads and carbody height at the end, and Newton's iterations per step while moving."""
    from vehicle.car import MetroCar
    from vehicle.params import metro_car_arb_dampers
    from vehicle.track import Straight, TrackGeometry

    if roundoff_safety is not None:
        monkeypatch.setattr(CarSolver, "ROUNDOFF_SAFETY", roundoff_safety)
    car = MetroCar(metro_car_arb_dampers(), track=TrackGeometry((Straight(start_s_m + 100.0),)),
                   speed_profile=PROFILE, start_s_m=start_s_m)
    iterations = newton_per_step(car, 4.0, 243e3, counted_after_s=1.0)
    return car.wheel_loads_N(), car.bellow_crushing()[0], iterations


def test_the_tolerance_is_the_given_one_near_the_origin_and_follows_ulp_far_from_it():
    from vehicle.car import MetroCar
    from vehicle.params import manchester_vehicle_1, metro_car_arb_dampers

    car = MetroCar(metro_car_arb_dampers())
    stiffness = 8 * metro_car_arb_dampers().primary_stiffness_x_N_per_m   # two axlebox springs a wheelset
    assert car.solver._roundoff_N_per_m == stiffness
    # the metro car (17.5 MN/m a spring) below 4096 m and the stiffest shipped car (Manchester,
    # 31.4 MN/m) below 2048 m: under 1e-4 N, the given tolerance, to the bit as before the rule
    assert CarSolver.ROUNDOFF_SAFETY * stiffness * math.ulp(4095.0) < 1e-4
    assert CarSolver.ROUNDOFF_SAFETY * 8 * manchester_vehicle_1().primary_stiffness_x_N_per_m * math.ulp(2047.0) < 1e-4
    # at 17 km: 1.5 x 1.4e8 N/m x 3.64e-12 m
    assert CarSolver.ROUNDOFF_SAFETY * stiffness * math.ulp(FAR_M) == pytest.approx(7.64e-4, rel=1e-3)
    car.advance(0.005)
    assert car.solver._newton.absoluteTolerance == car.solver._abs_tol


@pytest.mark.slow
def test_a_car_far_from_the_origin_runs_as_one_near_it(monkeypatch):
    """Translation along a straight changes nothing physical: the car started 17 km out gives the
    wheel loads and crushings of the car started at 10 m, and at the same Newton cost. Without
    the rule (factor 0: the absolute tolerance 1e-4 N everywhere) the far car's residual stalls
    on its round-off floor (1.8-6e-4 N measured there) and Newton iterates on fresh Jacobians.
    Measured here: 2.89 iterations per step near, 2.83 far, 7.81 far without the rule; far against
    near 2.9e-5 N in the wheel loads and 1.8e-12 m in the crushings, and without the rule 35 N
    and 2.5e-5 m (the steps that did not converge were taken all the same)."""
    near_Q, near_z, near_it = _run(10.0, monkeypatch)
    far_Q, far_z, far_it = _run(FAR_M, monkeypatch)
    # Newton's residual <= 7.6e-4 N against the car's stiffnesses (>= 2.4e5 N/m): displacements
    # within ~3e-9 m, forces within ~7e-4 N per step; 1e-3 N and 1e-9 m are those bounds
    np.testing.assert_allclose(far_Q, near_Q, rtol=0, atol=1e-3)
    np.testing.assert_allclose(far_z, near_z, rtol=0, atol=1e-9)
    assert far_it < 1.3 * near_it, (near_it, far_it)
    _, _, stalled_it = _run(FAR_M, monkeypatch, roundoff_safety=0.0)
    assert stalled_it > 2.0 * near_it, (near_it, stalled_it)
