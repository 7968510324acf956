"""Where a service's car-alone time goes along its route (not a test): the shipped line's car
(``scenarios/service_line.yaml``: track, speed profile, passengers) driven alone on linear
bellows as in ``bench_service.py``, timed per block of simulated time with the solver's Newton
iterations per step and the fresh Jacobians it took.

    python benchmarks/line_segments.py                 # the whole round trip, 25 s blocks
    python benchmarks/line_segments.py --until 500 --block 50
    python benchmarks/line_segments.py --scenario my_line.yaml --origin-m 17000 --until 120
    python benchmarks/line_segments.py --roundoff 0     # Newton's tolerance as before the rule
    python benchmarks/line_segments.py --roundoff 0 --vehicle primary_stiffness_x_N_per_m=1.75e6

``--origin-m``: the line starts that far along its track (a straight before it), and the car
with it: the same route and dynamics, far from the coordinates' origin. ``--roundoff``: the
solver's CarSolver.ROUNDOFF_SAFETY (0: Newton's absolute tolerance never follows the coordinates'
round-off). ``--vehicle NAME=VALUE``: a vehicle parameter changed (repeatable).

Found with it (docs/service.md, speed): before the round-off rule, out to the terminus every 25 s
cost 1-2 s and on the way back up to 38 s (thousands of fresh Jacobians per block); the line's
first stations started 17 km out blew up the same way as soon as the car moved: Newton's
residual stalls on a round-off floor that grows with the distance from the origin.
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_service import LINE, K
from bench_vehicle import K_ADIABATIC_N_PER_M

from cosim.kinds import service
from cosim.load import load_scenario
from vehicle.car.solver import CarSolver


def _start_line_at(origin_m: float) -> None:
    """Every route planned from now on starts ``origin_m`` along its track (the plan's slack: a
    straight before the first station); the service's car starts at the route's origin."""
    plan = service.plan

    def shifted_plan(*args, **kwargs):
        kwargs["slack_m"] = kwargs.get("slack_m", 0.0) + origin_m
        return plan(*args, **kwargs)

    service.plan = shifted_plan


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--until", type=float, help="simulated time to stop at [s] (default: the trip's end)")
    ap.add_argument("--block", type=float, default=25.0, help="simulated time per printed line [s]")
    ap.add_argument("--scenario", type=Path, default=LINE, help="a service scenario (default: the shipped line)")
    ap.add_argument("--origin-m", type=float, default=0.0, help="start the line this far along its track [m]")
    ap.add_argument("--roundoff", type=float, help="CarSolver.ROUNDOFF_SAFETY (default: the solver's; 0: no rule)")
    ap.add_argument("--vehicle", action="append", default=[], metavar="NAME=VALUE",
                    help="change a vehicle parameter (vehicle.params.VehicleParams field), repeatable")
    args = ap.parse_args(argv)
    if args.roundoff is not None:
        CarSolver.ROUNDOFF_SAFETY = args.roundoff
    if args.origin_m:
        _start_line_at(args.origin_m)
    scenario = load_scenario(args.scenario, [], k_override=K)
    if args.vehicle:
        changes = {name: float(value) for name, value in (item.split("=", 1) for item in args.vehicle)}
        scenario = dataclasses.replace(scenario, vehicle=dataclasses.replace(scenario.vehicle, **changes))
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
