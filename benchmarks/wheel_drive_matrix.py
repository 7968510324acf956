"""A car braked and driven through its wheels (vehicle.car.WheelDrive) over what users give it (not
a test): service and emergency-like rates, dry to slippery rail, two or four motored axles, braking
in a canted curve, line speed. Car alone (linear bellows, as benchmarks/bench_vehicle.py), contact
guidance, ``metro_car_arb_dampers``, 5 ms steps.

    python benchmarks/wheel_drive_matrix.py                 # every row (~3 min on one core)
    python benchmarks/wheel_drive_matrix.py --only base,wet
    python benchmarks/wheel_drive_matrix.py --jerk 1.0      # acceleration ramped at 1 m/s^3

Each row: stand 1 s, accelerate to ``v`` at ``a``, cruise 4 s, brake at ``b`` to a stand, stand 3
s; with a curve, the car brakes in its arc. ``--jerk``: every change of acceleration ramps at it
(the service's S-curves, cosim.runs.route.run_phases); the braking check then averages the
last 2 s of full braking, before it ramps out. Printed: the outcome (``ok``, or the wheel slide or
solver failure that stopped it), the largest share of adhesion a wheelset used (|Fx| / mu N), the
car's largest offset from the profile and where it stopped against where the profile stops it,
the braking creep forces' mean over the last 2 s of braking against M b, fresh Newton Jacobians,
wall time.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from cosim.runs.route import run_phases
from vehicle.car import MetroCar, WheelDrive
from vehicle.errors import WheelSlide
from vehicle.params import ContactParams, metro_car_arb_dampers
from vehicle.speed import PhasedSpeedProfile
from vehicle.track import Arc, Straight, TrackGeometry, Transition

H = 0.005
K_BELLOW = 243e3
BASE = dict(a=1.0, b=1.0, v=15.0, mu=0.36, motored=(1, 2, 3, 4), radius=None, cant=0.0)
#: name -> changes to BASE
ROWS = {
    "base": {},
    "gentle 0.5": dict(a=0.5, b=0.5),
    "brisk 1.3": dict(a=1.3, b=1.3),
    "emergency 1.5": dict(b=1.5),
    "wet mu 0.15": dict(mu=0.15),
    "slippery mu 0.10": dict(mu=0.10),
    "2 motored (1,2)": dict(motored=(1, 2)),
    "2 motored (2,3)": dict(motored=(2, 3)),
    "curve R300 cant 0.06": dict(radius=300.0, cant=0.06),
    "curve R150 cant 0.10": dict(radius=150.0, cant=0.10, v=12.0),
    "line 25 m/s": dict(v=25.0),
}


def profile_of(a, b, v, jerk=None):
    """The row's speed profile (module docstring), the time braking starts and the time the
    full braking ends (the stop without a jerk limit, the start of the ramp-out with one)."""
    phases = run_phases(1e9, v, a, b, jerk)              # a long run: its cruise starts and ends at v, a = 0
    cruise = next(i for i in range(1, len(phases)) if phases[i][1:] == phases[i - 1][1:] == (v, 0.0))
    phases[cruise] = (4.0, v, 0.0)
    times, speeds, accels = [0.0, 1.0], [0.0, 0.0], [0.0, 0.0]
    for duration, speed, accel in phases + [(3.0, 0.0, 0.0)]:
        times.append(times[-1] + duration)
        speeds.append(speed)
        accels.append(accel)
    profile = PhasedSpeedProfile(tuple(times), tuple(speeds), None if jerk is None else tuple(accels))
    full = [i for i, acc in enumerate(accels) if acc == -b]
    brake_end = times[full[-1]] if jerk is not None else times[-2]
    return profile, times, times[cruise + 2], brake_end


def run_row(a, b, v, mu, motored, radius, cant, jerk=None):
    profile, knots, braking_s, brake_end_s = profile_of(a, b, v, jerk)
    stop_s = float(profile.distance(knots[-1]))
    brake_start = float(profile.distance(braking_s))
    if radius is None:
        track = TrackGeometry((Straight(stop_s + 40.0),))
    else:                         # the arc from where the braking starts to beyond the stop
        lead = brake_start + 8.0 - 30.0
        track = TrackGeometry((Straight(lead), Transition(30.0), Arc(radius, stop_s - brake_start + 30.0, 1, cant),
                               Transition(30.0), Straight(40.0)))
    p = metro_car_arb_dampers()
    car = MetroCar(p, track=track, speed_profile=profile, start_s_m=8.0, guidance="contact",
                   drive=WheelDrive(motored_wheelsets=motored),
                   contact=ContactParams(min_creep_speed_m_per_s=0.1, friction_coefficient=mu))
    F0, k = car.static_bellow_forces_N(), np.full(4, K_BELLOW)
    mass = p.carbody_mass_kg + 2 * p.bogie_mass_kg + 4 * p.wheelset_mass_kg
    used, off, brake_fx = 0.0, 0.0, []
    start, outcome = time.perf_counter(), "ok"
    n_end = int(round(knots[-1] / H))
    try:
        for n in range(1, n_end + 1):
            z, _ = car.bellow_crushing()
            car.set_bellow_forces(F0 + k * z, k)
            car.advance(n * H)
            used = max(used, float(car.adhesion_used().max()))
            off = max(off, abs(car.hooks.torques.offset_m))
            if brake_end_s - 2.0 < n * H <= brake_end_s:
                brake_fx.append(car.wheelset_longitudinal_forces_N().sum())
    except (WheelSlide, RuntimeError) as exc:
        outcome = f"{type(exc).__name__}: {str(exc)[:150]}"
    stop_err = car.hooks.torques.offset_m if outcome == "ok" else float("nan")
    newton = np.mean(brake_fx) / (-mass * b) - 1.0 if brake_fx and outcome == "ok" else float("nan")
    return dict(outcome=outcome, adhesion_used_max=used, offset_max_mm=1e3 * off, stop_error_mm=1e3 * stop_err,
                braking_creep_vs_Mb=newton, jacobians=car.jacobian_count, wall_s=time.perf_counter() - start,
                simulated_s=car.t_s)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", help="comma-separated row names")
    ap.add_argument("--jerk", type=float, help="jerk limit [m/s^3] (default: none, the acceleration steps)")
    args = ap.parse_args()
    names = args.only.split(",") if args.only else list(ROWS)
    print("| row | outcome | adhesion used max | offset max [mm] | stop error [mm] | braking ΣFx / (M b) - 1 "
          "| Jacobians | simulated [s] | wall [s] |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for name in names:
        r = run_row(**{**BASE, **ROWS[name]}, jerk=args.jerk)
        print(f"| {name} | {r['outcome']} | {r['adhesion_used_max']:.3f} | {r['offset_max_mm']:.2f} | "
              f"{r['stop_error_mm']:.3f} | {r['braking_creep_vs_Mb']:.1e} | {r['jacobians']} | {r['simulated_s']:.1f} | "
              f"{r['wall_s']:.1f} |", flush=True)


if __name__ == "__main__":
    main()
