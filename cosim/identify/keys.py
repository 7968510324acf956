"""The scenario keys identify may fit: k, or any positive number of the rig's circuit."""
from __future__ import annotations

import dataclasses
import math
from typing import Tuple

from cosim.errors import ScenarioError
from cosim.scenario.schema import range_of


def key_value_and_range(model, key: str) -> Tuple[float, float, float]:
    """(the scenario's value, lowest, highest allowed) of ``key``, a dotted path into the rig's
    ``circuit`` (``circuit.pipe.zeta``, ``circuit.bellow.dA_dz_m`` ...). Only keys with a value
    > 0 can be fitted (they are searched in log10); the bounds come from the key's valid range."""
    parts = key.split(".")
    where = ["--fit", key]
    if parts[0] != "circuit" or len(parts) < 2:
        raise ScenarioError(model.scenario_file, where, "expected k_W_per_K or a key of the rig's circuit, "
                                                        "e.g. circuit.pipe.zeta")
    node = model.base.circuit
    for p in parts[1:-1]:
        node = getattr(node, p, None)
        if node is None or not dataclasses.is_dataclass(node):
            raise ScenarioError(model.scenario_file, where, f"the rig's circuit has no {p!r} here")
    field = parts[-1]
    value = getattr(node, field, None)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ScenarioError(model.scenario_file, where, f"not a number of the circuit ({type(node).__name__} fields: "
                                                        f"{', '.join(f.name for f in dataclasses.fields(node))})")
    if not (math.isfinite(value) and value > 0):
        raise ScenarioError(model.scenario_file, where, f"only a key whose value is > 0 can be fitted (searched on a "
                                                        f"log scale); the scenario has {value}")
    rule = range_of(type(node), field)
    lo = rule.low if rule is not None and rule.low is not None and rule.low > 0 else 0.0
    hi = rule.high if rule is not None and rule.high is not None else math.inf
    return float(value), max(lo, 1e-300), hi
