"""``circuit: {fmu: FILE, map: ...}``: a car's circuit imported from an FMI 2.0 co-simulation FMU,
checked when the scenario is loaded, before anything runs (docs/fmi.md, "Import as a car's
circuit"). Nothing runs here: the FMU's model description is read (FMPy's reader, which loads no
binary); :mod:`cosim.engine.imported` runs the FMU.

What is checked, each error naming the scenario file, the key path and the FMU's variable: the
file exists and is a zip with a ``modelDescription.xml``; it is FMI 2.0 with co-simulation (a
model-exchange-only FMU is refused); the map has one entry per bellow of the car; every mapped
variable exists, is a Real (``isothermal``: a Boolean) of the right causality (the crushing and
its rate inputs, the force and what is recorded outputs, k and the step parameters) and, when the
FMU declares a unit, of the unit expected; the variables of the master's own exchange
(:data:`NATIVE_BELLOW_KEYS`, :data:`NATIVE_PARAMETER_KEYS`) all mapped or none."""
from __future__ import annotations

import hashlib
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Optional, Tuple

from cosim.errors import ScenarioError
from cosim.scenario.schema import check_keys, coerce, describe
from pneumatics.layouts import BELLOWS

#: per bellow: map key -> (required, causality, unit)
BELLOW_KEYS = {"crushing": (True, "input", "m"), "rate": (True, "input", "m/s"), "force": (True, "output", "N"),
               "pressure": (False, "output", "Pa"), "temperature": (False, "output", "K"),
               "crushing_end": (False, "input", "m"), "rate_end": (False, "input", "m/s"),
               "stiffness": (False, "output", "N/m"), "force_rate": (False, "output", "N/s")}
#: ``map.air``: the car run's air outputs an FMU output may give (each cumulative or a total) [kg]
AIR_KEYS = ("total_mass_kg", "air_from_supply_kg", "air_to_atmosphere_kg")
#: the parameters a map may name: key -> (variable type, unit)
PARAMETER_KEYS = {"k_W_per_K": ("Real", "W/K"), "isothermal": ("Boolean", None), "pneumatic_step_s": ("Real", "s"),
                  "lookahead": ("Boolean", None), "macro_step_s": ("Real", "s")}
#: calculated parameters a map may name: the sub-step the FMU uses (the importer gives every case
#: the shortest of every k's, as a native run does: ``pneumatic_step_s`` must be mapped too)
CALCULATED_KEYS = {"pneumatic_step_used_s": "s"}
#: what the master's own exchange needs of an FMU (all or none): per bellow, the crushing and rate
#: at the step's end in, the stiffness and the force's rate at frozen crushing out; the switch
#: that makes the FMU follow the crushing to the step's end, and the step of the force's rate
NATIVE_BELLOW_KEYS = ("crushing_end", "rate_end", "stiffness", "force_rate")
NATIVE_PARAMETER_KEYS = ("lookahead", "macro_step_s")

#: the model identifier of the FMUs ``pneumorail fmu`` exports (cosim.fmi.slave.PneumorailCircuit)
PNEUMORAIL_IDENTIFIER = "PneumorailCircuit"


def installed_version() -> str:
    """pneumorail's version here (as the FMU's slave reads it, cosim.fmi.slave)."""
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version("pneumorail")
    except PackageNotFoundError:
        return "not installed"


def pneumorail_map(native: bool = True) -> dict:
    """The map of an FMU ``pneumorail fmu`` exported (its variable names: docs/fmi.md); ``native``:
    with the variables of the master's own exchange (an FMU exported before they existed has none)."""
    extra = ({"crushing_end": "z_end_m", "rate_end": "zdot_end_m_per_s", "stiffness": "K_N_per_m",
              "force_rate": "dFdt_N_per_s"} if native else {})
    return {**{b: {"crushing": f"bellow_{b}.z_m", "rate": f"bellow_{b}.zdot_m_per_s", "force": f"bellow_{b}.F_N",
                   "pressure": f"bellow_{b}.p_Pa", "temperature": f"bellow_{b}.T_K",
                   **{key: f"bellow_{b}.{name}" for key, name in extra.items()}} for b in BELLOWS},
            "air": {"total_mass_kg": "total_air_mass_kg", "air_from_supply_kg": "air_injected_kg",
                    "air_to_atmosphere_kg": "air_exhausted_kg"},
            "k_W_per_K": "k_W_per_K", "isothermal": "isothermal", "pneumatic_step_s": "pneumatic_step_s",
            **({"lookahead": "lookahead", "macro_step_s": "macro_step_s",
                "pneumatic_step_used_s": "pneumatic_step_used_s"} if native else {})}


@dataclass(frozen=True)
class BellowMap:
    """The FMU's variables of one bellow: its crushing [m] and rate [m/s] in, its force [N] out,
    optionally its pressure [Pa] and temperature [K] out (recorded; else NaN)."""

    bellow: str
    crushing: str
    rate: str
    force: str
    pressure: Optional[str] = None
    temperature: Optional[str] = None
    crushing_end: Optional[str] = None
    rate_end: Optional[str] = None
    stiffness: Optional[str] = None
    force_rate: Optional[str] = None


