"""A corpus of malformed scenarios, files and command lines: each
ends in exit 2 before anything is simulated, with one message naming the file, the key path as
the user wrote it and what was expected, no traceback, within seconds.

Most cases call the CLI in this process (``cosim.cli.main``) with the simulation replaced by a
tripwire, so a case that would start simulating fails loudly; a few run ``pneumorail`` in a
subprocess, as a user would, and one checks that the messages do not depend on the hash seed.
"""
from __future__ import annotations

import copy
import dataclasses
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, Optional, Sequence, Union

import pytest
import yaml

from cosim import cli
from cosim.load import load_scenario

from helpers import SCENARIOS, short_twist, vehicle_file

PARAMS = vehicle_file(tempfile.mkdtemp(prefix="pneumorail_params_"))   # a parameter file, as a user writes one
INF, NAN = float("inf"), float("nan")
DELETE = object()


def _shipped(name: str) -> dict:
    data = yaml.safe_load((SCENARIOS / name).read_text())
    if isinstance(data.get("vehicle"), str):
        data["vehicle"] = str(PARAMS)
    if "solver" in data:
        data["solver"]["jobs"] = 1
    return data


#: base scenarios the cases change (car scenarios with the vehicle file as an absolute path)
BASES: Dict[str, Callable[[], dict]] = {
    "ramp": lambda: _shipped("rig_ramp.yaml"),
    "sine": lambda: _shipped("rig_sine_1hz.yaml"),
    "stiff": lambda: _shipped("rig_stiffness.yaml"),
    "table2": lambda: _shipped("rig_table2.yaml"),
    "twist": short_twist,                                  # ramp 1 s + hold 1 s, steps 10 ms
    "en": lambda: _shipped("twist_en14363.yaml"),
    "explicit": lambda: _shipped("twist_throttled_tanks.yaml"),
    "curve": lambda: _shipped("curve_entry.yaml"),
    "irregular": lambda: _shipped("straight_irregular.yaml"),
    "stability": lambda: _shipped("stability_ramp.yaml"),
    "ride": lambda: _shipped("ride_comfort.yaml"),
}


@dataclass
class Case:
    """``base`` changed by ``changes`` (dotted key -> value, DELETE) or given as raw ``text``
    (bytes, or a function of the base's YAML text); ``argv``: more CLI arguments. The message
    must name ``file`` ("scenario", "vehicle": car.yaml beside it, or None: a CLI option), the
    key path ``where`` and contain ``phrase``."""

    base: Optional[str]
    where: str
    phrase: str
    changes: Dict[str, Any] = field(default_factory=dict)
    text: Union[bytes, Callable[[str], str], None] = None
    argv: Sequence[str] = ()
    file: Optional[str] = "scenario"
    vehicle_file: Union[bytes, dict, None] = None          # written as car.yaml beside the scenario
    no_file: bool = False                                   # the scenario path does not exist
    command: str = "run"


def _set(data: dict, key: str, value) -> None:
    node = data
    *parents, last = key.split(".")
    for p in parents:
        node = node.setdefault(p, {})
    if value is DELETE:
        node.pop(last, None)
    else:
        node[last] = value


def _alias_bomb() -> bytes:
    return b"a: &a [x, x, x, x, x, x, x, x, x]\n" + b"".join(
        f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n".encode()
        for p, c in zip("abcdefgh", "bcdefghi"))


def _components(**extra) -> dict:
    """The explicit circuit of twist_throttled_tanks.yaml with ``extra`` components added."""
    comps = _shipped("twist_throttled_tanks.yaml")["circuit"]["components"]
    comps.update(extra)
    return {"components": comps}


def _reordered() -> dict:
    comps = _shipped("twist_throttled_tanks.yaml")["circuit"]["components"]
    return {"components": {"FR": comps.pop("FR"), **comps}}


