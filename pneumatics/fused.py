"""The circuit's evaluation fused into a few compiled calls (:class:`FusedLaws`), for the circuits
of the co-simulation's usual kind: chambers, dynamic pipes without cells, orifices, levelling and
differential valves, compressors and air demands, faults; no compressible pipe, no quasi-steady
pipe, no heat correlation (those circuits keep the numpy evaluation of
:class:`~pneumatics.runtime.CircuitRuntime`, which this mirrors).

Why: the co-simulation evaluates its circuit four times per macro-step on arrays of a few numbers
(chambers or links x cases), where each of numpy's ~90 operations per evaluation costs its call
(~1 us), not its arithmetic. Here the elementwise parts between the matrix products run as three
compiled functions (:mod:`pneumatics.compiled`), calling the very laws the numpy evaluation calls
(each element's law compiled from the same Python function, or the same numba implementation of
``np.interp``), in the same order: the numbers are the numpy evaluation's bit for bit
(``tests/pneumatics/test_fused.py`` compares both on random states of several circuits).

What stays numpy: the matrix products (incidence, volumes, levers: BLAS sums in its own order)
and the sums over the chambers (numpy's pairwise summation of one case differs from its sum of
several), and the compression work's log and power (numpy's own implementations).
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from .chamber import temperature_rate_K_per_s, upstream_enthalpy_flow_W
from .compiled import arrays, scalar
from .orifice import _iso6358
from .pipe import pipe_flow_rate_kg_per_s2

# the elementwise laws the numpy evaluation calls as ufuncs, called here element by element
_enthalpy = scalar(upstream_enthalpy_flow_W.py_func)
_pipe_rate = scalar(pipe_flow_rate_kg_per_s2.py_func)
_temperature_rate = scalar(temperature_rate_K_per_s.py_func)


@scalar
def _clip01(v):
    """np.clip(v, 0.0, 1.0) as numpy's clip loop has it for floats: v unless it is below 0 (then
    0) or above 1 (then 1); a NaN passes, and so does -0.0 (tests/pneumatics/test_fused.py)."""
    if not (np.isnan(v) or v >= 0.0):
        v = 0.0
    if not (np.isnan(v) or v <= 1.0):
        v = 1.0
    return v


@arrays
def _flows(x2, EzZ, u_f, V0, R, cp, rho_ref, p_atm, p_bnd, T_bnd, nc, q0, nq,
           link_a, link_b, pipe_links, diff, diff_xp, diff_fp, valves, valve_xp, valve_fp, stuck, stuck_lever,
           orifices, b_critical, C_fixed, compressors, w_compressor, demands, w_demand, dp_off, blocked):
    """V, p_n, T_n, rho_n, w, C (orifice conductances: fixed, valve supply, valve exhaust sides)
    and Hw (each link's upstream enthalpy flow) at state ``x2`` (volumes' crushing part ``EzZ`` =
    Ez @ z, the valves' lever ``u_f`` after their dynamics): :meth:`CircuitRuntime._evaluate`.

    ``diff``: (differential valve link, a node, b node, table start, table end) rows into
    ``diff_xp``/``diff_fp``; ``valves``: (valve, orifice row of its side, side sign, table start,
    end) rows, the supply sides then the exhaust sides, each side's table group in the numpy
    evaluation's order; ``stuck``: (valve row) with ``stuck_lever``; ``orifices``: (link, a, b);
    ``compressors``: (link, governor state row, reservoir); ``demands``: (link, node). Also
    whether a compressor works (:meth:`FusedLaws.evaluate`)."""
    n = x2.shape[1]
    nb = p_bnd.shape[0]
    n_nodes = nc + nb
    V = np.empty((nc, n))
    p_n, T_n, rho_n = np.empty((n_nodes, n)), np.empty((n_nodes, n)), np.empty((n_nodes, n))
    for i in range(nc):
        for j in range(n):
            V[i, j] = V0[i, 0] - EzZ[i, j]
    for i in range(nc):
        for j in range(n):
            p_n[i, j] = x2[i, j] * R * x2[nc + i, j] / V[i, j]                    # eq. (3)
            T_n[i, j] = x2[nc + i, j]
    for i in range(nb):
        for j in range(n):
            p_n[nc + i, j] = p_bnd[i, j]
            T_n[nc + i, j] = T_bnd[i, j]
    for i in range(n_nodes):
        for j in range(n):
            rho_n[i, j] = p_n[i, j] / (R * T_n[i, j])
    w = np.empty((link_a.size, n))
    for k in range(nq):
        for j in range(n):
            w[pipe_links[k], j] = x2[q0 + k, j]
    for k in range(diff.shape[0]):                  # sign(dp) q(|dp|), as differential_valve_flow_kg_per_s
        dp = np.empty(n)
        for j in range(n):
            dp[j] = p_n[diff[k, 1], j] - p_n[diff[k, 2], j]
        q = np.sign(dp) * np.interp(np.abs(dp), diff_xp[diff[k, 3]:diff[k, 4]], diff_fp[diff[k, 3]:diff[k, 4]])
        for j in range(n):
            w[diff[k, 0], j] = q[j]
    lever = u_f.copy()
    for k in range(stuck.size):
        for j in range(n):
            lever[stuck[k], j] = stuck_lever[k, 0]
    n_fixed = C_fixed.shape[0]
    C = np.empty((n_fixed + valves.shape[0], n))
    for i in range(n_fixed):
        for j in range(n):
            C[i, j] = C_fixed[i, 0]
    for k in range(valves.shape[0]):                # as lever_conductance
        side = np.empty(n)
        for j in range(n):
            side[j] = valves[k, 2] * lever[valves[k, 0], j]
        xp, fp = valve_xp[valves[k, 3]:valves[k, 4]], valve_fp[valves[k, 3]:valves[k, 4]]
        c = np.interp(np.maximum(side, 0.0), xp, fp) * (side > 0.0)
        for j in range(n):
            C[valves[k, 1], j] = c[j]
    for k in range(orifices.shape[0]):              # as orifice_flow_kg_per_s
        ia, ib = orifices[k, 1], orifices[k, 2]
        for j in range(n):
            if p_n[ia, j] >= p_n[ib, j]:
                w[orifices[k, 0], j] = _iso6358(C[k, j], b_critical[k, 0], p_n[ia, j], T_n[ia, j], p_n[ib, j], rho_ref)
            else:
                w[orifices[k, 0], j] = -_iso6358(C[k, j], b_critical[k, 0], p_n[ib, j], T_n[ib, j], p_n[ia, j], rho_ref)
    for k in range(compressors.shape[0]):
        for j in range(n):
            w[compressors[k, 0], j] = x2[compressors[k, 1], j] * w_compressor[k, 0]
    for k in range(demands.shape[0]):               # as demand_flow_kg_per_s
        for j in range(n):
            w[demands[k, 0], j] = w_demand[k, 0] * _clip01((p_n[demands[k, 1], j] - p_atm) / dp_off[k, 0])
    for k in range(blocked.size):
        for j in range(n):
            w[blocked[k], j] = 0.0
    Hw = np.empty_like(w)
    for i in range(link_a.size):
        for j in range(n):
            Hw[i, j] = _enthalpy(w[i, j], T_n[link_a[i], j], T_n[link_b[i], j], cp)
    # the compressors' work: delivered x work per kg is +0 wherever nothing is delivered (w = +0)
    # and the reservoir's pressure is finite (the work per kg is then finite and >= +0)
    working = False
    for k in range(compressors.shape[0]):
        for j in range(n):
            delivered = w[compressors[k, 0], j]
            if not (delivered == 0.0 and math.copysign(1.0, delivered) > 0.0 and np.isfinite(p_n[compressors[k, 2], j])):
                working = True
    return V, p_n, T_n, rho_n, w, C, Hw, working


@arrays
def _rates(x2, mdot, p_n, rho_n, w, C_valve, n_open, nc, q0, pipe_a, pipe_b, pipe_L, pipe_A, pipe_K, blocked_pipes,
           through0, open0, governor0, run0, work0, compressors, w_iso, w_ad):
    """d(state)/dt's rows that depend on the state and the crushing only, but the boundary
    enthalpy (a matrix product): :meth:`CircuitRuntime._rates_at_crushing`. The other rows are
    left to be written."""
    n = x2.shape[1]
    dx = np.empty_like(x2)
    for i in range(nc):
        for j in range(n):
            dx[i, j] = mdot[i, j]
    for k in range(pipe_a.size):                    # eq. (5)
        for j in range(n):
            rho = 0.5 * (rho_n[pipe_a[k], j] + rho_n[pipe_b[k], j])
            dx[q0 + k, j] = _pipe_rate(x2[q0 + k, j], p_n[pipe_a[k], j], p_n[pipe_b[k], j], rho, pipe_L[k, 0],
                                       pipe_A[k, 0], pipe_K[k, 0])
    for k in range(blocked_pipes.size):
        for j in range(n):
            dx[q0 + blocked_pipes[k], j] = 0.0
    for i in range(w.shape[0]):
        for j in range(n):
            dx[through0 + i, j] = w[i, j]
    for i in range(n_open):                         # 1 while open, 0 when shut (C >= 0)
        for j in range(n):
            dx[open0 + i, j] = np.sign(C_valve[i, j])
    nk = compressors.shape[0]
    for k in range(nk):
        for j in range(n):
            dx[governor0 + k, j] = 0.0
            dx[run0 + k, j] = x2[compressors[k, 1], j]
            delivered = w[compressors[k, 0], j]
            dx[work0 + k, j] = delivered * w_iso[k, j]
            dx[work0 + nk + k, j] = delivered * w_ad[k, j]
    return dx


@arrays
def _temperatures(dx, x2, p, mdot, Hdot, Vdot, k_finite, isothermal, T_atm, cv, nc):
    """Write the chambers' temperature rates (eq. 2, the heat flow of eq. 8 or the isothermal
    one) into ``dx``; return the heat flows Qdot and p Vdot, (chambers, cases), for the sums of
    :meth:`CircuitRuntime._write_crushing_rate_terms`."""
    n = x2.shape[1]
    Qdot, pV = np.empty((nc, n)), np.empty((nc, n))
    for i in range(nc):
        for j in range(n):
            m, T, pc = x2[i, j], x2[nc + i, j], p[i, j]
            if isothermal[i, j]:                    # as isothermal_heat_flow_W
                Q = cv * T * mdot[i, j] - Hdot[i, j] + pc * Vdot[i, j]
            else:                                   # as heat_flow_into_W
                Q = k_finite[i, j] * (T_atm - T)
            Qdot[i, j] = Q
            dx[nc + i, j] = 0.0 if isothermal[i, j] else _temperature_rate(m, T, pc, mdot[i, j], Hdot[i, j], Q,
                                                                             Vdot[i, j], cv)
            pV[i, j] = pc * Vdot[i, j]
    return Qdot, pV


@arrays
def _bellow_laws(x2, held, half, V, z, m_rows, T_rows, R, p_atm, A0, dA_dz, A0_b, dA_dz_b, V0, dV_dz, n_poly):
    """Each bellow's force at ``x2`` and at ``x2 + half held`` (eq. 4) and its stiffness at ``x2``
    (:func:`pneumatics.chamber.bellow_stiffness_N_per_m`), (bellows, cases), ``V`` the bellows'
    volumes (V0 - Ez @ z); the areas (bellows, 1) as the forces take them (the chambers' A0,
    dA/dz) and as the stiffness does (the bellows' columns, with their V0 and dV/dz), no area
    tables."""
    nb, n = z.shape
    F, F_half, K = np.empty((nb, n)), np.empty((nb, n)), np.empty((nb, n))
    for i in range(nb):
        mr, tr = m_rows[i], T_rows[i]
        for j in range(n):
            A = A0[i, 0] + dA_dz[i, 0] * z[i, j]
            p = x2[mr, j] * R * x2[tr, j] / V[i, j]
            F[i, j] = A * (p - p_atm)
            p_half = (x2[mr, j] + half * held[mr, j]) * R * (x2[tr, j] + half * held[tr, j]) / V[i, j]
            F_half[i, j] = A * (p_half - p_atm)
            V_z = V0[i, 0] - dV_dz[i, 0] * z[i, j]
            A_b = A0_b[i, 0] + dA_dz_b[i, 0] * z[i, j]
            K[i, j] = dA_dz_b[i, 0] * (p - p_atm) + A_b * n_poly[i, j] * p * dV_dz[i, 0] / V_z
    return F, F_half, K


@arrays
def governors(x2, nc, reservoir, V0, R, cut_in, cut_out, governor0):
    """The governors' next states (compressors, cases) and whether one switched (as numpy's
    array_equal has it: a NaN state counts as switched): :func:`pneumatics.air_supply.governor`
    at each reservoir's pressure m R T / V0 in state ``x2``."""
    n = x2.shape[1]
    new = np.empty((reservoir.size, n))
    switched = False
    for k in range(reservoir.size):
        i = reservoir[k]
        for j in range(n):
            p = x2[i, j] * R * x2[nc + i, j] / V0[k, 0]
            running = x2[governor0 + k, j]
            if p <= cut_in[k, 0]:
                running = 1.0
            if p >= cut_out[k, 0]:
                running = 0.0
            new[k, j] = running
            if not running == x2[governor0 + k, j]:
                switched = True
    return new, switched


