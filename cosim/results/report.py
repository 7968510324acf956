"""``pneumorail report``: one self-contained HTML file an engineer can hand on -- what ran, the
EN 14363 assessment beside its limits with pass / fail, the checks, the verification if the run
has one, validity flags and warnings, every figure (embedded), and the provenance. Several runs
give a side-by-side report. Read from the output folders; nothing is fetched (no network, no
script), so the file opens anywhere, e.g. from a USB stick."""
from __future__ import annotations

import base64
import html
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence

from cosim.errors import ScenarioError
from cosim.results.io import atomic_write, read_rows
from cosim.results.overlay import run_info

#: summary columns shown beside the headline metrics of run.json
ALWAYS = ("valves", "k_W_per_K", "validity")

STYLE = """
body { font-family: sans-serif; margin: 2em; color: #222; max-width: 1400px; }
h1 { font-size: 1.6em; } h2 { font-size: 1.25em; border-bottom: 1px solid #aaa; margin-top: 2em; }
table { border-collapse: collapse; margin: 0.5em 0 1em 0; font-size: 0.85em; }
th, td { border: 1px solid #bbb; padding: 0.2em 0.5em; text-align: left; vertical-align: top; }
th { background: #eee; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
td.pass { background: #d8f0d8; } td.fail { background: #f6c9c9; font-weight: bold; }
td.indicator { background: #fdf0c8; }
figure { margin: 1em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
.wide { overflow-x: auto; }
figcaption { font-size: 0.85em; color: #555; } .note { color: #555; font-size: 0.9em; }
"""


@dataclass
class RunFolder:
    """What one output folder holds for the report."""

    path: Path
    info: dict
    summary: List[Dict[str, str]]
    limits: List[Dict[str, str]]
    check: Optional[dict] = None
    verify: Optional[dict] = None
    figures: List[Path] = field(default_factory=list)
    label: str = ""

    @property
    def name(self) -> str:
        """The folder the user named (a verify folder, not its level_0)."""
        return self.label or self.path.name


def read_run(path: Path) -> RunFolder:
    """An output folder (of ``run``, ``check`` or ``verify``: a verify folder is reported by its
    level-0 run with its verify.json)."""
    path = label = Path(path)
    verify = None
    if (path / "verify.json").exists() and (path / "level_0" / "run.json").exists():
        verify, path = _json(path / "verify.json"), path / "level_0"
    elif path.name.startswith("level_") and (path.parent / "verify.json").exists():
        verify = _json(path.parent / "verify.json")
    info = run_info(path)
    rows = read_rows(path / "summary.csv") if (path / "summary.csv").exists() else []
    limits = read_rows(path / "assessment_limits.csv") if (path / "assessment_limits.csv").exists() else []
    check = _json(path / "check.json") if (path / "check.json").exists() else None
    return RunFolder(path, info, rows, limits, check, verify, sorted(path.glob("*.png")), label.name)


def _json(path: Path) -> dict:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise ScenarioError(path, [], f"cannot read it ({exc})") from None


def _e(value) -> str:
    return html.escape(str(value))


def _number(text) -> str:
    """A number as the report shows it: 4 significant digits, inf spelled out."""
    try:
        v = float(text)
    except (TypeError, ValueError):
        return _e(text)
    if math.isnan(v):
        return "nan"
    return "inf" if math.isinf(v) else f"{v:.4g}"


def _in_unit(unit: str):
    """How a value of ``unit`` is shown: forces in kN, dimensionless ones bare."""
    if unit == "N":
        return lambda v: "nan" if str(v) == "nan" else f"{float(v) * 1e-3:.4g} kN"
    return lambda v: _number(v) + ("" if unit in ("1", "") else f" {_e(unit)}")


