"""Named, cited parameter sets of the pneumatic circuit.

A preset is a function returning a :class:`CircuitPreset`; scenarios name it
(``circuit: {preset: paper_table1}``) and override single fields on top
(``circuit: {preset: paper_table1, tank: {V_m3: 0.04}}``, ``--set circuit.bellow.V0_m3=0.015``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Dict

from .chamber import Bellow, Tank
from .pipe import Pipe


@dataclass(frozen=True)
class CircuitPreset:
    """One bellow with its auxiliary tank and connecting pipe (every bellow of a car is the
    same), and the rig's initial absolute pressure."""

    bellow: Bellow
    tank: Tank
    pipe: Pipe
    p0_Pa: float


def paper_table1() -> CircuitPreset:
    """The paper's Table 1 (the bellow-tank subsystem of the metro car): bellow V0 = 12 dm^3,
    effective area 0.13 m^2 (the table's "volume gradient", equal to the area: the bellow's
    volume changes by A dz), constant area; tank 27 dm^3; pipe 1 m long, 18 mm bore, total loss
    coefficient 1.11 (no separate friction); initial pressure 4 bar absolute. These are also the
    defaults of :class:`~pneumatics.chamber.Bellow`, :class:`~pneumatics.chamber.Tank` and
    :class:`~pneumatics.pipe.Pipe`: the preset names them."""
    return CircuitPreset(bellow=Bellow(), tank=Tank(), pipe=Pipe("", ""), p0_Pa=4.0e5)


#: preset name -> function
CIRCUIT_PRESETS: Dict[str, Callable[[], CircuitPreset]] = {"paper_table1": paper_table1}
