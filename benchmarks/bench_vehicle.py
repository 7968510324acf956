"""Wall time of the exudyn car model per simulated second (not run as a test).

Emulates the co-simulation master: every macro-step it reads the bellow crushing, sets the bellow
forces of an adiabatic bellow+tank pair linearised about the static state (F = F0 + k z,
k = 243 kN/m, paper Table 2) with dF/dz = k, advances the car and reads the wheel loads. The rails
under 1R and 2R rise by 5 mm (half-cosine over 5 s), as in a twist test.

    python benchmarks/bench_vehicle.py            # full table (~1 min)
    python benchmarks/bench_vehicle.py --quick    # fewer runs, shorter horizon

Prints, per (macro-step, internal step), the median over the runs of wall seconds per simulated
second, Newton iterations per internal step and fresh Jacobians, plus a split of one macro-step
(bellow_crushing, set_bellow_forces, advance, wheel_loads_N) in microseconds.
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from vehicle.car import MetroCar
from vehicle.params import VehicleParams

K_ADIABATIC_N_PER_M = 243e3  # paper Table 2, bellow + tank, adiabatic
TWIST_M = 0.005
RAMP_S = 5.0


def rail_height_m(t: float) -> np.ndarray:
    z = np.zeros(8)
    z[1] = z[3] = 0.5 * TWIST_M * (1.0 - np.cos(np.pi * min(t / RAMP_S, 1.0)))
    return z


def drive(car: MetroCar, macro_s: float, horizon_s: float, outputs=lambda car: car.wheel_loads_N()):
    """The co-simulation master's loop with emulated bellows (F = F0 + k z, dF/dz = k): returns
    the wall time [s] and the split of one macro-step (crushing, set forces, advance, outputs) [us]."""
    F0 = car.static_bellow_forces_N()
    k = np.full(4, K_ADIABATIC_N_PER_M)
    n = int(round(horizon_s / macro_s))
    split = np.zeros(4)
    pc = time.perf_counter
    start = pc()
    for i in range(n):
        t0 = pc()
        z, _ = car.bellow_crushing()
        t1 = pc()
        car.set_bellow_forces(F0 + k * z, k)
        t2 = pc()
        car.advance((i + 1) * macro_s)
        t3 = pc()
        outputs(car)
        t4 = pc()
        split += (t1 - t0, t2 - t1, t3 - t2, t4 - t3)
    return pc() - start, split / n * 1e6


def run(macro_s: float, step_s: float, horizon_s: float, reuse: bool = True) -> dict:
    car = MetroCar(VehicleParams(), rail_height_m=rail_height_m, step_s=step_s,
                   reuse_jacobian=reuse)
    wall, split_us = drive(car, macro_s, horizon_s)
    steps = horizon_s / min(step_s, macro_s)
    return {"wall_per_sim_s": wall / horizon_s,
            "newton_per_step": car._solver.it.newtonStepsCount / steps,
            "jacobians": car.jacobian_count if reuse else car._solver.it.newtonJacobiCount,
            "split_us": split_us}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1 run of 4 s per case")
    args = ap.parse_args()
    runs, horizon = (1, 4.0) if args.quick else (3, 8.0)
    cases = [(1e-3, 1e-3), (2e-3, 2e-3), (5e-3, 1e-3), (5e-3, 5e-3), (10e-3, 5e-3),
             (10e-3, 10e-3)]
    print(f"median of {runs} run(s), {horizon:g} s simulated each; '40 s' = 40 x wall/sim s")
    print(" macro   step | wall/sim s   40 s | Newton/step  Jacobians |"
          " crush  set  advance  loads [us/macro]")
    for macro, step in cases:
        res = [run(macro, step, horizon) for _ in range(runs)]
        w = statistics.median(r["wall_per_sim_s"] for r in res)
        r0 = res[0]
        sp = np.median([r["split_us"] for r in res], axis=0)
        print(f"{macro * 1e3:4.0f}ms {step * 1e3:4.0f}ms | {w:9.4f} {40 * w:6.2f} s |"
              f" {r0['newton_per_step']:10.2f} {r0['jacobians']:10d} |"
              f" {sp[0]:5.0f} {sp[1]:4.0f} {sp[2]:8.0f} {sp[3]:6.0f}")
    res = [run(5e-3, 5e-3, horizon, reuse=False) for _ in range(runs)]
    w = statistics.median(r["wall_per_sim_s"] for r in res)
    print(f"   5ms    5ms | {w:9.4f} {40 * w:6.2f} s | without Jacobian reuse"
          f" ({res[0]['jacobians']} Jacobians)")


if __name__ == "__main__":
    main()
