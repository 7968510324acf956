"""A line in service: the car runs a route of stations (accelerate, cruise, brake to a stop,
stand for the dwell while passengers alight and board on the platform side), through curves with
cant and transitions, and the levelling valves keep the floor at the platforms. Kind
``service``, section ``service`` (:class:`Service`); the route is planned by
:mod:`cosim.runs.route`.

Per case (k value x valve setting) the summary gives the trip's worst floor at the doors (on the
platform side, relative to the platform: the floor's height at the start, the car levelled with
its initial load at the first station), the stops whose floor misses the tolerance at door close,
the longest re-levelling, the valve openings and the air: injected and exhausted, in kg and in
normal litres, with the compressor's duty and energy where the circuit has one. The table
``stops`` gives every stop of every case: the floor at arrival, at its lowest and highest while
the doors are open and at door close, the time it needs to re-level, the valve openings and the
air injected during the stop.

``air_per_stop`` (:class:`AirPerStop`): the brakes and doors take an amount of air from the main
reservoir at every stop, a demand on the circuit's supply that draws only while the car stands
(:class:`~pneumatics.air_supply.ScheduledDemand`, switched by the co-simulation); the stops table
and the summary then give what it drew.

The car runs on kinematic guidance (the wheelsets led along the track at the speed profile's
s(t)): the longitudinal inertia of braking and accelerating reaches the carbody through the
guidance at the axle centres, not as creep forces at the rails (docs/service.md); or, with
``drive`` (:class:`DriveSpec`), on the wheel-rail contact, braked and driven through its wheels.
``gradients``: the line rises and falls (the car's weight tilts with the grade under its centre).
"""
from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import xarray as xr

from cosim.engine.cases import simulate_cases
from cosim.engine.master import Output, PerCar
from cosim.errors import ScenarioError
from cosim.kinds.base import CarKind
from cosim.kinds.station_stop import Doors, FloorHeights, check_doors, openings, payload_kg
from cosim.results.io import Progress
from cosim.results.outcome import Computed, Outcome, warn
from cosim.results.overlay import Selection, case_series
from cosim.results.plots import Curve, Figure, Panel, k_legend, save_panels
from cosim.runs.car import air_columns, fault_columns, of_setting, per_case
from cosim.runs.route import LineCurve, LineGrade, LineStation, Plan, RoutePayload, plan, run_time_s
from cosim.runs.track_run import plane_roll_rad
from cosim.runs.track_spec import CANT, MAX_TRACK_LENGTH_M, RADIUS, SPEED, TRANSITION
from cosim.scenario.imported import is_imported
from cosim.scenario.model import Scenario
from cosim.scenario.payload import PayloadSchedule, PayloadSettings
from cosim.scenario.schema import build, check_keys, check_valve_settings, describe, is_key, k_label, set_at_load
from pneumatics.air_supply import DP_OFF, ScheduledDemand, normal_density_kg_per_m3
from pneumatics.boundary import Supply
from pneumatics.chamber import Tank
from pneumatics.gas import AIR
from pneumorail.quantities import plausible, ranged
from vehicle.params import VehicleParams
from vehicle.track import TRANSITION_SHAPES

SIDES = ("left", "right")
#: the air per stop's demand in the circuit: its link's name, its share of ``air_demand_kg``
STOP_DEMAND = "air_per_stop"


@dataclass(frozen=True)
class StationSpec:
    """A station of ``service.stations``: its ``name``, position along the line ``at_m`` from the
    first station [m], ``dwell_s``, the ``platform_side`` as the car runs outwards, and the
    passengers alighting and boarding there outwards; ``return_alighting`` / ``return_boarding``
    on the way back (null: the outward flows reversed, i.e. those who boarded alight and those who
    alighted board)."""

    name: str
    at_m: float = field(metadata=plausible(0.0, MAX_TRACK_LENGTH_M / 2, "m", "along the line from its first station"))
    dwell_s: float = field(default=30.0, metadata=plausible(0.0, 3600.0, "s", "a dwell, up to an hour", low_inclusive=False))
    platform_side: str = "right"
    alighting: int = field(default=0, metadata=plausible(0, 1000, why="passengers"))
    boarding: int = field(default=0, metadata=plausible(0, 1000, why="passengers"))
    return_alighting: Optional[int] = field(default=None, metadata=plausible(0, 1000, why="passengers"))
    return_boarding: Optional[int] = field(default=None, metadata=plausible(0, 1000, why="passengers"))


@dataclass(frozen=True)
class CurveSpec:
    """A curve of ``service.curves``: its entry transition starts ``at_m`` along the line [m]; two
    transitions of ``transition_m``, an arc of ``arc_m`` and ``radius_m``, turning ``left`` or
    ``right`` (as the car runs outwards), ``cant_rad`` (positive raises the outer rail),
    ``transition_shape`` (as a curve entry's)."""

    at_m: float = field(metadata=plausible(0.0, MAX_TRACK_LENGTH_M / 2, "m", "along the line from its first station"))
    radius_m: float = field(metadata=RADIUS)
    arc_m: float = field(metadata=plausible(0.0, 1e4, "m", "a curve's arc", low_inclusive=False))
    transition_m: float = field(default=30.0, metadata=TRANSITION)
    direction: str = "left"
    cant_rad: float = field(default=0.0, metadata=CANT)
    transition_shape: str = "bloss"


