"""Sensitivity of the curve entry's air consumption to what the paper does not give.

    python studies/air_sensitivity.py [--k 0,inf] [--out results/air_sensitivity] [--jobs 2]

The paper's Table 4 (25, 29, 35, 35 g for k = 0, 1, 10, 1e4) belongs to a car whose levelling
valve dead band and lever gain, valve dynamics, airspring spacing and carbody centre of gravity
it does not state. This study varies each of them alone from the shipped curve entry
(``scenarios/curve_entry.yaml``, valves connected) and tabulates the air injected from the
supply (one-at-a-time, a tornado plot per k). Every variant is a ``--set`` override of the
scenario, so each row can be rerun with ``pneumorail run``.

Writes ``air_sensitivity.csv`` (one row per variant and k), ``air_sensitivity.md`` (the table)
and ``air_sensitivity.png`` (tornado plot) into the output folder.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from cosim.cli import _k_list
from cosim.load import load_scenario
from cosim.results.io import write_rows
from cosim.runner import run
from cosim.scenario.schema import k_label

SCENARIO = Path(__file__).resolve().parent.parent / "scenarios" / "curve_entry.yaml"

#: (label, overrides): each varies one assumption of the shipped car (baseline in brackets)
VARIANTS = (
    ("baseline", ()),
    ("dead band 3 mm [5]", ("circuit.levelling_valve.supply_lever_m=[0, 0.003, 0.025]",
                            "circuit.levelling_valve.exhaust_lever_m=[0, 0.003, 0.025]")),
    ("dead band 10 mm [5]", ("circuit.levelling_valve.supply_lever_m=[0, 0.010, 0.025]",
                             "circuit.levelling_valve.exhaust_lever_m=[0, 0.010, 0.025]")),
    ("lever gain 0.5 [1]", ("circuit.levelling_valve.lever_gain=0.5",)),
    ("lever gain 1.5 [1]", ("circuit.levelling_valve.lever_gain=1.5",)),
    ("valve lag 1 s [0]", ("circuit.levelling_valve.lag_s=1.0",)),
    ("valve dead time 1 s [0]", ("circuit.levelling_valve.delay_s=1.0",)),
    ("valve play 2 mm [0]", ("circuit.levelling_valve.hysteresis_m=0.002",)),
    ("valve lag + dead time + play [0]", ("circuit.levelling_valve.lag_s=1.0", "circuit.levelling_valve.delay_s=1.0",
                                          "circuit.levelling_valve.hysteresis_m=0.002")),
    ("airspring spacing 1.6 m [2.0]", ("vehicle.airspring_lateral_spacing_m=1.6",)),
    ("carbody CoG 1.8 m [1.5]", ("vehicle.carbody_cog_height_m=1.8",)),
)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--k", type=_k_list, default=[0.0, math.inf], help="k values [W/K] (default 0,inf)")
    ap.add_argument("--out", type=Path, default=Path("results/air_sensitivity"))
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args(argv)
    rows = []
    for label, overrides in VARIANTS:
        t0 = time.perf_counter()
        scenario = load_scenario(SCENARIO, [*overrides, f"solver.jobs={args.jobs}", "curve.valve_settings=[true]"],
                                 args.k)
        outcome = run(scenario)
        ks = [row["k_W_per_K"] for row in outcome.rows]
        for row in outcome.rows:
            rows.append({"variant": label, "overrides": "; ".join(overrides), "k_W_per_K": row["k_W_per_K"],
                         "air_injected_kg": row["air_injected_kg"], "air_exhausted_kg": row["air_exhausted_kg"],
                         "diverged": outcome.diverged or ""})
        print(f"{label:<36} " + "  ".join(f"k={k_label(k)}: {1e3 * r['air_injected_kg']:6.2f} g"
                                           for k, r in zip(ks, rows[-len(ks):]))
              + f"   ({time.perf_counter() - t0:.1f} s)", file=sys.stderr)
    args.out.mkdir(parents=True, exist_ok=True)
    write_rows(args.out / "air_sensitivity.csv", rows)
    _table(args.out / "air_sensitivity.md", rows, args.k)
    _tornado(args.out / "air_sensitivity.png", rows, args.k)
    print((args.out / "air_sensitivity.md").read_text())
    return 0


def _injected_g(rows, label, k, column="air_injected_kg"):
    return next(1e3 * r[column] for r in rows if r["variant"] == label and r["k_W_per_K"] == k)


def _table(path: Path, rows, ks) -> None:
    """Air injected / exhausted per variant and k: both large and close together is a valve
    that hunts (air in and straight out again)."""
    head = "| variant | " + " | ".join(f"k = {k_label(k)}: injected / exhausted [g]" for k in ks) + " |"
    lines = [head, "|" + " --- |" * (len(ks) + 1)]
    for label, _ in VARIANTS:
        lines.append(f"| {label} | " + " | ".join(
            f"{_injected_g(rows, label, k):.1f} / {_injected_g(rows, label, k, 'air_exhausted_kg'):.1f}"
            for k in ks) + " |")
    path.write_text("\n".join(lines) + "\n")


def _tornado(path: Path, rows, ks) -> None:
    labels = [label for label, _ in VARIANTS[1:]]
    fig, axes = plt.subplots(1, len(ks), figsize=(6 * len(ks), 0.45 * len(labels) + 1.5), squeeze=False)
    for ax, k in zip(axes[0], ks):
        base = _injected_g(rows, "baseline", k)
        change = [_injected_g(rows, label, k) - base for label in labels]
        ax.barh(range(len(labels)), change, color=["tab:red" if c > 0 else "tab:blue" for c in change])
        ax.set_yticks(range(len(labels)), labels, fontsize=8)
        ax.axvline(0.0, color="k", lw=0.8)
        ax.set_xlabel(f"change of air injected [g] (baseline {base:.1f} g)")
        ax.set_title(f"k = {k_label(k)} W/K", fontsize=10)
        ax.invert_yaxis()
    fig.suptitle("Curve entry, valves connected: sensitivity of the air injected (one at a time)", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
