"""Steady braking and accelerating through the wheels against quasi-static hand models.

The contact car (``guidance="contact"``, ``drive=WheelDrive()``, vehicle/car/wheel_drive.py; its
code is not read here, only its module doc and the torques it applies) on straight track, moved
by torques on its wheelsets' spin coordinates alone: stand 1 s, accelerate at A = 1.0 m/s^2 for
14 s, brake at A for 14 s to a stop, stand 1 s, the bellows driven as tests/vehicle/test_braking.py
does (F = F0 + k z, k = 243 kN/m, set every 5 ms), ``metro_car_arb_dampers()``, the contact's
creep law viscous below 0.1 m/s (as tests/vehicle/test_wheel_drive.py). Averaged: the last 4 s
of accelerating, and braking the 4 s that end 1 s before the stop (5 to 1 m/s, clear of the
creep law's regularisation). The step in acceleration rings for ~10 s (the carbody's surge on
the rods and the driver's 0.5 Hz loop, ~e^-1.4 per second); in the windows the wheel loads'
std is 3e-4 .. 1.4e-3 N (checked). The loads "at rest" are those at the end of the first
standing second. Signs and symbols: test_braking's module doc (x forward, theta > 0 nose down,
dQ_j the change of wheelset j's load from rest, 1..4 from the front; a < 0 braking).

What carries the longitudinal load (vehicle/car/build.py, vehicle/wheelrail/track_contact.py and
contact_law.py, read for where each force acts): the wheelsets are free along the track. Each
wheel's creep force F acts at its contact point, r_c below the axle; in the model the wheelset
body takes F at its centre (its translation) and the spin coordinate its moment about the axle,
-r_c F. The body's pitch is held by a joint to the ground, a pure moment, with no vertical or
longitudinal reaction. Torque T_j drives spin j; its reaction -T_j is a pure moment on the bogie
frame that carries the wheelset. From the wheelset on the load goes as in the kinematic car:
primary at axle height, traction rod and bellows' shear to the carbody.

The wheelsets (:class:`Wheels`, read from the car): r_c = 0.419916 m, the contact law's rolling
radius at the centred wheelset, is the creep forces' lever. It is the smoothed table's r(0),
10 um above the raw table's r0 = 0.419906 m (``track_contact.r0``), which the driver's
T = r0 F uses. r_w = 0.4198622 m is ``car.static.wheelset_z_m``, r0 plus the law's static rise.
delta0 = 44.27 um is the contacts' overlap at rest (dz0(0) + r0 - r_w; the Hertz law acts along
the normal at 0.025 rad; the kinematic car's r_w is 0.42 m less 44.24 um). I_s = 49 kg m^2.

Level 0 (closed form, :func:`level_0_wheels`)
--------------------------------------------
Rigid geometry, quasi-static, d'Alembert forces at the centres of gravity, as test_braking's:

* Newton along the track: the creep forces carry the translating mass, sum_j F_j = M_tot a
  (M_tot = 24 000 kg: carbody, frames, wheelset bodies; the spin nodes carry spin inertia only).
* Spin j, rolling (creepage left out): I_s a / r_c = T_j - r_c F_j. With the drive's shares s_j
  (1/4 each braking; traction 1/n on the n motored wheelsets), T_j = s_j r_c M_e a with
  M_e = M_tot + 4 I_s / r_c^2 = 25 112 kg, and F_j = T_j / r_c - I_s a / r_c^2.
* Carbody: as the kinematic car's. Bogie i pushes it with R_i = F_lead + F_trail - (m_b + 2 m_w) a
  (M a / 2 when all four are driven equally) through rod and shear at h_e. So
  dV_1 = -M a (h_c - h_e) / L and theta = dV_1 (1/k_v + 1/(2 k_pz)) / L: the carbody's balance
  does not see where the wheels take the force.
* Bogie frame i, moments about its CoG: the primary's longitudinal force at axle height r_w (the
  creep force reaches the body at the wheelset centre), the bellows' vertical force at its
  centre, and the torque reactions, pure moments:
      dN_i = [R_i (r_w - h_e) + m_b a (r_w - h_b) - T_lead - T_trail] / w,
  the kinematic car's dN less (T_lead + T_trail) / w: the lever of the rail-level forces.
* dQ_1 = dV_1/2 + dN_1, dQ_2 = dV_1/2 - dN_1, dQ_3 = -dV_1/2 + dN_2, dQ_4 = -dV_1/2 - dN_2.

At a = -1 m/s^2: T_j = -2636.2 N m, F_j = -6000 N, dV_1 = 1683.1 N, dN = 554.2 + 2636.2 =
3190.2 N, dQ = (4031.8, -2348.7, 2348.7, -4031.8) N, theta = 0.9005 mrad.

Level 0 against the model
-------------------------
Per wheelset level 0 agrees within 1.17 % (asserted, 2 %). The pitch and the bogies' transfer
dV_1 = dQ_1 + dQ_2 it misses by 2.14 % and 2.13 %: beyond the issue's 2 %, so not asserted on
this car (the kinematic car: 1.05 %). The torque reactions pitch each frame by dN / (k_pz w) =
2.35 mrad (the kinematic car's 0.43 mrad). Level 0 keeps every body in its static geometry, and
(A) and (C) of test_braking's doc grow with the frames' pitch. Level 1 reproduces the model (below),
so the physics was switched off there, one piece at a time (braking; level 0's miss on the
pitch): as is 2.14 %; g / 10 (A) 0.88 %; bellows 100 x stiff (B) 1.86 %; shear 1 kN/m (C)
1.43 %; all three 0.23 %; the primary 10 x stiffer vertically (the frames pitch a tenth) 0.89 %,
the kinematic car with that primary 0.78 %. The last is run in the model too:
:func:`test_level_0_holds_when_the_frames_do_not_pitch` (0.89 %, 0.88 %, per wheelset 1.6 %).
Level 0 misses by its rigid geometry; the model puts no force elsewhere.

Level 1 (test_braking's :func:`level_1` with :class:`ThroughWheels`; :func:`level_1_wheels`)
-------------------------------------------------------------------------------------------
The deformed-geometry equilibrium of test_braking, its connectors written as the model has them,
with the wheelsets free along x (4 more unknowns; the mean of their x fixed, one x equation
redundant), pushed at their centres by the creep forces, the frames taking the pure moments -T_j,
each wheelset's contacts carrying 2 Q0 ((delta0 - Z) / delta0)^1.5 at a heave Z. Two sets of
forces:

* the car's torques (``car.hooks.torques.torques_N_m``) and creep forces (``contact_state()``,
  scaled to sum exactly M_tot a): the model to 3.8e-7 (pitch) and 1.6e-7 (wheel loads) in every
  run. Every force is where the hand derivation puts it.
* the hand's: within 1.6e-4 (wheel loads), 3.8e-6 (pitch), because the car's torques exceed the
  hand's (below).

Level 1 showed one more piece of exudyn, found here: an intrinsic connector's deflection is the
translation of the SE(3) logarithm of the markers' relative pose. In the plane that is the
mid-frame components times (phi/2) / sin(phi/2), phi the two bodies' relative pitch. On a 0.25 m
bellow with the front frame driven alone (phi = 3.8 mrad) it adds 0.15 um, 0.03 N. Without it
level 1 missed the pitch by 1.6e-5 there; with it, 3.8e-7. test_braking's level 1 has it since:
3e-10 on the pitch instead of 4e-9.

The torques
-----------
The car's torques exceed the hand's by 0.372 N m per wheelset in both phases (1.4e-4 of T). The
spin's balance, T - r_c F - I_s a / r_c, leaves 0.34 .. 0.40 N m per wheelset (0.35 .. 0.43 with
the front bogie driven alone), more on the more loaded wheelsets. It is the rails' resistance to
rolling: the spin creep moment about the contact normal, tilted by the contact angle, has a
component about the axle. With f23 = f33 = 0 the residue falls to 0.037 N m. That is what the
creepage adds to the spin's acceleration:
I_s a |xi| / r_c, 0.039 N m from Kalker and Shen-Hedrick-Elkins by hand, measured within 4.2 %
(:func:`test_without_spin_creep_the_torques_need_only_the_creepage`). With r0 as the lever, the
residue would carry an odd part of +-0.06 N m, (r_c - r0) F. The driver's feed-forward
(T = r0 F) is 10 um of lever, 2.4e-5 of T, short of the law's. Its feedback takes that up, with
the resistance (1.5 N m over the car, ~3.5 N along the track).

Hand against model (a = +-1 m/s^2; pitch [mrad], dQ [N], creep sum [N]; in parentheses the
model's relative difference, pitch and the largest of the dQ):

    braking            pitch     dQ_1     dQ_2     dQ_3     dQ_4   creep sum
    model             0.91979   4040.1  -2321.2   2340.3  -4059.2  -24000.0004
    level 0           0.90053   4031.8  -2348.7   2348.7  -4031.8  -24000
      model off by     2.14 %   0.21 %   1.17 %   0.36 %   0.68 %   1.6e-8
    level 1 (hand)    0.91979   4040.4  -2321.5   2340.6  -4059.6   (1.3e-6, <= 1.6e-4)
    level 1 (car's)            (2.2e-7, <= 1.3e-7)
    kinematic car     0.90997   1429.8    270.7   -252.9  -1447.7
    accelerating
    model            -0.91980  -4059.9   2341.0  -2321.9   4040.8   24000.0068
    level 0          -0.90053  -4031.8   2348.7  -2348.7   4031.8   24000
      model off by     2.14 %   0.70 %   0.33 %   1.14 %   0.22 %   2.8e-7
    level 1 (hand)   -0.91979  -4059.6   2340.7  -2321.5   4040.4   (1.5e-6, <= 1.6e-4)
    level 1 (car's)            (2.0e-8, <= 9.0e-9)
    kinematic car    -0.90997  -1447.7   -252.9    270.7   1429.8

(the kinematic car: test_braking's level 1, which reproduces that car to 9e-9.) Accelerating is
braking mirrored (wheelsets 4..1 read 1..4, within 0.7 N), not negated: the 19 N between the
front and the rear bogie's transfer is even in a ((B) of test_braking's doc).

Against the kinematic car
-------------------------
The issue's "small load transfer between the two wheelsets that the axle-height lever adds" is
not small. The forces at rail level and the torque reactions move load within each bogie by
(T_lead + T_trail) / w = 2636 N at 1 m/s^2, 4.5 % of a wheelset's static 58.9 kN (measured
+2601 N front, +2602 N rear; the frames' pitch takes 1.3 %). The transfer within a bogie,
3181 .. 3200 N, is then 5.4 times the kinematic car's 580 .. 597 N, and the trailing wheelset of
each bogie goes from loaded (+271 N braking) to unloaded (-2321 N). Between the bogies little
changes: the carbody's balance does not see the wheels, and the frames' pitch adds 18.3 N to
dV_1 and to the carbody's pitch (both +1.08 %, :func:`test_against_the_kinematic_car`).

Traction on the front bogie alone (``motored_wheelsets=(1, 2)``,
:func:`test_traction_on_the_front_bogie`): the front frame takes both reactions (dN_1 = 6405 N,
level 0 within 0.2 %). The rear takes none (dN_2 = -5.6 N). Its wheelsets are braked by their
creep forces (-278.7 N), which spin them up. Level 1 agrees to 3.8e-7 with the car's forces; a
reaction on the wrong frame would move dQ_3, dQ_4 by ~2.6 kN.
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np
import pytest
from test_braking import (
    HAND_REL_TOL,
    K_BELLOW_N_PER_M,
    MACRO_S,
    ThroughWheels,
    effective_height,
    hand_symbols,
    level_0,
    level_1,
)

A_M_PER_S2 = 1.0        #: acceleration and deceleration [m/s^2]
PHASE_S = 14.0          #: duration of each phase [s]
STAND_S = 1.0           #: standing before and after [s]
AVERAGE_S = 4.0         #: averaged at the end of each phase [s]
STOP_MARGIN_S = 1.0     #: the braking window ends this long before the stop (above 1 m/s) [s]
MIN_CREEP_SPEED_M_PER_S = 0.1   #: as tests/vehicle/test_wheel_drive.py
ALL_WHEELSETS = (1, 2, 3, 4)


@dataclasses.dataclass(frozen=True)
class Wheels:
    """The contact car's wheelsets as the hand models need them, read from the car (module doc,
    "The wheelsets"): rc the contact law's rolling radius at the centred wheelset (the creep
    forces' lever about the axle), rw the wheelset centre height at rest, delta0 the contacts'
    vertical overlap there, Is the spin inertia."""

    rc: float
    rw: float
    delta0: float
    Is: float

    @classmethod
    def of(cls, car) -> Wheels:
        law = car.contact.track_contact
        centred = law.table.geometry(0.0)
        rw = float(car.static.wheelset_z_m)
        return cls(float(centred["r_L"]), rw, float(centred["dz0"]) + float(law.r0) - rw,
                   float(car.params.wheelset_inertia_yy_kg_m2))


def shares(a: float, motored=ALL_WHEELSETS) -> np.ndarray:
    """(4,) each wheelset's share of the drive's force: traction (a >= 0) on the motored
    wheelsets equally, braking on all four equally."""
    on = ALL_WHEELSETS if a < 0.0 else motored
    return np.array([1.0 / len(on) if j in on else 0.0 for j in ALL_WHEELSETS])


def hand_torques(p, a: float, wheels: Wheels, motored=ALL_WHEELSETS) -> tuple[np.ndarray, np.ndarray]:
    """The torques T (4,) [N m] and the creep forces (4,) [N] on the wheelsets in steady
    acceleration ``a`` (module doc, "Level 0"): T_j = s_j r_c M_e a, F_j = T_j / r_c - I_s a / r_c^2."""
    rc = wheels.rc
    M_e = hand_symbols(p)["M_tot"] + 4.0 * wheels.Is / rc ** 2
    T = shares(a, motored) * rc * M_e * a
    return T, T / rc - wheels.Is * a / rc ** 2


def level_0_wheels(p, a: float, wheels: Wheels, motored=ALL_WHEELSETS, k_bellow: float = K_BELLOW_N_PER_M) -> dict:
    """Level 0 of the car moved through its wheels (module doc): carbody pitch theta and bogie
    transfer dV_1 as the kinematic car's level 0 (the carbody's balance), per bogie the transfer
    between its wheelsets dN_i with the creep forces C_i and the torques' reactions on the frame,
    and dQ (4,), all at acceleration ``a``; also the hand's torques (4,) and creep forces (4,)."""
    s, l0 = hand_symbols(p, k_bellow), level_0(p, a, k_bellow)
    he, rw, mb, mw = effective_height(s), wheels.rw, s["mb"], s["mw"]
    T, creep = hand_torques(p, a, wheels, motored)
    dN = []
    for i in range(2):
        R = creep[2 * i] + creep[2 * i + 1] - (mb + 2.0 * mw) * a     # what the bogie pushes the carbody with
        dN.append((R * (rw - he) + mb * a * (rw - s["hb"]) - T[2 * i] - T[2 * i + 1]) / s["w"])
    dV1 = l0["dV1"]
    dQ = np.array([dV1 / 2 + dN[0], dV1 / 2 - dN[0], -dV1 / 2 + dN[1], -dV1 / 2 - dN[1]])
    return dict(theta=l0["theta"], dV1=dV1, dN=np.array(dN), dQ=dQ, torques=T, creep_N=creep)


