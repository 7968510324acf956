"""A run of the car along a track, as a scenario describes it: the track (straight, transition,
circular arc, cant; or straight alone), the speed, the guidance, the contact's parameters, the
limits of the summary, and the track's irregularities (:class:`CurveTest`,
:class:`IrregularitySpec`), checked against the car (:func:`parse`). The ``curve_entry`` kind's
experiment is one; ``ride`` builds one per speed."""
from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Optional, Tuple

import numpy as np

from cosim.errors import ScenarioError
from cosim.limits.criteria import NADAL_FLANGE_ANGLE_DEG, NADAL_FRICTION, nadal_limit
from cosim.scenario.model import DEFAULT_WINDOW_S
from cosim.scenario.schema import build, check_valve_settings, describe
from pneumorail.quantities import Range, plausible, positive, ranged
from vehicle.irregularities import (
    CHANNELS,
    DEFAULT_WAVELENGTH_RANGE_M,
    MAX_SAMPLES,
    PERIOD_FACTOR,
    TrackIrregularity,
    canonical_kind,
)
from vehicle.params import CONTACT_DAMPING, FRICTION, TABLE_SMOOTHING, ContactParams, VehicleParams
from vehicle.track import TRANSITION_SHAPES, Straight, TrackGeometry

#: Largest cant [rad]: 0.2 rad is 300 mm over the 1.5 m rail-centre distance; railway cant is
#: limited to 150-200 mm (EN 13803: 180 mm, ~0.12 rad).
MAX_CANT_RAD = 0.2
#: the range of a cant (field metadata of a curve's and a ride's)
CANT = plausible(-MAX_CANT_RAD, MAX_CANT_RAD, "rad", "0.2 rad = 300 mm over 1.5 m; railway cant is at most ~0.12 rad")
#: Highest running speed [m/s]: 100 m/s = 360 km/h, beyond any metro and the wheel-rail model.
MAX_SPEED_M_PER_S = 100.0
#: the range of a running speed (field metadata of a curve's and each of a ride's)
SPEED = Range(0.0, MAX_SPEED_M_PER_S, False, True, "m/s", "360 km/h at most")
#: the range of a curve's radius (field metadata of a curve's and a ride's): the tightest tram
#: curves are ~13-15 m (street corners, depot loops), metro lines keep 100-300 m in service; at
#: 100 km a curve is straight for every purpose (EN 14363's widest zone starts at 600 m). A
#: radius in km falls out (0.25 for 250 m), and its slip is named
RADIUS = plausible(10.0, 1e5, "m", "a railway curve, tram to straight")
#: the range of a transition's length (field metadata of a curve's and a ride's): 10-30 m on
#: metro lines, up to ~300 m where high speed and cant need it (its length grows with both); a
#: length in mm falls out
TRANSITION = plausible(0.0, 1000.0, "m", "a transition curve, metro to high-speed lines", low_inclusive=False)
#: Longest track [m]: the car tabulates it every 0.1 m (vehicle.guidance.TrackSampler), ~100 bytes
#: per point; 200 km is 2e6 points, 5 minutes at 100 m/s is 30 km
MAX_TRACK_LENGTH_M = 2.0e5
#: wheelset guidance of a curve run (vehicle.car.MetroCar ``guidance``)
GUIDANCE = ("kinematic", "contact")


