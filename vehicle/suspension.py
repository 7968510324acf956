"""Force laws of the secondary suspension components (pure functions, SI units).

Every law here is written once and serves twice: with plain floats (:data:`FLOAT_OPS`, the
default) for Python-side bookkeeping and tests, and with exudyn symbolic expressions (``ops`` =
the symbolic namespace built in :mod:`vehicle.car`) for the connectors' user functions, which then
run in C++. The laws therefore use only arithmetic, comparisons and ``ops.where`` / ``ops.abs``
/ ``ops.sign`` / ``ops.max`` / ``ops.min``.

Sign conventions (all components between a bogie frame and the carbody):

* a *deflection* d is the carbody point relative to the bogie point along the component's axis;
  the component *force* F is the force on the bogie frame along that axis (the carbody gets
  -F): F > 0 resists d > 0, like a spring F = k d;
* crushing z (bellow, emergency spring, vertical bumpstop) is positive in compression;
  the axial force F is positive in compression (pushes the carbody up).

Components:

* :func:`bilinear_damper_force_N` -- hydraulic damper, linear or bilinear ("blow-off") in the
  velocity;
* :func:`maxwell_step` -- the damper in series with an elastic mounting (a Maxwell element),
  advanced over one time step with the trapezoidal rule;
* :func:`maxwell_complex_stiffness_N_per_m` -- its analytic frequency response;
* :func:`unilateral_stop_force_N` -- bumpstop: zero inside a clearance, linear beyond;
* :func:`arb_roll_stiffness_N_m_per_rad` -- anti-roll bar roll stiffness from the torsion bar
  and its lever/link geometry;
* :func:`airspring_series_force_N` -- bellow (force law from the pneumatics) in parallel with its
  internal bumpstop, the pair in series with the emergency spring.

This module imports neither exudyn nor the pneumatics.
"""
from __future__ import annotations

import math
from typing import NamedTuple


class _FloatOps:
    """The operations the laws need, for plain floats."""

    @staticmethod
    def where(condition, if_true, if_false):
        return if_true if condition else if_false

    abs = staticmethod(abs)
    max = staticmethod(max)
    min = staticmethod(min)

    @staticmethod
    def sign(x):
        return (x > 0) - (x < 0)


#: float implementation of the operations the force laws use (the default ``ops``)
FLOAT_OPS = _FloatOps()


# ====================================================================== damper
def bilinear_damper_force_N(v_m_per_s, c1_N_s_per_m: float, c2_N_s_per_m: float = 0.0,
                            blowoff_velocity_m_per_s: float = math.inf, ops=FLOAT_OPS):
    """Force [N] of a hydraulic damper at the stroke velocity ``v`` [m/s] (extension > 0).

    Linear, F = c1 v, up to the blow-off velocity v_b; beyond it the relief valves open and the
    slope drops to c2: F = sign(v) (c1 v_b + c2 (|v| - v_b)). ``v_b = inf`` (default): linear.
    F > 0 resists extension. Continuous, odd and monotone for c1, c2 >= 0.
    """
    c1, c2, vb = c1_N_s_per_m, c2_N_s_per_m, blowoff_velocity_m_per_s
    if math.isinf(vb):
        return c1 * v_m_per_s
    return ops.where(ops.abs(v_m_per_s) <= vb, c1 * v_m_per_s,
                     c2 * v_m_per_s + ops.sign(v_m_per_s) * ((c1 - c2) * vb))


def bilinear_damper_velocity_m_per_s(F_N: float, c1_N_s_per_m: float, c2_N_s_per_m: float = 0.0,
                                     blowoff_velocity_m_per_s: float = math.inf) -> float:
    """Inverse of :func:`bilinear_damper_force_N` (floats): the velocity [m/s] at force ``F``.
    Needs c2 > 0 when |F| exceeds the blow-off force c1 v_b."""
    c1, c2, vb = c1_N_s_per_m, c2_N_s_per_m, blowoff_velocity_m_per_s
    if abs(F_N) <= c1 * vb:
        return F_N / c1
    return math.copysign(vb + (abs(F_N) - c1 * vb) / c2, F_N)


class MaxwellState(NamedTuple):
    """State of a Maxwell element at the end of a step."""
    force_N: float  #: force F [N] (> 0 resists extension)
    damper_m: float  #: damper elongation y [m]
    damper_rate_m_per_s: float  #: damper stroke velocity dy/dt [m/s]


