"""What a scenario asks for, as data: the experiments (rig tests, the twist, the curve entry), the
circuits, the solver settings and the :class:`Scenario` that holds them. Nothing here reads files
or runs anything: :mod:`cosim.scenario.load` builds these from YAML and validates them, the runners
(:mod:`cosim.runner`) consume them.
"""
from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Optional, Tuple

from pneumatics.boundary import Supply
from pneumatics.chamber import Bellow, Tank
from pneumatics.layouts import car_circuit
from pneumatics.pipe import Pipe
from pneumatics.rig import bellow_tank_components
from pneumatics.valves import DifferentialPressureValve, LevellingValve
from vehicle.irregularities import TrackIrregularity
from vehicle.params import ContactParams, TrackStructure, VehicleParams
from vehicle.track import TRANSITION_SHAPES, TrackGeometry  # noqa: F401 (re-exported)

from cosim.limits.checks import Check

RIG_KINDS = ("rig_ramp", "rig_sine", "rig_stiffness", "rig_table2")
CAR_KINDS = ("twist", "curve_entry")
KINDS = RIG_KINDS + CAR_KINDS


# ----------------------------------------------------------------------------------- tests
@dataclass(frozen=True)
class RampTest:
    """Fig. 3: crushing ramp to ``amplitude_m`` in ``ramp_s``, held until ``duration_s``."""

    amplitude_m: float = 0.02
    ramp_s: float = 1.0
    duration_s: float = 30.0
    samples: int = 601
    configurations: Tuple[str, ...] = ("bellow_tank", "bellow_only")


@dataclass(frozen=True)
class SineTest:
    """Fig. 5: z = a sin(2 pi f t) for ``duration_s``; the time history is sampled
    ``samples_per_period`` times a period. The run counts as stabilised when the mean bellow
    temperature drifts by less than ``stable_drift_K_per_period`` over the last tenth of it
    (default 1e-3 K: at 1 Hz, less than 4 K an hour)."""

    amplitude_m: float = 0.02
    frequency_Hz: float = 1.0
    duration_s: float = 300.0
    samples_per_period: int = 20
    stable_drift_K_per_period: float = 1e-3


@dataclass(frozen=True)
class StiffnessTest:
    """Fig. 6: K_dyn (eq. 9) on the periodic steady state for each frequency."""

    amplitude_m: float = 0.02
    frequencies_Hz: Tuple[float, ...] = (0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0)


@dataclass(frozen=True)
class QuasiStaticTest:
    """Table 2: slope of a slow small ramp."""

    amplitude_m: float = 1e-4
    ramp_s: float = 20.0


RIG_TESTS = {"rig_ramp": RampTest, "rig_sine": SineTest, "rig_stiffness": StiffnessTest, "rig_table2": QuasiStaticTest}


@dataclass(frozen=True)
class TwistTest:
    """EN 14363 twist (Fig. 7): the rails under ``raised_wheels`` rise by the test height in
    ``ramp_s`` (smooth cosine ramp), then hold for ``hold_s``.

    Test height = twist x base. The twist limit of the track the car must negotiate depends on the
    base length 2a (here the bogie centre distance): 7 permille for 2a <= 4 m, 20/2a + 2 permille
    for 4 m < 2a <= 20 m, 3 permille above (the rule commonly quoted from EN 14363; set
    ``twist_per_mille`` to override it).

    EN 14363 twists the car over both bases together: the carbody twist g* over the bogie
    centre distance 2a* and the bogie twist g+ over the wheelbase 2a+. ``bogie_base_m`` (2a+,
    the car's wheelbase) switches the bogie twist on: the front bogie's rails on the raised side
    (``raised_wheels`` must then be that side of the front bogie, e.g. [1R, 2R]) are in addition
    twisted by h+ = g+ x 2a+ about the bogie centre, leading wheelset + h+/2, trailing - h+/2
    (``bogie_twist_per_mille``, default the EN 14363 limit for 2a+); see
    :func:`cosim.kinds.twist.rail_heights` for the track geometry. Without it: Fig. 7, the carbody twist
    alone.

    ``window_s``: final window over which the quasi-static end values are averaged (default 5 s,
    or the whole hold if that is shorter); ``settle_drift``: the case counts as settled when every
    wheel's ΔQ/Q0 drifts by less than that over the final window: its mean over the final window
    differs from its mean over the window before by less (an undamped ~1 Hz sway left in the
    window moves the mean by at most 4 b / (w W) of its amplitude b).
    ``valve_settings``: run with the levelling valves isolated (false) and/or connected (true);
    null: one run as ``circuit.valves`` says.
    """

    base_m: float = 10.0
    twist_per_mille: Optional[float] = None
    raised_wheels: Tuple[str, ...] = ("1R", "2R")
    ramp_s: float = 5.0
    hold_s: float = 35.0
    bogie_base_m: Optional[float] = None
    bogie_twist_per_mille: Optional[float] = None
    window_s: Optional[float] = None
    settle_drift: float = 1e-3
    valve_settings: Optional[Tuple[bool, ...]] = None

    @property
    def twist(self) -> float:
        if self.twist_per_mille is not None:
            return self.twist_per_mille / 1000.0
        return en14363_twist_limit(self.base_m)

    @property
    def height_m(self) -> float:
        return self.twist * self.base_m

    @property
    def bogie_twist(self) -> float:
        """g+ [-]: 0 without ``bogie_base_m``."""
        if self.bogie_base_m is None:
            return 0.0
        if self.bogie_twist_per_mille is not None:
            return self.bogie_twist_per_mille / 1000.0
        return en14363_twist_limit(self.bogie_base_m)

    @property
    def bogie_height_m(self) -> float:
        """h+ = g+ x 2a+ [m]: the height difference between the front bogie's wheelsets."""
        return self.bogie_twist * (self.bogie_base_m or 0.0)

    @property
    def duration_s(self) -> float:
        return self.ramp_s + self.hold_s

    @property
    def window(self) -> float:
        """The final averaging window [s]."""
        return self.window_s if self.window_s is not None else min(DEFAULT_WINDOW_S, self.hold_s)


