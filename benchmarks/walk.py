"""The walk of one scenario from its YAML to its files: which of cosim's rooms a run enters, and
how often the path crosses from one room into another and back.

Runs ``pneumorail run SCENARIO`` in this process (``solver.jobs=1``: no worker processes) under a
profiler hook that sees every Python call and return, and counts, for the functions of ``cosim``
(a room is ``cosim/<room>/`` or a top-level module ``cosim/<module>.py``; ``pneumatics`` and
``vehicle`` count as one room each):

* rooms entered: the distinct rooms a function of which ran;
* crossings: the distinct (caller function, callee function) pairs whose rooms differ, i.e. the
  distinct ways the path leaves a room and enters another (each returns once it is done);
* returns into a room: how many of those crossings come back into the room they left from
  below it (a callee calling its caller's room again: a back edge);
* functions: the distinct cosim functions that ran.

An import's module code (and whatever it calls) is not the run's path and is left out.

Distinct pairs, not call counts: a run's thousands of macro-steps repeat the same path, and the
measure is of the path, not of the length of the run. Usage (from the repository's root, or a
worktree of an older commit for a before / after comparison)::

    python benchmarks/walk.py scenarios/twist_dqq.yaml --set twist.duration_s=1 --set twist.ramp_s=0.5
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def room_of(filename: str):
    """The room a source file belongs to (None: not ours)."""
    path = Path(filename)
    try:
        parts = path.resolve().relative_to(ROOT).parts
    except ValueError:
        return None
    if parts[0] in ("pneumatics", "vehicle", "pneumorail"):
        return parts[0]
    if parts[0] != "cosim":
        return None
    return parts[1][:-3] if parts[1].endswith(".py") else parts[1]


def walk(argv):
    from cosim import cli

    rooms, functions, crossings = set(), set(), set()
    stack = []                              # (room, function) of the frames we follow
    IMPORTING = ("<import>", "")

    def hook(frame, event, arg):
        if event == "call":
            if frame.f_code.co_name == "<module>" or (stack and stack[-1] == IMPORTING):
                stack.append(IMPORTING)     # an import's module code: not the run's path
                return
            room = room_of(frame.f_code.co_filename)
            here = (room, f"{frame.f_code.co_filename}:{frame.f_code.co_name}") if room else None
            if here:
                rooms.add(room)
                if room not in ("pneumatics", "vehicle"):
                    functions.add(here[1])
                caller = next((s for s in reversed(stack) if s and s != IMPORTING), None)
                if caller and caller[0] != room:
                    crossings.add((caller, here))
            stack.append(here)
        elif event == "return" and stack:
            stack.pop()

    with tempfile.TemporaryDirectory() as out:
        sys.setprofile(hook)
        try:
            code = cli.main(["run", *argv, "--out", str(Path(out) / "run"), "--quiet"])
        finally:
            sys.setprofile(None)
    order = [r for r in ("cli", "load", "runner", "keyref", "scenario", "kinds", "runs", "engine", "results", "limits",
                         "stability", "errors", "interrupts", "pneumorail", "pneumatics", "vehicle") if r in rooms]
    order += sorted(rooms - set(order))
    rank = {r: i for i, r in enumerate(order)}
    back = sum(1 for (a, _), (b, _) in crossings if rank[b] < rank[a])
    return code, order, crossings, back, functions


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenario")
    parser.add_argument("--set", action="append", default=[], help="a scenario override, as pneumorail run takes it")
    args = parser.parse_args(argv)
    run_args = [args.scenario, "--set", "solver.jobs=1", *(a for s in args.set for a in ("--set", s))]
    code, rooms, crossings, back, functions = walk(run_args)
    pairs = sorted({(a[0], b[0]) for a, b in crossings})
    print(f"exit {code}")
    print(f"rooms entered      {len(rooms)}: {', '.join(rooms)}")
    print(f"crossings          {len(crossings)} distinct caller -> callee pairs across rooms, "
          f"{len(pairs)} distinct room -> room edges")
    print(f"back edges         {back} (a crossing into a room the path came through above)")
    print(f"cosim functions    {len(functions)}")
    for a, b in pairs:
        print(f"  {a:>12} -> {b}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
