"""``pneumorail report``: one self-contained HTML file an engineer can hand on -- the verdict first
(PASS / FAIL / NOT ASSESSED and the criterion that decides it, :mod:`cosim.results.verdict`), what
ran (faults and overrides included), the vehicle's and the circuit's parameters, the EN 14363
assessment and the checks with each limit's basis (stated by the standard, assumed, the
scenario's), the summary, the verification if the run has one, validity flags and warnings, every
figure (embedded, captioned with its own run's facts) and the provenance. Several runs give a
side-by-side report. Read from the output folders; nothing is fetched (no network, no script), so
the file opens anywhere, e.g. from a USB stick. Every table wraps its cells to the page's width."""
from __future__ import annotations

import base64
import html
import json
import math
import re
import time
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Callable, Dict, List, Mapping, Optional, Sequence, Tuple

from cosim.errors import ScenarioError
from cosim.limits.validity import FLAGS
from cosim.results.io import atomic_write, read_rows
from cosim.results.outdir import INCOMPLETE, LOCK, holder
from cosim.results.overlay import folder_json, incomplete, run_info
from cosim.results.verdict import (
    CHECK_STATUS,
    FAIL,
    NOT_ASSESSED,
    PASS,
    Judged,
    Verdict,
    case_text,
    judged,
    outer_rail,
    unit_of,
    verdict,
    worst_of,
)
from pneumorail.files import FIGURE_MAX_BYTES, read_bytes

#: the summary columns always shown (those present): validity, faults, the EN 14363 criteria failed
ALWAYS = ("validity", "faults", "en14363_failed")
#: a summary column about the faults (the transient after the first, the air lost) has one of
#: these in its name
FAULT_MARKS = ("fault", "lost")
#: cases per summary table: more go into a further table below (each case is a column)
CASES_PER_TABLE = 8
#: parameters per table of the vehicle and circuit data (the tables sit side by side where they fit)
PARAMETERS_PER_TABLE = 22

STYLE = """
body { font-family: sans-serif; margin: 2em; color: #222; max-width: 1400px; }
h1 { font-size: 1.6em; } h2 { font-size: 1.25em; border-bottom: 1px solid #aaa; margin-top: 2em; }
h3 { font-size: 1.05em; }
table { border-collapse: collapse; margin: 0.5em 0 1em 0; font-size: 0.85em; max-width: 100%; }
th, td { border: 1px solid #bbb; padding: 0.2em 0.5em; text-align: left; vertical-align: top;
         overflow-wrap: break-word; }
th { background: #eee; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
td.pass { background: #d8f0d8; } td.fail { background: #f6c9c9; font-weight: bold; }
td.indicator { background: #fdf0c8; } td.unassessed { background: #e4e4e4; font-weight: bold; }
td.set { background: #fff3c4; font-weight: bold; } td.differs { outline: 2px solid #4a7fc1; }
.verdict { display: inline-block; font-size: 1.6em; font-weight: bold; padding: 0.2em 0.8em;
           border: 2px solid #555; margin: 0.3em 0; }
.verdict.pass { background: #d8f0d8; } .verdict.fail { background: #f6c9c9; }
.verdict.unassessed { background: #e4e4e4; }
.grid { display: flex; flex-wrap: wrap; gap: 0 1.5em; align-items: flex-start; }
figure { margin: 1em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 0.85em; color: #555; } .note { color: #555; font-size: 0.9em; }
"""
#: a status as the tables show it: (text, css class)
SHOWN = {PASS: ("pass", "pass"), FAIL: ("FAIL", "fail"), NOT_ASSESSED: ("not assessed", "unassessed")}
VERDICT_CSS = {"PASS": "pass", "FAIL": "fail", "NOT ASSESSED": "unassessed"}
#: the verdicts, the better first
VERDICTS = ("PASS", "NOT ASSESSED", "FAIL")


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

    @cached_property
    def items(self) -> Dict[str, List[Judged]]:
        """Every value beside its limit, by table (:func:`cosim.results.verdict.judged`)."""
        return judged(self.info, self.summary, self.limits, self.check)

    @property
    def verdict(self) -> Verdict:
        return verdict([i for table in self.items.values() for i in table])


