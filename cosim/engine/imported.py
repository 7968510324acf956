"""An FMU as a car's circuit (``circuit: {fmu: ...}``, :mod:`cosim.scenario.imported`): FMPy runs
it (FMI 2.0 co-simulation), one instance per case, and :class:`ImportedCoSimulation` gives the
co-simulation master's macro-step exchange around it, in one of two ways (docs/fmi.md):

* **the master's own exchange**, with an FMU that gives what it needs (pneumorail's does): the
  force law of the step (``linearised`` or ``explicit``) built from the FMU's force, stiffness and
  force rate at t_n as :meth:`CoSimulation._force_laws` builds it from its circuit; the FMU given
  the crushing and rate at both ends of the step (it follows the master's cubic Hermite between
  them) and, for every case, the shortest pneumatic sub-step of all the scenario's k values. The
  native run to the last bit;
* **the force held**, with an FMU that gives its force only: the forces it gave at t_n held over
  the macro-step (as ``coupling: explicit``: without dF/dz and the force's rate the linearised
  law cannot be built), the FMU given the crushing and rate at t_n (within the step it follows
  its own inputs). First order in the macro-step.

Either way, what the record holds: the force, and the pressure, temperature and air totals the map
names (NaN where it names none); no flows through links, no valve accounts (those outputs are left
out), no faults' air nor net inflow (NaN), and so no mass balance (NaN). A step the FMU refuses
(fmi2Discard, fmi2Error, fmi2Fatal) stops that case with a diagnosis, as a diverged circuit does:
its record holds NaN from then on, the others go on, the run exits 1.
"""
from __future__ import annotations

import math
import shutil
import tempfile
from types import SimpleNamespace
from typing import List, Optional, Sequence

import numpy as np
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import fmi2Real, fmi2True, fmi2ValueReference

from cosim.engine.master import OUTPUTS, CoSimulation, Output, Sample
from cosim.errors import ScenarioError
from cosim.limits.watch import StateWatch
from cosim.scenario.imported import ImportedCircuit

#: outputs of a native car run the FMU cannot give (they need pneumorail's own links and valves)
LEFT_OUT = ("link_flow_kg_per_s", "valve_supply_air_kg", "valve_exhaust_air_kg", "valve_supply_open_s",
            "valve_exhaust_open_s")


