"""Levelling, safety and differential pressure valves (paper §2.3, Fig. 2).

Valve characteristics are tables, linearly interpolated and held constant beyond their ends.
The default values are assumptions (the paper shows the curves only qualitatively); each is
explained where it is defined.

Levelling-valve dynamics (optional, see :class:`LevellingValve`): the lever displacement u
passes through a play (backlash), a dead time and a first-order lag before it reaches the
conductance tables::

    u = lever_gain * mean crushing  --play(hysteresis_m)-->  u_p  --delay(delay_s)-->  u_d
        --lag(lag_s)-->  u_f  --tables-->  C_supply(u_f), C_exhaust(-u_f)

Each element is the identity when its parameter is 0 (the default), so a default valve acts on
u instantly, as before. The laws are the small functions at the end of this module; the
circuit (:mod:`pneumatics.circuit`) holds their states.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Tuple

import numpy as np
from scipy.special import gammainc

from pneumorail.quantities import nonnegative, plausible, ranged

from .compiled import arrays
from .orifice import CRITICAL_RATIO

#: Sonic conductance of a fully open levelling valve [m^3/(s Pa)]. Assumed: a large railway
#: levelling valve passes about 1000 l/min ANR, ~0.02 kg/s choked from a 9 bar reservoir, i.e.
#: C ~ 2e-8; half of that is taken, for a valve whose lever is not fully deflected in normal service.
LEVELLING_C_MAX = 1.0e-8
#: ranges of the valves' tables (field metadata): a lever displacement from 0 to 1 m (the safety
#: valve's never-opening supply side is tabled to 1 m; an airspring's whole stroke is ~0.1 m);
#: a sonic conductance from 0 (the dead band: shut) to 1e-4 m^3/(s Pa), 10 000 times the
#: levelling valve's, a bore of ~7 cm (C = 1.99e-3 A)
LEVER_TABLE = plausible(0.0, 1.0, "m", "a lever displacement from the valve's neutral")
CONDUCTANCE_TABLE = plausible(0.0, 1e-4, "m^3/(s Pa)", "a sonic conductance; 0: shut")


@dataclass(frozen=True)
class LevellingValve:
    """A lever-operated valve that inflates ``bellow`` from ``supply`` or deflates it to ``exhaust``.

    Lever displacement u = ``lever_gain`` x (mean crushing of the ``sensed`` bellows; default: the
    controlled bellow itself). Crushing is positive in compression, so a compressed (too low)
    bellow (u > 0) opens the supply side with conductance C_supply(u), an extended one (u < 0) the
    exhaust side with C_exhaust(-u). Tables start with a dead band of zero conductance (Fig. 2a).
    Defaults: 5 mm dead band, full opening at 25 mm (assumed, typical of railway levelling valves);
    b = 0.4 (assumed, a typical ISO 6358 critical ratio of a spool valve).

    **Response dynamics** (all optional; 0 = absent, the default, which keeps the instantaneous
    valve above bit for bit and adds no signal state). The tables are read at u_f instead of u:

    * ``hysteresis_m`` = w, full width of the play (backlash) in the lever linkage, in lever
      displacement [m]. Classical play operator: its output u_p stays put while
      |u - u_p| < w/2 and is dragged along at u_p = u -+ w/2 once the input pushes against a
      side. State: u_p, with du_p/dt = du/dt while pushing, else 0 (:func:`play_rate`), read
      through :func:`play_output`. du/dt = lever_gain x mean crushing rate, so the crushing rate
      given to the circuit must be the derivative of the crushing (it already must be, for the
      bellow's work p dV).
    * ``delay_s`` = T, dead time of the valve's response [s], approximated by a chain of
      n = ``delay_stages`` equal first-order lags of time constant T/n (an Erlang, or "gamma",
      delay): transfer function (1 + sT/n)^-n -> exp(-sT) as n -> inf. Chosen over a Padé
      approximant because its step response is monotone (it rises from 0 to 1 without
      overshoot): every Padé approximant of equal degrees jumps at t = 0 by +-1 (order 1 starts
      on the wrong side, order 2 starts fully open), which would open the wrong side or open
      at once. Step response: the regularised lower incomplete gamma function P(n, n t/T)
      (:func:`erlang_step_response`); mean exactly T, standard deviation T/sqrt(n). Accuracy
      for the default n = 16 (fraction of a step that has arrived at t): 0.8 % at 0.5 T, 37 % at
      0.9 T, 50 % at 0.98 T, 97 % at 1.5 T. A valve therefore opens when the delayed lever
      crosses the dead band: after a step of 2x the dead band at 0.98 T, after a step to full
      opening (5x) at 0.79 T. n states per valve; the stage rate n/T must stay within RK4's
      stability limit: h < 2.78 T/n (T >= 6 ms at h = 1 ms, n = 16).
    * ``lag_s`` = tau, first-order lag of the lever signal [s]: du_f/dt = (u_d - u_f)/tau, the
      valve spool following the lever through a spring and a hydraulic damper
      (:func:`lag_rate`). One state per valve.

    Play, delay and lag states start at rest, at the lever displacement of the initial state
    (Circuit.initial_state: z = 0, so 0; Circuit.valves_at_rest for another crushing).

    **Recommended values** (assumptions, argued here; no supplier data sheet is available to
    the project - replace them with one when it is): ``lag_s`` = 1.0, ``delay_s`` = 1.0 with
    ``delay_stages`` = 16, ``hysteresis_m`` = 0.002.
    Reasoning: a metro carbody on air springs sways and bounces at ~1 Hz with little damping,
    and an instantaneous valve with a 5 mm dead band chases a +-10 mm sway into limit cycles.
    What prevents that is the attenuation of the ~1 Hz signal below the dead band, not the dead
    time itself (a pure dead time would pass the sway unattenuated and only cost phase margin).
    At 1 Hz the lag attenuates by 1/sqrt(1 + (2 pi tau)^2) = 0.157, the 16-stage delay chain by
    (1 + (2 pi T/16)^2)^-8 = 0.317: together 0.050, so a +-10 mm sway reaches the tables as
    +-0.5 mm, a tenth of the dead band. The valve then answers a load change (passengers
    boarding) after ~tau + T = 2 s, short against a station stop (~20 s). 2 mm of play (+-1 mm)
    is an assumed clearance of the lever linkage's joints: it stops the valve from toggling at
    the edge of its dead band on small vibrations and, being well inside the 5 mm dead band,
    widens the levelling tolerance only by 1 mm each way.
    """

    bellow: str
    supply: str = "supply"
    exhaust: str = "atmosphere"
    sensed: Tuple[str, ...] = ()
    lever_gain: float = field(default=1.0, metadata=plausible(0.0, 20.0, why="lever displacement per metre of crushing, "
                                                                             "a lever ratio", low_inclusive=False))
    supply_lever_m: Tuple[float, ...] = field(default=(0.0, 0.005, 0.025), metadata=LEVER_TABLE)
    supply_C_m3_per_sPa: Tuple[float, ...] = field(default=(0.0, 0.0, LEVELLING_C_MAX), metadata=CONDUCTANCE_TABLE)
    exhaust_lever_m: Tuple[float, ...] = field(default=(0.0, 0.005, 0.025), metadata=LEVER_TABLE)
    exhaust_C_m3_per_sPa: Tuple[float, ...] = field(default=(0.0, 0.0, LEVELLING_C_MAX), metadata=CONDUCTANCE_TABLE)
    b_critical: float = field(default=0.4, metadata=ranged(CRITICAL_RATIO))
    lag_s: float = field(default=0.0, metadata=ranged(nonnegative("s", "0: no lag")))
    delay_s: float = field(default=0.0, metadata=ranged(nonnegative("s", "0: no delay")))
    delay_stages: int = field(default=16, metadata=plausible(1, 1000, why="first-order stages approximating the delay; "
                                                                           "one state each"))
    hysteresis_m: float = field(default=0.0, metadata=plausible(0.0, 0.05, "m", "the lever's play; 0: no play"))

    @property
    def sensed_bellows(self) -> Tuple[str, ...]:
        return self.sensed or (self.bellow,)


@dataclass(frozen=True)
class SafetyValve(LevellingValve):
    """A lever valve of the same form that only vents a grossly over-extended bellow.

    Defaults (assumed): the supply side never opens; the exhaust side opens beyond 60 mm of
    extension and is fully open at 80 mm.
    """

    supply: str = "atmosphere"
    supply_lever_m: Tuple[float, ...] = field(default=(0.0, 1.0), metadata=LEVER_TABLE)
    supply_C_m3_per_sPa: Tuple[float, ...] = field(default=(0.0, 0.0), metadata=CONDUCTANCE_TABLE)
    exhaust_lever_m: Tuple[float, ...] = field(default=(0.0, 0.060, 0.080), metadata=LEVER_TABLE)
    exhaust_C_m3_per_sPa: Tuple[float, ...] = field(default=(0.0, 0.0, 2.0 * LEVELLING_C_MAX), metadata=CONDUCTANCE_TABLE)


@dataclass(frozen=True)
class DifferentialPressureValve:
    """Transfers air from the higher- to the lower-pressure of two bellows (four-point circuits).

    Mass flow is a tabulated function of |p_a - p_b| (Fig. 2b), directed from high to low
    pressure, so the valve is antisymmetric. Defaults (assumed): closed below 1.5 bar, the usual
    setting of railway differential valves, rising to 0.02 kg/s at 2.5 bar.
    """

    a: str
    b: str
    # a pressure difference, not an absolute pressure: from 0; 20 bar is beyond any railway circuit
    dp_Pa: Tuple[float, ...] = field(default=(0.0, 1.5e5, 2.5e5), metadata=plausible(
        0.0, 2e6, "Pa", "a pressure difference across the valve"))
    # 0.02 kg/s is the default's full flow; 10 kg/s would empty a 12-litre bellow at 5 bar in ms
    q_kg_per_s: Tuple[float, ...] = field(default=(0.0, 0.0, 0.02), metadata=plausible(0.0, 10.0, "kg/s", "a valve's flow"))


@arrays
def lever_conductance(lever_m, table_lever_m, table_C):
    """Sonic conductance at lever displacement ``lever_m`` (an array): > 0 may open this side
    (beyond the table's dead band); <= 0 keeps it shut. Compiled (:mod:`pneumatics.compiled`)."""
    return np.interp(np.maximum(lever_m, 0.0), table_lever_m, table_C) * (lever_m > 0.0)


@arrays
def differential_valve_flow_kg_per_s(p_a_Pa, p_b_Pa, table_dp_Pa, table_q):
    """Signed flow from a to b (arrays): sign(p_a - p_b) q(|p_a - p_b|); antisymmetric by
    construction. Compiled (:mod:`pneumatics.compiled`)."""
    dp = p_a_Pa - p_b_Pa
    return np.sign(dp) * np.interp(np.abs(dp), table_dp_Pa, table_q)


# ----------------------------------------------------------------------------- valve dynamics
def play_output(y_m, u_m, half_width_m):
    """Output of a play (backlash) of half width r = w/2 with state ``y_m`` and input ``u_m``:
    clip(y, u - r, u + r). Equal to y in exact arithmetic; the clip keeps |u - output| <= r
    exactly, whatever the integration error of y."""
    return np.minimum(np.maximum(y_m, u_m - half_width_m), u_m + half_width_m)


def play_rate(gap_m, half_width_m, u_rate_m_per_s):
    """dy/dt of the play state y for gap = u - y and input rate du/dt: the input drags the
    output when it presses against a side and moves outwards (gap >= r and du/dt > 0, or
    gap <= -r and du/dt < 0); otherwise the output stays put.

    The switch is discontinuous only where the input reaches a side; there a fixed RK4 step
    leaves y behind the side by at most h |du/dt| (not cumulative: the next contact starts
    afresh), e.g. 0.06 mm for a 10 mm, 1 Hz sway at h = 1 ms. While pushing, the output
    (:func:`play_output`) is exact regardless."""
    # gap sign(du/dt) >= r: pressing outwards against the side it moves towards (r > 0, so never at rest)
    return u_rate_m_per_s * (gap_m * np.sign(u_rate_m_per_s) >= half_width_m)


def lag_rate(u_in, u_out, tau_s):
    """First-order lag: du_out/dt = (u_in - u_out) / tau. Also one stage of the delay chain
    (tau = T/n)."""
    return (u_in - u_out) / tau_s


def erlang_step_response(t_s, delay_s, stages):
    """Unit step response of the n-stage delay chain (1 + s T/n)^-n at time t after the step:
    P(n, n t / T) = 1 - sum_{k<n} exp(-x) x^k / k!, x = n t / T (0 for t <= 0)."""
    return gammainc(stages, np.maximum(np.asarray(t_s, float), 0.0) * stages / delay_s)
