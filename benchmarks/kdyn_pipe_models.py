"""K_dyn of the paper's bellow-pipe-tank with an inertial and a compressible pipe.

    python benchmarks/kdyn_pipe_models.py [--out DIR] [--timing] [--repeat 3]

1. The small-signal complex stiffness K*(f) = G_z + G_x (i w I - A)^-1 (B_z + i w B_zd) of the
   circuit linearised at rest (:mod:`pneumatics.linear`), 0.1 to 100 Hz, k = 100 W/K, for the
   paper's pipe (1 m, 18 mm bore, zeta 1.11) and 5 m and 20 m pipes of the same bore and losses:
   the inertial pipe (``model: dynamic``, eq. 5) and the compressible pipe (``model:
   compressible``, 5 cm cells: 20, 100 and 400 cells). Magnitude |K*| and loss angle
   atan(K''/K') to ``kdyn_pipe_models.csv`` and ``kdyn_pipe_models.png`` in DIR (default: the
   current folder). The linearisation keeps no quadratic pipe loss (it has no linear part at
   rest): the resonances are damped by the heat exchange alone, the same in both models.
2. ``--timing``: the rig's nonlinear K_dyn sweep (:func:`pneumatics.rig.dynamic_stiffness_sweep`,
   periodic steady state by RK4 shooting) of the paper's pipe at 1, 2, 5 and 10 Hz, k = 100 W/K,
   2 mm, inertial and compressible with 20 cells, ``--repeat`` times each: median wall times.
"""
from __future__ import annotations

import argparse
import csv
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pneumatics.chamber import Bellow, Tank  # noqa: E402
from pneumatics.circuit import Circuit  # noqa: E402
from pneumatics.linear import linearise_circuit  # noqa: E402
from pneumatics.pipe import Pipe  # noqa: E402
from pneumatics.rig import bellow_tank_components, dynamic_stiffness_sweep  # noqa: E402

P0_PA = 4.0e5
K_W_PER_K = 100.0
LENGTHS_M = (1.0, 5.0, 20.0)
MODELS = ("dynamic", "compressible")
FREQUENCIES_HZ = np.round(np.logspace(-1, 2, 121), 6)


def complex_stiffness(length_m: float, model: str, f_Hz: np.ndarray) -> np.ndarray:
    """K*(f) [N/m] of the bellow-pipe-tank at rest (one bellow: the (1, 1) entry)."""
    comps = bellow_tank_components(Bellow(), Tank(), Pipe("", "", length_m=length_m, model=model))
    circuit = Circuit(comps, k_W_per_K=K_W_PER_K)
    lin = linearise_circuit(circuit, circuit.initial_state({"bellow": P0_PA, "tank": P0_PA}))
    n = lin.A.shape[0]
    out = np.empty(f_Hz.size, complex)
    for i, f in enumerate(f_Hz):
        w = 2 * np.pi * f
        x = np.linalg.solve(1j * w * np.eye(n) - lin.A, lin.B_z[:, 0] + 1j * w * lin.B_zd[:, 0])
        out[i] = lin.G_z[0, 0] + lin.G_x[0] @ x
    return out


def table():
    rows = []
    for L in LENGTHS_M:
        K = {m: complex_stiffness(L, m, FREQUENCIES_HZ) for m in MODELS}
        for i, f in enumerate(FREQUENCIES_HZ):
            row = {"pipe_length_m": L, "frequency_Hz": f}
            for m in MODELS:
                row[f"K_{m}_N_per_m"] = abs(K[m][i])
                row[f"loss_angle_{m}_deg"] = np.degrees(np.angle(K[m][i]))
            rows.append(row)
    return rows


def figure(rows, path: Path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax_k, ax_a) = plt.subplots(2, 1, figsize=(8, 8), sharex=True)
    for L, colour in zip(LENGTHS_M, ("C0", "C1", "C2")):
        sel = [r for r in rows if r["pipe_length_m"] == L]
        f = [r["frequency_Hz"] for r in sel]
        for m, style in zip(MODELS, ("--", "-")):
            label = f"{L:g} m, {'inertial' if m == 'dynamic' else 'compressible'}"
            ax_k.loglog(f, [r[f"K_{m}_N_per_m"] / 1e3 for r in sel], style, color=colour, label=label)
            ax_a.semilogx(f, [r[f"loss_angle_{m}_deg"] for r in sel], style, color=colour, label=label)
    ax_k.set_ylabel("|K*| [kN/m]")
    ax_a.set_ylabel("loss angle [deg]")
    ax_a.set_xlabel("frequency [Hz]")
    ax_k.set_title(f"bellow-pipe-tank (Table 1), small signal, k = {K_W_PER_K:g} W/K: inertial vs compressible pipe")
    for ax in (ax_k, ax_a):
        ax.grid(True, which="both", alpha=0.3)
    ax_k.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def timing(repeat: int):
    f = [1.0, 2.0, 5.0, 10.0]
    out = {}
    for model in MODELS:
        comps = bellow_tank_components(Bellow(), Tank(), Pipe("", "", model=model, cells=20))
        walls = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            dynamic_stiffness_sweep(comps, [K_W_PER_K], f, 0.002, p0_Pa={"bellow": P0_PA, "tank": P0_PA})
            walls.append(time.perf_counter() - t0)
        out[model] = statistics.median(walls)
        print(f"rig K_dyn sweep, {model}: median {out[model]:.2f} s of {repeat} ({', '.join(f'{w:.2f}' for w in walls)})")
    print(f"compressible (20 cells) / inertial: {out['compressible'] / out['dynamic']:.1f}x")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path("."))
    ap.add_argument("--timing", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    rows = table()
    args.out.mkdir(parents=True, exist_ok=True)
    with open(args.out / "kdyn_pipe_models.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    figure(rows, args.out / "kdyn_pipe_models.png")
    for L in LENGTHS_M:
        sel = [r for r in rows if r["pipe_length_m"] == L]
        dev = [abs(r["K_compressible_N_per_m"] / r["K_dynamic_N_per_m"] - 1) for r in sel]
        below5 = max(d for d, r in zip(dev, sel) if r["frequency_Hz"] <= 5.0)
        worst = int(np.argmax(dev))
        print(f"{L:g} m: |K| compressible vs inertial: at most {100 * below5:.2f} % below 5 Hz, "
              f"{100 * dev[worst]:.0f} % at {sel[worst]['frequency_Hz']:g} Hz")
    if args.timing:
        timing(args.repeat)


if __name__ == "__main__":
    main()
