"""``payload:`` of a car scenario: passengers boarding and alighting (:class:`PayloadSchedule`),
checked at load (:func:`parse_payload`) and handed to the car as what its floor carries at each
time (:meth:`PayloadSchedule.blocks_at`, :mod:`vehicle.payload`).

```yaml
payload:
  initial: {normal_fraction: 0.5}                 # on board at arrival: uniform, centred
  events:
    - {t_s: 5, duration_s: 20, passengers: 60, position: right}     # boarding from a right-hand platform
    - {t_s: 40, duration_s: 10, mass_kg: -2100, position: front}    # alighting at the front end
    - {t_s: 60, duration_s: 5, passengers: 10, position: {x_m: 4.5, y_m: -1.0}}
```

Reference masses, after EN 15663 (*Railway applications - Vehicle reference masses*; its
design mass in working order is the car's tare here, ``vehicle.carbody_mass_kg`` with the bogies
and wheelsets): the **normal payload** is the seated passengers plus the standing density of the
normal payload on the standing area, the **exceptional payload** (crush load) the seated
passengers plus the exceptional standing density, each passenger of ``passenger_mass_kg``. The
defaults (70 kg, 4 and 6 standing passengers per m^2) are the values commonly used for metro and
suburban cars with EN 15663's definitions: **assumed** -- they were not checked against the
standard's tables (not available here); set them from the car's specification. The floor
(14.0 m x 2.6 m, its standing area the whole floor, no seats) is **assumed** for a metro car with
10 m bogie centres (carbody ~14.5 m long, ~2.65 m wide).

Passengers are uniform blocks standing on a patch of the floor, ``passenger_height_m`` tall, their
centre of gravity ``cog_above_floor_m`` above it (**assumed** 1.0 m: ~0.55 of a 1.75 m stature).
Named positions: ``uniform`` (the whole floor), ``front``/``rear`` (the half of the floor at that
end), ``left``/``right`` (the half on that side: a one-sided platform), ``front_left`` ... (a
quarter); or ``{x_m, y_m}``: the payload's centre of gravity at that point of the floor (from the
car centre, x + forward, y + left), as a point mass. A negative amount (``passengers: -30``,
``mass_kg: -2100``) alights. Each event ramps linearly over ``duration_s``.

Checked before anything runs (:class:`~cosim.errors.ScenarioError`, key path): the keys, exactly
one amount per event, each event within the run (t_s >= 0, t_s + duration_s at most the shortest
case's duration), the position on the floor, the initial payload and the payload after each
event's start and end (it is linear in between) between none (tare) and the exceptional payload.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple

from cosim.errors import ScenarioError
from cosim.scenario.schema import build, check_keys, coerce, describe
from pneumorail.quantities import plausible
from vehicle.payload import PayloadBlock

#: Named positions on the floor: (x, y) of the patch's centre as fractions of the floor's length
#: and width, and the patch's length and width as fractions of the floor's.
POSITIONS: Dict[str, Tuple[float, float, float, float]] = {
    "uniform": (0.0, 0.0, 1.0, 1.0),
    "front": (0.25, 0.0, 0.5, 1.0), "rear": (-0.25, 0.0, 0.5, 1.0),
    "left": (0.0, 0.25, 1.0, 0.5), "right": (0.0, -0.25, 1.0, 0.5),
    "front_left": (0.25, 0.25, 0.5, 0.5), "front_right": (0.25, -0.25, 0.5, 0.5),
    "rear_left": (-0.25, 0.25, 0.5, 0.5), "rear_right": (-0.25, -0.25, 0.5, 0.5),
}
#: the ways an amount of payload is given (exactly one per event)
AMOUNTS = ("passengers", "mass_kg", "normal_fraction")


@dataclass(frozen=True)
class PayloadEvent:
    """Passengers boarding (+) or alighting (-): ``mass_kg`` of payload, ramped linearly from
    ``t_s`` over ``duration_s``, its patch centred at (``x_m``, ``y_m``) on the floor, ``length_m``
    by ``width_m`` (0 by 0: a point mass); ``label`` says what the scenario gave."""

    t_s: float
    duration_s: float
    mass_kg: float
    x_m: float
    y_m: float
    length_m: float
    width_m: float
    label: str

    @property
    def end_s(self) -> float:
        return self.t_s + self.duration_s

    def fraction(self, t: float) -> float:
        """How much of the event has happened at ``t`` (0 ... 1, linear)."""
        return min(max((t - self.t_s) / self.duration_s, 0.0), 1.0)


@dataclass(frozen=True)
class PayloadSettings:
    """The ``payload:`` keys besides ``initial`` and ``events`` (reference masses and the
    passengers' build; see the module docstring for the sources and what is assumed)."""

    passenger_mass_kg: float = field(default=70.0, metadata=plausible(30.0, 150.0, "kg", "one passenger, with luggage"))
    floor_length_m: float = field(default=14.0, metadata=plausible(2.0, 40.0, "m", "a carbody's floor"))
    floor_width_m: float = field(default=2.6, metadata=plausible(1.0, 4.0, "m", "a carbody's floor"))
    seats: int = field(default=0, metadata=plausible(0, 500, why="seated passengers"))
    standing_area_m2: Optional[float] = field(default=None, metadata=plausible(0.0, 200.0, "m^2",
                                                                                "the floor's standing area"))
    normal_standing_per_m2: float = field(default=4.0, metadata=plausible(0.0, 10.0, "passengers/m^2"))
    exceptional_standing_per_m2: float = field(default=6.0, metadata=plausible(0.0, 10.0, "passengers/m^2"))
    passenger_height_m: float = field(default=1.7, metadata=plausible(0.5, 2.5, "m"))
    cog_above_floor_m: float = field(default=1.0, metadata=plausible(0.0, 2.0, "m"))


@dataclass(frozen=True)
class PayloadSchedule:
    """What the floor carries over a run: ``initial_kg`` uniform from the start, then the
    ``events``; the reference masses of :class:`PayloadSettings`."""

    settings: PayloadSettings
    initial_kg: float
    events: Tuple[PayloadEvent, ...]

    @property
    def standing_area_m2(self) -> float:
        s = self.settings
        return s.floor_length_m * s.floor_width_m if s.standing_area_m2 is None else s.standing_area_m2

    @property
    def normal_payload_kg(self) -> float:
        """EN 15663's normal payload: the seated plus the normal standing density on the standing area."""
        s = self.settings
        return s.passenger_mass_kg * (s.seats + s.normal_standing_per_m2 * self.standing_area_m2)

    @property
    def exceptional_payload_kg(self) -> float:
        """EN 15663's exceptional payload (the crush load): seated plus the exceptional standing density."""
        s = self.settings
        return s.passenger_mass_kg * (s.seats + s.exceptional_standing_per_m2 * self.standing_area_m2)

    def _block(self, mass_kg: float, x_m: float, y_m: float, length_m: float, width_m: float) -> PayloadBlock:
        s = self.settings
        return PayloadBlock(mass_kg, x_m, y_m, length_m, width_m, s.passenger_height_m if length_m else 0.0,
                            s.cog_above_floor_m)

    def blocks_at(self, t_s: float) -> Tuple[PayloadBlock, ...]:
        """What the floor carries at ``t_s``: the initial payload over the whole floor and each
        event's block with the part of its mass that has boarded (``MetroCar(payload=...)``)."""
        s = self.settings
        blocks = [self._block(self.initial_kg, 0.0, 0.0, s.floor_length_m, s.floor_width_m)]
        blocks += [self._block(e.mass_kg * e.fraction(t_s), e.x_m, e.y_m, e.length_m, e.width_m) for e in self.events]
        return tuple(blocks)

    def total_kg(self, t_s: float) -> float:
        """The payload on board at ``t_s`` [kg]."""
        return self.initial_kg + sum(e.mass_kg * e.fraction(t_s) for e in self.events)

    def label(self) -> str:
        """The payload in words (summary rows, figure titles)."""
        parts = [f"{self.initial_kg:.0f} kg at arrival"] if self.initial_kg else []
        parts += [e.label for e in self.events]
        return "; ".join(parts)


def _amount(item: Mapping, schedule: PayloadSchedule, file, where: Sequence[str]) -> Tuple[float, str]:
    """(mass [kg], words) of the one amount an event or ``initial`` gives."""
    given = [a for a in AMOUNTS if a in item]
    if len(given) != 1:
        got = "none" if not given else " and ".join(given)
        raise ScenarioError(file, list(where), f"give exactly one amount of {', '.join(AMOUNTS)}; got {got}")
    key = given[0]
    value = coerce(item[key], float, file, [*where, key])
    s = schedule.settings
    if key == "passengers":
        if value != int(value):
            raise ScenarioError(file, [*where, key], f"expected a whole number of passengers, got {value:g}")
        return value * s.passenger_mass_kg, f"{value:+.0f} passengers ({value * s.passenger_mass_kg:+.0f} kg)"
    if key == "mass_kg":
        return value, f"{value:+.0f} kg"
    mass = value * schedule.normal_payload_kg
    return mass, f"{value:+g} x normal payload ({mass:+.0f} kg)"


def _position(value: Any, settings: PayloadSettings, file, where: Sequence[str]) -> Tuple[float, float, float, float, str]:
    """(x, y, length, width, words) of ``position`` on the floor."""
    L, W = settings.floor_length_m, settings.floor_width_m
    if value is None:
        value = "uniform"
    if isinstance(value, str):
        if value not in POSITIONS:
            raise ScenarioError(file, list(where), f"unknown position {value!r} (expected one of {', '.join(POSITIONS)}, "
                                                   f"or {{x_m, y_m}} on the floor)")
        fx, fy, fl, fw = POSITIONS[value]
        return fx * L, fy * W, fl * L, fw * W, value
    if not isinstance(value, dict):
        raise ScenarioError(file, list(where), f"expected a named position ({', '.join(POSITIONS)}) or {{x_m, y_m}}, "
                                               f"got {describe(value)}")
    check_keys(value, ("x_m", "y_m"), file, list(where))
    xy = []
    for key, half, along in (("x_m", L / 2, "along the car (floor_length_m / 2)"),
                             ("y_m", W / 2, "across the car (floor_width_m / 2)")):
        v = coerce(value.get(key, 0.0), float, file, [*where, key])
        if abs(v) > half:
            raise ScenarioError(file, [*where, key], f"expected a point on the floor, within +-{half:g} m {along}; "
                                                     f"got {v:g} m")
        xy.append(v)
    return xy[0], xy[1], 0.0, 0.0, f"at x = {xy[0]:g} m, y = {xy[1]:g} m"


def parse_payload(value: Any, file, duration_s: float) -> Optional[PayloadSchedule]:
    """``payload:`` checked (see the module docstring); None when absent. ``duration_s``: the
    shortest case's duration (every event must end within it)."""
    if value is None:
        return None
    if not isinstance(value, dict):
        raise ScenarioError(file, ["payload"], f"expected a mapping (initial, events, reference masses), got "
                                               f"{describe(value)}")
    settings = build(PayloadSettings, {k: v for k, v in value.items() if k not in ("initial", "events")}, file,
                     ["payload"])
    if not settings.exceptional_standing_per_m2 >= settings.normal_standing_per_m2:
        raise ScenarioError(file, ["payload", "exceptional_standing_per_m2"],
                            f"must be at least the normal density ({settings.normal_standing_per_m2:g} passengers/m2), "
                            f"got {settings.exceptional_standing_per_m2:g}")
    schedule = PayloadSchedule(settings, 0.0, ())
    crush = schedule.exceptional_payload_kg
    bounds = f"between none (tare) and the exceptional payload, {crush:.0f} kg"
    initial = value.get("initial")
    if initial is not None:
        if not isinstance(initial, dict):
            raise ScenarioError(file, ["payload", "initial"], f"expected a mapping ({{passengers: 60}}, {{mass_kg: ...}} "
                                                              f"or {{normal_fraction: 0.5}}), got {describe(initial)}")
        check_keys(initial, AMOUNTS, file, ["payload", "initial"])
        mass, _ = _amount(initial, schedule, file, ["payload", "initial"])
        if not 0.0 <= mass <= crush:
            raise ScenarioError(file, ["payload", "initial"], f"{mass:.0f} kg on board at arrival: expected {bounds}")
        schedule = dataclasses.replace(schedule, initial_kg=mass)
    items = value.get("events", [])
    if not isinstance(items, list):
        raise ScenarioError(file, ["payload", "events"], f"expected a list of events ({{t_s, duration_s, passengers, "
                                                         f"position}}), got {describe(items)}")
    events = []
    for i, item in enumerate(items):
        where = ["payload", f"events[{i}]"]
        if not isinstance(item, dict):
            raise ScenarioError(file, where, f"expected a mapping {{t_s, duration_s, passengers, position}}, got "
                                             f"{describe(item)}")
        check_keys(item, ("t_s", "duration_s", "position", *AMOUNTS), file, where)
        for key in ("t_s", "duration_s"):
            if key not in item:
                raise ScenarioError(file, [*where, key], "missing required key (a number, s)")
        t_s = coerce(item["t_s"], float, file, [*where, "t_s"])
        d_s = coerce(item["duration_s"], float, file, [*where, "duration_s"])
        if not t_s >= 0.0:
            raise ScenarioError(file, [*where, "t_s"], f"expected a time within the run (>= 0 s), got {t_s:g} s")
        if not d_s > 0.0:
            raise ScenarioError(file, [*where, "duration_s"], f"expected a duration > 0 s (a linear ramp), got {d_s:g} s")
        if t_s + d_s > duration_s * (1 + 1e-12):
            raise ScenarioError(file, [*where, "duration_s"], f"the event must end within the run ({duration_s:g} s); it "
                                                              f"ends at {t_s + d_s:g} s")
        mass, words = _amount(item, schedule, file, where)
        x, y, length, width, place = _position(item.get("position"), settings, file, [*where, "position"])
        events.append(PayloadEvent(t_s, d_s, mass, x, y, length, width, f"{words} {place} at {t_s:g}-{t_s + d_s:g} s"))
    schedule = dataclasses.replace(schedule, events=tuple(events))
    for i, e in enumerate(events):
        for t in (e.t_s, e.end_s):
            total = schedule.total_kg(t)
            if not -1e-9 * crush <= total <= crush * (1 + 1e-12):
                raise ScenarioError(file, ["payload", f"events[{i}]"], f"the payload on board reaches {total:.0f} kg at "
                                                                       f"{t:g} s: expected {bounds}")
    return schedule


__all__ = ["PayloadSchedule", "PayloadEvent", "PayloadSettings", "parse_payload", "POSITIONS"]
