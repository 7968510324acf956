"""Real track (canted curves, a flexible track, impossible states): the checks that do not need a
long run. The cant x speed x radius x transition matrix itself is benchmarks/track_matrix.py;
its corners that failed before (balanced and excess cant on the paper's curve) run here."""
from __future__ import annotations

import math

import numpy as np
import pytest

from cosim.limits.watch import StateWatch
from cosim.scenario.model import StateLimits

from helpers import SCENARIOS


class FakeCar:
    """The outputs StateWatch reads, set by hand."""

    def __init__(self, roll=(0.0, 0.0, 0.0), crushing=(0.0,) * 4, loads=(30e3,) * 8):
        self.roll, self.crushing, self.loads = map(np.asarray, (roll, crushing, loads))

    def roll_to_track_rad(self):
        return self.roll

    def airspring_crushing_m(self):
        return self.crushing

    def wheel_loads_N(self):
        return self.loads


H0 = 0.25  # bellow height [m]


def watch(**limits) -> StateWatch:
    return StateWatch(StateLimits(**limits), n_cases=2, bellow_height_m=H0)


def test_a_running_car_is_not_stopped():
    w = watch()
    for t in np.arange(0.0, 1.0, 0.005):
        assert w.car(0, FakeCar(roll=(0.19, 0.09, -0.09), crushing=(0.2, -0.2, 0.0, 0.1)), t) is None
    # one wheel of every wheelset lifted (a twisted track's unloading) is not a derailment
    lifted = FakeCar(loads=(0.0, 60e3) * 4)
    assert all(w.car(0, lifted, t) is None for t in np.arange(0.0, 2.0, 0.005))


@pytest.mark.parametrize("roll, body", [((0.21, 0, 0), "carbody"), ((0, -0.11, 0), "front bogie frame"),
                                        ((0, 0, 0.11), "rear bogie frame")])
def test_an_overturned_body_stops_the_case(roll, body):
    reason = watch().car(0, FakeCar(roll=roll), 3.25)
    assert reason.startswith(f"{body} rolled") and "t = 3.25 s" in reason and "overturned" in reason


def test_a_bellow_crushed_through_stops_the_case():
    reason = watch().car(1, FakeCar(crushing=(0.0, 0.0, 0.26, 0.0)), 2.0)
    assert "airspring RL crushed by 260.0 mm" in reason and "1 x its height (250 mm)" in reason
    assert "extended" in watch().car(1, FakeCar(crushing=(-0.3, 0.0, 0.0, 0.0)), 2.0)


def test_a_wheelset_stops_the_case_only_after_the_lift_time():
    """Both wheels of wheelset 3 off the rails: a bounce shorter than wheelset_lift_s (0.1 s)
    passes, a longer lift stops the case naming when it began; each case has its own timer."""
    w = watch()
    off = np.full(8, 30e3)
    off[4:6] = 0.0
    flying, landed = FakeCar(loads=off), FakeCar()
    assert w.car(0, flying, 1.00) is None
    assert w.car(0, flying, 1.09) is None
    assert w.car(0, landed, 1.10) is None             # landed again: the timer restarts
    assert w.car(0, flying, 1.20) is None
    assert w.car(1, flying, 1.20) is None             # the other case's own timer
    reason = w.car(0, flying, 1.31)
    assert reason.startswith("wheelset 3 (3L, 3R) off the rails since t = 1.2 s") and "derailed" in reason
    assert w.car(1, flying, 1.29) is None


def test_air_outside_physics_stops_its_case_only():
    w = watch()
    T = np.array([[293.0, 293.0], [293.0, 98.8]])
    p = np.array([[4.2e5, 4.2e5], [4.2e5, 0.162e5]])
    reasons = w.air(p, T, ["FL", "FR"], 0.08)
    assert reasons[0] is None
    assert reasons[1].startswith("air in 'FR' at 98.8 K, 0.162 bar absolute at t = 0.08 s")
    hot = w.air(np.array([[4.2e5], [60e5]]), np.array([[293.0], [293.0]]), ["FL", "FR"], 1.0)
    assert "60 bar" in hot[0]


