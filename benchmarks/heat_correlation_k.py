"""The correlation's k (pneumatics.heat_transfer) on the rig of the identification example, against
the k identify fits there (docs/models.md, "Heat transfer per chamber"; ~2 min on 2 cores).

    python benchmarks/heat_correlation_k.py

1. The example's rig (examples/identify/rig_sine_60s.yaml: the paper's bellow and tank, 20 mm at
   1 Hz for 60 s) integrated by LSODA (rtol 1e-9) with both chambers on the correlation (heat:
   {model: correlation}, every value its default, still air): each chamber's k over the run (min,
   mean, max, and the mean of the last 10 s); and the inside film's conductance alone, h_in A
   (the same correlation with the wall and the outside film made negligible, 1 nm of wall and
   1e6 m/s of outside air: a numerical device, not a case), the k a wall that holds its
   temperature would leave; and k with 10 m/s of air across both chambers outside (at the same
   states: how much a running car's air could add).
2. A record made from that run as the example was made (20 Hz; the example's noise and seed,
   cosim.identify.synthetic), fitted by identify's single k: the one k that explains the
   correlation's air.
The example's own fit, for comparison: ``pneumorail identify examples/identify/rig_sine_60s.yaml
--data examples/identify/sine_k10.csv`` (its record is synthetic, made at k = 10 W/K).
"""
from __future__ import annotations

import dataclasses
import tempfile
from pathlib import Path

import numpy as np
import yaml

from cosim.identify.data import read_measurements
from cosim.identify.fit import fit_k
from cosim.identify.model import RigModel
from cosim.identify.synthetic import NOISE, sine_record, write_csv
from cosim.load import load_scenario
from pneumatics.circuit import Circuit
from pneumatics.heat_transfer import ChamberHeat
from pneumatics.integrate import simulate
from pneumatics.rig import sine_motion

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "identify" / "rig_sine_60s.yaml"
SEED = 2026                                   # the example's (examples/identify/make_example.py)


def main() -> None:
    data = yaml.safe_load(EXAMPLE.read_text())
    data["circuit"].update(bellow={"heat": {"model": "correlation"}}, tank={"heat": {"model": "correlation"}})
    with tempfile.TemporaryDirectory() as folder:
        scenario_file = Path(folder) / "rig_correlation.yaml"
        scenario_file.write_text(yaml.safe_dump(data))
        s = load_scenario(scenario_file)
        test, rig = s.experiment, s.circuit
        comps = rig.components()
        circuit = Circuit(comps, k_W_per_K=10.0)          # the case's k: neither chamber takes it
        t = np.linspace(0.0, test.duration_s, int(test.duration_s * 20) + 1)
        sol = simulate(circuit, circuit.initial_state(rig.initial_pressures(comps)), t[-1],
                       sine_motion(test.amplitude_m, test.frequency_Hz), t_eval=t, rtol=1e-9)
        assert sol.success, sol.message
        z = (test.amplitude_m * np.sin(2 * np.pi * test.frequency_Hz * t))[None]
        k = circuit.heat_conductances_W_per_K(sol.y, z)
        k_in = _on(comps, ChamberHeat("correlation", wall_thickness_m=1e-9, air_speed_m_per_s=1e6), sol.y, z)
        k_wind = _on(comps, ChamberHeat("correlation", air_speed_m_per_s=10.0), sol.y, z)
        T = sol.y[circuit.layout.T]
        last = t >= t[-1] - 10.0
        print(f"{'chamber':8} {'k min':>8} {'k mean':>8} {'k max':>8} {'last 10 s':>10} {'h_in A mean':>12} "
              f"{'10 m/s mean':>12} {'T range [K]':>16}")
        for i, name in enumerate(circuit.chamber_names):
            print(f"{name:8} {k[i].min():8.3f} {k[i].mean():8.3f} {k[i].max():8.3f} {k[i][last].mean():10.3f} "
                  f"{k_in[i].mean():12.3f} {k_wind[i].mean():12.3f} {T[i].min():7.2f}-{T[i].max():7.2f}")
        record = write_csv(Path(folder) / "correlation.csv", sine_record(scenario_file, 10.0, NOISE, SEED))
        e = fit_k(RigModel(EXAMPLE, (), read_measurements(record))).estimates[0]
        print(f"single k fitted to the correlation's record (the example's noise, seed {SEED}): {e.value:.4g} W/K, "
              f"95 % interval {e.ci_low:.4g} ... {e.ci_high:.4g}")


def _on(comps, heat: ChamberHeat, x: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Each chamber's k with both chambers on ``heat``, at the states ``x`` (chambers, samples)."""
    other = {n: dataclasses.replace(c, heat=heat) if n in ("bellow", "tank") else c for n, c in comps.items()}
    return Circuit(other, k_W_per_K=10.0).heat_conductances_W_per_K(x, z)


if __name__ == "__main__":
    main()
