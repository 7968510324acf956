"""How fast the car runs: :class:`SpeedProfile`, a constant speed, then (optionally) a constant
deceleration -- the ramp-down of a nonlinear critical-speed run (start on a hunting limit cycle,
slow down until it dies)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["SpeedProfile"]


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