def level_1_wheels(p, a: float, wheels: Wheels, motored=ALL_WHEELSETS, torques=None, creep_N=None,
                   k_bellow: float = K_BELLOW_N_PER_M) -> dict:
    """Level 1 of the car moved through its wheels (test_braking's :func:`level_1` with
    :class:`ThroughWheels`): the creep forces of :func:`hand_torques` on the wheelsets, the
    torques' reactions -T_j on the frames. ``torques`` and ``creep_N`` (4,) given: those instead
    of the hand's (the car's: what the hand model leaves out of them set apart from where they
    act); the creep forces then scaled to sum M_tot a exactly (level 1 has no solution else; the
    car's sum is M_tot a to 3e-7, :func:`test_newton_through_the_wheels`)."""
    T, creep = hand_torques(p, a, wheels, motored)
    if torques is not None:
        T = np.asarray(torques, float)
    if creep_N is not None:
        creep = np.asarray(creep_N, float) * (hand_symbols(p, k_bellow)["M_tot"] * a / np.sum(creep_N))
    through = ThroughWheels(wheels.rw, wheels.delta0, tuple(creep), tuple(-T))
    return level_1(p, a, k_bellow, wheels=through)


def run_profile(p, a: float = A_M_PER_S2, brake: bool = True, motored=ALL_WHEELSETS, contact=None) -> dict:
    """Drive the contact car through its wheels: stand / accelerate (/ brake to a stop / stand);
    per phase ("accel", "brake") the averages over its window: pitch (body angle and floor
    heights), dQ (4,), the creep forces per wheelset (4,), the torques (4,), the traction rods;
    the std of the wheel loads there; and the car's :class:`Wheels`."""
    import exudyn as exu

    from vehicle.car import MetroCar, WheelDrive
    from vehicle.params import ContactParams
    from vehicle.speed import PhasedSpeedProfile
    from vehicle.track import Straight, TrackGeometry

    out_t = exu.OutputVariableType
    t1, t2, t3 = STAND_S, STAND_S + PHASE_S, STAND_S + 2 * PHASE_S
    v = a * PHASE_S
    if brake:
        profile = PhasedSpeedProfile((0.0, t1, t2, t3, t3 + STAND_S), (0.0, 0.0, v, 0.0, 0.0))
        windows = {"accel": (t2 - AVERAGE_S, t2), "brake": (t3 - STOP_MARGIN_S - AVERAGE_S, t3 - STOP_MARGIN_S)}
        t_end = t3 + STAND_S
    else:
        profile = PhasedSpeedProfile((0.0, t1, t2), (0.0, 0.0, v))
        windows = {"accel": (t2 - AVERAGE_S, t2)}
        t_end = t2
    contact = contact or ContactParams(min_creep_speed_m_per_s=MIN_CREEP_SPEED_M_PER_S)
    car = MetroCar(p, track=TrackGeometry((Straight(a * PHASE_S ** 2 + 60.0),)), speed_profile=profile,
                   start_s_m=8.0, guidance="contact", drive=WheelDrive(motored_wheelsets=tuple(motored)),
                   contact=contact)
    mbs = car.mbs
    F0, k = car.static_bellow_forces_N(), np.full(4, K_BELLOW_N_PER_M)
    rows = {name: [] for name in windows}
    Q_rest = None
    start = time.perf_counter()
    for n in range(1, int(round(t_end / MACRO_S)) + 1):
        z, _ = car.bellow_crushing()
        car.set_bellow_forces(F0 + k * z, k)
        t = n * MACRO_S
        car.advance(t)
        if abs(t - t1) < 1e-9:
            Q_rest = car.wheel_loads_N()
        for name, (lo, hi) in windows.items():
            if lo + 1e-9 < t < hi + 1e-9:
                floor = car.floor_heights_m([[5.0, 0.0], [-5.0, 0.0]])
                rows[name].append([
                    mbs.GetObjectOutputBody(car.model.carbody, out_t.Rotation)[1],
                    (floor[1] - floor[0]) / 10.0,
                    *car.traction_rod_forces_N(), *car.hooks.torques.torques_N_m,
                    *car.outputs.contact_state().force_track_N[:, 0], *car.wheel_loads_N()])
    result, wheels = {"wall_s": time.perf_counter() - start}, Wheels.of(car)
    for name, r in rows.items():
        r = np.array(r)
        mean = r.mean(axis=0)
        result[name] = dict(wheels=wheels, theta_body=mean[0], theta_floor=mean[1], rods_N=mean[2:4], torques=mean[4:8],
                            creep_N=mean[8:16].reshape(4, 2).sum(axis=1),
                            dQ=(mean[16:24] - Q_rest).reshape(4, 2).sum(axis=1), Q_std_N=r[:, 16:24].std(axis=0).max())
    return result


