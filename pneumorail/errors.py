"""The one base class of every error pneumorail raises on purpose.

``except PneumorailError`` catches each of them and nothing else (a bug stays a traceback):

* bad input: :class:`InputError` (a file or option that cannot be used: file, key path or line,
  what was expected; raised by the one file reader, :mod:`pneumorail.files`), and its subclass
  ``cosim.errors.ScenarioError`` (a scenario, a sweep file, an option: file, key path,
  what was expected); ``pneumatics.errors.CircuitError`` (a circuit that cannot be assembled);
* a state that stopped being physical: ``pneumatics.errors.CircuitDiverged``,
  ``vehicle.errors.Derailed``;
* an environment that cannot do what was asked: ``cosim.errors.ExecutorUnavailable``.

Each keeps the built-in class it had (``ValueError`` for bad input, ``RuntimeError`` for the
rest), so code that caught those still does.
"""


class PneumorailError(Exception):
    """Base class of every error pneumorail raises on purpose."""


class InputError(PneumorailError, ValueError):
    """Bad input: which file, where in it (a key path, a line, a column, an option), what was
    expected. The command line prints it and exits 2."""

    def __init__(self, file, path, message: str):
        self.file = str(file) if file else "<scenario>"
        self.path = ".".join(str(p) for p in path) or "(top level)"
        self.reason = message
        super().__init__(f"{self.file}: {self.path}: {message}")

    def __reduce__(self):
        """Picklable (an error raised in a worker process reaches the user unchanged)."""
        return _rebuild, (type(self), self.file, self.path, self.reason)


def _rebuild(cls, file: str, path: str, reason: str) -> "InputError":
    error = cls(file, [], reason)
    error.path = path
    error.args = (f"{error.file}: {path}: {reason}",)
    return error
