"""Turn an :class:`~cosim.results.outcome.Outcome` into files: the time series (CSV, one file per
case), ``summary.csv`` and the outcome's further tables (``<name>.csv``), the figures (PNG) and
``run.json`` (provenance, status, metrics, diagnoses, warnings, and what the report shows: the
parameters and where each came from, the faults, the figures' titles), in that order; every file
is written atomically."""
from __future__ import annotations

import dataclasses
import json
import multiprocessing
import textwrap
import xml.etree.ElementTree as ET
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import List, Sequence

from cosim.interrupts import ignore_in_worker
from cosim.results.io import atomic_write, jsonable, write_columns, write_rows, write_run_json
from cosim.results.outcome import Outcome
from cosim.results.plots import Figure, pyplot
from cosim.results.series import case_columns


def write_outcome(outcome: Outcome, out: Path, figures: Sequence[Figure] = (), jobs: int = 1) -> None:
    """Write everything ``outcome`` holds into the folder ``out``; ``figures`` are drawn on up to
    ``jobs`` processes."""
    out = Path(out)
    for name, ds in outcome.series.items():
        if "case" in ds.dims:
            for case in ds["case"].values:
                write_columns(out / "timeseries" / f"{name}_{case}.csv", case_columns(ds, case))
        else:
            write_columns(out / "timeseries" / f"{name}.csv", case_columns(ds))
    write_rows(out / "summary.csv", outcome.rows)
    for name, rows in outcome.tables.items():
        write_rows(out / f"{name}.csv", rows)
    flagged = sorted({f for r in outcome.rows for f in str(r.get("validity", "ok")).split(";")} - {"ok", ""})
    if flagged:
        note = f"[outside the model's validity in some cases: {', '.join(flagged)}; see summary.csv, column validity]"
        figures = [dataclasses.replace(f, title="\n".join(filter(None, [f.title, textwrap.fill(note, 90 * f.ncols)])))
                   for f in figures]
    save_figures(out, figures, jobs)
    write_run_json(out, outcome.scenario, outcome.wall_s, "interrupted" if outcome.interrupted else "complete",
                   {"diverged": outcome.diverged, "metrics": outcome.metrics, "warnings": outcome.warnings,
                    **report_facts(outcome, figures), **outcome.info})


def report_facts(outcome: Outcome, figures: Sequence[Figure] = ()) -> dict:
    """What ``pneumorail report`` shows beyond the results: the summary columns the kind shows
    (``summary_columns``), the faults in words, every parameter the car and its circuit ran with
    and where each value came from (:func:`parameter_groups`), and each figure's title (its
    caption: the run's own radius, limits ...)."""
    faults = getattr(outcome.scenario.circuit, "faults", ()) or ()
    return {"summary_columns": list(outcome.shown), "faults": [f.label() for f in faults],
            "parameters": parameter_groups(outcome.scenario),
            "figures": {f.name: f.title or "" for f in figures}}


#: the parts of a circuit whose parameters are listed, and which of them a circuit preset gives
CIRCUIT_PARTS = ("bellow", "tank", "pipe", "cross_pipe", "levelling_valve", "differential_valve", "supply")
PRESET_PARTS = ("bellow", "tank", "pipe")
#: fields that name the components a part connects, not a parameter of it
CONNECTIONS = ("a", "b", "bellow", "supply", "exhaust", "sensed")


def parameter_groups(scenario) -> List[dict]:
    """The vehicle's and the circuit's parameters as the run used them, by group (``vehicle``,
    ``circuit bellow`` ...): ``base`` (what the values come from: a preset, a parameter file, the
    defaults), ``values`` (name -> value) and ``set`` (name -> ``scenario`` or ``--set``: the
    values the scenario or the command line put over the base)."""
    raw, overrides = scenario.raw or {}, [o.split("=", 1)[0].strip() for o in scenario.overrides]
    groups = []
    if getattr(scenario, "vehicle", None) is not None:
        groups.append(_group("vehicle", scenario.vehicle, ("vehicle",), raw, overrides, _vehicle_base(raw.get("vehicle"))))
    circuit_raw = raw.get("circuit") if isinstance(raw.get("circuit"), dict) else {}
    preset = circuit_raw.get("preset")
    for part in CIRCUIT_PARTS:
        value = getattr(scenario.circuit, part, None)
        if dataclasses.is_dataclass(value):
            base = f"preset {preset}" if preset and part in PRESET_PARTS else "defaults"
            groups.append(_group(f"circuit {part.replace('_', ' ')}", value, ("circuit", part), raw, overrides, base))
    return groups


