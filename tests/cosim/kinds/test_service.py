"""A line in service (cosim/kinds/service.py, cosim/runs/route.py): the route checked at load
with the key that is wrong, the plan against hand arithmetic (stops where the stations are,
run times of the trapezoid, the round trip mirrored, the passengers' mass conserved), a
short trip's stops and air accounts, and the air the brakes and doors take at every stop."""
from __future__ import annotations

import numpy as np
import pytest

from cosim.errors import ScenarioError
from cosim.kinds.service import STOP_DEMAND, outputs
from cosim.load import load_scenario
from cosim.runs.route import RoutePayload, run_phases, run_time_s
from pneumatics.air_supply import normal_density_kg_per_m3
from pneumatics.gas import AIR
from vehicle.speed import PhasedSpeedProfile

from helpers import SCENARIOS

LINE = SCENARIOS / "service_line.yaml"


def test_the_shipped_line_plans_a_round_trip_of_about_30_minutes():
    service = load_scenario(LINE).experiment
    plan = service.plan
    n = len(service.stations)
    assert len(plan.stops) == 2 * n - 1                                    # out, and back without the terminus twice
    assert 25 * 60 < plan.duration_s < 32 * 60
    line_m = service.stations[-1].at_m
    for stop, st in zip(plan.stops[:n], service.stations):
        assert stop.s_m - plan.offset_m == st.at_m and stop.platform_side == st.platform_side
        # the car's centre stands at the station: the speed profile's distance at arrival and
        # at departure (the exact integral of its phases; 1e-9 m of round-off over 9 km)
        for t in (stop.arrive_s, stop.depart_s):
            assert plan.speed.distance(t) == pytest.approx(st.at_m, abs=1e-9)
    for stop, st in zip(plan.stops[n:], reversed(service.stations[:-1])):
        assert stop.s_m - plan.offset_m == pytest.approx(2 * line_m - st.at_m, abs=1e-9)
        assert stop.platform_side != st.platform_side                    # the car runs the other way
        assert stop.direction == "back"


def test_run_phases_are_the_trapezoid_by_hand():
    # 1000 m at 20 m/s, 1 m/s^2 up and 0.8 m/s^2 down: 200 m in 20 s, 250 m in 25 s, 550 m cruising in 27.5 s
    assert run_phases(1000.0, 20.0, 1.0, 0.8) == [(20.0, 20.0, 0.0), (27.5, 20.0, 0.0), (25.0, 0.0, -0.0)]
    # too short to reach the line speed: a triangle to v = sqrt(2 d a b / (a + b)) = 10 m/s for 100 m at 1 m/s^2
    (t_up, v, _), (t_down, _, _) = run_phases(100.0, 20.0, 1.0, 1.0)
    assert v == pytest.approx(10.0) and t_up == pytest.approx(10.0) and t_down == pytest.approx(10.0)
    assert run_time_s(100.0, 20.0, 1.0, 1.0) == pytest.approx(20.0)


def test_jerk_limited_run_phases_by_hand():
    # 1000 m at 20 m/s, 1 m/s^2 up and 0.8 m/s^2 down, jerk 0.5 m/s^3: up, the acceleration ramps in
    # over 2 s (1 m/s), holds 18 s, ramps out over 2 s: 22 s, 220 m (the S is point-symmetric, its
    # mean speed 10 m/s); down, ramps of 1.6 s (0.64 m/s) around 23.4 s held: 26.6 s, 266 m; the
    # cruise 514 m in 25.7 s. In all D/V + V/2A + A/2j + V/2B + B/2j = 50 + 10 + 1 + 12.5 + 0.8 s.
    phases = run_phases(1000.0, 20.0, 1.0, 0.8, 0.5)
    expected = [(2.0, 1.0, 1.0), (18.0, 19.0, 1.0), (2.0, 20.0, 0.0), (25.7, 20.0, 0.0),
                (1.6, 19.36, -0.8), (23.4, 0.64, -0.8), (1.6, 0.0, -0.0)]
    assert np.allclose(phases, expected, rtol=0, atol=1e-12)
    assert run_time_s(1000.0, 20.0, 1.0, 0.8, 0.5) == pytest.approx(74.3, abs=1e-12)
    # short runs: v (v + 1) = 20 m at 1 m/s^2 and 1 m/s^3 gives 4 m/s, each change v / A + A / j = 5 s;
    # 0.25 m never reaches A: 2 v^1.5 = 0.25 m, v = 0.25 m/s, each change 2 sqrt(v / j) = 1 s
    assert run_time_s(20.0, 20.0, 1.0, 1.0, 1.0) == pytest.approx(10.0, abs=1e-9)
    phases = run_phases(0.25, 20.0, 1.0, 1.0, 1.0)
    assert [round(d, 9) for d, _, _ in phases] == [0.5, 0.5, 0.5, 0.5]
    assert max(v for _, v, _ in phases) == pytest.approx(0.25, abs=1e-12)


