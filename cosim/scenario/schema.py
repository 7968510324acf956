"""Validate plain YAML data into parameter dataclasses, with errors that say where and what.

One generic mechanism serves every parameter dataclass (pneumatic components, vehicle
parameters, test definitions): field types come from the dataclass annotations; every number
must be finite (``.inf`` only where the field's default is infinite, where it means something:
an infinite supply reservoir, a rigid damper mounting); and every number must lie in its range
(:data:`RANGES`, looked up as ``Class.field`` along the class's MRO, then by unit suffix,
:data:`SUFFIX_RANGES`: a quantity such as a volume, a mass, an absolute pressure or a duration is
> 0). Lists are checked element by element, and for being non-empty and free of duplicates where
that matters (:data:`LIST_RULES`). The checks are pure functions of the data: the first field in
error, in the dataclass's field order, is reported, whatever the interpreter's hash seed.
"""
from __future__ import annotations

import dataclasses
import math
import re
import typing
from typing import Any, Dict, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

from cosim.errors import ScenarioError
from vehicle.params import VehicleParams

_NUMBER_STRING = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)[eE][+-]?\d+$")


# ----------------------------------------------------------------------------------- ranges
class Range(NamedTuple):
    """Allowed values of a number: ``low``/``high`` bounds (None: unbounded), each inclusive or
    not; ``nonzero`` excludes 0; ``unit`` and ``why`` complete the message."""

    low: Optional[float] = None
    high: Optional[float] = None
    low_inclusive: bool = True
    high_inclusive: bool = True
    unit: str = ""
    why: str = ""
    nonzero: bool = False
    #: 0 (an absent component) and inf (a rigid one) allowed besides the bounds
    zero_or_inf: bool = False

    def admits(self, v: float) -> bool:
        if self.zero_or_inf and (v == 0 or v == math.inf):
            return True
        if self.nonzero and v == 0:
            return False
        if self.low is not None and not (v >= self.low if self.low_inclusive else v > self.low):
            return False
        if self.high is not None and not (v <= self.high if self.high_inclusive else v < self.high):
            return False
        return True

    def expected(self, integer: bool = False) -> str:
        u = f" {self.unit}" if self.unit else ""
        a = "an integer" if integer else ""
        if self.low is not None and self.high is not None:
            lo, hi = ("[" if self.low_inclusive else "("), ("]" if self.high_inclusive else ")")
            text = f"{a} in {lo}{_num(self.low)}, {_num(self.high)}{hi}{u}"
        elif self.low is not None:
            text = f"{a} {'>=' if self.low_inclusive else '>'} {_num(self.low)}{u}"
        elif self.high is not None:
            text = f"{a} {'<=' if self.high_inclusive else '<'} {_num(self.high)}{u}"
        else:
            text = a or "a number"
        if self.nonzero:
            text += f" other than 0{u}"
        if self.zero_or_inf:
            text = f"0 (none), inf (rigid) or{text}"
        text = text.strip()
        return text + (f" ({self.why})" if self.why else "")


def _num(v) -> str:
    """A bound or a value for messages: 1000000, not 1e+06; 0.005, 1e-08."""
    if isinstance(v, int) or (isinstance(v, float) and v.is_integer() and abs(v) < 1e7):
        return str(int(v))
    return f"{v:g}"


def positive(unit: str = "", why: str = "") -> Range:
    return Range(0.0, None, False, True, unit, why)


def nonnegative(unit: str = "", why: str = "") -> Range:
    return Range(0.0, None, True, True, unit, why)


