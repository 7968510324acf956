"""Scenario files: load (a stricter ``yaml.SafeLoader``, :mod:`cosim.yaml_input`), apply ``--set`` overrides, validate everything
before any simulation starts, and build the typed scenario the runners consume.

A scenario is a YAML mapping with a ``kind``:

* ``rig_ramp``, ``rig_sine``, ``rig_stiffness``, ``rig_table2``: the bellow-tank virtual test
  rig (paper §3) with a ``circuit`` of ``bellow``, ``tank`` (null: bellow alone), ``pipe``,
  ``p0_Pa`` and a ``test`` section;
* ``twist``: the metro car on the EN 14363 twist (paper §4.1) with ``vehicle``, a car
  ``circuit``, ``twist``, ``solver`` and ``checks``;
* ``curve_entry``: the car running into a curve (paper §4.2) with ``vehicle``, ``circuit``,
  ``curve``, ``solver`` and ``checks``.

Every error names the file, the key path and what was expected (:class:`ScenarioError`).
"""
from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple

from pneumatics.boundary import Supply
from pneumatics.chamber import Bellow, Tank
from pneumatics.circuit import COMPONENT_TYPES, Circuit, CircuitError
from pneumatics.layouts import BELLOWS
from pneumatics.pipe import Pipe
from pneumatics.valves import DifferentialPressureValve, LevellingValve
from vehicle.params import WHEELS, VehicleParams

from .checks import parse_checks
from .experiments import (CAR_KINDS, KINDS, RIG_KINDS, RIG_TESTS, CarCircuit, CurveTest, QuasiStaticTest, RampTest,
                          RigCircuit, Scenario, SineTest, SolverSettings, StiffnessTest, TwistTest, VerifySettings)
from .master import COUPLINGS
from .schema import ScenarioError, build, check_keys, coerce, k_values, require
from .yaml_input import parse_yaml, read_yaml

__all__ = ["load_scenario", "apply_overrides", "load_yaml", "CAR_KINDS", "RIG_KINDS", "KINDS"]

def load_yaml(path: Path) -> Any:
    """(data, text) of a scenario or parameter file, read strictly (see :mod:`cosim.yaml_input`)."""
    return read_yaml(path)


def apply_overrides(data: Dict[str, Any], overrides: Sequence[str], file) -> Dict[str, Any]:
    """``key.path=value`` (value parsed as YAML) into a copy of ``data``."""
    import copy
    data = copy.deepcopy(data)
    for item in overrides:
        if "=" not in item:
            raise ScenarioError(file, ["--set"], f"expected key.path=value, got {item!r}")
        key, value = item.split("=", 1)
        parts = key.strip().split(".")
        if not all(parts):
            raise ScenarioError(file, ["--set"], f"expected key.path=value with a non-empty key path, got {item!r}")
        node = data
        for i, p in enumerate(parts[:-1]):
            if not isinstance(node.get(p), dict):
                if p in node:
                    raise ScenarioError(file, parts[: i + 1], "--set cannot descend into a value that is not a mapping")
                node[p] = {}
            node = node[p]
        node[parts[-1]] = parse_yaml(value, file, ["--set", key.strip()])
    return data


