"""The one base class of every error pneumorail raises on purpose.

``except PneumorailError`` catches each of them and nothing else (a bug stays a traceback):

* bad input: ``cosim.errors.ScenarioError`` (a scenario, a sweep file, an option: file, key path,
  what was expected); ``pneumatics.errors.CircuitError`` (a circuit that cannot be assembled);
* a state that stopped being physical: ``pneumatics.errors.CircuitDiverged``,
  ``vehicle.errors.Derailed``;
* an environment that cannot do what was asked: ``cosim.errors.ExecutorUnavailable``.

Each keeps the built-in class it had (``ValueError`` for bad input, ``RuntimeError`` for the
rest), so code that caught those still does.
"""


class PneumorailError(Exception):
    """Base class of every error pneumorail raises on purpose."""
