"""The numbers of each flow law, gathered over the links that obey it, as the evaluation of the
circuit reads them: dynamic and quasi-steady pipes (eq. 5), the ISO 6358 links (eqs 6-7: fixed
orifices, faults' openings, valve sides; one call serves them all), differential valves, and the
levelling valves' levers and conductance tables."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np

from ..compressible_pipe import AIR_VISCOSITY_PA_S, PipeSegment
from .arrays import column, read_only, rows, table_groups
from .links import Links
from .nodes import Nodes
from .valve_dynamics import ValveDynamics, compile_valve_dynamics


@dataclass(frozen=True, eq=False)
class ReynoldsFriction:
    """The compressible pipes' links whose lambda follows the Reynolds number: their rows among
    the pipe-flow states, their ends' node rows, l, A, their share of zeta, d, mu (rows, 1)."""

    rows: object
    a: object
    b: object
    length_m: np.ndarray
    area_m2: np.ndarray
    zeta: np.ndarray
    diameter_m: np.ndarray
    viscosity_Pa_s: np.ndarray


@dataclass(frozen=True, eq=False)
class ChokedEnds:
    """The end links of the compressible pipes, whose flow out of the pipe is limited to the
    choked flow of their cell: their rows among the pipe-flow states (= link rows), their cells'
    node rows, A, l and the sign of a flow out of the pipe (-1 at end a, +1 at b) (rows, 1); their
    cells' indices among :class:`PipeCells`."""

    rows: object
    cell: np.ndarray
    area_m2: np.ndarray
    length_m: np.ndarray
    outflow_sign: np.ndarray
    cell_index: np.ndarray = None
    chamber: np.ndarray = None


@dataclass(frozen=True, eq=False)
class PipeCells:
    """The compressible pipes' cells as their links see them: each cell's chamber row, the rows
    of its left (towards a) and right links among the pipe-flow states (an end cell's are both
    its inner link: its velocity is that link's, not the end link's, which may be choked), its
    length dx (cells, 1); the inner links' rows, the indices (among the cells) of the cell on each side of them and
    their lengths (inner links, 1)."""

    rows: np.ndarray
    left: np.ndarray
    right: np.ndarray
    dx_m: np.ndarray
    inner: np.ndarray
    inner_left: np.ndarray
    inner_right: np.ndarray
    inner_length_m: np.ndarray


@dataclass(frozen=True, eq=False)
class DynamicPipes:
    """Pipes whose flow is a state (eq. 5): their links (the first ones, in the order of the
    pipe-flow states), their ends' node rows, and each pipe's L, A, K (pipes, 1); the links of
    compressible pipes with Reynolds friction and their end links (None: none)."""

    links: slice
    a: object
    b: object
    length_m: np.ndarray
    area_m2: np.ndarray
    loss_coefficient: np.ndarray
    reynolds: Optional[ReynoldsFriction] = None
    choked: Optional[ChokedEnds] = None
    cells: Optional[PipeCells] = None


@dataclass(frozen=True, eq=False)
class QuasiSteadyPipes:
    """Pipes at steady state (eq. 5 without dq/dt): how many, their links, each pipe's A and K."""

    count: int
    links: slice
    area_m2: np.ndarray
    loss_coefficient: np.ndarray


@dataclass(frozen=True, eq=False)
class OrificeLinks:
    """The links whose flow is ISO 6358's (eqs 6-7): fixed orifices, faults' openings, then the
    valves' supply and exhaust sides. Their link rows and ends' node rows; the conductances of
    the first ``n_fixed`` (fixed orifices, then openings: 0 while shut) (n_fixed, 1); every
    link's critical ratio b (links, 1)."""

    links: object
    a: object
    b: object
    n_fixed: int
    fixed_C_m3_per_sPa: np.ndarray
    b_critical: np.ndarray


@dataclass(frozen=True, eq=False)
class DifferentialValves:
    """Differential valves, one group per distinct flow table: (link rows, a-end node rows, b-end
    node rows, dp table, q table)."""

    tables: Tuple[tuple, ...]


