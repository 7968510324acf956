"""Railway track centre-line geometry as a function of arc length s [m].

The track is a chain of segments -- :class:`Straight`, :class:`Transition` and :class:`Arc` --
assembled by :class:`TrackGeometry`, which evaluates, vectorised over s:

- ``position_m(s) -> (x, y)`` [m], ``heading_rad(s)`` [rad], ``curvature_per_m(s)`` [1/m],
  ``cant_rad(s)`` [rad], and ``total_length_m`` [m].

Frame and signs: x forward (heading 0 at s = 0), y to the left, z up; the track starts at the
origin. Positive curvature turns LEFT. Heading is the unwrapped integral of curvature; the
position is the integral of (cos, sin)(heading).

Cant (superelevation) is an angle. ``Arc.cant_rad`` is the usual railway quantity: positive
raises the outer rail. ``TrackGeometry.cant_rad(s)`` is signed like the curvature: positive banks
the track plane toward +y (right rail higher), so a normally canted curve has
``cant_rad(s) * curvature_per_m(s) >= 0``. The roll angle of the track plane about the forward
tangent (right-handed about x) is ``-cant_rad(s)``; the rail height difference over a rail-centre
distance b is ``b * sin(cant)``.

Transitions. Along a transition of length L the curvature and the cant go from the previous
segment's values (kappa0, c0) to the next one's (kappa1, c1) with one shape function f of
xi = u / L (u: arc length into the transition), f(0) = 0, f(1) = 1:

    kappa(u) = kappa0 + (kappa1 - kappa0) f(xi),    cant(u) = c0 + (c1 - c0) f(xi),

* ``linear``: f = xi -- a clothoid with a linear cant ramp (the paper's transition). Curvature
  and cant are continuous, but their slopes jump at both ends: on canted track the rails' roll
  rate steps from 0 to v (c1 - c0) / L as a wheelset enters the ramp;
* ``cosine``: f = (1 - cos(pi xi)) / 2 -- slopes 0 at both ends (no step in the roll rate; the
  roll acceleration steps by v^2 (c1 - c0) pi^2 / (2 L^2));
* ``bloss``: f = 3 xi^2 - 2 xi^3 (Bloss's transition) -- slopes 0 at both ends as well; its
  largest slope is 1.5 / L, against pi / (2 L) = 1.57 / L for ``cosine`` and 1 / L for
  ``linear``.

The heading is the integral of the curvature, theta(u) = theta0 + kappa0 u + (kappa1 - kappa0)
L F(xi) with F the integral of f (xi^2/2; xi/2 - sin(pi xi)/(2 pi); xi^3 - xi^4/2).

Everything is exact up to round-off: straights and arcs analytically, clothoids (curvature
linear in s, possibly starting at non-zero curvature) via Fresnel integrals of the spiral they
are a piece of. A clothoid between two nearly equal curvatures is a piece of a spiral so far from
its inflection point that the Fresnel difference cancels badly, and the other shapes have no
closed form: their position is integrated by composite Gauss-Legendre quadrature of the exact
integrand exp(i theta(u)) (error << 1e-12 m).

s outside [0, total_length_m] raises ValueError (no clamping, no extrapolation).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Union

import numpy as np
from scipy.special import fresnel

__all__ = ["Straight", "Transition", "Arc", "Segment", "TrackGeometry", "TRANSITION_SHAPES"]


def _checked_float(owner: str, name: str, value, *, positive: bool) -> float:
    """Return ``value`` as a finite float, > 0 if ``positive``; else ValueError naming it."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{owner}: {name} must be a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{owner}: {name} must be finite, got {v!r}")
    if positive and v <= 0.0:
        raise ValueError(f"{owner}: {name} must be > 0, got {v!r}")
    return v


def _checked_cant(owner: str, value) -> float:
    v = _checked_float(owner, "cant_rad", value, positive=False)
    if abs(v) >= math.pi / 2:
        raise ValueError(f"{owner}: cant_rad must lie in (-pi/2, pi/2) rad, got {v!r}")
    return v


@dataclass(frozen=True)
class Straight:
    """Straight level track: curvature 0, cant 0. ``length_m`` [m] > 0."""

    length_m: float

    def __post_init__(self):
        object.__setattr__(self, "length_m",
                           _checked_float("Straight", "length_m", self.length_m, positive=True))

    @property
    def curvature_per_m(self) -> float:
        return 0.0

    @property
    def signed_cant_rad(self) -> float:
        return 0.0