PHASES = {"accel": A_M_PER_S2, "brake": -A_M_PER_S2}
# Level 1 given the car's own torques and creep forces (what the hand leaves out of them set
# apart): the model's statics to its solver tolerance (Newton's 1e-6 relative with contact
# guidance; measured at most 1.6e-7 on the wheel loads, 3.8e-7 on the pitch, 7.5e-7 on the rods
# over the four runs); 1e-5 as test_braking, ~20 x margin, still catching a bellow force off by
# 0.03 N (the 0.15 um of exudyn's SE(3)-logarithm deflection, module doc: 1.6e-5 on the pitch)
LEVEL_1_REL_TOL = 1e-5
# Level 1 with the hand's torques: the car's exceed them by the rolling resistance of the spin
# creep and the creepage's share of the spin acceleration, <= RESISTANCE_N_M per wheelset, whose
# reactions move the within-bogie transfer by <= 1 N: 4.3e-4 of the smallest |dQ| compared
# (2321 N; measured 1.6e-4 on dQ_2, dQ_3, 3.8e-6 on the pitch)
LEVEL_1_HAND_REL_TOL = 5e-4
# the moment [N m] per wheelset that the rails' rolling resistance takes from the spin (measured
# 0.34 .. 0.40 with spin creep, 0.038 without: module doc, "The torques")
RESISTANCE_N_M = 1.0
# Newton along the track: every body accelerates at a in the window (the transients have decayed
# to std 1e-3 N in the wheel loads); the creep forces sum to M_tot a to the solver tolerance
# (measured 2.8e-7 relative at most): 1e-5
NEWTON_REL_TOL = 1e-5


