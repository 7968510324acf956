"""What the car pool's parent loads before it forks (cosim.engine.cases): the compiled laws its
circuits call, and only those, so that the workers inherit them (issue 37)."""
from __future__ import annotations

import subprocess
import sys

from helpers import SCENARIOS

SCRIPT = """
import sys
from cosim.engine.cases import _load_compiled_laws
from cosim.load import load_scenario
from pneumatics.fused import _flows, _bellow_laws
from pneumatics.integrate import _rk4_step
from pneumatics.orifice import _signed_flow
from pneumatics.pipe import pipe_flow_rate_kg_per_s2
_load_compiled_laws([load_scenario(sys.argv[1])])
print(*(law._call is not None for law in (_flows, _bellow_laws, _rk4_step, pipe_flow_rate_kg_per_s2, _signed_flow)))
"""


def test_the_parent_loads_the_laws_its_circuits_call_and_no_other():
    # a fresh process: another test may have compiled the laws in this one
    done = subprocess.run([sys.executable, "-c", SCRIPT, str(SCENARIOS / "twist_dqq.yaml")],
                          capture_output=True, text=True, check=True)
    # the four-point circuit's fused evaluation (pneumatics.fused), its bellows' force laws and RK4's
    # combination; not the pipes' and orifices' ufuncs (the fused evaluation calls their laws itself)
    assert done.stdout.split() == ["True", "True", "True", "False", "False"]
