"""Command line: ``pneumorail run | check | validate | verify | compare | report | comfort | sweep | presets``.

Exit codes: 0 success (for ``check``: every limit holds; for ``verify``: every estimated
discretisation error within the scenario's ``verify.tolerance``; for ``sweep``: every case
finished without diverging, and with ``--check`` every limit holds in every case), 1 a limit is
violated, an error estimate exceeds its tolerance, a run diverged or a sweep case failed, 2 bad
input (the message names the file, the key path and what was expected), 130 / 143 interrupted
by SIGINT (Ctrl-C) / SIGTERM (what was computed is kept; a sweep resumes when rerun).
"""
from __future__ import annotations

import argparse
import contextlib
import logging
import math
import signal
import sys
import time
from pathlib import Path
from typing import List, Optional, Sequence

from cosim.errors import ExecutorUnavailable, ScenarioError
from cosim.results.io import Progress
from cosim.scenario.schema import k_label

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130


def _version() -> str:
    from cosim.results.io import versions
    return versions().get("pneumorail", "unknown")


def _argument(name: str):
    """An argparse type from :mod:`cosim.results.compare`'s parser ``name``, which raises ValueError
    (argparse then exits 2 with the message); imported when used (matplotlib is slow to load)."""
    def convert(text: str):
        from cosim.results import compare
        try:
            return getattr(compare, name)(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
    convert.__name__ = name
    return convert


def _k_list(text: str) -> List[float]:
    out = []
    for item in text.split(","):
        item = item.strip()
        try:
            k = math.inf if item.lower() in ("inf", ".inf", "infinity") else float(item)
        except ValueError:
            raise argparse.ArgumentTypeError(f"--k expects comma-separated numbers or inf, got {item!r}") from None
        if not k >= 0:
            raise argparse.ArgumentTypeError(f"k must be >= 0 W/K, got {item}")
        out.append(k)
    return out


EPILOG = """\
exit codes:
  0    success (check: every limit holds; verify: every error estimate within its tolerance;
       validate: every file is valid; sweep: every case finished)
  1    a limit is violated or a check has no value (check: ERROR, saying why), a result is
       outside the model's validity (check), an error estimate exceeds its tolerance, a run
       diverged, a sweep case failed, a result could not be written
  2    bad input: the message names the file, the key path and what was expected
  130  interrupted by Ctrl-C (SIGINT), 143 by SIGTERM: what was computed is kept

examples:
  pneumorail run scenarios/twist_dqq.yaml                       # results/twist_dqq/
  pneumorail run scenarios/curve_entry.yaml --k 0,inf --set curve.speed_m_per_s=12
  pneumorail check scenarios/twist_dqq.yaml --quiet             # CI gate; check.json, check.xml (JUnit)
  pneumorail validate scenarios/*.yaml                          # every check, no simulation
  pneumorail presets metro_car_arb_dampers > mycar.yaml         # a car to start from (vehicle: mycar.yaml)
  pneumorail verify scenarios/curve_entry.yaml --k 0,inf        # halve every step twice: error estimates
  pneumorail sweep scenarios/curve_entry.yaml --grid curve.speed_m_per_s=8,10,12 --k 0,inf
  pneumorail compare results/twist_dqq results/twist_dqq_1a2b3c4d --wheels 1L,3R
  pneumorail report results/curve_canted --out curve_canted.html    # one HTML file to hand on
  pneumorail fmu scenarios/twist_dqq.yaml --k 10 --out twist_dqq.fmu   # the air circuit for another tool
  pneumorail comfort results/straight_irregular/timeseries/curve_valves=off_k=inf.csv --point centre

every scenario key: docs/scenario_keys.md; the models: docs/models.md
"""


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="pneumorail", description=__doc__.split("\n")[0], epilog=EPILOG,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    def scenario_options(parser, out_default: str) -> None:
        """Options every command that runs one scenario shares."""
        parser.add_argument("--out", type=Path, default=None, help=f"output folder (default: {out_default})")
        parser.add_argument("--k", type=_k_list, default=None, help="override the k values [W/K], e.g. 0,10,inf")
        parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                            help="override a scenario value, e.g. --set twist.hold_s=10 (repeatable)")
        parser.add_argument("--jobs", type=int, default=None, help="parallel processes for the k cases")
        parser.add_argument("--quiet", action="store_true", help="no progress lines")

    for name, help_ in (("run", "run a scenario and write its results"),
                        ("check", "run a scenario and check the limits of its 'checks:' section")):
        s = sub.add_parser(name, help=help_)
        s.add_argument("scenario", type=Path, help="scenario YAML file")
        scenario_options(s, "results/<scenario name>, plus a hash of --set/--k if given")
        s.add_argument("--overwrite", action="store_true", help="replace a previous run in the output folder")
        if name == "check":
            s.add_argument("--report", action="store_true",
                           help="also write report.html (pneumorail report) next to check.json")
    r = sub.add_parser("presets", help="list the named parameter sets, or print one as a YAML file to start from")
    r.add_argument("name", nargs="?", default=None, help="a preset name: print it (e.g. > mycar.yaml)")
    a = sub.add_parser("validate", help="check scenario or sweep files completely without running them (exit 0 or 2)")
    a.add_argument("scenarios", type=Path, nargs="+", help="scenario or sweep YAML files")
    a.add_argument("--k", type=_k_list, default=None, help="override the k values [W/K], e.g. 0,10,inf")
    a.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scenario value, e.g. --set twist.hold_s=10 (repeatable)")
    v = sub.add_parser("verify", help="rerun with every step halved, estimate the discretisation error (Richardson)")
    v.add_argument("scenario", type=Path, help="a car scenario YAML file (a rig scenario is refused, naming the car kinds)")
    v.add_argument("--levels", type=int, default=None, help="number of halvings (default: the scenario's verify.levels, 2)")
    scenario_options(v, "results/<scenario name>_verify")
    w = sub.add_parser("sweep", help="run a scenario for every combination of a grid of values (docs/sweeps.md)")
    w.add_argument("scenario", type=Path, help="scenario YAML file, or a sweep file (with a 'sweep:' section)")
    w.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2,...",
                   help="a grid key and its values (YAML); the cases are the product of the grid keys (repeatable)")
    w.add_argument("--zip", action="append", default=[], metavar="KEY=V1,V2,...",
                   help="keys whose value lists (equal length) vary together, one more factor of the product (repeatable)")
    w.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a value of the base scenario for every case (repeatable)")
    w.add_argument("--k", type=_k_list, default=None, help="the k values [W/K] of every case, e.g. 0,inf")
    w.add_argument("--out", type=Path, default=None, help="output folder (default: results/<sweep name>)")
    w.add_argument("--jobs", type=int, default=None,
                   help="cases run at once (default 2; 1: one after the other in this process)")
    where = w.add_mutually_exclusive_group()
    where.add_argument("--dask", action="store_true", help="run on a Dask LocalCluster of --jobs worker processes")
    where.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="run on an existing Dask cluster, e.g. tcp://host:8786 (shared file system)")
    w.add_argument("--connect-timeout", type=float, default=5.0, metavar="SECONDS",
                   help="how long the --scheduler may take to accept a connection (default 5 s)")
    w.add_argument("--check", action="store_true",
                   help="evaluate the base scenario's checks: in every case; exit 1 naming the cases that fail")
    w.add_argument("--quiet", action="store_true", help="no progress lines")
    m = sub.add_parser("comfort", help="ride comfort (EN 12299 N_MV, Cc, Sperling Wz, ISO 2631) of an acceleration CSV")
    m.add_argument("record", type=Path, help="CSV with t_s and any of ax_m_per_s2, ay_m_per_s2, az_m_per_s2 (car axes)")
    m.add_argument("--point", default=None, help="a car run's floor point (front, centre, rear): its a<x|y|z>_<point> columns")
    m.add_argument("--out", type=Path, default=None, help="output folder (default: beside the file, comfort_<its name>)")
    i = sub.add_parser("identify", help="fit scenario keys (k first) to measured rig data, with 95 %% intervals "
                                        "(docs/identify.md)")
    i.add_argument("scenario", type=Path, help="a rig scenario of an identifiable kind (a time history or a "
                                               "stiffness table; others are refused, naming them)")
    i.add_argument("--data", type=Path, default=None, help="CSV: t_s, z_m and any of F_bellow_N, p_bellow_Pa, p_tank_Pa, "
                                                           "T_bellow_K, T_tank_K; or a stiffness table")
    i.add_argument("--fit", default="k_W_per_K", metavar="KEY[,KEY ...]",
                   help="the keys to fit (default k_W_per_K; others: e.g. circuit.pipe.zeta)")
    i.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scenario value (repeatable)")
    i.add_argument("--out", type=Path, default=None, help="output folder (default: results/identify_<the data's name>, as run)")
    i.add_argument("--plan", action="store_true", help="instead of fitting: which sine frequency identifies k best")
    i.add_argument("--k", type=float, default=10.0, help="--plan: the nominal k [W/K] (default 10)")
    i.add_argument("--jobs", type=int, default=2, help="processes: a stiffness table's frequencies, the profiles of "
                                                       "a fit of several keys (default 2)")
    i.add_argument("--dask", action="store_true", help="profiles on a Dask LocalCluster of --jobs workers")
    f = sub.add_parser("fmu", help="export the scenario's air circuit as an FMI 2.0 co-simulation FMU (docs/fmi.md)")
    f.add_argument("scenario", type=Path, help="car scenario YAML file")
    f.add_argument("--out", type=Path, required=True, help="the FMU file to write (NAME.fmu)")
    f.add_argument("--k", type=_k_list, default=None,
                   help="k [W/K] the FMU starts with (its parameter k_W_per_K); default: the scenario's one k")
    f.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scenario value (repeatable)")
    o = sub.add_parser("report", help="one self-contained HTML report of one or more runs (side by side)")
    o.add_argument("dirs", type=Path, nargs="+", help="output folders of runs, checks or verify")
    o.add_argument("--out", type=Path, default=None, help="the HTML file (default: report.html in the first folder)")
    o.add_argument("--allow-incomplete", action="store_true",
                   help="report interrupted or unfinished runs too (their verdict: NOT ASSESSED)")
    c = sub.add_parser("compare", help="overlay the results of several runs")
    c.add_argument("dirs", type=Path, nargs="+", help="output folders of earlier runs")
    c.add_argument("--out", type=Path, default=None,
                   help="folder for the comparison plots (default: beside the first run, compare_<its name>)")
    c.add_argument("--wheels", type=_argument("parse_wheels"), default=None, metavar="LIST",
                   help="twist: the wheels to show, e.g. 1L,3R (default: 1L 1R 4L 4R and the worst wheel)")
    c.add_argument("--k", type=_k_list, default=None, help="only these k values [W/K], e.g. 0,inf")
    c.add_argument("--time", type=_argument("parse_window"), default=None, metavar="T0,T1",
                   help="only this time window [s], e.g. 5,15")
    c.add_argument("--allow-incomplete", action="store_true",
                   help="draw interrupted or unfinished runs too, marked 'interrupted' in the legend")
    return p


