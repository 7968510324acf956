"""The payload on the carbody's floor during a run (:class:`CarbodyPayload`): before every internal
step the carbody's mass, centre of gravity and inertia are set from the payload at the step's end
time (:func:`vehicle.payload.carbody_mass`).

Why the carbody's own parameters, not a second body: exudyn reads a rigid body's ``mass``,
``centerOfMass`` and ``inertia`` afresh at every evaluation, and its gravity
(``LoadMassProportional``) follows the mass (checked: a body on a spring sinks by the new m g / k
after its mass is changed between steps, and tilts by m g x / k after its centre of mass is moved
by x). A second body on the floor would need the same changing mass, plus a joint, six
coordinates and a constraint. The cost: three ``SetObjectParameter`` calls (~1 us each) per
internal step while the payload changes, nothing while it holds (the last values are kept and
compared). The Newton Jacobian kept across steps (:mod:`.solver`) then carries the mass matrix of
when it was computed; modified Newton converges on it all the same (a boarding changes the
carbody's mass by ~0.02 % per 5 ms step).

The car starts at its static equilibrium with the payload at t = 0 (:meth:`CarbodyPayload.initial`),
which must therefore be centred on the floor (the static reference is the symmetric one).
"""
from __future__ import annotations

from typing import Callable, Sequence

from ..params import VehicleParams
from ..payload import CarbodyMass, PayloadBlock, carbody_mass, payload_mass_kg

#: a centred payload's first moment may differ from zero by this [kg m] (round-off of the sums)
CENTRED_TOL_KG_M = 1e-6


class CarbodyPayload:
    """The payload ``payload(t) -> blocks`` of the carbody of ``params``."""

    def __init__(self, params: VehicleParams, payload: Callable[[float], Sequence[PayloadBlock]]):
        self._params, self._payload = params, payload
        blocks = payload(0.0)
        moment = [sum(b.mass_kg * getattr(b, axis) for b in blocks) for axis in ("x_m", "y_m")]
        if max(abs(m) for m in moment) > CENTRED_TOL_KG_M:
            raise ValueError(f"the payload at t = 0 must be centred on the floor (the car starts at its symmetric "
                             f"static equilibrium): its first moment is {moment[0]:g} kg m along and "
                             f"{moment[1]:g} kg m across the car")
        #: the carbody at t = 0 (what it is built with)
        self.initial: CarbodyMass = carbody_mass(params, blocks)
        #: payload mass at t = 0 [kg]
        self.initial_payload_kg = payload_mass_kg(blocks)
        self._set = (tuple(blocks), self.initial)
        #: payload mass set last [kg]
        self.payload_kg = self.initial_payload_kg

    def pre_step(self, mbs, carbody, t: float) -> None:
        """The carbody's mass, centre of gravity and inertia at ``t`` (set only when they change)."""
        blocks = tuple(self._payload(t))
        if blocks == self._set[0]:
            return
        now = carbody_mass(self._params, blocks)
        mbs.SetObjectParameter(carbody, "mass", now.mass_kg)
        mbs.SetObjectParameter(carbody, "centerOfMass", list(now.com_m))
        mbs.SetObjectParameter(carbody, "inertia", list(now.inertia6_kg_m2))
        self._set = (blocks, now)
        self.payload_kg = payload_mass_kg(blocks)

    @property
    def carbody_mass_kg(self) -> float:
        """The carbody's mass with the payload set last [kg]."""
        return self._set[1].mass_kg
