"""Every number a scenario can give has a range, declared next to its field (or by its unit
suffix): a new numeric field without one fails here. Each default lies in its field's range (a
range that refused the value a field starts with could not be the physical one), and a value
out of range written in a likely wrong unit names the slip."""
from __future__ import annotations

import dataclasses
import math
import typing

import pytest

from cosim.keyref import CAR_SECTIONS, CIRCUIT_SECTIONS, kind_sections
from cosim.kinds.rig import RigCircuit
from cosim.scenario.schema import range_of, unit_slip
from pneumorail.quantities import Range, plausible, range_of_field
from vehicle.params import TRACK_PRESETS, TrackStructure

NUMBERS = (int, float)


def _parsed_dataclasses():
    """Every dataclass a scenario's YAML is read into: the sections of the key reference (every
    kind's experiment and what it nests, the car kinds' common sections, the circuit's
    components), the rig's circuit, and every dataclass their fields hold."""
    todo = [cls for _, cls, _ in (*kind_sections(), *CAR_SECTIONS, *CIRCUIT_SECTIONS)] + [RigCircuit]
    seen = []
    while todo:
        cls = todo.pop()
        if cls in seen:
            continue
        seen.append(cls)
        for tp in typing.get_type_hints(cls).values():
            todo += [t for t in (tp, *typing.get_args(tp)) if dataclasses.is_dataclass(t)]
    return seen


def _is_number(tp) -> bool:
    """int, float, Optional of one, or a tuple of them."""
    if tp in NUMBERS:
        return True
    return any(_is_number(a) for a in typing.get_args(tp) if a is not type(None) and a is not Ellipsis)


def _numeric_fields():
    return [(cls, f) for cls in _parsed_dataclasses() for f in dataclasses.fields(cls) if f.init
            and _is_number(typing.get_type_hints(cls)[f.name])]


FIELDS = _numeric_fields()


def test_the_walk_reaches_every_section():
    names = {cls.__name__ for cls in _parsed_dataclasses()}
    assert {"TwistTest", "CurveTest", "IrregularitySpec", "RideTest", "StabilityTest", "RampTest", "SineTest",
            "StiffnessTest", "QuasiStaticTest", "Bellow", "Tank", "Pipe", "Supply", "Orifice", "LevellingValve",
            "SafetyValve", "DifferentialPressureValve", "Fault", "StateLimits", "SolverSettings", "VerifySettings",
            "VehicleParams", "TrackStructure", "RigCircuit"} <= names
    assert len(FIELDS) > 150


@pytest.mark.parametrize("cls, f", FIELDS, ids=[f"{cls.__name__}.{f.name}" for cls, f in FIELDS])
def test_every_numeric_field_has_a_range(cls, f):
    # declare one next to the field: field(default=..., metadata=plausible(low, high, unit, why))
    assert range_of(cls, f.name) is not None, f"{cls.__name__}.{f.name} has no range"


def _defaults(cls, f):
    """The values a field starts with: its default (a flexible track's: the presets', a rigid one
    has none to check), each item of a list."""
    if cls is TrackStructure:
        values = [getattr(preset(), f.name) for preset in TRACK_PRESETS.values() if preset().flexible]
    elif f.default is not dataclasses.MISSING:
        values = [f.default]
    elif f.default_factory is not dataclasses.MISSING:
        values = [f.default_factory()]
    else:
        values = []
    items = [v for value in values for v in (value if isinstance(value, tuple) else (value,))]
    # None: the field is unset; an infinite default means something (no mounting spring, a fixed reservoir)
    return [v for v in items if v is not None and not (isinstance(v, float) and math.isinf(v))]


@pytest.mark.parametrize("cls, f", FIELDS, ids=[f"{cls.__name__}.{f.name}" for cls, f in FIELDS])
def test_every_default_lies_in_its_range(cls, f):
    rule = range_of(cls, f.name)
    refused = [v for v in _defaults(cls, f) if not rule.admits(v)]
    assert not refused, f"{cls.__name__}.{f.name}: {refused} outside {rule.expected()}"


def test_a_subclass_that_changes_a_default_keeps_the_range():
    from pneumatics.valves import LevellingValve, SafetyValve
    for name in ("supply_lever_m", "exhaust_C_m3_per_sPa", "b_critical"):
        assert range_of(SafetyValve, name) == range_of(LevellingValve, name) is not None


def test_metadata_is_read_before_the_suffix_rule():
    @dataclasses.dataclass
    class Probe:
        length_m: float = dataclasses.field(default=1.0, metadata=plausible(0.5, 2.0, "m", "a probe"))
        volume_m3: float = 1.0

    assert range_of(Probe, "length_m") == range_of_field(dataclasses.fields(Probe)[0]) == Range(0.5, 2.0, unit="m",
                                                                                                 why="a probe")
    assert range_of(Probe, "volume_m3").expected() == "> 0 m^3"          # the suffix rule


@pytest.mark.parametrize("value, rule, hint", [
    (26, Range(2e3, 1.5e5, unit="kg"), "; tonnes? (26 tonnes = 26000 kg)"),
    (40000, Range(0, 1000, False, True, "m"), "; millimetres? (40000 millimetres = 40 m)"),
    (0.25, Range(10, 1e5, unit="m"), "; kilometres? (0.25 kilometres = 250 m)"),
    (8, Range(2e4, 2e6, unit="Pa absolute"), "; bar? (8 bar = 800000 Pa absolute)"),
    (6, Range(-0.2, 0.2, unit="rad"), "; degrees? (6 degrees = 0.10472 rad)"),
    (300000, Range(0, 3600, False, True, "s"), "; milliseconds? (300000 milliseconds = 300 s)"),
    (144.8, Range(1e6, 1e10, unit="N/m"), "; MN/m? (144.8 MN/m = 1.448e+08 N/m)"),
    (20, Range(200, 400, unit="K"), "; degrees Celsius? (20 degrees Celsius = 293.15 K)"),
    (15, Range(1e-3, 1.0, unit="m^3"), "; litres? (15 litres = 0.015 m^3)"),
    (-5, Range(10, 1e5, unit="m"), ""),                  # no unit makes it a radius
])
def test_a_likely_unit_slip_is_named(value, rule, hint):
    assert unit_slip(value, rule) == hint
