"""What a scenario kind is: a :class:`Kind` subclass, one instance of which the registry
(:mod:`cosim.kinds`) holds.

A kind declares, as class attributes, its name, its YAML section and the experiment dataclass that
section builds, and the metrics it offers (checkable, per wheel, per zone, headline, plotted); it
implements :meth:`Kind.run`, the one method every kind must have. Everything else has a default
that a kind overrides where it differs: its figures, the checks and limits its experiment cannot
give, the track's test zones, the files its scenario reads besides itself, and what ``compare``
overlays. :class:`CarKind` adds what a co-simulated car run needs (its section parsed, how long it
runs, its valve settings, the car it builds); :class:`RigKind` what a rig run needs (its whole
scenario loaded; the circuit ``pneumorail identify`` drives).

The application layer asks the registry's instances; nothing is found by name on a module::

    kind = KINDS[scenario.kind]
    computed = kind.run(scenario, progress)       # rows, series, tables, warnings
    outcome = cosim.runner.run(scenario)          # the Outcome, built once from them
    figures = kind.figures(outcome)
"""
from __future__ import annotations

import math
from abc import ABC, abstractmethod
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Dict, List, Mapping, Optional, Sequence, Tuple

from cosim.limits.checks import CaseMetrics
from cosim.results.outcome import largest

if TYPE_CHECKING:                              # annotations only: the kinds import these rooms themselves
    from cosim.results.io import Progress
    from cosim.results.outcome import Computed, Outcome
    from cosim.results.plots import Figure
    from cosim.scenario.model import Scenario


class Kind(ABC):
    """A scenario kind.

    Class attributes
    ----------------
    name : str
        ``kind:`` in the scenario file.
    section : str
        The YAML section of its experiment (``twist``, ``curve``, ``test``); the scenario holds
        what it builds as ``scenario.experiment``.
    experiment : type
        The experiment dataclass the section builds.
    car : bool
        A car kind (:class:`CarKind`: ``vehicle``, ``track``, ``circuit``, ``solver``, ``verify``,
        ``state_limits``, ``checks``; co-simulated, verifiable) or a rig kind (:class:`RigKind`).
    check_metrics : tuple of str
        The metrics ``checks:`` may name (each the largest over the selected cases).
    wheel_metrics : tuple of str
        Those of them that can name a wheel (``dqq_max[3R]``).
    zone_metrics : tuple of str
        Those of them that can name a test zone of the track (``yq_2m_p9985[zone=R<250]``);
        :meth:`zones` lists the zones a scenario's track has.
    headline_metrics : tuple of str
        The summary columns ``verify`` estimates the discretisation error of.
    total_metrics : tuple of str
        The summary columns :meth:`totals` takes the largest of over the cases (None: the
        headline metrics).
    plot_metrics : tuple of str
        The summary columns a sweep plots against its keys.
    k_fixed : str
        Why ``--k`` does not apply, for a kind computed for fixed k values (empty: it applies).
    case_columns : tuple of str
        The summary columns that identify a case (a row): what ``verify`` pairs across its levels
        and ``sweep.nc`` takes as dimensions (those present in the rows).
    identify : str
        What ``pneumorail identify`` fits its scenarios to: ``time`` (a rig's time history) or
        ``table`` (a dynamic-stiffness table); empty: not identifiable (see
        :meth:`RigKind.identify_circuit`).
    """

    name: ClassVar[str]
    section: ClassVar[str]
    experiment: ClassVar[type]
    car: ClassVar[bool] = False
    check_metrics: ClassVar[Tuple[str, ...]] = ()
    wheel_metrics: ClassVar[Tuple[str, ...]] = ()
    zone_metrics: ClassVar[Tuple[str, ...]] = ()
    headline_metrics: ClassVar[Tuple[str, ...]] = ()
    total_metrics: ClassVar[Optional[Tuple[str, ...]]] = None
    plot_metrics: ClassVar[Tuple[str, ...]] = ()
    k_fixed: ClassVar[str] = ""
    case_columns: ClassVar[Tuple[str, ...]] = ("valves", "k_W_per_K")
    identify: ClassVar[str] = ""

    @abstractmethod
    def run(self, scenario: "Scenario", progress: "Progress") -> "Computed":
        """Compute the scenario (nothing written): its rows, series, tables and warnings
        (:class:`~cosim.results.outcome.Computed`; the runner builds the Outcome)."""

    def totals(self, rows: Sequence[Mapping[str, object]]) -> Dict[str, float]:
        """The totals over the cases (``Outcome.metrics``): the largest of each of
        :attr:`total_metrics` a row has (NaN if a case has none or NaN: it diverged)."""
        names = self.headline_metrics if self.total_metrics is None else self.total_metrics
        return {m: largest(r.get(m, math.nan) for r in rows) for m in names if any(m in r for r in rows)}

    def case_metrics(self, row: Mapping[str, object]) -> Optional[CaseMetrics]:
        """The checkable metrics of one summary row (None: the row is not a case ``checks:``
        judge); default: each of :attr:`check_metrics`, NaN where the row has none."""
        if not self.check_metrics:
            return None
        return CaseMetrics(row["k_W_per_K"], row["valves"], {m: row.get(m, math.nan) for m in self.check_metrics})

    def figures(self, outcome: "Outcome") -> List["Figure"]:
        """The figures of a run (default: none; its numbers are the summary)."""
        return []

    def refuse_check(self, metric: str, experiment: Any) -> Optional[str]:
        """Why the experiment cannot give ``metric`` (e.g. lateral wheel forces without wheel-rail
        contact); None: it can."""
        return None

    def refuse_limit(self, metric: str, op: str, limit: float, experiment: Any) -> Optional[str]:
        """Why the experiment cannot decide this limit (e.g. a critical speed above the speeds it
        scans); None: it can."""
        return None

    def refuse_zone(self, metric: str, zone: str, experiment: Any) -> Optional[str]:
        """Why ``metric`` has no value in test zone ``zone`` of the experiment's track (e.g. a
        quasi-static value, assessed in tight arcs only, on the straight); None: it has one."""
        return None

    def zones(self, experiment: Any) -> Tuple[str, ...]:
        """The test zones of the experiment's track (kinds with ``zone_metrics``)."""
        return ()

    def extra_files(self, experiment: Any) -> Tuple[Path, ...]:
        """The files the experiment reads besides the scenario (hashed into the provenance)."""
        return ()

    #: whether :meth:`compare` overlays this kind's runs
    @property
    def compares(self) -> bool:
        return type(self).compare is not Kind.compare

    def compare(self, infos, out_dir: Path, select, label, window: str) -> List[Path]:
        """Overlays of several runs' results (``pneumorail compare``): the figures' paths."""
        raise NotImplementedError(f"{self.name} runs have no overlays")

    def __repr__(self) -> str:
        return f"<kind {self.name}>"


