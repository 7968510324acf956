"""The circuit's advance over a macro-step as one compiled call (:class:`CompiledStep`): every RK4
sub-step of :func:`pneumatics.integrate.rk4`, each stage's evaluation of d(state)/dt
(:meth:`CircuitRuntime.derivatives` by the fused laws) and the bellows' cubic Hermite motion
(:func:`pneumatics.integrate.hermite_motion`), for the circuits :func:`pneumatics.fused.fused_laws`
covers; :func:`pneumatics.integrate.advance` takes it when its motion is a Hermite one.

Why: after the fusion of the elementwise laws (:mod:`pneumatics.fused`) an evaluation still made
~15 numpy calls (matrix products with the volume, lever and incidence matrices, sums over the
chambers, RK4's stage combinations, the motion's terms) of ~1 us each on arrays of a few numbers:
~300 us of a service's 5 ms macro-step for two cars, more than all the laws' arithmetic. Here they
are loops in the same compiled function that calls the fused laws themselves (the very Python
functions :mod:`pneumatics.fused` and :mod:`pneumatics.valve_signals` compile, registered as
helpers: no law is written twice).

The numbers: every elementwise operation is the present path's, in its order (RK4's combinations,
the motion's terms, the laws); the sums over the chambers are numpy's own orders (:func:`_column_sum`).
What differs is the matrix products: numpy hands them to BLAS, whose kernels sum in their own
order and with fused multiply-adds (which depends on the machine); here each is summed over its
terms in order. Products whose terms are exact (the incidence's +-1, a volume row's single bellow)
are the same; a lever's mean of two bellows' crushing and the like differ in the last bit, and so
do the states after it, at round-off (tests/pneumatics/test_compiled_step.py bounds them;
docs/service.md gives the shipped scenarios' outputs against the numpy path). The compression
work's log and power are numba's (libm) rather than numpy's own, equal to within an ulp.
"""
from __future__ import annotations

from typing import Optional

import numpy as np

from .air_supply import compression_work
from .compiled import arrays, scalar
from .fused import _flows, _rates, _temperatures, governors
from .integrate import _hermite_z, _hermite_zd, _rk4_stage, _rk4_step, hermite_coefficients
from .valve_signals import _chain
from .valve_signals import _rates as _signal_rates

# the laws the present path calls compiled one by one, here compiled into the step itself
_flows_law = scalar(_flows.py_func)
_rates_law = scalar(_rates.py_func)
_temperatures_law = scalar(_temperatures.py_func)
_governors_law = scalar(governors.py_func)
_chain_law = scalar(_chain.py_func)
_signal_rates_law = scalar(_signal_rates.py_func)
# and rk4's: its stage and step combinations (elementwise laws), the motion's terms
_stage_law, _step_law = scalar(_rk4_stage.py_func), scalar(_rk4_step.py_func)
_hermite_z_law, _hermite_zd_law = scalar(_hermite_z.py_func), scalar(_hermite_zd.py_func)


@scalar
def _matmul(A, B):
    """A @ B, each element summed over its terms in order from +0 (BLAS's order and fused
    multiply-adds may differ in the last bit)."""
    rows, inner = A.shape
    n = B.shape[1]
    out = np.empty((rows, n))
    for i in range(rows):
        for j in range(n):
            acc = 0.0
            for k in range(inner):
                acc += A[i, k] * B[k, j]
            out[i, j] = acc
    return out


