"""Issue 27: the Signals screen's empty plots point at the line above only while that line
says why they are empty (a refused preview), never under a success."""

from __future__ import annotations

import asyncio

from textual.widgets import Input, Static

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.charts import Chart

from .conftest import wait_for


def _status(app) -> str:
    return str(app.query_one("#sig-status", Static).render())


def test_the_empty_plots_point_at_an_error_line_only(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 20, "outputs open")
            pane = app.pane("signals")
            await wait_for(pilot, lambda: pane.preview is not None, 20, "first preview")
            wave = app.query_one("#sig-wave", Chart)
            app.query_one("#sig-target", Input).value = "PZ"  # no such patch
            app.query_one("#sig-name", Input).value = "mine"
            await pilot.press("enter")
            await wait_for(pilot, lambda: pane.preview is None, 20, "refused")
            assert app.query_one("#sig-status").has_class("error")
            assert "see the line above" in wave.summary()
            # a target naming no channel is refused by ctrl+s too; with none (the field
            # emptied) the expression saves for any channel: a success on the line
            app.query_one("#sig-target", Input).value = ""
            await pilot.press("ctrl+s")
            await wait_for(pilot, lambda: _status(app).startswith("saved mine"), 20, "saved")
            assert not app.query_one("#sig-status").has_class("error")
            assert "see the line above" not in wave.summary(), wave.summary()
            assert "enter" in wave.summary()

    asyncio.run(scenario())
