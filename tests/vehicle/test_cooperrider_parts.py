"""What the Cooperrider configuration adds to the car (docs/validation.md): given creep coefficients
that do not follow the load, the roll-rate creepage as a switch, a cone with level contact, the
secondary yaw stiffness, and bodies held by joints that run with the car."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from vehicle.car import MetroCar
from vehicle.car.linear import linearise_car
from vehicle.params import ContactParams, VehicleParams
from vehicle.wheelrail.contact_law import SCALAR, ContactLawTable, WheelGeometry, WheelsetParams, WheelsetState, contact
from vehicle.wheelrail.geometry import ContactTable

GIVEN = (2.349e7, 2.029e7, 4.911e4, 12.0)          # f11 [N], f22 [N], f23 [N m], f33 [N m^2]
CONE = ContactTable.cone(0.1, r0_m=0.42, half_spacing_m=0.75)


def _wheel(law: ContactLawTable, z: float, roll_t: float = 0.0, roll_rate_creepage: bool = True):
    """The left wheel of a centred wheelset at height z (sunk into the rail: a load), rolling
    freely at 10 m/s with a small lateral creepage (y' = 1 mm/s) and the given roll rate."""
    geo = law.geometry(0.0)
    V = 10.0
    st = WheelsetState(0.0, z, 0.0, 0.0, 1e-3, 0.0, roll_t, 0.0, V / geo["r_L"], 0.0)
    c = WheelsetParams().law_constants(law.reference_load_N, law.creep_follows_load, roll_rate_creepage)
    return contact(SCALAR, 1.0, st, WheelGeometry.of_side(geo, "L"), V, 0.0, c, 1.0 / V)


def test_given_creep_coefficients_do_not_follow_the_load():
    law = ContactLawTable(CONE, given_creep=GIVEN, smoothing_mm=0.0)
    assert not law.creep_follows_load
    light, heavy = (_wheel(law, law.geometry(0.0)["dz0"] - sink) for sink in (2e-5, 8e-5))
    assert heavy.N > 5 * light.N > 0
    for w in (light, heavy):                    # F_y = -f22 xi_y - f23 phi, whatever N
        assert w.fy == pytest.approx(-GIVEN[1] * w.xi_y - GIVEN[2] * w.phi, rel=1e-12)   # linear part
    followed = ContactLawTable(CONE, smoothing_mm=0.0)
    assert followed.creep_follows_load
    light, heavy = (_wheel(followed, followed.geometry(0.0)["dz0"] - sink) for sink in (2e-5, 8e-5))
    assert heavy.xi_y == pytest.approx(light.xi_y) and heavy.phi == pytest.approx(light.phi)
    assert abs(heavy.fy) > 2 * abs(light.fy) > 0          # the same creepages, 8 x the load: f22 x 4, f23 x 8


def test_roll_rate_creepage_can_be_left_out():
    law = ContactLawTable(CONE, smoothing_mm=0.0)
    z = law.geometry(0.0)["dz0"] - 5e-5
    with_roll, without = (_wheel(law, z, roll_t=0.01, roll_rate_creepage=on) for on in (True, False))
    r, cg = law.geometry(0.0)["r_L"], np.cos(law.geometry(0.0)["gamma_L"])
    assert with_roll.xi_y - without.xi_y == pytest.approx(r * 0.01 / 10.0 / cg, rel=1e-12)


def test_level_cone_keeps_the_radii_and_lays_the_contact_flat():
    level = ContactTable.cone(0.1, r0_m=0.42, half_spacing_m=0.75, level_contact=True)
    for name in ("r_L_m", "r_R_m", "roll_rad", "dz_mm"):
        np.testing.assert_array_equal(level.columns[name], CONE.columns[name])
    assert not np.any(level.columns["gamma_L_rad"]) and not np.any(level.columns["gamma_R_rad"])
    assert CONE.columns["gamma_L_rad"][len(CONE.columns["y_ws_mm"]) // 2] == pytest.approx(np.arctan(0.1))


@pytest.fixture(scope="module")
def held_car():
    """The metro car on contact, carbody and rear bogie held, a secondary yaw stiffness of 1 MN m/rad,
    given creep coefficients; linearised at 20 m/s."""
    p = dataclasses.replace(VehicleParams(), secondary_yaw_stiffness_N_m_per_rad=1.0e6)
    car = MetroCar(p, speed_m_per_s=20.0, guidance="contact", contact=ContactParams(creep_coefficients=GIVEN),
                   held=("carbody", "rear bogie"))
    return linearise_car(car, car.static_bellow_forces_N(), np.full(4, 4.0e5))


def test_held_bodies_leave_the_linear_model(held_car):
    names = held_car.coordinates
    gone = [("carbody", a) for a in ("y", "roll", "yaw")] + [("bogie 2", a) for a in ("y", "roll", "yaw")] + \
           [(f"wheelset {i}", a) for i in (3, 4) for a in ("y", "yaw")]
    assert not set(gone) & set(names)
    kept = [("carbody", "z"), ("carbody", "pitch"), ("bogie 1", "y"), ("bogie 1", "yaw"), ("bogie 1", "roll"),
            ("wheelset 1", "y"), ("wheelset 1", "yaw"), ("wheelset 3", "roll")]
    assert set(kept) <= set(names)
    assert held_car.reaction_N < 1.0                # straight, centred: the holding joints carry nothing


def test_secondary_yaw_stiffness_is_a_yaw_couple_to_the_carbody(held_car):
    """The front frame's yaw stiffness: the yaw spring, the bellows' shear in x at +-1 m (2 x 120 kN/m x
    1 m^2) and the primary's longitudinal springs to the wheelsets (2 x 2 x 17.5 MN/m x (1 m)^2 and the
    lateral springs at +-1 m wheelbase/2: 2 x 2 x 2.17 MN/m x (1 m)^2)."""
    i = held_car.coordinates.index(("bogie 1", "yaw"))
    p = VehicleParams()
    expected = (1.0e6 + 2 * p.bellow_shear_stiffness_N_per_m * (p.airspring_lateral_spacing_m / 2) ** 2
                + 2 * 2 * p.primary_stiffness_x_N_per_m * (p.primary_lateral_spacing_m / 2) ** 2
                + 2 * 2 * p.primary_stiffness_y_N_per_m * (p.wheelbase_m / 2) ** 2)
    assert held_car.system.K[i, i] == pytest.approx(expected, rel=1e-4)   # central differences: ~1e-7