#: transition shapes (see the module docstring and :func:`shape_function`)
TRANSITION_SHAPES = ("linear", "cosine", "bloss")


def shape_function(shape: str, xi):
    """(f, F, f') of a transition shape at xi = u / L in [0, 1] (arrays or floats): the fraction
    of the change of curvature and cant reached, its integral over xi, and its slope d f / d xi
    (module docstring)."""
    xi = np.asarray(xi, dtype=float)
    if shape == "linear":
        return xi, 0.5 * xi * xi, np.ones_like(xi)
    if shape == "cosine":
        return (0.5 - 0.5 * np.cos(np.pi * xi), 0.5 * xi - np.sin(np.pi * xi) / (2.0 * np.pi),
                0.5 * np.pi * np.sin(np.pi * xi))
    if shape == "bloss":
        x2 = xi * xi
        return x2 * (3.0 - 2.0 * xi), x2 * xi * (1.0 - 0.5 * xi), 6.0 * xi * (1.0 - xi)
    raise ValueError(f"transition shape must be one of {TRANSITION_SHAPES}, got {shape!r}")


@dataclass(frozen=True)
class Transition:
    """Transition of ``length_m`` [m] > 0.

    Curvature and (signed) cant go from the previous segment's values to the next segment's
    values along ``shape`` (``linear``: a clothoid with a linear cant ramp; ``cosine``;
    ``bloss``; see the module docstring); a missing neighbour (transition at either end of the
    track) counts as straight level track. Two transitions may not be adjacent.
    """

    length_m: float
    shape: str = "linear"

    def __post_init__(self):
        object.__setattr__(self, "length_m",
                           _checked_float("Transition", "length_m", self.length_m, positive=True))
        if self.shape not in TRANSITION_SHAPES:
            raise ValueError(f"Transition: shape must be one of {', '.join(TRANSITION_SHAPES)}, "
                             f"got {self.shape!r}")


@dataclass(frozen=True)
class Arc:
    """Circular arc.

    radius_m [m] > 0, length_m [m] > 0, direction +1 (curve to the left) or -1 (to the right),
    cant_rad [rad]: superelevation as an angle, positive raises the outer rail.
    """

    radius_m: float
    length_m: float
    direction: int = +1
    cant_rad: float = 0.0

    def __post_init__(self):
        set_ = object.__setattr__
        set_(self, "radius_m", _checked_float("Arc", "radius_m", self.radius_m, positive=True))
        set_(self, "length_m", _checked_float("Arc", "length_m", self.length_m, positive=True))
        if self.direction not in (1, -1):
            raise ValueError(f"Arc: direction must be +1 (left) or -1 (right), "
                             f"got {self.direction!r}")
        set_(self, "direction", int(self.direction))
        set_(self, "cant_rad", _checked_cant("Arc", self.cant_rad))

    @property
    def curvature_per_m(self) -> float:
        """Signed curvature [1/m], positive to the left."""
        return self.direction / self.radius_m

    @property
    def signed_cant_rad(self) -> float:
        """Cant [rad] signed like the curvature (positive banks toward +y)."""
        return self.direction * self.cant_rad


Segment = Union[Straight, Transition, Arc]

# --- local offsets: complex displacement D(u) = x + i y after arc length u [m] from a start at the
# origin with heading 0, curvature kappa0 [1/m] and curvature rate [1/m^2] ------------------------

# Fresnel path's round-off is about eps * (a + |kappa|/|rate|) with a = sqrt(pi/|rate|) [m]; keep
# that below ~1e-12 m, else use quadrature.
_FRESNEL_MAX_SCALE_M = 1.0e4
_GL_X, _GL_W = np.polynomial.legendre.leggauss(12)
# Phase variation per Gauss-Legendre panel [rad]: 12 nodes integrate exp(i*phase) over a 1 rad
# phase change with a truncation error far below round-off.
_GL_MAX_PANEL_PHASE_RAD = 1.0
_GL_CHUNK = 4096


def _arc_offset(kappa: float, u: np.ndarray) -> np.ndarray:
    """Constant curvature (kappa = 0: straight): x = sin(k u)/k, y = (1 - cos(k u))/k, stably."""
    x = u * np.sinc(kappa * u / np.pi)
    y = 0.5 * kappa * u * u * np.sinc(kappa * u / (2.0 * np.pi)) ** 2
    return x + 1j * y