#: default length of the final window the quasi-static end values are averaged over [s]
DEFAULT_WINDOW_S = 5.0
#: the track under the car when a scenario names none (``track:``; vehicle.params.TrackStructure)
DEFAULT_TRACK_MODEL = "rigid"
#: the parameters of a flexible track when a scenario names no preset
DEFAULT_TRACK_PRESET = "slab_track"
#: default spectral radius of the multibody integrator (:class:`SolverSettings`): the car's own
#: (vehicle.car.SPECTRAL_RADIUS; written here so that loading a scenario does not import exudyn)
DEFAULT_SPECTRAL_RADIUS = 0.5


def en14363_twist_limit(base_m: float) -> float:
    """Track twist [-] for a base 2a [m]: 7e-3 (2a <= 4 m), (20/2a + 2)e-3 (<= 20 m), 3e-3 above."""
    if base_m <= 4.0:
        return 7e-3
    if base_m <= 20.0:
        return (20.0 / base_m + 2.0) * 1e-3
    return 3e-3


@dataclass(frozen=True)
class SolverSettings:
    """Co-simulation settings (see cosim/master.py for the scheme). ``spectral_radius``: the
    multibody integrator's (generalized-alpha) spectral radius at infinite frequency, rho in
    [0, 1]: how much it damps what its step cannot resolve (1: nothing; 0: the most; the
    integrator stays second order for every rho). The wheelsets' modes on their contacts lie at
    ~250 Hz, far beyond a 5 ms step; see docs/models.md, "Numerical damping", for how the
    default was chosen."""

    macro_step_s: float = 0.005
    mechanics_step_s: float = 0.005
    pneumatic_step_s: float = 0.005
    coupling: str = "linearised"
    output_interval_s: float = 0.02
    jobs: int = 2
    spectral_radius: float = DEFAULT_SPECTRAL_RADIUS


@dataclass(frozen=True)
class StateLimits:
    """States no car can be in: a case whose state passes one of these stops at the end of that
    macro-step with a diagnosis (time, body or component, state) and the run exits 1, keeping
    what it computed (:mod:`cosim.limits.watch`). Each is far beyond what a running car reaches, so
    that it marks a capsized, derailed or crushed car, not a demanding one:

    * ``carbody_roll_rad``: the carbody rolled relative to the track plane by more than this
      (0.2 rad: the paper's car rolls 0.03 rad at 1 m/s^2 of unbalanced lateral acceleration;
      its bellows' plates touch at ~0.17 rad);
    * ``bogie_roll_rad``: a bogie frame rolled relative to the track plane by more (0.1 rad:
      40 mm of primary stroke over the 2 m axlebox spacing is 0.04 rad);
    * ``wheelset_lift_s``: both wheels of a wheelset off their rails (no contact force) for
      longer than this (0.1 s: 1 m of track at 10 m/s; a wheel unloaded by an impact lifts for
      milliseconds);
    * ``bellow_crushing_fraction``: an airspring (bellow and emergency spring) crushed or
      extended by more than this fraction of its height (1: its plates meet, or it has doubled
      its height);
    * ``bellow_volume_fraction``: a bellow crushed to less than this fraction of its nominal
      volume (0.05: its air compressed twentyfold or more, the bellow crushed flat);
    * ``T_min_K``, ``T_max_K``, ``p_min_Pa``, ``p_max_Pa``: air in a chamber colder or hotter,
      or at a lower or higher absolute pressure than this (150 K / 1000 K, 0.1 / 50 bar: air
      liquefies near 80 K; the ideal gas with constant heat capacities is no longer air far
      above 1000 K; the car's bellows carry ~4.2 bar).
    """

    carbody_roll_rad: float = 0.2
    bogie_roll_rad: float = 0.1
    wheelset_lift_s: float = 0.1
    bellow_crushing_fraction: float = 1.0
    bellow_volume_fraction: float = 0.05
    T_min_K: float = 150.0
    T_max_K: float = 1000.0
    p_min_Pa: float = 1.0e4
    p_max_Pa: float = 5.0e6