# ---------------------------------------------------------------------------- flexible track
from cosim.limits.criteria import largest_track_twist  # noqa: E402
from cosim.runs.track_run import track_twist_warnings  # noqa: E402
from vehicle.params import VehicleParams as _Params  # noqa: E402
from vehicle.track import TrackGeometry  # noqa: E402

RAIL_BASE_M = 1.5


def _ramp(shape: str, cant: float = 0.1, length: float = 30.0) -> TrackGeometry:
    return TrackGeometry.curve_entry(20.0, length, 300.0, 50.0, cant_rad=cant, transition_shape=shape)


def test_a_linear_ramps_largest_twist_is_its_first_base():
    """Linear ramp c s / L: the cross-level 1.5 sin(c s / L) rises fastest where the cant is
    smallest, so the largest twist over a base b is the first window, 1.5 sin(c b / L) / b, ending
    b after the ramp's start (s = 22 m, a grid point): exact up to rounding."""
    for b in (2.0, 10.0):
        twist, at = largest_track_twist(_ramp("linear").cant_rad, np.arange(0.0, 100.0, 0.05), b, RAIL_BASE_M)
        assert twist == pytest.approx(RAIL_BASE_M * math.sin(0.1 * b / 30.0) / b, rel=1e-12)
        assert at == pytest.approx(20.0 + b)


def test_a_bloss_ramps_largest_twist_is_across_its_middle():
    """Bloss 3 x^2 - 2 x^3 is symmetric about its middle (f(1 - x) = 1 - f(x)); over the window of
    relative length beta = b / L centred there the ramp rises by df = beta (1.5 - beta^2 / 2) (the mean
    of f' = 1.5 - 6 t^2), so the cross-level by 2 cos(c / 2) sin(c df / 2) x 1.5 exactly. The
    largest window sits a little before the middle (the sine flattens the upper half) and the grid is
    0.05 m: both move the maximum by ~2e-6 of itself (against a 0.1 mm grid), hence 1e-5."""
    c, L, b = 0.1, 30.0, 2.0
    beta = b / L
    df = beta * (1.5 - beta ** 2 / 2.0)
    expected = 2.0 * math.cos(c / 2.0) * math.sin(c * df / 2.0) * RAIL_BASE_M / b
    twist, at = largest_track_twist(_ramp("bloss").cant_rad, np.arange(0.0, 100.0, 0.05), b, RAIL_BASE_M)
    assert twist == pytest.approx(expected, rel=1e-5)
    assert at == pytest.approx(20.0 + L / 2.0 + b / 2.0, abs=0.1)


def test_the_twist_counts_in_either_sense():
    """A curve to the right (cant of the other sign) and the ramp down out of a curve twist the
    track as much as the ramp into a curve to the left (the linear ramp's first window, above)."""
    from vehicle.track import Arc, Straight, Transition
    expected = RAIL_BASE_M * math.sin(0.1 * 2.0 / 30.0) / 2.0
    right = TrackGeometry.curve_entry(20.0, 30.0, 300.0, 50.0, cant_rad=0.1, transition_shape="linear", direction=-1)
    exit_only = TrackGeometry((Arc(300.0, 20.0, cant_rad=0.1), Transition(30.0, "linear"), Straight(40.0)))
    for track in (right, exit_only):
        twist, _ = largest_track_twist(track.cant_rad, np.arange(0.0, track.total_length_m, 0.05), 2.0, RAIL_BASE_M)
        assert twist == pytest.approx(expected, rel=1e-12)
    assert len(track_twist_warnings(_ramp("bloss", length=10.0), _Params())) == \
        len(track_twist_warnings(TrackGeometry.curve_entry(20.0, 10.0, 300.0, 50.0, cant_rad=0.1, direction=-1),
                                 _Params())) == 2