#: Largest number of samples (time points) one series may hold: 1e6 rows of a few dozen columns
#: are ~100 MB in memory; the shipped scenarios store at most 12 000.
MAX_SAMPLES = 1_000_000
#: Most integration steps one run may take (macro-steps of a car run; the rig's integrator
#: steps, bounded below by its largest step): 1e7 steps are hours of computing. The shipped
#: scenarios take at most 120 000.
MAX_STEPS = 10_000_000
#: ``Class.field`` -> allowed range; looked up along the class's MRO before the suffix rules (a
#: kind's experiment dataclass declares its own: ``FIELD_RANGES``).
RANGES: Dict[str, Range] = {
    # pneumatic components
    "Bellow.dA_dz_m": Range(unit="m", why="change of effective area with crushing, either sign"),
    "Bellow.area_table_m2": Range(0.0, 2.0, False, True, "m^2", "an airspring's effective area"),
    "Bellow.area_table_z_m": Range(-0.5, 0.5, unit="m", why="crushing from the static height"),
    "Pipe.length_m": positive("m"),
    "Pipe.diameter_m": Range(0.0, 0.3, False, True, "m", "a pneumatic pipe's bore"),
    "Pipe.friction_factor": nonnegative(why="Darcy friction factor lambda"),
    "Pipe.zeta": nonnegative(why="pressure-loss coefficient of fittings"),
    "Orifice.b_critical": Range(0.0, 1.0, True, False, why="ISO 6358 critical pressure ratio"),
    "LevellingValve.b_critical": Range(0.0, 1.0, True, False, why="ISO 6358 critical pressure ratio"),
    "LevellingValve.lag_s": nonnegative("s", "0: no lag"),
    "LevellingValve.delay_s": nonnegative("s", "0: no delay"),
    "LevellingValve.hysteresis_m": Range(0.0, 0.05, unit="m", why="the lever's play; 0: no play"),
    "LevellingValve.delay_stages": Range(1, 1000, why="first-order stages approximating the delay; "
                                                      "one state each"),
    "Fault.t_s": nonnegative("s", "when the fault happens; 0: from the start"),
    "Fault.area_m2": Range(0.0, 0.1, False, True, "m^2", "an opening's effective area (a bellow's is ~0.13 m^2)"),
    "Fault.C_m3_per_sPa": Range(0.0, 1e-4, False, True, "m^3/(s Pa)", "an ISO 6358 sonic conductance"),
    "Fault.b_critical": Range(0.0, 1.0, True, False, why="ISO 6358 critical pressure ratio"),
    "Fault.lever_m": Range(-0.2, 0.2, unit="m", why="a levelling valve's lever displacement (+ opens the supply side)"),
    "SolverSettings.jobs": Range(1, 256, why="worker processes"),
    "StateLimits.carbody_roll_rad": Range(0.0, 3.2, False, True, "rad", "a roll relative to the track plane"),
    "StateLimits.bogie_roll_rad": Range(0.0, 3.2, False, True, "rad", "a roll relative to the track plane"),
    "StateLimits.bellow_crushing_fraction": Range(0.0, 10.0, False, True, why="a fraction of the bellow height"),
    "StateLimits.bellow_volume_fraction": Range(0.0, 1.0, True, False, why="a fraction of the bellow's volume"),
    "SolverSettings.spectral_radius": Range(0.0, 1.0, unit="",
                                            why="generalized-alpha: 1 damps nothing, 0 the most"),
    "VerifySettings.tolerance": Range(0.0, 1.0, False, False, why="a relative error"),
    "VerifySettings.levels": Range(2, 6, why="halvings of every step; each doubles the cost of the last run"),
    # vehicle: every parameter is a mass, inertia, length, height above rail, stiffness, damping or
    # clearance, none negative (0: the component is absent); the geometry and masses within what
    # rail vehicles have, from a tram module to a loaded locomotive, so that a value typed in the
    # wrong unit (tonnes, millimetres) is refused with the slip named
    "VehicleParams.gravity_m_per_s2": Range(9.7, 9.9, unit="m/s^2", why="gravity on the Earth's surface"),
    "VehicleParams.carbody_mass_kg": Range(2e3, 1.5e5, unit="kg", why="a carbody"),
    "VehicleParams.bogie_mass_kg": Range(2e2, 2e4, unit="kg", why="a bogie frame"),
    "VehicleParams.wheelset_mass_kg": Range(1e2, 5e3, unit="kg", why="a wheelset"),
    "VehicleParams.bogie_centre_distance_m": Range(2.0, 40.0, unit="m", why="between the bogie centres"),
    "VehicleParams.wheelbase_m": Range(1.0, 5.0, unit="m", why="a bogie's wheelbase"),
    "VehicleParams.contact_spacing_m": Range(0.9, 1.8, unit="m", why="between the wheels' contact points, "
                                                                     "gauges 1000-1676 mm"),
    "VehicleParams.wheel_radius_m": Range(0.15, 0.8, unit="m", why="a wheel's rolling radius"),
    "VehicleParams.primary_lateral_spacing_m": Range(0.5, 4.0, unit="m", why="across the car"),
    "VehicleParams.airspring_lateral_spacing_m": Range(0.5, 4.0, unit="m", why="across the car"),
    "VehicleParams.secondary_vertical_damper_lateral_spacing_m": Range(0.0, 4.0, unit="m", why="across the car"),
    "VehicleParams.yaw_damper_lateral_spacing_m": Range(0.0, 4.0, unit="m", why="across the car"),
    "VehicleParams.arb_link_spacing_m": Range(0.0, 4.0, unit="m", why="across the car; 0: no bar"),
    "VehicleParams.arb_lever_arm_m": Range(0.0, 2.0, unit="m", why="the bar's lever; 0: no bar"),
    **{f"VehicleParams.{name}": Range(0.0, 5.0, unit="m", why="a height above the rail top")
       for name in ("airspring_lower_height_m", "airspring_upper_height_m", "floor_height_m", "carbody_cog_height_m",
                    "bogie_cog_height_m", "secondary_lateral_damper_height_m", "yaw_damper_height_m",
                    "traction_rod_height_m")},
    **{f"VehicleParams.{name}": Range(0.0, 0.3, unit="m", why="a bumpstop's free travel")
       for name in ("lateral_bumpstop_clearance_m", "vertical_bumpstop_clearance_m")},
    **{f"VehicleParams.{body}_inertia_{axis}_kg_m2": Range(1.0, 1e8, False, True, "kg m^2", f"a {body}'s inertia")
       for body in ("carbody", "bogie", "wheelset") for axis in ("xx", "yy", "zz")},
    # stiffnesses and dampings: 0 (absent) or inf (rigid), else within what suspension elements
    # have; a value in kN/m or kN s/m typed as N/m is a thousand times too small
    **{f"VehicleParams.{f.name}": Range(1e3, 1e10, unit="N/m", why="a spring", zero_or_inf=True)
       for f in dataclasses.fields(VehicleParams) if f.name.endswith("_N_per_m")
       and not f.name.startswith("primary_stiffness")},
    **{f"VehicleParams.{f.name}": Range(10.0, 1e7, unit="N s/m", why="a damper", zero_or_inf=True)
       for f in dataclasses.fields(VehicleParams) if f.name.endswith("_N_s_per_m")},
    **{f"VehicleParams.{f.name}": Range(1e3, 1e9, unit="N m/rad", why="a torsion spring", zero_or_inf=True)
       for f in dataclasses.fields(VehicleParams) if f.name.endswith("_N_m_per_rad")},
    **{f"VehicleParams.primary_stiffness_{axis}_N_per_m": Range(1e3, 1e10, unit="N/m", why="a primary spring")
       for axis in "xyz"},
    "VehicleParams.hertz_constant_N_per_m1_5": positive("N/m^1.5"),
}

