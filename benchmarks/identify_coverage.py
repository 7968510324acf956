"""Coverage of identify's 95 % profile interval for k (not a test: ~15 min on 2 cores).

    python benchmarks/identify_coverage.py [--seeds 50] [--k 10] [--jobs 2]

Per seed: a synthetic record of scenarios/rig_sine_1hz.yaml (20 mm, 1 Hz) cut to 60 s, made at
the true k by LSODA (cosim.identify.synthetic) with the example's noise, then k fitted alone.
Prints per seed the estimate and its interval, then the fraction of intervals that hold the true
k (a correct 95 % interval: 90-99 % over 50 seeds is what chance allows, the binomial 95 % range
being 88-100 %), the median relative error and the median wall time of a fit.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def one(args):
    seed, k, folder = args
    import yaml

    from cosim.identify.data import read_measurements
    from cosim.identify.fit import fit_k
    from cosim.identify.model import RigModel
    from cosim.identify.synthetic import NOISE, sine_record, write_csv
    data = yaml.safe_load((ROOT / "scenarios" / "rig_sine_1hz.yaml").read_text())
    data["test"]["duration_s"] = 60.0
    scenario = Path(folder) / "rig.yaml"
    scenario.write_text(yaml.safe_dump(data))
    path = write_csv(Path(folder) / f"seed{seed}.csv", sine_record(scenario, k, NOISE, seed))
    t0 = time.perf_counter()
    e = fit_k(RigModel(scenario, (), read_measurements(path))).estimates[0]
    return seed, e.value, e.ci_low, e.ci_high, time.perf_counter() - t0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=50)
    ap.add_argument("--k", type=float, default=10.0)
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as folder, ProcessPoolExecutor(args.jobs) as pool:
        results = []
        for seed, value, lo, hi, wall in pool.map(one, [(s, args.k, folder) for s in range(args.seeds)]):
            hit = lo <= args.k <= hi
            results.append((value, hit, wall))
            print(f"seed {seed:3d}: k = {value:.4g} W/K, 95 % interval {lo:.4g} ... {hi:.4g} {'covers' if hit else 'MISSES'}"
                  f"  ({wall:.1f} s)", flush=True)
    covered = sum(h for _, h, _ in results) / len(results)
    err = statistics.median(abs(v / args.k - 1.0) for v, _, _ in results)
    print(f"coverage {covered:.0%} over {len(results)} seeds (true k = {args.k:g} W/K); median |error| {err:.2%}; "
          f"median wall of a fit {statistics.median(w for *_, w in results):.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
