"""``pneumorail comfort FILE.csv``: the ride comfort of an acceleration record, simulated (a car
run's time series) or measured, into ``comfort.json``, ``comfort.csv`` (the 5 s blocks) and
``comfort.png``. The indices: :mod:`cosim.limits.comfort`."""
from __future__ import annotations

import csv
import hashlib
import json
import math
from pathlib import Path
from typing import Dict, Optional

import numpy as np

from cosim.errors import ScenarioError
from cosim.limits.comfort import AXES, BLOCK_S, N_MV_SCALE, ComfortResult, comfort
from cosim.results.io import atomic_write, jsonable, write_columns
from cosim.results.plots import Curve, Panel, save_panels

#: the accepted column of each axis: ``a<axis>_m_per_s2`` or, for a car run's time series,
#: ``a<axis>_<point>_m_per_s2`` with ``--point``
COLUMN = "a{axis}{point}_m_per_s2"


def read_record(path: Path, point: Optional[str] = None) -> tuple:
    """(t_s, {axis: acceleration}) of a CSV with ``t_s`` and any of the axes' columns (other
    columns are ignored). Errors name the file and the line."""
    path = Path(path)
    suffix = f"_{point}" if point else ""
    try:
        with path.open(newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
    except UnicodeDecodeError as exc:
        raise ScenarioError(path, [], f"not a UTF-8 text CSV ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise ScenarioError(path, [], f"cannot read it ({exc.strerror})") from None
    rows = [r for r in rows if r and not r[0].lstrip().startswith("#")]
    if not rows:
        raise ScenarioError(path, [], "empty file; expected a header line with t_s and a<x|y|z>_m_per_s2 columns")
    header = [h.strip() for h in rows[0]]
    if "t_s" not in header:
        raise ScenarioError(path, ["line 1"], f"no 't_s' column (columns: {', '.join(header)})")
    wanted = {axis: COLUMN.format(axis=axis, point=suffix) for axis in AXES}
    present = {axis: header.index(c) for axis, c in wanted.items() if c in header}
    if not present:
        points = sorted({h[3:-len("_m_per_s2")] for h in header
                         if h[:3] in ("ax_", "ay_", "az_") and h.endswith("_m_per_s2") and len(h) > len("ax_m_per_s2")})
        hint = f"; this file has floor points: --point {' | '.join(points)}" if points and not point else ""
        raise ScenarioError(path, ["line 1"], f"no acceleration column: expected any of {', '.join(wanted.values())}{hint}")
    columns = {"t_s": header.index("t_s"), **present}
    values = {name: [] for name in columns}
    for n, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise ScenarioError(path, [f"line {n}"], f"{len(row)} fields, expected {len(header)}")
        for name, i in columns.items():
            try:
                v = float(row[i])
            except ValueError:
                raise ScenarioError(path, [f"line {n}"], f"{header[i]} = {row[i]!r} is not a number") from None
            if not math.isfinite(v):
                raise ScenarioError(path, [f"line {n}"], f"{header[i]} = {row[i]!r} is not finite")
            values[name].append(v)
    t = np.asarray(values.pop("t_s"))
    if t.size < 2 or np.any(np.diff(t) <= 0):
        bad = int(np.argmax(np.diff(t) <= 0)) + 3 if t.size >= 2 else 2
        raise ScenarioError(path, [f"line {bad}" if t.size >= 2 else "t_s"], "t_s must increase from line to line")
    return t, {axis: np.asarray(v) for axis, v in values.items()}


def comfort_of_file(path: Path, out: Path, point: Optional[str] = None) -> ComfortResult:
    """Read the record, compute its comfort, write comfort.json, comfort.csv and comfort.png into
    ``out``."""
    path = Path(path)
    t, accelerations = read_record(path, point)
    try:
        result = comfort(t, accelerations)
    except ValueError as exc:
        raise ScenarioError(path, ["t_s"], str(exc)) from None
    out = Path(out)
    summary = {
        "file": str(path), "file_sha256": hashlib.sha256(path.read_bytes()).hexdigest(), "point": point,
        "duration_s": result.duration_s, "N_MV": result.N_MV, "N_MV_scale": result.scale,
        **{f"a{a.upper()}P95_m_per_s2": result.aP95_m_per_s2.get(a) for a in AXES},
        **{f"Cc_{a}_max_m_per_s2": result.Cc_max_m_per_s2.get(a) for a in AXES},
        **{f"Wz_{a}": result.Wz.get(a) for a in AXES},
        "a_v_m_per_s2": result.a_v_m_per_s2, "block_s": BLOCK_S, "blocks": len(result.block_start_s),
        "weightings": {"x": "Wd", "y": "Wd", "z": "Wb"}, "warnings": result.warnings,
    }
    with atomic_write(out / "comfort.json") as fh:
        fh.write(json.dumps(jsonable(summary), indent=2, allow_nan=False) + "\n")
    columns: Dict[str, np.ndarray] = {"block_start_s": result.block_start_s}
    for a in result.blocks:
        columns[f"a{a}_weighted_rms_m_per_s2"] = result.blocks[a]
    write_columns(out / "comfort.csv", columns)
    _figure(result, out / "comfort.png", path.name)
    return result


def _figure(result: ComfortResult, png: Path, name: str) -> None:
    """Weighted accelerations, continuous comfort with the N_MV scale (divided by 6: the value one
    axis alone would need for that N), the 5 s block rms."""
    axes = list(result.weighted)
    weighting = {"x": "Wd", "y": "Wd", "z": "Wb"}
    bands = [(bound / 6.0, f"N = {bound:g} alone ({label} below)") for bound, label in N_MV_SCALE if math.isfinite(bound)]
    panels = [Panel([Curve(result.t_s, result.weighted[a], f"a{a}, {weighting[a]}") for a in axes], "time t [s]",
                    "weighted acceleration [m/s²]"),
              Panel([Curve(result.cc_t_s, result.cc[a], f"Cc_{a}") for a in axes], "time t [s]",
                    "continuous comfort Cc, 5 s rms [m/s²]", hlines=bands),
              Panel([Curve(result.block_start_s + BLOCK_S / 2, result.blocks[a], f"a{a}", "o-") for a in axes],
                    "block centre t [s]", "weighted rms of each 5 s block [m/s²]")]
    title = (f"Ride comfort of {name}: N_MV = {result.N_MV:.2f} ({result.scale})" if result.N_MV is not None
             else f"Ride comfort of {name} (N_MV needs x, y and z)")
    save_panels(png, panels, title, ncols=1)
