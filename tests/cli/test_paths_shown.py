"""A path in a message is never relative to the working folder unless it was typed so
(issue 27, fifth new-user try: `haptable signals show nosuch` run in /tmp/newuser5 with
HOME=/tmp/newuser5/home said `no signal 'nosuch' in home/.config/haptable/sim/signals.toml`).
Under the home folder it reads `~/...`, elsewhere absolute (``console.files.paths.
shown_path``, the one function the CLI and the console shorten paths with)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from console.files.paths import shown_path

from ..conftest import PINNED_DIRS


def _haptable(cwd: Path, env: dict[str, str], *args: str) -> subprocess.CompletedProcess:
    base = {k: v for k, v in os.environ.items() if k not in PINNED_DIRS}
    return subprocess.run(
        [sys.executable, "-m", "console.cli.entry", *args],
        cwd=cwd,
        env={**base, **env},
        capture_output=True,
        text=True,
        timeout=60,
    )


def test_a_path_under_home_reads_with_a_tilde_from_the_folder_above_it(tmp_path):
    home = tmp_path / "home"
    home.mkdir()
    got = _haptable(tmp_path, {"HOME": str(home)}, "signals", "show", "nosuch")
    assert got.returncode == 2, got
    said = got.stderr.strip()
    assert "in ~/.config/haptable/sim/signals.toml" in said, said
    assert " home/.config" not in said, said


def test_a_path_outside_home_reads_absolute_from_the_folder_it_is_in(tmp_path):
    (tmp_path / "home").mkdir()
    work = tmp_path / "work"
    work.mkdir()
    env = {"HOME": str(tmp_path / "home"), "XDG_CONFIG_HOME": str(work / "cfg")}
    got = _haptable(work, env, "signals", "show", "nosuch")
    assert got.returncode == 2, got
    said = got.stderr.strip()
    assert f"in {work}/cfg/haptable/sim/signals.toml" in said, said


@pytest.mark.parametrize(
    ("given", "shown"),
    [
        ("{home}/.config/x.toml", "~/.config/x.toml"),
        ("{home}", "~"),
        ("{cwd}/profiles/x.toml", "{cwd}/profiles/x.toml"),  # absolute, never cwd-relative
        ("profiles/x.toml", "profiles/x.toml"),  # relative: as typed
        ("~/x.toml", "~/x.toml"),
        ("/etc/x.toml", "/etc/x.toml"),
    ],
)
def test_shown_path(tmp_path, monkeypatch, given, shown):
    home, cwd = tmp_path / "home", tmp_path / "work"
    home.mkdir()
    cwd.mkdir()
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(cwd)
    assert shown_path(given.format(home=home, cwd=cwd)) == shown.format(home=home, cwd=cwd)
