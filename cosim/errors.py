"""The exceptions of the application layer, in one place.

* :class:`ScenarioError`: bad input (a scenario, a sweep file, a command-line option): which
  file, which key path, what was expected. Raised before anything runs; the CLI prints it and
  exits 2.
* :class:`ExecutorUnavailable`: the sweep executor asked for cannot be used here (Dask not
  installed, no scheduler at the address).

Every one of them, and what the physics raises, has one base class, :class:`pneumorail.errors.PneumorailError`.
What the physics raises stays with the physics: ``pneumatics.circuit.CircuitError`` (a circuit
that cannot be assembled), ``pneumatics.circuit.CircuitDiverged``, ``vehicle.errors.Derailed``.
"""
from __future__ import annotations

from pneumorail.errors import InputError, PneumorailError


class ScenarioError(InputError):
    """Bad input: which file, which key path, what was expected (:class:`pneumorail.errors.InputError`,
    the application's own)."""


class ExecutorUnavailable(PneumorailError, RuntimeError):
    """The executor asked for cannot be used here (e.g. Dask is not installed)."""
