"""Issue 27, fourth new-user try: when the loop the Latency screen shows stops (``m``
ended), its camera line (fps, frames dropped) stays with the stage table, marked as the
last run's, as the README promises ("the last numbers stay when a loop stops")."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.panes import latency

from .conftest import wait_for, words_on


def test_the_camera_line_stays_with_the_last_numbers(plugins, monkeypatch):
    monkeypatch.setattr(latency, "MEASURE_S", 6.0)  # rows come on a loaded machine

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        async with app.run_test(size=(80, 24)) as pilot:
            head = lambda: words_on(app, "#lat-head")  # noqa: E731
            await wait_for(pilot, lambda: "m measures" in head(), 20, "the idle hint")
            await pilot.press("m")
            table = app.query_one("#lat-table")
            await wait_for(pilot, lambda: table.row_count >= 2, 30, "the loop's rows")
            assert "frames dropped" in head(), head()
            await wait_for(pilot, lambda: not app.session.camera_started.running, 30, "stop")
            await wait_for(pilot, lambda: "last numbers" in head(), 10, "kept numbers")
            text = head()
            assert "camera loop" in text and "stopped" in text, text
            assert "fps" in text and "frames dropped by the camera" in text, text
            assert table.row_count >= 2

    asyncio.run(scenario())
