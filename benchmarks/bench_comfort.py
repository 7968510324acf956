"""Ride comfort of a 5-minute, 400 Hz, three-axis record (issue target: <= 2 s), median of 5:

    python benchmarks/bench_comfort.py          # the computation alone, then the whole command
"""
from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from cosim import cli
from cosim.limits.comfort import comfort


def record(fs_Hz: float = 400.0, duration_s: float = 300.0, seed: int = 0):
    """Band-limited random accelerations (white noise through a 3 Hz first-order low-pass)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s, 1.0 / fs_Hz)
    out = {}
    for axis, scale in (("x", 0.05), ("y", 0.2), ("z", 0.3)):
        w = rng.standard_normal(t.size)
        a = np.empty_like(w)
        alpha = 1.0 - np.exp(-2 * np.pi * 3.0 / fs_Hz)
        acc = 0.0
        for i, v in enumerate(w):
            acc += alpha * (v - acc)
            a[i] = acc
        out[axis] = scale * a / a.std() + (9.81 if axis == "z" else 0.0)
    return t, out


def main() -> int:
    t, acc = record()
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        comfort(t, acc)
        times.append(time.perf_counter() - t0)
    print(f"comfort(), 300 s at 400 Hz, 3 axes: median {statistics.median(times):.3f} s (of 5)")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "record.csv"
        columns = np.column_stack([t, acc["x"], acc["y"], acc["z"]])
        np.savetxt(path, columns, delimiter=",", header="t_s,ax_m_per_s2,ay_m_per_s2,az_m_per_s2", comments="",
                   fmt="%.6g")
        times = []
        for _ in range(5):
            t0 = time.perf_counter()
            cli.main(["comfort", str(path), "--out", str(Path(tmp) / "out")])
            times.append(time.perf_counter() - t0)
    print(f"pneumorail comfort on its CSV (read, compute, json, csv, figure): median {statistics.median(times):.3f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
