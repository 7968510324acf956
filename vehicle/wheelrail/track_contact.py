"""Wheel-rail contact forces on the wheelsets of a multibody vehicle running along a track:
the force law of :mod:`vehicle.wheelrail.contact_law` applied to wheelsets that are rigid bodies
in *global* coordinates, each with its own track frame.

Pure math (no exudyn import): the car (:mod:`vehicle.car.build`) wraps it in an exudyn ``ObjectGenericODE2``
force user function (:meth:`WheelsetTrackContact.forces`) and a Jacobian user function
(:meth:`WheelsetTrackContact.jacobian`). Both, and :meth:`WheelsetTrackContact.outputs`, are
kernels numba compiles from the functions below and the law's own
(:mod:`vehicle.wheelrail.compiled`): one call for the 8 wheels of a car costs ~4 us, against
~65 us for the same law in Python.

Coordinates (per wheelset, 7): the wheelset body's exudyn ``RotationRxyz`` node coordinates
(displacements ux, uy, uz from its reference position and the Tait-Bryan angles a, b, c of
A = Rx(a) Ry(b) Rz(c), global axes: x forward at the start, y left, z up) and the spin angle of
a separate one-coordinate node (rotation about the axle relative to the non-rotating body, > 0
rolling forward). The body does not spin: its pitch relative to the track is held by the model;
it is free along the track (its velocity along the tangent relative to the frame, x_t, enters
the longitudinal creepage).

Flexible track (``track_preload_N`` given; 10 coordinates per wheelset): the last three are the
track's displacement under the wheelset, lateral y along the track plane's lateral axis, normal
z along its normal and roll about the tangent through the track centre at rail level, each
relative to the frame (:func:`_moved`): the track rolls the frame, moves its origin along the
rolled normal and both rails along the rolled lateral axis, as irregularities move them. The
rails get the opposite of the contact forces: on y minus the lateral force, on z the support's
preload (the static load of the wheelset on its rails, along the normal) minus the normal force,
on the roll minus the contact moment about the tangent through the origin. The track's own
mass, stiffness and damping are a separate linear object (``vehicle/car/``).

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

import math
from typing import NamedTuple, Sequence

import numpy as np

from . import compiled, kernel_ops
from . import contact_law as _contact_law
from .compiled import jitable, kernel
from .contact_law import (
    GEOMETRY_COLUMNS,
    SCALAR,
    ContactLawTable,
    LawConstants,
    WheelGeometry,
    WheelsetParams,
    WheelsetState,
    contact,
    force_and_moment,
)

__all__ = ["WheelsetTrackContact", "WheelContactOutputs", "COORDINATES_PER_WHEELSET"]

#: coordinates per wheelset in the force vector: body (ux, uy, uz, a, b, c), spin angle
COORDINATES_PER_WHEELSET = 7

_SIDES = ("L", "R")


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


@jitable
def _unpacked(row) -> _Frame:
    """The frame of a row of :func:`_frame_rows`."""
    return _Frame(row[0], row[1], row[2], row[3], (row[4], row[5], row[6]),
                  (row[7], row[8], row[9]), (row[10], row[11], row[12]),
                  (row[13], row[14], row[15]), row[16], ((row[17], row[18]), (row[19], row[20])))


class _Setup(NamedTuple):
    """What the kernel needs besides the state and the frames (floats; see
    :class:`WheelsetTrackContact`)."""

    law: LawConstants
    V: float  # running speed, m/s
    inv_V: float  # 1 / max(V, V_min)
    r0: float  # centre height of the centred rigid contact, m
    spin_inertia: float  # kg m^2
    track_preload: float  # flexible track: the support's force at rest, N (module docstring)


@jitable
def _unpacked_setup(row) -> _Setup:
    """The :class:`_Setup` of its values in a flat array (kernels take arrays: numba checks
    their types at every call much faster than those of tuples)."""
    return _Setup(LawConstants(row[0], row[1], row[2], row[3], row[9], row[10]), row[4], row[5], row[6],
                  row[7], row[8])


@jitable
def _moved(fr, y, z, roll, y_t, z_t, roll_t) -> _Frame:
    """Frame ``fr`` with the flexible track's displacement under the wheelset (module
    docstring): rolled by ``roll`` about its tangent t, its origin moved by ``z`` along the
    rolled normal n', both rails moved by ``y`` along the rolled lateral axis l' (as an
    alignment irregularity moves them). y, z and roll are thus displacements along orthogonal
    axes of the track plane, as the track's diagonal mass matrix has them. The origin's rate
    along n', z_t, is not in the frame: :func:`_wheelset` subtracts it."""
    c, s = math.cos(roll), math.sin(roll)
    l0, l1, l2 = fr.l
    n0, n1, n2 = fr.n
    w0, w1, w2 = fr.w
    (eL, eLt), (eR, eRt) = fr.rails
    m0, m1, m2 = c * n0 - s * l0, c * n1 - s * l1, c * n2 - s * l2
    return _Frame(fr.ox + z * m0, fr.oy + z * m1, fr.oz + z * m2, fr.oz_t, fr.t,
                  (c * l0 + s * n0, c * l1 + s * n1, c * l2 + s * n2), (m0, m1, m2),
                  (w0 + roll_t, c * w1 + s * w2, c * w2 - s * w1), fr.kappa,
                  ((eL + y, eLt + y_t), (eR + y, eRt + y_t)))


