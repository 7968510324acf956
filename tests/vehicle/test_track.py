"""Tests of vehicle/track.py against closed forms and independent quadrature.

Tolerance budget: the module's closed forms are exact up to round-off, i.e. ~1e-16 relative on
coordinates of O(100 m) -> ~1e-14 m. scipy.integrate.quad with epsabs=epsrel=1e-13 on these
smooth, slowly oscillating integrands (values < 100 m) is accurate to ~1e-12 m at worst.
Position checks therefore use 1e-11 m: an order of magnitude above both error sources and two
below the 1e-9 m requirement.
"""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from vehicle import track as track_module
from vehicle.track import Arc, Straight, TrackGeometry, Transition

POS_TOL_M = 1e-11
ANGLE_TOL_RAD = 1e-13  # heading values are O(1) rad, polynomial in s: round-off ~1e-15 rad

# The paper's curve entry (Fig. 9): straight, 15 m transition, R = 100 m, no cant.
STRAIGHT_M, TRANSITION_M, RADIUS_M, ARC_M = 40.0, 15.0, 100.0, 80.0


@pytest.fixture
def paper_track():
    return TrackGeometry.curve_entry(STRAIGHT_M, TRANSITION_M, RADIUS_M, ARC_M)


def quad_xy(heading, a, b):
    """Independent reference: integral of (cos, sin)(heading(u)) du over [a, b]."""
    opts = dict(epsabs=1e-13, epsrel=1e-13, limit=200)
    return (quad(lambda u: math.cos(heading(u)), a, b, **opts)[0],
            quad(lambda u: math.sin(heading(u)), a, b, **opts)[0])


def test_clothoid_end_point_matches_quadrature(paper_track):
    # Standard clothoid with A^2 = R L: heading u^2 / (2 A^2) from u = 0 at the straight's end.
    a2 = RADIUS_M * TRANSITION_M
    x_ref, y_ref = quad_xy(lambda u: u * u / (2.0 * a2), 0.0, TRANSITION_M)
    x, y = paper_track.position_m(STRAIGHT_M + TRANSITION_M)
    assert abs(x - (STRAIGHT_M + x_ref)) < POS_TOL_M
    assert abs(y - y_ref) < POS_TOL_M
    # Sanity against the series y ~ L^2/(6R) (1 - L^2/(56 R^2)): agreement to the next term.
    assert y == pytest.approx(TRANSITION_M**2 / (6 * RADIUS_M)
                              * (1 - TRANSITION_M**2 / (56 * RADIUS_M**2)), rel=1e-6)


def test_heading_and_curvature_in_transition(paper_track):
    u = np.linspace(0.0, TRANSITION_M, 31)
    s = STRAIGHT_M + u
    assert np.allclose(paper_track.heading_rad(s), u**2 / (2 * RADIUS_M * TRANSITION_M),
                       rtol=0, atol=ANGLE_TOL_RAD)
    # curvature is linear from 0 to 1/R; round-off ~1e-18 1/m
    assert np.allclose(paper_track.curvature_per_m(s), u / (RADIUS_M * TRANSITION_M),
                       rtol=0, atol=1e-16)
    assert paper_track.heading_rad(STRAIGHT_M + TRANSITION_M) == pytest.approx(
        TRANSITION_M / (2 * RADIUS_M), abs=ANGLE_TOL_RAD)


def test_straight_is_the_x_axis(paper_track):
    s = np.linspace(0.0, STRAIGHT_M, 11)
    x, y = paper_track.position_m(s)
    assert np.array_equal(x, s) and np.array_equal(y, np.zeros_like(s))
    assert np.array_equal(paper_track.heading_rad(s), np.zeros_like(s))


@pytest.mark.parametrize("direction", [+1, -1])
def test_arc_points_are_at_radius_from_centre(direction):
    track = TrackGeometry.curve_entry(STRAIGHT_M, TRANSITION_M, RADIUS_M, ARC_M,
                                      direction=direction)
    s_start = STRAIGHT_M + TRANSITION_M
    x0, y0 = track.position_m(s_start)
    th0 = track.heading_rad(s_start)
    # centre lies on the normal toward the curve (left normal for a left curve)
    cx, cy = x0 - direction * RADIUS_M * math.sin(th0), y0 + direction * RADIUS_M * math.cos(th0)
    s = np.linspace(s_start, track.total_length_m, 41)
    x, y = track.position_m(s)
    # coordinates O(100 m) with round-off ~1e-14 m; 1e-11 m leaves ample margin
    assert np.allclose(np.hypot(x - cx, y - cy), RADIUS_M, rtol=0, atol=POS_TOL_M)
    assert np.allclose(track.curvature_per_m(s), direction / RADIUS_M, rtol=0, atol=0)
    assert np.allclose(track.heading_rad(s), th0 + direction * (s - s_start) / RADIUS_M,
                       rtol=0, atol=ANGLE_TOL_RAD)


