"""The car over the track users give it: cant x speed x radius x transition length, in both
guidance modes, at the shipped steps (not a test; tests/cosim/kinds/test_real_track.py runs a corner of it).

    python benchmarks/track_matrix.py                       # the full matrix, both guidances
    python benchmarks/track_matrix.py --guidance contact --cant 0.1016 --speed 10 --radius 100 --transition 15
    python benchmarks/track_matrix.py --set solver.spectral_radius=0.8 --set track=flexible
    python benchmarks/track_matrix.py --verify              # + every step halved twice per case

Each case is the curve entry of ``scenarios/curve_entry.yaml`` (k = inf, valves off: the
pneumatics, k and the valves were switched and ruled out as causes of the canted-track failures)
with the cant, speed, radius and transition length of the matrix, and the default transition
shape (``bloss``; the file's own is the paper's clothoid: ``--set curve.transition_shape=linear``
runs that); the run lasts until the car has been 8 s (and at least 20 m) in the arc. Printed
per case:

* outcome: ``ok`` (ran to its end), ``stop`` (an impossible state stopped it: a capsized or
  derailed car, :class:`cosim.scenario.model.StateLimits`) or ``DIVERGED`` (a solver gave up);
* ΣY against the balance (contact guidance): the mean over the last 6 s of the four wheelsets'
  lateral forces minus M (v²/R cos c - g sin c), in % of the larger of M v²/R and M g sin c
  (six periods of the ~1 Hz carbody sway, which nothing damps with the valves off at k = inf);
* ΔQ/Q0: the largest EN 14363 2 m sliding mean over the run (and the sampled peak), its 99.85 %
  percentile over the worst test zone, the number of EN 14363 criteria the case fails and the
  zones it crossed (cosim/limits/assessment.py);
* with ``--verify``: the largest estimated error of the case's headline metrics
  (``pneumorail verify``'s Richardson estimates, floors and all) and whether it passes 0.5 %.

A physically impossible case (25 m/s into R = 100 m without cant: 6.25 m/s² of unbalanced
acceleration, beyond this car's overturning limit) is expected to stop, with the same
diagnosis at every step size.
"""
from __future__ import annotations

import argparse
import itertools
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from cosim.kinds import KINDS
from cosim.load import load_scenario
from cosim.runner import run
from cosim.runs.track_spec import CurveTest
from cosim.verification.verify import estimates, refined

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "curve_entry.yaml"
CANTS = (0.0, 0.05, 0.1, 0.15)
SPEEDS = (2.5, 10.0, 25.0)
RADII = (100.0, 300.0, 1000.0)
TRANSITIONS = (10.0, 30.0, 100.0)
#: the transition shape a scenario gets when it names none
DEFAULT_SHAPE = CurveTest().transition_shape
#: the car is this long between its outer wheelsets, and starts with the rear one at s = 0
CAR_M = 12.0
STRAIGHT_M = 20.0


def scenario_of(guidance: str, cant: float, speed: float, radius: float, transition: float, extra=()):
    """The curve entry of one matrix case (see the module docstring); ``extra``: overrides."""
    in_arc_s = max(8.0, 20.0 / speed)
    duration = (STRAIGHT_M - CAR_M + transition + CAR_M) / speed + in_arc_s
    arc = speed * in_arc_s + CAR_M + 5.0
    sets = [f"curve.guidance={guidance}", f"curve.cant_rad={cant}", f"curve.speed_m_per_s={speed}",
            f"curve.radius_m={radius}", f"curve.transition_m={transition}", f"curve.arc_m={arc}",
            f"curve.duration_s={duration:.6g}", "curve.valve_settings=[false]", "solver.jobs=1",
            f"curve.transition_shape={DEFAULT_SHAPE}",
            f"solver.output_interval_s={0.005 * max(1, min(4, round(0.2 / speed / 0.005))):.6g}", *extra]
    return load_scenario(SCENARIO, sets, [math.inf])


