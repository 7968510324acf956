"""The types of link a circuit compiles, in the order its links take (:data:`LINK_TYPES`).

A link carries a signed mass flow between two nodes, a -> b. Each link type declares how it is
compiled: which components (or faults' openings) it takes, the link each of them makes (its
name and ends), the checks of their values, and the numbers of its flow law:

====================  ======================  ===========================  ==================
link type (``key``)   from                    link name                    law's numbers
====================  ======================  ===========================  ==================
``pipe``              dynamic pipe            ``<pipe>``                   L, A, K (eq. 5)
                      compressible pipe's     ``<pipe>``, ``<pipe>.seg<i>``  l, A, K of its share
                      links                                                (eq. 5 per link)
``quasi_steady_pipe`` quasi-steady pipe       ``<pipe>``                   A, K (eq. 5, steady)
``orifice``           orifice                 ``<orifice>``                C, b (eqs 6-7)
``fault_opening``     a fault's opening       ``<component>.<kind>``       C (0 while inactive), b
``differential``      differential valve      ``<valve>``                  table q(|dp|)
``valve_supply``      levelling/safety valve  ``<valve>.supply``           table C(u), b
``valve_exhaust``     levelling/safety valve  ``<valve>.exhaust``          table C(-u), b
``compressor``        compressor              ``<compressor>``             w when running, cut-in, out
``air_demand``        air demand              ``<demand>``                 w, dp_off
====================  ======================  ===========================  ==================

A compressor's link runs from its intake (a boundary node named after it) into its reservoir,
a demand's from its node to its exhaust (likewise): :mod:`pneumatics.air_supply`.
"""
from __future__ import annotations

from typing import Mapping, NamedTuple, Sequence, Tuple

import numpy as np

from ..air_supply import AirDemand, Compressor
from ..compressible_pipe import COMPRESSIBLE, PipeSegment
from ..errors import CircuitError
from ..orifice import Orifice
from ..pipe import Pipe
from ..valves import DifferentialPressureValve, LevellingValve
from .components import ATMOSPHERE
from .faults import Opening
from .nodes import Nodes


class LinkEnds(NamedTuple):
    """A link's name, what an error about its ends names (a component, or ``faults[i]``), and
    each end: the field that names it and the node it names."""

    link: str
    owner: str
    a_field: str
    a: str
    b_field: str
    b: str


class LinkType:
    """How one type of link is compiled (a subclass per type, registered in :data:`LINK_TYPES`);
    ``key`` names its links in the compiled circuit. The class attributes declare its value
    checks: the fields that must be > 0, whether ``b_critical`` must be in [0, 1), its tables
    (x field, y field; :func:`_check_table`)."""

    key = ""
    positive: Tuple[str, ...] = ()
    critical_ratio = False
    tables: Tuple[Tuple[str, str], ...] = ()

    def takes(self, comp) -> bool:
        """Whether component ``comp`` makes a link of this type."""
        return False

    def sources(self, components: Mapping[str, object], openings: Sequence[Opening]) -> list:
        """[(name, item)]: what makes this type's links, in their order."""
        return [(n, c) for n, c in components.items() if self.takes(c)]

    def ends(self, name: str, item) -> LinkEnds:
        """The link ``item`` makes: by default named ``name``, from its field ``a`` to its ``b``."""
        return LinkEnds(name, name, "a", item.a, "b", item.b)

    def check_nodes(self, name: str, item, nodes: Nodes) -> None:
        """Checks of the nodes an item names beyond its link's ends (none by default)."""

    def parameters(self, name: str, item) -> tuple:
        """The numbers of the link's flow law."""
        return ()

    def check(self, name: str, comp) -> None:
        """The checks its class attributes declare, in their order."""
        for field in self.positive:
            if not getattr(comp, field) > 0:
                raise CircuitError([name, field], f"must be > 0, got {getattr(comp, field)}")
        if self.critical_ratio and not 0.0 <= comp.b_critical < 1.0:
            raise CircuitError([name, "b_critical"], f"must be in [0, 1), got {comp.b_critical}")
        self.check_more(name, comp)
        for xf, yf in self.tables:
            _check_table(name, comp, xf, yf)

    def check_more(self, name: str, comp) -> None:
        """Checks of a link type's own (none by default)."""


def _check_table(name: str, comp, xf: str, yf: str) -> None:
    """The table (``xf``, ``yf``) of component ``name``: as many of each, at least 2; x from >= 0
    strictly increasing; y >= 0."""
    x, y = np.asarray(getattr(comp, xf), float), np.asarray(getattr(comp, yf), float)
    if x.size < 2 or x.size != y.size:
        raise CircuitError([name, yf], f"needs as many values as {xf} (at least 2); got {y.size} and {x.size}")
    if np.any(np.diff(x) <= 0) or x[0] < 0:
        raise CircuitError([name, xf], "must start at >= 0 and increase strictly")
    if np.any(y < 0):
        raise CircuitError([name, yf], "must be >= 0")


