"""Curve entry (paper §4.2, Fig. 9, Table 4): carbody roll and air consumption across k, with the
levelling and differential pressure valves disconnected and connected; with ``curve.guidance:
contact`` also the wheel-rail forces and the running-safety quantities of EN 14363 (Y/Q against
Nadal's limit, ΣY against Prud'homme's, wheel unloading ΔQ/Q0; docs/wheel_rail.md, "Curve runs
with contact guidance"). Kind ``curve_entry``, section ``curve`` (:class:`CurveTest`)."""
from __future__ import annotations

import dataclasses
import functools
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np
import xarray as xr

from cosim.engine.cases import simulate_scenarios
from cosim.errors import ScenarioError
from cosim.kinds.base import CarKind
from cosim.kinds.car import add_wheel_unloading, air_columns, bellow_panels, fault_columns, fault_figure, of_setting, per_case
from cosim.limits import en14363
from cosim.limits.assessment import STEP_M
from cosim.limits.checks import CaseMetrics
from cosim.limits.criteria import (
    NADAL_FLANGE_ANGLE_DEG,
    NADAL_FRICTION,
    SLIDING_MEAN_M,
    en14363_twist_limit,
    largest_track_twist,
    nadal_limit,
    prudhomme_limit_N,
    sliding_mean,
    window_mean,
)
from cosim.limits.ride_comfort import comfort_columns
from cosim.results.io import Progress, read_rows
from cosim.results.outcome import Outcome, largest, warn
from cosim.results.overlay import Selection, case_series
from cosim.results.plots import Curve, Figure, Panel, Span, save_panels
from cosim.results.series import WHEELSETS, with_column
from cosim.scenario.model import DEFAULT_WINDOW_S, Scenario
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
from vehicle.params import BELLOWS, CONTACT_DAMPING, FRICTION, TABLE_SMOOTHING, WHEELS, ContactParams, VehicleParams
from vehicle.track import TRANSITION_SHAPES, Arc, TrackGeometry

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
#: checkable metrics of the lateral wheel-rail forces: they need ``curve.guidance: contact``
CONTACT_METRICS = ("yq_max", "sum_y_max", "yq_2m_p9985", "sum_y_2m_p9985", "Y_2m_p50", "sum_y_rms_max")



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
    """Curve entry (paper §4.2, Fig. 9): straight, transition, circular arc, at constant speed.
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
    radius_m: float = field(default=100.0, metadata=RADIUS)
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

    def track(self) -> TrackGeometry:
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
    on_track = (curve.straight_m + curve.transition_m + curve.arc_m - car_length) / curve.speed_m_per_s
    if curve.duration_s > on_track:
        raise ScenarioError(path, ["curve", "duration_s"], f"the front wheelset leaves the track at t = {on_track:.3g} s; "
                                                           f"lengthen arc_m or shorten duration_s (got {curve.duration_s:g} s)")
    _check_contact(curve, path)
    length = curve.straight_m + curve.transition_m + curve.arc_m
    if length > MAX_TRACK_LENGTH_M:
        longest = max(("straight_m", "transition_m", "arc_m"), key=lambda k: getattr(curve, k))
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


def refuse_check(metric: str, curve: CurveTest) -> Optional[str]:
    """Why ``checks`` cannot name ``metric`` for this curve (None: it can)."""
    if metric in CONTACT_METRICS and not curve.contact:
        return (f"{metric} needs curve.guidance: contact (with {curve.guidance} guidance no lateral wheel-rail force "
                f"is computed)")
    if metric in en14363.QUASI_STATIC and not any(z in en14363.CURVE_ZONES for z in zones(curve)):
        return f"{metric} is a quasi-static value of a curve R < 600 m, and this track has none (R = {curve.radius_m:g} m)"
    return None


def refuse_zone(metric: str, zone: str, curve: CurveTest) -> Optional[str]:
    """Why ``checks`` cannot name ``metric`` in ``zone`` (None: it can): EN 14363 assesses the
    quasi-static values in the arcs R < 600 m only."""
    if metric in en14363.QUASI_STATIC and zone not in en14363.CURVE_ZONES:
        curves = [z for z in zones(curve) if z in en14363.CURVE_ZONES]
        return (f"{metric} is a quasi-static value of an arc R < 600 m: zone {zone!r} has none (this track's: "
                f"{', '.join(curves)})")
    return None


def zones(curve: CurveTest) -> Tuple[str, ...]:
    """The test zones of the curve's track (:mod:`cosim.limits.assessment`), in track order."""
    return tuple(dict.fromkeys(en14363.zone_table(curve.track())[1]))


def make_car(scenario: Scenario):
    """The car running along the curve-entry track (picklable factory for cosim.engine.cases), with
    the curve's guidance, contact parameters and track irregularity (generated from its seed in
    each worker: the same track in every one)."""
    from vehicle.car import MetroCar  # exudyn: imported when a car is built, not to read a scenario
    curve = scenario.curve
    return MetroCar(scenario.vehicle, step_s=scenario.solver.mechanics_step_s, track=curve.track(),
                    spectral_radius=scenario.solver.spectral_radius, track_structure=scenario.track,
                    speed_m_per_s=curve.speed_m_per_s, guidance=curve.guidance,
                    contact=curve.contact_params() if curve.contact else None,
                    irregularity=curve.track_irregularity(scenario.vehicle))


