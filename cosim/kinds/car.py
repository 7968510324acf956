"""Running cars co-simulated with their circuit, one car per k value, k cases split over processes,
gathered into one labelled Dataset (:mod:`cosim.results.series`)."""
from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from typing import Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np
import xarray as xr

from cosim.interrupts import install_in_worker
from cosim.limits.criteria import static_wheel_loads, wheel_unloading
from cosim.limits.watch import StateWatch
from cosim.master import CoSimulation
from cosim.results.io import Progress
from cosim.results.plots import Curve, Figure, Panel, k_legend
from cosim.results.series import car_dataset, concat_cases
from cosim.scenario.model import Scenario
from cosim.scenario.schema import k_label
from pneumatics.integrate import stable_step_s
from pneumatics.layouts import static_pressures
from pneumatics.valves import DifferentialPressureValve
from vehicle.params import BELLOWS

#: make_car(scenario) -> a car with the vehicle.car.MetroCar interface (module-level: picklable)
CarFactory = Callable[[Scenario], object]


def build_cosimulation(scenario: Scenario, k_values: Sequence[float], make_car: CarFactory) -> CoSimulation:
    """Cars (one per k) in static equilibrium and the circuit with bellow pressures that carry them.

    The pneumatic step is the one of all the scenario's k values (and ``k_values``), not only of
    those this circuit batches (:func:`pneumatics.integrate.stable_step_s` shortens it for a large
    finite k, ~1e4 W/K and above at 5 ms, and a batched circuit takes one step for all its cases):
    so a case's numbers do not depend on which cases share its circuit, i.e. on ``solver.jobs`` and
    on how the runs are grouped onto processes."""
    settings = scenario.solver
    cars = [make_car(scenario) for _ in k_values]
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
                        case_labels=[f"k = {k_label(k)} W/K" for k in k_values], watch=watch)


def _run_chunk(args) -> Tuple[Dict[str, np.ndarray], Optional[str], List[float]]:
    scenario, k_values, make_car, duration_s, label = args
    cosim = build_cosimulation(scenario, k_values, make_car)
    progress = Progress(f"{label} k={','.join(k_label(k) for k in sorted(k_values))}") if label else None
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


def simulate_variants(variants: Sequence[Scenario], make_car: CarFactory, durations_s: Sequence[float],
                      labels: Optional[Sequence[Optional[str]]] = None) -> List[Tuple[List[Tuple[int, list]], List[str]]]:
    """Run every k of every variant (e.g. the valve settings of one scenario), each for its
    duration, on one pool of ``solver.jobs`` processes (the first variant's), the cases shared out
    by :func:`_worker_shares`; returns, per variant, its chunks' record arrays with their k values,
    and the divergence diagnoses. ``labels``: per variant, a progress label (None: silent)."""
    labels = list(labels or [None] * len(variants))
    shares = _worker_shares([v.k_W_per_K for v in variants], variants[0].solver.jobs)
    tasks = [[(variants[v], ks, make_car, durations_s[v], labels[v]) for v, ks in share] for share in shares]
    if len(tasks) == 1:
        done = [_run_chunks(tasks[0])]
    else:
        with ProcessPoolExecutor(len(tasks), initializer=install_in_worker) as pool:
            done = list(pool.map(_run_chunks, tasks))
    per_variant: List[Tuple[list, List[str]]] = [([], []) for _ in variants]
    for share, results in zip(shares, done):
        for (v, _), (arrays, diagnosis, ks) in zip(share, results):
            per_variant[v][0].append((ks, arrays))
            if diagnosis:
                per_variant[v][1].append(diagnosis)
    return per_variant


