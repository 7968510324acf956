"""The levelling valves' lever signal at a state, along the chain u -> play -> delay -> lag
(:mod:`pneumatics.valves`), and the rates of its states; the compiled layout of those states is
:class:`pneumatics.assembly.valve_dynamics.ValveDynamics`. Signals are (valves, cases), the
states ``s`` (valve-signal states, cases)."""
from __future__ import annotations

import numpy as np

from .assembly.valve_dynamics import ValveDynamics
from .valves import lag_rate, play_output, play_rate


def lever_chain(dyn: ValveDynamics, u: np.ndarray, s: np.ndarray):
    """(u, u_p, u_d, u_f): the lever signal ``u`` after the play, the delay and the lag whose
    states are ``s``; a valve without one of them passes its signal on unchanged."""
    u_p = u
    if dyn.n_play:
        u_p = u.copy()
        u_p[dyn.play_rows] = play_output(s[dyn.play], u[dyn.play_rows], dyn.play_half_m)
    u_d = u_p
    if dyn.n_delay:
        u_d = u_p.copy()
        u_d[dyn.delay_rows] = s[dyn.delay][dyn.delay_last]
    u_f = u_d
    if dyn.n_lag:
        u_f = u_d.copy()
        u_f[dyn.lag_rows] = s[dyn.lag]
    return u, u_p, u_d, u_f


def signal_rates(dyn: ValveDynamics, s: np.ndarray, chain, lever_play: np.ndarray, zdot_m_per_s: np.ndarray) -> np.ndarray:
    """d/dt of the valve-signal states ``s``: play (input rate = ``lever_play``, the lever rows
    of the valves with a play, @ crushing rate), the delay stages (each a lag driven by the stage
    before it, the first by u_p), the lags; ``chain``: :func:`lever_chain` at ``s``."""
    u, u_p, u_d, _ = chain
    rate = np.empty_like(s)
    if dyn.n_play:
        rate[dyn.play] = play_rate(u[dyn.play_rows] - s[dyn.play], dyn.play_half_m, lever_play @ zdot_m_per_s)
    if dyn.n_delay:
        stages = s[dyn.delay]
        driving = np.empty_like(stages)
        driving[1:] = stages[:-1]
        driving[dyn.delay_first] = u_p[dyn.delay_rows]
        rate[dyn.delay] = lag_rate(driving, stages, dyn.delay_tau_s)
    if dyn.n_lag:
        rate[dyn.lag] = lag_rate(u_d[dyn.lag_rows], s[dyn.lag], dyn.lag_tau_s)
    return rate


def set_at_rest(dyn: ValveDynamics, s: np.ndarray, u: np.ndarray) -> None:
    """Write into ``s`` the states at rest at lever signal ``u``: play, every delay stage and lag
    equal to it, as if it had been held for ever."""
    s[dyn.play] = u[dyn.play_rows]
    s[dyn.delay] = u[dyn.delay_stage_valve]
    s[dyn.lag] = u[dyn.lag_rows]
