"""Steady braking and accelerating of the kinematic car against quasi-static hand models.

The car (``metro_car_arb_dampers()``: traction rods and dampers, so the transients die out) stands
1 s, accelerates at A = 1.0 m/s^2 for 20 s, brakes at A for 20 s to a stop and stands 1 s
(:class:`~vehicle.speed.PhasedSpeedProfile`, straight track, kinematic guidance), its bellows
driven as benchmarks/bench_vehicle.py does: F = F0 + k z with k = 243 kN/m, set every 5 ms. The
last 4 s of each phase are averaged (the transients of the step in acceleration have then decayed
to ~1e-6 N in the wheel loads: std over the window, checked below) and compared with the hand
models. The loads "at rest" are those at the end of the first standing second.

Sign conventions
----------------
x forward (the running direction), z up, y left. ``a`` is the acceleration along +x: a > 0
accelerating, a < 0 braking. Pitch theta is the right-hand rotation about +y, which turns +x
towards -z: theta > 0 is **nose down** (the front end lower). It is read as the carbody's
Tait-Bryan angle about y and, independently, from the floor heights 5 m ahead of and behind the
car centre, theta = (z_rear - z_front) / 10 m. dQ_j is the change of the vertical load of
wheelset j (both wheels) from rest, wheelsets 1..4 from the front. Braking (a < 0) pitches the
carbody nose down and loads the leading wheelset (dQ_1 > 0, the largest increase); in each bogie
the leading wheelset gains against the trailing one. Accelerating is the mirror image.

What carries the longitudinal load (from vehicle/car/build.py and secondary.py, where each force
acts; no code of theirs is used here): every wheelset is held along the track by a joint to the
ground that also locks its pitch, so the joint's longitudinal force and its pitch moment together
act as a longitudinal force at the wheelset centre (axle height r_w): the documented "cheaper
longitudinal model" -- not creep forces at rail level (the hand models follow the model there;
they are not models of braking at the rails). From the wheelset the load goes through the
primary springs (axle height) to the bogie frame, through the traction rod (height h_r) and the
two bellows' shear (intrinsic connectors: at the midpoint of the plates, h_s = (h_l + h_u) / 2)
to the carbody. Anti-roll bar (roll only), lateral damper and bumpstop (y only) carry nothing in
the pitch plane; the vertical dampers (Maxwell elements) carry nothing in a steady state.

Symbols (``vehicle.params``; values of ``metro_car_arb_dampers()``)
------------------------------------------------------------------
M = 17 000 kg carbody, m_b = 1 900 kg bogie frame, m_w = 800 kg wheelset, M_tot = M + 2 m_b + 4 m_w;
h_c = 1.5 m, h_b = 0.6 m CoG heights; h_r = 0.5 m traction rod; h_l = 0.80, h_u = 1.05 m bellow
plates, h_s = 0.925 m; r_w = r_0 - delta_0 = 0.41996 m wheelset centre (wheel radius less the
static Hertz approach delta_0 = (Q_0 / C_H)^(2/3)); L = 10 m bogie centres (x = +-L/2), w = 2 m
wheelbase; k_r = 10 MN/m rod, k_s = 120 kN/m shear per bellow, k_v = (1/k + 1/k_e)^-1 = 216.7
kN/m vertical per bellow (the linear bellow law k = 243 kN/m in series with the 2 MN/m emergency
spring), k_pz = 0.68 MN/m primary vertical per axlebox.

Level 0: rigid, statically determinate hand model (closed form)
--------------------------------------------------------------
Every body keeps its static geometry; quasi-static, each body in equilibrium with its
d'Alembert force -m a at its CoG.

* Carbody, along x: the bogies push it with M a, M a / 2 each, split between rod and shear as
  their stiffnesses (parallel springs, same deflection): rod share rho = k_r / (k_r + 2 k_s), so
  the force acts at the effective height h_e = rho h_r + (1 - rho) h_s (0.510 m).
* Carbody, pitch moment about its CoG: the two bellow pairs' vertical forces change by
      dV_1 = -dV_2 = -M a (h_c - h_e) / L                       (front bogie = 1)
* Bogie frame i, along x: the primary carries (m_b + M/2) a at axle height; moment about its CoG
  (the bellows' vertical force acts at the bogie centre, no arm):
      dN = [ (M a / 2) (r_w - h_e) + m_b a (r_w - h_b) ] / w      (leading minus trailing, halved)
* Wheelset j: the guidance joint has no vertical reaction, so dQ_j = the change of its primary
  force:  dQ_1 = dV_1/2 + dN,  dQ_2 = dV_1/2 - dN,  dQ_3 = -dV_1/2 + dN,  dQ_4 = -dV_1/2 - dN.
* Pitch: each front bellow (dV_1 / 2) compresses by dV_1 / (2 k_v) more, the bogie centre sinks
  by dV_1 / (4 k_pz) (four axleboxes), the rear the opposite:
      theta = dV_1 (1/k_v + 1/(2 k_pz)) / L
  (the Hertz contacts, ~1e9 N/m per wheel, add 0.07 %: neglected).

At a = -1 m/s^2: dV_1 = 1683 N, dN = 554 N, dQ = (1395, 288, -288, -1395) N, theta = 0.900 mrad.

Level 0 against the model (measured here, braking; accelerating is the mirror image, wheelsets
1..4 read 4..1): the pitch and the per-bogie transfer dV_1 = dQ_1 + dQ_2 agree within 1.05 %
(asserted, 2 %), but the per-wheelset transfer misses by 2.5, 6.0, 12.2, 3.8 % (model 1429.8,
270.7, -252.9, -1447.7 N): wheelsets 2 and 3, the difference of two larger terms, are the
sensitive ones. Level 0 leaves out three pieces of physics; the experiment switched each off in
the model (same run, level 0 against the model, braking; the last row is
:func:`test_level_0_holds_once_the_missing_physics_is_switched_off`):

    run                               pitch    dQ_1    dQ_2    dQ_3    dQ_4   (level 0 error)
    as is                             1.05 %   2.49 %  6.00 %  12.2 %  3.77 %
    g / 10             (A off)        0.09 %   0.21 %  1.69 %  7.80 %  1.47 %
    bellows 100x stiff (B off)        0.77 %   1.53 %  3.29 %  4.12 %  1.70 %
    shear 1 kN/m       (C off)        1.30 %   1.97 %  1.44 %  6.92 %  3.33 %
    all three off                     0.20 %   0.11 %  0.15 %  0.88 %  0.29 %

(A) the static loads act in the deformed geometry. The carbody's centre of gravity is 1.92 mm
    behind the wheelsets accelerating (ahead braking): the primary 0.23 mm, the rods 0.83 mm and
    the pitch of carbody and frame at the rods 0.87 mm; its weight shifts with it along the car
    (M g x 1.92 mm = 320 N m, 1.7 % of the 19.0 kN m overturning moment sum m a (h - r_w)). In
    the model this comes through the intrinsic connectors: their vertical preloads (bellows
    41.7 kN, axleboxes 25.5 kN) act at the midpoint of their two markers, which moves by half
    their relative displacement, and along the mid-frame's axes (the bellow force tilts by the
    mean pitch of carbody and frame). Proportional to g a: g / 10 takes all of level 0's pitch
    error away.
(B) the traction rod force (8.3 kN) acts at the midpoint of its two markers, which the bellows'
    extension (3.9 mm, front and rear opposite) moves up or down by half: +-16 N m on the bogie
    frames, front and rear opposite -- the front-rear asymmetry of the model (braking loads
    wheelset 1 by 1429.8 N and unloads wheelset 4 by 1447.7 N). Proportional to a^2 (even in a):
    the accelerating run is the braking one mirrored, not negated, and at 0.5 m/s^2 the
    asymmetry is 4.5 N, a quarter of 17.8 N. Bellows 100x stiffer vertically shrink it to 2.4 N.
(C) the relative pitch of carbody and frame deflects the shear (at h_s) more than the rod (at
    h_r): the shear carries 2.9 % of M a, not level 0's 2.3 %, higher up.

Level 1: the same equilibrium in the deformed geometry (:func:`level_1`)
------------------------------------------------------------------------
Carbody and both bogie frames in the pitch plane (X, Z, theta each) and the four wheelsets' heave
on their Hertz contacts (Q = C_H delta^1.5 per wheel), 13 unknowns; the wheelsets are held at
their prescribed x with zero pitch. Each body point moves with its body's exact rotation; every
connector is written as the model defines it (read from build.py/secondary.py, not copied):
deflection measured in the mid-frame of its two bodies (rotated by the mean of their pitches),
force along that frame's axes, applied at the midpoint of its two markers on both bodies. The
deflection is exudyn's for an intrinsic connector, the translation of the SE(3) logarithm of the
markers' relative pose: in the plane the mid-frame components times (phi/2) / sin(phi/2), phi
their relative pitch (1 + phi^2/24: it lengthens a 0.25 m bellow by 2 nm at the 0.5 mrad
here, the last 4e-9 of the pitch between level 1 and the model; found in
tests/vehicle/test_wheel_braking.py, where the frames pitch more):

* bellow pair: crush = H - d_z (H = h_u - h_l), force on the carbody 2 (V_0 + k_v crush) along
  the frame's z and -2 k_s d_x along its x;
* traction rod: -k_r d_x along the frame's x;
* primary per wheelset: -2 k_px d_x, and the preload 2 P_0 plus -2 k_pz d_z (P_0 the static
  axlebox load) on the wheelset along the frame's z (the frame of bogie frame and unpitched
  wheelset).

Equations: for each body sum F_x = m a (d'Alembert), sum F_z = m g, sum M_y = 0 about its CoG; for
each wheelset, Hertz load = m_w g + its primary's vertical force. Solved by Newton
(:func:`scipy.optimize.fsolve`), residual < 1e-9 x 10 kN. Level 1 is level 0 plus (A), (B) and
(C); it reproduces the model to 3e-10 (pitch) and 9e-9 (wheel loads) relative, the model's own
solver tolerance: the hand derivation and the model agree on where every force acts. (With the
wheelsets free along x, pushed by creep forces, and the frames taking torque reactions,
:class:`ThroughWheels`, it is the level 1 of the car moved through its wheels,
tests/vehicle/test_wheel_braking.py.)

Newton's law
------------
The guidance joints' reactions are readable (``ForceLocal`` of the four ``JointGeneric`` between
the ground and the wheelsets, found in the system by their bodies; on straight track the joint
frame is the ground's, so local x is global x). Their sum must be -M_tot a: ``ForceLocal`` is
the force on the ground marker, measured sign (accelerating, it is negative); the wheelsets
receive its opposite.
"""
from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
import pytest
from scipy.optimize import fsolve

