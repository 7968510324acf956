"""Coupling error of the co-simulation at the default macro-step, against much smaller steps.

    python benchmarks/coupling_error.py [--k 0,100,inf] [--hold 10]

Runs the twist scenario (shortened hold) three times:
  A. the scenario's settings: macro-step H (--H to override), multibody step H;
  B. reference: H = 0.5 ms, multibody step 0.5 ms;
  C. macro-step H with the multibody step of B (0.5 ms): C - B is the coupling error alone,
     A - B the total discretisation error of the settings A.
Prints dqq_max per k and the largest wheel-load differences.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cosim.cli import _k_list  # noqa: E402
from cosim.kinds.twist import simulate  # noqa: E402
from cosim.load import load_scenario  # noqa: E402


def run(k, hold, H, h_mech):
    s = load_scenario(ROOT / "scenarios" / "twist_dqq.yaml",
                      [f"twist.hold_s={hold}", f"solver.macro_step_s={H}", f"solver.mechanics_step_s={h_mech}",
                       "solver.output_interval_s=0.01"], k)
    t0 = time.perf_counter()
    ds, _ = simulate(s)
    order = ("time", "wheel", "case")
    return (ds["wheel_load_N"].transpose(*order).values, ds["dqq"].transpose(*order).values,
            time.perf_counter() - t0)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--k", type=_k_list, default=[0.0, 100.0, float("inf")])
    p.add_argument("--hold", type=float, default=10.0)
    p.add_argument("--H", type=float, default=None, help="macro-step and multibody step of A and C [s] "
                                                           "(default: the scenario's)")
    a = p.parse_args()
    H = a.H or load_scenario(ROOT / "scenarios" / "twist_dqq.yaml").solver.macro_step_s
    A = run(a.k, a.hold, H, H)
    B = run(a.k, a.hold, 0.0005, 0.0005)
    C = run(a.k, a.hold, H, 0.0005)
    Q0 = A[0][0].mean()
    print(f"twist, ramp 5 s + hold {a.hold:g} s, k = {a.k}, H = {H * 1e3:g} ms; static wheel load {Q0:.0f} N")
    print(f"wall: A {A[2]:.1f} s, B {B[2]:.1f} s, C {C[2]:.1f} s")
    for j, k in enumerate(a.k):
        print(f"k = {k:g}: dqq_max A {A[1][..., j].max():.5f}  B {B[1][..., j].max():.5f}  C {C[1][..., j].max():.5f} | "
              f"max |Q_A - Q_B| {np.abs(A[0][..., j] - B[0][..., j]).max():.1f} N (total), "
              f"max |Q_C - Q_B| {np.abs(C[0][..., j] - B[0][..., j]).max():.2f} N (coupling only)")


if __name__ == "__main__":
    main()