@dataclass(frozen=True, eq=False)
class LevellingValves:
    """The levelling (and safety) valves: names; their links (supply sides, then exhaust sides);
    their supply and exhaust conductance tables,
    grouped by distinct table ((valve rows, lever table, C table)); the lever matrix (valves,
    bellows), u = lever @ z (lever_gain x mean crushing of the sensed bellows), and its rows of
    the valves with a play; their response dynamics."""

    names: Tuple[str, ...]
    links: slice
    supply_tables: tuple
    exhaust_tables: tuple
    lever: np.ndarray
    lever_play: np.ndarray
    dynamics: ValveDynamics

    @property
    def count(self) -> int:
        return len(self.names)


@dataclass(frozen=True, eq=False)
class AirSupply:
    """The compressors and air demands (:mod:`pneumatics.air_supply`): the compressors' links,
    their reservoirs' chamber rows, mass flow while running [kg/s], cut-in and cut-out pressures
    [Pa] and governor states at t = 0 (compressors, 1); the demands' links, their nodes' rows,
    full mass flows [kg/s] and fade-out widths [Pa] (demands, 1)."""

    n_compressors: int
    compressor_links: slice
    reservoir: np.ndarray
    w_compressor_kg_per_s: np.ndarray
    p_cut_in_Pa: np.ndarray
    p_cut_out_Pa: np.ndarray
    running_at_start: np.ndarray
    demand_links: slice
    demand_node: np.ndarray
    w_demand_kg_per_s: np.ndarray
    dp_off_Pa: np.ndarray

    @property
    def present(self) -> bool:
        return bool(self.n_compressors or self.demand_node.size)


def compile_air_supply(links: Links, rho_free_kg_per_m3: float, rho_normal_kg_per_m3: float) -> AirSupply:
    """The numbers of the compressors' and demands' laws (``rho_free``: the density of the air a
    compressor takes in; ``rho_normal``: of a normal cubic metre)."""
    rows_c, rows_d = links.rows["compressor"], links.rows["air_demand"]
    fad, cut_in, cut_out, start = _columns(links.parameters["compressor"], 4)
    q_n, dp_off = _columns(links.parameters["air_demand"], 2)
    return AirSupply(rows_c.stop - rows_c.start, rows_c, read_only(links.b[rows_c].copy()), column(rho_free_kg_per_m3 * fad),
                     cut_in, cut_out, start, rows_d, read_only(links.a[rows_d].copy()), column(rho_normal_kg_per_m3 * q_n),
                     dp_off)


def compile_dynamic_pipes(links: Links, V0_m3: Optional[np.ndarray] = None) -> DynamicPipes:
    """The numbers of eq. (5) over the dynamic pipes (``V0_m3``: the chambers' volumes, which
    give a compressible pipe's cells their length)."""
    sl = links.rows["pipe"]
    L, A, K = _columns(links.parameters["pipe"], 3)
    items = [item for _, item in links.sources["pipe"]]
    re_rows = [i for i, c in enumerate(items) if isinstance(c, PipeSegment) and c.friction_factor is None]
    end_rows = [i for i, c in enumerate(items) if isinstance(c, PipeSegment) and c.end]
    reynolds = choked = None
    a, b = links.a[sl], links.b[sl]
    if re_rows:
        segs = [items[i] for i in re_rows]
        reynolds = ReynoldsFriction(rows(re_rows), rows(a[re_rows]), rows(b[re_rows]),
                                    *(column([getattr(c, f) for c in segs]) for f in ("length_m", "area_m2", "zeta",
                                                                                      "diameter_m")),
                                    column([AIR_VISCOSITY_PA_S] * len(segs)))
    if end_rows:
        segs = [items[i] for i in end_rows]
    cells = _pipe_cells(items, a, b, V0_m3)
    if end_rows:
        segs = [items[i] for i in end_rows]
        cell = np.where([c.end == "a" for c in segs], b[end_rows], a[end_rows])
        index = {int(c): j for j, c in enumerate(cells.rows)}
        choked = ChokedEnds(rows(end_rows), read_only(cell), column([c.area_m2 for c in segs]),
                            column([c.length_m for c in segs]), column([-1.0 if c.end == "a" else 1.0 for c in segs]),
                            read_only(np.array([index[int(c)] for c in cell], dtype=int)),
                            read_only(np.where([c.end == "a" for c in segs], a[end_rows], b[end_rows])))
    return DynamicPipes(sl, rows(a), rows(b), L, A, K, reynolds, choked, cells)


