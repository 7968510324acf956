"""Wall time of the twist run with its circuit imported from an FMU against the native run
(not a test; docs/fmi.md, "A car's circuit from an FMU").

    python benchmarks/bench_fmu_import.py                  # k = 10 W/K, the whole twist, 3 runs each
    python benchmarks/bench_fmu_import.py --repeat 5 --k 0,10,inf

The twist's circuit is exported once (``pneumorail fmu scenarios/twist_dqq.yaml --k K``) into a
temporary folder beside a copy of the scenario whose circuit is ``fmu: twist.fmu``; then the
native run and the FMU run alternate (native, FMU, native, FMU, ...: a change of the machine's
load affects both alike), each a fresh ``python -m cosim.cli run SCENARIO --k K --quiet``
process, so imports, the process pool, the result files and the plots count. Printed: each
run's wall time and the runner's own (``wall_time_s`` of run.json: the simulation and its
summary, without imports and plots), their medians and the FMU's over the native's. The FMU run
steps its FMUs in a worker process (cosim.engine.cases), the native run of one k in the main one.
Target: the FMU run <= 1.5 x the native one.
"""
from __future__ import annotations

import argparse
import json
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "twist_dqq.yaml"


def time_run(scenario: Path, k: str, out: Path) -> tuple[float, float]:
    """(process wall time [s], the runner's wall time [s]) of one run."""
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "cosim.cli", "run", str(scenario), "--k", k, "--out", str(out), "--quiet",
                    "--overwrite"], cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    return wall, float(json.loads((out / "run.json").read_text())["wall_time_s"])


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--k", default="10", help="the k values [W/K] of both runs, e.g. 0,10,inf (default 10)")
    args = p.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_fmu_import_") as tmp:
        folder = Path(tmp)
        export_k = "10" if "," in args.k else args.k
        subprocess.run([sys.executable, "-m", "cosim.cli", "fmu", str(SCENARIO), "--k", export_k, "--out",
                        str(folder / "twist.fmu")], cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
        imported = folder / "twist_fmu.yaml"
        imported.write_text(re.sub(r"circuit:\n(  .*\n)+", "circuit:\n  fmu: twist.fmu\n", SCENARIO.read_text()))
        times = {"native": [], "fmu": []}
        for i in range(args.repeat):
            for name, scenario in (("native", SCENARIO), ("fmu", imported)):
                wall, runner = time_run(scenario, args.k, folder / name)
                times[name].append((wall, runner))
                print(f"run {i + 1} {name:6s}: wall {wall:6.2f} s, runner {runner:6.2f} s", flush=True)
    medians = {name: (statistics.median(w for w, _ in t), statistics.median(r for _, r in t)) for name, t in times.items()}
    for name, (wall, runner) in medians.items():
        print(f"median {name:6s}: wall {wall:6.2f} s, runner {runner:6.2f} s")
    print(f"FMU / native: wall {medians['fmu'][0] / medians['native'][0]:.2f}, "
          f"runner {medians['fmu'][1] / medians['native'][1]:.2f} (target <= 1.5)")


if __name__ == "__main__":
    main()
