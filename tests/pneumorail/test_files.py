"""The one file reader (pneumorail.files): regular files only, never blocking or reading without
end, a size limit, no symbolic link out of the folder read, UTF-8 checked, line numbers as an
editor shows them (issue 39)."""
from __future__ import annotations

import os
import time

import pytest

from pneumorail.errors import InputError
from pneumorail.files import TextFile, duplicated, read_bytes, read_text


def test_a_fifo_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "record.csv"
    os.mkfifo(fifo)
    t0 = time.perf_counter()
    with pytest.raises(InputError, match="FIFO"):
        read_text(fifo, "record", 1000)
    assert time.perf_counter() - t0 < 1.0               # opened non-blocking: no writer is waited for


@pytest.mark.parametrize("path, words", [("/dev/zero", "device"), ("/", "folder"), ("/no/such/file", "no such file")])
def test_what_is_not_a_regular_file_is_refused_naming_it(path, words):
    with pytest.raises(InputError, match=words) as err:
        read_bytes(path, "record", 1000, where=["--data"])
    assert err.value.file == path and err.value.path == "--data"


def test_the_size_limit_is_checked_before_reading(tmp_path):
    big = tmp_path / "big.csv"
    big.write_bytes(b"x" * 2001)
    with pytest.raises(InputError, match="at most 2 kB"):
        read_bytes(big, "record", 2000)
    assert read_bytes(big, "record", 2001) == b"x" * 2001


def test_links_may_not_leave_the_folder_read(tmp_path):
    outside, folder = tmp_path / "secret.txt", tmp_path / "run"
    outside.write_text("secret")
    folder.mkdir()
    (folder / "inside.txt").write_text("mine")
    (folder / "out.txt").symlink_to(outside)
    (folder / "in.txt").symlink_to(folder / "inside.txt")
    with pytest.raises(InputError, match="symbolic link leading out of"):
        read_text(folder / "out.txt", "table", 1000, within=folder)
    assert read_text(folder / "in.txt", "table", 1000, within=folder).text == "mine"
    assert read_text(folder / "out.txt", "table", 1000).text == "secret"     # a file the user named: followed
    (folder / "a").symlink_to(folder / "b")
    (folder / "b").symlink_to(folder / "a")
    for within in (None, folder):
        with pytest.raises(InputError, match="symbolic links|Symlink loop"):
            read_text(folder / "a", "table", 1000, within=within)


@pytest.mark.parametrize("raw, words", [(b"a\0b", "binary"), ("t;\u00e9\n".encode("latin-1"), "not UTF-8"),
                                        ("t_s\n".encode("utf-16"), "binary")])
def test_text_must_be_utf8(tmp_path, raw, words):
    path = tmp_path / "r.csv"
    path.write_bytes(raw)
    with pytest.raises(InputError, match=words):
        read_text(path, "record", 1000)


def test_a_format_may_admit_latin1_and_a_bom_is_dropped(tmp_path):
    path = tmp_path / "w.prw"
    path.write_bytes("! r\u00e9f\n".encode("latin-1"))
    assert read_text(path, "profile", 1000, encodings=("utf-8", "latin-1")).text == "! r\u00e9f\n"
    path.write_bytes("\ufefft_s\n".encode("utf-8"))
    assert read_text(path, "record", 1000).text == "t_s\n"


def test_line_numbers_are_the_editors():
    # comments and blank lines count; \r\n, \r and \n end a line, a form feed or U+2028 does not
    text = TextFile("r.csv", "# c\r\n\r\nt_s,a\rx\x0cy,1\u2028z\n# end\n1,2\n")
    assert text.lines() == [(1, "# c"), (2, ""), (3, "t_s,a"), (4, "x\x0cy,1\u2028z"), (5, "# end"), (6, "1,2")]
    assert [n for n, _ in text.data_lines()] == [3, 4, 6]
    assert list(text.csv_rows())[-1] == (6, ["1", "2"])


def test_duplicated_names_each_once_in_order():
    assert duplicated(["t_s", "az", "ax", "az", "t_s", "az"]) == ["az", "t_s"]
