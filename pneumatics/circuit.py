"""Assemble components into one pneumatic circuit: a state vector and its time derivative.

A circuit is described declaratively as a mapping ``name -> component`` (the dataclasses of
:mod:`pneumatics.chamber`, :mod:`pneumatics.boundary`, :mod:`pneumatics.pipe`,
:mod:`pneumatics.orifice`, :mod:`pneumatics.valves`). Chambers (bellows, tanks, finite
reservoirs) are the nodes that hold air; the atmosphere and fixed-pressure supplies are boundary
nodes; pipes, orifices and valves are links that carry a signed mass flow between two nodes.

State vector (one column per independent case when batched; see :class:`StateLayout`):

=================  =========================================================
``m``              air mass in each chamber [kg] (eq. 1)
``T``              temperature of each chamber [K] (eq. 2)
``q``              mass flow in each dynamic pipe, a -> b [kg/s] (eq. 5)
``mass_through``   cumulative mass through each link, a -> b [kg]
``heat_in``        cumulative heat into all chambers from the atmosphere [J] (eq. 8)
``work_in``        cumulative work done on the gas by the bellows, -int p dV [J]
``enthalpy_in``    cumulative enthalpy brought in from boundary nodes [J]
``open_time``      cumulative time each levelling/safety valve side has been open
                   (conductance > 0) [s]: supply sides, then exhaust sides, in the
                   order of :attr:`Circuit.valve_names` (2 per valve; absent without valves)
``valve_signal``   states of the valves' response dynamics [m] (absent unless a valve sets
                   ``hysteresis_m``, ``delay_s`` or ``lag_s``): the play outputs u_p of
                   the valves with a play, then the delay-chain stages of the valves with a
                   delay (valve by valve, input side first), then the lagged lever u_f of
                   the valves with a lag; each group in the order of ``valve_names``
=================  =========================================================

The groups up to ``enthalpy_in`` sit where they always did: the valve groups are appended, so a
circuit without valves has exactly its former layout, and one with default (instantaneous)
valves only gains the open-time accumulators at the end (its other derivatives are unchanged
bit for bit). The mass through each side of a valve is ``mass_through`` of the links
``<valve>.supply`` (supply -> bellow) and ``<valve>.exhaust`` (bellow -> exhaust); see
:meth:`Circuit.valve_air_kg` and :meth:`Circuit.valve_open_time_s`. The valve-signal states are
physical states but lie outside the ``n_dynamic`` prefix (the periodic solver, run on rig
circuits without valves, resets everything after that prefix to 0: valves at rest at z = 0).

Inputs: the crushing z [m] (positive in compression) and its rate of every bellow, in the order
of :attr:`Circuit.bellow_names`; the rate must be the derivative of z (it drives the bellow's
work p dV and the valves' play). Every array may carry a trailing "case" axis so that many
cases (e.g. several k values or frequencies) are integrated as one vectorised system.
"""
from __future__ import annotations

import dataclasses
import functools
import math
import operator
from dataclasses import dataclass
from typing import Mapping, NamedTuple, Optional, Sequence, Tuple

import numpy as np

from .boundary import Atmosphere, Supply
from .chamber import (
    Bellow,
    Tank,
    bellow_force_N,
    bellow_stiffness_N_per_m,
    heat_flow_into_W,
    isothermal_heat_flow_W,
    temperature_rate_K_per_s,
)
from .faults import FAULT_KINDS, VALVE_SIDES, Fault, nozzle_conductance
from .gas import AIR, Gas
from .orifice import Orifice, orifice_flow_kg_per_s
from .pipe import Pipe, pipe_flow_quasi_steady_kg_per_s, pipe_flow_rate_kg_per_s2
from .valves import (
    DifferentialPressureValve,
    LevellingValve,
    SafetyValve,
    differential_valve_flow_kg_per_s,
    lag_rate,
    lever_conductance,
    play_output,
    play_rate,
)

#: YAML ``type`` name -> component class.
COMPONENT_TYPES = {
    "bellow": Bellow,
    "tank": Tank,
    "supply": Supply,
    "pipe": Pipe,
    "orifice": Orifice,
    "levelling_valve": LevellingValve,
    "safety_valve": SafetyValve,
    "differential_valve": DifferentialPressureValve,
}

ATMOSPHERE = "atmosphere"
PIPE_MODELS = ("dynamic", "quasi_steady")


#: fault kind -> (component types it applies to, fields it takes besides kind, component, t_s)
_FAULT_RULES = {
    "burst": ((Bellow, Tank, Supply), ("area_m2", "C_m3_per_sPa", "b_critical")),
    "leak": ((Bellow, Tank, Supply), ("area_m2", "C_m3_per_sPa", "b_critical")),
    "blocked": ((Pipe, Orifice), ()),
    "ruptured": ((Pipe,), ("area_m2", "C_m3_per_sPa", "b_critical")),
    "stuck_closed": ((LevellingValve, DifferentialPressureValve), ()),
    "stuck_open": ((LevellingValve, DifferentialPressureValve), ("side",)),
    "stuck_at": ((LevellingValve,), ("lever_m",)),
    "supply_lost": ((Supply,), ()),
}
_TYPE_WORDS = {Bellow: "bellow", Tank: "tank", Supply: "supply", Pipe: "pipe", Orifice: "orifice",
               LevellingValve: "levelling or safety valve", DifferentialPressureValve: "differential valve"}


def _type_word(comp) -> str:
    return next((w for t, w in _TYPE_WORDS.items() if isinstance(comp, t)), type(comp).__name__)


def _without_dead_band(valve: DifferentialPressureValve) -> DifferentialPressureValve:
    """A differential valve stuck open: its flow table shifted so that it opens at dp = 0, the
    flow it passed at dp_0 + dp now passing at dp (dp_0: the last table point of zero flow)."""
    dp, q = np.asarray(valve.dp_Pa, float), np.asarray(valve.q_kg_per_s, float)
    if q[0] > 0 or not np.any(q > 0):         # no dead band to remove (or a valve that never passes air)
        return valve
    last_shut = int(np.flatnonzero(q > 0)[0]) - 1
    return dataclasses.replace(valve, dp_Pa=tuple(dp[last_shut:] - dp[last_shut]), q_kg_per_s=tuple(q[last_shut:]))


class CircuitError(ValueError):
    """A circuit description that cannot be assembled; ``path`` locates the offending field."""

    def __init__(self, path: Sequence[str], message: str):
        self.path = tuple(str(p) for p in path)
        self.reason = message
        super().__init__(f"{'.'.join(self.path)}: {message}")

    def __reduce__(self):          # picklable: raised in worker processes
        return type(self), (self.path, self.reason)


def _check_area_table(name: str, bellow: Bellow) -> None:
    """A bellow's area table: as many areas as crushings, at least two, crushings increasing,
    areas > 0 and finite."""
    zs, As = bellow.area_table_z_m, bellow.area_table_m2
    if not zs and not As:
        return
    if len(zs) != len(As) or len(zs) < 2:
        raise CircuitError([name, "area_table_m2"], f"expected as many areas as crushings (area_table_z_m), at "
                                                    f"least 2; got {len(As)} areas for {len(zs)} crushings")
    for i in range(len(zs)):
        if not (np.isfinite(zs[i]) and np.isfinite(As[i]) and As[i] > 0):
            raise CircuitError([name, f"area_table_m2[{i}]"], f"expected a finite area > 0 m^2 at a finite "
                                                               f"crushing, got {As[i]} at {zs[i]} m")
        if i and not zs[i] > zs[i - 1]:
            raise CircuitError([name, f"area_table_z_m[{i}]"], f"crushings must increase, got {zs[i]} after "
                                                               f"{zs[i - 1]} m")


