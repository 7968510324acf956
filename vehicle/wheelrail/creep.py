"""Creep forces: Kalker's linear theory with Shen-Hedrick-Elkins saturation, Hertz contact
ellipse, and the creepages of a wheelset. Pure functions, SI units, numpy only.

Contact frame (per wheel): x forward (rolling direction), y in the contact plane pointing to the
**left** of the track (for both wheels), n the contact normal pointing from the rail into the
wheel (up); (x, y, n) is right-handed. Forces and the spin moment act **on the wheel**.

Kalker linear theory (Kalker 1967; table E.3 of Kalker 1990, "Three-dimensional elastic bodies in
rolling contact"), with c^2 = a b (a: semi-axis along x, b: across)::

    F_x = -G a b C11 xi_x
    F_y = -G a b C22 xi_y - G (a b)^{3/2} C23 phi
    M_z =  G (a b)^{3/2} C23 xi_y - G (a b)^2 C33 phi

Saturation (Shen, Hedrick & Elkins 1983, "A comparison of alternative creep force models for
rail vehicle dynamic analysis", 8th IAVSD): with the linear resultant F = sqrt(F_x^2 + F_y^2)
and u = F / (mu N)::

    F' = mu N (u - u^2/3 + u^3/27)   for u <= 3,      F' = mu N   for u > 3,

and both force components (and, here, M_z) are scaled by eps = F'/F. The law is tangent to the
linear one at u = 0 and reaches mu N with zero slope at u = 3.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk, ellipkm1

__all__ = [
    "SHEAR_MODULUS_PA",
    "POISSON_RATIO",
    "kalker_coefficients",
    "KalkerCoefficients",
    "hertz_semi_axes",
    "creepages",
    "kalker_linear",
    "shen_hedrick_elkins",
    "creep_forces",
]

SHEAR_MODULUS_PA = 82.0e9  # steel, wheel and rail alike
POISSON_RATIO = 0.28

# --- Kalker's coefficients, Table E.3 of Kalker (1990) ------------------------------------------
# Transcribed from CONTACT (github.com/eve70a/CONTACT, Apache-2.0), src/m_hertz.f90, subroutine
# linrol ("table E.3 of Kalker coefficients Cij of the linear theory of rolling contact for
# elliptical contact areas"). Rows: g = 0.1 .. 1.0 for a/b = g (a <= b) and, in the second half,
# for b/a = g (a >= b); columns nu = 0, 0.25, 0.5. (CONTACT's src/usetab_table.f90 carries a
# copy with a typo, C23(nu=0.25, g=0.8, a<b) = 1.15; m_hertz.f90 has 1.25, which also matches
# the independent transcription of the nu = 0.25 column in the Iwnicki-handbook form.)
_G = np.round(np.arange(1, 11) * 0.1, 10)
_NU = np.array([0.0, 0.25, 0.5])
# [case a<=b | a>=b][row g][nu]
_C11 = np.array([
    [[2.51, 3.31, 4.85], [2.59, 3.37, 4.81], [2.68, 3.44, 4.80], [2.78, 3.53, 4.82],
     [2.88, 3.62, 4.83], [2.98, 3.72, 4.91], [3.09, 3.81, 4.97], [3.19, 3.91, 5.05],
     [3.29, 4.01, 5.12], [3.40, 4.12, 5.20]],
    [[10.7, 11.7, 12.9], [6.96, 7.78, 8.82], [5.57, 6.34, 7.34], [4.84, 5.57, 6.57],
     [4.37, 5.10, 6.11], [4.06, 4.78, 5.80], [3.82, 4.54, 5.58], [3.65, 4.36, 5.42],
     [3.51, 4.22, 5.30], [3.40, 4.12, 5.20]],
])
_C22 = np.array([
    [[2.51, 2.52, 2.53], [2.59, 2.63, 2.66], [2.68, 2.75, 2.81], [2.78, 2.88, 2.98],
     [2.88, 3.01, 3.14], [2.98, 3.14, 3.31], [3.09, 3.28, 3.48], [3.19, 3.41, 3.65],
     [3.29, 3.54, 3.82], [3.40, 3.67, 3.98]],
    [[10.7, 12.8, 16.0], [6.96, 8.14, 9.79], [5.57, 6.40, 7.51], [4.84, 5.48, 6.31],
     [4.37, 4.90, 5.56], [4.06, 4.50, 5.04], [3.82, 4.21, 4.67], [3.65, 3.99, 4.39],
     [3.51, 3.81, 4.16], [3.40, 3.67, 3.98]],
])
_C23 = np.array([
    [[.334, .473, .731], [.483, .603, .809], [.607, .715, .889], [.720, .823, .977],
     [.827, .929, 1.07], [.930, 1.03, 1.18], [1.03, 1.14, 1.29], [1.13, 1.25, 1.40],
     [1.23, 1.36, 1.51], [1.33, 1.47, 1.63]],
    [[12.2, 14.6, 18.0], [5.72, 6.63, 7.89], [3.79, 4.32, 5.01], [2.88, 3.24, 3.70],
     [2.35, 2.62, 2.96], [2.01, 2.23, 2.50], [1.76, 1.95, 2.18], [1.58, 1.75, 1.94],
     [1.44, 1.59, 1.77], [1.33, 1.47, 1.63]],
])
# C33 is not in CONTACT (it needs only C11, C22, C23). Values as transcribed (two decimals) in
# github.com/RoccoLiberoGiossi/SimRail, lib/contact_kalkers_table.py, from the same Kalker table;
# lower precision and a secondary source: used only for the spin moment M_z.
_C33 = np.array([
    [[6.42, 8.28, 11.7], [3.46, 4.27, 5.66], [2.49, 2.96, 3.72], [2.02, 2.32, 2.77],
     [1.74, 1.93, 2.22], [1.56, 1.68, 1.86], [1.43, 1.50, 1.60], [1.34, 1.37, 1.42],
     [1.27, 1.27, 1.27], [1.21, 1.19, 1.16]],
    [[0.80, 0.53, 0.23], [0.83, 0.60, 0.34], [0.87, 0.67, 0.45], [0.91, 0.75, 0.55],
     [0.96, 0.82, 0.65], [1.01, 0.89, 0.75], [1.05, 0.97, 0.85], [1.10, 1.04, 0.95],
     [1.16, 1.11, 1.06], [1.21, 1.19, 1.16]],
])


class KalkerCoefficients(NamedTuple):
    C11: float
    C22: float
    C23: float
    C33: float


def kalker_coefficients(a_over_b: float, nu: float = POISSON_RATIO) -> KalkerCoefficients:
    """Kalker's creep coefficients at ellipse ratio a/b (a along the rolling direction).

    Interpolation as in CONTACT's ``linrol``: linear in g = min(a/b, b/a) within the half of the
    table that applies (a <= b or a >= b), then in nu by the quadratic through the three
    tabulated Poisson ratios applied to 1/C. Outside 0.1 <= g, Kalker's asymptotic expressions
    (also from ``linrol``) are used for C11, C22, C23; C33 is then held at the table's end value.
    """
    aob = float(a_over_b)
    if not (aob > 0 and math.isfinite(aob)):
        raise ValueError("a/b must be positive and finite")
    if not 0.0 <= nu <= 0.5:
        raise ValueError("Poisson ratio must be in [0, 0.5]")
    case, g = (0, aob) if aob <= 1.0 else (1, 1.0 / aob)
    if g < 0.1:
        c11, c22, c23 = _kalker_asymptotes(case, g, nu)
        c33 = float(_nu_interp(_C33[case, 0], nu))
        return KalkerCoefficients(c11, c22, c23, c33)
    # linear in g between tabulated rows (rows are g = 0.1 .. 1.0)
    pos = min(max(10.0 * g - 1.0, 0.0), 9.0)
    i = min(int(math.floor(pos)), 8)
    f = pos - i
    out = []
    for tab in (_C11, _C22, _C23, _C33):
        row = (1.0 - f) * tab[case, i] + f * tab[case, i + 1]
        out.append(float(_nu_interp(row, nu)))
    return KalkerCoefficients(*out)


def _nu_interp(c3: np.ndarray, nu: float) -> float:
    """Quadratic (Lagrange) interpolation of 1/C through nu = 0, 0.25, 0.5 (CONTACT linrol)."""
    inv = ((nu - 0.25) * (nu - 0.5) * 8.0 / c3[0]
           - (nu - 0.5) * nu * 16.0 / c3[1]
           + nu * (nu - 0.25) * 8.0 / c3[2])
    return 1.0 / inv


def _kalker_asymptotes(case: int, g: float, nu: float):
    pi = math.pi
    if case == 0:  # a << b
        c11 = pi ** 2 / 4.0 / (1.0 - nu)
        c22 = pi ** 2 / 4.0
        c23 = pi * math.sqrt(g) / 3.0 / (1.0 - nu) * (1.0 + nu * (math.log(16.0 / g) - 5.0))
        return c11, c22, c23
    al = math.log(16.0 / g ** 2)  # a >> b
    c11 = 2 * pi / (al - 2 * nu) / g * (1 + (3 - math.log(4.0)) / (al - 2 * nu))
    w = (1 - nu) * al + 2 * nu
    c22 = 2 * pi / g * (1 + (1 - nu) * (3 - math.log(4.0)) / w) / w
    c23 = 2 * pi / 3.0 / g ** 1.5 / ((1 - nu) * al - 2 + 4 * nu)
    return c11, c22, c23


# --- Hertz ------------------------------------------------------------------------------------
def hertz_semi_axes(normal_force_N: float, A: float, B: float,
                    G: float = SHEAR_MODULUS_PA, nu: float = POISSON_RATIO) -> tuple[float, float]:
    """Hertz contact-ellipse semi-axes (a along x, b along y), m.

    ``A``, ``B`` are the relative curvatures of the gap h = A x^2 + B y^2 (1/m):
    A = (1/R_wheel,x + 1/R_rail,x) / 2 (wheel rolling circle: 1/R = cos(delta)/r, rail straight),
    B = (kappa_wheel + kappa_rail) / 2 with the transverse profile curvatures, convex positive
    (the ``kw``/``kr`` columns of the contact table). Both must be positive (a concave wheel
    closer in curvature than the rail crown is a conformal, non-Hertzian contact).

    Method: the standard elliptic-integral solution (Johnson, *Contact Mechanics*, 1985, sec. 4.2),
    not the tabulated Hertz coefficients m, n. With e the eccentricity (e^2 = 1 - (minor/major)^2),
    K, E the complete elliptic integrals of parameter e^2::

        B_minor / A_major = (E / (1 - e^2) - K) / (K - E)            (ellipticity)
        major^3 = 3 N (K - E) / (2 pi E* e^2 A_major)                 (size)

    where A_major is the smaller curvature (along the major axis), E* = E / (2 (1 - nu^2)) =
    G / (1 - nu) for identical materials. For A = B it reduces to the circle
    a = b = (3 N R / (4 E*))^{1/3} with A = B = 1/(2R).
    """
    N = float(normal_force_N)
    if N < 0:
        raise ValueError("normal force must be non-negative")
    if not (A > 0 and B > 0):
        raise ValueError("relative curvatures A and B must be positive (Hertzian contact)")
    if N == 0:
        return 0.0, 0.0
    e_star = G / (1.0 - nu)
    lo_c, hi_c = (A, B) if A <= B else (B, A)  # curvature along major / minor axis
    ratio = hi_c / lo_c
    if ratio - 1.0 < 1e-6:  # circle (the ellipse differs by < 1e-6 relative)
        R = 1.0 / (A + B)
        a = (3.0 * N * R / (4.0 * e_star)) ** (1.0 / 3.0)
        return a, a

    def f(log_k):  # k = minor/major = exp(log_k) < 1; m = e^2 = 1 - k^2
        k = math.exp(log_k)
        m1 = k * k
        m = 1.0 - m1
        K = float(ellipkm1(m1))
        E = float(ellipe(m))
        return math.log((E / m1 - K) / (K - E)) - math.log(ratio)

    log_k = brentq(f, math.log(1e-8), math.log(1.0 - 1e-9), xtol=1e-15, rtol=1e-15)
    k = math.exp(log_k)
    m = 1.0 - k * k
    K, E = float(ellipk(m)), float(ellipe(m))
    major = (3.0 * N * (K - E) / (2.0 * math.pi * e_star * m * lo_c)) ** (1.0 / 3.0)
    minor = k * major
    # the major axis lies along the direction of smaller relative curvature
    return (major, minor) if A <= B else (minor, major)


# --- creepages -------------------------------------------------------------------------------
def creepages(V: float, y_dot: float, psi: float, psi_dot: float, omega: float, r: float,
              gamma: float, b: float, side: str, roll_rate: float = 0.0):
    """Creepages (xi_x, xi_y, phi) of one wheel, contact-frame axes as in the module docstring.

    V        forward speed of the wheelset centre (m/s, > 0)
    y_dot    lateral velocity of the wheelset centre (m/s, left positive)
    psi      yaw angle (rad, counter-clockwise seen from above positive)
    psi_dot  yaw rate (rad/s)
    omega    spin (rolling) rate about the axle (rad/s, positive when rolling forward; V / r0 for
             free rolling)
    r        rolling radius of this wheel (m)
    gamma    contact angle in the track frame (rad, table convention: >0 descending to the
             centre)
    b        lateral distance of the contact point from the wheelset centre (m, > 0)
    side     'left' or 'right'
    roll_rate  roll rate of the wheelset (rad/s), optional

    Definitions (relative velocity of the wheel material at the contact point with respect to
    the rail, divided by V; small yaw)::

        xi_x = (V -+ b psi_dot - omega r) / V                 (- left, + right)
        xi_y = (y_dot + r roll_rate - V psi) / (V cos gamma)
        phi  = (psi_dot cos gamma -+ omega sin gamma) / V      (- left, + right)

    xi_y is the in-plane lateral slip with the rigid-contact constraint (the contact point's
    vertical velocity keeps the slip in the tangent plane, hence 1/cos gamma); phi is the wheel's
    angular velocity about the contact normal (n_L = (0, -sin g, cos g), n_R = (0, sin g, cos g)).
    Free rolling of a centred wheelset on a cone therefore has phi_L = -sin(gamma)/r0 < 0 and
    phi_R = +sin(gamma)/r0.
    """
    if not V > 0:
        raise ValueError("forward speed V must be positive")
    s = {"left": 1.0, "right": -1.0}[side]
    xi_x = (V - s * b * psi_dot - omega * r) / V
    xi_y = (y_dot + r * roll_rate - V * psi) / (V * math.cos(gamma))
    phi = (psi_dot * math.cos(gamma) - s * omega * math.sin(gamma)) / V
    return xi_x, xi_y, phi


# --- forces ----------------------------------------------------------------------------------
def kalker_linear(xi_x, xi_y, phi, a: float, b: float, G: float = SHEAR_MODULUS_PA,
                  nu: float = POISSON_RATIO):
    """Kalker's linear creep forces and spin moment (F_x, F_y, M_z) on the wheel, N and N m."""
    c = kalker_coefficients(a / b, nu)
    ab = a * b
    xi_x, xi_y, phi = (np.asarray(v, dtype=float) for v in (xi_x, xi_y, phi))
    fx = -G * ab * c.C11 * xi_x
    fy = -G * ab * c.C22 * xi_y - G * ab ** 1.5 * c.C23 * phi
    mz = G * ab ** 1.5 * c.C23 * xi_y - G * ab ** 2 * c.C33 * phi
    return fx, fy, mz