@dataclass(frozen=True)
class ImportedCircuit:
    """A car's circuit as an FMU: where it is (resolved), its sha256, what identifies it, its map.
    ``valves``: whether its circuit has levelling valves (a label of the results: an FMU's
    valves cannot be switched); ``faults``: none (an FMU's circuit cannot be faulted from here)."""

    fmu: str
    sha256: str
    model_identifier: str
    guid: str
    bellows: Tuple[BellowMap, ...]
    air: Tuple[Tuple[str, str], ...] = ()
    k_W_per_K: Optional[str] = None
    isothermal: Optional[str] = None
    pneumatic_step_s: Optional[str] = None
    lookahead: Optional[str] = None
    macro_step_s: Optional[str] = None
    pneumatic_step_used_s: Optional[str] = None
    valves: bool = False
    faults: tuple = ()

    @property
    def native_exchange(self) -> bool:
        """The FMU takes the master's own exchange (docs/fmi.md): the crushing at both ends of
        the step in, the force law's stiffness and rate out."""
        return self.lookahead is not None

    def components(self) -> dict:
        """None of pneumorail's: the circuit is inside the FMU."""
        return {}

    def faults_label(self) -> str:
        return ""


def is_imported(circuit) -> bool:
    return isinstance(circuit, ImportedCircuit)


def imported_circuit(data: Mapping, file) -> ImportedCircuit:
    """``circuit: {fmu: FILE, map: {...}, valves: BOOL}`` checked against the FMU's model
    description (see the module docstring)."""
    P = ["circuit"]
    check_keys(data, ("fmu", "map", "valves"), file, P)
    name = coerce(data["fmu"], str, file, P + ["fmu"])
    path = Path(file).parent / name
    if not path.is_file():
        raise ScenarioError(file, P + ["fmu"], f"the FMU {str(path)!r} does not exist" if not path.exists()
                            else f"the FMU {str(path)!r} is not a file")
    if not zipfile.is_zipfile(path):
        raise ScenarioError(file, P + ["fmu"], f"{str(path)!r} is not an FMU: not a zip archive")
    with zipfile.ZipFile(path) as z:
        if "modelDescription.xml" not in z.namelist():
            raise ScenarioError(file, P + ["fmu"], f"{str(path)!r} is not an FMU: the zip has no modelDescription.xml")
    try:
        from fmpy import read_model_description
    except ImportError:
        raise ScenarioError(file, P + ["fmu"], "importing an FMU needs FMPy: pip install 'pneumorail[fmi]'") from None
    try:
        md = read_model_description(str(path), validate=False)
    except Exception as exc:                     # noqa: BLE001 -- FMPy's reader raises plain exceptions (and lxml's)
        raise ScenarioError(file, P + ["fmu"], f"{str(path)!r}: its modelDescription.xml cannot be read: {exc}") from None
    if md.fmiVersion != "2.0":
        raise ScenarioError(file, P + ["fmu"], f"{str(path)!r} is FMI {md.fmiVersion}: only FMI 2.0 is imported")
    if md.coSimulation is None:
        raise ScenarioError(file, P + ["fmu"], f"{str(path)!r} is a model-exchange FMU (no CoSimulation element): "
                                               f"only co-simulation FMUs are imported (the FMU must integrate itself)")
    identifier = md.coSimulation.modelIdentifier
    if identifier == PNEUMORAIL_IDENTIFIER and md.version != installed_version():
        raise ScenarioError(file, P + ["fmu"], f"{str(path)!r} was exported by pneumorail {md.version}; this is "
                                               f"pneumorail {installed_version()}: its slave runs pneumorail's own classes, "
                                               f"export it again with this version (docs/fmi.md)")
    variables = {v.name: v for v in md.modelVariables}
    if "map" in data:
        given = data["map"]
        if not isinstance(given, dict):
            raise ScenarioError(file, P + ["map"], f"expected a mapping (FL: {{crushing: ..., rate: ..., force: ...}}, "
                                                   f"...), got {describe(given)}")
    elif identifier == PNEUMORAIL_IDENTIFIER:
        given = pneumorail_map(native="lookahead" in variables)
    else:
        raise ScenarioError(file, P + ["map"], f"{str(path)!r} (model {identifier!r}) is not an FMU pneumorail exported: "
                                               f"give the map of its variables to the bellows (docs/fmi.md)")
    M = P + ["map"]
    check_keys(given, (*BELLOWS, "air", *PARAMETER_KEYS, *CALCULATED_KEYS), file, M)

    def variable(key_path, var_name, causality, unit, type_="Real") -> str:
        var_name = coerce(var_name, str, file, key_path)
        v = variables.get(var_name)
        if v is None:
            raise ScenarioError(file, key_path, f"the FMU {path.name} has no variable {var_name!r}")
        if v.causality != causality:
            raise ScenarioError(file, key_path, f"the FMU {path.name}'s variable {var_name!r} is {v.causality}: "
                                                f"expected {causality}")
        if v.type != type_:
            raise ScenarioError(file, key_path, f"the FMU {path.name}'s variable {var_name!r} is a {v.type}: "
                                                f"expected a {type_}")
        declared = v.unit or (v.declaredType.unit if v.declaredType is not None else None)
        if unit is not None and declared and declared != unit:
            raise ScenarioError(file, key_path, f"the FMU {path.name}'s variable {var_name!r} is in {declared}: "
                                                f"expected {unit}")
        return var_name

    bellows = []
    for b in BELLOWS:
        if b not in given:
            raise ScenarioError(file, M + [b], f"bellow {b} of the car is not mapped: give its crushing, rate and "
                                               f"force variables (one mapping per bellow: {', '.join(BELLOWS)})")
        entry = given[b]
        if not isinstance(entry, dict):
            raise ScenarioError(file, M + [b], f"expected a mapping {{crushing: ..., rate: ..., force: ...}}, got "
                                               f"{describe(entry)}")
        check_keys(entry, tuple(BELLOW_KEYS), file, M + [b])
        names = {}
        for key, (required, causality, unit) in BELLOW_KEYS.items():
            if key not in entry:
                if required:
                    raise ScenarioError(file, M + [b, key], f"missing: the FMU variable of bellow {b}'s {key} "
                                                            f"({causality}, {unit})")
                continue
            names[key] = variable(M + [b, key], entry[key], causality, unit)
        bellows.append(BellowMap(b, **names))
    air = given.get("air") or {}
    if not isinstance(air, dict):
        raise ScenarioError(file, M + ["air"], f"expected a mapping ({', '.join(AIR_KEYS)}: output), got {describe(air)}")
    check_keys(air, AIR_KEYS, file, M + ["air"])
    air_map = tuple((key, variable(M + ["air", key], air[key], "output", "kg")) for key in AIR_KEYS if key in air)
    parameters = {key: variable(M + [key], given[key], "parameter", unit, type_)
                  for key, (type_, unit) in PARAMETER_KEYS.items() if given.get(key) is not None}
    parameters.update({key: variable(M + [key], given[key], "calculatedParameter", unit)
                       for key, unit in CALCULATED_KEYS.items() if given.get(key) is not None})
    if "pneumatic_step_used_s" in parameters and "pneumatic_step_s" not in parameters:
        raise ScenarioError(file, M + ["pneumatic_step_s"], "pneumatic_step_used_s is mapped: map the parameter it "
                                                            "comes from too (the importer sets it)")
    _check_all_or_none(given, file, M)
    valves = coerce(data.get("valves", "valves connected" in (md.description or "")), bool, file, P + ["valves"])
    return ImportedCircuit(str(path.resolve()), hashlib.sha256(path.read_bytes()).hexdigest(), identifier, md.guid,
                           tuple(bellows), air_map, valves=valves, **parameters)


