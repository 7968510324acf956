"""The payload on the carbody's floor (vehicle/payload.py, vehicle/car/payload.py): the loaded
carbody's mass properties against exudyn's own inertia arithmetic and the parallel-axis theorem
written here; the car carrying a payload from the start at rest; a payload boarding during a run
sinks and pitches the carbody as statics says it must.

The pneumatic suspension is emulated as in tests/vehicle/test_vehicle.py: a linear spring per
bellow about the static state, F = F0 + K z (anchored at z = 0), so the end state has a closed form.
"""
import math

import numpy as np
import pytest
from exudyn.rigidBodyUtilities import InertiaCuboid, RigidBodyInertia
from linear_bellows import newton_per_step

from vehicle.car import MetroCar
from vehicle.params import VehicleParams
from vehicle.payload import PayloadBlock, block_position_m, carbody_mass

P = VehicleParams()
G = P.gravity_m_per_s2
K_BELLOW_N_PER_M = 243e3      # paper Table 2 (bellow + tank, adiabatic), as tests/vehicle/test_vehicle.py
MACRO_S = 5e-3


def test_loaded_carbody_against_exudyn_inertia_arithmetic():
    """Two blocks on the floor (one off the centre in x and y): mass, centre of gravity and inertia
    about the reference point as exudyn's RigidBodyInertia (cuboids translated and added) gives
    them: an independent implementation of the same sums (to round-off, 1e-9 relative)."""
    blocks = [PayloadBlock(2000.0, 0.0, 0.0, 14.0, 2.6, 1.7, 1.0), PayloadBlock(800.0, 3.5, -0.65, 7.0, 1.3, 1.7, 1.0)]
    body = RigidBodyInertia(mass=P.carbody_mass_kg, inertiaTensor=np.diag(
        [P.carbody_inertia_xx_kg_m2, P.carbody_inertia_yy_kg_m2, P.carbody_inertia_zz_kg_m2]), inertiaTensorAtCOM=True)
    for b in blocks:
        sides = [b.length_m, b.width_m, b.height_m]
        body = body + InertiaCuboid(b.mass_kg / math.prod(sides), sides).Translated(list(block_position_m(P, b)))
    loaded = carbody_mass(P, blocks)
    assert loaded.mass_kg == pytest.approx(body.Mass(), rel=1e-12)
    assert np.allclose(loaded.com_m, body.COM(), rtol=1e-9, atol=1e-12)
    assert np.allclose(loaded.inertia6_kg_m2, body.GetInertia6D(), rtol=1e-9, atol=1e-6)


def test_point_payload_by_the_parallel_axis_theorem():
    """A point mass m at r = (x, y, z): I_xx grows by m (y^2 + z^2), I_xy becomes -m x y (the
    tensor's entry), the centre of gravity moves by m r / (M + m)."""
    m, (x, y) = 1000.0, (2.0, -0.5)
    loaded = carbody_mass(P, [PayloadBlock(m, x, y)])
    z = P.floor_height_m - P.carbody_cog_height_m
    assert loaded.com_m == pytest.approx((m * x / (P.carbody_mass_kg + m), m * y / (P.carbody_mass_kg + m),
                                          m * z / (P.carbody_mass_kg + m)), rel=1e-12)
    Ixx, Iyy, Izz, Iyz, Ixz, Ixy = loaded.inertia6_kg_m2
    assert Ixx == pytest.approx(P.carbody_inertia_xx_kg_m2 + m * (y ** 2 + z ** 2), rel=1e-12)
    assert Iyy == pytest.approx(P.carbody_inertia_yy_kg_m2 + m * (x ** 2 + z ** 2), rel=1e-12)
    assert Izz == pytest.approx(P.carbody_inertia_zz_kg_m2 + m * (x ** 2 + y ** 2), rel=1e-12)
    assert (Iyz, Ixz, Ixy) == pytest.approx((-m * y * z, -m * x * z, -m * x * y), rel=1e-12)


def test_an_initial_payload_must_be_centred():
    with pytest.raises(ValueError, match="centred"):
        MetroCar(P, payload=lambda t: [PayloadBlock(1000.0, 0.0, -0.6)])


def advance_on_springs(car, t_end_s, record=None):
    """Advance with linear bellows F = F0 + K z about the tare+initial static state."""
    F0, K = car.static_bellow_forces_N(), np.full(4, K_BELLOW_N_PER_M)
    n = int(round((t_end_s - car.t_s) / MACRO_S))
    t0 = car.t_s
    for i in range(n):
        car.set_bellow_forces(F0, K, z_anchor_m=np.zeros(4))
        car.advance(t0 + (i + 1) * MACRO_S)
        if record is not None:
            record.append((car.t_s, car.bellow_crushing()[0].copy(), car.wheel_loads_N().sum()))


