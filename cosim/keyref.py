"""The scenario key reference (``docs/scenario_keys.md``), generated from the dataclasses that
validate each section, so that it cannot drift from the code (``tests/test_docs.py`` fails when
the file is stale).

    python -m cosim.keyref > docs/scenario_keys.md
"""
from __future__ import annotations

import dataclasses
import inspect
import math
import typing

from cosim.scenario.model import (
    SolverSettings,
    StateLimits,
    VerifySettings,
)
from cosim.scenario.payload import PayloadSettings
from cosim.scenario.schema import _type_name, is_key, range_of
from pneumatics.air_supply import AirDemand, Compressor
from pneumatics.boundary import Supply
from pneumatics.chamber import Bellow, Tank
from pneumatics.faults import Fault
from pneumatics.heat_transfer import ChamberHeat
from pneumatics.orifice import Orifice
from pneumatics.pipe import Pipe
from pneumatics.valves import DifferentialPressureValve, LevellingValve, SafetyValve
from vehicle.params import TrackStructure, VehicleParams

#: (YAML section as written in a scenario, dataclass, note) of the car kinds' common sections and
#: the circuit's components; fields set by the layout (a bellow's name, a pipe's ends) are listed
#: too: they matter in ``circuit.components``. The kinds' own sections come from the registry.
CAR_SECTIONS = (
    ("solver", SolverSettings, "the car kinds"),
    ("verify", VerifySettings, "the car kinds: `pneumorail verify`"),
    ("state_limits", StateLimits, "the car kinds"),
    ("track", TrackStructure, "the car kinds: `rigid` (the default), `flexible` (preset `slab_track`), or "
                              "{model: flexible, preset: slab_track, FIELD: value}"),
    ("vehicle", VehicleParams, "the car kinds: a parameter file, or {file: ..., FIELD: value}"),
    ("faults[i]", Fault, "the car kinds: a list of faults, each {kind, component, t_s, ...}; kinds and what each "
                         "needs: docs/faults.md"),
    ("payload", PayloadSettings, "the car kinds but `stability`: passengers boarding and alighting; besides these "
                                 "keys `initial: {passengers | mass_kg | normal_fraction}` (uniform, on board at "
                                 "arrival) and `events: [{t_s, duration_s, passengers | mass_kg | normal_fraction, "
                                 "position}]`, position `uniform`, `front`, `rear`, `left`, `right`, `front_left` ... "
                                 "or `{x_m, y_m}`; sources and what is assumed: docs/payload.md"),
)
CIRCUIT_SECTIONS = (
    ("circuit.bellow", Bellow, "also `type: bellow` in circuit.components"),
    ("circuit.tank", Tank, "also `type: tank`; `tank: null` = no tank"),
    ("circuit.bellow.heat, circuit.tank.heat", ChamberHeat, "also `heat:` of a `type: bellow` or `type: tank` in "
                                                            "circuit.components; null (the default): the case's k "
                                                            "(`k_W_per_K`); equations, sources, validity and assumed "
                                                            "values: docs/models.md, \"Heat transfer per chamber\""),
    ("circuit.pipe, circuit.cross_pipe", Pipe, "also `type: pipe`; a, b: the nodes it joins; `cross_pipe: null` = none"),
    ("circuit.supply", Supply, "also `type: supply`"),
    ("circuit.levelling_valve", LevellingValve, "also `type: levelling_valve`; `{}`: the defaults; null is refused "
                                                "(the valve settings connect the valves: `valve_settings: [false]` runs "
                                                "without them)"),
    ("circuit.differential_valve", DifferentialPressureValve, "also `type: differential_valve`; null = none"),
    ("circuit.compressor", Compressor, "also `type: compressor`; fills the supply, which then needs a volume `V_m3`; "
                                       "absent: none (docs/models.md, \"The air supply\")"),
    ("circuit.air_demand", AirDemand, "also `type: air_demand`; draws from the supply (needs its `V_m3`); absent: none"),
    ("circuit.components: type: safety_valve", SafetyValve, "explicit circuits only"),
    ("circuit.components: type: orifice", Orifice, "explicit circuits only"),
)


def kind_sections():
    """(key, dataclass, note) of every kind's experiment section, and of the dataclasses nested in
    it (``curve.irregularity``)."""
    from cosim.kinds import KINDS
    out = []
    for kind in KINDS.values():
        out.append((kind.section, kind.experiment, f"kind: {kind.name}"))
        hints = typing.get_type_hints(kind.experiment)
        for f in filter(is_key, dataclasses.fields(kind.experiment)):
            nested = [t for t in (hints[f.name], *typing.get_args(hints[f.name])) if dataclasses.is_dataclass(t)]
            if nested:
                optional = type(None) in typing.get_args(hints[f.name])
                out.append((f"{kind.section}.{f.name}", nested[0],
                            f"kind: {kind.name}" + ("; null = none" if optional else "")))
    return tuple(out)


