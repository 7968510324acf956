"""Fast evaluation of a track centre line at a few arc lengths per time step.

:class:`~vehicle.track.TrackGeometry` is exact (Fresnel integrals, quadrature) but costs ~150 us
per call on the four wheelset positions, i.e. ~30 ms per simulated second at 5 ms steps: a fifth
of the car's whole budget. :class:`TrackSampler` samples the geometry once on a grid that
contains every segment join and interpolates between the samples, each interval with the values
of its own segment at both of its ends (curvature, cant and their slopes may jump at a join):

* heading: cubic Hermite with the exact curvature as its slope at both ends; the curvature is
  its derivative. Exact (to round-off) on straights, arcs and clothoids, where the heading is at
  most quadratic; on the smoothed transitions (cosine, Bloss) the curvature is continuous across
  the grid points and within ~spacing^3 max|d3 kappa / ds3| / 24 of the exact one;
* cant: cubic Hermite with the exact d(cant)/ds at both ends, and d(cant)/ds its derivative:
  exact on linear ramps, and continuous across the grid points on smoothed ones, so that the
  rails' roll rate has no step the geometry does not have (a slope held constant per interval
  would step at every grid point: on a 15 m cosine ramp to 0.15 rad, by ~3e-4 rad/m every
  0.1 m);
* position: cubic Hermite with the exact tangents (cos, sin)(heading) at both ends. The error is
  about spacing^4 / 384 * max|d^4 p / ds^4|; on a clothoid d^4 p / ds^4 ~ 3 kappa kappa' (the
  arc alone: kappa^3), so at the default 0.1 m spacing the paper's transition (R = 100 m over
  15 m) gives 5e-12 m (measured; 2e-10 m at 0.25 m). tests/vehicle/test_vehicle_curve.py checks
  < 1e-9 m against the exact geometry.

Building the table costs one vectorised evaluation of the whole track (~6 ms per 400 m); the
few points of a time step then cost ~2 us (:meth:`TrackSampler.rows`, compiled).
"""
from __future__ import annotations

import functools
import math

import numpy as np

from .track import TrackGeometry
from .wheelrail.compiled import kernel

__all__ = ["TrackSampler", "shared_sampler"]


def _hermite_coefficients(v0, v1, slope0, slope1, d):
    """(a2, a3) of the cubic v0 + slope0 u + a2 u^2 + a3 u^3 on [0, d] that ends at v1 with
    slope1 (arrays)."""
    dv = v1 - v0 - slope0 * d
    dslope = (slope1 - slope0) * d
    return (3.0 * dv - dslope) / (d * d), (dslope - 2.0 * dv) / (d * d * d)