#: components whose link flows are written to the time series
VALVE_PREFIXES = ("lv_", "dpv_")


def sliding_window_s(curve: CurveTest) -> float:
    """EN 14363's 2 m sliding window as a time [s] at the curve's speed: 2 m / v."""
    return SLIDING_MEAN_M / curve.speed_m_per_s


def _over_time(da: xr.DataArray, fn) -> xr.DataArray:
    """``fn(values)`` on ``da`` with time first, as a DataArray of the same dimensions."""
    dims = ("time",) + tuple(d for d in da.dims if d != "time")
    out = fn(da.transpose(*dims).values)
    return xr.DataArray(out, dims=dims, coords={d: da[d] for d in dims if d in da.coords}).transpose(*da.dims)


def _attrs(da: xr.DataArray, **attrs) -> xr.DataArray:
    """``da`` with exactly ``attrs`` (arithmetic keeps an operand's, e.g. its CSV ``column``)."""
    da = da.copy()
    da.attrs = dict(attrs)
    return da


def wheel_rail_series(ds: xr.Dataset, curve: CurveTest) -> None:
    """Add the running-safety series to a curve run's Dataset (in place): ``dqq`` (ΔQ/Q0 per
    wheel, Q0 the static wheel load at t = 0, mean of the wheelset's two wheels, EN 14363),
    ``dqq_2m`` (its 2 m sliding mean, NaN for the first 2 m) and, with contact guidance,
    ``y_over_q`` (Y/Q per wheel; 0 on a wheel that carries nothing), ``y_over_q_2m`` and
    ``sum_y_2m_N`` (their EN 14363 2 m sliding means, NaN for the first 2 m)."""
    t = ds["time"].values
    add_wheel_unloading(ds)
    W = sliding_window_s(curve)
    ds["dqq_2m"] = with_column(_over_time(ds["dqq"], lambda v: sliding_mean(t, v, W)), "dqq_2m_{}", "1",
                               f"ΔQ/Q0 per wheel, sliding mean over {SLIDING_MEAN_M:g} m")
    if "lateral_wheel_force_N" not in ds:
        return
    Q = ds["wheel_load_N"]
    Y = ds["lateral_wheel_force_N"]
    with np.errstate(invalid="ignore", divide="ignore"):
        yq = xr.where(Q > 0.0, Y / Q, xr.where(Q.isnull() | Y.isnull(), np.nan, 0.0))
    ds["y_over_q"] = _attrs(yq, units="1", long_name="Y/Q per wheel")
    ds["y_over_q_2m"] = with_column(_over_time(yq, lambda v: sliding_mean(t, v, W)), "YQ_2m_{}", "1",
                                    f"Y/Q per wheel, EN 14363 sliding mean over {SLIDING_MEAN_M:g} m")
    ds["sum_y_2m_N"] = with_column(_over_time(ds["wheelset_lateral_force_N"], lambda v: sliding_mean(t, v, W)),
                                   "sumY_2m_{}_N", "N", f"ΣY per wheelset, EN 14363 sliding mean over {SLIDING_MEAN_M:g} m")


def car_centre_s_m(scenario: Scenario, t_s: np.ndarray) -> np.ndarray:
    """Arc length [m] of the car centre (midway between the bogie centres) at times ``t_s``:
    start_s + v t, with MetroCar's default start, the rear wheelset at s = 0, i.e. the car centre
    at (bogie centre distance + wheelbase) / 2."""
    p = scenario.vehicle
    return 0.5 * (p.bogie_centre_distance_m + p.wheelbase_m) + scenario.curve.speed_m_per_s * np.asarray(t_s, dtype=float)


def track_roll_rad(scenario: Scenario, t_s: np.ndarray) -> np.ndarray:
    """Roll [rad] of the track plane under the car: the mean of the design cant at the two bogie
    centres (the carbody rests on the bogies, so this is the plane it would settle parallel to; at
    the car centre alone the reference kinks where the centre passes a cant ramp's end while the
    bogies do not), in the carbody roll's convention (right hand about the forward axis, positive =
    left side up). ``TrackGeometry.cant_rad(s)`` is signed like the curvature, positive raising the
    right rail (a left-hand curve's outer rail): the plane's roll is minus it."""
    track = scenario.curve.track()
    s = car_centre_s_m(scenario, t_s)
    cants = [np.asarray(track.cant_rad(np.clip(s + x, 0.0, track.total_length_m)), dtype=float)
             for x in scenario.vehicle.bogie_x_m]
    return -0.5 * (cants[0] + cants[1])


def simulate(scenario: Scenario, progress: Optional[Progress] = None) -> Tuple[xr.Dataset, List[str]]:
    """Every case (k value x valve setting) of the curve entry: the labelled time series (see
    :mod:`cosim.results.series`) with the track plane's roll, the carbody roll relative to it, and the
    flows through the valves added, and the divergence diagnoses."""
    return simulate_many([scenario], progress)[0]


