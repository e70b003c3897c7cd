"""A shell's bare `haptable estop` latches every table (the one the console holds and
every other profile's); ctrl+r in the console resets its own table only (its kernel takes
a reset from its own console, an operator's key). So the console shows the tables left
latched, on the safety bar and with ctrl+r's outcome, and how each is reset (ctrl+r in
its console, or `haptable reset` at a terminal): no latched e-stop the operator looking
at this console cannot see. 80 x 24 and 120 x 40."""

from __future__ import annotations

import asyncio
import os
import subprocess
import sys
from pathlib import Path

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_screens import _ready

ROOT = Path(__file__).resolve().parents[2]


def _said(app) -> list[str]:
    return [str(n.message) for n in app._notifications]


def _bar(app) -> str:
    return " ".join(str(app.query_one("#safety").render()).split())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_shell_estop_of_every_table_shows_the_others_after_ctrl_r(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="devices")
        async with app.run_test(size=size, notifications=True) as pilot:
            await _ready(app, pilot)
            done = await asyncio.to_thread(
                subprocess.run,
                [sys.executable, "-m", "console.cli.entry", "estop"],
                cwd=ROOT,
                env=dict(os.environ),
                capture_output=True,
                text=True,
                timeout=60,
            )
            # the command names every table it latched, the other profiles' too, each
            # with the command that resets it
            latched = [ln for ln in done.stdout.splitlines() if "latched" in ln]
            assert any(
                "haptable-lab" in ln and "haptable --profile haptable-lab reset" in ln
                for ln in latched
            ), done.stdout
            await wait_for(pilot, lambda: app.session.outputs.estopped, 20, "e-stopped")
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 20, "reset")
            said = [m for m in _said(app) if m.startswith("e-stop reset")]
            assert said and "still e-stopped: table" in said[-1], _said(app)
            # each named with the command that resets it at a terminal
            assert "(`haptable --profile haptable-lab reset`)" in said[-1], said[-1]
            # the bar: this table's state, and the others still latched, by name
            await wait_for(pilot, lambda: "haptable-lab" in _bar(app), 10, "others on the bar")
            bar = _bar(app)
            assert "idle" in bar and "e-stop" in bar.lower(), bar
            assert len(bar) <= size[0], bar
            # ctrl+r again: nothing here to reset, and it says which table still is
            await pilot.press("ctrl+r")
            await pilot.pause(0.3)
            assert "haptable-lab" in _said(app)[-1], _said(app)

    asyncio.run(scenario())
