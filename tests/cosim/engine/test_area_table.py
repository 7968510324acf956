"""A bellow's effective area given as a table of crushing: the force and the stiffness
the coupling uses follow the table; a table that restates the linear law changes nothing."""
from __future__ import annotations

import numpy as np
import pytest

from cosim.errors import ScenarioError
from cosim.load import load_scenario
from pneumatics.chamber import Bellow
from pneumatics.circuit import Circuit, CircuitError
from pneumatics.rig import ramp_motion, run_time_series

from helpers import SCENARIOS

P0_PA = 4.0e5
TABLE = dict(area_table_z_m=(-0.06, -0.02, 0.0, 0.03, 0.08), area_table_m2=(0.118, 0.126, 0.13, 0.138, 0.16))


def closed_bellow(**fields):
    return Circuit({"bellow": Bellow(p0_Pa=P0_PA, **fields)}, k_W_per_K=0.0)


def test_a_table_restating_the_linear_law_changes_nothing():
    linear = closed_bellow(A0_m2=0.13, dA_dz_m=0.25)
    table = closed_bellow(area_table_z_m=(-0.1, 0.1), area_table_m2=(0.13 - 0.025, 0.13 + 0.025))
    x = linear.initial_state()
    assert np.array_equal(x, table.initial_state())
    for z in np.linspace(-0.05, 0.05, 11):
        zz = np.array([z])
        # same law, evaluated by interpolation instead of A0 + dA/dz z: equal to round-off
        assert table.bellow_forces_N(x, zz) == pytest.approx(linear.bellow_forces_N(x, zz), rel=1e-12)
        assert table.bellow_stiffness_N_per_m(x, zz) == pytest.approx(linear.bellow_stiffness_N_per_m(x, zz),
                                                                        rel=1e-12)


def test_force_follows_the_table_and_the_stiffness_is_its_derivative():
    # Adiabatic closed bellow, slow 60 mm ramp (LSODA, error-controlled): the force is
    # A_table(z) (p(z) - p_atm) with p = p0 (V0 / V(z))^gamma, and the stiffness the coupling
    # uses is its derivative (central difference of the analytic force, h = 1e-6 m).
    b = Bellow(p0_Pa=P0_PA, **TABLE)
    ts = run_time_series({"bellow": b}, 0.0, ramp_motion(0.06, 1.0), 1.0, 61)
    gamma, p_atm = 1.4, 101325.0
    p = P0_PA * (b.V0_m3 / b.volume_m3(ts.z_m)) ** gamma
    expected = b.area_m2(ts.z_m) * (p - p_atm)
    # rtol 1e-8 of the integrator, and the rig's gas constants: 1e-6
    assert ts.force_N == pytest.approx(expected, rel=1e-6)
    c = closed_bellow(**TABLE)
    x = c.initial_state()
    for z in (-0.04, 0.01, 0.05):              # inside intervals (the slope jumps at the points)
        h = 1e-6
        def force(zz):
            V = b.volume_m3(zz)
            return b.area_m2(zz) * (P0_PA * (b.V0_m3 / V) ** gamma - p_atm)
        numeric = (force(z + h) - force(z - h)) / (2 * h)
        # the circuit's state x is at z = 0; move the air adiabatically to z first
        assert c.bellow_stiffness_N_per_m(_state_at(c, x, z), np.array([z]))[0] == pytest.approx(numeric, rel=1e-6)


def _state_at(c, x, z):
    """The closed bellow's state compressed adiabatically from z = 0 to z (same mass, T from
    T0 (V0/V)^(gamma - 1))."""
    b = c.components["bellow"]
    x = x.copy()
    lay = c.layout
    x[lay.T] = x[lay.T] * (b.V0_m3 / b.volume_m3(z)) ** 0.4
    return x


@pytest.mark.parametrize("fields, key", [
    (dict(area_table_z_m=(0.0, 0.1), area_table_m2=(0.13,)), "area_table_m2"),
    (dict(area_table_z_m=(0.1, 0.0), area_table_m2=(0.13, 0.14)), "area_table_z_m[1]"),
    (dict(area_table_z_m=(0.0, 0.1), area_table_m2=(0.13, -0.1)), "area_table_m2[1]"),
])
def test_a_bad_table_is_refused_naming_the_entry(fields, key):
    with pytest.raises(CircuitError) as info:
        closed_bellow(**fields)
    assert ".".join(info.value.path) == f"bellow.{key}"


def test_a_scenario_takes_the_table_and_names_a_bad_entry():
    s = load_scenario(SCENARIOS / "twist_dqq.yaml", ["circuit.bellow.area_table_z_m=[-0.05, 0.05]",
                                                     "circuit.bellow.area_table_m2=[0.125, 0.135]"])
    assert s.circuit.bellow.area_m2(0.0) == pytest.approx(0.13)
    with pytest.raises(ScenarioError) as info:
        load_scenario(SCENARIOS / "twist_dqq.yaml", ["circuit.bellow.area_table_z_m=[-0.05, 0.05]",
                                                     "circuit.bellow.area_table_m2=[0.125, 0]"])
    assert info.value.path.startswith("circuit.bellow.area_table_m2")
