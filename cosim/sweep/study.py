"""Parameter sweeps: one scenario run for every combination of a grid of values (``pneumorail
sweep``, see docs/sweeps.md).

A sweep is a base scenario, base overrides (``--set``, ``--k``), a *grid* (key path -> values;
the cases are its Cartesian product, first key slowest) and optionally a *zip* (keys whose
value lists, of equal length, vary together: one more factor of the product, innermost). Keys
are the scenario key paths ``--set`` accepts (``curve.speed_m_per_s``); ``k_W_per_K`` is allowed
(a number or a list of numbers per case). Every case is validated before anything runs.

Each case is keyed by a hash of its resolved scenario -- the content of every file it reads, its sorted
overrides and its k list -- and runs with ``run_scenario`` into ``OUT/cases/<key>/`` (its own
summary.csv, run.json, time series and plots). When it has finished, ``done.json`` (its summary
rows, every checkable metric of each of its k / valve cases -- values, per wheel, per test zone --,
status) is written atomically: a rerun skips every case with a marker and
runs the others, so an interrupted sweep resumes where it stopped. A case that diverges is
finished (status ``diverged``, the diagnosis kept); a case that raises or whose worker dies gets
``failed.json`` instead and is retried by the next run.

Outputs: ``sweep.csv`` (one row per case and summary row, the grid values as columns, then every
summary metric, ``status`` and ``diagnosis``), ``sweep.json`` (the definition and each case's
key and status), ``sweep.nc`` (xarray) and plots of the headline metrics; with ``--check``,
``check.json``: the base scenario's checks judged in every case by the same path as
``pneumorail check`` (:func:`cosim.limits.checks.evaluate`: pass, fail, or error when a value is
missing, saying why).
"""
from __future__ import annotations

import dataclasses
import functools
import hashlib
import itertools
import json
import math
import shutil
import sys
import time
import traceback
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple

import yaml

from cosim.errors import ScenarioError
from cosim.kinds import KINDS
from cosim.limits.checks import ERROR, FAIL, PASS, CaseMetrics, CheckResult, overall
from cosim.results.io import Progress, atomic_write, csv_rows, jsonable, write_rows
from cosim.results.outcome import Outcome
from cosim.results.plots import pyplot
from cosim.scenario.schema import folder_name, k_label, k_values

DONE, FAILED, CHECK = "done.json", "failed.json", "check.json"
#: what a case's done.json holds: 2, every field of each k / valve case's checkable metrics
#: (:class:`~cosim.limits.checks.CaseMetrics`); a record without ``format`` (1) kept the plain and
#: per-wheel metrics only, not the per-zone ones of the EN 14363 assessment
RECORD_FORMAT = 2
K_KEY = "k_W_per_K"
#: the most cases a sweep expands (counted from the axes before anything is expanded): a
#: hundred thousand cases of even a second each are more than a day on a workstation
MAX_CASES = 100_000
#: identity columns of a summary row (besides the grid values)
SWEEP_KEYS = ("scenario", "grid", "zip", "set", "k_W_per_K", "name")


# ------------------------------------------------------------------------------ definition
@dataclass
class SweepSpec:
    """What to sweep. ``source``: the file errors are reported against (the sweep file, or the
    scenario for a command-line sweep); ``where``: how grid keys are named there."""

    scenario_file: Path
    grid: Dict[str, List[Any]] = field(default_factory=dict)
    zip: Dict[str, List[Any]] = field(default_factory=dict)
    base: Dict[str, Any] = field(default_factory=dict)        # --set / set:
    base_k: Optional[Tuple[float, ...]] = None                 # --k / k_W_per_K:
    name: Optional[str] = None
    source: Optional[Path] = None
    where: Tuple[str, str] = ("--grid", "--zip")
    origin: Dict[str, str] = field(default_factory=dict)      # key -> how it was given, for errors

    def label(self, key: str) -> str:
        return self.origin.get(key) or (self.where[1] if key in self.zip and key not in self.grid else self.where[0])

    def path(self, key: str) -> List[str]:
        """The key path of a grid or zip key in errors: ``--grid KEY`` or ``sweep.grid.KEY``."""
        label = self.label(key)
        return [f"{label} {key}"] if label.startswith("--") else [label, key]


@dataclass(frozen=True)
class Case:
    index: int
    values: Tuple[Tuple[str, Any], ...]          # (grid or zip key, value), in column order
    overrides: Tuple[Tuple[str, Any], ...]       # base + case (k_W_per_K apart), in application order
    k: Optional[Tuple[float, ...]]               # k override (None: the scenario's, or the base --k)
    key: str = ""

    @property
    def label(self) -> str:
        return ", ".join(f"{k}={value_text(v)}" for k, v in self.values) or "(base)"

    def override_strings(self) -> List[str]:
        return [f"{k}={value_text(v)}" for k, v in self.overrides]


