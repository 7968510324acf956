"""Ride comfort from floor accelerations, simulated or measured: EN 12299's mean comfort index
N_MV and continuous comfort Cc, ISO 2631-1's overall weighted rms, Sperling's ride index Wz.

Sources (the standards' texts were not available here; the values are those the standards are
quoted with in the literature and in comfpy, and each is marked where it is used):

* **Frequency weightings** (EN 12299:2009 Annex A, ISO 2631-1:1997 Annex A, ISO 2631-4): products
  of a band limit, an acceleration-velocity transition and an upward step,

      H(s) = Hh(s) Hl(s) Ht(s) Hs(s),
      Hh = s² / (s² + ω1 s / Q1 + ω1²),        Hl = ω2² / (s² + ω2 s / Q1 + ω2²),  Q1 = 1/√2,
      Ht = (1 + s/ω3) / (1 + s/(Q4 ω4) + s²/ω4²),
      Hs = K (1 + s/(Q5 ω5) + s²/ω5²) / (1 + s/(Q6 ω6) + s²/ω6²),

  ω = 2π f, with (:data:`WEIGHTINGS`) Wb (EN 12299 vertical: f1 0.4, f2 100, f3 = f4 16 Hz, Q4 0.63,
  f5 2.5, Q5 0.8, f6 4, Q6 0.8, K 0.4, so 0.4 below 2.5 Hz and 1.024 above 4 Hz), Wd (horizontal:
  f3 = f4 2 Hz, Q4 0.63, no step), Wc (f3 = f4 8 Hz) and Wk (ISO 2631-1 vertical: f3 = f4 12.5 Hz,
  Q4 0.63, f5 2.37, Q5 0.91, f6 3.35, Q6 0.91, K 1). They are applied in the frequency domain
  (the record's FFT times H(j2πf)): the exact analytic response at every frequency, no bilinear
  warping near the Nyquist frequency.
* **N_MV** (EN 12299, the standard (simplified) method): the weighted accelerations' rms over
  consecutive 5 s blocks, their 95th percentiles over the record (5 minutes in the standard),
  N_MV = 6 √(a_XP95^Wd² + a_YP95^Wd² + a_ZP95^Wb²). Scale: < 1 very comfortable, 1-2 comfortable,
  2-4 medium, 4-5 uncomfortable, > 5 very uncomfortable.
* **Continuous comfort** Cc_x,y,z(t): the 5 s sliding rms of the weighted acceleration, every
  second (EN 12299 Cc), in m/s².
* **Sperling's ride index** in its spectral form (Wz = (∫ B(f)² G(f) df)^(1/6.67), G the one-sided
  PSD of the acceleration in (cm/s²)²/Hz over 0.5-30 Hz; B the vertical weighting 0.588 √((1.911 f² +
  (0.25 f²)²) / ((1 - 0.277 f²)² + (1.563 f - 0.0368 f³)²)), lateral 1.25 times it; as in Forstberg
  2000 and comfpy). Classical scale: 1 very good ... 4.5 not running-safe.
* **ISO 2631-1 overall weighted rms** (comfort, seated): a_v = √(a_wx² + a_wy² + a_wz²), Wd on x and
  y, Wk on z, multiplying factors 1.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np

#: name -> (f1, f2, f3, f4, Q4, f5, Q5, f6, Q6, K) [Hz, -]; f5 None: no upward step
WEIGHTINGS = {
    "Wb": (0.4, 100.0, 16.0, 16.0, 0.63, 2.5, 0.8, 4.0, 0.8, 0.4),
    "Wd": (0.4, 100.0, 2.0, 2.0, 0.63, None, None, None, None, 1.0),
    "Wc": (0.4, 100.0, 8.0, 8.0, 0.63, None, None, None, None, 1.0),
    "Wk": (0.4, 100.0, 12.5, 12.5, 0.63, 2.37, 0.91, 3.35, 0.91, 1.0),
}
#: EN 12299 block and evaluation lengths [s]
BLOCK_S = 5.0
STANDARD_RECORD_S = 300.0
#: N_MV comfort scale (upper bounds) and names
N_MV_SCALE = ((1.0, "very comfortable"), (2.0, "comfortable"), (4.0, "medium"), (5.0, "uncomfortable"),
              (math.inf, "very uncomfortable"))
#: Sperling's band [Hz]
WZ_BAND_HZ = (0.5, 30.0)
AXES = ("x", "y", "z")


def response(name: str, f_Hz) -> np.ndarray:
    """The complex frequency response H(j 2π f) of weighting ``name`` (:data:`WEIGHTINGS`)."""
    f1, f2, f3, f4, q4, f5, q5, f6, q6, k = WEIGHTINGS[name]
    s = 2j * math.pi * np.asarray(f_Hz, dtype=float)
    w1, w2, w3, w4 = (2 * math.pi * f for f in (f1, f2, f3, f4))
    q1 = 1.0 / math.sqrt(2.0)
    h = s * s / (s * s + w1 * s / q1 + w1 * w1)
    h = h * w2 * w2 / (s * s + w2 * s / q1 + w2 * w2)
    h = h * (1.0 + s / w3) / (1.0 + s / (q4 * w4) + s * s / (w4 * w4))
    if f5 is not None:
        w5, w6 = 2 * math.pi * f5, 2 * math.pi * f6
        h = h * (1.0 + s / (q5 * w5) + s * s / (w5 * w5)) / (1.0 + s / (q6 * w6) + s * s / (w6 * w6))
    return k * h


def sperling_weighting(f_Hz, axis: str) -> np.ndarray:
    """Sperling's B(f): vertical, and 1.25 times it laterally (and longitudinally)."""
    f = np.asarray(f_Hz, dtype=float)
    b = 0.588 * np.sqrt((1.911 * f ** 2 + (0.25 * f ** 2) ** 2)
                        / ((1.0 - 0.277 * f ** 2) ** 2 + (1.563 * f - 0.0368 * f ** 3) ** 2))
    return b if axis == "z" else 1.25 * b


