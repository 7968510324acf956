"""Scenario files: load (a stricter ``yaml.SafeLoader``, :mod:`cosim.scenario.yaml_input`), apply
``--set`` overrides, validate everything before any simulation starts, and build the typed
scenario the kinds run.

A scenario is a YAML mapping with a ``kind`` (:mod:`cosim.kinds`) and the section of its
experiment: a rig kind (:class:`~cosim.kinds.base.RigKind`) adds a rig ``circuit`` and its
``test``; a car kind (:class:`~cosim.kinds.base.CarKind`) adds ``vehicle``, ``track``, a car
``circuit``, ``solver``, ``verify``, ``state_limits`` and ``checks``.

Every error names the file, the key path and what was expected (:class:`ScenarioError`).
"""
from __future__ import annotations

import dataclasses
import hashlib
import re
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple

from cosim.engine.master import COUPLINGS
from cosim.errors import ScenarioError
from cosim.scenario.checks import parse_checks
from cosim.scenario.circuits import InitialAir, car_circuit, check_initial_state, parse_faults
from cosim.scenario.imported import check_imported_ks, imported_circuit
from cosim.scenario.model import (
    DEFAULT_TRACK_MODEL,
    DEFAULT_TRACK_PRESET,
    Scenario,
    SolverSettings,
    StateLimits,
    VerifySettings,
)
from cosim.scenario.payload import parse_payload
from cosim.scenario.presets import VEHICLE_PRESETS
from cosim.scenario.schema import (
    MAX_SAMPLES,
    MAX_STEPS,
    build,
    check_keys,
    coerce,
    describe,
    folder_name,
    k_values,
    known_name,
    range_of,
    require,
    unit_slip,
)
from cosim.scenario.yaml_input import MAX_BYTES, parse_yaml, read_yaml
from pneumorail.quantities import Range
from vehicle.params import TRACK_MODELS, TRACK_PRESETS, TrackStructure, VehicleParams

__all__ = ["load_scenario", "apply_overrides", "load_yaml"]


def load_yaml(path: Path) -> Any:
    """(data, text) of a scenario or parameter file, read strictly (see :mod:`cosim.scenario.yaml_input`)."""
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
        node, last = data, parts[-1]
        for i, p in enumerate(parts[:-1]):
            node = _descend(node, p, parts[: i + 1], file)
        value = parse_yaml(value, file, [f"--set {key.strip()}"])
        item = _LIST_ITEM.fullmatch(last)
        if item:
            _descend(node, last, parts, file)            # the item must exist: an index within the list
            node[item.group(1)][int(item.group(2))] = value
        else:
            node[last] = value
    return data


#: a key path part that names a list item: ``faults[0]``
_LIST_ITEM = re.compile(r"(.+)\[(\d+)\]")


def _descend(node: Dict[str, Any], part: str, where: Sequence[str], file) -> Dict[str, Any]:
    """The mapping at ``part`` of ``node`` for an override (created when absent); ``name[i]``:
    item i of the list at ``name``, which must exist."""
    item = _LIST_ITEM.fullmatch(part)
    if item:
        name, i = item.group(1), int(item.group(2))
        items = node.get(name)
        if not isinstance(items, list) or i >= len(items):
            size = f"a list of {len(items)}" if isinstance(items, list) else "no list"
            raise ScenarioError(file, where, f"--set can only change an item that exists; the scenario has {size} at {name!r}")
        if not isinstance(items[i], dict):
            raise ScenarioError(file, where, "--set cannot descend into a value that is not a mapping")
        return items[i]
    if not isinstance(node.get(part), dict):
        if isinstance(node.get(part), list):
            raise ScenarioError(file, where, f"is a list: name an item of it, e.g. {part}[0]")
        if part in node:
            raise ScenarioError(file, where, "--set cannot descend into a value that is not a mapping")
        node[part] = {}
    return node[part]


