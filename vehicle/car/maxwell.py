"""The Maxwell dampers' internal states, stepped with the solver (:class:`MaxwellDampers`; the
element and why its state lives in its force law: :func:`.secondary._add_damper`)."""
from __future__ import annotations

import exudyn as exu

from ..suspension import maxwell_step
from .secondary import OptionalComponents

_OUT = exu.OutputVariableType


class MaxwellDampers:
    """The secondary dampers that are Maxwell elements (none: :attr:`active` is False)."""

    def __init__(self, components: OptionalComponents):
        #: the Maxwell elements (:class:`~.secondary.SecondaryDamper`)
        self.dampers = components.maxwell
        #: symbolic variable: the internal step size [s] their laws read (None without any)
        self.step_size = components.maxwell_step
        self.active = bool(self.dampers)
        self._time_s = 0.0  # time of the states (last accepted step end)

    def set_step_size(self, mbs, t: float) -> None:
        """Before the step ending at t: its size, for the laws."""
        self.step_size.SetValue(t - mbs.systemData.GetTime(exu.ConfigurationType.StartOfStep))

    def post_step(self, mbs, t: float) -> bool:
        """PostStep user function: after an accepted step ending at t, advance each Maxwell
        element's state (y, dy/dt) to t from the converged deflection, with the very law the
        connector used (:func:`maxwell_step`). Idempotent: exudyn also calls it at the start of
        every SolveSteps, for a state already committed."""
        t0 = self._time_s
        if not t > t0:
            return True
        h = t - t0
        get = mbs.GetObjectOutput
        for d in self.dampers:
            deflection = float(get(d.connector, _OUT.DisplacementLocal)[d.axis])
            d.force, d.y, d.ydot = maxwell_step(deflection, d.y, d.ydot, h, d.k_s, d.c1, d.c2, d.v_b)
            d.y_sym.SetValue(d.y)
            d.ydot_sym.SetValue(d.ydot)
        self._time_s = t
        return True
