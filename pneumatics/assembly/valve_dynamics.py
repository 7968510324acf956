"""The levelling valves' response dynamics compiled: where each valve-signal state sits and the
constants of its law (:mod:`pneumatics.valves`: play, delay chain, lag).

Play states first, then the delay stages, then the lag states; each group gathers the valves
that have that element, so that one array operation serves them all (rows are slices when they
are evenly spaced, as when every valve comes from one template)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..valves import LevellingValve
from .arrays import column, read_only, rows


@dataclass(frozen=True, eq=False)
class ValveDynamics:
    """``present``: any of the ``n_valves`` valves has a play, a delay or a lag (else no signal
    state at all). Counts, valve rows and signal-state slices of the plays, delay stages and
    lags; each play's half width; each delay stage's owner (a valve row), the first and last
    stage of each chain (rows among the stages) and time constant T/n; each lag's time constant."""

    n_valves: int
    present: bool
    n_play: int
    n_delay: int
    n_lag: int
    play_rows: object
    delay_rows: object
    lag_rows: object
    play_half_m: np.ndarray
    delay_stage_valve: np.ndarray
    delay_first: object
    delay_last: object
    delay_tau_s: np.ndarray
    lag_tau_s: np.ndarray
    play: slice
    delay: slice
    lag: slice

    @property
    def n_states(self) -> int:
        return self.lag.stop

    def valve_of_state(self, i: int) -> int:
        """The row of the valve that owns valve-signal state ``i``."""
        n_valves = self.n_valves
        owners = np.r_[np.arange(n_valves)[self.play_rows], self.delay_stage_valve, np.arange(n_valves)[self.lag_rows]]
        return int(owners[i])


def compile_valve_dynamics(valves: Sequence[LevellingValve]) -> ValveDynamics:
    """The signal states of ``valves`` (in the order of the circuit's valves)."""
    play = [i for i, v in enumerate(valves) if v.hysteresis_m > 0.0]
    delay = [i for i, v in enumerate(valves) if v.delay_s > 0.0]
    lag = [i for i, v in enumerate(valves) if v.lag_s > 0.0]
    stages = [valves[i].delay_stages for i in delay]
    stage_valve = np.repeat(np.array(delay, dtype=int), stages)   # owner of each stage
    starts = np.cumsum([0] + stages)
    delay_states = slice(len(play), len(play) + int(starts[-1]))
    return ValveDynamics(
        n_valves=len(valves), present=bool(play or delay or lag), n_play=len(play), n_delay=len(delay), n_lag=len(lag),
        play_rows=rows(play), delay_rows=rows(delay), lag_rows=rows(lag),
        play_half_m=column([0.5 * valves[i].hysteresis_m for i in play]),
        delay_stage_valve=read_only(stage_valve), delay_first=rows(starts[:-1]), delay_last=rows(starts[1:] - 1),
        delay_tau_s=column([valves[i].delay_s / valves[i].delay_stages for i in stage_valve]),
        lag_tau_s=column([valves[i].lag_s for i in lag]),
        play=slice(0, len(play)), delay=delay_states, lag=slice(delay_states.stop, delay_states.stop + len(lag)))