@pytest.fixture(scope="module")
def car_params():
    from vehicle.params import metro_car_arb_dampers

    return metro_car_arb_dampers()


@pytest.fixture(scope="module")
def steady(car_params):
    return run_profile(car_params)


@pytest.fixture(scope="module")
def kinematic(car_params):
    """The kinematic car's level 1 per phase, which test_braking asserts reproduces that car (to
    9e-9 on the wheel loads): the comparison without another run."""
    return {phase: level_1(car_params, a) for phase, a in PHASES.items()}


def _rel(model, hand):
    return np.abs(np.asarray(model) - np.asarray(hand)) / np.abs(np.asarray(hand))


def _level_1_as_the_car(p, a, m, motored=ALL_WHEELSETS):
    return level_1_wheels(p, a, m["wheels"], motored, torques=m["torques"], creep_N=m["creep_N"])


@pytest.mark.slow
@pytest.mark.parametrize("phase", list(PHASES))
def test_steady_state_reached(steady, phase):
    # the wheel loads stand still over the averaging window (std 3.5e-4 N accelerating, 1.4e-3 N
    # braking measured): 1e-2 N is 4e-6 of the smallest transfer compared (2321 N)
    assert steady[phase]["Q_std_N"] < 1e-2


@pytest.mark.slow
@pytest.mark.parametrize("phase", list(PHASES))
def test_newton_through_the_wheels(steady, car_params, phase):
    a, m = PHASES[phase], steady[phase]
    wheels = m["wheels"]
    T_hand, creep_hand = hand_torques(car_params, a, wheels)
    # the longitudinal creep forces carry the translating mass's inertia, M_tot a (24 kN): the
    # spins' inertia is the torques' business
    assert m["creep_N"].sum() == pytest.approx(hand_symbols(car_params)["M_tot"] * a, rel=NEWTON_REL_TOL)
    # each wheelset a quarter: within what the rolling resistance moves between them (0.07 N
    # measured, the spin creep's resistance follows each wheelset's load)
    assert np.all(np.abs(m["creep_N"] - creep_hand) < RESISTANCE_N_M / wheels.rc)
    # every wheelset braked / driven equally; the torques are the hand's plus the resistance
    assert np.ptp(m["torques"]) < 1e-9 * abs(T_hand[0])
    assert np.all(np.abs(m["torques"] - T_hand) < RESISTANCE_N_M)
    # the spin's balance: the torque turns the wheel against the creep force's moment at the
    # rolling radius and accelerates its spin inertia; what is left is the rails' resistance
    # moment, which opposes the rolling in both phases (measured 0.34 .. 0.40 N m)
    resistance = m["torques"] - wheels.rc * m["creep_N"] - wheels.Is * a / wheels.rc
    assert np.all((resistance > 0.0) & (resistance < RESISTANCE_N_M))