def test_right_curve_mirrors_left_curve():
    left = TrackGeometry.curve_entry(10.0, TRANSITION_M, RADIUS_M, ARC_M, cant_rad=0.1)
    right = TrackGeometry.curve_entry(10.0, TRANSITION_M, RADIUS_M, ARC_M, cant_rad=0.1,
                                      direction=-1)
    s = np.linspace(0.0, left.total_length_m, 57)
    (xl, yl), (xr, yr) = left.position_m(s), right.position_m(s)
    assert np.allclose(xr, xl, rtol=0, atol=1e-12) and np.allclose(yr, -yl, rtol=0, atol=1e-12)
    assert np.allclose(right.heading_rad(s), -left.heading_rad(s), rtol=0, atol=1e-15)
    assert np.allclose(right.cant_rad(s), -left.cant_rad(s), rtol=0, atol=1e-15)


def test_cant_ramps_linearly_in_transition_and_is_constant_in_arc():
    cant = 0.09
    track = TrackGeometry.curve_entry(STRAIGHT_M, TRANSITION_M, RADIUS_M, ARC_M, cant_rad=cant)
    u = np.linspace(0.0, TRANSITION_M, 16)
    assert np.allclose(track.cant_rad(STRAIGHT_M + u), cant * u / TRANSITION_M, rtol=0,
                       atol=1e-16)
    assert np.all(track.cant_rad(np.linspace(0, STRAIGHT_M, 5)) == 0.0)
    assert np.all(track.cant_rad(np.linspace(STRAIGHT_M + TRANSITION_M, track.total_length_m,
                                             5)) == cant)
    # the paper's case has no cant anywhere
    paper = TrackGeometry.curve_entry(STRAIGHT_M, TRANSITION_M, RADIUS_M, ARC_M)
    assert np.all(paper.cant_rad(np.linspace(0, paper.total_length_m, 50)) == 0.0)


# A general layout: clothoids starting at non-zero curvature, a reverse curve whose transition
# passes through zero curvature (inflection inside the segment), a compound curve, a transition
# between nearly equal curvatures (quadrature path) and an exit spiral ending the track.
GENERAL = (
    Straight(12.0),
    Transition(15.0),
    Arc(100.0, 30.0, +1, 0.08),
    Transition(20.0),                  # +1/100 -> -1/250: inflection inside
    Arc(250.0, 25.0, -1, 0.02),
    Transition(18.0),                  # -1/250 -> -1/80: compound curve
    Arc(80.0, 10.0, -1, 0.1),
    Transition(7.0),                   # -1/80 -> -1/80.0001: nearly constant curvature
    Arc(80.0001, 12.0, -1, 0.1),
    Transition(30.0),                  # exit spiral to curvature 0 at the track's end
)


def general_heading_reference(segments):
    """Piecewise heading(s) built directly from the segment definitions, for quad."""
    kappas = []
    for k, seg in enumerate(segments):
        if isinstance(seg, Transition):
            k0 = segments[k - 1].curvature_per_m if k > 0 else 0.0
            k1 = segments[k + 1].curvature_per_m if k + 1 < len(segments) else 0.0
        else:
            k0 = k1 = seg.curvature_per_m
        kappas.append((k0, k1, seg.length_m))
    return kappas


def test_general_clothoids_match_quadrature():
    track = TrackGeometry(GENERAL)
    x, y, theta = 0.0, 0.0, 0.0
    for k, (k0, k1, length) in enumerate(general_heading_reference(GENERAL)):
        rate = (k1 - k0) / length
        dx, dy = quad_xy(lambda u: theta + k0 * u + 0.5 * rate * u * u, 0.0, length)
        x, y, theta = x + dx, y + dy, theta + k0 * length + 0.5 * rate * length**2
        s_end = track.segment_start_m[k] + length
        xe, ye = track.position_m(s_end)
        assert abs(xe - x) < POS_TOL_M and abs(ye - y) < POS_TOL_M, f"segment {k}"
        assert abs(track.heading_rad(s_end) - theta) < ANGLE_TOL_RAD, f"segment {k}"
    assert track.curvature_per_m(track.total_length_m) == pytest.approx(0.0, abs=1e-17)
    # points inside the reverse-curve transition, before and after its inflection (u ~ 14.3 m)
    k = 3
    k0, k1, length = general_heading_reference(GENERAL)[k]
    s0 = track.segment_start_m[k]
    xs, ys = track.position_m(s0)
    th0 = track.heading_rad(s0)
    rate = (k1 - k0) / length
    for u in (0.3, 9.7, 17.5):
        dx, dy = quad_xy(lambda v: th0 + k0 * v + 0.5 * rate * v * v, 0.0, u)
        xu, yu = track.position_m(s0 + u)
        assert abs(xu - xs - dx) < POS_TOL_M and abs(yu - ys - dy) < POS_TOL_M


