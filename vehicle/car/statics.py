"""The car's reference configuration: loads and positions at static equilibrium on level track
(:class:`StaticReference`; why this state: :mod:`vehicle.car`, "Reference configuration")."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..params import VehicleParams


@dataclass(frozen=True)
class StaticReference:
    """Static equilibrium on level track (the car is symmetric)."""

    #: force of each airspring carrying the carbody [N]
    bellow_force_N: float
    #: load of each axlebox spring [N]
    axlebox_load_N: float
    #: vertical load of each wheel [N]
    wheel_load_N: float
    #: bogie centre x [m], front then rear
    bogie_x_m: np.ndarray
    #: wheelset centre x [m], wheelsets 1..4 from the front
    wheelset_x_m: np.ndarray
    #: height of the wheelset centres [m]: the wheel radius less the Hertz deflection (contact
    #: guidance: where the contact law holds the wheelset, see :func:`.contact.contact_guidance`)
    wheelset_z_m: float
    #: nominal height of the airsprings: the distance of their plates [m]
    bellow_height_m: float
    #: the airsprings include an emergency spring and/or a vertical bumpstop
    airspring_in_series: bool

    @classmethod
    def of(cls, p: VehicleParams, payload_kg: float = 0.0) -> StaticReference:
        """The reference state of the car ``p`` on its vertical Hertz contacts, its carbody
        carrying ``payload_kg`` centred on the floor (:mod:`.payload`)."""
        g = p.gravity_m_per_s2
        carbody_kg = p.carbody_mass_kg + payload_kg
        P_axlebox_N = (carbody_kg * g / 2.0 + p.bogie_mass_kg * g) / 4.0
        Q_static_N = P_axlebox_N + p.wheelset_mass_kg * g / 2.0
        delta_static_m = (Q_static_N / p.hertz_constant_N_per_m1_5) ** (2.0 / 3.0)
        bellow_height_m = p.airspring_upper_height_m - p.airspring_lower_height_m
        if bellow_height_m <= 0.0:
            raise ValueError("airspring_upper_height_m must exceed airspring_lower_height_m")
        return cls(bellow_force_N=carbody_kg * g / 4.0, axlebox_load_N=P_axlebox_N,
                   wheel_load_N=Q_static_N, bogie_x_m=np.array(p.bogie_x_m),
                   wheelset_x_m=np.array(p.wheelset_x_m),
                   wheelset_z_m=p.wheel_radius_m - delta_static_m, bellow_height_m=bellow_height_m,
                   airspring_in_series=(math.isfinite(p.emergency_spring_stiffness_N_per_m)
                                        or p.vertical_bumpstop_stiffness_N_per_m > 0.0))

    def with_wheelset_z_m(self, z_m: float) -> StaticReference:
        """The same state with the wheelset centres at ``z_m`` (contact guidance)."""
        return dataclasses.replace(self, wheelset_z_m=z_m)