#: Unit suffix -> range, for fields :data:`RANGES` does not name (longest suffix first):
#: quantities that only make sense positive (pressures are absolute).
SUFFIX_RANGES: Tuple[Tuple[str, Range], ...] = (
    # rates first: a velocity ends in _s too, and its message must say m/s, not s
    ("_m_per_s", positive("m/s")), ("_kg_per_s", positive("kg/s")), ("_rad_per_s", positive("rad/s")),
    ("_kg_m2", positive("kg m^2")),
    ("_m3", positive("m^3")), ("_m2", positive("m^2")), ("_kg", positive("kg")), ("_Pa", positive("Pa absolute")),
    ("_K", positive("K")), ("_s", positive("s")), ("_Hz", positive("Hz")), ("_m3_per_sPa", positive("m^3/(s Pa)")),
)

#: Class -> range of every other number of that class.
CLASS_RANGES: Dict[str, Range] = {
    "VehicleParams": nonnegative(why="a vehicle parameter; 0: the component is absent"),
    "TrackStructure": positive(why="a flexible track's mass, stiffness or damping"),
}

#: ``Class.field`` of list fields -> (must be non-empty, must hold no duplicates).
LIST_RULES: Dict[str, Tuple[bool, bool]] = {
}   # valve settings: check_valve_settings; a kind's experiment declares its own (FIELD_LIST_RULES)