@pytest.mark.parametrize("distance", [15.0, 80.0, 400.0, 1500.0])
@pytest.mark.parametrize("line_speed, accel, brake", [(19.4, 1.0, 1.0), (25.0, 0.6, 1.3), (12.0, 1.5, 0.8)])
@pytest.mark.parametrize("jerk", [0.3, 1.0, 5.0])
def test_jerk_limited_runs_keep_their_limits_and_land_at_the_stop(distance, line_speed, accel, brake, jerk):
    # the matrix of runs users give (short runs that reach neither the line speed nor the full
    # acceleration, long ones, unequal acceleration and braking, soft and hard jerk): the profile of
    # the phases integrates to the distance (1e-9 relative: bisection and sums' round-off), never
    # exceeds the line speed, the acceleration, the braking or the jerk, and never runs backwards
    phases = run_phases(distance, line_speed, accel, brake, jerk)
    times = np.concatenate([[0.0], np.cumsum([d for d, _, _ in phases])])
    profile = PhasedSpeedProfile(tuple(times), (0.0, *(v for _, v, _ in phases)), (0.0, *(a for _, _, a in phases)))
    assert profile.distance(times[-1]) == pytest.approx(distance, rel=1e-9)
    t = np.linspace(0.0, times[-1], 4001)
    v = profile.speed(t)
    a = np.array([profile.acceleration(x) for x in t])
    assert v.min() >= -1e-12 and v.max() <= line_speed * (1 + 1e-12)
    assert a.max() <= accel * (1 + 1e-12) and a.min() >= -brake * (1 + 1e-12)
    assert np.all(np.abs(np.diff([0.0, *(a for _, _, a in phases)]) / np.diff(times)) <= jerk * (1 + 1e-9))


def test_a_jerk_limited_route_stops_at_its_stations_with_a_continuous_acceleration():
    service = load_scenario(LINE, ["service.jerk_m_per_s3=0.8"]).experiment
    route = service.plan
    assert route.speed.accelerations_m_per_s2 is not None
    for stop in route.stops:                          # where the plan puts it, to round-off over the line
        assert route.offset_m + route.speed.distance(stop.arrive_s) == pytest.approx(stop.s_m, abs=1e-8)
        assert route.speed.speed(stop.arrive_s) == pytest.approx(0.0, abs=1e-12)
    t = np.asarray(route.speed.times_s[1:-1])
    jump = [abs(route.speed.acceleration(x + 1e-7) - route.speed.acceleration(x - 1e-7)) for x in t]
    assert max(jump) <= 0.8 * 2e-7 + 1e-12            # continuous: at most the jerk times the 2e-7 s apart
    # slower than the same line without the limit, by A / 2j + B / 2j = 1.25 s a run (14 runs, round trip)
    plain = load_scenario(LINE).experiment.plan
    runs = len(route.stops) - 1
    assert route.duration_s - plain.duration_s == pytest.approx(runs * 1.25, abs=1e-6)


def test_the_return_runs_the_curves_backwards_turning_the_other_way():
    service = load_scenario(LINE).experiment
    plan, line_m = service.plan, service.stations[-1].at_m
    track = plan.track
    for c in service.curves:
        mid = c.at_m + c.transition_m + 0.5 * c.arc_m                       # the middle of the arc
        out = track.curvature_per_m(plan.offset_m + mid)
        back = track.curvature_per_m(plan.offset_m + 2 * line_m - mid)
        assert out == pytest.approx((1 if c.direction == "left" else -1) / c.radius_m, rel=1e-12)
        assert back == pytest.approx(-out, rel=1e-12)
        assert track.cant_rad(plan.offset_m + 2 * line_m - mid) == pytest.approx(-track.cant_rad(plan.offset_m + mid))