def _fresnel_offset(kappa0: float, rate: float, u: np.ndarray) -> np.ndarray:
    """Clothoid offset via Fresnel integrals.

    With t = u + kappa0/rate the heading is (rate/2)(t^2 - t0^2): the segment is the piece
    [t0, t0 + u] of the standard spiral, rotated back by rate*t0^2/2. Substituting
    rate*t^2/2 = sign(rate)*(pi/2)*(t/a)^2, a = sqrt(pi/|rate|):
        D(u) = a exp(-i kappa0^2/(2 rate)) [C(w) - C(w0) + i sign(rate) (S(w) - S(w0))], w = t/a.
    """
    a = math.sqrt(math.pi / abs(rate))
    t0 = kappa0 / rate
    s0, c0 = fresnel(t0 / a)  # scipy returns (S, C)
    s1, c1 = fresnel((u + t0) / a)
    rotation = np.exp(-0.5j * kappa0 * t0)
    return a * rotation * ((c1 - c0) + 1j * math.copysign(1.0, rate) * (s1 - s0))


def _quadrature_offset(kappa0: float, dkappa: float, length: float, u: np.ndarray,
                       shape: str = "linear") -> np.ndarray:
    """Transition offset by composite Gauss-Legendre quadrature of exp(i phase(v)), phase(v) =
    kappa0 v + dkappa length F(v / length) (F: the shape's integral, :func:`shape_function`; for
    ``linear`` kappa0 v + rate v^2 / 2 with rate = dkappa / length)."""
    kappa_max = max(abs(kappa0), abs(kappa0 + dkappa))  # the shapes are monotonic
    # the phase's curvature is dkappa f' / length, f' <= pi / 2 for every shape
    phase_span = (kappa_max + math.sqrt(0.5 * math.pi * abs(dkappa) / length)) * length
    n_panels = max(1, math.ceil(phase_span / _GL_MAX_PANEL_PHASE_RAD))
    frac = ((np.arange(n_panels)[:, None] + 0.5 * (_GL_X + 1.0)) / n_panels).ravel()
    weights = np.tile(0.5 * _GL_W, n_panels) / n_panels
    out = np.empty(u.shape, dtype=complex)
    for i in range(0, u.size, _GL_CHUNK):
        uc = u[i:i + _GL_CHUNK]
        v = uc[:, None] * frac[None, :]
        phase = kappa0 * v + dkappa * length * shape_function(shape, v / length)[1]
        out[i:i + _GL_CHUNK] = uc * (np.exp(1j * phase) @ weights)
    return out


def _fresnel_is_accurate(kappa0: float, rate: float, length: float) -> bool:
    kappa_max = max(abs(kappa0), abs(kappa0 + rate * length))
    return math.sqrt(math.pi / abs(rate)) + kappa_max / abs(rate) <= _FRESNEL_MAX_SCALE_M


def _local_offset(kappa0: float, dkappa: float, length: float, u: np.ndarray,
                  shape: str = "linear") -> np.ndarray:
    if dkappa == 0.0:
        return _arc_offset(kappa0, u)
    rate = dkappa / length
    if shape == "linear" and _fresnel_is_accurate(kappa0, rate, length):
        return _fresnel_offset(kappa0, rate, u)
    return _quadrature_offset(kappa0, dkappa, length, u, shape)


def _float_out(a: np.ndarray, scalar: bool):
    return float(a) if scalar else a


