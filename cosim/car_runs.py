"""Running cars co-simulated with their circuit, one car per k value, k cases split over processes."""
from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

from pneumatics.circuit import Circuit
from pneumatics.orifice import Orifice
from pneumatics.pipe import Pipe
from vehicle.car import BELLOWS, WHEELS

from .interrupts import install_in_worker
from .master import CoSimulation
from .plots import Curve, Panel, k_legend, save_panels
from .results import Progress, k_label
from .scenario import Scenario

#: make_car(scenario) -> a car with the vehicle.car.MetroCar interface (module-level: picklable)
CarFactory = Callable[[Scenario], object]


def build_cosimulation(scenario: Scenario, k_values: Sequence[float], make_car: CarFactory) -> CoSimulation:
    """Cars (one per k) in static equilibrium and the circuit with bellow pressures that carry them."""
    settings = scenario.solver
    cars = [make_car(scenario) for _ in k_values]
    components = scenario.circuit.components()
    circuit = Circuit(components, k_W_per_K=np.asarray(k_values, dtype=float))
    if tuple(circuit.bellow_names) != BELLOWS:
        raise ValueError(f"the circuit's bellows must be {BELLOWS}, got {circuit.bellow_names}")
    x0 = circuit.initial_state(static_pressures(components, cars[0].static_bellow_forces_N(), circuit.atmosphere.p_Pa),
                               n_cases=len(k_values))
    return CoSimulation(cars, circuit, x0, settings.macro_step_s, settings.pneumatic_step_s, settings.coupling,
                        case_labels=[f"k = {k_label(k)} W/K" for k in k_values])


def static_pressures(components: Dict[str, object], F0_N: Sequence[float], p_atm_Pa: float) -> Dict[str, float]:
    """Bellow pressures that carry the static load, eq. (4) solved for p at z = 0; a chamber with no
    initial pressure of its own that a pipe or an orifice (a throttle) joins to a bellow (its
    auxiliary tank) starts at that bellow's pressure, so the circuit starts at rest."""
    p0 = {b: p_atm_Pa + F / components[b].area_m2(0.0) for b, F in zip(BELLOWS, F0_N)}
    for c in components.values():
        if isinstance(c, (Pipe, Orifice)):
            for bellow, other in ((c.a, c.b), (c.b, c.a)):
                if bellow in p0 and other not in p0 and getattr(components.get(other), "p0_Pa", 0) is None:
                    p0[other] = p0[bellow]
    return p0


def _run_chunk(args) -> Tuple[Dict[str, np.ndarray], Optional[str], List[float]]:
    scenario, k_values, make_car, duration_s, label = args
    cosim = build_cosimulation(scenario, k_values, make_car)
    progress = Progress(f"{label} k={','.join(k_label(k) for k in k_values)}") if label else None
    record, diagnosis = cosim.run(duration_s, scenario.solver.output_interval_s, progress)
    return record.arrays(), diagnosis, list(k_values)


def _run_chunks(tasks) -> list:
    """One worker's share: its chunks (see :func:`_worker_shares`), one after the other."""
    return [_run_chunk(task) for task in tasks]


def _chunks(k_values: Sequence[float], jobs: int) -> List[List[float]]:
    jobs = max(1, min(jobs, len(k_values)))
    return [list(k_values[i::jobs]) for i in range(jobs)]


