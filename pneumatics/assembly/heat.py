"""The chambers' heat exchange with the atmosphere (eq. 8), one coefficient k per case: 0 is
adiabatic, ``inf`` the exact isothermal limit (T held at the atmosphere's temperature)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import CircuitError
from .arrays import read_only


@dataclass(frozen=True, eq=False)
class HeatExchange:
    """k as given [W/K] (a scalar, or one per case); the isothermal cases (k = inf); whether
    there is any; k with the isothermal cases set to 0, for the law of the finite ones."""

    k_W_per_K: np.ndarray
    isothermal: np.ndarray
    any_isothermal: bool
    k_finite_W_per_K: np.ndarray


def compile_heat_exchange(k_W_per_K) -> HeatExchange:
    """k checked: >= 0, or inf for isothermal."""
    k = read_only(np.array(k_W_per_K, dtype=float))
    if np.any(k < 0) or np.any(np.isnan(k)):
        raise CircuitError(["k_W_per_K"], f"must be >= 0 (or inf for isothermal), got {k_W_per_K}")
    isothermal = read_only(np.asarray(np.isinf(k)))
    return HeatExchange(k, isothermal, bool(np.any(isothermal)), read_only(np.where(isothermal, 0.0, k)))
