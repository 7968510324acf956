"""Named parameter sets, one source of truth each: the vehicle presets are functions of
:mod:`vehicle.params` (the :class:`~vehicle.params.VehicleParams` defaults are the paper's car),
the circuit presets functions of :mod:`pneumatics.presets`. A scenario names one
(``vehicle: paper_metro_car``, ``vehicle: {preset: metro_car_arb_dampers, carbody_mass_kg: 21000}``,
``circuit: {preset: paper_table1, ...}``) and overrides single fields on top;
``pneumorail presets NAME`` prints one as a commented YAML file to start a car of one's own from.
"""
from __future__ import annotations

import dataclasses
import inspect
import io
import math
import tokenize
from typing import Callable, Dict

import yaml

from pneumatics.presets import CIRCUIT_PRESETS
from vehicle.params import VehicleParams, cooperrider_bogie, manchester_vehicle_1, metro_car_arb_dampers


def paper_metro_car() -> VehicleParams:
    """The paper's metro car (Table 3: masses, bogie centre distance, wheelbase), every other value
    a documented default (the Manchester benchmark vehicle scaled to a metro car, or textbook
    reasoning; see vehicle/params.py). No anti-roll bar, no secondary dampers."""
    return VehicleParams()


#: preset name -> function returning the VehicleParams
VEHICLE_PRESETS: Dict[str, Callable[[], VehicleParams]] = {
    "paper_metro_car": paper_metro_car, "metro_car_arb_dampers": metro_car_arb_dampers,
    "cooperrider": cooperrider_bogie, "manchester_vehicle_1": manchester_vehicle_1}
PRESETS = {**{name: ("vehicle", fn) for name, fn in VEHICLE_PRESETS.items()},
           **{name: ("circuit", fn) for name, fn in CIRCUIT_PRESETS.items()}}


def summary(name: str) -> str:
    """The first sentence of a preset's docstring."""
    doc = inspect.cleandoc(PRESETS[name][1].__doc__ or "")
    return doc.split(". ")[0].replace("\n", " ").rstrip(".") + "."


def field_notes(cls) -> Dict[str, str]:
    """The comments written next to (or just above) each field of a dataclass in its source."""
    notes: Dict[str, str] = {}
    pending: list = []
    names = {f.name for f in dataclasses.fields(cls)}
    for tok_line in _logical_lines(inspect.getsource(cls)):
        comments = [t.string.lstrip("# ").rstrip() for t in tok_line
                    if t.type == tokenize.COMMENT and not t.string.lstrip("# ").startswith("---")]
        code = [t for t in tok_line if t.type == tokenize.NAME]
        if code and code[0].string in names:
            notes[code[0].string] = " ".join(pending + comments).strip()
            pending = []
        elif not code:
            pending += comments
        else:
            pending = []
    return notes


def _logical_lines(source: str):
    line: list = []
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type in (tokenize.NEWLINE, tokenize.NL):
            if line:
                yield line
            line = []
        elif tok.type not in (tokenize.INDENT, tokenize.DEDENT):
            line.append(tok)


def _yaml_value(value) -> str:
    if isinstance(value, float) and math.isinf(value):
        return ".inf" if value > 0 else "-.inf"
    return yaml.safe_dump(value, default_flow_style=True).strip().removesuffix("...").strip()


def preset_yaml(name: str) -> str:
    """A preset as a commented YAML parameter file (a car's: ``vehicle: mycar.yaml``; a circuit's:
    the ``circuit:`` entries of a scenario)."""
    section, fn = PRESETS[name]
    lines = [f"# preset {name}: " + inspect.cleandoc(fn.__doc__ or "").replace("\n", "\n# "), ""]
    if section == "vehicle":
        params = fn()
        notes = field_notes(type(params))
        for f in dataclasses.fields(params):
            note = notes.get(f.name, "")
            lines.append(f"{f.name}: {_yaml_value(getattr(params, f.name))}" + (f"  # {note}" if note else ""))
    else:
        preset = fn()
        for key in ("bellow", "tank", "pipe"):
            fields = {k: v for k, v in dataclasses.asdict(getattr(preset, key)).items()
                      if k not in ("a", "b", "p0_Pa", "T0_K")}
            lines.append(f"{key}: {{{', '.join(f'{k}: {_yaml_value(v)}' for k, v in fields.items())}}}")
        lines.append(f"p0_Pa: {_yaml_value(preset.p0_Pa)}  # rig scenarios only: initial absolute pressure")
    return "\n".join(lines) + "\n"