def test_the_passengers_mass_is_conserved_along_the_trip():
    scenario = load_scenario(LINE)
    service = scenario.experiment
    plan, kg = service.plan, service.payload_settings.passenger_mass_kg
    payload = RoutePayload(plan, 14.0, 2.6, 1.7, 1.0)
    on_board = plan.initial_kg
    for stop in plan.stops:
        on_board += stop.boarding_kg - stop.alighting_kg
        assert stop.on_board_kg == pytest.approx(on_board, abs=1e-9)
        # the floor carries what the plan says once the doors closed, and once the boarders spread
        assert payload.total_kg(stop.close_s) == pytest.approx(on_board, abs=1e-9)
        assert [b.mass_kg for b in payload(stop.depart_s + service.spread_s)][1:] == [0.0, 0.0]
    # the shipped line: 29 on board at the start, every flow reversed on the way back
    assert plan.initial_kg == 29 * kg and plan.stops[-1].on_board_kg == pytest.approx(29 * kg)
    # at t = 0 the payload is centred (the car starts at its symmetric static equilibrium)
    assert all(b.y_m == 0.0 or b.mass_kg == 0.0 for b in payload(0.0))
    # while passengers board from a right-hand platform, the load stands right of the centre line
    first = plan.stops[0]
    blocks = payload(0.5 * (first.alighted_s + first.close_s))
    assert first.platform_side == "right" and sum(b.mass_kg * b.y_m for b in blocks) < 0.0


@pytest.mark.parametrize("sets, key, words", [
    (["service.stations[0].at_m=10"], "service.stations[0].at_m", "origin"),
    (["service.stations[2].at_m=800"], "service.stations[2].at_m", "in order"),
    (["service.stations[1].dwell_s=4"], "service.stations[1].dwell_s", "longer dwell"),
    (["service.stations[1].platform_side=up"], "service.stations[1].platform_side", "left or right"),
    (["service.curves[0].at_m=850"], "service.curves[0].at_m", "station 'B'"),
    (["service.curves[1].at_m=200"], "service.curves[1].at_m", "in order"),
    (["service.curves[4].at_m=8900"], "service.curves[4].at_m", "beyond the last station"),
    (["service.curves[0].direction=up"], "service.curves[0].direction", "left or right"),
    (["service.spread_s=500"], "service.spread_s", "shortest run"),
    (["service.stations[0].boarding=300"], "service.stations[0].boarding", "exceptional payload"),
    (["service.stations[1].alighting=200"], "service.stations[1].alighting", "between none"),
    (["payload.events=[{t_s: 1, duration_s: 1, passengers: 3}]"], "payload.events", "stations"),
    (["service.line_speed_m_per_s=70"], None, None),                       # 70 m/s is fast, but a speed
    (["service.line_speed_m_per_s=700"], "service.line_speed_m_per_s", "360 km/h"),
    (["service.stations=[{name: A, at_m: 0}]"], "service.stations", "at least two"),
    (["service.stations[0].colour=red"], "service.stations[0].colour", "unknown key"),
    (["service.air_per_stop={normal_volume_m3: 40}"], "service.air_per_stop.normal_volume_m3", "litres?"),
    (["service.air_per_stop={normal_volume_m3: 0}"], "service.air_per_stop.normal_volume_m3", "(0, 1] m^3"),
    (["service.air_per_stop={normal_volume_m3: -0.04}"], "service.air_per_stop.normal_volume_m3", "(0, 1] m^3"),
    (["service.air_per_stop={normal_volume_m3: .nan}"], "service.air_per_stop.normal_volume_m3", "finite"),
    (["service.air_per_stop={normal_volume_m3: lots}"], "service.air_per_stop.normal_volume_m3", "expected a number"),
    (["service.air_per_stop={dp_off_Pa: 0}"], "service.air_per_stop.dp_off_Pa", "[100, 500000] Pa"),
    (["service.air_per_stop={normal_litres: 40}"], "service.air_per_stop.normal_litres", "unknown key"),
    (["service.air_per_stop=40"], "service.air_per_stop", "expected a mapping"),
    (["service.air_per_stop={}", "circuit.supply={p_Pa: 9.0e+5}", "circuit.compressor=null", "circuit.air_demand=null"],
     "service.air_per_stop", "give circuit.supply a volume"),
    (["service.air_per_stop=null"], None, None),                            # none, as without the key
    (["service.drive={motored_wheelsets: [0, 1]}"], "service.drive.motored_wheelsets[0]", "[1, 4]"),
    (["service.drive={motored_wheelsets: [1, 1]}"], "service.drive.motored_wheelsets[1]", "twice"),
    (["service.drive={motored_wheelsets: []}"], "service.drive.motored_wheelsets", "at least one"),
    (["service.drive={motored_wheelsets: [1.5]}"], "service.drive.motored_wheelsets[0]", "integer"),
    (["service.drive={friction_coefficient: 36}"], "service.drive.friction_coefficient", "(0, 1]"),
    (["service.drive={tracking_frequency_Hz: 0}"], "service.drive.tracking_frequency_Hz", "(0, 5] Hz"),
    (["service.drive={brakes: all}"], "service.drive.brakes", "unknown key"),
    (["service.drive=wheels"], "service.drive", "expected a mapping"),
    (["service.drive={}"], None, None),                                     # through the wheels, defaults
    (["service.gradients=[{at_m: 3, length_m: 300, grade: 0.03}]"], "service.gradients[0].at_m", "level track"),
    (["service.gradients=[{at_m: 100, length_m: 300, grade: 0.03}, {at_m: 300, length_m: 100, grade: 0.01}]"],
     "service.gradients[1].at_m", "in order"),
    (["service.gradients=[{at_m: 8000, length_m: 900, grade: 0.03}]"], "service.gradients[0].length_m", "last station"),
    (["service.gradients=[{at_m: 100, length_m: 60, grade: 0.03}]"], "service.gradients[0].transition_m", "do not fit"),
    (["service.gradients=[{at_m: 100, length_m: 300, grade: 4}]"], "service.gradients[0].grade", "[-0.1, 0.1]"),
    (["service.gradients=[{at_m: 100, length_m: 300, grade: 0}]"], "service.gradients[0].grade", "0"),
    (["service.gradients=[{at_m: 100, length_m: 300}]"], "service.gradients[0].grade", "missing"),
    (["service.gradients=[{at_m: 100, length_m: 300, grade: -0.04}]"], None, None),
    (["service.jerk_m_per_s3=0"], "service.jerk_m_per_s3", "(0, 20] m/s^3"),
    (["service.jerk_m_per_s3=fast"], "service.jerk_m_per_s3", "number"),
    (["service.jerk_m_per_s3=0.8"], None, None),
])
def test_a_wrong_route_is_refused_naming_its_key(sets, key, words):
    if key is None:
        load_scenario(LINE, sets)
        return
    with pytest.raises(ScenarioError) as err:
        load_scenario(LINE, sets)
    assert key in str(err.value) and words in str(err.value), str(err.value)


