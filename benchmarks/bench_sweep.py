"""Sweep benchmarks (not run as tests): ``python benchmarks/bench_sweep.py [--repeat N] [--only overhead|scaling]``.

1. Overhead per case: a sweep of short twist cases (0.2 s ramp, 0.2 s hold, k = 0) run with
   ``--jobs 1`` (in this process) against the same cases run directly (``load_scenario`` +
   ``run_scenario``, what ``pneumorail run`` does). Reported per case: the sweep's validation,
   hashing, markers and bookkeeping; and separately the once-per-sweep outputs (sweep.csv,
   sweep.json, sweep.nc, plots). Target: <= 5 % per case.
2. Throughput: a 16-case sweep of the same short twists on ``--jobs 2`` against ``--jobs 1``.
   Target: >= 1.8x on 2 free cores.

Prints medians over ``--repeat`` repetitions (default 5). Wall times depend on what else runs on
the machine: run it on an otherwise idle machine.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import yaml  # noqa: E402

from cosim.load import load_scenario  # noqa: E402
from cosim.results.io import Progress  # noqa: E402
from cosim.runner import run_scenario  # noqa: E402
from cosim.sweep import study as sw  # noqa: E402
from cosim.sweep.executors import Pool, Serial  # noqa: E402


def short_twist(folder: Path) -> Path:
    data = yaml.safe_load((ROOT / "scenarios" / "twist_dqq.yaml").read_text())
    data["vehicle"] = "paper_metro_car"
    data["k_W_per_K"] = [0]
    data["twist"].update(ramp_s=0.2, hold_s=0.2)
    data["solver"].update(jobs=1)
    path = folder / "short_twist.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def spec(scenario: Path, n_twist: int, n_tank: int) -> sw.SweepSpec:
    twists = [3.0 + 0.25 * i for i in range(n_twist)]
    tanks = [0.020 + 0.003 * i for i in range(n_tank)]
    return sw.SweepSpec(scenario, grid={"twist.twist_per_mille": twists, "circuit.tank.V_m3": tanks})


def _clocks():
    return time.perf_counter(), time.process_time()


def sweep_time(s: sw.SweepSpec, out: Path, executor):
    """((wall, cpu) of prepare + the cases, wall of the once-per-sweep outputs). The cpu time is
    this process's (it is the whole work with ``--jobs 1``)."""
    w0, c0 = _clocks()
    prepared = sw.prepare(s)
    outcome = sw.run_sweep(prepared, out, executor, quiet=True)
    w1, c1 = _clocks()
    sw.write_tables(outcome)                      # the outputs again, to time them alone
    sw.write_netcdf(outcome)
    sw.write_plots(outcome)
    w2, c2 = _clocks()
    assert outcome.all_ok, outcome.report()
    return (w1 - w0) - (w2 - w1), (c1 - c0) - (c2 - c1), w2 - w1


def direct_time(s: sw.SweepSpec, out: Path):
    """(wall, cpu) of the same cases run as ``pneumorail run`` runs them, one after the other."""
    cases = sw.expand(s)
    w0, c0 = _clocks()
    for case in cases:
        scenario = load_scenario(s.scenario_file, case.override_strings(), case.k)
        scenario = sw._one_process(scenario)
        run_scenario(scenario, out / f"case_{case.index}", Progress("bench", quiet=True))
    w1, c1 = _clocks()
    return w1 - w0, c1 - c0


def overhead(scenario: Path, repeat: int, tmp: Path) -> None:
    s = spec(scenario, 2, 2)
    n = len(sw.expand(s))
    direct_time(s, tmp / "warm_up")               # font cache, first imports
    dw, dc, ww, wc, outputs = [], [], [], [], []
    for r in range(repeat):
        order = ("direct", "sweep") if r % 2 == 0 else ("sweep", "direct")
        for what in order:                        # alternate: drifting load hits both alike
            if what == "direct":
                w, c = direct_time(s, tmp / f"direct_{r}")
                dw.append(w / n)
                dc.append(c / n)
            else:
                w, c, o = sweep_time(s, tmp / f"sweep_{r}", Serial())
                ww.append(w / n)
                wc.append(c / n)
                outputs.append(o)
    m = statistics.median
    print(f"overhead ({n} cases, --jobs 1, {repeat} repetitions, medians per case):")
    print(f"  direct run    wall {m(dw):7.3f} s   cpu {m(dc):7.3f} s")
    print(f"  sweep         wall {m(ww):7.3f} s   cpu {m(wc):7.3f} s   overhead wall {100 * (m(ww) - m(dw)) / m(dw):+6.2f} %, "
          f"cpu {100 * (m(wc) - m(dc)) / m(dc):+6.2f} %  (target <= 5 %)")
    print(f"  once-per-sweep outputs (sweep.csv/json/nc, plots): {m(outputs):.3f} s = "
          f"{100 * m(outputs) / (n * m(dw)):.1f} % of these {n} cases, {100 * m(outputs) / (16 * m(dw)):.1f} % of 16",
          flush=True)


def scaling(scenario: Path, repeat: int, tmp: Path) -> None:
    s = spec(scenario, 4, 4)
    n = len(sw.expand(s))
    one, two = [], []
    for r in range(repeat):
        cpu0 = os.times()
        w, _, o = sweep_time(s, tmp / f"one_{r}", Serial())
        one.append(w + o)
        w, _, o = sweep_time(s, tmp / f"two_{r}", Pool(2))
        two.append(w + o)
        cpu1 = os.times()
        print(f"  repetition {r}: --jobs 1 {one[-1]:.1f} s, --jobs 2 {two[-1]:.1f} s "
              f"(cpu of the benchmark and its children {cpu1.user + cpu1.children_user - cpu0.user - cpu0.children_user:.0f} s)",
              flush=True)
    a, b = statistics.median(one), statistics.median(two)
    print(f"throughput ({n} cases, {repeat} repetitions, medians): --jobs 1 {a:.1f} s ({n / a:.2f} cases/s), "
          f"--jobs 2 {b:.1f} s ({n / b:.2f} cases/s): speed-up {a / b:.2f}x (target >= 1.8x; "
          f"{os.cpu_count()} cores, load average now {os.getloadavg()[0]:.1f})")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--only", choices=("overhead", "scaling"), default=None)
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        scenario = short_twist(tmp)
        print(f"load average before: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores", flush=True)
        if args.only in (None, "overhead"):
            overhead(scenario, args.repeat, tmp)
        if args.only in (None, "scaling"):
            scaling(scenario, args.repeat, tmp)


if __name__ == "__main__":
    main()