@dataclass(frozen=True)
class GradientSpec:
    """A gradient of ``service.gradients``: the section from ``at_m`` along the line over
    ``length_m`` [m] rises at ``grade`` (rise over run, > 0 rising as the car runs outwards;
    0.04 is 4 %), reached and left over ``transition_m`` at each end, where the grade changes
    linearly (a vertical curve; **assumed** 50 m: radius 1 250 m at 4 %). The car's weight tilts
    with the grade under its centre (vehicle/car/gradient.py); on a round trip's way back what
    rose falls."""

    at_m: float = field(metadata=plausible(0.0, MAX_TRACK_LENGTH_M / 2, "m", "along the line from its first station"))
    length_m: float = field(metadata=plausible(0.0, MAX_TRACK_LENGTH_M / 2, "m", "a gradient's section",
                                               low_inclusive=False))
    grade: float = field(metadata=plausible(-0.1, 0.1, "", "rise over run: metros climb up to ~6 %, rarely more; "
                                            "0.1 is 10 %", nonzero=True))
    transition_m: float = field(default=50.0, metadata=plausible(0.0, 1000.0, "m", "a vertical curve's length"))


@dataclass(frozen=True)
class AirPerStop:
    """``service.air_per_stop``: the air the brakes and doors take from the main reservoir
    (``circuit.supply``, which then needs a volume ``V_m3``) at every stop of the route, the first
    included: ``normal_volume_m3`` of free air (DIN 1343 normal cubic metres, 0 degC and
    1.01325 bar; 40 Nl = 0.04), drawn at a constant rate from the car's arrival to its departure.
    Default **assumed** 40 Nl: one brake application and one cycle of the platform side's three
    doors of a metro car (docs/service.md). Like ``circuit.air_demand`` the draw fades out within
    ``dp_off_Pa`` of the atmosphere's pressure."""

    normal_volume_m3: float = field(default=0.04, metadata=plausible(
        0.0, 1.0, "m^3", "a car's air at a stop, up to 1 Nm^3 (1000 Nl)", low_inclusive=False))
    dp_off_Pa: float = field(default=2.0e4, metadata=DP_OFF)


#: a car driven through its wheels divides its creepages by at least this speed [m/s] below it
#: (vehicle.params.ContactParams.min_creep_speed_m_per_s; 0.01 by default). At 0.01 the creep
#: law is a 1e9 N s/m damper that saturates at ~1e-5 m/s of slip, and each start from rest and
#: each stop under the brakes' torque took ~950 fresh Newton Jacobians within a quarter second
#: while exudyn cut the step to 6 us (measured: a car started at 1 m/s^2 and braked to a stand);
#: at 0.03 the whole trip took 35, at 0.1 26, with the same wheel loads over 10 s of standing to
#: 0.2 N and no lateral drift. 0.1 keeps a margin; above it the law is Kalker's.
WHEEL_DRIVE_MIN_CREEP_SPEED_M_PER_S = 0.1
#: the track starts this far behind the car's rear wheelset at the first station when the car is
#: driven through its wheels [m]: standing there on its brakes it may creep back by micrometres
WHEEL_DRIVE_TRACK_SLACK_M = 1.0


@dataclass(frozen=True)
class DriveSpec:
    """``service.drive``: the car accelerated and braked **through its wheels** (null, the default:
    kinematic guidance, the cheaper longitudinal model). The car then runs on the wheel-rail
    contact (free wheelsets, Kalker creep forces, as ``guidance: contact`` of a curve entry) and
    is moved along the route's speed profile by torques on its wheelsets (vehicle.car.WheelDrive):
    traction on ``motored_wheelsets`` (1..4 from the front; all four: **assumed**, a motor car
    Bo'Bo'), braking on all. ``friction_coefficient``: the wheel-rail mu, the adhesion limit
    (null: 0.36, dry rail; wet rail 0.15-0.25). ``tracking_frequency_Hz`` and
    ``tracking_damping_ratio``: the driver's feedback on the car's position against the profile.
    The summary then gives the largest share of the adhesion the wheels used."""

    motored_wheelsets: Tuple[int, ...] = field(default=(1, 2, 3, 4), metadata=plausible(
        1, 4, why="wheelset numbers from the front", non_empty=True, unique=True))
    friction_coefficient: Optional[float] = field(default=None, metadata=plausible(
        0.0, 1.0, why="a wheel-rail friction coefficient; dry rail 0.3-0.5", low_inclusive=False))
    tracking_frequency_Hz: float = field(default=0.5, metadata=plausible(
        0.0, 5.0, "Hz", "below the carbody's surge on its traction rods (~5 Hz)", low_inclusive=False))
    tracking_damping_ratio: float = field(default=1.0, metadata=plausible(0.0, 10.0, low_inclusive=False))

    def wheel_drive(self):
        """The car's :class:`vehicle.car.WheelDrive`."""
        from vehicle.car.wheel_drive import WheelDrive
        return WheelDrive(self.motored_wheelsets, self.tracking_frequency_Hz, self.tracking_damping_ratio)

    def contact_params(self):
        """The contact's parameters: mu, and the creep regularisation a start and a stop need."""
        from vehicle.params import ContactParams
        mu = {} if self.friction_coefficient is None else {"friction_coefficient": self.friction_coefficient}
        return ContactParams(min_creep_speed_m_per_s=WHEEL_DRIVE_MIN_CREEP_SPEED_M_PER_S, **mu)


