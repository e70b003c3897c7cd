"""A misspelt option before the command is named, with the option meant: ``haptable
--profle sim doctor`` said ``invalid choice: 'sim'`` (the option's value read as the
command), through the installed command as a user runs it."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path


def test_a_misspelt_option_before_the_command_is_named(tmp_path):
    env = {**os.environ, "HOME": str(tmp_path), "XDG_STATE_HOME": str(tmp_path / "state")}
    exe = Path(sys.executable).with_name("haptable")
    run = subprocess.run(
        [str(exe), "--profle", "sim", "doctor"],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert run.returncode == 2, run
    assert "--profle" in run.stderr and "did you mean '--profile'?" in run.stderr, run.stderr
    assert "invalid choice" not in run.stderr, run.stderr