@scalar
def _pairwise(a, n):
    """numpy's pairwise sum of a[:n, 0] (its reduction of one contiguous column) for n <= 128:
    beyond, numpy splits it in halves (:func:`compiled_step` leaves such circuits to numpy)."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[i, 0]
        return res
    r = np.empty(8)
    for k in range(8):
        r[k] = a[k, 0]
    i = 8
    while i < n - n % 8:
        for k in range(8):
            r[k] += a[i + k, 0]
        i += 8
    res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
    while i < n:
        res += a[i, 0]
        i += 1
    return res


@scalar
def _column_sum(a):
    """np.add.reduce(a, axis=0) as numpy orders it: from +0, one column pairwise, several row by
    row (what :meth:`CircuitRuntime._write_crushing_rate_terms` sums the heat and work with)."""
    rows, n = a.shape
    out = np.zeros(n)
    if n == 1:
        out[0] = 0.0 + _pairwise(a, rows)
        return out
    for i in range(rows):
        for j in range(n):
            out[j] += a[i, j]
    return out


@scalar
def _at_crushing(x2, z2, geometry, flow, air, rates, heat, signals):
    """The rows of d(state)/dt that depend on the state and the crushing only, and the terms the
    others need: :meth:`CircuitRuntime._rates_at_crushing` by the fused laws, the matrix products
    summed here. (dx, (p_n, mdot, Hdot), (u, u_p, u_d))."""
    Ez, minus_Ez, lever, lever_play, incidence, boundary_sign = geometry
    (V0, R, cp, rho_ref, p_atm, p_bnd, T_bnd, nc, q0, nq, link_a, link_b, pipe_links, diff, diff_xp, diff_fp,
     valves, valve_xp, valve_fp, stuck, stuck_lever, orifices, b_critical, C_fixed, n_fixed) = flow
    compressors, w_compressor, demands, w_demand, dp_off, blocked, reservoir, T_atm, gamma = air
    (n_open, nc_, q0_, pipe_a, pipe_b, pipe_L, pipe_A, pipe_K, blocked_pipes, through0, open0, governor0, run0, work0,
     compressors_) = rates
    enthalpy_in = heat[4]
    dynamics, s0, s1, chain = signals[0], signals[1], signals[2], signals[3]
    n = x2.shape[1]
    u = _matmul(lever, z2)
    u_p, u_d, u_f = u, u, u
    if dynamics:
        u_p, u_d, u_f = _chain_law(u, x2[s0:s1], *chain)
    V, p_n, T_n, rho_n, w, C, Hw, working = _flows_law(
        x2, _matmul(Ez, z2), u_f, V0, R, cp, rho_ref, p_atm, p_bnd, T_bnd, nc, q0, nq, link_a, link_b, pipe_links,
        diff, diff_xp, diff_fp, valves, valve_xp, valve_fp, stuck, stuck_lever, orifices, b_critical, C_fixed,
        compressors, w_compressor, demands, w_demand, dp_off, blocked)
    mdot = _matmul(incidence, w)                                        # eq. (1)
    Hdot = _matmul(incidence, Hw)
    nk = compressors.shape[0]
    if nk and working:
        w_iso, w_ad = compression_work(p_n[reservoir], p_atm, T_atm, R, cp, gamma)
    else:                        # nothing delivered: the work's rates are +0 x (finite, >= 0) = +0
        w_iso, w_ad = np.zeros((nk, n)), np.zeros((nk, n))
    dx = _rates_law(x2, mdot, p_n, rho_n, w, C[n_fixed:], n_open, nc_, q0_, pipe_a, pipe_b, pipe_L, pipe_A, pipe_K,
                    blocked_pipes, through0, open0, governor0, run0, work0, compressors_, w_iso, w_ad)
    for j in range(n):
        acc = 0.0
        for k in range(boundary_sign.size):
            acc += boundary_sign[k] * Hw[k, j]
        dx[enthalpy_in, j] = acc
    return dx, (p_n, mdot, Hdot), (u, u_p, u_d)


@scalar
def _crushing_rate_terms(dx, x2, zd2, terms, chain, geometry, flow, air, heat, signals):
    """Write the rows of d(state)/dt the crushing rate ``zd2`` enters (temperatures, heat and
    work, valve signals): :meth:`CircuitRuntime._write_crushing_rate_terms` by the fused laws."""
    minus_Ez, lever_play = geometry[1], geometry[3]
    nc, T_atm = flow[7], air[7]
    k_finite, isothermal, cv, heat_in = heat[0], heat[1], heat[2], heat[3]
    dynamics, s0, s1, signal_rates = signals[0], signals[1], signals[2], signals[4]
    p_n, mdot, Hdot = terms
    u, u_p, u_d = chain
    n = x2.shape[1]
    Qdot, pV = _temperatures_law(dx, x2, p_n[:nc], mdot, Hdot, _matmul(minus_Ez, zd2), k_finite, isothermal, T_atm,
                                 cv, nc)
    heat_sum, work_sum = _column_sum(Qdot), _column_sum(pV)
    for j in range(n):
        dx[heat_in, j] = heat_sum[j]
        dx[heat_in + 1, j] = -work_sum[j]
    if dynamics:
        rate = _signal_rates_law(x2[s0:s1], u, u_p, u_d, _matmul(lever_play, zd2), *signal_rates)
        for i in range(s1 - s0):
            for j in range(n):
                dx[s0 + i, j] = rate[i, j]


@scalar
def _derivatives(x2, z2, zd2, geometry, flow, air, rates, heat, signals):
    """d(state)/dt at state ``x2``, crushing ``z2`` and its rate ``zd2`` (each 2-D, cases last):
    :meth:`CircuitRuntime.derivatives` by the fused laws."""
    dx, terms, chain = _at_crushing(x2, z2, geometry, flow, air, rates, heat, signals)
    _crushing_rate_terms(dx, x2, zd2, terms, chain, geometry, flow, air, heat, signals)
    return dx


@arrays
def _derivatives_and_held(x2, z2, zd2, geometry, flow, air, rates, heat, signals):
    """(d(state)/dt, d(state)/dt at zero crushing rate) from one evaluation:
    :meth:`CircuitRuntime.derivatives_and_held` by the fused laws."""
    dx, terms, chain = _at_crushing(x2, z2, geometry, flow, air, rates, heat, signals)
    held = dx.copy()
    _crushing_rate_terms(dx, x2, zd2, terms, chain, geometry, flow, air, heat, signals)
    _crushing_rate_terms(held, x2, np.zeros_like(zd2), terms, chain, geometry, flow, air, heat, signals)
    return dx, held


@scalar
def _motion(t, t0, H, z0, dz, zd0, zd1):
    """(z, zdot) of :class:`pneumatics.integrate.HermiteMotion` at ``t``: its coefficients and
    terms (the same functions)."""
    c_dz, c_zd0, c_zd1, d_dz, d_zd0, d_zd1 = hermite_coefficients((t - t0) / H, H)
    return _hermite_z_law(z0, dz, zd0, zd1, c_dz, c_zd0, c_zd1), _hermite_zd_law(dz, zd0, zd1, d_dz, H, d_zd0, d_zd1)


@scalar
def _stage(x, c, k):
    """x + c k, RK4's stage state (pneumatics.integrate._rk4_stage, element by element)."""
    out = np.empty_like(x)
    for i in range(x.shape[0]):
        for j in range(x.shape[1]):
            out[i, j] = _stage_law(x[i, j], c, k[i, j])
    return out


