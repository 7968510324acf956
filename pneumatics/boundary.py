"""Boundary nodes: the atmosphere and the supply (main reservoir)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

from pneumorail.quantities import ranged

from .chamber import VESSEL_VOLUME
from .gas import ABSOLUTE_PRESSURE, AIR_TEMPERATURE


@dataclass(frozen=True)
class Atmosphere:
    """The surroundings: fixed pressure and temperature; node name ``atmosphere``."""

    p_Pa: float = 101_325.0
    T_K: float = 293.15


@dataclass(frozen=True)
class Supply:
    """The main reservoir feeding the levelling valves.

    ``V_m3`` infinite (default): a source at fixed ``p_Pa`` and ``T_K``. Finite: a rigid
    reservoir chamber starting at ``p_Pa`` that empties as it delivers (it exchanges heat like
    any chamber). Default 9 bar absolute: a railway main reservoir at about 8 bar gauge (assumed).
    ``T_K`` None means the atmosphere's temperature.
    """

    p_Pa: float = field(default=9.0e5, metadata=ranged(ABSOLUTE_PRESSURE))
    T_K: Optional[float] = field(default=None, metadata=ranged(AIR_TEMPERATURE))
    V_m3: float = field(default=math.inf, metadata=VESSEL_VOLUME)

    @property
    def is_fixed(self) -> bool:
        return math.isinf(self.V_m3)