NUMBERS = {  # numbers not finite or out of range
    "infinite hold": Case("twist", "twist.hold_s", "finite", {"twist.hold_s": INF}),
    "nan ramp": Case("twist", "twist.ramp_s", "finite", {"twist.ramp_s": NAN}),
    "infinite rig duration": Case("ramp", "test.duration_s", "finite", {"test.duration_s": INF}),
    "infinite output interval": Case("twist", "solver.output_interval_s", "finite", {"solver.output_interval_s": INF}),
    "zero frequency": Case("sine", "test.frequency_Hz", "must be > 0 Hz, got 0", {"test.frequency_Hz": 0}),
    "negative frequency": Case("sine", "test.frequency_Hz", "> 0 Hz", {"test.frequency_Hz": -2.0}),
    "zero in a frequency list": Case("stiff", "test.frequencies_Hz[1]", "> 0 Hz", {"test.frequencies_Hz": [1.0, 0.0]}),
    "infinite in a frequency list": Case("stiff", "test.frequencies_Hz[1]", "finite",
                                         {"test.frequencies_Hz": [1.0, INF]}),
    "empty frequency list": Case("stiff", "test.frequencies_Hz", "at least one", {"test.frequencies_Hz": []}),
    "zero pipe diameter (rig)": Case("ramp", "circuit.pipe.diameter_m", "in (0, 0.3] m", {"circuit.pipe.diameter_m": 0}),
    "zero pipe diameter (car)": Case("twist", "circuit.pipe.diameter_m", "in (0, 0.3] m", {"circuit.pipe.diameter_m": 0.0}),
    "zero pipe length": Case("ramp", "circuit.pipe.length_m", "> 0", {"circuit.pipe.length_m": 0}),
    "zero samples": Case("ramp", "test.samples", "must be an integer in [2, 1000000] (stored time points), got 0",
                         {"test.samples": 0}),
    "negative samples": Case("ramp", "test.samples", "got -5", {"test.samples": -5}),
    "a billion samples": Case("ramp", "test.samples", "an integer in [2, 1000000]", {"test.samples": 10 ** 9}),
    "zero samples per period": Case("sine", "test.samples_per_period", "[2, 10000]", {"test.samples_per_period": 0}),
    "zero amplitude (ramp)": Case("ramp", "test.amplitude_m", "other than 0", {"test.amplitude_m": 0}),
    "zero amplitude (stiffness)": Case("stiff", "test.amplitude_m", "other than 0", {"test.amplitude_m": 0.0}),
    "zero amplitude (table 2)": Case("table2", "test.amplitude_m", "other than 0", {"test.amplitude_m": 0.0}),
    "negative base length": Case("twist", "twist.base_m", "> 0 m", {"twist.base_m": -10.0}),
    "twist of 100 permille": Case("twist", "twist.twist_per_mille", "[0, 21] per mille", {"twist.twist_per_mille": 100}),
    "negative twist": Case("twist", "twist.twist_per_mille", "[0, 21]", {"twist.twist_per_mille": -4}),
    "bogie twist of 50 permille": Case("en", "twist.bogie_twist_per_mille", "[0, 21] per mille",
                                       {"twist.bogie_twist_per_mille": 50}),
    "infinite bellow volume": Case("ramp", "circuit.bellow.V0_m3", "finite", {"circuit.bellow.V0_m3": INF}),
    "infinite pipe diameter": Case("twist", "circuit.pipe.diameter_m", "finite", {"circuit.pipe.diameter_m": INF}),
    "infinite cant": Case("curve", "curve.cant_rad", "finite", {"curve.cant_rad": INF}),
    "cant of 1 rad": Case("curve", "curve.cant_rad", "[-0.2, 0.2] rad", {"curve.cant_rad": 1.0}),
    "infinite speed": Case("curve", "curve.speed_m_per_s", "finite", {"curve.speed_m_per_s": INF}),
    "zero speed": Case("curve", "curve.speed_m_per_s", "m/s", {"curve.speed_m_per_s": 0}),
    "supersonic speed": Case("curve", "curve.speed_m_per_s", "360 km/h", {"curve.speed_m_per_s": 400}),
    "negative radius": Case("curve", "curve.radius_m", "[10, 100000] m", {"curve.radius_m": -100}),
    "negative k": Case("ramp", "k_W_per_K[1]", ">= 0 W/K", {"k_W_per_K": [0, -1]}),
    "minus infinite k": Case("ramp", "k_W_per_K[0]", ">= 0 W/K", {"k_W_per_K": [-INF]}),
    "nan k": Case("ramp", "k_W_per_K[0]", "finite", {"k_W_per_K": [NAN]}),
    "macro-step longer than the run": Case("twist", "solver.macro_step_s", "longer than the run",
                                           {"solver.macro_step_s": 5.0, "solver.mechanics_step_s": 5.0,
                                            "solver.pneumatic_step_s": 5.0, "solver.output_interval_s": 5.0}),
    "zero macro-step": Case("twist", "solver.macro_step_s", "> 0 s", {"solver.macro_step_s": 0}),
    "nan pressure": Case("ramp", "circuit.p0_Pa", "finite", {"circuit.p0_Pa": NAN}),
    "negative supply pressure": Case("en", "circuit.supply.p_Pa", "[20000, 2000000] Pa absolute",
                                     {"circuit.supply.p_Pa": -9e5}),
    "nan zeta": Case("ramp", "circuit.pipe.zeta", "finite", {"circuit.pipe.zeta": NAN}),
    "zero drift threshold": Case("sine", "test.stable_drift_K_per_period", "> 0",
                                 {"test.stable_drift_K_per_period": 0}),
    "a billion delay stages": Case("en", "circuit.levelling_valve.delay_stages", "[1, 1000]",
                                   {"circuit.levelling_valve.delay_stages": 10 ** 9}),
    "negative valve lag": Case("en", "circuit.levelling_valve.lag_s", ">= 0 s", {"circuit.levelling_valve.lag_s": -1}),
    "zero orifice conductance": Case("explicit", "circuit.components.throttle_FL.C_m3_per_sPa", "> 0",
                                     {"circuit.components.throttle_FL.C_m3_per_sPa": 0}),
    "critical ratio of 1.5": Case("explicit", "circuit.components.throttle_RR.b_critical", "[0, 1)",
                                  {"circuit.components.throttle_RR.b_critical": 1.5}),
    "a 400-digit number": Case("ramp", "test.amplitude_m", "too large", text=lambda t: t.replace(
        "amplitude_m: 0.02", "amplitude_m: 1" + "0" * 400)),
    "zero verify tolerance": Case("twist", "verify.tolerance", "(0, 1)", {"verify.tolerance": 0}),
    "negative vehicle stiffness": Case("twist", "vehicle.primary_stiffness_z_N_per_m", "[1000, 1e+10] N/m",
                                       {"vehicle": {"file": str(PARAMS), "primary_stiffness_z_N_per_m": -1.0}}),
    "zero gravity": Case("twist", "vehicle.gravity_m_per_s2", "[9.7, 9.9] m/s^2", argv=["--set", "vehicle.gravity_m_per_s2=0"]),
    "nan vehicle mass (--set)": Case("twist", "vehicle.carbody_mass_kg", "finite",
                                     argv=["--set", "vehicle.carbody_mass_kg=.nan"]),
    "infinite hold (--set)": Case("twist", "twist.hold_s", "finite", argv=["--set", "twist.hold_s=.inf"]),
    "infinite macro-step (--set)": Case("twist", "solver.macro_step_s", "finite",
                                        argv=["--set", "solver.macro_step_s=.inf"]),
    "a run of 1e9 samples": Case("sine", "test.duration_s", "samples", {"test.duration_s": 1.0e8}),
    "a ramp of a microsecond": Case("ramp", "test.ramp_s", "steps", {"test.ramp_s": 1e-6}),
    "more jobs than any machine": Case("twist", "solver.jobs", "[1, 256]", {"solver.jobs": 100000}),
}

DUPLICATES = {
    "the same k twice": Case("ramp", "k_W_per_K[1]", "twice", {"k_W_per_K": [0, 0.0]}),
    "the same k twice (--k)": Case("twist", "--k[2]", "twice", argv=["--k", "0,10,0"]),
    "the same k twice (--set)": Case("twist", "k_W_per_K[1]", "twice", argv=["--set", "k_W_per_K=[0, 0]"]),
    "duplicate top-level key": Case(None, "kind", "duplicate key", text=b"kind: twist\nkind: curve_entry\n"),
    "duplicate nested key": Case("ramp", "test.ramp_s", "duplicate key (first at line", text=lambda t: t.replace(
        "test:\n", "test:\n  ramp_s: 2.0\n", 1)),
    "duplicate component name": Case("explicit", "circuit.components.FL", "duplicate key", text=lambda t: t.replace(
        "    FR:", "    FL:\n      type: bellow\n    FR:", 1)),
    "duplicate frequencies": Case("stiff", "test.frequencies_Hz[2]", "twice", {"test.frequencies_Hz": [1.0, 2.0, 1.0]}),
    "duplicate raised wheels": Case("twist", "twist.raised_wheels[1]", "twice", {"twist.raised_wheels": ["1R", "1R"]}),
    "duplicate configurations": Case("ramp", "test.configurations[1]", "twice",
                                     {"test.configurations": ["bellow_tank", "bellow_tank"]}),
    "duplicate valve settings": Case("en", "twist.valve_settings", "at most once", {"twist.valve_settings": [True, True]}),
}

