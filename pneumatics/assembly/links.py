"""The circuit's links compiled from the table of link types (:data:`~.link_types.LINK_TYPES`):
their names and ends, each type's rows, sources and law's numbers, and the incidence of the
links on the chambers (eq. 1: dm/dt = incidence @ w)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Sequence, Tuple

import numpy as np

from ..compressible_pipe import PipeSegment
from ..errors import CircuitError
from ..pipe import Pipe
from .arrays import read_only
from .faults import Opening
from .link_types import LINK_TYPES, PIPE_MODELS, LinkEnds
from .nodes import Nodes


@dataclass(frozen=True, eq=False)
class Links:
    """Every link, in the order of :data:`LINK_TYPES`: names; node index of each end (a positive
    flow goes from a to b); by link type key, its rows (a slice), its sources ((name, item)) and
    each link's law numbers; the incidence on the chambers (chambers, links: -1 at a, +1 at b);
    each link's sign of outflow from the boundary (+1 out of a boundary node at a, -1 at b)."""

    names: Tuple[str, ...]
    a: np.ndarray
    b: np.ndarray
    rows: Mapping[str, slice]
    sources: Mapping[str, tuple]
    parameters: Mapping[str, tuple]
    incidence: np.ndarray
    boundary_sign: np.ndarray

    def names_of(self, key: str) -> list:
        """The names of the sources of link type ``key`` (components, or the faults' links)."""
        return [name for name, _ in self.sources[key]]


def compile_links(components: Mapping[str, object], nodes: Nodes, openings: Sequence[Opening]) -> Links:
    """The links of ``components`` and of the faults' ``openings``, each end checked
    (:func:`_end_nodes`); then every link's values checked, component by component."""
    for n, c in components.items():
        if isinstance(c, Pipe) and not isinstance(c, PipeSegment) and c.model not in PIPE_MODELS:
            raise CircuitError([n, "model"], f"expected one of {PIPE_MODELS}, got '{c.model}'")
    names, ends, rows, sources, parameters = [], [], {}, {}, {}
    for link_type in LINK_TYPES:
        selected = link_type.sources(components, openings)
        rows[link_type.key] = slice(len(names), len(names) + len(selected))
        for name, item in selected:
            link_type.check_nodes(name, item, nodes)
            link = link_type.ends(name, item)
            ends.append(_end_nodes(link, nodes))
            names.append(link.link)
        sources[link_type.key] = tuple(selected)
        parameters[link_type.key] = tuple(link_type.parameters(name, item) for name, item in selected)
    for name, comp in components.items():
        for link_type in LINK_TYPES:
            if link_type.takes(comp):
                link_type.check(name, comp)
    incidence, boundary_sign = _incidence(ends, len(nodes.chamber_names))
    return Links(tuple(names), read_only(np.array([e[0] for e in ends], dtype=int)),
                 read_only(np.array([e[1] for e in ends], dtype=int)), rows, sources, parameters, incidence, boundary_sign)


def _end_nodes(link: LinkEnds, nodes: Nodes) -> Tuple[int, int]:
    """The node indices of the ends of ``link``: nodes of the circuit, not both the same, not
    both boundary nodes."""
    ia, ib = nodes.node(link.owner, link.a_field, link.a), nodes.node(link.owner, link.b_field, link.b)
    if ia == ib:
        raise CircuitError([link.owner, link.b_field], f"both ends are '{link.a}'")
    n_chambers = len(nodes.chamber_names)
    if ia >= n_chambers and ib >= n_chambers:
        raise CircuitError([link.owner], f"connects two boundary nodes ('{link.a}', '{link.b}')")
    return ia, ib


def _incidence(ends, n_chambers: int):
    """(incidence on the chambers (chambers, links), sign of outflow from the boundary (links,))."""
    incidence = np.zeros((n_chambers, len(ends)))
    boundary_sign = np.zeros(len(ends))
    for j, (ia, ib) in enumerate(ends):
        if ia < n_chambers:
            incidence[ia, j] -= 1.0
        else:
            boundary_sign[j] = 1.0
        if ib < n_chambers:
            incidence[ib, j] += 1.0
        else:
            boundary_sign[j] = -1.0
    return read_only(incidence), read_only(boundary_sign)