A_M_PER_S2 = 1.0        #: acceleration and deceleration [m/s^2]
PHASE_S = 20.0          #: duration of each phase [s]
STAND_S = 1.0           #: standing before and after [s]
AVERAGE_S = 4.0         #: averaged at the end of each phase [s]
MACRO_S = 0.005         #: bellow law update (the co-simulation's macro-step) [s]
K_BELLOW_N_PER_M = 243e3  #: adiabatic bellow + tank, paper Table 2 (as benchmarks/bench_vehicle.py)

# 2 %: the tolerance for a hand model against the multibody model.
HAND_REL_TOL = 0.02
# Level 1 is the model's own statics: only the solver tolerance and the last transients separate
# them (measured 9e-9 on the wheel loads, 3e-10 on the pitch); 1e-5 leaves a factor ~1000 of
# margin and still catches the rod force applied 0.1 mm off in height (1.6e-3 of dQ_2).
LEVEL_1_REL_TOL = 1e-5
# Newton: the wheelsets' acceleration is prescribed exactly and the other bodies' accelerations
# have decayed (the 5.5 Hz carbody-on-rods mode, damping ratio ~0.05 from the rods' 30 kN s/m,
# decays by e^-28 in the 16 s before the window; measured 2e-12 and 2e-11): 1e-6 as asked.
NEWTON_REL_TOL = 1e-6


