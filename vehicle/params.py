"""Parameters of the metro car multibody model (SI units, names carry the unit).

The paper (Table 3) gives only the masses, the bogie centre distance and the wheelbase. Every
other value is a documented default: the Manchester benchmark passenger vehicle (Iwnicki 1998,
"The Manchester Benchmarks for Rail Vehicle Simulation") scaled to a metro car, or textbook
reasoning. ``scenarios/params/metro_car.yaml`` mirrors these values with the same comments.

Scaling rules used below (Manchester -> metro):
  * load ratio per axlebox: Manchester (32 000/2 + 2 615) kg, metro (17 000/2 + 1 900) kg
    -> 0.558; primary stiffness and damping are scaled by it (same static deflection, ~37 mm);
  * inertias scale with mass, and pitch/yaw inertias also with the square of the length ratio
    (bogie centres 10 m vs 19 m, wheelbase 2.0 m vs 2.56 m).

Only ``float``/``int`` fields (real classes in ``dataclasses.fields(...)[i].type``, no string
annotations), so a generic loader can fill the dataclass by introspection.
"""
from dataclasses import dataclass

#: Bellows (airsprings): front/rear bogie, left/right in the running direction.
BELLOWS = ("FL", "FR", "RL", "RR")
#: Wheels: wheelset 1..4 from the front, left/right in the running direction.
WHEELS = ("1L", "1R", "2L", "2R", "3L", "3R", "4L", "4R")


