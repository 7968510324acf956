"""``pneumorail comfort FILE.csv``: the ride comfort of an acceleration record, simulated (a car
run's time series) or measured, into ``comfort.json``, ``comfort.csv`` (the 5 s blocks) and
``comfort.png``. The indices: :mod:`cosim.limits.comfort`."""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np

from cosim.errors import ScenarioError
from cosim.limits.comfort import AXES, BLOCK_S, N_MV_SCALE, ComfortResult, comfort
from cosim.results.io import atomic_write, jsonable, write_columns
from cosim.results.plots import Curve, Panel, save_panels
from pneumorail.files import RECORD_MAX_BYTES, duplicated, read_text

#: the accepted column of each axis: ``a<axis>_m_per_s2`` or, for a car run's time series,
#: ``a<axis>_<point>_m_per_s2`` with ``--point``
COLUMN = "a{axis}{point}_m_per_s2"
#: Coarsest sampling step admitted [s]: 20 Hz sampling resolves up to 10 Hz, the top of the band
#: Wb and Wd weigh most (Wb's plateau 4-16 Hz begins there); coarser, the indices lose what they
#: measure. A record in milliseconds has steps of 1-10 "s" and is refused here.
MAX_STEP_S = 0.05
#: A step longer than this many median steps is a gap (or one time stamp of another clock): the
#: resampler would interpolate straight across it, erasing every frequency above 1/(2 gap).
MAX_GAP_STEPS = 10
#: A first time stamp above this [s] is absolute Unix time: 1e8 s is 3.2 years (no ride record
#: is that long) and Unix time passed it in 1973. Such a record is shifted to start at 0 (the
#: indices depend on time differences only) and the shift is reported as a warning.
UNIX_TIME_S = 1e8
#: Largest acceleration magnitude admitted [m/s^2]: 100 g; a car floor in service sees a few
#: m/s^2, a crash ~10 g. Larger values are another unit (mm/s^2?) or a broken channel.
MAX_ACCELERATION_M_PER_S2 = 1000.0
#: A vertical mean within this of 1 (the vertical axis) is gravity in g: in m/s^2 the mean is
#: 9.81 with gravity (an accelerometer at rest reads 1 g up) or ~0 without, and a sustained
#: vertical 1 m/s^2 (0.1 g) is no railway motion. 0.2 leaves room for a tilted sensor (cos 35°).
G_MEAN_BAND = 0.2
STANDARD_GRAVITY = 9.80665


@dataclass
class Record:
    """A comfort record as read: time [s] from its start, accelerations [m/s^2] by axis, what
    reading it noticed (``warnings``) and the sha256 of the file."""

    t_s: np.ndarray
    accelerations: Dict[str, np.ndarray]
    warnings: List[str]
    sha256: str


def read_record(path: Path, point: Optional[str] = None) -> Record:
    """The :class:`Record` of a CSV with ``t_s`` and any of the axes' columns
    (other columns are ignored), read by the project's one reader (:mod:`pneumorail.files`) and
    sniffed for its units: time in milliseconds, absolute Unix time, gaps, accelerations in g or
    beyond any car's. Errors name the file and the line as the editor shows it, the column or
    the option, and the likely unit."""
    path = Path(path)
    suffix = f"_{point}" if point else ""
    text = read_text(path, "comfort record (CSV)", RECORD_MAX_BYTES, error=ScenarioError)
    rows = text.csv_rows()
    first = next(rows, None)
    if first is None:
        raise ScenarioError(path, [], "empty file; expected a header line with t_s and a<x|y|z>_m_per_s2 columns")
    head_line, header = first
    at_header = f"line {head_line}"
    if "t_s" not in header:
        raise ScenarioError(path, [at_header], f"no 't_s' column (columns: {', '.join(header)})")
    wanted = {axis: COLUMN.format(axis=axis, point=suffix) for axis in AXES}
    present = {axis: header.index(c) for axis, c in wanted.items() if c in header}
    if not present:
        points = sorted({h[3:-len("_m_per_s2")] for h in header
                         if h[:3] in ("ax_", "ay_", "az_") and h.endswith("_m_per_s2") and len(h) > len("ax_m_per_s2")})
        if point:
            raise ScenarioError(path, ["--point"], f"no floor point {point!r} in this file (no column "
                                                   f"{', '.join(wanted.values())}); its points: "
                                                   f"{', '.join(points) or 'none'}")
        hint = f"; this file has floor points: --point {' | '.join(points)}" if points else ""
        raise ScenarioError(path, [at_header], f"no acceleration column: expected any of {', '.join(wanted.values())}{hint}")
    twice = [c for c in duplicated(header) if c == "t_s" or c in wanted.values()]
    if twice:
        raise ScenarioError(path, [at_header, twice[0]], "this column appears twice: which one is the record?")
    columns = {"t_s": header.index("t_s"), **present}
    values = {name: [] for name in columns}
    lines = []
    for n, row in rows:
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
        lines.append(n)
    t = np.asarray(values.pop("t_s"))
    if t.size < 2 or np.any(np.diff(t) <= 0):
        where = f"line {lines[int(np.argmax(np.diff(t) <= 0)) + 1]}" if t.size >= 2 else "t_s"
        raise ScenarioError(path, [where], "t_s must increase from line to line")
    t, warnings = _time_units(path, t, lines)
    accelerations = {axis: np.asarray(values[axis]) for axis in present}
    _acceleration_units(path, accelerations, {axis: wanted[axis] for axis in present}, lines)
    return Record(t, accelerations, warnings, text.sha256)


