"""What ``compare`` reads from output folders: the run's description (``run.json``), the time
series of its cases and the wheels its summary names as the worst; the selection the user made
(:class:`Selection`). The kinds draw their overlays from these (``compare`` in a kind module)."""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator, List, Optional, Sequence, Tuple

import numpy as np

from cosim.errors import ScenarioError
from cosim.results.io import read_rows
from pneumorail.files import RUN_FILE_MAX_BYTES, SERIES_MAX_BYTES, read_text
from vehicle.params import WHEELS


@dataclass(frozen=True)
class Selection:
    """What to overlay: ``wheels`` (None: the kind's default), ``k`` values (None: all) and the
    time window ``t_s`` (None: the whole run)."""

    wheels: Optional[Tuple[str, ...]] = None
    k: Optional[Tuple[float, ...]] = None
    t_s: Optional[Tuple[float, float]] = None


def folder_json(run_dir: Path, name: str) -> Optional[dict]:
    """The JSON object ``name`` of an output folder (None when absent), read by the one reader:
    a regular file inside the folder (no link out of it), at most
    :data:`~pneumorail.files.RUN_FILE_MAX_BYTES`, UTF-8; an error naming it if it is not a JSON
    object (e.g. cut short by a full disk, or edited into a list)."""
    path = Path(run_dir) / name
    if not path.exists() and not path.is_symlink():
        return None
    text = read_text(path, f"pneumorail {name}", RUN_FILE_MAX_BYTES, within=run_dir, error=ScenarioError).text
    try:
        data = json.loads(text)
    except ValueError as exc:
        raise ScenarioError(path, [], f"not valid JSON ({exc}); the run did not finish writing it, or it was "
                                      f"edited") from None
    if not isinstance(data, dict):
        raise ScenarioError(path, [], f"expected a JSON object {{...}} as pneumorail writes it, got "
                                      f"{type(data).__name__ if data is not None else 'null'}")
    return data


def run_info(run_dir: Path) -> dict:
    """The ``run.json`` of an output folder (:func:`folder_json`; an error naming the folder if it
    is not one, pointing at a sweep's cases in a sweep's folder)."""
    run_dir = Path(run_dir)
    if not (run_dir / "run.json").exists() and not (run_dir / "run.json").is_symlink():
        if (run_dir / "sweep.csv").exists() or (run_dir / "cases").is_dir():
            cases = sorted(p.name for p in (run_dir / "cases").glob("*") if (p / "run.json").exists())
            example = f", e.g. {run_dir / 'cases' / cases[0]}" if cases else ""
            raise ScenarioError(run_dir, ["run.json"], f"a sweep's folder (sweep.csv, cases/): name one case's "
                                                       f"folder, {run_dir / 'cases'}/<case>/{example}")
        raise ScenarioError(run_dir, ["run.json"], "not a pneumorail output folder (no run.json)")
    return folder_json(run_dir, "run.json")


def incomplete(run_dir: Path, info: dict) -> str:
    """Why a run's results are not whole ("" when they are): an INCOMPLETE marker left in its
    folder (interrupted while writing, or still running) or run.json's status."""
    if (Path(run_dir) / "INCOMPLETE").exists():
        return "its folder holds an INCOMPLETE marker (interrupted, or still being written)"
    if info.get("status", "complete") != "complete":
        return f"run.json says status {info['status']}"
    return ""


def _case_k(name: str) -> float:
    """The k of a time series file's case name (``valves=on_k=inf`` -> inf)."""
    return float(name.rsplit("k=", 1)[1])


def case_series(run_dir: Path, prefix: str, select: Selection) -> Iterator[Tuple[str, np.ndarray]]:
    """(case label, columns) of every time series ``prefix*.csv`` the selection keeps; the label
    is the file name without the prefix (:func:`case_label`), e.g. ``valves on, k = inf W/K``."""
    for path in sorted((run_dir / "timeseries").glob(f"{prefix}*.csv")):
        case = path.stem[len(prefix):]
        if select.k is not None and "k=" in case and _case_k(case) not in select.k:
            continue
        text = read_text(path, "time series (CSV)", SERIES_MAX_BYTES, within=run_dir, error=ScenarioError).text
        data = np.genfromtxt(text.splitlines(), delimiter=",", names=True)
        if select.t_s is not None:
            data = data[(data["t_s"] >= select.t_s[0]) & (data["t_s"] <= select.t_s[1])]
        yield case_label(case), data


def case_label(case: str) -> str:
    """A legend label of a time series file's case name, the k with its unit:
    ``valves=on_k=inf`` -> ``valves on, k = inf W/K``, ``bellow_tank_k=100`` -> ``bellow_tank, k = 100 W/K``."""
    if "k=" not in case:
        return case
    head, k = case.rsplit("k=", 1)
    head = head.rstrip("_").replace("valves=", "valves ")
    return f"{head + ', ' if head else ''}k = {k} W/K"


def worst_wheels(run_dirs: Sequence[Path]) -> List[str]:
    """The wheels the runs' summaries name as unloading most (dynamic and quasi-static)."""
    worst = []
    for d in run_dirs:
        for row in read_rows(d / "summary.csv") if (d / "summary.csv").exists() else []:
            worst += [row.get(c) for c in ("dqq_max_wheel", "dqq_qs_max_wheel") if row.get(c) in WHEELS]
    return worst
