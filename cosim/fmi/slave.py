"""The FMU's slave: a scenario's car circuit behind FMI 2.0 co-simulation (pythonfmu).

This file is copied into the FMU (``resources/``) beside the circuit it runs, ``circuit.pickle``
(written by :mod:`cosim.fmi.export`): the components of the circuit, its bellows' initial
pressures at the car's static load, k and the pneumatic step. It imports only pythonfmu (which
the FMU carries), numpy and :mod:`pneumatics`: the importing machine needs a Python with
pneumorail installed (the same version: the pickle holds its classes), not exudyn.

Between two communication points the inputs given at the start of the step are extrapolated
(the FMU is not told the next sample, so it cannot ramp towards it as the car co-simulation's
cubic Hermite does): z(t) = z_k + zdot_k s + a_k s^2 / 2, zdot(t) = zdot_k + a_k s, s = t - t_k,
with the acceleration a_k = (zdot_k - zdot_{k-1}) / (t_k - t_{k-1}) from the previous step's rate
(0 at the first step). The crushing and its rate stay consistent within the step (the volume
changes as the compression work says); the crushing it reaches at t_{k+1} is off the next
sample by O(h^3), so the result is second order in the communication step h (a plain linear
extrapolation, a_k = 0, is first order: 20 times the error at h = 10 ms in the tests).

With the parameter ``lookahead`` true the step follows instead the co-simulation master's own
motion, the cubic Hermite from (z_k, zdot_k) to the inputs ``z_end_m``, ``zdot_end_m_per_s`` given
for t_{k+1} (a master that advances the mechanics first knows them), and the outputs are at those
end values; with the stiffness and the force's rate at frozen crushing (outputs in either mode)
the master builds its linearised force law, and the FMU is then its native circuit exactly
(:mod:`cosim.engine.imported`).

Each communication step is integrated by :func:`pneumatics.integrate.advance` (RK4 in equal
sub-steps no longer than ``pneumatic_step_s``), so any communication step size is accepted.
"""
from __future__ import annotations

import math
import pickle
from pathlib import Path
from xml.etree.ElementTree import Element, SubElement

import numpy as np
from pythonfmu import Boolean, DefaultExperiment, Fmi2Causality, Fmi2Slave, Fmi2Variability, Real
from pythonfmu.enums import Fmi2Initial

#: the spec file :mod:`cosim.fmi.export` writes into the FMU's resources
SPEC_FILE = "circuit.pickle"

#: unit -> its SI base-unit exponents (FMI 2.0 BaseUnit attributes)
UNITS = {
    "m": {"m": 1}, "m/s": {"m": 1, "s": -1}, "N": {"kg": 1, "m": 1, "s": -2}, "Pa": {"kg": 1, "m": -1, "s": -2},
    "K": {"K": 1}, "kg": {"kg": 1}, "W/K": {"kg": 1, "m": 2, "s": -3, "K": -1}, "s": {"s": 1},
    "N/m": {"kg": 1, "s": -2}, "N/s": {"kg": 1, "m": 1, "s": -3},
}


def _installed_version() -> str:
    """pneumorail's version in the Python the slave runs in (as the export records it)."""
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version("pneumorail")
    except PackageNotFoundError:
        return "not installed"


def extrapolation_acceleration(zdot_m_per_s: np.ndarray, t_s: float, previous) -> np.ndarray:
    """The crushing's acceleration [m/s^2] the FMU extrapolates with from ``t_s`` on: the change of
    the sampled rate since the previous communication point ``previous`` = (t, zdot) over the time
    between them; zero at the first step (and if time did not advance)."""
    if previous is None or not t_s > previous[0]:
        return np.zeros_like(zdot_m_per_s)
    return (zdot_m_per_s - previous[1]) / (t_s - previous[0])


class UnitReal(Real):
    """pythonfmu's Real with a unit (its own writes none) and a start value that reads back to
    the same double (its own writes 16 digits; a double needs 17)."""

    def __init__(self, name: str, unit: str, **kwargs):
        super().__init__(name, **kwargs)
        self.unit = unit

    def to_xml(self) -> Element:
        node = super().to_xml()
        real = node.find("Real")
        real.set("unit", self.unit)
        if self.start is not None:
            real.set("start", repr(float(self.start)))
        return node


