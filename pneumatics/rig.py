"""Virtual test rig for a bellow (with or without its auxiliary tank) under prescribed crushing (paper §3).

Experiments: ramp (Fig. 3), sinusoidal time histories (Fig. 5), the dynamic-stiffness sweep on the
periodic steady state (eq. 9, Fig. 6) and the quasi-static stiffness (Table 2).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Callable, Dict, Iterable, List, Optional

import numpy as np

from .chamber import Bellow, Tank, quasi_static_stiffness_N_per_m
from .circuit import Circuit
from .integrate import Motion, simulate, stable_step_s
from .periodic import one_period, periodic_steady_state, sine_phase_motion
from .pipe import Pipe

BELLOW, TANK, PIPE = "bellow", "tank", "pipe"


def bellow_tank_components(bellow: Bellow, tank: Optional[Tank], pipe: Optional[Pipe]) -> Dict[str, object]:
    """The rig's circuit: a bellow, and optionally a tank joined to it by a pipe (Fig. 4a)."""
    comps: Dict[str, object] = {BELLOW: bellow}
    if tank is not None:
        comps[TANK] = tank
        comps[PIPE] = dataclasses.replace(pipe, a=BELLOW, b=TANK)
    return comps


def ramp_motion(amplitude_m: float, ramp_s: float) -> Motion:
    """Crushing rising linearly from 0 to ``amplitude_m`` over ``ramp_s``, then held."""
    rate = amplitude_m / ramp_s

    def motion(t):
        return np.array([amplitude_m * min(t / ramp_s, 1.0)]), np.array([rate if t < ramp_s else 0.0])
    return motion


def sine_motion(amplitude_m: float, frequency_Hz: float) -> Motion:
    """z = a sin(2 pi f t)."""
    w = 2.0 * math.pi * frequency_Hz

    def motion(t):
        return np.array([amplitude_m * math.sin(w * t)]), np.array([amplitude_m * w * math.cos(w * t)])
    return motion


@dataclass
class TimeSeries:
    """Rig response sampled at ``t_s``; per-chamber arrays are (chambers, samples)."""

    t_s: np.ndarray
    z_m: np.ndarray
    force_N: np.ndarray
    p_Pa: np.ndarray
    T_K: np.ndarray
    chamber_names: List[str]
    pipe_mach: np.ndarray             # largest pipe flow Mach number |q| / (rho A c), c at the colder end
    diagnosis: Optional[str] = None   # why the integration stopped early (the arrays end there)


def run_time_series(components: Dict[str, object], k_W_per_K: float, motion: Motion, t_end_s: float,
                    n_samples: int, max_step_s: float = np.inf, p0_Pa: Optional[Dict[str, float]] = None,
                    rtol: float = 1e-8) -> TimeSeries:
    """Integrate the rig with scipy's LSODA (error-controlled) and sample it uniformly."""
    circuit = Circuit(components, k_W_per_K=k_W_per_K)
    x0 = circuit.initial_state(p0_Pa)
    t = np.linspace(0.0, t_end_s, n_samples)
    sol = simulate(circuit, x0, t_end_s, motion, t_eval=t, max_step_s=max_step_s, rtol=rtol)
    diagnosis = None
    if not sol.success:
        lay = circuit.layout
        state = {f"{q}_{n}": sol.y[sl][i, -1] for q, sl in (("m_kg", lay.m), ("T_K", lay.T))
                 for i, n in enumerate(circuit.chamber_names)} if sol.t.size else {}
        diagnosis = (f"integration stopped at t = {sol.t[-1] if sol.t.size else 0.0:.6g} s "
                     f"(k = {k_W_per_K:g} W/K): {sol.message}; last state " + ", ".join(f"{k}={v:.6g}" for k, v in state.items()))
    t = sol.t
    z = np.array([motion(ti)[0] for ti in t]).T.reshape(1, -1)
    out = circuit.outputs(sol.y, z)
    return TimeSeries(t, z[0], out.bellow_force_N[0], out.p_Pa, out.T_K, circuit.chamber_names,
                      pipe_mach_number(circuit, sol.y, out), diagnosis)


def pipe_mach_number(circuit: Circuit, x: np.ndarray, out) -> np.ndarray:
    """Largest Mach number over the dynamic pipes, per sample: eq. (5) is an incompressible law,
    outside its validity beyond Mach ~0.3 (docs/models.md erratum 4). Velocity |q| / (rho_mean A),
    sound speed sqrt(gamma R T) at the colder end."""
    names = circuit.pipe_names
    if not names:
        return np.zeros(x.shape[-1])
    gas, chambers = circuit.gas, circuit.chamber_names
    mach = []
    for i, name in enumerate(names):
        pipe = circuit.components[name]
        ends = [chambers.index(n) for n in (pipe.a, pipe.b) if n in chambers]
        rho = np.mean([out.p_Pa[j] / (gas.R_J_per_kgK * out.T_K[j]) for j in ends], axis=0)
        c = np.sqrt(gas.gamma * gas.R_J_per_kgK * np.min([out.T_K[j] for j in ends], axis=0))
        mach.append(np.abs(x[circuit.layout.q][i]) / (rho * pipe.area_m2 * c))
    return np.max(mach, axis=0)