def test_a_car_loaded_at_arrival_starts_at_rest():
    """3 t on board from t = 0 (uniform): the bellows carry (M + m) g / 4 and the car stays where it
    starts (its static state includes the payload: the floor moves < 1 um in 1 s)."""
    m = 3000.0
    car = MetroCar(P, payload=lambda t: [PayloadBlock(m, 0.0, 0.0, 14.0, 2.6, 1.7, 1.0)])
    assert car.static_bellow_forces_N() == pytest.approx(np.full(4, (P.carbody_mass_kg + m) * G / 4), rel=1e-12)
    points = [[4.5, 1.3], [-4.5, -1.3]]
    z0 = car.floor_heights_m(points)
    advance_on_springs(car, 1.0)
    assert np.abs(car.floor_heights_m(points) - z0).max() < 1e-6
    total = P.carbody_mass_kg + m + 2 * P.bogie_mass_kg + 4 * P.wheelset_mass_kg
    assert car.wheel_loads_N().sum() == pytest.approx(total * G, rel=1e-6)


def test_boarding_at_the_front_sinks_and_pitches_the_carbody_as_statics_says():
    """2 t boarding on the front half of the floor (centre of gravity 3.5 m ahead of the car centre)
    over 8 s: once settled each bellow carries its static share of the added weight, front
    (1/2 + x/(2a)) / 2, rear (1/2 - x/(2a)) / 2 of Δm g with 2a the bogie centre distance, so with
    F = F0 + K z it is crushed by that share / K. Mean over the last 2 s of a 14 s run, within 1 %
    of the largest crushing (0.34 mm): the carbody's ~1.1 Hz heave and pitch are barely damped
    and the ramp leaves ~1 % of the static deflection swinging, averaged out over the window to
    well below that; the hand model leaves out the pitch's geometric term, the loaded centre of
    gravity h ~ 0.5 m above the upper plates moving forward by h theta (theta = 2.8 mrad here),
    which shifts W h theta / 2a ~ 14 N per bellow to the front: 0.06 mm, 1.3 % of the rear's
    small share (measured: -1.3 %), 0.2 % of the front's."""
    dm, x, ramp = 2000.0, 3.5, 8.0

    def payload(t):
        return [PayloadBlock(dm * min(max(t / ramp, 0.0), 1.0), x, 0.0, 7.0, 2.6, 1.7, 1.0)]
    car = MetroCar(P, payload=payload)
    record = []
    advance_on_springs(car, 14.0, record)
    t = np.array([r[0] for r in record])
    z = np.array([r[1] for r in record])[t >= 12.0].mean(axis=0)
    a2 = P.bogie_centre_distance_m
    share = {"F": (0.5 + x / a2) / 2.0, "R": (0.5 - x / a2) / 2.0}
    expected = np.array([dm * G * share[b[0]] / K_BELLOW_N_PER_M for b in ("FL", "FR", "RL", "RR")])
    assert z == pytest.approx(expected, abs=0.01 * expected.max())
    assert car.payload_kg() == dm
    total = P.carbody_mass_kg + dm + 2 * P.bogie_mass_kg + 4 * P.wheelset_mass_kg
    assert np.mean([r[2] for r in record if r[0] >= 12.0]) == pytest.approx(total * G, rel=1e-3)


def _newton_per_boarding_step(mass_tol: float, monkeypatch) -> tuple[float, int]:
    """Newton iterations per 5 ms step, and fresh Jacobians, of a standing car while 3000 kg
    board over 10 s (one side, as at a platform), its Jacobian renewed when the carbody's mass
    has changed by ``mass_tol`` of it."""
    from vehicle.car.solver import CarSolver

    monkeypatch.setattr(CarSolver, "JACOBIAN_MASS_TOL", mass_tol)

    def payload(t):
        return [PayloadBlock(3000.0 * min(max(t / 10.0, 0.0), 1.0), 0.0, 0.65, 14.0, 1.3, 1.7, 1.0)]
    car = MetroCar(P, payload=payload)
    j0 = car.jacobian_count
    return newton_per_step(car, 10.0, K_BELLOW_N_PER_M), car.jacobian_count - j0


def test_the_kept_jacobian_is_renewed_while_passengers_board(monkeypatch):
    """The kept Jacobian holds the carbody's mass matrix (M / (beta h^2), its largest term):
    kept from t = 0 while 3000 kg board (16 % of this carbody) modified Newton contracts by ~ the
    mass's relative error per iteration and the steps take more iterations as the load grows.
    Measured: 5.92 iterations per step kept (2 Jacobians), 2.93 renewed on every 0.5 % of mass
    (32 Jacobians), 2.18 on every 0.05 % (262); the bound sits between the first two."""
    kept, kept_jac = _newton_per_boarding_step(math.inf, monkeypatch)
    renewed, renewed_jac = _newton_per_boarding_step(0.005, monkeypatch)
    assert kept > 1.5 * renewed, (kept, renewed)
    # ~3000 kg / (0.005 x ~19 t) = 31 renewals, plus the first
    assert 20 <= renewed_jac - kept_jac <= 45, (kept_jac, renewed_jac)