def load_scenario(path, overrides: Sequence[str] = (), k_override: Optional[Sequence[float]] = None) -> Scenario:
    """Read and validate a scenario file; raises :class:`ScenarioError` before anything runs.

    Every check runs here, in the calling process, before any simulation: types, finite numbers
    in their ranges (:mod:`cosim.scenario.schema`), lists non-empty and without duplicates, and the rules
    between fields (amplitude vs bellow stroke, twist height vs a plausible lift, steps vs duration,
    windows within the run, the circuit assembled and started once). The kind's own section is
    checked by its module (:mod:`cosim.kinds`)."""
    from cosim.kinds import KINDS
    path = Path(path)
    data, text = load_yaml(path)
    if not isinstance(data, dict):
        got = "an empty document" if data is None else describe(data)
        raise ScenarioError(path, [], f"expected a mapping at the top level (kind: ..., k_W_per_K: ...), got {got}")
    if isinstance(data.get("vehicle"), str) and any(o.strip().startswith("vehicle.") for o in overrides):
        # a preset or a parameter file, then single fields on top
        key = "preset" if data["vehicle"] in VEHICLE_PRESETS else "file"
        data = {**data, "vehicle": {key: data["vehicle"]}}
    data = apply_overrides(data, overrides, path)
    name = require(data, "kind", path, [], str)
    if name not in KINDS:
        raise ScenarioError(path, ["kind"], f"unknown kind {name!r} (expected one of {', '.join(KINDS)})")
    kind = KINDS[name]
    if kind.car:
        check_keys(data, ("kind", "name", "description", "k_W_per_K", "vehicle", "track", "circuit", "faults", "payload",
                          kind.section, "solver", "verify", "state_limits", "checks", "allow"), path, [])
    else:
        check_keys(data, ("kind", "name", "description", "k_W_per_K", "circuit", kind.section, "allow"), path, [])
    ks = (k_values(list(k_override), path, ["--k"]) if k_override
          else k_values(require(data, "k_W_per_K", path, []), path, ["k_W_per_K"]))
    common = dict(file=path, kind=name, section=kind.section, name=_name(data, path),
                  description=_description(data, path), k_W_per_K=ks,
                  content_sha256=hashlib.sha256(text.encode()).hexdigest(), overrides=tuple(overrides), raw=data,
                  allow=_allow(data.get("allow"), path))
    if not kind.car:
        return kind.load(data, path, {**common, "files_sha256": _files_read(path, data)})
    return _car_scenario(kind, data, path, common)


def _car_scenario(kind, data: Mapping, path: Path, common: Mapping) -> Scenario:
    """A car scenario: the car (built once), its track, circuit and solver, the kind's section
    (:meth:`~cosim.kinds.base.CarKind.parse`), and the rules between them."""
    vehicle = _vehicle(data.get("vehicle"), path)
    car = _check_car_builds(vehicle, data.get("vehicle"), path)
    track = _track_structure(data.get("track"), path)
    circuit_data = require(data, "circuit", path, [], dict)
    imported = "fmu" in circuit_data
    circuit = imported_circuit(circuit_data, path) if imported else car_circuit(circuit_data, path)
    solver = build(SolverSettings, data.get("solver"), path, ["solver"])
    if solver.coupling not in COUPLINGS:
        raise ScenarioError(path, ["solver", "coupling"], f"expected one of {', '.join(COUPLINGS)}, got {solver.coupling!r}")
    experiment = kind.parse(data.get(kind.section), vehicle, path)
    valve_settings = kind.valve_settings(experiment, circuit.valves)
    if imported:
        refused = kind.refuse_imported_circuit(experiment)
        if refused:
            raise ScenarioError(path, ["circuit", "fmu"], refused)
        check_imported_ks(circuit, common["k_W_per_K"], path)
    if imported or circuit.explicit is not None:
        # an explicit or imported circuit has no valves switch: its valves are what its components are
        given = (data.get(kind.section) or {}).get("valve_settings")
        if given is not None and tuple(valve_settings) != (circuit.valves,):
            has = "has levelling valves" if circuit.valves else "has no levelling valve"
            what = "an FMU circuit (circuit.fmu; circuit.valves says whether it has valves)" if imported else \
                "an explicit circuit (circuit.components)"
            raise ScenarioError(path, [kind.section, "valve_settings"], f"{what} {has}: leave valve_settings out, or "
                                                                        f"give [{str(circuit.valves).lower()}]")
        valve_settings = (circuit.valves,)
        experiment = dataclasses.replace(experiment, valve_settings=valve_settings)
    _check_steps(solver, kind.duration_s(experiment), path)
    refused = kind.refuse_faults(experiment) if data.get("faults") else None
    if imported and data.get("faults"):
        refused = "an FMU circuit cannot be faulted from the scenario (its components are inside the FMU)"
    if refused:
        raise ScenarioError(path, ["faults"], refused)
    shortest = kind.shortest_duration_s(experiment)   # every case sees every fault
    if not imported:
        circuit = dataclasses.replace(circuit, faults=parse_faults(data.get("faults"), path, circuit, shortest,
                                                                   valve_settings))
    refused = kind.refuse_payload(experiment) if data.get("payload") else None
    if refused:
        raise ScenarioError(path, ["payload"], refused)
    payload = parse_payload(data.get("payload"), path, shortest)
    experiment = kind.with_payload(experiment, payload, path)
    circuit = kind.with_circuit(experiment, circuit, path)
    if payload is not None:       # the car starts carrying its payload at arrival: the bellows' pressures follow
        car = _check_car_builds(vehicle, data.get("vehicle"), path, payload)
    # an FMU's initial air is its own, known once it runs
    air = () if imported else check_initial_state(circuit, car, common["k_W_per_K"], valve_settings, path)
    verify = build(VerifySettings, data.get("verify"), path, ["verify"])
    state_limits = _state_limits(data.get("state_limits"), path, air)
    checks = parse_checks(data.get("checks", []), kind, experiment, path, common["k_W_per_K"], valve_settings)
    extra = kind.extra_files(experiment)
    return Scenario(**common, files_sha256=_files_read(path, data, extra), experiment=experiment, circuit=circuit,
                    vehicle=vehicle, track=track, solver=solver, verify=verify, state_limits=state_limits,
                    checks=checks, payload=payload)