def maxwell_force_N(d_m, y_m, ydot_m_per_s, h_s, k_s_N_per_m: float, c1_N_s_per_m: float,
                    c2_N_s_per_m: float = 0.0, blowoff_velocity_m_per_s: float = math.inf,
                    ops=FLOAT_OPS):
    """Force [N] at the end of a time step of a damper in series with a spring (Maxwell element).

    The element's deflection d = (spring elongation) + (damper elongation y); its force is
    F = k_s (d - y) = f_d(dy/dt), f_d the (bi)linear damper law. The internal state y is advanced
    with the trapezoidal rule, y_1 = y_0 + h/2 (ydot_0 + ydot_1), from the state (y_0, ydot_0)
    at the start of the step, so that F at the end of the step is a function of the deflection d
    at the end alone, solved in closed form:

        z = d - y_0 - h/2 ydot_0;  ydot_1 = k_s z / (c1 + k_s h/2)  (|ydot_1| <= v_b)
        F = c1 ydot_1, or beyond the blow-off
        F = k_s (c2 z + sign(z) (c1 - c2) v_b h/2) / (c2 + k_s h/2).

    ``d_m`` (and, in the symbolic case, every other argument but the parameters) may be an
    expression. Trapezoidal like exudyn's own ODE1 integration and second order like
    generalized-alpha; A-stable (the relaxation factor (1 - h k_s/(2c)) / (1 + h k_s/(2c)) stays
    in (-1, 1]; it approaches -1, a slowly decaying alternation, only for h >> 2 c / k_s).
    """
    k, c1, c2, vb = k_s_N_per_m, c1_N_s_per_m, c2_N_s_per_m, blowoff_velocity_m_per_s
    a = 0.5 * h_s
    z = d_m - y_m - a * ydot_m_per_s
    linear = k * c1 * z / (c1 + a * k)
    if math.isinf(vb):
        return linear
    blown = k * (c2 * z + ops.sign(z) * ((c1 - c2) * vb) * a) / (c2 + a * k)
    return ops.where(ops.abs(k * z) <= (c1 + a * k) * vb, linear, blown)


def maxwell_step(d_m: float, y_m: float, ydot_m_per_s: float, h_s: float, k_s_N_per_m: float,
                 c1_N_s_per_m: float, c2_N_s_per_m: float = 0.0,
                 blowoff_velocity_m_per_s: float = math.inf) -> MaxwellState:
    """One trapezoidal step of a Maxwell element (floats): the force and new internal state at
    the end of a step of ``h_s`` ending at deflection ``d_m``, from the state (``y_m``,
    ``ydot_m_per_s``) at its start. See :func:`maxwell_force_N` for the law."""
    F = maxwell_force_N(d_m, y_m, ydot_m_per_s, h_s, k_s_N_per_m, c1_N_s_per_m, c2_N_s_per_m,
                        blowoff_velocity_m_per_s)
    y = d_m - F / k_s_N_per_m
    ydot = 2.0 * (y - y_m) / h_s - ydot_m_per_s if h_s > 0.0 else ydot_m_per_s
    return MaxwellState(F, y, ydot)


def maxwell_complex_stiffness_N_per_m(omega_rad_per_s: float, k_s_N_per_m: float,
                                      c_N_s_per_m: float) -> complex:
    """Dynamic stiffness F / d [N/m] of a linear Maxwell element at circular frequency omega:
    K*(w) = k_s i w c / (k_s + i w c). Low frequency: i w c (the damper); high frequency: k_s
    (the series spring). Real part: the stiffness the element adds; imaginary part / w: its
    effective damping c k_s^2 / (k_s^2 + (w c)^2)."""
    iwc = 1j * omega_rad_per_s * c_N_s_per_m
    return k_s_N_per_m * iwc / (k_s_N_per_m + iwc)


# ====================================================================== stops, anti-roll bar
def unilateral_stop_force_N(d_m, clearance_m: float, k_N_per_m: float, ops=FLOAT_OPS):
    """Compression bumpstop [N]: 0 while the deflection d <= clearance, k (d - clearance)
    beyond (d, F > 0 in compression). Real stops are progressive; linear past the clearance is
    the usual simplification."""
    return k_N_per_m * ops.max(d_m - clearance_m, 0.0)


