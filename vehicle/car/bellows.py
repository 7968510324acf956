"""The co-simulation's side of the airsprings: the force laws the pneumatics give the bellows
and the crushing those laws are written in (:class:`BellowLaws`)."""
from __future__ import annotations

import math

import exudyn as exu
import numpy as np

from ..params import VehicleParams
from ..suspension import airspring_series_bellow_crushing
from .build import CarModel
from .statics import StaticReference

_OUT = exu.OutputVariableType


def _four_floats(values) -> list[float]:
    """(4,) values as a list of floats; None = zeros."""
    return [0.0] * 4 if values is None else np.asarray(values, dtype=float).reshape(4).tolist()


class BellowLaws:
    """The airspring force laws F(t, z) = F_n + dF/dt (t - t_n) + dF/dz (z - z_n), one per bellow
    in :data:`~vehicle.params.BELLOWS` order, and the bellows' crushing at the current state."""

    def __init__(self, mbs, model: CarModel, static: StaticReference, p: VehicleParams):
        self._mbs, self._model, self._static, self._params = mbs, model, static, p
        #: the laws as set, per bellow (F_n [N], dF/dz [N/m], dF/dt [N/s], z_n [m])
        self.laws = [(static.bellow_force_N, 0.0, 0.0, 0.0)] * 4
        #: the time t_n [s] they were set at
        self.law_time_s = 0.0
        #: the time [s] of the cached crushing (None: none cached)
        self.crushing_time_s = None
        self._z = self._zdot = self._z_total = None

    def set(self, t_s: float, F_N, dF_dz_N_per_m=None, dF_dt_N_per_s=None, z_anchor_m=None) -> None:
        """The laws from t_s on (see :meth:`~vehicle.car.MetroCar.set_bellow_forces`); z_n is the
        crushing at the current state unless ``z_anchor_m`` is given."""
        F, dF, Fdot = (_four_floats(v) for v in (F_N, dF_dz_N_per_m, dF_dt_N_per_s))
        if not all(map(math.isfinite, F + dF + Fdot)):
            raise ValueError(f"non-finite bellow force law: F={F}, dF/dz={dF}, dF/dt={Fdot}")
        if z_anchor_m is None:
            self._update(t_s)
            anchor = self._z.tolist()
        else:
            anchor = _four_floats(z_anchor_m)
        for (Fv, Kv, Fdv, z0v), Fk, Kk, Fdk, zk in zip(self._model.airsprings.law_vars, F, dF, Fdot,
                                                         anchor):
            Fv.SetValue(Fk)
            Kv.SetValue(Kk)
            Fdv.SetValue(Fdk)
            z0v.SetValue(zk)
        self._model.airsprings.law_time.SetValue(t_s)
        self.laws = list(zip(F, dF, Fdot, anchor))
        self.law_time_s = t_s
        if self._static.airspring_in_series:
            self.crushing_time_s = None  # the new law splits the same total crushing anew

    def crushing(self, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        """The bellows' own crushing z [m] and its rate [m/s] at the current state, at time t_s."""
        self._update(t_s)
        return self._z.copy(), self._zdot.copy()

    def airspring_crushing_m(self, t_s: float) -> np.ndarray:
        """The whole airsprings' crushing [m] (bellow + emergency spring) at time t_s."""
        self._update(t_s)
        return self._z_total.copy()

    def _update(self, t_s: float) -> None:
        """Crushing and rate of the bellows at the current state (cached per time).

        z = h0 - d_z with d = p_upper - p_lower in the connector's mid-frame J, the very
        quantity the force law uses (see :func:`.secondary.add_airsprings`). Its rate
        approximates the time derivative of that component: exudyn's ``VelocityLocal`` is the
        relative velocity expressed in J, which misses the rotation of J itself,
        d(A^T r)/dt = A^T r' - w x d (w: J's angular velocity, taken as the mean of the two
        bodies'). Exact only to second order in the bodies' relative rotation: over the twist
        ramp its integral overstates the crushing change by 2.7 um of 17 mm (measured against a
        directional derivative, see cosim/verification/monolithic.py). The co-simulation's
        Hermite interpolant ends on the exact crushing at both ends of each step, so only the
        shape within a step sees it."""
        if self.crushing_time_s == t_s:
            return
        get = self._mbs.GetObjectOutput
        h0 = self._static.bellow_height_m
        w_frames = self._mid_frame_angular_velocities()
        z, zdot = [], []
        for k, co in enumerate(self._model.airsprings.connectors):
            d0, d1, d2 = get(co, _OUT.DisplacementLocal).tolist()
            v2 = float(get(co, _OUT.VelocityLocal)[2])
            w0, w1 = w_frames[k // 2]
            z.append(h0 - d2)
            zdot.append(-(v2 - (w0 * d1 - w1 * d0)))
        self._z_total = np.array(z)
        if self._static.airspring_in_series:  # the bellow's own share (see add_airsprings)
            p, t = self._params, t_s
            out = [airspring_series_bellow_crushing(
                zk, zdk, F + Fdot * (t - self.law_time_s) - K * z0, K, Fdot, self._static.bellow_force_N,
                p.emergency_spring_stiffness_N_per_m, p.vertical_bumpstop_stiffness_N_per_m,
                p.vertical_bumpstop_clearance_m)
                for zk, zdk, (F, K, Fdot, z0) in zip(z, zdot, self.laws)]
            z = [o[1] for o in out]
            zdot = [o[2] for o in out]
        self._z, self._zdot = np.array(z), np.array(zdot)
        self.crushing_time_s = t_s

    def _mid_frame_angular_velocities(self) -> list[tuple[float, float]]:
        """Per bogie, the x and y components of the angular velocity of the mid-frame between
        its frame and the carbody (the mean of the two bodies'), in the bogie frame's axes."""
        body = self._mbs.GetObjectOutputBody
        w_carbody = np.asarray(body(self._model.carbody, _OUT.AngularVelocity))
        out = []
        for bogie in self._model.bogies:
            A = np.asarray(body(bogie, _OUT.RotationMatrix)).reshape(3, 3)
            w = A.T @ (0.5 * (w_carbody + np.asarray(body(bogie, _OUT.AngularVelocity))))
            out.append((float(w[0]), float(w[1])))
        return out