def simulate_many(scenarios: Sequence[Scenario], progress: Optional[Progress] = None,
                  names: Optional[Sequence[str]] = None) -> List[Tuple[xr.Dataset, List[str]]]:
    """:func:`simulate` for several curve entries at once (e.g. a ride's speeds), on one pool of
    processes (:func:`cosim.engine.cases.simulate_scenarios`: a scenario's k values share a process
    and a circuit where the processes allow). All must have the same valve settings."""
    settings = scenarios[0].curve.valve_settings
    if any(s.curve.valve_settings != settings for s in scenarios):
        raise ValueError("simulate_many: the scenarios' valve settings differ")
    results = simulate_scenarios(scenarios, settings, make_car, [s.curve.duration_s for s in scenarios], progress, names)
    return [(_with_track_series(scenario, ds), diagnoses) for scenario, (ds, diagnoses) in zip(scenarios, results)]


def _with_track_series(scenario: Scenario, ds: xr.Dataset) -> xr.Dataset:
    """The run's time series with the track plane's roll, the carbody roll relative to it, the
    wheel-rail series and the flows through the valves added."""
    curve = scenario.curve
    plane = track_roll_rad(scenario, ds["time"].values)
    ds["roll_track_plane_rad"] = with_column(xr.DataArray(plane, dims="time"), "roll_track_plane_rad", "rad",
                                             "roll of the track plane under the car (mean of the bogie centres)")
    ds["roll_rel_rad"] = with_column(ds["roll_rad"] - ds["roll_track_plane_rad"], "roll_carbody_rel_track_rad", "rad",
                                     "carbody roll relative to the track plane")
    wheel_rail_series(ds, curve)
    if "link" in ds.dims:
        valves = [name for name in ds["link"].values if str(name).startswith(VALVE_PREFIXES)]
        ds["valve_flow_kg_per_s"] = with_column(ds["link_flow_kg_per_s"].sel(link=valves).rename(link="valve_link"),
                                                "q_{}_kg_per_s", "kg/s", "mass flow through each valve, a -> b",
                                                sparse=True)
    return ds


def run(scenario: Scenario, progress: Progress) -> Outcome:
    """The curve entry: every case, its summary row (:func:`summary_row`) and checkable metrics."""
    t0 = time.perf_counter()
    curve = scenario.curve
    progress(f"curve entry at {curve.speed_m_per_s:g} m/s: {curve.straight_m:g} m straight, {curve.transition_m:g} m "
             f"transition, R = {curve.radius_m:g} m, {curve.guidance} guidance"
             f"{', irregular track' if curve.irregularity else ''}; {len(scenario.k_W_per_K)} k values x valves "
             f"{curve.valve_settings}")
    track, warnings = curve.track(), []
    for message in track_twist_warnings(track, scenario.vehicle):
        warn(warnings, message)
    ds, diagnoses = simulate(scenario, progress)
    rows, cases, statistics, assessed = [], [], [], []
    s_centre = car_centre_s_m(scenario, ds["time"].values)
    yq_lim = nadal_limit(curve.nadal_flange_angle_deg, curve.nadal_friction)
    for j in range(ds.sizes["case"]):
        case = ds.isel(case=j)
        row = summary_row(case, curve)
        sum_y_lim = prudhomme_limit_N(float(case["Q0_N"].min()), curve.prudhomme_alpha)
        stats, found = en14363.assess_case(case, s_centre, track, scenario.vehicle, yq_lim, sum_y_lim)
        row.update(en14363.summary_columns(found))
        row.update(en14363.stability_columns(case, curve.speed_m_per_s, sum_y_lim))
        row.update(comfort_columns(case))
        row.update(fault_columns(scenario, case))
        rows.append(row)
        cases.append(case_metrics(row, en14363.zone_metrics(found, stats)))
        statistics += en14363.statistics_rows(stats, row["valves"], row["k_W_per_K"])
        assessed += en14363.limit_rows(found, row["valves"], row["k_W_per_K"])
    headline = [m for m in KIND.headline_metrics if rows and m in rows[0]]
    metrics = {m: largest(r[m] for r in rows) for m in headline} if rows else {}
    shown = ("valves", "k_W_per_K", "roll_max_rad", "roll_mean_end_rad", "air_injected_kg", "air_exhausted_kg",
             "dqq_2m_p9985", "Q_2m_p9985_N")
    if curve.contact:
        shown += ("yq_2m_p9985", "sum_y_2m_p9985_N")
    shown += ("en14363_failed",)
    info = {"window_s": curve.window, "guidance": curve.guidance}
    info.update(sliding_mean_m=SLIDING_MEAN_M, assessment_step_m=STEP_M,
                zones=list(en14363.zones_run(track, scenario.vehicle, s_centre[[0, -1]])))
    if curve.contact:
        info.update(yq_lim=rows[0]["yq_lim"] if rows else None, sum_y_lim_N=rows[0]["sum_y_lim_N"] if rows else None)
    if curve.irregularity is not None:
        info["irregularity"] = curve.track_irregularity(scenario.vehicle).source
    coarse = en14363.acceleration_warning(ds["time"].values)
    if coarse:
        warn(warnings, coarse)
    step = ramp_roll_rate_step_rad_per_s(curve)
    if step:
        warn(warnings, f"the linear cant ramp steps the rails' roll rate by {step:.3g} rad/s where a wheelset "
                       f"enters and leaves it (curve.transition_shape: linear): that rings each wheelset on its "
                       f"contacts (~240 Hz on a rigid track), beyond the step, so sampled peaks there (dqq_raw_max, "
                       f"Y_raw_max_N) depend on the step; the 2 m means hold better. transition_shape: bloss or cosine has "
                       f"no step")
    return Outcome(scenario, rows, shown, {"curve": ds}, metrics, cases, diagnoses, warnings, info,
                   time.perf_counter() - t0, tables={"assessment": statistics, "assessment_limits": assessed})