def main(argv: Optional[Sequence[str]] = None) -> int:
    args = build_parser().parse_args(argv)
    _show_warnings(quiet=getattr(args, "quiet", False))
    try:
        if args.command == "compare":
            from cosim.kinds import overlays
            from cosim.results.compare import Selection, compare_runs
            select = Selection(args.wheels, tuple(args.k) if args.k else None, args.time)
            out = args.out or args.dirs[0].resolve().parent / f"compare_{args.dirs[0].resolve().name}"
            for path in compare_runs(args.dirs, out, overlays(), select, args.allow_incomplete):
                print(path)
            return EXIT_OK
        if args.command == "comfort":
            return _comfort(args)
        if args.command == "identify":
            return _identify(args)
        if args.command == "report":
            from cosim.results.report import write_report
            t0 = time.perf_counter()
            path = write_report(args.dirs, args.out, args.allow_incomplete)
            print(f"report in {path} ({time.perf_counter() - t0:.2f} s)")
            return EXIT_OK
        if args.command == "validate":
            return _validate(args)
        if args.command == "presets":
            return _presets(args)
        if args.command == "verify":
            return _verify(args)
        if args.command == "sweep":
            return _sweep(args)
        if args.command == "fmu":
            return _fmu(args)
        return _run(args)
    except ScenarioError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except ExecutorUnavailable as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as exc:                       # a result that could not be written (disk full ...)
        if exc.filename is None:
            raise
        print(f"error: cannot write {exc.filename}: {exc.strerror}; the output folder is marked INCOMPLETE",
              file=sys.stderr)
        return EXIT_FAILED