@dataclass
class StiffnessPoint:
    """One (k, f) case of the dynamic-stiffness sweep, on its periodic steady state."""

    k_W_per_K: float
    frequency_Hz: float
    K_dyn_N_per_m: float          # eq. (9): (Fmax - Fmin) / (2 z_max)
    F_min_N: float
    F_max_N: float
    T_bellow_mean_K: float
    T_bellow_max_K: float
    stabilised: bool
    residual: float               # scaled periodicity residual
    floquet_max: float            # largest Floquet multiplier modulus (< 1: the orbit attracts)
    cycles_to_settle: float       # cycles for a disturbance to decay by 1e3 (from floquet_max)
    pipe_mach_max: float          # largest pipe Mach number along the orbit (see pipe_mach_number)
    K_storage_N_per_m: float      # first harmonic of F in phase with z = a sin(wt), over a: K' (Re K*)
    K_loss_N_per_m: float         # first harmonic in quadrature (with dz/dt), over a: K'' (Im K*)
    loop_phase: np.ndarray        # the periodic orbit, decimated: phase in [0, 1)
    loop_F_N: np.ndarray          # bellow force along it
    loop_T_K: np.ndarray          # bellow temperature along it


def sweep_step_counts(frequencies_Hz: np.ndarray, dt_max_s: float, n_min: int) -> np.ndarray:
    """RK4 steps per period: at least ``n_min``, and short enough for the stiffest case (dt_max)."""
    return np.maximum(n_min, np.ceil(1.0 / (np.asarray(frequencies_Hz) * dt_max_s))).astype(int)


def _group_by_steps(steps: np.ndarray, ratio: float = 1.3) -> List[np.ndarray]:
    """Indices of cases grouped so that each group's step count is within ``ratio`` of its smallest."""
    order = np.argsort(steps)
    groups, current = [], [order[0]]
    for i in order[1:]:
        if steps[i] <= ratio * steps[current[0]]:
            current.append(i)
        else:
            groups.append(np.array(current))
            current = [i]
    groups.append(np.array(current))
    return groups


def dynamic_stiffness_sweep(components: Dict[str, object], k_values: Iterable[float], frequencies_Hz: Iterable[float],
                            amplitude_m: float, p0_Pa: Optional[Dict[str, float]] = None, n_min: int = 400,
                            dt_max_s: float = 5e-3, tol: float = 1e-9, max_iter: int = 20,
                            progress: Optional[Callable[[str], None]] = None) -> List[StiffnessPoint]:
    """K_dyn (eq. 9) on the periodic steady state, for every k and frequency.

    Cases (k, f) whose periods need similar numbers of RK4 steps (``dt_max_s`` or the thermal
    stability limit of the largest finite k, at least ``n_min`` per period) are solved as one
    batch. Where Newton fails for a case (small k run very hot near the pipe resonance, far from
    the atmospheric start), it is retried from the periodic state of a converged neighbour: the
    next larger k at the same frequency, then, round after round, the nearest converged
    frequency at the same k (see _solve_with_continuation).
    """
    ks = np.array(sorted(set(float(k) for k in k_values), reverse=True))
    freqs = np.array(sorted(set(float(f) for f in frequencies_Hz)))
    k_cases, f_cases = (a.ravel() for a in np.meshgrid(ks, freqs, indexing="ij"))
    probe = Circuit(components, k_W_per_K=k_cases)
    x_rest = probe.initial_state(p0_Pa)[:, 0]
    dt = stable_step_s(probe, x_rest, dt_max_s)
    steps = sweep_step_counts(f_cases, dt, n_min)
    points: List[StiffnessPoint] = []
    for group in _group_by_steps(steps):
        n_steps = int(steps[group].max())
        f, k = f_cases[group], k_cases[group]
        if progress:
            progress(f"{group.size} cases, {f.min():g}-{f.max():g} Hz, {n_steps} RK4 steps per period")
        circuit, res = _solve_with_continuation(components, k, f, x_rest, amplitude_m, n_steps, tol, max_iter)
        points += _stiffness_points(circuit, res, f, k, amplitude_m, n_steps)
    points.sort(key=lambda p: (-p.k_W_per_K, p.frequency_Hz))
    return points


