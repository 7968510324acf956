"""What a scenario asks for, as data: the car's circuit, the solver, verify and state-limit
settings and the :class:`Scenario` that holds them with its kind's experiment (each kind declares
its own experiment dataclass, :mod:`cosim.kinds`). Nothing here reads files or runs anything:
:mod:`cosim.load` builds these from YAML and validates them, the kinds run them.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Optional, Tuple

from cosim.scenario.checks import Check
from cosim.scenario.payload import PayloadSchedule
from pneumatics.air_supply import AirDemand, Compressor, ScheduledDemand
from pneumatics.boundary import Supply
from pneumatics.chamber import Bellow, Tank
from pneumatics.circuit import Circuit
from pneumatics.faults import Fault
from pneumatics.layouts import car_circuit
from pneumatics.pipe import Pipe
from pneumatics.valves import DifferentialPressureValve, LevellingValve
from pneumorail.quantities import plausible
from vehicle.params import SPECTRAL_RADIUS, TrackStructure, VehicleParams

#: default length of the final window the quasi-static end values are averaged over [s]
DEFAULT_WINDOW_S = 5.0
#: the track under the car when a scenario names none (``track:``; vehicle.params.TrackStructure)
DEFAULT_TRACK_MODEL = "rigid"
#: the parameters of a flexible track when a scenario names no preset
DEFAULT_TRACK_PRESET = "slab_track"


@dataclass(frozen=True)
class SolverSettings:
    """Co-simulation settings (see cosim/engine/master.py for the scheme). ``spectral_radius``: the
    multibody integrator's (generalized-alpha) spectral radius at infinite frequency, rho in
    [0, 1]: how much it damps what its step cannot resolve (1: nothing; 0: the most; the
    integrator stays second order for every rho). The wheelsets' modes on their contacts lie at
    ~250 Hz, far beyond a 5 ms step; see docs/models.md, "Numerical damping", for how the
    default was chosen. ``pneumatic_step_s``: the largest RK4 step of the air; shortened for a
    large finite k (its thermal rate, :func:`pneumatics.integrate.stable_step_s`; ~1e4 W/K and
    above at 5 ms), the same for every k of a run, so that ``jobs`` (how the k values are shared
    out over processes) does not change a number."""

    macro_step_s: float = 0.005
    mechanics_step_s: float = 0.005
    pneumatic_step_s: float = 0.005
    coupling: str = "linearised"
    output_interval_s: float = 0.02
    jobs: int = field(default=2, metadata=plausible(1, 256, why="worker processes"))
    spectral_radius: float = field(default=SPECTRAL_RADIUS, metadata=plausible(
        0.0, 1.0, why="generalized-alpha: 1 damps nothing, 0 the most"))


#: ranges of :class:`StateLimits`' fields (metadata): a roll relative to the track plane (3.2 rad:
#: upside down); air temperature and pressure limits up to 10 000 K and 1000 bar, far beyond
#: any air (a limit must also admit the air a run starts with: cosim.load)
_ROLL = plausible(0.0, 3.2, "rad", "a roll relative to the track plane", low_inclusive=False)
_TEMPERATURE_LIMIT = plausible(0.0, 1e4, "K", "a limit of the air's temperature", low_inclusive=False)
_PRESSURE_LIMIT = plausible(0.0, 1e8, "Pa absolute", "a limit of the air's pressure", low_inclusive=False)


@dataclass(frozen=True)
class StateLimits:
    """States no car can be in: a case whose state passes one of these stops at the end of that
    macro-step with a diagnosis (time, body or component, state) and the run exits 1, keeping
    what it computed (:mod:`cosim.limits.watch`); a limit the air already passes when the run
    starts (a chamber's initial pressure or temperature, e.g. ``T_max_K`` written in degrees
    Celsius) is refused when the scenario is loaded. Each is far beyond what a running car reaches,
    so that it marks a capsized, derailed or crushed car, not a demanding one:

    * ``carbody_roll_rad``: the carbody rolled relative to the track plane by more than this
      (0.2 rad: the paper's car rolls 0.03 rad at 1 m/s^2 of unbalanced lateral acceleration;
      its bellows' plates touch at ~0.17 rad);
    * ``bogie_roll_rad``: a bogie frame rolled relative to the track plane by more (0.1 rad:
      40 mm of primary stroke over the 2 m axlebox spacing is 0.04 rad);
    * ``wheelset_lift_s``: both wheels of a wheelset off their rails (no contact force) for
      longer than this (0.1 s: 1 m of track at 10 m/s; a wheel unloaded by an impact lifts for
      milliseconds);
    * ``bellow_crushing_fraction``: an airspring (bellow and emergency spring) crushed or
      extended by more than this fraction of its height (1: its plates meet, or it has doubled
      its height);
    * ``bellow_volume_fraction``: a bellow crushed to less than this fraction of its nominal
      volume (0.05: its air compressed twentyfold or more, the bellow crushed flat);
    * ``T_min_K``, ``T_max_K``, ``p_min_Pa``, ``p_max_Pa``: air in a chamber colder or hotter,
      or at a lower or higher absolute pressure than this (150 K / 1000 K, 0.1 / 50 bar: air
      liquefies near 80 K; the ideal gas with constant heat capacities is no longer air far
      above 1000 K; the car's bellows carry ~4.2 bar).
    """

    carbody_roll_rad: float = field(default=0.2, metadata=_ROLL)
    bogie_roll_rad: float = field(default=0.1, metadata=_ROLL)
    wheelset_lift_s: float = 0.1
    bellow_crushing_fraction: float = field(default=1.0, metadata=plausible(
        0.0, 10.0, why="a fraction of the bellow height", low_inclusive=False))
    bellow_volume_fraction: float = field(default=0.05, metadata=plausible(
        0.0, 1.0, why="a fraction of the bellow's volume", high_inclusive=False))
    T_min_K: float = field(default=150.0, metadata=_TEMPERATURE_LIMIT)
    T_max_K: float = field(default=1000.0, metadata=_TEMPERATURE_LIMIT)
    p_min_Pa: float = field(default=1.0e4, metadata=_PRESSURE_LIMIT)
    p_max_Pa: float = field(default=5.0e6, metadata=_PRESSURE_LIMIT)


@dataclass(frozen=True)
class VerifySettings:
    """``pneumorail verify``: the run is repeated with every step halved ``levels`` times; it
    fails when a headline metric's estimated relative discretisation error (Richardson) at
    the scenario's own steps exceeds ``tolerance``."""

    tolerance: float = field(default=0.005, metadata=plausible(0.0, 1.0, why="a relative error", low_inclusive=False,
                                                                high_inclusive=False))
    levels: int = field(default=2, metadata=plausible(2, 6, why="halvings of every step; each doubles the cost of the last run"))


@dataclass(frozen=True)
class CarCircuit:
    """The car's circuit: ``four_point`` (one levelling valve per bellow) or ``two_point``;
    ``valves`` false isolates every bellow (with its tank) from the supply and the other bellows."""

    layout: str
    bellow: Bellow
    tank: Optional[Tank]
    pipe: Pipe
    valves: bool
    levelling_valve: LevellingValve
    differential_valve: Optional[DifferentialPressureValve]
    supply: Supply
    cross_pipe: Optional[Pipe]
    explicit: Optional[Tuple[Tuple[str, object], ...]] = None
    #: what fails, when (``faults:``; :mod:`pneumatics.faults`)
    faults: Tuple[Fault, ...] = ()
    #: the compressor filling the (finite) supply and the other consumers drawing from it
    #: (``circuit.compressor``, ``circuit.air_demand``; :mod:`pneumatics.air_supply`)
    compressor: Optional[Compressor] = None
    air_demand: Optional[AirDemand] = None
    #: demands that draw only within their windows (a service's air per stop), name -> demand: each
    #: an air demand of the circuit at its rate at t = 0, which the co-simulation switches at the
    #: windows' edges (:class:`cosim.engine.master.CoSimulation`)
    scheduled_demands: Tuple[Tuple[str, ScheduledDemand], ...] = ()

    def components(self) -> Dict[str, object]:
        scheduled = {name: s.at(0.0) for name, s in self.scheduled_demands}
        if self.explicit is not None:
            return {**dict(self.explicit), **scheduled}
        components = car_circuit(self.bellow, self.tank, self.pipe,
                                 levelling=self.levelling_valve if self.valves else None,
                                 differential=self.differential_valve if self.valves else None,
                                 supply=self.supply, points=4 if self.layout == "four_point" else 2,
                                 cross_pipe=self.cross_pipe)
        extra = {name: c for name, c in (("compressor", self.compressor), ("air_demand", self.air_demand)) if c is not None}
        extra.update(scheduled)
        if extra and "supply" not in components:     # valves off: the reservoir is still there, filled and drawn
            components["supply"] = self.supply
        return {**components, **extra}

    def compile(self, k_W_per_K=0.0) -> Circuit:
        """The circuit with its faults (none happened yet), for the k values ``k_W_per_K``."""
        return Circuit(self.components(), k_W_per_K=k_W_per_K, faults=self.faults)

    def faults_label(self) -> str:
        """The faults in words (summary rows, figure titles); empty without faults."""
        return "; ".join(f.label() for f in self.faults)


# ----------------------------------------------------------------------------------- scenario
@dataclass(frozen=True)
class Scenario:
    """A validated scenario (built by :func:`cosim.load.load_scenario`): where it came from
    (file, content hash, overrides, every file read), its k values, its kind's ``experiment`` (the
    dataclass of its YAML section: a ``TwistTest`` from ``twist:``, a ``CurveTest`` from ``curve:``,
    a rig test from ``test:``) and its ``circuit``; the car kinds add ``vehicle``,
    ``track``, ``solver``, ``verify``, ``state_limits`` and ``checks``."""

    file: Path
    kind: str
    name: str
    description: str
    k_W_per_K: Tuple[float, ...]
    content_sha256: str
    overrides: Tuple[str, ...] = ()
    #: (path relative to the scenario file, sha256) of every file read: the scenario, parameter files
    files_sha256: Tuple[Tuple[str, str], ...] = ()
    #: the YAML section that holds the experiment (the kind's :attr:`~cosim.kinds.base.Kind.section`)
    section: str = ""
    #: the experiment of the kind (``TwistTest``, ``CurveTest``, a rig test ...)
    experiment: Any = None
    #: the circuit: the car's (:class:`CarCircuit`) or the rig's (``cosim.kinds.rig.RigCircuit``)
    circuit: Any = None
    vehicle: Optional[VehicleParams] = None
    #: the track under the rails (car kinds): rigid or flexible
    track: TrackStructure = TrackStructure()
    solver: SolverSettings = SolverSettings()
    verify: VerifySettings = VerifySettings()
    #: states that stop a case (car kinds: ``state_limits``)
    state_limits: StateLimits = StateLimits()
    checks: Tuple[Check, ...] = ()
    #: passengers boarding and alighting (car kinds: ``payload:``; None: the tare car throughout)
    payload: Optional[PayloadSchedule] = None
    #: validity flags (:data:`cosim.limits.validity.FLAGS`) that ``check`` accepts instead of failing on
    allow: Tuple[str, ...] = ()
    raw: Dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    @property
    def car_payload(self):
        """What the car's floor carries over time, ``MetroCar(payload=...)``: t -> payload blocks
        (None: no ``payload:``, the tare car, built as before)."""
        return self.payload.blocks_at if self.payload is not None else None

    def with_valves(self, valves: bool) -> "Scenario":
        """The same car scenario with its levelling (and differential) valves connected (True) or
        isolated (False)."""
        return dataclasses.replace(self, circuit=dataclasses.replace(self.circuit, valves=valves))

    def with_experiment(self, **changes) -> "Scenario":
        """The same scenario with fields of its experiment changed (``ramp_s=1.0``)."""
        return dataclasses.replace(self, experiment=dataclasses.replace(self.experiment, **changes))
