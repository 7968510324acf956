"""What the car does at every internal step: the track under each wheelset, the rail heights
and guidance frames set before the step (PreStep), the Maxwell dampers' states after it
(PostStep) (:class:`StepHooks`, a part of :class:`~vehicle.car.MetroCar`)."""
from __future__ import annotations

import math

import exudyn as exu
import numpy as np

from ..irregularities import TrackIrregularity
from ..suspension import maxwell_step
from ..wheelrail.compiled import kernel

_OUT = exu.OutputVariableType


def _four_channels(values: tuple, shape: tuple) -> np.ndarray | None:
    """``values`` as one (4, *shape) array (four arrays shaped like s, or broadcasting to it), or
    None when they are not four or do not broadcast."""
    try:  # the usual case, four arrays shaped like s: one conversion
        v = np.array(values, dtype=float)
        if v.shape == (4,) + shape:
            return v
    except ValueError:  # shapes that differ (e.g. a scalar 0 for a channel)
        pass
    if len(values) != 4:
        return None
    try:
        return np.array([np.broadcast_to(np.asarray(x, dtype=float), shape) for x in values])
    except ValueError:
        return None


@kernel(__file__)
def _rails_from(irregularity, z_rail, d):
    """Per wheelset and rail (left, right) the rail's (e, de/dt, zr, dzr/dt) at t, (n, 2, 4),
    from the ``irregularity`` (3, n, 4): (lateral, vertical, cross_level, gauge) under the n
    wheelsets at t - d, t, t + d, and the rail heights ``z_rail`` (3, 2n) of ``rail_height_m``
    at those times. Each rail moves by e_L,R = lateral +- gauge / 2, zr_L,R = z_rail + (vertical
    -+ cross_level / 2) (the signs of :mod:`vehicle.irregularities`); the rates are central
    differences over +-d."""
    n = irregularity.shape[1]
    e, z = np.empty((3, 2 * n)), np.empty((3, 2 * n))
    for k in range(3):
        for i in range(n):
            lateral, vertical, cross, gauge = irregularity[k, i]
            e[k, 2 * i], e[k, 2 * i + 1] = lateral + 0.5 * gauge, lateral - 0.5 * gauge
            z[k, 2 * i] = z_rail[k, 2 * i] + (vertical - 0.5 * cross)
            z[k, 2 * i + 1] = z_rail[k, 2 * i + 1] + (vertical + 0.5 * cross)
    out = np.empty((n, 2, 4))
    for j in range(2 * n):
        out[j // 2, j % 2, 0] = e[1, j]
        out[j // 2, j % 2, 1] = (e[2, j] - e[0, j]) / (2.0 * d)
        out[j // 2, j % 2, 2] = z[1, j]
        out[j // 2, j % 2, 3] = (z[2, j] - z[0, j]) / (2.0 * d)
    return out


class StepHooks:
    """Per-step user functions and the track they read."""

    def _wheelset_s_m(self, t) -> np.ndarray:
        """Arc lengths [m] of the wheelsets at time(s) t: s0 + s(t) (v t at constant speed), plus
        each wheelset's own offset along the track with contact guidance (shaped like s0 + v t)."""
        return self._s0_wheelset + self._distance_m(t) + self._ds_wheelset

    def _track_at(self, t: float) -> np.ndarray:
        """Track centre line (x, y, heading, cant, curvature, d(cant)/ds) under each wheelset
        at time t: (4, 6), rows as :meth:`~vehicle.guidance.TrackSampler.rows` gives them (with
        contact guidance (5, 6): the last under the car centre, where the drive holds the
        carbody)."""
        s = self._wheelset_s_m(t)
        if self._contact_mode:
            s = np.append(s, self.start_s_m + self._distance_m(t))
        if self._sampler is None:
            rows = np.zeros((s.size, 6))
            rows[:, 0] = s
            return rows
        return self._sampler.rows(s)

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

    def _contact_rails(self, t: float) -> np.ndarray:
        """(4, 2, 4) per wheelset and rail (left, right) the rail's lateral offset e (+ left),
        de/dt, height offset zr (+ up, normal to the track plane) and dzr/dt at time t (contact
        guidance; the cant is in the track frame, not here): ``rail_height_m`` plus the
        irregularity (:func:`_rails_from`), the rates central differences over
        +-:attr:`RAIL_RATE_DT_S`."""
        d = self.RAIL_RATE_DT_S
        times = np.array([t - d, t, t + d])
        if self._rail_fn is None:
            z = np.zeros((3, 8))
        else:
            z = np.array([self._rail_fn(float(ti)) for ti in times], dtype=float)
            if z.shape != (3, 8):
                raise ValueError(f"rail_height_m(t) must return shape (8,), got {z.shape[1:]}")
        if self._irr is None:
            irr = np.zeros((3, 4, 4))
        else:
            irr = self._irregularity_stacked(times[:, None])
        return _rails_from(irr, z, d)

    def _irregularity_stacked(self, t) -> np.ndarray:
        """(lateral, vertical, cross_level, gauge) as one array shaped like s = s0 + v t with a
        last axis of 4: (4, 4) under the wheelsets at a time t, (n, 4, 4) for times of shape
        (n, 1)."""
        s = self._wheelset_s_m(t)
        if type(self._irr) is TrackIrregularity:  # finite by construction: no checks (a
            # subclass may redefine __call__: it takes the general path)
            return self._irr.stacked(s)
        v = _four_channels(tuple(self._irr(s)), s.shape)
        if v is None or not np.isfinite(v).all():
            raise ValueError("irregularity(s) must return 4 finite arrays (lateral_m, "
                             "vertical_m, cross_level_m, gauge_m) shaped like s")
        return np.moveaxis(v, 0, -1)

    def _irregularity_at(self, t) -> tuple[np.ndarray, ...]:
        """(lateral, vertical, cross_level, gauge), each shaped like s = s0 + v t: (4,) under the
        wheelsets at a time t, (n, 4) for times of shape (n, 1)."""
        return tuple(np.moveaxis(self._irregularity_stacked(t), -1, 0))

    def _set_contact_track(self, t: float, state=None) -> None:
        """Track frames and rail offsets, with their rates, at the step end t (contact guidance).

        The rates are those at t (a central difference over +-:attr:`RAIL_RATE_DT_S`), not the
        means over the step: the creep forces see the rail velocity, and a step mean lags it by
        half a step, a first-order error (the straight irregular run's largest lateral wheel
        force moved 3015 / 2947 / 2921 N at 5 / 2.5 / 1.25 ms with step means, 2926 / 2928 /
        2931 N with the rates at t: car alone, 10 s of scenarios/straight_irregular.yaml)."""
        state = self._track_at(t)[:4] if state is None else state
        self._frames_t = t
        self._wr.set_track(state, self._contact_rails(t))

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
            self._ds_wheelset = (self._ds_wheelset + self._wr.longitudinal_offsets(q, q_t, t - t0)
                                 - self._distance_between_m(self._frames_t, t))
        if not self.speed_profile.constant:          # the law's frames and creepages run at v(t)
            self._wr.set_speed(self.speed_profile.speed(t))
        state = self._track_at(t)
        if self._guided:
            self._set_guidance(state)
            self._heading_now = float(state[0, 2])
        self._set_contact_track(t, state[:4])
        y, inside = self._wr.lateral_positions(q, q_t, t - t0)
        if not inside:  # predicted at the step end from the state at its start
            self._wr_left_table = (t0, y)
            return False
        return True

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
            rows = self._track_at(t) if track_state is None else track_state
            for iw, (_, _, _, cant, _, _) in enumerate(np.asarray(rows)[:4].tolist()):
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
                for (x, y, psi, *rest), e in zip(track_state.tolist(), lat.tolist())]

    def _set_guidance(self, track_state) -> None:
        """Guidance offsets (see :meth:`_add_wheelset_guidance`, :meth:`_add_drive`) for the
        given track state (rows as :meth:`_track_at` gives them; contact guidance: its fifth
        row is the car centre's)."""
        if isinstance(track_state, np.ndarray):
            track_state = track_state.tolist()
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
            self._heading_now = float(state[0, 2])
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