FILES = {  # files that cannot be scenarios
    "binary": Case(None, "(top level)", "binary", text=bytes(range(256)) * 4),
    "latin-1": Case(None, "(top level)", "UTF-8", text="kind: twist\nname: caf\xe9\n".encode("latin-1")),
    "utf-16": Case(None, "(top level)", "binary", text="kind: twist\n".encode("utf-16")),
    "too large": Case(None, "(top level)", "kB", text=b"# padding\n" * 200_000),
    "deep flow nesting": Case(None, "(top level)", "nesting deeper", text=b"a: " + b"[" * 5000 + b"]" * 5000 + b"\n"),
    "deep block nesting": Case(None, "(top level)", "nesting deeper", text=b"- " * 5000 + b"x\n"),
    "alias bomb": Case(None, "(top level)", "expands", text=_alias_bomb()),
    "a long list": Case(None, "(top level)", "values", text=b"k_W_per_K: [" + b"1, " * 60_000 + b"1]\n"),
    "empty": Case(None, "(top level)", "empty document", text=b""),
    "only comments": Case(None, "(top level)", "empty document", text=b"# kind: twist\n"),
    "a list": Case(None, "(top level)", "mapping", text=b"- 1\n- 2\n"),
    "a scalar": Case(None, "(top level)", "mapping", text=b"twist\n"),
    "missing": Case(None, "(top level)", "no such file", no_file=True),
    "not yaml": Case(None, "(top level)", "not valid YAML", text=b"kind: [twist\n"),
    "two documents": Case(None, "(top level)", "not valid YAML", text=b"kind: twist\n---\nkind: twist\n"),
    "python tag": Case(None, "(top level)", "not valid YAML", text=b"kind: !!python/object/apply:os.system [ls]\n"),
    "impossible date": Case(None, "(top level)", "cannot be read", text=b"kind: twist\nname: 2024-13-45\n"),
    "binary vehicle file": Case("twist", "(top level)", "binary", {"vehicle": "car.yaml"}, file="vehicle",
                                vehicle_file=bytes(range(256))),
    "vehicle file a list": Case("twist", "(top level)", "mapping of vehicle parameters", {"vehicle": "car.yaml"},
                                file="vehicle", vehicle_file=b"- 1\n"),
    "empty vehicle file under file:": Case("twist", "(top level)", "empty document",
                                           {"vehicle": {"file": "car.yaml", "carbody_mass_kg": 17000.0}},
                                           file="vehicle", vehicle_file=b""),
}

KEYS = {  # messages that must name the key the user wrote
    "negative zeta": Case("ramp", "circuit.pipe.zeta", ">= 0", {"circuit.pipe.zeta": -1.11}),
    "negative zeta (car)": Case("twist", "circuit.pipe.zeta", ">= 0", {"circuit.pipe.zeta": -1.0}),
    "negative zeta (explicit pipe)": Case("explicit", "circuit.components.pipe_X.zeta", ">= 0",
                                          {"circuit": _components(pipe_X={"type": "pipe", "a": "tank_FL",
                                                                          "b": "tank_FR", "zeta": -1})}),
    "no loss at all": Case("ramp", "circuit.pipe.zeta", "lambda L/d + zeta must be > 0",
                           {"circuit.pipe.zeta": 0, "circuit.pipe.friction_factor": 0}),
    "negative friction factor": Case("twist", "circuit.pipe.friction_factor", ">= 0",
                                     {"circuit.pipe.friction_factor": -0.02}),
    "missing vehicle file": Case("twist", "vehicle", "does not exist", {"vehicle": "no_such_car.yaml"}),
    "missing vehicle file under file:": Case("twist", "vehicle.file", "does not exist",
                                             {"vehicle": {"file": "no_such_car.yaml"}}),
    "vehicle file is a folder": Case("twist", "vehicle", "not a file", {"vehicle": "."}),
    "vehicle path with a NUL byte": Case("twist", "vehicle", "does not exist", {"vehicle": "car\0.yaml"}),
    "unknown key in the vehicle file": Case("twist", "carbody_mas_kg", "unknown key", {"vehicle": "car.yaml"},
                                            file="vehicle", vehicle_file={"carbody_mas_kg": 17000.0}),
    "negative mass in the vehicle file": Case("twist", "bogie_mass_kg", "[200, 20000] kg", {"vehicle": "car.yaml"},
                                              file="vehicle", vehicle_file={"bogie_mass_kg": -1900.0}),
    "--set =1": Case("twist", "--set", "non-empty key path", argv=["--set", "=1"]),
    "--set without =": Case("twist", "--set", "expected key.path=value", argv=["--set", "twist.hold_s"]),
    "--set empty part": Case("twist", "--set", "non-empty key path", argv=["--set", "twist..hold_s=1"]),
    "--set malformed YAML": Case("twist", "--set twist.hold_s", "not valid YAML", argv=["--set", "twist.hold_s=[1"]),
    "--set alias bomb": Case("twist", "--set twist.hold_s", "expands",
                             argv=["--set", "twist.hold_s={" + _alias_bomb().decode().strip().replace("\n", ", ") + "}"]),
    "--set into a number": Case("twist", "kind", "cannot descend", argv=["--set", "kind.x=1"]),
    "--k garbage": Case("twist", "--k", "comma-separated numbers", argv=["--k", "0,ten"], file=None),
    "--k negative": Case("twist", "--k", ">= 0", argv=["--k", "-1"], file=None),
    "--k nan": Case("twist", "--k", ">= 0", argv=["--k", "nan"], file=None),
    "--jobs 0": Case("twist", "--jobs", "must be an integer in [1, 256]", argv=["--jobs", "0"]),
    "verify --levels 1": Case("twist", "--levels", "an integer in [2, 6]", argv=["--levels", "1"], command="verify"),
    # the same range as the scenario's verify.levels key: 50 halvings would run for days
    # bounded work: an irregularity is counted before it is generated (these used to be killed
    # out of memory after tens of seconds)
    "irregularity every 0.1 um": Case("irregular", "curve.irregularity.ds_m", "more than 1e+07",
                                      {"curve.irregularity.ds_m": 1e-7}),
    # (a wavelength's range, 0.1 m to 1 km, now refuses this before its memory is counted)
    "irregularity to 1e9 m wavelengths": Case("irregular", "curve.irregularity.wavelength_range_m[1]", "[0.1, 1000] m",
                                              {"curve.irregularity.wavelength_range_m": [3.0, 1e9]}),
    "irregular straight of 4e8 m": Case("irregular", "curve.straight_m", "more than 200 km would not fit",
                                        {"curve.straight_m": 4e8}),
    "irregularity over 150 km": Case("irregular", "curve.irregularity.ds_m", "the track's 150022 m",
                                     {"curve.straight_m": 1.5e5, "curve.irregularity.ds_m": 0.01}),
    # one meaning for null: "none" (tank, differential_valve, cross_pipe); where none cannot be
    # meant it is refused instead of read as the defaults
    "null levelling valve": Case("twist", "circuit.levelling_valve", "write {} for the defaults",
                                 {"circuit.levelling_valve": None}),
    # a value typed in the wrong unit is refused with the slip named
    "carbody in tonnes": Case("twist", "vehicle.carbody_mass_kg", "26 tonnes = 26000 kg",
                              {"vehicle": {"preset": "paper_metro_car", "carbody_mass_kg": 26}}),
    "CoG height in mm": Case("twist", "vehicle.carbody_cog_height_m", "millimetres? (1600 millimetres = 1.6 m)",
                             {"vehicle": {"preset": "paper_metro_car", "carbody_cog_height_m": 1600}}),
    "wheel radius in mm": Case("twist", "vehicle.wheel_radius_m", "millimetres?",
                               {"vehicle": {"preset": "paper_metro_car", "wheel_radius_m": 420}}),
    "airspring spacing in mm": Case("twist", "vehicle.airspring_lateral_spacing_m", "2000 millimetres = 2 m",
                                    {"vehicle": {"preset": "paper_metro_car", "airspring_lateral_spacing_m": 2000}}),
    "valve play of 2 m": Case("twist", "circuit.levelling_valve.hysteresis_m", "[0, 0.05] m",
                              {"circuit.levelling_valve": {"hysteresis_m": 2.0}}),
    "pipe bore of 18 m": Case("twist", "circuit.pipe.diameter_m", "18 millimetres = 0.018 m",
                              {"circuit.pipe.diameter_m": 18.0}),
    "area table in cm^2": Case("twist", "circuit.bellow.area_table_m2[0]", "cm^2? (1200 cm^2 = 0.12 m^2)",
                               {"circuit.bellow.area_table_z_m": [-0.05, 0.0, 0.05],
                                "circuit.bellow.area_table_m2": [1200, 1300, 1400]}),
    "area table crushing in mm": Case("twist", "circuit.bellow.area_table_z_m[0]", "millimetres?",
                                      {"circuit.bellow.area_table_z_m": [-50, 0, 50],
                                       "circuit.bellow.area_table_m2": [0.12, 0.13, 0.14]}),
    "primary stiffness in kN/m": Case("twist", "vehicle.primary_stiffness_z_N_per_m", "kN/m? (680 kN/m = 680000 N/m)",
                                      {"vehicle": {"preset": "paper_metro_car", "primary_stiffness_z_N_per_m": 680}}),
    "straight of 4e8 m": Case("curve", "curve.straight_m", "more than 200 km would not fit in memory",
                              {"curve.straight_m": 4e8}),
    "zero blow-off velocity": Case("twist", "vehicle.secondary_vertical_damper_blowoff_velocity_m_per_s", "> 0 m/s,",
                                   {"vehicle": {"preset": "metro_car_arb_dampers",
                                                "secondary_vertical_damper_blowoff_velocity_m_per_s": 0.0}}),
    "verify --levels 50": Case("twist", "--levels", "an integer in [2, 6]", argv=["--levels", "50"], command="verify"),
}