def uniform(t_s: np.ndarray, values: np.ndarray) -> tuple:
    """(t, values) on a uniform grid at the record's median step, linearly interpolated where the
    samples are not uniform already (within 1e-6 of the step)."""
    t = np.asarray(t_s, dtype=float)
    v = np.asarray(values, dtype=float)
    dt = float(np.median(np.diff(t)))
    if np.all(np.abs(np.diff(t) - dt) <= 1e-6 * dt):
        return t, v
    grid = t[0] + dt * np.arange(int(math.floor((t[-1] - t[0]) / dt + 1e-9)) + 1)
    return grid, np.interp(grid, t, v)


def weighted(t_s: np.ndarray, a: np.ndarray, name: str) -> np.ndarray:
    """The acceleration ``a`` (uniform samples) through weighting ``name``, its mean (gravity, an
    offset) removed first; in the frequency domain, the record taken as one period."""
    a = np.asarray(a, dtype=float) - np.mean(a)
    dt = float(t_s[1] - t_s[0])
    spectrum = np.fft.rfft(a)
    f = np.fft.rfftfreq(a.size, dt)
    return np.fft.irfft(spectrum * response(name, f), a.size)


def block_rms(t_s: np.ndarray, a: np.ndarray, block_s: float = BLOCK_S) -> np.ndarray:
    """rms over consecutive whole blocks of ``block_s`` (a last partial block is left out)."""
    dt = float(t_s[1] - t_s[0])
    n = int(round(block_s / dt))
    blocks = a.size // n
    return np.sqrt((a[:blocks * n].reshape(blocks, n) ** 2).mean(axis=1))


def continuous_comfort(t_s: np.ndarray, a: np.ndarray, block_s: float = BLOCK_S) -> tuple:
    """(times, Cc): the sliding rms over the last ``block_s``, every second from the first whole
    block on."""
    dt = float(t_s[1] - t_s[0])
    n = int(round(block_s / dt))
    cum = np.concatenate([[0.0], np.cumsum(a * a)])
    ends = np.arange(n, a.size + 1, max(1, int(round(1.0 / dt))))
    return t_s[0] + ends * dt, np.sqrt((cum[ends] - cum[ends - n]) / n)


def sperling(t_s: np.ndarray, a: np.ndarray, axis: str) -> float:
    """Sperling's Wz of the acceleration ``a`` [m/s^2] (spectral form, see the module docstring)."""
    a_cm = (np.asarray(a, dtype=float) - np.mean(a)) * 100.0
    dt = float(t_s[1] - t_s[0])
    spectrum = np.fft.rfft(a_cm)
    f = np.fft.rfftfreq(a_cm.size, dt)
    # one-sided PSD of the record, so that its integral is the mean square
    psd = 2.0 * np.abs(spectrum) ** 2 * dt / a_cm.size
    psd[0] /= 2.0
    band = (f >= WZ_BAND_HZ[0]) & (f <= WZ_BAND_HZ[1])
    df = f[1] - f[0]
    return float((np.sum(sperling_weighting(f[band], axis) ** 2 * psd[band]) * df) ** 0.15)