class CircuitDiverged(RuntimeError):
    """Integration produced a non-physical state; carries where and when, for a diagnosis."""

    def __init__(self, t_s: float, component: str, state: Mapping[str, float], reason: str):
        self.t_s, self.component, self.state, self.reason = t_s, component, dict(state), reason
        detail = ", ".join(f"{k}={v:.6g}" for k, v in self.state.items())
        super().__init__(f"pneumatic circuit diverged at t = {t_s:.6g} s in '{component}': {reason} ({detail})")

    def __reduce__(self):          # picklable: raised in worker processes
        return type(self), (self.t_s, self.component, self.state, self.reason)


@dataclass(frozen=True)
class StateLayout:
    """Where each group of states sits in the state vector (order: see the module docstring)."""

    n_chambers: int
    n_pipes: int
    n_links: int
    n_valves: int = 0
    n_valve_states: int = 0

    @property
    def m(self) -> slice:
        return slice(0, self.n_chambers)

    @property
    def T(self) -> slice:
        return slice(self.n_chambers, 2 * self.n_chambers)

    @property
    def q(self) -> slice:
        start = 2 * self.n_chambers
        return slice(start, start + self.n_pipes)

    @property
    def mass_through(self) -> slice:
        start = 2 * self.n_chambers + self.n_pipes
        return slice(start, start + self.n_links)

    @property
    def heat_in(self) -> int:
        return 2 * self.n_chambers + self.n_pipes + self.n_links

    @property
    def work_in(self) -> int:
        return self.heat_in + 1

    @property
    def enthalpy_in(self) -> int:
        return self.heat_in + 2

    @property
    def open_time(self) -> slice:
        """Open time of each valve side: supply sides of all valves, then exhaust sides."""
        start = self.heat_in + 3
        return slice(start, start + 2 * self.n_valves)

    @property
    def valve_signal(self) -> slice:
        start = self.heat_in + 3 + 2 * self.n_valves
        return slice(start, start + self.n_valve_states)

    @property
    def size(self) -> int:
        return self.heat_in + 3 + 2 * self.n_valves + self.n_valve_states

    @property
    def n_dynamic(self) -> int:
        """The prefix of states that describe the physical condition (m, T, q); the accumulators
        follow, then the valve-signal states (physical too, but outside this prefix so that the
        former layout is kept; see the module docstring)."""
        return 2 * self.n_chambers + self.n_pipes


class ValveSides(NamedTuple):
    """A per-valve quantity for each side: arrays (valves[, cases]) in the order of
    :attr:`Circuit.valve_names`."""

    supply: np.ndarray
    exhaust: np.ndarray


class Evaluation(NamedTuple):
    """:meth:`Circuit.evaluate`: the circuit at one state and crushing, each (rows, cases):
    chamber masses, temperatures, volumes, pressures; node pressures, temperatures, densities
    (chambers, then boundary nodes); link flows; the valves' lever chain (or None); the valves'
    conductances (supply sides, then exhaust)."""

    m: np.ndarray
    T: np.ndarray
    V: np.ndarray
    p: np.ndarray
    p_n: np.ndarray
    T_n: np.ndarray
    rho_n: np.ndarray
    w: np.ndarray
    chain: Optional[tuple]
    C_valve: np.ndarray


@dataclass(frozen=True)
class CircuitOutputs:
    """Everything observable at one instant (arrays: chambers or links first, cases last)."""

    p_Pa: np.ndarray
    T_K: np.ndarray
    m_kg: np.ndarray
    V_m3: np.ndarray
    link_flow_kg_per_s: np.ndarray
    bellow_force_N: np.ndarray


def _table_groups(tables):
    """[(rows, x, y)]: the indices of the components that share each distinct (x, y) table, so that
    one interpolation serves them all (rows: a slice when evenly spaced, see :func:`_rows`)."""
    groups = {}
    for i, (x, y) in enumerate(tables):
        groups.setdefault((tuple(x), tuple(y)), []).append(i)
    return [(_rows(rows), np.array(x, float), np.array(y, float)) for (x, y), rows in groups.items()]


def _column(values) -> np.ndarray:
    return np.asarray(values, dtype=float).reshape(-1, 1)


def _rows(indices):
    """Row indices as a slice when they are evenly spaced (a cheap view), else as an index array."""
    idx = np.asarray(indices, dtype=int)
    if idx.size == 0:
        return slice(0, 0)
    step = int(idx[1] - idx[0]) if idx.size > 1 else 1
    if step > 0 and np.array_equal(idx, idx[0] + step * np.arange(idx.size)):
        return slice(int(idx[0]), int(idx[-1]) + 1, step)
    return idx