def _table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """An HTML table; a cell given as (text, css class) gets that class."""
    def cell(c):
        text, css = c if isinstance(c, tuple) else (c, "")
        return f"<td class='{css}'>{text}</td>" if css else f"<td>{text}</td>"
    head = "".join(f"<th>{_e(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(cell(c) for c in r) + "</tr>" for r in rows)
    return f"<div class='wide'><table><tr>{head}</tr>{body}</table></div>"


def _what_ran(runs: Sequence[RunFolder]) -> str:
    def setting(run, *keys):
        node = run.info.get("settings", {})
        for k in keys:
            node = node.get(k, {}) if isinstance(node, dict) else {}
        return node if node != {} else "—"

    def experiment(run):
        section = run.info.get("resolved", {}).get(run.info.get("section") or "", {})
        if not isinstance(section, dict):
            return "—"
        return ", ".join(f"{k} = {v}" for k, v in section.items() if not isinstance(v, dict) and v is not None) or "—"

    facts = [
        ("scenario", lambda r: r.info.get("name")), ("description", lambda r: setting(r, "description")),
        ("kind", lambda r: r.info.get("kind")), ("scenario file", lambda r: r.info.get("scenario_file")),
        ("vehicle", lambda r: setting(r, "vehicle")),
        ("circuit", lambda r: f"{setting(r, 'circuit', 'layout')}, preset {setting(r, 'circuit', 'preset')}, "
                              f"valves {setting(r, 'circuit', 'valves')}"),
        ("track", lambda r: r.info.get("resolved", {}).get("track", {}).get("model", "—")),
        ("experiment", experiment),
        ("k [W/K]", lambda r: ", ".join(map(str, r.info.get("k_W_per_K", [])))),
        ("test zones", lambda r: ", ".join(r.info.get("zones", [])) or "—"),
        ("status", lambda r: r.info.get("status")), ("wall time [s]", lambda r: _number(r.info.get("wall_time_s"))),
    ]
    return _table(["", *(r.name for r in runs)], [[_e(name), *(_e(fn(r)) for r in runs)] for name, fn in facts])


def _assessment(runs: Sequence[RunFolder]) -> str:
    """Side by side: per quantity and zone the worst value over each run's cases, its limit,
    pass / fail."""
    if not any(r.limits for r in runs):
        return "<p class='note'>No EN 14363 assessment in these runs (it is made for car runs on track).</p>"
    keys = list(dict.fromkeys((row["quantity"], row["zone"]) for r in runs for row in r.limits))
    rows = []
    for quantity, zone in keys:
        limit_row = next(row for r in runs for row in r.limits if (row["quantity"], row["zone"]) == (quantity, zone))
        shown = _in_unit(limit_row["unit"])
        cells = [_e(quantity), _e(zone), shown(limit_row["limit"]), _e(limit_row["kind"])]
        for r in runs:
            mine = [row for row in r.limits if (row["quantity"], row["zone"]) == (quantity, zone)]
            if not mine:
                cells.append("—")
                continue
            worst = max(mine, key=lambda row: -math.inf if row["value"] == "nan" else float(row["value"]))
            failed = any(row["status"] == "fail" for row in mine)
            css = ("fail" if limit_row["kind"] == "criterion" else "indicator") if failed else "pass"
            where = f"valves {'on' if worst['valves'] == 'True' else 'off'}, k = {worst['k_W_per_K']} W/K, {worst['at']}"
            cells.append((f"{shown(worst['value'])} ({'FAIL' if failed else 'pass'}; {_e(where)})", css))
        rows.append(cells)
    sources = sorted({(row["quantity"], row["source"]) for r in runs for row in r.limits})
    legend = "; ".join(f"{_e(q)}: {_e(s)}" for q, s in dict(sources).items())
    return (_table(["quantity", "zone", "limit", "type", *(r.name for r in runs)], rows)
            + f"<p class='note'>2 m sliding means every 0.5 m of track, per zone; the worst case and wheel (wheelset) "
              f"of each run. Limits: {legend}.</p>")


def _checks(run: RunFolder) -> str:
    if not run.check:
        return ""
    rows = [[_e(c.get("name")), _number(c.get("value", "")), _e(c.get("at", c.get("message", ""))),
             ("PASS", "pass") if c["status"] == "pass" else ("FAIL", "fail")] for c in run.check["checks"]]
    return f"<h3>{_e(run.name)}: checks ({_e(run.check['status'])})</h3>" + _table(["check", "value", "at", "result"], rows)


def _summary(run: RunFolder) -> str:
    if not run.summary:
        return f"<p class='note'>{_e(run.name)}: no summary.</p>"
    columns = [c for c in (*ALWAYS, *run.info.get("metrics", {}), "en14363_failed") if c in run.summary[0]]
    rows = [[_number(row[c]) if c not in ("validity", "valves") else _e(row[c]) for c in columns] for row in run.summary]
    return f"<h3>{_e(run.name)}</h3>" + _table(columns, rows)


def _verification(run: RunFolder) -> str:
    """verify.json's estimates: per headline metric and case the three levels' values, the observed
    order, the Richardson estimate and the estimated relative error against the tolerance."""
    if not run.verify:
        return ""
    tolerance = float(run.verify.get("tolerance", 0.005))
    rows, worst = [], 0.0
    for e in run.verify.get("estimates", []):
        error = float(e["estimated_relative_error"])
        worst = max(worst, error)
        levels = " / ".join(_number(e[k]) for k in sorted(k for k in e if k.startswith("level_")))
        rows.append([_e(e["metric"]), _e(e["case"]), levels, _number(e["observed_order"]), _number(e["richardson"]),
                     (f"{100 * error:.3f} %", "pass" if error <= tolerance else "fail")])
    steps = "; ".join(f"level {s['level']}: H {s['macro_step_s']:g} s, multibody {s['mechanics_step_s']:g} s, "
                      f"pneumatic {s['pneumatic_step_s']:g} s" for s in run.verify.get("levels", []))
    head = (f"<h3>{_e(run.name)}: verify, every step halved per level (largest estimated error "
            f"{100 * worst:.3f} %, tolerance {100 * tolerance:g} %)</h3><p class='note'>{_e(steps)}</p>")
    return head + _table(["metric", "case", "levels 0 / 1 / 2", "observed order", "Richardson estimate",
                          "estimated error of level 0"], rows)


def _flags(run: RunFolder) -> str:
    flagged = [f"{row.get('valves', '')} k = {row.get('k_W_per_K', '')}: {row['validity']}"
               for row in run.summary if row.get("validity", "ok") not in ("ok", "")]
    items = [f"outside the model's validity: {f}" for f in flagged] + list(run.info.get("warnings", []))
    if run.info.get("diverged"):
        items.append(f"diverged: {run.info['diverged']}")
    body = "".join(f"<li>{_e(i)}</li>" for i in items) or "<li>none</li>"
    return f"<h3>{_e(run.name)}</h3><ul>{body}</ul>"


def _figures(run: RunFolder) -> str:
    out = []
    for png in run.figures:
        data = base64.b64encode(png.read_bytes()).decode("ascii")
        out.append(f"<figure><img alt='{_e(png.stem)}' src='data:image/png;base64,{data}'>"
                   f"<figcaption>{_e(run.name)}: {_e(png.name)}</figcaption></figure>")
    return "".join(out) or f"<p class='note'>{_e(run.name)}: no figures.</p>"


def _provenance(runs: Sequence[RunFolder]) -> str:
    def files(r):
        return "<br>".join(f"{_e(k)}: {_e(v)}" for k, v in r.info.get("files_sha256", {}).items())
    facts = [("command", lambda r: _e(r.info.get("command", "—"))),
             ("finished (UTC)", lambda r: _e(r.info.get("finished_utc", "—"))),
             ("source", lambda r: _e(json.dumps(r.info.get("source") or "not a git checkout"))),
             ("versions", lambda r: _e(", ".join(f"{k} {v}" for k, v in r.info.get("versions", {}).items()))),
             ("files (sha256)", files),
             ("folder", lambda r: _e(r.path.resolve()))]
    return _table(["", *(r.name for r in runs)], [[_e(name), *(fn(r) for r in runs)] for name, fn in facts])


def render(runs: Sequence[RunFolder]) -> str:
    """The report's HTML."""
    names = ", ".join(r.name for r in runs)
    sections = [
        ("What ran", _what_ran(runs)),
        ("EN 14363 assessment", _assessment(runs)),
        ("Checks", "".join(_checks(r) for r in runs) or "<p class='note'>No checks were evaluated "
                                                         "(pneumorail check writes them).</p>"),
        ("Summary", "".join(_summary(r) for r in runs)),
        ("Verification", "".join(_verification(r) for r in runs) or "<p class='note'>No verification "
                                                                     "(pneumorail verify makes one).</p>"),
        ("Validity and warnings", "".join(_flags(r) for r in runs)),
        ("Figures", "".join(_figures(r) for r in runs)),
        ("Provenance", _provenance(runs)),
    ]
    body = "".join(f"<h2>{_e(title)}</h2>{content}" for title, content in sections)
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    return (f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>pneumorail report: {_e(names)}</title>"
            f"<style>{STYLE}</style></head><body><h1>pneumorail report: {_e(names)}</h1>"
            f"<p class='note'>Generated {stamp} from {len(runs)} output folder(s).</p>{body}</body></html>\n")


def write_report(run_dirs: Sequence[Path], out_file: Optional[Path] = None) -> Path:
    """Write the report of ``run_dirs`` to ``out_file`` (default: ``report.html`` in the first
    run's folder); returns its path."""
    runs = [read_run(Path(d)) for d in run_dirs]
    out_file = Path(out_file) if out_file else runs[0].path / "report.html"
    with atomic_write(out_file) as fh:
        fh.write(render(runs))
    return out_file
