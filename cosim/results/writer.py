"""Turn an :class:`~cosim.results.outcome.Outcome` into files: the time series (CSV, one file per
case), ``summary.csv`` and the outcome's further tables (``<name>.csv``), the figures (PNG) and
``run.json`` (provenance, status, metrics, diagnoses, warnings), in that order; every file is
written atomically."""
from __future__ import annotations

import dataclasses
import json
import textwrap
import xml.etree.ElementTree as ET
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Sequence

from cosim.results.io import atomic_write, jsonable, write_columns, write_rows, write_run_json
from cosim.results.outcome import Outcome
from cosim.results.plots import Figure
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
                    **outcome.info})


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
    with ProcessPoolExecutor(workers) as pool:
        list(pool.map(Figure.save, figures, [out] * len(figures)))