class _Stderr(logging.Handler):
    """Log records as ``warning: ...`` lines on the current sys.stderr."""

    def emit(self, record: logging.LogRecord) -> None:
        print(f"{record.levelname.lower()}: {record.getMessage()}", file=sys.stderr, flush=True)


def _show_warnings(quiet: bool = False) -> None:
    """Warnings about results (validity, settling) on stderr, each once; none with --quiet (they
    stay in run.json and check.json)."""
    log = logging.getLogger("pneumorail")
    for handler in [h for h in log.handlers if isinstance(h, (_Stderr, logging.NullHandler))]:
        log.removeHandler(handler)
    log.addHandler(logging.NullHandler() if quiet else _Stderr())   # NullHandler: not logging's last resort
    log.setLevel(logging.WARNING)
    log.propagate = False


def _sweep_spec(args, path: Path):
    """The sweep of ``path`` (a sweep file, or a scenario) with the command line's --grid, --zip,
    --set and --k applied."""
    from cosim.sweep.study import SweepSpec, is_sweep_file, load_sweep_file, parse_assignment
    spec = load_sweep_file(path) if is_sweep_file(path) else SweepSpec(path)
    file = spec.source or spec.scenario_file
    for option, items, target in (("--grid", getattr(args, "grid", []), spec.grid),
                                  ("--zip", getattr(args, "zip", []), spec.zip)):
        for item in items:
            key, values = parse_assignment(item, file, option, many=True)
            spec.grid.pop(key, None)
            spec.zip.pop(key, None)
            target[key] = values
            spec.origin[key] = option
    for item in args.overrides:
        key, value = parse_assignment(item, file, "--set", many=False)
        spec.base[key] = value
    if args.k:
        spec.base_k = tuple(args.k)
    return spec


