"""The chambers' volumes and the bellows' effective areas (eq. 4): V = V0 - Ez @ z over every
chamber, A_e = A0 + (dA/dz) z over every bellow (or its area table)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Optional

import numpy as np

from ..chamber import Bellow
from ..compressible_pipe import PipeCell
from ..errors import CircuitError
from .arrays import column, read_only
from .nodes import Nodes


@dataclass(frozen=True, eq=False)
class ChamberGeometry:
    """Nominal volumes (chambers, 1); ``Ez`` (chambers, bellows), each bellow's dV/dz in its
    chamber's row; the bellows' A0 and dA/dz (bellows, 1); whether any bellow has an area table
    (then the bellows' laws are evaluated bellow by bellow); each bellow's chamber row; every
    bellow at once as a Bellow of (bellows, 1) columns, for the vectorised laws."""

    V0_m3: np.ndarray
    Ez_m2: np.ndarray
    A0_m2: np.ndarray
    dA_dz_m: np.ndarray
    area_tables: bool
    bellow_chamber: np.ndarray
    bellow_columns: Bellow
    pipe_cells: Optional[np.ndarray] = None


def check_area_table(name: str, bellow: Bellow) -> None:
    """A bellow's area table: as many areas as crushings, at least two, crushings increasing,
    areas > 0 and finite."""
    zs, As = bellow.area_table_z_m, bellow.area_table_m2
    if not zs and not As:
        return
    if len(zs) != len(As) or len(zs) < 2:
        raise CircuitError([name, "area_table_m2"], f"expected as many areas as crushings (area_table_z_m), at "
                                                    f"least 2; got {len(As)} areas for {len(zs)} crushings")
    for i in range(len(zs)):
        if not (np.isfinite(zs[i]) and np.isfinite(As[i]) and As[i] > 0):
            raise CircuitError([name, f"area_table_m2[{i}]"], f"expected a finite area > 0 m^2 at a finite "
                                                               f"crushing, got {As[i]} at {zs[i]} m")
        if i and not zs[i] > zs[i - 1]:
            raise CircuitError([name, f"area_table_z_m[{i}]"], f"crushings must increase, got {zs[i]} after "
                                                               f"{zs[i - 1]} m")


def compile_chambers(components: Mapping[str, object], nodes: Nodes) -> ChamberGeometry:
    """The geometry of the chambers of ``nodes``; every volume > 0, every area table valid."""
    V0 = []
    for n in nodes.chamber_names:
        c = components[n]
        V0.append(c.V0_m3 if isinstance(c, Bellow) else c.V_m3)
        if V0[-1] <= 0:
            raise CircuitError([n, "V0_m3" if isinstance(c, Bellow) else "V_m3"], f"volume must be > 0, got {V0[-1]}")
    bellows = [components[n] for n in nodes.bellow_names]
    bellow_chamber = np.array([nodes.chamber_names.index(n) for n in nodes.bellow_names], dtype=int)
    Ez = np.zeros((len(nodes.chamber_names), len(bellows)))
    for j, b in enumerate(bellows):
        Ez[bellow_chamber[j], j] = b.dV_dz_m2
    for n, b in zip(nodes.bellow_names, bellows):
        check_area_table(n, b)
    laws = {f: column([getattr(b, f) for b in bellows]) for f in ("V0_m3", "dV_dz_m2", "A0_m2", "dA_dz_m")}
    cells = [i for i, n in enumerate(nodes.chamber_names) if isinstance(components[n], PipeCell)]
    return ChamberGeometry(column(V0), read_only(Ez), laws["A0_m2"], laws["dA_dz_m"], any(b.area_table_z_m for b in bellows),
                           read_only(bellow_chamber), Bellow(**laws), read_only(np.array(cells, dtype=int)) if cells else None)
