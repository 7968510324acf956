"""Checks of the independent Cooperrider model against what cannot be tuned: kinematic wavelengths
(Klingel's for a free wheelset, Wickens' for a rigid bogie), the algebra of a real system
(conjugate eigenvalue pairs), a hand-derived Routh-Hurwitz boundary, and the trend with conicity.

No published linear critical speed for exactly this parameter set could be read (see README.md):
the one that could, 68.66 for Kaas-Petersen's 7-DOF set (bifurcation.de, example exd10), uses a
different profile, creep law and frame roll, so it is quoted, not asserted."""
from __future__ import annotations

import numpy as np
import pytest
from independent.cooperrider import (
    CONICITIES,
    CooperriderParams,
    critical_speed,
    eigenvalues,
    klingel_wavelength,
    max_real,
    rigid_bogie_wavelength,
    table,
)

P0 = CooperriderParams()
SWITCHES = [(s, g) for s in (True, False) for g in (True, False)]


def _kinematic(p: CooperriderParams, creep_factor: float) -> CooperriderParams:
    """Creep-dominated limit: creep coefficients scaled up, no spin, no gravitational stiffness."""
    return p.replace(f11=p.f11 * creep_factor, f22=p.f22 * creep_factor, f23=p.f23 * creep_factor,
                     spin=False, gravity=False)


def _closest_frequency(p: CooperriderParams, V: float, target_hz: float) -> complex:
    ev = eigenvalues(p, V)
    osc = ev[ev.imag > 0]
    return osc[np.argmin(abs(osc.imag / (2 * np.pi) - target_hz))]


@pytest.mark.parametrize("lam", CONICITIES)
@pytest.mark.parametrize("V", [2.0, 10.0])
def test_free_wheelset_runs_at_klingels_wavelength(lam, V):
    """No primary suspension (free wheelsets), creep x1000: a wheelset mode at V / L_Klingel.
    The inertial correction scales as m V^2 / f22 ~ 1e-5 here; 0.1 % is a generous bound."""
    p = _kinematic(P0.replace(lam=lam, k1=0.0, k2=0.0), 1e3)
    f_k = V / klingel_wavelength(lam, p.e, p.r0)
    ev = _closest_frequency(p, V, f_k)
    assert ev.imag / (2 * np.pi) == pytest.approx(f_k, rel=1e-3)
    assert abs(ev.real) < 1e-2 * ev.imag                  # a (nearly) undamped kinematic oscillation


@pytest.mark.parametrize("lam", CONICITIES)
def test_free_wheelset_with_nominal_creep_at_low_speed(lam):
    """With the DYTSI creep coefficients, at 2 m/s the free wheelset still follows Klingel within 1 %."""
    p = _kinematic(P0.replace(lam=lam, k1=0.0, k2=0.0), 1.0)
    f_k = 2.0 / klingel_wavelength(lam, p.e, p.r0)
    assert _closest_frequency(p, 2.0, f_k).imag / (2 * np.pi) == pytest.approx(f_k, rel=1e-2)


@pytest.mark.parametrize("lam", CONICITIES)
def test_rigid_bogie_runs_at_its_kinematic_wavelength(lam):
    """Primary suspension rigid (1e14), no secondary, creep x100: the bogie's kinematic mode has
    L = 2 pi sqrt(e r0/lam (1 + (f22/f11) b^2/e^2)), longer than a free wheelset's. The primary
    must be much stiffer than the creep forces (at 1e12 with creep x1000 the error is 0.05 %)."""
    p = _kinematic(P0.replace(lam=lam, k1=1e14, k2=1e14, k4=0.0, D2=0.0, k6=0.0, D6=0.0), 1e2)
    V = 10.0
    f_b = V / rigid_bogie_wavelength(lam, p.e, p.r0, p.b, p.f22 / p.f11)
    assert _closest_frequency(p, V, f_b).imag / (2 * np.pi) == pytest.approx(f_b, rel=1e-4)
    # and the equal-creep textbook form is off by exactly the creep ratio's share
    assert V / rigid_bogie_wavelength(lam, p.e, p.r0, p.b) != pytest.approx(f_b, rel=1e-2)


@pytest.mark.parametrize("spin,gravity", SWITCHES)
@pytest.mark.parametrize("V", [1.0, 5.0, 20.0])
def test_eigenvalues_are_conjugate_pairs_and_stable_at_low_speed(spin, gravity, V):
    p = P0.replace(spin=spin, gravity=gravity)
    ev = eigenvalues(p, V)
    assert len(ev) == 12
    complex_ev = ev[abs(ev.imag) > 1e-9 * abs(ev).max()]
    np.testing.assert_allclose(np.sort_complex(complex_ev), np.sort_complex(complex_ev.conj()), rtol=1e-9)
    assert max_real(p, V) < 0


