"""Measured data for identification: a rig's time history or a dynamic-stiffness table, read from
a CSV whose column names carry their units, as the project writes them.

Time history (a ``rig_sine`` or ``rig_ramp`` scenario): ``t_s``, the crushing ``z_m`` (the
excitation: + compression, measured from the state at the scenario's ``p0_Pa``), and any of the
observed channels of :data:`TIME_CHANNELS` (a rig run's ``timeseries`` CSV has these names).

Dynamic-stiffness table (a ``rig_stiffness`` scenario, at its ``amplitude_m``): ``frequency_Hz``
and either ``K_abs_N_per_m`` with ``loss_angle_deg`` or ``K_storage_N_per_m`` with
``K_loss_N_per_m``: the complex stiffness K* = K' + i K'' of the force's first harmonic against
z = a sin(wt); |K*| = sqrt(K'^2 + K''^2), loss angle atan(K''/K').
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List

import numpy as np

from cosim.errors import ScenarioError
from pneumorail.files import RECORD_MAX_BYTES, duplicated, read_text

#: observed channel of a time history -> what it is
TIME_CHANNELS = {"F_bellow_N": "bellow force", "p_bellow_Pa": "bellow pressure (absolute)",
                 "p_tank_Pa": "tank pressure (absolute)", "T_bellow_K": "bellow air temperature",
                 "T_tank_K": "tank air temperature"}
#: the two pairs a stiffness table may give
TABLE_PAIRS = (("K_abs_N_per_m", "loss_angle_deg"), ("K_storage_N_per_m", "K_loss_N_per_m"))
#: fewest rows a fit can use
MIN_ROWS = 5


@dataclass
class Measurements:
    """What was measured: ``kind`` ``time`` (x = t_s, with ``z_m``) or ``table`` (x = frequency_Hz);
    ``channels``: observed column -> values; ``sha256``: of the file read."""

    file: Path
    kind: str
    x: np.ndarray
    channels: Dict[str, np.ndarray]
    z_m: np.ndarray = field(default_factory=lambda: np.zeros(0))
    sha256: str = ""

    @property
    def x_name(self) -> str:
        return "t_s" if self.kind == "time" else "frequency_Hz"

    @property
    def n(self) -> int:
        return sum(v.size for v in self.channels.values())


#: Unit sniffing, each bound from physics (a value beyond it is another unit, named):
#: an absolute air pressure below 1 kPa (1 % of the atmosphere) is a vacuum no air spring holds:
#: bar (1-12 for a bellows) or kPa; an air temperature below 200 K (the coldest air measured on
#: Earth is 184 K; a rig runs at 250-330 K) is in °C; a crushing beyond 0.5 m is more than any
#: air spring's stroke (~0.1 m): millimetres.
MIN_PRESSURE_PA = 1e3
MIN_TEMPERATURE_K = 200.0
MAX_CRUSHING_M = 0.5


def read_measurements(path: Path) -> Measurements:
    """The CSV at ``path``, read by the project's one reader (:mod:`pneumorail.files`) and checked:
    known columns, each once, finite numbers in their units (:data:`MIN_PRESSURE_PA` ...), ``t_s``
    or ``frequency_Hz`` increasing, at least :data:`MIN_ROWS` rows and one observed channel.
    Errors name the line as the editor shows it."""
    path = Path(path)
    text = read_text(path, "measured record (CSV)", RECORD_MAX_BYTES, where=["--data"], error=ScenarioError)
    rows = list(text.csv_rows())
    if len(rows) < MIN_ROWS + 1:
        raise ScenarioError(path, [], f"expected a header and at least {MIN_ROWS} rows, got {max(len(rows) - 1, 0)} rows")
    head_line, header = rows[0]
    twice = duplicated(header)
    if twice:
        raise ScenarioError(path, [f"line {head_line}", twice[0]], "this column appears twice: which one was measured?")
    columns: Dict[str, List[float]] = {h: [] for h in header}
    for line, row in rows[1:]:
        if len(row) != len(header):
            raise ScenarioError(path, [f"line {line}"], f"expected {len(header)} values, got {len(row)}")
        for h, cell in zip(header, row):
            try:
                value = float(cell)
            except ValueError:
                raise ScenarioError(path, [f"line {line}", h], f"expected a number, got {cell!r}") from None
            if not math.isfinite(value):
                raise ScenarioError(path, [f"line {line}", h], f"expected a finite number, got {cell!r}")
            columns[h].append(value)
    data = {h: np.asarray(v) for h, v in columns.items()}
    _check_units(path, data, [n for n, _ in rows[1:]])
    if "t_s" in data:
        return _time_history(path, data, text.sha256)
    if "frequency_Hz" in data:
        return _table(path, data, text.sha256)
    raise ScenarioError(path, ["header"], "expected a time history (t_s, z_m, and any of "
                                          f"{', '.join(TIME_CHANNELS)}) or a stiffness table (frequency_Hz and "
                                          f"{' + '.join(TABLE_PAIRS[0])} or {' + '.join(TABLE_PAIRS[1])})")


def _check_units(path: Path, data: Dict[str, np.ndarray], lines: List[int]) -> None:
    """Refuse pressures, temperatures and crushings in another unit (bounds: module constants)."""
    for name, values in data.items():
        if name.endswith("_Pa") and values.min() < MIN_PRESSURE_PA:
            i = int(np.argmin(values))
            unit = "bar" if values.max() < 50.0 else "kPa"          # a bellows holds < 50 bar: above, kPa
            raise ScenarioError(path, [f"line {lines[i]}", name],
                                f"{values[i]:g} Pa is below {MIN_PRESSURE_PA:g} Pa, a vacuum no air spring holds "
                                f"(absolute pressure, the atmosphere is 101325 Pa): the column looks like {unit}; "
                                f"give it in Pa")
        if name.endswith("_K") and values.min() < MIN_TEMPERATURE_K:
            i = int(np.argmin(values))
            raise ScenarioError(path, [f"line {lines[i]}", name],
                                f"{values[i]:g} K is below {MIN_TEMPERATURE_K:g} K, colder than any air on Earth: the "
                                f"column looks like °C; give it in kelvin (°C + 273.15)")
        if name == "z_m" and np.abs(values).max() > MAX_CRUSHING_M:
            i = int(np.argmax(np.abs(values)))
            raise ScenarioError(path, [f"line {lines[i]}", name],
                                f"{values[i]:g} m is beyond {MAX_CRUSHING_M:g} m, more than any air spring's stroke: "
                                f"the column looks like millimetres; give it in metres")


def _increasing(path, name, x) -> None:
    if np.any(np.diff(x) <= 0):
        i = int(np.flatnonzero(np.diff(x) <= 0)[0]) + 1
        raise ScenarioError(path, [name], f"must increase from row to row; row {i + 1} has {x[i]:g} after {x[i - 1]:g}")


def _time_history(path, data, sha256: str) -> Measurements:
    if "z_m" not in data:
        raise ScenarioError(path, ["z_m"], "a time history needs the crushing z_m: the excitation the model is driven by")
    unknown = [h for h in data if h not in ("t_s", "z_m", *TIME_CHANNELS)]
    if unknown:
        raise ScenarioError(path, [unknown[0]], f"unknown column (a time history has t_s, z_m and any of "
                                                f"{', '.join(TIME_CHANNELS)})")
    channels = {h: data[h] for h in TIME_CHANNELS if h in data}
    if not channels:
        raise ScenarioError(path, ["header"], f"nothing to fit: give at least one of {', '.join(TIME_CHANNELS)}")
    _increasing(path, "t_s", data["t_s"])
    if abs(data["t_s"][0]) > 1e-9:
        raise ScenarioError(path, ["t_s"], f"must start at 0 (the rig at rest at p0_Pa), got {data['t_s'][0]:g} s")
    return Measurements(path, "time", data["t_s"], channels, data["z_m"], sha256)


def _table(path, data, sha256: str) -> Measurements:
    pair = next((p for p in TABLE_PAIRS if all(c in data for c in p)), None)
    if pair is None:
        raise ScenarioError(path, ["header"], f"a stiffness table needs {' + '.join(TABLE_PAIRS[0])} or "
                                              f"{' + '.join(TABLE_PAIRS[1])}")
    unknown = [h for h in data if h not in ("frequency_Hz", *pair)]
    if unknown:
        raise ScenarioError(path, [unknown[0]], f"unknown column (this table has frequency_Hz, {', '.join(pair)})")
    _increasing(path, "frequency_Hz", data["frequency_Hz"])
    if data["frequency_Hz"][0] <= 0:
        raise ScenarioError(path, ["frequency_Hz"], "frequencies must be > 0 Hz")
    return Measurements(path, "table", data["frequency_Hz"], {c: data[c] for c in pair}, sha256=sha256)


def table_channels(K_storage: np.ndarray, K_loss: np.ndarray, pair) -> Dict[str, np.ndarray]:
    """A model's K', K'' in the channels of the table (``pair``: its columns)."""
    if pair[0] == "K_abs_N_per_m":
        return {"K_abs_N_per_m": np.hypot(K_storage, K_loss),
                "loss_angle_deg": np.degrees(np.arctan2(K_loss, K_storage))}
    return {"K_storage_N_per_m": K_storage, "K_loss_N_per_m": K_loss}