def simulate_cases(scenario: Scenario, settings: Sequence[Optional[bool]], make_car: CarFactory, duration_s: float,
                   progress: Optional[Progress] = None) -> Tuple[xr.Dataset, List[str]]:
    """Every k of ``scenario`` for each valve setting (None: as ``circuit.valves`` says), all on
    one pool of ``solver.jobs`` processes: one labelled Dataset (:func:`cosim.results.series.car_dataset`;
    cases valve setting by valve setting, k ascending within each) and the divergence diagnoses
    (prefixed with the valve setting when there are several)."""
    return simulate_scenarios([scenario], settings, make_car, [duration_s], progress)[0]


def simulate_scenarios(scenarios: Sequence[Scenario], settings: Sequence[Optional[bool]], make_car: CarFactory,
                       durations_s: Sequence[float], progress: Optional[Progress] = None,
                       names: Optional[Sequence[str]] = None) -> List[Tuple[xr.Dataset, List[str]]]:
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
    results = simulate_variants(variants, make_car, [durations_s[i // n] for i in range(len(variants))], labels)
    out = []
    for i in range(len(scenarios)):
        datasets, diagnoses = [], []
        for variant, (chunks, diag) in zip(variants[i * n:(i + 1) * n], results[i * n:(i + 1) * n]):
            circuit = variant.circuit.compile()
            valves = variant.circuit.valves
            parts = [car_dataset(arrays, ks, valves, named, circuit.link_names, circuit.valve_names)
                     for ks, arrays in chunks]
            ds = concat_cases(parts)
            datasets.append(ds.isel(case=np.argsort(ds["k_W_per_K"].values, kind="stable")))  # inf sorts last
            diagnoses += [f"valves {'on' if valves else 'off'}: {d}" if named else d for d in diag]
        out.append((concat_cases(datasets), diagnoses))
    return out


def add_wheel_unloading(ds: xr.Dataset, column: Optional[str] = None) -> None:
    """Add the static wheel loads ``Q0_N`` (wheel x case: each wheelset's mean load at t = 0, the
    car at rest on level track; EN 14363) and the wheel unloading ``dqq`` = (Q0 - Q)/Q0 (time x
    wheel x case, positive: unloaded) to a car run's Dataset, in place; ``column``: its CSV
    column pattern (None: not written to the time series)."""
    Q = ds["wheel_load_N"].transpose("time", "wheel", "case")
    Q0 = static_wheel_loads(Q.values[0])                                   # (8, cases)
    ds["Q0_N"] = (("wheel", "case"), Q0, {"units": "N", "long_name": "static wheel load Q0 (wheelset mean, level track)"})
    attrs = {"units": "1", "long_name": "wheel unloading ΔQ/Q0 = (Q0 - Q)/Q0 (positive: unloaded)"}
    ds["dqq"] = (("time", "wheel", "case"), wheel_unloading(Q.values, Q0), {**attrs, **({"column": column} if column else {})})


def per_case(da: xr.DataArray, scale: float = 1.0, label: str = "") -> List[Curve]:
    """One curve per case of ``da`` (time x case) against time, labelled by its k."""
    return [Curve(da["time"].values, da.sel(case=c).values * scale, f"{label}{k_legend(float(k))}")
            for c, k in zip(da["case"].values, da["k_W_per_K"].values)]


def bellow_panels(ds: xr.Dataset) -> List[Panel]:
    """Pressure and temperature of each bellow, one curve per case of ``ds``."""
    return ([Panel(per_case(ds["bellow_p_Pa"].sel(bellow=b), 1e-5), "time t [s]", f"p_{b} [bar abs]", f"bellow {b}")
             for b in BELLOWS] +
            [Panel(per_case(ds["bellow_T_K"].sel(bellow=b)), "time t [s]", f"T_{b} [K]", f"bellow {b}")
             for b in BELLOWS])


def of_setting(ds: xr.Dataset, valves: Optional[bool]) -> xr.Dataset:
    """The cases of one valve setting (None: every case)."""
    return ds if valves is None else ds.isel(case=np.flatnonzero(ds["valves"].values == valves))


def air_columns(case: xr.Dataset) -> Dict[str, float]:
    """The air a case exchanged (cumulative, at its last sample) [kg]: injected from the supply,
    exhausted by the valves, lost through the faults' openings; and the error of the mass balance
    air(end) - air(start) - net inflow from outside (= injected - exhausted - lost with a fixed
    supply; a finite supply is a chamber, its air moves within), which closes to the
    integrator's round-off (the circuit holds every term as a state)."""
    m = case["total_mass_kg"].values
    return {"air_injected_kg": float(case["air_from_supply_kg"].values[-1]),
            "air_exhausted_kg": float(case["air_to_atmosphere_kg"].values[-1]) + 0.0,   # no "-0"
            "air_lost_kg": float(case["air_lost_kg"].values[-1]) + 0.0,
            "mass_balance_error_kg": float(m[-1] - m[0] - case["net_inflow_kg"].values[-1])}


def fault_figure(scenario: Scenario, ds: xr.Dataset, suffix: str = "", valves_text: str = "") -> List[Figure]:
    """With faults: the air lost through their openings, the flow of every differential valve
    and the flow through every faulted link (each against time, one curve per case); none
    without faults."""
    faults = scenario.circuit.faults
    if not faults:
        return []
    panels = [Panel(per_case(ds["air_lost_kg"], 1e3), "time t [s]", "air lost [g]", "through the faults' openings")]
    circuit = scenario.circuit.compile()
    ends = dict(zip(circuit.link_names, circuit.link_ends()))
    links = [str(n) for n in ds["link"].values] if "link" in ds.dims else []
    named = {f.component for f in faults}
    shown = [n for n in links if n in ends and (isinstance(circuit.components.get(n), DifferentialPressureValve)
                                                or n.split(".")[0] in named or named & set(ends[n]))]
    for link in shown:
        flow = ds["link_flow_kg_per_s"].sel(link=link)
        if np.all(np.isnan(flow.values)):
            continue                                  # a link of the other valve setting's circuit
        a, b = ends[link]
        panels.append(Panel(per_case(flow, 1e3), "time t [s]", f"flow {a} → {b} [g/s]", link))
    return [Figure(f"faults{suffix}.png", panels, f"Air lost and flows of the faulted and differential valves"
                                                  f"{valves_text}", 2)]


#: the window before a fault over which the state it strikes is averaged [s]
BEFORE_FAULT_S = 1.0


def fault_columns(scenario: Scenario, case: xr.Dataset) -> Dict[str, float]:
    """The transient after the first fault that happens during the run (t > 0; none: no columns):
    ``roll_before_fault_rad``, the carbody roll (to the track plane where the run has it)
    averaged over the second before; ``roll_max_after_fault_rad``, its largest magnitude after;
    ``dqq_max_after_fault``, the largest wheel unloading ΔQ/Q0 after (its EN 14363 2 m mean where
    the run has it); ``yq_2m_max_after_fault`` likewise for Y/Q on the wheel-rail contact."""
    times = [f.t_s for f in scenario.circuit.faults if f.t_s > 0.0]
    if not times:
        return {}
    t_fault = min(times)
    t = case["time"].values
    after, before = t >= t_fault, (t >= t_fault - BEFORE_FAULT_S) & (t < t_fault)
    if not after.any():                               # the run stopped before the fault
        return {}
    roll = case["roll_rel_rad"] if "roll_rel_rad" in case else case["roll_rad"]
    dqq = case["dqq_2m"] if "dqq_2m" in case else case["dqq"]
    columns = {"roll_before_fault_rad": float(np.mean(roll.values[before])) if before.any() else float("nan"),
               "roll_max_after_fault_rad": float(np.max(np.abs(roll.values[after]))),
               "dqq_max_after_fault": float(np.max(dqq.transpose("time", "wheel").values[after]))}
    if "y_over_q_2m" in case:
        columns["yq_2m_max_after_fault"] = float(np.max(case["y_over_q_2m"].transpose("time", "wheel").values[after]))
    return columns
