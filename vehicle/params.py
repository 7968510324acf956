"""Parameters of the metro car multibody model (SI units, names carry the unit).

The paper (Table 3) gives only the masses, the bogie centre distance and the wheelbase. Every
other value is a documented default: the Manchester benchmark passenger vehicle (Iwnicki 1998,
"The Manchester Benchmarks for Rail Vehicle Simulation") scaled to a metro car, or textbook
reasoning. The comments next to the fields are part of the documentation: ``pneumorail presets
paper_metro_car`` prints them with the values as a parameter file.

Scaling rules used below (Manchester -> metro):
  * load ratio per axlebox: Manchester (32 000/2 + 2 615) kg, metro (17 000/2 + 1 900) kg
    -> 0.558; primary stiffness and damping are scaled by it (same static deflection, ~37 mm);
  * inertias scale with mass, and pitch/yaw inertias also with the square of the length ratio
    (bogie centres 10 m vs 19 m, wheelbase 2.0 m vs 2.56 m).

Only ``float``/``int`` fields (real classes in ``dataclasses.fields(...)[i].type``, no string
annotations), so a generic loader can fill the dataclass by introspection.

Optional secondary components (anti-roll bar, secondary dampers, traction rod, emergency spring,
vertical bumpstop; see the last sections of :class:`VehicleParams`) are all off by default: the
paper's car has none of them, and with them off the model is the same, bit for bit. Their
typical values are collected, with sources, in :func:`metro_car_arb_dampers`. An ``inf``
stiffness means a rigid connection (no series spring), an ``inf`` blow-off velocity a linear
damper; 0 damping or stiffness means the component is absent.

Textbook sources for the typical ranges quoted below:
  [I] S. Iwnicki (ed.), Handbook of Railway Vehicle Dynamics, CRC Press, 2006 (2nd ed. 2019):
      chapter "Suspension components" (air springs with emergency springs, hydraulic dampers
      with series stiffness and blow-off, anti-roll bars, traction rods);
  [KS] K. Knothe, S. Stichel, Rail Vehicle Dynamics, Springer, 2017: secondary suspensions of
      passenger vehicles, roll coefficient and anti-roll bars;
  [M] S. Iwnicki, The Manchester Benchmarks for Rail Vehicle Simulation, Vehicle System
      Dynamics 30 (1998) 295-313: secondary vertical damper 20 kN s/m per side on a 32 t body.
Values not taken from these are reasoned from this car's masses and geometry; they are typical
orders of magnitude, not the data of one particular vehicle.
"""
import dataclasses
import math
from dataclasses import dataclass, field

from pneumorail.quantities import plausible, positive, ranged

#: Bellows (airsprings): front/rear bogie, left/right in the running direction.
BELLOWS = ("FL", "FR", "RL", "RR")
#: default spectral radius of the implicit integrator (generalized-alpha) at infinite frequency.
#: A linear cant ramp steps the rails' roll rate and rings each wheelset's ~240 Hz roll on its
#: contacts (omega h ~ 7.5 at 5 ms): with 0.8 those impacts were integrated unstably on canted
#: track (balanced and excess cant on the paper's curve diverged, kinematic and contact
#: guidance); 0.5 damps them within a few steps and runs every case of the cant x speed x radius
#: x transition matrix (benchmarks/track_matrix.py), while the converged results of the
#: paper's scenarios move by less than their own discretisation error (docs/models.md,
#: "Numerical damping").
SPECTRAL_RADIUS = 0.5

#: Wheels: wheelset 1..4 from the front, left/right in the running direction.
WHEELS = ("1L", "1R", "2L", "2R", "3L", "3R", "4L", "4R")
#: wheelsets, "1" ... "4" from the front (from the wheel names)
WHEELSETS = tuple(dict.fromkeys(wheel[:-1] for wheel in WHEELS))
#: Floor points where the carbody's accelerations are measured: above the front bogie centre, at
#: the car centre, above the rear bogie centre (at ``floor_height_m``; EN 12299's positions).
FLOOR_POINTS = ("front", "centre", "rear")


#: ranges of the vehicle parameters (field metadata, :mod:`pneumorail.quantities`): every parameter is
#: a mass, inertia, length, height above rail, stiffness, damping or clearance, none negative (0: the
#: component is absent); the geometry and masses within what rail vehicles have, from a tram module
#: to a loaded locomotive, so that a value typed in the wrong unit (tonnes, millimetres) is refused
#: with the slip named. Stiffnesses and dampings: 0 (absent) or inf (rigid), else within what
#: suspension elements have; a value in kN/m or kN s/m typed as N/m is a thousand times too small.
_HEIGHT = plausible(0.0, 5.0, "m", "a height above the rail top")
_FREE_TRAVEL = plausible(0.0, 0.3, "m", "a bumpstop's free travel")
_SPRING = plausible(1e3, 1e10, "N/m", "a spring", zero_or_inf=True)
_DAMPER = plausible(10.0, 1e7, "N s/m", "a damper", zero_or_inf=True)
_TORSION = plausible(1e3, 1e9, "N m/rad", "a torsion spring", zero_or_inf=True)
_PRIMARY_SPRING = plausible(1e3, 1e10, "N/m", "a primary spring")


def _inertia(body: str):
    """The range of an inertia of ``body`` (field metadata)."""
    return plausible(1.0, 1e8, "kg m^2", f"a {body}'s inertia", low_inclusive=False)