TYPES = {  # wrong types, unknown keys and names
    # a name where a list or mapping was written: refused as such, not a TypeError (unhashable)
    "list for a circuit preset": Case("twist", "circuit.preset", "expected a circuit preset name",
                                      {"circuit.preset": ["paper_table1"]}),
    "mapping for a vehicle preset": Case("twist", "vehicle.preset", "expected a vehicle preset name",
                                         {"vehicle": {"preset": {"name": "paper_metro_car"}}}),
    "list for a track preset": Case("twist", "track.preset", "expected a track preset name",
                                    {"track": {"model": "flexible", "preset": ["slab_track"]}}),
    "string for a number": Case("ramp", "test.amplitude_m", "expected a number, got a string 'abc'",
                                {"test.amplitude_m": "abc"}),
    "list for a number": Case("twist", "twist.hold_s", "expected a number, got a list", {"twist.hold_s": [1, 2]}),
    "bool for a number": Case("twist", "twist.ramp_s", "expected a number, got true/false", {"twist.ramp_s": True}),
    "float for an integer": Case("ramp", "test.samples", "expected an integer", {"test.samples": 1.5}),
    "list for a mapping": Case("ramp", "circuit.pipe", "expected a mapping", {"circuit.pipe": [1, 2]}),
    "number for the circuit": Case("ramp", "circuit", "expected a mapping, got the number 5", {"circuit": 5}),
    "string for a list": Case("twist", "twist.raised_wheels", "expected a list of strings", {"twist.raised_wheels": "1R"}),
    "string for the checks": Case("twist", "checks", "expected a list", {"checks": "dqq_max <= 0.6"}),
    "string for k": Case("ramp", "k_W_per_K[0]", "expected a number", {"k_W_per_K": ["lots"]}),
    "number for the vehicle": Case("twist", "vehicle", "expected a parameter file path or a mapping", {"vehicle": 5}),
    "number for the kind": Case("ramp", "kind", "expected a string", {"kind": 5}),
    "unknown kind": Case("ramp", "kind", "unknown kind 'rig_teleport'", {"kind": "rig_teleport"}),
    "list for the name": Case("ramp", "name", "expected a string", {"name": [1]}),
    "a name that leaves the results folder": Case("ramp", "name", "folder name", {"name": "../../etc"}),
    "unknown top-level key": Case("ramp", "tset", "unknown key", {"tset": {}}),
    "unknown key in circuit": Case("ramp", "circuit.tanks", "unknown key", {"circuit.tanks": {}}),
    "unknown key in circuit (car)": Case("twist", "circuit.valve", "unknown key", {"circuit.valve": True}),
    "unknown key in a component": Case("ramp", "circuit.pipe.diameter", "unknown key for Pipe",
                                       {"circuit.pipe.diameter": 0.018}),
    "unknown key in the test": Case("sine", "test.frequency", "unknown key for SineTest", {"test.frequency": 1.0}),
    "unknown key in twist": Case("twist", "twist.hold", "unknown key for TwistTest", {"twist.hold": 1.0}),
    "unknown key in solver": Case("twist", "solver.step_s", "unknown key for SolverSettings", {"solver.step_s": 0.01}),
    "unknown key in vehicle": Case("twist", "vehicle.mass_kg", "unknown key for VehicleParams",
                                   {"vehicle": {"file": str(PARAMS), "mass_kg": 1.0}}),
    "unknown component type": Case("explicit", "circuit.components.X.type", "unknown component type 'flux_capacitor'",
                                   {"circuit": _components(X={"type": "flux_capacitor"})}),
    "component without a type": Case("explicit", "circuit.components.X.type", "missing",
                                     {"circuit": _components(X={"V_m3": 0.01})}),
    "link to a missing component": Case("explicit", "circuit.components.throttle_FL.b", "'tank_XX', which is not",
                                        {"circuit.components.throttle_FL.b": "tank_XX"}),
    "a fifth bellow": Case("explicit", "circuit.components.X", "four bellows",
                           {"circuit": _components(X={"type": "bellow"})}),
    "unknown coupling": Case("twist", "solver.coupling", "expected one of linearised, explicit",
                             {"solver.coupling": "magic"}),
    "unknown pipe model": Case("ramp", "circuit.pipe.model", "expected one of", {"circuit.pipe.model": "laminar"}),
    "unknown configuration": Case("ramp", "test.configurations[0]", "bellow_tank or bellow_only",
                                  {"test.configurations": ["diesel"]}),
    "unknown layout": Case("twist", "circuit.layout", "four_point", {"circuit.layout": "three_point"}),
    "curve direction 0": Case("curve", "curve.direction", "1 (left) or -1 (right)", {"curve.direction": 0}),
}

