"""The log view follows the terminal's width: its lines wrap again when it changes (a
long driver message written at 80 columns stayed wrapped at 80 on a wider terminal)."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.logs import LogScreen

from .conftest import wait_for

LONG = "driver message " + " ".join(f"word{i:02d}" for i in range(40))


def test_the_log_wraps_again_when_the_terminal_widens(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("ctrl+l")
            await wait_for(pilot, lambda: isinstance(app.screen, LogScreen), 10, "the log")
            app.screen.add(LONG)  # a record arriving while the log is open
            await pilot.pause(0.3)

            def rows_with_words() -> int:
                rows = [s.text for s in app.screen._compositor.render_strips()]
                return sum("word" in r for r in rows)

            narrow = rows_with_words()
            await pilot.resize_terminal(160, 24)
            await pilot.pause(0.5)
            wide = rows_with_words()
            assert narrow >= 3 and wide < narrow, (narrow, wide)

    asyncio.run(scenario())