class PneumorailCircuit(Fmi2Slave):
    """A pneumorail car circuit: per bellow, crushing and its rate in; force, pressure and
    temperature out; the air's accounts out; k, the initial bellow pressures and the pneumatic
    step as parameters (fixed: set before initialisation)."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        with open(Path(self.resources) / SPEC_FILE, "rb") as f:
            spec = pickle.load(f)     # written by pneumorail's own export into this very FMU
        installed = _installed_version()
        if installed != spec["pneumorail_version"]:
            raise RuntimeError(f"this FMU was exported by pneumorail {spec['pneumorail_version']}; the Python it runs "
                               f"in has pneumorail {installed}: install the same version (docs/fmi.md)")
        self.spec = spec
        self.author = "pneumorail"
        self.version = spec["pneumorail_version"]
        self.description = spec["description"]
        self.default_experiment = DefaultExperiment(*spec["default_experiment"])
        self.bellows = list(spec["bellows"])
        n = len(self.bellows)
        self.z_m = [0.0] * n
        self.zdot_m_per_s = [0.0] * n
        self.z_end_m = [0.0] * n
        self.zdot_end_m_per_s = [0.0] * n
        self.F_N = [0.0] * n
        self.K_N_per_m = [0.0] * n
        self.dFdt_N_per_s = [0.0] * n
        self.p_Pa = [0.0] * n
        self.T_K = [0.0] * n
        self.p0_Pa = [float(spec["p0_Pa"][b]) for b in self.bellows]
        self.k_W_per_K = float(spec["k_W_per_K"])
        self.isothermal = bool(spec["isothermal"])
        self.pneumatic_step_s = float(spec["pneumatic_step_s"])
        self.lookahead = False
        self.macro_step_s = float(spec["default_experiment"][2])
        self.total_air_mass_kg = 0.0
        self.air_injected_kg = 0.0
        self.air_exhausted_kg = 0.0
        self._circuit = None
        self._x = None
        self._bellow_rows = None            # the bellows' rows among the circuit's chambers
        self._previous_rate = None
        self._rate = (None, None, None)     # (z, zdot, d(state)/dt) of the last outputs
        self._h = self.pneumatic_step_s

        def indexed(values, i):
            return (lambda: values[i]), (lambda v: values.__setitem__(i, float(v)))

        for name, unit, values, causality, text in (
                ("z_m", "m", self.z_m, Fmi2Causality.input, "crushing z (+ in compression) of bellow {}"),
                ("zdot_m_per_s", "m/s", self.zdot_m_per_s, Fmi2Causality.input, "crushing rate dz/dt of bellow {}"),
                ("z_end_m", "m", self.z_end_m, Fmi2Causality.input, "crushing of bellow {} at the end of the "
                                                                    "communication step (used with lookahead)"),
                ("zdot_end_m_per_s", "m/s", self.zdot_end_m_per_s, Fmi2Causality.input,
                 "crushing rate of bellow {} at the end of the communication step (used with lookahead)"),
                ("F_N", "N", self.F_N, Fmi2Causality.output, "force of bellow {} (eq. 4, + pushing the plates apart)"),
                ("K_N_per_m", "N/m", self.K_N_per_m, Fmi2Causality.output,
                 "stiffness dF/dz of bellow {} at constant air mass (adiabatic; isothermal at k = inf)"),
                ("dFdt_N_per_s", "N/s", self.dFdt_N_per_s, Fmi2Causality.output,
                 "rate of the force of bellow {} at frozen crushing (an Euler step of macro_step_s / 2)"),
                ("p_Pa", "Pa", self.p_Pa, Fmi2Causality.output, "pressure of bellow {} (absolute)"),
                ("T_K", "K", self.T_K, Fmi2Causality.output, "air temperature of bellow {}")):
            for i, b in enumerate(self.bellows):
                get, set_ = indexed(values, i)
                extra = {"start": 0.0} if causality == Fmi2Causality.input else {}
                self.register_variable(UnitReal(f"bellow_{b}.{name}", unit, causality=causality,
                                                variability=Fmi2Variability.continuous, description=text.format(b),
                                                getter=get, setter=set_ if causality == Fmi2Causality.input else None,
                                                **extra), nested=False)
        for name, text in (("total_air_mass_kg", "air in all chambers of the circuit"),
                           ("air_injected_kg", "air injected from the supply into the suspension (cumulative)"),
                           ("air_exhausted_kg", "air exhausted to the atmosphere by the valves (cumulative)")):
            self.register_variable(UnitReal(name, "kg", causality=Fmi2Causality.output,
                                            variability=Fmi2Variability.continuous, description=text))
        for i, b in enumerate(self.bellows):
            get, set_ = indexed(self.p0_Pa, i)
            self.register_variable(UnitReal(f"bellow_{b}.p0_Pa", "Pa", causality=Fmi2Causality.parameter,
                                            variability=Fmi2Variability.fixed, initial=Fmi2Initial.exact,
                                            description=f"initial pressure of bellow {b} (absolute; default: the "
                                                        f"scenario's car at rest); its tank, if any, starts at it",
                                            getter=get, setter=set_), nested=False)
        self.register_variable(UnitReal("k_W_per_K", "W/K", causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.fixed, initial=Fmi2Initial.exact,
                                        description="heat transfer coefficient k of every chamber (eq. 8)"))
        self.register_variable(Boolean("isothermal", causality=Fmi2Causality.parameter,
                                       variability=Fmi2Variability.fixed, initial=Fmi2Initial.exact,
                                       description="k = infinity: every chamber held at the atmosphere's "
                                                   "temperature (k_W_per_K is then ignored)"))
        self.register_variable(Boolean("lookahead", causality=Fmi2Causality.parameter,
                                       variability=Fmi2Variability.fixed, initial=Fmi2Initial.exact,
                                       description="true: each step follows the cubic Hermite from the crushing and "
                                                   "rate at its start to those at its end (z_end_m, zdot_end_m_per_s), "
                                                   "a master that advances the mechanics first; false: it extrapolates"))
        self.register_variable(UnitReal("macro_step_s", "s", causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.fixed, initial=Fmi2Initial.exact,
                                        description="the step over which dFdt_N_per_s is taken (an Euler step of half "
                                                    "of it at zero crushing rate; default: the default experiment's)"))
        self.register_variable(UnitReal("pneumatic_step_used_s", "s", causality=Fmi2Causality.calculatedParameter,
                                        variability=Fmi2Variability.fixed, initial=Fmi2Initial.calculated,
                                        getter=lambda: self._h,
                                        description="the RK4 sub-step bound in use: pneumatic_step_s, shortened at "
                                                    "initialisation if k needs it"))
        self.register_variable(UnitReal("pneumatic_step_s", "s", causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.fixed, initial=Fmi2Initial.exact,
                                        description="longest RK4 step of the air within a communication step (shortened at "
                                                    "initialisation if k needs it: pneumatics.integrate.stable_step_s)"))
        #: every Real's getter, and every Real's setter where it has one, by value reference (:meth:`get_real`)
        self._real_getters = {vr: v.getter for vr, v in self.vars.items() if isinstance(v, Real)}
        self._real_setters = {vr: v.setter for vr, v in self.vars.items() if isinstance(v, Real) and v.setter is not None}

    # -- the importer's reads and writes: pythonfmu's, with the variables looked up once -----------

    def get_real(self, vrs):
        """The values of the Reals ``vrs`` (pythonfmu's :meth:`Fmi2Slave.get_real`, which checks each
        variable's type on every call: a few us per step of an instance that is read ~25 values)."""
        getters = self._real_getters
        try:
            return [float(getters[vr]()) for vr in vrs]
        except KeyError:                  # not a Real: pythonfmu's own raises its TypeError
            return super().get_real(vrs)

    def set_real(self, vrs, values):
        """Set the Reals ``vrs`` to ``values`` (pythonfmu's :meth:`Fmi2Slave.set_real`, without its
        per-variable type check)."""
        setters = self._real_setters
        try:
            calls = [setters[vr] for vr in vrs]
        except KeyError:                  # not a Real, or one without a setter: pythonfmu's own raises
            return super().set_real(vrs, values)
        for setter, value in zip(calls, values):
            setter(value)

    # -- the model description: units and the scenario it came from ---------------------------------

    def to_xml(self, model_options=dict()) -> Element:
        root = super().to_xml(model_options)
        units = Element("UnitDefinitions")
        for unit, exponents in UNITS.items():
            SubElement(SubElement(units, "Unit", name=unit), "BaseUnit", {k: str(v) for k, v in exponents.items()})
        children = list(root)
        root.insert(children.index(root.find("CoSimulation")) + 1, units)
        annotations = Element("VendorAnnotations")
        tool = SubElement(SubElement(annotations, "Tool", name="pneumorail"), "Source")
        for key in ("scenario_file", "scenario_sha256", "scenario_name", "pneumorail_version"):
            tool.set(key, str(self.spec[key]))
        root.insert(list(root).index(root.find("ModelVariables")), annotations)
        # every output is calculated at initialisation (FMI 2.0: listed as an initial unknown),
        structure = root.find("ModelStructure")
        # and so is every calculated parameter; listed by index, as FMI 2.0 orders them
        initial = SubElement(structure, "InitialUnknowns")
        calculated = [i + 1 for i, v in enumerate(root.find("ModelVariables"))
                      if v.get("causality") == "calculatedParameter"]
        for index in sorted([int(u.get("index")) for u in structure.find("Outputs")] + calculated):
            SubElement(initial, "Unknown", index=str(index))
        return root

    # -- the simulation ----------------------------------------------------------------------------

    def exit_initialization_mode(self):
        from pneumatics.circuit import Circuit
        from pneumatics.integrate import stable_step_s
        from pneumatics.layouts import pressures_at_rest
        components = self.spec["components"]
        k = math.inf if self.isothermal else self.k_W_per_K
        self._circuit = Circuit(components, k_W_per_K=k)
        self._x = self._circuit.initial_state(pressures_at_rest(components, dict(zip(self.bellows, self.p0_Pa))))
        self._bellow_rows = [self._circuit.chamber_names.index(b) for b in self.bellows]
        # k may have been raised since the export: its thermal rate may need a shorter step
        self._h = stable_step_s(self._circuit, self._x, self.pneumatic_step_s)
        self._sample(np.array(self.z_m), np.array(self.zdot_m_per_s))

    def do_step(self, current_time: float, step_size: float) -> bool:
        from pneumatics.integrate import advance, hermite_motion
        t0, t1 = current_time, current_time + step_size
        z0, zd0 = np.array(self.z_m), np.array(self.zdot_m_per_s)
        if self.lookahead:
            z1, zd1 = np.array(self.z_end_m), np.array(self.zdot_end_m_per_s)
            motion = hermite_motion(t0, t1, z0, zd0, z1, zd1)
        else:
            a = extrapolation_acceleration(zd0, t0, self._previous_rate)
            z1, zd1 = z0 + step_size * (zd0 + 0.5 * step_size * a), zd0 + step_size * a

            def motion(t):
                return z0 + (t - t0) * (zd0 + 0.5 * (t - t0) * a), zd0 + (t - t0) * a
        # the state's rate at the step's start is known when the outputs were sampled at these very
        # inputs (a master's crushing at t_k is what it gave as the previous step's end: lookahead);
        # compared as lists of floats, as np.array_equal compares them (0.0 == -0.0, NaN != NaN)
        z_s, zd_s, rate = self._rate
        rate0 = rate if z_s == self.z_m and zd_s == self.zdot_m_per_s else None
        self._x = advance(self._circuit, self._x, t0, t1, motion, self._h, rate0=rate0)
        self._previous_rate = (t0, zd0)
        self._sample(z1, zd1)
        return True

    def _sample(self, z_m: np.ndarray, zdot_m_per_s: np.ndarray) -> None:
        """The outputs at the current state and crushing ``z_m``, rate ``zdot_m_per_s`` (the
        inputs are left as the importer set them). The stiffness and the force's rate at frozen
        crushing are those of the co-simulation master's linearised force law (cosim.engine.master).
        The pressures and temperatures are the circuit's evaluation's, the force eq. (4) once: what
        ``circuit.outputs`` gives, without what it computes that the FMU does not output."""
        circuit, x = self._circuit, self._x
        evaluated = circuit.evaluate(x, z_m)
        F = circuit.bellow_forces_N(x, z_m)
        rate, held = circuit.derivatives_and_held(x, z_m, zdot_m_per_s, evaluated)
        self._rate = (z_m.tolist(), zdot_m_per_s.tolist(), rate)
        half = 0.5 * self.macro_step_s
        self.F_N[:] = F.tolist()
        self.dFdt_N_per_s[:] = ((circuit.bellow_forces_N(x + half * held, z_m) - F) / half).tolist()
        self.K_N_per_m[:] = circuit.bellow_stiffness_N_per_m(x, z_m).tolist()
        rows = self._bellow_rows
        self.p_Pa[:] = evaluated.p[rows, 0].tolist()
        self.T_K[:] = evaluated.T[rows, 0].tolist()
        self.total_air_mass_kg = float(circuit.total_mass_kg(x))
        nodes = circuit.node_names
        self.air_injected_kg = float(circuit.mass_from(x, "supply")) if "supply" in nodes else 0.0
        self.air_exhausted_kg = -float(circuit.mass_from(x, "atmosphere")) if "atmosphere" in nodes else 0.0
