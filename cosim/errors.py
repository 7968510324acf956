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

from pathlib import Path
from typing import Sequence, Union

from pneumorail.errors import PneumorailError


class ScenarioError(PneumorailError, ValueError):
    """Bad input: which file, which key path, what was expected."""

    def __init__(self, file: Union[str, Path, None], path: Sequence[str], message: str):
        self.file = str(file) if file else "<scenario>"
        self.path = ".".join(str(p) for p in path) or "(top level)"
        self.reason = message
        super().__init__(f"{self.file}: {self.path}: {message}")

    def __reduce__(self):
        """Picklable (an error raised in a worker process reaches the user unchanged)."""
        return _scenario_error, (self.file, self.path, self.reason)


def _scenario_error(file: str, path: str, reason: str) -> "ScenarioError":
    error = ScenarioError(file, [], reason)
    error.path = path
    error.args = (f"{error.file}: {path}: {reason}",)
    return error


class ExecutorUnavailable(PneumorailError, RuntimeError):
    """The executor asked for cannot be used here (e.g. Dask is not installed)."""