@pytest.mark.slow
def test_a_short_trip_reports_its_stops_and_closes_its_air_balance(tmp_path):
    """Two stations 200 m apart, 10 passengers board at the first and alight at the second, one
    way, k = 100 W/K: the first stop's floor at arrival is the platform (the reference), the
    floor sinks while they board and rises when they alight; the valves open; the air balance
    closes to the integrator's round-off (the circuit holds every flow as a state)."""
    from cosim.runner import run

    scenario = load_scenario(LINE, ["service.stations=[{name: A, at_m: 0, dwell_s: 12, boarding: 10}, "
                                    "{name: B, at_m: 200, dwell_s: 12, alighting: 10}]", "service.curves=[]",
                                    "service.round_trip=false", "payload.initial={passengers: 0}", "solver.jobs=1"],
                             k_override=[100.0])
    outcome = run(scenario)
    (row,) = outcome.rows
    first, second = outcome.tables["stops"]
    assert first["floor_dz_arrive_m"] == 0.0
    # 700 kg before the valves act sinks the floor at the right-hand doors by at most 16 mm: 9.9 mm
    # on isothermal bellows (4 x 243 / 1.4 kN/m, the softest they get), 1.3 mm on the 5.4 MN/m of
    # primary springs, < 4 mm of roll at the door 1.3 m out (the load 0.65 m right of centre on
    # >= 2 MN m/rad of bellows and anti-roll bars); at least the primary's 1.3 mm
    assert -0.016 < first["floor_dz_min_m"] < -0.0013
    assert second["floor_dz_max_m"] > second["floor_dz_arrive_m"]
    assert row["valve_openings"] >= 1 and row["stops"] == 2
    # 1e-9 kg: the balance's round-off over 50 s of 5 ms steps on ~0.1 kg of air per chamber
    assert abs(row["mass_balance_error_kg"]) < 1e-9
    assert row["air_injected_NL"] == pytest.approx(row["air_injected_kg"] / 1.2923 * 1e3, rel=1e-3)
    payload = outcome.series["service"]["payload_kg"].values.ravel()
    assert payload[0] == 0.0 and payload[-1] == pytest.approx(0.0, abs=1e-9) and max(payload) == pytest.approx(700.0)


