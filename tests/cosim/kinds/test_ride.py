"""The ride kind composes the track run (cosim.runs): each speed's track, the record's start and
the scenario of one speed; and a track run on the straight alone (``radius_m: null``)."""
from __future__ import annotations

import math

import pytest

from cosim.kinds import ride
from cosim.kinds.curve_entry import KIND as CURVE
from cosim.load import load_scenario
from cosim.runs.track_run import car_centre_s_m
from cosim.runs.track_spec import CurveTest
from vehicle.track import Arc, Straight

from helpers import SCENARIOS


@pytest.fixture(scope="module")
def scenario():
    return load_scenario(SCENARIOS / "ride_comfort.yaml")


def test_a_straight_ride_runs_on_the_straight_alone_and_never_reaches_its_end(scenario):
    test, vehicle = scenario.experiment, scenario.vehicle
    car = vehicle.bogie_centre_distance_m + vehicle.wheelbase_m
    for v in test.speeds_m_per_s:
        curve, start = ride.curve_at(test, v, vehicle)
        track = curve.track()
        assert [type(s) for s in track.segments] == [Straight] and start == test.settle_s
        # the front wheelset (the rear one at v t, the car's length ahead) at the end of the run
        # is the margin and the tail short of the track's end
        front_end = v * curve.duration_s + car
        assert track.total_length_m - front_end == pytest.approx(ride.TRACK_MARGIN_M + ride.STRAIGHT_TAIL_M)


def test_a_ride_in_a_curve_records_with_the_whole_car_in_the_arc(scenario):
    test = scenario.experiment.__class__(speeds_m_per_s=(5.0, 20.0), radius_m=300.0, cant_rad=0.05, transition_m=40.0,
                                         record_s=10.0, settle_s=1.0)
    for v in test.speeds_m_per_s:
        curve, start = ride.curve_at(test, v, scenario.vehicle)
        arc_start = curve.straight_m + curve.transition_m
        assert isinstance(curve.track().segments[-1], Arc)
        # the rear wheelset (at s = v t) is in the arc when the record starts, and the front one
        # is still on the track when it ends
        assert v * start >= arc_start - 1e-9
        assert v * curve.duration_s + scenario.vehicle.bogie_centre_distance_m + scenario.vehicle.wheelbase_m \
            < curve.track().total_length_m
    assert ride.duration_s(test) == pytest.approx(max(test.settle_s, (20.0 + 40.0) / 5.0) + test.record_s)
    assert ride.shortest_duration_s(test) == pytest.approx(max(test.settle_s, (20.0 + 40.0) / 20.0) + test.record_s)


def test_the_scenario_of_one_speed_stays_a_ride(scenario):
    # it used to be relabelled a curve entry for the machinery; the track run reads only its
    # experiment, so the ride's scenario keeps its kind and section
    curve, _ = ride.curve_at(scenario.experiment, 10.0, scenario.vehicle)
    one = ride._speed_scenario(scenario, curve)
    assert (one.kind, one.section, one.experiment) == ("ride", "ride", curve)
    t = [0.0, 1.0]
    half = (scenario.vehicle.bogie_centre_distance_m + scenario.vehicle.wheelbase_m) / 2
    # the track run reads the speed of this speed's curve: the car centre moves 10 m in 1 s
    assert list(car_centre_s_m(one, t)) == pytest.approx([half, 10.0 + half], rel=1e-12)


def test_a_curve_entry_on_the_straight_alone():
    curve = CurveTest(radius_m=None, straight_m=200.0, duration_s=5.0, speed_m_per_s=20.0)
    assert curve.length_m == 200.0 and [type(s) for s in curve.track().segments] == [Straight]
    # no curve: its quasi-static EN 14363 values cannot be checked, and the message says why
    assert CURVE.zones(curve) and not any("R<" in z for z in CURVE.zones(curve))
    why = CURVE.refuse_check("Y_2m_p50", curve)
    assert why and "200 m straight alone" in why
    assert math.isclose(CurveTest(straight_m=20.0, transition_m=15.0, arc_m=300.0).length_m, 335.0)
