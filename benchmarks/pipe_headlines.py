"""Twist, curve and ride headlines with the compressible pipe against the inertial pipe (issue 38).

    python benchmarks/pipe_headlines.py [--out DIR] [--only twist,curve,ride,lengths,volume,checks]
                                        [--quick] [--jobs 1] [--force]

Every run is ``pneumorail run`` (of this checkout, as a subprocess) of a variant of a shipped
scenario that differs from it in ``circuit.pipe`` alone: ``{model: dynamic}`` (eq. 5, the inertial
pipe the shipped scenarios use through ``preset: paper_table1``) or ``{model: compressible}`` (5 cm
cells: 20 for the paper's 1 m pipe), and for the lengths study ``length_m``. The variants are
written to ``DIR/scenarios``; other changes are ``--k`` / ``--set`` overrides on the command line,
recorded in each run's ``run.json``. A run whose folder already holds a complete ``run.json`` of
the same scenario content, overrides and k is reused (``--force`` reruns it).

Sections (``--only``; default all, in this order):

* ``twist``: ``scenarios/twist_dqq.yaml``, every k: ΔQ/Q0 max and quasi-static.
* ``curve``: ``scenarios/curve_entry.yaml``, every k, valves off and on: roll max and end roll,
  air injected and exhausted.
* ``ride``: ``scenarios/ride_comfort.yaml`` at 20 m/s only (``--set
  ride.speeds_m_per_s=[20.0]``), k = 0, 10, 100, inf, 60 s record: N_MV at the car centre and
  above the front bogie, Wz.
* ``lengths``: the ride at 20 m/s, k = 10 and 100 W/K, pipe 1 m (the ride section's runs), 5 m
  and 20 m, both models; the compressible pipe in cells of 5, 10 and 20 cm
  (:data:`CELL_LENGTH_M`: 20, 50, 100 cells).
* ``volume``: is the difference the pipe's volume? The inertial runs of every section once more
  with the pipe's volume A L added to the tank (the inertial pipe stores no air).
* ``checks``: is the difference physics or discretisation? ``pneumorail verify`` (every step
  halved twice) of the inertial twist and curve at k = 0 and inf and of the inertial rides (1, 5,
  20 m); the compressible twist at k = 0 and inf with every step halved (cells kept) and with the
  cells doubled (steps kept); the compressible curve, valves on, k = 0 and inf, every step halved.

``--quick``: k = 0 and inf only, ride records of 10 s, lengths 1 and 5 m, no volume or checks: a
smoke test of the script, not the documented numbers.

Prints markdown tables (also to ``DIR/pipe_headlines.md``) and the runs' wall times from their
``run.json`` (on a machine shared with other work they vary by tens of %).
"""
from __future__ import annotations

import argparse
import csv
import hashlib
import json
import math
import os
import subprocess
import sys
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import yaml

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"
MODELS = ("dynamic", "compressible")
NAMES = {"dynamic": "inertial", "compressible": "compressible"}
RIDE_SETS = ("ride.speeds_m_per_s=[20.0]",)
STEPS = ("macro_step_s", "mechanics_step_s", "pneumatic_step_s")
#: ``pneumorail`` of this checkout (not whichever is installed on PATH)
PNEUMORAIL = (sys.executable, "-m", "cosim.cli")
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, (str(ROOT), os.environ.get("PYTHONPATH"))))}


# -- running --------------------------------------------------------------------------------------

def variant(out: Path, shipped: str, pipe: Dict[str, object], tag: str) -> Path:
    """The shipped scenario with ``circuit.pipe`` replaced by ``pipe`` (merged onto the preset's)."""
    data = yaml.safe_load((SCENARIOS / shipped).read_text())
    data["circuit"]["pipe"] = dict(pipe)
    path = out / "scenarios" / f"{Path(shipped).stem}_{tag}.yaml"
    path.parent.mkdir(parents=True, exist_ok=True)
    text = yaml.safe_dump(data, sort_keys=False)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
    return path


def _reusable(folder: Path, scenario: Path, k: Optional[str], sets: Sequence[str]) -> bool:
    meta = folder / "run.json"
    if not meta.exists():
        return False
    run = json.loads(meta.read_text())
    same_k = k is None or [str(v) for v in run.get("k_W_per_K", [])] == k.split(",")
    return (run.get("status") == "complete" and not run.get("diverged")
            and run.get("scenario_sha256") == hashlib.sha256(scenario.read_bytes()).hexdigest()
            and list(run.get("overrides", [])) == list(sets) and same_k)


