"""The levelling valves' lever signal at a state, along the chain u -> play -> delay -> lag
(:mod:`pneumatics.valves`), and the rates of its states; the compiled layout of those states is
:class:`pneumatics.assembly.valve_dynamics.ValveDynamics`. Signals are (valves, cases), the
states ``s`` (valve-signal states, cases).

:func:`lever_chain` and :func:`signal_rates` are the laws as numpy operations; the circuit
evaluates them compiled (:func:`compiled_lever_chain`, :func:`compiled_signal_rates`: one call
each instead of a dozen numpy operations on a few numbers, evaluated at every stage of the
integrator), the same operations in the same order (tests/pneumatics/test_compiled.py checks
them against these bit for bit)."""
from __future__ import annotations

import numpy as np

from .assembly.valve_dynamics import ValveDynamics
from .compiled import arrays
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


@arrays
def _chain(u, s, play_rows, play, play_half, delay_rows, delay_last, lag_rows, lag):
    """(u_p, u_d, u_f) of :func:`lever_chain`, rows as index arrays into u and s (the delay's last
    stages as rows of ``s``)."""
    n_cases = u.shape[1]
    u_p = u.copy()
    for i in range(play_rows.size):
        r, k, half = play_rows[i], play[i], play_half[i, 0]
        for j in range(n_cases):
            u_p[r, j] = np.minimum(np.maximum(s[k, j], u[r, j] - half), u[r, j] + half)
    u_d = u_p.copy()
    for i in range(delay_rows.size):
        for j in range(n_cases):
            u_d[delay_rows[i], j] = s[delay_last[i], j]
    u_f = u_d.copy()
    for i in range(lag_rows.size):
        for j in range(n_cases):
            u_f[lag_rows[i], j] = s[lag[i], j]
    return u_p, u_d, u_f


@arrays
def _rates(s, u, u_p, u_d, u_play_rate, play_rows, play, play_half, delay, delay_first, delay_rows, delay_tau,
           lag_rows, lag, lag_tau):
    """:func:`signal_rates` with ``u_play_rate`` = lever_play @ crushing rate, rows as index arrays
    (``delay``: every stage's row of ``s``, ``delay_first``: each chain's first stage among them)."""
    n_cases = s.shape[1]
    rate = np.empty_like(s)
    for i in range(play.size):
        r, k, half = play_rows[i], play[i], play_half[i, 0]
        for j in range(n_cases):
            du = u_play_rate[i, j]
            pressing = (u[r, j] - s[k, j]) * np.sign(du) >= half
            rate[k, j] = du * (1.0 if pressing else 0.0)
    n_stages = delay.size
    if n_stages:
        driving = np.empty((n_stages, n_cases))
        for i in range(1, n_stages):
            for j in range(n_cases):
                driving[i, j] = s[delay[i - 1], j]
        for i in range(delay_rows.size):
            for j in range(n_cases):
                driving[delay_first[i], j] = u_p[delay_rows[i], j]
        for i in range(n_stages):
            for j in range(n_cases):
                rate[delay[i], j] = (driving[i, j] - s[delay[i], j]) / delay_tau[i, 0]
    for i in range(lag.size):
        for j in range(n_cases):
            rate[lag[i], j] = (u_d[lag_rows[i], j] - s[lag[i], j]) / lag_tau[i, 0]
    return rate


def _index(rows, n: int) -> np.ndarray:
    """Row selection ``rows`` (a slice or an index array) of ``n`` rows as an index array."""
    return np.ascontiguousarray(np.arange(n)[rows], dtype=np.int64)


class CompiledSignals:
    """The valve-signal laws of ``dyn`` compiled (:func:`compiled_lever_chain`,
    :func:`compiled_signal_rates`): its row selections as index arrays, looked up once."""

    def __init__(self, dyn: ValveDynamics):
        n_states, nv = dyn.n_states, dyn.n_valves
        states = np.arange(n_states)
        delay = _index(dyn.delay, n_states)
        self.chain = (_index(dyn.play_rows, nv), _index(dyn.play, n_states), np.ascontiguousarray(dyn.play_half_m),
                      _index(dyn.delay_rows, nv), np.ascontiguousarray(states[dyn.delay][dyn.delay_last], dtype=np.int64),
                      _index(dyn.lag_rows, nv), _index(dyn.lag, n_states))
        self.rates = (self.chain[0], self.chain[1], self.chain[2], delay, _index(dyn.delay_first, delay.size),
                      self.chain[3], np.ascontiguousarray(dyn.delay_tau_s), self.chain[5], self.chain[6],
                      np.ascontiguousarray(dyn.lag_tau_s))

    def lever_chain(self, u: np.ndarray, s: np.ndarray):
        """:func:`lever_chain` (u, s: 2-D), compiled."""
        return (u, *_chain(u, s, *self.chain))

    def signal_rates(self, s: np.ndarray, chain, u_play_rate: np.ndarray) -> np.ndarray:
        """:func:`signal_rates` (``u_play_rate``: lever_play @ crushing rate), compiled."""
        u, u_p, u_d, _ = chain
        return _rates(s, u, u_p, u_d, u_play_rate, *self.rates)
