"""The station stop and the service over what users give them (not a test): payload from tare to
crush load, symmetric and one-sided, boarding and alighting; dwells of 10-60 s; the valves' dead
band and lag; four- and two-point circuits; each row across k = 0, 10, 100, inf in one run.

    python benchmarks/service_matrix.py                  # every row (~10 min on 2 cores)
    python benchmarks/service_matrix.py --only base,crush_right
    python benchmarks/service_matrix.py --csv matrix.csv

Each station-stop row is ``scenarios/station_stop.yaml`` with the changes of the row (one factor
at a time around the shipped stop); the service rows are ``scenarios/service_line.yaml`` cut to
its first three stations one way. Printed per row and k: the outcome (``ok`` or the diagnosis that
stopped it), the floor at door close and its worst deviation while the doors were open (the
platform-side doors, relative to arrival), the re-levelling time (NaN: never within the +-15.9 mm
tolerance), valve openings, the air injected and the mass-balance error.
"""
from __future__ import annotations

import argparse
import csv
import math
import time
from pathlib import Path

from cosim.load import load_scenario
from cosim.runner import run

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
K = [0.0, 10.0, 100.0, math.inf]
EVENT = "payload.events[0]"
STOP = ("station_stop.yaml", ["solver.jobs=2"])
LINE = ("service_line.yaml", ["service.stations=[{name: A, at_m: 0, dwell_s: 25, boarding: 60}, "
                              "{name: B, at_m: 900, dwell_s: 25, platform_side: left, alighting: 20, boarding: 40}, "
                              "{name: C, at_m: 1900, dwell_s: 25, alighting: 109}]",
                              "service.curves=[{at_m: 300, radius_m: 300, arc_m: 150, transition_m: 40, cant_rad: 0.06}]",
                              "service.round_trip=false", "solver.jobs=2"])
TWO_POINT = ["circuit.layout=two_point", "circuit.cross_pipe={length_m: 2.0, diameter_m: 0.018, zeta: 2.0}",
             "vehicle=metro_car_arb_dampers"]

#: name -> (base, its changes, what the row varies)
ROWS = {
    "base": (STOP, [], "the shipped stop: 0.5 -> 1.0 normal, right half, 20 s, dwell 60 s"),
    "tare_to_normal_uniform": (STOP, ["payload.initial={normal_fraction: 0}", f"{EVENT}.normal_fraction=1.0",
                                      f"{EVENT}.position=uniform"], "payload tare -> normal, uniform"),
    "normal_to_crush_right": (STOP, ["payload.initial={normal_fraction: 1.0}", f"{EVENT}.normal_fraction=0.49",
                                     f"{EVENT}.position=right"], "payload normal -> crush (exceptional), right half"),
    "crush_to_tare_alighting": (STOP, ["payload.initial={normal_fraction: 1.49}", f"{EVENT}.normal_fraction=-1.49",
                                       f"{EVENT}.position=uniform"], "crush load alighting, uniform"),
    "front_end": (STOP, [f"{EVENT}.position=front"], "boarding at the front end"),
    "dwell_10s": (STOP, [f"{EVENT}.duration_s=6", "station.duration_s=10"], "dwell 10 s (6 s boarding)"),
    "dwell_30s": (STOP, [f"{EVENT}.duration_s=20", "station.duration_s=30"], "dwell 30 s"),
    "valve_deadband_0.5mm": (STOP, ["circuit.levelling_valve.supply_lever_m=[0, 0.0005, 0.025]",
                                    "circuit.levelling_valve.exhaust_lever_m=[0, 0.0005, 0.025]"],
                             "valve dead band 0.5 mm (5 mm shipped)"),
    "valve_no_lag": (STOP, ["circuit.levelling_valve.lag_s=0", "circuit.levelling_valve.delay_s=0"],
                     "valve without lag and delay (1 s and 1 s shipped)"),
    "two_point": (STOP, TWO_POINT, "two-point circuit (bellows of a bogie cross-connected)"),
    "service_four_point": (LINE, [], "service, three stations one way, a canted curve"),
    "service_two_point": (LINE, TWO_POINT, "service, two-point circuit"),
}


def one(name: str, extra):
    (file, base), changes, what = ROWS[name]
    scenario = load_scenario(SCENARIOS / file, [*base, *changes, *extra], k_override=K)
    start = time.perf_counter()
    outcome = run(scenario)
    wall = time.perf_counter() - start
    out = []
    for row in outcome.rows:
        k = row["k_W_per_K"]
        diag = [d for d in outcome.diagnoses if f"k = {k:g}" in d or (math.isinf(k) and "k = inf" in d)]
        out.append({"row": name, "what": what, "k_W_per_K": k, "outcome": "ok" if not diag else diag[0][:80],
                    "floor_dz_close_mm": 1e3 * row.get("floor_dz_close_m", row.get("floor_dev_close_m", math.nan)),
                    "floor_dev_max_mm": 1e3 * row["floor_dev_max_m"],
                    "relevel_s": row.get("relevel_s", row.get("relevel_max_s")),
                    "valve_openings": row["valve_openings"], "air_injected_g": 1e3 * row["air_injected_kg"],
                    "mass_balance_error_kg": row["mass_balance_error_kg"], "wall_s": wall})
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", help="comma-separated row names")
    ap.add_argument("--set", action="append", default=[], help="an override for every row")
    ap.add_argument("--csv", help="write the table here too")
    args = ap.parse_args(argv)
    names = args.only.split(",") if args.only else list(ROWS)
    rows = []
    print("| row | k [W/K] | outcome | floor at close [mm] | worst while open [mm] | re-levelled [s] | openings "
          "| air [g] | balance [kg] |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for name in names:
        for r in one(name, args.set):
            rows.append(r)
            print(f"| {r['row']} | {r['k_W_per_K']:g} | {r['outcome']} | {r['floor_dz_close_mm']:+.1f} | "
                  f"{r['floor_dev_max_mm']:.1f} | {r['relevel_s']:.1f} | {r['valve_openings']} | "
                  f"{r['air_injected_g']:.1f} | {r['mass_balance_error_kg']:.1e} |", flush=True)
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main()
