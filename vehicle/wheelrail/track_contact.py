"""Wheel-rail contact forces on the wheelsets of a multibody vehicle running along a track
(issue 11, item 3): the force law of :mod:`vehicle.wheelrail.contact_law` applied to wheelsets
that are rigid bodies in *global* coordinates, each with its own track frame.

Pure math (floats or numpy arrays; no exudyn import): ``vehicle/car.py`` wraps it in an exudyn
``ObjectGenericODE2`` force user function (:meth:`WheelsetTrackContact.forces`) and a Jacobian
user function (:meth:`WheelsetTrackContact.jacobian`).

Coordinates (per wheelset, 7): the wheelset body's exudyn ``RotationRxyz`` node coordinates
(displacements ux, uy, uz from its reference position and the Tait-Bryan angles a, b, c of
A = Rx(a) Ry(b) Rz(c), global axes: x forward at the start, y left, z up) and the spin angle of
a separate one-coordinate node (rotation about the axle relative to the non-rotating body, > 0
rolling forward). The body does not spin: its pitch relative to the track is held by the model.

Track frame of a wheelset (:meth:`WheelsetTrackContact.set_track`, once per time step): origin
on the track centre line at rail level at the wheelset's arc length, axes R = Rz(psi) Rx(-cant)
(t tangent, l lateral in the track plane pointing left, n normal to it, up), moving along the
track at the running speed V and turning at (kappa V about the vertical, -cant' V about t). In
it the wheelset's pose (lateral y, height, roll about t, yaw about n) and rates relative to the
moving frame are those of :class:`~vehicle.wheelrail.contact_law.WheelsetState`; angular rates
are the components of the relative angular velocity (the Tait-Bryan rates to first order).

Rails (per wheel, also set per step): lateral offset e (positive to the left) and height offset
zr (positive up) of that wheel's rail from its design position, and their rates. The heights
move the wheelset's track frame: its origin rises by the mean (zr_L + zr_R)/2 and its plane rolls
by (zr_L - zr_R)/(2 b) (b: half the spacing of the centred contact points) on top of the cant,
so that a cross-level or a twist of e.g. 40 mm does not appear as a relative roll of the
wheelset (which the yaw- and roll-free table would misread as a lateral shift r0 roll). The
lateral offsets stay per wheel: each wheel is evaluated with the contact table at its own
lateral position relative to its rail, y - e (a gauge change moves the two rails apart,
e_L - e_R): the left wheel's contact depends on the left profiles only, so at first order the
table of the pair at y - e_L describes it, its roll difference being taken up by the overlap's
lever term.

Per wheel the law gives the contact force F (Hertz normal force, Kalker + Shen-Hedrick-Elkins
creep forces; :func:`~vehicle.wheelrail.contact_law.wheel_contact`) and its moment about the
wheelset centre (:func:`~vehicle.wheelrail.contact_law.force_and_moment`) in the track frame.
Their sum is rotated to global axes; the moment's component along the axle a drives the spin
coordinate, the rest acts on the body together with the spin's gyroscopic moment
I_s Omega (a x omega) (omega the body's angular velocity). Generalized forces on the Rxyz
coordinates: the force on (ux, uy, uz) and G^T M on (a, b, c), omega = G (a, b, c)'.

Standstill: the creepages are divided by max(V, ``min_creep_speed_m_per_s``) (their numerators
stay the slip velocities), so below that speed the creep forces are viscous rather than
divided by zero (see :class:`WheelsetTrackContact`).
"""

from __future__ import annotations

import bisect
import math
from typing import NamedTuple, Sequence

import numpy as np

from .contact_law import (GEOMETRY_COLUMNS, NUMPY, SCALAR, ContactLawTable, WheelsetParams,
                          WheelsetState, force_and_moment, wheel_contact)

__all__ = ["WheelsetTrackContact", "WheelContactOutputs", "COORDINATES_PER_WHEELSET"]

#: coordinates per wheelset in the force vector: body (ux, uy, uz, a, b, c), spin angle
COORDINATES_PER_WHEELSET = 7