CROSS = {  # rules between fields
    "amplitude beyond the bellow stroke": Case("ramp", "test.amplitude_m", "V0/(dV/dz)", {"test.amplitude_m": 0.5}),
    "stiffness amplitude beyond the stroke": Case("stiff", "test.amplitude_m", "V0/(dV/dz)",
                                                  {"test.amplitude_m": -0.1}),
    "twist height beyond a plausible lift": Case("twist", "twist.twist_per_mille", "at most 200 mm",
                                                 {"twist.twist_per_mille": 20, "twist.base_m": 30.0}),
    "EN 14363 twist over an implausible base": Case("twist", "twist.base_m", "rise by 1500 mm",
                                                    {"twist.base_m": 500.0}),
    "steps do not divide the run": Case("twist", "solver.macro_step_s", "whole number of macro-steps",
                                        {"solver.macro_step_s": 0.003, "solver.mechanics_step_s": 0.003,
                                         "solver.pneumatic_step_s": 0.003, "solver.output_interval_s": 0.003}),
    "output interval not a multiple of the macro-step": Case("twist", "solver.output_interval_s", "whole number",
                                                             {"solver.output_interval_s": 0.015}),
    "multibody step beyond the macro-step": Case("twist", "solver.mechanics_step_s", "must not exceed",
                                                 {"solver.mechanics_step_s": 0.02}),
    "a run of 1e8 rows": Case("twist", "solver.macro_step_s", "at most", {"twist.hold_s": 1e6}),
    "window longer than the hold": Case("twist", "twist.window_s", "within the hold", {"twist.window_s": 200.0}),
    "window longer than the curve run": Case("curve", "curve.window_s", "within the run", {"curve.window_s": 31.0}),
    "curve run beyond the track": Case("curve", "curve.duration_s", "leaves the track", {"curve.duration_s": 60.0}),
    "straight shorter than the car": Case("curve", "curve.straight_m", "whole car", {"curve.straight_m": 5.0}),
    "ramp longer than the run": Case("ramp", "test.ramp_s", "within the run", {"test.ramp_s": 100.0}),
    "sine shorter than two periods": Case("sine", "test.duration_s", "at least 2 periods", {"test.duration_s": 1.0}),
    "bogie twist without its base": Case("twist", "twist.bogie_twist_per_mille", "bogie_base_m",
                                         {"twist.bogie_twist_per_mille": 7.0}),
    "bogie base not the car's": Case("en", "twist.bogie_base_m", "vehicle.wheelbase_m", {"twist.bogie_base_m": 2.5}),
    "two valve settings on an explicit circuit": Case("explicit", "twist.valve_settings", "has no levelling valve",
                                                      {"twist.valve_settings": [False, True]}),
    "valves on for an explicit circuit without valves": Case("explicit", "twist.valve_settings", "give [false]",
                                                             {"twist.valve_settings": [True]}),
    "isothermal bellow not at ambient": Case("explicit", "circuit.components.FL.T0_K", "isothermal",
                                             {"circuit.components.FL.T0_K": 350.0}),
    "tank with no initial pressure": Case("explicit", "circuit.components.tank_X.p0_Pa", "not set",
                                          {"circuit": _components(tank_X={"type": "tank"})}),
    "valve table wrong while the valves are off": Case(
        "twist", "circuit.levelling_valve.supply_lever_m", "increase strictly",
        {"circuit.levelling_valve": {"supply_lever_m": [0.0, 0.01, 0.005]}, "twist.valve_settings": [False, True]}),
    "two_point without a cross pipe": Case("twist", "circuit.cross_pipe", "cross_pipe",
                                           {"circuit.layout": "two_point"}),
    "check on an unknown k": Case("twist", "checks[0]", "k", {"checks": ["dqq_max[k=5] <= 0.6"]}),
}

def _burst(**fields):
    return [{"kind": "burst", "component": "FL", "t_s": 0.5, "area_m2": 5e-4, **fields}]


FAULTS = {  # faults: validated before anything runs (the twist base: 2 s, valves isolated)
    "fault of a component not in the circuit": Case("twist", "faults[0].component", "not a component",
                                                    {"faults": _burst(component="XX")}),
    "burst of a pipe": Case("twist", "faults[0].component", "needs a chamber", {"faults": _burst(component="pipe_FL")}),
    "pipe blocked given a bellow": Case("twist", "faults[0].component", "needs pipe or orifice",
                                        {"faults": [{"kind": "blocked", "component": "FL"}]}),
    "fault after the end of the run": Case("twist", "faults[0].t_s", "within the run", {"faults": _burst(t_s=5.0)}),
    "fault before the start": Case("twist", "faults[0].t_s", ">= 0", {"faults": _burst(t_s=-1.0)}),
    "burst without an opening": Case("twist", "faults[0].area_m2", "one of them", {"faults": _burst(area_m2=None)}),
    "burst area in cm^2": Case("twist", "faults[0].area_m2", "cm^2", {"faults": _burst(area_m2=5.0)}),
    "unknown fault kind": Case("twist", "faults[0].kind", "unknown fault kind", {"faults": _burst(kind="explode")}),
    "unknown fault key": Case("twist", "faults[0].where", "unknown key", {"faults": _burst(where="FL")}),
    "faults not a list": Case("twist", "faults", "a list of faults", {"faults": {"kind": "burst"}}),
    "valve fault with the valves isolated": Case("en", "faults[0].component", "valve_settings: [true]",
                                                 {"faults": [{"kind": "stuck_closed", "component": "lv_FL"}]}),
    "stuck-open valve without a side": Case("en", "faults[0].side", "supply, exhaust",
                                            {"faults": [{"kind": "stuck_open", "component": "lv_FL"}],
                                             "twist.valve_settings": [True]}),
    "--set of a fault that is not there": Case("twist", "faults[1]", "list of 1", {"faults": _burst()},
                                               argv=["--set", "faults[1].t_s=1.0"]),
}

