"""Issue 27, third new-user try: Scope's ``p`` (last plan) shows the last plan the gate
passed whoever sent it, naming who (a plan from the CLI while the console is open), and
that plan's e-stop; it showed only this console's own last plan."""

from __future__ import annotations

import asyncio
import os
import subprocess
import sys
from pathlib import Path

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on

ROOT = Path(__file__).resolve().parents[2]
LONG = "sine(100 Hz, 5 V, 6 s) * ramp(10 ms)"


def _cli(*args: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("HAPTABLE_TWIN_LOG", None)
    return subprocess.Popen(
        [sys.executable, "-m", "console.cli.entry", *args],
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_p_shows_a_plan_from_the_cli_and_its_estop(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="scope")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
            proc = _cli("signals", "play", LONG, "--patch", "PA")
            try:

                def cli_plays() -> bool:
                    last = app.session.last_plan()
                    return last is not None and not last.own and not last.done

                await wait_for(pilot, cli_plays, 30, "the CLI's plan plays")
                await pilot.press("p")
                who = f"last plan expression from the CLI (pid {proc.pid}): 6.00 s on PA"
                head = lambda: words_on(app, "#scope-head")  # noqa: E731
                await wait_for(pilot, lambda: who in head(), 30, "named")
                assert "(playing)" in head()
                await pilot.press("ctrl+e")
                await wait_for(pilot, lambda: "(stopped: " in head(), 30, "its end")
                await wait_for(
                    pilot, lambda: "estop at " in words_on(app, "#scope-info"), 30, "its e-stop"
                )
                assert who in head() and "FROZEN ON THE LAST PLAN" in head()
                assert proc.wait(30) == 4
            finally:
                if proc.poll() is None:
                    proc.kill()
                    proc.wait()

    asyncio.run(scenario())