def test_a_ramp_steeper_than_en14363s_twist_is_said_and_a_gentle_one_is_not():
    """0.1 rad over 10 m (Bloss): over the 2 m wheelbase the closed form above (beta = 0.2), 22 per
    mille (7 allowed); over the 10 m bogie centre distance the whole ramp, 1.5 sin(0.1) / 10 = 15
    per mille (4 allowed): one warning each. 0.1 rad over 60 m linear (2.5 per mille) and straight
    track raise none."""
    p = _Params()
    beta = 2.0 / 10.0
    df = beta * (1.5 - beta ** 2 / 2.0)
    over_wheelbase = 2.0 * math.cos(0.05) * math.sin(0.1 * df / 2.0) * RAIL_BASE_M / 2.0
    over_bogies = RAIL_BASE_M * math.sin(0.1) / 10.0
    steep = track_twist_warnings(_ramp("bloss", length=10.0), p)
    assert len(steep) == 2
    assert f"{1e3 * over_wheelbase:.3g} per mille over the wheelbase 2a+ (2 m" in steep[0]
    assert "the 7 per mille EN 14363" in steep[0]
    assert f"{1e3 * over_bogies:.3g} per mille over the bogie centre distance 2a* (10 m" in steep[1]
    assert "the 4 per mille" in steep[1]
    assert track_twist_warnings(_ramp("linear", length=60.0), p) == []
    assert track_twist_warnings(_ramp("bloss", cant=0.0), p) == []

from vehicle.car import MetroCar  # noqa: E402 (exudyn: after the pure tests)
from vehicle.params import VehicleParams, slab_track  # noqa: E402

K_BELLOW_N_PER_M = 243e3  # bellow + tank, adiabatic (paper Table 2)


def settle(car, t_end_s, load=None, torque=None, macro_s=5e-3):
    """Advance with the bellows as linear springs about their static force; ``load(t)``,
    ``torque(t)``: the carbody force [N] and torque [N m] (global) for each macro-step."""
    F0, K = car.static_bellow_forces_N(), np.full(4, K_BELLOW_N_PER_M)
    while car.t_s < t_end_s - 1e-9:
        if load is not None:
            car.set_carbody_load(force_N=load(car.t_s + macro_s),
                                 torque_N_m=torque(car.t_s + macro_s) if torque else (0.0, 0.0, 0.0))
        z, _ = car.bellow_crushing()
        car.set_bellow_forces(F0 + K * z, K)
        car.advance(car.t_s + macro_s)


@pytest.mark.parametrize("guidance", ["kinematic", "contact"])
def test_flexible_track_carries_a_load_by_its_own_stiffness(guidance):
    """A standing car on the slab track (preset), then 40 kN pressing its carbody down, 40 kN m
    rolling it and, with contact guidance, 8 kN pushing it sideways: once the load is on, each
    wheelset's track has
    moved by its share over the track's own stiffness, 10 kN / 144.8 MN/m = 69 um down and
    2 kN / 42 MN/m = 48 um sideways; it starts at rest at 0 (its support carries the static
    load). Two implementations of one model: exudyn bodies (kinematic) and the contact law's
    kernel (contact). The load rises smoothly over 6 s, so that the undamped ~1.2 Hz bounce on the
    bellows (linear springs in this harness) is hardly excited: bound 1 %."""
    track = slab_track()
    car = MetroCar(VehicleParams(), guidance=guidance, track_structure=track, carbody_load=True)
    settle(car, 0.2)
    assert np.abs(car.track_deflection()).max() < 1e-9
    Fz, Fy, Mx = 40e3, (8e3 if guidance == "contact" else 0.0), 40e3

    def ramp(t):
        return 0.5 - 0.5 * math.cos(math.pi * min(max(t - 0.2, 0.0) / 6.0, 1.0))

    settle(car, 7.0, lambda t: (0.0, Fy * ramp(t), -Fz * ramp(t)),
           lambda t: (Mx * ramp(t), 0.0, 0.0))
    d = car.track_deflection()
    assert d[:, 1] == pytest.approx(-Fz / 4 / track.vertical_stiffness_N_per_m, rel=0.01)
    if guidance == "contact":
        assert d[:, 0].sum() == pytest.approx(Fy / track.lateral_stiffness_N_per_m, rel=0.01)
        # the rails push the wheelsets back with what the carbody is pushed with
        assert car.wheelset_lateral_forces_N().sum() == pytest.approx(-Fy, rel=0.01)
    # a 40 kN m roll moment (+x: left side up) rolls the car onto its right wheels (with contact
    # guidance against the 8 kN lateral load, which alone leans it on the left ones); the track
    # rolls under the moment of the load difference about its centre
    # (the lateral forces act at rail level, through the roll axis): k_roll roll = -(Q_L - Q_R) b,
    # b the half-spacing of the contact points (contact: 0.753 m, the table's; kinematic: 0.75 m),
    # within 2 % (the contact points move by a few mm across the wheel)
    Q = car.wheel_loads_N()
    b = car.contact_table.contact_half_spacing if guidance == "contact" else car.params.contact_spacing_m / 2
    assert np.all(Q[1::2] - Q[0::2] > 1e3)
    assert track.roll_stiffness_N_m_per_rad * d[:, 2] == pytest.approx(-(Q[0::2] - Q[1::2]) * b, rel=0.02)


