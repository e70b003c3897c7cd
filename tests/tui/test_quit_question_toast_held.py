"""Issue 27: ``q again within 3 s to quit`` is a timed question on the toast row; a
hidden screen's status said meanwhile (a demo's progress on Scenes while Signals shows)
replaced it, the newest toast being the only one, while a second ``q`` still quit. The
question holds the toast row as the e-stop's toast does: that status goes to the log."""

from __future__ import annotations

import asyncio

from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.said import said_here

from .conftest import wait_for
from .test_signals_panel import _type
from .test_signals_quit_unsaved import TYPED


def test_a_hidden_screen_s_status_waits_while_q_asks(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24), notifications=True) as pilot:
            expr = app.query_one("#sig-expr", Input)
            await wait_for(pilot, lambda: app.focused is expr, 10, "expression focused")
            expr.value = ""
            await _type(pilot, TYPED)
            await pilot.press("ctrl+q")
            asked = "q again within 3 s quits"
            shown = lambda: " ".join(str(n.message) for n in app._notifications)  # noqa: E731
            await wait_for(pilot, lambda: asked in shown(), 5, "asks")
            app.ensure_pane("scenes")
            await wait_for(pilot, lambda: app.pane("scenes") is not None, 10, "scenes built")
            said_here(app.pane("scenes"), "Scenes", "demo flow: preparing the atlas", "warning")
            await pilot.pause(0.3)
            assert asked in shown() and "preparing" not in shown(), shown()
            assert app.is_running

    asyncio.run(scenario())