def hand_symbols(p, k_bellow: float = K_BELLOW_N_PER_M) -> dict:
    """The symbols of the module doc, from the parameters ``p``."""
    g = p.gravity_m_per_s2
    M, mb, mw = p.carbody_mass_kg, p.bogie_mass_kg, p.wheelset_mass_kg
    P0 = (M * g / 2.0 + mb * g) / 4.0            # static axlebox load
    Q0 = P0 + mw * g / 2.0                        # static wheel load
    delta0 = (Q0 / p.hertz_constant_N_per_m1_5) ** (2.0 / 3.0)
    return dict(g=g, M=M, mb=mb, mw=mw, M_tot=M + 2 * mb + 4 * mw, P0=P0, Q0=Q0, delta0=delta0,
                hc=p.carbody_cog_height_m, hb=p.bogie_cog_height_m, hr=p.traction_rod_height_m,
                hl=p.airspring_lower_height_m, hu=p.airspring_upper_height_m,
                hs=0.5 * (p.airspring_lower_height_m + p.airspring_upper_height_m),
                rw=p.wheel_radius_m - delta0, L=p.bogie_centre_distance_m, w=p.wheelbase_m,
                kr=p.traction_rod_stiffness_N_per_m, ks=p.bellow_shear_stiffness_N_per_m,
                kv=1.0 / (1.0 / k_bellow + 1.0 / p.emergency_spring_stiffness_N_per_m),
                kpx=p.primary_stiffness_x_N_per_m, kpz=p.primary_stiffness_z_N_per_m,
                CH=p.hertz_constant_N_per_m1_5)