def _check_all_or_none(given: Mapping, file, M) -> None:
    """The master's own exchange needs every one of its variables (:data:`NATIVE_BELLOW_KEYS` of
    each bellow, :data:`NATIVE_PARAMETER_KEYS`), or none of them."""
    wanted = [[b, key] for b in BELLOWS for key in NATIVE_BELLOW_KEYS] + [[key] for key in NATIVE_PARAMETER_KEYS]
    given_paths = [p for p in wanted if (given[p[0]].get(p[1]) if len(p) == 2 else given.get(p[0])) is not None]
    if given_paths and len(given_paths) < len(wanted):
        missing = next(p for p in wanted if p not in given_paths)
        raise ScenarioError(file, M + missing, f"the master's own exchange ({', '.join(given_paths[0])} is mapped) needs "
                                               f"{', '.join(NATIVE_BELLOW_KEYS)} of every bellow and "
                                               f"{', '.join(NATIVE_PARAMETER_KEYS)}: map them all, or none")


def check_imported_ks(circuit: ImportedCircuit, ks, file) -> None:
    """Each k value is a case: set on the FMU's k parameter (k = inf: its isothermal switch); an
    FMU with no k parameter mapped runs one case, its k a label."""
    if circuit.k_W_per_K is None and len(ks) > 1:
        raise ScenarioError(file, ["k_W_per_K"], f"the FMU has no k parameter mapped (circuit.map.k_W_per_K): give one "
                                                 f"k value (it labels the case), got {len(ks)}")
    if circuit.k_W_per_K is not None and any(k == float("inf") for k in ks) and circuit.isothermal is None:
        raise ScenarioError(file, ["k_W_per_K"], "k = inf needs the FMU's isothermal switch mapped "
                                                 "(circuit.map.isothermal)")
