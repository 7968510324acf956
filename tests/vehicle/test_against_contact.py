"""The contact law against CONTACT's published results (docs/validation.md, "Creep forces against
CONTACT"; ~2 s). The reference numbers are CONTACT's own ``.ref_out`` outputs
(``vehicle/wheelrail/data/contact_*.csv``, extracted by ``benchmarks/contact_reference.py``); the
comparison code is ``benchmarks/contact_vs_contact.py``, loaded here as a module.

**The yardstick for forces** is the spread CONTACT itself shows between Kalker's exact theory and
his simplified theory FASTSIM on the same Hertzian creep curve (``tractcurv`` cases 1-30 against
61-90): up to 0.039 mu N. A departure within that is as good as the simplified theory used in
multibody codes; where ours is outside it (the flanging wheel's longitudinal force, the spin case)
the test pins the measured departure (so a change in the law shows up) and the docs state it as a
deficiency, with its cause isolated below.
"""
import importlib.util
import math

import pytest

from helpers import ROOT

YARDSTICK_MU_N = 0.04  # FASTSIM - exact in CONTACT's tractcurv: 0.039 mu N at most (asserted below)


@pytest.fixture(scope="module")
def cmp():
    spec = importlib.util.spec_from_file_location(
        "contact_vs_contact", ROOT / "benchmarks" / "contact_vs_contact.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def mbench(cmp):
    return cmp.mbench()


@pytest.fixture(scope="module")
def hertz(cmp):
    return cmp.hertz_cases()


def _region(r):
    """centre (y < 0.75 mm: the two-band tread and its jump at 0.2 mm), tread, flange root
    (right wheel, 5-6 mm) or flange (right wheel, >= 6.5 mm)."""
    if r["y_mm"] < 0.75:
        return "centre"
    if r["side"] == "L" or r["y_mm"] < 4.75:
        return "tread"
    return "root" if r["y_mm"] < 6.25 else "flange"


# ----------------------------------------------------------------------------- law alone
def test_the_yardstick_is_contacts_own_fastsim_spread(hertz):
    t = {r["case"]: r for r in hertz if r["example"] == "tractcurv"}
    spread = max(abs(t[k + 60]["FX"] - t[k]["FX"]) / (t[k]["mu"] * t[k]["FN"]) for k in range(1, 31))
    assert 0.035 < spread <= YARDSTICK_MU_N


def test_creep_curve_without_spin_within_the_yardstick(hertz):
    """Kalker linear + Shen-Hedrick-Elkins on CONTACT's ellipse against the exact theory, pure
    longitudinal creepage from 1e-5 to 0.25 (partial slip to full slip)."""
    exact = [r for r in hertz if r["example"] == "tractcurv" and r["case"] <= 30]
    # FX < 0 in CONTACT's convention for xi > 0: d < 0 where ours is below the exact curve
    d = [(r["CKSI"], (r["FX"] - r["ours_FX"]) / (r["mu"] * r["FN"])) for r in exact]
    assert max(abs(v) for _, v in d) <= YARDSTICK_MU_N  # measured 0.038 (xi = 0.002)
    # below the curve in partial slip (SHE saturates early), equal once fully sliding
    assert all(v < 0.001 for xi, v in d if 2e-4 < xi < 0.004)
    assert all(abs(v) < 0.002 for xi, v in d if xi >= 0.004)
    # initial slope: Kalker's C11 against CONTACT's discretised exact solution (48 x 44 grid),
    # 1.5 % apart; CONTACT's FASTSIM is 1.6 % the other way at the same creepage
    first = exact[0]
    assert first["ours_FX"] == pytest.approx(first["FX"], rel=0.02)


def test_spin_case_departure_is_pinned(hertz):
    """Lateral creepage with spin (fastsim case 1, exact): ours is 12 % low in F_y and 10 % high
    in M_z; the spin term carries the sign of F_y (spin off: +7.3 kN against -14.9 kN).
    CONTACT's FASTSIM is 0.7 % off in F_y and 19 % in M_z, so the F_y departure is ours, a
    deficiency of the linear law with heuristic saturation under spin (docs/validation.md)."""
    ex = next(r for r in hertz if r["example"] == "fastsim" and r["case"] == 1)
    fy, mz = ex["ours_FY"] / ex["FY"] - 1.0, ex["ours_MZ"] / ex["MZ"] - 1.0  # same signs
    assert -0.15 < fy < -0.10
    assert 0.0 < mz < 0.19  # within CONTACT's own FASTSIM-exact spread in M_z
    assert ex["ours_FY_nospin"] > 0 > ex["FY"]


# ----------------------------------------------------------------------------- Manchester
def test_geometry_on_the_tread_and_flange(mbench):
    """Contact angle and rolling radius of the rigid, yaw-free table (smoothed 0.1 mm) against
    CONTACT's contact reference point: on the tread within 0.002 rad and 0.06 mm (measured
    0.0014 rad, 0.047 mm: CONTACT's point lies in an elastic patch discretised at 0.2 mm, whose
    approach is ~0.02 mm), on the flange root and flank within 0.02 rad and 0.3 mm (measured
    0.0165 rad, 0.25 mm: there gamma turns by ~0.5 rad per mm of the profile, so 0.03 mm of
    contact position is 0.015 rad)."""
    for r in mbench:
        c, o, g = r["contact"], r["same_spin"], _region(r)
        if g == "centre":
            continue  # the two-band tread: see test_centred_wheelset
        dg, dr = (0.002, 0.06e-3) if g == "tread" else (0.02, 0.3e-3)
        assert abs(o["gamma"] - c["gamma"]) < dg, (r["case"], r["side"])
        assert abs(o["r"] - c["r"]) < dr, (r["case"], r["side"])


def test_creepages_match_given_the_same_state(mbench):
    """The same kinematics: lateral creepage within 1.5 % on the tread (measured 1.2 %, the left
    wheel at 10 mm) and 4 % on the flange (measured 3.6 %; the yaw-free table misses the flange
    contact point's 7 mm lag behind the axle, XCP in CONTACT), spin within 0.04 /m (the contact
    angle difference above, sin(0.016)/0.48 m)."""
    for r in mbench:
        c, o = r["contact"], r["same_spin"]
        if r["y_mm"] == 0:
            continue
        assert o["xi_y"] == pytest.approx(c["xi_y"], rel=0.04 if _region(r) == "flange" else 0.015)
        assert abs(o["phi"] - c["phi"]) < 0.04


def test_saturated_tread_forces_within_the_yardstick(mbench):
    """Tread contacts from 1 mm on are fully sliding in CONTACT (slip area 1.00): every force
    component on the wheel within the yardstick (measured: F_x 0.028, F_y 0.018, Y 0.031 mu N)."""
    for r in mbench:
        if _region(r) != "tread" or r["y_mm"] < 0.75:
            continue
        c, o = r["contact"], r["same_spin"]
        muN = 0.3 * c["N"]
        for k in ("Fx", "Fy", "Y"):
            assert abs(o[k] - c[k]) < YARDSTICK_MU_N * muN, (r["case"], r["side"], k)


def test_flanging_wheel_longitudinal_force_departure_is_pinned(mbench):
    """Flange contact (right wheel, y >= 6.5 mm): outside the yardstick. Measured Y 0.062 and
    F_x 0.114 mu N off (ours F_x 14-27 % low); pinned at 0.07 / 0.12 mu N. The cause is isolated
    in the next test."""
    for r in mbench:
        if _region(r) != "flange":
            continue
        c, o = r["contact"], r["same_spin"]
        muN = 0.3 * c["N"]
        assert abs(o["Y"] - c["Y"]) < 0.07 * muN
        assert 0.07 * muN < c["Fx"] - o["Fx"] < 0.12 * muN  # ours 14-27 % low


def test_saturated_direction_is_the_cause(cmp, mbench):
    """Isolation: with CONTACT's creepages and N (geometry out), our law departs by up to
    0.118 mu N on the flange; switching its spin creep off leaves 0.069; our force magnitude put
    along the rigid slip direction -(xi_x, xi_y) (no Kalker weighting C11 != C22, no spin) is
    within 0.0075 mu N of CONTACT on every fully sliding tread and flange contact, except the
    flange-root patch at 5 mm (0.051). So in full slip the difference is the direction Kalker's
    linear law gives the saturated force, not its magnitude nor the geometry."""
    for r in cmp.saturated_direction(mbench):
        if r["slip_fraction"] < 1.0 or r["y_mm"] == 5.0 and r["side"] == "R":
            continue
        d = {k: math.hypot(r[k][0] - r["contact"][0], r[k][1] - r["contact"][1]) / r["muN"]
             for k in ("law", "nospin", "slipdir")}
        if r["y_mm"] >= 1.5:
            assert d["slipdir"] < 0.0085, (r["y_mm"], r["side"], d)
        if r["side"] == "R" and r["y_mm"] >= 6.5:
            assert d["slipdir"] < 0.1 * d["law"] and d["nospin"] < 0.7 * d["law"], d


def test_wheelset_sum_y_and_flanging_y_over_q(mbench):
    """ΣY (both wheels, track lateral) within 4 % of CONTACT's on the flange (measured up to
    3.7 %) and within 2 % from 1 to 5.5 mm (measured 1.5 %, at 5.5 mm; the tread forces above); Y/Q of the
    flanging wheel within 0.025 (measured 0.022: its F_y is 5 % high, F_x low, see above).
    At 0.5 and 6.0 mm ΣY is 12 % off: the right wheel there sits just past a contact jump of the
    rigid table (0.2 mm, flange root), where CONTACT's elastic patch still spans both points."""
    by = {(r["case"], r["side"]): r for r in mbench}
    for case in sorted({r["case"] for r in mbench}):
        L, R = by[(case, "L")], by[(case, "R")]
        so = L["same_spin"]["Y"] + R["same_spin"]["Y"]
        sc = L["contact"]["Y"] + R["contact"]["Y"]
        y = L["y_mm"]
        if y >= 6.5:
            assert so == pytest.approx(sc, rel=0.04)
            yq_o = R["same_spin"]["Y"] / R["same_spin"]["Z"]
            yq_c = R["contact"]["Y"] / R["contact"]["Z"]
            assert abs(yq_o - yq_c) < 0.025
        elif 1.0 <= y <= 5.5:
            assert so == pytest.approx(sc, rel=0.02)


def test_centred_wheelset(mbench):
    """y = 0, no yaw: the only partial-slip case of A-2.2 (CONTACT: 27 % of the patch slips).
    CONTACT's spin rate makes its wheels roll freely (F_x = 0.3 N); with the same spin ours has
    -0.44 kN per wheel, because our rigid contact point (3.25 mm field side on the first tread
    band) rolls on a 0.011 mm smaller radius than CONTACT's patch spanning both bands:
    xi_x 1.15e-4 against 0.57e-4. The lateral force, from spin alone, is 23 % low (0.195 against
    0.254 kN): 13 % from the contact angle (0.025 against 0.029 rad) and 9.5 % from the law
    (law alone with CONTACT's spin: 0.230 kN)."""
    r = next(r for r in mbench if r["case"] == 1 and r["side"] == "L")
    c, o, la = r["contact"], r["same_spin"], r["law_alone"]
    assert abs(c["Fx"]) < 1.0 and -0.5e3 < o["Fx"] < -0.4e3
    assert 0.7 < o["Fy"] / c["Fy"] < 0.8
    assert 0.85 < la["Fy"] / c["Fy"] < 0.95