@dataclass(frozen=True)
class VehicleParams:
    """Metro car: one carbody, two bogie frames, four wheelsets; purely pneumatic secondary."""

    # --- masses (paper Table 3) ---
    carbody_mass_kg: float = field(default=17000.0, metadata=plausible(2000.0, 150000.0, "kg", "a carbody"))  # Table 3
    # Table 3 (bogie frame)
    bogie_mass_kg: float = field(default=1900.0, metadata=plausible(200.0, 20000.0, "kg", "a bogie frame"))
    wheelset_mass_kg: float = field(default=800.0, metadata=plausible(100.0, 5000.0, "kg", "a wheelset"))  # Table 3

    # --- geometry ---
    # Table 3
    bogie_centre_distance_m: float = field(default=10.0, metadata=plausible(2.0, 40.0, "m", "between the bogie centres"))
    wheelbase_m: float = field(default=2.0, metadata=plausible(1.0, 5.0, "m", "a bogie's wheelbase"))  # Table 3
    # Nominal lateral distance of the two wheel-rail contact points, standard gauge 1435 mm.
    contact_spacing_m: float = field(default=1.5, metadata=plausible(0.9, 1.8, "m", "between the wheels' contact points, "
                                                                                    "gauges 1000-1676 mm"))
    # 840 mm tread diameter: usual for metro cars (Manchester mainline vehicle: 0.46 m).
    wheel_radius_m: float = field(default=0.42, metadata=plausible(0.15, 0.8, "m", "a wheel's rolling radius"))
    # Axlebox (primary spring) lateral spacing: Manchester 2 x 1.0 m, typical of 1435 mm bogies.
    primary_lateral_spacing_m: float = field(default=2.0, metadata=plausible(0.5, 4.0, "m", "across the car"))
    # Airspring lateral spacing: Manchester secondary 2 x 1.0 m; metro bogies use 1.8-2.0 m.
    airspring_lateral_spacing_m: float = field(default=2.0, metadata=plausible(0.5, 4.0, "m", "across the car"))
    # Bellow lower plate (on the bogie frame) above rail top at static equilibrium: top of a
    # metro bogie frame side beam, ~0.8 m.
    airspring_lower_height_m: float = field(default=0.80, metadata=_HEIGHT)
    # Bellow upper plate (on the carbody) above rail top at static equilibrium: 0.25 m nominal
    # bellow height, typical of metro airsprings (0.2-0.3 m), under a ~1.1 m floor.
    airspring_upper_height_m: float = field(default=1.05, metadata=_HEIGHT)

    # Floor above rail top, where the floor accelerations are measured (EN 12299 places its
    # measuring points on the floor above the bogie centres and at the car centre): ~1.1 m on
    # metro cars, just above the bellows' upper plates.
    floor_height_m: float = field(default=1.1, metadata=_HEIGHT)

    # --- centres of gravity above rail top at static equilibrium ---
    # Low-floor-ish metro carbody (floor ~1.1 m, roof ~3.6 m): CoG ~1.5 m (Manchester vehicle 1: 1.8 m
    # in the one public set that gives it, manchester_vehicle_1()).
    carbody_cog_height_m: float = field(default=1.5, metadata=_HEIGHT)
    # Bogie frame CoG between axle height (0.42 m) and airspring seat (0.8 m).
    bogie_cog_height_m: float = field(default=0.6, metadata=_HEIGHT)

    # --- inertias about the body CoG, body axes x forward, y left, z up ---
    # Manchester carbody (32 t): 56.8 / 1970 / 1970 t m^2. Roll scaled with mass (x 0.531);
    # pitch and yaw also with (10/19)^2 = 0.277: 30 200 / 290 000 / 290 000 kg m^2.
    carbody_inertia_xx_kg_m2: float = field(default=30.2e3, metadata=_inertia("carbody"))
    carbody_inertia_yy_kg_m2: float = field(default=290.0e3, metadata=_inertia("carbody"))
    carbody_inertia_zz_kg_m2: float = field(default=290.0e3, metadata=_inertia("carbody"))
    # Manchester bogie frame (2615 kg): 1722 / 1476 / 3067 kg m^2; mass ratio 0.727, pitch also
    # x (2.0/2.56)^2 = 0.61; yaw ~ roll + pitch for a flat frame.
    bogie_inertia_xx_kg_m2: float = field(default=1250.0, metadata=_inertia("bogie"))
    bogie_inertia_yy_kg_m2: float = field(default=650.0, metadata=_inertia("bogie"))
    bogie_inertia_zz_kg_m2: float = field(default=1900.0, metadata=_inertia("bogie"))
    # Manchester wheelset (1813 kg): 1120 / 112 / 1120 kg m^2, scaled with mass (x 0.441).
    wheelset_inertia_xx_kg_m2: float = field(default=494.0, metadata=_inertia("wheelset"))
    wheelset_inertia_yy_kg_m2: float = field(default=49.0, metadata=_inertia("wheelset"))
    wheelset_inertia_zz_kg_m2: float = field(default=494.0, metadata=_inertia("wheelset"))

    # --- primary suspension, per axlebox, acting in the bogie frame ---
    # Manchester per axlebox: kx 31.39 MN/m, ky 3.884 MN/m, kz 1.22 MN/m, cz 4 kN s/m;
    # scaled by the axlebox-load ratio 0.558 (same static deflection ~37 mm).
    primary_stiffness_x_N_per_m: float = field(default=17.5e6, metadata=_PRIMARY_SPRING)
    primary_stiffness_y_N_per_m: float = field(default=2.17e6, metadata=_PRIMARY_SPRING)
    primary_stiffness_z_N_per_m: float = field(default=0.68e6, metadata=_PRIMARY_SPRING)
    primary_damping_x_N_s_per_m: float = field(default=0.0, metadata=_DAMPER)  # Manchester: no longitudinal primary damper
    primary_damping_y_N_s_per_m: float = field(default=0.0, metadata=_DAMPER)  # Manchester: no lateral primary damper
    primary_damping_z_N_s_per_m: float = field(default=2.2e3, metadata=_DAMPER)  # Manchester 4 kN s/m x 0.558

    # --- secondary suspension (pneumatic; vertical force comes from the pneumatic model) ---
    # Shear (horizontal) stiffness of one bellow, x and y: metro airsprings 100-150 kN/m at
    # ~3 bar gauge (Manchester secondary lateral: 160 kN/m per side). No traction rod is
    # modelled: the shear stiffness also holds the carbody longitudinally (stationary tests).
    bellow_shear_stiffness_N_per_m: float = field(default=120.0e3, metadata=_SPRING)
    # Lateral bumpstops (one per bogie: carbody centre pivot against stops on the bogie frame).
    # Clearance (reasoning, no published value for this car): airspring bogies typically leave
    # +-30...40 mm of free lateral secondary travel; at the paper's 1 m/s^2 unbalanced lateral
    # acceleration (R = 100 m, 10 m/s, no cant) the four bellows' shear alone deflect
    # 17 t x 1 m/s^2 / (4 x 120 kN/m) = 35 mm, so 40 mm keeps the stops free in the steady curve
    # (measured at the stop: 33 mm steady, 37 mm peak in the undamped sway after the transition)
    # and catches larger excursions (no lateral dampers in this car).
    # Stiffness: order of the initial rate of a rubber bumpstop, ~1 MN/m (real stops are
    # progressive; linear past the clearance is the usual simplification).
    lateral_bumpstop_clearance_m: float = field(default=0.040, metadata=_FREE_TRAVEL)
    lateral_bumpstop_stiffness_N_per_m: float = field(default=1.0e6, metadata=_SPRING)

    # --- wheel-rail vertical contact, Q = C_H * delta^1.5 (+ damping, never pulling) ---
    # Hertz with the equivalent-sphere approximation (wheel R 0.42 m on a 0.3 m rail crown,
    # E 210 GPa, nu 0.28) gives 0.9e11; the empirical G = 3.86e-8 R^-0.115 m/N^(2/3)
    # (Zhai, Vehicle-track coupled dynamics) gives 1.13e11. Round value in between. The
    # static deflection is ~40 um, far below the primary's ~37 mm: Q is insensitive to C_H.
    hertz_constant_N_per_m1_5: float = field(default=1.0e11, metadata=ranged(positive("N/m^1.5")))
    # Light damping of the ~250 Hz wheelset-on-contact bounce mode (damping ratio ~0.04),
    # the order of a rail pad's damping; the force is clipped so the contact never pulls.
    contact_damping_N_s_per_m: float = field(default=5.0e4, metadata=_DAMPER)

    # --- environment ---
    # standard gravity, rounded as in most vehicle codes
    gravity_m_per_s2: float = field(default=9.81, metadata=plausible(9.7, 9.9, "m/s^2", "gravity on the Earth's surface"))

    # ================================================================ optional components
    # All off by default (the paper's car has none). Typical values: metro_car_arb_dampers().

    # --- anti-roll bar, one per bogie, between bogie frame and carbody ---
    # Roll couple k (phi_carbody - phi_frame). Give either the equivalent roll stiffness, or the
    # torsion bar with its geometry: k = k_t (link spacing / lever arm)^2 (not both).
    # Air-sprung passenger cars: of order 1 MN m/rad per bogie [I, KS]; it sets the roll
    # coefficient, indispensable with a two-point (cross-connected) air suspension.
    arb_roll_stiffness_N_m_per_rad: float = field(default=0.0, metadata=_TORSION)
    # Torsion-bar stiffness G pi d^4 / (32 L): e.g. d = 50 mm, L = 1.8 m, G = 80 GPa: 27 kN m/rad.
    arb_torsion_stiffness_N_m_per_rad: float = field(default=0.0, metadata=_TORSION)
    # Lever (crank) arm from the bar's axis to the link joint, typically 0.25-0.4 m.
    arb_lever_arm_m: float = field(default=0.0, metadata=plausible(0.0, 2.0, "m", "the bar's lever; 0: no bar"))
    # Lateral distance between the two vertical links, ~ the airspring spacing (1.8-2.2 m).
    arb_link_spacing_m: float = field(default=0.0, metadata=plausible(0.0, 4.0, "m", "across the car; 0: no bar"))

    # --- secondary vertical dampers: two per bogie, at +-spacing/2, vertical ---
    # Each a (bi)linear damper in series with its mounting (rubber end bushes), see
    # vehicle/suspension.py. Damping per damper: 10-40 kN s/m on air-sprung passenger
    # vehicles [I]; Manchester benchmark 20 kN s/m on a 32 t body [M].
    secondary_vertical_damping_N_s_per_m: float = field(default=0.0, metadata=_DAMPER)
    # Blow-off (relief valve opening) velocity v_b; beyond it the slope is the blow-off
    # damping. Typical knees 0.05-0.2 m/s, slopes beyond 10-50 % of the first [I]. inf: linear.
    secondary_vertical_damper_blowoff_velocity_m_per_s: float = math.inf
    secondary_vertical_damper_blowoff_damping_N_s_per_m: float = field(default=0.0, metadata=_DAMPER)
    # Series (mounting) stiffness: end bushes and oil compressibility, of order 1-10 MN/m [I].
    # inf: rigid mounting (a plain damper).
    secondary_vertical_damper_series_stiffness_N_per_m: float = field(default=math.inf, metadata=_SPRING)
    # Lateral spacing of the two vertical dampers: next to the airsprings (here 2.0 m).
    secondary_vertical_damper_lateral_spacing_m: float = field(default=2.0, metadata=plausible(0.0, 4.0, "m", "across the car"))

    # --- secondary lateral damper: one per bogie, at the bogie centre, lateral ---
    # 15-40 kN s/m on passenger vehicles [I]; same law and parameters as the vertical ones.
    secondary_lateral_damping_N_s_per_m: float = field(default=0.0, metadata=_DAMPER)
    secondary_lateral_damper_blowoff_velocity_m_per_s: float = math.inf
    secondary_lateral_damper_blowoff_damping_N_s_per_m: float = field(default=0.0, metadata=_DAMPER)
    secondary_lateral_damper_series_stiffness_N_per_m: float = field(default=math.inf, metadata=_SPRING)
    # Height above rail: between the frame's side beams and the carbody underframe, ~0.9 m.
    secondary_lateral_damper_height_m: float = field(default=0.9, metadata=_HEIGHT)

    # --- yaw dampers: two per bogie, longitudinal, at +-spacing/2 ---
    # Against bogie hunting at speed: high-speed cars use a few hundred kN s/m with blow-off
    # at ~0.01-0.02 m/s and 5-10 MN/m series stiffness [I, KS]; metro cars (<= 100 km/h)
    # usually have none (e.g. doi:10.1007/s40864-016-0045-x).
    yaw_damping_N_s_per_m: float = field(default=0.0, metadata=_DAMPER)
    yaw_damper_blowoff_velocity_m_per_s: float = math.inf
    yaw_damper_blowoff_damping_N_s_per_m: float = field(default=0.0, metadata=_DAMPER)
    yaw_damper_series_stiffness_N_per_m: float = field(default=math.inf, metadata=_SPRING)
    # Mounted outside the frame's side beams: 2.5-2.8 m apart.
    yaw_damper_lateral_spacing_m: float = field(default=2.6, metadata=plausible(0.0, 4.0, "m", "across the car"))
    # Height above rail, near the bogie frame's side beam top.
    yaw_damper_height_m: float = field(default=0.8, metadata=_HEIGHT)

    # --- secondary yaw stiffness, one per bogie: a yaw couple between bogie frame and carbody ---
    # k (psi_frame - psi_carbody), in parallel with the yaw the bellows' shear already gives
    # (2 k_shear (airspring spacing / 2)^2 per bogie). Stands for a yaw stiffness the bellows do
    # not carry: a friction-free side-bearer or a model's longitudinal secondary springs (the
    # Cooperrider bogie's k6 at +-d6, cooperrider_bogie()). 0: none.
    secondary_yaw_stiffness_N_m_per_rad: float = field(default=0.0, metadata=_TORSION)

    # --- traction rod (or centre pivot), one per bogie: longitudinal, at the bogie centre ---
    # Longitudinal stiffness of the rod's rubber bushes, 5-20 MN/m [I]. 0: none (the bellows'
    # shear then holds the carbody longitudinally, as in the paper's car).
    traction_rod_stiffness_N_per_m: float = field(default=0.0, metadata=_SPRING)
    # Damping of the bushes; rubber loss factor ~0.1 at the ~5 Hz carbody-on-rods mode gives
    # c = 0.1 k / omega ~ 30 kN s/m for 10 MN/m.
    traction_rod_damping_N_s_per_m: float = field(default=0.0, metadata=_DAMPER)
    # Height above rail of the rod: low traction rods (0.4-0.6 m) limit the load transfer
    # between wheelsets under traction and braking.
    traction_rod_height_m: float = field(default=0.5, metadata=_HEIGHT)

    # --- emergency spring and vertical bumpstop, per bellow ---
    # Emergency (auxiliary) rubber spring in series with the bellow: it carries the load always
    # and alone, through the bumpstop, when the bellow is deflated or bottoms. Laminated rubber
    # emergency springs: ~1-3 MN/m vertical, several times the bellow's stiffness [I]. inf: none
    # (the bellow sits on a rigid seat, as in the paper's car).
    emergency_spring_stiffness_N_per_m: float = field(default=math.inf, metadata=_SPRING)
    # Internal bumpstop of the bellow, in parallel with it: engages when the bellow's own
    # crushing exceeds the clearance (measured from the static height). Typical free travel
    # 30-60 mm [I]; the stop then rests on the emergency spring.
    vertical_bumpstop_clearance_m: float = field(default=0.04, metadata=_FREE_TRAVEL)
    # Stop stiffness (rubber pad on the emergency spring's top plate): stiffer than the
    # emergency spring, ~10 MN/m. 0: no stop.
    vertical_bumpstop_stiffness_N_per_m: float = field(default=0.0, metadata=_SPRING)

    @property
    def bogie_x_m(self) -> tuple:
        """x [m] of the bogie centres from the car centre, front then rear."""
        xb = self.bogie_centre_distance_m / 2.0
        return (xb, -xb)

    @property
    def floor_points_m(self) -> tuple:
        """(x, y, z) [m] of the :data:`FLOOR_POINTS` relative to the carbody's centre of gravity."""
        dz = self.floor_height_m - self.carbody_cog_height_m
        return tuple((x, 0.0, dz) for x in (self.bogie_x_m[0], 0.0, self.bogie_x_m[1]))

    @property
    def wheelset_x_m(self) -> tuple:
        """x [m] of the wheelset centres from the car centre, wheelsets 1 ... 4 from the front."""
        a = self.wheelbase_m / 2.0
        return tuple(xb + sign * a for xb in self.bogie_x_m for sign in (1.0, -1.0))


