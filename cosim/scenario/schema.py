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
from pathlib import Path
from typing import Any, Dict, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

_NUMBER_STRING = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)[eE][+-]?\d+$")


class ScenarioError(ValueError):
    """Bad input: which file, which key path, what was expected."""

    def __init__(self, file: Union[str, Path, None], path: Sequence[str], message: str):
        self.file = str(file) if file else "<scenario>"
        self.path = ".".join(str(p) for p in path) or "(top level)"
        self.reason = message
        super().__init__(f"{self.file}: {self.path}: {message}")

    def __reduce__(self):
        """Picklable (an error raised in a worker process reaches the user unchanged)."""
        return _scenario_error, (self.file, self.path, self.reason)


def _scenario_error(file: str, path: str, reason: str) -> "ScenarioError":
    error = ScenarioError(file, [], reason)
    error.path = path
    error.args = (f"{error.file}: {path}: {reason}",)
    return error


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

    def admits(self, v: float) -> bool:
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
        text = text.strip()
        return text + (f" ({self.why})" if self.why else "")


def _num(v) -> str:
    """A bound or a value for messages: 1000000, not 1e+06; 0.005, 1e-08."""
    if isinstance(v, int) or (isinstance(v, float) and v.is_integer() and abs(v) < 1e7):
        return str(int(v))
    return f"{v:g}"


def _pos(unit: str = "", why: str = "") -> Range:
    return Range(0.0, None, False, True, unit, why)


def _nonneg(unit: str = "", why: str = "") -> Range:
    return Range(0.0, None, True, True, unit, why)


#: Largest number of samples (time points) one series may hold: 1e6 rows of a few dozen columns
#: are ~100 MB in memory; the shipped scenarios store at most 12 000.
MAX_SAMPLES = 1_000_000
#: Largest track twist [per mille] a twist test may apply: three times the largest EN 14363 limit
#: (7 per mille, bases <= 4 m). Beyond it the "track" is no track: 100 per mille over a 10 m base
#: raises the rails by 1 m. (The test height is bounded as well: cosim.scenario.load.MAX_RAIL_LIFT_M.)
MAX_TWIST_PER_MILLE = 21.0
#: Largest cant [rad]: 0.2 rad is 300 mm over the 1.5 m rail-centre distance; railway cant is
#: limited to 150-200 mm (EN 13803: 180 mm, ~0.12 rad).
MAX_CANT_RAD = 0.2
#: Highest running speed [m/s]: 100 m/s = 360 km/h, beyond any metro and the wheel-rail model.
MAX_SPEED_M_PER_S = 100.0

_AMPLITUDE = Range(None, None, unit="m", why="a crushing amplitude; 0 moves nothing", nonzero=True)
_TWIST = Range(0.0, MAX_TWIST_PER_MILLE, unit="per mille",
               why="3 x the largest EN 14363 limit; 0: untwisted reference")