def _allow(value, path) -> Tuple[str, ...]:
    """``allow: [pipe_mach, ...]``: validity flags (cosim.limits.validity.FLAGS) check accepts."""
    from cosim.limits.validity import FLAGS
    if value is None:
        return ()
    if not isinstance(value, list):
        raise ScenarioError(path, ["allow"], f"expected a list of validity flags ({', '.join(FLAGS)}), got {describe(value)}")
    for i, flag in enumerate(value):
        if flag not in FLAGS:
            raise ScenarioError(path, [f"allow[{i}]"], f"unknown validity flag {flag!r} (expected one of {', '.join(FLAGS)})")
        if flag in value[:i]:
            raise ScenarioError(path, [f"allow[{i}]"], f"{flag} listed twice")
    return tuple(value)


def _name(data: Mapping, path: Path) -> str:
    """``name`` (default: the file name): it names the default output folder ``results/<name>``,
    so it must be usable as one folder name."""
    if "name" not in data:
        return path.stem
    return folder_name(data["name"], path, ["name"])


def _description(data: Mapping, path: Path) -> str:
    value = data.get("description", "")
    if value is None:
        return ""
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise ScenarioError(path, ["description"], f"expected a string, got {describe(value)}")
    return str(value)


def _files_read(path: Path, data: Mapping, extra: Sequence[Path] = ()) -> Tuple[Tuple[str, str], ...]:
    """(path relative to the scenario file, sha256) of every file the scenario reads: itself, the
    vehicle parameter file, the files its kind reads (``extra``, e.g. a track irregularity; called
    once they have been validated)."""
    vehicle = data.get("vehicle")
    vehicle = vehicle.get("file") if isinstance(vehicle, dict) else vehicle
    files = [path] + ([path.parent / vehicle] if isinstance(vehicle, str) and vehicle not in VEHICLE_PRESETS else [])
    files += list(extra)
    folder = path.parent.resolve()
    return tuple((str(f.resolve().relative_to(folder)) if f.resolve().is_relative_to(folder) else str(f),
                  hashlib.sha256(f.read_bytes()).hexdigest())
                 for f in files if f.is_file() and f.stat().st_size <= MAX_BYTES)


