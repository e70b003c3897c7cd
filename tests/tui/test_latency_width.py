"""The Latency screen's sparklines use the width the terminal gives them."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.panes.latency import spark_width

from .conftest import wait_for


def test_spark_width_is_what_the_other_columns_leave():
    assert spark_width(100, [10, 6, 6, 6], 1) == 100 - 28 - 10 - 1
    assert spark_width(30, [10, 6, 6, 6], 1) == 8  # never less than a few bars


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_sparklines_fill_the_row_and_no_more(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        async with app.run_test(size=size) as pilot:
            pane = app.pane("latency")
            table = app.query_one("#lat-table")
            head = app.query_one("#lat-head")
            await wait_for(pilot, lambda: "m measures" in str(head.render()), 20, "the hint")
            await pilot.press("m")  # the camera loop runs for the screen's numbers
            await wait_for(pilot, lambda: table.row_count >= 3, 30, "latency rows")
            for label in ("vision", "classify"):
                pane.history[label].extend(float(v % 7 + 1) for v in range(400))
            await wait_for(
                pilot,
                lambda: len(str(table.get_row_at(_row(table, "vision"))[5])) > 30,
                10,
                "long history drawn",
            )
            spark = str(table.get_row_at(_row(table, "vision"))[5])
            # the table measures its new cells at its next idle: then it fills the row
            fills = lambda: table.size.width - table.virtual_size.width <= 3  # noqa: E731
            await wait_for(pilot, fills, 10, "the table laid out")
            assert table.virtual_size.width <= table.size.width  # no sideways scrolling
            assert table.size.width - table.virtual_size.width <= 3  # and no room left
            assert len(spark) >= size[0] - 50  # the five other columns take ~47

    asyncio.run(scenario())


def _row(table, label: str) -> int:
    return next(i for i in range(table.row_count) if str(table.get_row_at(i)[0]) == label)
