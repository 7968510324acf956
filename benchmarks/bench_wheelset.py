"""Wall time of the free wheelset with wheel-rail contact (vehicle.wheelrail.wheelset), not run
as a test.

Two running cases on the default S1002 / UIC60 1:40 pair at 10 m/s:

* straight: released at y = 3 mm (the Klingel check's situation), 4 s simulated;
* curve: left curve R = 1000 m entered by a 100 m half-cosine transition, 19 s simulated
  (the free-curving check's situation),

each with the contact law as a Python user function and as an exudyn symbolic user function
(the same law, :mod:`vehicle.wheelrail.contact_law`), at internal steps of 2 and 5 ms. Prints
the median over the runs of wall seconds per simulated second, Newton iterations per step,
Jacobians, contact-law calls per step (Python runs: counted), the cost of one call of each law
at a typical state (the symbolic one through ``UserFunction.Evaluate``, which adds the Python
interface), and a physics check per case (Klingel wavelength, settled y vs pure rolling).

    python benchmarks/bench_wheelset.py            # 3 runs per case (~1 min)
    python benchmarks/bench_wheelset.py --quick    # 1 run per case, 2 ms only
"""
from __future__ import annotations

import argparse
import math
import statistics
import time

from scipy.optimize import brentq

from vehicle.wheelrail.contact_law import ContactLawTable
from vehicle.wheelrail.geometry import ContactTable
from vehicle.wheelrail.wheelset import FreeWheelset

V = 10.0
R = 1000.0
TRANSITION_M = 100.0


def transition(s: float) -> float:
    return 0.5 * (1.0 - math.cos(math.pi * min(s, TRANSITION_M) / TRANSITION_M)) / R


def build(table: ContactLawTable, case: str, law: str, step: float) -> FreeWheelset:
    if case == "straight":
        return FreeWheelset(table, speed_m_per_s=V, y0_m=0.003, force_law=law, step_s=step)
    return FreeWheelset(table, speed_m_per_s=V, curvature_per_m=transition, force_law=law,
                        step_s=step)


def one(table, case, law, step) -> dict:
    ws = build(table, case, law, step)
    calls = [0]
    if law == "python":
        f0 = ws._python_force

        def counted(*args):
            calls[0] += 1
            return f0(*args)

        ws.mbs.SetObjectParameter(ws.contact, "forceUserFunction", counted)
    horizon = 4.0 if case == "straight" else 19.0
    run = ws.run(horizon)
    it = ws.mbs.sys["dynamicSolver"].it
    steps = run.steps
    return {"wall_per_sim_s": run.wall_s / horizon, "newton": it.newtonStepsCount / steps,
            "jac": it.newtonJacobiCount, "calls": calls[0] / steps if calls[0] else float("nan"),
            "check": check(table, case, run)}


def check(table, case, run) -> str:
    t = table.table
    s, y = run.distance_m, run.y
    if case == "straight":
        zc = [s[i] - y[i] * (s[i + 1] - s[i]) / (y[i + 1] - y[i])
              for i in range(len(y) - 1) if (y[i] > 0) != (y[i + 1] > 0)]
        L = zc[2] - zc[0]
        A = 0.5 * (max(abs(y[(s >= zc[0]) & (s <= zc[1])])) +
                   max(abs(y[(s >= zc[1]) & (s <= zc[2])])))
        Lk = t.klingel_wavelength(t.equivalent_conicity(A, "klingel"))
        return f"L {L:.3f} m, Klingel(lambda_e({1e3 * A:.2f} mm)) {Lk:.3f} m ({L / Lk - 1:+.2%})"
    last = s > s[-1] - 20.0
    y_eq = 0.5 * (y[last].min() + y[last].max())

    def pure(yy):
        c = t.at(yy)
        return c.r_L * (1 - c.yc_R / R) - c.r_R * (1 - c.yc_L / R)

    y_star = brentq(pure, -4e-3, -0.5e-3)
    return f"y {1e3 * y_eq:.4f} mm, pure rolling {1e3 * y_star:.4f} mm ({y_eq / y_star - 1:+.2%})"


def call_cost(table) -> tuple[float, float]:
    """Microseconds per call of the Python law and of the symbolic law (via Evaluate)."""
    out = []
    for law in ("python", "symbolic"):
        ws = build(table, "straight", law, 2e-3)
        st = ws.initial_state
        q = [0.0, st.y, st.z, st.roll, 0.0, 2e-4, 0.0]
        qt = [0.0, 1e-3, 1e-5, 1e-4, 0.0, 1e-4, st.spin_t]
        if law == "python":
            def fn():
                return ws._python_force(ws.mbs, 0.0, 0, q, qt)
        else:
            uf = ws._sym_keep[0]

            def fn():
                return uf.Evaluate(ws.mbs, 0.0, 0, q, qt)
        n = 3000
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        out.append((time.perf_counter() - t0) / n * 1e6)
    return out[0], out[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1 run per case, 2 ms step only")
    args = ap.parse_args()
    runs, steps = (1, (2e-3,)) if args.quick else (3, (2e-3, 5e-3))
    table = ContactLawTable(ContactTable.default())
    py_us, sym_us = call_cost(table)
    print(f"one call of the contact law (both wheels, 7 generalized forces): Python "
          f"{py_us:.1f} us, symbolic {sym_us:.1f} us (through Evaluate)")
    print(f"median of {runs} run(s); V = {V:g} m/s")
    print(" case      law       step | wall/sim s | Newton/step  Jacobians  calls/step | check")
    for case in ("straight", "curve"):
        for law in ("python", "symbolic"):
            for step in steps:
                res = [one(table, case, law, step) for _ in range(runs)]
                w = statistics.median(r["wall_per_sim_s"] for r in res)
                r0 = res[0]
                print(f" {case:9s} {law:9s} {step * 1e3:2.0f}ms | {w:10.4f} |"
                      f" {r0['newton']:11.2f} {r0['jac']:10d} {r0['calls']:11.2f} |"
                      f" {r0['check']}")


if __name__ == "__main__":
    main()
