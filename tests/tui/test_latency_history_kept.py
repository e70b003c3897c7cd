"""Issue 27, finding 12: the Latency screen's p50 history of the console's camera loop is
kept by the camera service whether or not the screen showed while it ran, so it stays
(said to have stopped) when the Camera screen lets the loop go; its sparklines fill the
screen's width even with a few readings; the camera loop schedules no output, so it has
no end-to-end row, and the screen says what each number means."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_camera_loop_s_history_stays_and_fills_the_row(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            svc = lambda: app.session.camera_started  # noqa: E731

            def frames() -> int:  # the loop's, counted by its monitor
                s = svc()
                return s.loop.monitor.frames if s is not None and s.loop is not None else 0

            await wait_for(pilot, lambda: frames() >= 10, 60, "the camera loop running")
            await pilot.pause(2.5)  # a few readings while the Latency screen never showed
            await pilot.press("f7")  # the Camera screen lets the loop go: it stops
            await wait_for(pilot, lambda: not svc().running, 30, "the camera loop stopped")
            head = lambda: words_on(app, "#lat-head")  # noqa: E731
            await wait_for(pilot, lambda: "last numbers" in head(), 20, "its last numbers")
            table = app.query_one("#lat-table")
            await wait_for(pilot, lambda: table.row_count >= 2, 10, "its rows")
            rows = {
                str(table.get_row_at(i)[0]): table.get_row_at(i) for i in range(table.row_count)
            }
            rows_at = {str(table.get_row_at(i)[0]): i for i in range(table.row_count)}
            spark = str(rows["vision"][5])
            assert spark.strip(), rows  # the history stayed
            fills = lambda: table.size.width - table.virtual_size.width <= 3  # noqa: E731
            await wait_for(pilot, fills, 10, "the table laid out")
            # the sparkline as drawn for that width (read again: it was drawn for the
            # width before, on a loaded machine the table's first layout)
            wide = lambda: len(str(table.get_row_at(rows_at["vision"])[5])) >= size[0] - 50  # noqa: E731
            await wait_for(pilot, wide, 10, "the sparkline as wide as the row")
            assert "end to end" not in rows, rows  # the camera loop schedules no output
            key = words_on(app, "#lat-key")
            assert "no end to end: this loop schedules no output" in key, key
            assert "p50 history:" in key and "the loop has stopped" in key, key
            assert "p50/p99/max: ms a stage took per frame" in key, key

    asyncio.run(scenario())
