"""Exudyn multibody model of the metro car (paper section 4, Table 3), standing on prescribed rail
heights (twist test) or running at constant speed along a track (curve entry, paper section 4.2).

Bodies: carbody, two bogie frames, four wheelsets (rigid, 6 coordinates each, Tait-Bryan xyz).
Coordinates: x forward (running direction at the start), y to the left, z up; rail top at z = 0
on level track.

* Primary suspension: one spring-damper per axlebox (``RigidBodySpringDamper``), x/y/z stiffness
  and damping from :class:`VehicleParams`.
* Secondary suspension (airsprings), per bellow, one ``RigidBodySpringDamper`` in exudyn's
  intrinsic formulation between the lower plate (bogie frame) and the upper plate (carbody):
  the plate offset d is measured in the mid-frame between the two bodies and the force is
  applied at the midpoint of the plate centres on both bodies. Its symbolic user function gives
    - the axial force F(t, z) = F_n + dF/dt (t - t_n) + dF/dz (z - z_n) along the mid-frame's z
      axis (the bellow axis: the mean of the plates' normals; on canted track it follows the
      bodies), pushing the carbody up and the bogie down, with the crushing z = h0 - d_z;
    - shear stiffness across it (d_x, d_y).
  A point-to-point spring would add a negative lateral stiffness -F/L; this force does not turn
  with the plate offset, only with the bodies' mean roll (a lateral component F (phi_c +
  phi_b)/2 in a curve: the carbody leans on its bellows' axes).
* Lateral bumpstops, one per bogie: between bogie frame and carbody at the bogie centre, at the
  height of the lower bellow plate (where the carbody's centre pivot meets the stops on the bogie
  frame); lateral force k_bs (|d| - clearance) beyond the clearance, 0 inside it.
* Optional secondary components (:class:`VehicleParams`; each off by default, and then not built
  at all, so that a car without them is the same model, bit for bit):
    - anti-roll bar, one per bogie: an intrinsic ``RigidBodySpringDamper`` between bogie frame
      and carbody with a rotational stiffness about x only: a pure roll couple
      k_roll (phi_carbody - phi_frame), the x component of the relative rotation vector in the
      mid-frame (the SE(3) logarithm the intrinsic formulation uses), and nothing else (no
      bounce, pitch or yaw stiffness, no force, so no point of application to get wrong);
    - traction rod (or centre pivot), one per bogie: longitudinal spring-damper between bogie
      centre and carbody at ``traction_rod_height_m`` (intrinsic ``RigidBodySpringDamper``, x
      stiffness and damping only);
    - secondary dampers: vertical (two per bogie, at the bellow mid-height), lateral (one per
      bogie, at the bogie centre) and yaw (two per bogie, longitudinal, at +-half their
      spacing); each a (bi)linear damper in series with its mounting stiffness (a Maxwell
      element, see :meth:`MetroCar._add_damper`), or a plain damper on a rigid mounting;
    - emergency spring and vertical bumpstop, per bellow: the bellow and its internal stop in
      parallel, the pair in series with the emergency spring (see :meth:`MetroCar._add_airspring`
      and :func:`vehicle.suspension.airspring_series_force_N`); :meth:`bellow_crushing` stays
      the bellow's own crushing, the quantity the pneumatic force law is written in.
  The bellow's effective area as a function of its height belongs to the pneumatic bellow model
  (force = gauge pressure x effective area, volume): the vehicle side only receives the force
  law through :meth:`MetroCar.set_bellow_forces`.
* Wheel-rail contact, per wheel: unilateral Hertz law Q = max(0, C_H delta^1.5 + c d(delta)/dt),
  Q = 0 when delta <= 0, vertical only, acting at a point fixed on the (non-spinning) wheelset
  body below the wheel centre, against the rail height prescribed for that wheel: the track's
  cant (rails at -/+ (contact spacing / 2) sin(cant), left/right) plus the optional
  ``rail_height_m`` irregularity. Lateral wheel-rail forces (creep, flange) are not modelled:
  the guidance carries them. (Kinematic guidance; see "Contact guidance" below.)
* Wheelset guidance (:meth:`MetroCar._add_wheelset_guidance`): each wheelset runs along the
  track at constant speed v, at arc length s_i(t) = s0_i + v t. A ``GenericJoint`` to ground
  at rail level (the point midway between the wheelset's contacts), whose frame follows the
  track (heading psi(s_i), and the cant roll) through a symbolic offset user function set
  before every internal step, locks that point's longitudinal and lateral position, the
  wheelset's pitch (no spin: the wheelset body does not rotate about its axle) and its yaw: the
  axle stays normal to the track tangent (radial wheelsets). Vertical motion and roll about the
  tangent stay free, on the contact springs; a wheelset rolls about its rail-level point, as it
  does between two rails. ``track=None`` is an unbounded straight level track along x (speed 0:
  the stationary rig of the twist test). The centrifugal and gyroscopic loads arise from this
  prescribed motion alone; no force is added.
* Contact guidance (``guidance="contact"``, issue 11): the wheelsets are free laterally, in yaw
  and roll, held on the track by the wheel-rail contact forces alone; the vertical Hertz
  connectors are replaced by the contact law of :mod:`vehicle.wheelrail.contact_law` for all
  8 wheels (:class:`~vehicle.wheelrail.track_contact.WheelsetTrackContact`): Hertz normal force
  along the contact normal, Kalker's linear creep forces with Shen-Hedrick-Elkins saturation
  (mu = :class:`~vehicle.params.ContactParams` ``friction_coefficient``), from the rigid contact
  table of S1002 on UIC60 1:40 for the car's wheel radius, evaluated per wheel at its lateral
  position relative to its own rail. Each wheelset has a spin coordinate (a one-coordinate node
  with the spin inertia; the wheelset body does not rotate about its axle). The guidance joint
  keeps only the body's pitch: the wheelsets are free along the track too. The car is *driven
  at its centre* (:meth:`MetroCar._add_drive`: a joint holds the carbody's position along the
  track tangent at s_c(t) = s_c0 + v t; its reaction is the force that keeps the speed). Per
  internal step (PreStep) each wheelset gets its track frame at its own arc length, where it
  is (position, heading, cant, curvature from the
  :class:`~vehicle.guidance.TrackSampler`; the rail heights and cross-level roll that frame,
  lateral alignment and gauge move each rail).
  The law runs as one force user function for the whole car (one call per residual evaluation)
  with a finite-difference Jacobian user function, both compiled by numba
  (:mod:`vehicle.wheelrail.compiled`). Outputs:
  :meth:`MetroCar.lateral_wheel_forces_N`, :meth:`MetroCar.wheel_loads_N` (normal to the track
  plane), :meth:`MetroCar.wheelset_lateral_forces_N`,
  :meth:`MetroCar.wheelset_lateral_displacement_m`, :meth:`MetroCar.angle_of_attack_rad`,
  :meth:`MetroCar.flange_contact`, :meth:`MetroCar.contact_state`. Static start: each wheelset
  at the height where the contact carries the static wheel load (no settling transient).
  Standstill: creepages are divided by max(v, ``min_creep_speed_m_per_s`` = 0.01 m/s).
  Cost (benchmarks/bench_vehicle_curve.py --contact): 1.57 times the kinematic car on the
  paper's curve entry (docs/wheel_rail.md, "Cost").

Newton's third law in the strong form (moment balance). A force pair between body-fixed points
that separate is not collinear and leaves a couple d x f: the bellow pair (F = 42 kN over the
37 mm lateral bellow deflection of the paper's curve) and the shear (4.2 kN over the 0.25 m
bellow height) left 5.9 kNm per bogie, 31 % of the 37.7 kNm by which the wheel loads must
balance the overturning moment (measured before this was fixed). Hence:

* all ``RigidBodySpringDamper`` connectors (primary, airsprings, bumpstops) use exudyn's
  intrinsic formulation: axes of the mid-frame between the two bodies, force applied at the
  midpoint of the two markers on both bodies;
* the guidance joint reacts at rail level, where the rails apply the lateral force.

Both hold at every instant, from the current state (an earlier version added the bellow end
moments and the rail couples as torque loads computed at the start of each internal step, one
step late). tests/test_vehicle_curve.py checks the wheel load transfer in the curve against the
overturning moment.

Static equilibrium on level track under :meth:`MetroCar.static_bellow_forces_N` is the *reference
configuration*: bodies sit at their static positions, the primary springs carry their static load
through their offsets and each contact point penetrates its rail by the Hertz deflection; with a
speed, every body starts at it along x on the initial straight, so a run starts without settling
transient.

Force laws are exudyn *symbolic* user functions: they run in C++ (a Python user function costs
~1.5 us per call and the numerical Jacobian calls it 13 times per connector); their inputs (rail
height/rate, bellow force law, guidance offsets) are named symbolic variables set from
Python. The track is evaluated through :class:`~vehicle.guidance.TrackSampler` (~10 us per step).

Solver: implicit generalized-alpha, driven macro-step by macro-step with
``MainSolverImplicitSecondOrder.SolveSteps`` (no restart: state-exact continuation). SolveSteps
asks for a new Newton Jacobian at every call; a Jacobian user function serves that request with
the previous Jacobian when the step size is unchanged (the bellow stiffness is ~1e-4 of the
effective mass stiffness M/(beta h^2), so it never matters) and the track heading has turned by
less than :attr:`MetroCar.JACOBIAN_HEADING_TOL_RAD` since it was computed (the guidance
directions and the Rxyz mass matrix follow the heading), and computes a fresh one, with a second
solver object on the same system, otherwise and whenever Newton itself asks (e.g. a wheel lifts).
With contact guidance the heading-triggered one is computed at the end of the macro-step that
turned past the tolerance, at its converged state, rather than at the next step's predictor
(see ``MetroCar._refresh_jacobian``).
When the stored Jacobian is kept, the pre-step function withdraws SolveSteps' request
(``solver.conv.jacobianUpdateRequested``) so that exudyn does not factorise the unchanged matrix
again: Newton uses the factorisation it holds (the same LU, bit for bit; ~10 % of a step).

Known limits of the running model (see also :class:`MetroCar`); all but the third concern
kinematic guidance only:

* radial wheelsets: the yaw of every wheelset is prescribed to the track heading, so in a curve
  the two wheelsets of a bogie are 2 a / R apart in yaw (0.02 rad at R = 100 m) and the stiff
  primary (k_x = 17.5 MN/m) takes ~175 kN per axlebox and ~350 kNm per wheelset of internal yaw
  moment, which real, creep-steered wheelsets would not see. These longitudinal forces barely
  touch roll and vertical loads (the steady roll at R = 1000 m, 31.6 m/s, the same 1 m/s^2,
  differs by 0.02 %), but they are not physical;
* on canted track the contact forces stay vertical and the guidance takes the in-plane lateral
  force at rail level: Q is the vertical load, not the load normal to the track plane;
* no lateral damping by default (the paper's car has no hydraulic dampers): the carbody
  sway/roll mode at ~1 Hz, excited by the transition, decays only through the primary vertical
  dampers and the pneumatics (secondary dampers: see the optional components above);
* the guidance prescribes every wheelset's arc length, so in a curve the bogie centres sit a
  chord apart, shorter than the carbody's 10 m by 10^3 / (24 R^2) (4.2 mm at R = 100 m): stiff
  traction rods take it as an internal longitudinal force (measured 11.4 kN per 10 MN/m rod at
  R = 100 m, wheel loads shifted by up to 0.4 kN, roll unchanged), which real wheelsets,
  free to roll forward, would not see. It falls with 1/R^2 (0.1 kN at R = 1000 m). On canted
  track the wheelset centres run on a radius smaller by r0 sin(cant) than the rail-level line
  whose arc lengths are prescribed, and the primary suspensions carry the difference too
  (+-15 kN between the wheelsets of a bogie at balanced cant on R = 100 m). Contact guidance
  has neither: its wheelsets are free along the track (:meth:`MetroCar._add_drive`).
"""
from __future__ import annotations

import functools
import math
from typing import Callable

import exudyn as exu
import numpy as np
from exudyn.advancedUtilities import CreateSymbolicUserFunction
from exudyn.rigidBodyUtilities import RigidBodyInertia

from .errors import Derailed  # noqa: F401 (re-exported)
from .guidance import shared_sampler
from .params import BELLOWS, WHEELS, ContactParams, TrackStructure, VehicleParams  # noqa: F401 (re-exported)
from .suspension import (airspring_series_bellow_crushing, airspring_series_force_N,
                         arb_roll_stiffness_N_m_per_rad, bilinear_damper_force_N, maxwell_force_N,
                         maxwell_step)
from .track import TrackGeometry
from .wheelrail.contact_law import ContactLawTable, WheelsetParams
from .wheelrail.geometry import ContactTable, table_path
from .wheelrail.track_contact import WheelContactOutputs, WheelsetTrackContact


