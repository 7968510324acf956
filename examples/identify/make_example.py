"""Makes sine_k10.csv, the identification example: CLEARLY SYNTHETIC, not a measurement.

    python examples/identify/make_example.py

The rig of rig_sine_60s.yaml integrated by scipy's LSODA (rtol 1e-9) at k = 10 W/K, sampled at
20 Hz, with Gaussian noise of standard deviation 50 N on the force, 500 Pa on the bellow
pressure and 0.2 K on the bellow temperature (cosim.identify.synthetic.NOISE), seed 2026.
"""
from pathlib import Path

from cosim.identify.synthetic import NOISE, sine_record, write_csv

HERE = Path(__file__).resolve().parent
TRUE_K_W_PER_K = 10.0
SEED = 2026

if __name__ == "__main__":
    comment = (f"SYNTHETIC (not measured): made by examples/identify/make_example.py, k = {TRUE_K_W_PER_K:g} W/K, "
               f"noise {NOISE}, seed {SEED}")
    path = write_csv(HERE / "sine_k10.csv", sine_record(HERE / "rig_sine_60s.yaml", TRUE_K_W_PER_K, NOISE, SEED), comment)
    print(f"wrote {path} (synthetic: k = {TRUE_K_W_PER_K:g} W/K, noise {NOISE}, seed {SEED})")