def load_scenario(path, overrides: Sequence[str] = (), k_override: Optional[Sequence[float]] = None) -> Scenario:
    """Read and validate a scenario file; raises :class:`ScenarioError` before anything runs."""
    path = Path(path)
    data, text = load_yaml(path)
    if not isinstance(data, dict):
        raise ScenarioError(path, [], f"expected a mapping at the top level, got {type(data).__name__}")
    if isinstance(data.get("vehicle"), str) and any(o.strip().startswith("vehicle.") for o in overrides):
        data = {**data, "vehicle": {"file": data["vehicle"]}}  # a parameter file, then single fields on top
    data = apply_overrides(data, overrides, path)
    kind = require(data, "kind", path, [], str)
    if kind not in KINDS:
        raise ScenarioError(path, ["kind"], f"unknown kind {kind!r} (expected one of {', '.join(KINDS)})")
    common = dict(file=path, kind=kind, name=str(data.get("name", path.stem)),
                  description=str(data.get("description", "")),
                  k_W_per_K=k_values(list(k_override), path, ["--k"]) if k_override else k_values(require(data, "k_W_per_K", path, []), path, ["k_W_per_K"]),
                  content_sha256=hashlib.sha256(text.encode()).hexdigest(), overrides=tuple(overrides), raw=data,
                  files_sha256=_files_read(path, data))
    if kind in RIG_KINDS:
        check_keys(data, ("kind", "name", "description", "k_W_per_K", "circuit", "test"), path, [])
        rig = _rig_circuit(require(data, "circuit", path, [], dict), path)
        test = build(RIG_TESTS[kind], data.get("test"), path, ["test"])
        if isinstance(test, RampTest):
            for i, c in enumerate(test.configurations):
                if c not in ("bellow_tank", "bellow_only"):
                    raise ScenarioError(path, ["test", f"configurations[{i}]"], "expected bellow_tank or bellow_only")
        stroke = rig.bellow.V0_m3 / rig.bellow.dV_dz_m2
        if isinstance(test, (RampTest, SineTest, StiffnessTest, QuasiStaticTest)) and not abs(test.amplitude_m) < stroke:
            raise ScenarioError(path, ["test", "amplitude_m"], f"|amplitude| must be below V0/(dV/dz) = {stroke:.4g} m, "
                                                               f"where the bellow volume vanishes; got {test.amplitude_m}")
        if isinstance(test, StiffnessTest) and any(f <= 0 for f in test.frequencies_Hz):
            raise ScenarioError(path, ["test", "frequencies_Hz"], "frequencies must be > 0 Hz")
        return Scenario(**common, rig=rig, test=test)

    experiment = "twist" if kind == "twist" else "curve"
    check_keys(data, ("kind", "name", "description", "k_W_per_K", "vehicle", "circuit", experiment, "solver", "verify",
                      "checks"), path, [])
    vehicle = _vehicle(data.get("vehicle"), path)
    _check_car_builds(vehicle, data.get("vehicle"), path)
    circuit = _car_circuit(require(data, "circuit", path, [], dict), path)
    solver = build(SolverSettings, data.get("solver"), path, ["solver"])
    if solver.coupling not in COUPLINGS:
        raise ScenarioError(path, ["solver", "coupling"], f"expected one of {COUPLINGS}, got {solver.coupling!r}")
    if kind == "twist":
        tests = {"twist": _twist(data.get("twist"), vehicle, path)}
        duration = tests["twist"].duration_s
        valve_settings = tests["twist"].valve_settings or (circuit.valves,)
    else:
        tests = {"curve": _curve(data.get("curve"), vehicle, path)}
        duration = tests["curve"].duration_s
        valve_settings = tests["curve"].valve_settings
    if circuit.explicit is not None and len(set(valve_settings)) > 1:
        raise ScenarioError(path, [experiment, "valve_settings"], "an explicit circuit (circuit.components) has no "
                                                                  "valves switch: give a single setting")
    _check_steps(solver, duration, path)
    verify = build(VerifySettings, data.get("verify"), path, ["verify"])
    if not verify.tolerance > 0:
        raise ScenarioError(path, ["verify", "tolerance"], f"expected a relative error > 0, got {verify.tolerance}")
    if verify.levels < 2:
        raise ScenarioError(path, ["verify", "levels"], f"Richardson extrapolation needs at least 2 halvings, got {verify.levels}")
    checks = parse_checks(data.get("checks", []), kind, path, common["k_W_per_K"], valve_settings)
    return Scenario(**common, vehicle=vehicle, circuit=circuit, solver=solver, verify=verify, checks=checks, **tests)


def _files_read(path: Path, data: Mapping) -> Tuple[Tuple[str, str], ...]:
    """(path relative to the scenario file, sha256) of the scenario and the vehicle parameter file."""
    vehicle = data.get("vehicle")
    vehicle = vehicle.get("file") if isinstance(vehicle, dict) else vehicle
    files = [path] + ([path.parent / vehicle] if isinstance(vehicle, str) else [])
    return tuple((str(f.relative_to(path.parent)) if f.is_relative_to(path.parent) else str(f),
                  hashlib.sha256(f.read_bytes()).hexdigest()) for f in files if f.is_file())