def run(args, name: str, scenario: Path, k: Optional[str] = None, sets: Sequence[str] = ()) -> Path:
    """``pneumorail run`` into ``DIR/runs/name`` unless a matching run is there."""
    folder = args.out / "runs" / name
    if not args.force and _reusable(folder, scenario, k, sets):
        print(f"[reuse] {name}", file=sys.stderr)
        return folder
    cmd = [*PNEUMORAIL, "run", str(scenario), "--out", str(folder), "--jobs", str(args.jobs), "--quiet", "--overwrite"]
    if k:
        cmd += ["--k", k]
    for s in sets:
        cmd += ["--set", s]
    print("[run]", " ".join(cmd), file=sys.stderr, flush=True)
    done = subprocess.run(cmd, env=ENV)
    if done.returncode != 0:
        print(f"[run] {name} exited {done.returncode} (its run.json and log say why)", file=sys.stderr)
    return folder


def verify(args, name: str, scenario: Path, k: Optional[str] = None, sets: Sequence[str] = ()) -> Path:
    """``pneumorail verify`` (the scenario's levels: steps halved twice) into ``DIR/runs/name``."""
    folder = args.out / "runs" / name
    if not args.force and (folder / "verify.csv").exists():
        print(f"[reuse] {name}", file=sys.stderr)
        return folder
    cmd = [*PNEUMORAIL, "verify", str(scenario), "--out", str(folder), "--jobs", str(args.jobs), "--quiet"]
    if k:
        cmd += ["--k", k]
    for s in sets:
        cmd += ["--set", s]
    print("[verify]", " ".join(cmd), file=sys.stderr, flush=True)
    subprocess.run(cmd, env=ENV)
    return folder


# -- reading --------------------------------------------------------------------------------------

def summary(folder: Path) -> List[Dict[str, str]]:
    path = folder / "summary.csv"
    if not path.exists():
        return []
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def wall(folder: Path) -> float:
    try:
        return float(json.loads((folder / "run.json").read_text())["wall_time_s"])
    except (OSError, KeyError, ValueError):
        return math.nan


def key(row: Dict[str, str], columns: Sequence[str]) -> tuple:
    return tuple(row[c] for c in columns)


def index(rows, columns) -> Dict[tuple, Dict[str, str]]:
    return {key(r, columns): r for r in rows}


def _norm(v: str) -> str:
    """A case value as verify.csv and summary.csv may spell it differently (20 / 20.0)."""
    try:
        return repr(float(v))
    except ValueError:
        return v.strip().lower()


def verify_errors(folder: Path) -> Dict[tuple, float]:
    """(metric, {column: value} of the case) -> estimated relative error of the shipped steps
    (verify.csv: ``case`` is ``column=value, ...``)."""
    path = folder / "verify.csv"
    if not path.exists():
        return {}
    out = {}
    with open(path, newline="") as fh:
        for r in csv.DictReader(fh):
            case = frozenset((c.strip(), _norm(v)) for c, v in (item.split("=", 1) for item in r["case"].split(", ")))
            out[(r["metric"], case)] = float(r["estimated_relative_error"])
    return out


def step_error(errors: Dict[tuple, float], metric: str, row: Dict[str, str], columns: Sequence[str]) -> Optional[float]:
    """The verify error of a summary row's case: the verify case whose columns ``columns`` match."""
    want = {(c, _norm(row[c])) for c in columns}
    found = [e for (m, case), e in errors.items() if m == metric and want <= case]
    return found[0] if len(found) == 1 else None


def fnum(x: float, scale: float = 1.0, digits: int = 4) -> str:
    return "–" if x is None or math.isnan(x) else f"{x * scale:.{digits}g}"


def pct(a: float, b: float, decimals: int = 2) -> str:
    """(b - a) / |a| in %."""
    if a is None or b is None or math.isnan(a) or math.isnan(b) or a == 0:
        return "–"
    return f"{100 * (b - a) / abs(a):+.{decimals}f} %"


def val(row: Optional[Dict[str, str]], col: str) -> float:
    try:
        return float(row[col]) if row is not None else math.nan
    except (KeyError, ValueError):
        return math.nan


