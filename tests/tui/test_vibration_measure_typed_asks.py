"""Issue 27 (a new-user try at 80 x 24): the typed ``measure`` never replaces the kept map
at once, as ``m`` does not: the first Enter says what a second one does and keeps the
command on its line; Enter again within the 5 s measures."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.session.vibration import Cancelled
from console.tui.app import HapTableApp
from console.tui.command_line import CommandLine

from .conftest import command, wait_for, words_on
from .test_screens import _ready


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_typed_measure_asks_before_replacing_the_kept_map(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=size) as pilot:
            await _ready(app, pilot)
            kept = app.session.vibration.cached_map_path()
            kept.parent.mkdir(parents=True, exist_ok=True)
            kept.write_bytes(b"")  # a kept map exists (its content is not read here)
            asked: list[int] = []
            app.session.vibration.measure = lambda *a, **kw: (
                asked.append(1) or (_ for _ in ()).throw(Cancelled())
            )
            await command(app, pilot, "measure")
            await pilot.pause(0.3)
            status = words_on(app, "#vib-status")
            assert not asked, "the typed measure replaced the kept map at once"
            assert "Enter again within 5 s" in status and "replaces the kept map" in status
            line = app.screen.query_one("#vib-cmd", CommandLine)
            # the command waits on its line for the Enter that confirms it
            assert line.value == "measure" and app.focused is line
            await pilot.press("enter")
            await wait_for(pilot, lambda: asked, what="the second Enter measures")

    asyncio.run(scenario())