@contextlib.contextmanager
def _terminate_as_interrupt():
    """In a sweep's main process SIGTERM stops the sweep as Ctrl-C does: the executor's workers
    are stopped, finished cases kept, the tables written with the pending rows. Yields a list
    that holds the signal once it came (the command then exits 143)."""
    received: List[int] = []

    def handler(signum, frame):
        received.append(signum)
        raise KeyboardInterrupt
    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield received
    finally:
        signal.signal(signal.SIGTERM, previous)


def _sweep(args) -> int:
    from cosim.results.outdir import FolderLock
    from cosim.sweep.executors import make_executor
    from cosim.sweep.study import prepare, run_sweep
    spec = _sweep_spec(args, args.scenario)
    file = spec.source or spec.scenario_file
    jobs = 2 if args.jobs is None else _jobs(args.jobs, file)
    if not args.connect_timeout > 0:
        raise ScenarioError(file, ["--connect-timeout"], f"expected a time > 0 s, got {args.connect_timeout:g}")
    executor = make_executor(jobs, dask=args.dask, scheduler=args.scheduler, connect_timeout_s=args.connect_timeout)
    prepared = prepare(spec, check=args.check)
    out = args.out or Path("results") / (spec.name or f"{prepared.base.name}_sweep")
    # the folder is held for the whole sweep: a second sweep into it is refused (exit 2), and one
    # that cannot be written is refused before anything runs
    with FolderLock(out, "sweep"), _terminate_as_interrupt() as terminated:
        outcome = run_sweep(prepared, out, executor, quiet=args.quiet)
    print(outcome.report())
    print(f"results in {out}/ (sweep.csv, cases/<case>/)")
    if outcome.interrupted:
        done = sum(1 for c in prepared.cases if outcome.status(c) in ("ok", "diverged"))
        print(f"interrupted{' by SIGTERM' if terminated else ''}: {done} of {len(prepared.cases)} cases finished and "
              f"kept; rerun the same command to resume (finished cases are skipped)", file=sys.stderr)
        return 128 + signal.SIGTERM if terminated else EXIT_INTERRUPTED
    if args.check:
        print(outcome.check_report())
        if outcome.check_failures():
            return EXIT_FAILED
    return EXIT_OK if outcome.all_ok else EXIT_FAILED


def _load(args, path: Optional[Path] = None):
    """The validated scenario with the command line's --k, --set and --jobs applied; an option
    that does not apply to the scenario's kind is refused, not ignored."""
    import dataclasses

    from cosim.kinds import KINDS
    from cosim.load import load_scenario
    path = path or args.scenario
    scenario = load_scenario(path, args.overrides, args.k)
    kind = KINDS[scenario.kind]
    if args.k and kind.k_fixed:
        raise ScenarioError(path, ["--k"], f"does not apply to {kind.name}: {kind.k_fixed}")
    jobs = getattr(args, "jobs", None)
    if jobs is not None:
        _jobs(jobs, path)
        if not kind.car:
            raise ScenarioError(path, ["--jobs"], f"does not apply to {scenario.kind}: rig scenarios run in one "
                                                  f"process (their cases take seconds)")
        scenario = dataclasses.replace(scenario, solver=dataclasses.replace(scenario.solver, jobs=jobs))
    return scenario


