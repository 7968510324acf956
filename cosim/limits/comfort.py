"""Ride comfort from floor accelerations, simulated or measured: EN 12299's mean comfort index
N_MV and continuous comfort Cc, ISO 2631-1's overall weighted rms, Sperling's ride index Wz.

Sources. None of the standards' own texts could be read here (EN 12299:2009, ISO 2631-1:1997,
ISO 2631-4:2001, ISO 8041); every value below names the secondary source it was read in.

* **Frequency weightings**: the cascade of ISO 8041 Table 3,

      H(s) = K Hh(s) Hl(s) Ht(s) Hs(s),
      Hh = s² / (s² + ω1 s / Q1 + ω1²),   Hl = ω2² / (s² + ω2 s / Q2 + ω2²),   Q1 = Q2 = 1/√2,
      Ht = (1 + s/ω3) / (1 + s/(Q4 ω4) + s²/ω4²),
      Hs = (s² + ω5 s/Q5 + ω5²) / (s² + ω6 s/Q6 + ω6²),

  ω = 2π f, s = j ω. The upward step Hs tends to (f5/f6)² at low frequency and to 1 at high
  frequency, so K is the high-frequency gain. The form is the one the Larson Davis HVM200
  reference manual implements from ISO 8041 Table 3 (pp. 3-14 to 3-16: its Table 3.1, "source:
  ISO 8041", and its filter code, upward step numerator [1/ω5², 1/(Q5 ω5), 1]·ω5²/ω6²,
  denominator [1/ω6², 1/(Q6 ω6), 1]), and the one the printed tables agree with (both typed into
  tests/cosim/limits/test_comfort.py with their transcriptions named): ISO 8041-1:2017 Annex B gives Wk
  0.4825 at 1 Hz and ISO 2631-1:1997 Table 3 0.482, where the step written
  (1 + s/(Q5 ω5) + s²/ω5²)/(1 + s/(Q6 ω6) + s²/ω6²) (this module before, equal to the form above
  times (f6/f5)²) gives twice that. Parameters (:data:`WEIGHTINGS`), all from ISO 8041 Table 3 as
  quoted in that manual's Table 3.1 (ISO 8041 NOTE 1 there: its Wb is ISO 2631-4:2001 Table A.1's):

  ====  =====  =====  =====  =====  ====  =====  ====  =====  ====  =====
  name  f1 Hz  f2 Hz  f3 Hz  f4 Hz  Q4    f5 Hz  Q5    f6 Hz  Q6    K
  ====  =====  =====  =====  =====  ====  =====  ====  =====  ====  =====
  Wb    0.4    100    16     16     0.55  2.5    0.9   4      0.95  1.024
  Wc    0.4    100    8      8      0.63  -      -     -      -     1
  Wd    0.4    100    2      2      0.63  -      -     -      -     1
  Wk    0.4    100    12.5   12.5   0.63  2.37   0.91  3.35   0.91  1
  ====  =====  =====  =====  =====  ====  =====  ====  =====  ====  =====

  Wb (vertical) and Wd (horizontal) are EN 12299's; EN 12299:2009 lists EN ISO 8041:2005 among
  its normative references (the SR EN 12299:2009 catalogue entry), whose Wb this is. Two public
  EN 12299 implementations (tobias-bettinger/comfpy comfpy/filters.py, which cites EN 12299:2009;
  ifs-rwth-aachen/PyRidy pyridy/processing/comfort.py) use instead Q4 0.63, Q5 0.8, Q6 0.8 and
  K 0.4 in the (1 + s/(Qω) + s²/ω²) form (the same gains 0.4 and 1.024, another shape: 13.4 %
  higher near 17 Hz, 7.8 % lower near 4 Hz): this module used them until now.
  Which of the two EN 12299:2009 Annex A prints was not read; ISO 8041's is the one its tables
  (ISO 8041-1:2017 Annex B, Table B.1) confirm. Wk is ISO 2631-1's vertical weighting (seated,
  comfort), Wc its seat-back one. Wp (EN 12299's roll velocity weighting) is not implemented.
  The weightings are applied in the frequency domain (the record's FFT times H(j2πf)): the exact
  analytic response at every frequency, no bilinear warping near the Nyquist frequency.
* **N_MV** (EN 12299, standard (simplified) method): the weighted accelerations' rms over
  consecutive 5 s blocks, their 95th percentiles over the record (5 minutes in the standard),
  N_MV = 6 √(a_XP95^Wd² + a_YP95^Wd² + a_ZP95^Wb²). Scale (:data:`N_MV_SCALE`): N_MV < 1.5 very
  comfortable, 1.5 ≤ N_MV < 2.5 comfortable, 2.5 ≤ N_MV < 3.5 medium, 3.5 ≤ N_MV < 4.5
  uncomfortable, N_MV ≥ 4.5 very uncomfortable. EN 12299's own table was not read: this is the
  scale implementations of its clause 6 use (e.g. the open ``ride_comfort`` scripts for N_MV, N_VD
  and N_VA) and the one users of the standard expect; the 1 / 2 / 4 / 5 boundaries often quoted
  with it are UIC leaflet 513's, EN 12299's predecessor (pneumorail printed those until it was
  checked).
* **Continuous comfort** Cc_x,y,z(t): the 5 s sliding rms of the weighted acceleration, every
  second (EN 12299 Cc), in m/s². Its scale is not used (not printed, not checked).
* **Sperling's ride index** in its spectral form (Wz = (∫ B(f)² G(f) df)^(1/6.67), G the one-sided
  PSD of the acceleration in (cm/s²)²/Hz over 0.5-30 Hz; B the vertical weighting 0.588 √((1.911 f² +
  (0.25 f²)²) / ((1 - 0.277 f²)² + (1.563 f - 0.0368 f³)²)), lateral 1.25 times it; as in Forstberg
  2000 and comfpy). Classical scale: 1 very good ... 4.5 not running-safe.
* **ISO 2631-1 overall weighted rms** (comfort, seated): a_v = √(a_wx² + a_wy² + a_wz²), Wd on x and
  y, Wk on z, multiplying factors 1. No comfort words are printed for it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np

#: Q1 = Q2 of the band limits: two-pole Butterworth (ISO 8041 Table 3, "1/√2") [-]
BAND_Q = 1.0 / math.sqrt(2.0)


@dataclass(frozen=True)
class Weighting:
    """A frequency weighting of ISO 8041 Table 3's form (module docstring): band limits f1, f2
    [Hz], acceleration-velocity transition f3, f4 [Hz] and Q4, upward step f5, f6 [Hz] and Q5,
    Q6 (None: no step), high-frequency gain k [-]."""

    f1_Hz: float
    f2_Hz: float
    f3_Hz: float
    f4_Hz: float
    q4: float
    f5_Hz: Optional[float] = None
    q5: Optional[float] = None
    f6_Hz: Optional[float] = None
    q6: Optional[float] = None
    k: float = 1.0


#: the weightings (ISO 8041 Table 3, as quoted in the module docstring)
WEIGHTINGS = {
    "Wb": Weighting(0.4, 100.0, 16.0, 16.0, 0.55, 2.5, 0.9, 4.0, 0.95, 1.024),
    "Wc": Weighting(0.4, 100.0, 8.0, 8.0, 0.63),
    "Wd": Weighting(0.4, 100.0, 2.0, 2.0, 0.63),
    "Wk": Weighting(0.4, 100.0, 12.5, 12.5, 0.63, 2.37, 0.91, 3.35, 0.91),
}
#: EN 12299 block and evaluation lengths [s]
BLOCK_S = 5.0
STANDARD_RECORD_S = 300.0
#: N_MV comfort scale: (upper bound, exclusive; name), EN 12299's (sources: the module docstring)
N_MV_SCALE = ((1.5, "very comfortable"), (2.5, "comfortable"), (3.5, "medium"), (4.5, "uncomfortable"),
              (math.inf, "very uncomfortable"))
#: Sperling's band [Hz]
WZ_BAND_HZ = (0.5, 30.0)
AXES = ("x", "y", "z")


def _omega(f_Hz: float) -> float:
    """2π f [rad/s]."""
    return 2.0 * math.pi * f_Hz


def _quadratic(s, w: float, q: float):
    """s² + ω s / Q + ω²."""
    return s * s + w * s / q + w * w


def band_limit(s, w1: float, w2: float):
    """Hh Hl: the two-pole Butterworth high pass at ω1 and low pass at ω2 [rad/s]."""
    return s * s / _quadratic(s, w1, BAND_Q) * w2 * w2 / _quadratic(s, w2, BAND_Q)


def transition(s, w3: float, w4: float, q4: float):
    """Ht: proportional to acceleration below ω3, ω4 and to velocity above [rad/s]."""
    return (1.0 + s / w3) / (1.0 + s / (q4 * w4) + s * s / (w4 * w4))


def upward_step(s, w5: float, q5: float, w6: float, q6: float):
    """Hs: (ω5/ω6)² at low frequency, 1 at high frequency [rad/s]."""
    return _quadratic(s, w5, q5) / _quadratic(s, w6, q6)


def weighting_response(w: Weighting, f_Hz) -> np.ndarray:
    """The complex frequency response H(j 2π f) of the weighting ``w``."""
    s = 2j * math.pi * np.asarray(f_Hz, dtype=float)
    h = band_limit(s, _omega(w.f1_Hz), _omega(w.f2_Hz)) * transition(s, _omega(w.f3_Hz), _omega(w.f4_Hz), w.q4)
    if w.f5_Hz is not None:
        h = h * upward_step(s, _omega(w.f5_Hz), w.q5, _omega(w.f6_Hz), w.q6)
    return w.k * h


def response(name: str, f_Hz) -> np.ndarray:
    """The complex frequency response H(j 2π f) of weighting ``name`` (:data:`WEIGHTINGS`)."""
    return weighting_response(WEIGHTINGS[name], f_Hz)


def n_mv_scale(n_mv: float) -> str:
    """The name of ``n_mv`` on EN 12299's comfort scale (:data:`N_MV_SCALE`)."""
    return next(name for bound, name in N_MV_SCALE if n_mv < bound)


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
        return None if self.N_MV is None else n_mv_scale(self.N_MV)


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
