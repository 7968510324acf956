"""Rigid wheel-rail contact geometry of a wheelset on straight track, tabulated over the lateral
displacement, and the equivalent conicity.

Frames and signs (SI in the API, mm in profile coordinates)
-----------------------------------------------------------
Track frame: x forward, **y to the left**, z up (the car's body axes, ``vehicle/params.py``).
The **left** wheel/rail is at y > 0. The wheelset is displaced laterally by ``y`` (positive to the
left), rolled by ``roll`` about x (right-handed: positive lifts the left wheel) and raised by
``dz``; yaw is zero (the table is the classical 2-D, yaw-free contact geometry).

Per wheel (suffix ``_L`` / ``_R``) the table gives:

* ``r``     rolling radius: distance from the axle to the contact point, measured perpendicular
  to the axle (m);
* ``gamma`` contact angle in the **track** frame: angle of the common tangent of wheel and rail
  to the track plane, positive when the surface descends towards the track centre (the normal
  force then pushes the wheel towards the centre; tread ~0.03, flange ~1.2 rad). The angle
  relative to the axle is ``delta_L = gamma_L - roll``, ``delta_R = gamma_R + roll``;
* ``yw``    contact position on the wheel, in the wheel-profile coordinate (mm, positive to the
  field side, 0 = profile datum = tape circle for S1002, flange at negative values);
* ``yr``    contact position on the rail, in the rail-profile coordinate (mm, positive to the
  field side, origin of the profile file, profile as installed, i.e. inclined);
* ``yc``    lateral position of the contact point in the track frame (m, left positive);
* ``kw``, ``kr`` transverse curvature of the wheel / rail profile at the contact (1/m, positive
  when convex towards the other body: rail crown > 0, a concave wheel throat < 0), for a Hertz
  ellipse (:func:`vehicle.wheelrail.creep.hertz_semi_axes`);
* ``gap2`` and ``yw2``: the vertical gap (mm) and wheel position (mm) of the nearest *second*
  local minimum of the wheel-rail distance on that side (a second potential contact point, e.g.
  the flange before it touches); NaN when there is none.

Wheelset columns: ``y_ws_mm`` (lateral displacement), ``roll_rad`` and ``dz_mm`` (rise of the
wheelset centre relative to the centred position).

Contact search ("minimum vertical distance, then roll/height for two-point contact")
------------------------------------------------------------------------------------
Both profiles are interpolated by parametric cubic splines in chord length and sampled every
``ds`` = 0.01 mm. For a wheelset pose (y, roll) at nominal centre height, the vertical distance
from every rail sample up to the (rolled, shifted) wheel surface is computed; its minimum over the
rail is that side's gap g (refined to sub-sample precision by a parabola through the three
samples around the discrete minimum). Yaw being zero, the profile plane x = 0 contains the lowest
point of every wheel circle, so this 2-D search is exact for the rigid wheelset. The roll that
closes both gaps together solves g_L(y, roll) = g_R(y, roll) (Brent's method; g_L - g_R is
increasing in roll), then dz = -g_L. The right side is evaluated as the mirror image of the left
(right at (y, roll) = left at (-y, -roll)), so the pair is symmetric by construction.

Because the global minimum is taken, the contact point *jumps* wherever two local minima
exchange: first to the flange root, then onto the flange. Those jumps are in the table as
steps in ``yw``/``r``/``gamma`` between neighbouring rows (a rigid two-point contact exists only
at the jump itself); :meth:`ContactTable.derive` refines the cells holding them to 0.01 mm.

Placement (CONTACT conventions, CONTACT user guide section "Track and roller geometry"):

* rail: rotated by the inclination towards the track centre (unless the file is already
  inclined), raised so that its highest point touches the track plane (z = 0), then shifted so
  that its gauge face at ``gauge_height_mm`` (14 mm) below the track plane is at
  ``gauge_m/2`` from the track centre (the first crossing of that depth from the gauge side);
* wheel: the profile datum is at lateral distance ``flange_back_distance_m/2 - flange_back_pos``
  from the wheelset centre (1360/2 + 70 = 750 mm for S1002 with back-to-back 1360 mm and the tape
  circle 70 mm from the flange back) and at radius ``nominal_radius_m`` (+ the profile height at
  the tape circle, so r = r_nom exactly at ``tape_circle_y_mm``).
"""

from __future__ import annotations

import hashlib
import io
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq

from .profiles import Profile, read_profile

__all__ = [
    "PairSetup",
    "ContactGeometry",
    "ContactTable",
    "ContactState",
    "DATA_DIR",
    "DEFAULT_TABLE",
    "DEFAULT_WHEEL",
    "DEFAULT_RAIL",
    "default_setup",
    "table_path",
]

