"""``pneumorail compare``: overlay the results of several runs (across k, or across runs)."""
from __future__ import annotations

import json
from pathlib import Path
from typing import List, Sequence

import numpy as np

from .plots import Curve, Panel, save_panels
from .results import read_rows
from .schema import ScenarioError

WHEELS_SHOWN = ("1L", "1R", "4L", "4R")


def _load(run_dir: Path):
    info_path = run_dir / "run.json"
    if not info_path.exists():
        raise ScenarioError(run_dir, ["run.json"], "not a pneumorail output folder (no run.json)")
    return json.loads(info_path.read_text())


def _series(run_dir: Path, prefix: str):
    """(case label, columns) of every time series ``prefix*.csv``; the label is the file name
    without the prefix, e.g. ``bellow_tank_k=100`` or ``valves=on_k=inf``."""
    for path in sorted((run_dir / "timeseries").glob(f"{prefix}*.csv")):
        yield path.stem[len(prefix):].replace("_k=", ", k = ").replace("k=", "k = "), \
            np.genfromtxt(path, delimiter=",", names=True)


def compare_runs(run_dirs: Sequence[Path], out_dir: Path) -> List[Path]:
    """Write overlay plots of the given output folders into ``out_dir``; returns the files."""
    infos = [(d, _load(d)) for d in run_dirs]
    kinds = {info["kind"] for _, info in infos}
    if len(kinds) != 1:
        raise ScenarioError(run_dirs[0], ["kind"], f"cannot compare runs of different kinds: {sorted(kinds)}")
    kind = kinds.pop()
    many = len(infos) > 1
    label = (lambda d, case: f"{d.name}: {case}") if many else (lambda d, case: case)
    written = []
    if kind == "twist":
        for quantity, scale, unit in (("Q", 1e-3, "kN"), ("dqq", 1.0, "-")):
            panels = []
            for w in WHEELS_SHOWN:
                curves = [Curve(data["t_s"], data[f"{quantity}_{w}{'_N' if quantity == 'Q' else ''}"] * scale, label(d, k))
                          for d, _ in infos for k, data in _series(d, "twist_")]
                name = "wheel load Q" if quantity == "Q" else "ΔQ/Q0"
                panels.append(Panel(curves, "time t [s]", f"{name} of wheel {w} [{unit}]", f"wheel {w}",
                                    hlines=[(0.6, "EN 14363 limit")] if quantity == "dqq" else []))
            written.append(save_panels(out_dir / f"compare_{quantity}.png", panels, "Twist test comparison", ncols=2))
    elif kind == "rig_stiffness":
        curves = []
        for d, _ in infos:
            rows = [r for r in read_rows(d / "summary.csv") if r["stabilised"] == "True"]
            for k in sorted({r["k_W_per_K"] for r in rows}, key=float):
                pts = [r for r in rows if r["k_W_per_K"] == k]
                curves.append(Curve([float(r["frequency_Hz"]) for r in pts],
                                    [float(r["K_dyn_N_per_m"]) / 1e3 for r in pts], label(d, f"k = {k}"), "o-"))
        written.append(save_panels(out_dir / "compare_stiffness.png",
                                   [Panel(curves, "frequency f [Hz]", "K_dyn [kN/m]", logx=True)], "Dynamic stiffness comparison"))
    elif kind == "curve_entry":
        panels = []
        for column, scale, ylabel in (("roll_carbody_rad", 1e3, "carbody roll [mrad]"),
                                      ("air_from_supply_kg", 1e3, "air injected from the supply [g]")):
            curves = [Curve(data["t_s"], data[column] * scale, label(d, case))
                      for d, _ in infos for case, data in _series(d, "curve_")]
            panels.append(Panel(curves, "time t [s]", ylabel))
        written.append(save_panels(out_dir / "compare_curve.png", panels, "Curve entry comparison", ncols=2))
    elif kind in ("rig_sine", "rig_ramp"):
        prefix = "sine_" if kind == "rig_sine" else "ramp_"
        column, ylabel = ("T_bellow_K", "bellow temperature T [K]") if kind == "rig_sine" else ("F_bellow_N", "bellow force F [N]")
        curves = [Curve(data["t_s"], data[column], label(d, k)) for d, _ in infos for k, data in _series(d, prefix)]
        written.append(save_panels(out_dir / f"compare_{kind}.png", [Panel(curves, "time t [s]", ylabel)], f"{kind} comparison"))
    else:
        raise ScenarioError(run_dirs[0], ["kind"], f"compare does not support {kind!r} runs (summary.csv holds its numbers)")
    return written
