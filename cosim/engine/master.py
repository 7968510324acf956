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

from dataclasses import dataclass
from typing import Callable, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from cosim.interrupts import stop_requested
from cosim.limits.watch import StateWatch
from pneumatics.air_supply import ScheduledDemand
from pneumatics.circuit import Circuit, CircuitDiverged
from pneumatics.integrate import advance, hermite_motion, stable_step_s
from vehicle.errors import Derailed, WheelSlide

COUPLINGS = ("linearised", "explicit")


@dataclass(frozen=True)
class Output:
    """One quantity a car run samples, declared once: the record, the labelled Dataset
    (:func:`cosim.results.series.car_dataset`) and the CSV time series take it from here.

    ``dims``: its label dimensions besides time and case (``wheel``, ``wheelset``, ``bellow``,
    ``link``, ``valve``); ``column``: its CSV column pattern (``{}``: the label; None: not in the
    CSV); ``read(sample)``: its value at the current state, (..., cases) (:class:`Sample`);
    ``contact``: sampled only when the cars run on the wheel-rail contact; ``air_supply``: only when
    the circuit has a compressor or an air demand."""

    name: str
    dims: Tuple[str, ...]
    unit: str
    long_name: str
    column: Optional[str]
    read: Callable[["Sample"], np.ndarray]
    contact: bool = False
    air_supply: bool = False


@dataclass
class Sample:
    """What the outputs are read from at one sampling instant: the co-simulation (its cars,
    state x, crushing z) and the circuit's outputs at that state."""

    sim: "CoSimulation"
    circuit: object         # pneumatics.circuit.CircuitOutputs at (x, z)
    valve_air: object       # cumulative air through each valve's supply and exhaust side
    valve_open: object      # cumulative open time of each valve's supply and exhaust side
    floor: Optional[np.ndarray] = None   # the cars' floor accelerations (3, 3, cases), read once


@dataclass(frozen=True)
class PerCar:
    """A car output (``MetroCar.<method>()``: shape ``n``, a scalar for n None) stacked over the
    cases, zeros for a stopped case (it becomes NaN in the record); picklable, so that a kind's
    outputs travel to the worker processes."""

    method: str
    n: Optional[int | Tuple[int, ...]] = None

    def __call__(self, sample: Sample) -> np.ndarray:
        cars, active = sample.sim.cars, sample.sim.active
        shape = () if self.n is None else tuple(np.atleast_1d(self.n).tolist())
        out = np.zeros(shape + (len(cars),))
        for j, car in enumerate(cars):
            if active[j]:
                out[..., j] = getattr(car, self.method)()
        return out



_FLOOR = PerCar("floor_accelerations_m_per_s2", (3, 3))


def _floor_axis(axis: int) -> Callable[[Sample], np.ndarray]:
    """One axis (0 x, 1 y, 2 z) of the cars' floor accelerations (3 floor points, cases), read
    once per sampling instant for the three axes."""
    def read(sample: Sample) -> np.ndarray:
        if sample.floor is None:
            sample.floor = _FLOOR(sample)
        return sample.floor[axis]
    return read


def _air_from(node: str, sign: float = 1.0) -> Callable[[Sample], np.ndarray]:
    """Air that left ``node`` (cumulative, kg, per case); 0 when the circuit has no such node."""
    def read(sample: Sample) -> np.ndarray:
        sim = sample.sim
        if node not in sim.circuit.node_names:
            return np.zeros(len(sim.cars))
        return sign * sim.circuit.mass_from(sim.x, node)
    return read


def _compression(bound: int) -> Callable[[Sample], np.ndarray]:
    """The compressors' cumulative energy of compression [J] per case: 0 its isothermal bound, 1
    its adiabatic one."""
    def read(sample: Sample) -> np.ndarray:
        return sample.sim.circuit.compression_energy_J(sample.sim.x)[bound].sum(axis=0)
    return read