#: ranges of the contact's parameters (field metadata; also of the scenario keys that set them):
#: the table's smoothing, a friction coefficient (above 1 no rail, dry or wet, grips), the normal
#: damping (the shipped 2e5 stands in for the track's; 1e7 N s/m overdamps the contact's modes)
TABLE_SMOOTHING = plausible(0.0, 1.0, "mm", "0: the rigid table; 1 mm blurs the flange itself")
FRICTION = plausible(0.0, 1.0, why="a wheel-rail friction coefficient; dry rail 0.3-0.5", low_inclusive=False)
CONTACT_DAMPING = plausible(0.0, 1e7, "N s/m", "the shipped 2e5 stands in for the track's damping")


@dataclass(frozen=True)
class ContactParams:
    """Wheel-rail contact of :class:`~vehicle.car.MetroCar` with ``guidance="contact"`` (issue
    11): the wheelsets run free laterally and in yaw on the contact forces of
    :mod:`vehicle.wheelrail.contact_law` (Hertz normal force along the contact normal, Kalker's
    linear creep forces with Shen-Hedrick-Elkins saturation). The normal contact's Hertz
    constant is :class:`VehicleParams`' ``hertz_constant_N_per_m1_5`` (its damping is
    ``normal_damping_N_s_per_m`` below, not the kinematic car's ``contact_damping_N_s_per_m``),
    the wheel radius ``wheel_radius_m`` (the radius at the tape
    circle of the table's wheel profile); ``contact_spacing_m`` is not used (the contact points
    come from the table: 1.5065 m apart for S1002 on UIC60 1:40, centred). Kept apart from
    :class:`VehicleParams` because dimensionless and text values do not fit its unit-suffixed
    numeric fields (tests/vehicle/test_vehicle.py), and so that the scenario YAML mirror of
    VehicleParams is unchanged."""

    # Wheel-rail friction coefficient mu: the creep forces saturate at mu N. 0.36 is the value
    # the Nadal limit uses (70 deg flange, mu 0.36: Y/Q 1.20); dry rail 0.3-0.5, wet
    # 0.15-0.25 (Iwnicki, Handbook of Railway Vehicle Dynamics, ch. "Wheel-rail contact").
    friction_coefficient: float = field(default=0.36, metadata=FRICTION)
    # Creepages are slip velocities divided by the running speed V; below this speed they are
    # divided by it instead, so that the car can stand (V = 0, the twist test) or start: the
    # creep forces then act as viscous forces f_ij / V_min on the slip velocities (for a 30 kN
    # wheel f22 / V_min ~ 1e9 N s/m at 0.01 m/s), stiff enough to hold a standing car like
    # static friction would (a wheelset pushed by 1 kN creeps at ~1 um/s; saturation still
    # caps the forces at mu N). With 1 m/s the standing car of the twist test drifts sideways
    # and in yaw and its wheel loads move by ~1 % of Q0 within seconds. At and above V_min the
    # law is Kalker's, unchanged.
    min_creep_speed_m_per_s: float = 0.01
    # A wheel counts as in flange contact (:meth:`MetroCar.flange_contact`) when its contact
    # angle exceeds this: 0.7 rad (40 deg) separates the tread and flange root (S1002 on UIC60
    # 1:40: up to 0.67 rad just before the flank) from the flange flank (1.22 rad, 70 deg). The
    # law reads the table smoothed over 0.1 mm (table_smoothing_mm), so its angle passes 0.7 rad
    # continuously within ~0.1 mm of the jump at 6.26-6.29 mm: there the flag is a threshold on
    # a blend.
    flange_angle_rad: float = 0.7
    # Damping of the normal contact force [N s/m], along the normal, per wheel. The track is
    # rigid in this model, so the contact damping stands in for the track's (rail pads, ballast),
    # which damps the wheelset-on-track modes far more than the Hertz contact itself: 2e5 gives
    # the ~250 Hz wheelset-on-contact modes a damping ratio of ~0.1 (contact stiffness ~1e9 N/m,
    # 800 kg). With the car's vertical value 5e4 (ratio ~0.03) a wheel on the flange root has a
    # friction-driven flutter of those modes, even on the smoothed table: the linearised
    # flanging wheelset's eigenvalues reach +82 /s (vehicle/wheelrail/stability.py), which at
    # 5 ms steps only the integrator's numerical damping hid (docs/wheel_rail.md, "Flange
    # contact and step convergence").
    normal_damping_N_s_per_m: float = field(default=2.0e5, metadata=CONTACT_DAMPING)
    # Gaussian smoothing of the contact table the force law reads, standard deviation in mm of
    # wheelset lateral displacement (vehicle.wheelrail.contact_law.ContactLawTable: the rigid
    # table's jumps and its fast turn across the conformal flange root, smoothed as an elastic
    # contact spreads over them). 0 reads the rigid table as it is.
    table_smoothing_mm: float = field(default=0.1, metadata=TABLE_SMOOTHING)
    # Contact table: a CSV written by vehicle.wheelrail.ContactTable.to_csv; "" = the S1002 /
    # UIC60 1:40 / 1435 mm table for the car's wheel radius (shipped for 0.42 m and 0.46 m,
    # vehicle/wheelrail/data, else derived from the profiles in ~2 s).
    table_csv: str = ""
    # Kalker's linear creep coefficients given instead of computed from the contact ellipse:
    # (f11 [N], f22 [N], f23 [N m], f33 [N m^2]) per wheel, the same at every normal force (the
    # law's own scale with the load, (N/N_ref)^(2/3), ^1, ^(4/3), is then off), as linear models
    # of the literature give them. () = from the contact law (Hertz ellipse, Kalker's table).
    creep_coefficients: tuple = ()
    # The lateral creepage's roll-rate part r roll'/V (the contact point lies r below the axle):
    # False leaves it out, as classical linear wheelset models do -- an experiment, to show what
    # it does to a result (docs/validation.md), not a model choice.
    roll_rate_creepage: bool = True

    def __post_init__(self):
        if not (self.friction_coefficient > 0.0 and math.isfinite(self.friction_coefficient)):
            raise ValueError(f"friction_coefficient must be > 0, got {self.friction_coefficient}")
        for name in ("normal_damping_N_s_per_m", "table_smoothing_mm"):
            v = getattr(self, name)
            if not (v >= 0.0 and math.isfinite(v)):
                raise ValueError(f"{name} must be >= 0, got {v}")
        if not (self.min_creep_speed_m_per_s > 0.0
                and math.isfinite(self.min_creep_speed_m_per_s)):
            raise ValueError("min_creep_speed_m_per_s must be > 0, got "
                             f"{self.min_creep_speed_m_per_s}")
        if not 0.0 < self.flange_angle_rad < math.pi / 2:
            raise ValueError(f"flange_angle_rad must lie in (0, pi/2), got {self.flange_angle_rad}")


