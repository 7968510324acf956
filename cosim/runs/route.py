"""A line in service, planned: the stops the car makes (:class:`Stop`), the track it runs on
(straights and curves with their transitions and cant), its speed over time (accelerate, cruise,
brake to a stop at each station, stand for the dwell) and what its floor carries (passengers
alighting and boarding at each stop) -- everything :mod:`cosim.kinds.service` hands to the car,
computed once from the route (:func:`plan`).

Conventions:

* positions along the line ``at_m`` [m] from the first station, stations in increasing order;
  the car's centre stops exactly at a station's position (the speed profile's distance is the
  exact integral of its phases, :class:`vehicle.speed.PhasedSpeedProfile`);
* the track's arc length is the line position plus :attr:`Plan.offset_m` (the car starts with its
  rear wheelset at the track's start, :class:`vehicle.car.MetroCar`); a round trip continues
  onto the same line run backwards: the stations in reverse order with the platform on the other
  side of the car, each curve in reverse turning the other way (the car's front stays its front:
  the metro car is symmetric front to rear, so running the return with the other end leading is
  the same car);
* a stop's exchange: the doors open ``door_open_delay_s`` after the car stops and close
  ``door_close_s`` before it leaves; in between, the alighting passengers leave first (from the
  whole floor), then the boarding ones come in and stand on the platform side's half of the floor;
  after the car leaves they spread over the whole floor within ``spread_s``.
"""
from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import List, Optional, Sequence, Tuple

import numpy as np

from vehicle.payload import PayloadBlock
from vehicle.speed import PhasedSpeedProfile
from vehicle.track import Arc, Straight, TrackGeometry, Transition

#: the floor's patches a service's passengers stand on: (name, y of the patch centre as a fraction of
#: the floor's width, the patch's width as a fraction of it)
PATCHES = (("uniform", 0.0, 1.0), ("left", 0.25, 0.5), ("right", -0.25, 0.5))


@dataclass(frozen=True)
class Stop:
    """One stop of the car: the station's ``name``, the car centre's arc length on the track
    ``s_m``, arrival and departure ``arrive_s`` / ``depart_s``, the doors' opening and closing
    ``open_s`` / ``close_s``, the ``platform_side`` (of the car, as it runs), the passengers'
    masses alighting and boarding [kg] and the payload on board when the doors close [kg];
    ``direction``: ``out`` or ``back`` (round trip)."""

    name: str
    s_m: float
    arrive_s: float
    open_s: float
    close_s: float
    depart_s: float
    platform_side: str
    alighting_kg: float
    boarding_kg: float
    on_board_kg: float
    direction: str

    @property
    def alighted_s(self) -> float:
        """When the last alighting passenger is off (the exchange window split by the counts)."""
        total = self.alighting_kg + self.boarding_kg
        share = self.alighting_kg / total if total > 0.0 else 0.0
        return self.open_s + share * (self.close_s - self.open_s)


@dataclass(frozen=True)
class LineStation:
    """A station as the route gives it (:mod:`cosim.kinds.service`): position along the line [m],
    dwell [s], platform side, passengers alighting and boarding in each direction [kg]."""

    name: str
    at_m: float
    dwell_s: float
    platform_side: str
    alighting_kg: float
    boarding_kg: float
    return_alighting_kg: float
    return_boarding_kg: float


@dataclass(frozen=True)
class LineCurve:
    """A curve as the route gives it: where its entry transition starts along the line [m], its
    transitions, arc, radius, turn (+1 left, -1 right, as run outwards), cant [rad], transition shape."""

    at_m: float
    transition_m: float
    arc_m: float
    radius_m: float
    direction: int
    cant_rad: float
    transition_shape: str

    @property
    def length_m(self) -> float:
        return 2.0 * self.transition_m + self.arc_m

    @property
    def end_m(self) -> float:
        return self.at_m + self.length_m

    def returned(self, line_length_m: float) -> "LineCurve":
        """The same curve on the return of a round trip along a line of ``line_length_m``: at
        2 L - its end on the track's line positions, turning the other way."""
        return LineCurve(2.0 * line_length_m - self.end_m, self.transition_m, self.arc_m, self.radius_m,
                         -self.direction, self.cant_rad, self.transition_shape)