#: the per-wheel columns of the kernels' table, in WheelGeometry's order (then roll0, dz0)
_WHEEL_COLUMNS = WheelGeometry._fields[:7]


@jitable
def _lookup(table, side, y) -> WheelGeometry:
    """The wheel's (side 0 left, 1 right) geometry at y from the kernels' table
    ``(y rows, values (2, 9, rows), slopes (2, 9, rows - 1))``: linear interpolation; beyond
    the table its end rows hold (a derailing wheelset or a Newton iterate: the law stays finite
    and the next PreStep stops the run, :meth:`WheelsetTrackContact.lateral_positions`)."""
    ys, values, slopes = table
    y = min(max(y, ys[0]), ys[-1])
    i = min(max(np.searchsorted(ys, y, side="right") - 1, 0), ys.size - 2)
    d = y - ys[i]
    v, s = values[side], slopes[side]
    return WheelGeometry(v[0, i] + s[0, i] * d, v[1, i] + s[1, i] * d, v[2, i] + s[2, i] * d,
                         v[3, i] + s[3, i] * d, v[4, i] + s[4, i] * d, v[5, i] + s[5, i] * d,
                         v[6, i] + s[6, i] * d, v[7, i] + s[7, i] * d, v[8, i] + s[8, i] * d,
                         s[7, i], s[8, i])


@jitable
def _wheel(ops, table, su, side, fr, ry, z, roll, yaw, x_t, y_t, z_t, roll_t, yaw_t, spin):
    """One wheel (side 0 left, 1 right) of a wheelset at its pose in the track frame: its
    :class:`WheelContact`, and the contact's force and moment about the wheelset centre in the
    track frame."""
    e, e_t = fr.rails[side]
    ys = ry - e
    st = WheelsetState(ys, z, roll, yaw, y_t - e_t, z_t, roll_t, yaw_t, spin, x_t)
    wc = contact(ops, 1.0 - 2.0 * side, st, _lookup(table, side, ys), su.V, fr.kappa, su.law,
                 su.inv_V)
    F, M = force_and_moment(ops, wc, yaw)
    return wc, F, M