#: the columns of assessment_limits.csv the report reads (:func:`cosim.results.verdict.assessment_items`)
ASSESSMENT_COLUMNS = ("quantity", "value", "limit", "unit", "status", "kind", "source", "valves", "k_W_per_K", "zone",
                      "at")


def read_run(path: Path, allow_incomplete: bool = False) -> RunFolder:
    """An output folder (of ``run``, ``check`` or ``verify``: a verify folder is reported by its
    level-0 run with its verify.json), every file read by the one reader (inside the folder, a
    size limit, UTF-8: :mod:`pneumorail.files`) and checked for the shape pneumorail writes. A
    run still being written or interrupted (an INCOMPLETE marker, a lock, run.json's status) is
    refused unless ``allow_incomplete`` (its verdict is then NOT ASSESSED)."""
    path = label = Path(path)
    verify = None
    if (path / "verify.json").exists() and (path / "level_0" / "run.json").exists():
        verify, path = folder_json(path, "verify.json"), path / "level_0"
    elif path.name.startswith("level_") and (path.parent / "verify.json").exists():
        verify = folder_json(path.parent, "verify.json")
    if holder(path) and not allow_incomplete:
        raise ScenarioError(path, [LOCK], f"a run (process {holder(path)}) is writing into this folder now: report it "
                                          f"when it has finished")
    info = run_info(path)
    why = incomplete(path, info)
    if why and not allow_incomplete:
        raise ScenarioError(path, [INCOMPLETE if (path / INCOMPLETE).exists() else "run.json"],
                            f"not a complete run: {why}; report a finished run, or add --allow-incomplete (its "
                            f"verdict is then NOT ASSESSED)")
    rows = _folder_rows(path, "summary.csv")
    limits = _folder_rows(path, "assessment_limits.csv", ASSESSMENT_COLUMNS)
    check = folder_json(path, "check.json")
    if check is not None:
        _check_shape(path / "check.json", check)
    return RunFolder(path, info, rows, limits, check, verify, sorted(path.glob("*.png")), label.name)


def _folder_rows(path: Path, name: str, needed: Sequence[str] = ()) -> List[Dict[str, str]]:
    """The rows of the table ``name`` of a folder ([] when absent), each with every column of the
    header and the ``needed`` ones among them."""
    file = path / name
    if not file.exists() and not file.is_symlink():
        return []
    rows = read_rows(file)
    for n, row in enumerate(rows, start=2):
        if None in row or None in row.values():
            raise ScenarioError(file, [f"line {n}"], "a row of another length than the header: not the table "
                                                     "pneumorail writes")
    missing = [c for c in needed if rows and c not in rows[0]]
    if missing:
        raise ScenarioError(file, [missing[0]], f"no such column: not the table pneumorail writes (its columns: "
                                                f"{', '.join(needed)})")
    return rows


def _check_shape(file: Path, check: Mapping) -> None:
    """check.json as :meth:`Outcome.verdict` writes it: a list of checks, each a mapping with a
    name, a status and, with a value, its metric and limit."""
    checks = check.get("checks", [])
    if not isinstance(checks, list):
        raise ScenarioError(file, ["checks"], f"expected a list of checks, got {type(checks).__name__}")
    for i, c in enumerate(checks):
        if not isinstance(c, dict):
            raise ScenarioError(file, [f"checks[{i}]"], f"expected a check (a mapping), got {type(c).__name__}")
        for key in ("name", "status", *(("metric", "limit") if "value" in c else ())):
            if key not in c:
                raise ScenarioError(file, [f"checks[{i}]", key], "missing: not the check.json pneumorail writes")
        if c["status"] not in CHECK_STATUS:
            raise ScenarioError(file, [f"checks[{i}]", "status"], f"expected one of {', '.join(CHECK_STATUS)}, "
                                                                   f"got {c['status']!r}")


