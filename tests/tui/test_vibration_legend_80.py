"""The Vibration screen (F3) at 80 x 24 and 120 x 40: the FRF plot's legend names every
excitation with its value (the one that plays too, PALL on the twin's map), wrapping
rather than cutting the last ones; page down brings the plot's axes and legend into view
while the grid keeps the focus and its cursor, page up the grid back."""

from __future__ import annotations

import asyncio

import pytest
from rich.text import Text

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.charts import legend_rows

from .conftest import wait_for
from .test_camera_layout import SIZES, screen_lines
from .test_screens import _load_map, _ready

LEGEND = [(f"{n} 0.0{k}34 um/V", "red", "⣿") for k, n in enumerate(["PA", "PB", "PC", "PD"])]
LEGEND += [("PALL 0.0491 um/V", "blue", "⣿"), ("plays at 163 Hz", "gray", "⣿")]


def test_the_legend_wraps_every_entry_whole():
    rows = legend_rows(LEGEND, 78)
    assert len(rows) == 2 and all(r.cell_len <= 78 for r in rows), rows
    shown = " ".join(r.plain for r in rows)
    for label, _c, _m in LEGEND:
        assert label in shown, (label, shown)
    assert "…" not in shown
    one = legend_rows(LEGEND, 200)
    assert len(one) == 1, one  # wide enough: one row, as before
    few = legend_rows(LEGEND, 30, most=2)  # no room for more rows: the last says so
    assert len(few) == 2 and few[-1].plain.endswith("…"), few
    assert all(isinstance(r, Text) for r in few)


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_page_down_shows_the_plot_s_legend_with_every_excitation(plugins, map_file, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=size) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            grid = pane.focus_target
            grid.focus()
            await wait_for(pilot, lambda: app.focused is grid, 10, "the grid focused")
            await pilot.press("right", "down")
            cursor = grid.cursor_coordinate
            await pilot.press("enter")
            chart = app.query_one("#frf-plot")
            await wait_for(pilot, lambda: "plays at" in " ".join(s.label for s in chart.series),
                           30, "the FRF of the point")  # fmt: skip
            labels = [s.label for s in chart.series]
            assert any(lb.startswith("PALL ") for lb in labels), labels
            for _ in range(4):  # the screen's end: the plot's legend
                await pilot.press("pagedown")
            await pilot.pause(0.3)
            shown = "\n".join(screen_lines(app))
            for label in labels:
                assert label in shown, (label, shown)
            assert "frequency (Hz)" in shown, shown  # the x axis' label
            assert app.focused is grid and grid.cursor_coordinate == cursor
            for _ in range(4):
                await pilot.press("pageup")
            await pilot.pause(0.3)
            assert pane.scroll_offset.y == 0
            assert app.focused is grid and grid.cursor_coordinate == cursor

    asyncio.run(scenario())
