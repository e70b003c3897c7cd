"""A table that gets shorter keeps its highlighted row in view (Scenes, F6, at 80 x 24
and 120 x 40): enter on a scene starts the projector, its line grows to several rows
and the scene list shrinks, scrolled to the row chosen; a terminal made shorter does
the same."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import DataTable

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import SIZES, text_in


def _cursor_shows(table: DataTable) -> bool:
    """The highlighted row lies within the rows the table shows under its header."""
    y = table.cursor_row
    top = table.scroll_offset.y
    rows = table.scrollable_content_region.height - table.header_height
    shown = [table.ordered_rows[i] for i in range(table.row_count)]
    first = sum(r.height for r in shown[:y])
    return top <= first and first + shown[y].height <= top + rows


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_the_chosen_scene_stays_in_view_as_the_list_shrinks(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.pane("scenes") is not None, what="scenes")
            table = app.query_one("#scene-table", DataTable)
            await wait_for(pilot, lambda: app.focused is table, 10, "the scenes focused")
            names = [table.coordinate_to_cell_key((i, 0)).row_key.value for i in range(3)]
            await pilot.press("down", "down")
            assert table.cursor_row == 2, table.cursor_row
            line = app.query_one("#projector-status")
            before = line.region.height
            await pilot.press("enter")
            await wait_for(
                pilot, lambda: f"scene: {names[2]}" in text_in(app, line), 60, "the scene shown"
            )
            await wait_for(pilot, lambda: line.region.height > before, 30, "the line grown")
            await pilot.pause(0.3)
            assert _cursor_shows(table), (table.scroll_offset, table.region, names[2])
            assert names[2] in text_in(app, table), text_in(app, table)
            await pilot.resize_terminal(size[0], size[1] - 4)  # a shorter terminal
            await pilot.pause(0.3)
            assert _cursor_shows(table), (table.scroll_offset, table.region)
            assert names[2] in text_in(app, table), text_in(app, table)

    asyncio.run(scenario())