#: grid of the arc length on which :func:`track_twist_warnings` looks for the largest twist [m]
TWIST_GRID_M = 0.05


def track_twist_warnings(track: TrackGeometry, vehicle: VehicleParams) -> List[str]:
    """A warning for each base, the bogie's wheelbase 2a+ and the bogie centre distance 2a*, over
    which the design cant twists the track more than EN 14363's limit track twist for that base
    (:func:`~cosim.limits.criteria.en14363_twist_limit`, the twist of its test on twisted track: what
    the standard asks a vehicle to negotiate): a steep cant ramp, e.g. 0.1 rad over 10 m (22 per
    mille over a 2 m wheelbase), on which the car may unload a wheel or climb a flange because of
    the track. The cross-level is taken over ``contact_spacing_m``."""
    s = np.append(np.arange(0.0, track.total_length_m, TWIST_GRID_M), track.total_length_m)
    found = []
    for name, base in (("wheelbase 2a+", vehicle.wheelbase_m), ("bogie centre distance 2a*",
                                                                 vehicle.bogie_centre_distance_m)):
        twist, at = largest_track_twist(track.cant_rad, s, base, vehicle.contact_spacing_m)
        limit = en14363_twist_limit(base)
        if twist > limit:
            found.append(f"the cant ramp twists the track by {1e3 * twist:.3g} per mille over the {name} "
                         f"({base:g} m, ending at s = {at:.1f} m): steeper than the {1e3 * limit:g} per mille EN 14363 "
                         f"asks a vehicle to negotiate over that base (its test on twisted track); the wheel "
                         f"unloading there includes the ramp's own twist")
    return found


def ramp_roll_rate_step_rad_per_s(curve: CurveTest) -> float:
    """The step of the rails' roll rate at the ends of a linear cant ramp, v c / L [rad/s] (0 for
    a smoothed transition, or without cant)."""
    if curve.transition_shape != "linear" or curve.cant_rad == 0.0:
        return 0.0
    return curve.speed_m_per_s * abs(curve.cant_rad) / curve.transition_m


def case_metrics(row: Dict[str, object], zoned: Dict[str, Dict[str, Dict[str, float]]]) -> CaseMetrics:
    """The checkable metrics of a summary row (:attr:`KIND.check_metrics <cosim.kinds.base.Kind.check_metrics>`): the wheel
    metrics per wheel; ``yq_max`` and ``sum_y_max`` [N] only with contact guidance; the EN 14363
    assessment's per zone and wheel (``zoned``, :func:`cosim.limits.en14363.zone_metrics`)."""
    values = {m: row[m] for m in ("roll_max_rad", "air_injected_kg", "air_exhausted_kg", "air_lost_kg")}
    wheels = {m: {w: row[f"{m}_{w}"] for w in WHEELS} for m in ("dqq_raw_max", "dqq_2m_max")}
    if "sum_y_rms_max_N" in row:
        values["sum_y_rms_max"] = row["sum_y_rms_max_N"]
    if "yq_max" in row:
        values["sum_y_max"] = row["sum_y_max_N"]
        wheels["yq_max"] = {w: row[f"yq_max_{w}"] for w in WHEELS}
    return CaseMetrics(row["k_W_per_K"], row["valves"], values, wheels, zoned)


def _largest_after(t: np.ndarray, values: np.ndarray, t_from: float) -> np.ndarray:
    """Largest sample (over time, the first axis) from ``t_from`` on; NaN if one of them is NaN
    (a diverged case) or there is none."""
    keep = t >= t_from - 1e-9
    if not keep.any():
        return np.full(values.shape[1:], np.nan)
    return values[keep].max(axis=0)


def summary_row(case: xr.Dataset, curve: CurveTest) -> Dict[str, object]:
    """The summary of one case (``case``: the Dataset of :func:`simulate` at one case): roll
    relative to the track plane (largest |roll| over the run, and its mean over the final window:
    the steady roll in the arc, not wherever the ~1 Hz sway is at the last sample), air exchanged
    (cumulative: its last sample), bellow crushing (final-window means), and per levelling valve
    the air through its supply and exhaust sides and the fraction of the run each side was open."""
    t = case["time"].values
    roll = case["roll_rel_rad"].values
    row = {"valves": bool(case["valves"]), "k_W_per_K": float(case["k_W_per_K"]),
           "roll_max_rad": float(np.abs(roll).max()),
           "roll_mean_end_rad": float(window_mean(t, roll, curve.window))}
    air = air_columns(case)
    row.update({name: air[name] for name in ("air_injected_kg", "air_exhausted_kg", "air_lost_kg")})
    z = window_mean(t, case["crushing_m"].transpose("time", "bellow").values, curve.window)
    row.update({f"z_mean_end_{b}_m": float(z[i]) for i, b in enumerate(BELLOWS)})
    duration = float(t[-1] - t[0])
    if "valve" in case.dims:
        for v in case["valve"].values:
            if np.isnan(case["valve_supply_air_kg"].sel(valve=v).values[-1]):
                continue                             # a valve of another setting's circuit
            at_end = {name: float(case[name].sel(valve=v).values[-1]) for name in
                      ("valve_supply_air_kg", "valve_exhaust_air_kg", "valve_supply_open_s", "valve_exhaust_open_s")}
            row[f"{v}_supply_air_kg"] = at_end["valve_supply_air_kg"]
            row[f"{v}_exhaust_air_kg"] = at_end["valve_exhaust_air_kg"]
            row[f"{v}_supply_open_fraction"] = at_end["valve_supply_open_s"] / duration
            row[f"{v}_exhaust_open_fraction"] = at_end["valve_exhaust_open_s"] / duration
    T = case["bellow_T_K"].values
    row["T_bellow_min_K"], row["T_bellow_max_K"] = float(T.min()), float(T.max())
    # closes to the integrator's round-off: air in the chambers changes only by what crosses the boundary
    m = case["total_mass_kg"].values
    row["air_initial_kg"] = float(m[0])  # the air the circuit holds at the start (verify's floor for air)
    row["Q0_N"] = float(case["Q0_N"].mean())  # the static wheel load (verify's floor for forces)
    row["mass_balance_error_kg"] = air["mass_balance_error_kg"]
    row.update(wheel_rail_summary(case, curve))
    return row


