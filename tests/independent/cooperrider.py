"""Linear stability of the Cooperrider two-axle bogie (truck) under a held carbody.

An INDEPENDENT reference model: written from the open DYTSI code (D. Bigoni, DTU,
github.com/daniele-bigoni/dytsi, snapshot 8c3d600) and from textbook linear wheel-rail theory,
without reference to pneumorail's own vehicle/ or cosim/ code. Pure numpy/scipy.

Bodies and states
-----------------
A bogie frame and two wheelsets run at constant speed V on straight, perfect track under a
carbody that moves at V and is held laterally (its lateral and yaw motion are zero). Only the
lateral plane is modelled:

    q = [y1, psi1, y2, psi2, yf, psif],   x = [q, dq/dt]   (12 first-order states)

y is lateral displacement [m] (positive to the left), psi yaw [rad] (positive nose-left, z up);
1 is the leading wheelset at x = +b, 2 the trailing one at x = -b, f the frame. Wheelset roll,
vertical motion and axle spin perturbation are not states: in a linear, left/right-antisymmetric
motion the longitudinal creep forces of the two wheels cancel in the sum, so the spin (DYTSI's
BETA state) is not excited at first order. The frame roll of Cooperrider's 7-DOF model
(Kaas-Petersen 1986, section 1: lateral/yaw of each axle plus lateral, yaw and roll of the frame)
is omitted: with the carbody held the roll couples only through the small secondary spring
heights.

Equations (M q'' + C(V) q' + K(V) q = 0)
-----------------------------------------
Creepages of the left (L, at +e) and right (R, at -e) wheel, linearised about centred rolling,
with rolling radii r_L,R = r0 +- lam*y and contact angles delta_L,R = delta0 +- eps*y/e
(DYTSI src/GeneralModel/WheelSetComponent.cpp, xi_flx l.1084-1094, xi_fly l.1108-1117,
xi_fls l.1176-1183 and their right-wheel twins l.1096-1106, 1119-1128, 1185-1192; the same
expressions as Garg & Dukkipati 1984, ch. 6, and Wickens 2003, ch. 2):

    xi_x,L = -e*psi'/V - lam*y/r0            xi_x,R = +e*psi'/V + lam*y/r0
    xi_y   =  y'/V - psi                     (both wheels)
    phi_L  =  psi'/V - delta_L/r0            phi_R  = psi'/V + delta_R/r0

Linear Kalker creep forces on each wheel (DYTSI WheelSetComponent.cpp l.1212-1219, used through
the Shen-Hedrick-Elkins saturation of l.875-886 whose slope at zero creep is one):

    F_x = -f11*xi_x ,   F_y = -f22*xi_y - f23*phi ,   [spin moment M_z = f23*xi_y - f33*phi]
    f11 = G*a*b*C11 ,   f22 = G*a*b*C22 ,   f23 = G*(a*b)**1.5*C23

(DYTSI has no spin moment; ``spin_moment=True`` adds Kalker's reciprocal yaw-moment term
f23*xi_y and the spin-moment f33 term, which DYTSI leaves out.)

Summed over the two wheels, the creep force and moment on a wheelset are

    Fy = -2*f22*(y'/V - psi)
         - [spin]   2*f23*psi'/V  +  [spin and gravity] 2*f23*eps*y/(e*r0)
    Mz = -2*f11*e*(e*psi'/V + lam*y/r0)
         + [spin_moment] 2*f23*(y'/V - psi) - 2*f33*psi'/V + [and gravity] 2*f33*eps*y/(e*r0)

Gravitational terms (``gravity=True``), from the tilted normal forces N = W/2 of the two wheels
(DYTSI WheelSetComponent.cpp l.700 Nly = -N sin(delta_L + phi), l.728 Nry = N sin(delta_R - phi),
and the yaw torques l.709 and l.737, -al*(Fly + Nly)*psi and +ar*(Fry + Nry)*psi):

    Fy_grav = -W*eps/e * y          (lateral gravitational stiffness, restoring)
    Mz_grav = +W*e*delta0 * psi     (yaw gravitational stiffness, destabilising, tiny here)

``gravity=False`` treats the profile as a cone on a knife-edge rail: eps = delta0 = 0, so both
gravitational terms and the spin force's y-term vanish.

Suspension (DYTSI src/Models/CooperriderOrthogonalModel.cpp, the model the DYTSI input files
use): per wheelset, two lateral springs k1 and dampers D5 at the wheelset's x on the frame
(l.716-752) and two longitudinal springs k2 and dampers D3 at lateral offsets +-s1 (l.792-830);
per bogie, two secondary lateral springs k4 with dampers D2 (l.374-399), two secondary
longitudinal (yaw) springs k6 with dampers D6 at lateral offsets +-d6 = +-(a+l1+l2+l3/2)
(l.446-483), all to the held carbody. With the wheelset at x_i (x_1 = +b, x_2 = -b):

    wheelset i:  m_w*y_i''   = Fy_i - 2*k1*(y_i - yf - x_i*psif) - 2*D5*(d/dt of the same)
                 I_wz*psi_i'' = Mz_i - 2*k2*s1**2*(psi_i - psif) - 2*D3*s1**2*(d/dt of the same)
    frame:       m_f*yf''    = sum_i 2*k1*(y_i - yf - x_i*psif) [+ dampers] - 2*k4*yf - 2*D2*yf'
                 I_fz*psif'' = sum_i [2*k1*x_i*(y_i - yf - x_i*psif) + 2*k2*s1**2*(psi_i - psif)]
                               [+ dampers] - 2*k6*d6**2*psif - 2*D6*d6**2*psif'

Critical speed and hunting frequency
------------------------------------
A(V) = [[0, I], [-M^-1 K(V), -M^-1 C(V)]]. The linear critical speed is the lowest V at which
max Re eig A(V) crosses zero from below (found by a grid scan, then brentq to xtol 1e-4 m/s);
the hunting frequency is |Im| / (2 pi) of that eigenvalue at the critical speed.

Checks that cannot be faked (tests/independent/test_independent_cooperrider.py): Klingel's kinematic
wavelength L = 2*pi*sqrt(e*r0/lam) of a free wheelset, the rigid-bogie kinematic wavelength
L = 2*pi*sqrt(e*r0/lam*(1 + (f22/f11)*b**2/e**2)) (Wickens 2003, ch. 2, for f11 = f22), and the Routh-Hurwitz stability
boundary of a single wheelset on a fixed frame, derived by hand from the two equations above.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

# ---------------------------------------------------------------------------------------------
# Numbers read from DYTSI (github.com/daniele-bigoni/dytsi, snapshot 8c3d600)
#   XML  = input/InputFiles/inputBifurcation-Cooperrider-straight.xml (the straight-track case)
#   CPP  = src/Models/CooperriderOrthogonalModel.cpp
#   RSG  = input/RSGEO/1o40/RSGEO.dat, the row at y = 0 (wheel-rail table, rail inclination 1:40):
#          y=-5.25e-16  N=66661.24 N  delta=0.014223 rad  a=5.95185e-3 m  b=6.65256e-3 m
#          contact y=0.756301 m  r=0.4248829 m  C11=4.124565  C22=3.563105  C23=1.370322
#   From RSG by central differences at y = +-0.1 mm (left wheel at +y, right wheel at -y, as
#   WheelSetComponent::find_rsgeodata does): (r(y)-r(-y))/(2y) = 0.02970 (equivalent conicity
#   at the centred position); (delta(y)-delta(-y))/(2y) = 4.769 1/m, eps = e*that = 3.606.
#   At +-1 mm the same give lam = 0.02750, eps = 2.396; at +-3 mm lam = 0.0572; at +-5 mm 0.0921.
# ---------------------------------------------------------------------------------------------
_G_DYTSI = 2.1e11 / (2 * (1 - 0.27))     # CPP l.631 exactly as coded: E/(2(1-nu)) = 1.438e11 Pa
_G_SHEAR = 2.1e11 / (2 * (1 + 0.27))     # the shear modulus E/(2(1+nu)) = 8.268e10 Pa
_AB = 5.95185e-3 * 6.65256e-3            # RSG contact semi-axes a*b at y = 0 [m^2]
_C11, _C22, _C23 = 4.124565, 3.563105, 1.370322   # RSG Kalker coefficients at y = 0


def kalker_f(G: float = _G_DYTSI) -> tuple[float, float, float]:
    """(f11, f22, f23) from the DYTSI table's contact at y = 0 and a modulus G
    (WheelSetComponent.cpp l.1212-1219: F_x = -G a b C11 xi_x, F_y = -G a b (C22 xi_y + sqrt(ab) C23 xi_s))."""
    return G * _AB * _C11, G * _AB * _C22, G * _AB ** 1.5 * _C23


_F11, _F22, _F23 = kalker_f()


@dataclass(frozen=True)
class CooperriderParams:
    """The Cooperrider bogie as DYTSI sets it up (defaults), SI units. Each field says where it comes from."""
    # --- masses and inertias
    m_w: float = 1022.0        # wheelset mass [kg]; CPP l.625 (also the classic Cooperrider value)
    I_wz: float = 678.0        # wheelset yaw inertia [kg m^2]; CPP l.628 (Iz)
    m_f: float = 2918.9        # bogie frame mass [kg]; CPP l.333
    I_fz: float = 6780.0       # frame yaw inertia [kg m^2]; CPP l.336 (Iz)
    # --- geometry
    r0: float = 0.4248829      # nominal rolling radius [m]; RSG at y=0 (the XML's r0 is 0.425, used by DYTSI for Omega_0)
    e: float = 0.756301        # half distance of the contact points [m]; RSG 'BJA+0.75' at y=0 (XML a = 0.75)
    b: float = 1.074           # half wheelbase [m]; XML u2 (CPP l.343 passes u2 as the frame's b)
    s1: float = 0.62           # lateral offset of the primary longitudinal springs [m]; XML s1 (CPP l.792-830)
    d6: float = 1.5            # lateral offset of the secondary yaw springs/dampers [m]; a+l1+l2+l3/2 (XML, CPP l.450)
    # --- wheel-rail contact, linearised
    lam: float = 0.02970       # equivalent conicity [-]; RSG central difference at +-0.1 mm (see above)
    eps: float = 3.606         # contact angle parameter e*d(delta)/dy [-]; RSG, same differences
    delta0: float = 0.014223   # contact angle at y=0 [rad]; RSG
    W: float = 2 * 66661.24    # axle load [N]; 2 x RSG normal force at y=0 (= car weight / 4 axles)
    f11: float = _F11          # longitudinal creep coefficient [N]; G a b C11, G as coded in CPP l.631
    f22: float = _F22          # lateral creep coefficient [N]; G a b C22
    f23: float = _F23          # lateral/spin creep coefficient [N m]; G (ab)^1.5 C23
    f33: float = 0.0           # spin creep coefficient [N m^2]; not in DYTSI (no spin moment), 0
    # --- primary suspension (per spring; two per wheelset)
    k1: float = 1.823e6        # primary lateral spring [N/m]; XML k1 (LateralSpring, CPP l.716/734)
    k2: float = 3.646e6        # primary longitudinal spring [N/m]; XML k2 (LongitudinalSpring, CPP l.792/810)
    D5: float = 0.0            # primary lateral damper [N s/m]; XML D5
    D3: float = 0.0            # primary longitudinal damper [N s/m]; XML D3
    # --- secondary suspension to the held carbody (per element; two per bogie)
    k4: float = 1.823e5        # secondary lateral spring [N/m]; XML k4 (LateralSpring, CPP l.374/394)
    D2: float = 2.92e4         # secondary lateral damper [N s/m]; XML D2 (LateralDamper, CPP l.375/395)
    k6: float = 903350.0       # secondary longitudinal (yaw) spring [N/m]; XML k6 (CPP l.460/480)
    D6: float = 166669.0       # secondary longitudinal (yaw) damper [N s/m]; XML D6 (CPP l.456/476)
    # --- switches
    spin: bool = True          # spin creep force terms f23 (as DYTSI's F_y does)
    spin_moment: bool = False  # Kalker's reciprocal spin yaw moment f23*xi_y - f33*phi (DYTSI: none)
    gravity: bool = True       # gravitational stiffness (eps, delta0); False = cone on knife-edge rail

    def replace(self, **changes) -> CooperriderParams:
        return dataclasses.replace(self, **changes)


def matrices(p: CooperriderParams, V: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(M, C, K) of the 6 degrees of freedom q = [y1, psi1, y2, psi2, yf, psif] at speed V [m/s]."""
    if V <= 0:
        raise ValueError(f"speed must be positive, got {V}")
    M = np.diag([p.m_w, p.I_wz, p.m_w, p.I_wz, p.m_f, p.I_fz])
    C = np.zeros((6, 6))
    K = np.zeros((6, 6))
    eps = p.eps if p.gravity else 0.0
    delta0 = p.delta0 if p.gravity else 0.0
    yf, pf = 4, 5
    for i, x_i in ((0, p.b), (2, -p.b)):
        y, ps = i, i + 1
        # creep force on the wheelset: Fy = -2 f22 (y'/V - psi) [- 2 f23 psi'/V + 2 f23 eps y/(e r0)]
        C[y, y] += 2 * p.f22 / V
        K[y, ps] += -2 * p.f22
        if p.spin:
            C[y, ps] += 2 * p.f23 / V
            K[y, y] += -2 * p.f23 * eps / (p.e * p.r0)
        # creep moment: Mz = -2 f11 e (e psi'/V + lam y/r0) [+ 2 f23 (y'/V - psi) - 2 f33 psi'/V + ...]
        C[ps, ps] += 2 * p.f11 * p.e ** 2 / V
        K[ps, y] += 2 * p.f11 * p.e * p.lam / p.r0
        if p.spin_moment:
            C[ps, y] += -2 * p.f23 / V
            K[ps, ps] += 2 * p.f23
            C[ps, ps] += 2 * p.f33 / V
            K[ps, y] += -2 * p.f33 * eps / (p.e * p.r0)
        # gravitational stiffness: Fy = -W eps/e y, Mz = +W e delta0 psi
        K[y, y] += p.W * eps / p.e
        K[ps, ps] += -p.W * p.e * delta0
        # primary lateral: deflection u = y_i - yf - x_i psif, force 2 k1 u (and 2 D5 u') on the wheelset
        u = np.zeros(6)
        u[y], u[yf], u[pf] = 1.0, -1.0, -x_i
        g = np.zeros(6)                          # generalised force direction of +u on the wheelset
        g[y], g[yf], g[pf] = 1.0, -1.0, -x_i     # reaction on the frame: -force at x_i
        K += 2 * p.k1 * np.outer(g, u)
        C += 2 * p.D5 * np.outer(g, u)
        # primary yaw from the longitudinal springs: 2 k2 s1^2 (psi_i - psif)
        w = np.zeros(6)
        w[ps], w[pf] = 1.0, -1.0
        K += 2 * p.k2 * p.s1 ** 2 * np.outer(w, w)
        C += 2 * p.D3 * p.s1 ** 2 * np.outer(w, w)
    # secondary, to the held carbody
    K[yf, yf] += 2 * p.k4
    C[yf, yf] += 2 * p.D2
    K[pf, pf] += 2 * p.k6 * p.d6 ** 2
    C[pf, pf] += 2 * p.D6 * p.d6 ** 2
    return M, C, K


