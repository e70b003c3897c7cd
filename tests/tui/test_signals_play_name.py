"""A play is named after the library's signal only when it plays that signal: an edited
expression under a loaded name plays as designed (the status said "playing tone-250"
for another signal)."""

from __future__ import annotations

import asyncio

from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def test_the_status_names_what_plays(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("signals")
            await wait_for(pilot, lambda: app.session.outputs is not None, 20, "outputs open")
            await wait_for(pilot, lambda: bool(pane.entries), 10, "library")
            name, entry = next(iter(pane.entries.items()))
            assert pane.play_label(entry.expr, name) == name
            other = "sine(100 Hz, 5 V, 0.2 s) * ramp(5 ms)"
            assert pane.play_label(other, name) == f"designed ({name} edited)"
            assert pane.play_label(other, "") == "designed"
            app.query_one("#sig-name", Input).value = name
            app.query_one("#sig-expr", Input).value = other
            await pilot.press("ctrl+o")
            status = app.query_one("#sig-status")
            await wait_for(pilot, lambda: "played" in str(status.render()), 20, "played")
            assert f"played designed ({name} edited)" in str(status.render())

    asyncio.run(scenario())
