"""How fast the car runs: :class:`SpeedProfile`, a constant speed, then (optionally) a constant
deceleration -- the ramp-down of a nonlinear critical-speed run (start on a hunting limit cycle,
slow down until it dies); :class:`PhasedSpeedProfile`, phases of constant acceleration that may
stop and start again -- a train in service (accelerate, cruise, brake, stand at a station) --,
or of constant jerk when its accelerations ramp."""
from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Optional, Tuple

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
    """v(t) between the knots (``times_s[i]``, ``speeds_m_per_s[i]``), v >= 0, standing where two
    consecutive knots have v = 0. Before the first knot (t = 0) and after the last the speed holds.

    Without ``accelerations_m_per_s2`` v is linear between the knots: phases of constant
    acceleration, which steps at a knot. With it (the acceleration at each knot, one per knot) the
    acceleration is linear between the knots: phases of constant jerk, an acceleration that
    ramps in and out as a jerk-limited traction and brake controller gives it; the speeds must then
    be its integral (v_i+1 - v_i = (a_i + a_i+1) / 2 (t_i+1 - t_i), to 1e-9 m/s).

    The distance run s(t) is the exact integral of the speed (a polynomial per phase), so a stop
    lands where the phases put it to round-off.

    It is the same interface as :class:`SpeedProfile` (``speed``, ``distance``,
    ``time_at_distance``, ``end_s``, ``constant``); ``end_s`` is the last knot, not the time the
    car stops for good."""

    times_s: Tuple[float, ...]
    speeds_m_per_s: Tuple[float, ...]
    accelerations_m_per_s2: Optional[Tuple[float, ...]] = None

    def __post_init__(self):
        t, v = np.asarray(self.times_s, float), np.asarray(self.speeds_m_per_s, float)
        if t.ndim != 1 or t.shape != v.shape or len(t) < 2:
            raise ValueError("times_s and speeds_m_per_s must be equal-length sequences of at least two knots")
        if t[0] != 0.0 or not np.all(np.diff(t) > 0.0) or not np.all(np.isfinite(t)):
            raise ValueError(f"times_s must start at 0 and increase, got {self.times_s!r}")
        if not (np.all(np.isfinite(v)) and np.all(v >= 0.0)):
            raise ValueError(f"speeds_m_per_s must be finite and >= 0, got {self.speeds_m_per_s!r}")
        dt = np.diff(t)
        if self.accelerations_m_per_s2 is None:
            a0 = a1 = np.diff(v) / dt                                  # constant per phase
        else:
            a = np.asarray(self.accelerations_m_per_s2, float)
            if a.shape != t.shape or not np.all(np.isfinite(a)):
                raise ValueError(f"accelerations_m_per_s2 must be finite, one per knot, got {self.accelerations_m_per_s2!r}")
            a0, a1 = a[:-1], a[1:]
            gap = np.abs(v[:-1] + 0.5 * (a0 + a1) * dt - v[1:])
            if np.any(gap > 1e-9 * np.maximum(1.0, np.abs(v[1:]))):
                i = int(np.argmax(gap))
                raise ValueError(f"the speeds are not the integral of the accelerations: from knot {i} to {i + 1} "
                                 f"the speed changes by {v[i + 1] - v[i]:.9g} m/s, the accelerations give "
                                 f"{0.5 * (a0[i] + a1[i]) * dt[i]:.9g} m/s")
            # v within a phase is a parabola: its vertex, where the acceleration passes 0, must not dip below 0
            turn = (a0 * a1 < 0.0) & (a0 < 0.0)
            u = np.where(turn, a0 * dt / np.where(turn, a0 - a1, 1.0), 0.0)
            low = v[:-1] + a0 * u + 0.5 * (a1 - a0) / dt * u * u
            if np.any(turn & (low < -1e-9)):
                raise ValueError("the accelerations take the speed below 0 between two knots")
        if self.accelerations_m_per_s2 is None:
            step = 0.5 * (v[1:] + v[:-1]) * dt                        # trapezoids
        else:
            step = v[:-1] * dt + (2.0 * a0 + a1) * dt * dt / 6.0
        s = np.concatenate([[0.0], np.cumsum(step)])
        for name, value in (("_t", t), ("_v", v), ("_s", s), ("_a0", a0), ("_a1", a1), ("_t_list", t.tolist())):
            object.__setattr__(self, name, value)

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

    def _polynomial(self, i: int, u: float):
        """(s, v, a) at ``u`` into phase i (u in [0, t_i+1 - t_i]; i and u may be arrays)."""
        a0 = self._a0[i]
        if self.accelerations_m_per_s2 is None:
            return self._s[i] + self._v[i] * u + 0.5 * a0 * u * u, self._v[i] + a0 * u, a0
        jerk = (self._a1[i] - a0) / (self._t[i + 1] - self._t[i])
        return (self._s[i] + u * (self._v[i] + u * (0.5 * a0 + u * jerk / 6.0)),
                self._v[i] + u * (a0 + 0.5 * jerk * u), a0 + jerk * u)

    def acceleration(self, t_s: float) -> float:
        """dv/dt at t [m/s^2] (the phase's holding t; 0 before the first and after the last knot)."""
        if t_s < 0.0 or t_s >= self._t_list[-1]:
            return 0.0
        i = self._phase(t_s)
        return float(self._polynomial(i, t_s - self._t_list[i])[2])

    def speed(self, t_s):
        """v(t) [m/s]."""
        if self.accelerations_m_per_s2 is None:
            return np.interp(t_s, self._t, self._v)
        t = np.clip(np.asarray(t_s, float), self._t[0], self._t[-1])
        i = np.clip(np.searchsorted(self._t, t, side="right") - 1, 0, len(self._t) - 2)
        v = self._polynomial(i, t - self._t[i])[1]
        return float(v) if np.ndim(t_s) == 0 else v

    def _distance(self, t: float) -> float:
        t_list = self._t_list
        if t <= 0.0:
            return float(self._v[0]) * t
        if t >= t_list[-1]:
            return float(self._s[-1] + self._v[-1] * (t - t_list[-1]))
        i = self._phase(t)
        return float(self._polynomial(i, t - t_list[i])[0])

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
        rest = distance_m - s[i]
        if self._a0[i] == self._a1[i]:                                # a quadratic: its root
            a = self._a0[i]
            if a == 0.0:
                return float(self._t[i] + rest / v0) if v0 > 0.0 else float(self._t[i + 1])
            u = (-v0 + math.sqrt(max(v0 * v0 + 2.0 * a * rest, 0.0))) / a
            return float(self._t[i] + min(max(u, 0.0), dt))
        lo, hi = 0.0, dt                                              # a cubic, s nondecreasing: bisect
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if mid in (lo, hi):
                break
            if self._polynomial(i, mid)[0] < distance_m:
                lo = mid
            else:
                hi = mid
        return float(self._t[i] + hi)
