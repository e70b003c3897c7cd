"""The runtime directory is private and checked; writes never follow a symlink."""

from __future__ import annotations

import os

import pytest

from console.core.errors import UserError
from console.kernel.private_dir import ensure_private_dir, runtime_dir, write_private


def test_created_0700_under_xdg(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    d = runtime_dir()
    assert d == tmp_path / "haptable"
    assert os.stat(d).st_mode & 0o777 == 0o700


def test_shared_mode_refused_with_fix(tmp_path):
    d = tmp_path / "shared"
    d.mkdir(mode=0o777)
    os.chmod(d, 0o777)
    with pytest.raises(UserError, match=r"mode 777 .*run `chmod 700"):
        ensure_private_dir(d)


def test_symlinked_dir_refused(tmp_path):
    (tmp_path / "elsewhere").mkdir(mode=0o700)
    (tmp_path / "link").symlink_to(tmp_path / "elsewhere")
    with pytest.raises(UserError, match="not a plain directory"):
        ensure_private_dir(tmp_path / "link")


def test_write_never_follows_a_symlink(tmp_path):
    target = tmp_path / "victim"
    target.write_text("keep")
    (tmp_path / "log.json").symlink_to(target)
    with pytest.raises(UserError, match="symlink"):
        write_private(tmp_path / "log.json", "{}")
    assert target.read_text() == "keep"
    p = write_private(tmp_path / "fresh.json", "{}")
    assert os.stat(p).st_mode & 0o777 == 0o600
