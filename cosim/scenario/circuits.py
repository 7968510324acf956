"""The ``circuit`` section: the car's circuit (a layout, or explicit components) and the pieces a
rig circuit is made of (bellow, tank, pipe, with a preset under them), checked and assembled
once, so that an inconsistent circuit fails before any simulation."""
from __future__ import annotations

import dataclasses
from typing import Any, Dict, Mapping, NamedTuple, Sequence, Tuple

import numpy as np

from cosim.errors import ScenarioError
from cosim.scenario.model import CarCircuit
from cosim.scenario.schema import build, check_keys, coerce, describe, known_name, require
from pneumatics.air_supply import AirDemand, Compressor
from pneumatics.boundary import Supply
from pneumatics.chamber import Bellow, Tank
from pneumatics.circuit import COMPONENT_TYPES, Circuit, CircuitError
from pneumatics.faults import Fault
from pneumatics.layouts import BELLOWS, static_pressures
from pneumatics.pipe import Pipe
from pneumatics.presets import CIRCUIT_PRESETS
from pneumatics.valves import DifferentialPressureValve, LevellingValve


def with_preset(data: Mapping, file, sections: Sequence[str]) -> Dict[str, Any]:
    """``circuit: {preset: NAME, ...}``: the preset's bellow, tank and pipe (and, for a rig,
    ``p0_Pa``) under what the scenario writes, field by field; ``tank: null`` stays null."""
    if "preset" not in data:
        return dict(data)
    name = known_name(data["preset"], CIRCUIT_PRESETS, file, ["circuit", "preset"], "circuit preset")
    preset = CIRCUIT_PRESETS[name]()
    merged = {k: v for k, v in data.items() if k != "preset"}
    for key in sections:
        base = getattr(preset, key)
        if key == "p0_Pa":
            merged.setdefault(key, base)
            continue
        given = merged.get(key, {})
        if given is None or not isinstance(given, dict):
            continue                              # null (no tank) or an error build() reports
        fields = {k: v for k, v in dataclasses.asdict(base).items() if k not in ("a", "b", "p0_Pa", "T0_K")}
        merged[key] = {**fields, **given}
    return merged


def chambers_and_pipe(data: Mapping, file):
    """The bellow, the tank (``tank: null``: none) and the bellow-tank pipe of a circuit section;
    initial pressures come from elsewhere (rig ``p0_Pa``, or the car's static load)."""
    P = ["circuit"]
    bellow = build(Bellow, data.get("bellow"), file, P + ["bellow"], p0_Pa=None, T0_K=None)
    tank = optional(Tank, data, "tank", file, P, p0_Pa=None, T0_K=None)
    pipe = pipe_of(data.get("pipe"), file, P + ["pipe"])
    return bellow, tank, pipe


def pipe_of(data, file, where) -> Pipe:
    pipe = build(Pipe, data, file, where, a="", b="")
    check_pipe(pipe, file, where)
    return pipe


def check_pipe(pipe: Pipe, file, where) -> None:
    """The total loss coefficient lambda L/d + zeta of eq. (5) divides the quasi-steady flow: it
    must be > 0 (each term is >= 0 by the field rules); reported at ``zeta``, the key one sets. A
    compressible pipe may have none (its links' losses divide nothing)."""
    if pipe.model != "compressible" and not pipe.loss_coefficient > 0:
        raise ScenarioError(file, [*where, "zeta"], "the pressure-loss coefficient lambda L/d + zeta must be > 0 "
                                                    f"(friction_factor = {pipe.friction_factor or 0:g}, zeta = {pipe.zeta:g})")


def optional(cls, data: Mapping, key: str, file, prefix, **fixed):
    """``key: null`` means the component is absent; a missing key means its defaults."""
    if key in data and data[key] is None:
        return None
    return build(cls, data.get(key), file, [*prefix, key], **fixed)


LAYOUTS = ("four_point", "two_point")


def explicit_components(data: Mapping, file) -> Dict[str, object]:
    """``circuit.components``: name -> {type: bellow|tank|supply|pipe|orifice|levelling_valve|...,
    parameters...}; links name the nodes they join (``a``/``b``, ``bellow``, ``supply`` ...).
    The car's four bellows are put first, in the order FL, FR, RL, RR (the order the runners
    expect), whatever the order they are written in; the other components keep theirs."""
    comps = require(data, "components", file, ["circuit"], dict)
    out = {}
    for name, spec in comps.items():
        path = ["circuit", "components", str(name)]
        if not isinstance(spec, dict):
            raise ScenarioError(file, path, f"expected a mapping with a 'type', got {describe(spec)}")
        kind = require(spec, "type", file, path, str)
        if kind not in COMPONENT_TYPES:
            raise ScenarioError(file, path + ["type"], f"unknown component type {kind!r} "
                                                       f"(expected one of {', '.join(sorted(COMPONENT_TYPES))})")
        out[str(name)] = build(COMPONENT_TYPES[kind], {k: v for k, v in spec.items() if k != "type"}, file, path)
        if isinstance(out[str(name)], Pipe):
            check_pipe(out[str(name)], file, path)
    compile_check(out, file, ["circuit", "components"], {})
    missing = [b for b in BELLOWS if not isinstance(out.get(b), Bellow)]
    if missing:
        raise ScenarioError(file, ["circuit", "components"], f"the car needs bellows named {', '.join(BELLOWS)}; "
                                                             f"missing {', '.join(missing)}")
    extra = [n for n, c in out.items() if isinstance(c, Bellow) and n not in BELLOWS]
    if extra:
        raise ScenarioError(file, ["circuit", "components", extra[0]], f"the car has four bellows, "
                                                                       f"{', '.join(BELLOWS)}: another bellow has no "
                                                                       f"place on it (a chamber: type tank)")
    return {**{b: out[b] for b in BELLOWS}, **{n: c for n, c in out.items() if n not in BELLOWS}}