def _check_steps(solver: SolverSettings, duration_s: float, path) -> None:
    """The run and its output interval must be whole numbers of macro-steps (nothing is rounded
    silently), the multibody step no longer than the macro-step, and the run of a
    bounded size (:data:`MAX_STEPS` macro-steps, :data:`~cosim.scenario.schema.MAX_SAMPLES` output rows)."""
    H = solver.macro_step_s
    if H > duration_s * (1 + 1e-9):
        raise ScenarioError(path, ["solver", "macro_step_s"], f"the macro-step ({H:g} s) is longer than the run "
                                                              f"({duration_s:g} s)")
    for key, value in (("output_interval_s", solver.output_interval_s), ("duration", duration_s)):
        n = value / H
        if abs(n - round(n)) > 1e-6 * max(n, 1.0) or round(n) < 1:
            where = ["solver", key] if key != "duration" else ["solver", "macro_step_s"]
            raise ScenarioError(path, where, f"the {key.replace('_s', '').replace('_', ' ')} ({value:g} s) must be a "
                                             f"whole number of macro-steps ({H:g} s)")
    if duration_s / H > MAX_STEPS:
        raise ScenarioError(path, ["solver", "macro_step_s"], f"the run ({duration_s:g} s) takes {duration_s / H:.3g} "
                                                              f"macro-steps of {H:g} s; at most {MAX_STEPS:.0e}")
    if duration_s / solver.output_interval_s > MAX_SAMPLES:
        raise ScenarioError(path, ["solver", "output_interval_s"], f"the run ({duration_s:g} s) would store "
                                                                   f"{duration_s / solver.output_interval_s:.3g} rows; "
                                                                   f"at most {MAX_SAMPLES:.0e}")
    # (the pneumatic step only bounds the circuit's RK4 sub-steps within a macro-step: it may exceed it)
    if solver.mechanics_step_s > H * (1 + 1e-9):
        raise ScenarioError(path, ["solver", "mechanics_step_s"], f"must not exceed the macro-step ({H:g} s), got "
                                                                  f"{solver.mechanics_step_s:g} s")


def _param_file(value, file, where) -> Path:
    """The vehicle parameter file ``value`` (relative to the scenario) if it can be read; else an
    error naming the scenario and the key that names the file."""
    vpath = Path(file).parent / value
    if not vpath.exists():
        raise ScenarioError(file, where, f"the vehicle parameter file {str(vpath)!r} does not exist")
    if not vpath.is_file():
        raise ScenarioError(file, where, f"the vehicle parameter file {str(vpath)!r} is not a file")
    return vpath


def _read_params(vpath: Path) -> Dict[str, Any]:
    """The mapping of a vehicle parameter file; errors in it name that file."""
    data, _ = load_yaml(vpath)
    if not isinstance(data, dict):
        got = "an empty document" if data is None else describe(data)
        raise ScenarioError(vpath, [], f"expected a mapping of vehicle parameters (field: value), got {got}")
    return data


def _vehicle(value, file) -> VehicleParams:
    """``vehicle``: absent (the paper's car), a preset name, a parameter file, or a mapping of
    fields on top of ``preset: NAME`` or ``file: PATH``."""
    if value is None:
        return VehicleParams()
    if isinstance(value, str):
        if value in VEHICLE_PRESETS:
            return VEHICLE_PRESETS[value]()
        vpath = _param_file(value, file, ["vehicle"])
        return build(VehicleParams, _read_params(vpath), vpath, [])
    if isinstance(value, dict):
        base = value.get("file")
        defaults: Dict[str, Any] = {}
        if "preset" in value:
            if base is not None:
                raise ScenarioError(file, ["vehicle", "preset"], "give a preset or a file, not both")
            name = known_name(value["preset"], VEHICLE_PRESETS, file, ["vehicle", "preset"], "vehicle preset")
            defaults = dataclasses.asdict(VEHICLE_PRESETS[name]())
            value = {k: v for k, v in value.items() if k != "preset"}
        if base is not None:
            vpath = _param_file(coerce(base, str, file, ["vehicle", "file"]), file, ["vehicle", "file"])
            defaults = _read_params(vpath)
            build(VehicleParams, defaults, vpath, [])            # the file's own errors name the file
        merged = {**defaults, **{k: v for k, v in value.items() if k != "file"}}
        return build(VehicleParams, merged, file, ["vehicle"])
    raise ScenarioError(file, ["vehicle"], f"expected a parameter file path or a mapping, got {describe(value)}")


