"""Validate plain YAML data into parameter dataclasses, with errors that say where and what.

One generic mechanism serves every parameter dataclass (pneumatic components, vehicle
parameters, test definitions): field types come from the dataclass annotations; every number
must be finite (``.inf`` only where the field's default is infinite, where it means something:
an infinite supply reservoir, a rigid damper mounting, or where its range admits it: a chamber's
own k = inf, isothermal); and every number must lie in its range:
the one its field declares next to it, as metadata (:mod:`pneumorail.quantities`), else the one
of its unit suffix (:data:`SUFFIX_RANGES`: a quantity such as a volume, a mass, an absolute
pressure or a duration is > 0). Lists are checked element by element, and for being non-empty
and free of duplicates where their field says so (metadata too). A field whose type is a dataclass
is a nested mapping, built by the same rules (its errors name the nested key). The checks are pure
functions of the data: the first field in error, in the dataclass's field order, is reported,
whatever the interpreter's hash seed.
"""
from __future__ import annotations

import dataclasses
import math
import re
import typing
from typing import Any, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

from cosim.errors import ScenarioError
from pneumorail.quantities import Range, list_rule_of_field, number_text, positive, range_of_field

_NUMBER_STRING = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)[eE][+-]?\d+$")


# ----------------------------------------------------------------------------------- ranges
_num = number_text


#: Largest number of samples (time points) one series may hold: 1e6 rows of a few dozen columns
#: are ~100 MB in memory; the shipped scenarios store at most 12 000.
MAX_SAMPLES = 1_000_000
#: Most integration steps one run may take (macro-steps of a car run; the rig's integrator
#: steps, bounded below by its largest step): 1e7 steps are hours of computing. The shipped
#: scenarios take at most 120 000.
MAX_STEPS = 10_000_000
#: Unit suffix -> range, for fields that declare none (longest suffix first):
#: quantities that only make sense positive (pressures are absolute).
SUFFIX_RANGES: Tuple[Tuple[str, Range], ...] = (
    # rates first: a velocity ends in _s too, and its message must say m/s, not s
    ("_m_per_s", positive("m/s")), ("_kg_per_s", positive("kg/s")), ("_rad_per_s", positive("rad/s")),
    ("_kg_m2", positive("kg m^2")),
    ("_m3", positive("m^3")), ("_m2", positive("m^2")), ("_kg", positive("kg")), ("_Pa", positive("Pa absolute")),
    ("_K", positive("K")), ("_s", positive("s")), ("_Hz", positive("Hz")), ("_m3_per_sPa", positive("m^3/(s Pa)")),
)

def _field(cls, name: str) -> Optional[dataclasses.Field]:
    fields = {f.name: f for f in dataclasses.fields(cls)} if dataclasses.is_dataclass(cls) else {}
    return fields.get(name)


def range_of(cls, name: str) -> Optional[Range]:
    """The range of field ``name`` of dataclass ``cls``: the one the field declares in its metadata
    (:func:`pneumorail.quantities.plausible`), else its unit suffix's (:data:`SUFFIX_RANGES`);
    None: any finite number."""
    f = _field(cls, name)
    rule = range_of_field(f) if f is not None else None
    if rule is not None:
        return rule
    for suffix, rule in SUFFIX_RANGES:
        if name.endswith(suffix):
            return rule
    return None


def list_rule_of(cls, name: str) -> Optional[Tuple[bool, bool]]:
    """(non-empty, no duplicates) of list field ``name`` of ``cls`` (its metadata; None: no rule)."""
    f = _field(cls, name)
    return list_rule_of_field(f) if f is not None else None


class UnitSlip(NamedTuple):
    """A unit a user may have typed instead of the field's ``unit``: the value in the right unit is
    ``value * factor + offset``."""

    unit: str
    factor: float
    typed: str
    offset: float = 0.0


#: unit slips a value out of its range may be, tried in this order (the first that brings the
#: value into its range is named)
UNIT_SLIPS = (UnitSlip("kg", 1e3, "tonnes"), UnitSlip("m", 1e-3, "millimetres"), UnitSlip("m", 1e-2, "centimetres"),
              UnitSlip("m", 1e3, "kilometres"), UnitSlip("kg m^2", 1e3, "t m^2"), UnitSlip("m^2", 1e-4, "cm^2"),
              UnitSlip("m^3", 1e-3, "litres"), UnitSlip("N/m", 1e3, "kN/m"), UnitSlip("N/m", 1e6, "MN/m"),
              UnitSlip("N s/m", 1e3, "kN s/m"), UnitSlip("N m/rad", 1e3, "kN m/rad"), UnitSlip("N m/rad", 1e6, "MN m/rad"),
              UnitSlip("N m s/rad", 1e3, "kN m s/rad"),
              *(UnitSlip(pa, factor, typed) for pa in ("Pa absolute", "Pa") for factor, typed in ((1e5, "bar"), (1e3, "kPa"))),
              UnitSlip("rad", math.pi / 180.0, "degrees"), UnitSlip("s", 1e-3, "milliseconds"),
              UnitSlip("m/s", 1.0 / 3.6, "km/h"), UnitSlip("K", 1.0, "degrees Celsius", 273.15))


def unit_slip(value: float, rule: Range) -> str:
    """A hint when ``value`` out of ``rule`` would be in it in the unit a user may have typed
    instead (tonnes for kg, millimetres for m, bar for Pa ...): ``"; tonnes? (26 tonnes = 26000
    kg)"``."""
    for slip in UNIT_SLIPS:
        right = value * slip.factor + slip.offset
        if rule.unit == slip.unit and value != 0 and rule.admits(right):
            return f"; {slip.typed}? ({_num(value)} {slip.typed} = {_num(right)} {slip.unit})"
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
    if dataclasses.is_dataclass(tp):                # a nested section (a chamber's heat: {...})
        return build(tp, value, file, path)
    raise TypeError(f"unsupported field type {tp!r}")


def _infinite_default(f: dataclasses.Field) -> bool:
    d = f.default
    return isinstance(d, float) and math.isinf(d)


#: field metadata of a value a kind sets at load from other sections (not a key of its own: the
#: reader refuses it and the key reference leaves it out), see :func:`set_at_load`
SET_AT_LOAD = "set_at_load"


def set_at_load(metadata=None) -> dict:
    """Field metadata (with ``metadata``, e.g. a range) marking a value set at load, not a key."""
    return {**(metadata or {}), SET_AT_LOAD: True}


def is_key(f: dataclasses.Field) -> bool:
    """Whether field ``f`` is a scenario key (not :func:`set_at_load`)."""
    return f.init and not f.metadata.get(SET_AT_LOAD, False)


def build(cls, data: Any, file, path: Sequence[str], **fixed):
    """Instantiate dataclass ``cls`` from mapping ``data`` (None = all defaults); ``fixed`` are set
    by the caller. Types, finiteness, ranges and list rules are checked (module doc)."""
    if data is None:
        data = {}
    if not isinstance(data, Mapping):
        raise ScenarioError(file, path, f"expected a mapping of {cls.__name__} parameters, got {describe(data)}")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if is_key(f)}
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
        rule = range_of(cls, name)
        infinite = rule is not None and rule.infinite             # .inf is a limit the field admits
        value = coerce(data[name], hints[name], file, where, allow_inf=_infinite_default(f) or infinite)
        if isinstance(value, tuple):
            for i, v in enumerate(value):
                check_range(v, rule, file, _item_path(where, i))
            check_list(value, list_rule_of(cls, name), file, where)
        elif isinstance(value, float) and math.isinf(value) and not infinite:   # where the default is .inf
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
