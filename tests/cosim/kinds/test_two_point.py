"""The two-point suspension: with the bellows of a bogie cross-connected, the carbody's static
roll stiffness is the anti-roll bar's (in series with the primary), the bellows adding none."""
from __future__ import annotations

import numpy as np
import pytest
from hand_models import roll_hand_calculation

from cosim.engine.cases import build_cosimulation
from cosim.load import load_scenario
from vehicle.car import MetroCar

from helpers import SCENARIOS

M_N_m = 20e3        # static roll moment on the carbody


def car_with_roll_moment(scenario):
    car = MetroCar(scenario.vehicle, step_s=scenario.solver.mechanics_step_s, carbody_load=True)
    car.set_carbody_load((0.0, 0.0, 0.0), (M_N_m, 0.0, 0.0))
    return car


@pytest.mark.slow
@pytest.mark.parametrize("layout", ["two_point", "four_point"])
def test_static_roll_stiffness_with_the_cross_pipe_open_is_the_anti_roll_bars(layout):
    # The car of two_point_twist.yaml standing on level track, isothermal bellows (k = inf: the
    # static limit), a 20 kN m roll moment applied at t = 0, the roll read as its mean over the
    # last 3 of 20 s (the dampers settle the sway in ~5 s).
    s = load_scenario(SCENARIOS / "two_point_twist.yaml", [f"circuit.layout={layout}", "twist.twist_per_mille=0",
                                                           "solver.jobs=1"], [float("inf")])
    cosim = build_cosimulation(s, [float("inf")], car_with_roll_moment)
    record, diagnosis = cosim.run(20.0, 0.02)
    assert diagnosis is None
    t, roll = np.asarray(record.t_s), record.arrays()["roll_rad"][:, 0]
    measured = roll[t > 17.0].mean()
    k_arb = s.vehicle.arb_roll_stiffness_N_m_per_rad
    # Two-point: the cross pipes keep each bogie's bellows at one pressure and their total volume
    # does not change in roll, so they resist none of it: the hand calculation with bellow
    # stiffness 0 (tests/vehicle/test_vehicle_components.py; 2 %, as there: what it leaves out is the
    # second-order tilt of the connectors' mid-frames; measured 0.01495 rad). Four-point: the
    # isothermal bellows add A^2 p / V_total each (bellow and tank, 39 dm3: 183 kN/m), so the car
    # rolls clearly less (measured 0.01203 rad; the hand calculation with 183 kN/m bellows gives
    # 0.01176, 2.2 % less, a difference not isolated here).
    arb_only = roll_hand_calculation(s.vehicle, 0.0, k_arb, M_N_m / 2)["phi_c"]
    if layout == "two_point":
        assert measured == pytest.approx(arb_only, rel=0.02)
    else:
        assert measured < 0.85 * arb_only