def balance(outcome) -> float:
    """Mean ΣY over the last 6 s minus M (v²/R cos c - g sin c), in % of the larger term."""
    sc = outcome.scenario
    ds = outcome.series["curve"]
    if "wheelset_lateral_force_N" not in ds:
        return math.nan
    t = ds["time"].values
    sum_y = ds["wheelset_lateral_force_N"].isel(case=0).sum("wheelset").values
    last = t >= t[-1] - 6.0
    p, c = sc.vehicle, sc.experiment
    M = p.carbody_mass_kg + 2 * p.bogie_mass_kg + 4 * p.wheelset_mass_kg
    g = p.gravity_m_per_s2
    v2R = c.speed_m_per_s ** 2 / c.radius_m
    target = M * (v2R * math.cos(c.cant_rad) - g * math.sin(c.cant_rad))
    scale = max(M * v2R, M * g * abs(math.sin(c.cant_rad)))
    return 100.0 * (float(np.mean(sum_y[last])) - target) / scale


def one(args) -> dict:
    """One matrix case (and its verify levels with ``verify``)."""
    key, verify, extra = args
    t0 = time.perf_counter()
    scenario = scenario_of(*key, extra=extra)
    outcome = run(scenario)
    row = outcome.rows[0]
    out = {"key": key, "wall_s": time.perf_counter() - t0,
           "outcome": ("DIVERGED" if "impossible state" not in outcome.diverged else "stop") if outcome.diverged else "ok",
           "diagnosis": outcome.diverged or "", "balance_pct": balance(outcome),
           "dqq_2m_max": row["dqq_2m_max"], "dqq_raw_max": row["dqq_raw_max"],
           "dqq_2m_p9985": row.get("dqq_2m_p9985", float("nan")), "failed": row.get("en14363_failed", -1),
           "zones": ",".join(outcome.info.get("zones", []))}
    if verify:
        rows = [[outcome.rows[0]]]
        stops = [outcome.diverged]
        for level in (1, 2):
            finer = run(refined(scenario, level))
            rows.append([finer.rows[0]])
            stops.append(finer.diverged)
        if any(stops):  # a stop is verified by its time and place at every level
            out["diagnosis"] = "\n      ".join(f"level {i}: {d or 'ran to its end'}" for i, d in enumerate(stops))
            out["verify"] = ("stops", math.nan)
        else:
            found = estimates(rows, KINDS[scenario.kind].headline_metrics, KINDS[scenario.kind].case_columns)
            worst = max(found, key=lambda e: e.error)
            out["verify"] = (worst.metric, worst.error)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--guidance", choices=("kinematic", "contact"), action="append")
    ap.add_argument("--cant", type=float, action="append")
    ap.add_argument("--speed", type=float, action="append")
    ap.add_argument("--radius", type=float, action="append")
    ap.add_argument("--transition", type=float, action="append")
    ap.add_argument("--set", action="append", default=[], help="a scenario override for every case")
    ap.add_argument("--verify", action="store_true", help="also halve every step twice per case")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args(argv)
    keys = list(itertools.product(args.guidance or ("kinematic", "contact"), args.cant or CANTS,
                                  args.speed or SPEEDS, args.radius or RADII, args.transition or TRANSITIONS))
    print(f"{len(keys)} cases, overrides {args.set or '-'}; columns: guidance, cant [rad], v [m/s], R [m], "
          f"L [m]: outcome, ΣY - balance [% of the larger term], ΔQ/Q0 2 m max (sampled), wall [s]"
          + (", largest verify error" if args.verify else ""), flush=True)
    tasks = [(k, args.verify, tuple(args.set)) for k in keys]
    counts = {"ok": 0, "stop": 0, "DIVERGED": 0}
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.jobs) as pool:
        for r in pool.map(one, tasks):
            counts[r["outcome"]] += 1
            g, c, v, R, L = r["key"]
            line = (f"{g:9s} {c:6.4g} {v:5.3g} {R:6.4g} {L:5.3g}: {r['outcome']:8s} "
                    f"{r['balance_pct']:+7.3f} %  {r['dqq_2m_max']:.3f} ({r['dqq_raw_max']:.3f}) "
                    f"p99.85 {r['dqq_2m_p9985']:.3f} EN14363 failed {r['failed']} [{r['zones']}]  {r['wall_s']:5.1f} s")
            if args.verify:
                metric, err = r["verify"]
                line += (f"  {100 * err:.3f} % ({metric}){'' if err <= 0.005 else '  > 0.5 %'}"
                         if metric != "stops" else "  (stops: see the levels)")
            if r["diagnosis"]:
                line += f"\n      {r['diagnosis'][:300]}"
            print(line, flush=True)
    print(f"{counts} in {time.perf_counter() - t0:.0f} s")
    return 1 if counts["DIVERGED"] else 0


if __name__ == "__main__":
    sys.exit(main())