#: ranges of a flexible track's fields (metadata; a rigid track has none), per wheelset (both
#: rails), around :func:`slab_track`'s values: the mass that moves with a wheelset, from the rails
#: alone (~60 kg/m each) to a concrete slab (1520 kg), with its roll inertia; support stiffnesses
#: of soft ballast (~10 MN/m) to a stiff slab (~1 GN/m); dampings of rail pads and ballast (tens to
#: hundreds of kN s/m). A value in tonnes, MN/m or kN s/m falls out, and the slip is named
_TRACK_MASS = plausible(20.0, 2e4, "kg", "a track mass per wheelset, rails to slab")
_TRACK_INERTIA = plausible(1.0, 1e5, "kg m^2", "a track mass's roll inertia")
_TRACK_STIFFNESS = plausible(1e6, 1e10, "N/m", "a track's support per wheelset, soft ballast to slab")
_TRACK_DAMPING = plausible(1e3, 1e7, "N s/m", "a track's damping per wheelset")
_TRACK_ROLL_STIFFNESS = plausible(1e5, 1e10, "N m/rad", "a track's roll support per wheelset")
_TRACK_ROLL_DAMPING = plausible(1e2, 1e8, "N m s/rad", "a track's roll damping per wheelset")
#: track models of :class:`TrackStructure`
TRACK_MODELS = ("rigid", "flexible")