@jitable
def _wheelset(ops, table, su, ref, fr, q, qt):
    """One wheelset: (generalized forces on its coordinates ``q``, ``qt`` (7 each, or 10 on a
    flexible track: the track's lateral, vertical and roll displacement under it last), the two
    wheels' (contact, track-frame force), and its pose (lateral y, yaw, mean lateral rail
    offset) in the track frame)."""
    flexible = len(q) == 10
    track_z_t = 0.0  # the flexible track's rate along its normal (_moved)
    if flexible:
        fr = _moved(fr, q[7], q[8], q[9], qt[7], qt[8], qt[9])
        track_z_t = qt[8]
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
    vx = qt[0] - track_z_t * nx
    vy = qt[1] - track_z_t * ny
    vz = qt[2] - fr.oz_t - track_z_t * nz
    # rates relative to the moving, turning frame: R^T (v - V t - origin') - W x r
    x_t = tx * vx + ty * vy - su.V - (W1 * rz - W2 * ry)
    y_t = lx * vx + ly * vy + lz * vz - (W2 * rx - W0 * rz)
    z_t = nx * vx + ny * vy + nz * vz - (W0 * ry - W1 * rx)
    roll = ops.atan2(-(lx * azx + ly * azy + lz * azz), nx * azx + ny * azy + nz * azz)
    yaw = ops.atan2(-(tx * ayx + ty * ayy), tx * axx + ty * axy)
    roll_t = tx * wx + ty * wy - W0
    yaw_t = nx * wx + ny * wy + nz * wz - W2
    spin = qt[6]
    z = rz - su.r0
    wl, Fl, Ml = _wheel(ops, table, su, 0, fr, ry, z, roll, yaw, x_t, y_t, z_t, roll_t, yaw_t,
                        spin)
    wr, Fr, Mr = _wheel(ops, table, su, 1, fr, ry, z, roll, yaw, x_t, y_t, z_t, roll_t, yaw_t,
                        spin)
    F0, F1, F2 = Fl[0] + Fr[0], Fl[1] + Fr[1], Fl[2] + Fr[2]
    M0, M1, M2 = Ml[0] + Mr[0], Ml[1] + Mr[1], Ml[2] + Mr[2]
    # to global axes (track frame columns t, l, n)
    Fgx, Fgy, Fgz = F0 * tx + F1 * lx + F2 * nx, F0 * ty + F1 * ly + F2 * ny, F1 * lz + F2 * nz
    Mgx, Mgy, Mgz = M0 * tx + M1 * lx + M2 * nx, M0 * ty + M1 * ly + M2 * ny, M1 * lz + M2 * nz
    m_spin = Mgx * ayx + Mgy * ayy + Mgz * ayz
    gyro = su.spin_inertia * spin  # I_s Omega (a x omega)
    Mbx = Mgx - m_spin * ayx + gyro * (ayy * wz - ayz * wy)
    Mby = Mgy - m_spin * ayy + gyro * (ayz * wx - ayx * wz)
    Mbz = Mgz - m_spin * ayz + gyro * (ayx * wy - ayy * wx)
    Q = (Fgx, Fgy, Fgz, Mbx, ca * Mby + sa * Mbz, sb * Mbx - sa * cb * Mby + ca * cb * Mbz,
         m_spin, 0.0, 0.0, 0.0)
    if flexible:  # the rails get the opposite of the contact forces (module docstring)
        Q = Q[:7] + (-F1, su.track_preload * nz - F2, -(M0 + ry * F2 - rz * F1))
    e_mean = 0.5 * (fr.rails[0][0] + fr.rails[1][0])
    return Q, ((wl, Fl), (wr, Fr)), (ry, yaw, e_mean)


#: the sources of every function the kernels compile (their cache is named by a digest of these)
_DEPENDS = (__file__, _contact_law.__file__, compiled.__file__, kernel_ops.__file__)


@kernel(*_DEPENDS)
def _frame_rows(frames, rails, V, b):
    """The frames of the wheelsets (:class:`_Frame`) packed as rows of 21 floats, (n, 21): ox,
    oy, oz, oz_t, t (3), l (3), n (3), w (3), kappa, eL, eL_t, eR, eR_t (:func:`_unpacked` reads
    one), from ``frames`` (n, 6): (x, y, heading, cant, curvature, d(cant)/ds) of the centre line,
    and ``rails`` (n, 2, 4): per side (left, right) the rail's (e, de/dt, zr, dzr/dt)."""
    out = np.empty((frames.shape[0], 21))
    for i in range(frames.shape[0]):
        x, y, heading, cant, curvature, cant_rate = frames[i]
        eL, eLt, zL, zLt = rails[i, 0]
        eR, eRt, zR, zRt = rails[i, 1]
        cp, sp = math.cos(heading), math.sin(heading)
        # track plane rolled by g = -cant (+ the rail height difference) about t
        g = -cant + (zL - zR) / (2.0 * b)
        g_t = -cant_rate * V + (zLt - zRt) / (2.0 * b)
        cg, sg = math.cos(g), math.sin(g)
        row = out[i]
        row[0], row[1], row[2], row[3] = x, y, 0.5 * (zL + zR), 0.5 * (zLt + zRt)
        row[4], row[5], row[6] = cp, sp, 0.0                      # t
        row[7], row[8], row[9] = -sp * cg, cp * cg, sg            # l
        row[10], row[11], row[12] = sp * sg, -cp * sg, cg         # n
        row[13], row[14], row[15] = g_t, curvature * V * sg, curvature * V * cg  # w
        row[16], row[17], row[18], row[19], row[20] = curvature, eL, eLt, eR, eRt
    return out