ONE_WAY = ["service.curves=[]", "service.round_trip=false", "payload.initial={passengers: 0}"]


def test_without_air_per_stop_the_circuit_and_the_outputs_are_as_before():
    scenario = load_scenario(LINE)
    assert scenario.experiment.air_per_stop is None and scenario.circuit.scheduled_demands == ()
    assert STOP_DEMAND not in scenario.circuit.components()
    assert "air_per_stop_kg" not in [o.name for o in outputs(scenario.experiment)]


def test_the_air_per_stop_is_drawn_over_each_stop_of_the_plan():
    scenario = load_scenario(LINE, ["service.air_per_stop={normal_volume_m3: 0.05}"])
    (name, demand), = scenario.circuit.scheduled_demands
    stops = scenario.experiment.plan.stops
    assert name == STOP_DEMAND and demand.node == "supply" and len(demand.windows) == len(stops) == 19
    for (t_on, t_off, q), stop in zip(demand.windows, stops):                # the first stop too, at t = 0
        assert (t_on, t_off) == (stop.arrive_s, stop.depart_s) and q * (t_off - t_on) == pytest.approx(0.05, rel=1e-14)
    assert scenario.circuit.components()[STOP_DEMAND].normal_flow_m3_per_s == demand.windows[0][2]   # at t = 0
    assert "air_per_stop_kg" in [o.name for o in outputs(scenario.experiment)]


@pytest.fixture(scope="module")
def trip_with_air_per_stop():
    """Three stations 200 m apart, 8 s dwells, one way, k = 0; 50 Nl at every stop beside the
    line's steady 100 Nl/min, the compressor keeping the 200 l reservoir at 8.5-10 bar."""
    from cosim.runner import run

    scenario = load_scenario(LINE, ["service.stations=[{name: A, at_m: 0, dwell_s: 8, boarding: 10}, "
                                    "{name: B, at_m: 200, dwell_s: 8}, {name: C, at_m: 400, dwell_s: 8, alighting: 10}]",
                                    *ONE_WAY, "service.air_per_stop={normal_volume_m3: 0.05}", "solver.jobs=1"],
                             k_override=[0.0])
    return scenario, run(scenario)


@pytest.mark.slow
def test_a_trip_draws_its_air_per_stop_at_the_stops_only(trip_with_air_per_stop):
    scenario, outcome = trip_with_air_per_stop
    (row,) = outcome.rows
    stops = outcome.tables["stops"]
    rho_n = normal_density_kg_per_m3(AIR.R_J_per_kgK)          # DIN 1343: 1.2923 kg/m^3
    # the reservoir never nears the atmosphere (the draw's fade-out below 1.2 bar): every stop
    # draws its full amount at a constant rate, which RK4 integrates exactly, the windows' edges
    # inside the macro-steps (the master switches there); 1e-9: the round-off of ~1e4 steps' sums
    assert len(stops) == 3 and row["air_per_stop_kg"] == pytest.approx(3 * 0.05 * rho_n, rel=1e-9)
    assert row["air_per_stop_NL"] == pytest.approx(150.0, rel=1e-9)
    for stop in stops:
        assert stop["air_per_stop_kg"] == pytest.approx(0.05 * rho_n, rel=1e-9)
    # air_demand_kg: the steady demand's 100 Nl/min over the run and the stops' air
    t = outcome.series["service"]["time"].values
    steady = 1.667e-3 * rho_n * (t[-1] - t[0])
    assert row["air_demand_kg"] == pytest.approx(steady + row["air_per_stop_kg"], rel=1e-9)
    # the timing: flat outside the stops, bit for bit; rising at its constant rate within them
    drawn = outcome.series["service"]["air_per_stop_kg"].values.ravel()
    windows = [(s.arrive_s, s.depart_s) for s in scenario.experiment.plan.stops]
    within = np.array([any(a < t_off and t_on < b for t_on, t_off in windows) for a, b in zip(t, t[1:])])
    assert np.all(np.diff(drawn)[~within] == 0.0) and (~within).sum() > 400       # the two runs between stops
    inside = np.array([any(t_on <= a and b <= t_off for t_on, t_off in windows) for a, b in zip(t, t[1:])])
    assert np.diff(drawn)[inside] == pytest.approx(0.05 * rho_n / 8.0 * np.diff(t)[inside], rel=1e-9)
    # the air balance of the chambers (reservoir, bellows, tanks) with the compressor, the steady
    # demand and the stops' demand: 1e-9 kg, round-off over 75 s of 5 ms steps on ~2 kg of air
    assert abs(row["mass_balance_error_kg"]) < 1e-9
    assert row["compressor_air_kg"] > 0.0


