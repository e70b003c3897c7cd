"""A run that holds the table's outputs (a participant's study run) holds them against
every process: another process's plays, relay settings and streams are refused naming
the run, from the client API and from a shell; the e-stop still wins; the hold ends when
its process lets go or leaves."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from console.core.errors import SafetyRefusal
from console.core.types import OutputPlan, Segment
from console.kernel.client import open_outputs
from console.signals.waveforms import tone

ROOT = Path(__file__).resolve().parents[2]
FS = 48000
RUN = "P02's study run (Studies screen)"


def plan_of(seconds: float = 0.05) -> OutputPlan:
    x = tone(250, 20.0, seconds, FS, 0.01)
    return OutputPlan(FS, (Segment(x, np.zeros_like(x), frozenset({"PA"})),), name="tone")


def haptable(*args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("HAPTABLE_TWIN_LOG", None)
    return subprocess.run(
        [sys.executable, "-m", "console.cli.entry", *args],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )


@pytest.fixture
def two(profile, plugins):
    """Two processes' clients of the sim table's shared kernel (the run's, another's)."""
    run = open_outputs(profile, plugins, fast=False, private=False)
    other = open_outputs(profile, plugins, fast=False, private=False)
    yield run, other
    other.close()
    run.close()


def test_a_held_table_refuses_every_other_process_naming_the_run(two):
    run, other = two
    run.hold(RUN)
    with pytest.raises(SafetyRefusal, match=r"tone: refused: P02's study run .* holds the outputs"):
        other.play(plan_of())
    with pytest.raises(SafetyRefusal) as refused:  # a paused run holds them too: no pause advice
        other.play(plan_of())
    assert str(refused.value).endswith("holds the outputs, paused or not (stop it there first)")
    with pytest.raises(SafetyRefusal, match="holds the outputs"):
        other.set_relays({1})
    with pytest.raises(SafetyRefusal, match="holds the outputs"):
        other.hold("another run")
    got = haptable("play", "sine-PA")  # a shell beside the console
    assert got.returncode != 0
    lines = [ln for ln in (got.stdout + got.stderr).splitlines() if ln.strip()]
    assert len(lines) == 1 and "P02's study run" in lines[0], lines
    run.play(plan_of())  # the run itself plays
    run.unhold()
    other.play(plan_of())


def test_the_estop_wins_over_a_hold_and_a_hold_ends_with_its_process(profile, plugins, two):
    run, other = two
    run.hold(RUN)
    other.estop("operator e-stop")
    with pytest.raises(SafetyRefusal, match="e-stop"):
        run.play(plan_of())
    assert run.estopped or other.estopped


def test_a_hold_ends_when_its_process_leaves(profile, plugins):
    run = open_outputs(profile, plugins, fast=False, private=False)
    other = open_outputs(profile, plugins, fast=False, private=False)
    try:
        run.hold(RUN)
        with pytest.raises(SafetyRefusal, match="holds the outputs"):
            other.play(plan_of())
        run.close()
        other.play(plan_of())
    finally:
        other.close()