def value_text(value: Any) -> str:
    """A value as YAML flow text that reads back as the same value (``8``, ``.inf``, ``[1R, 2R]``)."""
    text = yaml.safe_dump(value, default_flow_style=True, width=1 << 30).strip()
    if text.endswith("\n..."):
        text = text[: -len("\n...")]
    return text


def split_values(text: str) -> List[str]:
    """``8,10,[1R, 2R]`` -> ['8', '10', '[1R, 2R]']: commas inside brackets or quotes stay."""
    out, depth, quote, start = [], 0, None, 0
    for i, ch in enumerate(text):
        if quote:
            quote = None if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        elif ch == "," and depth == 0:
            out.append(text[start:i])
            start = i + 1
    out.append(text[start:])
    return [item.strip() for item in out]


def parse_assignment(item: str, file, option: str, many: bool) -> Tuple[str, Any]:
    """``KEY=V1,V2`` (many) or ``KEY=VALUE``, values parsed as YAML."""
    if "=" not in item:
        raise ScenarioError(file, [option], f"expected key.path={'V1,V2,...' if many else 'value'}, got {item!r}")
    key, text = (s.strip() for s in item.split("=", 1))
    _check_key(key, file, [option])
    from cosim.scenario.yaml_input import parse_yaml
    where = [f"{option} {key}"]
    if many:
        items = split_values(text)
        if any(t == "" for t in items):
            raise ScenarioError(file, where, f"empty value in {text!r}")
        return key, [parse_yaml(t, file, where) for t in items]
    return key, parse_yaml(text, file, where)


def _check_key(key: str, file, path) -> None:
    if not key or any(not part for part in key.split(".")):
        raise ScenarioError(file, path, f"expected a key path like curve.speed_m_per_s, got {key!r}")


def load_sweep_file(path: Path) -> SweepSpec:
    """A sweep file: a ``sweep:`` section (its keys may also stand at the top level) with
    ``scenario`` (relative to the sweep file), ``grid``, optional ``zip``, ``set`` (base
    overrides: a mapping of key paths to values) and ``k_W_per_K`` (base k values)."""
    from cosim.load import load_yaml
    path = Path(path)
    data, _ = load_yaml(path)
    if not isinstance(data, dict):
        raise ScenarioError(path, [], f"expected a mapping with a 'sweep:' section, got {type(data).__name__}")
    prefix: List[str] = []
    if "sweep" in data:
        if set(data) - {"sweep"}:
            raise ScenarioError(path, [sorted(set(data) - {"sweep"})[0]], "unknown key next to the sweep: section")
        data, prefix = data["sweep"], ["sweep"]
        if not isinstance(data, dict):
            raise ScenarioError(path, prefix, f"expected a mapping, got {type(data).__name__}")
    for key in data:
        if key not in SWEEP_KEYS:
            raise ScenarioError(path, [*prefix, str(key)], f"unknown key (allowed: {', '.join(SWEEP_KEYS)})")
    scenario = data.get("scenario")
    if not isinstance(scenario, str):
        raise ScenarioError(path, [*prefix, "scenario"], "expected the scenario file (relative to this file)")
    target = path.parent / scenario
    if not target.is_file():
        raise ScenarioError(path, [*prefix, "scenario"], f"the scenario file {str(target)!r} does not exist or is not a file")
    if target.resolve() == path.resolve():
        raise ScenarioError(path, [*prefix, "scenario"], "names this sweep file itself; expected the scenario it varies")
    name = folder_name(data.get("name", path.stem), path, [*prefix, "name"])
    spec = SweepSpec(target, name=name, source=path,
                     where=(".".join([*prefix, "grid"]), ".".join([*prefix, "zip"])))
    for section, target in (("grid", spec.grid), ("zip", spec.zip)):
        value = data.get(section) or {}
        if not isinstance(value, dict):
            raise ScenarioError(path, [*prefix, section], f"expected a mapping key.path: [values], got {type(value).__name__}")
        for key, values in value.items():
            _check_key(str(key), path, [*prefix, section])
            if not isinstance(values, list) or not values:
                raise ScenarioError(path, [*prefix, section, str(key)], f"expected a non-empty list of values, got {values!r}")
            target[str(key)] = values
    base = data.get("set") or {}
    if isinstance(base, list):                 # ["key=value", ...] as on the command line
        base = dict(parse_assignment(str(item), path, ".".join([*prefix, f"set[{i}]"]), many=False)
                    for i, item in enumerate(base))
    if not isinstance(base, dict):
        raise ScenarioError(path, [*prefix, "set"], f"expected a mapping key.path: value, got {type(base).__name__}")
    spec.base = {str(k): v for k, v in base.items()}
    if K_KEY in data:
        spec.base_k = k_values(data[K_KEY], path, [*prefix, K_KEY])
    return spec


def is_sweep_file(path: Path) -> bool:
    """Whether ``path`` holds a sweep (a ``sweep:`` section, or ``scenario:`` + ``grid:``)."""
    from cosim.load import load_yaml
    try:
        data, _ = load_yaml(Path(path))
    except ScenarioError:                   # unreadable, not text, hostile YAML: the caller says why
        return False
    return isinstance(data, dict) and ("sweep" in data or ("scenario" in data and "kind" not in data))