@kernel(*_DEPENDS)
def _offsets_kernel(rows, ref, q, qt, h, lo, hi):
    """Per wheelset the centre's offset along its frame's tangent t and across it along l
    (minus the flexible track's lateral displacement), at q + h qt, and whether every wheel's
    lateral position relative to its rail lies in [lo, hi] (frames: rows of
    :func:`_frame_rows`)."""
    n = ref.shape[0]
    m = q.shape[0] // n
    along, across = np.empty(n), np.empty(n)
    inside = True
    for i in range(n):
        k = m * i
        d0 = ref[i, 0] + (q[k] + h * qt[k]) - rows[i, 0]
        d1 = ref[i, 1] + (q[k + 1] + h * qt[k + 1]) - rows[i, 1]
        d2 = ref[i, 2] + (q[k + 2] + h * qt[k + 2]) - rows[i, 2]
        along[i] = rows[i, 4] * d0 + rows[i, 5] * d1
        y = rows[i, 7] * d0 + rows[i, 8] * d1 + rows[i, 9] * d2
        if m == 10:
            y = y - (q[k + 7] + h * qt[k + 7])
        across[i] = y
        for e in (rows[i, 17], rows[i, 19]):
            inside = inside and lo <= y - e <= hi
    return along, across, inside


@kernel(*_DEPENDS)
def _forces_kernel(q, qt, refs, frames, ys, values, slopes, setup):
    """Generalized contact forces of all wheelsets, (m n,), m = 7 or 10 coordinates each."""
    ops, table, su = kernel_ops, (ys, values, slopes), _unpacked_setup(setup)
    n = refs.shape[0]
    m = q.shape[0] // n
    out = np.empty(m * n)
    for i in range(n):
        k = m * i
        Q = _wheelset(ops, table, su, refs[i], _unpacked(frames[i]), q[k:k + m], qt[k:k + m])[0]
        for j in range(m):
            out[k + j] = Q[j]
    return out


@kernel(*_DEPENDS)
def _jacobian_kernel(q, qt, refs, frames, ys, values, slopes, setup, factor_q, factor_q_t, h_q,
                     h_qt):
    """factor_q d(-Q)/dq + factor_q_t d(-Q)/dq_t by forward differences, block diagonal."""
    ops, table, su = kernel_ops, (ys, values, slopes), _unpacked_setup(setup)
    n = refs.shape[0]
    m = q.shape[0] // n
    J = np.zeros((m * n, m * n))
    for i in range(n):
        k = m * i
        fr = _unpacked(frames[i])
        qi, vi = q[k:k + m].copy(), qt[k:k + m].copy()
        base = _wheelset(ops, table, su, refs[i], fr, qi, vi)[0]
        for j in range(m):  # positions: all but the spin angle (nothing depends on it)
            if j == 6:
                continue
            qp = qi.copy()
            qp[j] += h_q
            Qp = _wheelset(ops, table, su, refs[i], fr, qp, vi)[0]
            for r in range(m):
                J[k + r, k + j] -= factor_q / h_q * (Qp[r] - base[r])
        for j in range(m):  # rates
            vp = vi.copy()
            vp[j] += h_qt
            Qp = _wheelset(ops, table, su, refs[i], fr, qi, vp)[0]
            for r in range(m):
                J[k + r, k + j] -= factor_q_t / h_qt * (Qp[r] - base[r])
    return J