@dataclass(frozen=True)
class Service(Doors):
    """A route run by one car (module docstring). ``line_speed_m_per_s``: the speed it cruises
    at between stations (**assumed** 70 km/h, a metro's); ``acceleration_m_per_s2`` and
    ``braking_m_per_s2``: its service acceleration and braking (**assumed** 1.0 m/s2 each,
    typical of metro stock); ``jerk_m_per_s3``: how fast the traction and brake controller ramps
    the acceleration in and out (null, the default: at once, the acceleration steps; a metro's
    controller ramps at ~0.5-1.5 m/s3, **assumed**); ``round_trip``: back to the first station after the last;
    ``door_open_delay_s``, ``door_close_s``: from the stop to the doors open, from their closing
    to the departure (**assumed** 2 s and 3 s); ``spread_s``: how long the boarders take to
    spread from the platform side over the floor after departure (**assumed** 15 s). The doors and
    the floor's tolerance as a station stop's (:class:`~cosim.kinds.station_stop.Doors`).
    ``valve_settings``: as the twist's. ``air_per_stop``: the air the brakes and doors take from
    the main reservoir at every stop (:class:`AirPerStop`; null: none). ``drive``: braking and
    traction through the wheels (:class:`DriveSpec`; null: kinematic guidance). ``gradients``:
    the line's rising and falling sections (:class:`GradientSpec`; none: a level line)."""

    stations: Tuple[StationSpec, ...] = ()
    curves: Tuple[CurveSpec, ...] = ()
    gradients: Tuple[GradientSpec, ...] = ()
    line_speed_m_per_s: float = field(default=70.0 / 3.6, metadata=ranged(SPEED))
    acceleration_m_per_s2: float = field(default=1.0, metadata=plausible(
        0.0, 3.0, "m/s^2", "a train's acceleration; 3 m/s^2 is a third of g", low_inclusive=False))
    braking_m_per_s2: float = field(default=1.0, metadata=plausible(
        0.0, 3.0, "m/s^2", "a train's braking; emergency braking of metros reaches ~1.5 m/s^2", low_inclusive=False))
    jerk_m_per_s3: Optional[float] = field(default=None, metadata=plausible(
        0.0, 20.0, "m/s^3", "a controller's jerk limit; metros ramp at ~0.5-1.5 m/s^3", low_inclusive=False))
    round_trip: bool = True
    door_open_delay_s: float = field(default=2.0, metadata=plausible(0.0, 60.0, "s"))
    door_close_s: float = field(default=3.0, metadata=plausible(0.0, 60.0, "s"))
    spread_s: float = field(default=15.0, metadata=plausible(0.0, 600.0, "s", low_inclusive=False))
    valve_settings: Optional[Tuple[bool, ...]] = None
    air_per_stop: Optional[AirPerStop] = None
    drive: Optional[DriveSpec] = None
    # set at load, not keys: the car's half length (centre to front wheelset) and the payload's settings
    car_half_length_m: float = field(default=6.0, metadata=set_at_load(plausible(0.5, 30.0, "m",
                                                                                  "a car's centre to its front wheelset")))
    payload_settings: PayloadSettings = field(default=PayloadSettings(), metadata=set_at_load())
    initial_kg: float = field(default=0.0, metadata=set_at_load(plausible(0.0, 1e5, "kg", "a car's payload")))

    @property
    def plan(self) -> Plan:
        """The route as the car runs it (:func:`cosim.runs.route.plan`)."""
        return _plan(self)


@functools.lru_cache(maxsize=16)
def _plan(service: Service) -> Plan:
    mass = service.payload_settings.passenger_mass_kg
    stations = [LineStation(st.name, st.at_m, st.dwell_s, st.platform_side, st.alighting * mass, st.boarding * mass,
                            (st.boarding if st.return_alighting is None else st.return_alighting) * mass,
                            (st.alighting if st.return_boarding is None else st.return_boarding) * mass)
                for st in service.stations]
    curves = [LineCurve(c.at_m, c.transition_m, c.arc_m, c.radius_m, 1 if c.direction == "left" else -1, c.cant_rad,
                        c.transition_shape) for c in service.curves]
    grades = [LineGrade(g.at_m, g.length_m, g.grade, g.transition_m) for g in service.gradients]
    return plan(stations, curves, round_trip=service.round_trip, line_speed_m_per_s=service.line_speed_m_per_s,
                acceleration_m_per_s2=service.acceleration_m_per_s2, braking_m_per_s2=service.braking_m_per_s2,
                door_open_delay_s=service.door_open_delay_s, door_close_s=service.door_close_s,
                spread_s=service.spread_s, initial_kg=service.initial_kg, car_half_length_m=service.car_half_length_m,
                slack_m=WHEEL_DRIVE_TRACK_SLACK_M if service.drive is not None else 0.0, grades=grades,
                jerk_m_per_s3=service.jerk_m_per_s3)


