"""``pneumorail compare``: overlay the results of several runs of one kind (across k, or across
runs), from the output folders the user names; optionally only some wheels, some k values and a
time window. What is overlaid is the kind's (``compare`` in its module, :mod:`cosim.kinds`)."""
from __future__ import annotations

import math
from pathlib import Path
from typing import Callable, List, Mapping, Sequence, Tuple

from cosim.errors import ScenarioError
from cosim.results.overlay import Selection, incomplete, run_info
from vehicle.params import WHEELS

__all__ = ["Selection", "compare_runs", "parse_wheels", "parse_window"]


def compare_runs(run_dirs: Sequence[Path], out_dir: Path, overlays: Mapping[str, Callable],
                 select: Selection = Selection(), allow_incomplete: bool = False) -> List[Path]:
    """Write overlay plots of the given output folders into ``out_dir``; returns the files.
    ``overlays``: kind name -> the kind's ``compare`` (:func:`cosim.kinds.overlays`). A run whose
    results are not whole is refused, or with ``allow_incomplete`` drawn with "interrupted" in its
    legend."""
    infos = [(d, run_info(d)) for d in run_dirs]
    partial = {d for d, info in infos if incomplete(d, info)}
    if partial and not allow_incomplete:
        d = sorted(partial)[0]
        raise ScenarioError(d, [], f"not a complete run: {incomplete(d, dict(infos)[d])}; --allow-incomplete draws it "
                                   f"marked as interrupted")
    kinds = {info["kind"] for _, info in infos}
    if len(kinds) != 1:
        raise ScenarioError(run_dirs[0], ["kind"], f"cannot compare runs of different kinds: {sorted(kinds)}")
    name = kinds.pop()
    overlay = overlays.get(name)
    if overlay is None:
        raise ScenarioError(run_dirs[0], ["kind"], f"compare does not support {name!r} runs (summary.csv holds its numbers)")
    many = len(infos) > 1

    def label(d, case):
        text = f"{d.name}: {case}" if many else case
        return f"{text} (interrupted)" if d in partial else text
    window = "" if select.t_s is None else f", {select.t_s[0]:g} ... {select.t_s[1]:g} s"
    return overlay(infos, out_dir, select, label, window)


def parse_wheels(text: str) -> Tuple[str, ...]:
    wheels = tuple(w.strip().upper() for w in text.split(",") if w.strip())
    bad = [w for w in wheels if w not in WHEELS]
    if bad or not wheels:
        raise ValueError(f"--wheels expects wheels among {', '.join(WHEELS)}, got {text!r}")
    return wheels


def parse_window(text: str) -> Tuple[float, float]:
    try:
        t0, t1 = (float(v) for v in text.split(","))
    except ValueError:
        raise ValueError(f"--time expects T0,T1 in seconds, got {text!r}") from None
    if not (math.isfinite(t0) and math.isfinite(t1) and t1 > t0):
        raise ValueError(f"--time expects finite T0 < T1, got {text!r}")
    return t0, t1