@pytest.mark.slow
@pytest.mark.parametrize("phase", list(PHASES))
def test_carbody_pitch(steady, car_params, phase):
    a, m = PHASES[phase], steady[phase]
    # the two readings: the floor heights 10 m apart give sin(theta), the body angle theta
    assert m["theta_floor"] == pytest.approx(m["theta_body"], rel=1e-6)
    # sign: braking pitches the carbody nose down
    assert np.sign(m["theta_body"]) == -np.sign(a)
    # level 1 with the car's torques and creep forces: the model's statics to solver tolerance
    assert _rel(m["theta_body"], _level_1_as_the_car(car_params, a, m)["theta"]) < LEVEL_1_REL_TOL
    # level 1 with the hand's torques (measured 1.5e-6)
    assert _rel(m["theta_body"], level_1_wheels(car_params, a, m["wheels"])["theta"]) < LEVEL_1_HAND_REL_TOL
    # level 0 is not asserted here: it misses the pitch by 2.14 % (the kinematic car: 1.05 %),
    # beyond the 2 %. The torque reactions pitch the frames 2.3 mrad and level 0 keeps
    # every body in its static geometry (module doc, "Level 0 against the model"); level 1,
    # which has that geometry, agrees to 2e-7 (above), and level 0 holds within 2 % once the
    # frames pitch a tenth (test_level_0_holds_when_the_frames_do_not_pitch)


