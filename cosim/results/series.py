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

from cosim.scenario.schema import k_label
from vehicle.params import BELLOWS, FLOOR_POINTS, WHEELS, WHEELSETS


def case_name(k: float, valves: Optional[bool]) -> str:
    """``k=0`` or ``valves=on_k=0`` (``valves`` None: a scenario with one setting): a case's
    name, also its CSV file suffix."""
    return (f"valves={'on' if valves else 'off'}_" if valves is not None else "") + f"k={k_label(k)}"


def car_dataset(arrays: Dict[str, np.ndarray], outputs: Sequence, ks: Sequence[float], valves: bool,
                named: bool = True, links: Sequence[str] = (), valve_names: Sequence[str] = ()) -> xr.Dataset:
    """A car record (:meth:`cosim.engine.master.Record.arrays`: arrays (samples, ..., cases)) as a
    Dataset; ``outputs``: what each array is (:data:`cosim.engine.master.OUTPUTS`: name, dims, unit,
    long name, CSV column). ``valves``: the valve setting of every case; ``named``: the case names
    carry it (a scenario with several settings)."""
    labels = {"wheel": list(WHEELS), "wheelset": list(WHEELSETS), "bellow": list(BELLOWS), "link": list(links),
              "valve": list(valve_names), "floor_point": list(FLOOR_POINTS)}
    data = {}
    for o in outputs:                       # every sampled output the engine declares
        if o.name not in arrays:
            continue
        attrs = {"units": o.unit, "long_name": o.long_name, **({"column": o.column} if o.column else {})}
        data[o.name] = (("time", *o.dims, "case"), np.asarray(arrays[o.name], dtype=float), attrs)
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
