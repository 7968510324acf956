"""What separates the Cooperrider bogie of the stability kind (scenarios/cooperrider.yaml) from the
independent linear model (tests/independent/cooperrider.py), term by term (not a test; the test is
tests/cosim/stability/test_cooperrider.py). Prints the Markdown tables of docs/validation.md,
"Running stability: the Cooperrider bogie":

1. the chain: from the shipped configuration, the terms the independent model does not have are
   switched off one after the other (each step keeps the ones before), and the independent model
   runs with the switches that match each step;
2. one at a time: from the matched configuration (all of them off), each term switched back on
   alone.

Our rows: the linear critical speed [m/s] and hunting frequency [Hz] with the air circuit in the
eigenvalue problem and with the airsprings' static stiffness. The independent model's switches:
``cone`` = spin creep force and Kalker's reciprocal spin moment (ours has both; f33 = 0), gravity
with the cone's geometry (eps = lambda: the contact angle turns with the roll lambda y / e;
delta0 = atan(lambda)); ``level`` = the same without gravity (eps = delta0 = 0); ``no spin`` =
f11 and f22 alone.

    python studies/cooperrider_terms.py            # 4 conicities x 14 runs, ~3 min on 2 cores
"""
from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests" / "independent")]     # this checkout's code, the independent model
from cooperrider import CooperriderParams, critical_speed  # the independent model  # noqa: E402

from cosim.load import load_scenario  # noqa: E402
from cosim.runner import run  # noqa: E402

CONICITIES = (0.05, 0.1, 0.2, 0.3)
SPEEDS_M_PER_S = [20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0, 110.0, 120.0, 135.0, 150.0]
#: a wheelset's spin inertia that leaves the gyroscopic moments out (the schema's lower bound is 1)
NO_SPIN_INERTIA = {"wheelset_inertia_yy_kg_m2": 1.01}
#: the chain: (label, stability keys, vehicle fields, the independent model's switches), cumulative
CHAIN = [
    ("held carbody (shipped)", {}, {}, "cone"),
    ("+ no creep saturation (mu = 100)", {"friction_coefficient": 100.0}, {}, "cone"),
    ("+ frame roll held", {"frame_roll": "held"}, {}, "cone"),
    ("+ no roll-rate creepage", {"roll_rate_creepage": False}, {}, "cone"),
    ("+ no gyroscopic moments (spin inertia 1 kg m^2)", {}, NO_SPIN_INERTIA, "cone"),
    ("+ level cone contact (no gravitational, load-transfer terms)", {"cone_contact": "level"}, {}, "level"),
    ("+ no spin creep (f23 = 0)", {"f23_N_m": 0.0}, {}, "no spin"),
]
MATCHED = {"friction_coefficient": 100.0, "frame_roll": "held", "roll_rate_creepage": False, "cone_contact": "level"}
#: one at a time from the matched configuration: (label, stability keys, vehicle fields, independent)
ALONE = [
    ("matched", {}, NO_SPIN_INERTIA, "level"),
    ("frame roll", {"frame_roll": "free"}, NO_SPIN_INERTIA, "level"),
    ("roll-rate creepage", {"roll_rate_creepage": True}, NO_SPIN_INERTIA, "level"),
    ("gyroscopic moments (spin inertia 80 kg m^2)", {}, {}, "level"),
    ("tilted cone contact", {"cone_contact": "tilted"}, NO_SPIN_INERTIA, "cone"),
    ("tilted cone contact and creep saturation (mu = 0.36)", {"cone_contact": "tilted", "friction_coefficient": 0.36},
     NO_SPIN_INERTIA, "cone"),
]


def independent(conicity: float, switches: str) -> tuple:
    p = CooperriderParams().replace(lam=conicity)
    if switches == "cone":
        p = p.replace(spin=True, spin_moment=True, gravity=True, eps=conicity, delta0=math.atan(conicity))
    elif switches == "level":
        p = p.replace(spin=True, spin_moment=True, gravity=False)
    else:
        p = p.replace(spin=False, spin_moment=False, gravity=False)
    return critical_speed(p)


def ours(conicity: float, stability: dict, vehicle: dict, folder: Path) -> dict:
    """{airspring model: (critical speed, frequency)} of the shipped scenario with the keys changed."""
    data = yaml.safe_load((ROOT / "scenarios" / "cooperrider.yaml").read_text())
    data["stability"].update(equivalent_conicity=conicity, speeds_m_per_s=SPEEDS_M_PER_S, **stability)
    if vehicle:
        data["vehicle"] = {"preset": "cooperrider", **vehicle}
    path = folder / "scenario.yaml"
    path.write_text(yaml.safe_dump(data))
    return {r["airspring"]: (r["linear_critical_speed_m_per_s"], r["critical_frequency_Hz"])
            for r in run(load_scenario(path)).rows}


def _cell(mine: dict, theirs: tuple) -> str:
    def pair(v):
        return "inf" if math.isinf(v[0]) else f"{v[0]:.2f} / {v[1]:.3f}"
    return f"{pair(mine['circuit'])}; {pair(mine['static'])}; {pair(theirs)}"


def table(title: str, steps: list, base: dict, folder: Path) -> None:
    print(f"{title}: ours with the air circuit; ours with static airsprings; independent -- "
          "critical speed [m/s] / hunting frequency [Hz]\n")
    print("| | " + " | ".join(f"λ = {c:g}" for c in CONICITIES) + " |")
    print("| --- |" + " --- |" * len(CONICITIES))
    keys = {c: dict(base) for c in CONICITIES}
    vehicle = {c: {} for c in CONICITIES}
    for label, stability, fields, switches in steps:
        cells = []
        for c in CONICITIES:
            if steps is CHAIN:                        # cumulative
                keys[c].update(stability)
                vehicle[c].update(fields)
                mine = ours(c, keys[c], vehicle[c], folder)
            else:
                mine = ours(c, {**base, **stability}, fields, folder)
            cells.append(_cell(mine, independent(c, switches)))
        print(f"| {label} | " + " | ".join(cells) + " |", flush=True)
    print()


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as tmp:
        table("The chain", CHAIN, {}, Path(tmp))
        table("One at a time from the matched configuration", ALONE, MATCHED, Path(tmp))
