"""The application layer's map holds: its rooms import one way, a kind is one module, and the
public API is where ``cosim``'s docstring says."""
from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

from helpers import ROOT

#: the rooms of cosim/, each importing only from those before it (or itself); ``load``, ``runner``
#: and ``keyref`` are the entry points above the kinds, ``cli`` the top
LAYERS = (("errors", "interrupts"), ("scenario",), ("limits",), ("stability",), ("results",), ("engine",), ("runs",), ("kinds",),
          ("load", "runner", "keyref"), ("verification", "sweep", "identify", "fmi"), ("cli",))
RANK = {room: i for i, rooms in enumerate(LAYERS) for room in rooms}


def _modules():
    """dotted name -> path of every module of cosim/."""
    out = {}
    for path in (ROOT / "cosim").rglob("*.py"):
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


def _imports(path: Path, modules) -> set:
    """The cosim modules ``path`` imports, at any level (a lazy import inside a function counts)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level:
            raise AssertionError(f"{path}: relative import (write cosim.<room>.<module>)")
        if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "cosim":
            for alias in node.names:
                full = f"{node.module}.{alias.name}"
                found.add(full if full in modules else node.module)
        elif isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.split(".")[0] == "cosim"}
    return found


def _room(module: str) -> str:
    return module.split(".")[1] if module != "cosim" else "cosim"


def test_the_rooms_import_one_way():
    modules = _modules()
    assert set(RANK) | {"cosim"} == {_room(m) for m in modules}, "a new room: place it in LAYERS"
    upward = [f"{m} -> {i}" for m, path in modules.items() if m != "cosim" for i in _imports(path, modules)
              if i != "cosim" and RANK[_room(i)] > RANK[_room(m)]]
    assert not upward, upward


def test_no_module_outside_the_kinds_names_a_kind():
    """Kind names appear only in their own modules (and in messages and docs of the kinds'
    registry): the rest of the application layer asks the registry."""
    from cosim.kinds import KINDS
    offenders = []
    for name, path in _modules().items():
        if name.startswith("cosim.kinds"):
            continue
        tree = ast.parse(path.read_text())
        docstrings = {id(n.body[0].value) for n in ast.walk(tree)
                      if isinstance(n, (ast.Module, ast.FunctionDef, ast.ClassDef)) and n.body
                      and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
        for node in ast.walk(tree):
            if (isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in KINDS
                    and id(node) not in docstrings):
                offenders.append(f"{name}:{node.lineno}: {node.value!r}")
    assert not offenders, offenders


def test_every_kind_declares_what_the_application_needs():
    """Every registered kind is an instance of the contract's classes (abstract methods all
    implemented, or it could not have been instantiated), registered under its own name, with
    metrics that refer to its checkable ones and a zone list where it offers zone metrics."""
    from cosim.kinds import KINDS
    from cosim.kinds.base import CarKind, Kind, RigKind
    for name, kind in KINDS.items():
        assert isinstance(kind, Kind) and kind.name == name, name
        assert isinstance(kind, CarKind if kind.car else RigKind), name
        assert set(kind.wheel_metrics) <= set(kind.check_metrics), name
        assert set(kind.zone_metrics) <= set(kind.check_metrics), name
        assert not kind.zone_metrics or type(kind).zones is not Kind.zones, name
        assert not kind.identify or type(kind).identify_circuit is not RigKind.identify_circuit, name


@pytest.mark.parametrize("name", ["load_scenario", "run", "run_scenario", "Outcome", "ScenarioError"])
def test_the_public_api_is_at_the_top(name):
    import cosim
    assert name in cosim.__all__ and getattr(cosim, name) is not None


def test_reading_a_scenario_imports_no_exudyn():
    """Loading a rig scenario (or the kinds' registry) does not pay for the multibody code."""
    code = ("import sys, cosim; from cosim import load_scenario; load_scenario(sys.argv[1]); "
            "import cosim.kinds; print('exudyn' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code, str(ROOT / "scenarios" / "rig_ramp.yaml")], capture_output=True,
                         text=True, cwd=ROOT, check=True).stdout
    assert out.split() == ["False"]


def test_the_two_physics_packages_name_the_bellows_alike():
    # pneumatics/ and vehicle/ may not import each other, so each declares the four bellow names;
    # cosim/ pairs them by name, and a rename in one alone would silently unpair a bellow
    from pneumatics.layouts import BELLOWS as circuit_bellows
    from vehicle.params import BELLOWS as car_bellows
    assert circuit_bellows == car_bellows


def test_every_module_of_the_packages_is_in_git():
    # a clean clone has only what git tracks: an ignore rule that hides a new module (results/
    # once hid cosim/results/) breaks every fresh install while the working tree still imports
    tracked = set(subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split())
    missing = [str(p.relative_to(ROOT)) for package in ("pneumorail", "cosim", "pneumatics", "vehicle")
               for p in (ROOT / package).rglob("*.py") if str(p.relative_to(ROOT)) not in tracked]
    assert not missing, f"not tracked by git: {missing}"


def test_the_common_ground_imports_none_of_the_packages():
    # pneumatics/ and vehicle/ import pneumorail/ (the base error, the ranges of their fields); were
    # it to import them back, the physics split would be broken through it
    code = ("import sys, pneumorail, pneumorail.errors, pneumorail.quantities; "
            "print([m for m in sys.modules if m.split('.')[0] in ('cosim', 'pneumatics', 'vehicle', 'exudyn')])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True).stdout
    assert out.strip() == "[]"


def test_every_deliberate_error_has_the_one_base_class():
    from cosim.errors import ExecutorUnavailable, ScenarioError
    from pneumatics.errors import CircuitDiverged, CircuitError
    from pneumorail import PneumorailError
    from vehicle.errors import Derailed
    errors = (ScenarioError("s.yaml", ["a"], "bad"), ExecutorUnavailable("no dask"), CircuitError(["pipe"], "bad"),
              CircuitDiverged(1.0, "bellow FL", {"p_Pa": -1.0}, "negative pressure"), Derailed("wheelset 1"))
    assert all(isinstance(e, PneumorailError) for e in errors)
    # the built-in classes they had still catch them (bad input: ValueError, the rest: RuntimeError)
    assert [isinstance(e, ValueError) for e in errors] == [True, False, True, False, False]
    assert not issubclass(ValueError, PneumorailError)     # a plain bug is not one of them