def _jobs(jobs: int, file) -> int:
    """``--jobs``, in the range ``solver.jobs`` has (one rule for both)."""
    from cosim.scenario.model import SolverSettings
    from cosim.scenario.schema import check_range, range_of
    check_range(jobs, range_of(SolverSettings, "jobs"), file, ["--jobs"])
    return jobs


def _presets(args) -> int:
    from cosim.scenario.presets import PRESETS, preset_yaml, summary
    if args.name is None:
        for name, (section, _) in PRESETS.items():
            print(f"{name:<24} {section:<8} {summary(name)}")
        return EXIT_OK
    if args.name not in PRESETS:
        raise ScenarioError("<command line>", ["presets"], f"unknown preset {args.name!r} (expected one of "
                                                            f"{', '.join(PRESETS)})")
    print(preset_yaml(args.name), end="")
    return EXIT_OK


def _validate(args) -> int:
    """Load and check every file (a sweep file: every case) without running anything."""
    from cosim.kinds import KINDS
    from cosim.sweep.study import is_sweep_file, prepare
    bad = 0
    for path in args.scenarios:
        try:
            if is_sweep_file(path):
                prepared = prepare(_sweep_spec(args, path))
                print(f"{path}: valid sweep, {len(prepared.cases)} cases of {prepared.base.kind}")
            else:
                s = _load(args, path)
                k = "" if KINDS[s.kind].k_fixed else f", k = {', '.join(map(k_label, s.k_W_per_K))} W/K"
                print(f"{path}: valid {s.kind} scenario '{s.name}'{k}, {len(s.checks)} checks")
        except ScenarioError as exc:
            print(f"error: {exc}", file=sys.stderr)
            bad += 1
    return EXIT_BAD_INPUT if bad else EXIT_OK


def _verify(args) -> int:
    from cosim.kinds import KINDS
    from cosim.results.outdir import FolderLock
    from cosim.scenario.model import VerifySettings
    from cosim.scenario.schema import range_of
    from cosim.verification.verify import report, verify
    scenario = _load(args)
    if not KINDS[scenario.kind].car:
        cars = ", ".join(k.name for k in KINDS.values() if k.car)
        raise ScenarioError(args.scenario, ["kind"], f"verify needs a car scenario ({cars}), got {scenario.kind}")
    levels = scenario.verify.levels if args.levels is None else args.levels
    allowed = range_of(VerifySettings, "levels")               # the same range as the verify.levels key
    if not allowed.admits(levels):
        raise ScenarioError(args.scenario, ["--levels"], f"expected {allowed.expected(integer=True)}, got {levels}")
    out = args.out or Path("results") / f"{scenario.name}_verify"
    with FolderLock(out, "verify"):
        found, diverged = verify(scenario, out, levels, Progress(scenario.name, quiet=args.quiet))
    print(report(found, scenario.verify.tolerance))
    print(f"results in {out}/")
    if diverged:
        print(f"DIVERGED: {diverged}")
        return EXIT_FAILED
    return EXIT_OK if all(e.error <= scenario.verify.tolerance for e in found) else EXIT_FAILED


def _fmu(args) -> int:
    from cosim.fmi.export import export_fmu
    if args.k is not None and len(args.k) != 1:
        raise ScenarioError(args.scenario, ["--k"], f"expected one k value, got {len(args.k)}")
    scenario = _load(args)
    path = export_fmu(scenario, args.out, args.k[0] if args.k else None)
    print(f"FMU in {path}")
    return EXIT_OK


def _comfort(args) -> int:
    from cosim.results.comfort_files import comfort_of_file
    from cosim.results.outdir import FolderLock
    out = args.out or args.record.resolve().parent / f"comfort_{args.record.stem}"
    with FolderLock(out, "comfort"):                 # an --out that cannot be a folder: exit 2 first
        result = comfort_of_file(args.record, out, args.point)
    for message in result.warnings:
        print(f"warning: {message}", file=sys.stderr)
    n_mv = "—" if result.N_MV is None else f"{result.N_MV:.3f} ({result.scale})"
    print(f"N_MV {n_mv}; " + ", ".join(f"a{a.upper()}P95 {v:.4g} m/s²" for a, v in result.aP95_m_per_s2.items())
          + "; " + ", ".join(f"Wz_{a} {v:.3g}" for a, v in result.Wz.items()))
    print(f"results in {out}/")
    return EXIT_OK