STABILITY = {  # the stability kind's section
    "ramp that speeds up": Case("stability", "stability.ramp_to_m_per_s", "slows down",
                                {"stability.ramp_to_m_per_s": 50.0}),
    "ramp decelerating at 5 g": Case("stability", "stability.ramp_decelerations_m_per_s2[0]", "m/s^2",
                                     {"stability.ramp_decelerations_m_per_s2": [50.0]}),
    "speed in km/h": Case("stability", "stability.speeds_m_per_s[0]", "m/s", {"stability.speeds_m_per_s": [200.0]}),
    "no speeds": Case("stability", "stability.speeds_m_per_s", "empty", {"stability.speeds_m_per_s": []}),
    "disturbance in mm": Case("stability", "stability.disturbances_m[0]", "m", {"stability.disturbances_m": [3.0]}),
    "cone and profile": Case("stability", "stability.wheel_profile", "not both",
                             {"stability.conicity": 0.2, "stability.wheel_profile": "w.prw"}),
    "profile file missing": Case("stability", "stability.wheel_profile", "does not exist",
                                 {"stability.wheel_profile": "worn.prw"}),
    "conicity of a flange": Case("stability", "stability.conicity", "conicities", {"stability.conicity": 1.2}),
    "critical speed above the scan": Case("stability", "checks[0]", "scan ends at 50 m/s",
                                          {"checks": ["critical_speed_m_per_s >= 60"]}),
}

def _flexible(**fields):
    return {"track": {"model": "flexible", **fields}}


UNITS = {  # a number in its field's plausible range, else refused with the unit it was likely typed in
    "curve radius in km": Case("curve", "curve.radius_m", "got 0.25; kilometres? (0.25 kilometres = 250 m)",
                               {"curve.radius_m": 0.25}),
    "transition in mm": Case("curve", "curve.transition_m", "millimetres? (40000 millimetres = 40 m)",
                             {"curve.transition_m": 40000}),
    "supply pressure in bar": Case("en", "circuit.supply.p_Pa", "bar? (8 bar = 800000 Pa absolute)",
                                   {"circuit.supply.p_Pa": 8}),
    "rig pressure in bar": Case("ramp", "circuit.p0_Pa", "bar? (4 bar = 400000 Pa absolute)", {"circuit.p0_Pa": 4}),
    "bellow volume in litres": Case("twist", "circuit.bellow.V0_m3", "litres? (15 litres = 0.015 m^3)",
                                    {"circuit.bellow.V0_m3": 15}),
    "tank volume in litres (rig)": Case("ramp", "circuit.tank.V_m3", "litres? (27 litres = 0.027 m^3)",
                                        {"circuit.tank.V_m3": 27}),
    "bellow temperature in Celsius": Case("explicit", "circuit.components.FL.T0_K",
                                          "degrees Celsius? (20 degrees Celsius = 293.15 K)",
                                          {"circuit.components.FL.T0_K": 20}),
    "ride radius in km": Case("ride", "ride.radius_m", "kilometres? (0.3 kilometres = 300 m)", {"ride.radius_m": 0.3}),
    "ride cant in degrees": Case("ride", "ride.cant_rad", "degrees? (6 degrees = 0.10472 rad)",
                                 {"ride.radius_m": 300.0, "ride.cant_rad": 6}),
    # it was blamed on irregularity.ds_m (too many samples for the track of a 300 000 s record)
    "ride record in ms": Case("ride", "ride.record_s", "milliseconds? (300000 milliseconds = 300 s)",
                              {"ride.record_s": 300000}),
    "ride speed in km/h": Case("ride", "ride.speeds_m_per_s[1]", "km/h? (120 km/h = 33.3333 m/s)",
                               {"ride.speeds_m_per_s": [10.0, 120.0]}),
    "irregularity wavelength in mm": Case("irregular", "curve.irregularity.wavelength_range_m[0]",
                                          "millimetres? (3000 millimetres = 3 m)",
                                          {"curve.irregularity.wavelength_range_m": [3000, 150000]}),
    "negative irregularity seed": Case("irregular", "curve.irregularity.seed", ">= 0 (a random seed",
                                       {"curve.irregularity.seed": -1}),
    "track stiffness in MN/m": Case("twist", "track.vertical_stiffness_N_per_m", "MN/m? (144.8 MN/m = 1.448e+08 N/m)",
                                    _flexible(vertical_stiffness_N_per_m=144.8)),
    "track mass in tonnes": Case("twist", "track.mass_kg", "tonnes? (1.52 tonnes = 1520 kg)", _flexible(mass_kg=1.52)),
    "track damping in kN s/m": Case("twist", "track.vertical_damping_N_s_per_m", "kN s/m? (186.7 kN s/m",
                                    _flexible(vertical_damping_N_s_per_m=186.7)),
    "differential valve beyond 20 bar": Case("en", "circuit.differential_valve.dp_Pa[2]", "[0, 2000000] Pa",
                                             {"circuit.differential_valve": {"dp_Pa": [0, 1.5e5, 2.5e7]}}),
    "curve direction 2": Case("curve", "curve.direction", "1 (left) or -1 (right)", {"curve.direction": 2}),
    "friction above 1": Case("curve", "curve.friction_coefficient", "(0, 1]",
                             {"curve.guidance": "contact", "curve.friction_coefficient": 1.5}),
}


def _valve_faults(*faults):
    return {"faults": list(faults), "twist.valve_settings": [True]}


