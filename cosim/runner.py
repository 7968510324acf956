"""Run a scenario: its kind's ``run(scenario, progress) -> Outcome`` (compute only, nothing
written), the validity flags on every summary row, then (:func:`run_scenario`) the kind's
``figures(outcome)`` and the files (:mod:`cosim.results.writer`). :func:`run` gives the in-memory
result. A kind's module (:mod:`cosim.kinds`) holds the rest."""
from __future__ import annotations

import logging
from contextlib import contextmanager
from pathlib import Path
from typing import List, Optional

from cosim.interrupts import stop_requested
from cosim.kinds import KINDS
from cosim.limits.validity import flag_rows, warnings_for
from cosim.results.io import Progress
from cosim.results.outcome import LOG, Outcome, warn
from cosim.results.writer import write_outcome
from cosim.scenario.model import Scenario


def run(scenario: Scenario, progress: Optional[Progress] = None) -> Outcome:
    """Run ``scenario`` and return its :class:`Outcome` (nothing is written); every summary row
    carries its validity flags (:mod:`cosim.limits.validity`). Every warning of the run is in
    ``outcome.warnings`` (run.json) and logged once: a kind that only kept one has it logged here."""
    with _logged_warnings() as logged:
        outcome = KINDS[scenario.kind].run(scenario, progress or Progress(scenario.name, quiet=True))
    outcome.interrupted = stop_requested()
    faults = _faults_label(scenario)
    if faults:                                    # every row says what failed
        outcome.rows = [{**row, "faults": faults} for row in outcome.rows]
    flag_rows(outcome.rows)
    for message in outcome.warnings:
        if message not in logged:
            LOG.warning(message)
    for message in warnings_for(outcome.rows):
        warn(outcome.warnings, message)
    return outcome


class _Collect(logging.Handler):
    def __init__(self):
        super().__init__(logging.WARNING)
        self.messages: List[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


@contextmanager
def _logged_warnings():
    """The messages logged on the ``pneumorail`` logger meanwhile (none while it is disabled, as
    in a sweep's case: logging them again then prints nothing either)."""
    handler = _Collect()
    LOG.addHandler(handler)
    try:
        yield handler.messages
    finally:
        LOG.removeHandler(handler)


def run_scenario(scenario: Scenario, out_dir: Path, progress: Progress) -> Outcome:
    """Run ``scenario`` and write its results into ``out_dir``."""
    kind = KINDS[scenario.kind]
    outcome = run(scenario, progress)
    figures = kind.figures(outcome)
    faults = _faults_label(scenario)
    for figure in figures if faults else ():     # every figure says what failed
        figure.title = f"{figure.title or ''}\nfaults: {faults}".lstrip("\n")
    write_outcome(outcome, out_dir, figures, scenario.solver.jobs if kind.car else 1)
    return outcome


def _faults_label(scenario: Scenario) -> str:
    """The scenario's faults in words; empty without faults (or for a rig)."""
    return getattr(scenario.circuit, "faults_label", lambda: "")()