def _pipe_cells(items: list, a: np.ndarray, b: np.ndarray, V0_m3) -> Optional[PipeCells]:
    """The cells of the compressible pipes among the dynamic links ``items`` (ends a, b)."""
    segs = [i for i, c in enumerate(items) if isinstance(c, PipeSegment)]
    if not segs:
        return None
    left = {int(b[i]): i for i in segs if items[i].end != "b"}     # a cell is the b end of its left link
    right = {int(a[i]): i for i in segs if items[i].end != "a"}
    cells = list(left)
    for c in cells:             # an end cell moves with its inner link (the end link's flow may be choked)
        if items[left[c]].end and not items[right[c]].end:
            left[c] = right[c]
        elif items[right[c]].end and not items[left[c]].end:
            right[c] = left[c]
    index = {cell: j for j, cell in enumerate(cells)}
    inner = [i for i in segs if not items[i].end]
    area = np.array([items[left[c]].area_m2 for c in cells])
    return PipeCells(read_only(np.array(cells, dtype=int)), read_only(np.array([left[c] for c in cells], dtype=int)),
                     read_only(np.array([right[c] for c in cells], dtype=int)), column(V0_m3[cells, 0] / area),
                     read_only(np.array(inner, dtype=int)), read_only(np.array([index[int(a[i])] for i in inner], dtype=int)),
                     read_only(np.array([index[int(b[i])] for i in inner], dtype=int)),
                     column([items[i].length_m for i in inner]))


def compile_quasi_steady_pipes(links: Links) -> QuasiSteadyPipes:
    """The numbers of eq. (5) at steady state over the quasi-steady pipes."""
    parameters = links.parameters["quasi_steady_pipe"]
    return QuasiSteadyPipes(len(parameters), links.rows["quasi_steady_pipe"], *_columns(parameters, 2))


def compile_orifice_links(links: Links) -> OrificeLinks:
    """The numbers of eqs (6-7) over the fixed orifices, the faults' openings and the valve sides."""
    fixed = links.parameters["orifice"] + links.parameters["fault_opening"]
    sides = links.parameters["valve_supply"] + links.parameters["valve_exhaust"]
    fixed_rows = slice(links.rows["orifice"].start, links.rows["fault_opening"].stop)
    side_rows = valve_sides(links)
    idx = np.r_[np.arange(fixed_rows.start, fixed_rows.stop), np.arange(side_rows.start, side_rows.stop)].astype(int)
    return OrificeLinks(rows(idx), rows(links.a[idx]), rows(links.b[idx]), len(fixed), column([C for C, _ in fixed]),
                        column([b for *_, b in fixed + sides]))


def compile_differential_valves(links: Links) -> DifferentialValves:
    """The differential valves grouped by distinct flow table."""
    sl = links.rows["differential"]
    groups = ((sl.start + np.arange(sl.stop - sl.start)[members], dp, q)
              for members, dp, q in table_groups(links.parameters["differential"]))
    return DifferentialValves(tuple((rows(idx), rows(links.a[idx]), rows(links.b[idx]), dp, q) for idx, dp, q in groups))


def compile_levelling_valves(links: Links, nodes: Nodes) -> LevellingValves:
    """The valves of ``links``; every sensed bellow a bellow of the circuit."""
    valves = [valve for _, valve in links.sources["valve_supply"]]
    names = tuple(links.names_of("valve_supply"))
    lever = np.zeros((len(valves), len(nodes.bellow_names)))
    for i, (name, valve) in enumerate(zip(names, valves)):
        sensed = valve.sensed_bellows
        for s in sensed:
            lever[i, nodes.bellow(name, "sensed", s)] += valve.lever_gain / len(sensed)
    dynamics = compile_valve_dynamics(valves)
    return LevellingValves(names, valve_sides(links), _tables(links.parameters["valve_supply"]),
                           _tables(links.parameters["valve_exhaust"]), read_only(lever), read_only(lever[dynamics.play_rows]),
                           dynamics)


def valve_sides(links: Links) -> slice:
    """The links of the valves' sides: supply sides, then exhaust sides."""
    return slice(links.rows["valve_supply"].start, links.rows["valve_exhaust"].stop)


def _columns(parameters: Tuple[tuple, ...], n: int) -> list:
    """The links' law numbers as ``n`` columns (links, 1), one per number."""
    return [column([p[j] for p in parameters]) for j in range(n)]


def _tables(parameters: Tuple[tuple, ...]) -> tuple:
    """The valve sides' conductance tables grouped by distinct table."""
    return table_groups([(lever, C) for lever, C, _ in parameters])
