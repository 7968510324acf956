"""Files that cannot be scenarios, and --set values that cannot be parsed: each ends in exit 2
with one message naming the file and what was wrong, no traceback, within seconds, whatever the
bytes (a subprocess per case, as a user would call it)."""
from __future__ import annotations

import subprocess
import sys
import time

import pytest
import yaml

from helpers import SCENARIOS, short_twist

#: name -> (file content as bytes, a phrase the message must contain)
FILES = {
    "binary": (bytes(range(256)) * 4, "binary"),
    "latin-1": ("kind: twist\nname: caf\xe9\n".encode("latin-1"), "UTF-8"),
    "too large": (b"# padding\n" * 200_000, "MB"),
    "deep nesting": (b"a: " + b"[" * 5000 + b"]" * 5000 + b"\n", "nesting"),
    "alias bomb": (b"a: &a [x, x, x, x, x, x, x, x, x]\n" + b"".join(
        f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n".encode()
        for p, c in zip("abcdefgh", "bcdefghi")), "expands"),
    "duplicate key": (b"kind: twist\nkind: curve_entry\n", "duplicate key 'kind'"),
    "not yaml": (b"kind: [twist\n", "not valid YAML"),
    "a list": (b"- 1\n- 2\n", "mapping"),
    "empty": (b"", "mapping"),
}


def _pneumorail(*args, timeout=20):
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "cosim.cli", *args], capture_output=True, text=True, timeout=timeout)
    return proc, time.perf_counter() - t0


@pytest.mark.parametrize("case", list(FILES))
def test_files_that_cannot_be_scenarios_exit_2_with_one_line(case, tmp_path):
    content, phrase = FILES[case]
    path = tmp_path / "scenario.yaml"
    path.write_bytes(content)
    proc, seconds = _pneumorail("run", str(path), "--out", str(tmp_path / "out"))
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    assert str(path) in proc.stderr and phrase in proc.stderr
    assert seconds < 5.0           # each refusal is immediate (the interpreter starts in ~1 s)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("override, phrase", [
    ("twist.hold_s=[1", "not valid YAML"),
    ("=1", "--set"),
    ("twist..hold_s=1", "--set"),
    ("twist.hold_s=.inf", "finite"),
    ("twist.hold_s=.nan", "finite"),
    ("k_W_per_K=[0, 0]", "twice"),
    ("solver.macro_step_s=.inf", "finite"),
    ("vehicle.carbody_mass_kg=.inf", "finite"),
])
def test_malformed_overrides_exit_2_naming_the_key(override, phrase, tmp_path):
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(short_twist()))
    proc, seconds = _pneumorail("run", str(path), "--set", override, "--out", str(tmp_path / "out"))
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr and phrase in proc.stderr
    assert seconds < 5.0
    assert not (tmp_path / "out").exists()


def test_duplicate_k_on_the_command_line_exits_2(tmp_path):
    proc, _ = _pneumorail("run", str(SCENARIOS / "twist_dqq.yaml"), "--k", "0,10,0", "--out", str(tmp_path / "out"))
    assert proc.returncode == 2 and "twice" in proc.stderr and "--k" in proc.stderr