_SIDES = ("L", "R")
_SIDE_COLUMNS = {side: tuple(n for n in GEOMETRY_COLUMNS if n.endswith("_" + side)
                             or n in ("roll0", "dz0")) for side in _SIDES}


class WheelContactOutputs(NamedTuple):
    """Contact state of every wheel (arrays; wheels in wheelset order, left then right) and
    wheelset (see :meth:`WheelsetTrackContact.outputs`)."""

    normal_N: np.ndarray  # (2n,) Hertz normal force N >= 0
    force_track_N: np.ndarray  # (2n, 3) force of the rail on the wheel, track frame (t, l, n)
    gamma_rad: np.ndarray  # (2n,) contact angle in the track frame (table, at y - e)
    saturation: np.ndarray  # (2n,) Shen-Hedrick-Elkins factor eps (1: linear, < 1: saturating)
    creepage: np.ndarray  # (2n, 3) xi_x, xi_y, spin phi [1/m]
    lateral_m: np.ndarray  # (n,) wheelset centre, lateral in the track frame (design line)
    yaw_rad: np.ndarray  # (n,) wheelset yaw relative to the track tangent
    lateral_to_rails_m: np.ndarray  # (n,) lateral relative to the mean of its rails (y - mean e)


class _Frame(NamedTuple):
    """Track frame of one wheelset for one time step (precomputed, see set_track)."""

    ox: float
    oy: float
    oz: float  # origin height (mean rail height offset)
    oz_t: float  # its rate
    t: tuple  # tangent (global)
    l: tuple  # lateral axis in the track plane (global), pointing left
    n: tuple  # normal to the track plane (global), up
    w: tuple  # frame angular velocity, frame axes
    kappa: float
    rails: tuple  # ((e, e_t) left, (e, e_t) right): lateral rail offsets and rates


def _frame(x, y, heading, cant, curvature, cant_rate, V, rails, b) -> _Frame:
    (eL, eLt, zL, zLt), (eR, eRt, zR, zRt) = rails
    cp, sp = math.cos(heading), math.sin(heading)
    # track plane rolled by g = -cant (+ the rail height difference) about t
    g = -cant + (zL - zR) / (2.0 * b)
    g_t = -cant_rate * V + (zLt - zRt) / (2.0 * b)
    cg, sg = math.cos(g), math.sin(g)
    t = (cp, sp, 0.0)
    l = (-sp * cg, cp * cg, sg)
    n = (sp * sg, -cp * sg, cg)
    w = (g_t, curvature * V * sg, curvature * V * cg)
    return _Frame(float(x), float(y), 0.5 * (zL + zR), 0.5 * (zLt + zRt), t, l, n, w,
                  float(curvature), ((float(eL), float(eLt)), (float(eR), float(eRt))))


