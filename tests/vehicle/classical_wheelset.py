r"""
Independent, hand-derived LINEAR model of a single railway wheelset
(coned wheels on knife-edge rails), coordinates q = (y, psi).

    M q'' + C q' + K q = 0,      M = diag(m, I_z)

Written as a reference for tests/vehicle/test_linear.py by a separate author who had not read
the project's code (given only the physical setup and Kalker's sign convention); it uses none of it.

=====================================================================
0. Conventions
=====================================================================
Axes: x forward (direction of travel), y left, z up (right-handed).
Frame (carrying the springs k_y, k_psi) moves at constant V along x.
  y   : lateral displacement of the wheelset centre, left positive.
  psi : yaw about +z, positive turns the nose to the left.
  phi : roll about +x, positive lifts the LEFT wheel. Not a DOF:
        phi = sigma*y with sigma = lam/b (as in the task statement; see 7.).
Spin: forward rolling needs angular velocity +Omega about the axle
(+y): v_contact = V x + (Omega y) x (-r0 z) = (V - Omega r0) x = 0
=> Omega = V/r0, taken constant (to 1st order the two longitudinal
creep forces are equal and opposite, so no net spin torque).

delta0 = atan(lam), s = sin(delta0), c = cos(delta0),
D = b c - r0 s  (roll lever of a normal-force difference, see 3.)

Contact geometry (left L at rail y=+b, right R at y=-b):
  r_L = r0 + lam_e y, r_R = r0 - lam_e y  (lam_e = lam, statement)
  contact point relative to the centre, in track axes:
      rho_L = (x_L,  b - y, -r0),   rho_R = (x_R, -b - y, -r0)
  contact angles gamma_L = delta0 + phi, gamma_R = delta0 - phi
  unit normals (force of rail ON wheel, pointing into the wheel):
      n_L = (0, -sin gL, cos gL),   n_R = (0, +sin gR, cos gR)
  in-plane lateral unit vectors (roughly +y):
      t_L = (0, cos gL, sin gL),     t_R = (0, cos gR, -sin gR)
  For a yawed cone the true point of tangency with the knife edge is
  at x_L = -e psi, x_R = +e psi, e = b - r0 lam, and the normal stays
  in the y-z plane (no x component).  [Verified numerically: centre
  height z_c(psi) = r0 - lam (b - r0 lam) psi^2/2.]  Creep axes are
  track axes (x along the rail = rolling direction; t in the plane).

=====================================================================
1. Creepages (wheel material velocity at contact, rail at rest, / V)
=====================================================================
omega = (phidot - Omega psi, Omega, psidot + T*Omega*phi), i.e.
phidot x + psidot z + Omega a, axle a = (-psi, 1, phi).  v = (V, ydot, 0) + omega x rho.

Longitudinal (x lies in the contact plane):
  v_x = V - Omega r_{L,R} - psidot*(+-b)
  xi_xL = -lam_e y/r0 - b psidot/V ,  xi_xR = +lam_e y/r0 + b psidot/V
Lateral: horizontal slip v_y = ydot + r0 phidot - V psi
  (the r0 phidot term = roll kinematics, flag 'roll_kin'; -V psi from
  -omega_x rho_z = -Omega r0 psi).  The contact constraint gives the
  slip a vertical part v_y tan(gamma), so the in-plane slip is
  v_y / cos(gamma):
  xi_y (both wheels) = (kappa ydot - V psi)/(V c),  kappa = 1 + r0 sigma
  (cos gamma = c + O(phi) multiplies a 1st-order slip -> c).
Spin (omega . n / V):
  phi_sL = (psidot cos gL - Omega sin gL + T Omega phi cos gL)/V
  phi_sR = (psidot cos gR + Omega sin gR + T Omega phi cos gR)/V
  zeroth order: phi_sL0 = -s/r0, phi_sR0 = +s/r0
  first order (both wheels): phi_s1 = c psidot/V - (1-T) c sigma y/r0
  T = 1 (flag 'spin_axle_tilt', physically exact): the spin vector
  Omega a is tilted by the roll phi; this exactly cancels the change of
  contact angle (the angle between axle and cone normal is fixed), so
  the O(y) spin term vanishes.  T = 0 reproduces the task statement's literal
  "-Omega sin(gamma_L)" (axle treated as horizontal).

=====================================================================
2. Creep forces (Kalker linear, per wheel, load independent)
=====================================================================
  F_x = -f11 xi_x ;  F_y = -f22 xi_y - f23 phi_s ;  M_z = f23 xi_y - f33 phi_s
Zeroth order (constant spin creepage of a cone):
  F_yL0 = +F0, F_yR0 = -F0, F0 = f23 s/r0   (along t_L / t_R)
  M_zL0 = +M0, M_zR0 = -M0, M0 = f33 s/r0   (about n_L / n_R)
First order (identical on both wheels):
  F_y1 = -f22 (kappa ydot - V psi)/(V c) - f23 phi_s1
  M_z1 = +f23 (kappa ydot - V psi)/(V c) - f33 phi_s1
  F1 := F_yL1 + F_yR1 = 2 F_y1
  F_xL = f11 (lam_e y/r0 + b psidot/V) = -F_xR

=====================================================================
3. Normal forces (quasi-static vertical + roll balance about centre)
=====================================================================
N_L = N0 + dN_L, N_R = N0 + dN_R, dN = dN_L - dN_R.
Vertical, 0th order: 2 N0 c + 2 F0 s = W  ->  N0 = (W - 2 F0 s)/(2c)
  (the constant spin forces F0 have upward components F0 s).
Roll moment about x through the centre (rho x F)_x = rho_y F_z - rho_z F_y:
  normal forces:    D dN - 2 N0 [y c + (b s + r0 c) phi]
  F0 (geometry):    2 F0 (-y s + D phi)
  F1:               (b s + r0 c) F1
  gyroscopic:       + I_s Omega psidot       (flag 'gyro_roll')
  (F_x, M_z n have no roll moment: n has no x-component.)
  Roll inertia I_x*phi'' is NOT included (quasi-static roll, as the
  statement prescribes; with I_x it would add I_x sigma^2-type mass terms).
Sum = 0 gives dN (flag 'load_transfer'; off => dN = 0, N_L = N_R = N0).

=====================================================================
4. Lateral equation  m y'' = sum F_y - k_y y
=====================================================================
  normals:      -N_L sin gL + N_R sin gR = -2 N0 c phi - s dN
  tangential:   F_yL cos gL + F_yR cos gR = c F1 - 2 F0 s phi
Eliminating dN:
  sum F_y = A_F F1 - 2 N0 c sigma y - 2 F0 s sigma y
            + LT (s/D)[ -2 N0 (c + (b s + r0 c) sigma) y
                        + 2 F0 (D sigma - s) y + GR I_s Omega psidot ]
  A_F = c + LT (s/D)(b s + r0 c)  (= b/D with load transfer, = c without):
  a lateral creep force acts at rail level (r0 below the centre), its
  roll moment shifts load between the inclined normals and adds a
  lateral component.  The y-shift of the load (term y c) doubles the
  gravitational stiffness for cones: with exact geometry the result
  equals W d^2 z_c/dy^2 (checked numerically against the exact height
  function), approx 2 W lam/b, whereas the equal-load ("textbook")
  value is W lam / b.

=====================================================================
5. Yaw equation  I_z psi'' = sum M_z - k_psi psi
=====================================================================
  F_x:        -b F_xL + b F_xR = -2 b f11 (lam_e y/r0 + b psidot/V)
  spin moments: M_zL cos gL + M_zR cos gR = c (2 M_z1) - 2 M0 s phi
  contact shift of the 0th-order lateral forces Y_L0 = -N0 s + F0 c,
  Y_R0 = -Y_L0 at x = -+ e psi: +2 e (N0 s - F0 c) psi  (flag
  'grav_yaw'; the N0 part is the negative gravitational yaw stiffness
  -W lam (b - r0 lam), equal to W d^2 z_c/dpsi^2)
  gyroscopic: dH/dt = I_s Omega (phidot z - psidot x) => yaw moment
  -I_s Omega phidot = -I_s Omega sigma ydot  (flag 'gyro_yaw')
  (the roll part +I_s Omega psidot is the term in 3.)

=====================================================================
6. Final matrices (flags: L long_creep, Y lat_creep, S spin_creep,
   G grav, LT load_transfer, RK roll_kin, GY gyro_yaw, GR gyro_roll,
   GW grav_yaw, T spin_axle_tilt; a switched-off creep flag sets the
   corresponding f's to 0; F0, M0 exist only with S)
=====================================================================
  M = diag(m, I_z)
  C_yy     = A_F 2 f22 kappa / (V c)
  C_ypsi   = A_F 2 f23 c / V  -  LT GR (s/D) I_s Omega
  C_psiy   = -2 f23 kappa / V  +  GY I_s Omega sigma
  C_psipsi = 2 f11 b^2 / V  +  2 f33 c^2 / V
  K_yy     = k_y + G 2 N0 c sigma + 2 F0 s sigma
             + LT (s/D) [ G 2 N0 (c + (b s + r0 c) sigma) - 2 F0 (D sigma - s) ]
             - A_F 2 f23 (1-T) c sigma / r0
  K_ypsi   = -A_F 2 f22 / c
  K_psiy   = 2 b f11 lam_e / r0 - 2 f33 (1-T) c^2 sigma / r0 + 2 M0 s sigma
  K_psipsi = k_psi + 2 f23 - GW 2 e (G N0 s - F0 c)
Textbook (Wickens) limit, L,Y,G only: A_F = c, kappa = 1, N0 = W/(2c):
  m y'' + 2 f22/V y' - 2 f22 psi + (k_y + W lam/b) y = 0
  I_z psi'' + 2 f11 b^2/V psi' + 2 f11 b lam/r0 y + k_psi psi = 0
Gyroscopic pair with LT+GR+GY: C_ypsi = -(s/D) I_s Omega,
  C_psiy = +sigma I_s Omega  -> skew (conservative) when sigma = s/D.

=====================================================================
7. Approximations / dropped terms
=====================================================================
* All products of (y, psi, ydot, psidot) dropped, e.g. the rise of the
  centre O(y^2), cos(gamma) - c multiplying 1st-order creepages, load
  dependence of creep coefficients, psi * F_x, x_L * F_y1, y * F_x in
  the yaw arm (b - y), second-order spin-rate changes, vertical
  accelerations (z_c'' = O(y ydot^2 ...)).
* Roll inertia I_x phi'' neglected (quasi-static roll, per statement).
* Brief kinematics: phi = lam y/b and r = r0 +- lam y.  Exact cone /
  knife-edge geometry gives phi = (s/D) y = lam y/(b - r0 lam) and
  lam_e = lam b/(b - r0 lam) (about 12.6% larger for the example);
  available with flag 'exact_cone_geometry' (default off).
* Sign of f23: taken literally from the task statement's Kalker law, with the
  normal n pointing into the wheel (up).  Kalker's own contact axes
  may flip the sign of f23 terms; only the f23 results depend on it.
"""
from __future__ import annotations

