"""Issue 27: ``haptable study run exp1 --participant P03 --out DIR`` at a terminal asks
age, sex, handedness, hand width, hand length and consent, and checked the answers only
after all six: ``abc`` for the age failed at the end and all had to be typed again. Each
answer is checked as typed (the option's rule and words) and that one asked again."""

from __future__ import annotations

import os
import pty
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _run_at_a_terminal(args: list[str], typed: str) -> subprocess.CompletedProcess:
    """The command with a terminal as its stdin (it asks only at one), ``typed`` typed."""
    master, slave = pty.openpty()
    try:
        proc = subprocess.Popen(
            [sys.executable, "-m", "console.cli.entry", *args],
            cwd=ROOT,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
            stdin=slave,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        os.write(master, typed.encode())
        out, err = proc.communicate(timeout=120)
    finally:
        os.close(slave)
        os.close(master)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def test_a_bad_answer_is_asked_again_at_once(map_file, tmp_path):
    args = ["study", "run", "exp1", "--participant", "P03", "--out", str(tmp_path)]
    args += ["--map", str(map_file)]
    # abc for the age, 99 for the hand width: each asked again; then no consent
    typed = "abc\n31\nf\nright\n99\n8.4\n18.1\nn\n"
    got = _run_at_a_terminal(args, typed)
    said = got.stdout + got.stderr
    assert got.stdout.count("P03: age: ") == 2, got.stdout
    assert got.stdout.count("P03: hand width cm: ") == 2, got.stdout
    assert got.stdout.count("P03: sex: ") == 1, got.stdout
    assert "participant P03: --age abc: give a number from 1 to 120; type it again" in said
    assert "--hand-width-cm 99: give a number from 3 to 30; type it again" in said
    # the end: what was not given (the consent), not the age typed long before
    assert got.returncode == 2, said
    assert "consent not noted" in got.stderr, said
    assert "give a number" not in got.stderr.splitlines()[-1], said
