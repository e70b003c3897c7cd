"""An option given where the command does not take it gets one line that says where it
goes (`haptable --json estop`: after the command's name), and a mistyped option of the
shell's e-stop gets the one meant, as every other command's does."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _haptable(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "console.cli.entry", *args],
        cwd=ROOT,
        env=dict(os.environ),
        capture_output=True,
        text=True,
        timeout=60,
    )


def test_an_option_before_the_command_is_told_where_it_goes():
    got = _haptable("--json", "estop")
    err = got.stderr.strip().splitlines()
    assert got.returncode == 2 and len(err) == 1, got
    assert "`haptable estop --json`" in err[0], err  # the command as it should be typed
    assert "did you mean '--json'" not in err[0], err  # not the flag it refused
    assert got.stdout == ""  # nothing e-stopped by a refused command


def test_a_mistyped_estop_option_names_the_one_meant():
    got = _haptable("estop", "--jsn")
    err = got.stderr.strip().splitlines()
    assert got.returncode == 2 and len(err) == 1, got
    assert "did you mean '--json'?" in err[0] and "haptable estop --help" in err[0], err
