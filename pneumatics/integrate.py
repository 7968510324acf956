"""Time integration of a circuit driven by prescribed bellow motion.

Two integrators serve different needs:

* :func:`advance` - classical fixed-step RK4 over one interval, the co-simulation's macro-step.
  It is cheap per call (no start-up cost) and, batched over cases, advances many circuits at once.
  The step must resolve the fastest pneumatic dynamics: the pipe's air-inertia mode (~10-15 Hz
  here) and, for large k, the thermal rate k/(m c_v) (~230 1/s for a 12 dm^3 bellow at k = 1e4).
  :func:`stable_step_s` picks a step from those rates.
* :func:`simulate` - scipy's adaptive integrators with error control, the reference for tests and
  for standalone rig runs.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Callable, Tuple

import numpy as np

from .compiled import arrays, elementwise, scalar
from .errors import CircuitError

if TYPE_CHECKING:        # runtime -> compiled_step imports this module: Circuit for the annotations only
    from .circuit import Circuit

#: motion(t_s) -> (z_m, zdot_m_per_s), each shaped (bellows,) or (bellows, cases)
Motion = Callable[[float], Tuple[np.ndarray, np.ndarray]]


@arrays
def _hermite_z(z0, dz, zd0, zd1, c_dz, c_zd0, c_zd1):
    """z0 + c_dz dz + c_zd0 zd0 + c_zd1 zd1, added in this order."""
    return z0 + c_dz * dz + c_zd0 * zd0 + c_zd1 * zd1


@arrays
def _hermite_zd(dz, zd0, zd1, c_dz, H, c_zd0, c_zd1):
    """c_dz dz / H + c_zd0 zd0 + c_zd1 zd1, added in this order."""
    return c_dz * dz / H + c_zd0 * zd0 + c_zd1 * zd1


@scalar
def hermite_coefficients(s, H):
    """The Hermite motion's coefficients at s = (t - t0) / H: z's of dz, zd0, zd1, then zd's of
    dz (before its / H), zd0, zd1 (:class:`HermiteMotion`; the compiled macro-step's too)."""
    s2, s3 = s * s, s * s * s
    return 3 * s2 - 2 * s3, (s - 2 * s2 + s3) * H, (s3 - s2) * H, 6 * s - 6 * s2, 1 - 4 * s + 3 * s2, 3 * s2 - 2 * s


class HermiteMotion:
    """Cubic Hermite interpolation of the crushing over [t0, t1]: matches z and dz/dt at both ends
    (the co-simulation master's motion over a macro-step; the exported FMU's with ``lookahead``).

    z = z0 + (3 s^2 - 2 s^3) dz + (s - 2 s^2 + s^3) H zd0 + (s^3 - s^2) H zd1,
    zd = (6 s - 6 s^2) dz / H + (1 - 4 s + 3 s^2) zd0 + (3 s^2 - 2 s) zd1, s = (t - t0) / H,
    dz = z1 - z0: the coefficients are floats, the terms over the bellows compiled
    (:mod:`pneumatics.compiled`: a call per stage of the integrator instead of a numpy operation
    per term, the same operations in the same order; functions of arrays, not ufuncs: they load
    in a few ms, a ufunc in ~60 ms). A motion of its own type (not a closure) so that
    :func:`advance` can hand its parameters to the compiled macro-step
    (:mod:`pneumatics.compiled_step`), which evaluates it the same way."""

    __slots__ = ("t0", "H", "z0", "dz", "zd0", "zd1")

    def __init__(self, t0: float, t1: float, z0, zd0, z1, zd1):
        self.t0, self.H, self.z0, self.dz, self.zd0, self.zd1 = t0, t1 - t0, z0, z1 - z0, zd0, zd1

    def __call__(self, t):
        t0, H, z0, dz, zd0, zd1 = self.t0, self.H, self.z0, self.dz, self.zd0, self.zd1
        c_dz, c_zd0, c_zd1, d_dz, d_zd0, d_zd1 = hermite_coefficients((t - t0) / H, H)
        return _hermite_z(z0, dz, zd0, zd1, c_dz, c_zd0, c_zd1), _hermite_zd(dz, zd0, zd1, d_dz, H, d_zd0, d_zd1)


def hermite_motion(t0: float, t1: float, z0, zd0, z1, zd1) -> HermiteMotion:
    """The crushing's cubic Hermite interpolation over [t0, t1] (:class:`HermiteMotion`)."""
    return HermiteMotion(t0, t1, z0, zd0, z1, zd1)


@elementwise(3)
def _rk4_stage(x, c, k):
    """x + c k: a stage's state (c = h/2 or h)."""
    return x + c * k


@elementwise(6)
def _rk4_step(x, k1, k2, k3, k4, h6):
    """x + h6 (k1 + 2 (k2 + k3) + k4): the step's new state (h6 = h/6)."""
    return x + h6 * (k1 + 2.0 * (k2 + k3) + k4)


#: RK4's step for the compressible pipes' fastest (undamped) wave, h omega_max with omega_max =
#: 2 c / dx = c / l_end: RK4 is stable on the imaginary axis up to 2.83, and its amplitude error
#: per step there is (h omega)^6 / 144 (1.8e-3 at 1.2 for a mode that is numerical noise anyway)
ACOUSTIC_COURANT = 1.2


def stable_step_s(circuit: Circuit, x: np.ndarray, h_max_s: float = 1e-3, courant: float = 1.5) -> float:
    """A fixed RK4 step that keeps the thermal relaxation stable: h <= courant / max(k / (m c_v)).

    RK4's stability limit is |h lambda| < 2.78 on the real axis. At ``courant`` = 1.5 a step damps
    that mode by 0.27 instead of exp(-1.5) = 0.22: a fast transient decaying a little slower, with
    the slow thermal state itself unaffected. ``h_max_s`` bounds the step for the pipe mode; a
    compressible pipe's fastest wave bounds it too (:data:`ACOUSTIC_COURANT`); its cells, which
    exchange no heat, do not count in the thermal rate. A correlation's k (a chamber's own law,
    :mod:`pneumatics.heat_transfer`) counts at ``x``, the crushing at 0 (a few W/K: its rate is far
    below the finite k of the cases a step must resolve).
    """
    heat = circuit.assembly.heat
    k = heat.k_finite_W_per_K
    if heat.correlations:
        z = np.zeros((len(circuit.bellow_names),) + x.shape[1:])
        k = np.where(heat.isothermal, 0.0, circuit.heat_conductances_W_per_K(x, z))
    ends, cells = circuit.assembly.pipes.choked, circuit.assembly.chambers.pipe_cells
    if ends is not None:                     # compressible pipes: their fastest wave, 2 c / dx
        gas = circuit.gas
        T = np.max(x[circuit.layout.T][cells])
        h_max_s = min(h_max_s, ACOUSTIC_COURANT * np.min(ends.length_m) / math.sqrt(gas.gamma * gas.R_J_per_kgK * T))
    if not np.any(k > 0):
        return h_max_s
    m = x[circuit.layout.m]
    if cells is not None:                    # the cells exchange no heat
        m = np.delete(m, cells, axis=0)
    rate = np.max(np.asarray(k) / (np.min(m) * circuit.gas.cv_J_per_kgK))
    return min(h_max_s, courant / rate)


def rk4(f: Callable[[float, np.ndarray], np.ndarray], x: np.ndarray, t0_s: float, t1_s: float, n_steps: int,
        observe: Callable[[float, np.ndarray], None] | None = None, rate0: np.ndarray | None = None,
        switch: Callable[[np.ndarray], np.ndarray] | None = None) -> np.ndarray:
    """Classical fixed-step RK4 of dx/dt = f(t, x) over [t0, t1] in ``n_steps`` equal steps.

    ``observe(t, x)`` is called after every step (for recording a trajectory). ``rate0``, if given,
    must be f(t0, x): the first stage of the first step takes it instead of evaluating f again.
    ``switch(x)``: the discrete states switched after every step (the compressors' governors);
    when it switches one, the next step's first stage is evaluated afresh.
    """
    h = (t1_s - t0_s) / n_steps
    t = t0_s
    for i in range(n_steps):
        # the numpy expressions x + 0.5 h k1, ..., x + (h / 6) (k1 + 2 (k2 + k3) + k4), compiled
        # (:mod:`pneumatics.compiled`: the same operations in the same order, one call each)
        k1 = rate0 if i == 0 and rate0 is not None else f(t, x)
        k2 = f(t + 0.5 * h, _rk4_stage(x, 0.5 * h, k1))
        k3 = f(t + 0.5 * h, _rk4_stage(x, 0.5 * h, k2))
        k4 = f(t + h, _rk4_stage(x, h, k3))
        x = _rk4_step(x, k1, k2, k3, k4, h / 6.0)
        if switch is not None:
            x = switch(x)
        t = t0_s + (i + 1) * h
        if observe is not None:
            observe(t, x)
    return x


def circuit_rhs(circuit: Circuit, motion: Motion) -> Callable[[float, np.ndarray], np.ndarray]:
    """dx/dt = f(t, x) of ``circuit`` driven by ``motion`` (evaluated once per time: RK4's second
    and third stages share theirs)."""
    last = [None, None]

    def f(t, x):
        if last[0] != t:
            last[0], last[1] = t, motion(t)
        z, zd = last[1]
        return circuit.derivatives(x, z, zd)
    return f


def advance(circuit: Circuit, x: np.ndarray, t0_s: float, t1_s: float, motion: Motion, h_max_s: float = 1e-3,
            rate0: np.ndarray | None = None) -> np.ndarray:
    """Integrate from t0 to t1 with classical RK4 in equal sub-steps no longer than ``h_max_s``.
    ``rate0``: the derivative at (t0, x) under ``motion(t0)``, if already known (see :func:`rk4`)."""
    n = max(1, math.ceil((t1_s - t0_s) / h_max_s - 1e-9))
    step = getattr(circuit, "compiled_step", None)
    if step is not None and type(motion) is HermiteMotion and type(x) is np.ndarray and x.size:
        # the whole advance in one compiled call (pneumatics.compiled_step): the same steps and
        # stages, the matrix products summed in their own order (round-off)
        return step.advance(x, t0_s, t1_s, n, motion, rate0)
    switch = circuit.update_governors if circuit.has_governors else None
    return rk4(circuit_rhs(circuit, motion), x, t0_s, t1_s, n, rate0=rate0, switch=switch)


def absolute_tolerances(circuit: Circuit, rtol: float) -> np.ndarray:
    """Per-state absolute tolerances, scaled to each state's natural size."""
    lay = circuit.layout
    atol = np.empty(lay.size)
    atol[lay.m] = 1e-6 * rtol * 1e3      # kg; chambers hold ~0.01-1 kg
    atol[lay.T] = 300.0 * rtol           # K
    atol[lay.q] = 1e-3 * rtol * 1e2      # kg/s
    atol[lay.mass_through] = 1e-3 * rtol * 1e2
    atol[lay.heat_in:] = 1e3 * rtol      # J
    return atol


def simulate(circuit: Circuit, x0: np.ndarray, t_end_s: float, motion: Motion, *, t_eval=None,
             method: str = "LSODA", rtol: float = 1e-8, max_step_s: float = np.inf):
    """Integrate a single case (1-D state) with scipy's adaptive ``solve_ivp``; returns its result.

    A failed integration is returned too (``sol.success`` False, ``sol.t``/``sol.y`` up to the
    failure) so that the caller can keep what was computed and diagnose it; it stops as soon as
    a chamber stops being physical (see Circuit.physical_margin) instead of crawling on."""
    from scipy.integrate import solve_ivp  # here: importing it costs ~0.15 s that co-simulations never need

    if circuit.has_governors:
        raise CircuitError([circuit.compressor_names[0]], "a compressor's governor switches between fixed steps: "
                                                          "integrate this circuit with advance (the co-simulation's "
                                                          "integrator), not the adaptive one")
    def non_physical(t, x):
        return circuit.physical_margin(x, motion(t)[0])
    non_physical.terminal = True

    sol = solve_ivp(circuit_rhs(circuit, motion), (0.0, t_end_s), x0, method=method, t_eval=t_eval, rtol=rtol,
                    atol=absolute_tolerances(circuit, rtol), max_step=max_step_s, events=non_physical)
    if sol.status == 1:
        sol.success = False
        sol.message = (f"a chamber stopped being physical (mass or temperature <= 0, or volume below "
                       f"{circuit.MIN_VOLUME_FRACTION:g} of nominal)")
    return sol
