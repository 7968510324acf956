"""Labelled time series (xarray Datasets) and their CSV layout.

A car run's record becomes one Dataset with dimensions ``time`` x ``wheel`` / ``bellow`` /
``valve`` / ``link`` x ``case``; each case is a k value with a valve setting (coordinates
``k_W_per_K(case)``, ``valves(case)``; the case's name, e.g. ``valves=on_k=0``, is the ``case``
coordinate itself). Every variable carries ``units`` and a ``long_name``; those written to the
CSV time series carry a ``column`` pattern (``Q_{}_N``: one column per wheel), so the CSV layout
is a property of the data, not of the code that writes it (:func:`case_columns`).
"""
from __future__ import annotations

from typing import Dict, Optional, Sequence

import numpy as np
import xarray as xr

from vehicle.params import BELLOWS, WHEELS

from cosim.results.io import k_label

#: record entry -> (dimensions after time, units, long name, CSV column pattern or None)
CAR_VARIABLES = {
    "wheel_load_N": (("wheel",), "N", "vertical wheel-rail force Q", "Q_{}_N"),
    "crushing_m": (("bellow",), "m", "bellow crushing z (+ compression)", "z_{}_m"),
    "bellow_force_N": (("bellow",), "N", "bellow force F", "F_bellow_{}_N"),
    "bellow_p_Pa": (("bellow",), "Pa", "bellow pressure p (absolute)", "p_bellow_{}_Pa"),
    "bellow_T_K": (("bellow",), "K", "bellow temperature T", "T_bellow_{}_K"),
    "roll_rad": ((), "rad", "carbody roll (absolute, positive left side up)", "roll_carbody_rad"),
    "air_from_supply_kg": ((), "kg", "air injected from the supply (cumulative)", "air_from_supply_kg"),
    "air_to_atmosphere_kg": ((), "kg", "air exhausted to the atmosphere (cumulative)", "air_to_atmosphere_kg"),
    "link_flow_kg_per_s": (("link",), "kg/s", "mass flow through each link, from its a node to its b node", None),
    "total_mass_kg": ((), "kg", "air in all chambers", None),
    "valve_supply_air_kg": (("valve",), "kg", "air through each levelling valve's supply side (cumulative)", None),
    "valve_exhaust_air_kg": (("valve",), "kg", "air through each levelling valve's exhaust side (cumulative)", None),
    "valve_supply_open_s": (("valve",), "s", "time each levelling valve's supply side was open (cumulative)", None),
    "valve_exhaust_open_s": (("valve",), "s", "time each levelling valve's exhaust side was open (cumulative)", None),
    # wheel-rail contact (guidance: contact only; a kinematic run has none of them)
    "lateral_wheel_force_N": (("wheel",), "N", "lateral wheel-rail force Y (+ towards the track centre)", "Y_{}_N"),
    "wheelset_lateral_force_N": (("wheelset",), "N", "sum of the lateral wheel forces of a wheelset, ΣY (+ left)",
                                 "sumY_{}_N"),
    "wheelset_lateral_m": (("wheelset",), "m", "wheelset lateral displacement from the design centre line (+ left)",
                           "y_ws_{}_m"),
    "wheelset_lateral_to_rails_m": (("wheelset",), "m", "wheelset lateral displacement relative to its rails "
                                    "(+ left; track irregularities subtracted)", "y_ws_rails_{}_m"),
    "angle_of_attack_rad": (("wheelset",), "rad", "wheelset angle of attack (yaw to the track tangent, + to the left)",
                            "aoa_{}_rad"),
    "flange_contact": (("wheel",), "1", "flange contact (1: contact angle above the flange threshold)", "flange_{}"),
}

#: wheelsets, 1 ... 4 from the front
WHEELSETS = ("1", "2", "3", "4")