# ----------------------------------------------------------------------------------- formatting
#: a word this long (a metric's name, a path, a hash) gets places to break (<wbr>), so that no
#: table cell is wider than the page and no short word is broken
LONG_WORD = 16


def _e(value) -> str:
    """Text as HTML: escaped, each long word breakable after ``_ / = . , -`` and every
    :data:`LONG_WORD` characters of a run without them (<wbr>: invisible, not copied)."""
    parts = re.split(rf"(\S{{{LONG_WORD + 1},}})", str(value))
    return "".join(_breakable(p) if i % 2 else html.escape(p) for i, p in enumerate(parts))


def _breakable(word: str) -> str:
    pieces = re.findall(rf"[^_/=.,-]{{1,{LONG_WORD}}}[_/=.,-]*|[_/=.,-]+", word)
    return "<wbr>".join(html.escape(p) for p in pieces)


def _number(text) -> str:
    """A number as the report shows it: 4 significant digits, inf spelled out; text as it is."""
    try:
        v = float(text)
    except (TypeError, ValueError):
        return _e(text)
    if math.isnan(v):
        return "nan"
    return "inf" if math.isinf(v) else f"{v:.4g}"


def _in_unit(unit: str) -> Callable[[float], str]:
    """How a value of ``unit`` is shown: forces in kN, dimensionless ones bare."""
    if unit == "N":
        return lambda v: "nan" if math.isnan(float(v)) else f"{float(v) * 1e-3:.4g} kN"
    return lambda v: _number(v) + ("" if unit in ("1", "") else f" {_e(unit)}")


