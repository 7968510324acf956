"""The car as a whole: :class:`MetroCar`, a façade over its parts (the model is described in
:mod:`vehicle.car`): it builds them in order, hands each what it needs, and keeps the public
interface (construction, the co-simulation's bellow crushing in and force laws out,
:meth:`MetroCar.advance`, the outputs)."""
from __future__ import annotations

import functools
import operator

import exudyn as exu
import numpy as np

from ..errors import Derailed, WheelSlide
from ..params import ContactParams, VehicleParams
from .bellows import BellowLaws
from .build import build_model
from .contact import contact_guidance
from .gradient import Gradient
from .hooks import step_hooks
from .maxwell import MaxwellDampers
from .options import CONTACT_NEWTON_REL_TOL, SPECTRAL_RADIUS, CarOptions
from .outputs import CarOutputs
from .path import CarPath
from .payload import CarbodyPayload
from .secondary import check_components
from .solver import CarSolver
from .statics import StaticReference
from .track_input import TrackInput
from .wheel_drive import SLIDE_CREEPAGE

__all__ = ["MetroCar", "SPECTRAL_RADIUS", "EXUDYN_TESTED_MINOR"]

#: exudyn minor version this module was written and measured against (the API changes between
#: minor versions; tests/vehicle/test_vehicle.py fails loudly on any other)
EXUDYN_TESTED_MINOR = "1.13"


def _part(path: str, doc: str) -> property:
    """A read-only attribute of the car that is ``path`` (dotted) of its parts."""
    return property(operator.attrgetter(path), doc=doc)


def _output(name: str):
    """The car's method ``name``: :class:`~.outputs.CarOutputs`' (none takes arguments) at the
    car's outputs."""
    function = getattr(CarOutputs, name)

    @functools.wraps(function)
    def method(self):
        return function(self.outputs)
    return method


