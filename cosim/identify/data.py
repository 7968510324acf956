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

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List

import numpy as np

from cosim.errors import ScenarioError

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
    ``channels``: observed column -> values."""

    file: Path
    kind: str
    x: np.ndarray
    channels: Dict[str, np.ndarray]
    z_m: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def x_name(self) -> str:
        return "t_s" if self.kind == "time" else "frequency_Hz"

    @property
    def n(self) -> int:
        return sum(v.size for v in self.channels.values())


def read_measurements(path: Path) -> Measurements:
    """The CSV at ``path``, checked: known columns, finite numbers, ``t_s`` or ``frequency_Hz``
    increasing, at least :data:`MIN_ROWS` rows and one observed channel."""
    path = Path(path)
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
    except FileNotFoundError:
        raise ScenarioError(path, ["--data"], "no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError(path, ["--data"], f"cannot be read as UTF-8 text: {exc}") from None
    rows = [r for r in rows if r and not r[0].startswith("#")]
    if len(rows) < MIN_ROWS + 1:
        raise ScenarioError(path, [], f"expected a header and at least {MIN_ROWS} rows, got {max(len(rows) - 1, 0)} rows")
    header = [h.strip() for h in rows[0]]
    columns: Dict[str, List[float]] = {h: [] for h in header}
    for line, row in enumerate(rows[1:], start=2):
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
    if "t_s" in data:
        return _time_history(path, data)
    if "frequency_Hz" in data:
        return _table(path, data)
    raise ScenarioError(path, ["header"], "expected a time history (t_s, z_m, and any of "
                                          f"{', '.join(TIME_CHANNELS)}) or a stiffness table (frequency_Hz and "
                                          f"{' + '.join(TABLE_PAIRS[0])} or {' + '.join(TABLE_PAIRS[1])})")


def _increasing(path, name, x) -> None:
    if np.any(np.diff(x) <= 0):
        i = int(np.flatnonzero(np.diff(x) <= 0)[0]) + 1
        raise ScenarioError(path, [name], f"must increase from row to row; row {i + 1} has {x[i]:g} after {x[i - 1]:g}")


def _time_history(path, data) -> Measurements:
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
    return Measurements(path, "time", data["t_s"], channels, data["z_m"])


def _table(path, data) -> Measurements:
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
    return Measurements(path, "table", data["frequency_Hz"], {c: data[c] for c in pair})


def table_channels(K_storage: np.ndarray, K_loss: np.ndarray, pair) -> Dict[str, np.ndarray]:
    """A model's K', K'' in the channels of the table (``pair``: its columns)."""
    if pair[0] == "K_abs_N_per_m":
        return {"K_abs_N_per_m": np.hypot(K_storage, K_loss),
                "loss_angle_deg": np.degrees(np.arctan2(K_loss, K_storage))}
    return {"K_storage_N_per_m": K_storage, "K_loss_N_per_m": K_loss}
