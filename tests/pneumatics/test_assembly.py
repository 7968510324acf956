"""The circuit's assembly (pneumatics.assembly) and its runtime (pneumatics.runtime): the links
follow the table of link types, the compiled arrays cannot be changed by what evaluates them,
and a circuit is its runtime built from its components."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pneumatics.air_supply import AirDemand, Compressor
from pneumatics.assembly import assemble
from pneumatics.assembly.link_types import LINK_TYPES
from pneumatics.boundary import Supply
from pneumatics.chamber import Bellow, Tank
from pneumatics.circuit import Circuit, CircuitError
from pneumatics.faults import Fault
from pneumatics.orifice import Orifice
from pneumatics.pipe import Pipe
from pneumatics.runtime import CircuitRuntime
from pneumatics.valves import DifferentialPressureValve, LevellingValve, SafetyValve


def every_link_type() -> dict:
    """A circuit with a link of every type (components given in an order unlike the links')."""
    return {"lv": LevellingValve("A", lag_s=0.5, delay_s=0.2, delay_stages=2, hysteresis_m=0.001),
            "A": Bellow(p0_Pa=4e5), "B": Bellow(p0_Pa=4e5), "tank": Tank(p0_Pa=4e5), "supply": Supply(),
            "dpv": DifferentialPressureValve("A", "B"), "throttle": Orifice("B", "tank", 1e-9),
            "steady": Pipe("A", "tank", model="quasi_steady"), "pipe": Pipe("B", "tank"), "safety": SafetyValve("B"),
            "brakes": AirDemand(node="tank"), "compressor": Compressor(reservoir="tank")}


FAULTS = (Fault("burst", "A", 1.0, area_m2=1e-4), Fault("ruptured", "pipe", 2.0))


def test_the_links_follow_the_table_of_link_types():
    assembly = assemble(every_link_type(), faults=FAULTS)
    expected = {"pipe": ["pipe"], "quasi_steady_pipe": ["steady"], "orifice": ["throttle"],
                "fault_opening": ["A.burst", "pipe.ruptured@B", "pipe.ruptured@tank"], "differential": ["dpv"],
                "valve_supply": ["lv.supply", "safety.supply"], "valve_exhaust": ["lv.exhaust", "safety.exhaust"],
                "compressor": ["compressor"], "air_demand": ["brakes"]}
    assert [t.key for t in LINK_TYPES] == list(expected)
    links = assembly.links
    assert [list(links.names[links.rows[key]]) for key in expected] == list(expected.values())
    assert list(links.names) == sum(expected.values(), [])
    assert assembly.fault_links == links.rows["fault_opening"]


def test_each_link_type_checks_its_own_values():
    with pytest.raises(CircuitError) as err:
        assemble({**every_link_type(), "throttle": Orifice("B", "tank", 1e-9, b_critical=1.0)})
    assert err.value.path == ("throttle", "b_critical")
    with pytest.raises(CircuitError) as err:
        assemble({**every_link_type(), "safety": SafetyValve("B", exhaust_C_m3_per_sPa=(0.0, -1.0, 0.0))})
    assert err.value.path == ("safety", "exhaust_C_m3_per_sPa")
    with pytest.raises(CircuitError) as err:
        assemble({**every_link_type(), "lv": LevellingValve("tank")})
    assert err.value.path == ("lv", "bellow")


def _arrays(value, where="assembly"):
    """(where, array) for every numpy array the compiled value holds, however deep."""
    if isinstance(value, np.ndarray):
        yield where, value
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        for field in dataclasses.fields(value):
            yield from _arrays(getattr(value, field.name), f"{where}.{field.name}")
    elif isinstance(value, (tuple, list)):
        for i, item in enumerate(value):
            yield from _arrays(item, f"{where}[{i}]")
    elif hasattr(value, "items"):
        for key, item in value.items():
            yield from _arrays(item, f"{where}[{key!r}]")


def test_the_compiled_arrays_are_read_only():
    circuit = Circuit(every_link_type(), k_W_per_K=[0.0, np.inf], faults=FAULTS, active_faults=[1])
    found = dict(_arrays(circuit.assembly))
    assert "assembly.links.incidence" in found and "assembly.valves.lever" in found
    assert [where for where, array in found.items() if array.flags.writeable] == []
    x = circuit.initial_state()
    z = np.full((2, 2), 0.01)
    dx = circuit.derivatives(x, z, z)                 # the runtime reads them and writes only its own arrays
    assert dx.shape == x.shape and np.all(np.isfinite(dx))


def test_a_circuit_is_its_runtime_built_from_its_components():
    comps = every_link_type()
    circuit = Circuit(comps, k_W_per_K=5.0, faults=FAULTS)
    runtime = CircuitRuntime(assemble(comps, k_W_per_K=5.0, faults=FAULTS))
    assert isinstance(circuit, CircuitRuntime)
    x = circuit.initial_state()
    z = np.array([0.01, -0.02])
    assert np.array_equal(circuit.derivatives(x, z, z), runtime.derivatives(x, z, z))
    assert circuit.link_names == runtime.link_names and circuit.layout == runtime.layout
    faulty = circuit.with_active_faults([0])
    assert faulty.layout == circuit.layout and faulty.active_faults == frozenset({0})
    burst = 1                                         # fixed orifices first (the throttle), then the openings
    assert circuit.assembly.orifice_links.fixed_C_m3_per_sPa[burst, 0] == 0.0      # shut until it happens
    assert faulty.assembly.orifice_links.fixed_C_m3_per_sPa[burst, 0] > 0.0