@dataclass(frozen=True)
class IrregularitySpec:
    """Track irregularities of a curve run (``curve.irregularity``): generated from a PSD
    (``psd``: erri_b176_low | erri_b176_high | fra_1 ... fra_6, with ``seed``,
    ``wavelength_range_m``, ``channels``, sample spacing ``ds_m``) from ``start_m`` (default: just
    ahead of the front wheelset at t = 0, so the car starts on design track) to the end of the
    track, faded in and out over ``taper_m``; or read from ``file`` (a CSV of
    :meth:`vehicle.irregularities.TrackIrregularity.from_file`, path relative to the scenario;
    ``s_m`` is the track's arc length, the values must be 0 under the car at t = 0). Each worker
    generates the same track from the same seed (:mod:`vehicle.irregularities`)."""

    psd: Optional[str] = None
    seed: int = field(default=0, metadata=plausible(0, None, why="a random seed: the same seed, the same track"))
    # EN 13848's bands span 3-150 m (D1-D3), the FRA PSDs 1.5-300 m; 0.1 m reaches rail
    # corrugation, 1 km beyond any vehicle's response: a wavelength in mm falls out
    wavelength_range_m: Tuple[float, ...] = field(default=DEFAULT_WAVELENGTH_RANGE_M, metadata=plausible(
        0.1, 1000.0, "m", "a track irregularity's wavelength, corrugation to 1 km"))
    channels: Tuple[str, ...] = CHANNELS
    # (and at most half the shortest wavelength: parse_irregularity)
    ds_m: float = field(default=0.25, metadata=plausible(0.0, 10.0, "m", "a sample spacing", low_inclusive=False))
    start_m: Optional[float] = field(default=None, metadata=plausible(0.0, MAX_TRACK_LENGTH_M, "m", "a position on the track"))
    taper_m: float = field(default=10.0, metadata=plausible(0.0, 1000.0, "m", "the length the irregularity fades in and out "
                                                                              "over; 0: none"))
    file: Optional[str] = None

    def build(self, track_length_m: float, start_m: float) -> TrackIrregularity:
        """The irregularity along a track of ``track_length_m`` [m]; ``start_m``: where a PSD
        irregularity starts when ``self.start_m`` is None. ``file`` must be an absolute path
        (:func:`parse` resolves it)."""
        return _irregularity_track(self, float(track_length_m), float(start_m))


@functools.lru_cache(maxsize=8)
def _irregularity_track(spec: IrregularitySpec, track_length_m: float, start_m: float) -> TrackIrregularity:
    if spec.file is not None:
        return TrackIrregularity.from_file(spec.file)
    start = spec.start_m if spec.start_m is not None else start_m
    t = TrackIrregularity.from_psd(spec.psd, track_length_m - start, spec.ds_m, spec.seed,
                                   wavelength_range_m=spec.wavelength_range_m, channels=spec.channels,
                                   taper_m=spec.taper_m)
    return TrackIrregularity(t.s_m + start, t.lateral_m, t.vertical_m, t.cross_level_m, t.gauge_m,
                             source=f"{t.source}, from s = {start:g} m")