DATA_DIR = Path(__file__).resolve().parent / "data"
DEFAULT_WHEEL = DATA_DIR / "MBench_S1002_v3.prw"
DEFAULT_RAIL = DATA_DIR / "MBench_UIC60_v3.prr"
DEFAULT_TABLE = DATA_DIR / "S1002_UIC60_1in40_1435_r460.csv"


def table_path(nominal_radius_m: float = 0.46) -> Path:
    """Path of the shipped S1002 / UIC60 1:40 / 1435 mm table for wheels of ``nominal_radius_m``
    (``data/S1002_UIC60_1in40_1435_r<radius in mm>.csv``; written by
    ``python -m vehicle.wheelrail.derive_table --nominal-radius-m <r>``). It may not exist."""
    mm = round(1000.0 * float(nominal_radius_m), 6)
    label = f"{mm:g}".replace(".", "p")
    return DATA_DIR / f"S1002_UIC60_1in40_1435_r{label}.csv"


@dataclass(frozen=True)
class PairSetup:
    """Track and wheelset dimensions of a wheel-rail pair (SI except profile-coordinate mm)."""

    gauge_m: float = 1.435
    gauge_height_mm: float = 14.0  # gauge measured 14 mm below the running surface (EN 13848-1)
    inclination: float = 1.0 / 40.0  # rail inclination (cant) towards the track centre, rad
    rail_profile_inclined: bool = False  # True: the rail file already contains the inclination
    flange_back_distance_m: float = 1.360  # wheel back-to-back (inner faces of the flanges)
    flange_back_pos_mm: float = -70.0  # flange back in wheel-profile coordinates
    nominal_radius_m: float = 0.46
    tape_circle_y_mm: float = 0.0  # wheel-profile coordinate where r = nominal_radius_m

    def __post_init__(self):
        for name in ("gauge_m", "flange_back_distance_m", "nominal_radius_m", "gauge_height_mm"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive")
        if not abs(self.inclination) < 0.2:
            raise ValueError("inclination is an angle in rad (1/40 = 0.025)")


def default_setup() -> PairSetup:
    """The default pair: Manchester-benchmark S1002 on UIC60 (file already inclined 1:40),
    gauge 1435 mm, back-to-back 1360 mm, r0 = 0.46 m."""
    return PairSetup(rail_profile_inclined=True)


class _Curve:
    """Parametric cubic spline (chord length) of a canonical profile, densely sampled."""

    def __init__(self, y: np.ndarray, z: np.ndarray, ds: float):
        # drop points closer than 1 um to the previous one (the benchmark rail has runs of
        # points 1e-6 mm apart at the foot of the gauge face; they would only ill-condition the
        # spline, far from any contact)
        keep = [0]
        for i in range(1, y.size):
            if math.hypot(y[i] - y[keep[-1]], z[i] - z[keep[-1]]) > 1e-3:
                keep.append(i)
        y, z = y[keep], z[keep]
        s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(y), np.diff(z)))])
        self.sy = CubicSpline(s, y)
        self.sz = CubicSpline(s, z)
        n = int(math.ceil(s[-1] / ds)) + 1
        self.s = np.linspace(0.0, s[-1], n)
        self.y = self.sy(self.s)
        self.z = self.sz(self.s)

    def at(self, s):
        """y, z, dy/ds, dz/ds, d2y/ds2, d2z/ds2 at parameter s."""
        return (self.sy(s), self.sz(s), self.sy(s, 1), self.sz(s, 1), self.sy(s, 2),
                self.sz(s, 2))


class _SideContact(NamedTuple):
    gap: float  # vertical gap (mm) at nominal centre height
    Y: float  # track-frame lateral position of the contact (mm)
    yw: float  # wheel-profile coordinate (mm)
    zw: float  # wheel-profile height (mm, down)
    yr: float  # rail-profile coordinate (mm)
    delta: float  # contact angle relative to the axle (rad)
    kw: float  # wheel transverse curvature (1/mm)
    kr: float  # rail transverse curvature (1/mm)
    gap2: float
    yw2: float