def wheel_rail_summary(case: xr.Dataset, curve: CurveTest) -> Dict[str, object]:
    """The running-safety columns of one case (``case``: the Dataset of :func:`simulate` at one
    case, with :func:`wheel_rail_series`):

    * ``dqq_raw_max_<wheel>``, ``dqq_raw_max``: the largest sampled ΔQ/Q0 over the run (raw: no
      filter, no mean), per wheel and over the wheels (both guidances; kinematic Q is vertical, contact Q
      normal to the track plane); ``dqq_2m_max_<wheel>``, ``dqq_2m_max``: the same for its 2 m
      sliding mean (the sampled peak of a flange impact's ~45 Hz ringing depends on where the
      samples fall: on the R = 150 m twisted curve it moves by 9 % as the steps are halved,
      while the 2 m mean holds to 4 digits; docs/wheel_rail.md);

    with contact guidance also, the 2 m sliding means (EN 14363) counted from the first whole
    window on:

    * ``Y_raw_max_<wheel>_N``, ``Y_raw_max_N``: the largest sampled Y (raw; + towards the track centre);
    * ``yq_max_<wheel>``, ``yq_max``: the largest (Y/Q)_2m, against ``yq_lim`` (Nadal,
      :func:`cosim.limits.criteria.nadal_limit`);
    * ``sum_y_max_<wheelset>_N``, ``sum_y_max_N``: the largest |ΣY_2m| per wheelset and over
      them, against ``sum_y_lim_N`` (Prud'homme as EN 14363 states it, Q0 the static wheel load;
      :func:`cosim.limits.criteria.prudhomme_limit_N`);
    * ``y_ws_max_<wheelset>_m``, ``y_ws_rails_max_<wheelset>_m``, ``aoa_max_<wheelset>_rad``:
      the largest |lateral displacement| from the design centre line and relative to the rails
      (they differ by the alignment irregularity), and |angle of attack| per wheelset;
    * ``flange_fraction_<wheel>``, ``flange_fraction``: the fraction of the samples a wheel is in
      flange contact, and the largest over the wheels."""
    t = case["time"].values
    t_full = t[0] + sliding_window_s(curve)
    dqq = case["dqq"].transpose("time", "wheel").values
    worst = dqq.max(axis=0)
    row: Dict[str, object] = {f"dqq_raw_max_{w}": float(v) for w, v in zip(WHEELS, worst)}
    row["dqq_raw_max"] = largest(worst)
    worst = _largest_after(t, case["dqq_2m"].transpose("time", "wheel").values, t_full)
    row.update({f"dqq_2m_max_{w}": float(v) for w, v in zip(WHEELS, worst)})
    row["dqq_2m_max"] = largest(worst)
    if "y_over_q_2m" not in case:
        return row
    Y = case["lateral_wheel_force_N"].transpose("time", "wheel").values
    Y_max = Y.max(axis=0)
    row.update({f"Y_raw_max_{w}_N": float(v) for w, v in zip(WHEELS, Y_max)})
    row["Y_raw_max_N"] = largest(Y_max)
    yq = _largest_after(t, case["y_over_q_2m"].transpose("time", "wheel").values, t_full)
    row.update({f"yq_max_{w}": float(v) for w, v in zip(WHEELS, yq)})
    row["yq_max"] = largest(yq)
    row["yq_lim"] = nadal_limit(curve.nadal_flange_angle_deg, curve.nadal_friction)
    sum_y = _largest_after(t, np.abs(case["sum_y_2m_N"].transpose("time", "wheelset").values), t_full)
    row.update({f"sum_y_max_{ws}_N": float(v) for ws, v in zip(WHEELSETS, sum_y)})
    row["sum_y_max_N"] = largest(sum_y)
    # each wheelset's own static wheel load; the smallest limit (the lightest wheelset) is reported
    row["sum_y_lim_N"] = prudhomme_limit_N(float(case["Q0_N"].min()), curve.prudhomme_alpha)
    for name, column in (("wheelset_lateral_m", "y_ws_max_{}_m"), ("wheelset_lateral_to_rails_m", "y_ws_rails_max_{}_m"),
                         ("angle_of_attack_rad", "aoa_max_{}_rad")):
        worst = np.abs(case[name].transpose("time", "wheelset").values).max(axis=0)
        row.update({column.format(ws): float(v) for ws, v in zip(WHEELSETS, worst)})
    flange = case["flange_contact"].transpose("time", "wheel").values.mean(axis=0)
    row.update({f"flange_fraction_{w}": float(v) for w, v in zip(WHEELS, flange)})
    row["flange_fraction"] = largest(flange)
    return row


