"""Writing results: CSV with unit-carrying headers, run.json provenance, progress lines."""
from __future__ import annotations

import csv
import io
import json
import math
import os
import platform
import sys
import time
from contextlib import contextmanager
from importlib import metadata
from pathlib import Path
from typing import Dict, Iterable, List, Mapping, Sequence

import numpy as np

from cosim.errors import ScenarioError
from cosim.scenario.schema import k_label
from pneumorail.files import RUN_FILE_MAX_BYTES, read_text


@contextmanager
def atomic_write(path: Path, mode: str = "w", durable: bool = False, **kwargs):
    """Write ``path`` through a temporary file in the same folder (named by the process: several
    processes may write the same file), renamed over it only when complete: a reader never sees
    half a file, and a failed write (disk full) leaves no cut file behind (the error still
    propagates, with the file's name). ``durable``: on disk before the rename (fsync), for a file
    whose presence means work is done (a sweep case's marker)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with tmp.open(mode, **kwargs) as fh:
            yield fh
            if durable:
                fh.flush()
                os.fsync(fh.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        if exc.filename is None or Path(exc.filename) == tmp:
            raise OSError(exc.errno, exc.strerror, str(path)) from None
        raise
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_columns(path: Path, columns: Mapping[str, Sequence[float]]) -> None:
    """A CSV of equal-length numeric columns (header = column names, which carry units)."""
    names = list(columns)
    data = np.column_stack([np.asarray(columns[n], dtype=float) for n in names])
    with atomic_write(path) as fh:
        np.savetxt(fh, data, delimiter=",", header=",".join(names), comments="", fmt="%.10g")


def csv_rows(rows: Iterable[Mapping[str, object]]) -> List[Dict[str, str]]:
    """The rows as a CSV of them holds them (:func:`write_rows`, read back by :func:`read_rows`):
    every key that appears in any row, in first-seen order; each value as text (:func:`cell`),
    a missing one ``nan``."""
    rows = list(rows)
    header = list(dict.fromkeys(key for row in rows for key in row))
    return [{k: ("" if row[k] is None else str(cell(row[k]))) if k in row else "nan" for k in header} for row in rows]


def write_rows(path: Path, rows: Iterable[Mapping[str, object]]) -> None:
    """A CSV with one row per mapping (:func:`csv_rows`)."""
    rows = csv_rows(rows)
    with atomic_write(path, newline="") as fh:
        if not rows:
            return
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def read_rows(path: Path) -> List[Dict[str, str]]:
    """The rows of a CSV table of an output folder (summary.csv ...), read by the one reader: a
    regular file inside its folder, at most :data:`~pneumorail.files.RUN_FILE_MAX_BYTES`, UTF-8."""
    path = Path(path)
    text = read_text(path, "pneumorail table (CSV)", RUN_FILE_MAX_BYTES, within=path.parent, error=ScenarioError)
    return list(csv.DictReader(io.StringIO(text.text, newline="")))


def cell(v):
    """A value as a CSV cell shows it: floats to 10 significant digits, inf, nan."""
    if isinstance(v, (float, np.floating)):
        return "inf" if math.isinf(v) else ("nan" if math.isnan(v) else f"{v:.10g}")
    return v


def versions() -> Dict[str, str]:
    out = {"python": platform.python_version()}
    for dist in ("pneumorail", "exudyn", "numpy", "scipy", "pyyaml", "matplotlib", "xarray"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = "not installed"
    return out


def source_commit() -> Dict[str, object]:
    """The git commit of the pneumorail source when it runs from a checkout (and whether the
    work tree had changes); empty when it is an installed copy or git is not available."""
    import subprocess
    root = Path(__file__).resolve().parent.parent
    try:
        run = lambda *args: subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True,
                                           timeout=5, check=True).stdout.strip()
        if Path(run("rev-parse", "--show-toplevel")).resolve() != root:
            return {}
        return {"commit": run("rev-parse", "HEAD"), "dirty": bool(run("status", "--porcelain", "--untracked-files=no"))}
    except (OSError, subprocess.SubprocessError):
        return {}


def resolved_parameters(scenario) -> Dict[str, object]:
    """Every parameter value the run used, defaults included: the scenario's typed sections (its
    experiment under its section's name; the car's sections for a car scenario) and the circuit's
    components."""
    import dataclasses
    car = ("vehicle", "track", "solver", "verify", "state_limits") if scenario.vehicle is not None else ()
    sections = {"circuit": scenario.circuit, scenario.section: scenario.experiment,
                **{name: getattr(scenario, name) for name in car}}
    out = {name: dataclasses.asdict(value) for name, value in sections.items() if dataclasses.is_dataclass(value)}
    if scenario.circuit is not None and getattr(scenario.circuit, "explicit", None) is None:
        out["circuit_components"] = {n: {"type": type(c).__name__, **dataclasses.asdict(c)}
                                     for n, c in scenario.circuit.components().items()}
    out["checks"] = [c.text for c in scenario.checks]
    return out


def write_run_json(out_dir: Path, scenario, wall_s: float, status: str = "complete",
                   extra: Mapping[str, object] = ()) -> None:
    """Provenance: what ran (scenario file and every file it read, with their sha256, paths
    relative to the scenario file; overrides; every parameter value actually used), with which
    versions and source commit, how long it took and how it ended (``status``: complete or
    interrupted). Strict JSON: non-finite numbers are
    written as the strings "inf", "-inf", "nan"."""
    info = {
        "scenario_file": str(scenario.file),
        "scenario_sha256": scenario.content_sha256,
        "files_sha256": dict(getattr(scenario, "files_sha256", ())),
        "kind": scenario.kind,
        "section": getattr(scenario, "section", None),
        "name": scenario.name,
        "overrides": list(scenario.overrides),
        "k_W_per_K": [k_label(k) for k in scenario.k_W_per_K],
        "settings": scenario.raw,
        "resolved": resolved_parameters(scenario),
        "versions": versions(),
        "source": source_commit(),
        "command": " ".join(sys.argv),
        "finished_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "wall_time_s": round(wall_s, 3),
        "status": status,
        **dict(extra),
    }
    with atomic_write(out_dir / "run.json") as fh:
        fh.write(json.dumps(jsonable(info), indent=2, allow_nan=False) + "\n")


def jsonable(v):
    """``v`` for strict JSON: non-finite numbers as the strings inf, -inf, nan; numpy scalars as
    Python numbers."""
    if isinstance(v, dict):
        return {str(k): jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [jsonable(x) for x in v]
    if isinstance(v, (float, np.floating)) and not math.isfinite(v):
        return str(float(v))
    if isinstance(v, np.generic):
        return v.item()
    return v


class Progress:
    """Progress lines on stderr with elapsed wall time (only when a run takes more than a moment)."""

    def __init__(self, label: str, stream=None, min_interval_s: float = 2.0, quiet: bool = False):
        self.label, self.stream, self.min_interval_s = label, stream or sys.stderr, min_interval_s
        self.quiet = quiet
        self.t0 = time.perf_counter()
        self._last = -math.inf

    def __call__(self, message: str, force: bool = True) -> None:
        now = time.perf_counter()
        if self.quiet:
            return
        if force or now - self._last >= self.min_interval_s:
            self._last = now
            print(f"[{self.label} {now - self.t0:6.1f} s] {message}", file=self.stream, flush=True)
