"""Issue 27, finding 5 (of the fourth try): ``haptable study run`` from a shell holds the
profile's vibration map as the Studies screen's runs hold the console's: while it runs
the console's Vibration screen refuses ``m`` naming the shell's run, and a second run
from another shell is refused as busy (exit 5); the hold ends with the run's process."""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from console.cli.main import Context
from console.config.profile import load_profile
from console.runtime.map_hold import hold_file, map_holder
from console.tui.app import HapTableApp

from ..kernel.test_kernel import haptable
from .studies_pilot import wait_for

ROOT = Path(__file__).resolve().parents[2]


def _status(app) -> str:
    return " ".join(str(app.query_one("#vib-status").render()).split())


def _shell_run(out: Path) -> subprocess.Popen:
    """A simulated study run from a shell (it holds the map until it ends)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    args = ["study", "run", "exp1", "--participant", "P09", "--simulate", "--out", str(out)]
    return subprocess.Popen(
        [sys.executable, "-m", "console.cli.entry", *args],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        # Ctrl-C reaches it as it reaches a command typed at a terminal: a test worker
        # that ignores SIGINT passes that on, and an early one was lost (a CI run waited
        # 30 s for the run to end by itself)
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )


def _held(profile, proc: subprocess.Popen, timeout_s: float = 60.0) -> str:
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end and proc.poll() is None:
        who = map_holder(profile)
        if who is not None:
            return who
        time.sleep(0.05)
    raise AssertionError(f"the shell's run held no map (exit {proc.poll()})")


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_shell_s_study_run_holds_the_console_s_map(plugins, tmp_path, size):
    profile = load_profile("sim", plugins)
    proc = _shell_run(tmp_path / "a")
    try:
        who = _held(profile, proc)
        assert who.startswith("a simulated study run of exp1 (haptable study run --simulate, pid ")
        got = haptable(
            "study",
            "run",
            "exp1",
            "--participant",
            "P10",
            "--simulate",
            "--out",
            str(tmp_path / "b"),
        )
        assert got.returncode == 5, got.stdout + got.stderr  # the table is busy
        assert f"haptable: busy: {who} holds the outputs" in got.stderr, got.stderr

        async def scenario():
            app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
            async with app.run_test(size=size) as pilot:
                await wait_for(pilot, lambda: app.query("#vib-status"), what="its status")
                await pilot.pause(0.5)
                await pilot.press("m")
                await wait_for(pilot, lambda: "refused" in _status(app), 10, "the refusal")
                assert (
                    _status(app)
                    == f"measure refused: {who} plays on this map (stop it there first)"
                )

        asyncio.run(scenario())
    finally:
        proc.send_signal(signal.SIGINT)  # Ctrl-C: the run stops, its hold with it
        proc.wait(30)
    assert map_holder(profile) is None and not hold_file(profile).exists()