def figures(outcome: Outcome) -> List[Figure]:
    """Carbody roll (paper Fig. 9), per valve setting the bellows, and the air consumption; the roll
    and, with contact, the wheel-rail quantities also along the track (:func:`along_track`), each
    such figure named after its time figure with ``_along_track``."""
    if not outcome.rows:
        return []
    ds = outcome.series["curve"]
    curve = outcome.scenario.curve
    axis = track_axis(outcome.scenario, ds["time"].values)
    settings = curve.valve_settings
    roll = [Panel(per_case(of_setting(ds, v)["roll_rel_rad"], 1e3), "time t [s]",
                  "carbody roll to the track plane [mrad]", f"valves {'connected' if v else 'disconnected'}")
            for v in settings]
    out = along_track(Figure("fig9_roll.png", roll, "Carbody roll entering a curve (paper Fig. 9)", len(roll)),
                      [axis.centre_m for _ in roll], [axis.spans] * len(roll), "car centre", axis.outer_text)
    for valves in settings:
        sub = of_setting(ds, valves)
        tag = "on" if valves else "off"
        heights = [Panel(per_case(sub["crushing_m"].sel(bellow=b), 1e3), "time t [s]", f"crushing z_{b} [mm]",
                         f"bellow {b}") for b in BELLOWS]
        out.append(Figure(f"bellows_valves={tag}.png", heights + bellow_panels(sub),
                          f"Bellow crushing (+ compression), pressure and temperature, valves {tag}", 2))
        if valves:
            out.append(Figure("air_consumption.png",
                              [Panel(per_case(sub["air_from_supply_kg"], 1e3), "time t [s]",
                                     "air injected from the supply [g]"),
                               Panel(per_case(sub["air_to_atmosphere_kg"], 1e3), "time t [s]",
                                     "air exhausted to the atmosphere [g]")],
                              "Air consumption of the levelling valves (paper Table 4)", 2))
        out += fault_figure(outcome.scenario, sub, f"_valves={tag}", f", valves {tag}")
    if curve.contact:
        out += wheel_rail_figures(ds, curve, outcome.rows, axis)
    return out


@dataclass(frozen=True)
class TrackAxis:
    """Where a curve run's samples lie along the track: ``centre_m`` the car centre's arc length
    at each sample [m], ``wheelset_x_m`` each wheelset's offset from it (front first), ``spans``
    the track's segments as they are drawn (:func:`track_spans`) and ``outer`` the side of the
    outer rail in the curve (``R`` or ``L``)."""

    centre_m: np.ndarray
    wheelset_x_m: Tuple[float, ...]
    spans: Tuple[Span, ...]
    outer: str

    def wheelset(self, wheelset: str, shift_m: float = 0.0) -> np.ndarray:
        """Arc length [m] of wheelset ``1`` ... ``4`` at each sample, plus ``shift_m``."""
        return self.centre_m + self.wheelset_x_m[WHEELSETS.index(wheelset)] + shift_m

    def wheel(self, wheel: str, shift_m: float = 0.0) -> np.ndarray:
        return self.wheelset(wheel[:-1], shift_m)

    def rail(self, wheel: str) -> str:
        """`` (outer rail)`` / `` (inner rail)`` of a wheel in the curve."""
        return " (outer rail)" if wheel[-1] == self.outer else " (inner rail)"

    @property
    def outer_text(self) -> str:
        side = "right" if self.outer == "R" else "left"
        return f"outer rail {side} (wheels 1{self.outer}-4{self.outer})"


def track_axis(scenario: Scenario, t_s: np.ndarray) -> TrackAxis:
    """The :class:`TrackAxis` of a curve run sampled at ``t_s``."""
    curve = scenario.curve
    return TrackAxis(car_centre_s_m(scenario, t_s), tuple(scenario.vehicle.wheelset_x_m), track_spans(curve.track()),
                     "R" if curve.direction > 0 else "L")


def track_spans(track: TrackGeometry) -> Tuple[Span, ...]:
    """The track's segments as spans of a position axis: straights unshaded, transitions and arcs
    shaded, each named with its EN 14363 test zone (:func:`cosim.limits.en14363.zone_table`)."""
    starts, zones, _ = en14363.zone_table(track)
    ends = [*starts[1:], track.total_length_m]
    spans = []
    for seg, zone, a, b in zip(track.segments, zones, starts, ends):
        if isinstance(seg, Arc):
            spans.append(Span(a, b, f"arc R = {seg.radius_m:g} m (zone {zone})"))
        else:
            spans.append(Span(a, b, zone, shade=zone != "straight"))
    return tuple(spans)