@arrays
def _advance(x, t0, t1, n_steps, rate0, has_rate0, m_t0, H, z0, dz, zd0, zd1, geometry, flow, air, rates, heat, signals,
             governed):
    """:func:`pneumatics.integrate.rk4` of the circuit over [t0, t1] in ``n_steps`` steps along
    the Hermite motion (m_t0, H, z0, dz, zd0, zd1); ``rate0`` its first stage if ``has_rate0``;
    ``governed``: (compressors?, nc, reservoir, V0, R, cut_in, cut_out, governor0), switched after
    every step as :meth:`CircuitRuntime.update_governors`."""
    h = (t1 - t0) / n_steps
    half, h6 = 0.5 * h, h / 6.0
    has_governors, nc, reservoir, V0r, R, cut_in, cut_out, g0 = governed
    for i in range(n_steps):
        t = t0 if i == 0 else t0 + i * h
        if i == 0 and has_rate0:
            k1 = rate0
        else:
            z, zd = _motion(t, m_t0, H, z0, dz, zd0, zd1)
            k1 = _derivatives(x, z, zd, geometry, flow, air, rates, heat, signals)
        z, zd = _motion(t + half, m_t0, H, z0, dz, zd0, zd1)
        k2 = _derivatives(_stage(x, half, k1), z, zd, geometry, flow, air, rates, heat, signals)
        k3 = _derivatives(_stage(x, half, k2), z, zd, geometry, flow, air, rates, heat, signals)
        z, zd = _motion(t + h, m_t0, H, z0, dz, zd0, zd1)
        k4 = _derivatives(_stage(x, h, k3), z, zd, geometry, flow, air, rates, heat, signals)
        new = np.empty_like(x)
        for r in range(x.shape[0]):
            for j in range(x.shape[1]):
                new[r, j] = _step_law(x[r, j], k1[r, j], k2[r, j], k3[r, j], k4[r, j], h6)
        if has_governors:
            states, switched = _governors_law(new, nc, reservoir, V0r, R, cut_in, cut_out, g0)
            if switched:
                for k in range(states.shape[0]):
                    for j in range(x.shape[1]):
                        new[g0 + k, j] = states[k, j]
        x = new
    return x


def _c(v, dtype=float) -> np.ndarray:
    """``v`` as a writable C-contiguous array of ``dtype`` (one compiled specialization for all)."""
    return np.array(v, dtype=dtype, order="C")


def _input(v, shape) -> np.ndarray:
    """``v`` as a writable C-contiguous float array of ``shape`` (a 1-D input one column, a
    column broadcast over the cases): itself when it is one already (the co-simulation's)."""
    if type(v) is np.ndarray and v.shape == shape and v.dtype == np.float64 and v.flags.c_contiguous \
            and v.flags.writeable:
        return v
    return _c(np.broadcast_to(np.reshape(v, (shape[0], -1)), shape))