import numpy as np

FLAG_NAMES = ("long_creep", "lat_creep", "spin_creep", "grav", "load_transfer",
              "roll_kin", "gyro_yaw", "gyro_roll", "grav_yaw", "spin_axle_tilt",
              "exact_cone_geometry")

# everything the physics (as derived above) contains
FLAGS_ALL = dict(long_creep=True, lat_creep=True, spin_creep=True, grav=True,
                 load_transfer=True, roll_kin=True, gyro_yaw=True, gyro_roll=True,
                 grav_yaw=True, spin_axle_tilt=True, exact_cone_geometry=False)


def _get(p, k):
    return p[k] if isinstance(p, dict) else getattr(p, k)


def _flags(flags=None, **kw):
    f = dict(FLAGS_ALL)
    if flags is not None:
        f.update(flags)
    f.update(kw)
    unknown = set(f) - set(FLAG_NAMES)
    if unknown:
        raise KeyError(f"unknown flags {unknown}")
    return f


def wheelset_matrices(V, p, flags=None, **kw):
    """(M, C, K), 2x2 each, coordinates (y, psi).  flags: dict (default FLAGS_ALL),
    individual flags may also be given as keywords."""
    f = _flags(flags, **kw)
    m, Iz, Is = _get(p, "m"), _get(p, "I_z"), _get(p, "I_s")
    r0, b, lam, W = _get(p, "r0"), _get(p, "b"), _get(p, "lam"), _get(p, "W")
    f11 = _get(p, "f11") if f["long_creep"] else 0.0
    f22 = _get(p, "f22") if f["lat_creep"] else 0.0
    f23 = _get(p, "f23") if f["spin_creep"] else 0.0
    f33 = _get(p, "f33") if f["spin_creep"] else 0.0
    ky, kpsi = _get(p, "k_y"), _get(p, "k_psi")

    d0 = np.arctan(lam)
    s, c = np.sin(d0), np.cos(d0)
    D = b * c - r0 * s
    if f["exact_cone_geometry"]:
        sigma = s / D
        lam_e = lam * b * c / D
    else:
        sigma = lam / b
        lam_e = lam
    e = b - r0 * lam
    Omega = V / r0

    G = 1.0 if f["grav"] else 0.0
    LT = 1.0 if f["load_transfer"] else 0.0
    GY = 1.0 if f["gyro_yaw"] else 0.0
    GR = 1.0 if f["gyro_roll"] else 0.0
    GW = 1.0 if f["grav_yaw"] else 0.0
    nT = 0.0 if f["spin_axle_tilt"] else 1.0          # (1 - T)
    kappa = 1.0 + (r0 * sigma if f["roll_kin"] else 0.0)

    F0 = f23 * s / r0
    M0 = f33 * s / r0
    N0 = (W - 2.0 * F0 * s) / (2.0 * c)
    A_F = c + LT * (s / D) * (b * s + r0 * c)

    C = np.empty((2, 2))
    K = np.empty((2, 2))
    C[0, 0] = A_F * 2 * f22 * kappa / (V * c)
    C[0, 1] = A_F * 2 * f23 * c / V - LT * GR * (s / D) * Is * Omega
    C[1, 0] = -2 * f23 * kappa / V + GY * Is * Omega * sigma
    C[1, 1] = 2 * f11 * b**2 / V + 2 * f33 * c**2 / V
    K[0, 0] = (ky + G * 2 * N0 * c * sigma + 2 * F0 * s * sigma
               + LT * (s / D) * (G * 2 * N0 * (c + (b * s + r0 * c) * sigma)
                                 - 2 * F0 * (D * sigma - s))
               - A_F * 2 * f23 * nT * c * sigma / r0)
    K[0, 1] = -A_F * 2 * f22 / c
    K[1, 0] = 2 * b * f11 * lam_e / r0 - 2 * f33 * nT * c**2 * sigma / r0 + 2 * M0 * s * sigma
    K[1, 1] = kpsi + 2 * f23 - GW * 2 * e * (G * N0 * s - F0 * c)
    M = np.diag([m, Iz]).astype(float)
    return M, C, K


