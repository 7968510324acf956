"""Exudyn multibody model of the metro car (paper section 4, Table 3), standing on prescribed rail
heights (twist test) or running at constant speed along a track (curve entry, paper section 4.2).

Bodies: carbody, two bogie frames, four wheelsets (rigid, 6 coordinates each, Tait-Bryan xyz).
Coordinates: x forward (running direction at the start), y to the left, z up; rail top at z = 0
on level track.

* Primary suspension: one spring-damper per axlebox (``RigidBodySpringDamper``), x/y/z stiffness
  and damping from :class:`VehicleParams`.
* Secondary suspension (airsprings), per bellow:
    - an axial force pair F(z) = F_N + dF/dz (z - z_call) pushing the carbody up and the bogie
      down: a ``CartesianSpringDamper`` between the upper and lower plate centres whose force
      law is a symbolic user function of the crushing z. The axis n is the normal of the track
      plane under the bogie centre: global z on uncanted track (the paper's curve), so the pair
      is exactly vertical there, whatever the yaw. The bogie frame's z would differ from it by
      the bogie roll on its primary (5 mrad in the paper's curve: a lateral component of 0.5 % of
      F, against a shear force of 10 % of F); on canted track n follows the cant. A
      point-to-point spring would add a negative lateral stiffness -F/L (design notes);
    - shear stiffness in x and y (``RigidBodySpringDamper``).
* Lateral bumpstops, one per bogie: between bogie frame and carbody at the bogie centre, at the
  height of the lower bellow plate (where the carbody's centre pivot meets the stops on the bogie
  frame); lateral force k_bs (|d| - clearance) beyond the clearance, 0 inside it.
* Wheel-rail contact, per wheel: unilateral Hertz law Q = max(0, C_H delta^1.5 + c d(delta)/dt),
  Q = 0 when delta <= 0, vertical only, acting at a point fixed on the (non-spinning) wheelset
  body below the wheel centre, against the rail height prescribed for that wheel: the track's
  cant (rails at -/+ (contact spacing / 2) sin(cant), left/right) plus the optional
  ``rail_height_m`` irregularity. Lateral wheel-rail forces (creep, flange) are not modelled:
  the guidance carries them.
* Wheelset guidance (:meth:`MetroCar._add_wheelset_guidance`): each wheelset runs along the
  track at constant speed v, its centre at arc length s_i(t) = s0_i + v t. A ``GenericJoint``
  to ground, whose frame follows the track (heading psi(s_i), and the cant roll) through a
  symbolic offset user function set before every internal step, locks the wheelset centre's
  longitudinal and lateral position, its pitch (no spin: the wheelset body does not rotate
  about its axle) and its yaw: the axle stays normal to the track tangent (radial wheelsets).
  Vertical motion and roll about the tangent stay free, on the contact springs. ``track=None``
  is an unbounded straight level track along x (speed 0: the stationary rig of the twist
  test). The centrifugal and gyroscopic loads arise from this prescribed motion alone; no
  force is added.

Newton's third law in the strong form (moment balance). A force pair between body-fixed points
that separate is not collinear and leaves a couple d x f: the bellow pair (F = 42 kN over the
37 mm lateral bellow deflection of the paper's curve) and the shear (4.2 kN over the 0.25 m
bellow height) left 5.9 kNm per bogie, 31 % of the 37.7 kNm by which the wheel loads must
balance the overturning moment (measured before this was fixed). Hence:

* all ``RigidBodySpringDamper`` connectors (primary, shear, bumpstops) use exudyn's intrinsic
  formulation: axes of the mid-frame between the two bodies, force applied at the midpoint of the
  two markers on both bodies;
* the ``CartesianSpringDamper`` of each bellow keeps its force at the plate centres (its force
  output and crushing are the co-simulation interface), and :meth:`MetroCar._set_end_moments`
  adds the end moments -(d x F n)/2 on carbody and bogie frame each (torque loads): with them the
  pair's line of action passes through the bellow midpoint too -- the bellow behaves as a
  point-symmetric element whose force resultant passes through its centre;
* the guidance joint reacts at the wheelset centre, the rails at rail level:
  :meth:`MetroCar._set_rail_couples` adds the couple (-z_w n) x f on each wheelset (10 kNm in
  the paper's curve, 27 % of the overturning moment).

The two torque loads are recomputed from the state at the start of every internal step (one
step of lag: exudyn's Cartesian connector cannot carry a torque, and neither the joint reaction
nor the plate offset of another connector is available to a symbolic user function); their
Jacobian (~F/2 per radian of roll, < 1 % of the roll stiffness) is left out. tests/
test_vehicle_curve.py checks the wheel load transfer in the curve against the overturning moment.

Static equilibrium on level track under :meth:`MetroCar.static_bellow_forces_N` is the *reference
configuration*: bodies sit at their static positions, the primary springs carry their static load
through their offsets and each contact point penetrates its rail by the Hertz deflection; with a
speed, every body starts at it along x on the initial straight, so a run starts without settling
transient.

Force laws are exudyn *symbolic* user functions: they run in C++ (a Python user function costs
~1.5 us per call and the numerical Jacobian calls it 13 times per connector); their inputs (rail
height/rate, bellow force/stiffness/axis, guidance offsets) are named symbolic variables set from
Python. The track is evaluated through :class:`~vehicle.guidance.TrackSampler` (~10 us per step).

Solver: implicit generalized-alpha, driven macro-step by macro-step with
``MainSolverImplicitSecondOrder.SolveSteps`` (no restart: state-exact continuation). SolveSteps
asks for a new Newton Jacobian at every call; a Jacobian user function serves that request with
the previous Jacobian when the step size is unchanged (the bellow stiffness is ~1e-4 of the
effective mass stiffness M/(beta h^2), so it never matters) and the track heading has turned by
less than :attr:`MetroCar.JACOBIAN_HEADING_TOL_RAD` since it was computed (the guidance
directions and the Rxyz mass matrix follow the heading), and computes a fresh one, with a second
solver object on the same system, otherwise and whenever Newton itself asks (e.g. a wheel lifts).

Known limits of the running model (see also :class:`MetroCar`):

* radial wheelsets: the yaw of every wheelset is prescribed to the track heading, so in a curve
  the two wheelsets of a bogie are 2 a / R apart in yaw (0.02 rad at R = 100 m) and the stiff
  primary (k_x = 17.5 MN/m) takes ~175 kN per axlebox and ~350 kNm per wheelset of internal yaw
  moment, which real, creep-steered wheelsets would not see. These longitudinal forces barely
  touch roll and vertical loads (the steady roll at R = 1000 m, 31.6 m/s, the same 1 m/s^2,
  differs by 0.02 %), but they are not physical;
* on canted track the contact forces stay vertical and the guidance takes the in-plane lateral
  force at rail level: Q is the vertical load, not the load normal to the track plane;
* no lateral damping (the paper's car has no hydraulic dampers): the carbody sway/roll mode at
  ~1 Hz, excited by the transition, decays only through the primary vertical dampers and the
  pneumatics.
"""
from __future__ import annotations

