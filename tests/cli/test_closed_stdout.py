"""A new operator's try (issue 27, newuser7 #10): `haptable estop | head -1` printed a
BrokenPipeError traceback (1 of 2 times; the e-stop latched). Every command survives a
closed stdout: it does its work, exits quietly with its usual code, no traceback."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from console.config.profile import PROJECT_PROFILES
from console.kernel.tables import read_latch, table_for

ROOT = Path(__file__).resolve().parents[2]


def _run(*args: str, closed: bool) -> subprocess.CompletedProcess:
    """``haptable ARGS``, its stdout a pipe nobody reads (``closed``: its reader gone
    before it writes a byte, as `| head -1` after its line), else captured."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("HAPTABLE_TWIN_LOG", None)
    cmd = [sys.executable, "-m", "console.cli.entry", *args]
    if not closed:
        return subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=60)
    r, w = os.pipe()
    os.close(r)  # the reader went away: every write fails (EPIPE)
    try:
        return subprocess.run(cmd, env=env, stdout=w, stderr=subprocess.PIPE, text=True, timeout=60)
    finally:
        os.close(w)


@pytest.mark.parametrize(
    "args", [("--help",), ("estop", "--help"), ("signals", "list"), ("plugins",)]
)
def test_a_command_with_its_stdout_closed_exits_quietly_with_its_code(args):
    usual = _run(*args, closed=False)
    got = _run(*args, closed=True)
    assert "Traceback" not in got.stderr and "BrokenPipe" not in got.stderr, got.stderr
    assert "Exception ignored" not in got.stderr, got.stderr
    assert got.returncode == usual.returncode, (got.returncode, usual.returncode, got.stderr)


def test_estop_with_its_stdout_closed_still_latches():
    got = _run("estop", closed=True)
    assert "Traceback" not in got.stderr and "BrokenPipe" not in got.stderr, got.stderr
    assert "Exception ignored" not in got.stderr, got.stderr
    assert got.returncode == 0, got.stderr
    assert read_latch(table_for(PROJECT_PROFILES / "sim.toml")) is not None
