"""What a pneumatic circuit raises: a description that cannot be assembled (:class:`CircuitError`),
a state that stopped being physical (:class:`CircuitDiverged`). Both are picklable: they are
raised in worker processes too."""
from __future__ import annotations

from typing import Mapping, Sequence

from pneumorail.errors import PneumorailError


class CircuitError(PneumorailError, ValueError):
    """A circuit description that cannot be assembled; ``path`` locates the offending field."""

    def __init__(self, path: Sequence[str], message: str):
        self.path = tuple(str(p) for p in path)
        self.reason = message
        super().__init__(f"{'.'.join(self.path)}: {message}")

    def __reduce__(self):          # picklable: raised in worker processes
        return type(self), (self.path, self.reason)


class CircuitDiverged(PneumorailError, RuntimeError):
    """Integration produced a non-physical state; carries where and when, for a diagnosis."""

    def __init__(self, t_s: float, component: str, state: Mapping[str, float], reason: str):
        self.t_s, self.component, self.state, self.reason = t_s, component, dict(state), reason
        detail = ", ".join(f"{k}={v:.6g}" for k, v in self.state.items())
        super().__init__(f"pneumatic circuit diverged at t = {t_s:.6g} s in '{component}': {reason} ({detail})")

    def __reduce__(self):          # picklable: raised in worker processes
        return type(self), (self.t_s, self.component, self.state, self.reason)