@pytest.mark.slow
@pytest.mark.parametrize("phase", list(PHASES))
def test_wheel_load_transfer(steady, car_params, phase):
    a, m = PHASES[phase], steady[phase]
    dQ = m["dQ"]
    # load is transferred, not created (1e-6 of the largest transfer: solver tolerance)
    assert abs(dQ.sum()) < 1e-6 * np.abs(dQ).max()
    # braking loads the leading wheelset of each bogie and unloads the trailing one (the
    # kinematic car loads wheelset 2 as well); accelerating the opposite
    brake = -np.sign(a)
    assert np.all(brake * dQ * np.array([1.0, -1.0, 1.0, -1.0]) > 0.0)
    assert np.argmax(brake * dQ) == 0
    # level 0 per wheelset: within the 2 % (measured 1.17 %, dQ_2 braking); per bogie it
    # misses by 2.13 %, as the pitch (test_carbody_pitch), not asserted here
    hand0 = level_0_wheels(car_params, a, m["wheels"])
    assert np.all(_rel(dQ, hand0["dQ"]) < HAND_REL_TOL)
    # level 1: with the car's torques and creep forces to solver tolerance (measured 1.3e-7),
    # with the hand's torques within their resistance (measured 1.6e-4)
    assert np.all(_rel(dQ, _level_1_as_the_car(car_params, a, m)["dQ"]) < LEVEL_1_REL_TOL)
    assert np.all(_rel(dQ, level_1_wheels(car_params, a, m["wheels"])["dQ"]) < LEVEL_1_HAND_REL_TOL)
    # the traction rods as level 1 has them (measured 1.7e-8)
    assert np.all(_rel(m["rods_N"], _level_1_as_the_car(car_params, a, m)["rods_N"]) < LEVEL_1_REL_TOL)


