"""What the car sets before every internal step from the track under it (:mod:`.track_input`):
the guidance frames and, with kinematic guidance, the rail heights of the Hertz contacts
(:class:`KinematicStepHooks`), with contact guidance the track frames and rails of the contact
law (:class:`ContactStepHooks`)."""
from __future__ import annotations

import math
from typing import Callable

import exudyn as exu
import numpy as np

from .build import CarModel
from .contact import ContactGuidance
from .track_input import TrackInput
from .wheel_drive import SLIDE_CREEPAGE, SLIDE_SPEED_M_PER_S


class StepHooks:
    """The guidance frames set from the track before each step (common to both guidances)."""

    def __init__(self, track: TrackInput, model: CarModel, wheelset_x_m: np.ndarray):
        self.track = track
        self._model = model
        # x [m] of each wheelset's guidance point at t = 0 (see _Builder.wheelset_guidance)
        self._joint_x_m = [float(x) + track.path.x0_m for x in wheelset_x_m]
        #: track heading under wheelset 1 at the last step end [rad]
        self.heading_rad = 0.0
        #: track heading at the car centre at the last step end [rad]
        self.centre_heading_rad = 0.0
        #: gravity's component along the track in the running direction [m/s^2] (a gradient;
        #: set by the car before each step)
        self.gravity_along_m_per_s2 = 0.0
        #: the car's speed at the last step end [m/s] (a speed profile that stops and starts, with
        #: kinematic guidance or driven through the wheels; otherwise its constant speed)
        self.speed_m_per_s = float(track.path.speed_m_per_s)
        #: the torques of a contact car driven through its wheels (:mod:`.wheel_drive`), else None
        self.torques = None
        #: (t, longitudinal creepages) when a wheelset driven through its wheels slid, else None
        self.sliding = None

    def set_guidance(self, track_state) -> None:
        """Guidance offsets (see :meth:`.build._Builder.wheelset_guidance`,
        :meth:`.build._Builder.drive`) for the given track state (rows as
        :meth:`.track_input.TrackInput.rows` gives them; contact guidance: its fifth row is the
        car centre's)."""
        path = self.track.path
        if isinstance(track_state, np.ndarray):
            track_state = track_state.tolist()
        centre = track_state[4][2] if len(track_state) > 4 else 0.5 * (track_state[0][2] + track_state[3][2])
        self.centre_heading_rad = centre
        if self._model.drive_vars is not None:
            (xi, rz), (x, y, psi, *_) = self._model.drive_vars, track_state[4]
            xi.SetValue(math.cos(psi) * (x - path.x0_m) + math.sin(psi) * y)
            rz.SetValue(psi)
        for (xi, eta, rx, ry, rz), (x, y, psi, cant, _, _), x0 in zip(
                self._model.guidance_vars, track_state, self._joint_x_m):
            dx = x - x0
            c, s = math.cos(psi), math.sin(psi)
            if cant == 0.0:
                xi.SetValue(c * dx + s * y)
                eta.SetValue(-s * dx + c * y)
                rz.SetValue(psi)
                if path.canted:
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


class KinematicStepHooks(StepHooks):
    """Kinematic guidance: before each step the guidance frames (moved across by the lateral
    alignment) and the Hertz contacts' rail heights and rates."""

    def __init__(self, track: TrackInput, model: CarModel, wheelset_x_m: np.ndarray, rail0_m: np.ndarray):
        super().__init__(track, model, wheelset_x_m)
        self._rail_cache = (0.0, rail0_m)  # (t, heights) of the last preStep evaluation
        self._rail_set = None  # (heights, rates) last given to the contacts' symbolic variables

    def pre_step(self, mbs, t: float) -> bool:
        """PreStep: guidance offsets and rail heights at the step end t, mean rail rate over the
        step."""
        track, path = self.track, self.track.path
        state = track.rows(t) if path.guided else None
        if path.guided:
            self.set_guidance(state if track.irregularity is None else self._aligned(state, t))
            self.heading_rad = float(state[0, 2])
            if not path.speed_profile.constant:
                self.speed_m_per_s = float(path.speed_profile.speed(t))
        if track.rail_height_m is None and not path.canted and track.irregularity is None:
            return True  # level rails: nothing else changes
        t0 = mbs.systemData.GetTime(exu.ConfigurationType.StartOfStep)
        tc, zc = self._rail_cache
        z0 = zc if t0 == tc else track.rail_heights_m(t0)
        z1 = track.rail_heights_m(t, state)
        v = (z1 - z0) / (t - t0) if t > t0 else np.zeros(8)
        values = (z1.tolist(), v.tolist())
        if values != self._rail_set:  # held rails (e.g. after the twist ramp): nothing to set
            for (rz, rv), zj, vj in zip(self._model.rail_vars, *values):
                rz.SetValue(zj)
                rv.SetValue(vj)
            self._rail_set = values
        self._rail_cache = (t, z1)
        return True

    def _aligned(self, track_state, t: float) -> list[tuple[float, ...]]:
        """The track state with each wheelset's point moved across the track by the lateral
        alignment of the irregularity (horizontally, normal to the tangent)."""
        lat = self.track.irregularity_at(t)[0]
        return [(x - math.sin(psi) * e, y + math.cos(psi) * e, psi, *rest)
                for (x, y, psi, *rest), e in zip(track_state.tolist(), lat.tolist())]