def effective_height(s: dict) -> float:
    """h_e of the module doc: the height at which rod and shear together push the carbody along x
    (parallel springs, rod share rho = k_r / (k_r + 2 k_s)); ``s``: :func:`hand_symbols`."""
    rho = s["kr"] / (s["kr"] + 2.0 * s["ks"])
    return rho * s["hr"] + (1.0 - rho) * s["hs"]


def level_0(p, a: float, k_bellow: float = K_BELLOW_N_PER_M) -> dict:
    """The closed-form rigid hand model (module doc, "Level 0"): carbody pitch theta [rad, + nose
    down], bogie transfer dV_1 [N] and per-wheelset transfer dQ (4,) [N] at acceleration ``a``."""
    s = hand_symbols(p, k_bellow)
    he = effective_height(s)
    dV1 = -s["M"] * a * (s["hc"] - he) / s["L"]
    dN = (s["M"] * a / 2.0 * (s["rw"] - he) + s["mb"] * a * (s["rw"] - s["hb"])) / s["w"]
    theta = dV1 * (1.0 / s["kv"] + 1.0 / (2.0 * s["kpz"])) / s["L"]
    return dict(theta=theta, dV1=dV1, dQ=np.array([dV1 / 2 + dN, dV1 / 2 - dN, -dV1 / 2 + dN, -dV1 / 2 - dN]))


def _rot(theta: float) -> np.ndarray:
    """2D rotation (x, z) of a body pitched by theta (+ nose down): columns are its x and z axes."""
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, s], [-s, c]])


def _deflection(theta0: float, theta1: float, p0: np.ndarray, p1: np.ndarray) -> np.ndarray:
    """Deflection (x, z) of an intrinsic connector from marker p0 on a body pitched theta0 to p1
    on one pitched theta1, as exudyn measures it: the translation of the SE(3) logarithm of the
    relative pose, which in the plane is p1 - p0 in the mid-frame (pitched by the mean) times
    (phi/2) / sin(phi/2), phi = theta1 - theta0 (1 + phi^2/24: 6e-7 at the 3.8 mrad between the
    carbody and a frame pitched by traction torques, 0.15 um on a 0.25 m bellow)."""
    phi = theta1 - theta0
    scale = 1.0 if phi == 0.0 else 0.5 * phi / math.sin(0.5 * phi)
    return scale * (_rot(0.5 * (theta0 + theta1)).T @ (p1 - p0))