class WheelsetTrackContact:
    """Contact forces of ``n`` wheelsets on their rails (see the module docstring).

    Args:
        law_table: contact geometry with Kalker coefficients (built with ``params``).
        params: the wheelset and contact parameters (Hertz constant, contact damping, friction
            coefficient, spin inertia, G and nu); its axle load and mass are not used here.
        reference_positions_m: (n, 3) reference positions of the wheelset bodies (global; their
            node coordinates are displacements from these).
        centre_height_m: height of the wheelset centre above the rail plane in the centred
            rigid contact, i.e. the table's r0 (the law's z is the rise above it).
        speed_m_per_s: running speed V >= 0 of the track frames.
        min_creep_speed_m_per_s: V_min > 0; creepages are divided by max(V, V_min).
        flange_angle_rad: contact angle above which a wheel counts as in flange contact.
    """

    def __init__(self, law_table: ContactLawTable, params: WheelsetParams,
                 reference_positions_m, centre_height_m: float, speed_m_per_s: float,
                 min_creep_speed_m_per_s: float = 1.0, flange_angle_rad: float = 0.7):
        if not speed_m_per_s >= 0.0:
            raise ValueError(f"speed_m_per_s must be >= 0 with contact guidance, got "
                             f"{speed_m_per_s!r}")
        if not min_creep_speed_m_per_s > 0.0:
            raise ValueError("min_creep_speed_m_per_s must be > 0")
        self.table = law_table
        self.params = params
        self.N_ref = law_table.reference_load_N
        ref = np.asarray(reference_positions_m, dtype=float)
        if ref.ndim != 2 or ref.shape[1] != 3:
            raise ValueError("reference_positions_m must be (n, 3)")
        self.n = ref.shape[0]
        self._ref = [tuple(r) for r in ref.tolist()]
        self._ref_arr = ref
        self.r0 = float(centre_height_m)
        self.V = float(speed_m_per_s)
        self.V_ref = max(self.V, float(min_creep_speed_m_per_s))
        self.flange_angle_rad = float(flange_angle_rad)
        self.b = law_table.table.contact_half_spacing
        # table rows for the scalar lookup: per side, (values, slopes) of that side's columns
        self._y = law_table.y
        self._y_list = law_table.y.tolist()
        self._last = law_table.y.size - 2
        idx = {n: j for j, n in enumerate(GEOMETRY_COLUMNS)}
        self._rows = {}
        self._cols = {}
        for side in _SIDES:
            names = _SIDE_COLUMNS[side]
            js = [idx[n] for n in names]
            vals = law_table.values[js, :-1].T.tolist()
            slos = law_table.slopes[js, :].T.tolist()
            self._rows[side] = [(names, v, s, s[names.index("roll0")], s[names.index("dz0")])
                                for v, s in zip(vals, slos)]
            # the side's columns as contiguous (columns, rows) blocks: one gather per lookup
            self._cols[side] = (names, law_table.values[js], law_table.slopes[js])
        self.set_track([(r[0], 0.0, 0.0, 0.0, 0.0, 0.0) for r in self._ref])

    # ------------------------------------------------------------------ per step
    def set_track(self, frames: Sequence[tuple], rails=None) -> None:
        """Track frames of the wheelsets for the coming step: ``frames[i] = (x, y, heading,
        cant, curvature, d(cant)/ds)`` of the centre line at wheelset i's arc length (as
        :class:`~vehicle.guidance.TrackSampler` gives them). ``rails``: (n, 2, 4) per wheelset
        and side (left, right) the rail's (lateral offset e [m], de/dt [m/s], height offset zr
        [m], dzr/dt [m/s]); None = design rails."""
        if rails is None:
            rails = [((0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0))] * self.n
        V, b = self.V, self.b
        self._frames = [_frame(*f, V, (tuple(r[0]), tuple(r[1])), b)
                        for f, r in zip(frames, rails)]

    def lateral_positions_at_step_end(self, q, q_t, h: float) -> list[float]:
        """Lateral positions of the wheelsets predicted h later, y + h y' (``q``, ``q_t``: the
        coordinates at the step start), for :meth:`in_table`."""
        qq = q.tolist() if hasattr(q, "tolist") else list(q)
        qt = q_t.tolist() if hasattr(q_t, "tolist") else list(q_t)
        return self.lateral_positions([a + h * b for a, b in zip(qq, qt)])

    # ------------------------------------------------------------------ lookups
    def _geo_scalar(self, side: str, y: float) -> dict:
        """The side's table columns at y (linear interpolation between the rows)."""
        yl = self._y_list
        # beyond the table (a derailing wheelset, or a Newton iterate) its end rows hold: the
        # law stays finite and the next PreStep stops the run (WheelsetTrackContact.in_table)
        y = yl[0] if y < yl[0] else (yl[-1] if y > yl[-1] else y)
        i = bisect.bisect_right(yl, y) - 1
        i = 0 if i < 0 else (self._last if i > self._last else i)
        names, v, s, droll0, ddz0 = self._rows[side][i]
        dy = y - self._y_list[i]
        geo = {n: vi + si * dy for n, vi, si in zip(names, v, s)}
        geo["droll0"] = droll0
        geo["ddz0"] = ddz0
        return geo

    def _geo_numpy(self, side: str, y: np.ndarray) -> dict:
        y = np.clip(y, self._y[0], self._y[-1])  # end rows hold beyond the table
        i = np.clip(np.searchsorted(self._y, y, side="right") - 1, 0, self._last)
        dy = y - self._y[i]
        names, vals, slos = self._cols[side]
        s = slos[:, i]
        geo = dict(zip(names, vals[:, i] + s * dy))
        geo["droll0"] = s[names.index("roll0")]
        geo["ddz0"] = s[names.index("dz0")]
        return geo

    # ------------------------------------------------------------------ the kernel
    def _wheelset(self, ops, lookup, ref, fr, q, qt):
        """One wheelset: (generalized forces (7) on its coordinates ``q``, ``qt`` (sequences of
        7 floats, or of arrays for ``ops`` = NUMPY), the per-wheel (contact dict, track-frame
        force) pairs, and its pose (lateral y, yaw) in the track frame)."""
        p = self.params
        a, b, c = q[3], q[4], q[5]
        ca, sa, cb, sb, cc, sc = ops.cos(a), ops.sin(a), ops.cos(b), ops.sin(b), ops.cos(c), \
            ops.sin(c)
        # body axes, columns of A = Rx(a) Ry(b) Rz(c) (global); ay is the axle
        axx, axy = cb * cc, ca * sc + sa * sb * cc
        ayx, ayy, ayz = -cb * sc, ca * cc - sa * sb * sc, sa * cc + ca * sb * sc
        azx, azy, azz = sb, -sa * cb, ca * cb
        ad, bd, cd = qt[3], qt[4], qt[5]
        wx, wy, wz = ad + sb * cd, ca * bd - sa * cb * cd, sa * bd + ca * cb * cd  # G theta'
        tx, ty, _ = fr.t
        lx, ly, lz = fr.l
        nx, ny, nz = fr.n
        W0, W1, W2 = fr.w
        dx, dy, dz = ref[0] + q[0] - fr.ox, ref[1] + q[1] - fr.oy, ref[2] + q[2] - fr.oz
        rx = tx * dx + ty * dy
        ry = lx * dx + ly * dy + lz * dz
        rz = nx * dx + ny * dy + nz * dz
        vx, vy, vz = qt[0], qt[1], qt[2] - fr.oz_t
        # rates relative to the moving, turning frame: R^T (v - V t - oz' e_z) - W x r
        y_t = lx * vx + ly * vy + lz * vz - (W2 * rx - W0 * rz)
        z_t = nx * vx + ny * vy + nz * vz - (W0 * ry - W1 * rx)
        roll = ops.atan2(-(lx * azx + ly * azy + lz * azz), nx * azx + ny * azy + nz * azz)
        yaw = ops.atan2(-(tx * ayx + ty * ayy), tx * axx + ty * axy)
        roll_t = tx * wx + ty * wy - W0
        yaw_t = nx * wx + ny * wy + nz * wz - W2
        spin = qt[6]
        z = rz - self.r0
        F0 = F1 = F2 = M0 = M1 = M2 = 0.0
        wheels = []
        for side, (e, e_t) in zip(_SIDES, fr.rails):
            ys = ry - e
            st = WheelsetState(ys, z, roll, yaw, y_t - e_t, z_t, roll_t, yaw_t, spin)
            wc = wheel_contact(ops, side, st, lookup(side, ys), self.V, fr.kappa, p,
                               self.N_ref, self.V_ref)
            Fs, Ms = force_and_moment(ops, wc, yaw)
            F0, F1, F2 = F0 + Fs[0], F1 + Fs[1], F2 + Fs[2]
            M0, M1, M2 = M0 + Ms[0], M1 + Ms[1], M2 + Ms[2]
            wheels.append((wc, Fs))
        # to global axes (track frame columns t, l, n)
        Fgx, Fgy, Fgz = F0 * tx + F1 * lx + F2 * nx, F0 * ty + F1 * ly + F2 * ny, F1 * lz + F2 * nz
        Mgx, Mgy, Mgz = M0 * tx + M1 * lx + M2 * nx, M0 * ty + M1 * ly + M2 * ny, M1 * lz + M2 * nz
        m_spin = Mgx * ayx + Mgy * ayy + Mgz * ayz
        gyro = p.spin_inertia_kg_m2 * spin  # I_s Omega (a x omega)
        Mbx = Mgx - m_spin * ayx + gyro * (ayy * wz - ayz * wy)
        Mby = Mgy - m_spin * ayy + gyro * (ayz * wx - ayx * wz)
        Mbz = Mgz - m_spin * ayz + gyro * (ayx * wy - ayy * wx)
        Q = [Fgx, Fgy, Fgz, Mbx, ca * Mby + sa * Mbz, sb * Mbx - sa * cb * Mby + ca * cb * Mbz,
             m_spin]
        return Q, wheels, (ry, yaw)

    # ------------------------------------------------------------------ interface
    def forces(self, q, q_t) -> list:
        """Generalized contact forces on all wheelsets' coordinates (7 per wheelset, in the
        order of the module docstring), floats. The evaluation is kept: :meth:`outputs` at
        the same coordinates reuses it (the last residual of a converged step is the state)."""
        q = q.tolist() if hasattr(q, "tolist") else list(q)
        q_t = q_t.tolist() if hasattr(q_t, "tolist") else list(q_t)
        out = []
        kept = []
        look = self._geo_scalar
        wheelset = self._wheelset
        for i, (ref, fr) in enumerate(zip(self._ref, self._frames)):
            k = 7 * i
            Q, wheels, pose = wheelset(SCALAR, look, ref, fr, q[k:k + 7], q_t[k:k + 7])
            out += Q
            kept.append((wheels, pose))
        self._kept = (q, q_t, self._frames, kept)
        return out

    #: finite-difference steps of :meth:`jacobian` for positions [m, rad] and rates [m/s, rad/s]
    FD_STEP_POSITION = 1e-8
    FD_STEP_RATE = 1e-6

    def jacobian(self, q, q_t, factor_q: float, factor_q_t: float) -> np.ndarray:
        """factor_q d(-Q)/dq + factor_q_t d(-Q)/dq_t (the derivative of the left-hand side,
        where the contact forces enter with a minus sign), (7n, 7n), block diagonal: forward
        differences of the same law, all wheelsets and perturbations in one vectorised
        evaluation."""
        nw, m = self.n, 14  # base, 6 positions (the spin angle does not enter), 7 rates
        qa = np.asarray(q, dtype=float).reshape(nw, 7).T
        va = np.asarray(q_t, dtype=float).reshape(nw, 7).T
        Qin = np.repeat(qa[:, :, None], m, axis=2)
        Vin = np.repeat(va[:, :, None], m, axis=2)
        hq, hv = self.FD_STEP_POSITION, self.FD_STEP_RATE
        for k in range(6):
            Qin[k, :, 1 + k] += hq
        for k in range(7):
            Vin[k, :, 7 + k] += hv
        Qin = Qin.reshape(7, nw * m)
        Vin = Vin.reshape(7, nw * m)
        ref = self._ref_arr.repeat(m, axis=0).T
        frs = self._frames
        rep = lambda vals: np.repeat(np.asarray(vals, dtype=float), m)  # noqa: E731
        fr = _Frame(rep([f.ox for f in frs]), rep([f.oy for f in frs]),
                    rep([f.oz for f in frs]), rep([f.oz_t for f in frs]),
                    tuple(rep([f.t[k] for f in frs]) for k in range(3)),
                    tuple(rep([f.l[k] for f in frs]) for k in range(3)),
                    tuple(rep([f.n[k] for f in frs]) for k in range(3)),
                    tuple(rep([f.w[k] for f in frs]) for k in range(3)),
                    rep([f.kappa for f in frs]),
                    tuple(tuple(rep([f.rails[s][k] for f in frs]) for k in range(2))
                          for s in range(2)))
        Q = self._wheelset(NUMPY, self._geo_numpy, ref, fr, Qin, Vin)[0]
        Q = np.array([np.broadcast_to(v, (nw * m,)) for v in Q]).reshape(7, nw, m)
        J = np.zeros((7 * nw, 7 * nw))
        for i in range(nw):
            base = Q[:, i, 0:1]
            dq = (Q[:, i, 1:7] - base) / hq
            dv = (Q[:, i, 7:14] - base) / hv
            blk = J[7 * i:7 * i + 7, 7 * i:7 * i + 7]
            blk[:, :6] -= factor_q * dq
            blk -= factor_q_t * dv
        return J

    def outputs(self, q, q_t) -> WheelContactOutputs:
        """The contact state of every wheel and wheelset at the given coordinates (the last
        :meth:`forces` evaluation if it was at these coordinates and track, else evaluated)."""
        q = q.tolist() if hasattr(q, "tolist") else list(q)
        q_t = q_t.tolist() if hasattr(q_t, "tolist") else list(q_t)
        kept = getattr(self, "_kept", None)
        if kept is not None and kept[2] is self._frames and kept[0] == q and kept[1] == q_t:
            per_wheelset = kept[3]
        else:
            look = self._geo_scalar
            per_wheelset = [self._wheelset(SCALAR, look, ref, fr, q[7 * i:7 * i + 7],
                                           q_t[7 * i:7 * i + 7])[1:]
                            for i, (ref, fr) in enumerate(zip(self._ref, self._frames))]
        N, F, gam, eps, xi, y, yaw, y_rails = [], [], [], [], [], [], [], []
        for (wheels, (ry, ps)), fr in zip(per_wheelset, self._frames):
            for wc, Fs in wheels:
                N.append(wc["N"])
                F.append(Fs)
                gam.append(math.atan2(wc["sin_gamma"], wc["cos_gamma"]))
                eps.append(wc["eps"])
                xi.append((wc["xi_x"], wc["xi_y"], wc["phi"]))
            y.append(ry)
            yaw.append(ps)
            y_rails.append(ry - 0.5 * (fr.rails[0][0] + fr.rails[1][0]))
        return WheelContactOutputs(np.array(N), np.array(F), np.array(gam), np.array(eps),
                                   np.array(xi), np.array(y), np.array(yaw), np.array(y_rails))

    def in_table(self, lateral_m: Sequence[float]) -> bool:
        """Whether every wheel's lateral position relative to its rail (wheelset lateral
        ``lateral_m[i]`` minus the rail offsets of the current step) lies inside the table."""
        lo, hi = self.table.y_range_m
        return all(lo <= yi - fr.rails[s][0] <= hi
                   for yi, fr in zip(lateral_m, self._frames) for s in range(2))

    def lateral_positions(self, q) -> list[float]:
        """Lateral position of each wheelset centre in its track frame [m] (cheap)."""
        out = []
        for i, (ref, fr) in enumerate(zip(self._ref, self._frames)):
            k = 7 * i
            l = fr.l
            out.append(l[0] * (ref[0] + q[k] - fr.ox) + l[1] * (ref[1] + q[k + 1] - fr.oy)
                       + l[2] * (ref[2] + q[k + 2] - fr.oz))
        return out

    def static_rise_m(self, wheel_load_N: float) -> float:
        """The law's z (rise of the centre above the centred rigid contact height; negative:
        the Hertz approach) at which a centred wheelset at rest (rolling freely at the running
        speed, no roll, no yaw) carries ``wheel_load_N`` per wheel: the sum of both contacts'
        forces normal to the track plane equals 2 wheel_load_N."""
        p = self.params
        look = self._geo_scalar
        r0 = look("L", 0.0)["r_L"]
        spin = self.V / r0

        def vertical(z):
            total = 0.0
            for side in _SIDES:
                st = WheelsetState(0.0, z, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, spin)
                wc = wheel_contact(SCALAR, side, st, look(side, 0.0), self.V, 0.0, p,
                                   self.N_ref, self.V_ref)
                total += force_and_moment(SCALAR, wc, 0.0)[0][2]
            return total - 2.0 * wheel_load_N

        from scipy.optimize import brentq
        d0 = (wheel_load_N / p.hertz_constant_N_per_m1_5) ** (2.0 / 3.0)
        return float(brentq(vertical, -3.0 * d0, 0.0, xtol=1e-16, rtol=1e-15))
