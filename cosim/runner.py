"""The runner registry: for every scenario kind, ``run(scenario, progress) -> Outcome`` (compute
only, nothing written) and ``figures(outcome) -> [Figure]`` (what to draw). :func:`run` gives the
in-memory result, :func:`run_scenario` runs and writes (:mod:`cosim.results.writer`).

The runner modules are imported when their kind is run: a rig scenario needs no exudyn."""
from __future__ import annotations

import importlib
from pathlib import Path
from typing import Optional

from cosim.scenario.model import CAR_KINDS, RIG_KINDS, Scenario
from cosim.results.outcome import Outcome, Runner, warn
from cosim.results.io import Progress
from cosim.limits.validity import flag_rows, warnings_for
from cosim.results.writer import write_outcome

#: kind -> the module whose ``RUNNERS`` dict holds its :class:`Runner`
MODULES = {**{kind: "cosim.kinds.rig" for kind in RIG_KINDS}, "twist": "cosim.kinds.twist", "curve_entry": "cosim.kinds.curve_entry"}


def runner(kind: str) -> Runner:
    return importlib.import_module(MODULES[kind]).RUNNERS[kind]


def run(scenario: Scenario, progress: Optional[Progress] = None) -> Outcome:
    """Run ``scenario`` and return its :class:`Outcome` (nothing is written); every summary row
    carries its validity flags (:mod:`cosim.limits.validity`)."""
    outcome = runner(scenario.kind).run(scenario, progress or Progress(scenario.name, quiet=True))
    flag_rows(outcome.rows)
    for message in warnings_for(outcome.rows):
        warn(outcome.warnings, message)
    return outcome


def run_scenario(scenario: Scenario, out_dir: Path, progress: Progress) -> Outcome:
    """Run ``scenario`` and write its results into ``out_dir``."""
    chosen = runner(scenario.kind)
    outcome = run(scenario, progress)
    jobs = scenario.solver.jobs if scenario.kind in CAR_KINDS else 1
    write_outcome(outcome, out_dir, chosen.figures(outcome), jobs)
    return outcome