def test_a_service_driven_through_its_wheels_builds_a_contact_car_with_its_torques():
    """``service.drive``: the car runs on the contact, moved by torques (no joint at its centre),
    on the regularised creep a start and a stop need, its track 1 m longer behind the first
    station (a car on its brakes may creep back); without the key, the kinematic car as before."""
    from cosim.kinds.service import WHEEL_DRIVE_MIN_CREEP_SPEED_M_PER_S, WHEEL_DRIVE_TRACK_SLACK_M, make_car

    plain = load_scenario(LINE, ["service.stations=[{name: A, at_m: 0}, {name: B, at_m: 300}]", *ONE_WAY])
    driven = load_scenario(LINE, ["service.stations=[{name: A, at_m: 0}, {name: B, at_m: 300}]", *ONE_WAY,
                                  "service.drive={motored_wheelsets: [2, 3], friction_coefficient: 0.2}"])
    assert plain.experiment.drive is None and make_car(plain).guidance == "kinematic"
    car = make_car(driven)
    assert car.guidance == "contact" and car.model.drive is None and car.hooks.torques is not None
    assert car.hooks.torques.drive.motored_wheelsets == (2, 3)
    assert car.contact_params.friction_coefficient == 0.2
    assert car.contact_params.min_creep_speed_m_per_s == WHEEL_DRIVE_MIN_CREEP_SPEED_M_PER_S
    assert driven.experiment.plan.offset_m == plain.experiment.plan.offset_m + WHEEL_DRIVE_TRACK_SLACK_M
    # the car's centre at the line's origin either way: the stops stand where the stations are
    assert car.start_s_m == driven.experiment.plan.offset_m
    names = [o.name for o in outputs(driven.experiment)]
    assert "adhesion_used" in names and "adhesion_used" not in [o.name for o in outputs(plain.experiment)]


@pytest.mark.slow
@pytest.mark.parametrize("mu, slides", [(0.36, False), (0.08, True)])
def test_a_trip_through_the_wheels_reports_its_adhesion_or_stops_when_they_slide(mu, slides):
    """Two stations 150 m apart at 1 m/s^2, k = 100: on dry rail (mu 0.36) the trip completes and
    the wheelsets use ~0.3 of their adhesion (a / g = 0.10 over mu, plus the load shifted off
    the leading wheelsets); at mu = 0.08 the traction asks more than the rails give: the case
    stops at the start with the wheel slide's diagnosis, and what it computed is kept."""
    from cosim.runner import run

    scenario = load_scenario(LINE, ["service.stations=[{name: A, at_m: 0, dwell_s: 8}, "
                                    "{name: B, at_m: 150, dwell_s: 8}]", *ONE_WAY, "solver.jobs=1",
                                    f"service.drive={{friction_coefficient: {mu}}}"], k_override=[100.0])
    outcome = run(scenario)
    (row,) = outcome.rows
    if not slides:
        assert not outcome.diagnoses and row["stops"] == 2
        # the feed-forward a = 1 m/s^2 of 26.4 t on ~260 kN of wheel load: 0.10 / 0.36 = 0.28;
        # the leading wheelset of each bogie unloaded in traction (~3 %): up to ~0.33
        assert 0.27 < row["adhesion_used_max"] < 0.36
        assert row["longitudinal_force_max_N"] == pytest.approx(26_400 / 4, rel=0.15)
        return
    (diagnosis,) = outcome.diagnoses.values() if isinstance(outcome.diagnoses, dict) else outcome.diagnoses
    assert "wheel slide" in str(diagnosis) and "mu = 0.08" in str(diagnosis)
    # kept: the samples of the first dwell (8 s at 0.1 s), before it slid as it started
    ds = outcome.series["service"]
    kept = ds["time"].values[np.isfinite(ds["adhesion_used"].values).all(axis=tuple(range(1, ds["adhesion_used"].ndim)))]
    assert kept.size >= 80 and kept[-1] >= 8.0 - 1e-9