def along_track(figure: Figure, positions: Sequence[np.ndarray], spans: Sequence[Sequence[Span]], where: str,
                note: str = "") -> List[Figure]:
    """``figure`` (panels against time) and its twin along the track: each panel's curves against
    the arc length of what they belong to (``positions``, one per panel: the car centre, a wheel
    at its 2 m window's centre ...), with its track's segments and zones marked (``spans``, one
    list per panel); ``where`` names the position in the axis label, ``note`` is added to the
    title (e.g. which rail is outer)."""
    panels = [dataclasses.replace(p, curves=[dataclasses.replace(c, x=s) for c in p.curves],
                                  xlabel=f"position along the track s [m] ({where})", spans=list(marks))
              for p, s, marks in zip(figure.panels, positions, spans)]
    title = f"{figure.title}, along the track" + (f"; {note}" if note else "")
    return [figure, dataclasses.replace(figure, name=figure.name.replace(".png", "_along_track.png"), panels=panels,
                                        title=title)]


def wheel_rail_figures(ds: xr.Dataset, curve: CurveTest, rows: List[Dict[str, object]],
                       axis: TrackAxis) -> List[Figure]:
    """Contact guidance, per valve setting: Y/Q (2 m sliding mean) per wheel across k with Nadal's
    limit, ΔQ/Q0 per wheel across k, ΣY (2 m sliding mean) per wheelset with Prud'homme's limit;
    each against time and along the track (a 2 m mean at its window's centre: 1 m behind the
    wheel), every wheel's panel naming its rail in the curve."""
    yq_lim, sum_y_lim = rows[0]["yq_lim"], rows[0]["sum_y_lim_N"]
    nadal = [(yq_lim, f"Nadal limit {yq_lim:.2f} ({curve.nadal_flange_angle_deg:g}°, μ = {curve.nadal_friction:g})")]
    prud = [(sign * sum_y_lim * 1e-3, f"{'+' if sign > 0 else '-'}Prud'homme limit {sum_y_lim * 1e-3:.1f} kN")
            for sign in (1.0, -1.0)]
    centre = -0.5 * SLIDING_MEAN_M                        # a trailing 2 m mean belongs to its window's centre
    out = []
    for valves in curve.valve_settings:
        sub = of_setting(ds, valves)
        tag = "on" if valves else "off"
        yq = [Panel(per_case(sub["y_over_q_2m"].sel(wheel=w)), "time t [s]", f"(Y/Q)_2m, wheel {w}",
                    f"wheel {w}{axis.rail(w)}", hlines=nadal) for w in WHEELS]
        out += along_track(Figure(f"wheel_yq_valves={tag}.png", yq,
                                  f"Y/Q per wheel, {SLIDING_MEAN_M:g} m sliding mean (EN 14363), valves {tag}", 2),
                           [axis.wheel(w, centre) for w in WHEELS], [axis.spans] * len(WHEELS),
                           "the wheel's 2 m window centre", axis.outer_text)
        dqq = [Panel(per_case(sub["dqq"].sel(wheel=w)), "time t [s]", f"ΔQ/Q0, wheel {w}", f"wheel {w}{axis.rail(w)}")
               for w in WHEELS]
        out += along_track(Figure(f"wheel_dqq_valves={tag}.png", dqq, f"Wheel unloading ΔQ/Q0 per wheel, valves {tag}",
                                  2), [axis.wheel(w) for w in WHEELS], [axis.spans] * len(WHEELS), "the wheel",
                           axis.outer_text)
        sum_y = [Panel(per_case(sub["sum_y_2m_N"].sel(wheelset=ws), 1e-3), "time t [s]", "(ΣY)_2m [kN]",
                       f"wheelset {ws}", hlines=prud) for ws in WHEELSETS]
        out += along_track(Figure(f"wheelset_sum_y_valves={tag}.png", sum_y,
                                  f"ΣY per wheelset (+ left), {SLIDING_MEAN_M:g} m sliding mean, valves {tag}", 2),
                           [axis.wheelset(ws, centre) for ws in WHEELSETS], [axis.spans] * len(WHEELSETS),
                           "the wheelset's 2 m window centre", axis.outer_text)
    return out


def record_headlines(scenario: Scenario, rec: Dict[str, np.ndarray], j: int = 0,
                     window_s: Optional[float] = None) -> Dict[str, float]:
    """Headlines of case ``j`` of raw record arrays (``CoSimulation.run``'s or the monolithic
    reference's: :mod:`cosim.verification.monolithic`): largest |roll| relative to the track
    plane, its mean over the final window (``window_s``, default the scenario's), air injected
    and exhausted [kg]."""
    t = np.asarray(rec["t_s"])
    roll = rec["roll_rad"][:, j] - track_roll_rad(scenario, t)
    w = window_s if window_s is not None else scenario.curve.window
    return {"roll_max_rad": float(np.abs(roll).max()),
            "roll_mean_end_rad": float(window_mean(t, roll, min(w, t[-1] - t[0]))),
            "air_injected_kg": float(rec["air_from_supply_kg"][-1, j]),
            "air_exhausted_kg": float(rec["air_to_atmosphere_kg"][-1, j])}