@dataclass(frozen=True)
class VerifySettings:
    """``pneumorail verify``: the run is repeated with every step halved ``levels`` times; it
    fails when a headline metric's estimated relative discretisation error (Richardson) at
    the scenario's own steps exceeds ``tolerance``."""

    tolerance: float = 0.005
    levels: int = 2


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
        (:func:`cosim.scenario.load._curve` resolves it)."""
        return _irregularity(self, float(track_length_m), float(start_m))


@functools.lru_cache(maxsize=8)
def _irregularity(spec: IrregularitySpec, track_length_m: float, start_m: float) -> TrackIrregularity:
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
    path relative to the scenario} (see IrregularitySpec in cosim/experiments.py)."""

    speed_m_per_s: float = 10.0
    straight_m: float = 20.0
    transition_m: float = 15.0
    transition_shape: str = "bloss"
    radius_m: float = 100.0
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


# ----------------------------------------------------------------------------------- circuits
@dataclass(frozen=True)
class RigCircuit:
    bellow: Bellow
    tank: Optional[Tank]
    pipe: Pipe
    p0_Pa: float

    def components(self, with_tank: bool = True) -> Dict[str, object]:
        return bellow_tank_components(self.bellow, self.tank if with_tank else None, self.pipe)

    def initial_pressures(self, components) -> Dict[str, float]:
        return {n: self.p0_Pa for n, c in components.items() if isinstance(c, (Bellow, Tank))}


@dataclass(frozen=True)
class CarCircuit:
    """The car's circuit: ``four_point`` (one levelling valve per bellow) or ``two_point``;
    ``valves`` false isolates every bellow (with its tank) from the supply and the other bellows."""

    layout: str
    bellow: Bellow
    tank: Optional[Tank]
    pipe: Pipe
    valves: bool
    levelling_valve: LevellingValve
    differential_valve: Optional[DifferentialPressureValve]
    supply: Supply
    cross_pipe: Optional[Pipe]
    explicit: Optional[Tuple[Tuple[str, object], ...]] = None

    def components(self) -> Dict[str, object]:
        if self.explicit is not None:
            return dict(self.explicit)
        return car_circuit(self.bellow, self.tank, self.pipe,
                           levelling=self.levelling_valve if self.valves else None,
                           differential=self.differential_valve if self.valves else None,
                           supply=self.supply, points=4 if self.layout == "four_point" else 2,
                           cross_pipe=self.cross_pipe)


# ----------------------------------------------------------------------------------- scenario
@dataclass(frozen=True)
class Scenario:
    """A validated scenario (built by :func:`cosim.scenario.load.load_scenario`): where it came from
    (file, content hash, overrides, every file read), its k values, and the typed sections of its
    kind -- ``rig`` and ``test`` for the rig kinds, ``vehicle``, ``track``, ``circuit``,
    ``twist`` or ``curve``, ``solver``, ``verify`` and ``checks`` for the car kinds."""

    file: Path
    kind: str
    name: str
    description: str
    k_W_per_K: Tuple[float, ...]
    content_sha256: str
    overrides: Tuple[str, ...] = ()
    #: (path relative to the scenario file, sha256) of every file read: the scenario, parameter files
    files_sha256: Tuple[Tuple[str, str], ...] = ()
    rig: Optional[RigCircuit] = None
    test: Any = None
    vehicle: Optional[VehicleParams] = None
    #: the track under the rails (car kinds): rigid or flexible
    track: TrackStructure = TrackStructure()
    circuit: Optional[CarCircuit] = None
    twist: Optional[TwistTest] = None
    curve: Optional[CurveTest] = None
    solver: SolverSettings = SolverSettings()
    verify: VerifySettings = VerifySettings()
    #: states that stop a case (car kinds: ``state_limits``)
    state_limits: StateLimits = StateLimits()
    checks: Tuple[Check, ...] = ()
    #: validity flags (:data:`cosim.limits.validity.FLAGS`) that ``check`` accepts instead of failing on
    allow: Tuple[str, ...] = ()
    raw: Dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    def with_valves(self, valves: bool) -> "Scenario":
        """The same car scenario with its levelling (and differential) valves connected (True) or
        isolated (False)."""
        return dataclasses.replace(self, circuit=dataclasses.replace(self.circuit, valves=valves))
