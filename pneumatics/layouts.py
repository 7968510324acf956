"""Ready-made circuits of a car's secondary suspension (four bellows FL, FR, RL, RR).

Names: bellows ``FL FR RL RR``; auxiliary tanks ``tank_XX``; bellow-tank pipes ``pipe_XX``;
levelling valves ``lv_XX`` (four-point) or ``lv_F``/``lv_R`` (two-point); differential
pressure valves ``dpv_F``/``dpv_R``; the main reservoir ``supply``.
"""
from __future__ import annotations

import dataclasses
from typing import Dict, Optional, Sequence

from .boundary import Supply
from .chamber import Bellow, Tank
from .orifice import Orifice
from .pipe import Pipe
from .valves import DifferentialPressureValve, LevellingValve

BELLOWS = ("FL", "FR", "RL", "RR")
BOGIES = {"F": ("FL", "FR"), "R": ("RL", "RR")}


def car_circuit(bellow: Bellow, tank: Optional[Tank], pipe: Pipe, *, levelling: Optional[LevellingValve] = None,
                differential: Optional[DifferentialPressureValve] = None, supply: Supply = Supply(),
                points: int = 4, cross_pipe: Optional[Pipe] = None) -> Dict[str, object]:
    """Four bellows, each with its pipe and auxiliary tank (Table 1), and optionally the valves.

    ``levelling`` is a template (its bellow/sensed fields are replaced). ``points`` = 4: one
    levelling valve per bellow, driven by that bellow's height. ``points`` = 2: one valve per
    bogie, driven by the mean height of its two bellows, feeding the left bellow, the two bellows
    being joined by ``cross_pipe`` (required then). ``differential``: a template for one
    differential pressure valve between the two bellows of each bogie.
    """
    comps: Dict[str, object] = {}
    for b in BELLOWS:
        comps[b] = bellow
        if tank is not None:
            comps[f"tank_{b}"] = tank
            comps[f"pipe_{b}"] = dataclasses.replace(pipe, a=b, b=f"tank_{b}")
    if points not in (2, 4):
        raise ValueError(f"points must be 2 or 4, got {points}")
    if points == 2:
        if cross_pipe is None:
            raise ValueError("a two-point circuit needs a cross pipe between the bellows of a bogie")
        for bogie, (left, right) in BOGIES.items():
            comps[f"cross_{bogie}"] = dataclasses.replace(cross_pipe, a=left, b=right)
    if levelling is not None:
        comps["supply"] = supply
        if points == 4:
            for b in BELLOWS:
                comps[f"lv_{b}"] = dataclasses.replace(levelling, bellow=b, sensed=(b,), supply="supply")
        else:
            for bogie, (left, right) in BOGIES.items():
                comps[f"lv_{bogie}"] = dataclasses.replace(levelling, bellow=left, sensed=(left, right), supply="supply")
    if differential is not None:
        for bogie, (left, right) in BOGIES.items():
            comps[f"dpv_{bogie}"] = dataclasses.replace(differential, a=left, b=right)
    return comps


def static_pressures(components: Dict[str, object], F0_N: Sequence[float], p_atm_Pa: float) -> Dict[str, float]:
    """Bellow pressures that carry the static load, eq. (4) solved for p at z = 0, and the chambers
    that follow them (:func:`pressures_at_rest`), so the circuit starts at rest."""
    return pressures_at_rest(components, {b: p_atm_Pa + F / components[b].area_m2(0.0) for b, F in zip(BELLOWS, F0_N)})


def pressures_at_rest(components: Dict[str, object], bellow_p0_Pa: Dict[str, float]) -> Dict[str, float]:
    """The bellows' pressures ``bellow_p0_Pa`` and, for a chamber with no initial pressure of its own
    that a pipe or an orifice (a throttle) joins to a bellow (its auxiliary tank), that bellow's."""
    p0 = dict(bellow_p0_Pa)
    for c in components.values():
        if isinstance(c, (Pipe, Orifice)):
            for bellow, other in ((c.a, c.b), (c.b, c.a)):
                if bellow in p0 and other not in p0 and getattr(components.get(other), "p0_Pa", 0) is None:
                    p0[other] = p0[bellow]
    return p0
