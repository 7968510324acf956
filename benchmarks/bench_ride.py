"""Real-time factor of the ride: the car on wheel-rail contact over irregular track, co-simulated
with its circuit at the shipped steps (issue target: >= 15 x real time per core, i.e. 5 minutes
simulated in <= 20 s of one core). Not run as a test.

    python benchmarks/bench_ride.py                 # 20 m/s, k = 10, 30 s simulated, median of 3
    python benchmarks/bench_ride.py --k 0,10,100,inf --seconds 60 --repeat 1

Builds the co-simulation of ``scenarios/ride_comfort.yaml`` at one speed (the cars, the circuit,
the contact table and the irregularity are built before the clock starts) and runs it with the
scenario's output interval. Prints the median wall time, simulated seconds per wall second per
case (per core: one process), and the split of a macro-step (force laws, cars, air, sampling,
the rest) in microseconds per case.
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from cosim.engine.cases import build_cosimulation
from cosim.engine.master import Record
from cosim.kinds import ride
from cosim.load import load_scenario
from cosim.runs import track_run

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "ride_comfort.yaml"
STAGES = ("_force_laws", "_advance_cars", "_advance_air", "sample")


def timed(obj, name: str, totals: dict) -> None:
    """Wrap ``obj.name`` so that its wall time adds to ``totals[name]``."""
    inner = getattr(obj, name)

    def wrapper(*args, **kwargs):
        t0 = time.perf_counter()
        try:
            return inner(*args, **kwargs)
        finally:
            totals[name] += time.perf_counter() - t0
    setattr(obj, name, wrapper)


def build(scenario, k_values):
    """The co-simulation of the ride ``scenario``'s first speed, one car per k value."""
    curve, _ = ride.curve_at(scenario.experiment, scenario.experiment.speeds_m_per_s[0], scenario.vehicle)
    speed_scenario = ride._speed_scenario(scenario, curve)
    return build_cosimulation(speed_scenario, k_values, track_run.make_car)


def once(scenario, k_values, seconds: float, split: bool):
    cosim = build(scenario, k_values)
    totals = dict.fromkeys(STAGES, 0.0)
    if split:
        for name in STAGES:
            timed(cosim, name, totals)
    t0 = time.perf_counter()
    record, diagnosis = cosim.run(seconds, scenario.solver.output_interval_s)
    wall = time.perf_counter() - t0
    if diagnosis:
        raise SystemExit(f"the run failed: {diagnosis}")
    assert isinstance(record, Record)
    return wall, totals, round(seconds / scenario.solver.macro_step_s)


def ride_arguments(description: str, seconds: float) -> argparse.ArgumentParser:
    """The options that choose a ride case (shared with ``bench_car_floor.py``)."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--k", default="10", help="k values [W/K], comma-separated (one car each, one circuit)")
    ap.add_argument("--speed", type=float, default=20.0, help="running speed [m/s]")
    ap.add_argument("--seconds", type=float, default=seconds, help="simulated time [s]")
    ap.add_argument("--set", dest="overrides", action="append", default=[], help="a scenario override")
    return ap


def ride_case(args):
    """(scenario at ``args.speed`` lasting ``args.seconds``, k values) of parsed ride arguments."""
    overrides = [f"ride.speeds_m_per_s=[{args.speed}]", f"ride.record_s={args.seconds}", *args.overrides]
    return load_scenario(SCENARIO, overrides), [float(k) for k in args.k.split(",")]


def main() -> int:
    ap = ride_arguments(__doc__.splitlines()[0], seconds=30.0)
    ap.add_argument("--repeat", type=int, default=3, help="runs; the median is quoted")
    args = ap.parse_args()
    scenario, k_values = ride_case(args)
    walls, splits = [], []
    for i in range(args.repeat):
        wall, totals, steps = once(scenario, k_values, args.seconds, split=(i == 0))
        walls.append(wall)
        if i == 0:
            splits = {name: 1e6 * v / steps / len(k_values) for name, v in totals.items()}
            splits["rest"] = 1e6 * wall / steps / len(k_values) - sum(splits.values())
        print(f"run {i + 1}: {wall:.2f} s wall (with the split's timers: {i == 0})")
    timed_runs = walls[1:] or walls
    wall = statistics.median(timed_runs)
    per_case = args.seconds * len(k_values) / wall
    print(f"{len(k_values)} case(s) at {args.speed:g} m/s, {args.seconds:g} s simulated, macro-step "
          f"{scenario.solver.macro_step_s * 1e3:g} ms, mechanics {scenario.solver.mechanics_step_s * 1e3:g} ms, "
          f"pneumatics {scenario.solver.pneumatic_step_s * 1e3:g} ms, outputs every "
          f"{scenario.solver.output_interval_s * 1e3:g} ms")
    print(f"median wall {wall:.2f} s (of {len(timed_runs)}): {per_case:.1f} x real time per case and core "
          f"(target 15); 300 s would take {300.0 / per_case:.1f} s")
    print("one macro-step per case [us]: " + ", ".join(f"{k.strip('_')} {v:.0f}" for k, v in splits.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
