"""The linear stability analysis over the inputs a user gives it (not a test): car (the paper's, with
dampers) x circuit (four-point with tanks, bellows without tanks, two-point with a cross pipe) x track
(rigid, flexible) x valves (isolated, connected) x wheels (S1002/UIC60, a 0.2 cone), k = 0 / 10 / inf
in each run, 20 speeds 5-100 m/s. Prints a Markdown table: the linear critical speed per k (the air
circuit's model), the mode that loses its damping, the wall time.

    python benchmarks/stability_matrix.py          # 48 runs, ~4 min on 2 cores
"""
from __future__ import annotations

import itertools
import math
import tempfile
import time
from pathlib import Path

import yaml

from cosim.load import load_scenario
from cosim.runner import run

CIRCUITS = {"four-point": {}, "no tank": {"tank": None},
            "two-point": {"layout": "two_point", "cross_pipe": {"length_m": 2.0, "diameter_m": 0.018, "zeta": 2.0}}}
VALVES = {"off": {"valves": False},
          "on": {"valves": True, "supply": {"p_Pa": 9.0e5}, "levelling_valve": {}, "differential_valve": {}}}


def _speed(v: float) -> str:
    return f"{v:.2f}" if math.isfinite(v) else ("< 5" if math.isnan(v) else "> 100")


def main() -> None:
    folder = Path(tempfile.mkdtemp())
    print("| car | circuit | track | valves | wheels | critical speed k = 0 / 10 / inf [m/s] | mode | wall [s] |")
    print("|---|---|---|---|---|---|---|---|")
    for car, (cname, circuit), track, (vname, valves), wheels in itertools.product(
            ("paper_metro_car", "metro_car_arb_dampers"), CIRCUITS.items(), ("rigid", "flexible"), VALVES.items(),
            ("S1002", "cone 0.2")):
        circ = {"layout": "four_point", "preset": "paper_table1", **circuit, **valves}
        if cname == "two-point" and vname == "on":
            circ["differential_valve"] = None             # the cross pipe equalises the bogie's bellows
        stability = {"speeds_m_per_s": [float(v) for v in range(5, 101, 5)], "valve_settings": [valves["valves"]]}
        if wheels != "S1002":
            stability["conicity"] = 0.2
        data = {"kind": "stability", "name": "matrix", "k_W_per_K": [0, 10, float("inf")], "vehicle": car,
                "circuit": circ, "stability": stability, "track": track, "solver": {"jobs": 1}}
        path = folder / "matrix.yaml"
        path.write_text(yaml.safe_dump(data))
        t0 = time.perf_counter()
        out = run(load_scenario(path))
        rows = [r for r in out.rows if r["airspring"] == "circuit"]
        speeds = " / ".join(_speed(r["critical_speed_m_per_s"]) for r in rows)
        modes = ", ".join(sorted({r["critical_mode"] for r in rows}))
        print(f"| {car} | {cname} | {track} | {vname} | {wheels} | {speeds} | {modes} | "
              f"{time.perf_counter() - t0:.1f} |", flush=True)


if __name__ == "__main__":
    main()
