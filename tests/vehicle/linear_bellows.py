"""A car driven on linear bellow laws, counting its solver's Newton iterations (a helper of the
tests of the car's solver rules)."""
from __future__ import annotations

import numpy as np


def newton_per_step(car, t_end_s: float, k_N_per_m: float, counted_after_s: float = 0.0,
                    step_s: float = 0.005) -> float:
    """Advance ``car`` to ``t_end_s`` in ``step_s`` macro-steps, each on the bellow laws
    F = F0 + k z anchored at the step's start (F0 the static forces); the mean Newton iterations
    per step over the steps that end after ``counted_after_s``."""
    F0, k = car.static_bellow_forces_N(), np.full(4, k_N_per_m)
    it, counts = car.solver.main.it, []
    for n in range(1, int(round(t_end_s / step_s)) + 1):
        z, _ = car.bellow_crushing()
        car.set_bellow_forces(F0 + k * z, k)
        n0 = it.newtonStepsCount
        car.advance(n * step_s)
        if n * step_s > counted_after_s:
            counts.append(it.newtonStepsCount - n0)
    return float(np.mean(counts))
