"""The shapes the compiled circuit keeps its numbers in: read-only columns (one row per component,
broadcast over the cases), row selections (a slice where evenly spaced: a view, not a copy), and
tables shared by several components (one interpolation serves them all)."""
from __future__ import annotations

import numpy as np


def read_only(array: np.ndarray) -> np.ndarray:
    """``array``, no longer writable: the compiled circuit is not changed by what evaluates it."""
    array.setflags(write=False)
    return array


def column(values) -> np.ndarray:
    """Values as a read-only (n, 1) column of floats."""
    return read_only(np.asarray(values, dtype=float).reshape(-1, 1))


def rows(indices):
    """Row indices as a slice when they are evenly spaced (a cheap view), else as an index array."""
    idx = np.asarray(indices, dtype=int)
    if idx.size == 0:
        return slice(0, 0)
    step = int(idx[1] - idx[0]) if idx.size > 1 else 1
    if step > 0 and np.array_equal(idx, idx[0] + step * np.arange(idx.size)):
        return slice(int(idx[0]), int(idx[-1]) + 1, step)
    return read_only(idx)


def table_groups(tables) -> tuple:
    """((rows, x, y), ...): the indices of the components that share each distinct (x, y) table, so
    that one interpolation serves them all (rows: see :func:`rows`)."""
    groups = {}
    for i, (x, y) in enumerate(tables):
        groups.setdefault((tuple(x), tuple(y)), []).append(i)
    return tuple((rows(members), read_only(np.array(x, float)), read_only(np.array(y, float)))
                 for (x, y), members in groups.items())
