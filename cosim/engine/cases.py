"""Running a car scenario's cases: cars co-simulated with their circuit (:mod:`cosim.engine.master`),
one car per k value, the cases shared out over a pool of processes, gathered into one labelled
Dataset (:mod:`cosim.results.series`)."""
from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from typing import Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np
import xarray as xr

from cosim.engine.master import OUTPUTS, CoSimulation, Output
from cosim.interrupts import install_in_worker
from cosim.limits.watch import StateWatch
from cosim.results.io import Progress
from cosim.results.series import car_dataset, concat_cases
from cosim.scenario.imported import is_imported
from cosim.scenario.model import Scenario
from cosim.scenario.schema import k_label
from pneumatics.integrate import advance, hermite_motion, stable_step_s
from pneumatics.layouts import static_pressures
from vehicle.params import BELLOWS

#: make_car(scenario) -> a car with the vehicle.car.MetroCar interface (module-level: picklable)
CarFactory = Callable[[Scenario], object]


def build_cosimulation(scenario: Scenario, k_values: Sequence[float], make_car: CarFactory,
                       extra_outputs: Sequence[Output] = ()) -> CoSimulation:
    """Cars (one per k) in static equilibrium and the circuit with bellow pressures that carry them.

    The pneumatic step is the one of all the scenario's k values (and ``k_values``), not only of
    those this circuit batches (:func:`pneumatics.integrate.stable_step_s` shortens it for a large
    finite k, ~1e4 W/K and above at 5 ms, and a batched circuit takes one step for all its cases):
    so a case's numbers do not depend on which cases share its circuit, i.e. on ``solver.jobs`` and
    on how the runs are grouped onto processes. ``extra_outputs``: what the kind samples besides
    :data:`~cosim.engine.master.OUTPUTS`."""
    settings = scenario.solver
    cars = [make_car(scenario) for _ in k_values]
    if is_imported(scenario.circuit):
        from cosim.engine.imported import build_imported
        return build_imported(scenario, k_values, cars, [f"k = {k_label(k)} W/K" for k in k_values],
                              StateWatch(scenario.state_limits, len(k_values), cars[0].bellow_height_m), extra_outputs)
    components = scenario.circuit.components()
    circuit = scenario.circuit.compile(np.asarray(k_values, dtype=float))
    if tuple(circuit.bellow_names) != BELLOWS:
        raise ValueError(f"the circuit's bellows must be {BELLOWS}, got {circuit.bellow_names}")
    p0 = static_pressures(components, cars[0].static_bellow_forces_N(), circuit.atmosphere.p_Pa)
    x0 = circuit.initial_state(p0, n_cases=len(k_values))
    every_k = sorted(set(scenario.k_W_per_K) | set(k_values))
    every = scenario.circuit.compile(np.asarray(every_k, dtype=float))
    h_pneumatic = stable_step_s(every, every.initial_state(p0, n_cases=len(every_k)), settings.pneumatic_step_s)
    watch = StateWatch(scenario.state_limits, len(k_values), cars[0].bellow_height_m)
    return CoSimulation(cars, circuit, x0, settings.macro_step_s, h_pneumatic, settings.coupling,
                        case_labels=[f"k = {k_label(k)} W/K" for k in k_values], watch=watch, extra_outputs=extra_outputs,
                        scheduled_demands=dict(scenario.circuit.scheduled_demands))


def _run_chunk(args) -> Tuple[Dict[str, np.ndarray], Optional[str], List[float]]:
    scenario, k_values, make_car, duration_s, label, extra_outputs = args
    cosim = build_cosimulation(scenario, k_values, make_car, extra_outputs)
    progress = Progress(f"{label} k={','.join(k_label(k) for k in sorted(k_values))}") if label else None
    try:
        record, diagnosis = cosim.run(duration_s, scenario.solver.output_interval_s, progress)
    finally:
        if is_imported(scenario.circuit):
            cosim.close()
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


def _load_compiled_laws(variants: Sequence[Scenario]) -> None:
    """Evaluate each variant's circuit once, at rest (and with all its faults having happened),
    so that the laws it calls are compiled (:mod:`pneumatics.compiled`: numba, its compiler and
    the laws loaded from the cache) in this process before it forks the pool: the workers inherit
    them instead of each loading them again, ~0.4 s of CPU per worker of the twist's main job.
    Only the laws the circuits call: loading all three took 0.57 s here. The evaluation's numbers
    are thrown away; a law it did not reach compiles in the worker that calls it, as before. A
    macro-step's other compiled calls (the bellows' force laws, RK4's combinations, the governors,
    the divergence check) are made once too."""
    for scenario in variants:
        try:
            circuit = scenario.circuit.compile(np.asarray(scenario.k_W_per_K, dtype=float))
            p0 = static_pressures(scenario.circuit.components(), np.full(len(BELLOWS), 50e3), circuit.atmosphere.p_Pa)
            x = circuit.initial_state(p0)
            z = np.zeros((len(BELLOWS),) + x.shape[1:])
            every = [circuit.with_active_faults(range(len(circuit.faults)))] if circuit.faults else []
            with np.errstate(all="ignore"):
                for c in (circuit, *every):
                    # what every macro-step calls: the force laws, RK4 (its stages' evaluations and
                    # combinations, the governors), the divergence check
                    c.derivatives_and_held(x, z, z)
                    c.bellow_force_laws(x, z, x, 0.0)
                    advance(c, x, 0.0, 1e-3, lambda t: (z, z), 1e-3)
                    advance(c, x, 0.0, 1e-3, hermite_motion(0.0, 1e-3, z, z, z, z), 1e-3)   # compiled_step's
                    c.physical_cases(x)
        except Exception:                       # noqa: BLE001 -- only a head start: the workers compile what they need
            pass