class ContactStepHooks(StepHooks):
    """Contact guidance: before each step the drive and the wheelsets' guidance, the track frames
    and the rails of the contact law, each wheelset's where it is along the track."""

    def __init__(self, track: TrackInput, model: CarModel, wheelset_x_m: np.ndarray,
                 contact: ContactGuidance, payload_kg: Callable[[], float] | None = None):
        super().__init__(track, model, wheelset_x_m)
        self._contact = contact.track_contact
        self.torques = model.wheel_torques
        self._payload_kg = payload_kg or (lambda: 0.0)
        self._index = model.contact_index
        #: (t, wheelset lateral positions) when a wheelset left the contact table, else None
        self.left_table = None
        self._frames_t = None
        self.set_contact_track(0.0)

    def set_contact_track(self, t: float, state=None) -> None:
        """Track frames and rail offsets, with their rates, at the step end t.

        The rates are those at t (a central difference over
        +-:data:`~.track_input.RAIL_RATE_DT_S`), not the means over the step: the creep forces
        see the rail velocity, and a step mean lags it by half a step, a first-order error (the
        straight irregular run's largest lateral wheel force moved 3015 / 2947 / 2921 N at 5 /
        2.5 / 1.25 ms with step means, 2926 / 2928 / 2931 N with the rates at t: car alone, 10 s
        of scenarios/straight_irregular.yaml)."""
        state = self.track.rows(t)[:4] if state is None else state
        self._frames_t = t
        self._contact.set_track(state, self.track.contact_rails(t))

    def pre_step(self, mbs, t: float) -> bool:
        """PreStep: guidance offsets (the drive at the car centre, the wheelsets' pitch), track
        frames and rail offsets at the step end t, each wheelset's at its own arc length; stops
        the integration (advance raises) when a wheelset has left the contact table (derailed).

        The wheelsets are free along the track: wheelset i's frame is set at s0_i + v t plus its
        offset along the tangent, predicted at the step end from the state at its start
        (position + h velocity), so that the law sees the track where the wheelset is. (Holding
        the offset of the step start instead lags a step: the R 150 m twisted curve's ΣY then
        drifted by 22 N, 0.2 %, with every halving of the steps.) A frame a few millimetres off
        along a curve would hand the law a spurious angle of attack kappa dx (3e-5 rad for 3 mm
        at R = 100 m: ~0.2 kN of lateral creep force per wheel)."""
        track, path, wr = self.track, self.track.path, self._contact
        t0 = mbs.systemData.GetTime(exu.ConfigurationType.StartOfStep)
        sd, idx = mbs.systemData, self._index
        q, q_t = sd.GetODE2Coordinates()[idx], sd.GetODE2Coordinates_t()[idx]
        if path.guided:  # the offsets predicted at t (the frames may be of t0 or, on a retry, of t)
            track.wheelset_offsets_m = (track.wheelset_offsets_m + wr.longitudinal_offsets(q, q_t, t - t0)
                                        - path.distance_between_m(self._frames_t, t))
        if self.torques is not None:
            self._set_torques(mbs, q, q_t, t0, t)
            if np.abs(self.torques.creepage).max() > SLIDE_CREEPAGE:
                self.sliding = (t0, self.torques.creepage.copy())
                return False
        if not path.speed_profile.constant:          # the law's frames and creepages run at v(t)
            wr.set_speed(path.speed_profile.speed(t))
        state = track.rows(t)
        if path.guided:
            self.set_guidance(state)
            self.heading_rad = float(state[0, 2])
        self.set_contact_track(t, state[:4])
        y, inside = wr.lateral_positions(q, q_t, t - t0)
        if not inside:  # predicted at the step end from the state at its start
            self.left_table = (t0, y)
            return False
        return True


    def _set_torques(self, mbs, q, q_t, t0: float, t: float) -> None:
        """The wheel torques for the step [t0, t] (:mod:`.wheel_drive`): the profile's mean
        acceleration over it, the car's mean offset from the profile predicted at t and its rate
        at t0 (the wheelsets' velocity along their tangents less the profile's speed)."""
        profile, wr = self.track.path.speed_profile, self._contact
        v0, v1 = float(profile.speed(t0)), float(profile.speed(t))
        a_ref = (v1 - v0) / (t - t0) if t > t0 else 0.0
        along = wr.longitudinal_offsets(q, q_t, 1.0) - wr.longitudinal_offsets(q)   # exact: linear in h
        offset = float(np.mean(self.track.wheelset_offsets_m))
        self.torques.set(mbs, a_ref, offset, float(np.mean(along)) - v0, self._payload_kg(),
                         self.gravity_along_m_per_s2)
        spin = q_t[6::wr.m]                                 # each wheelset's spin rate [rad/s]
        self.torques.creepage = (along - wr.r0 * spin) / np.maximum(np.abs(along), SLIDE_SPEED_M_PER_S)
        if not profile.constant:  # the kept Jacobian's speed rule (.solver) follows the car
            self.speed_m_per_s = v1


def step_hooks(track: TrackInput, model: CarModel, wheelset_x_m: np.ndarray, contact: ContactGuidance | None,
               rail0_m: np.ndarray, payload_kg: Callable[[], float] | None = None
               ) -> KinematicStepHooks | ContactStepHooks:
    """The hooks of a car with the ``contact`` guidance (None: kinematic guidance, its rails at
    ``rail0_m`` at t = 0); ``payload_kg()``: the payload now (a car driven through its wheels)."""
    if contact is None:
        return KinematicStepHooks(track, model, wheelset_x_m, rail0_m)
    return ContactStepHooks(track, model, wheelset_x_m, contact, payload_kg)