#: default spectral radius of the implicit integrator (generalized-alpha) at infinite frequency.
#: A linear cant ramp steps the rails' roll rate and rings each wheelset's ~240 Hz roll on its
#: contacts (omega h ~ 7.5 at 5 ms): with 0.8 those impacts were integrated unstably on canted
#: track (balanced and excess cant on the paper's curve diverged, kinematic and contact
#: guidance); 0.5 damps them within a few steps and runs every case of the cant x speed x radius
#: x transition matrix (benchmarks/track_matrix.py), while the converged results of the
#: paper's scenarios move by less than their own discretisation error (docs/models.md,
#: "Numerical damping").
SPECTRAL_RADIUS = 0.5

#: exudyn minor version this module was written and measured against (the API changes between
#: minor versions; tests/test_vehicle.py fails loudly on any other)
EXUDYN_TESTED_MINOR = "1.13"

_OUT = exu.OutputVariableType
esym = exu.symbolic


class _SymbolicOps:
    """The operations of the :mod:`vehicle.suspension` force laws, on exudyn symbolic
    expressions (the laws then compile into the connectors' C++ user functions)."""

    @staticmethod
    def where(condition, if_true, if_false):
        real = esym.Real
        return esym.IfThenElse(condition, *(v if isinstance(v, real) else real(float(v))
                                            for v in (if_true, if_false)))

    abs = staticmethod(esym.abs)
    sign = staticmethod(esym.sign)
    max = staticmethod(esym.max)
    min = staticmethod(esym.min)


_SYMBOLIC_OPS = _SymbolicOps()


class _Damper:
    """One secondary damper: its connector, law and (Maxwell element) internal state."""

    def __init__(self, name: str, axis: int, c1: float, c2: float, v_b: float, k_s: float):
        self.name, self.axis = name, axis
        self.c1, self.c2, self.v_b, self.k_s = c1, c2, v_b, k_s
        self.maxwell = math.isfinite(k_s)
        self.connector = None
        # Maxwell state at the start of the current step: damper elongation y [m] and rate
        # [m/s] (Python values and the symbolic variables the force law reads), force [N]
        self.y = self.ydot = self.force = 0.0
        self.y_sym = self.ydot_sym = None


def _check_components(p: VehicleParams) -> None:
    """ValueError naming the field when an optional component's parameters are inconsistent."""
    nonnegative = ("arb_roll_stiffness_N_m_per_rad", "arb_torsion_stiffness_N_m_per_rad",
                   "traction_rod_stiffness_N_per_m", "traction_rod_damping_N_s_per_m",
                   "vertical_bumpstop_clearance_m", "vertical_bumpstop_stiffness_N_per_m")
    for kind in ("secondary_vertical", "secondary_lateral", "yaw"):
        nonnegative += (f"{kind}_damping_N_s_per_m", f"{kind}_damper_blowoff_damping_N_s_per_m")
    positive = ("emergency_spring_stiffness_N_per_m",) + tuple(
        f"{kind}_damper_{what}" for kind in ("secondary_vertical", "secondary_lateral", "yaw")
        for what in ("series_stiffness_N_per_m", "blowoff_velocity_m_per_s"))
    for name in nonnegative:
        value = getattr(p, name)
        if not (value >= 0.0 and math.isfinite(value)):
            raise ValueError(f"{name} must be finite and >= 0, got {value}")
    for name in positive:
        value = getattr(p, name)
        if not value > 0.0:
            raise ValueError(f"{name} must be > 0 (inf: rigid / linear), got {value}")
    if p.arb_roll_stiffness_N_m_per_rad > 0.0 and p.arb_torsion_stiffness_N_m_per_rad > 0.0:
        raise ValueError("give the anti-roll bar either as arb_roll_stiffness_N_m_per_rad or as "
                         "arb_torsion_stiffness_N_m_per_rad with its lever and link geometry, "
                         "not both")
    arb_roll_stiffness_N_m_per_rad(p.arb_torsion_stiffness_N_m_per_rad, p.arb_lever_arm_m,
                                   p.arb_link_spacing_m)  # raises on a bad geometry


@functools.lru_cache(maxsize=8)
def _contact_table(table_csv: str, wheel_radius_m: float) -> ContactTable:
    """The contact table of :class:`ContactParams` ``table_csv``, or for an empty one the S1002 /
    UIC60 1:40 / 1435 mm table for the wheel radius: shipped, else derived (~2 s, cached)."""
    if table_csv:
        return ContactTable.from_csv(table_csv)
    path = table_path(wheel_radius_m)
    if path.exists():
        return ContactTable.from_csv(path)
    from .wheelrail.derive_table import derive_default
    return derive_default(wheel_radius_m)


def _four_floats(values) -> list[float]:
    """(4,) values as a list of floats; None = zeros."""
    return [0.0] * 4 if values is None else np.asarray(values, dtype=float).reshape(4).tolist()