def _check_steps(solver: SolverSettings, duration_s: float, path) -> None:
    """The run and its output interval must be whole numbers of macro-steps (nothing is rounded
    silently), and the multibody step no longer than the macro-step."""
    H = solver.macro_step_s
    for key, value in (("output_interval_s", solver.output_interval_s), ("duration", duration_s)):
        n = value / H
        if abs(n - round(n)) > 1e-6 * max(n, 1.0) or round(n) < 1:
            where = ["solver", key] if key != "duration" else ["solver", "macro_step_s"]
            raise ScenarioError(path, where, f"the {key.replace('_s', '')} ({value:g} s) must be a whole number of "
                                             f"macro-steps ({H:g} s)")
    if solver.mechanics_step_s > H * (1 + 1e-9):
        raise ScenarioError(path, ["solver", "mechanics_step_s"], f"must not exceed the macro-step ({H:g} s)")
    if solver.jobs < 1:
        raise ScenarioError(path, ["solver", "jobs"], f"expected at least 1 process, got {solver.jobs}")


def _twist(data, vehicle: VehicleParams, path) -> TwistTest:
    twist = build(TwistTest, data, path, ["twist"])
    for i, w in enumerate(twist.raised_wheels):
        if w not in WHEELS:
            raise ScenarioError(path, ["twist", f"raised_wheels[{i}]"], f"unknown wheel {w!r} (wheels: {', '.join(WHEELS)})")
    if twist.window_s is not None and twist.window_s > twist.hold_s:
        raise ScenarioError(path, ["twist", "window_s"], f"the final window must lie within the hold "
                                                         f"(hold_s = {twist.hold_s:g} s), got {twist.window_s:g} s")
    if not twist.settle_drift > 0:
        raise ScenarioError(path, ["twist", "settle_drift"], f"must be > 0 (a drift of ΔQ/Q0), got {twist.settle_drift}")
    _valve_settings(twist.valve_settings, path, ["twist", "valve_settings"])
    if twist.bogie_twist_per_mille is not None and twist.bogie_base_m is None:
        raise ScenarioError(path, ["twist", "bogie_twist_per_mille"], "a bogie twist needs its base: set bogie_base_m "
                                                                      "(the wheelbase 2a+)")
    if twist.bogie_base_m is not None:
        # the rails are twisted about the real wheel positions: the bases must be the car's
        for key, value, name, actual in (("bogie_base_m", twist.bogie_base_m, "vehicle.wheelbase_m", vehicle.wheelbase_m),
                                         ("base_m", twist.base_m, "vehicle.bogie_centre_distance_m",
                                          vehicle.bogie_centre_distance_m)):
            if abs(value - actual) > 1e-9 * actual:
                raise ScenarioError(path, ["twist", key], f"with a bogie twist the bases are the car's: expected "
                                                          f"{name} = {actual:g} m, got {value:g} m")
        side = twist.raised_wheels[0][-1] if twist.raised_wheels else ""
        if sorted(twist.raised_wheels) != [f"1{side}", f"2{side}"]:
            raise ScenarioError(path, ["twist", "raised_wheels"], "a bogie twist (bogie_base_m) twists one side of the "
                                                                  "front bogie: expected [1R, 2R] or [1L, 2L], got "
                                                                  f"{list(twist.raised_wheels)}")
    return twist


def _valve_settings(settings, path, where) -> None:
    if settings is None:
        return
    if not settings:
        raise ScenarioError(path, where, "expected at least one setting (false: valves isolated, true: connected)")
    if len(set(settings)) != len(settings):
        raise ScenarioError(path, where, f"each setting at most once, got {list(settings)}")


