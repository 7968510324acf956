"""A circuit linearised about a state (:func:`linearise_circuit`): the small-signal model the
running-stability analysis couples to the car's,

    dx' = A dx + B_z dz + B_zd dz',     dF = G_x dx + G_z dz,

x the circuit's physical states (chamber masses and temperatures, pipe flows, valve-signal
states; the accumulators, which feed nothing back, and states that cannot change, such as the
temperatures of isothermal chambers, left out), z and z' the bellows' crushing and its rate, F
the bellow forces (eq. 4). Central differences of :meth:`Circuit.derivatives` and
:meth:`Circuit.bellow_forces_N`, all perturbations evaluated in one vectorised call.

What the linearisation keeps and loses, about a state at rest:

* the pipe's pressure drop is quadratic in the flow (eq. 5), so it has no linear part at zero
  flow: the bellow-tank (Helmholtz) mode is damped in the linear model only by the heat exchange
  (k between 0 and inf); at k = 0 and k = inf it is undamped;
* the valves' dead bands (levelling, differential) hold them shut for small motions: they drop
  out, only their signal dynamics (delay, lag) remain, uncoupled;
* G_z is the stiffness at frozen air (mass and temperature held): the adiabatic or isothermal
  stiffness arises from the temperature's rate (eq. 2, p dV/dt), through B_zd.

:attr:`CircuitLinearisation.kinetic_energy` is the quadratic form of the air's kinetic energy,
L dq^2 / (2 rho A) of each pipe's air column: beside the car's bodies' kinetic energies it says how
much of a mode's motion is the air's. (Kinetic energies only: the air's acoustic potential energy
is also the potential energy of every mode the airsprings carry, the carbody's bounce as much as
the bellow-tank resonance, and says nothing about what moves.)
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import List

import numpy as np

from .circuit import Circuit
from .pipe import Pipe

__all__ = ["CircuitLinearisation", "linearise_circuit"]

#: central-difference steps, relative to each quantity's scale (round-off ~1e-16 / 1e-6 ~ 1e-10
#: relative, truncation ~1e-12)
RELATIVE_STEP = 1e-6
#: scales of the quantities that are zero at rest: pipe flow [kg/s], valve signal [m], crushing
#: [m], crushing rate [m/s]
FLOW_SCALE_KG_PER_S = 1e-3
SIGNAL_SCALE_M = 1e-3
CRUSHING_SCALE_M = 0.01
RATE_SCALE_M_PER_S = 0.01


@dataclass(frozen=True)
class CircuitLinearisation:
    """dx' = A dx + B_z dz + B_zd dz', dF = G_x dx + G_z dz (see the module docstring).

    Attributes
    ----------
    names : list of str
        Each state: ``m <chamber>`` [kg], ``T <chamber>`` [K], ``q <pipe>`` [kg/s],
        ``signal <i>`` (a valve-signal state) [m].
    index : (n,) int array
        Their positions in the circuit's state vector.
    A : (n, n) array [1/s]
    B_z, B_zd : (n, bellows) arrays
        Per metre of crushing, per m/s of crushing rate.
    G_x : (bellows, n) array
        Bellow force per unit state [N/kg, N/K, ...].
    G_z : (bellows, bellows) array
        Bellow stiffness at frozen air [N/m] (diagonal).
    kinetic_energy : (n, n) array
        The quadratic form of the air columns' kinetic energy, E = dx^T kinetic_energy dx / 2 [J].
    """

    names: List[str]
    index: np.ndarray
    A: np.ndarray
    B_z: np.ndarray
    B_zd: np.ndarray
    G_x: np.ndarray
    G_z: np.ndarray
    kinetic_energy: np.ndarray


def _central(f, x0: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """d f / d x at ``x0`` by central differences, f evaluated once on all 2 n perturbations as
    columns (f maps (n, cols) to (m, cols))."""
    n = x0.size
    X = np.repeat(x0[:, None], 2 * n, axis=1)
    X[np.arange(n), np.arange(n)] += steps
    X[np.arange(n), n + np.arange(n)] -= steps
    F = f(X)
    return (F[:, :n] - F[:, n:]) / (2.0 * steps)


def linearise_circuit(circuit: Circuit, x0, z0_m=None) -> CircuitLinearisation:
    """The circuit (one case: a scalar k) linearised about state ``x0`` (size,) at bellow crushing
    ``z0_m`` (default 0) and zero crushing rate (see the module docstring)."""
    if np.ndim(circuit.k_W_per_K) != 0:
        raise ValueError("linearise_circuit needs a circuit of one case (a scalar k)")
    lay = circuit.layout
    x0 = np.asarray(x0, dtype=float).reshape(lay.size)
    nb = len(circuit.bellow_names)
    z0 = np.zeros(nb) if z0_m is None else np.asarray(z0_m, dtype=float).reshape(nb)
    nc = lay.n_chambers
    index = np.r_[np.arange(lay.n_dynamic), np.arange(lay.size)[lay.valve_signal]].astype(int)
    names = ([f"m {c}" for c in circuit.chamber_names] + [f"T {c}" for c in circuit.chamber_names]
             + [f"q {p}" for p in circuit.pipe_names] + [f"signal {i}" for i in range(lay.n_valve_states)])
    scale = np.abs(x0[index])
    scale[2 * nc:2 * nc + lay.n_pipes] = np.maximum(scale[2 * nc:2 * nc + lay.n_pipes], FLOW_SCALE_KG_PER_S)
    scale[2 * nc + lay.n_pipes:] = np.maximum(scale[2 * nc + lay.n_pipes:], SIGNAL_SCALE_M)
    steps = RELATIVE_STEP * scale

    def full(cols: np.ndarray) -> np.ndarray:
        X = np.repeat(x0[:, None], cols.shape[1], axis=1)
        X[index] = cols
        return X

    def zs(cols: int) -> np.ndarray:
        return np.repeat(z0[:, None], cols, axis=1)

    A = _central(lambda c: circuit.derivatives(full(c), zs(c.shape[1]), np.zeros((nb, c.shape[1])))[index], x0[index], steps)
    G_x = _central(lambda c: circuit.bellow_forces_N(full(c), zs(c.shape[1])), x0[index], steps)
    base = lambda cols: np.repeat(x0[:, None], cols, axis=1)
    h_z = np.full(nb, RELATIVE_STEP * CRUSHING_SCALE_M)
    h_zd = np.full(nb, RELATIVE_STEP * RATE_SCALE_M_PER_S)
    B_z = _central(lambda c: circuit.derivatives(base(c.shape[1]), c, np.zeros_like(c))[index], z0, h_z)
    B_zd = _central(lambda c: circuit.derivatives(base(c.shape[1]), zs(c.shape[1]), c)[index], np.zeros(nb), h_zd)
    G_z = _central(lambda c: circuit.bellow_forces_N(base(c.shape[1]), c), z0, h_z)
    # states that cannot change (isothermal temperatures): constants, not states
    moving = np.any(A != 0.0, axis=1) | np.any(B_z != 0.0, axis=1) | np.any(B_zd != 0.0, axis=1)
    keep = np.flatnonzero(moving)
    energy = _kinetic_energy(circuit, x0, z0)[np.ix_(keep, keep)]
    return CircuitLinearisation([names[i] for i in keep], index[keep], A[np.ix_(keep, keep)], B_z[keep], B_zd[keep],
                                G_x[:, keep], G_z, energy)


def _kinetic_energy(circuit: Circuit, x0: np.ndarray, z0: np.ndarray) -> np.ndarray:
    """The air columns' kinetic energy's quadratic form over the states of :func:`linearise_circuit`
    (before states that cannot change are dropped): L / (rho A) on each pipe flow, rho the mean
    density of the chambers at its ends."""
    lay = circuit.layout
    nc = lay.n_chambers
    p, T = (v[:, 0] for v in circuit.chamber_states(x0, z0))
    R = circuit.gas.R_J_per_kgK
    size = 2 * nc + lay.n_pipes + lay.n_valve_states
    W = np.zeros((size, size))
    rho = dict(zip(circuit.chamber_names, p / (R * T)))
    for j, name in enumerate(circuit.pipe_names):
        pipe: Pipe = circuit.components[name]
        ends = [rho[e] for e in (pipe.a, pipe.b) if e in rho] or [circuit.atmosphere.p_Pa / (R * circuit.atmosphere.T_K)]
        W[2 * nc + j, 2 * nc + j] = pipe.length_m / (np.mean(ends) * pipe.area_m2)
    return W