def _items(data: Dict, key: str, cls, path: Path) -> Tuple[Any, ...]:
    items = data.get(key, [])
    if not isinstance(items, list):
        raise ScenarioError(path, ["service", key], f"expected a list of {cls.__name__} mappings, got {describe(items)}")
    return tuple(build(cls, item, path, ["service", f"{key}[{i}]"]) for i, item in enumerate(items))


def parse(data, vehicle: VehicleParams, path: Path) -> Service:
    """``service:`` checked: the stations in order along the line, each curve on the line between
    them and clear of every station (the car stands on straight level track), the dwells long
    enough for the doors, the boarders spread before the next stop."""
    if not isinstance(data, dict):
        raise ScenarioError(path, ["service"], f"expected a mapping (stations, curves, line_speed_m_per_s, ...), got "
                                               f"{describe(data)}")
    check_keys(data, [f.name for f in dataclasses.fields(Service) if is_key(f)], path, ["service"])
    stations, curves = _items(data, "stations", StationSpec, path), _items(data, "curves", CurveSpec, path)
    gradients = _items(data, "gradients", GradientSpec, path)
    half = 0.5 * (vehicle.bogie_centre_distance_m + vehicle.wheelbase_m)
    rest = {k: v for k, v in data.items() if k not in ("stations", "curves", "gradients")}
    service = build(Service, rest, path, ["service"], stations=stations, curves=curves, gradients=gradients,
                    car_half_length_m=half)
    check_doors(service, path, "service")
    if service.valve_settings is not None:
        check_valve_settings(service.valve_settings, path, ["service", "valve_settings"])
    if len(stations) < 2:
        raise ScenarioError(path, ["service", "stations"], f"expected at least two stations, got {len(stations)}")
    if stations[0].at_m != 0.0:
        raise ScenarioError(path, ["service", "stations[0]", "at_m"], f"the first station is the line's origin: "
                                                                      f"expected 0, got {stations[0].at_m:g} m")
    for i, st in enumerate(stations):
        where = ["service", f"stations[{i}]"]
        if st.platform_side not in SIDES:
            raise ScenarioError(path, [*where, "platform_side"], f"expected left or right, got {st.platform_side!r}")
        if i and not st.at_m - stations[i - 1].at_m >= 2.0 * half:
            before = stations[i - 1].at_m
            raise ScenarioError(path, [*where, "at_m"], f"expected stations in order along the line, each at least a "
                                                        f"car ({2 * half:g} m) beyond the one before ({before:g} m); "
                                                        f"got {st.at_m:g} m")
        if not st.dwell_s > service.door_open_delay_s + service.door_close_s:
            raise ScenarioError(path, [*where, "dwell_s"], f"the doors open {service.door_open_delay_s:g} s after the stop "
                                                           f"and close {service.door_close_s:g} s before the departure: "
                                                           f"expected a longer dwell, got {st.dwell_s:g} s")
    line_m = stations[-1].at_m
    spans = []
    for i, c in enumerate(curves):
        where = ["service", f"curves[{i}]"]
        if c.direction not in SIDES:
            raise ScenarioError(path, [*where, "direction"], f"expected left or right, got {c.direction!r}")
        if c.transition_shape not in TRANSITION_SHAPES:
            raise ScenarioError(path, [*where, "transition_shape"], f"expected one of {', '.join(TRANSITION_SHAPES)}, "
                                                                    f"got {c.transition_shape!r}")
        end = c.at_m + 2.0 * c.transition_m + c.arc_m
        if spans and c.at_m < spans[-1]:
            raise ScenarioError(path, [*where, "at_m"], f"expected the curves in order along the line, each after the "
                                                        f"one before (it ends at {spans[-1]:g} m); got {c.at_m:g} m")
        for st in stations:
            if st.at_m - half - 1.0 < end and c.at_m < st.at_m + half + 1.0:
                raise ScenarioError(path, [*where, "at_m"], f"the curve ({c.at_m:g}-{end:g} m) reaches station "
                                                            f"{st.name!r} at {st.at_m:g} m: the car must stand on straight "
                                                            f"track (clear by {half + 1.0:g} m either side)")
        if end > line_m:
            raise ScenarioError(path, [*where, "at_m"], f"the curve ends at {end:g} m, beyond the last station "
                                                        f"({line_m:g} m)")
        spans.append(end)
    _check_gradients(gradients, line_m, half, path)
    shortest = min(run_time_s(b.at_m - a.at_m, service.line_speed_m_per_s, service.acceleration_m_per_s2,
                              service.braking_m_per_s2, service.jerk_m_per_s3) for a, b in zip(stations, stations[1:]))
    if not service.spread_s < shortest:
        raise ScenarioError(path, ["service", "spread_s"], f"the boarders must spread before the next stop: expected "
                                                           f"less than the shortest run ({shortest:.1f} s), got "
                                                           f"{service.spread_s:g} s")
    return service


