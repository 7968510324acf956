"""A compiled circuit evaluated at a state (:class:`CircuitRuntime`): the time derivative of the
state vector, everything observable (pressures, flows, bellow forces and stiffnesses), the air's
accounts and the checks that a state is physical.

It holds the :class:`~pneumatics.assembly.Assembly` it was given, which nothing here changes
(its arrays are read-only); its only state is two caches of values derived from it. The state
vector's layout is :mod:`pneumatics.circuit`'s docstring. Inputs are the crushing z [m] and its
rate of every bellow, in the order of ``bellow_names``; every array may carry a trailing case axis.
"""
from __future__ import annotations

import functools
import operator
from dataclasses import dataclass
from typing import Mapping, NamedTuple, Optional

import numpy as np

from .air_supply import compression_work_J_per_kg, demand_flow_kg_per_s, governor
from .assembly import Assembly
from .boundary import Supply
from .chamber import (
    bellow_force_N,
    bellow_stiffness_N_per_m,
    heat_flow_into_W,
    isothermal_heat_flow_W,
    temperature_rate_K_per_s,
    upstream_enthalpy_flow_W,
)
from .compiled import arrays
from .compiled_step import compiled_step
from .compressible_pipe import PipeCell, choked_end_flow_kg_per_s, segment_flow_rate_kg_per_s2
from .errors import CircuitDiverged, CircuitError
from .fused import FusedBellows, fused_laws, governors
from .heat_transfer import bellow_surface, wall_conductance_W_per_K
from .orifice import orifice_flow_kg_per_s
from .pipe import pipe_flow_quasi_steady_kg_per_s, pipe_flow_rate_kg_per_s2
from .valve_signals import CompiledSignals, set_at_rest
from .valves import differential_valve_flow_kg_per_s, lever_conductance


@arrays
def node_states(m, T, V, p_bnd, T_bnd, R):
    """(p, T, rho) of every node (chambers, then boundary nodes) x cases: a chamber's p = m R T / V
    (eq. 3), a boundary node's given; rho = p / (R T). The numpy expressions' operations in their
    order (compiled, :mod:`pneumatics.compiled`: one call instead of six numpy operations)."""
    nc, n = m.shape
    nb = p_bnd.shape[0]
    p_n, T_n = np.empty((nc + nb, n)), np.empty((nc + nb, n))
    for i in range(nc):
        for j in range(n):
            p_n[i, j] = m[i, j] * R * T[i, j] / V[i, j]
            T_n[i, j] = T[i, j]
    for i in range(nb):
        for j in range(n):
            p_n[nc + i, j] = p_bnd[i, j]
            T_n[nc + i, j] = T_bnd[i, j]
    rho_n = np.empty((nc + nb, n))
    for i in range(nc + nb):
        for j in range(n):
            rho_n[i, j] = p_n[i, j] / (R * T_n[i, j])
    return p_n, T_n, rho_n


@arrays
def physical_columns(x2, n_chamber_rows, q0, q1, s0, s1):
    """(cases,) True where rows [0, n_chamber_rows) (masses, temperatures) are finite and > 0 and
    rows [q0, q1) and [s0, s1) finite (compiled, :meth:`CircuitRuntime.physical_cases`)."""
    n = x2.shape[1]
    ok = np.ones(n, dtype=np.bool_)
    for j in range(n):
        for i in range(n_chamber_rows):
            v = x2[i, j]
            if not (v > 0.0 and np.isfinite(v)):
                ok[j] = False
        for i in range(q0, q1):
            if not np.isfinite(x2[i, j]):
                ok[j] = False
        for i in range(s0, s1):
            if not np.isfinite(x2[i, j]):
                ok[j] = False
    return ok


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


