"""The documentation inside the project: the generated key reference is current, and nothing in
the repository refers to files outside it."""
from __future__ import annotations

import subprocess
from pathlib import Path

from cosim.scenario.keyref import reference

ROOT = Path(__file__).resolve().parent.parent


def test_scenario_key_reference_is_current():
    # regenerate with: python -m cosim.scenario.keyref > docs/scenario_keys.md
    assert (ROOT / "docs" / "scenario_keys.md").read_text() == reference()


def test_nothing_refers_outside_the_repository():
    files = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    # the patterns are assembled so that this file does not match itself
    patterns = ("../" + "shared", "design" + ".md")
    outside = [f for f in files if Path(f).suffix in (".py", ".md", ".yaml", ".toml", "") and (ROOT / f).is_file()
               and any(s in (ROOT / f).read_text(errors="ignore") for s in patterns)]
    assert outside == []