SEMANTICS = {  # values each in range that cannot be meant together: refused before any run
    "temperature limit in Celsius": Case("twist", "state_limits.T_max_K", "degrees Celsius? (200 degrees Celsius = "
                                                                          "473.15 K)", {"state_limits.T_max_K": 200}),
    "pressure limit below the static pressure": Case("twist", "state_limits.p_max_Pa", "when the run starts (FL: ",
                                                     {"state_limits.p_max_Pa": 3e5}),
    "pressure limit in bar": Case("twist", "state_limits.p_max_Pa", "bar? (50 bar = 5000000 Pa absolute)",
                                  {"state_limits.p_max_Pa": 50, "state_limits.p_min_Pa": 1}),
    "lower pressure limit above the supply": Case("en", "state_limits.p_min_Pa", "every case stops at its first step",
                                                  {"state_limits.p_min_Pa": 5e5}),
    "lower temperature limit above ambient": Case("twist", "state_limits.T_min_K", "below the air's temperature",
                                                  {"state_limits.T_min_K": 300}),
    "stuck open and stuck closed at once": Case("en", "faults[1]", "faults[0] already makes 'lv_FL' stuck open at 1 s",
                                                _valve_faults({"kind": "stuck_open", "component": "lv_FL", "side": "supply",
                                                               "t_s": 1.0},
                                                              {"kind": "stuck_closed", "component": "lv_FL", "t_s": 1.0})),
    "blocked and ruptured at once": Case("twist", "faults[1]", "one fault of a component at a time",
                                         {"faults": [{"kind": "blocked", "component": "pipe_FL", "t_s": 0.5},
                                                     {"kind": "ruptured", "component": "pipe_FL", "t_s": 0.5}]}),
    "mistyped valve with the valves also off": Case("en", "faults[0].component", "lv_FL, lv_FR",
                                                    {"faults": [{"kind": "stuck_closed", "component": "lv_FX"}],
                                                     "twist.valve_settings": [False, True]}),
    "quasi-static check on the straight": Case("curve", "checks[0]", "zone 'straight' has none",
                                               {"curve.guidance": "contact",
                                                "checks": ["Y_2m_p50[zone=straight] <= 60000"]}),
}

HEAT = {  # a chamber's own heat exchange (circuit.bellow.heat, circuit.tank.heat, a component's heat)
    "negative own k": Case("ramp", "circuit.bellow.heat.k_W_per_K", ">= 0 W/K or .inf",
                           {"circuit.bellow.heat": {"k_W_per_K": -1.0}}),
    "minus infinite own k": Case("twist", "circuit.tank.heat.k_W_per_K", ">= 0 W/K or .inf",
                                 {"circuit.tank.heat": {"k_W_per_K": -INF}}),
    "nan own k": Case("ramp", "circuit.tank.heat.k_W_per_K", "finite", {"circuit.tank.heat": {"k_W_per_K": NAN}}),
    "string for own k": Case("ramp", "circuit.bellow.heat.k_W_per_K", "expected a number, got a string",
                             {"circuit.bellow.heat": {"k_W_per_K": "high"}}),
    "number for the heat law": Case("ramp", "circuit.bellow.heat", "expected a mapping of ChamberHeat parameters",
                                    {"circuit.bellow.heat": 10}),
    "unknown heat key": Case("ramp", "circuit.bellow.heat.h_W_per_m2K", "unknown key for ChamberHeat",
                             {"circuit.bellow.heat": {"model": "correlation", "h_W_per_m2K": 5}}),
    "unknown heat model": Case("twist", "circuit.bellow.heat.model", "expected one of constant, correlation",
                               {"circuit.bellow.heat": {"model": "radiation"}}),
    "a constant law without its k": Case("ramp", "circuit.tank.heat.k_W_per_K", "needs its k", {"circuit.tank.heat": {}}),
    "a correlation given a k": Case("ramp", "circuit.bellow.heat.k_W_per_K", "the correlation computes k",
                                    {"circuit.bellow.heat": {"model": "correlation", "k_W_per_K": 5}}),
    "a correlation key on a constant law": Case("twist", "circuit.bellow.heat.wall_thickness_m", "model: correlation",
                                                {"circuit.bellow.heat": {"k_W_per_K": 5, "wall_thickness_m": 0.005}}),
    "a bellow given a diameter": Case("ramp", "circuit.bellow.heat.diameter_m", "a tank's",
                                      {"circuit.bellow.heat": {"model": "correlation", "diameter_m": 0.4}}),
    "wall thickness in mm": Case("ramp", "circuit.bellow.heat.wall_thickness_m", "millimetres? (6 millimetres = 0.006 m)",
                                 {"circuit.bellow.heat": {"model": "correlation", "wall_thickness_m": 6}}),
    "negative air speed": Case("twist", "circuit.tank.heat.air_speed_m_per_s", "[0, 100] m/s",
                               {"circuit.tank.heat": {"model": "correlation", "air_speed_m_per_s": -5}}),
    "emissivity above 1": Case("ramp", "circuit.tank.heat.emissivity", "[0, 1]",
                               {"circuit.tank.heat": {"model": "correlation", "emissivity": 1.5}}),
    "a tank narrower than its port": Case("ramp", "circuit.tank.heat.diameter_m", "wider than its port",
                                          {"circuit.tank.heat": {"model": "correlation", "diameter_m": 0.01}}),
    "an explicit component's heat": Case("explicit", "circuit.components.tank_FL.heat.wall_conductivity_W_per_mK",
                                         "(0.05, 500] W/(m K)", {"circuit.components.tank_FL.heat": {
                                             "model": "correlation", "wall_conductivity_W_per_mK": 0}}),
    "own k (--set)": Case("twist", "circuit.bellow.heat.k_W_per_K", ">= 0 W/K", argv=["--set",
                                                                                   "circuit.bellow.heat.k_W_per_K=-2"]),
}

CORPUS = {f"{group}: {name}": case for group, cases in (
    ("numbers", NUMBERS), ("duplicates", DUPLICATES), ("files", FILES), ("keys", KEYS), ("types", TYPES),
    ("cross-field", CROSS), ("faults", FAULTS), ("stability", STABILITY), ("units", UNITS),
    ("semantics", SEMANTICS), ("heat", HEAT)) for name, case in cases.items()}


def test_the_corpus_is_large_enough():
    assert len(CORPUS) >= 60


def _no_simulation(*args, **kwargs):
    raise AssertionError("the simulation started: this input should have been refused before")


def _write(case: Case, tmp_path: Path) -> Path:
    path = tmp_path / "scenario.yaml"
    if case.vehicle_file is not None:
        content = case.vehicle_file
        (tmp_path / "car.yaml").write_bytes(content if isinstance(content, bytes) else yaml.safe_dump(content).encode())
    if case.no_file:
        return path
    if isinstance(case.text, bytes):
        path.write_bytes(case.text)
        return path
    data = copy.deepcopy(BASES[case.base]())
    for key, value in case.changes.items():
        _set(data, key, value)
    text = yaml.safe_dump(data, sort_keys=False)
    path.write_text(case.text(text) if case.text else text)
    return path