def system_matrix(p: CooperriderParams, V: float) -> np.ndarray:
    """First-order A(V) with x' = A x, x = [q, q']."""
    M, C, K = matrices(p, V)
    Minv = np.linalg.inv(M)
    n = M.shape[0]
    return np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ C]])


def eigenvalues(p: CooperriderParams, V: float) -> np.ndarray:
    return np.linalg.eigvals(system_matrix(p, V))


def max_real(p: CooperriderParams, V: float) -> float:
    return float(np.max(eigenvalues(p, V).real))


def critical_speed(p: CooperriderParams, v_lo: float = 1.0, v_hi: float = 400.0, n_grid: int = 400,
                   xtol: float = 1e-4) -> tuple[float, float]:
    """(V_cr [m/s], hunting frequency at V_cr [Hz]): the lowest V in [v_lo, v_hi] where the largest real
    part of the eigenvalues crosses zero from below; (nan, nan) if none in the range."""
    grid = np.geomspace(v_lo, v_hi, n_grid)
    prev_v, prev_s = grid[0], max_real(p, grid[0])
    if prev_s >= 0:
        raise ValueError(f"unstable already at v_lo = {v_lo} m/s (max Re = {prev_s:.3g})")
    for v in grid[1:]:
        s = max_real(p, v)
        if s >= 0:
            vc = brentq(lambda V: max_real(p, V), prev_v, v, xtol=xtol, rtol=1e-12)
            ev = eigenvalues(p, vc)
            lead = ev[np.argmax(ev.real)]
            return float(vc), float(abs(lead.imag) / (2 * np.pi))
        prev_v, prev_s = v, s
    return float("nan"), float("nan")