class PipeLinks(LinkType):
    """Pipes of one ``model`` (eq. 5)."""

    model = ""
    positive = ("length_m", "diameter_m", "loss_coefficient")

    def takes(self, comp) -> bool:
        return isinstance(comp, Pipe) and comp.model == self.model


class DynamicPipeLinks(PipeLinks):
    """Pipes whose flow is a state: (L/A) dq/dt = dp - K q|q| / (2 rho A^2) (eq. 5); and the
    links of the compressible pipes (:mod:`pneumatics.compressible_pipe`), each over its length,
    with its share of the fittings' loss (which may be 0: its K need not be > 0)."""

    key, model = "pipe", "dynamic"

    def takes(self, comp) -> bool:
        return isinstance(comp, PipeSegment) or super().takes(comp)

    def parameters(self, name: str, pipe: Pipe) -> tuple:
        return pipe.length_m, pipe.area_m2, pipe.loss_coefficient

    def check(self, name: str, comp) -> None:
        if isinstance(comp, PipeSegment):             # its pipe was checked when it was cut into links
            return
        super().check(name, comp)


class QuasiSteadyPipeLinks(PipeLinks):
    """Pipes at steady state: eq. (5) without dq/dt."""

    key, model = "quasi_steady_pipe", "quasi_steady"

    def parameters(self, name: str, pipe: Pipe) -> tuple:
        return pipe.area_m2, pipe.loss_coefficient


class OrificeLinks(LinkType):
    """Fixed orifices: ISO 6358 (eqs 6-7) at their conductance C and critical ratio b."""

    key = "orifice"
    positive = ("C_m3_per_sPa",)
    critical_ratio = True

    def takes(self, comp) -> bool:
        return isinstance(comp, Orifice)

    def parameters(self, name: str, orifice: Orifice) -> tuple:
        return orifice.C_m3_per_sPa, orifice.b_critical


class FaultOpeningLinks(LinkType):
    """The faults' openings to the atmosphere (:mod:`pneumatics.assembly.faults`): ISO 6358
    (eqs 6-7), shut (C = 0) while their fault has not happened."""

    key = "fault_opening"

    def sources(self, components: Mapping[str, object], openings: Sequence[Opening]) -> list:
        return [(o.link, o) for o in openings]

    def ends(self, name: str, opening: Opening) -> LinkEnds:
        return LinkEnds(name, f"faults[{opening.fault}]", "component", opening.node, "b", ATMOSPHERE)

    def parameters(self, name: str, opening: Opening) -> tuple:
        return (opening.C_m3_per_sPa if opening.active else 0.0), opening.b_critical


class DifferentialValveLinks(LinkType):
    """Differential pressure valves: a flow table q(|dp|), from the higher pressure to the lower."""

    key = "differential"
    tables = (("dp_Pa", "q_kg_per_s"),)

    def takes(self, comp) -> bool:
        return isinstance(comp, DifferentialPressureValve)

    def parameters(self, name: str, valve: DifferentialPressureValve) -> tuple:
        return valve.dp_Pa, valve.q_kg_per_s


class ValveSupplyLinks(LinkType):
    """The supply sides of the levelling (and safety) valves, supply -> bellow: ISO 6358 (eqs
    6-7) at the conductance C(u) of the lever u (u > 0 opens). The valve's own checks (critical
    ratio, response dynamics) go with this side."""

    key = "valve_supply"
    critical_ratio = True
    tables = (("supply_lever_m", "supply_C_m3_per_sPa"),)

    def takes(self, comp) -> bool:
        return isinstance(comp, LevellingValve)

    def ends(self, name: str, valve: LevellingValve) -> LinkEnds:
        return LinkEnds(f"{name}.supply", name, "supply", valve.supply, "bellow", valve.bellow)

    def check_nodes(self, name: str, valve: LevellingValve, nodes: Nodes) -> None:
        nodes.node(name, "bellow", valve.bellow, chambers_only=True)
        nodes.bellow(name, "bellow", valve.bellow)

    def parameters(self, name: str, valve: LevellingValve) -> tuple:
        return valve.supply_lever_m, valve.supply_C_m3_per_sPa, valve.b_critical

    def check_more(self, name: str, valve: LevellingValve) -> None:
        for field in ("lag_s", "delay_s", "hysteresis_m"):
            value = getattr(valve, field)
            if not (np.isfinite(value) and value >= 0.0):
                raise CircuitError([name, field], f"must be >= 0 (0: none), got {value}")
        stages = valve.delay_stages
        if isinstance(stages, bool) or not isinstance(stages, (int, np.integer)) or stages < 1:
            raise CircuitError([name, "delay_stages"], f"must be an integer >= 1, got {stages!r}")