def _main(argv, capsys):
    t0 = time.perf_counter()
    try:
        code = cli.main(argv)
    except SystemExit as exc:                       # argparse refuses an option before any file is read
        code = exc.code
    return code, capsys.readouterr().err, time.perf_counter() - t0


@pytest.mark.parametrize("name", list(CORPUS))
def test_bad_input_exits_2_naming_the_file_and_the_key(name, tmp_path, capsys, monkeypatch):
    case = CORPUS[name]
    monkeypatch.setattr("cosim.runner.run_scenario", _no_simulation)
    monkeypatch.setattr("cosim.verification.verify.verify", _no_simulation)
    path = _write(case, tmp_path)
    out = tmp_path / "out"
    code, err, seconds = _main([case.command, str(path), *case.argv, "--out", str(out)], capsys)
    assert code == cli.EXIT_BAD_INPUT, err
    assert "Traceback" not in err
    if case.file is None:
        assert case.where in err and case.phrase in err, err
    else:
        file = path if case.file == "scenario" else tmp_path / "car.yaml"
        assert f"error: {file}: {case.where}: " in err, err
        assert case.phrase in err, err
        assert len(err.strip().splitlines()) == 1, err          # one line
    assert seconds < 5.0
    assert not out.exists()


# ------------------------------------------------------------------ what is accepted, and stays so
def test_a_zero_valve_lag_is_accepted(tmp_path):
    # 0 (the default) means "no lag": written explicitly it must not trip the "_s > 0" rule
    data = _shipped("twist_en14363.yaml")
    data["circuit"]["levelling_valve"].update(lag_s=0, delay_s=0.0, hysteresis_m=0)
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    assert load_scenario(tmp_path / "s.yaml").circuit.levelling_valve.lag_s == 0.0


def test_a_chambers_own_heat_exchange_is_accepted_and_reaches_the_circuit(tmp_path):
    """heat: {model: correlation} on the bellows, an isothermal tank by its own k = .inf (YAML's
    infinity, admitted where the range says so); the preset's other keys stay."""
    data = BASES["twist"]()
    data["circuit"].update(bellow={"heat": {"model": "correlation", "air_speed_m_per_s": 0}},
                           tank={"heat": {"k_W_per_K": INF}})
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(data))
    circuit = load_scenario(path).circuit
    assert circuit.bellow.heat.model == "correlation" and circuit.bellow.heat.air_speed_m_per_s == 0.0
    assert circuit.tank.heat.k_W_per_K == INF and circuit.tank.V_m3 == 0.027
    components = circuit.components()
    assert components["FL"].heat == circuit.bellow.heat and components["tank_RR"].heat == circuit.tank.heat


def test_explicit_bellows_in_any_order_are_put_in_the_car_order(tmp_path):
    data = _shipped("twist_throttled_tanks.yaml")
    data["circuit"] = _reordered()
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data, sort_keys=False))
    names = [n for n, _ in load_scenario(tmp_path / "s.yaml").circuit.explicit]
    assert names[:4] == ["FL", "FR", "RL", "RR"]


def test_two_openings_of_one_chamber_may_coincide(tmp_path):
    """Two bursts of one bellow at one instant are two holes, not a contradiction."""
    data = BASES["twist"]()
    data["faults"] = _burst() + _burst(area_m2=1e-4)
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data))
    assert len(load_scenario(path).circuit.faults) == 2


def test_the_valves_default_tables_may_be_written(tmp_path):
    """A table starts at 0 (a dead band of conductance 0, a pressure difference of 0): written out
    as the defaults are, it is accepted (it was refused as a conductance or an absolute pressure
    that must be > 0)."""
    from pneumatics.valves import DifferentialPressureValve, LevellingValve
    lv, dpv = LevellingValve(""), DifferentialPressureValve("", "")
    data = BASES["en"]()
    data["circuit"]["levelling_valve"] = {k: list(getattr(lv, k)) for k in ("supply_lever_m", "supply_C_m3_per_sPa",
                                                                         "exhaust_lever_m", "exhaust_C_m3_per_sPa")}
    data["circuit"]["differential_valve"] = {"dp_Pa": list(dpv.dp_Pa), "q_kg_per_s": list(dpv.q_kg_per_s)}
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data))
    scenario = load_scenario(path)
    assert scenario.circuit.levelling_valve == dataclasses.replace(lv, bellow="", supply="supply")
    assert scenario.circuit.differential_valve == dpv


def test_an_infinite_supply_reservoir_may_be_written(tmp_path):
    # Supply.V_m3 defaults to .inf (a fixed-pressure source): writing it is not an error
    data = _shipped("twist_en14363.yaml")
    data["circuit"]["supply"]["V_m3"] = INF
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    assert load_scenario(tmp_path / "s.yaml").circuit.supply.is_fixed


# ------------------------------------------------------------------ as a user calls it: a subprocess
def _pneumorail(*args, env=None, timeout=30):
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "cosim.cli", *args], capture_output=True, text=True, timeout=timeout,
                          env=env)
    return proc, time.perf_counter() - t0


@pytest.mark.parametrize("name", ["files: binary", "files: deep flow nesting", "files: alias bomb",
                                  "keys: --set malformed YAML"])
@pytest.mark.slow
def test_in_a_fresh_process_no_traceback(name, tmp_path):
    case = CORPUS[name]
    path = _write(case, tmp_path)
    proc, seconds = _pneumorail(case.command, str(path), *case.argv, "--out", str(tmp_path / "out"))
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    assert f"error: {path}: {case.where}: " in proc.stderr and case.phrase in proc.stderr
    assert seconds < 5.0           # each refusal is immediate (the interpreter starts in ~1 s)
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_messages_do_not_depend_on_the_hash_seed(tmp_path):
    """Several faults in one pipe (the circuit's own check iterated over a set, so the field it
    named depended on PYTHONHASHSEED): always the first in field order."""
    data = _shipped("rig_ramp.yaml")
    data["circuit"]["pipe"] = {"length_m": 0.0, "diameter_m": 0.0, "friction_factor": 0.02, "zeta": -1.0}
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data))
    messages = set()
    for seed in ("0", "1", "2"):
        proc, _ = _pneumorail("run", str(path), "--out", str(tmp_path / "out"),
                              env={**os.environ, "PYTHONHASHSEED": seed})
        assert proc.returncode == 2 and "Traceback" not in proc.stderr
        messages.add(proc.stderr)
    assert len(messages) == 1
    assert f"{path}: circuit.pipe.length_m: " in messages.pop()