def _pairs(*columns) -> np.ndarray:
    """Integer rows of ``columns`` as a (rows, len(columns)) int64 array."""
    return np.ascontiguousarray(np.array(list(zip(*columns)), dtype=np.int64).reshape(-1, len(columns)))


def _rows(selection, n: int) -> np.ndarray:
    """A row selection (slice or index array) of ``n`` rows as an int64 index array."""
    return np.ascontiguousarray(np.arange(n)[selection], dtype=np.int64)


def _tables(groups, rows_of, n: int):
    """Rows (item, table start, table end) over the groups' (rows, xp, fp), and their tables
    concatenated (xp, fp)."""
    out, xp, fp, start = [], [], [], 0
    for rows, x, f in groups:
        for i in rows_of(rows, n):
            out.append((int(i), start, start + len(x)))
        xp.append(np.asarray(x, float))
        fp.append(np.asarray(f, float))
        start += len(x)
    cat = (lambda a: np.ascontiguousarray(np.concatenate(a)) if a else np.zeros(0))
    return out, cat(xp), cat(fp)


class FusedLaws:
    """The fused evaluation of ``runtime`` (a :class:`~pneumatics.runtime.CircuitRuntime`), or
    :func:`fused_laws` says it has none."""

    def __init__(self, runtime):
        lay = runtime.layout
        a = runtime.assembly
        nodes, links, orifices, valves, air = a.nodes, a.links, a.orifice_links, a.valves, a.air_supply
        nl, nv = len(links.names), len(runtime.valve_names)
        self.nc = lay.n_chambers
        link_a, link_b = np.asarray(links.a, dtype=np.int64), np.asarray(links.b, dtype=np.int64)
        pipes = a.pipes
        pipe_links = _rows(pipes.links, nl)
        diff_rows, self._diff_xp, self._diff_fp = [], [], []
        start = 0
        for rows, ia, ib, xp, fp in a.differential_valves.tables:
            for r, i, j in zip(_rows(rows, nl), np.atleast_1d(np.arange(len(nodes.names))[ia]),
                               np.atleast_1d(np.arange(len(nodes.names))[ib])):
                diff_rows.append((int(r), int(i), int(j), start, start + len(xp)))
            self._diff_xp.append(np.asarray(xp, float))
            self._diff_fp.append(np.asarray(fp, float))
            start += len(xp)
        diff_xp = np.ascontiguousarray(np.concatenate(self._diff_xp)) if self._diff_xp else np.zeros(0)
        diff_fp = np.ascontiguousarray(np.concatenate(self._diff_fp)) if self._diff_fp else np.zeros(0)
        n_fixed = orifices.n_fixed
        sides = []
        for groups, sign, offset in ((valves.supply_tables, 1.0, n_fixed), (valves.exhaust_tables, -1.0, n_fixed + nv)):
            rows, xp, fp = _tables(groups, _rows, nv)
            sides.append(([(v, offset + v, sign, s, e) for v, s, e in rows], xp, fp))
        shift = len(sides[0][1])
        valve_rows = sides[0][0] + [(v, o, sg, s + shift, e + shift) for v, o, sg, s, e in sides[1][0]]
        valve_xp = np.ascontiguousarray(np.concatenate([sides[0][1], sides[1][1]]))
        valve_fp = np.ascontiguousarray(np.concatenate([sides[0][2], sides[1][2]]))
        active = a.active
        stuck = np.zeros(0, np.int64) if active.stuck_valves is None else np.asarray(active.stuck_valves, np.int64)
        orifice_links = _rows(orifices.links, nl)
        n_orifices = orifice_links.size
        orifice_rows = _pairs(orifice_links, link_a[orifice_links], link_b[orifice_links]) if n_orifices else \
            np.zeros((0, 3), np.int64)
        governor_rows = np.arange(lay.size)[lay.governor]
        compressor_links = _rows(air.compressor_links, nl)
        compressors = _pairs(compressor_links, governor_rows, np.asarray(air.reservoir, np.int64).reshape(-1)) \
            if compressor_links.size else np.zeros((0, 3), np.int64)
        demand_links = _rows(air.demand_links, nl)
        demands = _pairs(demand_links, np.asarray(air.demand_node, np.int64)) if demand_links.size else \
            np.zeros((0, 2), np.int64)
        blocked = np.zeros(0, np.int64) if active.blocked_links is None else np.asarray(active.blocked_links, np.int64)
        gas = runtime.gas
        self._flow_args = (
            np.ascontiguousarray(runtime._chambers.V0_m3), gas.R_J_per_kgK, gas.cp_J_per_kgK, gas.rho_ref_kg_per_m3,
            float(runtime.atmosphere.p_Pa))
        self._flow_tail = (
            self.nc, lay.q.start, lay.q.stop - lay.q.start, link_a, link_b, pipe_links,
            np.array(diff_rows, dtype=np.int64).reshape(-1, 5), diff_xp, diff_fp,
            np.array([(v, o, int(sg), s, e) for v, o, sg, s, e in valve_rows], dtype=np.int64).reshape(-1, 5),
            valve_xp, valve_fp, stuck, np.ascontiguousarray(active.stuck_lever_m, dtype=float).reshape(-1, 1),
            orifice_rows, np.ascontiguousarray(orifices.b_critical, dtype=float))
        self._air_args = (compressors, np.ascontiguousarray(air.w_compressor_kg_per_s, dtype=float).reshape(-1, 1),
                          demands, np.ascontiguousarray(air.w_demand_kg_per_s, dtype=float).reshape(-1, 1),
                          np.ascontiguousarray(air.dp_off_Pa, dtype=float).reshape(-1, 1), blocked)
        self._fixed_C = np.ascontiguousarray(orifices.fixed_C_m3_per_sPa, dtype=float).reshape(-1, 1)
        blocked_pipes = np.zeros(0, np.int64) if active.blocked_pipes is None else np.asarray(active.blocked_pipes, np.int64)
        self._rate_args = (self.nc, lay.q.start, np.asarray(np.arange(len(nodes.names))[pipes.a], np.int64).reshape(-1),
                           np.asarray(np.arange(len(nodes.names))[pipes.b], np.int64).reshape(-1),
                           np.ascontiguousarray(pipes.length_m, dtype=float).reshape(-1, 1),
                           np.ascontiguousarray(pipes.area_m2, dtype=float).reshape(-1, 1),
                           np.ascontiguousarray(pipes.loss_coefficient, dtype=float).reshape(-1, 1), blocked_pipes,
                           lay.mass_through.start, lay.open_time.start, lay.governor.start, lay.run_time.start,
                           lay.compression_work.start, compressors)
        self._n_open = 2 * nv
        self._heat = {}                      # n_cases -> (k_finite, isothermal) as (chambers, cases)
        self._runtime_heat = a.heat

    def evaluate(self, x2: np.ndarray, EzZ: np.ndarray, u_f: np.ndarray, p_bnd: np.ndarray, T_bnd: np.ndarray):
        """(V, p_n, T_n, rho_n, w, C, Hw, working): :func:`_flows`; ``working``: a compressor
        delivers (or its reservoir's pressure is not finite), else the compression work's rates
        are +0 whatever the work per kg (:meth:`CircuitRuntime._rates_fused` skips it)."""
        R, cp, rho_ref = self._flow_args[1:4]
        V0, p_atm = self._flow_args[0], self._flow_args[4]
        return _flows(x2, EzZ, u_f, V0, R, cp, rho_ref, p_atm, p_bnd, T_bnd, *self._flow_tail, self._fixed_C,
                      *self._air_args)

    def rates(self, x2, mdot, p_n, rho_n, w, C_valve, w_iso, w_ad) -> np.ndarray:
        """:func:`_rates` (``C_valve``: the valves' sides' conductances; ``w_iso``, ``w_ad``: the
        compressors' work per kg, (compressors, cases))."""
        return _rates(x2, mdot, p_n, rho_n, w, C_valve, self._n_open, *self._rate_args, w_iso, w_ad)

    def temperatures(self, dx, x2, p, mdot, Hdot, Vdot, T_atm: float, cv: float):
        """:func:`_temperatures`, the heat exchange laid out per chamber and case (cached)."""
        n = x2.shape[1]
        heat = self._heat.get(n)
        if heat is None:
            h = self._runtime_heat
            heat = self._heat[n] = (np.ascontiguousarray(np.broadcast_to(h.k_finite_W_per_K, (self.nc, n)), dtype=float),
                                    np.ascontiguousarray(np.broadcast_to(h.isothermal, (self.nc, n)), dtype=np.bool_))
        return _temperatures(dx, x2, p, mdot, Hdot, Vdot, heat[0], heat[1], T_atm, cv, self.nc)