def _check_gradients(gradients: Tuple[GradientSpec, ...], line_m: float, half_m: float, path: Path) -> None:
    """The gradients in order along the line, apart, within it, each long enough for its two
    vertical curves, and the first station level under the whole car (it starts there at its
    static equilibrium on level track)."""
    end = -math.inf
    for i, g in enumerate(gradients):
        where = ["service", f"gradients[{i}]"]
        if g.at_m < end:
            raise ScenarioError(path, [*where, "at_m"], f"expected the gradients in order along the line, each after "
                                                        f"the one before (it ends at {end:g} m); got {g.at_m:g} m")
        if g.at_m < half_m + 1.0:
            raise ScenarioError(path, [*where, "at_m"], f"the car starts at the first station on level track: expected "
                                                        f"the gradient to begin at least {half_m + 1.0:g} m along the "
                                                        f"line (half a car and a metre), got {g.at_m:g} m")
        if g.at_m + g.length_m > line_m:
            raise ScenarioError(path, [*where, "length_m"], f"the gradient ends at {g.at_m + g.length_m:g} m, beyond "
                                                            f"the last station ({line_m:g} m)")
        if 2.0 * g.transition_m > g.length_m:
            raise ScenarioError(path, [*where, "transition_m"], f"two vertical curves of {g.transition_m:g} m do not "
                                                                f"fit in the section of {g.length_m:g} m")
        end = g.at_m + g.length_m


def with_payload(service: Service, payload, path: Path) -> Service:
    """The payload's reference masses and the load on board at the first station; the load on
    board after every stop between none and the exceptional payload. A service's passengers
    board and alight at its stations, so ``payload.events`` is refused."""
    if payload is not None and payload.events:
        raise ScenarioError(path, ["payload", "events"], "a service's passengers alight and board at its stations "
                                                         "(service.stations[i].alighting / boarding): leave "
                                                         "payload.events out (initial and the reference masses stay)")
    payload = payload if payload is not None else PayloadSchedule(PayloadSettings(), 0.0, ())
    service = dataclasses.replace(service, payload_settings=payload.settings, initial_kg=payload.initial_kg)
    crush = payload.exceptional_payload_kg
    for stop in service.plan.stops:
        if not -1e-9 * crush <= stop.on_board_kg <= crush * (1 + 1e-12):
            i = [st.name for st in service.stations].index(stop.name)
            key = "alighting" if stop.on_board_kg < 0 else "boarding"
            key = key if stop.direction == "out" else f"return_{key}"
            raise ScenarioError(path, ["service", f"stations[{i}]", key],
                                f"{stop.on_board_kg:.0f} kg on board when the doors close at {stop.name} "
                                f"({'outwards' if stop.direction == 'out' else 'on the way back'}): expected between none "
                                f"and the exceptional payload, {crush:.0f} kg")
    return service


def stop_demand(service: Service) -> Optional[ScheduledDemand]:
    """The air per stop as a demand on the main reservoir (None without ``air_per_stop``): at
    every stop its normal volume over [arrival, departure), at a constant rate."""
    air = service.air_per_stop
    if air is None:
        return None
    windows = tuple((st.arrive_s, st.depart_s, air.normal_volume_m3 / (st.depart_s - st.arrive_s))
                    for st in service.plan.stops)
    return ScheduledDemand(windows, "supply", air.dp_off_Pa)


def with_circuit(service: Service, circuit, path: Path):
    """With ``air_per_stop``: the circuit with its demand (:data:`STOP_DEMAND`) on the main
    reservoir, which must hold air (a supply with a volume, or a tank named ``supply`` in an
    explicit circuit); refused with an FMU circuit, whose air is inside the FMU."""
    demand = stop_demand(service)
    if demand is None:
        return circuit
    where = ["service", "air_per_stop"]
    if is_imported(circuit):
        raise ScenarioError(path, where, "an FMU circuit's air supply is inside the FMU (circuit.fmu): leave "
                                         "air_per_stop out")
    if circuit.explicit is not None:
        components = dict(circuit.explicit)
        if STOP_DEMAND in components:
            raise ScenarioError(path, where, f"the circuit already has a component named {STOP_DEMAND!r}, the name "
                                             f"of the air per stop's demand: rename it")
        supply = components.get("supply")
        holds = isinstance(supply, Tank) or (isinstance(supply, Supply) and not supply.is_fixed)
    else:
        holds = not circuit.supply.is_fixed
    if not holds:
        raise ScenarioError(path, where, "draws from the main reservoir, which must hold air: give circuit.supply a "
                                         "volume V_m3 (the default supply is a source at fixed pressure)")
    return dataclasses.replace(circuit, scheduled_demands=(*circuit.scheduled_demands, (STOP_DEMAND, demand)))


def duration_s(service: Service) -> float:
    """The trip, rounded up to a whole second (the car stands after the last dwell): a whole
    number of every usual macro-step and output interval."""
    return float(math.ceil(service.plan.duration_s - 1e-9))


def valve_settings(service: Service, valves: bool) -> Tuple[bool, ...]:
    return service.valve_settings or (valves,)