@dataclass(frozen=True)
class CurveTest:
    """Curve entry (paper §4.2, Fig. 9): straight, transition, circular arc, at constant speed;
    with ``radius_m`` null the straight alone (``transition_m``, ``arc_m``, ``cant_rad`` do not apply).
    Along the transition curvature and cant change by ``transition_shape``: ``bloss`` (the
    default) or ``cosine`` (slopes 0 at both ends: the rails' roll rate has no step), or
    ``linear`` (a clothoid with a linear cant ramp, the paper's: the roll rate steps where a
    wheelset enters and leaves a canted ramp, which rings the wheelsets on a rigid track at
    ~240 Hz, beyond a 5 ms step: sampled peaks there depend on the step); on canted track the
    transition is a twisted track (vehicle/track.py). The car
    starts at rest relative to the straight (rear wheelset at s = 0), so ``straight_m`` must
    hold the whole car. ``valve_settings``: runs with the levelling and differential valves
    disconnected (false) and connected (true). ``window_s``: final window over which the end
    values (roll, bellow crushing) are averaged (default 5 s, or the whole run if shorter).
    ``guidance``: ``contact`` (default: free wheelsets on the S1002/UIC60 contact with Kalker
    creep forces, docs/wheel_rail.md: adds Y, Y/Q, ΣY, wheelset displacement, angle of attack,
    flange contact to the outputs and the checks ``yq_max`` and ``sum_y_max``) or ``kinematic``
    (wheelsets led along the track by a joint, no lateral wheel-rail forces: the paper's model,
    which scenarios/curve_entry.yaml reproduces; a run takes about half the time);
    ``friction_coefficient``: the contact model's μ (null: 0.36, vehicle.params.ContactParams);
    ``contact_damping_N_s_per_m``: its normal damping (null: 2e5, standing in for the rigid
    track's damping); ``contact_smoothing_mm``: the Gaussian smoothing of its contact table
    (null: 0.1 mm; 0: the rigid table; docs/wheel_rail.md, "Flange contact and step
    convergence", for what both change). Limits in the summary: Nadal (Y/Q)_lim = (tan γ - μ)/(1
    + μ tan γ) with ``nadal_flange_angle_deg`` γ and ``nadal_friction`` μ (70°, 0.36: 1.20),
    Prud'homme ΣY_lim = α (10 kN + 2 Q0/3), α = ``prudhomme_alpha`` (EN 14363: 1, freight wagons
    0.85). ``irregularity``: null (design track) or {psd: erri_b176_low | erri_b176_high | fra_1
    ... fra_6, seed, wavelength_range_m: [3, 150], channels, ds_m, start_m, taper_m} or {file:
    path relative to the scenario} (:class:`IrregularitySpec`)."""

    speed_m_per_s: float = field(default=10.0, metadata=ranged(SPEED))
    # (the straight and the arc: bounded by what the run covers and MAX_TRACK_LENGTH_M, in parse)
    straight_m: float = field(default=20.0, metadata=ranged(positive("m")))
    transition_m: float = field(default=15.0, metadata=TRANSITION)
    transition_shape: str = "bloss"
    radius_m: Optional[float] = field(default=100.0, metadata=RADIUS)
    arc_m: float = field(default=300.0, metadata=ranged(positive("m")))
    cant_rad: float = field(default=0.0, metadata=CANT)
    direction: int = field(default=1, metadata=plausible(-1, 1, why="1 (left) or -1 (right)", nonzero=True))
    duration_s: float = 30.0
    valve_settings: Tuple[bool, ...] = (False, True)
    window_s: Optional[float] = None
    guidance: str = "contact"
    friction_coefficient: Optional[float] = field(default=None, metadata=FRICTION)
    contact_damping_N_s_per_m: Optional[float] = field(default=None, metadata=CONTACT_DAMPING)
    contact_smoothing_mm: Optional[float] = field(default=None, metadata=TABLE_SMOOTHING)
    nadal_flange_angle_deg: float = field(default=NADAL_FLANGE_ANGLE_DEG, metadata=plausible(
        0.0, 90.0, "deg", "a flange angle", low_inclusive=False, high_inclusive=False))
    nadal_friction: float = field(default=NADAL_FRICTION, metadata=plausible(0.0, 1.0, why="a friction coefficient"))
    prudhomme_alpha: float = field(default=1.0, metadata=plausible(0.0, 1.0, why="EN 14363: 1, freight wagons 0.85",
                                                                   low_inclusive=False))
    irregularity: Optional[IrregularitySpec] = None

    @property
    def window(self) -> float:
        """The final averaging window [s]."""
        return self.window_s if self.window_s is not None else min(DEFAULT_WINDOW_S, self.duration_s)

    @property
    def contact(self) -> bool:
        """The wheelsets run on the wheel-rail contact (``guidance: contact``)."""
        return self.guidance == "contact"

    @property
    def length_m(self) -> float:
        """The track's length [m]: the straight alone without a radius, else straight,
        transition and arc."""
        return self.straight_m if self.radius_m is None else self.straight_m + self.transition_m + self.arc_m

    def track(self) -> TrackGeometry:
        """The track: a straight of ``straight_m`` alone (``radius_m`` None), or the straight, the
        transition and the arc."""
        if self.radius_m is None:
            return TrackGeometry((Straight(self.straight_m),))
        return TrackGeometry.curve_entry(self.straight_m, self.transition_m, self.radius_m, self.arc_m,
                                         cant_rad=self.cant_rad, direction=self.direction,
                                         transition_shape=self.transition_shape)

    def contact_params(self) -> ContactParams:
        """The contact model's parameters: the defaults, with the keys the scenario gives."""
        given = {name: value for name, value in (
            ("friction_coefficient", self.friction_coefficient),
            ("normal_damping_N_s_per_m", self.contact_damping_N_s_per_m),
            ("table_smoothing_mm", self.contact_smoothing_mm)) if value is not None}
        return ContactParams(**given)

    def track_irregularity(self, vehicle: VehicleParams) -> Optional[TrackIrregularity]:
        """The irregularity along :meth:`track` (None: design track); a PSD irregularity starts
        by default 1 m ahead of the front wheelset's position at t = 0."""
        if self.irregularity is None:
            return None
        front = vehicle.bogie_centre_distance_m + vehicle.wheelbase_m
        return self.irregularity.build(self.track().total_length_m, front + 1.0)