# ------------------------------------------------------------------------------ cases
def expand(spec: SweepSpec) -> List[Case]:
    """The cases: the product of the grid's values (first key slowest), times the zip (innermost)."""
    file = spec.source or spec.scenario_file
    gw, zw = spec.where
    for key, values in spec.grid.items():
        if key in spec.zip:
            raise ScenarioError(file, spec.path(key), "is also a grid key: give it in one of grid and zip")
        # k sets are sets: [0, inf] and [inf, 0] run the same cases
        _no_duplicates([_as_set(v) if key == K_KEY else v for v in values], file, spec.path(key))
    lengths = {k: len(v) for k, v in spec.zip.items()}
    count = math.prod([len(v) for v in spec.grid.values()] + [max(lengths.values(), default=1)])
    if count > MAX_CASES:
        axes = " x ".join([str(len(v)) for v in spec.grid.values()] + ([str(max(lengths.values()))] if lengths else []))
        raise ScenarioError(file, [gw], f"{axes} = {count} cases, more than a sweep takes ({MAX_CASES}); split it")
    if len(set(lengths.values())) > 1:
        raise ScenarioError(file, [zw], "the zip keys vary together and need lists of equal length, got "
                                        + ", ".join(f"{k}: {n}" for k, n in lengths.items()))
    if spec.zip:
        _no_duplicates(list(zip(*spec.zip.values())), file, [zw])
    for key, value in spec.base.items():
        if key in spec.grid or key in spec.zip:
            raise ScenarioError(file, spec.path(key), "is also a base override (--set/set:)")
    factors = [[((key, v),) for v in values] for key, values in spec.grid.items()]
    if spec.zip:
        factors.append([tuple((key, values[i]) for key, values in spec.zip.items())
                        for i in range(next(iter(lengths.values())))])
    cases = []
    for index, combo in enumerate(itertools.product(*factors)):
        values = tuple(pair for group in combo for pair in group)
        k = spec.base_k
        overrides = list(spec.base.items())
        for key, value in values:
            if key == K_KEY:
                k = k_values(value, file, spec.path(K_KEY))
            else:
                overrides.append((key, value))
        cases.append(Case(index, values, tuple(overrides), k))
    return cases


def _as_set(value):
    """A k list as the set it stands for (order and repetition do not change the cases)."""
    try:
        return tuple(sorted(set(value))) if isinstance(value, list) else value
    except TypeError:                        # not numbers: k_values says what is wrong
        return value


def _no_duplicates(values, file, path) -> None:
    seen = []
    for v in values:
        if v in seen:
            raise ScenarioError(file, path, f"value {value_text(v)} given twice")
        seen.append(v)


def case_key(files_sha256, overrides: Iterable[Tuple[str, Any]], k: Sequence[float]) -> str:
    """Stable identity of a case: the content of every file the scenario reads (the scenario,
    its vehicle parameter file), its sorted overrides, its k list. Overrides of ``checks`` are
    left out: they change what is checked, not what is computed."""
    material = json.dumps({"files_sha256": sorted(sha for _, sha in files_sha256),
                           "overrides": sorted(f"{key}={value_text(v)}" for key, v in overrides
                                               if key.split(".")[0] != "checks"),
                           "k_W_per_K": [k_label(x) for x in k]}, sort_keys=True)
    return hashlib.sha256(material.encode()).hexdigest()[:16]


@dataclass
class Prepared:
    spec: SweepSpec
    base: Any                               # the base scenario (validated)
    cases: List[Case]
    scenarios: Dict[str, Any]               # case key -> validated Scenario
    check: bool = False                     # judge the base scenario's checks: in every case (check.json)


def prepare(spec: SweepSpec, check: bool = False) -> Prepared:
    """Expand and validate every case (``load_scenario``) before anything runs; bad input is a
    :class:`ScenarioError` naming the file and the key path."""
    from cosim.load import load_scenario
    from cosim.scenario.checks import checks_hint
    if not spec.grid and not spec.zip:
        raise ScenarioError(spec.source or spec.scenario_file, [spec.where[0]],
                            "nothing to sweep: give at least one grid key (KEY=V1,V2,...)")
    base_strings = [f"{k}={value_text(v)}" for k, v in spec.base.items()]
    base = load_scenario(spec.scenario_file, base_strings, spec.base_k)
    if check and not base.checks:
        raise ScenarioError(base.file, ["checks"], f"no checks to evaluate in the sweep's cases: "
                                                   f"{checks_hint(KINDS[base.kind])}")
    cases = expand(spec)
    out, scenarios = [], {}
    for case in cases:
        try:
            scenario = load_scenario(spec.scenario_file, case.override_strings(), case.k)
        except ScenarioError as exc:
            key, value = _blame(exc, case)
            source = spec.source or spec.scenario_file
            inner = f"{exc.path}: {exc.reason}" if Path(exc.file) == Path(source) else str(exc)
            raise ScenarioError(source, spec.path(key), f"{key}={value_text(value)} is not valid ({inner})") from None
        key = case_key(scenario.files_sha256, case.overrides, scenario.k_W_per_K)
        if key in scenarios:
            raise ScenarioError(spec.source or spec.scenario_file, [spec.where[0]],
                                f"two cases are the same scenario ({case.label})")
        scenarios[key] = _one_process(scenario)
        out.append(dataclasses.replace(case, key=key))
    return Prepared(spec, base, out, scenarios, check)