@dataclasses.dataclass(frozen=True)
class ThroughWheels:
    """What changes in :func:`level_1` when the car is moved through its wheels (contact
    guidance, tests/vehicle/test_wheel_braking.py) instead of by the guidance joints: the
    wheelsets are free along x (their positions are unknowns, the mean of the four fixed: the
    translation along the track is free), each pushed along x at its centre by its creep force
    (the creep force's moment about the axle goes to the spin coordinate, not the body), and each
    bogie frame takes the pure moments of its wheelsets' torque reactions."""

    #: height of the wheelset centres at rest [m]
    rw: float
    #: vertical approach of the contacts at rest [m]: a wheelset's contacts carry
    #: 2 Q0 ((delta0 - Zw) / delta0)^1.5 at a heave Zw
    delta0: float
    #: (4,) longitudinal creep force on each wheelset [N]; they must sum to M_tot a
    creep_N: tuple
    #: (4,) pure moment about +y on the bogie frame carrying each wheelset [N m]
    frame_moment_N_m: tuple


def level_1(p, a: float, k_bellow: float = K_BELLOW_N_PER_M, wheels: ThroughWheels | None = None,
            weight_g: float | None = None) -> dict:
    """Quasi-static equilibrium in the deformed geometry (module doc, "Level 1"): carbody pitch
    theta [rad], per-wheelset transfer dQ (4,) [N], the traction rod forces on the carbody (2,) [N]
    and the displacements (X, Z, theta) of carbody and bogie frames at acceleration ``a``; with
    ``wheels`` the car moved through its wheels (:class:`ThroughWheels`; 17 unknowns, with the
    wheelsets' x displacements, also returned), else held by the guidance joints. ``weight_g``:
    the bodies' weights at this gravity instead of the parameters' (the springs' preloads, the
    static reference, stay at the parameters' g): a car standing on a gradient, whose weight
    tilts (vehicle/car/gradient.py)."""
    s = hand_symbols(p, k_bellow)
    g, M, mb, mw = s["g"], s["M"], s["mb"], s["mw"]
    gw = g if weight_g is None else weight_g
    xb = (s["L"] / 2.0, -s["L"] / 2.0)
    H, V0 = s["hu"] - s["hl"], M * g / 4.0          # bellow height, static force per bellow
    w2 = s["w"] / 2.0
    rw, delta0 = (s["rw"], s["delta0"]) if wheels is None else (wheels.rw, wheels.delta0)
    n = 13 if wheels is None else 17

    def hertz(Zw):
        return 2.0 * s["Q0"] * (np.maximum(delta0 - Zw, 0.0) / delta0) ** 1.5

    def residual(u, rods=None, full=False):
        (Xc, Zc, tc), Zw = u[0:3], u[9:13]
        Xw = np.zeros(4) if wheels is None else u[13:17]
        bodies = {"c": (Xc, Zc, tc, 0.0, s["hc"])}
        for i in range(2):
            bodies[i] = (*u[3 + 3 * i: 6 + 3 * i], xb[i], s["hb"])
        force = {k: np.zeros(2) for k in bodies}
        moment = dict.fromkeys(bodies, 0.0)

        def cog(k):
            X, Z, _, x0, z0 = bodies[k]
            return np.array([x0 + X, z0 + Z])

        def point(k, local):      # a point fixed in body k, local offset from its static CoG
            return cog(k) + _rot(bodies[k][2]) @ np.asarray(local, float)

        def apply(k, f, at):
            force[k] += f
            r = at - cog(k)
            moment[k] += r[1] * f[0] - r[0] * f[1]

        for k in bodies:          # d'Alembert and gravity at the CoG
            m = M if k == "c" else mb
            apply(k, np.array([-m * a, -m * gw]), cog(k))
        wheel_z_force, wheel_x_force = np.zeros(4), np.zeros(4)
        for i in range(2):
            J = _rot(0.5 * (tc + bodies[i][2]))      # mid-frame of carbody and frame i
            # bellow pair: plates on the frame (bogie centre, h_l) and the carbody (x_i, h_u)
            lower, upper = point(i, [0.0, s["hl"] - s["hb"]]), point("c", [xb[i], s["hu"] - s["hc"]])
            d = _deflection(bodies[i][2], tc, lower, upper)
            f = J @ np.array([-2.0 * s["ks"] * d[0], 2.0 * (V0 + s["kv"] * (H - d[1]))])
            mid = 0.5 * (lower + upper)
            apply("c", f, mid)
            apply(i, -f, mid)
            # traction rod: bogie centre and carbody, both at h_r
            pb, pc = point(i, [0.0, s["hr"] - s["hb"]]), point("c", [xb[i], s["hr"] - s["hc"]])
            d = _deflection(bodies[i][2], tc, pb, pc)
            f = J @ np.array([-s["kr"] * d[0], 0.0])
            if rods is not None:
                rods.append(-s["kr"] * d[0])
            mid = 0.5 * (pb + pc)
            apply("c", f, mid)
            apply(i, -f, mid)
            # primary, two axleboxes per wheelset: frame marker and wheelset centre (held at its
            # x, or moved by Xw through the wheels; unpitched; heave Zw on its contacts); frame:
            # mean of the frame's pitch and 0
            Jp = _rot(0.5 * bodies[i][2])
            for j, dx in ((2 * i, w2), (2 * i + 1, -w2)):
                pw = np.array([xb[i] + dx + Xw[j], rw + Zw[j]])
                pm = point(i, [dx, rw - s["hb"]])
                d = _deflection(bodies[i][2], 0.0, pm, pw)
                f_w = -Jp @ np.array([2.0 * s["kpx"] * d[0], 2.0 * (s["kpz"] * d[1] + s["P0"])])
                apply(i, -f_w, 0.5 * (pw + pm))
                wheel_z_force[j] = f_w[1]
                wheel_x_force[j] = f_w[0]
                if wheels is not None:      # the torque's reaction on the frame: a pure moment
                    moment[i] += wheels.frame_moment_N_m[j]
        res = [*force["c"], moment["c"], *force[0], moment[0], *force[1], moment[1],
               *(hertz(Zw) + wheel_z_force - mw * gw)]
        if wheels is not None:
            # the wheelsets along x; all the x equations sum to (creep forces) - M_tot a, so with
            # creep forces that carry M_tot a one of them is redundant: traded for the gauge
            along = np.asarray(wheels.creep_N) + wheel_x_force - mw * a
            res += [*along] if full else [*along[:3], Xw.sum()]
        return np.array(res) / 1e4

    u = fsolve(residual, np.zeros(n), xtol=1e-12, full_output=True)[0]
    rods = []
    assert np.abs(residual(u, rods, full=True)).max() < 1e-9, "level 1 did not converge"
    result = dict(theta=float(u[2]), dQ=hertz(u[9:13]) - 2.0 * s["Q0"], rods_N=np.array(rods),
                  carbody=u[0:3], bogies=u[3:9].reshape(2, 3))
    if wheels is not None:
        result["wheelsets_x"] = u[13:17]
    return result