#: What every car run samples, in the order of the Dataset and the CSV columns; a kind that needs
#: more declares its own (:attr:`cosim.kinds.base.CarKind.outputs`), sampled after these, in its runs only.
OUTPUTS = (
    Output("wheel_load_N", ("wheel",), "N", "vertical wheel-rail force Q", "Q_{}_N", PerCar("wheel_loads_N", 8)),
    Output("crushing_m", ("bellow",), "m", "bellow crushing z (+ compression)", "z_{}_m", lambda s: s.sim.z),
    Output("bellow_force_N", ("bellow",), "N", "bellow force F", "F_bellow_{}_N", lambda s: s.circuit.bellow_force_N),
    Output("bellow_p_Pa", ("bellow",), "Pa", "bellow pressure p (absolute)", "p_bellow_{}_Pa",
           lambda s: s.circuit.p_Pa[s.sim.bellow_chambers]),
    Output("bellow_T_K", ("bellow",), "K", "bellow temperature T", "T_bellow_{}_K",
           lambda s: s.circuit.T_K[s.sim.bellow_chambers]),
    Output("roll_rad", (), "rad", "carbody roll (absolute, positive left side up)", "roll_carbody_rad",
           PerCar("carbody_roll_rad")),
    *(Output(f"floor_a{axis}_m_per_s2", ("floor_point",), "m/s2",
             f"floor acceleration along the carbody's {axis} axis ({meaning}; specific force a - g, as an "
             f"accelerometer on the floor measures it)", f"a{axis}_{{}}_m_per_s2", _floor_axis(i))
      for i, (axis, meaning) in enumerate((("x", "forward"), ("y", "left"), ("z", "up")))),
    Output("air_from_supply_kg", (), "kg", "air injected from the supply (cumulative)", "air_from_supply_kg",
           _air_from("supply")),
    Output("air_to_atmosphere_kg", (), "kg", "air exhausted to the atmosphere by the valves (cumulative)",
           "air_to_atmosphere_kg", _air_from("atmosphere", -1.0)),
    Output("air_lost_kg", (), "kg", "air lost to the atmosphere through the faults' openings: bursts, leaks, "
           "ruptured pipes (cumulative)", "air_lost_kg", lambda s: s.sim.circuit.air_lost_kg(s.sim.x)),
    Output("link_flow_kg_per_s", ("link",), "kg/s", "mass flow through each link, from its a node to its b node", None,
           lambda s: s.circuit.link_flow_kg_per_s),
    Output("total_mass_kg", (), "kg", "air in all chambers", None, lambda s: s.sim.circuit.total_mass_kg(s.sim.x)),
    Output("net_inflow_kg", (), "kg", "air that entered the chambers from outside, net of what left (cumulative)",
           None, lambda s: s.sim.circuit.net_inflow_kg(s.sim.x)),
    Output("valve_supply_air_kg", ("valve",), "kg", "air through each levelling valve's supply side (cumulative)",
           None, lambda s: s.valve_air.supply),
    Output("valve_exhaust_air_kg", ("valve",), "kg", "air through each levelling valve's exhaust side (cumulative)",
           None, lambda s: s.valve_air.exhaust),
    Output("valve_supply_open_s", ("valve",), "s", "time each levelling valve's supply side was open (cumulative)",
           None, lambda s: s.valve_open.supply),
    Output("valve_exhaust_open_s", ("valve",), "s", "time each levelling valve's exhaust side was open (cumulative)",
           None, lambda s: s.valve_open.exhaust),
    # wheel-rail contact (guidance: contact only; a kinematic run has none of them)
    Output("lateral_wheel_force_N", ("wheel",), "N", "lateral wheel-rail force Y (+ towards the track centre)",
           "Y_{}_N", PerCar("lateral_wheel_forces_N", 8), contact=True),
    Output("wheelset_lateral_force_N", ("wheelset",), "N", "sum of the lateral wheel forces of a wheelset, ΣY (+ left)",
           "sumY_{}_N", PerCar("wheelset_lateral_forces_N", 4), contact=True),
    Output("wheelset_lateral_m", ("wheelset",), "m", "wheelset lateral displacement from the design centre line "
           "(+ left)", "y_ws_{}_m", PerCar("wheelset_lateral_displacement_m", 4), contact=True),
    Output("wheelset_lateral_to_rails_m", ("wheelset",), "m", "wheelset lateral displacement relative to its rails "
           "(+ left; track irregularities subtracted)", "y_ws_rails_{}_m", PerCar("wheelset_lateral_to_rails_m", 4),
           contact=True),
    Output("angle_of_attack_rad", ("wheelset",), "rad", "wheelset angle of attack (yaw to the track tangent, + to "
           "the left)", "aoa_{}_rad", PerCar("angle_of_attack_rad", 4), contact=True),
    Output("flange_contact", ("wheel",), "1", "flange contact (1: contact angle above the flange threshold)",
           "flange_{}", PerCar("flange_contact", 8), contact=True),
    # the air supply beyond the suspension (a compressor, air demands: pneumatics.air_supply)
    Output("compressor_running", (), "1", "compressors running (each 1 while its governor runs it)", "compressor_running",
           lambda s: s.sim.circuit.compressor_running(s.sim.x).sum(axis=0), air_supply=True),
    Output("compressor_run_time_s", (), "s", "compressor running time (cumulative)", "compressor_run_time_s",
           lambda s: s.sim.circuit.compressor_run_time_s(s.sim.x).sum(axis=0), air_supply=True),
    Output("compressor_air_kg", (), "kg", "air the compressors delivered into the reservoir (cumulative)",
           "compressor_air_kg", lambda s: s.sim.circuit.compressor_air_kg(s.sim.x).sum(axis=0), air_supply=True),
    Output("air_demand_kg", (), "kg", "air the other consumers (brakes, doors) drew (cumulative)", "air_demand_kg",
           lambda s: s.sim.circuit.demand_air_kg(s.sim.x).sum(axis=0), air_supply=True),
    *(Output(f"compression_{bound}_J", (), "J", f"energy of compression, its {bound} bound (cumulative)",
             f"compression_{bound}_J", _compression(i), air_supply=True)
      for i, bound in enumerate(("isothermal", "adiabatic"))),
)


