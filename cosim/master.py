"""The co-simulation master: advances exudyn cars and one batched pneumatic circuit in macro-steps.

Scheme (Gauss-Seidel, mechanics first), over each macro-step [t_n, t_n + H]:

1. Pneumatics -> mechanics: the bellow force F_n = A_e (p_b - p_atm) (eq. 4) at the pneumatic
   state x_n and crushing z_n. With ``coupling = "linearised"`` (default) the car also receives
   the bellow's instantaneous stiffness K_n = dF/dz at constant air mass (adiabatic, or isothermal
   for k = inf: the air in the pipe cannot move instantly), and applies
   F(z) = F_mid + K_n (z - z_n) within the step: the volume change, the stiff part, is taken
   implicitly by the multibody solver; the slow part (air flowing through the pipes and valves,
   heat exchange) is held at its value predicted for the middle of the step, F_mid = F(x_n +
   H/2 dx/dt|_{z frozen}). Holding it at F_n instead lags by H/2 and destabilises the lightly
   damped pipe-suspension modes (there are no dampers). With ``"explicit"`` the force F_n is held
   constant (K = 0): first order, for comparison.
2. The cars advance to t_n + H (exudyn, implicit generalized-alpha, their own step).
3. Mechanics -> pneumatics: the crushing and its rate at t_n and t_n + H define a cubic Hermite
   interpolant of z(t) over the step; the circuit integrates x_n -> x_{n+1} with RK4 along it.

Several cars (one per k value) share one batched circuit whose columns are the k cases, so the
pneumatic cost per macro-step is paid once for all of them.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np

from pneumatics.circuit import Circuit, CircuitDiverged
from pneumatics.integrate import advance, stable_step_s

COUPLINGS = ("linearised", "explicit")


def hermite_motion(t0: float, t1: float, z0, zd0, z1, zd1):
    """Cubic Hermite interpolation of the crushing over [t0, t1]: matches z and dz/dt at both ends."""
    H = t1 - t0
    dz = z1 - z0

    def motion(t):
        s = (t - t0) / H
        s2, s3 = s * s, s * s * s
        z = z0 + (3 * s2 - 2 * s3) * dz + (s - 2 * s2 + s3) * H * zd0 + (s3 - s2) * H * zd1
        zd = (6 * s - 6 * s2) * dz / H + (1 - 4 * s + 3 * s2) * zd0 + (3 * s2 - 2 * s) * zd1
        return z, zd
    return motion


@dataclass
class Record:
    """Sampled co-simulation output: arrays (samples, ..., cases)."""

    t_s: List[float] = field(default_factory=list)
    wheel_load_N: List[np.ndarray] = field(default_factory=list)      # (8, cases)
    crushing_m: List[np.ndarray] = field(default_factory=list)        # (4, cases)
    bellow_force_N: List[np.ndarray] = field(default_factory=list)    # (4, cases)
    bellow_p_Pa: List[np.ndarray] = field(default_factory=list)       # (4, cases)
    bellow_T_K: List[np.ndarray] = field(default_factory=list)        # (4, cases)
    roll_rad: List[np.ndarray] = field(default_factory=list)          # (cases,)
    air_from_supply_kg: List[np.ndarray] = field(default_factory=list)  # (cases,)
    air_to_atmosphere_kg: List[np.ndarray] = field(default_factory=list)  # (cases,)
    link_flow_kg_per_s: List[np.ndarray] = field(default_factory=list)  # (links, cases), a -> b
    total_mass_kg: List[np.ndarray] = field(default_factory=list)       # (cases,) air in all chambers

    def arrays(self) -> Dict[str, np.ndarray]:
        return {name: np.asarray(values) for name, values in vars(self).items()}


class CoSimulation:
    """Couple ``cars`` (exudyn models with the vehicle.car.MetroCar interface) to ``circuit``,
    whose k array has one entry per car."""

    def __init__(self, cars: Sequence, circuit: Circuit, x0: np.ndarray, macro_step_s: float,
                 pneumatic_step_s: float, coupling: str = "linearised"):
        if coupling not in COUPLINGS:
            raise ValueError(f"coupling must be one of {COUPLINGS}, got {coupling!r}")
        self.cars, self.circuit, self.x = list(cars), circuit, x0.copy()
        self.H, self.coupling = macro_step_s, coupling
        self.h_pneumatic = stable_step_s(circuit, x0, pneumatic_step_s)
        self.t = 0.0
        self.z, self.zd = self._crushing()
        self._supply = "supply" in circuit.node_names

    def _crushing(self):
        zs, zds = zip(*(car.bellow_crushing() for car in self.cars))
        return np.stack(zs, axis=1), np.stack(zds, axis=1)

    def step(self) -> None:
        """One macro-step (see the module docstring)."""
        t1 = self.t + self.H
        if self.coupling == "linearised":
            # Held part (mass and heat exchange) predicted at the step's midpoint: one Euler
            # half-step at frozen volume, so the force the car feels lags by O(H^2), not H/2.
            held_rate = self.circuit.derivatives(self.x, self.z, np.zeros_like(self.z))
            F = self.circuit.bellow_forces_N(self.x + 0.5 * self.H * held_rate, self.z)
            K = self.circuit.bellow_stiffness_N_per_m(self.x, self.z)
        else:
            F, K = self.circuit.bellow_forces_N(self.x, self.z), None
        for j, car in enumerate(self.cars):
            car.set_bellow_forces(F[:, j], None if K is None else K[:, j])
            car.advance(t1)
        z1, zd1 = self._crushing()
        motion = hermite_motion(self.t, t1, self.z, self.zd, z1, zd1)
        self.x = advance(self.circuit, self.x, self.t, t1, motion, self.h_pneumatic)
        self.circuit.check_state(self.x, t1)
        self.t, self.z, self.zd = t1, z1, zd1

    def sample(self, record: Record) -> None:
        c = self.circuit
        out = c.outputs(self.x, self.z)
        idx = [c.chamber_names.index(b) for b in c.bellow_names]
        record.t_s.append(self.t)
        record.wheel_load_N.append(np.stack([car.wheel_loads_N() for car in self.cars], axis=1))
        record.crushing_m.append(self.z.copy())
        record.bellow_force_N.append(out.bellow_force_N)
        record.bellow_p_Pa.append(out.p_Pa[idx])
        record.bellow_T_K.append(out.T_K[idx])
        record.roll_rad.append(np.array([car.carbody_roll_rad() for car in self.cars]))
        zero = np.zeros(len(self.cars))
        record.air_from_supply_kg.append(c.mass_from(self.x, "supply") if self._supply else zero)
        record.air_to_atmosphere_kg.append(-c.mass_from(self.x, "atmosphere"))
        record.link_flow_kg_per_s.append(out.link_flow_kg_per_s)
        record.total_mass_kg.append(c.total_mass_kg(self.x))

    def run(self, t_end_s: float, output_interval_s: float,
            progress: Optional[Callable[[str, bool], None]] = None) -> tuple[Record, Optional[str]]:
        """Advance to ``t_end_s``, sampling every ``output_interval_s``. Returns the record and,
        if the run diverged, a diagnosis (the record then holds everything up to that point)."""
        record = Record()
        every = max(1, round(output_interval_s / self.H))
        n = round(t_end_s / self.H)
        self.sample(record)
        for i in range(1, n + 1):
            try:
                self.step()
            except CircuitDiverged as exc:
                return record, str(exc)
            except Exception as exc:  # the multibody solver failed: keep what was computed
                return record, f"multibody solver failed at t = {self.t:.6g} s: {exc}"
            if i % every == 0 or i == n:
                self.sample(record)
            if progress:
                progress(f"t = {self.t:6.2f} / {t_end_s:g} s", False)
        return record, None