def _hurwitz_critical_speed(m, I, f11, f22, e, r0, lam, k_y, k_psi):
    """Single wheelset on a FIXED frame with lateral stiffness k_y and yaw stiffness k_psi, no spin.
    Derived by hand from
        m y'' + (F/V) y' - F psi + k_y y = 0,   I psi'' + (G/V) psi' + H y + k_psi psi = 0,
    F = 2 f22, G = 2 f11 e^2, H = 2 f11 e lam / r0. The characteristic polynomial
    a4 s^4 + a3 s^3 + a2 s^2 + a1 s + a0 has a4 = m I, a3 = (m G + I F)/V,
    a2 = m k_psi + I k_y + F G / V^2, a1 = (F k_psi + G k_y)/V, a0 = k_y k_psi + F H, and loses
    stability where the Hurwitz determinant a3 a2 a1 - a4 a1^2 - a0 a3^2 changes sign."""
    F, G, H = 2 * f22, 2 * f11 * e ** 2, 2 * f11 * e * lam / r0

    def h3(V):
        a4, a3 = m * I, (m * G + I * F) / V
        a2, a1, a0 = m * k_psi + I * k_y + F * G / V ** 2, (F * k_psi + G * k_y) / V, k_y * k_psi + F * H
        return (a3 * a2 * a1 - a4 * a1 ** 2 - a0 * a3 ** 2) * V ** 5   # scaled, same sign

    from scipy.optimize import brentq
    grid = np.geomspace(1.0, 400.0, 400)
    signs = np.sign([h3(v) for v in grid])
    k = int(np.argmax(signs < 0))
    assert signs[0] > 0 and k > 0, "the single wheelset must be stable at 1 m/s and unstable below 400 m/s"
    return brentq(h3, grid[k - 1], grid[k], xtol=1e-6)


@pytest.mark.parametrize("gravity", [True, False])
@pytest.mark.parametrize("lam", [0.1, 0.2, 0.3])
def test_wheelsets_on_a_held_frame_match_the_hurwitz_boundary(lam, gravity):
    """Secondary suspension rigid (1e12): the frame is held, both wheelsets hunt alone on 2 k1
    laterally and 2 k2 s1^2 in yaw (+ the gravitational terms), and the model's critical speed is
    the hand-derived Hurwitz one. Frame compliance enters as 2 k1 / 1e12 ~ 4e-6: 1e-4 relative."""
    p = P0.replace(lam=lam, spin=False, gravity=gravity, k4=1e12, k6=1e12)
    k_y = 2 * p.k1 + (p.W * p.eps / p.e if gravity else 0.0)
    k_psi = 2 * p.k2 * p.s1 ** 2 - (p.W * p.e * p.delta0 if gravity else 0.0)
    v_h = _hurwitz_critical_speed(p.m_w, p.I_wz, p.f11, p.f22, p.e, p.r0, lam, k_y, k_psi)
    vc, _ = critical_speed(p)
    assert vc == pytest.approx(v_h, rel=1e-4)


def test_critical_speed_falls_with_conicity_for_every_switch():
    rows = table()
    assert len(rows) == 4 * len(CONICITIES)
    assert all(np.isfinite(vc) and vc > 0 and f > 0 for _, _, _, vc, f in rows)
    for spin, gravity in SWITCHES:
        speeds = [vc for lam, s, g, vc, _ in rows if (s, g) == (spin, gravity)]
        assert all(a > b for a, b in zip(speeds, speeds[1:])), (spin, gravity, speeds)


def test_critical_speed_is_a_zero_crossing():
    """At the returned V_cr the largest real part is zero to the bisection's resolution, negative
    just below and positive just above."""
    p = P0.replace(lam=0.1)
    vc, f = critical_speed(p)
    assert max_real(p, vc - 0.01) < 0 < max_real(p, vc + 0.01)
    assert 0.5 < f < 20.0


def test_spin_force_and_gravitational_stiffness_nearly_cancel_with_the_shear_modulus():
    """With f23 from G = E/(2(1+nu)), the spin creep force's lateral stiffness -2 f23 eps/(e r0)
    almost cancels the gravitational stiffness W eps/e (their ratio here is 0.997), so with spin on
    the critical speed barely depends on the gravity switch. DYTSI's G = E/(2(1-nu)) breaks this
    (ratio 1.73): the net lateral stiffness turns negative and gravity lowers V_cr."""
    from independent.cooperrider import _G_SHEAR, kalker_f
    f11, f22, f23 = kalker_f(_G_SHEAR)
    p = P0.replace(f11=f11, f22=f22, f23=f23, lam=0.1)
    ratio = (2 * f23 / (p.e * p.r0)) / (p.W / p.e)
    assert ratio == pytest.approx(1.0, abs=0.01)
    v_on, _ = critical_speed(p.replace(gravity=True))
    v_off, _ = critical_speed(p.replace(gravity=False))
    assert v_on == pytest.approx(v_off, rel=1e-3)