class FmuCircuit:
    """One instance of the FMU (FMPy ``FMU2Slave``) as one case's circuit, the bellows in the
    order of ``spec.bellows`` (FL, FR, RL, RR)."""

    def __init__(self, spec: ImportedCircuit, unzipped: str, k_W_per_K: float, pneumatic_step_s: Optional[float],
                 macro_step_s: float, instance_name: str, scenario_file=None, model_description=None):
        from fmpy import read_model_description
        from fmpy.fmi2 import FMU2Slave
        md = model_description or read_model_description(unzipped)
        ref = self._ref = {v.name: v.valueReference for v in md.modelVariables}
        self.spec, self.scenario_file = spec, scenario_file
        self.native = spec.native_exchange
        ends = ("crushing", "rate", "crushing_end", "rate_end") if self.native else ("crushing", "rate")
        self.inputs = [ref[getattr(b, key)] for key in ends for b in spec.bellows]
        law = ("force", "stiffness", "force_rate") if self.native else ("force",)
        #: the force law's outputs first (force; with the native exchange, stiffness and force rate)
        self.forces = [ref[getattr(b, key)] for key in law for b in spec.bellows]
        # the recorded outputs: (name, index in the values read, or None: not mapped)
        recorded = [b.pressure for b in spec.bellows] + [b.temperature for b in spec.bellows] + \
            [dict(spec.air).get(key) for key in ("total_mass_kg", "air_from_supply_kg", "air_to_atmosphere_kg")]
        self._read = self.forces + [ref[name] for name in recorded if name is not None]
        self._where = []
        i = len(self.forces)
        for name in recorded:
            self._where.append(i if name is not None else None)
            i += name is not None
        self.slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=spec.model_identifier,
                               instanceName=instance_name)
        try:
            self.slave.instantiate()
        except Exception as exc:                      # noqa: BLE001 -- FMPy raises a plain Exception when it fails
            raise ScenarioError(scenario_file, ["circuit", "fmu"], f"the FMU {spec.fmu} could not be instantiated "
                                                                 f"({exc}): it runs in this Python (pythonfmu's FMUs: "
                                                                 f"docs/fmi.md, \"What the importing machine needs\")") from None
        self._parameters = []
        if spec.k_W_per_K is not None:
            if math.isinf(k_W_per_K):
                self._parameters.append(("Boolean", ref[spec.isothermal], True))
            else:
                self._parameters.append(("Real", ref[spec.k_W_per_K], float(k_W_per_K)))
                if spec.isothermal is not None:
                    self._parameters.append(("Boolean", ref[spec.isothermal], False))
        if spec.pneumatic_step_s is not None and pneumatic_step_s is not None:
            self._parameters.append(("Real", ref[spec.pneumatic_step_s], float(pneumatic_step_s)))
        if self.native:
            self._parameters += [("Boolean", ref[spec.lookahead], True), ("Real", ref[spec.macro_step_s], macro_step_s)]
        self.values = np.full(len(self._read), np.nan)
        # the step's fmi2SetReal and fmi2GetReal take these arrays, built once (FMPy's setReal and
        # getReal build their ctypes arrays and lists anew on every call)
        self._inputs_vr = (fmi2ValueReference * len(self.inputs))(*self.inputs)
        self._inputs_buffer = (fmi2Real * len(self.inputs))()
        self._inputs_values = np.ctypeslib.as_array(self._inputs_buffer)
        self._read_vr = (fmi2ValueReference * len(self._read))(*self._read)
        self._read_buffer = (fmi2Real * len(self._read))()
        self._read_values = np.ctypeslib.as_array(self._read_buffer)

    def start(self, t0: float, z: np.ndarray, zd: np.ndarray) -> None:
        """Parameters and the crushing at ``t0`` set, initialised; the outputs at t0 read."""
        s = self.slave
        try:
            s.setupExperiment(startTime=t0)
            s.enterInitializationMode()
            for type_, vr, value in self._parameters:
                (s.setBoolean if type_ == "Boolean" else s.setReal)([vr], [value])
            s.setReal(self.inputs, self._values(z, zd, z, zd))
            s.exitInitializationMode()
        except FMICallException as exc:
            raise ScenarioError(self.scenario_file, ["circuit", "fmu"], f"the FMU {self.spec.fmu} could not be "
                                                                        f"initialised: {exc}") from None
        self._sample()

    def step(self, t: float, H: float, z: np.ndarray, zd: np.ndarray, z1: np.ndarray, zd1: np.ndarray) -> None:
        """The crushing and its rate at ``t`` (and, with the native exchange, at t + H: ``z1``,
        ``zd1``) in, one communication step to t + H, the outputs at t + H read; an FMI status
        worse than warning raises (FMPy's ``FMICallException``)."""
        s = self.slave
        np.concatenate((z, zd, z1, zd1) if self.native else (z, zd), out=self._inputs_values)
        s.fmi2SetReal(s.component, self._inputs_vr, len(self._inputs_buffer), self._inputs_buffer)
        s.fmi2DoStep(s.component, t, H, fmi2True)
        self._sample()

    def _values(self, z, zd, z1, zd1) -> list:
        ends = (z, zd, z1, zd1) if self.native else (z, zd)
        return [float(v) for end in ends for v in end]

    def law(self):
        """(force, stiffness, force rate) at the last communication point, each (bellows,); the
        last two None without the native exchange."""
        n = len(self.spec.bellows)
        v = self.values
        return (v[:n], v[n:2 * n], v[2 * n:3 * n]) if self.native else (v[:n], None, None)

    def _sample(self) -> None:
        s = self.slave
        s.fmi2GetReal(s.component, self._read_vr, len(self._read_buffer), self._read_buffer)
        self.values = self._read_values.copy()

    def output(self, i: int) -> float:
        """Recorded output ``i`` (pressures, temperatures, air totals in turn), NaN if not mapped."""
        where = self._where[i]
        return float(self.values[where]) if where is not None else math.nan

    def used_step_s(self) -> float:
        """The pneumatic sub-step the FMU initialised with (its ``pneumatic_step_used_s``)."""
        return float(self.slave.getReal([self._ref[self.spec.pneumatic_step_used_s]])[0])

    def close(self) -> None:
        try:
            self.slave.terminate()
        finally:
            self.slave.freeInstance()


