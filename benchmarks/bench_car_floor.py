"""Where a ride's macro-step goes inside the car, by exudyn's own timers: how much of the 15x
budget (1/15 of a 5 ms macro-step = 333 us per case) exudyn's C++ work takes by itself, how much
the car's Python takes (the contact law called at every Newton residual, the PreStep and
PostStep), and what a call from exudyn into Python costs bare. Not run as a test.

    python benchmarks/bench_car_floor.py                    # 20 m/s, k = 10, 10 s simulated
    python benchmarks/bench_car_floor.py --speed 15 --set ride.radius_m=300 \\
        --set ride.cant_rad=0.1 --set ride.transition_m=30

exudyn's timers (``MainSolverImplicitSecondOrder.timer``) split the step: the residual's right-hand
side (ODE2RHS, which holds the contact law's Python call), the mass matrix (computed at every
residual: the Rxyz bodies' mass matrices depend on their rotation), the constraints' reaction
forces and algebraic equations, the linear solves, and the Python PreStep/PostStep ("python").
"C++ only" is their sum less the contact law's calls (timed around the call) and the PreStep and
PostStep: what no change on the Python side can remove at these steps, Newton iterations and
model. The timers and the wrapper add ~1 us per call to what they time.
"""
from __future__ import annotations

import statistics
import time

import exudyn as exu
import numpy as np
from bench_ride import build, ride_arguments, ride_case

TIMERS = ("ODE2RHS", "massMatrix", "reactionForces", "AERHS", "factorization", "newtonIncrement",
          "integrationFormula", "python")


def instrument(car, totals: dict) -> None:
    """Turn on ``car``'s solver timers and time its contact law's calls and its advance."""
    car._solver.timer.useTimer = True
    contact = car._wr
    forces, advance = contact.forces, car.advance

    def timed_forces(q, q_t):
        t0 = time.perf_counter()
        try:
            return forces(q, q_t)
        finally:
            totals["contact"] += time.perf_counter() - t0
            totals["contact_calls"] += 1

    def timed_advance(t_end_s):
        t0 = time.perf_counter()
        try:
            return advance(t_end_s)
        finally:
            totals["advance"] += time.perf_counter() - t0
    contact.forces = timed_forces
    car.advance = timed_advance


def bare_crossing_us(repeat: int = 5, calls: int = 20000) -> float:
    """A Newton residual of a 28-coordinate ``ObjectGenericODE2`` (the contact object's size) with a
    force user function that returns a stored array, less the same without it [us, median]."""
    def residual_us(with_function: bool) -> float:
        mbs = exu.SystemContainer().AddSystem()
        nodes = [mbs.AddNode(exu.itemInterface.NodeGenericODE2(
            referenceCoordinates=[0.0] * 7, initialCoordinates=[0.0] * 7, initialCoordinates_t=[0.0] * 7,
            numberOfODE2Coordinates=7)) for _ in range(4)]
        zero = np.zeros(28)
        extra = {"forceUserFunction": lambda mbs, t, i, q, q_t: zero} if with_function else {}
        mbs.AddObject(exu.itemInterface.ObjectGenericODE2(
            nodeNumbers=nodes, massMatrix=np.eye(28), stiffnessMatrix=1e3 * np.eye(28), **extra))
        mbs.Assemble()
        settings = exu.SimulationSettings()
        settings.solution.file.write = False
        solver = exu.MainSolverImplicitSecondOrder()
        solver.InitializeSolver(mbs, settings)
        runs = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            for _ in range(calls):
                solver.ComputeNewtonResidual(mbs, settings)
            runs.append(1e6 * (time.perf_counter() - t0) / calls)
        return statistics.median(runs)
    return residual_us(True) - residual_us(False)


def main() -> int:
    args = ride_arguments(__doc__.splitlines()[0], seconds=10.0).parse_args()
    scenario, k_values = ride_case(args)
    cosim = build(scenario, k_values)
    totals = dict.fromkeys(("contact", "contact_calls", "advance"), 0.0)
    cars = cosim.cars
    for car in cars:
        instrument(car, totals)
    t0 = time.perf_counter()
    _, diagnosis = cosim.run(args.seconds, scenario.solver.output_interval_s)
    wall = time.perf_counter() - t0
    if diagnosis:
        raise SystemExit(f"the run failed: {diagnosis}")
    H = scenario.solver.macro_step_s
    steps = round(args.seconds / H) * len(cars)  # car-steps
    budget = 1e6 * H / 15.0

    def per_step(seconds: float) -> float:
        return 1e6 * seconds / steps

    timers = {name: per_step(sum(getattr(c._solver.timer, name) for c in cars)) for name in TIMERS}
    contact = per_step(totals["contact"])
    cpp = sum(timers.values()) - timers["python"] - contact
    newton = sum(c._solver.it.newtonStepsCount for c in cars) / steps
    calls = totals["contact_calls"] / steps
    print(f"{len(cars)} car(s) at {args.speed:g} m/s, {args.seconds:g} s, steps of {1e3 * H:g} ms; "
          f"the 15x budget: {budget:.0f} us per case and macro-step")
    print(f"whole macro-step per case: {per_step(wall):.0f} us; the car's advance: "
          f"{per_step(totals['advance']):.0f} us")
    print(f"Newton iterations per step {newton:.2f}, contact-law calls per step {calls:.2f}")
    print("exudyn's timers per step [us]: " + ", ".join(f"{k} {v:.1f}" for k, v in timers.items()))
    print(f"the contact law's calls: {contact:.0f} us per step ({contact / calls:.2f} us per call)")
    print(f"C++ only: {cpp:.0f} us per step = {100 * cpp / budget:.0f} % of the budget, "
          f"{cpp / calls:.1f} us per residual evaluation")
    print(f"a bare call into Python from a residual (28 coordinates): {bare_crossing_us():.2f} us")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