class CompiledStep:
    """The macro-step of ``runtime`` (a :class:`~pneumatics.runtime.CircuitRuntime` whose fused
    laws exist) as one call of :func:`_advance`; its arrays looked up once, per number of cases."""

    def __init__(self, runtime, fused):
        lay, a = runtime.layout, runtime.assembly
        self._size, self._nb = lay.size, len(runtime.bellow_names)
        self._runtime, self._fused, self._per_cases = runtime, fused, {}
        chambers, valves, links = a.chambers, a.valves, a.links
        self._geometry = (_c(chambers.Ez_m2), _c(-chambers.Ez_m2), _c(valves.lever).reshape(-1, self._nb),
                          _c(valves.lever_play).reshape(-1, self._nb), _c(links.incidence), _c(links.boundary_sign))
        air, gas = a.air_supply, runtime.gas
        self._air = (*fused._air_args, _c(np.asarray(air.reservoir).reshape(-1), np.int64),
                     float(runtime.atmosphere.T_K), float(gas.gamma))
        self._rates = (fused._n_open, *fused._rate_args)
        signals = runtime._signals
        if signals is not None:
            self._signals = (True, lay.valve_signal.start, lay.valve_signal.stop, signals.chain, signals.rates)
        else:                                # typed empty stand-ins: the branch is not taken
            i, f = np.zeros(0, np.int64), np.zeros((0, 1))
            self._signals = (False, 0, 0, (i, i, f, i, i, i, i), (i, i, f, i, i, i, f, i, i, f))
        self._governed = (bool(air.n_compressors), lay.n_chambers, runtime._reservoirs, runtime._reservoir_V0,
                          float(gas.R_J_per_kgK), _c(air.p_cut_in_Pa).reshape(-1, 1),
                          _c(air.p_cut_out_Pa).reshape(-1, 1), lay.governor.start)

    def _arguments(self, n: int):
        """(flow, heat) of ``n`` cases (cached): the boundary nodes' states and the heat exchange
        laid out per case."""
        args = self._per_cases.get(n)
        if args is None:
            rt, fused = self._runtime, self._fused
            p_bnd, T_bnd, _ = rt._boundary(n)
            V0, R, cp, rho_ref, p_atm = fused._flow_args
            flow = (V0, R, cp, rho_ref, p_atm, _c(p_bnd), _c(T_bnd), *fused._flow_tail, fused._fixed_C,
                    rt._orifices.n_fixed if rt._n_orifice_rows else 0)
            h, lay = rt._heat, rt.layout
            heat = (_c(np.broadcast_to(h.k_finite_W_per_K, (lay.n_chambers, n))),   # as FusedLaws.temperatures
                    _c(np.broadcast_to(h.isothermal, (lay.n_chambers, n)), np.bool_), float(rt._cv), lay.heat_in,
                    lay.enthalpy_in)
            args = self._per_cases[n] = (flow, heat)
        return args

    def advance(self, x, t0_s: float, t1_s: float, n_steps: int, motion, rate0: Optional[np.ndarray]) -> np.ndarray:
        """``x`` advanced from t0 to t1 by :func:`pneumatics.integrate.rk4` in ``n_steps`` along
        ``motion`` (a :class:`pneumatics.integrate.HermiteMotion`), ``rate0`` its first stage if
        given: the present path's numbers but for the matrix products' round-off (module docstring)."""
        x2 = _input(x, (self._size, x.size // self._size))
        shape = (self._nb, x2.shape[1])
        flow, heat = self._arguments(shape[1])
        has_rate0 = rate0 is not None
        out = _advance(x2, float(t0_s), float(t1_s), int(n_steps), _input(rate0, x2.shape) if has_rate0 else x2,
                       has_rate0, float(motion.t0), float(motion.H), _input(motion.z0, shape), _input(motion.dz, shape),
                       _input(motion.zd0, shape), _input(motion.zd1, shape), self._geometry, flow, self._air,
                       self._rates, heat, self._signals, self._governed)
        return out.reshape(x.shape)

    def derivatives_and_held(self, x, z_m, zdot_m_per_s):
        """:meth:`CircuitRuntime.derivatives_and_held` in one compiled call (the co-simulation's
        force laws and RK4's first stage at the start of every macro-step): the present path's
        numbers but for the matrix products' round-off."""
        x2 = _input(x, (self._size, x.size // self._size))
        shape = (self._nb, x2.shape[1])
        flow, heat = self._arguments(shape[1])
        dx, held = _derivatives_and_held(x2, _input(z_m, shape), _input(zdot_m_per_s, shape), self._geometry, flow,
                                         self._air, self._rates, heat, self._signals)
        return dx.reshape(x.shape), held.reshape(x.shape)


#: beyond this many chambers numpy's sum of one case's heat flows splits them in halves, which
#: :func:`_pairwise` does not (no circuit of this project comes near it)
MAX_CHAMBERS = 128


def compiled_step(runtime) -> Optional[CompiledStep]:
    """The compiled macro-step of ``runtime``, or None where its evaluation is not fused (the
    circuits :func:`pneumatics.fused.fused_laws` does not cover), it has no bellows or more than
    :data:`MAX_CHAMBERS` chambers."""
    fused = runtime._fused
    if fused is None or not len(runtime.bellow_names) or runtime.layout.n_chambers > MAX_CHAMBERS:
        return None
    return CompiledStep(runtime, fused)