class _AirView:
    """What the master's outputs (:data:`cosim.engine.master.OUTPUTS`) read from a circuit, for
    the FMUs of a run: forces, pressures and temperatures (bellow x case), the air totals the map
    names; NaN where the FMU gives nothing."""

    has_air_supply = False
    node_names = ("supply", "atmosphere")

    def __init__(self, sim: "ImportedCoSimulation"):
        self.sim = sim
        n = len(sim.fmus[0].spec.bellows)
        self.bellow_names = tuple(b.bellow for b in sim.fmus[0].spec.bellows)
        self.chamber_names = self.bellow_names
        self._n = n

    def _per_case(self, i: int) -> np.ndarray:
        return np.array([fmu.output(i) for fmu in self.sim.fmus])

    def pressures_temperatures(self):
        n = self._n
        p = np.array([[fmu.output(i) for fmu in self.sim.fmus] for i in range(n)])
        T = np.array([[fmu.output(n + i) for fmu in self.sim.fmus] for i in range(n)])
        return p, T

    def total_mass_kg(self, x=None) -> np.ndarray:
        return self._per_case(2 * self._n)

    def mass_from(self, x, node: str) -> np.ndarray:
        """Air that left ``node`` (cumulative): from the supply as mapped; to the atmosphere as
        mapped (the FMU gives what went in, so the sign is turned as the master's output turns it back)."""
        if node == "supply":
            return self._per_case(2 * self._n + 1)
        return -self._per_case(2 * self._n + 2)

    def air_lost_kg(self, x=None) -> np.ndarray:
        return np.full(len(self.sim.fmus), np.nan)

    net_inflow_kg = air_lost_kg


class ImportedCoSimulation(CoSimulation):
    """The master's macro-step exchange (:class:`~cosim.engine.master.CoSimulation`: its cars,
    sampling, stopping and running) with FMUs as the circuit, one per car (see the module
    docstring for what differs). ``coupling``: the master's, with an FMU of the native exchange;
    otherwise the force is held (``explicit``)."""

    def __init__(self, cars: Sequence, fmus: Sequence[FmuCircuit], macro_step_s: float,
                 case_labels: Optional[Sequence[str]] = None, watch: Optional[StateWatch] = None,
                 extra_outputs: Sequence[Output] = (), unzipped: Optional[str] = None, coupling: str = "linearised"):
        self.cars, self.fmus = list(cars), list(fmus)
        self.outputs = tuple(o for o in (*OUTPUTS, *extra_outputs) if o.name not in LEFT_OUT)
        self.native = all(f.native for f in self.fmus)
        self.H, self.coupling = macro_step_s, coupling if self.native else "explicit"
        self.t = 0.0
        self.labels = list(case_labels or (f"case {j}" for j in range(len(self.cars))))
        self.active = np.ones(len(self.cars), bool)
        self.diagnoses: List[str] = []
        self.z, self.zd = self._crushing()
        self.x = None
        self.circuit = _AirView(self)
        self.bellow_chambers = list(range(len(self.circuit.bellow_names)))
        self.contact = any(getattr(car, "guidance", "kinematic") == "contact" for car in self.cars)
        self.watch = watch
        self._watch_every = max(1, round(StateWatch.INTERVAL_S / macro_step_s))
        self._steps = 0
        self._unzipped = unzipped
        try:
            for j, fmu in enumerate(self.fmus):
                fmu.start(0.0, self.z[:, j], self.zd[:, j])
        except ScenarioError:
            self.close()
            raise
        #: the FMUs' (force, stiffness, force rate) at the last communication point, read once per
        #: step (at its end, for the next step's force laws); the force with stopped cases frozen
        self._laws = self._law()
        self._F = self._laws[0]
        self._F_end = None  # with the native exchange: the forces the cars feel at the end of the last step

    def _law(self):
        """The FMUs' force, stiffness and force rate at their last communication point (each
        bellow x case; the last two None without the native exchange)."""
        laws = [fmu.law() for fmu in self.fmus]
        return tuple(None if laws[0][i] is None else np.stack([law[i] for law in laws], axis=1) for i in range(3))

    def _force_laws(self):
        """The bellow force laws of this step, each (bellow, case): (F_s, K_n, (F_e - F_s) / H) as
        the master's (:meth:`CoSimulation._force_laws`) from what the FMUs gave at t_n; without
        the native exchange, or with ``coupling: explicit``, the force held."""
        F_now, K, dF_dt = self._F, self._laws[1], self._laws[2]   # stopped cases' forces frozen (step)
        if self.coupling != "linearised":
            zero = np.zeros_like(F_now)
            return F_now, zero, zero
        F_start = F_now if self._F_end is None else self._F_end
        return F_start, K, (F_now + self.H * dF_dt - F_start) / self.H

    def step(self) -> None:
        """One macro-step: the cars advance under the force laws of t_n, then each FMU steps from
        t_n with the crushing of t_n (and, with the native exchange, of t_n + H)."""
        t1 = self.t + self.H
        F_start, K, F_rate = self._force_laws()
        self._advance_cars(F_start, K, F_rate, t1)
        z1, zd1 = self._crushing()
        if self.watch is not None and self._steps % self._watch_every == 0:
            for j in np.flatnonzero(self.active):
                reason = self.watch.car(j, self.cars[j], t1)
                if reason:
                    self._stop(j, f"impossible state: {reason}")
            z1[:, ~self.active], zd1[:, ~self.active] = self.z[:, ~self.active], 0.0
        for j in np.flatnonzero(self.active):
            try:
                self.fmus[j].step(self.t, self.H, self.z[:, j], self.zd[:, j], z1[:, j], zd1[:, j])
            except FMICallException as exc:           # fmi2Discard, fmi2Error, fmi2Fatal
                self._stop(j, f"the FMU {self.fmus[j].spec.fmu} refused its step from t = {self.t:.6g} to {t1:.6g} s: "
                              f"{exc}")
        if self.watch is not None and self._steps % self._watch_every == 0:
            p, T = self.circuit.pressures_temperatures()
            if not (np.isnan(p).all() or np.isnan(T).all()):
                for j, reason in enumerate(self.watch.air(p, T, self.circuit.chamber_names, t1)):
                    if reason and self.active[j]:
                        self._stop(j, f"impossible state: {reason}")
        self._steps += 1
        self._laws = self._law()
        F = self._laws[0]
        F[:, ~self.active] = self._F[:, ~self.active]  # stopped cases stay frozen
        self._F = F
        self._F_end = F_start + self.H * F_rate + K * (z1 - self.z)  # what the cars feel at t1
        self.t, self.z, self.zd = t1, z1, zd1

    def sample(self, record) -> None:
        """Append the current outputs (NaN for a stopped case), those the FMU cannot give left out."""
        p, T = self.circuit.pressures_temperatures()
        now = Sample(self, SimpleNamespace(bellow_force_N=self._F, p_Pa=p, T_K=T), None, None)
        stopped = ~self.active
        record.t_s.append(self.t)
        for output in self.outputs:
            if (output.contact and not self.contact) or output.air_supply:
                continue
            values = np.array(output.read(now), dtype=float)
            if stopped.any():
                values[..., stopped] = np.nan
            record.values[output.name].append(values)

    def close(self) -> None:
        """Every FMU terminated and freed, its unzipped folder removed."""
        for fmu in self.fmus:
            try:
                fmu.close()
            except FMICallException:                  # a refused step may leave an instance that cannot terminate
                pass
        if self._unzipped:
            shutil.rmtree(self._unzipped, ignore_errors=True)