def parse(data, vehicle: VehicleParams, path: Path) -> CurveTest:
    """The ``curve`` section, checked against the car (the straight holds it, the run ends before
    it leaves the track) and its irregularity generated or read once."""
    irregularity = None
    if isinstance(data, Mapping) and "irregularity" in data:
        irregularity = data["irregularity"]
        data = {k: v for k, v in data.items() if k != "irregularity"}
    curve = build(CurveTest, data, path, ["curve"])
    if curve.transition_shape not in TRANSITION_SHAPES:
        raise ScenarioError(path, ["curve", "transition_shape"], f"expected one of {', '.join(TRANSITION_SHAPES)}, "
                                                                 f"got {curve.transition_shape!r}")
    car_length = vehicle.bogie_centre_distance_m + vehicle.wheelbase_m
    if curve.straight_m < car_length:
        raise ScenarioError(path, ["curve", "straight_m"], f"the straight must hold the whole car ({car_length:g} m "
                                                           f"between the outer wheelsets), got {curve.straight_m:g} m")
    if curve.window_s is not None and curve.window_s > curve.duration_s:
        raise ScenarioError(path, ["curve", "window_s"], f"the final window must lie within the run "
                                                         f"(duration_s = {curve.duration_s:g} s), got {curve.window_s:g} s")
    check_valve_settings(curve.valve_settings, path, ["curve", "valve_settings"])
    on_track = (curve.length_m - car_length) / curve.speed_m_per_s
    if curve.duration_s > on_track:
        raise ScenarioError(path, ["curve", "duration_s"], f"the front wheelset leaves the track at t = {on_track:.3g} s; "
                                                           f"lengthen arc_m or shorten duration_s (got {curve.duration_s:g} s)")
    _check_contact(curve, path)
    length = curve.length_m
    if length > MAX_TRACK_LENGTH_M:
        longest = max(("straight_m", "transition_m", "arc_m") if curve.radius_m is not None else ("straight_m",),
                      key=lambda k: getattr(curve, k))
        raise ScenarioError(path, ["curve", longest], f"a track of {length:.3g} m: the car tabulates its track every "
                                                      f"0.1 m, and more than {MAX_TRACK_LENGTH_M / 1e3:g} km would not "
                                                      f"fit in memory (a {duration_s(curve):g} s run covers "
                                                      f"{curve.speed_m_per_s * curve.duration_s:.3g} m)")
    try:
        curve.track()
    except ValueError as exc:
        raise ScenarioError(path, ["curve"], f"the track cannot be built: {exc}") from None
    if irregularity is not None:
        curve = dataclasses.replace(curve, irregularity=parse_irregularity(irregularity, curve, vehicle, path))
    return curve


def _check_contact(curve: CurveTest, path) -> None:
    """The guidance, the contact model's friction and the limits' parameters of a curve."""
    if curve.guidance not in GUIDANCE:
        raise ScenarioError(path, ["curve", "guidance"], f"expected one of {', '.join(GUIDANCE)}, got {curve.guidance!r}")
    for key in ("friction_coefficient", "contact_damping_N_s_per_m", "contact_smoothing_mm"):
        if getattr(curve, key) is not None and not curve.contact:
            raise ScenarioError(path, ["curve", key], "a parameter of the contact model needs curve.guidance: contact")
    if not nadal_limit(curve.nadal_flange_angle_deg, curve.nadal_friction) > 0.0:
        raise ScenarioError(path, ["curve", "nadal_friction"], f"the Nadal limit (tan g - mu)/(1 + mu tan g) must be "
                                                               f"> 0: mu = {curve.nadal_friction:g} is not below tan "
                                                               f"{curve.nadal_flange_angle_deg:g} deg")