class ValveExhaustLinks(LinkType):
    """The exhaust sides of the levelling (and safety) valves, bellow -> exhaust: ISO 6358 (eqs
    6-7) at the conductance C(-u) of the lever u (u < 0 opens)."""

    key = "valve_exhaust"
    tables = (("exhaust_lever_m", "exhaust_C_m3_per_sPa"),)

    def takes(self, comp) -> bool:
        return isinstance(comp, LevellingValve)

    def ends(self, name: str, valve: LevellingValve) -> LinkEnds:
        return LinkEnds(f"{name}.exhaust", name, "bellow", valve.bellow, "exhaust", valve.exhaust)

    def parameters(self, name: str, valve: LevellingValve) -> tuple:
        return valve.exhaust_lever_m, valve.exhaust_C_m3_per_sPa, valve.b_critical


class CompressorLinks(LinkType):
    """Compressors: from the intake into the reservoir, the free air delivery while the governor
    runs it (:mod:`pneumatics.air_supply`)."""

    key = "compressor"
    positive = ("free_air_delivery_m3_per_s", "p_cut_in_Pa", "p_cut_out_Pa")

    def takes(self, comp) -> bool:
        return isinstance(comp, Compressor)

    def ends(self, name: str, comp: Compressor) -> LinkEnds:
        return LinkEnds(name, name, "intake", name, "reservoir", comp.reservoir)

    def check_nodes(self, name: str, comp: Compressor, nodes: Nodes) -> None:
        nodes.node(name, "reservoir", comp.reservoir, chambers_only=True)
        if comp.reservoir in nodes.bellow_names:
            raise CircuitError([name, "reservoir"], f"'{comp.reservoir}' is a bellow; a compressor fills a reservoir "
                                                    f"(a finite supply or a tank)")

    def parameters(self, name: str, comp: Compressor) -> tuple:
        return comp.free_air_delivery_m3_per_s, comp.p_cut_in_Pa, comp.p_cut_out_Pa, comp.running_at_start

    def check_more(self, name: str, comp: Compressor) -> None:
        if not comp.p_cut_in_Pa < comp.p_cut_out_Pa:
            raise CircuitError([name, "p_cut_out_Pa"], f"must be above p_cut_in_Pa ({comp.p_cut_in_Pa:g} Pa), "
                                                       f"got {comp.p_cut_out_Pa:g} Pa")
        if comp.T_delivery_K is not None and not comp.T_delivery_K > 0:
            raise CircuitError([name, "T_delivery_K"], f"must be > 0 K (absolute), got {comp.T_delivery_K}")


class AirDemandLinks(LinkType):
    """Air demands: from their node to their exhaust, a steady normal flow that fades out near
    the atmosphere's pressure (:mod:`pneumatics.air_supply`)."""

    key = "air_demand"
    positive = ("dp_off_Pa",)

    def takes(self, comp) -> bool:
        return isinstance(comp, AirDemand)

    def check_more(self, name: str, demand: AirDemand) -> None:
        # 0: a demand switched off (a scheduled demand between its windows) draws nothing
        if not demand.normal_flow_m3_per_s >= 0:
            raise CircuitError([name, "normal_flow_m3_per_s"], f"must be >= 0, got {demand.normal_flow_m3_per_s}")

    def ends(self, name: str, demand: AirDemand) -> LinkEnds:
        return LinkEnds(name, name, "node", demand.node, "exhaust", name)

    def check_nodes(self, name: str, demand: AirDemand, nodes: Nodes) -> None:
        nodes.node(name, "node", demand.node, chambers_only=True)

    def parameters(self, name: str, demand: AirDemand) -> tuple:
        return demand.normal_flow_m3_per_s, demand.dp_off_Pa


#: every link type, in the order of the circuit's links
LINK_TYPES = (DynamicPipeLinks(), QuasiSteadyPipeLinks(), OrificeLinks(), FaultOpeningLinks(), DifferentialValveLinks(),
              ValveSupplyLinks(), ValveExhaustLinks(), CompressorLinks(), AirDemandLinks())

#: the pipe models: one link type each, a compressible pipe made of dynamic links and cells
PIPE_MODELS = (DynamicPipeLinks.model, QuasiSteadyPipeLinks.model, COMPRESSIBLE)