class TrackSampler:
    """Tabulated :class:`~vehicle.track.TrackGeometry` for repeated evaluation of a few points.

    Args:
        track: the exact geometry.
        spacing_m: largest grid spacing [m] inside a segment.
    """

    def __init__(self, track: TrackGeometry, spacing_m: float = 0.1):
        if not spacing_m > 0.0:
            raise ValueError(f"spacing_m must be > 0, got {spacing_m}")
        self.track = track
        self.total_length_m = track.total_length_m
        starts = list(np.asarray(track.segment_start_m, dtype=float)) + [self.total_length_m]
        left, segment = [], []  # left ends of the grid intervals (every segment start is one)
        for k, (a, b) in enumerate(zip(starts[:-1], starts[1:])):
            n = max(1, math.ceil((b - a) / spacing_m))
            left.append(a + (b - a) * np.arange(n) / n)
            segment.append(np.full(n, k))
        s0 = np.concatenate(left)
        segment = np.concatenate(segment)
        s1 = np.append(s0[1:], self.total_length_m)
        ds = s1 - s0
        # heading, curvature, cant and its slope at both ends of each interval from the
        # interval's own segment (position and heading are continuous at the joins anyway)
        ends = np.empty((2, 4, s0.size))
        for k in np.unique(segment):
            mask = segment == k
            for side, s in enumerate((s0, s1)):
                ends[side][:, mask] = track.segment_values(int(k), s[mask] - starts[k])
        (psi0, kappa0, c0, dc0), (psi1, kappa1, c1, dc1) = ends
        x0, y0 = track.position_m(s0)
        x1, y1 = track.position_m(s1)
        # per interval the cubic Hermites of heading and cant in the local coordinate u,
        # value0 + u (slope0 + u (a2 + u a3)), and the position's end tangents; one row each:
        # (s0, ds, x0, y0, x1, y1, psi0, kappa0, psi a2, psi a3, c0, dc0, cant a2, cant a3,
        # cos psi0, sin psi0, cos psi1, sin psi1)
        psi_a2, psi_a3 = _hermite_coefficients(psi0, psi1, kappa0, kappa1, ds)
        c_a2, c_a3 = _hermite_coefficients(c0, c1, dc0, dc1, ds)
        self._table = np.ascontiguousarray(np.stack((
            s0, ds, x0, y0, x1, y1, psi0, kappa0, psi_a2, psi_a3, c0, dc0, c_a2, c_a3,
            np.cos(psi0), np.sin(psi0), np.cos(psi1), np.sin(psi1)), axis=1))

    def __call__(self, s) -> tuple[np.ndarray, ...]:
        """(x [m], y [m], heading [rad], cant [rad], curvature [1/m], d(cant)/ds [rad/m]) at the
        arc lengths ``s`` [m] (1-D array): the columns of :meth:`rows`.

        Same conventions as :class:`~vehicle.track.TrackGeometry`; s outside
        [0, total_length_m] raises ValueError.
        """
        return tuple(self.rows(s).T)

    def rows(self, s) -> np.ndarray:
        """The centre line at the arc lengths ``s`` [m] as one (points, 6) array whose rows are
        (x, y, heading, cant, curvature, d(cant)/ds): a compiled kernel, ~2 us for the five
        points a car asks for at each time step (a numpy evaluation took ~60 us)."""
        s = np.asarray(s, dtype=float).ravel()
        out, inside = _sampled_rows(self._table, s, self.total_length_m)
        if not inside:
            self._check(s.min(), s.max(), s)
        return out

    def at(self, s) -> list[tuple[float, ...]]:
        """:meth:`rows` as a list of tuples ``[(x, y, heading, cant, curvature, d(cant)/ds),
        ...]``."""
        return [tuple(r) for r in self.rows(s).tolist()]

    def _check(self, lo, hi, s) -> None:
        # written so that NaN fails too
        if not (0.0 <= lo and hi <= self.total_length_m):
            raise ValueError(f"track: s must lie in [0, {self.total_length_m!r}] m; got {s}")


@kernel(__file__)
def _sampled_rows(table, s, total_length_m):
    """The rows of :meth:`TrackSampler.rows` at the arc lengths ``s`` from the sampler's
    per-interval ``table`` (the interval with s0 <= s, the first or last one beyond the ends;
    the Hermite cubics of the module docstring in the local coordinate u), and whether every s
    lies on the track (NaN does not)."""
    out = np.empty((s.size, 6))
    last = table.shape[0] - 1
    inside = True
    for n in range(s.size):
        si = s[n]
        inside = inside and 0.0 <= si <= total_length_m
        j = min(max(np.searchsorted(table[:, 0], si, side="right") - 1, 0), last)
        (a, d, x0, y0, x1, y1, psi0, k0, p2, p3, c0, dc0, q2, q3, cp0, sp0, cp1,
         sp1) = table[j]
        u = si - a
        t = u / d
        t2, r = t * t, 1.0 - t
        h00, h01 = (1.0 + 2.0 * t) * r * r, t2 * (3.0 - 2.0 * t)
        h10, h11 = t * r * r * d, -t2 * r * d
        out[n, 0] = h00 * x0 + h01 * x1 + h10 * cp0 + h11 * cp1
        out[n, 1] = h00 * y0 + h01 * y1 + h10 * sp0 + h11 * sp1
        out[n, 2] = psi0 + u * (k0 + u * (p2 + u * p3))
        out[n, 3] = c0 + u * (dc0 + u * (q2 + u * q3))
        out[n, 4] = k0 + u * (2.0 * p2 + 3.0 * u * p3)
        out[n, 5] = dc0 + u * (2.0 * q2 + 3.0 * u * q3)
    return out, inside


@functools.lru_cache(maxsize=16)
def shared_sampler(track: TrackGeometry) -> TrackSampler:
    """The :class:`TrackSampler` (default spacing) of ``track``, one per distinct track in this
    process: the cars of a co-simulation run the same track, so they share its table."""
    return TrackSampler(track)