def guidance_joints(car) -> list:
    """The wheelsets' guidance joints: the ``JointGeneric`` objects between the ground and a
    wheelset, in wheelset order."""
    mbs = car.mbs
    ground, wheelsets = int(car.model.ground), [int(b) for b in car.model.wheelsets]
    found = {}
    for i in range(mbs.systemData.NumberOfObjects()):
        obj = mbs.GetObject(i)
        if obj["objectType"] != "JointGeneric":
            continue
        b0, b1 = (int(mbs.GetMarker(m)["bodyNumber"]) for m in obj["markerNumbers"])
        if b0 == ground and b1 in wheelsets:
            found[wheelsets.index(b1)] = i
    assert sorted(found) == [0, 1, 2, 3], found
    return [found[k] for k in range(4)]


def run_profile(p, k_bellow: float = K_BELLOW_N_PER_M, a: float = A_M_PER_S2) -> dict:
    """Drive the car through stand / accelerate / brake / stand; per phase ("accel", "brake") the
    averages over its last AVERAGE_S: pitch (body angle and floor heights), dQ (4,), guidance
    force on the wheelsets (sum), traction rods; and the std of the wheel loads there."""
    import exudyn as exu

    from vehicle.car import MetroCar
    from vehicle.speed import PhasedSpeedProfile
    from vehicle.track import Straight, TrackGeometry

    out_t = exu.OutputVariableType
    t1, t2, t3 = STAND_S, STAND_S + PHASE_S, STAND_S + 2 * PHASE_S
    profile = PhasedSpeedProfile((0.0, t1, t2, t3, t3 + STAND_S), (0.0, 0.0, a * PHASE_S, 0.0, 0.0))
    track = TrackGeometry((Straight(a * PHASE_S ** 2 + 50.0),))
    car = MetroCar(p, track=track, speed_profile=profile)
    mbs, joints = car.mbs, guidance_joints(car)
    F0, k = car.static_bellow_forces_N(), np.full(4, k_bellow)
    windows = {"accel": (t2 - AVERAGE_S, t2), "brake": (t3 - AVERAGE_S, t3)}
    rows = {name: [] for name in windows}
    Q_rest = None
    start = time.perf_counter()
    for n in range(1, int(round((t3 + STAND_S) / MACRO_S)) + 1):
        z, _ = car.bellow_crushing()
        car.set_bellow_forces(F0 + k * z, k)
        t = n * MACRO_S
        car.advance(t)
        if abs(t - t1) < 1e-9:
            Q_rest = car.wheel_loads_N()
        for name, (lo, hi) in windows.items():
            if lo + 1e-9 < t < hi + 1e-9:
                Q = car.wheel_loads_N()
                floor = car.floor_heights_m([[5.0, 0.0], [-5.0, 0.0]])
                rows[name].append([
                    mbs.GetObjectOutputBody(car.model.carbody, out_t.Rotation)[1],
                    (floor[1] - floor[0]) / 10.0,
                    -sum(mbs.GetObjectOutput(j, out_t.ForceLocal)[0] for j in joints),
                    *car.traction_rod_forces_N(), *Q])
    result = {"wall_s": time.perf_counter() - start}
    for name, r in rows.items():
        r = np.array(r)
        mean = r.mean(axis=0)
        Q = mean[5:13]
        result[name] = dict(theta_body=mean[0], theta_floor=mean[1], guidance_N=mean[2], rods_N=mean[3:5],
                            dQ=(Q - Q_rest).reshape(4, 2).sum(axis=1), Q_std_N=r[:, 5:13].std(axis=0).max())
    return result


