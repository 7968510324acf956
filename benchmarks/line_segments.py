"""Where a service's car-alone time goes along its route (not a test): the shipped line's car
(``scenarios/service_line.yaml``: track, speed profile, passengers) driven alone on linear
bellows as in ``bench_service.py``, timed per block of simulated time with the solver's Newton
iterations per step and the fresh Jacobians it took.

    python benchmarks/line_segments.py                 # the whole round trip, 25 s blocks
    python benchmarks/line_segments.py --until 500 --block 50

Found with it (docs/service.md, speed): out to the terminus every 25 s costs 1-2 s; on the way
back the kept Jacobian stops serving (thousands of fresh ones per block) and a block costs up to
38 s.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_service import LINE, K
from bench_vehicle import K_ADIABATIC_N_PER_M

from cosim.kinds import service
from cosim.load import load_scenario


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--until", type=float, help="simulated time to stop at [s] (default: the trip's end)")
    ap.add_argument("--block", type=float, default=25.0, help="simulated time per printed line [s]")
    args = ap.parse_args(argv)
    scenario = load_scenario(LINE, [], k_override=K)
    plan = scenario.experiment.plan
    horizon = args.until or service.duration_s(scenario.experiment)
    car = service.make_car(scenario)
    F0, k = car.static_bellow_forces_N(), np.full(4, K_ADIABATIC_N_PER_M)
    macro = scenario.solver.macro_step_s
    n, block = int(round(horizon / macro)), int(round(args.block / macro))
    counters = car._solver.it                         # exudyn's Newton counters (cumulative)
    newton, jacobians, start = counters.newtonStepsCount, car.jacobian_count, time.perf_counter()
    for i in range(n):
        z, _ = car.bellow_crushing()
        car.set_bellow_forces(F0 + k * z, k)
        car.advance((i + 1) * macro)
        car.wheel_loads_N()
        if (i + 1) % block == 0 or i + 1 == n:
            t, now, steps = (i + 1) * macro, time.perf_counter(), (i % block) + 1
            print(f"t {t:7.1f} s  v {float(plan.speed.speed(t)):5.1f} m/s  wall {now - start:6.2f} s  "
                  f"Newton per step {(counters.newtonStepsCount - newton) / steps:5.2f}  "
                  f"fresh Jacobians {car.jacobian_count - jacobians}", flush=True)
            newton, jacobians, start = counters.newtonStepsCount, car.jacobian_count, now


if __name__ == "__main__":
    main()