@dataclass(frozen=True)
class TrackStructure:
    """The track under the rails. ``rigid``: the rails are where the track geometry and its
    irregularities put them. ``flexible``: under each wheelset a track mass (the rails and
    sleepers that move with the wheel) that travels along with the wheelset, on springs and
    dampers to the ground, lateral and normal to the track plane (on level track: vertical) and
    in roll about the track centre at rail level; the wheel-rail contact acts between wheelset
    and track mass
    (:class:`~vehicle.car.MetroCar`). The values are per wheelset (both rails). With kinematic
    guidance the lateral guidance is prescribed, so only the vertical and roll values enter.
    Values and sources: :func:`slab_track`."""

    model: str = "rigid"
    mass_kg: float = field(default=0.0, metadata=_TRACK_MASS)
    roll_inertia_kg_m2: float = field(default=0.0, metadata=_TRACK_INERTIA)
    lateral_stiffness_N_per_m: float = field(default=0.0, metadata=_TRACK_STIFFNESS)
    lateral_damping_N_s_per_m: float = field(default=0.0, metadata=_TRACK_DAMPING)
    vertical_stiffness_N_per_m: float = field(default=0.0, metadata=_TRACK_STIFFNESS)
    vertical_damping_N_s_per_m: float = field(default=0.0, metadata=_TRACK_DAMPING)
    roll_stiffness_N_m_per_rad: float = field(default=0.0, metadata=_TRACK_ROLL_STIFFNESS)
    roll_damping_N_m_s_per_rad: float = field(default=0.0, metadata=_TRACK_ROLL_DAMPING)

    def __post_init__(self):
        if self.model not in TRACK_MODELS:
            raise ValueError(f"model must be one of {', '.join(TRACK_MODELS)}, got {self.model!r}")
        if self.flexible:
            for f in dataclasses.fields(self)[1:]:
                v = getattr(self, f.name)
                if not (v > 0.0 and math.isfinite(v)):
                    raise ValueError(f"{f.name} must be finite and > 0 on a flexible track, got {v}")

    @property
    def flexible(self) -> bool:
        return self.model == "flexible"