class ContactGeometry:
    """Rigid contact search for one wheel-rail pair (the machinery behind :class:`ContactTable`)."""

    def __init__(self, wheel: Profile, rail: Profile, setup: PairSetup, ds_mm: float = 0.01):
        if wheel.kind != "wheel" or rail.kind != "rail":
            raise ValueError("need a wheel profile and a rail profile")
        self.setup = setup
        self.wheel = wheel
        self.rail = rail
        # --- rail, left side, track frame (mm): inclination, top to z = 0, gauge point ---
        yr, zr = rail.y_mm.copy(), rail.z_mm.copy()
        if not setup.rail_profile_inclined:
            th = setup.inclination
            # canonical (y to field, z down): tilting the head towards the track centre (-y)
            yr, zr = yr * math.cos(th) + zr * math.sin(th), -yr * math.sin(th) + zr * math.cos(th)
        self._rail_rot = (yr, zr)  # installed orientation, file origin
        self.rail_curve = _Curve(yr, zr, ds_mm)
        rc = self.rail_curve
        self.rail_dz_top = float(rc.z.min())  # shift so the top touches the track plane
        zt = rc.z - self.rail_dz_top
        below = zt >= setup.gauge_height_mm
        # first crossing of the gauge depth walking from the gauge-side end (index 0)
        if not below[0]:
            raise ValueError("rail profile does not reach the gauge measuring depth on its "
                             "gauge side")
        k = int(np.argmax(~below))
        y_g = float(np.interp(setup.gauge_height_mm, [zt[k], zt[k - 1]], [rc.y[k], rc.y[k - 1]]))
        self.rail_y_gauge = y_g
        half_gauge_mm = 500.0 * setup.gauge_m
        self.rail_offset = half_gauge_mm - y_g  # track Y of the rail-profile origin (left rail)
        self.rail_Y = self.rail_offset + rc.y
        self.rail_Z = -zt
        # --- wheel: wheelset frame (mm), ascending Y ---
        wc = _Curve(wheel.y_mm, wheel.z_mm, ds_mm)
        self.wheel_curve = wc
        ytape = setup.tape_circle_y_mm
        if not (wheel.y_mm.min() <= ytape <= wheel.y_mm.max()):
            raise ValueError("tape circle position outside the wheel profile")
        order = np.argsort(wc.y)
        self._w_y = wc.y[order]
        self._w_z = wc.z[order]
        self._w_s = wc.s[order]
        z_tape = float(np.interp(ytape, self._w_y, self._w_z))
        self.r_eff_mm = 1000.0 * setup.nominal_radius_m - z_tape  # axle to profile datum
        self.wheel_offset = 500.0 * setup.flange_back_distance_m - setup.flange_back_pos_mm
        self._wY = self.wheel_offset + self._w_y
        self._wZ = -(self.r_eff_mm + self._w_z)
        self.zc_nom = 1000.0 * setup.nominal_radius_m

    # ------------------------------------------------------------------ single side
    def side(self, y_mm: float, roll: float, details: bool = False):
        """Left-side contact for wheelset lateral displacement y (mm) and roll (rad), centre at
        nominal height. Returns the gap (mm) or, with details, a :class:`_SideContact`."""
        c, s = math.cos(roll), math.sin(roll)
        Y = y_mm + c * self._wY - s * self._wZ
        Z = self.zc_nom + s * self._wY + c * self._wZ
        if np.any(np.diff(Y) <= 0):
            raise RuntimeError("rolled wheel profile is no longer a graph over y")
        zw = np.interp(self.rail_Y, Y, Z, left=np.nan, right=np.nan)
        g = zw - self.rail_Z
        g = np.where(np.isnan(g), np.inf, g)
        i = int(np.argmin(g))
        if not np.isfinite(g[i]):
            raise RuntimeError("wheel and rail do not overlap laterally")
        t, gmin = 0.0, float(g[i])
        if 0 < i < g.size - 1 and np.isfinite(g[i - 1]) and np.isfinite(g[i + 1]):
            den = g[i - 1] - 2.0 * g[i] + g[i + 1]
            if den > 0:
                t = 0.5 * (g[i - 1] - g[i + 1]) / den
                t = min(0.5, max(-0.5, t))
                gmin = float(g[i] - 0.25 * (g[i - 1] - g[i + 1]) * t)
        if not details:
            return gmin
        rc = self.rail_curve
        s_r = float(np.interp(i + t, np.arange(rc.s.size), rc.s))
        ry, rz, ry1, rz1, ry2, rz2 = (float(v) for v in rc.at(s_r))
        Yc = self.rail_offset + ry
        # wheel point under the contact: invert Y(wheel index)
        fi = float(np.interp(Yc, Y, np.arange(Y.size)))
        s_w = float(np.interp(fi, np.arange(Y.size), self._w_s))
        wy, wz, wy1, wz1, wy2, wz2 = (float(v) for v in self.wheel_curve.at(s_w))
        delta = math.atan2(-wz1, wy1) if wy1 > 0 else math.atan2(wz1, -wy1)
        # curvatures, convex towards the other body positive (see module docstring)
        kappa_w = (wy1 * wz2 - wz1 * wy2) / (wy1 * wy1 + wz1 * wz1) ** 1.5
        if wy1 > 0:  # parameter runs to +y: flip to the descending-y convention
            kappa_w = -kappa_w
        kappa_r = (ry1 * rz2 - rz1 * ry2) / (ry1 * ry1 + rz1 * rz1) ** 1.5
        if ry1 < 0:
            kappa_r = -kappa_r
        gap2, yw2 = self._second_minimum(g, i, Y)
        return _SideContact(gmin, Yc, wy, wz, ry, delta, kappa_w, kappa_r, gap2, yw2)

    def _second_minimum(self, g: np.ndarray, i: int, Y: np.ndarray):
        """Nearest other local minimum of the gap with a prominence of at least 1 um, on a
        0.1 mm decimated grid (the second potential contact point)."""
        step = 10
        idx = np.arange(0, g.size, step)
        gd = g[idx]
        fin = np.isfinite(gd)
        best = (math.nan, math.nan)
        cand = np.where(fin[1:-1] & (gd[1:-1] <= gd[:-2]) & (gd[1:-1] <= gd[2:]))[0] + 1
        for j in cand:
            k = idx[j]
            if abs(self.rail_Y[k] - self.rail_Y[i]) < 1.0:
                continue
            lo, hi = sorted((k, i))
            ridge = float(np.max(g[lo:hi + 1]))
            if ridge - g[k] < 1e-3:
                continue
            if math.isnan(best[0]) or g[k] < best[0]:
                Yk = float(self.rail_Y[k])
                fi = float(np.interp(Yk, Y, np.arange(Y.size)))
                yw = float(np.interp(fi, np.arange(Y.size), self._w_y))
                best = (float(g[k]), yw)
        return best

    # ------------------------------------------------------------------ wheelset
    def solve(self, y_mm: float, roll_bracket: float = 0.08) -> dict:
        """Two-point rigid contact for lateral displacement y (mm): roll, height, both contacts."""

        def f(roll):
            return self.side(y_mm, roll) - self.side(-y_mm, -roll)

        a, b = -roll_bracket, roll_bracket
        roll = brentq(f, a, b, xtol=1e-14, rtol=4 * np.finfo(float).eps, maxiter=200)
        L = self.side(y_mm, roll, details=True)
        R = self.side(-y_mm, -roll, details=True)
        r0 = self.r_eff_mm
        return {
            "y_ws_mm": y_mm,
            "roll_rad": roll,
            "dz_mm": -L.gap,  # absolute; made relative to y = 0 by the caller
            "r_L_m": (r0 + L.zw) / 1000.0,
            "r_R_m": (r0 + R.zw) / 1000.0,
            "gamma_L_rad": L.delta + roll,
            "gamma_R_rad": R.delta - roll,
            "yw_L_mm": L.yw,
            "yw_R_mm": R.yw,
            "yr_L_mm": L.yr,
            "yr_R_mm": R.yr,
            "yc_L_m": L.Y / 1000.0,
            "yc_R_m": -R.Y / 1000.0,
            "kw_L_1pm": 1000.0 * L.kw,
            "kw_R_1pm": 1000.0 * R.kw,
            "kr_L_1pm": 1000.0 * L.kr,
            "kr_R_1pm": 1000.0 * R.kr,
            "gap2_L_mm": L.gap2,
            "gap2_R_mm": R.gap2,
            "yw2_L_mm": L.yw2,
            "yw2_R_mm": R.yw2,
        }