class CarKind(Kind):
    """A kind that co-simulates the car with its circuit (a section of its own beside
    ``vehicle``, ``track``, ``circuit``, ``solver``, ...)."""

    car = True
    #: what its runs sample besides every car run's :data:`cosim.engine.master.OUTPUTS`
    #: (:class:`cosim.engine.master.Output`, each ``read`` a module-level function): columns of its
    #: own, that no other kind's files gain; pass them to :func:`cosim.engine.cases.simulate_cases`
    outputs: ClassVar[Tuple[Any, ...]] = ()

    @abstractmethod
    def parse(self, data: Any, vehicle, path: Path) -> Any:
        """The kind's section checked: its experiment (``vehicle``: the scenario's car parameters)."""

    @abstractmethod
    def duration_s(self, experiment: Any) -> float:
        """How long its longest run lasts [s] (the steps are checked against it)."""

    def shortest_duration_s(self, experiment: Any) -> float:
        """How long its shortest run lasts [s]: every fault must happen within it."""
        return self.duration_s(experiment)

    def valve_settings(self, experiment: Any, valves: bool) -> Tuple[bool, ...]:
        """The valve settings its cases run with (``valves``: ``circuit.valves``)."""
        return experiment.valve_settings

    def refuse_faults(self, experiment: Any) -> Optional[str]:
        """Why the experiment cannot honour ``faults:`` (None: it runs them)."""
        return None

    def refuse_imported_circuit(self, experiment: Any) -> Optional[str]:
        """Why the experiment cannot run with an FMU as its circuit (``circuit.fmu``; None: it
        runs it, through :func:`cosim.engine.cases.simulate_cases`)."""
        return None

    def refuse_payload(self, experiment: Any) -> Optional[str]:
        """Why the experiment cannot honour ``payload:`` (None: it runs it; its ``make_car`` passes
        ``scenario.car_payload`` to the car)."""
        return None

    def with_payload(self, experiment: Any, payload: Any, path: Path) -> Any:
        """The experiment once the scenario's ``payload:`` is read (``payload``: its
        :class:`~cosim.scenario.payload.PayloadSchedule`, None without one): what the kind needs of it,
        checked (default: the experiment unchanged). A service takes its reference masses and
        the load on board at the start, and checks the load at every stop."""
        return experiment

    def with_circuit(self, experiment: Any, circuit: Any, path: Path) -> Any:
        """The scenario's circuit once the experiment is final (after :meth:`with_payload`), with
        what the kind adds to it, checked (default: the circuit unchanged). A service adds its air
        per stop: a demand on the main reservoir that draws at every stop
        (:class:`~pneumatics.air_supply.ScheduledDemand`)."""
        return circuit

    @abstractmethod
    def make_car(self, scenario: "Scenario"):
        """The car of a run, with the :class:`vehicle.car.MetroCar` interface (a bound method of
        the registry's instance: picklable, for the worker processes)."""


class RigKind(Kind):
    """A kind that runs the bellow-tank test rig alone (``circuit`` and ``test`` sections)."""

    section = "test"

    @abstractmethod
    def load(self, data: Mapping, path: Path, common: Mapping) -> "Scenario":
        """The whole scenario from its checked top level (``common``: the fields every scenario
        has)."""

    def identify_circuit(self, scenario: "Scenario"):
        """(components, initial pressures) of the rig ``pneumorail identify`` drives (kinds with
        ``identify``)."""
        raise NotImplementedError(f"{self.name} scenarios are not identifiable")