import math
from typing import Callable

import exudyn as exu
import numpy as np
from exudyn.advancedUtilities import CreateSymbolicUserFunction
from exudyn.rigidBodyUtilities import RigidBodyInertia

from .guidance import TrackSampler
from .params import VehicleParams
from .track import TrackGeometry

BELLOWS = ("FL", "FR", "RL", "RR")
WHEELS = ("1L", "1R", "2L", "2R", "3L", "3R", "4L", "4R")

#: exudyn minor version this module was written and measured against (the API changes between
#: minor versions; tests/test_vehicle.py fails loudly on any other)
EXUDYN_TESTED_MINOR = "1.13"

_OUT = exu.OutputVariableType
esym = exu.symbolic


class MetroCar:
    """Metro car on rails whose heights are prescribed wheel by wheel, standing or running.

    Args:
        params: vehicle parameters (SI).
        rail_height_m: ``rail_height_m(t_s) -> (8,)`` vertical rail height [m] under each wheel
            in :data:`WHEELS` order, 0 = level; ``None`` = level track. Evaluated at the end of
            every internal time step (the contact damping uses the mean rail rate over the
            step). It should be 0 at t = 0 for a transient-free start. On a canted ``track`` it
            adds to the heights the cant gives.
        step_s: largest internal time step [s]; every :meth:`advance` is split into equal steps
            not larger than this.
        track: centre line the car runs along; ``None`` = unbounded straight level track along
            x. It must be straight and level under the whole car at the start (the start state
            is the static equilibrium on level track).
        speed_m_per_s: constant running speed v [m/s] (0 = standing); every body starts at v.
        start_s_m: arc length [m] of the car centre (midway between the bogie centres) at
            t = 0. Default: the rear wheelset at s = 0 on a ``track``, 0 without one.
        spectral_radius: generalized-alpha spectral radius at infinite frequency, 0 < rho <= 1
            (numerical damping of the ~250 Hz wheelset-on-contact modes).
        newton_abs_tol: Newton absolute tolerance on the residual (force scale [N]).
        newton_rel_tol: Newton tolerance relative to the initial residual of the step.
        reuse_jacobian: reuse the Newton Jacobian across :meth:`advance` calls (see module doc).
    """

    #: the stored Newton Jacobian is renewed at the next macro-step once the track heading has
    #: changed by more than this since it was computed [rad] (see :meth:`advance`)
    JACOBIAN_HEADING_TOL_RAD = 0.01

    def __init__(self, params: VehicleParams,
                 rail_height_m: Callable[[float], np.ndarray] | None = None,
                 step_s: float = 5e-3, *, track: TrackGeometry | None = None,
                 speed_m_per_s: float = 0.0, start_s_m: float | None = None,
                 spectral_radius: float = 0.8,
                 newton_abs_tol: float = 1e-4, newton_rel_tol: float = 1e-8,
                 reuse_jacobian: bool = True):
        if not step_s > 0.0:
            raise ValueError(f"step_s must be > 0, got {step_s}")
        if not math.isfinite(speed_m_per_s):
            raise ValueError(f"speed_m_per_s must be finite, got {speed_m_per_s!r}")
        self.params = params
        self.step_s = float(step_s)
        self._rail_fn = rail_height_m
        p = params
        g = p.gravity_m_per_s2
        # --- static loads on level track (the car is symmetric) ---
        self._F_static_N = p.carbody_mass_kg * g / 4.0
        self._P_axlebox_N = (p.carbody_mass_kg * g / 2.0 + p.bogie_mass_kg * g) / 4.0
        #: static vertical wheel load on level track [N]
        self.Q_static_N = self._P_axlebox_N + p.wheelset_mass_kg * g / 2.0
        self._delta_static_m = (self.Q_static_N / p.hertz_constant_N_per_m1_5) ** (2.0 / 3.0)
        # --- geometry at static equilibrium ---
        a = p.wheelbase_m / 2.0
        xb = p.bogie_centre_distance_m / 2.0
        #: bogie centre x [m], front then rear
        self.bogie_x_m = np.array([xb, -xb])
        #: wheelset centre x [m], wheelsets 1..4 from the front
        self.wheelset_x_m = np.array([xb + a, xb - a, -xb + a, -xb - a])
        self._z_wheelset_m = p.wheel_radius_m - self._delta_static_m
        self._bellow_height_m = p.airspring_upper_height_m - p.airspring_lower_height_m
        if self._bellow_height_m <= 0.0:
            raise ValueError("airspring_upper_height_m must exceed airspring_lower_height_m")
        self._init_run(track, float(speed_m_per_s), start_s_m)

        rail0 = self._rail_at(0.0)
        self._rail_cache = (0.0, rail0)  # (t, heights) of the last preStep evaluation

        self.SC = exu.SystemContainer()
        self.mbs = self.SC.AddSystem()
        self._build(rail0)
        self.mbs.Assemble()
        #: first global algebraic coordinate (Lagrange multiplier) of each guidance joint
        self._guidance_ae = [int(self.mbs.systemData.GetObjectLTGAE(j)[0])
                             for j in self._guidance_joints]
        self._init_solver(spectral_radius, newton_abs_tol, newton_rel_tol, reuse_jacobian)

        self._bellow_t = None  # time of the cached bellow crushing

    # ================================================================== run
    def _init_run(self, track: TrackGeometry | None, v: float, start_s: float | None) -> None:
        """Arc lengths at t = 0 and the track sampler; checks the straight, level start."""
        self.track = track
        #: running speed [m/s]
        self.speed_m_per_s = v
        if start_s is None:
            start_s = float(-self.wheelset_x_m[-1]) if track is not None else 0.0
        start_s = float(start_s)
        if not math.isfinite(start_s):
            raise ValueError(f"start_s_m must be finite, got {start_s!r}")
        #: arc length [m] of the car centre at t = 0
        self.start_s_m = start_s
        self._s0_wheelset = start_s + self.wheelset_x_m  # (4,) arc lengths at t = 0
        self._x0_m = start_s  # x of the car centre at t = 0 (the track starts at the origin)
        self._sampler = None
        self._canted = False
        self._s0_tracked = self._s0_wheelset  # arc lengths evaluated every step
        if track is None:
            self._guided = v != 0.0
            return
        if not isinstance(track, TrackGeometry):
            raise ValueError(f"track must be a TrackGeometry or None, got {type(track).__name__}")
        s = self._s0_wheelset
        if s.min() < 0.0 or s.max() > track.total_length_m:
            raise ValueError(f"the car (wheelsets at s = {s} m) is not on the track "
                             f"[0, {track.total_length_m}] m at t = 0")
        x, y = track.position_m(s)
        straight = (np.all(track.curvature_per_m(s) == 0.0) and np.all(track.cant_rad(s) == 0.0)
                    and np.all(np.abs(track.heading_rad(s)) <= 1e-12)
                    and np.all(np.abs(y) <= 1e-9) and np.all(np.abs(x - s) <= 1e-9))
        if not straight:
            raise ValueError("the track must be straight and level along x under the whole car "
                             f"at t = 0 (wheelsets at s = {s} m): start on the initial straight")
        self._sampler = TrackSampler(track)
        self._guided = True
        self._canted = any(getattr(seg, "cant_rad", 0.0) != 0.0 for seg in track.segments)
        if self._canted:  # the bellow axes follow the track plane under the bogie centres
            self._s0_tracked = np.concatenate([self._s0_wheelset, start_s + self.bogie_x_m])

    @property
    def s_m(self) -> float:
        """Arc length [m] of the car centre at the current time: start_s_m + v t."""
        return self.start_s_m + self.speed_m_per_s * self._t

    @property
    def t_end_max_s(self) -> float:
        """Latest time [s] the front wheelset is still on the track (inf without a track)."""
        v = self.speed_m_per_s
        if self.track is None or v == 0.0:
            return math.inf
        if v > 0.0:
            return (self.track.total_length_m - self._s0_wheelset[0]) / v
        return -self._s0_wheelset[-1] / v

    def _track_at(self, t: float) -> list[tuple[float, ...]]:
        """Track centre line (x, y, heading, cant, curvature, d(cant)/ds) under each wheelset
        and, on canted track, each bogie centre at time t: 4 (or 6) tuples."""
        s = (self._s0_tracked + self.speed_m_per_s * t).tolist()
        if self._sampler is None:
            return [(si, 0.0, 0.0, 0.0, 0.0, 0.0) for si in s]
        return self._sampler.at(s)

    # ================================================================== model
    def _build(self, rail0: np.ndarray) -> None:
        p, mbs = self.params, self.mbs
        gravity = [0.0, 0.0, -p.gravity_m_per_s2]

        def body(m, ixx, iyy, izz, pos):
            return mbs.CreateRigidBody(
                inertia=RigidBodyInertia(mass=m, inertiaTensor=np.diag([ixx, iyy, izz]),
                                         inertiaTensorAtCOM=True),
                referencePosition=[pos[0] + self._x0_m, pos[1], pos[2]],
                initialVelocity=[self.speed_m_per_s, 0.0, 0.0], gravity=gravity,
                nodeType=exu.NodeType.RotationRxyz)

        self._ground = mbs.CreateGround()
        self._carbody = body(p.carbody_mass_kg, p.carbody_inertia_xx_kg_m2,
                             p.carbody_inertia_yy_kg_m2, p.carbody_inertia_zz_kg_m2,
                             [0.0, 0.0, p.carbody_cog_height_m])
        self._bogies = [body(p.bogie_mass_kg, p.bogie_inertia_xx_kg_m2, p.bogie_inertia_yy_kg_m2,
                             p.bogie_inertia_zz_kg_m2, [x, 0.0, p.bogie_cog_height_m])
                        for x in self.bogie_x_m]
        self._wheelsets = [body(p.wheelset_mass_kg, p.wheelset_inertia_xx_kg_m2,
                                p.wheelset_inertia_yy_kg_m2, p.wheelset_inertia_zz_kg_m2,
                                [x, 0.0, self._z_wheelset_m])
                           for x in self.wheelset_x_m]
        self._sym = []  # symbolic variables and functions: must live as long as the system
        for iw in range(4):
            self._add_wheelset_guidance(iw)
            self._add_primary(iw)
        for k in range(4):
            self._add_airspring(k)
        for ib in range(2):
            self._add_bumpstop(ib)
        for j in range(8):
            self._add_contact(j, rail0[j])

    def _add_wheelset_guidance(self, iw: int) -> None:
        """Track guidance of wheelset ``iw`` (see module doc).

        ``GenericJoint`` between ground and the wheelset centre (both markers at the centre's
        position at t = 0, p0). The joint frame is ground's rotated by the offset rotation
        A = Rz(psi) Rx(-cant) (track heading, and the roll of the canted track plane; given to
        exudyn as Tait-Bryan xyz angles); in that frame the constraints read
            t . (p - p0) = xi(t),  l . (p - p0) = eta(t)  (t: tangent, l: lateral in the plane)
            t . e_y = 0,  t . e_z = 0  (e_y axle, e_z: wheelset axes),
        with (xi, eta) the position, relative to p0 in that frame, of the point at the static
        centre height z_w above the track centre line along the track plane's normal. Motion
        along that normal and roll about t stay free. The joint's reaction acts at the centre;
        the rails apply the lateral force at rail level, z_w lower: see :meth:`_set_rail_couples`.
        """
        mbs = self.mbs
        xi = esym.Real(f"xi{iw}", 0.0)  # [m]
        eta = esym.Real(f"eta{iw}", 0.0)  # [m]
        rx = esym.Real(f"rx{iw}", 0.0)  # Tait-Bryan angles of Rz(psi) Rx(-cant) [rad]
        ry = esym.Real(f"ry{iw}", 0.0)
        rz = esym.Real(f"rz{iw}", 0.0)
        zero = esym.Real(0.0)

        def offset(mbs, t, itemNumber, offsetUserFunctionParameters):
            return [xi, eta, zero, rx, ry, rz]

        pos = [float(self.wheelset_x_m[iw]) + self._x0_m, 0.0, self._z_wheelset_m]
        joint = mbs.CreateGenericJoint(itemNumbers=[self._ground, self._wheelsets[iw]],
                                       position=pos, constrainedAxes=[1, 1, 0, 0, 1, 1],
                                       show=False)
        if self._guided:
            fn = CreateSymbolicUserFunction(mbs, offset, "offsetUserFunction", joint)
            mbs.SetObjectParameter(joint, "offsetUserFunction", fn)
            self._sym += [fn, zero]
        if iw == 0:
            self._guidance_vars, self._guidance_joints = [], []
            self._rail_couple_loads = [mbs.CreateTorque(itemNumber=w, loadVector=[0.0, 0.0, 0.0],
                                                        show=False) for w in self._wheelsets]
        self._guidance_vars.append((xi, eta, rx, ry, rz))
        self._guidance_joints.append(joint)
        if iw == 0:
            self._joint_frame = [((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))] * 4

    def _add_primary(self, iw: int) -> None:
        """Left and right axlebox springs between bogie frame and wheelset ``iw``.

        Displacement u = 0 at the static position; the z offset carries the static axlebox load
        P (force on the wheelset -K (u - offset) = -P e_z). Intrinsic formulation (axes of the
        mid-frame between bogie and wheelset, force applied at the midpoint of the two markers
        on both bodies): no spurious couple P x (relative displacement), see module doc."""
        p = self.params
        ib = iw // 2
        K = np.diag([p.primary_stiffness_x_N_per_m, p.primary_stiffness_y_N_per_m,
                     p.primary_stiffness_z_N_per_m, 0.0, 0.0, 0.0])
        D = np.diag([p.primary_damping_x_N_s_per_m, p.primary_damping_y_N_s_per_m,
                     p.primary_damping_z_N_s_per_m, 0.0, 0.0, 0.0])
        off_z = -self._P_axlebox_N / p.primary_stiffness_z_N_per_m
        for y in (p.primary_lateral_spacing_m / 2.0, -p.primary_lateral_spacing_m / 2.0):
            self.mbs.CreateRigidBodySpringDamper(
                itemNumbers=[self._bogies[ib], self._wheelsets[iw]],
                localPosition0=[self.wheelset_x_m[iw] - self.bogie_x_m[ib], y,
                                self._z_wheelset_m - p.bogie_cog_height_m],
                localPosition1=[0.0, y, 0.0],
                stiffness=K, damping=D, offset=[0.0, 0.0, off_z, 0.0, 0.0, 0.0],
                useIntrinsicFormulation=True, show=False)

    def _bellow_plates(self, k: int) -> tuple[list[float], list[float]]:
        """Local positions of bellow ``k``'s lower plate (bogie) and upper plate (carbody)."""
        p = self.params
        ib = k // 2
        y = p.airspring_lateral_spacing_m / 2.0 * (1.0 if BELLOWS[k][1] == "L" else -1.0)
        lower = [0.0, y, p.airspring_lower_height_m - p.bogie_cog_height_m]
        upper = [float(self.bogie_x_m[ib]), y,
                 p.airspring_upper_height_m - p.carbody_cog_height_m]
        return lower, upper

    def _add_airspring(self, k: int) -> None:
        """Bellow ``k``: axial force law (symbolic, along the bellow axis n) and shear
        stiffness in x and y (intrinsic: mid-frame of bogie and carbody, at the midpoint)."""
        p, mbs = self.params, self.mbs
        bogie = self._bogies[k // 2]
        lower, upper = self._bellow_plates(k)
        F = esym.Real(f"F{k}", self._F_static_N)  # force at z = z0 [N]
        K = esym.Real(f"K{k}", 0.0)  # dF/dz [N/m]
        z0 = esym.Real(f"z0_{k}", 0.0)  # crushing at the last set_bellow_forces [m]
        if k == 0:  # bellow axis n per bogie: the track plane's normal (module doc)
            self._axis_vars = [tuple(esym.Real(f"n{c}{ib}", 1.0 if c == "z" else 0.0)
                                     for c in "xyz") for ib in range(2)]
            self._axis_now = [((0.0, 0.0, 1.0), (0.0, 0.0, 0.0))] * 2  # (n, dn/dt) per bogie
        nx, ny, nz = self._axis_vars[k // 2]
        h0 = self._bellow_height_m

        # displacement d = p_upper - p_lower - offset, offset = nominal height h0 e_z: crushing
        # z = h0 - (d + h0 e_z) . n (= -d_z for n = e_z, exactly); the connector force f acts as
        # -f on the upper plate (carbody), +f on the lower (bogie)
        def bellow_force(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
            z = h0 * (1.0 - nz) - (displacement[0] * nx + displacement[1] * ny
                                   + displacement[2] * nz)
            f = F + K * (z - z0)
            return [-f * nx, -f * ny, -f * nz]

        co = mbs.CreateCartesianSpringDamper(
            itemNumbers=[bogie, self._carbody], localPosition0=lower, localPosition1=upper,
            offset=[0.0, 0.0, self._bellow_height_m], show=False)
        fn = CreateSymbolicUserFunction(mbs, bellow_force, "springForceUserFunction", co)
        mbs.SetObjectParameter(co, "springForceUserFunction", fn)
        ks = p.bellow_shear_stiffness_N_per_m
        mbs.CreateRigidBodySpringDamper(
            itemNumbers=[bogie, self._carbody], localPosition0=lower, localPosition1=upper,
            stiffness=np.diag([ks, ks, 0.0, 0.0, 0.0, 0.0]), damping=np.zeros((6, 6)),
            offset=[0.0, 0.0, self._bellow_height_m, 0.0, 0.0, 0.0],
            useIntrinsicFormulation=True, show=False)
        if k == 0:
            self._bellows, self._bellow_vars = [], []
            # end moments of the vertical force pairs (see module doc), updated every step
            self._end_moment_loads = [mbs.CreateTorque(itemNumber=b, loadVector=[0.0, 0.0, 0.0],
                                                       show=False)
                                      for b in (self._carbody, *self._bogies)]
        self._bellows.append(co)
        self._bellow_vars.append((F, K, z0))
        self._force_law = [(self._F_static_N, 0.0, 0.0)] * (k + 1)  # (F, dF/dz, z0) as set
        self._sym.append(fn)

    def _add_bumpstop(self, ib: int) -> None:
        """Lateral bumpstop of bogie ``ib`` (see module doc): lateral force beyond the
        clearance (y of the mid-frame between bogie and carbody), between the bogie centre at
        the lower-plate height and the carbody point that coincides with it at static
        equilibrium."""
        p, mbs = self.params, self.mbs
        clearance = esym.Real(p.lateral_bumpstop_clearance_m)
        k = esym.Real(p.lateral_bumpstop_stiffness_N_per_m)
        zero = esym.Real(0.0)

        # displacement = carbody point relative to the bogie point in the mid-frame between
        # bogie and carbody (intrinsic formulation); the returned connector force f enters the
        # left-hand side like K u: it acts as -f on the carbody (marker 1), +f on the bogie
        # frame, both at the markers' midpoint
        def bumpstop_force(mbs, t, itemNumber, displacement, rotation, velocity, angularVelocity,
                           stiffness, damping, rotJ0, rotJ1, offset):
            d = displacement[1]
            f = k * (esym.max(d - clearance, zero) + esym.min(d + clearance, zero))
            return [zero, f, zero, zero, zero, zero]

        h = p.airspring_lower_height_m
        co = mbs.CreateRigidBodySpringDamper(
            itemNumbers=[self._bogies[ib], self._carbody],
            localPosition0=[0.0, 0.0, h - p.bogie_cog_height_m],
            localPosition1=[float(self.bogie_x_m[ib]), 0.0, h - p.carbody_cog_height_m],
            useIntrinsicFormulation=True, show=False)
        fn = CreateSymbolicUserFunction(mbs, bumpstop_force, "springForceTorqueUserFunction", co)
        mbs.SetObjectParameter(co, "springForceTorqueUserFunction", fn)
        if ib == 0:
            self._bumpstops = []
        self._bumpstops.append(co)
        self._sym += [fn, clearance, k, zero]

    def _add_contact(self, j: int, rail0_m: float) -> None:
        """Wheel ``WHEELS[j]``: unilateral Hertz contact against its prescribed rail height.

        Connector displacement u = p_contact - p_rail_base (global), rail base at z = 0, so the
        penetration is delta = rail_height - u_z."""
        p = self.params
        C, c = p.hertz_constant_N_per_m1_5, p.contact_damping_N_s_per_m
        name = WHEELS[j]
        iw = int(name[0]) - 1
        y = p.contact_spacing_m / 2.0 * (1.0 if name[1] == "L" else -1.0)
        rz = esym.Real(f"rail_z{j}", float(rail0_m))  # rail height [m]
        rv = esym.Real(f"rail_v{j}", 0.0)  # rail vertical rate [m/s]
        zero = esym.Real(0.0)

        def contact_force(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
            delta = rz - displacement[2]  # IfThenElse evaluates only the selected branch
            q = esym.max(C * delta * esym.sqrt(delta) + c * (rv - velocity[2]), zero)
            return [0.0, 0.0, -esym.IfThenElse(delta > 0.0, q, zero)]  # on the wheel: +Q e_z

        co = self.mbs.CreateCartesianSpringDamper(
            itemNumbers=[self._ground, self._wheelsets[iw]],
            localPosition0=[float(self.wheelset_x_m[iw]) + self._x0_m, y, 0.0],
            localPosition1=[0.0, y, -p.wheel_radius_m], show=False)
        fn = CreateSymbolicUserFunction(self.mbs, contact_force, "springForceUserFunction", co)
        self.mbs.SetObjectParameter(co, "springForceUserFunction", fn)
        if j == 0:
            self._contacts, self._rail_vars = [], []
        self._contacts.append(co)
        self._rail_vars.append((rz, rv))
        self._sym += [fn, zero]

    # ================================================================== rail and track
    def _rail_at(self, t: float, track_state=None) -> np.ndarray:
        """(8,) rail heights [m] at time t: cant of the track plus ``rail_height_m``."""
        if self._rail_fn is None:
            h = np.zeros(8)
        else:
            h = np.array(self._rail_fn(t), dtype=float)
            if h.shape != (8,):
                raise ValueError(f"rail_height_m(t) must return shape (8,), got {h.shape}")
        if self._canted:
            b = self.params.contact_spacing_m / 2.0
            for iw, (_, _, _, cant, _, _) in enumerate((track_state or self._track_at(t))[:4]):
                if cant != 0.0:
                    dz = b * math.sin(cant)  # track plane rolled by -cant: left down, right up
                    h[2 * iw] -= dz
                    h[2 * iw + 1] += dz
        return h

    def _set_guidance(self, track_state) -> None:
        """Guidance offsets (see :meth:`_add_wheelset_guidance`) for the given track state."""
        for iw, ((xi, eta, rx, ry, rz), (x, y, psi, cant, _, _)) in enumerate(
                zip(self._guidance_vars, track_state)):
            dx = x - (float(self.wheelset_x_m[iw]) + self._x0_m)
            c, s = math.cos(psi), math.sin(psi)
            if cant == 0.0:
                xi.SetValue(c * dx + s * y)
                eta.SetValue(-s * dx + c * y)
                rz.SetValue(psi)
                if self._canted:
                    rx.SetValue(0.0)
                    ry.SetValue(0.0)
                self._joint_frame[iw] = ((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0))
                continue
            # A = Rz(psi) Rx(g), g = -cant = Rx(a) Ry(b) Rz(psi'):
            # A = [[c, -s cg, s sg], [s, c cg, -c sg], [0, sg, cg]]; target point
            # (x, y, 0) + z_w n (n = A e_z), p0 = (x0, 0, z_w): A^T (target - p0) =
            # A^T (dx, y, 0) + (0, 0, z_w) - z_w A^T e_z
            cg, sg = math.cos(cant), -math.sin(cant)
            xi.SetValue(c * dx + s * y)
            eta.SetValue(-s * cg * dx + c * cg * y - self._z_wheelset_m * sg)
            rx.SetValue(math.atan2(c * sg, cg))
            ry.SetValue(math.asin(s * sg))
            rz.SetValue(math.atan2(s * cg, c))
            self._joint_frame[iw] = ((c, -s * cg, s * sg), (s, c * cg, -c * sg), (0.0, sg, cg))

    def _set_end_moments(self) -> None:
        """End moments of the bellow force pairs at the current state (module doc).

        Each pair F n (n: bellow axis) acts at the plate centres, whose relative position is
        d = p_upper - p_lower (connector displacement + nominal height); the couple d x F n it
        leaves unbalanced is returned as -(d x F n) / 2 on the carbody and on the bogie frame
        each, which puts the pair's line of action through the bellow's midpoint for both
        bodies."""
        get, disp = self.mbs.GetObjectOutput, _OUT.Displacement
        h0 = self._bellow_height_m
        cx, cy, cz = 0.0, 0.0, 0.0  # carbody
        bogie = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
        for k, (co, (F0, K, z0)) in enumerate(zip(self._bellows, self._force_law)):
            nx, ny, nz = self._axis_now[k >> 1][0]
            dx, dy, dz = get(co, disp)
            dz += h0
            F = F0 + K * (h0 - (dx * nx + dy * ny + dz * nz) - z0)  # force law, on the carbody
            hF = -0.5 * F  # -(d x F n) / 2
            mx = hF * (dy * nz - dz * ny)
            my = hF * (dz * nx - dx * nz)
            mz = hF * (dx * ny - dy * nx)
            cx += mx
            cy += my
            cz += mz
            tb = bogie[k >> 1]
            tb[0] += mx
            tb[1] += my
            tb[2] += mz
        set_load = self.mbs.SetLoadParameter
        loads = self._end_moment_loads
        set_load(loads[0], "loadVector", [cx, cy, cz])
        set_load(loads[1], "loadVector", bogie[0])
        set_load(loads[2], "loadVector", bogie[1])

    def _set_rail_couples(self) -> None:
        """Move the guidance reactions' line of action from the wheelset centre to rail level.

        The joint applies the lateral (and longitudinal) reaction f at the wheelset centre; the
        rails apply it at the contact points, z_w lower. The difference is the couple
        (-z_w n) x f (n: the joint frame's z, the track plane normal), applied as a torque on
        the wheelset, from the reaction at the start of the step. Without it the wheel loads
        would balance an overturning moment short of sum(m a) z_w (10 kNm, 27 % in the paper's
        curve)."""
        lam = self.mbs.systemData.GetAECoordinates()  # joint ForceLocal = its first 3 multipliers
        zw = self._z_wheelset_m
        set_load = self.mbs.SetLoadParameter
        for i0, load, A in zip(self._guidance_ae, self._rail_couple_loads, self._joint_frame):
            # reaction on the ground marker, joint frame: (fx, fy, fz); on the wheelset
            # (-fx, -fy, 0); couple (-z_w e_z) x (-fx, -fy, 0) = z_w (-fy, fx, 0), joint frame
            mx, my = -zw * lam[i0 + 1], zw * lam[i0]
            set_load(load, "loadVector", [A[0][0] * mx + A[0][1] * my,
                                          A[1][0] * mx + A[1][1] * my,
                                          A[2][0] * mx + A[2][1] * my])

    def _set_bellow_axes(self, track_state) -> None:
        """Bellow axes n = normal of the canted track plane at each bogie centre (and dn/dt)."""
        v = self.speed_m_per_s
        for ib, (_, _, psi, c, kappa, dc) in enumerate(track_state[4:6]):
            sc, cc, sp, cp = math.sin(c), math.cos(c), math.sin(psi), math.cos(psi)
            n = (-sc * sp, sc * cp, cc)
            cdot, psidot = v * dc, v * kappa
            ndot = (-cc * sp * cdot - sc * cp * psidot, cc * cp * cdot - sc * sp * psidot,
                    -sc * cdot)
            for var, value in zip(self._axis_vars[ib], n):
                var.SetValue(value)
            self._axis_now[ib] = (n, ndot)

    def _pre_step(self, mbs, t: float) -> bool:
        """PreStep user function: end moments of the bellow force pairs at the start of the
        step, guidance offsets and rail heights at the step end t, mean rail rate over the
        step."""
        self._set_end_moments()
        self._set_rail_couples()  # before the joint frames move on to t
        state = self._track_at(t) if self._guided else None
        if self._guided:
            self._set_guidance(state)
            self._heading_now = state[0][2]
        if self._canted:
            self._set_bellow_axes(state)
        if self._rail_fn is None and not self._canted:
            return True  # level rails: nothing else changes
        t0 = mbs.systemData.GetTime(exu.ConfigurationType.StartOfStep)
        tc, zc = self._rail_cache
        z0 = zc if t0 == tc else self._rail_at(t0)
        z1 = self._rail_at(t, state)
        v = (z1 - z0) / (t - t0) if t > t0 else np.zeros(8)
        for (rz, rv), zj, vj in zip(self._rail_vars, z1.tolist(), v.tolist()):
            rz.SetValue(zj)
            rv.SetValue(vj)
        self._rail_cache = (t, z1)
        return True

    # ================================================================== solver
    def _init_solver(self, rho: float, abs_tol: float, rel_tol: float, reuse: bool) -> None:
        s = exu.SimulationSettings()
        s.solution.file.write = False
        s.solution.sensors.active = False
        s.linearSolver.solverType = exu.LinearSolverType.EigenDense  # fastest at this size
        ti = s.timeIntegration
        ti.verboseMode = 0
        ti.numberOfSteps = 1
        ti.startTime = 0.0
        ti.endTime = self.step_s
        ti.adaptiveStep = True  # lets SolveSteps clamp a step to the macro-step end
        ti.generalizedAlpha.spectralRadius = rho
        ti.newton.useModifiedNewton = True
        ti.newton.absoluteTolerance = abs_tol
        ti.newton.relativeTolerance = rel_tol
        self._settings = s
        self.mbs.SetPreStepUserFunction(self._pre_step)
        if reuse:
            # a second solver on the same system computes fresh Jacobians on demand (calling the
            # main solver's ComputeNewtonJacobian from its own user function would recurse)
            self._jac_solver = exu.MainSolverImplicitSecondOrder()
            if not self._jac_solver.InitializeSolver(self.mbs, s):
                raise RuntimeError("exudyn: InitializeSolver failed")
        self._solver = exu.MainSolverImplicitSecondOrder()
        if not self._solver.InitializeSolver(self.mbs, s):
            raise RuntimeError("exudyn: InitializeSolver failed")
        if reuse:
            self._solver.SetUserFunctionComputeNewtonJacobian(self.mbs, self._jacobian)
        self._ti = s.timeIntegration  # handles (references into the C++ objects)
        self._it = self._solver.it
        self._jac_h = None  # step size of the stored Jacobian
        self._jac_heading = 0.0  # track heading under wheelset 1 when it was computed [rad]
        self._heading_now = 0.0  # track heading under wheelset 1 at the last step end [rad]
        self._jac_may_skip = False
        self.jacobian_count = 0  # fresh Jacobians computed (diagnostics)
        self._t = 0.0

    def _jacobian(self, solver, mbs, settings) -> bool:
        """Newton Jacobian user function of the main solver (see module doc)."""
        h = solver.it.currentStepSize
        if self._jac_may_skip and self._jac_h is not None and abs(h - self._jac_h) <= 1e-9 * h:
            self._jac_may_skip = False  # later requests in this advance come from Newton
            return True  # keep the stored (already factorizable) Jacobian
        self._jac_may_skip = False
        js = self._jac_solver
        js.it.currentStepSize = h
        # ComputeNewtonJacobian adds the solver's own stored mass matrix: the second solver's
        # would stay the one of t = 0, but the Rxyz mass matrix changes with the rotation (yaw
        # in a curve: 10 % off at 0.1 rad, and Newton diverges)
        js.ComputeMassMatrix(mbs)
        js.ComputeNewtonJacobian(mbs, settings)
        solver.SetSystemJacobian(js.GetSystemJacobian())
        self._jac_h = h
        self._jac_heading = self._heading_now
        self.jacobian_count += 1
        return True

    # ================================================================== interface
    def static_bellow_forces_N(self) -> np.ndarray:
        """(4,) airspring forces [N] carrying the carbody in static equilibrium on level track."""
        return np.full(4, self._F_static_N)

    @property
    def t_s(self) -> float:
        """Current simulation time [s]."""
        return self._t

    def _bellow_state(self) -> None:
        """Crushing and rate of the bellows at the current state (cached per time)."""
        if self._bellow_t == self._t:
            return
        get = self.mbs.GetObjectOutput
        h0 = self._bellow_height_m
        z, zdot = [], []
        for k, co in enumerate(self._bellows):
            (n, ndot) = self._axis_now[k // 2]
            d = get(co, _OUT.Displacement)  # p_upper - p_lower - h0 e_z
            v = get(co, _OUT.Velocity)
            # z = h0 - (d + h0 e_z) . n  (see _add_airspring)
            z.append(h0 * (1.0 - n[2]) - (d[0] * n[0] + d[1] * n[1] + d[2] * n[2]))
            zdot.append(-(v[0] * n[0] + v[1] * n[1] + v[2] * n[2])
                        - (d[0] * ndot[0] + d[1] * ndot[1] + (d[2] + h0) * ndot[2]))
        self._z, self._zdot = np.array(z), np.array(zdot)
        self._bellow_t = self._t

    def bellow_crushing(self) -> tuple[np.ndarray, np.ndarray]:
        """Bellow crushing z [m] and its rate [m/s], each (4,) in :data:`BELLOWS` order.

        z = nominal bellow height - (p_upper_plate - p_lower_plate) . n, n the bellow axis
        (global z on uncanted track, see module doc), positive in compression, 0 at static
        equilibrium on level track (bellow at nominal height). In a curve the carbody rolls
        outward: the outer bellows are crushed (z > 0), the inner ones extend."""
        self._bellow_state()
        return self._z.copy(), self._zdot.copy()

    def set_bellow_forces(self, F_N: np.ndarray, dF_dz_N_per_m: np.ndarray | None = None) -> None:
        """Airspring forces [N] for the following :meth:`advance`, (4,) in :data:`BELLOWS` order.

        F(z) = F_N + dF_dz (z - z_now): a force pair along the bellow axis (vertical on
        uncanted track) pushing the carbody up and the bogie down; ``dF_dz`` [N/m] is the
        instantaneous pneumatic stiffness (linearised implicit coupling), ``None`` = 0 (force
        held constant). z_now is the crushing of
        :meth:`bellow_crushing` at the current state, so pass F_N for the current state.

        Note: a jump of F_N between macro-steps enters generalized-alpha with about half an
        internal step of delay (the step starts from the old acceleration); smooth force
        histories, as from a pneumatic model, are not affected."""
        F = np.asarray(F_N, dtype=float).reshape(4)
        dF = np.zeros(4) if dF_dz_N_per_m is None else np.asarray(dF_dz_N_per_m, float).reshape(4)
        if not (np.all(np.isfinite(F)) and np.all(np.isfinite(dF))):
            raise ValueError(f"non-finite bellow force or stiffness: F={F}, dF/dz={dF}")
        self._bellow_state()
        for (Fv, Kv, z0v), Fk, Kk, zk in zip(self._bellow_vars, F.tolist(), dF.tolist(),
                                             self._z.tolist()):
            Fv.SetValue(Fk)
            Kv.SetValue(Kk)
            z0v.SetValue(zk)
        self._force_law = list(zip(F.tolist(), dF.tolist(), self._z.tolist()))

    def advance(self, t_end_s: float) -> None:
        """Integrate from :attr:`t_s` to ``t_end_s`` [s] in equal steps <= ``step_s``."""
        span = t_end_s - self._t
        if span < -1e-12:
            raise ValueError(f"advance: t_end_s={t_end_s} is before t_s={self._t}")
        if span <= 1e-12:
            return
        if t_end_s > self.t_end_max_s + 1e-9:
            raise ValueError(f"advance: at t_end_s={t_end_s} s the front wheelset would have "
                             f"left the track (t_end_max_s={self.t_end_max_s} s)")
        n = max(1, math.ceil(span / self.step_s - 1e-9))
        it = self._it
        self._ti.endTime = t_end_s
        it.endTime = t_end_s
        it.maxStepSize = span / n
        # keep the stored Jacobian unless the car has turned (the constraint directions and
        # the rotational mass matrix follow the heading)
        turned = abs(self._heading_now - self._jac_heading)
        self._jac_may_skip = turned <= self.JACOBIAN_HEADING_TOL_RAD
        ok = self._solver.SolveSteps(self.mbs, self._settings)
        self._t = float(it.currentTime)
        if not ok:
            raise RuntimeError(f"exudyn: time integration failed at t={self._t} s "
                               f"(advance to {t_end_s} s)")
        self._t = float(t_end_s)

    def wheel_loads_N(self) -> np.ndarray:
        """(8,) vertical wheel-rail forces Q >= 0 [N] at the current state, :data:`WHEELS` order."""
        get = self.mbs.GetObjectOutput
        # the contact connector's force f acts as -f = +Q e_z on the wheel
        return np.array([-get(co, _OUT.Force)[2] for co in self._contacts])

    def carbody_roll_rad(self) -> float:
        """Carbody roll angle [rad], right-hand about its own x axis (forward): positive = left
        side up, i.e. the outward roll of a left-hand curve (negative in a right-hand one).
        Yaw-independent: the angle of the body's y axis above the horizontal plane."""
        A = np.asarray(self.mbs.GetObjectOutputBody(self._carbody, _OUT.RotationMatrix))
        A = A.reshape(3, 3)
        return float(math.atan2(A[2, 1], A[2, 2]))

    def carbody_lateral_m(self) -> float:
        """Lateral offset [m] of the carbody centre of gravity from the track centre line,
        positive to the left, measured horizontally along the track normal at the car centre's
        nominal arc length :attr:`s_m`. In a curve of radius R this includes the geometric
        offset of a body between bogies on the chord: (bogie centre distance)^2 / (8 R) to the
        inside (0.125 m at R = 100 m) -- see :meth:`secondary_lateral_m` for the suspension
        deflection alone."""
        x, y, _ = self.mbs.GetObjectOutputBody(self._carbody, _OUT.Position)
        if self._sampler is None:
            return float(y)
        xt, yt, heading = self._sampler.at([self.s_m])[0][:3]
        return float(-math.sin(heading) * (x - xt) + math.cos(heading) * (y - yt))

    def secondary_lateral_m(self) -> np.ndarray:
        """(2,) lateral secondary deflection [m] at the bumpstops, front and rear bogie: carbody
        relative to bogie frame at the bumpstop (bogie centre, lower-plate height), along the
        y axis of the mid-frame between the two (positive: carbody to the left). The bumpstop
        engages beyond +-``lateral_bumpstop_clearance_m``."""
        get = self.mbs.GetObjectOutput
        return np.array([get(co, _OUT.DisplacementLocal)[1] for co in self._bumpstops])

    def bumpstop_forces_N(self) -> np.ndarray:
        """(2,) lateral bumpstop forces [N] on the carbody, front and rear bogie, along the same
        axis as :meth:`secondary_lateral_m` (0 inside the clearance, opposite to the deflection
        beyond it)."""
        get = self.mbs.GetObjectOutput
        # the connector force acts as -f on the carbody (see _add_bumpstop)
        return np.array([-get(co, _OUT.ForceLocal)[1] for co in self._bumpstops])
