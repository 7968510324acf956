"""Where the car is along its track over time: the arc lengths at t = 0, the speed profile, the
distance run, the tabulated track (:class:`CarPath`)."""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ..guidance import TrackSampler, shared_sampler
from ..speed import PhasedSpeedProfile, SpeedProfile
from ..track import TrackGeometry
from .options import RunSettings


@dataclass(frozen=True)
class CarPath:
    """The car's run along its track (or along x without one)."""

    #: centre line the car runs along (None: unbounded straight level track along x)
    track: TrackGeometry | None
    #: running speed at t = 0 [m/s]
    speed_m_per_s: float
    #: arc length [m] of the car centre at t = 0
    start_s_m: float
    #: (4,) arc lengths [m] of the wheelsets at t = 0
    wheelset_s0_m: np.ndarray
    #: x [m] of the car centre at t = 0 (the track starts at the origin)
    x0_m: float
    #: the track tabulated for the per-step evaluations (None without a track)
    sampler: TrackSampler | None
    #: the track has cant somewhere
    canted: bool
    #: the guidance follows the track (a track, or a running car along x)
    guided: bool
    #: the speed over time (:class:`~vehicle.speed.SpeedProfile` or
    #: :class:`~vehicle.speed.PhasedSpeedProfile`)
    speed_profile: SpeedProfile | PhasedSpeedProfile

    @classmethod
    def plan(cls, run: RunSettings, wheelset_x_m: np.ndarray, contact_guidance: bool,
             wheel_drive: bool = False) -> CarPath:
        """The path of a car with wheelsets at ``wheelset_x_m`` from its centre; checks the
        straight, level start."""
        track, v, start_s = run.track, float(run.speed_m_per_s), run.start_s_m
        if start_s is None:
            start_s = float(-wheelset_x_m[-1]) if track is not None else 0.0
        start_s = float(start_s)
        if not math.isfinite(start_s):
            raise ValueError(f"start_s_m must be finite, got {start_s!r}")
        s0 = start_s + wheelset_x_m
        sampler, canted, guided = None, False, v != 0.0 or run.speed_profile is not None
        if track is not None:
            _check_start(track, s0)
            sampler, guided = shared_sampler(track), True
            canted = any(getattr(seg, "cant_rad", 0.0) != 0.0 for seg in track.segments)
        profile = run.speed_profile or SpeedProfile(float(max(run.speed_m_per_s, 0.0)), *(run.deceleration or (0.0, 0.0)))
        if run.deceleration is not None and not contact_guidance:
            raise ValueError("deceleration needs guidance='contact' (the kinematic guidance prescribes a "
                             "constant speed or a speed_profile)")
        if run.speed_profile is not None and contact_guidance and not wheel_drive:
            raise ValueError("a speed_profile with guidance='contact' needs drive=WheelDrive() (traction and "
                             "braking through the wheels): with guidance='kinematic' the joints lead "
                             "the wheelsets; the joint that drives a contact car at its centre is for constant "
                             "speed or a ramp-down")
        return cls(track, v, start_s, s0, start_s, sampler, canted, guided, profile)

    def distance_m(self, t):
        """Distance run since t = 0 [m]: v t at constant speed, else the speed profile's."""
        return self.speed_m_per_s * t if self.speed_profile.constant else self.speed_profile.distance(t)

    def distance_between_m(self, t0: float, t1: float) -> float:
        """Distance run from t0 to t1 [m]: v (t1 - t0) at constant speed (rounded as it always was:
        a constant-speed run stays the same bit for bit), else the speed profile's."""
        if self.speed_profile.constant:
            return self.speed_m_per_s * (t1 - t0)
        return self.speed_profile.distance(t1) - self.speed_profile.distance(t0)

    def centre_s_m(self, t: float) -> float:
        """Arc length [m] of the car centre at time t."""
        return self.start_s_m + self.distance_m(t)

    def reach_m(self, t: float) -> float:
        """An upper bound of the distance [m] of the car's wheelsets from the origin at time t
        (the track starts at the origin; a car without one runs along x): the largest of
        their arc lengths' magnitudes, plus the distance run (a profile's distance is monotonic,
        so the bound holds over the whole advance to t)."""
        return self._s0_reach_m + abs(self.distance_m(t))

    @functools.cached_property
    def _s0_reach_m(self) -> float:
        """The largest of the wheelsets' arc lengths' magnitudes at t = 0 [m]."""
        return float(np.max(np.abs(self.wheelset_s0_m)))

    @property
    def t_end_max_s(self) -> float:
        """Latest time [s] the front wheelset is still on the track (inf without a track; a
        decelerating car: the time its speed reaches zero at most)."""
        if not self.speed_profile.constant:
            if self.track is None:
                return self.speed_profile.usable_until_s
            return self.speed_profile.time_at_distance(self.track.total_length_m - self.wheelset_s0_m[0])
        v = self.speed_m_per_s
        if self.track is None or v == 0.0:
            return math.inf
        if v > 0.0:
            return (self.track.total_length_m - self.wheelset_s0_m[0]) / v
        return -self.wheelset_s0_m[-1] / v


def _check_start(track: TrackGeometry, s: np.ndarray) -> None:
    """ValueError unless the wheelsets at arc lengths ``s`` are on ``track``, on a straight level
    start along x (the start state is the static equilibrium on level track)."""
    if not isinstance(track, TrackGeometry):
        raise ValueError(f"track must be a TrackGeometry or None, got {type(track).__name__}")
    if s.min() < 0.0 or s.max() > track.total_length_m:
        raise ValueError(f"the car (wheelsets at s = {s} m) is not on the track "
                         f"[0, {track.total_length_m}] m at t = 0")
    x, y = track.position_m(s)
    straight = (np.all(track.curvature_per_m(s) == 0.0) and np.all(track.cant_rad(s) == 0.0)
                and np.all(np.abs(track.heading_rad(s)) <= 1e-12)
                and np.all(np.abs(y) <= 1e-9) and np.all(np.abs(x - s) <= 1e-9))
    if not straight:
        raise ValueError("the track must be straight and level along x under the whole car "
                         f"at t = 0 (wheelsets at s = {s} m): start on the initial straight")
