"""The circuit's nodes: the chambers that hold air (bellows, tanks, finite supplies), then the
boundary nodes whose pressure and temperature are given (the atmosphere, fixed supplies, and
each compressor's intake and each air demand's exhaust, named after the component:
:mod:`pneumatics.air_supply`)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Tuple

import numpy as np

from ..air_supply import AirDemand, Compressor
from ..boundary import Atmosphere, Supply
from ..chamber import Bellow, Tank
from ..errors import CircuitError
from .arrays import column
from .components import ATMOSPHERE, COMPONENT_TYPES


@dataclass(frozen=True, eq=False)
class Nodes:
    """Node names and indices (chambers first, then boundary nodes), and the boundary nodes'
    pressures and temperatures as (boundary nodes, 1) columns."""

    chamber_names: Tuple[str, ...]
    bellow_names: Tuple[str, ...]
    boundary_names: Tuple[str, ...]
    index: Mapping[str, int]
    p_boundary_Pa: np.ndarray
    T_boundary_K: np.ndarray

    @property
    def names(self) -> Tuple[str, ...]:
        return self.chamber_names + self.boundary_names

    def node(self, link: str, field: str, name: str, chambers_only: bool = False) -> int:
        """The index of node ``name``, which field ``field`` of ``link`` refers to."""
        if name not in self.index:
            known = ", ".join(self.names)
            raise CircuitError([link, field], f"refers to '{name}', which is not in the circuit (known nodes: {known})")
        if chambers_only and name not in self.chamber_names:
            raise CircuitError([link, field], f"'{name}' must be a chamber (bellow, tank or finite supply)")
        return self.index[name]

    def bellow(self, link: str, field: str, name: str) -> int:
        """The index among the bellows of bellow ``name``, which field ``field`` of ``link`` refers to."""
        if name not in self.bellow_names:
            raise CircuitError([link, field], f"'{name}' is not a bellow of the circuit (bellows: {list(self.bellow_names)})")
        return self.bellow_names.index(name)


def classify_nodes(components: Mapping[str, object], atmosphere: Atmosphere) -> Nodes:
    """The nodes of ``components``: every component must be of a known type; the name of the
    atmosphere is reserved."""
    if ATMOSPHERE in components:
        raise CircuitError([ATMOSPHERE], "the name 'atmosphere' is reserved for the surroundings")
    chambers = []
    boundary = [(ATMOSPHERE, atmosphere.p_Pa, atmosphere.T_K)]
    for name, comp in components.items():
        if not isinstance(comp, tuple(COMPONENT_TYPES.values())):
            raise CircuitError([name], f"unknown component {type(comp).__name__}; "
                                       f"expected one of {sorted(COMPONENT_TYPES)}")
        if isinstance(comp, (Bellow, Tank)) or (isinstance(comp, Supply) and not comp.is_fixed):
            chambers.append(name)
        elif isinstance(comp, Supply):
            boundary.append((name, comp.p_Pa, comp.T_K or atmosphere.T_K))
        elif isinstance(comp, Compressor):             # its intake: the air it delivers comes from here
            boundary.append((name, atmosphere.p_Pa, comp.T_delivery_K or atmosphere.T_K))
        elif isinstance(comp, AirDemand):              # its exhaust: the air it draws goes there
            boundary.append((name, atmosphere.p_Pa, atmosphere.T_K))
    bellows = tuple(n for n in chambers if isinstance(components[n], Bellow))
    names = chambers + [b[0] for b in boundary]
    return Nodes(tuple(chambers), bellows, tuple(b[0] for b in boundary), {n: i for i, n in enumerate(names)},
                 column([b[1] for b in boundary]), column([b[2] for b in boundary]))