def shen_hedrick_elkins(fx, fy, mu_N):
    """Saturation factor eps (Shen-Hedrick-Elkins 1983) for linear forces fx, fy and limit mu N."""
    fx, fy = np.asarray(fx, dtype=float), np.asarray(fy, dtype=float)
    mu_N = np.asarray(mu_N, dtype=float)
    F = np.hypot(fx, fy)
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.where(mu_N > 0, F / mu_N, np.inf)
        Fs = np.where(u <= 3.0, mu_N * (u - u * u / 3.0 + u ** 3 / 27.0), mu_N)
        eps = np.where(F > 0, Fs / F, 1.0)
    eps = np.where(mu_N > 0, eps, 0.0)
    return eps


def creep_forces(xi_x, xi_y, phi, N: float, mu: float, a: float, b: float,
                 G: float = SHEAR_MODULUS_PA, nu: float = POISSON_RATIO):
    """Saturated creep forces (F_x, F_y, M_z) on the wheel: Kalker linear theory scaled by the
    Shen-Hedrick-Elkins factor (the method name: "Kalker linear + Shen-Hedrick-Elkins")."""
    fx, fy, mz = kalker_linear(xi_x, xi_y, phi, a, b, G, nu)
    eps = shen_hedrick_elkins(fx, fy, mu * N)
    return eps * fx, eps * fy, eps * mz
