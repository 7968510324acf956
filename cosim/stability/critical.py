"""Modes across speed and the linear critical speed.

:func:`scan_speeds` computes every mode at each of a list of speeds; :func:`critical_speed`
finds where the least damped mode's damping ratio crosses zero: the first speed of the scan at
which a mode grows, then bisection between it and the speed before, until the bracket is
``resolution_m_per_s`` wide. The car's linearisation depends on the speed only (the creep
forces scale with 1/V), the air's on k only: ``car_at(v)`` is called once per speed and its
results may be cached across k.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, List, Optional, Sequence, Tuple, Union

import numpy as np

from cosim.stability.coupled import Mode, couple, modes
from pneumatics.linear import CircuitLinearisation
from vehicle.car.linear import CarLinearisation

__all__ = ["SpeedScan", "scan_speeds", "critical_speed", "least_damped", "grows", "modes_at", "DAMPING_TOLERANCE"]

#: a mode grows when its damping ratio is below minus this: the round-off of the central
#: differences (relative ~1e-8 in the matrices) stays two orders below it, and an undamped
#: mode of the model (the bellow-tank mode at k = 0 or inf, whose pipe loss has no linear part)
#: sits at 0 within it
DAMPING_TOLERANCE = 1e-6

CarAt = Callable[[float], CarLinearisation]
#: what the car is coupled to: the air's linearisation, or None (frozen air) with optional springs
#: between the bellows (:func:`~cosim.stability.coupled.couple`)
Air = Union[CircuitLinearisation, None, Tuple[None, np.ndarray]]


@dataclass(frozen=True)
class SpeedScan:
    """The modes at each speed of a scan (each list least damped first)."""

    speeds_m_per_s: np.ndarray
    modes: List[List[Mode]]


def least_damped(mode_list: Sequence[Mode], oscillatory: bool = False) -> Optional[Mode]:
    """The mode with the smallest damping ratio (``oscillatory``: among those with a frequency)."""
    chosen = [m for m in mode_list if m.oscillatory or not oscillatory]
    return min(chosen, key=lambda m: m.damping_ratio) if chosen else None


def grows(mode_list: Sequence[Mode]) -> bool:
    """Some mode grows (damping ratio below -:data:`DAMPING_TOLERANCE`)."""
    return any(m.damping_ratio < -DAMPING_TOLERANCE for m in mode_list)


def modes_at(car_at: CarAt, air: Air, v: float) -> List[Mode]:
    if isinstance(air, tuple):
        return modes(couple(car_at(v), None, air[1]))
    return modes(couple(car_at(v), air))


def scan_speeds(car_at: CarAt, air: Air, speeds_m_per_s: Sequence[float]) -> SpeedScan:
    """Every mode at each speed (ascending)."""
    speeds = np.sort(np.asarray(speeds_m_per_s, dtype=float))
    return SpeedScan(speeds, [modes_at(car_at, air, float(v)) for v in speeds])


def critical_speed(car_at: CarAt, air: Air, scan: SpeedScan,
                   resolution_m_per_s: float = 0.1) -> Tuple[Optional[float], Tuple[float, float], str]:
    """(critical speed [m/s] or None, its bracket (stable, growing) [m/s], a sentence saying what
    was found). None when no speed of the scan grows (stable up to its last speed) or the first
    one already does (below the scan)."""
    unstable = [grows(m) for m in scan.modes]
    speeds = scan.speeds_m_per_s
    if not any(unstable):
        return None, (float(speeds[-1]), float("nan")), f"no mode grows up to {speeds[-1]:g} m/s"
    first = unstable.index(True)
    if first == 0:
        return None, (float("nan"), float(speeds[0])), f"a mode grows already at {speeds[0]:g} m/s, the scan's lowest speed"
    lo, hi = float(speeds[first - 1]), float(speeds[first])
    while hi - lo > resolution_m_per_s:
        mid = 0.5 * (lo + hi)
        if grows(modes_at(car_at, air, mid)):
            hi = mid
        else:
            lo = mid
    v = 0.5 * (lo + hi)
    return v, (lo, hi), f"critical speed {v:.2f} m/s (stable at {lo:.3f}, growing at {hi:.3f} m/s)"
