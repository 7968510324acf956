"""Wall time of the running exudyn car on the paper's curve entry (not run as a test).

Paper section 4.2: 10 m/s, straight, 15 m clothoid, R = 100 m arc, no cant; here 30 m of
straight (the car starts with its rear wheelset at s = 0) and 30 s simulated (300 m). Emulates
the co-simulation master as benchmarks/bench_vehicle.py does: every macro-step it reads the
bellow crushing, sets the forces of an adiabatic bellow+tank pair linearised about the static
state (F = F0 + k z, dF/dz = k = 243 kN/m, paper Table 2), advances the car and reads the
wheel loads, the carbody roll and lateral offset.

    python benchmarks/bench_vehicle_curve.py            # 3 runs per case (~1 min)
    python benchmarks/bench_vehicle_curve.py --quick    # 1 run of the default case
    python benchmarks/bench_vehicle_curve.py --contact  # contact against kinematic guidance
    python benchmarks/bench_vehicle_curve.py --ceiling  # ... and the time inside the contact law

``--contact``: the same curve entry with ``guidance="contact"`` (free wheelsets on
the S1002/UIC60 contact) and with the default kinematic guidance, alternately, 5 ms macro and
internal steps, median of 3 runs each (``--runs``): wall time per 30 s, the ratio, Newton
iterations per step, Jacobians, contact-law evaluations per step, and the 1R wheel's Q, Y/Q at
the end as a check.

Prints, per (macro-step, internal step), the median over the runs of the wall time per 30 s
simulated, Newton iterations per internal step, fresh Jacobians, the split of one macro-step
(bellow_crushing, set_bellow_forces, advance, outputs) in microseconds, and the cost of the
PreStep user function (track, guidance, end moments, rail couples) per internal step. The end
roll is printed as a check that all cases compute the same thing.
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from bench_vehicle import drive  # same folder: the master's loop with emulated bellows

from vehicle.car import MetroCar
from vehicle.params import VehicleParams
from vehicle.track import TrackGeometry

SPEED_M_PER_S = 10.0
HORIZON_S = 30.0


def paper_track() -> TrackGeometry:
    return TrackGeometry.curve_entry(straight_m=30.0, transition_m=15.0, radius_m=100.0,
                                     arc_m=SPEED_M_PER_S * HORIZON_S + 10.0)


def run(macro_s: float, step_s: float, horizon_s: float = HORIZON_S,
        time_prestep: bool = False, guidance: str = "kinematic") -> dict:
    car = MetroCar(VehicleParams(), step_s=step_s, track=paper_track(),
                   speed_m_per_s=SPEED_M_PER_S, guidance=guidance)
    law_calls = [0]
    if guidance == "contact":  # count the contact-law evaluations (adds ~0.2 us per call)
        forces = car._wr.forces

        def counted(q, q_t):
            law_calls[0] += 1
            return forces(q, q_t)

        car._wr.forces = counted
    prestep = [0.0, 0]
    if time_prestep:  # wrap the PreStep user function to time it (adds ~0.3 us per call)
        inner = car._pre_step

        def timed(mbs, t):
            t0 = time.perf_counter()
            ok = inner(mbs, t)
            prestep[0] += time.perf_counter() - t0
            prestep[1] += 1
            return ok

        car.mbs.SetPreStepUserFunction(timed)
    wall, split_us = drive(car, macro_s, horizon_s,
                           lambda c: (c.wheel_loads_N(), c.carbody_roll_rad(), c.carbody_lateral_m()))
    steps = horizon_s / min(step_s, macro_s)
    return {"wall_per_30s": wall / horizon_s * 30.0,
            "newton_per_step": car._solver.it.newtonStepsCount / steps,
            "jacobians": car.jacobian_count, "split_us": split_us,
            "prestep_us": prestep[0] / max(prestep[1], 1) * 1e6,
            "roll_end_rad": car.carbody_roll_rad(), "law_per_step": law_calls[0] / steps,
            "Q_1R": car.wheel_loads_N()[1], "Y_1R": car.lateral_wheel_forces_N()[1]}


def law_ceiling(runs: int, horizon_s: float) -> None:
    """The time spent inside the contact's force and Jacobian user functions (compiled kernels
    since the law was compiled; the Python law's 2.07 s and 0.18 s per 30 s before), timed
    around the calls, and the contact/kinematic ratio with that time taken out (medians of
    ``runs`` alternating runs): what is left to gain in the law."""
    walls = {"kinematic": [], "contact": []}
    law, jac = [], []
    for _ in range(runs):
        for guidance in walls:
            car = MetroCar(VehicleParams(), step_s=5e-3, track=paper_track(),
                           speed_m_per_s=SPEED_M_PER_S, guidance=guidance)
            spent = {"forces": 0.0, "jacobian": 0.0}
            if guidance == "contact":
                for name in spent:
                    inner = getattr(car._wr, name)

                    def timed(*args, inner=inner, name=name):
                        t0 = time.perf_counter()
                        out = inner(*args)
                        spent[name] += time.perf_counter() - t0
                        return out

                    setattr(car._wr, name, timed)
            wall, _ = drive(car, 5e-3, horizon_s, lambda c: (c.wheel_loads_N(), c.carbody_roll_rad()))
            walls[guidance].append(wall)
            if guidance == "contact":
                law.append(spent["forces"])
                jac.append(spent["jacobian"])
    kin, con = statistics.median(walls["kinematic"]), statistics.median(walls["contact"])
    f, j = statistics.median(law), statistics.median(jac)
    print(f"curve entry, {horizon_s:g} s, 5 ms steps, median of {runs}: kinematic {kin:.2f} s, "
          f"contact {con:.2f} s (law {f:.2f} s, Jacobian {j:.2f} s)")
    print(f"contact / kinematic: {con / kin:.2f}; without the law's time {(con - f) / kin:.2f}; "
          f"without the law's and the Jacobian's {(con - f - j) / kin:.2f}")


def compare_guidance(runs: int, horizon_s: float) -> None:
    """Contact against kinematic guidance on the curve entry (see the module doc)."""
    print(f"curve entry, {horizon_s:g} s simulated at {SPEED_M_PER_S:g} m/s, 5 ms steps; "
          f"median of {runs} run(s) per guidance, alternating")
    res = {"kinematic": [], "contact": []}
    for _ in range(runs):
        for guidance in res:
            res[guidance].append(run(5e-3, 5e-3, horizon_s, guidance=guidance))
    print(" guidance  | wall/30 s | Newton/step  Jacobians  law calls/step | roll_end [rad]"
          " | Q_1R [kN]  Y/Q_1R")
    walls = {}
    for guidance, rs in res.items():
        walls[guidance] = statistics.median(r["wall_per_30s"] for r in rs)
        r0 = rs[0]
        print(f" {guidance:9s} | {walls[guidance]:8.3f} s | {r0['newton_per_step']:10.2f}"
              f" {r0['jacobians']:10d} {r0['law_per_step']:14.2f} | {r0['roll_end_rad']:.6f}"
              f"      | {r0['Q_1R'] / 1e3:8.2f}  {r0['Y_1R'] / r0['Q_1R']:6.3f}")
    print(f"contact / kinematic: {walls['contact'] / walls['kinematic']:.2f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1 run of the 5 ms / 5 ms case")
    ap.add_argument("--contact", action="store_true",
                    help="contact against kinematic guidance")
    ap.add_argument("--ceiling", action="store_true",
                    help="contact: the time inside the law, and the ratio to kinematic without it")
    ap.add_argument("--runs", type=int, default=3, help="runs per guidance with --contact")
    ap.add_argument("--horizon", type=float, default=HORIZON_S,
                    help="simulated seconds with --contact")
    args = ap.parse_args()
    if args.ceiling:
        law_ceiling(args.runs, args.horizon)
        return
    if args.contact:
        compare_guidance(args.runs, args.horizon)
        return
    runs = 1 if args.quick else 3
    cases = [(5e-3, 5e-3)] if args.quick else [(5e-3, 5e-3), (5e-3, 2.5e-3), (10e-3, 5e-3),
                                               (10e-3, 10e-3)]
    print(f"curve entry, {HORIZON_S:g} s simulated at {SPEED_M_PER_S:g} m/s; "
          f"median of {runs} run(s)")
    print(" macro   step | wall/30 s | Newton/step  Jacobians |"
          " crush  set  advance  outputs [us/macro] | roll_end [rad]")
    for macro, step in cases:
        res = [run(macro, step) for _ in range(runs)]
        w = statistics.median(r["wall_per_30s"] for r in res)
        r0 = res[0]
        sp = np.median([r["split_us"] for r in res], axis=0)
        print(f"{macro * 1e3:4.0f}ms {step * 1e3:4.1f}ms | {w:8.3f} s |"
              f" {r0['newton_per_step']:10.2f} {r0['jacobians']:10d} |"
              f" {sp[0]:5.0f} {sp[1]:4.0f} {sp[2]:8.0f} {sp[3]:8.0f} | {r0['roll_end_rad']:.6f}")
    r = run(5e-3, 5e-3, horizon_s=10.0, time_prestep=True)
    print(f"PreStep user function (5 ms steps, 10 s): {r['prestep_us']:.1f} us per internal step")


if __name__ == "__main__":
    main()