def _curve(data, vehicle: VehicleParams, path) -> CurveTest:
    curve = build(CurveTest, data, path, ["curve"])
    if curve.direction not in (1, -1):
        raise ScenarioError(path, ["curve", "direction"], f"expected 1 (left) or -1 (right), got {curve.direction}")
    if not curve.speed_m_per_s > 0:
        raise ScenarioError(path, ["curve", "speed_m_per_s"], f"must be > 0 m/s, got {curve.speed_m_per_s}")
    for name in ("straight_m", "transition_m", "radius_m", "arc_m"):
        if not getattr(curve, name) > 0:
            raise ScenarioError(path, ["curve", name], f"must be > 0 m, got {getattr(curve, name)}")
    car_length = vehicle.bogie_centre_distance_m + vehicle.wheelbase_m
    if curve.straight_m < car_length:
        raise ScenarioError(path, ["curve", "straight_m"], f"the straight must hold the whole car ({car_length:g} m "
                                                           f"between the outer wheelsets), got {curve.straight_m:g} m")
    if curve.window_s is not None and curve.window_s > curve.duration_s:
        raise ScenarioError(path, ["curve", "window_s"], f"the final window must lie within the run "
                                                         f"(duration_s = {curve.duration_s:g} s), got {curve.window_s:g} s")
    _valve_settings(curve.valve_settings, path, ["curve", "valve_settings"])
    on_track = (curve.straight_m + curve.transition_m + curve.arc_m - car_length) / curve.speed_m_per_s
    if curve.duration_s > on_track:
        raise ScenarioError(path, ["curve", "duration_s"], f"the front wheelset leaves the track at t = {on_track:.3g} s; "
                                                           f"lengthen arc_m or shorten duration_s")
    return curve


def _chambers_and_pipe(data: Mapping, file):
    """The bellow, the tank (``tank: null``: none) and the bellow-tank pipe of a circuit section;
    initial pressures come from elsewhere (rig ``p0_Pa``, or the car's static load)."""
    P = ["circuit"]
    bellow = build(Bellow, data.get("bellow"), file, P + ["bellow"], p0_Pa=None, T0_K=None)
    tank = _optional(Tank, data, "tank", file, P, p0_Pa=None, T0_K=None)
    pipe = build(Pipe, data.get("pipe"), file, P + ["pipe"], a="", b="")
    return bellow, tank, pipe


def _optional(cls, data: Mapping, key: str, file, prefix, **fixed):
    """``key: null`` means the component is absent; a missing key means its defaults."""
    if key in data and data[key] is None:
        return None
    return build(cls, data.get(key), file, [*prefix, key], **fixed)


def _rig_circuit(data: Mapping, file) -> RigCircuit:
    check_keys(data, ("bellow", "tank", "pipe", "p0_Pa"), file, ["circuit"])
    bellow, tank, pipe = _chambers_and_pipe(data, file)
    p0 = coerce(require(data, "p0_Pa", file, ["circuit"]), float, file, ["circuit", "p0_Pa"])
    if not p0 > 0:
        raise ScenarioError(file, ["circuit", "p0_Pa"], f"absolute pressure must be > 0 Pa, got {p0}")
    rig = RigCircuit(bellow, tank, pipe, p0)
    _compile_check(rig.components(tank is not None), file, ["circuit"], {"bellow": "bellow", "tank": "tank", "pipe": "pipe"})
    return rig


LAYOUTS = ("four_point", "two_point")


def _explicit_components(data: Mapping, file) -> Dict[str, object]:
    """``circuit.components``: name -> {type: bellow|tank|supply|pipe|orifice|levelling_valve|...,
    parameters...}; links name the nodes they join (``a``/``b``, ``bellow``, ``supply`` ...)."""
    comps = require(data, "components", file, ["circuit"], dict)
    out = {}
    for name, spec in comps.items():
        path = ["circuit", "components", str(name)]
        if not isinstance(spec, dict):
            raise ScenarioError(file, path, f"expected a mapping with a 'type', got {type(spec).__name__}")
        kind = require(spec, "type", file, path, str)
        if kind not in COMPONENT_TYPES:
            raise ScenarioError(file, path + ["type"], f"unknown component type {kind!r} "
                                                       f"(expected one of {', '.join(sorted(COMPONENT_TYPES))})")
        out[str(name)] = build(COMPONENT_TYPES[kind], {k: v for k, v in spec.items() if k != "type"}, file, path)
    _compile_check(out, file, ["circuit", "components"], {})
    missing = [b for b in BELLOWS if b not in out]
    if missing:
        raise ScenarioError(file, ["circuit", "components"], f"the car needs bellows named {', '.join(BELLOWS)}; "
                                                             f"missing {', '.join(missing)}")
    return out