def make_car(scenario: Scenario):
    """The car on the route's track at its speed profile, carrying the route's passengers
    (picklable factory for cosim.engine.cases)."""
    from vehicle.car import MetroCar  # exudyn: imported when a car is built, not to read a scenario
    service = scenario.experiment
    route, s = service.plan, service.payload_settings
    payload = RoutePayload(route, s.floor_length_m, s.floor_width_m, s.passenger_height_m, s.cog_above_floor_m)
    drive = {} if service.drive is None else dict(guidance="contact", drive=service.drive.wheel_drive(),
                                                    contact=service.drive.contact_params())
    return MetroCar(scenario.vehicle, step_s=scenario.solver.mechanics_step_s,
                    spectral_radius=scenario.solver.spectral_radius, track_structure=scenario.track,
                    track=route.track, speed_profile=route.speed, payload=payload, grade=route.grade,
                    start_s_m=route.offset_m, **drive)


def air_per_stop_kg(sample) -> np.ndarray:
    """The air the air per stop's demand drew (cumulative, kg, per case)."""
    circuit = sample.sim.circuit
    return circuit.demand_air_kg(sample.sim.x)[circuit.demand_names.index(STOP_DEMAND)]


def outputs(service: Service) -> Tuple[Output, ...]:
    """What a service samples besides every car run's outputs: the floor at the doors on both
    sides, the payload on board; with ``air_per_stop``, the air it drew."""
    air = (Output("air_per_stop_kg", (), "kg", "air the brakes and doors drew at the stops (service.air_per_stop; "
                  "cumulative)", "air_per_stop_kg", air_per_stop_kg, air_supply=True),) if service.air_per_stop else ()
    return tuple(Output(f"floor_{side}_z_m", ("floor_point",), "m", f"floor height above rail top at the {side}-hand "
                        "door thresholds (front, centre, rear door)", f"floor_{side}_z_{{}}_m",
                        FloorHeights(service.door_points(side))) for side in SIDES) + (
        Output("payload_kg", (), "kg", "payload on board", "payload_kg", payload_kg),) + air + (
        DRIVE_OUTPUTS if service.drive is not None else ())


#: a car driven through its wheels is warned of once a wheelset's traction or braking uses this
#: share of its adhesion (|Fx| / (mu N)); the creep law saturates towards 1, where it slides
ADHESION_WARNING = 0.9
#: what a car driven through its wheels samples besides a contact car's outputs
DRIVE_OUTPUTS = (
    Output("wheelset_longitudinal_force_N", ("wheelset",), "N", "sum of the longitudinal creep forces of a wheelset "
           "(+ forward: traction; - braking)", "Fx_ws_{}_N", PerCar("wheelset_longitudinal_forces_N", 4), contact=True),
    Output("adhesion_used", ("wheelset",), "1", "share of the adhesion a wheelset's traction or braking uses, "
           "|Fx| / (mu N) over its two wheels (1: the limit, it slides)", "adhesion_{}", PerCar("adhesion_used", 4),
           contact=True))


def _at(t: np.ndarray, when: float) -> int:
    return int(np.argmin(np.abs(t - when)))


def _worst(row: np.ndarray) -> float:
    """The signed value of largest magnitude."""
    return float(row[np.argmax(np.abs(row))])


def stop_rows(case: xr.Dataset, service: Service) -> List[Dict[str, object]]:
    """One row per stop of a case (module docstring); the floor relative to the platform, i.e. its
    height at the doors at t = 0."""
    t = case["time"].values
    sides = {side: case[f"floor_{side}_z_m"].transpose("time", "floor_point").values for side in SIDES}
    valves = ([case[f"valve_{s}_open_s"].transpose("time", "valve").values for s in ("supply", "exhaust")]
              if "valve" in case.dims else [np.zeros((len(t), 0))])
    open_s = np.concatenate(valves, axis=1)
    injected = case["air_from_supply_kg"].values
    drawn = case["air_per_stop_kg"].values if "air_per_stop_kg" in case else None
    recorded = np.flatnonzero(np.isfinite(injected))
    t_last = t[recorded[-1]] if recorded.size else -math.inf   # a case that stopped early is NaN after
    rows = []
    for n, stop in enumerate(service.plan.stops):
        if stop.depart_s > t_last + 1e-9:
            break                                         # the run stopped before this stop ended
        dz = sides[stop.platform_side] - sides[stop.platform_side][0]
        i_arr, i_open, i_close, i_dep = (_at(t, x) for x in (stop.arrive_s, stop.open_s, stop.close_s, stop.depart_s))
        doors = dz[i_open:i_close + 1]
        outside = np.flatnonzero(np.any(np.abs(dz[i_open:i_dep + 1]) > service.tolerance_m, axis=1))
        relevel = 0.0 if not outside.size else (math.nan if outside[-1] == i_dep - i_open else
                                                float(t[i_open + outside[-1] + 1] - t[i_open]))
        rows.append({"stop": n + 1, "station": stop.name, "direction": stop.direction, "platform_side": stop.platform_side,
                     "arrive_s": stop.arrive_s, "depart_s": stop.depart_s,
                     "alighting_kg": stop.alighting_kg, "boarding_kg": stop.boarding_kg, "on_board_kg": stop.on_board_kg,
                     "floor_dz_arrive_m": _worst(dz[i_arr]), "floor_dz_min_m": float(doors.min()),
                     "floor_dz_max_m": float(doors.max()), "floor_dz_close_m": _worst(dz[i_close]),
                     "relevel_s": relevel, "valve_openings": openings(open_s[i_arr:i_dep + 1]),
                     "air_injected_kg": float(injected[i_dep] - injected[i_arr])})
        if drawn is not None:
            # the samples around the stop, so that the window [arrival, departure) lies within them
            # whatever the output interval; the demand draws nothing between stops
            i0 = int(np.searchsorted(t, stop.arrive_s + 1e-9, side="right")) - 1
            i1 = int(np.searchsorted(t, stop.depart_s - 1e-9, side="left"))
            rows[-1]["air_per_stop_kg"] = float(drawn[i1] - drawn[i0])
    return rows