COLUMNS = [
    "y_ws_mm", "roll_rad", "dz_mm",
    "r_L_m", "r_R_m", "gamma_L_rad", "gamma_R_rad",
    "yw_L_mm", "yw_R_mm", "yr_L_mm", "yr_R_mm", "yc_L_m", "yc_R_m",
    "kw_L_1pm", "kw_R_1pm", "kr_L_1pm", "kr_R_1pm",
    "gap2_L_mm", "gap2_R_mm", "yw2_L_mm", "yw2_R_mm",
]


#: a table cell is refined when between its rows a contact angle changes by more than this
#: [rad] or a contact point moves on the wheel profile by more than this [mm] (either wheel):
#: the contact jumps and the steep flanks next to them (S1002 / UIC60 1:40: near +-0.25,
#: +-4.9 and +-6.0 .. 6.8 mm)
REFINE_WHEN = {"gamma_{}_rad": 0.02, "yw_{}_mm": 0.5}


def _cells_to_refine(rows: list[dict]) -> list[int]:
    """Indices i of the cells [row i, row i + 1] to refine (see :data:`REFINE_WHEN`)."""
    out = []
    for i, (a, b) in enumerate(zip(rows[:-1], rows[1:])):
        if any(abs(b[q.format(s)] - a[q.format(s)]) > lim
               for q, lim in REFINE_WHEN.items() for s in "LR"):
            out.append(i)
    return out


