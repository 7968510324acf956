"""Periodic steady state of a circuit under periodic bellow motion, by shooting.

Integrating each case until it "looks" stable takes minutes (the slowest thermal time constant,
m c_v / k, is ~10 s for a tank at k = 10 W/K) and leaves the criterion vague. Here the periodic
state is solved for directly: find x0 with Phi(x0) = x0, Phi the one-period flow map, by Newton's
method with a finite-difference monodromy matrix. All cases (k values, frequencies) and all
finite-difference perturbations are one batched, time-normalised RK4 integration.

A case counts as **stabilised** when
  1. Newton converged: max |Phi(x0) - x0| / scale < ``tol`` (scales: chamber mass, 300 K, 0.01 kg/s);
  2. the orbit attracts: every Floquet multiplier (eigenvalue of the monodromy matrix,
     restricted to the states of constant total mass in a closed circuit) has modulus < 1.
An adiabatic circuit (k = 0) has no stable periodic state: its temperature rises every cycle.
It is reported as not stabilised, never as a stiffness.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .circuit import Circuit
from .integrate import rk4

#: phase motion: (tau in [0, 1], period_s (cases,)) -> (z_m, zdot_m_per_s), each (bellows, cases)
PhaseMotion = Callable[[float, np.ndarray], tuple]


@dataclass
class PeriodicResult:
    x0: np.ndarray               # (size, cases) state at phase 0 of the periodic orbit
    residual: np.ndarray         # (cases,) scaled max |Phi(x0) - x0|
    floquet_max: np.ndarray      # (cases,) largest |multiplier|
    converged: np.ndarray        # (cases,) Newton converged
    iterations: int

    @property
    def stabilised(self) -> np.ndarray:
        return self.converged & (self.floquet_max < 1.0)


def sine_phase_motion(amplitude_m: float, n_bellows: int = 1) -> PhaseMotion:
    """z = a sin(2 pi tau) on every bellow, tau = t / period."""
    def motion(tau, period_s):
        w = 2.0 * np.pi
        z = np.full((n_bellows, period_s.size), amplitude_m * np.sin(w * tau))
        zd = np.broadcast_to(amplitude_m * w * np.cos(w * tau) / period_s, (n_bellows, period_s.size))
        return z, zd
    return motion


def one_period(circuit: Circuit, x: np.ndarray, period_s: np.ndarray, motion: PhaseMotion, n_steps: int,
               observe=None) -> np.ndarray:
    """Integrate every column of ``x`` over one period of its own length, in phase tau in [0, 1]."""
    def f(tau, xx):
        z, zd = motion(tau, period_s)
        return circuit.derivatives(xx, z, zd) * period_s
    return rk4(f, x, 0.0, 1.0, n_steps, observe)


def _scales(circuit: Circuit, x: np.ndarray) -> np.ndarray:
    lay = circuit.layout
    s = np.empty(lay.n_dynamic)
    s[lay.m] = np.max(x[lay.m], axis=1)
    s[lay.T] = 300.0
    s[lay.q] = 0.01
    return s


def periodic_steady_state(circuit: Circuit, x_start: np.ndarray, period_s: np.ndarray, motion: PhaseMotion, *,
                          n_steps: int = 2000, warmup_periods: int = 3, tol: float = 1e-9, max_iter: int = 15,
                          fd_step: float = 1e-6) -> PeriodicResult:
    """Solve Phi(x0) = x0 for every case (column) of ``x_start`` by Newton shooting.

    ``circuit`` carries one k per case. The accumulator states are carried along but not solved
    for. In a closed circuit (no link to a boundary node) the total mass is an invariant: one
    chamber mass is eliminated and set from the others, which keeps the Newton system regular.
    """
    lay = circuit.layout
    nd, n_cases = lay.n_dynamic, x_start.shape[1]
    closed = not np.any(circuit.assembly.links.boundary_sign)
    free = np.arange(nd)
    if closed:
        free = free[free != lay.m.start]       # mass of the first chamber follows from the total
    total_mass = circuit.total_mass_kg(x_start)
    scale = _scales(circuit, x_start)

    def close_mass(x):
        if closed:
            total = np.tile(total_mass, x.shape[1] // n_cases)
            x[lay.m.start] = total - x[lay.m][1:].sum(axis=0)
        return x

    x = x_start.copy()
    for _ in range(warmup_periods):
        x = one_period(circuit, x, period_s, motion, n_steps)
    x[nd:] = 0.0

    nf = free.size
    tiled_k = np.tile(np.broadcast_to(circuit.k_W_per_K, (n_cases,)), nf + 1)
    batch = Circuit(circuit.components, gas=circuit.gas, atmosphere=circuit.atmosphere, k_W_per_K=tiled_k)
    tiled_period = np.tile(period_s, nf + 1)
    converged = np.zeros(n_cases, bool)
    floquet = np.full(n_cases, np.nan)
    eps = fd_step * scale[free]
    # Newton with non-monotone backtracking: a step that multiplies a case's residual by more
    # than 4 is halved and retried (the trial costs nothing extra: every case is integrated every
    # iteration anyway). Near-neutral thermal modes (multipliers ~0.99) need large first steps
    # that may raise the residual before it collapses, hence the tolerance.
    best_res = np.full(n_cases, np.inf)
    best_x = x.copy()
    best_floquet = floquet.copy()
    step = np.zeros((nf, n_cases))
    given_up = np.zeros(n_cases, bool)
    it = 0
    for it in range(1, max_iter + 1):
        X = np.tile(x, nf + 1)
        for i, j in enumerate(free):
            X[j, (i + 1) * n_cases:(i + 2) * n_cases] += eps[i]
        X = close_mass(X)
        Y = one_period(batch, X, tiled_period, motion, n_steps)
        r = (Y[:nd, :n_cases] - X[:nd, :n_cases])[free] / scale[free, None]
        residual = np.max(np.abs(r), axis=0)
        residual[~np.isfinite(residual)] = np.inf
        # monodromy of the reduced map, in scaled variables
        mono = np.empty((n_cases, nf, nf))
        for i, j in enumerate(free):
            dY = (Y[:nd, (i + 1) * n_cases:(i + 2) * n_cases] - Y[:nd, :n_cases])[free] / scale[free, None]
            mono[:, :, i] = (dY / (eps[i] / scale[j])).T
        heat = circuit.assembly.heat
        if heat.any_isothermal and not heat.per_chamber:
            # Held temperatures are not states of an isothermal case: drop them from the map.
            held = np.isin(free, np.arange(lay.T.start, lay.T.stop))
            iso = np.broadcast_to(heat.isothermal, (n_cases,))
            mono[np.ix_(iso, held, np.arange(nf))] = 0.0
            mono[np.ix_(iso, np.arange(nf), held)] = 0.0
        elif heat.any_isothermal:
            # ... nor of an isothermal chamber (its own k = inf, or its case's): per case
            iso = np.broadcast_to(heat.isothermal, (lay.n_chambers, n_cases))
            temperature = (free >= lay.T.start) & (free < lay.T.stop)
            held = np.zeros((n_cases, nf), bool)
            held[:, temperature] = iso[free[temperature] - lay.T.start].T
            mono[held[:, :, None] | held[:, None, :]] = 0.0
        mono[~np.isfinite(mono)] = np.nan
        finite = np.all(np.isfinite(mono), axis=(1, 2))
        floquet = np.full(n_cases, np.nan)
        floquet[finite] = np.max(np.abs(np.linalg.eigvals(mono[finite])), axis=1)

        accept = (residual <= 4.0 * best_res) & ~given_up
        best_res = np.where(accept, residual, best_res)
        best_x[:, accept] = x[:, accept]
        best_floquet = np.where(accept, floquet, best_floquet)
        converged = best_res < tol
        reject = ~accept & ~converged & ~given_up
        step[:, reject] *= 0.5
        given_up |= reject & (np.max(np.abs(step), axis=0) < 1e-9)
        if np.all(converged | given_up):
            break
        new = accept & ~converged & finite
        if np.any(new):
            J = mono[new] - np.eye(nf)
            step[:, new] = np.linalg.solve(J, -r.T[new][..., None])[..., 0].T
            # Damp steps that would move a mass or temperature by more than 30 % (keeps them > 0).
            bounded = free < lay.q.start
            relative = np.abs(step[bounded][:, new]) * scale[free][bounded, None] / np.abs(x[free][bounded][:, new])
            step[:, new] /= np.maximum(np.max(relative, axis=0) / 0.3, 1.0)
        step[:, converged | given_up] = 0.0
        x = best_x.copy()
        x[free] += step * scale[free, None]
        x = close_mass(x)
        x[nd:] = 0.0
    best_x[nd:] = 0.0
    return PeriodicResult(best_x, best_res, best_floquet, converged, it)