def case_name(k: float, valves: Optional[bool]) -> str:
    """``k=0`` or ``valves=on_k=0`` (``valves`` None: a scenario with one setting): a case's
    name, also its CSV file suffix."""
    return (f"valves={'on' if valves else 'off'}_" if valves is not None else "") + f"k={k_label(k)}"


def car_dataset(arrays: Dict[str, np.ndarray], ks: Sequence[float], valves: bool, named: bool = True,
                links: Sequence[str] = (), valve_names: Sequence[str] = ()) -> xr.Dataset:
    """A car record (:meth:`cosim.master.Record.arrays`: arrays (samples, ..., cases)) as a
    Dataset. ``valves``: the valve setting of every case; ``named``: the case names carry it
    (a scenario with several settings)."""
    labels = {"wheel": list(WHEELS), "wheelset": list(WHEELSETS), "bellow": list(BELLOWS), "link": list(links),
              "valve": list(valve_names)}
    data = {}
    for name, (dims, units, long_name, column) in CAR_VARIABLES.items():
        if name not in arrays:
            continue
        attrs = {"units": units, "long_name": long_name, **({"column": column} if column else {})}
        data[name] = (("time", *dims, "case"), np.asarray(arrays[name], dtype=float), attrs)
    coords = {"time": ("time", np.asarray(arrays["t_s"], dtype=float), {"units": "s", "long_name": "time t"}),
              "case": [case_name(k, valves if named else None) for k in ks],
              "k_W_per_K": ("case", np.asarray(ks, dtype=float), {"units": "W/K", "long_name": "heat transfer coefficient k"}),
              "valves": ("case", np.full(len(ks), bool(valves)), {"long_name": "levelling valves connected"})}
    coords.update({dim: values for dim, values in labels.items() if any(dim in v[0] for v in data.values())})
    return xr.Dataset(data, coords=coords)


def concat_cases(datasets: Sequence[xr.Dataset]) -> xr.Dataset:
    """Datasets of the same run's variants (e.g. valve settings) along ``case``; a variant that
    stopped early (every case diverged, or the run was interrupted) is padded with NaN to the
    longest record."""
    longest = max(datasets, key=lambda d: d.sizes["time"])
    n = longest.sizes["time"]
    padded = [d if d.sizes["time"] == n else d.pad(time=(0, n - d.sizes["time"])).assign_coords(time=longest.time)
              for d in datasets]
    return xr.concat(padded, dim="case", data_vars="all", coords="minimal", join="outer",
                     combine_attrs="override") if len(padded) > 1 else padded[0]


def with_column(da: xr.DataArray, column: str, units: str, long_name: str, sparse: bool = False) -> xr.DataArray:
    """``da`` tagged for the CSV time series (see the module docstring). ``sparse``: a label
    whose values are all NaN in a case is a component that case's circuit does not have (e.g. a
    valve of the valves-on circuit in a valves-off case): no column."""
    return da.assign_attrs(units=units, long_name=long_name, column=column, **({"sparse": 1} if sparse else {}))


def case_columns(ds: xr.Dataset, case: Optional[str] = None) -> Dict[str, np.ndarray]:
    """The CSV columns of one case (or of a Dataset without cases): ``t_s`` (if the Dataset has a
    time axis), then every variable with a ``column`` pattern, one column per label of its other
    dimension, in the Dataset's order."""
    sub = ds.sel(case=case) if case is not None else ds
    cols: Dict[str, np.ndarray] = {}
    if "time" in sub.coords:
        cols["t_s"] = sub["time"].values
    for name, da in sub.data_vars.items():
        pattern = da.attrs.get("column")
        if pattern is None:
            continue
        rows = da.dims[0]
        others = [d for d in da.dims if d != rows]
        if not others:
            cols[pattern] = da.values
            continue
        label_dim = others[0]
        for label in da[label_dim].values:
            values = da.sel({label_dim: label}).values
            if not (da.attrs.get("sparse") and np.isnan(values).all()):
                cols[pattern.format(label)] = values
    return cols