def eigenvalues(V, p, flags=None, **kw):
    """4 eigenvalues [1/s] of M q'' + C q' + K q = 0, sorted by real part (descending)."""
    M, C, K = wheelset_matrices(V, p, flags, **kw)
    Mi = np.linalg.inv(M)
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Mi @ K, -Mi @ C]])
    ev = np.linalg.eigvals(A)
    return ev[np.argsort(-ev.real, kind="stable")]


def max_real(V, p, flags=None, **kw):
    return float(np.max(eigenvalues(V, p, flags, **kw).real))


def critical_speed(p, v_lo=0.5, v_hi=200.0, tol=1e-4, flags=None, n_scan=2000, **kw):
    """Smallest V in [v_lo, v_hi] where max Re(eig) changes sign (first sign change
    of a linear scan with n_scan points, refined by bisection to tol).  NaN if none."""
    Vs = np.linspace(v_lo, v_hi, n_scan)
    g = np.array([max_real(V, p, flags, **kw) for V in Vs])
    idx = np.nonzero(np.sign(g[1:]) != np.sign(g[:-1]))[0]
    if len(idx) == 0:
        return float("nan")
    a, bb = Vs[idx[0]], Vs[idx[0] + 1]
    ga = g[idx[0]]
    while bb - a > tol:
        mid = 0.5 * (a + bb)
        gm = max_real(mid, p, flags, **kw)
        if np.sign(gm) == np.sign(ga):
            a, ga = mid, gm
        else:
            bb = mid
    return 0.5 * (a + bb)