def test_the_grade_under_the_car_ramps_in_and_out_and_the_way_back_falls():
    """service.gradients: 4 % from 100 m over 400 m with 50 m vertical curves; on the way back (a
    round trip) the same section at 2 L - x with the opposite sign; level elsewhere."""
    scenario = load_scenario(LINE, ["service.gradients=[{at_m: 100, length_m: 400, grade: 0.04}]"])
    plan = scenario.experiment.plan
    grade, L, o = plan.grade, scenario.experiment.stations[-1].at_m, plan.offset_m
    for x, expected in ((0.0, 0.0), (100.0, 0.0), (125.0, 0.02), (150.0, 0.04), (300.0, 0.04), (475.0, 0.02),
                        (500.0, 0.0), (900.0, 0.0)):
        assert grade(o + x) == pytest.approx(expected, abs=1e-15)
        assert grade(o + 2 * L - x) == pytest.approx(-expected, abs=1e-15)
    assert load_scenario(LINE).experiment.plan.grade is None


@pytest.mark.slow
def test_a_car_climbing_a_gradient_shifts_its_load_to_the_rear_bogie():
    """Two stations 700 m apart, 4 % from 150 m over 400 m, no passengers, k = 100, kinematic
    guidance: cruising at 70 km/h in the middle of the climb the carbody's weight component along
    the track, M g sin(theta), loads the rear bogie against the front by 2 M g sin(theta) (h_c -
    h_e) / L, as the hand model of tests/vehicle/test_braking.py (level 0) has it for a car
    accelerating at g sin(theta): within 2 % (measured ~1 % there for the pitch plane's
    deformed geometry, which level 0 leaves out; measured 1.1 % here: 1335 against 1320 N)."""
    import math

    from cosim.runner import run
    from vehicle.params import metro_car_arb_dampers

    scenario = load_scenario(LINE, ["service.stations=[{name: A, at_m: 0, dwell_s: 6}, {name: B, at_m: 700, dwell_s: 6}]",
                                    *ONE_WAY, "service.gradients=[{at_m: 150, length_m: 400, grade: 0.04}]",
                                    "solver.jobs=1", "solver.output_interval_s=0.05"], k_override=[100.0])
    outcome = run(scenario)
    ds = outcome.series["service"].isel(case=0)
    plan = scenario.experiment.plan
    t = ds["time"].values
    x = plan.speed.distance(t)
    middle = np.flatnonzero((x > 330.0) & (x < 370.0))
    assert plan.speed.speed(t[middle]).min() == pytest.approx(70 / 3.6, rel=1e-3)     # cruising there
    Q = ds["wheel_load_N"].transpose("time", "wheel").values[middle]
    front, rear = Q[:, :4].sum(axis=1).mean(), Q[:, 4:].sum(axis=1).mean()
    # level 0: the carbody pushed along x at h_e, where traction rods (k_r at h_r) and the bellows'
    # shear (2 k_s at mid-bellow h_s) share the force as parallel springs
    p = metro_car_arb_dampers()
    rod = p.traction_rod_stiffness_N_per_m / (p.traction_rod_stiffness_N_per_m + 2.0 * p.bellow_shear_stiffness_N_per_m)
    h_e = rod * p.traction_rod_height_m + (1.0 - rod) * 0.5 * (p.airspring_lower_height_m + p.airspring_upper_height_m)
    a_equivalent = p.gravity_m_per_s2 * math.sin(math.atan(0.04))
    shift = 2.0 * p.carbody_mass_kg * a_equivalent * (p.carbody_cog_height_m - h_e) / p.bogie_centre_distance_m
    assert rear - front == pytest.approx(shift, rel=0.02)
