"""Output folders that never mix two runs and say when they are incomplete.

Before anything is simulated, :class:`OutputFolder` checks that the folder can be written, that
no other run is writing into it (a lock file holding the writer's process id) and that it does
not hold a previous run (refused unless ``overwrite``, which clears it first). While the run
lasts the folder holds an ``INCOMPLETE`` marker; it is removed only when the run finished and
every file was written, so a folder left by a crash, an interrupt or a full disk says so.
"""
from __future__ import annotations

import hashlib
import os
import shutil
from pathlib import Path
from typing import Optional, Sequence

from cosim.errors import ScenarioError

LOCK = ".pneumorail.lock"
INCOMPLETE = "INCOMPLETE"
#: Files whose presence marks a folder as holding a run.
RUN_MARKERS = ("run.json", "summary.csv", "sweep.csv", INCOMPLETE, LOCK)


def default_folder(name: str, overrides: Sequence[str] = (), k: Optional[Sequence[float]] = None,
                   suffix: str = "") -> Path:
    """``results/<name><suffix>``, plus a short hash of the ``--set``/``--k`` overrides when there
    are any, so that a quick experiment never lands in the baseline's folder."""
    tag = ""
    if overrides or k:
        text = "\n".join(sorted(overrides)) + f"\nk={list(k) if k else ''}"
        tag = "_" + hashlib.sha256(text.encode()).hexdigest()[:8]
    return Path("results") / f"{name}{suffix}{tag}"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def holder(folder: Path) -> int:
    """The process id of the live process holding ``folder`` (its lock file), 0 when none does (no
    lock, or one left by a process that is gone)."""
    try:
        pid = int((Path(folder) / LOCK).read_text().strip() or 0)
    except (OSError, ValueError):
        return 0
    return pid if pid and _alive(pid) else 0


class FolderLock:
    """A folder held by one process while it writes there: created if need be, then a lock file
    with the holder's process id, made exclusively; a lock whose process is gone is taken over.
    Errors are :class:`ScenarioError` on ``--out`` (exit 2), raised before anything runs: a folder
    that cannot be written, or one another process is writing into. Used by sweeps and verify
    (which resume into their folder) and by :class:`OutputFolder`."""

    def __init__(self, path: Path, what: str = "run"):
        self.path, self.what = Path(path), what

    def _refuse(self, message: str):
        raise ScenarioError(self.path, ["--out"], message)

    def __enter__(self) -> Path:
        p = self.path
        if p.exists() and not p.is_dir():
            self._refuse("exists and is not a folder")
        lock = p / LOCK
        for _ in range(2):
            try:
                p.mkdir(parents=True, exist_ok=True)
                fd = os.open(lock, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
                with os.fdopen(fd, "w") as fh:
                    fh.write(str(os.getpid()))
                return p
            except FileExistsError:
                pid = holder(p)
                if pid and pid != os.getpid():
                    self._refuse(f"another {self.what} (process {pid}) is writing into this folder")
                lock.unlink(missing_ok=True)            # left by a process that is gone
            except OSError as exc:
                self._refuse(f"cannot be written ({exc.strerror})")
        self._refuse(f"another {self.what} started writing into this folder just now")

    def __exit__(self, exc_type, exc, tb) -> None:
        (self.path / LOCK).unlink(missing_ok=True)


class OutputFolder:
    """Context manager around one run's output folder (module doc). Errors are
    :class:`ScenarioError` on ``--out`` (bad input: exit 2), raised before anything runs."""

    def __init__(self, path: Path, overwrite: bool = False):
        self.path, self.overwrite = Path(path), overwrite
        self._lock = FolderLock(path)

    def __enter__(self) -> Path:
        p = self._lock.__enter__()
        try:
            if any((p / m).exists() for m in RUN_MARKERS if m != LOCK):
                if not self.overwrite:
                    raise ScenarioError(p, ["--out"], "holds a previous run; choose another --out or add --overwrite "
                                                      "to replace it")
                for entry in p.iterdir():
                    if entry.name != LOCK:
                        shutil.rmtree(entry) if entry.is_dir() and not entry.is_symlink() else entry.unlink()
            try:
                (p / INCOMPLETE).write_text("this run has not finished writing its results\n")
            except OSError as exc:
                raise ScenarioError(p, ["--out"], f"cannot be written ({exc.strerror})") from None
        except BaseException:
            self._lock.__exit__(None, None, None)
            raise
        return p

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            (self.path / INCOMPLETE).unlink(missing_ok=True)
        self._lock.__exit__(exc_type, exc, tb)