class Record:
    """Sampled co-simulation output: ``t_s`` and, per output sampled (:data:`OUTPUTS` and a
    kind's own), a list of arrays (..., cases)."""

    def __init__(self, outputs: Sequence[Output] = OUTPUTS):
        self.t_s: List[float] = []
        self.values: Dict[str, List[np.ndarray]] = {o.name: [] for o in outputs}

    def arrays(self) -> Dict[str, np.ndarray]:
        """Every sampled output as an array (samples, ..., cases), ``t_s`` first."""
        return {"t_s": np.asarray(self.t_s), **{name: np.asarray(v) for name, v in self.values.items() if v}}


class CoSimulation:
    """Couple ``cars`` (exudyn models with the vehicle.car.MetroCar interface) to ``circuit``,
    whose k array has one entry per car.

    Cases are independent: one that diverges (its multibody solver fails, or its air leaves the
    physical range) is stopped and frozen, with a diagnosis, while the others go on; its record
    holds NaN from then on.

    Faults (``circuit.faults``, :mod:`pneumatics.faults`) happen at their own times: the air is
    integrated up to a fault's time with the circuit before it and on with the circuit after
    it (:meth:`Circuit.with_active_faults`), within the macro-step, so the instant is exact
    whatever the steps; the force law of that step is the one of its start, anchored again to
    the faulted air at the next step (a one-step O(H) force error, O(H^2) in what it moves).
    The scheduled demands (``scheduled_demands``: name -> :class:`~pneumatics.air_supply.ScheduledDemand`,
    each an air demand of the circuit that draws only within its windows) switch the circuit
    the same way at their windows' edges (:meth:`Circuit.with_demands`): one list of switches,
    faults and demand rates merged by time, every circuit of it with the same state layout.

    It samples :data:`OUTPUTS` and then ``extra_outputs`` (a kind's own, each ``read`` a
    module-level function: the outputs travel to the worker processes).
    """

    def __init__(self, cars: Sequence, circuit: Circuit, x0: np.ndarray, macro_step_s: float,
                 pneumatic_step_s: float, coupling: str = "linearised", case_labels: Optional[Sequence[str]] = None,
                 watch: Optional[StateWatch] = None, extra_outputs: Sequence[Output] = (),
                 scheduled_demands: Optional[Mapping[str, ScheduledDemand]] = None):
        if coupling not in COUPLINGS:
            raise ValueError(f"coupling must be one of {COUPLINGS}, got {coupling!r}")
        self.cars, self.circuit, self.x = list(cars), circuit, x0.copy()
        #: what :meth:`sample` records
        self.outputs: Tuple[Output, ...] = (*OUTPUTS, *extra_outputs)
        self.H, self.coupling = macro_step_s, coupling
        self.h_pneumatic = stable_step_s(circuit, x0, pneumatic_step_s)
        self.t = 0.0
        self.labels = list(case_labels or (f"case {j}" for j in range(len(self.cars))))
        self.active = np.ones(len(self.cars), bool)
        self.diagnoses: List[str] = []
        self.z, self.zd = self._crushing()
        #: the circuit's chambers that are the bellows (their order)
        self.bellow_chambers = [circuit.chamber_names.index(b) for b in circuit.bellow_names]
        self._F_end = None  # bellow forces the cars feel at the end of the last step (4, cases)
        #: the cars run on the wheel-rail contact: :meth:`sample` records its outputs too
        self.contact = any(getattr(car, "guidance", "kinematic") == "contact" for car in self.cars)
        #: impossible states that stop a case (None: only divergence does): each bellow's volume
        #: every macro-step, before the air sees it; the rest every StateWatch.INTERVAL_S
        self.watch = watch
        self._watch_every = max(1, round(StateWatch.INTERVAL_S / macro_step_s))
        self._steps = 0
        #: (x, z, circuit, evaluation) of the last sample (the next macro-step's force laws start
        #: from the same state: :meth:`_evaluation_now`), None after a step
        self._sampled = None
        #: [(time, circuit from then on)] of the switches still to happen (faults, scheduled
        #: demands' rates), by time
        self._switches = self._circuit_switches(circuit, scheduled_demands or {})
        self._switch(0.0)

    #: switches within this time of a macro-step boundary happen at it [s] (round-off of t_n)
    FAULT_TIME_TOL_S = 1e-9

    @staticmethod
    def _circuit_switches(circuit: Circuit, scheduled: Mapping[str, ScheduledDemand]) -> List[Tuple[float, Circuit]]:
        """At every fault's time and every scheduled demand's switch time, the circuit from then
        on: the faults up to then active, each scheduled demand at its rate from then on. Equal
        circuits are built once (a service's stops repeat a few rates)."""
        faults = circuit.faults
        times = sorted({f.t_s for f in faults} | {t for s in scheduled.values() for t in s.switch_times()})
        built: Dict[tuple, Circuit] = {}
        switches = []
        for t in times:
            active = tuple(i for i, f in enumerate(faults) if f.t_s <= t)
            demands = tuple((name, s.at(t)) for name, s in scheduled.items())
            if (active, demands) not in built:
                built[active, demands] = circuit.with_demands(dict(demands), active) if demands else \
                    circuit.with_active_faults(active)
            switches.append((t, built[active, demands]))
        return switches

    def _switch(self, t: float) -> None:
        """The circuit of every switch up to ``t``."""
        while self._switches and self._switches[0][0] <= t + self.FAULT_TIME_TOL_S:
            self.circuit = self._switches.pop(0)[1]

    def _advance_air(self, t1: float, motion, rate) -> np.ndarray:
        """The circuit's state at ``t1`` from (t_n, x_n) along ``motion``, switching the circuit
        at the faults and demand rates that change within the step (``rate``: d(state)/dt at
        t_n, see :meth:`step`)."""
        x, t = self.x, self.t
        while self._switches and self._switches[0][0] < t1 - self.FAULT_TIME_TOL_S:
            t_switch = self._switches[0][0]
            x = advance(self.circuit, x, t, t_switch, motion, self.h_pneumatic, rate0=rate)
            t, rate = t_switch, None
            self._switch(t)
        x = advance(self.circuit, x, t, t1, motion, self.h_pneumatic, rate0=rate)
        self._switch(t1)
        return x

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
            if not self.active.all():
                z1[:, ~self.active], zd1[:, ~self.active] = self.z[:, ~self.active], 0.0
        motion = hermite_motion(self.t, t1, self.z, self.zd, z1, zd1)
        with np.errstate(all="ignore"):               # a diverging column is diagnosed just below
            # the motion starts at (z_n, zd_n) exactly, so RK4's first stage is ``rate``
            x1 = self._advance_air(t1, motion, rate)
        self._stop_diverged(x1, t1)
        if watching:
            self._stop_impossible_air(x1, z1, t1)
        self._steps += 1
        if not self.active.all():
            x1[:, ~self.active] = self.x[:, ~self.active]  # stopped cases stay frozen
        self._F_end = F_start + self.H * F_rate + K * (z1 - self.z)  # what the cars feel at t1
        self.x, self.t, self.z, self.zd = x1, t1, z1, zd1
        self._sampled = None

    def _evaluation_now(self):
        """The circuit's evaluation that :meth:`sample` computed, if it is of the current state
        and circuit (the very objects: a caller that replaced x, z or the circuit since gets a
        fresh evaluation), else None."""
        if self._sampled is None:
            return None
        x, z, circuit, evaluated = self._sampled
        return evaluated if (x is self.x and z is self.z and circuit is self.circuit) else None

    def _force_laws(self):
        """The bellow force laws of this step (see the module docstring), each (4, cases):
        (F_s, K_n, (F_e - F_s) / H), and the circuit's rate d(state)/dt at (x_n, z_n, zd_n).

        The held rate (zero crushing rate) behind dF/dt|_z comes from the same evaluation of the
        circuit as that rate (:meth:`Circuit.derivatives_and_held`), bit for bit as a separate
        evaluation would give it."""
        c = self.circuit
        if self.coupling != "linearised":
            F_now = c.bellow_forces_N(self.x, self.z)
            zero = np.zeros_like(F_now)
            return F_now, zero, zero, c.derivatives(self.x, self.z, self.zd)
        rate, held_rate = c.derivatives_and_held(self.x, self.z, self.zd, self._evaluation_now())
        half = 0.5 * self.H
        # F(x_n, z_n), F(x_n + H/2 held rate, z_n) and K_n in one call (Circuit.bellow_force_laws)
        F_now, F_half, K = c.bellow_force_laws(self.x, self.z, held_rate, half)
        dF_dt = (F_half - F_now) / half
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
            except WheelSlide as exc:                 # the same: beyond the adhesion
                self._stop(j, f"wheel slide: {exc}")
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
        running = self.active if cars else self.active & self.watch.any_flat(fractions)   # the others pass
        for j in np.flatnonzero(running):
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
        """Append the current state's :attr:`outputs` to ``record`` (NaN for a stopped case; the
        contact outputs only when the cars run on the wheel-rail contact)."""
        c = self.circuit
        evaluated = c.evaluate(self.x, self.z)
        self._sampled = (self.x, self.z, c, evaluated)  # the next macro-step starts from this state
        now = Sample(self, c.outputs(self.x, self.z, evaluated), c.valve_air_kg(self.x), c.valve_open_time_s(self.x))
        stopped = ~self.active
        any_stopped = bool(stopped.any())
        record.t_s.append(self.t)
        for output in self.outputs:
            if (output.contact and not self.contact) or (output.air_supply and not c.has_air_supply):
                continue
            values = np.array(output.read(now), dtype=float)
            if any_stopped:
                values[..., stopped] = np.nan
            record.values[output.name].append(values)

    def run(self, t_end_s: float, output_interval_s: float,
            progress: Optional[Callable[[str, bool], None]] = None) -> tuple[Record, Optional[str]]:
        """Advance to ``t_end_s``, sampling every ``output_interval_s``. Returns the record and,
        if a case diverged, the diagnoses (that case's record holds NaN from then on; the run
        stops early only when every case has stopped). A SIGINT/SIGTERM (:mod:`cosim.interrupts`)
        stops it after the current macro-step, keeping the record so far, with a diagnosis."""
        record = Record(self.outputs)
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