#: component names of a layout circuit (pneumatics.layouts) -> its key under ``circuit``
LAYOUT_KEYS = {**{b: "bellow" for b in BELLOWS}, **{f"tank_{b}": "tank" for b in BELLOWS},
                **{f"pipe_{b}": "pipe" for b in BELLOWS}, **{f"lv_{b}": "levelling_valve" for b in BELLOWS},
                "lv_F": "levelling_valve", "lv_R": "levelling_valve", "dpv_F": "differential_valve",
                "dpv_R": "differential_valve", "supply": "supply", "cross_F": "cross_pipe", "cross_R": "cross_pipe",
                "compressor": "compressor", "air_demand": "air_demand"}


def car_circuit(data: Mapping, file) -> CarCircuit:
    if "components" in data:
        check_keys(data, ("components",), file, ["circuit"])
        explicit = explicit_components(data, file)
        has_valves = any(isinstance(c, LevellingValve) for c in explicit.values())   # the outputs' valves on/off
        return CarCircuit("explicit", Bellow(), None, Pipe("", ""), has_valves, LevellingValve(""), None, Supply(), None,
                          tuple(explicit.items()))
    keys = ("preset", "layout", "bellow", "tank", "pipe", "valves", "levelling_valve", "differential_valve", "supply",
            "cross_pipe", "compressor", "air_demand")
    check_keys(data, keys, file, ["circuit"])
    data = with_preset(data, file, ("bellow", "tank", "pipe"))
    layout = coerce(data.get("layout", "four_point"), str, file, ["circuit", "layout"])
    if layout not in LAYOUTS:
        raise ScenarioError(file, ["circuit", "layout"], f"expected one of {', '.join(LAYOUTS)}, got {layout!r}")
    P = ["circuit"]
    bellow, tank, pipe = chambers_and_pipe(data, file)
    valves = coerce(data.get("valves", False), bool, file, P + ["valves"])
    if "levelling_valve" in data and data["levelling_valve"] is None:
        # null means "none" for tank, differential_valve and cross_pipe; a car's valve settings
        # connect levelling valves, so none cannot be meant here: refused, not read as the defaults
        raise ScenarioError(file, P + ["levelling_valve"], "null would mean no levelling valve, but the valve settings "
                                                           "connect them: write {} for the defaults, or run with the "
                                                           "valves disconnected (valve_settings: [false])")
    lv = build(LevellingValve, data.get("levelling_valve"), file, P + ["levelling_valve"],
               bellow="", supply="supply", sensed=())
    dpv = optional(DifferentialPressureValve, data, "differential_valve", file, P, a="", b="")
    supply = build(Supply, data.get("supply"), file, P + ["supply"])
    cross = pipe_of(data["cross_pipe"], file, P + ["cross_pipe"]) if data.get("cross_pipe") is not None else None
    if layout == "two_point" and cross is None:
        raise ScenarioError(file, P + ["cross_pipe"], "a two_point layout needs a cross_pipe between the bellows of a bogie")
    compressor = optional(Compressor, {"compressor": None, **data}, "compressor", file, P, reservoir="supply")
    demand = optional(AirDemand, {"air_demand": None, **data}, "air_demand", file, P, node="supply")
    if (compressor or demand) and supply.is_fixed:
        key = "compressor" if compressor else "air_demand"
        raise ScenarioError(file, P + [key], "needs a main reservoir that holds air: give circuit.supply a volume "
                                             "V_m3 (the default supply is a source at fixed pressure)")
    spec = CarCircuit(layout, bellow, tank, pipe, valves, lv, dpv, supply, cross, compressor=compressor, air_demand=demand)
    # both valve settings: the runs may switch the valves (twist/curve valve_settings)
    for setting in (valves, not valves):
        compile_check(dataclasses.replace(spec, valves=setting).components(), file, P, LAYOUT_KEYS)
    return spec


def compile_check(components, file, prefix, yaml_key_of) -> None:
    """Assemble once (cheap) so that inconsistent circuits fail before any simulation."""
    try:
        Circuit(components)
    except CircuitError as exc:
        raise circuit_error(exc, file, prefix, yaml_key_of) from None