@kernel(*_DEPENDS)
def _outputs_kernel(q, qt, refs, frames, ys, values, slopes, setup):
    """Per wheel (2n): N, the track-frame force (3), the contact angle, eps, the creepages (3);
    per wheelset (n): lateral y and yaw in the track frame, and its rails' mean lateral
    offset (irregularity and flexible track)."""
    ops, table, su = kernel_ops, (ys, values, slopes), _unpacked_setup(setup)
    n = refs.shape[0]
    m = q.shape[0] // n
    wheels = np.empty((2 * n, 9))
    pose = np.empty((n, 3))
    for i in range(n):
        k = m * i
        _, ws, (ry, yaw, e_mean) = _wheelset(ops, table, su, refs[i], _unpacked(frames[i]),
                                             q[k:k + m], qt[k:k + m])
        pose[i, 0], pose[i, 1], pose[i, 2] = ry, yaw, e_mean
        for side in range(2):
            wc, F = ws[side]
            row = wheels[2 * i + side]
            row[0] = wc.N
            row[1], row[2], row[3] = F[0], F[1], F[2]
            row[4] = math.atan2(wc.sin_gamma, wc.cos_gamma)
            row[5] = wc.eps
            row[6], row[7], row[8] = wc.xi_x, wc.xi_y, wc.phi
    return wheels, pose


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
        track_preload_N: None: rigid track (7 coordinates per wheelset); a number: a flexible
            track, 10 coordinates per wheelset, the last three the track's lateral, vertical
            and roll displacement under the wheelset (module docstring), whose support pushes
            up with this force at rest (the static load of the wheelset on its rails, so that
            the track starts at rest at 0).
        roll_rate_creepage: False leaves the roll rate out of the lateral creepage (an
            experiment, :attr:`~vehicle.params.ContactParams.roll_rate_creepage`).
    """

    def __init__(self, law_table: ContactLawTable, params: WheelsetParams,
                 reference_positions_m, centre_height_m: float, speed_m_per_s: float,
                 min_creep_speed_m_per_s: float = 1.0, flange_angle_rad: float = 0.7,
                 track_preload_N: float | None = None, roll_rate_creepage: bool = True):
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
        self._V_min = float(min_creep_speed_m_per_s)
        self.V_ref = max(self.V, self._V_min)
        self.flange_angle_rad = float(flange_angle_rad)
        self.b = law_table.table.contact_half_spacing
        #: coordinates per wheelset: 7 (rigid track) or 10 (flexible track)
        self.m = COORDINATES_PER_WHEELSET + (0 if track_preload_N is None else 3)
        # the kernels' table: per side the columns of WheelGeometry (r .. k33, roll0, dz0)
        idx = [[GEOMETRY_COLUMNS.index(n) for n in
                [f"{c}_{side}" for c in _WHEEL_COLUMNS] + ["roll0", "dz0"]] for side in _SIDES]
        self._table = (np.ascontiguousarray(law_table.y),
                       np.ascontiguousarray(law_table.values[idx]),
                       np.ascontiguousarray(law_table.slopes[idx]))
        # the kernels' constants as a flat array (its _Setup: the property below)
        law = params.law_constants(self.N_ref, law_table.creep_follows_load, roll_rate_creepage)
        self._setup_row = np.array([*law[:4], self.V, 1.0 / self.V_ref, self.r0, params.spin_inertia_kg_m2,
                                    track_preload_N or 0.0, law.creep_load_offset, law.roll_rate_creep],
                                   dtype=float)
        self.set_track([(r[0], 0.0, 0.0, 0.0, 0.0, 0.0) for r in self._ref])

    @property
    def _setup(self) -> _Setup:
        """The kernels' constants (:func:`_unpacked_setup` of ``_setup_row``)."""
        return _unpacked_setup(self._setup_row)

    # ------------------------------------------------------------------ per step
    def set_speed(self, speed_m_per_s: float) -> None:
        """The running speed V for the coming step (a car that slows down): the creepages'
        reference and the frames' speed; call before :meth:`set_track`."""
        self.V = float(speed_m_per_s)
        self.V_ref = max(self.V, self._V_min)
        self._setup_row[4], self._setup_row[5] = self.V, 1.0 / self.V_ref

    def set_track(self, frames: Sequence[tuple], rails=None) -> None:
        """Track frames of the wheelsets for the coming step: ``frames[i] = (x, y, heading,
        cant, curvature, d(cant)/ds)`` of the centre line at wheelset i's arc length (as
        :class:`~vehicle.guidance.TrackSampler` gives them). ``rails``: (n, 2, 4) per wheelset
        and side (left, right) the rail's (lateral offset e [m], de/dt [m/s], height offset zr
        [m], dzr/dt [m/s]); None = design rails."""
        frames = np.asarray(frames, dtype=float)
        rails = np.zeros((self.n, 2, 4)) if rails is None else np.asarray(rails, dtype=float)
        if not (frames.shape == (self.n, 6) and rails.shape == (self.n, 2, 4)):
            raise ValueError(f"need {self.n} frames of 6 values and rails of (2, 4), got "
                             f"{frames.shape} and {rails.shape}")
        self._frame_rows = _frame_rows(frames, rails, self.V, self.b)

    @property
    def _frames(self) -> list[_Frame]:
        """The frames of the last :meth:`set_track` (for Python callers of the law)."""
        return [_unpacked(row) for row in self._frame_rows.tolist()]

    # ------------------------------------------------------------------ interface
    def _args(self, q, q_t) -> tuple:
        q, q_t = np.asarray(q, dtype=float), np.asarray(q_t, dtype=float)
        m = self.m
        if not q.shape == q_t.shape == (m * self.n,):  # the kernels do not check bounds
            raise ValueError(f"q and q_t must have {m * self.n} entries ({m} per wheelset), got "
                             f"{q.shape} and {q_t.shape}")
        return q, q_t, self._ref_arr, self._frame_rows, *self._table, self._setup_row

    def forces(self, q, q_t) -> np.ndarray:
        """Generalized contact forces on all wheelsets' coordinates (:attr:`m` per wheelset, in
        the order of the module docstring), (m n,): the compiled kernel
        (:mod:`vehicle.wheelrail.compiled`)."""
        return _forces_kernel(*self._args(q, q_t))

    #: finite-difference steps of :meth:`jacobian` for positions [m, rad] and rates [m/s, rad/s]
    FD_STEP_POSITION = 1e-8
    FD_STEP_RATE = 1e-6

    def jacobian(self, q, q_t, factor_q: float, factor_q_t: float) -> np.ndarray:
        """factor_q d(-Q)/dq + factor_q_t d(-Q)/dq_t (the derivative of the left-hand side,
        where the contact forces enter with a minus sign), (m n, m n), block diagonal: forward
        differences of the same law (compiled kernel)."""
        return _jacobian_kernel(*self._args(q, q_t), float(factor_q), float(factor_q_t),
                                self.FD_STEP_POSITION, self.FD_STEP_RATE)

    def outputs(self, q, q_t) -> WheelContactOutputs:
        """The contact state of every wheel and wheelset at the given coordinates."""
        wheels, pose = _outputs_kernel(*self._args(q, q_t))
        return WheelContactOutputs(wheels[:, 0], wheels[:, 1:4], wheels[:, 4], wheels[:, 5],
                                   wheels[:, 6:9], pose[:, 0], pose[:, 1], pose[:, 0] - pose[:, 2])

    def _predicted(self, q, q_t, h: float) -> tuple:
        """The offsets kernel's arguments for the coordinates q + h q_t (q_t None: q)."""
        q = np.asarray(q, dtype=float)
        q_t = np.zeros_like(q) if q_t is None else np.asarray(q_t, dtype=float)
        if not q.shape == q_t.shape == (self.m * self.n,):  # the kernels do not check bounds
            raise ValueError(f"q and q_t must have {self.m * self.n} entries, got {q.shape} and "
                             f"{q_t.shape}")
        return self._frame_rows, self._ref_arr, q, q_t, float(h)

    def longitudinal_offsets(self, q, q_t=None, h: float = 0.0) -> np.ndarray:
        """Offset [m] of each wheelset centre along its frame's tangent from the frame's origin,
        at the coordinates q + h q_t (the frames of the last :meth:`set_track`)."""
        return _offsets_kernel(*self._predicted(q, q_t, h), -math.inf, math.inf)[0]

    def lateral_positions(self, q, q_t=None, h: float = 0.0) -> tuple[np.ndarray, bool]:
        """Lateral position [m] of each wheelset centre in its track frame, relative to its
        flexible track's lateral displacement (first order in the track's roll), at the
        coordinates q + h q_t (the frames of the last :meth:`set_track`), and whether every
        wheel's position relative to its rail (minus the rail's lateral offset) lies inside the
        table."""
        lo, hi = self.table.y_range_m
        _, y, inside = _offsets_kernel(*self._predicted(q, q_t, h), lo, hi)
        return y, bool(inside)

    def static_rise_m(self, wheel_load_N: float) -> float:
        """The law's z (rise of the centre above the centred rigid contact height; negative:
        the Hertz approach) at which a centred wheelset at rest (rolling freely at the running
        speed, no roll, no yaw) carries ``wheel_load_N`` per wheel: the sum of both contacts'
        forces normal to the track plane equals 2 wheel_load_N."""
        su = self._setup
        geo = [_lookup(self._table, side, 0.0) for side in range(2)]
        spin = self.V / float(geo[0].r)

        def vertical(z):
            total = 0.0
            for side in range(2):
                st = WheelsetState(0.0, z, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, spin, 0.0)
                wc = contact(SCALAR, 1.0 - 2.0 * side, st, geo[side], su.V, 0.0, su.law,
                             su.inv_V)
                total += force_and_moment(SCALAR, wc, 0.0)[0][2]
            return total - 2.0 * wheel_load_N

        from scipy.optimize import brentq
        d0 = (wheel_load_N / self.params.hertz_constant_N_per_m1_5) ** (2.0 / 3.0)
        return float(brentq(vertical, -3.0 * d0, 0.0, xtol=1e-16, rtol=1e-15))
