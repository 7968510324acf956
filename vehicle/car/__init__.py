"""Exudyn multibody model of the metro car (paper section 4, Table 3), standing on prescribed rail
heights (twist test) or running at constant speed along a track (curve entry, paper section 4.2):
:class:`MetroCar`.

The package, by what its files hold (each part a small object that receives what it needs
explicitly; :class:`MetroCar` composes them and keeps the public interface):

* :mod:`.model`: :class:`MetroCar`, the façade: builds the parts in order, the co-simulation
  interface (:meth:`~MetroCar.bellow_crushing`, :meth:`~MetroCar.set_bellow_forces`,
  :meth:`~MetroCar.advance`), the outputs;
* :mod:`.options`: what a car is asked for, three frozen groups (:class:`ModelOptions`,
  :class:`RunSettings`, :class:`SolverSettings`) in :class:`CarOptions`;
* :mod:`.statics`: the reference configuration (static loads and positions);
* :mod:`.path`: where the car is along its track over time (arc lengths, speed profile);
* :mod:`.contact`: contact guidance's table and law and where it holds the wheelsets at rest;
* :mod:`.build`: the bodies, the guidance, the primary suspension, the contacts, the flexible
  track: the exudyn model as built (:class:`~.build.CarModel`, its indices and variables);
* :mod:`.secondary`: the airsprings, bumpstops and optional components as built;
* :mod:`.track_input`: the track under the car at a time (centre line, rail heights,
  irregularities, the contact law's rails);
* :mod:`.hooks`: what is set before every internal step (guidance frames, rail heights, the
  contact's track frames);
* :mod:`.bellows`: the airspring force laws the co-simulation sets and the bellows' crushing;
* :mod:`.maxwell`: the Maxwell dampers' internal states, stepped after every step;
* :mod:`.solver`: the solver and the reuse of its Newton Jacobian;
* :mod:`.wheel_drive`: traction and braking through the wheels (torques, the driver's law);
* :mod:`.outputs`: the quantities the car reports (wheel loads, wheel-rail forces, roll, ...);
* :mod:`.linear`: the car linearised about steady running (contact guidance).

Bodies: carbody, two bogie frames, four wheelsets (rigid, 6 coordinates each, Tait-Bryan xyz).
Coordinates: x forward (running direction at the start), y to the left, z up; rail top at z = 0
on level track.

* Primary suspension: one spring-damper per axlebox (``RigidBodySpringDamper``), x/y/z stiffness
  and damping from :class:`~vehicle.params.VehicleParams`.
* Secondary suspension (airsprings), per bellow, one ``RigidBodySpringDamper`` in exudyn's
  intrinsic formulation between the lower plate (bogie frame) and the upper plate (carbody):
  the plate offset d is measured in the mid-frame between the two bodies and the force is
  applied at the midpoint of the plate centres on both bodies. Its symbolic user function gives
    - the axial force F(t, z) = F_n + dF/dt (t - t_n) + dF/dz (z - z_n) along the mid-frame's z
      axis (the bellow axis: the mean of the plates' normals; on canted track it follows the
      bodies), pushing the carbody up and the bogie down, with the crushing z = h0 - d_z;
    - shear stiffness across it (d_x, d_y).
  A point-to-point spring would add a negative lateral stiffness -F/L; this force does not turn
  with the plate offset, only with the bodies' mean roll (a lateral component F (phi_c +
  phi_b)/2 in a curve: the carbody leans on its bellows' axes).
  The bellow's effective area as a function of its height belongs to the pneumatic bellow model
  (force = gauge pressure x effective area, volume): the vehicle side only receives the force
  law through :meth:`MetroCar.set_bellow_forces`.
* Lateral bumpstops, one per bogie: between bogie frame and carbody at the bogie centre, at the
  height of the lower bellow plate; lateral force k_bs (|d| - clearance) beyond the clearance.
* Optional secondary components (each off by default, and then not built at all, so that a car
  without them is the same model, bit for bit): the anti-roll bar (a pure roll couple about the
  mid-frame's x axis), traction rods (longitudinal spring-dampers at ``traction_rod_height_m``),
  secondary dampers (vertical, lateral, yaw; each a (bi)linear damper in series with its
  mounting stiffness, a Maxwell element, or a plain damper on a rigid mounting), the emergency
  spring and vertical bumpstop in series with each bellow (:meth:`MetroCar.bellow_crushing`
  stays the bellow's own crushing, the quantity the pneumatic force law is written in).
* Wheelset guidance, ``guidance="kinematic"`` (the paper's model): a ``GenericJoint`` to ground at
  rail level, whose frame follows the track (heading and cant at the wheelset's arc length
  s_i(t) = s0_i + v t), locks each wheelset's longitudinal and lateral position, pitch and yaw
  (radial wheelsets); vertical motion and roll stay free on vertical Hertz contacts per wheel,
  Q = max(0, C_H delta^1.5 + c d(delta)/dt), against the rail heights the track's cant and the
  optional ``rail_height_m`` prescribe. No lateral wheel-rail forces: the guidance carries them.
* Wheelset guidance, ``guidance="contact"``: the wheelsets are free laterally, in yaw and along
  the track, held on the rails by the contact forces of :mod:`vehicle.wheelrail` alone (the
  S1002/UIC60 contact table, Hertz normal force along the contact normal, Kalker's creep forces
  with Shen-Hedrick-Elkins saturation; each wheelset's spin is a coordinate). The car is driven
  at its centre: a joint holds the carbody's position along the track tangent at
  s_c(t) = s_c0 + v t. Before each internal step every wheelset gets its track frame where it is.
  With ``drive`` (:mod:`.wheel_drive`) there is no such joint: torques on the wheelsets (reacted
  on the bogie frames) move the car along a speed profile that may stop and start, and the
  longitudinal creep forces carry its inertia.
  The law runs compiled (numba) as one force user function for the whole car with a
  finite-difference Jacobian. Standstill: creepages are divided by max(v, 0.01 m/s).
* Track: rigid (the rails are where the geometry puts them) or flexible
  (:class:`~vehicle.params.TrackStructure`: under each wheelset a track body with vertical and
  roll freedom on the foundation's springs and dampers, which receives the opposite of the
  contact forces).

Newton's third law holds in the strong form (moment balance): every ``RigidBodySpringDamper``
uses exudyn's intrinsic formulation (axes of the mid-frame, force at the midpoint of the two
markers on both bodies), and the guidance reacts at rail level, where the rails apply the
lateral force; tests/vehicle/test_vehicle_curve.py checks the wheel load transfer in a curve against
the overturning moment.

Reference configuration: static equilibrium on level track under
:meth:`MetroCar.static_bellow_forces_N`: the bodies sit at their static positions, the primary
springs carry their static loads, each wheel penetrates its rail by the Hertz deflection; with a
speed every body starts at it on the initial straight, so a run starts without a settling
transient.

Force laws are exudyn symbolic user functions (they run in C++); their inputs (rail heights and
rates, the bellow force law, the guidance frames) are named symbolic variables set from Python.

Solver (:mod:`.solver`): implicit generalized-alpha (spectral radius
:data:`SPECTRAL_RADIUS`), driven macro-step by macro-step with
``MainSolverImplicitSecondOrder.SolveSteps`` (state-exact continuation). The Newton Jacobian is
kept across macro-steps while the step size is unchanged and the track heading has turned by
less than :attr:`MetroCar.JACOBIAN_HEADING_TOL_RAD` (the bellow stiffness is ~1e-4 of the
effective mass stiffness M/(beta h^2)); a fresh one is computed with a second solver on the same
system when the heading has turned or Newton asks for it. Newton's absolute tolerance follows the
round-off of the coordinates far from the origin, where the residual cannot be brought below the
axlebox springs' longitudinal stiffness times ulp(x) (:attr:`.solver.CarSolver.ROUNDOFF_SAFETY`).

Known limits of kinematic guidance (contact guidance has none of them):

* radial wheelsets: in a curve the two wheelsets of a bogie are 2a/R apart in yaw and the stiff
  primary takes an internal yaw moment real, creep-steered wheelsets would not see (it barely
  touches roll and vertical loads);
* the contact forces stay vertical on canted track and the guidance takes the in-plane lateral
  force: Q is the vertical load, not the load normal to the track plane;
* the guidance prescribes every wheelset's arc length, so the bogie centres sit a chord apart in
  a curve and traction rods take the difference as an internal force (falling with 1/R^2).

The paper's car has no hydraulic dampers: its ~1 Hz sway/roll mode decays only through the
primary dampers and the pneumatics unless secondary dampers are given. docs/models.md and
docs/wheel_rail.md give the measurements behind these choices.

This package must not import ``pneumatics`` or ``cosim``.
"""
from ..errors import Derailed
from ..params import BELLOWS, WHEELS, ContactParams, TrackStructure, VehicleParams
from .model import EXUDYN_TESTED_MINOR, MetroCar
from .options import SPECTRAL_RADIUS, CarOptions, ModelOptions, RunSettings, SolverSettings
from .secondary import SYMBOLIC_OPS
from .wheel_drive import WheelDrive

__all__ = ["MetroCar", "CarOptions", "ModelOptions", "RunSettings", "SolverSettings", "SPECTRAL_RADIUS",
           "EXUDYN_TESTED_MINOR", "WHEELS", "BELLOWS", "Derailed", "ContactParams", "TrackStructure",
           "VehicleParams", "SYMBOLIC_OPS", "WheelDrive"]