@dataclass(frozen=True)
class Plan:
    """A route planned for the car: its ``stops``, ``track``, ``speed`` profile, the track's arc
    length of the line's origin ``offset_m``, the run's ``duration_s``, and the payload's knots
    (:meth:`payload`)."""

    stops: Tuple[Stop, ...]
    track: TrackGeometry
    speed: PhasedSpeedProfile
    offset_m: float
    duration_s: float
    initial_kg: float
    #: the payload on each patch of :data:`PATCHES` at the knot times (piecewise linear between)
    knots_s: Tuple[float, ...]
    patch_kg: Tuple[Tuple[float, ...], ...]
    #: the grade under the car centre at a track arc length (None: a level line)
    grade: Optional[RouteGrade] = None


@dataclass(frozen=True)
class LineGrade:
    """A gradient as the route gives it: a section of the line from ``at_m`` over ``length_m``
    [m] at ``grade`` (rise over run as run outwards, > 0 rising), reached and left over
    ``transition_m`` at each end, the grade changing linearly there (a vertical curve of radius
    transition_m / grade)."""

    at_m: float
    length_m: float
    grade: float
    transition_m: float

    def at(self, x_m: float) -> float:
        """The grade of this section at line position ``x_m`` (0 outside it)."""
        u = min(x_m - self.at_m, self.at_m + self.length_m - x_m)
        if u <= 0.0:
            return 0.0
        return self.grade if u >= self.transition_m else self.grade * u / self.transition_m


@dataclass(frozen=True)
class RouteGrade:
    """The grade under the car centre at a track arc length (:class:`~vehicle.car.MetroCar`'s
    ``grade``): the sections' at the line position, and on a round trip's way back (beyond the
    terminus) the way out's mirrored and negated: what rose falls. Picklable (it travels with the
    car's factory)."""

    sections: Tuple[LineGrade, ...]
    offset_m: float
    line_m: float
    round_trip: bool

    def __call__(self, s_m: float) -> float:
        x = s_m - self.offset_m
        sign = 1.0
        if self.round_trip and x > self.line_m:
            x, sign = 2.0 * self.line_m - x, -1.0
        return sign * sum(g.at(x) for g in self.sections)


def _speed_change(v_m_per_s: float, accel: float, jerk: Optional[float]) -> List[Tuple[float, float, float]]:
    """(duration [s], speed change at its end [m/s], |acceleration| at its end [m/s^2]) of the
    phases that change the speed by ``v_m_per_s`` at most ``accel``: one phase of constant
    acceleration without a jerk limit; with one, the acceleration ramps in at ``jerk``, holds at
    ``accel`` and ramps out (or, for a small change, ramps in and out to sqrt(v j) without
    holding). Symmetric in time, so the distance run is the mean speed times the duration."""
    if jerk is None:
        return [(v_m_per_s / accel, v_m_per_s, 0.0)]
    peak = min(accel, math.sqrt(v_m_per_s * jerk))
    ramp, ramp_v = peak / jerk, 0.5 * peak * peak / jerk
    phases = [(ramp, ramp_v, peak)]
    hold = v_m_per_s / peak - ramp                       # the acceleration held at its peak
    if hold > 1e-12 * ramp:
        phases.append((hold, v_m_per_s - ramp_v, peak))
    phases.append((ramp, v_m_per_s, 0.0))
    return phases


