"""A run of the car along a track, as a scenario describes it: the track (straight, transition,
circular arc, cant; or straight alone), the speed, the guidance, the contact's parameters, the
limits of the summary, and the track's irregularities (:class:`CurveTest`,
:class:`IrregularitySpec`), checked against the car (:func:`parse`). The ``curve_entry`` kind's
experiment is one; ``ride`` builds one per speed."""
from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Optional, Tuple

import numpy as np

from cosim.errors import ScenarioError
from cosim.limits.criteria import nadal_limit
from cosim.scenario.model import DEFAULT_WINDOW_S
from cosim.scenario.schema import Range, build, check_valve_settings, describe, positive
from vehicle.irregularities import CHANNELS, MAX_SAMPLES, PERIOD_FACTOR, TrackIrregularity, canonical_kind
from vehicle.params import ContactParams, VehicleParams
from vehicle.track import TRANSITION_SHAPES, Straight, TrackGeometry

#: Largest cant [rad]: 0.2 rad is 300 mm over the 1.5 m rail-centre distance; railway cant is
#: limited to 150-200 mm (EN 13803: 180 mm, ~0.12 rad).
MAX_CANT_RAD = 0.2
#: Highest running speed [m/s]: 100 m/s = 360 km/h, beyond any metro and the wheel-rail model.
MAX_SPEED_M_PER_S = 100.0
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
    seed: int = 0
    wavelength_range_m: Tuple[float, ...] = (3.0, 150.0)
    channels: Tuple[str, ...] = ("lateral", "vertical", "cross_level", "gauge")
    ds_m: float = 0.25
    start_m: Optional[float] = None
    taper_m: float = 10.0
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

    speed_m_per_s: float = 10.0
    straight_m: float = 20.0
    transition_m: float = 15.0
    transition_shape: str = "bloss"
    radius_m: Optional[float] = 100.0
    arc_m: float = 300.0
    cant_rad: float = 0.0
    direction: int = 1
    duration_s: float = 30.0
    valve_settings: Tuple[bool, ...] = (False, True)
    window_s: Optional[float] = None
    guidance: str = "contact"
    friction_coefficient: Optional[float] = None
    contact_damping_N_s_per_m: Optional[float] = None
    contact_smoothing_mm: Optional[float] = None
    nadal_flange_angle_deg: float = 70.0
    nadal_friction: float = 0.36
    prudhomme_alpha: float = 1.0
    irregularity: Optional[IrregularitySpec] = None

    FIELD_RANGES = {
        "speed_m_per_s": Range(0.0, MAX_SPEED_M_PER_S, False, True, "m/s", "360 km/h at most"),
        "straight_m": positive("m"), "transition_m": positive("m"), "radius_m": positive("m"), "arc_m": positive("m"),
        "cant_rad": Range(-MAX_CANT_RAD, MAX_CANT_RAD, unit="rad",
                          why="0.2 rad = 300 mm over 1.5 m; railway cant is at most ~0.12 rad"),
        "contact_damping_N_s_per_m": Range(0.0, 1e7, unit="N s/m", why="the shipped 2e5 stands in for the track's damping"),
        "contact_smoothing_mm": Range(0.0, 1.0, unit="mm", why="0: the rigid table; 1 mm blurs the flange itself"),
    }

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
    if curve.direction not in (1, -1):
        raise ScenarioError(path, ["curve", "direction"], f"expected 1 (left) or -1 (right), got {curve.direction}")
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
    mu = curve.friction_coefficient
    if mu is not None and not 0.0 < mu <= 1.0:
        raise ScenarioError(path, ["curve", "friction_coefficient"], f"expected a wheel-rail friction coefficient in "
                                                                     f"(0, 1] (dry rail 0.3-0.5), got {mu:g}")
    for key in ("friction_coefficient", "contact_damping_N_s_per_m", "contact_smoothing_mm"):
        if getattr(curve, key) is not None and not curve.contact:
            raise ScenarioError(path, ["curve", key], "a parameter of the contact model needs curve.guidance: contact")
    if not 0.0 < curve.nadal_flange_angle_deg < 90.0:
        raise ScenarioError(path, ["curve", "nadal_flange_angle_deg"], f"expected a flange angle in (0, 90) degrees, "
                                                                       f"got {curve.nadal_flange_angle_deg:g}")
    if not 0.0 <= curve.nadal_friction <= 1.0:
        raise ScenarioError(path, ["curve", "nadal_friction"], f"expected a friction coefficient in [0, 1], "
                                                               f"got {curve.nadal_friction:g}")
    if not nadal_limit(curve.nadal_flange_angle_deg, curve.nadal_friction) > 0.0:
        raise ScenarioError(path, ["curve", "nadal_friction"], f"the Nadal limit (tan g - mu)/(1 + mu tan g) must be "
                                                               f"> 0: mu = {curve.nadal_friction:g} is not below tan "
                                                               f"{curve.nadal_flange_angle_deg:g} deg")
    if not 0.0 < curve.prudhomme_alpha <= 1.0:
        raise ScenarioError(path, ["curve", "prudhomme_alpha"], f"expected a factor in (0, 1] (EN 14363: 1, freight "
                                                                f"wagons 0.85), got {curve.prudhomme_alpha:g}")


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
        if spec.seed < 0:
            raise ScenarioError(path, [*where, "seed"], f"expected an integer >= 0, got {spec.seed}")
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