def klingel_wavelength(lam: float, e: float, r0: float) -> float:
    """Kinematic wavelength of a free coned wheelset, L = 2 pi sqrt(e r0 / lam) (Klingel 1883)."""
    return 2 * np.pi * np.sqrt(e * r0 / lam)


def rigid_bogie_wavelength(lam: float, e: float, r0: float, b: float, f22_over_f11: float = 1.0) -> float:
    """Kinematic wavelength of a rigid two-axle bogie in the creep-dominated (massless) limit,
    L = 2 pi sqrt(e r0 / lam (1 + (f22/f11) b^2/e^2)); with f11 = f22 the textbook form
    2 pi sqrt(e r0 / lam (1 + b^2/e^2)) (Wickens 2003, ch. 2). Derivation: the lateral creep forces
    sum to zero, so y' = V psi; the yaw moments -4 f11 e (e psi'/V + lam y/r0) of the longitudinal
    creep and -4 f22 b^2 psi'/V of the lateral creep at +-b sum to zero, so
    psi' (f11 e^2 + f22 b^2)/V = -f11 e lam y / r0, hence y'' = -omega^2 y with
    omega^2 = V^2 lam / (e r0) / (1 + f22 b^2 / (f11 e^2))."""
    return 2 * np.pi * np.sqrt(e * r0 / lam * (1 + f22_over_f11 * b ** 2 / e ** 2))


