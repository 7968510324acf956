"""Impossible states stop a case: a capsized carbody, a derailed wheelset, a bellow crushed
through, air outside physics (:class:`~cosim.scenario.model.StateLimits`). The co-simulation
master asks :class:`StateWatch` after every macro-step; a case it names stops there with the
returned diagnosis, like a case whose solver diverged, and keeps what it computed."""
from __future__ import annotations

from typing import List, Optional, Sequence

import numpy as np

from cosim.scenario.model import StateLimits
from vehicle.params import BELLOWS, WHEELS

_BODIES = ("carbody", "front bogie frame", "rear bogie frame")


class StateWatch:
    """Checks the cars of one co-simulation against ``limits`` (one lift timer per wheelset)."""

    #: interval [s] of the checks of the car and the air (the master checks each bellow's
    #: volume every macro-step): a car overturns or derails over tenths of a second, and checking
    #: every 5 ms step cost 12 % of a curve run; the wheelset lift time is decided to within it
    INTERVAL_S = 0.02

    def __init__(self, limits: StateLimits, n_cases: int, bellow_height_m: float):
        self.limits = limits
        self._roll_limits = np.array([limits.carbody_roll_rad] + [limits.bogie_roll_rad] * 2)
        self._crushing_limit_m = limits.bellow_crushing_fraction * bellow_height_m
        self._lifted_since = np.full((n_cases, 4), np.nan)  # time both wheels left the rails

    def car(self, j: int, car, t_s: float) -> Optional[str]:
        """Why car ``j`` (a :class:`~vehicle.car.MetroCar`) is in an impossible state at t_s, or
        None. The crushing is the whole airspring's (bellow and emergency spring): its plates
        meet at 1 x the bellow height."""
        lim = self.limits
        roll = car.roll_to_track_rad()
        beyond = np.abs(roll) > self._roll_limits
        if beyond.any():
            i = int(np.argmax(beyond))
            return (f"{_BODIES[i]} rolled {roll[i]:+.3f} rad relative to the track plane at t = {t_s:.4g} s "
                    f"(limit {self._roll_limits[i]:g} rad): the car overturned")
        crushing_m = car.airspring_crushing_m()
        over = np.abs(crushing_m) > self._crushing_limit_m
        if over.any():
            k = int(np.argmax(over))
            what = "crushed" if crushing_m[k] > 0 else "extended"
            return (f"airspring {BELLOWS[k]} {what} by {1e3 * abs(crushing_m[k]):.1f} mm at t = {t_s:.4g} s, beyond "
                    f"{lim.bellow_crushing_fraction:g} x its height ({1e3 * self._crushing_limit_m:.0f} mm)")
        Q = car.wheel_loads_N()
        off = (Q[0::2] <= 0.0) & (Q[1::2] <= 0.0)
        since = self._lifted_since[j]
        since[~off] = np.nan
        since[off & np.isnan(since)] = t_s
        lifted = off & (t_s - since > lim.wheelset_lift_s)
        if lifted.any():
            w = int(np.argmax(lifted))
            return (f"wheelset {w + 1} ({WHEELS[2 * w]}, {WHEELS[2 * w + 1]}) off the rails since t = {since[w]:.4g} s "
                    f"(longer than {lim.wheelset_lift_s:g} s) at t = {t_s:.4g} s: derailed")
        return None

    def any_flat(self, volume_fractions: np.ndarray) -> np.ndarray:
        """Per case (the last axis), whether :meth:`bellows` would name a bellow."""
        return np.any(volume_fractions < self.limits.bellow_volume_fraction, axis=0)

    def bellows(self, volume_fractions: np.ndarray, names: Sequence[str], t_s: float) -> Optional[str]:
        """Why a bellow is crushed flat (``volume_fractions``: each bellow's volume over its
        nominal one), or None."""
        flat = volume_fractions < self.limits.bellow_volume_fraction
        if not flat.any():
            return None
        k = int(np.argmax(flat))
        return (f"bellow {names[k]} crushed to {100 * volume_fractions[k]:.1f} % of its volume at t = {t_s:.4g} s "
                f"(limit {100 * self.limits.bellow_volume_fraction:g} %)")

    def air(self, p_Pa: np.ndarray, T_K: np.ndarray, chambers: Sequence[str], t_s: float) -> List[Optional[str]]:
        """Per case, why its air is outside physics (``p_Pa``, ``T_K``: (chambers, cases)), or None."""
        lim = self.limits
        bad = (T_K < lim.T_min_K) | (T_K > lim.T_max_K) | (p_Pa < lim.p_min_Pa) | (p_Pa > lim.p_max_Pa)
        out: List[Optional[str]] = [None] * T_K.shape[1]
        for j in np.flatnonzero(bad.any(axis=0)):
            i = int(np.argmax(bad[:, j]))
            out[j] = (f"air in '{chambers[i]}' at {T_K[i, j]:.1f} K, {p_Pa[i, j] / 1e5:.3g} bar absolute at t = "
                      f"{t_s:.4g} s, outside [{lim.T_min_K:g}, {lim.T_max_K:g}] K x [{lim.p_min_Pa / 1e5:g}, "
                      f"{lim.p_max_Pa / 1e5:g}] bar")
        return out