def run_phases(distance_m: float, line_speed: float, accel: float, brake: float,
               jerk: Optional[float] = None) -> List[Tuple[float, float, float]]:
    """(duration [s], speed at its end [m/s], acceleration at its end [m/s^2]) of the phases of a
    run of ``distance_m`` from a stop to a stop: accelerate at ``accel`` to the line speed (or as
    far as the distance allows), cruise, brake at ``brake`` to the stop (the trapezoid or triangle
    of the speed); with a ``jerk`` limit [m/s^3] each change of acceleration ramps at it."""
    def needed(v):                                       # the distance to reach v and stop again (mean speed v / 2)
        return 0.5 * v * sum(d for change in (accel, brake) for d, _, _ in _speed_change(v, change, jerk))

    if jerk is None:                                     # (the arithmetic before the jerk limit, to the bit)
        v_top = min(line_speed, math.sqrt(2.0 * distance_m * accel * brake / (accel + brake)))
        cruise_m = distance_m - v_top * v_top / (2.0 * accel) - v_top * v_top / (2.0 * brake)
    elif needed(line_speed) <= distance_m:
        v_top = line_speed
    else:                                                # needed(v) increases with v: bisect
        lo, hi = 0.0, line_speed
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if mid in (lo, hi):
                break
            lo, hi = (mid, hi) if needed(mid) <= distance_m else (lo, mid)
        v_top = lo
    if jerk is not None:
        cruise_m = distance_m - needed(v_top)
    phases = _speed_change(v_top, accel, jerk)
    if cruise_m > 1e-9 * distance_m:
        phases.append((cruise_m / v_top, v_top, 0.0))
    phases += [(d, v_top - v, -a) for d, v, a in _speed_change(v_top, brake, jerk)]
    return phases


def run_time_s(distance_m: float, line_speed: float, accel: float, brake: float, jerk: Optional[float] = None) -> float:
    """How long a run from stop to stop takes [s] (:func:`run_phases`)."""
    return sum(d for d, _, _ in run_phases(distance_m, line_speed, accel, brake, jerk))


def _track(curves: Sequence[LineCurve], offset_m: float, length_m: float) -> TrackGeometry:
    """Straights between the curves (in order along the track, positions on the line + offset)."""
    segments, s = [], 0.0
    for c in curves:
        start = c.at_m + offset_m
        if start > s:
            segments.append(Straight(start - s))
        segments += [Transition(c.transition_m, c.transition_shape),
                     Arc(c.radius_m, c.arc_m, c.direction, c.cant_rad),
                     Transition(c.transition_m, c.transition_shape)]
        s = start + c.length_m
    segments.append(Straight(length_m - s))
    return TrackGeometry(tuple(segments))


def plan(stations: Sequence[LineStation], curves: Sequence[LineCurve], *, round_trip: bool, line_speed_m_per_s: float,
         acceleration_m_per_s2: float, braking_m_per_s2: float, door_open_delay_s: float, door_close_s: float,
         spread_s: float, initial_kg: float, car_half_length_m: float, slack_m: float = 0.0,
         grades: Sequence[LineGrade] = (), jerk_m_per_s3: Optional[float] = None) -> Plan:
    """The route as the car runs it (module docstring). ``car_half_length_m``: from the car centre
    to its front wheelset (the track starts that far plus ``slack_m`` behind the origin and ends
    that far plus 10 m beyond the last stop). ``jerk_m_per_s3``: the jerk limit of the runs
    between the stations (:func:`run_phases`; None: none, the acceleration steps)."""
    line_m = stations[-1].at_m
    offset = car_half_length_m + slack_m
    calls = [(st, st.at_m, st.platform_side, "out") for st in stations]
    track_curves = list(curves)
    if round_trip:
        flip = {"left": "right", "right": "left"}
        calls += [(st, 2.0 * line_m - st.at_m, flip[st.platform_side], "back") for st in reversed(stations[:-1])]
        track_curves += [c.returned(line_m) for c in reversed(curves)]
    end_m = calls[-1][1]
    track = _track(track_curves, offset, end_m + offset + car_half_length_m + 10.0)

    times, speeds, accels = [0.0], [0.0], [0.0]
    stops: List[Stop] = []
    on_board = initial_kg
    t = 0.0
    for i, (st, pos, side, direction) in enumerate(calls):
        if i > 0:
            for duration, v, a in run_phases(pos - calls[i - 1][1], line_speed_m_per_s, acceleration_m_per_s2,
                                             braking_m_per_s2, jerk_m_per_s3):
                t += duration
                times.append(t)
                speeds.append(v)
                accels.append(a)
        turning = round_trip and direction == "out" and st is stations[-1]   # the terminus: alight, board for the return
        alight = st.alighting_kg if direction == "out" else st.return_alighting_kg
        board = st.return_boarding_kg if turning or direction == "back" else st.boarding_kg
        on_board = on_board - alight + board
        arrive, depart = t, t + st.dwell_s
        stops.append(Stop(st.name, pos + offset, arrive, arrive + door_open_delay_s, depart - door_close_s, depart,
                          side, alight, board, on_board, direction))
        t = depart
        times.append(t)
        speeds.append(0.0)
        accels.append(0.0)
    speed = PhasedSpeedProfile(tuple(times), tuple(speeds), None if jerk_m_per_s3 is None else tuple(accels))
    knots, patch = _payload_knots(stops, initial_kg, spread_s)
    grade = RouteGrade(tuple(grades), offset, line_m, round_trip) if grades else None
    return Plan(tuple(stops), track, speed, offset, t, initial_kg, knots, patch, grade)


