"""The co-simulation master: advances exudyn cars and one batched pneumatic circuit in macro-steps.

Scheme (Gauss-Seidel, mechanics first), over each macro-step [t_n, t_n + H]:

1. Pneumatics -> mechanics: a force law per bellow that the multibody solver evaluates at every
   internal step from its current state (``coupling = "linearised"``, default):

       F(t, z) = F_s + (F_e - F_s) (t - t_n) / H + K_n (z - z_n)

   * K_n = dF/dz at the pneumatic state x_n and crushing z_n, at constant air mass (adiabatic,
     or isothermal for k = inf): the volume change, the stiff part, is taken implicitly;
   * F_s is the force the car felt at the end of the previous step (F(x_0, z_0) at the start),
     so the force is continuous in time: no jump at macro-step boundaries;
   * F_e = F(x_n, z_n) + H dF/dt|_z, the slow part (air flowing through pipes and valves, heat
     exchange) extrapolated to the step end at frozen crushing (dF/dt|_z from an Euler
     half-step of the circuit at zero crushing rate). Anchored to the pneumatic state every
     step, the O(H^2) mismatch between F_s and F(x_n, z_n) is worked off within one step and
     does not accumulate.

   Holding the slow part constant over a step makes the force jump at every boundary; each
   jump enters the implicit integrator about half an internal step late, a first-order error
   that acts as artificial damping of the ~1 Hz sway (measured before this scheme: the curve's
   air injected converged at first order in the multibody step, 11.45 -> 13.2 g).
   With ``"explicit"`` the force F(x_n, z_n) is held constant (K = 0): first order, for
   comparison.
2. The cars advance to t_n + H (exudyn, implicit generalized-alpha, their own step).
3. Mechanics -> pneumatics: the crushing and its rate at t_n and t_n + H define a cubic Hermite
   interpolant of z(t) over the step; the circuit integrates x_n -> x_{n+1} with RK4 along it.

Order: every exchanged quantity is continuous and matches the true one to O(H^2) locally, so
the scheme is second order in H (``benchmarks/coupling_error.py`` and ``pneumorail verify``
measure it); the multibody integrator (generalized-alpha) and RK4 are second and fourth order in
their own steps.

Several cars (one per k value) share one batched circuit whose columns are the k cases, so the
pneumatic cost per macro-step is paid once for all of them.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np

from pneumatics.circuit import Circuit, CircuitDiverged
from vehicle.errors import Derailed

from cosim.interrupts import stop_requested
from cosim.limits.watch import StateWatch
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
    valve_supply_air_kg: List[np.ndarray] = field(default_factory=list)   # (valves, cases) cumulative
    valve_exhaust_air_kg: List[np.ndarray] = field(default_factory=list)  # (valves, cases) cumulative
    valve_supply_open_s: List[np.ndarray] = field(default_factory=list)   # (valves, cases) cumulative
    valve_exhaust_open_s: List[np.ndarray] = field(default_factory=list)  # (valves, cases) cumulative
    # wheel-rail outputs, sampled only when the cars run on the wheel-rail contact
    # (guidance="contact", :data:`CONTACT_FIELDS`); empty otherwise
    lateral_wheel_force_N: List[np.ndarray] = field(default_factory=list)     # (8, cases) Y, + towards the track centre
    wheelset_lateral_force_N: List[np.ndarray] = field(default_factory=list)  # (4, cases) ΣY, + left
    wheelset_lateral_m: List[np.ndarray] = field(default_factory=list)        # (4, cases) + left
    wheelset_lateral_to_rails_m: List[np.ndarray] = field(default_factory=list)  # (4, cases) + left
    angle_of_attack_rad: List[np.ndarray] = field(default_factory=list)       # (4, cases)
    flange_contact: List[np.ndarray] = field(default_factory=list)            # (8, cases) 1 / 0

    def arrays(self) -> Dict[str, np.ndarray]:
        """Every sampled output as an array (samples, ..., cases); the wheel-rail outputs only
        when they were sampled."""
        return {name: np.asarray(values) for name, values in vars(self).items()
                if values or name not in CONTACT_FIELDS}


#: Record entries of the wheel-rail contact -> (the MetroCar output each samples, its length)
CONTACT_FIELDS = {"lateral_wheel_force_N": (lambda car: car.lateral_wheel_forces_N(), 8),
                  "wheelset_lateral_force_N": (lambda car: car.wheelset_lateral_forces_N(), 4),
                  "wheelset_lateral_m": (lambda car: car.wheelset_lateral_displacement_m(), 4),
                  "wheelset_lateral_to_rails_m": (lambda car: car.contact_state().lateral_to_rails_m, 4),
                  "angle_of_attack_rad": (lambda car: car.angle_of_attack_rad(), 4),
                  "flange_contact": (lambda car: car.flange_contact(), 8)}


class CoSimulation:
    """Couple ``cars`` (exudyn models with the vehicle.car.MetroCar interface) to ``circuit``,
    whose k array has one entry per car.

    Cases are independent: one that diverges (its multibody solver fails, or its air leaves the
    physical range) is stopped and frozen, with a diagnosis, while the others go on; its record
    holds NaN from then on.
    """

    def __init__(self, cars: Sequence, circuit: Circuit, x0: np.ndarray, macro_step_s: float,
                 pneumatic_step_s: float, coupling: str = "linearised", case_labels: Optional[Sequence[str]] = None,
                 watch: Optional[StateWatch] = None):
        if coupling not in COUPLINGS:
            raise ValueError(f"coupling must be one of {COUPLINGS}, got {coupling!r}")
        self.cars, self.circuit, self.x = list(cars), circuit, x0.copy()
        self.H, self.coupling = macro_step_s, coupling
        self.h_pneumatic = stable_step_s(circuit, x0, pneumatic_step_s)
        self.t = 0.0
        self.labels = list(case_labels or (f"case {j}" for j in range(len(self.cars))))
        self.active = np.ones(len(self.cars), bool)
        self.diagnoses: List[str] = []
        self.z, self.zd = self._crushing()
        self._supply = "supply" in circuit.node_names
        self._bellow_chambers = [circuit.chamber_names.index(b) for b in circuit.bellow_names]
        self._F_end = None  # bellow forces the cars feel at the end of the last step (4, cases)
        #: the cars run on the wheel-rail contact: :meth:`sample` records its outputs too
        self.contact = any(getattr(car, "guidance", "kinematic") == "contact" for car in self.cars)
        #: impossible states that stop a case (None: only divergence does): each bellow's volume
        #: every macro-step, before the air sees it; the rest every StateWatch.INTERVAL_S
        self.watch = watch
        self._watch_every = max(1, round(StateWatch.INTERVAL_S / macro_step_s))
        self._steps = 0

    def _crushing(self):
        zs, zds = [], []
        for j, car in enumerate(self.cars):
            if self.active[j]:
                zj, zdj = car.bellow_crushing()
            else:                                    # a stopped case stays where it stopped
                zj, zdj = self.z[:, j], np.zeros(self.z.shape[0])
            zs.append(zj)
            zds.append(zdj)
        return np.stack(zs, axis=1), np.stack(zds, axis=1)

    def _stop(self, j: int, reason: str) -> None:
        self.active[j] = False
        self.diagnoses.append(f"{self.labels[j]}: {reason}")

    def step(self) -> None:
        """One macro-step (see the module docstring)."""
        t1 = self.t + self.H
        F_start, K, F_rate, rate = self._force_laws()
        self._advance_cars(F_start, K, F_rate, t1)
        z1, zd1 = self._crushing()
        watching = self.watch is not None and self._steps % self._watch_every == 0
        if self.watch is not None:                    # before the air sees an impossible crushing
            self._stop_impossible_cars(z1, t1, watching)
            z1[:, ~self.active], zd1[:, ~self.active] = self.z[:, ~self.active], 0.0
        motion = hermite_motion(self.t, t1, self.z, self.zd, z1, zd1)
        with np.errstate(all="ignore"):               # a diverging column is diagnosed just below
            # the motion starts at (z_n, zd_n) exactly, so RK4's first stage is ``rate``
            x1 = advance(self.circuit, self.x, self.t, t1, motion, self.h_pneumatic, rate0=rate)
        self._stop_diverged(x1, t1)
        if watching:
            self._stop_impossible_air(x1, z1, t1)
        self._steps += 1
        x1[:, ~self.active] = self.x[:, ~self.active]  # stopped cases stay frozen
        self._F_end = F_start + self.H * F_rate + K * (z1 - self.z)  # what the cars feel at t1
        self.x, self.t, self.z, self.zd = x1, t1, z1, zd1

    def _force_laws(self):
        """The bellow force laws of this step (see the module docstring), each (4, cases):
        (F_s, K_n, (F_e - F_s) / H), and the circuit's rate d(state)/dt at (x_n, z_n, zd_n).

        The held rate (zero crushing rate) behind dF/dt|_z comes from the same evaluation of the
        circuit as that rate (:meth:`Circuit.derivatives_and_held`), bit for bit as a separate
        evaluation would give it."""
        c = self.circuit
        F_now = c.bellow_forces_N(self.x, self.z)
        if self.coupling != "linearised":
            zero = np.zeros_like(F_now)
            return F_now, zero, zero, c.derivatives(self.x, self.z, self.zd)
        rate, held_rate = c.derivatives_and_held(self.x, self.z, self.zd)
        half = 0.5 * self.H
        dF_dt = (c.bellow_forces_N(self.x + half * held_rate, self.z) - F_now) / half
        K = c.bellow_stiffness_N_per_m(self.x, self.z)
        F_start = F_now if self._F_end is None else self._F_end
        F_rate = (F_now + self.H * dF_dt - F_start) / self.H
        return F_start, K, F_rate, rate

    def _advance_cars(self, F_start, K, F_rate, t1: float) -> None:
        """Each running car gets its force laws and advances to ``t1``; one whose multibody
        solver gives up is stopped."""
        for j in np.flatnonzero(self.active):
            car = self.cars[j]
            car.set_bellow_forces(F_start[:, j], K[:, j], F_rate[:, j])
            try:
                car.advance(t1)
            except Derailed as exc:                   # a physical end, not a numerical one
                self._stop(j, f"impossible state: derailed: {exc}")
            except RuntimeError as exc:               # the multibody solver gave up
                self._stop(j, f"multibody solver failed advancing from t = {self.t:.6g} to {t1:.6g} s: {exc}")

    def _stop_diverged(self, x1: np.ndarray, t1: float) -> None:
        """Stop every running case whose circuit state left the physical range (one vectorised
        test; the diagnosis of a failing case comes from :meth:`Circuit.check_state`)."""
        for j in np.flatnonzero(self.active & ~self.circuit.physical_cases(x1)):
            try:
                self.circuit.check_state(x1[:, j], t1)
            except CircuitDiverged as exc:
                self._stop(j, str(exc))

    def _stop_impossible_cars(self, z1: np.ndarray, t1: float, cars: bool) -> None:
        """Stop every running case whose bellows are crushed flat or, with ``cars``, whose car
        is in a state no car can be in (:class:`~cosim.limits.watch.StateWatch`)."""
        fractions = self.circuit.bellow_volume_fractions(z1)
        for j in np.flatnonzero(self.active):
            reason = self.watch.bellows(fractions[:, j], self.circuit.bellow_names, t1) or \
                (self.watch.car(j, self.cars[j], t1) if cars else None)
            if reason:
                self._stop(j, f"impossible state: {reason}")

    def _stop_impossible_air(self, x1: np.ndarray, z1: np.ndarray, t1: float) -> None:
        """Stop every running case whose air left the range of physics."""
        p, T = self.circuit.chamber_states(x1, z1)
        for j, reason in enumerate(self.watch.air(p, T, self.circuit.chamber_names, t1)):
            if reason and self.active[j]:
                self._stop(j, f"impossible state: {reason}")

    def sample(self, record: Record) -> None:
        c = self.circuit
        out = c.outputs(self.x, self.z)
        idx = self._bellow_chambers
        stopped = ~self.active

        def live(values):
            values = np.array(values, dtype=float)
            values[..., stopped] = np.nan
            return values

        record.t_s.append(self.t)
        record.wheel_load_N.append(live(np.stack([car.wheel_loads_N() if a else np.zeros(8)
                                                  for car, a in zip(self.cars, self.active)], axis=1)))
        record.crushing_m.append(live(self.z))
        record.bellow_force_N.append(live(out.bellow_force_N))
        record.bellow_p_Pa.append(live(out.p_Pa[idx]))
        record.bellow_T_K.append(live(out.T_K[idx]))
        record.roll_rad.append(live([car.carbody_roll_rad() if a else 0.0 for car, a in zip(self.cars, self.active)]))
        record.air_from_supply_kg.append(live(c.mass_from(self.x, "supply") if self._supply else np.zeros(len(self.cars))))
        record.air_to_atmosphere_kg.append(live(-c.mass_from(self.x, "atmosphere")))
        record.link_flow_kg_per_s.append(live(out.link_flow_kg_per_s))
        record.total_mass_kg.append(live(c.total_mass_kg(self.x)))
        air, open_s = c.valve_air_kg(self.x), c.valve_open_time_s(self.x)
        record.valve_supply_air_kg.append(live(air.supply))
        record.valve_exhaust_air_kg.append(live(air.exhaust))
        record.valve_supply_open_s.append(live(open_s.supply))
        record.valve_exhaust_open_s.append(live(open_s.exhaust))
        if self.contact:
            for name, (output, n) in CONTACT_FIELDS.items():
                getattr(record, name).append(live(np.stack(
                    [np.asarray(output(car), dtype=float) if a else np.zeros(n)
                     for car, a in zip(self.cars, self.active)], axis=1)))

    def run(self, t_end_s: float, output_interval_s: float,
            progress: Optional[Callable[[str, bool], None]] = None) -> tuple[Record, Optional[str]]:
        """Advance to ``t_end_s``, sampling every ``output_interval_s``. Returns the record and,
        if a case diverged, the diagnoses (that case's record holds NaN from then on; the run
        stops early only when every case has stopped). A SIGINT/SIGTERM (:mod:`cosim.interrupts`)
        stops it after the current macro-step, keeping the record so far, with a diagnosis."""
        record = Record()
        every = max(1, round(output_interval_s / self.H))
        n = round(t_end_s / self.H)
        self.sample(record)
        for i in range(1, n + 1):
            self.step()
            if stop_requested():
                self.sample(record)
                self.diagnoses.append(f"interrupted at t = {self.t:.6g} s (results up to then kept)")
                break
            if i % every == 0 or i == n or not np.any(self.active):
                self.sample(record)
            if not np.any(self.active):
                break
            if progress:
                progress(f"t = {self.t:6.2f} / {t_end_s:g} s", False)
        return record, "; ".join(self.diagnoses) or None
