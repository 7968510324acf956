"""A circuit's components compiled, once, into the arrays its evaluation reads (:class:`Assembly`).

:func:`assemble` checks the description and builds, in this order: the cases' k, the nodes
(:mod:`.nodes`) and the chambers' geometry (:mod:`.chambers`), the faults (:mod:`.faults`), the
links from the table of link types (:mod:`.link_types`, :mod:`.links`), the heat exchange, each
chamber's own law included (:mod:`.heat`), the numbers of each flow law (:mod:`.laws`, with the valves' response dynamics,
:mod:`.valve_dynamics`; the compressors and air demands), the state layout (:mod:`.layout`) and what the active faults change.
An error in the description is a :class:`~pneumatics.errors.CircuitError` naming the field.
The evaluation at a state is :class:`pneumatics.runtime.CircuitRuntime`'s.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import FrozenSet, Mapping, Sequence, Tuple

from ..air_supply import free_air_density_kg_per_m3, normal_density_kg_per_m3
from ..boundary import Atmosphere
from ..compressible_pipe import expand_compressible_pipes
from ..faults import Fault
from ..gas import AIR, Gas
from .chambers import ChamberGeometry, compile_chambers
from .faults import ActiveFaults, check_faults, compile_active_faults, fault_openings
from .heat import HeatExchange, case_k, compile_heat_exchange
from .laws import (
    AirSupply,
    DifferentialValves,
    DynamicPipes,
    LevellingValves,
    OrificeLinks,
    QuasiSteadyPipes,
    compile_air_supply,
    compile_differential_valves,
    compile_dynamic_pipes,
    compile_levelling_valves,
    compile_orifice_links,
    compile_quasi_steady_pipes,
)
from .layout import StateLayout
from .links import Links, compile_links
from .nodes import Nodes, classify_nodes

__all__ = ["Assembly", "assemble"]


@dataclass(frozen=True, eq=False)
class Assembly:
    """A circuit compiled: the components as compiled (an active stuck-open differential valve
    without its dead band), the gas, the surroundings, the faults and which of them are active,
    and the compiled parts (every array read-only)."""

    components: Mapping[str, object]
    gas: Gas
    atmosphere: Atmosphere
    faults: Tuple[Fault, ...]
    active_faults: FrozenSet[int]
    heat: HeatExchange
    nodes: Nodes
    chambers: ChamberGeometry
    links: Links
    pipes: DynamicPipes
    quasi_steady_pipes: QuasiSteadyPipes
    orifice_links: OrificeLinks
    differential_valves: DifferentialValves
    valves: LevellingValves
    active: ActiveFaults
    layout: StateLayout
    air_supply: AirSupply

    @property
    def fault_links(self) -> slice:
        """The links of the faults' openings to the atmosphere."""
        return self.links.rows["fault_opening"]


def assemble(components: Mapping[str, object], *, gas: Gas = AIR, atmosphere: Atmosphere = Atmosphere(),
             k_W_per_K=0.0, faults: Sequence[Fault] = (), active_faults: Sequence[int] = ()) -> Assembly:
    """``components`` (name -> component) compiled with ``faults``, those of indices
    ``active_faults`` having happened; ``k_W_per_K``: the heat-transfer coefficient (eq. 8), one
    per case or one for all."""
    faults = tuple(faults)
    active = frozenset(int(i) for i in active_faults)
    k = case_k(k_W_per_K)
    # a compressible pipe is cut into its cells (chambers) and links (dynamic pipes) here; the
    # faults name the components as given, and a ruptured pipe opens at its own ends
    nodes = classify_nodes(expand_compressible_pipes(components), atmosphere)
    chambers = compile_chambers(expand_compressible_pipes(components), nodes)
    given = check_faults(faults, active, components, nodes.chamber_names)
    compiled = expand_compressible_pipes(given)
    links = compile_links(compiled, nodes, fault_openings(faults, active, given, nodes.chamber_names, gas))
    heat = compile_heat_exchange(k, compiled, nodes, chambers, links)
    valves = compile_levelling_valves(links, nodes)
    pipes = compile_dynamic_pipes(links, chambers.V0_m3)
    n_pipes = pipes.links.stop - pipes.links.start
    air_supply = compile_air_supply(links, free_air_density_kg_per_m3(atmosphere.p_Pa, atmosphere.T_K, gas.R_J_per_kgK),
                                    normal_density_kg_per_m3(gas.R_J_per_kgK))
    layout = StateLayout(len(nodes.chamber_names), n_pipes, len(links.names), valves.count, valves.dynamics.n_states,
                         air_supply.n_compressors)
    effects = compile_active_faults(faults, active, compiled, links.names, links.a, links.b, links.rows["fault_opening"],
                                    nodes.index, valves.names, n_pipes)
    return Assembly(MappingProxyType(compiled), gas, atmosphere, faults, active, heat, nodes, chambers, links, pipes,
                    compile_quasi_steady_pipes(links), compile_orifice_links(links), compile_differential_valves(links),
                    valves, effects, layout, air_supply)