class CircuitRuntime:
    """The circuit ``assembly`` evaluated at a state. Its public attributes name what the
    circuit is made of (lists, in the order of the state vector's rows)."""

    #: below this fraction of its nominal volume a chamber counts as crushed flat (non-physical)
    MIN_VOLUME_FRACTION = 1e-3

    def __init__(self, assembly: Assembly):
        self.assembly = assembly
        self.components = dict(assembly.components)
        self.faults, self.active_faults = assembly.faults, assembly.active_faults
        self.gas, self.atmosphere = assembly.gas, assembly.atmosphere
        self.k_W_per_K = assembly.heat.k_W_per_K
        self.layout = assembly.layout
        nodes, links = assembly.nodes, assembly.links
        self.chamber_names = list(nodes.chamber_names)
        self.bellow_names = list(nodes.bellow_names)
        self.boundary_names = list(nodes.boundary_names)
        self.node_names = list(nodes.names)
        self.link_names = list(links.names)
        self.pipe_names = links.names_of("pipe")
        self.valve_names = list(assembly.valves.names)
        #: the links of the faults' openings to the atmosphere (what :meth:`air_lost_kg` counts)
        self.fault_links = assembly.fault_links
        # the assembly's parts, one attribute away
        self._heat, self._nodes, self._chambers, self._links = assembly.heat, nodes, assembly.chambers, links
        self._pipes, self._quasi_steady, self._orifices = assembly.pipes, assembly.quasi_steady_pipes, assembly.orifice_links
        self._differential, self._valves, self._dynamics = assembly.differential_valves, assembly.valves, assembly.valves.dynamics
        self._active = assembly.active
        self._n_valves, self._n_bellows = len(self.valve_names), len(self.bellow_names)
        self._air = assembly.air_supply
        #: the compressors and the air demands (:mod:`pneumatics.air_supply`), in state order
        self.compressor_names = links.names_of("compressor")
        self.demand_names = links.names_of("air_demand")
        self._air_supply_nodes = {nodes.index[n] for n in self.compressor_names + self.demand_names}
        self._air_supply_links = np.r_[np.arange(self._air.compressor_links.start, self._air.compressor_links.stop),
                                       np.arange(self._air.demand_links.start, self._air.demand_links.stop)].astype(int)
        self._boundary_columns = {}   # n_cases -> boundary columns repeated (cached)
        self._outflow_signs = {}      # mass_from's link signs by node (cached)
        # what every evaluation reads, looked up once (the assembly and the gas do not change):
        # the same numbers as the expressions they stand for
        self._cp, self._cv = self.gas.cp_J_per_kgK, self.gas.cv_J_per_kgK
        self._minus_Ez = -self._chambers.Ez_m2            # -Ez @ zdot: the volumes' rates
        self._air_present = self._air.present
        self._n_orifice_rows = self._orifices.b_critical.shape[0]
        # the bellows' rows: of their chambers' nominal volumes and volume matrix, and of the
        # state's masses and temperatures
        idx = self._chambers.bellow_chamber
        self._bellow_V0, self._bellow_Ez = self._chambers.V0_m3[idx], self._chambers.Ez_m2[idx]
        rows = np.arange(self.layout.size)
        self._bellow_m_rows, self._bellow_T_rows = rows[self.layout.m][idx], rows[self.layout.T][idx]
        #: each case's polytropic index of the bellows' stiffness: gamma, 1 where isothermal
        self._polytropic_index = np.where(self._heat.isothermal_of(self._chambers.bellow_chamber), 1.0, self.gas.gamma)
        #: the valves' signal laws compiled (None without valve dynamics)
        self._signals = CompiledSignals(self._dynamics) if self._dynamics.present else None
        #: the evaluation fused into compiled calls (:mod:`pneumatics.fused`; None: the numpy one)
        self._fused = fused_laws(self)
        #: the bellows' force laws compiled (None: with area tables, the numpy ones)
        self._fused_bellows = FusedBellows(self) if self._n_bellows and not self._chambers.area_tables else None
        self._reservoirs = np.asarray(self._air.reservoir, dtype=np.int64).reshape(-1)
        self._reservoir_V0 = np.ascontiguousarray(self._chambers.V0_m3[self._reservoirs], dtype=float).reshape(-1, 1)
        self._last_Hw = None          # (w, its links' enthalpy flows, a compressor works) of the last fused evaluation
        #: the macro-step's RK4 advance as one compiled call (:mod:`pneumatics.compiled_step`; None:
        #: :func:`pneumatics.integrate.rk4` over :meth:`derivatives`)
        self.compiled_step = compiled_step(self)

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
        cells = {}
        for i, n in enumerate(self.chamber_names):
            c = self.components[n]
            p = p0_Pa.get(n, c.p_Pa if isinstance(c, Supply) else c.p0_Pa)
            if p is None and isinstance(c, PipeCell):    # set from its pipe's ends, below
                cells[i] = c
                continue
            if p is None:
                raise CircuitError([n, "p0_Pa"], "initial pressure is not set")
            if not p > 0:
                raise CircuitError([n, "p0_Pa"], f"must be > 0 (absolute pressure), got {p}")
            T = getattr(c, "T0_K", None) or getattr(c, "T_K", None) or self.atmosphere.T_K
            if np.any(self._heat.isothermal_of(i)) and T != self.atmosphere.T_K:
                raise CircuitError([n, "T0_K"], "an isothermal (k = inf) chamber must start at the atmosphere's temperature")
            x[lay.T][i] = T
            x[lay.m][i] = self.gas.mass_kg(p, T, self._chambers.V0_m3[i, 0])
        for i, c in cells.items():                 # a pipe's cell: between its ends' states
            (p_a, T_a), (p_b, T_b) = (self._node_at_start(x, end) for end in c.ends)
            p, T = p_a + c.position * (p_b - p_a), T_a + c.position * (T_b - T_a)
            x[lay.T][i] = T
            x[lay.m][i] = self.gas.mass_kg(p, T, self._chambers.V0_m3[i, 0])
        air = self._air
        if air.n_compressors:                      # each governor as its reservoir's pressure has it
            x[lay.governor] = self._governors(x[:, None], air.running_at_start)[:, 0]
        if n_cases is None and self.k_W_per_K.ndim:
            n_cases = self.k_W_per_K.size
        return x if n_cases is None else np.repeat(x[:, None], n_cases, axis=1)

    def _node_at_start(self, x: np.ndarray, name: str) -> tuple:
        """(p, T) of node ``name`` in the initial state ``x`` being built (a chamber's at its
        nominal volume, a boundary node's given)."""
        i = self._nodes.index[name]
        nc = len(self.chamber_names)
        if i >= nc:
            return float(self._nodes.p_boundary_Pa[i - nc, 0]), float(self._nodes.T_boundary_K[i - nc, 0])
        T = x[self.layout.T][i]
        return self.gas.pressure_Pa(x[self.layout.m][i], T, self._chambers.V0_m3[i, 0]), T

    # ----------------------------------------------------------------------------- physics
    def _boundary(self, n_cases: int):
        """Boundary-node pressures, temperatures and fixed orifice conductances repeated over
        ``n_cases`` (cached)."""
        cols = self._boundary_columns.get(n_cases)
        if cols is None:
            nodes = self._nodes
            cols = self._boundary_columns[n_cases] = tuple(
                np.repeat(v, n_cases, axis=1) for v in (nodes.p_boundary_Pa, nodes.T_boundary_K,
                                                        self._orifices.fixed_C_m3_per_sPa))
        return cols

    def _valve_chain(self, x2: np.ndarray, z2: np.ndarray):
        """Lever signals (valves x cases) along the chain u -> play -> delay -> lag: (u, u_p, u_d, u_f).
        Without valve dynamics all four are the same array u = lever @ z."""
        u = self._valves.lever @ z2
        if not self._dynamics.present:
            return u, u, u, u
        return self._signals.lever_chain(u, x2[self.layout.valve_signal])

    def _evaluate(self, x2: np.ndarray, z2: np.ndarray):
        """Pressures, volumes and link flows for a 2-D state (states x cases) and crushing (bellows
        x cases); also the valves' lever chain and their conductances (supply sides, then exhaust)."""
        gas, lay, chambers, links = self.gas, self.layout, self._chambers, self._links
        m, T = x2[lay.m], x2[lay.T]
        n_cases = x2.shape[1]
        p_bnd, T_bnd, C_fixed = self._boundary(n_cases)
        if self._fused is not None and n_cases:
            return self._evaluate_fused(x2, z2, m, T, p_bnd, T_bnd, C_fixed)
        V = chambers.V0_m3 - chambers.Ez_m2 @ z2
        # eq. (3) and the nodes' states: the chambers', then the boundary nodes'
        p_n, T_n, rho_n = node_states(m, T, V, p_bnd, T_bnd, gas.R_J_per_kgK)
        p = p_n[:len(m)]
        a, b = links.a, links.b
        w = np.empty((len(a), n_cases))
        w[self._pipes.links] = x2[lay.q]
        ends = self._pipes.choked
        if ends is not None:                               # compressible pipes' ends: choked flow
            p0, T0 = self._end_stagnation(x2[lay.q], m, p_n, T_n)
            w[ends.rows] = choked_end_flow_kg_per_s(x2[lay.q][ends.rows], ends.area_m2, p0, T0, ends.outflow_sign,
                                                    gas.R_J_per_kgK, gas.gamma)
        qs = self._quasi_steady
        if qs.count:
            ia, ib = a[qs.links], b[qs.links]
            w[qs.links] = pipe_flow_quasi_steady_kg_per_s(p_n[ia], p_n[ib], 0.5 * (rho_n[ia] + rho_n[ib]), qs.area_m2,
                                                          qs.loss_coefficient)
        for rows, ia, ib, xp, fp in self._differential.tables:
            w[rows] = differential_valve_flow_kg_per_s(p_n[ia], p_n[ib], xp, fp)
        orifices = self._orifices
        chain = None
        if self._n_orifice_rows:
            C = np.empty((self._n_orifice_rows, n_cases))   # fixed orifices, then valve supply and exhaust sides
            C[:orifices.n_fixed] = C_fixed
            C_valve = C[orifices.n_fixed:]
            chain = self._valve_conductances(x2, z2, C_valve) if self._n_valves else None
            if n_cases:
                ia, ib = orifices.a, orifices.b
                w[orifices.links] = orifice_flow_kg_per_s(C, orifices.b_critical, p_n[ia], T_n[ia], p_n[ib], T_n[ib],
                                                          gas)
        else:                                              # no orifice, no valve: no conductance
            C_valve = C_fixed
        air = self._air
        if self._air_present:                              # compressors (governed) and demands
            w[air.compressor_links] = x2[lay.governor] * air.w_compressor_kg_per_s
            w[air.demand_links] = demand_flow_kg_per_s(air.w_demand_kg_per_s, p_n[air.demand_node],
                                                       self.atmosphere.p_Pa, air.dp_off_Pa)
        blocked = self._active.blocked_links
        if blocked is not None:                            # faults: links that carry nothing
            w[blocked] = 0.0
        return m, T, V, p, p_n, T_n, rho_n, w, chain, C_valve

    def _evaluate_fused(self, x2, z2, m, T, p_bnd, T_bnd, C_fixed):
        """:meth:`_evaluate` by the fused laws (:mod:`pneumatics.fused`), the same numbers."""
        chain = None
        if self._n_valves:
            if self._dynamics.present:
                chain = self._valve_chain(x2, z2)
                u_f = chain[3]
            else:
                u_f = self._valves.lever @ z2
        else:
            u_f = np.empty((0, x2.shape[1]))
        V, p_n, T_n, rho_n, w, C, Hw, working = self._fused.evaluate(x2, self._chambers.Ez_m2 @ z2, u_f, p_bnd, T_bnd)
        self._last_Hw = (w, Hw, working)
        C_valve = C[self._orifices.n_fixed:] if self._n_orifice_rows else C_fixed
        return m, T, V, p_n[:len(m)], p_n, T_n, rho_n, w, chain, C_valve

    def _valve_conductances(self, x2: np.ndarray, z2: np.ndarray, C_valve: np.ndarray):
        """Write the valves' conductances (supply sides, then exhaust) into ``C_valve`` and return
        their lever chain (None without valve dynamics)."""
        valves, chain = self._valves, None
        if self._dynamics.present:
            chain = self._valve_chain(x2, z2)
            lever = chain[3]
        else:
            lever = valves.lever @ z2
        active, nv = self._active, self._n_valves
        if active.stuck_valves is not None:                # a stuck valve acts on its stuck lever
            lever = lever.copy()
            lever[active.stuck_valves] = active.stuck_lever_m
        for tables, sign, side in ((valves.supply_tables, 1.0, C_valve[:nv]), (valves.exhaust_tables, -1.0, C_valve[nv:])):
            for rows, xp, fp in tables:
                side[rows] = lever_conductance(sign * lever[rows], xp, fp)
        return chain

    def _per_bellow(self, values, x2: np.ndarray) -> np.ndarray:
        """A bellow input as (bellows, cases); a circuit without bellows takes an empty array."""
        nb = self._n_bellows
        if not nb:
            return np.zeros((0, x2.shape[1]))
        return values.reshape(nb, -1) if type(values) is np.ndarray else np.reshape(values, (nb, -1))

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
        this very (x, z_m), when the caller has it already (the same numbers, not computed again).
        With a compiled macro-step (:attr:`compiled_step`) its one compiled call instead, whose
        matrix products differ at round-off (it evaluates afresh: cheaper than reusing ``evaluated``)."""
        step = self.compiled_step
        if step is not None and type(x) is np.ndarray and x.size:   # one compiled call (pneumatics.compiled_step)
            return step.derivatives_and_held(x, z_m, zdot_m_per_s)
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
        lay, links, pipes = self.layout, self._links, self._pipes
        m, T, V, p, p_n, T_n, rho_n, w, chain, C_valve = evaluated or self._evaluate(x2, z2)
        a, b = links.a, links.b
        if self._fused is not None and x2.shape[1]:
            return self._rates_fused(x2, m, T, p, p_n, T_n, rho_n, w, chain, C_valve)
        Hw = upstream_enthalpy_flow_W(w, T_n[a], T_n[b], self._cp)            # upstream total enthalpy
        mdot = links.incidence @ w                                              # eq. (1)
        Hdot = links.incidence @ Hw
        dx = np.empty_like(x2)
        dx[lay.m] = mdot
        pa, pb = pipes.a, pipes.b
        dx[lay.q] = pipe_flow_rate_kg_per_s2(x2[lay.q], p_n[pa], p_n[pb], 0.5 * (rho_n[pa] + rho_n[pb]),
                                             pipes.length_m, pipes.area_m2, pipes.loss_coefficient)  # eq. (5)
        cells = pipes.cells
        if cells is not None:
            self._compressible_rates(dx[lay.q], x2[lay.q], m, p_n, T_n, rho_n, w)
        blocked_pipes = self._active.blocked_pipes
        if blocked_pipes is not None:                     # a blocked pipe's air column stands still
            dx[lay.q][blocked_pipes] = 0.0
        if cells is not None:                             # the cells' kinetic energy, in and out
            Hdot = Hdot + self._kinetic_energy_rates(x2[lay.q], dx[lay.q], m, mdot, w)
        dx[lay.mass_through] = w
        dx[lay.enthalpy_in] = links.boundary_sign @ Hw
        if self._n_valves:
            np.sign(C_valve, out=dx[lay.open_time])  # C >= 0 (tables checked): 1 while open, 0 when shut
        if self._air.n_compressors:
            dx[lay.governor] = 0.0                   # switched between steps (update_governors)
            dx[lay.run_time] = x2[lay.governor]
            air = self._air
            atm = self.atmosphere
            w_iso, w_ad = compression_work_J_per_kg(p[air.reservoir], atm.p_Pa, atm.T_K, self.gas)
            delivered = w[air.compressor_links]
            dx[lay.compression_work] = np.concatenate([delivered * w_iso, delivered * w_ad])
        conductances = self._correlation_conductances(m, T, V, w, mdot, z2) if self._heat.correlations else None
        return dx, (m, T, p, mdot, Hdot, chain, conductances)

    def _rates_fused(self, x2, m, T, p, p_n, T_n, rho_n, w, chain, C_valve):
        """:meth:`_rates_at_crushing` by the fused laws (:mod:`pneumatics.fused`), the same numbers."""
        links, air = self._links, self._air
        last = self._last_Hw
        if last is not None and last[0] is w:
            _, Hw, working = last
        else:
            Hw, working = upstream_enthalpy_flow_W(w, T_n[links.a], T_n[links.b], self._cp), True
        mdot = links.incidence @ w                                              # eq. (1)
        Hdot = links.incidence @ Hw
        if air.n_compressors and working:
            atm = self.atmosphere
            w_iso, w_ad = compression_work_J_per_kg(p[air.reservoir], atm.p_Pa, atm.T_K, self.gas)
        else:                    # nothing delivered: the work's rates are +0 x (finite, >= 0) = +0
            w_iso = w_ad = np.zeros((air.n_compressors, x2.shape[1]))
        dx = self._fused.rates(x2, mdot, p_n, rho_n, w, C_valve, w_iso, w_ad)
        dx[self.layout.enthalpy_in] = links.boundary_sign @ Hw
        return dx, (m, T, p, mdot, Hdot, chain, None)

    def _correlation_conductances(self, m, T, V, w, mdot, z2) -> list:
        """k [W/K] of the chambers a correlation serves, (rows, cases) per group
        (:func:`pneumatics.heat_transfer.wall_conductance_W_per_K`): at their temperature and
        density, the air flowing in, a bellow's surface at its crushing."""
        gas, atm, out = self.gas, self.atmosphere, []
        for g in self._heat.correlations:
            r = g.rows
            inflow = 0.5 * (g.abs_incidence @ np.abs(w) + mdot[r])
            if g.bellows is not None:
                area, height, diameter = bellow_surface(self._bellow_areas_m2(z2)[g.bellows], V[r])
            else:
                area, height, diameter = g.area_m2, g.height_m, g.diameter_m
            out.append(wall_conductance_W_per_K(T[r], m[r] / V[r], inflow, atm.T_K, atm.p_Pa, area, height, diameter,
                                                g.port_area_m2, g.wall_m2K_per_W, g.air_speed_m_per_s, g.emissivity,
                                                g.cylinder,
                                                gas.cp_J_per_kgK, gas.R_J_per_kgK))
        return out

    def _end_stagnation(self, q: np.ndarray, m: np.ndarray, p_n, T_n):
        """The stagnation pressure and temperature of the compressible pipes' end cells (ends,
        cases): T0 = T + u^2 / (2 c_p), p0 = p (T0 / T)^(gamma / (gamma - 1)), u the cell's velocity."""
        ends, gas = self._pipes.choked, self.gas
        flow, _, per_m = self._cell_flows(q, m)
        u = (flow * per_m)[ends.cell_index]
        T = T_n[ends.cell]
        T0 = T + 0.5 * u * u / gas.cp_J_per_kgK
        return p_n[ends.cell] * (T0 / T) ** (gas.gamma / (gas.gamma - 1.0)), T0

    def _cell_flows(self, q: np.ndarray, m: np.ndarray):
        """Each cell's mass flow (the mean of its two links'), the flow of its upwind link, and
        dx / m (so that a flow times it is a velocity)."""
        cells = self._pipes.cells
        q_left, q_right = q[cells.left], q[cells.right]
        flow = 0.5 * (q_left + q_right)
        return flow, np.where(flow >= 0.0, q_left, q_right), cells.dx_m / m[cells.rows]

    def _compressible_rates(self, dq: np.ndarray, q: np.ndarray, m, p_n, T_n, rho_n, w) -> None:
        """Write the rates of the compressible pipes' links into ``dq``: eq. (5) with lambda of the
        Reynolds number where the pipe's is null; on the inner links, the momentum flux rho u^2 A
        of the cells on either side (upwind); at the ends, q relaxing towards the choked flow w
        it passes in the link's acoustic time l / c (:mod:`pneumatics.compressible_pipe`)."""
        gas, cells = self.gas, self._pipes.cells
        flow, upwind, per_m = self._cell_flows(q, m)
        momentum = flow * upwind * per_m                     # rho u^2 A = flow x upwind velocity [N]
        dq[cells.inner] += (momentum[cells.inner_left] - momentum[cells.inner_right]) / cells.inner_length_m
        ends = self._pipes.choked
        # an end link the air enters by: Bernoulli from the chamber's air at rest to its cell's,
        # the dynamic pressure rho u^2 / 2 = momentum / 2A spent; where it leaves, the jet's
        # dynamic pressure is not regained (its kinetic energy heats the chamber: the exit loss)
        q_end = q[ends.rows]
        entering = q_end * ends.outflow_sign < 0.0
        g = gas.gamma
        u = (flow * per_m)[ends.cell_index]
        ratio = np.maximum(1.0 - 0.5 * u * u / (gas.cp_J_per_kgK * T_n[ends.chamber]), 0.0)
        drop = p_n[ends.chamber] * (1.0 - ratio ** (g / (g - 1.0)))     # isentropic, from rest to u
        dq[ends.rows] -= np.where(entering, np.sign(q_end) * drop, 0.0) * ends.area_m2 / ends.length_m
        # a jet leaving the pipe sees no pressure below the critical one of its cell's stagnation
        # state (below it the jet expands outside the pipe: the exit is choked)
        p0, _ = self._end_stagnation(q, m, p_n, T_n)
        p_c = p_n[ends.chamber]
        floor = np.maximum(p_c, p0 * (2.0 / (g + 1.0)) ** (g / (g - 1.0))) - p_c
        dq[ends.rows] -= np.where(entering, 0.0, ends.outflow_sign * floor) * ends.area_m2 / ends.length_m
        fr = self._pipes.reynolds
        if fr is not None:
            ia, ib = fr.a, fr.b
            dq[fr.rows] = segment_flow_rate_kg_per_s2(q[fr.rows], p_n[ia], p_n[ib], 0.5 * (rho_n[ia] + rho_n[ib]),
                                                      fr.length_m, fr.area_m2, fr.zeta, fr.diameter_m, fr.viscosity_Pa_s)
        if ends is not None:
            c = np.sqrt(gas.gamma * gas.R_J_per_kgK * T_n[ends.cell])
            dq[ends.rows] -= (q[ends.rows] - w[ends.rows]) * c / ends.length_m

    def _kinetic_energy_rates(self, q: np.ndarray, dq: np.ndarray, m, mdot, w) -> np.ndarray:
        """The kinetic energy the links carry into each node, w u^2 / 2 of the upstream node (a
        cell's velocity u = its flow dx / m; a chamber's air is at rest), less the rate of change
        of each cell's own kinetic energy, m u^2 / 2 = flow^2 dx^2 / (2 m): added to the enthalpy
        flow, the cells and chambers keep internal plus kinetic energy (chambers, cases) [W]."""
        cells, links = self._pipes.cells, self._links
        flow, _, per_m = self._cell_flows(q, m)
        u_n = np.zeros((len(self.node_names), q.shape[1]))
        u_n[cells.rows] = flow * per_m
        u_up = np.where(w >= 0.0, u_n[links.a], u_n[links.b])
        into = links.incidence @ (0.5 * w * u_up * u_up)
        dflow = 0.5 * (dq[cells.left] + dq[cells.right])
        into[cells.rows] -= flow * dflow * per_m * cells.dx_m - 0.5 * (flow * per_m) ** 2 * mdot[cells.rows]
        return into

    def _write_crushing_rate_terms(self, dx: np.ndarray, x2: np.ndarray, terms, zdot2: np.ndarray) -> None:
        """Write the rows of d(state)/dt that the crushing rate enters: temperatures (eq. 2, with
        the heat flow of eq. 8 or the isothermal one), heat and work accumulators, valve signals."""
        lay, heat = self.layout, self._heat
        m, T, p, mdot, Hdot, chain, conductances = terms
        cv = self._cv
        Vdot = self._minus_Ez @ zdot2
        if self._fused is not None and x2.shape[1]:
            Qdot, pV = self._fused.temperatures(dx, x2, p, mdot, Hdot, Vdot, self.atmosphere.T_K, cv)
            dx[lay.heat_in] = np.add.reduce(Qdot, axis=0)
            dx[lay.work_in] = -np.add.reduce(pV, axis=0)
            if self._dynamics.present:
                dx[lay.valve_signal] = self._signals.signal_rates(x2[lay.valve_signal], chain,
                                                                  self._valves.lever_play @ zdot2)
            return
        Qdot = heat_flow_into_W(heat.k_finite_W_per_K, T, self.atmosphere.T_K)   # eq. (8), physical sign
        if conductances is not None:                       # a correlation's k, at this state
            Qdot = np.array(np.broadcast_to(Qdot, T.shape))
            for g, k in zip(heat.correlations, conductances):
                Qdot[g.rows] = heat_flow_into_W(k, T[g.rows], self.atmosphere.T_K)
        if heat.any_isothermal:
            Qdot = np.where(heat.isothermal, isothermal_heat_flow_W(T, p, mdot, Hdot, Vdot, cv), Qdot)
        cells = self._chambers.pipe_cells
        if cells is not None:                              # compressible pipes' cells: adiabatic
            Qdot = np.array(np.broadcast_to(Qdot, T.shape))
            Qdot[cells] = 0.0
        dT = temperature_rate_K_per_s(m, T, p, mdot, Hdot, Qdot, Vdot, cv)       # eq. (2)
        if heat.any_isothermal:
            dT_cells = dT[cells] if cells is not None else None
            dT = np.where(heat.isothermal, 0.0, dT)
            if cells is not None:
                dT[cells] = dT_cells
        dx[lay.T] = dT
        dx[lay.heat_in] = np.add.reduce(Qdot, axis=0)        # Qdot.sum(axis=0), without its wrappers
        dx[lay.work_in] = -np.add.reduce(p * Vdot, axis=0)
        if self._dynamics.present:
            dx[lay.valve_signal] = self._signals.signal_rates(x2[lay.valve_signal], chain, self._valves.lever_play @ zdot2)

    def heat_conductances_W_per_K(self, x, z_m) -> np.ndarray:
        """Each chamber's k [W/K] at state ``x`` and crushing ``z_m``, (chambers, cases): its case's,
        its own constant one (inf: isothermal), or its correlation's at this state (eq. 8: the
        heat flow into it is k (T_atm - T); a compressible pipe's cells exchange none whatever k)."""
        x2 = x.reshape(self.layout.size, -1)
        z2 = self._per_bellow(z_m, x2)
        heat = self._heat
        k = np.array(np.broadcast_to(np.where(heat.isothermal, np.inf, heat.k_finite_W_per_K),
                                     (self.layout.n_chambers, x2.shape[1])))
        if heat.correlations:
            m, T, V, _, _, _, _, w, _, _ = self._evaluate(x2, z2)
            for g, kg in zip(heat.correlations, self._correlation_conductances(m, T, V, w, self._links.incidence @ w, z2)):
                k[g.rows] = kg
        return k

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
        lay, chambers = self.layout, self._chambers
        x2 = x.reshape(lay.size, -1)
        z2 = self._per_bellow(z_m, x2)
        T = x2[lay.T]
        return x2[lay.m] * self.gas.R_J_per_kgK * T / (chambers.V0_m3 - chambers.Ez_m2 @ z2), T

    # ----------------------------------------------------------------------------- bellows
    def bellow_volume_fractions(self, z_m) -> np.ndarray:
        """Volume of each bellow over its nominal volume at crushing ``z_m`` (bellows[, cases])."""
        chambers = self._chambers
        z = np.asarray(z_m, dtype=float)
        idx = chambers.bellow_chamber
        z2 = z.reshape(len(idx), -1)
        V0 = chambers.V0_m3[idx].reshape(len(idx), 1)
        return ((V0 - chambers.Ez_m2[idx] @ z2) / V0).reshape(z.shape)

    def bellow_pressures_Pa(self, x2, z2) -> np.ndarray:
        V = self._bellow_V0 - self._bellow_Ez @ z2
        return x2[self._bellow_m_rows] * self.gas.R_J_per_kgK * x2[self._bellow_T_rows] / V

    def bellow_forces_N(self, x, z_m) -> np.ndarray:
        """Eq. (4) for every bellow; shapes follow ``z_m`` (bellows[, cases])."""
        z = np.asarray(z_m, float)
        x2 = x.reshape(self.layout.size, -1)
        z2 = self._per_bellow(z, x2)
        F = bellow_force_N(self._bellow_areas_m2(z2), self.bellow_pressures_Pa(x2, z2), self.atmosphere.p_Pa)
        return F.reshape(z.shape)

    def _bellow_areas_m2(self, z2: np.ndarray) -> np.ndarray:
        """Each bellow's effective area A_e(z) (eq. 4) at crushing ``z2`` (bellows, cases)."""
        chambers = self._chambers
        if chambers.area_tables:
            return np.stack([self.components[b].area_m2(z2[i]) for i, b in enumerate(self.bellow_names)])
        return chambers.A0_m2 + chambers.dA_dz_m * z2

    def bellow_force_laws(self, x, z_m, rate, dt_s: float):
        """(:meth:`bellow_forces_N` at (x, z), at (x + dt_s rate, z), :meth:`bellow_stiffness_N_per_m`
        at (x, z)): the co-simulation's force laws' parts, compiled (pneumatics.fused.FusedBellows)
        in one call instead of three of ~8 numpy operations each, the same numbers."""
        if self._fused_bellows is None:
            return (self.bellow_forces_N(x, z_m), self.bellow_forces_N(x + dt_s * rate, z_m),
                    self.bellow_stiffness_N_per_m(x, z_m))
        z = np.asarray(z_m, float)
        x2 = x.reshape(self.layout.size, -1)
        z2 = self._per_bellow(z, x2)
        V = self._bellow_V0 - self._bellow_Ez @ z2
        return tuple(v.reshape(z.shape) for v in self._fused_bellows.laws(x2, rate.reshape(x2.shape), dt_s, V, z2))

    def bellow_stiffness_N_per_m(self, x, z_m) -> np.ndarray:
        """Instantaneous dF/dz of each bellow (air in the pipe cannot move instantly): adiabatic,
        or isothermal when its k = inf. The co-simulation master uses it to linearise the force over a step."""
        z = np.asarray(z_m, float)
        x2 = x.reshape(self.layout.size, -1)
        z2 = self._per_bellow(z, x2)
        p = self.bellow_pressures_Pa(x2, z2)
        n = self._polytropic_index
        if self._chambers.area_tables:
            K = np.stack([bellow_stiffness_N_per_m(self.components[b], z2[i], p[i], self.atmosphere.p_Pa, n)
                          for i, b in enumerate(self.bellow_names)])
        else:
            K = bellow_stiffness_N_per_m(self._chambers.bellow_columns, z2, p, self.atmosphere.p_Pa, n)
        return K.reshape(z.shape)

    # ----------------------------------------------------------------------------- air accounts
    def total_mass_kg(self, x) -> np.ndarray:
        """Air in all chambers [kg], per case: added chamber by chamber, in order (numpy's sum
        orders one column differently from several: the last bit would depend on how many cases
        a circuit batches)."""
        return functools.reduce(operator.add, x[self.layout.m])

    def mass_from(self, x, node: str) -> np.ndarray:
        """Cumulative mass that left boundary node ``node`` into the circuit (negative: received)
        [kg], through every link but the faults' openings (:meth:`air_lost_kg` counts those) and,
        unless ``node`` is a compressor's intake or a demand's exhaust, but the compressors' and
        demands' links (:meth:`compressor_air_kg`, :meth:`demand_air_kg` count those): the air a
        finite supply gives the suspension is what leaves it towards the valves."""
        sign = self._outflow_signs.get(node)
        if sign is None:
            i = self._nodes.index[node]
            sign = (self._links.a == i).astype(float) - (self._links.b == i).astype(float)
            sign[self.fault_links] = 0.0
            if i not in self._air_supply_nodes:
                sign[self._air_supply_links] = 0.0
            self._outflow_signs[node] = sign
        return sign @ x[self.layout.mass_through]

    def link_ends(self) -> list:
        """(a node, b node) of every link, in the order of :attr:`link_names`: a positive flow
        goes from a to b."""
        return [(self.node_names[i], self.node_names[j]) for i, j in zip(self._links.a, self._links.b)]

    def net_inflow_kg(self, x) -> np.ndarray:
        """Cumulative air that entered the chambers from outside [kg], per case: from every
        boundary node (the atmosphere, fixed supplies) minus what the faults' openings lost. The
        air in the chambers changes by exactly this (a finite supply is a chamber: what it
        delivers is moved, not gained)."""
        inflow = sum(self.mass_from(x, node) for node in self.boundary_names)
        return inflow - self.air_lost_kg(x)

    def compressor_air_kg(self, x) -> np.ndarray:
        """Cumulative air each compressor delivered [kg], (compressors[, cases])."""
        return x[self.layout.mass_through][self._air.compressor_links]

    def compressor_running(self, x) -> np.ndarray:
        """Each compressor's governor: 1.0 running, 0.0 stopped, (compressors[, cases])."""
        return x[self.layout.governor]

    def compressor_run_time_s(self, x) -> np.ndarray:
        """Each compressor's cumulative running time [s], (compressors[, cases])."""
        return x[self.layout.run_time]

    def compression_energy_J(self, x) -> tuple[np.ndarray, np.ndarray]:
        """Each compressor's cumulative energy of compression [J], (compressors[, cases]): its
        (isothermal, adiabatic) bounds (:func:`pneumatics.air_supply.compression_work_J_per_kg`)."""
        work = x[self.layout.compression_work]
        n = self._air.n_compressors
        return work[:n], work[n:]

    def demand_air_kg(self, x) -> np.ndarray:
        """Cumulative air each demand drew [kg], (demands[, cases])."""
        return x[self.layout.mass_through][self._air.demand_links]

    def _governors(self, x2: np.ndarray, running: np.ndarray) -> np.ndarray:
        """The governors' next states (compressors, cases) from ``running`` and their reservoirs'
        pressures in state ``x2`` (a reservoir is a rigid chamber: its nominal volume)."""
        air, lay = self._air, self.layout
        i = air.reservoir
        p = x2[lay.m][i] * self.gas.R_J_per_kgK * x2[lay.T][i] / self._chambers.V0_m3[i]
        return governor(running, p, air.p_cut_in_Pa, air.p_cut_out_Pa)

    @property
    def has_air_supply(self) -> bool:
        """The circuit has compressors or air demands (:mod:`pneumatics.air_supply`)."""
        return self._air.present

    @property
    def has_governors(self) -> bool:
        """The circuit has compressors, whose governors switch between the integrator's steps."""
        return bool(self._air.n_compressors)

    def update_governors(self, x) -> np.ndarray:
        """``x`` with each compressor's governor switched as its reservoir's pressure now says
        (:func:`pneumatics.air_supply.governor`): the integrator calls it after every step. A
        circuit without compressors returns ``x`` itself."""
        if not self._air.n_compressors:
            return x
        lay, air = self.layout, self._air
        x2 = x.reshape(lay.size, -1)
        # compiled (pneumatics.fused.governors): _governors and np.array_equal in one call
        new, switched = governors(x2, lay.n_chambers, self._reservoirs, self._reservoir_V0, self.gas.R_J_per_kgK,
                                  air.p_cut_in_Pa, air.p_cut_out_Pa, lay.governor.start)
        if not switched:
            return x
        x = x.copy()
        x.reshape(lay.size, -1)[lay.governor] = new
        return x

    def air_lost_kg(self, x) -> np.ndarray:
        """Cumulative air lost to the atmosphere through the faults' openings (bursts, leaks,
        ruptured pipes) [kg], per case; 0 without such faults."""
        return x[self.layout.mass_through][self.fault_links].sum(axis=0)

    # ----------------------------------------------------------------------------- valves
    def valve_air_kg(self, x) -> ValveSides:
        """Cumulative air through each valve's sides [kg], arrays (valves[, cases]): ``supply`` from
        the supply into the bellow, ``exhaust`` from the bellow to the exhaust. Net values: a side
        that lets air pass backwards (bellow above supply pressure) counts it negative."""
        through = x[self.layout.mass_through][self._valves.links]
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
        if not self._dynamics.present:
            return x
        x2 = x.reshape(self.layout.size, -1)
        set_at_rest(self._dynamics, x2[self.layout.valve_signal], self._valves.lever @ self._per_bellow(z_m, x2))
        return x

    # ----------------------------------------------------------------------------- checks
    def physical_margin(self, x, z_m) -> float:
        """> 0 while every chamber keeps a positive mass, temperature and more than
        MIN_VOLUME_FRACTION of its volume; crosses zero when one of them stops being physical."""
        lay, chambers = self.layout, self._chambers
        x2 = x.reshape(lay.size, -1)
        V = chambers.V0_m3 - chambers.Ez_m2 @ self._per_bellow(z_m, x2)
        return float(min(np.min(x2[lay.m]), np.min(x2[lay.T]), np.min(V / chambers.V0_m3) - self.MIN_VOLUME_FRACTION))

    def physical_cases(self, x) -> np.ndarray:
        """(cases,) True where :meth:`check_state` would pass: finite positive masses and
        temperatures, finite pipe flows and valve signals (one compiled pass over every case)."""
        lay = self.layout
        x2 = x.reshape(lay.size, -1)
        return physical_columns(x2, lay.T.stop, lay.q.start, lay.q.stop, lay.valve_signal.start, lay.valve_signal.stop)

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
            raise CircuitDiverged(t_s, self.valve_names[self._dynamics.valve_of_state(i)],
                                  {"case": case, "u_m": x2[lay.valve_signal][i, case]}, "valve lever signal is not finite")