def case_row(stops: List[Dict[str, object]], case: xr.Dataset, service: Service, gas) -> Dict[str, object]:
    """A case's summary: the worst stop, the stops out of tolerance, the air of the trip (``gas``:
    the circuit's, for the normal litres)."""
    close = np.array([abs(r["floor_dz_close_m"]) for r in stops])
    doors = np.array([max(abs(r["floor_dz_min_m"]), abs(r["floor_dz_max_m"])) for r in stops])
    relevel = np.array([r["relevel_s"] for r in stops])
    row = {"stops": len(stops), "floor_dev_close_m": float(close.max()) if stops else math.nan,
           "floor_dev_max_m": float(doors.max()) if stops else math.nan,
           "stops_outside_tolerance": int(np.sum(close > service.tolerance_m)),
           "relevel_max_s": float(relevel.max()) if stops else math.nan,        # NaN if a stop never re-levelled
           "valve_openings": int(sum(r["valve_openings"] for r in stops))}
    row.update(air_columns(case))
    rho_n = normal_density_kg_per_m3(gas.R_J_per_kgK)      # a normal litre: DIN 1343, 0 degC and 1.01325 bar
    row["air_injected_NL"] = row["air_injected_kg"] / rho_n * 1e3
    row["air_exhausted_NL"] = row["air_exhausted_kg"] / rho_n * 1e3
    if "adhesion_used" in case:                            # driven through the wheels
        row["adhesion_used_max"] = float(np.nanmax(case["adhesion_used"].values))
        row["longitudinal_force_max_N"] = float(np.nanmax(np.abs(case["wheelset_longitudinal_force_N"].values)))
    if "air_per_stop_kg" in case:                          # its share of air_demand_kg
        row["air_per_stop_kg"] = float(case["air_per_stop_kg"].values[-1])
        row["air_per_stop_NL"] = row["air_per_stop_kg"] / rho_n * 1e3
    return row


def run(scenario: Scenario, progress: Progress) -> Computed:
    """Every case of the service: its summary row (:func:`case_row`), its stops (table ``stops``)
    and series."""
    service = scenario.experiment
    route = service.plan
    settings = service.valve_settings or (None,)
    progress(f"service: {len(route.stops)} stops over {route.stops[-1].s_m - route.offset_m:.0f} m in "
             f"{route.duration_s / 60:.1f} min; {len(scenario.k_W_per_K)} k values")
    ds, diagnoses = simulate_cases(scenario, settings, make_car, duration_s(service), progress, outputs(service))
    rows, table, found = [], [], []
    for j, (k, valves) in enumerate(zip(ds["k_W_per_K"].values, ds["valves"].values)):
        case = ds.isel(case=j)
        stops = stop_rows(case, service)
        head = {"valves": bool(valves), "k_W_per_K": float(k)}
        table += [{**head, **r} for r in stops]
        rows.append({**head, **case_row(stops, case, service, AIR), **fault_columns(scenario, case)})
        if rows[-1].get("adhesion_used_max", 0.0) >= ADHESION_WARNING:
            used = case["adhesion_used"].max("wheelset").values
            first = case["time"].values[np.argmax(used >= ADHESION_WARNING)]
            warn(found, f"k = {k_label(float(k))}: the wheels used up to {rows[-1]['adhesion_used_max']:.2f} of the "
                        f"adhesion (first above {ADHESION_WARNING:g} at t = {first:.1f} s): at 1 they slide; lower the "
                        f"braking or acceleration, or check service.drive.friction_coefficient")
        missed = [r["station"] for r in stops if abs(r["floor_dz_close_m"]) > service.tolerance_m]
        if missed:
            warn(found, f"k = {k_label(float(k))}: the floor misses +-{service.tolerance_m * 1e3:g} mm at door close at "
                        f"{len(missed)} of {len(stops)} stops ({', '.join(missed[:5])}{', ...' if len(missed) > 5 else ''})")
    info = {"tolerance_m": service.tolerance_m, "duration_s": route.duration_s,
            "line_m": service.stations[-1].at_m, "round_trip": service.round_trip,
            "stops": [{"station": s.name, "direction": s.direction, "arrive_s": s.arrive_s, "depart_s": s.depart_s,
                       "platform_side": s.platform_side} for s in route.stops]}
    shown = ("valves", "k_W_per_K", "floor_dev_close_m", "stops_outside_tolerance", "relevel_max_s", "valve_openings",
             "air_injected_kg", "air_injected_NL", "air_exhausted_kg")
    return Computed(rows, shown, {"service": ds}, tables={"stops": table}, diagnoses=diagnoses, warnings=found,
                    info=info)


