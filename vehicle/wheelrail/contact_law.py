"""Contact force law of a wheelset on track, as pure functions.

One law, written once against a small table of math operations (``ops``), evaluates either

* numbers (:data:`SCALAR` with ``math``; :data:`NUMPY` for arrays, e.g. along a whole time
  series; the Python force user function of the exudyn model ``vehicle.wheelrail.wheelset``),
* machine code: the car's contact (``vehicle.wheelrail.track_contact``) runs it in kernels that
  numba compiles from these same functions (:mod:`vehicle.wheelrail.compiled`), or
* an exudyn symbolic expression tree (``vehicle.wheelrail.wheelset`` passes its own ``ops``)
  that exudyn evaluates in C++ (optional there: slower for this law, see that module).

So the force law the tests check without exudyn is, operation for operation, the one exudyn runs.
This module imports numpy/scipy only (``tests/vehicle/test_wheelrail.py`` checks the subpackage; numba
is imported when the first kernel compiles).

Frames, coordinates, signs
--------------------------
Track frame (x forward, y left, z up) moving along the track centre line at the speed V; on a
curve of curvature kappa (> 0 turns left) it also turns at the rate kappa V. The wheelset's
coordinates in it (:class:`WheelsetState`): lateral ``y``, vertical ``z`` (rise of the wheelset
centre above its rigid-contact height at y = 0, i.e. the contact table's ``dz``), ``roll``
(right-handed about x: left side up), ``yaw`` (about z, relative to the track tangent) and the
spin rate ``spin_t`` about the axle (V / r0 when rolling freely, > 0 forward). The wheelset body
itself does not spin (a non-rotating frame); ``spin_t`` is a separate coordinate's rate.

Per wheel (``side`` "L" at y > 0, "R"), from the contact table at the current y (the table is
the rigid, yaw-free contact geometry, :class:`~vehicle.wheelrail.geometry.ContactTable`):
rolling radius r, contact angle gamma (track frame, > 0 descending to the track centre), lateral
contact position yc (track frame), and the wheelset's rigid-contact roll0 and rise dz0.

* **Normal force** (Hertz, unilateral, along the contact normal): the contact point of the
  actual wheelset is below the rigid-contact one by the vertical overlap
  ``delta = (dz0 - z) + a (roll0 - roll)`` with the roll arm ``a = l - s r tan(gamma)``,
  ``l = yc - y`` (lateral lever from the wheelset centre), s = +1 left, -1 right (rolling moves
  the contact point up by l and sideways by r per radian; along the normal that is the moment arm
  of N); the overlap along the normal is ``delta cos(gamma)`` (two tangent planes inclined by
  gamma) and ``N = C_H (delta cos gamma)^1.5 + c d(delta cos gamma)/dt``, clipped at 0, and 0 when
  delta <= 0. C_H is the car's vertical Hertz constant (``VehicleParams``), so the stiffness is
  the car's along the normal instead of the vertical; c is
  ``ContactParams.normal_damping_N_s_per_m`` (2e5 N s/m, :class:`WheelsetParams`).
* **Creepages** (:func:`vehicle.wheelrail.creep.creepages` extended to the curve; relative
  velocity of wheel to rail at the contact over V)::

      xi_x = (V (1 - kappa yc) + x_t - l yaw_t - spin_t r) / V
      xi_y = (y_t + r roll_t - V yaw) / (V cos gamma)
      phi  = ((yaw_t + kappa V) cos gamma -+ spin_t sin gamma) / V     (- left, + right)

  (the rail under a contact at yc runs at V (1 - kappa yc) in the turning frame, the wheelset
  centre at V + x_t; the absolute yaw rate is yaw_t + kappa V).
* **Creep forces**: Kalker's linear theory, coefficients ``f11 = G a b C11``,
  ``f22 = G a b C22``, ``f23 = G (ab)^1.5 C23``, ``f33 = G (ab)^2 C33`` with the Hertz ellipse
  (a, b) of the contact's curvatures (table columns ``kw``, ``kr``, and cos(delta)/r along the
  track). The ellipse shape a/b does not depend on the load and its size scales as N^(1/3), so
  :class:`ContactLawTable` stores the coefficients at a reference load and the law scales them
  by (N/N_ref)^(2/3), ^1, ^(4/3): exact Hertz, no per-step ellipse solve. Then
  Shen-Hedrick-Elkins saturation to mu N (factor eps on F_x, F_y and the spin moment M_z).
* **Contact frame**: t1 = (cos yaw, sin yaw, 0) (rolling direction of the yawed wheel), t2 the
  in-plane lateral direction pointing left, n from rail into wheel (for the left wheel
  n = (sin(yaw) sin(gamma), -cos(yaw) sin(gamma), cos(gamma))); the force on the wheel
  ``F = F_x t1 + F_y t2 + N n`` acts at ``p = (-l sin yaw, l cos yaw, -r)`` from the wheelset
  centre, with the spin moment ``M_z n``. Its moment about the axle drives the spin coordinate;
  the rest acts on the non-rotating wheelset body.

The spinning wheelset's gyroscopic moments (spin inertia I_s): ``+I_s spin_t (yaw_t + kappa V)``
about x and ``-I_s spin_t roll_t`` about z; the turning frame adds the centrifugal force
``-m kappa V^2`` along y (no cant).

Simplifications: the table is the rigid, yaw-free geometry (yaw neither moves the contact
points nor changes r, gamma); the small elastic roll beyond roll0 changes the overlap but not
gamma; one contact point per wheel (the table's; the flange arises when the table's contact
jumps there); Kalker's linear theory with heuristic saturation (no FASTSIM/Polach).

Note on the kinematics: the roll rate enters the lateral creepage (r roll_t: the contact point
is r below the centre). On a profile whose rigid roll follows y (roll0' = d roll0/dy) lateral pure
rolling is y_t (1 + r0 roll0') = V yaw, so the kinematic wavelength is Klingel's times
sqrt(1 + r0 roll0'): +0.76 % for a 1:40 cone (roll0' = lambda / b), ~+1 % for S1002/UIC60
at 3 mm. Klingel's formula neglects the roll.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .compiled import PYTHON, Ops, jitable
from .creep import POISSON_RATIO, SHEAR_MODULUS_PA, hertz_semi_axes, kalker_coefficients
from .geometry import ContactTable

__all__ = [
    "WheelsetParams",
    "WheelsetState",
    "WheelGeometry",
    "WheelContact",
    "LawConstants",
    "ContactLawTable",
    "GEOMETRY_COLUMNS",
    "SCALAR",
    "NUMPY",
    "contact",
    "wheel_contact",
    "force_and_moment",
    "wheelset_forces",
    "generalized_forces",
]

GRAVITY_M_PER_S2 = 9.81


@dataclass(frozen=True)
class WheelsetParams:
    """A wheelset and its contact (SI). Defaults: the metro car's wheelset (``VehicleParams``:
    800 kg, 494 / 49 / 494 kg m^2) under its static axle load (carbody 17 t and bogies 1.9 t on
    four axles: 2 x 29.43 kN wheel load, of which 51.0 kN comes through the axleboxes), the car's
    vertical Hertz constant, the normal contact damping of contact guidance
    (:class:`~vehicle.params.ContactParams`) and mu = 0.36 (the issue's Nadal setting)."""

    mass_kg: float = 800.0
    roll_inertia_kg_m2: float = 494.0
    spin_inertia_kg_m2: float = 49.0  # about the axle
    yaw_inertia_kg_m2: float = 494.0
    # vertical load on the axle from the bogie (primary springs), downwards, N
    axle_load_N: float = (17000.0 * GRAVITY_M_PER_S2 / 2.0 + 1900.0 * GRAVITY_M_PER_S2) / 2.0
    gravity_m_per_s2: float = GRAVITY_M_PER_S2
    hertz_constant_N_per_m1_5: float = 1.0e11  # VehicleParams.hertz_constant_N_per_m1_5
    # normal contact damping: ContactParams.normal_damping_N_s_per_m (see there)
    contact_damping_N_s_per_m: float = 2.0e5
    friction_coefficient: float = 0.36
    shear_modulus_Pa: float = SHEAR_MODULUS_PA
    poisson_ratio: float = POISSON_RATIO

    def __post_init__(self):
        for name in ("mass_kg", "roll_inertia_kg_m2", "spin_inertia_kg_m2", "yaw_inertia_kg_m2",
                     "hertz_constant_N_per_m1_5", "friction_coefficient", "shear_modulus_Pa"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive")
        if not (self.axle_load_N >= 0 and self.contact_damping_N_s_per_m >= 0):
            raise ValueError("axle_load_N and contact_damping_N_s_per_m must be >= 0")

    @property
    def static_wheel_load_N(self) -> float:
        """Vertical load per wheel at rest on level track."""
        return 0.5 * (self.axle_load_N + self.mass_kg * self.gravity_m_per_s2)

    def law_constants(self, reference_load_N: float, creep_follows_load: bool = True,
                      roll_rate_creepage: bool = True) -> "LawConstants":
        """The constants :func:`contact` reads, with the table's reference load; with
        ``creep_follows_load`` False the creep coefficients stay the table's at every load
        (given coefficients, :class:`ContactLawTable`: load ratio 0 N + 1); with
        ``roll_rate_creepage`` False the lateral creepage leaves the roll rate out."""
        if creep_follows_load:
            inverse, offset = 1.0 / float(reference_load_N), 0.0
        else:
            inverse, offset = 0.0, 1.0
        return LawConstants(float(self.hertz_constant_N_per_m1_5),
                            float(self.contact_damping_N_s_per_m),
                            float(self.friction_coefficient), inverse, offset,
                            1.0 if roll_rate_creepage else 0.0)


class WheelsetState(NamedTuple):
    """Wheelset coordinates in the track frame and their rates (see the module docstring);
    ``x_t``: the centre's longitudinal velocity relative to the frame (0 for a wheelset held at
    the frame's arc length)."""

    y: object
    z: object
    roll: object
    yaw: object
    y_t: object
    z_t: object
    roll_t: object
    yaw_t: object
    spin_t: object
    x_t: object = 0.0


# ----------------------------------------------------------------------------- ops
#: floats (Python's ``math``); ``where`` picks like exudyn's IfThenElse
SCALAR = PYTHON
#: arrays (element-wise); every branch is finite, so ``np.where`` warns about nothing
NUMPY = Ops(np.sqrt, np.sin, np.cos, np.arctan2, np.power, np.where, np.maximum, np.minimum,
            float)


class WheelGeometry(NamedTuple):
    """One wheel's contact geometry at the wheelset's lateral position (floats, arrays or
    expressions; :meth:`of_side` of :meth:`ContactLawTable.geometry`): rolling radius ``r`` [m], contact
    angle ``gamma`` [rad], lateral contact position ``yc`` [m], Kalker coefficients ``k11`` ..
    ``k33`` at the table's reference load, the wheelset's rigid-contact ``roll0`` [rad] and
    ``dz0`` [m], and their slopes in y ``droll0`` [rad/m], ``ddz0`` [-]."""

    r: object
    gamma: object
    yc: object
    k11: object
    k22: object
    k23: object
    k33: object
    roll0: object
    dz0: object
    droll0: object
    ddz0: object

    @classmethod
    def of_side(cls, geo, side: str) -> "WheelGeometry":
        """The ``side``'s ("L" or "R") wheel from a mapping of the :data:`GEOMETRY_COLUMNS`
        and ``droll0``, ``ddz0`` (e.g. :meth:`ContactLawTable.geometry`)."""
        return tuple.__new__(cls, map(geo.__getitem__, _WHEEL_KEYS[side]))


class LawConstants(NamedTuple):
    """The constants of :func:`contact` (SI; :meth:`WheelsetParams.law_constants`)."""

    hertz_constant: float  # N/m^1.5
    damping: float  # normal contact damping, N s/m
    friction_coefficient: float
    inv_reference_load: float  # 1 / the table's reference load of the Kalker coefficients, 1/N
    # added to N * inv_reference_load: 0 (coefficients scale with the load), or 1 with
    # inv_reference_load 0 (given coefficients, the same at every load)
    creep_load_offset: float = 0.0
    # factor of the roll rate's part of the lateral creepage, r roll'/V: 1 (the kinematics), 0
    # leaves it out as classical linear models do (an experiment: ContactParams.roll_rate_creepage)
    roll_rate_creep: float = 1.0


class WheelContact(NamedTuple):
    """One wheel's contact (:func:`contact`; floats, arrays or expressions): ``N`` normal force
    [N], Kalker's linear creep forces ``fx``, ``fy`` [N] and spin moment ``mz`` [N m] (contact
    frame), ``eps`` the Shen-Hedrick-Elkins factor (the forces are eps fx, eps fy, eps mz), the
    creepages ``xi_x``, ``xi_y`` [-] and ``phi`` [1/m], ``delta`` the vertical overlap [m], and
    the geometry the force acts through: ``r`` [m], ``lever`` = yc - y [m], ``cos_gamma``,
    ``sin_gamma``, ``sign`` (+1 left, -1 right)."""

    N: object
    fx: object
    fy: object
    mz: object
    eps: object
    xi_x: object
    xi_y: object
    phi: object
    delta: object
    r: object
    lever: object
    cos_gamma: object
    sin_gamma: object
    sign: float


# ----------------------------------------------------------------------------- geometry table
#: per-wheel and wheelset columns the force law reads (``k*`` creep-coefficient columns at the
#: table's reference load; ``roll0``/``dz0`` the rigid-contact roll [rad] and rise [m])
GEOMETRY_COLUMNS = (
    "r_L", "r_R", "gamma_L", "gamma_R", "yc_L", "yc_R", "roll0", "dz0",
    "k11_L", "k22_L", "k23_L", "k33_L", "k11_R", "k22_R", "k23_R", "k33_R",
)

#: per side: the sign (+1 left) and the keys of that wheel's columns in ``geo`` (r, gamma, yc,
#: k11, k22, k23, k33), so that the law does not build key strings per evaluation
_SIDE_KEYS = {side: (sign, tuple(f"{name}_{side}" for name in
                                 ("r", "gamma", "yc", "k11", "k22", "k23", "k33")))
              for side, sign in (("L", 1.0), ("R", -1.0))}


#: per side: the keys in ``geo`` of that wheel's WheelGeometry fields, in their order
_WHEEL_KEYS = {side: keys + ("roll0", "dz0", "droll0", "ddz0")
               for side, (_, keys) in _SIDE_KEYS.items()}


#: Gaussian smoothing (standard deviation, mm of lateral displacement) of the contact geometry
#: the force law reads; see :class:`ContactLawTable`
SMOOTHING_MM = 0.1
#: row spacing of the smoothed law table [mm]
SMOOTHED_GRID_MM = 0.01


class ContactLawTable:
    """The contact table in SI plus Kalker's creep coefficients per row, for the force law.

    ``k11 = G a b C11``, ``k22 = G a b C22``, ``k23 = G (ab)^1.5 C23``, ``k33 = G (ab)^2 C33``
    with the Hertz ellipse of that row's contact at ``reference_load_N`` (the law rescales them
    with the actual normal force). Interpolation is linear in y.

    **Smoothing** (``smoothing_mm``, default :data:`SMOOTHING_MM` = 0.1 mm; 0 or None: the
    rigid rows as they are): every column is resampled every :data:`SMOOTHED_GRID_MM` and
    convolved with a Gaussian of that standard deviation in y (linear extrapolation at the
    ends, so a straight column stays straight). The rigid single-point table jumps where two
    contact points exchange (tread to flange root) and turns by 0.56 rad within 3 um of y
    where the contact runs through the near-conformal flange root onto the flank. Read as it
    is, it gives a wheelset whose flange-contact modes grow: linearised about its steady
    rolling state pressed against the flange (continuous model, no integrator;
    :mod:`vehicle.wheelrail.stability`, ``tests/vehicle/test_contact_stability.py``; 0 to 60 kN of
    lateral load in 4 kN steps) its modes above 100 Hz grow at up to +386 /s with 0.1 mm rows
    and +875 /s with 0.01 mm rows at the jumps (+105 /s with the creep forces off), and normal
    damping up to 1e6 N s/m does not remove that. Smoothed over 0.1 mm with the normal damping
    of :class:`~vehicle.params.ContactParams` (2e5 N s/m) they are damped at every load
    (<= -98 /s); either alone is not enough (smoothed, 5e4 N s/m: +82 /s).
    Physically the smoothing stands for the elastic contact spreading over the conformal
    flange root, where wheel and rail stay within a few um of each other over 4 mm of the
    profiles while the wheel sinks ~50 um into the rail: one rigid contact point does not
    describe that. What the smoothing width changes is measured in docs/wheel_rail.md
    ("Flange contact and step convergence").
    """

    def __init__(self, table: ContactTable, params: WheelsetParams | None = None,
                 reference_load_N: float = 50.0e3, smoothing_mm: float | None = SMOOTHING_MM,
                 given_creep: tuple | None = None):
        p = params or WheelsetParams()
        #: the creep coefficients scale with the normal force (False: ``given_creep``, the same
        #: (f11 [N], f22 [N], f23 [N m], f33 [N m^2]) on every row and at every load, as a
        #: linear model with given coefficients has them)
        self.creep_follows_load = not given_creep
        if given_creep and not (len(given_creep) == 4 and all(v >= 0 and math.isfinite(v) for v in given_creep)):
            raise ValueError(f"given_creep: four finite coefficients >= 0 (f11, f22, f23, f33), got {given_creep!r}")
        if not reference_load_N > 0:
            raise ValueError("reference_load_N must be positive")
        if smoothing_mm is not None and not (smoothing_mm >= 0 and math.isfinite(smoothing_mm)):
            raise ValueError(f"smoothing_mm must be >= 0, got {smoothing_mm!r}")
        self.table = table
        self.reference_load_N = float(reference_load_N)
        self.smoothing_mm = float(smoothing_mm or 0.0)
        c = table.columns
        self.y = c["y_ws_mm"] * 1e-3
        roll = c["roll_rad"]
        cols = {"roll0": roll, "dz0": c["dz_mm"] * 1e-3}
        G, nu = p.shear_modulus_Pa, p.poisson_ratio
        for side, sgn in (("L", 1.0), ("R", -1.0)):
            r, gam = c[f"r_{side}_m"], c[f"gamma_{side}_rad"]
            cols[f"r_{side}"], cols[f"gamma_{side}"] = r, gam
            cols[f"yc_{side}"] = c[f"yc_{side}_m"]
            delta = gam - sgn * roll  # contact angle relative to the axle
            A = np.cos(delta) / (2.0 * r)  # rolling circle; straight rail along the track
            B = 0.5 * (c[f"kw_{side}_1pm"] + c[f"kr_{side}_1pm"])
            k = np.empty((4, r.size))
            for i in range(r.size):
                a, b = hertz_semi_axes(self.reference_load_N, float(A[i]), float(B[i]), G, nu)
                C = kalker_coefficients(a / b, nu)
                ab = a * b
                k[:, i] = (G * ab * C.C11, G * ab * C.C22, G * ab ** 1.5 * C.C23,
                           G * ab ** 2 * C.C33)
            if given_creep:
                k = np.outer(np.asarray(given_creep, float), np.ones(r.size))
            for j, name in enumerate(("k11", "k22", "k23", "k33")):
                cols[f"{name}_{side}"] = k[j]
        self.values = np.vstack([cols[n] for n in GEOMETRY_COLUMNS])  # (columns, rows)
        if self.smoothing_mm > 0:
            self.y, self.values = _smoothed(self.y, self.values, 1e-3 * self.smoothing_mm,
                                            1e-3 * SMOOTHED_GRID_MM)
        self.slopes = np.diff(self.values, axis=1) / np.diff(self.y)  # (columns, rows - 1)

    @property
    def y_range_m(self) -> tuple[float, float]:
        return float(self.y[0]), float(self.y[-1])

    def segment(self, y: float) -> tuple[int, float, np.ndarray, np.ndarray]:
        """Table interval holding y: (index i, y_i, values at y_i, slopes on [y_i, y_i+1]).
        Beyond the table the end interval is returned (linear extrapolation)."""
        i = int(np.searchsorted(self.y, y, side="right")) - 1
        i = min(max(i, 0), self.y.size - 2)
        return i, float(self.y[i]), self.values[:, i], self.slopes[:, i]

    def geometry(self, y) -> dict:
        """Columns at y (scalar or array), linearly interpolated, plus the slopes of roll0 and
        dz0 (``droll0``, ``ddz0``, for the rate of the overlap): the ``geo`` of the force law."""
        y_arr = np.asarray(y, dtype=float)
        i = np.clip(np.searchsorted(self.y, y_arr, side="right") - 1, 0, self.y.size - 2)
        dy = y_arr - self.y[i]
        out = {}
        for j, name in enumerate(GEOMETRY_COLUMNS):
            v = self.values[j, i] + self.slopes[j, i] * dy
            out[name] = float(v) if v.ndim == 0 else v
        for name, key in (("roll0", "droll0"), ("dz0", "ddz0")):
            s = self.slopes[GEOMETRY_COLUMNS.index(name), i]
            out[key] = float(s) if np.ndim(s) == 0 else s
        return out


def _smoothed(y: np.ndarray, values: np.ndarray, sigma: float, dy: float):
    """``values`` (columns, rows) over ``y`` resampled every ``dy`` over the same range and
    convolved with a Gaussian of standard deviation ``sigma`` (kernel cut at 4 sigma; beyond
    the ends each column is extended linearly). Returns (grid, smoothed values)."""
    n = int(round((y[-1] - y[0]) / dy))
    grid = y[0] + dy * np.arange(n + 1)
    grid[-1] = y[-1]
    half = int(math.ceil(4.0 * sigma / dy))
    kernel = np.exp(-0.5 * (dy * np.arange(-half, half + 1) / sigma) ** 2)
    kernel /= kernel.sum()
    ext = np.arange(1, half + 1) * dy
    out = np.empty((values.shape[0], grid.size))
    for j, col in enumerate(values):
        v = np.interp(grid, y, col)
        lo = v[0] - (v[1] - v[0]) / dy * ext[::-1]
        hi = v[-1] + (v[-1] - v[-2]) / dy * ext
        out[j] = np.convolve(np.concatenate([lo, v, hi]), kernel, mode="valid")
    return grid, out


# ----------------------------------------------------------------------------- the law
@jitable
def contact(ops, s, st, g, V, kappa, c, inv_V):
    """Contact of one wheel (see the module docstring): a :class:`WheelContact`.

    ``s`` the side (+1.0 left, -1.0 right), ``st`` the :class:`WheelsetState`, ``g`` the
    wheel's :class:`WheelGeometry` at st.y, ``V`` the speed [m/s], ``kappa`` the curvature
    [1/m], ``c`` the :class:`LawConstants`, ``inv_V`` 1 / the speed the creepages are divided
    by (see :func:`wheel_contact`). Compiled into the car's kernels
    (:mod:`vehicle.wheelrail.compiled`)."""
    y, z, roll, yaw, y_t, z_t, roll_t, yaw_t, spin_t, x_t = st
    c0 = ops.const(0.0)
    c3 = ops.const(3.0)
    r, gam, yc = g.r, g.gamma, g.yc
    lever = yc - y
    cg, sg = ops.cos(gam), ops.sin(gam)
    # --- normal force: Hertz along the normal, unilateral ---
    # rolling by d(roll) moves the contact point (lever l, depth r below the centre) up by
    # l d(roll) and sideways by r d(roll): along the normal (cos g, -s sin g) that is
    # cos(g) (l - s r tan g) d(roll), the moment arm of N about the axle (_arms: wn)
    arm = lever - s * r * sg / cg
    delta = (g.dz0 - z) + arm * (g.roll0 - roll)
    delta_t = (g.ddz0 + arm * g.droll0) * y_t - z_t - arm * roll_t
    dn = ops.max(delta, c0) * cg
    N = ops.where(delta > 0.0, ops.max(c.hertz_constant * ops.pow(dn, 1.5)
                                       + c.damping * cg * delta_t, c0), c0)
    # --- Kalker coefficients at this load: ellipse size ~ N^(1/3) ---
    load = N * c.inv_reference_load + c.creep_load_offset  # N / N_ref (given coefficients: 1)
    ab = ops.pow(load, 2.0 / 3.0)  # a b / (a b)_ref
    f11, f22 = g.k11 * ab, g.k22 * ab
    f23, f33 = g.k23 * load, g.k33 * ops.pow(load, 4.0 / 3.0)
    # --- creepages ---
    xi_x = (V * (1.0 - kappa * yc) + x_t - lever * yaw_t - spin_t * r) * inv_V
    xi_y = (y_t + c.roll_rate_creep * r * roll_t - V * yaw) * inv_V / cg
    phi = ((yaw_t + kappa * V) * cg - s * spin_t * sg) * inv_V
    # --- Kalker linear + Shen-Hedrick-Elkins ---
    fx = -f11 * xi_x
    fy = -f22 * xi_y - f23 * phi
    mz = f23 * xi_y - f33 * phi
    u = ops.sqrt(ops.pow(fx, 2.0) + ops.pow(fy, 2.0)) / ops.max(
        c.friction_coefficient * N, ops.const(1e-9))
    # eps = 1 - u/3 + u^2/27 = ((u - 4.5)^2 + 6.75)/27 for u <= 3 and 1/u beyond, written with
    # min/max: u is evaluated twice and no branch divides by zero
    um = ops.min(u, c3)
    eps = (ops.pow(um - 4.5, 2.0) * (1.0 / 27.0) + 0.25) * ops.min(
        ops.const(1.0), 3.0 / ops.max(u, c3))
    return WheelContact(N, fx, fy, mz, eps, xi_x, xi_y, phi, delta, r, lever, cg, sg, s)


def wheel_contact(ops, side: str, st: WheelsetState, geo, V, kappa, p: WheelsetParams,
                  reference_load_N: float, V_ref=None) -> WheelContact:
    """Contact of one wheel, :func:`contact` with the wheel's columns of ``geo``.

    ``V_ref``: the speed the creepages are divided by (default ``V``). A model that may stand
    still passes a regularised one, e.g. max(|V|, V_min): the numerators stay the true slip
    velocities, so below V_min the creep forces become viscous (slip velocity times f / V_min)
    instead of dividing by zero.

    ``geo`` maps the :data:`GEOMETRY_COLUMNS` (and ``droll0``, ``ddz0``) to values or
    expressions at the current y (:meth:`ContactLawTable.geometry`), or is the side's
    :class:`WheelGeometry`."""
    try:
        s = _SIDE_KEYS[side][0]
    except KeyError:
        raise ValueError("side must be 'L' or 'R'") from None
    g = geo if isinstance(geo, WheelGeometry) else WheelGeometry.of_side(geo, side)
    return contact(ops, s, st, g, V, kappa, p.law_constants(reference_load_N),
                   1.0 / (V if V_ref is None else V_ref))


@jitable
def _arms(ops, w, yaw):
    """Directions and moment arms of one wheel's contact forces in the track frame.

    Contact frame of the yawed wheel: t1 = (cos yaw, sin yaw, 0), t2 = (-sin yaw cos g,
    cos yaw cos g, s sin g), n = (s sin yaw sin g, -s cos yaw sin g, cos g) (s = +1 left); the
    force acts at p = (-l sin yaw, l cos yaw, -r). Returns the directions (t1, t2, n) and the
    moments about the wheelset centre per unit force: p x t1 = (r sin yaw, -r cos yaw, -l),
    p x t2 = w2 (cos yaw, sin yaw, 0), p x n = wn (cos yaw, sin yaw, 0) with
    w2 = s l sin g + r cos g, wn = l cos g - s r sin g (the spin moment acts along n)."""
    s, r, l, cg, sg = w.sign, w.r, w.lever, w.cos_gamma, w.sin_gamma
    cy, sy = ops.cos(yaw), ops.sin(yaw)
    t1 = (cy, sy, 0.0)
    t2 = (-sy * cg, cy * cg, s * sg)
    n = (s * sy * sg, -s * cy * sg, cg)
    w2 = s * l * sg + r * cg
    wn = l * cg - s * r * sg
    return (t1, t2, n), ((r * sy, -r * cy, -l), (cy * w2, sy * w2, 0.0), (cy * wn, sy * wn, 0.0))


@jitable
def force_and_moment(ops, w, yaw):
    """Track-frame force of one wheel's contact on the wheelset and its moment about the
    wheelset centre (N, N m), from a :class:`WheelContact`."""
    (t1, t2, n), (m1, m2, mn) = _arms(ops, w, yaw)
    eps = w.eps
    Fx, Fy, Mz, N = eps * w.fx, eps * w.fy, eps * w.mz, w.N
    # written out per component (no generator: this runs 8 times per residual of the car);
    # the terms with a zero direction component (t1 and the moment arms have none along z,
    # see _arms) are left out
    F = (Fx * t1[0] + Fy * t2[0] + N * n[0],
         Fx * t1[1] + Fy * t2[1] + N * n[1],
         Fy * t2[2] + N * n[2])
    M = (Fx * m1[0] + Fy * m2[0] + N * mn[0] + Mz * n[0],
         Fx * m1[1] + Fy * m2[1] + N * mn[1] + Mz * n[1],
         Fx * m1[2] + Mz * n[2])
    return F, M


def wheelset_forces(ops, st: WheelsetState, geo, V, kappa, p: WheelsetParams,
                    reference_load_N: float, V_ref=None) -> tuple[WheelContact, WheelContact]:
    """Both wheels' :func:`wheel_contact` (left, right)."""
    c = p.law_constants(reference_load_N)  # once for both wheels: this is a hot path
    inv_V = 1.0 / (V if V_ref is None else V_ref)
    return (contact(ops, 1.0, st, WheelGeometry.of_side(geo, "L"), V, kappa, c, inv_V),
            contact(ops, -1.0, st, WheelGeometry.of_side(geo, "R"), V, kappa, c, inv_V))


def generalized_forces(ops, st: WheelsetState, geo, V, kappa, p: WheelsetParams,
                       reference_load_N: float) -> list:
    """Generalized forces on the wheelset model's 7 coordinates: the non-rotating body's
    (x, y, z, roll, pitch, yaw) as Tait-Bryan xyz angles (exudyn ``RotationRxyz``,
    A = Rx(roll) Ry(pitch) Rz(yaw), pitch held at 0) and the spin angle about the axle.

    Contact forces of both wheels, the gyroscopic moments of the spin and the centrifugal force
    of the turning frame (module docstring); gravity and the axle load are separate loads. A
    moment M about the centre splits into its component along the axle a = A e_y =
    (-sin yaw, cos yaw cos roll, cos yaw sin roll), which drives the spin, and the rest
    Mb = M - (M.a) a on the body, whose generalized forces are Mb.e_x (roll) and Mb.e3 (yaw,
    e3 = Rx e_z = (0, -sin roll, cos roll); a.e3 = 0). The pitch entry is 0 (held).

    Written as sum_wheels eps (c_x fx + c_y fy + c_z mz) + c_N N with cheap geometric
    coefficients c: the same numbers as summing :func:`force_and_moment`, but every expensive
    quantity appears once per coordinate (exudyn's symbolic trees have no shared
    subexpressions: each use is evaluated again)."""
    cr, sr = ops.cos(st.roll), ops.sin(st.roll)
    cy, sy = ops.cos(st.yaw), ops.sin(st.yaw)
    a = (-sy, cy * cr, cy * sr)
    e3 = (0.0, -sr, cr)

    def dot(u, v):
        return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]

    Q = [0.0] * 7
    for w in wheelset_forces(ops, st, geo, V, kappa, p, reference_load_N):
        (t1, t2, n), (m1, m2, mn) = _arms(ops, w, st.yaw)
        # per unit of (fx, fy, mz, N): forces, axle moment, body roll and yaw moments
        a1, a2, az, aN = dot(m1, a), dot(m2, a), dot(n, a), dot(mn, a)
        coef = [
            (t1[0], t2[0], 0.0, n[0]),
            (t1[1], t2[1], 0.0, n[1]),
            (0.0, t2[2], 0.0, n[2]),
            (m1[0] + sy * a1, m2[0] + sy * a2, n[0] + sy * az, mn[0] + sy * aN),
            None,
            (dot(m1, e3), dot(m2, e3), dot(n, e3), dot(mn, e3)),
            (a1, a2, az, aN),
        ]
        for k, c in enumerate(coef):
            if c is None:
                continue
            creep = c[0] * w.fx + c[1] * w.fy
            if k >= 3:
                creep = creep + c[2] * w.mz
            Q[k] = Q[k] + w.eps * creep + c[3] * w.N
    Is = p.spin_inertia_kg_m2
    Q[3] = Q[3] + Is * st.spin_t * (st.yaw_t + kappa * V)  # gyroscopic, about x
    Q[5] = Q[5] - Is * st.spin_t * st.roll_t  # gyroscopic, about z
    Q[1] = Q[1] - p.mass_kg * kappa * V * V  # centrifugal (turning frame)
    return Q
