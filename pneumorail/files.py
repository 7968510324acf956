"""The one reader of the project's input files (besides what it wrote itself as a cache): scenario
and parameter files, wheel and rail profiles, track irregularities, comfort and identification
records, the files of the output folders ``report`` and ``compare`` read.

Every file is checked before a byte is used, each refusal an :class:`~pneumorail.errors.InputError`
(the application passes its ``ScenarioError``) naming the file, where, and what was expected:

* a **regular file** only: a folder, a device (``/dev/zero`` never ends), a FIFO (blocks) or a
  socket is refused; the file is opened without blocking and checked again on the open
  descriptor, so one swapped for a FIFO in between is refused too;
* a **size limit** per kind of file (the callers' constants, each with its reason), checked
  on the size and again on what is read (a file may grow meanwhile): nothing is read to the
  memory limit;
* **no symbolic link leaving the folder** it is read from (``within``: an output folder the
  command reads): a report embeds what it reads, and a link in a run folder to a file
  elsewhere would carry that file into the report; links inside the folder are followed;
* **text**: no NUL byte (binary, or UTF-16 from a spreadsheet), UTF-8 (a leading byte-order mark
  is dropped; another encoding only where the format has one, e.g. SIMPACK profiles);
* **line numbers as the user's editor shows them**: every line counts, comments and blank lines
  included; a line ends at ``\\n``, ``\\r\\n`` or ``\\r`` and nowhere else (``str.splitlines``
  would also break at form feeds and Unicode separators, and count lines no editor shows).
"""
from __future__ import annotations

import csv
import errno
import hashlib
import os
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator, List, Optional, Sequence, Tuple, Type

from pneumorail.errors import InputError

KiB, MiB = 1024, 1024 * 1024
#: A wheel or rail profile: a few hundred points, 10-30 kB (the shipped S1002 and UIC60 files);
#: 1 MiB holds a profile sampled every 0.01 mm over 200 mm.
PROFILE_MAX_BYTES = 1 * MiB
#: A track irregularity CSV: 100 km sampled every 0.25 m in five columns is about 40 MB.
TABLE_MAX_BYTES = 64 * MiB
#: A measured or simulated record (comfort, identification): a 30 min record of three axes at
#: 1 kHz is about 110 MB of text; EN 12299 evaluates 5 min. Read whole, then parsed line by line.
RECORD_MAX_BYTES = 256 * MiB
#: A description or table of an output folder (run.json, check.json, summary.csv, ...): the
#: project writes at most a few hundred kB (a sweep's summary of a thousand cases ~1 MB).
RUN_FILE_MAX_BYTES = 16 * MiB
#: A figure of an output folder (embedded into a report): matplotlib's are 50-500 kB.
FIGURE_MAX_BYTES = 32 * MiB
#: A time series of an output folder (compare): the schema's 1e6 samples of ~50 columns of
#: 18 characters.
SERIES_MAX_BYTES = 1024 * MiB


def _refuse(error, path, where, message):
    raise error(path, list(where), message)


def _check_within(path: Path, within: Optional[Path], error, where) -> None:
    """``path`` (links followed) lies in ``within`` (links followed), or is refused."""
    if within is None:
        return
    target, folder = path.resolve(), Path(within).resolve()
    if not target.is_relative_to(folder):
        _refuse(error, path, where, f"a symbolic link leading out of {within} (to {target}): only files inside "
                                    f"the folder are read")


def _kind_of(mode: int) -> str:
    return ("a folder" if stat.S_ISDIR(mode) else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode)
            else "a FIFO" if stat.S_ISFIFO(mode) else "a socket" if stat.S_ISSOCK(mode) else "not a regular file")


