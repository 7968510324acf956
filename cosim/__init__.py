"""pneumorail's application layer: scenarios in, results out. The map, in the order the rooms
import each other (each only from those above it; ``tests/test_architecture.py`` holds it):

* :mod:`cosim.errors`: the exceptions (``ScenarioError``: bad input; ``ExecutorUnavailable``);
  :mod:`cosim.interrupts`: Ctrl-C and SIGTERM stop a run at a step boundary, keeping its results;
* ``cosim/scenario/``: what a scenario is, nothing runs: the data (:mod:`~cosim.scenario.model`),
  the strict YAML reader (:mod:`~cosim.scenario.yaml_input`), the checking of values into
  dataclasses (:mod:`~cosim.scenario.schema`), circuits (:mod:`~cosim.scenario.circuits`),
  presets, the ``checks:`` section (:mod:`~cosim.scenario.checks`);
* ``cosim/limits/``: judging results: the checks evaluated, EN 14363 criteria and the
  assessment of a run on track, comfort, the models' validity flags, the state limits that stop
  an impossible case;
* ``cosim/stability/``: the car and its circuit as one linear system;
* ``cosim/results/``: the :class:`~cosim.results.outcome.Outcome` of a run, its labelled series,
  the writer, plots, the report, output folders, what ``compare`` reads;
* ``cosim/engine/``: the co-simulation master (the macro-step coupling of car and circuit, the
  sampled outputs) and a car scenario's cases run on a process pool;
* ``cosim/kinds/``: the scenario kinds, each a :class:`~cosim.kinds.base.Kind` subclass (its
  experiment, its checking, its run, figures and metrics), and the registry of their instances
  (:data:`cosim.kinds.KINDS`; docs/architecture.md);
* :mod:`cosim.load` (:func:`load_scenario`), :mod:`cosim.runner` (:func:`run`,
  :func:`run_scenario`), :mod:`cosim.keyref` (the generated key reference);
* ``cosim/verification/``: ``verify`` (every step halved: Richardson) and the monolithic
  reference; ``cosim/sweep/``: parameter studies on a process pool or Dask;
* :mod:`cosim.cli`: the ``pneumorail`` command.

The public API, importable from here::

    from cosim import load_scenario, run
    outcome = run(load_scenario("scenarios/twist_dqq.yaml"))
"""
from __future__ import annotations

import importlib

#: public name -> the module that defines it (imported on first use: ``import cosim`` stays cheap)
_PUBLIC = {"load_scenario": "cosim.load", "run": "cosim.runner", "run_scenario": "cosim.runner",
           "Outcome": "cosim.results.outcome", "ScenarioError": "cosim.errors",
           "ExecutorUnavailable": "cosim.errors"}

__all__ = list(_PUBLIC)


def __getattr__(name: str):
    if name in _PUBLIC:
        return getattr(importlib.import_module(_PUBLIC[name]), name)
    raise AttributeError(f"module 'cosim' has no attribute {name!r}")
