"""The shared bounded reader: kind and size checked before a byte is read, so a FIFO, a
device or a huge file in a settings file's place is one line, never a hang."""

from __future__ import annotations

import os

import pytest

from console.core.errors import ProfileError, UserError
from console.files.file_read import read_bytes_capped, read_text_capped, read_toml_capped

KW = {"what": "settings file", "fix": "give a TOML file"}


@pytest.mark.timeout(30, method="signal")
@pytest.mark.parametrize(
    ("make", "says"),
    [
        (os.mkfifo, "a FIFO (named pipe), not a settings file; give a TOML file"),
        (lambda p: os.symlink("/dev/zero", p), "a character device"),
        (os.mkdir, "a folder"),
        (lambda p: os.symlink(p, p), "a symlink loop"),
        (lambda p: p.write_bytes(b"x" * 20_000), "20,000 bytes is too large for a settings file"),
        (lambda p: p.write_bytes(b"a = 1\n\xfe\n"), "not UTF-8 text (byte 0xfe on line 2)"),
        (lambda p: p.write_text("a = [\n"), "not valid TOML"),
        (lambda p: p.write_text("a = " + "[" * 2000 + "]" * 2000), "nested too deeply"),
        (lambda p: p.write_text("a = 1" + "0" * 5000), "write it as a short number"),
    ],
)
def test_one_line_per_kind_of_bad_file(tmp_path, make, says):
    path = tmp_path / "f.toml"
    make(path)
    with pytest.raises(ProfileError) as err:
        read_toml_capped(path, max_bytes=10_000, error=ProfileError, **KW)
    assert says in str(err.value) and "\n" not in str(err.value)


def test_missing_reads_as_none_or_one_line(tmp_path):
    gone = tmp_path / "gone.toml"
    assert read_text_capped(gone, missing_ok=True, **KW) is None
    (tmp_path / "dangling").symlink_to(gone)
    assert read_toml_capped(tmp_path / "dangling", missing_ok=True, **KW) is None
    with pytest.raises(UserError, match="no such file; give a TOML file"):
        read_bytes_capped(gone, **KW)


def test_the_read_itself_is_bounded(tmp_path, monkeypatch):
    # a file that claims few bytes but yields more (a /proc file, or one growing meanwhile)
    path = tmp_path / "f"
    path.write_bytes(b"x" * 10)
    real_fstat, real_read = os.fstat, os.read
    monkeypatch.setattr(os, "read", lambda fd, n: b"y" * n)  # never ends
    with pytest.raises(UserError, match="more than 100 bytes"):
        read_bytes_capped(path, max_bytes=100, **KW)
    monkeypatch.setattr(os, "read", real_read)
    assert real_fstat is os.fstat
    assert read_bytes_capped(path, max_bytes=100, **KW) == b"x" * 10
    assert read_toml_capped(_write(tmp_path / "ok.toml", "a = 1\n"), **KW) == {"a": 1}


def _write(path, text):
    path.write_text(text)
    return path