class MetroCar:
    """Metro car on rails whose heights are prescribed wheel by wheel, standing or running.

    Composed of parts, each with its own interface: :attr:`static` (the reference state),
    :attr:`path` (where the car is over time), :attr:`contact` (contact guidance's law),
    :attr:`track_input` (the track under the car), :attr:`model` (the exudyn model as built: its
    indices), :attr:`bellows` (the airspring laws and crushing), :attr:`maxwell` (the Maxwell
    dampers' states), :attr:`hooks` (what is set before each step), :attr:`solver` and
    :attr:`outputs`.

    The keywords below are the fields of :class:`~vehicle.car.options.CarOptions`' three groups
    (:class:`~vehicle.car.options.ModelOptions`, :class:`~vehicle.car.options.RunSettings`,
    :class:`~vehicle.car.options.SolverSettings`); ``options=CarOptions(...)`` gives them grouped
    instead.

    Args:
        params: vehicle parameters (SI).
        rail_height_m: ``rail_height_m(t_s) -> (8,)`` vertical rail height [m] under each wheel
            in :data:`WHEELS` order, 0 = level; ``None`` = level track. Evaluated at the end of
            every internal time step (kinematic guidance: the contact damping uses the mean rail
            rate over the step; contact guidance: the rate at the step end, from evaluations
            1 us either side of it, so also at t = -1 us). It should be 0 at t = 0 for a
            transient-free start. On a canted ``track`` it
            adds to the heights the cant gives.
        step_s: largest internal time step [s] (default 5e-3); every :meth:`advance` is split into
            equal steps not larger than this.
        track: centre line the car runs along; ``None`` = unbounded straight level track along
            x. It must be straight and level under the whole car at the start (the start state
            is the static equilibrium on level track).
        speed_m_per_s: running speed v [m/s] (0 = standing); every body starts at v.
        deceleration: contact guidance only: a :class:`~vehicle.speed.SpeedProfile`'s hold time
            and deceleration, ``(hold_s, deceleration_m_per_s2)``: the car keeps v for hold_s, then
            slows down at that rate (the drive, the track frames and the creepages follow v(t));
            None = constant speed.
        speed_profile: a :class:`~vehicle.speed.PhasedSpeedProfile`, phases of constant
            acceleration that may stop and start (a train in service). Kinematic guidance: the
            wheelsets' guidance points run at its s(t), so the longitudinal inertia loads reach
            the car through the guidance joints at the axle centres (the cheaper longitudinal
            model). Contact guidance: only with ``drive``, torques on the wheelsets follow it.
            ``speed_m_per_s`` must be its speed at t = 0. None = constant speed.
        start_s_m: arc length [m] of the car centre (midway between the bogie centres) at
            t = 0. Default: the rear wheelset at s = 0 on a ``track``, 0 without one.
        spectral_radius: generalized-alpha spectral radius at infinite frequency, 0 <= rho <= 1
            (numerical damping of what the step cannot resolve, e.g. the ~240 Hz
            wheelset-on-contact modes; :data:`SPECTRAL_RADIUS`).
        newton_abs_tol: Newton absolute tolerance on the residual (force scale [N]); never
            below the round-off of the coordinates far from the origin (for the metro cars
            beyond 4096 m, see :attr:`.solver.CarSolver.ROUNDOFF_SAFETY`).
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
        drive: contact guidance only: a :class:`~vehicle.car.wheel_drive.WheelDrive` moves the car
            by torques on its wheelsets (traction on the motored ones, braking on all, each reacted
            on its bogie frame) instead of the joint at its centre, so that the longitudinal creep
            forces carry its inertia and the adhesion limits it; the only way a contact car runs a
            ``speed_profile`` that stops and starts. A wheelset that slides raises
            :class:`~vehicle.errors.WheelSlide`. None = driven at its centre.
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
        payload: ``payload(t_s) -> blocks`` (:class:`~vehicle.payload.PayloadBlock`): what the
            floor carries at t; before every internal step the carbody's mass, centre of gravity
            and inertia follow it (:mod:`.payload`). At t = 0 it must be centred: the car starts
            at its static equilibrium carrying it. None = the tare carbody.
        wheelset_lateral_offset_m: contact guidance only: (4,) initial lateral displacements
            [m] of the wheelsets (+ left), e.g. to release them on straight track; each starts
            at the rigid-contact height and roll of the table at that displacement (with the
            static Hertz approach), at rest laterally, the rest of the car at its static
            position. None = centred (the static equilibrium).
        grade: the line's gradient, ``grade(s_m) -> rise over run`` (> 0 rising in the running
            direction) at the car centre's arc length, read before every internal step: every
            body's weight is tilted by it (:mod:`.gradient`; the track stays in the horizontal
            plane). None = level.
        options: the options grouped (:class:`~vehicle.car.options.CarOptions`), instead of the
            keywords.
    """

    #: see :data:`.options.CONTACT_NEWTON_REL_TOL`
    CONTACT_NEWTON_REL_TOL = CONTACT_NEWTON_REL_TOL

    #: see :attr:`.solver.CarSolver.JACOBIAN_HEADING_TOL_RAD`
    JACOBIAN_HEADING_TOL_RAD = CarSolver.JACOBIAN_HEADING_TOL_RAD

    def __init__(self, params: VehicleParams, rail_height_m=None, step_s=None, *,
                 options: CarOptions | None = None, **keywords):
        positional = {"rail_height_m": rail_height_m, "step_s": step_s}
        keywords.update((name, value) for name, value in positional.items() if value is not None)
        self.params = params
        #: what the car was asked for (:class:`~.options.CarOptions`)
        self.options = options = CarOptions.given(options, keywords)
        model, run = options.model, options.run
        flexible = model.track_structure.flexible
        #: the payload on the floor (:class:`~.payload.CarbodyPayload`; None: the tare carbody throughout)
        self.payload = CarbodyPayload(params, run.payload) if run.payload is not None else None
        static = StaticReference.of(params, self.payload.initial_payload_kg if self.payload else 0.0)
        check_components(params)
        #: where the car is along its track over time (:class:`~.path.CarPath`)
        self.path = CarPath.plan(run, static.wheelset_x_m, model.contact_guidance, model.drive is not None)
        #: the wheel-rail contact (:class:`~.contact.ContactGuidance`; None: kinematic guidance)
        self.contact = None
        if model.contact_guidance:
            self.contact = contact_guidance(params, model.contact or ContactParams(), static, self.path,
                                            flexible)
            static = static.with_wheelset_z_m(self.contact.wheelset_z_m)
        #: the reference configuration (:class:`~.statics.StaticReference`)
        self.static = static
        #: the track under the car (:class:`~.track_input.TrackInput`)
        self.track_input = TrackInput(self.path, run.rail_height_m, run.irregularity,
                                      params.contact_spacing_m, model.contact_guidance)
        rail0 = self.track_input.rail_heights_m(0.0)
        self.SC = exu.SystemContainer()
        self.mbs = self.SC.AddSystem()
        #: the exudyn model as built and assembled (:class:`~.build.CarModel`)
        self.model = build_model(self.mbs, params, static, self.path, model, self.contact,
                                 options.solver.step_s, rail0, self.payload.initial if self.payload else None)
        #: the airspring force laws and the bellows' crushing (:class:`~.bellows.BellowLaws`)
        self.bellows = BellowLaws(self.mbs, self.model, static, params)
        #: the Maxwell dampers' states (:class:`~.maxwell.MaxwellDampers`)
        self.maxwell = MaxwellDampers(self.model.optional)
        #: what is set before each step (:mod:`.hooks`)
        self.hooks = step_hooks(self.track_input, self.model, static.wheelset_x_m, self.contact, rail0,
                                self.payload_kg)
        #: the solver (:class:`~.solver.CarSolver`)
        self.solver = CarSolver(self.mbs, options.solver, options.solver.relative_tolerance(model.contact_guidance),
                                self._pre_step, refresh_after_turn=model.contact_guidance,
                                # two axlebox springs on each of the four wheelsets: their longitudinal
                                # stiffness sets the residual's round-off floor far from the origin
                                roundoff_stiffness_N_per_m=8.0 * params.primary_stiffness_x_N_per_m)
        if self.maxwell.active:
            self.mbs.SetPostStepUserFunction(self.maxwell.post_step)
        #: the line's gradient (:class:`~.gradient.Gradient`; None: level)
        self.gradient = None
        if run.grade is not None:
            self.gradient = Gradient(self.mbs, run.grade, params.gravity_m_per_s2)
            self.gradient.pre_step(self.mbs, self.path.centre_s_m(0.0), 0.0)
        #: the quantities the car reports (:class:`~.outputs.CarOutputs`)
        self.outputs = CarOutputs(self.mbs, self.model, params, static, self.track_input, self.contact,
                                  self.solver, flexible)

    # --- the run, as attributes of the car
    guidance = _part("options.model.guidance", '"kinematic" or "contact" (see the class doc)')
    track_structure = _part("options.model.track_structure",
                            "the track under the rails (:class:`~vehicle.params.TrackStructure`)")
    step_s = _part("options.solver.step_s", "largest internal time step [s]")
    track = _part("path.track", "centre line the car runs along (None: straight level track along x)")
    speed_m_per_s = _part("path.speed_m_per_s", "running speed [m/s]")
    start_s_m = _part("path.start_s_m", "arc length [m] of the car centre at t = 0")
    speed_profile = _part("path.speed_profile", "the speed over time (:class:`~vehicle.speed.SpeedProfile`)")
    t_end_max_s = _part("path.t_end_max_s", "latest time [s] the front wheelset is still on the track "
                        "(inf without a track; a decelerating car: the time its speed reaches zero at most)")
    Q_static_N = _part("static.wheel_load_N", "static vertical wheel load on level track [N]")
    bogie_x_m = _part("static.bogie_x_m", "bogie centre x [m], front then rear")
    wheelset_x_m = _part("static.wheelset_x_m", "wheelset centre x [m], wheelsets 1..4 from the front")
    bellow_height_m = _part("static.bellow_height_m", "nominal height [m] of the airsprings: the distance "
                            "of their plates at static equilibrium (``airspring_upper_height_m - "
                            "airspring_lower_height_m``)")
    airspring_in_series = _part("static.airspring_in_series",
                                "the airsprings include an emergency spring and/or a vertical bumpstop")
    contact_params = _part("contact.params", "contact parameters (guidance='contact')")
    contact_table = _part("contact.table", "the contact table in use (guidance='contact')")
    t_s = _part("solver.t_s", "current simulation time [s]")
    jacobian_count = _part("solver.jacobian_count", "fresh Jacobians computed (diagnostics)")

    @property
    def s_m(self) -> float:
        """Arc length [m] of the car centre at the current time: start_s_m + s(t)."""
        return self.path.centre_s_m(self.solver.t_s)

    def static_bellow_forces_N(self) -> np.ndarray:
        """(4,) airspring forces [N] carrying the carbody in static equilibrium on level track."""
        return np.full(4, self.static.bellow_force_N)

    # --- the co-simulation interface
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
        self.bellows.set(self.solver.t_s, F_N, dF_dz_N_per_m, dF_dt_N_per_s, z_anchor_m)

    def bellow_crushing(self) -> tuple[np.ndarray, np.ndarray]:
        """Bellow crushing z [m] and its rate [m/s], each (4,) in :data:`BELLOWS` order.

        z = nominal bellow height - (p_upper_plate - p_lower_plate) . n, n the bellow axis
        (the z axis of the mid-frame between bogie frame and carbody, see
        :func:`.secondary.add_airsprings`), positive in compression, 0 at static equilibrium on
        level track (bellow at nominal height). In a curve the carbody rolls outward: the outer
        bellows are crushed (z > 0), the inner ones extend."""
        return self.bellows.crushing(self.solver.t_s)

    def airspring_crushing_m(self) -> np.ndarray:
        """(4,) crushing [m] of each whole airspring (bellow + emergency spring), :data:`BELLOWS`
        order, positive in compression, 0 at static equilibrium: z = h0 - d_z as in
        :meth:`bellow_crushing`, which without an emergency spring or vertical bumpstop is the
        same number and with them the bellow's own share."""
        return self.bellows.airspring_crushing_m(self.solver.t_s)

    def advance(self, t_end_s: float) -> None:
        """Integrate from :attr:`t_s` to ``t_end_s`` [s] in equal steps <= ``step_s``."""
        span = t_end_s - self.solver.t_s
        if span < -1e-12:
            raise ValueError(f"advance: t_end_s={t_end_s} is before t_s={self.solver.t_s}")
        if span <= 1e-12:
            return
        if t_end_s > self.t_end_max_s + 1e-9:
            raise ValueError(f"advance: at t_end_s={t_end_s} s the front wheelset would have "
                             f"left the track (t_end_max_s={self.t_end_max_s} s)")
        ok = self.solver.solve(t_end_s, self.path.reach_m(t_end_s))
        if self.contact is not None and self.hooks.left_table is not None:
            t_out, y_out = self.hooks.left_table
            lo, hi = self.contact.track_contact.table.y_range_m
            raise Derailed(
                f"a wheelset left the contact table at t = {t_out:.4f} s (derailment or "
                f"flange climb): lateral positions {np.round(1e3 * np.array(y_out), 2)} mm, "
                f"the table covers {1e3 * lo:g} .. {1e3 * hi:g} mm relative to the rails")
        if self.hooks.sliding is not None:
            t_out, creepage = self.hooks.sliding
            raise WheelSlide(
                f"wheelset(s) {', '.join(str(i + 1) for i in np.flatnonzero(np.abs(creepage) > SLIDE_CREEPAGE))} slid "
                f"at t = {t_out:.4f} s: longitudinal creepages {np.round(100 * creepage, 1)} % (sliding beyond "
                f"{100 * SLIDE_CREEPAGE:g} %): the {'traction' if self.hooks.torques.force_N > 0 else 'braking'} asked "
                f"{abs(self.hooks.torques.force_N) / 1e3:.1f} kN in all, more than the adhesion at mu = "
                f"{self.contact.params.friction_coefficient:g} gives those wheelsets")
        if not ok:
            message = f"exudyn: time integration failed at t={self.solver.t_s} s (advance to {t_end_s} s)"
            airborne = self.outputs.airborne_wheelsets()
            if airborne:  # said, not concluded: a wheel lifts for milliseconds on an impact too
                message += f"; wheelset(s) {', '.join(map(str, airborne))} had no wheel in contact"
            raise RuntimeError(message)
        self.solver.reached(t_end_s)

    def _pre_step(self, mbs, t: float) -> bool:
        """PreStep user function: withdraws the Jacobian request SolveSteps makes at its start
        when the stored Jacobian is kept (:meth:`.solver.CarSolver.keep_jacobian`), gives the
        Maxwell laws the step size, sets what the track sets (:mod:`.hooks`) and tells the
        solver the track's heading."""
        solver, hooks = self.solver, self.hooks
        if solver.jacobian_may_skip:
            solver.keep_jacobian()
        if self.maxwell.active:
            self.maxwell.set_step_size(mbs, t)
        if self.gradient is not None:   # at the car centre's place on the profile
            s_centre = self.path.centre_s_m(t)
            hooks.gravity_along_m_per_s2 = self.gradient.along_track_m_per_s2(s_centre)
        ok = hooks.pre_step(mbs, t)
        if self.gradient is not None:   # the heading there, as the hooks found it
            self.gradient.pre_step(mbs, s_centre, hooks.centre_heading_rad)
        if self.payload is not None:
            self.payload.pre_step(mbs, self.model.carbody, t)
            solver.carbody_mass_kg = self.payload.carbody_mass_kg
        solver.heading_rad = hooks.heading_rad
        solver.speed_m_per_s = hooks.speed_m_per_s
        return ok

    def floor_heights_m(self, points_xy_m) -> np.ndarray:
        """(n,) height [m] of the floor at ``points_xy_m`` ((n, 2): x along the car from its
        centre, y across, + left), see :meth:`.outputs.CarOutputs.floor_heights_m`."""
        return self.outputs.floor_heights_m(points_xy_m)

    def payload_kg(self) -> float:
        """The payload the carbody carries now [kg] (0 without one)."""
        return self.payload.payload_kg if self.payload is not None else 0.0

    def set_carbody_load(self, force_N=(0.0, 0.0, 0.0), torque_N_m=(0.0, 0.0, 0.0)) -> None:
        """External load on the carbody for the following :meth:`advance` (needs
        ``carbody_load=True``): a force [N] at its centre of gravity and a torque [N m], both in
        global axes (x forward at the start, y left, z up; torque right-hand: +x rolls the left
        side up)."""
        if not self.options.model.carbody_load:
            raise ValueError("set_carbody_load needs MetroCar(..., carbody_load=True)")
        for load, value in ((self.model.load_force, force_N), (self.model.load_torque, torque_N_m)):
            v = np.asarray(value, dtype=float).reshape(3)
            if not np.all(np.isfinite(v)):
                raise ValueError(f"non-finite carbody load {v}")
            self.mbs.SetLoadParameter(load, "loadVector", v.tolist())

    # --- the outputs (:class:`~.outputs.CarOutputs`)
    wheel_loads_N = _output("wheel_loads_N")
    contact_state = _output("contact_state")
    lateral_wheel_forces_N = _output("lateral_wheel_forces_N")
    wheelset_lateral_forces_N = _output("wheelset_lateral_forces_N")
    wheelset_longitudinal_forces_N = _output("wheelset_longitudinal_forces_N")
    adhesion_used = _output("adhesion_used")
    wheelset_lateral_to_rails_m = _output("wheelset_lateral_to_rails_m")
    wheelset_lateral_displacement_m = _output("wheelset_lateral_displacement_m")
    angle_of_attack_rad = _output("angle_of_attack_rad")
    flange_contact = _output("flange_contact")
    floor_accelerations_m_per_s2 = _output("floor_accelerations_m_per_s2")
    carbody_roll_rad = _output("carbody_roll_rad")
    track_deflection = _output("track_deflection")
    roll_to_track_rad = _output("roll_to_track_rad")
    carbody_lateral_m = _output("carbody_lateral_m")
    secondary_lateral_m = _output("secondary_lateral_m")
    bumpstop_forces_N = _output("bumpstop_forces_N")
    anti_roll_bar_moments_N_m = _output("anti_roll_bar_moments_N_m")
    traction_rod_forces_N = _output("traction_rod_forces_N")
    damper_forces_N = _output("damper_forces_N")

    # --- private names that code outside vehicle/ reads (cosim/kinds/stability.py, tests/cosim,
    # benchmarks): kept as they were, each now a part's attribute
    _wr = _part("contact.track_contact", "the contact law (contact guidance)")
    _wr_index = _part("model.contact_index", "the contact object's coordinates in the system vectors")
    _solver = _part("solver.main", "the exudyn solver")
    _carbody = _part("model.carbody", "the carbody")
    _bogies = _part("model.bogies", "the bogie frames")
    _wheelsets = _part("model.wheelsets", "the wheelsets")
    _drive = _part("model.drive", "the drive joint (contact guidance)")
    _bellows = _part("model.airsprings.connectors", "the airspring connectors")
    _bellow_law = _part("bellows.laws", "the airspring laws as set")
    _maxwell = _part("maxwell.dampers", "the Maxwell dampers")

    @property
    def _bellow_t(self):
        """Time of the cached bellow crushing; None forgets it (the state was moved)."""
        return self.bellows.crushing_time_s

    @_bellow_t.setter
    def _bellow_t(self, value) -> None:
        self.bellows.crushing_time_s = value