def parse_irregularity(value, curve: CurveTest, vehicle: VehicleParams, path, where=("curve", "irregularity")):
    """``curve.irregularity`` (or the section ``where`` names): null, {psd: KIND, seed, ...} or
    {file: PATH}; generated (or read) once here, so that a bad one fails before any run."""
    where = list(where)
    if not isinstance(value, Mapping):
        raise ScenarioError(path, where, f"expected null, {{psd: erri_b176_low, seed: 1}} or {{file: irregularity.csv}}, "
                                         f"got {describe(value)}")
    spec = build(IrregularitySpec, value, path, where)
    if (spec.psd is None) == (spec.file is None):
        raise ScenarioError(path, where, "give either psd (with a seed) or file, not " + ("both" if spec.psd else "neither"))
    if spec.file is not None:
        others = [k for k in value if k != "file"]
        if others:
            raise ScenarioError(path, [*where, others[0]], "a file irregularity takes no other keys (the file gives "
                                                           "s_m and the values)")
        fpath = Path(path).parent / spec.file
        if not fpath.is_file():
            raise ScenarioError(path, [*where, "file"], f"the irregularity file {str(fpath)!r} does not exist or is not a file")
        spec = dataclasses.replace(spec, file=str(fpath.resolve()))
    else:
        try:
            spec = dataclasses.replace(spec, psd=canonical_kind(spec.psd))
        except ValueError as exc:
            raise ScenarioError(path, [*where, "psd"], str(exc)) from None
        band = spec.wavelength_range_m
        if len(band) != 2 or not 0.0 < band[0] < band[1]:
            raise ScenarioError(path, [*where, "wavelength_range_m"], f"expected [shortest, longest] wavelength in m, "
                                                                      f"0 < shortest < longest, got {list(band)}")
        for i, c in enumerate(spec.channels):
            if c not in CHANNELS or c in spec.channels[:i]:
                raise ScenarioError(path, [*where, f"channels[{i}]"], f"expected each of {', '.join(CHANNELS)} at most "
                                                                      f"once, got {c!r}")
        if not spec.ds_m <= 0.5 * band[0]:
            raise ScenarioError(path, [*where, "ds_m"], f"the spacing must be at most half the shortest wavelength "
                                                        f"({0.5 * band[0]:g} m), got {spec.ds_m:g} m")
        length = curve.track().total_length_m
        start = spec.start_m
        if start is not None and not 0.0 <= start < length:
            raise ScenarioError(path, [*where, "start_m"], f"expected a position on the track, [0, {length:g}) m, "
                                                           f"got {start:g} m")
    try:
        irr = dataclasses.replace(curve, irregularity=spec).track_irregularity(vehicle)
    except ValueError as exc:
        raise ScenarioError(path, _irregularity_culprit(spec, curve, where, str(exc)),
                            f"cannot build the irregularity: {exc}") from None
    # the car starts in static equilibrium on design track: nothing under it at t = 0
    car_length = vehicle.bogie_centre_distance_m + vehicle.wheelbase_m
    s = np.linspace(0.0, car_length, 241)
    worst = max(float(np.abs(v).max()) for v in irr(s))
    if worst > 1e-6:
        raise ScenarioError(path, [*where, "file" if spec.file is not None else "start_m"],
                            f"the irregularity must be 0 under the car at t = 0 (s = 0 ... {car_length:g} m, the "
                            f"rear wheelset at s = 0); it reaches {worst * 1e3:.3g} mm there")
    return spec


def _irregularity_culprit(spec: IrregularitySpec, curve: CurveTest, where, message: str) -> list:
    """The key an irregularity that cannot be built is blamed on: for too many samples the longest
    wavelength if even the coarsest spacing could not hold its period, the irregularity itself if
    the track is too long for it, else the spacing."""
    if spec.file is not None:
        return [*where, "file"]
    if "samples" in message:
        coarsest = 0.5 * spec.wavelength_range_m[0]
        if PERIOD_FACTOR * spec.wavelength_range_m[1] / coarsest > MAX_SAMPLES:
            return [*where, "wavelength_range_m"]
        if curve.track().total_length_m / coarsest > MAX_SAMPLES:
            return list(where)
        return [*where, "ds_m"]
    return [*where, "taper_m" if "taper_m" in message else "psd"]


def duration_s(curve: CurveTest) -> float:
    """How long a case runs [s]."""
    return curve.duration_s


def valve_settings(curve: CurveTest, valves: bool) -> Tuple[bool, ...]:
    """The valve settings the cases run with: ``curve.valve_settings`` (it has a default)."""
    return curve.valve_settings


def extra_files(curve: CurveTest) -> Tuple[Path, ...]:
    """Files the run reads besides the scenario and the vehicle's: the irregularity file."""
    irregularity = curve.irregularity
    return (Path(irregularity.file),) if irregularity is not None and irregularity.file is not None else ()
