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
from vehicle.params import WHEELS


@dataclass(frozen=True)
class Selection:
    """What to overlay: ``wheels`` (None: the kind's default), ``k`` values (None: all) and the
    time window ``t_s`` (None: the whole run)."""

    wheels: Optional[Tuple[str, ...]] = None
    k: Optional[Tuple[float, ...]] = None
    t_s: Optional[Tuple[float, float]] = None


def run_info(run_dir: Path) -> dict:
    """The ``run.json`` of an output folder (an error naming it if it is not one, or if the file is
    not valid JSON, e.g. cut short by a full disk)."""
    info_path = run_dir / "run.json"
    if not info_path.exists():
        raise ScenarioError(run_dir, ["run.json"], "not a pneumorail output folder (no run.json)")
    try:
        return json.loads(info_path.read_text())
    except (ValueError, OSError) as exc:
        raise ScenarioError(info_path, [], f"cannot be read as a run's description ({exc}); the run did not finish "
                                           f"writing it") from None


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
        data = np.genfromtxt(path, delimiter=",", names=True)
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
