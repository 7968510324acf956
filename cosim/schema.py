"""Validate plain YAML data into parameter dataclasses, with errors that say where and what.

One generic mechanism serves every parameter dataclass (pneumatic components, vehicle
parameters, test definitions): field types come from the dataclass annotations, and fields
named with an SI suffix that only makes sense positive (``_m3``, ``_m2``, ``_kg``, ``_Pa``,
``_K``, ``_s``) must be > 0 (pressures are absolute).
"""
from __future__ import annotations

import dataclasses
import math
import re
import typing
from pathlib import Path
from typing import Any, Mapping, Sequence, Tuple, Union

#: Suffixes of quantities that must be strictly positive.
POSITIVE_SUFFIXES = ("_m3", "_m2", "_kg", "_Pa", "_K", "_s")
_NUMBER_STRING = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)[eE][+-]?\d+$")

class ScenarioError(ValueError):
    """Bad input: which file, which key path, what was expected."""

    def __init__(self, file: Union[str, Path, None], path: Sequence[str], message: str):
        self.file = str(file) if file else "<scenario>"
        self.path = ".".join(str(p) for p in path) or "(top level)"
        self.reason = message
        super().__init__(f"{self.file}: {self.path}: {message}")

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

def coerce(value: Any, tp, file, path: Sequence[str]):
    """Check ``value`` against the annotation ``tp`` and return it converted (int -> float etc.)."""
    origin = typing.get_origin(tp)
    if origin is Union:
        args = typing.get_args(tp)
        if value is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        return coerce(value, inner[0], file, path)
    if origin in (tuple, Tuple):
        if not isinstance(value, (list, tuple)):
            raise ScenarioError(file, path, f"expected {_type_name(tp)}, got {type(value).__name__} {value!r}")
        item = typing.get_args(tp)[0]
        return tuple(coerce(v, item, file, [*path[:-1], f"{path[-1]}[{i}]"]) for i, v in enumerate(value))
    if tp is float:
        if isinstance(value, str) and _NUMBER_STRING.match(value.strip()):
            # YAML 1.1 (PyYAML) reads 4.0e5 as a string: it needs 4.0e+5. Accept the obvious intent.
            return float(value)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ScenarioError(file, path, f"expected a number, got {type(value).__name__} {value!r}")
        if not math.isfinite(value):
            raise ScenarioError(file, path, f"expected a finite number, got {value}")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ScenarioError(file, path, f"expected an integer, got {type(value).__name__} {value!r}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ScenarioError(file, path, f"expected true or false, got {type(value).__name__} {value!r}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ScenarioError(file, path, f"expected a string, got {type(value).__name__} {value!r}")
        return value
    raise TypeError(f"unsupported field type {tp!r}")

def build(cls, data: Any, file, path: Sequence[str], **fixed):
    """Instantiate dataclass ``cls`` from mapping ``data`` (None = all defaults); ``fixed`` are set by the caller."""
    if data is None:
        data = {}
    if not isinstance(data, Mapping):
        raise ScenarioError(file, path, f"expected a mapping of {cls.__name__} parameters, got {type(data).__name__}")
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
        value = coerce(data[name], hints[name], file, [*path, name])
        if isinstance(value, float) and name.endswith(POSITIVE_SUFFIXES) and not value > 0:
            raise ScenarioError(file, [*path, name], f"must be > 0, got {value}")
        kwargs[name] = value
    return cls(**kwargs)

def require(data: Mapping, key: str, file, path: Sequence[str], kind=None, default=dataclasses.MISSING):
    """Fetch ``data[key]`` checking its Python type (``kind``: a type or tuple of types)."""
    if key not in data:
        if default is not dataclasses.MISSING:
            return default
        raise ScenarioError(file, [*path, key], "missing required key")
    value = data[key]
    if kind is not None and not isinstance(value, kind):
        names = " or ".join(k.__name__ for k in (kind if isinstance(kind, tuple) else (kind,)))
        raise ScenarioError(file, [*path, key], f"expected {names}, got {type(value).__name__} {value!r}")
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
        where = [*path[:-1], f"{path[-1]}[{i}]"] if isinstance(value, (list, tuple)) else path
        isothermal = isinstance(v, float) and v == math.inf
        k = math.inf if isothermal else coerce(v, float, file, where)
        if k < 0:
            raise ScenarioError(file, where, f"k must be >= 0 W/K (0 adiabatic, .inf isothermal), got {k}")
        if k in out:
            raise ScenarioError(file, where, f"k = {v} appears twice: each case must be distinct")
        out.append(k)
    if not out:
        raise ScenarioError(file, path, "expected at least one k value")
    return tuple(out)
