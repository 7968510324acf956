"""The documentation inside the project: the generated key reference is current, the README's
example runs, and nothing in the repository refers to files outside it."""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from cosim.keyref import reference

from helpers import ROOT


def test_scenario_key_reference_is_current():
    # regenerate with: python -m cosim.keyref > docs/scenario_keys.md
    assert (ROOT / "docs" / "scenario_keys.md").read_text() == reference()


def test_nothing_refers_outside_the_repository():
    files = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    # the patterns are assembled so that this file does not match itself
    patterns = ("../" + "shared", "design" + ".md")
    outside = [f for f in files if Path(f).suffix in (".py", ".md", ".yaml", ".toml", "") and (ROOT / f).is_file()
               and any(s in (ROOT / f).read_text(errors="ignore") for s in patterns)]
    assert outside == []


@pytest.mark.slow
def test_the_readme_python_example_runs(monkeypatch):
    """The README's in-memory example, as written (a 15 s twist at two k values)."""
    text = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert blocks, "the README shows how to run from Python"
    monkeypatch.chdir(ROOT)
    namespace: dict = {}
    exec(compile(blocks[0], "README.md", "exec"), namespace)      # the project's own README
    outcome = namespace["outcome"]
    assert outcome.rows and not outcome.diverged and outcome.series["twist"].sizes["case"] == 2
