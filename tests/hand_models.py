"""Hand models shared by tests in more than one folder: closed-form answers written
independently of the code under test."""
from __future__ import annotations

import numpy as np


def roll_hand_calculation(p, k_b, k_arb, torque_per_bogie):
    """Static carbody and bogie roll [rad] under a roll moment T per bogie on the carbody.

    Suspension alone: the anti-roll bar in parallel with the bellows' vertical stiffness times
    the half-spacing squared, K_s = k_arb + 2 k_b b^2, in series with the primary,
    K_p = 4 k_z b_p^2: phi_c = T (1/K_s + 1/K_p). Gravity adds the usual destabilising terms
    (same derivation as tests/vehicle/test_vehicle_curve.py::hand_calculation, without centrifugal
    load): the weight on supports that move under the body, the bellow force's tilt with the
    bodies (carried by the shear), the bogie's and the half carbody's weights over the primary.
    Per bogie, m = half the carbody mass, heights above rail, roll positive left side up:
      (2) carbody about its CoG: K_s (phi_c - phi_b) = T + m g (phi_c (h_c - h_u) + delta/2),
          delta = e (phi_c + phi_b) + (h0/2) (phi_c - phi_b) the bellows' shear offset,
          e = m g / (4 k_shear);
      (4) bogie + half carbody about the axle-height point: K_p phi_b = T + g (m y_c + m_b y_b),
          y_b = phi_b (h_b - h_a), y_c = delta + y_b + phi_b (h_l - h_b) + phi_c (h_c - h_u).
    """
    g = p.gravity_m_per_s2
    m, mb = p.carbody_mass_kg / 2.0, p.bogie_mass_kg
    hc, hb = p.carbody_cog_height_m, p.bogie_cog_height_m
    hl, hu = p.airspring_lower_height_m, p.airspring_upper_height_m
    b, bp = p.airspring_lateral_spacing_m / 2.0, p.primary_lateral_spacing_m / 2.0
    Q0 = (2.0 * m + mb) * g / 4.0 + p.wheelset_mass_kg * g / 2.0
    ha = p.wheel_radius_m - (Q0 / p.hertz_constant_N_per_m1_5) ** (2.0 / 3.0)
    Ks = k_arb + 2.0 * k_b * b * b
    Kp = 4.0 * p.primary_stiffness_z_N_per_m * bp * bp
    e, c = m * g / (4.0 * p.bellow_shear_stiffness_N_per_m), (hu - hl) / 2.0
    row2 = [Ks - m * g * (hc - hu) - m * g * (c + e) / 2, -Ks + m * g * (c - e) / 2]
    row4 = [-m * g * (c + e + hc - hu),
            Kp - m * g * (-c + e + hb - ha + hl - hb) - mb * g * (hb - ha)]
    phi_c, phi_b = np.linalg.solve([row2, row4], [torque_per_bogie, torque_per_bogie])
    return {"phi_c": phi_c, "phi_b": phi_b,
            "phi_c_without_gravity": torque_per_bogie * (1.0 / Ks + 1.0 / Kp)}
