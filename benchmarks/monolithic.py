"""Co-simulation against the monolithic reference (cosim/verification/monolithic.py), one k, full scenarios.

    python benchmarks/monolithic.py [--k 0] [--only twist|curve] [--levels 3]
                                    [--twist-duration S] [--curve-duration S]

For each scenario (the shipped twist_dqq.yaml, and curve_entry.yaml with the valves connected):
  * the co-simulation at the scenario's own steps (macro = multibody = pneumatic step);
  * the monolithic reference at h, h/2, h/4 (--levels), h = the scenario's multibody step.
Prints the reference's convergence (values per step, observed order from the last three levels,
Richardson estimate for order 2), then the co-simulation-minus-reference differences (against the
finest reference and against its Richardson estimate) and the wall times.
Twist: dqq_max (largest ΔQ/Q0 over the run and the wheels) and ΔQ/Q0 at the last sample per
wheel. Curve: largest |roll| and its mean over the final window (relative to the track plane),
air injected from the supply and exhausted to the atmosphere.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cosim.engine.cases import build_cosimulation  # noqa: E402
from cosim.kinds import twist as twist_mod  # noqa: E402
from cosim.load import load_scenario  # noqa: E402
from cosim.runs import track_run as curve_mod  # noqa: E402
from cosim.verification.monolithic import run_monolithic  # noqa: E402

SCENARIOS = ROOT / "scenarios"
#: display scale and unit of each metric
UNITS = {"roll_max_rad": (1e3, "mrad"), "roll_mean_end_rad": (1e3, "mrad"), "air_injected_kg": (1e3, "g"),
         "air_exhausted_kg": (1e3, "g")}


def scenario(kind: str, k: float, duration: float | None):
    if kind == "twist":
        sc = load_scenario(SCENARIOS / "twist_dqq.yaml", ["solver.jobs=1"], [k])
        if duration:
            hold = duration - sc.experiment.ramp_s
            sc = sc.with_experiment(hold_s=hold, window_s=min(hold, 5.0))
        return sc, sc.experiment.duration_s, twist_mod.make_car
    sc = load_scenario(SCENARIOS / "curve_entry.yaml", ["solver.jobs=1"], [k])
    if duration:
        sc = sc.with_experiment(duration_s=duration)
    return sc.with_valves(True), sc.experiment.duration_s, curve_mod.make_car


def headlines(kind, sc, rec):
    return twist_mod.record_headlines(sc, rec) if kind == "twist" else curve_mod.record_headlines(sc, rec)


def fmt(name, v):
    s, _ = UNITS.get(name, (1.0, ""))
    return f"{v * s:.7g}"


def bench(kind: str, k: float, levels: int, duration: float | None) -> None:
    sc, T, make_car = scenario(kind, k, duration)
    H = sc.solver.mechanics_step_s
    t0 = time.perf_counter()
    cs_rec, diag = build_cosimulation(sc, [k], make_car).run(T, sc.solver.output_interval_s)
    cs_wall = time.perf_counter() - t0
    if diag:
        print(f"co-simulation diverged: {diag}")
    cs = headlines(kind, sc, cs_rec.arrays())
    refs, walls = [], []
    for i in range(levels):
        h = H / 2 ** i
        t0 = time.perf_counter()
        rec = run_monolithic(sc, k, T, h)
        walls.append((h, time.perf_counter() - t0, rec.monolithic.stats))
        refs.append(headlines(kind, sc, rec.arrays()))
    title = (f"{kind}: {sc.name}, k = {k:g} W/K, {T:g} s"
             + (", valves connected" if kind == "curve" else f", ramp {sc.experiment.ramp_s:g} s"))
    print("=" * len(title))
    print(title)
    print("=" * len(title))
    units = {m: UNITS.get(m, (1.0, "-"))[1] for m in cs}
    print(f"\nmonolithic reference (generalized-alpha, rho = 0.8), step h = {H * 1e3:g} ms:")
    head = " | ".join(f"h/{2 ** i}" if i else "h" for i in range(levels))
    print(f"| metric [unit] | {head} | order | Richardson |")
    print("|---" * (levels + 3) + "|")
    rich = {}
    for m in cs:
        v = [r[m] for r in refs]
        order, r = math.nan, v[-1]
        if levels >= 3:
            d1, d2 = v[-3] - v[-2], v[-2] - v[-1]
            if d2 != 0 and d1 / d2 > 0:
                order = math.log2(d1 / d2)
            r = v[-1] + (v[-1] - v[-2]) / 3.0          # Richardson, order 2 (generalized-alpha)
        rich[m] = r
        print(f"| {m} [{units[m]}] | " + " | ".join(fmt(m, x) for x in v) + f" | {order:.2f} | {fmt(m, r)} |")
    print(f"\nco-simulation (H = {sc.solver.macro_step_s * 1e3:g} ms, multibody {H * 1e3:g} ms, "
          f"pneumatic {sc.solver.pneumatic_step_s * 1e3:g} ms) minus monolithic:")
    print(f"| metric [unit] | co-simulation | monolithic h/{2 ** (levels - 1)} | difference | relative "
          f"| co-sim - Richardson | relative |")
    print("|---" * 7 + "|")
    for m in cs:
        ref, d, dr = refs[-1][m], cs[m] - refs[-1][m], cs[m] - rich[m]
        scale = max(abs(rich[m]), 1e-30)
        print(f"| {m} [{units[m]}] | {fmt(m, cs[m])} | {fmt(m, ref)} | {fmt(m, d)} | {d / scale:.2e} "
              f"| {fmt(m, dr)} | {dr / scale:.2e} |")
    print(f"\nwall: co-simulation {cs_wall:.1f} s; monolithic " +
          ", ".join(f"{h * 1e3:g} ms {w:.1f} s ({s.newton_iterations / max(s.steps, 1):.1f} Newton it./step, "
                    f"{s.jacobians} Jacobians)" for h, w, s in walls))
    print()


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--k", type=float, default=0.0, help="heat-transfer coefficient [W/K] (default 0)")
    p.add_argument("--only", choices=("twist", "curve"), default=None)
    p.add_argument("--levels", type=int, default=3, help="monolithic steps h, h/2, ... (default 3)")
    p.add_argument("--twist-duration", type=float, default=None, help="ramp + hold [s] (default: the scenario's)")
    p.add_argument("--curve-duration", type=float, default=None, help="[s] (default: the scenario's)")
    a = p.parse_args()
    for kind in ("twist", "curve"):
        if a.only in (None, kind):
            bench(kind, a.k, a.levels, a.twist_duration if kind == "twist" else a.curve_duration)


if __name__ == "__main__":
    main()