def slab_track() -> TrackStructure:
    """Slab track with rails on resilient fasteners (the usual track of metro tunnels), as one
    track mass per wheelset: the co-running track benchmark's two layers ("rail - track slab -
    ground") reduced to one.

    Sources: [Y] Y. Ye, P. Huang, Y. Zhang, Deep learning-based fault diagnostic network of
    high-speed train secondary suspension systems, Railway Engineering Science 30 (2022) 96-116,
    Table 2 (a SIMPACK co-running track): fastener stiffness 30 MN/m lateral, 150 MN/m vertical,
    damping 150 / 100 kN s/m; slab support (cement-asphalt mortar) 70 / 140 MN/m, 350 / 1400
    kN s/m. [Y] gives no masses; those are from a public implementation of the same benchmark
    (rail 60 kg per rail, slab 1400 kg and 450 kg m^2 of roll inertia under each wheelset, the
    support springs 0.75 m either side of the track centre) and are the least certain values.

    Reduction to one mass, per wheelset (both rails): taking every stiffness and damping of [Y]
    per rail (a fastener under each rail, a support spring under each rail), the fasteners and
    the support act in series: springs in series (exact for slow loads) and dampers in series
    (exact for fast ones):

    * mass 1400 + 2 x 60 = 1520 kg; roll inertia 450 + 2 x 60 x 0.75^2 = 517.5 kg m^2;
    * vertical 1 / (1/(2 x 150) + 1/(2 x 140)) = 144.8 MN/m, 1 / (1/200 + 1/2800) kN s/m
      = 186.7 kN s/m;
    * lateral 1 / (1/60 + 1/140) = 42.0 MN/m, 1 / (1/300 + 1/700) = 210 kN s/m;
    * roll: the per-rail vertical series values at 0.75 m either side, 2 x 0.75^2 x 72.4 MN/m
      = 81.5 MN m/rad and 2 x 0.75^2 x 93.3 kN s/m = 105 kN m s/rad.

    What the reduction drops: the rails' own modes on the fasteners (60 kg on 150 MN/m,
    ~250 Hz). The wheelset (800 kg) on this track (1520 kg on 144.8 MN/m) bounces at ~40 Hz,
    the range of the P2 resonance of metro vehicles."""
    return TrackStructure(model="flexible", mass_kg=1520.0, roll_inertia_kg_m2=517.5,
                          lateral_stiffness_N_per_m=42.0e6, lateral_damping_N_s_per_m=210.0e3,
                          vertical_stiffness_N_per_m=144.8e6, vertical_damping_N_s_per_m=186.7e3,
                          roll_stiffness_N_m_per_rad=81.5e6, roll_damping_N_m_s_per_rad=105.0e3)


