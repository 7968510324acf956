"""verify refines a compressible pipe's cells with the steps (:func:`cosim.verification.verify.refined`)."""
from __future__ import annotations

from cosim.load import load_scenario
from cosim.verification.verify import refined

from helpers import short_twist, write_scenario


def test_compressible_pipe_cells_double_with_each_level(tmp_path):
    s = load_scenario(write_scenario(tmp_path, short_twist(**{"circuit.pipe": {"model": "compressible",
                                                                                "cell_length_m": 0.2}})))
    assert refined(s, 0).circuit.pipe.cells == 0                 # level 0: the scenario as given
    assert refined(s, 2).circuit.pipe.cells == 20                 # 1 m of 0.2 m cells = 5, times 4
    assert refined(s, 2).solver.pneumatic_step_s == s.solver.pneumatic_step_s / 4


def test_scenarios_without_a_compressible_pipe_keep_their_circuit(tmp_path):
    s = load_scenario(write_scenario(tmp_path, short_twist()))
    assert refined(s, 2).circuit is s.circuit