class MetroCar:
    """Metro car on rails whose heights are prescribed wheel by wheel, standing or running.

    Args:
        params: vehicle parameters (SI).
        rail_height_m: ``rail_height_m(t_s) -> (8,)`` vertical rail height [m] under each wheel
            in :data:`WHEELS` order, 0 = level; ``None`` = level track. Evaluated at the end of
            every internal time step (kinematic guidance: the contact damping uses the mean rail
            rate over the step; contact guidance: the rate at the step end, from evaluations
            1 us either side of it, so also at t = -1 us). It should be 0 at t = 0 for a
            transient-free start. On a canted ``track`` it
            adds to the heights the cant gives.
        step_s: largest internal time step [s]; every :meth:`advance` is split into equal steps
            not larger than this.
        track: centre line the car runs along; ``None`` = unbounded straight level track along
            x. It must be straight and level under the whole car at the start (the start state
            is the static equilibrium on level track).
        speed_m_per_s: constant running speed v [m/s] (0 = standing); every body starts at v.
        start_s_m: arc length [m] of the car centre (midway between the bogie centres) at
            t = 0. Default: the rear wheelset at s = 0 on a ``track``, 0 without one.
        spectral_radius: generalized-alpha spectral radius at infinite frequency, 0 <= rho <= 1
            (numerical damping of what the step cannot resolve, e.g. the ~240 Hz
            wheelset-on-contact modes; :data:`SPECTRAL_RADIUS`).
        newton_abs_tol: Newton absolute tolerance on the residual (force scale [N]).
        newton_rel_tol: Newton tolerance relative to the initial residual of the step; None:
            1e-8 with kinematic guidance, :attr:`CONTACT_NEWTON_REL_TOL` with contact guidance.
        reuse_jacobian: reuse the Newton Jacobian across :meth:`advance` calls (see module doc).
        carbody_load: build an external force and torque on the carbody, set with
            :meth:`set_carbody_load` (zero until then); e.g. a static roll moment or wind.
        guidance: how the wheelsets are held on the track (see the module doc):
            ``"kinematic"`` (default): a joint prescribes each wheelset's position along and
            across the track and its yaw; vertical Hertz contacts, no lateral wheel-rail forces.
            ``"contact"``: the wheelsets are free laterally and in yaw, held on the track by the
            wheel-rail contact forces alone (contact table, Hertz normal force along the
            contact normal, Kalker + Shen-Hedrick-Elkins creep forces; each wheelset's spin is a
            state). The car keeps its speed by **driving the wheelsets**: a joint prescribes
            each wheelset's position *along* the track, s_i(t) = s0_i + v t (and holds the
            pitch of the non-rotating wheelset body); its reaction is the longitudinal force
            that keeps the speed (the rolling resistance of the creep forces, curving), at rail
            level. Needs ``speed_m_per_s >= 0``.
        contact: parameters of the contact guidance (:class:`~vehicle.params.ContactParams`;
            None = defaults); ignored with kinematic guidance.
        irregularity: track irregularities, ``irregularity(s_m: np.ndarray) -> (lateral_m,
            vertical_m, cross_level_m, gauge_m)`` (arrays shaped like s, metres; e.g. a
            :class:`vehicle.irregularities.TrackIrregularity`) at the wheelsets' arc lengths
            s_i(t), evaluated at the end of every internal step. Signs as there: lateral and
            vertical displace the track centre line (+ left, + up), cross-level is z_R - z_L,
            gauge + wider; each rail moves by y_L,R = lateral +- gauge/2, z_L,R = vertical -+
            cross_level/2. With contact guidance every wheel sees its own rail's offsets (and
            their rates). With kinematic guidance the heights add to ``rail_height_m`` and a
            running car's guidance follows the lateral alignment; gauge has no effect there.
            Should be 0 under the car at t = 0 (static start). None = design track.
        wheelset_lateral_offset_m: contact guidance only: (4,) initial lateral displacements
            [m] of the wheelsets (+ left), e.g. to release them on straight track; each starts
            at the rigid-contact height and roll of the table at that displacement (with the
            static Hertz approach), at rest laterally, the rest of the car at its static
            position. None = centred (the static equilibrium).
    """

    #: the stored Newton Jacobian is renewed at the next macro-step once the track heading has
    #: changed by more than this since it was computed [rad] (see :meth:`advance`; with contact
    #: guidance at the end of the macro-step that turned past it, see :meth:`_refresh_jacobian`)
    JACOBIAN_HEADING_TOL_RAD = 0.01
    #: Newton's relative tolerance with contact guidance. A step's initial residual is ~M a
    #: there (~30 kN in the paper's curve) against ~700 kN with kinematic guidance, where the
    #: guidance constraints dominate it, so 1e-8 asked the contact for ~3e-4 N, 20 times the
    #: kinematic car's ~7e-3 N, and took 5.0 Newton iterations per step against 3.2. 1e-6
    #: (~3e-2 N) takes 3.9 and moves the wheel loads and lateral forces of that curve by at most
    #: 0.05 N (roll 7e-9 rad), against ~10 N between 5 and 2.5 ms steps (pneumorail verify).
    CONTACT_NEWTON_REL_TOL = 1e-6

    def __init__(self, params: VehicleParams,
                 rail_height_m: Callable[[float], np.ndarray] | None = None,
                 step_s: float = 5e-3, *, track: TrackGeometry | None = None,
                 speed_m_per_s: float = 0.0, start_s_m: float | None = None,
                 spectral_radius: float = SPECTRAL_RADIUS,
                 newton_abs_tol: float = 1e-4, newton_rel_tol: float | None = None,
                 reuse_jacobian: bool = True, carbody_load: bool = False,
                 guidance: str = "kinematic", contact: ContactParams | None = None,
                 irregularity: Callable[[np.ndarray], tuple] | None = None,
                 wheelset_lateral_offset_m=None, track_structure: TrackStructure | None = None):
        if guidance not in ("kinematic", "contact"):
            raise ValueError(f"guidance must be 'kinematic' or 'contact', got {guidance!r}")
        if irregularity is not None and not callable(irregularity):
            raise ValueError("irregularity must be callable: irregularity(s_m) -> (lateral_m, "
                             "vertical_m, cross_level_m, gauge_m)")
        #: "kinematic" or "contact" (see the class doc)
        self.guidance = guidance
        self._contact_mode = guidance == "contact"
        self._irr = irregularity
        if not step_s > 0.0:
            raise ValueError(f"step_s must be > 0, got {step_s}")
        if not math.isfinite(speed_m_per_s):
            raise ValueError(f"speed_m_per_s must be finite, got {speed_m_per_s!r}")
        self.params = params
        #: the track under the rails (:class:`~vehicle.params.TrackStructure`; rigid by default)
        self.track_structure = track_structure or TrackStructure()
        self._flexible = self.track_structure.flexible
        self.step_s = float(step_s)
        self._rail_fn = rail_height_m
        p = params
        g = p.gravity_m_per_s2
        # --- static loads on level track (the car is symmetric) ---
        self._F_static_N = p.carbody_mass_kg * g / 4.0
        self._P_axlebox_N = (p.carbody_mass_kg * g / 2.0 + p.bogie_mass_kg * g) / 4.0
        #: static vertical wheel load on level track [N]
        self.Q_static_N = self._P_axlebox_N + p.wheelset_mass_kg * g / 2.0
        self._delta_static_m = (self.Q_static_N / p.hertz_constant_N_per_m1_5) ** (2.0 / 3.0)
        # --- geometry at static equilibrium ---
        a = p.wheelbase_m / 2.0
        xb = p.bogie_centre_distance_m / 2.0
        #: bogie centre x [m], front then rear
        self.bogie_x_m = np.array([xb, -xb])
        #: wheelset centre x [m], wheelsets 1..4 from the front
        self.wheelset_x_m = np.array([xb + a, xb - a, -xb + a, -xb - a])
        self._z_wheelset_m = p.wheel_radius_m - self._delta_static_m
        self._bellow_height_m = p.airspring_upper_height_m - p.airspring_lower_height_m
        if self._bellow_height_m <= 0.0:
            raise ValueError("airspring_upper_height_m must exceed airspring_lower_height_m")
        _check_components(p)
        #: the airsprings include an emergency spring and/or a vertical bumpstop
        self.airspring_in_series = (math.isfinite(p.emergency_spring_stiffness_N_per_m)
                                    or p.vertical_bumpstop_stiffness_N_per_m > 0.0)
        self._carbody_load = carbody_load
        self._init_run(track, float(speed_m_per_s), start_s_m)
        if self._contact_mode:
            self._init_contact(contact or ContactParams())

        rail0 = self._rail_at(0.0)
        self._rail_cache = (0.0, rail0)  # (t, heights) of the last preStep evaluation
        self._rail_set = None  # (heights, rates) last given to the contacts' symbolic variables

        self.SC = exu.SystemContainer()
        self.mbs = self.SC.AddSystem()
        self._build(rail0)
        if wheelset_lateral_offset_m is not None:
            self._offset_wheelsets(wheelset_lateral_offset_m)
        self.mbs.Assemble()
        if self._contact_mode:
            self._init_contact_state()
        if newton_rel_tol is None:
            newton_rel_tol = self.CONTACT_NEWTON_REL_TOL if self._contact_mode else 1e-8
        self._init_solver(spectral_radius, newton_abs_tol, newton_rel_tol, reuse_jacobian)
        if self._maxwell:
            self._maxwell_t = 0.0  # time of the Maxwell states (last accepted step end)
            self.mbs.SetPostStepUserFunction(self._post_step)

        self._bellow_t = None  # time of the cached bellow crushing

    # ================================================================== run
    def _init_run(self, track: TrackGeometry | None, v: float, start_s: float | None) -> None:
        """Arc lengths at t = 0 and the track sampler; checks the straight, level start."""
        self.track = track
        #: running speed [m/s]
        self.speed_m_per_s = v
        if start_s is None:
            start_s = float(-self.wheelset_x_m[-1]) if track is not None else 0.0
        start_s = float(start_s)
        if not math.isfinite(start_s):
            raise ValueError(f"start_s_m must be finite, got {start_s!r}")
        #: arc length [m] of the car centre at t = 0
        self.start_s_m = start_s
        self._s0_wheelset = start_s + self.wheelset_x_m  # (4,) arc lengths at t = 0
        # contact guidance: each wheelset's offset along the track from s0 + v t [m] (the
        # wheelsets are free longitudinally; their track frames follow them, see _pre_step_contact)
        self._ds_wheelset = np.zeros(4)
        self._x0_m = start_s  # x of the car centre at t = 0 (the track starts at the origin)
        self._sampler = None
        self._canted = False
        if track is None:
            self._guided = v != 0.0
            return
        if not isinstance(track, TrackGeometry):
            raise ValueError(f"track must be a TrackGeometry or None, got {type(track).__name__}")
        s = self._s0_wheelset
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
        self._sampler = shared_sampler(track)
        self._guided = True
        self._canted = any(getattr(seg, "cant_rad", 0.0) != 0.0 for seg in track.segments)

    def _init_contact(self, cp: ContactParams) -> None:
        """Contact guidance: the contact law for the car's wheelsets and the static wheelset
        height on the contacts (the reference configuration, see the module doc)."""
        p = self.params
        if self.speed_m_per_s < 0.0:
            raise ValueError("guidance='contact' needs speed_m_per_s >= 0 (the creep law's "
                             f"rolling direction), got {self.speed_m_per_s}")
        g = p.gravity_m_per_s2
        #: contact parameters (guidance="contact")
        self.contact_params = cp
        #: the contact table in use (guidance="contact")
        self.contact_table = _contact_table(cp.table_csv, float(p.wheel_radius_m))
        wp = WheelsetParams(
            mass_kg=p.wheelset_mass_kg, roll_inertia_kg_m2=p.wheelset_inertia_xx_kg_m2,
            spin_inertia_kg_m2=p.wheelset_inertia_yy_kg_m2,
            yaw_inertia_kg_m2=p.wheelset_inertia_zz_kg_m2, axle_load_N=2.0 * self._P_axlebox_N,
            gravity_m_per_s2=g, hertz_constant_N_per_m1_5=p.hertz_constant_N_per_m1_5,
            contact_damping_N_s_per_m=cp.normal_damping_N_s_per_m,
            friction_coefficient=cp.friction_coefficient)
        law = ContactLawTable(self.contact_table, wp, smoothing_mm=cp.table_smoothing_mm)
        r0 = self.contact_table.r0

        def contact_model(z_centre):
            refs = [[float(x) + self._x0_m, 0.0, z_centre] for x in self.wheelset_x_m]
            return WheelsetTrackContact(law, wp, refs, r0, self.speed_m_per_s,
                                        cp.min_creep_speed_m_per_s, cp.flange_angle_rad,
                                        2.0 * self.Q_static_N if self._flexible else None)

        # the wheelset centre sits r0 above the rail plane in the rigid centred contact and
        # approaches it by the Hertz deflection under the static wheel load
        rise = contact_model(r0).static_rise_m(self.Q_static_N)
        self._z_wheelset_m = r0 + rise
        self._wr = contact_model(self._z_wheelset_m)
        self._wr_left_table = None  # (t, wheelset lateral positions) when a wheelset left it
        self._wr_cache = (None, None)  # (key, WheelContactOutputs)
        self._advances = 0

    @property
    def s_m(self) -> float:
        """Arc length [m] of the car centre at the current time: start_s_m + v t."""
        return self.start_s_m + self.speed_m_per_s * self._t

    @property
    def t_end_max_s(self) -> float:
        """Latest time [s] the front wheelset is still on the track (inf without a track)."""
        v = self.speed_m_per_s
        if self.track is None or v == 0.0:
            return math.inf
        if v > 0.0:
            return (self.track.total_length_m - self._s0_wheelset[0]) / v
        return -self._s0_wheelset[-1] / v

    def _wheelset_s_m(self, t) -> np.ndarray:
        """Arc lengths [m] of the wheelsets at time(s) t: s0 + v t, plus each wheelset's own
        offset along the track with contact guidance (shaped like s0 + v t)."""
        return self._s0_wheelset + self.speed_m_per_s * t + self._ds_wheelset

    def _track_at(self, t: float) -> list[tuple[float, ...]]:
        """Track centre line (x, y, heading, cant, curvature, d(cant)/ds) under each wheelset
        at time t: 4 tuples (with contact guidance a fifth: under the car centre, where the
        drive holds the carbody)."""
        s = self._wheelset_s_m(t).tolist()
        if self._contact_mode:
            s.append(self.start_s_m + self.speed_m_per_s * t)
        if self._sampler is None:
            return [(si, 0.0, 0.0, 0.0, 0.0, 0.0) for si in s]
        return self._sampler.at(s)

    # ================================================================== model
    def _build(self, rail0: np.ndarray) -> None:
        p, mbs = self.params, self.mbs
        gravity = [0.0, 0.0, -p.gravity_m_per_s2]

        def body(m, ixx, iyy, izz, pos):
            return mbs.CreateRigidBody(
                inertia=RigidBodyInertia(mass=m, inertiaTensor=np.diag([ixx, iyy, izz]),
                                         inertiaTensorAtCOM=True),
                referencePosition=[pos[0] + self._x0_m, pos[1], pos[2]],
                initialVelocity=[self.speed_m_per_s, 0.0, 0.0], gravity=gravity,
                nodeType=exu.NodeType.RotationRxyz)

        self._ground = mbs.CreateGround()
        self._carbody = body(p.carbody_mass_kg, p.carbody_inertia_xx_kg_m2,
                             p.carbody_inertia_yy_kg_m2, p.carbody_inertia_zz_kg_m2,
                             [0.0, 0.0, p.carbody_cog_height_m])
        self._bogies = [body(p.bogie_mass_kg, p.bogie_inertia_xx_kg_m2, p.bogie_inertia_yy_kg_m2,
                             p.bogie_inertia_zz_kg_m2, [x, 0.0, p.bogie_cog_height_m])
                        for x in self.bogie_x_m]
        self._wheelsets = [body(p.wheelset_mass_kg, p.wheelset_inertia_xx_kg_m2,
                                p.wheelset_inertia_yy_kg_m2, p.wheelset_inertia_zz_kg_m2,
                                [x, 0.0, self._z_wheelset_m])
                           for x in self.wheelset_x_m]
        self._sym = []  # symbolic variables and functions: must live as long as the system
        for iw in range(4):
            self._add_wheelset_guidance(iw)
            self._add_primary(iw)
        if self._contact_mode and self._guided:
            self._add_drive()
        for k in range(4):
            self._add_airspring(k)
        for ib in range(2):
            self._add_bumpstop(ib)
        if self._contact_mode:
            self._add_wheel_rail_contact()
        else:
            self._track_bodies = [self._add_track_body(iw) for iw in range(4)] \
                if self._flexible else None
            for j in range(8):
                self._add_contact(j, rail0[j])
        # optional components (nothing is built when they are off: the same model, bit for bit)
        self._arbs, self._traction_rods, self._dampers = [], [], []
        k_arb = p.arb_roll_stiffness_N_m_per_rad + arb_roll_stiffness_N_m_per_rad(
            p.arb_torsion_stiffness_N_m_per_rad, p.arb_lever_arm_m, p.arb_link_spacing_m)
        for ib in range(2):
            if k_arb > 0.0:
                self._add_anti_roll_bar(ib, k_arb)
            if p.traction_rod_stiffness_N_per_m > 0.0 or p.traction_rod_damping_N_s_per_m > 0.0:
                self._add_traction_rod(ib)
            self._add_dampers(ib)
        self._maxwell = [d for d in self._dampers if d.maxwell]
        if self._maxwell:
            self._h_step = esym.Real("h_step", self.step_s)  # internal step size [s]
            self._sym.append(self._h_step)
            for d in self._maxwell:
                self._set_maxwell_function(d)
        if self._carbody_load:
            self._load_force = mbs.CreateForce(itemNumber=self._carbody, show=False)
            self._load_torque = mbs.CreateTorque(itemNumber=self._carbody, show=False)

    def _add_wheelset_guidance(self, iw: int) -> None:
        """Track guidance of wheelset ``iw`` (see module doc).

        ``GenericJoint`` between ground and the wheelset at rail level: both markers at the
        point midway between the wheel-rail contacts, on the track centre line, at t = 0 (p0).
        The joint frame is ground's rotated by the offset rotation A = Rz(psi) Rx(-cant) (track
        heading, and the roll of the canted track plane; given to exudyn as Tait-Bryan xyz
        angles); in that frame the constraints read
            t . (p - p0) = xi(t),  l . (p - p0) = eta(t)  (t: tangent, l: lateral in the plane)
            t . e_y = 0,  t . e_z = 0  (e_y axle, e_z: wheelset axes),
        with p the wheelset's rail-level point and (xi, eta) the position, relative to p0 in
        that frame, of the track centre line. Motion along the track plane's normal and roll
        about t stay free. The joint's lateral reaction acts where the rails apply it, at rail
        level, at every instant: no couple needs adding.

        Contact guidance locks only the pitch, t . e_z = 0 (the wheelset body does not spin; its
        rotation about the axle is a separate coordinate): the position along the track, lateral
        motion, yaw and roll are left to the primary suspension and the wheel-rail contact
        forces (the car is driven at its centre, :meth:`_add_drive`)."""
        mbs = self.mbs
        xi = esym.Real(f"xi{iw}", 0.0)  # [m]
        eta = esym.Real(f"eta{iw}", 0.0)  # [m]
        rx = esym.Real(f"rx{iw}", 0.0)  # Tait-Bryan angles of Rz(psi) Rx(-cant) [rad]
        ry = esym.Real(f"ry{iw}", 0.0)
        rz = esym.Real(f"rz{iw}", 0.0)
        zero = esym.Real(0.0)

        def offset(mbs, t, itemNumber, offsetUserFunctionParameters):
            return [xi, eta, zero, rx, ry, rz]

        pos = [float(self.wheelset_x_m[iw]) + self._x0_m, 0.0, 0.0]
        # contact guidance: only the pitch stays prescribed (the body does not spin)
        axes = [0, 0, 0, 0, 1, 0] if self._contact_mode else [1, 1, 0, 0, 1, 1]
        joint = mbs.CreateGenericJoint(itemNumbers=[self._ground, self._wheelsets[iw]],
                                       position=pos, constrainedAxes=axes, show=False)
        if self._guided:
            fn = CreateSymbolicUserFunction(mbs, offset, "offsetUserFunction", joint)
            mbs.SetObjectParameter(joint, "offsetUserFunction", fn)
            self._sym += [fn, zero]
        if iw == 0:
            self._guidance_vars = []
        self._guidance_vars.append((xi, eta, rx, ry, rz))

    def _add_drive(self) -> None:
        """Contact guidance: the car is driven at its centre. A ``GenericJoint`` between ground
        and the carbody's centre of gravity locks only its position along the track tangent at
        the car centre's arc length s_c(t) = start_s + v t, t . (p - p0) = xi_c(t) (the joint
        frame turns with the heading there, through a symbolic offset user function like the
        wheelsets' guidance): the carbody is free laterally, vertically and in every rotation,
        and the wheelsets, each held only in pitch, roll along behind it on their creep forces,
        where the bogie frames and the primary suspension put them. Its reaction is the force
        along the track that keeps the speed (the curving resistance of the creep forces),
        along the tangent at the car centre: no force across the track.

        (Driving each wheelset at its own s_i(t) = s0_i + v t, as an earlier version did,
        over-constrains the car: on canted track the wheelset centres run on a radius smaller by
        r0 sin(cant) than the rail-level line whose arc lengths were prescribed, so the two
        wheelsets of a bogie were held ~0.9 mm too far apart on R = 100 m at balanced cant; the
        primary suspensions carried +-15 kN between them, and those forces, along tangents up to
        0.06 rad apart, took ~3 % of M g sin(cant) of the lateral load off the rails.)"""
        mbs, p = self.mbs, self.params
        xi = esym.Real("xi_drive", 0.0)  # [m]
        rz = esym.Real("rz_drive", 0.0)  # heading at the car centre [rad]
        zero = esym.Real(0.0)

        def offset(mbs, t, itemNumber, offsetUserFunctionParameters):
            return [xi, zero, zero, zero, zero, rz]

        joint = mbs.CreateGenericJoint(itemNumbers=[self._ground, self._carbody],
                                       position=[self._x0_m, 0.0, p.carbody_cog_height_m],
                                       constrainedAxes=[1, 0, 0, 0, 0, 0], show=False)
        fn = CreateSymbolicUserFunction(mbs, offset, "offsetUserFunction", joint)
        mbs.SetObjectParameter(joint, "offsetUserFunction", fn)
        self._sym += [fn, zero]
        self._drive = joint
        self._drive_vars = (xi, rz)

    def _add_primary(self, iw: int) -> None:
        """Left and right axlebox springs between bogie frame and wheelset ``iw``.

        Displacement u = 0 at the static position; the z offset carries the static axlebox load
        P (force on the wheelset -K (u - offset) = -P e_z). Intrinsic formulation (axes of the
        mid-frame between bogie and wheelset, force applied at the midpoint of the two markers
        on both bodies): no spurious couple P x (relative displacement), see module doc."""
        p = self.params
        ib = iw // 2
        K = np.diag([p.primary_stiffness_x_N_per_m, p.primary_stiffness_y_N_per_m,
                     p.primary_stiffness_z_N_per_m, 0.0, 0.0, 0.0])
        D = np.diag([p.primary_damping_x_N_s_per_m, p.primary_damping_y_N_s_per_m,
                     p.primary_damping_z_N_s_per_m, 0.0, 0.0, 0.0])
        off_z = -self._P_axlebox_N / p.primary_stiffness_z_N_per_m
        for y in (p.primary_lateral_spacing_m / 2.0, -p.primary_lateral_spacing_m / 2.0):
            self.mbs.CreateRigidBodySpringDamper(
                itemNumbers=[self._bogies[ib], self._wheelsets[iw]],
                localPosition0=[self.wheelset_x_m[iw] - self.bogie_x_m[ib], y,
                                self._z_wheelset_m - p.bogie_cog_height_m],
                localPosition1=[0.0, y, 0.0],
                stiffness=K, damping=D, offset=[0.0, 0.0, off_z, 0.0, 0.0, 0.0],
                useIntrinsicFormulation=True, show=False)

    def _bellow_plates(self, k: int) -> tuple[list[float], list[float]]:
        """Local positions of bellow ``k``'s lower plate (bogie) and upper plate (carbody)."""
        p = self.params
        ib = k // 2
        y = p.airspring_lateral_spacing_m / 2.0 * (1.0 if BELLOWS[k][1] == "L" else -1.0)
        lower = [0.0, y, p.airspring_lower_height_m - p.bogie_cog_height_m]
        upper = [float(self.bogie_x_m[ib]), y,
                 p.airspring_upper_height_m - p.carbody_cog_height_m]
        return lower, upper

    def _add_airspring(self, k: int) -> None:
        """Bellow ``k``: one intrinsic ``RigidBodySpringDamper`` between the lower plate (bogie)
        and the upper plate (carbody) carrying the axial force law and the shear stiffness.

        Intrinsic formulation: the displacement d = p_upper - p_lower is measured in the
        mid-frame J between bogie frame and carbody, and the force is applied at the midpoint of
        the two plate centres on both bodies, so the pair is collinear at every instant (no end
        moments to add). In J the crushing is z = h0 - d_z (h0: nominal bellow height), the
        axial force F(t, z) = F_n + dF/dt (t - t_n) + dF/dz (z - z_n) pushes the carbody up along
        J's z axis (the bellow axis: the mean of the two plates' normals), and the shear springs
        act on d_x, d_y. The connector force f enters the left-hand side like K u: it acts as
        -f on the carbody (marker 1) and +f on the bogie, hence f = (k_s d_x, k_s d_y, -F).

        With an emergency spring and/or a vertical bumpstop (:attr:`airspring_in_series`), z is
        the crushing of the whole airspring and the axial force is that of the bellow law in
        parallel with the stop, in series with the emergency spring, solved in closed form by
        :func:`~vehicle.suspension.airspring_series_force_N` (the massless node between bellow
        and emergency spring needs no coordinate); the bellow law stays a law of the bellow's
        own crushing z_b (:meth:`bellow_crushing`)."""
        p, mbs = self.params, self.mbs
        bogie = self._bogies[k // 2]
        lower, upper = self._bellow_plates(k)
        F = esym.Real(f"F{k}", self._F_static_N)  # force at t_n and z_n [N]
        K = esym.Real(f"K{k}", 0.0)  # dF/dz [N/m]
        Fdot = esym.Real(f"Fdot{k}", 0.0)  # dF/dt at constant crushing [N/s]
        z0 = esym.Real(f"z0_{k}", 0.0)  # crushing z_n at the last set_bellow_forces [m]
        if k == 0:
            self._t_set = esym.Real("t_n", 0.0)  # time t_n of the last set_bellow_forces [s]
        tn = self._t_set
        h0 = esym.Real(self._bellow_height_m)
        ks = esym.Real(p.bellow_shear_stiffness_N_per_m)
        zero = esym.Real(0.0)

        def bellow_force(mbs, t, itemNumber, displacement, rotation, velocity, angularVelocity,
                         stiffness, damping, rotJ0, rotJ1, offset):
            z = h0 - displacement[2]
            f = F + Fdot * (t - tn) + K * (z - z0)
            return [ks * displacement[0], ks * displacement[1], -f, zero, zero, zero]

        F_static = self._F_static_N
        k_e, k_stop = p.emergency_spring_stiffness_N_per_m, p.vertical_bumpstop_stiffness_N_per_m
        clearance = p.vertical_bumpstop_clearance_m

        def airspring_force(mbs, t, itemNumber, displacement, rotation, velocity,
                            angularVelocity, stiffness, damping, rotJ0, rotJ1, offset):
            z = h0 - displacement[2]  # crushing of bellow + emergency spring
            f = airspring_series_force_N(z, F + Fdot * (t - tn) - K * z0, K, F_static, k_e,
                                         k_stop, clearance, _SYMBOLIC_OPS)
            return [ks * displacement[0], ks * displacement[1], -f, zero, zero, zero]

        co = mbs.CreateRigidBodySpringDamper(
            itemNumbers=[bogie, self._carbody], localPosition0=lower, localPosition1=upper,
            useIntrinsicFormulation=True, show=False)
        law = airspring_force if self.airspring_in_series else bellow_force
        fn = CreateSymbolicUserFunction(mbs, law, "springForceTorqueUserFunction", co)
        mbs.SetObjectParameter(co, "springForceTorqueUserFunction", fn)
        if k == 0:
            self._bellows, self._bellow_vars, self._bellow_law = [], [], []
            self._t_set_s = 0.0
        self._bellows.append(co)
        self._bellow_vars.append((F, K, Fdot, z0))
        self._bellow_law.append((self._F_static_N, 0.0, 0.0, 0.0))  # Python copy: F, K, Fdot, z0
        self._sym += [fn, h0, ks, zero]

    def _add_bumpstop(self, ib: int) -> None:
        """Lateral bumpstop of bogie ``ib`` (see module doc): lateral force beyond the
        clearance (y of the mid-frame between bogie and carbody), between the bogie centre at
        the lower-plate height and the carbody point that coincides with it at static
        equilibrium."""
        p, mbs = self.params, self.mbs
        clearance = esym.Real(p.lateral_bumpstop_clearance_m)
        k = esym.Real(p.lateral_bumpstop_stiffness_N_per_m)
        zero = esym.Real(0.0)

        # displacement = carbody point relative to the bogie point in the mid-frame between
        # bogie and carbody (intrinsic formulation); the returned connector force f enters the
        # left-hand side like K u: it acts as -f on the carbody (marker 1), +f on the bogie
        # frame, both at the markers' midpoint
        def bumpstop_force(mbs, t, itemNumber, displacement, rotation, velocity, angularVelocity,
                           stiffness, damping, rotJ0, rotJ1, offset):
            d = displacement[1]
            f = k * (esym.max(d - clearance, zero) + esym.min(d + clearance, zero))
            return [zero, f, zero, zero, zero, zero]

        h = p.airspring_lower_height_m
        co = mbs.CreateRigidBodySpringDamper(
            itemNumbers=[self._bogies[ib], self._carbody],
            localPosition0=[0.0, 0.0, h - p.bogie_cog_height_m],
            localPosition1=[float(self.bogie_x_m[ib]), 0.0, h - p.carbody_cog_height_m],
            useIntrinsicFormulation=True, show=False)
        fn = CreateSymbolicUserFunction(mbs, bumpstop_force, "springForceTorqueUserFunction", co)
        mbs.SetObjectParameter(co, "springForceTorqueUserFunction", fn)
        if ib == 0:
            self._bumpstops = []
        self._bumpstops.append(co)
        self._sym += [fn, clearance, k, zero]

    def _between_bogie_and_carbody(self, ib: int, x: float, y: float, h: float) -> dict:
        """Local positions, on bogie frame ``ib`` and on the carbody, of the point at (x, y)
        from the bogie centre and height h above rail at static equilibrium (coincident markers:
        a component's deflection is 0 there)."""
        p = self.params
        return dict(itemNumbers=[self._bogies[ib], self._carbody],
                    localPosition0=[x, y, h - p.bogie_cog_height_m],
                    localPosition1=[float(self.bogie_x_m[ib]) + x, y, h - p.carbody_cog_height_m],
                    useIntrinsicFormulation=True, show=False)

    def _add_anti_roll_bar(self, ib: int, k_roll: float) -> None:
        """Anti-roll bar of bogie ``ib``: a roll couple k_roll (phi_carbody - phi_frame) between
        bogie frame and carbody (see module doc). Intrinsic ``RigidBodySpringDamper`` with only
        the rotational x stiffness: the torque is k_roll times the x component of the relative
        rotation vector in the mid-frame; no force, no other stiffness. The couple is free
        (no point of application); the markers sit at the bogie centre, lower-plate height."""
        K = np.zeros((6, 6))
        K[3, 3] = k_roll
        co = self.mbs.CreateRigidBodySpringDamper(
            stiffness=K, **self._between_bogie_and_carbody(ib, 0.0, 0.0,
                                                           self.params.airspring_lower_height_m))
        self._arbs.append(co)

    def _add_traction_rod(self, ib: int) -> None:
        """Traction rod (or centre pivot) of bogie ``ib``: longitudinal spring-damper between the
        bogie centre and the carbody at ``traction_rod_height_m`` (intrinsic
        ``RigidBodySpringDamper``, x stiffness and damping only: it carries the longitudinal
        force and leaves the bogie free to yaw, roll and bounce)."""
        p = self.params
        K, D = np.zeros((6, 6)), np.zeros((6, 6))
        K[0, 0], D[0, 0] = p.traction_rod_stiffness_N_per_m, p.traction_rod_damping_N_s_per_m
        co = self.mbs.CreateRigidBodySpringDamper(
            stiffness=K, damping=D,
            **self._between_bogie_and_carbody(ib, 0.0, 0.0, p.traction_rod_height_m))
        self._traction_rods.append(co)

    def _add_dampers(self, ib: int) -> None:
        """Secondary dampers of bogie ``ib`` that have damping: vertical (left, right; at the
        bellow mid-height), lateral (bogie centre) and yaw (left, right; longitudinal)."""
        p = self.params
        side = "FR"[ib]
        h_mid = 0.5 * (p.airspring_lower_height_m + p.airspring_upper_height_m)
        kinds = (("secondary_vertical", 2, [(f"vertical_{side}{lr}", 0.0, y, h_mid) for lr, y in
                                            (("L", 0.5), ("R", -0.5))]),
                 ("secondary_lateral", 1, [(f"lateral_{side}", 0.0, 0.0,
                                            p.secondary_lateral_damper_height_m)]),
                 ("yaw", 0, [(f"yaw_{side}{lr}", 0.0, y, p.yaw_damper_height_m) for lr, y in
                             (("L", 0.5), ("R", -0.5))]))
        spacing = {"secondary_vertical": p.secondary_vertical_damper_lateral_spacing_m,
                   "secondary_lateral": 0.0, "yaw": p.yaw_damper_lateral_spacing_m}
        for kind, axis, places in kinds:
            c1 = getattr(p, f"{kind}_damping_N_s_per_m")
            if c1 == 0.0:
                continue
            for name, x, y, h in places:
                d = _Damper(name, axis, c1, getattr(p, f"{kind}_damper_blowoff_damping_N_s_per_m"),
                            getattr(p, f"{kind}_damper_blowoff_velocity_m_per_s"),
                            getattr(p, f"{kind}_damper_series_stiffness_N_per_m"))
                self._add_damper(d, ib, x, y * spacing[kind], h)

    def _add_damper(self, d: _Damper, ib: int, x: float, y: float, h: float) -> None:
        """Damper ``d`` between bogie frame ``ib`` and the carbody at (x, y, h) (see
        :meth:`_between_bogie_and_carbody`), acting along the mid-frame axis ``d.axis`` (intrinsic
        ``RigidBodySpringDamper``; force f = F along that axis, -F on the carbody).

        Rigid mounting (series stiffness ``inf``): a linear damper is the connector's damping
        matrix; a bilinear one a symbolic user function of the relative velocity.

        Maxwell element (finite series stiffness k_s): the damper's elongation y is an internal
        state. exudyn 1.13 has no connector that couples a generic first-order state (ODE1
        coordinates, ``NodeGenericODE1``) to body motion (only the hydraulic actuator does), and
        a massless intermediate body would make the mass matrix singular (a small mass, a stiff
        spurious mode). So the state is integrated inside the force law, as an internal variable
        (as in plasticity's return mapping): the symbolic user function gives the force at the
        end of the step as a closed-form function of the deflection there, the step size and the
        state (y, dy/dt) at the start of the step (trapezoidal rule, :func:`maxwell_force_N`).
        The force law is thus an ordinary, deflection-dependent spring law for the implicit
        solver: Newton sees its exact tangent k_s c / (c + k_s h/2) (numerical Jacobian), the
        generalized-alpha step stays implicit in y, and no Python runs inside Newton. After every
        accepted step a PostStep function (:meth:`_post_step`) commits the state from the
        converged deflection (in C++ exudyn would do the same with ODE1 coordinates: its
        implicit solver integrates them with the trapezoidal rule too).
        """
        K = np.zeros((6, 6))
        D = np.zeros((6, 6))
        rigid_linear = not d.maxwell and math.isinf(d.v_b)
        if rigid_linear:
            D[d.axis, d.axis] = d.c1
        d.connector = self.mbs.CreateRigidBodySpringDamper(
            stiffness=K, damping=D, **self._between_bogie_and_carbody(ib, x, y, h))
        self._dampers.append(d)
        if rigid_linear or d.maxwell:
            return  # the Maxwell function needs the step-size variable: _set_maxwell_function
        zero = esym.Real(0.0)
        axis, c1, c2, vb = d.axis, d.c1, d.c2, d.v_b

        def damper_force(mbs, t, itemNumber, displacement, rotation, velocity, angularVelocity,
                         stiffness, damping, rotJ0, rotJ1, offset):
            f = [zero] * 6
            f[axis] = bilinear_damper_force_N(velocity[axis], c1, c2, vb, _SYMBOLIC_OPS)
            return f

        self._set_user_function(d.connector, damper_force, zero)

    def _set_maxwell_function(self, d: _Damper) -> None:
        """Symbolic force law of Maxwell damper ``d`` (see :meth:`_add_damper`)."""
        zero = esym.Real(0.0)
        d.y_sym = esym.Real(f"y_{d.name}", 0.0)  # damper elongation at the step start [m]
        d.ydot_sym = esym.Real(f"ydot_{d.name}", 0.0)  # its rate [m/s]
        axis, y, ydot, h = d.axis, d.y_sym, d.ydot_sym, self._h_step
        k_s, c1, c2, vb = d.k_s, d.c1, d.c2, d.v_b

        def maxwell_force(mbs, t, itemNumber, displacement, rotation, velocity, angularVelocity,
                          stiffness, damping, rotJ0, rotJ1, offset):
            f = [zero] * 6
            f[axis] = maxwell_force_N(displacement[axis], y, ydot, h, k_s, c1, c2, vb,
                                      _SYMBOLIC_OPS)
            return f

        self._set_user_function(d.connector, maxwell_force, zero, y, ydot)

    def _set_user_function(self, co, function, *keep) -> None:
        """``function`` as the symbolic springForceTorqueUserFunction of connector ``co``."""
        fn = CreateSymbolicUserFunction(self.mbs, function, "springForceTorqueUserFunction", co)
        self.mbs.SetObjectParameter(co, "springForceTorqueUserFunction", fn)
        self._sym += [fn, *keep]

    def _post_step(self, mbs, t: float) -> bool:
        """PostStep user function (only with Maxwell dampers): after an accepted step ending at
        t, advance each Maxwell element's state (y, dy/dt) to t from the converged deflection,
        with the very law the connector used (:func:`maxwell_step`). Idempotent: exudyn also
        calls it at the start of every SolveSteps, for a state already committed."""
        t0 = self._maxwell_t
        if not t > t0:
            return True
        h = t - t0
        get = mbs.GetObjectOutput
        for d in self._maxwell:
            deflection = float(get(d.connector, _OUT.DisplacementLocal)[d.axis])
            d.force, d.y, d.ydot = maxwell_step(deflection, d.y, d.ydot, h, d.k_s, d.c1, d.c2,
                                                d.v_b)
            d.y_sym.SetValue(d.y)
            d.ydot_sym.SetValue(d.ydot)
        self._maxwell_t = t
        return True

    def _add_contact(self, j: int, rail0_m: float) -> None:
        """Wheel ``WHEELS[j]``: unilateral Hertz contact against its prescribed rail height.

        Connector displacement u = p_contact - p_rail_base (global), rail base at z = 0, so the
        penetration is delta = rail_height - u_z."""
        p = self.params
        C, c = p.hertz_constant_N_per_m1_5, p.contact_damping_N_s_per_m
        name = WHEELS[j]
        iw = int(name[0]) - 1
        y = p.contact_spacing_m / 2.0 * (1.0 if name[1] == "L" else -1.0)
        rz = esym.Real(f"rail_z{j}", float(rail0_m))  # rail height [m]
        rv = esym.Real(f"rail_v{j}", 0.0)  # rail vertical rate [m/s]
        zero = esym.Real(0.0)

        def contact_force(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
            delta = rz - displacement[2]  # IfThenElse evaluates only the selected branch
            q = esym.max(C * delta * esym.sqrt(delta) + c * (rv - velocity[2]), zero)
            return [0.0, 0.0, -esym.IfThenElse(delta > 0.0, q, zero)]  # on the wheel: +Q e_z

        # the rail: a point of the ground, or of the wheelset's track body on a flexible track
        rail = ([self._track_bodies[iw], [0.0, y, 0.0]] if self._flexible else
                [self._ground, [float(self.wheelset_x_m[iw]) + self._x0_m, y, 0.0]])
        co = self.mbs.CreateCartesianSpringDamper(
            itemNumbers=[rail[0], self._wheelsets[iw]], localPosition0=rail[1],
            localPosition1=[0.0, y, -p.wheel_radius_m], show=False)
        fn = CreateSymbolicUserFunction(self.mbs, contact_force, "springForceUserFunction", co)
        self.mbs.SetObjectParameter(co, "springForceUserFunction", fn)
        if j == 0:
            self._contacts, self._rail_vars = [], []
        self._contacts.append(co)
        self._rail_vars.append((rz, rv))
        self._sym += [fn, zero]

    def _add_wheel_rail_contact(self) -> None:
        """Contact guidance (``guidance="contact"``): a spin node per wheelset and one
        ``ObjectGenericODE2`` on all four wheelset bodies and spin nodes (28 coordinates, per
        wheelset the body's 6 and its spin) whose force user function is the contact law of
        the 8 wheels (:class:`~vehicle.wheelrail.track_contact.WheelsetTrackContact`: one call
        per residual evaluation for the whole car) and whose Jacobian user function
        differentiates the same law (forward differences); both run compiled kernels.

        Spin nodes: one coordinate each, the rotation about the axle relative to the
        non-rotating wheelset body, with the wheelsets' spin inertia (``wheelset_inertia_yy``;
        the body keeps its own, which only meets the held pitch); they start rolling freely at
        v / r0."""
        mbs, p = self.mbs, self.params
        Is = p.wheelset_inertia_yy_kg_m2
        spin0 = self.speed_m_per_s / self._wr.r0
        self._spin_nodes = [mbs.AddNode(exu.itemInterface.NodeGenericODE2(
            referenceCoordinates=[0.0], initialCoordinates=[0.0], initialCoordinates_t=[spin0],
            numberOfODE2Coordinates=1)) for _ in range(4)]
        mbs.AddObject(exu.itemInterface.ObjectGenericODE2(nodeNumbers=self._spin_nodes,
                                                          massMatrix=np.diag([Is] * 4)))
        self._ws_nodes = [mbs.GetObject(b)["nodeNumber"] for b in self._wheelsets]
        nodes = [n for pair in zip(self._ws_nodes, self._spin_nodes) for n in pair]
        self._track_nodes = []
        if self._flexible:
            self._track_nodes = self._add_track_nodes()
            nodes = [n for trio in zip(self._ws_nodes, self._spin_nodes, self._track_nodes)
                     for n in trio]
        wr = self._wr

        def forces(mbs, t, itemNumber, q, q_t):
            return wr.forces(q, q_t)

        def jacobian(mbs, t, itemNumber, q, q_t, fODE2, fODE2_t):
            return wr.jacobian(q, q_t, fODE2, fODE2_t)

        self._wr_object = mbs.AddObject(exu.itemInterface.ObjectGenericODE2(
            nodeNumbers=nodes, forceUserFunction=forces, jacobianUserFunction=jacobian))

    def _add_track_nodes(self) -> list:
        """Flexible track, contact guidance: per wheelset a node of three coordinates, the
        track's lateral displacement (along the track plane), vertical displacement and roll
        about the tangent through the track centre at rail level, under that wheelset, with the
        track's mass, stiffness and damping to the ground on them (one ``ObjectGenericODE2``;
        the contact's reaction is in the contact law, :mod:`vehicle.wheelrail.track_contact`).
        The track mass moves with the wheelset along the track but carries no inertia of that
        travel: it stands for the rails and sleepers under the wheel at each instant."""
        mbs, ts = self.mbs, self.track_structure
        nodes = [mbs.AddNode(exu.itemInterface.NodeGenericODE2(
            referenceCoordinates=[0.0] * 3, initialCoordinates=[0.0] * 3,
            initialCoordinates_t=[0.0] * 3, numberOfODE2Coordinates=3)) for _ in range(4)]

        def per_node(values):
            return np.diag(list(values) * 4)

        mbs.AddObject(exu.itemInterface.ObjectGenericODE2(
            nodeNumbers=nodes,
            massMatrix=per_node((ts.mass_kg, ts.mass_kg, ts.roll_inertia_kg_m2)),
            stiffnessMatrix=per_node((ts.lateral_stiffness_N_per_m, ts.vertical_stiffness_N_per_m,
                                      ts.roll_stiffness_N_m_per_rad)),
            dampingMatrix=per_node((ts.lateral_damping_N_s_per_m, ts.vertical_damping_N_s_per_m,
                                    ts.roll_damping_N_m_s_per_rad))))
        return nodes

    def _add_track_body(self, iw: int) -> int:
        """Flexible track, kinematic guidance: the track under wheelset ``iw`` as a body free to
        move vertically and to roll about its centre at rail level (a ``GenericJoint`` locks the
        rest), on a vertical spring-damper and a roll spring-damper to the ground; both wheels'
        vertical contacts act on it (:meth:`_add_contact`), so it carries the wheelset's load
        and the load difference between its wheels. It stays where the wheelset started: with
        vertical contact forces only, where it stands does not matter, and it carries no inertia
        of the wheelset's travel (see :meth:`_add_track_nodes`). The vertical spring's offset
        carries the static load of the wheelset on its rails: the track starts at rest at 0."""
        mbs, ts = self.mbs, self.track_structure
        pos = [float(self.wheelset_x_m[iw]) + self._x0_m, 0.0, 0.0]
        inertia = ts.roll_inertia_kg_m2
        body = mbs.CreateRigidBody(
            inertia=RigidBodyInertia(mass=ts.mass_kg, inertiaTensor=np.diag([inertia] * 3),
                                     inertiaTensorAtCOM=True),
            referencePosition=pos, nodeType=exu.NodeType.RotationRxyz)
        mbs.CreateGenericJoint(itemNumbers=[self._ground, body], position=pos,
                               constrainedAxes=[1, 1, 0, 0, 1, 1], show=False)
        K, D = np.zeros((6, 6)), np.zeros((6, 6))
        K[2, 2], K[3, 3] = ts.vertical_stiffness_N_per_m, ts.roll_stiffness_N_m_per_rad
        D[2, 2], D[3, 3] = ts.vertical_damping_N_s_per_m, ts.roll_damping_N_m_s_per_rad
        preload_m = 2.0 * self.Q_static_N / ts.vertical_stiffness_N_per_m
        mbs.CreateRigidBodySpringDamper(itemNumbers=[self._ground, body], localPosition0=pos,
                                        localPosition1=[0.0, 0.0, 0.0], stiffness=K, damping=D,
                                        offset=[0.0, 0.0, preload_m, 0.0, 0.0, 0.0], show=False)
        return body

    def _offset_wheelsets(self, offsets) -> None:
        """Initial lateral displacements of the wheelsets (see ``wheelset_lateral_offset_m``)."""
        if not self._contact_mode:
            raise ValueError("wheelset_lateral_offset_m needs guidance='contact'")
        y0 = np.asarray(offsets, dtype=float).reshape(4)
        lo, hi = self._wr.table.y_range_m
        if not np.all((y0 > lo) & (y0 < hi)):
            raise ValueError(f"wheelset_lateral_offset_m must lie inside the contact table "
                             f"({lo} .. {hi} m), got {y0}")
        geo = self._wr.table.geometry(y0)
        for body, y, dz, roll in zip(self._wheelsets, y0, geo["dz0"], geo["roll0"]):
            node = self.mbs.GetObject(body)["nodeNumber"]
            self.mbs.SetNodeParameter(node, "initialCoordinates",
                                      [0.0, float(y), float(dz), float(roll), 0.0, 0.0])

    def _init_contact_state(self) -> None:
        """After Assemble: the object's coordinate indices in the system vectors and the track
        frames at t = 0."""
        idx = []
        for i, (nb, ns) in enumerate(zip(self._ws_nodes, self._spin_nodes)):
            i0 = int(self.mbs.GetNodeODE2Index(nb))
            idx += list(range(i0, i0 + 6)) + [int(self.mbs.GetNodeODE2Index(ns))]
            if self._flexible:
                it = int(self.mbs.GetNodeODE2Index(self._track_nodes[i]))
                idx += [it, it + 1, it + 2]
        self._wr_index = np.array(idx)
        self._set_contact_track(0.0)

    def _contact_rail_values(self, times) -> tuple[np.ndarray, np.ndarray]:
        """(n, 8) lateral rail offsets e (+ left) and (n, 8) rail height offsets zr (+ up, normal
        to the track plane) under each wheel at the n ``times`` (contact guidance; the cant is in
        the track frame, not here), the irregularity evaluated once for all of them."""
        times = np.atleast_1d(np.asarray(times, dtype=float))
        if self._rail_fn is None:
            z = np.zeros((times.size, 8))
        else:
            z = np.array([self._rail_fn(float(t)) for t in times], dtype=float)
            if z.shape != (times.size, 8):
                raise ValueError(f"rail_height_m(t) must return shape (8,), got {z.shape[1:]}")
        e = np.zeros((times.size, 8))
        if self._irr is not None:
            lat, ver, cross, gauge = self._irregularity_at(times[:, None])
            e[:, 0::2], e[:, 1::2] = lat + 0.5 * gauge, lat - 0.5 * gauge
            z[:, 0::2] += ver - 0.5 * cross
            z[:, 1::2] += ver + 0.5 * cross
        return e, z

    def _irregularity_at(self, t) -> tuple[np.ndarray, ...]:
        """(lateral, vertical, cross_level, gauge), each shaped like s = s0 + v t: (4,) under the
        wheelsets at a time t, (n, 4) for times of shape (n, 1)."""
        s = self._wheelset_s_m(t)
        out = tuple(np.broadcast_to(np.asarray(v, dtype=float), s.shape).astype(float)
                    for v in self._irr(s))
        if len(out) != 4 or not all(np.all(np.isfinite(v)) for v in out):
            raise ValueError("irregularity(s) must return 4 finite arrays (lateral_m, "
                             "vertical_m, cross_level_m, gauge_m) shaped like s")
        return out

    #: half-width [s] of the central difference that gives the rails' rates to the contact law
    RAIL_RATE_DT_S = 1e-6

    def _set_contact_track(self, t: float, state=None) -> None:
        """Track frames and rail offsets, with their rates, at the step end t (contact guidance).

        The rates are those at t (a central difference over +-:attr:`RAIL_RATE_DT_S`), not the
        means over the step: the creep forces see the rail velocity, and a step mean lags it by
        half a step, a first-order error (the straight irregular run's largest lateral wheel
        force moved 3015 / 2947 / 2921 N at 5 / 2.5 / 1.25 ms with step means, 2926 / 2928 /
        2931 N with the rates at t: car alone, 10 s of scenarios/straight_irregular.yaml)."""
        state = state or self._track_at(t)[:4]
        self._frames_t = t
        if self._rail_fn is None and self._irr is None:
            self._wr.set_track(state)
            return
        d = self.RAIL_RATE_DT_S
        (em, e1, ep), (zm, z1, zp) = self._contact_rail_values((t - d, t, t + d))
        ed, zd = (ep - em) / (2.0 * d), (zp - zm) / (2.0 * d)
        rails = [tuple((e1[j], ed[j], z1[j], zd[j]) for j in (2 * i, 2 * i + 1))
                 for i in range(4)]
        self._wr.set_track(state, rails)

    def _pre_step_contact(self, mbs, t: float) -> bool:
        """PreStep with contact guidance: guidance offsets (the drive at the car centre, the
        wheelsets' pitch), track frames and rail offsets at the step end t, each wheelset's at
        its own arc length; stops the integration (advance raises) when a wheelset has left the
        contact table (derailed).

        The wheelsets are free along the track: wheelset i's frame is set at s0_i + v t plus its
        offset along the tangent, predicted at the step end from the state at its start
        (position + h velocity), so that the law sees the track where the wheelset is. (Holding
        the offset of the step start instead lags a step: the R 150 m twisted curve's ΣY then
        drifted by 22 N, 0.2 %, with every halving of the steps.) A frame a few millimetres off along a
        curve would hand the law a spurious angle of attack kappa dx (3e-5 rad for 3 mm at
        R = 100 m: ~0.2 kN of lateral creep force per wheel)."""
        t0 = mbs.systemData.GetTime(exu.ConfigurationType.StartOfStep)
        sd, idx = mbs.systemData, self._wr_index
        q, q_t = sd.GetODE2Coordinates()[idx], sd.GetODE2Coordinates_t()[idx]
        if self._guided:  # the offsets predicted at t (the frames may be of t0 or, on a retry, of t)
            ahead = np.asarray(q) + (t - t0) * np.asarray(q_t)
            self._ds_wheelset = (self._ds_wheelset + np.asarray(self._wr.longitudinal_offsets(ahead))
                                 - self.speed_m_per_s * (t - self._frames_t))
        state = self._track_at(t)
        if self._guided:
            self._set_guidance(state)
            self._heading_now = state[0][2]
        self._set_contact_track(t, state[:4])
        y = self._wr.lateral_positions_at_step_end(q, q_t, t - t0)
        if not self._wr.in_table(y):  # predicted at the step end from the state at its start
            self._wr_left_table = (t0, y)
            return False
        return True

    # ================================================================== rail and track
    def _rail_at(self, t: float, track_state=None) -> np.ndarray:
        """(8,) rail heights [m] at time t: cant of the track plus ``rail_height_m``."""
        if self._rail_fn is None:
            h = np.zeros(8)
        else:
            h = np.array(self._rail_fn(t), dtype=float)
            if h.shape != (8,):
                raise ValueError(f"rail_height_m(t) must return shape (8,), got {h.shape}")
        if self._irr is not None:
            _, ver, cross, _ = self._irregularity_at(t)
            h[0::2] += ver - 0.5 * cross
            h[1::2] += ver + 0.5 * cross
        if self._canted:
            b = self.params.contact_spacing_m / 2.0
            for iw, (_, _, _, cant, _, _) in enumerate((track_state or self._track_at(t))[:4]):
                if cant != 0.0:
                    dz = b * math.sin(cant)  # track plane rolled by -cant: left down, right up
                    h[2 * iw] -= dz
                    h[2 * iw + 1] += dz
        return h

    def _aligned(self, track_state, t: float) -> list[tuple[float, ...]]:
        """Kinematic guidance with irregularities: the track state with each wheelset's point
        moved across the track by the lateral alignment (horizontally, normal to the tangent)."""
        lat = self._irregularity_at(t)[0]
        return [(x - math.sin(psi) * e, y + math.cos(psi) * e, psi, *rest)
                for (x, y, psi, *rest), e in zip(track_state, lat.tolist())]

    def _set_guidance(self, track_state) -> None:
        """Guidance offsets (see :meth:`_add_wheelset_guidance`, :meth:`_add_drive`) for the
        given track state (contact guidance: its fifth entry is the car centre's)."""
        if self._contact_mode:
            (xi, rz), (x, y, psi, *_) = self._drive_vars, track_state[4]
            xi.SetValue(math.cos(psi) * (x - self._x0_m) + math.sin(psi) * y)
            rz.SetValue(psi)
        for iw, ((xi, eta, rx, ry, rz), (x, y, psi, cant, _, _)) in enumerate(
                zip(self._guidance_vars, track_state)):
            dx = x - (float(self.wheelset_x_m[iw]) + self._x0_m)
            c, s = math.cos(psi), math.sin(psi)
            if cant == 0.0:
                xi.SetValue(c * dx + s * y)
                eta.SetValue(-s * dx + c * y)
                rz.SetValue(psi)
                if self._canted:
                    rx.SetValue(0.0)
                    ry.SetValue(0.0)
                continue
            # A = Rz(psi) Rx(g), g = -cant = Rx(a) Ry(b) Rz(psi'):
            # A = [[c, -s cg, s sg], [s, c cg, -c sg], [0, sg, cg]]; target point (x, y, 0) on
            # the centre line at rail level, p0 = (x0, 0, 0): A^T (target - p0) = A^T (dx, y, 0)
            cg, sg = math.cos(cant), -math.sin(cant)
            xi.SetValue(c * dx + s * y)
            eta.SetValue(-s * cg * dx + c * cg * y)
            rx.SetValue(math.atan2(c * sg, cg))
            ry.SetValue(math.asin(s * sg))
            rz.SetValue(math.atan2(s * cg, c))

    def _pre_step(self, mbs, t: float) -> bool:
        """PreStep user function: guidance offsets and rail heights at the step end t, mean
        rail rate over the step; withdraws the Jacobian request SolveSteps makes at its start
        when the stored Jacobian is kept (see :meth:`_keep_jacobian`)."""
        if self._jac_may_skip:
            self._keep_jacobian()
        if self._maxwell:
            self._h_step.SetValue(t - mbs.systemData.GetTime(exu.ConfigurationType.StartOfStep))
        if self._contact_mode:
            return self._pre_step_contact(mbs, t)
        state = self._track_at(t) if self._guided else None
        if self._guided:
            self._set_guidance(state if self._irr is None else self._aligned(state, t))
            self._heading_now = state[0][2]
        if self._rail_fn is None and not self._canted and self._irr is None:
            return True  # level rails: nothing else changes
        t0 = mbs.systemData.GetTime(exu.ConfigurationType.StartOfStep)
        tc, zc = self._rail_cache
        z0 = zc if t0 == tc else self._rail_at(t0)
        z1 = self._rail_at(t, state)
        v = (z1 - z0) / (t - t0) if t > t0 else np.zeros(8)
        values = (z1.tolist(), v.tolist())
        if values != self._rail_set:  # held rails (e.g. after the twist ramp): nothing to set
            for (rz, rv), zj, vj in zip(self._rail_vars, *values):
                rz.SetValue(zj)
                rv.SetValue(vj)
            self._rail_set = values
        self._rail_cache = (t, z1)
        return True

    # ================================================================== solver
    def _init_solver(self, rho: float, abs_tol: float, rel_tol: float, reuse: bool) -> None:
        s = exu.SimulationSettings()
        s.solution.file.write = False
        s.solution.sensors.active = False
        s.linearSolver.solverType = exu.LinearSolverType.EigenDense  # fastest at this size
        ti = s.timeIntegration
        ti.verboseMode = 0
        ti.numberOfSteps = 1
        ti.startTime = 0.0
        ti.endTime = self.step_s
        ti.adaptiveStep = True  # lets SolveSteps clamp a step to the macro-step end
        ti.generalizedAlpha.spectralRadius = rho
        ti.newton.useModifiedNewton = True
        ti.newton.absoluteTolerance = abs_tol
        ti.newton.relativeTolerance = rel_tol
        self._settings = s
        self._reuse_jacobian = reuse
        self.mbs.SetPreStepUserFunction(self._pre_step)
        if reuse:
            # a second solver on the same system computes fresh Jacobians on demand (calling the
            # main solver's ComputeNewtonJacobian from its own user function would recurse)
            self._jac_solver = exu.MainSolverImplicitSecondOrder()
            if not self._jac_solver.InitializeSolver(self.mbs, s):
                raise RuntimeError("exudyn: InitializeSolver failed")
        self._solver = exu.MainSolverImplicitSecondOrder()
        if not self._solver.InitializeSolver(self.mbs, s):
            raise RuntimeError("exudyn: InitializeSolver failed")
        if reuse:
            self._solver.SetUserFunctionComputeNewtonJacobian(self.mbs, self._jacobian)
        self._ti = s.timeIntegration  # handles (references into the C++ objects)
        self._it = self._solver.it
        self._conv = self._solver.conv
        self._jac_h = None  # step size of the stored Jacobian
        self._jac_heading = 0.0  # track heading under wheelset 1 when it was computed [rad]
        self._heading_now = 0.0  # track heading under wheelset 1 at the last step end [rad]
        self._jac_may_skip = False
        self._jac_unfactorised = False  # the stored Jacobian awaits its factorisation
        self.jacobian_count = 0  # fresh Jacobians computed (diagnostics)
        self._t = 0.0

    def _keep_jacobian(self) -> None:
        """At the first step of an :meth:`advance` (SolveSteps has just requested a Jacobian):
        when :meth:`_jacobian` would answer that request with the stored Jacobian, withdraw the
        request instead, so that Newton goes on with the factorisation of that very matrix,
        which the solver still holds, rather than factorising it again (the same LU, bit for
        bit). Later requests (Newton's own) reach :meth:`_jacobian` and get a fresh one. A
        Jacobian stored by :meth:`_refresh_jacobian` has no factorisation yet: the request
        stays, and :meth:`_jacobian` answers it with that matrix."""
        if self._jac_unfactorised:
            return
        self._jac_may_skip = False
        conv = self._conv
        h = self._it.currentStepSize
        if conv.jacobianUpdateRequested and self._jac_h is not None and abs(h - self._jac_h) <= 1e-9 * h:
            conv.jacobianUpdateRequested = False

    def _jacobian(self, solver, mbs, settings) -> bool:
        """Newton Jacobian user function of the main solver (see module doc)."""
        h = solver.it.currentStepSize
        if self._jac_may_skip and self._jac_h is not None and abs(h - self._jac_h) <= 1e-9 * h:
            self._jac_may_skip = False  # later requests in this advance come from Newton
            self._jac_unfactorised = False  # Newton factorises it now
            return True  # keep the stored (already factorizable) Jacobian
        self._jac_may_skip = False
        self._store_jacobian(solver, h)
        return True

    def _store_jacobian(self, solver, h: float) -> None:
        """Compute a fresh Newton Jacobian for the step size h at the system's current state
        (with the second solver) and hand it to ``solver``."""
        js = self._jac_solver
        js.it.currentStepSize = h
        # ComputeNewtonJacobian adds the solver's own stored mass matrix: the second solver's
        # would stay the one of t = 0, but the Rxyz mass matrix changes with the rotation (yaw
        # in a curve: 10 % off at 0.1 rad, and Newton diverges)
        js.ComputeMassMatrix(self.mbs)
        js.ComputeNewtonJacobian(self.mbs, self._settings)
        solver.SetSystemJacobian(js.GetSystemJacobian())
        self._jac_h = h
        self._jac_heading = self._heading_now
        self._jac_unfactorised = False
        self.jacobian_count += 1

    def _refresh_jacobian(self) -> None:
        """After an :meth:`advance` through which the track has turned by more than
        :attr:`JACOBIAN_HEADING_TOL_RAD` since the stored Jacobian was computed: a fresh one
        at the converged end state, for the next advance (which factorises it at its first
        request, see :meth:`_keep_jacobian`).

        Why there rather than at the next step's first Newton iteration: that iteration starts
        from exudyn's predictor (zero new accelerations); in a curve it is off the solution by
        h^2 beta a in position and h gamma a in velocity (a ~ V^2/R), which with the stiff,
        load-dependent contact law (contact guidance) is far enough for a Jacobian taken
        there to slow the following modified-Newton iterations (contraction ~0.2-0.3 per
        iteration instead of ~0.01 with one taken at a converged state). Contact guidance
        only: with kinematic guidance the predictor's Jacobian serves as well (measured: 3.29
        instead of 3.19 Newton iterations per step on the curve entry when taken here)."""
        self._store_jacobian(self._solver, self._it.currentStepSize)
        self._jac_unfactorised = True

    # ================================================================== interface
    def static_bellow_forces_N(self) -> np.ndarray:
        """(4,) airspring forces [N] carrying the carbody in static equilibrium on level track."""
        return np.full(4, self._F_static_N)

    @property
    def bellow_height_m(self) -> float:
        """Nominal height [m] of the airsprings: the distance of their plates at static
        equilibrium (``airspring_upper_height_m - airspring_lower_height_m``)."""
        return self._bellow_height_m

    @property
    def t_s(self) -> float:
        """Current simulation time [s]."""
        return self._t

    def _bellow_state(self) -> None:
        """Crushing and rate of the bellows at the current state (cached per time).

        z = h0 - d_z with d = p_upper - p_lower in the connector's mid-frame J, the very
        quantity the force law uses (see :meth:`_add_airspring`). Its rate approximates the time
        derivative of that component: exudyn's ``VelocityLocal`` is the relative velocity
        expressed in J, which misses the rotation of J itself, d(A^T r)/dt = A^T r' - w x d
        (w: J's angular velocity, taken as the mean of the two bodies'). Exact only to second
        order in the bodies' relative rotation: over the twist ramp its integral overstates the
        crushing change by 2.7 um of 17 mm (measured against a directional derivative, see
        cosim/monolithic.py). The co-simulation's Hermite interpolant ends on the exact crushing
        at both ends of each step, so only the shape within a step sees it."""
        if self._bellow_t == self._t:
            return
        get = self.mbs.GetObjectOutput
        h0 = self._bellow_height_m
        w_frames = self._mid_frame_angular_velocities()
        z, zdot = [], []
        for k, co in enumerate(self._bellows):
            d0, d1, d2 = get(co, _OUT.DisplacementLocal).tolist()
            v2 = float(get(co, _OUT.VelocityLocal)[2])
            w0, w1 = w_frames[k // 2]
            z.append(h0 - d2)
            zdot.append(-(v2 - (w0 * d1 - w1 * d0)))
        self._z_total = np.array(z)
        if self.airspring_in_series:  # the bellow's own share (see _add_airspring)
            p, t = self.params, self._t
            out = [airspring_series_bellow_crushing(
                zk, zdk, F + Fdot * (t - self._t_set_s) - K * z0, K, Fdot, self._F_static_N,
                p.emergency_spring_stiffness_N_per_m, p.vertical_bumpstop_stiffness_N_per_m,
                p.vertical_bumpstop_clearance_m)
                for zk, zdk, (F, K, Fdot, z0) in zip(z, zdot, self._bellow_law)]
            z = [o[1] for o in out]
            zdot = [o[2] for o in out]
        self._z, self._zdot = np.array(z), np.array(zdot)
        self._bellow_t = self._t

    def _mid_frame_angular_velocities(self) -> list[tuple[float, float]]:
        """Per bogie, the x and y components of the angular velocity of the mid-frame between
        its frame and the carbody (the mean of the two bodies'), in the bogie frame's axes."""
        body = self.mbs.GetObjectOutputBody
        w_carbody = np.asarray(body(self._carbody, _OUT.AngularVelocity))
        out = []
        for bogie in self._bogies:
            A = np.asarray(body(bogie, _OUT.RotationMatrix)).reshape(3, 3)
            w = A.T @ (0.5 * (w_carbody + np.asarray(body(bogie, _OUT.AngularVelocity))))
            out.append((float(w[0]), float(w[1])))
        return out

    def bellow_crushing(self) -> tuple[np.ndarray, np.ndarray]:
        """Bellow crushing z [m] and its rate [m/s], each (4,) in :data:`BELLOWS` order.

        z = nominal bellow height - (p_upper_plate - p_lower_plate) . n, n the bellow axis
        (the z axis of the mid-frame between bogie frame and carbody, see
        :meth:`_add_airspring`), positive in compression, 0 at static equilibrium on level
        track (bellow at nominal height). In a curve the carbody rolls outward: the outer
        bellows are crushed (z > 0), the inner ones extend."""
        self._bellow_state()
        return self._z.copy(), self._zdot.copy()

    def set_bellow_forces(self, F_N: np.ndarray, dF_dz_N_per_m: np.ndarray | None = None,
                          dF_dt_N_per_s: np.ndarray | None = None) -> None:
        """Airspring force laws for the following :meth:`advance`, each (4,) in :data:`BELLOWS`
        order.

        F(t, z) = F_N + dF_dt (t - t_now) + dF_dz (z - z_now): a force pair along the bellow
        axis pushing the carbody up and the bogie down, evaluated by the multibody solver at
        every internal step from the current state. ``dF_dz`` [N/m] is the instantaneous
        pneumatic stiffness (linearised implicit coupling), ``dF_dt`` [N/s] the rate of the
        slow part (air flows, heat); ``None`` = 0. t_now and z_now are :attr:`t_s` and the
        crushing of :meth:`bellow_crushing` at the current state, so F_N is the force at the
        current state: pass the force the previous law reached at t_now and the force stays
        continuous in time across calls.

        Note: a jump of F_N between calls enters generalized-alpha with about half an internal
        step of delay (the step starts from the old acceleration)."""
        F, dF, Fdot = (_four_floats(v) for v in (F_N, dF_dz_N_per_m, dF_dt_N_per_s))
        if not all(map(math.isfinite, F + dF + Fdot)):
            raise ValueError(f"non-finite bellow force law: F={F}, dF/dz={dF}, dF/dt={Fdot}")
        self._bellow_state()
        for (Fv, Kv, Fdv, z0v), Fk, Kk, Fdk, zk in zip(self._bellow_vars, F, dF, Fdot, self._z.tolist()):
            Fv.SetValue(Fk)
            Kv.SetValue(Kk)
            Fdv.SetValue(Fdk)
            z0v.SetValue(zk)
        self._t_set.SetValue(self._t)
        self._bellow_law = list(zip(F, dF, Fdot, self._z.tolist()))
        self._t_set_s = self._t
        if self.airspring_in_series:
            self._bellow_t = None  # the new law splits the same total crushing anew

    def advance(self, t_end_s: float) -> None:
        """Integrate from :attr:`t_s` to ``t_end_s`` [s] in equal steps <= ``step_s``."""
        span = t_end_s - self._t
        if span < -1e-12:
            raise ValueError(f"advance: t_end_s={t_end_s} is before t_s={self._t}")
        if span <= 1e-12:
            return
        if t_end_s > self.t_end_max_s + 1e-9:
            raise ValueError(f"advance: at t_end_s={t_end_s} s the front wheelset would have "
                             f"left the track (t_end_max_s={self.t_end_max_s} s)")
        n = max(1, math.ceil(span / self.step_s - 1e-9))
        it = self._it
        self._ti.endTime = t_end_s
        it.endTime = t_end_s
        it.maxStepSize = span / n
        # keep the stored Jacobian unless the car has turned (the constraint directions and
        # the rotational mass matrix follow the heading; normally renewed already at the end
        # of the previous advance, see _refresh_jacobian)
        turned = abs(self._heading_now - self._jac_heading)
        self._jac_may_skip = turned <= self.JACOBIAN_HEADING_TOL_RAD
        ok = self._solver.SolveSteps(self.mbs, self._settings)
        self._t = float(it.currentTime)
        if self._contact_mode:
            self._advances += 1
            if self._wr_left_table is not None:
                t_out, y_out = self._wr_left_table
                lo, hi = self._wr.table.y_range_m
                raise Derailed(
                    f"a wheelset left the contact table at t = {t_out:.4f} s (derailment or "
                    f"flange climb): lateral positions {np.round(1e3 * np.array(y_out), 2)} mm, "
                    f"the table covers {1e3 * lo:g} .. {1e3 * hi:g} mm relative to the rails")
        if not ok:
            message = f"exudyn: time integration failed at t={self._t} s (advance to {t_end_s} s)"
            airborne = self._airborne_wheelsets()
            if airborne:  # said, not concluded: a wheel lifts for milliseconds on an impact too
                message += f"; wheelset(s) {', '.join(map(str, airborne))} had no wheel in contact"
            raise RuntimeError(message)
        self._t = float(t_end_s)
        if self._contact_mode and self._reuse_jacobian and \
                abs(self._heading_now - self._jac_heading) > self.JACOBIAN_HEADING_TOL_RAD:
            self._refresh_jacobian()  # at the converged state, for the next advance

    def _airborne_wheelsets(self) -> list[int]:
        """Wheelsets (1..4) with neither wheel in contact at the current state."""
        Q = self.wheel_loads_N() if not self._contact_mode else self.contact_state().normal_N
        return [i + 1 for i in range(4) if Q[2 * i] <= 0.0 and Q[2 * i + 1] <= 0.0]

    def wheel_loads_N(self) -> np.ndarray:
        """(8,) vertical wheel-rail forces Q >= 0 [N] at the current state, :data:`WHEELS` order.

        Kinematic guidance: the vertical Hertz contact force (global vertical). Contact
        guidance: the component of the whole contact force (normal force and creep forces) of
        the rail on the wheel normal to the track plane (the track frame's z; on canted track
        perpendicular to the canted plane), i.e. EN 14363's Q in the track frame."""
        if self._contact_mode:
            return self.contact_state().force_track_N[:, 2].copy()
        get = self.mbs.GetObjectOutput
        # the contact connector's force f acts as -f = +Q e_z on the wheel
        return np.array([-get(co, _OUT.Force)[2] for co in self._contacts])

    # ================================================================== wheel-rail outputs
    def contact_state(self) -> WheelContactOutputs:
        """The contact of every wheel at the current state (contact guidance only; see
        :class:`~vehicle.wheelrail.track_contact.WheelContactOutputs`: normal forces, forces in
        the track frame, contact angles, saturation, creepages, wheelset lateral positions and
        yaw). Evaluated once per state (cached)."""
        if not self._contact_mode:
            raise ValueError("contact_state needs guidance='contact'")
        key = (self._t, self._advances)
        if self._wr_cache[0] != key:
            sd = self.mbs.systemData
            idx = self._wr_index
            out = self._wr.outputs(sd.GetODE2Coordinates()[idx].tolist(),
                                   sd.GetODE2Coordinates_t()[idx].tolist())
            self._wr_cache = (key, out)
        return self._wr_cache[1]

    def lateral_wheel_forces_N(self) -> np.ndarray:
        """(8,) lateral wheel-rail forces Y [N], :data:`WHEELS` order: the force of the rail on
        the wheel along the track plane's lateral axis, **positive towards the track centre**
        (on the left wheel towards -y, on the right towards +y): the sense in which a flange
        force pushes the wheelset back, so Y/Q > 0 is the flanging wheel's value in Nadal's
        criterion. Includes the normal force's lateral component and the creep forces.
        Kinematic guidance: NaN (no lateral wheel-rail force is modelled; the guidance joint
        carries it)."""
        if not self._contact_mode:
            return np.full(8, np.nan)
        Fl = self.contact_state().force_track_N[:, 1]
        return np.where(np.arange(8) % 2 == 0, -Fl, Fl)

    def wheelset_lateral_forces_N(self) -> np.ndarray:
        """(4,) sum of the two wheels' lateral forces per wheelset [N] in the track frame,
        positive to the left (the force of the rails on the wheelset; the track receives the
        opposite): Y_R - Y_L with :meth:`lateral_wheel_forces_N`' inward-positive Y, i.e.
        EN 14363's track shifting force sum Y. NaN with kinematic guidance."""
        if not self._contact_mode:
            return np.full(4, np.nan)
        Fl = self.contact_state().force_track_N[:, 1]
        return Fl[0::2] + Fl[1::2]

    def wheelset_lateral_displacement_m(self) -> np.ndarray:
        """(4,) lateral displacement [m] of each wheelset centre from the design track centre
        line, in the track plane at the wheelset's arc length, positive to the left (track
        irregularities are not subtracted: the lateral position relative to the rails is
        ``contact_state().lateral_to_rails_m``). ~0 with kinematic guidance (prescribed)."""
        if self._contact_mode:
            return self.contact_state().lateral_m.copy()
        return self._wheelset_pose()[0]

    def angle_of_attack_rad(self) -> np.ndarray:
        """(4,) yaw [rad] of each wheelset relative to the track tangent at its arc length,
        positive counter-clockwise seen from above (the wheelset's x axis turned to the left).
        In a left-hand curve a leading wheelset flanging on the outer (right) rail has a
        negative angle of attack. ~0 with kinematic guidance (prescribed)."""
        if self._contact_mode:
            return self.contact_state().yaw_rad.copy()
        return self._wheelset_pose()[1]

    def flange_contact(self) -> np.ndarray:
        """(8,) bool: the wheel touches its rail with a contact angle above
        ``ContactParams.flange_angle_rad`` (default 0.7 rad, 40 deg: the flange flank, see
        :class:`~vehicle.params.ContactParams`) and a positive normal force. All False with
        kinematic guidance."""
        if not self._contact_mode:
            return np.zeros(8, dtype=bool)
        c = self.contact_state()
        return (c.gamma_rad > self.contact_params.flange_angle_rad) & (c.normal_N > 0.0)

    def _wheelset_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """(lateral offsets of the rail-level points, yaw angles) of the wheelsets relative to
        the track (from the body states; kinematic guidance)."""
        body = self.mbs.GetObjectOutputBody
        y, yaw = [], []
        for wheelset, (xt, yt, psi, *_) in zip(self._wheelsets, self._track_at(self._t)):
            A = np.asarray(body(wheelset, _OUT.RotationMatrix)).reshape(3, 3)
            # the rail-level point the guidance holds (the centre moves across when the
            # wheelset rolls on raised rails)
            x, yb, _ = np.asarray(body(wheelset, _OUT.Position)) - self._z_wheelset_m * A[:, 2]
            y.append(-math.sin(psi) * (x - xt) + math.cos(psi) * (yb - yt))
            yaw.append(math.atan2(A[1, 0], A[0, 0]) - psi)
        yaw = (np.array(yaw) + math.pi) % (2.0 * math.pi) - math.pi
        return np.array(y), yaw

    def carbody_roll_rad(self) -> float:
        """Carbody roll angle [rad], right-hand about its own x axis (forward): positive = left
        side up, i.e. the outward roll of a left-hand curve (negative in a right-hand one).
        Yaw-independent: the angle of the body's y axis above the horizontal plane."""
        A = np.asarray(self.mbs.GetObjectOutputBody(self._carbody, _OUT.RotationMatrix))
        A = A.reshape(3, 3)
        return float(math.atan2(A[2, 1], A[2, 2]))

    def track_deflection(self) -> np.ndarray:
        """(4, 3) per wheelset the flexible track's displacement under it from its position at
        rest: lateral [m] (in the track plane, + left; 0 with kinematic guidance, which leaves
        the track laterally rigid), vertical [m] (+ up) and roll [rad] (about the track
        tangent, + left rail up). Zeros on a rigid track."""
        out = np.zeros((4, 3))
        if not self._flexible:
            return out
        if self._contact_mode:
            q = self.mbs.systemData.GetODE2Coordinates()
            for i, node in enumerate(self._track_nodes):
                i0 = int(self.mbs.GetNodeODE2Index(node))
                out[i] = q[i0:i0 + 3]
            return out
        body = self.mbs.GetObjectOutputBody
        for i, b in enumerate(self._track_bodies):
            out[i, 1] = body(b, _OUT.Displacement)[2]
            out[i, 2] = body(b, _OUT.Rotation)[0]
        return out

    def roll_to_track_rad(self) -> np.ndarray:
        """(3,) roll [rad] of the carbody, the front and the rear bogie frame relative to the
        track plane (the design track's cant at the car centre and at each bogie centre; the
        irregularities' cross-level is not subtracted), in :meth:`carbody_roll_rad`'s
        convention (positive: left side up)."""
        body = self.mbs.GetObjectOutputBody
        rolls = []
        for b in [self._carbody, *self._bogies]:
            A = np.asarray(body(b, _OUT.RotationMatrix)).reshape(3, 3)
            rolls.append(math.atan2(A[2, 1], A[2, 2]))
        if self._sampler is None or not self._canted:
            return np.array(rolls)
        s = self.s_m
        plane = [-row[3] for row in self._sampler.at([s, s + self.bogie_x_m[0], s + self.bogie_x_m[1]])]
        return np.array(rolls) - np.array(plane)

    def carbody_lateral_m(self) -> float:
        """Lateral offset [m] of the carbody centre of gravity from the track centre line,
        positive to the left, measured horizontally along the track normal at the car centre's
        nominal arc length :attr:`s_m`. In a curve of radius R this includes the geometric
        offset of a body between bogies on the chord: (bogie centre distance)^2 / (8 R) to the
        inside (0.125 m at R = 100 m) -- see :meth:`secondary_lateral_m` for the suspension
        deflection alone."""
        x, y, _ = self.mbs.GetObjectOutputBody(self._carbody, _OUT.Position)
        if self._sampler is None:
            return float(y)
        xt, yt, heading = self._sampler.at([self.s_m])[0][:3]
        return float(-math.sin(heading) * (x - xt) + math.cos(heading) * (y - yt))

    def secondary_lateral_m(self) -> np.ndarray:
        """(2,) lateral secondary deflection [m] at the bumpstops, front and rear bogie: carbody
        relative to bogie frame at the bumpstop (bogie centre, lower-plate height), along the
        y axis of the mid-frame between the two (positive: carbody to the left). The bumpstop
        engages beyond +-``lateral_bumpstop_clearance_m``."""
        get = self.mbs.GetObjectOutput
        return np.array([get(co, _OUT.DisplacementLocal)[1] for co in self._bumpstops])

    def bumpstop_forces_N(self) -> np.ndarray:
        """(2,) lateral bumpstop forces [N] on the carbody, front and rear bogie, along the same
        axis as :meth:`secondary_lateral_m` (0 inside the clearance, opposite to the deflection
        beyond it)."""
        get = self.mbs.GetObjectOutput
        # the connector force acts as -f on the carbody (see _add_bumpstop)
        return np.array([-get(co, _OUT.ForceLocal)[1] for co in self._bumpstops])

    # ================================================================== optional components
    def airspring_crushing_m(self) -> np.ndarray:
        """(4,) crushing [m] of each whole airspring (bellow + emergency spring), :data:`BELLOWS`
        order, positive in compression, 0 at static equilibrium: z = h0 - d_z as in
        :meth:`bellow_crushing`, which without an emergency spring or vertical bumpstop is the
        same number and with them the bellow's own share."""
        self._bellow_state()
        return self._z_total.copy()

    def anti_roll_bar_moments_N_m(self) -> np.ndarray:
        """(2,) roll moments [N m] of the anti-roll bars on the carbody, front and rear bogie,
        about the x axis of the mid-frame between bogie frame and carbody: -k_roll (phi_carbody
        - phi_frame), negative when the carbody rolls left side up relative to the frame.
        Empty without anti-roll bars."""
        get = self.mbs.GetObjectOutput
        return np.array([-get(co, _OUT.TorqueLocal)[0] for co in self._arbs])

    def traction_rod_forces_N(self) -> np.ndarray:
        """(2,) longitudinal forces [N] of the traction rods on the carbody, front and rear bogie,
        along the x axis of the mid-frame (negative when the carbody is ahead of its position
        relative to the bogie). Empty without traction rods."""
        get = self.mbs.GetObjectOutput
        return np.array([-get(co, _OUT.ForceLocal)[0] for co in self._traction_rods])

    def damper_forces_N(self) -> dict[str, float]:
        """Force [N] of every secondary damper, by name (``vertical_FL``, ``lateral_F``,
        ``yaw_RR``, ...; F/R bogie, L/R side): the force on the bogie frame along the damper's
        axis (the carbody gets the opposite), positive when it resists the carbody moving along
        +x (yaw), +y (lateral) or +z (vertical) relative to the frame. Maxwell elements: the
        force at the end of the last accepted step."""
        get = self.mbs.GetObjectOutput
        return {d.name: d.force if d.maxwell else float(get(d.connector, _OUT.ForceLocal)[d.axis])
                for d in self._dampers}

    def set_carbody_load(self, force_N=(0.0, 0.0, 0.0), torque_N_m=(0.0, 0.0, 0.0)) -> None:
        """External load on the carbody for the following :meth:`advance` (needs
        ``carbody_load=True``): a force [N] at its centre of gravity and a torque [N m], both in
        global axes (x forward at the start, y left, z up; torque right-hand: +x rolls the left
        side up)."""
        if not self._carbody_load:
            raise ValueError("set_carbody_load needs MetroCar(..., carbody_load=True)")
        for load, value in ((self._load_force, force_N), (self._load_torque, torque_N_m)):
            v = np.asarray(value, dtype=float).reshape(3)
            if not np.all(np.isfinite(v)):
                raise ValueError(f"non-finite carbody load {v}")
            self.mbs.SetLoadParameter(load, "loadVector", v.tolist())