# ---------------------------------------------------------------------------- runs
from cosim import cli  # noqa: E402
from cosim.load import load_scenario  # noqa: E402
from cosim.runner import run  # noqa: E402
from cosim.runs.track_run import ramp_roll_rate_step_rad_per_s  # noqa: E402


def canted_curve(guidance, cant, *extra):
    """The paper's curve entry (10 m/s, R 100 m, 15 m transition) with cant, k = inf, valves
    off, 15 s, one process."""
    return load_scenario(SCENARIOS / "curve_entry.yaml",
                         [f"curve.guidance={guidance}", f"curve.cant_rad={cant}", "curve.duration_s=15",
                          "curve.valve_settings=[false]", "solver.jobs=1", *extra], [math.inf])


@pytest.mark.slow
@pytest.mark.parametrize("guidance", ["kinematic", "contact"])
@pytest.mark.parametrize("cant", [0.1016, 0.15])
def test_the_cases_that_failed_run_at_the_shipped_steps(guidance, cant):
    """Balanced (0.1016 rad) and excess cant on the paper's curve: with 0.8 of spectral radius and
    the linear ramp, kinematic guidance diverged and contact guidance derailed (Real track). At
    the defaults (Bloss transition, 0.5) both run to their end, and so does the linear ramp when
    asked for, with a warning naming the step of the rails' roll rate (v c / L: 0.068 rad/s at
    balanced cant). Bounds: ΔQ/Q0's 2 m mean is the twist's quasi-static unloading, below 1
    (no wheel off its rail for 2 m)."""
    for shape in ("bloss", "linear"):
        outcome = run(canted_curve(guidance, cant, f"curve.transition_shape={shape}"))
        assert not outcome.diverged, (shape, outcome.diverged)
        assert 0.3 < outcome.rows[0]["dqq_2m_max"] < 1.0
        warned = [w for w in outcome.warnings if "roll rate" in w]
        assert bool(warned) == (shape == "linear")
    assert ramp_roll_rate_step_rad_per_s(canted_curve(guidance, 0.1016, "curve.transition_shape=linear").experiment) \
        == pytest.approx(0.0677, abs=1e-4)


