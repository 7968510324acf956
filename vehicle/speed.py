"""How fast the car runs: :class:`SpeedProfile`, a constant speed, then (optionally) a constant
deceleration -- the ramp-down of a nonlinear critical-speed run (start on a hunting limit cycle,
slow down until it dies); :class:`PhasedSpeedProfile`, phases of constant acceleration that may
stop and start again -- a train in service (accelerate, cruise, brake, stand at a station)."""
from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Tuple

import numpy as np

__all__ = ["SpeedProfile", "PhasedSpeedProfile"]


@dataclass(frozen=True)
class SpeedProfile:
    """v(t) = v0 until ``hold_s``, then v0 - a (t - hold_s), a = ``deceleration_m_per_s2`` >= 0;
    the distance run s(t) is its integral. A profile is used only while v(t) > 0 (:meth:`end_s`):
    the creepages are relative to v."""

    v0_m_per_s: float
    hold_s: float = 0.0
    deceleration_m_per_s2: float = 0.0

    def __post_init__(self):
        for name in ("v0_m_per_s", "hold_s", "deceleration_m_per_s2"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} must be finite and >= 0, got {value!r}")

    @property
    def constant(self) -> bool:
        return self.deceleration_m_per_s2 == 0.0

    def speed(self, t_s):
        """v(t) [m/s]."""
        return self.v0_m_per_s - self.deceleration_m_per_s2 * np.maximum(np.asarray(t_s, float) - self.hold_s, 0.0)

    def distance(self, t_s):
        """s(t) - s(0) [m] (t a float or an array)."""
        if self.constant:
            return self.v0_m_per_s * t_s
        ramp = np.maximum(np.asarray(t_s, float) - self.hold_s, 0.0)
        return self.v0_m_per_s * t_s - 0.5 * self.deceleration_m_per_s2 * ramp * ramp

    def time_at_distance(self, distance_m: float) -> float:
        """The time the car has run ``distance_m`` [s] (:attr:`end_s` if it stops before)."""
        v0, hold, a = self.v0_m_per_s, self.hold_s, self.deceleration_m_per_s2
        if distance_m <= v0 * hold:
            return distance_m / v0 if v0 > 0.0 else 0.0
        if self.constant:
            return distance_m / v0 if v0 > 0.0 else math.inf
        if distance_m >= self.distance(self.end_s):
            return self.end_s
        rest = distance_m - v0 * hold                      # v0 r - a r^2 / 2 = rest, the smaller root
        return hold + (v0 - math.sqrt(v0 * v0 - 2.0 * a * rest)) / a

    @property
    def end_s(self) -> float:
        """The time the speed reaches 0 (inf for a constant speed) [s]."""
        return math.inf if self.constant else self.hold_s + self.v0_m_per_s / self.deceleration_m_per_s2

    @property
    def usable_until_s(self) -> float:
        """The profile holds until the speed reaches 0 [s] (:attr:`end_s`): beyond, v would be negative."""
        return self.end_s


@dataclass(frozen=True)
class PhasedSpeedProfile:
    """v(t) linear between the knots (``times_s[i]``, ``speeds_m_per_s[i]``): phases of constant
    acceleration, v >= 0, standing where two consecutive knots have v = 0. Before the first knot
    (t = 0) and after the last the speed holds. The distance run s(t) is the exact integral
    (trapezoids), so a stop lands where the phases put it to round-off.

    It is the same interface as :class:`SpeedProfile` (``speed``, ``distance``,
    ``time_at_distance``, ``end_s``, ``constant``); ``end_s`` is the last knot, not the time the
    car stops for good."""

    times_s: Tuple[float, ...]
    speeds_m_per_s: Tuple[float, ...]

    def __post_init__(self):
        t, v = np.asarray(self.times_s, float), np.asarray(self.speeds_m_per_s, float)
        if t.ndim != 1 or t.shape != v.shape or len(t) < 2:
            raise ValueError("times_s and speeds_m_per_s must be equal-length sequences of at least two knots")
        if t[0] != 0.0 or not np.all(np.diff(t) > 0.0) or not np.all(np.isfinite(t)):
            raise ValueError(f"times_s must start at 0 and increase, got {self.times_s!r}")
        if not (np.all(np.isfinite(v)) and np.all(v >= 0.0)):
            raise ValueError(f"speeds_m_per_s must be finite and >= 0, got {self.speeds_m_per_s!r}")
        s = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
        object.__setattr__(self, "_t", t)
        object.__setattr__(self, "_v", v)
        object.__setattr__(self, "_s", s)
        object.__setattr__(self, "_t_list", t.tolist())

    constant = False

    @property
    def v0_m_per_s(self) -> float:
        return float(self._v[0])

    @property
    def end_s(self) -> float:
        """The last knot [s]; the speed holds after it."""
        return float(self._t[-1])

    #: the profile holds for ever (it stops and starts; kinematic guidance needs no v > 0)
    usable_until_s = math.inf

    def _phase(self, t: float) -> int:
        """Index i of the phase [t_i, t_i+1) holding t (clamped to the first and last)."""
        return min(max(bisect.bisect_right(self._t_list, t) - 1, 0), len(self._t_list) - 2)

    def acceleration(self, t_s: float) -> float:
        """dv/dt in the phase holding t [m/s^2] (0 before the first and after the last knot)."""
        if t_s < 0.0 or t_s >= self._t_list[-1]:
            return 0.0
        i = self._phase(t_s)
        return float((self._v[i + 1] - self._v[i]) / (self._t[i + 1] - self._t[i]))

    def speed(self, t_s):
        """v(t) [m/s]."""
        return np.interp(t_s, self._t, self._v)

    def _distance(self, t: float) -> float:
        t_list = self._t_list
        if t <= 0.0:
            return float(self._v[0]) * t
        if t >= t_list[-1]:
            return float(self._s[-1] + self._v[-1] * (t - t_list[-1]))
        i = self._phase(t)
        u = t - t_list[i]
        a = (self._v[i + 1] - self._v[i]) / (self._t[i + 1] - self._t[i])
        return float(self._s[i] + self._v[i] * u + 0.5 * a * u * u)

    def distance(self, t_s):
        """s(t) - s(0) [m] (t a float or an array)."""
        if np.ndim(t_s) == 0:
            return self._distance(float(t_s))
        return np.array([self._distance(float(t)) for t in np.asarray(t_s, float).ravel()]).reshape(np.shape(t_s))

    def time_at_distance(self, distance_m: float) -> float:
        """The first time the car has run ``distance_m`` [s] (inf if it never does)."""
        s = self._s
        if distance_m <= 0.0:
            return 0.0
        if distance_m > s[-1]:
            return self.end_s + (distance_m - s[-1]) / self._v[-1] if self._v[-1] > 0.0 else math.inf
        i = int(np.searchsorted(s, distance_m, side="left")) - 1
        i = min(max(i, 0), len(s) - 2)
        v0, dt = self._v[i], self._t[i + 1] - self._t[i]
        a = (self._v[i + 1] - v0) / dt
        rest = distance_m - s[i]
        if a == 0.0:
            return float(self._t[i] + rest / v0) if v0 > 0.0 else float(self._t[i + 1])
        u = (-v0 + math.sqrt(max(v0 * v0 + 2.0 * a * rest, 0.0))) / a
        return float(self._t[i] + min(max(u, 0.0), dt))
