"""Where a service's macro-step goes (not a test): one process's share of the cases of
``benchmarks/bench_service.py``'s line (its first stations, one way), co-simulated in this process,
against the same cars driven alone (:func:`bench_vehicle.drive`), in microseconds per macro-step.

    python benchmarks/profile_service.py                         # 2 stations, k = 0 and 100, 40 s
    python benchmarks/profile_service.py --k 10,inf --duration 116
    python benchmarks/profile_service.py --wall                  # wall time instead of CPU time

CPU time by default (``time.process_time``): on a machine shared with other work the wall time
of a part is mostly the others' load. Each part is timed by wrapping the master's methods (about
a microsecond per call of its own); the master's rest is the step less its parts. The first 0.2 s
are run before timing (the compiled laws loaded).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_service import LINE
from bench_vehicle import drive

from cosim.engine.cases import build_cosimulation
from cosim.kinds import service
from cosim.load import load_scenario

PARTS = (("car.advance", "cars: advance (exudyn)"), ("car.set_bellow_forces", "cars: set the force laws"),
         ("_crushing", "cars: crushing read"), ("_force_laws", "circuit: force laws (derivatives_and_held, dF/dt, K)"),
         ("_advance_air", "circuit: RK4 over the step"), ("_stop_impossible_cars", "watch: bellows, cars"),
         ("_stop_impossible_air", "watch: air"), ("_stop_diverged", "divergence check"), ("sample", "outputs (sampling)"))


def scenario_of(stations: int):
    """The shipped line cut to its first ``stations`` stations, one way (as bench_service cuts it)."""
    base = load_scenario(LINE)
    keep = base.experiment.stations[:stations]
    text = ", ".join("{" + f"name: {s.name}, at_m: {s.at_m:g}, dwell_s: {s.dwell_s:g}, platform_side: "
                     f"{s.platform_side}, alighting: {s.alighting}, boarding: {s.boarding}" + "}" for s in keep)
    curves = ", ".join("{" + f"at_m: {c.at_m:g}, radius_m: {c.radius_m:g}, arc_m: {c.arc_m:g}, transition_m: "
                       f"{c.transition_m:g}, direction: {c.direction}, cant_rad: {c.cant_rad:g}" + "}"
                       for c in base.experiment.curves if c.at_m + 2 * c.transition_m + c.arc_m < keep[-1].at_m)
    return load_scenario(LINE, ["service.round_trip=false", f"service.stations=[{text}]", f"service.curves=[{curves}]"])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--stations", type=int, default=2)
    ap.add_argument("--k", default="0,100", help="the k values of the process (bench_service: 0,100 and 10,inf)")
    ap.add_argument("--duration", type=float, default=40.0, help="simulated seconds after the first 0.2 s")
    ap.add_argument("--wall", action="store_true", help="wall time instead of CPU time")
    args = ap.parse_args(argv)
    clock = time.perf_counter if args.wall else time.process_time
    k = [float(v) for v in args.k.split(",")]
    scenario = scenario_of(args.stations)
    H = scenario.solver.macro_step_s
    spent = dict.fromkeys(["step", *(name for name, _ in PARTS)], 0.0)

    def timed(obj, name, key=None):
        method, key = getattr(obj, name), key or name

        def wrapper(*a, **kw):
            t0 = clock()
            try:
                return method(*a, **kw)
            finally:
                spent[key] += clock() - t0
        setattr(obj, name, wrapper)

    sim = build_cosimulation(scenario, k, service.make_car, service.outputs(scenario.experiment))
    sim.run(0.2, scenario.solver.output_interval_s)
    for name in ("step", "sample", *(n for n, _ in PARTS if not n.startswith("car."))):
        timed(sim, name)
    for car in sim.cars:
        timed(car, "advance", "car.advance")
        timed(car, "set_bellow_forces", "car.set_bellow_forces")
    n = round(args.duration / H)
    newton0 = [car.solver._it.newtonStepsCount for car in sim.cars]
    t0 = clock()
    sim.run(args.duration, scenario.solver.output_interval_s)
    total = clock() - t0
    newton = [(car.solver._it.newtonStepsCount - a) / n for car, a in zip(sim.cars, newton0)]

    alone, newton_alone = 0.0, []
    for _ in k:
        car = service.make_car(scenario)
        t1 = clock()
        drive(car, H, 0.2 + args.duration)
        alone += clock() - t1
        newton_alone.append(car.solver._it.newtonStepsCount / round((0.2 + args.duration) / H))
    alone *= n / round((0.2 + args.duration) / H)

    us = 1e6 / n
    within_step = sum(v for key, v in spent.items() if key not in ("step", "sample"))
    print(f"{'clock' if args.wall else 'CPU'} time per macro-step of {H * 1e3:g} ms, {len(k)} cars (k = {args.k}), "
          f"{args.duration:g} s of {args.stations} stations one way")
    for name, label in PARTS:
        print(f"  {label:55s} {spent[name] * us:8.1f} us")
    print(f"  {'master: the rest of the step (motion, F_end, arrays)':55s} "
          f"{(spent['step'] - within_step) * us:8.1f} us")
    print(f"  {'master: the loop (progress, sampling test)':55s} {(total - spent['step'] - spent['sample']) * us:8.1f} us")
    print(f"  {'co-simulation in all':55s} {total * us:8.1f} us")
    print(f"  {'the same cars alone (bench_vehicle.drive)':55s} {alone * us:8.1f} us   ratio {total / alone:.2f}")
    print(f"  Newton iterations per step: co-simulation {[round(v, 2) for v in newton]}, alone "
          f"{[round(v, 2) for v in newton_alone]}")


if __name__ == "__main__":
    main()
