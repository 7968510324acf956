"""Wall time of the linear running-stability analysis (not a test; the issue's target: 20 speeds x 4
k values in at most 30 s on the 2-core machine).

    python benchmarks/bench_stability.py              # scenarios/stability.yaml, 3 repetitions
    python benchmarks/bench_stability.py --repeat 5 --set vehicle=paper_metro_car

Each repetition runs the scenario in this process (``cosim.runner.run``: both airspring models,
the circuit's and the static stiffness, each with its bisection to 0.1 m/s) and is timed; printed:
each wall time, their median, and the split: the car's linearisations (the speeds and the
bisection's speeds, shared by every k) against the rest (eigenvalues, air, labels).
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import vehicle.car.linear as car_linear
from cosim.load import load_scenario
from cosim.runner import run

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "stability.yaml"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    args = parser.parse_args()
    scenario = load_scenario(SCENARIO, args.overrides)
    spent = {"car": 0.0, "calls": 0}
    original = car_linear.linearise_car

    def timed(*a, **kw):
        t0 = time.perf_counter()
        try:
            return original(*a, **kw)
        finally:
            spent["car"] += time.perf_counter() - t0
            spent["calls"] += 1

    car_linear.linearise_car = timed
    walls = []
    for i in range(args.repeat):
        spent.update(car=0.0, calls=0)
        t0 = time.perf_counter()
        out = run(scenario)
        walls.append(time.perf_counter() - t0)
        print(f"run {i + 1}: {walls[-1]:.2f} s ({len(scenario.experiment.speeds_m_per_s)} speeds x "
              f"{len(scenario.k_W_per_K)} k x 2 airspring models; {spent['calls']} car linearisations "
              f"{spent['car']:.2f} s); critical speed {out.metrics['critical_speed_m_per_s']:.2f} m/s")
    print(f"median {statistics.median(walls):.2f} s over {args.repeat} runs (target: 30 s)")


if __name__ == "__main__":
    main()
