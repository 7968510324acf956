"""Track irregularities: lateral alignment, vertical level, cross-level and gauge
as functions of the distance s along the track, read from a CSV file or generated from a
one-sided power spectral density (ERRI B176 low/high level, FRA classes 1-6) with a seed.

Pure numpy/scipy (the evaluation compiled by numba where available); no exudyn, no
``pneumatics``/``cosim`` imports. Nothing here is switched on by itself: a model that wants
irregularities builds a :class:`TrackIrregularity` and evaluates it.
User documentation with the formulas, coefficients and their sources: ``docs/track_irregularities.md``.

Quantities and signs (all in metres, s in metres along the running direction; track frame x
forward, **y to the left**, z up -- the frame of :mod:`vehicle.track` and :mod:`vehicle.wheelrail`)
-------------------------------------------------------------------------------------------------

* ``lateral_m`` -- alignment: lateral displacement of the track centre line (mean of the two
  rails' lateral positions), **positive to the left** of the running direction (+y).
* ``vertical_m`` -- vertical level (longitudinal level) of the track centre line (mean of the two
  rails' heights), **positive up**.
* ``cross_level_m`` -- **right rail height minus left rail height** (z_R - z_L). This is the sign
  of :mod:`vehicle.track`'s cant (positive cant raises the right rail), so an irregularity adds
  to the design height difference ``b sin(cant)``; the track plane's roll about +x (positive
  lifts the left rail, as in :mod:`vehicle.wheelrail`) changes by ``-cross_level_m / b``, b the
  distance between the points where the heights are taken.
* ``gauge_m`` -- gauge deviation from nominal, **positive = wider** track.

Each rail's offset from its nominal position (:meth:`TrackIrregularity.rail_offsets`)::

    y_L = lateral + gauge/2      z_L = vertical - cross_level/2
    y_R = lateral - gauge/2      z_R = vertical + cross_level/2

Evaluation: a shape-preserving piecewise cubic through the samples (PCHIP: continuous slope,
so the rails' lateral and vertical velocities under a running car are continuous, and no
overshoot beyond the samples); **zero outside [s_0, s_end]** (ideal track before and after the
described stretch). Linear interpolation, as the first version had, makes the rail velocity
jump at every sample: at 20 m/s over samples 0.25 m apart the creep forces then took a kick
every 12.5 ms, and the largest lateral wheel force of the straight run moved by 4 %
non-monotonically as the time step was halved (docs/track_irregularities.md). A signal that
does not start and end at zero therefore steps there; :meth:`TrackIrregularity.tapered` fades
the ends in and out with a raised cosine.

File format (:meth:`TrackIrregularity.from_file`)
-------------------------------------------------
CSV, header ``s_m,lateral_m,vertical_m,cross_level_m,gauge_m`` (``s_m`` required, the others
optional and in any order; a missing column is zero), values in metres, s strictly increasing.
Blank lines and lines starting with ``#`` are ignored. Any irregularity of magnitude above
0.1 m is refused as a probable unit mistake (millimetres written as metres); ``max_abs_m``
raises that limit for very poor track.

PSD models (:func:`psd`, :meth:`TrackIrregularity.from_psd`)
-------------------------------------------------------------
Convention: **one-sided PSD in angular wavenumber**, S(Omega) in m^2/(rad/m), Omega = 2 pi /
wavelength in rad/m, such that the variance is ``sigma^2 = integral_0^inf S(Omega) dOmega``.
In cycles per metre (f = 1/wavelength) the same spectrum is ``S_f(f) = 2 pi S(2 pi f)`` in
m^2/(cycle/m) (:func:`psd_per_cycle`); that is what ``scipy.signal.welch(x, fs=1/ds)`` estimates.

ERRI B176 (ORE/ERRI committee B176, "low" and "high" level; the same numbers are published in the
Chinese literature as the "German" high-speed spectra), Omega_c = 0.8246, Omega_r = 0.0206,
Omega_s = 0.4380 rad/m::

    vertical     S_v(Omega) = A_v Omega_c^2 / ((Omega^2 + Omega_r^2)(Omega^2 + Omega_c^2))
    lateral      S_a(Omega) = A_a Omega_c^2 / ((Omega^2 + Omega_r^2)(Omega^2 + Omega_c^2))
    cross-level  S_c(Omega) = (A_v / b^2) Omega_c^2 Omega^2
                              / ((Omega^2 + Omega_r^2)(Omega^2 + Omega_c^2)(Omega^2 + Omega_s^2))
    gauge        S_g(Omega) = A_g Omega_c^2 Omega^2
                              / ((Omega^2 + Omega_r^2)(Omega^2 + Omega_c^2)(Omega^2 + Omega_s^2))

    level  A_v [m^2 rad/m]  A_a [m^2 rad/m]  A_g [m^2 rad/m]
    low    4.032e-7         2.119e-7         5.32e-8
    high   1.080e-6         6.125e-7         1.032e-7

S_c is the PSD of the cross-level *angle* (rad^2/(rad/m)), b = half the distance between the
rails' reference points. Here cross-level is a height difference over 2b, whose PSD is
(2b)^2 S_c = 4 A_v Omega_c^2 Omega^2 / (...): b cancels, no rail distance is needed.

FRA classes 1-6 (US Federal Railroad Administration; Hamid & Yang's fits as reproduced by Garg &
Dukkipati, "Dynamics of Railway Vehicle Systems", 1984), k = 0.25, Omega_c = 0.8245 rad/m, A in
cm^2 rad/m (converted here to m^2 rad/m by 1e-4)::

    vertical     S_v(Omega) = k A_v Omega_c^2 / (Omega^2 (Omega^2 + Omega_c^2))
    lateral      S_a(Omega) = k A_a Omega_c^2 / (Omega^2 (Omega^2 + Omega_c^2))
    cross-level  S_c(Omega) = 4 k A_v Omega_c^2 / ((Omega^2 + Omega_c^2)(Omega^2 + Omega_s^2))
    gauge        S_g(Omega) = S_c(Omega)

    class  A_v      A_a      Omega_s
    1      1.2107   3.3634   0.6046
    2      1.0181   1.2107   0.9308
    3      0.6816   0.4128   0.8520
    4      0.5376   0.3027   1.1312
    5      0.2095   0.0762   0.8209
    6      0.0339   0.0339   0.4380

How sure the coefficients are (none of the primary reports was available to read): ERRI B176 A_v,
A_a, Omega_c, Omega_r, Omega_s and the cross-level form agree across several independent public
implementations (one labelled "ERRI", others "German spectrum"), and a published summary gives
the cross-level PSD in 1/(rad/m) with b half the rail-centre distance; the gauge coefficients
A_g come from a single implementation. FRA A_v (all classes), Omega_c and k were checked against
two public implementations; FRA A_a, Omega_s and the cross-level/gauge form are **transcribed
from memory of the widely reproduced table and were not verified against a source read here**.
Whether the published spectra are meant as one- or two-sided is not stated in what was read; the
one-sided reading taken here (amplitudes sqrt(2 S dOmega), as the implementations that were read
use) gives sigma = 0.98 mm for ERRI low vertical level in the 3-25 m band, a plausible value for
good track.

Generation: sum of cosines with random phases (Shinozuka) on the harmonics Omega_k = 2 pi k / P
of a period P = max(length_m, 8 * longest wavelength), dOmega = 2 pi / P. Harmonic k carries the
power of its cell [Omega_k - dOmega/2, Omega_k + dOmega/2] clipped to the band:
``a_k = sqrt(2 * integral_cell S dOmega)`` (~ sqrt(2 S(Omega_k) dOmega) inside the band), so the
variance over one full period equals the band integral of S exactly, not to a midpoint-rule
error. Phases are uniform in [0, 2 pi) from ``numpy.random.default_rng`` seeded per channel from
``SeedSequence(seed).spawn(4)``. The signal is a function of s alone: the same seed gives the
same values at the same s whatever ds (an inverse real FFT when P/ds is an integer, direct
summation otherwise; the two agree to round-off). Amplitudes are deterministic, phases random:
each sample is asymptotically Gaussian (many harmonics), and a spectral estimate from the
signal scatters less than for a Gaussian process.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple, Sequence, Union

import numpy as np
from scipy.interpolate import PchipInterpolator

from pneumorail.files import TABLE_MAX_BYTES, read_text

from .wheelrail.compiled import kernel

__all__ = [
    "CHANNELS",
    "COLUMNS",
    "MAX_ABS_IRREGULARITY_M",
    "PSD_KINDS",
    "DEFAULT_WAVELENGTH_RANGE_M",
    "RailOffsets",
    "IrregularityValues",
    "TrackIrregularity",
    "psd",
    "psd_per_cycle",
    "band_variance",
    "canonical_kind",
]

CHANNELS = ("lateral", "vertical", "cross_level", "gauge")
COLUMNS = ("s_m", "lateral_m", "vertical_m", "cross_level_m", "gauge_m")
MAX_ABS_IRREGULARITY_M = 0.1  # a larger value is taken for a unit mistake (mm written as m)
DEFAULT_WAVELENGTH_RANGE_M = (3.0, 150.0)  # EN 14363 / EN 13848 bands D1 (3-25), D2 (25-70), D3 (70-150)
PERIOD_FACTOR = 8.0  # period of the generated signal >= this many longest wavelengths
#: the most samples a generated irregularity (or its period) may take: 1e7 x 8 bytes per channel,
#: under half a gigabyte for all of them together
MAX_SAMPLES = 10_000_000

# --- PSD coefficients (see the module docstring for sources and how sure they are) ---------------
_ERRI_OMEGA_C = 0.8246  # rad/m
_ERRI_OMEGA_R = 0.0206  # rad/m
_ERRI_OMEGA_S = 0.4380  # rad/m
# level: (A_v, A_a, A_g) in m^2 rad/m
_ERRI_LEVELS = {"low": (4.032e-7, 2.119e-7, 5.32e-8), "high": (1.080e-6, 6.125e-7, 1.032e-7)}

_FRA_K = 0.25
_FRA_OMEGA_C = 0.8245  # rad/m
_CM2 = 1e-4  # cm^2 -> m^2
# class: (A_v [cm^2 rad/m], A_a [cm^2 rad/m], Omega_s [rad/m])
_FRA_CLASSES = {
    1: (1.2107, 3.3634, 0.6046),
    2: (1.0181, 1.2107, 0.9308),
    3: (0.6816, 0.4128, 0.8520),
    4: (0.5376, 0.3027, 1.1312),
    5: (0.2095, 0.0762, 0.8209),
    6: (0.0339, 0.0339, 0.4380),
}

PSD_KINDS = ("erri_b176_low", "erri_b176_high") + tuple(f"fra_{c}" for c in _FRA_CLASSES)

Number = Union[float, int]


def canonical_kind(kind: str) -> str:
    """Normalize a PSD name: case, '-', ' ' and a few spellings ("ERRI-B176-low", "ORE B176 high",
    "FRA class 4", "fra4") map to one of :data:`PSD_KINDS`; anything else is a ValueError."""
    if not isinstance(kind, str):
        raise ValueError(f"PSD kind must be a string, one of {', '.join(PSD_KINDS)}; got {kind!r}")
    k = kind.strip().lower().replace("-", "_").replace(" ", "_")
    k = k.replace("ore_b176", "erri_b176").replace("class_", "").replace("class", "")
    while "__" in k:
        k = k.replace("__", "_")
    if k.startswith("fra") and not k.startswith("fra_"):
        k = "fra_" + k[3:]
    if k.startswith("b176"):
        k = "erri_" + k
    if k not in PSD_KINDS:
        raise ValueError(f"unknown PSD kind {kind!r}; expected one of {', '.join(PSD_KINDS)}")
    return k


def _check_channel(channel: str) -> str:
    if channel not in CHANNELS:
        raise ValueError(f"unknown channel {channel!r}; expected one of {', '.join(CHANNELS)}")
    return channel


def psd(kind: str, channel: str, omega_rad_per_m) -> np.ndarray:
    """One-sided PSD S(Omega) [m^2/(rad/m)] of ``channel`` (lateral, vertical, cross_level --
    height difference z_R - z_L --, gauge) for ``kind`` (see :data:`PSD_KINDS`) at angular
    wavenumber(s) Omega [rad/m] > 0. sigma^2 = integral_0^inf S dOmega."""
    kind = canonical_kind(kind)
    _check_channel(channel)
    w = np.asarray(omega_rad_per_m, dtype=float)
    if np.any(~np.isfinite(w)) or np.any(w <= 0.0):
        raise ValueError("psd: omega_rad_per_m must be finite and > 0 (rad/m)")
    w2 = w * w
    if kind.startswith("erri_b176_"):
        a_v, a_a, a_g = _ERRI_LEVELS[kind.rsplit("_", 1)[1]]
        oc2, or2, os2 = _ERRI_OMEGA_C**2, _ERRI_OMEGA_R**2, _ERRI_OMEGA_S**2
        base = oc2 / ((w2 + or2) * (w2 + oc2))
        if channel == "vertical":
            return a_v * base
        if channel == "lateral":
            return a_a * base
        shaped = base * w2 / (w2 + os2)
        if channel == "cross_level":
            # (A_v / b^2) * shaped is the angle PSD; times (2b)^2 for the height difference over 2b
            return 4.0 * a_v * shaped
        return a_g * shaped
    a_v, a_a, o_s = _FRA_CLASSES[int(kind.split("_")[1])]
    a_v, a_a = a_v * _CM2, a_a * _CM2
    oc2 = _FRA_OMEGA_C**2
    if channel == "vertical":
        return _FRA_K * a_v * oc2 / (w2 * (w2 + oc2))
    if channel == "lateral":
        return _FRA_K * a_a * oc2 / (w2 * (w2 + oc2))
    return 4.0 * _FRA_K * a_v * oc2 / ((w2 + oc2) * (w2 + o_s * o_s))  # cross-level and gauge


def psd_per_cycle(kind: str, channel: str, f_cycles_per_m) -> np.ndarray:
    """The same spectrum per cycle: S_f(f) = 2 pi S(2 pi f) [m^2/(cycle/m)], f = 1/wavelength."""
    f = np.asarray(f_cycles_per_m, dtype=float)
    return 2.0 * math.pi * psd(kind, channel, 2.0 * math.pi * f)


def _checked_band(wavelength_range_m) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in wavelength_range_m)
    except (TypeError, ValueError):
        raise ValueError("wavelength_range_m must be two numbers (shortest, longest) in m, got "
                         f"{wavelength_range_m!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi):
        raise ValueError(f"wavelength_range_m must satisfy 0 < shortest < longest (m), got {(lo, hi)!r}")
    return lo, hi


def band_variance(kind: str, channel: str, wavelength_range_m=DEFAULT_WAVELENGTH_RANGE_M) -> float:
    """sigma^2 [m^2] of ``channel`` between the two wavelengths: integral of S over the band."""
    from scipy.integrate import quad

    lo, hi = _checked_band(wavelength_range_m)
    a, b = 2.0 * math.pi / hi, 2.0 * math.pi / lo
    val, _ = quad(lambda w: float(psd(kind, channel, w)), a, b, epsabs=0.0, epsrel=1e-10, limit=200)
    return val


class RailOffsets(NamedTuple):
    """Offsets of each rail from its nominal position, track frame (y left, z up), metres."""

    y_left_m: np.ndarray
    z_left_m: np.ndarray
    y_right_m: np.ndarray
    z_right_m: np.ndarray


class IrregularityValues(NamedTuple):
    """The four quantities at s, metres (signs: module docstring)."""

    lateral_m: np.ndarray
    vertical_m: np.ndarray
    cross_level_m: np.ndarray
    gauge_m: np.ndarray


def _as_array(name: str, values, n: int | None) -> np.ndarray:
    a = np.array(values, dtype=float)  # a copy: the caller's array stays writable and unshared
    if a.ndim != 1:
        raise ValueError(f"TrackIrregularity: {name} must be a 1-D sequence, got shape {a.shape}")
    if n is not None and a.size != n:
        raise ValueError(f"TrackIrregularity: {name} has {a.size} values, s_m has {n}")
    if not np.all(np.isfinite(a)):
        i = int(np.flatnonzero(~np.isfinite(a))[0])
        raise ValueError(f"TrackIrregularity: {name}[{i}] = {a[i]!r} is not finite")
    a.setflags(write=False)
    return a


@kernel(__file__)
def _piecewise_cubic_at(x, c, s):
    """A piecewise cubic (scipy's ``PPoly``: breakpoints ``x``, coefficients ``c`` (4, intervals,
    columns), highest power first) at the points ``s`` (1-D), zero outside [x[0], x[-1]] and at
    NaN: (points, columns). The same arithmetic as ``PPoly.__call__`` (interval x[i] <= s <
    x[i+1], the last one closed; sum of c[3 - k] d^k with d = s - x[i] and d^k accumulated), so
    the same numbers, bit for bit, without its per-call cost (the car evaluates the track's
    irregularities at every internal step)."""
    n_cols = c.shape[2]
    out = np.zeros((s.size, n_cols))
    lo, hi = x[0], x[-1]
    for n in range(s.size):
        sv = s[n]
        if not (lo <= sv <= hi):
            continue
        i = min(np.searchsorted(x, sv, side="right") - 1, x.size - 2)
        d = sv - x[i]
        for j in range(n_cols):
            res, z = 0.0, 1.0
            for k in range(c.shape[0]):
                res = res + c[c.shape[0] - 1 - k, i, j] * z
                z = z * d
            out[n, j] = res
    return out


@dataclass(frozen=True, eq=False)
class TrackIrregularity:
    """Sampled irregularities over s [m]; all values in metres (signs: module docstring).

    ``t(s)`` returns ``(lateral_m, vertical_m, cross_level_m, gauge_m)`` by shape-preserving
    piecewise cubic interpolation (PCHIP) through the samples, zero outside
    ``[s_m[0], s_m[-1]]``; scalars in give floats out, arrays give arrays.
    """

    s_m: np.ndarray
    lateral_m: np.ndarray
    vertical_m: np.ndarray
    cross_level_m: np.ndarray
    gauge_m: np.ndarray
    source: str = ""

    def __post_init__(self):
        s = _as_array("s_m", self.s_m, None)
        if s.size < 2:
            raise ValueError("TrackIrregularity: need at least two samples in s_m")
        d = np.diff(s)
        if np.any(d <= 0.0):
            i = int(np.flatnonzero(d <= 0.0)[0])
            raise ValueError(f"TrackIrregularity: s_m must be strictly increasing; "
                             f"s_m[{i}] = {s[i]!r}, s_m[{i + 1}] = {s[i + 1]!r}")
        object.__setattr__(self, "s_m", s)
        for name in COLUMNS[1:]:
            object.__setattr__(self, name, _as_array(name, getattr(self, name), s.size))
        # one interpolant for the four columns: one evaluation per call (the car calls it every
        # internal step)
        values = np.stack([getattr(self, n) for n in COLUMNS[1:]], axis=-1)
        spline = PchipInterpolator(s, values, axis=0)
        # its breakpoints and coefficients, as the kernel takes them (scipy's properties convert
        # on every access)
        object.__setattr__(self, "_pieces", (np.ascontiguousarray(spline.x),
                                             np.ascontiguousarray(spline.c)))

    # --- evaluation --------------------------------------------------------------------------
    def __call__(self, s_m) -> IrregularityValues:
        """(lateral_m, vertical_m, cross_level_m, gauge_m) at s [m]; zero outside the range."""
        v = self.stacked(s_m)
        if v.ndim == 1:
            return IrregularityValues(*(float(x) for x in v))
        return IrregularityValues(*(v[..., j] for j in range(4)))

    def stacked(self, s_m) -> np.ndarray:
        """The four channels at s [m] as one array, shaped like s with a last axis of 4 (the
        columns in :meth:`__call__`'s order); finite everywhere (zero outside the range and at
        NaN)."""
        s = np.asarray(s_m, dtype=float)
        return _piecewise_cubic_at(*self._pieces, s.ravel()).reshape(s.shape + (4,))

    def rail_offsets(self, s_m) -> RailOffsets:
        """Each rail's lateral (y, + left) and vertical (z, + up) offset [m] at s::

            y_L = lateral + gauge/2,  y_R = lateral - gauge/2,
            z_L = vertical - cross_level/2,  z_R = vertical + cross_level/2.
        """
        lat, ver, cross, gauge = self(s_m)
        return RailOffsets(lat + 0.5 * gauge, ver - 0.5 * cross, lat - 0.5 * gauge, ver + 0.5 * cross)

    @classmethod
    def from_rail_offsets(cls, s_m, y_left_m, z_left_m, y_right_m, z_right_m, source: str = ""):
        """Inverse of :meth:`rail_offsets`: the four quantities from per-rail offsets [m]."""
        yl, zl, yr, zr = (np.asarray(v, dtype=float) for v in (y_left_m, z_left_m, y_right_m, z_right_m))
        return cls(s_m, 0.5 * (yl + yr), 0.5 * (zl + zr), zr - zl, yl - yr, source=source)

    @property
    def length_m(self) -> float:
        return float(self.s_m[-1] - self.s_m[0])

    def tapered(self, taper_m: float) -> "TrackIrregularity":
        """A copy faded in over the first and out over the last ``taper_m`` metres with a raised
        cosine (weight 0 at the ends, 1 beyond taper_m), so that zero-outside does not step."""
        taper_m = float(taper_m)
        if not (math.isfinite(taper_m) and 0.0 <= taper_m <= 0.5 * self.length_m):
            raise ValueError(f"taper_m must lie in [0, half the length = {0.5 * self.length_m!r}] m, "
                             f"got {taper_m!r}")
        if taper_m == 0.0:
            return self
        u = np.minimum(self.s_m - self.s_m[0], self.s_m[-1] - self.s_m) / taper_m
        w = np.where(u >= 1.0, 1.0, 0.5 - 0.5 * np.cos(math.pi * np.clip(u, 0.0, 1.0)))
        return TrackIrregularity(self.s_m, *(w * getattr(self, n) for n in COLUMNS[1:]),
                                 source=f"{self.source} (tapered {taper_m:g} m)".strip())

    # --- files -------------------------------------------------------------------------------
    def to_csv(self, path) -> None:
        """Write the five columns (header :data:`COLUMNS`); floats round-trip exactly."""
        path = Path(path)
        with path.open("w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(COLUMNS)
            for row in zip(*(getattr(self, n) for n in COLUMNS)):
                w.writerow([repr(float(v)) for v in row])

    @classmethod
    def from_file(cls, path, max_abs_m: float = MAX_ABS_IRREGULARITY_M) -> "TrackIrregularity":
        """Read a CSV file (format: module docstring). Errors are ValueErrors naming the file,
        the line and what was expected. A value above ``max_abs_m`` (default 0.1 m) in magnitude
        is refused as a probable unit mistake; raise it for very poor track (FRA classes 1-2 over
        wavelengths up to 150 m reach about 0.15 m)."""
        path = Path(path)
        max_abs_m = float(max_abs_m)
        if not (math.isfinite(max_abs_m) and max_abs_m > 0.0):
            raise ValueError(f"max_abs_m must be a finite number > 0 (m), got {max_abs_m!r}")
        where = str(path)
        # the one reader: a regular file of bounded size, UTF-8 (a binary file or UTF-16 from a
        # spreadsheet is refused naming the file), line numbers as the editor shows them
        rows = read_text(path, "track irregularity (CSV)", TABLE_MAX_BYTES).data_lines()
        if not rows:
            raise ValueError(f"{where}: empty file; expected a header line "
                             f"'{','.join(COLUMNS)}' (s_m required) and data lines")
        head_line, head = rows[0]
        names = [c.strip() for c in next(csv.reader([head]))]
        for name in names:
            if name in COLUMNS:
                continue
            hint = ""
            stem = name.rsplit("_", 1)[0] if "_" in name else name
            if f"{stem}_m" in COLUMNS and name != f"{stem}_m":
                hint = f" (values must be in metres, as column '{stem}_m')"
            raise ValueError(f"{where}, line {head_line}: unknown column {name!r}{hint}; expected "
                             f"columns among {','.join(COLUMNS)} with s_m required")
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"{where}, line {head_line}: column(s) {', '.join(dup)} appear more than once")
        if "s_m" not in names:
            raise ValueError(f"{where}, line {head_line}: header has no 's_m' column; expected a "
                             f"header like '{','.join(COLUMNS)}'")
        data = {n: [] for n in names}
        prev_s = None
        for lineno, line in rows[1:]:
            fields = [f.strip() for f in next(csv.reader([line]))]
            if len(fields) != len(names):
                raise ValueError(f"{where}, line {lineno}: {len(fields)} fields, expected "
                                 f"{len(names)} ({','.join(names)})")
            for name, text in zip(names, fields):
                try:
                    v = float(text)
                except ValueError:
                    raise ValueError(f"{where}, line {lineno}: {name} = {text!r} is not a number") from None
                if not math.isfinite(v):
                    raise ValueError(f"{where}, line {lineno}: {name} = {text!r} is not finite")
                if name != "s_m" and abs(v) > max_abs_m:
                    raise ValueError(f"{where}, line {lineno}: {name} = {v!r} m exceeds "
                                     f"{max_abs_m:g} m in magnitude; irregularities are in "
                                     "metres -- was the file written in millimetres?")
                data[name].append(v)
            s = data["s_m"][-1]
            if prev_s is not None and not s > prev_s:
                raise ValueError(f"{where}, line {lineno}: s_m = {s!r} does not increase (previous "
                                 f"s_m = {prev_s!r}); s must be strictly increasing")
            prev_s = s
        n = len(data["s_m"])
        if n < 2:
            raise ValueError(f"{where}: {n} data line(s); expected at least 2")
        zeros = [0.0] * n
        return cls(*(data.get(c, zeros) for c in COLUMNS), source=where)

    # --- PSD generation ----------------------------------------------------------------------

    @classmethod
    def from_psd(cls, kind: str, length_m: Number, ds_m: Number, seed: int,
                 wavelength_range_m: Sequence[Number] = DEFAULT_WAVELENGTH_RANGE_M,
                 channels: Sequence[str] = CHANNELS, taper_m: Number = 0.0) -> "TrackIrregularity":
        """Generate the irregularities of ``kind`` (:data:`PSD_KINDS`) on s = 0, ds, ... up to
        the first multiple of ds >= length_m, from the wavelengths in ``wavelength_range_m``
        (shortest, longest) [m], reproducibly from the integer ``seed``.

        Channels not in ``channels`` are zero (each listed channel keeps its own random stream,
        so leaving one out does not change the others). ``ds_m`` must be at most half the
        shortest wavelength (no aliasing); the shape-preserving cubic between samples is within
        ~1 % of a harmonic's amplitude at 12 samples per wavelength. ``taper_m`` > 0 applies
        :meth:`tapered`. Method and conventions: module docstring.
        """
        kind = canonical_kind(kind)
        lo, hi = _checked_band(wavelength_range_m)
        length_m, ds_m = float(length_m), float(ds_m)
        if not (math.isfinite(length_m) and length_m > 0.0):
            raise ValueError(f"length_m must be a finite number > 0 (m), got {length_m!r}")
        if not (math.isfinite(ds_m) and 0.0 < ds_m <= 0.5 * lo):
            raise ValueError(f"ds_m must lie in (0, shortest wavelength / 2 = {0.5 * lo!r}] m, got {ds_m!r}")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
        chosen = [_check_channel(c) for c in channels]

        period = max(length_m, PERIOD_FACTOR * hi)
        n_samples = math.ceil(length_m / ds_m - 1e-9) + 1
        n_largest = max(n_samples, period / ds_m)
        if n_largest > MAX_SAMPLES:
            # refused before anything is allocated: a slip of ds_m, the track or the band would
            # otherwise end in an out-of-memory kill
            raise ValueError(f"{n_largest:.3g} samples (the track's {length_m:g} m, or {PERIOD_FACTOR:g} x the longest "
                             f"wavelength {hi:g} m, at ds_m = {ds_m:g} m; about {n_largest * 8 * (2 + len(chosen)) / 1e9:.3g} "
                             f"GB), more than {MAX_SAMPLES:.0e}: make ds_m larger, or the track or the longest wavelength "
                             f"shorter")
        d_omega = 2.0 * math.pi / period
        w_min, w_max = 2.0 * math.pi / hi, 2.0 * math.pi / lo
        # every harmonic whose cell [Omega_k - dOmega/2, Omega_k + dOmega/2] overlaps the band
        k_lo = max(1, math.floor(w_min / d_omega + 0.5 + 1e-9))
        k_hi = math.ceil(w_max / d_omega - 0.5 - 1e-9)
        k = np.arange(k_lo, k_hi + 1)
        omega = k * d_omega
        cell_lo = np.maximum(omega - 0.5 * d_omega, w_min)
        cell_hi = np.minimum(omega + 0.5 * d_omega, w_max)
        s = np.arange(n_samples) * ds_m
        n_period = period / ds_m
        use_fft = abs(n_period - round(n_period)) < 1e-9 * n_period and k_hi < round(n_period) / 2

        streams = np.random.SeedSequence(int(seed)).spawn(len(CHANNELS))
        out = {}
        for ch, ss in zip(CHANNELS, streams):
            if ch not in chosen:
                out[ch] = np.zeros(n_samples)
                continue
            # phases for harmonics 0..k_hi, so narrowing the band keeps the common ones
            phase = np.random.default_rng(ss).uniform(0.0, 2.0 * math.pi, size=k_hi + 1)[k_lo:]
            amp = np.sqrt(2.0 * _cell_integrals(kind, ch, cell_lo, cell_hi))
            out[ch] = (_sum_cosines_fft(amp, phase, k, int(round(n_period)), n_samples) if use_fft
                       else _sum_cosines_direct(amp, phase, omega, s))
        src = (f"{kind}, seed {seed}, wavelengths {lo:g}-{hi:g} m, ds {ds_m:g} m, "
               f"channels {'+'.join(chosen) or 'none'}")
        t = cls(s, out["lateral"], out["vertical"], out["cross_level"], out["gauge"], source=src)
        return t.tapered(float(taper_m)) if taper_m else t


_GL_X, _GL_W = np.polynomial.legendre.leggauss(6)


def _cell_integrals(kind: str, channel: str, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """integral of S over each [a_i, b_i] by 6-point Gauss-Legendre. The cells are narrow next
    to the scale on which S varies (b - a <= Omega / 7.5 at the band's long-wavelength end, where
    S varies fastest), so the rule is exact to ~1e-12 relative."""
    half, mid = 0.5 * (b - a), 0.5 * (b + a)
    nodes = mid[:, None] + half[:, None] * _GL_X[None, :]
    return half * (psd(kind, channel, nodes) @ _GL_W)


def _sum_cosines_fft(amp, phase, k, n_period: int, n_samples: int) -> np.ndarray:
    """sum_k amp_k cos(2 pi k n / N + phase_k) for n = 0..n_samples-1 (periodic in N) by irfft."""
    spec = np.zeros(n_period // 2 + 1, dtype=complex)
    spec[k] = 0.5 * n_period * amp * np.exp(1j * phase)
    x = np.fft.irfft(spec, n=n_period)
    return np.take(x, np.arange(n_samples), mode="wrap")


def _sum_cosines_direct(amp, phase, omega, s, chunk_elems: int = 4_000_000) -> np.ndarray:
    """sum_k amp_k cos(omega_k s + phase_k), in chunks of s to bound memory."""
    out = np.empty(s.size)
    step = max(1, chunk_elems // max(1, omega.size))
    for i in range(0, s.size, step):
        out[i:i + step] = np.cos(np.outer(s[i:i + step], omega) + phase) @ amp
    return out