class Circuit:
    """A compiled pneumatic circuit.

    ``k_W_per_K`` is the heat-transfer coefficient of every chamber (eq. 8): 0 is adiabatic,
    ``inf`` the exact isothermal limit (T held at the atmosphere's temperature, the heat flow
    being whatever that takes). An array of k values, one per case, batches cases.

    ``faults`` (:mod:`pneumatics.faults`) are compiled from the start, so that the state vector
    is the same whether they have happened or not; those in ``active_faults`` (their indices)
    have happened. :meth:`with_active_faults` gives the same circuit with other faults active.
    Each opening a fault makes to the atmosphere is a link of its own (``<component>.<kind>``,
    a ruptured pipe's ``<pipe>.ruptured@<end node>``), shut while the fault is inactive.
    """

    def __init__(self, components: Mapping[str, object], *, gas: Gas = AIR,
                 atmosphere: Atmosphere = Atmosphere(), k_W_per_K=0.0, faults: Sequence[Fault] = (),
                 active_faults: Sequence[int] = ()):
        self.components = dict(components)
        self._given_components = dict(components)
        self.faults = tuple(faults)
        self.active_faults = frozenset(int(i) for i in active_faults)
        self.gas = gas
        self.atmosphere = atmosphere
        self.k_W_per_K = np.asarray(k_W_per_K, dtype=float)
        if np.any(self.k_W_per_K < 0) or np.any(np.isnan(self.k_W_per_K)):
            raise CircuitError(["k_W_per_K"], f"must be >= 0 (or inf for isothermal), got {k_W_per_K}")
        self._isothermal = np.isinf(self.k_W_per_K)
        self._any_isothermal = bool(np.any(self._isothermal))
        self._k_finite = np.where(self._isothermal, 0.0, self.k_W_per_K)
        self._boundary_columns = {}
        self._outflow_signs = {}  # mass_from's link signs by node (cached)
        self._classify()
        self._check_faults()
        self._compile_links()
        self._compile_faults()

    # ----------------------------------------------------------------------------- assembly
    def _classify(self) -> None:
        if ATMOSPHERE in self.components:
            raise CircuitError([ATMOSPHERE], "the name 'atmosphere' is reserved for the surroundings")
        self.chamber_names = []
        boundary = [(ATMOSPHERE, self.atmosphere.p_Pa, self.atmosphere.T_K)]
        for name, comp in self.components.items():
            if not isinstance(comp, tuple(COMPONENT_TYPES.values())):
                raise CircuitError([name], f"unknown component {type(comp).__name__}; "
                                           f"expected one of {sorted(COMPONENT_TYPES)}")
            if isinstance(comp, (Bellow, Tank)) or (isinstance(comp, Supply) and not comp.is_fixed):
                self.chamber_names.append(name)
            elif isinstance(comp, Supply):
                boundary.append((name, comp.p_Pa, comp.T_K or self.atmosphere.T_K))
        self.bellow_names = [n for n in self.chamber_names if isinstance(self.components[n], Bellow)]
        self.boundary_names = [b[0] for b in boundary]
        self.node_names = self.chamber_names + self.boundary_names
        self._node_index = {n: i for i, n in enumerate(self.node_names)}
        self._p_boundary = _column([b[1] for b in boundary])
        self._T_boundary = _column([b[2] for b in boundary])

        nc, nb = len(self.chamber_names), len(self.bellow_names)
        V0 = []
        for n in self.chamber_names:
            c = self.components[n]
            V0.append(c.V0_m3 if isinstance(c, Bellow) else c.V_m3)
            if V0[-1] <= 0:
                raise CircuitError([n, "V0_m3" if isinstance(c, Bellow) else "V_m3"],
                                   f"volume must be > 0, got {V0[-1]}")
        self._V0 = _column(V0)
        # chamber <- bellow selection, scaled by dV/dz: V = V0 - Ez @ z
        self._Ez = np.zeros((nc, nb))
        for j, n in enumerate(self.bellow_names):
            self._Ez[self.chamber_names.index(n), j] = self.components[n].dV_dz_m2
        self._A0 = _column([self.components[n].A0_m2 for n in self.bellow_names])
        self._dAdz = _column([self.components[n].dA_dz_m for n in self.bellow_names])
        for n in self.bellow_names:
            _check_area_table(n, self.components[n])
        #: bellows with a tabulated effective area (their laws are evaluated bellow by bellow)
        self._area_tables = any(self.components[n].area_table_z_m for n in self.bellow_names)
        self._bellow_chamber = np.array([self.chamber_names.index(n) for n in self.bellow_names], dtype=int)
        # every bellow at once: a Bellow whose fields are (bellows, 1) columns, for the vectorised laws
        self._bellow_columns = Bellow(**{f: _column([getattr(self.components[n], f) for n in self.bellow_names])
                                         for f in ("V0_m3", "dV_dz_m2", "A0_m2", "dA_dz_m")})

    def _node(self, link: str, field: str, name: str, chambers_only: bool = False) -> int:
        if name not in self._node_index:
            known = ", ".join(self.node_names)
            raise CircuitError([link, field], f"refers to '{name}', which is not in the circuit (known nodes: {known})")
        if chambers_only and name not in self.chamber_names:
            raise CircuitError([link, field], f"'{name}' must be a chamber (bellow, tank or finite supply)")
        return self._node_index[name]

    def _bellow_index(self, link: str, field: str, name: str) -> int:
        if name not in self.bellow_names:
            raise CircuitError([link, field], f"'{name}' is not a bellow of the circuit (bellows: {self.bellow_names})")
        return self.bellow_names.index(name)

    def _compile_links(self) -> None:
        comps = self.components
        pipes = [n for n, c in comps.items() if isinstance(c, Pipe) and c.model == "dynamic"]
        qs_pipes = [n for n, c in comps.items() if isinstance(c, Pipe) and c.model == "quasi_steady"]
        for n, c in comps.items():
            if isinstance(c, Pipe) and c.model not in PIPE_MODELS:
                raise CircuitError([n, "model"], f"expected one of {PIPE_MODELS}, got '{c.model}'")
        orifices = [n for n, c in comps.items() if isinstance(c, Orifice)]
        valves = [n for n, c in comps.items() if isinstance(c, LevellingValve)]
        dpvs = [n for n, c in comps.items() if isinstance(c, DifferentialPressureValve)]

        openings = self._fault_openings()
        ends, self.link_names = [], []

        def add(link_name, comp_name, a_field, a, b_field, b):
            ia, ib = self._node(comp_name, a_field, a), self._node(comp_name, b_field, b)
            if ia == ib:
                raise CircuitError([comp_name, b_field], f"both ends are '{a}'")
            if ia >= len(self.chamber_names) and ib >= len(self.chamber_names):
                raise CircuitError([comp_name], f"connects two boundary nodes ('{a}', '{b}')")
            ends.append((ia, ib))
            self.link_names.append(link_name)

        for n in pipes + qs_pipes + orifices:
            add(n, n, "a", comps[n].a, "b", comps[n].b)
        for link, i, node, _, _ in openings:
            add(link, f"faults[{i}]", "component", node, "b", ATMOSPHERE)
        for n in dpvs:
            add(n, n, "a", comps[n].a, "b", comps[n].b)
        for n in valves:
            v = comps[n]
            self._node(n, "bellow", v.bellow, chambers_only=True)
            self._bellow_index(n, "bellow", v.bellow)
            add(f"{n}.supply", n, "supply", v.supply, "bellow", v.bellow)
        for n in valves:
            v = comps[n]
            add(f"{n}.exhaust", n, "bellow", v.bellow, "exhaust", v.exhaust)
        for n, c in comps.items():
            if isinstance(c, (Pipe, Orifice, DifferentialPressureValve, LevellingValve)):
                self._check_link_values(n, c)

        self._a = np.array([e[0] for e in ends], dtype=int)
        self._b = np.array([e[1] for e in ends], dtype=int)
        nc, nl = len(self.chamber_names), len(ends)
        n_valve_states = self._compile_valve_dynamics([comps[n] for n in valves])
        self.layout = StateLayout(nc, len(pipes), nl, len(valves), n_valve_states)
        self.valve_names = valves
        self.pipe_names = pipes
        self._incidence = np.zeros((nc, nl))
        self._boundary_sign = np.zeros(nl)
        for j, (ia, ib) in enumerate(ends):
            if ia < nc:
                self._incidence[ia, j] -= 1.0
            else:
                self._boundary_sign[j] = 1.0
            if ib < nc:
                self._incidence[ib, j] += 1.0
            else:
                self._boundary_sign[j] = -1.0

        n_pipe, n_qs, n_dpv, n_v = len(pipes), len(qs_pipes), len(dpvs), len(valves)
        n_or = len(orifices) + len(openings)         # fixed orifices, then the faults' openings
        self._sl_pipe = slice(0, n_pipe)
        self._sl_qs = slice(n_pipe, n_pipe + n_qs)
        self._sl_or = slice(n_pipe + n_qs, n_pipe + n_qs + n_or)
        self._sl_dpv = slice(self._sl_or.stop, self._sl_or.stop + n_dpv)
        self._sl_valve = slice(self._sl_dpv.stop, nl)  # supply sides then exhaust sides
        #: the links of the faults' openings to the atmosphere (what :meth:`air_lost_kg` counts)
        self.fault_links = slice(self._sl_or.start + len(orifices), self._sl_or.stop)
        # links whose flow is an ISO 6358 orifice law: fixed orifices, fault openings, then valve sides
        self._orifice_links = np.r_[np.arange(self._sl_or.start, self._sl_or.stop),
                                    np.arange(self._sl_valve.start, self._sl_valve.stop)].astype(int)
        # node rows of the links' ends, as slices where evenly spaced (views instead of copies)
        self._pipe_a, self._pipe_b = _rows(self._a[self._sl_pipe]), _rows(self._b[self._sl_pipe])
        self._or_rows = _rows(self._orifice_links)
        self._or_a, self._or_b = _rows(self._a[self._orifice_links]), _rows(self._b[self._orifice_links])
        lay = self.layout
        self._s_m, self._s_T, self._s_q, self._s_through = lay.m, lay.T, lay.q, lay.mass_through
        self._s_open, self._s_valve = lay.open_time, lay.valve_signal
        self._pipe_L = _column([comps[n].length_m for n in pipes])
        self._pipe_A = _column([comps[n].area_m2 for n in pipes])
        self._pipe_K = _column([comps[n].loss_coefficient for n in pipes])
        self._qs_A = _column([comps[n].area_m2 for n in qs_pipes])
        self._qs_K = _column([comps[n].loss_coefficient for n in qs_pipes])
        self._or_C = _column([comps[n].C_m3_per_sPa for n in orifices] +
                             [C if i in self.active_faults else 0.0 for _, i, _, C, _ in openings])
        self._n_orifices = n_or
        self._dpv = [comps[n] for n in dpvs]
        self._valves = [comps[n] for n in valves]
        self._b_crit = _column([comps[n].b_critical for n in orifices] + [b for *_, b in openings] +
                               [comps[n].b_critical for n in valves] * 2)
        self._supply_tables = _table_groups([(v.supply_lever_m, v.supply_C_m3_per_sPa) for v in self._valves])
        self._exhaust_tables = _table_groups([(v.exhaust_lever_m, v.exhaust_C_m3_per_sPa) for v in self._valves])
        # per distinct table: (link rows, their a-end and b-end node rows, table)
        self._dpv_tables = [(_rows(links), _rows(self._a[links]), _rows(self._b[links]), xp, fp)
                            for links, xp, fp in ((self._sl_dpv.start + np.arange(n_dpv)[rows], xp, fp) for rows, xp, fp
                                                  in _table_groups([(v.dp_Pa, v.q_kg_per_s) for v in self._dpv]))]
        self._lever = np.zeros((n_v, len(self.bellow_names)))
        for i, n in enumerate(valves):
            sensed = comps[n].sensed_bellows
            for s in sensed:
                self._lever[i, self._bellow_index(n, "sensed", s)] += comps[n].lever_gain / len(sensed)
        self._lever_play = self._lever[self._play_rows]

    # ----------------------------------------------------------------------------- faults
    def _check_faults(self) -> None:
        """Every fault names a component of the right type, with the fields its kind needs (and
        no other), each in range; an active stuck-open differential valve's table loses its dead
        band here (:mod:`pneumatics.faults`)."""
        chambers = set(self.chamber_names)
        for i, f in enumerate(self.faults):
            where = f"faults[{i}]"
            if f.kind not in FAULT_KINDS:
                raise CircuitError([where, "kind"], f"unknown fault kind {f.kind!r} (expected one of {', '.join(FAULT_KINDS)})")
            comp = self.components.get(f.component)
            if comp is None:
                known = ", ".join(self.components)
                raise CircuitError([where, "component"], f"{f.component!r} is not a component of the circuit "
                                                         f"(components: {known})")
            allowed, needs = _FAULT_RULES[f.kind]
            if not (isinstance(comp, allowed) and (f.kind not in ("burst", "leak") or f.component in chambers)):
                what = "a chamber (bellow, tank or finite supply)" if f.kind in ("burst", "leak") else \
                    " or ".join(_TYPE_WORDS[t] for t in allowed)
                raise CircuitError([where, "component"], f"a {f.kind} fault needs {what}; {f.component!r} is a "
                                                         f"{_type_word(comp)}")
            if not (math.isfinite(f.t_s) and f.t_s >= 0.0):
                raise CircuitError([where, "t_s"], f"must be a finite time >= 0 s, got {f.t_s}")
            if isinstance(comp, DifferentialPressureValve):
                needs = ()                               # a differential valve has no sides or lever
            for field in ("area_m2", "C_m3_per_sPa", "b_critical", "side", "lever_m"):
                value = getattr(f, field)
                if value is not None and field not in needs:
                    raise CircuitError([where, field], f"is not used by a {f.kind} fault of a {_type_word(comp)}")
            self._check_fault_values(f, where, comp)
            if f.kind == "stuck_open" and isinstance(comp, DifferentialPressureValve) and i in self.active_faults:
                self.components[f.component] = _without_dead_band(comp)

    @staticmethod
    def _check_fault_values(f: Fault, where: str, comp) -> None:
        for field in ("area_m2", "C_m3_per_sPa"):
            value = getattr(f, field)
            if value is not None and not (math.isfinite(value) and value > 0.0):
                raise CircuitError([where, field], f"must be a finite number > 0, got {value}")
        if f.kind in ("burst", "leak") and (f.area_m2 is None) == (f.C_m3_per_sPa is None):
            raise CircuitError([where, "area_m2"], "give the opening's effective area (area_m2) or its sonic "
                                                   "conductance (C_m3_per_sPa), one of them")
        if f.area_m2 is not None and f.C_m3_per_sPa is not None:
            raise CircuitError([where, "C_m3_per_sPa"], "give area_m2 or C_m3_per_sPa, not both")
        if f.b_critical is not None:
            if f.C_m3_per_sPa is None:
                raise CircuitError([where, "b_critical"], "goes with C_m3_per_sPa (an area is an ideal nozzle, b = 0.528)")
            if not 0.0 <= f.b_critical < 1.0:
                raise CircuitError([where, "b_critical"], f"must be in [0, 1), got {f.b_critical}")
        if f.kind == "stuck_open" and isinstance(comp, LevellingValve) and f.side not in VALVE_SIDES:
            raise CircuitError([where, "side"], f"which side is stuck open: expected one of {', '.join(VALVE_SIDES)}, "
                                                f"got {f.side!r}")
        if f.kind == "stuck_at" and not (f.lever_m is not None and math.isfinite(f.lever_m)):
            raise CircuitError([where, "lever_m"], f"the lever displacement the valve is stuck at [m] (+ opens the "
                                                   f"supply side), a finite number; got {f.lever_m}")

    def _fault_openings(self):
        """[(link name, fault index, node, C, b)]: the openings to the atmosphere the faults make
        (a burst or leak at its chamber; a ruptured pipe at each end that is a chamber)."""
        out = []
        for i, f in enumerate(self.faults):
            if f.kind in ("burst", "leak"):
                out.append((f"{f.component}.{f.kind}", i, f.component, *self._opening(f, None)))
            elif f.kind == "ruptured":
                pipe = self.components[f.component]
                for end in dict.fromkeys((pipe.a, pipe.b)):
                    if end in self.chamber_names:
                        out.append((f"{f.component}.ruptured@{end}", i, end, *self._opening(f, pipe.area_m2)))
        names = [o[0] for o in out]             # a second opening of the same name: the fault's index added
        return [(name if names.count(name) == 1 else f"{name}[{i}]", i, *rest) for name, i, *rest in out]

    def _opening(self, f: Fault, bore_m2: Optional[float]) -> Tuple[float, float]:
        """(C, b) of a fault's opening: its conductance, its area's ideal nozzle, or the bore's."""
        if f.C_m3_per_sPa is not None:
            return f.C_m3_per_sPa, (0.5 if f.b_critical is None else f.b_critical)
        return nozzle_conductance(f.area_m2 if f.area_m2 is not None else bore_m2, self.gas)

    def _compile_faults(self) -> None:
        """What the active faults change besides their openings: links that carry nothing
        (blocked, ruptured, a shut differential valve, every link of a lost supply), the pipe
        states that stop with them, and the levers of stuck valves."""
        blocked, stuck = [], {}
        openings = set(range(self.fault_links.start, self.fault_links.stop))
        for i in sorted(self.active_faults, key=lambda i: (self.faults[i].t_s, i)):   # the latest fault wins
            f = self.faults[i]
            if f.kind in ("blocked", "ruptured") or (f.kind == "stuck_closed" and f.component in self.link_names):
                blocked.append(self.link_names.index(f.component))
            elif f.kind == "supply_lost":                  # every link but a fault's own opening
                node = self._node_index[f.component]
                blocked += [j for j in range(len(self.link_names))
                            if node in (self._a[j], self._b[j]) and j not in openings]
            elif isinstance(self.components[f.component], LevellingValve):   # stuck closed, open or at
                valve = self.components[f.component]
                if f.kind == "stuck_at":
                    lever = f.lever_m
                elif f.kind == "stuck_closed":
                    lever = 0.0                            # inside the dead band: both sides shut
                else:                                      # the side's table end: fully open
                    lever = max(valve.supply_lever_m) if f.side == "supply" else -max(valve.exhaust_lever_m)
                stuck[self.valve_names.index(f.component)] = lever
        blocked = sorted(set(blocked))
        self._blocked = np.array(blocked, dtype=int) if blocked else None
        pipes = [j for j in blocked if j < len(self.pipe_names)]
        self._blocked_pipes = np.array(pipes, dtype=int) if pipes else None
        self._stuck_valves = np.array(list(stuck), dtype=int) if stuck else None
        self._stuck_lever = _column(list(stuck.values()))

    def with_active_faults(self, active: Sequence[int]) -> "Circuit":
        """The same circuit (same components, faults and state layout) with the faults of
        indices ``active`` having happened."""
        return Circuit(self._given_components, gas=self.gas, atmosphere=self.atmosphere, k_W_per_K=self.k_W_per_K,
                       faults=self.faults, active_faults=active)

    def _compile_valve_dynamics(self, valves) -> int:
        """Index the valve-signal states (see the module docstring); returns their number.

        Play states first, then the delay stages, then the lag states; each group gathers the
        valves that have that element, so that one array operation serves them all (rows are
        slices when they are evenly spaced, as when every valve comes from one template)."""
        play = [i for i, v in enumerate(valves) if v.hysteresis_m > 0.0]
        delay = [i for i, v in enumerate(valves) if v.delay_s > 0.0]
        lag = [i for i, v in enumerate(valves) if v.lag_s > 0.0]
        self._valve_dynamics = bool(play or delay or lag)
        self._n_play, self._n_delay, self._n_lag = len(play), len(delay), len(lag)
        self._play_rows, self._delay_rows, self._lag_rows = (_rows(r) for r in (play, delay, lag))
        self._play_half = _column([0.5 * valves[i].hysteresis_m for i in play])
        stages = [valves[i].delay_stages for i in delay]
        self._delay_stage_valve = np.repeat(np.array(delay, dtype=int), stages)   # owner of each stage
        starts = np.cumsum([0] + stages)
        self._delay_first, self._delay_last = _rows(starts[:-1]), _rows(starts[1:] - 1)
        self._delay_tau = _column([valves[i].delay_s / valves[i].delay_stages for i in self._delay_stage_valve])
        self._lag_tau = _column([valves[i].lag_s for i in lag])
        self._sl_play = slice(0, len(play))
        self._sl_delay = slice(len(play), len(play) + int(starts[-1]))
        self._sl_lag = slice(self._sl_delay.stop, self._sl_delay.stop + len(lag))
        return self._sl_lag.stop

    @staticmethod
    def _check_link_values(name: str, comp) -> None:
        positive = {"length_m", "diameter_m", "loss_coefficient"} if isinstance(comp, Pipe) else set()
        if isinstance(comp, Orifice):
            positive = {"C_m3_per_sPa"}
        for field in positive:
            if not getattr(comp, field) > 0:
                raise CircuitError([name, field], f"must be > 0, got {getattr(comp, field)}")
        if isinstance(comp, (Orifice, LevellingValve)) and not 0.0 <= comp.b_critical < 1.0:
            raise CircuitError([name, "b_critical"], f"must be in [0, 1), got {comp.b_critical}")
        if isinstance(comp, LevellingValve):
            for field in ("lag_s", "delay_s", "hysteresis_m"):
                value = getattr(comp, field)
                if not (np.isfinite(value) and value >= 0.0):
                    raise CircuitError([name, field], f"must be >= 0 (0: none), got {value}")
            stages = comp.delay_stages
            if isinstance(stages, bool) or not isinstance(stages, (int, np.integer)) or stages < 1:
                raise CircuitError([name, "delay_stages"], f"must be an integer >= 1, got {stages!r}")
        tables = []
        if isinstance(comp, LevellingValve):
            tables = [("supply_lever_m", "supply_C_m3_per_sPa"), ("exhaust_lever_m", "exhaust_C_m3_per_sPa")]
        elif isinstance(comp, DifferentialPressureValve):
            tables = [("dp_Pa", "q_kg_per_s")]
        for xf, yf in tables:
            x, y = np.asarray(getattr(comp, xf), float), np.asarray(getattr(comp, yf), float)
            if x.size < 2 or x.size != y.size:
                raise CircuitError([name, yf], f"needs as many values as {xf} (at least 2); got {y.size} and {x.size}")
            if np.any(np.diff(x) <= 0) or x[0] < 0:
                raise CircuitError([name, xf], "must start at >= 0 and increase strictly")
            if np.any(y < 0):
                raise CircuitError([name, yf], "must be >= 0")

    # ----------------------------------------------------------------------------- state
    def initial_state(self, p0_Pa: Optional[Mapping[str, float]] = None, n_cases: Optional[int] = None) -> np.ndarray:
        """State at rest with every bellow at z = 0: each chamber at its initial pressure, no flow.

        ``p0_Pa`` overrides chamber initial pressures by name (e.g. bellow pressures that carry
        the static load). Temperatures start at the component's ``T0_K`` or the atmosphere's.
        ``n_cases`` returns a (size, n_cases) array (default: one column per k value, or 1-D).
        """
        p0_Pa = dict(p0_Pa or {})
        unknown = set(p0_Pa) - set(self.chamber_names)
        if unknown:
            raise CircuitError([sorted(unknown)[0]], f"initial pressure given for a name that is not a chamber "
                                                     f"(chambers: {self.chamber_names})")
        lay = self.layout
        x = np.zeros(lay.size)
        for i, n in enumerate(self.chamber_names):
            c = self.components[n]
            p = p0_Pa.get(n, c.p_Pa if isinstance(c, Supply) else c.p0_Pa)
            if p is None:
                raise CircuitError([n, "p0_Pa"], "initial pressure is not set")
            if not p > 0:
                raise CircuitError([n, "p0_Pa"], f"must be > 0 (absolute pressure), got {p}")
            T = getattr(c, "T0_K", None) or getattr(c, "T_K", None) or self.atmosphere.T_K
            if np.any(self._isothermal) and T != self.atmosphere.T_K:
                raise CircuitError([n, "T0_K"], "an isothermal (k = inf) chamber must start at the atmosphere's temperature")
            x[lay.T][i] = T
            x[lay.m][i] = self.gas.mass_kg(p, T, self._V0[i, 0])
        if n_cases is None and self.k_W_per_K.ndim:
            n_cases = self.k_W_per_K.size
        return x if n_cases is None else np.repeat(x[:, None], n_cases, axis=1)

    # ----------------------------------------------------------------------------- physics
    def _boundary(self, n_cases: int):
        """Boundary-node pressures, temperatures and orifice conductances repeated over ``n_cases`` (cached)."""
        cols = self._boundary_columns.get(n_cases)
        if cols is None:
            cols = self._boundary_columns[n_cases] = tuple(
                np.repeat(v, n_cases, axis=1) for v in (self._p_boundary, self._T_boundary, self._or_C))
        return cols

    def _valve_chain(self, x2: np.ndarray, z2: np.ndarray):
        """Lever signals (valves x cases) along the chain u -> play -> delay -> lag: (u, u_p, u_d, u_f).
        Without valve dynamics all four are the same array u = lever @ z."""
        u = self._lever @ z2
        if not self._valve_dynamics:
            return u, u, u, u
        s = x2[self._s_valve]
        u_p = u
        if self._n_play:
            u_p = u.copy()
            u_p[self._play_rows] = play_output(s[self._sl_play], u[self._play_rows], self._play_half)
        u_d = u_p
        if self._n_delay:
            u_d = u_p.copy()
            u_d[self._delay_rows] = s[self._sl_delay][self._delay_last]
        u_f = u_d
        if self._n_lag:
            u_f = u_d.copy()
            u_f[self._lag_rows] = s[self._sl_lag]
        return u, u_p, u_d, u_f

    def _valve_signal_rates(self, x2: np.ndarray, chain, zdot2: np.ndarray) -> np.ndarray:
        """d/dt of the valve-signal states: play (input rate = lever @ crushing rate), the delay
        stages (each a lag driven by the stage before it, the first by u_p), the lags."""
        u, u_p, u_d, _ = chain
        s = x2[self._s_valve]
        rate = np.empty_like(s)
        if self._n_play:
            rows = self._play_rows
            rate[self._sl_play] = play_rate(u[rows] - s[self._sl_play], self._play_half, self._lever_play @ zdot2)
        if self._n_delay:
            stages = s[self._sl_delay]
            driving = np.empty_like(stages)
            driving[1:] = stages[:-1]
            driving[self._delay_first] = u_p[self._delay_rows]
            rate[self._sl_delay] = lag_rate(driving, stages, self._delay_tau)
        if self._n_lag:
            rate[self._sl_lag] = lag_rate(u_d[self._lag_rows], s[self._sl_lag], self._lag_tau)
        return rate

    def _evaluate(self, x2: np.ndarray, z2: np.ndarray):
        """Pressures, volumes and link flows for a 2-D state (states x cases) and crushing (bellows
        x cases); also the valves' lever chain and their conductances (supply sides, then exhaust)."""
        gas = self.gas
        m, T = x2[self._s_m], x2[self._s_T]
        V = self._V0 - self._Ez @ z2
        p = m * gas.R_J_per_kgK * T / V
        n_cases = x2.shape[1]
        p_bnd, T_bnd, C_or = self._boundary(n_cases)
        p_n, T_n = np.concatenate([p, p_bnd]), np.concatenate([T, T_bnd])
        rho_n = p_n / (gas.R_J_per_kgK * T_n)
        a, b = self._a, self._b
        w = np.empty((len(a), n_cases))
        w[self._sl_pipe] = x2[self._s_q]
        qs = self._sl_qs
        if qs.stop > qs.start:
            rho = 0.5 * (rho_n[a[qs]] + rho_n[b[qs]])
            w[qs] = pipe_flow_quasi_steady_kg_per_s(p_n[a[qs]], p_n[b[qs]], rho, self._qs_A, self._qs_K)
        for links, ia, ib, xp, fp in self._dpv_tables:
            w[links] = differential_valve_flow_kg_per_s(p_n[ia], p_n[ib], xp, fp)
        chain = None
        C = np.empty((self._b_crit.shape[0], n_cases))     # fixed orifices, then valve supply and exhaust sides
        C[:self._n_orifices] = C_or
        if self._valves:
            if self._valve_dynamics:
                chain = self._valve_chain(x2, z2)
                lever = chain[3]
            else:
                lever = self._lever @ z2
            nv, start = len(self._valves), self._n_orifices
            if self._stuck_valves is not None:             # a stuck valve acts on its stuck lever
                lever = lever.copy()
                lever[self._stuck_valves] = self._stuck_lever
            for tables, sign, side in ((self._supply_tables, 1.0, C[start:start + nv]),
                                       (self._exhaust_tables, -1.0, C[start + nv:])):
                for rows, xp, fp in tables:
                    side[rows] = lever_conductance(sign * lever[rows], xp, fp)
        if C.size:
            ia, ib = self._or_a, self._or_b
            w[self._or_rows] = orifice_flow_kg_per_s(C, self._b_crit, p_n[ia], T_n[ia], p_n[ib], T_n[ib], gas)
        if self._blocked is not None:                      # faults: links that carry nothing
            w[self._blocked] = 0.0
        return m, T, V, p, p_n, T_n, rho_n, w, chain, C[self._n_orifices:]

    def _per_bellow(self, values, x2: np.ndarray) -> np.ndarray:
        """A bellow input as (bellows, cases); a circuit without bellows takes an empty array."""
        nb = len(self.bellow_names)
        return np.reshape(values, (nb, -1)) if nb else np.zeros((0, x2.shape[1]))

    def derivatives(self, x, z_m, zdot_m_per_s) -> np.ndarray:
        """d(state)/dt for state ``x`` (size,) or (size, cases) and bellow crushing and rate."""
        x2, z2, zdot2 = self._inputs(x, z_m, zdot_m_per_s)
        dx, terms = self._rates_at_crushing(x2, z2)
        self._write_crushing_rate_terms(dx, x2, terms, zdot2)
        return dx.reshape(x.shape)

    def derivatives_and_held(self, x, z_m, zdot_m_per_s, evaluated: "Evaluation | None" = None
                             ) -> tuple[np.ndarray, np.ndarray]:
        """(d(state)/dt, d(state)/dt at zero crushing rate): the latter is ``derivatives(x, z_m, 0)``
        bit for bit, from the same evaluation of the flows (they depend on the crushing only, not
        on its rate); only the rows that the rate enters (temperatures through p dV/dt, heat and
        work accumulators, valve signals) are computed twice. ``evaluated``: :meth:`evaluate` at
        this very (x, z_m), when the caller has it already (the same numbers, not computed again)."""
        x2, z2, zdot2 = self._inputs(x, z_m, zdot_m_per_s)
        dx, terms = self._rates_at_crushing(x2, z2, evaluated)
        held = dx.copy()
        self._write_crushing_rate_terms(dx, x2, terms, zdot2)
        self._write_crushing_rate_terms(held, x2, terms, np.zeros_like(zdot2))
        return dx.reshape(x.shape), held.reshape(x.shape)

    def _inputs(self, x, z_m, zdot_m_per_s):
        """State (states x cases), crushing and its rate (bellows x cases)."""
        x2 = x.reshape(self.layout.size, -1)
        return x2, self._per_bellow(z_m, x2), self._per_bellow(zdot_m_per_s, x2)

    def _rates_at_crushing(self, x2: np.ndarray, z2: np.ndarray, evaluated: "Evaluation | None" = None):
        """The rows of d(state)/dt that depend on the state and the crushing only (chamber masses,
        pipe flows, link mass, boundary enthalpy, valve open times), and the terms the other rows
        need: (dx with those rows written, (m, T, p, mdot, Hdot, chain))."""
        lay = self.layout
        m, T, V, p, p_n, T_n, rho_n, w, chain, C_valve = evaluated or self._evaluate(x2, z2)
        a, b = self._a, self._b
        Hw = w * (self.gas.cp_J_per_kgK * np.where(w >= 0.0, T_n[a], T_n[b]))  # upstream total enthalpy
        mdot = self._incidence @ w                                                # eq. (1)
        Hdot = self._incidence @ Hw
        dx = np.empty_like(x2)
        dx[self._s_m] = mdot
        pa, pb = self._pipe_a, self._pipe_b
        dx[self._s_q] = pipe_flow_rate_kg_per_s2(x2[self._s_q], p_n[pa], p_n[pb], 0.5 * (rho_n[pa] + rho_n[pb]),
                                                 self._pipe_L, self._pipe_A, self._pipe_K)  # eq. (5)
        if self._blocked_pipes is not None:               # a blocked pipe's air column stands still
            dx[self._s_q][self._blocked_pipes] = 0.0
        dx[self._s_through] = w
        dx[lay.enthalpy_in] = self._boundary_sign @ Hw
        if self._valves:
            np.sign(C_valve, out=dx[self._s_open])  # C >= 0 (tables checked): 1 while open, 0 when shut
        return dx, (m, T, p, mdot, Hdot, chain)

    def _write_crushing_rate_terms(self, dx: np.ndarray, x2: np.ndarray, terms, zdot2: np.ndarray) -> None:
        """Write the rows of d(state)/dt that the crushing rate enters: temperatures (eq. 2, with
        the heat flow of eq. 8 or the isothermal one), heat and work accumulators, valve signals."""
        lay = self.layout
        m, T, p, mdot, Hdot, chain = terms
        cv = self.gas.cv_J_per_kgK
        Vdot = -self._Ez @ zdot2
        Qdot = heat_flow_into_W(self._k_finite, T, self.atmosphere.T_K)          # eq. (8), physical sign
        if self._any_isothermal:
            Qdot = np.where(self._isothermal, isothermal_heat_flow_W(T, p, mdot, Hdot, Vdot, cv), Qdot)
        dT = temperature_rate_K_per_s(m, T, p, mdot, Hdot, Qdot, Vdot, cv)       # eq. (2)
        if self._any_isothermal:
            dT = np.where(self._isothermal, 0.0, dT)
        dx[self._s_T] = dT
        dx[lay.heat_in] = Qdot.sum(axis=0)
        dx[lay.work_in] = -(p * Vdot).sum(axis=0)
        if self._valve_dynamics:
            dx[self._s_valve] = self._valve_signal_rates(x2, chain, zdot2)

    def evaluate(self, x, z_m) -> "Evaluation":
        """The circuit at state ``x`` and crushing ``z_m`` (pressures, volumes, flows: everything
        but the terms of the crushing rate), to hand to :meth:`outputs` and
        :meth:`derivatives_and_held` at this same (x, z_m), which then do not compute it again
        (the co-simulation samples a state and starts the next macro-step from it). Read only."""
        x2 = x.reshape(self.layout.size, -1)
        return Evaluation(*self._evaluate(x2, self._per_bellow(z_m, x2)))

    def outputs(self, x, z_m, evaluated: "Evaluation | None" = None) -> CircuitOutputs:
        """Pressures, temperatures, masses, volumes, link flows and bellow forces (eq. 4).
        ``evaluated``: :meth:`evaluate` at this very (x, z_m), if the caller has it."""
        x2 = x.reshape(self.layout.size, -1)
        z2 = self._per_bellow(z_m, x2)
        m, T, V, p, _, _, _, w, _, _ = evaluated or self._evaluate(x2, z2)
        F = self.bellow_forces_N(x2, z2)
        squeeze = (lambda v: v[:, 0]) if x.ndim == 1 else (lambda v: v)
        return CircuitOutputs(*(squeeze(v) for v in (p, T, m, V, w, F)))

    def chamber_states(self, x, z_m) -> tuple[np.ndarray, np.ndarray]:
        """(absolute pressure [Pa], temperature [K]) of every chamber, each (chambers, cases),
        at state ``x`` and bellow crushing ``z_m`` (cheap: no flows)."""
        x2 = x.reshape(self.layout.size, -1)
        z2 = self._per_bellow(z_m, x2)
        T = x2[self._s_T]
        return x2[self._s_m] * self.gas.R_J_per_kgK * T / (self._V0 - self._Ez @ z2), T

    def bellow_volume_fractions(self, z_m) -> np.ndarray:
        """Volume of each bellow over its nominal volume at crushing ``z_m`` (bellows[, cases])."""
        z = np.asarray(z_m, dtype=float)
        idx = self._bellow_chamber
        z2 = z.reshape(len(idx), -1)
        V0 = self._V0[idx].reshape(len(idx), 1)
        return ((V0 - self._Ez[idx] @ z2) / V0).reshape(z.shape)

    def bellow_pressures_Pa(self, x2, z2) -> np.ndarray:
        idx = self._bellow_chamber
        lay = self.layout
        V = self._V0[idx] - self._Ez[idx] @ z2
        return x2[lay.m][idx] * self.gas.R_J_per_kgK * x2[lay.T][idx] / V

    def bellow_forces_N(self, x, z_m) -> np.ndarray:
        """Eq. (4) for every bellow; shapes follow ``z_m`` (bellows[, cases])."""
        z = np.asarray(z_m, float)
        x2 = x.reshape(self.layout.size, -1)
        z2 = self._per_bellow(z, x2)
        if self._area_tables:
            A = np.stack([self.components[b].area_m2(z2[i]) for i, b in enumerate(self.bellow_names)])
        else:
            A = self._A0 + self._dAdz * z2
        F = bellow_force_N(A, self.bellow_pressures_Pa(x2, z2), self.atmosphere.p_Pa)
        return F.reshape(z.shape)

    def bellow_stiffness_N_per_m(self, x, z_m) -> np.ndarray:
        """Instantaneous dF/dz of each bellow (air in the pipe cannot move instantly): adiabatic,
        or isothermal when k = inf. The co-simulation master uses it to linearise the force over a step."""
        z = np.asarray(z_m, float)
        x2 = x.reshape(self.layout.size, -1)
        z2 = self._per_bellow(z, x2)
        p = self.bellow_pressures_Pa(x2, z2)
        n = np.where(self._isothermal, 1.0, self.gas.gamma)
        if self._area_tables:
            K = np.stack([bellow_stiffness_N_per_m(self.components[b], z2[i], p[i], self.atmosphere.p_Pa, n)
                          for i, b in enumerate(self.bellow_names)])
        else:
            K = bellow_stiffness_N_per_m(self._bellow_columns, z2, p, self.atmosphere.p_Pa, n)
        return K.reshape(z.shape)

    def total_mass_kg(self, x) -> np.ndarray:
        """Air in all chambers [kg], per case: added chamber by chamber, in order (numpy's sum
        orders one column differently from several: the last bit would depend on how many cases
        a circuit batches)."""
        return functools.reduce(operator.add, x[self.layout.m])

    def mass_from(self, x, node: str) -> np.ndarray:
        """Cumulative mass that left boundary node ``node`` into the circuit (negative: received)
        [kg], through every link but the faults' openings (:meth:`air_lost_kg` counts those)."""
        sign = self._outflow_signs.get(node)
        if sign is None:
            i = self._node_index[node]
            sign = (self._a == i).astype(float) - (self._b == i).astype(float)
            sign[self.fault_links] = 0.0
            self._outflow_signs[node] = sign
        return sign @ x[self.layout.mass_through]

    def link_ends(self) -> list:
        """(a node, b node) of every link, in the order of :attr:`link_names`: a positive flow
        goes from a to b."""
        return [(self.node_names[i], self.node_names[j]) for i, j in zip(self._a, self._b)]

    def net_inflow_kg(self, x) -> np.ndarray:
        """Cumulative air that entered the chambers from outside [kg], per case: from every
        boundary node (the atmosphere, fixed supplies) minus what the faults' openings lost. The
        air in the chambers changes by exactly this (a finite supply is a chamber: what it
        delivers is moved, not gained)."""
        inflow = sum(self.mass_from(x, node) for node in self.boundary_names)
        return inflow - self.air_lost_kg(x)

    def air_lost_kg(self, x) -> np.ndarray:
        """Cumulative air lost to the atmosphere through the faults' openings (bursts, leaks,
        ruptured pipes) [kg], per case; 0 without such faults."""
        return x[self.layout.mass_through][self.fault_links].sum(axis=0)

    # ----------------------------------------------------------------------------- valves
    def valve_air_kg(self, x) -> ValveSides:
        """Cumulative air through each valve's sides [kg], arrays (valves[, cases]): ``supply`` from
        the supply into the bellow, ``exhaust`` from the bellow to the exhaust. Net values: a side
        that lets air pass backwards (bellow above supply pressure) counts it negative."""
        through = x[self.layout.mass_through][self._sl_valve]
        nv = len(self.valve_names)
        return ValveSides(through[:nv], through[nv:])

    def valve_open_time_s(self, x) -> ValveSides:
        """Cumulative time each valve side has been open (conductance > 0) [s], arrays
        (valves[, cases]). Integrated with the state, so a fixed RK4 step resolves an opening or
        closing instant to within one step."""
        t = x[self.layout.open_time]
        nv = len(self.valve_names)
        return ValveSides(t[:nv], t[nv:])

    def valve_lever_m(self, x, z_m) -> np.ndarray:
        """Lever displacement each valve acts on, u_f, after play, delay and lag [m], shaped
        (valves[, cases]) like ``x``: positive opens the supply side, negative the exhaust side."""
        x2 = x.reshape(self.layout.size, -1)
        u_f = self._valve_chain(x2, self._per_bellow(z_m, x2))[3]
        return u_f[:, 0] if x.ndim == 1 else u_f

    def valves_at_rest(self, x, z_m) -> np.ndarray:
        """A copy of ``x`` whose valve-signal states are at rest at crushing ``z_m``: play, every
        delay stage and lag equal to the lever displacement u = lever_gain x mean crushing, as if
        the crushing had been held for ever. (Circuit.initial_state is at rest at z = 0.)"""
        x = np.array(x, dtype=float)
        if not self._valve_dynamics:
            return x
        x2 = x.reshape(self.layout.size, -1)
        u = self._lever @ self._per_bellow(z_m, x2)
        s = x2[self._s_valve]                         # a view: writing s writes x
        s[self._sl_play] = u[self._play_rows]
        s[self._sl_delay] = u[self._delay_stage_valve]
        s[self._sl_lag] = u[self._lag_rows]
        return x

    #: below this fraction of its nominal volume a chamber counts as crushed flat (non-physical)
    MIN_VOLUME_FRACTION = 1e-3

    def physical_margin(self, x, z_m) -> float:
        """> 0 while every chamber keeps a positive mass, temperature and more than
        MIN_VOLUME_FRACTION of its volume; crosses zero when one of them stops being physical."""
        x2 = x.reshape(self.layout.size, -1)
        V = self._V0 - self._Ez @ self._per_bellow(z_m, x2)
        return float(min(np.min(x2[self._s_m]), np.min(x2[self._s_T]),
                         np.min(V / self._V0) - self.MIN_VOLUME_FRACTION))

    def physical_cases(self, x) -> np.ndarray:
        """(cases,) True where :meth:`check_state` would pass: finite positive masses and
        temperatures, finite pipe flows and valve signals (one vectorised test over every case)."""
        lay = self.layout
        x2 = x.reshape(lay.size, -1)
        chambers = x2[:lay.T.stop]                    # masses then temperatures
        ok = np.all(chambers > 0.0, axis=0) & np.all(np.isfinite(chambers), axis=0)
        return ok & np.all(np.isfinite(x2[lay.q]), axis=0) & np.all(np.isfinite(x2[lay.valve_signal]), axis=0)

    def check_state(self, x, t_s: float) -> None:
        """Raise :class:`CircuitDiverged` naming the component if a state is non-finite or non-physical."""
        lay = self.layout
        x2 = x.reshape(lay.size, -1)
        bad_m = ~np.isfinite(x2[lay.m]) | (x2[lay.m] <= 0)
        bad_T = ~np.isfinite(x2[lay.T]) | (x2[lay.T] <= 0)
        bad_q = ~np.isfinite(x2[lay.q])
        for bad, names, what in ((bad_m, self.chamber_names, "mass"), (bad_T, self.chamber_names, "temperature"),
                                 (bad_q, self.pipe_names, "pipe flow")):
            if np.any(bad):
                i, case = map(int, np.argwhere(bad)[0])
                state = {"case": case, "m_kg": x2[lay.m][i, case], "T_K": x2[lay.T][i, case]} if what != "pipe flow" \
                    else {"case": case, "q_kg_per_s": x2[lay.q][i, case]}
                raise CircuitDiverged(t_s, names[i], state, f"{what} is not finite and positive")
        bad_u = ~np.isfinite(x2[lay.valve_signal])
        if np.any(bad_u):
            i, case = map(int, np.argwhere(bad_u)[0])
            raise CircuitDiverged(t_s, self._valve_of_signal_state(i),
                                  {"case": case, "u_m": x2[lay.valve_signal][i, case]}, "valve lever signal is not finite")

    def _valve_of_signal_state(self, i: int) -> str:
        """Name of the valve that owns valve-signal state ``i``."""
        owners = np.r_[np.arange(self.layout.n_valves)[self._play_rows], self._delay_stage_valve,
                       np.arange(self.layout.n_valves)[self._lag_rows]]
        return self.valve_names[int(owners[i])]
