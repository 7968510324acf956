"""Every fault kind a user can state, on the car in a curve, across k and the valve settings (not
a test; tests/pneumatics/test_faults.py and tests/cosim/kinds/test_car_faults.py check the laws).

    python benchmarks/fault_matrix.py                      # every fault, t = 8 s (in the arc)
    python benchmarks/fault_matrix.py --t 0                # every fault from the start
    python benchmarks/fault_matrix.py --only burst_FR --set curve.cant_rad=0.1
    python benchmarks/fault_matrix.py --only burst_FR --kinematic --set curve.radius_m=300

Each case is ``scenarios/curve_burst.yaml`` (contact curve entry, R = 100 m, 10 m/s, the car with
emergency springs, k = 0 and inf in one run) cut to 20 s, with its burst replaced by the fault of
the row, happening at ``--t`` (default 8 s: 4.5 s into the arc). A fault of a valve needs the
valves: those rows run with them connected only; the others run isolated and connected.
Printed per case: the outcome (``ok``, or the diagnosis that stopped it), the largest EN 14363
ΔQ/Q0 and Y/Q 2 m means after the fault, the largest roll after it, the air lost through the
fault's openings and injected by the valves, and the mass-balance error (the circuit's air
against what crossed its boundary; round-off).
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from cosim.load import load_scenario
from cosim.runner import run

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "curve_burst.yaml"

#: name -> (fault fields, needs the valves)
FAULTS = {
    "burst_FR": ({"kind": "burst", "component": "FR", "area_m2": 5e-4}, False),
    "burst_FL": ({"kind": "burst", "component": "FL", "area_m2": 5e-4}, False),
    "leak_FR_4mm2": ({"kind": "leak", "component": "FR", "area_m2": 4e-6}, False),
    "burst_tank_FR": ({"kind": "burst", "component": "tank_FR", "area_m2": 5e-4}, False),
    "pipe_FR_blocked": ({"kind": "blocked", "component": "pipe_FR"}, False),
    "pipe_FR_ruptured": ({"kind": "ruptured", "component": "pipe_FR"}, False),
    "lv_FR_stuck_closed": ({"kind": "stuck_closed", "component": "lv_FR"}, True),
    "lv_FR_stuck_open_supply": ({"kind": "stuck_open", "component": "lv_FR", "side": "supply"}, True),
    "lv_FR_stuck_open_exhaust": ({"kind": "stuck_open", "component": "lv_FR", "side": "exhaust"}, True),
    "lv_FR_stuck_at_+10mm": ({"kind": "stuck_at", "component": "lv_FR", "lever_m": 0.010}, True),
    "dpv_F_stuck_open": ({"kind": "stuck_open", "component": "dpv_F"}, True),
    "dpv_F_stuck_closed": ({"kind": "stuck_closed", "component": "dpv_F"}, True),
    "supply_lost": ({"kind": "supply_lost", "component": "supply"}, True),
}


def case_overrides(fields, t_s: float, valves) -> list:
    out = [f"faults=[{{{', '.join(f'{k}: {v}' for k, v in {**fields, 't_s': t_s}.items())}}}]",
           "curve.duration_s=20.0", f"curve.valve_settings=[{', '.join(str(v).lower() for v in valves)}]"]
    return out


def _kinematic_copy() -> Path:
    """curve_burst.yaml with kinematic guidance: the contact model's keys and checks removed."""
    import tempfile

    import yaml
    data = yaml.safe_load(SCENARIO.read_text())
    for key in ("friction_coefficient", "nadal_flange_angle_deg", "nadal_friction", "prudhomme_alpha"):
        data["curve"].pop(key, None)
    data["curve"]["guidance"] = "kinematic"
    data["checks"] = []
    path = Path(tempfile.mkdtemp(prefix="fault_matrix_")) / SCENARIO.name
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t", type=float, default=8.0, help="when the fault happens [s] (default 8: in the arc)")
    ap.add_argument("--only", action="append", choices=sorted(FAULTS), help="run only these rows")
    ap.add_argument("--set", action="append", default=[], help="further overrides (key.path=value)")
    ap.add_argument("--kinematic", action="store_true",
                    help="kinematic guidance (the scenario's contact-model keys dropped): no Y/Q")
    args = ap.parse_args(argv)
    scenario_file = _kinematic_copy() if args.kinematic else SCENARIO
    names = args.only or list(FAULTS)
    print(f"{'fault':26s} {'valves':6s} {'k':>4s} {'outcome':8s} {'dqq_2m':>7s} {'yq_2m':>6s} {'roll':>7s} "
          f"{'lost g':>7s} {'inj g':>7s} {'balance kg':>10s}  wall")
    failures = 0
    for name in names:
        fields, needs_valves = FAULTS[name]
        valves = (True,) if needs_valves else (False, True)
        t0 = time.perf_counter()
        scenario = load_scenario(scenario_file, case_overrides(fields, args.t, valves) + args.set)
        outcome = run(scenario)
        wall = time.perf_counter() - t0
        for row in outcome.rows:
            stopped = [d for d in outcome.diagnoses if f"k = {'inf' if math.isinf(row['k_W_per_K']) else '0'}" in d]
            state = "ok" if not stopped else "stop"
            after = "" if args.t > 0 else "_2m_p9985"
            dqq = row.get("dqq_max_after_fault", row.get(f"dqq{after}", math.nan))
            yq = row.get("yq_2m_max_after_fault", row.get(f"yq{after}", math.nan))
            roll = row.get("roll_max_after_fault_rad", row["roll_max_rad"])
            print(f"{name:26s} {'on' if row['valves'] else 'off':6s} {row['k_W_per_K']:4g} {state:8s} {dqq:7.3f} "
                  f"{yq:6.3f} {roll:7.4f} {row['air_lost_kg'] * 1e3:7.1f} {row['air_injected_kg'] * 1e3:7.1f} "
                  f"{row['mass_balance_error_kg']:10.1e}  {wall:.0f} s", flush=True)
            failures += state != "ok"
        for d in outcome.diagnoses:
            print(f"    {d}")
    return 0 if failures == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
