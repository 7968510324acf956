"""Wall time of whole scenarios, median of repeated runs (not a test).

    python benchmarks/bench_scenarios.py scenarios/twist_dqq.yaml --repeat 3
    python benchmarks/bench_scenarios.py scenarios/rig_stiffness.yaml --repeat 3
    python benchmarks/bench_scenarios.py scenarios/curve_entry.yaml --k 0 --set "curve.valve_settings=[true]"

Targets (issues): the stiffness sweep (5 k x >= 20 frequencies) < 60 s; the twist scenario for
all seven k values < 20 s; one curve-entry run < 10 s and the k x valves matrix < 60 s, on the
2-core reference machine. Each run is a fresh process, as a
user would run it, so imports and start-up count.
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("scenarios", nargs="+", type=Path)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--k", default=None, help="passed to pneumorail run")
    p.add_argument("--set", dest="overrides", action="append", default=[], help="passed to pneumorail run")
    args = p.parse_args()
    extra = (["--k", args.k] if args.k else []) + [a for o in args.overrides for a in ("--set", o)]
    for scenario in args.scenarios:
        times = []
        for _ in range(args.repeat):
            with tempfile.TemporaryDirectory() as out:
                t0 = time.perf_counter()
                subprocess.run([sys.executable, "-m", "cosim.cli", "run", str(scenario), "--out", out, "--quiet", *extra],
                               check=True, stdout=subprocess.DEVNULL)
                times.append(time.perf_counter() - t0)
        print(f"{scenario} {' '.join(extra)}: median {statistics.median(times):.2f} s wall over {len(times)} runs "
              f"(min {min(times):.2f}, max {max(times):.2f})")


if __name__ == "__main__":
    main()