HEADER = """# Scenario key reference

Generated from the code by `python -m cosim.keyref > docs/scenario_keys.md` (a test fails when
this file is stale). Every key is optional unless the scenario kind needs it; a missing key takes
the default shown; a number must lie in the range shown (its reason in brackets: what the bounds rest
on; a value outside is refused, naming a likely unit slip such as bar for Pa or mm for m). Units
are in the names (SI: Pa absolute, K, kg, m, s, N, W/K). Top-level keys
of every scenario: `kind`, `name`, `description`, `k_W_per_K` (a list; `.inf` is isothermal),
`checks` (car scenarios: e.g. `dqq_max <= 0.6`, `dqq_max[3R] <= 0.6`, `dqq_max[k=0] <= 0.6`,
`yq_2m_p9985[zone=R<250] <= 1.2`; docs/assessment.md).
The rig kinds ({rig}) take `circuit: {{bellow, tank, pipe, p0_Pa}}` (`p0_Pa`: {p0}) and `test`; the car kinds
({car}) take `vehicle`, `track`, `circuit` (`layout: four_point | two_point`, `valves`, the
sections below, an explicit `components:` mapping of named components with a `type`, or an FMU:
`fmu: FILE.fmu` with `map:` its variables per bellow (`FL: {{crushing, rate, force, pressure,
temperature, crushing_end, rate_end, stiffness, force_rate}}`, ...), `air`, `k_W_per_K`, `isothermal`,
`pneumatic_step_s`, `pneumatic_step_used_s`, `lookahead`, `macro_step_s`, and `valves`; docs/fmi.md),
`solver`, `verify`, `state_limits`, `faults`, `payload` and their experiment ({sections}).
"""


def _default(field: dataclasses.Field) -> str:
    if field.default is not dataclasses.MISSING:
        value = field.default
    elif field.default_factory is not dataclasses.MISSING:  # type: ignore[misc]
        value = field.default_factory()  # type: ignore[misc]
    else:
        return "(required)"
    if isinstance(value, float) and math.isinf(value):
        return "`.inf`"
    if value is None:
        return "`null`"
    if isinstance(value, tuple):
        return "`[" + ", ".join(str(v).lower() if isinstance(v, bool) else str(v) for v in value) + "]`"
    if isinstance(value, bool):
        return f"`{str(value).lower()}`"
    return f"`{value}`"


def _allowed(cls, name: str, tp) -> str:
    """A number's range (its field's, or its unit suffix's: :func:`cosim.scenario.schema.range_of`),
    as the loader states it; empty for other values."""
    numeric = any(t in (int, float) for t in (tp, *typing.get_args(tp),
                                              *(a for t in typing.get_args(tp) for a in typing.get_args(t))))
    rule = range_of(cls, name) if numeric else None
    if rule is None:
        return ""
    default = {f.name: f.default for f in dataclasses.fields(cls)}[name]
    infinite = isinstance(default, float) and math.isinf(default) and not rule.zero_or_inf
    return ("`.inf` or " if infinite else "") + rule.expected(tp is int)      # .inf: where the default is (schema.build)


def section(key: str, cls, note: str) -> str:
    hints = typing.get_type_hints(cls)
    doc = inspect.cleandoc(cls.__doc__ or "").split("\n\n")[0].replace("\n", " ")
    lines = [f"## `{key}` ({cls.__name__})", "", f"{note}. {doc}", "", "| key | type | default | allowed |",
             "| --- | --- | --- | --- |"]
    for f in filter(is_key, dataclasses.fields(cls)):
        lines.append(f"| `{f.name}` | {_type_name(hints[f.name])} | {_default(f)} | {_allowed(cls, f.name, hints[f.name])} |")
    return "\n".join(lines) + "\n"


def header() -> str:
    """:data:`HEADER` with the registry's kinds (:data:`cosim.kinds.KINDS`)."""
    from cosim.kinds import KINDS
    car = [k for k in KINDS.values() if k.car]
    from cosim.kinds.rig import RigCircuit
    return HEADER.format(rig=", ".join(f"`{k.name}`" for k in KINDS.values() if not k.car),
                         p0=range_of(RigCircuit, "p0_Pa").expected(),
                         car=", ".join(f"`{k.name}`" for k in car),
                         sections=", ".join(f"`{k.section}`" for k in car))


def reference() -> str:
    return header() + "".join("\n" + section(*s) for s in (*kind_sections(), *CAR_SECTIONS, *CIRCUIT_SECTIONS))


if __name__ == "__main__":
    print(reference(), end="")
