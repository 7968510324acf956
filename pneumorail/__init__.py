"""pneumorail's common ground: what the three packages share and nothing else.

The physics packages (``pneumatics``: the air circuit, ``vehicle``: the car) may not import each
other nor the application (``cosim``); what all of them need — the one base class of the project's
errors (:mod:`pneumorail.errors`), the type of the ranges their parameter fields declare
(:mod:`pneumorail.quantities`) and the one bounded reader of every input file
(:mod:`pneumorail.files`) — lives here, importing nothing of theirs. The application's
entry points are in :mod:`cosim` (``pneumorail`` on the command line).
"""
from pneumorail.errors import PneumorailError

__all__ = ["PneumorailError"]
