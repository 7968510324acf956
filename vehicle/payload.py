"""Payload on the carbody's floor: passengers as uniform blocks standing on patches of the floor
(:class:`PayloadBlock`), and the mass, centre of gravity and inertia of the carbody carrying them
(:func:`carbody_mass`). Pure numbers (no exudyn): the scenario reader checks payloads with it,
the car (:mod:`vehicle.car.payload`) sets what it gives on its carbody between steps.

A block of mass m, footprint length a (along x) by width b (along y) and height c, its centre of
gravity at (x, y, z) relative to the carbody's reference point (the tare carbody's centre of
gravity), has about its own centre of gravity (uniform rectangular block, e.g. Gross et al.,
*Engineering Mechanics 3*, table of moments of inertia)

    I_xx = m (b^2 + c^2) / 12,   I_yy = m (a^2 + c^2) / 12,   I_zz = m (a^2 + b^2) / 12.

The loaded carbody (tare body + blocks, masses m_i at r_i, the tare body at r = 0) then has

    M = sum m_i,   r_G = sum m_i r_i / M,
    I_O = sum [ I_Gi + m_i (|r_i|^2 E - r_i r_i^T) ]          (about the reference point O)

(Steiner's parallel-axis theorem). exudyn's ``ObjectRigidBody`` takes exactly these: its mass,
its centre of mass relative to the node (``centerOfMass``) and its inertia about the node
(``inertia``, not about the centre of mass). A block of negative mass is a payload leaving that
patch (alighting): the sums hold for it as they are; the total must stay at least the tare mass.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence, Tuple

import numpy as np

from .params import VehicleParams


@dataclass(frozen=True)
class PayloadBlock:
    """Passengers (or any payload) on a patch of the floor, a uniform block: ``mass_kg`` (negative:
    payload leaving that patch), its footprint centred at ``x_m`` along the car from the car
    centre (+ forward) and ``y_m`` across (+ left), ``length_m`` by ``width_m`` (0 by 0: a point
    mass), ``height_m`` tall, its centre of gravity ``cog_above_floor_m`` above the floor."""

    mass_kg: float
    x_m: float = 0.0
    y_m: float = 0.0
    length_m: float = 0.0
    width_m: float = 0.0
    height_m: float = 0.0
    cog_above_floor_m: float = 0.0

    def scaled(self, fraction: float) -> "PayloadBlock":
        """The same block with ``fraction`` of its mass (a boarding under way)."""
        return PayloadBlock(self.mass_kg * fraction, self.x_m, self.y_m, self.length_m, self.width_m,
                            self.height_m, self.cog_above_floor_m)


@dataclass(frozen=True)
class CarbodyMass:
    """Mass properties of the carbody with its payload, as exudyn's rigid body takes them."""

    #: total mass [kg]
    mass_kg: float
    #: centre of gravity relative to the carbody's reference point (its tare centre of gravity) [m]
    com_m: Tuple[float, float, float]
    #: inertia about the reference point, body axes, exudyn's order (Ixx, Iyy, Izz, Iyz, Ixz, Ixy) [kg m^2]
    inertia6_kg_m2: Tuple[float, float, float, float, float, float]


def payload_mass_kg(blocks: Sequence[PayloadBlock]) -> float:
    """Total payload mass [kg] of ``blocks``."""
    return float(sum(b.mass_kg for b in blocks))


def block_position_m(p: VehicleParams, block: PayloadBlock) -> np.ndarray:
    """(3,) centre of gravity of ``block`` relative to the tare carbody's centre of gravity [m]."""
    return np.array([block.x_m, block.y_m, p.floor_height_m + block.cog_above_floor_m - p.carbody_cog_height_m])


def carbody_mass(p: VehicleParams, blocks: Sequence[PayloadBlock]) -> CarbodyMass:
    """The carbody of ``p`` carrying ``blocks`` (see the module docstring for the sums)."""
    M = p.carbody_mass_kg
    first = np.zeros(3)
    I_O = np.diag([p.carbody_inertia_xx_kg_m2, p.carbody_inertia_yy_kg_m2, p.carbody_inertia_zz_kg_m2]).astype(float)
    for b in blocks:
        if b.mass_kg == 0.0:
            continue
        r = block_position_m(p, b)
        m = b.mass_kg
        a2, b2, c2 = b.length_m ** 2, b.width_m ** 2, b.height_m ** 2
        I_G = np.diag([m * (b2 + c2), m * (a2 + c2), m * (a2 + b2)]) / 12.0
        I_O += I_G + m * (float(r @ r) * np.eye(3) - np.outer(r, r))
        M += m
        first += m * r
    if not M > 0.0:
        raise ValueError(f"the carbody's mass with its payload must be positive, got {M:g} kg")
    com = first / M
    return CarbodyMass(float(M), tuple(float(c) for c in com),
                       (float(I_O[0, 0]), float(I_O[1, 1]), float(I_O[2, 2]),
                        float(I_O[1, 2]), float(I_O[0, 2]), float(I_O[0, 1])))