@pytest.mark.slow
def test_a_capsizing_car_stops_with_a_diagnosis_and_keeps_its_results(tmp_path):
    """54 m/s (km/h typed as m/s) into R 300 m with cant 0.1, kinematic guidance, k = 0, valves
    off: the car overturns. It ran to its end with exit 0 before (roll 2.4 rad, bellow air at
    23 K); now the case stops where a body passes its roll limit, the run exits 1, and what was
    computed up to then is written."""
    out = tmp_path / "capsize"
    code = cli.main(["run", str(SCENARIOS / "curve_entry.yaml"), "--out", str(out), "--quiet", "--k", "0",
                     "--set", "curve.speed_m_per_s=54", "--set", "curve.radius_m=300", "--set", "curve.cant_rad=0.1",
                     "--set", "curve.valve_settings=[false]", "--set", "curve.duration_s=4", "--set", "solver.jobs=1"])
    assert code == 1
    info = (out / "run.json").read_text()
    assert "impossible state" in info and "the car overturned" in info
    series = (out / "timeseries").glob("*.csv")
    rows = sum(1 for _ in open(next(series))) - 1
    assert rows > 10  # the samples before the stop


def test_only_the_rails_push_the_contact_guided_car_across_the_track():
    """Newton's law for the whole car at an instant, in a canted curve (R 100 m, 10 m/s, balanced
    cant 0.1016 rad on a Bloss transition; car alone): the bodies' sum of m a equals gravity plus
    the contact forces plus the drive's reaction along the track tangent at the car centre, and
    nothing else: no joint pushes the car across the track. Bound: 1e-6 of the car's weight
    (Newton's tolerance)."""
    from exudyn import OutputVariableType as _OUT

    from vehicle.track import TrackGeometry
    p = VehicleParams()
    track = TrackGeometry.curve_entry(20.0, 15.0, 100.0, 150.0, cant_rad=0.1016, transition_shape="bloss")
    car = MetroCar(p, track=track, speed_m_per_s=10.0, guidance="contact")
    settle(car, 6.0)
    mbs = car.mbs
    bodies = [car._carbody, *car._bogies, *car._wheelsets]
    masses = [p.carbody_mass_kg] + [p.bogie_mass_kg] * 2 + [p.wheelset_mass_kg] * 4
    ma = sum(m * np.asarray(mbs.GetObjectOutputBody(b, _OUT.Acceleration)) for b, m in zip(bodies, masses))
    sd = mbs.systemData
    Q = car._wr.forces(sd.GetODE2Coordinates()[car._wr_index], sd.GetODE2Coordinates_t()[car._wr_index])
    contact = sum(Q[7 * i:7 * i + 3] for i in range(4))
    drive = np.asarray(mbs.GetObjectOutput(car._drive, _OUT.ForceLocal))  # along the tangent
    psi = track.heading_rad(car.s_m)
    drive_global = drive[0] * np.array([math.cos(psi), math.sin(psi), 0.0])
    M = sum(masses)
    gravity = np.array([0.0, 0.0, -M * p.gravity_m_per_s2])
    # exudyn reports the joint's force on its first marker (ground): the car gets the opposite
    assert np.abs(ma - (gravity + contact - drive_global)).max() < 1e-6 * M * p.gravity_m_per_s2
    # the balance above has no joint force but the drive's: the wheelsets' joints hold a couple
    # (their pitch), nothing else


def test_a_wheelset_off_the_contact_table_stops_the_case_as_derailed():
    """0.15 rad of cant over a 10 m transition at 10 m/s into R 300 m with contact guidance: a
    twist of 34 per mille at the Bloss curve's steepest, five times EN 14363's largest limit.
    A wheelset climbs its flange and leaves the contact table: the case stops as an impossible
    state, "derailed", with its place and time (benchmarks/track_matrix.py: at 1.5 s)."""
    s = load_scenario(SCENARIOS / "curve_entry.yaml",
                      ["curve.guidance=contact", "curve.cant_rad=0.15", "curve.transition_m=10",
                       "curve.radius_m=300", "curve.transition_shape=bloss", "curve.duration_s=3",
                       "curve.valve_settings=[false]", "solver.jobs=1"], [math.inf])
    outcome = run(s)
    assert outcome.diverged and "impossible state: derailed: a wheelset left the contact table" in outcome.diverged
