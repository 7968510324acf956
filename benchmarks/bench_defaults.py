"""Wall time of the two issue-7 speed targets at the shipped defaults, medians of repeated runs
(not a test).

    python benchmarks/bench_defaults.py                 # both scenarios, 3 runs each
    python benchmarks/bench_defaults.py --repeat 5 --only twist
    python benchmarks/bench_defaults.py --root . --root /path/to/other/checkout   # A/B, interleaved

Targets (on a 2-core machine): ``pneumorail run scenarios/twist_dqq.yaml`` <= 10 s and
``pneumorail run scenarios/curve_entry.yaml`` <= 20 s. Each run is a fresh process
(``python -m cosim.cli run SCENARIO --out TMP --quiet`` in the checkout's root, which is what
``pneumorail run`` does), so imports, the process pool, the result files and the plots count.

Other processes may load the machine: the load average before each run and the CPU time the
run's processes used (user + system, all of them) are printed next to the wall time. Several
``--root`` checkouts are run in turn (A, B, A, B, ...), so that a change of load affects them
alike.
"""
from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: name -> (scenario, target wall time [s])
TARGETS = {"twist": ("scenarios/twist_dqq.yaml", 10.0), "curve": ("scenarios/curve_entry.yaml", 20.0)}


def children_cpu_s() -> float:
    """User + system CPU time [s] of every finished child process so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def time_run(root: Path, scenario: str) -> tuple[float, float, float]:
    """(wall [s], CPU [s], 1-min load average before) of one ``pneumorail run`` in ``root``."""
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as out:
        cpu0, t0 = children_cpu_s(), time.perf_counter()
        subprocess.run([sys.executable, "-m", "cosim.cli", "run", scenario, "--out", out, "--quiet"],
                       cwd=root, check=True, stdout=subprocess.DEVNULL)
        return time.perf_counter() - t0, children_cpu_s() - cpu0, load


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--only", choices=sorted(TARGETS), action="append", help="run only this target (repeatable)")
    p.add_argument("--root", type=Path, action="append", help="checkout to time (repeatable; default: this one)")
    args = p.parse_args()
    roots = [r.resolve() for r in (args.root or [ROOT])]
    for name in args.only or list(TARGETS):
        scenario, target = TARGETS[name]
        runs = {root: [] for root in roots}
        for _ in range(args.repeat):
            for root in roots:
                runs[root].append(time_run(root, scenario))
        for root, samples in runs.items():
            wall, cpu, load = (statistics.median(s[i] for s in samples) for i in range(3))
            where = "" if roots == [ROOT] else f" [{root}]"
            print(f"{name} ({scenario}){where}: median {wall:.2f} s wall (target {target:g} s; "
                  f"min {min(s[0] for s in samples):.2f}, max {max(s[0] for s in samples):.2f}), "
                  f"median CPU {cpu:.2f} s, median load before a run {load:.2f}, {len(samples)} runs")


if __name__ == "__main__":
    main()