def _table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """An HTML table (cells wrap to the page); a cell given as (text, css class) gets that class;
    the header is escaped, the cells are HTML already."""
    def cell(c):
        text, css = c if isinstance(c, tuple) else (c, "")
        return f"<td class='{css}'>{text}</td>" if css else f"<td>{text}</td>"
    head = "".join(f"<th>{_e(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(cell(c) for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _chunks(items: Sequence, size: int) -> List[Sequence]:
    return [items[i:i + size] for i in range(0, len(items), size)] or [items]


def _status_cell(item: Judged) -> Tuple[str, str]:
    """A result cell: pass / FAIL / not assessed; an indicator beyond its value is marked, not failed."""
    text, css = SHOWN[item.status]
    if item.status == FAIL and not item.counts:
        return "above (indicator)", "indicator"
    return text, css


def _margin(item: Judged) -> str:
    """How far from its limit, in the value's unit and as a share of the limit."""
    if math.isnan(item.margin):
        return "—"
    share = f" ({100.0 * item.margin / abs(item.limit):.0f} %)" if item.limit else ""
    return f"{_in_unit(item.unit)(item.margin)}{share}"


def _limit(item: Judged) -> str:
    return "—" if math.isnan(item.limit) else f"{_e(item.op)} {_in_unit(item.unit)(item.limit)}"


def _basis(item: Judged) -> str:
    """What a limit rests on, with its formula or origin below."""
    head, _, rest = item.basis.partition(";")
    source = item.source or rest.strip()
    return f"<b>{_e(head)}</b>" + (f"<br><span class='note'>{_e(source)}</span>" if source else "")


# ----------------------------------------------------------------------------------- run facts
def _section(run: RunFolder) -> dict:
    """The run's experiment (its kind's section) as it ran."""
    section = run.info.get("resolved", {}).get(run.info.get("section") or "", {})
    return section if isinstance(section, dict) else {}


#: the facts that tell a run's figures apart: (where, key, how it is shown)
FACTS = (("section", "speed_m_per_s", lambda v: f"{v:g} m/s"),
         ("section", "speeds_m_per_s", lambda v: f"{', '.join(f'{x:g}' for x in v)} m/s"),
         ("section", "radius_m", lambda v: f"R = {v:g} m"), ("section", "cant_rad", lambda v: f"cant {v:g} rad"),
         ("section", "transition_m", lambda v: f"{v:g} m transition"),
         ("info", "twist_per_mille", lambda v: f"twist {v:.3g} per mille"),
         ("info", "yq_lim", lambda v: f"Nadal limit {v:.3g}"),
         ("info", "sum_y_lim_N", lambda v: f"Prud'homme limit {v * 1e-3:.4g} kN"),
         ("info", "irregularity", lambda v: f"irregularity {v}"))
#: the facts of a curve, left out on straight track
CURVE_FACTS = ("cant_rad", "transition_m")


def run_facts(run: RunFolder) -> str:
    """The facts of a run a reader needs beside its figures: speed, radius, cant, outer rail,
    limits (each run its own)."""
    section = _section(run)
    sources = {"section": section, "info": run.info}
    curved = section.get("radius_m") is not None            # cant and transition belong to a curve
    out = []
    for where, key, shown in FACTS:
        value = sources[where].get(key)
        if value is None or value == "inf" or (key in CURVE_FACTS and not curved):
            continue
        try:
            out.append(shown(value))
        except (TypeError, ValueError):
            out.append(f"{key} {value}")
    if "speeds_m_per_s" in section and not curved:
        out.append("straight track")
    outer = _outer_text(run.info)
    if outer:
        out.append(f"outer rail {outer}")
    faults = _faults(run.info)
    if faults != "none":
        out.append(f"faults: {faults}")
    return ", ".join(out)


def _outer_text(info: Mapping) -> str:
    """``right (wheels 1R-4R)``: the outer rail of the run's curve; "" without a curve."""
    outer = outer_rail(info)
    return f"{outer} (wheels 1{outer[0].upper()}-4{outer[0].upper()})" if outer else ""


def _faults(info: Mapping) -> str:
    """The run's faults in words (run.json's ``faults``; an older one's scenario settings)."""
    if "faults" in info:
        return "; ".join(info["faults"]) or "none"
    given = (info.get("settings") or {}).get("faults") or []
    return "; ".join(", ".join(f"{k} {v}" for k, v in f.items()) if isinstance(f, dict) else str(f)
                     for f in given) or "none"


# ----------------------------------------------------------------------------------- sections
def _verdicts(runs: Sequence[RunFolder]) -> str:
    """The overall verdict (the worst of the runs') and, per run, what decides it."""
    found = [(r, r.verdict) for r in runs]
    overall = max((v.status for _, v in found), key=VERDICTS.index)
    rows = [[_e(run.name), (f"<b>{v.status}</b>", f"{VERDICT_CSS[v.status]} overall"), *_decided(v),
             _e(_tally(run, v))] for run, v in found]
    several = f" ({sum(v.status == overall for _, v in found)} of {len(runs)} runs)" if len(runs) > 1 else ""
    return (f"<div class='verdict {VERDICT_CSS[overall]}'>{overall}{several}</div>"
            + _table(["run", "verdict", "worst criterion or check", "value", "limit", "margin", "limit basis",
                      "where", "assessed"], rows)
            + "<p class='note'>From the EN 14363 assessment and the checks below (the same values): FAIL if a "
              "criterion or check fails, NOT ASSESSED if nothing was assessed or a value is missing, PASS only when "
              "every one holds; decided by the failing one, else the one closest to its limit. Indicators do not "
              "count.</p>")


def _decided(v: Verdict) -> List[str]:
    """The cells of what decides a verdict: name, value, limit, margin, basis, where (and why)."""
    w = v.worst
    if w is None:
        return ["—"] * 5 + [_e(v.reason)]
    where = "; ".join(filter(None, (v.reason, w.case, w.place, w.message)))
    return [_e(w.name), _value(w), _limit(w), _margin(w), _basis(w), _e(where or "—")]


def _value(item: Judged) -> str:
    return "—" if math.isnan(item.value) else _in_unit(item.unit)(item.value)


def _tally(run: RunFolder, v: Verdict) -> str:
    """How many values were judged, from where, how many fail; indicators beyond their value."""
    items = run.items
    criteria = sum(i.counts for i in items["EN 14363"])
    cases = len({i.case for i in items["EN 14363"]})
    parts = [f"EN 14363: {criteria} criteria over {cases} case(s)" if criteria else "",
             f"checks: {len(items['check'])}" if items["check"] else "",
             f"run: {len(items['run'])}" if items["run"] else ""]
    above = sum(1 for i in items["EN 14363"] if not i.counts and i.status == FAIL)
    return "; ".join(filter(None, [*parts, f"{v.failed} fail" if v.counted else "",
                                   f"{above} indicator(s) above their value" if above else ""])) or "nothing"


def _what_ran(runs: Sequence[RunFolder]) -> str:
    def setting(run, *keys):
        node = run.info.get("settings", {})
        for k in keys:
            node = node.get(k, {}) if isinstance(node, dict) else {}
        return node if node != {} else "—"

    def experiment(run):
        return ", ".join(f"{k} = {v}" for k, v in _section(run).items()
                         if not isinstance(v, dict) and v is not None) or "—"

    def vehicle(run):
        groups = {g["group"]: g for g in run.info.get("parameters") or []}
        if "vehicle" not in groups:
            return setting(run, "vehicle")
        g = groups["vehicle"]
        return g["base"] + "".join(f"; {k} = {g['values'][k]} ({how})" for k, how in g["set"].items())

    facts = [
        ("scenario", lambda r: r.info.get("name")), ("description", lambda r: setting(r, "description")),
        ("kind", lambda r: r.info.get("kind")), ("scenario file", lambda r: r.info.get("scenario_file")),
        ("vehicle", vehicle),
        ("circuit", lambda r: f"{setting(r, 'circuit', 'layout')}, preset {setting(r, 'circuit', 'preset')}, "
                              f"valves {setting(r, 'circuit', 'valves')}"),
        ("faults", lambda r: _faults(r.info)),
        ("set on the command line", lambda r: ", ".join(r.info.get("overrides") or []) or "nothing"),
        ("track", lambda r: r.info.get("resolved", {}).get("track", {}).get("model", "—")),
        ("experiment", experiment),
        ("outer rail", lambda r: _outer_text(r.info) or "no curve"),
        ("k [W/K]", lambda r: ", ".join(map(str, r.info.get("k_W_per_K", [])))),
        ("test zones", lambda r: ", ".join(r.info.get("zones", [])) or "—"),
        ("status", lambda r: r.info.get("status")), ("wall time [s]", lambda r: _number(r.info.get("wall_time_s"))),
    ]
    return _table(["", *(r.name for r in runs)], [[_e(name), *(_e(fn(r)) for r in runs)] for name, fn in facts])


def _parameter(value) -> str:
    if isinstance(value, list):
        return ", ".join(_parameter(v) for v in value)
    if isinstance(value, float):
        return f"{value:.6g}"
    return _e(value)


def _parameters(runs: Sequence[RunFolder]) -> str:
    """Per group (vehicle, each part of the circuit) every value each run used, the values the
    scenario or the command line set marked as such."""
    per_run = [{g["group"]: g for g in r.info.get("parameters") or []} for r in runs]
    groups = list(dict.fromkeys(name for groups in per_run for name in groups))
    if not groups:
        return ("<p class='note'>Not recorded: these runs' run.json predates the parameter table (run.json's "
                "resolved values hold what they used).</p>")
    tables = []
    for name in groups:
        keys = list(dict.fromkeys(k for groups in per_run if name in groups for k in groups[name]["values"]))
        header = [f"{r.name}: {groups[name]['base']}" if name in groups else f"{r.name}: not recorded"
                  for r, groups in zip(runs, per_run)]
        parts = _chunks(keys, PARAMETERS_PER_TABLE)
        for i, part in enumerate(parts):
            title = name + (f" ({i + 1}/{len(parts)})" if len(parts) > 1 else "")
            rows = [_parameter_row(k, [groups.get(name) for groups in per_run]) for k in part]
            tables.append(_table([title, *header], rows))
    return (f"<div class='grid'>{''.join(tables)}</div><p class='note'>Each table heads its values with what they "
            f"come from (a preset, a parameter file, the defaults); a value the scenario or --set put over it is "
            f"marked (scenario) or (--set)" + (", a value that differs between the runs framed" if len(runs) > 1
                                               else "") + ".</p>")


def _parameter_row(key: str, groups: Sequence[Optional[Mapping]]) -> list:
    """A parameter's row: its name, its value in each run (marked where the runs differ)."""
    cells = [_parameter_cell(g, key) for g in groups]
    values = {json.dumps(g["values"].get(key)) for g in groups if g is not None}
    if len(values) > 1:
        cells = [(c[0], f"{c[1]} differs") if isinstance(c, tuple) else (c, "differs") for c in cells]
    return [_e(key), *cells]


def _parameter_cell(group: Optional[Mapping], key: str):
    if group is None:
        return "not recorded"
    if key not in group["values"]:
        return "—"
    text = _parameter(group["values"][key])
    how = group["set"].get(key)
    return (f"{text} ({_e(how)})", "set") if how else text


def _assessment(run: RunFolder) -> str:
    """Per quantity and zone the worst case and wheel of the run, beside its own limit, with the
    limit's basis and the margin."""
    items = run.items["EN 14363"]
    if not items:
        return ""
    keys = list(dict.fromkeys((i.name, i.zone) for i in items))
    rows = []
    for quantity, zone in keys:
        w = worst_of([i for i in items if (i.name, i.zone) == (quantity, zone)])
        rows.append([_e(quantity), _e(zone), "criterion" if w.counts else "indicator", _limit(w), _basis(w),
                     (_value(w), "num"), _margin(w), _status_cell(w), _e(w.case), _e(w.where)])
    rail = f" Outer rail in the curve: {_outer_text(run.info)}." if outer_rail(run.info) else ""
    return (f"<h3>{_e(run.name)}</h3>"
            + _table(["quantity", "zone", "type", "limit", "limit basis", "worst value", "margin", "result",
                      "worst case", "where"], rows)
            + f"<p class='note'>2 m sliding means every 0.5 m of track, per zone; of each quantity and zone the "
              f"worst case and wheel (wheelset) of {_e(run.name)}.{_e(rail)}</p>")


def _checks(run: RunFolder) -> str:
    """The run's checks (check.json) and what run.json says against the run itself."""
    items = run.items["check"] + run.items["run"]
    if not items:
        return ""
    rows = [[_e(i.name), (_value(i), "num"), _limit(i), _margin(i), _status_cell(i), _basis(i),
             _e("; ".join(filter(None, (i.where, i.message))) or "—")] for i in items]
    sources = [name for name, found in (("check.json", run.check), ("run.json", run.items["run"])) if found]
    return (f"<h3>{_e(run.name)}: checks (from {' and '.join(sources)})</h3>"
            + _table(["check", "value", "limit", "margin", "result", "limit basis", "at"], rows))


def _case_header(row: Mapping[str, str], columns: Sequence[str]) -> str:
    """A case as a column head: its identifying values (speed, valves, k, airspring ...)."""
    shown = {"valves": lambda v: f"valves {'on' if v == 'True' else 'off'}", "k_W_per_K": lambda v: f"k = {v} W/K",
             "speed_m_per_s": lambda v: f"{_number(v)} m/s"}
    return ", ".join(shown.get(c, lambda v, c=c: f"{c} {v}")(row[c]) for c in columns)


def case_columns(run: RunFolder) -> List[str]:
    """The summary columns that tell the cases apart: valves and k, and any further column needed
    where two rows would otherwise look alike (the airspring model, the speed ...)."""
    rows = run.summary
    named = [c for c in ("valves", "k_W_per_K") if c in rows[0]]
    return named + _distinguishing(rows, named)


def _distinguishing(rows: Sequence[Mapping[str, str]], columns: Sequence[str]) -> List[str]:
    """Columns to add, each one that differs between the rows, text ones first, then in the
    summary's order (a kind writes what names its case first: the speed), until no two rows look
    alike over ``columns`` + these."""
    chosen: List[str] = []
    candidates = sorted((c for c in rows[0] if c not in columns),
                        key=lambda c: not _is_text(rows[0][c]))
    for c in candidates:
        keys = [tuple(r[x] for x in (*columns, *chosen)) for r in rows]
        if len(set(keys)) == len(rows):
            break
        if len({r[c] for r in rows}) > 1:
            chosen.append(c)
    return chosen


def _is_text(cell: str) -> bool:
    """A summary cell that is not a number (nan and inf are numbers)."""
    try:
        float(cell)
        return False
    except ValueError:
        return True


def summary_columns(run: RunFolder, cases: Sequence[str]) -> List[str]:
    """The rows of the summary table: the columns the kind shows (run.json's ``summary_columns``),
    the run's metrics, every text column whose values differ between the cases (e.g. which method
    gave the critical speed), the faults' transient, validity."""
    first = run.summary[0]
    shown = run.info.get("summary_columns") or ()
    texts = [c for c in first if _is_text(first[c]) and len({r[c] for r in run.summary}) > 1]
    faults = [c for c in first if any(mark in c for mark in FAULT_MARKS)]
    wanted = [*shown, *run.info.get("metrics", {}), *texts, *faults, *ALWAYS]
    return [c for c in dict.fromkeys(wanted) if c in first and c not in cases]


def _summary_table(run: RunFolder, columns: Sequence[str], cases: Sequence[str]) -> str:
    """The summary transposed: a row per column, a column per case (in tables of at most
    :data:`CASES_PER_TABLE` cases)."""
    out = []
    for part in _chunks(run.summary, CASES_PER_TABLE):
        rows = [[_e(c), *((_in_unit(unit_of(c))(r[c]) if unit_of(c) == "N" else _number(r[c]), "num")
                          if not _is_text(r[c]) else _e(r[c]) for r in part)] for c in columns]
        out.append(_table(["", *(_case_header(r, cases) for r in part)], rows))
    return "".join(out)


def _summary(run: RunFolder) -> str:
    if not run.summary:
        return f"<h3>{_e(run.name)}</h3><p class='note'>No summary.</p>"
    cases = case_columns(run)
    every = [c for c in run.summary[0] if c not in cases]
    return (f"<h3>{_e(run.name)}</h3>" + _summary_table(run, summary_columns(run, cases), cases)
            + f"<details><summary class='note'>All {len(every)} columns of summary.csv</summary>"
              f"{_summary_table(run, every, cases)}</details>")


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


def flags(run: RunFolder) -> List[str]:
    """What the run says about itself: how it ended, every validity flag of its cases (allowed
    ones too), every warning of run.json; each line says what was looked at when it found nothing."""
    info, rows = run.info, run.summary
    out = []
    if info.get("diverged"):
        out.append(f"diverged: {info['diverged']}")
    if info.get("status", "complete") != "complete":
        out.append(f"status {info['status']}: the results end where the run stopped")
    allowed = (info.get("settings") or {}).get("allow") or ()
    flagged = [(case_text(r.get("valves", ""), r.get("k_W_per_K", "")), f) for r in rows
               for f in str(r.get("validity", "ok")).split(";") if f not in ("ok", "")]
    out += [f"outside the model's validity ({flag}: {FLAGS.get(flag, flag)}): {case}"
            + (" (allowed by the scenario)" if flag in allowed else "") for case, flag in flagged]
    if rows and "validity" not in rows[0]:
        out.append("validity flags not recorded in summary.csv")
    elif rows and not flagged:
        out.append(f"validity: all {len(rows)} cases within the models' range ({', '.join(FLAGS)} checked)")
    warnings = list(info.get("warnings", []))
    out += [f"warning: {w}" for w in warnings] or ["warnings: none recorded in run.json"]
    return out


def _flags(run: RunFolder) -> str:
    return f"<h3>{_e(run.name)}</h3><ul>{''.join(f'<li>{_e(i)}</li>' for i in flags(run))}</ul>"


def _figures(run: RunFolder) -> str:
    """The run's figures, each captioned with its title and the run's own facts."""
    titles = run.info.get("figures") or {}
    facts = run_facts(run)
    out = []
    for png in run.figures:
        data = base64.b64encode(read_bytes(png, "figure (PNG)", FIGURE_MAX_BYTES, within=run.path,
                                           error=ScenarioError)).decode("ascii")
        title = " ".join(str(titles.get(png.name, "")).split())
        caption = f"{run.name}" + (f" ({facts})" if facts else "") + f": {title or png.stem} [{png.name}]"
        out.append(f"<figure><img alt='{html.escape(png.stem, quote=True)}' src='data:image/png;base64,{data}'>"
                   f"<figcaption>{_e(caption)}</figcaption></figure>")
    head = f"<h3>{_e(run.name)}</h3>" + (f"<p class='note'>{_e(facts)}</p>" if facts else "")
    return head + ("".join(out) or "<p class='note'>No figures.</p>")


def _provenance(runs: Sequence[RunFolder]) -> str:
    def files(r):
        return "<br>".join(f"{_e(k)}: {_e(v)}" for k, v in r.info.get("files_sha256", {}).items()) or "—"
    facts = [("command", lambda r: _e(r.info.get("command", "—"))),
             ("finished (UTC)", lambda r: _e(r.info.get("finished_utc", "—"))),
             ("source", lambda r: _e(json.dumps(r.info.get("source") or "not a git checkout"))),
             ("versions", lambda r: _e(", ".join(f"{k} {v}" for k, v in r.info.get("versions", {}).items()) or "—")),
             ("files (sha256)", files),
             ("folder", lambda r: _e(r.path.resolve()))]
    return _table(["", *(r.name for r in runs)], [[_e(name), *(fn(r) for r in runs)] for name, fn in facts])


def render(runs: Sequence[RunFolder]) -> str:
    """The report's HTML."""
    names = ", ".join(r.name for r in runs)
    sections = [
        ("Verdict", _verdicts(runs)),
        ("What ran", _what_ran(runs)),
        ("Vehicle and circuit", _parameters(runs)),
        ("EN 14363 assessment", "".join(_assessment(r) for r in runs)
         or "<p class='note'>No EN 14363 assessment in these runs (it is made for curve runs, kind curve_entry).</p>"),
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


def write_report(run_dirs: Sequence[Path], out_file: Optional[Path] = None, allow_incomplete: bool = False) -> Path:
    """Write the report of ``run_dirs`` to ``out_file`` (default: ``report.html`` in the first
    run's folder); returns its path. Folders are read by :func:`read_run`."""
    runs = [read_run(Path(d), allow_incomplete) for d in run_dirs]
    out_file = Path(out_file) if out_file else runs[0].path / "report.html"
    try:
        page = render(runs)
    except ScenarioError:
        raise
    except (KeyError, TypeError, ValueError, AttributeError, IndexError) as exc:
        # a value of another type deep in run.json (the folder's files were edited, or written
        # by another version): the folders are named, not a traceback
        raise ScenarioError(", ".join(str(r.path) for r in runs), [],
                            f"the files do not have the shape pneumorail writes ({type(exc).__name__}: {exc})") from None
    with atomic_write(out_file) as fh:
        fh.write(page)
    return out_file