def test_fresnel_and_quadrature_paths_agree():
    # The two internal clothoid evaluations must agree wherever Fresnel is declared accurate,
    # including near the switching threshold (scale ~1e4 m). Round-off there ~1e-12 m.
    u = np.linspace(0.0, 1.0, 7)
    for k0, k1, length in [(0.0, 0.01, 15.0), (0.01, -0.004, 20.0), (-0.0125, -0.004, 18.0),
                           (0.002, 0.00201, 1.0), (0.0, 4e-8, 1.0), (0.01, 0.0101, 1.0)]:
        rate = (k1 - k0) / length
        assert track_module._fresnel_is_accurate(k0, rate, length)
        f = track_module._fresnel_offset(k0, rate, u * length)
        q = track_module._quadrature_offset(k0, k1 - k0, length, u * length)
        assert np.max(np.abs(f - q)) < 1e-11, (k0, k1, length)


@pytest.mark.parametrize("segments", [GENERAL,
                                      TrackGeometry.curve_entry(20.0, 15.0, 100.0, 30.0,
                                                                cant_rad=0.05).segments])
def test_continuity_at_joins(segments):
    track = TrackGeometry(segments)
    for k in range(1, len(segments)):
        join = track.segment_start_m[k]
        before = np.nextafter(join, -np.inf)  # evaluated on segment k-1, one ulp from its end
        # One ulp of s (~1e-14 m) moves the point by ~1e-14 m and the heading by ~1e-16 rad.
        (xa, ya), (xb, yb) = track.position_m(before), track.position_m(join)
        assert math.hypot(xb - xa, yb - ya) < 1e-12, f"position jump at join {k}"
        assert abs(track.heading_rad(join) - track.heading_rad(before)) < 1e-14
        if isinstance(segments[k], Transition) or isinstance(segments[k - 1], Transition):
            assert abs(track.curvature_per_m(join) - track.curvature_per_m(before)) < 1e-15
            assert abs(track.cant_rad(join) - track.cant_rad(before)) < 1e-15


def test_vectorised_equals_scalar():
    track = TrackGeometry(GENERAL)
    s = np.linspace(0.0, track.total_length_m, 97).reshape(97, 1)
    x, y = track.position_m(s)
    h, c, q = track.heading_rad(s), track.curvature_per_m(s), track.cant_rad(s)
    assert x.shape == y.shape == h.shape == c.shape == q.shape == s.shape
    for i, si in enumerate(s[:, 0]):
        xi, yi = track.position_m(float(si))
        assert isinstance(xi, float) and isinstance(track.heading_rad(float(si)), float)
        assert (xi, yi) == (x[i, 0], y[i, 0])
        assert track.heading_rad(si) == h[i, 0]
        assert track.curvature_per_m(si) == c[i, 0]
        assert track.cant_rad(si) == q[i, 0]


def test_total_length(paper_track):
    assert paper_track.total_length_m == STRAIGHT_M + TRANSITION_M + ARC_M
    # the end point is in range; heading there = L_t/(2R) + L_arc/R
    assert paper_track.heading_rad(paper_track.total_length_m) == pytest.approx(
        TRANSITION_M / (2 * RADIUS_M) + ARC_M / RADIUS_M, abs=ANGLE_TOL_RAD)


@pytest.mark.parametrize("s", [-1e-9, STRAIGHT_M + TRANSITION_M + ARC_M + 1e-9,
                               [0.0, 1.0, 1e6], float("nan")])
def test_s_out_of_range_raises(paper_track, s):
    with pytest.raises(ValueError, match=r"s must"):
        paper_track.position_m(s)
    with pytest.raises(ValueError, match=r"s must"):
        paper_track.heading_rad(s)