def _worst(run_dirs, columns: Sequence[str]) -> Optional[str]:
    """The label (wheel or wheelset) whose summary column ``<metric>_<label>...`` is largest over
    the runs' cases; ``columns``: (label, column) pairs."""
    best, where = -np.inf, None
    for d in run_dirs:
        for row in read_rows(d / "summary.csv") if (d / "summary.csv").exists() else []:
            for label, column in columns:
                try:
                    value = float(row.get(column, "nan"))
                except ValueError:
                    continue
                if value > best:
                    best, where = value, label
    return where


def compare(infos, out_dir: Path, select: Selection, label, window: str) -> List[Path]:
    """Overlay the carbody roll (to the track plane) and the air injected of several curve runs;
    with contact guidance also (ΔQ/Q0)_2m and (Y/Q)_2m of the worst wheel and (ΣY)_2m of the
    worst wheelset over the runs (or of the wheels ``select.wheels`` names)."""
    run_dirs = [d for d, _ in infos]

    def panel(column, scale, ylabel, title="", hlines=()):
        curves = [Curve(data["t_s"], data[column] * scale, label(d, case))
                  for d in run_dirs for case, data in case_series(d, "curve_", select) if column in data.dtype.names]
        return Panel(curves, "time t [s]", ylabel, title, hlines=list(hlines)) if curves else None

    panels = [panel("roll_carbody_rel_track_rad", 1e3, "carbody roll to the track plane [mrad]"),
              panel("air_from_supply_kg", 1e3, "air injected from the supply [g]")]
    info = infos[0][1]
    nadal = [(info["yq_lim"], f"Nadal limit {info['yq_lim']:.2f}")] if info.get("yq_lim") else []
    prud = ([(sign * info["sum_y_lim_N"] * 1e-3, "Prud'homme limit") for sign in (1.0, -1.0)]
            if info.get("sum_y_lim_N") else [])
    for column, name, ranked, limit in (("dqq_2m_{}", "(ΔQ/Q0)_2m", "dqq_2m_max_{}", []),
                                        ("YQ_2m_{}", "(Y/Q)_2m", "yq_max_{}", nadal)):
        worst = _worst(run_dirs, [(w, ranked.format(w)) for w in WHEELS])
        for w in select.wheels or ((worst,) if worst else ()):
            tag = f"wheel {w}" + (" (the worst)" if w == worst else "")
            panels.append(panel(column.format(w), 1.0, f"{name}, wheel {w} [-]", tag, limit))
    ws = _worst(run_dirs, [(n, f"sum_y_max_{n}_N") for n in WHEELSETS])
    if ws is not None:
        panels.append(panel(f"sumY_2m_{ws}_N", 1e-3, f"(ΣY)_2m, wheelset {ws} [kN]", f"wheelset {ws} (the worst)",
                            prud))
    panels = [p for p in panels if p is not None]
    return [save_panels(out_dir / "compare_curve.png", panels, f"Curve entry comparison{window}", ncols=2)]


class CurveEntryKind(CarKind):
    """A run into a curve (paper §4.2)."""

    name, section, experiment = "curve_entry", "curve", CurveTest
    check_metrics = ("roll_max_rad", "air_injected_kg", "air_exhausted_kg", "air_lost_kg", "yq_max", "sum_y_max",
                     "dqq_raw_max",
                     "dqq_2m_max", "sum_y_rms_max", *en14363.METRICS)
    wheel_metrics = ("dqq_raw_max", "yq_max", "dqq_2m_max",
                     *(m for m, (q, _, _) in en14363.METRICS.items() if en14363.QUANTITIES.get(q, ("", ""))[1] == "wheel"))
    zone_metrics = tuple(en14363.METRICS)
    # the processed quantities an engineer is judged by: EN 14363's statistics of the 2 m
    # means along the track (cosim.limits.en14363), the roll (largest, and its mean over the
    # final window), the air; not the raw sampled peaks (dqq_raw_max, Y_raw_max_N: one sample
    # of a transient the step may not resolve); a column that is absent (yq_2m_p9985 and
    # sum_y_2m_p9985_N without contact, Y_2m_p50_N without an arc R < 600 m) is skipped; the
    # carbody accelerations by their rms: their largest filtered value is one output sample
    # (checkable, in the summary and the report, but a single sample; on curve_canted it is
    # 0.53 % from its Richardson estimate, and the sampling at the output interval can miss a
    # 10 Hz peak by more)
    headline_metrics = ("roll_max_rad", "roll_end_rad", "roll_mean_end_rad", "air_injected_kg",
                        "air_exhausted_kg", "dqq_2m_p9985", "Q_2m_p9985_N", "Q_2m_p50_N", "Y_2m_p50_N",
                        "yq_2m_p9985", "sum_y_2m_p9985_N", "ay_floor_rms_m_per_s2", "az_floor_rms_m_per_s2")
    plot_metrics = ("roll_max_rad", "roll_mean_end_rad", "air_injected_kg", "air_exhausted_kg")

    parse = staticmethod(parse)
    duration_s = staticmethod(duration_s)
    valve_settings = staticmethod(valve_settings)
    extra_files = staticmethod(extra_files)
    refuse_check = staticmethod(refuse_check)
    refuse_zone = staticmethod(refuse_zone)
    zones = staticmethod(zones)
    make_car = staticmethod(make_car)
    run = staticmethod(run)
    figures = staticmethod(figures)
    compare = staticmethod(compare)


KIND = CurveEntryKind()