CONICITIES = (0.05, 0.1, 0.2, 0.3)


def table(p: CooperriderParams | None = None, conicities=CONICITIES) -> list[tuple]:
    """Rows (lam, spin, gravity, V_cr, f_hunt) for spin on/off and gravity on/off."""
    p = p or CooperriderParams()
    rows = []
    for lam in conicities:
        for spin in (True, False):
            for gravity in (True, False):
                vc, f = critical_speed(p.replace(lam=lam, spin=spin, gravity=gravity))
                rows.append((lam, spin, gravity, vc, f))
    return rows


def _print_table(title: str, p: CooperriderParams) -> None:
    print(title)
    print(f"{'lambda':>7} {'spin':>5} {'grav':>5} {'V_cr [m/s]':>11} {'V_cr [km/h]':>11} {'f [Hz]':>7}")
    for lam, spin, gravity, vc, f in table(p):
        print(f"{lam:7.2f} {'on' if spin else 'off':>5} {'on' if gravity else 'off':>5} {vc:11.3f} {vc * 3.6:11.1f} {f:7.3f}")
    print()


if __name__ == "__main__":
    p0 = CooperriderParams()
    vc, f = critical_speed(p0)
    print(f"DYTSI Cooperrider set, held carbody, lam = {p0.lam} (DYTSI table at y=0): "
          f"V_cr = {vc:.3f} m/s, f = {f:.3f} Hz")
    print(f"creep coefficients (G as coded in DYTSI, {_G_DYTSI:.4g} Pa): f11 = {p0.f11:.4g} N, "
          f"f22 = {p0.f22:.4g} N, f23 = {p0.f23:.4g} N m\n")
    _print_table("Critical speed and hunting frequency, DYTSI parameters (G = E/(2(1-nu)) as coded):", p0)
    f11, f22, f23 = kalker_f(_G_SHEAR)
    _print_table("Same with the shear modulus G = E/(2(1+nu)) = 8.27e10 Pa:", p0.replace(f11=f11, f22=f22, f23=f23))