def _time_units(path: Path, t: np.ndarray, lines) -> tuple:
    """``t`` in seconds from the record's start, refused in milliseconds or with a gap (module
    constants give the physics); absolute Unix time is shifted to 0, with a warning."""
    steps = np.diff(t)
    step = float(np.median(steps))
    if step > MAX_STEP_S:
        likely = (f"; if t_s is in milliseconds (a step of {step:g} ms, {1000 / step:.4g} Hz), divide it by 1000"
                  if step / 1000 <= MAX_STEP_S else "")
        raise ScenarioError(path, ["t_s"], f"a median step of {step:g} s ({1 / step:.3g} Hz sampling): the comfort "
                                           f"weightings need at least {1 / MAX_STEP_S:g} Hz (a step of at most "
                                           f"{MAX_STEP_S:g} s){likely}")
    gap = int(np.argmax(steps))
    if steps[gap] > MAX_GAP_STEPS * step:
        raise ScenarioError(path, [f"line {lines[gap + 1]}", "t_s"],
                            f"jumps by {steps[gap]:g} s (from {t[gap]:.10g} to {t[gap + 1]:.10g}), {steps[gap] / step:.3g} "
                            f"times the median step {step:g} s: a gap, or a time stamp of another clock (Unix "
                            f"time?); a comfort record is sampled without gaps")
    if t[0] > UNIX_TIME_S:
        return t - t[0], [f"t_s starts at {t[0]:.10g} s, absolute (Unix) time: taken from the first sample "
                          f"(line {lines[0]}) on"]
    return t, []


def _acceleration_units(path: Path, accelerations: Dict[str, np.ndarray], names: Dict[str, str], lines) -> None:
    """Refuse accelerations in g or beyond any car's (module constants give the physics)."""
    for axis, a in accelerations.items():
        big = int(np.argmax(np.abs(a)))
        if abs(a[big]) > MAX_ACCELERATION_M_PER_S2:
            raise ScenarioError(path, [f"line {lines[big]}", names[axis]],
                                f"{a[big]:g} m/s² is beyond {MAX_ACCELERATION_M_PER_S2:g} m/s² (100 g), more than any "
                                f"railway car floor sees: another unit (mm/s²?) or a broken channel")
    if "z" in accelerations and abs(abs(float(np.mean(accelerations["z"]))) - 1.0) < G_MEAN_BAND:
        mean = float(np.mean(accelerations["z"]))
        raise ScenarioError(path, [names["z"]], f"the vertical mean is {mean:.3g}: gravity in g (1 g; in m/s² it "
                                                f"would be {STANDARD_GRAVITY:g} with gravity or ~0 without); the "
                                                f"accelerations are in m/s²: multiply the record by {STANDARD_GRAVITY:g}")


def comfort_of_file(path: Path, out: Path, point: Optional[str] = None) -> ComfortResult:
    """Read the record, compute its comfort, write comfort.json, comfort.csv and comfort.png into
    ``out``."""
    path = Path(path)
    record = read_record(path, point)
    try:
        result = comfort(record.t_s, record.accelerations)
    except ValueError as exc:
        raise ScenarioError(path, ["t_s"], str(exc)) from None
    result.warnings[:0] = record.warnings
    out = Path(out)
    summary = {
        "file": str(path), "file_sha256": record.sha256, "point": point,
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
