"""What the car reports at its current state: bellow crushing, wheel loads, the wheel-rail
forces and wheelset positions, roll, the secondary components' forces (:class:`CarOutputs`, a part
of :class:`~vehicle.car.MetroCar`)."""
from __future__ import annotations

import math

import exudyn as exu
import numpy as np

from ..suspension import airspring_series_bellow_crushing
from ..wheelrail.track_contact import WheelContactOutputs

_OUT = exu.OutputVariableType


class CarOutputs:
    """Outputs at the current state (each in SI units, in :data:`~vehicle.params.WHEELS` /
    :data:`~vehicle.params.BELLOWS` / wheelset order)."""

    def _bellow_state(self) -> None:
        """Crushing and rate of the bellows at the current state (cached per time).

        z = h0 - d_z with d = p_upper - p_lower in the connector's mid-frame J, the very
        quantity the force law uses (see :meth:`_add_airspring`). Its rate approximates the time
        derivative of that component: exudyn's ``VelocityLocal`` is the relative velocity
        expressed in J, which misses the rotation of J itself, d(A^T r)/dt = A^T r' - w x d
        (w: J's angular velocity, taken as the mean of the two bodies'). Exact only to second
        order in the bodies' relative rotation: over the twist ramp its integral overstates the
        crushing change by 2.7 um of 17 mm (measured against a directional derivative, see
        cosim/verification/monolithic.py). The co-simulation's Hermite interpolant ends on the exact crushing
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

    def wheelset_lateral_to_rails_m(self) -> np.ndarray:
        """(4,) wheelset lateral displacements relative to their rails [m] (+ left; the track's
        irregularities subtracted), contact guidance only."""
        return self.contact_state().lateral_to_rails_m

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

    def floor_accelerations_m_per_s2(self) -> np.ndarray:
        """(3, 3) acceleration [m/s^2] at the floor points (:data:`~vehicle.params.FLOOR_POINTS`,
        columns) along the carbody's own axes x (forward), y (left), z (up) (rows), as an
        accelerometer fixed to the floor measures it: the specific force a - g, so 1 g upwards at
        rest, and in a curve the lateral acceleration the track's cant does not compensate. The
        point's acceleration includes the body's rotation (angular acceleration and velocity)."""
        body = self.mbs.GetObjectOutputBody
        A = np.asarray(body(self._carbody, _OUT.RotationMatrix)).reshape(3, 3)
        g = np.array([0.0, 0.0, -self.params.gravity_m_per_s2])
        out = np.empty((3, 3))
        for j, point in enumerate(self.params.floor_points_m):
            a = np.asarray(body(self._carbody, _OUT.Acceleration, localPosition=list(point)))
            out[:, j] = A.T @ (a - g)
        return out

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