@dataclass(frozen=True)
class TrackGeometry:
    """Track centre line built from a sequence of segments, starting at the origin, heading +x.

    Evaluation methods accept a float or an array of s [m] in [0, total_length_m] and return a
    float or an array of the same shape. At a segment join the following segment is used; the
    geometry is continuous in position and heading there, and in curvature and cant wherever a
    Transition joins its neighbours.
    """

    segments: tuple
    # Per-segment tables (index k = segment k), filled in __post_init__.
    _s0: np.ndarray = field(init=False, repr=False, compare=False)
    _length: np.ndarray = field(init=False, repr=False, compare=False)
    _kappa0: np.ndarray = field(init=False, repr=False, compare=False)
    _dkappa: np.ndarray = field(init=False, repr=False, compare=False)  # change over the segment
    _cant0: np.ndarray = field(init=False, repr=False, compare=False)
    _dcant: np.ndarray = field(init=False, repr=False, compare=False)    # change over the segment
    _shape: tuple = field(init=False, repr=False, compare=False)        # transition shape names
    _xy0: np.ndarray = field(init=False, repr=False, compare=False)   # complex start position
    _theta0: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        segs = tuple(self.segments)
        if not segs:
            raise ValueError("TrackGeometry: segments must not be empty")
        for k, seg in enumerate(segs):
            if not isinstance(seg, (Straight, Transition, Arc)):
                raise ValueError(f"TrackGeometry: segments[{k}] is {type(seg).__name__}, "
                                 "expected Straight, Transition or Arc")
            if k and isinstance(seg, Transition) and isinstance(segs[k - 1], Transition):
                raise ValueError(f"TrackGeometry: segments[{k - 1}] and segments[{k}] are "
                                 "adjacent Transitions; the curvature at their join is undefined")

        def ends(k):  # (curvature, signed cant) of segment k; beyond the ends: straight level
            if 0 <= k < len(segs):
                return segs[k].curvature_per_m, segs[k].signed_cant_rad
            return 0.0, 0.0

        n = len(segs)
        tab = {name: np.empty(n) for name in ("s0", "length", "kappa0", "dkappa", "cant0",
                                              "dcant", "theta0")}
        xy0 = np.empty(n, dtype=complex)
        shapes = []
        s, xy, theta = 0.0, 0j, 0.0
        for k, seg in enumerate(segs):
            length = seg.length_m
            if isinstance(seg, Transition):
                (k0, c0), (k1, c1) = ends(k - 1), ends(k + 1)
                shape = seg.shape
            else:
                (k0, c0) = (k1, c1) = ends(k)
                shape = "linear"
            for name, value in (("s0", s), ("length", length), ("kappa0", k0),
                                ("dkappa", k1 - k0), ("cant0", c0), ("dcant", c1 - c0),
                                ("theta0", theta)):
                tab[name][k] = value
            shapes.append(shape)
            xy0[k] = xy
            end = _local_offset(k0, k1 - k0, length, np.array([length]), shape)[0]
            xy += np.exp(1j * theta) * end
            # heading change: kappa0 L + (kappa1 - kappa0) L F(1), F(1) = 1/2 for every shape
            theta += k0 * length + 0.5 * (k1 - k0) * length
            s += length
        set_ = object.__setattr__
        set_(self, "segments", segs)
        for name, arr in tab.items():
            arr.flags.writeable = False
            set_(self, "_" + name, arr)
        set_(self, "_shape", tuple(shapes))
        xy0.flags.writeable = False
        set_(self, "_xy0", xy0)

    # --- construction ------------------------------------------------------------------------

    @classmethod
    def curve_entry(cls, straight_m: float, transition_m: float, radius_m: float, arc_m: float,
                    cant_rad: float = 0.0, direction: int = +1,
                    transition_shape: str = "linear") -> "TrackGeometry":
        """Straight [m], transition [m], circular arc of radius_m [m] and length arc_m [m].

        cant_rad [rad] is the arc's cant (positive raises the outer rail), reached along the
        transition like the curvature, by ``transition_shape`` (``linear``: a clothoid with a
        linear cant ramp; ``cosine``, ``bloss``: see the module docstring); direction +1 curves
        left, -1 right. A zero straight_m or transition_m omits that segment. The paper's case
        (Fig. 9): transition_m=15, radius_m=100, cant_rad=0, linear.
        """
        straight_m = _checked_float("curve_entry", "straight_m", straight_m, positive=False)
        transition_m = _checked_float("curve_entry", "transition_m", transition_m,
                                      positive=False)
        for name, value in (("straight_m", straight_m), ("transition_m", transition_m)):
            if value < 0.0:
                raise ValueError(f"curve_entry: {name} must be >= 0, got {value!r}")
        segs = []
        if straight_m > 0.0:
            segs.append(Straight(straight_m))
        if transition_m > 0.0:
            segs.append(Transition(transition_m, transition_shape))
        _checked_float("curve_entry", "arc_m", arc_m, positive=True)
        # radius_m, cant_rad and direction are checked by Arc, under the same names.
        segs.append(Arc(radius_m=radius_m, length_m=arc_m, direction=direction,
                        cant_rad=cant_rad))
        return cls(tuple(segs))

    # --- evaluation --------------------------------------------------------------------------

    @property
    def total_length_m(self) -> float:
        """Total track length [m]."""
        return float(self._s0[-1] + self._length[-1])

    @property
    def segment_start_m(self) -> np.ndarray:
        """Arc length [m] at the start of each segment (read-only array)."""
        return self._s0

    def _locate(self, s):
        """(segment index array, local arc length u [m] array, input-was-scalar)."""
        s_arr = np.asarray(s, dtype=float)
        if s_arr.size:
            if not np.all(np.isfinite(s_arr)):
                raise ValueError("track: s must be finite (got NaN or inf)")
            lo, hi = float(s_arr.min()), float(s_arr.max())
            if lo < 0.0 or hi > self.total_length_m:
                raise ValueError(f"track: s must lie in [0, {self.total_length_m!r}] m "
                                 f"(the track length); got values in [{lo!r}, {hi!r}] m")
        idx = np.searchsorted(self._s0, s_arr, side="right") - 1
        return idx, s_arr - self._s0[idx], s_arr.ndim == 0

    def _shape_at(self, idx: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, ...]:
        """(f, F, f') of each point's segment shape at xi = u / length (:func:`shape_function`;
        0 and 1 on straights and arcs, whose changes are 0)."""
        xi = u / self._length[idx]
        out = tuple(np.empty(u.shape) for _ in range(3))
        for shape in set(self._shape[k] for k in np.unique(idx)):
            mask = np.isin(idx, [k for k, sh in enumerate(self._shape) if sh == shape])
            for arr, value in zip(out, shape_function(shape, xi[mask])):
                arr[mask] = value
        return out

    def segment_values(self, k: int, u) -> tuple[np.ndarray, ...]:
        """(heading [rad], curvature [1/m], cant [rad], d(cant)/ds [rad/m]) of segment ``k`` at
        local arc lengths ``u`` [m] in [0, its length]: its own values also at its end, where
        the next segment may start with others (curvature, cant and their slopes may jump at a
        join; :class:`~vehicle.guidance.TrackSampler` interpolates each segment on its own)."""
        u = np.asarray(u, dtype=float)
        length = self._length[k]
        f, F, df = shape_function(self._shape[k], u / length)
        k0, dk, c0, dc = self._kappa0[k], self._dkappa[k], self._cant0[k], self._dcant[k]
        return (self._theta0[k] + k0 * u + dk * length * F, k0 + dk * f, c0 + dc * f,
                dc * df / length)

    def curvature_per_m(self, s):
        """Signed curvature [1/m] at s [m], positive to the left."""
        idx, u, scalar = self._locate(s)
        f = self._shape_at(idx, u)[0]
        return _float_out(self._kappa0[idx] + self._dkappa[idx] * f, scalar)

    def heading_rad(self, s):
        """Heading [rad] at s [m]: angle of the tangent from +x toward +y, unwrapped."""
        idx, u, scalar = self._locate(s)
        F = self._shape_at(idx, u)[1]
        return _float_out(self._theta0[idx] + self._kappa0[idx] * u
                          + self._dkappa[idx] * self._length[idx] * F, scalar)

    def cant_rad(self, s):
        """Cant [rad] at s [m], signed like the curvature (positive: right rail higher).

        The track plane's roll angle about the forward tangent (right-handed about x) is minus
        this value.
        """
        idx, u, scalar = self._locate(s)
        f = self._shape_at(idx, u)[0]
        return _float_out(self._cant0[idx] + self._dcant[idx] * f, scalar)

    def cant_slope_per_m(self, s):
        """d(cant)/ds [rad/m] at s [m] (the rails' roll rate over the running speed)."""
        idx, u, scalar = self._locate(s)
        df = self._shape_at(idx, u)[2]
        return _float_out(self._dcant[idx] * df / self._length[idx], scalar)

    def position_m(self, s):
        """Centre-line position (x [m], y [m]) at s [m]."""
        idx, u, scalar = self._locate(s)
        xy = np.empty(u.shape, dtype=complex)
        for k in np.unique(idx):
            mask = idx == k
            d = _local_offset(self._kappa0[k], self._dkappa[k], self._length[k], u[mask],
                              self._shape[k])
            xy[mask] = self._xy0[k] + np.exp(1j * self._theta0[k]) * d
        return _float_out(xy.real, scalar), _float_out(xy.imag, scalar)
