"""``pneumorail fmu``: a car scenario's circuit as an FMI 2.0 co-simulation FMU (pythonfmu).

What goes into the FMU: :mod:`cosim.fmi.slave` (the slave class) and ``circuit.pickle``, the
circuit's components (its preset or ``components:``, valves connected or not as the scenario
says), the bellows' initial pressures that carry the scenario's car at rest (computed here, with
the car: the FMU itself needs no exudyn), k, the pneumatic step, and where it came from (the
scenario file's name and sha256, pneumorail's version). docs/fmi.md says how to use it.
"""
from __future__ import annotations

import hashlib
import math
import pickle
import shutil
import tempfile
from pathlib import Path
from typing import Optional

from cosim.errors import ScenarioError
from cosim.kinds import KINDS
from cosim.scenario.model import Scenario
from pneumatics.integrate import stable_step_s
from pneumatics.layouts import static_pressures

#: the default experiment's stop time [s]; its communication step is the scenario's macro-step
DEFAULT_STOP_S = 10.0

SLAVE = Path(__file__).with_name("slave.py")


def _version() -> str:
    from cosim.results.io import versions
    return versions().get("pneumorail", "unknown")


def circuit_spec(scenario: Scenario, k_W_per_K: Optional[float]) -> dict:
    """What the FMU's slave needs, computed from ``scenario`` (a car scenario) at ``k_W_per_K``
    (None: the scenario's one k value)."""
    kind = KINDS[scenario.kind]
    if not kind.car:
        cars = ", ".join(k.name for k in KINDS.values() if k.car)
        raise ScenarioError(scenario.file, ["kind"], f"fmu exports a car scenario's circuit ({cars}), got {scenario.kind}")
    if scenario.circuit.faults:
        raise ScenarioError(scenario.file, ["faults"], "the FMU holds the healthy circuit: faults happen at times "
                                                       "of a car run, which an FMU's importer does not share; remove them")
    if k_W_per_K is None:
        if len(scenario.k_W_per_K) != 1:
            raise ScenarioError(scenario.file, ["--k"], f"the scenario has {len(scenario.k_W_per_K)} k values: choose "
                                                        f"the FMU's default with --k (its parameter k_W_per_K can be "
                                                        f"changed by the importer)")
        k_W_per_K = scenario.k_W_per_K[0]
    if not k_W_per_K >= 0:
        raise ScenarioError(scenario.file, ["--k"], f"expected k >= 0 W/K, got {k_W_per_K}")
    components = scenario.circuit.components()
    circuit = scenario.circuit.compile(k_W_per_K)
    car = kind.make_car(scenario)
    p0 = static_pressures(components, car.static_bellow_forces_N(), circuit.atmosphere.p_Pa)
    h = stable_step_s(circuit, circuit.initial_state(p0), scenario.solver.pneumatic_step_s)
    isothermal = math.isinf(k_W_per_K)
    spec = {
        "components": components,
        "bellows": list(circuit.bellow_names),
        "p0_Pa": {b: float(p0[b]) for b in circuit.bellow_names},
        "k_W_per_K": 0.0 if isothermal else float(k_W_per_K),
        "isothermal": isothermal,
        "pneumatic_step_s": float(h),
        "scenario_name": scenario.name,
        "scenario_file": Path(scenario.file).name,
        "scenario_sha256": hashlib.sha256(Path(scenario.file).read_bytes()).hexdigest(),
        "pneumorail_version": _version(),
        "default_experiment": (0.0, DEFAULT_STOP_S, float(scenario.solver.macro_step_s)),
    }
    spec["description"] = (f"pneumorail {spec['pneumorail_version']}: the air circuit of scenario '{scenario.name}' "
                           f"({spec['scenario_file']}, sha256 {spec['scenario_sha256']}), valves "
                           f"{'connected' if scenario.circuit.valves else 'disconnected'}, k = "
                           f"{'inf' if isothermal else f'{k_W_per_K:g}'} W/K at export")
    return spec


def export_fmu(scenario: Scenario, out: Path, k_W_per_K: Optional[float] = None) -> Path:
    """Write the FMU of ``scenario``'s circuit to ``out`` (a .fmu file); returns its path."""
    try:
        from pythonfmu import FmuBuilder
    except ImportError:
        raise ScenarioError("<command line>", ["fmu"], "exporting an FMU needs pythonfmu: pip install "
                                                       "'pneumorail[fmi]'") from None
    out = Path(out)
    if out.suffix != ".fmu":
        raise ScenarioError("<command line>", ["--out"], f"expected a file name ending in .fmu, got {out}")
    spec = circuit_spec(scenario, k_W_per_K)
    with tempfile.TemporaryDirectory(prefix="pneumorail_fmu_") as tmp:
        folder = Path(tmp)
        # the module's name is the FMU's slave module; the class's name, its model identifier
        script = folder / "pneumorail_circuit.py"
        shutil.copy2(SLAVE, script)
        with open(folder / "circuit.pickle", "wb") as f:
            pickle.dump(spec, f)
        out.parent.mkdir(parents=True, exist_ok=True)
        FmuBuilder.build_FMU(script, dest=out, project_files=[folder / "circuit.pickle"],
                             needsExecutionTool="true", canHandleVariableCommunicationStepSize="true",
                             canGetAndSetFMUstate="false", canSerializeFMUstate="false", canInterpolateInputs="false")
    return out