@pytest.mark.parametrize("make, name", [
    (lambda: Straight(-1.0), "length_m"),
    (lambda: Straight(0.0), "length_m"),
    (lambda: Transition(-15.0), "length_m"),
    (lambda: Arc(0.0, 10.0), "radius_m"),
    (lambda: Arc(-100.0, 10.0), "radius_m"),
    (lambda: Arc(float("inf"), 10.0), "radius_m"),
    (lambda: Arc(100.0, -10.0), "length_m"),
    (lambda: Arc(100.0, 10.0, direction=0), "direction"),
    (lambda: Arc(100.0, 10.0, cant_rad=2.0), "cant_rad"),
    (lambda: TrackGeometry.curve_entry(-1.0, 15.0, 100.0, 50.0), "straight_m"),
    (lambda: TrackGeometry.curve_entry(10.0, -15.0, 100.0, 50.0), "transition_m"),
    (lambda: TrackGeometry.curve_entry(10.0, 15.0, 0.0, 50.0), "radius_m"),
    (lambda: TrackGeometry.curve_entry(10.0, 15.0, 100.0, -50.0), "arc_m"),
    (lambda: TrackGeometry.curve_entry(10.0, 15.0, 100.0, 0.0), "arc_m"),
    (lambda: TrackGeometry(()), "segments"),
    (lambda: TrackGeometry((Transition(5.0), Transition(5.0))), "adjacent Transitions"),
])
def test_invalid_parameters_rejected(make, name):
    with pytest.raises(ValueError, match=name):
        make()


def test_zero_straight_or_transition_omitted():
    track = TrackGeometry.curve_entry(0.0, 0.0, RADIUS_M, ARC_M)
    assert len(track.segments) == 1 and track.total_length_m == ARC_M
    assert track.curvature_per_m(0.0) == 1 / RADIUS_M


def test_segments_are_immutable(paper_track):
    with pytest.raises(AttributeError):
        paper_track.segments[0].length_m = 5.0
    with pytest.raises(ValueError):
        paper_track.segment_start_m[0] = 1.0


# --- smoothed transitions (cosine, Bloss): checked against their definitions, not the code's
# own closed forms: the heading is the numerical integral of the curvature, the position the
# numerical integral of (cos, sin)(heading)

SMOOTH = {"cosine": lambda xi: 0.5 - 0.5 * math.cos(math.pi * xi),
          "bloss": lambda xi: 3 * xi**2 - 2 * xi**3}


@pytest.mark.parametrize("shape", ["cosine", "bloss"])
def test_smoothed_transition_against_its_definition(shape):
    cant, L = 0.1, TRANSITION_M
    track = TrackGeometry.curve_entry(STRAIGHT_M, L, RADIUS_M, ARC_M, cant_rad=cant,
                                      transition_shape=shape)
    f = SMOOTH[shape]
    opts = dict(epsabs=1e-14, epsrel=1e-14, limit=200)

    def heading(u):  # integral of the curvature f(v / L) / R from the transition's start
        return quad(lambda v: f(v / L) / RADIUS_M, 0.0, u, **opts)[0]

    for u in (0.0, 0.7, 5.0, 7.5, 11.3, L):
        s = STRAIGHT_M + u
        assert track.curvature_per_m(s) == pytest.approx(f(u / L) / RADIUS_M, abs=1e-16)
        assert track.cant_rad(s) == pytest.approx(cant * f(u / L), abs=1e-16)
        assert track.heading_rad(s) == pytest.approx(heading(u), abs=ANGLE_TOL_RAD)
        x, y = track.position_m(s)
        dx, dy = quad_xy(heading, 0.0, u)
        assert abs(x - STRAIGHT_M - dx) < POS_TOL_M and abs(y - dy) < POS_TOL_M
    # the point of the shapes: no step in the cant's (and curvature's) slope at either end
    ends = np.array([STRAIGHT_M, STRAIGHT_M + L, np.nextafter(STRAIGHT_M + L, 0.0)])
    assert np.all(np.abs(track.cant_slope_per_m(ends)) < 1e-15)
    # the arc follows on at the curve's own heading: L / (2 R) for every shape (F(1) = 1/2)
    assert track.heading_rad(STRAIGHT_M + L + 10.0) == pytest.approx(
        L / (2 * RADIUS_M) + 10.0 / RADIUS_M, abs=ANGLE_TOL_RAD)


def test_linear_transition_cant_slope_steps_at_its_ends():
    cant, L = 0.1, TRANSITION_M
    track = TrackGeometry.curve_entry(STRAIGHT_M, L, RADIUS_M, ARC_M, cant_rad=cant)
    before, start = np.nextafter(STRAIGHT_M, 0.0), STRAIGHT_M
    assert track.cant_slope_per_m(before) == 0.0
    assert track.cant_slope_per_m(start) == pytest.approx(cant / L, rel=1e-15)


def test_unknown_transition_shape_is_refused():
    with pytest.raises(ValueError, match="shape must be one of linear, cosine, bloss"):
        Transition(15.0, "parabolic")