def _blame(exc: ScenarioError, case: Case) -> Tuple[str, Any]:
    """The case's grid/zip entry an error is about (the first whose key path meets the error's)."""
    for key, value in case.values:
        if exc.path == key or exc.path.startswith(key + ".") or exc.path.startswith(key + "[") \
                or key.startswith(exc.path + "."):
            return key, value
    return case.values[0] if case.values else ("(base)", None)


def _one_process(scenario):
    """Cases are the unit of parallelism: each car scenario runs its k values in one process."""
    if KINDS[scenario.kind].car and scenario.solver.jobs != 1:
        scenario = dataclasses.replace(scenario, solver=dataclasses.replace(scenario.solver, jobs=1))
    return scenario


# ------------------------------------------------------------------------------ one case
def _run_scenario(scenario, out_dir: Path):
    """Indirection for tests (a forked worker sees a monkeypatched replacement). A case's
    warnings go to its run.json (and its rows' validity column), not between the sweep's
    progress lines."""
    import logging

    from cosim.runner import run_scenario
    log = logging.getLogger("pneumorail")
    was = log.disabled
    log.disabled = True
    try:
        return run_scenario(scenario, out_dir, Progress(scenario.name, quiet=True))
    finally:
        log.disabled = was


def run_case(scenario, case_dir: str, record: Dict[str, Any]) -> Dict[str, Any]:
    """Run one case into ``case_dir`` (module level: runs in worker processes). Returns its record
    (also written as done.json, or failed.json when it raised): status ``ok``/``diverged``/
    ``failed``, diagnosis, summary rows (strings, exactly as in its summary.csv) and the metrics
    its checks are evaluated on."""
    folder = Path(case_dir)
    if folder.exists():                     # leftovers of an attempt that did not finish
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    t0 = time.perf_counter()
    try:
        outcome = _run_scenario(scenario, folder)
        rows = csv_rows(outcome.rows)       # as its summary.csv holds them
    except Exception as exc:                # noqa: BLE001 -- recorded; the sweep goes on
        result = {**record, "status": "failed", "diagnosis": f"{type(exc).__name__}: {exc}".strip(),
                  "traceback": traceback.format_exc(), "rows": [], "metrics": [],
                  "wall_time_s": round(time.perf_counter() - t0, 3)}
        write_json_atomic(folder / FAILED, result)
        return result
    result = {**record, "format": RECORD_FORMAT, "status": "diverged" if outcome.diverged else "ok",
              "diagnosis": outcome.diverged or "", "rows": rows, "metrics": [metrics_json(c) for c in outcome.cases],
              "wall_time_s": round(time.perf_counter() - t0, 3)}
    write_json_atomic(folder / DONE, result)      # last: the case counts as finished from here
    return result


def write_json_atomic(path: Path, data: Mapping[str, Any]) -> None:
    """``data`` as JSON, written whole and on disk before it appears (a case's marker)."""
    with atomic_write(path, durable=True) as fh:
        json.dump(data, fh, indent=1)


def metrics_json(case: CaseMetrics) -> Dict[str, Any]:
    """Every field of a case's :class:`~cosim.limits.checks.CaseMetrics` as strict JSON (numbers
    that are not finite as the text ``nan``, ``inf``): whatever a check can name is kept."""
    return jsonable(dataclasses.asdict(case))


def metrics_from_json(item: Mapping[str, Any]) -> CaseMetrics:
    """The :class:`~cosim.limits.checks.CaseMetrics` of :func:`metrics_json` (or of a format-1
    record, without its per-zone metrics)."""
    return CaseMetrics(**{name: _number_tree(value) for name, value in item.items()})


def _number_tree(value):
    """JSON numbers (and nan/inf as text) back to floats, through nested mappings; booleans stay."""
    if isinstance(value, Mapping):
        return {key: _number_tree(v) for key, v in value.items()}
    return value if isinstance(value, bool) else float(value)