def _identify(args) -> int:
    from cosim.identify.run import identify, parse_keys, plan, report, write
    from cosim.identify.synthetic import NOISE
    from cosim.results.outdir import FolderLock
    if args.plan:
        rows = plan(args.scenario, args.k, NOISE, args.overrides)
        valid = [r for r in rows if r["valid"]]
        best = min(valid, key=lambda r: r["se_k_relative"]) if valid else None
        print(f"sine of the scenario's amplitude and duration, nominal k = {args.k:g} W/K, noise "
              + ", ".join(f"{c} {v:g}" for c, v in NOISE.items()))
        print("frequency [Hz]   standard error of k   pipe Mach   T max [K]")
        for r in rows:
            note = "   <- best" if r is best else ("" if r["valid"] else "   outside the model's validity")
            print(f"{r['frequency_Hz']:14g}   {r['se_k_relative']:19.3%}   {r['pipe_mach_max']:9.2f}   "
                  f"{r['T_max_K']:9.1f}{note}")
        return EXIT_OK
    if args.data is None:
        raise ScenarioError(args.scenario, ["--data"], "give the measured data (--data FILE.csv), or --plan")
    if args.jobs < 1:
        raise ScenarioError(args.scenario, ["--jobs"], f"expected at least 1, got {args.jobs}")
    keys = parse_keys(args.fit, args.scenario)
    executor = None
    if len(keys) > 1:
        from cosim.sweep.executors import make_executor
        executor = make_executor(args.jobs, args.dask)
    out = _identify_out(args, keys)
    with FolderLock(out, "identification"):      # refused (exit 2) before anything is fitted
        model, result = identify(args.scenario, args.data, keys, args.overrides, executor, args.jobs)
        write(model, result, out)
    print(report(result))
    print(f"results in {out}/")
    return EXIT_OK


def _identify_out(args, keys: Sequence[str]) -> Path:
    """``--out``, or as ``run``: ``results/identify_<the data's name>``, never beside the data (which
    may be in the source tree); a fit of other keys or with ``--set`` gets a hash suffix."""
    from cosim.identify.fit import K_KEY
    from cosim.results.outdir import default_folder
    fitted = [] if list(keys) == [K_KEY] else [f"--fit={','.join(keys)}"]
    return args.out or default_folder(f"identify_{args.data.stem}", [*args.overrides, *fitted])


def _run(args) -> int:
    from cosim import interrupts
    from cosim.kinds import KINDS
    from cosim.results.outdir import INCOMPLETE, OutputFolder, default_folder
    from cosim.runner import run_scenario
    from cosim.scenario.checks import checks_hint
    from cosim.sweep.study import is_sweep_file
    if is_sweep_file(args.scenario):
        raise ScenarioError(args.scenario, [], f"this is a sweep file: pneumorail sweep {args.scenario}"
                                               f"{' --check' if args.command == 'check' else ''}")
    scenario = _load(args)
    if args.command == "check" and not scenario.checks:
        kind = KINDS[scenario.kind]
        hint = checks_hint(kind) + ("" if kind.check_metrics else "; use 'run'")
        raise ScenarioError(scenario.file, ["checks"], f"no checks to evaluate: {hint}")
    out = args.out or default_folder(scenario.name, args.overrides, args.k)
    progress = Progress(scenario.name, quiet=args.quiet)
    with interrupts.handled(), OutputFolder(out, args.overwrite):
        outcome = run_scenario(scenario, out, progress)
        if args.command == "check" and not interrupts.stop_requested():
            from cosim.results.writer import write_verdict
            write_verdict(outcome, out)
    if interrupts.stop_requested():
        name = signal.Signals(interrupts.received_signal()).name
        (out / INCOMPLETE).write_text(f"interrupted by {name}: the run stopped before its end\n")
        print(f"interrupted by {name}: the results computed until then are in {out}/ (run.json: status "
              f"interrupted)", file=sys.stderr)
        return interrupts.exit_code()
    print(outcome.report())
    print(f"results in {out}/")
    if args.command == "check":
        print(outcome.check_report())
        print(f"verdict in {out}/check.json and check.xml (JUnit)")
        if args.report:
            from cosim.results.report import write_report
            print(f"report in {write_report([out])}")
        return EXIT_OK if outcome.checks_hold() else EXIT_FAILED
    return EXIT_FAILED if outcome.diverged else EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