def _car_circuit(data: Mapping, file) -> CarCircuit:
    if "components" in data:
        check_keys(data, ("components",), file, ["circuit"])
        explicit = _explicit_components(data, file)
        return CarCircuit("explicit", Bellow(), None, Pipe("", ""), False, LevellingValve(""), None, Supply(), None,
                          tuple(explicit.items()))
    keys = ("layout", "bellow", "tank", "pipe", "valves", "levelling_valve", "differential_valve", "supply", "cross_pipe")
    check_keys(data, keys, file, ["circuit"])
    layout = coerce(data.get("layout", "four_point"), str, file, ["circuit", "layout"])
    if layout not in LAYOUTS:
        raise ScenarioError(file, ["circuit", "layout"], f"expected one of {LAYOUTS}, got {layout!r}")
    P = ["circuit"]
    bellow, tank, pipe = _chambers_and_pipe(data, file)
    valves = coerce(data.get("valves", False), bool, file, P + ["valves"])
    lv = build(LevellingValve, data.get("levelling_valve"), file, P + ["levelling_valve"],
               bellow="", supply="supply", sensed=())
    dpv = _optional(DifferentialPressureValve, data, "differential_valve", file, P, a="", b="")
    supply = build(Supply, data.get("supply"), file, P + ["supply"])
    cross = build(Pipe, data["cross_pipe"], file, P + ["cross_pipe"], a="", b="") if data.get("cross_pipe") is not None else None
    if layout == "two_point" and cross is None:
        raise ScenarioError(file, P + ["cross_pipe"], "a two_point layout needs a cross_pipe between the bellows of a bogie")
    spec = CarCircuit(layout, bellow, tank, pipe, valves, lv, dpv, supply, cross)
    names = {**{b: "bellow" for b in BELLOWS}, **{f"tank_{b}": "tank" for b in BELLOWS},
             **{f"pipe_{b}": "pipe" for b in BELLOWS}, **{f"lv_{b}": "levelling_valve" for b in BELLOWS},
             "lv_F": "levelling_valve", "lv_R": "levelling_valve", "dpv_F": "differential_valve",
             "dpv_R": "differential_valve", "supply": "supply", "cross_F": "cross_pipe", "cross_R": "cross_pipe"}
    _compile_check(spec.components(), file, P, names)
    return spec


def _compile_check(components, file, prefix, yaml_key_of) -> None:
    """Assemble once (cheap) so that inconsistent circuits fail before any simulation."""
    try:
        Circuit(components)
    except CircuitError as exc:
        name, *rest = exc.path
        raise ScenarioError(file, [*prefix, yaml_key_of.get(name, name), *rest], exc.reason) from None


def _vehicle(value, file) -> VehicleParams:
    if value is None:
        return VehicleParams()
    if isinstance(value, str):
        vpath = (Path(file).parent / value)
        data, _ = load_yaml(vpath)
        return build(VehicleParams, data, vpath, [])
    if isinstance(value, dict):
        base = value.get("file")
        defaults = {}
        if base is not None:
            vpath = Path(file).parent / coerce(base, str, file, ["vehicle", "file"])
            defaults, _ = load_yaml(vpath)
        merged = {**(defaults or {}), **{k: v for k, v in value.items() if k != "file"}}
        return build(VehicleParams, merged, file, ["vehicle"])
    raise ScenarioError(file, ["vehicle"], f"expected a parameter file path or a mapping, got {type(value).__name__}")


def _check_car_builds(vehicle: VehicleParams, source, file) -> None:
    """Build the car once (~0.1 s): constraints between parameters (e.g. the bellow's upper plate
    above its lower one) fail here, as bad input, not later inside a worker process."""
    from vehicle.car import MetroCar  # exudyn: only for car scenarios
    try:
        MetroCar(vehicle)
    except ValueError as exc:
        where = Path(file).parent / source if isinstance(source, str) else file
        raise ScenarioError(where, ["vehicle"] if where == file else [], f"inconsistent car parameters: {exc}") from None