def case_verdict(scenario, record: Optional[Mapping[str, Any]], folder: str) -> Dict[str, Any]:
    """The verdict of ``pneumorail check`` (:meth:`~cosim.results.outcome.Outcome.verdict`: status,
    and an item per check, validity flag and divergence) for one case of a sweep, from its record
    (None: not run). A case that failed or did not run has no value for any check (errors saying
    so); a check a format-1 record cannot answer says how to recompute the case (``folder``)."""
    status = record["status"] if record else "pending"
    if status in ("ok", "diverged"):
        outcome = Outcome(scenario=scenario, rows=record["rows"], cases=[metrics_from_json(m) for m in record["metrics"]],
                          diagnoses=[record["diagnosis"]] if status == "diverged" else [])
        items = outcome.verdict()["checks"]
        if record.get("format", 1) < RECORD_FORMAT:
            items = [_recompute_hint(item, folder) for item in items]
    else:
        why = f"the case failed ({record['diagnosis']})" if status == "failed" else "the case has not run"
        outcome = Outcome(scenario=scenario, rows=[])
        items = [outcome.check_item(CheckResult(c, math.nan, "", (why,))) for c in scenario.checks]
    return {"status": overall([item["status"] for item in items]), "checks": items}


def _recompute_hint(item: Dict[str, Any], folder: str) -> Dict[str, Any]:
    if "metric" not in item or "message" not in item:
        return item
    return {**item, "message": f"{item['message']} ({folder}/{DONE} was written by an earlier pneumorail that kept "
                               f"only some of a case's metrics: delete it and rerun the sweep to recompute the case)"}


def item_line(item: Mapping[str, Any]) -> str:
    """A verdict item as one line: ``FAIL dqq_max <= 0.6: 0.7 at k = 0, wheel 3R``, ``ERROR
    yq_2m_p9985 <= 1.2: no value: ...``, ``FAIL run completes: diverged at ...``."""
    value = item.get("value")
    parts = [f"{value:.4g}" + (f" at {item['at']}" if item.get("at") else "")] \
        if isinstance(value, float) and not math.isnan(value) else []
    parts += [item["message"]] if item.get("message") else []
    return f"{item['status'].upper()} {item['name']}: {'; '.join(parts)}"


def write_check(outcome: "SweepOutcome") -> None:
    """``check.json`` of a sweep run with ``--check`` that was not interrupted; otherwise an earlier
    one is removed (it would not be this run's verdict)."""
    path = outcome.out / CHECK
    if outcome.prepared.check and not outcome.interrupted:
        with atomic_write(path) as fh:
            fh.write(json.dumps(jsonable(outcome.check_verdict()), indent=1, allow_nan=False) + "\n")
    else:
        path.unlink(missing_ok=True)


# ------------------------------------------------------------------------------ the sweep
@dataclass
class SweepOutcome:
    prepared: Prepared
    out: Path
    results: Dict[str, Dict[str, Any]]      # case key -> record (done, failed this run, or absent)
    ran: List[str]
    skipped: List[str]
    interrupted: bool = False
    notes: List[str] = field(default_factory=list)

    def status(self, case: Case) -> str:
        return self.results.get(case.key, {}).get("status", "pending")

    @property
    def counts(self) -> Dict[str, int]:
        out: Dict[str, int] = {}
        for case in self.prepared.cases:
            out[self.status(case)] = out.get(self.status(case), 0) + 1
        return out

    @property
    def all_ok(self) -> bool:
        return all(self.status(c) == "ok" for c in self.prepared.cases)

    @functools.cached_property
    def verdicts(self) -> Dict[str, Dict[str, Any]]:
        """Case key -> :func:`case_verdict`."""
        return {c.key: case_verdict(self.prepared.scenarios[c.key], self.results.get(c.key), f"cases/{c.key}")
                for c in self.prepared.cases}

    def check_failures(self) -> List[Tuple[Case, List[str]]]:
        """Cases whose verdict is not a pass -- a limit violated, a check without a value (the case
        diverged, failed, did not run or did not keep the metric), a result outside the models'
        validity (unless allowed), a divergence -- with a line (:func:`item_line`) per item that
        does not pass."""
        verdicts = [(c, self.verdicts[c.key]) for c in self.prepared.cases]
        return [(c, [item_line(i) for i in v["checks"] if i["status"] != PASS]) for c, v in verdicts
                if v["status"] != PASS]

    def check_report(self) -> str:
        checks = ", ".join(c.text for c in self.prepared.base.checks)
        failures = self.check_failures()
        n = len(self.prepared.cases)
        if not failures:
            return f"checks [{checks}]: all limits hold in every one of the {n} cases"
        count = Counter(self.verdicts[c.key]["status"] for c, _ in failures)
        parts = [f"{word} in {count[s]} of {n} cases" for s, word in ((FAIL, "LIMIT VIOLATED"),
                                                                     (ERROR, "ERROR (a check without a value)"))
                 if count[s]]
        lines = [f"checks [{checks}]: {', '.join(parts)}"]
        lines += [f"  {case.key}  {case.label}: {line}" for case, why in failures for line in why]
        return "\n".join(lines)

    def check_verdict(self) -> Dict[str, Any]:
        """``check.json``: the overall status and, per case, its run status and verdict."""
        cases = [{"case": c.key, "label": c.label, "run": self.status(c), **self.verdicts[c.key]}
                 for c in self.prepared.cases]
        return {"scenario": str(self.prepared.spec.scenario_file), "name": self.prepared.base.name,
                "checks": [c.text for c in self.prepared.base.checks],
                "status": overall([c["status"] for c in cases]), "cases": cases}

    def report(self) -> str:
        counts = self.counts
        n = len(self.prepared.cases)
        parts = [f"{counts.get(s, 0)} {s}" for s in ("ok", "diverged", "failed", "pending") if counts.get(s)]
        lines = [f"{n} cases: {', '.join(parts)} ({len(self.ran)} run now, {len(self.skipped)} finished before)"]
        for case in self.prepared.cases:
            status = self.status(case)
            if status != "ok":
                diag = self.results.get(case.key, {}).get("diagnosis", "")
                lines.append(f"  {status.upper()}: {case.key}  {case.label}" + (f": {diag}" if diag else ""))
        lines += self.notes
        return "\n".join(lines)


