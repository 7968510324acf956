"""Ride comfort of a car run (:mod:`cosim.limits.comfort` computes the indices): per case and
floor point N_MV, Sperling's Wz and the largest continuous comfort Cc across and up, from the floor
accelerations every car run samples.
Shared by the car kinds that run along a track."""
from __future__ import annotations

from typing import Dict

import xarray as xr

from cosim.limits.comfort import BLOCK_S, comfort
from vehicle.params import FLOOR_POINTS

#: summary columns per floor point (``{}``: the point)
COLUMNS = ("N_MV_{}", "Wz_y_{}", "Wz_z_{}", "Cc_y_max_{}_m_per_s2", "Cc_z_max_{}_m_per_s2")


def comfort_columns(case: xr.Dataset, t_from_s: float = -float("inf")) -> Dict[str, float]:
    """N_MV and Wz (lateral, vertical) at each floor point of one case (``case``: its Dataset)
    over its samples from ``t_from_s`` on; empty when that is shorter than one 5 s block or the
    run has no floor accelerations. EN 12299 asks for 5 minutes; a shorter record gives the index
    of what it has."""
    if "floor_az_m_per_s2" not in case:
        return {}
    case = case.sel(time=case["time"] >= t_from_s)
    t = case["time"].values
    if t.size < 2 or t[-1] - t[0] + (t[1] - t[0]) < BLOCK_S:
        return {}
    out: Dict[str, float] = {}
    for point in FLOOR_POINTS:
        axes = {a: case[f"floor_a{a}_m_per_s2"].sel(floor_point=point).values for a in "xyz"}
        if any(not (v == v).all() for v in axes.values()):      # a stopped case: NaN
            out.update({c.format(point): float("nan") for c in COLUMNS})
            continue
        result = comfort(t, axes)
        out.update({f"N_MV_{point}": result.N_MV, f"Wz_y_{point}": result.Wz["y"], f"Wz_z_{point}": result.Wz["z"],
                    f"Cc_y_max_{point}_m_per_s2": result.Cc_max_m_per_s2["y"],
                    f"Cc_z_max_{point}_m_per_s2": result.Cc_max_m_per_s2["z"]})
    return out