def figures(outcome: Outcome) -> List[Figure]:
    """Per valve setting: the floor at door close at every stop against the tolerance band, one
    curve per k; the floor at the centre doors over the trip; the speed, the payload and the air
    injected over the trip across k."""
    if not outcome.rows:
        return []
    scenario = outcome.scenario
    service, ds = scenario.experiment, outcome.series["service"]
    stops = outcome.tables.get("stops", [])
    tol = service.tolerance_m * 1e3
    band = [(tol, f"+{tol:.1f} mm"), (-tol, f"-{tol:.1f} mm")]
    out = []
    for setting in service.valve_settings or (None,):
        sub = of_setting(ds, setting)
        suffix = "" if setting is None else f"_valves={'on' if setting else 'off'}"
        valves = "" if setting is None else f", valves {'connected' if setting else 'isolated'}"
        at_close, centre = [], []
        t = sub["time"].values
        roll = plane_roll_rad(service.plan.track, service.plan.offset_m + service.plan.speed.distance(t),
                              scenario.vehicle.bogie_x_m)
        plane = [y * np.sin(roll) for y in (service.door_y_m, -service.door_y_m)]   # the rail plane at each side's doors
        for c, k in zip(sub["case"].values, sub["k_W_per_K"].values):
            mine = [r for r in stops if r["k_W_per_K"] == float(k) and (setting is None or r["valves"] == setting)]
            n = np.array([r["stop"] for r in mine], dtype=float)
            at_close += [Curve(n, np.array([r["floor_dz_close_m"] for r in mine]) * 1e3, f"door close, {k_legend(float(k))}"),
                         Curve(n, np.array([r["floor_dz_arrive_m"] for r in mine]) * 1e3, f"arrival, {k_legend(float(k))}")]
            for side, z_plane in zip(SIDES, plane):
                z = sub[f"floor_{side}_z_m"].sel(case=c, floor_point="centre").values - z_plane
                centre.append(Curve(t, (z - z[0]) * 1e3, f"{side} centre door, {k_legend(float(k))}"))
        out += [Figure(f"floor_at_stops{suffix}.png",
                       [Panel(at_close, "stop number (route order; stops.csv names them)",
                              "floor - platform at the platform-side doors [mm]", "worst door at each stop",
                              hlines=band),
                        Panel(centre, "time t [s]", "floor - platform [mm]", "centre doors over the trip (in curves: above the "
                              "canted rail plane)", hlines=band)],
                       f"Floor at the platforms, tolerance +-{tol:.1f} mm{valves}", 1),
                Figure(f"trip{suffix}.png",
                       [Panel([Curve(sub["time"].values, service.plan.speed.speed(sub["time"].values) * 3.6,
                                     "speed")], "time t [s]", "speed [km/h]", "speed profile"),
                        Panel(per_case(sub["payload_kg"], 1e-3), "time t [s]", "payload on board [t]", "payload"),
                        Panel(per_case(sub["air_from_supply_kg"], 1e3), "time t [s]", "air injected [g]",
                              "air across k")],
                       f"The trip: speed, payload and air{valves}", 1)]
    return out


def compare(infos, out_dir: Path, select: Selection, label, window: str) -> List[Path]:
    """Overlay several service runs: the air injected and the floor at the centre doors, each
    side relative to its height at the start, over the trip."""
    run_dirs = [d for d, _ in infos]
    series = [(d, k, data) for d in run_dirs for k, data in case_series(d, "service_", select)]
    panels = [Panel([Curve(data["t_s"], data["air_from_supply_kg"] * 1e3, label(d, k)) for d, k, data in series],
                    "time t [s]", "air injected [g]", "air")]
    for side in SIDES:
        column = f"floor_{side}_z_centre_m"
        panels.append(Panel([Curve(data["t_s"], (data[column] - data[column][0]) * 1e3, label(d, k))
                             for d, k, data in series], "time t [s]", "floor - at the start [mm]",
                            f"{side}-hand centre door (in curves: the cant's tilt included)"))
    return [save_panels(out_dir / "compare_service.png", panels, f"Service comparison{window}", ncols=1)]


class ServiceKind(CarKind):
    """A line in service: stops, passengers, curves; the floor at the platforms and the air."""

    name, section, experiment = "service", "service", Service
    check_metrics = ("floor_dev_close_m", "floor_dev_max_m", "stops_outside_tolerance", "relevel_max_s",
                     "valve_openings", "air_injected_kg", "adhesion_used_max")
    headline_metrics = ("floor_dev_close_m", "stops_outside_tolerance", "air_injected_kg")
    total_metrics = ("floor_dev_close_m", "floor_dev_max_m", "stops_outside_tolerance", "relevel_max_s",
                     "valve_openings", "air_injected_kg")
    plot_metrics = ("floor_dev_close_m", "air_injected_kg")

    parse = staticmethod(parse)
    duration_s = staticmethod(duration_s)
    valve_settings = staticmethod(valve_settings)
    make_car = staticmethod(make_car)
    run = staticmethod(run)
    figures = staticmethod(figures)
    compare = staticmethod(compare)

    def with_payload(self, experiment, payload, path):
        return with_payload(experiment, payload, path)

    def with_circuit(self, experiment, circuit, path):
        return with_circuit(experiment, circuit, path)


KIND = ServiceKind()