def _lookup(table: Mapping[str, Any], cls, name: str, attribute: str = "FIELD_RANGES"):
    """The rule of field ``name`` of ``cls``: from the class's own ``attribute`` (a mapping a kind's
    experiment dataclass declares, e.g. ``FIELD_RANGES = {"base_m": ...}``), else from ``table``
    (``Class.field``), along the MRO."""
    for klass in getattr(cls, "__mro__", ()):
        rule = vars(klass).get(attribute, {}).get(name)
        if rule is None:
            rule = table.get(f"{klass.__name__}.{name}")
        if rule is not None:
            return rule
    return None


def range_of(cls, name: str) -> Optional[Range]:
    """The range of field ``name`` of dataclass ``cls`` (None: any finite number)."""
    rule = _lookup(RANGES, cls, name)
    if rule is not None:
        return rule
    for suffix, rule in SUFFIX_RANGES:
        if name.endswith(suffix):
            return rule
    for klass in getattr(cls, "__mro__", ()):
        if klass.__name__ in CLASS_RANGES:
            return CLASS_RANGES[klass.__name__]
    return None


#: unit slips a value out of its range may be: (unit, factor to the right unit, what was typed)
UNIT_SLIPS = (("kg", 1e3, "tonnes"), ("m", 1e-3, "millimetres"), ("m", 1e-2, "centimetres"),
              ("kg m^2", 1e3, "t m^2"), ("m^2", 1e-4, "cm^2"), ("N/m", 1e3, "kN/m"), ("N s/m", 1e3, "kN s/m"),
              ("N m/rad", 1e3, "kN m/rad"))


def unit_slip(value: float, rule: Range) -> str:
    """A hint when ``value`` out of ``rule`` would be in it in the unit a user may have typed
    instead (tonnes for kg, millimetres for m ...): ``"; tonnes? (26 t = 26000 kg)"``."""
    for unit, factor, typed in UNIT_SLIPS:
        if rule.unit == unit and value != 0 and rule.admits(value * factor):
            return f"; {typed}? ({_num(value)} {typed} = {_num(value * factor)} {unit})"
    return ""


def check_range(value, rule: Optional[Range], file, path: Sequence[str]) -> None:
    if rule is not None and isinstance(value, (int, float)) and not isinstance(value, bool) and not rule.admits(value):
        raise ScenarioError(file, path, f"must be {rule.expected(isinstance(value, int))}, got {_num(value)}"
                                        f"{unit_slip(value, rule)}")


# ----------------------------------------------------------------------------------- types
def _type_name(tp) -> str:
    origin = typing.get_origin(tp)
    if origin is Union:
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        return " or ".join(_type_name(a) for a in args) + " (or null)"
    if origin in (tuple, Tuple):
        item = typing.get_args(tp)[0]
        return "a list of " + {float: "numbers", int: "integers", bool: "true/false values", str: "strings"}.get(
            item, _type_name(item))
    return {float: "a number", int: "an integer", bool: "true/false", str: "a string"}.get(tp, getattr(tp, "__name__", str(tp)))


def describe(value: Any) -> str:
    """What a YAML value is, for messages: ``a list [1, 2]``, ``a mapping``, ``nothing (null)``."""
    if value is None:
        return "nothing (null)"
    if isinstance(value, bool):
        return f"true/false ({str(value).lower()})"
    if isinstance(value, (dict, Mapping)):
        return "a mapping"
    if isinstance(value, (list, tuple)):
        text = repr(list(value))
        return f"a list {text if len(text) <= 60 else text[:57] + '...'}"
    if isinstance(value, str):
        text = repr(value)
        return f"a string {text if len(text) <= 60 else text[:57] + '...'}"
    if isinstance(value, (int, float)):
        return f"the number {value!r}" if not isinstance(value, int) or abs(value) < 10 ** 30 else "a huge integer"
    return f"{type(value).__name__} {value!r}"


