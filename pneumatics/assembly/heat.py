"""The chambers' heat exchange with the atmosphere (eq. 8): one coefficient k per case (0 is
adiabatic, ``inf`` the exact isothermal limit, T held at the atmosphere's temperature), unless a
bellow or a tank carries its own law (``heat``: :class:`~pneumatics.heat_transfer.ChamberHeat`):
its own constant k, the same in every case, or k from a correlation at its state."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Optional, Tuple

import numpy as np

from ..chamber import Bellow, Tank
from ..errors import CircuitError
from ..heat_transfer import (
    EMISSIVITY,
    HEAT_MODELS,
    PORT_DIAMETER_M,
    RUBBER_CONDUCTIVITY_W_PER_MK,
    RUBBER_THICKNESS_M,
    STEEL_CONDUCTIVITY_W_PER_MK,
    STEEL_THICKNESS_M,
    ChamberHeat,
    tank_surface,
)
from .arrays import column, read_only
from .chambers import ChamberGeometry
from .links import Links
from .nodes import Nodes


@dataclass(frozen=True, eq=False)
class CorrelationGroup:
    """Chambers of one kind (bellows, or tanks) whose k a correlation gives
    (:func:`pneumatics.heat_transfer.wall_conductance_W_per_K`): their chamber rows; the bellows'
    indices (None: tanks); the incidence of the links on them and its magnitude (the air flowing
    in: (|E| @ |w| + E @ w) / 2); a tank's surface, height (its diameter: it lies) and diameter
    (None for bellows: they follow the crushing); the port's area, the wall's resistance t /
    lambda, the outside air speed and emissivity; 1.0 for a tank (outside a horizontal cylinder), 0.0 for a
    bellow (a vertical plate). Columns (rows, 1)."""

    rows: np.ndarray
    bellows: Optional[np.ndarray]
    incidence: np.ndarray
    abs_incidence: np.ndarray
    area_m2: Optional[np.ndarray]
    height_m: Optional[np.ndarray]
    diameter_m: Optional[np.ndarray]
    port_area_m2: np.ndarray
    wall_m2K_per_W: np.ndarray
    air_speed_m_per_s: np.ndarray
    emissivity: np.ndarray
    cylinder: float


@dataclass(frozen=True, eq=False)
class HeatExchange:
    """k of the cases as given [W/K] (a scalar, or one per case); which chambers are held
    isothermal and the finite k of the others (k = inf set to 0, for eq. 8's law): per case when
    every chamber takes its case's k (``per_chamber`` False), else (chambers, cases) (a
    correlation's rows 0 there: their k is computed at the state); whether any chamber is
    isothermal; the chambers a correlation serves (none: an empty tuple)."""

    k_W_per_K: np.ndarray
    isothermal: np.ndarray
    any_isothermal: bool
    k_finite_W_per_K: np.ndarray
    per_chamber: bool = False
    correlations: Tuple[CorrelationGroup, ...] = ()

    def isothermal_of(self, rows) -> np.ndarray:
        """Which of the chambers ``rows`` are held isothermal, (rows, cases); per case, shared by
        every chamber, when no chamber has its own law."""
        return self.isothermal[rows] if self.per_chamber else self.isothermal


def case_k(k_W_per_K) -> np.ndarray:
    """The cases' k checked: >= 0, or inf for isothermal."""
    k = read_only(np.array(k_W_per_K, dtype=float))
    if np.any(k < 0) or np.any(np.isnan(k)):
        raise CircuitError(["k_W_per_K"], f"must be >= 0 (or inf for isothermal), got {k_W_per_K}")
    return k


def compile_heat_exchange(k: np.ndarray, components: Mapping[str, object], nodes: Nodes, chambers: ChamberGeometry,
                          links: Links) -> HeatExchange:
    """The heat exchange of the chambers of ``nodes`` at the cases' k (:func:`case_k`); each
    chamber's own law checked."""
    laws = {n: check_law(n, components[n], chambers.V0_m3[i, 0] if isinstance(components[n], Tank) else None)
            for i, n in enumerate(nodes.chamber_names) if getattr(components[n], "heat", None) is not None}
    if not laws:                                   # every chamber takes its case's k: as it always was
        isothermal = read_only(np.asarray(np.isinf(k)))
        return HeatExchange(k, isothermal, bool(np.any(isothermal)), read_only(np.where(isothermal, 0.0, k)))
    K = np.empty((len(nodes.chamber_names), k.size if k.ndim else 1))
    K[:] = k
    for name, law in laws.items():
        K[nodes.index[name]] = law.k_W_per_K if law.model == "constant" else 0.0
    isothermal = read_only(np.isinf(K))
    groups = tuple(group for group in (_correlations(laws, components, nodes, chambers, links, Bellow),
                                       _correlations(laws, components, nodes, chambers, links, Tank)) if group)
    return HeatExchange(k, isothermal, bool(np.any(isothermal)), read_only(np.where(isothermal, 0.0, K)), True, groups)


def check_law(name: str, chamber, V_m3: Optional[float]) -> ChamberHeat:
    """Chamber ``name``'s own law, its keys consistent with its model (``V_m3``: a tank's volume,
    None for a bellow)."""
    law = chamber.heat
    where = [name, "heat"]
    if not isinstance(chamber, (Bellow, Tank)):
        raise CircuitError(where, "only a bellow or a tank carries its own heat exchange")
    if not isinstance(law, ChamberHeat):
        raise CircuitError(where, f"expected a ChamberHeat, got {type(law).__name__}")
    if law.model not in HEAT_MODELS:
        raise CircuitError([*where, "model"], f"expected one of {', '.join(HEAT_MODELS)}, got {law.model!r}")
    if law.model == "constant":
        if law.k_W_per_K is None:
            raise CircuitError([*where, "k_W_per_K"], "a constant law needs its k (W/K; 0 adiabatic, .inf "
                                                      "isothermal), or model: correlation")
        if not law.k_W_per_K >= 0:
            raise CircuitError([*where, "k_W_per_K"], f"must be >= 0 (or inf for isothermal), got {law.k_W_per_K}")
        given = [key for key in ChamberHeat.CORRELATION_KEYS if getattr(law, key) is not None]
        if given:
            raise CircuitError([*where, given[0]], "a key of the correlation: give model: correlation, or remove it "
                                                   "(a constant law has its k only)")
        return law
    if law.k_W_per_K is not None:
        raise CircuitError([*where, "k_W_per_K"], "the correlation computes k: remove it, or give model: constant")
    for key in ChamberHeat.CORRELATION_KEYS:
        value, zero_allowed = getattr(law, key), key in ("air_speed_m_per_s", "emissivity")
        if value is not None and not (math.isfinite(value) and (value >= 0 if zero_allowed else value > 0)):
            raise CircuitError([*where, key], f"must be finite and {'>= 0' if zero_allowed else '> 0'}, got {value}")
    if law.emissivity is not None and law.emissivity > 1.0:
        raise CircuitError([*where, "emissivity"], f"must be at most 1 (a black surface), got {law.emissivity}")
    if V_m3 is None and law.diameter_m is not None:
        raise CircuitError([*where, "diameter_m"], "a bellow's diameter follows from its effective area: "
                                                   "diameter_m is a tank's")
    diameter = (4.0 * chamber.A0_m2 / math.pi) ** 0.5 if V_m3 is None else tank_surface(V_m3, law.diameter_m)[1]
    port = law.port_diameter_m if law.port_diameter_m is not None else PORT_DIAMETER_M
    if not port < diameter:                        # blamed on the key the user gave
        key = ([*where, "port_diameter_m"] if law.port_diameter_m is not None else [name, "A0_m2"] if V_m3 is None
               else [*where, "diameter_m"] if law.diameter_m is not None else [name, "V_m3"])
        raise CircuitError(key, f"the chamber (diameter {diameter:.4g} m) must be wider than its port (bore "
                                f"{port:g} m{'' if law.port_diameter_m is not None else ', assumed: port_diameter_m'})")
    return law


def _correlations(laws: Mapping[str, ChamberHeat], components, nodes: Nodes, chambers: ChamberGeometry, links: Links,
                  kind) -> Optional[CorrelationGroup]:
    """The chambers of type ``kind`` (Bellow or Tank) a correlation serves, or None."""
    names = [n for n, law in laws.items() if law.model == "correlation" and isinstance(components[n], kind)]
    if not names:
        return None
    rows = np.array([nodes.index[n] for n in names], dtype=int)
    rubber = kind is Bellow

    def given(key: str, default: float) -> list:
        return [default if getattr(laws[n], key) is None else getattr(laws[n], key) for n in names]
    thickness = given("wall_thickness_m", RUBBER_THICKNESS_M if rubber else STEEL_THICKNESS_M)
    conductivity = given("wall_conductivity_W_per_mK", RUBBER_CONDUCTIVITY_W_PER_MK if rubber
                         else STEEL_CONDUCTIVITY_W_PER_MK)
    port = given("port_diameter_m", PORT_DIAMETER_M)
    incidence = read_only(np.array(links.incidence[rows]))
    geometry = (None, None, None)
    if not rubber:
        surfaces = [tank_surface(chambers.V0_m3[i, 0], laws[n].diameter_m) for i, n in zip(rows, names)]
        geometry = (column([s[0] for s in surfaces]), column([s[1] for s in surfaces]), column([s[1] for s in surfaces]))
    return CorrelationGroup(read_only(rows), read_only(np.array([nodes.bellow_names.index(n) for n in names])) if rubber
                            else None, incidence, read_only(np.abs(incidence)), *geometry,
                            column([0.25 * math.pi * d * d for d in port]),
                            column([t / lam for t, lam in zip(thickness, conductivity)]),
                            column(given("air_speed_m_per_s", 0.0)), column(given("emissivity", EMISSIVITY)),
                            0.0 if rubber else 1.0)