PHASES = {"accel": A_M_PER_S2, "brake": -A_M_PER_S2}


@pytest.fixture(scope="module")
def car_params():
    from vehicle.params import metro_car_arb_dampers

    return metro_car_arb_dampers()


@pytest.fixture(scope="module")
def steady(car_params):
    return run_profile(car_params)


def _rel(model, hand):
    return np.abs(np.asarray(model) - np.asarray(hand)) / np.abs(np.asarray(hand))


@pytest.mark.slow
@pytest.mark.parametrize("phase", list(PHASES))
def test_steady_state_reached(steady, phase):
    # the wheel loads stand still over the averaging window (std 2e-6 N measured): 1e-3 N is
    # 1e-6 of the smallest transfer compared, so the average is the steady state
    assert steady[phase]["Q_std_N"] < 1e-3


@pytest.mark.slow
@pytest.mark.parametrize("phase", list(PHASES))
def test_carbody_pitch(steady, car_params, phase):
    a = PHASES[phase]
    m = steady[phase]
    # the two readings of the pitch: the floor heights 10 m apart give sin(theta), the body angle
    # theta: theta^2 / 6 = 1.4e-7 relative apart
    assert m["theta_floor"] == pytest.approx(m["theta_body"], rel=1e-6)
    # sign: braking pitches the carbody nose down
    assert np.sign(m["theta_body"]) == -np.sign(a)
    # level 0 within the 2 % (measured 1.04 %: it leaves out (A), (B), (C) of the doc)
    assert _rel(m["theta_body"], level_0(car_params, a)["theta"]) < HAND_REL_TOL
    # level 1 (deformed geometry): the model's statics to solver tolerance
    assert _rel(m["theta_body"], level_1(car_params, a)["theta"]) < LEVEL_1_REL_TOL


