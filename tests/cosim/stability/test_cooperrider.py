"""The Cooperrider configuration of the stability kind (scenarios/cooperrider.yaml: DYTSI's bogie under
a held carbody, on cones of given equivalent conicity, with given creep coefficients) against the
independent linear model of tests/independent/cooperrider.py, run with matching switches.

What the two models share once the terms the independent model leaves out are switched off in ours
(``frame_roll: held``, ``roll_rate_creepage: false``, a spin inertia of 1 kg m^2 instead of 80 for
the gyroscopic moments, ``cone_contact: level`` for the cone's gravitational, spin-geometric and
load-transfer terms, ``friction_coefficient: 100`` so that no steady creep force saturates): the
lateral and yaw motion of two wheelsets and a frame on linear creep, primary and secondary springs
and dampers, against a held carbody. Each of those terms moves our critical speed by 2-9 %; what
each does is in docs/validation.md ("Running stability: the Cooperrider bogie"), measured by the
same chain of switches.
"""
from __future__ import annotations

import math
import sys

import pytest
import yaml

from cosim.load import load_scenario
from cosim.runner import run

from helpers import ROOT, SCENARIOS, write_scenario

sys.path.insert(0, str(ROOT / "tests" / "independent"))
from cooperrider import CooperriderParams, critical_speed  # the independent model's folder, on the path above

#: Relative tolerance of critical speed and hunting frequency in the matched configuration. What
#: still differs between the models there: our wheelset's roll (it follows y on the cone, 0.13 rad/m
#: at 0.1; its inertia and the primary's vertical springs resisting it shift the wheel loads), its
#: spin and longitudinal freedom, the primary springs' preload turning with the wheelset's roll, the
#: Hertz deflection in the rolling radius; each estimated at 0.1 % of the lateral stiffness or below
#: (docs/validation.md). Measured: 0.07-0.15 % (speed) and 0.07-0.17 % (frequency) at 0.05-0.3.
#: The bisection's bracket (0.01 m/s) and the independent model's brentq (1e-4 m/s) are far below it.
TOLERANCE = 5e-3

#: The switches that leave out of ours what the independent model does not have (module doc).
MATCHED = dict(frame_roll="held", roll_rate_creepage=False, cone_contact="level", friction_coefficient=100.0)

SPEEDS_M_PER_S = [20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0, 110.0, 120.0, 135.0, 150.0]


def _ours(tmp_path, conicity: float, vehicle: dict | None = None, **stability) -> dict:
    """{airspring model: (linear critical speed [m/s], hunting frequency [Hz])} of the shipped
    scenario at that equivalent conicity with the keys changed."""
    data = yaml.safe_load((SCENARIOS / "cooperrider.yaml").read_text())
    data["stability"].update(equivalent_conicity=conicity, speeds_m_per_s=SPEEDS_M_PER_S, **stability)
    if vehicle:
        data["vehicle"] = {"preset": "cooperrider", **vehicle}
    data.pop("checks", None)
    out = run(load_scenario(write_scenario(tmp_path, data, f"cooperrider_{conicity:g}.yaml")))
    return {r["airspring"]: (r["linear_critical_speed_m_per_s"], r["critical_frequency_Hz"], r["critical_mode"])
            for r in out.rows}


def _independent(conicity: float, spin: bool) -> tuple:
    """The independent model with the cone's geometry switched off (gravity=False: eps = delta0 = 0, as
    ``cone_contact: level``), the spin creep force and Kalker's reciprocal spin moment as ours has them
    (spin_moment: f23 xi_y, f33 = 0)."""
    p = CooperriderParams().replace(lam=conicity, gravity=False, spin=spin, spin_moment=spin)
    return critical_speed(p)


@pytest.mark.parametrize("conicity", [0.05, 0.1, 0.2, 0.3])
def test_matched_configuration_agrees_with_the_independent_model(tmp_path, conicity):
    mine = _ours(tmp_path, conicity, vehicle={"wheelset_inertia_yy_kg_m2": 1.01}, **MATCHED)
    v_ref, f_ref = _independent(conicity, spin=True)
    for model in ("circuit", "static"):            # the frames cannot roll: the air plays no part
        v, f, mode = mine[model]
        assert "hunting" in mode
        assert v == pytest.approx(v_ref, rel=TOLERANCE), (model, v, v_ref)
        assert f == pytest.approx(f_ref, rel=TOLERANCE), (model, f, f_ref)


def test_without_spin_creep_too(tmp_path):
    """f23 = 0 in ours, spin off in the independent model: the textbook bogie of f11 and f22 alone."""
    v, f, _ = _ours(tmp_path, 0.1, vehicle={"wheelset_inertia_yy_kg_m2": 1.01}, f23_N_m=0.0, **MATCHED)["circuit"]
    v_ref, f_ref = _independent(0.1, spin=False)
    assert v == pytest.approx(v_ref, rel=TOLERANCE) and f == pytest.approx(f_ref, rel=TOLERANCE)


def test_the_bogies_do_not_meet_under_a_held_carbody(tmp_path):
    """With the carbody held the two bogies are uncoupled in the lateral plane: the front bogie alone
    (the rear one held) hunts at the speed and frequency of both, and a free carbody moves it."""
    both = _ours(tmp_path, 0.2)["static"]
    front = _ours(tmp_path, 0.2, bogies="front")["static"]
    free = _ours(tmp_path, 0.2, carbody="free")["static"]
    assert front[0] == pytest.approx(both[0], abs=0.02)            # two bisection brackets (0.01 m/s)
    assert front[1] == pytest.approx(both[1], rel=1e-6) and "bogie 1" in front[2]
    assert abs(free[0] - both[0]) > 0.5


def test_shipped_scenario_gives_the_critical_speed_per_conicity_and_its_keys_are_checked(tmp_path):
    data = yaml.safe_load((SCENARIOS / "cooperrider.yaml").read_text())
    assert data["vehicle"] == "cooperrider" and data["stability"]["carbody"] == "held"
    for bad, message in ((dict(conicity=0.1), "older name"), (dict(carbody="floating"), "carbody"),
                         (dict(carbody="free", bogies="front"), "held"), (dict(f33_N_m2=None, f11_N=None, f22_N=1.0e+7),
                                                                          "all four")):
        broken = {**data, "stability": {**data["stability"], **bad}}
        broken["stability"] = {k: v for k, v in broken["stability"].items() if v is not None}
        with pytest.raises(Exception, match=message):
            load_scenario(write_scenario(tmp_path, broken, "broken.yaml"))
    assert math.isfinite(_ours(tmp_path, 0.3)["circuit"][0])