#: ``Class.field`` -> allowed range; looked up along the class's MRO before the suffix rules.
RANGES: Dict[str, Range] = {
    # pneumatic components
    "Bellow.dA_dz_m": Range(unit="m", why="change of effective area with crushing, either sign"),
    "Pipe.length_m": _pos("m"),
    "Pipe.diameter_m": _pos("m"),
    "Pipe.friction_factor": _nonneg(why="Darcy friction factor lambda"),
    "Pipe.zeta": _nonneg(why="pressure-loss coefficient of fittings"),
    "Orifice.b_critical": Range(0.0, 1.0, True, False, why="ISO 6358 critical pressure ratio"),
    "LevellingValve.b_critical": Range(0.0, 1.0, True, False, why="ISO 6358 critical pressure ratio"),
    "LevellingValve.lag_s": _nonneg("s", "0: no lag"),
    "LevellingValve.delay_s": _nonneg("s", "0: no delay"),
    "LevellingValve.hysteresis_m": _nonneg("m", "0: no play"),
    "LevellingValve.delay_stages": Range(1, 1000, why="first-order stages approximating the delay; "
                                                      "one state each"),
    # rig tests
    "RampTest.amplitude_m": _AMPLITUDE,
    "RampTest.samples": Range(2, MAX_SAMPLES, why="stored time points"),
    "SineTest.amplitude_m": _AMPLITUDE,
    "SineTest.frequency_Hz": _pos("Hz"),
    "SineTest.samples_per_period": Range(2, 10_000, why="stored time points per period"),
    "SineTest.stable_drift_K_per_period": _pos("K per period"),
    "StiffnessTest.amplitude_m": _AMPLITUDE,
    "StiffnessTest.frequencies_Hz": _pos("Hz"),
    "QuasiStaticTest.amplitude_m": _AMPLITUDE,
    # car tests
    "TwistTest.base_m": _pos("m", "the base length 2a*"),
    "TwistTest.bogie_base_m": _pos("m", "the wheelbase 2a+"),
    "TwistTest.twist_per_mille": _TWIST,
    "TwistTest.bogie_twist_per_mille": _TWIST,
    "TwistTest.settle_drift": _pos(why="a drift of dQ/Q0"),
    "CurveTest.speed_m_per_s": Range(0.0, MAX_SPEED_M_PER_S, False, True, "m/s", "360 km/h at most"),
    "CurveTest.straight_m": _pos("m"),
    "CurveTest.transition_m": _pos("m"),
    "CurveTest.radius_m": _pos("m"),
    "CurveTest.arc_m": _pos("m"),
    "CurveTest.cant_rad": Range(-MAX_CANT_RAD, MAX_CANT_RAD, unit="rad",
                                why="0.2 rad = 300 mm over 1.5 m; railway cant is at most ~0.12 rad"),
    "CurveTest.contact_damping_N_s_per_m": Range(0.0, 1e7, unit="N s/m",
                                                  why="the shipped 2e5 stands in for the track's damping"),
    "CurveTest.contact_smoothing_mm": Range(0.0, 1.0, unit="mm",
                                            why="0: the rigid table; 1 mm blurs the flange itself"),
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
    # clearance, none negative (0: the component is absent); these cannot be 0 either
    "VehicleParams.gravity_m_per_s2": _pos("m/s^2"),
    "VehicleParams.bogie_centre_distance_m": _pos("m"),
    "VehicleParams.wheelbase_m": _pos("m"),
    "VehicleParams.contact_spacing_m": _pos("m"),
    "VehicleParams.wheel_radius_m": _pos("m"),
    "VehicleParams.primary_lateral_spacing_m": _pos("m"),
    "VehicleParams.airspring_lateral_spacing_m": _pos("m"),
    "VehicleParams.primary_stiffness_x_N_per_m": _pos("N/m"),
    "VehicleParams.primary_stiffness_y_N_per_m": _pos("N/m"),
    "VehicleParams.primary_stiffness_z_N_per_m": _pos("N/m"),
    "VehicleParams.hertz_constant_N_per_m1_5": _pos("N/m^1.5"),
}

#: Unit suffix -> range, for fields :data:`RANGES` does not name (longest suffix first):
#: quantities that only make sense positive (pressures are absolute).
SUFFIX_RANGES: Tuple[Tuple[str, Range], ...] = (
    ("_kg_m2", _pos("kg m^2")),
    ("_m3", _pos("m^3")), ("_m2", _pos("m^2")), ("_kg", _pos("kg")), ("_Pa", _pos("Pa absolute")),
    ("_K", _pos("K")), ("_s", _pos("s")), ("_Hz", _pos("Hz")), ("_m3_per_sPa", _pos("m^3/(s Pa)")),
)
#: Kept for callers of the former interface.
POSITIVE_SUFFIXES = tuple(s for s, _ in SUFFIX_RANGES)

#: Class -> range of every other number of that class.
CLASS_RANGES: Dict[str, Range] = {
    "VehicleParams": _nonneg(why="a vehicle parameter; 0: the component is absent"),
    "TrackStructure": _pos(why="a flexible track's mass, stiffness or damping"),
}

#: ``Class.field`` of list fields -> (must be non-empty, must hold no duplicates).
LIST_RULES: Dict[str, Tuple[bool, bool]] = {
    "StiffnessTest.frequencies_Hz": (True, True),
    "RampTest.configurations": (True, True),
    "TwistTest.raised_wheels": (True, True),
}   # valve_settings: cosim.scenario.load._valve_settings


def _lookup(table: Mapping[str, Any], cls, name: str):
    for klass in getattr(cls, "__mro__", ()):
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


def check_range(value, rule: Optional[Range], file, path: Sequence[str]) -> None:
    if rule is not None and isinstance(value, (int, float)) and not isinstance(value, bool) and not rule.admits(value):
        raise ScenarioError(file, path, f"must be {rule.expected(isinstance(value, int))}, got {_num(value)}")


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
            check_list(value, _lookup(LIST_RULES, cls, name), file, where)
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