@pytest.mark.slow
@pytest.mark.parametrize("phase", list(PHASES))
def test_wheel_load_transfer(steady, car_params, phase):
    a = PHASES[phase]
    dQ = steady[phase]["dQ"]
    # load is transferred, not created: the four changes sum to zero (vertical equilibrium;
    # 1e-6 of the largest transfer: solver tolerance)
    assert abs(dQ.sum()) < 1e-6 * np.abs(dQ).max()
    # sign convention: braking loads the leading wheelset (and in each bogie the leading one)
    brake = -np.sign(a)
    assert np.argmax(brake * dQ) == 0
    assert brake * dQ[0] > 0 and brake * (dQ[0] - dQ[1]) > 0 and brake * (dQ[2] - dQ[3]) > 0
    # level 0, per bogie (the carbody's moment balance, dV_1 = dQ_1 + dQ_2): within 2 %
    # (measured 1.04 %); per wheelset level 0 misses by up to 14 % (module doc: (A), (B), (C))
    hand0 = level_0(car_params, a)
    assert _rel(dQ[0] + dQ[1], hand0["dV1"]) < HAND_REL_TOL
    assert _rel(dQ[2] + dQ[3], -hand0["dV1"]) < HAND_REL_TOL
    # level 1 per wheelset: within 2 % (the issue's), and in fact to solver tolerance
    hand1 = level_1(car_params, a)["dQ"]
    assert np.all(_rel(dQ, hand1) < HAND_REL_TOL)
    assert np.all(_rel(dQ, hand1) < LEVEL_1_REL_TOL)


@pytest.mark.slow
@pytest.mark.parametrize("phase", list(PHASES))
def test_newton_guidance_forces(steady, car_params, phase):
    a = PHASES[phase]
    M_tot = hand_symbols(car_params)["M_tot"]
    # the guidance joints' longitudinal forces on the wheelsets sum to M_tot a (24 kN)
    assert steady[phase]["guidance_N"] == pytest.approx(M_tot * a, rel=NEWTON_REL_TOL)
    # the traction rods alone do not carry M a (measured 97.7 %): the bellows' shear takes 2.9 %
    # (level 0's 2 k_s / (k_r + 2 k_s) = 2.3 %, more as the carbody pitches about the rods) and
    # their tilted axial force (V (theta_c + theta_b) / 2 = 112 N, 0.66 %) works against; a
    # Newton check on the rods alone would have missed by 2.3 %. Each rod as level 1 has it, to
    # its tolerance (above)
    assert np.all(_rel(steady[phase]["rods_N"], level_1(car_params, a)["rods_N"]) < LEVEL_1_REL_TOL)


@pytest.mark.slow
def test_level_0_holds_once_the_missing_physics_is_switched_off(car_params):
    """The experiment behind (A), (B), (C) of the module doc: the same braking with the static
    loads a tenth (g / 10: (A)), the bellows 100 x stiffer vertically (k and the emergency spring:
    (B)) and the shear ~0 (1 kN/m, the parameter's lower bound: (C)). Level 0 then agrees per
    wheelset within 2 % (measured 0.9 % at most, against 14 % with all on), and level 1 still
    reproduces the model: the differences were those three pieces of physics, nothing else."""
    # level 1 to 1e-4 here, not 1e-5: the bellows 100 x stiffer vertically outrun their dampers
    # (10 kN s/m behind a 2 MN/m mounting), so a bounce of 0.1 N std is left in the averaging
    # window (measured 1.6e-5 off level 1 on the 338 N of wheelset 2)
    p = dataclasses.replace(car_params, gravity_m_per_s2=car_params.gravity_m_per_s2 / 10.0,
                            emergency_spring_stiffness_N_per_m=100.0 * car_params.emergency_spring_stiffness_N_per_m,
                            bellow_shear_stiffness_N_per_m=1.0e3)
    k_bellow = 100.0 * K_BELLOW_N_PER_M
    m = run_profile(p, k_bellow)["brake"]
    a = -A_M_PER_S2
    assert np.all(_rel(m["dQ"], level_0(p, a, k_bellow)["dQ"]) < HAND_REL_TOL)
    assert _rel(m["theta_body"], level_0(p, a, k_bellow)["theta"]) < HAND_REL_TOL
    assert np.all(_rel(m["dQ"], level_1(p, a, k_bellow)["dQ"]) < 1e-4)