def _payload_knots(stops: Sequence[Stop], initial_kg: float, spread_s: float):
    """The payload on each patch of :data:`PATCHES` as knots of a piecewise-linear function of
    time: every stop's alighting (from the whole floor), boarding (onto the platform side) and,
    after the car leaves, the boarders' spreading over the floor."""
    ramps = []                                         # (t0, t1, change per patch)
    for st in stops:
        side = [name for name, *_ in PATCHES].index(st.platform_side)
        if st.alighting_kg > 0.0:
            ramps.append((st.open_s, st.alighted_s, {0: -st.alighting_kg}))
        if st.boarding_kg > 0.0:
            ramps.append((st.alighted_s, st.close_s, {side: st.boarding_kg}))
            ramps.append((st.depart_s, st.depart_s + spread_s, {side: -st.boarding_kg, 0: st.boarding_kg}))
    knots = sorted({0.0, *(t for r in ramps for t in r[:2])})
    kg = np.zeros((len(knots), len(PATCHES)))
    kg[:, 0] = initial_kg
    k = np.asarray(knots)
    for t0, t1, change in ramps:
        done = np.clip((k - t0) / (t1 - t0), 0.0, 1.0) if t1 > t0 else (k >= t0).astype(float)
        for patch, dm in change.items():
            kg[:, patch] += dm * done
    kg[np.abs(kg) < 1e-9 * max(initial_kg, 1.0)] = 0.0   # round-off of a patch emptied again
    return tuple(knots), tuple(map(tuple, kg.T))


class RoutePayload:
    """What the floor carries at t, ``MetroCar(payload=...)``: a block per patch of
    :data:`PATCHES` (piecewise linear in t between the plan's knots). Three blocks whatever the
    number of stops; between knots where nothing changes (the car running, most of a trip) the
    same tuple is returned without arithmetic. Picklable for the worker processes."""

    def __init__(self, plan: Plan, floor_length_m: float, floor_width_m: float, height_m: float, cog_above_floor_m: float):
        self._knots = list(plan.knots_s)
        self._kg = np.asarray(plan.patch_kg).T                      # (knots, patches)
        self._shape = [(fy * floor_width_m, floor_length_m, fw * floor_width_m) for _, fy, fw in PATCHES]
        self._height, self._cog = height_m, cog_above_floor_m
        #: per knot: the blocks held until the next knot when nothing changes there, else None
        self._held = [self._blocks(self._kg[i]) if i + 1 == len(self._knots) or np.array_equal(self._kg[i], self._kg[i + 1])
                      else None for i in range(len(self._knots))]

    def _blocks(self, kg) -> Tuple[PayloadBlock, ...]:
        return tuple(PayloadBlock(float(m), 0.0, y, length, width, self._height, self._cog)
                     for m, (y, length, width) in zip(kg, self._shape))

    def __call__(self, t_s: float) -> Tuple[PayloadBlock, ...]:
        i = max(bisect.bisect_right(self._knots, t_s) - 1, 0)
        held = self._held[i]
        if held is not None:
            return held
        t0, t1 = self._knots[i], self._knots[i + 1]
        return self._blocks(self._kg[i] + (self._kg[i + 1] - self._kg[i]) * ((t_s - t0) / (t1 - t0)))

    def total_kg(self, t_s) -> np.ndarray:
        """The payload on board at ``t_s`` [kg]."""
        return sum(np.interp(t_s, self._knots, self._kg[:, j]) for j in range(len(PATCHES)))


__all__ = ["Stop", "LineStation", "LineCurve", "Plan", "plan", "run_phases", "run_time_s", "RoutePayload", "PATCHES"]