def build_imported(scenario, k_values: Sequence[float], cars: Sequence, labels: Sequence[str], watch,
                   extra_outputs: Sequence[Output] = ()) -> ImportedCoSimulation:
    """The cars and, per car, an instance of the scenario's FMU at its k (unzipped once)."""
    from fmpy import extract, read_model_description
    spec: ImportedCircuit = scenario.circuit
    unzipped = extract(spec.fmu, unzipdir=tempfile.mkdtemp(prefix="pneumorail_fmu_import_"))
    fmus: List[FmuCircuit] = []
    settings = scenario.solver
    try:
        md = read_model_description(unzipped)     # once for every instance (the scenario's load checked it)
        h = settings.pneumatic_step_s
        if spec.pneumatic_step_used_s is not None:
            # every case takes the sub-step of all the scenario's k values, as a native run does
            # (cosim.engine.cases.build_cosimulation): a case's numbers do not depend on its chunk
            zero = np.zeros(len(spec.bellows))
            for k in sorted(set(scenario.k_W_per_K) | set(k_values)):
                fmus.append(FmuCircuit(spec, unzipped, k, settings.pneumatic_step_s, settings.macro_step_s,
                                       f"{scenario.name}_probe", scenario.file, md))
                fmus[-1].start(0.0, zero, zero)
                h = min(h, fmus[-1].used_step_s())
                fmus.pop().close()
        for j, k in enumerate(k_values):
            fmus.append(FmuCircuit(spec, unzipped, k, h, settings.macro_step_s, f"{scenario.name}_{j}", scenario.file, md))
    except ScenarioError:
        for fmu in fmus:
            try:
                fmu.close()
            except FMICallException:
                pass
        shutil.rmtree(unzipped, ignore_errors=True)
        raise
    return ImportedCoSimulation(cars, fmus, scenario.solver.macro_step_s, labels, watch, extra_outputs, unzipped,
                                scenario.solver.coupling)