class FusedBellows:
    """The bellows' force laws of ``runtime`` compiled (:func:`_bellow_laws`), for bellows
    without area tables."""

    def __init__(self, runtime):
        chambers = runtime._chambers
        b = chambers.bellow_columns
        col = (lambda v: np.ascontiguousarray(np.broadcast_to(v, (len(runtime.bellow_names), 1)), dtype=float))
        self._rows = (np.asarray(runtime._bellow_m_rows, np.int64), np.asarray(runtime._bellow_T_rows, np.int64),
                      runtime.gas.R_J_per_kgK, float(runtime.atmosphere.p_Pa), col(chambers.A0_m2), col(chambers.dA_dz_m),
                      col(b.A0_m2), col(b.dA_dz_m), col(b.V0_m3), col(b.dV_dz_m2))
        self._index = runtime._polytropic_index
        self._n_poly = {}                    # n_cases -> the polytropic index (bellows, cases)

    def laws(self, x2, held2, half: float, V, z2):
        """(F(x), F(x + half held), dF/dz(x)), each (bellows, cases)."""
        n = x2.shape[1]
        n_poly = self._n_poly.get(n)
        if n_poly is None:
            n_poly = self._n_poly[n] = np.ascontiguousarray(np.broadcast_to(self._index, z2.shape), dtype=float)
        return _bellow_laws(x2, held2, half, V, z2, *self._rows, n_poly)


def fused_laws(runtime) -> Optional[FusedLaws]:
    """The fused evaluation of ``runtime``, or None for a circuit it does not cover (compressible or
    quasi-steady pipes, heat correlations)."""
    a = runtime.assembly
    pipes = a.pipes
    if pipes.cells is not None or pipes.choked is not None or pipes.reynolds is not None or a.quasi_steady_pipes.count \
            or a.heat.correlations or a.chambers.pipe_cells is not None:
        return None
    return FusedLaws(runtime)