def circuit_error(exc: CircuitError, file, prefix, yaml_key_of) -> ScenarioError:
    name, *rest = exc.path or ("",)
    return ScenarioError(file, [*prefix, yaml_key_of.get(name, name), *rest], exc.reason)


class InitialAir(NamedTuple):
    """A chamber's air when a run starts: absolute pressure [Pa] and temperature [K]."""

    chamber: str
    p_Pa: float
    T_K: float


def check_initial_state(circuit: CarCircuit, car, ks, valve_settings, path) -> Tuple[InitialAir, ...]:
    """Start the circuit once as the runners will (cars/runs: cosim.engine.cases.build_cosimulation):
    bellow pressures that carry the car's static load, tanks at their bellow's, every k value; an
    initial state that cannot be set (a chamber with no initial pressure, an isothermal chamber
    not at the atmosphere's temperature) fails here, not in a worker process. Returns every
    chamber's air at the start, in every valve setting (what the state limits must admit)."""
    explicit = circuit.explicit is not None
    prefix, keys = (["circuit", "components"], {}) if explicit else (["circuit"], LAYOUT_KEYS)
    air = []
    for setting in dict.fromkeys(valve_settings):
        components = circuit.components() if explicit else dataclasses.replace(circuit, valves=setting).components()
        try:
            c = Circuit(components, k_W_per_K=list(ks))
            x = c.initial_state(static_pressures(components, car.static_bellow_forces_N(), c.atmosphere.p_Pa))
        except CircuitError as exc:
            if exc.reason == "initial pressure is not set":
                exc.reason += " (give it p0_Pa, or join it to a bellow by a pipe or an orifice: it starts at the bellow's)"
            raise circuit_error(exc, path, prefix, keys) from None
        p, T = c.chamber_states(x, np.zeros((len(c.bellow_names),) + x.shape[1:]))      # every bellow at z = 0
        air += [InitialAir(name, float(p[i].max()), float(T[i].max())) for i, name in enumerate(c.chamber_names)]
    return tuple(air)


def parse_faults(value, file, circuit: CarCircuit, duration_s: float, valve_settings) -> Tuple[Fault, ...]:
    """``faults:``, a list of {kind, component, t_s, ...} (:mod:`pneumatics.faults`): each names a
    component of the circuit of the right type, with what its kind needs, and happens within
    the run, in every valve setting the scenario runs (a valve's fault needs the valves)."""
    if value is None:
        return ()
    if not isinstance(value, list):
        raise ScenarioError(file, ["faults"], f"expected a list of faults ({{kind, component, t_s, ...}}), got "
                                              f"{describe(value)}")
    faults = tuple(build(Fault, item, file, [f"faults[{i}]"]) for i, item in enumerate(value))
    for i, f in enumerate(faults):
        if not f.t_s < duration_s:
            raise ScenarioError(file, [f"faults[{i}]", "t_s"], f"the fault must happen within the run, before its end "
                                                               f"at {duration_s:g} s; got {f.t_s:g} s")
        _check_one_fault_at_a_time(faults, i, file)
    explicit = circuit.explicit is not None
    # the settings with the valves first: a name that is no component at all is then answered with
    # every component the runs have, the valves among them
    for setting in sorted(dict.fromkeys(valve_settings), reverse=True):
        components = circuit.components() if explicit else dataclasses.replace(circuit, valves=setting).components()
        try:
            Circuit(components, faults=faults)
        except CircuitError as exc:
            name = faults[int(exc.path[0][7:-1])].component if exc.path[0].startswith("faults[") else ""
            if (not setting and not explicit and name not in components
                    and name in dataclasses.replace(circuit, valves=True).components()):
                exc.reason = (f"{name!r} is part of the valves, which this scenario also runs isolated "
                              f"(valve_settings includes false): run with the valves connected only "
                              f"(valve_settings: [true])")
            raise ScenarioError(file, list(exc.path), exc.reason) from None
    return faults


#: fault kinds that open a chamber to the atmosphere: several at one instant are several openings
OPENINGS = ("burst", "leak")


def _check_one_fault_at_a_time(faults: Sequence[Fault], i: int, file) -> None:
    """Fault ``i`` may not set the state of a component an earlier fault sets at the same instant
    (stuck open and stuck closed, blocked and ruptured ...): the two would contradict each other,
    or one repeat the other, and which one holds would depend on their order in the list (of two
    at different times the later one holds). Openings (:data:`OPENINGS`) add up, and may coincide."""
    f = faults[i]
    for j, other in enumerate(faults[:i]):
        if (other.component == f.component and other.t_s == f.t_s and f.kind not in OPENINGS
                and other.kind not in OPENINGS):
            raise ScenarioError(file, [f"faults[{i}]"], f"faults[{j}] already makes {f.component!r} "
                                                        f"{other.kind.replace('_', ' ')} at {f.t_s:g} s: one fault of a "
                                                        f"component at a time (give this one another t_s, or remove "
                                                        f"one of them)")