def _solve_with_continuation(components, k, f, x_rest, amplitude_m, n_steps, tol, max_iter,
                             max_continuation_rounds: int = 6):
    """Batched shooting for cases (k, f); failed cases are continued in k (see dynamic_stiffness_sweep)."""
    motion = sine_phase_motion(amplitude_m)

    def solve(k_c, x_start, period_s):
        circuit = Circuit(components, k_W_per_K=k_c)
        return circuit, periodic_steady_state(circuit, x_start, period_s, motion, n_steps=n_steps, tol=tol,
                                              max_iter=max_iter)

    circuit, res = solve(k, np.repeat(x_rest[:, None], k.size, axis=1), 1.0 / f)
    # Continuation for the failed cases, in batches: first from the periodic state of the next
    # larger k at the same frequency, then, round after round, from the nearest frequency that
    # converged at the same k (walking along the resonance curve as it heats up).
    tried = set()

    def donor_of(i, by_frequency):
        if not by_frequency:
            same_f = np.flatnonzero((f == f[i]) & (k > k[i]) & res.stabilised)
            return same_f[np.argmin(k[same_f])] if same_f.size else None
        same_k = np.flatnonzero((k == k[i]) & res.stabilised)
        return same_k[np.argmin(np.abs(np.log(f[same_k] / f[i])))] if same_k.size else None

    for round_ in range(max_continuation_rounds):
        pairs = [(i, donor_of(i, round_ > 0)) for i in np.flatnonzero(~res.stabilised & (k > 0))]
        pairs = [(i, d) for i, d in pairs if d is not None and (i, d) not in tried]
        if not pairs:
            if round_ > 0:
                break
            continue
        tried.update(pairs)
        retry = np.array([i for i, _ in pairs], dtype=int)
        _, again = solve(k[retry], res.x0[:, [d for _, d in pairs]], 1.0 / f[retry])
        better = again.stabilised
        for name in ("x0", "residual", "floquet_max", "converged"):
            getattr(res, name)[..., retry[better]] = getattr(again, name)[..., better]
    return circuit, res


def _stiffness_points(circuit: Circuit, res, f: np.ndarray, k: np.ndarray, amplitude_m: float, n_steps: int):
    """Eq. (9) and the record of every case along one period of its periodic state."""
    forces, temps, mach = [], [], []
    ib = circuit.chamber_names.index(BELLOW)
    motion = sine_phase_motion(amplitude_m)

    def observe(tau, x):
        z, _ = motion(tau, 1.0 / f)
        out = circuit.outputs(x, z)
        forces.append(out.bellow_force_N[0])
        temps.append(out.T_K[ib])
        mach.append(pipe_mach_number(circuit, x, out))

    one_period(circuit, res.x0, 1.0 / f, motion, n_steps, observe)
    F, T, M = np.array(forces), np.array(temps), np.array(mach)
    phase = np.arange(1, n_steps + 1) / n_steps
    # complex stiffness K* = K' + i K'': F's first Fourier coefficients over the period (the n_steps
    # samples are equally spaced in phase: the rectangle rule is exact for a trigonometric polynomial)
    K_storage = 2.0 / n_steps * (np.sin(2 * np.pi * phase) @ F) / amplitude_m
    K_loss = 2.0 / n_steps * (np.cos(2 * np.pi * phase) @ F) / amplitude_m
    keep = np.unique(np.linspace(0, n_steps - 1, 64).astype(int))     # 64 points per loop for the record
    out = []
    for i in range(f.size):
        fl = res.floquet_max[i]
        settle = math.log(1e-3) / math.log(fl) if 0.0 < fl < 1.0 else (0.0 if fl == 0.0 else math.inf)
        out.append(StiffnessPoint(float(k[i]), float(f[i]), float((F[:, i].max() - F[:, i].min()) / (2 * amplitude_m)),
                                  float(F[:, i].min()), float(F[:, i].max()), float(T[:, i].mean()), float(T[:, i].max()),
                                  bool(res.stabilised[i]), float(res.residual[i]), float(fl), settle, float(M[:, i].max()),
                                  float(K_storage[i]), float(K_loss[i]), phase[keep], F[keep, i], T[keep, i]))
    return out


@dataclass
class QuasiStaticStiffness:
    """Table 2: analytic n A^2 p0 / V and the simulated slope of a slow small ramp."""

    configuration: str     # "bellow and tank" or "bellow only"
    regime: str            # "adiabatic" or "isothermal"
    analytic_N_per_m: float
    simulated_N_per_m: float


def quasi_static_stiffness_table(bellow: Bellow, tank: Tank, pipe: Pipe, p0_Pa: float, gamma: float,
                                 amplitude_m: float = 1e-4, ramp_s: float = 20.0) -> List[QuasiStaticStiffness]:
    """Table 2 analytically and by simulation: a 0.1 mm ramp over 20 s for k = 0 and k = inf. The
    pipe flow is then quasi-static (its pressure drop is < 1e-6 of p0) and the slope over the
    ramp differs from the tangent stiffness by < 0.15 % (volume change 0.1 % of a bellow)."""
    rows = []
    for config, tank_ in (("bellow and tank", tank), ("bellow only", None)):
        V = bellow.V0_m3 + (tank_.V_m3 if tank_ else 0.0)
        comps = bellow_tank_components(bellow, tank_, pipe)
        p0 = {name: p0_Pa for name, c in comps.items() if isinstance(c, (Bellow, Tank))}
        for regime, k, n in (("adiabatic", 0.0, gamma), ("isothermal", math.inf, 1.0)):
            ts = run_time_series(comps, k, ramp_motion(amplitude_m, ramp_s), ramp_s, 3, p0_Pa=p0)
            rows.append(QuasiStaticStiffness(config, regime, quasi_static_stiffness_N_per_m(bellow, p0_Pa, V, n),
                                             (ts.force_N[-1] - ts.force_N[0]) / amplitude_m))
    return rows
