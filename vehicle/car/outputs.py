"""What the car reports at its current state: wheel loads, the wheel-rail forces and wheelset
positions, roll, the secondary components' forces (:class:`CarOutputs`; the bellows' crushing:
:mod:`.bellows`)."""
from __future__ import annotations

import math

import exudyn as exu
import numpy as np

from ..params import VehicleParams
from ..wheelrail.track_contact import WheelContactOutputs
from .build import CarModel
from .contact import ContactGuidance
from .solver import CarSolver
from .statics import StaticReference
from .track_input import TrackInput

_OUT = exu.OutputVariableType


class CarOutputs:
    """Outputs at the current state of the car's system ``mbs`` (each in SI units, in
    :data:`~vehicle.params.WHEELS` / wheelset / bogie order): the ``model`` built in it, the
    ``track`` it runs on, its ``contact`` (None: kinematic guidance), its ``solver`` (the time
    of the state)."""

    def __init__(self, mbs, model: CarModel, p: VehicleParams, static: StaticReference, track: TrackInput,
                 contact: ContactGuidance | None, solver: CarSolver, flexible_track: bool):
        self._mbs, self._model, self._params = mbs, model, p
        self._wheelset_z_m, self._bogie_x_m = static.wheelset_z_m, static.bogie_x_m
        self._track, self._contact, self._solver = track, contact, solver
        self._flexible = flexible_track
        self._contact_cache = (None, None)  # ((t, advance), WheelContactOutputs)

    def airborne_wheelsets(self) -> list[int]:
        """Wheelsets (1..4) with neither wheel in contact at the current state."""
        Q = self.wheel_loads_N() if self._contact is None else self.contact_state().normal_N
        return [i + 1 for i in range(4) if Q[2 * i] <= 0.0 and Q[2 * i + 1] <= 0.0]

    def wheel_loads_N(self) -> np.ndarray:
        """(8,) vertical wheel-rail forces Q >= 0 [N] at the current state, :data:`WHEELS` order.

        Kinematic guidance: the vertical Hertz contact force (global vertical). Contact
        guidance: the component of the whole contact force (normal force and creep forces) of
        the rail on the wheel normal to the track plane (the track frame's z; on canted track
        perpendicular to the canted plane), i.e. EN 14363's Q in the track frame."""
        if self._contact is not None:
            return self.contact_state().force_track_N[:, 2].copy()
        get = self._mbs.GetObjectOutput
        # the contact connector's force f acts as -f = +Q e_z on the wheel
        return np.array([-get(co, _OUT.Force)[2] for co in self._model.wheel_contacts])

    def contact_state(self) -> WheelContactOutputs:
        """The contact of every wheel at the current state (contact guidance only; see
        :class:`~vehicle.wheelrail.track_contact.WheelContactOutputs`: normal forces, forces in
        the track frame, contact angles, saturation, creepages, wheelset lateral positions and
        yaw). Evaluated once per state (cached)."""
        if self._contact is None:
            raise ValueError("contact_state needs guidance='contact'")
        key = (self._solver.t_s, self._solver.advance_count)
        if self._contact_cache[0] != key:
            sd = self._mbs.systemData
            idx = self._model.contact_index
            out = self._contact.track_contact.outputs(sd.GetODE2Coordinates()[idx].tolist(),
                                                      sd.GetODE2Coordinates_t()[idx].tolist())
            self._contact_cache = (key, out)
        return self._contact_cache[1]

    def lateral_wheel_forces_N(self) -> np.ndarray:
        """(8,) lateral wheel-rail forces Y [N], :data:`WHEELS` order: the force of the rail on
        the wheel along the track plane's lateral axis, **positive towards the track centre**
        (on the left wheel towards -y, on the right towards +y): the sense in which a flange
        force pushes the wheelset back, so Y/Q > 0 is the flanging wheel's value in Nadal's
        criterion. Includes the normal force's lateral component and the creep forces.
        Kinematic guidance: NaN (no lateral wheel-rail force is modelled; the guidance joint
        carries it)."""
        if self._contact is None:
            return np.full(8, np.nan)
        Fl = self.contact_state().force_track_N[:, 1]
        return np.where(np.arange(8) % 2 == 0, -Fl, Fl)

    def wheelset_lateral_forces_N(self) -> np.ndarray:
        """(4,) sum of the two wheels' lateral forces per wheelset [N] in the track frame,
        positive to the left (the force of the rails on the wheelset; the track receives the
        opposite): Y_R - Y_L with :meth:`lateral_wheel_forces_N`' inward-positive Y, i.e.
        EN 14363's track shifting force sum Y. NaN with kinematic guidance."""
        if self._contact is None:
            return np.full(4, np.nan)
        Fl = self.contact_state().force_track_N[:, 1]
        return Fl[0::2] + Fl[1::2]

    def wheelset_longitudinal_forces_N(self) -> np.ndarray:
        """(4,) sum of the two wheels' longitudinal creep forces per wheelset [N], along the track
        tangent, positive forward (the force of the rails on the wheelset: > 0 in traction, < 0
        braking). NaN with kinematic guidance."""
        if self._contact is None:
            return np.full(4, np.nan)
        Fx = self.contact_state().force_track_N[:, 0]
        return Fx[0::2] + Fx[1::2]

    def adhesion_used(self) -> np.ndarray:
        """(4,) per wheelset the share of its adhesion its traction or braking uses:
        |F_x,L + F_x,R| / (mu (N_L + N_R)), the utilised adhesion F_x / N over the friction
        coefficient mu of the contact. 1 is the limit: the creep forces saturate at mu N and the
        wheelset slides. The sum over the two wheels leaves out what they exchange in a curve
        (steering: the outer wheel pulled back, the inner pushed, equal and opposite), which takes
        its own share of each wheel's mu N. NaN with kinematic guidance."""
        if self._contact is None:
            return np.full(4, np.nan)
        state = self.contact_state()
        mu = self._contact.params.friction_coefficient
        Fx, N = state.force_track_N[:, 0], state.normal_N
        return np.abs(Fx[0::2] + Fx[1::2]) / np.maximum(mu * (N[0::2] + N[1::2]), 1e-9)

    def wheelset_lateral_to_rails_m(self) -> np.ndarray:
        """(4,) wheelset lateral displacements relative to their rails [m] (+ left; the track's
        irregularities subtracted), contact guidance only."""
        return self.contact_state().lateral_to_rails_m

    def wheelset_lateral_displacement_m(self) -> np.ndarray:
        """(4,) lateral displacement [m] of each wheelset centre from the design track centre
        line, in the track plane at the wheelset's arc length, positive to the left (track
        irregularities are not subtracted: the lateral position relative to the rails is
        ``contact_state().lateral_to_rails_m``). ~0 with kinematic guidance (prescribed)."""
        if self._contact is not None:
            return self.contact_state().lateral_m.copy()
        return self._wheelset_pose()[0]

    def angle_of_attack_rad(self) -> np.ndarray:
        """(4,) yaw [rad] of each wheelset relative to the track tangent at its arc length,
        positive counter-clockwise seen from above (the wheelset's x axis turned to the left).
        In a left-hand curve a leading wheelset flanging on the outer (right) rail has a
        negative angle of attack. ~0 with kinematic guidance (prescribed)."""
        if self._contact is not None:
            return self.contact_state().yaw_rad.copy()
        return self._wheelset_pose()[1]

    def flange_contact(self) -> np.ndarray:
        """(8,) bool: the wheel touches its rail with a contact angle above
        ``ContactParams.flange_angle_rad`` (default 0.7 rad, 40 deg: the flange flank, see
        :class:`~vehicle.params.ContactParams`) and a positive normal force. All False with
        kinematic guidance."""
        if self._contact is None:
            return np.zeros(8, dtype=bool)
        c = self.contact_state()
        return (c.gamma_rad > self._contact.params.flange_angle_rad) & (c.normal_N > 0.0)

    def _wheelset_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """(lateral offsets of the rail-level points, yaw angles) of the wheelsets relative to
        the track (from the body states; kinematic guidance)."""
        body = self._mbs.GetObjectOutputBody
        y, yaw = [], []
        for wheelset, (xt, yt, psi, *_) in zip(self._model.wheelsets, self._track.rows(self._solver.t_s)):
            A = np.asarray(body(wheelset, _OUT.RotationMatrix)).reshape(3, 3)
            # the rail-level point the guidance holds (the centre moves across when the
            # wheelset rolls on raised rails)
            x, yb, _ = np.asarray(body(wheelset, _OUT.Position)) - self._wheelset_z_m * A[:, 2]
            y.append(-math.sin(psi) * (x - xt) + math.cos(psi) * (yb - yt))
            yaw.append(math.atan2(A[1, 0], A[0, 0]) - psi)
        yaw = (np.array(yaw) + math.pi) % (2.0 * math.pi) - math.pi
        return np.array(y), yaw

    def floor_accelerations_m_per_s2(self) -> np.ndarray:
        """(3, 3) acceleration [m/s^2] at the floor points (:data:`~vehicle.params.FLOOR_POINTS`,
        columns) along the carbody's own axes x (forward), y (left), z (up) (rows), as an
        accelerometer fixed to the floor measures it: the specific force a - g, so 1 g upwards at
        rest, and in a curve the lateral acceleration the track's cant does not compensate. The
        point's acceleration includes the body's rotation (angular acceleration and velocity)."""
        body = self._mbs.GetObjectOutputBody
        A = np.asarray(body(self._model.carbody, _OUT.RotationMatrix)).reshape(3, 3)
        g = np.array([0.0, 0.0, -self._params.gravity_m_per_s2])
        out = np.empty((3, 3))
        for j, point in enumerate(self._params.floor_points_m):
            a = np.asarray(body(self._model.carbody, _OUT.Acceleration, localPosition=list(point)))
            out[:, j] = A.T @ (a - g)
        return out

    def floor_heights_m(self, points_xy_m) -> np.ndarray:
        """(n,) height [m] above the rail-top plane z = 0 of the floor points ``points_xy_m``
        ((n, 2): x along the car from its centre, + forward, y across, + left), points of the
        carbody at ``floor_height_m`` (moving with its heave, pitch and roll; read at the node,
        the tare centre of gravity, whatever the payload)."""
        body = self._mbs.GetObjectOutputBody
        dz = self._params.floor_height_m - self._params.carbody_cog_height_m
        return np.array([body(self._model.carbody, _OUT.Position, localPosition=[float(x), float(y), dz])[2]
                         for x, y in np.asarray(points_xy_m, dtype=float).reshape(-1, 2)])

    def carbody_roll_rad(self) -> float:
        """Carbody roll angle [rad], right-hand about its own x axis (forward): positive = left
        side up, i.e. the outward roll of a left-hand curve (negative in a right-hand one).
        Yaw-independent: the angle of the body's y axis above the horizontal plane."""
        A = np.asarray(self._mbs.GetObjectOutputBody(self._model.carbody, _OUT.RotationMatrix))
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
        if self._contact is not None:
            q = self._mbs.systemData.GetODE2Coordinates()
            for i, node in enumerate(self._model.track_nodes):
                i0 = int(self._mbs.GetNodeODE2Index(node))
                out[i] = q[i0:i0 + 3]
            return out
        body = self._mbs.GetObjectOutputBody
        for i, b in enumerate(self._model.track_bodies):
            out[i, 1] = body(b, _OUT.Displacement)[2]
            out[i, 2] = body(b, _OUT.Rotation)[0]
        return out

    def roll_to_track_rad(self) -> np.ndarray:
        """(3,) roll [rad] of the carbody, the front and the rear bogie frame relative to the
        track plane (the design track's cant at the car centre and at each bogie centre; the
        irregularities' cross-level is not subtracted), in :meth:`carbody_roll_rad`'s
        convention (positive: left side up)."""
        body = self._mbs.GetObjectOutputBody
        rolls = []
        for b in [self._model.carbody, *self._model.bogies]:
            A = np.asarray(body(b, _OUT.RotationMatrix)).reshape(3, 3)
            rolls.append(math.atan2(A[2, 1], A[2, 2]))
        path = self._track.path
        if path.sampler is None or not path.canted:
            return np.array(rolls)
        s = path.centre_s_m(self._solver.t_s)
        plane = [-row[3] for row in path.sampler.at([s, s + self._bogie_x_m[0], s + self._bogie_x_m[1]])]
        return np.array(rolls) - np.array(plane)

    def carbody_lateral_m(self) -> float:
        """Lateral offset [m] of the carbody centre of gravity from the track centre line,
        positive to the left, measured horizontally along the track normal at the car centre's
        nominal arc length :attr:`~vehicle.car.MetroCar.s_m`. In a curve of radius R this includes the geometric
        offset of a body between bogies on the chord: (bogie centre distance)^2 / (8 R) to the
        inside (0.125 m at R = 100 m) -- see :meth:`secondary_lateral_m` for the suspension
        deflection alone."""
        x, y, _ = self._mbs.GetObjectOutputBody(self._model.carbody, _OUT.Position)
        path = self._track.path
        if path.sampler is None:
            return float(y)
        xt, yt, heading = path.sampler.at([path.centre_s_m(self._solver.t_s)])[0][:3]
        return float(-math.sin(heading) * (x - xt) + math.cos(heading) * (y - yt))

    def secondary_lateral_m(self) -> np.ndarray:
        """(2,) lateral secondary deflection [m] at the bumpstops, front and rear bogie: carbody
        relative to bogie frame at the bumpstop (bogie centre, lower-plate height), along the
        y axis of the mid-frame between the two (positive: carbody to the left). The bumpstop
        engages beyond +-``lateral_bumpstop_clearance_m``."""
        get = self._mbs.GetObjectOutput
        return np.array([get(co, _OUT.DisplacementLocal)[1] for co in self._model.bumpstops])

    def bumpstop_forces_N(self) -> np.ndarray:
        """(2,) lateral bumpstop forces [N] on the carbody, front and rear bogie, along the same
        axis as :meth:`secondary_lateral_m` (0 inside the clearance, opposite to the deflection
        beyond it)."""
        get = self._mbs.GetObjectOutput
        # the connector force acts as -f on the carbody (see .secondary._add_bumpstop)
        return np.array([-get(co, _OUT.ForceLocal)[1] for co in self._model.bumpstops])

    def anti_roll_bar_moments_N_m(self) -> np.ndarray:
        """(2,) roll moments [N m] of the anti-roll bars on the carbody, front and rear bogie,
        about the x axis of the mid-frame between bogie frame and carbody: -k_roll (phi_carbody
        - phi_frame), negative when the carbody rolls left side up relative to the frame.
        Empty without anti-roll bars."""
        get = self._mbs.GetObjectOutput
        return np.array([-get(co, _OUT.TorqueLocal)[0] for co in self._model.optional.anti_roll_bars])

    def traction_rod_forces_N(self) -> np.ndarray:
        """(2,) longitudinal forces [N] of the traction rods on the carbody, front and rear bogie,
        along the x axis of the mid-frame (negative when the carbody is ahead of its position
        relative to the bogie). Empty without traction rods."""
        get = self._mbs.GetObjectOutput
        return np.array([-get(co, _OUT.ForceLocal)[0] for co in self._model.optional.traction_rods])

    def damper_forces_N(self) -> dict[str, float]:
        """Force [N] of every secondary damper, by name (``vertical_FL``, ``lateral_F``,
        ``yaw_RR``, ...; F/R bogie, L/R side): the force on the bogie frame along the damper's
        axis (the carbody gets the opposite), positive when it resists the carbody moving along
        +x (yaw), +y (lateral) or +z (vertical) relative to the frame. Maxwell elements: the
        force at the end of the last accepted step."""
        get = self._mbs.GetObjectOutput
        return {d.name: d.force if d.maxwell else float(get(d.connector, _OUT.ForceLocal)[d.axis])
                for d in self._model.optional.dampers}