def read_bytes(path, what: str, max_bytes: int, within: Optional[Path] = None, where: Sequence[str] = (),
               error: Type[InputError] = InputError) -> bytes:
    """The bytes of the regular file ``path`` (module doc); ``what`` names it in messages (e.g.
    "comfort record"), ``where`` is the key path or option errors name."""
    path = Path(path)
    try:
        _check_within(path, within, error, where)
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        try:
            info = os.fstat(fd)
            if not stat.S_ISREG(info.st_mode):
                _refuse(error, path, where, f"{_kind_of(info.st_mode)}, not a file: expected a {what}")
            if info.st_size > max_bytes:
                _refuse(error, path, where, f"the file is {_size(info.st_size)}; a {what} is at most {_size(max_bytes)}")
            with os.fdopen(fd, "rb", closefd=False) as fh:
                raw = fh.read(max_bytes + 1)
        finally:
            os.close(fd)
    except InputError:
        raise
    except FileNotFoundError:
        _refuse(error, path, where, f"no such file (expected a {what})")
    except IsADirectoryError:
        _refuse(error, path, where, f"a folder, not a file: expected a {what}")
    except OSError as exc:
        reason = "a folder, not a file" if exc.errno == errno.EISDIR else f"cannot read it ({exc.strerror or exc})"
        _refuse(error, path, where, f"{reason}: expected a {what}")
    except ValueError as exc:                                  # e.g. a NUL byte in the path
        _refuse(error, path, where, f"not a usable file name ({exc})")
    except RuntimeError as exc:                                # Path.resolve: a loop of symbolic links
        _refuse(error, path, where, f"cannot read it ({exc})")
    if len(raw) > max_bytes:
        _refuse(error, path, where, f"more than {_size(max_bytes)} (it grew while read): a {what} is at most "
                                    f"{_size(max_bytes)}")
    return raw


def _size(n: int) -> str:
    return f"{n / MiB:.0f} MB" if n >= 10 * MiB else f"{n / KiB:.0f} kB"


@dataclass(frozen=True)
class TextFile:
    """A text file read by :func:`read_text`: its path, text and the sha256 of its bytes."""

    path: Path
    text: str
    sha256: str = ""

    def lines(self) -> List[Tuple[int, str]]:
        """(line number as an editor shows it, line) of every line (module doc)."""
        lines = self.text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
        if lines and lines[-1] == "":
            lines.pop()                                        # the newline ending the last line
        return list(enumerate(lines, start=1))

    def data_lines(self, comment: str = "#") -> List[Tuple[int, str]]:
        """The lines that are neither blank nor comments, with their editor line numbers."""
        return [(n, line) for n, line in self.lines() if line.strip() and not line.lstrip().startswith(comment)]

    def csv_rows(self, comment: str = "#") -> Iterator[Tuple[int, List[str]]]:
        """(editor line number, stripped fields) of each data line as CSV (one record a line)."""
        for n, line in self.data_lines(comment):
            yield n, [field.strip() for field in next(csv.reader([line]))]


def read_text(path, what: str, max_bytes: int, within: Optional[Path] = None, where: Sequence[str] = (),
              encodings: Sequence[str] = ("utf-8",), error: Type[InputError] = InputError) -> TextFile:
    """The text of ``path`` (module doc: a regular file of at most ``max_bytes``, NUL-free, in the
    first of ``encodings`` that decodes it; UTF-8 unless the format says otherwise)."""
    raw = read_bytes(path, what, max_bytes, within, where, error)
    if b"\0" in raw:
        _refuse(error, path, where, f"binary content (NUL bytes; UTF-16?): expected a {what} as UTF-8 text")
    for encoding in encodings:
        try:
            return TextFile(Path(path), raw.decode(encoding).removeprefix("\ufeff"), hashlib.sha256(raw).hexdigest())
        except UnicodeDecodeError as exc:
            first = exc
    line = raw[:first.start].count(b"\n") + 1
    _refuse(error, path, where, f"not UTF-8 text (line {line}, byte {first.start} cannot be decoded): save the "
                                f"{what} as UTF-8 (or ASCII) text")


def duplicated(names: Sequence[str]) -> List[str]:
    """The names that occur more than once, each once, in order of first appearance (a CSV header)."""
    return list(dict.fromkeys(n for i, n in enumerate(names) if n in names[:i]))
