"""``pneumorail compare``: overlay the results of several runs (across k, or across runs), from
their output folders; optionally only some wheels, some k values and a time window."""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import List, Optional, Sequence, Tuple

import numpy as np

from vehicle.params import WHEELS

from cosim.limits.criteria import DQQ_LIMIT
from cosim.results.plots import Curve, Panel, save_panels
from cosim.results.io import k_label, read_rows
from cosim.scenario.schema import ScenarioError

#: wheels a twist comparison shows by default (paper Fig. 8), the worst wheel of the runs added
WHEELS_SHOWN = ("1L", "1R", "4L", "4R")


@dataclass(frozen=True)
class Selection:
    """What to overlay: ``wheels`` (None: Fig. 8's and the worst), ``k`` values (None: all) and
    the time window ``t_s`` (None: the whole run)."""

    wheels: Optional[Tuple[str, ...]] = None
    k: Optional[Tuple[float, ...]] = None
    t_s: Optional[Tuple[float, float]] = None


def _load(run_dir: Path):
    info_path = run_dir / "run.json"
    if not info_path.exists():
        raise ScenarioError(run_dir, ["run.json"], "not a pneumorail output folder (no run.json)")
    return json.loads(info_path.read_text())


def _case_k(name: str) -> float:
    """The k of a time series file's case name (``valves=on_k=inf`` -> inf)."""
    return float(name.rsplit("k=", 1)[1])


def _series(run_dir: Path, prefix: str, select: Selection):
    """(case label, columns) of every time series ``prefix*.csv`` the selection keeps; the label
    is the file name without the prefix, e.g. ``bellow_tank, k = 100`` or ``valves=on, k = inf``."""
    for path in sorted((run_dir / "timeseries").glob(f"{prefix}*.csv")):
        case = path.stem[len(prefix):]
        if select.k is not None and "k=" in case and _case_k(case) not in select.k:
            continue
        data = np.genfromtxt(path, delimiter=",", names=True)
        if select.t_s is not None:
            data = data[(data["t_s"] >= select.t_s[0]) & (data["t_s"] <= select.t_s[1])]
        yield case.replace("_k=", ", k = ").replace("k=", "k = "), data


def _worst_wheels(run_dirs: Sequence[Path]) -> List[str]:
    """The wheels the runs' summaries name as unloading most (dynamic and quasi-static)."""
    worst = []
    for d in run_dirs:
        for row in read_rows(d / "summary.csv") if (d / "summary.csv").exists() else []:
            worst += [row.get(c) for c in ("dqq_max_wheel", "dqq_qs_max_wheel") if row.get(c) in WHEELS]
    return worst


def compare_runs(run_dirs: Sequence[Path], out_dir: Path, select: Selection = Selection()) -> List[Path]:
    """Write overlay plots of the given output folders into ``out_dir``; returns the files."""
    infos = [(d, _load(d)) for d in run_dirs]
    kinds = {info["kind"] for _, info in infos}
    if len(kinds) != 1:
        raise ScenarioError(run_dirs[0], ["kind"], f"cannot compare runs of different kinds: {sorted(kinds)}")
    kind = kinds.pop()
    many = len(infos) > 1
    label = (lambda d, case: f"{d.name}: {case}") if many else (lambda d, case: case)
    window = "" if select.t_s is None else f", {select.t_s[0]:g} ... {select.t_s[1]:g} s"
    written = []
    if kind == "twist":
        wheels = select.wheels or tuple(w for w in WHEELS if w in WHEELS_SHOWN or w in _worst_wheels(run_dirs))
        for quantity, scale, unit in (("Q", 1e-3, "kN"), ("dqq", 1.0, "-")):
            panels = []
            for w in wheels:
                column = f"{quantity}_{w}{'_N' if quantity == 'Q' else ''}"
                curves = [Curve(data["t_s"], data[column] * scale, label(d, k))
                          for d, _ in infos for k, data in _series(d, "twist_", select)]
                name = "wheel load Q" if quantity == "Q" else "ΔQ/Q0"
                panels.append(Panel(curves, "time t [s]", f"{name} of wheel {w} [{unit}]", f"wheel {w}",
                                    hlines=[(DQQ_LIMIT, "EN 14363 limit")] if quantity == "dqq" else []))
            written.append(save_panels(out_dir / f"compare_{quantity}.png", panels, f"Twist test comparison{window}",
                                       ncols=2))
    elif kind == "rig_stiffness":
        curves = []
        for d, _ in infos:
            rows = [r for r in read_rows(d / "summary.csv") if r["stabilised"] == "True"]
            for k in sorted({float(r["k_W_per_K"]) for r in rows}):
                if select.k is not None and k not in select.k:
                    continue
                pts = [r for r in rows if float(r["k_W_per_K"]) == k]
                curves.append(Curve([float(r["frequency_Hz"]) for r in pts],
                                    [float(r["K_dyn_N_per_m"]) / 1e3 for r in pts], label(d, f"k = {k_label(k)}"), "o-"))
        written.append(save_panels(out_dir / "compare_stiffness.png",
                                   [Panel(curves, "frequency f [Hz]", "K_dyn [kN/m]", logx=True)], "Dynamic stiffness comparison"))
    elif kind == "curve_entry":
        panels = []
        for column, scale, ylabel in (("roll_carbody_rel_track_rad", 1e3, "carbody roll to the track plane [mrad]"),
                                      ("air_from_supply_kg", 1e3, "air injected from the supply [g]")):
            curves = [Curve(data["t_s"], data[column] * scale, label(d, case))
                      for d, _ in infos for case, data in _series(d, "curve_", select) if column in data.dtype.names]
            panels.append(Panel(curves, "time t [s]", ylabel))
        written.append(save_panels(out_dir / "compare_curve.png", panels, f"Curve entry comparison{window}", ncols=2))
    elif kind in ("rig_sine", "rig_ramp"):
        prefix = "sine_" if kind == "rig_sine" else "ramp_"
        column, ylabel = ("T_bellow_K", "bellow temperature T [K]") if kind == "rig_sine" else ("F_bellow_N", "bellow force F [N]")
        curves = [Curve(data["t_s"], data[column], label(d, k)) for d, _ in infos for k, data in _series(d, prefix, select)]
        written.append(save_panels(out_dir / f"compare_{kind}.png", [Panel(curves, "time t [s]", ylabel)],
                                   f"{kind} comparison{window}"))
    else:
        raise ScenarioError(run_dirs[0], ["kind"], f"compare does not support {kind!r} runs (summary.csv holds its numbers)")
    return written


def parse_wheels(text: str) -> Tuple[str, ...]:
    wheels = tuple(w.strip().upper() for w in text.split(",") if w.strip())
    bad = [w for w in wheels if w not in WHEELS]
    if bad or not wheels:
        raise ValueError(f"--wheels expects wheels among {', '.join(WHEELS)}, got {text!r}")
    return wheels


def parse_window(text: str) -> Tuple[float, float]:
    try:
        t0, t1 = (float(v) for v in text.split(","))
    except ValueError:
        raise ValueError(f"--time expects T0,T1 in seconds, got {text!r}") from None
    if not (math.isfinite(t0) and math.isfinite(t1) and t1 > t0):
        raise ValueError(f"--time expects finite T0 < T1, got {text!r}")
    return t0, t1
