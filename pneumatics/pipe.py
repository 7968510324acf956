"""Pneumatic pipe (paper §2.2, eq. 5): no mass storage, adiabatic, incompressible flow with inertia.

Mass flow q is counted positive from end ``a`` to end ``b``. The paper's eq. (5) counts it the
other way (from port 2 to port 1); the physics is the same.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from pneumorail.quantities import nonnegative, plausible, positive, ranged

from .compiled import elementwise


@dataclass(frozen=True)
class Pipe:
    """A pipe between two nodes. Defaults: the bellow-tank pipe of Table 1.

    The pressure-drop coefficient is lambda L/d + zeta; Table 1 gives a total of 1.11, entered
    as ``zeta`` with ``friction_factor`` (lambda) 0. ``model``: ``dynamic`` (eq. 5, the flow is a
    state), ``quasi_steady`` (eq. 5 with dq/dt = 0, an algebraic flow) or ``compressible`` (a
    finite-volume line of ``cells`` cells, or of cells about ``cell_length_m`` long when ``cells``
    is 0, that carries pressure waves: :mod:`pneumatics.compressible_pipe`). ``friction_factor``
    null (compressible pipes only): lambda from the Reynolds number of the flow, laminar to
    turbulent (:func:`pneumatics.compressible_pipe.darcy_friction_factor`).
    """

    a: str
    b: str
    length_m: float = field(default=1.0, metadata=ranged(positive("m")))
    diameter_m: float = field(default=0.018, metadata=plausible(0.0, 0.3, "m", "a pneumatic pipe's bore", low_inclusive=False))
    friction_factor: Optional[float] = field(default=0.0, metadata=ranged(nonnegative(why="Darcy friction factor lambda")))
    zeta: float = field(default=1.11, metadata=ranged(nonnegative(why="pressure-loss coefficient of fittings")))
    model: str = "dynamic"
    # compressible pipes only: 0 = from cell_length_m; 1000 cells of a 1 m pipe are 1 mm each,
    # finer than any wave a suspension excites, and the explicit step shrinks with the cell
    cells: int = field(default=0, metadata=plausible(0, 1000, "", "cells of a compressible pipe (0: from "
                                                                    "cell_length_m)"))
    cell_length_m: float = field(default=0.05, metadata=plausible(0.0, 10.0, "m", "a compressible pipe's target "
                                                                               "cell length", low_inclusive=False))

    @property
    def area_m2(self) -> float:
        return math.pi * self.diameter_m ** 2 / 4.0

    @property
    def loss_coefficient(self) -> float:
        """lambda L/d + zeta, the factor of the quadratic pressure drop in eq. (5) (lambda null,
        from the Reynolds number: zeta alone)."""
        return (self.friction_factor or 0.0) * self.length_m / self.diameter_m + self.zeta


@elementwise(7)
def pipe_flow_rate_kg_per_s2(q_kg_per_s, p_a_Pa, p_b_Pa, rho_kg_per_m3, length_m, area_m2, loss_coefficient):
    """Eq. (5): dq/dt = A/L ((p_a - p_b) - (lambda L/d + zeta) q |q| / (2 rho A^2)). Arrays
    broadcast (compiled, :mod:`pneumatics.compiled`)."""
    drop = loss_coefficient * q_kg_per_s * abs(q_kg_per_s) / (2.0 * rho_kg_per_m3 * (area_m2 * area_m2))
    return area_m2 / length_m * ((p_a_Pa - p_b_Pa) - drop)


#: Pressure difference [Pa] below which the quasi-steady pipe law is rounded off to stay differentiable.
QUASI_STEADY_ROUNDING_PA = 1.0


def pipe_flow_quasi_steady_kg_per_s(p_a_Pa, p_b_Pa, rho_kg_per_m3, area_m2, loss_coefficient,
                                    rounding_Pa=QUASI_STEADY_ROUNDING_PA):
    """Eq. (5) at steady state: q = sign(dp) A sqrt(2 rho |dp| / K).

    The square root has an infinite slope at dp = 0, which stalls implicit integrators; it is
    replaced by A sqrt(2 rho / K) dp / (dp^2 + r^2)^(1/4), equal to it within 1e-6 relative once
    |dp| > 1000 r (r = 1 Pa by default, 1e-5 of a bellow's pressure).
    """
    dp = p_a_Pa - p_b_Pa
    return area_m2 * np.sqrt(2.0 * rho_kg_per_m3 / loss_coefficient) * dp / (dp * dp + rounding_Pa ** 2) ** 0.25