class ContactState(NamedTuple):
    """Interpolated contact geometry at wheelset lateral displacement y (SI units)."""

    y: np.ndarray | float  # wheelset lateral displacement (m, left positive)
    r_L: np.ndarray | float  # rolling radii (m)
    r_R: np.ndarray | float
    gamma_L: np.ndarray | float  # contact angles, track frame (rad)
    gamma_R: np.ndarray | float
    yw_L: np.ndarray | float  # contact position on the wheel profile (m, field side positive)
    yw_R: np.ndarray | float
    yr_L: np.ndarray | float  # contact position on the rail profile (m, field side positive)
    yr_R: np.ndarray | float
    yc_L: np.ndarray | float  # contact lateral position in the track frame (m, left positive)
    yc_R: np.ndarray | float
    roll: np.ndarray | float  # wheelset roll (rad, left side up positive)
    dz: np.ndarray | float  # wheelset centre rise relative to the centred position (m)


class ContactTable:
    """Tabulated rigid contact geometry over the wheelset lateral displacement."""

    def __init__(self, columns: dict[str, np.ndarray], meta: dict[str, str] | None = None):
        missing = [c for c in COLUMNS if c not in columns]
        if missing:
            raise ValueError(f"contact table lacks columns {missing}")
        self.columns = {k: np.asarray(v, dtype=float) for k, v in columns.items()}
        y = self.columns["y_ws_mm"]
        if y.ndim != 1 or y.size < 3 or np.any(np.diff(y) <= 0):
            raise ValueError("y_ws_mm must be strictly increasing with at least 3 rows")
        self.meta = dict(meta or {})

    # ---------------------------------------------------------------- construction
    @classmethod
    def from_profiles(cls, wheel_file, rail_file, gauge_m: float = 1.435,
                      inclination: float = 1.0 / 40.0, *, rail_profile_inclined: bool = False,
                      flange_back_distance_m: float = 1.360, flange_back_pos_mm: float = -70.0,
                      nominal_radius_m: float = 0.46, tape_circle_y_mm: float = 0.0,
                      gauge_height_mm: float = 14.0, y_max_mm: float = 12.0,
                      dy_mm: float = 0.1) -> "ContactTable":
        """Derive the table from profile files (SIMPACK .prw/.prr or canonical 2-column tables).

        ``inclination`` is the rail inclination of the track (1/40 = 0.025 rad); set
        ``rail_profile_inclined=True`` when the rail file is already drawn inclined (as the
        Manchester-benchmark UIC60 file is), so it is not rotated a second time."""
        setup = PairSetup(gauge_m=gauge_m, gauge_height_mm=gauge_height_mm,
                          inclination=inclination, rail_profile_inclined=rail_profile_inclined,
                          flange_back_distance_m=flange_back_distance_m,
                          flange_back_pos_mm=flange_back_pos_mm,
                          nominal_radius_m=nominal_radius_m, tape_circle_y_mm=tape_circle_y_mm)
        wheel = read_profile(wheel_file, "wheel")
        rail = read_profile(rail_file, "rail")
        return cls.derive(wheel, rail, setup, y_max_mm=y_max_mm, dy_mm=dy_mm)

    @classmethod
    def derive(cls, wheel: Profile, rail: Profile, setup: PairSetup, y_max_mm: float = 12.0,
               dy_mm: float = 0.1, refine_dy_mm: float | None = 0.01) -> "ContactTable":
        """The table on a grid of ``dy_mm`` over +-``y_max_mm``, refined to ``refine_dy_mm``
        in every cell where the contact point moves fast (:data:`REFINE_WHEN`; None: no
        refinement).

        Why refine: between rows the table is read by linear interpolation, which blends a jump
        over its whole cell; with the jump cells every 0.01 mm the jumps are located to
        0.01 mm and the fast turn of the contact angle before the flange jump (0.50 to 0.67 rad
        over the last 0.1 mm) is resolved. The force law does not read the rigid rows as they
        are: it smooths them (:class:`~vehicle.wheelrail.contact_law.ContactLawTable`, where the
        reason is measured)."""
        geo = ContactGeometry(wheel, rail, setup)
        n = int(round(y_max_mm / dy_mm))
        if not math.isclose(n * dy_mm, y_max_mm, rel_tol=0, abs_tol=1e-9):
            raise ValueError("y_max_mm must be a multiple of dy_mm")
        ys = np.arange(-n, n + 1) * dy_mm
        rows = [geo.solve(float(y)) for y in ys]
        if refine_dy_mm is not None:
            m = int(round(dy_mm / refine_dy_mm))
            if m < 2 or not math.isclose(m * refine_dy_mm, dy_mm, rel_tol=1e-12):
                raise ValueError("dy_mm must be a multiple (>= 2) of refine_dy_mm")
            fine = [k for i in _cells_to_refine(rows) for k in range(m * (i - n) + 1,
                                                                     m * (i + 1 - n))]
            extra = {k: geo.solve(k * refine_dy_mm) for k in fine}
            grid = sorted([m * (i - n) for i in range(ys.size)] + fine)
            ys = np.array(grid, dtype=float) * refine_dy_mm
            coarse = {m * (i - n): row for i, row in enumerate(rows)}
            rows = [coarse[k] if k in coarse else extra[k] for k in grid]
        cols = {c: np.array([row[c] for row in rows], dtype=float) for c in COLUMNS}
        cols["y_ws_mm"] = ys
        i0 = int(np.argmin(np.abs(ys)))  # y = 0
        cols["dz_mm"] = cols["dz_mm"] - cols["dz_mm"][i0]
        meta = {
            "wheel_profile": Path(wheel.source).name,
            "wheel_profile_md5": _md5(wheel.source),
            "rail_profile": Path(rail.source).name,
            "rail_profile_md5": _md5(rail.source),
            **{k: repr(v) for k, v in asdict(setup).items()},
            "wheel_profile_datum_lateral_mm": repr(geo.wheel_offset),
            "rail_profile_origin_lateral_mm": repr(geo.rail_offset),
            "rail_gauge_point_y_mm": repr(geo.rail_y_gauge),
            "method": "rigid, yaw-free, minimum vertical distance per side, roll by Brent",
            "grid": (f"every {dy_mm!r} mm" if refine_dy_mm is None else
                     f"every {dy_mm!r} mm, every {refine_dy_mm!r} mm in cells where "
                     + ", ".join(f"|d {k.format('L/R')}| > {v!r}" for k, v in REFINE_WHEN.items())),
        }
        return cls(cols, meta)

    @classmethod
    def from_csv(cls, path) -> "ContactTable":
        """Read a table written by :meth:`to_csv` (``#`` lines: ``# key: value`` metadata)."""
        path = Path(path)
        meta: dict[str, str] = {}
        header = None
        with path.open(encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("#"):
                    key, sep, value = line[1:].partition(":")
                    if sep:
                        meta[key.strip()] = value.strip()
                    continue
                header = [h.strip() for h in line.strip().split(",")]
                break
            data = np.loadtxt(fh, delimiter=",", ndmin=2)
        if header is None:
            raise ValueError(f"{path}: no column header")
        return cls({h: data[:, j] for j, h in enumerate(header)}, meta)

    @classmethod
    def cone(cls, conicity: float, r0_m: float = 0.46, half_spacing_m: float = 0.75,
             y_max_mm: float = 12.0, dy_mm: float = 0.1,
             rail_crown_radius_m: float = 0.3, level_contact: bool = False) -> "ContactTable":
        """Analytic table of a pure cone (tan delta = ``conicity``) on knife-edge rails at
        y = +-``half_spacing_m`` (b): the contact points stay at the rails, so
        r_L,R = r0 +- lambda y exactly, roll tan(phi) = lambda y / b, rise dz ~ lambda y^2 / b
        (both wheel points on their rail), contact angles gamma_L,R = atan(lambda) +- phi. For
        the Hertz ellipse the wheel is straight across (kw = 0) and the rail has a crown of
        ``rail_crown_radius_m``. The textbook wheelset for
        Klingel's formula: its equivalent conicity is lambda at every amplitude.

        ``conicity`` is the equivalent conicity (r_L - r_R = 2 lambda y), not the slope of a real
        cone on knife-edge rails, whose contact points move on the wheel by the roll as well
        (y + r0 phi) and whose equivalent conicity is slope x b / (b - slope r0); the contact
        angle atan(lambda) stands for the slope (they differ by lambda r0 / b, 5.6 % at 0.1).

        ``level_contact`` (an experiment): every contact angle 0 in the track frame, the normal
        forces vertical: no gravitational stiffness, no spin creepage from the cone, no lateral
        share of the normal forces' load transfer -- the wheelset of the textbook linear model
        without gravitational terms (tests/independent/cooperrider.py, ``gravity=False``)."""
        lam, b = float(conicity), float(half_spacing_m)
        if not (0 < lam < 1 and r0_m > 0 and b > 0 and rail_crown_radius_m > 0):
            raise ValueError("need 0 < conicity < 1 and positive r0, half spacing, crown radius")
        n = int(round(y_max_mm / dy_mm))
        y_mm = np.arange(-n, n + 1) * dy_mm
        y = y_mm * 1e-3
        rL, rR = r0_m + lam * y, r0_m - lam * y
        # wheel points at axle coordinates uL = b - y, uR = -b - y touch the rails (z = 0):
        # h + u sin(phi) - r cos(phi) = 0 on both sides
        phi = np.arctan2(rL - rR, 2.0 * b)
        h = rL * np.cos(phi) - (b - y) * np.sin(phi)
        delta = math.atan(lam)
        nan = np.full(y.size, np.nan)
        cols = {
            "y_ws_mm": y_mm, "roll_rad": phi, "dz_mm": 1e3 * (h - r0_m),
            "r_L_m": rL, "r_R_m": rR,
            "gamma_L_rad": 0 * y if level_contact else delta + phi,
            "gamma_R_rad": 0 * y if level_contact else delta - phi,
            "yw_L_mm": -y_mm, "yw_R_mm": y_mm, "yr_L_mm": 0 * y, "yr_R_mm": 0 * y,
            "yc_L_m": np.full(y.size, b), "yc_R_m": np.full(y.size, -b),
            "kw_L_1pm": 0 * y, "kw_R_1pm": 0 * y,
            "kr_L_1pm": np.full(y.size, 1.0 / rail_crown_radius_m),
            "kr_R_1pm": np.full(y.size, 1.0 / rail_crown_radius_m),
            "gap2_L_mm": nan, "gap2_R_mm": nan, "yw2_L_mm": nan, "yw2_R_mm": nan,
        }
        meta = {"method": f"analytic cone, conicity {lam!r}, knife-edge rails at +-{b!r} m, "
                          f"r0 {r0_m!r} m" + (", level contact (contact angles 0)" if level_contact else "")}
        return cls(cols, meta)

    @classmethod
    def default(cls) -> "ContactTable":
        """The shipped S1002 / UIC60 1:40 / 1435 mm / r0 = 0.46 m table."""
        return cls.from_csv(DEFAULT_TABLE)

    def to_csv(self, path=None) -> str:
        buf = io.StringIO()
        buf.write("# rigid wheel-rail contact table, vehicle.wheelrail (derive_table.py)\n")
        buf.write("# columns: see vehicle/wheelrail/geometry.py and docs/wheel_rail.md; units in "
                  "the names; _L left wheel (track y > 0), _R right wheel\n")
        for k, v in self.meta.items():
            buf.write(f"# {k}: {v}\n")
        buf.write(",".join(COLUMNS) + "\n")
        for i in range(self.columns["y_ws_mm"].size):
            buf.write(",".join(_fmt(self.columns[c][i]) for c in COLUMNS) + "\n")
        text = buf.getvalue()
        if path is not None:
            Path(path).write_text(text, encoding="utf-8")
        return text

    # ---------------------------------------------------------------- queries
    @property
    def y_range_m(self) -> tuple[float, float]:
        y = self.columns["y_ws_mm"]
        return float(y[0]) / 1000.0, float(y[-1]) / 1000.0

    @property
    def r0(self) -> float:
        """Rolling radius of the centred wheelset (m)."""
        return float(np.interp(0.0, self.columns["y_ws_mm"], self.columns["r_L_m"]))

    @property
    def contact_half_spacing(self) -> float:
        """b: half the lateral distance between the contact points of the centred wheelset (m)."""
        y = self.columns["y_ws_mm"]
        return 0.5 * float(np.interp(0.0, y, self.columns["yc_L_m"])
                           - np.interp(0.0, y, self.columns["yc_R_m"]))

    def _interp(self, name: str, y_m):
        yt = self.columns["y_ws_mm"]
        ymm = 1000.0 * np.asarray(y_m, dtype=float)
        if np.any(ymm < yt[0] - 1e-9) or np.any(ymm > yt[-1] + 1e-9):
            raise ValueError(f"y outside the table range [{yt[0]}, {yt[-1]}] mm")
        out = np.interp(ymm, yt, self.columns[name])
        return float(out) if np.ndim(out) == 0 else out

    def at(self, y_m) -> ContactState:
        """Linearly interpolated contact geometry at wheelset lateral displacement ``y_m`` (m)."""
        g = self._interp
        mm = 1e-3
        return ContactState(
            y=y_m, r_L=g("r_L_m", y_m), r_R=g("r_R_m", y_m),
            gamma_L=g("gamma_L_rad", y_m), gamma_R=g("gamma_R_rad", y_m),
            yw_L=g("yw_L_mm", y_m) * mm, yw_R=g("yw_R_mm", y_m) * mm,
            yr_L=g("yr_L_mm", y_m) * mm, yr_R=g("yr_R_mm", y_m) * mm,
            yc_L=g("yc_L_m", y_m), yc_R=g("yc_R_m", y_m),
            roll=g("roll_rad", y_m), dz=g("dz_mm", y_m) * mm)

    def delta_r(self, y_m):
        """Rolling-radius difference r_L - r_R (m) at lateral displacement y (m)."""
        return self._interp("r_L_m", y_m) - self._interp("r_R_m", y_m)

    def contact_jumps(self, min_step_mm: float = 1.0) -> list[dict]:
        """Rows where the contact point on a wheel jumps by more than ``min_step_mm`` between
        neighbouring table rows (positive y side, left wheel; the right wheel mirrors it)."""
        y = self.columns["y_ws_mm"]
        out = []
        for side in ("L", "R"):
            yw = self.columns[f"yw_{side}_mm"]
            gam = self.columns[f"gamma_{side}_rad"]
            for i in np.where(np.abs(np.diff(yw)) > min_step_mm)[0]:
                out.append({"side": side, "y_from_mm": float(y[i]), "y_to_mm": float(y[i + 1]),
                            "yw_from_mm": float(yw[i]), "yw_to_mm": float(yw[i + 1]),
                            "gamma_from_rad": float(gam[i]), "gamma_to_rad": float(gam[i + 1])})
        return out

    def flange_contact_y(self, gamma_min_rad: float = 0.7) -> float:
        """Smallest positive lateral displacement (m) at which the left wheel's contact angle
        exceeds ``gamma_min_rad`` (flange contact; 0.7 rad = 40 deg separates tread/root from
        flange flank). NaN if it never does within the table."""
        y = self.columns["y_ws_mm"]
        gam = self.columns["gamma_L_rad"]
        hit = np.where((y > 0) & (gam > gamma_min_rad))[0]
        return float(y[hit[0]]) / 1000.0 if hit.size else math.nan

    # ---------------------------------------------------------------- conicity
    def equivalent_conicity(self, amplitude_m: float = 0.003, method: str = "harmonic",
                            n: int = 4096) -> float:
        """Equivalent conicity for a lateral wheelset amplitude ``amplitude_m``.

        ``harmonic``: harmonic linearisation (describing function) of Delta r(y) = r_L - r_R,
            lambda_e = b1 / (2 A),  b1 = (1/pi) * int_0^{2pi} Delta r(A sin phi) sin phi dphi
                                       = (2/pi) * int_0^{pi} Delta r(A sin phi) sin phi dphi
            (the fundamental Fourier coefficient of Delta r over a sinusoid of amplitude A).
        ``klingel``: EN 15302 / UIC 519 style "integration of the linearised (Klingel)
            equation": the kinematic wheelset motion y'' = -Delta r(y) / (2 b r0) (derivatives
            along the track, b = half the contact spacing, r0 = centred rolling radius) is
            integrated from y = A, y' = 0 for one period (wavelength L) and
            lambda_e = r0 b (2 pi / L)^2, the conicity of the linear Klingel wavelength
            L = 2 pi sqrt(r0 b / lambda) with the same period. A is the amplitude (half the
            peak-to-peak) of the wheelset's lateral displacement, as in EN 15302.
        """
        A = float(amplitude_m)
        lo, hi = self.y_range_m
        if not (0 < A <= min(-lo, hi)):
            raise ValueError("amplitude must be positive and inside the table range")
        if method == "harmonic":
            # midpoint rule on [0, pi]: spectrally accurate for the periodic integrand
            phi = (np.arange(n) + 0.5) * math.pi / n
            b1 = (2.0 / math.pi) * float(np.sum(self.delta_r(A * np.sin(phi)) * np.sin(phi))) \
                * (math.pi / n)
            return b1 / (2.0 * A)
        if method == "klingel":
            r0, b = self.r0, self.contact_half_spacing
            k = 1.0 / (2.0 * b * r0)

            def rhs(_x, u):
                return [u[1], -k * self.delta_r(min(max(u[0], lo), hi))]

            def crossing(_x, u):  # y' = 0 with y < 0: half period
                return u[1]

            crossing.direction = 1.0
            crossing.terminal = True
            lam_guess = max(self.equivalent_conicity(A, "harmonic"), 1e-3)
            L_guess = 2 * math.pi * math.sqrt(r0 * b / lam_guess)
            sol = solve_ivp(rhs, (0.0, 3.0 * L_guess), [A, 0.0], events=crossing,
                            rtol=1e-10, atol=1e-13, max_step=L_guess / 200.0)
            if not sol.t_events[0].size:
                raise RuntimeError("no half period found in the Klingel integration")
            L = 2.0 * float(sol.t_events[0][0])
            return r0 * b * (2.0 * math.pi / L) ** 2
        raise ValueError("method must be 'harmonic' or 'klingel'")

    def klingel_wavelength(self, conicity: float) -> float:
        """Klingel's kinematic wavelength L = 2 pi sqrt(r0 b / lambda) (m)."""
        return 2.0 * math.pi * math.sqrt(self.r0 * self.contact_half_spacing / conicity)


def _fmt(v: float) -> str:
    if not np.isfinite(v):
        return "nan"
    return f"{v:.12g}"


def _md5(path) -> str:
    try:
        return hashlib.md5(Path(path).read_bytes()).hexdigest()
    except OSError:
        return "n/a"