def _item_path(path: Sequence[str], i: int):
    return [*path[:-1], f"{path[-1]}[{i}]"] if path else [f"[{i}]"]


def coerce(value: Any, tp, file, path: Sequence[str], allow_inf: bool = False):
    """Check ``value`` against the annotation ``tp`` and return it converted (int -> float etc.);
    numbers must be finite (``allow_inf``: +-inf too, never NaN)."""
    origin = typing.get_origin(tp)
    if origin is Union:
        args = typing.get_args(tp)
        if value is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        return coerce(value, inner[0], file, path, allow_inf)
    if origin in (tuple, Tuple):
        if not isinstance(value, (list, tuple)):
            raise ScenarioError(file, path, f"expected {_type_name(tp)}, got {describe(value)}")
        item = typing.get_args(tp)[0]
        return tuple(coerce(v, item, file, _item_path(path, i), allow_inf) for i, v in enumerate(value))
    if tp is float:
        if isinstance(value, str) and _NUMBER_STRING.match(value.strip()):
            # YAML 1.1 (PyYAML) reads 4.0e5 as a string: it needs 4.0e+5. Accept the obvious intent.
            value = float(value)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ScenarioError(file, path, f"expected a number, got {describe(value)}")
        try:
            number = float(value)
        except OverflowError:                       # an integer of hundreds of digits
            raise ScenarioError(file, path, "expected a finite number, got an integer too large for a float") from None
        if math.isnan(number) or (math.isinf(number) and not allow_inf):
            raise ScenarioError(file, path, f"expected a finite number, got {number}")
        return number
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            if isinstance(value, float) and math.isfinite(value) and value == int(value) and abs(value) < 2 ** 53:
                return int(value)                   # 600.0: the obvious intent
            raise ScenarioError(file, path, f"expected an integer, got {describe(value)}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ScenarioError(file, path, f"expected true or false, got {describe(value)}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ScenarioError(file, path, f"expected a string, got {describe(value)}")
        return value
    raise TypeError(f"unsupported field type {tp!r}")


def _infinite_default(f: dataclasses.Field) -> bool:
    d = f.default
    return isinstance(d, float) and math.isinf(d)


def build(cls, data: Any, file, path: Sequence[str], **fixed):
    """Instantiate dataclass ``cls`` from mapping ``data`` (None = all defaults); ``fixed`` are set
    by the caller. Types, finiteness, ranges and list rules are checked (module doc)."""
    if data is None:
        data = {}
    if not isinstance(data, Mapping):
        raise ScenarioError(file, path, f"expected a mapping of {cls.__name__} parameters, got {describe(data)}")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    unknown = [k for k in data if k not in fields or k in fixed]
    if unknown:
        allowed = ", ".join(k for k in fields if k not in fixed)
        raise ScenarioError(file, [*path, str(unknown[0])], f"unknown key for {cls.__name__} (allowed: {allowed})")
    kwargs = dict(fixed)
    for name, f in fields.items():
        if name in fixed:
            continue
        if name not in data:
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
                raise ScenarioError(file, [*path, name], f"missing required key ({_type_name(hints[name])})")
            continue
        where = [*path, name]
        value = coerce(data[name], hints[name], file, where, allow_inf=_infinite_default(f))
        rule = range_of(cls, name)
        if isinstance(value, tuple):
            for i, v in enumerate(value):
                check_range(v, rule, file, _item_path(where, i))
            check_list(value, _lookup(LIST_RULES, cls, name, "FIELD_LIST_RULES"), file, where)
        elif isinstance(value, float) and math.isinf(value):      # only where the default is .inf
            if value != f.default:
                raise ScenarioError(file, where, f"expected a finite number or .inf, got {value}")
        else:
            check_range(value, rule, file, where)
        kwargs[name] = value
    return cls(**kwargs)


def check_list(values: Sequence, rule: Optional[Tuple[bool, bool]], file, path: Sequence[str]) -> None:
    """``rule`` = (non-empty, no duplicates); a duplicate is reported at its second occurrence."""
    if rule is None:
        return
    non_empty, unique = rule
    if non_empty and not values:
        raise ScenarioError(file, path, "expected at least one value, got an empty list")
    if unique:
        for i, v in enumerate(values):
            if v in values[:i]:
                raise ScenarioError(file, _item_path(path, i), f"{_text(v)} appears twice: each value at most once")


def _text(v) -> str:
    return str(v).lower() if isinstance(v, bool) else f"{v:g}" if isinstance(v, float) else str(v)


_KIND_NAMES = {dict: "a mapping", list: "a list", str: "a string", int: "an integer", float: "a number",
               bool: "true or false"}


def require(data: Mapping, key: str, file, path: Sequence[str], kind=None, default=dataclasses.MISSING):
    """Fetch ``data[key]`` checking its Python type (``kind``: a type or tuple of types)."""
    if key not in data:
        if default is not dataclasses.MISSING:
            return default
        raise ScenarioError(file, [*path, key], "missing required key")
    value = data[key]
    kinds = kind if isinstance(kind, tuple) else (kind,)
    if kind is not None and (not isinstance(value, kind) or (isinstance(value, bool) and bool not in kinds)):
        names = " or ".join(_KIND_NAMES.get(k, k.__name__) for k in kinds)
        raise ScenarioError(file, [*path, key], f"expected {names}, got {describe(value)}")
    return value


def check_keys(data: Mapping, allowed: Sequence[str], file, path: Sequence[str]) -> None:
    for key in data:
        if key not in allowed:
            raise ScenarioError(file, [*path, str(key)], f"unknown key (allowed: {', '.join(allowed)})")


def k_values(value: Any, file, path: Sequence[str]) -> Tuple[float, ...]:
    """A list of heat-transfer coefficients [W/K]: numbers >= 0 or .inf (isothermal)."""
    values = value if isinstance(value, (list, tuple)) else [value]
    out = []
    for i, v in enumerate(values):
        where = _item_path(path, i) if isinstance(value, (list, tuple)) else path
        k = coerce(v, float, file, where, allow_inf=True)
        if not k >= 0:
            raise ScenarioError(file, where, f"expected k >= 0 W/K (0 adiabatic, .inf isothermal), got {k:g}")
        if k in out:
            raise ScenarioError(file, where, f"k = {_text(k)} appears twice: each case must be distinct")
        out.append(k)
    if not out:
        raise ScenarioError(file, path, "expected at least one k value, got an empty list")
    return tuple(out)


def check_valve_settings(settings, path, where) -> None:
    """A list of valve settings (false: valves isolated, true: connected): each at most once, not
    empty; None: one run as ``circuit.valves`` says."""
    if settings is None:
        return
    if not settings:
        raise ScenarioError(path, where, "expected at least one setting (false: valves isolated, true: connected)")
    if len(set(settings)) != len(settings):
        raise ScenarioError(path, where, f"each setting at most once, got {list(settings)}")


def k_label(k: float) -> str:
    """k for file names and legends: 0, 10, 1e+04, inf."""
    return "inf" if math.isinf(k) else f"{k:g}"


def known_name(value, known, file, where, what: str) -> str:
    """``value`` as one of the names in ``known`` (a preset, a layout ...), or an error naming the
    key: a list or a mapping where a name belongs is refused as such, not hashed."""
    if not isinstance(value, str):
        raise ScenarioError(file, list(where), f"expected a {what} name (one of {', '.join(known)}), got {describe(value)}")
    if value not in known:
        raise ScenarioError(file, list(where), f"unknown {what} {value!r} (expected one of {', '.join(known)})")
    return value


def folder_name(value, file, where) -> str:
    """A ``name`` that names an output folder: one path component, so that nothing is written
    outside the folder the user chose (no / or \\, not . or .., no control characters, at most 100
    characters)."""
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise ScenarioError(file, list(where), f"expected a string, got {describe(value)}")
    name = str(value)
    if (not name.strip() or name in (".", "..") or any(c in name for c in "/\\") or any(ord(c) < 32 for c in name)
            or len(name) > 100):
        raise ScenarioError(file, list(where), f"expected a name usable as a folder name (no / or \\, no control "
                                               f"characters, at most 100 characters), got {name!r}")
    return name