def _worker_shares(k_lists: Sequence[Sequence[float]], jobs: int) -> List[List[Tuple[int, List[float]]]]:
    """The cases (variant, k) of every variant split over at most ``jobs`` workers with equal
    numbers of cars (one more for the first ones), each share a list of (variant, k values)
    chunks, a chunk being one co-simulation (one batched circuit).

    The cases are laid out variant by variant, each variant's k values in the order of
    :func:`_chunks` (k[0::n], k[1::n], ...), and cut into consecutive shares: a single variant
    gets exactly the chunks of :func:`_chunks` (and so the same circuits, pneumatic steps and
    results as before), several variants fill the workers one variant after the other (two
    variants of 7 k on 2 workers: one variant per worker, all 7 k in one circuit)."""
    cases = [(v, k) for v, ks in enumerate(k_lists) for chunk in _chunks(ks, jobs) for k in chunk]
    workers = max(1, min(jobs, len(cases)))
    sizes = [len(cases) // workers + (i < len(cases) % workers) for i in range(workers)]
    shares, start = [], 0
    for size in sizes:
        share: List[Tuple[int, List[float]]] = []
        for v, k in cases[start:start + size]:
            if share and share[-1][0] == v:
                share[-1][1].append(k)
            else:
                share.append((v, [k]))
        shares.append(share)
        start += size
    return shares


def simulate(scenario: Scenario, make_car: CarFactory, duration_s: float, label: Optional[str] = None):
    """Run every k of ``scenario`` (``solver.jobs`` processes); returns (k values in ascending
    order, record arrays (samples, ..., cases), divergence diagnoses). ``label``: show progress."""
    return simulate_variants([scenario], make_car, duration_s, [label])[0]


def simulate_variants(variants: Sequence[Scenario], make_car: CarFactory, duration_s: float,
                      labels: Optional[Sequence[Optional[str]]] = None,
                      on_done: Optional[Callable[[int, tuple, Optional[Callable]], None]] = None) -> list:
    """Run every k of every variant (e.g. the valve settings of one scenario) on one pool of
    ``solver.jobs`` processes (the first variant's), the cases shared out by
    :func:`_worker_shares`; returns, per variant, what :func:`simulate` returns.

    ``on_done(v, result, submit)``: called in this process as soon as every case of variant
    ``v`` is done (in order of completion), ``result`` what :func:`simulate` returns for it,
    while other variants may still be running: their post-processing overlaps the simulation.
    ``submit(fn, *args)`` queues work on a pool worker that has finished its share (picklable
    ``fn``), or is None if no such worker exists (all in this process, or every variant done);
    the call returns once all submitted work has finished, and re-raises its errors."""
    labels = list(labels or [None] * len(variants))
    shares = _worker_shares([v.k_W_per_K for v in variants], variants[0].solver.jobs)
    tasks = [[(variants[v], ks, make_car, duration_s, labels[v]) for v, ks in share] for share in shares]
    per_variant: List[list] = [[None] * sum(v == w for share in shares for w, _ in share) for v in range(len(variants))]
    missing = [len(chunks) for chunks in per_variant]
    merged: List[Optional[tuple]] = [None] * len(variants)
    slots = [[] for _ in shares]  # per share: (variant, index of the chunk within its variant)
    seen = [0] * len(variants)
    for i, share in enumerate(shares):
        for v, _ in share:
            slots[i].append((v, seen[v]))
            seen[v] += 1

    def collect(i: int, results, submit) -> None:
        for (v, n), result in zip(slots[i], results):
            per_variant[v][n] = result
            missing[v] -= 1
            if missing[v] == 0:
                merged[v] = _merge(per_variant[v])
                if on_done is not None:
                    on_done(v, merged[v], submit if any(missing) else None)

    if len(tasks) == 1:
        collect(0, _run_chunks(tasks[0]), None)
    else:
        extra = []
        with ProcessPoolExecutor(len(tasks), initializer=install_in_worker) as pool:
            def submit(fn, *args):
                extra.append(pool.submit(fn, *args))
            futures = {pool.submit(_run_chunks, task): i for i, task in enumerate(tasks)}
            for future in as_completed(futures):
                collect(futures[future], future.result(), submit)
            for future in extra:
                future.result()
    return merged


def _merge(results):
    """(k values in ascending order, record arrays, diagnoses) from the chunks of one variant."""
    ks, arrays, diagnoses = [], [], []
    for rec, diag, chunk in results:
        ks += chunk
        arrays.append(rec)
        if diag:
            diagnoses.append(diag)
    # a process whose cases all diverged stopped early: pad its record with NaN
    longest = max(arrays, key=lambda a: len(a["t_s"]))
    n = len(longest["t_s"])
    merged = {name: np.concatenate([_pad(a[name], n) for a in arrays], axis=-1) for name in arrays[0] if name != "t_s"}
    merged["t_s"] = longest["t_s"]
    order = np.argsort(ks)                        # inf sorts last
    merged = {name: (v[..., order] if name != "t_s" else v) for name, v in merged.items()}
    return [ks[i] for i in order], merged, diagnoses


#: a figure to draw: (path, panels, suptitle, ncols), the arguments of :func:`cosim.plots.save_panels`
Figure = Tuple[Path, Sequence[Panel], Optional[str], int]


def save_figures(figures: Sequence[Figure], jobs: int) -> None:
    """Draw independent figures on up to ``jobs`` processes, the largest (most panels) first."""
    figures = sorted(figures, key=lambda f: -len(f[1]))
    workers = max(1, min(jobs, len(figures)))
    if workers == 1:
        for figure in figures:
            _save_figure(figure)
        return
    with ProcessPoolExecutor(workers) as pool:
        list(pool.map(_save_figure, figures))


def _save_figure(figure: Figure) -> Path:
    path, panels, suptitle, ncols = figure
    return save_panels(path, panels, suptitle, ncols=ncols)


def _pad(values: np.ndarray, n: int) -> np.ndarray:
    if len(values) == n:
        return values
    pad = np.full((n - len(values),) + values.shape[1:], np.nan)
    return np.concatenate([values, pad])


def record_columns(rec: Dict[str, np.ndarray], j: int) -> Dict[str, np.ndarray]:
    """Time-series columns of case ``j`` (headers carry units)."""
    cols = {"t_s": rec["t_s"]}
    cols.update({f"Q_{w}_N": rec["wheel_load_N"][:, i, j] for i, w in enumerate(WHEELS)})
    for name, key, unit in (("z", "crushing_m", "m"), ("F_bellow", "bellow_force_N", "N"),
                            ("p_bellow", "bellow_p_Pa", "Pa"), ("T_bellow", "bellow_T_K", "K")):
        cols.update({f"{name}_{b}_{unit}": rec[key][:, i, j] for i, b in enumerate(BELLOWS)})
    cols["roll_carbody_rad"] = rec["roll_rad"][:, j]
    cols["air_from_supply_kg"] = rec["air_from_supply_kg"][:, j]
    cols["air_to_atmosphere_kg"] = rec["air_to_atmosphere_kg"][:, j]
    return cols


def curves_per_k(t_s: np.ndarray, ks: Sequence[float], label: str = ""):
    """per_k(values (samples, cases), scale) -> one Curve per k."""
    def per_k(values, scale=1.0):
        return [Curve(t_s, values[..., j] * scale, f"{label}{k_legend(k)}") for j, k in enumerate(ks)]
    return per_k


def bellow_panels(rec: Dict[str, np.ndarray], ks: Sequence[float]) -> List[Panel]:
    per_k = curves_per_k(rec["t_s"], ks)
    return ([Panel(per_k(rec["bellow_p_Pa"][:, i], 1e-5), "time t [s]", f"p_{b} [bar abs]", f"bellow {b}")
             for i, b in enumerate(BELLOWS)] +
            [Panel(per_k(rec["bellow_T_K"][:, i]), "time t [s]", f"T_{b} [K]", f"bellow {b}")
             for i, b in enumerate(BELLOWS)])