def _state_limits(value, file, air: Sequence[InitialAir] = ()) -> StateLimits:
    """``state_limits``: the states that stop a case (:class:`~cosim.scenario.model.StateLimits`).
    A limit the air already passes when the run starts (``air``: every chamber's, in every valve
    setting) would stop every case at its first step: refused, with the unit it was likely
    written in (degrees Celsius for K, bar for Pa)."""
    limits = build(StateLimits, value, file, ["state_limits"])
    for low, high in (("T_min_K", "T_max_K"), ("p_min_Pa", "p_max_Pa")):
        if not getattr(limits, low) < getattr(limits, high):
            raise ScenarioError(file, ["state_limits", high], f"must exceed {low} ({getattr(limits, low):g}), "
                                                              f"got {getattr(limits, high):g}")
    if air:
        for key, state, unit, upper in (("T_max_K", "T_K", "K", True), ("T_min_K", "T_K", "K", False),
                                        ("p_max_Pa", "p_Pa", "Pa absolute", True), ("p_min_Pa", "p_Pa", "Pa absolute", False)):
            _check_limit_admits_start(getattr(limits, key), key, state, unit, upper, air, file)
    return limits


def _check_limit_admits_start(limit: float, key: str, state: str, unit: str, upper: bool, air: Sequence[InitialAir],
                              file) -> None:
    """An upper (``upper``) or lower state limit ``key`` must leave every chamber's starting
    ``state`` (``p_Pa`` or ``T_K`` of :class:`InitialAir`) inside it."""
    start = (max if upper else min)(air, key=lambda a: getattr(a, state))
    value = getattr(start, state)
    if (limit > value) if upper else (limit < value):
        return
    field = range_of(StateLimits, key)       # the slip must also land within the field's own range
    start_range = Range(value, field.high, False, True, unit) if upper else Range(field.low, value, False, False, unit)
    raise ScenarioError(file, ["state_limits", key], f"must be {'above' if upper else 'below'} the air's "
                                                     f"{'temperature' if state == 'T_K' else 'pressure'} when the run "
                                                     f"starts ({start.chamber}: {value:.6g} {unit}), or every case "
                                                     f"stops at its first step; got {limit:g}{unit_slip(limit, start_range)}")


def _track_structure(value, file) -> TrackStructure:
    """``track``: absent (:data:`~cosim.scenario.model.DEFAULT_TRACK_MODEL`), ``rigid``, ``flexible``
    (the ``slab_track`` preset), or a mapping ``{model: flexible, preset: NAME, <field>:
    value ...}`` (fields of :class:`~vehicle.params.TrackStructure` on top of the preset)."""
    if value is None:
        value = DEFAULT_TRACK_MODEL
    if isinstance(value, str):
        value = {"model": value}
    if not isinstance(value, dict):
        raise ScenarioError(file, ["track"], f"expected rigid, flexible or a mapping {{model: flexible, ...}}, "
                                             f"got {describe(value)}")
    model = value.get("model", "flexible")
    if model not in TRACK_MODELS:
        raise ScenarioError(file, ["track", "model"], f"expected one of {', '.join(TRACK_MODELS)}, got {model!r}")
    fields = {k: v for k, v in value.items() if k not in ("model", "preset")}
    if model == "rigid":
        extra = [k for k in value if k != "model"]
        if extra:
            raise ScenarioError(file, ["track", extra[0]], "a rigid track takes no parameters (model: flexible does)")
        return TrackStructure()
    name = known_name(value.get("preset", DEFAULT_TRACK_PRESET), TRACK_PRESETS, file, ["track", "preset"], "track preset")
    defaults = {k: v for k, v in dataclasses.asdict(TRACK_PRESETS[name]()).items() if k != "model"}
    return build(TrackStructure, {**defaults, **fields}, file, ["track"], model="flexible")


def _check_car_builds(vehicle: VehicleParams, source, file, payload=None):
    """Build the car once (~0.1 s): constraints between parameters (e.g. the bellow's upper plate
    above its lower one) fail here, as bad input, not later inside a worker process. Returns the
    car (its static bellow forces start the circuit, :func:`check_initial_state`); ``payload``: its
    :class:`~cosim.scenario.payload.PayloadSchedule` (the car carries its payload at arrival)."""
    from vehicle.car import MetroCar  # exudyn: only for car scenarios
    try:
        if payload is not None:
            return MetroCar(vehicle, payload=payload.blocks_at)
        return MetroCar(vehicle)
    except Exception as exc:                    # noqa: BLE001 -- whatever the parameters break is bad input
        where = Path(file).parent / source if isinstance(source, str) else file
        reason = str(exc) if isinstance(exc, ValueError) else f"{type(exc).__name__}: {exc}"
        raise ScenarioError(where, ["vehicle"] if where == file else [], f"inconsistent car parameters: {reason}") from None