def arb_roll_stiffness_N_m_per_rad(torsion_stiffness_N_m_per_rad: float, lever_arm_m: float,
                                   link_spacing_m: float) -> float:
    """Roll stiffness [N m/rad] of an anti-roll bar between bogie frame and carbody.

    A relative roll phi moves the two vertical links (lateral spacing s) by +-s phi / 2; each
    lever (arm l) turns the bar's end by s phi / (2 l), so the bar twists by s phi / l and
    carries the torque k_t s phi / l; each link then pushes with k_t s phi / l^2, a couple
    k_t s^2 phi / l^2 about the roll axis: K_roll = k_t (s / l)^2.
    """
    if torsion_stiffness_N_m_per_rad == 0.0:
        return 0.0
    if not (lever_arm_m > 0.0 and link_spacing_m > 0.0):
        raise ValueError("an anti-roll bar given by its torsion stiffness needs arb_lever_arm_m "
                         f"> 0 and arb_link_spacing_m > 0, got {lever_arm_m}, {link_spacing_m}")
    return torsion_stiffness_N_m_per_rad * (link_spacing_m / lever_arm_m) ** 2


# ====================================================================== airspring in series
def airspring_series_force_N(z_total_m, A_N, K_N_per_m, F_static_N: float,
                             k_emergency_N_per_m: float, k_stop_N_per_m: float,
                             stop_clearance_m: float, ops=FLOAT_OPS):
    """Axial force [N] of an airspring made of the bellow, its internal bumpstop in parallel,
    and the emergency spring in series with the pair, at the total crushing ``z_total_m``.

    Bellow: F_b = A + K z_b (the pneumatic force law, linear in the bellow's own crushing z_b:
    A = F_n + dF/dt (t - t_n) - K z_n, see ``MetroCar.set_bellow_forces``); internal stop:
    k_stop max(z_b - clearance, 0); emergency spring (stiffness k_e; ``inf`` = rigid seat)
    carries the same force F and compresses by (F - F_static) / k_e from its static state, so
    z_total = z_b + (F - F_static) / k_e. All crushings are 0 at static equilibrium. Solved in
    closed form, stop free or engaged (monotone in z_b for K + k_e > 0):

        F = (k_e (A' + K' z_total) + K' F_static) / (k_e + K'),
        K' = K (+ k_stop), A' = A (- k_stop clearance).

    A deflated bellow (A = K = 0) crushes until the stop carries the load through the emergency
    spring; a stiff law that bottoms the bellow does the same.
    """
    ke, ks, c = k_emergency_N_per_m, k_stop_N_per_m, stop_clearance_m
    if math.isinf(ke):
        return A_N + K_N_per_m * z_total_m + unilateral_stop_force_N(z_total_m, c, ks, ops)
    free = (ke * (A_N + K_N_per_m * z_total_m) + K_N_per_m * F_static_N) / (ke + K_N_per_m)
    if ks == 0.0:
        return free
    zb_free = z_total_m - (free - F_static_N) / ke
    Kt = K_N_per_m + ks
    stop = (ke * (A_N - ks * c + Kt * z_total_m) + Kt * F_static_N) / (ke + Kt)
    return ops.where(zb_free > c, stop, free)


def airspring_series_bellow_crushing(z_total_m: float, zdot_total_m_per_s: float, A_N: float,
                                     K_N_per_m: float, Fdot_N_per_s: float, F_static_N: float,
                                     k_emergency_N_per_m: float, k_stop_N_per_m: float,
                                     stop_clearance_m: float) -> tuple[float, float, float]:
    """(F [N], z_b [m], dz_b/dt [m/s]) of :func:`airspring_series_force_N` (floats): the force,
    the bellow's own crushing and its rate, given the total crushing and its rate and the
    bellow law's time rate dF/dt. dz_b/dt = (k_e dz/dt - dF/dt) / (k_e + K') (K' as there)."""
    ke, ks = k_emergency_N_per_m, k_stop_N_per_m
    F = airspring_series_force_N(z_total_m, A_N, K_N_per_m, F_static_N, ke, ks, stop_clearance_m)
    if math.isinf(ke):
        return F, z_total_m, zdot_total_m_per_s
    zb = z_total_m - (F - F_static_N) / ke
    Kt = K_N_per_m + (ks if ks > 0.0 and zb > stop_clearance_m else 0.0)
    return F, zb, (ke * zdot_total_m_per_s - Fdot_N_per_s) / (ke + Kt)