def _group(name: str, params, path, raw: dict, overrides: Sequence[str], base: str) -> dict:
    """One group of :func:`parameter_groups`: ``params`` (a dataclass) at ``path`` in the scenario."""
    given = raw
    for key in path:
        given = given.get(key) if isinstance(given, dict) else None
    given = given if isinstance(given, dict) else {}
    values = {k: v for k, v in dataclasses.asdict(params).items()
              if k not in CONNECTIONS and v not in (None, "", [], ())}
    dotted = ".".join(path)
    if dotted in overrides:                               # the whole section given on the command line
        base += " (--set)"
    return {"group": name, "base": base, "values": values,
            "set": {k: "--set" if f"{dotted}.{k}" in overrides else "scenario" for k in values if k in given}}


def _vehicle_base(value) -> str:
    """Where the vehicle's values come from: a preset, a parameter file or the defaults (the
    paper's car)."""
    from cosim.scenario.presets import VEHICLE_PRESETS
    if isinstance(value, dict):
        if value.get("file"):
            return f"file {value['file']}"
        value = value.get("preset")
    if value is None:
        return "defaults (paper_metro_car)"
    return f"preset {value}" if value in VEHICLE_PRESETS else f"file {value}"


def write_verdict(outcome: Outcome, out: Path) -> None:
    """``check.json`` (:meth:`Outcome.verdict`) and ``check.xml``, the same as a JUnit report
    (one test case per check, validity flag and divergence; a check without a value is an error)
    for CI systems."""
    verdict = outcome.verdict()
    with atomic_write(Path(out) / "check.json") as fh:
        fh.write(json.dumps(jsonable(verdict), indent=2, allow_nan=False) + "\n")
    items = verdict["checks"]
    suite = ET.Element("testsuite", name=f"pneumorail check {verdict['name']}", tests=str(len(items)),
                       failures=str(sum(i["status"] == "fail" for i in items)),
                       errors=str(sum(i["status"] == "error" for i in items)),
                       time=f"{outcome.wall_s:.3f}")
    for item in items:
        case = ET.SubElement(suite, "testcase", classname=f"pneumorail.{verdict['name']}", name=item["name"])
        if "value" in item:
            ET.SubElement(case, "system-out").text = f"value {item['value']:.6g} at {item['at'] or 'the run'}"
        if item["status"] == "fail":
            message = f"{item['value']:.6g} violates {item['name']} ({item['at']})" if "value" in item else item["message"]
            ET.SubElement(case, "failure", message=message)
        elif item["status"] == "error":                     # a check without a value: why
            ET.SubElement(case, "error", message=item["message"])
    with atomic_write(Path(out) / "check.xml") as fh:
        fh.write(ET.tostring(ET.ElementTree(suite).getroot(), encoding="unicode", xml_declaration=True) + "\n")


def save_figures(out: Path, figures: Sequence[Figure], jobs: int = 1) -> None:
    """Draw independent figures into ``out`` on up to ``jobs`` processes, the largest first."""
    figures = sorted(figures, key=lambda f: -len(f.panels))
    workers = max(1, min(jobs, len(figures)))
    if workers == 1:
        for figure in figures:
            figure.save(out)
        return
    context = multiprocessing.get_context()             # the pool's default
    if context.get_start_method() == "fork":            # the workers inherit what this process imported:
        pyplot()                                        # matplotlib once here, not in each (~0.35 s of CPU)
    with ProcessPoolExecutor(workers, mp_context=context, initializer=ignore_in_worker) as pool:      # Ctrl-C: the parent's
        list(pool.map(Figure.save, figures, [out] * len(figures)))
