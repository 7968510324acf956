"""Manchester benchmark vehicle 1 (vehicle.params.manchester_vehicle_1; docs/validation.md,
"Manchester benchmark vehicle 1"): the preset builds a car and stands on its wheels with the
benchmark's weight shared equally."""
import numpy as np
import pytest

from cosim.scenario.presets import VEHICLE_PRESETS
from vehicle.car import MetroCar
from vehicle.params import manchester_vehicle_1

# The benchmark's masses (Iwnicki 1998, as read in TTB-2D and [C], vehicle/params.py):
# carbody 32 000 kg, two bogie frames of 2 615 kg, four wheelsets of 1 813 kg: 44 482 kg.
BENCHMARK_MASS_KG = 32000.0 + 2 * 2615.0 + 4 * 1813.0


def test_preset_is_registered_and_carries_the_benchmark_masses():
    p = VEHICLE_PRESETS["manchester_vehicle_1"]()
    assert p == manchester_vehicle_1()
    assert p.carbody_mass_kg + 2 * p.bogie_mass_kg + 4 * p.wheelset_mass_kg == BENCHMARK_MASS_KG
    assert (p.bogie_centre_distance_m, p.wheelbase_m, p.wheel_radius_m) == (19.0, 2.56, 0.46)


def test_static_wheel_loads_are_the_weight_over_eight():
    p = manchester_vehicle_1()
    car = MetroCar(p)
    Q = car.wheel_loads_N()
    q8 = BENCHMARK_MASS_KG * p.gravity_m_per_s2 / 8  # 54 546 N at g = 9.81
    # The car is built in its analytic static equilibrium (symmetric car, level track), so the
    # loads are exact up to round-off: ~2e-13 relative on the sum (measured), as for the metro
    # car (tests/vehicle/test_vehicle.py). 1e-9 relative per wheel (0.05 mN) is far below any
    # physical effect and would catch a lost mass (a wheelset's 1 813 kg is 4 % of a wheel load)
    # or an off-centre load (left/right or front/rear) at once.
    assert Q.shape == (8,)
    assert np.allclose(Q, q8, rtol=1e-9, atol=0.0)
    assert Q.sum() == pytest.approx(8 * q8, rel=1e-9)
    assert car.static_bellow_forces_N().sum() == pytest.approx(32000.0 * p.gravity_m_per_s2, rel=1e-12)
