"""Scenario files: load (a stricter ``yaml.SafeLoader``, :mod:`cosim.scenario.yaml_input`), apply ``--set`` overrides, validate everything
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

import dataclasses
import hashlib
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple

import numpy as np

from pneumatics.boundary import Supply
from pneumatics.chamber import Bellow, Tank
from pneumatics.circuit import COMPONENT_TYPES, Circuit, CircuitError
from pneumatics.layouts import BELLOWS
from pneumatics.pipe import Pipe
from pneumatics.presets import CIRCUIT_PRESETS
from pneumatics.valves import DifferentialPressureValve, LevellingValve
from vehicle.params import TRACK_MODELS, TRACK_PRESETS, WHEELS, TrackStructure, VehicleParams

from cosim.limits.checks import parse_checks
from cosim.scenario.model import (CAR_KINDS, DEFAULT_TRACK_MODEL, DEFAULT_TRACK_PRESET, KINDS, RIG_KINDS, RIG_TESTS,
                          TRANSITION_SHAPES, CarCircuit, CurveTest, RampTest, RigCircuit, Scenario, SineTest,
                          SolverSettings, StateLimits, TwistTest, VerifySettings)
from cosim.master import COUPLINGS
from cosim.scenario.presets import VEHICLE_PRESETS
from cosim.scenario.schema import MAX_SAMPLES, ScenarioError, build, check_keys, coerce, describe, k_values, require
from cosim.scenario.yaml_input import MAX_BYTES, parse_yaml, read_yaml

__all__ = ["load_scenario", "apply_overrides", "load_yaml", "CAR_KINDS", "RIG_KINDS", "KINDS"]

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
        node = data
        for i, p in enumerate(parts[:-1]):
            if not isinstance(node.get(p), dict):
                if p in node:
                    raise ScenarioError(file, parts[: i + 1], "--set cannot descend into a value that is not a mapping")
                node[p] = {}
            node = node[p]
        node[parts[-1]] = parse_yaml(value, file, [f"--set {key.strip()}"])
    return data


#: Most integration steps one run may take (macro-steps of a car run; the rig's integrator
#: steps, bounded below by its largest step): 1e7 steps are hours of computing. The shipped
#: scenarios take at most 120 000.
MAX_STEPS = 10_000_000
#: Highest rail lift of a twist test [m]: three times the largest EN 14363 test height. The limit
#: twist times its base, (20/2a* + 2) per mille x 2a*, is 20 mm + 2 per mille x 2a*: 60 mm for the
#: longest bogie-centre distance the rule covers (20 m), plus half the bogie twist's 7 per mille x
#: 2a+ (~10 mm); 3 x 70 mm ~ 0.2 m. Beyond it a "track" lifts a wheel off any plausible test bench
#: (100 per mille over a 10 m base: 1 m).
MAX_RAIL_LIFT_M = 0.2


def load_scenario(path, overrides: Sequence[str] = (), k_override: Optional[Sequence[float]] = None) -> Scenario:
    """Read and validate a scenario file; raises :class:`ScenarioError` before anything runs.

    Every check runs here, in the calling process, before any simulation: types, finite numbers
    in their ranges (:mod:`cosim.scenario.schema`), lists non-empty and without duplicates, and the rules
    between fields (amplitude vs bellow stroke, twist height vs a plausible lift, steps vs duration,
    windows within the run, the circuit assembled and started once)."""
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
    kind = require(data, "kind", path, [], str)
    if kind not in KINDS:
        raise ScenarioError(path, ["kind"], f"unknown kind {kind!r} (expected one of {', '.join(KINDS)})")
    if kind in RIG_KINDS:
        check_keys(data, ("kind", "name", "description", "k_W_per_K", "circuit", "test", "allow"), path, [])
    else:
        experiment = "twist" if kind == "twist" else "curve"
        check_keys(data, ("kind", "name", "description", "k_W_per_K", "vehicle", "track", "circuit", experiment,
                          "solver", "verify", "state_limits", "checks", "allow"), path, [])
    ks = (k_values(list(k_override), path, ["--k"]) if k_override
          else k_values(require(data, "k_W_per_K", path, []), path, ["k_W_per_K"]))
    common = dict(file=path, kind=kind, name=_name(data, path), description=_description(data, path),
                  k_W_per_K=ks, content_sha256=hashlib.sha256(text.encode()).hexdigest(),
                  overrides=tuple(overrides), raw=data, allow=_allow(data.get("allow"), path))
    if kind in RIG_KINDS:
        rig = _rig_circuit(require(data, "circuit", path, [], dict), path)
        test = build(RIG_TESTS[kind], data.get("test"), path, ["test"])
        _check_rig_test(test, rig, path)
        return Scenario(**common, files_sha256=_files_read(path, data), rig=rig, test=test)

    vehicle = _vehicle(data.get("vehicle"), path)
    car = _check_car_builds(vehicle, data.get("vehicle"), path)
    track = _track_structure(data.get("track"), path)
    circuit = _car_circuit(require(data, "circuit", path, [], dict), path)
    solver = build(SolverSettings, data.get("solver"), path, ["solver"])
    if solver.coupling not in COUPLINGS:
        raise ScenarioError(path, ["solver", "coupling"], f"expected one of {', '.join(COUPLINGS)}, got {solver.coupling!r}")
    if kind == "twist":
        tests = {"twist": _twist(data.get("twist"), vehicle, path)}
        duration = tests["twist"].duration_s
        valve_settings = tests["twist"].valve_settings or (circuit.valves,)
    else:
        tests = {"curve": _curve(data.get("curve"), vehicle, path)}
        duration = tests["curve"].duration_s
        valve_settings = tests["curve"].valve_settings
    if circuit.explicit is not None:
        # an explicit circuit has no valves switch: its valves are what its components are
        given = (data.get(experiment) or {}).get("valve_settings")
        if given is not None and tuple(valve_settings) != (circuit.valves,):
            has = "has levelling valves" if circuit.valves else "has no levelling valve"
            raise ScenarioError(path, [experiment, "valve_settings"], f"an explicit circuit (circuit.components) "
                                                                      f"{has}: leave valve_settings out, or give "
                                                                      f"[{str(circuit.valves).lower()}]")
        valve_settings = (circuit.valves,)
        tests = {name: dataclasses.replace(test, valve_settings=valve_settings) for name, test in tests.items()}
    _check_steps(solver, duration, path)
    _check_initial_state(circuit, car, ks, valve_settings, path)
    verify = build(VerifySettings, data.get("verify"), path, ["verify"])
    state_limits = _state_limits(data.get("state_limits"), path)
    checks = parse_checks(data.get("checks", []), kind, path, ks, valve_settings,
                          guidance=tests["curve"].guidance if kind == "curve_entry" else None)
    return Scenario(**common, files_sha256=_files_read(path, data), vehicle=vehicle, track=track, circuit=circuit,
                    solver=solver, verify=verify, state_limits=state_limits, checks=checks, **tests)


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


def _with_preset(data: Mapping, file, sections: Sequence[str]) -> Dict[str, Any]:
    """``circuit: {preset: NAME, ...}``: the preset's bellow, tank and pipe (and, for a rig,
    ``p0_Pa``) under what the scenario writes, field by field; ``tank: null`` stays null."""
    if "preset" not in data:
        return dict(data)
    name = data["preset"]
    if name not in CIRCUIT_PRESETS:
        raise ScenarioError(file, ["circuit", "preset"], f"unknown circuit preset {name!r} "
                                                         f"(expected one of {', '.join(CIRCUIT_PRESETS)})")
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


def _name(data: Mapping, path: Path) -> str:
    """``name`` (default: the file name): it names the default output folder ``results/<name>``,
    so it must be usable as one folder name."""
    if "name" not in data:
        return path.stem
    value = data["name"]
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise ScenarioError(path, ["name"], f"expected a string, got {describe(value)}")
    name = str(value)
    if (not name.strip() or name in (".", "..") or any(c in name for c in "/\\") or any(ord(c) < 32 for c in name)
            or len(name) > 100):
        raise ScenarioError(path, ["name"], f"expected a name usable as a folder name (no / or \\, no control "
                                            f"characters, at most 100 characters), got {name!r}")
    return name


def _description(data: Mapping, path: Path) -> str:
    value = data.get("description", "")
    if value is None:
        return ""
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise ScenarioError(path, ["description"], f"expected a string, got {describe(value)}")
    return str(value)


def _check_rig_test(test, rig: RigCircuit, path) -> None:
    """Rules between the fields of a rig test and its circuit."""
    if isinstance(test, RampTest):
        for i, c in enumerate(test.configurations):
            if c not in ("bellow_tank", "bellow_only"):
                raise ScenarioError(path, ["test", f"configurations[{i}]"], f"expected bellow_tank or bellow_only, "
                                                                            f"got {c!r}")
    stroke = rig.bellow.V0_m3 / rig.bellow.dV_dz_m2
    if not abs(test.amplitude_m) < stroke:
        raise ScenarioError(path, ["test", "amplitude_m"], f"|amplitude| must be below V0/(dV/dz) = {stroke:.4g} m, "
                                                           f"where the bellow volume vanishes; got {test.amplitude_m}")
    if isinstance(test, RampTest):
        if test.ramp_s > test.duration_s:
            raise ScenarioError(path, ["test", "ramp_s"], f"the ramp must end within the run (duration_s = "
                                                          f"{test.duration_s:g} s), got {test.ramp_s:g} s")
        steps = test.duration_s / (test.ramp_s / 50.0)      # the integrator's largest step: ramp_s / 50
        if steps > MAX_STEPS:
            raise ScenarioError(path, ["test", "ramp_s"], f"the integrator steps at most ramp_s/50: a {test.ramp_s:g} s "
                                                          f"ramp in a {test.duration_s:g} s run takes {steps:.3g} steps "
                                                          f"(at most {MAX_STEPS:.0e})")
    if isinstance(test, SineTest):
        periods = test.duration_s * test.frequency_Hz
        if periods < 2:
            raise ScenarioError(path, ["test", "duration_s"], f"expected at least 2 periods of the sine (the summary "
                                                              f"compares periods), got {periods:.3g} "
                                                              f"({test.duration_s:g} s at {test.frequency_Hz:g} Hz)")
        samples = periods * test.samples_per_period + 1
        if samples > MAX_SAMPLES:
            raise ScenarioError(path, ["test", "duration_s"], f"the run would store {samples:.3g} samples (duration_s x "
                                                              f"frequency_Hz x samples_per_period); at most {MAX_SAMPLES:.0e}")
        if periods * 20 > MAX_STEPS:                        # the integrator's largest step: a period / 20
            raise ScenarioError(path, ["test", "duration_s"], f"{periods:.3g} periods take {periods * 20:.3g} integration "
                                                              f"steps (20 a period); at most {MAX_STEPS:.0e}")


def _files_read(path: Path, data: Mapping) -> Tuple[Tuple[str, str], ...]:
    """(path relative to the scenario file, sha256) of every file the scenario reads: itself, the
    vehicle parameter file, the track irregularity file (called once they have been validated)."""
    vehicle = data.get("vehicle")
    vehicle = vehicle.get("file") if isinstance(vehicle, dict) else vehicle
    files = [path] + ([path.parent / vehicle] if isinstance(vehicle, str) and vehicle not in VEHICLE_PRESETS else [])
    irregularity = (data.get("curve") or {}).get("irregularity")
    if isinstance(irregularity, dict) and isinstance(irregularity.get("file"), str):
        files.append(path.parent / irregularity["file"])
    return tuple((str(f.relative_to(path.parent)) if f.is_relative_to(path.parent) else str(f),
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
    # Plausible test height. The twist is bounded by MAX_TWIST_PER_MILLE (cosim.scenario.schema); the lift
    # of the highest rail, twist x base (+ half the bogie twist's height), by MAX_RAIL_LIFT_M.
    # (The bellow stroke is deliberately not the bound: a bellow driven beyond its stroke is a
    # legitimate study of divergence, which the runs diagnose.)
    lift = twist.height_m + 0.5 * twist.bogie_height_m
    if not lift <= MAX_RAIL_LIFT_M:
        if twist.bogie_base_m is not None and twist.height_m <= MAX_RAIL_LIFT_M:   # the bogie twist tips it over
            key = "bogie_twist_per_mille" if twist.bogie_twist_per_mille is not None else "bogie_base_m"
        else:
            key = "twist_per_mille" if twist.twist_per_mille is not None else "base_m"
        raise ScenarioError(path, ["twist", key], f"the rails rise by {lift * 1e3:.0f} mm (twist {twist.twist * 1e3:g} "
                                                  f"per mille x base {twist.base_m:g} m"
                                                  + (f" + half the bogie twist's {twist.bogie_height_m * 1e3:.0f} mm"
                                                     if twist.bogie_base_m is not None else "")
                                                  + f"): expected at most {MAX_RAIL_LIFT_M * 1e3:.0f} mm, three times "
                                                  f"the largest EN 14363 test height")
    return twist


def _valve_settings(settings, path, where) -> None:
    if settings is None:
        return
    if not settings:
        raise ScenarioError(path, where, "expected at least one setting (false: valves isolated, true: connected)")
    if len(set(settings)) != len(settings):
        raise ScenarioError(path, where, f"each setting at most once, got {list(settings)}")


def _curve(data, vehicle: VehicleParams, path) -> CurveTest:
    irregularity = None
    if isinstance(data, Mapping) and "irregularity" in data:
        irregularity = data["irregularity"]
        data = {k: v for k, v in data.items() if k != "irregularity"}
    curve = build(CurveTest, data, path, ["curve"])
    if curve.direction not in (1, -1):
        raise ScenarioError(path, ["curve", "direction"], f"expected 1 (left) or -1 (right), got {curve.direction}")
    if curve.transition_shape not in TRANSITION_SHAPES:
        raise ScenarioError(path, ["curve", "transition_shape"], f"expected one of {', '.join(TRANSITION_SHAPES)}, "
                                                                 f"got {curve.transition_shape!r}")
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
                                                           f"lengthen arc_m or shorten duration_s (got {curve.duration_s:g} s)")
    _curve_contact(curve, path)
    try:
        curve.track()
    except ValueError as exc:
        raise ScenarioError(path, ["curve"], f"the track cannot be built: {exc}") from None
    if irregularity is not None:
        curve = dataclasses.replace(curve, irregularity=_irregularity(irregularity, curve, vehicle, path))
    return curve


def _curve_contact(curve: CurveTest, path) -> None:
    """The guidance, the contact model's friction and the limits' parameters of a curve."""
    from cosim.limits.criteria import nadal_limit
    from cosim.scenario.model import GUIDANCE
    if curve.guidance not in GUIDANCE:
        raise ScenarioError(path, ["curve", "guidance"], f"expected one of {', '.join(GUIDANCE)}, got {curve.guidance!r}")
    mu = curve.friction_coefficient
    if mu is not None and not 0.0 < mu <= 1.0:
        raise ScenarioError(path, ["curve", "friction_coefficient"], f"expected a wheel-rail friction coefficient in "
                                                                     f"(0, 1] (dry rail 0.3-0.5), got {mu:g}")
    for key in ("friction_coefficient", "contact_damping_N_s_per_m", "contact_smoothing_mm"):
        if getattr(curve, key) is not None and not curve.contact:
            raise ScenarioError(path, ["curve", key], "a parameter of the contact model needs curve.guidance: contact")
    if not 0.0 < curve.nadal_flange_angle_deg < 90.0:
        raise ScenarioError(path, ["curve", "nadal_flange_angle_deg"], f"expected a flange angle in (0, 90) degrees, "
                                                                       f"got {curve.nadal_flange_angle_deg:g}")
    if not 0.0 <= curve.nadal_friction <= 1.0:
        raise ScenarioError(path, ["curve", "nadal_friction"], f"expected a friction coefficient in [0, 1], "
                                                               f"got {curve.nadal_friction:g}")
    if not nadal_limit(curve.nadal_flange_angle_deg, curve.nadal_friction) > 0.0:
        raise ScenarioError(path, ["curve", "nadal_friction"], f"the Nadal limit (tan g - mu)/(1 + mu tan g) must be "
                                                               f"> 0: mu = {curve.nadal_friction:g} is not below tan "
                                                               f"{curve.nadal_flange_angle_deg:g} deg")
    if not 0.0 < curve.prudhomme_alpha <= 1.0:
        raise ScenarioError(path, ["curve", "prudhomme_alpha"], f"expected a factor in (0, 1] (EN 14363: 1, freight "
                                                                f"wagons 0.85), got {curve.prudhomme_alpha:g}")


def _irregularity(value, curve: CurveTest, vehicle: VehicleParams, path):
    """``curve.irregularity``: null, {psd: KIND, seed, ...} or {file: PATH}; generated (or read)
    once here, so that a bad one fails before any run."""
    from vehicle.irregularities import CHANNELS, canonical_kind
    from cosim.scenario.model import IrregularitySpec
    where = ["curve", "irregularity"]
    if not isinstance(value, Mapping):
        raise ScenarioError(path, where, f"expected null, {{psd: erri_b176_low, seed: 1}} or {{file: irregularity.csv}}, "
                                         f"got {describe(value)}")
    spec = build(IrregularitySpec, value, path, where)
    if (spec.psd is None) == (spec.file is None):
        raise ScenarioError(path, where, "give either psd (with a seed) or file, not " + ("both" if spec.psd else "neither"))
    if spec.file is not None:
        others = [k for k in value if k != "file"]
        if others:
            raise ScenarioError(path, [*where, others[0]], "a file irregularity takes no other keys (the file gives "
                                                           "s_m and the values)")
        fpath = Path(path).parent / spec.file
        if not fpath.is_file():
            raise ScenarioError(path, [*where, "file"], f"the irregularity file {str(fpath)!r} does not exist or is not a file")
        spec = dataclasses.replace(spec, file=str(fpath.resolve()))
    else:
        try:
            spec = dataclasses.replace(spec, psd=canonical_kind(spec.psd))
        except ValueError as exc:
            raise ScenarioError(path, [*where, "psd"], str(exc)) from None
        if spec.seed < 0:
            raise ScenarioError(path, [*where, "seed"], f"expected an integer >= 0, got {spec.seed}")
        band = spec.wavelength_range_m
        if len(band) != 2 or not 0.0 < band[0] < band[1]:
            raise ScenarioError(path, [*where, "wavelength_range_m"], f"expected [shortest, longest] wavelength in m, "
                                                                      f"0 < shortest < longest, got {list(band)}")
        for i, c in enumerate(spec.channels):
            if c not in CHANNELS or c in spec.channels[:i]:
                raise ScenarioError(path, [*where, f"channels[{i}]"], f"expected each of {', '.join(CHANNELS)} at most "
                                                                      f"once, got {c!r}")
        if not spec.ds_m <= 0.5 * band[0]:
            raise ScenarioError(path, [*where, "ds_m"], f"the spacing must be at most half the shortest wavelength "
                                                        f"({0.5 * band[0]:g} m), got {spec.ds_m:g} m")
        length = curve.track().total_length_m
        start = spec.start_m
        if start is not None and not 0.0 <= start < length:
            raise ScenarioError(path, [*where, "start_m"], f"expected a position on the track, [0, {length:g}) m, "
                                                           f"got {start:g} m")
    try:
        irr = dataclasses.replace(curve, irregularity=spec).track_irregularity(vehicle)
    except ValueError as exc:
        key = "file" if spec.file is not None else "taper_m" if "taper_m" in str(exc) else "psd"
        raise ScenarioError(path, [*where, key], f"cannot build the irregularity: {exc}") from None
    # the car starts in static equilibrium on design track: nothing under it at t = 0
    car_length = vehicle.bogie_centre_distance_m + vehicle.wheelbase_m
    s = np.linspace(0.0, car_length, 241)
    worst = max(float(np.abs(v).max()) for v in irr(s))
    if worst > 1e-6:
        raise ScenarioError(path, [*where, "file" if spec.file is not None else "start_m"],
                            f"the irregularity must be 0 under the car at t = 0 (s = 0 ... {car_length:g} m, the "
                            f"rear wheelset at s = 0); it reaches {worst * 1e3:.3g} mm there")
    return spec


def _chambers_and_pipe(data: Mapping, file):
    """The bellow, the tank (``tank: null``: none) and the bellow-tank pipe of a circuit section;
    initial pressures come from elsewhere (rig ``p0_Pa``, or the car's static load)."""
    P = ["circuit"]
    bellow = build(Bellow, data.get("bellow"), file, P + ["bellow"], p0_Pa=None, T0_K=None)
    tank = _optional(Tank, data, "tank", file, P, p0_Pa=None, T0_K=None)
    pipe = _pipe(data.get("pipe"), file, P + ["pipe"])
    return bellow, tank, pipe


def _pipe(data, file, where) -> Pipe:
    pipe = build(Pipe, data, file, where, a="", b="")
    _check_pipe(pipe, file, where)
    return pipe


def _check_pipe(pipe: Pipe, file, where) -> None:
    """The total loss coefficient lambda L/d + zeta of eq. (5) divides the quasi-steady flow: it
    must be > 0 (each term is >= 0 by the field rules); reported at ``zeta``, the key one sets."""
    if not pipe.loss_coefficient > 0:
        raise ScenarioError(file, [*where, "zeta"], "the pressure-loss coefficient lambda L/d + zeta must be > 0 "
                                                    f"(friction_factor = {pipe.friction_factor:g}, zeta = {pipe.zeta:g})")


def _optional(cls, data: Mapping, key: str, file, prefix, **fixed):
    """``key: null`` means the component is absent; a missing key means its defaults."""
    if key in data and data[key] is None:
        return None
    return build(cls, data.get(key), file, [*prefix, key], **fixed)


def _rig_circuit(data: Mapping, file) -> RigCircuit:
    check_keys(data, ("preset", "bellow", "tank", "pipe", "p0_Pa"), file, ["circuit"])
    data = _with_preset(data, file, ("bellow", "tank", "pipe", "p0_Pa"))
    bellow, tank, pipe = _chambers_and_pipe(data, file)
    p0 = coerce(require(data, "p0_Pa", file, ["circuit"]), float, file, ["circuit", "p0_Pa"])
    if not p0 > 0:
        raise ScenarioError(file, ["circuit", "p0_Pa"], f"expected an absolute pressure > 0 Pa, got {p0:g}")
    rig = RigCircuit(bellow, tank, pipe, p0)
    _compile_check(rig.components(tank is not None), file, ["circuit"], {"bellow": "bellow", "tank": "tank", "pipe": "pipe"})
    return rig


LAYOUTS = ("four_point", "two_point")


def _explicit_components(data: Mapping, file) -> Dict[str, object]:
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
            _check_pipe(out[str(name)], file, path)
    _compile_check(out, file, ["circuit", "components"], {})
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
_LAYOUT_KEYS = {**{b: "bellow" for b in BELLOWS}, **{f"tank_{b}": "tank" for b in BELLOWS},
                **{f"pipe_{b}": "pipe" for b in BELLOWS}, **{f"lv_{b}": "levelling_valve" for b in BELLOWS},
                "lv_F": "levelling_valve", "lv_R": "levelling_valve", "dpv_F": "differential_valve",
                "dpv_R": "differential_valve", "supply": "supply", "cross_F": "cross_pipe", "cross_R": "cross_pipe"}


def _car_circuit(data: Mapping, file) -> CarCircuit:
    if "components" in data:
        check_keys(data, ("components",), file, ["circuit"])
        explicit = _explicit_components(data, file)
        has_valves = any(isinstance(c, LevellingValve) for c in explicit.values())   # the outputs' valves on/off
        return CarCircuit("explicit", Bellow(), None, Pipe("", ""), has_valves, LevellingValve(""), None, Supply(), None,
                          tuple(explicit.items()))
    keys = ("preset", "layout", "bellow", "tank", "pipe", "valves", "levelling_valve", "differential_valve", "supply",
            "cross_pipe")
    check_keys(data, keys, file, ["circuit"])
    data = _with_preset(data, file, ("bellow", "tank", "pipe"))
    layout = coerce(data.get("layout", "four_point"), str, file, ["circuit", "layout"])
    if layout not in LAYOUTS:
        raise ScenarioError(file, ["circuit", "layout"], f"expected one of {', '.join(LAYOUTS)}, got {layout!r}")
    P = ["circuit"]
    bellow, tank, pipe = _chambers_and_pipe(data, file)
    valves = coerce(data.get("valves", False), bool, file, P + ["valves"])
    lv = build(LevellingValve, data.get("levelling_valve"), file, P + ["levelling_valve"],
               bellow="", supply="supply", sensed=())
    dpv = _optional(DifferentialPressureValve, data, "differential_valve", file, P, a="", b="")
    supply = build(Supply, data.get("supply"), file, P + ["supply"])
    cross = _pipe(data["cross_pipe"], file, P + ["cross_pipe"]) if data.get("cross_pipe") is not None else None
    if layout == "two_point" and cross is None:
        raise ScenarioError(file, P + ["cross_pipe"], "a two_point layout needs a cross_pipe between the bellows of a bogie")
    spec = CarCircuit(layout, bellow, tank, pipe, valves, lv, dpv, supply, cross)
    # both valve settings: the runs may switch the valves (twist/curve valve_settings)
    for setting in (valves, not valves):
        _compile_check(dataclasses.replace(spec, valves=setting).components(), file, P, _LAYOUT_KEYS)
    return spec


def _compile_check(components, file, prefix, yaml_key_of) -> None:
    """Assemble once (cheap) so that inconsistent circuits fail before any simulation."""
    try:
        Circuit(components)
    except CircuitError as exc:
        raise _circuit_error(exc, file, prefix, yaml_key_of) from None


def _circuit_error(exc: CircuitError, file, prefix, yaml_key_of) -> ScenarioError:
    name, *rest = exc.path or ("",)
    return ScenarioError(file, [*prefix, yaml_key_of.get(name, name), *rest], exc.reason)


def _check_initial_state(circuit: CarCircuit, car, ks, valve_settings, path) -> None:
    """Start the circuit once as the runners will (cars/runs: cosim.kinds.car.build_cosimulation):
    bellow pressures that carry the car's static load, tanks at their bellow's, every k value; an
    initial state that cannot be set (a chamber with no initial pressure, an isothermal chamber
    not at the atmosphere's temperature) fails here, not in a worker process."""
    from cosim.kinds.car import static_pressures
    explicit = circuit.explicit is not None
    prefix, keys = (["circuit", "components"], {}) if explicit else (["circuit"], _LAYOUT_KEYS)
    for setting in dict.fromkeys(valve_settings):
        components = circuit.components() if explicit else dataclasses.replace(circuit, valves=setting).components()
        try:
            c = Circuit(components, k_W_per_K=list(ks))
            c.initial_state(static_pressures(components, car.static_bellow_forces_N(), c.atmosphere.p_Pa))
        except CircuitError as exc:
            if exc.reason == "initial pressure is not set":
                exc.reason += " (give it p0_Pa, or join it to a bellow by a pipe or an orifice: it starts at the bellow's)"
            raise _circuit_error(exc, path, prefix, keys) from None


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
            name = value["preset"]
            if name not in VEHICLE_PRESETS:
                raise ScenarioError(file, ["vehicle", "preset"], f"unknown vehicle preset {name!r} "
                                                                 f"(expected one of {', '.join(VEHICLE_PRESETS)})")
            defaults = dataclasses.asdict(VEHICLE_PRESETS[name]())
            value = {k: v for k, v in value.items() if k != "preset"}
        if base is not None:
            vpath = _param_file(coerce(base, str, file, ["vehicle", "file"]), file, ["vehicle", "file"])
            defaults = _read_params(vpath)
            build(VehicleParams, defaults, vpath, [])            # the file's own errors name the file
        merged = {**defaults, **{k: v for k, v in value.items() if k != "file"}}
        return build(VehicleParams, merged, file, ["vehicle"])
    raise ScenarioError(file, ["vehicle"], f"expected a parameter file path or a mapping, got {describe(value)}")


def _state_limits(value, file) -> StateLimits:
    """``state_limits``: the states that stop a case (:class:`~cosim.scenario.model.StateLimits`)."""
    limits = build(StateLimits, value, file, ["state_limits"])
    for low, high in (("T_min_K", "T_max_K"), ("p_min_Pa", "p_max_Pa")):
        if not getattr(limits, low) < getattr(limits, high):
            raise ScenarioError(file, ["state_limits", high], f"must exceed {low} ({getattr(limits, low):g}), "
                                                              f"got {getattr(limits, high):g}")
    return limits


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
    name = value.get("preset", DEFAULT_TRACK_PRESET)
    if name not in TRACK_PRESETS:
        raise ScenarioError(file, ["track", "preset"], f"unknown track preset {name!r} "
                                                       f"(expected one of {', '.join(TRACK_PRESETS)})")
    defaults = {k: v for k, v in dataclasses.asdict(TRACK_PRESETS[name]()).items() if k != "model"}
    return build(TrackStructure, {**defaults, **fields}, file, ["track"], model="flexible")


def _check_car_builds(vehicle: VehicleParams, source, file):
    """Build the car once (~0.1 s): constraints between parameters (e.g. the bellow's upper plate
    above its lower one) fail here, as bad input, not later inside a worker process. Returns the
    car (its static bellow forces start the circuit, :func:`_check_initial_state`)."""
    from vehicle.car import MetroCar  # exudyn: only for car scenarios
    try:
        return MetroCar(vehicle)
    except Exception as exc:                    # noqa: BLE001 -- whatever the parameters break is bad input
        where = Path(file).parent / source if isinstance(source, str) else file
        reason = str(exc) if isinstance(exc, ValueError) else f"{type(exc).__name__}: {exc}"
        raise ScenarioError(where, ["vehicle"] if where == file else [], f"inconsistent car parameters: {reason}") from None
