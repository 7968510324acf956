"""Every shipped scenario's files, to show a change left the numbers alone (not a test).

    python benchmarks/shipped_outputs.py run results/outputs_before          # from the repository's top
    python benchmarks/shipped_outputs.py run results/outputs_after --only curve_,twist_
    python benchmarks/shipped_outputs.py run results/gates --gates          # every gate: check --report
    python benchmarks/shipped_outputs.py compare results/outputs_before results/outputs_after

``run`` writes each scenario's run (``pneumorail run``, as a user would) into a folder of its own
name and prints its wall time; ``compare`` lists every CSV file of the two trees: identical to the
byte, different (with the largest relative difference of its numbers and the column), or present
in one tree only. ``run`` takes the scenarios and the code of the folder it is run from (the
current folder comes first on ``python -m``'s path): for the commit before, ``git worktree add
/tmp/before HEAD~1`` and run this script from /tmp/before.
"""
from __future__ import annotations

import argparse
import csv
import math
import subprocess
import sys
import time
from pathlib import Path

import yaml

from cosim.limits.checks import VERDICT_LINE

SCENARIOS = Path("scenarios")
#: check's closing lines
VERDICT_WORDS = tuple(VERDICT_LINE.values())


def run_all(out: Path, only: tuple, gates: bool = False) -> int:
    """Every scenario (``gates``: those with checks through ``check --report``, printing the
    verdict's last line)."""
    failed = 0
    for path in sorted(SCENARIOS.glob("*.yaml")):
        if only and not any(path.stem.startswith(o) for o in only):
            continue
        t0 = time.perf_counter()
        gated = gates and bool((yaml.safe_load(path.read_text()) or {}).get("checks"))
        command = ["check", str(path), "--report"] if gated else ["run", str(path)]
        done = subprocess.run([sys.executable, "-m", "cosim.cli", *command, "--out", str(out.resolve() / path.stem),
                               "--overwrite", "--quiet"], capture_output=True, text=True)
        failed += done.returncode not in (0, 1)            # 1: a check or a diverged case is a result too
        verdict = [line for line in done.stdout.splitlines() if any(w in line for w in VERDICT_WORDS)] if gated else []
        print(f"{path.stem:28s} exit {done.returncode}  {time.perf_counter() - t0:7.1f} s  {' '.join(verdict)}",
              flush=True)
        if done.returncode not in (0, 1):
            print(done.stderr[-2000:], file=sys.stderr)
    return 1 if failed else 0


def _largest_difference(a: Path, b: Path) -> str:
    """The largest relative difference between the two files' numbers, and where."""
    with a.open() as fa, b.open() as fb:
        ra, rb = list(csv.reader(fa)), list(csv.reader(fb))
    if len(ra) != len(rb) or (ra and ra[0] != rb[0]):
        return f"shape or header differs ({len(ra)} / {len(rb)} lines)"
    worst, where = 0.0, ""
    for row_a, row_b in zip(ra[1:], rb[1:]):
        for name, x, y in zip(ra[0], row_a, row_b):
            if x == y:
                continue
            try:
                fx, fy = float(x), float(y)
            except ValueError:
                return f"text differs in {name}: {x!r} / {y!r}"
            rel = abs(fx - fy) / max(abs(fx), abs(fy), 1e-300) if not (math.isnan(fx) and math.isnan(fy)) else 0.0
            if rel > worst:
                worst, where = rel, name
    return f"largest relative difference {worst:.3g} in {where}"


def compare(before: Path, after: Path) -> int:
    files = sorted({p.relative_to(before) for p in before.rglob("*.csv")} | {p.relative_to(after) for p in after.rglob("*.csv")})
    same = 0
    for rel in files:
        a, b = before / rel, after / rel
        if not a.exists() or not b.exists():
            print(f"only in {'after' if not a.exists() else 'before'}: {rel}")
        elif a.read_bytes() == b.read_bytes():
            same += 1
        else:
            print(f"differs: {rel}: {_largest_difference(a, b)}")
    print(f"{same} of {len(files)} CSV files identical to the byte")
    return 0 if same == len(files) else 1


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run")
    r.add_argument("out", type=Path)
    r.add_argument("--only", default="", help="comma-separated scenario name prefixes")
    r.add_argument("--gates", action="store_true", help="scenarios with checks: check --report instead of run")
    c = sub.add_parser("compare")
    c.add_argument("before", type=Path)
    c.add_argument("after", type=Path)
    args = p.parse_args()
    if args.command == "run":
        return run_all(args.out, tuple(o for o in args.only.split(",") if o), args.gates)
    return compare(args.before, args.after)


if __name__ == "__main__":
    sys.exit(main())
