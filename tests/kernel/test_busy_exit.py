"""A command the table refuses because it is busy (a study run holds its outputs) exits
with its own status, 5, not bad input's 2: every command that plays or holds the
outputs from a shell, one line naming the run."""

from __future__ import annotations

import pytest

from console.core.errors import TableBusy
from console.kernel.client import open_outputs

from .test_kernel import haptable

RUN = "P02's study run (Studies screen)"

#: commands that would play or hold the outputs, each refused by the run's hold
COMMANDS = [
    ("play", "sine-PA"),
    ("signals", "play", "tone-250", "--patch", "PA"),
    ("study", "run", "exp1", "--participant", "P09", "--out", "{out}"),
]


@pytest.fixture
def held(profile, plugins):
    """The sim table's shared kernel held by a run in this process."""
    run = open_outputs(profile, plugins, fast=False, private=False)
    run.hold(RUN)
    yield run
    run.close()


def test_a_busy_table_is_its_own_exit_status(held, tmp_path):
    for cmd in COMMANDS:
        args = [a.format(out=tmp_path / "study") for a in cmd]
        got = haptable(*args)
        lines = [ln for ln in (got.stdout + got.stderr).splitlines() if ln.strip()]
        assert got.returncode == TableBusy.EXIT_CODE == 5, (cmd, got.returncode, lines)
        said = [ln for ln in lines if ln.startswith("haptable")]  # progress aside
        assert len(said) == 1 and said == lines[-1:], (cmd, lines)
        assert said[0].startswith("haptable: busy: ") and "P02's study run" in said[0], lines


def test_bad_input_keeps_its_status(held):
    got = haptable("play", "no-such-stimulus")
    assert got.returncode == 2, got.stdout + got.stderr