@pytest.mark.slow
@pytest.mark.parametrize("phase", list(PHASES))
def test_against_the_kinematic_car(steady, kinematic, car_params, phase):
    """What the rail-level forces and the torque reactions change against the kinematic car
    (module doc, "Against the kinematic car"): the transfer between the two wheelsets of a bogie
    grows by the torques' reactions, (T_lead + T_trail) / w = 2636 N (measured 2601 and 2602 N:
    the frames' pitch takes 1.3 %), and the carbody's pitch and the transfer between the bogies
    by ~1 % only (measured 1.08 %), through the frames' pitch."""
    a, m, kin = PHASES[phase], steady[phase], kinematic[phase]
    T, _ = hand_torques(car_params, a, m["wheels"])
    w = hand_symbols(car_params)["w"]
    for i in range(2):
        within = (m["dQ"][2 * i] - m["dQ"][2 * i + 1]) / 2.0 - (kin["dQ"][2 * i] - kin["dQ"][2 * i + 1]) / 2.0
        assert _rel(within, -(T[2 * i] + T[2 * i + 1]) / w) < HAND_REL_TOL
    dV1, dV1_kin = m["dQ"][0] + m["dQ"][1], kin["dQ"][0] + kin["dQ"][1]
    assert 0.0 < (dV1 - dV1_kin) / dV1_kin < HAND_REL_TOL
    assert 0.0 < (m["theta_body"] - kin["theta"]) / kin["theta"] < HAND_REL_TOL


@pytest.mark.slow
def test_traction_on_the_front_bogie(car_params):
    """Traction on wheelsets 1 and 2 only (``WheelDrive(motored_wheelsets=(1, 2))``), from rest:
    each torque reacts on the frame that carries its wheelset, so the front frame takes both and
    the rear none (a reaction on the wrong frame would move dQ_3, dQ_4 by ~2.6 kN); the rear
    wheelsets are braked by their creep forces, which spin them up. The front bogie pushes the
    carbody and the rear bogie."""
    a, motored = A_M_PER_S2, (1, 2)
    m = run_profile(car_params, brake=False, motored=motored)["accel"]
    wheels = m["wheels"]
    assert m["Q_std_N"] < 1e-2                 # steady (measured 5e-4 N)
    T_hand, creep_hand = hand_torques(car_params, a, wheels, motored)
    assert np.all(m["torques"][2:] == 0.0)
    assert np.all(np.abs(m["torques"][:2] - T_hand[:2]) < 2 * RESISTANCE_N_M)  # the rear's too
    assert m["creep_N"].sum() == pytest.approx(hand_symbols(car_params)["M_tot"] * a, rel=NEWTON_REL_TOL)
    # the rear wheelsets: -I_s a / r_c^2 = -278 N, less their rolling resistance (measured -278.7)
    assert np.all(np.abs(m["creep_N"] - creep_hand) < 2 * RESISTANCE_N_M / wheels.rc)
    hand1, car1 = level_1_wheels(car_params, a, wheels, motored), _level_1_as_the_car(car_params, a, m, motored)
    # level 1 (measured: 1.6e-7 the loads, 3.8e-7 the pitch, 7.5e-7 the rods with the car's
    # forces; 1.5e-4, 3.8e-6 with the hand's)
    assert np.all(_rel(m["dQ"], car1["dQ"]) < LEVEL_1_REL_TOL)
    assert _rel(m["theta_body"], car1["theta"]) < LEVEL_1_REL_TOL
    assert np.all(_rel(m["rods_N"], car1["rods_N"]) < LEVEL_1_REL_TOL)
    assert np.all(_rel(m["dQ"], hand1["dQ"]) < LEVEL_1_HAND_REL_TOL)
    assert _rel(m["theta_body"], hand1["theta"]) < LEVEL_1_HAND_REL_TOL
    # level 0: the front bogie's within-bogie transfer (6.4 kN) within 2 % (measured 0.20 %); the
    # rear's is the small difference of two terms (level 0: 11.6 N, model -5.6 N), and dQ_3, dQ_4
    # carry the bogies' transfer, which level 0 misses by 1.7 % as in the main run
    hand0 = level_0_wheels(car_params, a, wheels, motored)
    assert _rel((m["dQ"][0] - m["dQ"][1]) / 2.0, hand0["dN"][0]) < HAND_REL_TOL


