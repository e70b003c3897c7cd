"""Issue 27, third new-user try: ctrl+e during a Signals play is said once, on the
Signals status line, as stopped by the e-stop with its fix (not a toast "refused:
bursts: bursts: stopped: ..." and a second toast about the same event)."""

from __future__ import annotations

import asyncio

from textual.widgets import Input

from console.cli.main import Context
from console.session.events import ESTOP_FIX
from console.tui.app import HapTableApp

from .conftest import wait_for

LONG = "sine(100 Hz, 5 V, 4 s) * ramp(10 ms)"


def _toasts(app) -> list[str]:
    return [str(n.message) for n in app._notifications]


def test_an_estop_during_a_play_is_said_once_as_stopped(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("signals")
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
            await wait_for(pilot, lambda: bool(pane.entries), 30, "library")
            app.query_one("#sig-name", Input).value = "bursts"
            app.query_one("#sig-expr", Input).value = LONG
            await pilot.press("ctrl+o")
            status = app.query_one("#sig-status")

            def started() -> bool:
                last = app.session.last_played()
                return last is not None and bool(last[1].segment_start)

            await wait_for(pilot, started, 30, "playing")
            toasts_before = len(_toasts(app))
            await pilot.press("ctrl+e")
            said = lambda: " ".join(str(status.render()).split())  # noqa: E731
            await wait_for(pilot, lambda: "e-stop" in said(), 30, "said on the status line")
            await wait_for(pilot, lambda: app.session.last_played()[1].done.is_set(), 30, "end")
            await pilot.pause(1.0)  # a late second message would come now
            line = said()
            assert "stopped by the e-stop" in line and "bursts" in line, line
            assert ESTOP_FIX in line, line
            assert "refused" not in line and "bursts: bursts" not in line, line
            new = _toasts(app)[toasts_before:]
            assert not [t for t in new if "bursts" in t or "refused" in t], new

    asyncio.run(scenario())
