"""Synthetic rig records with a known k, for examples, tests and coverage studies: the rig of a
``rig_sine`` scenario integrated by scipy's LSODA at rtol 1e-9 (an integrator independent of the
fixed-step RK4 that ``identify`` fits with), plus Gaussian noise of given standard deviations."""
from __future__ import annotations

import csv
from pathlib import Path
from typing import Dict

import numpy as np

from cosim.load import load_scenario
from pneumatics.rig import run_time_series, sine_motion

#: the noise of the shipped example (standard deviations per channel): a force cell to 50 N
#: (0.1 % of the 50 kN load), a pressure transducer to 5 mbar, a thermocouple to 0.2 K
NOISE = {"F_bellow_N": 50.0, "p_bellow_Pa": 500.0, "T_bellow_K": 0.2}


def sine_record(scenario_file: Path, k_W_per_K: float, noise: Dict[str, float], seed: int,
                samples_per_second: float = 20.0) -> Dict[str, np.ndarray]:
    """The scenario's sine test (amplitude, frequency, duration) at ``k_W_per_K``: columns t_s, z_m
    and the noisy channels of ``noise``."""
    s = load_scenario(scenario_file)
    test, rig = s.experiment, s.circuit
    comps = rig.components()
    n = int(round(test.duration_s * samples_per_second)) + 1
    ts = run_time_series(comps, k_W_per_K, sine_motion(test.amplitude_m, test.frequency_Hz), test.duration_s, n,
                         p0_Pa=rig.initial_pressures(comps), rtol=1e-9)
    rng = np.random.default_rng(seed)
    exact = {"F_bellow_N": ts.force_N, "p_bellow_Pa": ts.p_Pa[0], "T_bellow_K": ts.T_K[0]}
    if "tank" in ts.chamber_names:
        exact.update(p_tank_Pa=ts.p_Pa[1], T_tank_K=ts.T_K[1])
    out = {"t_s": ts.t_s, "z_m": ts.z_m}
    out.update({c: exact[c] + rng.normal(0.0, sd, n) for c, sd in noise.items()})
    return out


def write_csv(path: Path, columns: Dict[str, np.ndarray], comment: str = "") -> Path:
    """``columns`` as CSV; ``comment``: a first line starting with '#' (the reader skips it)."""
    with open(path, "w", newline="", encoding="utf-8") as fh:
        if comment:
            fh.write(f"# {comment}\n")
        w = csv.writer(fh)
        w.writerow(list(columns))
        for row in zip(*columns.values()):
            w.writerow([f"{v:.10g}" for v in row])
    return path