def metro_car_arb_dampers() -> VehicleParams:
    """The paper's metro car (the :class:`VehicleParams` defaults) with the secondary components
    an air-sprung metro car usually has: an anti-roll bar per bogie, vertical and lateral
    dampers, a traction rod per bogie, and an emergency spring with a bumpstop under each
    bellow. No yaw dampers (usual below ~100 km/h). Typical values, sources [I], [KS], [M] in
    the module doc; where a value is reasoned from this car, the reasoning:

    * anti-roll bar 1.0 MN m/rad per bogie ("of order 1 MN m/rad" [I, KS]); e.g. a 50 mm steel
      bar 1.8 m long (27 kN m/rad) with 0.3 m levers and links 2.0 m apart gives 1.2 MN m/rad.
      Quasi-static carbody roll at 1 m/s^2 unbalanced lateral acceleration (hand calculation of
      tests/vehicle/test_vehicle_curve.py with the bar added): 0.020 rad without the bar, 0.0095 rad
      with it (bellows 243 kN/m each), 0.012 rad with the bar alone (two-point suspension,
      no bellow roll stiffness): roll coefficients ~0.1-0.2, the usual range;
    * vertical dampers 10 kN s/m each: the Manchester benchmark's 20 kN s/m [M] scaled by the
      carbody mass (17 t / 32 t); damping ratio of the bounce mode ~0.1 on 243 kN/m bellows.
      Blow-off at 0.1 m/s to 30 % of the slope; 2 MN/m series stiffness (end bushes) [I];
    * lateral damper 20 kN s/m, one per bogie (15-40 kN s/m [I]): sway damping ratio ~0.2 on
      the bellows' 4 x 120 kN/m shear; blow-off at 0.1 m/s to 30 %; 2 MN/m series stiffness;
    * traction rods 10 MN/m (5-20 MN/m [I]), 30 kN s/m (rubber loss factor ~0.1 at the 5.5 Hz
      carbody-on-rods mode), 0.5 m above rail;
    * emergency springs 2 MN/m (1-3 MN/m [I]), stops after 40 mm of bellow crushing
      (30-60 mm [I]), 10 MN/m.
    """
    return dataclasses.replace(
        VehicleParams(),
        arb_roll_stiffness_N_m_per_rad=1.0e6,
        secondary_vertical_damping_N_s_per_m=10.0e3,
        secondary_vertical_damper_blowoff_velocity_m_per_s=0.1,
        secondary_vertical_damper_blowoff_damping_N_s_per_m=3.0e3,
        secondary_vertical_damper_series_stiffness_N_per_m=2.0e6,
        secondary_lateral_damping_N_s_per_m=20.0e3,
        secondary_lateral_damper_blowoff_velocity_m_per_s=0.1,
        secondary_lateral_damper_blowoff_damping_N_s_per_m=6.0e3,
        secondary_lateral_damper_series_stiffness_N_per_m=2.0e6,
        traction_rod_stiffness_N_per_m=10.0e6,
        traction_rod_damping_N_s_per_m=30.0e3,
        emergency_spring_stiffness_N_per_m=2.0e6,
        vertical_bumpstop_stiffness_N_per_m=10.0e6,
    )


def cooperrider_bogie() -> VehicleParams:
    """The Cooperrider bogie (truck) with the parameter set of the open DYTSI code (D. Bigoni,
    DTU, github.com/daniele-bigoni/dytsi; tests/independent/README.md lists each value with its
    file and line), mapped onto this car: for running-stability studies under a held carbody
    (kind stability, ``carbody: held``; scenarios/cooperrider.yaml). DYTSI values, as there:

    * wheelset 1022 kg, inertias 678 / 80 / 678 kg m^2 (roll / spin / yaw); frame 2918.9 kg,
      6780 kg m^2 about every axis; carbody 44388 kg, 2.8e5 / 5.0e5 / 5.0e5 kg m^2 (axle load
      (44388/4 + 2918.9/2 + 1022) g = 133.2 kN, DYTSI's wheel-rail table 133.3 kN);
    * half wheelbase b = 1.074 m; contact points 2 e = 2 x 0.75630 m apart (DYTSI's table at
      y = 0; a cone's knife-edge rails sit there); wheel radius r0 = 0.42488 m (the table's);
    * primary, per axlebox (two per wheelset at +-s1 = +-0.62 m): longitudinal k2 = 3.646 MN/m,
      lateral k1 = 1.823 MN/m, no longitudinal or lateral dampers (D3 = D5 = 0);
    * secondary, per bogie: two lateral springs k4 = 182.3 kN/m (the two bellows' shear), two
      lateral dampers D2 = 29.2 kN s/m (one damper of 2 D2 at the bogie centre), two longitudinal
      springs k6 = 903.35 kN/m and dampers D6 = 166.669 kN s/m at +-d6 = +-1.5 m (the dampers:
      the yaw dampers, 3.0 m apart, linear, rigidly mounted; the springs: a yaw stiffness
      2 k6 d6^2 = 4.065 MN m/rad, of which the bellows' shear in x at +-1.0 m carries
      2 k4 (1.0 m)^2 = 0.365 MN m/rad and ``secondary_yaw_stiffness_N_m_per_rad`` the rest).

    Not mapped (the car's values stay, each irrelevant to the lateral linear problem or named
    in docs/validation.md where it is not): the secondary's longitudinal stiffness (2 k4 here
    against DYTSI's 2 k6: the frame's longitudinal motion, which the lateral modes do not
    move); the primary and secondary vertical suspension (DYTSI's vertical springs; here the
    primary's 1.66 MN/m per axlebox, the metro car's 37 mm static deflection under this load,
    and the air circuit); the heights of the secondary lateral spring and damper (DYTSI's
    h1, h2, s2: here the bellows' plates and the damper at 0.9 m), through which the frame's
    roll, absent from the independent model, meets its lateral motion."""
    k4, k6, d6 = 1.823e5, 9.0335e5, 1.5          # DYTSI k4, k6 [N/m], d6 = a + l1 + l2 + l3/2 [m]
    base = VehicleParams()
    return dataclasses.replace(
        base,
        carbody_mass_kg=44388.0, carbody_inertia_xx_kg_m2=2.8e5, carbody_inertia_yy_kg_m2=5.0e5,
        carbody_inertia_zz_kg_m2=5.0e5,
        bogie_mass_kg=2918.9, bogie_inertia_xx_kg_m2=6780.0, bogie_inertia_yy_kg_m2=6780.0,
        bogie_inertia_zz_kg_m2=6780.0,
        wheelset_mass_kg=1022.0, wheelset_inertia_xx_kg_m2=678.0, wheelset_inertia_yy_kg_m2=80.0,
        wheelset_inertia_zz_kg_m2=678.0,
        wheelbase_m=2 * 1.074, contact_spacing_m=2 * 0.756301, wheel_radius_m=0.4248829,
        primary_lateral_spacing_m=2 * 0.62, primary_stiffness_x_N_per_m=3.646e6,
        primary_stiffness_y_N_per_m=1.823e6, primary_stiffness_z_N_per_m=1.66e6,
        primary_damping_x_N_s_per_m=0.0, primary_damping_y_N_s_per_m=0.0,
        bellow_shear_stiffness_N_per_m=k4,
        secondary_lateral_damping_N_s_per_m=2 * 2.92e4,
        yaw_damping_N_s_per_m=166669.0, yaw_damper_lateral_spacing_m=2 * d6,
        secondary_yaw_stiffness_N_m_per_rad=2 * k6 * d6 ** 2
        - 2 * k4 * (base.airspring_lateral_spacing_m / 2) ** 2,
    )