@dataclass(frozen=True)
class VehicleParams:
    """Metro car: one carbody, two bogie frames, four wheelsets; purely pneumatic secondary."""

    # --- masses (paper Table 3) ---
    carbody_mass_kg: float = 17000.0  # Table 3
    bogie_mass_kg: float = 1900.0  # Table 3 (bogie frame)
    wheelset_mass_kg: float = 800.0  # Table 3

    # --- geometry ---
    bogie_centre_distance_m: float = 10.0  # Table 3
    wheelbase_m: float = 2.0  # Table 3
    # Nominal lateral distance of the two wheel-rail contact points, standard gauge 1435 mm.
    contact_spacing_m: float = 1.5
    # 840 mm tread diameter: usual for metro cars (Manchester mainline vehicle: 0.46 m).
    wheel_radius_m: float = 0.42
    # Axlebox (primary spring) lateral spacing: Manchester 2 x 1.0 m, typical of 1435 mm bogies.
    primary_lateral_spacing_m: float = 2.0
    # Airspring lateral spacing: Manchester secondary 2 x 1.0 m; metro bogies use 1.8-2.0 m.
    airspring_lateral_spacing_m: float = 2.0
    # Bellow lower plate (on the bogie frame) above rail top at static equilibrium: top of a
    # metro bogie frame side beam, ~0.8 m.
    airspring_lower_height_m: float = 0.80
    # Bellow upper plate (on the carbody) above rail top at static equilibrium: 0.25 m nominal
    # bellow height, typical of metro airsprings (0.2-0.3 m), under a ~1.1 m floor.
    airspring_upper_height_m: float = 1.05

    # --- centres of gravity above rail top at static equilibrium ---
    # Low-floor-ish metro carbody (floor ~1.1 m, roof ~3.6 m): CoG ~1.5 m (Manchester: 2.0 m).
    carbody_cog_height_m: float = 1.5
    # Bogie frame CoG between axle height (0.42 m) and airspring seat (0.8 m).
    bogie_cog_height_m: float = 0.6

    # --- inertias about the body CoG, body axes x forward, y left, z up ---
    # Manchester carbody (32 t): 56.8 / 1970 / 1970 t m^2. Roll scaled with mass (x 0.531);
    # pitch and yaw also with (10/19)^2 = 0.277: 30 200 / 290 000 / 290 000 kg m^2.
    carbody_inertia_xx_kg_m2: float = 30.2e3
    carbody_inertia_yy_kg_m2: float = 290.0e3
    carbody_inertia_zz_kg_m2: float = 290.0e3
    # Manchester bogie frame (2615 kg): 1722 / 1476 / 3067 kg m^2; mass ratio 0.727, pitch also
    # x (2.0/2.56)^2 = 0.61; yaw ~ roll + pitch for a flat frame.
    bogie_inertia_xx_kg_m2: float = 1250.0
    bogie_inertia_yy_kg_m2: float = 650.0
    bogie_inertia_zz_kg_m2: float = 1900.0
    # Manchester wheelset (1813 kg): 1120 / 112 / 1120 kg m^2, scaled with mass (x 0.441).
    wheelset_inertia_xx_kg_m2: float = 494.0
    wheelset_inertia_yy_kg_m2: float = 49.0
    wheelset_inertia_zz_kg_m2: float = 494.0

    # --- primary suspension, per axlebox, acting in the bogie frame ---
    # Manchester per axlebox: kx 31.39 MN/m, ky 3.884 MN/m, kz 1.22 MN/m, cz 4 kN s/m;
    # scaled by the axlebox-load ratio 0.558 (same static deflection ~37 mm).
    primary_stiffness_x_N_per_m: float = 17.5e6
    primary_stiffness_y_N_per_m: float = 2.17e6
    primary_stiffness_z_N_per_m: float = 0.68e6
    primary_damping_x_N_s_per_m: float = 0.0  # Manchester: no longitudinal primary damper
    primary_damping_y_N_s_per_m: float = 0.0  # Manchester: no lateral primary damper
    primary_damping_z_N_s_per_m: float = 2.2e3  # Manchester 4 kN s/m x 0.558

    # --- secondary suspension (pneumatic; vertical force comes from the pneumatic model) ---
    # Shear (horizontal) stiffness of one bellow, x and y: metro airsprings 100-150 kN/m at
    # ~3 bar gauge (Manchester secondary lateral: 160 kN/m per side). No traction rod is
    # modelled: the shear stiffness also holds the carbody longitudinally (stationary tests).
    bellow_shear_stiffness_N_per_m: float = 120.0e3
    # Lateral bumpstops (one per bogie: carbody centre pivot against stops on the bogie frame).
    # Clearance (reasoning, no published value for this car): airspring bogies typically leave
    # +-30...40 mm of free lateral secondary travel; at the paper's 1 m/s^2 unbalanced lateral
    # acceleration (R = 100 m, 10 m/s, no cant) the four bellows' shear alone deflect
    # 17 t x 1 m/s^2 / (4 x 120 kN/m) = 35 mm, so 40 mm keeps the stops free in the steady curve
    # (measured at the stop: 33 mm steady, 37 mm peak in the undamped sway after the transition)
    # and catches larger excursions (no lateral dampers in this car).
    # Stiffness: order of the initial rate of a rubber bumpstop, ~1 MN/m (real stops are
    # progressive; linear past the clearance is the usual simplification).
    lateral_bumpstop_clearance_m: float = 0.040
    lateral_bumpstop_stiffness_N_per_m: float = 1.0e6

    # --- wheel-rail vertical contact, Q = C_H * delta^1.5 (+ damping, never pulling) ---
    # Hertz with the equivalent-sphere approximation (wheel R 0.42 m on a 0.3 m rail crown,
    # E 210 GPa, nu 0.28) gives 0.9e11; the empirical G = 3.86e-8 R^-0.115 m/N^(2/3)
    # (Zhai, Vehicle-track coupled dynamics) gives 1.13e11. Round value in between. The
    # static deflection is ~40 um, far below the primary's ~37 mm: Q is insensitive to C_H.
    hertz_constant_N_per_m1_5: float = 1.0e11
    # Light damping of the ~250 Hz wheelset-on-contact bounce mode (damping ratio ~0.04),
    # the order of a rail pad's damping; the force is clipped so the contact never pulls.
    contact_damping_N_s_per_m: float = 5.0e4

    # --- environment ---
    gravity_m_per_s2: float = 9.81  # standard gravity, rounded as in most vehicle codes