@pytest.mark.slow
def test_level_0_holds_when_the_frames_do_not_pitch(car_params):
    """The experiment behind "Level 0 against the model": the primary 10 x stiffer vertically,
    so that the torque reactions pitch the frames a tenth (0.24 mrad). Level 0 then agrees on
    the pitch and the bogies' transfer within the issue's 2 % (measured 0.89 %, 0.88 %, as the
    kinematic car with the same primary: 0.78 %) and per wheelset (1.6 %); level 1 still
    reproduces the model (measured 4e-8): the 2.14 % were the frames' pitch, nothing else."""
    p = dataclasses.replace(car_params, primary_stiffness_z_N_per_m=10.0 * car_params.primary_stiffness_z_N_per_m)
    a = A_M_PER_S2
    m = run_profile(p, brake=False)["accel"]
    assert m["Q_std_N"] < 1e-2                 # steady (measured 4e-5 N)
    hand0 = level_0_wheels(p, a, m["wheels"])
    assert _rel(m["theta_body"], hand0["theta"]) < HAND_REL_TOL
    assert _rel(m["dQ"][0] + m["dQ"][1], hand0["dV1"]) < HAND_REL_TOL
    assert np.all(_rel(m["dQ"], hand0["dQ"]) < HAND_REL_TOL)
    car1 = _level_1_as_the_car(p, a, m)
    assert np.all(_rel(m["dQ"], car1["dQ"]) < LEVEL_1_REL_TOL)
    assert _rel(m["theta_body"], car1["theta"]) < LEVEL_1_REL_TOL


@pytest.mark.slow
def test_without_spin_creep_the_torques_need_only_the_creepage(car_params):
    """The experiment behind "The torques": Kalker's coefficients given with f23 = f33 = 0 (no
    spin creep; f11 = f22 = 10 MN, constant). The rails' resistance moment on each spin then
    falls from 0.34 .. 0.40 N m to what the creepage adds to the spin's acceleration: a wheel
    that transmits F turns faster (accelerating; slower braking) than it rolls by the creepage
    xi, so the spin accelerates at a (1 + |xi|) / r_c and takes I_s a |xi| / r_c more, with
    F / 2 = mu N (u - u^2/3 + u^3/27), u = f11 |xi| / (mu N) per wheel (Shen-Hedrick-Elkins):
    0.039 N m predicted, measured within 4.2 %; level 1 with the hand's torques then meets the
    model to 1.7e-5 (1.6e-4 with the spin creep)."""
    from scipy.optimize import brentq

    from vehicle.params import ContactParams

    f11 = 1e7
    contact = ContactParams(min_creep_speed_m_per_s=MIN_CREEP_SPEED_M_PER_S, creep_coefficients=(f11, f11, 0.0, 0.0))
    a = A_M_PER_S2
    m = run_profile(car_params, brake=False, contact=contact)["accel"]
    wheels, mu = m["wheels"], contact.friction_coefficient
    resistance = m["torques"] - wheels.rc * m["creep_N"] - wheels.Is * a / wheels.rc
    # per wheel F the wheelset's creep force halved, N its load (the normal force's tilt by the
    # 0.025 rad contact angle, 3e-4, left out)
    for j, (F, N) in enumerate(zip(m["creep_N"] / 2.0, hand_symbols(car_params)["Q0"] + m["dQ"] / 2.0)):
        u = brentq(lambda u, F=F, N=N: mu * N * (u - u * u / 3.0 + u ** 3 / 27.0) - abs(F), 0.0, 3.0)
        xi = u * mu * N / f11
        # 10 %: the creepage term predicted within 4.2 % (measured); the spin creep's
        # resistance, had it stayed, would be ten times the prediction
        assert resistance[j] == pytest.approx(wheels.Is * a * xi / wheels.rc, rel=0.1)
    # level 1 with the hand's torques (measured 1.7e-5)
    assert np.all(_rel(m["dQ"], level_1_wheels(car_params, a, wheels)["dQ"]) < 1e-4)