@dataclass
class ComfortResult:
    """Comfort of one record.

    Attributes
    ----------
    duration_s : float
        Length of the record [s].
    N_MV : float or None
        EN 12299 mean comfort index (None without all three axes).
    aP95_m_per_s2 : dict
        Per axis the 95th percentile of the weighted 5 s rms [m/s^2] (x, y: Wd; z: Wb).
    Cc_max_m_per_s2 : dict
        Per axis the largest continuous comfort value [m/s^2].
    Wz : dict
        Per axis Sperling's ride index [-].
    a_v_m_per_s2 : float or None
        ISO 2631-1 overall weighted rms (comfort, seated) over the record [m/s^2].
    blocks : dict
        Per axis the weighted rms of each 5 s block [m/s^2]; ``block_start_s`` their starts.
    cc_t_s, cc : numpy arrays, dict
        The continuous comfort's times and values per axis.
    weighted : dict
        The weighted accelerations per axis (uniform samples at ``t_s``).
    warnings : list of str
        What limits the result (a record shorter than the standard's 5 minutes, missing axes).
    """

    duration_s: float
    N_MV: Optional[float]
    aP95_m_per_s2: Dict[str, float]
    Cc_max_m_per_s2: Dict[str, float]
    Wz: Dict[str, float]
    a_v_m_per_s2: Optional[float]
    block_start_s: np.ndarray
    blocks: Dict[str, np.ndarray]
    t_s: np.ndarray
    weighted: Dict[str, np.ndarray]
    cc_t_s: np.ndarray
    cc: Dict[str, np.ndarray]
    warnings: List[str] = field(default_factory=list)

    @property
    def scale(self) -> Optional[str]:
        """N_MV on EN 12299's comfort scale."""
        if self.N_MV is None:
            return None
        return next(name for bound, name in N_MV_SCALE if self.N_MV < bound)


def comfort(t_s: np.ndarray, accelerations: Dict[str, np.ndarray]) -> ComfortResult:
    """The comfort indices of a record: ``t_s`` [s] and per axis (``x`` along the car, ``y``
    lateral, ``z`` vertical; any of them) the acceleration [m/s^2], gravity and offsets included
    or not (the mean is removed). Raises ValueError for a record shorter than one 5 s block."""
    t = np.asarray(t_s, dtype=float)
    if t.size < 2 or not np.all(np.diff(t) > 0):
        raise ValueError("t_s must increase")
    # each sample stands for one step: N samples at dt last N dt (what the blocks count)
    duration = float(t[-1] - t[0] + np.median(np.diff(t)))
    if duration < BLOCK_S - 1e-9:
        raise ValueError(f"the record lasts {duration:g} s, shorter than one {BLOCK_S:g} s block")
    axes = [a for a in AXES if a in accelerations]
    if not axes:
        raise ValueError("no acceleration axis (x, y or z)")
    warnings = []
    if duration < STANDARD_RECORD_S - 1e-9:
        warnings.append(f"the record lasts {duration:g} s, shorter than the {STANDARD_RECORD_S:g} s EN 12299 "
                        f"evaluates N_MV over: its 95th percentiles rest on {int(duration // BLOCK_S + 1e-9)} blocks")
    out = {"weighted": {}, "blocks": {}, "cc": {}, "P95": {}, "Cc_max": {}, "Wz": {}}
    resampled = {axis: uniform(t, accelerations[axis]) for axis in axes}
    grid = resampled[axes[0]][0]
    for axis in axes:
        a = resampled[axis][1]
        aw = weighted(grid, a, "Wb" if axis == "z" else "Wd")
        out["weighted"][axis] = aw
        out["blocks"][axis] = block_rms(grid, aw)
        out["P95"][axis] = float(np.percentile(out["blocks"][axis], 95))
        cc_t, out["cc"][axis] = continuous_comfort(grid, aw)
        out["Cc_max"][axis] = float(out["cc"][axis].max())
        out["Wz"][axis] = sperling(grid, a, axis)
    missing = [a for a in AXES if a not in axes]
    n_mv = None
    if missing:
        warnings.append(f"N_MV needs all three axes; missing: {', '.join(missing)}")
    else:
        n_mv = 6.0 * math.sqrt(sum(out["P95"][a] ** 2 for a in AXES))
    a_v = None
    if not missing:
        iso = [weighted(grid, resampled[a][1], "Wk" if a == "z" else "Wd") for a in AXES]
        a_v = float(math.sqrt(sum(np.mean(w * w) for w in iso)))
    n_blocks = len(next(iter(out["blocks"].values())))
    return ComfortResult(duration, n_mv, out["P95"], out["Cc_max"], out["Wz"], a_v,
                         grid[0] + BLOCK_S * np.arange(n_blocks), out["blocks"], grid, out["weighted"], cc_t,
                         out["cc"], warnings)
