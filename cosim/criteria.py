"""Safety criteria: wheel unloading ΔQ/Q0 (EN 14363)."""
from __future__ import annotations

import numpy as np

#: EN 14363 limit on the wheel unloading ΔQ/Q0 on twisted track.
DQQ_LIMIT = 0.6


def static_wheel_loads(Q_level_N: np.ndarray) -> np.ndarray:
    """Q0 per wheel: the static vertical wheel force on level track, as the mean of the two wheels
    of the wheelset (EN 14363). ``Q_level_N``: (8, ...) in the order 1L 1R 2L 2R ... 4R."""
    pairs = Q_level_N.reshape(4, 2, *Q_level_N.shape[1:]).mean(axis=1)
    return np.repeat(pairs, 2, axis=0)


def wheel_unloading(Q_N: np.ndarray, Q0_N: np.ndarray) -> np.ndarray:
    """ΔQ/Q0 = (Q0 - Q) / Q0: positive when the wheel unloads; 1 for a lifted wheel (Q = 0)."""
    return (Q0_N - Q_N) / Q0_N
