"""The components a circuit is made of: their YAML type names, the reserved name of the
surroundings, and the words error messages call them by."""
from __future__ import annotations

from ..air_supply import AirDemand, Compressor
from ..boundary import Supply
from ..chamber import Bellow, Tank
from ..orifice import Orifice
from ..pipe import Pipe
from ..valves import DifferentialPressureValve, LevellingValve, SafetyValve

#: YAML ``type`` name -> component class.
COMPONENT_TYPES = {
    "bellow": Bellow,
    "tank": Tank,
    "supply": Supply,
    "pipe": Pipe,
    "orifice": Orifice,
    "levelling_valve": LevellingValve,
    "safety_valve": SafetyValve,
    "differential_valve": DifferentialPressureValve,
    "compressor": Compressor,
    "air_demand": AirDemand,
}

#: the node name of the surroundings (:class:`~pneumatics.boundary.Atmosphere`), reserved
ATMOSPHERE = "atmosphere"

#: component class -> what messages call it
TYPE_WORDS = {Bellow: "bellow", Tank: "tank", Supply: "supply", Pipe: "pipe", Orifice: "orifice",
              LevellingValve: "levelling or safety valve", DifferentialPressureValve: "differential valve",
              Compressor: "compressor", AirDemand: "air demand"}


def type_word(comp) -> str:
    """What messages call the component ``comp`` (its class name when it has no word)."""
    return next((w for t, w in TYPE_WORDS.items() if isinstance(comp, t)), type(comp).__name__)