def comparison(title: str, rows_i, rows_c, columns, metrics) -> str:
    """One markdown table, a row per case: each metric inertial / compressible (difference)."""
    by_c = index(rows_c, columns)
    head = [*columns, *(label for _, label, _ in metrics)]
    lines = [f"**{title}**: inertial / compressible (difference)", "",
             "| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for r in rows_i:
        rc = by_c.get(key(r, columns))
        cells = list(r[c] for c in columns)
        for metric, _, scale in metrics:
            x, y = val(r, metric), val(rc, metric)
            cells.append("0 / 0" if x == 0 and y == 0 else f"{fnum(x, scale)} / {fnum(y, scale)} ({pct(x, y)})")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def against_step_error(blocks) -> str:
    """The difference compressible - inertial against the inertial run's estimated step error.
    ``blocks``: (scenario, inertial folder, compressible folder, case columns, metrics, verify folder)."""
    lines = ["**Difference against the step error**: compressible - inertial, and the inertial run's "
             "estimated relative error at the shipped steps (`pneumorail verify`, steps halved twice, "
             "Richardson)", "",
             "| scenario | case | metric | compressible - inertial | step error | difference / error |",
             "| --- | --- | --- | --- | --- | --- |"]
    for scenario, folder_i, folder_c, columns, metrics, folder_v in blocks:
        errors = verify_errors(folder_v)
        by_c = index(summary(folder_c), columns)
        for r in summary(folder_i):
            for metric, label, _ in metrics:
                e = step_error(errors, metric, r, columns)
                x, y = val(r, metric), val(by_c.get(key(r, columns)), metric)
                if e is None or x == 0:
                    continue
                d = abs(y - x) / abs(x)
                ratio = "–" if e == 0 else f"{d / e:.2g}"
                lines.append(f"| {scenario} | {', '.join(f'{c} {r[c]}' for c in columns)} | {label} | "
                             f"{pct(x, y)} | {100 * e:.3f} % | {ratio} |")
    return "\n".join(lines)


# -- sections -------------------------------------------------------------------------------------

TWIST_METRICS = (("dqq_max", "ΔQ/Q0 max", 1.0), ("dqq_qs_max", "ΔQ/Q0 quasi-static", 1.0))
CURVE_METRICS = (("roll_max_rad", "roll max [mrad]", 1e3), ("roll_mean_end_rad", "roll end [mrad]", 1e3),
                 ("air_injected_kg", "air injected [g]", 1e3), ("air_exhausted_kg", "air exhausted [g]", 1e3))
RIDE_METRICS = (("N_MV_centre", "N_MV centre", 1.0), ("N_MV_front", "N_MV front", 1.0),
                ("Wz_z_centre", "Wz vertical centre", 1.0), ("Wz_y_centre", "Wz lateral centre", 1.0))


def pair(args, name: str, shipped: str, k: Optional[str] = None, sets: Sequence[str] = ()) -> Dict[str, Path]:
    """The shipped scenario run with the inertial and with the compressible pipe."""
    return {m: run(args, f"{name}_{NAMES[m]}", variant(args.out, shipped, {"model": m}, NAMES[m]), k, sets)
            for m in MODELS}


def section_twist(args):
    runs = pair(args, "twist", "twist_dqq.yaml", "0,inf" if args.quick else None)

    def table():
        return comparison("Twist (scenarios/twist_dqq.yaml, 40 mm under 1R/2R, valves isolated)",
                          summary(runs["dynamic"]), summary(runs["compressible"]), ("k_W_per_K",), TWIST_METRICS)
    return runs, table


def section_curve(args):
    runs = pair(args, "curve", "curve_entry.yaml", "0,inf" if args.quick else None)

    def table():
        return comparison("Curve entry (scenarios/curve_entry.yaml, R 100 m at 10 m/s)",
                          summary(runs["dynamic"]), summary(runs["compressible"]), ("valves", "k_W_per_K"),
                          CURVE_METRICS)
    return runs, table


def ride_sets(args) -> List[str]:
    return [*RIDE_SETS, *(["ride.record_s=10.0"] if args.quick else [])]


def section_ride(args):
    runs = pair(args, "ride", "ride_comfort.yaml", "0,inf" if args.quick else None, ride_sets(args))

    def table():
        record = "10 s" if args.quick else "60 s"
        return comparison(f"Ride (scenarios/ride_comfort.yaml at 20 m/s, {record} record, valves connected)",
                          summary(runs["dynamic"]), summary(runs["compressible"]), ("speed_m_per_s", "k_W_per_K"),
                          RIDE_METRICS)
    return runs, table


#: cell length of the compressible pipe by pipe length in the lengths study: the default 5 cm for
#: the paper's 1 m, coarser for the long pipes (the RK4 step is bounded by the cell: 87 us at 5 cm,
#: 350 us at 20 cm); 10 and 20 cm cells are 43 and 22 per wavelength at 80 Hz (the top of the
#: comfort weightings, 4.3 m). Their cell error is not checked (see the docs: the 20 m pipe in 10 cm
#: cells, one k, had not finished after 50 min).
CELL_LENGTH_M = {1.0: 0.05, 5.0: 0.1, 20.0: 0.2}
LENGTHS = (5.0, 20.0)
LENGTHS_K = "10,100"
RIDE_COMFORT = (("N_MV_centre", "N_MV centre"), ("N_MV_front", "N_MV front"), ("Wz_z_centre", "Wz vertical centre"))


def long_pipe(args, model: str, L: float) -> Path:
    """ride_comfort's variant with a pipe of length ``L`` (compressible: cells of CELL_LENGTH_M)."""
    pipe = {"model": model, "length_m": L, **({"cell_length_m": CELL_LENGTH_M[L]} if model == "compressible" else {})}
    return variant(args.out, "ride_comfort.yaml", pipe, f"{NAMES[model]}_{L:g}m")


def section_lengths(args):
    lengths = (5.0,) if args.quick else LENGTHS
    k = "0,inf" if args.quick else LENGTHS_K
    # the paper's 1 m pipe: the ride section's runs (every k; a case's result does not depend on
    # the other cases run with it)
    ride = pair(args, "ride", "ride_comfort.yaml", "0,inf" if args.quick else None, ride_sets(args))
    runs = {f"1 m, {NAMES[m]}": folder for m, folder in ride.items()}
    for L in lengths:
        for m in MODELS:
            runs[f"{L:g} m, {NAMES[m]}"] = run(args, f"ride_{NAMES[m]}_{L:g}m", long_pipe(args, m, L), k,
                                                ride_sets(args))
    wanted = k.split(",")

    def table():
        lines = ["**Ride comfort against pipe length** (ride_comfort at 20 m/s, 18 mm bore, zeta = 1.11; "
                 "compressible pipe in cells of " + ", ".join(f"{100 * CELL_LENGTH_M[L]:g} cm at {L:g} m"
                                                               for L in (1.0, *lengths)) + ")", "",
                 "| pipe | k [W/K] | " + " | ".join(f"{label}, inertial / compressible | difference"
                                                    for _, label in RIDE_COMFORT) + " |",
                 "|" + " --- |" * (2 + 2 * len(RIDE_COMFORT))]
        for L in (1.0, *lengths):
            ri = index(summary(runs[f"{L:g} m, inertial"]), ("k_W_per_K",))
            rc = index(summary(runs[f"{L:g} m, compressible"]), ("k_W_per_K",))
            for kk in (kk for kk in ri if kk[0] in wanted):
                cells = [f"{L:g} m", kk[0]]
                for metric, _ in RIDE_COMFORT:
                    a, b = val(ri[kk], metric), val(rc.get(kk), metric)
                    cells += [f"{fnum(a)} / {fnum(b)}", pct(a, b)]
                lines.append("| " + " | ".join(cells) + " |")
        return "\n".join(lines)
    return runs, table


def halved(reference: Path) -> List[str]:
    """``--set`` overrides that halve the steps a reference run used (its run.json)."""
    solver = json.loads((reference / "run.json").read_text())["resolved"]["solver"]
    return [f"solver.{s}={solver[s] / 2:g}" for s in STEPS]


def section_checks(args):
    """Discretisation against physics: the inertial runs verified (steps halved twice), the
    compressible runs refined once (steps halved, or cells doubled). In order of cost."""
    twist, curve = pair(args, "twist", "twist_dqq.yaml"), pair(args, "curve", "curve_entry.yaml")
    ride = pair(args, "ride", "ride_comfort.yaml", None, ride_sets(args))
    runs = {"twist verify (inertial)": verify(args, "twist_inertial_verify", variant(
                args.out, "twist_dqq.yaml", {"model": "dynamic"}, "inertial"), "0,inf"),
            "curve verify (inertial)": verify(args, "curve_inertial_verify", variant(
                args.out, "curve_entry.yaml", {"model": "dynamic"}, "inertial"), "0,inf")}
    for L in sorted(LENGTHS, reverse=True):
        runs[f"ride {L:g} m verify (inertial)"] = verify(args, f"ride_inertial_{L:g}m_verify",
                                                         long_pipe(args, "dynamic", L), LENGTHS_K, list(RIDE_SETS))
    runs["ride verify (inertial)"] = verify(args, "ride_inertial_verify", variant(
        args.out, "ride_comfort.yaml", {"model": "dynamic"}, "inertial"), None, list(RIDE_SETS))
    # the references are the sections' runs of every k
    twist_c = variant(args.out, "twist_dqq.yaml", {"model": "compressible"}, "compressible")
    curve_c = variant(args.out, "curve_entry.yaml", {"model": "compressible"}, "compressible")
    runs.update({
        "twist compressible, steps halved": run(args, "twist_compressible_halved", twist_c, "0,inf",
                                                halved(twist["compressible"])),
        "twist compressible, 40 cells": run(args, "twist_compressible_40cells", twist_c, "0,inf",
                                            ["circuit.pipe.cells=40"]),
        "curve compressible, valves on, steps halved": run(args, "curve_compressible_halved", curve_c, "0,inf",
                                                           [*halved(curve["compressible"]),
                                                            "curve.valve_settings=[true]"])})

    def table():
        out = args.out / "runs"
        blocks = [("twist", twist["dynamic"], twist["compressible"], ("k_W_per_K",), TWIST_METRICS,
                   out / "twist_inertial_verify"),
                  ("curve", curve["dynamic"], curve["compressible"], ("valves", "k_W_per_K"), CURVE_METRICS,
                   out / "curve_inertial_verify"),
                  ("ride, 1 m", ride["dynamic"], ride["compressible"], ("k_W_per_K",), RIDE_METRICS,
                   out / "ride_inertial_verify")]
        blocks += [(f"ride, {L:g} m", out / f"ride_inertial_{L:g}m", out / f"ride_compressible_{L:g}m",
                    ("k_W_per_K",), RIDE_METRICS, out / f"ride_inertial_{L:g}m_verify") for L in LENGTHS]
        refined = (("twist", twist["compressible"], runs["twist compressible, steps halved"], twist["dynamic"],
                    "steps halved (5 ms)", ("k_W_per_K",), TWIST_METRICS),
                   ("twist", twist["compressible"], runs["twist compressible, 40 cells"], twist["dynamic"],
                    "40 cells of 2.5 cm", ("k_W_per_K",), TWIST_METRICS),
                   ("curve", curve["compressible"], runs["curve compressible, valves on, steps halved"],
                    curve["dynamic"], "steps halved (2.5 ms)", ("valves", "k_W_per_K"), CURVE_METRICS))
        lines = ["**The compressible runs refined**: each refinement against the compressible run at the "
                 "shipped steps and cells, and the difference compressible - inertial for scale", "",
                 "| scenario | case; refinement | metric | compressible | refined | change | "
                 "compressible - inertial |", "| --- | --- | --- | --- | --- | --- | --- |"]
        for scenario, ref, fine, inertial, label, columns, metrics in refined:
            by_ref, by_i = index(summary(ref), columns), index(summary(inertial), columns)
            for r in summary(fine):
                kk = key(r, columns)
                for metric, mlabel, scale in metrics:
                    x, y = val(by_ref.get(kk), metric), val(r, metric)
                    if x == 0 and y == 0:
                        continue
                    lines.append(f"| {scenario} | {', '.join(f'{c} {v}' for c, v in zip(columns, kk))}; {label} | "
                                 f"{mlabel} | {fnum(x, scale, 6)} | {fnum(y, scale, 6)} | {pct(x, y, 3)} | "
                                 f"{pct(val(by_i.get(kk), metric), x)} |")
        return against_step_error(blocks) + "\n\n" + "\n".join(lines)
    return runs, table


def pipe_volume_set(reference: Path) -> str:
    """``--set`` that adds the pipe's volume A L to the tank of an inertial run (its run.json)."""
    circuit = json.loads((reference / "run.json").read_text())["resolved"]["circuit"]
    pipe = circuit["pipe"]
    volume = math.pi / 4 * pipe["diameter_m"] ** 2 * pipe["length_m"]
    return f"circuit.tank.V_m3={circuit['tank']['V_m3'] + volume!r}"


def section_volume(args):
    """Is the difference the pipe's volume? The inertial pipe (which stores no air) with the
    compressible pipe's volume A L added to the tank, against both models."""
    twist, curve = pair(args, "twist", "twist_dqq.yaml"), pair(args, "curve", "curve_entry.yaml")
    ride = pair(args, "ride", "ride_comfort.yaml", None, ride_sets(args))
    out = args.out / "runs"
    inertial = {"model": "dynamic"}
    cases = [("twist", twist["dynamic"], twist["compressible"], variant(args.out, "twist_dqq.yaml", inertial, "inertial"),
              None, (), ("k_W_per_K",), TWIST_METRICS),
             ("curve", curve["dynamic"], curve["compressible"], variant(args.out, "curve_entry.yaml", inertial,
                                                                        "inertial"),
              None, (), ("valves", "k_W_per_K"), CURVE_METRICS),
             ("ride, 1 m", ride["dynamic"], ride["compressible"], variant(args.out, "ride_comfort.yaml", inertial,
                                                                          "inertial"),
              None, RIDE_SETS, ("k_W_per_K",), RIDE_METRICS)]
    cases += [(f"ride, {L:g} m", out / f"ride_inertial_{L:g}m", out / f"ride_compressible_{L:g}m",
               long_pipe(args, "dynamic", L), LENGTHS_K, RIDE_SETS, ("k_W_per_K",), RIDE_METRICS) for L in LENGTHS]
    runs = {}
    for scenario, reference, _, path, k, sets, _, _ in cases:
        runs[f"{scenario}, inertial + pipe volume in the tank"] = run(
            args, reference.name + "_plus_volume", path, k, [*sets, pipe_volume_set(reference)])

    def table():
        lines = ["**The pipe's volume switched on in the inertial model**: the inertial pipe with A L added to "
                 "the tank (inertial + V), against the inertial run and the compressible run", "",
                 "| scenario | case | metric | inertial | inertial + V | compressible | compressible - inertial | "
                 "compressible - (inertial + V) |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
        for (scenario, inertial, compressible, _, _, _, columns, metrics), folder in zip(cases, runs.values()):
            by_i, by_c = index(summary(inertial), columns), index(summary(compressible), columns)
            for r in summary(folder):
                kk = key(r, columns)
                for metric, label, scale in metrics:
                    x, v, y = val(by_i.get(kk), metric), val(r, metric), val(by_c.get(kk), metric)
                    if x == 0 and y == 0:
                        continue
                    lines.append(f"| {scenario} | {', '.join(f'{c} {q}' for c, q in zip(columns, kk))} | {label} | "
                                 f"{fnum(x, scale, 5)} | {fnum(v, scale, 5)} | {fnum(y, scale, 5)} | {pct(x, y)} | "
                                 f"{pct(v, y)} |")
        return "\n".join(lines)
    return runs, table


#: run order; the tables are written after every run (they read the checks' verify errors)
SECTIONS = {"twist": section_twist, "curve": section_curve, "ride": section_ride, "lengths": section_lengths,
            "volume": section_volume,
            "checks": section_checks}


def wall_of(folder: Path) -> float:
    """A run's wall time, or a verify's: the sum over its levels."""
    if (folder / "verify.csv").exists():
        return sum(wall(p) for p in sorted(folder.glob("level_*")))
    return wall(folder)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path("results/pipe_headlines"))
    ap.add_argument("--only", default=",".join(SECTIONS), help="comma-separated sections: " + ", ".join(SECTIONS))
    ap.add_argument("--quick", action="store_true", help="fewer k, 10 s ride records, no checks (smoke test)")
    ap.add_argument("--jobs", type=int, default=1, help="processes per run (default 1)")
    ap.add_argument("--force", action="store_true", help="rerun even where a matching run exists")
    args = ap.parse_args(argv)
    args.out = args.out.resolve()
    only = [s.strip() for s in args.only.split(",") if s.strip()]
    unknown = set(only) - set(SECTIONS)
    if unknown:
        ap.error(f"unknown section(s): {', '.join(sorted(unknown))}")
    if args.quick:
        only = [s for s in only if s not in ("checks", "volume")]
    tables, walls = [], []
    for name in SECTIONS:
        if name in only:
            runs, table = SECTIONS[name](args)
            tables.append(table)
            walls += [f"| {name} | {NAMES.get(label, label)} | {fnum(wall_of(folder), digits=4)} |"
                      for label, folder in runs.items()]
    out = [table() for table in tables]
    out.append("**Wall times** (run.json; 1 process per run, 2 cores shared with other work)\n\n"
               "| section | run | wall [s] |\n| --- | --- | --- |\n" + "\n".join(walls))
    text = "\n\n".join(out) + "\n"
    (args.out / "pipe_headlines.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