class SweepProgress:
    """One line per finished case on stderr (through the runs' own :class:`Progress`): done /
    total, running, failed, ETA."""

    def __init__(self, total: int, skipped: int, quiet: bool = False, stream=None):
        self.total, self.skipped = total, skipped
        self.say = Progress("sweep", stream, quiet=quiet)
        self.t0 = self.say.t0
        self.finished = 0
        self.failed = 0

    def case_done(self, case: Case, record: Dict[str, Any], running: int) -> None:
        self.finished += 1
        self.failed += record["status"] == "failed"
        elapsed = time.perf_counter() - self.t0
        left = self.total - self.skipped - self.finished
        eta = f", ETA {_clock(elapsed / self.finished * left)}" if left else ""
        what = record["status"] + (f" ({record['diagnosis']})" if record["status"] != "ok" and record["diagnosis"] else "")
        self.say(f"{self.skipped + self.finished}/{self.total} done, {running} running, {self.failed} failed{eta} -- "
                 f"{case.key} {case.label}: {what}, {record.get('wall_time_s', 0):.1f} s")


def _clock(seconds: float) -> str:
    seconds = int(round(seconds))
    return f"{seconds // 3600}:{seconds // 60 % 60:02d}:{seconds % 60:02d}" if seconds >= 3600 else \
        f"{seconds // 60}:{seconds % 60:02d}"


def run_sweep(prepared: Prepared, out: Path, executor, quiet: bool = False, stream=None) -> SweepOutcome:
    """Run every case without a done marker on ``executor``, then write sweep.csv, sweep.json,
    sweep.nc and the plots. Ctrl-C stops the executor, keeps what finished and writes the
    tables of what there is (the outcome says ``interrupted``)."""
    out = Path(out).resolve()
    (out / "cases").mkdir(parents=True, exist_ok=True)
    results: Dict[str, Dict[str, Any]] = {}
    todo, skipped = [], []
    for case in prepared.cases:
        marker = out / "cases" / case.key / DONE
        record = _read_json(marker)
        if record is not None:
            results[case.key] = record
            skipped.append(case.key)
        else:
            todo.append(case)
    progress = SweepProgress(len(prepared.cases), len(skipped), quiet, stream)
    progress.say(f"{prepared.base.name}: {len(prepared.cases)} cases, {len(skipped)} already finished, "
                 f"{len(todo)} to run {executor.description}; results in {out}/")
    by_key = {c.key: c for c in prepared.cases}
    tasks = [(c.key, (prepared.scenarios[c.key], str(out / "cases" / c.key), _record(c))) for c in todo]
    ran: List[str] = []
    interrupted = False
    stream_ = executor.run(run_case, tasks)
    try:
        for done in stream_:
            case = by_key[done.key]
            record = done.result
            if done.error is not None or not isinstance(record, dict):
                record = {**_record(case), "status": "failed", "diagnosis": done.error or "no result",
                          "rows": [], "metrics": []}
                folder = out / "cases" / case.key
                folder.mkdir(parents=True, exist_ok=True)
                write_json_atomic(folder / FAILED, record)
            results[case.key] = record
            ran.append(case.key)
            progress.case_done(case, record, executor.running)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        stream_.close()
    outcome = SweepOutcome(prepared, out, results, ran, skipped, interrupted)
    write_tables(outcome)
    write_check(outcome)
    if not interrupted:
        outcome.notes += write_netcdf(outcome)
        outcome.notes += write_plots(outcome)
    return outcome


def _record(case: Case) -> Dict[str, Any]:
    return {"case": case.key, "index": case.index, "values": {k: value_text(v) for k, v in case.values},
            "overrides": case.override_strings(), "k_W_per_K": [k_label(k) for k in case.k] if case.k else None}


def _read_json(path: Path) -> Optional[Dict[str, Any]]:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


# ------------------------------------------------------------------------------ outputs
def grid_columns(prepared: Prepared) -> List[str]:
    return [k for k in (*prepared.spec.grid, *prepared.spec.zip) if k != K_KEY]


