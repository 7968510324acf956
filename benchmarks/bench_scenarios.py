"""Wall time of whole scenarios, median of repeated runs (not a test).

    python benchmarks/bench_scenarios.py scenarios/twist_dqq.yaml --repeat 3
    python benchmarks/bench_scenarios.py scenarios/rig_stiffness.yaml --repeat 3
    python benchmarks/bench_scenarios.py scenarios/curve_entry.yaml --k 0 --set "curve.valve_settings=[true]"
    python benchmarks/bench_scenarios.py scenarios/curve_entry_contact.yaml --against-kinematic

``--against-kinematic`` (target: a contact run within 1.5 times the kinematic one): each
scenario is also run as its kinematic twin, the same file with ``curve.guidance: kinematic``
and without what only contact guidance has (the contact model's keys and the checks of lateral
wheel-rail metrics), alternating contact and kinematic runs; prints both medians and the ratio.

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

import yaml

from cosim.limits.checks import CONTACT_METRICS

#: keys of ``curve`` that only contact guidance accepts
CONTACT_KEYS = ("friction_coefficient", "contact_damping_N_s_per_m", "contact_smoothing_mm")


def kinematic_twin(scenario: Path, folder: Path) -> Path:
    """``scenario`` with kinematic guidance, written into ``folder``."""
    data = yaml.safe_load(scenario.read_text())
    curve = data["curve"]
    curve["guidance"] = "kinematic"
    for key in CONTACT_KEYS:
        curve.pop(key, None)
    irregularity = curve.get("irregularity")
    if isinstance(irregularity, dict) and "file" in irregularity:  # relative to the scenario
        irregularity["file"] = str((scenario.parent / irregularity["file"]).resolve())
    data["checks"] = [c for c in data.get("checks", [])
                      if c.split()[0].split("[")[0] not in CONTACT_METRICS]
    path = folder / scenario.name.replace(".yaml", "_kinematic.yaml")
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def wall_s(scenario: Path, extra: list) -> float:
    """Wall time of one ``pneumorail run`` in a fresh process."""
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "cosim.cli", "run", str(scenario), "--out", out,
                        "--quiet", *extra], check=True, stdout=subprocess.DEVNULL)
        return time.perf_counter() - t0


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("scenarios", nargs="+", type=Path)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--k", default=None, help="passed to pneumorail run")
    p.add_argument("--set", dest="overrides", action="append", default=[], help="passed to pneumorail run")
    p.add_argument("--against-kinematic", action="store_true",
                   help="also run each (contact) scenario's kinematic twin; print the ratio")
    args = p.parse_args()
    extra = (["--k", args.k] if args.k else []) + [a for o in args.overrides for a in ("--set", o)]
    for scenario in args.scenarios:
        if args.against_kinematic:
            with tempfile.TemporaryDirectory() as folder:
                twin = kinematic_twin(scenario, Path(folder))
                pairs = [(wall_s(scenario, extra), wall_s(twin, extra)) for _ in range(args.repeat)]
            con, kin = (statistics.median(t) for t in zip(*pairs))
            print(f"{scenario} {' '.join(extra)}: contact {con:.2f} s, kinematic {kin:.2f} s, "
                  f"ratio {con / kin:.2f} (medians of {args.repeat} alternating runs)")
            continue
        times = [wall_s(scenario, extra) for _ in range(args.repeat)]
        print(f"{scenario} {' '.join(extra)}: median {statistics.median(times):.2f} s wall over {len(times)} runs "
              f"(min {min(times):.2f}, max {max(times):.2f})")


if __name__ == "__main__":
    main()
