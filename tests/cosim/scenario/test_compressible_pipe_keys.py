"""A compressible pipe in a scenario: ``circuit.pipe.model: compressible`` with its keys
(``cells``, ``cell_length_m``, ``friction_factor: null``), their ranges and the errors."""
from __future__ import annotations

import pytest

from cosim.errors import ScenarioError
from cosim.load import load_scenario
from pneumatics.pipe import Pipe

from helpers import short_twist, write_scenario


def load(tmp_path, pipe):
    return load_scenario(write_scenario(tmp_path, short_twist(**{"circuit.pipe": pipe})))


def test_compressible_pipe_and_its_keys_are_read(tmp_path):
    s = load(tmp_path, {"model": "compressible", "cells": 8, "friction_factor": None, "zeta": 0.0})
    pipe = s.circuit.components()["pipe_FL"]
    assert isinstance(pipe, Pipe) and (pipe.model, pipe.cells, pipe.friction_factor, pipe.zeta) == \
        ("compressible", 8, None, 0.0)


@pytest.mark.parametrize("pipe, where, words", [
    ({"model": "compressible", "cells": 1001}, "cells", "1000"),
    ({"model": "compressible", "cells": 2.5}, "cells", "integer"),
    ({"model": "compressible", "cell_length_m": 0.0}, "cell_length_m", "m"),
    ({"model": "compresible"}, "model", "compressible"),
    ({"model": "dynamic", "friction_factor": None}, "friction_factor", "needs model: compressible"),
])
def test_bad_compressible_pipe_keys_are_refused_by_name(tmp_path, pipe, where, words):
    with pytest.raises(ScenarioError) as exc:
        load(tmp_path, pipe)
    text = str(exc.value)
    assert where in text and words in text, text