def table_rows(outcome: SweepOutcome) -> List[Dict[str, object]]:
    """sweep.csv: one row per case and summary row (case, status, grid values, summary metrics,
    diagnosis); a case without rows (failed, pending) has one row of NaN metrics."""
    keys = grid_columns(outcome.prepared)
    metric_cols: List[str] = []
    for case in outcome.prepared.cases:           # case order: the same columns whatever finished first
        for row in outcome.results.get(case.key, {}).get("rows", []):
            metric_cols += [c for c in row if c not in metric_cols]
    if K_KEY not in metric_cols:
        metric_cols.insert(0, K_KEY)
    rows = []
    for case in outcome.prepared.cases:
        record = outcome.results.get(case.key, {})
        values = dict(case.values)
        head = {"case": case.key, "status": outcome.status(case),
                **{k: _cell(values[k]) for k in keys}}
        summary = record.get("rows") or [{}]
        for srow in summary:
            row = dict(head)
            for c in metric_cols:
                row[c] = srow.get(c, "nan")
            if K_KEY in values and not srow:
                row[K_KEY] = _cell(values[K_KEY])
            row["diagnosis"] = record.get("diagnosis", "")
            rows.append(row)
    return rows


def _cell(value):
    return value if isinstance(value, (int, float, str, bool)) else value_text(value)


def write_tables(outcome: SweepOutcome) -> None:
    prepared = outcome.prepared
    write_rows(outcome.out / "sweep.csv", table_rows(outcome))
    spec = prepared.spec
    info = {"scenario_file": str(spec.scenario_file), "sweep_file": str(spec.source) if spec.source else None,
            "scenario_sha256": prepared.base.content_sha256,
            "grid": {k: [value_text(v) for v in vs] for k, vs in spec.grid.items()},
            "zip": {k: [value_text(v) for v in vs] for k, vs in spec.zip.items()},
            "set": {k: value_text(v) for k, v in spec.base.items()},
            "k_W_per_K": [k_label(k) for k in spec.base_k] if spec.base_k else None,
            "command": " ".join(sys.argv),
            "finished_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "interrupted": outcome.interrupted,
            "last_run": {"ran": outcome.ran, "skipped": outcome.skipped},
            "cases": [{"case": c.key, "index": c.index, "label": c.label, "status": outcome.status(c),
                       "folder": f"cases/{c.key}"} for c in prepared.cases]}
    (outcome.out / "sweep.json").write_text(json.dumps(info, indent=1) + "\n")


def _float(text) -> float:
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def _numeric_column(rows, col) -> bool:
    return all(isinstance(r[col], (int, float)) and not isinstance(r[col], bool) for r in rows)


def write_netcdf(outcome: SweepOutcome) -> List[str]:
    """sweep.nc: every numeric summary metric over (grid keys..., first zip key, k, valves)."""
    import pandas as pd  # comes with xarray
    rows = table_rows(outcome)
    if not rows:
        return []
    spec = outcome.prepared.spec
    zip_keys = list(spec.zip)
    case_columns = KINDS[outcome.prepared.base.kind].case_columns
    dims = [k for k in spec.grid if k != K_KEY] + zip_keys[:1] + [c for c in case_columns if c in rows[0]]
    frame = pd.DataFrame(rows)
    for col in frame.columns:
        if col in ("case", "status", "diagnosis") or col in spec.grid or col in spec.zip:
            continue
        converted = pd.to_numeric(frame[col].replace({"True": 1, "False": 0}), errors="coerce")
        if col == "valves" or not converted.isna().all():
            frame[col] = converted
    frame = frame[frame["status"].isin(["ok", "diverged"])]
    frame = frame.drop(columns=[c for c in zip_keys[1:] if c in frame.columns])
    if frame.empty:
        return ["sweep.nc skipped: no finished case"]
    if frame.duplicated(subset=dims).any():
        return [f"sweep.nc skipped: the rows are not one per ({', '.join(dims)})"]
    try:
        ds = frame.set_index(dims).to_xarray()
        full = {k: [_cell(v) for v in spec.grid[k]] for k in spec.grid if k != K_KEY}
        if zip_keys:
            full[zip_keys[0]] = [_cell(v) for v in spec.zip[zip_keys[0]]]
        ds = ds.reindex(full)               # cases that did not finish: NaN
        if "valves" in ds.coords:
            ds = ds.assign_coords(valves=ds.valves.astype(bool))
        for key in zip_keys[1:]:
            ds = ds.assign_coords({key: (zip_keys[0], [_cell(v) for v in spec.zip[key]])})
        for name in ("case", "status", "diagnosis", *[c for c in frame.columns if frame[c].dtype == object]):
            if name in ds and ds[name].dtype == object:
                ds[name] = ds[name].fillna("").astype(str)
        ds.attrs.update({"scenario": str(spec.scenario_file), "scenario_sha256": outcome.prepared.base.content_sha256,
                         "source": "pneumorail sweep"})
        data = _netcdf_bytes(ds)
    except Exception as exc:                # noqa: BLE001 -- the CSV holds everything; say why
        return [f"sweep.nc skipped: {type(exc).__name__}: {exc}"]
    # the file written from memory by Python, through a temporary file renamed over the old one:
    # a full disk is an OSError naming sweep.nc (the previous one, or none, stays), never a
    # half-written file, and never the netCDF library failing (once a segfault) while closing it
    try:
        with atomic_write(outcome.out / "sweep.nc", "wb") as fh:
            fh.write(data)
    except OSError as exc:
        return [f"sweep.nc not written: {exc.strerror} ({exc.filename}); sweep.csv holds the same numbers"]
    return []


