"""Wall and CPU time of the main job, ``pneumorail run scenarios/twist_dqq.yaml``, for one or more
source trees run side by side (not run as a test; issue 37).

    python benchmarks/bench_main_job.py                          # this tree, 3 runs
    python benchmarks/bench_main_job.py --tree old=/tmp/wt_old --tree new=. --repeats 5
    python benchmarks/bench_main_job.py --scenario scenarios/curve_entry.yaml --set solver.jobs=1

Each run is ``python -m cosim.cli run SCENARIO --out TMP --overwrite --quiet`` in a fresh process
with ``PYTHONPATH=TREE`` and the tree as working directory; the trees take turns (old, new, old,
new ...) so that the load of a shared machine falls on all of them alike. One warm-up run per tree
first (numba's caches, the page cache), not counted. Printed per tree: the median over the runs
of the wall time and of the CPU time (user + sys of the process and of every worker it waited
for: the pools' processes), and, with ``--stages`` (the default), the same split by stage:

    start       interpreter, imports, loading the scenario, up to the cars' run
    simulate    the kind's run (the cars and circuits on the worker pool, gathering the Dataset)
    prepare     the kind's figures (what to draw) and the labels
    csv         the time series and summary files
    figures     drawing the PNGs (on the pool of ``solver.jobs`` processes)
    run.json    provenance and what the report shows
    end         the printed report
    outside     what the driver does not see: the interpreter's start and its end (tearing down
                every module, where the tree's ``python -m cosim.cli`` does)

The stages are timed by wrapping functions found by name in the tree (``cosim.runner.run``,
``write_outcome``, ``save_figures``, ``write_run_json``) from a small driver that then calls
``cosim.cli.main``; trees without them get the totals only. A CPU time on a shared machine is
far steadier than a wall time (the wall time waits for other people's processes); still compare
medians of several alternating runs, not single ones.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

STAGES = ("start", "simulate", "prepare", "csv", "figures", "run.json", "end")

# Runs in the child: times the stages by wrapping functions wherever a module holds them, then
# runs the command line. Prints one JSON line on stderr (the last line).
DRIVER = r"""
import json, os, resource, sys, time
T0 = (time.perf_counter(), time.process_time())
marks = {}
def cpu():
    c = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + c.ru_utime + c.ru_stime
def stamp(name):
    marks[name] = (time.perf_counter(), cpu())
import cosim.cli
try:
    import cosim.runner
except ImportError:
    pass
def wrap(module_names, attr, before, after):
    target = None
    for name in module_names:
        module = sys.modules.get(name)
        if module is not None and hasattr(module, attr):
            target = getattr(module, attr)
            break
    if target is None:
        return
    def wrapper(*a, **k):
        stamp(before)
        try:
            return target(*a, **k)
        finally:
            stamp(after)
    for module in list(sys.modules.values()):
        try:
            if getattr(module, attr, None) is target:
                setattr(module, attr, wrapper)
        except Exception:
            pass
wrap(["cosim.runner"], "run", "run0", "run1")
wrap(["cosim.results.writer", "cosim.writer"], "write_outcome", "write0", "write1")
wrap(["cosim.results.writer", "cosim.writer"], "save_figures", "fig0", "fig1")
wrap(["cosim.results.io", "cosim.results"], "write_run_json", "json0", "json1")
main = cosim.cli.main
def timed_main(argv=None):
    try:
        return main(argv)
    finally:
        sys.stdout.flush()
        stamp("exit")
        print(json.dumps({"marks": marks, "t0": [T0[0], T0[1]]}), file=sys.stderr, flush=True)
cosim.cli.main = timed_main
# as python -m cosim.cli ends: the tree's entry() where it has one, else sys.exit(main())
if hasattr(cosim.cli, "entry"):
    cosim.cli.entry()
sys.exit(timed_main())
"""


def one_run(tree: Path, scenario: str, extra, out: Path) -> dict:
    """One run of the main job from ``tree``: wall and CPU (self + children) [s], and the stages."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    cmd = [sys.executable, "-c", DRIVER, "run", scenario, "--out", str(out), "--overwrite", "--quiet", *extra]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode not in (0, 1):
        raise SystemExit(f"{tree}: exit {proc.returncode}\n{proc.stderr[-3000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    result = {"wall": wall, "cpu": cpu}
    try:
        info = json.loads(proc.stderr.strip().splitlines()[-1])
    except (ValueError, IndexError):
        return result
    marks, t0 = info["marks"], info["t0"]
    if not all(m in marks for m in ("run0", "run1", "write0", "fig0", "fig1", "write1", "exit")):
        return result
    edges = [("start", None, "run0"), ("simulate", "run0", "run1"), ("prepare", "run1", "write0"),
             ("csv", "write0", "fig0"), ("figures", "fig0", "fig1"),
             ("run.json", "json0" if "json0" in marks else "fig1", "json1" if "json1" in marks else "write1"),
             ("end", "json1" if "json1" in marks else "write1", "exit")]
    stages = {}
    for name, a, b in edges:
        wall_b, cpu_b = marks[b]
        wall_a, cpu_a = marks[a] if a else (t0[0], t0[1])
        stages[name] = (wall_b - wall_a, cpu_b - cpu_a)
    stages["outside"] = (wall - (marks["exit"][0] - t0[0]), cpu - (marks["exit"][1] - t0[1]))
    result["stages"] = stages
    return result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tree", action="append", default=[], metavar="NAME=PATH",
                        help="a source tree to time (repeatable; default: this one)")
    parser.add_argument("--scenario", default="scenarios/twist_dqq.yaml", help="relative to each tree")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="passed on to run")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-warmup", action="store_true")
    parser.add_argument("--json", type=Path, help="write every run's numbers here")
    args = parser.parse_args(argv)
    trees = []
    for item in args.tree or [f"this={Path(__file__).resolve().parents[1]}"]:
        name, _, path = item.rpartition("=")
        trees.append((name or Path(path).name, Path(path).resolve()))
    extra = [x for s in args.set for x in ("--set", s)]
    runs = {name: [] for name, _ in trees}
    with tempfile.TemporaryDirectory() as tmp:
        if not args.no_warmup:
            for name, tree in trees:
                one_run(tree, args.scenario, extra, Path(tmp) / name)
        for i in range(args.repeats):
            for name, tree in trees:
                r = one_run(tree, args.scenario, extra, Path(tmp) / name)
                runs[name].append(r)
                print(f"run {i + 1}/{args.repeats} {name:>8}: wall {r['wall']:6.2f} s  cpu {r['cpu']:6.2f} s", flush=True)
    print(f"\n{args.scenario} {' '.join(args.set)}: medians of {args.repeats} alternating runs [s]")
    print(f"{'tree':>8} {'wall':>7} {'cpu':>7}   " + "  ".join(f"{s:>14}" for s in (*STAGES, "outside")))
    print(f"{'':>8} {'':>7} {'':>7}   " + "  ".join(f"{'wall / cpu':>14}" for _ in (*STAGES, "outside")))
    for name, _ in trees:
        rs = runs[name]
        line = f"{name:>8} {statistics.median(r['wall'] for r in rs):7.2f} {statistics.median(r['cpu'] for r in rs):7.2f}   "
        if all("stages" in r for r in rs):
            def median(stage, i):
                return statistics.median(r["stages"][stage][i] for r in rs)
            line += "  ".join(f"{median(s, 0):6.2f} /{median(s, 1):6.2f}" for s in (*STAGES, "outside"))
        print(line)
    if args.json:
        args.json.write_text(json.dumps(runs, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
