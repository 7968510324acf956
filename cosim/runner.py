"""Run a scenario: its kind's ``run(scenario, progress) -> Computed`` (compute only, nothing
written), the one :class:`Outcome` built from it (timing, totals, validity flags), then (:func:`run_scenario`) the kind's
``figures(outcome)`` and the files (:mod:`cosim.results.writer`). :func:`run` gives the in-memory
result. A kind's module (:mod:`cosim.kinds`) holds the rest."""
from __future__ import annotations

import logging
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Dict, List, Optional

from cosim.interrupts import stop_requested
from cosim.kinds import KINDS
from cosim.limits.validity import flag_rows, warnings_for
from cosim.results.io import Progress
from cosim.results.outcome import LOG, Outcome, warn
from cosim.results.writer import write_outcome
from cosim.scenario.model import Scenario


def run(scenario: Scenario, progress: Optional[Progress] = None) -> Outcome:
    """Run ``scenario`` and return its :class:`Outcome` (nothing is written), built here once from
    what its kind computed (:class:`~cosim.results.outcome.Computed`): the wall time, the totals
    and checkable metrics of the cases (:meth:`~cosim.kinds.base.Kind.totals`,
    :meth:`~cosim.kinds.base.Kind.case_metrics`), on every row what failed and what the floor
    carries (``faults``, ``payload``), and every row's validity flags (:mod:`cosim.limits.validity`).
    Every warning of the run is in ``outcome.warnings`` (run.json) and logged once: a kind that only
    kept one has it logged here."""
    kind = KINDS[scenario.kind]
    t0 = time.perf_counter()
    with _logged_warnings() as logged:
        computed = kind.run(scenario, progress or Progress(scenario.name, quiet=True))
    wall_s = time.perf_counter() - t0
    labels = _labels(scenario)
    rows = [{**row, **labels} for row in computed.rows]   # what failed, what the floor carries
    cases = computed.cases
    if cases is None:
        cases = [c for c in map(kind.case_metrics, computed.rows) if c is not None]
    flag_rows(rows)
    warnings = list(computed.warnings)
    for message in warnings:
        if message not in logged:
            LOG.warning(message)
    for message in warnings_for(rows):
        warn(warnings, message)
    return Outcome(scenario=scenario, rows=rows, shown=computed.shown, series=computed.series,
                   metrics=kind.totals(computed.rows), cases=cases, diagnoses=computed.diagnoses, warnings=warnings,
                   info=computed.info, wall_s=wall_s, interrupted=stop_requested(), tables=computed.tables)


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
    labels = _labels(scenario)
    for figure in figures if labels else ():    # every figure says what failed and what the floor carries
        figure.title = "\n".join([figure.title or "", *(f"{name}: {text}" for name, text in labels.items())]).lstrip("\n")
    write_outcome(outcome, out_dir, figures, scenario.solver.jobs if kind.car else 1)
    return outcome


def _labels(scenario: Scenario) -> Dict[str, str]:
    """What a run carries besides the intact car at its tare, in words, by summary column: its
    ``faults`` and its ``payload`` (at arrival and what boards or alights); none without them (or
    for a rig)."""
    payload = scenario.payload.label() if scenario.payload is not None else ""
    return {name: text for name, text in (("faults", scenario.circuit.faults_label()), ("payload", payload)) if text}