def simulate_variants(variants: Sequence[Scenario], make_car: CarFactory, durations_s: Sequence[float],
                      labels: Optional[Sequence[Optional[str]]] = None,
                      extra_outputs: Sequence[Output] = ()) -> List[Tuple[List[Tuple[int, list]], List[str]]]:
    """Run every k of every variant (e.g. the valve settings of one scenario), each for its
    duration, on one pool of ``solver.jobs`` processes (the first variant's), the cases shared out
    by :func:`_worker_shares`; returns, per variant, its chunks' record arrays with their k values,
    and the divergence diagnoses. ``labels``: per variant, a progress label (None: silent);
    ``extra_outputs``: sampled besides :data:`~cosim.engine.master.OUTPUTS`."""
    labels = list(labels or [None] * len(variants))
    shares = _worker_shares([v.k_W_per_K for v in variants], variants[0].solver.jobs)
    tasks = [[(variants[v], ks, make_car, durations_s[v], labels[v], tuple(extra_outputs)) for v, ks in share]
             for share in shares]
    if len(tasks) == 1 and not any(is_imported(v.circuit) for v in variants):
        done = [_run_chunks(tasks[0])]
    else:
        context = multiprocessing.get_context()         # the pool's default
        if context.get_start_method() == "fork":        # the workers inherit what this process loaded
            _load_compiled_laws(variants)
        with ProcessPoolExecutor(len(tasks), mp_context=context, initializer=install_in_worker) as pool:
            done = list(pool.map(_run_chunks, tasks))
    per_variant: List[Tuple[list, List[str]]] = [([], []) for _ in variants]
    for share, results in zip(shares, done):
        for (v, _), (arrays, diagnosis, ks) in zip(share, results):
            per_variant[v][0].append((ks, arrays))
            if diagnosis:
                per_variant[v][1].append(diagnosis)
    return per_variant


def simulate_cases(scenario: Scenario, settings: Sequence[Optional[bool]], make_car: CarFactory, duration_s: float,
                   progress: Optional[Progress] = None, extra_outputs: Sequence[Output] = ()) -> Tuple[xr.Dataset, List[str]]:
    """Every k of ``scenario`` for each valve setting (None: as ``circuit.valves`` says), all on
    one pool of ``solver.jobs`` processes: one labelled Dataset (:func:`cosim.results.series.car_dataset`;
    cases valve setting by valve setting, k ascending within each) and the divergence diagnoses
    (prefixed with the valve setting when there are several). ``extra_outputs``: what the kind
    samples besides :data:`~cosim.engine.master.OUTPUTS` (:attr:`cosim.kinds.base.CarKind.outputs`)."""
    return simulate_scenarios([scenario], settings, make_car, [duration_s], progress, extra_outputs=extra_outputs)[0]


def simulate_scenarios(scenarios: Sequence[Scenario], settings: Sequence[Optional[bool]], make_car: CarFactory,
                       durations_s: Sequence[float], progress: Optional[Progress] = None,
                       names: Optional[Sequence[str]] = None,
                       extra_outputs: Sequence[Output] = ()) -> List[Tuple[xr.Dataset, List[str]]]:
    """:func:`simulate_cases` for several scenarios at once (e.g. a ride's speeds, each on its own
    track, each run for its own duration), all on one pool of ``solver.jobs`` processes (the first
    scenario's): per scenario its Dataset and diagnoses. The cases are shared out scenario by
    scenario (:func:`_worker_shares`), so that two scenarios of 4 k values on 2 processes run one
    scenario per process, its 4 cars on one batched circuit: the circuit's cost per macro-step is
    paid once for 4 cases instead of 2 (a case's numbers do not depend on the cases it shares a
    circuit with: :func:`build_cosimulation`). ``names``: the progress labels of the
    scenarios (default: their names)."""
    named = any(s is not None for s in settings)
    show = progress is not None and not progress.quiet
    variants = [scenario if valves is None else scenario.with_valves(valves)
                for scenario in scenarios for valves in settings]       # scenario by scenario
    n = len(settings)
    labels = [((names[i // n] if names else v.name) + (f" valves {'on' if v.circuit.valves else 'off'}" if named else ""))
              if show else None for i, v in enumerate(variants)]
    results = simulate_variants(variants, make_car, [durations_s[i // n] for i in range(len(variants))], labels,
                                extra_outputs)
    out = []
    for i in range(len(scenarios)):
        datasets, diagnoses = [], []
        for variant, (chunks, diag) in zip(variants[i * n:(i + 1) * n], results[i * n:(i + 1) * n]):
            circuit = None if is_imported(variant.circuit) else variant.circuit.compile()   # an FMU's: no links, valves
            links, valve_names = (circuit.link_names, circuit.valve_names) if circuit else ((), ())
            valves = variant.circuit.valves
            parts = [car_dataset(arrays, (*OUTPUTS, *extra_outputs), ks, valves, named, links, valve_names)
                     for ks, arrays in chunks]
            ds = concat_cases(parts)
            datasets.append(ds.isel(case=np.argsort(ds["k_W_per_K"].values, kind="stable")))  # inf sorts last
            diagnoses += [f"valves {'on' if valves else 'off'}: {d}" if named else d for d in diag]
        out.append((concat_cases(datasets), diagnoses))
    return out