def _netcdf_bytes(ds) -> bytes:
    """The Dataset as the bytes of a netCDF file, built in memory (netCDF4/HDF5 through h5netcdf
    where it is installed, else netCDF3 through scipy)."""
    import io
    try:
        import h5netcdf  # noqa: F401 -- writes netCDF4 into a buffer
    except ImportError:
        return bytes(ds.to_netcdf(engine="scipy"))
    buffer = io.BytesIO()
    ds.to_netcdf(buffer, engine="h5netcdf")
    return buffer.getvalue()


def write_plots(outcome: SweepOutcome) -> List[str]:
    """``sweep_<metric>_vs_<key>.png``: each headline metric against each numeric grid key, a
    line per k, a panel per valve setting and value of the other grid keys; with two numeric grid
    keys, ``sweep_<metric>_heatmap.png``: the metric over both, a panel per (valves, k)."""
    from cosim.results.plots import Curve, Panel, k_legend, save_panels
    prepared = outcome.prepared
    metrics = KINDS[prepared.base.kind].plot_metrics
    rows = [r for r in table_rows(outcome) if r["status"] in ("ok", "diverged")]
    keys = [k for k in prepared.spec.grid if k != K_KEY and _numeric_column(rows, k)] if rows else []
    if not rows or not keys or not metrics:
        return []
    valves = sorted({r.get("valves", "") for r in rows})
    ks = sorted({_float(r[K_KEY]) for r in rows})
    for metric in metrics:
        if metric not in rows[0]:
            continue
        for key in keys:
            others = [k for k in keys if k != key]
            groups = sorted({(r.get("valves", ""), *(r[o] for o in others)) for r in rows}, key=str)
            panels = []
            for group in groups:
                sel = [r for r in rows if (r.get("valves", ""), *(r[o] for o in others)) == group]
                curves = []
                for k in ks:
                    pts = sorted((r[key], _float(r[metric])) for r in sel if _float(r[K_KEY]) == k)
                    if pts:
                        curves.append(Curve([p[0] for p in pts], [p[1] for p in pts], k_legend(k), "o-"))
                title = ", ".join(([f"valves {'on' if group[0] == 'True' else 'off'}"] if len(valves) > 1 else [])
                                  + [f"{o} = {v}" for o, v in zip(others, group[1:])])
                panels.append(Panel(curves, key, metric, title))
            save_panels(outcome.out / f"sweep_{metric}_vs_{key}.png", panels,
                        f"{prepared.base.name}: {metric} against {key}", ncols=min(2, len(panels)))
        if len(keys) >= 2:
            _heatmap(outcome.out / f"sweep_{metric}_heatmap.png", rows, metric, keys[0], keys[1], valves, ks,
                     f"{prepared.base.name}: {metric}" + (f" ({', '.join(keys[2:])} at their first values)" if keys[2:] else ""),
                     {k: rows[0][k] for k in keys[2:]})
    return []


def _heatmap(path: Path, rows, metric, xkey, ykey, valves, ks, title, fixed) -> None:
    plt = pyplot()
    import numpy as np
    xs = sorted({r[xkey] for r in rows})
    ys = sorted({r[ykey] for r in rows})
    nrow, ncol = len(valves), len(ks)
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.2 * ncol + 1, 2.8 * nrow + 0.8), squeeze=False)
    for i, v in enumerate(valves):
        for j, k in enumerate(ks):
            grid = np.full((len(ys), len(xs)), np.nan)
            for r in rows:
                if r.get("valves", "") == v and _float(r[K_KEY]) == k and all(r[f] == x for f, x in fixed.items()):
                    grid[ys.index(r[ykey]), xs.index(r[xkey])] = _float(r[metric])
            ax = axes[i, j]
            im = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis")
            ax.set_xticks(range(len(xs)), [f"{x:g}" for x in xs], fontsize=7)
            ax.set_yticks(range(len(ys)), [f"{y:g}" for y in ys], fontsize=7)
            for (yi, xi), value in np.ndenumerate(grid):
                if np.isfinite(value):
                    ax.text(xi, yi, f"{value:.3g}", ha="center", va="center", fontsize=6, color="w")
            ax.set_xlabel(xkey, fontsize=8)
            ax.set_ylabel(ykey, fontsize=8)
            ax.set_title(f"k = {k_label(k)} W/K" + (f", valves {'on' if v == 'True' else 'off'}" if len(valves) > 1 else ""),
                         fontsize=8)
            fig.colorbar(im, ax=ax, shrink=0.8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
