"""The car as a whole: :class:`MetroCar`, its construction and its co-simulation interface
(bellow crushing in, airspring force laws out, :meth:`MetroCar.advance`). The parts: :mod:`.build`,
:mod:`.hooks`, :mod:`.jacobian`, :mod:`.outputs`; the model is described in :mod:`vehicle.car`."""
from __future__ import annotations

import math
from typing import Callable

import exudyn as exu
import numpy as np

from ..errors import Derailed
from ..guidance import shared_sampler
from ..params import ContactParams, TrackStructure, VehicleParams
from ..speed import SpeedProfile
from ..track import TrackGeometry
from ..wheelrail.contact_law import ContactLawTable, WheelsetParams
from ..wheelrail.track_contact import WheelsetTrackContact
from .build import CarBuild, _check_components, _contact_table
from .hooks import StepHooks
from .jacobian import JacobianReuse
from .outputs import CarOutputs

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
#: minor versions; tests/vehicle/test_vehicle.py fails loudly on any other)
EXUDYN_TESTED_MINOR = "1.13"


def _four_floats(values) -> list[float]:
    """(4,) values as a list of floats; None = zeros."""
    return [0.0] * 4 if values is None else np.asarray(values, dtype=float).reshape(4).tolist()


class MetroCar(CarBuild, StepHooks, JacobianReuse, CarOutputs):
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
        speed_m_per_s: running speed v [m/s] (0 = standing); every body starts at v.
        deceleration: contact guidance only: a :class:`~vehicle.speed.SpeedProfile`'s hold time
            and deceleration, ``(hold_s, deceleration_m_per_s2)``: the car keeps v for hold_s, then
            slows down at that rate (the drive, the track frames and the creepages follow v(t));
            None = constant speed.
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
            ``"contact"``: the wheelsets are free laterally, in yaw and along the track, held
            on the rails by the wheel-rail contact forces alone (contact table, Hertz normal
            force along the contact normal, Kalker + Shen-Hedrick-Elkins creep forces; each
            wheelset's spin is a state; a joint holds only the pitch of the non-rotating
            wheelset body). The car keeps its speed by being **driven at its centre**: a joint
            holds the carbody's position along the track tangent at s_c(t) = s_c0 + v t; its
            reaction is the force that keeps the speed (the rolling resistance of the creep
            forces, curving). Needs ``speed_m_per_s >= 0``.
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
                 wheelset_lateral_offset_m=None, track_structure: TrackStructure | None = None,
                 deceleration: tuple[float, float] | None = None):
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
        #: bogie centre x [m], front then rear
        self.bogie_x_m = np.array(p.bogie_x_m)
        #: wheelset centre x [m], wheelsets 1..4 from the front
        self.wheelset_x_m = np.array(p.wheelset_x_m)
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
        #: the speed over time (:class:`~vehicle.speed.SpeedProfile`)
        self.speed_profile = SpeedProfile(float(max(speed_m_per_s, 0.0)), *(deceleration or (0.0, 0.0)))
        if deceleration is not None and guidance != "contact":
            raise ValueError("deceleration needs guidance='contact' (the kinematic guidance prescribes a "
                             "constant speed)")
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
        """Arc length [m] of the car centre at the current time: start_s_m + s(t)."""
        return self.start_s_m + self._distance_m(self._t)

    def _distance_m(self, t):
        """Distance run since t = 0 [m]: v t at constant speed, else the speed profile's."""
        return self.speed_m_per_s * t if self.speed_profile.constant else self.speed_profile.distance(t)

    def _distance_between_m(self, t0: float, t1: float) -> float:
        """Distance run from t0 to t1 [m]: v (t1 - t0) at constant speed (rounded as it always was:
        a constant-speed run stays the same bit for bit), else the speed profile's."""
        if self.speed_profile.constant:
            return self.speed_m_per_s * (t1 - t0)
        return self.speed_profile.distance(t1) - self.speed_profile.distance(t0)

    @property
    def t_end_max_s(self) -> float:
        """Latest time [s] the front wheelset is still on the track (inf without a track; a
        decelerating car: the time its speed reaches zero at most)."""
        if not self.speed_profile.constant:
            if self.track is None:
                return self.speed_profile.end_s
            return self.speed_profile.time_at_distance(self.track.total_length_m - self._s0_wheelset[0])
        v = self.speed_m_per_s
        if self.track is None or v == 0.0:
            return math.inf
        if v > 0.0:
            return (self.track.total_length_m - self._s0_wheelset[0]) / v
        return -self._s0_wheelset[-1] / v

    #: half-width [s] of the central difference that gives the rails' rates to the contact law
    RAIL_RATE_DT_S = 1e-6

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

    def set_bellow_forces(self, F_N: np.ndarray, dF_dz_N_per_m: np.ndarray | None = None,
                          dF_dt_N_per_s: np.ndarray | None = None, z_anchor_m: np.ndarray | None = None) -> None:
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

        ``z_anchor_m``: the crushing z_now the law is anchored at, given instead of the current one
        (a linearisation varies F_N about a fixed state: with an emergency spring in series the
        current crushing moves with the law itself, so each call would move the anchor).

        Note: a jump of F_N between calls enters generalized-alpha with about half an internal
        step of delay (the step starts from the old acceleration)."""
        F, dF, Fdot = (_four_floats(v) for v in (F_N, dF_dz_N_per_m, dF_dt_N_per_s))
        if not all(map(math.isfinite, F + dF + Fdot)):
            raise ValueError(f"non-finite bellow force law: F={F}, dF/dz={dF}, dF/dt={Fdot}")
        if z_anchor_m is None:
            self._bellow_state()
            anchor = self._z.tolist()
        else:
            anchor = _four_floats(z_anchor_m)
        for (Fv, Kv, Fdv, z0v), Fk, Kk, Fdk, zk in zip(self._bellow_vars, F, dF, Fdot, anchor):
            Fv.SetValue(Fk)
            Kv.SetValue(Kk)
            Fdv.SetValue(Fdk)
            z0v.SetValue(zk)
        self._t_set.SetValue(self._t)
        self._bellow_law = list(zip(F, dF, Fdot, anchor))
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
