"""What a scenario kind is: :class:`Kind`, the declaration each kind module makes of itself.

A kind module (``cosim/kinds/twist.py`` ...) holds everything about its kind: the experiment
dataclass (its YAML section), how that section is checked, how the kind runs and what it draws,
its checkable and headline metrics, what ``compare`` overlays, and (for the car kinds) how the car
is built. It declares it in a :class:`Kind`; the registry (:mod:`cosim.kinds`) lists the kinds,
and nothing else in the application layer names one.

Functions a kind module provides (``Kind.module`` names it; imported when needed):

* ``run(scenario, progress) -> Outcome`` and ``figures(outcome) -> [Figure]`` (every kind);
* ``parse(data, vehicle, path) -> experiment``: the kind's section checked (car kinds; the rig
  kinds load their whole scenario, ``load(data, path, common) -> Scenario``);
* ``duration_s(experiment)``, ``valve_settings(experiment, valves)``: how long a car run lasts,
  and its valve settings (``valves``: ``circuit.valves``);
* ``make_car(scenario)``: the car of a car kind (a picklable module-level function);
* ``shortest_duration_s(experiment)``: how long its shortest case runs, when its cases differ
  (optional; the faults must happen within it);
* ``zones(experiment) -> (zone, ...)``: the track's test zones (kinds with ``zone_metrics``);
* ``refuse_check(metric, experiment) -> reason or None``: a checkable metric the scenario's
  experiment cannot give (e.g. lateral wheel forces without wheel-rail contact);
  ``refuse_limit(metric, op, limit, experiment) -> reason or None``: a limit it cannot decide
  (e.g. a critical speed above the speeds it scans);
* ``compare(infos, out_dir, select, label, window) -> [Path]``: overlays of several runs' time
  series (optional: without it ``compare`` says the kind has none).
"""
from __future__ import annotations

import sys
from dataclasses import dataclass
from types import ModuleType
from typing import Tuple


@dataclass(frozen=True)
class Kind:
    """A scenario kind.

    Attributes
    ----------
    name : str
        ``kind:`` in the scenario file.
    section : str
        The YAML section of its experiment (``twist``, ``curve``, ``test``); the scenario's
        experiment is also ``scenario.<section>``.
    experiment : type
        The experiment dataclass the section builds.
    module : str
        The module that declares and runs it.
    car : bool
        A car kind (``vehicle``, ``track``, ``circuit``, ``solver``, ``verify``,
        ``state_limits``, ``checks``; co-simulated, verifiable) or a rig kind.
    check_metrics : tuple of str
        The metrics ``checks:`` may name (each the largest over the selected cases).
    wheel_metrics : tuple of str
        Those of them that can name a wheel (``dqq_max[3R]``).
    zone_metrics : tuple of str
        Those of them that can name a test zone of the track (``yq_2m_p9985[zone=R<250]``); the
        module's ``zones(experiment)`` lists the zones its track has.
    headline_metrics : tuple of str
        The summary columns ``verify`` estimates the discretisation error of.
    plot_metrics : tuple of str
        The summary columns a sweep plots against its keys.
    k_fixed : str
        Why ``--k`` does not apply, for a kind computed for fixed k values (empty: it applies).
    case_columns : tuple of str
        The summary columns that identify a case (a row): what ``verify`` pairs across its levels
        and ``sweep.nc`` takes as dimensions (those present in the rows).
    identify : str
        What ``pneumorail identify`` fits its scenarios to: ``time`` (a rig's time history) or
        ``table`` (a dynamic-stiffness table); empty: not identifiable. Such a kind's module
        provides ``identify_circuit(scenario) -> (components, initial pressures)``.
    """

    name: str
    section: str
    experiment: type
    module: str
    car: bool = False
    check_metrics: Tuple[str, ...] = ()
    wheel_metrics: Tuple[str, ...] = ()
    zone_metrics: Tuple[str, ...] = ()
    headline_metrics: Tuple[str, ...] = ()
    plot_metrics: Tuple[str, ...] = ()
    k_fixed: str = ""
    case_columns: Tuple[str, ...] = ("valves", "k_W_per_K")
    identify: str = ""

    @property
    def code(self) -> ModuleType:
        """The module that declares and runs the kind (imported: it made this declaration)."""
        return sys.modules[self.module]
