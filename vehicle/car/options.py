"""What a :class:`~vehicle.car.MetroCar` is asked for, in three groups: what is built
(:class:`ModelOptions`), how the car runs (:class:`RunSettings`) and how it is integrated
(:class:`SolverSettings`), held together by :class:`CarOptions`, which also reads them from
``MetroCar``'s keywords. Each field is documented at :class:`~vehicle.car.MetroCar`."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from ..params import SPECTRAL_RADIUS, ContactParams, TrackStructure
from ..payload import PayloadBlock
from ..speed import PhasedSpeedProfile
from ..track import TrackGeometry
from .wheel_drive import WheelDrive

#: Newton's relative tolerance with contact guidance. A step's initial residual is ~M a
#: there (~30 kN in the paper's curve) against ~700 kN with kinematic guidance, where the
#: guidance constraints dominate it, so 1e-8 asked the contact for ~3e-4 N, 20 times the
#: kinematic car's ~7e-3 N, and took 5.0 Newton iterations per step against 3.2. 1e-6
#: (~3e-2 N) takes 3.9 and moves the wheel loads and lateral forces of that curve by at most
#: 0.05 N (roll 7e-9 rad), against ~10 N between 5 and 2.5 ms steps (pneumorail verify).
CONTACT_NEWTON_REL_TOL = 1e-6


#: the ways the wheelsets can be held on the track (``guidance``)
GUIDANCES = ("kinematic", "contact")

#: what a car with contact guidance on straight track can have held (``held``), each by a joint
#: to the ground that moves with the car (:meth:`vehicle.car.build._Builder.hold`): name ->
#: ((body, constrained axes of x, y, z, roll, pitch, yaw), ...). "carbody": the Cooperrider
#: configuration of running-stability studies, a carbody that runs at constant speed with no
#: lateral, roll or yaw motion (vertical and pitch stay on the airsprings); "rear bogie": the
#: rear frame and its wheelsets without lateral and yaw motion (the frame also without roll), so
#: that only the front bogie runs free (with the carbody held the bogies do not meet in the
#: lateral plane); "bogie roll": both frames without roll (an experiment: what frame roll does)
HOLDS = {
    "carbody": (("carbody", (0, 1, 0, 1, 0, 1)),),
    "rear bogie": (("bogie 2", (0, 1, 0, 1, 0, 1)), ("wheelset 3", (0, 1, 0, 0, 0, 1)),
                   ("wheelset 4", (0, 1, 0, 0, 0, 1))),
    "bogie roll": (("bogie 1", (0, 0, 0, 1, 0, 0)), ("bogie 2", (0, 0, 0, 1, 0, 0))),
}


@dataclass(frozen=True)
class ModelOptions:
    """What is built: the guidance, its contact, the track structure, the optional carbody load,
    the wheelsets' initial lateral offsets, what is held (:data:`HOLDS`; straight track
    only) and how a contact car is moved (``drive``: None, a joint at its centre; a
    :class:`~.wheel_drive.WheelDrive`, torques on its wheelsets). ``track_structure`` None
    becomes the rigid :class:`~vehicle.params.TrackStructure`."""

    guidance: str = "kinematic"
    contact: ContactParams | None = None
    track_structure: TrackStructure | None = None
    carbody_load: bool = False
    wheelset_lateral_offset_m: Sequence[float] | None = None
    held: Sequence[str] = ()
    drive: WheelDrive | None = None

    def __post_init__(self):
        if self.guidance not in GUIDANCES:
            raise ValueError(f"guidance must be 'kinematic' or 'contact', got {self.guidance!r}")
        unknown = [h for h in self.held if h not in HOLDS]
        if unknown:
            raise ValueError(f"held: unknown {', '.join(map(repr, unknown))}; known: {', '.join(HOLDS)}")
        if self.held and not self.contact_guidance:
            raise ValueError("held needs guidance='contact' (the kinematic guidance holds the wheelsets already)")
        object.__setattr__(self, "held", tuple(self.held))
        if self.drive is not None:
            if not isinstance(self.drive, WheelDrive):
                raise ValueError(f"drive must be a vehicle.car.WheelDrive or None, got {type(self.drive).__name__}")
            if not self.contact_guidance:
                raise ValueError("drive (traction and braking through the wheels) needs guidance='contact': the "
                                 "kinematic guidance holds the wheelsets along the track")
        if self.track_structure is None:
            object.__setattr__(self, "track_structure", TrackStructure())

    @property
    def contact_guidance(self) -> bool:
        """The wheelsets run on the wheel-rail contact (``guidance="contact"``)."""
        return self.guidance == "contact"


@dataclass(frozen=True)
class RunSettings:
    """How the car runs: along which track, how fast, from where, what the rails under it
    do (prescribed heights, irregularities), what its floor carries (``payload``) and the line's
    gradient (``grade``)."""

    track: TrackGeometry | None = None
    speed_m_per_s: float = 0.0
    start_s_m: float | None = None
    deceleration: tuple[float, float] | None = None
    speed_profile: PhasedSpeedProfile | None = None
    rail_height_m: Callable[[float], np.ndarray] | None = None
    irregularity: Callable[[np.ndarray], tuple] | None = None
    payload: Callable[[float], Sequence[PayloadBlock]] | None = None
    grade: Callable[[float], float] | None = None

    def __post_init__(self):
        if self.grade is not None and not callable(self.grade):
            raise ValueError("grade must be callable: grade(s_m) -> rise over run at the car centre's arc length")
        if self.payload is not None and not callable(self.payload):
            raise ValueError("payload must be callable: payload(t_s) -> payload blocks (vehicle.payload.PayloadBlock)")
        if self.irregularity is not None and not callable(self.irregularity):
            raise ValueError("irregularity must be callable: irregularity(s_m) -> (lateral_m, "
                             "vertical_m, cross_level_m, gauge_m)")
        if not math.isfinite(self.speed_m_per_s):
            raise ValueError(f"speed_m_per_s must be finite, got {self.speed_m_per_s!r}")
        if self.speed_profile is not None:
            if self.deceleration is not None:
                raise ValueError("give a speed_profile or a deceleration, not both")
            if not isinstance(self.speed_profile, PhasedSpeedProfile):
                raise ValueError("speed_profile must be a vehicle.speed.PhasedSpeedProfile")
            if self.speed_m_per_s != self.speed_profile.v0_m_per_s:
                raise ValueError(f"speed_m_per_s ({self.speed_m_per_s!r}) must be the speed_profile's speed at t = 0 "
                                 f"({self.speed_profile.v0_m_per_s!r}): every body starts at it")


@dataclass(frozen=True)
class SolverSettings:
    """How the car is integrated: the largest internal step [s], the generalized-alpha spectral
    radius, Newton's tolerances (``newton_rel_tol`` None: chosen by the guidance) and the reuse of
    the Newton Jacobian."""

    step_s: float = 5e-3
    spectral_radius: float = SPECTRAL_RADIUS
    newton_abs_tol: float = 1e-4
    newton_rel_tol: float | None = None
    reuse_jacobian: bool = True

    def __post_init__(self):
        if not self.step_s > 0.0:
            raise ValueError(f"step_s must be > 0, got {self.step_s}")
        object.__setattr__(self, "step_s", float(self.step_s))

    def relative_tolerance(self, contact_guidance: bool) -> float:
        """Newton's relative tolerance: ``newton_rel_tol``, or for None 1e-8 with kinematic
        guidance, :data:`CONTACT_NEWTON_REL_TOL` with contact guidance."""
        if self.newton_rel_tol is not None:
            return self.newton_rel_tol
        return CONTACT_NEWTON_REL_TOL if contact_guidance else 1e-8


@dataclass(frozen=True)
class CarOptions:
    """Everything a car is built and run with besides its :class:`~vehicle.params.VehicleParams`."""

    model: ModelOptions = field(default_factory=ModelOptions)
    run: RunSettings = field(default_factory=RunSettings)
    solver: SolverSettings = field(default_factory=SolverSettings)

    @classmethod
    def given(cls, options: CarOptions | None, keywords: dict) -> CarOptions:
        """``options``, or for None the options from the ``keywords`` (:meth:`from_keywords`);
        TypeError when both are given."""
        if options is None:
            return cls.from_keywords(**keywords)
        if keywords:
            raise TypeError("MetroCar() takes its options either as keywords or as options=, not both")
        return options

    @classmethod
    def from_keywords(cls, **keywords) -> CarOptions:
        """The options from ``MetroCar``'s flat keywords, each the name of a field of one of the
        three groups (TypeError for any other, as for an unknown keyword of a function)."""
        groups = {}
        for name, group in (("model", ModelOptions), ("run", RunSettings), ("solver", SolverSettings)):
            names = [f.name for f in dataclasses.fields(group) if f.name in keywords]
            groups[name] = group(**{n: keywords.pop(n) for n in names})
        if keywords:
            raise TypeError(f"MetroCar() got unexpected keyword argument(s) {', '.join(map(repr, keywords))}")
        return cls(**groups)