def manchester_vehicle_1() -> VehicleParams:
    """Manchester benchmark vehicle 1, the passenger vehicle of Iwnicki's "The Manchester
    Benchmarks for Rail Vehicle Simulation" (Vehicle System Dynamics 30 (1998) 295-313), as far as
    its parameters could be read here (sources named per field, inferred values marked). The paper
    and the book were not readable; every value below is from a public file that states it is the
    benchmark's, and the ones no file gives are inferred
    (marked, with the reasoning). docs/validation.md, "Manchester benchmark vehicle 1", has the
    table with each source and what is missing. Sources:

    [T] github.com/DanielCanteroNTNU/TTB-2D, TrainProp_Manchester_BenchMark.m (commit 2b414dd),
        "taken from Iwnicki (1998)", a 2D (vertical) model: masses, pitch inertias, half bogie
        distance 9.5 m, half wheelbase 1.28 m, primary vertical 1200 kN/m and 4 kN s/m per
        axlebox, secondary vertical 430 kN/m and 20 kN s/m per side;
    [C] a public MATLAB file of a CRH380A model (search-index file id 65921690791, repository not
        resolvable here), a commented-out block ``strcmp(Type_Vehicle, 'Manchester Benchmark')``:
        the full 3D set (inertias, primary and secondary in x/y/z, anti-roll bar, heights, the
        lateral bumpstop's force table). One source, no citation of its own: single-source;
    [S] J. Sresakoolchai, C. Puttasrijaru, Predictive maintenance of railway suspension systems
        ..., doi:10.1007/s42452-026-08531-2, a Universal Mechanism model "based on the Manchester
        benchmark vehicle": Table 2, primary stiffness 1 220 000 N/m and damping 4 000 N s/m
        ("regular"), which [C] agrees with ([T] has 1200 kN/m).

    Not mapped: the vertical secondary is this project's air circuit, not [T]/[C]'s linear
    430 kN/m per side (a scenario's circuit sets it); [C]'s secondary "bending" stiffness
    10.5 kN m/rad per side; the traction rods the benchmark has (GENSYS chapter of the
    benchmark book, abstract) with no stiffness readable; the wheel and rail profiles of the
    benchmark (not available here: runs use S1002 / UIC60 1:40)."""
    return dataclasses.replace(
        VehicleParams(),
        # --- masses [T, C]; total 44 482 kg, 436.4 kN, 54.55 kN per wheel at g = 9.81
        carbody_mass_kg=32000.0, bogie_mass_kg=2615.0, wheelset_mass_kg=1813.0,
        # --- geometry: bogie centres 2 x 9.5 m, wheelbase 2 x 1.28 m [T, C]; wheel radius
        # 0.46 m, axlebox and secondary springs at +-1.0 m [C]
        bogie_centre_distance_m=19.0, wheelbase_m=2.56, wheel_radius_m=0.46,
        primary_lateral_spacing_m=2.0, airspring_lateral_spacing_m=2.0,
        # inferred: [C] attaches the secondary at one point 0.8275 m above rail (zero length);
        # the bellow here needs two plates: 0.25 m apart about that height
        airspring_lower_height_m=0.70, airspring_upper_height_m=0.95,
        # inferred: not in any source read; only places the floor measuring points
        floor_height_m=1.2,
        # --- centres of gravity above rail [C]: carbody 1.8 m, bogie frame 0.6 m
        carbody_cog_height_m=1.8, bogie_cog_height_m=0.6,
        # --- inertias roll / pitch / yaw [C]; the pitch ones also [T]
        carbody_inertia_xx_kg_m2=56.8e3, carbody_inertia_yy_kg_m2=1.97e6,
        carbody_inertia_zz_kg_m2=1.97e6,
        bogie_inertia_xx_kg_m2=1722.0, bogie_inertia_yy_kg_m2=1476.0, bogie_inertia_zz_kg_m2=3067.0,
        wheelset_inertia_xx_kg_m2=1120.0, wheelset_inertia_yy_kg_m2=112.0,
        wheelset_inertia_zz_kg_m2=1120.0,
        # --- primary per axlebox [C]; kz and cz also [S] ([T]: kz 1200 kN/m)
        primary_stiffness_x_N_per_m=31.391e6, primary_stiffness_y_N_per_m=3.884e6,
        primary_stiffness_z_N_per_m=1.22e6,
        primary_damping_x_N_s_per_m=15.0e3, primary_damping_y_N_s_per_m=2.0e3,
        primary_damping_z_N_s_per_m=4.0e3,
        # --- secondary horizontal per side, x and y: 160 kN/m [C]
        bellow_shear_stiffness_N_per_m=160.0e3,
        # lateral bumpstop [C]: free 25 mm, then progressive (0.6 / 1.76 / 3.73 / 6.87 / 11.58 /
        # 17.17 / 29.2 / 230 kN at 30 ... 65 mm). Inferred linear law: the 25 mm clearance and
        # the secant stiffness to 60 mm, 29.2 kN / 35 mm = 0.83 MN/m
        lateral_bumpstop_clearance_m=0.025, lateral_bumpstop_stiffness_N_per_m=0.83e6,
        # --- anti-roll bar 940 kN m/rad [C] (units and "per bogie" inferred: [C] gives the
        # number without them; a roll stiffness of this order per bogie is usual [I, KS])
        arb_roll_stiffness_N_m_per_rad=940.0e3,
        # --- secondary vertical dampers 20 kN s/m per side [T, C], linear, rigidly mounted;
        # spacing inferred: at the secondary springs (+-1.0 m [C])
        secondary_vertical_damping_N_s_per_m=20.0e3, secondary_vertical_damper_lateral_spacing_m=2.0,
        # --- secondary lateral damping 32 kN s/m per side [C]: one damper of 2 x 32 at the
        # bogie centre; height inferred: [C]'s secondary height 0.8275 m
        secondary_lateral_damping_N_s_per_m=64.0e3, secondary_lateral_damper_height_m=0.83,
    )


#: track presets: name -> function returning the :class:`TrackStructure`
TRACK_PRESETS = {"slab_track": slab_track}
